/* libFuzzer target: the spinning-lidar drivers (src/drivers/ldlidar.c,
 * src/drivers/slamtec.c) on two in-memory links (tests/support/fakelink.c) whose
 * far ends say whatever the input says, their points going through a
 * revolution assembler each (src/drivers/revolution.c) with odometry of a robot
 * turning on the spot.
 *
 * The input is a script of steps; each starts with an opcode byte:
 *   bit 0   which link (LD06 or RPLIDAR) the step concerns;
 *   bits 1-2: 0 the next length byte's worth of input bytes arrive on that
 *            link (after a delay from the next byte, in 100 us);
 *            1 time passes (the next byte, in 10 ms);
 *            2 the driver connects, or 3 disconnects;
 *   bit 3   the RPLIDAR runs express scans (taken at its next connect);
 *   bit 4   the RPLIDAR's connect is a listen-only start instead.
 * Both drivers are polled after every step. Whatever arrives, every poll
 * returns RSM_OK or a negative status, waits no longer than its read
 * timeout, gives a documented event, points with angles in [0, 360),
 * finite non-negative ranges and stamps that never go back, so the
 * assembler takes every point; its scans hold at most RSM_MAX_BEAMS finite
 * readings; a listening RPLIDAR driver writes nothing at all; a driver in
 * IDLE has no deadline. Invariants that fail stop the run with
 * __builtin_trap(). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "fakelink.h"
#include "rsm/ldlidar.h"
#include "rsm/revolution.h"
#include "rsm/slamtec.h"
#include "rsm/status.h"

#include "fuzz_check.h"

typedef struct side {
    rsm_fakelink_t fl;
    rsm_link_t link;
    rsm_clock_t clock;
    rsm_rev_t rev;
    uint64_t last_stamp;
    uint64_t next_odom;
    size_t writes_at_listen; /* host writes when the driver began listening */
} side_t;

/* Odometry up to time t: turning on the spot at 1 rad/s. */
static void odometry(side_t *s, uint64_t t)
{
    while (s->next_odom <= t) {
        rsm_pose_t p;
        p.x = 0.0f;
        p.y = 0.0f;
        p.theta = rsm_wrap_angle((float)(s->next_odom % 6283185u) * 1e-6f);
        CHECK(rsm_rev_odometry(&s->rev, s->next_odom, &p) == RSM_OK);
        s->next_odom += 20000u;
    }
}

/* A delivered turn (rc 1) holds finite points at bearings in [-pi, pi]. */
static void check_turn(const side_t *s, int rc)
{
    size_t k;
    CHECK(rc == 0 || rc == 1);
    if (rc == 1) {
        CHECK(s->rev.scan.count <= (size_t)RSM_MAX_BEAMS);
        for (k = 0; k < s->rev.scan.count; ++k) {
            CHECK(isfinite(s->rev.scan.range_m[k]) && s->rev.scan.range_m[k] >= 0.0f);
            CHECK(s->rev.scan.angle_rad[k] >= -3.1416f && s->rev.scan.angle_rad[k] <= 3.1416f);
        }
    }
}

static void take_points(side_t *s, const rsm_lidar_point_t *pts, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        CHECK(pts[i].angle_deg >= 0.0f && pts[i].angle_deg < 360.0f);
        CHECK(pts[i].range_m >= 0.0f && isfinite(pts[i].range_m));
        CHECK(pts[i].stamp_us >= s->last_stamp);
        s->last_stamp = pts[i].stamp_us;
        odometry(s, pts[i].stamp_us);
        check_turn(s, rsm_rev_push(&s->rev, &pts[i]));
    }
}

/* The link was lost: a turn waiting for odometry comes out, the one in
 * progress is dropped. */
static void lost(side_t *s)
{
    check_turn(s, rsm_rev_flush(&s->rev));
    rsm_rev_reset(&s->rev);
}

static void poll_ld(rsm_ldlidar_t *d, const rsm_ldlidar_config_t *cfg, side_t *s)
{
    rsm_ldlidar_event_t ev;
    const uint64_t t0 = s->fl.now_us;
    const int rc = rsm_ldlidar_poll(d, &ev);
    CHECK(rc <= RSM_OK);
    CHECK(s->fl.now_us - t0 <= cfg->read_timeout_us);
    CHECK(ev.type <= RSM_LDLIDAR_EVENT_LINK_LOST);
    CHECK(ev.count <= RSM_LD06_POINTS);
    CHECK(ev.type == RSM_LDLIDAR_EVENT_POINTS || ev.count == 0u);
    CHECK(s->fl.n_writes == 0u); /* the LD06 takes no commands */
    CHECK(d->state != RSM_LDLIDAR_IDLE || rsm_ldlidar_next_deadline_us(d) == UINT64_MAX);
    if (ev.type == RSM_LDLIDAR_EVENT_LINK_LOST) {
        lost(s);
    }
    take_points(s, ev.points, ev.count);
}

static void poll_rp(rsm_slamtec_t *d, const rsm_slamtec_config_t *cfg, side_t *s)
{
    rsm_slamtec_event_t ev;
    const uint64_t t0 = s->fl.now_us;
    const uint32_t requests = d->stats.requests;
    const int rc = rsm_slamtec_poll(d, &ev);
    CHECK(rc <= RSM_OK);
    CHECK(s->fl.now_us - t0 <= cfg->read_timeout_us);
    CHECK(ev.type <= RSM_SLAMTEC_EVENT_DISCONNECTED);
    CHECK(ev.count <= RSM_RPLIDAR_MAX_POINTS);
    CHECK(ev.type == RSM_SLAMTEC_EVENT_POINTS || ev.count == 0u);
    CHECK(ev.type != RSM_SLAMTEC_EVENT_ERROR ||
          ev.status == RSM_ERR_TIMEOUT || ev.status == RSM_ERR_PROTO);
    /* a poll sends at most one request after each of its two drains and
     * two timer runs: no request storm whatever the unit says */
    CHECK(d->stats.requests >= requests && d->stats.requests - requests <= 4u);
    CHECK(!d->listen || s->fl.n_writes == s->writes_at_listen); /* listening sends nothing */
    CHECK(d->state != RSM_SLAMTEC_IDLE || rsm_slamtec_next_deadline_us(d) == UINT64_MAX);
    if (ev.type == RSM_SLAMTEC_EVENT_LINK_LOST) {
        lost(s);
    }
    take_points(s, ev.points, ev.count);
}

static void side_init(side_t *s, const rsm_rev_config_t *rcfg)
{
    rsm_fakelink_init(&s->fl, 1000000u, &s->link, &s->clock);
    CHECK(rsm_rev_init(&s->rev, rcfg) == RSM_OK);
    s->last_stamp = 0u;
    s->next_odom = 0u;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static side_t ld;
    static side_t rp;
    static rsm_ldlidar_t ldd;
    static rsm_slamtec_t rpd;
    rsm_ldlidar_config_t lcfg;
    rsm_slamtec_config_t scfg;
    rsm_rev_config_t rcfg;
    size_t i = 0;

    CHECK(rsm_ldlidar_config_default(&lcfg) == RSM_OK);
    CHECK(rsm_slamtec_config_default(&scfg) == RSM_OK);
    CHECK(rsm_rev_config_default(&rcfg) == RSM_OK);
    rcfg.min_points = 3u;
    side_init(&ld, &rcfg);
    side_init(&rp, &rcfg);
    CHECK(rsm_ldlidar_init(&ldd, &ld.link, &ld.clock, &lcfg) == RSM_OK);
    CHECK(rsm_slamtec_init(&rpd, &rp.link, &rp.clock, &scfg) == RSM_OK);
    while (i < size) {
        const uint8_t op = data[i++];
        side_t *s = (op & 1u) ? &rp : &ld;
        const uint8_t arg = i < size ? data[i++] : 0u;
        switch ((op >> 1) & 3u) {
        case 0: {
            const size_t n = (size_t)arg < size - i ? (size_t)arg : size - i;
            const uint32_t delay = i + n < size ? 100u * data[i + n] : 0u;
            rsm_fakelink_inject(&s->fl, data + i, n, delay);
            i += n + (i + n < size ? 1u : 0u);
            break;
        }
        case 1:
            rsm_fakelink_advance(&s->fl, 10000u * (uint64_t)arg);
            break;
        case 2:
            if (op & 1u) {
                scfg.scan_mode = (op & 8u) ? RSM_SLAMTEC_SCAN_EXPRESS : RSM_SLAMTEC_SCAN_STANDARD;
                rp.writes_at_listen = rp.fl.n_writes;
                CHECK(((op & 16u) ? rsm_slamtec_listen(&rpd) : rsm_slamtec_connect(&rpd)) == RSM_OK);
            } else {
                CHECK(rsm_ldlidar_connect(&ldd) == RSM_OK);
            }
            break;
        default:
            if (op & 1u) {
                CHECK(rsm_slamtec_disconnect(&rpd) == RSM_OK);
            } else {
                CHECK(rsm_ldlidar_disconnect(&ldd) == RSM_OK);
            }
            break;
        }
        poll_ld(&ldd, &lcfg, &ld);
        poll_rp(&rpd, &scfg, &rp);
    }
    return 0;
}
