#include "devices.h"

#include <stdio.h>
#include <string.h>

#include "rsm/status.h"

void nav_devices_defaults(nav_devices_t *dv, int listen, int quiet)
{
    memset(dv, 0, sizeof *dv);
    (void)rsm_p3dx_config_default(&dv->pcfg);
    (void)rsm_sicklms_config_default(&dv->lcfg);
    (void)rsm_ldlidar_config_default(&dv->ldcfg);
    (void)rsm_slamtec_config_default(&dv->slcfg);
    (void)rsm_rev_config_default(&dv->rcfg);
    {
        const rsm_odometry_config_t odo = rsm_odometry_config_default();
        (void)rsm_odometry_init(&dv->odo, &odo);
    }
    dv->kind = NAV_LASER_LMS;
    dv->listen = listen;
    dv->quiet = quiet;
}

/* A silence a listen-only run waits out (an hour): a replay held back, a
 * capture with a gap. */
#define NAV_LISTEN_PATIENCE_US 3600000000u

int nav_devices_lidar(nav_devices_t *dv, nav_laser_kind_t kind, const rsm_pose_t *mount, int upside_down,
                      unsigned keep_every)
{
    if (keep_every < 1u || keep_every > 64u) {
        fprintf(stderr, "rsm-nav: --lidar-keep must be 1 to 64\n");
        return -1;
    }
    dv->kind = kind;
    dv->rcfg.mount = *mount;
    dv->rcfg.upside_down = (uint8_t)(upside_down != 0);
    dv->rcfg.keep_every = (uint16_t)keep_every;
    if (dv->listen) {
        dv->rcfg.max_gap_us = NAV_LISTEN_PATIENCE_US;
        dv->ldcfg.stream_timeout_us = NAV_LISTEN_PATIENCE_US;
        dv->slcfg.stream_timeout_us = NAV_LISTEN_PATIENCE_US;
    }
    return 0;
}

void nav_devices_odometry(nav_devices_t *dv, const rsm_odometry_config_t *cfg)
{
    (void)rsm_odometry_set_config(&dv->odo, cfg);
}

static int start_laser(nav_devices_t *dv, const rsm_link_t *link, const rsm_clock_t *clock)
{
    if (dv->kind != NAV_LASER_LMS && rsm_rev_init(&dv->rev, &dv->rcfg) != RSM_OK) {
        return 0;
    }
    switch (dv->kind) {
    case NAV_LASER_LD06: /* listens whatever the mode: the sensor takes no commands */
        return rsm_ldlidar_init(&dv->ld06, link, clock, &dv->ldcfg) == RSM_OK &&
               rsm_ldlidar_connect(&dv->ld06) == RSM_OK;
    case NAV_LASER_RPLIDAR:
        return rsm_slamtec_init(&dv->rplidar, link, clock, &dv->slcfg) == RSM_OK &&
               (dv->listen ? rsm_slamtec_listen(&dv->rplidar) : rsm_slamtec_connect(&dv->rplidar)) == RSM_OK;
    default:
        return rsm_sicklms_init(&dv->laser, link, clock, &dv->lcfg, &dv->laser_scan) == RSM_OK &&
               (dv->listen ? rsm_sicklms_listen(&dv->laser) : rsm_sicklms_connect(&dv->laser)) == RSM_OK;
    }
}

static const char *laser_name(const nav_devices_t *dv)
{
    return dv->kind == NAV_LASER_LD06 ? "LD06" : dv->kind == NAV_LASER_RPLIDAR ? "RPLIDAR" : "LMS";
}

int nav_devices_start(nav_devices_t *dv, int robot, const rsm_link_t *link, const rsm_clock_t *clock)
{
    int ok;
    if (robot) {
        ok = rsm_p3dx_init(&dv->robot, link, clock, &dv->pcfg) == RSM_OK &&
             (dv->listen ? rsm_p3dx_listen(&dv->robot) : rsm_p3dx_connect(&dv->robot)) == RSM_OK;
    } else {
        ok = start_laser(dv, link, clock);
    }
    if (!ok) {
        fprintf(stderr, "rsm-nav: cannot start the %s driver\n", robot ? "P3-DX" : laser_name(dv));
        return -1;
    }
    return 0;
}

/* An encoder sample as a pose for the de-skew, on the clock the lidar's
 * points are stamped with. */
static void lidar_odometry(nav_devices_t *dv, const rsm_odometry_sample_t *s, int restart)
{
    rsm_motion_t u;
    if (restart) {
        rsm_odometry_restart(&dv->odo);
    }
    if (rsm_odometry_update_ticks_at(&dv->odo, s->left, s->right, s->stamp_us, &u) == RSM_OK) {
        dv->odo_pose = rsm_odometry_apply(&dv->odo_pose, &u);
    }
    (void)rsm_rev_odometry(&dv->rev, s->stamp_us, &dv->odo_pose);
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
        if (dv->kind != NAV_LASER_LMS) {
            lidar_odometry(dv, &ev.encoder.sample, !dv->listen && !ev.encoder.has_delta);
        }
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
            /* The robot's own TicksMM (its CONFIGpac's, else the driver's
             * default). When the run takes it, a lidar's de-skew converts
             * the counts with it too: the same motion as the localizer's. */
            rsm_odometry_config_t odo = dv->odo.cfg;
            if (rsm_p3dx_odometry_config(d, &odo) == RSM_OK && sink->calibration(sink->ctx, odo.ticks_per_m_left)) {
                (void)rsm_odometry_set_config(&dv->odo, &odo);
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

/* A lidar's points into the assembler; each completed turn to sink. */
static void lidar_points(nav_devices_t *dv, const rsm_lidar_point_t *pts, size_t n, const nav_sink_t *sink)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        if (rsm_rev_push(&dv->rev, &pts[i]) == 1) {
            sink->scan(sink->ctx, &dv->rev.scan);
        }
    }
}

/* No more points for now (link lost, restarted, the stream ended): a whole
 * turn still waiting for odometry goes to sink with what there is, then
 * the turn in progress is dropped. */
static void lidar_stop(nav_devices_t *dv, const nav_sink_t *sink)
{
    nav_devices_flush(dv, sink);
    rsm_rev_reset(&dv->rev);
}

void nav_devices_flush(nav_devices_t *dv, const nav_sink_t *sink)
{
    /* The turn in progress is left as it is: a stream that ends in mid-turn
     * counts no partial turn. */
    if (dv->kind != NAV_LASER_LMS && rsm_rev_flush(&dv->rev) == 1 && sink != NULL) {
        sink->scan(sink->ctx, &dv->rev.scan);
    }
}

static int poll_ld06(nav_devices_t *dv, const nav_sink_t *sink)
{
    rsm_ldlidar_event_t ev;
    const int st = rsm_ldlidar_poll(&dv->ld06, &ev);
    if (st != RSM_OK) {
        return st < 0 ? st : 0;
    }
    switch (ev.type) {
    case RSM_LDLIDAR_EVENT_POINTS:
        lidar_points(dv, ev.points, ev.count, sink);
        break;
    case RSM_LDLIDAR_EVENT_CONNECTED:
        if (!dv->quiet) {
            fprintf(stderr, "rsm-nav: LD06 streaming\n");
        }
        break;
    case RSM_LDLIDAR_EVENT_LINK_LOST:
        fprintf(stderr, "rsm-nav: LD06 link lost, listening again\n");
        lidar_stop(dv, sink); /* the turn in progress has a hole */
        break;
    default:
        break;
    }
    return ev.type != RSM_LDLIDAR_EVENT_NONE;
}

static int poll_rplidar(nav_devices_t *dv, const nav_sink_t *sink)
{
    static rsm_slamtec_event_t ev; /* large (a capsule's points): not on the stack */
    rsm_slamtec_t *d = &dv->rplidar;
    const int st = rsm_slamtec_poll(d, &ev);
    if (st != RSM_OK) {
        return st < 0 ? st : 0;
    }
    switch (ev.type) {
    case RSM_SLAMTEC_EVENT_POINTS:
        lidar_points(dv, ev.points, ev.count, sink);
        break;
    case RSM_SLAMTEC_EVENT_CONNECTED:
        if (!dv->quiet) {
            fprintf(stderr, "rsm-nav: RPLIDAR scanning: model 0x%02X, firmware %u.%02u, health %u\n",
                    (unsigned)d->info.model, (unsigned)d->info.firmware_major,
                    (unsigned)d->info.firmware_minor, (unsigned)d->health.status);
        }
        break;
    case RSM_SLAMTEC_EVENT_LINK_LOST:
        fprintf(stderr, "rsm-nav: RPLIDAR link lost, starting again\n");
        lidar_stop(dv, sink);
        break;
    case RSM_SLAMTEC_EVENT_ERROR:
        fprintf(stderr, "rsm-nav: RPLIDAR start-up step failed: %s\n", rsm_strerror(ev.status));
        break;
    case RSM_SLAMTEC_EVENT_DISCONNECTED:
        if (!dv->quiet) {
            fprintf(stderr, "rsm-nav: RPLIDAR stopped\n");
        }
        break;
    default:
        break;
    }
    return ev.type != RSM_SLAMTEC_EVENT_NONE;
}

int nav_devices_poll(nav_devices_t *dv, int robot, const nav_sink_t *sink)
{
    if (robot) {
        return poll_robot(dv, sink);
    }
    switch (dv->kind) {
    case NAV_LASER_LD06: return poll_ld06(dv, sink);
    case NAV_LASER_RPLIDAR: return poll_rplidar(dv, sink);
    default: return poll_laser(dv, sink);
    }
}

uint64_t nav_devices_bytes(const nav_devices_t *dv, int robot)
{
    if (robot) {
        return dv->robot.io.bytes;
    }
    switch (dv->kind) {
    case NAV_LASER_LD06: return dv->ld06.io.bytes;
    case NAV_LASER_RPLIDAR: return dv->rplidar.io.bytes;
    default: return dv->laser.io.bytes;
    }
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
    } else if (dv->kind != NAV_LASER_LMS) {
        const rsm_rev_stats_t *rs = &dv->rev.stats;
        if (dv->kind == NAV_LASER_LD06) {
            const rsm_ldlidar_t *d = &dv->ld06;
            fprintf(stderr,
                    "rsm-nav: LD06: %u packets, %u points, %u connects, %u link losses; CRC errors %u,"
                    " bytes skipped %u\n",
                    (unsigned)d->stats.packets, (unsigned)d->stats.points, (unsigned)d->stats.connects,
                    (unsigned)d->stats.link_lost, (unsigned)d->parser.stats.crc_errors,
                    (unsigned)d->parser.stats.bytes_skipped);
        } else {
            const rsm_slamtec_t *d = &dv->rplidar;
            fprintf(stderr,
                    "rsm-nav: RPLIDAR: %u requests (%u retries, %u timeouts), %u points, %u connects,"
                    " %u link losses, %u errors\n",
                    (unsigned)d->stats.requests, (unsigned)d->stats.retries, (unsigned)d->stats.timeouts,
                    (unsigned)d->stats.points, (unsigned)d->stats.connects, (unsigned)d->stats.link_lost,
                    (unsigned)d->stats.errors);
        }
        fprintf(stderr,
                "rsm-nav: turns: %u scans, %u partial (%u points), %u points over the scan size, %u thinned,"
                " %u without return, %u bad points, %u not de-skewed, %u over 2 s; %u points left as measured"
                " (implausible odometry), %u odometry bursts, %u turns waited for odometry (%u de-skewed"
                " without odometry past their end); de-skew odometry %.0f ticks/m\n",
                (unsigned)rs->scans, (unsigned)rs->partial, (unsigned)rs->dropped, (unsigned)rs->overflow,
                (unsigned)rs->thinned, (unsigned)rs->invalid, (unsigned)rs->bad_points,
                (unsigned)rs->not_deskewed, (unsigned)rs->long_turns, (unsigned)rs->implausible,
                (unsigned)rs->odometry_bursts, (unsigned)rs->waited, (unsigned)rs->uncovered,
                (double)dv->odo.cfg.ticks_per_m_left);
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

/* ---- what live mode asks of either laser -------------------------------------- */

void nav_devices_restart(nav_devices_t *dv, int robot, const nav_sink_t *sink)
{
    if (robot) {
        (void)rsm_p3dx_connect(&dv->robot);
        return;
    }
    switch (dv->kind) {
    case NAV_LASER_LD06:
        lidar_stop(dv, sink);
        (void)rsm_ldlidar_connect(&dv->ld06);
        break;
    case NAV_LASER_RPLIDAR:
        lidar_stop(dv, sink);
        (void)rsm_slamtec_connect(&dv->rplidar);
        break;
    default:
        (void)rsm_sicklms_connect(&dv->laser);
        break;
    }
}

void nav_devices_stop(nav_devices_t *dv, int robot)
{
    if (robot) {
        (void)rsm_p3dx_disconnect(&dv->robot);
        return;
    }
    switch (dv->kind) {
    case NAV_LASER_LD06: (void)rsm_ldlidar_disconnect(&dv->ld06); break;
    case NAV_LASER_RPLIDAR: (void)rsm_slamtec_disconnect(&dv->rplidar); break;
    default: (void)rsm_sicklms_disconnect(&dv->laser); break;
    }
}

int nav_devices_busy(const nav_devices_t *dv, int robot)
{
    if (robot) {
        return dv->robot.state != RSM_P3DX_IDLE;
    }
    switch (dv->kind) {
    case NAV_LASER_LD06: return dv->ld06.state != RSM_LDLIDAR_IDLE;
    case NAV_LASER_RPLIDAR: return dv->rplidar.state != RSM_SLAMTEC_IDLE;
    default: return dv->laser.state != RSM_SICKLMS_IDLE;
    }
}

uint32_t nav_devices_connects(const nav_devices_t *dv, int robot)
{
    if (robot) {
        return dv->robot.stats.connects;
    }
    switch (dv->kind) {
    case NAV_LASER_LD06: return dv->ld06.stats.connects;
    case NAV_LASER_RPLIDAR: return dv->rplidar.stats.connects;
    default: return dv->laser.stats.connects;
    }
}

uint32_t nav_devices_losses(const nav_devices_t *dv, int robot)
{
    if (robot) {
        return dv->robot.stats.link_lost;
    }
    switch (dv->kind) {
    case NAV_LASER_LD06: return dv->ld06.stats.link_lost;
    case NAV_LASER_RPLIDAR: return dv->rplidar.stats.link_lost;
    default: return dv->laser.stats.link_lost;
    }
}

uint32_t nav_devices_scans(const nav_devices_t *dv)
{
    return dv->kind == NAV_LASER_LMS ? dv->laser.stats.scans : dv->rev.stats.scans;
}

uint64_t nav_devices_next_deadline(const nav_devices_t *dv, int robot)
{
    if (robot) {
        return rsm_p3dx_next_deadline_us(&dv->robot);
    }
    switch (dv->kind) {
    case NAV_LASER_LD06: return rsm_ldlidar_next_deadline_us(&dv->ld06);
    case NAV_LASER_RPLIDAR: return rsm_slamtec_next_deadline_us(&dv->rplidar);
    default: return rsm_sicklms_next_deadline_us(&dv->laser);
    }
}
