/* Scan-to-map matching against the persistent map (tilemap.h), coarse to
 * fine, with the odometry prediction as a prior.
 *
 * The pose x minimises
 *     sum_i (1 - M(x (+) p_i))^2 / sigma^2  +  (x - x0)^T P0^-1 (x - x0)
 * where M is a level's occupancy interpolated bilinearly (so the sum pulls
 * each point onto the nearest wall within about one cell of that level) and
 * (x0, P0) is the prediction. Gauss-Newton runs on the coarsest level first,
 * whose wide cells give a wide basin, then on each finer one. Because the
 * prior is part of the cost, a scan that pins only some directions (a
 * corridor pins the sideways position and the heading, not the position
 * along it) moves the estimate only in those, and the posterior covariance
 * (J^T J / sigma^2 + P0^-1)^-1 says so: this is an iterated EKF update with
 * the map as the measurement. Points far from any wall have no gradient and
 * no pull, so outliers and things not yet in the map are ignored.
 *
 * That holds for the map's walls as lines, not as written: how a wall's band
 * of cells looks along it depends on the poses it was written from, and in a
 * bare corridor those gradients pull the scan back towards them, scan after
 * scan. So a scan whose surfaces all run one way (rsm_mapmatch_spread) is
 * unpinned along them: that share of its pull is left out of every pass's
 * sums, and the prediction keeps that direction (docs/map.md, "Bare corridors").
 *
 * Optionally (fan) the descent also starts from the best of a fan of
 * headings around the prediction, scored on the coarsest level with the
 * prior's heading term, for odometry whose heading is far off after a fast
 * turn. */
#ifndef RSM_MAPMATCH_H
#define RSM_MAPMATCH_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/geom.h"
#include "rsm/localizer_parts.h"
#include "map/tilemap.h"

#ifdef __cplusplus
extern "C" {
#endif

rsm_mapmatch_config_t rsm_mapmatch_config_default(void);

/* RSM_OK if cfg is usable: iterations >= 1, sigma > 0, search_rad within
 * [0, 1] rad and at most 64 steps each side, no negative value. Else
 * RSM_ERR_INVAL. */
int rsm_mapmatch_check(const rsm_mapmatch_config_t *cfg);

/* What rsm_mapmatch leaves to the prediction: the fraction frac (0 to 1) of
 * the scan's pull along the world direction dir. */
typedef struct rsm_mapmatch_unpin {
    float dir[2];
    float frac;
} rsm_mapmatch_unpin_t;

typedef struct rsm_mapmatch_result {
    rsm_pose_t pose;        /* the estimate */
    float cov[9];           /* its covariance (posterior), row-major */
    float info[9];          /* the scan's information J^T J / sigma^2 at the finest level */
    float cost;             /* mean (1 - M)^2 over the points with a gradient, finest level */
    float hit;              /* mean M over all points at the finest level, in [0, 1] */
    uint32_t used;          /* points with a gradient at the finest level */
    uint32_t iterations;    /* steps taken, all levels */
    uint32_t passes;        /* passes over the points (each reads every point's cells on a
                             * level): what the match cost */
    uint32_t top;           /* the level the descent started on (cfg->basin) */
    float d2;               /* (x - x0)^T P0^-1 (x - x0): how far the scan moved the estimate */
} rsm_mapmatch_result_t;

/* Aligns the robot-frame points to the map with the prediction (x0, p0) as
 * prior. The descent starts at *start when it is given, else at the best
 * heading of the fan around x0. With unpin (may be NULL) that share of the
 * scan's pull along its direction is left out of every pass's sums and so
 * of the information (rsm_mapmatch_unpin_for). Returns RSM_OK (res filled),
 * RSM_ERR_DEGENERATE when the prior covariance cannot be inverted or fewer
 * than 3 points touch the map (res->pose = x0), RSM_ERR_INVAL for bad
 * arguments. Reentrant; the map is not changed. */
int rsm_mapmatch(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts, size_t n,
                 const rsm_pose_t *x0, const float p0[9], const rsm_pose_t *start,
                 const rsm_mapmatch_unpin_t *unpin, rsm_mapmatch_result_t *res);

/* Most candidates rsm_mapmatch_search returns. */
#define RSM_MAPMATCH_MAX_CANDIDATES 8u
/* Most points it scores (every stride-th of the scan). */
#define RSM_MAPMATCH_SEARCH_POINTS 64u
/* Most headings either side of the centre (the radius_rad limit). */
#define RSM_MAPMATCH_MAX_FAN 64

/* Exhaustive search on the coarsest level for the poses that best fit the
 * points: positions on that level's cell grid within +-radius_m of x0, each
 * with headings within +-radius_rad, cfg->search_step_rad apart; points
 * are subsampled to at most max_points (1 .. RSM_MAPMATCH_SEARCH_POINTS).
 * For recovery after a large odometry error (about (2r/cell)^2 x fan x
 * max_points cell reads). Writes the k (1..RSM_MAPMATCH_MAX_CANDIDATES)
 * lowest-cost poses to best[], lowest first, no two within one grid step
 * of each other (separate basins for a descent to start from). Returns how
 * many were written (1..k), or RSM_ERR_INVAL (radius negative or above 100
 * cells, radius_rad negative, above 1 or 64 steps, k or max_points out of
 * range). */
int rsm_mapmatch_search(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts, size_t n,
                        const rsm_pose_t *x0, float radius_m, float radius_rad, rsm_pose_t *best, size_t k,
                        size_t max_points);

/* The size of that search: headings -*fan .. *fan (each cfg->search_step_rad
 * apart) and *positions a heading. RSM_OK, or RSM_ERR_INVAL for the radii
 * rsm_mapmatch_search refuses. */
int rsm_mapmatch_search_size(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, float radius_m,
                             float radius_rad, int32_t *fan, uint32_t *positions);

/* Part of rsm_mapmatch_search: its headings from .. to - 1 (of -fan .. fan,
 * clamped), their candidates merged into the *found kept so far (0 at
 * first) in best, cost_of (their costs) and ij (2 a candidate: their
 * position on the grid), all k long, so that a search can be spread over
 * calls. Parts that cover the headings in order find what the whole search
 * finds. Returns *found, or RSM_ERR_INVAL as rsm_mapmatch_search. */
int rsm_mapmatch_search_part(const rsm_tmap_t *map, const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts,
                             size_t n, const rsm_pose_t *x0, float radius_m, float radius_rad, int32_t from,
                             int32_t to, rsm_pose_t *best, float *cost_of, int32_t *ij, size_t k, size_t *found,
                             size_t max_points);

/* The points' fit at pose without a descent: their mean occupancy on the
 * finest level, interpolated (rsm_mapmatch_result_t.hit); 0 for no points. */
float rsm_mapmatch_fit(const rsm_tmap_t *map, const rsm_point_t *pts, size_t n, const rsm_pose_t *pose);

/* The share (0 to 1) of the points at pose that land within a cell of a
 * wall on the finest level: one of the four cells around the point holds
 * at least wall. Unlike the fit it does not grow with how often a wall
 * was seen: two places that look alike score alike, though the map saw one
 * of them more (a recovery's proof, docs/robustness.md). */
float rsm_mapmatch_wall_share(const rsm_tmap_t *map, const rsm_point_t *pts, size_t n, const rsm_pose_t *pose,
                              uint32_t wall);

/* How well the scan's surfaces pin the position: the ratio (0 to 1) of the
 * smaller to the larger eigenvalue of the sum of t t^T over the unit chords
 * t of the points (pts in beam order; a chord runs from a point to the
 * first at least 0.3 m away on the same surface), 1 when there is no chord;
 * the chords' main direction in dir (robot frame). A bare corridor reads
 * about 0.01, a room or clutter 0.1 to 1. */
float rsm_mapmatch_spread(const rsm_point_t *pts, size_t n, float dir[2]);

/* The unpinning cfg->unpin_lo/unpin_hi asks for the points (robot frame,
 * beam order) at heading theta. */
void rsm_mapmatch_unpin_for(const rsm_mapmatch_config_t *cfg, const rsm_point_t *pts, size_t n, float theta,
                            rsm_mapmatch_unpin_t *un);

#ifdef __cplusplus
}
#endif

#endif /* RSM_MAPMATCH_H */
