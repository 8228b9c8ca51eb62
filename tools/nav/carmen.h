/* CARMEN log reader for rsm-nav: FLASER and ROBOTLASER1 scans with the
 * odometry pose they carry (and the laser's mount where the line gives it),
 * and ODOM lines. Plain or gzip files (zlib reads both). Malformed lines are
 * counted by reason, never fatal. */
#ifndef RSM_NAV_CARMEN_H
#define RSM_NAV_CARMEN_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/geom.h"
#include "rsm/scan.h"

typedef enum carmen_kind {
    CARMEN_EOF = 0,
    CARMEN_SCAN = 1,
    CARMEN_ODOM = 2,
    CARMEN_SKIPPED = 3,  /* internal: a well-formed record the reader cannot hold (counted) */
    CARMEN_BAD_POSE = 4, /* internal: a pose or timestamp is NaN or infinite (counted as malformed) */
    CARMEN_ERROR = 5     /* the file cannot be read on (read error, corrupt or truncated gzip):
                          * carmen_error() says why; every later call returns it again */
} carmen_kind_t;

typedef struct carmen_counts {
    uint64_t lines;
    uint64_t scans;
    uint64_t odoms;
    uint64_t comments;
    uint64_t unknown;          /* other record types, skipped */
    uint64_t malformed;        /* wrong field count or bad number (bad_pose included) */
    uint64_t bad_pose;         /* of those: a pose or timestamp that is NaN or infinite */
    uint64_t flaser_offset;    /* FLASER lines whose laser pose differs from their odometry pose */
    uint64_t too_many_beams;   /* more readings than RSM_MAX_BEAMS */
    uint64_t too_long;         /* line longer than the reader's buffer */
} carmen_counts_t;

typedef struct carmen_record {
    carmen_kind_t kind;
    const char *type;          /* the record's keyword: "FLASER", "ROBOTLASER1" or "ODOM" */
    double stamp_s;            /* ipc timestamp */
    rsm_pose_t odom;           /* odometry pose (FLASER odom triple, or ODOM x y theta) */
    double odom_d[3];          /* the same as read, in double: log poses can be far from the origin */
    size_t count;              /* readings (scans) */
    float range_m[RSM_MAX_BEAMS];
    float start_rad;           /* angle of reading 0 */
    float step_rad;            /* angle between readings */
    float max_range_m;         /* sensor's maximum range if the record says (ROBOTLASER1), else 0 */
    /* The laser's pose in the robot frame, between(robot pose, laser pose),
     * when the record carries one: always for ROBOTLASER1; for FLASER only
     * when its laser triple differs from its odometry triple (CARMEN's robot
     * module writes odometry composed with the laser offset there; logs
     * rebuilt without it, like Intel and ACES, repeat the odometry pose,
     * which says nothing about the mount). */
    int has_mount;
    rsm_pose_t mount;
} carmen_record_t;

typedef struct carmen_reader {
    void *gz;                  /* gzFile */
    char error[200];           /* why reading stopped early (empty: it did not) */
    char line[1 << 16];
    int fov179;                /* 1: spread FLASER beams over exactly 180 deg (pi/(n-1) steps) */
    carmen_counts_t counts;
} carmen_reader_t;

int carmen_open(carmen_reader_t *r, const char *path);
void carmen_close(carmen_reader_t *r);

/* Next scan or odometry record; CARMEN_EOF at the end, CARMEN_ERROR if the
 * rest of the file cannot be read. */
carmen_kind_t carmen_next(carmen_reader_t *r, carmen_record_t *rec);

/* Next well-formed scan record that carries a mount (has_mount), skipping
 * everything else without parsing readings it need not; CARMEN_EOF if none.
 * For a look ahead before the real pass: only counts.lines is meaningful
 * (it is then the record's line number). */
carmen_kind_t carmen_next_mount(carmen_reader_t *r, carmen_record_t *rec);

/* The pose "to" seen from "from" (x, y, theta each, same frame), computed in
 * double. */
rsm_pose_t carmen_between(const double from[3], const double to[3]);

/* Why the last CARMEN_ERROR happened. */
const char *carmen_error(const carmen_reader_t *r);

#endif
