/* The parts of the localizer's state and of its config, laid out here so
 * that the caller can own an rsm_localizer_t (statically or on the stack)
 * and tune each stage through rsm_localizer_config_t.
 *
 * Public: the *_config_t structs, which rsm_localizer_config_default fills
 * and the caller may change before rsm_localizer_init. Layout only: the
 * state structs (grid image, key points, RANSAC, ICP, EKF, window map,
 * persistent map); read them through the rsm_localizer_* accessors, not
 * directly, since their members change between versions. The functions on
 * these types are the core's own and not installed (src/core/grid.h,
 * src/map/tilemap.h, ...). */
#ifndef RSM_LOCALIZER_PARTS_H
#define RSM_LOCALIZER_PARTS_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- grid.h ------------------------------------------------------------------ */

/* How a reading near a cell border is treated (docs/reference/method.md, step 2). */
typedef enum rsm_grid_rule {
    RSM_GRID_SIGMA_INSIDE = 0, /* paper: mark only if the point is >= sigma inside its cell */
    RSM_GRID_SIGMA_TOUCH = 1,  /* mark every cell the sigma circle touches (1 to 4) */
    RSM_GRID_NEAREST = 2       /* mark the cell the point falls in */
} rsm_grid_rule_t;

typedef struct rsm_grid_config {
    float cell_m;          /* a: cell side, metres; default 0.05 (the paper's 50 mm) */
    float sigma_m;         /* laser range noise, metres; default 0.005 (the paper's 5 mm) */
    rsm_grid_rule_t rule;  /* default RSM_GRID_SIGMA_TOUCH */
} rsm_grid_config_t;

/* The window: global cell of its lower-left corner. */
typedef struct rsm_window {
    int32_t ox;
    int32_t oy;
} rsm_window_t;

/* A cell's global index. */
typedef struct rsm_cell {
    int32_t gx;
    int32_t gy;
} rsm_cell_t;

#define RSM_BITMAP_WORDS (RSM_MAP_CELLS / 32)
/* A binary image over the window, with the list of its set cells so that
 * work (and clearing) costs grow with occupied cells, not with image area.
 * RAM: RSM_MAP_CELLS / 8 + 4 * RSM_IMAGE_MAX_CELLS bytes. */
typedef struct rsm_image {
    uint32_t bits[RSM_BITMAP_WORDS];
    uint32_t cells[RSM_IMAGE_MAX_CELLS]; /* toroidal indices of the set cells */
    size_t count;          /* set cells listed in cells[] */
    uint32_t outside;      /* cells (or non-finite points) that fell outside the window since the last clear */
    uint32_t overflow;     /* cells not listed because cells[] was full */
} rsm_image_t;

/* ---- harris.h ---------------------------------------------------------------- */

typedef struct rsm_harris_config {
    int32_t k_num;         /* k numerator; default 1 */
    int32_t k_den;         /* k denominator; default 25 (k = 0.04) */
    int32_t min_response;  /* R (scaled by k_den) must exceed this; default 1 */
    int32_t nms_radius;    /* suppression radius in cells; default 1 (3x3) */
} rsm_harris_config_t;

typedef struct rsm_keypoint {
    int32_t gx;        /* global cell */
    int32_t gy;
    int32_t response;  /* scaled Harris response */
} rsm_keypoint_t;

/* Caller-owned scratch for one detection. RAM: 8 * RSM_MAX_CANDIDATES. */
typedef struct rsm_harris_work {
    int32_t response[RSM_MAX_CANDIDATES];
    uint32_t order[RSM_MAX_CANDIDATES];
} rsm_harris_work_t;

/* ---- match.h ----------------------------------------------------------------- */

typedef struct rsm_match {
    uint16_t ref; /* index into the reference key points */
    uint16_t cur; /* index into the current key points */
} rsm_match_t;

/* ---- ransac.h ---------------------------------------------------------------- */

typedef struct rsm_ransac_config {
    float inlier_tol_m;      /* support distance; default 0.075 (1.5 cells) */
    float length_tol_m;      /* early length test | |A| - |C| |; default 0.1 */
    float min_pair_sep_m;    /* reject samples whose points are closer; default 0.2 */
    float confidence;        /* delta of eq. 16; default 0.99 */
    uint32_t max_iterations; /* hypothesis budget; default 300 */
    uint32_t min_support;    /* fewer inliers is a failure; default 5 */
    uint32_t seed;           /* PRNG seed (non-zero); default 0x2545F491 */
} rsm_ransac_config_t;

typedef struct rsm_ransac {
    const rsm_ransac_config_t *cfg;  /* kept by pointer */
    uint32_t rng;                    /* xorshift32 state */
    uint8_t inlier[RSM_MAX_MATCHES]; /* inliers of the returned transform */
    rsm_point_t src[RSM_MAX_MATCHES];
    rsm_point_t dst[RSM_MAX_MATCHES];
} rsm_ransac_t;

/* ---- icp.h ------------------------------------------------------------------- */

typedef struct rsm_icp_config {
    uint16_t max_iterations;     /* default 30 (the paper's comparison) */
    float max_pair_dist_m;       /* pairs farther apart are ignored; default 1.0 */
    float converged_m;           /* stop when the step moves less; default 1e-4 */
    float converged_rad;         /* and turns less; default 1e-4 */
    uint16_t min_pairs;          /* fewer pairs -> RSM_ERR_DEGENERATE; default 10 */
} rsm_icp_config_t;

typedef struct rsm_icp {
    const rsm_icp_config_t *cfg;              /* kept by pointer */
    rsm_point_t ref[RSM_ICP_MAX_POINTS];      /* world frame */
    size_t ref_count;
    rsm_point_t work[RSM_ICP_MAX_POINTS];     /* scratch: reference partner of each
                                               * current point (NaN: none) */
} rsm_icp_t;

/* ---- ekf.h ------------------------------------------------------------------- */

typedef struct rsm_ekf {
    rsm_pose_t x;     /* state estimate */
    float p[9];       /* covariance, row-major, symmetric positive definite */
    uint32_t predicts;
    uint32_t updates;
    uint32_t rejected; /* updates refused: non-finite input, singular S, gate
                        * exceeded or non-finite result */
    uint32_t lost;     /* predictions whose covariance passed RSM_EKF_LOST_VAR_XY_M2
                        * or RSM_EKF_LOST_VAR_THETA (reset to a diagonal, see below) */
} rsm_ekf_t;

/* ---- map.h ------------------------------------------------------------------- */

typedef struct rsm_map {
    rsm_window_t win;              /* current window */
    float cell_m;                  /* a, metres */
    uint8_t hits[RSM_MAP_CELLS];   /* saturating hit counters, toroidal */
    uint32_t scrolls;              /* window moves so far */
    uint32_t outside;              /* points dropped because they fell outside */
} rsm_map_t;

/* ---- tilemap.h --------------------------------------------------------------- */

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
    uint16_t write_cells;  /* a write runs over the next scans, about this many cells (beam
                            * steps and returns) per scan, sector by sector of beams and
                            * level by level (finest first), so that no scan pays for a
                            * whole write; 0 = each write at once. Default 4096 */
} rsm_tmap_config_t;

typedef struct rsm_tmap_counters {
    uint32_t updates;       /* scans written */
    uint32_t allocated;     /* tiles taken from free slots */
    uint32_t evicted;       /* tiles whose slot was reused for another */
    uint32_t freed;         /* tiles given back when beams had cleared every cell */
    uint32_t behind;        /* returns not written: their beam crossed a wall (and, with
                             * wall_echo, the last write saw nothing there) */
    uint32_t dropped;       /* returns lost because every slot was in use by the update */
    uint32_t outside;       /* returns beyond the tile coordinate range */
    uint32_t stored;        /* tiles the pool let go into the store (rsm/tilestore.h) */
    uint32_t fetched;       /* tiles taken back from the store */
    uint32_t unstored;      /* tiles let go that the store refused (full): forgotten */
} rsm_tmap_counters_t;

/* The write in progress: the level it is on (in write order: the finest
 * first, or wall_level with the wall rule) and the first beam of that
 * level's next sector; the returns themselves stay with the caller until
 * the write ends. */
typedef struct rsm_tmap_job {
    rsm_point_t origin;                /* the laser's position for the write */
    uint32_t n;                        /* returns of the write; 0: none in progress */
    uint32_t next;                     /* first beam of the next sector */
    uint32_t pass;                     /* index of the level in write order */
    uint8_t behind[(RSM_MAX_BEAMS + 7) / 8];  /* returns not written (wall_value) */
    uint8_t lone[(RSM_MAX_BEAMS + 7) / 8];    /* returns no echo confirmed (wall_echo) */
} rsm_tmap_job_t;

struct rsm_tile_store;

typedef struct rsm_tmap {
    rsm_tmap_config_t cfg;             /* copied at init */
    const struct rsm_tile_store *store;  /* where let-go tiles go (rsm/tilestore.h); NULL: none */
    float occ[RSM_TMAP_MAX_VALUE + 1u];  /* occupancy in [0, 1] of each cell value */
    float inv_cell[RSM_TMAP_LEVELS];   /* 1 / cell side of each level */
    uint32_t stamp;                    /* update counter (29 bits used) */
    uint16_t used;                     /* slots in use */
    uint16_t level_used[RSM_TMAP_LEVELS];  /* of those, per level */
    uint8_t write_hit;                 /* what a return adds on writes: cfg.hit_inc, or a loaded
                                        * map's rate (rsm_localizer_config_t.map_loaded_hit) */
    /* On each level, the tiles writes began (empty, not from the store)
     * less those that ended (freed, or let go with no store to keep them),
     * and the same sum of their places mixed (rsm_tmap_place_sig): a
     * global search's grids kept through writes tell by them the tiles of
     * those writes from tiles come from elsewhere (globalsearch.c). */
    uint32_t churn[RSM_TMAP_LEVELS];
    uint32_t churn_sig[RSM_TMAP_LEVELS];
    uint16_t hash[RSM_TMAP_HASH];      /* slot of a key, linear probing; RSM_TMAP_NONE empty */
    rsm_tile_t tile[RSM_TMAP_TILES];
    uint8_t echo[RSM_TMAP_ECHO_BYTES];  /* hashed wall_level cells of the last write's returns */
    rsm_tmap_job_t job;
    /* The oldest tiles the last search of the full pool found (slot, and
     * its stamp then: a tile written or replaced since no longer matches),
     * best first, for the evictions of the same write: within a write no
     * age changes, so the next valid one is what a new search would find. */
    uint16_t victim_slot[RSM_TMAP_VICTIMS];
    uint32_t victim_stamp[RSM_TMAP_VICTIMS];
    uint32_t victims;                  /* entries found; 0: search again (a new write, a slot
                                        * moved) */
    uint32_t victim_next;              /* the next one to try */
    rsm_tmap_counters_t counters;
} rsm_tmap_t;

/* ---- globalsearch.h ---------------------------------------------------------- */

/* Bytes of the bound grids: at least those of the scan a map write reads
 * (RSM_MAX_BEAMS points of 8 bytes), whose memory they share, or more
 * with a larger RSM_GLOBAL_SIDE. */
#define RSM_GLOBAL_GRID_BYTES_SIDE ((RSM_GLOBAL_SIDE * RSM_GLOBAL_SIDE * 4) / 3 + 4 * RSM_GLOBAL_SIDE + 32)
#define RSM_GLOBAL_GRID_BYTES                                                                                      \
    (RSM_GLOBAL_GRID_BYTES_SIDE > RSM_MAX_BEAMS * 8 ? RSM_GLOBAL_GRID_BYTES_SIDE : RSM_MAX_BEAMS * 8)
/* Memory lent to the search (rsm_localizer_set_search_memory) beyond this
 * is not used: the grids' bit indices stay 32-bit. */
#define RSM_GLOBAL_MAX_GRID_BYTES (1ul << 24)
/* What rsm-nav and the map-in-flash images lend (rsm/config.h says why):
 * 24576 bytes, or the shared bytes where those are more. A lend set by
 * hand must hold the grids too: rsm_localizer_set_search_memory refuses
 * less than the shared bytes (tests/config/check_asserts.cmake). */
#ifndef RSM_GLOBAL_LEND_BYTES
#define RSM_GLOBAL_LEND_BYTES (RSM_GLOBAL_GRID_BYTES > 24576 ? RSM_GLOBAL_GRID_BYTES : 24576)
#endif
RSM_STATIC_ASSERT(global_lend_holds_grids, RSM_GLOBAL_LEND_BYTES >= RSM_GLOBAL_GRID_BYTES);
/* Boxes of at most 2^RSM_GLOBAL_MAX_H positions a side (13 km with 0.2 m
 * cells): one bound grid per box size up to it. */
#define RSM_GLOBAL_MAX_H 16
/* The finest grid's blocks start at most 2^RSM_GLOBAL_MAX_BASE_H cells
 * apart (beyond: the map is too wide for the memory). */
#define RSM_GLOBAL_MAX_BASE_H 10
/* Boxes the depth-first search holds: three siblings waiting per level of
 * a descent from the root. */
#define RSM_GLOBAL_STACK (3 * RSM_GLOBAL_MAX_H + 4)
/* Wall directions over half a turn, in bins of 4 degrees: the scan's and
 * the map's, whose correlation tells which headings to search. */
#define RSM_GLOBAL_BINS 45
/* Headings at most. */
#define RSM_GLOBAL_MAX_HEADINGS 1024

typedef struct rsm_global_box {
    int32_t i;       /* first position of the box on the lattice of coarse cells */
    int32_t j;
    float bound;     /* the most any pose in it can score */
    uint32_t h;      /* the box is 2^h positions a side */
} rsm_global_box_t;

typedef struct rsm_global_candidate {
    rsm_pose_t pose; /* in the map, at the scan searched */
    float score;     /* coarse score: summed occupancy under its points, each the largest of
                      * the cells it may fall in (the search's bound at a leaf) */
    float fine;      /* how they are ranked: the occupancy summed under its points at the
                      * pose itself, interpolated */
} rsm_global_candidate_t;

typedef struct rsm_global {
    uint32_t phase;                /* idle, pending (next scan starts it), running, proving */
    uint32_t level;                /* the map level scored (cells of about 0.2 m) */
    float dir_scan[RSM_GLOBAL_BINS];  /* wall directions of the scan, of the map */
    float dir_map[RSM_GLOBAL_BINS];
    uint32_t dir_next;             /* the next tile slot whose walls join dir_map */
    float agree[RSM_GLOBAL_BINS];  /* how well the directions agree at each heading (mod half a
                                    * turn, best 1), the best within a bin either side */
    uint32_t pass;                 /* headings are searched in passes, best agreeing first */
    /* The searched scan's readings, robot frame: the first npts the search
     * reads, in the order it reads them (one that ends a box's bound moves
     * up one place); all nseen, evenly over the scan, the proof's (then
     * those of the scan a proof left in doubt begins again with). */
    rsm_point_t pts[2 * RSM_GLOBAL_POINTS];
    uint32_t npts;
    uint32_t nseen;
    rsm_pose_t seen_at;            /* the estimate at the scan of pts[0 .. nseen) */
    uint32_t grid_bytes;           /* the grid memory the layout below was made for */
    /* The bound grids (the caller's memory, grid_bytes of it), one
     * bit a block: grid h (boxes of 2^h positions a side, h >= 1) has
     * grid_nx[h] x grid_ny[h] blocks from bit grid_at[h]; block (a, b)
     * says whether any cell of the search level is nonzero in the
     * 2^h + 2^grid_e[h] cells a side from cell (ox - 2^h + a 2^grid_e[h],
     * oy - 2^h + b 2^grid_e[h]). */
    uint32_t grid_at[RSM_GLOBAL_MAX_H + 1];
    uint16_t grid_nx[RSM_GLOBAL_MAX_H + 1];
    uint16_t grid_ny[RSM_GLOBAL_MAX_H + 1];
    uint8_t grid_e[RSM_GLOBAL_MAX_H + 1];
    int32_t ox;                    /* the map's first cell on the search level */
    int32_t oy;
    uint32_t top_h;                /* the whole map: 2^top_h cells a side from (ox, oy) */
    uint32_t build_next;           /* the next block of grids 2 and up to build (bit index) */
    uint32_t build_end;            /* the grids' bits */
    /* The grids and dir_map, once built, hold for the next search while
     * the map is not written (the localizer clears cached when it writes
     * the map or the grids' memory, or replaces the map): the map's writes
     * (counters.updates: its stamp ticks with a store's fetches too), the
     * tiles of the levels read (their count and a signature of their
     * places) and box on the search level they were built from. */
    uint32_t cached;
    uint32_t cache_writes;
    uint32_t cache_tiles;
    uint32_t cache_sig;
    uint32_t cache_churn;          /* the map's churn of the levels read, and its sum, */
    uint32_t cache_churn_sig;      /* when the grids were built (rsm_global_keep) */
    int32_t cache_box[4];
    int32_t root_i;                /* the root box: 2^root_h positions a side from here */
    int32_t root_j;
    uint32_t root_h;
    float radius_m;                /* positions within this of the estimate; 0: the whole map */
    uint32_t heading;              /* the heading in progress, and how many there are */
    uint32_t headings;
    float step_rad;
    rsm_global_box_t stack[RSM_GLOBAL_STACK];
    uint32_t depth;
    rsm_global_candidate_t cand[RSM_GLOBAL_CANDIDATES];
    uint32_t found;
    uint32_t unkept;               /* leaves that reached the bar outside the kept poses' basins
                                    * when cand was full (a place may count more than once) */
    float floor_score;             /* a pose must score at least this to be kept */
    float best_score;              /* the best coarse score found */
    uint32_t give_up;              /* searches that may prove nothing before it ends unproven
                                    * (a search after a gap in the scans); 0: until one proves */
    uint32_t unproven;             /* searches in a row that proved nothing (each next one
                                    * keeps poses with a lower share of points on walls) */
    /* The proof, spread over scans: every kept pose descended with pts, to
     * end with fit hit; then the winner, carried to the scan at hand. */
    uint32_t proved;               /* kept poses descended so far (found + 1: the winner too) */
    uint32_t rounds;               /* proofs of the same kept poses that were left in doubt */
    uint32_t taken_back;           /* the levels read came back from the store whole ... */
    uint32_t back_stored;          /* ... when the map had let this many tiles go into it
                                    * (counters.stored): none let go since, none to take back
                                    * (cleared for another map or store) */
    /* A crowded search's winner waiting for a second search to prove it
     * too, and the estimate then (odometry carries it from there); valid
     * while pending is 1. */
    uint32_t pending;
    rsm_pose_t pending_pose;
    rsm_pose_t pending_at;
    float hit[RSM_GLOBAL_CANDIDATES];
    /* Over the rounds before this one: the sum of each kept pose's log fit,
     * and the pose that fitted best in every one of them (the views add
     * up: a place a little better than a look-alike from each of several
     * views is proven; RSM_GLOBAL_CANDIDATES: none led them all). */
    float log_hit[RSM_GLOBAL_CANDIDATES];
    uint32_t leader;
    rsm_pose_t end[RSM_GLOBAL_CANDIDATES];
    uint32_t work;                 /* cells and blocks read so far */
} rsm_global_t;

/* ---- mapmatch.h -------------------------------------------------------------- */

typedef struct rsm_mapmatch_config {
    uint8_t iterations;     /* Gauss-Newton steps per level at most; default 6 */
    float sigma;            /* std of one point's occupancy residual (unitless); smaller
                             * trusts the scan more against odometry; default 0.3 */
    float min_step_m;       /* a level has converged when a step is below this times its
                             * cell's multiple of the finest (and min_step_rad likewise);
                             * default 0.002 */
    float min_step_rad;     /* default 0.001 */
    float search_rad;       /* the heading fan: headings within +-search_rad of a position,
                             * search_step_rad apart, scored on the coarsest level; used by
                             * rsm_mapmatch_search and, with fan set, by rsm_mapmatch;
                             * default 0.1 */
    float search_step_rad;  /* spacing of those headings; default 0.02 (a point 5 m away
                             * moves a quarter of a 40 cm coarse cell) */
    uint8_t fan;            /* 1: rsm_mapmatch also descends from the fan's best heading
                             * and keeps the lower end; default 0 (the coarse levels reach
                             * ten degrees on their own; on the logs the fan cost time and
                             * gained nothing, docs/map.md) */
    float gate_d2;          /* refuse a result farther than this from the prediction
                             * ((x - x0)^T P0^-1 (x - x0)); 0 = off, the default: the prior
                             * is already part of the cost, and refusing scans lets the map
                             * and the estimate part ways (measured in docs/map.md) */
    float basin;            /* the descent starts on the coarsest level whose cell is at
                             * least basin times the prior's reach (its position std plus
                             * heading std times the scan's mean range): coarser cells
                             * only widen a basin the prediction does not need; 0 = always
                             * the coarsest */
    float unpin_lo;         /* a scan whose surfaces run nearly one way (a bare corridor)
                             * does not pin the position along them, yet the map's wall
                             * bands, shaped by the poses they were written from, pull
                             * it back there: below a spread (rsm_mapmatch_spread) of
                             * unpin_hi that pull is taken out in proportion, wholly
                             * below unpin_lo, and the prediction keeps that direction;
                             * defaults 0.02 and 0.06 (docs/map.md, "Bare corridors") */
    float unpin_hi;         /* 0 = off */
} rsm_mapmatch_config_t;
#ifdef __cplusplus
}
#endif

#endif /* RSM_LOCALIZER_PARTS_H */
