/* Unit tests for src/core/fmath.c: the core's own float functions against libm in
 * double (the reference), over many arguments, and their special values. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "core/fmath.h"
#include "test_support.h"
#include "unity.h"

void setUp(void)
{
}

void tearDown(void)
{
}

/* Spacing of floats at |r| (the smallest subnormal at 0). */
static double ulp_of(double r)
{
    int e;
    double u;
    if (r == 0.0) {
        return ldexp(1.0, -149);
    }
    (void)frexp(fabs(r), &e);
    u = ldexp(1.0, e - 24);
    return u < ldexp(1.0, -149) ? ldexp(1.0, -149) : u;
}

static uint32_t bits_of(float x)
{
    uint32_t b;
    memcpy(&b, &x, sizeof b);
    return b;
}

typedef struct err_max {
    double abs;
    double ulp;
} err_max_t;

static void note(err_max_t *m, double got, double ref)
{
    const double e = fabs(got - ref);
    if (e > m->abs) {
        m->abs = e;
    }
    if (e / ulp_of(ref) > m->ulp) {
        m->ulp = e / ulp_of(ref);
    }
}

void test_sinf_cosf_should_be_within_6e8_up_to_8192(void)
{
    err_max_t s = {0.0, 0.0};
    err_max_t c = {0.0, 0.0};
    int32_t i;
    /* 8 million evenly spread angles: every reduction quadrant many times. */
    for (i = -4000000; i <= 4000000; ++i) {
        const float x = (float)i * (8192.0f / 4000000.0f);
        note(&s, (double)rsm_sinf(x), sin((double)x));
        note(&c, (double)rsm_cosf(x), cos((double)x));
    }
    printf("fmath: |x| <= 8192: sin max abs error %.3g, cos %.3g\n", s.abs, c.abs);
    TEST_ASSERT_TRUE(s.abs <= 6.0e-8);
    TEST_ASSERT_TRUE(c.abs <= 6.0e-8);
}

void test_sinf_cosf_should_be_within_1_ulp_near_the_angles_used(void)
{
    err_max_t s = {0.0, 0.0};
    err_max_t c = {0.0, 0.0};
    int32_t i;
    for (i = 0; i <= 2000000; ++i) {
        const float x = -7.0f + (float)i * (14.0f / 2000000.0f);
        note(&s, (double)rsm_sinf(x), sin((double)x));
        note(&c, (double)rsm_cosf(x), cos((double)x));
    }
    /* The closest floats to the zeros are the hardest (most cancellation). */
    {
        const float pi_f = 3.14159274f;
        const float pio2_f = 1.57079637f;
        note(&s, (double)rsm_sinf(pi_f), sin((double)pi_f));
        note(&c, (double)rsm_cosf(pio2_f), cos((double)pio2_f));
    }
    printf("fmath: |x| <= 7: sin max error %.3f ulp, cos %.3f ulp\n", s.ulp, c.ulp);
    TEST_ASSERT_TRUE(s.ulp <= 1.0);
    TEST_ASSERT_TRUE(c.ulp <= 1.0);
}

void test_sinf_cosf_should_keep_sign_of_zero_and_reject_non_finite(void)
{
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_sinf(-0.0f));
    TEST_ASSERT_TRUE(signbit(rsm_sinf(-0.0f)));
    TEST_ASSERT_EQUAL_FLOAT(1.0f, rsm_cosf(0.0f));
    TEST_ASSERT_TRUE(isnan(rsm_sinf(INFINITY)));
    TEST_ASSERT_TRUE(isnan(rsm_cosf(-INFINITY)));
    TEST_ASSERT_TRUE(isnan(rsm_sinf(NAN)));
    /* Beyond the exact reduction: still a sine, roughly. */
    TEST_ASSERT_TRUE(fabsf(rsm_sinf(1.0e7f)) <= 1.0f);
}

void test_sincosf_should_give_sinf_and_cosf_bit_for_bit(void)
{
    static const float special[] = {0.0f, -0.0f, 1.0e-30f, -1.0e-30f, 0x1p-12f, -0x1p-12f, 0x1.fffffep-13f,
                                    0.785398f, 1.5707964f, -3.1415927f, 3.1415927f, 24999.0f, -25001.0f,
                                    1.0e7f, -1.0e20f};
    uint32_t seed = 5u;
    uint32_t mismatches = 0u;
    float s;
    float c;
    size_t k;
    int32_t i;
    for (k = 0; k < sizeof special / sizeof special[0]; ++k) {
        rsm_sincosf(special[k], &s, &c);
        TEST_ASSERT_EQUAL_HEX32(bits_of(rsm_sinf(special[k])), bits_of(s));
        TEST_ASSERT_EQUAL_HEX32(bits_of(rsm_cosf(special[k])), bits_of(c));
    }
    for (i = 0; i < 200000; ++i) {
        const float x = rsm_test_rng_uniform(&seed, -40.0f, 40.0f);
        rsm_sincosf(x, &s, &c);
        mismatches += bits_of(rsm_sinf(x)) != bits_of(s) ? 1u : 0u;
        mismatches += bits_of(rsm_cosf(x)) != bits_of(c) ? 1u : 0u;
    }
    TEST_ASSERT_EQUAL_UINT32(0u, mismatches);
    rsm_sincosf(INFINITY, &s, &c);
    TEST_ASSERT_TRUE(isnan(s) && isnan(c));
    rsm_sincosf(NAN, &s, &c);
    TEST_ASSERT_TRUE(isnan(s) && isnan(c));
}

void test_atan2f_should_be_within_3_ulp_all_around(void)
{
    err_max_t a = {0.0, 0.0};
    uint32_t seed = 11u;
    int32_t i;
    for (i = 0; i < 4000000; ++i) {
        const float ang = rsm_test_rng_uniform(&seed, -3.14159265f, 3.14159265f);
        const float r = rsm_test_rng_uniform(&seed, 1.0e-3f, 10.0f);
        const float y = r * (float)sin((double)ang);
        const float x = r * (float)cos((double)ang);
        note(&a, (double)rsm_atan2f(y, x), atan2((double)y, (double)x));
    }
    printf("fmath: atan2 max error %.3f ulp, %.3g absolute\n", a.ulp, a.abs);
    TEST_ASSERT_TRUE(a.ulp <= 3.0);
    TEST_ASSERT_TRUE(a.abs <= 3.0e-7);
}

void test_atan2f_should_follow_c99_on_zeros_and_infinities(void)
{
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_atan2f(0.0f, 1.0f));
    TEST_ASSERT_TRUE(signbit(rsm_atan2f(-0.0f, 1.0f)));
    TEST_ASSERT_EQUAL_FLOAT(3.14159265f, rsm_atan2f(0.0f, -1.0f));
    TEST_ASSERT_EQUAL_FLOAT(-3.14159265f, rsm_atan2f(-0.0f, -1.0f));
    TEST_ASSERT_EQUAL_FLOAT(3.14159265f, rsm_atan2f(0.0f, -0.0f));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_atan2f(0.0f, 0.0f));
    TEST_ASSERT_EQUAL_FLOAT(1.57079633f, rsm_atan2f(2.0f, 0.0f));
    TEST_ASSERT_EQUAL_FLOAT(-1.57079633f, rsm_atan2f(-2.0f, -0.0f));
    TEST_ASSERT_EQUAL_FLOAT(0.78539816f, rsm_atan2f(INFINITY, INFINITY));
    TEST_ASSERT_EQUAL_FLOAT(2.35619449f, rsm_atan2f(INFINITY, -INFINITY));
    TEST_ASSERT_EQUAL_FLOAT(1.57079633f, rsm_atan2f(INFINITY, 5.0f));
    TEST_ASSERT_EQUAL_FLOAT(3.14159265f, rsm_atan2f(5.0f, -INFINITY));
    TEST_ASSERT_TRUE(isnan(rsm_atan2f(NAN, 1.0f)));
    TEST_ASSERT_TRUE(isnan(rsm_atan2f(1.0f, NAN)));
}

void test_logf_should_be_within_2_ulp_over_the_exponent_range(void)
{
    err_max_t l = {0.0, 0.0};
    uint32_t seed = 5u;
    int32_t i;
    for (i = 0; i < 4000000; ++i) {
        const float m = rsm_test_rng_uniform(&seed, 0.5f, 1.0f);
        const int e = (int)(i % 250) - 125;
        const float x = ldexpf(m, e);
        note(&l, (double)rsm_logf(x), log((double)x));
    }
    note(&l, (double)rsm_logf(1.0e-40f), log((double)1.0e-40f)); /* subnormal */
    printf("fmath: log max error %.3f ulp\n", l.ulp);
    TEST_ASSERT_TRUE(l.ulp <= 2.0);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_logf(1.0f));
    TEST_ASSERT_TRUE(isinf(rsm_logf(0.0f)) && rsm_logf(0.0f) < 0.0f);
    TEST_ASSERT_TRUE(isnan(rsm_logf(-1.0f)));
    TEST_ASSERT_TRUE(isnan(rsm_logf(NAN)));
    TEST_ASSERT_TRUE(isinf(rsm_logf(INFINITY)) && rsm_logf(INFINITY) > 0.0f);
}

void test_floorf_ceilf_should_equal_libm_exactly(void)
{
    static const float special[] = {0.0f, -0.0f, 0.3f, -0.3f, 1.0f, -1.0f, 2.5f, -2.5f, 8388607.5f,
                                    -8388607.5f, 8388608.0f, 1.0e20f, -1.0e20f, 1.0e-40f, -1.0e-40f};
    uint32_t seed = 3u;
    uint32_t mismatches = 0u;
    size_t k;
    int32_t i;
    for (k = 0; k < sizeof special / sizeof special[0]; ++k) {
        const float x = special[k];
        TEST_ASSERT_EQUAL_HEX32(bits_of(floorf(x)), bits_of(rsm_floorf(x)));
        TEST_ASSERT_EQUAL_HEX32(bits_of(ceilf(x)), bits_of(rsm_ceilf(x)));
    }
    for (i = 0; i < 1000000; ++i) {
        const float x = rsm_test_rng_uniform(&seed, -1000.0f, 1000.0f);
        mismatches += bits_of(floorf(x)) != bits_of(rsm_floorf(x)) ? 1u : 0u;
        mismatches += bits_of(ceilf(x)) != bits_of(rsm_ceilf(x)) ? 1u : 0u;
    }
    TEST_ASSERT_EQUAL_UINT32(0u, mismatches);
    TEST_ASSERT_TRUE(isinf(rsm_floorf(INFINITY)));
    TEST_ASSERT_TRUE(isnan(rsm_ceilf(NAN)));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_sinf_cosf_should_be_within_6e8_up_to_8192);
    RUN_TEST(test_sinf_cosf_should_be_within_1_ulp_near_the_angles_used);
    RUN_TEST(test_sinf_cosf_should_keep_sign_of_zero_and_reject_non_finite);
    RUN_TEST(test_sincosf_should_give_sinf_and_cosf_bit_for_bit);
    RUN_TEST(test_atan2f_should_be_within_3_ulp_all_around);
    RUN_TEST(test_atan2f_should_follow_c99_on_zeros_and_infinities);
    RUN_TEST(test_logf_should_be_within_2_ulp_over_the_exponent_range);
    RUN_TEST(test_floorf_ceilf_should_equal_libm_exactly);
    return UNITY_END();
}
