/* The persistent map: occupancy at several resolutions in a fixed pool of
 * tiles (docs/map.md has the design and the measurements behind it).
 *
 * Level l has cells of cell_m * 2^l. Space is cut into square tiles of
 * RSM_TMAP_TILE_SIDE x RSM_TMAP_TILE_SIDE cells; a tile takes a pool slot the
 * first time a laser return lands in it, so the map costs memory only where
 * there are walls, wherever the robot goes. Each cell is a 4-bit occupancy
 * value: a return adds hit_inc (write_hit: a loaded map's lower rate, set by
 * the localizer), a beam passing through subtracts miss_dec,
 * clamped to 0..15; a missing tile reads as 0 (free or never seen). So moving
 * people, outliers and wrongly placed scans fade once beams pass where they
 * were.
 *
 * When the pool is full a return in a new tile takes the slot of the tile
 * least recently written (the smallest stamp), where coarse tiles age more
 * slowly and tiles that no second return confirmed faster (age_shift,
 * unconfirmed_shift); never one written by the update in progress; if every
 * slot was, the return is dropped and counted. Travel is unbounded: the
 * oldest places are forgotten first.
 *
 * A return adds hit_inc to its own cell on the finest level; on coarser
 * levels (from splat_from) it is shared among the four nearest cells by
 * bilinear weights (rounded), which keeps the coarse levels unbiased.
 *
 * RAM: RSM_TMAP_TILES * (RSM_TMAP_TILE_BYTES + 8) + 2 * RSM_TMAP_HASH bytes. */
#ifndef RSM_TILEMAP_H
#define RSM_TILEMAP_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/localizer_parts.h"

#ifdef __cplusplus
extern "C" {
#endif

rsm_tmap_config_t rsm_tmap_config_default(void);

/* RSM_OK if cfg is usable, else RSM_ERR_INVAL naming the first bad field
 * in *field (field may be NULL; see src/core/check.h). Reads only. */
int rsm_tmap_config_check(const rsm_tmap_config_t *cfg, const char **field);

/* Empties the map. RSM_ERR_INVAL for a bad config (cell not positive,
 * levels out of range, zero increments, saturation beyond 15). */
int rsm_tmap_init(rsm_tmap_t *map, const rsm_tmap_config_t *cfg);

/* Writes one scan into every level: points[k] (world frame, metres) is the
 * return of a beam from origin (the laser's position). Cells along each beam
 * lose miss_dec (except the clear_margin cells before the return), the cell of
 * each return gains hit_inc; all misses of a scan are applied before its hits.
 * Non-finite points are skipped. Returns RSM_OK or RSM_ERR_INVAL. */
int rsm_tmap_update(rsm_tmap_t *map, const rsm_point_t *origin, const rsm_point_t *points, size_t n);

/* The same write spread over several calls, so that a scan pays a bounded
 * share of it: begin stamps the map and remembers origin and n (RSM_ERR_INVAL
 * as above, or while a write is in progress); each run continues it over the
 * same points (unchanged by the caller until the write ends) and returns 1
 * while work remains, 0 once the write is complete. Levels go one after the
 * other, the finest first (wall_level first with the wall rule on); within
 * a level a run takes consecutive beams until they have cost budget cells
 * (beam steps; at least one beam) and then writes their returns, so the
 * misses-before-hits rule holds per sector of beams, and no level ever
 * reads with its beams cleared but its returns not yet written. Budget 0
 * runs to the end in exactly rsm_tmap_update's order. Reads see the map as
 * far as it is written. */
int rsm_tmap_write_begin(rsm_tmap_t *map, const rsm_point_t *origin, const rsm_point_t *points, size_t n);
int rsm_tmap_write_run(rsm_tmap_t *map, const rsm_point_t *points, uint32_t budget);

/* 1 while a write is in progress. */
int rsm_tmap_writing(const rsm_tmap_t *map);

/* Cell value (0..15) of cell (gx, gy) at a level; 0 where no tile is held. */
uint8_t rsm_tmap_value(const rsm_tmap_t *map, uint32_t level, int32_t gx, int32_t gy);

/* Cell side at a level, metres. */
float rsm_tmap_cell(const rsm_tmap_t *map, uint32_t level);

/* Tiles held at a level. */
uint32_t rsm_tmap_tiles(const rsm_tmap_t *map, uint32_t level);

/* Bounding box (cells, inclusive) of the tiles held at a level; 0 if none. */
int rsm_tmap_bounds(const rsm_tmap_t *map, uint32_t level, int32_t *gx0, int32_t *gy0, int32_t *gx1, int32_t *gy1);

/* Of the beams from the laser (origin, robot frame) to the points pts
 * (robot frame), every stride-th from the first, placed at pose: how many
 * meet a cell of at least value on a level, stopping margin + 1 cells short
 * of their return. A beam that passes through a wall the map holds says
 * the map, or the pose, is wrong there: a phantom return or a wall that
 * went, now and then; most beams of a scan, a robot placed where it is
 * not. *checked gets the beams looked at. Reads only. */
uint32_t rsm_tmap_beams_crossing(const rsm_tmap_t *map, uint32_t level, const rsm_pose_t *pose,
                                 const rsm_point_t *origin, const rsm_point_t *pts, size_t n, size_t stride,
                                 uint32_t value, uint32_t margin, uint32_t *checked);

/* Occupancy in [0, 1] of the cell holding world (x, y) on a level. */
float rsm_tmap_occupancy(const rsm_tmap_t *map, uint32_t level, float x, float y);

/* The least cell value a proof counts as a wall (the global search's, a
 * recovery's wall share): half of what one return adds (cfg.hit_inc),
 * rounded up (so at least 1, as hit_inc is). On the levels that share a
 * return's hit among the four cells around it by their bilinear weights, a
 * cell under that never had a return land nearer it than a neighbour, or
 * beams have worn it down to its last counts. Counted as walls, those
 * cells thicken every wall by a cell: more of the global search's boxes
 * pass, more places reach its bar and more searches are crowded
 * (docs/globalsearch.md, "Faint cells"). */
static inline uint32_t rsm_tmap_wall_value(const rsm_tmap_t *map)
{
    return ((uint32_t)map->cfg.hit_inc + 1u) / 2u;
}

/* A read position on one level of one map: remembers the last tiles found,
 * so that reads of nearby points (a scan's, in beam order) skip the index.
 * RSM_TMAP_CURSOR_WAYS^2 ways, one per tile column and row modulo that, so
 * that the 2 x 2 tiles around a read near a tile's edge are all held at
 * once, and a beam's walk finds the tiles the beam before it crossed.
 * Valid until the map is next written. */
typedef struct rsm_tmap_way {
    uint32_t key;    /* tile column (low half) and row (high half); RSM_TMAP_NO_KEY: empty */
    uint32_t slot;   /* RSM_TMAP_NONE: the tile is not held */
} rsm_tmap_way_t;

/* A key no tile has (tile coordinates stay within +-32000). */
#define RSM_TMAP_NO_KEY 0x80008000u

/* The tile of the last sample whose four cells lay in one tile (NULL or a
 * tile of zeros if none is held there) and that tile's first cell: the
 * next such sample in the same tile needs no lookup at all. Apart from the
 * ways, so that the map matcher's loop can keep its own in registers. */
typedef struct rsm_tmap_window {
    const rsm_tile_t *tile;
    int32_t bx;
    int32_t by;
} rsm_tmap_window_t;

typedef struct rsm_tmap_cursor {
    uint32_t level;
    rsm_tmap_way_t way[RSM_TMAP_CURSOR_WAYS * RSM_TMAP_CURSOR_WAYS];
    rsm_tmap_window_t win;
} rsm_tmap_cursor_t;

void rsm_tmap_cursor_init(rsm_tmap_cursor_t *c, uint32_t level);

/* rsm_tmap_occupancy and rsm_tmap_sample through a cursor (its level);
 * same results. */
float rsm_tmap_occupancy_at(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, float x, float y);
float rsm_tmap_sample_at(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, float x, float y, float *dx, float *dy);

/* Occupancy interpolated bilinearly between cell centres at world (x, y) on
 * a level, and its gradient per metre. Reentrant. */
float rsm_tmap_sample(const rsm_tmap_t *map, uint32_t level, float x, float y, float *dx, float *dy);

/* Tile coordinates stay within +-this (exclusive). */
#define RSM_TMAP_TILE_LIMIT 32000

/* Bits of rsm_tile_t.stamp that hold the write counter. */
#define RSM_TMAP_STAMP_MASK 0x1FFFFFFFu

/* Puts a tile read from storage (src/map/mapfile.c) into the next free slot,
 * as it is (its level in the stamp's top bits). RSM_OK; RSM_ERR_FORMAT for
 * a level beyond cfg.levels, coordinates out of range, a stamp newer than
 * map->stamp (set it first), or a tile already held at that place;
 * RSM_ERR_NOMEM with the pool full. Nothing is written on error. */
int rsm_tmap_restore(rsm_tmap_t *map, const rsm_tile_t *t);

/* Empties the map as rsm_tmap_init does, keeping its configuration and
 * store, and empties the store too. */
void rsm_tmap_reset(rsm_tmap_t *map);

/* Takes back from the map's store (rsm/tilestore.h; none: does nothing)
 * the tiles under pts (robot frame, metres) placed at pose, on every
 * level, and those within margin_m of each point (and two cells more: what
 * a read beside a cell touches), so that a match from about pose reads the
 * map the store holds. A tile comes back into a free slot, else the one a
 * return's hit would take (its tile let go into the store in turn),
 * stamped with the map's write counter, which a call that takes any back
 * ticks first. Returns the tiles taken back. Cursors on the map may hold
 * a slot it reused: forget them. */
uint32_t rsm_tmap_fetch(rsm_tmap_t *map, const rsm_pose_t *pose, const rsm_point_t *pts, size_t n,
                        float margin_m);

/* Takes back from the store the tiles of level_min and coarser (but the
 * coarsest, which a pool with a store never lets go) it holds under a tile
 * of the level above in the pool, top down, as rsm_tmap_fetch takes one (stamped newest, so that none of them
 * goes again to make room for the others), while the pool has slots: a
 * search of the whole map reads those levels everywhere, and tracking may
 * have let some go. At most `most` tiles a call: one that took `most` may
 * leave some for the next. Adds to *looked the places looked up (four a
 * tile of the levels above) and a sixteenth of the pool's tiles (made the
 * newest). Returns the tiles taken back; *full (may be NULL) 1 when it
 * stopped because every slot held a tile of those levels (some may be
 * left in the store), else 0. Cursors on the map may hold a slot it
 * reused: forget them. */
uint32_t rsm_tmap_take_back(rsm_tmap_t *map, uint32_t level_min, uint32_t most, uint32_t *looked, int *full);

/* Raises cell (gx, gy) of the cursor's level to at least v (at most 15),
 * taking a tile for it when none is held there (a free slot, else the one
 * a return's hit would take: never one written at the map's current write
 * counter) and stamping the tile with that counter, as a hit does (for
 * src/map/mapimport.c). RSM_OK, also when the cell already held v or more or v
 * is 0; RSM_ERR_NOMEM when no slot was left (counted in counters.dropped);
 * RSM_ERR_RANGE for a cell beyond the map's coordinate range or a level
 * the map lacks. Other cursors on the map may hold a slot this reused:
 * forget them. */
int rsm_tmap_raise(rsm_tmap_t *map, rsm_tmap_cursor_t *c, int32_t gx, int32_t gy, uint32_t v);

#ifdef __cplusplus
}
#endif

#endif /* RSM_TILEMAP_H */
