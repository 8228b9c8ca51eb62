/* Decoding of raw robot (ARIA) and laser (SICK LMS 2xx) byte streams for
 * rsm-nav's capture and listen-only live modes: bytes in, encoder counts and
 * robot-frame scans out. The same path serves both modes, so a capture read
 * from a file and the same capture replayed over serial links give the
 * localizer identical input. */
#ifndef RSM_NAV_STREAM_H
#define RSM_NAV_STREAM_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/aria.h"
#include "rsm/lms.h"
#include "rsm/odometry.h"
#include "rsm/scan.h"

typedef struct nav_stream_sink {
    void *ctx;
    /* An ENCODER packet: raw 32-bit counters and their stamp. restart: the
     * first packet of a new connection, whose counts need not follow the
     * previous ones. */
    void (*encoder)(void *ctx, const rsm_odometry_sample_t *sample, int restart);
    /* The robot reported its calibration (a P3-DX connection's CONFIGpac):
     * encoder ticks per metre. May be NULL. */
    void (*calibration)(void *ctx, float ticks_per_m);
    /* A complete 0xB0 scan converted to the robot frame, stamped with the
     * arrival of its telegram's first byte. */
    void (*scan)(void *ctx, const rsm_scan_t *scan, uint64_t stamp_us);
    /* Time passes (called before each input, and while a live link idles). */
    void (*tick)(void *ctx, uint64_t now_us);
} nav_stream_sink_t;

typedef struct nav_stream {
    rsm_aria_parser_t aria;
    rsm_lms_parser_t lms;
    rsm_lms_scan_t lms_scan;
    rsm_scan_t scan;
    uint64_t encoder_packets;
    uint64_t other_packets;   /* SIPs and other ARIA packets, ACK/NAK and other LMS telegrams */
    uint64_t lms_scans;
    uint64_t bad_scans;       /* 0xB0 telegrams that did not decode or had unknown angles */
    uint64_t lms_start_us;    /* arrival of the first byte of the telegram being received */
} nav_stream_t;

void nav_stream_init(nav_stream_t *s);

/* Feeds robot-link bytes (ARIA) received at stamp_us. */
void nav_stream_robot(nav_stream_t *s, const uint8_t *data, size_t n, uint64_t stamp_us,
                      const nav_stream_sink_t *sink);

/* Feeds laser-link bytes (LMS 2xx) received at stamp_us. */
void nav_stream_laser(nav_stream_t *s, const uint8_t *data, size_t n, uint64_t stamp_us,
                      const nav_stream_sink_t *sink);

#endif
