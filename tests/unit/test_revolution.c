/* Unit tests of the revolution assembler (src/drivers/revolution.c): a lidar
 * turning clockwise at 10 Hz in a square room while the robot turns in place
 * and while it drives an arc; the points of every turn placed in the room
 * with the scan's stamp pose and the mount, the way the localizer does it:
 * with de-skew they land on the walls, without they smear. Then the turn
 * boundaries, the counters and the argument checks. */
#include "unity.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "rsm/revolution.h"
#include "rsm/status.h"

void setUp(void) {}
void tearDown(void) {}

#define HALF 2.0f          /* the room is [-2, 2] x [-2, 2] m */
#define TURN_US 100000u    /* 10 Hz */
#define PER_TURN 360u      /* points per turn, 1 deg apart */
/* odometry at 50 Hz, or slower when the configured depth would not span a
 * turn and a half (the small test configuration keeps 4 poses) */
#define ODOM_US (RSM_REV_ODOM_DEPTH >= 8 ? 20000u : (2u * TURN_US) / (RSM_REV_ODOM_DEPTH - 1u))

static rsm_rev_t rev;

/* Robot motion: constant forward speed v and turn rate w from the origin. */
typedef struct motion {
    double v;
    double w;
} motion_t;

static void robot_at(const motion_t *m, double t, double *x, double *y, double *th)
{
    *th = m->w * t;
    if (fabs(m->w) < 1e-12) {
        *x = m->v * t;
        *y = 0.0;
    } else {
        *x = m->v / m->w * sin(m->w * t);
        *y = m->v / m->w * (1.0 - cos(m->w * t));
    }
}

/* Distance from (px, py) along heading a to the room's walls. */
static double to_wall(double px, double py, double a)
{
    const double dx = cos(a);
    const double dy = sin(a);
    double best = 1e9;
    if (dx > 1e-12) best = fmin(best, (HALF - px) / dx);
    if (dx < -1e-12) best = fmin(best, (-HALF - px) / dx);
    if (dy > 1e-12) best = fmin(best, (HALF - py) / dy);
    if (dy < -1e-12) best = fmin(best, (-HALF - py) / dy);
    return best;
}

static const rsm_pose_t mount = {0.12f, -0.03f, 0.3f};

/* Point j (from t = 0) of a clockwise lidar on the moving robot; every
 * 37th has no return. */
static rsm_lidar_point_t measure(const motion_t *m, unsigned j)
{
    rsm_lidar_point_t pt;
    const double t = (double)j * (double)TURN_US / PER_TURN * 1e-6;
    const double a_deg = fmod((double)j * 360.0 / PER_TURN + 7.5, 360.0);
    double x, y, th;
    double lx, ly, la;
    robot_at(m, t, &x, &y, &th);
    lx = x + cos(th) * mount.x - sin(th) * mount.y;
    ly = y + sin(th) * mount.x + cos(th) * mount.y;
    la = th + mount.theta - a_deg * 3.14159265358979323846 / 180.0; /* clockwise */
    memset(&pt, 0, sizeof pt);
    pt.angle_deg = (float)a_deg;
    pt.range_m = (j % 37u == 5u) ? 0.0f : (float)to_wall(lx, ly, la);
    pt.stamp_us = 1000000u + (uint64_t)j * TURN_US / PER_TURN;
    return pt;
}

/* How odometry reaches the assembler: as measured, or read in bursts (a host
 * that stalled reads its backlog: two packets 10 us apart, the first one
 * measured a period before its stamp). */
static int bursts;

static void feed_odometry(const motion_t *m, uint64_t upto_us, uint64_t *next_us)
{
    while (*next_us <= upto_us) {
        double x, y, th;
        rsm_pose_t p;
        robot_at(m, (double)(*next_us - 1000000u) * 1e-6, &x, &y, &th);
        p.x = (float)x;
        p.y = (float)y;
        p.theta = (float)th;
        if (bursts && ((*next_us - 1000000u) / ODOM_US) % 2u == 0u) {
            /* held back, stamped as read just before the next one */
            if (*next_us + ODOM_US > upto_us) {
                return;
            }
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, *next_us + ODOM_US - 10u, &p));
        } else {
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, *next_us, &p));
        }
        *next_us += ODOM_US;
    }
}

/* Largest distance of the valid points of a delivered scan from the nearest
 * wall, the scan placed with the robot pose at its stamp and the mount. */
static double worst_wall_error(const motion_t *m, const rsm_scan_t *s)
{
    double x, y, th;
    double worst = 0.0;
    size_t i;
    robot_at(m, (double)(s->stamp_us - 1000000u) * 1e-6, &x, &y, &th);
    for (i = 0; i < s->count; ++i) {
        double px, py, rx, ry, wx, wy, e;
        if (s->range_m[i] == 0.0f) {
            continue;
        }
        px = s->range_m[i] * cos(s->angle_rad[i]);
        py = s->range_m[i] * sin(s->angle_rad[i]);
        rx = mount.x + cos(mount.theta) * px - sin(mount.theta) * py;
        ry = mount.y + sin(mount.theta) * px + cos(mount.theta) * py;
        wx = x + cos(th) * rx - sin(th) * ry;
        wy = y + sin(th) * rx + cos(th) * ry;
        e = fmin(fabs(fabs(wx) - HALF), fabs(fabs(wy) - HALF));
        worst = fmax(worst, e);
    }
    return worst;
}

/* Runs three turns (the first is partial and dropped) and returns the worst
 * wall error of the two delivered ones. */
static double run(const motion_t *m, int deskew, uint16_t keep_every)
{
    rsm_rev_config_t cfg;
    uint64_t next_odom = 1000000u;
    double worst = 0.0;
    unsigned j;
    unsigned scans = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_config_default(&cfg));
    cfg.mount = mount;
    cfg.deskew = (uint8_t)deskew;
    cfg.keep_every = keep_every;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    for (j = 0; j < 3u * PER_TURN + 1u; ++j) {
        const rsm_lidar_point_t pt = measure(m, j);
        int rc;
        /* odometry runs a little ahead; read in bursts, it lags */
        feed_odometry(m, bursts ? pt.stamp_us : pt.stamp_us + ODOM_US, &next_odom);
        rc = rsm_rev_push(&rev, &pt);
        /* the stream ends: a turn still waiting for odometry comes out */
        if (rc == 0 && j == 3u * PER_TURN) {
            rc = rsm_rev_flush(&rev);
        }
        TEST_ASSERT_TRUE(rc == 0 || rc == 1);
        if (rc == 1) {
            const size_t kept = (PER_TURN + keep_every - 1u) / keep_every;
            scans++;
            TEST_ASSERT_EQUAL_size_t(kept < RSM_MAX_BEAMS ? kept : RSM_MAX_BEAMS, rev.scan.count);
            worst = fmax(worst, worst_wall_error(m, &rev.scan));
        }
    }
    /* the turn that began at 7.5 deg was cut: dropped; two whole turns */
    TEST_ASSERT_EQUAL_UINT(2, scans);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.partial);
    return worst;
}

void test_turning_in_place_deskewed_points_land_on_the_walls_and_smear_without(void)
{
    const motion_t spin = {0.0, 1.5}; /* 1.5 rad/s: 8.6 deg per turn of the lidar */
    const uint16_t thin = (uint16_t)((PER_TURN + RSM_MAX_BEAMS - 1u) / RSM_MAX_BEAMS);
    const double with = run(&spin, 1, thin);
    const double without = run(&spin, 0, thin);
    printf("turning in place at 1.5 rad/s: worst wall error %.6f m with de-skew, %.6f m without\n",
           with, without);
    TEST_ASSERT_TRUE_MESSAGE(with < 0.005, "de-skewed points within 5 mm of a wall");
    TEST_ASSERT_TRUE_MESSAGE(without > 0.1, "points without de-skew smear by more than 10 cm");
    TEST_ASSERT_EQUAL_UINT32(0, rev.stats.not_deskewed);
}

void test_driving_an_arc_deskewed_points_land_on_the_walls_and_smear_without(void)
{
    const motion_t arc = {0.8, -0.9};
    const uint16_t thin = (uint16_t)((PER_TURN + RSM_MAX_BEAMS - 1u) / RSM_MAX_BEAMS);
    const double with = run(&arc, 1, thin);
    const double without = run(&arc, 0, thin);
    printf("arc at 0.8 m/s, -0.9 rad/s: worst wall error %.6f m with de-skew, %.6f m without\n",
           with, without);
    TEST_ASSERT_TRUE(with < 0.005);
    TEST_ASSERT_TRUE(without > 0.05);
}

void test_odometry_read_in_bursts_deskews_as_well_as_on_time(void)
{
    /* Odometry read in pairs 10 us apart and lagging the points: the
     * pair's first pose (measured a period earlier than its stamp says) is
     * put halfway between its neighbours, and a turn waits for odometry
     * stamped after its last point before it is de-skewed. Measured over
     * the pair instead, a period's motion in 10 us flung points by 13 m
     * (issue 30); with the first pose at its stamp, 3.6 cm; extrapolated
     * past the newest pose with the motion over at least 20 ms, 0.6 mm
     * (9.6 cm with the small configuration's 67 ms period). Waiting, no
     * point is extrapolated and the walls are as close as with odometry on
     * time (0.03 mm; the small configuration's four poses cannot hold a
     * turn's while it waits: it is de-skewed before its first pose goes, 4.6
     * mm). */
    const motion_t arc = {0.8, -0.9};
    const uint16_t thin = (uint16_t)((PER_TURN + RSM_MAX_BEAMS - 1u) / RSM_MAX_BEAMS);
    double with;
    bursts = 1;
    with = run(&arc, 1, thin);
    bursts = 0;
    printf("arc, odometry in bursts: worst wall error %.6f m with de-skew (%u points extrapolated, %u poses "
           "read in a burst, %u turns waited, %u without odometry past their end)\n", with,
           (unsigned)rev.stats.extrapolated, (unsigned)rev.stats.odometry_bursts, (unsigned)rev.stats.waited,
           (unsigned)rev.stats.uncovered);
    TEST_ASSERT_TRUE(rev.stats.waited > 0u);
    if (ODOM_US > 20000u) {
        TEST_ASSERT_TRUE(with < 0.01);
    } else {
        TEST_ASSERT_TRUE(with < 0.0001);
        TEST_ASSERT_EQUAL_UINT32(0, rev.stats.extrapolated);
        TEST_ASSERT_EQUAL_UINT32(0, rev.stats.uncovered);
        TEST_ASSERT_TRUE(rev.stats.odometry_bursts > 0u);
    }
}

void test_a_burst_keeps_its_first_pose_halfway_between_its_neighbours(void)
{
    /* Odometry comes at a steady rate: the first pose of a burst (read 10
     * us before the second, measured a period earlier) is kept, put halfway
     * between the poses around it. It was dropped, which left de-skew a
     * chord over two periods (rsm-sim's curving drive as an RPLIDAR capture
     * in bursts: local error x3.1 of the clean run's, now x2.1; bench
     * section rsm_tools.bench.deskew). */
    rsm_rev_config_t cfg;
    const rsm_pose_t p0 = {0.0f, 0.0f, 0.0f};
    const rsm_pose_t p1 = {0.08f, 0.0f, -0.09f};
    const rsm_pose_t p2 = {0.16f, -0.01f, -0.18f};
    uint64_t t;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_config_default(&cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, 1000000u, &p0));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, 1199990u, &p1));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, 1200000u, &p2));
    TEST_ASSERT_EQUAL_size_t(3, rev.odom_n);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.odometry_bursts);
    TEST_ASSERT_EQUAL_UINT32(3, rev.stats.odometry);
    TEST_ASSERT_EQUAL_UINT64(1100000u, rev.odom_us[(rev.odom_head + 1u) % RSM_REV_ODOM_DEPTH]);
    t = rev.odom_us[(rev.odom_head + 2u) % RSM_REV_ODOM_DEPTH];
    TEST_ASSERT_EQUAL_UINT64(1200000u, t);
    TEST_ASSERT_EQUAL_FLOAT(p1.x, rev.odom[(rev.odom_head + 1u) % RSM_REV_ODOM_DEPTH].x);
}

void test_scan_stamp_is_the_middle_of_the_turn_and_invalid_points_stay_zero(void)
{
    const motion_t still = {0.0, 0.0};
    const uint16_t keep = (uint16_t)((PER_TURN + RSM_MAX_BEAMS - 1u) / RSM_MAX_BEAMS);
    rsm_rev_config_t cfg;
    rsm_lidar_point_t first = {0};
    rsm_lidar_point_t last = {0};
    uint32_t zeros = 0;
    unsigned j;
    size_t k = 0;
    (void)rsm_rev_config_default(&cfg);
    cfg.keep_every = keep;
    cfg.deskew = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    /* 352.5 .. 359.5 deg (a partial turn), then 0.5 .. 359.5 deg (j 353 to
     * 712), closed by the 0.5 deg of j = 713 */
    for (j = 345; j <= 713u; ++j) {
        const rsm_lidar_point_t pt = measure(&still, j);
        TEST_ASSERT_EQUAL_INT(j == 713u ? 1 : 0, rsm_rev_push(&rev, &pt));
        if (j == 353u) {
            first = pt;
        }
        if (j == 712u) {
            last = pt;
        }
        if (j >= 353u && j <= 712u && (j - 353u) % keep == 0u && pt.range_m == 0.0f) {
            zeros++;
        }
    }
    TEST_ASSERT_EQUAL_UINT64(first.stamp_us + (last.stamp_us - first.stamp_us) / 2u, rev.scan.stamp_us);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.partial);
    TEST_ASSERT_EQUAL_UINT32((8u + keep - 1u) / keep, rev.stats.dropped);
    TEST_ASSERT_EQUAL_UINT32(zeros, rev.stats.invalid);
    TEST_ASSERT_TRUE(zeros > 0u);
    for (j = 353; j <= 712u; j += keep) {
        const rsm_lidar_point_t pt = measure(&still, j);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, pt.range_m, rev.scan.range_m[k]);
        /* clockwise sensor angle a: bearing -a in (-pi, pi] */
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, rsm_wrap_angle(-pt.angle_deg * (RSM_PI / 180.0f)),
                                 rev.scan.angle_rad[k]);
        k++;
    }
    TEST_ASSERT_EQUAL_size_t(k, rev.scan.count);
}

void test_counters_for_overflow_gaps_bad_points_and_reset(void)
{
    rsm_rev_config_t cfg;
    const motion_t still = {0.0, 0.0};
    rsm_lidar_point_t pt;
    unsigned j;
    (void)rsm_rev_config_default(&cfg);
    cfg.min_points = 1u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    /* more points in one turn than RSM_MAX_BEAMS: 2 * RSM_MAX_BEAMS */
    for (j = 0; j < 2u * RSM_MAX_BEAMS; ++j) {
        memset(&pt, 0, sizeof pt);
        pt.angle_deg = 360.0f * (float)j / (float)(2u * RSM_MAX_BEAMS);
        pt.range_m = 1.0f;
        pt.stamp_us = 10u + j;
        TEST_ASSERT_EQUAL_INT(0, rsm_rev_push(&rev, &pt));
    }
    TEST_ASSERT_EQUAL_UINT32(RSM_MAX_BEAMS, rev.stats.overflow);
    /* bad points change nothing but their counter */
    pt.angle_deg = 360.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_rev_push(&rev, &pt));
    pt.angle_deg = 10.0f;
    pt.range_m = -1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_rev_push(&rev, &pt));
    pt.range_m = 1.0f;
    pt.stamp_us = 5u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_ORDER, rsm_rev_push(&rev, &pt));
    TEST_ASSERT_EQUAL_UINT32(3, rev.stats.bad_points);
    TEST_ASSERT_EQUAL_UINT32(2u * RSM_MAX_BEAMS, rev.stats.points);
    /* a gap drops the turn in progress */
    pt.angle_deg = 1.0f;
    pt.stamp_us = 10u + 2u * RSM_MAX_BEAMS + cfg.max_gap_us + 1u;
    TEST_ASSERT_EQUAL_INT(0, rsm_rev_push(&rev, &pt));
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.gaps);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.partial);
    TEST_ASSERT_EQUAL_UINT32(RSM_MAX_BEAMS, rev.stats.dropped);
    rsm_rev_reset(&rev);
    TEST_ASSERT_EQUAL_UINT32(2, rev.stats.partial);
    TEST_ASSERT_EQUAL_UINT32(RSM_MAX_BEAMS + 1u, rev.stats.dropped);
    TEST_ASSERT_EQUAL_UINT32(0, rev.stats.scans);
    (void)still;
}

void test_odometry_out_of_order_is_refused_and_without_any_no_deskew_is_counted(void)
{
    rsm_rev_config_t cfg;
    const motion_t still = {0.0, 0.0};
    rsm_pose_t p = {1.0f, 2.0f, 0.5f};
    unsigned j;
    int delivered = 0;
    (void)rsm_rev_config_default(&cfg);
    cfg.keep_every = (uint16_t)((PER_TURN + RSM_MAX_BEAMS - 1u) / RSM_MAX_BEAMS);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    for (j = 0; j < 2u * PER_TURN + 1u; ++j) {
        const rsm_lidar_point_t pt = measure(&still, j);
        delivered += rsm_rev_push(&rev, &pt);
    }
    TEST_ASSERT_EQUAL_INT(1, delivered);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.not_deskewed);
    TEST_ASSERT_TRUE(worst_wall_error(&still, &rev.scan) < 0.001);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, 100, &p));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_ORDER, rsm_rev_odometry(&rev, 99, &p));
    p.x = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_rev_odometry(&rev, 200, &p));
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.odometry);
    TEST_ASSERT_EQUAL_UINT32(2, rev.stats.odometry_bad);
}

void test_absurd_odometry_leaves_the_points_as_measured(void)
{
    /* Odometry of 1e30 m (finite, so taken) made NaN and infinite points
     * (issue 30); a pose a robot cannot reach in the time between a point
     * and the stamp is no motion to de-skew by: the point stays as
     * measured, counted. */
    const motion_t still = {0.0, 0.0};
    const rsm_pose_t zero = {0.0f, 0.0f, 0.0f};
    const rsm_pose_t far = {1e30f, -1e30f, 0.5f};
    rsm_rev_config_t cfg;
    unsigned j;
    unsigned scans = 0;
    (void)rsm_rev_config_default(&cfg);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, 1000000u, &zero));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, 1000000u + 3u * TURN_US / 2u, &far));
    for (j = 0; j < 3u * PER_TURN + 2u; ++j) {
        const rsm_lidar_point_t pt = measure(&still, j);
        /* the last pass: the stream ended, a turn waiting for odometry comes out */
        if ((j <= 3u * PER_TURN ? rsm_rev_push(&rev, &pt) : rsm_rev_flush(&rev)) == 1) {
            size_t i;
            scans++;
            for (i = 0; i < rev.scan.count; ++i) {
                TEST_ASSERT_TRUE(isfinite(rev.scan.range_m[i]) && isfinite(rev.scan.angle_rad[i]));
                TEST_ASSERT_TRUE(rev.scan.range_m[i] < 3.0f); /* the room's walls, not 1e30 m away */
            }
        }
    }
    TEST_ASSERT_EQUAL_UINT(2, scans);
    TEST_ASSERT_TRUE(rev.stats.implausible > PER_TURN / 2u);
}

void test_a_stuck_sensor_angle_drops_its_turn_after_two_seconds(void)
{
    /* An angle that stopped moving never wraps: the turn never ended and its
     * points (all at one bearing) went out with the next real turn. Over 2
     * s it is dropped, and turning again delivers whole turns. */
    const motion_t still = {0.0, 0.0};
    rsm_rev_config_t cfg;
    rsm_lidar_point_t pt;
    unsigned j;
    unsigned scans = 0;
    (void)rsm_rev_config_default(&cfg);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    for (j = 0; j < 2u * PER_TURN; ++j) {
        pt = measure(&still, j);
        scans += rsm_rev_push(&rev, &pt) == 1 ? 1u : 0u;
    }
    TEST_ASSERT_EQUAL_UINT(1, scans);
    for (j = 0; j < 5000u; ++j) { /* 5 s stuck at 42 deg, a point a millisecond */
        pt.angle_deg = 42.0f;
        pt.range_m = 1.5f;
        pt.stamp_us += 1000u;
        TEST_ASSERT_EQUAL_INT(0, rsm_rev_push(&rev, &pt));
    }
    TEST_ASSERT_EQUAL_UINT32(2, rev.stats.long_turns);
    for (j = 0; j < 3u * PER_TURN + 1u; ++j) {
        rsm_lidar_point_t q = measure(&still, j);
        q.stamp_us += pt.stamp_us + 1000u - 1000000u; /* on at once, no silence */
        if (rsm_rev_push(&rev, &q) == 1) {
            size_t i;
            scans++;
            TEST_ASSERT_EQUAL_size_t(PER_TURN < RSM_MAX_BEAMS ? PER_TURN : RSM_MAX_BEAMS, rev.scan.count);
            for (i = 0; i < rev.scan.count; ++i) {
                TEST_ASSERT_TRUE(rev.scan.range_m[i] != 1.5f);
            }
        }
    }
    TEST_ASSERT_EQUAL_UINT(3, scans);
}

void test_a_pause_between_turns_is_no_stuck_angle(void)
{
    /* A replayed log pauses between turns (rsm-nav listens with an hour's
     * patience): the turn before the pause is whole and delivered when the
     * next begins, however long the pause (the stuck-angle rule once took
     * it for a turn of 5 s). */
    const motion_t still = {0.0, 0.0};
    rsm_rev_config_t cfg;
    unsigned j;
    unsigned scans = 0;
    (void)rsm_rev_config_default(&cfg);
    cfg.max_gap_us = 3600000000u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    for (j = 0; j < 4u * PER_TURN; ++j) {
        rsm_lidar_point_t pt = measure(&still, j);
        pt.stamp_us += j >= 713u ? 5000000u : 0u; /* 5 s of silence before the third turn's first point */
        scans += rsm_rev_push(&rev, &pt) == 1 ? 1u : 0u;
    }
    TEST_ASSERT_EQUAL_UINT(3, scans); /* the second (at the third's start), the third and the fourth */
    TEST_ASSERT_EQUAL_UINT32(0, rev.stats.long_turns);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.partial); /* the first, joined mid-turn */
}

/* Points j = from .. to - 1 of a still lidar; the first j whose push
 * returned 1 (to if none). */
static unsigned push_until(unsigned from, unsigned to)
{
    const motion_t still = {0.0, 0.0};
    unsigned j;
    for (j = from; j < to; ++j) {
        const rsm_lidar_point_t pt = measure(&still, j);
        const int rc = rsm_rev_push(&rev, &pt);
        TEST_ASSERT_TRUE(rc == 0 || rc == 1);
        if (rc == 1) {
            return j;
        }
    }
    return to;
}

static void odometry_at(uint64_t stamp_us)
{
    const rsm_pose_t p = {0.0f, 0.0f, 0.0f};
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, stamp_us, &p));
}

/* The whole turn of measure(): points 353 to 712 (0.5 to 359.5 deg), ended
 * by point 713; its first point at 1 098 055 us, its last at 1 197 777 us, its middle
 * 1 147 916 us. */
#define TURN2_END 713u
#define TURN2_LAST_US 1197777u
#define TURN2_STAMP_US 1147916u

void test_a_turn_waits_for_odometry_past_its_last_point(void)
{
    /* Issue 30: odometry read late (a pair of encoder packets that came
     * after the turn ended) left the turn's end to extrapolation. The turn
     * now waits for a pose stamped after its last point, and for 2 ms more
     * past that pose (a burst's second would re-stamp it), then comes out
     * with the next point. */
    rsm_rev_config_t cfg;
    (void)rsm_rev_config_default(&cfg);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    odometry_at(1000000u);
    odometry_at(1100000u);
    TEST_ASSERT_EQUAL_UINT(TURN2_END + 2u, push_until(0u, TURN2_END + 2u)); /* nothing out */
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.waited);
    TEST_ASSERT_EQUAL_UINT32(0, rev.stats.scans);
    odometry_at(1200000u); /* past the last point: 1.2 s + 2 ms is point 728 */
    TEST_ASSERT_EQUAL_UINT(728u, push_until(TURN2_END + 2u, 1000u));
    TEST_ASSERT_EQUAL_UINT64(TURN2_STAMP_US, rev.scan.stamp_us);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.scans);
    TEST_ASSERT_EQUAL_UINT32(0, rev.stats.uncovered);
    TEST_ASSERT_EQUAL_UINT32(0, rev.stats.extrapolated);
    TEST_ASSERT_EQUAL_INT(0, rsm_rev_flush(&rev));
}

void test_a_turn_waits_no_longer_than_the_odometry_is_silent(void)
{
    /* Odometry that stopped (a robot link lost) cannot cover a turn: one
     * waits until the newest pose is odom_wait_us old, then is de-skewed
     * with what there is (counted), and the next turn, odometry still
     * silent, is not held at all. */
    rsm_rev_config_t cfg;
    (void)rsm_rev_config_default(&cfg);
    cfg.odom_wait_us = 60000u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    odometry_at(1000000u);
    odometry_at(1140000u);
    /* 1.14 s + 60 ms is point 720 */
    TEST_ASSERT_EQUAL_UINT(720u, push_until(0u, 1000u));
    TEST_ASSERT_EQUAL_UINT64(TURN2_STAMP_US, rev.scan.stamp_us);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.waited);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.uncovered);
    TEST_ASSERT_TRUE(rev.stats.extrapolated > 0u);
    /* the next turn ends at point 1073: out at once */
    TEST_ASSERT_EQUAL_UINT(1073u, push_until(721u, 1100u));
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.waited);
}

void test_a_waiting_turn_goes_out_before_the_next_and_flush_ends_the_wait(void)
{
    /* However long the wait, one turn at most waits: the next one's end
     * sends it out first, and the next one waits in its place; a stream
     * that ends gives it with rsm_rev_flush. With no wait set, a turn goes
     * out at its end, as before. */
    rsm_rev_config_t cfg;
    (void)rsm_rev_config_default(&cfg);
    cfg.odom_wait_us = 10000000u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    TEST_ASSERT_EQUAL_INT(0, rsm_rev_flush(&rev));
    odometry_at(1000000u);
    odometry_at(1100000u);
    TEST_ASSERT_EQUAL_UINT(1073u, push_until(0u, 1100u));
    TEST_ASSERT_EQUAL_UINT64(TURN2_STAMP_US, rev.scan.stamp_us);
    TEST_ASSERT_EQUAL_INT(1, rsm_rev_flush(&rev));
    TEST_ASSERT_EQUAL_UINT64(TURN2_STAMP_US + TURN_US, rev.scan.stamp_us);
    TEST_ASSERT_EQUAL_INT(0, rsm_rev_flush(&rev));
    TEST_ASSERT_EQUAL_UINT32(2, rev.stats.waited);
    TEST_ASSERT_EQUAL_UINT32(2, rev.stats.uncovered);
    TEST_ASSERT_EQUAL_UINT32(2, rev.stats.scans);

    cfg.odom_wait_us = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    odometry_at(1000000u);
    odometry_at(1100000u);
    TEST_ASSERT_EQUAL_UINT(TURN2_END, push_until(0u, 1100u));
    TEST_ASSERT_EQUAL_UINT32(0, rev.stats.waited);
}

void test_a_waiting_turn_goes_out_before_its_first_odometry_pose_is_dropped(void)
{
    /* The odometry kept is full and the next pose would push out the one
     * the waiting turn starts from: the turn is de-skewed with it first,
     * and the next point returns it. */
    rsm_rev_config_t cfg;
    unsigned k;
    (void)rsm_rev_config_default(&cfg);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &cfg));
    odometry_at(1000000u);
    odometry_at(1100000u);
    TEST_ASSERT_EQUAL_UINT(TURN2_END + 1u, push_until(0u, TURN2_END + 1u));
    for (k = 2u; k < RSM_REV_ODOM_DEPTH; ++k) {
        odometry_at(1100000u); /* the ring holds the turn's start */
    }
    TEST_ASSERT_EQUAL_UINT32(0, rev.stats.scans);
    odometry_at(1150000u); /* the turn's start would go */
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.scans);
    TEST_ASSERT_EQUAL_UINT(TURN2_END + 1u, push_until(TURN2_END + 1u, 1000u));
    TEST_ASSERT_EQUAL_UINT64(TURN2_STAMP_US, rev.scan.stamp_us);
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.uncovered);
}

void test_init_rejects_bad_settings(void)
{
    rsm_rev_config_t cfg;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_config_default(NULL));
    (void)rsm_rev_config_default(&cfg);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_init(NULL, &cfg));
    cfg.keep_every = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_init(&rev, &cfg));
    (void)rsm_rev_config_default(&cfg);
    cfg.wrap_deg = 360.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_init(&rev, &cfg));
    (void)rsm_rev_config_default(&cfg);
    cfg.mount.theta = INFINITY;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_init(&rev, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_push(NULL, NULL));
    {
        /* never initialised (zeroed): refused, not crashed on (issue 30) */
        rsm_lidar_point_t pt;
        memset(&pt, 0, sizeof pt);
        memset(&rev, 0, sizeof rev);
        TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_push(&rev, &pt));
    }
    rsm_rev_reset(NULL);
}

void test_init_refuses_a_caller_built_with_other_capacities(void)
{
    /* What rsm_rev_init passes for an application compiled with other
     * capacities (RSM_MAX_BEAMS and RSM_REV_ODOM_DEPTH size the assembler),
     * or with capacities that give the same size: refused, and not one
     * byte written. */
    static rsm_rev_t r;
    static rsm_rev_t before;
    rsm_rev_config_t cfg;
    (void)rsm_rev_config_default(&cfg);
    memset(&r, 0x5A, sizeof r);
    memcpy(&before, &r, sizeof r);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_rev_init_checked(&r, sizeof r - 8u,
                                                               (unsigned long)RSM_CONFIG_FINGERPRINT, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_rev_init_checked(&r, sizeof r,
                                                               (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul, &cfg));
    TEST_ASSERT_EQUAL_MEMORY(&before, &r, sizeof r);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&r, &cfg));
}

/* Every call on r refused (RSM_ERR_INVAL) and r untouched. */
static void assert_rev_refused(rsm_rev_t *r)
{
    static rsm_rev_t before;
    const rsm_pose_t pose = {0.0f, 0.0f, 0.0f};
    rsm_lidar_point_t pt;
    memset(&pt, 0, sizeof pt);
    if (r != NULL) {
        memcpy(&before, r, sizeof before);
    }
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_odometry(r, 1000u, &pose));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_push(r, &pt));
    rsm_rev_reset(r);
    if (r != NULL) {
        TEST_ASSERT_EQUAL_MEMORY(&before, r, sizeof before);
    }
}

void test_an_assembler_never_initialised_is_refused(void)
{
    /* Zeroed (rsm_rev_odometry took the pose into it), stale memory (push
     * went through its config pointer), NULL, and what a failed init left. */
    static rsm_rev_t r;
    rsm_rev_config_t cfg;
    memset(&r, 0, sizeof r);
    assert_rev_refused(&r);
    memset(&r, 0x5A, sizeof r);
    assert_rev_refused(&r);
    assert_rev_refused(NULL);
    (void)rsm_rev_config_default(&cfg);
    cfg.keep_every = 0u;
    memset(&r, 0, sizeof r);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rev_init(&r, &cfg));
    assert_rev_refused(&r);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_turning_in_place_deskewed_points_land_on_the_walls_and_smear_without);
    RUN_TEST(test_driving_an_arc_deskewed_points_land_on_the_walls_and_smear_without);
    RUN_TEST(test_odometry_read_in_bursts_deskews_as_well_as_on_time);
    RUN_TEST(test_a_burst_keeps_its_first_pose_halfway_between_its_neighbours);
    RUN_TEST(test_scan_stamp_is_the_middle_of_the_turn_and_invalid_points_stay_zero);
    RUN_TEST(test_counters_for_overflow_gaps_bad_points_and_reset);
    RUN_TEST(test_odometry_out_of_order_is_refused_and_without_any_no_deskew_is_counted);
    RUN_TEST(test_absurd_odometry_leaves_the_points_as_measured);
    RUN_TEST(test_a_stuck_sensor_angle_drops_its_turn_after_two_seconds);
    RUN_TEST(test_a_pause_between_turns_is_no_stuck_angle);
    RUN_TEST(test_a_turn_waits_for_odometry_past_its_last_point);
    RUN_TEST(test_a_turn_waits_no_longer_than_the_odometry_is_silent);
    RUN_TEST(test_a_waiting_turn_goes_out_before_the_next_and_flush_ends_the_wait);
    RUN_TEST(test_a_waiting_turn_goes_out_before_its_first_odometry_pose_is_dropped);
    RUN_TEST(test_init_rejects_bad_settings);
    RUN_TEST(test_init_refuses_a_caller_built_with_other_capacities);
    RUN_TEST(test_an_assembler_never_initialised_is_refused);
    return UNITY_END();
}
