/* The persistent map: occupancy at several resolutions in a fixed pool of
 * tiles (docs/map.md has the design and the measurements behind it).
 *
 * Level l has cells of cell_m * 2^l. Space is cut into square tiles of
 * RSM_TMAP_TILE_SIDE x RSM_TMAP_TILE_SIDE cells; a tile takes a pool slot the
 * first time a laser return lands in it, so the map costs memory only where
 * there are walls, wherever the robot goes. Each cell is a 4-bit occupancy
 * value: a return adds hit_inc, a beam passing through subtracts miss_dec,
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

#ifdef __cplusplus
extern "C" {
#endif

#define RSM_TMAP_TILE_SIDE (1 << RSM_TMAP_TILE_LOG2)
#define RSM_TMAP_TILE_CELLS (RSM_TMAP_TILE_SIDE * RSM_TMAP_TILE_SIDE)
#define RSM_TMAP_TILE_BYTES (RSM_TMAP_TILE_CELLS / 2)
#define RSM_TMAP_HASH (1 << RSM_TMAP_HASH_LOG2)
#define RSM_TMAP_NONE 0xFFFFu
#define RSM_TMAP_MAX_VALUE 15u
#define RSM_TMAP_ECHO_BYTES ((1u << RSM_TMAP_ECHO_LOG2) / 8u)

typedef struct rsm_tile {
    int16_t tx;                       /* tile column and row at its level */
    int16_t ty;
    uint32_t stamp;                   /* update that last wrote a return into it (bits 0-28); bit 29
                                       * set once a cell reached saturation; level in bits 30-31 */
    uint8_t cell[RSM_TMAP_TILE_BYTES];  /* two 4-bit cells per byte, row-major */
} rsm_tile_t;

typedef struct rsm_tmap_config {
    float cell_m;          /* finest cell side, metres; default RSM_TMAP_CELL_M (0.05) */
    uint8_t levels;        /* resolutions in use, 1..RSM_TMAP_LEVELS; default RSM_TMAP_LEVELS */
    uint8_t hit_inc;       /* added by a return; default 4 */
    uint8_t miss_dec;      /* taken by a beam passing through; default 1 */
    uint8_t saturation;    /* value read as fully occupied; default 8 */
    uint8_t clear_margin;  /* cells before a return that its beam does not clear; default 1 */
    uint8_t splat_from;    /* on this level and coarser ones a return's increment is shared
                            * among the four cells around it by bilinear weights, so that a
                            * wall reads where it is, not at a cell centre up to half a
                            * (coarse) cell away; finer levels give it all to the return's
                            * cell, which keeps walls one cell thick. Default 1 */
    uint8_t age_shift;     /* when the pool is full, a tile's age counts 2^-(age_shift * level):
                            * 2 keeps a coarse tile as long as the fine ones covering the same
                            * area. Default 2 */
    uint8_t unconfirmed_shift;  /* ... and 2^unconfirmed_shift times more while none of its cells
                            * has reached saturation (a stray return, most likely a phantom,
                            * goes before the places seen minutes ago), at most 16. Default 8 */
    uint8_t wall_level;    /* level that judges whether a beam crossed a wall; default 1 */
    uint8_t wall_value;    /* a cell at or above this on wall_level is a wall: a return whose
                            * beam crossed one, and that does not itself land on a wall, is
                            * not written; 0 = off. Default 0 (off; 8 is the value measured
                            * in docs/map.md) */
    uint8_t wall_echo;     /* 1: a return behind a wall is written all the same if the previous
                            * write had a return within one wall_level cell of it (its echo),
                            * or it lands within one cell of a saturated one: a phantom is
                            * random and comes once, a surface seen through a doorway or
                            * along a grazed wall comes again from the next pose. Default 0 */
} rsm_tmap_config_t;

rsm_tmap_config_t rsm_tmap_config_default(void);

typedef struct rsm_tmap_counters {
    uint32_t updates;       /* scans written */
    uint32_t allocated;     /* tiles taken from free slots */
    uint32_t evicted;       /* tiles whose slot was reused for another */
    uint32_t freed;         /* tiles given back when beams had cleared every cell */
    uint32_t behind;        /* returns not written: their beam crossed a wall (and, with
                             * wall_echo, the last write saw nothing there) */
    uint32_t dropped;       /* returns lost because every slot was in use by the update */
    uint32_t outside;       /* returns beyond the tile coordinate range */
} rsm_tmap_counters_t;

typedef struct rsm_tmap {
    rsm_tmap_config_t cfg;             /* copied at init */
    float occ[RSM_TMAP_MAX_VALUE + 1u];  /* occupancy in [0, 1] of each cell value */
    float inv_cell[RSM_TMAP_LEVELS];   /* 1 / cell side of each level */
    uint32_t stamp;                    /* update counter (29 bits used) */
    uint16_t used;                     /* slots in use */
    uint16_t level_used[RSM_TMAP_LEVELS];  /* of those, per level */
    uint16_t hash[RSM_TMAP_HASH];      /* slot of a key, linear probing; RSM_TMAP_NONE empty */
    rsm_tile_t tile[RSM_TMAP_TILES];
    uint8_t echo[RSM_TMAP_ECHO_BYTES];  /* hashed wall_level cells of the last write's returns */
    rsm_tmap_counters_t counters;
} rsm_tmap_t;

/* Empties the map. RSM_ERR_INVAL for a bad config (cell not positive,
 * levels out of range, zero increments, saturation beyond 15). */
int rsm_tmap_init(rsm_tmap_t *map, const rsm_tmap_config_t *cfg);

/* Writes one scan into every level: points[k] (world frame, metres) is the
 * return of a beam from origin (the laser's position). Cells along each beam
 * lose miss_dec (except the clear_margin cells before the return), the cell of
 * each return gains hit_inc; all misses of a scan are applied before its hits.
 * Non-finite points are skipped. Returns RSM_OK or RSM_ERR_INVAL. */
int rsm_tmap_update(rsm_tmap_t *map, const rsm_point_t *origin, const rsm_point_t *points, size_t n);

/* Cell value (0..15) of cell (gx, gy) at a level; 0 where no tile is held. */
uint8_t rsm_tmap_value(const rsm_tmap_t *map, uint32_t level, int32_t gx, int32_t gy);

/* Cell side at a level, metres. */
float rsm_tmap_cell(const rsm_tmap_t *map, uint32_t level);

/* Tiles held at a level. */
uint32_t rsm_tmap_tiles(const rsm_tmap_t *map, uint32_t level);

/* Bounding box (cells, inclusive) of the tiles held at a level; 0 if none. */
int rsm_tmap_bounds(const rsm_tmap_t *map, uint32_t level, int32_t *gx0, int32_t *gy0, int32_t *gx1, int32_t *gy1);

/* Occupancy in [0, 1] of the cell holding world (x, y) on a level. */
float rsm_tmap_occupancy(const rsm_tmap_t *map, uint32_t level, float x, float y);

/* A read position on one level of one map: remembers the last tiles found,
 * so that reads of nearby points (a scan's, in beam order) skip the index.
 * Four ways, one per parity of the tile's column and row, so that the 2 x 2
 * tiles around a read near a tile's edge are all held at once. Valid until
 * the map is next written. */
typedef struct rsm_tmap_way {
    uint32_t key;    /* tile column (low half) and row (high half); RSM_TMAP_NO_KEY: empty */
    uint32_t slot;   /* RSM_TMAP_NONE: the tile is not held */
} rsm_tmap_way_t;

/* A key no tile has (tile coordinates stay within +-32000). */
#define RSM_TMAP_NO_KEY 0x80008000u

typedef struct rsm_tmap_cursor {
    uint32_t level;
    rsm_tmap_way_t way[4];
} rsm_tmap_cursor_t;

void rsm_tmap_cursor_init(rsm_tmap_cursor_t *c, uint32_t level);

/* rsm_tmap_occupancy and rsm_tmap_sample through a cursor (its level);
 * same results. */
float rsm_tmap_occupancy_at(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, float x, float y);
float rsm_tmap_sample_at(const rsm_tmap_t *map, rsm_tmap_cursor_t *c, float x, float y, float *dx, float *dy);

/* Occupancy interpolated bilinearly between cell centres at world (x, y) on
 * a level, and its gradient per metre. Reentrant. */
float rsm_tmap_sample(const rsm_tmap_t *map, uint32_t level, float x, float y, float *dx, float *dy);

#ifdef __cplusplus
}
#endif

#endif /* RSM_TILEMAP_H */
