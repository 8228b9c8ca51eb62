/* Unit tests for src/core/scan.c: beam layout, reading validity and conversion to
 * points. */
#include <math.h>
#include <string.h>

#include "rsm/config.h"
#include "rsm/scan.h"
#include "rsm/status.h"
#include "unity.h"

static rsm_scan_t scan;
static rsm_scan_limits_t lim;
static rsm_scan_drops_t drops;

void setUp(void)
{
    memset(&scan, 0, sizeof scan);
    memset(&drops, 0, sizeof drops);
    lim = rsm_scan_limits_default();
}

void tearDown(void)
{
}

void test_scan_limits_default_should_be_5_cm_to_20_m(void)
{
    TEST_ASSERT_EQUAL_FLOAT(0.05f, lim.min_range_m);
    TEST_ASSERT_EQUAL_FLOAT(20.0f, lim.max_range_m);
}

void test_scan_set_uniform_should_lay_out_beam_angles(void)
{
    size_t i;
    scan.range_m[3] = 1.25f;
    /* An LMS at 1 deg over 180 deg: 181 beams from -90 deg. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, 181, -0.5f * RSM_PI, RSM_PI / 180.0f));
    TEST_ASSERT_EQUAL_INT(181, (int)scan.count);
    for (i = 0; i < 181; ++i) {
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, -0.5f * RSM_PI + (float)i * (RSM_PI / 180.0f), scan.angle_rad[i]);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.5f * RSM_PI, scan.angle_rad[180]);
    /* Ranges are not touched. */
    TEST_ASSERT_EQUAL_FLOAT(1.25f, scan.range_m[3]);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, scan.range_m[4]);
    /* An empty scan is allowed. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, 0, 0.0f, 0.1f));
    TEST_ASSERT_EQUAL_INT(0, (int)scan.count);
}

void test_scan_set_uniform_should_respect_capacity(void)
{
    static rsm_scan_t before;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, RSM_MAX_BEAMS, 0.0f, 0.01f));
    TEST_ASSERT_EQUAL_INT(RSM_MAX_BEAMS, (int)scan.count);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.01f * (float)(RSM_MAX_BEAMS - 1), scan.angle_rad[RSM_MAX_BEAMS - 1]);
    before = scan;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_scan_set_uniform(&scan, RSM_MAX_BEAMS + 1, 1.0f, 0.02f));
    TEST_ASSERT_EQUAL_MEMORY(&before, &scan, sizeof scan);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_scan_set_uniform(NULL, 10, 0.0f, 0.1f));
}

void test_scan_set_uniform_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* What rsm_scan_set_uniform passes for an application compiled with
     * another RSM_MAX_BEAMS (its scan of another size: the angles would land
     * past it), or with capacities that give the same size: refused, and
     * not one byte written. */
    static rsm_scan_t before;
    memset(&scan, 0x5A, sizeof scan);
    memcpy(&before, &scan, sizeof scan);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_scan_set_uniform_checked(&scan, sizeof scan - 8u,
                                                                       (unsigned long)RSM_CONFIG_FINGERPRINT, 2u, 0.0f,
                                                                       0.01f));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_scan_set_uniform_checked(&scan, sizeof scan,
                                                                       (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul, 2u,
                                                                       0.0f, 0.01f));
    TEST_ASSERT_EQUAL_MEMORY(&before, &scan, sizeof scan);
    /* The macro passes this build's own. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, 2u, 0.0f, 0.01f));
    TEST_ASSERT_EQUAL_size_t(2u, scan.count);
}

void test_scan_trig_init_should_refuse_a_caller_built_with_other_capacities(void)
{
    static rsm_scan_trig_t trig;
    static rsm_scan_trig_t before;
    memset(&trig, 0x5A, sizeof trig);
    memcpy(&before, &trig, sizeof trig);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_scan_trig_init_checked(&trig, sizeof trig - 12u,
                                                                     (unsigned long)RSM_CONFIG_FINGERPRINT));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_scan_trig_init_checked(&trig, sizeof trig,
                                                                     (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul));
    TEST_ASSERT_EQUAL_MEMORY(&before, &trig, sizeof trig);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_scan_trig_init(NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_trig_init(&trig));
    TEST_ASSERT_TRUE(isnan(trig.angle[0]) && isnan(trig.angle[RSM_MAX_BEAMS - 1]));
}

void test_scan_reading_ok_should_count_each_reason_separately(void)
{
    const float ranges[] = {
        1.0f,      /* ok */
        NAN,       /* nan */
        INFINITY,  /* nan (not finite) */
        -INFINITY, /* nan (not finite) */
        0.0f,      /* too short: "no echo" */
        0.05f,     /* too short: at the minimum */
        -1.0f,     /* too short */
        20.0f,     /* too long: at the maximum */
        81.91f,    /* too long: an LMS max-range code */
        19.99f,    /* ok */
        0.051f,    /* ok */
        5.0f,      /* nan: the angle is NaN */
    };
    const size_t n = sizeof ranges / sizeof ranges[0];
    size_t i;
    int ok = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, n, -1.0f, 0.1f));
    for (i = 0; i < n; ++i) {
        scan.range_m[i] = ranges[i];
    }
    scan.angle_rad[n - 1] = NAN;
    for (i = 0; i < n; ++i) {
        ok += rsm_scan_reading_ok(&scan, i, &lim, &drops);
    }
    TEST_ASSERT_EQUAL_INT(3, ok);
    TEST_ASSERT_EQUAL_UINT32(4u, drops.nan);
    TEST_ASSERT_EQUAL_UINT32(3u, drops.too_short);
    TEST_ASSERT_EQUAL_UINT32(2u, drops.too_long);

    /* Counting is cumulative and optional. */
    TEST_ASSERT_FALSE(rsm_scan_reading_ok(&scan, 1, &lim, &drops));
    TEST_ASSERT_EQUAL_UINT32(5u, drops.nan);
    TEST_ASSERT_FALSE(rsm_scan_reading_ok(&scan, 1, &lim, NULL));
    TEST_ASSERT_TRUE(rsm_scan_reading_ok(&scan, 0, &lim, NULL));
}

void test_scan_reading_ok_should_refuse_indices_past_the_count(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, 4, 0.0f, 0.1f));
    scan.range_m[4] = 1.0f;
    scan.range_m[0] = 1.0f;
    TEST_ASSERT_FALSE(rsm_scan_reading_ok(&scan, 4, &lim, &drops));
    TEST_ASSERT_FALSE(rsm_scan_reading_ok(&scan, RSM_MAX_BEAMS + 10u, &lim, &drops));
    TEST_ASSERT_FALSE(rsm_scan_reading_ok(NULL, 0, &lim, &drops));
    TEST_ASSERT_FALSE(rsm_scan_reading_ok(&scan, 0, NULL, &drops));
    TEST_ASSERT_EQUAL_UINT32(0u, drops.nan);
    TEST_ASSERT_EQUAL_UINT32(0u, drops.too_short);
    TEST_ASSERT_EQUAL_UINT32(0u, drops.too_long);
    TEST_ASSERT_TRUE(rsm_scan_reading_ok(&scan, 0, &lim, &drops));
}

void test_scan_to_points_should_convert_usable_readings(void)
{
    rsm_point_t pts[8];
    int n;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, 5, 0.0f, 0.5f * RSM_PI));
    scan.range_m[0] = 2.0f;  /* ahead */
    scan.range_m[1] = 3.0f;  /* left */
    scan.range_m[2] = 0.0f;  /* no echo */
    scan.range_m[3] = 1.5f;  /* right */
    scan.range_m[4] = NAN;
    memset(pts, 0xFF, sizeof pts);
    n = rsm_scan_to_points(&scan, &lim, pts, 8, &drops);
    TEST_ASSERT_EQUAL_INT(3, n);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.0f, pts[0].x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, pts[0].y);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, pts[1].x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 3.0f, pts[1].y);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, pts[2].x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, -1.5f, pts[2].y);
    TEST_ASSERT_EQUAL_UINT32(1u, drops.nan);
    TEST_ASSERT_EQUAL_UINT32(1u, drops.too_short);
    TEST_ASSERT_EQUAL_UINT32(0u, drops.too_long);

    /* Called again, out is overwritten from the start, not appended to. */
    scan.range_m[0] = 4.0f;
    n = rsm_scan_to_points(&scan, &lim, pts, 8, NULL);
    TEST_ASSERT_EQUAL_INT(3, n);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 4.0f, pts[0].x);
}

void test_scan_to_points_should_stop_at_cap(void)
{
    rsm_point_t pts[6];
    const rsm_point_t guard = { 123.0f, -456.0f };
    size_t i;
    int n;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, 10, -0.5f, 0.1f));
    for (i = 0; i < 10; ++i) {
        scan.range_m[i] = 1.0f + 0.1f * (float)i;
    }
    for (i = 0; i < 6; ++i) {
        pts[i] = guard;
    }
    n = rsm_scan_to_points(&scan, &lim, pts, 4, &drops);
    TEST_ASSERT_EQUAL_INT(4, n);
    TEST_ASSERT_EQUAL_MEMORY(&guard, &pts[4], sizeof guard);
    TEST_ASSERT_EQUAL_MEMORY(&guard, &pts[5], sizeof guard);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 1.3f * cosf(-0.2f), pts[3].x);
    /* cap 0 writes nothing. */
    n = rsm_scan_to_points(&scan, &lim, pts, 0, &drops);
    TEST_ASSERT_EQUAL_INT(0, n);
}

/* Points of the cached conversion equal the direct one's bit for bit,
 * whether the angles repeat, change, or are zeros of either sign. */
static void check_cached_equals_direct(rsm_scan_trig_t *trig)
{
    static rsm_point_t direct[RSM_MAX_BEAMS];
    static rsm_point_t cached[RSM_MAX_BEAMS];
    int n;
    int m;
    memset(direct, 0xAB, sizeof direct);
    memset(cached, 0xCD, sizeof cached);
    n = rsm_scan_to_points(&scan, &lim, direct, RSM_MAX_BEAMS, NULL);
    m = rsm_scan_to_points_cached(&scan, &lim, trig, cached, RSM_MAX_BEAMS, NULL);
    TEST_ASSERT_EQUAL_INT(n, m);
    TEST_ASSERT_GREATER_THAN_INT(0, n);
    TEST_ASSERT_EQUAL_MEMORY(direct, cached, (size_t)n * sizeof direct[0]);
}

void test_scan_to_points_cached_should_equal_the_direct_conversion(void)
{
    static rsm_scan_trig_t trig;
    rsm_point_t one[1];
    size_t i;
    rsm_scan_trig_init(&trig);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, RSM_MAX_BEAMS, -1.5f, 3.0f / (float)RSM_MAX_BEAMS));
    for (i = 0; i < RSM_MAX_BEAMS; ++i) {
        scan.range_m[i] = 1.0f + 0.01f * (float)i;
    }
    check_cached_equals_direct(&trig); /* fills the cache */
    check_cached_equals_direct(&trig); /* reads it */
    /* Other angles (another sensor, or a head turning): recomputed. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, RSM_MAX_BEAMS, 0.25f, 0.01f));
    check_cached_equals_direct(&trig);
    /* One beam's angle moved by one ulp: that beam only is recomputed, and
     * still right. */
    scan.angle_rad[7] = nextafterf(scan.angle_rad[7], 10.0f);
    check_cached_equals_direct(&trig);
    /* Zero, then minus zero: the sines differ in sign, and so do the points. */
    scan.angle_rad[0] = 0.0f;
    check_cached_equals_direct(&trig);
    scan.angle_rad[0] = -0.0f;
    check_cached_equals_direct(&trig);
    /* A fresh cache does not take +0 for an angle it holds (its slots are
     * NaN, not the zeros of a cleared struct). */
    rsm_scan_trig_init(&trig);
    scan.angle_rad[0] = 0.0f;
    check_cached_equals_direct(&trig);
    /* Unusable readings are skipped as by the direct conversion. */
    scan.range_m[3] = NAN;
    scan.range_m[4] = 0.0f;
    check_cached_equals_direct(&trig);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_scan_to_points_cached(&scan, &lim, NULL, one, 1, NULL));
}

void test_scan_to_points_should_handle_a_full_scan(void)
{
    static rsm_point_t pts[RSM_MAX_BEAMS];
    size_t i;
    int n;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, RSM_MAX_BEAMS, -1.5f, 3.0f / (float)RSM_MAX_BEAMS));
    for (i = 0; i < RSM_MAX_BEAMS; ++i) {
        scan.range_m[i] = 2.0f;
    }
    n = rsm_scan_to_points(&scan, &lim, pts, RSM_MAX_BEAMS, &drops);
    TEST_ASSERT_EQUAL_INT(RSM_MAX_BEAMS, n);
    for (i = 0; i < RSM_MAX_BEAMS; ++i) {
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, 2.0f, hypotf(pts[i].x, pts[i].y));
    }
}

void test_scan_to_points_should_reject_bad_arguments(void)
{
    rsm_point_t pts[2];
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, 2, 0.0f, 0.1f));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_scan_to_points(NULL, &lim, pts, 2, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_scan_to_points(&scan, NULL, pts, 2, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_scan_to_points(&scan, &lim, NULL, 2, NULL));
    /* A corrupted count is refused rather than read past the arrays. */
    scan.count = RSM_MAX_BEAMS + 1u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_scan_to_points(&scan, &lim, pts, 2, NULL));
}

/* A wall 2 m ahead of (ox, oy) seen by 1-degree beams, in beam order. */
static void wall_points(rsm_point_t *p, size_t n, float ox, float oy)
{
    size_t k;
    for (k = 0; k < n; ++k) {
        const float a = ((float)k - (float)(n / 2u)) * 0.0174533f;
        p[k].x = ox + 2.0f;
        p[k].y = oy + 2.0f * tanf(a);
    }
}

static rsm_isolation_t isolation(void)
{
    rsm_isolation_t iso;
    iso.tol_m = 0.1f;
    iso.slope = 3.0f;
    iso.window = 2u;
    iso.agree = 1u;
    return iso;
}

static int marked(const uint8_t *mask, size_t k)
{
    return (int)(((uint32_t)mask[k >> 3] >> (k & 7u)) & 1u);
}

void test_points_isolated_should_mark_a_phantom_and_not_the_wall(void)
{
    rsm_point_t p[21];
    uint8_t mask[3];
    const rsm_isolation_t iso = isolation();
    const rsm_point_t o = {0.0f, 0.0f};
    size_t k;
    wall_points(p, 21u, 0.0f, 0.0f);
    /* Beam 10 sees something 1.2 m short of the wall. */
    p[10].x = 0.8f;
    memset(mask, 0xFF, sizeof mask); /* every bit of the n is written */
    TEST_ASSERT_EQUAL_size_t(1u, rsm_points_isolated(p, 21u, &o, &iso, mask));
    for (k = 0; k < 21u; ++k) {
        TEST_ASSERT_EQUAL_INT(k == 10u, marked(mask, k));
    }
}

void test_points_isolated_should_judge_from_the_given_origin(void)
{
    /* The same scene seen from (5, -3): the same single phantom. */
    rsm_point_t p[21];
    uint8_t mask[3];
    const rsm_isolation_t iso = isolation();
    const rsm_point_t o = {5.0f, -3.0f};
    wall_points(p, 21u, o.x, o.y);
    p[3].x = o.x + 1.1f;
    TEST_ASSERT_EQUAL_size_t(1u, rsm_points_isolated(p, 21u, &o, &iso, mask));
    TEST_ASSERT_TRUE(marked(mask, 3u));
}

void test_points_isolated_should_let_a_pair_confirm_itself_and_honour_agree(void)
{
    /* Two neighbouring returns on a small object confirm each other; with
     * agree = 2 each has only one neighbour on its surface and both are
     * marked, while every wall return, the ends included, has two. */
    rsm_point_t p[21];
    uint8_t mask[3];
    rsm_isolation_t iso = isolation();
    wall_points(p, 21u, 0.0f, 0.0f);
    p[10].x = 1.0f;
    p[11].x = 1.0f;
    p[11].y = p[10].y + 0.0175f;
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_isolated(p, 21u, NULL, &iso, mask));
    iso.agree = 2u;
    TEST_ASSERT_EQUAL_size_t(2u, rsm_points_isolated(p, 21u, NULL, &iso, mask));
    TEST_ASSERT_TRUE(marked(mask, 10u) && marked(mask, 11u));
}

/* Nine beams, a degree apart, on the wall through (3, 0) along direction 25
 * degrees: 65 degrees incidence. */
static void steep_wall(rsm_point_t p[9])
{
    size_t k;
    for (k = 0; k < 9u; ++k) {
        const float a = ((float)k - 4.0f) * 0.0174533f;
        const float t = 3.0f * sinf(a) / sinf(0.436332f - a);
        p[k].x = 3.0f + t * cosf(0.436332f);
        p[k].y = t * sinf(0.436332f);
    }
}

void test_points_isolated_should_accept_steep_walls_up_to_the_slope(void)
{
    /* A wall at 25 degrees to the beams (65 degrees incidence): consecutive
     * returns lie 1.9 to 2.6 beam gaps apart, inside slope 3, outside 1.5. */
    rsm_point_t p[9];
    uint8_t mask[2];
    rsm_isolation_t iso = isolation();
    iso.tol_m = 0.01f;
    iso.window = 1u;
    steep_wall(p);
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_isolated(p, 9u, NULL, &iso, mask));
    iso.slope = 1.5f;
    TEST_ASSERT_EQUAL_size_t(9u, rsm_points_isolated(p, 9u, NULL, &iso, mask));
}

void test_points_isolated_should_mark_nothing_when_off(void)
{
    rsm_point_t p[5];
    uint8_t mask[1];
    rsm_isolation_t iso = isolation();
    wall_points(p, 5u, 0.0f, 0.0f);
    p[2].x = 0.5f;
    iso.tol_m = 0.0f;
    mask[0] = 0xFF;
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_isolated(p, 5u, NULL, &iso, mask));
    TEST_ASSERT_EQUAL_HEX8(0u, mask[0]);
    iso.tol_m = 0.1f;
    iso.window = 0u;
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_isolated(p, 5u, NULL, &iso, mask));
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_isolated(NULL, 5u, NULL, &iso, mask));
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_isolated(p, 5u, NULL, NULL, mask));
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_isolated(p, 5u, NULL, &iso, NULL));
    /* A single point has no neighbour at all. */
    iso.window = 2u;
    TEST_ASSERT_EQUAL_size_t(1u, rsm_points_isolated(p, 1u, NULL, &iso, mask));
}

/* ---- rsm_points_occluded ------------------------------------------------- */

static rsm_occlusion_t occlusion(void)
{
    rsm_occlusion_t occ;
    occ.window = 2u;
    occ.span_m = 0.3f;
    occ.tol_m = 0.1f;
    occ.slope = 3.0f;
    occ.margin_m = 0.2f;
    occ.margin_rel = 0.05f;
    return occ;
}

/* Beam k at (k - n/2) degrees, at range r[k], seen from (0, 0). */
static void polar_points(rsm_point_t *p, const float *r, size_t n)
{
    size_t k;
    for (k = 0; k < n; ++k) {
        const float a = ((float)k - (float)(n / 2u)) * 0.0174533f;
        p[k].x = r[k] * cosf(a);
        p[k].y = r[k] * sinf(a);
    }
}

/* Ranges of the wall x = 2 (as wall_points). */
static void wall_ranges(float *r, size_t n)
{
    size_t k;
    for (k = 0; k < n; ++k) {
        r[k] = 2.0f / cosf(((float)k - (float)(n / 2u)) * 0.0174533f);
    }
}

void test_points_occluded_should_mark_returns_behind_a_wall_and_nothing_else(void)
{
    /* Beams 5 and 12, 13 (two in a row: each has a wall return within two
     * beams on either side) see 1.5 to 4 m beyond the wall: phantoms. Beam
     * 17 sees 1.2 m short of it (a thin object in front is possible) and
     * beam 8 only 0.15 m beyond it (range noise): neither is marked. */
    rsm_point_t p[21];
    float r[21];
    uint8_t mask[3];
    const rsm_occlusion_t occ = occlusion();
    size_t k;
    wall_ranges(r, 21u);
    r[5] += 4.0f;
    r[12] += 1.5f;
    r[13] += 2.5f;
    r[17] -= 1.2f;
    r[8] += 0.15f;
    polar_points(p, r, 21u);
    memset(mask, 0xFF, sizeof mask); /* every bit of the n is written */
    TEST_ASSERT_EQUAL_size_t(3u, rsm_points_occluded(p, 21u, &occ, mask));
    for (k = 0; k < 21u; ++k) {
        TEST_ASSERT_EQUAL_INT(k == 5u || k == 12u || k == 13u, marked(mask, k));
    }
    /* With one neighbour a side, a phantom beside another is not seen. */
    {
        rsm_occlusion_t one = occ;
        one.window = 1u;
        TEST_ASSERT_EQUAL_size_t(1u, rsm_points_occluded(p, 21u, &one, mask));
        TEST_ASSERT_TRUE(marked(mask, 5u));
    }
}

void test_points_occluded_should_keep_what_is_seen_through_a_doorway_or_past_an_edge(void)
{
    /* A wall 2 m ahead with a doorway 0.8 m wide (beams 28 to 50 see a
     * wall 5 m away through it), and on the right an edge: the wall ends at
     * beam 70 and beams 71 on see a wall 6 m away. Nothing is marked. */
    rsm_point_t p[81];
    float r[81];
    uint8_t mask[11];
    const rsm_occlusion_t occ = occlusion();
    size_t k;
    wall_ranges(r, 81u);
    for (k = 28u; k <= 50u; ++k) {
        r[k] *= 2.5f; /* the wall 5 m ahead */
    }
    for (k = 71u; k < 81u; ++k) {
        r[k] *= 3.0f; /* 6 m */
    }
    polar_points(p, r, 81u);
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_occluded(p, 81u, &occ, mask));
    /* A gap of two beams (7 cm) is not a doorway: what it sees is marked,
     * as the price of catching phantoms two in a row. */
    r[60] = 5.0f;
    r[61] = 5.0f;
    polar_points(p, r, 81u);
    TEST_ASSERT_EQUAL_size_t(2u, rsm_points_occluded(p, 81u, &occ, mask));
    TEST_ASSERT_TRUE(marked(mask, 60u) && marked(mask, 61u));
}

void test_points_occluded_should_follow_a_steep_wall_up_to_the_slope(void)
{
    /* The wall at 65 degrees incidence of the isolation test, with a
     * phantom 2 m behind beam 4: its neighbours lie 1.9 to 2.6 beam gaps
     * apart, one surface for slope 3, not for slope 1. */
    rsm_point_t p[9];
    uint8_t mask[2];
    rsm_occlusion_t occ = occlusion();
    steep_wall(p);
    p[4].x += 2.0f;
    occ.tol_m = 0.01f;
    occ.window = 1u;
    TEST_ASSERT_EQUAL_size_t(1u, rsm_points_occluded(p, 9u, &occ, mask));
    TEST_ASSERT_TRUE(marked(mask, 4u));
    occ.slope = 1.0f;
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_occluded(p, 9u, &occ, mask));
}

void test_points_occluded_should_mark_nothing_when_off_or_without_neighbours(void)
{
    rsm_point_t p[5];
    float r[5];
    uint8_t mask[1];
    rsm_occlusion_t occ = occlusion();
    wall_ranges(r, 5u);
    r[2] += 3.0f;
    polar_points(p, r, 5u);
    TEST_ASSERT_EQUAL_size_t(1u, rsm_points_occluded(p, 5u, &occ, mask));
    occ.window = 0u;
    mask[0] = 0xFF;
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_occluded(p, 5u, &occ, mask));
    TEST_ASSERT_EQUAL_HEX8(0u, mask[0]);
    occ.window = 2u;
    occ.span_m = 0.0f;
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_occluded(p, 5u, &occ, mask));
    occ.span_m = 0.3f;
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_occluded(NULL, 5u, &occ, mask));
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_occluded(p, 5u, NULL, mask));
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_occluded(p, 5u, &occ, NULL));
    /* The first and last points have no neighbour on one side. */
    TEST_ASSERT_EQUAL_size_t(0u, rsm_points_occluded(p, 2u, &occ, mask));
}

void test_points_occluded_should_take_a_wider_window_as_the_widest(void)
{
    /* Three phantoms in a row behind the wall: two neighbours a side see
     * only the middle one hidden, four see all three; a window wider than
     * RSM_OCCLUSION_MAX_WINDOW (4) is taken as 4. */
    rsm_point_t p[21];
    float r[21];
    uint8_t mask[3];
    rsm_occlusion_t occ = occlusion();
    wall_ranges(r, 21u);
    r[9] += 2.0f;
    r[10] += 3.0f;
    r[11] += 2.5f;
    polar_points(p, r, 21u);
    TEST_ASSERT_EQUAL_size_t(1u, rsm_points_occluded(p, 21u, &occ, mask));
    TEST_ASSERT_TRUE(marked(mask, 10u));
    occ.window = 4u;
    TEST_ASSERT_EQUAL_size_t(3u, rsm_points_occluded(p, 21u, &occ, mask));
    occ.window = 200u;
    TEST_ASSERT_EQUAL_size_t(3u, rsm_points_occluded(p, 21u, &occ, mask));
    TEST_ASSERT_TRUE(marked(mask, 9u) && marked(mask, 10u) && marked(mask, 11u));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_scan_limits_default_should_be_5_cm_to_20_m);
    RUN_TEST(test_scan_set_uniform_should_lay_out_beam_angles);
    RUN_TEST(test_scan_set_uniform_should_respect_capacity);
    RUN_TEST(test_scan_set_uniform_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_scan_trig_init_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_scan_reading_ok_should_count_each_reason_separately);
    RUN_TEST(test_scan_reading_ok_should_refuse_indices_past_the_count);
    RUN_TEST(test_scan_to_points_should_convert_usable_readings);
    RUN_TEST(test_scan_to_points_should_stop_at_cap);
    RUN_TEST(test_scan_to_points_should_handle_a_full_scan);
    RUN_TEST(test_scan_to_points_cached_should_equal_the_direct_conversion);
    RUN_TEST(test_scan_to_points_should_reject_bad_arguments);
    RUN_TEST(test_points_isolated_should_mark_a_phantom_and_not_the_wall);
    RUN_TEST(test_points_isolated_should_judge_from_the_given_origin);
    RUN_TEST(test_points_isolated_should_let_a_pair_confirm_itself_and_honour_agree);
    RUN_TEST(test_points_isolated_should_accept_steep_walls_up_to_the_slope);
    RUN_TEST(test_points_isolated_should_mark_nothing_when_off);
    RUN_TEST(test_points_occluded_should_mark_returns_behind_a_wall_and_nothing_else);
    RUN_TEST(test_points_occluded_should_keep_what_is_seen_through_a_doorway_or_past_an_edge);
    RUN_TEST(test_points_occluded_should_follow_a_steep_wall_up_to_the_slope);
    RUN_TEST(test_points_occluded_should_mark_nothing_when_off_or_without_neighbours);
    RUN_TEST(test_points_occluded_should_take_a_wider_window_as_the_widest);
    return UNITY_END();
}
