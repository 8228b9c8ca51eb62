/* The walls' grid (src/localizer/wallgrid.c) and the heading measurement it
 * makes (rsm_ekf_update_heading; the localizer's use of both is measured
 * on the full logs by the bench's clean runs: docs/robustness.md). */
#include <math.h>

#include "rsm/config.h"
#include "rsm/localizer.h"
#include "rsm/status.h"
#include "core/ekf.h"
#include "localizer/wallgrid.h"
#include "synth.h"
#include "unity.h"

#define DEG (RSM_PI / 180.0f)
#define QUARTER (0.5f * RSM_PI)
#define MAX_PTS 2048u
#define SPACING_M 0.02f

static rsm_point_t pts[MAX_PTS];
static const float corner[4][2] = {{-3.0f, -2.0f}, {3.0f, -2.0f}, {3.0f, 2.0f}, {-3.0f, 2.0f}};

void setUp(void)
{
}

void tearDown(void)
{
}

/* Points every SPACING_M along the walls of a 6 x 4 m room turned by rot,
 * wall after wall, as a laser at the room's centre would list them. */
static size_t room_points(float rot)
{
    const float co = cosf(rot);
    const float si = sinf(rot);
    size_t n = 0;
    size_t k;
    for (k = 0; k < 4u; ++k) {
        const float *a = corner[k];
        const float *b = corner[(k + 1u) % 4u];
        const float len = hypotf(b[0] - a[0], b[1] - a[1]);
        float s;
        for (s = 0.0f; s < len && n < MAX_PTS; s += SPACING_M) {
            const float x = a[0] + (b[0] - a[0]) * s / len;
            const float y = a[1] + (b[1] - a[1]) * s / len;
            pts[n].x = co * x - si * y;
            pts[n].y = si * x + co * y;
            ++n;
        }
    }
    return n;
}

void test_wallgrid_should_find_a_turned_rooms_walls_modulo_a_quarter_turn(void)
{
    const float rots[4] = {0.3f, -0.6f, 1.2f, 2.0f};
    size_t k;
    for (k = 0; k < 4u; ++k) {
        const size_t n = room_points(rots[k]);
        float dir;
        float support;
        float straight;
        rsm_wallgrid_direction(pts, n, 0.0f, RSM_PI, &dir, &support, &straight);
        TEST_ASSERT_FLOAT_WITHIN(0.01f * DEG, 0.0f, rsm_wallgrid_diff(dir, rots[k]));
        /* Every stretch but those round a corner is straight and counts;
         * they overlap (each spans two spacings), so the walls count twice. */
        TEST_ASSERT_FLOAT_WITHIN(0.5f, 40.0f, straight);
        TEST_ASSERT_EQUAL_FLOAT(straight, support);
    }
}

void test_wallgrid_should_take_only_walls_within_the_window(void)
{
    const float rot = 0.3f;
    const size_t n = room_points(rot);
    float dir;
    float support;
    float straight;
    /* Expected 1 degree off, within a 2 degree window: the walls' own
     * direction comes out. */
    rsm_wallgrid_direction(pts, n, rot + 1.0f * DEG + QUARTER, 2.0f * DEG, &dir, &support, &straight);
    TEST_ASSERT_FLOAT_WITHIN(0.01f * DEG, 0.0f, rsm_wallgrid_diff(dir, rot));
    TEST_ASSERT_FLOAT_WITHIN(0.5f, 40.0f, support);
    /* Expected 5 degrees off: no wall in the window, the expectation back. */
    rsm_wallgrid_direction(pts, n, rot + 5.0f * DEG, 2.0f * DEG, &dir, &support, &straight);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, support);
    TEST_ASSERT_EQUAL_FLOAT(rot + 5.0f * DEG, dir);
    TEST_ASSERT_FLOAT_WITHIN(0.5f, 40.0f, straight);
}

void test_wallgrid_should_see_no_grid_in_a_round_room(void)
{
    /* A round wall of 2 m radius: every stretch is straight within a
     * fraction of a millimetre, and they run every way, so a 2 degree
     * window holds a share of them far below the localizer's quarter. */
    size_t n = 0;
    float dir;
    float support;
    float straight;
    for (n = 0; n < 600u; ++n) {
        const float a = (float)n * SPACING_M / 2.0f;
        pts[n].x = 2.0f * cosf(a);
        pts[n].y = 2.0f * sinf(a);
    }
    rsm_wallgrid_direction(pts, n, 0.1f, 2.0f * DEG, &dir, &support, &straight);
    TEST_ASSERT_TRUE(straight > 10.0f);
    TEST_ASSERT_TRUE(support < 0.1f * straight);
}

void test_wallgrid_should_skip_bends_and_gaps(void)
{
    /* Three points round a right angle, and two far apart: no stretch. */
    const rsm_point_t bend[3] = {{0.0f, 0.0f}, {0.1f, 0.0f}, {0.1f, 0.1f}};
    const rsm_point_t gap[3] = {{0.0f, 0.0f}, {0.5f, 0.0f}, {1.0f, 0.0f}};
    float dir;
    float support;
    float straight;
    rsm_wallgrid_direction(bend, 3u, 0.0f, RSM_PI, &dir, &support, &straight);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, straight);
    rsm_wallgrid_direction(gap, 3u, 0.0f, RSM_PI, &dir, &support, &straight);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, straight);
    rsm_wallgrid_direction(gap, 2u, 0.0f, RSM_PI, &dir, &support, &straight);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, straight);
}

void test_wallgrid_diff_should_wrap_into_a_quarter_turn(void)
{
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, rsm_wallgrid_diff(0.1f + QUARTER, 0.1f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, rsm_wallgrid_diff(0.1f - 3.0f * QUARTER, 0.1f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, -0.7f, rsm_wallgrid_diff(0.0f, 0.7f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, QUARTER - 0.8f, rsm_wallgrid_diff(0.0f, 0.8f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.02f, rsm_wallgrid_diff(0.02f + 2.0f * QUARTER, 0.0f));
}

void test_ekf_heading_pull_should_move_as_an_update_and_keep_p(void)
{
    /* P with heading correlated to x: K = P's last column / (P33 + r). */
    const float p0[9] = {0.01f, 0.0f, 0.01f, 0.0f, 0.01f, 0.0f, 0.01f, 0.0f, 0.04f};
    const rsm_pose_t x0 = {1.0f, 2.0f, 0.5f};
    rsm_ekf_t ekf;
    size_t i;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_pull_heading(&ekf, 0.1f, 0.04f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.55f, ekf.x.theta);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0125f, ekf.x.x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.0f, ekf.x.y);
    for (i = 0; i < 9u; ++i) {
        TEST_ASSERT_EQUAL_FLOAT(p0[i], ekf.p[i]);
    }
    /* Refused, and nothing changed: no variance, a NaN innovation. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_pull_heading(&ekf, 0.1f, 0.0f));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_pull_heading(&ekf, NAN, 0.01f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.55f, ekf.x.theta);
    TEST_ASSERT_EQUAL_UINT32(2u, ekf.rejected);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_pull_heading(NULL, 0.1f, 0.01f));
}

/* The localizer learns the grid from its first scans: a robot driving
 * slowly through a room turned by 0.2 rad has the room's direction after
 * 20 scans, and none with the measurement off or standing still (the same
 * walls seen again say nothing new). */
static void learn(float sigma, float step_m, uint32_t *scans, float *ref)
{
    static rsm_localizer_t loc;
    static rsm_scan_t scan;
    static rsm_synth_segment_t walls[4];
    rsm_synth_world_t room;
    rsm_localizer_config_t cfg = rsm_localizer_config_default();
    rsm_synth_scan_config_t scan_cfg = rsm_synth_scan_config_default();
    const float p0[9] = {1.0e-4f, 0.0f, 0.0f, 0.0f, 1.0e-4f, 0.0f, 0.0f, 0.0f, 1.0e-4f};
    const float rot = 0.2f;
    rsm_pose_t truth = {0.3f, -0.2f, 0.05f};
    const float co = cosf(rot);
    const float si = sinf(rot);
    size_t k;
    uint32_t s;
    for (k = 0; k < 4u; ++k) {
        const float *a = corner[k];
        const float *b = corner[(k + 1u) % 4u];
        walls[k].x0 = co * a[0] - si * a[1];
        walls[k].y0 = si * a[0] + co * a[1];
        walls[k].x1 = co * b[0] - si * b[1];
        walls[k].y1 = si * b[0] + co * b[1];
    }
    room.seg = walls;
    room.count = 4u;
    cfg.wall_sigma_rad = sigma;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &truth, p0));
    scan_cfg.beams = RSM_MAX_BEAMS < 361 ? (size_t)RSM_MAX_BEAMS : 361u;
    for (s = 0; s < 25u; ++s) {
        rsm_localizer_report_t rep;
        if (s > 0u) {
            const rsm_pose_t before = truth;
            rsm_motion_t u;
            truth.x += step_m * cosf(truth.theta);
            truth.y += step_m * sinf(truth.theta);
            u = rsm_synth_motion(&before, &truth, NULL);
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_motion(&loc, &u));
        }
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&room, &truth, &scan_cfg, NULL, 0u, &scan));
        scan.stamp_us = (uint64_t)(s + 1u) * 200000u;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &rep));
        TEST_ASSERT_EQUAL_INT(s == 0u ? RSM_SCAN_FIRST : RSM_SCAN_ACCEPTED, rep.outcome);
    }
    *scans = loc.state.persistent.wall_scans;
    *ref = loc.state.persistent.wall_ref;
}

void test_localizer_should_learn_the_walls_grid_from_its_first_scans(void)
{
    uint32_t scans;
    float ref;
    learn(0.0015f, 0.01f, &scans, &ref);
    TEST_ASSERT_EQUAL_UINT32(20u, scans);
    TEST_ASSERT_FLOAT_WITHIN(0.05f * DEG, 0.0f, rsm_wallgrid_diff(ref, 0.2f));
    learn(0.0f, 0.01f, &scans, &ref);
    TEST_ASSERT_EQUAL_UINT32(0u, scans);
    /* Standing still: the first scan only. */
    learn(0.0015f, 0.0f, &scans, &ref);
    TEST_ASSERT_EQUAL_UINT32(1u, scans);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_wallgrid_should_find_a_turned_rooms_walls_modulo_a_quarter_turn);
    RUN_TEST(test_wallgrid_should_take_only_walls_within_the_window);
    RUN_TEST(test_wallgrid_should_see_no_grid_in_a_round_room);
    RUN_TEST(test_wallgrid_should_skip_bends_and_gaps);
    RUN_TEST(test_wallgrid_diff_should_wrap_into_a_quarter_turn);
    RUN_TEST(test_ekf_heading_pull_should_move_as_an_update_and_keep_p);
    RUN_TEST(test_localizer_should_learn_the_walls_grid_from_its_first_scans);
    return UNITY_END();
}
