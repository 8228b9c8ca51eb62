/* The reference map: a fixed square of hit counters over the grid window
 * that scrolls with the robot (toroidal storage, see grid.h). Each accepted
 * scan is superimposed at its updated pose; cells that leave the window are
 * forgotten, so travel is unbounded in fixed memory (the paper instead
 * zero-pads an ever-growing image). RAM: RSM_MAP_CELLS bytes. */
#ifndef RSM_MAP_H
#define RSM_MAP_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/localizer_parts.h"
#include "core/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Empties the map and centres the window on (x, y). RSM_ERR_INVAL for a
 * non-positive cell size or non-finite centre. */
int rsm_map_init(rsm_map_t *map, float cell_m, float x_m, float y_m);

/* Scrolls the window so that (x, y) is near its centre once the robot is
 * more than a quarter window from it; cells entering the window are
 * cleared. Returns 1 if the window moved, 0 if not, RSM_ERR_INVAL for a
 * non-finite position (map unchanged). Cost: O(cells that enter). */
int rsm_map_recenter(rsm_map_t *map, float x_m, float y_m);

/* Adds one hit to the cell of each world point (same cell rule as grid
 * marking with RSM_GRID_NEAREST), saturating at 255. Returns cells hit. */
size_t rsm_map_add_points(rsm_map_t *map, const rsm_point_t *pts, size_t n);

/* Hit count of a global cell (0 outside the window). */
static inline uint8_t rsm_map_hits(const rsm_map_t *map, int32_t gx, int32_t gy)
{
    if (!rsm_window_contains(&map->win, gx, gy)) {
        return 0;
    }
    return map->hits[rsm_window_index(gx, gy)];
}

/* Result of aligning points to the map. */
typedef struct rsm_map_fit {
    rsm_pose_t pose;     /* refined pose */
    float info[9];       /* J^T J of the last iteration (information, unnormalised) */
    float cost;          /* mean squared residual (1 - M)^2 over used points */
    uint32_t used;       /* points with a non-zero map gradient */
    uint32_t iterations;
} rsm_map_fit_t;

/* Refines pose so that the robot-frame points land on occupied map cells:
 * Gauss-Newton on sum (1 - M(pose (+) p))^2, where M is the map's occupancy
 * (min(hits, saturation) / saturation) interpolated bilinearly between cell
 * centres. The cost is flat far from walls, so stray (outlier) points have no
 * pull; the basin is about one cell, which is why this runs after RANSAC.
 * A step that does not lower the cost is halved (a few times) before it is
 * taken, so the fit settles instead of bouncing between two poses.
 * Returns RSM_OK, RSM_ERR_DEGENERATE when too few points touch the map or
 * the normal equations are singular (fit->pose = start), RSM_ERR_INVAL for
 * bad arguments. Reentrant. */
int rsm_map_align(const rsm_map_t *map, const rsm_point_t *pts, size_t n, const rsm_pose_t *start,
                  uint8_t saturation, uint32_t iterations, rsm_map_fit_t *fit);

#ifdef __cplusplus
}
#endif

#endif /* RSM_MAP_H */
