/* Unit tests for src/core/ekf.c: prediction, update, angle wrapping, gating,
 * singular innovations and long-run covariance health. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "core/ekf.h"
#include "rsm/status.h"
#include "test_support.h"
#include "unity.h"

#define DEG (RSM_PI / 180.0f)

static rsm_ekf_t ekf;

void setUp(void)
{
    memset(&ekf, 0, sizeof ekf);
}

void tearDown(void)
{
}

static void diag3(float m[9], float a, float b, float c)
{
    int i;
    for (i = 0; i < 9; ++i) {
        m[i] = 0.0f;
    }
    m[0] = a;
    m[4] = b;
    m[8] = c;
}

/* Reference product in double, independent of the library's helpers. */
static void ref_mul(const double a[9], const double b[9], double out[9])
{
    int r;
    int c;
    int k;
    for (r = 0; r < 3; ++r) {
        for (c = 0; c < 3; ++c) {
            double acc = 0.0;
            for (k = 0; k < 3; ++k) {
                acc += a[r * 3 + k] * b[k * 3 + c];
            }
            out[r * 3 + c] = acc;
        }
    }
}

static void ref_transpose(const double a[9], double out[9])
{
    int r;
    int c;
    for (r = 0; r < 3; ++r) {
        for (c = 0; c < 3; ++c) {
            out[c * 3 + r] = a[r * 3 + c];
        }
    }
}

/* Sylvester's criterion: all leading principal minors positive. */
static int positive_definite(const float p[9])
{
    const double a = p[0];
    const double m2 = (double)p[0] * p[4] - (double)p[1] * p[3];
    const double m3 = (double)p[0] * ((double)p[4] * p[8] - (double)p[5] * p[7]) -
                      (double)p[1] * ((double)p[3] * p[8] - (double)p[5] * p[6]) +
                      (double)p[2] * ((double)p[3] * p[7] - (double)p[4] * p[6]);
    return a > 0.0 && m2 > 0.0 && m3 > 0.0;
}

void test_init_should_set_state_and_validate_covariance(void)
{
    const rsm_pose_t x0 = { 1.0f, 2.0f, 3.0f * RSM_PI };
    float p0[9];
    float zero[9];
    rsm_ekf_t before;
    diag3(p0, 0.1f, 0.2f, 0.3f);
    p0[1] = 0.01f;
    p0[3] = 0.01f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    TEST_ASSERT_EQUAL_FLOAT(1.0f, ekf.x.x);
    TEST_ASSERT_EQUAL_FLOAT(2.0f, ekf.x.y);
    /* The heading is wrapped into (-pi, pi]. */
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, RSM_PI, fabsf(ekf.x.theta));
    TEST_ASSERT_EQUAL_MEMORY(p0, ekf.p, sizeof p0);
    TEST_ASSERT_EQUAL_UINT32(0u, ekf.predicts);
    TEST_ASSERT_EQUAL_UINT32(0u, ekf.updates);
    TEST_ASSERT_EQUAL_UINT32(0u, ekf.rejected);

    /* NULL p0 means a zero covariance. */
    diag3(zero, 0.0f, 0.0f, 0.0f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, NULL));
    TEST_ASSERT_EQUAL_MEMORY(zero, ekf.p, sizeof zero);

    before = ekf;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_init(NULL, &x0, p0));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_init(&ekf, NULL, p0));
    /* Not symmetric. */
    p0[3] = 0.02f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_init(&ekf, &x0, p0));
    /* Negative variance. */
    p0[3] = 0.01f;
    p0[4] = -0.2f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_init(&ekf, &x0, p0));
    /* Not finite. */
    p0[4] = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_init(&ekf, &x0, p0));
    {
        rsm_pose_t bad = x0;
        bad.y = INFINITY;
        TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_init(&ekf, &bad, NULL));
    }
    TEST_ASSERT_EQUAL_MEMORY(&before, &ekf, sizeof ekf);
}

void test_predict_should_add_propagated_and_process_noise(void)
{
    /* At theta = 0 with u = (1, 0, 0): Jv = [1 0 0; 0 1 1; 0 0 1], Ju = I.
     * With P = diag(a, b, c), Jv P Jv^T = [a 0 0; 0 b+c c; 0 c c]. */
    const rsm_pose_t x0 = { 0.0f, 0.0f, 0.0f };
    const rsm_motion_t u = { 1.0f, 0.0f, 0.0f };
    float p0[9];
    float q[9];
    diag3(p0, 0.01f, 0.02f, 0.03f);
    diag3(q, 0.001f, 0.002f, 0.003f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_predict(&ekf, &u, q));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0f, ekf.x.x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, ekf.x.y);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, ekf.x.theta);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.011f, ekf.p[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, ekf.p[1]);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, ekf.p[2]);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, ekf.p[3]);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.052f, ekf.p[4]);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.03f, ekf.p[5]);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.0f, ekf.p[6]);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.03f, ekf.p[7]);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.033f, ekf.p[8]);
    TEST_ASSERT_EQUAL_UINT32(1u, ekf.predicts);
}

void test_predict_should_match_reference_propagation_at_any_heading(void)
{
    const rsm_pose_t x0 = { 0.5f, -1.0f, 2.0f };
    const rsm_motion_t u = { 0.3f, 0.1f, 0.2f };
    float p0[9] = { 0.04f, 0.01f, 0.002f, 0.01f, 0.09f, -0.003f, 0.002f, -0.003f, 0.01f };
    float q[9];
    double jv[9];
    double ju[9];
    double p[9];
    double qd[9];
    double t1[9];
    double t2[9];
    double jt[9];
    double expect[9];
    const double c = cos(2.0);
    const double s = sin(2.0);
    int i;
    diag3(q, 0.0004f, 0.0001f, 0.0009f);
    for (i = 0; i < 9; ++i) {
        p[i] = p0[i];
        qd[i] = q[i];
    }
    jv[0] = 1.0; jv[1] = 0.0; jv[2] = -s * 0.3 - c * 0.1;
    jv[3] = 0.0; jv[4] = 1.0; jv[5] = c * 0.3 - s * 0.1;
    jv[6] = 0.0; jv[7] = 0.0; jv[8] = 1.0;
    ju[0] = c; ju[1] = -s; ju[2] = 0.0;
    ju[3] = s; ju[4] = c; ju[5] = 0.0;
    ju[6] = 0.0; ju[7] = 0.0; ju[8] = 1.0;
    ref_mul(jv, p, t1);
    ref_transpose(jv, jt);
    ref_mul(t1, jt, expect);
    ref_mul(ju, qd, t1);
    ref_transpose(ju, jt);
    ref_mul(t1, jt, t2);
    for (i = 0; i < 9; ++i) {
        expect[i] += t2[i];
    }
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_predict(&ekf, &u, q));
    for (i = 0; i < 9; ++i) {
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, (float)expect[i], ekf.p[i]);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, (float)(0.5 + c * 0.3 - s * 0.1), ekf.x.x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, (float)(-1.0 + s * 0.3 + c * 0.1), ekf.x.y);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.2f, ekf.x.theta);
}

void test_predict_should_reject_bad_input_and_keep_state(void)
{
    const rsm_pose_t x0 = { 1.0f, 1.0f, 0.5f };
    rsm_motion_t u = { 0.1f, 0.0f, 0.0f };
    float q[9];
    rsm_ekf_t before;
    diag3(q, 1e-4f, 1e-4f, 1e-4f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, q));
    before = ekf;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_predict(NULL, &u, q));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_predict(&ekf, NULL, q));
    u.dtheta = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_predict(&ekf, &u, q));
    u.dtheta = 0.0f;
    q[4] = INFINITY;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_predict(&ekf, &u, q));
    /* Finite but overflowing: the result would not be finite. */
    u.dx = 3e38f;
    u.dy = 3e38f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_predict(&ekf, &u, NULL));
    TEST_ASSERT_EQUAL_MEMORY(&before, &ekf, sizeof ekf);

    /* NULL q: propagation only. */
    u.dx = 0.1f;
    u.dy = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_predict(&ekf, &u, NULL));
    TEST_ASSERT_FLOAT_WITHIN(1e-9f, 1e-4f, ekf.p[8]);
}

void test_update_should_keep_state_and_shrink_covariance_when_measurement_agrees(void)
{
    const rsm_pose_t x0 = { 3.0f, -2.0f, 1.0f };
    float p0[9] = { 0.04f, 0.01f, 0.0f, 0.01f, 0.05f, 0.002f, 0.0f, 0.002f, 0.01f };
    float r[9];
    float pb[9];
    int i;
    diag3(r, 0.01f, 0.01f, 0.001f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    memcpy(pb, ekf.p, sizeof pb);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_update(&ekf, &x0, r, 0.0f));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 3.0f, ekf.x.x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, -2.0f, ekf.x.y);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.0f, ekf.x.theta);
    for (i = 0; i < 3; ++i) {
        TEST_ASSERT_TRUE(ekf.p[i * 4] < pb[i * 4]);
        TEST_ASSERT_TRUE(ekf.p[i * 4] > 0.0f);
    }
    /* P - P_new = P S^-1 P is positive semi-definite: the information only
     * grew. Check it on a few directions. */
    {
        const float dirs[4][3] = { { 1.0f, 0.0f, 0.0f }, { 1.0f, -1.0f, 0.0f }, { 0.3f, 0.5f, -1.0f },
                                   { 0.0f, 1.0f, 1.0f } };
        int d;
        for (d = 0; d < 4; ++d) {
            float before_q = 0.0f;
            float after_q = 0.0f;
            int a;
            int b;
            for (a = 0; a < 3; ++a) {
                for (b = 0; b < 3; ++b) {
                    before_q += dirs[d][a] * pb[a * 3 + b] * dirs[d][b];
                    after_q += dirs[d][a] * ekf.p[a * 3 + b] * dirs[d][b];
                }
            }
            TEST_ASSERT_TRUE(after_q < before_q);
        }
    }
    TEST_ASSERT_EQUAL_UINT32(1u, ekf.updates);
    TEST_ASSERT_EQUAL_UINT32(0u, ekf.rejected);
}

void test_update_should_give_the_scalar_result_per_axis_for_diagonal_p_and_r(void)
{
    const rsm_pose_t x0 = { 1.0f, 2.0f, 0.1f };
    const rsm_pose_t z = { 1.5f, 1.0f, 0.3f };
    const float pv[3] = { 0.04f, 0.09f, 0.01f };
    const float rv[3] = { 0.01f, 0.09f, 0.03f };
    const float xv[3] = { 1.0f, 2.0f, 0.1f };
    const float zv[3] = { 1.5f, 1.0f, 0.3f };
    float p0[9];
    float r[9];
    float got[3];
    int i;
    diag3(p0, pv[0], pv[1], pv[2]);
    diag3(r, rv[0], rv[1], rv[2]);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_update(&ekf, &z, r, 0.0f));
    got[0] = ekf.x.x;
    got[1] = ekf.x.y;
    got[2] = ekf.x.theta;
    for (i = 0; i < 3; ++i) {
        const float k = pv[i] / (pv[i] + rv[i]);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, xv[i] + k * (zv[i] - xv[i]), got[i]);
        TEST_ASSERT_FLOAT_WITHIN(1e-7f, pv[i] * rv[i] / (pv[i] + rv[i]), ekf.p[i * 4]);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-9f, 0.0f, ekf.p[1]);
    TEST_ASSERT_FLOAT_WITHIN(1e-9f, 0.0f, ekf.p[2]);
    TEST_ASSERT_FLOAT_WITHIN(1e-9f, 0.0f, ekf.p[5]);
}

void test_update_should_cross_pi_the_short_way(void)
{
    /* State at 179 deg, measurement at -179 deg: the innovation is +2 deg.
     * With P_theta = 3 R_theta the gain is 0.75, so the estimate moves
     * +1.5 deg to 180.5 deg = -179.5 deg. The long way would give -89.5. */
    const rsm_pose_t x0 = { 0.0f, 0.0f, 179.0f * DEG };
    const rsm_pose_t z = { 0.0f, 0.0f, -179.0f * DEG };
    float p0[9];
    float r[9];
    diag3(p0, 1.0f, 1.0f, 0.03f);
    diag3(r, 1.0f, 1.0f, 0.01f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_update(&ekf, &z, r, 0.0f));
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, -179.5f * DEG, ekf.x.theta);
    TEST_ASSERT_TRUE(ekf.x.theta > -RSM_PI && ekf.x.theta <= RSM_PI);

    /* And back the other way: from -179 deg towards 179 deg. */
    {
        const rsm_pose_t x1 = { 0.0f, 0.0f, -179.0f * DEG };
        const rsm_pose_t z1 = { 0.0f, 0.0f, 179.0f * DEG };
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x1, p0));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_update(&ekf, &z1, r, 0.0f));
        TEST_ASSERT_FLOAT_WITHIN(1e-4f, 179.5f * DEG, ekf.x.theta);
    }
}

void test_update_should_refuse_singular_innovation_covariance(void)
{
    const rsm_pose_t x0 = { 1.0f, 1.0f, 0.2f };
    const rsm_pose_t z = { 1.1f, 0.9f, 0.25f };
    float r[9];
    float p0[9] = { 1.0f, 1.0f, 0.0f, 1.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f };
    rsm_ekf_t before;
    float d2 = -1.0f;
    diag3(r, 0.0f, 0.0f, 0.0f);

    /* All zero. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, NULL));
    before = ekf;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_update(&ekf, &z, r, 0.0f));
    TEST_ASSERT_EQUAL_MEMORY(&before.x, &ekf.x, sizeof ekf.x);
    TEST_ASSERT_EQUAL_MEMORY(before.p, ekf.p, sizeof ekf.p);
    TEST_ASSERT_EQUAL_UINT32(1u, ekf.rejected);
    TEST_ASSERT_EQUAL_UINT32(0u, ekf.updates);

    /* Rank 2: x and y perfectly correlated and no measurement noise. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    before = ekf;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_update(&ekf, &z, r, 0.0f));
    TEST_ASSERT_EQUAL_MEMORY(&before.x, &ekf.x, sizeof ekf.x);
    TEST_ASSERT_EQUAL_MEMORY(before.p, ekf.p, sizeof ekf.p);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_mahalanobis(&ekf, &z, r, &d2));
    TEST_ASSERT_EQUAL_FLOAT(-1.0f, d2);
}

void test_update_gate_should_reject_far_measurements(void)
{
    const rsm_pose_t x0 = { 0.0f, 0.0f, 0.0f };
    rsm_pose_t z = { 0.3f, 0.4f, 0.0f };
    float p0[9];
    float r[9];
    float d2 = 0.0f;
    rsm_ekf_t before;
    /* S = diag(0.02, 0.02, 0.02): d2 = (0.09 + 0.16) / 0.02 = 12.5. */
    diag3(p0, 0.01f, 0.01f, 0.01f);
    diag3(r, 0.01f, 0.01f, 0.01f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_mahalanobis(&ekf, &z, r, &d2));
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 12.5f, d2);

    before = ekf;
    /* 11.34 is the 99% point of chi-square with 3 degrees of freedom. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_ekf_update(&ekf, &z, r, 11.34f));
    TEST_ASSERT_EQUAL_MEMORY(&before.x, &ekf.x, sizeof ekf.x);
    TEST_ASSERT_EQUAL_MEMORY(before.p, ekf.p, sizeof ekf.p);
    TEST_ASSERT_EQUAL_UINT32(1u, ekf.rejected);
    TEST_ASSERT_EQUAL_UINT32(0u, ekf.updates);

    /* A wider gate lets it in, and gate 0 disables gating. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_update(&ekf, &z, r, 13.0f));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    z.x = 30.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_update(&ekf, &z, r, 0.0f));
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 15.0f, ekf.x.x);
    TEST_ASSERT_EQUAL_UINT32(0u, ekf.rejected);
}

void test_update_should_reject_non_finite_measurements(void)
{
    const rsm_pose_t x0 = { 1.0f, 2.0f, 0.3f };
    rsm_pose_t z = { NAN, 2.0f, 0.3f };
    float p0[9];
    float r[9];
    float d2 = 5.0f;
    rsm_ekf_t before;
    diag3(p0, 0.01f, 0.01f, 0.01f);
    diag3(r, 0.01f, 0.01f, 0.01f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    before = ekf;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_update(&ekf, &z, r, 0.0f));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_update(&ekf, &z, r, 11.34f));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_mahalanobis(&ekf, &z, r, &d2));
    TEST_ASSERT_EQUAL_FLOAT(5.0f, d2);
    z.x = 1.0f;
    z.theta = INFINITY;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_update(&ekf, &z, r, 0.0f));
    z.theta = 0.3f;
    r[4] = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_ekf_update(&ekf, &z, r, 0.0f));
    TEST_ASSERT_EQUAL_MEMORY(&before.x, &ekf.x, sizeof ekf.x);
    TEST_ASSERT_EQUAL_MEMORY(before.p, ekf.p, sizeof ekf.p);
    TEST_ASSERT_EQUAL_UINT32(4u, ekf.rejected);
    TEST_ASSERT_EQUAL_UINT32(0u, ekf.updates);

    /* NULL arguments are argument errors, not rejections. */
    r[4] = 0.01f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_update(NULL, &z, r, 0.0f));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_update(&ekf, NULL, r, 0.0f));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_update(&ekf, &z, NULL, 0.0f));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ekf_mahalanobis(&ekf, &z, r, NULL));
    TEST_ASSERT_EQUAL_UINT32(4u, ekf.rejected);
}

void test_covariance_should_stay_symmetric_positive_definite_over_random_cycles(void)
{
    uint32_t seed = 0xC0FFEEu;
    const rsm_pose_t x0 = { 0.0f, 0.0f, 0.0f };
    float p0[9];
    int k;
    diag3(p0, 0.01f, 0.01f, 0.001f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &x0, p0));
    for (k = 0; k < 10000; ++k) {
        rsm_motion_t u;
        rsm_pose_t z;
        float q[9];
        float r[9];
        const float qs = rsm_test_rng_uniform(&seed, -8.0f, -2.0f);
        const float rs = rsm_test_rng_uniform(&seed, -8.0f, 0.0f);
        u.dx = rsm_test_rng_uniform(&seed, -0.3f, 0.5f);
        u.dy = rsm_test_rng_uniform(&seed, -0.05f, 0.05f);
        u.dtheta = rsm_test_rng_uniform(&seed, -0.6f, 0.6f);
        diag3(q, powf(10.0f, qs), powf(10.0f, qs), powf(10.0f, qs - 1.0f));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_predict(&ekf, &u, q));
        if (k % 3 != 2) {
            /* A measurement near the state, with correlated noise of a random
             * scale (as a residual-based R would be). */
            const float rxy = powf(10.0f, rs);
            const float rho = rsm_test_rng_uniform(&seed, -0.9f, 0.9f);
            diag3(r, rxy, rxy * rsm_test_rng_uniform(&seed, 0.1f, 10.0f), powf(10.0f, rs - 2.0f));
            r[1] = rho * sqrtf(r[0] * r[4]);
            r[3] = r[1];
            z.x = ekf.x.x + rsm_test_rng_uniform(&seed, -0.05f, 0.05f);
            z.y = ekf.x.y + rsm_test_rng_uniform(&seed, -0.05f, 0.05f);
            z.theta = rsm_wrap_angle(ekf.x.theta + rsm_test_rng_uniform(&seed, -0.02f, 0.02f));
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_update(&ekf, &z, r, 0.0f));
        }
        TEST_ASSERT_EQUAL_FLOAT(ekf.p[1], ekf.p[3]);
        TEST_ASSERT_EQUAL_FLOAT(ekf.p[2], ekf.p[6]);
        TEST_ASSERT_EQUAL_FLOAT(ekf.p[5], ekf.p[7]);
        TEST_ASSERT_TRUE_MESSAGE(positive_definite(ekf.p), "P lost positive definiteness");
        TEST_ASSERT_TRUE(ekf.x.theta > -RSM_PI && ekf.x.theta <= RSM_PI);
    }
    TEST_ASSERT_EQUAL_UINT32(10000u, ekf.predicts);
    TEST_ASSERT_EQUAL_UINT32(0u, ekf.rejected);
}

void test_predict_should_keep_a_lost_covariance_usable_and_the_filter_recovers(void)
{
    const rsm_odometry_config_t oc = rsm_odometry_config_default();
    const rsm_motion_t corrupt = {8000.0f, 3.0f, 0.5f};
    const rsm_motion_t step = {0.05f, 0.0f, 0.01f};
    const float r[9] = {1e-4f, 0.0f, 0.0f, 0.0f, 1e-4f, 0.0f, 0.0f, 0.0f, 1e-5f};
    const rsm_pose_t origin = {0.0f, 0.0f, 0.0f};
    float q[9];
    rsm_pose_t z;
    int k;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_init(&ekf, &origin, NULL));
    /* An 8 km increment (with its noise: 1600 rad of heading std), then
     * more driving: in float the linearised P became singular and every
     * update was refused for ever. */
    rsm_odometry_noise(&oc, &corrupt, q);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_predict(&ekf, &corrupt, q));
    for (k = 0; k < 300; ++k) {
        rsm_odometry_noise(&oc, &step, q);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_predict(&ekf, &step, q));
    }
    TEST_ASSERT_GREATER_THAN_UINT32(0u, ekf.lost);
    TEST_ASSERT_TRUE(ekf.p[0] <= RSM_EKF_LOST_VAR_XY_M2 && ekf.p[4] <= RSM_EKF_LOST_VAR_XY_M2);
    TEST_ASSERT_TRUE(ekf.p[8] <= RSM_EKF_LOST_VAR_THETA);
    /* A measurement near the prediction is taken and P is small again. */
    z = ekf.x;
    z.x += 0.05f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ekf_update(&ekf, &z, r, 16.27f));
    TEST_ASSERT_LESS_THAN_FLOAT(1e-3f, ekf.p[0]);
    TEST_ASSERT_LESS_THAN_FLOAT(1e-3f, ekf.p[8]);
    TEST_ASSERT_FLOAT_WITHIN(1e-2f, z.x, ekf.x.x);
}

void test_mat3_inverse_should_invert_and_detect_singularity(void)
{
    uint32_t seed = 99u;
    float m[9];
    float inv[9];
    float keep[9];
    int k;
    for (k = 0; k < 500; ++k) {
        int i;
        int r;
        int c;
        for (i = 0; i < 9; ++i) {
            m[i] = rsm_test_rng_uniform(&seed, -1.0f, 1.0f);
        }
        /* Diagonally dominant, hence well conditioned. */
        m[0] += 3.0f;
        m[4] += 3.0f;
        m[8] -= 3.0f;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mat3_inverse(m, inv));
        for (r = 0; r < 3; ++r) {
            for (c = 0; c < 3; ++c) {
                const float e = m[r * 3] * inv[c] + m[r * 3 + 1] * inv[3 + c] + m[r * 3 + 2] * inv[6 + c];
                TEST_ASSERT_FLOAT_WITHIN(1e-5f, r == c ? 1.0f : 0.0f, e);
            }
        }
    }

    /* The singularity test is relative: tiny but well-conditioned is fine. */
    diag3(m, 1e-12f, 2e-12f, 4e-12f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mat3_inverse(m, inv));
    TEST_ASSERT_FLOAT_WITHIN(1e5f, 1e12f, inv[0]);
    diag3(m, 1e-6f, 1.0f, 1e6f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mat3_inverse(m, inv));
    TEST_ASSERT_FLOAT_WITHIN(1.0f, 1e6f, inv[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-12f, 1e-6f, inv[8]);

    /* Singular and nearly singular matrices are refused, out untouched. */
    for (k = 0; k < 9; ++k) {
        keep[k] = 7.0f;
        inv[k] = 7.0f;
    }
    {
        float sing[9] = { 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f, 8.0f, 9.0f };
        TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_mat3_inverse(sing, inv));
        sing[0] = 1.0f + 1e-7f;
        TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_mat3_inverse(sing, inv));
        sing[0] = NAN;
        TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_mat3_inverse(sing, inv));
    }
    {
        /* det = 1e-7 exactly representable and non-zero, but the third row
         * is within 1e-7 of the span of the first two. */
        const float near[9] = { 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1.0f, 1e-7f };
        TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_mat3_inverse(near, inv));
    }
    diag3(m, 0.0f, 0.0f, 0.0f);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_DEGENERATE, rsm_mat3_inverse(m, inv));
    TEST_ASSERT_EQUAL_MEMORY(keep, inv, sizeof inv);
    /* In place. */
    diag3(m, 2.0f, 4.0f, -8.0f);
    m[1] = 1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_mat3_inverse(m, m));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.5f, m[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, -0.125f, m[1]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.25f, m[4]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, -0.125f, m[8]);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mat3_inverse(NULL, inv));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_mat3_inverse(m, NULL));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_init_should_set_state_and_validate_covariance);
    RUN_TEST(test_predict_should_add_propagated_and_process_noise);
    RUN_TEST(test_predict_should_match_reference_propagation_at_any_heading);
    RUN_TEST(test_predict_should_reject_bad_input_and_keep_state);
    RUN_TEST(test_update_should_keep_state_and_shrink_covariance_when_measurement_agrees);
    RUN_TEST(test_update_should_give_the_scalar_result_per_axis_for_diagonal_p_and_r);
    RUN_TEST(test_update_should_cross_pi_the_short_way);
    RUN_TEST(test_update_should_refuse_singular_innovation_covariance);
    RUN_TEST(test_update_gate_should_reject_far_measurements);
    RUN_TEST(test_update_should_reject_non_finite_measurements);
    RUN_TEST(test_covariance_should_stay_symmetric_positive_definite_over_random_cycles);
    RUN_TEST(test_predict_should_keep_a_lost_covariance_usable_and_the_filter_recovers);
    RUN_TEST(test_mat3_inverse_should_invert_and_detect_singularity);
    return UNITY_END();
}
