/* The fixed-point map matcher (RSM_FIXED_MATCH) against the float one: the
 * conversion of a float to fixed point, the map read with its gradient and
 * the normal equations of a pass over a scan, on many values, each within a
 * stated tolerance of the float path. Built with RSM_FIXED_MATCH=1 in the
 * fixed.* variant of the unit tests (and on the soft-float cores); in a
 * float build only the fingerprint's rule is checked. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "rsm/config.h"
#include "rsm/status.h"
#include "map/mapmatch_fixed.h"
#include "map/tilemap.h"
#include "map/tmap_read.h"
#include "unity.h"

void setUp(void)
{
}

void tearDown(void)
{
}

/* A build with the fixed-point matcher has a fingerprint of its own, so
 * that a caller expecting the float build's trajectories is refused; the
 * float build's is the capacities' digest as before, and map files carry
 * that digest in both. */
void test_fingerprint_should_tell_the_arithmetic(void)
{
#if RSM_FIXED_MATCH
    TEST_ASSERT_TRUE((unsigned long)RSM_CONFIG_FINGERPRINT != (unsigned long)RSM_CONFIG_CAPACITY_FINGERPRINT);
#else
    TEST_ASSERT_TRUE((unsigned long)RSM_CONFIG_FINGERPRINT == (unsigned long)RSM_CONFIG_CAPACITY_FINGERPRINT);
#endif
}

#if RSM_FIXED_MATCH

static rsm_tmap_t map;

static uint32_t rnd(uint32_t *seed)
{
    *seed = *seed * 1664525u + 1013904223u;
    return *seed >> 8;
}

/* A uniform float in [lo, hi). */
static float uniform(uint32_t *seed, float lo, float hi)
{
    return lo + (hi - lo) * (float)rnd(seed) / 16777216.0f;
}

/* A map of level 0 only, 10 cm cells, saturation 5 (occupancies that are
 * not multiples of a power of two), random values in cells [-40, 40)^2
 * with blocks of equal values and holes without tiles. */
static void random_map(uint32_t seed)
{
    rsm_tmap_config_t cfg = rsm_tmap_config_default();
    rsm_tmap_cursor_t c;
    int32_t gx;
    int32_t gy;
    cfg.levels = 1u;
    cfg.cell_m = 0.1f;
    cfg.saturation = 5u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &cfg));
    rsm_tmap_cursor_init(&c, 0u);
    for (gy = -40; gy < 40; ++gy) {
        for (gx = -40; gx < 40; ++gx) {
            const uint32_t block = (uint32_t)(((gx + 40) / 3) * 31 + ((gy + 40) / 3) * 17);
            uint32_t v = rnd(&seed) % 16u;
            if (((gx + 40) / 8 + (gy + 40) / 8) % 5 == 0) {
                continue; /* no tile here */
            }
            if (block % 3u == 0u) {
                v = block % 16u; /* equal values: flat reads */
            }
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_raise(&map, &c, gx, gy, v));
        }
    }
}

/* rsm_tmap_fix rounds f 2^q to the nearest integer (halves away from zero),
 * exactly, over the exponents the matcher feeds it. */
void test_fix_should_round_f_times_a_power_of_two(void)
{
    static const float edge[] = {0.0f, -0.0f, 0.5f, -0.5f, 1.0f, -1.0f, 1.5f, 2.5f, -2.5f, 1e-30f, 1e-45f, 3.0e-5f,
                                 -3.0e-5f, 511.99997f, -511.99997f, 0.99999994f};
    uint32_t seed = 7u;
    uint32_t q;
    size_t k;
    for (q = 12u; q <= 20u; q += 4u) {
        for (k = 0; k < sizeof edge / sizeof edge[0]; ++k) {
            const double want = edge[k] == 0.0f ? 0.0 : floor(fabs((double)edge[k]) * ldexp(1.0, (int)q) + 0.5);
            TEST_ASSERT_EQUAL_INT32((int32_t)(edge[k] < 0.0f ? -want : want), rsm_tmap_fix(edge[k], q));
        }
        for (k = 0; k < 100000u; ++k) {
            uint32_t bits;
            float f;
            double want;
            /* every exponent from 2^-40 to just below 2^(30 - q) */
            bits = (rnd(&seed) & 0x7FFFFFu) | ((rnd(&seed) & 1u) << 31) |
                   ((uint32_t)(87u + rnd(&seed) % (70u - q)) << 23);
            memcpy(&f, &bits, sizeof f);
            if (!(fabsf(f) * ldexpf(1.0f, (int)q) < 1073741824.0f)) {
                continue;
            }
            want = floor(fabs((double)f) * ldexp(1.0, (int)q) + 0.5);
            TEST_ASSERT_EQUAL_INT32((int32_t)(f < 0.0f ? -want : want), rsm_tmap_fix(f, q));
        }
    }
}

/* The fixed-point read against rsm_tmap_read_cells (float) on 200 000
 * random coordinates over a map with tiles, holes, tile edges and flat
 * blocks, each a whole cell plus a fraction of 15 bits (so that both read
 * the same four cells at the same place): the occupancy and the gradient
 * within 2 units of 2^-15 (the table's rounding and each product's, half a
 * unit each; 1.28 and 1.60 seen), and a zero gradient exactly where the
 * float one is. */
void test_read_fixed_should_equal_the_float_read_within_units(void)
{
    const float unit = 1.0f / (float)RSM_TMAP_FIX_ONE;
    uint32_t seed = 99u;
    int32_t occ[RSM_TMAP_MAX_VALUE + 1u];
    rsm_tmap_cursor_t cf;
    rsm_tmap_cursor_t cx;
    rsm_tmap_window_t wx;
    float worst_m = 0.0f;
    float worst_g = 0.0f;
    size_t k;
    random_map(1234u);
    rsm_tmap_fix_occ(&map, occ);
    rsm_tmap_cursor_init(&cf, 0u);
    rsm_tmap_cursor_init(&cx, 0u);
    rsm_tmap_window_forget(&wx);
    for (k = 0; k < 200000u; ++k) {
        const int32_t i = (int32_t)(rnd(&seed) % 90u) - 45;
        const int32_t j = (int32_t)(rnd(&seed) % 90u) - 45;
        const int32_t fu = (int32_t)(rnd(&seed) & 0x7FFFu);
        const int32_t fv = k % 5u == 0u ? 0 : (int32_t)(rnd(&seed) & 0x7FFFu);
        const float u = (float)i + (float)fu * unit;
        const float v = (float)j + (float)fv * unit;
        float du;
        float dv;
        const float mf = rsm_tmap_read_cells(&map, &cf, &cf.win, u, v, 0, &du, &dv);
        int32_t gu;
        int32_t gv;
        const int32_t mq = rsm_tmap_read_fixed(&map, &cx, &wx, occ, i, j, fu, fv, &gu, &gv);
        TEST_ASSERT_TRUE(mq >= 0 && mq <= RSM_TMAP_FIX_ONE);
        worst_m = fmaxf(worst_m, fabsf((float)mq * unit - mf));
        worst_g = fmaxf(worst_g, fmaxf(fabsf((float)gu * unit - du), fabsf((float)gv * unit - dv)));
        if (du == 0.0f && dv == 0.0f) {
            TEST_ASSERT_EQUAL_INT32(0, gu);
            TEST_ASSERT_EQUAL_INT32(0, gv);
        }
    }
    TEST_ASSERT_TRUE(worst_m <= 2.0f * unit);
    TEST_ASSERT_TRUE(worst_g <= 2.0f * unit);
    TEST_ASSERT_TRUE(worst_m > 0.0f); /* the two paths are not one */
}

/* The float pass, in double: the points placed in float as the matcher's
 * float pass places them, each read with rsm_tmap_read_cells. */
typedef struct ref_sums {
    double h[6];
    double b[3];
    double cost;
    double hit;
    double mag_h[6]; /* sums of the terms' magnitudes: the tolerance's scale */
    double mag_b[3];
    uint32_t used;
} ref_sums_t;

static void float_pass(const rsm_point_t *pts, size_t n, float c, float sn, float tu, float tv, ref_sums_t *s)
{
    rsm_tmap_cursor_t cur;
    size_t k;
    memset(s, 0, sizeof *s);
    rsm_tmap_cursor_init(&cur, 0u);
    for (k = 0; k < n; ++k) {
        const float cx = c * pts[k].x;
        const float sy = sn * pts[k].y;
        const float sx = sn * pts[k].x;
        const float cy = c * pts[k].y;
        float gu;
        float gv;
        const float m = rsm_tmap_read_cells(&map, &cur, &cur.win, tu + cx - sy, tv + sx + cy, 0, &gu, &gv);
        const double r = 1.0 - (double)m;
        const double gt = (double)gu * (double)(-sx - cy) + (double)gv * (double)(cx - sy);
        const double t[9] = {(double)gu * gu, (double)gu * gv, gu * gt, (double)gv * gv, gv * gt, gt * gt,
                             gu * r, gv * r, gt * r};
        int q;
        s->cost += r * r;
        s->hit += m;
        if (gu == 0.0f && gv == 0.0f) {
            continue;
        }
        ++s->used;
        for (q = 0; q < 6; ++q) {
            s->h[q] += t[q];
            s->mag_h[q] += fabs(t[q]);
        }
        for (q = 0; q < 3; ++q) {
            s->b[q] += t[6 + q];
            s->mag_b[q] += fabs(t[6 + q]);
        }
    }
}

/* rsm_matchfix_pass against the float pass on 300 random scans and poses
 * over the random map: every sum within 1e-4 of the sum of its terms'
 * magnitudes (the reads' few units of 2^-15 against terms of about 0.1 to
 * 1, the points' placement rounded to 2^-15 cells), but in the few scans
 * (at most 3 here; 1 is seen) where a point lands on the other side of a
 * cell's edge than in float, whose terms then differ: within 5e-3 there.
 * The cost and the sum of occupancies within 2e-4 of the point count, and
 * the points with a gradient the same within two. */
void test_pass_fixed_should_equal_the_float_sums_within_tolerance(void)
{
    uint32_t seed = 4242u;
    rsm_point_t pts[RSM_MAX_BEAMS];
    double worst = 0.0;
    int edges = 0;
    int scan;
    random_map(777u);
    for (scan = 0; scan < 300; ++scan) {
        const size_t n = (size_t)(20u + rnd(&seed) % (uint32_t)(RSM_MAX_BEAMS - 20));
        const float theta = uniform(&seed, -3.14159f, 3.14159f);
        const float inv_a = map.inv_cell[0];
        const float c = cosf(theta) * inv_a;
        const float sn = sinf(theta) * inv_a;
        const float tu = uniform(&seed, -1.5f, 1.5f) * inv_a - 0.5f;
        const float tv = uniform(&seed, -1.5f, 1.5f) * inv_a - 0.5f;
        float reach = 0.0f;
        rsm_fixed_sums_t fx;
        ref_sums_t ref;
        size_t k;
        int q;
        memset(&fx, 0, sizeof fx);
        for (k = 0; k < n; ++k) {
            const float range = uniform(&seed, 0.1f, 2.9f);
            const float bearing = uniform(&seed, -3.14159f, 3.14159f);
            pts[k].x = range * cosf(bearing);
            pts[k].y = range * sinf(bearing);
            reach = fmaxf(reach, fabsf(pts[k].x) + fabsf(pts[k].y));
        }
        TEST_ASSERT_EQUAL_INT(1, rsm_matchfix_pass(&map, 0u, pts, n, reach, inv_a, c, sn, tu, tv, 0, &fx));
        float_pass(pts, n, c, sn, tu, tv, &ref);
        double worst_scan = 0.0;
        for (q = 0; q < 6; ++q) {
            const double e = fabs((double)fx.h[q] - ref.h[q]) / (ref.mag_h[q] + 1e-9);
            worst = fmax(worst, e);
            worst_scan = fmax(worst_scan, e);
        }
        for (q = 0; q < 3; ++q) {
            const double e = fabs((double)fx.b[q] - ref.b[q]) / (ref.mag_b[q] + 1e-9);
            worst = fmax(worst, e);
            worst_scan = fmax(worst_scan, e);
        }
        TEST_ASSERT_TRUE(worst_scan <= 5e-3);
        if (worst_scan > 1e-4) {
            ++edges;
        }
        TEST_ASSERT_TRUE(fabs((double)fx.cost - ref.cost) <= 2e-4 * (double)n);
        TEST_ASSERT_TRUE(fabs((double)fx.hit - ref.hit) <= 2e-4 * (double)n);
        TEST_ASSERT_TRUE(fx.used + 2u >= ref.used && ref.used + 2u >= fx.used);
    }
    TEST_ASSERT_TRUE(edges <= 3);
    TEST_ASSERT_TRUE(worst > 0.0); /* the two paths are not one */
}

/* Out of the integers' range (a point beyond RSM_MATCHFIX_REACH_M, a reach
 * that is NaN) the pass writes nothing and says so: the float pass runs. */
void test_pass_fixed_should_refuse_what_its_integers_cannot_hold(void)
{
    rsm_point_t p = {2000.0f, 0.0f};
    rsm_fixed_sums_t fx;
    random_map(5u);
    memset(&fx, 0x5A, sizeof fx);
    TEST_ASSERT_EQUAL_INT(0, rsm_matchfix_pass(&map, 0u, &p, 1u, 2000.0f, map.inv_cell[0], 10.0f, 0.0f, 0.0f,
                                               0.0f, 0, &fx));
    TEST_ASSERT_EQUAL_INT(0, rsm_matchfix_pass(&map, 0u, &p, 1u, NAN, map.inv_cell[0], 10.0f, 0.0f, 0.0f, 0.0f,
                                               0, &fx));
    TEST_ASSERT_EQUAL_HEX8(0x5A, ((const unsigned char *)&fx)[0]);
}

#endif /* RSM_FIXED_MATCH */

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_fingerprint_should_tell_the_arithmetic);
#if RSM_FIXED_MATCH
    RUN_TEST(test_fix_should_round_f_times_a_power_of_two);
    RUN_TEST(test_read_fixed_should_equal_the_float_read_within_units);
    RUN_TEST(test_pass_fixed_should_equal_the_float_sums_within_tolerance);
    RUN_TEST(test_pass_fixed_should_refuse_what_its_integers_cannot_hold);
#endif
    return UNITY_END();
}
