/* Integer Harris key points on a binary occupancy image.
 *
 * Pixels are 0/1, so Sobel derivatives lie in [-4, 4] and, summed over the
 * 3x3 window with 1-2-1 weights (total weight 16), the structure-tensor
 * entries stay within 16 * 16 = 256: det and trace^2 fit easily in 32 bits.
 * The response R = det - k trace^2 is computed as
 * k_den * det - k_num * trace^2 (k = k_num / k_den, default 1/25 = 0.04).
 * Only listed candidate cells are evaluated, so cost grows with occupied
 * cells, not image area. Non-maximum suppression is greedy: candidates are
 * taken strongest first and each accepted key point suppresses others
 * within nms_radius cells (Chebyshev), which is 3x3 suppression at radius 1. */
#ifndef RSM_HARRIS_H
#define RSM_HARRIS_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/localizer_parts.h"
#include "core/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

rsm_harris_config_t rsm_harris_config_default(void);

/* Reads the 5x5 neighbourhood of (gx, gy) as a 25-bit mask, bit
 * (dy + 2) * 5 + (dx + 2) for dx, dy in [-2, 2]. */
typedef uint32_t (*rsm_patch_fn)(const void *ctx, int32_t gx, int32_t gy);

/* Patch readers for a scan image (ctx: rsm_harris_image_src_t) and for a
 * thresholded map (ctx: rsm_harris_map_src_t, declared in localizer use). */
typedef struct rsm_harris_image_src {
    const rsm_image_t *img;
    const rsm_window_t *win;
} rsm_harris_image_src_t;
uint32_t rsm_harris_patch_image(const void *ctx, int32_t gx, int32_t gy);

/* Response at a cell from its 5x5 patch. Pure. */
int32_t rsm_harris_response(const rsm_harris_config_t *cfg, uint32_t patch);

/* Evaluates the response at n candidate cells (at most RSM_MAX_CANDIDATES
 * are evaluated; the rest are counted in *skipped if not NULL), suppresses
 * non-maxima and writes the strongest at most cap key points to out,
 * strongest first (overwritten). Returns the count (>= 0) or RSM_ERR_INVAL.
 * Deterministic: ties are broken by candidate order. Reentrant. */
int rsm_harris_detect(const rsm_harris_config_t *cfg, rsm_harris_work_t *work, rsm_patch_fn patch,
                      const void *ctx, const rsm_cell_t *cands, size_t n, rsm_keypoint_t *out, size_t cap,
                      size_t *skipped);

#ifdef __cplusplus
}
#endif

#endif /* RSM_HARRIS_H */
