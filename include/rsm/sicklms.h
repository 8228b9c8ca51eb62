/* SICK LMS 200/211/221/291 driver: the LMS codec (rsm/lms.h) on an
 * rsm_link_t, yielding rsm_scan_t scans in the robot frame.
 *
 * A non-blocking state machine driven by rsm_sicklms_poll. Each poll is the
 * cycle of rsm_link_poll (rsm/hal.h): it reads the link at most once, with
 * a timeout of at most config.read_timeout_us (less when a deadline is
 * nearer), handles what arrived and the timers, and returns at most one
 * event. Deadlines are absolute clock times.
 *
 * Start-up (protocols.md 2.10): probe with 0x20 0x25 (stop any stream) at
 * the power-up rate, then at the other rates (9600, 38400, 19200) when no
 * ACK comes; optionally switch to the working rate (0x20 0x40/0x41/0x42: the
 * 0xA0 reply comes at the OLD rate, then the link's rate is changed; a lost
 * baud-change reply is never repeated blindly: the rates are probed again,
 * the target first); set the variant (0x3B, the 0xBB reply must accept and
 * echo it); read the configuration block (0x74, reply 0xF4; optional) to
 * learn the measuring mode, units and index bytes that decoding 0xB0 needs;
 * start continuous output (0x20 0x24).
 *
 * Every request (protocols.md 2.4): ACK awaited ack_timeout_us, then the
 * reply reply_timeout_us (mode_timeout_us after 0x20); a NAK is answered by
 * re-sending after nak_wait_us; at most max_tries sends, then an ERROR event
 * and a new start-up after retry_wait_us.
 *
 * Streaming: every 0xB0 telegram is decoded (with d->format) and converted
 * into d->scan: scanner angle a (0 right, 90 deg ahead, 180 left) becomes
 * the robot-frame bearing a - 90 deg (x forward, y left, CCW positive;
 * 90 deg - a when mounted upside down), ranges in metres, invalid readings
 * (error codes) stored as range 0 so that the core drops and counts them.
 * The scan is stamped with the receive time of the read that brought the
 * telegram's first byte (the scan was measured before it was sent; a
 * 361-value telegram takes 0.2 s at 38400 Bd), minus config.latency_us, as
 * rsm/sync.h expects. No telegram for stream_timeout_us gives a LINK_LOST
 * event and a new start-up.
 *
 * Shutdown (protocols.md 2.10 step 8), started by rsm_sicklms_disconnect
 * and run by later polls like the start-up: 0x20 0x25 (stop the stream),
 * then, unless the link is already at power_up_baud, the 0x20 baud change
 * back to it (reply at the old rate, then the link follows), so that the
 * next user finds the unit where a start-up probes first; then a
 * DISCONNECTED event and IDLE. A step that fails (no ACK or reply after
 * max_tries sends) ends the shutdown at once with the event's status set.
 *
 * All state is in the caller's rsm_sicklms_t (about 7 KB with the default
 * RSM_MAX_BEAMS); link, clock and config are kept by pointer and must
 * outlive it. One driver must not be used from two contexts at once;
 * distinct drivers are independent. Not ISR-safe. */
#ifndef RSM_SICKLMS_H
#define RSM_SICKLMS_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/hal.h"
#include "rsm/link_poll.h"
#include "rsm/lms.h"
#include "rsm/scan.h"
#include "rsm/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Runtime tuning; rsm_sicklms_config_default gives the values in brackets. */
typedef struct rsm_sicklms_config {
    uint8_t address;            /* LMS address, 0..0x7F [0] */
    uint32_t power_up_baud;     /* first rate probed: 9600, 19200 or 38400 [9600] */
    uint32_t baud;              /* working rate 9600/19200/38400, or 0 to stay at
                                   the rate found [38400] */
    uint8_t probe;              /* 1: try the other rates when nothing answers [1] */
    uint16_t angle_deg;         /* variant: 180 or 100 [180] */
    uint16_t resolution_cdeg;   /* variant: 100, 50 or 25 (1/100 deg) [100] */
    uint8_t upside_down;        /* 1: scanner mounted upside down [0] */
    uint8_t max_tries;          /* sends per request, >= 1 [3] */
    uint32_t read_timeout_us;   /* longest wait inside one poll; 0: never wait [10 000] */
    uint32_t ack_timeout_us;    /* ACK/NAK wait [200 000] */
    uint32_t reply_timeout_us;  /* reply wait after the ACK [1 000 000] */
    uint32_t mode_timeout_us;   /* reply wait after a 0x20 request [3 000 000] */
    uint32_t nak_wait_us;       /* pause before re-sending after a NAK [30 000] */
    uint32_t baud_settle_us;    /* pause after changing the link rate [250 000] */
    uint32_t retry_wait_us;     /* pause after an ERROR before starting again [1 000 000] */
    uint32_t stream_timeout_us; /* silence while streaming = link lost [1 000 000] */
    uint32_t byte_timeout_us;   /* partial telegram abandoned after this silence [100 000] */
    uint32_t latency_us;        /* subtracted from the arrival of a scan's first byte [0] */
    uint8_t read_config;        /* 1: read the configuration block (0x74) at start-up
                                   and decode 0xB0 with its distance bits and index
                                   bytes [1] */
    rsm_lms_b0_format_t format; /* 0xB0 decoding [rsm_lms_b0_format_default]; with
                                   read_config only its units are kept (AUTO: the
                                   count word of each telegram says) */
} rsm_sicklms_config_t;

/* Fills *cfg with the defaults above. RSM_OK or RSM_ERR_INVAL (NULL). Pure. */
int rsm_sicklms_config_default(rsm_sicklms_config_t *cfg);

typedef enum rsm_sicklms_state {
    RSM_SICKLMS_IDLE = 0,
    RSM_SICKLMS_STARTING = 1,  /* a start-up request is in flight */
    RSM_SICKLMS_SETTLE = 2,    /* pause after a rate change */
    RSM_SICKLMS_BACKOFF = 3,   /* pause after an ERROR */
    RSM_SICKLMS_STREAMING = 4,
    RSM_SICKLMS_STOPPING = 5,  /* a shutdown request is in flight */
    RSM_SICKLMS_LISTENING = 6  /* listen-only (rsm_sicklms_listen): decodes, sends nothing */
} rsm_sicklms_state_t;

typedef enum rsm_sicklms_event_type {
    RSM_SICKLMS_EVENT_NONE = 0,
    RSM_SICKLMS_EVENT_CONNECTED = 1, /* streaming started; d->baud is the rate */
    RSM_SICKLMS_EVENT_SCAN = 2,      /* *ev->scan holds a new scan */
    RSM_SICKLMS_EVENT_LINK_LOST = 3, /* stream silent; starting again */
    RSM_SICKLMS_EVENT_ERROR = 4,     /* a start-up step failed (ev->status);
                                        starting again after retry_wait_us */
    RSM_SICKLMS_EVENT_DISCONNECTED = 5 /* shutdown done (ev->status RSM_OK) or
                                          given up (RSM_ERR_TIMEOUT,
                                          RSM_ERR_PROTO, RSM_ERR_IO); now IDLE */
} rsm_sicklms_event_type_t;

typedef struct rsm_sicklms_event {
    rsm_sicklms_event_type_t type;
    int status;                /* ERROR, DISCONNECTED: see above; else 0 */
    const rsm_scan_t *scan;    /* SCAN: the caller's scan given to rsm_sicklms_init
                                  (d->scan), holding the new scan until the next
                                  SCAN overwrites it; NULL otherwise */
    uint64_t stamp_us;         /* receive/detection time */
} rsm_sicklms_event_t;

/* Counters; each wraps modulo 2^32. Framing counters (CRC errors, skipped
 * bytes, truncated telegrams) are also in d->parser.stats. */
typedef struct rsm_sicklms_stats {
    uint32_t telegrams;        /* verified telegrams received */
    uint32_t crc_errors;       /* copy of d->parser.stats.crc_errors */
    uint32_t acks;             /* ACKs to our requests */
    uint32_t naks;             /* NAKs to our requests */
    uint32_t rejected;         /* 0x92 "not accepted" replies */
    uint32_t ack_timeouts;     /* requests without ACK in time */
    uint32_t reply_timeouts;   /* ACKed requests without reply in time */
    uint32_t retries;          /* requests re-sent */
    uint32_t probes;           /* probe requests sent */
    uint32_t baud_changes;     /* link rate changes */
    uint32_t errors;           /* ERROR events */
    uint32_t connects;         /* start-ups completed */
    uint32_t link_lost;        /* LINK_LOST events */
    uint32_t reconnects;       /* start-ups completed after a link loss */
    uint32_t scans;            /* scans delivered */
    uint32_t bad_scans;        /* 0xB0 telegrams that did not decode */
    uint32_t invalid_readings; /* readings delivered as range 0 */
    uint32_t unexpected;       /* other telegrams, ignored */
    uint32_t config_reads;     /* configuration blocks read (0xF4) */
    uint32_t disconnects;      /* shutdowns completed (DISCONNECTED with RSM_OK) */
    uint32_t write_errors;
    uint32_t read_errors;
} rsm_sicklms_stats_t;

/* What rsm_sicklms_init writes into rsm_sicklms_t.magic: the other
 * functions refuse a driver without it (never initialised, or zeroed). */
#define RSM_SICKLMS_MAGIC 0x52534d53UL

/* Driver state, caller owned. Read-only for the caller: state, stats, baud,
 * format, config and have_config may be read at any time; the rest is
 * private. */
typedef struct rsm_sicklms {
    uint32_t magic;            /* RSM_SICKLMS_MAGIC once initialised */
    const rsm_sicklms_config_t *cfg;
    const rsm_link_t *link;
    const rsm_clock_t *clock;
    rsm_sicklms_state_t state;
    rsm_sicklms_stats_t stats;
    uint32_t baud;             /* current link rate */
    rsm_lms_b0_format_t format; /* 0xB0 decoding in use: cfg->format, then
                                  what the configuration block says */
    rsm_lms_config_t config;   /* last configuration block read (0x74) */
    uint8_t have_config;       /* 1 once config holds a block from this unit */
    rsm_lms_parser_t parser;
    rsm_scan_t *scan;          /* the caller's: each 0xB0 is decoded into it, in the
                                  robot frame (no copy of the scan is kept here) */
    /* private */
    uint8_t step;              /* start-up step in flight */
    uint8_t sub;               /* awaiting ACK, reply, or NAK pause */
    uint8_t tries;             /* sends of the current request */
    uint8_t probe_idx;
    uint8_t probed;            /* rates tried in this probe round */
    uint8_t lost;
    uint8_t req_reply;         /* reply CMD expected */
    uint8_t req[16];
    size_t req_len;
    uint64_t deadline_us;
    uint64_t last_tel_us;      /* last telegram while streaming */
    uint64_t tel_start_us;     /* arrival of the first byte of the telegram in progress */
    rsm_link_rx_t io;          /* link, clock and receive chunk (rsm_link_poll) */
    rsm_sicklms_event_t out;   /* the event of the poll in progress */
} rsm_sicklms_t;

/* Initialises d in the IDLE state with zero counters; nothing is sent.
 * link, clock, cfg and scan are kept by pointer: each scan received is
 * decoded straight into the caller's *scan (overwriting it; a telegram
 * that does not decode leaves it untouched), so the caller that keeps a
 * scan while the next arrives copies it (rsm_sync_scan does).
 * Returns RSM_OK, or RSM_ERR_INVAL for NULL pointers, a link without read or
 * write, a clock without now_us, a zero ack/reply/mode timeout,
 * max_tries 0, an address above 0x7F, rates other than 9600/19200/38400
 * (baud may be 0), or a variant rsm_lms_encode_variant refuses (d is then
 * unchanged).
 * A macro, as rsm_localizer_init: it passes the caller's
 * sizeof(rsm_sicklms_t) and RSM_CONFIG_FINGERPRINT, so that a caller
 * compiled with other capacities than the library (which size d and *scan)
 * gets RSM_ERR_CONFIG, with d unchanged, instead of scans decoded past its
 * own. */
#define rsm_sicklms_init(d, link, clock, cfg, scan)                                                        \
    rsm_sicklms_init_checked((d), sizeof(rsm_sicklms_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (link), (clock), \
                             (cfg), (scan))

int rsm_sicklms_init_checked(rsm_sicklms_t *d, size_t d_size, unsigned long fingerprint, const rsm_link_t *link,
                             const rsm_clock_t *clock, const rsm_sicklms_config_t *cfg, rsm_scan_t *scan);

/* The functions below that take d refuse d NULL or never initialised (no
 * RSM_SICKLMS_MAGIC: zeroed or stale memory) with RSM_ERR_INVAL
 * (rsm_sicklms_next_deadline_us: UINT64_MAX), touching nothing. */

/* Starts (or restarts) the start-up: sets the link to power_up_baud when it
 * can change rates (d->baud is then that rate), then sends the first
 * probe. Returns RSM_OK or RSM_ERR_INVAL (d NULL or never initialised). */
int rsm_sicklms_connect(rsm_sicklms_t *d);

/* Listen-only mode, from any state: the driver sends nothing, never
 * changes the link's rate and runs no timer; every 0xB0 telegram that
 * arrives (from a unit another program started, or a replayed capture) is
 * decoded with cfg->format and given as a SCAN event exactly as when
 * streaming, stamped the same way (the receive time of the read that
 * brought the telegram's first byte, less latency_us). A telegram cut
 * short is abandoned after byte_timeout_us of silence, as always.
 * rsm_sicklms_connect leaves the mode; rsm_sicklms_disconnect goes to IDLE
 * (nothing sent). Received input is kept. Returns RSM_OK or RSM_ERR_INVAL
 * (d NULL). */
int rsm_sicklms_listen(rsm_sicklms_t *d);

/* Converts a decoded 0xB0 scan to a robot-frame scan: scanner angles run
 * 0..180 deg from the right, the robot's 0 is ahead (mirrored when
 * upside_down is 1); readings with an error code get range 0, which the
 * core drops and counts. out->stamp_us is not touched. Returns the number
 * of invalid readings (>= 0), RSM_ERR_PROTO if the scan's angles are unknown
 * (step 0) or RSM_ERR_INVAL for NULL pointers (out untouched on error).
 * Pure, reentrant; used by the driver and by log/capture readers alike.
 * A macro, as rsm_scan_set_uniform: it passes the caller's
 * sizeof(rsm_scan_t) and RSM_CONFIG_FINGERPRINT; RSM_ERR_CONFIG, out
 * untouched, for a caller compiled with other capacities than the library. */
#define rsm_sicklms_to_scan(raw, upside_down, out) \
    rsm_sicklms_to_scan_checked((raw), (upside_down), (out), sizeof(rsm_scan_t), (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_sicklms_to_scan_checked(const rsm_lms_scan_t *raw, uint8_t upside_down, rsm_scan_t *out, size_t out_size,
                                unsigned long fingerprint);

/* Runs the state machine once: at most one link read of at most
 * cfg->read_timeout_us (0: only what has already arrived; see
 * rsm_sicklms_next_deadline_us), then the timers. *ev receives the event (NONE if
 * nothing happened). Returns RSM_OK, RSM_ERR_INVAL (NULL pointers), or the
 * negative status of a failed read (ev NONE; the driver stays usable). */
int rsm_sicklms_poll(rsm_sicklms_t *d, rsm_sicklms_event_t *ev);

/* Clock time at which the driver next needs a poll even if nothing
 * arrives (a request's timeout, a pause's end, the stream's silence
 * check; now when received bytes are still unexamined); UINT64_MAX in
 * IDLE or for d NULL or never initialised. As rsm_p3dx_next_deadline_us:
 * one wait for all links. */
uint64_t rsm_sicklms_next_deadline_us(const rsm_sicklms_t *d);

/* Starts the shutdown described above, from any state but IDLE (a start-up
 * in progress is abandoned; the requests go out at the current rate).
 * Never blocks: later polls send the requests and, at the end, give a
 * DISCONNECTED event. In IDLE, or while already stopping, does nothing.
 * Returns RSM_OK or RSM_ERR_INVAL (d NULL or never initialised). */
int rsm_sicklms_disconnect(rsm_sicklms_t *d);

#ifdef __cplusplus
}
#endif

#endif /* RSM_SICKLMS_H */
