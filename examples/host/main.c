/* rsm on a CARMEN log, through the installed library: reads FLASER lines,
 * feeds each one's odometry step and scan to the localizer, and prints the
 * final pose and how many scans were accepted.
 *
 *   gzip -dc tests/data/intel_head.clf.gz | ./rsm_example_host
 *   ./rsm_example_host LOG              (plain text; "-" is stdin)
 *
 * Exit status 0 when at least one scan was read, 1 otherwise. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rsm/rsm.h"

/* The localizer is about 125 KiB: static, as on a robot, not on the stack. */
static rsm_localizer_t loc;
static rsm_localizer_config_t cfg; /* kept by pointer: lives as long as loc */
static rsm_scan_t scan;
static char line[1 << 16]; /* a FLASER line of RSM_MAX_BEAMS readings fits with room to spare */

/* Next number of the line at *p, in *v; 0 if there is none. */
static int next_num(char **p, double *v)
{
    char *end;
    *v = strtod(*p, &end);
    if (end == *p) {
        return 0;
    }
    *p = end;
    return 1;
}

/* One FLASER line: "FLASER n r_1 ... r_n  x y theta  odom_x odom_y
 * odom_theta  ipc_timestamp hostname logger_timestamp" (metres, radians,
 * seconds). Fills the scan's ranges and count, the odometry pose and the
 * ipc time stamp; 0 for any other line (other records, comments) and for
 * a malformed one. The laser pose is skipped: Intel's repeats odometry's. */
static int read_flaser(char *p, rsm_scan_t *s, rsm_pose_t *odom, double *stamp_s)
{
    double v[7];
    char *end;
    long n;
    size_t i;
    if (strncmp(p, "FLASER ", 7) != 0) {
        return 0;
    }
    n = strtol(p + 7, &end, 10);
    if (end == p + 7 || n < 1 || n > (long)RSM_MAX_BEAMS) {
        return 0;
    }
    p = end;
    for (i = 0; i < (size_t)n; ++i) {
        if (!next_num(&p, &v[0])) {
            return 0;
        }
        s->range_m[i] = (float)v[0]; /* 0 or the maximum: no echo, which the localizer drops */
    }
    for (i = 0; i < 7; ++i) {
        if (!next_num(&p, &v[i]) || !isfinite(v[i])) {
            return 0;
        }
    }
    /* CARMEN's usual laser: n readings spread over 180 degrees from -90. */
    if (rsm_scan_set_uniform(s, (size_t)n, -0.5f * RSM_PI, RSM_PI / (float)n) != RSM_OK) {
        return 0;
    }
    odom->x = (float)v[3];
    odom->y = (float)v[4];
    odom->theta = (float)v[5];
    *stamp_s = v[6];
    return 1;
}

int main(int argc, char **argv)
{
    FILE *in = stdin;
    rsm_pose_t odom;
    rsm_pose_t last_odom = {0.0f, 0.0f, 0.0f};
    rsm_pose_t pose;
    uint64_t last_us = 0;
    unsigned long scans = 0;
    double stamp_s;
    int failed;
    if (argc > 2) {
        fprintf(stderr, "usage: %s [CARMEN_LOG]   (plain text; none or - reads stdin)\n", argv[0]);
        return 1;
    }
    if (argc == 2 && strcmp(argv[1], "-") != 0 && (in = fopen(argv[1], "r")) == NULL) {
        perror(argv[1]);
        return 1;
    }
    cfg = rsm_localizer_config_default();
    while (fgets(line, sizeof line, in) != NULL) {
        uint64_t stamp_us;
        if (!read_flaser(line, &scan, &odom, &stamp_s) || !(stamp_s >= 0.0 && stamp_s < 1e12)) {
            continue;
        }
        if (scans == 0) {
            /* Start where odometry says, so that poses are in its frame. */
            if (rsm_localizer_init(&loc, &cfg, &odom, NULL) != RSM_OK) {
                fprintf(stderr, "rsm_localizer_init failed\n");
                return 1;
            }
        } else {
            /* Odometry's step since the last scan, in the robot's frame then. */
            const rsm_motion_t u = rsm_odometry_from_poses(&last_odom, &odom);
            (void)rsm_localizer_motion(&loc, &u);
        }
        last_odom = odom;
        /* The Intel log's stamps go backwards at times, and the localizer
         * refuses a scan older than the last (RSM_ERR_ORDER): hold the clock. */
        stamp_us = (uint64_t)llround(stamp_s * 1e6);
        scan.stamp_us = stamp_us > last_us ? stamp_us : last_us;
        last_us = scan.stamp_us;
        (void)rsm_localizer_scan(&loc, &scan, NULL); /* the outcome is counted in loc.counters */
        ++scans;
    }
    failed = ferror(in);
    if (in != stdin) {
        (void)fclose(in);
    }
    if (failed || scans == 0) {
        fprintf(stderr, "%s\n", failed ? "read error" : "no FLASER line read");
        return 1;
    }
    pose = rsm_localizer_pose(&loc);
    printf("rsm %s (headers %s)\n", rsm_version(), RSM_VERSION_STRING);
    printf("scans %lu accepted %lu\n", scans, (unsigned long)loc.counters.outcome[RSM_SCAN_ACCEPTED]);
    printf("final pose %.3f %.3f %.4f\n", (double)pose.x, (double)pose.y, (double)pose.theta);
    return 0;
}
