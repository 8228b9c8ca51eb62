/* rsm-nav's robot and laser: the library's P3-DX and LMS 2xx drivers, active
 * (they run the devices) or listen-only (they decode what arrives: a
 * replay over serial links, or a capture file fed through a memory link),
 * and what their events give the run. One decoding path for every source,
 * so a capture read from a file and the same capture replayed over serial
 * links give the localizer identical input. */
#ifndef RSM_NAV_DEVICES_H
#define RSM_NAV_DEVICES_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/hal.h"
#include "rsm/odometry.h"
#include "rsm/p3dx.h"
#include "rsm/scan.h"
#include "rsm/sicklms.h"

typedef struct nav_sink {
    void *ctx;
    /* An ENCODER packet. restart: the first packet of a new connection
     * (active mode), whose counts need not follow the previous ones. */
    void (*encoder)(void *ctx, const rsm_odometry_sample_t *sample, int restart);
    /* A scan in the robot frame, stamped (scan->stamp_us) with the arrival
     * of its telegram's first byte. */
    void (*scan)(void *ctx, const rsm_scan_t *scan);
    /* Time passes (after each input, and while the links idle). */
    void (*tick)(void *ctx, uint64_t now_us);
    /* The robot reported its calibration (a connection's CONFIGpac, active
     * mode): encoder ticks per metre. May be NULL. */
    void (*calibration)(void *ctx, float ticks_per_m);
} nav_sink_t;

typedef struct nav_devices {
    rsm_p3dx_config_t pcfg;
    rsm_sicklms_config_t lcfg;
    rsm_p3dx_t robot;
    rsm_sicklms_t laser;
    int listen;   /* 1: listen-only */
    int quiet;
} nav_devices_t;

/* Fills dv's driver configurations with the library defaults (the caller
 * may change them before nav_devices_start). */
void nav_devices_defaults(nav_devices_t *dv, int listen, int quiet);

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
