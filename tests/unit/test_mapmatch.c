/* Matching a scan to the persistent map: convergence from a wrong
 * prediction, the heading fan, the corridor (only the constrained
 * directions move, and the covariance says so), large heading errors
 * with and without the heading fan, the spread of a scan's surfaces and
 * the drag along a bare corridor it stops, the wide recovery search, the
 * share of readings on walls (the same however often the walls were seen),
 * an empty map, configuration checks and determinism. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "rsm/config.h"
#include "map/mapmatch.h"
#include "rsm/scan.h"
#include "rsm/status.h"
#include "map/tilemap.h"
#include "map/tmap_read.h"
#include "core/fmath.h"
#include "synth.h"
#include "unity.h"

#define DEG (RSM_PI / 180.0f)

static rsm_tmap_t map;
static rsm_tmap_config_t mcfg;
static rsm_mapmatch_config_t cfg;
static rsm_scan_t scan;
static rsm_point_t pts[RSM_MAX_BEAMS];
static rsm_point_t world_pts[RSM_MAX_BEAMS];
static rsm_synth_world_t world;
static rsm_synth_scan_config_t scfg;

/* The map frame is the synthetic world's shifted by half a cell, so that
 * the walls (on multiples of 5 cm) run through cell centres instead of
 * along cell borders, where each wall would read half a cell off (that
 * quantisation is what real walls average over). */
#define SHIFT (0.5f * RSM_TMAP_CELL_M)

static rsm_pose_t in_map(const rsm_pose_t *p)
{
    rsm_pose_t q = *p;
    q.x += SHIFT;
    q.y += SHIFT;
    return q;
}

/* A generous prior: 0.3 m and 10 degrees (std). */
static const float p_wide[9] = {0.09f, 0.0f, 0.0f, 0.0f, 0.09f, 0.0f, 0.0f, 0.0f, 0.0305f};

void setUp(void)
{
    mcfg = rsm_tmap_config_default();
    cfg = rsm_mapmatch_config_default();
    world = rsm_synth_world_room();
    scfg = rsm_synth_scan_config_default();
}

void tearDown(void)
{
}

/* Robot-frame points of a scan from pose within lim, with range noise
 * (scfg.sigma_m) drawn from rng, exact without one. */
static size_t scan_points(const rsm_pose_t *pose, rsm_synth_rng_t *rng, const rsm_scan_limits_t *lim)
{
    int n;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, pose, &scfg, rng, 0u, &scan));
    n = rsm_scan_to_points(&scan, lim, pts, RSM_MAX_BEAMS, NULL);
    TEST_ASSERT_GREATER_THAN_INT(20, n);
    return (size_t)n;
}

/* Robot-frame points of an exact scan from pose. */
static size_t points_at(const rsm_pose_t *pose)
{
    const rsm_scan_limits_t lim = rsm_scan_limits_default();
    return scan_points(pose, NULL, &lim);
}

/* A new map with exact scans from each pose written into it reps times. */
static void write_map(const rsm_pose_t *poses, size_t count, int reps)
{
    size_t i;
    int rep;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &mcfg));
    for (rep = 0; rep < reps; ++rep) {
        for (i = 0; i < count; ++i) {
            const size_t n = points_at(&poses[i]);
            const rsm_pose_t m = in_map(&poses[i]);
            const rsm_point_t o = {m.x, m.y};
            size_t k;
            for (k = 0; k < n; ++k) {
                world_pts[k] = rsm_pose_apply(&m, &pts[k]);
            }
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, world_pts, n));
        }
    }
}

/* ... twice. */
static void build_map(const rsm_pose_t *poses, size_t count)
{
    write_map(poses, count, 2);
}

/* What the tiny test pool does with a world it cannot hold: it has reused
 * slots, and a match is still a finite pose within reach of the
 * prediction (3 std of the prior), not a crash or a jump. The scenario's
 * accuracy is asserted with the shipped pool sizes. */
#if RSM_TMAP_TILES < 256
static void tiny_pool_outcome(const rsm_pose_t *truth_w, const rsm_pose_t *pred, const float prior[9])
{
    rsm_mapmatch_result_t res;
    const size_t n = points_at(truth_w);
    TEST_ASSERT_GREATER_THAN_UINT32(0u, map.counters.evicted);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)RSM_TMAP_TILES, map.used);
    (void)rsm_mapmatch(&map, &cfg, pts, n, pred, prior, NULL, NULL, &res);
    TEST_ASSERT_TRUE(rsm_synth_pose_finite(&res.pose));
    TEST_ASSERT_TRUE(rsm_synth_pos_error(&res.pose, pred) < 3.0f * sqrtf(prior[0] + prior[4]));
    TEST_ASSERT_TRUE(rsm_synth_angle_error(&res.pose, pred) < 3.0f * sqrtf(prior[8]));
}
#endif

static const rsm_pose_t room_poses[] = {{-1.2f, 0.6f, 0.0f}, {0.0f, -0.6f, 1.2f}, {1.5f, -0.9f, 2.5f},
                                        {-1.5f, -1.0f, -0.7f}, {0.2f, 1.0f, -2.0f}};

static void assert_converges(const rsm_pose_t *truth_w, const rsm_pose_t *pred_w, float tol_m, float tol_rad)
{
    char msg[160];
    rsm_mapmatch_result_t res;
    const size_t n = points_at(truth_w);
    const rsm_pose_t t = in_map(truth_w);
    const rsm_pose_t pr = in_map(pred_w);
    const rsm_pose_t *truth = &t;
    const rsm_pose_t *pred = &pr;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, pred, p_wide, NULL, NULL, &res));
    snprintf(msg, sizeof msg, "from %.3f %.3f %.2f deg: got %.4f %.4f %.3f deg, truth %.3f %.3f %.2f deg",
             (double)pred->x, (double)pred->y, (double)(pred->theta / DEG), (double)res.pose.x, (double)res.pose.y,
             (double)(res.pose.theta / DEG), (double)truth->x, (double)truth->y, (double)(truth->theta / DEG));
    TEST_ASSERT_TRUE_MESSAGE(rsm_synth_pos_error(&res.pose, truth) < tol_m, msg);
    TEST_ASSERT_TRUE_MESSAGE(rsm_synth_angle_error(&res.pose, truth) < tol_rad, msg);
    if (map.counters.evicted > 0u) {
        /* The test configuration's pool could not hold this world: the
         * pose is still found from what is left, but less of the scan lies
         * on the map and the fit is looser. */
        return;
    }
    TEST_ASSERT_TRUE_MESSAGE(res.hit > 0.6f, msg);
    TEST_ASSERT_GREATER_THAN_UINT32(20u, res.used);
    /* The posterior is tighter than the prior in every direction. */
    TEST_ASSERT_TRUE_MESSAGE(res.cov[0] < 0.1f * p_wide[0] && res.cov[4] < 0.1f * p_wide[4] &&
                                 res.cov[8] < 0.1f * p_wide[8],
                             msg);
}

void test_mapmatch_should_converge_from_a_wrong_prediction(void)
{
    const rsm_pose_t truth = {-0.3f, 0.1f, 0.4f};
    rsm_pose_t pred;
    build_map(room_poses, sizeof room_poses / sizeof room_poses[0]);
    assert_converges(&truth, &truth, 0.02f, 0.5f * DEG);
    /* Within the coarsest level's basin: 15 cm and 3 degrees off. */
    pred.x = truth.x + 0.15f;
    pred.y = truth.y - 0.1f;
    pred.theta = truth.theta + 3.0f * DEG;
    assert_converges(&truth, &pred, 0.02f, 0.5f * DEG);
    pred.x = truth.x - 0.1f;
    pred.y = truth.y + 0.12f;
    pred.theta = truth.theta - 2.0f * DEG;
    assert_converges(&truth, &pred, 0.02f, 0.5f * DEG);
}

/* The descent starts on the coarsest level only when the prior needs its
 * basin (cfg.basin): a tight prior starts finer and ends where the full
 * descent does; a wide one, or basin 0, starts on the coarsest. */
void test_mapmatch_should_start_on_the_level_the_prior_needs(void)
{
    /* 5 mm and 0.2 degrees (std). */
    static const float p_tight[9] = {2.5e-5f, 0.0f, 0.0f, 0.0f, 2.5e-5f, 0.0f, 0.0f, 0.0f, 1.2e-5f};
    const rsm_pose_t truth_w = {-0.3f, 0.1f, 0.4f};
    const rsm_pose_t truth = in_map(&truth_w);
    const uint32_t coarsest = (uint32_t)mcfg.levels - 1u;
    rsm_mapmatch_result_t tight;
    rsm_mapmatch_result_t all;
    rsm_mapmatch_result_t wide;
    size_t n;
    build_map(room_poses, sizeof room_poses / sizeof room_poses[0]);
    n = points_at(&truth_w);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &truth, p_tight, NULL, NULL, &tight));
    TEST_ASSERT_LESS_THAN_UINT32(coarsest, tight.top);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &truth, p_wide, NULL, NULL, &wide));
    TEST_ASSERT_EQUAL_UINT32(coarsest, wide.top);
    cfg.basin = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &truth, p_tight, NULL, NULL, &all));
    TEST_ASSERT_EQUAL_UINT32(coarsest, all.top);
    TEST_ASSERT_TRUE(rsm_synth_pos_error(&tight.pose, &all.pose) < 0.005f);
    TEST_ASSERT_TRUE(rsm_synth_angle_error(&tight.pose, &all.pose) < 0.1f * DEG);
    TEST_ASSERT_TRUE(rsm_synth_pos_error(&tight.pose, &truth) < 0.02f);
    /* Fewer levels, fewer steps. */
    TEST_ASSERT_LESS_THAN_UINT32(all.iterations, tight.iterations);
    /* A negative basin is refused. */
    cfg.basin = -1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_check(&cfg));
}

/* A 16 m x 10 m hall with four boxes: far walls, where a heading error of
 * a few degrees moves the points by more than the coarsest cell; the boxes
 * nearby still lead the coarse levels there. */
static const rsm_synth_segment_t hall[] = {
    {-8.0f, -5.0f, 8.0f, -5.0f}, {8.0f, -5.0f, 8.0f, 5.0f},   {8.0f, 5.0f, -8.0f, 5.0f},   {-8.0f, 5.0f, -8.0f, -5.0f},
    {3.0f, 2.0f, 4.0f, 2.0f},    {4.0f, 2.0f, 4.0f, 3.0f},    {4.0f, 3.0f, 3.0f, 3.0f},    {3.0f, 3.0f, 3.0f, 2.0f},
    {-5.0f, -3.0f, -4.0f, -3.0f}, {-4.0f, -3.0f, -4.0f, -2.0f}, {-4.0f, -2.0f, -5.0f, -2.0f}, {-5.0f, -2.0f, -5.0f, -3.0f},
    {-2.0f, 3.0f, -1.0f, 3.0f},  {-1.0f, 3.0f, -1.0f, 3.5f},  {-1.0f, 3.5f, -2.0f, 3.5f},  {-2.0f, 3.5f, -2.0f, 3.0f},
    {5.0f, -4.0f, 6.0f, -4.0f},  {6.0f, -4.0f, 6.0f, -3.0f},  {6.0f, -3.0f, 5.0f, -3.0f},  {5.0f, -3.0f, 5.0f, -4.0f}};

void test_mapmatch_should_recover_large_heading_errors_in_a_hall(void)
{
    const rsm_pose_t poses[] = {{0.0f, 0.0f, 0.0f}, {0.5f, 0.5f, 1.6f}, {-0.5f, -0.5f, 3.1f}, {0.0f, 0.5f, -1.6f}};
    const rsm_pose_t truth = {0.2f, -0.1f, 0.3f};
    rsm_pose_t pred = truth;
    const rsm_synth_world_t w = {hall, sizeof hall / sizeof hall[0]};
    world = w;
    build_map(poses, sizeof poses / sizeof poses[0]);
    pred.theta = truth.theta + 5.0f * DEG;
#if RSM_TMAP_TILES < 256
    tiny_pool_outcome(&truth, &pred, p_wide);
    return;
#endif
    TEST_ASSERT_EQUAL_UINT32(0u, map.counters.evicted);
    assert_converges(&truth, &pred, 0.02f, 0.3f * DEG);
    pred.theta = truth.theta - 5.0f * DEG;
    assert_converges(&truth, &pred, 0.02f, 0.3f * DEG);
    /* Ten degrees: the coarse levels reach that far by themselves; with
     * the heading fan too (it covers 5.7 of them, the descent the rest). */
    pred.theta = truth.theta + 10.0f * DEG;
    assert_converges(&truth, &pred, 0.02f, 0.3f * DEG);
    cfg.fan = 1u;
    assert_converges(&truth, &pred, 0.02f, 0.3f * DEG);
    pred.theta = truth.theta - 5.0f * DEG;
    assert_converges(&truth, &pred, 0.02f, 0.3f * DEG);
}

void test_mapmatch_should_move_only_across_a_corridor(void)
{
    /* In a straight corridor the scan pins the sideways position and the
     * heading; along it the prediction stays within its uncertainty (5 cm
     * here, as the filter would have it). The walls' uneven hit counts (far
     * returns are sparser than the cells) are all the scan has to say along
     * it: a few per cent of its information across, which still leaves the
     * variance along many times the variance across. */
    const float p_corr[9] = {0.0025f, 0.0f, 0.0f, 0.0f, 0.09f, 0.0f, 0.0f, 0.0f, 0.0305f};
    static const rsm_synth_segment_t walls[] = {{-20.0f, -0.6f, 20.0f, -0.6f}, {-20.0f, 0.6f, 20.0f, 0.6f}};
    const rsm_synth_world_t corridor = {walls, 2u};
    rsm_pose_t poses[13];
    size_t i;
    const rsm_pose_t truth_w = {0.5f, 0.05f, 0.02f};
    const rsm_pose_t truth = in_map(&truth_w);
    rsm_pose_t pred;
    rsm_mapmatch_result_t res;
    size_t n;
    world = corridor;
    scfg.max_range_m = 8.0f; /* the corridor's ends are out of sight */
    for (i = 0; i < 13u; ++i) {
        poses[i].x = -6.0f + (float)i;
        poses[i].y = 0.1f * (float)((int)(i % 3u) - 1);
        poses[i].theta = 0.05f * (float)((int)(i % 5u) - 2);
    }
    build_map(poses, 13u);
    pred.x = truth.x + 0.2f;
    pred.y = truth.y + 0.08f;
    pred.theta = truth.theta + 1.5f * DEG;
    n = points_at(&truth_w);
#if RSM_TMAP_TILES < 256
    tiny_pool_outcome(&truth_w, &pred, p_corr);
    return;
#endif
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &pred, p_corr, NULL, NULL, &res));
    TEST_ASSERT_FLOAT_WITHIN(0.01f, truth.y, res.pose.y);
    TEST_ASSERT_FLOAT_WITHIN(0.3f * DEG, truth.theta, res.pose.theta);
    TEST_ASSERT_FLOAT_WITHIN(0.1f, pred.x, res.pose.x);
    TEST_ASSERT_EQUAL_UINT32(0u, map.counters.evicted);
    TEST_ASSERT_TRUE(res.cov[4] < 0.01f * p_corr[4]);
    TEST_ASSERT_TRUE(res.cov[0] > 20.0f * res.cov[4]);
    TEST_ASSERT_TRUE(res.info[0] < 0.05f * res.info[4]);
    /* Unpinned along the corridor, the scan still places the sideways
     * position and the heading; along it the estimate and its variance are
     * the prediction's. */
    {
        const rsm_mapmatch_unpin_t un = {{1.0f, 0.0f}, 1.0f};
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &pred, p_corr, NULL, &un, &res));
    }
    TEST_ASSERT_FLOAT_WITHIN(0.01f, truth.y, res.pose.y);
    TEST_ASSERT_FLOAT_WITHIN(0.3f * DEG, truth.theta, res.pose.theta);
    TEST_ASSERT_FLOAT_WITHIN(0.005f, pred.x, res.pose.x);
    TEST_ASSERT_TRUE(res.info[0] < 1e-3f * res.info[4]);
    TEST_ASSERT_TRUE(res.cov[0] > 0.9f * p_corr[0]);
}

/* Robot-frame points of a noisy scan (range noise sigma_m) from pose in
 * a world; beams that see nothing within 7.9 m are dropped. */
static size_t noisy_points_at(const rsm_pose_t *pose, rsm_synth_rng_t *rng)
{
    const rsm_scan_limits_t lim = {0.05f, 7.9f};
    return scan_points(pose, rng, &lim);
}

void test_mapmatch_spread_should_tell_a_corridor_from_a_room(void)
{
    static const rsm_synth_segment_t walls[] = {{-20.0f, -1.0f, 40.0f, -1.0f}, {-20.0f, 1.0f, 40.0f, 1.0f}};
    const rsm_synth_world_t corridor = {walls, 2u};
    const rsm_pose_t along = {0.0f, 0.2f, 0.0f};
    const rsm_pose_t turned = {0.0f, 0.0f, 0.5f};
    const rsm_pose_t in_room = {0.3f, -0.2f, 0.4f};
    rsm_synth_rng_t rng;
    rsm_mapmatch_unpin_t un;
    float dir[2];
    float spread;
    size_t n;
    rsm_synth_rng_seed(&rng, 3u);
    scfg.max_range_m = 8.0f;
    scfg.sigma_m = 0.03f;
    world = corridor;
    /* Every chord runs along the corridor, up to the range noise. */
    n = noisy_points_at(&along, &rng);
    spread = rsm_mapmatch_spread(pts, n, dir);
    TEST_ASSERT_TRUE(spread < 0.02f);
    TEST_ASSERT_FLOAT_WITHIN(0.01f, 1.0f, fabsf(dir[0]));
    /* Turned by 0.5 rad, the robot sees the corridor at -0.5 rad; the
     * unpinning is whole, along the world's x. */
    n = noisy_points_at(&turned, &rng);
    TEST_ASSERT_TRUE(rsm_mapmatch_spread(pts, n, dir) < 0.02f);
    TEST_ASSERT_FLOAT_WITHIN(0.02f, 0.5f, fabsf(atan2f(dir[1], dir[0]) - (dir[0] < 0.0f ? -RSM_PI : 0.0f)));
    rsm_mapmatch_unpin_for(&cfg, pts, n, turned.theta, &un);
    TEST_ASSERT_EQUAL_FLOAT(1.0f, un.frac);
    TEST_ASSERT_FLOAT_WITHIN(0.01f, 1.0f, fabsf(un.dir[0]));
    /* Switched off, nothing is unpinned. */
    cfg.unpin_hi = 0.0f;
    rsm_mapmatch_unpin_for(&cfg, pts, n, turned.theta, &un);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, un.frac);
    cfg = rsm_mapmatch_config_default();
    /* A room's walls run both ways: pinned. */
    world = rsm_synth_world_room();
    n = noisy_points_at(&in_room, &rng);
    TEST_ASSERT_TRUE(rsm_mapmatch_spread(pts, n, dir) > 0.2f);
    rsm_mapmatch_unpin_for(&cfg, pts, n, in_room.theta, &un);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, un.frac);
    /* No chord at all (one point; points too far apart to be a surface):
     * nothing says the scan is one-sided. */
    TEST_ASSERT_EQUAL_FLOAT(1.0f, rsm_mapmatch_spread(pts, 1u, dir));
    TEST_ASSERT_EQUAL_FLOAT(1.0f, rsm_mapmatch_spread(pts, 0u, dir));
    {
        const rsm_point_t apart[3] = {{1.0f, 0.0f}, {1.0f, 1.0f}, {1.0f, 2.0f}};
        TEST_ASSERT_EQUAL_FLOAT(1.0f, rsm_mapmatch_spread(apart, 3u, dir));
    }
}

/* Drives 8 m of a bare corridor with exact odometry, matching each noisy
 * scan against the map written so far (every fifth scan, as the localizer
 * writes every 0.4 m) with the prediction from the last estimate; returns
 * how far the estimate ends behind the truth along the corridor. */
static float corridor_drive(int unpinned)
{
    static const rsm_synth_segment_t walls[] = {{-20.0f, -1.0f, 40.0f, -1.0f}, {-20.0f, 1.0f, 40.0f, 1.0f}};
    const rsm_synth_world_t corridor = {walls, 2u};
    /* 2 cm and 1 degree a scan. */
    const float p_step[9] = {0.0004f, 0.0f, 0.0f, 0.0f, 0.0004f, 0.0f, 0.0f, 0.0f, 0.0003f};
    rsm_synth_rng_t rng;
    rsm_pose_t est = {0.0f, 0.0f, 0.0f};
    int i;
    world = corridor;
    scfg.max_range_m = 8.0f;
    scfg.sigma_m = 0.02f;
    rsm_synth_rng_seed(&rng, 7u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &mcfg));
    for (i = 0; i <= 100; ++i) {
        const rsm_pose_t truth = {0.08f * (float)i, 0.0f, 0.0f};
        const size_t n = noisy_points_at(&truth, &rng);
        if (i > 0) {
            rsm_mapmatch_result_t res;
            rsm_mapmatch_unpin_t un;
            est.x += 0.08f; /* exact odometry */
            rsm_mapmatch_unpin_for(&cfg, pts, n, est.theta, &un);
            TEST_ASSERT_EQUAL_INT(RSM_OK,
                                  rsm_mapmatch(&map, &cfg, pts, n, &est, p_step, NULL, unpinned ? &un : NULL, &res));
            est = res.pose;
        }
        if (i % 5 == 0) {
            const rsm_point_t o = {est.x, est.y};
            size_t k;
            for (k = 0; k < n; ++k) {
                world_pts[k] = rsm_pose_apply(&est, &pts[k]);
            }
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, world_pts, n));
        }
    }
    return 8.0f - est.x;
}

void test_mapmatch_should_not_drag_a_scan_back_along_a_bare_corridor(void)
{
    /* How a wall looks in the map depends on the poses it was written
     * from, and a later scan reads gradients along it that pull it back
     * towards them: plain scan-to-map matching lags behind the robot in a
     * featureless corridor even with exact odometry. Unpinned, the
     * position along the corridor is the prediction's, and the estimate
     * keeps odometry's progress (up to the heading's random walk: the
     * prior allows 1 degree a scan). */
    const float plain = corridor_drive(0);
    const float unpinned = corridor_drive(1);
    char msg[96];
    snprintf(msg, sizeof msg, "behind after 8 m: %.4f m plain, %.4f m unpinned", (double)plain, (double)unpinned);
    printf("%s\n", msg);
    TEST_ASSERT_TRUE_MESSAGE(fabsf(unpinned) < 0.05f, msg);
    TEST_ASSERT_TRUE_MESSAGE(plain > 0.5f && plain > 10.0f * fabsf(unpinned), msg);
}

void test_mapmatch_search_should_find_a_pose_a_metre_off(void)
{
    const size_t ALL = RSM_MAPMATCH_SEARCH_POINTS; /* every point the search may score */
    const rsm_pose_t truth_w = {-0.5f, 0.3f, 0.3f};
    const rsm_pose_t truth = in_map(&truth_w);
    rsm_pose_t pred = truth;
    rsm_pose_t best;
    rsm_mapmatch_result_t res;
    size_t n;
    float coarse;
    build_map(room_poses, sizeof room_poses / sizeof room_poses[0]);
    coarse = rsm_tmap_cell(&map, (uint32_t)mcfg.levels - 1u);
    pred.x += 0.7f;
    pred.y -= 0.5f;
    pred.theta += 4.0f * DEG;
    n = points_at(&truth_w);
    TEST_ASSERT_EQUAL_INT(1, rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, cfg.search_rad, &best, 1u, ALL));
    TEST_ASSERT_TRUE(rsm_synth_pos_error(&best, &truth) < coarse);
    TEST_ASSERT_TRUE(rsm_synth_angle_error(&best, &truth) < 2.0f * DEG);
    /* and the descent from there lands on it, under the prior widened by
     * the search radius as the localizer does */
    {
        float wide[9];
        memcpy(wide, p_wide, sizeof wide);
        wide[0] += 1.0f;
        wide[4] += 1.0f;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &pred, wide, &best, NULL, &res));
    }
    TEST_ASSERT_TRUE(rsm_synth_pos_error(&res.pose, &truth) < 0.02f);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(&map, &cfg, pts, n, &pred, -1.0f, 0.1f, &best, 1u, ALL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL,
                          rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 200.0f * coarse, 0.1f, &best, 1u, ALL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, -0.1f, &best, 1u, ALL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, 1.5f, &best, 1u, ALL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, 0.1f, &best, 0u, ALL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, 0.1f, &best,
                                                             RSM_MAPMATCH_MAX_CANDIDATES + 1u, ALL));
    /* At least one point scored, and no more than it holds room for. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, 0.1f, &best, 1u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL,
                          rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, 0.1f, &best, 1u, ALL + 1u));
    /* NULL map or config, and NaN radii, are refused before anything is
     * read or converted (the sanitizer build would flag either). */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(NULL, &cfg, pts, n, &pred, 1.0f, 0.1f, &best, 1u, ALL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(&map, NULL, pts, n, &pred, 1.0f, 0.1f, &best, 1u, ALL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(&map, &cfg, pts, n, &pred, NAN, 0.1f, &best, 1u, ALL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, NAN, &best, 1u, ALL));
    /* The candidates a recovery descends from: the same best first, then
     * others no closer than two grid steps to any kept one, so that a wrong
     * basin ranked first along a corridor does not hide the right one
     * behind its own neighbours. 5 x 5 positions: room for 9 at most. */
    {
        rsm_pose_t some[RSM_MAPMATCH_MAX_CANDIDATES];
        const int found =
            rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, cfg.search_rad, some, RSM_MAPMATCH_MAX_CANDIDATES,
                                ALL);
        int a;
        int b;
        TEST_ASSERT_TRUE(found >= 2 && found <= 9);
        rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, cfg.search_rad, &best, 1u, RSM_MAPMATCH_SEARCH_POINTS);
        TEST_ASSERT_EQUAL_MEMORY(&best, &some[0], sizeof best);
        for (a = 0; a < found; ++a) {
            for (b = a + 1; b < found; ++b) {
                TEST_ASSERT_TRUE(fabsf(some[a].x - some[b].x) > 1.5f * coarse ||
                                 fabsf(some[a].y - some[b].y) > 1.5f * coarse);
            }
        }
    }
}

/* The coarse cost search_heading gives candidate (i, j) at heading theta
 * of a search around x0: each scored point's cell at x0, moved i, j, read
 * one by one (the search reads them a block at a time). */
static float candidate_cost(const rsm_pose_t *x0, float theta, int32_t i, int32_t j, size_t n, size_t most)
{
    const uint32_t level = (uint32_t)mcfg.levels - 1u;
    const size_t stride = n > most ? (n + most - 1u) / most : 1u;
    rsm_tmap_cursor_t cur;
    float cost = 0.0f;
    float c;
    float sn;
    size_t q;
    rsm_sincosf(theta, &sn, &c);
    rsm_tmap_cursor_init(&cur, level);
    for (q = 0; q < n; q += stride) {
        const int32_t gx = rsm_tmap_cell_of(x0->x + c * pts[q].x - sn * pts[q].y, map.inv_cell[level]) + i;
        const int32_t gy = rsm_tmap_cell_of(x0->y + sn * pts[q].x + c * pts[q].y, map.inv_cell[level]) + j;
        const float r = 1.0f - map.occ[rsm_tmap_slot_value(&map, rsm_tmap_cursor_slot(&map, &cur, gx, gy), gx, gy)];
        cost += r * r;
    }
    return cost;
}

/* Every candidate a search around truth_w (moved 0.3 m, -0.2 m) keeps, at
 * five headings, windows of 3 and 5 cells a side (within a coarse cell,
 * and 1 m), against candidate_cost; returns how many were checked. */
static size_t check_candidates(const rsm_pose_t *truth_w)
{
    const rsm_pose_t truth = in_map(truth_w);
    rsm_pose_t pred = truth;
    rsm_pose_t kept[RSM_MAPMATCH_MAX_CANDIDATES];
    float cost[RSM_MAPMATCH_MAX_CANDIDATES];
    int32_t ij[2 * RSM_MAPMATCH_MAX_CANDIDATES];
    const size_t n = points_at(truth_w);
    size_t r;
    size_t checked = 0;
    pred.x += 0.3f;
    pred.y -= 0.2f;
    for (r = 0; r < 2u; ++r) {
        const float radius = r == 0u ? rsm_tmap_cell(&map, (uint32_t)mcfg.levels - 1u) : 1.0f;
        int32_t a;
        for (a = -2; a <= 2; ++a) {
            size_t found = 0;
            size_t k;
            const float theta = rsm_wrap_angle(pred.theta + (float)a * cfg.search_step_rad);
            TEST_ASSERT_TRUE(rsm_mapmatch_search_part(&map, &cfg, pts, n, &pred, radius, cfg.search_rad, a, a + 1,
                                                      kept, cost, ij, RSM_MAPMATCH_MAX_CANDIDATES, &found, 32u) >= 1);
            for (k = 0; k < found; ++k) {
                const float want = candidate_cost(&pred, theta, ij[2 * k], ij[2 * k + 1u], n, 32u);
                TEST_ASSERT_TRUE(want == cost[k]);
                TEST_ASSERT_TRUE(kept[k].theta == theta);
                ++checked;
            }
        }
    }
    return checked;
}

void test_mapmatch_search_should_score_every_candidate_on_its_cells(void)
{
    /* The search sums a window of candidates a point at a time, a tile at
     * a time, and a block within one tile in one go: every kept
     * candidate's cost is the sum over its own cells, bit for bit, in the
     * room and in the hall with its boxes (cells that differ from their
     * neighbours). */
    const rsm_pose_t room_truth = {-0.5f, 0.3f, 0.3f};
    const rsm_pose_t hall_poses[] = {{0.0f, 0.0f, 0.0f}, {0.5f, 0.5f, 1.6f}, {-0.5f, -0.5f, 3.1f}};
    const rsm_pose_t hall_truth = {0.2f, -0.1f, 0.3f};
    const rsm_synth_world_t w = {hall, sizeof hall / sizeof hall[0]};
    build_map(room_poses, sizeof room_poses / sizeof room_poses[0]);
    TEST_ASSERT_TRUE(check_candidates(&room_truth) >= 10u);
    world = w;
    build_map(hall_poses, sizeof hall_poses / sizeof hall_poses[0]);
    TEST_ASSERT_TRUE(check_candidates(&hall_truth) >= 10u);
}

void test_mapmatch_search_should_read_a_window_across_tile_edges(void)
{
    /* Every cell of the coarse level around the origin holds its own
     * value (one tile left out), and a single point at the robot scores
     * the 3 x 3 window around each cell in turn: its block then lies at
     * every place a tile's edges can cut it (within a tile, across a column
     * edge, a row edge, both, into the missing tile), and the candidate
     * kept costs what its own cell does, bit for bit. */
    const uint32_t level = (uint32_t)mcfg.levels - 1u;
    const int32_t side = (int32_t)RSM_TMAP_TILE_SIDE;
    rsm_tmap_cursor_t cur;
    int32_t gx;
    int32_t gy;
    size_t checked = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &mcfg));
    rsm_tmap_cursor_init(&cur, level);
    for (gy = -2 * side; gy < 2 * side; ++gy) {
        for (gx = -2 * side; gx < 2 * side; ++gx) {
            if (!(gx >= side && gy < 0 && gy >= -side)) {
                const uint32_t v = 1u + (uint32_t)((gx * 7 + gy * 3 + 8 * side) % 15);
                TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_raise(&map, &cur, gx, gy, v));
            }
        }
    }
    pts[0].x = 0.0f;
    pts[0].y = 0.0f;
    for (gy = -side - 2; gy <= side + 1; ++gy) {
        for (gx = -side - 2; gx <= side + 1; ++gx) {
            const float cell = rsm_tmap_cell(&map, level);
            const rsm_pose_t pose = {((float)gx + 0.5f) * cell, ((float)gy + 0.5f) * cell, 0.0f};
            rsm_pose_t kept[RSM_MAPMATCH_MAX_CANDIDATES];
            float cost[RSM_MAPMATCH_MAX_CANDIDATES];
            int32_t ij[2 * RSM_MAPMATCH_MAX_CANDIDATES];
            size_t found = 0;
            size_t k;
            TEST_ASSERT_TRUE(rsm_mapmatch_search_part(&map, &cfg, pts, 1u, &pose, cell, 0.0f, 0, 1, kept, cost, ij,
                                                      RSM_MAPMATCH_MAX_CANDIDATES, &found, 1u) >= 1);
            for (k = 0; k < found; ++k) {
                TEST_ASSERT_TRUE(candidate_cost(&pose, 0.0f, ij[2 * k], ij[2 * k + 1u], 1u, 1u) == cost[k]);
                ++checked;
            }
        }
    }
    TEST_ASSERT_TRUE(checked >= (size_t)((2 * side + 4) * (2 * side + 4)));
}

void test_mapmatch_search_should_cost_places_the_map_does_not_hold_as_misses(void)
{
    /* Where no tile is held (10 m off the room) and where points lie
     * beyond the map's reach (a pose 2 m short of it: those read one
     * candidate at a time, rsm_tmap_occupancy_at), every scored point of every
     * candidate is a whole miss (occupancy 0): the cost is their count. */
    const rsm_pose_t truth = {-0.5f, 0.3f, 0.3f};
    rsm_pose_t far[2];
    size_t n;
    size_t stride;
    float reach;
    size_t f;
    build_map(room_poses, sizeof room_poses / sizeof room_poses[0]);
    n = points_at(&truth);
    stride = (n + 31u) / 32u;
    reach = (float)RSM_TMAP_CELL_LIMIT * rsm_tmap_cell(&map, (uint32_t)mcfg.levels - 1u);
    TEST_ASSERT_TRUE(map.occ[0] == 0.0f);
    far[0] = in_map(&truth);
    far[0].x += 10.0f;
    far[1] = far[0];
    far[1].x = reach - 2.0f;
    for (f = 0; f < 2u; ++f) {
        size_t r;
        for (r = 0; r < 2u; ++r) {
            const float radius = r == 0u ? rsm_tmap_cell(&map, (uint32_t)mcfg.levels - 1u) : 1.0f;
            rsm_pose_t kept[RSM_MAPMATCH_MAX_CANDIDATES];
            float cost[RSM_MAPMATCH_MAX_CANDIDATES];
            int32_t ij[2 * RSM_MAPMATCH_MAX_CANDIDATES];
            size_t found = 0;
            size_t k;
            TEST_ASSERT_TRUE(rsm_mapmatch_search_part(&map, &cfg, pts, n, &far[f], radius, cfg.search_rad, 0, 1, kept,
                                                      cost, ij, RSM_MAPMATCH_MAX_CANDIDATES, &found, 32u) >= 1);
            for (k = 0; k < found; ++k) {
                TEST_ASSERT_TRUE((float)((n + stride - 1u) / stride) == cost[k]);
            }
        }
    }
}

void test_mapmatch_search_should_find_in_parts_what_it_finds_whole(void)
{
    /* A recovery spreads its search over scans a few headings at a time:
     * the parts, in order, keep the candidates the whole search keeps, bit
     * for bit; and the fit at a pose is the descent's own at its end. */
    const rsm_pose_t truth_w = {-0.5f, 0.3f, 0.3f};
    const rsm_pose_t truth = in_map(&truth_w);
    rsm_pose_t pred = truth;
    rsm_pose_t whole[3];
    rsm_pose_t part[3];
    float cost[3];
    int32_t ij[6];
    size_t found = 0;
    uint32_t positions = 0;
    int32_t fan = 0;
    int32_t a;
    int n_whole;
    size_t n;
    rsm_mapmatch_result_t res;
    build_map(room_poses, sizeof room_poses / sizeof room_poses[0]);
    pred.x += 0.7f;
    pred.y -= 0.5f;
    pred.theta += 4.0f * DEG;
    n = points_at(&truth_w);
    n_whole = rsm_mapmatch_search(&map, &cfg, pts, n, &pred, 1.0f, cfg.search_rad, whole, 3u, 32u);
    TEST_ASSERT_TRUE(n_whole >= 2);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch_search_size(&map, &cfg, 1.0f, cfg.search_rad, &fan, &positions));
    TEST_ASSERT_EQUAL_INT32((int32_t)(cfg.search_rad / cfg.search_step_rad), fan);
    TEST_ASSERT_EQUAL_UINT32(25u, positions); /* 5 x 5 coarse cells within 1 m */
    for (a = -fan; a <= fan; a += 3) {
        TEST_ASSERT_TRUE(rsm_mapmatch_search_part(&map, &cfg, pts, n, &pred, 1.0f, cfg.search_rad, a, a + 3, part, cost,
                                                  ij, 3u, &found, 32u) >= 1);
    }
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n_whole, (uint32_t)found);
    TEST_ASSERT_EQUAL_MEMORY(whole, part, (size_t)n_whole * sizeof whole[0]);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search_size(&map, &cfg, -1.0f, 0.1f, &fan, &positions));
    found = 4u; /* more than k: a caller's state gone wrong */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_search_part(&map, &cfg, pts, n, &pred, 1.0f, 0.1f, 0, 1, part,
                                                                  cost, ij, 3u, &found, 32u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &pred, p_wide, &whole[0], NULL, &res));
    TEST_ASSERT_EQUAL_FLOAT(res.hit, rsm_mapmatch_fit(&map, pts, n, &res.pose));
    TEST_ASSERT_TRUE(res.passes > res.iterations);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_mapmatch_fit(&map, pts, 0u, &res.pose));
}

void test_mapmatch_wall_share_should_count_walls_not_how_often_they_were_seen(void)
{
    /* The share of readings within a cell of a wall: the same for a room
     * written once as for one written twice from the same poses, where the
     * fit (mean occupancy) grows with the hits; most readings at the truth,
     * few 0.3 m off both walls and turned; nothing on an empty map or for
     * no readings. */
    const rsm_pose_t truth_w = {-0.5f, 0.3f, 0.3f};
    const rsm_pose_t truth = in_map(&truth_w);
    uint32_t wall;
    rsm_pose_t off = truth;
    float once_share;
    float once_fit;
    float share;
    size_t n;
    write_map(room_poses, sizeof room_poses / sizeof room_poses[0], 1);
    wall = rsm_tmap_wall_value(&map);
    TEST_ASSERT_EQUAL_UINT32(((uint32_t)mcfg.hit_inc + 1u) / 2u, wall); /* half a return's hit */
    n = points_at(&truth_w);
    once_share = rsm_mapmatch_wall_share(&map, pts, n, &truth, wall);
    once_fit = rsm_mapmatch_fit(&map, pts, n, &truth);
    build_map(room_poses, sizeof room_poses / sizeof room_poses[0]); /* each pose twice */
    TEST_ASSERT_EQUAL_size_t(n, points_at(&truth_w));                 /* build_map took pts */
    share = rsm_mapmatch_wall_share(&map, pts, n, &truth, wall);
    TEST_ASSERT_TRUE(share >= 0.8f); /* measured 0.96 with 5 cm cells, 0.83 with 10 cm */
    TEST_ASSERT_EQUAL_FLOAT(once_share, share);
    /* measured 0.90 against 0.83 with 5 cm cells, 0.80 against 0.77 with 10 cm */
    TEST_ASSERT_TRUE(rsm_mapmatch_fit(&map, pts, n, &truth) > 1.02f * once_fit);
    off.x += 0.3f; /* off every wall: along both axes and turned */
    off.y += 0.3f;
    off.theta += 0.2f;
    TEST_ASSERT_TRUE(rsm_mapmatch_wall_share(&map, pts, n, &off, wall) < 0.5f * share);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_mapmatch_wall_share(&map, pts, 0u, &truth, wall));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_mapmatch_wall_share(NULL, pts, n, &truth, wall));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &mcfg));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_mapmatch_wall_share(&map, pts, n, &truth, wall));
}

void test_mapmatch_wall_share_should_read_the_cells_the_fit_reads(void)
{
    /* One wall cell: a reading counts on it exactly where the fit's
     * bilinear read takes some of it, from half a cell before the cell to
     * half a cell past the next one on each axis (cell g spans [g, g + 1)
     * cells, its value sits at its centre); a window half a cell off
     * either way fails at the edges. Sampled off the edges, where the
     * bilinear weight is not zero. */
    const rsm_pose_t at = {0.0f, 0.0f, 0.0f};
    const int32_t g = 10;
    rsm_tmap_cursor_t cur;
    uint32_t wall;
    float a;
    float empty;
    int i;
    int j;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &mcfg));
    rsm_tmap_cursor_init(&cur, 0u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_raise(&map, &cur, g, g, (uint32_t)mcfg.saturation));
    wall = rsm_tmap_wall_value(&map);
    TEST_ASSERT_TRUE((uint32_t)mcfg.saturation >= wall);
    a = rsm_tmap_cell(&map, 0u);
    pts[0].x = (float)(g + 40) * a; /* far from the wall: what an empty cell reads */
    pts[0].y = (float)g * a;
    empty = rsm_mapmatch_fit(&map, pts, 1u, &at);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_mapmatch_wall_share(&map, pts, 1u, &at, wall));
    for (j = -25; j < 35; ++j) {
        for (i = -25; i < 35; ++i) {
            /* Offsets of 0.1 cell from g + 0.05: never on an edge. */
            const float u = (float)g + 0.05f + 0.1f * (float)i;
            const float v = (float)g + 0.05f + 0.1f * (float)j;
            const int inside = u > (float)g - 0.5f && u < (float)g + 1.5f && v > (float)g - 0.5f && v < (float)g + 1.5f;
            float share;
            pts[0].x = u * a;
            pts[0].y = v * a;
            share = rsm_mapmatch_wall_share(&map, pts, 1u, &at, wall);
            TEST_ASSERT_EQUAL_FLOAT(inside ? 1.0f : 0.0f, share);
            TEST_ASSERT_EQUAL_INT(inside, rsm_mapmatch_fit(&map, pts, 1u, &at) > empty);
        }
    }
}

void test_mapmatch_should_report_an_empty_map_as_degenerate(void)
{
    const rsm_pose_t pred = {1.0f, 2.0f, 0.5f};
    rsm_mapmatch_result_t res;
    size_t n;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &mcfg));
    n = points_at(&pred);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_mapmatch(&map, &cfg, pts, n, &pred, p_wide, NULL, NULL, &res));
    TEST_ASSERT_EQUAL_MEMORY(&pred, &res.pose, sizeof pred);
    TEST_ASSERT_EQUAL_MEMORY(p_wide, res.cov, sizeof res.cov);
    /* A zero prior covariance is floored, not inverted as it is. */
    {
        const float zero[9] = {0};
        build_map(room_poses, 2u);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &pred, zero, NULL, NULL, &res));
        TEST_ASSERT_TRUE(rsm_synth_pos_error(&res.pose, &pred) < 1e-3f);
    }
}

void test_mapmatch_should_check_its_arguments_and_config(void)
{
    const rsm_pose_t pred = {0.0f, 0.0f, 0.0f};
    rsm_mapmatch_result_t res;
    rsm_mapmatch_config_t c;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &mcfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch_check(&cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_check(NULL));
    c = cfg;
    c.sigma = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_check(&c));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch(&map, &c, pts, 1u, &pred, p_wide, NULL, NULL, &res));
    c = cfg;
    c.iterations = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_check(&c));
    c = cfg;
    c.search_rad = 0.5f;
    c.search_step_rad = 0.001f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_check(&c));
    c.search_rad = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch_check(&c));
    c = cfg;
    c.unpin_hi = c.unpin_lo;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_check(&c));
    c.unpin_hi = 1.5f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_check(&c));
    c.unpin_hi = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch_check(&c));
    c.unpin_lo = -0.1f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch_check(&c));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch(NULL, &cfg, pts, 1u, &pred, p_wide, NULL, NULL, &res));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch(&map, &cfg, NULL, 1u, &pred, p_wide, NULL, NULL, &res));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch(&map, &cfg, pts, 1u, NULL, p_wide, NULL, NULL, &res));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch(&map, &cfg, pts, 1u, &pred, NULL, NULL, NULL, &res));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mapmatch(&map, &cfg, pts, 1u, &pred, p_wide, NULL, NULL, NULL));
}

void test_mapmatch_should_be_deterministic(void)
{
    const rsm_pose_t truth = {0.1f, 0.2f, -0.3f};
    const rsm_pose_t pred = {0.25f, 0.15f, -0.25f};
    rsm_mapmatch_result_t a;
    rsm_mapmatch_result_t b;
    size_t n;
    build_map(room_poses, sizeof room_poses / sizeof room_poses[0]);
    n = points_at(&truth);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &pred, p_wide, NULL, NULL, &a));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mapmatch(&map, &cfg, pts, n, &pred, p_wide, NULL, NULL, &b));
    TEST_ASSERT_EQUAL_MEMORY(&a, &b, sizeof a);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_mapmatch_should_converge_from_a_wrong_prediction);
    RUN_TEST(test_mapmatch_should_start_on_the_level_the_prior_needs);
    RUN_TEST(test_mapmatch_should_recover_large_heading_errors_in_a_hall);
    RUN_TEST(test_mapmatch_should_move_only_across_a_corridor);
    RUN_TEST(test_mapmatch_spread_should_tell_a_corridor_from_a_room);
    RUN_TEST(test_mapmatch_should_not_drag_a_scan_back_along_a_bare_corridor);
    RUN_TEST(test_mapmatch_search_should_find_a_pose_a_metre_off);
    RUN_TEST(test_mapmatch_search_should_score_every_candidate_on_its_cells);
    RUN_TEST(test_mapmatch_search_should_read_a_window_across_tile_edges);
    RUN_TEST(test_mapmatch_search_should_cost_places_the_map_does_not_hold_as_misses);
    RUN_TEST(test_mapmatch_search_should_find_in_parts_what_it_finds_whole);
    RUN_TEST(test_mapmatch_wall_share_should_count_walls_not_how_often_they_were_seen);
    RUN_TEST(test_mapmatch_wall_share_should_read_the_cells_the_fit_reads);
    RUN_TEST(test_mapmatch_should_report_an_empty_map_as_degenerate);
    RUN_TEST(test_mapmatch_should_check_its_arguments_and_config);
    RUN_TEST(test_mapmatch_should_be_deterministic);
    return UNITY_END();
}
