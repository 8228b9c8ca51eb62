/* Deterministic two-point RANSAC for the rigid transform T that carries
 * current key points onto reference key points: ref ~= T (+) cur.
 *
 * A hypothesis comes from two tentative matches (eqs 11-14): with
 * (A, B) = cur_i - cur_j and (C, D) = ref_i - ref_j, the rotation is
 * phi = atan2(A D - B C, A C + B D) (atan2, not atan; the sign follows from
 * writing ref = R(phi) cur + t) and t = ref_i - R(phi) cur_i. A sample is
 * rejected early when the two pair lengths differ by more than the length
 * tolerance. Support (eq. 15) counts the distinct reference key points with
 * a match that lands within the inlier tolerance. The iteration count
 * follows eq. 16 from the best support so far; when all pairs are fewer
 * than that count they are enumerated exhaustively instead of sampled. The
 * PRNG state lives in the struct and is seeded from the config, so the same
 * input always gives the same answer. The winner is refined by least squares
 * over its inliers. */
#ifndef RSM_RANSAC_H
#define RSM_RANSAC_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/localizer_parts.h"
#include "paper/match.h"

#ifdef __cplusplus
extern "C" {
#endif

rsm_ransac_config_t rsm_ransac_config_default(void);

typedef struct rsm_ransac_result {
    rsm_pose_t t;             /* ref ~= t (+) cur */
    uint32_t support;         /* distinct reference key points supporting t */
    uint32_t iterations;      /* hypotheses drawn (or pairs enumerated) */
    uint32_t length_rejects;  /* samples stopped by the early length test */
    uint32_t exhaustive;      /* 1 if every pair was tried */
    float rms_m;              /* RMS inlier residual after refinement */
} rsm_ransac_result_t;

/* RSM_OK if cfg is usable, else RSM_ERR_INVAL naming the first bad field
 * in *field (field may be NULL; see src/core/check.h). Reads only. */
int rsm_ransac_config_check(const rsm_ransac_config_t *cfg, const char **field);

/* Validates cfg (positive tolerances, 0 < confidence < 1, budget >= 1,
 * min_support >= 2) and seeds the PRNG. RSM_OK or RSM_ERR_INVAL. */
int rsm_ransac_init(rsm_ransac_t *rs, const rsm_ransac_config_t *cfg);

/* Estimates t from nm tentative matches between ref and cur points (one
 * frame, metres). Returns RSM_OK with *res filled, RSM_ERR_DEGENERATE when
 * no hypothesis reaches min_support (res->support tells the best found,
 * res->t is the identity), RSM_ERR_NOMEM if nm > RSM_MAX_MATCHES. The PRNG
 * advances, so repeated calls differ, but a fresh init repeats exactly. */
int rsm_ransac_estimate(rsm_ransac_t *rs, const rsm_point_t *ref, const rsm_point_t *cur, const rsm_match_t *m,
                        size_t nm, rsm_ransac_result_t *res);

#ifdef __cplusplus
}
#endif

#endif /* RSM_RANSAC_H */
