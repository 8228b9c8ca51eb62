#include "rsm/sicklms.h"

#include <string.h>

#include "core/check.h"

/* Start-up steps, in order. */
#define STEP_PROBE 0u   /* 0x20 0x25 at a candidate rate */
#define STEP_BAUD 1u    /* 0x20 0x40/0x41/0x42 */
#define STEP_VARIANT 2u /* 0x3B */
#define STEP_CONFIG 3u  /* 0x74 */
#define STEP_STREAM 4u  /* 0x20 0x24 */
/* Shutdown steps, in order. */
#define STEP_STOP 5u    /* 0x20 0x25 */
#define STEP_RESTORE 6u /* 0x20 0x42/0x41/0x40 back to the power-up rate */

/* What the request in flight waits for. */
#define SUB_ACK 0u
#define SUB_REPLY 1u
#define SUB_NAK_WAIT 2u

static const uint32_t probe_rates[3] = {9600u, 38400u, 19200u};
#define N_RATES 3u

#define PI_F 3.14159265358979f

static int rate_index(uint32_t baud)
{
    size_t i;
    for (i = 0u; i < N_RATES; i++) {
        if (probe_rates[i] == baud) {
            return (int)i;
        }
    }
    return -1;
}

int rsm_sicklms_config_default(rsm_sicklms_config_t *cfg)
{
    if (cfg == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->address = 0u;
    cfg->power_up_baud = 9600u;
    cfg->baud = 38400u;
    cfg->probe = 1u;
    cfg->angle_deg = 180u;
    cfg->resolution_cdeg = 100u;
    cfg->upside_down = 0u;
    cfg->max_tries = 3u;
    cfg->read_timeout_us = 10000u;
    cfg->ack_timeout_us = 200000u;
    cfg->reply_timeout_us = 1000000u;
    cfg->mode_timeout_us = 3000000u;
    cfg->nak_wait_us = 30000u;
    cfg->baud_settle_us = 250000u;
    cfg->retry_wait_us = 1000000u;
    cfg->stream_timeout_us = 1000000u;
    cfg->byte_timeout_us = 100000u;
    cfg->latency_us = 0u;
    cfg->read_config = 1u;
    (void)rsm_lms_b0_format_default(&cfg->format);
    return RSM_OK;
}

int rsm_sicklms_init_checked(rsm_sicklms_t *d, size_t d_size, unsigned long fingerprint, const rsm_link_t *link,
                             const rsm_clock_t *clock, const rsm_sicklms_config_t *cfg, rsm_scan_t *scan)
{
    uint8_t probe[16];
    rsm_link_rx_t io;
    if (!RSM_SAME_BUILD(rsm_sicklms_t, d_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (d == NULL || cfg == NULL || scan == NULL ||
        rsm_link_rx_init(&io, link, clock, cfg->read_timeout_us, cfg->byte_timeout_us) != RSM_OK ||
        cfg->ack_timeout_us == 0u || cfg->reply_timeout_us == 0u || cfg->mode_timeout_us == 0u ||
        cfg->max_tries == 0u || cfg->address > 0x7Fu || rate_index(cfg->power_up_baud) < 0 ||
        (cfg->baud != 0u && rate_index(cfg->baud) < 0) ||
        rsm_lms_encode_variant(probe, sizeof probe, cfg->address, cfg->angle_deg,
                               cfg->resolution_cdeg) < 0) {
        return RSM_ERR_INVAL;
    }
    memset(d, 0, sizeof *d);
    d->magic = (uint32_t)RSM_SICKLMS_MAGIC;
    d->cfg = cfg;
    d->link = link;
    d->clock = clock;
    d->scan = scan;
    d->io = io;
    d->state = RSM_SICKLMS_IDLE;
    d->baud = cfg->power_up_baud;
    d->format = cfg->format;
    (void)rsm_lms_parser_init(&d->parser);
    return RSM_OK;
}

/* Drops received input (link buffer, our chunk, the parser's bytes). */
static void drop_input(rsm_sicklms_t *d)
{
    rsm_link_rx_drop(&d->io);
    (void)rsm_lms_parser_flush(&d->parser);
}

static void send_request(rsm_sicklms_t *d, uint64_t now)
{
    if (rsm_link_write_all(d->link, d->req, d->req_len, NULL) != RSM_OK) {
        d->stats.write_errors++;
    }
    d->tries++;
    d->sub = SUB_ACK;
    d->deadline_us = now + d->cfg->ack_timeout_us;
}

/* Builds and sends the request of a start-up or shutdown step. */
static void start_step(rsm_sicklms_t *d, uint8_t step, uint64_t now)
{
    const rsm_sicklms_config_t *c = d->cfg;
    int n;
    switch (step) {
    case STEP_PROBE:
        n = rsm_lms_encode_mode(d->req, sizeof d->req, c->address, RSM_LMS_MODE_ON_REQUEST);
        d->req_reply = RSM_LMS_REPLY_MODE;
        d->stats.probes++;
        break;
    case STEP_BAUD:
        n = rsm_lms_encode_mode_baud(d->req, sizeof d->req, c->address, c->baud);
        d->req_reply = RSM_LMS_REPLY_MODE;
        break;
    case STEP_VARIANT:
        n = rsm_lms_encode_variant(d->req, sizeof d->req, c->address, c->angle_deg,
                                   c->resolution_cdeg);
        d->req_reply = RSM_LMS_REPLY_VARIANT;
        break;
    case STEP_CONFIG:
        n = rsm_lms_encode_request_config(d->req, sizeof d->req, c->address);
        d->req_reply = RSM_LMS_REPLY_CONFIG;
        break;
    case STEP_STOP:
        n = rsm_lms_encode_mode(d->req, sizeof d->req, c->address, RSM_LMS_MODE_ON_REQUEST);
        d->req_reply = RSM_LMS_REPLY_MODE;
        break;
    case STEP_RESTORE:
        n = rsm_lms_encode_mode_baud(d->req, sizeof d->req, c->address, c->power_up_baud);
        d->req_reply = RSM_LMS_REPLY_MODE;
        break;
    case STEP_STREAM:
    default:
        n = rsm_lms_encode_mode(d->req, sizeof d->req, c->address, RSM_LMS_MODE_CONTINUOUS);
        d->req_reply = RSM_LMS_REPLY_MODE;
        step = STEP_STREAM;
        break;
    }
    d->req_len = n > 0 ? (size_t)n : 0u;
    d->step = step;
    d->tries = 0u;
    d->state = step >= STEP_STOP ? RSM_SICKLMS_STOPPING : RSM_SICKLMS_STARTING;
    send_request(d, now);
}

/* Sets the link to probe_rates[idx] and probes there. */
static void probe_at(rsm_sicklms_t *d, uint8_t idx, uint64_t now)
{
    d->probe_idx = idx;
    if (probe_rates[idx] != d->baud && rsm_link_set_baud(d->link, probe_rates[idx]) == RSM_OK) {
        d->baud = probe_rates[idx];
        d->stats.baud_changes++;
    }
    drop_input(d);
    start_step(d, STEP_PROBE, now);
}

/* A new probe round starting at rate first (the current rate when the link
 * cannot change rates). */
static void begin_probing(rsm_sicklms_t *d, uint32_t first, uint64_t now)
{
    int idx = rate_index(first);
    if (idx < 0 || d->link->set_baud == NULL) {
        idx = rate_index(d->baud);
    }
    if (idx < 0) {
        idx = 0;
    }
    d->probed = 0u;
    probe_at(d, (uint8_t)idx, now);
}

/* Whether rsm_sicklms_init set d up (not for NULL, zeroed or stale memory). */
static int ready(const rsm_sicklms_t *d)
{
    return d != NULL && d->magic == (uint32_t)RSM_SICKLMS_MAGIC && d->cfg != NULL;
}

int rsm_sicklms_connect(rsm_sicklms_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    d->lost = 0u;
    d->format = d->cfg->format;
    if (rsm_link_set_baud(d->link, d->cfg->power_up_baud) == RSM_OK) {
        d->baud = d->cfg->power_up_baud;
    }
    begin_probing(d, d->cfg->power_up_baud, rsm_link_rx_now(&d->io));
    return RSM_OK;
}

int rsm_sicklms_listen(rsm_sicklms_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    d->lost = 0u;
    d->format = d->cfg->format;
    d->state = RSM_SICKLMS_LISTENING;
    return RSM_OK;
}

/* The shutdown is over (status RSM_OK) or given up. */
static void end_shutdown(rsm_sicklms_t *d, int status, uint64_t now)
{
    if (status == RSM_OK) {
        d->stats.disconnects++;
    }
    d->state = RSM_SICKLMS_IDLE;
    d->out.type = RSM_SICKLMS_EVENT_DISCONNECTED;
    d->out.status = status;
    d->out.stamp_us = now;
}

/* A step failed: a start-up begins again after a pause, a shutdown ends. */
static void fail(rsm_sicklms_t *d, int status, uint64_t now)
{
    if (d->state == RSM_SICKLMS_STOPPING) {
        end_shutdown(d, status, now);
        return;
    }
    d->stats.errors++;
    d->state = RSM_SICKLMS_BACKOFF;
    d->deadline_us = now + d->cfg->retry_wait_us;
    d->out.type = RSM_SICKLMS_EVENT_ERROR;
    d->out.status = status;
    d->out.stamp_us = now;
}

int rsm_sicklms_disconnect(rsm_sicklms_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    if (d->state == RSM_SICKLMS_IDLE || d->state == RSM_SICKLMS_STOPPING) {
        return RSM_OK;
    }
    if (d->state == RSM_SICKLMS_LISTENING) {
        d->state = RSM_SICKLMS_IDLE; /* it never spoke to the unit */
        return RSM_OK;
    }
    start_step(d, STEP_STOP, rsm_link_rx_now(&d->io));
    return RSM_OK;
}

/* No ACK or no reply in time. */
static void request_timed_out(rsm_sicklms_t *d, uint64_t now)
{
    if (d->sub == SUB_ACK) {
        d->stats.ack_timeouts++;
    } else {
        d->stats.reply_timeouts++;
    }
    if (d->step == STEP_PROBE) {
        /* Nothing at this rate: the next one (one try each, 2.10 step 2). */
        d->probed++;
        if (!d->cfg->probe || d->link->set_baud == NULL || d->probed >= N_RATES) {
            d->probed = 0u;
            fail(d, RSM_ERR_TIMEOUT, now);
            return;
        }
        probe_at(d, (uint8_t)((d->probe_idx + 1u) % N_RATES), now);
        return;
    }
    if (d->step == STEP_BAUD) {
        /* The LMS may or may not have switched: never repeat the change
         * blindly, find it again, trying the new rate first. */
        begin_probing(d, d->cfg->baud, now);
        return;
    }
    if (d->step == STEP_RESTORE && d->sub == SUB_REPLY) {
        /* Accepted, but did it switch? Not repeated blindly either: the
         * next start-up probes. */
        fail(d, RSM_ERR_TIMEOUT, now);
        return;
    }
    if (d->tries >= d->cfg->max_tries) {
        fail(d, RSM_ERR_TIMEOUT, now);
        return;
    }
    d->stats.retries++;
    drop_input(d);
    send_request(d, now);
}

static void streaming_started(rsm_sicklms_t *d, uint64_t now)
{
    d->state = RSM_SICKLMS_STREAMING;
    d->last_tel_us = now;
    d->stats.connects++;
    if (d->lost) {
        d->stats.reconnects++;
        d->lost = 0u;
    }
    d->out.type = RSM_SICKLMS_EVENT_CONNECTED;
    d->out.stamp_us = now;
}

/* The 0xF4 configuration block: keep it and decode 0xB0 as it says. A
 * measuring mode that gives no ranges (reflectivity) cannot be used. */
static int take_config(rsm_sicklms_t *d, const rsm_lms_telegram_t *t)
{
    rsm_lms_config_t c;
    rsm_lms_b0_format_t f;
    if (rsm_lms_decode_config(t, &c) != RSM_OK) {
        return RSM_ERR_PROTO;
    }
    d->config = c;
    d->have_config = 1u;
    d->stats.config_reads++;
    if (rsm_lms_b0_format_from_config(&c, &f) != RSM_OK) {
        return RSM_ERR_PROTO;
    }
    d->format.distance_bits = f.distance_bits;
    d->format.index_bytes = f.index_bytes;
    return RSM_OK;
}

/* A mode-change reply (0xA0) that accepts the change. */
static int mode_ok(const rsm_lms_telegram_t *t)
{
    rsm_lms_mode_reply_t mode;
    return rsm_lms_decode_mode_reply(t, &mode) == RSM_OK && mode.result == RSM_LMS_MODE_RESULT_OK;
}

/* The reply of a baud change came at the old rate: now the link follows. */
static int follow_baud(rsm_sicklms_t *d, uint32_t baud)
{
    if (rsm_link_set_baud(d->link, baud) != RSM_OK) {
        return RSM_ERR_IO;
    }
    d->baud = baud;
    d->stats.baud_changes++;
    drop_input(d);
    return RSM_OK;
}

/* The expected reply of the step in flight arrived. */
static void step_done(rsm_sicklms_t *d, const rsm_lms_telegram_t *t, uint64_t now)
{
    rsm_lms_mode_reply_t mode;
    rsm_lms_variant_reply_t var;
    int st;
    switch (d->step) {
    case STEP_PROBE:
        if (rsm_lms_decode_mode_reply(t, &mode) != RSM_OK) {
            fail(d, RSM_ERR_PROTO, now);
            return;
        }
        if (d->cfg->baud != 0u && d->cfg->baud != d->baud && d->link->set_baud != NULL) {
            start_step(d, STEP_BAUD, now);
        } else {
            start_step(d, STEP_VARIANT, now);
        }
        return;
    case STEP_BAUD:
        if (!mode_ok(t)) {
            fail(d, RSM_ERR_PROTO, now);
            return;
        }
        st = follow_baud(d, d->cfg->baud);
        if (st != RSM_OK) {
            fail(d, st, now);
            return;
        }
        d->state = RSM_SICKLMS_SETTLE;
        d->deadline_us = now + d->cfg->baud_settle_us;
        return;
    case STEP_VARIANT:
        if (rsm_lms_decode_variant_reply(t, &var) != RSM_OK ||
            var.result != RSM_LMS_RESULT_ACCEPTED || var.angle_deg != d->cfg->angle_deg ||
            var.resolution_cdeg != d->cfg->resolution_cdeg) {
            fail(d, RSM_ERR_PROTO, now);
            return;
        }
        start_step(d, d->cfg->read_config ? STEP_CONFIG : STEP_STREAM, now);
        return;
    case STEP_CONFIG:
        st = take_config(d, t);
        if (st != RSM_OK) {
            fail(d, st, now);
            return;
        }
        start_step(d, STEP_STREAM, now);
        return;
    case STEP_STOP:
        if (!mode_ok(t)) {
            fail(d, RSM_ERR_PROTO, now);
        } else if (d->baud != d->cfg->power_up_baud && d->link->set_baud != NULL) {
            start_step(d, STEP_RESTORE, now);
        } else {
            end_shutdown(d, RSM_OK, now);
        }
        return;
    case STEP_RESTORE:
        if (!mode_ok(t)) {
            fail(d, RSM_ERR_PROTO, now);
            return;
        }
        st = follow_baud(d, d->cfg->power_up_baud);
        end_shutdown(d, st, now);
        return;
    case STEP_STREAM:
    default:
        if (!mode_ok(t)) {
            fail(d, RSM_ERR_PROTO, now);
            return;
        }
        streaming_started(d, now);
        return;
    }
}

/* The robot-frame bearing of beam 0 and the step between beams, radians,
 * of a scan whose scanner angles are start + i * step (1/100 deg). Beam i is
 * then at start + step * i, the arithmetic of rsm_scan_set_uniform: a scan
 * decoded here has, bit for bit, the bearings of the same scan read from a
 * CARMEN log (rsm-nav --capture against --carmen). */
static void beam_layout(uint16_t start_cdeg, uint16_t step_cdeg, uint8_t upside_down, float *start_rad,
                        float *step_rad)
{
    const int32_t first = upside_down ? 9000 - (int32_t)start_cdeg : (int32_t)start_cdeg - 9000;
    const int32_t step = upside_down ? -(int32_t)step_cdeg : (int32_t)step_cdeg;
    *start_rad = (float)first * PI_F / 18000.0f;
    *step_rad = (float)step * PI_F / 18000.0f;
}

/* Beam i at start + step * i (beam_layout) into out in the robot frame: the
 * one conversion of both paths below. Returns 1 when the reading is invalid
 * (range 0, which the core drops). */
static int put_beam(rsm_scan_t *out, size_t i, float start_rad, float step_rad, const rsm_lms_reading_t *r)
{
    out->angle_rad[i] = start_rad + step_rad * (float)i;
    if (r->code == RSM_LMS_READING_OK) {
        out->range_m[i] = r->range_m;
        return 0;
    }
    out->range_m[i] = 0.0f;
    return 1;
}

int rsm_sicklms_to_scan_checked(const rsm_lms_scan_t *raw, uint8_t upside_down, rsm_scan_t *out, size_t out_size,
                                unsigned long fingerprint)
{
    size_t i;
    int invalid = 0;
    float start_rad;
    float step_rad;
    if (!RSM_SAME_BUILD(rsm_scan_t, out_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (raw == NULL || out == NULL) {
        return RSM_ERR_INVAL;
    }
    if (raw->step_cdeg == 0u || raw->count > RSM_MAX_BEAMS) {
        return RSM_ERR_PROTO;
    }
    beam_layout(raw->start_cdeg, raw->step_cdeg, upside_down, &start_rad, &step_rad);
    for (i = 0u; i < raw->count; i++) {
        invalid += put_beam(out, i, start_rad, step_rad, &raw->reading[i]);
    }
    out->count = raw->count;
    return invalid;
}

/* Decodes a 0xB0 telegram straight into the caller's scan (d->scan) in the
 * robot frame, stamped with the receive time less the configured latency:
 * the same result as rsm_lms_decode_b0 then rsm_sicklms_to_scan, with no
 * rsm_lms_scan_t between. The scan is untouched when the telegram does not
 * decode. */
static int decode_scan(rsm_sicklms_t *d, const rsm_lms_telegram_t *t)
{
    const uint64_t rx = d->tel_start_us;
    rsm_lms_b0_view_t v;
    size_t i;
    uint32_t invalid = 0u;
    float start_rad;
    float step_rad;
    int rc;
    if ((rc = rsm_lms_b0_open(t, &d->format, &v)) != RSM_OK) {
        return rc;
    }
    if (v.step_cdeg == 0u) {
        return RSM_ERR_PROTO;
    }
    beam_layout(v.start_cdeg, v.step_cdeg, d->cfg->upside_down, &start_rad, &step_rad);
    for (i = 0u; i < v.count; i++) {
        const rsm_lms_reading_t r = rsm_lms_b0_reading(&v, i);
        invalid += (uint32_t)put_beam(d->scan, i, start_rad, step_rad, &r);
    }
    d->scan->count = v.count;
    d->scan->stamp_us = rx >= d->cfg->latency_us ? rx - d->cfg->latency_us : 0u;
    d->stats.invalid_readings += invalid;
    return RSM_OK;
}

static void handle_stream_telegram(rsm_sicklms_t *d, const rsm_lms_telegram_t *t)
{
    d->last_tel_us = d->io.stamp_us;
    if (t->cmd != RSM_LMS_REPLY_VALUES) {
        d->stats.unexpected++;
        return;
    }
    if (decode_scan(d, t) != RSM_OK) {
        d->stats.bad_scans++;
        return;
    }
    d->stats.scans++;
    d->out.type = RSM_SICKLMS_EVENT_SCAN;
    d->out.scan = d->scan;
    d->out.stamp_us = d->scan->stamp_us;
}

static void handle_event(rsm_sicklms_t *d, const rsm_lms_event_t *e, uint64_t now)
{
    if (e->type == RSM_LMS_EVENT_TELEGRAM) {
        d->stats.telegrams++;
    }
    if (d->state == RSM_SICKLMS_STREAMING || d->state == RSM_SICKLMS_LISTENING) {
        /* 0x06/0x15 bytes mean nothing while streaming. */
        if (e->type == RSM_LMS_EVENT_TELEGRAM) {
            handle_stream_telegram(d, &e->telegram);
        }
        return;
    }
    if ((d->state != RSM_SICKLMS_STARTING && d->state != RSM_SICKLMS_STOPPING) ||
        d->sub == SUB_NAK_WAIT) {
        if (e->type == RSM_LMS_EVENT_TELEGRAM) {
            d->stats.unexpected++;
        }
        return;
    }
    if (e->type == RSM_LMS_EVENT_ACK) {
        if (d->sub == SUB_ACK) {
            d->stats.acks++;
            d->sub = SUB_REPLY;
            /* req[4] is the CMD byte of the request telegram; a mode change
             * may take the LMS up to 3 s (protocols.md 2.4). */
            d->deadline_us = now + (d->req[4] == RSM_LMS_CMD_MODE ? d->cfg->mode_timeout_us
                                                                   : d->cfg->reply_timeout_us);
        }
        return;
    }
    if (e->type == RSM_LMS_EVENT_NAK ||
        (e->type == RSM_LMS_EVENT_TELEGRAM && e->telegram.cmd == RSM_LMS_REPLY_NOT_ACK)) {
        if (e->type == RSM_LMS_EVENT_NAK) {
            d->stats.naks++;
        } else {
            d->stats.rejected++;
        }
        if (d->tries >= d->cfg->max_tries) {
            fail(d, RSM_ERR_PROTO, now);
            return;
        }
        /* The listing asks for at least 30 ms before the next request. */
        d->sub = SUB_NAK_WAIT;
        d->deadline_us = now + d->cfg->nak_wait_us;
        return;
    }
    if (e->type == RSM_LMS_EVENT_TELEGRAM) {
        if (e->telegram.cmd == d->req_reply) {
            step_done(d, &e->telegram, now);
        } else {
            d->stats.unexpected++; /* e.g. 0xB0 of a stream left running */
        }
    }
}

/* rsm_link_poll step 1/4: feeds the held bytes until an event or until
 * the chunk is used up. */
static int drain_cb(void *drv, uint64_t now)
{
    rsm_sicklms_t *d = (rsm_sicklms_t *)drv;
    rsm_lms_event_t e;
    for (;;) {
        size_t used = 0u;
        int r;
        if (rsm_lms_parser_pending(&d->parser) == 0u && d->io.off < d->io.len) {
            /* Whatever telegram comes next starts in this read: its scan is
             * stamped with the arrival of its first byte, not of its last
             * (a 361-value telegram is on the wire for 0.2 s at 38400 Bd). */
            d->tel_start_us = d->io.stamp_us;
        }
        r = rsm_lms_parser_feed(&d->parser, d->io.buf + d->io.off, d->io.len - d->io.off, &used,
                                &e);
        if (r < 0) {
            d->io.off = d->io.len;
            break;
        }
        d->io.off += used;
        if (r == 0) {
            break;
        }
        handle_event(d, &e, now);
        if (d->out.type != RSM_SICKLMS_EVENT_NONE) {
            break;
        }
    }
    d->stats.crc_errors = d->parser.stats.crc_errors;
    return d->out.type != RSM_SICKLMS_EVENT_NONE;
}

/* rsm_link_poll step 4, on silence: a telegram cut short is abandoned and
 * what it held looked at again. */
static int silence_cb(void *drv, uint64_t now)
{
    rsm_sicklms_t *d = (rsm_sicklms_t *)drv;
    rsm_lms_event_t e;
    while (d->out.type == RSM_SICKLMS_EVENT_NONE && rsm_lms_parser_timeout(&d->parser, &e) == 1) {
        handle_event(d, &e, now);
    }
    d->stats.crc_errors = d->parser.stats.crc_errors;
    return d->out.type != RSM_SICKLMS_EVENT_NONE;
}

/* rsm_link_poll steps 2 and 5. */
static int timers_cb(void *drv, uint64_t now)
{
    rsm_sicklms_t *d = (rsm_sicklms_t *)drv;
    switch (d->state) {
    case RSM_SICKLMS_STARTING:
    case RSM_SICKLMS_STOPPING:
        if (now < d->deadline_us) {
            break;
        }
        if (d->sub == SUB_NAK_WAIT) {
            d->stats.retries++;
            send_request(d, now);
        } else {
            request_timed_out(d, now);
        }
        break;
    case RSM_SICKLMS_SETTLE:
        if (now >= d->deadline_us) {
            start_step(d, STEP_VARIANT, now);
        }
        break;
    case RSM_SICKLMS_BACKOFF:
        if (now >= d->deadline_us) {
            begin_probing(d, d->baud, now);
        }
        break;
    case RSM_SICKLMS_STREAMING:
        if (now - d->last_tel_us >= d->cfg->stream_timeout_us) {
            d->stats.link_lost++;
            d->lost = 1u;
            d->out.type = RSM_SICKLMS_EVENT_LINK_LOST;
            d->out.stamp_us = now;
            begin_probing(d, d->baud, now);
        }
        break;
    case RSM_SICKLMS_IDLE:
    default:
        break;
    }
    return d->out.type != RSM_SICKLMS_EVENT_NONE;
}

/* rsm_link_poll: time until the next timer of the current state fires. */
static uint64_t until_due_cb(const void *drv, uint64_t now)
{
    const rsm_sicklms_t *d = (const rsm_sicklms_t *)drv;
    uint64_t due;
    if (d->state == RSM_SICKLMS_IDLE || d->state == RSM_SICKLMS_LISTENING) {
        return UINT64_MAX;
    }
    due = d->state == RSM_SICKLMS_STREAMING ? d->last_tel_us + d->cfg->stream_timeout_us
                                            : d->deadline_us;
    return due > now ? due - now : 0u;
}

static const rsm_link_poll_ops_t sicklms_poll_ops = {drain_cb, timers_cb, until_due_cb,
                                                     silence_cb};

uint64_t rsm_sicklms_next_deadline_us(const rsm_sicklms_t *d)
{
    return !ready(d) ? UINT64_MAX : rsm_link_next_deadline(&d->io, &sicklms_poll_ops, d);
}

int rsm_sicklms_poll(rsm_sicklms_t *d, rsm_sicklms_event_t *ev)
{
    int st;
    if (!ready(d) || ev == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(&d->out, 0, sizeof d->out);
    st = rsm_link_poll(&d->io, &sicklms_poll_ops, d);
    if (st < 0) {
        d->stats.read_errors++;
    }
    *ev = d->out;
    return st;
}
