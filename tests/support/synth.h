/* Synthetic worlds for the tests: a 2-D world of line segments, a ray caster
 * that fills an rsm_scan_t as a planar laser would see it from a robot pose,
 * a seeded noise source, scripted paths and corrupted odometry.
 *
 * Everything here is deterministic: the same calls with the same seeds give
 * bit-identical results (no time, no rand(); the PRNG state is the caller's
 * rsm_synth_rng_t). No heap, no globals except the read-only built-in worlds.
 *
 * synth.c is built once (in rsm_testsupport) and linked against both the
 * default and the small-config core, so it depends on no config.h capacity
 * and calls nothing in the rsm library; the one function that touches
 * rsm_scan_t is an inline wrapper compiled in each test.
 *
 * Frames: world metres, CCW-positive radians; a scan's beam angles are in the
 * robot frame, as in rsm_scan_t. */
#ifndef RSM_TEST_SYNTH_H
#define RSM_TEST_SYNTH_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/geom.h"
#include "rsm/odometry.h"
#include "rsm/scan.h"
#include "rsm/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- deterministic random numbers ------------------------------------- */

/* xorshift32 state; never zero once seeded. */
typedef struct rsm_synth_rng {
    uint32_t s;
} rsm_synth_rng_t;

/* Seeds the generator (a zero seed is replaced by a fixed non-zero one). */
void rsm_synth_rng_seed(rsm_synth_rng_t *rng, uint32_t seed);

/* Next raw 32-bit value. */
uint32_t rsm_synth_rng_next(rsm_synth_rng_t *rng);

/* Uniform in [0, 1), 24-bit resolution. */
float rsm_synth_rng_uniform(rsm_synth_rng_t *rng);

/* Approximately standard normal: the sum of 12 uniforms minus 6
 * (Irwin-Hall; bounded to [-6, 6], no libm, identical on every platform). */
float rsm_synth_rng_gauss(rsm_synth_rng_t *rng);

/* ---- worlds ------------------------------------------------------------ */

/* A wall from (x0, y0) to (x1, y1), metres. Walls have no thickness and are
 * seen from both sides. */
typedef struct rsm_synth_segment {
    float x0;
    float y0;
    float x1;
    float y1;
} rsm_synth_segment_t;

/* A world is a borrowed array of segments (not copied). */
typedef struct rsm_synth_world {
    const rsm_synth_segment_t *seg;
    size_t count;
} rsm_synth_world_t;

/* A closed room of 4 m x 3 m, x in [-2, 2], y in [-1.5, 1.5], with
 *  - an inner box x in [0.5, 1.1], y in [0.2, 0.6],
 *  - a square pillar x in [-1.0, -0.8], y in [-0.6, -0.4],
 *  - an alcove in the south wall x in [-0.3, 0.3], y down to -1.8,
 *  - a doorway in the east wall, y in [-0.4, 0.4], opening onto an
 *    L-shaped corridor 0.8 m wide: east to x = 4.8, then north up to
 *    y = 3.2 (its outer corner at (4.8, -0.4)), closed at the far end,
 *    with a 0.3 m wide, 0.2 m deep niche in each leg (south wall at
 *    x in [3.0, 3.3], east wall at y in [1.4, 1.7]).
 * Free space a robot may drive through: the room away from the box and
 * pillar, and the corridor's centre line (y = 0 for x in [2, 4.4], then
 * x = 4.4 for y in [0, 2.8]). Corners are close together, so that even
 * the small test configuration (3.2 m window) finds structure to match
 * from most poses. Every wall lies on a multiple of 5 cm, i.e. on the
 * border of the default 5 cm cells: the worst case for the half-cell
 * quantisation of the map (shift the frame by 2.5 cm for the best case). */
rsm_synth_world_t rsm_synth_world_room(void);

/* Only the L-corridor of the room world, as a world of its own (both ends
 * closed, the west end at x = 2 closed too). */
rsm_synth_world_t rsm_synth_world_corridor(void);

/* Distance from (ox, oy) along angle to the nearest wall, or max_range_m if
 * nothing is hit closer. Always finite and in [0, max_range_m]. */
float rsm_synth_cast(const rsm_synth_world_t *world, float ox, float oy, float angle_rad, float max_range_m);

/* ---- scans ------------------------------------------------------------- */

typedef struct rsm_synth_scan_config {
    size_t beams;            /* readings, <= RSM_MAX_BEAMS; default 181 */
    float start_rad;         /* first beam, robot frame; default -pi/2 */
    float end_rad;           /* last beam; default +pi/2 (beams evenly spaced, both ends included) */
    float max_range_m;       /* value of a "no return" reading; default 20 (what rsm drops as too long) */
    float sigma_m;           /* Gaussian range noise std (needs an rng); default 0 */
    float outlier_fraction;  /* share of readings replaced by uniform ranges (needs an rng); default 0 */
    float outlier_min_m;     /* outlier ranges are uniform in [outlier_min_m, outlier_max_m); default 0.1 */
    float outlier_max_m;     /* default 4 */
} rsm_synth_scan_config_t;

rsm_synth_scan_config_t rsm_synth_scan_config_default(void);

/* Fills range_m[0..beams) and angle_rad[0..beams) (overwritten) with
 * cfg->beams readings ray-cast from pose. Hits get Gaussian noise of sigma_m
 * (clamped to stay > 0 and below max_range_m); then exactly
 * round(outlier_fraction * beams) distinct readings, chosen by the rng, are
 * replaced by uniform random ranges. Misses read max_range_m exactly. With
 * rng NULL (or sigma 0 and fraction 0) the scan is exact. Never writes NaN.
 * Returns RSM_OK, or RSM_ERR_INVAL for NULL arguments, beams < 2 or > cap, a
 * fraction outside [0, 1], or noise/outliers asked for without an rng.
 * Independent of config.h, so one build of this file serves every config. */
int rsm_synth_ranges(const rsm_synth_world_t *world, const rsm_pose_t *pose, const rsm_synth_scan_config_t *cfg,
                     rsm_synth_rng_t *rng, float *range_m, float *angle_rad, size_t cap);

/* The same into an rsm_scan_t (overwritten: count = cfg->beams, stamp_us),
 * compiled in the caller's translation unit so that the scan layout follows
 * the caller's config.h. On error the scan is unchanged except that readings
 * may have been partly written. */
static inline int rsm_synth_scan(const rsm_synth_world_t *world, const rsm_pose_t *pose,
                                 const rsm_synth_scan_config_t *cfg, rsm_synth_rng_t *rng, uint64_t stamp_us,
                                 rsm_scan_t *scan)
{
    int rc;
    if (scan == NULL) {
        return RSM_ERR_INVAL;
    }
    rc = rsm_synth_ranges(world, pose, cfg, rng, scan->range_m, scan->angle_rad, (size_t)RSM_MAX_BEAMS);
    if (rc == RSM_OK) {
        scan->stamp_us = stamp_us;
        scan->count = cfg->beams;
    }
    return rc;
}

/* ---- paths and odometry ------------------------------------------------ */

/* One leg of a scripted path: drive forward_m while turning turn_rad, as a
 * constant-curvature arc (forward 0: spin in place; turn 0: straight). */
typedef struct rsm_synth_leg {
    float forward_m;
    float turn_rad;
} rsm_synth_leg_t;

/* Expands legs into true poses: out[0] = *start, then one pose per step.
 * Each leg is split into max(ceil(|forward| / step_m), ceil(|turn| /
 * step_rad), 1) equal steps, each the increment (d cos(phi/2), d sin(phi/2),
 * phi) of the odometry model. Writes at most cap poses and returns how many
 * (0 for bad arguments or non-positive step sizes). */
size_t rsm_synth_path(const rsm_pose_t *start, const rsm_synth_leg_t *legs, size_t nlegs, float step_m,
                      float step_rad, rsm_pose_t *out, size_t cap);

/* Systematic odometry errors. */
typedef struct rsm_synth_odo_error {
    float scale;            /* translation reads (1 + scale) times the truth, e.g. 0.03 */
    float drift_rad_per_m;  /* heading error added per metre travelled (CCW positive) */
} rsm_synth_odo_error_t;

/* The increment odometry reports for the true step from -> to: the true
 * increment between(from, to) (computed here in double precision) with dx, dy scaled by (1 + scale) and
 * drift_rad_per_m * |(dx, dy)| added to dtheta (wrapped). err NULL: exact. */
rsm_motion_t rsm_synth_motion(const rsm_pose_t *from, const rsm_pose_t *to, const rsm_synth_odo_error_t *err);

/* ---- error measures ----------------------------------------------------- */

/* Euclidean distance between the positions of a and b, metres. */
float rsm_synth_pos_error(const rsm_pose_t *a, const rsm_pose_t *b);

/* |wrap(a.theta - b.theta)|, radians, in [0, pi]. */
float rsm_synth_angle_error(const rsm_pose_t *a, const rsm_pose_t *b);

/* 1 if x, y and theta are all finite. */
int rsm_synth_pose_finite(const rsm_pose_t *p);

#ifdef __cplusplus
}
#endif

#endif /* RSM_TEST_SYNTH_H */
