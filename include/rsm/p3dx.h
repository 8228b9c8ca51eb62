/* Pioneer P3-DX driver: the ARIA codec (rsm/aria.h) on an rsm_link_t.
 *
 * A non-blocking state machine driven by rsm_p3dx_poll. Each poll is the
 * cycle of rsm_link_poll (rsm/hal.h): it reads the link at most once, with
 * a timeout no longer than config.read_timeout_us (shorter when a deadline
 * is nearer), handles what arrived and the timers, and returns at most one
 * event. Deadlines are absolute times from the driver's clock, so it does
 * not matter how often poll is called.
 *
 * Connect (protocols.md 1.6): SYNC0 -> SYNC1 -> SYNC2, each reply awaited
 * step_timeout_us; a wrong reply restarts at SYNC0; a SIP or ENCODER packet
 * during the handshake means an old session is open: CLOSE, wait
 * close_wait_us, flush, restart. Then OPEN, optionally CONFIG (TicksMM,
 * RevCount, the watchdog and AutoBaud are taken from the CONFIGpac if it
 * arrives within config_timeout_us, else the config defaults stay), the
 * optional rate switch below, ENABLE 1, ENCODER 2. After sync_tries failed
 * attempts at one rate the next rate of the probe list (9600, 38400, 19200,
 * 115200, 57600) is tried, when probe_baud is set and the link has
 * set_baud.
 *
 * Rate switch (protocols.md 1.1, as ARIA does it): when host_baud is set,
 * the link can change rates, and the CONFIGpac reported AutoBaud 2, the
 * driver sends HOSTBAUD at the old rate, moves the link to host_baud, sends
 * a PULSE and waits up to baud_check_us for any packet at the new rate; if
 * none comes, the link goes back to the old rate. ARIA's parameter file for
 * the p3dx-sh asks for 38400; the library default is to stay at the
 * connect rate (host_baud 0).
 *
 * Session (after OPEN): one command at least every keepalive_us (PULSE when
 * nothing else went out), so that the robot's watchdog (protocols.md 1.7)
 * never stops it. Queued motion commands are sent by the next poll; while
 * motion is commanded the last motion command is re-sent every resend_us
 * (ARIA re-sends every 500 ms), so a command lost on the line costs at most
 * that long; a stop (STOP or zero speeds) is re-sent stop_repeats more times
 * and then the keep-alive goes back to PULSE. Connected, no SIP for
 * link_lost_us gives a LINK_LOST event, forgets the commanded motion (it is
 * never resumed by itself) and starts a new handshake from SYNC0.
 *
 * Disconnect (ARIA's order, with a STOP first): STOP and ENABLE 0 at once,
 * CLOSE disconnect_wait_us later, then a DISCONNECTED event and IDLE.
 *
 * All state is in the caller's rsm_p3dx_t; the driver keeps pointers to the
 * link, the clock and the config given to init, which must outlive it. One
 * driver must not be used from two contexts at once; distinct drivers are
 * independent. Nothing here is ISR-safe (it calls the link). */
#ifndef RSM_P3DX_H
#define RSM_P3DX_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/aria.h"
#include "rsm/hal.h"
#include "rsm/link_poll.h"
#include "rsm/odometry.h"
#include "rsm/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Runtime tuning. rsm_p3dx_config_default gives the values in brackets. */
typedef struct rsm_p3dx_config {
    uint32_t baud;               /* first line rate tried, bit/s [9600] */
    uint8_t probe_baud;          /* 1: try the other rates after sync_tries failures [1] */
    uint8_t sync_tries;          /* handshake attempts per rate, >= 1 [3] */
    uint8_t request_config;      /* 1: send CONFIG and wait for the CONFIGpac [1] */
    uint8_t enable_motors;       /* 1: send ENABLE 1 after connecting [1] */
    uint8_t request_encoder;     /* 1: send ENCODER 2 after connecting [1] */
    uint32_t read_timeout_us;    /* longest wait inside one poll; 0: never wait [10 000] */
    uint32_t step_timeout_us;    /* handshake reply timeout per step [1 000 000] */
    uint32_t close_wait_us;      /* wait after CLOSE of a stale session [200 000] */
    uint32_t config_timeout_us;  /* wait for the CONFIGpac [1 000 000] */
    uint32_t keepalive_us;       /* longest gap between commands [500 000] */
    uint32_t link_lost_us;       /* no SIP for this long = link lost [2 000 000];
                                    ARIA uses 8 s */
    uint32_t disconnect_wait_us; /* between ENABLE 0 and CLOSE [100 000] */
    uint32_t byte_timeout_us;    /* partial packet abandoned after this silence [100 000] */
    uint32_t host_baud;          /* rate to switch to with HOSTBAUD after connecting:
                                    9600, 19200, 38400, 57600 or 115200; 0 = stay [0] */
    uint32_t baud_check_us;      /* after HOSTBAUD, wait this long for a packet at the
                                    new rate, else go back [1 000 000] */
    uint32_t resend_us;          /* re-send the motion command this often while motion
                                    is commanded; 0 = never [500 000] */
    uint8_t stop_repeats;        /* re-sends of a stop command after the first [1] */
    uint16_t ticks_mm;           /* TicksMM until a CONFIGpac says otherwise [128] */
    uint16_t rev_count;          /* RevCount until a CONFIGpac says otherwise [0 = unknown] */
    uint16_t watchdog_ms;        /* robot watchdog until a CONFIGpac says otherwise [2000] */
} rsm_p3dx_config_t;

/* Fills *cfg with the defaults above. Returns RSM_OK or RSM_ERR_INVAL
 * (cfg NULL). Pure, reentrant. */
int rsm_p3dx_config_default(rsm_p3dx_config_t *cfg);

/* Driver states (d->state; read-only for the caller). */
typedef enum rsm_p3dx_state {
    RSM_P3DX_IDLE = 0,          /* not connected; rsm_p3dx_connect starts */
    RSM_P3DX_SYNC = 1,          /* handshake, awaiting reply to SYNC0..2 */
    RSM_P3DX_CLOSE_WAIT = 2,    /* CLOSE sent to a stale session */
    RSM_P3DX_CONFIG_WAIT = 3,   /* OPEN (and CONFIG) sent, awaiting CONFIGpac */
    RSM_P3DX_CONNECTED = 4,
    RSM_P3DX_DISCONNECTING = 5, /* STOP and ENABLE 0 sent, CLOSE follows */
    RSM_P3DX_BAUD_CHECK = 6,    /* HOSTBAUD sent, awaiting a packet at the new rate */
    RSM_P3DX_LISTENING = 7      /* listen-only (rsm_p3dx_listen): decodes, sends nothing */
} rsm_p3dx_state_t;

typedef enum rsm_p3dx_event_type {
    RSM_P3DX_EVENT_NONE = 0,
    RSM_P3DX_EVENT_CONNECTED = 1,    /* handshake done; d->robot, d->ticks_mm valid */
    RSM_P3DX_EVENT_ENCODER = 2,      /* encoder counts in ev->encoder */
    RSM_P3DX_EVENT_SIP = 3,          /* a standard SIP in *ev->sip */
    RSM_P3DX_EVENT_LINK_LOST = 4,    /* no SIP for link_lost_us; reconnecting */
    RSM_P3DX_EVENT_DISCONNECTED = 5  /* CLOSE sent after rsm_p3dx_disconnect */
} rsm_p3dx_event_type_t;

/* One encoder reading: the free-running counts as the odometry sample the
 * aligner takes (rsm_sync_encoder), and the step from the previous one. */
typedef struct rsm_p3dx_encoder {
    rsm_odometry_sample_t sample; /* left/right counts (the packet's 32-bit
                                     values as unsigned counters) and the clock
                                     time of the read that completed the packet */
    int32_t d_left;     /* left - previous left, modulo 2^32 (0 if !has_delta) */
    int32_t d_right;    /* right - previous right, modulo 2^32 */
    uint8_t has_delta;  /* 0 for the first packet of a connection */
} rsm_p3dx_encoder_t;

typedef struct rsm_p3dx_event {
    rsm_p3dx_event_type_t type;
    rsm_p3dx_encoder_t encoder;  /* ENCODER only, zero otherwise */
    const rsm_aria_sip_t *sip;   /* SIP only: points to d->sip, valid until
                                    the next poll; NULL otherwise */
    uint64_t stamp_us;           /* receive (or detection) time of the event */
} rsm_p3dx_event_t;

/* Counters; each wraps modulo 2^32. Framing errors (checksum, bad length,
 * truncated, skipped bytes) are in d->parser.stats. */
typedef struct rsm_p3dx_stats {
    uint32_t sync_replies;       /* SYNC0..2 replies accepted */
    uint32_t sips;               /* standard SIPs (0x32/0x33) decoded */
    uint32_t encoder_packets;    /* ENCODER packets decoded */
    uint32_t config_packets;     /* CONFIGpacs decoded */
    uint32_t unknown_packets;    /* verified packets of another or unexpected type,
                                    or that failed to decode */
    uint32_t handshake_timeouts; /* handshake steps without a reply */
    uint32_t handshake_restarts; /* wrong reply: restarted at SYNC0 */
    uint32_t stale_sessions;     /* SIPs during the handshake: CLOSE sent */
    uint32_t handshake_retries;  /* SYNC0 re-sent (after a timeout, restart, CLOSE) */
    uint32_t config_timeouts;    /* CONFIGpac did not come; defaults kept */
    uint32_t baud_changes;       /* set_baud calls made by probing */
    uint32_t connects;           /* handshakes completed */
    uint32_t link_lost;          /* LINK_LOST events */
    uint32_t reconnects;         /* handshakes completed after a link loss */
    uint32_t keepalives;         /* PULSEs sent while a session is open */
    uint32_t commands;           /* motion commands sent (VEL, RVEL, VEL2, STOP),
                                    re-sends included */
    uint32_t resends;            /* motion commands re-sent (each VEL + RVEL pair once) */
    uint32_t host_baud_switches; /* HOSTBAUD switches confirmed by a packet */
    uint32_t host_baud_failures; /* no packet at the new rate (or the link refused
                                    it): back at the old rate */
    uint32_t host_baud_skipped;  /* host_baud set but not possible: no CONFIGpac,
                                    AutoBaud not 2, or a link without set_baud */
    uint32_t write_errors;       /* link writes that failed */
    uint32_t read_errors;        /* link reads that failed */
} rsm_p3dx_stats_t;

/* What rsm_p3dx_init writes into rsm_p3dx_t.magic: the other functions
 * refuse a driver without it (never initialised, or zeroed). */
#define RSM_P3DX_MAGIC 0x52534d50UL

/* Driver state, caller owned (about 1 KB). Members are read-only for the
 * caller; stats, state, robot, sip, ticks_mm, rev_count, watchdog_ms,
 * auto_baud and baud may be read at any time. */
typedef struct rsm_p3dx {
    uint32_t magic;           /* RSM_P3DX_MAGIC once initialised */
    const rsm_p3dx_config_t *cfg;
    const rsm_link_t *link;
    const rsm_clock_t *clock;
    rsm_p3dx_state_t state;
    rsm_p3dx_stats_t stats;
    rsm_aria_parser_t parser;
    rsm_aria_sync2_t robot;   /* SYNC2 reply of the current connection */
    rsm_aria_sip_t sip;       /* last SIP */
    uint16_t ticks_mm;        /* from the CONFIGpac, else cfg->ticks_mm */
    uint16_t rev_count;       /* from the CONFIGpac, else cfg->rev_count */
    uint16_t watchdog_ms;     /* from the CONFIGpac, else cfg->watchdog_ms */
    uint8_t auto_baud;        /* AutoBaud of this connection's CONFIGpac (0 if none) */
    uint32_t baud;            /* current line rate */
    /* private */
    uint8_t step;             /* handshake step awaited, 0..2 */
    uint8_t tries;            /* failed attempts at this rate */
    uint8_t probe_idx;
    uint8_t lost;             /* a link loss is being recovered */
    uint8_t have_enc;
    uint32_t last_left;
    uint32_t last_right;
    uint64_t deadline_us;
    uint64_t last_tx_us;      /* last command of any kind */
    uint64_t last_sip_us;
    uint8_t pend_vel;         /* VEL + RVEL queued */
    uint8_t pend_vel2;
    uint8_t pend_stop;
    int16_t vel_mm_s;
    int16_t rvel_deg_s;
    int8_t vel2_left;
    int8_t vel2_right;
    uint8_t motion;           /* last motion command sent: none, VEL, VEL2, STOP */
    uint8_t stops_left;       /* stop re-sends still due */
    uint64_t last_motion_us;  /* when it was last sent */
    uint32_t prev_baud;       /* rate before HOSTBAUD, restored if the check fails */
    rsm_link_rx_t io;         /* link, clock and receive chunk (rsm_link_poll) */
    rsm_p3dx_event_t out;     /* the event of the poll in progress */
} rsm_p3dx_t;

/* Initialises d in the IDLE state with zero counters. link, clock and cfg
 * are kept by pointer and must outlive d. Nothing is sent.
 * Returns RSM_OK, or RSM_ERR_INVAL for NULL pointers, a link without read or
 * write, a clock without now_us, sync_tries 0, a zero
 * timeout, a host_baud HOSTBAUD cannot select, or host_baud with
 * baud_check_us 0 (d is then unchanged).
 * A macro, as rsm_localizer_init: it passes the caller's sizeof(rsm_p3dx_t)
 * and RSM_CONFIG_FINGERPRINT, so that a caller compiled with other
 * capacities than the library gets RSM_ERR_CONFIG, with d unchanged. */
#define rsm_p3dx_init(d, link, clock, cfg) \
    rsm_p3dx_init_checked((d), sizeof(rsm_p3dx_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (link), (clock), (cfg))

int rsm_p3dx_init_checked(rsm_p3dx_t *d, size_t d_size, unsigned long fingerprint, const rsm_link_t *link,
                          const rsm_clock_t *clock, const rsm_p3dx_config_t *cfg);

/* The functions below refuse d NULL or never initialised (no
 * RSM_P3DX_MAGIC: zeroed or stale memory) with RSM_ERR_INVAL
 * (rsm_p3dx_next_deadline_us: UINT64_MAX), touching nothing. */

/* Starts the handshake: puts the link at cfg->baud (where the link can
 * change rates; d->baud is then that rate) and sends SYNC0. Also restarts
 * it from any other state. Returns RSM_OK, RSM_ERR_INVAL (d NULL or never
 * initialised) or a link error from the write (the handshake still
 * proceeds: a timeout will resend). */
int rsm_p3dx_connect(rsm_p3dx_t *d);

/* Listen-only mode, from any state: the driver sends nothing, never
 * changes the link's rate and runs no timer; it decodes what arrives
 * (another program drives the robot, or a capture is replayed) and gives
 * SIP and ENCODER events exactly as when connected, stamped the same way
 * (the clock time right after the read that completed the packet); the
 * first ENCODER packet has has_delta 0. A CONFIGpac updates ticks_mm and
 * the rest as in a session. rsm_p3dx_connect leaves the mode,
 * rsm_p3dx_disconnect goes to IDLE (nothing sent). Received input is kept.
 * Returns RSM_OK or RSM_ERR_INVAL (d NULL or never initialised). */
int rsm_p3dx_listen(rsm_p3dx_t *d);

/* Runs the state machine once: at most one link read of at most
 * cfg->read_timeout_us (0: the read only takes what has already arrived,
 * so a caller waiting on several links at once never blocks here; see
 * rsm_p3dx_next_deadline_us), then the timers. *ev receives the event (type NONE
 * if nothing happened). Returns RSM_OK, RSM_ERR_INVAL (NULL pointers), or a
 * negative link status if the read failed (ev type NONE; the driver stays
 * usable). Never blocks longer than the read timeout plus the link's write
 * time. */
int rsm_p3dx_poll(rsm_p3dx_t *d, rsm_p3dx_event_t *ev);

/* Clock time (the driver's clock, microseconds) at which the driver next
 * needs a poll even if nothing arrives: a handshake step's timeout, the
 * keep-alive, a motion re-send, the link-loss check; the current time when
 * received bytes are still unexamined or a command is queued; UINT64_MAX
 * in IDLE or for d NULL or never initialised. A caller serving several
 * links waits until the earliest deadline of all or until bytes arrive,
 * then polls each driver (with read_timeout_us 0) until it gives no
 * event. */
uint64_t rsm_p3dx_next_deadline_us(const rsm_p3dx_t *d);

/* The robot's odometry geometry as this connection reported it: *cfg
 * (filled by the caller, e.g. with the localizer's current odometry
 * configuration, loc->odo.cfg) gets ticks_per_m_left/right = TicksMM * 1000
 * (d->ticks_mm: the CONFIGpac's, else config.ticks_mm) and counter_bits 32
 * (ENCODER packets carry 32-bit counts); the wheel base and the noise stay
 * (the CONFIGpac does not carry DiffConvFactor). For
 * rsm_localizer_set_odometry once a CONNECTED event came. Returns RSM_OK,
 * or RSM_ERR_INVAL (NULL pointers, or ticks_mm 0; *cfg untouched). */
int rsm_p3dx_odometry_config(const rsm_p3dx_t *d, rsm_odometry_config_t *cfg);

/* Queues VEL mm_s (|mm_s| <= 32767, mm/s) and RVEL deg_s (deg/s, CCW
 * positive); the next poll sends them while connected, and they are re-sent
 * every resend_us until another motion command (zero speeds count as a
 * stop). Replaces a queued VEL2 or STOP. Returns RSM_OK, RSM_ERR_INVAL or
 * RSM_ERR_RANGE (nothing queued). */
int rsm_p3dx_set_vel(rsm_p3dx_t *d, int32_t mm_s, int32_t deg_s);

/* Queues VEL2 with wheel speeds in Vel2Divisor units (20 mm/s), each in
 * [-127, 127], re-sent like VEL. Replaces a queued VEL/RVEL or STOP.
 * Returns RSM_OK, RSM_ERR_INVAL or RSM_ERR_RANGE (nothing queued). */
int rsm_p3dx_set_vel2(rsm_p3dx_t *d, int32_t left, int32_t right);

/* Queues STOP and drops queued velocity commands. RSM_OK or RSM_ERR_INVAL. */
int rsm_p3dx_stop(rsm_p3dx_t *d);

/* Starts an orderly disconnect while a session is open (CONFIG_WAIT,
 * BAUD_CHECK, CONNECTED): STOP and ENABLE 0 now, CLOSE after
 * disconnect_wait_us, then a DISCONNECTED event and IDLE; queued and
 * commanded motion is forgotten. In any other state goes to IDLE at once
 * (no event). Returns RSM_OK, RSM_ERR_INVAL or a write error (the sequence
 * still proceeds). */
int rsm_p3dx_disconnect(rsm_p3dx_t *d);

#ifdef __cplusplus
}
#endif

#endif /* RSM_P3DX_H */
