/* The global search: where in the whole persistent map does a scan fit,
 * over every heading, with no prior (rsm_localizer_global; a robot
 * switched on somewhere in a known building, or carried).
 *
 * Branch and bound (docs/globalsearch.md). A pose's score is the occupancy
 * summed under the scan's points, each read at its cell of the second
 * coarsest level (0.2 m by default: the coarsest is too full to tell places
 * apart). The positions are that level's cells; the headings are spaced so
 * that the scan's far points move RSM_GLOBAL_HEADING_CELLS cells from one to
 * the next (rsm/config.h), and only those at which the scan's wall
 * directions agree with the map's are searched, the best agreeing first. For
 * one heading, a box of 2^h x 2^h cells of positions (a leaf, h = 0, is one
 * cell: positions anywhere in it) scores at most the number of points whose
 * window of 2^h + 1 cells a side holds a wall cell (at least half of what
 * one return adds: fainter cells count as free to the search): one bit a
 * point, read from a bit grid per box size whose blocks bound those windows
 * (built from the map's tiles within the scan budget, laid out to fit the
 * memory the caller lends, kept for the next search while the map is
 * unchanged). Large boxes read a quarter or half of the points, the others
 * counted as on a wall. A leaf's score is exact: each point's occupancy at
 * the largest cell value in its window of two cells a side, read from the
 * map, where that is a wall cell; the four leaves of a box share each
 * point's 3 x 3 window. Boxes are split depth first, the best
 * child first, and a box whose bound cannot reach the bar is dropped; a
 * point sum that can no longer reach it stops early, and the point that
 * ended it is read earlier from then on. The search keeps the
 * RSM_GLOBAL_CANDIDATES best distinct leaves, ranked by their fit at the
 * leaf's centre; the localizer then proves them (src/localizer/localizer.c,
 * prove_one, prove_verdict, prove_win).
 *
 * The work is spread over scans: rsm_global_run stops after a budget of
 * work and resumes where it stopped. Work is counted in units of about
 * the M4 instructions a bound grid's block read costs (about 18 at -O2):
 * each step counts what it was measured to cost (RSM_GLOBAL_*_WORK), so
 * that a budget bounds the instructions of a scan (docs/globalsearch.md,
 * "What a scan costs on the M4"). Everything lives in rsm_global_t
 * (include/rsm/localizer_parts.h) and the grid memory the caller lends;
 * no heap. */
#ifndef RSM_GLOBALSEARCH_H
#define RSM_GLOBALSEARCH_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/geom.h"
#include "rsm/localizer_parts.h"
#include "map/tilemap.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What the search's steps count, in units of a bound grid's block read,
 * from their M4 instructions (-O2, QEMU mps2-an386, regressed over the
 * scans of global searches on the Intel and ACES maps: a block read about
 * 18, a split's four children bounded 350 beside their reads, a leaf's
 * point 690, a kept leaf's point fitted 280, a heading begun 3 300, a
 * cell of the grids' build 50). */
#define RSM_GLOBAL_SPLIT_WORK 20u
#define RSM_GLOBAL_LEAF_WORK 38u
#define RSM_GLOBAL_FIT_WORK 15u
#define RSM_GLOBAL_HEADING_WORK 185u
#define RSM_GLOBAL_BUILD_WORK 3u
/* The most one step of rsm_global_run adds past its budget: a heading
 * begun and the four leaves of a box bounded. */
#define RSM_GLOBAL_STEP_WORK                                                                                           \
    (RSM_GLOBAL_HEADING_WORK + RSM_GLOBAL_SPLIT_WORK + RSM_GLOBAL_LEAF_WORK * (uint32_t)RSM_GLOBAL_POINTS)

/* rsm_global_t.phase */
#define RSM_GLOBAL_IDLE 0u
#define RSM_GLOBAL_PENDING 1u  /* the next usable scan begins it */
#define RSM_GLOBAL_RUNNING 2u
#define RSM_GLOBAL_PROVING 3u  /* done: the next usable scan tests what it kept */

/* Whether map can be searched: RSM_OK; RSM_ERR_DEGENERATE when the level
 * the search scores on holds nothing; RSM_ERR_NOMEM when it is too wide for
 * the bound grids (more than 2^RSM_GLOBAL_MAX_H cells of that level a side,
 * 13 km with the defaults, or more than grid_bytes of grid memory hold
 * with blocks 2^RSM_GLOBAL_MAX_BASE_H cells apart). */
int rsm_global_check(const rsm_tmap_t *map, size_t grid_bytes);

/* Takes back from map's store (rsm/tilestore.h) the tiles of the levels a
 * search reads, the level it scores on and the one finer that gives the
 * map's directions (rsm_tmap_take_back): tracking in a map larger than the
 * pool lets some of them go, and a search does not fetch. At most a
 * quarter of budget's worth of tiles a call (0: all); *more is 1 when
 * some may be left for the next, -1 when the pool had no slot left for
 * them (some stay in the store), 0 when they all came back. Returns the
 * work it counts: 10 a place
 * looked up (a hash probe in the pool and one in the store), 40 a tile
 * taken back. */
uint32_t rsm_global_take_back(rsm_tmap_t *map, uint32_t budget, int *more);

/* Builds the bound grids and the map's wall directions over the whole of
 * map into g and grid (grid_bytes of it), at once, and marks them
 * cached: the next rsm_global_begin on the same g and grid, with the map
 * unchanged, reads none of it (a map load does this: nothing else runs
 * then, while a search pays for the build out of its scans' budget). The
 * reads it took (as rsm_global_run counts them) are added to *used (may
 * be NULL). Returns as rsm_global_check, with g and grid untouched on an
 * error. */
int rsm_global_prepare(rsm_global_t *g, uint8_t *grid, size_t grid_bytes, const rsm_tmap_t *map, uint32_t *used);

/* Whether a write on map may keep the grids and directions in g (and its
 * grid memory) standing for the next search (rsm_global_keep): they were
 * built and every write since was kept. */
int rsm_global_can_keep(const rsm_global_t *g, const rsm_tmap_t *map);

/* Keeps the grids standing through a write of the points pts[0..n) (world
 * frame) begun on map (rsm_tmap_write_begin) when rsm_global_can_keep said
 * so before it: sets every block whose windows hold a cell of the search
 * level a hit may raise, and counts the write as in the grids. A block set
 * stays set when a write lowers cells (a bound only looser), and the
 * map's wall directions stay as built (they order the headings searched;
 * a building's walls keep their directions). The tiles the write begins
 * or ends are told apart from others (rsm_tmap_t.churn): with a store,
 * tiles of the levels read come and go while tracking, and the search
 * takes them back before it begins; a tile from elsewhere, or a hit
 * beyond the grids' box, still has the next search build them again. */
void rsm_global_keep(rsm_global_t *g, uint8_t *grid, const rsm_tmap_t *map, const rsm_point_t *pts, size_t n);

/* The share of kept points a search in map asks for (rsm_global_begin's
 * min_share) after `unproven` searches in a row that proved nothing: 0.97
 * for the first RSM_GLOBAL_FIRST_SEARCHES (a box whose window misses a
 * single point is dropped), then 0.95, 0.90, ... down to min_share
 * (global_min_share), each bar below the first for
 * RSM_GLOBAL_BAR_SEARCHES searches. A search near the estimate
 * (radius_m > 0; 0: the whole map) searches each window at 0.97 then 0.95
 * before it doubles (rsm_global_radius), and the bar falls further only
 * once the window holds the whole map. */
float rsm_global_share(const rsm_tmap_t *map, float radius_m, uint32_t unproven, float min_share);

/* Whether the search just run was crowded: it turned away at least as
 * many leaves that reached its bar outside its kept poses' basins as it
 * keeps (g->unkept >= RSM_GLOBAL_CANDIDATES), so its proof weighs only a
 * few of the places and one it never weighed may fit better. */
int rsm_global_crowded(const rsm_global_t *g);

/* The share of the map's own fit a winner of search g must reach:
 * min_fit (global_min_fit), or crowded_fit (global_crowded_fit) after a
 * crowded search (rsm_global_crowded). */
float rsm_global_fit_share(const rsm_global_t *g, float min_fit, float crowded_fit);

/* The window's radius for a search near the estimate begun with radius_m,
 * after `unproven` searches in a row that proved nothing: doubled every
 * second one (rsm_global_share). */
float rsm_global_radius(float radius_m, uint32_t unproven);

/* Starts a search for the readings pts (robot frame, in beam order; up to
 * RSM_GLOBAL_POINTS of them, taken evenly, are kept, and all give the
 * scan's wall directions) over map, whose estimate from odometry at this
 * scan is *at. grid (grid_bytes of it, at least RSM_GLOBAL_GRID_BYTES;
 * more lays the grids' blocks closer, for tighter bounds) holds the bound
 * grids until the search ends: the caller's, untouched by anything else
 * meanwhile.
 * The grids and the map's wall directions a search built on g are kept for
 * the next search on g while g->cached is set and the map's write counter,
 * tiles and box are as they were: the caller passes the same grid, and
 * clears g->cached when it writes the map or the grid memory in between.
 * A box is searched on only while it may score min_share of the kept
 * points' count (and 0.8 of the best so far); a leaf is kept down to 0.05
 * of the count below that. The proof's readings (twice as many, evenly)
 * go to g->pts[0 .. g->nseen), *at to g->seen_at. Returns RSM_OK, or
 * RSM_ERR_DEGENERATE when the map's coarsest level is empty or fewer than
 * 8 readings are given, or RSM_ERR_NOMEM as rsm_global_check says. */
int rsm_global_begin(rsm_global_t *g, uint8_t *grid, size_t grid_bytes, const rsm_tmap_t *map,
                     const rsm_point_t *pts, size_t n, const rsm_pose_t *at, float min_share);

/* Narrows a search begun (rsm_global_begin, before any rsm_global_run) to
 * the positions within radius_m of (x, y), in a square of a power of two
 * cells; every heading still. A window as wide as the map, or one out of
 * the map's range, leaves the whole map. Grids still to be built are laid
 * out over what the window's points can reach only (grid: as given to
 * rsm_global_begin). */
void rsm_global_window(rsm_global_t *g, uint8_t *grid, const rsm_tmap_t *map, float x, float y, float radius_m);

/* Goes on with the search for about budget work (0 = to the end): bound
 * grid blocks, leaves' points, the grids' build (a tile's cells, two a
 * direction tile's cell, each RSM_GLOBAL_BUILD_WORK), headings begun and
 * kept leaves' fits, each as RSM_GLOBAL_*_WORK says. It stops before the
 * next step once budget is reached, so a run does at most
 * RSM_GLOBAL_STEP_WORK beyond it. Returns 1 while work remains, 0 once
 * every heading is done (g->cand[0 .. g->found) then hold the kept poses,
 * best ranked first). Adds the work to g->work and to *used (may be
 * NULL). */
int rsm_global_run(rsm_global_t *g, uint8_t *grid, const rsm_tmap_t *map, uint32_t budget, uint32_t *used);

/* The verdict of a proof round, on the kept poses' fits with the kept
 * scan (g->hit, where their descents ended g->end): 1 with *win the best,
 * when it fits at least min_fit, in this round and over all the rounds
 * (its fits multiplied over them, as a mean, where it fitted in each
 * round before), and beats by margin (a share) every rival
 * beyond doubt of it (doubt_m or doubt_rad apart) on its fits multiplied
 * over all the rounds (g->rounds before this one, summed by
 * rsm_global_add_round) against each rival's (where both fitted in each
 * round before), and on this round's fits alone too unless it fitted
 * best in every round before, each above the bar (after a crowded search
 * this round's alone are always asked too); 0 in doubt (a rival too close,
 * or the best a little under min_fit: within a tenth); -1 when nothing
 * fits (or nothing was kept). */
int rsm_global_verdict(const rsm_global_t *g, float min_fit, float margin, float doubt_m, float doubt_rad,
                       uint32_t *win);

/* The waiting winner (g->pending_pose) carried by odometry from the
 * estimate then (g->pending_at) to the estimate at. */
rsm_pose_t rsm_global_pending_carried(const rsm_global_t *g, const rsm_pose_t *at);

/* Whether a proven winner at pose may be taken, at estimate `at` (which
 * odometry carries). A crowded search's proof (rsm_global_crowded)
 * weighed a few of the places that reached its bar, and one it never
 * weighed may fit better: its winner is taken only when a later search proves the
 * same place too (g->pending_pose, carried from g->pending_at to at,
 * within reach_m and reach_rad: odometry's drift over that motion), and
 * else becomes the pending winner, in place of any before. An uncrowded
 * search weighed every place that reached its bar: its winner is taken.
 * 1: taken (nothing pending after); 0: waits. */
int rsm_global_take(rsm_global_t *g, const rsm_pose_t *pose, const rsm_pose_t *at, float reach_m, float reach_rad);

/* Puts pose (in the map, at the scan searched) among the kept poses for
 * the proof, in place of the one ranked last, unless a kept pose is
 * within two lattice steps and two heading steps of it (its basin, kept
 * already). For a pose a search before proved: weighed again against
 * this search's own. */
void rsm_global_weigh_also(rsm_global_t *g, const rsm_tmap_t *map, const rsm_pose_t *pose);

/* Adds a round left in doubt to the sums the next verdicts read (the
 * caller counts g->rounds after it); a round whose best fitted under
 * min_fit (the verdict's) leaves no pose that led every round. */
void rsm_global_add_round(rsm_global_t *g, float min_fit);

#ifdef __cplusplus
}
#endif

#endif /* RSM_GLOBALSEARCH_H */
