/* rsm-nav's robot and laser: the library's P3-DX driver and an LMS 2xx, an
 * LD06/LD19 or an RPLIDAR driver, active (they run the devices) or
 * listen-only (they decode what arrives: a replay over serial links, or a
 * capture file fed through a memory link), and what their events give the
 * run. A spinning lidar's points go through the revolution assembler, whose
 * de-skew takes the pose the robot's encoder packets give. One decoding path for every source,
 * so a capture read from a file and the same capture replayed over serial
 * links give the localizer identical input. */
#ifndef RSM_NAV_DEVICES_H
#define RSM_NAV_DEVICES_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/hal.h"
#include "rsm/ldlidar.h"
#include "rsm/odometry.h"
#include "rsm/p3dx.h"
#include "rsm/revolution.h"
#include "rsm/scan.h"
#include "rsm/sicklms.h"
#include "rsm/slamtec.h"

/* Which laser: the LMS, or a spinning lidar. */
typedef enum nav_laser_kind { NAV_LASER_LMS = 0, NAV_LASER_LD06 = 1, NAV_LASER_RPLIDAR = 2 } nav_laser_kind_t;

typedef struct nav_sink {
    void *ctx;
    /* An ENCODER packet. restart: the first packet of a new connection
     * (active mode), whose counts need not follow the previous ones. */
    void (*encoder)(void *ctx, const rsm_odometry_sample_t *sample, int restart);
    /* A scan in the laser frame, stamped (scan->stamp_us) with the arrival
     * of its telegram's first byte (LMS) or the middle of its turn (lidar). */
    void (*scan)(void *ctx, const rsm_scan_t *scan);
    /* Time passes (after each input, and while the links idle). */
    void (*tick)(void *ctx, uint64_t now_us);
    /* The robot reported its calibration (a connection's CONFIGpac, active
     * mode): encoder ticks per metre. Returns 1 if the run takes it (a
     * lidar's de-skew then takes it too), 0 if not. May be NULL. */
    int (*calibration)(void *ctx, float ticks_per_m);
} nav_sink_t;

typedef struct nav_devices {
    rsm_p3dx_config_t pcfg;
    rsm_sicklms_config_t lcfg;
    rsm_ldlidar_config_t ldcfg;
    rsm_slamtec_config_t slcfg;
    rsm_rev_config_t rcfg;        /* the lidar's turns (mount: the localizer's) */
    rsm_p3dx_t robot;
    rsm_sicklms_t laser;
    rsm_scan_t laser_scan;        /* the LMS driver decodes into it */
    rsm_ldlidar_t ld06;
    rsm_slamtec_t rplidar;
    rsm_rev_t rev;
    /* De-skew: the encoder counts integrated into a pose on the drivers'
     * clock (any frame: the assembler uses only the motion). */
    rsm_odometry_t odo;
    rsm_pose_t odo_pose;
    nav_laser_kind_t kind;
    int listen;   /* 1: listen-only */
    int quiet;
} nav_devices_t;

/* Fills dv's driver configurations with the library defaults (the caller
 * may change them before nav_devices_start). */
void nav_devices_defaults(nav_devices_t *dv, int listen, int quiet);

/* The laser becomes a spinning lidar (before nav_devices_start): kind, its
 * mount and orientation as the localizer has them, one point in keep_every
 * kept. Listen-only runs (a replay's pace is not the sensor's) wait out
 * silences: neither the link nor a turn is given up for them. 0, or -1 for
 * a bad value (message on stderr). */
int nav_devices_lidar(nav_devices_t *dv, nav_laser_kind_t kind, const rsm_pose_t *mount, int upside_down,
                      unsigned keep_every);

/* The encoder geometry the de-skew converts counts with (the localizer's;
 * again whenever it changes). */
void nav_devices_odometry(nav_devices_t *dv, const rsm_odometry_config_t *cfg);

/* Starts the robot's (robot 1) or the laser's driver on link and clock
 * (kept by pointer): connects, or listens. 0, or -1 if the driver refused
 * (message on stderr). */
int nav_devices_start(nav_devices_t *dv, int robot, const rsm_link_t *link, const rsm_clock_t *clock);

/* One poll of one driver; its events go to sink. Returns 1 if the poll
 * gave an event, 0 if not, a negative status if the link failed. */
int nav_devices_poll(nav_devices_t *dv, int robot, const nav_sink_t *sink);

/* Polls one driver until it gives no event and reads nothing more, or
 * max_bytes were read. Returns the bytes read (>= 0) or, when the link
 * failed before anything was read, its negative status. */
long nav_devices_drain(nav_devices_t *dv, int robot, const nav_sink_t *sink, uint64_t max_bytes);

/* Live mode's view of either driver: connect again (a reopened link; a
 * lidar's whole turn still waiting for odometry goes to sink, its turn in
 * progress is dropped), start the shutdown, whether it has
 * not yet reached IDLE, CONNECTED and LINK_LOST events so far, scans
 * delivered, and the next time its poll has something to do (UINT64_MAX:
 * only bytes). */
void nav_devices_restart(nav_devices_t *dv, int robot, const nav_sink_t *sink);
void nav_devices_stop(nav_devices_t *dv, int robot);
int nav_devices_busy(const nav_devices_t *dv, int robot);
uint32_t nav_devices_connects(const nav_devices_t *dv, int robot);
uint32_t nav_devices_losses(const nav_devices_t *dv, int robot);
uint32_t nav_devices_scans(const nav_devices_t *dv);
uint64_t nav_devices_next_deadline(const nav_devices_t *dv, int robot);

/* The lidar's points have ended (the capture or the run is over): a whole
 * turn still waiting for odometry goes to sink (may be NULL: dropped),
 * de-skewed with the odometry there is. No-op for the LMS. */
void nav_devices_flush(nav_devices_t *dv, const nav_sink_t *sink);

/* Bytes one link delivered in all. */
uint64_t nav_devices_bytes(const nav_devices_t *dv, int robot);

/* Stderr reports of the driver counters. */
void nav_devices_report(const nav_devices_t *dv, int robot);

/* A memory link and a clock for feeding recorded bytes to a driver: each
 * read returns what is left of data (0 when all was read: no more for
 * now), the clock reads now_us. Writing fails (RSM_ERR_IO): only
 * listen-only drivers may use it. */
typedef struct nav_feed {
    const uint8_t *data;
    size_t len;
    size_t off;
    uint64_t now_us;
} nav_feed_t;

/* Fills link and clock to read from f. */
void nav_feed_init(nav_feed_t *f, rsm_link_t *link, rsm_clock_t *clock);

/* Gives one listen-only driver, started on feed's link and clock, len
 * bytes recorded at stamp_us (each decoded event to sink), then lets time
 * pass to sink (tick at stamp_us). */
void nav_devices_feed(nav_devices_t *dv, int robot, nav_feed_t *feed, const uint8_t *data, size_t len,
                      uint64_t stamp_us, const nav_sink_t *sink);

#endif
