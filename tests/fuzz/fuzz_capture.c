/* libFuzzer target: a capture file through rsm-nav's whole capture path
 * (tools/nav/capture.c reader, lenient; the P3-DX and LMS drivers listening
 * through tools/nav/devices.c; src/localizer/sync.c alignment) into the localizer.
 *
 * The input is the file. Whatever it holds, the reader returns documented
 * statuses and never a record longer than a chunk, every decoded scan fits
 * RSM_MAX_BEAMS, every fused scan returns RSM_OK or RSM_ERR_ORDER with a
 * valid outcome, and the estimate and its covariance stay finite. Invariants
 * that fail stop the run with __builtin_trap(). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "capture.h"
#include "devices.h"
#include "rsm/localizer.h"
#include "rsm/status.h"
#include "rsm/sync.h"

#include "fuzz_check.h"

typedef struct run {
    rsm_localizer_t loc;
    rsm_localizer_config_t cfg;
    rsm_sync_config_t sync_cfg;
    rsm_sync_t sync;
    rsm_scan_t copy;
    uint64_t last_scan_us;
} run_t;

static void check_finite(const rsm_localizer_t *loc)
{
    int k;
    CHECK(isfinite(loc->ekf.x.x) && isfinite(loc->ekf.x.y) && isfinite(loc->ekf.x.theta));
    for (k = 0; k < 9; ++k) {
        CHECK(isfinite(loc->ekf.p[k]));
    }
}

static void on_fused(void *ctx, const rsm_scan_t *scan, int status, const rsm_localizer_report_t *rep)
{
    (void)ctx;
    CHECK(scan->count <= RSM_MAX_BEAMS);
    CHECK(status == RSM_OK || status == RSM_ERR_ORDER);
    CHECK((unsigned)rep->outcome < (unsigned)RSM_SCAN_OUTCOMES);
}

static void sink_encoder(void *ctx, const rsm_odometry_sample_t *sample, int restart)
{
    run_t *r = (run_t *)ctx;
    if (restart) {
        CHECK(rsm_sync_encoder_restart(&r->sync) == RSM_OK);
    }
    CHECK(rsm_sync_encoder(&r->sync, sample) == RSM_OK);
    check_finite(&r->loc);
}

static void sink_scan(void *ctx, const rsm_scan_t *scan)
{
    run_t *r = (run_t *)ctx;
    const uint64_t stamp_us = scan->stamp_us;
    CHECK(scan->count <= RSM_MAX_BEAMS);
    r->copy = *scan;
    /* rsm-nav clamps stamps that go backwards; so does this. */
    r->copy.stamp_us = stamp_us > r->last_scan_us ? stamp_us : r->last_scan_us;
    r->last_scan_us = r->copy.stamp_us;
    CHECK(rsm_sync_scan(&r->sync, &r->copy) == RSM_OK);
    check_finite(&r->loc);
}

static void sink_tick(void *ctx, uint64_t now_us)
{
    run_t *r = (run_t *)ctx;
    const int fused = rsm_sync_poll(&r->sync, now_us);
    CHECK(fused == 0 || fused == 1);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static run_t run;
    static cap_reader reader;
    static nav_devices_t dev;
    static uint8_t buf[CAP_MAX_CHUNK];
    const rsm_pose_t start = {0.0f, 0.0f, 0.0f};
    nav_feed_t feed[2];
    rsm_link_t link[2];
    rsm_clock_t clock[2];
    nav_sink_t sink;
    int i;
    FILE *fp;
    int st;
    if (size == 0u) {
        return 0;
    }
    fp = fmemopen((void *)(uintptr_t)data, size, "rb");
    if (fp == NULL) {
        return 0;
    }
    memset(&run, 0, sizeof run);
    run.cfg = rsm_localizer_config_default();
    run.sync_cfg = rsm_sync_config_default();
    CHECK(rsm_localizer_init(&run.loc, &run.cfg, &start, NULL) == RSM_OK);
    CHECK(rsm_sync_init(&run.sync, &run.loc, &run.sync_cfg, on_fused, &run) == RSM_OK);
    sink.ctx = &run;
    sink.encoder = sink_encoder;
    sink.scan = sink_scan;
    sink.tick = sink_tick;
    sink.calibration = NULL;
    nav_devices_defaults(&dev, 1, 1);
    for (i = 0; i < 2; ++i) {
        nav_feed_init(&feed[i], &link[i], &clock[i]);
        CHECK(nav_devices_start(&dev, i == 0, &link[i], &clock[i]) == 0);
    }
    st = cap_open(&reader, fp, 1);
    if (st == CAP_OK) {
        for (;;) {
            cap_record rec;
            st = cap_next(&reader, &rec, buf, sizeof buf);
            CHECK(st == CAP_OK || st == CAP_END || st == CAP_ERR_IO);
            if (st != CAP_OK) {
                break;
            }
            CHECK(rec.length <= CAP_MAX_CHUNK && rec.offset < size);
            CHECK(cap_channel_by_id(&reader, rec.channel) != NULL);
            if (rec.direction != CAP_RX) {
                continue;
            }
            /* Channel 0 as the robot, the rest as the laser: every byte is decoded. */
            if (rec.channel == reader.channels[0].id) {
                nav_devices_feed(&dev, 1, &feed[0], buf, rec.length, rec.timestamp_us, &sink);
            } else {
                nav_devices_feed(&dev, 0, &feed[1], buf, rec.length, rec.timestamp_us, &sink);
            }
        }
        CHECK(reader.count.records + reader.count.corrupt + reader.count.truncated <= size);
        CHECK(reader.count.skipped_bytes <= size);
    } else {
        CHECK(st == CAP_ERR_HEADER || st == CAP_ERR_NOMEM);
    }
    cap_close(&reader);
    fclose(fp);
    (void)rsm_sync_flush(&run.sync);
    check_finite(&run.loc);
    return 0;
}
