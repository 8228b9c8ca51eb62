/* libFuzzer target: a CARMEN log through rsm-nav's log path
 * (tools/nav/carmen.c reader, plain or gzip through zlib) into the
 * localizer, the way rsm-nav --carmen runs it: odometry increments between
 * the log's poses (in double), a scan per laser line.
 *
 * The input is the file. Whatever it holds, the reader's counts add up,
 * every scan record fits RSM_MAX_BEAMS with finite poses and stamp, every
 * scan returns RSM_OK with a valid outcome, and the estimate and its
 * covariance stay finite. Invariants that fail stop the run with
 * __builtin_trap(). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "carmen.h"
#include "rsm/localizer.h"
#include "rsm/status.h"

#include "fuzz_check.h"

/* zlib reads files by name: one scratch file per process, rewritten per
 * input, in TMPDIR, and removed when the run ends (every test run left
 * one behind). */
static char scratch[4096];

static void remove_scratch(void)
{
    (void)remove(scratch);
}

static const char *scratch_path(void)
{
    if (scratch[0] == '\0') {
        const char *dir = getenv("TMPDIR");
        snprintf(scratch, sizeof scratch, "%s/rsm-fuzz-carmen-%ld.clf", dir != NULL && dir[0] != '\0' ? dir : "/tmp",
                 (long)getpid());
        (void)atexit(remove_scratch);
    }
    return scratch;
}

static void check_finite(const rsm_localizer_t *loc)
{
    int k;
    CHECK(isfinite(loc->ekf.x.x) && isfinite(loc->ekf.x.y) && isfinite(loc->ekf.x.theta));
    for (k = 0; k < 9; ++k) {
        CHECK(isfinite(loc->ekf.p[k]));
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static carmen_reader_t reader;
    static carmen_record_t rec;
    static rsm_localizer_t loc;
    static rsm_localizer_config_t cfg;
    static rsm_scan_t scan;
    double last[3] = {0.0, 0.0, 0.0};
    uint64_t stamp = 0;
    int started = 0;
    int records = 0;
    FILE *f = fopen(scratch_path(), "wb");
    if (f == NULL) {
        return 0;
    }
    if (size > 0u && fwrite(data, 1, size, f) != size) {
        fclose(f);
        return 0;
    }
    fclose(f);
    cfg = rsm_localizer_config_default();
    CHECK(carmen_open(&reader, scratch_path()) == 0);
    while (records < 256) {
        const carmen_kind_t k = carmen_next(&reader, &rec);
        size_t b;
        if (k == CARMEN_EOF || k == CARMEN_ERROR) {
            break;
        }
        ++records;
        CHECK(k == CARMEN_SCAN || k == CARMEN_ODOM);
        CHECK(isfinite(rec.odom_d[0]) && isfinite(rec.odom_d[1]) && isfinite(rec.odom_d[2]));
        CHECK(isfinite(rec.stamp_s));
        if (k != CARMEN_SCAN) {
            continue;
        }
        CHECK(rec.count <= RSM_MAX_BEAMS);
        if (!started) {
            rsm_pose_t x0;
            x0.x = (float)rec.odom_d[0];
            x0.y = (float)rec.odom_d[1];
            x0.theta = rsm_wrap_angle((float)rec.odom_d[2]);
            if (rsm_localizer_init(&loc, &cfg, &x0, NULL) != RSM_OK) {
                break; /* a start beyond the coordinate limit: rsm-nav says so and stops */
            }
            started = 1;
        } else {
            const rsm_pose_t d = carmen_between(last, rec.odom_d);
            const rsm_motion_t u = {d.x, d.y, d.theta};
            const int rc = rsm_localizer_motion(&loc, &u);
            CHECK(rc == RSM_OK || rc == RSM_ERR_RANGE);
        }
        memcpy(last, rec.odom_d, sizeof last);
        for (b = 0; b < rec.count; ++b) {
            scan.range_m[b] = rec.range_m[b];
        }
        if (rsm_scan_set_uniform(&scan, rec.count, rec.start_rad, rec.step_rad) == RSM_OK) {
            rsm_localizer_report_t rep;
            const uint64_t t = rec.stamp_s > 0.0 && rec.stamp_s < 1.8e13 ? (uint64_t)(rec.stamp_s * 1e6) : 0u;
            int rc;
            stamp = t > stamp ? t : stamp;
            scan.stamp_us = stamp;
            rc = rsm_localizer_scan(&loc, &scan, &rep);
            CHECK(rc == RSM_OK);
            CHECK((unsigned)rep.outcome < (unsigned)RSM_SCAN_OUTCOMES);
        }
        check_finite(&loc);
    }
    CHECK(reader.counts.scans + reader.counts.odoms + reader.counts.malformed + reader.counts.comments +
              reader.counts.unknown + reader.counts.too_many_beams <=
          reader.counts.lines + 1u);
    carmen_close(&reader);
    return 0;
}
