/* The building's wall grid: most indoor walls run along two perpendicular
 * directions, the same in every room. A scan's straight stretches of wall,
 * seen from the robot, give their direction modulo a quarter turn; set
 * against the grid's direction in the world (learnt from the first scans,
 * when the heading is still exact) that is a heading measurement no drift
 * accumulates in (docs/robustness.md, "Heading from the walls"). Internal. */
#ifndef RSM_WALLGRID_H
#define RSM_WALLGRID_H

#include <stddef.h>

#include "rsm/geom.h"

/* The walls' direction in the points' frame, modulo a quarter turn, among
 * the straight stretches (three consecutive points in a line, a few cm to
 * 0.3 m apart) whose direction lies within window_rad of expect (modulo a
 * quarter turn; window_rad >= pi/4 takes them all). *support gets their
 * summed length in metres (0: none, and *dir is expect), *straight that of
 * all straight stretches, in the window or not. */
void rsm_wallgrid_direction(const rsm_point_t *pts, size_t n, float expect, float window_rad, float *dir,
                            float *support, float *straight);

/* a - b wrapped into [-pi/4, pi/4): the difference of two directions
 * modulo a quarter turn. */
float rsm_wallgrid_diff(float a, float b);

#endif /* RSM_WALLGRID_H */
