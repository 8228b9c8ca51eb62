/* The smallest freestanding use of rsm: one localizer in static memory,
 * started with the default configuration, one odometry step and one
 * made-up scan. No heap, no stdio, no OS: what firmware does, less the
 * drivers (port/baremetal/firmware_main.c has those). It builds as a plain
 * host program, exit status 0 when every call did what it should, and for a
 * Cortex-M4F with arm-none-eabi-gcc (newlib's start-up; on a board, main
 * would loop on its sensors instead of returning). */
#include <stddef.h>

#include "rsm/localizer.h"
#include "rsm/status.h"

#define BEAMS 181u        /* 1 degree apart over 180 degrees */
#define ROOM_RADIUS_M 3.0f

/* About 125 KiB with the default capacities: in .bss, never on the stack,
 * and one per robot (two localizers never share state). */
static rsm_localizer_t loc;
static rsm_localizer_config_t cfg; /* kept by pointer: must live as long as loc */
static rsm_scan_t scan;

int main(void)
{
    const rsm_pose_t start = {0.0f, 0.0f, 0.0f};
    const rsm_motion_t step = {0.05f, 0.0f, 0.0f}; /* 5 cm straight ahead, from the wheel encoders */
    rsm_localizer_report_t rep;
    rsm_pose_t pose;
    size_t i;

    cfg = rsm_localizer_config_default();
    if (rsm_localizer_init(&loc, &cfg, &start, NULL) != RSM_OK) {
        return 1; /* RSM_ERR_CONFIG: built with other capacities than the library */
    }
    if (rsm_localizer_motion(&loc, &step) != RSM_OK) {
        return 2;
    }

    /* A made-up scan: a round room, every reading at its wall. */
    if (rsm_scan_set_uniform(&scan, BEAMS, -0.5f * RSM_PI, RSM_PI / (float)(BEAMS - 1u)) != RSM_OK) {
        return 3;
    }
    for (i = 0; i < BEAMS; ++i) {
        scan.range_m[i] = ROOM_RADIUS_M;
    }
    scan.stamp_us = 100000u; /* any monotonic microsecond clock */
    if (rsm_localizer_scan(&loc, &scan, &rep) != RSM_OK || rep.outcome != RSM_SCAN_FIRST) {
        return 4; /* the first scan starts the map */
    }

    /* Before the first scan a step moves the start exactly: x = 0.05. */
    pose = rsm_localizer_pose(&loc);
    if (!(pose.x > 0.049f && pose.x < 0.051f && pose.y > -0.001f && pose.y < 0.001f)) {
        return 5;
    }
    return 0;
}
