/* CARMEN log reader for rsm-nav: FLASER and ROBOTLASER1 scans with the
 * odometry pose they carry, and ODOM lines. Plain or gzip files (zlib reads
 * both). Malformed lines are counted by reason, never fatal. */
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
    CARMEN_SKIPPED = 3   /* internal: a well-formed record the reader cannot hold (counted) */
} carmen_kind_t;

typedef struct carmen_counts {
    uint64_t lines;
    uint64_t scans;
    uint64_t odoms;
    uint64_t comments;
    uint64_t unknown;          /* other record types, skipped */
    uint64_t malformed;        /* wrong field count or bad number */
    uint64_t too_many_beams;   /* more readings than RSM_MAX_BEAMS */
    uint64_t too_long;         /* line longer than the reader's buffer */
} carmen_counts_t;

typedef struct carmen_record {
    carmen_kind_t kind;
    double stamp_s;            /* ipc timestamp */
    rsm_pose_t odom;           /* odometry pose (FLASER odom triple, or ODOM x y theta) */
    size_t count;              /* readings (scans) */
    float range_m[RSM_MAX_BEAMS];
    float start_rad;           /* angle of reading 0 */
    float step_rad;            /* angle between readings */
    float max_range_m;         /* sensor's maximum range if the record says (ROBOTLASER1), else 0 */
} carmen_record_t;

typedef struct carmen_reader {
    void *gz;                  /* gzFile */
    char line[1 << 16];
    int fov179;                /* 1: spread FLASER beams over exactly 180 deg (pi/(n-1) steps) */
    carmen_counts_t counts;
} carmen_reader_t;

int carmen_open(carmen_reader_t *r, const char *path);
void carmen_close(carmen_reader_t *r);

/* Next scan or odometry record; CARMEN_EOF at the end. */
carmen_kind_t carmen_next(carmen_reader_t *r, carmen_record_t *rec);

#endif
