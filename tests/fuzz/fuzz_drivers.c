/* libFuzzer target: the P3-DX and SICK LMS drivers (src/drivers/p3dx.c,
 * src/drivers/sicklms.c) on two in-memory links (tests/support/fakelink.c) whose
 * far ends say whatever the input says.
 *
 * The input is a script of steps; each starts with an opcode byte:
 *   bit 0   which link (robot or laser) the step concerns;
 *   bits 1-2: 0 the next length byte's worth of input bytes arrive on that
 *            link (after a delay from the next byte, in milliseconds);
 *            1 time passes (the next byte, in 10 ms);
 *            2 the driver connects, or 3 disconnects.
 * Both drivers are polled after every step. Whatever arrives, every poll
 * returns RSM_OK or a negative status, every event is a documented one, no
 * poll waits longer than the configured read timeout, the counters never go
 * down, an encoder event's delta is a delta of the counts, and a scan holds
 * at most RSM_MAX_BEAMS readings. Invariants that fail stop the run with
 * __builtin_trap(). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "fakelink.h"
#include "rsm/aria.h"
#include "rsm/p3dx.h"
#include "rsm/sicklms.h"
#include "rsm/status.h"

#include "fuzz_check.h"

typedef struct side {
    rsm_fakelink_t fl;
    rsm_link_t link;
    rsm_clock_t clock;
} side_t;

static void poll_robot(rsm_p3dx_t *d, const rsm_p3dx_config_t *cfg, side_t *s)
{
    rsm_p3dx_event_t ev;
    const rsm_p3dx_stats_t before = d->stats;
    const uint64_t t0 = s->fl.now_us;
    const int rc = rsm_p3dx_poll(d, &ev);
    CHECK(rc <= RSM_OK);
    CHECK(s->fl.now_us - t0 <= cfg->read_timeout_us);
    CHECK(ev.type <= RSM_P3DX_EVENT_DISCONNECTED);
    CHECK(d->stats.encoder_packets >= before.encoder_packets && d->stats.connects >= before.connects &&
          d->stats.keepalives >= before.keepalives && d->stats.link_lost >= before.link_lost);
    if (ev.type == RSM_P3DX_EVENT_ENCODER && ev.encoder.has_delta) {
        CHECK(ev.encoder.d_left == rsm_odometry_count_delta(ev.encoder.sample.left,
                                                            ev.encoder.sample.left - (uint32_t)ev.encoder.d_left, 32u));
    }
}

static void poll_laser(rsm_sicklms_t *d, const rsm_sicklms_config_t *cfg, side_t *s)
{
    rsm_sicklms_event_t ev;
    const rsm_sicklms_stats_t before = d->stats;
    const uint64_t t0 = s->fl.now_us;
    const int rc = rsm_sicklms_poll(d, &ev);
    CHECK(rc <= RSM_OK);
    CHECK(s->fl.now_us - t0 <= cfg->read_timeout_us);
    CHECK(ev.type <= RSM_SICKLMS_EVENT_DISCONNECTED);
    CHECK(d->stats.scans >= before.scans && d->stats.connects >= before.connects &&
          d->stats.bad_scans >= before.bad_scans);
    if (ev.type == RSM_SICKLMS_EVENT_SCAN) {
        CHECK(ev.scan != NULL && ev.scan->count <= RSM_MAX_BEAMS);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static side_t robot;
    static side_t laser;
    static rsm_p3dx_t p3dx;
    static rsm_sicklms_t lms;
    static rsm_p3dx_config_t pcfg;
    static rsm_sicklms_config_t lcfg;
    static rsm_scan_t scan;
    size_t i = 0;
    int steps = 0;
    rsm_fakelink_init(&robot.fl, 1000000u, &robot.link, &robot.clock);
    rsm_fakelink_init(&laser.fl, 1000000u, &laser.link, &laser.clock);
    CHECK(rsm_p3dx_config_default(&pcfg) == RSM_OK);
    CHECK(rsm_sicklms_config_default(&lcfg) == RSM_OK);
    CHECK(rsm_p3dx_init(&p3dx, &robot.link, &robot.clock, &pcfg) == RSM_OK);
    CHECK(rsm_sicklms_init(&lms, &laser.link, &laser.clock, &lcfg, &scan) == RSM_OK);
    CHECK(rsm_p3dx_connect(&p3dx) == RSM_OK);
    CHECK(rsm_sicklms_connect(&lms) == RSM_OK);
    while (i < size && steps < 512) {
        const uint8_t op = data[i++];
        side_t *s = (op & 1u) ? &laser : &robot;
        ++steps;
        switch ((op >> 1) & 3u) {
        case 0: {
            size_t len = i < size ? data[i++] : 0u;
            const uint32_t delay_ms = i < size ? data[i++] : 0u;
            if (len > size - i) {
                len = size - i;
            }
            rsm_fakelink_inject(&s->fl, data + i, len, delay_ms * 1000u);
            i += len;
            break;
        }
        case 1:
            rsm_fakelink_advance(&s->fl, (uint64_t)(i < size ? data[i++] : 0u) * 10000u);
            break;
        case 2:
            if (op & 1u) {
                CHECK(rsm_sicklms_connect(&lms) == RSM_OK);
            } else {
                CHECK(rsm_p3dx_connect(&p3dx) == RSM_OK);
            }
            break;
        default:
            if (op & 1u) {
                (void)rsm_sicklms_disconnect(&lms);
            } else {
                (void)rsm_p3dx_disconnect(&p3dx);
            }
            break;
        }
        poll_robot(&p3dx, &pcfg, &robot);
        poll_laser(&lms, &lcfg, &laser);
    }
    return 0;
}
