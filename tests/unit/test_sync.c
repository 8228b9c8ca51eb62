/* Unit tests for src/localizer/sync.c: scans fused with odometry interpolated at their
 * own time, whatever order the two links delivered them in. The localizer
 * runs odometry-only, so every reported pose is the prediction and shows
 * exactly which encoder counts were applied before the scan. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "rsm/localizer.h"
#include "rsm/revolution.h"
#include "rsm/status.h"
#include "rsm/sync.h"
#include "test_support.h"
#include "unity.h"

#define TICKS_PER_M 128000.0f
#define MAX_RESULTS 64

static rsm_localizer_config_t lcfg;
static rsm_sync_config_t scfg;
static rsm_localizer_t loc;
static rsm_sync_t sync;
static rsm_scan_t scan;

typedef struct results {
    size_t n;
    uint64_t stamp[MAX_RESULTS];
    float x[MAX_RESULTS];
    int status[MAX_RESULTS];
} results_t;

static results_t res;

static void on_result(void *ctx, const rsm_scan_t *s, int status, const rsm_localizer_report_t *rep)
{
    results_t *r = (results_t *)ctx;
    TEST_ASSERT_TRUE_MESSAGE(r->n < MAX_RESULTS, "more results than the test expects");
    r->stamp[r->n] = s->stamp_us;
    r->x[r->n] = rep->pose.x;
    r->status[r->n] = status;
    r->n++;
}

void setUp(void)
{
    const rsm_pose_t x0 = {0.0f, 0.0f, 0.0f};
    size_t k;
    lcfg = rsm_localizer_config_default();
    lcfg.method = RSM_METHOD_ODOMETRY;
    scfg = rsm_sync_config_default();
    scfg.snap_us = 0u; /* the tests below use stamps 100 us apart; snapping has its own tests */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &lcfg, &x0, NULL));
    memset(&res, 0, sizeof res);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sync_init(&sync, &loc, &scfg, on_result, &res));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&scan, 181, -1.5707963f, 0.017453292f));
    for (k = 0; k < scan.count; ++k) {
        scan.range_m[k] = 2.0f;
    }
}

void tearDown(void)
{
}

static const rsm_odometry_sample_t zero_sample = {0u, 0u, 0u};

/* One encoder sample into the aligner. */
static int encoder(uint32_t left, uint32_t right, uint64_t stamp_us)
{
    rsm_odometry_sample_t smp;
    smp.stamp_us = stamp_us;
    smp.left = left;
    smp.right = right;
    return rsm_sync_encoder(&sync, &smp);
}

/* Straight-line odometry: both wheels at the same count. */
static void enc(uint32_t ticks, uint64_t stamp_us)
{
    TEST_ASSERT_EQUAL_INT(RSM_OK, encoder(ticks, ticks, stamp_us));
}

static void scan_at(uint64_t stamp_us)
{
    scan.stamp_us = stamp_us;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sync_scan(&sync, &scan));
}

static float metres(double ticks)
{
    return (float)(ticks / (double)TICKS_PER_M);
}

void test_init_should_reject_bad_arguments(void)
{
    rsm_sync_config_t none = scfg;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_init(NULL, &loc, &scfg, NULL, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_init(&sync, NULL, &scfg, NULL, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_init(&sync, &loc, NULL, NULL, NULL));
    none.max_wait_us = 0u;
    none.hold_us = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_init(&sync, &loc, &none, NULL, NULL));
    none = scfg;
    none.max_travel_m = -1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_init(&sync, &loc, &none, NULL, NULL));
    none.max_travel_m = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_init(&sync, &loc, &none, NULL, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_encoder(NULL, &zero_sample));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_encoder(&sync, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_scan(&sync, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_poll(NULL, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_flush(NULL));
    {
        const rsm_pose_t p = rsm_sync_pose(NULL); /* issue 30: it crashed */
        TEST_ASSERT_TRUE(isnan(p.x) && isnan(p.y) && isnan(p.theta));
    }
}

void test_encoder_samples_read_in_a_burst_are_spread_at_the_steady_rate(void)
{
    /* A host that stalled reads two packets 10 us apart: the first was
     * measured a period (100 ms) before its stamp. The robot drives 1000
     * ticks a period; a scan 150 ms in must see 1500 ticks. Taken at its
     * stamp the late packet made it 750 (issue 30's bursts); put halfway
     * between its neighbours, it is on time again. */
    const uint64_t t0 = 1000000u;
    enc(0u, t0);
    enc(1000u, t0 + 200000u - 10u);
    enc(2000u, t0 + 200000u);
    scan_at(t0 + 150000u);
    /* the second pair, after the first was applied */
    enc(3000u, t0 + 400000u - 10u);
    enc(4000u, t0 + 400000u);
    scan_at(t0 + 350000u);
    TEST_ASSERT_EQUAL_size_t(2, res.n);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(1500.0), res.x[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(3500.0), res.x[1]);
    TEST_ASSERT_EQUAL_UINT32(2, sync.counters.encoder_bursts);
    TEST_ASSERT_EQUAL_UINT32(2, sync.counters.interpolated);
}

void test_encoder_samples_at_an_uneven_rate_are_not_a_burst(void)
{
    /* Read as they came: a sample 30 ms after one that came 100 ms after
     * its own (not far sooner), one 10 ms after (far sooner, but no
     * backlog puts packets that far apart: a log replayed with its own
     * timing does), and two at the same time (a step sent in pieces). */
    const uint64_t t0 = 1000000u;
    enc(0u, t0);
    enc(1000u, t0 + 100000u);
    enc(1300u, t0 + 130000u);
    scan_at(t0 + 115000u);
    enc(2300u, t0 + 230000u);
    enc(2400u, t0 + 240000u);
    scan_at(t0 + 235000u);
    enc(3000u, t0 + 300000u);
    enc(3500u, t0 + 300000u);
    enc(4500u, t0 + 400000u);
    scan_at(t0 + 285000u);
    TEST_ASSERT_EQUAL_size_t(3, res.n);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(1150.0), res.x[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(2350.0), res.x[1]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(2850.0), res.x[2]);
    TEST_ASSERT_EQUAL_UINT32(0, sync.counters.encoder_bursts);
}

void test_the_aligner_and_the_assembler_see_the_same_bursts(void)
{
    /* One rule for both (src/core/burst.h). The aligner tested the gap as
     * d < gap / 8 in integers, the assembler as d * 8 < gap: a sample 1 us
     * after one that came 15 us after its own was a burst to the assembler
     * only, and 2 us after 23 us likewise. The others: a burst to both, and
     * to neither (d = gap / 8 exactly; d over 2 ms). */
    static const uint64_t gaps[][2] = {{15u, 1u}, {23u, 2u}, {100000u, 10u}, {16u, 2u}, {40000u, 2001u}};
    static rsm_rev_t rev;
    rsm_rev_config_t rcfg;
    const rsm_pose_t p = {0.0f, 0.0f, 0.0f};
    size_t k;
    (void)rsm_rev_config_default(&rcfg);
    for (k = 0; k < sizeof gaps / sizeof gaps[0]; ++k) {
        const uint64_t t0 = 1000000u;
        const uint64_t t1 = t0 + gaps[k][0];
        const uint64_t t2 = t1 + gaps[k][1];
        setUp();
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &rcfg));
        enc(0u, t0);
        enc(10u, t1);
        enc(20u, t2);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, t0, &p));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, t1, &p));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_odometry(&rev, t2, &p));
        TEST_ASSERT_EQUAL_UINT32_MESSAGE(k < 3u ? 1u : 0u, sync.counters.encoder_bursts, "aligner");
        TEST_ASSERT_EQUAL_UINT32_MESSAGE(k < 3u ? 1u : 0u, rev.stats.odometry_bursts, "assembler");
    }
}

void test_init_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* What rsm_sync_init passes for an application compiled with other
     * capacities (RSM_SYNC_DEPTH and RSM_MAX_BEAMS size the aligner), or
     * with capacities that give the same size: refused, and not one byte
     * written. */
    static rsm_sync_t s;
    static rsm_sync_t before;
    memset(&s, 0x5A, sizeof s);
    memcpy(&before, &s, sizeof s);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_sync_init_checked(&s, sizeof s - 8u,
                                                                (unsigned long)RSM_CONFIG_FINGERPRINT, &loc, &scfg,
                                                                NULL, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_sync_init_checked(&s, sizeof s,
                                                                (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul, &loc,
                                                                &scfg, NULL, NULL));
    TEST_ASSERT_EQUAL_MEMORY(&before, &s, sizeof s);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sync_init(&s, &loc, &scfg, NULL, NULL));
}

/* Every call on s refused (RSM_ERR_INVAL; a NaN pose), s untouched and
 * nothing fused. */
static void assert_sync_refused(rsm_sync_t *s)
{
    static rsm_sync_t before;
    const rsm_odometry_sample_t smp = {1000u, 10u, 10u};
    rsm_pose_t p;
    if (s != NULL) {
        memcpy(&before, s, sizeof before);
    }
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_encoder(s, &smp));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_encoder_restart(s));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_scan(s, &scan));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_poll(s, 1000000u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_flush(s));
    p = rsm_sync_pose(s);
    TEST_ASSERT_TRUE(isnan(p.x) && isnan(p.y) && isnan(p.theta));
    if (s != NULL) {
        TEST_ASSERT_EQUAL_MEMORY(&before, s, sizeof before);
    }
    TEST_ASSERT_EQUAL_size_t(0u, res.n);
    TEST_ASSERT_EQUAL_UINT32(0u, loc.counters.scans);
}

void test_an_aligner_never_initialised_should_be_refused(void)
{
    /* Zeroed (poll and flush answered 0 as if it were running), stale
     * memory (every call went through its loc pointer), NULL, and what a
     * failed init left. */
    static rsm_sync_t s;
    memset(&s, 0, sizeof s);
    assert_sync_refused(&s);
    memset(&s, 0x5A, sizeof s);
    assert_sync_refused(&s);
    assert_sync_refused(NULL);
    memset(&s, 0, sizeof s);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_init(&s, &loc, NULL, on_result, &res));
    assert_sync_refused(&s);
}

void test_init_should_refuse_a_localizer_never_initialised(void)
{
    /* Stale memory has a config pointer too: the localizer's own mark is
     * what counts. */
    static rsm_localizer_t stale;
    static rsm_sync_t s;
    static rsm_sync_t before;
    memset(&s, 0, sizeof s);
    memcpy(&before, &s, sizeof s);
    memset(&stale, 0, sizeof stale);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_init(&s, &stale, &scfg, NULL, NULL));
    memset(&stale, 0x5A, sizeof stale);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_init(&s, &stale, &scfg, NULL, NULL));
    TEST_ASSERT_EQUAL_MEMORY(&before, &s, sizeof s);
}

void test_scan_without_any_odometry_should_be_fused_at_once(void)
{
    scan_at(1000u);
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_EQUAL_INT(RSM_OK, res.status[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.exact);
}

void test_scan_stamped_with_its_encoder_packet_should_see_exactly_those_counts(void)
{
    /* Capture order: ENC(t) then SCAN(t) at the same stamp. */
    enc(0u, 100u);
    enc(12800u, 200u);
    scan_at(200u);
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.1f, res.x[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.exact);
    /* A packet with the same stamp after the scan comes after it. */
    enc(25600u, 200u);
    enc(38400u, 300u);
    scan_at(300u);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.3f, res.x[1]);
}

void test_odometry_set_at_run_time_should_convert_the_next_counts(void)
{
    rsm_odometry_config_t odo = loc.odo.cfg;
    rsm_odometry_config_t bad;
    enc(0u, 100u);
    enc(12800u, 200u);
    scan_at(200u);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.1f, res.x[0]);
    /* The robot reports TicksMM 256: the same 12800 ticks are 5 cm. The
     * localizer keeps a copy; the caller's struct is free at once. */
    odo.ticks_per_m_left = odo.ticks_per_m_right = 256000.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_odometry(&loc, &odo));
    odo.wheel_base_m = -1.0f;
    enc(25600u, 300u);
    scan_at(300u);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.15f, res.x[1]);
    /* Refused with nothing changed; the configuration given at init untouched. */
    bad = loc.odo.cfg;
    bad.ticks_per_m_left = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_set_odometry(&loc, &bad));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_set_odometry(&loc, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_set_odometry(NULL, &bad));
    TEST_ASSERT_EQUAL_FLOAT(256000.0f, loc.odo.cfg.ticks_per_m_left);
    TEST_ASSERT_EQUAL_FLOAT(TICKS_PER_M, lcfg.odometry.ticks_per_m_left);
}

void test_scan_arriving_before_its_odometry_should_wait_and_interpolate(void)
{
    enc(0u, 100u);
    enc(12800u, 200u);
    scan_at(250u);
    TEST_ASSERT_EQUAL_size_t(0, res.n); /* waits for a sample past 250 */
    enc(25600u, 300u);
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(19200.0), res.x[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.interpolated);
    /* The rest of the step is held back, and shown by rsm_sync_pose. */
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(19200.0), rsm_localizer_pose(&loc).x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.2f, rsm_sync_pose(&sync).x);
    TEST_ASSERT_EQUAL_INT(0, rsm_sync_flush(&sync));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.2f, rsm_localizer_pose(&loc).x);
}

void test_scan_arriving_after_later_odometry_should_be_fused_at_its_own_time(void)
{
    /* A long telegram: stamped at its first byte, complete 2 packets later. */
    enc(0u, 100u);
    enc(12800u, 200u);
    enc(25600u, 300u);
    enc(38400u, 400u);
    scan_at(225u);
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(16000.0), res.x[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.interpolated);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.3f, rsm_sync_pose(&sync).x);
}

void test_interpolation_should_not_depend_on_which_link_arrived_first(void)
{
    float a;
    enc(0u, 100u);
    scan_at(150u);
    enc(12800u, 200u);
    a = res.x[0];
    setUp();
    enc(0u, 100u);
    enc(12800u, 200u);
    scan_at(150u);
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_EQUAL_FLOAT(a, res.x[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.05f, a);
}

void test_interpolation_should_follow_counter_wrap_around(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_OK, encoder(0xFFFFF000u, 0x00000800u, 100u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, encoder(0x00001000u, 0x00002800u, 300u));
    scan_at(200u);
    /* Each wheel moves 8192 counts (the left one through zero); half by t = 200. */
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(4096.0), res.x[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, res.x[0] - rsm_localizer_pose(&loc).x);
}

void test_waiting_scan_should_time_out_with_the_odometry_there_is(void)
{
    enc(0u, 100u);
    enc(12800u, 200u);
    scan_at(1000u);
    TEST_ASSERT_EQUAL_INT(0, rsm_sync_poll(&sync, 1000u + scfg.max_wait_us - 1u));
    TEST_ASSERT_EQUAL_size_t(0, res.n);
    TEST_ASSERT_EQUAL_INT(1, rsm_sync_poll(&sync, 1000u + scfg.max_wait_us));
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.1f, res.x[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.timed_out);
    TEST_ASSERT_EQUAL_INT(0, rsm_sync_poll(&sync, 10000000u));
}

void test_newer_scan_should_release_a_waiting_one_first(void)
{
    enc(0u, 100u);
    scan_at(150u);
    scan_at(160u);
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_EQUAL_UINT64(150u, res.stamp[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.superseded);
    enc(12800u, 200u);
    TEST_ASSERT_EQUAL_size_t(2, res.n);
    TEST_ASSERT_EQUAL_UINT64(160u, res.stamp[1]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(7680.0), res.x[1]);
}

void test_flush_should_fuse_the_waiting_scan_and_apply_all_odometry(void)
{
    enc(0u, 100u);
    scan_at(150u);
    TEST_ASSERT_EQUAL_INT(1, rsm_sync_flush(&sync));
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    enc(12800u, 200u);
    enc(25600u, 300u);
    TEST_ASSERT_EQUAL_INT(0, rsm_sync_flush(&sync));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.2f, rsm_localizer_pose(&loc).x);
}

void test_scan_older_than_applied_odometry_should_count_as_late(void)
{
    enc(0u, 100u);
    enc(12800u, 200u);
    enc(25600u, 300u);
    scan_at(300u);
    scan_at(250u); /* stamped before odometry already applied */
    TEST_ASSERT_EQUAL_size_t(2, res.n);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.late);
    /* The localizer itself refuses a scan older than the previous one. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_ORDER, res.status[1]);
}

void test_backwards_encoder_stamp_should_be_taken_in_arrival_order(void)
{
    enc(0u, 100u);
    enc(12800u, 300u);
    enc(25600u, 200u); /* stamped 200, treated as 300 */
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.encoder_backwards);
    scan_at(300u);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.2f, res.x[0]);
}

void test_old_samples_should_be_applied_after_the_hold_time(void)
{
    enc(0u, 0u);
    enc(12800u, 100000u);
    TEST_ASSERT_EQUAL_UINT32(2u, sync.count);
    enc(25600u, 100000u + scfg.hold_us + 1u);
    /* The first two are older than the hold time: applied (composed for
     * the next scan's prediction), the third still held. */
    TEST_ASSERT_EQUAL_UINT32(1u, sync.count);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.1f, sync.pending.x);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_localizer_pose(&loc).x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.2f, rsm_sync_pose(&sync).x);
}

void test_full_buffer_should_apply_the_oldest_sample_and_count_it(void)
{
    uint32_t k;
    scfg.hold_us = 0xFFFFFFFFu;
    for (k = 0; k < RSM_SYNC_DEPTH + 2u; ++k) {
        enc(k * 1280u, 100u + k);
    }
    TEST_ASSERT_EQUAL_UINT32(2u, sync.counters.encoder_overflow);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(1280.0), sync.pending.x);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(1280.0 * (RSM_SYNC_DEPTH + 1)), rsm_sync_pose(&sync).x);
}

void test_scan_offset_should_move_the_alignment_time(void)
{
    scfg.scan_offset_us = -100;
    enc(0u, 100u);
    enc(12800u, 200u);
    enc(25600u, 300u);
    scan_at(250u); /* measured at 150 */
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.05f, res.x[0]);
    TEST_ASSERT_EQUAL_UINT64(250u, res.stamp[0]); /* the scan keeps its own stamp */
}

void test_scan_offset_should_saturate_instead_of_wrapping(void)
{
    scfg.scan_offset_us = 1000;
    enc(0u, 100u);
    enc(12800u, 5000u);
    /* Near the end of time: the offset saturates, the scan waits for later
     * odometry; it does not wrap round to a time before the samples. */
    scan_at(UINT64_MAX - 10u);
    TEST_ASSERT_EQUAL_size_t(0, res.n);
    TEST_ASSERT_EQUAL_UINT32(0u, sync.counters.late);
    scan_at((uint64_t)INT64_MAX - 10u); /* past the signed range too (UBSan checks) */
    TEST_ASSERT_EQUAL_UINT32(0u, sync.counters.late);
    TEST_ASSERT_EQUAL_INT(1, rsm_sync_flush(&sync));
    TEST_ASSERT_EQUAL_size_t(2, res.n);
}

void test_corrupt_encoder_sample_should_be_refused_and_lose_no_motion(void)
{
    enc(0u, 100000u);
    enc(12800u, 200000u);
    /* Checksum-valid but corrupt: one counter 2^30 ticks (8.4 km) on. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, encoder(12800u + 0x40000000u, 12800u, 300000u));
    enc(38400u, 400000u);
    scan_at(400000u);
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.3f, res.x[0]);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.0f, rsm_localizer_pose(&loc).theta);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT32(1u, loc.odo.implausible);
    TEST_ASSERT_LESS_THAN_FLOAT(1.0f, loc.ekf.p[0]);
}

void test_encoder_restart_should_take_no_step_across_a_new_connection(void)
{
    enc(5000000u, 100000u);
    enc(5012800u, 200000u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sync_encoder_restart(&sync));
    enc(0u, 300000u); /* the robot restarted: its counters read 0 */
    enc(12800u, 400000u);
    scan_at(400000u);
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.2f, res.x[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.restarts);
    TEST_ASSERT_EQUAL_UINT32(0u, loc.odo.implausible);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_encoder_restart(NULL));
}

/* First scan at 100 us, then two 0.1 m samples, then a scan at 300 us. */
static void two_samples_between_scans(void)
{
    enc(0u, 100u);
    scan_at(100u);
    enc(12800u, 200u);
    enc(25600u, 300u);
    scan_at(300u);
}

void test_odometry_between_scans_should_be_predicted_once_per_scan(void)
{
    static rsm_localizer_t ref;
    const rsm_pose_t x0 = {0.0f, 0.0f, 0.0f};
    const rsm_motion_t both = {0.2f, 0.0f, 0.0f};
    float p_once[9];
    two_samples_between_scans();
    TEST_ASSERT_EQUAL_size_t(2, res.n);
    TEST_ASSERT_EQUAL_UINT32(1u, loc.counters.motions);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.2f, res.x[1]);
    /* The filter of a run fed one increment per scan (a CARMEN log's). */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&ref, &lcfg, &x0, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&ref, &scan, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_motion(&ref, &both));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&ref, &scan, NULL));
    TEST_ASSERT_EQUAL_MEMORY(ref.ekf.p, loc.ekf.p, sizeof loc.ekf.p);
    TEST_ASSERT_EQUAL_MEMORY(&ref.ekf.x, &loc.ekf.x, sizeof loc.ekf.x);
    memcpy(p_once, loc.ekf.p, sizeof p_once);
    /* max_travel_m 0: a prediction per sample, each with its own noise
     * (the floors twice): another filter for the same motion. */
    setUp();
    scfg.max_travel_m = 0.0f;
    two_samples_between_scans();
    TEST_ASSERT_EQUAL_UINT32(2u, loc.counters.motions);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.2f, res.x[1]);
    TEST_ASSERT_TRUE(memcmp(p_once, loc.ekf.p, sizeof p_once) != 0);
}

void test_travel_without_scans_should_be_predicted_at_the_travel_limit(void)
{
    uint32_t k;
    enc(0u, 100u);
    scan_at(100u);
    /* 5 m straight with no scan: predicted at 2 m and 4 m of travel. */
    TEST_ASSERT_EQUAL_FLOAT(2.0f, scfg.max_travel_m);
    for (k = 1u; k <= 50u; ++k) {
        enc(k * 12800u, 100u + 100000u * k);
    }
    TEST_ASSERT_EQUAL_INT(0, rsm_sync_flush(&sync));
    TEST_ASSERT_EQUAL_UINT32(3u, loc.counters.motions); /* two at the limit, the rest at the flush */
    TEST_ASSERT_EQUAL_UINT32(2u, sync.counters.blind_predictions);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 5.0f, rsm_localizer_pose(&loc).x);
}

void test_turning_on_the_spot_should_be_predicted_before_half_a_turn(void)
{
    /* Four whole turns on the spot in sevenths, no scan: the net step is
     * nothing (a composed whole turn would wrap to it), but every three
     * sevenths (a fourth would pass half a turn) are predicted, with their
     * noise. */
    const float b = lcfg.odometry.wheel_base_m;
    const int32_t per_turn = (int32_t)lroundf(RSM_PI * b * TICKS_PER_M); /* each wheel, one turn */
    const float three_sevenths = 6.0f * RSM_PI / 7.0f;
    int32_t k;
    enc(0u, 100u);
    scan_at(100u);
    for (k = 1; k <= 28; ++k) {
        const int32_t t = per_turn * k / 7;
        TEST_ASSERT_EQUAL_INT(RSM_OK, encoder((uint32_t)-t, (uint32_t)t, 100u + 100000u * (uint64_t)k));
    }
    TEST_ASSERT_EQUAL_INT(0, rsm_sync_flush(&sync));
    TEST_ASSERT_EQUAL_UINT32(9u, sync.counters.blind_predictions); /* before the 4th, 7th, ... 28th */
    TEST_ASSERT_EQUAL_UINT32(10u, loc.counters.motions);          /* and the 28th at the flush */
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, 0.0f, rsm_localizer_pose(&loc).theta);
    TEST_ASSERT_GREATER_THAN_FLOAT(9.0f * powf(lcfg.odometry.sigma_rot_per_rad * three_sevenths, 2.0f) * 0.99f,
                                   loc.ekf.p[8]);
}

void test_default_config_should_snap_within_a_millisecond(void)
{
    TEST_ASSERT_EQUAL_UINT32(1000u, rsm_sync_config_default().snap_us);
    TEST_ASSERT_EQUAL_UINT32(250000u, rsm_sync_config_default().max_wait_us);
    TEST_ASSERT_EQUAL_UINT32(500000u, rsm_sync_config_default().hold_us);
    TEST_ASSERT_EQUAL_INT32(0, rsm_sync_config_default().scan_offset_us);
}

void test_scan_just_after_its_packet_should_snap_to_it_without_waiting(void)
{
    scfg.snap_us = 1000u;
    enc(0u, 100u);
    enc(12800u, 10000u);
    scan_at(10300u); /* the laser link delivered 0.3 ms after the robot link */
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_EQUAL_FLOAT(0.1f, res.x[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.exact);
    TEST_ASSERT_EQUAL_UINT32(0u, sync.counters.interpolated);
}

void test_scan_just_before_its_packet_should_snap_to_it(void)
{
    scfg.snap_us = 1000u;
    enc(0u, 100u);
    scan_at(9800u); /* the laser link won the race by 0.2 ms */
    TEST_ASSERT_EQUAL_size_t(0, res.n);
    enc(12800u, 10000u);
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_EQUAL_FLOAT(0.1f, res.x[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.exact);
}

void test_scan_between_packets_beyond_the_snap_should_interpolate(void)
{
    scfg.snap_us = 1000u;
    enc(0u, 100u);
    enc(12800u, 10100u);
    enc(25600u, 20100u);
    scan_at(12600u); /* a quarter into the second step */
    TEST_ASSERT_EQUAL_size_t(1, res.n);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, metres(16000.0), res.x[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.interpolated);
}

void test_oversized_scan_should_be_refused_and_not_fused(void)
{
    scan.count = RSM_MAX_BEAMS + 1u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sync_scan(&sync, &scan));
    TEST_ASSERT_EQUAL_size_t(0, res.n);
    TEST_ASSERT_EQUAL_UINT32(1u, sync.counters.scans);
}

void test_every_scan_should_be_fused_once_in_order_whatever_the_arrival_order(void)
{
    /* Two links shuffled over 50 steps: each scan (stamped halfway between
     * two packets) arrives before or after the packet that follows it. */
    uint32_t i;
    uint32_t fused;
    uint32_t rng = 7u;
    enc(0u, 100u);
    for (i = 1; i <= 50u; ++i) {
        const uint64_t t = 100u + 100u * i;
        if (rsm_test_rng_next(&rng) & 1u) {
            scan_at(t - 50u);
            enc(i * 1280u, t);
        } else {
            enc(i * 1280u, t);
            scan_at(t - 50u);
        }
    }
    (void)rsm_sync_flush(&sync);
    fused = sync.counters.interpolated + sync.counters.exact + sync.counters.late + sync.counters.timed_out +
            sync.counters.superseded;
    TEST_ASSERT_EQUAL_UINT32(50u, sync.counters.scans);
    TEST_ASSERT_EQUAL_UINT32(50u, fused);
    TEST_ASSERT_EQUAL_UINT32(50u, sync.counters.interpolated);
    TEST_ASSERT_EQUAL_size_t(50, res.n);
    for (i = 0; i < 50u; ++i) {
        TEST_ASSERT_EQUAL_UINT64(150u + 100u * i, res.stamp[i]);
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, metres(1280.0 * (i + 0.5)), res.x[i]);
    }
    TEST_ASSERT_EQUAL_UINT32(0u, loc.counters.outcome[RSM_SCAN_OUT_OF_ORDER]);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_init_should_reject_bad_arguments);
    RUN_TEST(test_encoder_samples_read_in_a_burst_are_spread_at_the_steady_rate);
    RUN_TEST(test_the_aligner_and_the_assembler_see_the_same_bursts);
    RUN_TEST(test_encoder_samples_at_an_uneven_rate_are_not_a_burst);
    RUN_TEST(test_init_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_an_aligner_never_initialised_should_be_refused);
    RUN_TEST(test_init_should_refuse_a_localizer_never_initialised);
    RUN_TEST(test_scan_without_any_odometry_should_be_fused_at_once);
    RUN_TEST(test_scan_stamped_with_its_encoder_packet_should_see_exactly_those_counts);
    RUN_TEST(test_odometry_set_at_run_time_should_convert_the_next_counts);
    RUN_TEST(test_scan_arriving_before_its_odometry_should_wait_and_interpolate);
    RUN_TEST(test_scan_arriving_after_later_odometry_should_be_fused_at_its_own_time);
    RUN_TEST(test_interpolation_should_not_depend_on_which_link_arrived_first);
    RUN_TEST(test_interpolation_should_follow_counter_wrap_around);
    RUN_TEST(test_waiting_scan_should_time_out_with_the_odometry_there_is);
    RUN_TEST(test_newer_scan_should_release_a_waiting_one_first);
    RUN_TEST(test_flush_should_fuse_the_waiting_scan_and_apply_all_odometry);
    RUN_TEST(test_scan_older_than_applied_odometry_should_count_as_late);
    RUN_TEST(test_backwards_encoder_stamp_should_be_taken_in_arrival_order);
    RUN_TEST(test_odometry_between_scans_should_be_predicted_once_per_scan);
    RUN_TEST(test_travel_without_scans_should_be_predicted_at_the_travel_limit);
    RUN_TEST(test_turning_on_the_spot_should_be_predicted_before_half_a_turn);
    RUN_TEST(test_old_samples_should_be_applied_after_the_hold_time);
    RUN_TEST(test_full_buffer_should_apply_the_oldest_sample_and_count_it);
    RUN_TEST(test_scan_offset_should_move_the_alignment_time);
    RUN_TEST(test_default_config_should_snap_within_a_millisecond);
    RUN_TEST(test_scan_just_after_its_packet_should_snap_to_it_without_waiting);
    RUN_TEST(test_scan_just_before_its_packet_should_snap_to_it);
    RUN_TEST(test_scan_between_packets_beyond_the_snap_should_interpolate);
    RUN_TEST(test_oversized_scan_should_be_refused_and_not_fused);
    RUN_TEST(test_scan_offset_should_saturate_instead_of_wrapping);
    RUN_TEST(test_corrupt_encoder_sample_should_be_refused_and_lose_no_motion);
    RUN_TEST(test_encoder_restart_should_take_no_step_across_a_new_connection);
    RUN_TEST(test_every_scan_should_be_fused_once_in_order_whatever_the_arrival_order);
    return UNITY_END();
}
