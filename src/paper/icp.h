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

/* 1: the baseline is built (CMake option RSM_ICP, on for host builds). 0:
 * only its config remains; rsm_icp_init and the rest return RSM_ERR_NOSYS,
 * so rsm_localizer_init refuses RSM_METHOD_ICP with it and no ICP code is
 * linked into a firmware image. */
#ifndef RSM_WITH_ICP
#define RSM_WITH_ICP 1
#endif

rsm_icp_config_t rsm_icp_config_default(void);

typedef struct rsm_icp_result {
    rsm_pose_t pose;        /* aligned robot pose in the world frame */
    uint16_t iterations;    /* iterations run */
    uint16_t pairs;         /* pairs used in the last iteration */
    float rms_m;            /* RMS pair distance after the last iteration */
} rsm_icp_result_t;

/* RSM_OK if cfg is usable, else RSM_ERR_INVAL naming the first bad field
 * in *field (field may be NULL; see src/core/check.h). Reads only; checked
 * even when the baseline is not built. */
int rsm_icp_config_check(const rsm_icp_config_t *cfg, const char **field);

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

#ifdef __cplusplus
}
#endif

#endif /* RSM_ICP_H */
