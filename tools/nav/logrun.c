#include "logrun.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* Beyond this step between two stamps (one hour), one is not trusted alone. */
#define LOGRUN_MAX_STEP_US 3600000000ull

static uint64_t stamp_gap(uint64_t a, uint64_t b)
{
    return a > b ? a - b : b - a;
}

uint64_t stamp_repair(stamp_repair_t *r, uint64_t stamp_us)
{
    uint64_t t;
    if (r->have_stamp && stamp_gap(stamp_us, r->src_last_us) > LOGRUN_MAX_STEP_US) {
        if (!r->have_odd || stamp_gap(stamp_us, r->odd_us) > LOGRUN_MAX_STEP_US) {
            r->odd_us = stamp_us;
            r->have_odd = 1;
            r->odd_stamps++;
            return r->last_us;
        }
        r->time_jumps++;
        r->base_us = r->last_us - stamp_us; /* modulo 2^64, so either direction works */
    }
    r->have_odd = 0;
    r->have_stamp = 1;
    r->src_last_us = stamp_us;
    t = stamp_us + r->base_us;
    if (t < r->last_us) {
        t = r->last_us;
        r->clamped++;
    }
    r->last_us = t;
    return t;
}

uint64_t logrun_stamp_us(const carmen_record_t *rec)
{
    return rec->stamp_s >= 0.0 && rec->stamp_s < 1.8e13 ? (uint64_t)llround(rec->stamp_s * 1e6) : UINT64_MAX;
}

void logrun_scan(const carmen_record_t *rec, rsm_scan_t *scan)
{
    size_t b;
    for (b = 0; b < rec->count; ++b) {
        /* A reading at the range the record says the laser has is its
         * no-return code, whatever the localizer's own limit: dropped as
         * too long (counted there). */
        scan->range_m[b] = rec->max_range_m > 0.0f && rec->range_m[b] >= rec->max_range_m ? FLT_MAX : rec->range_m[b];
    }
    (void)rsm_scan_set_uniform(scan, rec->count, rec->start_rad, rec->step_rad);
}

/* The odometry increment from last_odom to rec's pose, to ops->motion;
 * last_odom moves on to it. */
static void step_to(const carmen_record_t *rec, double *last_odom, const logrun_ops_t *ops, void *ctx)
{
    const rsm_pose_t d = carmen_between(last_odom, rec->odom_d);
    const rsm_motion_t u = {d.x, d.y, d.theta};
    ops->motion(ctx, &u);
    memcpy(last_odom, rec->odom_d, 3u * sizeof *last_odom);
}

int logrun_carmen(carmen_reader_t *reader, carmen_record_t *rec, const char *path, const char *prog,
                  stamp_repair_t *repair, const logrun_ops_t *ops, void *ctx, int odom_lines)
{
    double last_odom[3] = {0.0, 0.0, 0.0};
    int started = 0;
    int status = 0;
    if (carmen_open(reader, path) != 0) {
        fprintf(stderr, "%s: cannot open %s: %s\n", prog, path, strerror(errno));
        return -1;
    }
    for (;;) {
        carmen_kind_t k;
        if (ops->done != NULL && ops->done(ctx)) {
            break;
        }
        k = carmen_next(reader, rec);
        if (k == CARMEN_EOF) {
            break;
        }
        if (k == CARMEN_ERROR) {
            /* What was run so far is kept (the caller flushes it). */
            fprintf(stderr, "%s: cannot read %s: %s\n", prog, path, carmen_error(reader));
            status = 1;
            break;
        }
        if (k == CARMEN_ODOM && odom_lines && started) {
            /* Each step apart, as the robot's driver sends them: the
             * localizer calibrates and weighs each one (a drive between
             * two scans far apart, in one step, cannot be calibrated). */
            step_to(rec, last_odom, ops, ctx);
            continue;
        }
        /* Odometry comes from the pose carried by each laser line (and,
         * with odom_lines, the ODOM lines between them). */
        if (k != CARMEN_SCAN || (ops->want != NULL && !ops->want(ctx, rec))) {
            continue;
        }
        if (!started) {
            if (ops->start(ctx, rec) != 0) {
                status = 2;
                break;
            }
            started = 1;
            memcpy(last_odom, rec->odom_d, sizeof last_odom);
        } else {
            step_to(rec, last_odom, ops, ctx);
        }
        ops->scan(ctx, rec, stamp_repair(repair, logrun_stamp_us(rec)));
    }
    carmen_close(reader);
    return status;
}
