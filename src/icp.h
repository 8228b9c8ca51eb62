/* The paper's baseline: conventional point-to-point ICP (Besl and McKay),
 * nearest neighbours by exhaustive search, closed-form 2-D rigid alignment per
 * iteration, 30 iterations by default, in fixed memory. The reference is the
 * previous scan's points in the world frame. */
#ifndef RSM_ICP_H
#define RSM_ICP_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/localizer_parts.h"

#ifdef __cplusplus
extern "C" {
#endif

rsm_icp_config_t rsm_icp_config_default(void);

typedef struct rsm_icp_result {
    rsm_pose_t pose;        /* aligned robot pose in the world frame */
    uint16_t iterations;    /* iterations run */
    uint16_t pairs;         /* pairs used in the last iteration */
    float rms_m;            /* RMS pair distance after the last iteration */
} rsm_icp_result_t;

/* Validates cfg (max_iterations >= 1, max_pair_dist_m > 0, non-negative
 * convergence thresholds, min_pairs <= RSM_ICP_MAX_POINTS; a min_pairs below 2
 * acts as 2) and clears the reference. RSM_OK or RSM_ERR_INVAL. */
int rsm_icp_init(rsm_icp_t *icp, const rsm_icp_config_t *cfg);

/* Copies n world-frame points as the new reference (at most
 * RSM_ICP_MAX_POINTS; more -> RSM_ERR_NOMEM, reference unchanged). Points
 * that are not finite are left out of ref_count. */
int rsm_icp_set_reference(rsm_icp_t *icp, const rsm_point_t *pts, size_t n);

/* Aligns n robot-frame points to the reference starting from the world-frame
 * guess. On RSM_OK *res holds the aligned pose. RSM_ERR_DEGENERATE when
 * there is no reference or, in any iteration, fewer than min_pairs pairs or
 * a degenerate fit (res->pose = guess, iterations and pairs as reached,
 * rms_m = 0). RSM_ERR_NOMEM if n > RSM_ICP_MAX_POINTS, RSM_ERR_INVAL for
 * NULL arguments or a non-finite guess (*res untouched for both). Points
 * that are not finite are never paired. Stops after the first iteration whose
 * step moves the pose less than converged_m and turns it less than
 * converged_rad, or after max_iterations. rms_m is over the last iteration's
 * pairs at the returned pose. Reentrant for distinct states. */
int rsm_icp_align(rsm_icp_t *icp, const rsm_point_t *pts, size_t n, const rsm_pose_t *guess,
                  rsm_icp_result_t *res);

/* Least-squares rigid transform mapping src[i] onto dst[i] (w may be NULL
 * for unit weights; pairs of weight 0 are ignored): closed form for 2-D.
 * Writes *t such that dst ~= t (+) src. RSM_ERR_DEGENERATE (*t untouched) for
 * fewer than 2 pairs of positive weight, or when the rotation is undetermined
 * (all src or all dst points coincide, or the cost is flat in the angle).
 * RSM_ERR_INVAL for NULL arguments, non-finite points, or weights that are
 * negative or not finite. Shared by ICP and the RANSAC refinement. */
int rsm_rigid_fit(const rsm_point_t *src, const rsm_point_t *dst, const float *w, size_t n,
                  rsm_pose_t *t);

#ifdef __cplusplus
}
#endif

#endif /* RSM_ICP_H */
