/* Persistent multi-resolution occupancy map in a fixed tile pool; see
 * src/map/tilemap.h for the contract and docs/map.md for the design. */
#include "core/hot.h" /* first: speed over size */
#include "map/tilemap.h"

#include <math.h>
#include <string.h>

#include "core/grid.h"
#include "rsm/status.h"
#include "core/bits.h"
#include "core/check.h"
#include "core/compiler.h"
#include "core/fmath.h"
#include "map/tmap_read.h"
#include "rsm/tilestore.h"

#define STAMP_MASK RSM_TMAP_STAMP_MASK
/* Set in a tile's stamp once one of its cells has reached saturation. */
#define CONFIRMED 0x20000000u

rsm_tmap_config_t rsm_tmap_config_default(void)
{
    rsm_tmap_config_t c;
    c.cell_m = RSM_TMAP_CELL_M;
    c.levels = (uint8_t)RSM_TMAP_LEVELS;
    c.hit_inc = 4u;
    c.miss_dec = 1u;
    c.saturation = 8u;
    c.clear_margin = 1u;
    c.splat_from = 1u;
    c.age_shift = 2u;
    c.unconfirmed_shift = 8u;
    c.wall_level = 1u;
    c.wall_value = 0u;
    c.wall_echo = 0u;
    c.write_cells = 4096u;
    return c;
}

static uint32_t tile_level(const rsm_tile_t *t)
{
    return t->stamp >> 30;
}

static uint32_t hash_key(uint32_t level, int32_t tx, int32_t ty)
{
    return rsm_tmap_place_hash(level, tx, ty, RSM_TMAP_HASH_LOG2);
}

int rsm_tmap_config_check(const rsm_tmap_config_t *cfg, const char **field)
{
    RSM_CHECK_FIELD(cfg != NULL, "tmap");
    RSM_CHECK_FIELD(cfg->cell_m > 0.0f && cfg->cell_m < 1.0e3f, "tmap.cell_m");
    RSM_CHECK_FIELD(cfg->levels >= 1u && cfg->levels <= RSM_TMAP_LEVELS, "tmap.levels");
    RSM_CHECK_FIELD(cfg->hit_inc >= 1u && cfg->hit_inc <= RSM_TMAP_MAX_VALUE, "tmap.hit_inc");
    RSM_CHECK_FIELD(cfg->miss_dec <= RSM_TMAP_MAX_VALUE, "tmap.miss_dec");
    RSM_CHECK_FIELD(cfg->saturation >= 1u && cfg->saturation <= RSM_TMAP_MAX_VALUE, "tmap.saturation");
    RSM_CHECK_FIELD(cfg->age_shift <= 8u, "tmap.age_shift");
    RSM_CHECK_FIELD(cfg->unconfirmed_shift <= 16u, "tmap.unconfirmed_shift");
    return RSM_OK;
}

int rsm_tmap_init(rsm_tmap_t *map, const rsm_tmap_config_t *cfg)
{
    uint32_t v;
    if (map == NULL || rsm_tmap_config_check(cfg, NULL) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    memset(map, 0, sizeof *map);
    map->cfg = *cfg;
    map->write_hit = cfg->hit_inc;
    for (v = 0; v <= RSM_TMAP_MAX_VALUE; ++v) {
        map->occ[v] = v >= cfg->saturation ? 1.0f : (float)v / (float)cfg->saturation;
    }
    for (v = 0; v < (uint32_t)RSM_TMAP_LEVELS; ++v) {
        map->inv_cell[v] = 1.0f / (cfg->cell_m * (float)(1u << v));
    }
    memset(map->hash, 0xFF, sizeof map->hash);
    return RSM_OK;
}

void rsm_tmap_reset(rsm_tmap_t *map)
{
    const rsm_tile_store_t *store = map->store;
    const rsm_tmap_config_t cfg = map->cfg;
    (void)rsm_tmap_init(map, &cfg);
    map->store = store;
    if (store != NULL) {
        store->clear(store->ctx);
    }
}

float rsm_tmap_cell(const rsm_tmap_t *map, uint32_t level)
{
    return map->cfg.cell_m * (float)(1u << level);
}

uint32_t rsm_tmap_find_slot(const rsm_tmap_t *map, uint32_t level, int32_t tx, int32_t ty)
{
    /* Tile coordinates fit int16 (RSM_TMAP_TILE_LIMIT), so the packed
     * pair compares both at once (one load where the compiler merges the
     * two halves). */
    const uint32_t key = rsm_tmap_pack(tx, ty);
    uint32_t h = hash_key(level, tx, ty);
    for (;;) {
        const uint32_t s = map->hash[h];
        const rsm_tile_t *t;
        if (s == RSM_TMAP_NONE) {
            return RSM_TMAP_NONE;
        }
        t = &map->tile[s];
        if (rsm_tmap_pack(t->tx, t->ty) == key && tile_level(t) == level) {
            return s;
        }
        h = (h + 1u) & (RSM_TMAP_HASH - 1u);
    }
}

/* Removes the tile in slot s from the hash (backward-shift deletion keeps
 * every other key reachable without tombstones). */
static void hash_remove(rsm_tmap_t *map, uint32_t s)
{
    const rsm_tile_t *t = &map->tile[s];
    uint32_t i = hash_key(tile_level(t), t->tx, t->ty);
    uint32_t j;
    while (map->hash[i] != s) {
        i = (i + 1u) & (RSM_TMAP_HASH - 1u);
    }
    j = i;
    for (;;) {
        uint32_t home;
        const rsm_tile_t *u;
        j = (j + 1u) & (RSM_TMAP_HASH - 1u);
        if (map->hash[j] == RSM_TMAP_NONE) {
            break;
        }
        u = &map->tile[map->hash[j]];
        home = hash_key(tile_level(u), u->tx, u->ty);
        /* Move j's entry into the hole at i unless its home lies in (i, j]. */
        if (((j - home) & (RSM_TMAP_HASH - 1u)) >= ((j - i) & (RSM_TMAP_HASH - 1u))) {
            map->hash[i] = map->hash[j];
            i = j;
        }
    }
    map->hash[i] = (uint16_t)RSM_TMAP_NONE;
}

/* How far a tile of the given age (in writes) is from being kept: the age
 * divided by 2^(age_shift * level), times 2^unconfirmed_shift when no cell
 * of it reached saturation. */
static uint32_t scaled_age(const rsm_tmap_t *map, const rsm_tile_t *t, uint32_t age)
{
    const uint32_t scaled = age >> (map->cfg.age_shift * tile_level(t));
    if ((t->stamp & CONFIRMED) != 0u) {
        return scaled;
    }
    return scaled < (STAMP_MASK >> map->cfg.unconfirmed_shift) ? scaled << map->cfg.unconfirmed_shift : STAMP_MASK;
}

/* Searches the whole pool for the RSM_TMAP_VICTIMS tiles oldest_slot
 * would evict first: largest scaled age first, the lower slot first
 * among equals; none written by the update in progress. */
static void find_victims(rsm_tmap_t *map)
{
    uint32_t best[RSM_TMAP_VICTIMS];
    uint32_t n = 0;
    uint32_t k;
    for (k = 0; k < map->used; ++k) {
        const rsm_tile_t *t = &map->tile[k];
        const uint32_t age = (map->stamp - (t->stamp & STAMP_MASK)) & STAMP_MASK;
        uint32_t scaled;
        uint32_t at;
        if (age == 0u) {
            continue; /* written by the update in progress */
        }
        if (map->store != NULL && tile_level(t) + 1u == (uint32_t)map->cfg.levels) {
            /* With a store the coarsest level stays whole (a 64th of the
             * finest's tiles with four levels): the levels below come back
             * under it by place (rsm_tmap_take_back). */
            continue;
        }
        scaled = scaled_age(map, t, age);
        if (n == (uint32_t)RSM_TMAP_VICTIMS && !(scaled > best[n - 1u])) {
            continue;
        }
        /* After every entry at least as old: equals stay in slot order. */
        at = n < (uint32_t)RSM_TMAP_VICTIMS ? n : n - 1u;
        while (at > 0u && best[at - 1u] < scaled) {
            best[at] = best[at - 1u];
            map->victim_slot[at] = map->victim_slot[at - 1u];
            map->victim_stamp[at] = map->victim_stamp[at - 1u];
            --at;
        }
        best[at] = scaled;
        map->victim_slot[at] = (uint16_t)k;
        map->victim_stamp[at] = t->stamp;
        if (n < (uint32_t)RSM_TMAP_VICTIMS) {
            ++n;
        }
    }
    map->victims = n;
    map->victim_next = 0;
}

/* The slot to reuse: the one written longest ago, where a tile's age counts
 * 4^-level (a coarse tile holds 4^level times the area of a fine one for the
 * same bytes, so the building's outline outlives the fine detail around
 * it), and 2^unconfirmed_shift times more while no cell of it has reached
 * saturation (one stray return: a phantom, unless a second return confirms
 * it; phantoms in free space would otherwise push out the places seen
 * minutes ago). Never a slot written by the update in progress;
 * RSM_TMAP_NONE if every slot was. */
static uint32_t oldest_slot(rsm_tmap_t *map)
{
    int search;
    /* The list first, then, if none of it is left, one new search. */
    for (search = 0; search < 2; ++search) {
        while (map->victim_next < map->victims) {
            const uint32_t s = map->victim_slot[map->victim_next++];
            if (s < map->used && map->tile[s].stamp == map->victim_stamp[map->victim_next - 1u]) {
                return s;
            }
        }
        if (search == 0) {
            find_victims(map);
        }
    }
    return RSM_TMAP_NONE; /* every slot was written by this update */
}

/* A tile that ends (rsm_tmap_t.churn). */
static void ended(rsm_tmap_t *map, const rsm_tile_t *t)
{
    const uint32_t level = tile_level(t);
    map->churn[level]--;
    map->churn_sig[level] -= rsm_tmap_place_sig(level, t->tx, t->ty);
}

/* The tile in slot s is let go: into the store, if there is one. */
static void let_go(rsm_tmap_t *map, uint32_t s)
{
    if (map->store != NULL && map->store->put(map->store->ctx, &map->tile[s]) == RSM_OK) {
        map->counters.stored++;
        return;
    }
    if (map->store != NULL) {
        map->counters.unstored++;
    }
    ended(map, &map->tile[s]);
}

/* Slot for a tile that is not held: a free one, else oldest_slot's (its
 * tile let go); placed and indexed, its cells and stamp the caller's.
 * RSM_TMAP_NONE if none. */
static uint32_t claim_slot(rsm_tmap_t *map, uint32_t level, int32_t tx, int32_t ty)
{
    uint32_t s;
    uint32_t h;
    rsm_tile_t *t;
    if (map->used < (uint32_t)RSM_TMAP_TILES) {
        s = map->used++;
        map->counters.allocated++;
    } else {
        s = oldest_slot(map);
        if (s == RSM_TMAP_NONE) {
            return RSM_TMAP_NONE;
        }
        let_go(map, s);
        hash_remove(map, s);
        map->level_used[tile_level(&map->tile[s])]--;
        map->counters.evicted++;
    }
    map->level_used[level]++;
    t = &map->tile[s];
    t->tx = (int16_t)tx;
    t->ty = (int16_t)ty;
    h = hash_key(level, tx, ty);
    while (map->hash[h] != RSM_TMAP_NONE) {
        h = (h + 1u) & (RSM_TMAP_HASH - 1u);
    }
    map->hash[h] = (uint16_t)s;
    return s;
}

/* A tile back from the store into slot s (placed by claim_slot): its
 * cells, and the current write counter, so that it is not the first to go
 * again while the robot is there. */
static void put_back(rsm_tmap_t *map, uint32_t s, uint32_t level, const rsm_tile_t *from)
{
    rsm_tile_t *t = &map->tile[s];
    memcpy(t->cell, from->cell, sizeof t->cell);
    t->stamp = (level << 30) | (from->stamp & CONFIRMED) | map->stamp;
    map->counters.fetched++;
}

/* Takes the tile of (level, tx, ty) from the store into *t: 1 if it held
 * it (a tile for another place, which no sound store gives, is dropped). */
static int from_store(rsm_tmap_t *map, uint32_t level, int32_t tx, int32_t ty, rsm_tile_t *t)
{
    if (map->store == NULL || map->store->take(map->store->ctx, level, tx, ty, t) != 1) {
        return 0;
    }
    return t->tx == tx && t->ty == ty && tile_level(t) == level;
}

/* Slot for a tile that is not held, with the store's copy of it if there
 * is one, else empty. RSM_TMAP_NONE if no slot. */
static uint32_t take_slot(rsm_tmap_t *map, uint32_t level, int32_t tx, int32_t ty)
{
    const uint32_t s = claim_slot(map, level, tx, ty);
    rsm_tile_t stored;
    if (s == RSM_TMAP_NONE) {
        return s;
    }
    if (from_store(map, level, tx, ty, &stored)) {
        put_back(map, s, level, &stored);
    } else {
        rsm_tile_t *t = &map->tile[s];
        t->stamp = (level << 30) | map->stamp;
        memset(t->cell, 0, sizeof t->cell);
        map->churn[level]++;
        map->churn_sig[level] += rsm_tmap_place_sig(level, tx, ty);
    }
    return s;
}

int rsm_tmap_restore(rsm_tmap_t *map, const rsm_tile_t *t)
{
    const uint32_t level = tile_level(t);
    const int32_t lim = RSM_TMAP_TILE_LIMIT;
    uint32_t h;
    if (level >= (uint32_t)map->cfg.levels || t->tx <= -lim || t->tx >= lim || t->ty <= -lim || t->ty >= lim ||
        (t->stamp & RSM_TMAP_STAMP_MASK) > map->stamp ||
        rsm_tmap_find_slot(map, level, t->tx, t->ty) != RSM_TMAP_NONE) {
        return RSM_ERR_FORMAT;
    }
    if (map->used >= (uint32_t)RSM_TMAP_TILES) {
        return RSM_ERR_NOMEM;
    }
    map->tile[map->used] = *t;
    h = hash_key(level, t->tx, t->ty);
    while (map->hash[h] != RSM_TMAP_NONE) {
        h = (h + 1u) & (RSM_TMAP_HASH - 1u);
    }
    map->hash[h] = map->used;
    map->level_used[level]++;
    map->used++;
    return RSM_OK;
}

/* Gives back the slot of a tile that holds nothing any more (every cell 0,
 * which reads the same as no tile): the last slot in use moves into it, so
 * slots stay dense. */
static void free_slot(rsm_tmap_t *map, uint32_t s)
{
    const uint32_t last = (uint32_t)map->used - 1u;
    ended(map, &map->tile[s]);
    hash_remove(map, s);
    map->level_used[tile_level(&map->tile[s])]--;
    if (s != last) {
        const rsm_tile_t *t = &map->tile[last];
        uint32_t h = hash_key(tile_level(t), t->tx, t->ty);
        while (map->hash[h] != last) {
            h = (h + 1u) & (RSM_TMAP_HASH - 1u);
        }
        map->hash[h] = (uint16_t)s;
        map->tile[s] = *t;
    }
    map->used--;
    map->counters.freed++;
    map->victims = 0; /* a slot moved: search again */
}

static int tile_empty(const rsm_tile_t *t)
{
    uint32_t k;
    for (k = 0; k < (uint32_t)RSM_TMAP_TILE_BYTES; ++k) {
        if (t->cell[k] != 0u) {
            return 0;
        }
    }
    return 1;
}

void rsm_tmap_cursor_init(rsm_tmap_cursor_t *c, uint32_t level)
{
    uint32_t k;
    /* Every field set once (a memset first and then the keys was most of
     * this, which the map matcher runs on each of its passes). */
    c->level = level;
    for (k = 0; k < RSM_TMAP_CURSOR_WAYS * RSM_TMAP_CURSOR_WAYS; ++k) {
        c->way[k].key = RSM_TMAP_NO_KEY;
        c->way[k].slot = 0u;
    }
    rsm_tmap_window_forget(&c->win);
}

static void set_cell(rsm_tile_t *t, uint32_t i, uint32_t v)
{
    const uint32_t sh = (i & 1u) << 2;
    t->cell[i >> 1] = (uint8_t)(((uint32_t)t->cell[i >> 1] & ~(15u << sh)) | (v << sh));
}

uint8_t rsm_tmap_value(const rsm_tmap_t *map, uint32_t level, int32_t gx, int32_t gy)
{
    uint32_t s;
    if (map == NULL || level >= map->cfg.levels || !rsm_tmap_in_range(gx, gy)) {
        return 0;
    }
    s = rsm_tmap_find_slot(map, level, gx >> RSM_TMAP_TILE_LOG2, gy >> RSM_TMAP_TILE_LOG2);
    return s == RSM_TMAP_NONE ? 0u : (uint8_t)rsm_tmap_get_cell(&map->tile[s], rsm_tmap_cell_index(gx, gy));
}

uint32_t rsm_tmap_tiles(const rsm_tmap_t *map, uint32_t level)
{
    return level < (uint32_t)RSM_TMAP_LEVELS ? map->level_used[level] : 0u;
}

int rsm_tmap_bounds(const rsm_tmap_t *map, uint32_t level, int32_t *gx0, int32_t *gy0, int32_t *gx1, int32_t *gy1)
{
    uint32_t k;
    int any = 0;
    for (k = 0; k < map->used; ++k) {
        const rsm_tile_t *t = &map->tile[k];
        const int32_t x0 = (int32_t)t->tx * RSM_TMAP_TILE_SIDE;
        const int32_t y0 = (int32_t)t->ty * RSM_TMAP_TILE_SIDE;
        if (tile_level(t) != level) {
            continue;
        }
        if (!any || x0 < *gx0) {
            *gx0 = x0;
        }
        if (!any || y0 < *gy0) {
            *gy0 = y0;
        }
        if (!any || x0 + RSM_TMAP_TILE_MASK > *gx1) {
            *gx1 = x0 + RSM_TMAP_TILE_MASK;
        }
        if (!any || y0 + RSM_TMAP_TILE_MASK > *gy1) {
            *gy1 = y0 + RSM_TMAP_TILE_MASK;
        }
        any = 1;
    }
    return any;
}

/* Lowers the cells from (x0, y0) towards (x1, y1), stopping margin + 1
 * cells short of the end, and returns the highest value the beam met
 * (before lowering it). The cells are Bresenham's, one per step along the
 * major axis (the one with the larger extent, which steps every time) and
 * a step along the minor one when the error term says so. Most cells are
 * in tiles the pool does not hold, or hold 0, so the walk goes tile by
 * tile: one lookup per tile, then a loop over its cells that only steps
 * where no tile is held, and inside a held one moves the cell's index
 * with the step instead of recomputing it. adx and ady are the beam's
 * extents; xmajor (a constant in each caller) says adx >= ady. */
static RSM_ALWAYS_INLINE uint32_t walk_beam(rsm_tmap_t *map, rsm_tmap_cursor_t *c, int32_t x0, int32_t y0,
                                            int32_t x1, int32_t y1, int32_t adx, int32_t ady, uint32_t dec,
                                            uint32_t margin, const int xmajor)
{
    const int32_t big = xmajor ? adx : ady;   /* extent along the major axis */
    const int32_t small = xmajor ? ady : adx; /* and along the minor one */
    const int32_t su = (xmajor ? x1 > x0 : y1 > y0) ? 1 : -1;
    const int32_t sv = (xmajor ? y1 > y0 : x1 > x0) ? 1 : -1;
    /* The minor coordinate's offset in its tile right after it entered the
     * next tile. */
    const int32_t v_in = sv > 0 ? 0 : RSM_TMAP_TILE_MASK;
    /* Index steps within a tile for a major and a minor step. */
    const int32_t di_u = xmajor ? su : su * (int32_t)RSM_TMAP_TILE_SIDE;
    const int32_t di_v = xmajor ? sv * (int32_t)RSM_TMAP_TILE_SIDE : sv;
    int32_t u = xmajor ? x0 : y0;
    int32_t v = xmajor ? y0 : x0;
    int32_t err = big - small;
    int32_t left = big - (int32_t)margin;
    uint32_t top = 0;
    while (left > 0) {
        const int32_t x = xmajor ? u : v;
        const int32_t y = xmajor ? v : u;
        const int32_t ru = su > 0 ? RSM_TMAP_TILE_MASK - (u & RSM_TMAP_TILE_MASK) : (u & RSM_TMAP_TILE_MASK);
        const int32_t run = ru + 1 < left ? ru + 1 : left;
        const uint32_t s = rsm_tmap_cursor_slot(map, c, x, y);
        int32_t n = run;
        if (s == RSM_TMAP_NONE) {
            while (n > 0) {
                const int32_t e2 = 2 * err;
                --n;
                err -= small;
                if (e2 < big) {
                    err += big;
                    v += sv;
                    if ((v & RSM_TMAP_TILE_MASK) == v_in) {
                        break;
                    }
                }
            }
        } else {
            rsm_tile_t *t = &map->tile[s];
            int32_t i = (int32_t)rsm_tmap_cell_index(x, y);
            while (n > 0) {
                const uint32_t val = rsm_tmap_get_cell(t, (uint32_t)i);
                const int32_t e2 = 2 * err;
                int freed = 0;
                top = val > top ? val : top;
                if (val > dec) {
                    set_cell(t, (uint32_t)i, val - dec);
                } else if (val != 0u) {
                    set_cell(t, (uint32_t)i, 0u);
                    if (tile_empty(t)) {
                        free_slot(map, s);
                        rsm_tmap_cursor_forget(c);
                        freed = 1;
                    }
                }
                --n;
                err -= small;
                i += di_u;
                if (e2 < big) {
                    err += big;
                    v += sv;
                    i += di_v;
                    if ((v & RSM_TMAP_TILE_MASK) == v_in) {
                        break;
                    }
                }
                if (freed) {
                    break; /* the rest of the tile reads as none */
                }
            }
        }
        u += su * (run - n);
        left -= run - n;
    }
    return top;
}

/* walk_beam with one copy per major axis, each with its axes fixed. Not
 * inlined: inside the write loop the compiler spilled the walk's state on
 * a Cortex-M4, a third of each step. */
static RSM_NOINLINE uint32_t clear_beam(rsm_tmap_t *map, rsm_tmap_cursor_t *c, int32_t x0, int32_t y0, int32_t x1,
                                        int32_t y1, uint32_t dec, uint32_t margin)
{
    const int32_t adx = x1 > x0 ? x1 - x0 : x0 - x1;
    const int32_t ady = y1 > y0 ? y1 - y0 : y0 - y1;
    return adx >= ady ? walk_beam(map, c, x0, y0, x1, y1, adx, ady, dec, margin, 1)
                      : walk_beam(map, c, x0, y0, x1, y1, adx, ady, dec, margin, 0);
}

/* The highest value on a beam's cells from (x0, y0) towards (x1, y1),
 * stopping margin + 1 cells short of the end, stepping as walk_beam does
 * but reading only, one cell at a time (it runs on the rare scans that
 * fitted poorly, not on every write). */
static uint32_t beam_top(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, int32_t x0, int32_t y0, int32_t x1, int32_t y1,
                         uint32_t margin)
{
    const int32_t adx = x1 > x0 ? x1 - x0 : x0 - x1;
    const int32_t ady = y1 > y0 ? y1 - y0 : y0 - y1;
    const int32_t sx = x1 > x0 ? 1 : -1;
    const int32_t sy = y1 > y0 ? 1 : -1;
    const int32_t big = adx >= ady ? adx : ady;
    int32_t err = adx - ady;
    int32_t left = big - (int32_t)margin;
    int32_t x = x0;
    int32_t y = y0;
    uint32_t top = 0;
    while (left > 0) {
        const uint32_t v = rsm_tmap_cell_value(map, c, x, y);
        const int32_t e2 = 2 * err;
        top = v > top ? v : top;
        if (e2 > -ady) {
            err -= ady;
            x += sx;
        }
        if (e2 < adx) {
            err += adx;
            y += sy;
        }
        --left;
    }
    return top;
}

uint32_t rsm_tmap_beams_crossing(const rsm_tmap_t *map, uint32_t level, const rsm_pose_t *pose,
                                 const rsm_point_t *origin, const rsm_point_t *pts, size_t n, size_t stride,
                                 uint32_t value, uint32_t margin, uint32_t *checked)
{
    rsm_tmap_cursor_t c;
    rsm_point_t o;
    float inv;
    int32_t ox;
    int32_t oy;
    uint32_t crossing = 0;
    uint32_t looked = 0;
    size_t k;
    if (checked != NULL) {
        *checked = 0u;
    }
    if (map == NULL || pose == NULL || origin == NULL || pts == NULL || stride == 0u || level >= map->cfg.levels) {
        return 0u;
    }
    inv = 1.0f / rsm_tmap_cell(map, level);
    o = rsm_pose_apply(pose, origin);
    ox = rsm_tmap_cell_of(o.x, inv);
    oy = rsm_tmap_cell_of(o.y, inv);
    if (!rsm_tmap_in_range(ox, oy)) {
        return 0u;
    }
    rsm_tmap_cursor_init(&c, level);
    for (k = 0; k < n; k += stride) {
        const rsm_point_t w = rsm_pose_apply(pose, &pts[k]);
        const int32_t gx = rsm_tmap_cell_of(w.x, inv);
        const int32_t gy = rsm_tmap_cell_of(w.y, inv);
        if (!rsm_tmap_in_range(gx, gy)) {
            continue;
        }
        ++looked;
        if (beam_top(map, &c, ox, oy, gx, gy, margin) >= value) {
            ++crossing;
        }
    }
    if (checked != NULL) {
        *checked = looked;
    }
    return crossing;
}

/* The slot of the tile holding a cell, taking one for it if needed;
 * RSM_TMAP_NONE (counted as dropped) when every slot is in use by the write. */
static uint32_t slot_for(rsm_tmap_t *map, rsm_tmap_cursor_t *c, uint32_t level, int32_t gx, int32_t gy)
{
    uint32_t s = rsm_tmap_cursor_slot(map, c, gx, gy);
    if (s == RSM_TMAP_NONE) {
        s = take_slot(map, level, gx >> RSM_TMAP_TILE_LOG2, gy >> RSM_TMAP_TILE_LOG2);
        rsm_tmap_cursor_forget(c);
        if (s == RSM_TMAP_NONE) {
            map->counters.dropped++;
        }
    }
    return s;
}

/* Adds inc to a cell, taking a tile for it if needed. */
static void add_hit(rsm_tmap_t *map, rsm_tmap_cursor_t *c, uint32_t level, int32_t gx, int32_t gy, uint32_t inc)
{
    uint32_t s;
    uint32_t i;
    uint32_t v;
    rsm_tile_t *t;
    if (inc == 0u || (s = slot_for(map, c, level, gx, gy)) == RSM_TMAP_NONE) {
        return;
    }
    t = &map->tile[s];
    i = rsm_tmap_cell_index(gx, gy);
    v = rsm_tmap_get_cell(t, i) + inc;
    v = v > RSM_TMAP_MAX_VALUE ? RSM_TMAP_MAX_VALUE : v;
    t->stamp = (level << 30) | (t->stamp & CONFIRMED) | (v >= map->cfg.saturation ? CONFIRMED : 0u) | map->stamp;
    set_cell(t, i, v);
}

/* Bit of the echo set for a cell (multiplicative hashing of the packed
 * cell; a collision only lets a phantom through now and then). */
static uint32_t echo_bit(int32_t gx, int32_t gy)
{
    return rsm_tmap_mix(rsm_tmap_pack(gx, gy), RSM_TMAP_ECHO_LOG2);
}

/* rsm_tmap_config_t.wall_echo: marks in lone the returns that land neither
 * within one cell of a saturated cell of level judge nor within one cell of
 * a return of the previous write, then remembers this write's returns for
 * the next. */
static void mark_lone(rsm_tmap_t *map, uint32_t judge, const rsm_point_t *points, size_t n, uint8_t *lone)
{
    const float inv_a = map->inv_cell[judge];
    rsm_tmap_cursor_t c;
    size_t k;
    rsm_tmap_cursor_init(&c, judge);
    for (k = 0; k < n && k < (size_t)RSM_MAX_BEAMS; ++k) {
        const int32_t gx = rsm_tmap_cell_of(points[k].x, inv_a);
        const int32_t gy = rsm_tmap_cell_of(points[k].y, inv_a);
        int32_t dx;
        int32_t dy;
        int seen = 0;
        if (!rsm_tmap_in_range(gx - 1, gy - 1) || !rsm_tmap_in_range(gx + 1, gy + 1)) {
            continue; /* refused later as outside */
        }
        for (dy = -1; dy <= 1 && !seen; ++dy) {
            for (dx = -1; dx <= 1 && !seen; ++dx) {
                seen = rsm_bit_get(map->echo, echo_bit(gx + dx, gy + dy)) ||
                       rsm_tmap_cell_value(map, &c, gx + dx, gy + dy) >= map->cfg.saturation;
            }
        }
        if (!seen) {
            rsm_bit_set(lone, k);
        }
    }
    memset(map->echo, 0, sizeof map->echo);
    for (k = 0; k < n; ++k) {
        const int32_t gx = rsm_tmap_cell_of(points[k].x, inv_a);
        const int32_t gy = rsm_tmap_cell_of(points[k].y, inv_a);
        if (rsm_tmap_in_range(gx, gy)) {
            rsm_bit_set(map->echo, echo_bit(gx, gy));
        }
    }
}

/* Level of pass index idx: with the wall rule on, wall_level is written
 * first, so that every level knows which returns lie behind a wall; else
 * finest first, the level a write delayed over scans would cost most. */
static uint32_t pass_level(const rsm_tmap_t *map, uint32_t idx)
{
    const uint32_t judge =
        map->cfg.wall_value > 0u && map->cfg.wall_level < map->cfg.levels ? map->cfg.wall_level : 0u;
    return idx == 0u ? judge : (idx <= judge ? idx - 1u : idx);
}

int rsm_tmap_write_begin(rsm_tmap_t *map, const rsm_point_t *origin, const rsm_point_t *points, size_t n)
{
    rsm_tmap_job_t *job;
    uint32_t level;
    if (map == NULL || origin == NULL || (n > 0u && points == NULL) || !isfinite(origin->x) ||
        !isfinite(origin->y) || n > 0xFFFFFFFFu || map->job.n != 0u) {
        return RSM_ERR_INVAL;
    }
    for (level = 0; level < map->cfg.levels; ++level) {
        const float inv = map->inv_cell[level];
        if (!rsm_tmap_in_range(rsm_tmap_cell_of(origin->x, inv), rsm_tmap_cell_of(origin->y, inv))) {
            return RSM_ERR_INVAL;
        }
    }
    job = &map->job;
    memset(job, 0, sizeof *job);
    map->stamp = (map->stamp + 1u) & STAMP_MASK;
    map->victims = 0; /* found in an earlier write: ages have moved */
    map->counters.updates++;
    if (map->cfg.wall_echo != 0u && map->cfg.wall_value > 0u) {
        mark_lone(map, pass_level(map, 0u), points, n, job->lone);
    }
    job->origin = *origin;
    job->n = (uint32_t)n;
    return RSM_OK;
}

/* The beam pass of one return: clears its beam and, on wall_level, marks
 * the return behind a wall when its beam crossed one (a cell at wall_value
 * or above) without landing on one: behind a wall the laser cannot see, so
 * the return is a phantom (noise, a reflection) or the wall has gone;
 * either way it is not written until the beams have worn the wall down (or,
 * with wall_echo, the last write saw it too). Returns the cells it visited. */
static uint32_t clear_one(rsm_tmap_t *map, rsm_tmap_cursor_t *c, uint32_t idx, int32_t ox, int32_t oy,
                          const rsm_point_t *p, size_t k)
{
    rsm_tmap_job_t *job = &map->job;
    const float inv_a = map->inv_cell[c->level];
    int32_t gx;
    int32_t gy;
    uint32_t top;
    if (!(fabsf(p->x) < 1.0e6f && fabsf(p->y) < 1.0e6f)) {
        return 1u;
    }
    gx = rsm_tmap_cell_of(p->x, inv_a);
    gy = rsm_tmap_cell_of(p->y, inv_a);
    if (!rsm_tmap_in_range(gx, gy)) {
        return 1u;
    }
    top = clear_beam(map, c, ox, oy, gx, gy, map->cfg.miss_dec, map->cfg.clear_margin);
    if (map->cfg.wall_value > 0u && idx == 0u && top >= map->cfg.wall_value && k < (size_t)RSM_MAX_BEAMS &&
        (map->cfg.wall_echo == 0u || rsm_bit_get(job->lone, k)) &&
        rsm_tmap_cell_value(map, c, gx, gy) < map->cfg.wall_value) {
        rsm_bit_set(job->behind, k);
        map->counters.behind++;
    }
    gx = gx > ox ? gx - ox : ox - gx;
    gy = gy > oy ? gy - oy : oy - gy;
    return 1u + (uint32_t)(gx > gy ? gx : gy);
}

/* The return pass of one return: adds its hit. */
static void hit_one(rsm_tmap_t *map, rsm_tmap_cursor_t *c, const rsm_point_t *p, size_t k)
{
    const uint32_t level = c->level;
    const float inv_a = map->inv_cell[level];
    if (!(fabsf(p->x) < 1.0e6f && fabsf(p->y) < 1.0e6f)) {
        return;
    }
    if (k < (size_t)RSM_MAX_BEAMS && rsm_bit_get(map->job.behind, k)) {
        return;
    }
    if (level >= map->cfg.splat_from) {
        /* Share the increment among the four cells around the point by
         * bilinear weights, so that the interpolated occupancy peaks where
         * the returns are, not at cell centres. */
        const rsm_bilinear_t b = rsm_bilinear_at(p->x, p->y, inv_a);
        const int32_t gx = b.i;
        const int32_t gy = b.j;
        const float du = b.du;
        const float dv = b.dv;
        const float f = (float)map->write_hit;
        if (!rsm_tmap_in_range(gx, gy) || !rsm_tmap_in_range(gx + 1, gy + 1)) {
            map->counters.outside++;
            return;
        }
        add_hit(map, c, level, gx, gy, (uint32_t)(f * (1.0f - du) * (1.0f - dv) + 0.5f));
        add_hit(map, c, level, gx + 1, gy, (uint32_t)(f * du * (1.0f - dv) + 0.5f));
        add_hit(map, c, level, gx, gy + 1, (uint32_t)(f * (1.0f - du) * dv + 0.5f));
        add_hit(map, c, level, gx + 1, gy + 1, (uint32_t)(f * du * dv + 0.5f));
    } else {
        const int32_t gx = rsm_tmap_cell_of(p->x, inv_a);
        const int32_t gy = rsm_tmap_cell_of(p->y, inv_a);
        if (!rsm_tmap_in_range(gx, gy)) {
            map->counters.outside++;
            return;
        }
        add_hit(map, c, level, gx, gy, map->write_hit);
    }
}

int rsm_tmap_write_run(rsm_tmap_t *map, const rsm_point_t *points, uint32_t budget)
{
    rsm_tmap_job_t *job;
    uint32_t spent = 0;
    if (map == NULL || (map->job.n > 0u && points == NULL)) {
        return 0;
    }
    job = &map->job;
    while (job->n > 0u) {
        const uint32_t idx = job->pass;
        const uint32_t level = pass_level(map, idx);
        const float inv_a = map->inv_cell[level];
        const int32_t ox = rsm_tmap_cell_of(job->origin.x, inv_a);
        const int32_t oy = rsm_tmap_cell_of(job->origin.y, inv_a);
        uint32_t end = job->next;
        uint32_t k;
        rsm_tmap_cursor_t c;
        /* A sector of consecutive beams within the budget, then their
         * returns: beams of one sector seldom cross the returns of
         * another, so a level written sector by sector over several scans
         * ends nearly as one written whole, and never reads worn. */
        rsm_tmap_cursor_init(&c, level);
        if (map->cfg.miss_dec == 0u) {
            end = job->n;
        }
        while (end < job->n && (budget == 0u || spent < budget)) {
            spent += clear_one(map, &c, idx, ox, oy, &points[end], end);
            ++end;
        }
        for (k = job->next; k < end; ++k) {
            hit_one(map, &c, &points[k], k);
            spent += 1u;
        }
        job->next = end;
        if (end == job->n) {
            job->next = 0;
            job->pass++;
            if (job->pass >= map->cfg.levels) {
                job->n = 0;
                return 0;
            }
        }
        if (budget > 0u && spent >= budget) {
            return 1;
        }
    }
    return 0;
}

int rsm_tmap_writing(const rsm_tmap_t *map)
{
    return map != NULL && map->job.n > 0u;
}

int rsm_tmap_update(rsm_tmap_t *map, const rsm_point_t *origin, const rsm_point_t *points, size_t n)
{
    int rc;
    if (map != NULL && map->job.n > 0u) {
        return RSM_ERR_INVAL;
    }
    rc = rsm_tmap_write_begin(map, origin, points, n);
    if (rc == RSM_OK) {
        (void)rsm_tmap_write_run(map, points, 0u);
    }
    return rc;
}

float rsm_tmap_occupancy(const rsm_tmap_t *map, uint32_t level, float x, float y)
{
    rsm_tmap_cursor_t c;
    rsm_tmap_cursor_init(&c, level);
    return rsm_tmap_occupancy_at(map, &c, x, y);
}

float rsm_tmap_occupancy_at(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, float x, float y)
{
    const float inv_a = map->inv_cell[c->level];
    const int32_t gx = rsm_tmap_cell_of(x, inv_a);
    const int32_t gy = rsm_tmap_cell_of(y, inv_a);
    return rsm_tmap_in_range(gx, gy) ? map->occ[rsm_tmap_cell_value(map, c, gx, gy)] : 0.0f;
}

/* Read where the pool holds no tile: its cells are 0, as such a place
 * reads (occupancy +0), so the straddle's reads need no test for it. */
static const rsm_tile_t empty_tile = {0, 0, 0u, {0u}};

/* The tile holding cell (gx, gy) of the cursor's level, or empty_tile. */
static const rsm_tile_t *tile_of(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, int32_t gx, int32_t gy)
{
    const uint32_t s = rsm_tmap_cursor_slot(map, c, gx, gy);
    return s == RSM_TMAP_NONE ? &empty_tile : &map->tile[s];
}

/* The occupancy of the cell in nibble sh (0 or 4) of byte b of tile t:
 * rsm_tmap_get_cell, its index split once for the four cells. */
static float occ_at(const rsm_tmap_t *map, const rsm_tile_t *t, uint32_t b, uint32_t sh)
{
    return map->occ[((uint32_t)t->cell[b] >> sh) & 15u];
}

/* The tile of cell (i, j) (t when own: the caller's, NULL for none held;
 * looked up otherwise), and those of (i + 1, j), (i, j + 1) and
 * (i + 1, j + 1) into t10, t01 and t11, looked up only past a tile's edge. */
static RSM_ALWAYS_INLINE const rsm_tile_t *straddle_tiles(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, int own,
                                                          const rsm_tile_t *t, int32_t i, int32_t j,
                                                          const rsm_tile_t **t10, const rsm_tile_t **t01,
                                                          const rsm_tile_t **t11)
{
    const int edge_i = (i & RSM_TMAP_TILE_MASK) == RSM_TMAP_TILE_MASK;
    const int edge_j = (j & RSM_TMAP_TILE_MASK) == RSM_TMAP_TILE_MASK;
    const rsm_tile_t *t00 = !own ? tile_of(map, c, i, j) : t != NULL ? t : &empty_tile;
    *t10 = edge_i ? tile_of(map, c, i + 1, j) : t00;
    *t01 = edge_j ? tile_of(map, c, i, j + 1) : t00;
    *t11 = !edge_j ? *t10 : !edge_i ? *t01 : tile_of(map, c, i + 1, j + 1);
    return t00;
}

const rsm_tile_t *rsm_tmap_straddle(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, int own, const rsm_tile_t *t,
                                    int32_t i, int32_t j, float m[4])
{
    const rsm_tile_t *t10;
    const rsm_tile_t *t01;
    const rsm_tile_t *t11;
    const rsm_tile_t *t00 = straddle_tiles(map, c, own, t, i, j, &t10, &t01, &t11);
    /* Bytes of the two rows, byte and nibble of the two columns. */
    const uint32_t mask = (uint32_t)RSM_TMAP_TILE_MASK;
    const uint32_t r0 = ((uint32_t)j & mask) << (RSM_TMAP_TILE_LOG2 - 1);
    const uint32_t r1 = ((uint32_t)(j + 1) & mask) << (RSM_TMAP_TILE_LOG2 - 1);
    const uint32_t x0 = (uint32_t)i & mask;
    const uint32_t x1 = (uint32_t)(i + 1) & mask;
    m[0] = occ_at(map, t00, r0 + (x0 >> 1), (x0 & 1u) << 2);
    m[1] = occ_at(map, t10, r0 + (x1 >> 1), (x1 & 1u) << 2);
    m[2] = occ_at(map, t01, r1 + (x0 >> 1), (x0 & 1u) << 2);
    m[3] = occ_at(map, t11, r1 + (x1 >> 1), (x1 & 1u) << 2);
    return t00;
}

#if RSM_FIXED_MATCH
/* rsm_tmap_straddle with the four cells' values instead of their
 * occupancies, for the fixed-point reads (RSM_FIXED_MATCH); only there, so
 * that the float build's code stays as it was. */
const rsm_tile_t *rsm_tmap_straddle_values(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, int own, const rsm_tile_t *t,
                                           int32_t i, int32_t j, uint32_t v[4])
{
    const rsm_tile_t *t10;
    const rsm_tile_t *t01;
    const rsm_tile_t *t11;
    const rsm_tile_t *t00 = straddle_tiles(map, c, own, t, i, j, &t10, &t01, &t11);
    v[0] = rsm_tmap_get_cell(t00, rsm_tmap_cell_index(i, j));
    v[1] = rsm_tmap_get_cell(t10, rsm_tmap_cell_index(i + 1, j));
    v[2] = rsm_tmap_get_cell(t01, rsm_tmap_cell_index(i, j + 1));
    v[3] = rsm_tmap_get_cell(t11, rsm_tmap_cell_index(i + 1, j + 1));
    return t00;
}
#endif

float rsm_tmap_sample(const rsm_tmap_t *map, uint32_t level, float x, float y, float *dx, float *dy)
{
    rsm_tmap_cursor_t c;
    rsm_tmap_cursor_init(&c, level);
    return rsm_tmap_sample_at(map, &c, x, y, dx, dy);
}

float rsm_tmap_sample_at(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, float x, float y, float *dx, float *dy)
{
    return rsm_tmap_read_sample(map, c, x, y, 0, dx, dy);
}

int rsm_tmap_raise(rsm_tmap_t *map, rsm_tmap_cursor_t *c, int32_t gx, int32_t gy, uint32_t v)
{
    const uint32_t level = c->level;
    uint32_t s;
    uint32_t i;
    uint32_t old;
    rsm_tile_t *t;
    if (level >= (uint32_t)map->cfg.levels || !rsm_tmap_in_range(gx, gy)) {
        return RSM_ERR_RANGE;
    }
    if (v == 0u) {
        return RSM_OK;
    }
    v = v > RSM_TMAP_MAX_VALUE ? RSM_TMAP_MAX_VALUE : v;
    if ((s = slot_for(map, c, level, gx, gy)) == RSM_TMAP_NONE) {
        return RSM_ERR_NOMEM;
    }
    t = &map->tile[s];
    i = rsm_tmap_cell_index(gx, gy);
    old = rsm_tmap_get_cell(t, i);
    v = old > v ? old : v;
    t->stamp = (level << 30) | (t->stamp & CONFIRMED) | (v >= map->cfg.saturation ? CONFIRMED : 0u) | map->stamp;
    set_cell(t, i, v);
    return RSM_OK;
}

/* Takes the tile of (level, tx, ty) back from the store into the pool if
 * the store holds it and the pool does not: 1 when it came back, 0 when
 * there was nothing to take, -1 when no slot was left (it stays stored).
 * *ticked: whether this call already ticked the write counter. */
static int fetch_tile(rsm_tmap_t *map, uint32_t level, int32_t tx, int32_t ty, int *ticked)
{
    rsm_tile_t stored;
    uint32_t s;
    if (rsm_tmap_find_slot(map, level, tx, ty) != RSM_TMAP_NONE || !from_store(map, level, tx, ty, &stored)) {
        return 0;
    }
    if (!*ticked) {
        /* A tick of the write counter: the tiles this scan needs are the
         * newest, and those the last ones needed can go. Without it a
         * frozen map, never written, would keep every tile it took back as
         * "written now" and soon have no slot to reuse. */
        map->stamp = (map->stamp + 1u) & STAMP_MASK;
        map->victims = 0;
        *ticked = 1;
    }
    s = claim_slot(map, level, tx, ty);
    if (s == RSM_TMAP_NONE) {
        /* Every slot is this write's. */
        if (map->store->put(map->store->ctx, &stored) != RSM_OK) {
            map->counters.unstored++;
        }
        return -1;
    }
    put_back(map, s, level, &stored);
    return 1;
}

uint32_t rsm_tmap_take_back(rsm_tmap_t *map, uint32_t level_min, uint32_t most, uint32_t *looked, int *full)
{
    uint32_t got = 0;
    uint32_t level;
    int ticked;
    uint32_t k;
    if (full != NULL) {
        *full = 0;
    }
    if (map->store == NULL || map->cfg.levels < 2u) {
        return 0u;
    }
    /* Those levels' tiles in the pool become the newest, as those taken
     * back will: the slots the walk takes are the finer levels' (else a
     * tile already walked past could be let go to make room). */
    map->stamp = (map->stamp + 1u) & STAMP_MASK;
    map->victims = 0;
    ticked = 1;
    for (k = 0; k < map->used; ++k) {
        rsm_tile_t *t = &map->tile[k];
        if (tile_level(t) >= level_min) {
            t->stamp = (t->stamp & ~STAMP_MASK) | map->stamp;
        }
    }
    *looked += map->used / 16u;
    /* Top down, by place, not by the store's list (a store in flash
     * finds a tile by place at once, but its i-th only by counting): a
     * tile of level + 1 spans four of level, and a return written at one
     * level was written at every coarser one, so each tile the store holds
     * has its parent in the pool once the level above is back. The
     * coarsest level stays whole: a pool with a store never lets it go. */
    for (level = (uint32_t)map->cfg.levels - 1u; level-- > level_min;) {
        for (k = 0; k < map->used; ++k) {
            const rsm_tile_t *p = &map->tile[k];
            uint32_t c;
            if (tile_level(p) != level + 1u) {
                continue;
            }
            for (c = 0; c < 4u; ++c) {
                const int f = fetch_tile(map, level, 2 * (int32_t)p->tx + (int32_t)(c & 1u),
                                         2 * (int32_t)p->ty + (int32_t)(c >> 1), &ticked);
                ++*looked;
                if (f < 0) {
                    if (full != NULL) {
                        *full = 1;
                    }
                    return got; /* every slot holds a tile taken back now */
                }
                got += f > 0 ? 1u : 0u;
                if (got >= most) {
                    return got; /* the rest with the next call */
                }
            }
        }
    }
    return got;
}

/* Cells beyond the margin that a read may touch: its bilinear neighbour,
 * and one more for a match that moves by a cell on the coarsest level. */
#define FETCH_READ_CELLS 2

uint32_t rsm_tmap_fetch(rsm_tmap_t *map, const rsm_pose_t *pose, const rsm_point_t *pts, size_t n, float margin_m)
{
    uint32_t got = 0;
    uint32_t level;
    int ticked = 0;
    float c;
    float sn;
    if (map->store == NULL || map->store->count(map->store->ctx) == 0u || !(margin_m >= 0.0f)) {
        return 0u;
    }
    rsm_sincosf(pose->theta, &sn, &c);
    for (level = 0; level < (uint32_t)map->cfg.levels; ++level) {
        const float inv = map->inv_cell[level];
        /* Cells the margin spans, rounded up; less a hair, so that 5 cm
         * of 5 cm cells is one cell, not two by the product's rounding. */
        const float mc = margin_m * inv - 1.0e-3f;
        const int32_t m = (mc < 4096.0f ? (mc > 0.0f ? (int32_t)ceilf(mc) : 0) : 4096) + FETCH_READ_CELLS;
        /* The tiles a point's cell and the margin around it touch. A
         * scan's points come in beam order, so a point's rectangle of tiles
         * is mostly the one before it, or overlaps it but for a strip: only
         * tiles outside the last rectangle are looked up (on the M4 a
         * margin of a metre looked each tile up about forty times, 0.8
         * million instructions in one scan). */
        int32_t last[4] = {1, 0, 0, 0}; /* tx0 > tx1: none yet */
        size_t k;
        for (k = 0; k < n; ++k) {
            const float x = pose->x + c * pts[k].x - sn * pts[k].y;
            const float y = pose->y + sn * pts[k].x + c * pts[k].y;
            const int32_t gx = rsm_tmap_cell_of(x, inv);
            const int32_t gy = rsm_tmap_cell_of(y, inv);
            int32_t r[4];
            int32_t tx;
            int32_t ty;
            if (!rsm_tmap_in_range(gx - m, gy - m) || !rsm_tmap_in_range(gx + m, gy + m)) {
                continue;
            }
            r[0] = (gx - m) >> RSM_TMAP_TILE_LOG2;
            r[1] = (gy - m) >> RSM_TMAP_TILE_LOG2;
            r[2] = (gx + m) >> RSM_TMAP_TILE_LOG2;
            r[3] = (gy + m) >> RSM_TMAP_TILE_LOG2;
            if (r[0] == last[0] && r[1] == last[1] && r[2] == last[2] && r[3] == last[3]) {
                continue;
            }
            for (ty = r[1]; ty <= r[3]; ++ty) {
                for (tx = r[0]; tx <= r[2]; ++tx) {
                    int f;
                    if (tx >= last[0] && tx <= last[2] && ty >= last[1] && ty <= last[3]) {
                        continue;
                    }
                    f = fetch_tile(map, level, tx, ty, &ticked);
                    if (f < 0) {
                        return got;
                    }
                    got += (uint32_t)f;
                }
            }
            memcpy(last, r, sizeof last);
        }
    }
    return got;
}
