#include "live.h"

#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "rsm/p3dx.h"
#include "rsm/sicklms.h"
#include "rsm/status.h"
#include "rsm_posix.h"

/* Set by the signal handler: the one piece of process-wide state a clean
 * Ctrl-C needs (this is the host tool, not the library). */
static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* Active mode: a device that went away is reopened after this long, doubling
 * up to the cap while it stays away (an adapter unplugged and plugged back). */
#define REOPEN_FIRST_S 0.1
#define REOPEN_MAX_S 2.0
/* Listen mode: bytes taken from one link per wake-up, so that a source that
 * never runs dry still lets the loop see the time limit and signals. */
#define DRAIN_MAX_BYTES 65536

typedef struct endpoint {
    const char *path;
    const char *what;          /* "robot" or "laser" */
    uint32_t baud;             /* rate it was opened at */
    rsm_posix_auto_link_t state;
    rsm_link_t link;
    int open;
    int ended;
    int down;                  /* active mode: the link failed; reopened at retry_at */
    double retry_at;
    double backoff_s;
    unsigned reopens;
} endpoint_t;

static void report_open_error(const endpoint_t *e, int rc)
{
    const int err = rsm_posix_auto_errno(&e->state);
    fprintf(stderr, "rsm-nav: cannot open %s: %s%s%s\n", e->path, rsm_strerror(rc), err ? ": " : "",
            err ? strerror(err) : "");
}

static int open_endpoint(endpoint_t *e, const char *what, const char *path, uint32_t baud)
{
    int rc;
    memset(e, 0, sizeof *e);
    e->path = path;
    e->what = what;
    e->baud = baud;
    if (path == NULL) {
        e->ended = 1;
        return 0;
    }
    rc = rsm_posix_link_open_auto(&e->state, path, baud, 0u, &e->link);
    if (rc != RSM_OK) {
        report_open_error(e, rc);
        return -1;
    }
    e->open = 1;
    return 0;
}

/* Active mode: the driver's poll failed (the device vanished, the peer
 * died). The link is closed and reopened later, never polled in a loop. */
static void endpoint_failed(endpoint_t *e, int status)
{
    fprintf(stderr, "rsm-nav: %s link %s failed (%s): reopening\n", e->what, e->path, rsm_strerror(status));
    (void)rsm_posix_link_close(&e->state);
    e->down = 1;
    e->backoff_s = REOPEN_FIRST_S;
    e->retry_at = mono_s() + e->backoff_s;
}

/* Returns 1 when the link is open again (the driver must start over). */
static int endpoint_retry(endpoint_t *e, int quiet)
{
    int rc;
    if (mono_s() < e->retry_at) {
        return 0;
    }
    rc = rsm_posix_link_open_auto(&e->state, e->path, e->baud, 0u, &e->link);
    if (rc != RSM_OK) {
        e->backoff_s = e->backoff_s * 2.0 < REOPEN_MAX_S ? e->backoff_s * 2.0 : REOPEN_MAX_S;
        e->retry_at = mono_s() + e->backoff_s;
        return 0;
    }
    e->down = 0;
    e->reopens++;
    if (!quiet) {
        fprintf(stderr, "rsm-nav: %s link %s reopened\n", e->what, e->path);
    }
    return 1;
}

/* Sleeps until the earlier retry of the links that are down (at most 50 ms),
 * when no open link would make the loop wait. */
static void nap_while_down(const endpoint_t *a, const endpoint_t *b)
{
    double until = mono_s() + 0.05;
    struct timespec ts;
    double left;
    if ((a->open && !a->down) || (b->open && !b->down)) {
        return; /* the other driver's poll waits on its link */
    }
    if (a->open && a->down && a->retry_at < until) {
        until = a->retry_at;
    }
    if (b->open && b->down && b->retry_at < until) {
        until = b->retry_at;
    }
    left = until - mono_s();
    if (left <= 0.0) {
        return;
    }
    ts.tv_sec = 0;
    ts.tv_nsec = (long)(left * 1e9);
    nanosleep(&ts, NULL);
}

static int endpoint_fd(const endpoint_t *e)
{
    return (e->open && !e->ended && e->state.kind == RSM_POSIX_LINK_FD) ? e->state.fd.fd : -1;
}

/* Reads what is waiting on one link (no waiting); returns bytes fed or -1 at its end. */
static int drain(endpoint_t *e, nav_stream_t *s, int robot, const nav_stream_sink_t *sink, uint64_t now_us)
{
    uint8_t buf[4096];
    int total = 0;
    while (total < DRAIN_MAX_BYTES) {
        const int n = rsm_link_read(&e->link, buf, sizeof buf, 0u);
        if (n < 0) {
            /* The far end closed (a replay finished) or the device went away:
             * what was decoded so far stays written. */
            e->ended = 1;
            fprintf(stderr, "rsm-nav: %s link %s ended (%s)\n", robot ? "robot" : "laser", e->path,
                    rsm_strerror(n));
            return total > 0 ? total : -1;
        }
        if (n == 0) {
            return total;
        }
        if (robot) {
            nav_stream_robot(s, buf, (size_t)n, now_us, sink);
        } else {
            nav_stream_laser(s, buf, (size_t)n, now_us, sink);
        }
        total += n;
    }
    return total;
}

static int run_listen(const nav_live_options_t *opt, endpoint_t *robot, endpoint_t *laser,
                      const nav_stream_sink_t *sink)
{
    static nav_stream_t stream;
    const double t0 = mono_s();
    double last_data = 0.0;
    uint64_t bytes = 0;
    nav_stream_init(&stream);
    while (!stop_requested && !(robot->ended && laser->ended)) {
        struct pollfd pf[2];
        nfds_t n = 0;
        const int fr = endpoint_fd(robot);
        const int fl = endpoint_fd(laser);
        uint64_t now_us;
        int got;
        if (fr >= 0) {
            pf[n].fd = fr;
            pf[n].events = POLLIN;
            pf[n].revents = 0;
            ++n;
        }
        if (fl >= 0) {
            pf[n].fd = fl;
            pf[n].events = POLLIN;
            pf[n].revents = 0;
            ++n;
        }
        if (n > 0) {
            (void)poll(pf, n, 50);
        } else {
            struct timespec ts = {0, 2000000L}; /* libserialport links: short naps */
            nanosleep(&ts, NULL);
        }
        now_us = (uint64_t)((mono_s() - t0) * 1e6);
        /* Robot before laser within one wake-up: a replayer writes an
         * encoder packet before the scan it precedes, and this keeps that
         * order whenever both have arrived. */
        got = 0;
        if (!robot->ended) {
            const int r = drain(robot, &stream, 1, sink, now_us);
            got += r > 0 ? r : 0;
        }
        if (!laser->ended) {
            const int r = drain(laser, &stream, 0, sink, now_us);
            got += r > 0 ? r : 0;
        }
        if (got > 0) {
            bytes += (uint64_t)got;
            last_data = mono_s();
        } else if (sink->tick != NULL) {
            sink->tick(sink->ctx, now_us); /* a scan waiting for odometry may time out */
        }
        if (opt->seconds > 0.0 && mono_s() - t0 >= opt->seconds) {
            break;
        }
        if (opt->idle_exit_s > 0.0 && bytes > 0 && mono_s() - last_data >= opt->idle_exit_s) {
            break;
        }
    }
    if (!opt->quiet) {
        fprintf(stderr, "rsm-nav: listen-only: %llu bytes, %llu encoder packets, %llu scans, %llu bad scans\n",
                (unsigned long long)bytes, (unsigned long long)stream.encoder_packets,
                (unsigned long long)stream.lms_scans, (unsigned long long)stream.bad_scans);
    }
    if (bytes == 0u && !stop_requested) {
        fprintf(stderr, "rsm-nav: nothing arrived on any link\n");
        return 1;
    }
    return 0;
}

static void report_robot(const rsm_p3dx_t *d)
{
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
}

static void report_laser(const rsm_sicklms_t *d)
{
    const rsm_sicklms_stats_t *st = &d->stats;
    fprintf(stderr,
            "rsm-nav: laser: %u Bd, %u connects (%u after a link loss), %u link losses, %u scans, "
            "%u bad scans, %u start-up errors, %u shutdowns; CRC errors %u, bytes skipped %u\n",
            (unsigned)d->baud, (unsigned)st->connects, (unsigned)st->reconnects,
            (unsigned)st->link_lost, (unsigned)st->scans, (unsigned)st->bad_scans,
            (unsigned)st->errors, (unsigned)st->disconnects, (unsigned)d->parser.stats.crc_errors,
            (unsigned)d->parser.stats.bytes_skipped);
}

/* One poll of the robot driver; encoder packets go to the sink. Returns 1
 * if the poll gave an event, 0 if not, a negative status if the link failed. */
static int poll_robot(rsm_p3dx_t *d, const nav_stream_sink_t *sink, int quiet)
{
    rsm_p3dx_event_t ev;
    const int st = rsm_p3dx_poll(d, &ev);
    if (st != RSM_OK) {
        return st < 0 ? st : 0;
    }
    switch (ev.type) {
    case RSM_P3DX_EVENT_ENCODER:
        /* The first packet of a connection starts the counts over (a robot
         * that restarted counts from 0): the driver says so. */
        sink->encoder(sink->ctx, &ev.encoder.sample, !ev.encoder.has_delta);
        if (sink->tick != NULL) {
            sink->tick(sink->ctx, ev.stamp_us); /* a scan waiting for this sample goes on */
        }
        break;
    case RSM_P3DX_EVENT_CONNECTED:
        if (!quiet) {
            fprintf(stderr,
                    "rsm-nav: robot connected: %s (%s %s) at %u Bd; TicksMM %u, watchdog %u ms, "
                    "AutoBaud %u\n",
                    d->robot.name, d->robot.robot_class, d->robot.subclass, (unsigned)d->baud,
                    (unsigned)d->ticks_mm, (unsigned)d->watchdog_ms, (unsigned)d->auto_baud);
        }
        if (sink->calibration != NULL) {
            /* The robot's own TicksMM (its CONFIGpac's, else the driver's default). */
            sink->calibration(sink->ctx, (float)d->ticks_mm * 1000.0f);
        }
        break;
    case RSM_P3DX_EVENT_LINK_LOST:
        fprintf(stderr, "rsm-nav: robot link lost, reconnecting\n");
        break;
    case RSM_P3DX_EVENT_DISCONNECTED:
        if (!quiet) {
            fprintf(stderr, "rsm-nav: robot disconnected (STOP, ENABLE 0, CLOSE sent)\n");
        }
        break;
    default:
        break;
    }
    return ev.type != RSM_P3DX_EVENT_NONE;
}

/* One poll of the laser driver; scans go to the sink. Returns 1 if the poll
 * gave an event, 0 if not, a negative status if the link failed. */
static int poll_laser(rsm_sicklms_t *d, const nav_stream_sink_t *sink, int quiet)
{
    rsm_sicklms_event_t ev;
    const int st = rsm_sicklms_poll(d, &ev);
    if (st != RSM_OK) {
        return st < 0 ? st : 0;
    }
    switch (ev.type) {
    case RSM_SICKLMS_EVENT_SCAN:
        if (ev.scan != NULL) {
            sink->scan(sink->ctx, ev.scan, ev.stamp_us);
        }
        break;
    case RSM_SICKLMS_EVENT_CONNECTED:
        if (!quiet) {
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
        } else if (!quiet) {
            fprintf(stderr, "rsm-nav: laser stopped and back at %u Bd\n", (unsigned)d->baud);
        }
        break;
    default:
        break;
    }
    return ev.type != RSM_SICKLMS_EVENT_NONE;
}

static int run_active(const nav_live_options_t *opt, endpoint_t *robot, endpoint_t *laser,
                      const nav_stream_sink_t *sink)
{
    static rsm_p3dx_t p3dx;
    static rsm_sicklms_t lms;
    rsm_p3dx_config_t pcfg;
    rsm_sicklms_config_t lcfg;
    rsm_clock_t clock;
    const double t0 = mono_s();
    double t_end;
    int robot_live;
    int laser_live;
    (void)rsm_p3dx_config_default(&pcfg);
    (void)rsm_sicklms_config_default(&lcfg);
    (void)rsm_posix_clock_init(&clock);
    /* ARIA's parameter file for the p3dx-sh moves the robot to 38400 after
     * connecting; the driver does so only when the robot allows it. */
    pcfg.host_baud = 38400u;
    if (opt->robot_baud != 0u) {
        pcfg.baud = opt->robot_baud;
    }
    if (opt->lms_baud != 0u) {
        lcfg.baud = opt->lms_baud;
    }
    if (robot->open && (rsm_p3dx_init(&p3dx, &robot->link, &clock, &pcfg) != RSM_OK || rsm_p3dx_connect(&p3dx) != RSM_OK)) {
        fprintf(stderr, "rsm-nav: cannot start the P3-DX driver\n");
        return 1;
    }
    if (laser->open && (rsm_sicklms_init(&lms, &laser->link, &clock, &lcfg) != RSM_OK || rsm_sicklms_connect(&lms) != RSM_OK)) {
        fprintf(stderr, "rsm-nav: cannot start the LMS driver\n");
        return 1;
    }
    while (!stop_requested) {
        int events = 0;
        if (robot->open && robot->down) {
            if (endpoint_retry(robot, opt->quiet)) {
                (void)rsm_p3dx_connect(&p3dx);
            }
        } else if (robot->open) {
            const int r = poll_robot(&p3dx, sink, opt->quiet);
            if (r < 0) {
                endpoint_failed(robot, r);
            } else {
                events += r;
            }
        }
        if (laser->open && laser->down) {
            if (endpoint_retry(laser, opt->quiet)) {
                (void)rsm_sicklms_connect(&lms);
            }
        } else if (laser->open) {
            const int r = poll_laser(&lms, sink, opt->quiet);
            if (r < 0) {
                endpoint_failed(laser, r);
            } else {
                events += r;
            }
        }
        nap_while_down(robot, laser);
        if (events == 0 && sink->tick != NULL) {
            /* Idle: a scan waiting for odometry may time out. The drivers
             * stamp with this clock, so the aligner's times agree. */
            sink->tick(sink->ctx, rsm_posix_clock_now_us(NULL));
        }
        if (opt->seconds > 0.0 && mono_s() - t0 >= opt->seconds) {
            break;
        }
    }
    /* Orderly shutdown of both, run by the drivers' own polls: the robot
     * gets STOP and ENABLE 0, then CLOSE; the laser stops its stream and
     * goes back to its power-up rate. Bounded in time whatever the
     * devices do. */
    if (robot->open && !robot->down) {
        (void)rsm_p3dx_disconnect(&p3dx);
    }
    if (laser->open && !laser->down) {
        (void)rsm_sicklms_disconnect(&lms);
    }
    t_end = mono_s() + 5.0;
    robot_live = robot->open && !robot->down;
    laser_live = laser->open && !laser->down;
    while (mono_s() < t_end && ((robot_live && p3dx.state != RSM_P3DX_IDLE) ||
                                (laser_live && lms.state != RSM_SICKLMS_IDLE))) {
        if (robot_live && p3dx.state != RSM_P3DX_IDLE && poll_robot(&p3dx, sink, opt->quiet) < 0) {
            robot_live = 0; /* gone: nothing more to say to it */
        }
        if (laser_live && lms.state != RSM_SICKLMS_IDLE && poll_laser(&lms, sink, opt->quiet) < 0) {
            laser_live = 0;
        }
    }
    if (!opt->quiet) {
        if (robot->open) {
            report_robot(&p3dx);
            fprintf(stderr, "rsm-nav: robot link reopened %u times\n", robot->reopens);
        }
        if (laser->open) {
            report_laser(&lms);
            fprintf(stderr, "rsm-nav: laser link reopened %u times\n", laser->reopens);
        }
    }
    if ((robot->open && p3dx.stats.connects == 0u) || (laser->open && lms.stats.connects == 0u)) {
        fprintf(stderr, "rsm-nav: no %s ever connected\n",
                robot->open && p3dx.stats.connects == 0u
                    ? (laser->open && lms.stats.connects == 0u ? "device" : "robot")
                    : "laser");
        return 1;
    }
    return 0;
}

int nav_live_run(const nav_live_options_t *opt, const nav_stream_sink_t *sink)
{
    static endpoint_t robot;
    static endpoint_t laser;
    struct sigaction sa;
    int rc;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    if (open_endpoint(&robot, "robot", opt->robot,
                      opt->robot_baud ? opt->robot_baud : (opt->listen_only ? 38400u : 9600u)) != 0 ||
        open_endpoint(&laser, "laser", opt->lms,
                      opt->lms_baud ? opt->lms_baud : (opt->listen_only ? 38400u : 9600u)) != 0) {
        if (robot.open) {
            (void)rsm_posix_link_close(&robot.state);
        }
        return 1;
    }
    rc = opt->listen_only ? run_listen(opt, &robot, &laser, sink) : run_active(opt, &robot, &laser, sink);
    if (stop_requested && !opt->quiet) {
        fprintf(stderr, "rsm-nav: stopped by signal\n");
    }
    if (robot.open && !robot.down) {
        (void)rsm_posix_link_close(&robot.state);
    }
    if (laser.open && !laser.down) {
        (void)rsm_posix_link_close(&laser.state);
    }
    return rc;
}
