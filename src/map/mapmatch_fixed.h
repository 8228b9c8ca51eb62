/* The map matcher's pass over a scan in fixed point (RSM_FIXED_MATCH): the
 * points placed, the map read and the normal equations summed with 32-bit
 * integer products and 64-bit sums, for cores without an FPU, where each
 * of the float pass's ~45 operations a point is a call into libgcc. Its
 * sums equal the float pass's to a few units of their last bits (checked by
 * unit.test_fixedmatch), not bit for bit: a build with it computes its
 * own trajectory (docs/fpu-less.md). Internal to the library. */
#ifndef RSM_MAPMATCH_FIXED_H
#define RSM_MAPMATCH_FIXED_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"

/* The sums of one pass (the float pass's too), per cell of the level (as the float pass leaves
 * them, before level_sums scales them to metres): h the upper triangle of
 * J^T J (00 01 02 11 12 22), b = J^T r, cost the sum of r^2 over every
 * point, cost_used over those with a gradient, hit the sum of M, used the
 * points with a gradient. */
typedef struct rsm_fixed_sums {
    float h[6];
    float b[3];
    float cost;
    float cost_used;
    float hit;
    uint32_t used;
} rsm_fixed_sums_t;

#if RSM_FIXED_MATCH

#include "rsm/geom.h"
#include "map/tilemap.h"
#include "map/tmap_read.h"


/* Fractional bits of the points (metres: |x| < 2^11 m) and of the
 * rotation's terms (cells per metre: below 2^10); the heading's derivative
 * has RSM_MATCHFIX_GT_BITS. */
#define RSM_MATCHFIX_P_BITS 20
#define RSM_MATCHFIX_C_BITS 20
#define RSM_MATCHFIX_GT_BITS 12
/* Bounds that keep every product and sum inside its integer: the points'
 * reach (max |x| + |y|) in metres and in cells, and the pose in cells. */
#define RSM_MATCHFIX_REACH_M 1024.0f
#define RSM_MATCHFIX_REACH_CELLS 4096.0f
#define RSM_MATCHFIX_POSE_CELLS 4194304.0f

/* floor(t) into *ti and the fraction in units of 2^-15 into *tf; |t| below
 * RSM_MATCHFIX_POSE_CELLS (float operations: once a pass). */
static inline void rsm_matchfix_split(float t, int32_t *ti, int32_t *tf)
{
    int32_t i = (int32_t)t;
    float f = t - (float)i; /* exact: t and i share the exponent's range */
    if (f < 0.0f) {
        --i;
        f += 1.0f;
    }
    *tf = rsm_tmap_fix(f, (uint32_t)RSM_TMAP_FIX_BITS);
    if (*tf >= RSM_TMAP_FIX_ONE) {
        ++i; /* f rounded up to a whole cell */
        *tf -= RSM_TMAP_FIX_ONE;
    }
    *ti = i;
}

/* The pass over pts at the pose (c, sn, tu, tv) in the level's cells (c and
 * sn: the heading's cosine and sine times inv_a, the level's cells per
 * metre; tu, tv: the pose's position in cells less half a cell), as the
 * float pass computes it; inside: every point known to be within the map's
 * range (rsm_tmap_read_reach). reach: the points' largest |x| + |y|.
 * Returns 0, having written nothing, where the points or the pose are out
 * of the integers' range (the caller then runs the float pass). */
static inline int rsm_matchfix_pass(const rsm_tmap_t *map, uint32_t level, const rsm_point_t *pts, size_t n,
                                    float reach, float inv_a, float c, float sn, float tu, float tv, int inside,
                                    rsm_fixed_sums_t *s)
{
    const int32_t lim = RSM_TMAP_CELL_LIMIT;
    int32_t occ[RSM_TMAP_MAX_VALUE + 1u];
    int32_t cq;
    int32_t sq;
    int32_t ti;
    int32_t tf;
    int32_t tj;
    int32_t tg;
    /* Each r^2 and product of two gradients or of a gradient and r is below
     * 2^30, those with gt below 2^50: 64-bit sums hold the 4096 points a
     * scan has at most (RSM_MAX_BEAMS), and hit's 32 bits 2^16. */
    int64_t h0 = 0;
    int64_t h1 = 0;
    int64_t h2 = 0;
    int64_t h3 = 0;
    int64_t h4 = 0;
    int64_t h5 = 0;
    int64_t b0 = 0;
    int64_t b1 = 0;
    int64_t b2 = 0;
    int64_t cost = 0;
    int64_t cost_used = 0;
    int32_t hit = 0;
    size_t unused = 0;
    rsm_tmap_cursor_t cur;
    rsm_tmap_window_t win;
    const rsm_point_t *p;
    /* NaN fails every one of these tests too. */
    if (!(reach < RSM_MATCHFIX_REACH_M) || !(inv_a < 1024.0f) || !(reach * inv_a < RSM_MATCHFIX_REACH_CELLS) ||
        !(fabsf(tu) < RSM_MATCHFIX_POSE_CELLS) || !(fabsf(tv) < RSM_MATCHFIX_POSE_CELLS) || n > 4096u) {
        return 0;
    }
    rsm_tmap_fix_occ(map, occ);
    cq = rsm_tmap_fix(c, (uint32_t)RSM_MATCHFIX_C_BITS);
    sq = rsm_tmap_fix(sn, (uint32_t)RSM_MATCHFIX_C_BITS);
    rsm_matchfix_split(tu, &ti, &tf);
    rsm_matchfix_split(tv, &tj, &tg);
    rsm_tmap_cursor_init(&cur, level);
    rsm_tmap_window_forget(&win);
    for (p = pts; p != pts + n; ++p) {
        /* The point rotated into the level's cells, 15 fractional bits
         * (|ru|, |rv| < 2^12 cells by the reach test). */
        const int32_t shift = RSM_MATCHFIX_P_BITS + RSM_MATCHFIX_C_BITS - RSM_TMAP_FIX_BITS;
        const int64_t half = (int64_t)1 << (shift - 1);
        const int32_t px = rsm_tmap_fix(p->x, (uint32_t)RSM_MATCHFIX_P_BITS);
        const int32_t py = rsm_tmap_fix(p->y, (uint32_t)RSM_MATCHFIX_P_BITS);
        const int32_t ru = (int32_t)(((int64_t)cq * px - (int64_t)sq * py + half) >> shift);
        const int32_t rv = (int32_t)(((int64_t)sq * px + (int64_t)cq * py + half) >> shift);
        const int32_t u = tf + ru;
        const int32_t v = tg + rv;
        const int32_t i = ti + (u >> RSM_TMAP_FIX_BITS);
        const int32_t j = tj + (v >> RSM_TMAP_FIX_BITS);
        int32_t m;
        int32_t r;
        int32_t gu;
        int32_t gv;
        int32_t gt;
        if (!inside && !(i > -lim && i < lim - 1 && j > -lim && j < lim - 1)) {
            /* Out of the cells' range: no occupancy, no gradient. */
            cost += (int64_t)RSM_TMAP_FIX_ONE * RSM_TMAP_FIX_ONE;
            ++unused;
            continue;
        }
        m = rsm_tmap_read_fixed(map, &cur, &win, occ, i, j, u & (RSM_TMAP_FIX_ONE - 1), v & (RSM_TMAP_FIX_ONE - 1),
                                &gu, &gv);
        r = RSM_TMAP_FIX_ONE - m;
        cost += r * r;
        hit += m;
        if (gu == 0 && gv == 0) {
            ++unused;
            continue;
        }
        /* d(cell)/d(theta) = (-rv, ru): gv ru - gu rv, 30 fractional bits,
         * kept with RSM_MATCHFIX_GT_BITS (|gt| < 2^13). */
        {
            const int32_t gshift = 2 * RSM_TMAP_FIX_BITS - RSM_MATCHFIX_GT_BITS;
            const int64_t g = (int64_t)gv * ru - (int64_t)gu * rv;
            gt = (int32_t)((g + ((int64_t)1 << (gshift - 1))) >> gshift);
        }
        h0 += gu * gu;
        h1 += gu * gv;
        h2 += (int64_t)gu * gt;
        h3 += gv * gv;
        h4 += (int64_t)gv * gt;
        h5 += (int64_t)gt * gt;
        b0 += gu * r;
        b1 += gv * r;
        b2 += (int64_t)gt * r;
        cost_used += r * r;
    }
    {
        /* 2^-30, 2^-27 and 2^-24: the sums' units (exact in float). */
        const float q30 = 1.0f / 1073741824.0f;
        const float q27 = 1.0f / 134217728.0f;
        const float q24 = 1.0f / 16777216.0f;
        s->h[0] = (float)h0 * q30;
        s->h[1] = (float)h1 * q30;
        s->h[2] = (float)h2 * q27;
        s->h[3] = (float)h3 * q30;
        s->h[4] = (float)h4 * q27;
        s->h[5] = (float)h5 * q24;
        s->b[0] = (float)b0 * q30;
        s->b[1] = (float)b1 * q30;
        s->b[2] = (float)b2 * q27;
        s->cost = (float)cost * q30;
        s->cost_used = (float)cost_used * q30;
        s->hit = (float)hit * (1.0f / (float)RSM_TMAP_FIX_ONE);
        s->used = (uint32_t)(n - unused);
    }
    return 1;
}

#endif /* RSM_FIXED_MATCH */

#endif /* RSM_MAPMATCH_FIXED_H */
