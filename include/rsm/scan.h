/* One laser scan as the core consumes it: ranges and beam angles in the
 * robot frame, with a timestamp. Filled by a driver, a log reader or a test. */
#ifndef RSM_SCAN_H
#define RSM_SCAN_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct rsm_scan {
    uint64_t stamp_us;               /* acquisition time, microseconds, monotonic */
    size_t count;                    /* readings used, <= RSM_MAX_BEAMS */
    float range_m[RSM_MAX_BEAMS];    /* metres; invalid readings may be any value */
    float angle_rad[RSM_MAX_BEAMS];  /* beam direction in the robot frame, CCW positive */
} rsm_scan_t;

/* Why readings were not used (cumulative counters kept by the caller). */
typedef struct rsm_scan_drops {
    uint32_t nan;          /* NaN or infinite range */
    uint32_t too_short;    /* <= min range (0 is the usual "no echo" code) */
    uint32_t too_long;     /* >= max range (max-range "no return" readings) */
} rsm_scan_drops_t;

/* Range limits of a scan's usable readings, metres. */
typedef struct rsm_scan_limits {
    float min_range_m;     /* readings at or below are dropped; default 0.05 */
    float max_range_m;     /* readings at or above are dropped; default 20 */
} rsm_scan_limits_t;

rsm_scan_limits_t rsm_scan_limits_default(void);

/* Sets count readings at angles start + i * step (radians). Ranges are not
 * touched. Returns RSM_OK, RSM_ERR_INVAL for scan NULL, or RSM_ERR_NOMEM if
 * count > RSM_MAX_BEAMS (scan unchanged).
 * A macro, as rsm_localizer_init: it passes the caller's sizeof(rsm_scan_t)
 * and RSM_CONFIG_FINGERPRINT, so that a caller compiled with other
 * capacities than the library gets RSM_ERR_CONFIG, with scan unchanged,
 * instead of angles written past its scan. */
#define rsm_scan_set_uniform(scan, count, start_rad, step_rad)                                                  \
    rsm_scan_set_uniform_checked((scan), sizeof(rsm_scan_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (count), \
                                 (start_rad), (step_rad))

int rsm_scan_set_uniform_checked(rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint, size_t count,
                                 float start_rad, float step_rad);

/* The functions below that read a scan are macros too, passing the
 * caller's sizeof(rsm_scan_t) and RSM_CONFIG_FINGERPRINT: a scan the caller
 * filled itself, in a program compiled with other capacities, would be read
 * with the library's layout, past the caller's object. */

/* True if reading i is usable under the limits; otherwise counts why in
 * drops (which may be NULL). False, counting nothing, if scan or lim is NULL,
 * i >= scan->count, or the caller was compiled with other capacities. */
#define rsm_scan_reading_ok(scan, i, lim, drops)                                                              \
    rsm_scan_reading_ok_checked((scan), sizeof(rsm_scan_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (i), (lim), \
                                (drops))

int rsm_scan_reading_ok_checked(const rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint, size_t i,
                                const rsm_scan_limits_t *lim, rsm_scan_drops_t *drops);

/* Converts the usable readings to points in the robot frame. Writes at most
 * cap points into out (overwritten, not appended) and returns how many, or a
 * negative status for bad arguments (RSM_ERR_CONFIG, nothing read, for a
 * caller compiled with other capacities). Drops are counted into drops (may
 * be NULL). Reentrant. */
#define rsm_scan_to_points(scan, lim, out, cap, drops)                                                           \
    rsm_scan_to_points_checked((scan), sizeof(rsm_scan_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (lim), (out), \
                               (cap), (drops))

int rsm_scan_to_points_checked(const rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint,
                               const rsm_scan_limits_t *lim, rsm_point_t *out, size_t cap, rsm_scan_drops_t *drops);

/* The cosines and sines of the beam angles of the last scan converted
 * through it: a sensor whose angles repeat from scan to scan (every one
 * the drivers know) then pays no trigonometry per scan. 12 bytes a beam. */
typedef struct rsm_scan_trig {
    float angle[RSM_MAX_BEAMS];
    float cos[RSM_MAX_BEAMS];
    float sin[RSM_MAX_BEAMS];
} rsm_scan_trig_t;

/* Empties the cache: no angle matches until one has been converted.
 * Returns RSM_OK, or RSM_ERR_INVAL for trig NULL. A macro passing the
 * caller's sizeof(rsm_scan_trig_t) and RSM_CONFIG_FINGERPRINT: RSM_ERR_CONFIG,
 * with trig unchanged, for a caller compiled with other capacities than the
 * library (as rsm_localizer_init). */
#define rsm_scan_trig_init(trig) \
    rsm_scan_trig_init_checked((trig), sizeof(rsm_scan_trig_t), (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_scan_trig_init_checked(rsm_scan_trig_t *trig, size_t trig_size, unsigned long fingerprint);

/* rsm_scan_to_points through a cache (not NULL): the same points bit for
 * bit, with the cosine and sine of each angle computed only when the angle
 * differs from the one of the same beam in the last scan. A macro as
 * rsm_scan_to_points (the fingerprint covers the cache's size too). */
#define rsm_scan_to_points_cached(scan, lim, trig, out, cap, drops)                                      \
    rsm_scan_to_points_cached_checked((scan), sizeof(rsm_scan_t), (unsigned long)RSM_CONFIG_FINGERPRINT, \
                                      (lim), (trig), (out), (cap), (drops))

int rsm_scan_to_points_cached_checked(const rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint,
                                      const rsm_scan_limits_t *lim, rsm_scan_trig_t *trig, rsm_point_t *out,
                                      size_t cap, rsm_scan_drops_t *drops);

/* Parameters of rsm_points_isolated. */
#define RSM_ISOLATION_MAX_WINDOW 4u

typedef struct rsm_isolation {
    float tol_m;      /* 0 = keep every point */
    float slope;      /* 1 / cos of the steepest incidence kept (3 ~ 70 deg) */
    uint8_t window;   /* neighbours looked at on each side, 1..RSM_ISOLATION_MAX_WINDOW */
    uint8_t agree;    /* neighbours that must continue the surface, 1..2 * window */
} rsm_isolation_t;

/* Marks the points (in beam order, as rsm_scan_to_points gives them, seen
 * from origin: the laser's position, NULL for (0, 0)) that lie on no
 * surface with enough of their `window` neighbours on either side: a
 * neighbour q continues p's surface if |p - q| <= tol_m + slope * (the gap
 * between their beams at q's range). A return that its neighbours do not
 * confirm - a speck of dust, a mixed pixel at an edge, a reflection, random
 * noise - is more often wrong than a confirmed one; far away, where beams
 * are sparse and walls grazed, it is also often right. Sets bit k of mask
 * (n bits, all written) for each marked point and returns how many. */
size_t rsm_points_isolated(const rsm_point_t *pts, size_t n, const rsm_point_t *origin, const rsm_isolation_t *iso,
                           uint8_t *mask);

/* Parameters of rsm_points_occluded. */
#define RSM_OCCLUSION_MAX_WINDOW 4u

typedef struct rsm_occlusion {
    uint8_t window;   /* neighbours looked at on each side, 0 = mark nothing, 1..RSM_OCCLUSION_MAX_WINDOW */
    float span_m;     /* two neighbours at most this far apart can hide what lies behind them */
    float tol_m;      /* ... and at most tol_m + slope * (the gap between their beams at the */
    float slope;      /*     nearer one's range): one surface, seen at up to acos(1/slope) */
    float margin_m;   /* a point this far behind their chord, plus margin_rel of its range, */
    float margin_rel; /* is marked */
} rsm_occlusion_t;

/* Marks the points (in beam order, as rsm_scan_to_points gives them, in the
 * laser's frame: seen from (0, 0)) that lie behind a surface two of their
 * neighbours span across their beam: for neighbours p (up to `window`
 * before) and q (up to `window` after) no farther apart than span_m and
 * tol_m + slope * gap, whose beams are at most 10 degrees apart, a point
 * whose beam runs between theirs and whose
 * range exceeds the distance along that beam to the chord p-q by more
 * than margin_m + margin_rel * range. A laser cannot see through a wall,
 * so such a return is a phantom (a spurious echo, an outlier) or was seen
 * through a gap narrower than span_m: matched or written into a map it
 * would pull the pose towards whatever lies behind the wall and wear the
 * wall down with its beam. A doorway or a gap between furniture wider than
 * span_m is seen through and kept. Sets bit k of mask (n bits, all
 * written) for each marked point and returns how many. Uses no more
 * than window ranges on either side of a point (no scratch memory). */
size_t rsm_points_occluded(const rsm_point_t *pts, size_t n, const rsm_occlusion_t *occ, uint8_t *mask);

#ifdef __cplusplus
}
#endif

#endif /* RSM_SCAN_H */
