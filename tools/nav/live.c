#include "live.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

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
 * up to the cap while it stays away (an adapter unplugged and plugged back).
 * An open alone does not start the back-off again: only a connection over
 * the reopened link (its driver's handshake or stream verified), so that a
 * device that opens and fails at once is not reopened ten times a second. */
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
    double backoff_s;          /* 0 until the first failure */
    uint32_t connects_at_open; /* the driver's CONNECTED count when the link was last opened */
    unsigned reopens;
    unsigned failures;         /* the link failed (active mode) */
    /* Losses (link failures and the driver's LINK_LOST events) seen so far,
     * and when the last one was: whether the device came back after it is
     * judged at the end of the run. */
    uint32_t losses;
    double lost_at;            /* seconds into the run */
    uint32_t back_mark;        /* laser: scans, robot: connects, at the last loss */
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
 * died). The link is closed and reopened later, never polled in a loop.
 * connects: the driver's CONNECTED count now. */
static void endpoint_failed(endpoint_t *e, int status, uint32_t connects)
{
    fprintf(stderr, "rsm-nav: %s link %s failed (%s): reopening\n", e->what, e->path, rsm_strerror(status));
    (void)rsm_posix_link_close(&e->state);
    e->down = 1;
    e->failures++;
    if (e->backoff_s <= 0.0 || connects != e->connects_at_open) {
        e->backoff_s = REOPEN_FIRST_S; /* the link had proved itself: a new outage */
    } else {
        e->backoff_s = e->backoff_s * 2.0 < REOPEN_MAX_S ? e->backoff_s * 2.0 : REOPEN_MAX_S;
    }
    e->retry_at = mono_s() + e->backoff_s;
}

/* Returns 1 when the link is open again (the driver must start over);
 * connects: the driver's CONNECTED count now. */
static int endpoint_retry(endpoint_t *e, int quiet, uint32_t connects)
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
    e->connects_at_open = connects;
    if (!quiet) {
        fprintf(stderr, "rsm-nav: %s link %s reopened\n", e->what, e->path);
    }
    return 1;
}

static int endpoint_fd(const endpoint_t *e)
{
    return (e->open && !e->ended && !e->down && e->state.kind == RSM_POSIX_LINK_FD) ? e->state.fd.fd : -1;
}

/* Both links and their drivers. */
typedef struct live {
    const nav_live_options_t *opt;
    const nav_sink_t *sink;
    endpoint_t *ep[2];        /* robot, laser */
    nav_devices_t dev;
    rsm_clock_t clock;        /* reads now_us: one time for a whole cycle */
    uint64_t now_us;          /* the monotonic clock when the cycle began */
    uint64_t bytes;
    double last_data;         /* when bytes last came */
    double t0;                /* when the run began */
    int clock_fd;             /* the lockstep feeder's clock file, or -1 */
} live_t;

/* rsm-replay --lockstep names, in this variable, a file holding the capture
 * time (8 bytes, little-endian microseconds) of the group of records it
 * wrote last, rewritten while the reader is held before each group. Taken
 * as the drivers' clock, it makes a live run a function of the capture
 * alone, times included: the run a capture gives in capture mode, over
 * pseudo-terminals and this loop. */
#define LIVE_LOCKSTEP_CLOCK_ENV "RSM_LOCKSTEP_CLOCK"

/* The time the drivers see: the feeder's clock file, else the monotonic
 * clock. */
static uint64_t live_clock_us(const live_t *lv)
{
    if (lv->clock_fd >= 0) {
        uint8_t b[8];
        if (pread(lv->clock_fd, b, sizeof b, 0) == (ssize_t)sizeof b) {
            uint64_t t = 0;
            int i;
            for (i = 7; i >= 0; --i) {
                t = (t << 8) | b[i];
            }
            return t;
        }
    }
    return rsm_posix_clock_now_us(NULL);
}

/* The drivers' clock: the time the current cycle began. Everything that
 * arrived in one wake-up is stamped alike on both links, as a capture
 * stamps the records of one instant (a lockstep replay then gives the
 * capture-mode run bit for bit, whatever the load). */
static uint64_t live_now(void *ctx)
{
    return ((const live_t *)ctx)->now_us;
}

/* Whether endpoint i is open and its driver usable. */
static int live_up(const live_t *lv, int i)
{
    const endpoint_t *e = lv->ep[i];
    return e->open && !e->ended && !e->down;
}

/* Waits until a link has bytes, the earliest driver deadline or link
 * retry, or 50 ms: one wait for both links. */
static void live_wait(live_t *lv)
{
    struct pollfd pf[2];
    nfds_t n = 0;
    double until = mono_s() + 0.05;
    const uint64_t now_us = live_clock_us(lv);
    int i;
    for (i = 0; i < 2; ++i) {
        const endpoint_t *e = lv->ep[i];
        const int fd = endpoint_fd(e);
        if (e->open && e->down && e->retry_at < until) {
            until = e->retry_at;
        }
        if (live_up(lv, i)) {
            const uint64_t due = nav_devices_next_deadline(&lv->dev, i == 0);
            if (due != UINT64_MAX) {
                const double at = mono_s() + (due > now_us ? (double)(due - now_us) * 1e-6 : 0.0);
                until = at < until ? at : until;
            }
            if (fd < 0) {
                /* A libserialport link cannot be waited on here: short naps. */
                until = mono_s() + 0.002 < until ? mono_s() + 0.002 : until;
            }
        }
        if (fd >= 0) {
            pf[n].fd = fd;
            pf[n].events = POLLIN;
            pf[n].revents = 0;
            ++n;
        }
    }
    {
        const double left = until - mono_s();
        /* At least 1 ms: a wait with a zero timeout is no wait (and a
         * lockstep feeder only writes while the reader truly waits). */
        const int ms = left <= 0.001 ? 1 : (int)(left * 1000.0 + 0.5);
        if (n > 0) {
            (void)poll(pf, n, ms);
        } else {
            struct timespec ts;
            ts.tv_sec = ms / 1000;
            ts.tv_nsec = (long)(ms % 1000) * 1000000L;
            nanosleep(&ts, NULL);
        }
    }
}

/* What shows that a device came back after a loss: the laser's scans, the
 * robot's connections. */
static uint32_t came_back_count(const live_t *lv, int i)
{
    return i == 0 ? nav_devices_connects(&lv->dev, 1) : nav_devices_scans(&lv->dev);
}

/* Active mode: notes a new loss of either device (its link failed, or its
 * driver reported LINK_LOST) with the time and what had come until then. */
static void live_note_losses(live_t *lv)
{
    int i;
    if (lv->dev.listen) {
        return; /* a link that fails there has ended: a replay finished */
    }
    for (i = 0; i < 2; ++i) {
        endpoint_t *e = lv->ep[i];
        const uint32_t losses = e->failures + nav_devices_losses(&lv->dev, i == 0);
        if (e->open && losses != e->losses) {
            e->losses = losses;
            e->lost_at = mono_s() - lv->t0;
            e->back_mark = came_back_count(lv, i);
        }
    }
}

/* Active mode: how long the device lost longest ago and not back since has
 * been gone, in seconds (0 when none is). */
static double live_lost_for(const live_t *lv)
{
    double most = 0.0;
    int i;
    for (i = 0; i < 2; ++i) {
        const endpoint_t *e = lv->ep[i];
        if (e->open && e->losses > 0u && came_back_count(lv, i) == e->back_mark) {
            const double gone = mono_s() - lv->t0 - e->lost_at;
            most = gone > most ? gone : most;
        }
    }
    return most;
}

/* Active mode, at the end of a run: a device lost and not back since (the
 * laser with no scan after the loss, the robot not connected again) is
 * said in one line into why. Returns 1 if any was. */
static int live_never_back(const live_t *lv, char *why, size_t cap)
{
    size_t at = 0;
    int i;
    why[0] = '\0';
    for (i = 0; i < 2; ++i) {
        const endpoint_t *e = lv->ep[i];
        int n;
        if (!e->open || e->losses == 0u || came_back_count(lv, i) != e->back_mark) {
            continue;
        }
        n = snprintf(why + at, cap - at, "%sthe %s link %s was lost %.1f s into the run and %s", at > 0u ? "; " : "",
                     e->what, e->path, e->lost_at,
                     i == 0 ? "the robot never connected again" : "no scan came after that");
        at = n < 0 ? at : (size_t)n + at < cap ? (size_t)n + at : cap - 1u;
    }
    return at > 0u;
}

/* One cycle: each driver (robot first: a replayer writes an encoder packet
 * before the scan it precedes, and this keeps that order whenever both have
 * arrived) takes what has arrived; a link that failed is reopened later
 * (active mode) or has ended (listen-only). Returns the bytes read. */
static uint64_t live_cycle(live_t *lv)
{
    uint64_t got = 0;
    int i;
    lv->now_us = live_clock_us(lv);
    for (i = 0; i < 2; ++i) {
        endpoint_t *e = lv->ep[i];
        long r;
        if (!e->open || e->ended) {
            continue;
        }
        if (e->down) {
            if (endpoint_retry(e, lv->opt->quiet, nav_devices_connects(&lv->dev, i == 0))) {
                nav_devices_restart(&lv->dev, i == 0, lv->sink);
            }
            continue;
        }
        r = nav_devices_drain(&lv->dev, i == 0, lv->sink, DRAIN_MAX_BYTES);
        if (r < 0 && lv->dev.listen) {
            /* The far end closed (a replay finished) or the device went away:
             * what was decoded so far stays written. */
            e->ended = 1;
            fprintf(stderr, "rsm-nav: %s link %s ended (%s)\n", e->what, e->path, rsm_strerror((int)r));
        } else if (r < 0) {
            endpoint_failed(e, (int)r, nav_devices_connects(&lv->dev, i == 0));
        } else {
            got += (uint64_t)r;
        }
    }
    live_note_losses(lv);
    if (got > 0u) {
        lv->bytes += got;
        lv->last_data = mono_s();
    } else if (lv->sink->tick != NULL) {
        /* Idle: a scan waiting for odometry may time out. The drivers
         * stamp with this clock, so the aligner's times agree. */
        lv->sink->tick(lv->sink->ctx, lv->now_us);
    }
    return got;
}

/* Orderly shutdown of both, run by the drivers' own polls: the robot gets
 * STOP and ENABLE 0, then CLOSE; the laser stops its stream and goes back
 * to its power-up rate. Bounded in time whatever the devices do. Then the
 * counters. Returns 0, or 1 if a device never connected. */
static int live_shutdown(live_t *lv)
{
    const double t_end = mono_s() + 5.0;
    const int robot_open = lv->ep[0]->open;
    const int laser_open = lv->ep[1]->open;
    int i;
    for (i = 0; i < 2; ++i) {
        if (live_up(lv, i)) {
            nav_devices_stop(&lv->dev, i == 0);
        }
    }
    while (mono_s() < t_end && ((live_up(lv, 0) && nav_devices_busy(&lv->dev, 1)) ||
                                (live_up(lv, 1) && nav_devices_busy(&lv->dev, 0)))) {
        lv->now_us = live_clock_us(lv);
        for (i = 0; i < 2; ++i) {
            if (live_up(lv, i) && nav_devices_busy(&lv->dev, i == 0) &&
                nav_devices_poll(&lv->dev, i == 0, lv->sink) < 0) {
                lv->ep[i]->ended = 1; /* gone: nothing more to say to it */
            }
        }
        live_wait(lv);
    }
    nav_devices_flush(&lv->dev, lv->sink); /* a turn may still wait for odometry */
    if (!lv->opt->quiet) {
        if (robot_open) {
            nav_devices_report(&lv->dev, 1);
            fprintf(stderr, "rsm-nav: robot link reopened %u times\n", lv->ep[0]->reopens);
        }
        if (laser_open) {
            nav_devices_report(&lv->dev, 0);
            fprintf(stderr, "rsm-nav: laser link reopened %u times\n", lv->ep[1]->reopens);
        }
    }
    {
        const int robot_never = robot_open && lv->dev.robot.stats.connects == 0u;
        const int laser_never = laser_open && nav_devices_connects(&lv->dev, 0) == 0u;
        if (robot_never || laser_never) {
            fprintf(stderr, "rsm-nav: no %s ever connected\n",
                    robot_never ? (laser_never ? "device" : "robot") : "laser");
            return 1;
        }
    }
    return 0;
}

static int live_run(live_t *lv)
{
    const nav_live_options_t *opt = lv->opt;
    const double t0 = mono_s();
    char why[512];
    int never_back;
    int rc;
    int i;
    lv->t0 = t0;
    nav_devices_defaults(&lv->dev, opt->listen_only, opt->quiet);
    lv->clock.now_us = live_now;
    lv->clock.ctx = lv;
    lv->now_us = live_clock_us(lv);
    /* One wait serves both links (live_wait): the drivers never block. */
    lv->dev.pcfg.read_timeout_us = 0u;
    lv->dev.lcfg.read_timeout_us = 0u;
    /* ARIA's parameter file for the p3dx-sh moves the robot to 38400 after
     * connecting; the driver does so only when the robot allows it. */
    lv->dev.pcfg.host_baud = 38400u;
    if (opt->robot_baud != 0u) {
        lv->dev.pcfg.baud = opt->robot_baud;
    }
    if (opt->lms_baud != 0u) {
        lv->dev.lcfg.baud = opt->lms_baud;
        lv->dev.ldcfg.baud = opt->lms_baud;
        lv->dev.slcfg.baud = opt->lms_baud;
    }
    lv->dev.ldcfg.read_timeout_us = 0u;
    lv->dev.slcfg.read_timeout_us = 0u;
    if (opt->laser != NAV_LASER_LMS) {
        if (opt->odometry != NULL) {
            nav_devices_odometry(&lv->dev, opt->odometry);
        }
        lv->dev.rcfg.deskew = (uint8_t)(opt->deskew != 0);
        if (nav_devices_lidar(&lv->dev, opt->laser, &opt->mount, opt->upside_down, opt->lidar_keep) != 0) {
            return 1;
        }
    }
    for (i = 0; i < 2; ++i) {
        if (lv->ep[i]->open && nav_devices_start(&lv->dev, i == 0, &lv->ep[i]->link, &lv->clock) != 0) {
            return 1;
        }
    }
    while (!stop_requested && !(lv->ep[0]->ended && lv->ep[1]->ended)) {
        (void)live_cycle(lv);
        if (opt->seconds > 0.0 && mono_s() - t0 >= opt->seconds) {
            break;
        }
        if (opt->max_scans > 0u && nav_devices_scans(&lv->dev) >= opt->max_scans &&
            (!lv->ep[0]->open || nav_devices_connects(&lv->dev, 1) > 0u)) {
            break; /* and the robot too has connected: its part of the run is there */
        }
        if (opt->idle_exit_s > 0.0 && lv->bytes > 0u && mono_s() - lv->last_data >= opt->idle_exit_s) {
            break;
        }
        if (opt->lost_exit_s > 0.0 && !lv->dev.listen && live_lost_for(lv) >= opt->lost_exit_s) {
            break;
        }
        live_wait(lv);
    }
    if (lv->dev.listen) {
        if (!opt->quiet) {
            fprintf(stderr, "rsm-nav: listen-only: %llu bytes, %u encoder packets, %u scans, %u bad scans\n",
                    (unsigned long long)lv->bytes, (unsigned)lv->dev.robot.stats.encoder_packets,
                    (unsigned)nav_devices_scans(&lv->dev), (unsigned)lv->dev.laser.stats.bad_scans);
        }
        if (lv->bytes == 0u && !stop_requested) {
            fprintf(stderr, "rsm-nav: nothing arrived on any link\n");
            return 1;
        }
        return 0;
    }
    never_back = live_never_back(lv, why, sizeof why);
    rc = live_shutdown(lv);
    if (rc == 0 && never_back && !stop_requested) {
        /* What ran is kept; the caller sums it up and fails. */
        fprintf(stderr, "rsm-nav: %s\n", why);
        return NAV_LIVE_NEVER_BACK;
    }
    return rc;
}

/* The rate the laser's link opens at: the flag's, else what the device
 * talks at first (an LMS at power-up 9600, a replayed LMS 38400; a lidar
 * its only rate). */
static uint32_t laser_baud(const nav_live_options_t *opt)
{
    if (opt->lms_baud != 0u) {
        return opt->lms_baud;
    }
    switch (opt->laser) {
    case NAV_LASER_LD06: return 230400u;
    case NAV_LASER_RPLIDAR: return 115200u;
    default: return opt->listen_only ? 38400u : 9600u;
    }
}

int nav_live_run(const nav_live_options_t *opt, const nav_sink_t *sink)
{
    static endpoint_t robot;
    static endpoint_t laser;
    static live_t lv;
    struct sigaction sa;
    int rc;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    if (open_endpoint(&robot, "robot", opt->robot,
                      opt->robot_baud ? opt->robot_baud : (opt->listen_only ? 38400u : 9600u)) != 0 ||
        open_endpoint(&laser, "laser", opt->lms, laser_baud(opt)) != 0) {
        if (robot.open) {
            (void)rsm_posix_link_close(&robot.state);
        }
        return 1;
    }
    memset(&lv, 0, sizeof lv);
    lv.clock_fd = -1;
    {
        const char *clock_path = getenv(LIVE_LOCKSTEP_CLOCK_ENV);
        if (clock_path != NULL && clock_path[0] != '\0') {
            lv.clock_fd = open(clock_path, O_RDONLY);
            if (lv.clock_fd < 0) {
                fprintf(stderr, "rsm-nav: cannot open the lockstep clock %s: %s\n", clock_path, strerror(errno));
                if (robot.open) {
                    (void)rsm_posix_link_close(&robot.state);
                }
                if (laser.open) {
                    (void)rsm_posix_link_close(&laser.state);
                }
                return 1;
            }
            if (!opt->quiet) {
                fprintf(stderr, "rsm-nav: clock: the lockstep feeder's capture time (%s)\n", clock_path);
            }
        }
    }
    lv.opt = opt;
    lv.sink = sink;
    lv.ep[0] = &robot;
    lv.ep[1] = &laser;
    rc = live_run(&lv);
    if (lv.clock_fd >= 0) {
        (void)close(lv.clock_fd);
    }
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
