/* Importing an occupancy image (a ROS map_server map, or any grid of
 * occupied pixels) as the persistent map to localize in (RSM_METHOD_MAP).
 *
 * The image goes in row by row, so that a microcontroller streams it from
 * storage one row at a time: rsm_localizer_import_begin empties the map,
 * then rsm_localizer_import_row writes each row's occupied pixels into
 * every level of the map. Rows may come in any order (a PGM file holds its
 * top row first). Free and unknown pixels write nothing: the caller decides
 * which pixels are occupied (the ROS thresholds, negate and mode are the
 * host's business, tools/nav/rosmap.c).
 *
 * How a pixel becomes cells (docs/mapfile.md, "Importing a ROS map"):
 *  - on the levels below splat_from (the finest, by default), a pixel
 *    finer than the cell marks the cell holding its centre fully occupied,
 *    as a scan's return marks its own cell; a coarser one is sampled along
 *    both sides no farther apart than a cell (a cell over sqrt(2) in a
 *    turned image) and marks every cell a sample lies in, so that a wall
 *    stays unbroken however coarse the source is;
 *  - on the levels from splat_from, by default (RSM_IMPORT_SHARE), its
 *    centre (or, for a pixel coarser than the cell, points along it no
 *    farther apart than a cell) shares occupancy among the four nearest
 *    cell centres by bilinear weights, as a scan's return shares its hit,
 *    so that a wall reads where it is, not at a coarse cell's centre: the
 *    nearest centre gets the saturation, the others the saturation times
 *    their weight over the nearest's; a cell keeps the largest value any
 *    pixel gave it. RSM_IMPORT_TOUCH sets the cell a pixel's centre lies in
 *    fully occupied instead (measured in tests/unit/test_mapimport.c: the
 *    same tracking within half a millimetre).
 * Fully occupied is the cell value 15 (a wall seen many times). A pixel
 * centre on a cell border goes to the cell above it (floor), as a return.
 *
 * Capacity: the map holds RSM_TMAP_TILES tiles over all levels. An import
 * never evicts what it wrote itself; a cell that needs a tile when none is
 * left is dropped and counted (report.dropped), and the row returns
 * RSM_ERR_NOMEM after writing all of it that fit.
 *
 * No heap, no global state; not reentrant for one localizer. */
#ifndef RSM_MAPIMPORT_H
#define RSM_MAPIMPORT_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/localizer.h"

#ifdef __cplusplus
extern "C" {
#endif

/* How occupied pixels are written on the levels from splat_from. */
#define RSM_IMPORT_SHARE 0u /* bilinear shares among the four nearest cells (default) */
#define RSM_IMPORT_TOUCH 1u /* the cell a pixel lies in, fully occupied */

/* Where the image lies in the world: ROS map_server's conventions. Row 0 is
 * the bottom row (smallest y before the rotation), pixel 0 of a row its
 * leftmost (smallest x). */
typedef struct rsm_import_grid {
    float res_m;      /* pixel side, metres; > 0 */
    float origin_x;   /* world position of the outer corner of pixel 0 of row 0 */
    float origin_y;   /*   (the bottom-left corner of the image), metres */
    float yaw_rad;    /* the image's rotation about that corner, CCW; 0 in most maps */
    uint32_t width;   /* pixels per row; >= 1 */
    uint8_t coarse;   /* RSM_IMPORT_SHARE or RSM_IMPORT_TOUCH */
} rsm_import_grid_t;

/* What an import wrote so far (begin zeroes it, each row adds to it). */
typedef struct rsm_import_report {
    uint32_t rows;      /* rows taken */
    uint32_t occupied;  /* occupied pixels taken */
    uint32_t cells;     /* cell writes made, all levels */
    uint32_t dropped;   /* cell writes lost: no tile was left for them (pool full) */
    uint32_t outside;   /* occupied pixels beyond the map's coordinate range (not written) */
} rsm_import_report_t;

/* RSM_OK when rsm_localizer_import_row would take rows laid out as grid
 * describes: res_m above 0, at most 1000 m and at most 256 of the map's
 * finest cells; a finite origin and yaw; width >= 1; coarse one of the two
 * modes. Else RSM_ERR_INVAL (RSM_ERR_NOSYS for another method than
 * RSM_METHOD_MAP). Reads only: a caller checks a whole image's layout
 * before rsm_localizer_import_begin empties the map. */
int rsm_localizer_import_check(const rsm_localizer_t *loc, const rsm_import_grid_t *grid);

/* Starts an import: empties loc's persistent map (a write into it still
 * running is dropped) and zeroes *report (may be NULL). Returns RSM_OK;
 * RSM_ERR_INVAL for loc NULL or never initialised; RSM_ERR_NOSYS for
 * another method than RSM_METHOD_MAP (loc untouched). */
int rsm_localizer_import_begin(rsm_localizer_t *loc, rsm_import_report_t *report);

/* Writes row `row` of an image laid out by *grid into loc's persistent
 * map: occupied[k] != 0 marks pixel k (grid->width bytes). Adds to what is
 * there (rows of one import, or a map built before without begin; a write
 * still running is finished first), and adds to *report (may be NULL).
 * Then, as after rsm_localizer_load_map, the next scan is matched against
 * the map (none starts a new one): it is taken as written at loc's current
 * estimate, with no fit recorded yet. loc's estimate is left as it is: set
 * it with rsm_localizer_set_pose where the robot is in the map's frame.
 * Returns RSM_OK; RSM_ERR_NOMEM when cells of this row were dropped (pool
 * full; the rest of the row is written); RSM_ERR_INVAL for loc NULL or
 * never initialised, grid or occupied NULL, a resolution not positive and
 * finite (or above 256 finest cells, or 1 km), an origin or yaw not
 * finite, width 0 or a
 * coarse mode not listed (loc untouched); RSM_ERR_NOSYS for another
 * method than RSM_METHOD_MAP (loc untouched). */
int rsm_localizer_import_row(rsm_localizer_t *loc, const rsm_import_grid_t *grid, uint32_t row,
                             const uint8_t *occupied, rsm_import_report_t *report);

#ifdef __cplusplus
}
#endif

#endif /* RSM_MAPIMPORT_H */
