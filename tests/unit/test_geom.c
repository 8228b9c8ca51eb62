/* Unit tests for src/core/geom.c: angle wrapping and the pose algebra. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "rsm/geom.h"
#include "test_support.h"
#include "unity.h"

void setUp(void)
{
}

void tearDown(void)
{
}

static rsm_pose_t random_pose(uint32_t *s)
{
    rsm_pose_t p;
    p.x = rsm_test_rng_uniform(s, -20.0f, 20.0f);
    p.y = rsm_test_rng_uniform(s, -20.0f, 20.0f);
    p.theta = rsm_test_rng_uniform(s, -RSM_PI, RSM_PI);
    return p;
}

/* Distance between two angles on the circle, in double. */
static float angle_gap(double a, double b)
{
    const double two_pi = 6.283185307179586;
    double d = fmod(a - b, two_pi);
    if (d > 0.5 * two_pi) {
        d -= two_pi;
    } else if (d < -0.5 * two_pi) {
        d += two_pi;
    }
    return (float)fabs(d);
}

static void assert_pose_near(const rsm_pose_t *expect, const rsm_pose_t *got, float tol_m, float tol_rad)
{
    TEST_ASSERT_FLOAT_WITHIN(tol_m, expect->x, got->x);
    TEST_ASSERT_FLOAT_WITHIN(tol_m, expect->y, got->y);
    TEST_ASSERT_TRUE(angle_gap(expect->theta, got->theta) <= tol_rad);
    TEST_ASSERT_TRUE(got->theta > -RSM_PI && got->theta <= RSM_PI);
}

void test_wrap_angle_should_map_pi_to_pi(void)
{
    TEST_ASSERT_EQUAL_FLOAT(RSM_PI, rsm_wrap_angle(RSM_PI));
}

void test_wrap_angle_should_map_minus_pi_to_pi(void)
{
    /* The interval is (-pi, pi]: -pi itself is excluded. */
    TEST_ASSERT_EQUAL_FLOAT(RSM_PI, rsm_wrap_angle(-RSM_PI));
}

void test_wrap_angle_should_map_odd_multiples_of_pi_next_to_pi(void)
{
    /* 3 pi in float is not exactly 3 pi, so the result is pi to within a few
     * ulps, on either side of the seam. */
    const float a = rsm_wrap_angle(3.0f * RSM_PI);
    const float b = rsm_wrap_angle(-3.0f * RSM_PI);
    const float c = rsm_wrap_angle(5.0f * RSM_PI);
    TEST_ASSERT_FLOAT_WITHIN(2e-6f, RSM_PI, fabsf(a));
    TEST_ASSERT_FLOAT_WITHIN(2e-6f, RSM_PI, fabsf(b));
    TEST_ASSERT_FLOAT_WITHIN(4e-6f, RSM_PI, fabsf(c));
    TEST_ASSERT_TRUE(a > -RSM_PI && a <= RSM_PI);
    TEST_ASSERT_TRUE(b > -RSM_PI && b <= RSM_PI);
    TEST_ASSERT_TRUE(c > -RSM_PI && c <= RSM_PI);
}

void test_wrap_angle_should_leave_the_interval_alone(void)
{
    const float in[] = { 0.0f, 1e-30f, -1e-30f, 0.5f, -0.5f, 3.0f, -3.0f, 3.1415925f, -3.1415925f };
    size_t i;
    for (i = 0; i < sizeof in / sizeof in[0]; ++i) {
        TEST_ASSERT_EQUAL_FLOAT(in[i], rsm_wrap_angle(in[i]));
    }
    /* Just past either end crosses the seam. */
    TEST_ASSERT_TRUE(rsm_wrap_angle(3.2f) < 0.0f);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 3.2f - RSM_TWO_PI, rsm_wrap_angle(3.2f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, RSM_TWO_PI - 3.2f, rsm_wrap_angle(-3.2f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, rsm_wrap_angle(RSM_TWO_PI));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, rsm_wrap_angle(-RSM_TWO_PI));
}

void test_wrap_angle_should_reduce_large_values_to_input_precision(void)
{
    /* A float of magnitude x is only known to half an ulp, x * 2^-24; the
     * reduction must not lose more than about that. */
    const float in[] = { 7.0f, -7.0f, 100.0f, -100.0f, 1000.0f, -1000.0f, 12345.678f, 1e6f, -1e6f, 3e7f };
    size_t i;
    for (i = 0; i < sizeof in / sizeof in[0]; ++i) {
        const float r = rsm_wrap_angle(in[i]);
        const float tol = fmaxf(1e-6f, fabsf(in[i]) * 1.2e-7f);
        TEST_ASSERT_TRUE(r > -RSM_PI && r <= RSM_PI);
        TEST_ASSERT_TRUE(angle_gap((double)in[i], (double)r) <= tol);
    }
    /* Huge inputs still land in the interval. */
    TEST_ASSERT_TRUE(fabsf(rsm_wrap_angle(1e30f)) <= RSM_PI);
    TEST_ASSERT_TRUE(fabsf(rsm_wrap_angle(-3.4e38f)) <= RSM_PI);
}

void test_wrap_angle_should_pass_non_finite_values_through(void)
{
    TEST_ASSERT_FLOAT_IS_NAN(rsm_wrap_angle(NAN));
    TEST_ASSERT_FLOAT_IS_INF(rsm_wrap_angle(INFINITY));
    TEST_ASSERT_FLOAT_IS_NEG_INF(rsm_wrap_angle(-INFINITY));
}

/* rsm_wrap_angle with fmodf always first, as it was before it skipped
 * fmodf below one turn (fmodf's result is below one turn: no second). */
static float wrap_by_fmodf(float a)
{
    return rsm_wrap_angle(fmodf(a, RSM_TWO_PI));
}

void test_wrap_angle_should_equal_fmodf_first_bit_for_bit(void)
{
    /* fmodf returns a itself below one turn, so skipping it there changes
     * no bit; the turn's edges and beyond go through it. */
    static const float special[] = {0.0f, -0.0f, RSM_PI, -RSM_PI, RSM_TWO_PI, -RSM_TWO_PI, 6.2831850f, -6.2831850f,
                                    6.2831860f, 1.0e-38f, 25.0f, -1.0e6f};
    uint32_t seed = 11u;
    uint32_t mismatches = 0u;
    size_t k;
    int32_t i;
    for (k = 0; k < sizeof special / sizeof special[0]; ++k) {
        const float a = wrap_by_fmodf(special[k]);
        const float b = rsm_wrap_angle(special[k]);
        TEST_ASSERT_EQUAL_MEMORY(&a, &b, sizeof a);
    }
    for (i = 0; i < 200000; ++i) {
        const float x = rsm_test_rng_uniform(&seed, -20.0f, 20.0f);
        const float a = wrap_by_fmodf(x);
        const float b = rsm_wrap_angle(x);
        mismatches += memcmp(&a, &b, sizeof a) != 0 ? 1u : 0u;
    }
    TEST_ASSERT_EQUAL_UINT32(0u, mismatches);
}

void test_pose_compose_should_rotate_then_translate(void)
{
    const rsm_pose_t a = { 1.0f, 2.0f, 0.5f * RSM_PI };
    const rsm_pose_t b = { 3.0f, 0.0f, 0.5f * RSM_PI };
    const rsm_pose_t c = rsm_pose_compose(&a, &b);
    const rsm_point_t p = { 1.0f, 0.0f };
    const rsm_point_t q = rsm_pose_apply(&a, &p);
    /* b's 3 m forward is a's +y; the headings add and wrap. */
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0f, c.x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 5.0f, c.y);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, RSM_PI, c.theta);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0f, q.x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 3.0f, q.y);
}

void test_pose_inverse_should_undo_compose_on_random_poses(void)
{
    uint32_t seed = 424242u;
    const rsm_pose_t id = { 0.0f, 0.0f, 0.0f };
    int k;
    for (k = 0; k < 1000; ++k) {
        const rsm_pose_t a = random_pose(&seed);
        const rsm_pose_t inv = rsm_pose_inverse(&a);
        const rsm_pose_t l = rsm_pose_compose(&inv, &a);
        const rsm_pose_t r = rsm_pose_compose(&a, &inv);
        const rsm_pose_t back = rsm_pose_inverse(&inv);
        const rsm_pose_t same = rsm_pose_compose(&a, &id);
        const rsm_pose_t same2 = rsm_pose_compose(&id, &a);
        assert_pose_near(&id, &l, 2e-5f, 1e-6f);
        assert_pose_near(&id, &r, 2e-5f, 1e-6f);
        assert_pose_near(&a, &back, 2e-5f, 1e-6f);
        assert_pose_near(&a, &same, 1e-6f, 1e-7f);
        assert_pose_near(&a, &same2, 1e-6f, 1e-7f);
    }
}

void test_pose_between_should_be_the_relative_pose_on_random_poses(void)
{
    uint32_t seed = 777u;
    int k;
    for (k = 0; k < 1000; ++k) {
        const rsm_pose_t a = random_pose(&seed);
        const rsm_pose_t b = random_pose(&seed);
        const rsm_pose_t d = rsm_pose_between(&a, &b);
        const rsm_pose_t b2 = rsm_pose_compose(&a, &d);
        const rsm_pose_t ab = rsm_pose_compose(&a, &b);
        const rsm_pose_t b3 = rsm_pose_between(&a, &ab);
        const rsm_pose_t self = rsm_pose_between(&a, &a);
        const rsm_pose_t id = { 0.0f, 0.0f, 0.0f };
        assert_pose_near(&b, &b2, 5e-5f, 1e-6f);
        assert_pose_near(&b, &b3, 5e-5f, 1e-6f);
        assert_pose_near(&id, &self, 2e-5f, 1e-7f);
    }
}

void test_pose_compose_should_be_associative_and_agree_with_apply(void)
{
    uint32_t seed = 99991u;
    int k;
    for (k = 0; k < 1000; ++k) {
        const rsm_pose_t a = random_pose(&seed);
        const rsm_pose_t b = random_pose(&seed);
        const rsm_pose_t c = random_pose(&seed);
        const rsm_pose_t ab = rsm_pose_compose(&a, &b);
        const rsm_pose_t bc = rsm_pose_compose(&b, &c);
        const rsm_pose_t l = rsm_pose_compose(&ab, &c);
        const rsm_pose_t r = rsm_pose_compose(&a, &bc);
        rsm_point_t p;
        rsm_point_t q1;
        rsm_point_t q2;
        rsm_point_t tmp;
        assert_pose_near(&l, &r, 1e-4f, 1e-6f);
        p.x = rsm_test_rng_uniform(&seed, -10.0f, 10.0f);
        p.y = rsm_test_rng_uniform(&seed, -10.0f, 10.0f);
        q1 = rsm_pose_apply(&ab, &p);
        tmp = rsm_pose_apply(&b, &p);
        q2 = rsm_pose_apply(&a, &tmp);
        TEST_ASSERT_FLOAT_WITHIN(1e-4f, q2.x, q1.x);
        TEST_ASSERT_FLOAT_WITHIN(1e-4f, q2.y, q1.y);
    }
}

void test_pose_apply_should_preserve_distances(void)
{
    uint32_t seed = 5u;
    int k;
    for (k = 0; k < 200; ++k) {
        const rsm_pose_t a = random_pose(&seed);
        rsm_point_t p;
        rsm_point_t q;
        rsm_point_t pa;
        rsm_point_t qa;
        p.x = rsm_test_rng_uniform(&seed, -10.0f, 10.0f);
        p.y = rsm_test_rng_uniform(&seed, -10.0f, 10.0f);
        q.x = rsm_test_rng_uniform(&seed, -10.0f, 10.0f);
        q.y = rsm_test_rng_uniform(&seed, -10.0f, 10.0f);
        pa = rsm_pose_apply(&a, &p);
        qa = rsm_pose_apply(&a, &q);
        TEST_ASSERT_FLOAT_WITHIN(1e-4f, hypotf(p.x - q.x, p.y - q.y), hypotf(pa.x - qa.x, pa.y - qa.y));
    }
}

/* Poses apart: by distance or by heading, at the thresholds themselves,
 * and the distance seen from a (a turned a does not change it). */
static void test_pose_apart_should_judge_distance_and_heading(void)
{
    const rsm_pose_t a = {1.0f, 2.0f, 1.2f};
    rsm_pose_t b = a;
    TEST_ASSERT_EQUAL_INT(0, rsm_pose_apart(&a, &b, 0.1f, 0.1f));
    b.x += 0.09f;
    TEST_ASSERT_EQUAL_INT(0, rsm_pose_apart(&a, &b, 0.1f, 0.1f));
    b.y += 0.05f; /* 0.103 m away */
    TEST_ASSERT_EQUAL_INT(1, rsm_pose_apart(&a, &b, 0.1f, 0.1f));
    TEST_ASSERT_EQUAL_INT(0, rsm_pose_apart(&a, &b, 0.2f, 0.1f));
    b = a;
    b.theta = rsm_wrap_angle(a.theta - 0.15f);
    TEST_ASSERT_EQUAL_INT(1, rsm_pose_apart(&a, &b, 0.1f, 0.1f));
    TEST_ASSERT_EQUAL_INT(0, rsm_pose_apart(&a, &b, 0.1f, 0.2f));
    /* Across the wrap of the heading: 0.04 rad apart, not 2 pi. */
    b = a;
    b.theta = 3.12f;
    {
        rsm_pose_t c = a;
        c.theta = -3.12f;
        TEST_ASSERT_EQUAL_INT(0, rsm_pose_apart(&b, &c, 0.1f, 0.1f));
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_wrap_angle_should_map_pi_to_pi);
    RUN_TEST(test_wrap_angle_should_map_minus_pi_to_pi);
    RUN_TEST(test_wrap_angle_should_map_odd_multiples_of_pi_next_to_pi);
    RUN_TEST(test_wrap_angle_should_leave_the_interval_alone);
    RUN_TEST(test_wrap_angle_should_reduce_large_values_to_input_precision);
    RUN_TEST(test_wrap_angle_should_pass_non_finite_values_through);
    RUN_TEST(test_wrap_angle_should_equal_fmodf_first_bit_for_bit);
    RUN_TEST(test_pose_compose_should_rotate_then_translate);
    RUN_TEST(test_pose_inverse_should_undo_compose_on_random_poses);
    RUN_TEST(test_pose_between_should_be_the_relative_pose_on_random_poses);
    RUN_TEST(test_pose_compose_should_be_associative_and_agree_with_apply);
    RUN_TEST(test_pose_apply_should_preserve_distances);
    RUN_TEST(test_pose_apart_should_judge_distance_and_heading);
    return UNITY_END();
}
