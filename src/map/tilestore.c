/* A tile store in caller-supplied memory: include/rsm/tilestore.h has the
 * contract. Tiles stay dense in tiles[0..used); an open-addressing index
 * (linear probing, backward-shift deletion, no tombstones) finds a place. */
#include "rsm/tilestore.h"

#include <string.h>

#include "rsm/status.h"
#include "core/check.h"
#include "map/mapstate.h"

static uint32_t level_of(const rsm_tile_t *t)
{
    return t->stamp >> 30;
}

static uint32_t home(const rsm_tilestore_mem_t *m, uint32_t level, int32_t tx, int32_t ty)
{
    const uint32_t key = ((uint32_t)(uint16_t)tx | ((uint32_t)(uint16_t)ty << 16)) ^ (level * 0x9E3779B9u);
    return (key * 2654435761u) >> (32u - m->index_log2);
}

static int same_place(const rsm_tile_t *t, uint32_t level, int32_t tx, int32_t ty)
{
    return t->tx == tx && t->ty == ty && level_of(t) == level;
}

/* Index entry of a place, or the empty entry where it would go. */
static uint32_t probe(const rsm_tilestore_mem_t *m, uint32_t level, int32_t tx, int32_t ty)
{
    const uint32_t mask = (1u << m->index_log2) - 1u;
    uint32_t h = home(m, level, tx, ty);
    while (m->index[h] != 0u && !same_place(&m->tile[m->index[h] - 1u], level, tx, ty)) {
        h = (h + 1u) & mask;
    }
    return h;
}

/* Empties index entry i, moving later entries of the run back so that every
 * place stays reachable. */
static void unindex(rsm_tilestore_mem_t *m, uint32_t i)
{
    const uint32_t mask = (1u << m->index_log2) - 1u;
    uint32_t j = i;
    for (;;) {
        const rsm_tile_t *u;
        uint32_t h;
        j = (j + 1u) & mask;
        if (m->index[j] == 0u) {
            break;
        }
        u = &m->tile[m->index[j] - 1u];
        h = home(m, level_of(u), u->tx, u->ty);
        if (((j - h) & mask) >= ((j - i) & mask)) {
            m->index[i] = m->index[j];
            i = j;
        }
    }
    m->index[i] = 0u;
}

static int mem_put(void *ctx, const rsm_tile_t *t)
{
    rsm_tilestore_mem_t *m = (rsm_tilestore_mem_t *)ctx;
    const uint32_t h = probe(m, level_of(t), t->tx, t->ty);
    if (m->index[h] != 0u) {
        return RSM_ERR_FORMAT;
    }
    if (m->used >= m->capacity) {
        return RSM_ERR_NOMEM;
    }
    m->tile[m->used] = *t;
    m->index[h] = ++m->used;
    return RSM_OK;
}

static int mem_take(void *ctx, uint32_t level, int32_t tx, int32_t ty, rsm_tile_t *t)
{
    rsm_tilestore_mem_t *m = (rsm_tilestore_mem_t *)ctx;
    const uint32_t h = probe(m, level, tx, ty);
    const uint32_t s = m->index[h];
    if (s == 0u) {
        return 0;
    }
    *t = m->tile[s - 1u];
    unindex(m, h);
    if (s != m->used) {
        /* The last tile fills the hole: its index entry follows it. */
        const rsm_tile_t *last = &m->tile[m->used - 1u];
        const uint32_t e = probe(m, level_of(last), last->tx, last->ty);
        m->tile[s - 1u] = *last;
        m->index[e] = s;
    }
    m->used--;
    return 1;
}

static uint32_t mem_count(const void *ctx)
{
    return ((const rsm_tilestore_mem_t *)ctx)->used;
}

static int mem_at(const void *ctx, uint32_t i, rsm_tile_t *t)
{
    const rsm_tilestore_mem_t *m = (const rsm_tilestore_mem_t *)ctx;
    if (i >= m->used) {
        return RSM_ERR_RANGE;
    }
    *t = m->tile[i];
    return RSM_OK;
}

static void mem_clear(void *ctx)
{
    rsm_tilestore_mem_t *m = (rsm_tilestore_mem_t *)ctx;
    memset(m->index, 0, sizeof m->index[0] << m->index_log2);
    m->used = 0u;
}

uint32_t rsm_tilestore_mem_index_log2(uint32_t capacity)
{
    uint32_t k = 2u;
    while (k < 30u && (1u << k) < capacity + capacity / 3u + 1u) {
        ++k;
    }
    return k;
}

int rsm_tilestore_mem_init_checked(rsm_tilestore_mem_t *m, rsm_tile_t *tiles, uint32_t capacity, uint32_t *index,
                                   uint32_t index_log2, rsm_tile_store_t *store, size_t tile_size,
                                   unsigned long fingerprint)
{
    if (!RSM_SAME_BUILD(rsm_tile_t, tile_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (m == NULL || tiles == NULL || index == NULL || store == NULL || capacity == 0u ||
        capacity > (1u << 28) || index_log2 > 30u || index_log2 < rsm_tilestore_mem_index_log2(capacity)) {
        return RSM_ERR_INVAL;
    }
    m->tile = tiles;
    m->index = index;
    m->capacity = capacity;
    m->index_log2 = index_log2;
    mem_clear(m);
    store->ctx = m;
    store->capacity = capacity;
    store->put = mem_put;
    store->take = mem_take;
    store->count = mem_count;
    store->at = mem_at;
    store->clear = mem_clear;
    return RSM_OK;
}

int rsm_localizer_set_store(rsm_localizer_t *loc, const rsm_tile_store_t *store)
{
    if (!rsm_localizer_ready(loc) ||
        (store != NULL && (store->put == NULL || store->take == NULL || store->count == NULL || store->at == NULL ||
                           store->clear == NULL))) {
        return RSM_ERR_INVAL;
    }
    if (loc->cfg->method != RSM_METHOD_MAP) {
        return RSM_ERR_NOSYS;
    }
    loc->state.persistent.map.store = store;
    return RSM_OK;
}
