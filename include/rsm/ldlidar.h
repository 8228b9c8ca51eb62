/* LDRobot LD06 / LD19 driver: the LD06 codec (rsm/ld06.h) on an rsm_link_t,
 * listening only (the sensor takes no commands), yielding stamped points for
 * the revolution assembler (rsm/revolution.h).
 *
 * A non-blocking state machine driven by rsm_ldlidar_poll, one cycle of
 * rsm_link_poll (rsm/hal.h) per call: at most one link read, then the
 * timers, and at most one event.
 *
 * rsm_ldlidar_connect sets the link to cfg.baud (where the link has a rate)
 * and starts listening; the first verified packet gives CONNECTED, every
 * packet a POINTS event with its 12 points. Stamps: the packet's last byte
 * is taken to have come at the clock time of the read that brought it, less
 * the line time of the bytes after it in that read (cfg.baud, 8N1); its last
 * point is measured cfg.latency_us before that, the others one angle step
 * earlier each, a step lasting (span / 11) / speed (the packet's own
 * fields). Packets that came in one read could then overlap in time: a
 * packet whose first point would precede the previous packet's last is moved
 * later to meet it (counted in stamp_shifts), so that stamps never go back. No verified
 * packet for cfg.stream_timeout_us gives LINK_LOST and listening starts
 * over (the next packet gives CONNECTED again, counted as a reconnect).
 *
 * All state is in the caller's rsm_ldlidar_t; link, clock and cfg are kept
 * by pointer and must outlive it. One driver must not be used from two
 * contexts at once. */
#ifndef RSM_LDLIDAR_H
#define RSM_LDLIDAR_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/hal.h"
#include "rsm/link_poll.h"
#include "rsm/ld06.h"
#include "rsm/lidar.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Runtime settings; rsm_ldlidar_config_default gives the values in brackets. */
typedef struct rsm_ldlidar_config {
    uint32_t baud;              /* link rate, set at connect if the link has one [230400] */
    uint32_t read_timeout_us;   /* longest wait inside one poll; 0: take only what
                                   has arrived (see rsm_ldlidar_next_deadline_us) [10 000] */
    uint32_t byte_timeout_us;   /* a partial packet is dropped after this silence [20 000] */
    uint32_t stream_timeout_us; /* no verified packet this long = link lost, > 0 [500 000] */
    uint32_t latency_us;        /* subtracted from the arrival of a packet [0] */
} rsm_ldlidar_config_t;

/* Fills *cfg with the defaults. RSM_OK or RSM_ERR_INVAL (NULL). */
int rsm_ldlidar_config_default(rsm_ldlidar_config_t *cfg);

typedef enum rsm_ldlidar_state {
    RSM_LDLIDAR_IDLE = 0,
    RSM_LDLIDAR_LISTENING = 1, /* connected, no packet yet (or lost) */
    RSM_LDLIDAR_STREAMING = 2
} rsm_ldlidar_state_t;

typedef enum rsm_ldlidar_event_type {
    RSM_LDLIDAR_EVENT_NONE = 0,
    RSM_LDLIDAR_EVENT_CONNECTED = 1, /* the first packet after connect or a loss;
                                        its points come with the next POINTS */
    RSM_LDLIDAR_EVENT_POINTS = 2,    /* ev.points[0..count) */
    RSM_LDLIDAR_EVENT_LINK_LOST = 3  /* nothing valid for stream_timeout_us */
} rsm_ldlidar_event_type_t;

typedef struct rsm_ldlidar_event {
    rsm_ldlidar_event_type_t type;
    size_t count;
    rsm_lidar_point_t points[RSM_LD06_POINTS]; /* stamped */
    uint64_t stamp_us;                         /* POINTS: the packet's arrival
                                                  (see above); else detection time */
} rsm_ldlidar_event_t;

/* Counters, wrapping at 2^32. Framing counters are in d->parser.stats. */
typedef struct rsm_ldlidar_stats {
    uint32_t packets;     /* verified packets */
    uint32_t points;      /* points delivered */
    uint32_t connects;    /* CONNECTED events */
    uint32_t reconnects;  /* CONNECTED after a LINK_LOST */
    uint32_t link_lost;   /* LINK_LOST events */
    uint32_t read_errors; /* failed link reads */
    uint32_t baud_errors; /* the link refused cfg.baud (it may still work) */
    uint32_t stamp_shifts; /* packets moved later to keep stamps in order */
} rsm_ldlidar_stats_t;

/* What rsm_ldlidar_init writes into rsm_ldlidar_t.magic: the other
 * functions refuse a driver without it (never initialised, or zeroed). */
#define RSM_LDLIDAR_MAGIC 0x52534d44UL

/* Driver state, caller owned. state, stats, parser.stats and last may be
 * read at any time; the rest is private. */
typedef struct rsm_ldlidar {
    uint32_t magic;           /* RSM_LDLIDAR_MAGIC once initialised */
    const rsm_ldlidar_config_t *cfg;
    rsm_ldlidar_state_t state;
    rsm_ldlidar_stats_t stats;
    rsm_ld06_parser_t parser;
    rsm_ld06_packet_t last;   /* last verified packet */
    uint8_t pending;          /* a packet waits to be delivered as POINTS */
    uint8_t lost;
    uint64_t last_packet_us;  /* clock time of the last verified packet */
    uint64_t packet_us;       /* arrival of the waiting packet */
    uint64_t last_point_us;   /* stamp of the last point delivered */
    rsm_link_rx_t io;
    rsm_ldlidar_event_t out;
} rsm_ldlidar_t;

/* Initialises d (IDLE, zero counters); nothing is read. Returns RSM_OK, or
 * RSM_ERR_INVAL for NULL pointers, a link without read or write, a clock
 * without now_us, or a zero read or stream timeout (d unchanged).
 * A macro, as rsm_localizer_init: it passes the caller's
 * sizeof(rsm_ldlidar_t) and RSM_CONFIG_FINGERPRINT, so that a caller
 * compiled with other capacities than the library (RSM_LINK_RX_CHUNK sizes
 * the driver) gets RSM_ERR_CONFIG, with d unchanged. */
#define rsm_ldlidar_init(d, link, clock, cfg) \
    rsm_ldlidar_init_checked((d), sizeof(rsm_ldlidar_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (link), (clock), (cfg))

int rsm_ldlidar_init_checked(rsm_ldlidar_t *d, size_t d_size, unsigned long fingerprint, const rsm_link_t *link,
                             const rsm_clock_t *clock, const rsm_ldlidar_config_t *cfg);

/* The functions below that take d refuse d NULL or never initialised (no
 * RSM_LDLIDAR_MAGIC: zeroed or stale memory) with RSM_ERR_INVAL
 * (rsm_ldlidar_next_deadline_us: UINT64_MAX), touching nothing. */

/* Starts listening (sets the rate where the link has one, drops what was
 * received). Returns RSM_OK or RSM_ERR_INVAL (d NULL or never initialised). */
int rsm_ldlidar_connect(rsm_ldlidar_t *d);

/* Stops listening: IDLE, nothing more is read. RSM_OK or RSM_ERR_INVAL. */
int rsm_ldlidar_disconnect(rsm_ldlidar_t *d);

/* One cycle: at most one read of at most read_timeout_us, then the timers.
 * *ev receives the event (NONE if nothing happened). Returns RSM_OK,
 * RSM_ERR_INVAL (NULL pointers) or the status of a failed read. */
int rsm_ldlidar_poll(rsm_ldlidar_t *d, rsm_ldlidar_event_t *ev);

/* Clock time (the driver's clock, microseconds) at which the driver next
 * needs a poll even if nothing arrives: the stream's silence check; the
 * current time when received bytes are still unexamined or a packet waits
 * to be delivered; UINT64_MAX in IDLE or for d NULL or never initialised.
 * As rsm_p3dx_next_deadline_us: a caller serving several links waits
 * until the earliest deadline of all or until bytes arrive, then polls
 * each driver (read_timeout_us 0) until it gives no event. */
uint64_t rsm_ldlidar_next_deadline_us(const rsm_ldlidar_t *d);

/* The stamped points of packet pkt whose last point was measured at
 * last_us (the driver's rule above; pure, for log readers and tests).
 * Returns RSM_LD06_POINTS or RSM_ERR_INVAL. */
int rsm_ldlidar_stamp(const rsm_ld06_packet_t *pkt, uint64_t last_us, rsm_lidar_point_t *out);

#ifdef __cplusplus
}
#endif

#endif /* RSM_LDLIDAR_H */
