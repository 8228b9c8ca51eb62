/* Running the localizer over a CARMEN log, the one loop rsm-nav and
 * rsm-stages share: the first scan record starts the localizer, each later
 * one first predicts with the odometry increment between the log's poses
 * (taken in double: far from the origin a float difference loses
 * centimetres), then its scan runs stamped in the localizer's time, which
 * the stamp repair below keeps from going backwards. Host tools only. */
#ifndef RSM_NAV_LOGRUN_H
#define RSM_NAV_LOGRUN_H

#include <stdint.h>

#include "carmen.h"
#include "rsm/odometry.h"
#include "rsm/scan.h"

/* Log and capture timestamps can jitter backwards while the order of the
 * records is the true order (the Intel log does so 631 times): the
 * localizer gets a clamped stamp, counted; the trajectory keeps the
 * original. One stamp far from its neighbours (a negative or far-future
 * stamp in a log) is not trusted alone, or it would clamp every later scan:
 * it gets the previous stamp (counted as odd) unless the next one agrees
 * with it; then the clock really jumped and the localizer's time carries on
 * from where it was (no time passes across the jump). */
typedef struct stamp_repair {
    uint64_t last_us;      /* the localizer's time of the last scan */
    uint64_t clamped;      /* stamps that went backwards */
    uint64_t odd_stamps;   /* stamps far from both neighbours: replaced */
    uint64_t time_jumps;   /* far stamps confirmed by the next one */
    int have_stamp;
    uint64_t src_last_us;  /* the source's stamp of the last scan taken */
    uint64_t base_us;      /* localizer time = source stamp + base (modulo 2^64) */
    int have_odd;
    uint64_t odd_us;       /* a stamp far from the previous one, not yet confirmed */
} stamp_repair_t;

/* The localizer's time for a scan the source stamped stamp_us. */
uint64_t stamp_repair(stamp_repair_t *r, uint64_t stamp_us);

/* A record's stamp in microseconds; a negative or absurd one becomes the
 * farthest (UINT64_MAX: odd to stamp_repair). */
uint64_t logrun_stamp_us(const carmen_record_t *rec);

/* The record's readings as a scan (stamp_us untouched). */
void logrun_scan(const carmen_record_t *rec, rsm_scan_t *scan);

typedef struct logrun_ops {
    /* The first scan record taken: start the localizer (its pose is
     * rec->odom_d). 0, or nonzero to stop (logrun_carmen returns 2). */
    int (*start)(void *ctx, const carmen_record_t *rec);
    /* Whether to take this scan record at all; NULL: every one. */
    int (*want)(void *ctx, const carmen_record_t *rec);
    /* The odometry increment since the previous scan record taken. */
    void (*motion)(void *ctx, const rsm_motion_t *u);
    /* The record's scan, at localizer time stamp_us (stamp_repair). */
    void (*scan)(void *ctx, const carmen_record_t *rec, uint64_t stamp_us);
    /* Whether to stop before reading on (a limit); NULL: never. */
    int (*done)(void *ctx);
} logrun_ops_t;

/* Opens path with *reader (fov179 set by the caller), runs every scan
 * record through ops and closes it. With odom_lines, each ODOM record
 * after the first scan taken is an odometry increment of its own (ops->motion),
 * as a robot's driver sends them between scans; else odometry comes from
 * the scan records' poses alone. rec is the caller's (large) record
 * buffer, repair its stamp state. Returns 0; -1 if the log cannot be
 * opened, 1 if reading it failed part way (message on stderr, after prog;
 * what ran is kept); 2 if start refused. */
int logrun_carmen(carmen_reader_t *reader, carmen_record_t *rec, const char *path, const char *prog,
                  stamp_repair_t *repair, const logrun_ops_t *ops, void *ctx, int odom_lines);

#endif
