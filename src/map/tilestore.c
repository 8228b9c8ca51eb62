/* Tile stores: include/rsm/tilestore.h has the contracts. The one in
 * caller memory keeps its tiles dense in tiles[0..used); an open-addressing
 * index (linear probing, backward-shift deletion, no tombstones) finds a
 * place. The one over a saved map in flash never moves a tile: its index,
 * written once, finds the tile's number, and a bit a tile in RAM says
 * whether the pool has it. */
#include "rsm/tilestore.h"

#include <string.h>

#include "rsm/mapfile.h"
#include "rsm/status.h"
#include "core/bytes.h"
#include "core/check.h"
#include "map/mapstate.h"
#include "map/tmap_read.h"

static uint32_t level_of(const rsm_tile_t *t)
{
    return t->stamp >> 30;
}

static uint32_t home(const rsm_tilestore_mem_t *m, uint32_t level, int32_t tx, int32_t ty)
{
    return rsm_tmap_place_hash(level, tx, ty, m->index_log2);
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

/* The memory store's callbacks (ctx and capacity set by its init). */
static const rsm_tile_store_t mem_ops = {NULL, 0u, mem_put, mem_take, mem_count, mem_at, mem_clear};

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
    *store = mem_ops;
    store->ctx = m;
    store->capacity = capacity;
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
    loc->state.persistent.global.taken_back = 0u; /* another store: what it holds is not known */
    return RSM_OK;
}

/* ---- a store over a saved map in flash ---------------------------------- */

/* Tile k of a saved map's bytes (docs/mapfile.md). */
static void rom_tile(const uint8_t *map, uint32_t k, rsm_tile_t *t)
{
    rsm_mapfile_decode_tile(t, map + RSM_MAPFILE_HEADER_BYTES + (size_t)k * RSM_MAPFILE_TILE_BYTES);
}

/* The tile count of the map that begins the len bytes (magic, header
 * size; its length, from the header's tile count, within len: the bytes
 * may be a larger flash region); else 0xFFFFFFFF. */
static uint32_t rom_tiles(const uint8_t *map, uint32_t len)
{
    uint32_t tiles;
    if (len < RSM_MAPFILE_HEADER_BYTES + 4u || map[0] != 'R' || map[1] != 'S' || map[2] != 'M' || map[3] != 'M' ||
        rsm_get_u16le(map + 6) != RSM_MAPFILE_HEADER_BYTES) {
        return 0xFFFFFFFFu;
    }
    tiles = rsm_get_u32le(map + 24);
    if (tiles > (len - RSM_MAPFILE_HEADER_BYTES - 4u) / RSM_MAPFILE_TILE_BYTES) {
        return 0xFFFFFFFFu;
    }
    return tiles;
}

uint32_t rsm_tilestore_rom_index_log2(uint32_t tiles)
{
    return rsm_tilestore_mem_index_log2(tiles);
}

/* The tile number of a place, or 0xFFFFFFFF. */
static uint32_t rom_find(const rsm_tilestore_rom_t *m, uint32_t level, int32_t tx, int32_t ty)
{
    const uint32_t mask = (1u << m->index_log2) - 1u;
    uint32_t h = rsm_tmap_place_hash(level, tx, ty, m->index_log2);
    uint32_t probes;
    for (probes = 0; probes <= mask; ++probes) {
        const uint32_t k = m->index[h];
        rsm_tile_t t;
        if (k >= m->tiles) {
            return 0xFFFFFFFFu; /* erased: the place is not in the map */
        }
        rom_tile(m->map, k, &t);
        if (t.tx == tx && t.ty == ty && (t.stamp >> 30) == level) {
            return k;
        }
        h = (h + 1u) & mask;
    }
    return 0xFFFFFFFFu;
}

int rsm_tilestore_rom_build_index(const uint8_t *map, uint32_t len, const uint32_t *index, uint32_t index_log2,
                                  rsm_tilestore_program_fn program, void *ctx)
{
    rsm_tilestore_rom_t m;
    uint32_t k;
    if (map == NULL || index == NULL || program == NULL) {
        return RSM_ERR_INVAL;
    }
    m.tiles = rom_tiles(map, len);
    if (m.tiles == 0xFFFFFFFFu) {
        return RSM_ERR_FORMAT;
    }
    if (index_log2 > 30u || index_log2 < rsm_tilestore_rom_index_log2(m.tiles)) {
        return RSM_ERR_INVAL;
    }
    m.map = map;
    m.index = index;
    m.index_log2 = index_log2;
    for (k = 0; k < (1u << index_log2); ++k) {
        if (index[k] != 0xFFFFFFFFu) {
            return RSM_ERR_IO; /* not erased */
        }
    }
    for (k = 0; k < m.tiles; ++k) {
        const uint32_t mask = (1u << index_log2) - 1u;
        rsm_tile_t t;
        uint32_t h;
        rom_tile(map, k, &t);
        if (rom_find(&m, t.stamp >> 30, t.tx, t.ty) != 0xFFFFFFFFu) {
            return RSM_ERR_FORMAT;
        }
        h = rsm_tmap_place_hash(t.stamp >> 30, t.tx, t.ty, index_log2);
        while (index[h] != 0xFFFFFFFFu) {
            h = (h + 1u) & mask;
        }
        if (program(ctx, h, k) != 0 || index[h] != k) {
            return RSM_ERR_IO;
        }
    }
    return RSM_OK;
}

static int is_out(const rsm_tilestore_rom_t *m, uint32_t k)
{
    return (int)(((uint32_t)m->out[k >> 3] >> (k & 7u)) & 1u);
}

static void set_out(rsm_tilestore_rom_t *m, uint32_t k, int out)
{
    const uint8_t bit = (uint8_t)(1u << (k & 7u));
    m->out[k >> 3] = (uint8_t)(out ? m->out[k >> 3] | bit : m->out[k >> 3] & ~bit);
}

static int rom_put(void *ctx, const rsm_tile_t *t)
{
    rsm_tilestore_rom_t *m = (rsm_tilestore_rom_t *)ctx;
    const uint32_t k = rom_find(m, t->stamp >> 30, t->tx, t->ty);
    rsm_tile_t was;
    if (k == 0xFFFFFFFFu) {
        return RSM_ERR_NOMEM; /* a place the map in flash lacks: no room to keep it */
    }
    if (!is_out(m, k)) {
        return RSM_ERR_FORMAT;
    }
    rom_tile(m->map, k, &was);
    if (memcmp(was.cell, t->cell, sizeof was.cell) != 0) {
        return RSM_ERR_NOMEM; /* changed since: flash keeps the map as saved */
    }
    set_out(m, k, 0);
    m->held++;
    return RSM_OK;
}

static int rom_take(void *ctx, uint32_t level, int32_t tx, int32_t ty, rsm_tile_t *t)
{
    rsm_tilestore_rom_t *m = (rsm_tilestore_rom_t *)ctx;
    const uint32_t k = rom_find(m, level, tx, ty);
    if (k == 0xFFFFFFFFu || is_out(m, k)) {
        return 0;
    }
    rom_tile(m->map, k, t);
    set_out(m, k, 1);
    m->held--;
    return 1;
}

static uint32_t rom_count(const void *ctx)
{
    return ((const rsm_tilestore_rom_t *)ctx)->held;
}

static int rom_at(const void *ctx, uint32_t i, rsm_tile_t *t)
{
    /* The i-th tile held, in the map's order: a scan of the bitmap (a
     * save from flash is rare; a lookup by place is what runs). */
    const rsm_tilestore_rom_t *m = (const rsm_tilestore_rom_t *)ctx;
    uint32_t k;
    for (k = 0; k < m->tiles; ++k) {
        if (!is_out(m, k) && i-- == 0u) {
            rom_tile(m->map, k, t);
            return RSM_OK;
        }
    }
    return RSM_ERR_RANGE;
}

static void rom_clear(void *ctx)
{
    rsm_tilestore_rom_t *m = (rsm_tilestore_rom_t *)ctx;
    memset(m->out, 0xFF, ((size_t)m->tiles + 7u) / 8u);
    m->held = 0u;
}

/* The flash store's callbacks (ctx and capacity set by its init). */
static const rsm_tile_store_t rom_ops = {NULL, 0u, rom_put, rom_take, rom_count, rom_at, rom_clear};

int rsm_tilestore_rom_init(rsm_tilestore_rom_t *m, const uint8_t *map, uint32_t len, const uint32_t *index,
                           uint32_t index_log2, uint8_t *out, uint32_t out_bytes, rsm_tile_store_t *store)
{
    uint32_t tiles;
    if (m == NULL || map == NULL || index == NULL || out == NULL || store == NULL) {
        return RSM_ERR_INVAL;
    }
    tiles = rom_tiles(map, len);
    if (tiles == 0xFFFFFFFFu) {
        return RSM_ERR_FORMAT;
    }
    if (index_log2 > 30u || index_log2 < rsm_tilestore_rom_index_log2(tiles) || out_bytes < (tiles + 7u) / 8u) {
        return RSM_ERR_INVAL;
    }
    m->map = map;
    m->tiles = tiles;
    m->index = index;
    m->index_log2 = index_log2;
    m->out = out;
    rom_clear(m);
    *store = rom_ops;
    store->ctx = m;
    store->capacity = tiles;
    return RSM_OK;
}
