#include "rsm/p3dx.h"

#include <string.h>

#include "core/check.h"

/* Rates tried in turn when the robot does not answer (p2os's order). */
static const uint32_t probe_rates[5] = {9600u, 38400u, 19200u, 115200u, 57600u};
#define N_PROBE_RATES 5u

/* d->motion: the last motion command sent. */
#define MOTION_NONE 0u
#define MOTION_VEL 1u
#define MOTION_VEL2 2u
#define MOTION_STOP 3u

int rsm_p3dx_config_default(rsm_p3dx_config_t *cfg)
{
    if (cfg == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->baud = 9600u;
    cfg->probe_baud = 1u;
    cfg->sync_tries = 3u;
    cfg->request_config = 1u;
    cfg->enable_motors = 1u;
    cfg->request_encoder = 1u;
    cfg->read_timeout_us = 10000u;
    cfg->step_timeout_us = 1000000u;
    cfg->close_wait_us = 200000u;
    cfg->config_timeout_us = 1000000u;
    cfg->keepalive_us = 500000u;
    cfg->link_lost_us = 2000000u;
    cfg->disconnect_wait_us = 100000u;
    cfg->byte_timeout_us = 100000u;
    cfg->host_baud = 0u;
    cfg->baud_check_us = 1000000u;
    cfg->resend_us = 500000u;
    cfg->stop_repeats = 1u;
    cfg->ticks_mm = 128u;
    cfg->rev_count = 0u;
    cfg->watchdog_ms = 2000u;
    return RSM_OK;
}

static int send_frame(rsm_p3dx_t *d, const uint8_t *buf, int n, uint64_t now)
{
    int st;
    if (n < 0) {
        return n;
    }
    st = rsm_link_write_all(d->link, buf, (size_t)n, NULL);
    /* A failed write is an attempt too: the keep-alive clock moves on, or a
     * dead link would get a PULSE on every poll. */
    d->last_tx_us = now;
    if (st != RSM_OK) {
        d->stats.write_errors++;
        return st;
    }
    return RSM_OK;
}

/* Drops held input: the link's buffer, our chunk and the parser's partial
 * packet. The parser's counters survive (they are cumulative). */
static void drop_input(rsm_p3dx_t *d)
{
    rsm_aria_parser_stats_t keep = d->parser.stats;
    rsm_link_rx_drop(&d->io);
    (void)rsm_aria_parser_init(&d->parser);
    d->parser.stats = keep;
}

static void send_sync(rsm_p3dx_t *d, uint8_t step, uint64_t now)
{
    uint8_t buf[8];
    int n;
    if (step == 0u) {
        n = rsm_aria_encode_sync0(buf, sizeof buf);
    } else if (step == 1u) {
        n = rsm_aria_encode_sync1(buf, sizeof buf);
    } else {
        n = rsm_aria_encode_sync2(buf, sizeof buf);
    }
    d->step = step;
    d->state = RSM_P3DX_SYNC;
    d->deadline_us = now + d->cfg->step_timeout_us;
    (void)send_frame(d, buf, n, now);
}

/* Back to SYNC0 after a failed attempt, moving to the next rate once this
 * one has had its sync_tries. */
static void restart_handshake(rsm_p3dx_t *d, uint64_t now)
{
    d->stats.handshake_retries++;
    d->tries++;
    if (d->tries >= d->cfg->sync_tries) {
        d->tries = 0u;
        if (d->cfg->probe_baud && d->link->set_baud != NULL) {
            d->probe_idx = (uint8_t)((d->probe_idx + 1u) % N_PROBE_RATES);
            if (rsm_link_set_baud(d->link, probe_rates[d->probe_idx]) == RSM_OK) {
                d->baud = probe_rates[d->probe_idx];
                d->stats.baud_changes++;
            }
        }
    }
    drop_input(d);
    send_sync(d, 0u, now);
}

/* Forgets queued and commanded motion (a new session starts at rest). */
static void forget_motion(rsm_p3dx_t *d)
{
    d->pend_stop = 0u;
    d->pend_vel = 0u;
    d->pend_vel2 = 0u;
    d->motion = MOTION_NONE;
    d->stops_left = 0u;
}

static void begin_handshake(rsm_p3dx_t *d, uint64_t now)
{
    size_t i;
    d->tries = 0u;
    d->have_enc = 0u;
    d->auto_baud = 0u;
    forget_motion(d);
    for (i = 0u; i < N_PROBE_RATES; i++) {
        if (probe_rates[i] == d->baud) {
            d->probe_idx = (uint8_t)i;
        }
    }
    drop_input(d);
    send_sync(d, 0u, now);
}

int rsm_p3dx_init_checked(rsm_p3dx_t *d, size_t d_size, unsigned long fingerprint, const rsm_link_t *link,
                          const rsm_clock_t *clock, const rsm_p3dx_config_t *cfg)
{
    rsm_link_rx_t io;
    if (!RSM_SAME_BUILD(rsm_p3dx_t, d_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (d == NULL || cfg == NULL ||
        rsm_link_rx_init(&io, link, clock, cfg->read_timeout_us, cfg->byte_timeout_us) != RSM_OK ||
        cfg->sync_tries == 0u || cfg->step_timeout_us == 0u || cfg->keepalive_us == 0u ||
        cfg->link_lost_us == 0u || cfg->baud == 0u ||
        (cfg->host_baud != 0u &&
         (rsm_aria_baud_code(cfg->host_baud) < 0 || cfg->baud_check_us == 0u))) {
        return RSM_ERR_INVAL;
    }
    memset(d, 0, sizeof *d);
    d->magic = (uint32_t)RSM_P3DX_MAGIC;
    d->cfg = cfg;
    d->link = link;
    d->clock = clock;
    d->io = io;
    d->state = RSM_P3DX_IDLE;
    (void)rsm_aria_parser_init(&d->parser);
    d->ticks_mm = cfg->ticks_mm;
    d->rev_count = cfg->rev_count;
    d->watchdog_ms = cfg->watchdog_ms;
    d->baud = cfg->baud;
    return RSM_OK;
}

/* Whether rsm_p3dx_init set d up (not for NULL, zeroed or stale memory). */
static int ready(const rsm_p3dx_t *d)
{
    return d != NULL && d->magic == (uint32_t)RSM_P3DX_MAGIC && d->cfg != NULL;
}

int rsm_p3dx_connect(rsm_p3dx_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    d->lost = 0u;
    /* The line may be at any rate (a previous session's HOSTBAUD, a probe):
     * start where the configuration says. */
    if (rsm_link_set_baud(d->link, d->cfg->baud) == RSM_OK) {
        d->baud = d->cfg->baud;
    }
    begin_handshake(d, rsm_link_rx_now(&d->io));
    return RSM_OK;
}

int rsm_p3dx_listen(rsm_p3dx_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    forget_motion(d);
    d->have_enc = 0u;
    d->lost = 0u;
    d->state = RSM_P3DX_LISTENING;
    return RSM_OK;
}

/* OPEN was acknowledged by the SYNC2 reply: start the session. */
static void open_session(rsm_p3dx_t *d, uint64_t now)
{
    uint8_t buf[12];
    (void)send_frame(d, buf, rsm_aria_encode_open_int1(buf, sizeof buf), now);
    d->last_sip_us = now;
    d->state = RSM_P3DX_CONFIG_WAIT;
    d->deadline_us = now;
    if (d->cfg->request_config) {
        (void)send_frame(d, buf, rsm_aria_encode_config(buf, sizeof buf), now);
        d->deadline_us = now + d->cfg->config_timeout_us;
    }
}

static void finish_connect(rsm_p3dx_t *d, uint64_t now)
{
    uint8_t buf[12];
    if (d->cfg->enable_motors) {
        (void)send_frame(d, buf, rsm_aria_encode_enable(1, buf, sizeof buf), now);
    }
    if (d->cfg->request_encoder) {
        (void)send_frame(d, buf, rsm_aria_encode_encoder(1, buf, sizeof buf), now);
    }
    d->state = RSM_P3DX_CONNECTED;
    d->last_sip_us = now;
    d->tries = 0u;
    d->stats.connects++;
    if (d->lost) {
        d->stats.reconnects++;
        d->lost = 0u;
    }
    d->out.type = RSM_P3DX_EVENT_CONNECTED;
    d->out.stamp_us = now;
}

/* The CONFIGpac came or its wait ended: switch rates with HOSTBAUD when
 * asked for and possible (as ARIA: only when the robot reported AutoBaud
 * 2), else finish the connection. */
static void after_config(rsm_p3dx_t *d, uint64_t now)
{
    uint8_t buf[12];
    const uint32_t target = d->cfg->host_baud;
    if (target == 0u || target == d->baud) {
        finish_connect(d, now);
        return;
    }
    if (d->auto_baud != 2u || d->link->set_baud == NULL) {
        d->stats.host_baud_skipped++;
        finish_connect(d, now);
        return;
    }
    /* The command leaves at the old rate (set_baud drains pending output
     * first, hal.h), then both ends move. */
    (void)send_frame(d, buf,
                     rsm_aria_encode_hostbaud((uint8_t)rsm_aria_baud_code(target), buf, sizeof buf),
                     now);
    if (rsm_link_set_baud(d->link, target) != RSM_OK) {
        d->stats.host_baud_failures++;
        finish_connect(d, now);
        return;
    }
    d->prev_baud = d->baud;
    d->baud = target;
    drop_input(d);
    (void)send_frame(d, buf, rsm_aria_encode_pulse(buf, sizeof buf), now);
    d->state = RSM_P3DX_BAUD_CHECK;
    d->deadline_us = now + d->cfg->baud_check_us;
}

static int is_session_packet(uint8_t id)
{
    return (id & 0xF0u) == 0x30u || id == RSM_ARIA_PAC_ENCODER;
}

static void handle_handshake_packet(rsm_p3dx_t *d, const rsm_aria_packet_t *pkt, uint64_t now)
{
    uint8_t buf[12];
    /* A packet that verified proves the rate right: whatever restart
     * follows, it is not a reason to probe other rates. */
    d->tries = 0u;
    if (is_session_packet(pkt->id)) {
        /* An old session is still streaming: close it, let its last packets
         * drain, then start again (ARIA and p2os do the same). */
        d->stats.stale_sessions++;
        (void)send_frame(d, buf, rsm_aria_encode_close_int1(buf, sizeof buf), now);
        d->state = RSM_P3DX_CLOSE_WAIT;
        d->deadline_us = now + d->cfg->close_wait_us;
        return;
    }
    if (pkt->id > RSM_ARIA_PAC_SYNC2) {
        d->stats.unknown_packets++;
        return;
    }
    if (pkt->id != d->step) {
        d->stats.handshake_restarts++;
        restart_handshake(d, now);
        return;
    }
    d->stats.sync_replies++;
    if (d->step < 2u) {
        send_sync(d, (uint8_t)(d->step + 1u), now);
        return;
    }
    if (rsm_aria_decode_sync2(pkt, &d->robot) != RSM_OK) {
        memset(&d->robot, 0, sizeof d->robot);
    }
    open_session(d, now);
}

static void handle_encoder(rsm_p3dx_t *d, const rsm_aria_packet_t *pkt)
{
    rsm_p3dx_event_t *ev = &d->out;
    rsm_aria_encoder_t enc;
    if (rsm_aria_decode_encoder(pkt, &enc) != RSM_OK) {
        d->stats.unknown_packets++;
        return;
    }
    d->stats.encoder_packets++;
    ev->type = RSM_P3DX_EVENT_ENCODER;
    ev->stamp_us = d->io.stamp_us;
    /* Two's complement on the wire: the same bits as an unsigned counter. */
    ev->encoder.sample.left = (uint32_t)enc.left;
    ev->encoder.sample.right = (uint32_t)enc.right;
    ev->encoder.sample.stamp_us = d->io.stamp_us;
    if (d->have_enc) {
        ev->encoder.d_left = rsm_odometry_count_delta(ev->encoder.sample.left, d->last_left, 32u);
        ev->encoder.d_right = rsm_odometry_count_delta(ev->encoder.sample.right, d->last_right, 32u);
        ev->encoder.has_delta = 1u;
    }
    d->last_left = ev->encoder.sample.left;
    d->last_right = ev->encoder.sample.right;
    d->have_enc = 1u;
}

static void handle_config(rsm_p3dx_t *d, const rsm_aria_packet_t *pkt)
{
    /* Only a few fields are kept, so the decoded CONFIGpac (a few hundred
     * bytes) lives on the stack for this call instead of in the state. */
    rsm_aria_config_t c;
    if (rsm_aria_decode_config(pkt, &c) != RSM_OK) {
        d->stats.unknown_packets++;
        return;
    }
    d->stats.config_packets++;
    if (c.ticks_mm != 0u) {
        d->ticks_mm = c.ticks_mm;
    }
    if (c.rev_count != 0u) {
        d->rev_count = c.rev_count;
    }
    if (c.watchdog != 0u) {
        d->watchdog_ms = c.watchdog;
    }
    d->auto_baud = c.auto_baud;
}

/* A packet while a session is open (CONFIG_WAIT, BAUD_CHECK, CONNECTED,
 * DISCONNECTING) or while listening. Only CONNECTED and LISTENING give SIP
 * and ENCODER events. */
static void handle_session_packet(rsm_p3dx_t *d, const rsm_aria_packet_t *pkt, uint64_t now)
{
    const rsm_p3dx_state_t before = d->state;
    const int events = before == RSM_P3DX_CONNECTED || before == RSM_P3DX_LISTENING;
    if (pkt->id == RSM_ARIA_PAC_SIP_STOPPED || pkt->id == RSM_ARIA_PAC_SIP_MOVING) {
        if (rsm_aria_decode_sip(pkt, &d->sip) != RSM_OK) {
            d->stats.unknown_packets++;
        } else {
            d->stats.sips++;
            d->last_sip_us = d->io.stamp_us;
            if (events) {
                d->out.type = RSM_P3DX_EVENT_SIP;
                d->out.sip = &d->sip;
                d->out.stamp_us = d->io.stamp_us;
            }
        }
    } else if (pkt->id == RSM_ARIA_PAC_ENCODER) {
        if (events) {
            handle_encoder(d, pkt);
        } else {
            d->stats.unknown_packets++;
        }
    } else if (pkt->id == RSM_ARIA_PAC_CONFIG) {
        handle_config(d, pkt);
        if (before == RSM_P3DX_CONFIG_WAIT) {
            after_config(d, now);
        }
    } else {
        d->stats.unknown_packets++;
    }
    if (before == RSM_P3DX_BAUD_CHECK) {
        /* Any packet that verified at the new rate proves both ends moved. */
        d->stats.host_baud_switches++;
        finish_connect(d, now);
    }
}

static void handle_packet(rsm_p3dx_t *d, const rsm_aria_packet_t *pkt, uint64_t now)
{
    switch (d->state) {
    case RSM_P3DX_SYNC:
        handle_handshake_packet(d, pkt, now);
        break;
    case RSM_P3DX_CONFIG_WAIT:
    case RSM_P3DX_BAUD_CHECK:
    case RSM_P3DX_CONNECTED:
    case RSM_P3DX_DISCONNECTING:
    case RSM_P3DX_LISTENING:
        handle_session_packet(d, pkt, now);
        break;
    case RSM_P3DX_IDLE:
    case RSM_P3DX_CLOSE_WAIT:
    default:
        /* Nobody is listening: packets of a closing session are dropped. */
        break;
    }
}

/* rsm_link_poll step 1/4: feeds the held bytes until a packet yields an
 * event or the chunk is used up. */
static int drain_cb(void *drv, uint64_t now)
{
    rsm_p3dx_t *d = (rsm_p3dx_t *)drv;
    rsm_aria_packet_t pkt;
    for (;;) {
        size_t used = 0u;
        const int r = rsm_aria_parser_feed(&d->parser, d->io.buf + d->io.off,
                                           d->io.len - d->io.off, &used, &pkt);
        if (r < 0) {
            d->io.off = d->io.len;
            return 0;
        }
        d->io.off += used;
        if (r == 0) {
            return 0;
        }
        handle_packet(d, &pkt, now);
        if (d->out.type != RSM_P3DX_EVENT_NONE) {
            return 1;
        }
    }
}

/* rsm_link_poll step 4, on silence: a packet cut short is abandoned, then
 * what it held is looked at again. */
static int silence_cb(void *drv, uint64_t now)
{
    rsm_p3dx_t *d = (rsm_p3dx_t *)drv;
    if (rsm_aria_parser_pending(&d->parser) == 0u) {
        return 0;
    }
    (void)rsm_aria_parser_timeout(&d->parser);
    d->io.off = d->io.len;
    return drain_cb(d, now);
}

static int is_stop_motion(const rsm_p3dx_t *d)
{
    return d->motion == MOTION_STOP ||
           (d->motion == MOTION_VEL && d->vel_mm_s == 0 && d->rvel_deg_s == 0) ||
           (d->motion == MOTION_VEL2 && d->vel2_left == 0 && d->vel2_right == 0);
}

/* Sends the motion command d->motion describes. */
static void send_motion(rsm_p3dx_t *d, uint64_t now)
{
    uint8_t buf[12];
    if (d->motion == MOTION_STOP) {
        d->stats.commands++;
        (void)send_frame(d, buf, rsm_aria_encode_stop(buf, sizeof buf), now);
    } else if (d->motion == MOTION_VEL) {
        d->stats.commands += 2u;
        (void)send_frame(d, buf, rsm_aria_encode_vel(d->vel_mm_s, buf, sizeof buf), now);
        (void)send_frame(d, buf, rsm_aria_encode_rvel(d->rvel_deg_s, buf, sizeof buf), now);
    } else if (d->motion == MOTION_VEL2) {
        d->stats.commands++;
        (void)send_frame(d, buf,
                         rsm_aria_encode_vel2(d->vel2_left, d->vel2_right, buf, sizeof buf), now);
    }
    d->last_motion_us = now;
}

/* Sends a queued motion command, or re-sends the commanded one when due. */
static void run_motion(rsm_p3dx_t *d, uint64_t now)
{
    if (d->pend_stop || d->pend_vel || d->pend_vel2) {
        d->motion = d->pend_stop ? MOTION_STOP : d->pend_vel ? MOTION_VEL : MOTION_VEL2;
        d->pend_stop = 0u;
        d->pend_vel = 0u;
        d->pend_vel2 = 0u;
        d->stops_left = d->cfg->stop_repeats;
        send_motion(d, now);
        return;
    }
    if (d->motion == MOTION_NONE || d->cfg->resend_us == 0u ||
        now - d->last_motion_us < d->cfg->resend_us) {
        return;
    }
    if (is_stop_motion(d)) {
        if (d->stops_left == 0u) {
            d->motion = MOTION_NONE; /* stopped for sure: PULSEs from now on */
            return;
        }
        d->stops_left--;
    }
    d->stats.resends++;
    send_motion(d, now);
}

/* One command at least every keepalive_us while a session is open. */
static void keep_alive(rsm_p3dx_t *d, uint64_t now)
{
    uint8_t buf[8];
    if (now - d->last_tx_us >= d->cfg->keepalive_us) {
        d->stats.keepalives++;
        (void)send_frame(d, buf, rsm_aria_encode_pulse(buf, sizeof buf), now);
    }
}

/* rsm_link_poll steps 2 and 5. */
static int timers_cb(void *drv, uint64_t now)
{
    rsm_p3dx_t *d = (rsm_p3dx_t *)drv;
    uint8_t buf[12];
    switch (d->state) {
    case RSM_P3DX_SYNC:
        if (now >= d->deadline_us) {
            d->stats.handshake_timeouts++;
            restart_handshake(d, now);
        }
        break;
    case RSM_P3DX_CLOSE_WAIT:
        if (now >= d->deadline_us) {
            restart_handshake(d, now);
        }
        break;
    case RSM_P3DX_CONFIG_WAIT:
        if (now >= d->deadline_us) {
            if (d->cfg->request_config) {
                d->stats.config_timeouts++;
            }
            after_config(d, now);
        } else {
            keep_alive(d, now);
        }
        break;
    case RSM_P3DX_BAUD_CHECK:
        if (now >= d->deadline_us) {
            /* Nothing verified at the new rate: go back (as ARIA does). A
             * robot that did switch is found again by the link-loss path. */
            d->stats.host_baud_failures++;
            if (rsm_link_set_baud(d->link, d->prev_baud) == RSM_OK) {
                d->baud = d->prev_baud;
            }
            drop_input(d);
            finish_connect(d, now);
        } else {
            keep_alive(d, now);
        }
        break;
    case RSM_P3DX_CONNECTED:
        if (now - d->last_sip_us >= d->cfg->link_lost_us) {
            d->stats.link_lost++;
            d->lost = 1u;
            d->out.type = RSM_P3DX_EVENT_LINK_LOST;
            d->out.stamp_us = now;
            begin_handshake(d, now);
            break;
        }
        run_motion(d, now);
        keep_alive(d, now);
        break;
    case RSM_P3DX_DISCONNECTING:
        if (now >= d->deadline_us) {
            (void)send_frame(d, buf, rsm_aria_encode_close_int1(buf, sizeof buf), now);
            d->state = RSM_P3DX_IDLE;
            d->out.type = RSM_P3DX_EVENT_DISCONNECTED;
            d->out.stamp_us = now;
        }
        break;
    case RSM_P3DX_IDLE:
    default:
        break;
    }
    return d->out.type != RSM_P3DX_EVENT_NONE;
}

static uint64_t earlier(uint64_t a, uint64_t b)
{
    return a < b ? a : b;
}

/* rsm_link_poll: time until the next timer of the current state fires. */
static uint64_t until_due_cb(const void *drv, uint64_t now)
{
    const rsm_p3dx_t *d = (const rsm_p3dx_t *)drv;
    const uint64_t ka = d->last_tx_us + d->cfg->keepalive_us;
    uint64_t due;
    switch (d->state) {
    case RSM_P3DX_SYNC:
    case RSM_P3DX_CLOSE_WAIT:
    case RSM_P3DX_DISCONNECTING:
        due = d->deadline_us;
        break;
    case RSM_P3DX_CONFIG_WAIT:
    case RSM_P3DX_BAUD_CHECK:
        due = earlier(d->deadline_us, ka);
        break;
    case RSM_P3DX_CONNECTED:
        due = earlier(ka, d->last_sip_us + d->cfg->link_lost_us);
        if (d->pend_stop || d->pend_vel || d->pend_vel2) {
            due = now;
        } else if (d->motion != MOTION_NONE && d->cfg->resend_us != 0u) {
            due = earlier(due, d->last_motion_us + d->cfg->resend_us);
        }
        break;
    case RSM_P3DX_IDLE:
    case RSM_P3DX_LISTENING:
    default:
        return UINT64_MAX;
    }
    return due > now ? due - now : 0u;
}

static const rsm_link_poll_ops_t p3dx_poll_ops = {drain_cb, timers_cb, until_due_cb, silence_cb};

uint64_t rsm_p3dx_next_deadline_us(const rsm_p3dx_t *d)
{
    return !ready(d) ? UINT64_MAX : rsm_link_next_deadline(&d->io, &p3dx_poll_ops, d);
}

int rsm_p3dx_odometry_config(const rsm_p3dx_t *d, rsm_odometry_config_t *cfg)
{
    if (!ready(d) || cfg == NULL || d->ticks_mm == 0u) {
        return RSM_ERR_INVAL;
    }
    cfg->ticks_per_m_left = (float)d->ticks_mm * 1000.0f;
    cfg->ticks_per_m_right = cfg->ticks_per_m_left;
    cfg->counter_bits = 32u;
    return RSM_OK;
}

int rsm_p3dx_poll(rsm_p3dx_t *d, rsm_p3dx_event_t *ev)
{
    int st;
    if (!ready(d) || ev == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(&d->out, 0, sizeof d->out);
    st = rsm_link_poll(&d->io, &p3dx_poll_ops, d);
    if (st < 0) {
        d->stats.read_errors++;
    }
    *ev = d->out;
    return st;
}

int rsm_p3dx_set_vel(rsm_p3dx_t *d, int32_t mm_s, int32_t deg_s)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    if (mm_s < -RSM_ARIA_INT_MAX || mm_s > RSM_ARIA_INT_MAX || deg_s < -RSM_ARIA_INT_MAX ||
        deg_s > RSM_ARIA_INT_MAX) {
        return RSM_ERR_RANGE;
    }
    d->vel_mm_s = (int16_t)mm_s;
    d->rvel_deg_s = (int16_t)deg_s;
    d->pend_vel = 1u;
    d->pend_vel2 = 0u;
    d->pend_stop = 0u;
    return RSM_OK;
}

int rsm_p3dx_set_vel2(rsm_p3dx_t *d, int32_t left, int32_t right)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    if (left < -RSM_ARIA_VEL2_MAX || left > RSM_ARIA_VEL2_MAX || right < -RSM_ARIA_VEL2_MAX ||
        right > RSM_ARIA_VEL2_MAX) {
        return RSM_ERR_RANGE;
    }
    d->vel2_left = (int8_t)left;
    d->vel2_right = (int8_t)right;
    d->pend_vel2 = 1u;
    d->pend_vel = 0u;
    d->pend_stop = 0u;
    return RSM_OK;
}

int rsm_p3dx_stop(rsm_p3dx_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    d->pend_stop = 1u;
    d->pend_vel = 0u;
    d->pend_vel2 = 0u;
    return RSM_OK;
}

int rsm_p3dx_disconnect(rsm_p3dx_t *d)
{
    uint8_t buf[12];
    uint64_t now;
    int st;
    int st2;
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    now = rsm_link_rx_now(&d->io);
    forget_motion(d);
    if (d->state != RSM_P3DX_CONNECTED && d->state != RSM_P3DX_CONFIG_WAIT &&
        d->state != RSM_P3DX_BAUD_CHECK) {
        d->state = RSM_P3DX_IDLE;
        return RSM_OK;
    }
    d->state = RSM_P3DX_DISCONNECTING;
    d->deadline_us = now + d->cfg->disconnect_wait_us;
    d->stats.commands++;
    st = send_frame(d, buf, rsm_aria_encode_stop(buf, sizeof buf), now);
    st2 = send_frame(d, buf, rsm_aria_encode_enable(0, buf, sizeof buf), now);
    return st != RSM_OK ? st : st2;
}
