/* Unit tests for src/localizer/odometry.c: tick deltas to motion increments, counter
 * wrap-around, pose round trips, Jacobians and process noise. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "rsm/odometry.h"
#include "rsm/status.h"
#include "test_support.h"
#include "unity.h"

static rsm_odometry_config_t cfg;
static rsm_odometry_t odo;

void setUp(void)
{
    cfg = rsm_odometry_config_default();
    memset(&odo, 0, sizeof odo);
}

void tearDown(void)
{
}

static int32_t ticks_for(float metres)
{
    return (int32_t)lrintf(metres * 128000.0f);
}

void test_config_default_should_describe_a_p3dx(void)
{
    TEST_ASSERT_EQUAL_FLOAT(128000.0f, cfg.ticks_per_m_left);
    TEST_ASSERT_EQUAL_FLOAT(128000.0f, cfg.ticks_per_m_right);
    TEST_ASSERT_EQUAL_FLOAT(0.357f, cfg.wheel_base_m);
    TEST_ASSERT_EQUAL_INT(32, cfg.counter_bits);
    TEST_ASSERT_EQUAL_FLOAT(0.05f, cfg.sigma_trans_per_m);
    TEST_ASSERT_EQUAL_FLOAT(0.05f, cfg.sigma_rot_per_rad);
    TEST_ASSERT_EQUAL_FLOAT(0.02f, cfg.sigma_rot_per_m);
    TEST_ASSERT_EQUAL_FLOAT(0.002f, cfg.sigma_trans_min_m);
    TEST_ASSERT_EQUAL_FLOAT(0.002f, cfg.sigma_rot_min_rad);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    TEST_ASSERT_EQUAL_MEMORY(&cfg, &odo.cfg, sizeof cfg); /* a copy */
    TEST_ASSERT_EQUAL_INT(0, odo.have_last);
    TEST_ASSERT_EQUAL_UINT32(0u, odo.steps);
}

void test_init_should_reject_invalid_configs(void)
{
    rsm_odometry_config_t bad;
    rsm_odometry_t before;
    memset(&odo, 0xA5, sizeof odo);
    before = odo;

    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(NULL, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, NULL));

    bad = cfg;
    bad.ticks_per_m_left = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.ticks_per_m_right = -128000.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.wheel_base_m = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.wheel_base_m = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.ticks_per_m_left = INFINITY;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.counter_bits = 15u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.counter_bits = 33u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.sigma_trans_per_m = -0.1f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.sigma_rot_per_rad = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.sigma_rot_per_m = -1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.sigma_trans_min_m = -0.001f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));
    bad = cfg;
    bad.sigma_rot_min_rad = INFINITY;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &bad));

    /* Rejected configs leave the state alone. */
    TEST_ASSERT_EQUAL_MEMORY(&before, &odo, sizeof odo);

    /* The limits of the counter width are accepted, and zero noise too. */
    bad = cfg;
    bad.counter_bits = 16u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &bad));
    bad.counter_bits = 32u;
    bad.sigma_trans_per_m = 0.0f;
    bad.sigma_rot_min_rad = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &bad));
}

void test_update_ticks_should_latch_on_first_call(void)
{
    rsm_motion_t u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    u.dx = 9.0f;
    u.dy = 9.0f;
    u.dtheta = 9.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks(&odo, 1000u, 2000u, &u));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dx);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dy);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dtheta);
    TEST_ASSERT_EQUAL_UINT32(0u, odo.steps);

    /* The latched values are the baseline of the next increment, however
     * large the absolute counts were. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 1000u + 128000u, 2000u + 128000u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0f, u.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, u.dy);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, u.dtheta);
    TEST_ASSERT_EQUAL_UINT32(1u, odo.steps);

    /* Re-initialising latches again. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks(&odo, 5u, 5u, &u));
}

void test_update_ticks_should_reject_null_arguments(void)
{
    rsm_motion_t u;
    rsm_odometry_t blank;
    memset(&blank, 0, sizeof blank);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_update_ticks(NULL, 0u, 0u, &u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_update_ticks(&odo, 0u, 0u, NULL));
    /* A state never initialised has no config. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_update_ticks(&blank, 0u, 0u, &u));
    TEST_ASSERT_EQUAL_INT(0, odo.have_last);
}

void test_from_ticks_should_drive_straight(void)
{
    const rsm_motion_t u = rsm_odometry_from_ticks(&cfg, ticks_for(0.5f), ticks_for(0.5f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.5f, u.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, u.dy);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, u.dtheta);

    /* Backwards. */
    const rsm_motion_t b = rsm_odometry_from_ticks(&cfg, -ticks_for(0.25f), -ticks_for(0.25f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, -0.25f, b.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, b.dy);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, b.dtheta);
}

void test_from_ticks_should_spin_counter_clockwise_when_right_wheel_leads(void)
{
    /* Left back 0.1 m, right forward 0.1 m: dS = 0, dtheta = (dR - dL)/B =
     * 0.2/0.357 = +0.5602 rad. The printed eq. 5 would give -0.2801. */
    const rsm_motion_t u = rsm_odometry_from_ticks(&cfg, -ticks_for(0.1f), ticks_for(0.1f));
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, u.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, u.dy);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.2f / 0.357f, u.dtheta);
    TEST_ASSERT_TRUE(u.dtheta > 0.0f);

    /* And the mirror image turns clockwise. */
    const rsm_motion_t v = rsm_odometry_from_ticks(&cfg, ticks_for(0.1f), -ticks_for(0.1f));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, -0.2f / 0.357f, v.dtheta);
}

void test_from_ticks_should_follow_an_arc_at_mid_heading(void)
{
    /* Left 1.0 m, right 1.2 m: dS = 1.1, dtheta = 0.2 / 0.357. */
    const float dth = 0.2f / 0.357f;
    const rsm_motion_t u = rsm_odometry_from_ticks(&cfg, ticks_for(1.0f), ticks_for(1.2f));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, dth, u.dtheta);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 1.1f * cosf(0.5f * dth), u.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 1.1f * sinf(0.5f * dth), u.dy);
    /* Turning left moves the robot to its left. */
    TEST_ASSERT_TRUE(u.dy > 0.0f);

    /* Unequal tick scales per wheel are honoured. */
    rsm_odometry_config_t c2 = cfg;
    c2.ticks_per_m_right = 64000.0f;
    const rsm_motion_t w = rsm_odometry_from_ticks(&c2, 128000, 64000);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0f, w.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, w.dtheta);
}

void test_from_ticks_should_return_zero_for_unusable_config(void)
{
    rsm_odometry_config_t bad = cfg;
    rsm_motion_t u = rsm_odometry_from_ticks(NULL, 1000, 2000);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dx);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dy);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dtheta);
    bad.wheel_base_m = 0.0f;
    u = rsm_odometry_from_ticks(&bad, 1000, 2000);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dx);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dtheta);
}

void test_update_ticks_should_unwrap_32_bit_counters_both_ways(void)
{
    rsm_motion_t u;
    /* The arithmetic alone: half the range in one step is no robot's motion. */
    cfg.max_wheel_speed_mps = 0.0f;
    cfg.max_turn_rate_rps = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    /* Forwards across 2^32: 0xFFFFFF00 -> 0x00000100 is +512 ticks. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks(&odo, 0xFFFFFF00u, 0xFFFFFF00u, &u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0x00000100u, 0x00000100u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 512.0f / 128000.0f, u.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, u.dtheta);
    /* Backwards across 0: 0x00000100 -> 0xFFFFFF00 is -512 ticks. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0xFFFFFF00u, 0xFFFFFF00u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, -512.0f / 128000.0f, u.dx);
    /* Exactly half the range is read as the most negative step, -2^31. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0x7FFFFF00u, 0x7FFFFF00u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, -2147483648.0f / 128000.0f, u.dx);
    /* Across the signed boundary 0x7FFFFF00 -> 0x80000100 is +512. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0x80000100u, 0x80000100u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 512.0f / 128000.0f, u.dx);
    /* Wheels wrapping in opposite directions: a spin in place. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0x00000010u, 0xFFFFFFF0u, &u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0xFFFFFFF0u, 0x00000010u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, u.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, (64.0f / 128000.0f) / 0.357f, u.dtheta);
    TEST_ASSERT_EQUAL_UINT32(6u, odo.steps);
}

void test_update_ticks_should_refuse_a_corrupt_step_and_lose_nothing(void)
{
    rsm_motion_t u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks_at(&odo, 0u, 0u, 0u, &u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks_at(&odo, 12800u, 12800u, 100000u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.1f, u.dx);
    /* Two opposite bit flips the additive checksum misses: 8 km in 0.1 s. */
    u.dx = 9.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE,
                          rsm_odometry_update_ticks_at(&odo, 12800u + 0x40000000u, 12800u, 200000u, &u));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dx);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dtheta);
    TEST_ASSERT_EQUAL_UINT32(1u, odo.implausible);
    /* The next good sample carries the whole motion since the last good one. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks_at(&odo, 38400u, 38400u, 300000u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.2f, u.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, u.dtheta);
    TEST_ASSERT_EQUAL_UINT32(0u, odo.relatched);
    TEST_ASSERT_EQUAL_UINT32(2u, odo.steps);
    /* A turn too fast for the robot is refused as well (wheels within speed). */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_odometry_update_ticks_at(&odo, 38400u - 340000u,
                                                                      38400u + 340000u, 400000u, &u));
    TEST_ASSERT_EQUAL_UINT32(2u, odo.implausible);
}

void test_update_ticks_should_take_up_counters_that_started_over(void)
{
    rsm_motion_t u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks_at(&odo, 5000000u, 4000000u, 0u, &u));
    /* The robot restarted: its counters read from 0 again. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_odometry_update_ticks_at(&odo, 0u, 0u, 100000u, &u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks_at(&odo, 1280u, 1280u, 200000u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.01f, u.dx);
    TEST_ASSERT_EQUAL_UINT32(1u, odo.relatched);
    TEST_ASSERT_EQUAL_UINT32(1u, odo.implausible);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks_at(&odo, 2560u, 2560u, 300000u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.01f, u.dx);
    /* Told of the restart, the next sample only latches. */
    rsm_odometry_restart(&odo);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks_at(&odo, 9u, 9u, 400000u, &u));
    TEST_ASSERT_EQUAL_UINT32(1u, odo.implausible);
}

void test_update_ticks_should_allow_more_travel_after_a_longer_gap(void)
{
    rsm_motion_t u;
    const uint32_t five_m = 5u * 128000u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks_at(&odo, 0u, 0u, 0u, &u));
    /* 5 m in 0.1 s (plus 1 s of slack at 3 m/s): refused. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_odometry_update_ticks_at(&odo, five_m, five_m, 100000u, &u));
    /* The same counts 2 s after the last good sample: fine. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks_at(&odo, five_m, five_m, 2000000u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 5.0f, u.dx);
    /* Without a time, the slack alone: 5 m more is refused, 2 m is not. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_odometry_update_ticks(&odo, 2u * five_m, 2u * five_m, &u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, five_m + 256000u, five_m + 256000u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 2.0f, u.dx);
    /* Zero turns a check off. */
    cfg.max_wheel_speed_mps = 0.0f;
    cfg.max_turn_rate_rps = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_set_config(&odo, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 20u * five_m, 20u * five_m, &u));
    /* Negative or non-finite bounds are refused at init. */
    cfg.slack_s = -1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_init(&odo, &cfg));
}

void test_update_ticks_should_unwrap_16_bit_counters_both_ways(void)
{
    rsm_motion_t u;
    cfg.counter_bits = 16u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks(&odo, 0xFF00u, 0xFF00u, &u));
    /* Forwards across 2^16. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0x0100u, 0x0100u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 512.0f / 128000.0f, u.dx);
    /* Backwards across 0. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0xFF00u, 0xFF00u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, -512.0f / 128000.0f, u.dx);
    /* Bits above the counter width are ignored: same low 16 bits, no motion. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0xABCDFF00u, 0x1234FF00u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-9f, 0.0f, u.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-9f, 0.0f, u.dtheta);
    /* Half the range back is the most negative step: -32768 ticks. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0x7F00u, 0x7F00u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, -32768.0f / 128000.0f, u.dx);
    /* Just under half the range forwards is positive: +32767 ticks. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 0xFEFFu, 0xFEFFu, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 32767.0f / 128000.0f, u.dx);
}

void test_count_delta_should_wrap_at_the_counter_width(void)
{
    TEST_ASSERT_EQUAL_INT32(512, rsm_odometry_count_delta(0x0100u, 0xFF00u, 16u));
    TEST_ASSERT_EQUAL_INT32(-512, rsm_odometry_count_delta(0xFF00u, 0x0100u, 16u));
    TEST_ASSERT_EQUAL_INT32(-32768, rsm_odometry_count_delta(0x7F00u, 0xFF00u, 16u));
    TEST_ASSERT_EQUAL_INT32(32767, rsm_odometry_count_delta(0xFEFFu, 0x7F00u, 16u));
    TEST_ASSERT_EQUAL_INT32(0, rsm_odometry_count_delta(0xABCDFF00u, 0x1234FF00u, 16u));
    TEST_ASSERT_EQUAL_INT32(100, rsm_odometry_count_delta(0x80000034u, 0x7FFFFFD0u, 32u));
    TEST_ASSERT_EQUAL_INT32(INT32_MIN, rsm_odometry_count_delta(0x80000000u, 0u, 32u));
    TEST_ASSERT_EQUAL_INT32(INT32_MAX, rsm_odometry_count_delta(0x7FFFFFFFu, 0u, 32u));
    TEST_ASSERT_EQUAL_INT32(-8, rsm_odometry_count_delta(0x1FFFF8u, 0u, 21u));
}

void test_set_config_should_copy_validate_and_keep_the_baseline(void)
{
    rsm_odometry_config_t c2 = cfg;
    rsm_odometry_config_t bad;
    rsm_odometry_t before;
    rsm_motion_t u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_init(&odo, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks(&odo, 1000u, 1000u, &u));
    /* A robot reporting TicksMM 256: the same counts are half the travel. */
    c2.ticks_per_m_left = 256000.0f;
    c2.ticks_per_m_right = 256000.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_set_config(&odo, &c2));
    c2.ticks_per_m_left = -1.0f; /* the caller's struct is free: a copy was taken */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_update_ticks(&odo, 1000u + 256000u, 1000u + 256000u, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0f, u.dx);
    TEST_ASSERT_EQUAL_UINT32(1u, odo.steps);
    /* Refused, and nothing changed. */
    before = odo;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_set_config(&odo, &c2));
    bad = cfg;
    bad.wheel_base_m = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_set_config(&odo, &bad));
    bad = cfg;
    bad.counter_bits = 33u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_set_config(&odo, &bad));
    bad = cfg;
    bad.sigma_rot_per_m = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_set_config(&odo, &bad));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_set_config(&odo, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_set_config(NULL, &cfg));
    TEST_ASSERT_EQUAL_MEMORY(&before, &odo, sizeof odo);
    /* Another counter width restarts the counts: the next sample latches. */
    bad = odo.cfg;
    bad.counter_bits = 16u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_set_config(&odo, &bad));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_odometry_update_ticks(&odo, 5u, 5u, &u));
}

void test_from_poses_should_round_trip_through_apply(void)
{
    uint32_t seed = 0x2545F491u;
    int k;
    for (k = 0; k < 2000; ++k) {
        rsm_pose_t a;
        rsm_pose_t b;
        rsm_pose_t c;
        rsm_motion_t u;
        a.x = rsm_test_rng_uniform(&seed, -50.0f, 50.0f);
        a.y = rsm_test_rng_uniform(&seed, -50.0f, 50.0f);
        b.x = a.x + rsm_test_rng_uniform(&seed, -2.0f, 2.0f);
        b.y = a.y + rsm_test_rng_uniform(&seed, -2.0f, 2.0f);
        if (k % 4 == 0) {
            /* Headings straddling +-pi. */
            a.theta = RSM_PI - rsm_test_rng_uniform(&seed, 0.0f, 0.01f);
            b.theta = -RSM_PI + rsm_test_rng_uniform(&seed, 0.0f, 0.01f);
        } else if (k % 4 == 1) {
            a.theta = -RSM_PI + rsm_test_rng_uniform(&seed, 0.0f, 0.01f);
            b.theta = RSM_PI - rsm_test_rng_uniform(&seed, 0.0f, 0.01f);
        } else {
            a.theta = rsm_test_rng_uniform(&seed, -RSM_PI, RSM_PI);
            b.theta = rsm_test_rng_uniform(&seed, -RSM_PI, RSM_PI);
        }
        u = rsm_odometry_from_poses(&a, &b);
        TEST_ASSERT_TRUE(u.dtheta > -RSM_PI && u.dtheta <= RSM_PI);
        c = rsm_odometry_apply(&a, &u);
        TEST_ASSERT_FLOAT_WITHIN(2e-5f, b.x, c.x);
        TEST_ASSERT_FLOAT_WITHIN(2e-5f, b.y, c.y);
        TEST_ASSERT_FLOAT_WITHIN(2e-6f, 0.0f, rsm_wrap_angle(c.theta - b.theta));
    }
}

void test_from_poses_should_express_motion_in_the_start_frame(void)
{
    /* Facing +y, moving 1 m along +y is 1 m forward; a crossing of +-pi is a
     * small turn, not a full one. */
    rsm_pose_t a = { 2.0f, 3.0f, 0.5f * RSM_PI };
    rsm_pose_t b = { 2.0f, 4.0f, 0.5f * RSM_PI };
    rsm_motion_t u = rsm_odometry_from_poses(&a, &b);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0f, u.dx);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, u.dy);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, u.dtheta);

    a.theta = 3.1f;
    b = a;
    b.theta = -3.1f;
    u = rsm_odometry_from_poses(&a, &b);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, RSM_TWO_PI - 6.2f, u.dtheta);

    u = rsm_odometry_from_poses(NULL, &b);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dx);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, u.dtheta);
}

void test_apply_should_chain_with_ticks(void)
{
    /* Four quarter turns on the spot and four 1 m legs close a square. */
    rsm_pose_t p = { 0.0f, 0.0f, 0.0f };
    const int32_t quarter = (int32_t)lrintf(0.25f * RSM_PI * 0.357f * 128000.0f);
    int k;
    for (k = 0; k < 4; ++k) {
        rsm_motion_t u = rsm_odometry_from_ticks(&cfg, 128000, 128000);
        p = rsm_odometry_apply(&p, &u);
        u = rsm_odometry_from_ticks(&cfg, -quarter, quarter);
        p = rsm_odometry_apply(&p, &u);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.0f, p.x);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.0f, p.y);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.0f, rsm_wrap_angle(p.theta));
}

void test_jacobians_should_match_finite_differences(void)
{
    uint32_t seed = 12345u;
    const float h = 1e-2f;
    int k;
    for (k = 0; k < 200; ++k) {
        rsm_pose_t p;
        rsm_motion_t u;
        float jv[9];
        float ju[9];
        int col;
        p.x = rsm_test_rng_uniform(&seed, -5.0f, 5.0f);
        p.y = rsm_test_rng_uniform(&seed, -5.0f, 5.0f);
        p.theta = rsm_test_rng_uniform(&seed, -3.0f, 3.0f);
        u.dx = rsm_test_rng_uniform(&seed, -0.5f, 0.5f);
        u.dy = rsm_test_rng_uniform(&seed, -0.2f, 0.2f);
        u.dtheta = rsm_test_rng_uniform(&seed, -0.5f, 0.5f);
        rsm_odometry_jacobians(&p, &u, jv, ju);
        for (col = 0; col < 3; ++col) {
            rsm_pose_t pp = p;
            rsm_pose_t pm = p;
            rsm_motion_t up = u;
            rsm_motion_t um = u;
            rsm_pose_t a;
            rsm_pose_t b;
            float *fp = col == 0 ? &pp.x : (col == 1 ? &pp.y : &pp.theta);
            float *fm = col == 0 ? &pm.x : (col == 1 ? &pm.y : &pm.theta);
            float *gp = col == 0 ? &up.dx : (col == 1 ? &up.dy : &up.dtheta);
            float *gm = col == 0 ? &um.dx : (col == 1 ? &um.dy : &um.dtheta);
            *fp += h;
            *fm -= h;
            *gp += h;
            *gm -= h;
            /* d/d(pose), central differences. */
            a = rsm_odometry_apply(&pp, &u);
            b = rsm_odometry_apply(&pm, &u);
            TEST_ASSERT_FLOAT_WITHIN(2e-4f, (a.x - b.x) / (2.0f * h), jv[0 * 3 + col]);
            TEST_ASSERT_FLOAT_WITHIN(2e-4f, (a.y - b.y) / (2.0f * h), jv[1 * 3 + col]);
            TEST_ASSERT_FLOAT_WITHIN(2e-4f, rsm_wrap_angle(a.theta - b.theta) / (2.0f * h), jv[2 * 3 + col]);
            /* d/d(u). */
            a = rsm_odometry_apply(&p, &up);
            b = rsm_odometry_apply(&p, &um);
            TEST_ASSERT_FLOAT_WITHIN(2e-4f, (a.x - b.x) / (2.0f * h), ju[0 * 3 + col]);
            TEST_ASSERT_FLOAT_WITHIN(2e-4f, (a.y - b.y) / (2.0f * h), ju[1 * 3 + col]);
            TEST_ASSERT_FLOAT_WITHIN(2e-4f, rsm_wrap_angle(a.theta - b.theta) / (2.0f * h), ju[2 * 3 + col]);
        }
    }
}

void test_noise_should_grow_with_travel_and_turn(void)
{
    float q[9];
    rsm_motion_t u = { 0.0f, 0.0f, 0.0f };
    const float f2 = 0.002f * 0.002f;
    int i;

    /* Standing still: only the floors. */
    rsm_odometry_noise(&cfg, &u, q);
    TEST_ASSERT_FLOAT_WITHIN(1e-10f, f2, q[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-10f, f2, q[4]);
    TEST_ASSERT_FLOAT_WITHIN(1e-10f, f2, q[8]);

    /* 1 m straight ahead. */
    u.dx = 1.0f;
    rsm_odometry_noise(&cfg, &u, q);
    TEST_ASSERT_FLOAT_WITHIN(1e-8f, 0.05f * 0.05f + f2, q[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-8f, 0.05f * 0.05f + f2, q[4]);
    TEST_ASSERT_FLOAT_WITHIN(1e-8f, 0.02f * 0.02f + f2, q[8]);
    for (i = 0; i < 9; ++i) {
        if (i != 0 && i != 4 && i != 8) {
            TEST_ASSERT_EQUAL_FLOAT(0.0f, q[i]);
        }
    }

    /* Backwards travel counts by magnitude. */
    u.dx = -1.0f;
    rsm_odometry_noise(&cfg, &u, q);
    TEST_ASSERT_FLOAT_WITHIN(1e-8f, 0.05f * 0.05f + f2, q[0]);

    /* A spin of -1 rad in place. */
    u.dx = 0.0f;
    u.dtheta = -1.0f;
    rsm_odometry_noise(&cfg, &u, q);
    TEST_ASSERT_FLOAT_WITHIN(1e-10f, f2, q[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-8f, 0.05f * 0.05f + f2, q[8]);

    /* Both: the heading terms add. */
    u.dx = 0.6f;
    u.dy = 0.8f;
    u.dtheta = 0.5f;
    rsm_odometry_noise(&cfg, &u, q);
    TEST_ASSERT_FLOAT_WITHIN(1e-8f, 0.05f * 0.05f + f2, q[4]);
    TEST_ASSERT_FLOAT_WITHIN(1e-8f, 0.025f * 0.025f + 0.02f * 0.02f + f2, q[8]);

    /* NULL arguments leave q alone. */
    q[0] = 42.0f;
    rsm_odometry_noise(NULL, &u, q);
    rsm_odometry_noise(&cfg, NULL, q);
    rsm_odometry_noise(&cfg, &u, NULL);
    TEST_ASSERT_EQUAL_FLOAT(42.0f, q[0]);
}

void test_noise_walk_should_grow_linearly_beyond_an_ordinary_step(void)
{
    float q[9];
    float w[9];
    rsm_motion_t u = { 0.3f, 0.0f, 0.2f };
    const float f2 = 0.002f * 0.002f;
    const float ref = RSM_ODOMETRY_WALK_STEP_M;
    int i;

    /* Up to an ordinary step it is the ordinary noise. */
    rsm_odometry_noise(&cfg, &u, q);
    rsm_odometry_noise_walk(&cfg, &u, w);
    for (i = 0; i < 9; ++i) {
        TEST_ASSERT_EQUAL_FLOAT(q[i], w[i]);
    }

    /* 10 m and 1 rad in one step, along (0.6, 0.8): along the chord and in
     * heading the distance terms as a ten-metre walk of ordinary steps
     * (variance per metre times ref), the turn's as before; across the
     * chord the walk's heading error integrated (dS^3 / 3), and with the
     * heading dS^2 / 2. */
    u.dx = 6.0f;
    u.dy = 8.0f;
    u.dtheta = 1.0f;
    rsm_odometry_noise_walk(&cfg, &u, w);
    {
        const float along = 0.05f * 0.05f * 10.0f * ref + f2;
        const float k = 0.02f * 0.02f * ref;
        const float across = along + k * 1000.0f / 3.0f;
        const float c[2] = {0.6f, 0.8f};
        const float n[2] = {-0.8f, 0.6f};
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, along, w[0] * c[0] * c[0] + 2.0f * w[1] * c[0] * c[1] + w[4] * c[1] * c[1]);
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, across, w[0] * n[0] * n[0] + 2.0f * w[1] * n[0] * n[1] + w[4] * n[1] * n[1]);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, w[2] * c[0] + w[5] * c[1]);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, k * 100.0f / 2.0f, w[2] * n[0] + w[5] * n[1]);
        TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.05f * 0.05f + 0.02f * 0.02f * 10.0f * ref + f2, w[8]);
        TEST_ASSERT_EQUAL_FLOAT(w[1], w[3]);
        TEST_ASSERT_EQUAL_FLOAT(w[2], w[6]);
        TEST_ASSERT_EQUAL_FLOAT(w[5], w[7]);
    }
    /* Twice as far, twice the variance along the chord (not four times). */
    u.dx = 12.0f;
    u.dy = 16.0f;
    u.dtheta = 0.0f;
    rsm_odometry_noise_walk(&cfg, &u, w);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.05f * 0.05f * 20.0f * ref + f2,
                             w[0] * 0.36f + 2.0f * w[1] * 0.48f + w[4] * 0.64f);

    /* NULL arguments leave q alone. */
    w[0] = 42.0f;
    rsm_odometry_noise_walk(NULL, &u, w);
    rsm_odometry_noise_walk(&cfg, NULL, w);
    rsm_odometry_noise_walk(&cfg, &u, NULL);
    TEST_ASSERT_EQUAL_FLOAT(42.0f, w[0]);
}

/* ---- calibration of the heading error ------------------------------------ */

/* A robot whose odometry turns (1 + over) times the truth and drifts
 * drift rad per metre forward: the raw increment for a true step. */
static rsm_motion_t biased(float dx, float true_turn, float over, float drift)
{
    rsm_motion_t u;
    u.dx = dx;
    u.dy = 0.0f;
    u.dtheta = true_turn * (1.0f + over) + drift * dx;
    return u;
}

/* Drives n steps of a wavy path (turns of up to 0.06 rad, 4 cm forward,
 * now and then backwards) through the calibration, each step matched at the
 * true heading with weight w; returns the largest error of a corrected turn
 * over the last quarter. */
static float drive(rsm_odometry_cal_t *cal, const rsm_odometry_cal_config_t *c, uint32_t n, float over, float drift,
                   float w)
{
    rsm_pose_t est = {0.0f, 0.0f, 0.0f};
    float worst = 0.0f;
    uint32_t k;
    rsm_odometry_cal_update(cal, c, &est, w, NULL); /* the first scan: a reference only */
    for (k = 0; k < n; ++k) {
        const float turn = 0.06f * sinf(0.05f * (float)k);
        const float dx = (k / 200u) % 5u == 4u ? -0.02f : 0.04f;
        const rsm_motion_t u = biased(dx, turn, over, drift);
        const rsm_motion_t v = rsm_odometry_cal_apply(cal, &u);
        rsm_odometry_cal_count(cal, c, &u, 0.0f);
        TEST_ASSERT_EQUAL_FLOAT(u.dx, v.dx);
        TEST_ASSERT_EQUAL_FLOAT(u.dy, v.dy);
        if (k >= 3u * n / 4u && fabsf(v.dtheta - turn) > worst) {
            worst = fabsf(v.dtheta - turn);
        }
        est.theta = rsm_wrap_angle(est.theta + turn);
        rsm_odometry_cal_update(cal, c, &est, w, NULL);
    }
    return worst;
}

void test_odometry_cal_should_learn_a_turn_scale_and_a_drift(void)
{
    const rsm_odometry_cal_config_t c = rsm_odometry_cal_config_default();
    rsm_odometry_cal_t cal;
    float worst;
    rsm_odometry_cal_init(&cal);
    /* Turns 6 % too far, drifts 0.03 rad (1.7 deg) per metre to the left. */
    worst = drive(&cal, &c, 3000u, 0.06f, 0.03f, 1.0f);
    TEST_ASSERT_FLOAT_WITHIN(0.002f, 1.0f / 1.06f - 1.0f, cal.k_turn);
    TEST_ASSERT_FLOAT_WITHIN(0.002f, -0.03f, cal.k_drift);
    TEST_ASSERT_EQUAL_UINT32(3000u, cal.used);
    /* Uncorrected a step would be off by up to 4.8 mrad. */
    TEST_ASSERT_TRUE(worst < 2.0e-4f);
}

void test_odometry_cal_should_stay_near_zero_for_true_odometry_and_weigh_scans(void)
{
    const rsm_odometry_cal_config_t c = rsm_odometry_cal_config_default();
    rsm_odometry_cal_t cal;
    rsm_odometry_cal_t light;
    rsm_odometry_cal_init(&cal);
    (void)drive(&cal, &c, 2000u, 0.0f, 0.0f, 1.0f);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.0f, cal.k_turn);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.0f, cal.k_drift);
    /* Scans that pin the heading less move it more slowly: after 50 steps
     * at weight 0.05 the correction is further from the truth than after 50
     * at weight 1, and weight 0 adds nothing at all. */
    rsm_odometry_cal_init(&cal);
    rsm_odometry_cal_init(&light);
    (void)drive(&cal, &c, 50u, 0.06f, 0.0f, 1.0f);
    (void)drive(&light, &c, 50u, 0.06f, 0.0f, 0.05f);
    TEST_ASSERT_TRUE(cal.k_turn < light.k_turn && light.k_turn < 0.0f);
    rsm_odometry_cal_init(&light);
    (void)drive(&light, &c, 50u, 0.06f, 0.0f, 0.0f);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, light.k_turn);
    TEST_ASSERT_EQUAL_UINT32(0u, light.used);
}

void test_odometry_cal_should_gate_jumps_and_bound_the_correction(void)
{
    const rsm_odometry_cal_config_t c = rsm_odometry_cal_config_default();
    rsm_odometry_cal_t cal;
    rsm_pose_t est = {0.0f, 0.0f, 0.0f};
    rsm_motion_t u = {0.04f, 0.0f, 0.05f};
    float before;
    rsm_odometry_cal_init(&cal);
    (void)drive(&cal, &c, 500u, 0.06f, 0.0f, 1.0f);
    before = cal.k_turn;
    /* A step that matching placed 0.3 rad from where odometry and the
     * correction say (a slip, a wrong match) is not learnt from... */
    est.theta = 1.0f;
    rsm_odometry_cal_reference(&cal, &est);
    rsm_odometry_cal_count(&cal, &c, &u, 0.0f);
    est.theta = 1.0f + 0.05f + 0.3f;
    rsm_odometry_cal_update(&cal, &c, &est, 1.0f, NULL);
    TEST_ASSERT_EQUAL_FLOAT(before, cal.k_turn);
    TEST_ASSERT_EQUAL_UINT32(500u, cal.used);
    /* ...but it becomes the reference for the next. */
    TEST_ASSERT_EQUAL_FLOAT(est.theta, cal.ref.theta);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, cal.turn);
    /* Odometry that turns half as far again as the truth is corrected by
     * no more than max_turn, and a drift of 0.3 rad/m by max_drift. */
    rsm_odometry_cal_init(&cal);
    (void)drive(&cal, &c, 3000u, 0.5f, 0.3f, 1.0f);
    TEST_ASSERT_EQUAL_FLOAT(-c.max_turn, cal.k_turn);
    TEST_ASSERT_EQUAL_FLOAT(-c.max_drift, cal.k_drift);
}

void test_odometry_cal_should_survive_an_absurd_step(void)
{
    /* A step of 1e20 m (a corrupt increment that got through) would
     * overflow the sums, and a turn over pi between two scans would wrap:
     * neither is used, the correction in force is kept, nothing turns
     * NaN, and learning goes on (towards the new drift; the first 500
     * steps' evidence for none fades). */
    const rsm_odometry_cal_config_t c = rsm_odometry_cal_config_default();
    rsm_odometry_cal_t cal;
    rsm_pose_t est = {0.0f, 0.0f, 0.0f};
    const rsm_motion_t huge = {1e20f, 0.0f, 0.0f};
    const rsm_motion_t spin = {0.0f, 0.0f, 3.0f};
    rsm_motion_t v;
    float before;
    rsm_odometry_cal_init(&cal);
    (void)drive(&cal, &c, 500u, 0.06f, 0.0f, 1.0f);
    before = cal.k_turn;
    rsm_odometry_cal_reference(&cal, &est);
    rsm_odometry_cal_count(&cal, &c, &huge, 0.0f);
    rsm_odometry_cal_update(&cal, &c, &est, 1.0f, NULL);
    TEST_ASSERT_EQUAL_FLOAT(before, cal.k_turn);
    rsm_odometry_cal_count(&cal, &c, &spin, 0.0f);
    rsm_odometry_cal_count(&cal, &c, &spin, 0.0f);
    est.theta = rsm_wrap_angle(6.0f);
    rsm_odometry_cal_update(&cal, &c, &est, 1.0f, NULL);
    TEST_ASSERT_EQUAL_FLOAT(before, cal.k_turn);
    TEST_ASSERT_EQUAL_UINT32(500u, cal.used);
    v = rsm_odometry_cal_apply(&cal, &spin);
    TEST_ASSERT_TRUE(isfinite(v.dtheta) && isfinite(cal.k_drift));
    (void)drive(&cal, &c, 3000u, 0.06f, 0.03f, 1.0f);
    TEST_ASSERT_TRUE(cal.k_drift < -0.025f && cal.k_drift > -0.031f);
}

/* The variance a step adds to the position in drive_distance, and a
 * match's: a pinned scan knows its position far better than the steps
 * since the last one did. */
#define STEP_VAR 1e-4f
#define MATCH_VAR 1e-6f

/* Drives n steps of a wavy path (4 cm forward, now and then backwards)
 * with odometry that measures every distance 1 + over times too long and
 * drifts `drift` rad per metre, and matches one scan in every `pinned` at
 * the true pose with a match's covariance; the scans between keep the
 * prediction from the corrected odometry, the heading from the walls, and
 * the variance odometry added (a bare corridor). Returns the distance the
 * estimate ends off. */
static float drive_distance(rsm_odometry_cal_t *cal, const rsm_odometry_cal_config_t *c, uint32_t n, float over,
                            float drift, uint32_t pinned, float step_var)
{
    const float matched[3] = {MATCH_VAR, 0.0f, MATCH_VAR};
    rsm_pose_t truth = {0.0f, 0.0f, 0.0f};
    rsm_pose_t est = truth;
    float var = MATCH_VAR;
    uint32_t k;
    rsm_odometry_cal_update(cal, c, &est, 1.0f, matched);
    for (k = 0; k < n; ++k) {
        const float turn = 0.03f * sinf(0.05f * (float)k);
        const float dx = (k / 200u) % 5u == 4u ? -0.02f : 0.04f;
        const rsm_motion_t u = {dx * (1.0f + over), 0.0f, turn + drift * dx * (1.0f + over)};
        const rsm_motion_t v = rsm_odometry_cal_apply(cal, &u);
        rsm_odometry_cal_count(cal, c, &u, step_var);
        var += step_var;
        truth.x += dx * cosf(truth.theta);
        truth.y += dx * sinf(truth.theta);
        truth.theta = rsm_wrap_angle(truth.theta + turn);
        est.x += v.dx * cosf(est.theta);
        est.y += v.dx * sinf(est.theta);
        est.theta = truth.theta;
        if ((k + 1u) % pinned == 0u) {
            est = truth;
            var = MATCH_VAR;
            rsm_odometry_cal_update(cal, c, &est, 1.0f, matched);
        } else {
            const float grown[3] = {var, 0.0f, var};
            rsm_odometry_cal_update(cal, c, &est, 1.0f, grown);
        }
    }
    return hypotf(est.x - truth.x, est.y - truth.y);
}

/* The calibration with the distance's on. */
static rsm_odometry_cal_config_t with_distance(void)
{
    rsm_odometry_cal_config_t c = rsm_odometry_cal_config_default();
    c.max_scale = 0.1f;
    return c;
}

void test_odometry_cal_should_take_a_step_over_a_gap_as_reported(void)
{
    /* Odometry turning 6 % too far and drifting 0.03 rad/m, learned; then
     * one step for a stretch the scans missed. Up to 10 m (the longest
     * span the correction is fitted on) it is corrected; a longer one is
     * a chord of an unknown path (its turns summed and its metres driven
     * are what the correction needs), taken as reported, the distance's
     * correction too. */
    const rsm_odometry_cal_config_t c = rsm_odometry_cal_config_default();
    rsm_odometry_cal_t cal;
    const rsm_motion_t near = {9.0f, 1.0f, 0.5f};
    const rsm_motion_t far = {20.0f, -3.0f, 0.5f};
    const rsm_motion_t back = {-10.5f, 0.0f, -0.2f};
    rsm_motion_t v;
    rsm_odometry_cal_init(&cal);
    (void)drive(&cal, &c, 3000u, 0.06f, 0.03f, 1.0f);
    TEST_ASSERT_TRUE(cal.k_drift < -0.025f && cal.k_turn < -0.04f);
    cal.k_scale = 0.05f; /* as if learned (drive() learns no distance) */
    v = rsm_odometry_cal_apply(&cal, &near);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, rsm_wrap_angle(0.5f * (1.0f + cal.k_turn) + cal.k_drift * 9.0f), v.dtheta);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 9.0f * 1.05f, v.dx);
    v = rsm_odometry_cal_apply(&cal, &far);
    TEST_ASSERT_EQUAL_FLOAT(far.dx, v.dx);
    TEST_ASSERT_EQUAL_FLOAT(far.dy, v.dy);
    TEST_ASSERT_EQUAL_FLOAT(far.dtheta, v.dtheta);
    v = rsm_odometry_cal_apply(&cal, &back);
    TEST_ASSERT_EQUAL_FLOAT(back.dx, v.dx);
    TEST_ASSERT_EQUAL_FLOAT(back.dtheta, v.dtheta);
}

void test_odometry_cal_should_learn_the_distance_between_pinned_scans(void)
{
    const rsm_odometry_cal_config_t c = with_distance();
    const float truth = 1.0f / 1.04f - 1.0f;
    rsm_odometry_cal_t cal;
    rsm_motion_t u = {0.04f * 1.04f, 0.0f, 0.0f};
    rsm_motion_t v;
    /* Odometry 4 % long, every scan pinned (the prior's metre against the
     * 40 m the memory holds pulls 2.5 % of the way to none). */
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 3000u, 0.04f, 0.0f, 1u, STEP_VAR);
    TEST_ASSERT_FLOAT_WITHIN(0.0015f, truth, cal.k_scale);
    TEST_ASSERT_EQUAL_UINT32(3000u, cal.scale_used);
    v = rsm_odometry_cal_apply(&cal, &u);
    TEST_ASSERT_FLOAT_WITHIN(5e-5f, 0.04f, v.dx);
    /* One scan in ten pinned: the nine between follow the odometry and the
     * tenth takes their error back. Its equation spans the ten steps
     * (s = 0.416 m, found 0.4 m); one over its own step only would count
     * the whole jump against 4 cm (k -0.0154 from the first). */
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 10u, 0.04f, 0.0f, 10u, STEP_VAR);
    TEST_ASSERT_FLOAT_WITHIN(0.0005f, -0.016f / (0.416f + c.scale_prior_m), cal.k_scale);
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 3000u, 0.04f, 0.0f, 10u, STEP_VAR);
    TEST_ASSERT_FLOAT_WITHIN(0.0015f, truth, cal.k_scale);
    TEST_ASSERT_EQUAL_UINT32(300u, cal.scale_used);
    /* After that the unpinned stretches end within a millimetre of the
     * truth; uncorrected they end 1.6 cm off (ten steps of 4 cm, 4 %). */
    TEST_ASSERT_TRUE(drive_distance(&cal, &c, 9u, 0.04f, 0.0f, 10u, STEP_VAR) < 0.001f);
    /* True odometry stays uncorrected, and the heading's fit is left alone
     * by the distance's. */
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 2000u, 0.0f, 0.0f, 3u, STEP_VAR);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.0f, cal.k_scale);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.0f, cal.k_turn);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.0f, cal.k_drift);
}

void test_odometry_cal_should_gate_and_bound_the_distance(void)
{
    const float matched[3] = {MATCH_VAR, 0.0f, MATCH_VAR};
    rsm_odometry_cal_config_t c = with_distance();
    rsm_odometry_cal_t cal;
    rsm_pose_t est = {0.0f, 0.0f, 0.0f};
    const rsm_motion_t u = {0.04f, 0.0f, 0.0f};
    rsm_motion_t v;
    float before;
    float dir[2];
    rsm_odometry_cal_init(&cal);
    TEST_ASSERT_EQUAL_INT(0, rsm_odometry_cal_direction(&cal, dir)); /* no reference */
    (void)drive_distance(&cal, &c, 500u, 0.04f, 0.0f, 1u, STEP_VAR);
    before = cal.k_scale;
    /* A scan that matching placed 0.3 m further on than 4 cm of odometry
     * says (a slip, a wrong match) is not learnt from, but it is the next
     * reference. */
    rsm_odometry_cal_reference(&cal, &est);
    rsm_odometry_cal_count(&cal, &c, &u, STEP_VAR);
    TEST_ASSERT_EQUAL_INT(1, rsm_odometry_cal_direction(&cal, dir));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0f, dir[0]);
    est.x = 0.34f;
    rsm_odometry_cal_update(&cal, &c, &est, 1.0f, matched);
    TEST_ASSERT_EQUAL_FLOAT(before, cal.k_scale);
    TEST_ASSERT_EQUAL_UINT32(500u, cal.scale_used);
    TEST_ASSERT_EQUAL_FLOAT(0.34f, cal.sref.x);
    /* Odometry half as long again as the truth is corrected by no more
     * than max_scale. */
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 3000u, 0.5f, 0.0f, 1u, STEP_VAR);
    TEST_ASSERT_EQUAL_FLOAT(-c.max_scale, cal.k_scale);
    /* The gate is on the miss of the correction in force: with k_scale at
     * -0.1, a 1 m span found 0.24 m short misses it by 0.14 m, within 5 cm
     * plus 0.1 of the metre, and is learnt from. */
    before = (float)cal.scale_used;
    est.x = 0.0f;
    est.y = 0.0f;
    est.theta = 0.0f;
    rsm_odometry_cal_reference(&cal, &est);
    {
        const rsm_motion_t metre = {1.0f, 0.0f, 0.0f};
        rsm_odometry_cal_count(&cal, &c, &metre, STEP_VAR);
    }
    est.x = 0.76f;
    rsm_odometry_cal_update(&cal, &c, &est, 1.0f, matched);
    TEST_ASSERT_EQUAL_FLOAT(before + 1.0f, (float)cal.scale_used);
    /* max_scale 0 (the default): the distance is not calibrated, the
     * heading still is. */
    c = rsm_odometry_cal_config_default();
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 500u, 0.04f, 0.0f, 1u, STEP_VAR);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, cal.k_scale);
    TEST_ASSERT_EQUAL_UINT32(0u, cal.scale_used);
    TEST_ASSERT_EQUAL_UINT32(500u, cal.used);
    v = rsm_odometry_cal_apply(&cal, &u);
    TEST_ASSERT_EQUAL_FLOAT(u.dx, v.dx);
}

void test_odometry_cal_should_learn_the_distance_over_long_spans_of_a_drifting_heading(void)
{
    /* Odometry drifting 0.05 rad/m (Intel's is 0.056) with a scan pinned
     * every 8 m: the raw heading would curve each span by 0.4 rad, shorten
     * its chord and turn it aside (k -0.013 for exact distances). The
     * span is taken at the corrected heading. */
    const rsm_odometry_cal_config_t c = with_distance();
    rsm_odometry_cal_t cal;
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 8000u, 0.0f, 0.05f, 200u, STEP_VAR);
    TEST_ASSERT_FLOAT_WITHIN(0.002f, -0.05f, cal.k_drift);
    TEST_ASSERT_FLOAT_WITHIN(0.002f, 0.0f, cal.k_scale);
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 8000u, 0.04f, 0.05f, 200u, STEP_VAR);
    TEST_ASSERT_FLOAT_WITHIN(0.003f, 1.0f / 1.04f - 1.0f, cal.k_scale);
}

void test_odometry_cal_should_judge_pinning_against_odometrys_own_variance(void)
{
    /* Odometry a hundred times as precise as the match per step: one
     * scan's match says less than a step of odometry, so it does not pin;
     * a match pins once the steps since the last pinned scan add up to
     * twice its variance (about 20 steps here), and the distance is still
     * learnt from those spans. */
    const rsm_odometry_cal_config_t c = with_distance();
    rsm_odometry_cal_t cal;
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 4000u, 0.04f, 0.0f, 1u, MATCH_VAR / 10.0f);
    TEST_ASSERT_TRUE(cal.scale_used > 4000u / 40u && cal.scale_used < 4000u / 10u);
    TEST_ASSERT_FLOAT_WITHIN(0.002f, 1.0f / 1.04f - 1.0f, cal.k_scale);
}

void test_odometry_cal_direction_should_follow_the_reference_and_the_turns(void)
{
    const rsm_odometry_cal_config_t c = with_distance();
    const rsm_pose_t facing_y = {1.0f, 2.0f, 0.5f * RSM_PI};
    const rsm_motion_t side = {0.03f, 0.04f, 0.0f};
    const rsm_motion_t quarter = {0.0f, 0.0f, 0.5f * RSM_PI};
    const rsm_motion_t ahead = {0.05f, 0.02f, 0.0f};
    rsm_odometry_cal_t cal;
    float dir[2];
    rsm_odometry_cal_init(&cal);
    rsm_odometry_cal_reference(&cal, &facing_y);
    /* 3 cm ahead and 4 cm left, facing +y: 3 cm up and 4 cm to -x. */
    rsm_odometry_cal_count(&cal, &c, &side, 0.0f);
    TEST_ASSERT_EQUAL_INT(1, rsm_odometry_cal_direction(&cal, dir));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, -0.8f, dir[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.6f, dir[1]);
    /* A quarter turn left, then 5 cm ahead and 2 cm left, facing -x:
     * 5 cm to -x and 2 cm down; (-0.09, 0.01) in all. */
    rsm_odometry_cal_count(&cal, &c, &quarter, 0.0f);
    rsm_odometry_cal_count(&cal, &c, &ahead, 0.0f);
    TEST_ASSERT_EQUAL_INT(1, rsm_odometry_cal_direction(&cal, dir));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, -0.09f / hypotf(0.09f, 0.01f), dir[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.01f / hypotf(0.09f, 0.01f), dir[1]);
}

void test_odometry_cal_should_survive_a_nan_reference_and_an_infinite_span(void)
{
    /* A NaN estimate at a pinned scan becomes no reference that sticks,
     * an infinite step no equation; the next spans are learnt again. */
    const rsm_odometry_cal_config_t c = with_distance();
    const float matched[3] = {MATCH_VAR, 0.0f, MATCH_VAR};
    const rsm_motion_t inf_step = {INFINITY, 0.0f, 0.0f};
    const rsm_motion_t step = {0.04f, 0.0f, 0.0f};
    rsm_pose_t est = {0.0f, 0.0f, 0.0f};
    rsm_odometry_cal_t cal;
    float dir[2];
    uint32_t used;
    rsm_odometry_cal_init(&cal);
    (void)drive_distance(&cal, &c, 500u, 0.04f, 0.0f, 1u, STEP_VAR);
    used = cal.scale_used;
    est.x = NAN;
    est.theta = NAN;
    rsm_odometry_cal_count(&cal, &c, &step, STEP_VAR);
    rsm_odometry_cal_update(&cal, &c, &est, 1.0f, matched);
    rsm_odometry_cal_count(&cal, &c, &step, STEP_VAR);
    TEST_ASSERT_EQUAL_INT(0, rsm_odometry_cal_direction(&cal, dir));
    est.x = 0.0f;
    est.theta = 0.0f;
    rsm_odometry_cal_update(&cal, &c, &est, 1.0f, matched); /* no direction: a new reference */
    TEST_ASSERT_EQUAL_FLOAT(0.0f, cal.sref.theta);
    rsm_odometry_cal_count(&cal, &c, &inf_step, STEP_VAR);
    rsm_odometry_cal_update(&cal, &c, &est, 1.0f, matched);
    TEST_ASSERT_TRUE(isfinite(cal.k_scale) && isfinite(cal.scale_info) && isfinite(cal.scale_moment));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, cal.disp[0]);
    TEST_ASSERT_EQUAL_UINT32(used, cal.scale_used);
    (void)drive_distance(&cal, &c, 500u, 0.04f, 0.0f, 1u, STEP_VAR);
    TEST_ASSERT_TRUE(cal.scale_used > used + 400u);
    TEST_ASSERT_FLOAT_WITHIN(0.003f, 1.0f / 1.04f - 1.0f, cal.k_scale);
}

void test_odometry_cal_config_check_should_name_the_bad_field(void)
{
    rsm_odometry_cal_config_t c = rsm_odometry_cal_config_default();
    const char *field = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_cal_config_check(&c, &field));
    c.memory = 0.0f; /* off: the other fields are not read */
    c.prior = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_odometry_cal_config_check(&c, &field));
#define BAD(member, value, name)                                                          \
    do {                                                                                  \
        c = rsm_odometry_cal_config_default();                                            \
        c.member = (value);                                                               \
        field = NULL;                                                                     \
        TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_cal_config_check(&c, &field)); \
        TEST_ASSERT_EQUAL_STRING(name, field);                                            \
    } while (0)
    BAD(memory, 1.5f, "odometry_cal.memory");
    BAD(memory, -3.0f, "odometry_cal.memory");
    BAD(memory, NAN, "odometry_cal.memory");
    BAD(prior, 0.0f, "odometry_cal.prior");
    BAD(max_turn, 1.0f, "odometry_cal.max_turn");
    BAD(max_drift, INFINITY, "odometry_cal.max_drift");
    BAD(gate_rad, -0.1f, "odometry_cal.gate_rad");
    BAD(max_scale, 1.0f, "odometry_cal.max_scale");
    BAD(max_scale, -0.01f, "odometry_cal.max_scale");
    BAD(max_scale, NAN, "odometry_cal.max_scale");
    BAD(gate_m, 0.0f, "odometry_cal.gate_m");
    BAD(scale_prior_m, -1.0f, "odometry_cal.scale_prior_m");
#undef BAD
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_odometry_cal_config_check(NULL, &field));
    TEST_ASSERT_EQUAL_STRING("odometry_cal", field);
    /* NULL arguments are ignored. */
    rsm_odometry_cal_init(NULL);
    rsm_odometry_cal_reference(NULL, NULL);
    rsm_odometry_cal_update(NULL, &c, NULL, 1.0f, NULL);
    TEST_ASSERT_EQUAL_INT(0, rsm_odometry_cal_direction(NULL, NULL));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_config_default_should_describe_a_p3dx);
    RUN_TEST(test_init_should_reject_invalid_configs);
    RUN_TEST(test_update_ticks_should_latch_on_first_call);
    RUN_TEST(test_update_ticks_should_reject_null_arguments);
    RUN_TEST(test_from_ticks_should_drive_straight);
    RUN_TEST(test_from_ticks_should_spin_counter_clockwise_when_right_wheel_leads);
    RUN_TEST(test_from_ticks_should_follow_an_arc_at_mid_heading);
    RUN_TEST(test_from_ticks_should_return_zero_for_unusable_config);
    RUN_TEST(test_update_ticks_should_unwrap_32_bit_counters_both_ways);
    RUN_TEST(test_update_ticks_should_refuse_a_corrupt_step_and_lose_nothing);
    RUN_TEST(test_update_ticks_should_take_up_counters_that_started_over);
    RUN_TEST(test_update_ticks_should_allow_more_travel_after_a_longer_gap);
    RUN_TEST(test_update_ticks_should_unwrap_16_bit_counters_both_ways);
    RUN_TEST(test_from_poses_should_round_trip_through_apply);
    RUN_TEST(test_from_poses_should_express_motion_in_the_start_frame);
    RUN_TEST(test_count_delta_should_wrap_at_the_counter_width);
    RUN_TEST(test_set_config_should_copy_validate_and_keep_the_baseline);
    RUN_TEST(test_apply_should_chain_with_ticks);
    RUN_TEST(test_jacobians_should_match_finite_differences);
    RUN_TEST(test_noise_should_grow_with_travel_and_turn);
    RUN_TEST(test_noise_walk_should_grow_linearly_beyond_an_ordinary_step);
    RUN_TEST(test_odometry_cal_should_learn_a_turn_scale_and_a_drift);
    RUN_TEST(test_odometry_cal_should_stay_near_zero_for_true_odometry_and_weigh_scans);
    RUN_TEST(test_odometry_cal_should_gate_jumps_and_bound_the_correction);
    RUN_TEST(test_odometry_cal_should_survive_an_absurd_step);
    RUN_TEST(test_odometry_cal_should_take_a_step_over_a_gap_as_reported);
    RUN_TEST(test_odometry_cal_should_learn_the_distance_between_pinned_scans);
    RUN_TEST(test_odometry_cal_should_gate_and_bound_the_distance);
    RUN_TEST(test_odometry_cal_should_learn_the_distance_over_long_spans_of_a_drifting_heading);
    RUN_TEST(test_odometry_cal_should_judge_pinning_against_odometrys_own_variance);
    RUN_TEST(test_odometry_cal_direction_should_follow_the_reference_and_the_turns);
    RUN_TEST(test_odometry_cal_should_survive_a_nan_reference_and_an_infinite_span);
    RUN_TEST(test_odometry_cal_config_check_should_name_the_bad_field);
    return UNITY_END();
}
