/* rsm-nav live mode: the robot and laser serial links (devices or
 * pseudo-terminals) through the POSIX port, with the library's drivers.
 * Active mode drives both devices (P3-DX handshake and encoder packets, LMS
 * start-up and continuous output); listen-only mode (the drivers' own)
 * sends nothing and decodes what arrives, e.g. from rsm-replay. Both wait
 * once for all links: until bytes arrive or the earliest driver deadline,
 * then poll each driver without waiting, on a clock that reads the time the
 * wake-up began (so both links stamp what came in one wake-up alike). */
#ifndef RSM_NAV_LIVE_H
#define RSM_NAV_LIVE_H

#include <stdint.h>

#include "devices.h"

typedef struct nav_live_options {
    const char *robot;        /* device or pty path, NULL: no robot link */
    const char *lms;          /* device or pty path */
    uint32_t robot_baud;      /* default 9600 (active), 38400 (listen) */
    uint32_t lms_baud;
    int listen_only;          /* 1: send nothing, decode the incoming streams */
    double seconds;           /* stop after this long (0: until the links end or a signal) */
    double idle_exit_s;       /* listen-only: stop after this long without bytes once data flowed (0: never) */
    int quiet;
} nav_live_options_t;

/* Runs until both links end, the time limit passes, or SIGINT/SIGTERM.
 * Events go to sink. Returns 0, or 1 if a link cannot be opened (message on
 * stderr). */
int nav_live_run(const nav_live_options_t *opt, const nav_sink_t *sink);

#endif
