/* Branch and bound over the whole map: src/map/globalsearch.h has the method,
 * docs/globalsearch.md the measurements. */
#include "map/globalsearch.h"

#include <math.h>
#include <string.h>

#include "core/bits.h"
#include "core/fmath.h"
#include "rsm/status.h"
#include "map/tmap_read.h"

/* A pose is kept while it scores within this share of the best: its rivals
 * must be descended too, or a wrong winner could not be told apart. */
#define KEEP_SHARE 0.2f
#define LEAF_SLACK 0.05f
#define MAX_H ((uint32_t)RSM_GLOBAL_MAX_H)
#define MAX_BASE_H ((uint32_t)RSM_GLOBAL_MAX_BASE_H)
/* Grid h's blocks start at least 2^(h - FINEST_BELOW) cells apart. */
#define FINEST_BELOW 2u

/* A crowded search's winner is proven only against a kept rival fitting
 * at least this share of it: a place weighed against nothing alike. */
#define CROWDED_RIVAL 0.5f
/* A search is crowded when it turned away at least this many leaves that
 * reached its bar outside the basins it kept (g->unkept; a place may count
 * more than once): as many as it keeps and weighs. A few turned away
 * beside eight weighed asked the same second search, which on the bench's
 * logs only made the first pose later (docs/globalsearch.md, "Finer grids
 * in lent memory, and a few poses not kept"). */
#define CROWDED_UNKEPT ((uint32_t)RSM_GLOBAL_CANDIDATES)

/* Floor division by 2^h for any sign. */
static int32_t floor_shift(int32_t v, uint32_t h)
{
    return v >= 0 ? (int32_t)((uint32_t)v >> h) : -(int32_t)(((uint32_t)(-(v + 1)) >> h) + 1u);
}

/* The level scored: the second coarsest (0.2 m cells by default). The
 * coarsest (0.4 m) is too full to tell places apart in a building:
 * measured on the Intel log, dozens of wrong poses put every point of a
 * scan on an occupied coarse cell. */
static uint32_t search_level(const rsm_tmap_t *map)
{
    return map->cfg.levels >= 2u ? (uint32_t)map->cfg.levels - 2u : 0u;
}

/* What a point on a cell of value v scores: its occupancy where it is a
 * wall (rsm_tmap_wall_value), else nothing. */
static float cell_score(const rsm_tmap_t *map, uint32_t v, uint32_t wall)
{
    return v >= wall ? map->occ[v] : 0.0f;
}

/* The level whose walls give the map's directions: one finer. */
static uint32_t direction_level(uint32_t level)
{
    return level > 0u ? level - 1u : 0u;
}

/* The grid memory used of grid_bytes: what a bit index holds. */
static uint32_t grid_cap(size_t grid_bytes)
{
    return grid_bytes < (size_t)RSM_GLOBAL_MAX_GRID_BYTES ? (uint32_t)grid_bytes : (uint32_t)RSM_GLOBAL_MAX_GRID_BYTES;
}

/* Blocks a side of grid h over w cells, its blocks 2^e cells apart: the
 * windows [u, u + 2^h] that touch the map start at u = -2^h .. w - 1. */
static uint32_t grid_blocks(uint32_t w, uint32_t h, uint32_t e)
{
    return ((w - 1u + (1u << h)) >> e) + 1u;
}

/* The bits of grids 1 .. top; more than any cap when a grid is wider than
 * its block count's type holds. */
static uint32_t grid_bits(uint32_t w, uint32_t hgt, uint32_t top, const uint8_t *e)
{
    uint32_t bits = 0;
    uint32_t h;
    for (h = 1; h <= top; ++h) {
        const uint32_t nx = grid_blocks(w, h, e[h]);
        const uint32_t ny = grid_blocks(hgt, h, e[h]);
        if (nx > 0xFFFFu || ny > 0xFFFFu) {
            return UINT32_MAX;
        }
        bits += nx * ny;
    }
    return bits;
}

/* The grids for a map of w x hgt cells on the search level: the boxes'
 * sizes up to the whole map (*top; up to `fixed` instead, for a window,
 * when not 0), and for each box size h the spacing
 * 2^e[h] of its grid's blocks, each of which bounds the windows of 2^h + 1
 * cells that start in it: 2^e[h] - 1 cells wider than a window, so the
 * finer the spacing, the tighter the bound and the more bits. The coarsest
 * that fits (blocks 2^(h + 1 + r) apart) is made finer a box size at a
 * time, the smallest boxes first: they are the most numerous (measured on
 * the Intel log, exact windows at 0.4 and 0.8 m read 2.5 times fewer
 * blocks than windows twice as wide), in grid_bytes. RSM_ERR_NOMEM when
 * even the coarsest does not fit. */
static int layout(uint32_t w, uint32_t hgt, uint32_t fixed, uint32_t grid_bytes, uint32_t *top, uint8_t *e)
{
    const uint32_t cap = grid_bytes * 8u;
    const uint32_t side = w > hgt ? w : hgt;
    uint32_t r;
    uint32_t h;
    *top = fixed > 1u ? fixed : 1u;
    while (fixed == 0u && *top <= MAX_H && (1u << *top) < side) {
        ++*top;
    }
    if (*top > MAX_H) {
        return RSM_ERR_NOMEM;
    }
    for (r = 0;; ++r) {
        if (2u + r > MAX_BASE_H) {
            return RSM_ERR_NOMEM;
        }
        for (h = 1; h <= *top; ++h) {
            e[h] = (uint8_t)(h + 1u + r);
        }
        if (grid_bits(w, hgt, *top, e) <= cap) {
            break;
        }
    }
    for (h = 1; h <= *top; ++h) {
        /* Blocks a quarter of the box apart at the finest: beyond that the
         * bound hardly tightens (windows of 1.8 m and more hold walls
         * anyway), and every bit costs its build (and, in grids kept
         * through writes, each hit a write sets in them: docs/globalsearch.md,
         * "Finer grids in lent memory, and a few poses not kept"). */
        while (e[h] > 0u && e[h] + FINEST_BELOW > h) {
            e[h]--;
            if (grid_bits(w, hgt, *top, e) > cap) {
                e[h]++;
                break;
            }
        }
    }
    return RSM_OK;
}

/* Doublings of a window of radius_m before it is as wide as map's box on
 * the search level (none for radius_m 0: the whole map). */
static uint32_t widenings(const rsm_tmap_t *map, float radius_m)
{
    int32_t b[4];
    uint32_t widen = 0;
    if (radius_m > 0.0f && rsm_tmap_bounds(map, search_level(map), &b[0], &b[1], &b[2], &b[3])) {
        const int32_t side = b[2] - b[0] > b[3] - b[1] ? b[2] - b[0] + 1 : b[3] - b[1] + 1;
        float width = 2.0f * radius_m / rsm_tmap_cell(map, search_level(map));
        while (widen < 16u && width < (float)side) {
            width *= 2.0f;
            widen++;
        }
    }
    return widen;
}

float rsm_global_radius(float radius_m, uint32_t unproven)
{
    const uint32_t d = unproven / 2u;
    return radius_m * (float)(1u << (d < 16u ? d : 16u));
}

float rsm_global_share(const rsm_tmap_t *map, float radius_m, uint32_t unproven, float min_share)
{
    const uint32_t widen = widenings(map, radius_m);
    /* Each window smaller than the whole map is searched at the first two
     * bars before it doubles: one that holds the robot finds it at the
     * second where a person hides a point (a look-alike further out could
     * pass the first bar alone), and one that does not costs little, where
     * a lower bar over a wide window reads ten times as much as the first
     * (a robot carried away). The whole map is searched at the first bar
     * RSM_GLOBAL_FIRST_SEARCHES times, then at each lower one
     * RSM_GLOBAL_BAR_SEARCHES times (rsm/config.h says why); after the
     * windows, the whole map at the first bar once. */
    const uint32_t whole = unproven < 2u * widen ? unproven % 2u : unproven - 2u * widen;
    const uint32_t first = widen > 0u ? 1u : (uint32_t)RSM_GLOBAL_FIRST_SEARCHES;
    const uint32_t lowered = whole < first ? 0u : 1u + (whole - first) / (uint32_t)RSM_GLOBAL_BAR_SEARCHES;
    /* Measured on the Intel and ACES logs (docs/globalsearch.md): a first
     * search at 0.97, where a box whose window misses a single point is
     * dropped, read about half of what one at 0.95 (a miss allowed) did,
     * and still kept the true pose at most starts. */
    const float share = lowered == 0u ? 0.97f : 1.0f - 0.05f * (float)(lowered < 20u ? lowered : 20u);
    return share > min_share ? share : min_share;
}

int rsm_global_crowded(const rsm_global_t *g)
{
    return g->unkept >= CROWDED_UNKEPT;
}

float rsm_global_fit_share(const rsm_global_t *g, float min_fit, float crowded_fit)
{
    return rsm_global_crowded(g) && crowded_fit > min_fit ? crowded_fit : min_fit;
}

int rsm_global_check(const rsm_tmap_t *map, size_t grid_bytes)
{
    int32_t b[4];
    uint8_t e[RSM_GLOBAL_MAX_H + 1];
    uint32_t top;
    if (!rsm_tmap_bounds(map, search_level(map), &b[0], &b[1], &b[2], &b[3])) {
        return RSM_ERR_DEGENERATE;
    }
    return layout((uint32_t)(b[2] - b[0] + 1), (uint32_t)(b[3] - b[1] + 1), 0u, grid_cap(grid_bytes), &top, e);
}

/* One bit of a grid (rsm_bit_get's, unsigned for the counts below). */
static uint32_t get_bit(const uint8_t *grid, uint32_t i)
{
    return (uint32_t)rsm_bit_get(grid, i);
}

/* Whether grid h holds a wall cell (rsm_tmap_wall_value) in the window [u, u + 2^h]
 * x [v, v + 2^h] (cells of the search level): 1 when it may, 0 when it
 * holds none. */
static uint32_t grid_read(const rsm_global_t *g, const uint8_t *grid, uint32_t h, int32_t u, int32_t v)
{
    const int32_t x = u - g->ox + (int32_t)(1u << h);
    const int32_t y = v - g->oy + (int32_t)(1u << h);
    uint32_t a;
    uint32_t b;
    if (x < 0 || y < 0) {
        return 0u;
    }
    a = (uint32_t)x >> g->grid_e[h];
    b = (uint32_t)y >> g->grid_e[h];
    if (a >= g->grid_nx[h] || b >= g->grid_ny[h]) {
        return 0u;
    }
    return get_bit(grid, g->grid_at[h] + b * g->grid_nx[h] + a);
}

/* Sets the blocks of grid h whose windows hold a cell of the search level
 * in [x0, x1] x [y0, y1] (counted from the grids' first cell): block a
 * holds the cells a 2^e - 2^h .. a 2^e + 2^e - 1. */
static void mark_grid(const rsm_global_t *g, uint8_t *grid, uint32_t h, uint32_t x0, uint32_t y0, uint32_t x1,
                      uint32_t y1)
{
    const uint32_t e = g->grid_e[h];
    const uint32_t nx = g->grid_nx[h];
    const uint32_t a1 = ((x1 + (1u << h)) >> e) < nx ? (x1 + (1u << h)) >> e : nx - 1u;
    const uint32_t b1 = ((y1 + (1u << h)) >> e) < g->grid_ny[h] ? (y1 + (1u << h)) >> e : g->grid_ny[h] - 1u;
    uint32_t b;
    for (b = y0 >> e; b <= b1; ++b) {
        uint32_t a;
        for (a = x0 >> e; a <= a1; ++a) {
            rsm_bit_set(grid, g->grid_at[h] + b * nx + a);
        }
    }
}

/* A tile of the search level into the finest grid: each wall cell
 * (rsm_tmap_wall_value) of the grids' box (g->cache_box) sets the blocks whose
 * windows hold it. Returns the cells looked at. */
static uint32_t grid_tile(const rsm_global_t *g, uint8_t *grid, const rsm_tile_t *t, uint32_t wall)
{
    uint32_t c;
    for (c = 0; c < (uint32_t)RSM_TMAP_TILE_CELLS; c += 2u) {
        uint32_t k;
        if (t->cell[c >> 1] == 0u) {
            continue;
        }
        for (k = c; k < c + 2u; ++k) {
            const int32_t cx = (int32_t)t->tx * RSM_TMAP_TILE_SIDE + (int32_t)(k & (RSM_TMAP_TILE_SIDE - 1u));
            const int32_t cy = (int32_t)t->ty * RSM_TMAP_TILE_SIDE + (int32_t)(k >> RSM_TMAP_TILE_LOG2);
            if (((((uint32_t)t->cell[k >> 1]) >> ((k & 1u) << 2)) & 15u) >= wall && cx >= g->cache_box[0] &&
                cx <= g->cache_box[2] && cy >= g->cache_box[1] && cy <= g->cache_box[3]) {
                const uint32_t x = (uint32_t)(cx - g->ox);
                const uint32_t y = (uint32_t)(cy - g->oy);
                mark_grid(g, grid, 1u, x, y, x, y);
            }
        }
    }
    return (uint32_t)RSM_TMAP_TILE_CELLS;
}

/* Block i of the grids (counted over all of them, from grid 2's first) from
 * the grid below: the union of the finer blocks that cover its cells.
 * Returns the blocks read. */
static uint32_t grid_up(const rsm_global_t *g, uint8_t *grid, uint32_t i)
{
    uint32_t h = 2;
    uint32_t e;
    uint32_t f;
    int32_t half;
    uint32_t a;
    uint32_t b;
    int32_t c0;
    int32_t c1;
    int32_t d0;
    int32_t d1;
    int32_t c;
    int32_t step;
    uint32_t reads = 0;
    while (h < g->top_h && i >= g->grid_at[h + 1u]) {
        ++h;
    }
    e = g->grid_e[h];
    f = g->grid_e[h - 1u];
    half = (int32_t)(1u << (h - 1u));
    b = (i - g->grid_at[h]) / g->grid_nx[h];
    a = (i - g->grid_at[h]) - b * g->grid_nx[h];
    /* Block a holds the cells a 2^e - 2^h .. a 2^e + 2^e - 1 from the map's
     * first; finer block d those d 2^f - 2^(h-1) .. d 2^f + 2^f - 1. */
    c0 = floor_shift((int32_t)(b << e) - half, f);
    c1 = (int32_t)(((b << e) + (1u << e) - 1u) >> f);
    d0 = floor_shift((int32_t)(a << e) - half, f);
    d1 = (int32_t)(((a << e) + (1u << e) - 1u) >> f);
    c0 = c0 > 0 ? c0 : 0;
    d0 = d0 > 0 ? d0 : 0;
    c1 = c1 < (int32_t)g->grid_ny[h - 1u] - 1 ? c1 : (int32_t)g->grid_ny[h - 1u] - 1;
    d1 = d1 < (int32_t)g->grid_nx[h - 1u] - 1 ? d1 : (int32_t)g->grid_nx[h - 1u] - 1;
    /* Finer blocks overlap: every step-th of them still covers the span
     * (the last one always read). */
    step = (int32_t)(((uint32_t)half >> f) + 1u);
    for (c = c0; c <= c1; c = (c < c1 && c + step > c1) ? c1 : c + step) {
        int32_t d;
        for (d = d0; d <= d1; d = (d < d1 && d + step > d1) ? d1 : d + step) {
            reads++;
            if (get_bit(grid, g->grid_at[h - 1u] + (uint32_t)c * g->grid_nx[h - 1u] + (uint32_t)d) != 0u) {
                rsm_bit_set(grid, i);
                return reads;
            }
            if (d == d1) {
                break;
            }
        }
        if (c == c1) {
            break;
        }
    }
    return reads;
}

/* Lays the grids out over the map's box on the search level and clears
 * them; they are filled by rsm_global_run, a tile at a time. */
static int begin_grids(rsm_global_t *g, uint8_t *grid, int32_t gx0, int32_t gy0, int32_t gx1, int32_t gy1,
                       uint32_t fixed)
{
    const uint32_t w = (uint32_t)(gx1 - gx0 + 1);
    const uint32_t hgt = (uint32_t)(gy1 - gy0 + 1);
    uint8_t e[RSM_GLOBAL_MAX_H + 1];
    uint32_t at = 0;
    uint32_t h;
    int rc;
    if ((rc = layout(w, hgt, fixed, g->grid_bytes, &g->top_h, e)) != RSM_OK) {
        return rc;
    }
    memset(g->grid_at, 0, sizeof g->grid_at);
    memset(g->grid_nx, 0, sizeof g->grid_nx);
    memset(g->grid_ny, 0, sizeof g->grid_ny);
    memset(g->grid_e, 0, sizeof g->grid_e);
    for (h = 1; h <= g->top_h; ++h) {
        g->grid_e[h] = e[h];
        g->grid_nx[h] = (uint16_t)grid_blocks(w, h, e[h]);
        g->grid_ny[h] = (uint16_t)grid_blocks(hgt, h, e[h]);
        g->grid_at[h] = at;
        at += g->grid_nx[h] * g->grid_ny[h];
    }
    g->build_end = at;
    memset(grid, 0, (at + 7u) >> 3);
    g->ox = gx0;
    g->oy = gy0;
    g->root_i = gx0;
    g->root_j = gy0;
    g->root_h = g->top_h;
    g->build_next = g->top_h >= 2u ? g->grid_at[2] : at;
    return RSM_OK;
}

/* Wall directions, half a turn in RSM_GLOBAL_BINS bins, of the line from
 * a to b, weighted by its length. */
static void add_direction(float *hist, float dx, float dy, float w)
{
    float a = rsm_atan2f(dy, dx);
    int32_t b;
    if (a < 0.0f) {
        a += RSM_PI;
    }
    b = (int32_t)(a * ((float)RSM_GLOBAL_BINS / RSM_PI));
    if (b >= RSM_GLOBAL_BINS) {
        b -= RSM_GLOBAL_BINS;
    }
    if (b >= 0) {
        hist[b] += w;
    }
}

/* The scan's wall directions: chords between readings four apart that lie
 * 0.1 to 0.6 m apart (shorter ones are noise, longer ones span gaps). */
static void scan_directions(rsm_global_t *g, const rsm_point_t *pts, size_t n)
{
    size_t k;
    memset(g->dir_scan, 0, sizeof g->dir_scan);
    for (k = 0; k + 4u < n; ++k) {
        const float dx = pts[k + 4u].x - pts[k].x;
        const float dy = pts[k + 4u].y - pts[k].y;
        const float d2 = dx * dx + dy * dy;
        if (d2 >= 0.01f && d2 <= 0.36f) {
            add_direction(g->dir_scan, dx, dy, sqrtf(d2));
        }
    }
}

/* The grids and the map's directions over the whole map's box, cleared,
 * to be built from its first tile (build). */
static int begin_build(rsm_global_t *g, uint8_t *grid, int32_t gx0, int32_t gy0, int32_t gx1, int32_t gy1)
{
    int rc;
    g->cached = 0u;
    if ((rc = begin_grids(g, grid, gx0, gy0, gx1, gy1, 0u)) != RSM_OK) {
        return rc;
    }
    memset(g->dir_map, 0, sizeof g->dir_map);
    g->dir_next = 0;
    g->cache_box[0] = gx0;
    g->cache_box[1] = gy0;
    g->cache_box[2] = gx1;
    g->cache_box[3] = gy1;
    return RSM_OK;
}

uint32_t rsm_global_take_back(rsm_tmap_t *map, uint32_t budget, int *more)
{
    /* Tiles taken back at 40 each fill at most a quarter of the budget:
     * the places looked up take about as much on ACES. */
    const uint32_t most = budget == 0u ? UINT32_MAX : (budget / 160u > 0u ? budget / 160u : 1u);
    uint32_t looked = 0;
    int full = 0;
    const uint32_t got = rsm_tmap_take_back(map, direction_level(search_level(map)), most, &looked, &full);
    *more = full ? -1 : got >= most ? 1 : 0;
    return 10u * looked + 40u * got;
}

/* The tiles of the level searched, as a sum over them of a hash of their
 * place: with their count and the write counter, whether the grids built
 * from them still stand.
 * A frozen map's tiles come and go with a store (rsm_tmap_fetch) the same
 * as they were; only when the level's tiles are others must the grids be
 * built again (before, any tile taken back anywhere rebuilt them: a robot
 * lost after tracking on a map with a store paid the whole build again). */
static uint32_t read_signature(const rsm_tmap_t *map, uint32_t level)
{
    uint32_t sig = 0;
    uint32_t k;
    for (k = 0; k < map->used; ++k) {
        const rsm_tile_t *t = &map->tile[k];
        if ((t->stamp >> 30) == level) {
            sig += rsm_tmap_place_sig(level, t->tx, t->ty);
        }
    }
    return sig;
}

int rsm_global_can_keep(const rsm_global_t *g, const rsm_tmap_t *map)
{
    return g->cached != 0u && g->level == search_level(map) && g->cache_writes == map->counters.updates;
}

/* Whether the grids and directions built last stand for map as it is now,
 * over the box (gx0, gy0) .. (gx1, gy1) of its search level: no write
 * since but those kept (rsm_global_keep), and the tiles of the level
 * searched those they were built from, with those the kept writes began
 * and less those that ended (a grid block stays set for a tile gone: a
 * bound only looser). The level searched alone: the finer one the map's
 * directions come from may lose a tile to the store that the take-back
 * cannot reach (its parent worn away: measured on Intel's kidnaps with
 * updates, one such tile made a search build everything again, about
 * 700 000 of its units, 15 scans), and the directions only choose the
 * headings searched: they stay as built through the writes the grids are
 * kept through as well. */
static int stands(const rsm_global_t *g, const rsm_tmap_t *map, int32_t gx0, int32_t gy0, int32_t gx1, int32_t gy1)
{
    return rsm_global_can_keep(g, map) && g->cache_box[0] == gx0 && g->cache_box[1] == gy0 &&
           g->cache_box[2] == gx1 && g->cache_box[3] == gy1 &&
           (uint32_t)map->level_used[g->level] == g->cache_tiles + (map->churn[g->level] - g->cache_churn) &&
           read_signature(map, g->level) == g->cache_sig + (map->churn_sig[g->level] - g->cache_churn_sig);
}

void rsm_global_keep(rsm_global_t *g, uint8_t *grid, const rsm_tmap_t *map, const rsm_point_t *pts, size_t n)
{
    const float inv = 1.0f / rsm_tmap_cell(map, g->level);
    int32_t last_i = INT32_MIN;
    int32_t last_j = INT32_MIN;
    size_t k;
    for (k = 0; k < n; ++k) {
        /* The cells a hit may raise: the two either side of the point in
         * x and in y (a hit's bilinear shares, rsm_bilinear_at), which
         * hold the one cell it lands in when not shared. Marked whether or
         * not they reach rsm_tmap_wall_value: a bound may only be too high. */
        const float u = rsm_floorf(pts[k].x * inv - 0.5f);
        const float v = rsm_floorf(pts[k].y * inv - 0.5f);
        int32_t i;
        int32_t j;
        if (!(u > (float)g->cache_box[0] - 2.0f && u <= (float)g->cache_box[2] && v > (float)g->cache_box[1] - 2.0f &&
              v <= (float)g->cache_box[3])) {
            /* Beyond the grids' box (or NaN): a hit there widens the map's
             * bounds, and the next search builds the grids again. */
            continue;
        }
        i = (int32_t)u;
        j = (int32_t)v;
        if (i == last_i && j == last_j) {
            continue; /* the scan's next reading, most often in the same cells */
        }
        last_i = i;
        last_j = j;
        {
            const int32_t x0 = i > g->cache_box[0] ? i : g->cache_box[0];
            const int32_t y0 = j > g->cache_box[1] ? j : g->cache_box[1];
            const int32_t x1 = i + 1 < g->cache_box[2] ? i + 1 : g->cache_box[2];
            const int32_t y1 = j + 1 < g->cache_box[3] ? j + 1 : g->cache_box[3];
            uint32_t h;
            for (h = 1; h <= g->top_h; ++h) {
                mark_grid(g, grid, h, (uint32_t)(x0 - g->ox), (uint32_t)(y0 - g->oy), (uint32_t)(x1 - g->ox),
                          (uint32_t)(y1 - g->oy));
            }
        }
    }
    g->cache_writes = map->counters.updates;
}

int rsm_global_begin(rsm_global_t *g, uint8_t *grid, size_t grid_bytes, const rsm_tmap_t *map,
                     const rsm_point_t *pts, size_t n, const rsm_pose_t *at, float min_share)
{
    const uint32_t level = search_level(map);
    const float cell = rsm_tmap_cell(map, level);
    float range[RSM_GLOBAL_POINTS];
    int32_t gx0;
    int32_t gy0;
    int32_t gx1;
    int32_t gy1;
    float reach;
    uint32_t stride;
    uint32_t k;
    int rc;
    if (n < 8u) {
        return RSM_ERR_DEGENERATE;
    }
    if ((rc = rsm_global_check(map, grid_bytes)) != RSM_OK) {
        return rc;
    }
    if (grid_cap(grid_bytes) != g->grid_bytes) {
        /* Other memory: grids laid out for it. */
        g->cached = 0u;
        g->grid_bytes = grid_cap(grid_bytes);
    }
    (void)rsm_tmap_bounds(map, level, &gx0, &gy0, &gx1, &gy1);
    g->level = level;
    g->npts = n < (size_t)RSM_GLOBAL_POINTS ? (uint32_t)n : (uint32_t)RSM_GLOBAL_POINTS;
    /* Taken evenly over the scan, stored in an order that jumps across it
     * (a stride coprime with their count), so that a pose's first points
     * already sample the whole scan and a poor pose is given up early. */
    stride = (g->npts * 5u) / 8u;
    while (stride > 1u) {
        uint32_t a = g->npts;
        uint32_t b = stride;
        while (b != 0u) {
            const uint32_t t = a % b;
            a = b;
            b = t;
        }
        if (a == 1u) {
            break;
        }
        --stride;
    }
    if (stride == 0u) {
        stride = 1u;
    }
    for (k = 0; k < g->npts; ++k) {
        const uint32_t pick = (k * stride) % g->npts;
        rsm_point_t p = pts[(size_t)pick * n / g->npts];
        uint32_t m = k;
        /* A reading far beyond any map (max_range_m is the caller's) is
         * pulled in to the map's reach: it lands on nothing either way,
         * and its cell offset stays a small integer. */
        const float far = (float)(RSM_TMAP_TILE_LIMIT * RSM_TMAP_TILE_SIDE) * rsm_tmap_cell(map, 0u);
        const float r = sqrtf(p.x * p.x + p.y * p.y);
        if (!(r <= far)) {
            const float shrink = r > 0.0f ? far / r : 0.0f;
            p.x *= shrink;
            p.y *= shrink;
        }
        g->pts[k] = p;
        range[k] = sqrtf(p.x * p.x + p.y * p.y);
        /* Insertion sort of the ranges, for their upper decile. */
        while (m > 0u && range[m - 1u] > range[m]) {
            const float t = range[m - 1u];
            range[m - 1u] = range[m];
            range[m] = t;
            --m;
        }
    }
    /* For the proof, as many again: the readings halfway between those
     * (when the scan has them). */
    g->nseen = g->npts;
    if (n >= 2u * (size_t)g->npts) {
        for (k = 0; k < g->npts; ++k) {
            g->pts[g->npts + k] = pts[(2u * (size_t)k + 1u) * n / (2u * (size_t)g->npts)];
        }
        g->nseen = 2u * g->npts;
    }
    g->seen_at = *at;
    /* Headings so spaced that the scan's far points (its upper decile)
     * move RSM_GLOBAL_HEADING_CELLS cells from one heading to the next
     * (rsm/config.h says why the presets differ). */
    reach = range[(g->npts * 9u) / 10u];
    if (reach < cell) {
        reach = cell;
    }
    {
        /* Capped as a float, before it becomes a count. */
        float h = ceilf(2.0f * RSM_PI * reach / ((float)RSM_GLOBAL_HEADING_CELLS * cell));
        h = h < (float)RSM_GLOBAL_MAX_HEADINGS ? h : (float)RSM_GLOBAL_MAX_HEADINGS;
        g->headings = h > 8.0f ? (uint32_t)h : 8u;
        /* Even: a pose and the one turned half round are both searched
         * (a place that looks alike from there must be seen as a rival). */
        g->headings += g->headings & 1u;
    }
    g->step_rad = 2.0f * RSM_PI / (float)g->headings;
    if (stands(g, map, gx0, gy0, gx1, gy1)) {
        /* The map as the last search built its grids and directions from:
         * they stand (only the agreement with this scan is new). */
        g->dir_next = map->used;
        g->build_next = g->build_end;
        g->root_i = g->ox;
        g->root_j = g->oy;
        g->root_h = g->top_h;
    } else if ((rc = begin_build(g, grid, gx0, gy0, gx1, gy1)) != RSM_OK) {
        return rc;
    }
    scan_directions(g, pts, n);
    g->heading = 0;
    g->pass = 0;
    g->depth = 0;
    g->found = 0;
    g->unkept = 0;
    g->best_score = 0.0f;
    g->floor_score = min_share * (float)g->npts;
    g->work = 0;
    return RSM_OK;
}

/* The map's wall directions from one tile of the direction level: the
 * gradient of its cell values (a 3 x 3 Sobel inside the tile) is normal to
 * its walls. The tile's rows are unpacked once, three at a time. Returns
 * the cells looked at. */
static uint32_t tile_directions(rsm_global_t *g, const rsm_tile_t *t)
{
    const uint32_t side = (uint32_t)RSM_TMAP_TILE_SIDE;
    uint8_t row[3][RSM_TMAP_TILE_SIDE];
    uint32_t y;
    for (y = 0; y < side; ++y) {
        uint32_t x;
        for (x = 0; x < side; ++x) {
            const uint32_t c = y * side + x;
            row[y % 3u][x] = (uint8_t)(((uint32_t)t->cell[c >> 1] >> ((c & 1u) << 2)) & 15u);
        }
        if (y < 2u) {
            continue;
        }
        {
            /* Rows y - 2, y - 1, y: the cells of row y - 1 have all their
             * neighbours. */
            const uint8_t *lo = row[(y - 2u) % 3u];
            const uint8_t *mid = row[(y - 1u) % 3u];
            const uint8_t *hi = row[y % 3u];
            for (x = 1; x + 1u < side; ++x) {
                const int32_t gx = ((int32_t)lo[x + 1u] + 2 * (int32_t)mid[x + 1u] + (int32_t)hi[x + 1u]) -
                                   ((int32_t)lo[x - 1u] + 2 * (int32_t)mid[x - 1u] + (int32_t)hi[x - 1u]);
                const int32_t gy = ((int32_t)hi[x - 1u] + 2 * (int32_t)hi[x] + (int32_t)hi[x + 1u]) -
                                   ((int32_t)lo[x - 1u] + 2 * (int32_t)lo[x] + (int32_t)lo[x + 1u]);
                if (gx != 0 || gy != 0) {
                    const float fx = (float)gx;
                    const float fy = (float)gy;
                    /* The wall runs across its normal (gx, gy). */
                    add_direction(g->dir_map, -fy, fx, sqrtf(fx * fx + fy * fy));
                }
            }
        }
    }
    /* Two reads' worth a cell: the gradient's direction costs about as much
     * as its cells (measured on the M4). */
    return 2u * (side - 2u) * (side - 2u);
}

/* How well the scan's wall directions, turned by each heading, fall on the
 * map's: the correlation of the two histograms, as a share of its best,
 * and the best within a bin either side (the bins are 4 degrees). A room
 * with no dominant direction agrees equally at every heading. */
static void direction_agreement(rsm_global_t *g)
{
    float corr[RSM_GLOBAL_BINS];
    float best = 0.0f;
    uint32_t s;
    for (s = 0; s < (uint32_t)RSM_GLOBAL_BINS; ++s) {
        float c = 0.0f;
        uint32_t b;
        for (b = 0; b < (uint32_t)RSM_GLOBAL_BINS; ++b) {
            c += g->dir_scan[b] * g->dir_map[(b + s) % (uint32_t)RSM_GLOBAL_BINS];
        }
        corr[s] = c;
        if (c > best) {
            best = c;
        }
    }
    for (s = 0; s < (uint32_t)RSM_GLOBAL_BINS; ++s) {
        const uint32_t l = (s + (uint32_t)RSM_GLOBAL_BINS - 1u) % (uint32_t)RSM_GLOBAL_BINS;
        const uint32_t r = (s + 1u) % (uint32_t)RSM_GLOBAL_BINS;
        float m = corr[s] > corr[l] ? corr[s] : corr[l];
        m = corr[r] > m ? corr[r] : m;
        g->agree[s] = best > 0.0f ? m / best : 1.0f;
    }
}

/* The passes over the headings: the best agreeing first, so that the
 * right pose is likely found early and raises the bar for the rest; below
 * the last, a heading is not searched. */
static const float pass_floor[] = {0.85f, 0.65f, 0.5f};
#define PASSES (sizeof pass_floor / sizeof pass_floor[0])

static int in_pass(const rsm_global_t *g, uint32_t a)
{
    float th = (float)a * g->step_rad;
    int32_t bin;
    float v;
    while (th >= RSM_PI) {
        th -= RSM_PI;
    }
    bin = (int32_t)(th * ((float)RSM_GLOBAL_BINS / RSM_PI) + 0.5f) % RSM_GLOBAL_BINS;
    v = g->agree[bin];
    return v >= pass_floor[g->pass] && (g->pass == 0u || v < pass_floor[g->pass - 1u]);
}

/* The points of heading a, as coarse-cell offsets from the pose's cell. */
static void offsets(const rsm_global_t *g, float cell, uint32_t a, int32_t *fx, int32_t *fy)
{
    const float inv = 1.0f / cell;
    float c;
    float s;
    uint32_t k;
    rsm_sincosf((float)a * g->step_rad, &s, &c);
    for (k = 0; k < g->npts; ++k) {
        const rsm_point_t *p = &g->pts[k];
        fx[k] = (int32_t)floorf((c * p->x - s * p->y) * inv);
        fy[k] = (int32_t)floorf((s * p->x + c * p->y) * inv);
    }
}

/* The cells of the search level in the window [u, u + 2] x [v, v + 2],
 * row by row into c[9]: one tile lookup when they share a tile. */
static void window9(const rsm_tmap_t *map, rsm_tmap_cursor_t *cur, uint32_t level, int32_t u, int32_t v,
                    uint32_t *c)
{
    const int32_t lim = RSM_TMAP_CELL_LIMIT - 3;
    const int32_t tx = u >> RSM_TMAP_TILE_LOG2;
    const int32_t ty = v >> RSM_TMAP_TILE_LOG2;
    const rsm_tile_t *tile[4];
    uint32_t col[3];
    uint32_t x;
    uint32_t y;
    if (!(u > -lim && u < lim && v > -lim && v < lim)) {
        for (y = 0; y < 3u; ++y) {
            for (x = 0; x < 3u; ++x) {
                c[3u * y + x] = rsm_tmap_value(map, level, u + (int32_t)x, v + (int32_t)y);
            }
        }
        return;
    }
    if ((u & RSM_TMAP_TILE_MASK) < RSM_TMAP_TILE_MASK - 1 && (v & RSM_TMAP_TILE_MASK) < RSM_TMAP_TILE_MASK - 1) {
        /* Within one tile (most windows: all but the last two places a
         * side of a tile): one lookup, the rows read straight. */
        const uint32_t sl = rsm_tmap_cursor_slot(map, cur, u, v);
        if (sl == RSM_TMAP_NONE) {
            for (x = 0; x < 9u; ++x) {
                c[x] = 0u;
            }
        } else {
            const rsm_tile_t *t = &map->tile[sl];
            const uint32_t k = rsm_tmap_cell_index(u, v);
            for (y = 0; y < 3u; ++y) {
                const uint32_t r = k + y * (uint32_t)RSM_TMAP_TILE_SIDE;
                c[3u * y] = rsm_tmap_get_cell(t, r);
                c[3u * y + 1u] = rsm_tmap_get_cell(t, r + 1u);
                c[3u * y + 2u] = rsm_tmap_get_cell(t, r + 2u);
            }
        }
        return;
    }
    /* The window spans two or four tiles at a tile's edge: each through
     * the cursor (the points of a box fall on the same few tiles, box
     * after box), NULL where none is held. */
    for (y = 0; y < 2u; ++y) {
        for (x = 0; x < 2u; ++x) {
            const uint32_t sl = rsm_tmap_cursor_slot(map, cur, u + 2 * (int32_t)x, v + 2 * (int32_t)y);
            tile[2u * y + x] = sl == RSM_TMAP_NONE ? NULL : &map->tile[sl];
        }
    }
    for (x = 0; x < 3u; ++x) {
        col[x] = (uint32_t)(((u + (int32_t)x) >> RSM_TMAP_TILE_LOG2) - tx);
    }
    for (y = 0; y < 3u; ++y) {
        const int32_t wy = v + (int32_t)y;
        const uint32_t row = 2u * (uint32_t)((wy >> RSM_TMAP_TILE_LOG2) - ty);
        for (x = 0; x < 3u; ++x) {
            const rsm_tile_t *t = tile[row + col[x]];
            c[3u * y + x] = t == NULL ? 0u : rsm_tmap_get_cell(t, rsm_tmap_cell_index(u + (int32_t)x, wy));
        }
    }
}

static uint32_t max4(uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    const uint32_t x = a > b ? a : b;
    const uint32_t y = c > d ? c : d;
    return x > y ? x : y;
}

/* The points a box of 2^h positions a side reads (the first of g->pts):
 * all for leaves and the smallest boxes, fewer for large ones, where most
 * boxes pass anyway and a point not read counts as on a wall. */
static uint32_t points_read(const rsm_global_t *g, uint32_t h)
{
    const uint32_t n = h >= 3u ? g->npts / 4u : h == 2u ? g->npts / 2u : g->npts;
    return n > 0u ? n : 1u;
}

/* The point at place q of the order, which ended a box's bound, moves up
 * one place: points that fall off the map's walls where others do not are
 * read first, and poor boxes are given up after fewer reads. */
static void promote(rsm_global_t *g, int32_t *fx, int32_t *fy, uint32_t q)
{
    if (q > 0u) {
        const rsm_point_t p = g->pts[q];
        int32_t t = fx[q];
        g->pts[q] = g->pts[q - 1u];
        g->pts[q - 1u] = p;
        fx[q] = fx[q - 1u];
        fx[q - 1u] = t;
        t = fy[q];
        fy[q] = fy[q - 1u];
        fy[q - 1u] = t;
    }
}

/* The most a pose of box (i, j, h) scores at this heading: each point's
 * score (cell_score) of the largest cell value in the window of 2^h + 1
 * cells a side it can reach (for leaves, h = 0, the score itself, from the
 * map; for larger boxes 1 where the grid of h holds a wall cell over the
 * window, else 0; points not read count 1). Stops as soon as the points left could not
 * lift the sum to thr (each adds 1 at most): what it returns is then below
 * thr, which is all the caller asks. Adds the work (a grid block read,
 * or a leaf's point: RSM_GLOBAL_LEAF_WORK) to *work. */
static float box_bound(rsm_global_t *g, const uint8_t *grid, const rsm_tmap_t *map, int32_t *fx, int32_t *fy,
                       int32_t i, int32_t j, uint32_t h, float thr, uint32_t *work)
{
    uint32_t q;
    if (h == 0u) {
        const uint32_t wall = rsm_tmap_wall_value(map);
        float sum = 0.0f;
        for (q = 0; q < g->npts; ++q) {
            const uint32_t k = q;
            const int32_t u = fx[k] + i;
            const int32_t v = fy[k] + j;
            /* Grid 1 bounds a wider window: nothing there, nothing here. */
            if (grid_read(g, grid, 1u, u, v) != 0u) {
                sum += cell_score(map, rsm_tmap_window_max(map, g->level, u, v), wall);
            }
            if (sum + (float)(g->npts - q - 1u) < thr) {
                *work += RSM_GLOBAL_LEAF_WORK * (q + 1u);
                promote(g, fx, fy, q);
                return sum;
            }
        }
        *work += RSM_GLOBAL_LEAF_WORK * g->npts;
        return sum;
    } else {
        /* Grid h's block of a window [u, u + 2^h] is (u - ox + 2^h) >>
         * e: one read a point; a window left of the map wraps to a huge
         * block index, which is past the grid like one right of it (the
         * grids are far narrower than 2^(32 - e) blocks). */
        const uint32_t n = points_read(g, h);
        const uint32_t e = g->grid_e[h];
        const uint32_t nx = g->grid_nx[h];
        const uint32_t ny = g->grid_ny[h];
        const uint32_t at = g->grid_at[h];
        const int32_t x0 = i - g->ox + (int32_t)(1u << h);
        const int32_t y0 = j - g->oy + (int32_t)(1u << h);
        const float slack = (float)g->npts - thr;
        uint32_t miss = 0;
        for (q = 0; q < n; ++q) {
            const uint32_t k = q;
            const uint32_t a = (uint32_t)(fx[k] + x0) >> e;
            const uint32_t b = (uint32_t)(fy[k] + y0) >> e;
            uint32_t bit = 0;
            if (a < nx && b < ny) {
                const uint32_t at_bit = at + b * nx + a;
                bit = ((uint32_t)grid[at_bit >> 3] >> (at_bit & 7u)) & 1u;
            }
            if (bit == 0u) {
                ++miss;
                if ((float)miss > slack) {
                    *work += q + 1u;
                    promote(g, fx, fy, q);
                    return (float)(g->npts - miss);
                }
            }
        }
        *work += n;
        return (float)(g->npts - miss);
    }
}

/* The four leaves of box (i, j, 1), their scores into bound[] (child c at
 * (i + (c & 1), j + (c >> 1))): each point's 3 x 3 window, read once,
 * holds the four leaves' 2 x 2 ones. A leaf whose points left could not
 * lift it to thr is given up (its sum so far, below thr); the reads stop
 * when all four are. Returns the leaves that reach thr (bit c for leaf
 * c). Adds RSM_GLOBAL_LEAF_WORK a point read, and RSM_GLOBAL_SPLIT_WORK,
 * to *work. */
static uint32_t leaf_bounds(rsm_global_t *g, const uint8_t *grid, const rsm_tmap_t *map, int32_t *fx,
                            int32_t *fy, int32_t i, int32_t j, float thr, float *bound, uint32_t *work)
{
    const uint32_t wall = rsm_tmap_wall_value(map);
    uint32_t q;
    uint32_t live = 15u;
    rsm_tmap_cursor_t cur;
    rsm_tmap_cursor_init(&cur, g->level);
    bound[0] = bound[1] = bound[2] = bound[3] = 0.0f;
    for (q = 0; q < g->npts && live != 0u; ++q) {
        const uint32_t k = q;
        const int32_t u = fx[k] + i;
        const int32_t v = fy[k] + j;
        const float rest = (float)(g->npts - q - 1u);
        uint32_t c;
        /* Grid 1 bounds the whole 3 x 3 window: nothing there, nothing here. */
        if (grid_read(g, grid, 1u, u, v) != 0u) {
            uint32_t w[9];
            window9(map, &cur, g->level, u, v, w);
            bound[0] += cell_score(map, max4(w[0], w[1], w[3], w[4]), wall);
            bound[1] += cell_score(map, max4(w[1], w[2], w[4], w[5]), wall);
            bound[2] += cell_score(map, max4(w[3], w[4], w[6], w[7]), wall);
            bound[3] += cell_score(map, max4(w[4], w[5], w[7], w[8]), wall);
        }
        for (c = 0; c < 4u; ++c) {
            if ((live & (1u << c)) != 0u && bound[c] + rest < thr) {
                live &= ~(1u << c);
                if (live == 0u) {
                    promote(g, fx, fy, q);
                }
            }
        }
        *work += RSM_GLOBAL_LEAF_WORK;
    }
    *work += RSM_GLOBAL_SPLIT_WORK;
    return live;
}

/* A child's miss at point q: its count up, and once past allowed it dies
 * there (its bit out of *live), having read the points up to q. The cold
 * path: most reads hit. */
static void child_miss(int32_t *miss, uint32_t *live, uint32_t *reads, uint32_t c, uint32_t q, int32_t allowed)
{
    if (++miss[c] > allowed) {
        *live &= ~(1u << c);
        *reads += q + 1u;
    }
}

/* The four children of box (i, j, h + 1), boxes of 2^h positions a side
 * (h >= 1), their bounds into bound[] (child c at (i + (c & 1) 2^h, j +
 * (c >> 1) 2^h)), as box_bound gives each, in one pass over the points: a
 * child whose misses could no longer leave thr is given up, the reads stop
 * when all four are. A hit costs a test of the live children's mask and
 * the bit; the counts, the deaths and the reads (each child's, up to the
 * point it died at) are kept only on a miss: on the M4, a test of each
 * count at every read cost more than the read. Returns the children that
 * reach thr (bit c for child c): only theirs are written into bound[].
 * Adds the blocks read, and RSM_GLOBAL_SPLIT_WORK, to *work. */
static uint32_t child_bounds(rsm_global_t *g, const uint8_t *grid, int32_t *fx, int32_t *fy, int32_t i,
                             int32_t j, uint32_t h, float thr, float *bound, uint32_t *work)
{
    /* Grid h's block of a window [u, u + 2^h] is (u - ox + 2^h) >> e: one
     * read a point; a window left of the map wraps to a huge block index,
     * which is past the grid like one right of it (the grids are far
     * narrower than 2^(32 - e) blocks). */
    const uint32_t n = points_read(g, h);
    const uint32_t e = g->grid_e[h];
    const uint32_t nx = g->grid_nx[h];
    const uint32_t ny = g->grid_ny[h];
    const uint32_t at = g->grid_at[h];
    const int32_t half = (int32_t)(1u << h);
    const int32_t x0 = i - g->ox + half;
    const int32_t y0 = j - g->oy + half;
    const float slack = (float)g->npts - thr;
    /* A child is given up once its misses exceed this. */
    const int32_t allowed = slack >= 0.0f ? (int32_t)slack : -1;
    int32_t miss[4] = {0, 0, 0, 0};
    uint32_t reads = 0;
    uint32_t live = allowed >= 0 ? 15u : 0u;
    uint32_t q;
    uint32_t c;
    /* The children's blocks are d apart where they are no wider than a
     * child; where all four lie in the grid (most points: they fall on the
     * map) no bound is tested. Blocks wider than the children (rare: the
     * coarsest grids of a wide map) take the edge's way at every point. */
    const uint32_t d = e <= h ? (uint32_t)half >> e : 0u;
    const uint32_t row = d * nx;
    const uint32_t nx_in = d > 0u && nx > d ? nx - d : 0u;
    const uint32_t ny_in = d > 0u && ny > d ? ny - d : 0u;
    for (q = 0; q < n && live != 0u; ++q) {
        const uint32_t a = (uint32_t)(fx[q] + x0) >> e;
        const uint32_t b = (uint32_t)(fy[q] + y0) >> e;
        if (a < nx_in && b < ny_in) {
            const uint32_t first = at + b * nx + a;
            if ((live & 1u) != 0u && get_bit(grid, first) == 0u) {
                child_miss(miss, &live, &reads, 0u, q, allowed);
            }
            if ((live & 2u) != 0u && get_bit(grid, first + d) == 0u) {
                child_miss(miss, &live, &reads, 1u, q, allowed);
            }
            if ((live & 4u) != 0u && get_bit(grid, first + row) == 0u) {
                child_miss(miss, &live, &reads, 2u, q, allowed);
            }
            if ((live & 8u) != 0u && get_bit(grid, first + row + d) == 0u) {
                child_miss(miss, &live, &reads, 3u, q, allowed);
            }
        } else {
            /* Each child's block from its own window (a window left of
             * the grid wraps to a huge index, so the blocks are not d
             * apart there). */
            const uint32_t a1 = (uint32_t)(fx[q] + x0 + half) >> e;
            const uint32_t b1 = (uint32_t)(fy[q] + y0 + half) >> e;
            for (c = 0; c < 4u; ++c) {
                const uint32_t ac = (c & 1u) != 0u ? a1 : a;
                const uint32_t bc = (c & 2u) != 0u ? b1 : b;
                if ((live & (1u << c)) != 0u && !(ac < nx && bc < ny && get_bit(grid, at + bc * nx + ac) != 0u)) {
                    child_miss(miss, &live, &reads, c, q, allowed);
                }
            }
        }
    }
    if (live == 0u) {
        /* Most splits end here (on ACES, 96 % of the children of 0.8 m
         * boxes die): the dead's reads are counted, their bounds are not
         * asked for. The point that ended the last child's bound moves up. */
        *work += reads + RSM_GLOBAL_SPLIT_WORK;
        if (q > 0u) {
            promote(g, fx, fy, q - 1u);
        }
        return 0u;
    }
    /* The live read every point; the dead up to the one they died at
     * (child_miss). */
    for (c = 0; c < 4u; ++c) {
        if ((live & (1u << c)) != 0u) {
            reads += q;
            bound[c] = (float)((int32_t)g->npts - miss[c]);
        }
    }
    *work += reads + RSM_GLOBAL_SPLIT_WORK;
    return live;
}

/* The score a box must reach to be split or kept. */
static float threshold(const rsm_global_t *g)
{
    const float rel = (1.0f - KEEP_SHARE) * g->best_score;
    return rel > g->floor_score ? rel : g->floor_score;
}

/* The score a leaf must reach to be kept, below the boxes' by LEAF_SLACK of
 * the points: a leaf scores the lattice's heading, and a place that looks
 * the same as the best one (a room's twin turned half round) can score a
 * point or two less there than the best does at its own. Such a rival
 * must be kept, or the proof would take the best unopposed; its box above
 * reached the bar. */
static float leaf_threshold(const rsm_global_t *g)
{
    return threshold(g) - LEAF_SLACK * (float)g->npts;
}

/* How well the kept points fit at pose x itself: their occupancy on the
 * search level, interpolated, summed. Leaves that reach the bar often all
 * score the most (every point's window of two cells a side on a wall), so
 * this, not the leaf's score, ranks them. */
static float fine_score(const rsm_global_t *g, const rsm_tmap_t *map, const rsm_pose_t *x, float stop, uint32_t *read)
{
    float c;
    float s;
    float sum = 0.0f;
    uint32_t k;
    rsm_tmap_cursor_t cur;
    rsm_sincosf(x->theta, &s, &c);
    /* One cursor for the scan's points, which lie near each other in turn. */
    rsm_tmap_cursor_init(&cur, g->level);
    for (k = 0; k < g->npts; ++k) {
        const rsm_point_t *p = &g->pts[k];
        float dx;
        float dy;
        if (sum + (float)(g->npts - k) <= stop) {
            break; /* even a perfect rest (1 a point) would not reach it */
        }
        sum += rsm_tmap_sample_at(map, &cur, x->x + c * p->x - s * p->y, x->y + s * p->x + c * p->y, &dx, &dy);
    }
    *read = k;
    return sum;
}

/* The fine a leaf of the given score must exceed for keep to keep it or
 * drop a kept pose for it: a full list, none of whose poses the score
 * would leave behind, keeps a leaf only above its last one's fine (any
 * fine at or under it changes nothing but the counts, which do not depend
 * on it). -1 when any fine may matter. */
static float no_gain(const rsm_global_t *g, float score)
{
    const float best = score > g->best_score ? score : g->best_score;
    uint32_t m;
    if (g->found < (uint32_t)RSM_GLOBAL_CANDIDATES) {
        return -1.0f;
    }
    for (m = 0; m < g->found; ++m) {
        if (g->cand[m].score < (1.0f - KEEP_SHARE) * best) {
            return -1.0f;
        }
    }
    return g->cand[g->found - 1u].fine;
}

/* Whether kept pose o stands for x: x within two lattice steps and two
 * heading steps of it (its basin). */
static int in_basin(const rsm_global_t *g, float cell, const rsm_pose_t *o, const rsm_pose_t *x)
{
    const float near_m = 2.0f * cell + 1e-3f;
    const float near_rad = 2.0f * g->step_rad + 1e-4f;
    return fabsf(o->x - x->x) <= near_m && fabsf(o->y - x->y) <= near_m &&
           fabsf(rsm_wrap_angle(o->theta - x->theta)) <= near_rad;
}

/* Keeps a leaf among the best distinct poses, ranked by fine: one within
 * the basin of a better kept one is not a rival. */
static void keep(rsm_global_t *g, float cell, const rsm_pose_t *x, float score, float fine)
{
    uint32_t m;
    uint32_t kept = 0;
    uint32_t at;
    if (score > g->best_score) {
        g->best_score = score;
    }
    for (m = 0; m < g->found; ++m) {
        if (in_basin(g, cell, &g->cand[m].pose, x)) {
            if (g->cand[m].fine >= fine) {
                return;
            }
        } else {
            g->cand[kept++] = g->cand[m];
        }
    }
    g->found = kept;
    /* Those the best leaves behind by more than the share go. */
    for (m = 0, kept = 0; m < g->found; ++m) {
        if (!(g->cand[m].score < (1.0f - KEEP_SHARE) * g->best_score)) {
            g->cand[kept++] = g->cand[m];
        }
    }
    g->found = kept;
    if (g->found == (uint32_t)RSM_GLOBAL_CANDIDATES) {
        /* One of the two is not kept: the proof cannot weigh it. */
        g->unkept++;
        if (!(fine > g->cand[g->found - 1u].fine)) {
            return;
        }
        g->found--;
    }
    for (at = g->found; at > 0u && g->cand[at - 1u].fine < fine; --at) {
        g->cand[at] = g->cand[at - 1u];
    }
    g->cand[at].pose = *x;
    g->cand[at].score = score;
    g->cand[at].fine = fine;
    g->found++;
}

/* Whether tile t (of a level `up` finer than the search level) overlaps
 * the grids' box. */
static int in_box(const rsm_global_t *g, const rsm_tile_t *t, uint32_t up)
{
    const int32_t x0 = floor_shift((int32_t)t->tx * RSM_TMAP_TILE_SIDE, up);
    const int32_t y0 = floor_shift((int32_t)t->ty * RSM_TMAP_TILE_SIDE, up);
    const int32_t x1 = floor_shift((int32_t)t->tx * RSM_TMAP_TILE_SIDE + RSM_TMAP_TILE_SIDE - 1, up);
    const int32_t y1 = floor_shift((int32_t)t->ty * RSM_TMAP_TILE_SIDE + RSM_TMAP_TILE_SIDE - 1, up);
    return x1 >= g->cache_box[0] && x0 <= g->cache_box[2] && y1 >= g->cache_box[1] && y0 <= g->cache_box[3];
}

/* Builds the grids and the map's wall directions for about budget reads
 * more (0: to the end), into *work: a tile at a time, then the coarser
 * grids a block at a time. 1 once they stand (then marked as cached, for
 * the map as it is now; g->dir_next == map->used), 0 while work remains
 * (or once the caller has taken them, g->dir_next past map->used). */
static int build(rsm_global_t *g, uint8_t *grid, const rsm_tmap_t *map, uint32_t budget, uint32_t *work)
{
    while (g->dir_next < map->used) {
        const rsm_tile_t *t = &map->tile[g->dir_next];
        const uint32_t level = t->stamp >> 30;
        if (budget > 0u && *work >= budget) {
            break;
        }
        if (level == g->level && in_box(g, t, 0u)) {
            *work += RSM_GLOBAL_BUILD_WORK * grid_tile(g, grid, t, rsm_tmap_wall_value(map));
        }
        if (level == direction_level(g->level) && in_box(g, t, g->level - level)) {
            *work += RSM_GLOBAL_BUILD_WORK * tile_directions(g, t);
        }
        g->dir_next++;
    }
    while (g->dir_next == map->used && g->build_next < g->build_end) {
        if (budget > 0u && *work >= budget) {
            break;
        }
        *work += RSM_GLOBAL_BUILD_WORK * grid_up(g, grid, g->build_next);
        g->build_next++;
    }
    if (g->dir_next == map->used && g->build_next == g->build_end) {
        g->cached = 1u;
        g->cache_writes = map->counters.updates;
        g->cache_tiles = map->level_used[g->level];
        g->cache_sig = read_signature(map, g->level);
        g->cache_churn = map->churn[g->level];
        g->cache_churn_sig = map->churn_sig[g->level];
        return 1;
    }
    return 0;
}

int rsm_global_prepare(rsm_global_t *g, uint8_t *grid, size_t grid_bytes, const rsm_tmap_t *map, uint32_t *used)
{
    int32_t b[4];
    uint32_t work = 0;
    int rc;
    if ((rc = rsm_global_check(map, grid_bytes)) != RSM_OK) {
        return rc;
    }
    g->grid_bytes = grid_cap(grid_bytes);
    (void)rsm_tmap_bounds(map, search_level(map), &b[0], &b[1], &b[2], &b[3]);
    g->level = search_level(map);
    if ((rc = begin_build(g, grid, b[0], b[1], b[2], b[3])) != RSM_OK) {
        return rc;
    }
    (void)build(g, grid, map, 0u, &work);
    if (used != NULL) {
        *used += work;
    }
    return RSM_OK;
}

int rsm_global_run(rsm_global_t *g, uint8_t *grid, const rsm_tmap_t *map, uint32_t budget, uint32_t *used)
{
    const float cell = rsm_tmap_cell(map, g->level);
    int32_t fx[RSM_GLOBAL_POINTS];
    int32_t fy[RSM_GLOBAL_POINTS];
    uint32_t work = 0;
    int more = 1;
    if (g->depth > 0u) {
        offsets(g, cell, g->heading - 1u, fx, fy);
    }
    if (build(g, grid, map, budget, &work)) {
        direction_agreement(g);
        g->dir_next++;
    }
    for (;;) {
        rsm_global_box_t b;
        if (budget > 0u && work >= budget) {
            break;
        }
        if (g->depth == 0u) {
            while (g->pass < PASSES && (g->heading == g->headings || !in_pass(g, g->heading))) {
                if (g->heading == g->headings) {
                    g->heading = 0;
                    g->pass++;
                } else {
                    g->heading++;
                }
            }
            if (g->pass == PASSES) {
                more = 0;
                break;
            }
            offsets(g, cell, g->heading, fx, fy);
            g->heading++;
            work += RSM_GLOBAL_HEADING_WORK;
            b.i = g->root_i;
            b.j = g->root_j;
            b.h = g->root_h;
            b.bound = box_bound(g, grid, map, fx, fy, b.i, b.j, b.h, threshold(g), &work);
            if (b.bound >= threshold(g)) {
                g->stack[g->depth++] = b;
            }
            continue;
        }
        b = g->stack[--g->depth];
        if (b.bound < (b.h == 0u ? leaf_threshold(g) : threshold(g))) {
            continue;
        }
        if (b.h == 0u) {
            rsm_pose_t x;
            /* The leaf's positions span its cell: its centre stands for them. */
            x.x = ((float)b.i + 0.5f) * cell;
            x.y = ((float)b.j + 0.5f) * cell;
            x.theta = rsm_wrap_angle((float)(g->heading - 1u) * g->step_rad);
            {
                /* A leaf that cannot enter a full list is read only until
                 * that is sure (keep gives it the same verdict: a basin of
                 * a kept pose, or one not kept). */
                uint32_t read = 0;
                const float fine = fine_score(g, map, &x, no_gain(g, b.bound), &read);
                keep(g, cell, &x, b.bound, fine);
                work += RSM_GLOBAL_FIT_WORK * read;
            }
            continue;
        }
        {
            const uint32_t h = b.h - 1u;
            const int32_t half = (int32_t)(1u << h);
            rsm_global_box_t child[4];
            float leaf[4];
            uint32_t live;
            uint32_t c;
            uint32_t nc = 0;
            /* The bar of the children (the best score does not change
             * while they are bounded). */
            const float bar = h == 0u ? leaf_threshold(g) : threshold(g);
            if (h == 0u) {
                live = leaf_bounds(g, grid, map, fx, fy, b.i, b.j, bar, leaf, &work);
            } else {
                live = child_bounds(g, grid, fx, fy, b.i, b.j, h, bar, leaf, &work);
            }
            for (c = 0; live != 0u && c < 4u; ++c) {
                rsm_global_box_t ch;
                uint32_t at;
                if ((live & (1u << c)) == 0u) {
                    continue;
                }
                ch.i = b.i + ((c & 1u) ? half : 0);
                ch.j = b.j + ((c & 2u) ? half : 0);
                ch.h = h;
                ch.bound = leaf[c];
                /* Ascending, so that the best is pushed last, popped first. */
                for (at = nc; at > 0u && child[at - 1u].bound > ch.bound; --at) {
                    child[at] = child[at - 1u];
                }
                child[at] = ch;
                nc++;
            }
            /* Three siblings wait per level at most: the stack holds them
             * (RSM_GLOBAL_STACK). */
            for (c = 0; c < nc && g->depth < (uint32_t)RSM_GLOBAL_STACK; ++c) {
                g->stack[g->depth++] = child[c];
            }
        }
    }
    g->work += work;
    if (used != NULL) {
        *used += work;
    }
    return more;
}

void rsm_global_window(rsm_global_t *g, uint8_t *grid, const rsm_tmap_t *map, float x, float y, float radius_m)
{
    const float cell = rsm_tmap_cell(map, g->level);
    const float inv = 1.0f / cell;
    const float lim = (float)(RSM_TMAP_TILE_LIMIT * RSM_TMAP_TILE_SIDE);
    float fx0 = rsm_floorf((x - radius_m) * inv);
    float fy0 = rsm_floorf((y - radius_m) * inv);
    float w = rsm_floorf((x + radius_m) * inv) - fx0 + 1.0f;
    const float hgt = rsm_floorf((y + radius_m) * inv) - fy0 + 1.0f;
    int32_t box[4];
    float far = 0.0f;
    int32_t reach;
    uint32_t h = 0;
    uint32_t k;
    w = hgt > w ? hgt : w;
    /* Far outside the map's range, or wider than the map: the whole map. */
    if (!(fx0 > -lim && fx0 < lim && fy0 > -lim && fy0 < lim && w >= 1.0f && w < lim)) {
        return;
    }
    while (h < g->top_h && (float)(1u << h) < w) {
        ++h;
    }
    if (h >= g->top_h) {
        return;
    }
    if (g->cached == 0u) {
        /* The grids are yet to be built: only over what the window's
         * points can reach (the window, twice over for the windows of its
         * boxes, and the farthest point's range around it), so that the
         * build and the map's directions cost what is near, and the grids'
         * blocks come finer. */
        for (k = 0; k < g->npts; ++k) {
            const float r = sqrtf(g->pts[k].x * g->pts[k].x + g->pts[k].y * g->pts[k].y);
            far = r > far ? r : far;
        }
        reach = (int32_t)(far * inv) + 2;
        box[0] = (int32_t)fx0 - reach;
        box[1] = (int32_t)fy0 - reach;
        box[2] = (int32_t)fx0 + (int32_t)(2u << h) + reach;
        box[3] = (int32_t)fy0 + (int32_t)(2u << h) + reach;
        box[0] = box[0] > g->cache_box[0] ? box[0] : g->cache_box[0];
        box[1] = box[1] > g->cache_box[1] ? box[1] : g->cache_box[1];
        box[2] = box[2] < g->cache_box[2] ? box[2] : g->cache_box[2];
        box[3] = box[3] < g->cache_box[3] ? box[3] : g->cache_box[3];
        if (box[0] <= box[2] && box[1] <= box[3] &&
            (box[0] != g->cache_box[0] || box[1] != g->cache_box[1] || box[2] != g->cache_box[2] ||
             box[3] != g->cache_box[3]) &&
            begin_grids(g, grid, box[0], box[1], box[2], box[3], h > 0u ? h : 1u) == RSM_OK) {
            memcpy(g->cache_box, box, sizeof box);
        }
    }
    g->root_i = (int32_t)fx0;
    g->root_j = (int32_t)fy0;
    g->root_h = h;
}

/* A best pose fitting at least this share of the fit asked is judged
 * again with a new view rather than given up (rsm_global_verdict). */
#define NEAR_FIT 0.9f

/* The kept pose that fits the kept scan best this round. */
static uint32_t round_best(const rsm_global_t *g)
{
    uint32_t best = 0;
    uint32_t k;
    for (k = 1; k < g->found; ++k) {
        if (g->hit[k] > g->hit[best]) {
            best = k;
        }
    }
    return best;
}

/* A fit's log, floored: a pose that fell off the map loses for good, in
 * finite sums. */
static float log_fit(float hit)
{
    return logf(hit > 1.0e-3f ? hit : 1.0e-3f);
}

/* A view where a pose's descent ended nowhere (its hit -1, prove_one)
 * adds this to its sum of log fits, far under any sum of fits (at least
 * log_fit's floor, -6.9, a view): a sum under LOG_FIT_FLOOR holds such a
 * view. */
#define LOG_NO_FIT (-1000.0f)
#define LOG_FIT_FLOOR (-100.0f)

/* Whether kept pose k had a fit in every view before this one (its
 * descent ended somewhere each time), and the log of its fits multiplied
 * over all the views, this one too. */
static int fitted_before(const rsm_global_t *g, uint32_t k)
{
    return g->rounds > 0u && g->log_hit[k] > LOG_FIT_FLOOR;
}

static float log_views(const rsm_global_t *g, uint32_t k)
{
    return g->log_hit[k] + log_fit(g->hit[k]);
}

/* Kept pose k's fit over every view so far, as a mean of their logs (its
 * fit here where a view before holds none). The fit asked of a winner is
 * asked of all its views together, as the margin over its rivals is:
 * measured on an ACES kidnap with updates, a lone pose 3.64 m off and
 * turned half round fitted 0.624 and then 0.745 where 0.690 was asked,
 * and the second view alone took it. */
static float fit_views(const rsm_global_t *g, uint32_t k)
{
    return fitted_before(g, k) ? expf(log_views(g, k) / (float)(g->rounds + 1u)) : g->hit[k];
}

int rsm_global_verdict(const rsm_global_t *g, float min_fit, float margin, float doubt_m, float doubt_rad,
                       uint32_t *win)
{
    const float log_margin = logf(1.0f + margin);
    float rival = 0.0f;
    uint32_t k;
    uint32_t best;
    int summed = 1; /* every rival beyond doubt over the views so far (none before this one: 1) */
    int led;
    if (g->found == 0u) {
        return -1;
    }
    best = round_best(g);
    if (!(g->hit[best] >= min_fit && fit_views(g, best) >= min_fit)) {
        /* A little under: in doubt, for another view of the same poses
         * (traced on Intel starts: right poses fitting 0.79 and 0.81 of the
         * map's own in a crowded search, where 0.84 is asked, proven only by
         * a new search 15 to 30 scans later). */
        return g->hit[best] >= NEAR_FIT * min_fit ? 0 : -1;
    }
    /* Beyond doubt of every rival by all the views together (each pose's
     * fits multiplied over them, as independent evidence), and by this
     * view alone unless it led every view before, each above the bar.
     * A view alone is not enough after views that favoured a rival
     * (measured on an ACES kidnap with updates: a place 5.9 m off and
     * turned half round, 8 % behind the true one in the first view and
     * 16 % ahead in the second, was taken on the second). */
    /* After a crowded search this view must prove it alone too: its kept
     * poses are a few of many alike (a corridor's, whose views differ
     * little and together; measured on an ACES start: eight poses along
     * one corridor, the leader 15 m from the truth summed over two
     * views). */
    led = g->rounds > 0u && g->leader == best && !rsm_global_crowded(g);
    for (k = 0; k < g->found; ++k) {
        if (k == best || !rsm_pose_apart(&g->end[k], &g->end[best], doubt_m, doubt_rad)) {
            continue; /* the same place */
        }
        if (g->hit[k] > rival) {
            rival = g->hit[k];
        }
        if (fitted_before(g, best) && fitted_before(g, k) && !(log_views(g, best) - log_views(g, k) > log_margin)) {
            /* (Weighed where both had a fit in every view before: a pose
             * whose descent ended nowhere in one has none there.) */
            summed = 0;
        }
    }
    if (!summed || (g->hit[best] <= rival * (1.0f + margin) && !led)) {
        return 0;
    }
    if (rsm_global_crowded(g) && !(rival >= CROWDED_RIVAL * g->hit[best])) {
        /* A crowded search whose kept poses came down to one place: it
         * was weighed against none of the many others that reached the
         * bar (measured on an ACES kidnap: three of the eight kept poses
         * descended to one place, the rest fitted under a tenth of it,
         * and the place proven was the true one turned half round, 3.5 m
         * along a symmetric corridor). In doubt, for another view. */
        return 0;
    }
    *win = best;
    return 1;
}

rsm_pose_t rsm_global_pending_carried(const rsm_global_t *g, const rsm_pose_t *at)
{
    const rsm_pose_t moved = rsm_pose_between(&g->pending_at, at);
    return rsm_pose_compose(&g->pending_pose, &moved);
}

/* Each search begins from a later scan and keeps its own few poses, the
 * pending winner weighed among them (rsm_global_weigh_also). Measured on
 * the bench's ACES kidnaps: crowded winners 4.7 m (turned half round) and
 * 36 m off had been taken; the searches after each proved other places
 * (docs/globalsearch.md, "A crowded winner proven twice"). */
int rsm_global_take(rsm_global_t *g, const rsm_pose_t *pose, const rsm_pose_t *at, float reach_m, float reach_rad)
{
    if (!rsm_global_crowded(g)) {
        g->pending = 0u;
        return 1;
    }
    if (g->pending) {
        const rsm_pose_t carried = rsm_global_pending_carried(g, at);
        if (!rsm_pose_apart(&carried, pose, reach_m, reach_rad)) {
            g->pending = 0u;
            return 1;
        }
    }
    g->pending = 1u;
    g->pending_pose = *pose;
    g->pending_at = *at;
    return 0;
}

void rsm_global_weigh_also(rsm_global_t *g, const rsm_tmap_t *map, const rsm_pose_t *pose)
{
    const float cell = rsm_tmap_cell(map, g->level);
    uint32_t m;
    for (m = 0; m < g->found; ++m) {
        if (in_basin(g, cell, &g->cand[m].pose, pose)) {
            return;
        }
    }
    if (g->found == (uint32_t)RSM_GLOBAL_CANDIDATES) {
        g->found--;
    }
    g->cand[g->found].pose = *pose;
    g->cand[g->found].score = 0.0f;
    g->cand[g->found].fine = 0.0f;
    g->found++;
}

void rsm_global_add_round(rsm_global_t *g, float min_fit)
{
    const uint32_t best = round_best(g);
    uint32_t k;
    if (g->rounds == 0u) {
        g->leader = best;
        for (k = 0; k < g->found; ++k) {
            g->log_hit[k] = 0.0f;
        }
    } else if (g->leader != best) {
        g->leader = (uint32_t)RSM_GLOBAL_CANDIDATES;
    }
    if (!(g->hit[best] >= min_fit)) {
        /* A view the best fits poorly from is evidence against it, not
         * for it: its sums count no more (traced on ACES start 5, a
         * search crowded with 856 look-alikes: a pose 15 m off that fitted
         * under the bar in one of three views, proven by the other two). */
        g->leader = (uint32_t)RSM_GLOBAL_CANDIDATES;
    }
    for (k = 0; k < g->found; ++k) {
        g->log_hit[k] += g->hit[k] < 0.0f ? LOG_NO_FIT : log_fit(g->hit[k]);
    }
}
