/* Time alignment of wheel odometry and laser scans.
 *
 * The robot and the laser talk over two links that deliver independently:
 * an encoder packet may arrive before or after a scan taken at the same
 * moment, and a long LMS telegram is still on the wire for a large part of a
 * second at 38400 baud while encoder packets keep coming. Feeding the
 * localizer in arrival order then fuses scans with odometry from the wrong
 * time. The aligner stands between the links and the localizer: it holds the
 * latest encoder samples back (up to RSM_SYNC_DEPTH), and fuses each scan with
 * odometry interpolated at the scan's own timestamp (counts split linearly in
 * time between the samples around it, which is exact for a constant-velocity
 * arc). A scan whose time is past the newest sample waits for a later one, at
 * most max_wait_us. The increments of the samples up to a scan are composed
 * and predicted once, just before the scan: the odometry noise model (per
 * prediction, with a floor) then sees one step per scan whatever the
 * encoder rate, as a CARMEN log's odometry gives it (rsm-nav --carmen).
 *
 * Timestamps of both inputs must come from one clock (the HAL clock in a
 * driver, arrival times in a host tool, record times in a capture). A scan
 * stamp should be the time of the measurement, e.g. the arrival of the
 * telegram's first byte; scan_offset_us corrects a known fixed latency.
 *
 * Results are delivered through a callback, in scan order, once per scan.
 * All state is caller-owned (about one rsm_scan_t plus 16 bytes per held
 * sample); nothing blocks or allocates. */
#ifndef RSM_SYNC_H
#define RSM_SYNC_H

#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/localizer.h"
#include "rsm/odometry.h"
#include "rsm/scan.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct rsm_sync_config {
    uint32_t max_wait_us;     /* longest a scan waits for odometry past its time; default 250000 */
    uint32_t hold_us;         /* encoder samples older than the newest by this much are applied
                               * at once (they cannot bracket a scan still to come); default 500000 */
    int32_t scan_offset_us;   /* added to every scan stamp (negative: measured earlier); default 0 */
    uint32_t snap_us;         /* a sample this close to the scan time counts as taken with it:
                               * its counts are used as they are, and a scan does not wait for
                               * a later sample (arrival jitter of two links); default 1000 */
    float max_travel_m;       /* composed odometry is predicted at the latest after this much wheel
                               * travel (or before a half turn), even with no scan: a silent laser
                               * must not let a loop driven blind come back with the prior of
                               * its net step; default 2.0; 0: predict every sample as applied */
} rsm_sync_config_t;

rsm_sync_config_t rsm_sync_config_default(void);

/* How each scan was aligned, and what went wrong with the inputs. */
typedef struct rsm_sync_counters {
    uint32_t scans;             /* scans offered */
    uint32_t interpolated;      /* odometry interpolated between samples around the scan time */
    uint32_t exact;             /* a sample within snap_us of the scan time, or no odometry at all */
    uint32_t late;              /* scan older than odometry already applied: fused with it */
    uint32_t timed_out;         /* no sample past the scan time within max_wait_us */
    uint32_t superseded;        /* a newer scan arrived while this one waited */
    uint32_t encoders;          /* encoder samples offered */
    uint32_t encoder_backwards; /* sample stamped before the previous one: taken in arrival order */
    uint32_t encoder_overflow;  /* held samples applied early because the buffer was full */
    uint32_t encoder_bursts;    /* samples read within 2 ms of the one before, far sooner than the
                                   one before came after its own: that one is re-stamped halfway */
    uint32_t restarts;          /* rsm_sync_encoder_restart calls (new connections) */
    uint32_t blind_predictions; /* odometry predicted with no scan: max_travel_m, or a half turn */
} rsm_sync_counters_t;

/* Called once per fused scan with the localizer's status and report. */
typedef void (*rsm_sync_result_fn)(void *ctx, const rsm_scan_t *scan, int status,
                                   const rsm_localizer_report_t *rep);

/* What rsm_sync_init writes into rsm_sync_t.magic: the other functions
 * refuse an aligner without it (never initialised, or zeroed). */
#define RSM_SYNC_MAGIC 0x52534d41UL

typedef struct rsm_sync {
    uint32_t magic;                   /* RSM_SYNC_MAGIC once initialised */
    rsm_localizer_t *loc;
    const rsm_sync_config_t *cfg;     /* kept by pointer */
    rsm_sync_result_fn on_result;
    void *ctx;
    rsm_odometry_sample_t ring[RSM_SYNC_DEPTH]; /* samples not yet applied, oldest first */
    uint32_t head;
    uint32_t count;
    rsm_odometry_sample_t base;           /* the last counts applied */
    uint8_t have_base;
    uint8_t have_pending;             /* applied samples not yet predicted */
    rsm_pose_t pending;               /* their increments composed (robot frame of the last prediction) */
    float pending_travel_m;           /* their wheel travel */
    float pending_turn_rad;           /* their turn, not wrapped */
    uint8_t holding;                  /* a scan waits in held */
    uint64_t held_since_us;           /* its (offset) stamp: the wait runs from here */
    rsm_scan_t held;
    rsm_sync_counters_t counters;
} rsm_sync_t;

/* Binds the aligner to an initialised localizer (which must outlive it) and
 * validates cfg. on_result may be NULL. Returns RSM_OK, or RSM_ERR_INVAL
 * (s, loc or cfg NULL, loc never initialised, a bad cfg) with s unchanged.
 * A macro, as rsm_localizer_init: it passes the caller's sizeof(rsm_sync_t)
 * and RSM_CONFIG_FINGERPRINT, so that a caller compiled with other
 * capacities than the library gets RSM_ERR_CONFIG, with s unchanged. */
#define rsm_sync_init(s, loc, cfg, on_result, ctx)                                                          \
    rsm_sync_init_checked((s), sizeof(rsm_sync_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (loc), (cfg), \
                          (on_result), (ctx))

int rsm_sync_init_checked(rsm_sync_t *s, size_t s_size, unsigned long fingerprint, rsm_localizer_t *loc,
                          const rsm_sync_config_t *cfg, rsm_sync_result_fn on_result, void *ctx);

/* The functions below refuse s NULL or never initialised (no
 * RSM_SYNC_MAGIC: zeroed or stale memory) with RSM_ERR_INVAL. */

/* An encoder sample (raw counters, as a driver delivers them: rsm/p3dx.h
 * ENCODER events; copied). May fuse a waiting scan. Returns RSM_OK or
 * RSM_ERR_INVAL (sample NULL). */
int rsm_sync_encoder(rsm_sync_t *s, const rsm_odometry_sample_t *sample);

/* The encoder counters start over (the first sample of a new connection
 * follows: a robot that restarted counts from 0). Held samples are applied
 * first; the next sample only latches the counters, so no step is taken
 * across the restart. Returns RSM_OK or RSM_ERR_INVAL. */
int rsm_sync_encoder_restart(rsm_sync_t *s);

/* A scan, stamped in scan->stamp_us (copied; the caller's buffer is free on
 * return). Fuses it now when odometry past its time is already held, or
 * when no encoder sample was ever seen; otherwise it waits. A scan already
 * waiting is fused first with the odometry there is. Returns RSM_OK,
 * RSM_ERR_INVAL (scan NULL, or more than RSM_MAX_BEAMS readings: dropped) or
 * RSM_ERR_CONFIG (the caller was compiled with other capacities: the scan is
 * not read). A macro as rsm_sync_init, passing the caller's sizeof(rsm_scan_t)
 * and RSM_CONFIG_FINGERPRINT. */
#define rsm_sync_scan(s, scan) \
    rsm_sync_scan_checked((s), (scan), sizeof(rsm_scan_t), (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_sync_scan_checked(rsm_sync_t *s, const rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint);

/* Fuses a waiting scan whose wait has expired at now_us (call it from the
 * main loop). Returns 1 if a scan was fused, else 0; or RSM_ERR_INVAL. */
int rsm_sync_poll(rsm_sync_t *s, uint64_t now_us);

/* End of input: fuses a waiting scan with the odometry there is, then
 * applies every held encoder sample and predicts what was composed.
 * Returns 1 if a scan was fused, else 0; or RSM_ERR_INVAL. */
int rsm_sync_flush(rsm_sync_t *s);

/* Best current pose: the localizer's estimate moved on by the odometry
 * composed but not yet predicted and the odometry still held back. NaN in
 * every field for s NULL or never initialised, or a localizer never
 * initialised. */
rsm_pose_t rsm_sync_pose(const rsm_sync_t *s);

#ifdef __cplusplus
}
#endif

#endif /* RSM_SYNC_H */
