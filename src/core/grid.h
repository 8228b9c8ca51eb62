/* The grid: world points -> a binary image of cells of side a (eqs 6-9).
 *
 * Cells are indexed globally with floor(x / a) (not C's truncating cast,
 * which would make the cells either side of zero one cell too wide). Images
 * live in a square window of RSM_MAP_SIZE cells whose lower-left global cell
 * is (ox, oy); storage is toroidal (cell (gx, gy) lives at bit
 * (gx mod N) + N (gy mod N)), so the window scrolls with the robot without
 * moving any memory. Only cells inside the window are ever stored. */
#ifndef RSM_GRID_H
#define RSM_GRID_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "core/fmath.h"
#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/localizer_parts.h"

#ifdef __cplusplus
extern "C" {
#endif

rsm_grid_config_t rsm_grid_config_default(void);

/* Global cell of a coordinate: floor(v / a). */
int32_t rsm_grid_cell_of(float v_m, float cell_m);

/* Where world (x, y) sits among the cell centres of a grid with 1/a =
 * inv_a: cell (i, j) holds the nearest centre at or below-left of it, and
 * (du, dv) in [0, 1) are the fractions of the way to the next centres. What
 * a bilinear read or a bilinear write of the four cells needs. Beyond
 * 1e9 cells (or NaN): cell (2^30, 2^30), fractions 0. */
typedef struct rsm_bilinear {
    int32_t i;
    int32_t j;
    float du;
    float dv;
} rsm_bilinear_t;

static inline rsm_bilinear_t rsm_bilinear_at(float x, float y, float inv_a)
{
    /* Cell centres sit at integer coordinates of u, v. Inline: the map's
     * reads call it for every point of every descent step. */
    const float u = x * inv_a - 0.5f;
    const float v = y * inv_a - 0.5f;
    const float fu = rsm_floorf(u);
    const float fv = rsm_floorf(v);
    rsm_bilinear_t b;
    if (!(fu > -1.0e9f && fu < 1.0e9f && fv > -1.0e9f && fv < 1.0e9f)) {
        /* Beyond any grid (or NaN): a far cell, and no overflowing cast. */
        b.i = 1 << 30;
        b.j = 1 << 30;
        b.du = 0.0f;
        b.dv = 0.0f;
        return b;
    }
    b.i = (int32_t)fu;
    b.j = (int32_t)fv;
    b.du = u - fu;
    b.dv = v - fv;
    return b;
}

/* True if the global cell lies inside the window. */
static inline int rsm_window_contains(const rsm_window_t *w, int32_t gx, int32_t gy)
{
    return (uint32_t)(gx - w->ox) < (uint32_t)RSM_MAP_SIZE && (uint32_t)(gy - w->oy) < (uint32_t)RSM_MAP_SIZE;
}

/* Toroidal storage index of a global cell (the caller checks containment). */
static inline uint32_t rsm_window_index(int32_t gx, int32_t gy)
{
    const uint32_t m = (uint32_t)RSM_MAP_SIZE - 1u;
    return ((uint32_t)gx & m) | (((uint32_t)gy & m) << RSM_MAP_SIZE_LOG2);
}

/* Global cell of a toroidal index inside window w. */
static inline rsm_cell_t rsm_window_cell(const rsm_window_t *w, uint32_t index)
{
    const uint32_t m = (uint32_t)RSM_MAP_SIZE - 1u;
    rsm_cell_t c;
    c.gx = w->ox + (int32_t)(((index & m) - (uint32_t)w->ox) & m);
    c.gy = w->oy + (int32_t)(((index >> RSM_MAP_SIZE_LOG2) - (uint32_t)w->oy) & m);
    return c;
}

/* Empties an image. Cost: O(listed cells). */
void rsm_image_clear(rsm_image_t *img);

/* Clears every bit (use once after declaring an image). Cost: O(window). */
void rsm_image_reset(rsm_image_t *img);

/* Reads a cell: 1 if set, 0 if clear or outside the window. */
static inline int rsm_image_get(const rsm_image_t *img, const rsm_window_t *w, int32_t gx, int32_t gy)
{
    uint32_t i;
    if ((uint32_t)(gx - w->ox) >= (uint32_t)RSM_MAP_SIZE || (uint32_t)(gy - w->oy) >= (uint32_t)RSM_MAP_SIZE) {
        return 0;
    }
    i = rsm_window_index(gx, gy);
    return (int)((img->bits[i >> 5] >> (i & 31u)) & 1u);
}

/* Sets a cell inside the window and lists it; returns 1 if it was newly set,
 * 0 if already set or outside the window (counted in outside). */
int rsm_image_set(rsm_image_t *img, const rsm_window_t *w, int32_t gx, int32_t gy);

/* Marks the cells of n world-frame points under the grid rule (appends to
 * what is already set). Returns the number of newly set cells. */
size_t rsm_image_mark_points(rsm_image_t *img, const rsm_window_t *w, const rsm_grid_config_t *cfg,
                             const rsm_point_t *pts, size_t n);

#ifdef __cplusplus
}
#endif

#endif /* RSM_GRID_H */
