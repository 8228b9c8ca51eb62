#include "rsm/ldlidar.h"

#include <string.h>

#include "rsm/status.h"
#include "core/check.h"
#include "drivers/stamps.h"

int rsm_ldlidar_config_default(rsm_ldlidar_config_t *cfg)
{
    if (cfg == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->baud = 230400u;
    cfg->read_timeout_us = 10000u;
    cfg->byte_timeout_us = 20000u;
    cfg->stream_timeout_us = 500000u;
    cfg->latency_us = 0u;
    return RSM_OK;
}

int rsm_ldlidar_init_checked(rsm_ldlidar_t *d, size_t d_size, unsigned long fingerprint, const rsm_link_t *link,
                             const rsm_clock_t *clock, const rsm_ldlidar_config_t *cfg)
{
    rsm_link_rx_t io;
    if (!RSM_SAME_BUILD(rsm_ldlidar_t, d_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (d == NULL || cfg == NULL || cfg->stream_timeout_us == 0u ||
        rsm_link_rx_init(&io, link, clock, cfg->read_timeout_us, cfg->byte_timeout_us) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    memset(d, 0, sizeof *d);
    d->magic = (uint32_t)RSM_LDLIDAR_MAGIC;
    d->cfg = cfg;
    d->io = io;
    d->state = RSM_LDLIDAR_IDLE;
    (void)rsm_ld06_parser_init(&d->parser);
    return RSM_OK;
}

/* Whether rsm_ldlidar_init set d up (not for NULL, zeroed or stale memory). */
static int ready(const rsm_ldlidar_t *d)
{
    return d != NULL && d->magic == (uint32_t)RSM_LDLIDAR_MAGIC && d->cfg != NULL;
}

int rsm_ldlidar_connect(rsm_ldlidar_t *d)
{
    int st;
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    st = rsm_link_set_baud(d->io.link, d->cfg->baud);
    if (st != RSM_OK && st != RSM_ERR_NOSYS) {
        d->stats.baud_errors++;
    }
    rsm_link_rx_drop(&d->io);
    (void)rsm_ld06_parser_flush(&d->parser);
    d->state = RSM_LDLIDAR_LISTENING;
    d->pending = 0u;
    d->lost = 0u;
    d->last_packet_us = rsm_link_rx_now(&d->io);
    return RSM_OK;
}

int rsm_ldlidar_disconnect(rsm_ldlidar_t *d)
{
    if (!ready(d)) {
        return RSM_ERR_INVAL;
    }
    d->state = RSM_LDLIDAR_IDLE;
    d->pending = 0u;
    return RSM_OK;
}

int rsm_ldlidar_stamp(const rsm_ld06_packet_t *pkt, uint64_t last_us, rsm_lidar_point_t *out)
{
    uint64_t step_us = 0;
    size_t i;
    if (rsm_ld06_points(pkt, out) != (int)RSM_LD06_POINTS) {
        return RSM_ERR_INVAL;
    }
    if (pkt->speed_dps > 0u) {
        const uint32_t span =
            ((uint32_t)pkt->end_cdeg + RSM_LD06_MAX_CDEG - pkt->start_cdeg) % RSM_LD06_MAX_CDEG;
        /* (span / 100 deg) / (11 steps) / (speed deg/s), in us */
        step_us = (uint64_t)span * 10000u / ((uint64_t)pkt->speed_dps * (RSM_LD06_POINTS - 1u));
    }
    for (i = 0; i < RSM_LD06_POINTS; ++i) {
        const uint64_t back = step_us * (RSM_LD06_POINTS - 1u - i);
        out[i].stamp_us = rsm_stamp_before(last_us, back);
    }
    return (int)RSM_LD06_POINTS;
}

/* The waiting packet as a POINTS event. */
static void deliver(rsm_ldlidar_t *d)
{
    (void)rsm_ldlidar_stamp(&d->last, rsm_stamp_before(d->packet_us, d->cfg->latency_us),
                            d->out.points);
    d->stats.stamp_shifts +=
        (uint32_t)rsm_stamps_in_order(d->out.points, RSM_LD06_POINTS, &d->last_point_us);
    d->out.type = RSM_LDLIDAR_EVENT_POINTS;
    d->out.count = RSM_LD06_POINTS;
    d->out.stamp_us = d->packet_us;
    d->stats.points += RSM_LD06_POINTS;
    d->pending = 0u;
}

/* rsm_link_poll step 1/4. */
static int drain_cb(void *drv, uint64_t now)
{
    rsm_ldlidar_t *d = (rsm_ldlidar_t *)drv;
    if (d->state == RSM_LDLIDAR_IDLE) {
        d->io.off = d->io.len; /* not listening */
        return 0;
    }
    if (d->pending) {
        deliver(d);
        return 1;
    }
    while (d->io.off < d->io.len) {
        size_t used = 0;
        const int r = rsm_ld06_parser_feed(&d->parser, d->io.buf + d->io.off,
                                           d->io.len - d->io.off, &used, &d->last);
        d->io.off += used;
        if (r != 1) {
            break;
        }
        d->stats.packets++;
        d->last_packet_us = now;
        /* the read's time is when its last byte came: the packet's last
         * byte came the rest of the chunk earlier */
        d->packet_us = rsm_stamp_before(d->io.stamp_us, (uint64_t)(d->io.len - d->io.off) *
                                                            rsm_byte_us(d->cfg->baud));
        d->pending = 1u;
        if (d->state == RSM_LDLIDAR_LISTENING) {
            d->state = RSM_LDLIDAR_STREAMING;
            d->stats.connects++;
            d->stats.reconnects += d->lost;
            d->lost = 0u;
            d->out.type = RSM_LDLIDAR_EVENT_CONNECTED;
            d->out.stamp_us = now;
        } else {
            deliver(d);
        }
        return 1;
    }
    return 0;
}

/* rsm_link_poll step 4 on silence: a partial packet will not be completed. */
static int silence_cb(void *drv, uint64_t now)
{
    (void)now;
    (void)rsm_ld06_parser_flush(&((rsm_ldlidar_t *)drv)->parser);
    return 0;
}

/* rsm_link_poll steps 2 and 5. */
static int timers_cb(void *drv, uint64_t now)
{
    rsm_ldlidar_t *d = (rsm_ldlidar_t *)drv;
    if (d->state == RSM_LDLIDAR_IDLE || d->pending ||
        now - d->last_packet_us < d->cfg->stream_timeout_us) {
        return 0;
    }
    if (d->state == RSM_LDLIDAR_STREAMING) {
        d->stats.link_lost++;
        d->lost = 1u;
        d->state = RSM_LDLIDAR_LISTENING;
        d->out.type = RSM_LDLIDAR_EVENT_LINK_LOST;
        d->out.stamp_us = now;
    }
    (void)rsm_ld06_parser_flush(&d->parser);
    d->last_packet_us = now; /* the next loss is reported a timeout later */
    return d->out.type != RSM_LDLIDAR_EVENT_NONE;
}

static uint64_t until_due_cb(const void *drv, uint64_t now)
{
    const rsm_ldlidar_t *d = (const rsm_ldlidar_t *)drv;
    uint64_t due;
    if (d->state == RSM_LDLIDAR_IDLE) {
        return UINT64_MAX;
    }
    if (d->pending) {
        return 0u;
    }
    due = d->last_packet_us + d->cfg->stream_timeout_us;
    return due > now ? due - now : 0u;
}

static const rsm_link_poll_ops_t ldlidar_poll_ops = {drain_cb, timers_cb, until_due_cb,
                                                     silence_cb};

uint64_t rsm_ldlidar_next_deadline_us(const rsm_ldlidar_t *d)
{
    return !ready(d) ? UINT64_MAX : rsm_link_next_deadline(&d->io, &ldlidar_poll_ops, d);
}

int rsm_ldlidar_poll(rsm_ldlidar_t *d, rsm_ldlidar_event_t *ev)
{
    int st;
    if (!ready(d) || ev == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(&d->out, 0, sizeof d->out);
    st = rsm_link_poll(&d->io, &ldlidar_poll_ops, d);
    if (st < 0) {
        d->stats.read_errors++;
    }
    *ev = d->out;
    return st;
}
