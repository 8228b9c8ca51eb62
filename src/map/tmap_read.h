/* Reads of the tile map, inline: the map matcher samples every point of a
 * scan a dozen times per scan, and a call per read (plus one per tile
 * lookup) was most of a scan's cost on a Cortex-M4. The public readers in
 * tilemap.c are these same functions. Internal to the library. */
#ifndef RSM_TMAP_READ_H
#define RSM_TMAP_READ_H

#include <stdint.h>
#include <string.h>

#include "core/compiler.h"
#include "map/tilemap.h"

#define RSM_TMAP_TILE_MASK ((int32_t)RSM_TMAP_TILE_SIDE - 1)
/* Cells beyond this from the origin (at any level) are refused, so that tile
 * coordinates fit int16 and cell arithmetic never overflows. */
#define RSM_TMAP_CELL_LIMIT (RSM_TMAP_TILE_LIMIT * RSM_TMAP_TILE_SIDE)

/* A pair of tile (or cell) coordinates as one word: the cursor's key, and
 * what the index and the echo set hash. */
static inline uint32_t rsm_tmap_pack(int32_t x, int32_t y)
{
    return (uint32_t)(uint16_t)x | ((uint32_t)(uint16_t)y << 16);
}

/* Multiplicative mixing of a packed key; its top `bits` bits. */
static inline uint32_t rsm_tmap_mix(uint32_t k, unsigned bits)
{
    return (k * 2654435761u) >> (32u - bits);
}

/* Where a tile's place (level, column, row) starts its probe in an index
 * of 2^bits entries: the pool's (tilemap.c) and the tile stores'
 * (tilestore.c). */
static inline uint32_t rsm_tmap_place_hash(uint32_t level, int32_t tx, int32_t ty, unsigned bits)
{
    return rsm_tmap_mix(rsm_tmap_pack(tx, ty) ^ (level * 0x9E3779B9u), bits);
}

/* A tile's place (level, column, row) mixed into a word, for sums over a
 * set of tiles that tell one set from another (a global search's grids,
 * globalsearch.c, and the tiles writes began, tilemap.c). */
static inline uint32_t rsm_tmap_place_sig(uint32_t level, int32_t tx, int32_t ty)
{
    uint32_t h = (((uint32_t)(uint16_t)tx << 16) | (uint32_t)(uint16_t)ty) * 0x9E3779B1u;
    h ^= level * 0x85EBCA77u;
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    return h ^ (h >> 12);
}

/* Slot of a tile, or RSM_TMAP_NONE (the index lookup, in tilemap.c). */
uint32_t rsm_tmap_find_slot(const rsm_tmap_t *map, uint32_t level, int32_t tx, int32_t ty);

/* A window that holds no tile. */
static inline void rsm_tmap_window_forget(rsm_tmap_window_t *w)
{
    /* No tile's first cell (those are multiples of the tile side). */
    w->bx = INT32_MIN + 1;
    w->by = INT32_MIN + 1;
    w->tile = NULL;
}

/* Forgets every tile the cursor holds (after a write moved or freed one). */
static inline void rsm_tmap_cursor_forget(rsm_tmap_cursor_t *c)
{
    uint32_t k;
    for (k = 0; k < RSM_TMAP_CURSOR_WAYS * RSM_TMAP_CURSOR_WAYS; ++k) {
        c->way[k].key = RSM_TMAP_NO_KEY;
    }
    rsm_tmap_window_forget(&c->win);
}

/* Slot of the tile holding cell (gx, gy) of the cursor's level. */
static inline uint32_t rsm_tmap_cursor_slot(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, int32_t gx, int32_t gy)
{
    const int32_t tx = gx >> RSM_TMAP_TILE_LOG2;
    const int32_t ty = gy >> RSM_TMAP_TILE_LOG2;
    const uint32_t key = rsm_tmap_pack(tx, ty);
    const uint32_t m = (uint32_t)RSM_TMAP_CURSOR_WAYS - 1u;
    rsm_tmap_way_t *w = &c->way[((uint32_t)tx & m) | (((uint32_t)ty & m) * (uint32_t)RSM_TMAP_CURSOR_WAYS)];
    if (w->key != key) {
        w->key = key;
        w->slot = rsm_tmap_find_slot(map, c->level, tx, ty);
    }
    return w->slot;
}

static inline uint32_t rsm_tmap_cell_index(int32_t gx, int32_t gy)
{
    return ((uint32_t)(gy & RSM_TMAP_TILE_MASK) << RSM_TMAP_TILE_LOG2) | (uint32_t)(gx & RSM_TMAP_TILE_MASK);
}

static inline uint32_t rsm_tmap_get_cell(const rsm_tile_t *t, uint32_t i)
{
    return ((uint32_t)t->cell[i >> 1] >> ((i & 1u) << 2)) & 15u;
}

/* Value of cell (gx, gy) in the tile of slot s; 0 where no tile is held. */
static inline uint32_t rsm_tmap_slot_value(const rsm_tmap_t *map, uint32_t s, int32_t gx, int32_t gy)
{
    return s == RSM_TMAP_NONE ? 0u : rsm_tmap_get_cell(&map->tile[s], rsm_tmap_cell_index(gx, gy));
}

/* Cell of a world coordinate at a level (inv_a: 1 / its cell side): floor,
 * not truncation. */
static inline int32_t rsm_tmap_cell_of(float v, float inv_a)
{
    const float u = v * inv_a;
    int32_t i;
    /* floor(u) lies in (-L, L) exactly for u in [1 - L, L). Beyond (or
     * NaN): a cell rsm_tmap_in_range refuses, and no float-to-int
     * conversion that overflows. Within, the truncation stepped down where
     * it rounded up is the floor, without rsm_floorf's tests for the range
     * it knows. */
    if (!(u >= (float)(1 - RSM_TMAP_CELL_LIMIT) && u < (float)RSM_TMAP_CELL_LIMIT)) {
        return RSM_TMAP_CELL_LIMIT;
    }
    i = (int32_t)u;
    return (float)i > u ? i - 1 : i;
}

/* Whether a cell lies within the map's reach (rsm_tmap_cell_of's cells
 * beyond it do not). */
static inline int rsm_tmap_in_range(int32_t gx, int32_t gy)
{
    return gx > -RSM_TMAP_CELL_LIMIT && gx < RSM_TMAP_CELL_LIMIT && gy > -RSM_TMAP_CELL_LIMIT &&
           gy < RSM_TMAP_CELL_LIMIT;
}

/* Value of a cell through a cursor; 0 where no tile is held. */
static inline uint32_t rsm_tmap_cell_value(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, int32_t gx, int32_t gy)
{
    return rsm_tmap_slot_value(map, rsm_tmap_cursor_slot(map, c, gx, gy), gx, gy);
}

/* The occupancy of two horizontal neighbours, cells k and k + 1 of a tile's
 * row (k + 1 in the same row). */
static inline void rsm_tmap_occ_pair(const rsm_tmap_t *map, const rsm_tile_t *t, uint32_t k, float *left,
                                     float *right)
{
    const uint8_t *b = &t->cell[k >> 1];
    if ((k & 1u) == 0u) {
        *left = map->occ[b[0] & 15u];
        *right = map->occ[b[0] >> 4];
    } else {
        *left = map->occ[b[0] >> 4];
        *right = map->occ[b[1] & 15u];
    }
}

/* The largest cell value of a level in the window [u, u + 1] x [v, v + 1]
 * (0 where no tile is held, or out of the cells' range): one tile lookup
 * when the four cells share a tile. The global search's bounds and a
 * recovery's wall share read walls so. */
static inline uint32_t rsm_tmap_window_max(const rsm_tmap_t *map, uint32_t level, int32_t u, int32_t v)
{
    const int32_t lim = RSM_TMAP_CELL_LIMIT - 2;
    uint32_t best;
    if ((u & RSM_TMAP_TILE_MASK) != RSM_TMAP_TILE_MASK && (v & RSM_TMAP_TILE_MASK) != RSM_TMAP_TILE_MASK &&
        u > -lim && u < lim && v > -lim && v < lim) {
        const uint32_t s = rsm_tmap_find_slot(map, level, u >> RSM_TMAP_TILE_LOG2, v >> RSM_TMAP_TILE_LOG2);
        const rsm_tile_t *t;
        uint32_t k;
        uint32_t c;
        if (s == RSM_TMAP_NONE) {
            return 0u;
        }
        t = &map->tile[s];
        k = rsm_tmap_cell_index(u, v);
        best = rsm_tmap_get_cell(t, k);
        c = rsm_tmap_get_cell(t, k + 1u);
        best = c > best ? c : best;
        c = rsm_tmap_get_cell(t, k + (uint32_t)RSM_TMAP_TILE_SIDE);
        best = c > best ? c : best;
        c = rsm_tmap_get_cell(t, k + (uint32_t)RSM_TMAP_TILE_SIDE + 1u);
        return c > best ? c : best;
    }
    {
        uint32_t c;
        best = rsm_tmap_value(map, level, u, v);
        c = rsm_tmap_value(map, level, u + 1, v);
        best = c > best ? c : best;
        c = rsm_tmap_value(map, level, u, v + 1);
        best = c > best ? c : best;
        c = rsm_tmap_value(map, level, u + 1, v + 1);
        return c > best ? c : best;
    }
}

/* Metres from the origin within which every read is inside the cells'
 * range on every level (two finest cells short of it, for rounding). */
static inline float rsm_tmap_read_reach(const rsm_tmap_t *map)
{
    return (float)(RSM_TMAP_CELL_LIMIT - 3) / map->inv_cell[0];
}

/* Without an FPU (RSM_SOFT_FLOAT) the reads split a coordinate into its
 * floor and fraction on its bits, test a gradient for zero on its bits and
 * skip the products a zero makes exact, with the same results as the float
 * operations (the host replay equals the Cortex-M3's and the M0+'s bit for
 * bit: m3.replay_matches_host, m0plus.replay_matches_host). */

static inline uint32_t rsm_tmap_bits(float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    return b;
}

/* f == 0.0f (either zero), on the bits. */
static inline int rsm_tmap_is_zero(float f)
{
    return (rsm_tmap_bits(f) << 1) == 0u;
}

/* No gradient: gu and gv both zero (on the bits without an FPU). */
static inline int rsm_tmap_flat(float gu, float gv)
{
#if RSM_SOFT_FLOAT
    return ((rsm_tmap_bits(gu) | rsm_tmap_bits(gv)) << 1) == 0u;
#else
    return gu == 0.0f && gv == 0.0f;
#endif
}

/* floor(u) into *i and u - floor(u) into *frac, exactly as the float path
 * of rsm_tmap_read_cells computes them, on u's bits: returns 0 (nothing
 * written) where the difference would round, u in (-1, 0), or where u is
 * 2^23 or more, which the caller's range test keeps out. */
static inline int rsm_tmap_split(float u, int32_t *i, float *frac)
{
    const uint32_t b = rsm_tmap_bits(u);
    const int32_t e = (int32_t)((b >> 23) & 0xFFu) - 127;
    uint32_t shift;
    uint32_t m;
    uint32_t f;
    uint32_t p;
    if (e < 0) {
        if ((b >> 31) != 0u && (b << 1) != 0u) {
            return 0; /* u + 1 rounds for small negative u */
        }
        *i = 0;
        *frac = u; /* u - 0 */
        return 1;
    }
    if (e > 22) {
        return 0;
    }
    shift = 23u - (uint32_t)e;
    m = (b & 0x7FFFFFu) | 0x800000u;
    f = m & ((1u << shift) - 1u);
    if ((b >> 31) == 0u) {
        *i = (int32_t)(m >> shift);
    } else if (f == 0u) {
        *i = -(int32_t)(m >> shift);
    } else {
        *i = -(int32_t)(m >> shift) - 1;
        f = (1u << shift) - f;
    }
    if (f == 0u) {
        *frac = 0.0f;
        return 1;
    }
    /* f 2^-shift, f < 2^23: its leading bit p places the exponent. */
    p = (uint32_t)rsm_top_bit(f);
    f = ((f << (23u - p)) & 0x7FFFFFu) | ((p + 127u - shift) << 23);
    memcpy(frac, &f, sizeof f);
    return 1;
}

/* The occupancies of cells (i, j), (i + 1, j), (i, j + 1) and (i + 1, j + 1)
 * into m[0..3], where they straddle a tile's last column or row (i or j
 * the last of its tile): each tile they lie in is looked up once, but
 * (i, j)'s when own says it is t (the caller's window). Returns (i, j)'s
 * tile (one of zeros where none is held, which reads as no tile does),
 * where the window moves: the next reads are likely in it. Out of line, in
 * tilemap.c: a fifth of the map matcher's reads, whose registers the other
 * four fifths need. */
const rsm_tile_t *rsm_tmap_straddle(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, int own, const rsm_tile_t *t,
                                    int32_t i, int32_t j, float m[4]);

/* Cell (i, j)'s column and row in the window's tile (*ci, *cj): both below
 * the tile's last when the four cells from it lie in that tile (one compare
 * each, the window's tile and its edge at once). When all four lie in
 * another tile, the window moves there first. */
static RSM_ALWAYS_INLINE void rsm_tmap_window_place(const rsm_tmap_t *map, rsm_tmap_cursor_t *c,
                                                    rsm_tmap_window_t *w, int32_t i, int32_t j, uint32_t *ci,
                                                    uint32_t *cj)
{
    const uint32_t mask = (uint32_t)RSM_TMAP_TILE_MASK;
    *ci = (uint32_t)i - (uint32_t)w->bx;
    *cj = (uint32_t)j - (uint32_t)w->by;
    if ((*ci >= mask || *cj >= mask) && ((uint32_t)i & mask) != mask && ((uint32_t)j & mask) != mask) {
        const uint32_t s = rsm_tmap_cursor_slot(map, c, i, j);
        w->bx = (int32_t)((uint32_t)i & ~mask);
        w->by = (int32_t)((uint32_t)j & ~mask);
        w->tile = s == RSM_TMAP_NONE ? NULL : &map->tile[s];
        *ci = (uint32_t)i & mask;
        *cj = (uint32_t)j & mask;
    }
}

/* The occupancy at (u, v) in cells of the cursor's level, cell centres at
 * whole numbers: bilinear between the four centres around it. Its
 * gradient per cell goes to *du_out and *dv_out. inside: the caller knows
 * (u, v) to be within rsm_tmap_read_reach of the origin on both axes, so
 * the range test can go (the map matcher checks that once per pass, not
 * once per point). w: the cursor's window, or one of the caller's own
 * (the map matcher's, which then stays in registers). Always inline: the
 * map matcher has two copies of its loop. */
static RSM_ALWAYS_INLINE float rsm_tmap_read_cells(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, rsm_tmap_window_t *w, float u,
                                        float v, int inside, float *du_out, float *dv_out)
{
    /* The floor by conversion: the range test comes first, so the
     * conversion cannot overflow. u in [1 - L, L - 1) is exactly
     * floor(u) > -L and floor(u) + 1 < L, the cells' range. */
    const float lim = (float)(RSM_TMAP_CELL_LIMIT - 1);
    const uint32_t mask = (uint32_t)RSM_TMAP_TILE_MASK;
    int32_t i;
    int32_t j;
    uint32_t ci;
    uint32_t cj;
    float du;
    float dv;
    float m00;
    float m10;
    float m01;
    float m11;
    float a;
    float b;
    float top;
    float bottom;
    if (!inside && !(u >= -lim && u < lim && v >= -lim && v < lim)) {
        *du_out = 0.0f;
        *dv_out = 0.0f;
        return 0.0f;
    }
    if (!RSM_SOFT_FLOAT || !rsm_tmap_split(u, &i, &du) || !rsm_tmap_split(v, &j, &dv)) {
        /* u - trunc(u) is exact, and so is its sum with 1 rounded once
         * as u - (trunc(u) - 1) is: the same bits as the difference from
         * floor(u), for fewer instructions. */
        i = (int32_t)u;
        j = (int32_t)v;
        du = u - (float)i;
        dv = v - (float)j;
        if (du < 0.0f) {
            --i;
            du += 1.0f;
        }
        if (dv < 0.0f) {
            --j;
            dv += 1.0f;
        }
    }
    rsm_tmap_window_place(map, c, w, i, j, &ci, &cj);
    if (ci < mask && cj < mask) {
        const uint32_t k = (cj << RSM_TMAP_TILE_LOG2) | ci;
        if (w->tile == NULL) {
            *du_out = 0.0f;
            *dv_out = 0.0f;
            return 0.0f;
        }
#if RSM_SOFT_FLOAT
        /* Four equal cells: the interpolation below gives their value and
         * a zero gradient exactly (no occupancy is -0), at a dozen calls
         * into libgcc. */
        {
            const uint32_t v00 = rsm_tmap_get_cell(w->tile, k);
            if (rsm_tmap_get_cell(w->tile, k + 1u) == v00 &&
                rsm_tmap_get_cell(w->tile, k + (uint32_t)RSM_TMAP_TILE_SIDE) == v00 &&
                rsm_tmap_get_cell(w->tile, k + (uint32_t)RSM_TMAP_TILE_SIDE + 1u) == v00) {
                *du_out = 0.0f;
                *dv_out = 0.0f;
                return map->occ[v00];
            }
        }
#endif
        rsm_tmap_occ_pair(map, w->tile, k, &m00, &m10);
        rsm_tmap_occ_pair(map, w->tile, k + (uint32_t)RSM_TMAP_TILE_SIDE, &m01, &m11);
    } else {
        float m[4];
        w->tile = rsm_tmap_straddle(map, c, ci <= mask && cj <= mask, w->tile, i, j, m);
        w->bx = (int32_t)((uint32_t)i & ~mask);
        w->by = (int32_t)((uint32_t)j & ~mask);
        m00 = m[0];
        m10 = m[1];
        m01 = m[2];
        m11 = m[3];
    }
    a = m10 - m00;
    b = m11 - m01;
#if RSM_SOFT_FLOAT
    /* A call saved for each zero difference (two equal cells), with the
     * float path's bits: no occupancy, difference or corner value is -0,
     * so x + 0 * t is x whatever the zero's sign. */
    top = rsm_tmap_bits(a) == 0u ? m00 : m00 + a * du;
    bottom = rsm_tmap_bits(b) == 0u ? m01 : m01 + b * du;
    *du_out = rsm_tmap_bits(a) == rsm_tmap_bits(b) ? a : a + (b - a) * dv;
    if (rsm_tmap_bits(top) == rsm_tmap_bits(bottom)) {
        *dv_out = 0.0f;
        return top;
    }
#else
    top = m00 + a * du;
    bottom = m01 + b * du;
    *du_out = a + (b - a) * dv;
#endif
    *dv_out = bottom - top;
    return top + (bottom - top) * dv;
}

/* rsm_tmap_sample_at (see tilemap.h); inside as for rsm_tmap_read_cells. */
static inline float rsm_tmap_read_sample(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, float x, float y, int inside,
                                         float *dx, float *dy)
{
    const float inv_a = map->inv_cell[c->level];
    const float m = rsm_tmap_read_cells(map, c, &c->win, x * inv_a - 0.5f, y * inv_a - 0.5f, inside, dx, dy);
    *dx *= inv_a;
    *dy *= inv_a;
    return m;
}

#if RSM_FIXED_MATCH
/* ---- fixed-point reads (RSM_FIXED_MATCH) ---------------------------------
 * The map matcher's reads without a float operation: a cell coordinate is
 * its floor and a fraction of RSM_TMAP_FIX_BITS bits, an occupancy and a
 * gradient per cell are in units of 2^-RSM_TMAP_FIX_BITS. With 15 bits
 * every product of the interpolation fits 32 bits (differences of two
 * occupancies up to 2^16, times a fraction below 2^15). */
#define RSM_TMAP_FIX_BITS 15
#define RSM_TMAP_FIX_ONE ((int32_t)1 << RSM_TMAP_FIX_BITS)
#define RSM_TMAP_FIX_HALF ((int32_t)1 << (RSM_TMAP_FIX_BITS - 1))

/* f 2^q rounded to the nearest integer, on f's bits (a few integer
 * instructions instead of a multiplication and a conversion, two calls
 * without an FPU): for |f| 2^q below 2^30, which the caller ensures; zeros
 * and subnormal numbers give 0. */
static inline int32_t rsm_tmap_fix(float f, uint32_t q)
{
    const uint32_t b = rsm_tmap_bits(f);
    const int32_t e = (int32_t)((b >> 23) & 0xFFu);
    const int32_t sh = e - 150 + (int32_t)q; /* |f| 2^q = m 2^sh */
    uint32_t m = (b & 0x7FFFFFu) | 0x800000u;
    if (e == 0) {
        return 0;
    }
    if (sh >= 0) {
        m <<= (uint32_t)sh;
    } else if (sh < -24) {
        return 0; /* below a half */
    } else {
        m = (m + (1u << (uint32_t)(-sh - 1))) >> (uint32_t)(-sh);
    }
    return (b >> 31) != 0u ? -(int32_t)m : (int32_t)m;
}

/* The occupancy of every cell value in units of 2^-RSM_TMAP_FIX_BITS
 * (the float table rounded: the same values as min(v, sat) 2^15 / sat). */
static inline void rsm_tmap_fix_occ(const rsm_tmap_t *map, int32_t occ[RSM_TMAP_MAX_VALUE + 1u])
{
    uint32_t v;
    for (v = 0; v <= RSM_TMAP_MAX_VALUE; ++v) {
        occ[v] = rsm_tmap_fix(map->occ[v], (uint32_t)RSM_TMAP_FIX_BITS);
    }
}

/* rsm_tmap_straddle with the cells' values, not their occupancies. */
const rsm_tile_t *rsm_tmap_straddle_values(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, int own, const rsm_tile_t *t,
                                           int32_t i, int32_t j, uint32_t v[4]);

/* rsm_tmap_read_cells in fixed point at (i + du 2^-15, j + dv 2^-15), du
 * and dv in [0, 2^15): the occupancy (0 to 2^15) and its gradient per cell
 * into *gu and *gv (each within +-2^15), rounded to the nearest unit. The
 * caller has checked that i, j, i + 1 and j + 1 are in the cells' range.
 * occ: rsm_tmap_fix_occ's table. The window logic is rsm_tmap_read_cells'
 * (kept apart so that the float build's code stays as it was). */
static RSM_ALWAYS_INLINE int32_t rsm_tmap_read_fixed(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, rsm_tmap_window_t *w,
                                                     const int32_t *occ, int32_t i, int32_t j, int32_t du, int32_t dv,
                                                     int32_t *gu, int32_t *gv)
{
    const uint32_t mask = (uint32_t)RSM_TMAP_TILE_MASK;
    uint32_t ci;
    uint32_t cj;
    int32_t m00;
    int32_t m10;
    int32_t m01;
    int32_t m11;
    int32_t a;
    int32_t b;
    int32_t top;
    int32_t bottom;
    rsm_tmap_window_place(map, c, w, i, j, &ci, &cj);
    if (ci < mask && cj < mask) {
        const uint32_t k = (cj << RSM_TMAP_TILE_LOG2) | ci;
        uint32_t v00;
        uint32_t v10;
        uint32_t v01;
        uint32_t v11;
        if (w->tile == NULL) {
            *gu = 0;
            *gv = 0;
            return 0;
        }
        v00 = rsm_tmap_get_cell(w->tile, k);
        v10 = rsm_tmap_get_cell(w->tile, k + 1u);
        v01 = rsm_tmap_get_cell(w->tile, k + (uint32_t)RSM_TMAP_TILE_SIDE);
        v11 = rsm_tmap_get_cell(w->tile, k + (uint32_t)RSM_TMAP_TILE_SIDE + 1u);
        if (v00 == v10 && v00 == v01 && v00 == v11) {
            *gu = 0; /* most reads: four equal cells */
            *gv = 0;
            return occ[v00];
        }
        m00 = occ[v00];
        m10 = occ[v10];
        m01 = occ[v01];
        m11 = occ[v11];
    } else {
        uint32_t v[4];
        w->tile = rsm_tmap_straddle_values(map, c, ci <= mask && cj <= mask, w->tile, i, j, v);
        w->bx = (int32_t)((uint32_t)i & ~mask);
        w->by = (int32_t)((uint32_t)j & ~mask);
        m00 = occ[v[0]];
        m10 = occ[v[1]];
        m01 = occ[v[2]];
        m11 = occ[v[3]];
    }
    /* Right shifts of negative products: arithmetic on every compiler rsm
     * supports (as the tile coordinates' shifts above assume). */
    a = m10 - m00;
    b = m11 - m01;
    top = m00 + ((a * du + RSM_TMAP_FIX_HALF) >> RSM_TMAP_FIX_BITS);
    bottom = m01 + ((b * du + RSM_TMAP_FIX_HALF) >> RSM_TMAP_FIX_BITS);
    *gu = a + (((b - a) * dv + RSM_TMAP_FIX_HALF) >> RSM_TMAP_FIX_BITS);
    *gv = bottom - top;
    return top + (((bottom - top) * dv + RSM_TMAP_FIX_HALF) >> RSM_TMAP_FIX_BITS);
}
#endif /* RSM_FIXED_MATCH */

#endif /* RSM_TMAP_READ_H */
