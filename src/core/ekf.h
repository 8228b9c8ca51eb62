/* 3-state extended Kalman filter over the robot pose (x, y, theta).
 * Predict with an odometry increment (eq. 17), update with a measured pose
 * (H = I): innovation = measured - predicted with the angle wrapped (the
 * paper's eq. 18 has the sign reversed), K = P H^T S^-1 (eq. 20 omits S^-1),
 * Joseph-form covariance update, explicitly symmetrised. */
#ifndef RSM_EKF_H
#define RSM_EKF_H

#include <stdint.h>

#include "rsm/geom.h"
#include "rsm/odometry.h"
#include "rsm/localizer_parts.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Beyond these variances the estimate is lost in that respect (a position
 * std over 1 km, a heading std over pi): the linearised correlations mean
 * nothing, and in float they make S singular, so no update could ever be
 * taken again. The prediction then keeps only the diagonal, capped here,
 * and the next measurement within the gate restores the estimate. */
#define RSM_EKF_LOST_VAR_XY_M2 1.0e6f
#define RSM_EKF_LOST_VAR_THETA (3.14159265f * 3.14159265f)

/* Sets the state and covariance (p0 row-major; NULL -> zero). Returns
 * RSM_ERR_INVAL if p0 is not symmetric with a non-negative diagonal. */
int rsm_ekf_init(rsm_ekf_t *ekf, const rsm_pose_t *x0, const float p0[9]);

/* x = x (+) u; P = Jv P Jv^T + Ju Q Ju^T (q is 3x3 in increment space;
 * NULL -> no process noise), Jacobians taken at the prior state; a lost
 * covariance is reset to its capped diagonal (counted in lost). Returns
 * RSM_OK, RSM_ERR_INVAL for NULL ekf/u or non-finite u/q, RSM_ERR_DEGENERATE
 * if the result would not be finite; the state is unchanged on error. */
int rsm_ekf_predict(rsm_ekf_t *ekf, const rsm_motion_t *u, const float q[9]);

/* Squared Mahalanobis distance of measurement z (noise r, 3x3) from the
 * current state, written to *d2. RSM_ERR_DEGENERATE if S is singular or z/r
 * are not finite, RSM_ERR_INVAL for NULL arguments (*d2 untouched). */
int rsm_ekf_mahalanobis(const rsm_ekf_t *ekf, const rsm_pose_t *z, const float r[9], float *d2);

/* Update with measured pose z and its covariance r. If gate_d2 > 0 and the
 * squared Mahalanobis distance exceeds it, the state is left unchanged and
 * RSM_ERR_RANGE is returned. RSM_ERR_DEGENERATE (state unchanged) if S is
 * singular, z or r is not finite, or the result would not be finite. These
 * three outcomes count in `rejected`. RSM_ERR_INVAL for NULL arguments. */
int rsm_ekf_update(rsm_ekf_t *ekf, const rsm_pose_t *z, const float r[9], float gate_d2);

/* Moves the state as an update with a measurement of the heading alone
 * would (its innovation dtheta, measured - estimated and wrapped, and
 * variance r > 0; H = (0 0 1), no gate), and leaves P as it is: for a
 * measurement repeated scan after scan whose error does not average out
 * (the same walls seen again), which must not make the filter surer with
 * each scan. RSM_ERR_DEGENERATE (counted in rejected, state unchanged) for
 * non-finite input or result, RSM_ERR_INVAL for NULL. */
int rsm_ekf_pull_heading(rsm_ekf_t *ekf, float dtheta, float r);

/* Closed-form inverse of a 3x3 matrix; RSM_ERR_DEGENERATE if an entry is not
 * finite or |det| <= 1e-6 * (product of the row norms), out untouched;
 * RSM_ERR_INVAL for NULL. out may be m itself. */
int rsm_mat3_inverse(const float m[9], float out[9]);

#ifdef __cplusplus
}
#endif

#endif /* RSM_EKF_H */
