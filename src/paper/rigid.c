/* The closed-form 2-D rigid fit shared by the RANSAC refinement and the ICP
 * baseline; see src/paper/rigid.h for the contract. */
#include "paper/rigid.h"

#include <math.h>

#include "rsm/status.h"
#include "core/fmath.h"

/* A point set whose RMS spread about its centroid is below this fraction of
 * its largest coordinate is one point as far as float can tell (the spread
 * would be rounding noise), so it fixes no rotation. */
#define RSM_FIT_MIN_SPREAD 1e-5f
/* When the rotation-fixing sums vanish against Cauchy-Schwarz's bound the
 * cost is flat in the angle (e.g. a point set and its mirror image). */
#define RSM_FIT_MIN_CORR 1e-6f

int rsm_rigid_fit_core(const rsm_point_t *src, const rsm_pose_t *src_pose, const rsm_point_t *dst, const float *w,
                       size_t n, rsm_pose_t *t)
{
    size_t i;
    size_t used = 0;
    float wsum = 0.0f;
    float scx = 0.0f;
    float scy = 0.0f;
    float dcx = 0.0f;
    float dcy = 0.0f;
    float smag = 0.0f;
    float dmag = 0.0f;
    float dot = 0.0f;
    float cross = 0.0f;
    float ss = 0.0f;
    float sd = 0.0f;
    float th;
    float c;
    float s;
    float lim;

    for (i = 0; i < n; ++i) {
        const float wi = w != NULL ? w[i] : 1.0f;
        rsm_point_t p;
        if (!rsm_point_finite(&dst[i]) || !(wi > 0.0f)) {
            continue;
        }
        p = src_pose != NULL ? rsm_pose_apply(src_pose, &src[i]) : src[i];
        wsum += wi;
        scx += wi * p.x;
        scy += wi * p.y;
        dcx += wi * dst[i].x;
        dcy += wi * dst[i].y;
        smag = fmaxf(smag, fmaxf(fabsf(p.x), fabsf(p.y)));
        dmag = fmaxf(dmag, fmaxf(fabsf(dst[i].x), fabsf(dst[i].y)));
        ++used;
    }
    if (used < 2u || !(wsum > 0.0f)) {
        return RSM_ERR_DEGENERATE;
    }
    scx /= wsum;
    scy /= wsum;
    dcx /= wsum;
    dcy /= wsum;

    for (i = 0; i < n; ++i) {
        const float wi = w != NULL ? w[i] : 1.0f;
        rsm_point_t p;
        float ax;
        float ay;
        float bx;
        float by;
        if (!rsm_point_finite(&dst[i]) || !(wi > 0.0f)) {
            continue;
        }
        p = src_pose != NULL ? rsm_pose_apply(src_pose, &src[i]) : src[i];
        ax = p.x - scx;
        ay = p.y - scy;
        bx = dst[i].x - dcx;
        by = dst[i].y - dcy;
        dot += wi * (ax * bx + ay * by);
        cross += wi * (ax * by - ay * bx);
        ss += wi * (ax * ax + ay * ay);
        sd += wi * (bx * bx + by * by);
    }

    lim = RSM_FIT_MIN_SPREAD * smag;
    if (ss <= wsum * lim * lim) {
        return RSM_ERR_DEGENERATE;
    }
    lim = RSM_FIT_MIN_SPREAD * dmag;
    if (sd <= wsum * lim * lim) {
        return RSM_ERR_DEGENERATE;
    }
    if (sqrtf(dot * dot + cross * cross) <= RSM_FIT_MIN_CORR * sqrtf(ss) * sqrtf(sd)) {
        return RSM_ERR_DEGENERATE;
    }

    /* The angle that maximises sum w (R a) . b, i.e. minimises the squared
     * residuals; atan2 keeps the quadrant (any angle, not only +-90 deg). */
    th = rsm_atan2f(cross, dot);
    c = rsm_cosf(th);
    s = rsm_sinf(th);
    t->x = dcx - (c * scx - s * scy);
    t->y = dcy - (s * scx + c * scy);
    t->theta = rsm_wrap_angle(th);
    if (!isfinite(t->x) || !isfinite(t->y) || !isfinite(t->theta)) {
        return RSM_ERR_DEGENERATE;
    }
    return RSM_OK;
}

int rsm_rigid_fit(const rsm_point_t *src, const rsm_point_t *dst, const float *w, size_t n, rsm_pose_t *t)
{
    rsm_pose_t r;
    size_t i;
    int st;
    if (t == NULL || (n > 0u && (src == NULL || dst == NULL))) {
        return RSM_ERR_INVAL;
    }
    for (i = 0; i < n; ++i) {
        if (!rsm_point_finite(&src[i]) || !rsm_point_finite(&dst[i])) {
            return RSM_ERR_INVAL;
        }
        if (w != NULL && !(isfinite(w[i]) && w[i] >= 0.0f)) {
            return RSM_ERR_INVAL;
        }
    }
    if (n < 2u) {
        return RSM_ERR_DEGENERATE;
    }
    st = rsm_rigid_fit_core(src, NULL, dst, w, n, &r);
    if (st == RSM_OK) {
        *t = r;
    }
    return st;
}
