#include "core/grid.h"

#include <math.h>
#include <string.h>
#include "core/fmath.h"

rsm_grid_config_t rsm_grid_config_default(void)
{
    rsm_grid_config_t c;
    c.cell_m = 0.05f;
    c.sigma_m = 0.005f;
    c.rule = RSM_GRID_SIGMA_TOUCH;
    return c;
}

int32_t rsm_grid_cell_of(float v_m, float cell_m)
{
    /* floorf, not a cast: (int)(-0.3) is 0, which would give cell 0 twice the width. */
    return (int32_t)rsm_floorf(v_m / cell_m);
}

void rsm_image_clear(rsm_image_t *img)
{
    size_t k;
    for (k = 0; k < img->count; ++k) {
        const uint32_t i = img->cells[k];
        img->bits[i >> 5] &= ~(1u << (i & 31u));
    }
    img->count = 0;
    if (img->overflow != 0) {
        /* Unlisted cells exist: only a full wipe is certain to remove them. */
        memset(img->bits, 0, sizeof img->bits);
    }
    img->overflow = 0;
    img->outside = 0;
}

void rsm_image_reset(rsm_image_t *img)
{
    memset(img->bits, 0, sizeof img->bits);
    img->count = 0;
    img->overflow = 0;
    img->outside = 0;
}

int rsm_image_set(rsm_image_t *img, const rsm_window_t *w, int32_t gx, int32_t gy)
{
    uint32_t i;
    uint32_t bit;
    if (!rsm_window_contains(w, gx, gy)) {
        img->outside++;
        return 0;
    }
    i = rsm_window_index(gx, gy);
    bit = 1u << (i & 31u);
    if (img->bits[i >> 5] & bit) {
        return 0;
    }
    img->bits[i >> 5] |= bit;
    if (img->count < RSM_IMAGE_MAX_CELLS) {
        img->cells[img->count++] = i;
    } else {
        img->overflow++;
    }
    return 1;
}

size_t rsm_image_mark_points(rsm_image_t *img, const rsm_window_t *w, const rsm_grid_config_t *cfg,
                             const rsm_point_t *pts, size_t n)
{
    const float a = cfg->cell_m;
    const float s = cfg->sigma_m;
    size_t added = 0;
    size_t k;
    for (k = 0; k < n; ++k) {
        const float x = pts[k].x;
        const float y = pts[k].y;
        int32_t gx;
        int32_t gy;
        float fx;
        float fy;
        /* Far or non-finite points would overflow the int32 conversion. */
        if (!(fabsf(x) < 1.0e6f) || !(fabsf(y) < 1.0e6f)) {
            img->outside++;
            continue;
        }
        gx = rsm_grid_cell_of(x, a);
        gy = rsm_grid_cell_of(y, a);
        /* Offsets of the point inside its cell, in [0, a). */
        fx = x - (float)gx * a;
        fy = y - (float)gy * a;
        switch (cfg->rule) {
        case RSM_GRID_SIGMA_INSIDE:
            if (fx >= s && fx < a - s && fy >= s && fy < a - s) {
                added += (size_t)rsm_image_set(img, w, gx, gy);
            }
            break;
        case RSM_GRID_SIGMA_TOUCH: {
            /* The sigma circle can reach at most one neighbour per axis. */
            const int32_t nx = fx < s ? gx - 1 : (fx >= a - s ? gx + 1 : gx);
            const int32_t ny = fy < s ? gy - 1 : (fy >= a - s ? gy + 1 : gy);
            added += (size_t)rsm_image_set(img, w, gx, gy);
            if (nx != gx) {
                added += (size_t)rsm_image_set(img, w, nx, gy);
            }
            if (ny != gy) {
                added += (size_t)rsm_image_set(img, w, gx, ny);
            }
            if (nx != gx && ny != gy) {
                /* The corner cell is touched only if the circle reaches the corner. */
                const float cx = (nx > gx ? a : 0.0f) - fx;
                const float cy = (ny > gy ? a : 0.0f) - fy;
                if (cx * cx + cy * cy < s * s) {
                    added += (size_t)rsm_image_set(img, w, nx, ny);
                }
            }
            break;
        }
        default:
            added += (size_t)rsm_image_set(img, w, gx, gy);
            break;
        }
    }
    return added;
}
