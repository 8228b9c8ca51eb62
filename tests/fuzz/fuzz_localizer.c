/* libFuzzer target for the localizer's persistent-map method (src/localizer/localizer.c,
 * src/map/tilemap.c, src/map/mapmatch.c).
 *
 * The input is a script: each record starts with an opcode byte.
 *   0: a motion (three floats from the next 12 bytes, any bit pattern:
 *      NaN, infinities, huge values);
 *   1: a scan of a wall-rich room seen from the current estimate, with the
 *      next bytes replacing readings (NaN, zero, negative, huge, random) and
 *      bending the timestamp (backwards too);
 *   2: wheel ticks (two raw 32-bit counters);
 *   3: a scan of raw floats from the input.
 * Whatever arrives, every call returns a documented status, the estimate and
 * its covariance stay finite, the map's pool bookkeeping stays consistent,
 * and nothing reads or writes out of bounds (the sanitizers watch).
 * Invariants that fail stop the run with __builtin_trap(). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "rsm/localizer.h"
#include "rsm/status.h"
#include "map/tilemap.h" /* internal (src/): tiles held per level */

#include "fuzz_check.h"


typedef struct reader {
    const uint8_t *p;
    size_t n;
} reader_t;

static int take(reader_t *r, void *out, size_t len)
{
    if (r->n < len) {
        return 0;
    }
    memcpy(out, r->p, len);
    r->p += len;
    r->n -= len;
    return 1;
}

/* Range from the current estimate to a 6 m x 4 m room's walls around the
 * origin, along a robot-frame beam: enough structure to match and map. */
static float room_range(const rsm_pose_t *pose, float angle)
{
    const float a = pose->theta + angle;
    const float c = cosf(a);
    const float s = sinf(a);
    float best = 30.0f;
    if (c > 1e-4f) {
        best = fminf(best, (3.0f - pose->x) / c);
    } else if (c < -1e-4f) {
        best = fminf(best, (-3.0f - pose->x) / c);
    }
    if (s > 1e-4f) {
        best = fminf(best, (2.0f - pose->y) / s);
    } else if (s < -1e-4f) {
        best = fminf(best, (-2.0f - pose->y) / s);
    }
    return best > 0.0f ? best : 0.0f;
}

static void check_state(const rsm_localizer_t *loc)
{
    const rsm_tmap_t *m = &loc->state.persistent.map;
    uint32_t level;
    uint32_t sum = 0;
    int k;
    CHECK(isfinite(loc->ekf.x.x) && isfinite(loc->ekf.x.y) && isfinite(loc->ekf.x.theta));
    for (k = 0; k < 9; ++k) {
        CHECK(isfinite(loc->ekf.p[k]));
    }
    CHECK(m->used <= (uint32_t)RSM_TMAP_TILES);
    for (level = 0; level < (uint32_t)RSM_TMAP_LEVELS; ++level) {
        sum += rsm_tmap_tiles(m, level);
    }
    CHECK(sum == m->used);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static rsm_localizer_t loc;
    static rsm_scan_t scan;
    static rsm_localizer_config_t cfg;
    const rsm_pose_t start = {0.0f, 0.0f, 0.0f};
    reader_t r;
    uint64_t stamp = 0;
    int steps = 0;
    r.p = data;
    r.n = size;
    cfg = rsm_localizer_config_default();
    CHECK(rsm_localizer_init(&loc, &cfg, &start, NULL) == RSM_OK);
    while (r.n > 0u && steps < 64) {
        uint8_t op;
        ++steps;
        (void)take(&r, &op, 1u);
        switch (op & 3u) {
        case 0: {
            rsm_motion_t u;
            int rc;
            if (!take(&r, &u, sizeof u)) {
                break;
            }
            rc = rsm_localizer_motion(&loc, &u);
            CHECK(rc == RSM_OK || rc == RSM_ERR_RANGE);
            break;
        }
        case 1:
        case 3: {
            rsm_localizer_report_t rep;
            uint8_t edits = 0;
            uint16_t dt = 0;
            size_t i;
            int rc;
            (void)rsm_scan_set_uniform(&scan, 181u, -RSM_PI / 2.0f, RSM_PI / 180.0f);
            for (i = 0; i < scan.count; ++i) {
                scan.range_m[i] = room_range(&loc.ekf.x, scan.angle_rad[i]);
            }
            (void)take(&r, &dt, sizeof dt);
            /* Mostly forward in time; sometimes backwards. */
            stamp = (dt & 0x8000u) ? stamp - (uint64_t)(dt & 0x7FFFu) : stamp + (uint64_t)dt * 1000u;
            scan.stamp_us = stamp;
            (void)take(&r, &edits, 1u);
            for (i = 0; i < (size_t)edits; ++i) {
                uint8_t idx;
                float v;
                if (!take(&r, &idx, 1u) || !take(&r, &v, sizeof v)) {
                    break;
                }
                if ((op & 3u) == 3u) {
                    scan.angle_rad[idx % scan.count] = v; /* angles too, raw */
                }
                scan.range_m[idx % scan.count] = v;
            }
            rc = rsm_localizer_scan(&loc, &scan, &rep);
            CHECK(rc == RSM_OK || rc == RSM_ERR_ORDER);
            CHECK((unsigned)rep.outcome < (unsigned)RSM_SCAN_OUTCOMES);
            break;
        }
        default: {
            uint32_t ticks[2];
            int rc;
            if (!take(&r, ticks, sizeof ticks)) {
                break;
            }
            rc = rsm_localizer_ticks(&loc, ticks[0], ticks[1]);
            CHECK(rc == RSM_OK || rc == RSM_ERR_AGAIN || rc == RSM_ERR_RANGE);
            break;
        }
        }
        check_state(&loc);
    }
    return 0;
}
