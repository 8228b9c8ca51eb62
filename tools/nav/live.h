/* rsm-nav live mode: the robot and laser serial links (devices or
 * pseudo-terminals) through the POSIX port, with the library's drivers.
 * Active mode drives both devices (P3-DX handshake and encoder packets, LMS
 * start-up and continuous output, or an RPLIDAR's start-up and scan; an
 * LD06 only ever talks); listen-only mode (the drivers' own)
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
    const char *lms;          /* the laser's device or pty path (LMS or lidar) */
    nav_laser_kind_t laser;   /* which laser is on it */
    rsm_pose_t mount;         /* lidar: the localizer's laser_mount and upside-down flag, */
    int upside_down;          /* for the de-skew */
    unsigned lidar_keep;      /* lidar: keep one point in this many (>= 1) */
    int deskew;               /* lidar: 1 de-skews every turn with the odometry */
    const rsm_odometry_config_t *odometry; /* the encoder geometry the de-skew starts with */
    uint32_t robot_baud;      /* default 9600 (active), 38400 (listen) */
    uint32_t lms_baud;        /* 0: the laser driver's default (live), 38400 (LMS listen) */
    int listen_only;          /* 1: send nothing, decode the incoming streams */
    double seconds;           /* stop after this long (0: until the links end or a signal) */
    uint64_t max_scans;       /* stop once the laser gave this many scans and the robot (if
                                 any) connected (0: no limit): a run's length that does not
                                 depend on the machine's speed */
    double idle_exit_s;       /* listen-only: stop after this long without bytes once data flowed (0: never) */
    double lost_exit_s;       /* active: stop once a device has been lost this long and is not
                                 back (0: never): a run that ends on the loss, however long its
                                 start took */
    int quiet;
} nav_live_options_t;

/* nav_live_run's status for a run that went to its end (the time limit,
 * --idle-exit or --lost-exit) with a device lost and not back since: the laser gave no scan
 * after its loss, or the robot never connected again (active mode; one line
 * on stderr says which). What ran is valid: the caller sums it up, then
 * fails. */
#define NAV_LIVE_NEVER_BACK 3

/* Runs until both links end, the time limit passes, or SIGINT/SIGTERM.
 * Events go to sink. Returns 0, NAV_LIVE_NEVER_BACK, or 1 if a link cannot
 * be opened or a device never connected (message on stderr). */
int nav_live_run(const nav_live_options_t *opt, const nav_sink_t *sink);

#endif
