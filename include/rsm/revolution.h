/* Revolution assembler: the points of a spinning lidar (rsm/lidar.h, from
 * the LD06 or RPLIDAR drivers) gathered over one turn of the head into one
 * rsm_scan_t, optionally de-skewed with odometry.
 *
 * A turn ends where the sensor angle falls back (by more than wrap_deg: the
 * head passed its zero); the point that falls back starts the next turn. The
 * first turn after init, reset or a gap started somewhere in the middle and
 * is dropped (counted), as is a turn with fewer than min_points points.
 *
 * The scan is in the laser frame, as rsm_localizer_t expects it (the
 * localizer applies laser_mount and laser_upside_down itself): a sensor
 * angle a (degrees, clockwise seen from above when cfg.clockwise) becomes
 * the bearing -a (else +a), wrapped to (-pi, pi]; a point without a return
 * (range 0) stays range 0 at its bearing, so the core drops and counts it.
 * Points beyond RSM_MAX_BEAMS are dropped and counted; keep_every thins a
 * dense sensor (an LD06 gives 450 points per turn at 10 Hz) to fit.
 *
 * Time: scan.stamp_us is the middle of the turn, halfway between the times
 * of its first and last points. With de-skew on, every point is moved to
 * where the laser saw it from the robot's pose at that middle time: the
 * robot poses at the point's time and at the stamp are interpolated from the
 * odometry poses given with rsm_rev_odometry (linear in x, y and heading;
 * past the newest, extrapolated with the motion over at least the last 20 ms
 * of odometry, and over at least as long as it is carried on when the poses
 * reach that far back, for no longer than it was measured over, held when
 * the poses span under 5 ms; held before the oldest; a pose read within 2 ms
 * of the newest, far sooner than the newest came after the one before, makes
 * the newest the first of a burst, measured earlier than its stamp says: it
 * is put halfway between its neighbours),
 * the point taken through the mounting pose into the robot frame at its own
 * time, moved by the relative motion, and taken back into the laser frame.
 * Off, the points keep their bearings and ranges: a robot turning at w rad/s
 * with a lidar turning at f Hz smears each turn over w / f rad.
 *
 * Odometry late: with de-skew on and odom_wait_us set, a whole turn waits,
 * kept as measured while the next one fills, until odometry covers it (a
 * pose stamped at or after its last point, which no burst will re-stamp: the
 * pose before the newest, or the newest once 2 ms of points passed without
 * another); rsm_rev_push returns it with the next point. It goes out with
 * the odometry there is (stats.uncovered) once the newest pose is
 * odom_wait_us old, when the next turn ends, when the oldest odometry pose
 * it starts from would be dropped for a new one (it is then de-skewed in
 * rsm_rev_odometry, and the next push returns it), or on rsm_rev_flush.
 *
 * All state is in the caller's rsm_rev_t (a scan, two turns of 12 bytes per
 * beam, 24 bytes per odometry pose: 12 360 bytes on a Cortex-M4 with the
 * default configuration); cfg is kept by pointer. Pure computation, no I/O;
 * one assembler must not be used from two contexts at once. */
#ifndef RSM_REVOLUTION_H
#define RSM_REVOLUTION_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/lidar.h"
#include "rsm/scan.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Runtime settings; rsm_rev_config_default gives the values in brackets. */
typedef struct rsm_rev_config {
    rsm_pose_t mount;       /* laser pose in the robot frame: the same value as
                               rsm_localizer_config_t.laser_mount [0, 0, 0] */
    uint8_t upside_down;    /* as rsm_localizer_config_t.laser_upside_down [0] */
    uint8_t clockwise;      /* 1: sensor angles grow clockwise seen from above
                               (LD06, LD19, RPLIDAR) [1] */
    uint8_t deskew;         /* 1: move every point to the pose at the stamp [1] */
    uint16_t keep_every;    /* keep one point in this many, >= 1 [1] */
    uint16_t min_points;    /* shorter turns are dropped, >= 1 [30] */
    float wrap_deg;         /* a fall of the sensor angle by more than this ends
                               a turn, in (0, 360) [180] */
    uint32_t max_gap_us;    /* a longer silence between two points drops the
                               turn in progress, > 0 [300 000] */
    uint32_t odom_wait_us;  /* with de-skew, a whole turn waits at most this long
                               past its last point for odometry stamped after
                               it; 0: de-skewed at once [250 000] */
} rsm_rev_config_t;

/* Fills *cfg with the defaults. RSM_OK or RSM_ERR_INVAL (NULL). */
int rsm_rev_config_default(rsm_rev_config_t *cfg);

/* Counters; they only grow (wrapping at 2^32). */
typedef struct rsm_rev_stats {
    uint32_t points;        /* points pushed */
    uint32_t scans;         /* turns delivered */
    uint32_t partial;       /* turns dropped: the first, cut by a gap or reset,
                               or shorter than min_points */
    uint32_t dropped;       /* points of the dropped turns */
    uint32_t overflow;      /* points beyond RSM_MAX_BEAMS, dropped */
    uint32_t thinned;       /* points skipped by keep_every */
    uint32_t invalid;       /* points delivered with range 0 (no return) */
    uint32_t bad_points;    /* angle outside [0, 360), range negative or not
                               finite, or stamped before the previous point:
                               dropped */
    uint32_t gaps;          /* silences longer than max_gap_us */
    uint32_t long_turns;    /* turns dropped for lasting over 2 s (a sensor
                               angle stuck: no turn would ever end) */
    uint32_t implausible;   /* points left as measured because odometry
                               moved the robot faster than 5 m/s or 4 pi
                               rad/s between the point and the stamp (a
                               spike, a reset, absurd poses) */
    uint32_t odometry;      /* odometry poses taken */
    uint32_t odometry_bursts; /* odometry poses read within 2 ms of the newest, far sooner than
                               * it came after the one before (a backlog read in a burst): the
                               * newest was re-stamped halfway between its neighbours */
    uint32_t odometry_bad;  /* odometry stamped before the newest, or not finite:
                               dropped */
    uint32_t not_deskewed;  /* turns delivered without de-skew although it was
                               on: no odometry pose at all */
    uint32_t extrapolated;  /* points whose time lay past the newest odometry
                               pose (extrapolated) or before the oldest (held) */
    uint32_t waited;        /* turns that waited for odometry past their last
                               point */
    uint32_t uncovered;     /* turns de-skewed without odometry past their last
                               point: the wait ran out, odometry was silent for
                               as long, the next turn ended, the odometry kept
                               was about to lose the turn's start, or
                               rsm_rev_flush */
} rsm_rev_stats_t;

/* What rsm_rev_init writes into rsm_rev_t.magic: the other functions
 * refuse an assembler without it (never initialised, or zeroed). */
#define RSM_REV_MAGIC 0x52534d52UL

/* A turn's points as measured (private to the assembler). 12 bytes per
 * beam. */
typedef struct rsm_rev_turn {
    float angle_deg[RSM_MAX_BEAMS];
    float range_m[RSM_MAX_BEAMS];
    uint32_t dt_us[RSM_MAX_BEAMS]; /* after first_us */
    size_t n;
    uint64_t first_us;             /* its first point's stamp */
    uint64_t last_us;              /* its last point's (kept or not) */
} rsm_rev_turn_t;

/* Assembler state, caller owned. stats and scan may be read at any time
 * (scan holds the last delivered turn); the rest is private. */
typedef struct rsm_rev {
    uint32_t magic;                /* RSM_REV_MAGIC once initialised */
    const rsm_rev_config_t *cfg;
    rsm_rev_stats_t stats;
    rsm_scan_t scan;
    rsm_rev_turn_t cur;            /* the turn in progress */
    rsm_rev_turn_t held;           /* a whole turn waiting for odometry */
    size_t seen;                   /* points of this turn, kept or not */
    uint64_t last_us;              /* the newest point's stamp */
    float last_angle;
    uint8_t have_last;
    uint8_t whole;                 /* this turn began at the sensor's zero */
    uint8_t holding;               /* held is waiting */
    uint8_t unsaid;                /* scan holds a turn rsm_rev_push has not
                                      returned 1 for yet */
    /* odometry, oldest first */
    uint64_t odom_us[RSM_REV_ODOM_DEPTH];
    rsm_pose_t odom[RSM_REV_ODOM_DEPTH];
    size_t odom_head;
    size_t odom_n;
} rsm_rev_t;

/* Initialises r with no turn in progress and no odometry; cfg is kept by
 * pointer. Returns RSM_OK, or RSM_ERR_INVAL for NULL pointers or a setting
 * outside its range (r unchanged).
 * A macro, as rsm_localizer_init: it passes the caller's sizeof(rsm_rev_t)
 * and RSM_CONFIG_FINGERPRINT, so that a caller compiled with other
 * capacities than the library gets RSM_ERR_CONFIG, with r unchanged. */
#define rsm_rev_init(r, cfg) \
    rsm_rev_init_checked((r), sizeof(rsm_rev_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (cfg))

int rsm_rev_init_checked(rsm_rev_t *r, size_t r_size, unsigned long fingerprint, const rsm_rev_config_t *cfg);

/* An odometry pose (any fixed frame: only the motion between two times is
 * used) at stamp_us, on the clock the points are stamped with. The newest
 * RSM_REV_ODOM_DEPTH poses are kept (a waiting turn that starts at the
 * oldest is de-skewed into r->scan before that pose goes: the next
 * rsm_rev_push returns it). Returns RSM_OK, RSM_ERR_INVAL (NULL
 * pointers, r never initialised: no RSM_REV_MAGIC), RSM_ERR_ORDER for a
 * stamp before the newest pose's (dropped, counted) or RSM_ERR_RANGE for a
 * pose that is not finite (dropped, counted). */
int rsm_rev_odometry(rsm_rev_t *r, uint64_t stamp_us, const rsm_pose_t *pose);

/* One point, in measuring order. Returns 1 if a whole turn is delivered
 * (r->scan holds it, valid until the next call of rsm_rev_push,
 * rsm_rev_odometry or rsm_rev_flush; the point that ended a turn starts the
 * next one), 0 if not, RSM_ERR_INVAL for NULL pointers or r never
 * initialised, RSM_ERR_RANGE or RSM_ERR_ORDER for a point counted in
 * bad_points and dropped. With de-skew and odom_wait_us set, the turn a
 * point ends may come out with a later point: when odometry stamped after
 * its last point has come (see the top of this header). */
int rsm_rev_push(rsm_rev_t *r, const rsm_lidar_point_t *pt);

/* Delivers a whole turn still waiting for odometry, de-skewed with the
 * odometry there is: call it when no more points will come (the link was
 * lost, the stream ended). Returns 1 if r->scan now holds it (as for
 * rsm_rev_push), 0 if no turn was waiting, RSM_ERR_INVAL for NULL or r
 * never initialised. */
int rsm_rev_flush(rsm_rev_t *r);

/* Drops the turn in progress (counted as partial if it held points): call
 * it when the link was lost, after rsm_rev_flush. Odometry, and a whole
 * turn waiting for it, are kept. No-op for NULL or r never initialised. */
void rsm_rev_reset(rsm_rev_t *r);

#ifdef __cplusplus
}
#endif

#endif /* RSM_REVOLUTION_H */
