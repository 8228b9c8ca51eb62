/* Unit tests for src/scan.c: beam layout, reading validity and conversion to
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

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_scan_limits_default_should_be_5_cm_to_20_m);
    RUN_TEST(test_scan_set_uniform_should_lay_out_beam_angles);
    RUN_TEST(test_scan_set_uniform_should_respect_capacity);
    RUN_TEST(test_scan_reading_ok_should_count_each_reason_separately);
    RUN_TEST(test_scan_reading_ok_should_refuse_indices_past_the_count);
    RUN_TEST(test_scan_to_points_should_convert_usable_readings);
    RUN_TEST(test_scan_to_points_should_stop_at_cap);
    RUN_TEST(test_scan_to_points_should_handle_a_full_scan);
    RUN_TEST(test_scan_to_points_should_reject_bad_arguments);
    return UNITY_END();
}
