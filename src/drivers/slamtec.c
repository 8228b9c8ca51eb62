#include "rsm/slamtec.h"

#include <string.h>

#include "rsm/status.h"
#include "core/check.h"
#include "drivers/stamps.h"

/* Start-up steps, in order, then the shutdown step. */
#define STEP_STOP 0u
#define STEP_RESET 1u
#define STEP_HEALTH 2u
#define STEP_INFO 3u
#define STEP_RATE 4u
#define STEP_MOTOR 5u
#define STEP_SCAN 6u
#define STEP_HALT 7u

int rsm_slamtec_config_default(rsm_slamtec_config_t *cfg)
{
    if (cfg == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->baud = 115200u;
    cfg->scan_mode = RSM_SLAMTEC_SCAN_STANDARD;
    cfg->motor = RSM_SLAMTEC_MOTOR_NONE;
    cfg->motor_value = 660u;
    cfg->max_tries = 3u;
    cfg->sample_us = 250u;
    cfg->read_timeout_us = 10000u;
    cfg->byte_timeout_us = 50000u;
    cfg->reply_timeout_us = 500000u;
    cfg->stop_wait_us = 20000u;
    cfg->reset_wait_us = 1000000u;
    cfg->motor_wait_us = 1000000u;
    cfg->retry_wait_us = 1000000u;
    cfg->stream_timeout_us = 1000000u;
    return RSM_OK;
}

int rsm_slamtec_init_checked(rsm_slamtec_t *d, size_t d_size, unsigned long fingerprint, const rsm_link_t *link,
                             const rsm_clock_t *clock, const rsm_slamtec_config_t *cfg)
{
    rsm_link_rx_t io;
    if (!RSM_SAME_BUILD(rsm_slamtec_t, d_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (d == NULL || cfg == NULL || cfg->reply_timeout_us == 0u || cfg->stream_timeout_us == 0u ||
        cfg->max_tries == 0u || cfg->scan_mode > RSM_SLAMTEC_SCAN_EXPRESS ||
        cfg->motor > RSM_SLAMTEC_MOTOR_RPM ||
        rsm_link_rx_init(&io, link, clock, cfg->read_timeout_us, cfg->byte_timeout_us) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    memset(d, 0, sizeof *d);
    d->magic = (uint32_t)RSM_SLAMTEC_MAGIC;
    d->cfg = cfg;
    d->io = io;
    d->state = RSM_SLAMTEC_IDLE;
    (void)rsm_rplidar_parser_init(&d->parser);
    return RSM_OK;
}

static void write_req(rsm_slamtec_t *d, const uint8_t *req, size_t len)
{
    d->stats.requests++;
    if (rsm_link_write_all(d->io.link, req, len, NULL) != RSM_OK) {
        d->stats.write_errors++;
    }
}

/* Sends the request of the current step (again): the receiver then awaits
 * its answer descriptor. */
static void send_request(rsm_slamtec_t *d, uint64_t now)
{
    /* bytes read before the request went out cannot be its answer */
    d->stats.stale_bytes += (uint32_t)(d->io.len - d->io.off);
    d->io.off = d->io.len;
    (void)rsm_rplidar_parser_expect(&d->parser);
    write_req(d, d->req, d->req_len);
    d->tries++;
    d->deadline_us = now + d->cfg->reply_timeout_us;
}

/* The motor command of cfg (value, or 0 to stop); 0 bytes if none. */
static size_t motor_request(const rsm_slamtec_t *d, uint16_t value, uint8_t *out, size_t cap)
{
    const uint8_t cmd = d->cfg->motor == RSM_SLAMTEC_MOTOR_PWM ? RSM_RPLIDAR_CMD_MOTOR_PWM
                                                               : RSM_RPLIDAR_CMD_MOTOR_SPEED;
    int n;
    if (d->cfg->motor == RSM_SLAMTEC_MOTOR_NONE) {
        return 0u;
    }
    n = rsm_rplidar_encode_motor(out, cap, cmd, value);
    return n > 0 ? (size_t)n : 0u;
}

/* Sends a request without answer and pauses for pause_us. */
static void send_and_pause(rsm_slamtec_t *d, uint8_t cmd, uint32_t pause_us, uint64_t now)
{
    int n = rsm_rplidar_encode_request(d->req, sizeof d->req, cmd, NULL, 0);
    d->req_len = n > 0 ? (size_t)n : 0u;
    write_req(d, d->req, d->req_len);
    d->waiting = 1u;
    d->deadline_us = now + pause_us;
}

static void begin_step(rsm_slamtec_t *d, uint8_t step, uint64_t now)
{
    const rsm_slamtec_config_t *c = d->cfg;
    uint8_t cmd = RSM_RPLIDAR_CMD_GET_HEALTH;
    int n;
    d->step = step;
    d->tries = 0u;
    d->waiting = 0u;
    d->state = step == STEP_HALT ? RSM_SLAMTEC_STOPPING : RSM_SLAMTEC_STARTING;
    switch (step) {
    case STEP_STOP:
        send_and_pause(d, RSM_RPLIDAR_CMD_STOP, c->stop_wait_us, now);
        return;
    case STEP_RESET:
        d->stats.resets++;
        d->need_reset = 0u;
        send_and_pause(d, RSM_RPLIDAR_CMD_RESET, c->reset_wait_us, now);
        return;
    case STEP_MOTOR:
        d->req_len = motor_request(d, c->motor_value, d->req, sizeof d->req);
        write_req(d, d->req, d->req_len);
        d->waiting = 1u;
        d->deadline_us = now + c->motor_wait_us;
        return;
    case STEP_HALT: {
        uint8_t off[8];
        const size_t m = motor_request(d, 0u, off, sizeof off);
        send_and_pause(d, RSM_RPLIDAR_CMD_STOP, c->stop_wait_us, now);
        if (m > 0u) {
            write_req(d, off, m);
        }
        return;
    }
    case STEP_INFO:
        cmd = RSM_RPLIDAR_CMD_GET_INFO;
        break;
    case STEP_RATE:
        cmd = RSM_RPLIDAR_CMD_GET_SAMPLERATE;
        break;
    case STEP_SCAN:
        cmd = RSM_RPLIDAR_CMD_SCAN;
        break;
    default: /* STEP_HEALTH */
        break;
    }
    n = step == STEP_SCAN && c->scan_mode == RSM_SLAMTEC_SCAN_EXPRESS
            ? rsm_rplidar_encode_express_scan(d->req, sizeof d->req)
            : rsm_rplidar_encode_request(d->req, sizeof d->req, cmd, NULL, 0);
    d->req_len = n > 0 ? (size_t)n : 0u;
    send_request(d, now);
}

/* The step after the current one in the start-up. */
static void next_step(rsm_slamtec_t *d, uint64_t now)
{
    uint8_t s = (uint8_t)(d->step + 1u);
    if (s == STEP_RESET && !d->cfg->reset && !d->need_reset) {
        s = STEP_HEALTH;
    }
    if (s == STEP_MOTOR && d->cfg->motor == RSM_SLAMTEC_MOTOR_NONE) {
        s = STEP_SCAN;
    }
    begin_step(d, s, now);
}

static void fail(rsm_slamtec_t *d, int status, uint64_t now)
{
    d->stats.errors++;
    d->state = RSM_SLAMTEC_BACKOFF;
    d->deadline_us = now + d->cfg->retry_wait_us;
    d->out.type = RSM_SLAMTEC_EVENT_ERROR;
    d->out.status = status;
    d->out.stamp_us = now;
}

/* What connect and listen share: the link's rate, a fresh session. */
static void start_session(rsm_slamtec_t *d, uint8_t listen)
{
    if (d->cfg->baud != 0u) {
        const int st = rsm_link_set_baud(d->io.link, d->cfg->baud);
        if (st != RSM_OK && st != RSM_ERR_NOSYS) {
            d->stats.baud_errors++;
        }
    }
    d->listen = listen;
    d->lost = 0u;
    memset(&d->samplerate, 0, sizeof d->samplerate);
}

/* Whether rsm_slamtec_init set d up (not for NULL, zeroed or stale memory). */
static int ready(const rsm_slamtec_t *d)
{
    return d != NULL && d->magic == (uint32_t)RSM_SLAMTEC_MAGIC && d->cfg != NULL;
}

int rsm_slamtec_connect(rsm_slamtec_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    start_session(d, 0u);
    begin_step(d, STEP_STOP, rsm_link_rx_now(&d->io));
    return RSM_OK;
}

/* Listen-only: await a descriptor, whatever came before it. */
static void await_descriptor(rsm_slamtec_t *d)
{
    d->state = RSM_SLAMTEC_LISTENING;
    rsm_link_rx_drop(&d->io);
    (void)rsm_rplidar_parser_expect(&d->parser);
    d->resumed = 0u;
    d->listen_mark = d->parser.stats.bytes_skipped;
}

/* Listen-only, once a stream was heard and lost: the host that runs the
 * sensor may never have stopped it, so no descriptor will come however
 * long the silence was. Bytes that are no descriptor or answer for this
 * long are tried as the lost stream, and bytes that are not that stream
 * as descriptors again, in turn. */
#define LISTEN_TRY_BYTES (2u * RSM_RPLIDAR_MAX_FRAME)

static void listen_try(rsm_slamtec_t *d)
{
    if (d->state != RSM_SLAMTEC_LISTENING || d->stats.connects == 0u ||
        d->parser.stats.bytes_skipped - d->listen_mark < LISTEN_TRY_BYTES) {
        return;
    }
    if (d->resumed) {
        (void)rsm_rplidar_parser_expect(&d->parser);
    } else {
        (void)rsm_rplidar_parser_resume(&d->parser, d->answer);
    }
    d->resumed = (uint8_t)!d->resumed;
    d->listen_mark = d->parser.stats.bytes_skipped;
}

int rsm_slamtec_listen(rsm_slamtec_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    start_session(d, 1u);
    await_descriptor(d);
    return RSM_OK;
}

int rsm_slamtec_disconnect(rsm_slamtec_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    if (d->listen) {
        d->state = RSM_SLAMTEC_IDLE; /* nothing was ever sent: nothing to stop */
        d->listen = 0u;
        return RSM_OK;
    }
    if (d->state != RSM_SLAMTEC_IDLE && d->state != RSM_SLAMTEC_STOPPING) {
        begin_step(d, STEP_HALT, rsm_link_rx_now(&d->io));
    }
    return RSM_OK;
}

/* Sample time of the stream in use. */
static uint32_t sample_us(const rsm_slamtec_t *d)
{
    const uint16_t measured = d->answer == RSM_RPLIDAR_ANS_NODE ? d->samplerate.standard_us
                                                                : d->samplerate.express_us;
    return measured != 0u ? measured : d->cfg->sample_us;
}

/* Appends the points of a codec event to the outgoing event, stamped. */
static void take_points(rsm_slamtec_t *d, const rsm_rplidar_event_t *e)
{
    /* the frame's last byte came the line time of the rest of the read
     * before the read's time */
    const uint64_t arrived = rsm_stamp_before(
        d->io.stamp_us, (uint64_t)(d->io.len - d->io.off) * rsm_byte_us(d->cfg->baud));
    const uint64_t base = rsm_stamp_before(arrived, d->cfg->latency_us);
    rsm_lidar_point_t *first = &d->out.points[d->out.count];
    size_t k;
    for (k = 0; k < e->count; ++k) {
        rsm_lidar_point_t *p = &d->out.points[d->out.count++];
        *p = e->points[k];
        p->stamp_us = e->count > 1u
                          ? rsm_stamp_before(base, (uint64_t)sample_us(d) * (2u * e->count - 1u - k))
                          : base;
    }
    d->stats.stamp_shifts += (uint32_t)rsm_stamps_in_order(first, e->count, &d->last_point_us);
    d->stats.points += (uint32_t)e->count;
    d->out.type = RSM_SLAMTEC_EVENT_POINTS;
}

/* A scan descriptor came: the stream of answer type `answer` begins. */
static void stream_started(rsm_slamtec_t *d, uint8_t answer, uint64_t now)
{
    d->answer = answer;
    d->resumed = 0u;
    d->state = RSM_SLAMTEC_STREAMING;
    d->last_data_us = now;
    d->stats.connects++;
    d->stats.reconnects += d->lost;
    d->lost = 0u;
    d->out.type = RSM_SLAMTEC_EVENT_CONNECTED;
    d->out.stamp_us = now;
}

/* An answer during the start-up. */
static void startup_answer(rsm_slamtec_t *d, const rsm_rplidar_event_t *e, uint64_t now)
{
    const uint8_t want[STEP_SCAN + 1u] = {0u, 0u, RSM_RPLIDAR_EVENT_HEALTH, RSM_RPLIDAR_EVENT_INFO,
                                          RSM_RPLIDAR_EVENT_SAMPLERATE, 0u,
                                          RSM_RPLIDAR_EVENT_DESCRIPTOR};
    if (d->waiting || d->step > STEP_SCAN || (uint8_t)e->type != want[d->step]) {
        if (e->type != RSM_RPLIDAR_EVENT_DESCRIPTOR) {
            d->stats.unexpected++;
        }
        return;
    }
    switch (d->step) {
    case STEP_HEALTH:
        d->health = e->health;
        if (e->health.status == RSM_RPLIDAR_HEALTH_ERROR) {
            d->stats.health_errors++;
            d->need_reset = 1u;
            fail(d, RSM_ERR_PROTO, now);
            return;
        }
        if (e->health.status == RSM_RPLIDAR_HEALTH_WARNING) {
            d->stats.health_warnings++;
        }
        break;
    case STEP_INFO:
        d->info = e->info;
        break;
    case STEP_RATE:
        d->samplerate = e->samplerate;
        break;
    default: { /* STEP_SCAN: the descriptor of the scan stream */
        const int standard = d->cfg->scan_mode == RSM_SLAMTEC_SCAN_STANDARD;
        if (standard ? e->answer != RSM_RPLIDAR_ANS_NODE
                     : (e->answer != RSM_RPLIDAR_ANS_CAPSULE && e->answer != RSM_RPLIDAR_ANS_DENSE)) {
            d->stats.unexpected++;
            return;
        }
        stream_started(d, e->answer, now);
        return;
    }
    }
    next_step(d, now);
}

/* Listen-only: what the sensor says to whoever runs it. Answers are kept,
 * a scan descriptor starts the stream. */
static void overheard(rsm_slamtec_t *d, const rsm_rplidar_event_t *e, uint64_t now)
{
    switch (e->type) {
    case RSM_RPLIDAR_EVENT_HEALTH: d->health = e->health; break;
    case RSM_RPLIDAR_EVENT_INFO: d->info = e->info; break;
    case RSM_RPLIDAR_EVENT_SAMPLERATE: d->samplerate = e->samplerate; break;
    case RSM_RPLIDAR_EVENT_DESCRIPTOR:
        if (e->answer == RSM_RPLIDAR_ANS_NODE || e->answer == RSM_RPLIDAR_ANS_CAPSULE ||
            e->answer == RSM_RPLIDAR_ANS_DENSE) {
            stream_started(d, e->answer, now);
        }
        break; /* the descriptor of an answer: the answer follows */
    default: d->stats.unexpected++; break;
    }
}

/* rsm_link_poll step 1/4: feeds the held bytes; stops at an event, or when
 * a batch of nodes is full. */
static int drain_cb(void *drv, uint64_t now)
{
    rsm_slamtec_t *d = (rsm_slamtec_t *)drv;
    if (d->state == RSM_SLAMTEC_IDLE) {
        d->io.off = d->io.len;
        return 0;
    }
    while (d->io.off < d->io.len && d->out.type == RSM_SLAMTEC_EVENT_NONE) {
        size_t used = 0;
        const int r = rsm_rplidar_parser_feed(&d->parser, d->io.buf + d->io.off,
                                              d->io.len - d->io.off, &used, &d->ev);
        d->io.off += used;
        if (r != 1) {
            listen_try(d);
            break;
        }
        if (d->state == RSM_SLAMTEC_STREAMING && d->ev.type == RSM_RPLIDAR_EVENT_POINTS) {
            d->last_data_us = now;
            take_points(d, &d->ev);
            /* nodes come one by one (a node stream has nothing else):
             * gather them while they fit */
            if (d->answer == RSM_RPLIDAR_ANS_NODE && d->out.count < RSM_RPLIDAR_MAX_POINTS) {
                d->out.type = RSM_SLAMTEC_EVENT_NONE;
            }
        } else if (d->state == RSM_SLAMTEC_STARTING) {
            startup_answer(d, &d->ev, now);
        } else if (d->state == RSM_SLAMTEC_LISTENING && d->ev.type == RSM_RPLIDAR_EVENT_POINTS) {
            stream_started(d, d->answer, now); /* the lost stream, taken up again */
        } else if (d->state == RSM_SLAMTEC_LISTENING) {
            overheard(d, &d->ev, now);
        } else if (d->ev.type != RSM_RPLIDAR_EVENT_DESCRIPTOR) {
            d->stats.unexpected++;
        }
    }
    if (d->out.count > 0u) {
        d->out.type = RSM_SLAMTEC_EVENT_POINTS;
        d->out.stamp_us = now;
    }
    return d->out.type != RSM_SLAMTEC_EVENT_NONE;
}

/* rsm_link_poll step 4 on silence: a partial answer will not be
 * completed. */
static int silence_cb(void *drv, uint64_t now)
{
    (void)now;
    (void)rsm_rplidar_parser_flush(&((rsm_slamtec_t *)drv)->parser);
    return 0;
}

/* rsm_link_poll steps 2 and 5. */
static int timers_cb(void *drv, uint64_t now)
{
    rsm_slamtec_t *d = (rsm_slamtec_t *)drv;
    switch (d->state) {
    case RSM_SLAMTEC_STARTING:
    case RSM_SLAMTEC_STOPPING:
        if (now < d->deadline_us) {
            break;
        }
        if (d->state == RSM_SLAMTEC_STOPPING) {
            d->state = RSM_SLAMTEC_IDLE;
            d->stats.disconnects++;
            d->out.type = RSM_SLAMTEC_EVENT_DISCONNECTED;
            d->out.stamp_us = now;
        } else if (d->waiting) {
            if (d->step == STEP_STOP || d->step == STEP_RESET) {
                /* what a running scan or the boot text left behind */
                rsm_link_rx_drop(&d->io);
                (void)rsm_rplidar_parser_expect(&d->parser);
            }
            next_step(d, now);
        } else {
            d->stats.timeouts++;
            if (d->step == STEP_RATE) {
                d->stats.no_samplerate++;
                next_step(d, now);
            } else if (d->tries < d->cfg->max_tries) {
                d->stats.retries++;
                send_request(d, now);
            } else {
                fail(d, RSM_ERR_TIMEOUT, now);
            }
        }
        break;
    case RSM_SLAMTEC_BACKOFF:
        if (now >= d->deadline_us) {
            begin_step(d, STEP_STOP, now);
        }
        break;
    case RSM_SLAMTEC_STREAMING:
        if (now - d->last_data_us >= d->cfg->stream_timeout_us) {
            d->stats.link_lost++;
            d->lost = 1u;
            d->out.type = RSM_SLAMTEC_EVENT_LINK_LOST;
            d->out.stamp_us = now;
            if (d->listen) {
                await_descriptor(d);
            } else {
                begin_step(d, STEP_STOP, now);
            }
        }
        break;
    case RSM_SLAMTEC_LISTENING: /* no timer: the sensor speaks when it is run */
    case RSM_SLAMTEC_IDLE:
    default:
        break;
    }
    return d->out.type != RSM_SLAMTEC_EVENT_NONE;
}

static uint64_t until_due_cb(const void *drv, uint64_t now)
{
    const rsm_slamtec_t *d = (const rsm_slamtec_t *)drv;
    uint64_t due;
    if (d->state == RSM_SLAMTEC_IDLE || d->state == RSM_SLAMTEC_LISTENING) {
        return UINT64_MAX;
    }
    due = d->state == RSM_SLAMTEC_STREAMING ? d->last_data_us + d->cfg->stream_timeout_us
                                            : d->deadline_us;
    return due > now ? due - now : 0u;
}

static const rsm_link_poll_ops_t slamtec_poll_ops = {drain_cb, timers_cb, until_due_cb,
                                                     silence_cb};

uint64_t rsm_slamtec_next_deadline_us(const rsm_slamtec_t *d)
{
    return !ready(d) ? UINT64_MAX : rsm_link_next_deadline(&d->io, &slamtec_poll_ops, d);
}

int rsm_slamtec_poll(rsm_slamtec_t *d, rsm_slamtec_event_t *ev)
{
    int st;
    if (!ready(d) || ev == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(&d->out, 0, sizeof d->out);
    st = rsm_link_poll(&d->io, &slamtec_poll_ops, d);
    if (st < 0) {
        d->stats.read_errors++;
    }
    *ev = d->out;
    return st;
}
