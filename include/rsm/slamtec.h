/* Slamtec RPLIDAR driver: the RPLIDAR codec (rsm/rplidar.h) on an
 * rsm_link_t, yielding stamped points for the revolution assembler
 * (rsm/revolution.h).
 *
 * A non-blocking state machine driven by rsm_slamtec_poll, one cycle of
 * rsm_link_poll (rsm/hal.h) per call: at most one link read, then the
 * timers, and at most one event.
 *
 * Start-up (docs/reference/lidars.md section 2), by rsm_slamtec_connect and
 * later polls:
 *   1. STOP (a scan left running ends), pause stop_wait_us, drop the input;
 *   2. RESET and pause reset_wait_us, when cfg.reset is set or the last
 *      health answer said "error";
 *   3. GET_HEALTH: an "error" status fails the start-up (ERROR event,
 *      RSM_ERR_PROTO; the next attempt resets the unit first);
 *   4. GET_INFO (kept in d->info);
 *   5. GET_SAMPLERATE (one try; firmware before 1.17 does not answer, then
 *      cfg.sample_us is used);
 *   6. the motor command, if cfg.motor asks for one (SET_MOTOR_PWM for the
 *      A2/A3 accessory board, MOTOR_SPEED_CTRL in rpm for the C1 and the
 *      S-series), then a pause of motor_wait_us for the head to spin up. An
 *      A1/A2 on Slamtec's USB adapter runs its motor while the host clears
 *      DTR; rsm_link_t has no modem-line operation, so the port must do that;
 *   7. SCAN or EXPRESS_SCAN, whose answer descriptor (0x81; 0x82 or 0x85)
 *      gives CONNECTED.
 * A request without answer in reply_timeout_us is sent again, at most
 * max_tries times; then an ERROR event (RSM_ERR_TIMEOUT) and, after
 * retry_wait_us, the start-up again from step 1.
 *
 * Streaming: capsules give a POINTS event each, nodes are gathered up to
 * RSM_RPLIDAR_MAX_POINTS per event. Stamps: a frame's last byte is taken to
 * have come at the clock time of the read that brought it less the line
 * time of the bytes after it (cfg.baud, 8N1); a node is measured
 * cfg.latency_us before that; the samples of a capsule, published when the
 * next capsule is complete, latency plus (2n - 1 - k) sample times before
 * it for sample k of n (the sample time from GET_SAMPLERATE). A frame whose
 * first point would precede the last one delivered is moved later to meet
 * it (stamp_shifts), so stamps never go back. Nothing valid for
 * stream_timeout_us gives LINK_LOST and the start-up again.
 *
 * Listen-only (rsm_slamtec_listen): nothing is sent; the driver decodes
 * what the sensor sends while another host runs it (or a capture or a
 * replay of such a session): health, info and sample-rate answers are
 * kept in d->health, d->info and d->samplerate, a scan descriptor gives
 * CONNECTED and the nodes or capsules after it POINTS, stamped as above. A
 * stream picked up without its descriptor is not decoded (the descriptor
 * says what the bytes are). Nothing valid for stream_timeout_us gives
 * LINK_LOST and the driver awaits the next descriptor.
 *
 * Shutdown (rsm_slamtec_disconnect, run by later polls): STOP, then the
 * motor stop command if cfg.motor set one (PWM 0 / 0 rpm), a pause of
 * stop_wait_us, DISCONNECTED and IDLE.
 *
 * All state is in the caller's rsm_slamtec_t (about 2 KB); link, clock and
 * cfg are kept by pointer and must outlive it. One driver must not be used
 * from two contexts at once. */
#ifndef RSM_SLAMTEC_H
#define RSM_SLAMTEC_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/hal.h"
#include "rsm/link_poll.h"
#include "rsm/lidar.h"
#include "rsm/rplidar.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RSM_SLAMTEC_SCAN_STANDARD 0u /* SCAN, 5-byte nodes (every model) */
#define RSM_SLAMTEC_SCAN_EXPRESS 1u  /* EXPRESS_SCAN, legacy mode: express or
                                        dense capsules, as the model answers */

#define RSM_SLAMTEC_MOTOR_NONE 0u  /* no motor command (A1; DTR by the port) */
#define RSM_SLAMTEC_MOTOR_PWM 1u   /* SET_MOTOR_PWM motor_value (A2/A3 board) */
#define RSM_SLAMTEC_MOTOR_RPM 2u   /* MOTOR_SPEED_CTRL motor_value rpm (C1, S) */

/* Runtime settings; rsm_slamtec_config_default gives the values in brackets. */
typedef struct rsm_slamtec_config {
    uint32_t baud;              /* link rate, set at connect if the link has one,
                                   0 to leave it [115200] */
    uint8_t scan_mode;          /* RSM_SLAMTEC_SCAN_* [STANDARD] */
    uint8_t motor;              /* RSM_SLAMTEC_MOTOR_* [NONE] */
    uint16_t motor_value;       /* PWM duty or rpm [660] */
    uint8_t reset;              /* 1: RESET at every start-up [0] */
    uint8_t max_tries;          /* sends per request, >= 1 [3] */
    uint16_t sample_us;         /* sample time until GET_SAMPLERATE answers [250] */
    uint32_t read_timeout_us;   /* longest wait inside one poll; 0: take only what
                                   has arrived (see rsm_slamtec_next_deadline_us) [10 000] */
    uint32_t byte_timeout_us;   /* silence that ends a partial answer [50 000] */
    uint32_t reply_timeout_us;  /* answer wait, > 0 [500 000] */
    uint32_t stop_wait_us;      /* pause after STOP [20 000] */
    uint32_t reset_wait_us;     /* pause after RESET [1 000 000] */
    uint32_t motor_wait_us;     /* pause after the motor command [1 000 000] */
    uint32_t retry_wait_us;     /* pause after an ERROR [1 000 000] */
    uint32_t stream_timeout_us; /* nothing valid while streaming = lost, > 0 [1 000 000] */
    uint32_t latency_us;        /* subtracted from arrival times [0] */
} rsm_slamtec_config_t;

/* Fills *cfg with the defaults. RSM_OK or RSM_ERR_INVAL (NULL). */
int rsm_slamtec_config_default(rsm_slamtec_config_t *cfg);

typedef enum rsm_slamtec_state {
    RSM_SLAMTEC_IDLE = 0,
    RSM_SLAMTEC_STARTING = 1, /* a start-up step in flight (or its pause) */
    RSM_SLAMTEC_BACKOFF = 2,  /* pause after an ERROR */
    RSM_SLAMTEC_STREAMING = 3,
    RSM_SLAMTEC_STOPPING = 4,
    RSM_SLAMTEC_LISTENING = 5 /* listen-only, awaiting a scan descriptor */
} rsm_slamtec_state_t;

typedef enum rsm_slamtec_event_type {
    RSM_SLAMTEC_EVENT_NONE = 0,
    RSM_SLAMTEC_EVENT_CONNECTED = 1,   /* scanning; d->info and d->health hold
                                          the unit's answers */
    RSM_SLAMTEC_EVENT_POINTS = 2,      /* ev.points[0..count), stamped */
    RSM_SLAMTEC_EVENT_LINK_LOST = 3,   /* nothing valid while streaming;
                                          starting again */
    RSM_SLAMTEC_EVENT_ERROR = 4,       /* a start-up step failed (ev.status);
                                          starting again after retry_wait_us */
    RSM_SLAMTEC_EVENT_DISCONNECTED = 5 /* shutdown done; now IDLE */
} rsm_slamtec_event_type_t;

typedef struct rsm_slamtec_event {
    rsm_slamtec_event_type_t type;
    int status;       /* ERROR: RSM_ERR_TIMEOUT or RSM_ERR_PROTO; else 0 */
    size_t count;
    rsm_lidar_point_t points[RSM_RPLIDAR_MAX_POINTS];
    uint64_t stamp_us; /* detection time */
} rsm_slamtec_event_t;

/* Counters, wrapping at 2^32. Framing counters are in d->parser.stats. */
typedef struct rsm_slamtec_stats {
    uint32_t requests;        /* requests written */
    uint32_t retries;         /* requests sent again after a timeout */
    uint32_t timeouts;        /* answers not received in time */
    uint32_t health_errors;   /* health answers with status "error" */
    uint32_t health_warnings; /* ... with status "warning" (start-up goes on) */
    uint32_t resets;          /* RESET requests */
    uint32_t no_samplerate;   /* GET_SAMPLERATE unanswered: cfg.sample_us used */
    uint32_t unexpected;      /* answers nobody asked for, ignored */
    uint32_t stale_bytes;     /* bytes read before a request went out, dropped
                                 unexamined (they cannot be its answer) */
    uint32_t errors;          /* ERROR events */
    uint32_t connects;        /* CONNECTED events */
    uint32_t reconnects;      /* CONNECTED after a LINK_LOST */
    uint32_t link_lost;       /* LINK_LOST events */
    uint32_t points;          /* points delivered */
    uint32_t disconnects;     /* DISCONNECTED events */
    uint32_t write_errors;
    uint32_t read_errors;
    uint32_t baud_errors;     /* the link refused cfg.baud */
    uint32_t stamp_shifts;    /* frames moved later to keep stamps in order */
} rsm_slamtec_stats_t;

/* What rsm_slamtec_init writes into rsm_slamtec_t.magic: the other
 * functions refuse a driver without it (never initialised, or zeroed). */
#define RSM_SLAMTEC_MAGIC 0x52534d54UL

/* Driver state, caller owned. state, stats, parser.stats, info, health and
 * samplerate may be read at any time; the rest is private. */
typedef struct rsm_slamtec {
    uint32_t magic;           /* RSM_SLAMTEC_MAGIC once initialised */
    const rsm_slamtec_config_t *cfg;
    rsm_slamtec_state_t state;
    rsm_slamtec_stats_t stats;
    rsm_rplidar_parser_t parser;
    rsm_rplidar_info_t info;
    rsm_rplidar_health_t health;
    rsm_rplidar_samplerate_t samplerate; /* zero until the unit answered */
    /* private */
    uint8_t step;
    uint8_t tries;
    uint8_t waiting;          /* 1: the step's pause, not an answer, runs */
    uint8_t lost;
    uint8_t need_reset;
    uint8_t answer;           /* answer type of the stream */
    uint8_t listen;           /* 1: listen-only (nothing is sent) */
    uint8_t resumed;          /* listen-only: the lost stream is tried again */
    uint32_t listen_mark;     /* the parser's bytes skipped when the listener
                                 last changed what it awaits */
    uint8_t req[16];
    size_t req_len;
    uint64_t deadline_us;
    uint64_t last_data_us;
    uint64_t last_point_us;   /* stamp of the last point delivered */
    rsm_link_rx_t io;
    rsm_rplidar_event_t ev;   /* codec event being handled */
    rsm_slamtec_event_t out;
} rsm_slamtec_t;

/* Initialises d (IDLE, zero counters); nothing is sent. Returns RSM_OK, or
 * RSM_ERR_INVAL for NULL pointers, a link without read or write, a clock
 * without now_us, a zero read, reply or stream timeout, max_tries 0, or an
 * unknown scan mode or motor setting (d unchanged).
 * A macro, as rsm_localizer_init: it passes the caller's
 * sizeof(rsm_slamtec_t) and RSM_CONFIG_FINGERPRINT, so that a caller
 * compiled with other capacities than the library (RSM_LINK_RX_CHUNK sizes
 * the driver) gets RSM_ERR_CONFIG, with d unchanged. */
#define rsm_slamtec_init(d, link, clock, cfg) \
    rsm_slamtec_init_checked((d), sizeof(rsm_slamtec_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (link), (clock), (cfg))

int rsm_slamtec_init_checked(rsm_slamtec_t *d, size_t d_size, unsigned long fingerprint, const rsm_link_t *link,
                             const rsm_clock_t *clock, const rsm_slamtec_config_t *cfg);

/* The functions below refuse d NULL or never initialised (no
 * RSM_SLAMTEC_MAGIC: zeroed or stale memory) with RSM_ERR_INVAL
 * (rsm_slamtec_next_deadline_us: UINT64_MAX), touching nothing. */

/* Starts (or restarts) the start-up. RSM_OK or RSM_ERR_INVAL (d NULL or
 * never initialised). */
int rsm_slamtec_connect(rsm_slamtec_t *d);

/* Listen-only mode (see above): drops what was received, awaits a scan
 * descriptor and sends nothing, ever; the link's rate is set to cfg.baud
 * where the link has one. rsm_slamtec_connect leaves the mode,
 * rsm_slamtec_disconnect goes straight to IDLE (nothing sent, no event).
 * RSM_OK or RSM_ERR_INVAL (d NULL or never initialised). */
int rsm_slamtec_listen(rsm_slamtec_t *d);

/* Starts the shutdown from any state but IDLE; later polls finish it and
 * give DISCONNECTED (listen-only: IDLE at once, no event). RSM_OK or
 * RSM_ERR_INVAL (d NULL or never initialised). */
int rsm_slamtec_disconnect(rsm_slamtec_t *d);

/* One cycle: at most one read of at most read_timeout_us, then the timers.
 * *ev receives the event (NONE if nothing happened). Returns RSM_OK,
 * RSM_ERR_INVAL (NULL pointers) or the status of a failed read. */
int rsm_slamtec_poll(rsm_slamtec_t *d, rsm_slamtec_event_t *ev);

/* Clock time (the driver's clock, microseconds) at which the driver next
 * needs a poll even if nothing arrives: a start-up pause or answer
 * timeout, the pause after an error, the stream's silence check; the
 * current time when received bytes are still unexamined; UINT64_MAX in
 * IDLE, while listening for a descriptor, or for d NULL or never
 * initialised. As rsm_p3dx_next_deadline_us: a caller serving several
 * links waits until the earliest deadline of all or until bytes arrive,
 * then polls each driver (read_timeout_us 0) until it gives no event. */
uint64_t rsm_slamtec_next_deadline_us(const rsm_slamtec_t *d);

#ifdef __cplusplus
}
#endif

#endif /* RSM_SLAMTEC_H */
