/* Point-to-point ICP baseline, the paper's comparison; see src/paper/icp.h for
 * the contract. Built only with RSM_WITH_ICP (CMake option RSM_ICP). */
#include "paper/icp.h"

#include <math.h>

#include "rsm/status.h"
#include "core/check.h"
#include "core/fmath.h"
#include "paper/rigid.h"

/* Pair counts are reported in uint16_t. */
RSM_STATIC_ASSERT(icp_points_fit_u16, RSM_ICP_MAX_POINTS >= 2 && RSM_ICP_MAX_POINTS <= 65535);

rsm_icp_config_t rsm_icp_config_default(void)
{
    rsm_icp_config_t c;
    c.max_iterations = 30u;
    c.max_pair_dist_m = 1.0f;
    c.converged_m = 1e-4f;
    c.converged_rad = 1e-4f;
    c.min_pairs = 10u;
    return c;
}

int rsm_icp_config_check(const rsm_icp_config_t *cfg, const char **field)
{
    RSM_CHECK_FIELD(cfg != NULL, "icp");
    RSM_CHECK_FIELD(cfg->max_iterations >= 1u, "icp.max_iterations");
    RSM_CHECK_FIELD(isfinite(cfg->max_pair_dist_m) && cfg->max_pair_dist_m > 0.0f, "icp.max_pair_dist_m");
    RSM_CHECK_FIELD(isfinite(cfg->converged_m) && cfg->converged_m >= 0.0f, "icp.converged_m");
    RSM_CHECK_FIELD(isfinite(cfg->converged_rad) && cfg->converged_rad >= 0.0f, "icp.converged_rad");
    RSM_CHECK_FIELD(cfg->min_pairs <= RSM_ICP_MAX_POINTS, "icp.min_pairs");
    return RSM_OK;
}

#if RSM_WITH_ICP

int rsm_icp_init(rsm_icp_t *icp, const rsm_icp_config_t *cfg)
{
    if (icp == NULL || rsm_icp_config_check(cfg, NULL) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    icp->cfg = cfg;
    icp->ref_count = 0u;
    return RSM_OK;
}

int rsm_icp_set_reference(rsm_icp_t *icp, const rsm_point_t *pts, size_t n)
{
    size_t i;
    size_t k = 0;
    if (icp == NULL || (pts == NULL && n > 0u)) {
        return RSM_ERR_INVAL;
    }
    if (n > RSM_ICP_MAX_POINTS) {
        return RSM_ERR_NOMEM;
    }
    for (i = 0; i < n; ++i) {
        /* A non-finite point could never be anyone's nearest neighbour; leaving
         * it out keeps the search loop free of checks. */
        if (rsm_point_finite(&pts[i])) {
            icp->ref[k++] = pts[i];
        }
    }
    icp->ref_count = k;
    return RSM_OK;
}

/* Pairs every current point (mapped by est) with its nearest reference
 * point: icp->work[i] becomes that reference point, or NaN when point i has
 * none within max_dist2 (or is itself not finite). Returns the pair count. */
static size_t pair_points(rsm_icp_t *icp, const rsm_point_t *pts, size_t n, const rsm_pose_t *est, float max_dist2)
{
    size_t i;
    size_t j;
    size_t pairs = 0;
    for (i = 0; i < n; ++i) {
        rsm_point_t p;
        float best = INFINITY;
        size_t bj = 0;
        icp->work[i].x = NAN;
        icp->work[i].y = NAN;
        if (!rsm_point_finite(&pts[i])) {
            continue;
        }
        p = rsm_pose_apply(est, &pts[i]);
        for (j = 0; j < icp->ref_count; ++j) {
            const float dx = icp->ref[j].x - p.x;
            const float dy = icp->ref[j].y - p.y;
            const float d2 = dx * dx + dy * dy;
            if (d2 < best) {
                best = d2;
                bj = j;
            }
        }
        if (best <= max_dist2) {
            icp->work[i] = icp->ref[bj];
            ++pairs;
        }
    }
    return pairs;
}

static void degenerate_result(rsm_icp_result_t *res, const rsm_pose_t *guess, uint16_t iterations, size_t pairs)
{
    res->pose = *guess;
    res->iterations = iterations;
    res->pairs = (uint16_t)pairs;
    res->rms_m = 0.0f;
}

int rsm_icp_align(rsm_icp_t *icp, const rsm_point_t *pts, size_t n, const rsm_pose_t *guess,
                  rsm_icp_result_t *res)
{
    const rsm_icp_config_t *cfg;
    rsm_pose_t est;
    size_t min_pairs;
    size_t pairs = 0;
    size_t i;
    float max_dist2;
    float sum2 = 0.0f;
    uint16_t it;
    if (icp == NULL || icp->cfg == NULL || guess == NULL || res == NULL || (pts == NULL && n > 0u)) {
        return RSM_ERR_INVAL;
    }
    if (!isfinite(guess->x) || !isfinite(guess->y) || !isfinite(guess->theta)) {
        return RSM_ERR_INVAL;
    }
    if (n > RSM_ICP_MAX_POINTS) {
        return RSM_ERR_NOMEM;
    }
    cfg = icp->cfg;
    /* Two pairs is the least that fixes a rigid transform. */
    min_pairs = cfg->min_pairs < 2u ? 2u : (size_t)cfg->min_pairs;
    max_dist2 = cfg->max_pair_dist_m * cfg->max_pair_dist_m;
    if (icp->ref_count == 0u) {
        degenerate_result(res, guess, 0u, 0u);
        return RSM_ERR_DEGENERATE;
    }

    est = *guess;
    est.theta = rsm_wrap_angle(est.theta);
    for (it = 1u; it <= cfg->max_iterations; ++it) {
        rsm_pose_t delta;
        rsm_pose_t next;
        float step_m;
        float step_rad;
        pairs = pair_points(icp, pts, n, &est, max_dist2);
        /* delta maps the mapped points onto their partners in the world frame,
         * so the new robot pose is delta (+) est. */
        if (pairs < min_pairs || rsm_rigid_fit_core(pts, &est, icp->work, NULL, n, &delta) != RSM_OK) {
            degenerate_result(res, guess, it, pairs);
            return RSM_ERR_DEGENERATE;
        }
        next = rsm_pose_compose(&delta, &est);
        step_m = sqrtf((next.x - est.x) * (next.x - est.x) + (next.y - est.y) * (next.y - est.y));
        step_rad = fabsf(rsm_wrap_angle(next.theta - est.theta));
        est = next;
        if ((step_m < cfg->converged_m && step_rad < cfg->converged_rad) || it == cfg->max_iterations) {
            break;
        }
    }

    /* RMS over the last iteration's pairs, at the pose returned. */
    for (i = 0; i < n; ++i) {
        if (rsm_point_finite(&icp->work[i])) {
            const rsm_point_t p = rsm_pose_apply(&est, &pts[i]);
            const float dx = icp->work[i].x - p.x;
            const float dy = icp->work[i].y - p.y;
            sum2 += dx * dx + dy * dy;
        }
    }
    res->pose = est;
    res->iterations = it;
    res->pairs = (uint16_t)pairs;
    res->rms_m = sqrtf(sum2 / (float)pairs);
    return RSM_OK;
}

#else /* !RSM_WITH_ICP: the baseline is not built; the method is refused */

int rsm_icp_init(rsm_icp_t *icp, const rsm_icp_config_t *cfg)
{
    (void)icp;
    (void)cfg;
    return RSM_ERR_NOSYS;
}

int rsm_icp_set_reference(rsm_icp_t *icp, const rsm_point_t *pts, size_t n)
{
    (void)icp;
    (void)pts;
    (void)n;
    return RSM_ERR_NOSYS;
}

int rsm_icp_align(rsm_icp_t *icp, const rsm_point_t *pts, size_t n, const rsm_pose_t *guess,
                  rsm_icp_result_t *res)
{
    (void)icp;
    (void)pts;
    (void)n;
    (void)guess;
    (void)res;
    return RSM_ERR_NOSYS;
}

#endif /* RSM_WITH_ICP */
