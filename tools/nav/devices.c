#include "devices.h"

#include <stdio.h>
#include <string.h>

#include "rsm/status.h"

void nav_devices_defaults(nav_devices_t *dv, int listen, int quiet)
{
    memset(dv, 0, sizeof *dv);
    (void)rsm_p3dx_config_default(&dv->pcfg);
    (void)rsm_sicklms_config_default(&dv->lcfg);
    dv->listen = listen;
    dv->quiet = quiet;
}

int nav_devices_start(nav_devices_t *dv, int robot, const rsm_link_t *link, const rsm_clock_t *clock)
{
    int ok;
    if (robot) {
        ok = rsm_p3dx_init(&dv->robot, link, clock, &dv->pcfg) == RSM_OK &&
             (dv->listen ? rsm_p3dx_listen(&dv->robot) : rsm_p3dx_connect(&dv->robot)) == RSM_OK;
    } else {
        ok = rsm_sicklms_init(&dv->laser, link, clock, &dv->lcfg) == RSM_OK &&
             (dv->listen ? rsm_sicklms_listen(&dv->laser) : rsm_sicklms_connect(&dv->laser)) == RSM_OK;
    }
    if (!ok) {
        fprintf(stderr, "rsm-nav: cannot start the %s driver\n", robot ? "P3-DX" : "LMS");
        return -1;
    }
    return 0;
}

static int poll_robot(nav_devices_t *dv, const nav_sink_t *sink)
{
    rsm_p3dx_t *d = &dv->robot;
    rsm_p3dx_event_t ev;
    const int st = rsm_p3dx_poll(d, &ev);
    if (st != RSM_OK) {
        return st < 0 ? st : 0;
    }
    switch (ev.type) {
    case RSM_P3DX_EVENT_ENCODER:
        /* The first packet of a connection starts the counts over (a robot
         * that restarted counts from 0): the driver says so. A listener
         * has no connections: its counts just carry on. */
        sink->encoder(sink->ctx, &ev.encoder.sample, !dv->listen && !ev.encoder.has_delta);
        if (sink->tick != NULL) {
            sink->tick(sink->ctx, ev.stamp_us); /* a scan waiting for this sample goes on */
        }
        break;
    case RSM_P3DX_EVENT_CONNECTED:
        if (!dv->quiet) {
            fprintf(stderr,
                    "rsm-nav: robot connected: %s (%s %s) at %u Bd; TicksMM %u, watchdog %u ms, "
                    "AutoBaud %u\n",
                    d->robot.name, d->robot.robot_class, d->robot.subclass, (unsigned)d->baud,
                    (unsigned)d->ticks_mm, (unsigned)d->watchdog_ms, (unsigned)d->auto_baud);
        }
        if (sink->calibration != NULL) {
            /* The robot's own TicksMM (its CONFIGpac's, else the driver's default). */
            rsm_odometry_config_t odo = rsm_odometry_config_default();
            if (rsm_p3dx_odometry_config(d, &odo) == RSM_OK) {
                sink->calibration(sink->ctx, odo.ticks_per_m_left);
            }
        }
        break;
    case RSM_P3DX_EVENT_LINK_LOST:
        fprintf(stderr, "rsm-nav: robot link lost, reconnecting\n");
        break;
    case RSM_P3DX_EVENT_DISCONNECTED:
        if (!dv->quiet) {
            fprintf(stderr, "rsm-nav: robot disconnected (STOP, ENABLE 0, CLOSE sent)\n");
        }
        break;
    default:
        break;
    }
    return ev.type != RSM_P3DX_EVENT_NONE;
}

static int poll_laser(nav_devices_t *dv, const nav_sink_t *sink)
{
    rsm_sicklms_t *d = &dv->laser;
    rsm_sicklms_event_t ev;
    const int st = rsm_sicklms_poll(d, &ev);
    if (st != RSM_OK) {
        return st < 0 ? st : 0;
    }
    switch (ev.type) {
    case RSM_SICKLMS_EVENT_SCAN:
        if (ev.scan != NULL) {
            sink->scan(sink->ctx, ev.scan);
        }
        break;
    case RSM_SICKLMS_EVENT_CONNECTED:
        if (!dv->quiet) {
            fprintf(stderr, "rsm-nav: laser streaming at %u Bd (measuring mode 0x%02X, %u distance bits)\n",
                    (unsigned)d->baud, d->have_config ? (unsigned)d->config.measuring_mode : 0u,
                    (unsigned)d->format.distance_bits);
        }
        break;
    case RSM_SICKLMS_EVENT_LINK_LOST:
        fprintf(stderr, "rsm-nav: laser link lost, starting again\n");
        break;
    case RSM_SICKLMS_EVENT_ERROR:
        fprintf(stderr, "rsm-nav: laser start-up step failed: %s\n", rsm_strerror(ev.status));
        break;
    case RSM_SICKLMS_EVENT_DISCONNECTED:
        if (ev.status != RSM_OK) {
            fprintf(stderr, "rsm-nav: laser shutdown incomplete: %s\n", rsm_strerror(ev.status));
        } else if (!dv->quiet) {
            fprintf(stderr, "rsm-nav: laser stopped and back at %u Bd\n", (unsigned)d->baud);
        }
        break;
    default:
        break;
    }
    return ev.type != RSM_SICKLMS_EVENT_NONE;
}

int nav_devices_poll(nav_devices_t *dv, int robot, const nav_sink_t *sink)
{
    return robot ? poll_robot(dv, sink) : poll_laser(dv, sink);
}

uint64_t nav_devices_bytes(const nav_devices_t *dv, int robot)
{
    return robot ? dv->robot.io.bytes : dv->laser.io.bytes;
}

long nav_devices_drain(nav_devices_t *dv, int robot, const nav_sink_t *sink, uint64_t max_bytes)
{
    const uint64_t start = nav_devices_bytes(dv, robot);
    for (;;) {
        const uint64_t before = nav_devices_bytes(dv, robot);
        const int r = nav_devices_poll(dv, robot, sink);
        const uint64_t got = nav_devices_bytes(dv, robot) - start;
        if (r < 0) {
            return got > 0u ? (long)got : (long)r;
        }
        if ((r == 0 && nav_devices_bytes(dv, robot) == before) || got >= max_bytes) {
            return (long)got;
        }
    }
}

void nav_devices_report(const nav_devices_t *dv, int robot)
{
    if (robot) {
        const rsm_p3dx_t *d = &dv->robot;
        const rsm_p3dx_stats_t *st = &d->stats;
        fprintf(stderr,
                "rsm-nav: robot: %u Bd, %u connects (%u after a link loss), %u link losses, %u SIPs, "
                "%u encoder packets, %u keep-alives, %u motion commands, HOSTBAUD %u switched / "
                "%u failed / %u skipped; checksum errors %u, bytes skipped %u\n",
                (unsigned)d->baud, (unsigned)st->connects, (unsigned)st->reconnects,
                (unsigned)st->link_lost, (unsigned)st->sips, (unsigned)st->encoder_packets,
                (unsigned)st->keepalives, (unsigned)st->commands, (unsigned)st->host_baud_switches,
                (unsigned)st->host_baud_failures, (unsigned)st->host_baud_skipped,
                (unsigned)d->parser.stats.checksum_errors, (unsigned)d->parser.stats.bytes_skipped);
    } else {
        const rsm_sicklms_t *d = &dv->laser;
        const rsm_sicklms_stats_t *st = &d->stats;
        fprintf(stderr,
                "rsm-nav: laser: %u Bd, %u connects (%u after a link loss), %u link losses, %u scans, "
                "%u bad scans, %u start-up errors, %u shutdowns; CRC errors %u, bytes skipped %u\n",
                (unsigned)d->baud, (unsigned)st->connects, (unsigned)st->reconnects,
                (unsigned)st->link_lost, (unsigned)st->scans, (unsigned)st->bad_scans,
                (unsigned)st->errors, (unsigned)st->disconnects, (unsigned)d->parser.stats.crc_errors,
                (unsigned)d->parser.stats.bytes_skipped);
    }
}

/* ---- a memory link for recorded bytes ---------------------------------------- */

static int feed_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us)
{
    nav_feed_t *f = (nav_feed_t *)ctx;
    const size_t n = f->len - f->off < cap ? f->len - f->off : cap;
    (void)timeout_us; /* nothing more will come while the caller waits */
    if (n > 0u) {
        memcpy(buf, f->data + f->off, n);
        f->off += n;
    }
    return (int)n;
}

static int feed_write(void *ctx, const uint8_t *buf, size_t len)
{
    (void)ctx;
    (void)buf;
    (void)len;
    return RSM_ERR_IO;
}

static uint64_t feed_now(void *ctx)
{
    return ((const nav_feed_t *)ctx)->now_us;
}

void nav_feed_init(nav_feed_t *f, rsm_link_t *link, rsm_clock_t *clock)
{
    static const nav_feed_t empty = {NULL, 0u, 0u, 0u};
    /* read, write, no rate, no flush, ctx */
    const rsm_link_t feed_link = {feed_read, feed_write, NULL, NULL, NULL};
    *f = empty;
    *link = feed_link;
    link->ctx = f;
    clock->now_us = feed_now;
    clock->ctx = f;
}

void nav_devices_feed(nav_devices_t *dv, int robot, nav_feed_t *feed, const uint8_t *data, size_t len,
                      uint64_t stamp_us, const nav_sink_t *sink)
{
    feed->data = data;
    feed->len = len;
    feed->off = 0u;
    feed->now_us = stamp_us;
    (void)nav_devices_drain(dv, robot, sink, UINT64_MAX);
    /* After the packets: one past a waiting scan releases it exactly. */
    if (sink->tick != NULL) {
        sink->tick(sink->ctx, stamp_us);
    }
}
