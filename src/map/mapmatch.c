/* Coarse-to-fine Gauss-Newton of a scan against the tile map with the
 * prediction as a prior; see src/map/mapmatch.h. */
#include "core/hot.h" /* first: speed over size */
#include "map/mapmatch.h"

#include <math.h>
#include <string.h>

#include "core/ekf.h"
#include "rsm/status.h"
#include "core/compiler.h"
#include "core/fmath.h"
#include "map/tmap_read.h"
#include "map/mapmatch_fixed.h"

/* Smallest prior variance used, so that a filter that starts with a zero
 * covariance still has an invertible prior (m^2 and rad^2). */
#define PRIOR_FLOOR 1.0e-8f

rsm_mapmatch_config_t rsm_mapmatch_config_default(void)
{
    rsm_mapmatch_config_t c;
    c.iterations = 6u;
    c.sigma = 0.3f;
    c.min_step_m = 0.002f;
    c.min_step_rad = 0.001f;
    c.search_rad = 0.1f;
    c.search_step_rad = 0.02f;
    c.fan = 0u;
    c.gate_d2 = 0.0f;
    c.basin = 3.0f;
    c.unpin_lo = 0.02f;
    c.unpin_hi = 0.06f;
    return c;
}

int rsm_mapmatch_check(const rsm_mapmatch_config_t *cfg)
{
    if (cfg == NULL || cfg->iterations < 1u || !(cfg->sigma > 0.0f) || !(cfg->min_step_m >= 0.0f) ||
        !(cfg->min_step_rad >= 0.0f) || !(cfg->search_rad >= 0.0f) || !(cfg->search_rad <= 1.0f) ||
        !(cfg->gate_d2 >= 0.0f) || !(cfg->basin >= 0.0f) || !(cfg->unpin_lo >= 0.0f) ||
        !(cfg->unpin_hi <= 1.0f) || !(cfg->unpin_hi == 0.0f || cfg->unpin_hi > cfg->unpin_lo) ||
        (cfg->search_rad > 0.0f && !(cfg->search_step_rad > 0.0f && cfg->search_rad <= 64.0f * cfg->search_step_rad))) {
        return RSM_ERR_INVAL;
    }
    return RSM_OK;
}

/* Sums of one level at pose x: h (upper triangle of J^T J, order 00 01 02 11
 * 12 22), b = J^T r, cost = sum r^2 over all points, used = points with a
 * gradient, hit = sum of M. The fixed-point pass's struct where it runs. */
typedef rsm_fixed_sums_t sums_t;

/* The largest |x| + |y| of the points (a bound on how far from the pose
 * any of them lands, whatever the heading); NaN if one is not finite. Their
 * mean in *mean (0 for none). */
static float points_reach(const rsm_point_t *pts, size_t n, float *mean)
{
    float reach = 0.0f;
    float sum = 0.0f;
    size_t k;
    for (k = 0; k < n; ++k) {
        const float a = fabsf(pts[k].x) + fabsf(pts[k].y);
        sum += a;
        if (!(a <= reach)) {
            reach = a;
        }
    }
    *mean = n > 0u ? sum / (float)n : 0.0f;
    return reach;
}

/* The pass of level_sums over the points at the pose (c, sn, tu, tv) in
 * the level's cells: the sums per cell into s. Copied into each of its two
 * calls, so that inside is a constant in each loop, not a test per point. */
static RSM_ALWAYS_INLINE void sums_pass(const rsm_tmap_t *map, uint32_t level, const rsm_point_t *pts, size_t n,
                                        float c, float sn, float tu, float tv, int inside, sums_t *s)
{
    /* Sums in locals: through s the compiler would store each one per
     * point, not knowing that s does not alias the points. */
    float h0 = 0.0f;
    float h1 = 0.0f;
    float h2 = 0.0f;
    float h3 = 0.0f;
    float h4 = 0.0f;
    float h5 = 0.0f;
    float b0 = 0.0f;
    float b1 = 0.0f;
    float b2 = 0.0f;
    float cost = 0.0f;
    float cost_used = 0.0f;
    float hit = 0.0f;
    size_t unused = 0; /* counted where it is rare: a register fewer in the loop */
    rsm_tmap_cursor_t cur;
    rsm_tmap_window_t win; /* the cursor's, but never seen outside: kept in registers */
    const rsm_point_t *p;
    rsm_tmap_cursor_init(&cur, level);
    rsm_tmap_window_forget(&win);
    for (p = pts; p != pts + n; ++p) {
        const float cx = c * p->x;
        const float sy = sn * p->y;
        const float sx = sn * p->x;
        const float cy = c * p->y;
        /* With an FPU, gt's factors before the read: two values live across
         * its calls (the rare lookups), not four. Without, each is a call,
         * made only where the tests below do not skip it. */
        const float dtu = RSM_SOFT_FLOAT ? 0.0f : cx - sy;
        const float dtv = RSM_SOFT_FLOAT ? 0.0f : sx + cy;
        float gu;
        float gv;
        const float m = rsm_tmap_read_cells(map, &cur, &win, tu + cx - sy, tv + sx + cy, inside, &gu, &gv);
        const float r = 1.0f - m;
        float gt;
        int zu;
        int zv;
        cost += r * r;
        hit += m;
        if (rsm_tmap_flat(gu, gv)) {
            ++unused;
            continue;
        }
        /* Without an FPU each product is a call: a zero component of the
         * gradient adds only zeros to its sums, which are never -0 (they
         * start at +0, and a sum is -0 only of two), so those are left out
         * with the same bits; gt's sign, when it is zero, matters nowhere.
         * With an FPU the tests cost more than they save: zu and zv are 0. */
        zu = RSM_SOFT_FLOAT && rsm_tmap_is_zero(gu);
        zv = RSM_SOFT_FLOAT && rsm_tmap_is_zero(gv);
        /* d(cell)/d(theta) = (-s px - c py, c px - s py) / cell. With an
         * FPU, gu (-sx - cy) + gv (cx - sy) with the negation moved out:
         * the same rounding of the same value (but a zero's sign). */
        if (RSM_SOFT_FLOAT) {
            gt = zu ? gv * (cx - sy) : zv ? gu * (-sx - cy) : gu * (-sx - cy) + gv * (cx - sy);
        } else {
            gt = gv * dtu - gu * dtv;
        }
        if (!zu) {
            h0 += gu * gu;
            h2 += gu * gt;
            b0 += gu * r;
        }
        if (!zv) {
            h3 += gv * gv;
            h4 += gv * gt;
            b1 += gv * r;
        }
        if (!zu && !zv) {
            h1 += gu * gv;
        }
        h5 += gt * gt;
        b2 += gt * r;
        cost_used += r * r;
    }
    s->h[0] = h0;
    s->h[1] = h1;
    s->h[2] = h2;
    s->h[3] = h3;
    s->h[4] = h4;
    s->h[5] = h5;
    s->b[0] = b0;
    s->b[1] = b1;
    s->b[2] = b2;
    s->cost = cost;
    s->cost_used = cost_used;
    s->hit = hit;
    s->used = (uint32_t)(n - unused);
}

/* The fixed-point pass where it is built (RSM_FIXED_MATCH): 1 when it ran;
 * 0 in the float build, where the compiler drops the test. */
#if RSM_FIXED_MATCH
#define FIXED_PASS(map, level, pts, n, reach, inv_a, c, sn, tu, tv, inside, s) \
    rsm_matchfix_pass(map, level, pts, n, reach, inv_a, c, sn, tu, tv, inside, s)
#else
#define FIXED_PASS(map, level, pts, n, reach, inv_a, c, sn, tu, tv, inside, s) 0
#endif

/* reach: points_reach of pts. The points are placed and read in the
 * level's cells (gradients per cell, scaled to metres once at the end):
 * that is four multiplications and two subtractions a point fewer than in
 * metres. */
static void level_sums(const rsm_tmap_t *map, uint32_t level, const rsm_point_t *pts, size_t n, float reach,
                       const rsm_pose_t *x, sums_t *s)
{
    const float inv_a = map->inv_cell[level];
    const float tu = x->x * inv_a - 0.5f;
    const float tv = x->y * inv_a - 0.5f;
    const float most = rsm_tmap_read_reach(map);
    float c;
    float sn;
    rsm_sincosf(x->theta, &sn, &c);
    c *= inv_a;
    sn *= inv_a;
    if (FIXED_PASS(map, level, pts, n, reach, inv_a, c, sn, tu, tv,
                   fabsf(x->x) + reach < most && fabsf(x->y) + reach < most, s)) {
        /* In fixed point (RSM_FIXED_MATCH): the float pass only where the
         * points or the pose are out of the integers' range. */
    } else if (fabsf(x->x) + reach < most && fabsf(x->y) + reach < most) {
        /* Every point within the map's range: no range test per point. */
        sums_pass(map, level, pts, n, c, sn, tu, tv, 1, s);
    } else {
        sums_pass(map, level, pts, n, c, sn, tu, tv, 0, s);
    }
    s->h[0] *= inv_a * inv_a;
    s->h[1] *= inv_a * inv_a;
    s->h[2] *= inv_a;
    s->h[3] *= inv_a * inv_a;
    s->h[4] *= inv_a;
    s->b[0] *= inv_a;
    s->b[1] *= inv_a;
}

/* Sum of (1 - M)^2 over every stride-th point at pose x on a level, each
 * read at its nearest cell centre (no interpolation: a coarse score). */
static float coarse_cost(const rsm_tmap_t *map, uint32_t level, const rsm_point_t *pts, size_t n, size_t stride,
                         const rsm_pose_t *x)
{
    float c;
    float sn;
    float cost = 0.0f;
    rsm_tmap_cursor_t cur;
    size_t k;
    rsm_sincosf(x->theta, &sn, &c);
    rsm_tmap_cursor_init(&cur, level);
    for (k = 0; k < n; k += stride) {
        const float wx = x->x + c * pts[k].x - sn * pts[k].y;
        const float wy = x->y + sn * pts[k].x + c * pts[k].y;
        const float r = 1.0f - rsm_tmap_occupancy_at(map, &cur, wx, wy);
        cost += r * r;
    }
    return cost;
}

/* The heading of the fan around x0 with the lowest coarse cost plus the
 * prior's heading term (lam_tt = P0^-1's heading entry). */
static float best_heading(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts, size_t n,
                          const rsm_pose_t *x0, float w, float lam_tt)
{
    const uint32_t level = (uint32_t)map->cfg.levels - 1u;
    const int32_t half = (int32_t)(cfg->search_rad / cfg->search_step_rad);
    float best = x0->theta;
    float best_cost = 0.0f;
    int32_t k;
    for (k = -half; k <= half; ++k) {
        const float d = (float)k * cfg->search_step_rad;
        rsm_pose_t x = *x0;
        float f;
        x.theta = rsm_wrap_angle(x0->theta + d);
        f = coarse_cost(map, level, pts, n, 1u, &x) * w + d * d * lam_tt;
        if (k == -half || f < best_cost) {
            best_cost = f;
            best = x.theta;
        }
    }
    return best;
}

static void diff(const rsm_pose_t *x, const rsm_pose_t *x0, float e[3])
{
    e[0] = x->x - x0->x;
    e[1] = x->y - x0->y;
    e[2] = rsm_wrap_angle(x->theta - x0->theta);
}

static float quad(const float m[9], const float e[3])
{
    float q = 0.0f;
    int i;
    int j;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) {
            q += e[i] * m[i * 3 + j] * e[j];
        }
    }
    return q;
}

static void full(const float h[6], float w, float out[9])
{
    out[0] = h[0] * w;
    out[1] = h[1] * w;
    out[2] = h[2] * w;
    out[3] = out[1];
    out[4] = h[3] * w;
    out[5] = h[4] * w;
    out[6] = out[2];
    out[7] = out[5];
    out[8] = h[5] * w;
}

/* Puts a candidate into the list of the k best (ascending cost) unless a
 * better one lies within one grid step of it; worse ones that close give
 * up their places. No two kept ones are that close: the list holds k
 * separate basins, not one basin's neighbours. */
static void keep_candidate(rsm_pose_t *best, float *cost, int32_t *ij, size_t k, size_t *found, const rsm_pose_t *x,
                           float c, int32_t i, int32_t j)
{
    size_t m;
    size_t kept = 0;
    size_t at;
    for (m = 0; m < *found; ++m) {
        const int32_t di = ij[2 * m] - i;
        const int32_t dj = ij[2 * m + 1u] - j;
        if (di >= -1 && di <= 1 && dj >= -1 && dj <= 1 && cost[m] <= c) {
            return;
        }
    }
    for (m = 0; m < *found; ++m) {
        const int32_t di = ij[2 * m] - i;
        const int32_t dj = ij[2 * m + 1u] - j;
        if (!(di >= -1 && di <= 1 && dj >= -1 && dj <= 1)) {
            best[kept] = best[m];
            cost[kept] = cost[m];
            ij[2 * kept] = ij[2 * m];
            ij[2 * kept + 1u] = ij[2 * m + 1u];
            ++kept;
        }
    }
    if (kept == k) {
        if (!(c < cost[k - 1u])) {
            *found = kept;
            return;
        }
        --kept;
    }
    for (at = kept; at > 0u && cost[at - 1u] > c; --at) {
        best[at] = best[at - 1u];
        cost[at] = cost[at - 1u];
        ij[2 * at] = ij[2 * at - 2u];
        ij[2 * at + 1u] = ij[2 * at - 1u];
    }
    best[at] = *x;
    cost[at] = c;
    ij[2 * at] = i;
    ij[2 * at + 1u] = j;
    *found = kept + 1u;
}

/* Candidates a side of the window whose costs search_heading sums point by
 * point: each point's cells for every candidate lie in at most four tiles
 * (2 RSM_MAPMATCH_BLOCK_HALF + 1 <= the tile side). */
#define RSM_MAPMATCH_BLOCK_HALF 3
typedef char rsm_mapmatch_block_fits[(2 * RSM_MAPMATCH_BLOCK_HALF + 1 <= RSM_TMAP_TILE_SIDE) ? 1 : -1];
#define BLOCK_SIDE (2 * RSM_MAPMATCH_BLOCK_HALF + 1)

/* Adds to the rows of cost[] from row (side floats apart) what the cells
 * (x0 .. x1, y0 .. y1) of the tile in slot cost, the first at row[0]:
 * cells that lie in one tile, each row read from its first cell on. */
static void add_cells(const rsm_tmap_t *map, uint32_t slot, int32_t x0, int32_t y0, int32_t x1, int32_t y1,
                      int32_t side, const float *miss, float *row)
{
    const uint32_t len = (uint32_t)(x1 - x0) + 1u;
    uint32_t u;
    int32_t w;
    for (w = y0; w <= y1; ++w, row += side) {
        if (slot == RSM_TMAP_NONE) {
            for (u = 0; u < len; ++u) {
                row[u] += miss[0];
            }
        } else {
            const rsm_tile_t *t = &map->tile[slot];
            const uint32_t at = rsm_tmap_cell_index(x0, w);
            for (u = 0; u < len; ++u) {
                row[u] += miss[rsm_tmap_get_cell(t, at + u)];
            }
        }
    }
}

/* Adds to cost[] (the candidates i, j = -half .. half, row-major) what the
 * point at cell (gx, gy) of x0 costs each: the cell moved i, j, read tile
 * by tile (at most four) rather than looked up per candidate. The whole
 * block lies within the map's reach. */
static void add_block(const rsm_tmap_t *map, rsm_tmap_cursor_t *cur, int32_t gx, int32_t gy, int32_t half,
                      const float *miss, float *cost)
{
    const int32_t side = 2 * half + 1;
    int32_t y0 = gy - half;
    if (((gx - half) ^ (gx + half)) >> RSM_TMAP_TILE_LOG2 == 0 &&
        ((gy - half) ^ (gy + half)) >> RSM_TMAP_TILE_LOG2 == 0) {
        /* Within one tile (most blocks at a coarse cell's reach): one
         * lookup, without the walk over tiles below. */
        add_cells(map, rsm_tmap_cursor_slot(map, cur, gx, gy), gx - half, gy - half, gx + half, gy + half, side,
                  miss, cost);
        return;
    }
    while (y0 <= gy + half) {
        /* The rows of this tile row. */
        const int32_t y1 =
            (y0 | (int32_t)RSM_TMAP_TILE_MASK) < gy + half ? (y0 | (int32_t)RSM_TMAP_TILE_MASK) : gy + half;
        int32_t x0 = gx - half;
        while (x0 <= gx + half) {
            const int32_t x1 =
                (x0 | (int32_t)RSM_TMAP_TILE_MASK) < gx + half ? (x0 | (int32_t)RSM_TMAP_TILE_MASK) : gx + half;
            add_cells(map, rsm_tmap_cursor_slot(map, cur, x0, y0), x0, y0, x1, y1, side, miss,
                      &cost[(y0 - gy + half) * side + x0 - gx + half]);
            x0 = x1 + 1;
        }
        y0 = y1 + 1;
    }
}

/* The values of cells x0, x0 + 1 and x0 + 2 of row y in nibbles 0, 1 and
 * 2 (higher bits are left over): two bytes read at once where the three
 * lie in one tile (a row's nibbles lie in its bytes in order), else cell by
 * cell; 0 where no tile is held. */
static RSM_ALWAYS_INLINE uint32_t row3(const rsm_tmap_t *map, rsm_tmap_cursor_t *cur, int32_t x0, int32_t y)
{
    const uint32_t s = rsm_tmap_cursor_slot(map, cur, x0, y);
    if (((x0 ^ (x0 + 2)) >> RSM_TMAP_TILE_LOG2) == 0) {
        const uint8_t *b;
        if (s == RSM_TMAP_NONE) {
            return 0u;
        }
        b = &map->tile[s].cell[rsm_tmap_cell_index(x0, y) >> 1];
        return ((uint32_t)b[0] | ((uint32_t)b[1] << 8)) >> (((uint32_t)x0 & 1u) << 2);
    }
    {
        const uint32_t s2 = rsm_tmap_cursor_slot(map, cur, x0 + 2, y);
        const uint32_t s1 = ((x0 ^ (x0 + 1)) >> RSM_TMAP_TILE_LOG2) == 0 ? s : s2;
        return rsm_tmap_slot_value(map, s, x0, y) | (rsm_tmap_slot_value(map, s1, x0 + 1, y) << 4) |
               (rsm_tmap_slot_value(map, s2, x0 + 2, y) << 8);
    }
}

/* Adds the costs of the three cells of row3's word w to a[0..2]. */
static RSM_ALWAYS_INLINE void add_row3(float *a, const float *miss, uint32_t w)
{
    a[0] += miss[w & 15u];
    a[1] += miss[(w >> 4) & 15u];
    a[2] += miss[(w >> 8) & 15u];
}

/* search_heading's sums for a window of 3 x 3 candidates (a recovery's
 * first search, within one coarse cell: the common one), into cost[0..8]:
 * the same sums in the same order as add_block's, each point's three rows
 * read as three words and the nine sums kept in registers, not in memory
 * (on the M4 the search of ACES's costliest recovery scan took 0.37
 * million instructions where the general path took 0.66). Every index of
 * a[] is a constant, so that the compiler keeps it in registers. */
static void search_window3(const rsm_tmap_t *map, rsm_tmap_cursor_t *cur, const rsm_point_t *pts, size_t n,
                           size_t stride, const rsm_pose_t *x0, float c, float sn, float inv, float step,
                           const float *miss, float *cost)
{
    const int32_t lim = RSM_TMAP_CELL_LIMIT - 2;
    /* In locals: the calls into tilemap.c could change *x0 for all the
     * compiler knows. */
    const float ox = x0->x;
    const float oy = x0->y;
    float a[9] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    size_t q;
    for (q = 0; q < n; q += stride) {
        const int32_t gx = rsm_tmap_cell_of(ox + c * pts[q].x - sn * pts[q].y, inv);
        const int32_t gy = rsm_tmap_cell_of(oy + sn * pts[q].x + c * pts[q].y, inv);
        if (gx > -lim && gx < lim && gy > -lim && gy < lim) {
            if ((((gx - 1) ^ (gx + 1)) >> RSM_TMAP_TILE_LOG2) == 0 &&
                (((gy - 1) ^ (gy + 1)) >> RSM_TMAP_TILE_LOG2) == 0) {
                /* The block in one tile (most of them): one lookup, and
                 * the rows a row's bytes apart. */
                const uint32_t s = rsm_tmap_cursor_slot(map, cur, gx, gy);
                if (s != RSM_TMAP_NONE) {
                    const uint8_t *b = &map->tile[s].cell[rsm_tmap_cell_index(gx - 1, gy - 1) >> 1];
                    const uint32_t sh = ((uint32_t)(gx - 1) & 1u) << 2;
                    const uint32_t rb = (uint32_t)RSM_TMAP_TILE_SIDE / 2u;
                    add_row3(&a[0], miss, ((uint32_t)b[0] | ((uint32_t)b[1] << 8)) >> sh);
                    add_row3(&a[3], miss, ((uint32_t)b[rb] | ((uint32_t)b[rb + 1u] << 8)) >> sh);
                    add_row3(&a[6], miss, ((uint32_t)b[2u * rb] | ((uint32_t)b[2u * rb + 1u] << 8)) >> sh);
                } else {
                    add_row3(&a[0], miss, 0u);
                    add_row3(&a[3], miss, 0u);
                    add_row3(&a[6], miss, 0u);
                }
            } else {
                add_row3(&a[0], miss, row3(map, cur, gx - 1, gy - 1));
                add_row3(&a[3], miss, row3(map, cur, gx - 1, gy));
                add_row3(&a[6], miss, row3(map, cur, gx - 1, gy + 1));
            }
        } else {
            float p[9];
            int32_t i;
            int32_t j;
            for (j = -1; j <= 1; ++j) {
                for (i = -1; i <= 1; ++i) {
                    const float wx0 = ox + (float)i * step;
                    const float wy0 = oy + (float)j * step;
                    const float r = 1.0f - rsm_tmap_occupancy_at(map, cur, wx0 + c * pts[q].x - sn * pts[q].y,
                                                                 wy0 + sn * pts[q].x + c * pts[q].y);
                    p[(j + 1) * 3 + i + 1] = r * r;
                }
            }
            a[0] += p[0];
            a[1] += p[1];
            a[2] += p[2];
            a[3] += p[3];
            a[4] += p[4];
            a[5] += p[5];
            a[6] += p[6];
            a[7] += p[7];
            a[8] += p[8];
        }
    }
    memcpy(cost, a, sizeof a);
}

/* The coarse costs of one heading's candidates (x0 moved i, j cells of the
 * level, at x's heading), each kept or not as rsm_mapmatch_search goes.
 * A point's cell is found once for the heading, at x0; a candidate's is
 * that cell moved i, j: coarse_cost's sum over the same cells in the same
 * order, without a coordinate transform and a cell search per point and
 * candidate (on the M4 the search of a recovery cost 1 to 2 million
 * instructions). A small window's costs are summed point by point, a
 * point's cells read tile by tile (a window of 3 x 3, a row at a time:
 * search_window3). A point whose block of cells is not all within the
 * map's reach is looked up as coarse_cost does. */
static void search_heading(const rsm_tmap_t *map, uint32_t level, const rsm_point_t *pts, size_t n, size_t stride,
                           const rsm_pose_t *x0, rsm_pose_t *x, int32_t half, const float *miss, rsm_pose_t *best,
                           float *cost_of, int32_t *ij, size_t k, size_t *found)
{
    const float inv = map->inv_cell[level];
    const float step = rsm_tmap_cell(map, level);
    const int32_t side = 2 * half + 1;
    const int32_t lim = RSM_TMAP_CELL_LIMIT - 1 - half;
    float cost[BLOCK_SIDE * BLOCK_SIDE];
    float c;
    float sn;
    size_t q;
    int32_t i;
    int32_t j;
    rsm_tmap_cursor_t cur;
    rsm_sincosf(x->theta, &sn, &c);
    rsm_tmap_cursor_init(&cur, level);
    if (half == 1) {
        search_window3(map, &cur, pts, n, stride, x0, c, sn, inv, step, miss, cost);
    } else if (half <= RSM_MAPMATCH_BLOCK_HALF) {
        memset(cost, 0, sizeof cost);
        for (q = 0; q < n; q += stride) {
            const int32_t gx = rsm_tmap_cell_of(x0->x + c * pts[q].x - sn * pts[q].y, inv);
            const int32_t gy = rsm_tmap_cell_of(x0->y + sn * pts[q].x + c * pts[q].y, inv);
            if (gx > -lim && gx < lim && gy > -lim && gy < lim) {
                add_block(map, &cur, gx, gy, half, miss, cost);
                continue;
            }
            for (j = -half; j <= half; ++j) {
                for (i = -half; i <= half; ++i) {
                    const float wx0 = x0->x + (float)i * step;
                    const float wy0 = x0->y + (float)j * step;
                    const float r = 1.0f - rsm_tmap_occupancy_at(map, &cur, wx0 + c * pts[q].x - sn * pts[q].y,
                                                                 wy0 + sn * pts[q].x + c * pts[q].y);
                    cost[(j + half) * side + i + half] += r * r;
                }
            }
        }
    }
    if (half <= RSM_MAPMATCH_BLOCK_HALF) {
        for (j = -half; j <= half; ++j) {
            for (i = -half; i <= half; ++i) {
                x->x = x0->x + (float)i * step;
                x->y = x0->y + (float)j * step;
                keep_candidate(best, cost_of, ij, k, found, x, cost[(j + half) * side + i + half], i, j);
            }
        }
        return;
    }
    for (j = -half; j <= half; ++j) {
        for (i = -half; i <= half; ++i) {
            x->x = x0->x + (float)i * step;
            x->y = x0->y + (float)j * step;
            keep_candidate(best, cost_of, ij, k, found, x, coarse_cost(map, level, pts, n, stride, x), i, j);
        }
    }
}

int rsm_mapmatch_search_size(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, float radius_m,
                             float radius_rad, int32_t *fan, uint32_t *positions)
{
    float step;
    int32_t half;
    /* The radii are checked before they are converted to counts. */
    if (map == NULL || cfg == NULL || fan == NULL || positions == NULL) {
        return RSM_ERR_INVAL;
    }
    step = rsm_tmap_cell(map, (uint32_t)map->cfg.levels - 1u);
    if (!(radius_m >= 0.0f) || radius_m > 100.0f * step || !(radius_rad >= 0.0f) || radius_rad > 1.0f ||
        (radius_rad > 0.0f && !(radius_rad <= 64.0f * cfg->search_step_rad))) {
        return RSM_ERR_INVAL;
    }
    half = (int32_t)(radius_m / step);
    *fan = cfg->search_step_rad > 0.0f ? (int32_t)(radius_rad / cfg->search_step_rad) : 0;
    *positions = (uint32_t)((2 * half + 1) * (2 * half + 1));
    return RSM_OK;
}

int rsm_mapmatch_search_part(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts,
                             size_t n, const rsm_pose_t *x0, float radius_m, float radius_rad, int32_t from,
                             int32_t to, rsm_pose_t *best, float *cost_of, int32_t *ij, size_t k, size_t *found,
                             size_t max_points)
{
    /* Every stride-th point: the score only ranks candidates. */
    const size_t most = max_points > 0u ? max_points : 1u;
    const size_t stride = n > most ? (n + most - 1u) / most : 1u;
    uint32_t level;
    uint32_t positions;
    int32_t half;
    int32_t fan;
    int32_t a;
    /* Everything is checked before map or cfg is read. */
    if (map == NULL || cfg == NULL || (n > 0u && pts == NULL) || x0 == NULL || best == NULL || cost_of == NULL ||
        ij == NULL || found == NULL || k < 1u || k > RSM_MAPMATCH_MAX_CANDIDATES || *found > k || max_points < 1u ||
        max_points > RSM_MAPMATCH_SEARCH_POINTS ||
        rsm_mapmatch_search_size(map, cfg, radius_m, radius_rad, &fan, &positions) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    level = (uint32_t)map->cfg.levels - 1u;
    half = (int32_t)(radius_m / rsm_tmap_cell(map, level));
    from = from < -fan ? -fan : from;
    to = to > fan + 1 ? fan + 1 : to;
    {
        /* (1 - occupancy)^2 of each cell value, as coarse_cost sums it. */
        float miss[RSM_TMAP_MAX_VALUE + 1u];
        uint32_t v;
        for (v = 0; v <= RSM_TMAP_MAX_VALUE; ++v) {
            const float r = 1.0f - map->occ[v];
            miss[v] = r * r;
        }
        for (a = from; a < to; ++a) {
            rsm_pose_t x;
            x.theta = rsm_wrap_angle(x0->theta + (float)a * cfg->search_step_rad);
            search_heading(map, level, pts, n, stride, x0, &x, half, miss, best, cost_of, ij, k, found);
        }
    }
    return (int)*found;
}

int rsm_mapmatch_search(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts, size_t n,
                        const rsm_pose_t *x0, float radius_m, float radius_rad, rsm_pose_t *best, size_t k,
                        size_t max_points)
{
    float cost_of[RSM_MAPMATCH_MAX_CANDIDATES];
    int32_t ij[2 * RSM_MAPMATCH_MAX_CANDIDATES];
    size_t found = 0;
    return rsm_mapmatch_search_part(map, cfg, pts, n, x0, radius_m, radius_rad, -RSM_MAPMATCH_MAX_FAN,
                                    RSM_MAPMATCH_MAX_FAN + 1, best, cost_of, ij, k, &found, max_points);
}

float rsm_mapmatch_fit(const rsm_tmap_t *map, const rsm_point_t *pts, size_t n, const rsm_pose_t *pose)
{
    sums_t s;
    float mean;
    if (map == NULL || pts == NULL || pose == NULL || n == 0u) {
        return 0.0f;
    }
    level_sums(map, 0u, pts, n, points_reach(pts, n, &mean), pose, &s);
    return s.hit / (float)n;
}

float rsm_mapmatch_wall_share(const rsm_tmap_t *map, const rsm_point_t *pts, size_t n, const rsm_pose_t *pose,
                              uint32_t wall)
{
    float inv_a;
    float half;
    float c;
    float sn;
    size_t k;
    size_t on = 0;
    if (map == NULL || pts == NULL || pose == NULL || n == 0u) {
        return 0.0f;
    }
    inv_a = map->inv_cell[0];
    half = 0.5f / inv_a; /* cell centres at whole cells: the four around a point start half a cell back */
    rsm_sincosf(pose->theta, &sn, &c);
    for (k = 0; k < n; ++k) {
        const float wx = pose->x + c * pts[k].x - sn * pts[k].y;
        const float wy = pose->y + sn * pts[k].x + c * pts[k].y;
        /* Out of the cells' range (or not finite) rsm_tmap_cell_of gives
         * a cell the window reads as empty. */
        if (rsm_tmap_window_max(map, 0u, rsm_tmap_cell_of(wx - half, inv_a), rsm_tmap_cell_of(wy - half, inv_a)) >=
            wall) {
            ++on;
        }
    }
    return (float)on / (float)n;
}

/* The prior of a descent: its mean, information and the residual weight;
 * and how far the scan reaches. */
typedef struct prior {
    const rsm_pose_t *x0;
    float lam[9];
    float w;
    float reach; /* points_reach of the scan */
    int top;     /* the level the descent starts on */
    const rsm_mapmatch_unpin_t *unpin; /* or NULL */
} prior_t;

/* m <- P m P for a symmetric 3 x 3 m (row-major), P = I - frac d d^T with
 * d = (un->dir, 0): what is left of m once frac of it along the world
 * direction d is taken out. */
static void unpin_matrix(float m[9], const rsm_mapmatch_unpin_t *un)
{
    const float a = un->frac;
    const float d[3] = {un->dir[0], un->dir[1], 0.0f};
    float u[3]; /* m d */
    float sd;
    int i;
    int j;
    for (i = 0; i < 3; ++i) {
        u[i] = m[i * 3] * d[0] + m[i * 3 + 1] * d[1];
    }
    sd = u[0] * d[0] + u[1] * d[1];
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) {
            m[i * 3 + j] += a * (a * sd * d[i] * d[j] - d[i] * u[j] - u[i] * d[j]);
        }
    }
}

/* The larger of the prior's x and y variances. The descent does not look
 * along an unpinned direction, however uncertain the prediction is there:
 * with un, those of P p0 P (unpin_matrix). */
static float position_variance(const float p0[9], const rsm_mapmatch_unpin_t *un)
{
    float p[9];
    memcpy(p, p0, sizeof p);
    if (un != NULL && un->frac > 0.0f) {
        unpin_matrix(p, un);
    }
    return p[0] > p[4] ? p[0] : p[4];
}

/* The coarsest level the descent needs: the one whose cell is at least
 * cfg->basin times how far the prior's one-sigma error moves a point at
 * the scan's mean range (every level when basin is 0). */
static int start_level(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, const float p0[9], float mean,
                       const rsm_mapmatch_unpin_t *un)
{
    const int coarsest = (int)map->cfg.levels - 1;
    const float sp = sqrtf(position_variance(p0, un));
    const float need = cfg->basin * (sp + sqrtf(p0[8]) * mean);
    int level = 0;
    if (!(cfg->basin > 0.0f) || !(need < rsm_tmap_cell(map, (uint32_t)coarsest))) {
        return coarsest;
    }
    while (level < coarsest && rsm_tmap_cell(map, (uint32_t)level) < need) {
        ++level;
    }
    return level;
}

/* Whether a step is too small to matter on a level: coarser levels only
 * place the next one, so their thresholds grow with their cells. */
static int small_step(const rsm_mapmatch_config_t *cfg, const float step[3], int level)
{
    const float scale = (float)(1u << (uint32_t)level);
    return fabsf(step[0]) < cfg->min_step_m * scale && fabsf(step[1]) < cfg->min_step_m * scale &&
           fabsf(step[2]) < cfg->min_step_rad * scale;
}

/* Takes the fraction un->frac of the sums' pull along the world direction
 * d = (un->dir, 0) out: H <- P H P and b <- P b with P = I - frac d d^T.
 * The heading keeps what the points' moves along d tell of it. */
static void unpin_sums(sums_t *s, const rsm_mapmatch_unpin_t *un)
{
    float hf[9];
    float bd;
    int i;
    if (un == NULL || !(un->frac > 0.0f)) {
        return;
    }
    full(s->h, 1.0f, hf);
    unpin_matrix(hf, un);
    bd = s->b[0] * un->dir[0] + s->b[1] * un->dir[1];
    for (i = 0; i < 2; ++i) {
        s->b[i] -= un->frac * un->dir[i] * bd;
    }
    s->h[0] = hf[0];
    s->h[1] = hf[1];
    s->h[2] = hf[2];
    s->h[3] = hf[4];
    s->h[4] = hf[5];
    s->h[5] = hf[8];
}

/* Gauss-Newton from x on every level, coarse to fine. On return x is the
 * estimate, s the finest level's sums there and the result the objective
 * (residuals plus prior) on the finest level. */
static float descend(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts, size_t n,
                     const prior_t *pr, rsm_pose_t *x, sums_t *s, uint32_t *iterations, uint32_t *passes)
{
    float f = 0.0f;
    int level;
    int k;
    for (level = pr->top; level >= 0; --level) {
        float e[3];
        float scale = 1.0f; /* halved for good once a step overshoots */
        uint32_t it;
        level_sums(map, (uint32_t)level, pts, n, pr->reach, x, s);
        ++*passes;
        unpin_sums(s, pr->unpin);
        diff(x, pr->x0, e);
        f = s->cost * pr->w + quad(pr->lam, e);
        for (it = 0; it < cfg->iterations; ++it) {
            float a[9];
            float ai[9];
            float g[3];
            float step[3];
            int halvings;
            int accepted = 0;
            if (s->used < 3u) {
                break;
            }
            full(s->h, pr->w, a);
            for (k = 0; k < 9; ++k) {
                a[k] += pr->lam[k];
            }
            if (rsm_mat3_inverse(a, ai) != RSM_OK) {
                break;
            }
            for (k = 0; k < 3; ++k) {
                g[k] = s->b[k] * pr->w - (pr->lam[k * 3] * e[0] + pr->lam[k * 3 + 1] * e[1] + pr->lam[k * 3 + 2] * e[2]);
            }
            for (k = 0; k < 3; ++k) {
                step[k] = ai[k * 3] * g[0] + ai[k * 3 + 1] * g[1] + ai[k * 3 + 2] * g[2];
            }
            ++*iterations;
            /* A coarse level whose next step is below its threshold has
             * placed the next level: trying the step would cost a pass over
             * every point to move a few millimetres that the next level
             * sets anyway. The finest level tries every step it computes. */
            if (level > 0 && small_step(cfg, step, level)) {
                break;
            }
            /* The interpolated occupancy has kinks at cell borders where a full
             * step can overshoot: take it only where it lowers the cost. A
             * coarse level that cannot lower it has placed the next level
             * well enough; the finest tries half the step too, and keeps
             * halving its steps from then on: past a kink the heading
             * otherwise zigzags for the rest of the iterations. (Five
             * halvings everywhere cost a tenth more per scan for the same
             * accuracy: docs/map.md.) */
            for (k = 0; k < 3; ++k) {
                step[k] *= scale;
            }
            for (halvings = 0; halvings < (level > 0 ? 1 : 2) && !accepted; ++halvings) {
                rsm_pose_t cand;
                sums_t cs;
                float ce[3];
                float cf;
                cand.x = x->x + step[0];
                cand.y = x->y + step[1];
                cand.theta = rsm_wrap_angle(x->theta + step[2]);
                level_sums(map, (uint32_t)level, pts, n, pr->reach, &cand, &cs);
                ++*passes;
                unpin_sums(&cs, pr->unpin);
                diff(&cand, pr->x0, ce);
                cf = cs.cost * pr->w + quad(pr->lam, ce);
                if (cf < f) {
                    *x = cand;
                    *s = cs;
                    memcpy(e, ce, sizeof e);
                    f = cf;
                    accepted = 1;
                } else {
                    step[0] *= 0.5f;
                    step[1] *= 0.5f;
                    step[2] *= 0.5f;
                    scale *= 0.5f;
                }
            }
            if (!accepted || small_step(cfg, step, level)) {
                break;
            }
        }
    }
    return f;
}

int rsm_mapmatch(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts, size_t n,
                 const rsm_pose_t *x0, const float p0[9], const rsm_pose_t *start,
                 const rsm_mapmatch_unpin_t *unpin, rsm_mapmatch_result_t *res)
{
    float pf[9];
    prior_t pr;
    rsm_pose_t x;
    sums_t s;
    int k;
    if (map == NULL || cfg == NULL || (n > 0u && pts == NULL) || x0 == NULL || p0 == NULL || res == NULL ||
        !(cfg->sigma > 0.0f)) {
        return RSM_ERR_INVAL;
    }
    memset(res, 0, sizeof *res);
    res->pose = *x0;
    memcpy(res->cov, p0, sizeof res->cov);
    memcpy(pf, p0, sizeof pf);
    for (k = 0; k < 3; ++k) {
        if (!(pf[k * 4] >= PRIOR_FLOOR)) {
            pf[k * 4] = PRIOR_FLOOR;
        }
    }
    if (rsm_mat3_inverse(pf, pr.lam) != RSM_OK) {
        return RSM_ERR_DEGENERATE;
    }
    pr.x0 = x0;
    pr.unpin = unpin;
    pr.w = 1.0f / (cfg->sigma * cfg->sigma);
    {
        float mean;
        pr.reach = points_reach(pts, n, &mean);
        pr.top = start_level(map, cfg, pf, mean, unpin);
    }
    x = start != NULL ? *start : *x0;
    {
        const float f = descend(map, cfg, pts, n, &pr, &x, &s, &res->iterations, &res->passes);
        if (start == NULL && cfg->fan && cfg->search_rad > 0.0f && cfg->search_step_rad > 0.0f) {
            /* The fan's best heading is only a coarse guess: descend from it
             * too and keep whichever ends lower on the finest level. */
            rsm_pose_t alt = *x0;
            alt.theta = best_heading(map, cfg, pts, n, x0, pr.w, pr.lam[8]);
            if (fabsf(rsm_wrap_angle(alt.theta - x0->theta)) > 0.5f * cfg->search_step_rad) {
                sums_t as;
                const float af = descend(map, cfg, pts, n, &pr, &alt, &as, &res->iterations, &res->passes);
                if (af < f && as.used >= 3u) {
                    x = alt;
                    s = as;
                }
            }
        }
    }
    /* s holds the finest level's sums at x. */
    if (s.used < 3u) {
        return RSM_ERR_DEGENERATE;
    }
    {
        float a[9];
        float e[3];
        full(s.h, pr.w, res->info);
        for (k = 0; k < 9; ++k) {
            a[k] = res->info[k] + pr.lam[k];
        }
        if (rsm_mat3_inverse(a, res->cov) != RSM_OK) {
            memcpy(res->cov, p0, sizeof res->cov);
            return RSM_ERR_DEGENERATE;
        }
        diff(&x, x0, e);
        res->d2 = quad(pr.lam, e);
    }
    res->pose = x;
    res->top = (uint32_t)pr.top;
    res->used = s.used;
    res->cost = s.cost_used / (float)s.used;
    res->hit = n > 0u ? s.hit / (float)n : 0.0f;
    return RSM_OK;
}

/* Chords shorter than this are left out of the spread: over a few
 * centimetres the range noise turns a wall's chord by tens of degrees. */
#define SPREAD_CHORD_M 0.3f
/* Consecutive returns closer than this share a surface: a fraction of their
 * range (a wall seen at a grazing angle has its returns far apart), at
 * least SPREAD_GAP_M. */
#define SPREAD_GAP_REL 0.15f
#define SPREAD_GAP_M 0.1f

float rsm_mapmatch_spread(const rsm_point_t *pts, size_t n, float dir[2])
{
    float a = 0.0f; /* sum of t t^T over the unit chords t: (a b; b c) */
    float b = 0.0f;
    float c = 0.0f;
    size_t j = 1;
    size_t joined = 0; /* points 1..joined are known to join the point before */
    size_t k;
    dir[0] = 1.0f;
    dir[1] = 0.0f;
    /* Each point's chord runs to the first point at least SPREAD_CHORD_M
     * away on its surface; j only moves forward, so this is one pass (and
     * each gap is tested once, though the chords of several points may
     * reach it). */
    for (k = 0; k + 1u < n; ++k) {
        float dx = 0.0f;
        float dy = 0.0f;
        float d2 = 0.0f;
        if (j <= k) {
            j = k + 1u;
        }
        for (; j < n; ++j) {
            if (j > joined) {
                const float gx = pts[j].x - pts[j - 1u].x;
                const float gy = pts[j].y - pts[j - 1u].y;
                const float r = fabsf(pts[j].x) + fabsf(pts[j].y);
                const float g = SPREAD_GAP_REL * r > SPREAD_GAP_M ? SPREAD_GAP_REL * r : SPREAD_GAP_M;
                if (!(gx * gx + gy * gy <= g * g)) {
                    break;
                }
                joined = j;
            }
            dx = pts[j].x - pts[k].x;
            dy = pts[j].y - pts[k].y;
            d2 = dx * dx + dy * dy;
            if (d2 >= SPREAD_CHORD_M * SPREAD_CHORD_M) {
                break;
            }
        }
        if (j >= n) {
            break;
        }
        if (d2 >= SPREAD_CHORD_M * SPREAD_CHORD_M) {
            const float inv = 1.0f / d2;
            a += dx * dx * inv;
            b += dx * dy * inv;
            c += dy * dy * inv;
        } else {
            /* k's surface ends before j, short of a chord from k or from
             * any point after k: the next surface starts at j. */
            k = j - 1u;
        }
    }
    {
        /* Eigenvalues of (a b; b c): m +- dd; the larger one's vector. */
        const float h = 0.5f * (a - c);
        const float dd = sqrtf(h * h + b * b);
        const float m = 0.5f * (a + c);
        float vx;
        float vy;
        float len;
        if (!(m + dd > 0.0f)) {
            return 1.0f; /* no chord: nothing says the scan is one-sided */
        }
        if (h >= 0.0f) {
            vx = h + dd;
            vy = b;
        } else {
            vx = b;
            vy = dd - h;
        }
        len = sqrtf(vx * vx + vy * vy);
        if (len > 0.0f) {
            dir[0] = vx / len;
            dir[1] = vy / len;
        }
        return (m - dd) / (m + dd);
    }
}

void rsm_mapmatch_unpin_for(const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts, size_t n, float theta,
                            rsm_mapmatch_unpin_t *un)
{
    float dir[2];
    float spread;
    un->dir[0] = 1.0f;
    un->dir[1] = 0.0f;
    un->frac = 0.0f;
    if (!(cfg->unpin_hi > cfg->unpin_lo)) {
        return;
    }
    spread = rsm_mapmatch_spread(pts, n, dir);
    if (spread < cfg->unpin_hi) {
        const float f = (cfg->unpin_hi - spread) / (cfg->unpin_hi - cfg->unpin_lo);
        float c;
        float s;
        rsm_sincosf(theta, &s, &c);
        un->dir[0] = c * dir[0] - s * dir[1];
        un->dir[1] = s * dir[0] + c * dir[1];
        un->frac = f < 1.0f ? f : 1.0f;
    }
}
