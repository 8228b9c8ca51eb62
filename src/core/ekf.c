/* 3-state EKF over (x, y, theta); see src/core/ekf.h for the contract.
 * All algebra is explicit 3x3, row-major, single precision. */
#include "core/ekf.h"

#include <math.h>
#include <stddef.h>

#include "rsm/status.h"

/* |det| below this fraction of the product of the row norms (Hadamard's
 * bound, which |det| never exceeds) counts as singular. Scale-free: a
 * diagonal matrix of any scales scores 1, nearly dependent rows score ~0. */
#define RSM_EKF_SINGULAR_RATIO 1e-6f

/* x - x is +0 for a finite x and NaN for an infinite or NaN one, and a
 * NaN stays in a sum: one test for the whole array (a test per value cost
 * a Cortex-M4F twice the instructions, on every encoder step). */
static int all_finite(const float *v, size_t n)
{
    float z = 0.0f;
    size_t i;
    for (i = 0; i < n; ++i) {
        z += v[i] - v[i];
    }
    return z == 0.0f;
}

static int pose_finite(const rsm_pose_t *p)
{
    return isfinite(p->x) && isfinite(p->y) && isfinite(p->theta);
}

/* out = a * b. A row's three entries written out (the same terms in the
 * same order as a loop over them): every encoder step runs four of these
 * products, and the loop's indexing cost a Cortex-M4F as much as the
 * arithmetic. */
static void mat3_mul(const float a[9], const float b[9], float out[9])
{
    int r;
    for (r = 0; r < 3; ++r) {
        const float *x = &a[r * 3];
        out[r * 3] = x[0] * b[0] + x[1] * b[3] + x[2] * b[6];
        out[r * 3 + 1] = x[0] * b[1] + x[1] * b[4] + x[2] * b[7];
        out[r * 3 + 2] = x[0] * b[2] + x[1] * b[5] + x[2] * b[8];
    }
}

/* out = a * b^T, written out as mat3_mul */
static void mat3_mul_bt(const float a[9], const float b[9], float out[9])
{
    int r;
    for (r = 0; r < 3; ++r) {
        const float *x = &a[r * 3];
        out[r * 3] = x[0] * b[0] + x[1] * b[1] + x[2] * b[2];
        out[r * 3 + 1] = x[0] * b[3] + x[1] * b[4] + x[2] * b[5];
        out[r * 3 + 2] = x[0] * b[6] + x[1] * b[7] + x[2] * b[8];
    }
}

/* out = a * m * a^T */
static void mat3_sandwich(const float a[9], const float m[9], float out[9])
{
    float t[9];
    mat3_mul(a, m, t);
    mat3_mul_bt(t, a, out);
}

static void mat3_symmetrise(float m[9])
{
    const float m01 = 0.5f * (m[1] + m[3]);
    const float m02 = 0.5f * (m[2] + m[6]);
    const float m12 = 0.5f * (m[5] + m[7]);
    m[1] = m01;
    m[3] = m01;
    m[2] = m02;
    m[6] = m02;
    m[5] = m12;
    m[7] = m12;
}

int rsm_mat3_inverse(const float m[9], float out[9])
{
    float c[9];
    float det;
    float bound;
    float inv;
    int i;
    if (m == NULL || out == NULL) {
        return RSM_ERR_INVAL;
    }
    if (!all_finite(m, 9)) {
        return RSM_ERR_DEGENERATE;
    }
    /* Cofactors, already transposed into the adjugate. */
    c[0] = m[4] * m[8] - m[5] * m[7];
    c[1] = m[2] * m[7] - m[1] * m[8];
    c[2] = m[1] * m[5] - m[2] * m[4];
    c[3] = m[5] * m[6] - m[3] * m[8];
    c[4] = m[0] * m[8] - m[2] * m[6];
    c[5] = m[2] * m[3] - m[0] * m[5];
    c[6] = m[3] * m[7] - m[4] * m[6];
    c[7] = m[1] * m[6] - m[0] * m[7];
    c[8] = m[0] * m[4] - m[1] * m[3];
    det = m[0] * c[0] + m[1] * c[3] + m[2] * c[6];
    bound = sqrtf(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]) * sqrtf(m[3] * m[3] + m[4] * m[4] + m[5] * m[5]) *
            sqrtf(m[6] * m[6] + m[7] * m[7] + m[8] * m[8]);
    /* The <= also catches the all-zero matrix and underflowed bounds. */
    if (!isfinite(det) || !isfinite(bound) || fabsf(det) <= RSM_EKF_SINGULAR_RATIO * bound || bound <= 0.0f) {
        return RSM_ERR_DEGENERATE;
    }
    inv = 1.0f / det;
    for (i = 0; i < 9; ++i) {
        c[i] *= inv;
    }
    if (!all_finite(c, 9)) {
        return RSM_ERR_DEGENERATE;
    }
    for (i = 0; i < 9; ++i) {
        out[i] = c[i];
    }
    return RSM_OK;
}

int rsm_ekf_init(rsm_ekf_t *ekf, const rsm_pose_t *x0, const float p0[9])
{
    float p[9];
    int i;
    int j;
    if (ekf == NULL || x0 == NULL || !pose_finite(x0)) {
        return RSM_ERR_INVAL;
    }
    for (i = 0; i < 9; ++i) {
        p[i] = p0 != NULL ? p0[i] : 0.0f;
    }
    if (!all_finite(p, 9)) {
        return RSM_ERR_INVAL;
    }
    for (i = 0; i < 3; ++i) {
        if (p[i * 4] < 0.0f) {
            return RSM_ERR_INVAL;
        }
        for (j = i + 1; j < 3; ++j) {
            const float a = p[i * 3 + j];
            const float b = p[j * 3 + i];
            /* Relative tolerance: values computed elsewhere in float may
             * differ in the last bits; anything more is not a covariance. */
            if (fabsf(a - b) > 1e-5f * (fabsf(a) + fabsf(b))) {
                return RSM_ERR_INVAL;
            }
        }
    }
    mat3_symmetrise(p);
    ekf->x = *x0;
    ekf->x.theta = rsm_wrap_angle(x0->theta);
    for (i = 0; i < 9; ++i) {
        ekf->p[i] = p[i];
    }
    ekf->predicts = 0u;
    ekf->updates = 0u;
    ekf->rejected = 0u;
    return RSM_OK;
}

/* Keeps a lost covariance usable (see RSM_EKF_LOST_VAR_XY_M2 in ekf.h):
 * returns 1 if it was reset to its capped diagonal. */
static int bound_lost(float p[9])
{
    if (p[0] <= RSM_EKF_LOST_VAR_XY_M2 && p[4] <= RSM_EKF_LOST_VAR_XY_M2 && p[8] <= RSM_EKF_LOST_VAR_THETA) {
        return 0;
    }
    p[0] = p[0] < RSM_EKF_LOST_VAR_XY_M2 ? p[0] : RSM_EKF_LOST_VAR_XY_M2;
    p[4] = p[4] < RSM_EKF_LOST_VAR_XY_M2 ? p[4] : RSM_EKF_LOST_VAR_XY_M2;
    p[8] = p[8] < RSM_EKF_LOST_VAR_THETA ? p[8] : RSM_EKF_LOST_VAR_THETA;
    p[1] = p[2] = p[3] = p[5] = p[6] = p[7] = 0.0f;
    return 1;
}

int rsm_ekf_predict(rsm_ekf_t *ekf, const rsm_motion_t *u, const float q[9])
{
    float jv[9];
    float ju[9];
    float a[9];
    float b[9];
    rsm_pose_t x;
    int i;
    if (ekf == NULL || u == NULL) {
        return RSM_ERR_INVAL;
    }
    if (!isfinite(u->dx) || !isfinite(u->dy) || !isfinite(u->dtheta) || (q != NULL && !all_finite(q, 9))) {
        return RSM_ERR_INVAL;
    }
    /* Jacobians at the prior state, before it moves. The move is
     * rsm_odometry_apply's, with the heading's cosine and sine taken from
     * Ju (its first column) instead of computed again on every step. */
    rsm_odometry_jacobians(&ekf->x, u, jv, ju);
    x.x = ekf->x.x + ju[0] * u->dx - ju[3] * u->dy;
    x.y = ekf->x.y + ju[3] * u->dx + ju[0] * u->dy;
    x.theta = rsm_wrap_angle(ekf->x.theta + u->dtheta);
    mat3_sandwich(jv, ekf->p, a);
    if (q != NULL) {
        mat3_sandwich(ju, q, b);
        for (i = 0; i < 9; ++i) {
            a[i] += b[i];
        }
    }
    mat3_symmetrise(a);
    if (!pose_finite(&x) || !all_finite(a, 9)) {
        return RSM_ERR_DEGENERATE;
    }
    if (bound_lost(a)) {
        ekf->lost++;
    }
    ekf->x = x;
    for (i = 0; i < 9; ++i) {
        ekf->p[i] = a[i];
    }
    ekf->predicts++;
    return RSM_OK;
}

/* Innovation v = z - x (angle wrapped), S = P + R and S^-1. */
static int innovation(const rsm_ekf_t *ekf, const rsm_pose_t *z, const float r[9], float v[3], float s_inv[9])
{
    float s[9];
    int i;
    if (!pose_finite(z) || !all_finite(r, 9)) {
        return RSM_ERR_DEGENERATE;
    }
    v[0] = z->x - ekf->x.x;
    v[1] = z->y - ekf->x.y;
    /* The short way round: 179 deg to -179 deg is +2 deg, not -358. */
    v[2] = rsm_wrap_angle(z->theta - ekf->x.theta);
    for (i = 0; i < 9; ++i) {
        s[i] = ekf->p[i] + r[i];
    }
    return rsm_mat3_inverse(s, s_inv);
}

static float quad_form(const float v[3], const float m[9])
{
    return v[0] * (m[0] * v[0] + m[1] * v[1] + m[2] * v[2]) + v[1] * (m[3] * v[0] + m[4] * v[1] + m[5] * v[2]) +
           v[2] * (m[6] * v[0] + m[7] * v[1] + m[8] * v[2]);
}

int rsm_ekf_mahalanobis(const rsm_ekf_t *ekf, const rsm_pose_t *z, const float r[9], float *d2)
{
    float v[3];
    float s_inv[9];
    float d;
    int st;
    if (ekf == NULL || z == NULL || r == NULL || d2 == NULL) {
        return RSM_ERR_INVAL;
    }
    st = innovation(ekf, z, r, v, s_inv);
    if (st != RSM_OK) {
        return st;
    }
    d = quad_form(v, s_inv);
    if (!isfinite(d)) {
        return RSM_ERR_DEGENERATE;
    }
    *d2 = d;
    return RSM_OK;
}

int rsm_ekf_update(rsm_ekf_t *ekf, const rsm_pose_t *z, const float r[9], float gate_d2)
{
    float v[3];
    float s_inv[9];
    float k[9];
    float ikm[9];
    float a[9];
    float b[9];
    float p[9];
    rsm_pose_t x;
    int st;
    int i;
    if (ekf == NULL || z == NULL || r == NULL) {
        return RSM_ERR_INVAL;
    }
    st = innovation(ekf, z, r, v, s_inv);
    if (st != RSM_OK) {
        ekf->rejected++;
        return st;
    }
    if (gate_d2 > 0.0f) {
        const float d2 = quad_form(v, s_inv);
        /* A NaN distance fails the "<=" and is refused with the far ones. */
        if (!(d2 <= gate_d2)) {
            ekf->rejected++;
            return RSM_ERR_RANGE;
        }
    }
    /* H = I: K = P S^-1 (eq. 20 with the S^-1 the paper dropped). */
    mat3_mul(ekf->p, s_inv, k);
    x.x = ekf->x.x + k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
    x.y = ekf->x.y + k[3] * v[0] + k[4] * v[1] + k[5] * v[2];
    x.theta = rsm_wrap_angle(ekf->x.theta + k[6] * v[0] + k[7] * v[1] + k[8] * v[2]);
    /* Joseph form: P = (I-K) P (I-K)^T + K R K^T stays symmetric positive
     * semi-definite under rounding, unlike P - K S K^T (eq. 22). */
    for (i = 0; i < 9; ++i) {
        ikm[i] = -k[i];
    }
    ikm[0] += 1.0f;
    ikm[4] += 1.0f;
    ikm[8] += 1.0f;
    mat3_sandwich(ikm, ekf->p, a);
    mat3_sandwich(k, r, b);
    for (i = 0; i < 9; ++i) {
        p[i] = a[i] + b[i];
    }
    mat3_symmetrise(p);
    if (!pose_finite(&x) || !all_finite(p, 9)) {
        ekf->rejected++;
        return RSM_ERR_DEGENERATE;
    }
    ekf->x = x;
    for (i = 0; i < 9; ++i) {
        ekf->p[i] = p[i];
    }
    ekf->updates++;
    return RSM_OK;
}

int rsm_ekf_pull_heading(rsm_ekf_t *ekf, float dtheta, float r)
{
    float k[3];
    rsm_pose_t x;
    float s;
    int i;
    if (ekf == NULL) {
        return RSM_ERR_INVAL;
    }
    s = ekf->p[8] + r;
    if (!isfinite(dtheta) || !(r > 0.0f) || !isfinite(s)) {
        ekf->rejected++;
        return RSM_ERR_DEGENERATE;
    }
    /* H = (0 0 1): K is P's last column over S. */
    for (i = 0; i < 3; ++i) {
        k[i] = ekf->p[3 * i + 2] / s;
    }
    x.x = ekf->x.x + k[0] * dtheta;
    x.y = ekf->x.y + k[1] * dtheta;
    x.theta = rsm_wrap_angle(ekf->x.theta + k[2] * dtheta);
    if (!pose_finite(&x)) {
        ekf->rejected++;
        return RSM_ERR_DEGENERATE;
    }
    ekf->x = x;
    return RSM_OK;
}
