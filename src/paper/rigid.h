/* The closed-form least-squares 2-D rigid fit: what the RANSAC refinement
 * and the ICP baseline share (neither depends on the other). Internal. */
#ifndef RSM_RIGID_H
#define RSM_RIGID_H

#include <math.h>
#include <stddef.h>

#include "rsm/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

static inline int rsm_point_finite(const rsm_point_t *p)
{
    return isfinite(p->x) && isfinite(p->y);
}

/* Least-squares rigid transform mapping src[i] onto dst[i] (w may be NULL
 * for unit weights; pairs of weight 0 are ignored): closed form for 2-D.
 * Writes *t such that dst ~= t (+) src. RSM_ERR_DEGENERATE (*t untouched) for
 * fewer than 2 pairs of positive weight, or when the rotation is undetermined
 * (all src or all dst points coincide, or the cost is flat in the angle).
 * RSM_ERR_INVAL for NULL arguments, non-finite points, or weights that are
 * negative or not finite. */
int rsm_rigid_fit(const rsm_point_t *src, const rsm_point_t *dst, const float *w, size_t n,
                  rsm_pose_t *t);

/* The fit proper. Pair i is src[i] (first mapped by src_pose when that is
 * not NULL) onto dst[i]; pairs whose dst is not finite (ICP's "unpaired"
 * mark) or whose weight is zero are skipped. Inputs are otherwise trusted:
 * rsm_rigid_fit and ICP validate them. Two passes, so that the second
 * moments are taken about the centroids and do not cancel in float when the
 * points sit far from the origin. */
int rsm_rigid_fit_core(const rsm_point_t *src, const rsm_pose_t *src_pose, const rsm_point_t *dst, const float *w,
                       size_t n, rsm_pose_t *t);

#ifdef __cplusplus
}
#endif

#endif /* RSM_RIGID_H */
