/* Tentative correspondences between reference and current key points
 * (eq. 10 plus the +-w window): for each reference key point its nearest
 * current key point is found, then every current key point within +-w of
 * that nearest one (both axes) becomes a tentative match. Wrong ones are
 * left for RANSAC to reject. Matches come out grouped by reference index. */
#ifndef RSM_MATCH_H
#define RSM_MATCH_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/geom.h"
#include "rsm/localizer_parts.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ref/cur: key point positions in one frame (metres). max_nn_m: a nearest
 * neighbour farther than this gives no match (from the predicted
 * covariance). w_m: half-width of the box around the nearest neighbour.
 * Writes at most cap matches to out (overwritten) and returns the count;
 * matches that did not fit are counted in *dropped (may be NULL). Returns
 * RSM_ERR_INVAL for bad arguments (more than 65535 points, negative sizes). */
int rsm_match_tentative(const rsm_point_t *ref, size_t nref, const rsm_point_t *cur, size_t ncur,
                        float max_nn_m, float w_m, rsm_match_t *out, size_t cap, size_t *dropped);

#ifdef __cplusplus
}
#endif

#endif /* RSM_MATCH_H */
