/* Deterministic two-point RANSAC: recovery of known rigid transforms under
 * 30/50/70 % wrong matches, the early length test, exhaustive versus sampled
 * hypotheses, reproducibility, failure modes and the atan2 quadrant. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "rsm/config.h"
#include "paper/rigid.h"
#include "paper/ransac.h"
#include "rsm/status.h"
#include "synth.h"
#include "unity.h"

#define DEG (RSM_PI / 180.0f)
/* 30 matches fit the small configuration (RSM_MAX_MATCHES 32) too. */
#define NPTS 30u

static rsm_ransac_t rs;
static rsm_ransac_t rs2;
static rsm_ransac_config_t cfg;
static rsm_point_t ref[RSM_MAX_MATCHES + 1];
static rsm_point_t cur[RSM_MAX_MATCHES + 1];
static rsm_match_t m[RSM_MAX_MATCHES + 1];
static uint8_t wrong[RSM_MAX_MATCHES + 1];

RSM_STATIC_ASSERT(test_points_fit, NPTS <= RSM_MAX_MATCHES);

void setUp(void)
{
    cfg = rsm_ransac_config_default();
    memset(wrong, 0, sizeof wrong);
}

void tearDown(void)
{
}

/* n reference key points in a 6 m square, at least 0.3 m apart. */
static void make_reference(size_t n, uint32_t seed)
{
    rsm_synth_rng_t rng;
    size_t k = 0;
    rsm_synth_rng_seed(&rng, seed);
    while (k < n) {
        const float x = 6.0f * rsm_synth_rng_uniform(&rng) - 3.0f;
        const float y = 6.0f * rsm_synth_rng_uniform(&rng) - 3.0f;
        size_t j;
        int ok = 1;
        for (j = 0; j < k; ++j) {
            const float dx = ref[j].x - x;
            const float dy = ref[j].y - y;
            if (dx * dx + dy * dy < 0.09f) {
                ok = 0;
                break;
            }
        }
        if (ok) {
            ref[k].x = x;
            ref[k].y = y;
            ++k;
        }
    }
}

/* cur[i] = inverse(t) applied to ref[i], so that ref = t (+) cur exactly
 * (up to float rounding; computed in double). */
static void make_current(const rsm_pose_t *t, size_t n)
{
    const double c = cos((double)t->theta);
    const double s = sin((double)t->theta);
    size_t k;
    for (k = 0; k < n; ++k) {
        const double dx = (double)ref[k].x - (double)t->x;
        const double dy = (double)ref[k].y - (double)t->y;
        cur[k].x = (float)(c * dx + s * dy);
        cur[k].y = (float)(-s * dx + c * dy);
    }
}

/* One match per reference point (so grouped by reference index), n_wrong of
 * them, chosen by the seed, pointing at another current point. */
static void make_matches(size_t n, size_t n_wrong, uint32_t seed)
{
    rsm_synth_rng_t rng;
    size_t need = n_wrong;
    size_t k;
    rsm_synth_rng_seed(&rng, seed);
    for (k = 0; k < n; ++k) {
        m[k].ref = (uint16_t)k;
        m[k].cur = (uint16_t)k;
        wrong[k] = 0;
        if ((size_t)(rsm_synth_rng_next(&rng) % (uint32_t)(n - k)) < need) {
            const size_t off = 1u + (size_t)(rsm_synth_rng_next(&rng) % (uint32_t)(n - 1u));
            m[k].cur = (uint16_t)((k + off) % n);
            wrong[k] = 1;
            --need;
        }
    }
}

static void assert_pose_near(const rsm_pose_t *expected, const rsm_pose_t *actual, float tol_m, float tol_rad)
{
    char msg[160];
    const float dth = fabsf(rsm_wrap_angle(actual->theta - expected->theta));
    snprintf(msg, sizeof msg, "expected (%.5f, %.5f, %.4f deg) got (%.5f, %.5f, %.4f deg)", (double)expected->x,
             (double)expected->y, (double)(expected->theta / DEG), (double)actual->x, (double)actual->y,
             (double)(actual->theta / DEG));
    TEST_ASSERT_FLOAT_WITHIN_MESSAGE(tol_m, expected->x, actual->x, msg);
    TEST_ASSERT_FLOAT_WITHIN_MESSAGE(tol_m, expected->y, actual->y, msg);
    TEST_ASSERT_TRUE_MESSAGE(dth < tol_rad, msg);
}

/* Builds the data, runs a fresh RANSAC and checks an exact recovery: the
 * pose within 1 mm / 0.05 deg, support = the correct matches, and every
 * inlier flag right. */
static void check_recovery(float x, float y, float theta_deg, size_t n_wrong, uint32_t seed)
{
    rsm_pose_t t;
    rsm_ransac_result_t res;
    size_t k;
    t.x = x;
    t.y = y;
    t.theta = theta_deg * DEG;
    make_reference(NPTS, seed);
    make_current(&t, NPTS);
    make_matches(NPTS, n_wrong, seed * 7u + 1u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, NPTS, &res));
    assert_pose_near(&t, &res.t, 1.0e-3f, 0.05f * DEG);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)(NPTS - n_wrong), res.support);
    TEST_ASSERT_LESS_THAN_FLOAT(1.0e-4f, res.rms_m);
    for (k = 0; k < NPTS; ++k) {
        TEST_ASSERT_EQUAL_UINT8(wrong[k] ? 0u : 1u, rs.inlier[k]);
    }
    /* 435 pairs exceed the default budget of 300: sampled. */
    TEST_ASSERT_EQUAL_UINT32(0, res.exhaustive);
    TEST_ASSERT_TRUE(res.iterations >= 1u && res.iterations <= cfg.max_iterations);
}

/* ---- configuration ------------------------------------------------------- */

void test_ransac_config_default_should_hold_the_documented_values(void)
{
    const rsm_ransac_config_t c = rsm_ransac_config_default();
    TEST_ASSERT_EQUAL_FLOAT(0.075f, c.inlier_tol_m);
    TEST_ASSERT_EQUAL_FLOAT(0.1f, c.length_tol_m);
    TEST_ASSERT_EQUAL_FLOAT(0.2f, c.min_pair_sep_m);
    TEST_ASSERT_EQUAL_FLOAT(0.99f, c.confidence);
    TEST_ASSERT_EQUAL_UINT32(300u, c.max_iterations);
    TEST_ASSERT_EQUAL_UINT32(5u, c.min_support);
    TEST_ASSERT_NOT_EQUAL(0u, c.seed);
}

void test_ransac_init_should_reject_bad_configs(void)
{
    rsm_ransac_config_t c = cfg;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(NULL, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(&rs, NULL));
    c.inlier_tol_m = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(&rs, &c));
    c = cfg;
    c.inlier_tol_m = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(&rs, &c));
    c = cfg;
    c.length_tol_m = -0.1f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(&rs, &c));
    c = cfg;
    c.min_pair_sep_m = -1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(&rs, &c));
    c = cfg;
    c.confidence = 1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(&rs, &c));
    c.confidence = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(&rs, &c));
    c = cfg;
    c.max_iterations = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(&rs, &c));
    c = cfg;
    c.min_support = 1u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_init(&rs, &c));
    c = cfg;
    c.seed = 0u; /* allowed: replaced by a fixed non-zero seed */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &c));
}

/* ---- recovery ---------------------------------------------------------------- */

void test_ransac_estimate_should_recover_a_transform_from_exact_matches(void)
{
    check_recovery(0.0f, 0.0f, 0.0f, 0u, 11u);
    check_recovery(0.3f, -0.4f, 30.0f, 0u, 12u);
}

void test_ransac_estimate_should_recover_a_transform_with_30_percent_wrong_matches(void)
{
    check_recovery(0.5f, 0.0f, 30.0f, 9u, 21u);
    check_recovery(-0.35f, 0.35f, -30.0f, 9u, 22u);
    check_recovery(0.1f, 0.45f, 12.5f, 9u, 23u);
}

void test_ransac_estimate_should_recover_a_transform_with_50_percent_wrong_matches(void)
{
    check_recovery(0.0f, -0.5f, -25.0f, 15u, 31u);
    check_recovery(0.4f, 0.3f, 7.0f, 15u, 32u);
    check_recovery(-0.2f, -0.2f, 29.9f, 15u, 33u);
}

void test_ransac_estimate_should_recover_a_transform_with_70_percent_wrong_matches(void)
{
    check_recovery(-0.5f, 0.0f, 20.0f, 21u, 41u);
    check_recovery(0.3f, 0.4f, -30.0f, 21u, 42u);
    check_recovery(0.05f, -0.1f, -3.0f, 21u, 43u);
}

void test_ransac_estimate_should_recover_rotations_near_180_degrees(void)
{
    /* atan(x / y) folds these into (-90, 90) degrees; atan2 keeps the quadrant. */
    check_recovery(0.2f, -0.1f, 179.0f, 9u, 51u);
    check_recovery(-0.3f, 0.25f, -179.5f, 9u, 52u);
    check_recovery(0.0f, 0.5f, 180.0f, 9u, 53u);
    check_recovery(0.4f, 0.0f, 135.0f, 9u, 54u);
    check_recovery(-0.1f, -0.4f, -100.0f, 9u, 55u);
}

void test_ransac_estimate_should_refine_by_least_squares_over_the_inliers(void)
{
    /* 1 cm noise on the current points: any two-point hypothesis is off by
     * centimetres, the least-squares refit over all 20 inliers is the
     * result (rsm_rigid_fit over exactly the correct matches). */
    const rsm_pose_t t = {0.3f, -0.2f, 0.35f};
    static rsm_point_t src[NPTS];
    static rsm_point_t dst[NPTS];
    rsm_synth_rng_t rng;
    rsm_ransac_result_t res;
    rsm_pose_t ls;
    size_t n = 0;
    size_t k;
    make_reference(NPTS, 71u);
    make_current(&t, NPTS);
    make_matches(NPTS, 10u, 72u);
    rsm_synth_rng_seed(&rng, 73u);
    for (k = 0; k < NPTS; ++k) {
        cur[k].x += 0.01f * rsm_synth_rng_gauss(&rng);
        cur[k].y += 0.01f * rsm_synth_rng_gauss(&rng);
    }
    for (k = 0; k < NPTS; ++k) {
        if (!wrong[k]) {
            src[n] = cur[m[k].cur];
            dst[n] = ref[m[k].ref];
            ++n;
        }
    }
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rigid_fit(src, dst, NULL, n, &ls));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, NPTS, &res));
    TEST_ASSERT_EQUAL_UINT32(20u, res.support);
    TEST_ASSERT_FLOAT_WITHIN(1.0e-5f, ls.x, res.t.x);
    TEST_ASSERT_FLOAT_WITHIN(1.0e-5f, ls.y, res.t.y);
    TEST_ASSERT_FLOAT_WITHIN(1.0e-6f, ls.theta, res.t.theta);
    assert_pose_near(&t, &res.t, 0.006f, 0.3f * DEG);
    /* The RMS residual reflects the noise (about 1.4 cm per point). */
    TEST_ASSERT_TRUE(res.rms_m > 0.005f && res.rms_m < 0.025f);
}

/* ---- the early length test ---------------------------------------------------- */

void test_ransac_estimate_should_count_samples_stopped_by_the_length_test(void)
{
    rsm_ransac_result_t res;
    /* Three matches, exhaustive: pair (0, 1) is consistent, both pairs with
     * the wrong match 2 differ in length by > length_tol. */
    ref[0].x = 0.0f;
    ref[0].y = 0.0f;
    ref[1].x = 1.0f;
    ref[1].y = 0.0f;
    ref[2].x = 0.0f;
    ref[2].y = 1.0f;
    cur[0] = ref[0];
    cur[1] = ref[1];
    cur[2].x = 0.0f; /* |c0 - c2| = 2 vs 1; |c1 - c2| = 2.24 vs 1.41 */
    cur[2].y = 2.0f;
    m[0].ref = 0;
    m[0].cur = 0;
    m[1].ref = 1;
    m[1].cur = 1;
    m[2].ref = 2;
    m[2].cur = 2;
    cfg.min_support = 2u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, 3, &res));
    TEST_ASSERT_EQUAL_UINT32(1u, res.exhaustive);
    TEST_ASSERT_EQUAL_UINT32(3u, res.iterations);
    TEST_ASSERT_EQUAL_UINT32(2u, res.length_rejects);
    TEST_ASSERT_EQUAL_UINT32(2u, res.support);
    TEST_ASSERT_FLOAT_WITHIN(1.0e-6f, 0.0f, res.t.x);
    TEST_ASSERT_FLOAT_WITHIN(1.0e-6f, 0.0f, res.t.y);
    TEST_ASSERT_FLOAT_WITHIN(1.0e-6f, 0.0f, res.t.theta);
    TEST_ASSERT_EQUAL_UINT8(1, rs.inlier[0]);
    TEST_ASSERT_EQUAL_UINT8(1, rs.inlier[1]);
    TEST_ASSERT_EQUAL_UINT8(0, rs.inlier[2]);
    /* Within the tolerance the sample is not rejected. */
    cur[2].y = 1.05f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, 3, &res));
    TEST_ASSERT_EQUAL_UINT32(0u, res.length_rejects);
}

void test_ransac_estimate_should_not_reject_any_sample_on_exact_data(void)
{
    const rsm_pose_t t = {0.25f, -0.3f, 0.4f};
    rsm_ransac_result_t res;
    make_reference(NPTS, 61u);
    make_current(&t, NPTS);
    make_matches(NPTS, 0u, 62u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, NPTS, &res));
    TEST_ASSERT_EQUAL_UINT32(0u, res.length_rejects);
    TEST_ASSERT_EQUAL_UINT32(NPTS, res.support);
    /* Every match is an inlier: eq. 16 is met by the first clean hypothesis
     * (a draw of the same match twice counts as an iteration too). */
    TEST_ASSERT_TRUE(res.iterations >= 1u && res.iterations <= 3u);
}

void test_ransac_estimate_should_reject_wrong_samples_by_length_with_wrong_matches(void)
{
    const rsm_pose_t t = {0.25f, -0.3f, 0.4f};
    rsm_ransac_result_t res;
    make_reference(NPTS, 63u);
    make_current(&t, NPTS);
    make_matches(NPTS, 15u, 64u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, NPTS, &res));
    TEST_ASSERT_GREATER_THAN_UINT32(0u, res.length_rejects);
    TEST_ASSERT_TRUE(res.length_rejects <= res.iterations);
}

/* ---- exhaustive versus sampled ------------------------------------------------- */

void test_ransac_estimate_should_enumerate_all_pairs_when_within_budget(void)
{
    const rsm_pose_t t = {-0.2f, 0.1f, -0.3f};
    rsm_ransac_result_t res;
    make_reference(11u, 71u);
    make_current(&t, 11u);
    make_matches(11u, 3u, 72u);
    cfg.max_iterations = 45u; /* = 10 * 9 / 2 */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, 10u, &res));
    TEST_ASSERT_EQUAL_UINT32(1u, res.exhaustive);
    TEST_ASSERT_EQUAL_UINT32(45u, res.iterations);
    assert_pose_near(&t, &res.t, 1.0e-3f, 0.05f * DEG);
    /* One match more: 55 pairs exceed the budget, so hypotheses are sampled. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, 11u, &res));
    TEST_ASSERT_EQUAL_UINT32(0u, res.exhaustive);
    TEST_ASSERT_TRUE(res.iterations >= 1u && res.iterations <= 45u);
    assert_pose_near(&t, &res.t, 1.0e-3f, 0.05f * DEG);
}

/* ---- reproducibility ------------------------------------------------------------ */

void test_ransac_estimate_should_be_bit_identical_across_fresh_inits(void)
{
    const rsm_pose_t t = {0.45f, -0.15f, 0.5f};
    rsm_ransac_result_t r1;
    rsm_ransac_result_t r2;
    make_reference(NPTS, 81u);
    make_current(&t, NPTS);
    make_matches(NPTS, 15u, 82u);
    memset(&r1, 0, sizeof r1);
    memset(&r2, 0xFF, sizeof r2);
    memset(&rs2, 0xA5, sizeof rs2); /* stale contents must not matter */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs2, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, NPTS, &r1));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs2, ref, cur, m, NPTS, &r2));
    TEST_ASSERT_EQUAL_MEMORY(&r1, &r2, sizeof r1);
    TEST_ASSERT_EQUAL_MEMORY(rs.inlier, rs2.inlier, NPTS);
    TEST_ASSERT_EQUAL_UINT32(rs.rng, rs2.rng);
}

void test_ransac_init_should_treat_seed_zero_as_the_default_seed(void)
{
    const rsm_pose_t t = {0.1f, 0.2f, -0.2f};
    rsm_ransac_config_t c0 = cfg;
    rsm_ransac_result_t r1;
    rsm_ransac_result_t r2;
    c0.seed = 0u;
    make_reference(NPTS, 83u);
    make_current(&t, NPTS);
    make_matches(NPTS, 15u, 84u);
    memset(&r1, 0, sizeof r1);
    memset(&r2, 0, sizeof r2);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs2, &c0));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, NPTS, &r1));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs2, ref, cur, m, NPTS, &r2));
    TEST_ASSERT_EQUAL_MEMORY(&r1, &r2, sizeof r1);
}

/* ---- failures ------------------------------------------------------------------- */

void test_ransac_estimate_should_fail_with_identity_when_support_is_too_low(void)
{
    const rsm_pose_t t = {0.3f, 0.3f, 0.3f};
    rsm_ransac_result_t res;
    /* Ten matches, four correct: exhaustive search finds support 4 < 5. */
    make_reference(10u, 91u);
    make_current(&t, 10u);
    make_matches(10u, 6u, 92u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ransac_estimate(&rs, ref, cur, m, 10u, &res));
    TEST_ASSERT_EQUAL_UINT32(4u, res.support);
    TEST_ASSERT_EQUAL_UINT32(1u, res.exhaustive);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, res.t.x);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, res.t.y);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, res.t.theta);
    /* The same data succeeds once four inliers are enough. */
    cfg.min_support = 4u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, 10u, &res));
    assert_pose_near(&t, &res.t, 1.0e-3f, 0.05f * DEG);
}

void test_ransac_estimate_should_fail_when_every_match_is_wrong(void)
{
    const rsm_pose_t t = {0.3f, -0.3f, 1.0f};
    rsm_ransac_result_t res;
    make_reference(NPTS, 93u);
    make_current(&t, NPTS);
    make_matches(NPTS, NPTS, 94u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ransac_estimate(&rs, ref, cur, m, NPTS, &res));
    TEST_ASSERT_LESS_THAN_UINT32(cfg.min_support, res.support);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, res.t.x);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, res.t.y);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, res.t.theta);
}

void test_ransac_estimate_should_fail_on_fewer_than_two_matches(void)
{
    rsm_ransac_result_t res;
    make_reference(2u, 95u);
    cur[0] = ref[0];
    m[0].ref = 0;
    m[0].cur = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ransac_estimate(&rs, ref, cur, m, 1u, &res));
    TEST_ASSERT_EQUAL_UINT32(0u, res.support);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ransac_estimate(&rs, ref, cur, m, 0u, &res));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ransac_estimate(&rs, NULL, NULL, NULL, 0u, &res));
}

void test_ransac_estimate_should_refuse_more_than_rsm_max_matches(void)
{
    rsm_ransac_result_t res;
    size_t k;
    for (k = 0; k <= (size_t)RSM_MAX_MATCHES; ++k) {
        ref[k].x = (float)k;
        ref[k].y = 0.0f;
        cur[k] = ref[k];
        m[k].ref = (uint16_t)k;
        m[k].cur = (uint16_t)k;
    }
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM,
                          rsm_ransac_estimate(&rs, ref, cur, m, (size_t)RSM_MAX_MATCHES + 1u, &res));
    /* Exactly at capacity is fine. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_estimate(&rs, ref, cur, m, (size_t)RSM_MAX_MATCHES, &res));
    TEST_ASSERT_EQUAL_UINT32((uint32_t)RSM_MAX_MATCHES, res.support);
}

void test_ransac_estimate_should_reject_invalid_arguments(void)
{
    rsm_ransac_result_t res;
    rsm_ransac_t blank;
    make_reference(4u, 97u);
    make_current(&((rsm_pose_t){0.0f, 0.0f, 0.0f}), 4u);
    make_matches(4u, 0u, 98u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ransac_init(&rs, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_estimate(NULL, ref, cur, m, 4u, &res));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_estimate(&rs, NULL, cur, m, 4u, &res));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_estimate(&rs, ref, NULL, m, 4u, &res));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_estimate(&rs, ref, cur, NULL, 4u, &res));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_estimate(&rs, ref, cur, m, 4u, NULL));
    memset(&blank, 0, sizeof blank); /* never initialised: no config */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ransac_estimate(&blank, ref, cur, m, 4u, &res));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_ransac_config_default_should_hold_the_documented_values);
    RUN_TEST(test_ransac_init_should_reject_bad_configs);
    RUN_TEST(test_ransac_estimate_should_recover_a_transform_from_exact_matches);
    RUN_TEST(test_ransac_estimate_should_recover_a_transform_with_30_percent_wrong_matches);
    RUN_TEST(test_ransac_estimate_should_recover_a_transform_with_50_percent_wrong_matches);
    RUN_TEST(test_ransac_estimate_should_recover_a_transform_with_70_percent_wrong_matches);
    RUN_TEST(test_ransac_estimate_should_recover_rotations_near_180_degrees);
    RUN_TEST(test_ransac_estimate_should_refine_by_least_squares_over_the_inliers);
    RUN_TEST(test_ransac_estimate_should_count_samples_stopped_by_the_length_test);
    RUN_TEST(test_ransac_estimate_should_not_reject_any_sample_on_exact_data);
    RUN_TEST(test_ransac_estimate_should_reject_wrong_samples_by_length_with_wrong_matches);
    RUN_TEST(test_ransac_estimate_should_enumerate_all_pairs_when_within_budget);
    RUN_TEST(test_ransac_estimate_should_be_bit_identical_across_fresh_inits);
    RUN_TEST(test_ransac_init_should_treat_seed_zero_as_the_default_seed);
    RUN_TEST(test_ransac_estimate_should_fail_with_identity_when_support_is_too_low);
    RUN_TEST(test_ransac_estimate_should_fail_when_every_match_is_wrong);
    RUN_TEST(test_ransac_estimate_should_fail_on_fewer_than_two_matches);
    RUN_TEST(test_ransac_estimate_should_refuse_more_than_rsm_max_matches);
    RUN_TEST(test_ransac_estimate_should_reject_invalid_arguments);
    return UNITY_END();
}
