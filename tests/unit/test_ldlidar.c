/* Tests of the LD06 / LD19 listening driver (src/drivers/ldlidar.c) on the
 * in-memory fakelink: a fake sensor turning at 10 Hz in a square room,
 * 12-point packets every 2.67 ms; stamps, link loss and recovery, faults,
 * and the points through the revolution assembler into whole scans. */
#include <math.h>
#include <string.h>

#include "fakelink.h"
#include "rsm/ld06.h"
#include "rsm/ldlidar.h"
#include "rsm/revolution.h"
#include "rsm/status.h"
#include "unity.h"

#define T0_US 1000000u
#define SPEED_DPS 3600u                 /* 10 turns per second */
#define STEP_CDEG 80u                   /* 0.8 deg between points: 450 a turn */
#define PACKET_US (12u * 80u * 10000u / SPEED_DPS) /* 2666 us of turning */

static rsm_fakelink_t fl;
static rsm_link_t link;
static rsm_clock_t clk;
static rsm_ldlidar_config_t cfg;
static rsm_ldlidar_t drv;

/* the fake sensor */
static int sending;
static uint32_t next_cdeg;
static uint64_t next_send_us;
static uint32_t packets_sent;
static int corrupt_next;
static uint32_t bunch_us; /* > 0: packets come in bursts this far apart, as
                             through a USB serial adapter */

/* Distance from the centre of a 4 m square room along sensor angle a
 * (clockwise), mm. */
static uint16_t room_mm(uint32_t cdeg)
{
    const double a = -(double)cdeg / 18000.0 * 3.14159265358979323846;
    const double c = fabs(cos(a));
    const double s = fabs(sin(a));
    return (uint16_t)(2000.0 / (c > s ? c : s) + 0.5);
}

static void send_packet(uint32_t delay_us)
{
    rsm_ld06_packet_t p;
    uint8_t b[RSM_LD06_PACKET];
    unsigned i;
    memset(&p, 0, sizeof p);
    p.speed_dps = SPEED_DPS;
    p.start_cdeg = (uint16_t)next_cdeg;
    p.end_cdeg = (uint16_t)((next_cdeg + 11u * STEP_CDEG) % 36000u);
    p.timestamp_ms = (uint16_t)((fl.now_us / 1000u) % 30000u);
    for (i = 0; i < 12u; ++i) {
        p.distance_mm[i] = room_mm((next_cdeg + i * STEP_CDEG) % 36000u);
        p.intensity[i] = 200u;
    }
    TEST_ASSERT_EQUAL_INT((int)RSM_LD06_PACKET, rsm_ld06_encode(&p, b, sizeof b));
    if (corrupt_next) {
        b[20] ^= 0x04u;
        corrupt_next = 0;
    }
    rsm_fakelink_send(&fl, b, sizeof b, delay_us);
    next_cdeg = (next_cdeg + 12u * STEP_CDEG) % 36000u;
    packets_sent++;
}

/* One driver poll, the fake sensor sending what is due first. */
static rsm_ldlidar_event_type_t step(rsm_ldlidar_event_t *ev)
{
    /* packets due before the driver's read can end are queued to arrive
     * at their own times */
    while (sending && next_send_us <= fl.now_us + cfg.read_timeout_us) {
        uint32_t delay = (uint32_t)(next_send_us > fl.now_us ? next_send_us - fl.now_us : 0u);
        if (bunch_us > 0u) {
            const uint64_t at = fl.now_us + delay;
            delay += (uint32_t)(bunch_us - at % bunch_us);
        }
        send_packet(delay);
        next_send_us += PACKET_US;
    }
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ldlidar_poll(&drv, ev));
    return ev->type;
}

static int run_until(rsm_ldlidar_event_type_t want, uint64_t max_us, rsm_ldlidar_event_t *ev)
{
    const uint64_t end = fl.now_us + max_us;
    while (fl.now_us < end) {
        if (step(ev) == want) {
            return 1;
        }
    }
    return 0;
}

void setUp(void)
{
    rsm_fakelink_init(&fl, T0_US, &link, &clk);
    rsm_fakelink_set_peer_baud(&fl, 230400u);
    sending = 1;
    next_cdeg = 0;
    next_send_us = T0_US;
    packets_sent = 0;
    corrupt_next = 0;
    bunch_us = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ldlidar_config_default(&cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ldlidar_init(&drv, &link, &clk, &cfg));
}

void tearDown(void) {}

void test_connect_sets_the_rate_and_the_first_packet_connects(void)
{
    rsm_ldlidar_event_t ev;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ldlidar_connect(&drv));
    TEST_ASSERT_EQUAL_UINT32(230400u, fl.host_baud);
    TEST_ASSERT_EQUAL_UINT32(0, drv.stats.baud_errors);
    TEST_ASSERT_TRUE(run_until(RSM_LDLIDAR_EVENT_CONNECTED, 100000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_LDLIDAR_STREAMING, drv.state);
    /* the connecting packet's points come next */
    TEST_ASSERT_EQUAL_INT(RSM_LDLIDAR_EVENT_POINTS, step(&ev));
    TEST_ASSERT_EQUAL_size_t(12, ev.count);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.0f, ev.points[0].angle_deg);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.0f, ev.points[0].range_m);
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.connects);
    TEST_ASSERT_EQUAL_UINT32(0, drv.stats.reconnects);
}

void test_points_are_stamped_back_from_the_packet_arrival_by_the_angle_step(void)
{
    rsm_ldlidar_event_t ev;
    unsigned got = 0;
    cfg.latency_us = 700u;
    (void)rsm_ldlidar_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_LDLIDAR_EVENT_CONNECTED, 100000u, &ev));
    while (got < 20u && run_until(RSM_LDLIDAR_EVENT_POINTS, 50000u, &ev)) {
        size_t i;
        /* the last point at the arrival minus the latency; 0.8 deg at
         * 3600 deg/s = 222 us per step */
        TEST_ASSERT_EQUAL_UINT64(ev.stamp_us - 700u, ev.points[11].stamp_us);
        for (i = 0; i < 12u; ++i) {
            TEST_ASSERT_EQUAL_UINT64(ev.points[11].stamp_us - (11u - i) * 222u, ev.points[i].stamp_us);
        }
        /* a packet is complete only after its last byte was sent */
        TEST_ASSERT_TRUE(ev.stamp_us >= T0_US + (uint64_t)got * PACKET_US);
        got++;
    }
    TEST_ASSERT_EQUAL_UINT(20, got);
    TEST_ASSERT_EQUAL_UINT32(0, drv.stats.stamp_shifts);
    TEST_ASSERT_EQUAL_UINT32(got * 12u, drv.stats.points);
}

void test_packets_bunched_in_one_read_keep_their_stamps_in_order(void)
{
    rsm_ldlidar_event_t ev;
    uint64_t last = 0;
    unsigned got = 0;
    bunch_us = 8000u; /* three packets per burst */
    (void)rsm_ldlidar_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_LDLIDAR_EVENT_CONNECTED, 100000u, &ev));
    while (got < 30u && run_until(RSM_LDLIDAR_EVENT_POINTS, 50000u, &ev)) {
        size_t i;
        for (i = 0; i < 12u; ++i) {
            TEST_ASSERT_TRUE(ev.points[i].stamp_us >= last);
            last = ev.points[i].stamp_us;
        }
        /* moved at most by the packets before it in its burst (the read
         * chunk may be as small as 7 bytes, then the line-time correction
         * sees little of the burst) */
        TEST_ASSERT_TRUE(ev.points[11].stamp_us <= ev.stamp_us + 3u * PACKET_US);
        got++;
    }
    TEST_ASSERT_EQUAL_UINT(30, got);
    TEST_ASSERT_TRUE(drv.stats.stamp_shifts > 0u);
}

void test_silence_is_a_link_loss_and_the_next_packet_reconnects(void)
{
    rsm_ldlidar_event_t ev;
    uint64_t stopped;
    (void)rsm_ldlidar_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_LDLIDAR_EVENT_CONNECTED, 100000u, &ev));
    (void)run_until(RSM_LDLIDAR_EVENT_NONE, 50000u, &ev);
    sending = 0;
    stopped = fl.now_us;
    TEST_ASSERT_TRUE(run_until(RSM_LDLIDAR_EVENT_LINK_LOST, 2u * cfg.stream_timeout_us, &ev));
    /* reported once the timeout has run since the last packet, not later
     * than one read timeout after */
    TEST_ASSERT_TRUE(ev.stamp_us >= drv.last_packet_us);
    TEST_ASSERT_TRUE(ev.stamp_us <= stopped + cfg.stream_timeout_us + cfg.read_timeout_us);
    TEST_ASSERT_EQUAL_INT(RSM_LDLIDAR_LISTENING, drv.state);
    TEST_ASSERT_FALSE(run_until(RSM_LDLIDAR_EVENT_LINK_LOST, 3u * cfg.stream_timeout_us, &ev));
    sending = 1;
    next_send_us = fl.now_us;
    TEST_ASSERT_TRUE(run_until(RSM_LDLIDAR_EVENT_CONNECTED, 100000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.link_lost);
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.reconnects);
    TEST_ASSERT_EQUAL_UINT32(2, drv.stats.connects);
}

void test_a_corrupted_packet_is_counted_and_lost_alone(void)
{
    rsm_ldlidar_event_t ev;
    uint32_t before;
    (void)rsm_ldlidar_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_LDLIDAR_EVENT_CONNECTED, 100000u, &ev));
    (void)run_until(RSM_LDLIDAR_EVENT_NONE, 20000u, &ev);
    before = drv.stats.packets;
    corrupt_next = 1;
    (void)run_until(RSM_LDLIDAR_EVENT_NONE, 30u * PACKET_US, &ev);
    sending = 0;
    (void)run_until(RSM_LDLIDAR_EVENT_LINK_LOST, 2u * cfg.stream_timeout_us, &ev);
    TEST_ASSERT_EQUAL_UINT32(1, drv.parser.stats.crc_errors);
    TEST_ASSERT_EQUAL_UINT32(packets_sent - 1u, drv.stats.packets);
    TEST_ASSERT_TRUE(drv.stats.packets > before);
    TEST_ASSERT_EQUAL_UINT32(RSM_LD06_PACKET, drv.parser.stats.bytes_skipped);
}

void test_disconnected_driver_reads_nothing_into_events(void)
{
    rsm_ldlidar_event_t ev;
    (void)rsm_ldlidar_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_LDLIDAR_EVENT_CONNECTED, 100000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ldlidar_disconnect(&drv));
    TEST_ASSERT_FALSE(run_until(RSM_LDLIDAR_EVENT_POINTS, 200000u, &ev));
    TEST_ASSERT_FALSE(run_until(RSM_LDLIDAR_EVENT_LINK_LOST, 2u * cfg.stream_timeout_us, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_LDLIDAR_IDLE, drv.state);
}

void test_points_through_the_assembler_make_whole_turns_on_the_walls(void)
{
    static rsm_rev_t rev;
    rsm_rev_config_t rc;
    rsm_ldlidar_event_t ev;
    unsigned scans = 0;
    (void)rsm_rev_config_default(&rc);
    rc.deskew = 0u; /* the robot stands still */
    rc.keep_every = (uint16_t)((450u + RSM_MAX_BEAMS - 1u) / RSM_MAX_BEAMS);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_init(&rev, &rc));
    (void)rsm_ldlidar_connect(&drv);
    while (scans < 3u && fl.now_us < T0_US + 1000000u) {
        size_t i;
        if (step(&ev) != RSM_LDLIDAR_EVENT_POINTS) {
            continue;
        }
        for (i = 0; i < ev.count; ++i) {
            const int r = rsm_rev_push(&rev, &ev.points[i]);
            TEST_ASSERT_TRUE(r == 0 || r == 1);
            if (r == 1) {
                size_t k;
                scans++;
                TEST_ASSERT_EQUAL_size_t((450u + rc.keep_every - 1u) / rc.keep_every, rev.scan.count);
                for (k = 0; k < rev.scan.count; ++k) {
                    const float x = rev.scan.range_m[k] * cosf(rev.scan.angle_rad[k]);
                    const float y = rev.scan.range_m[k] * sinf(rev.scan.angle_rad[k]);
                    TEST_ASSERT_FLOAT_WITHIN(0.002f, 2.0f, fmaxf(fabsf(x), fabsf(y)));
                }
            }
        }
    }
    TEST_ASSERT_EQUAL_UINT(3, scans);
    /* the stream started at 0 deg: the first turn is whole, yet it cannot be
     * told from a cut one and is dropped by rule */
    TEST_ASSERT_EQUAL_UINT32(1, rev.stats.partial);
}

void test_stamp_and_init_reject_bad_arguments(void)
{
    rsm_ld06_packet_t p;
    rsm_lidar_point_t pts[12];
    rsm_ldlidar_config_t bad = cfg;
    memset(&p, 0, sizeof p);
    p.speed_dps = 0u; /* no speed: every point at the packet time */
    p.end_cdeg = 1100u;
    TEST_ASSERT_EQUAL_INT(12, rsm_ldlidar_stamp(&p, 5000u, pts));
    TEST_ASSERT_EQUAL_UINT64(5000u, pts[0].stamp_us);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ldlidar_stamp(NULL, 0u, pts));
    bad.stream_timeout_us = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ldlidar_init(&drv, &link, &clk, &bad));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ldlidar_init(&drv, NULL, &clk, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ldlidar_connect(NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ldlidar_poll(&drv, NULL));
}

/* A host serving several links polls with a zero read timeout and waits
 * until bytes come or the driver's next deadline: never blocked inside the
 * poll, it still sees the packets, and the link loss exactly when due. */
void test_next_deadline_serves_a_caller_that_never_blocks(void)
{
    rsm_ldlidar_event_t ev;
    unsigned points = 0;
    uint64_t due;
    TEST_ASSERT_TRUE(rsm_ldlidar_next_deadline_us(&drv) == UINT64_MAX); /* IDLE */
    TEST_ASSERT_TRUE(rsm_ldlidar_next_deadline_us(NULL) == UINT64_MAX);
    cfg.read_timeout_us = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ldlidar_init(&drv, &link, &clk, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ldlidar_connect(&drv));
    TEST_ASSERT_TRUE(rsm_ldlidar_next_deadline_us(&drv) == fl.now_us + cfg.stream_timeout_us);
    while (points < 600u) {
        const uint64_t before = fl.now_us;
        const rsm_ldlidar_event_type_t t = step(&ev);
        TEST_ASSERT_TRUE(fl.now_us == before); /* the poll did not wait */
        if (t == RSM_LDLIDAR_EVENT_CONNECTED) {
            /* the packet's points wait for the next poll */
            TEST_ASSERT_TRUE(rsm_ldlidar_next_deadline_us(&drv) == fl.now_us);
        } else if (t == RSM_LDLIDAR_EVENT_POINTS) {
            points += (unsigned)ev.count;
        } else if (t == RSM_LDLIDAR_EVENT_NONE) {
            due = rsm_ldlidar_next_deadline_us(&drv);
            TEST_ASSERT_TRUE(due == drv.last_packet_us + cfg.stream_timeout_us);
            /* the wait: until the next packet is sent, or the deadline */
            rsm_fakelink_advance(&fl, (next_send_us < due ? next_send_us + 300u : due) - fl.now_us);
        }
    }
    TEST_ASSERT_EQUAL_UINT32(0, drv.stats.link_lost);
    sending = 0;
    (void)step(&ev);
    (void)step(&ev);
    due = rsm_ldlidar_next_deadline_us(&drv);
    rsm_fakelink_advance(&fl, due - fl.now_us - 1u);
    TEST_ASSERT_EQUAL_INT(RSM_LDLIDAR_EVENT_NONE, step(&ev)); /* not yet */
    rsm_fakelink_advance(&fl, 1u);
    TEST_ASSERT_EQUAL_INT(RSM_LDLIDAR_EVENT_LINK_LOST, step(&ev));
    TEST_ASSERT_TRUE(ev.stamp_us == due);
}

void test_init_refuses_a_caller_built_with_other_capacities(void)
{
    /* What rsm_ldlidar_init passes for an application compiled with other
     * capacities (RSM_LINK_RX_CHUNK sizes the driver): refused, and not one
     * byte written. */
    static rsm_ldlidar_t d;
    static rsm_ldlidar_t before;
    memset(&d, 0x5A, sizeof d);
    memcpy(&before, &d, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_ldlidar_init_checked(&d, sizeof d - 8u,
                                                                   (unsigned long)RSM_CONFIG_FINGERPRINT, &link, &clk,
                                                                   &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_ldlidar_init_checked(&d, sizeof d,
                                                                   (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul, &link,
                                                                   &clk, &cfg));
    TEST_ASSERT_EQUAL_MEMORY(&before, &d, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ldlidar_init(&d, &link, &clk, &cfg));
}

/* Every call on d refused (RSM_ERR_INVAL; no deadline) and d untouched. */
static void assert_refused(rsm_ldlidar_t *d)
{
    static rsm_ldlidar_t before;
    rsm_ldlidar_event_t ev;
    if (d != NULL) {
        memcpy(&before, d, sizeof before);
    }
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ldlidar_connect(d));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ldlidar_poll(d, &ev));
    TEST_ASSERT_TRUE(rsm_ldlidar_next_deadline_us(d) == UINT64_MAX);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ldlidar_disconnect(d));
    if (d != NULL) {
        TEST_ASSERT_EQUAL_MEMORY(&before, d, sizeof before);
    }
}

void test_a_driver_never_initialised_is_refused(void)
{
    /* Zeroed (connect read through its NULL config and crashed), stale
     * memory, NULL, and what a failed init left. */
    static rsm_ldlidar_t d;
    memset(&d, 0, sizeof d);
    assert_refused(&d);
    memset(&d, 0x5A, sizeof d);
    assert_refused(&d);
    assert_refused(NULL);
    memset(&d, 0, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_ldlidar_init(&d, NULL, &clk, &cfg));
    assert_refused(&d);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_connect_sets_the_rate_and_the_first_packet_connects);
    RUN_TEST(test_points_are_stamped_back_from_the_packet_arrival_by_the_angle_step);
    RUN_TEST(test_packets_bunched_in_one_read_keep_their_stamps_in_order);
    RUN_TEST(test_silence_is_a_link_loss_and_the_next_packet_reconnects);
    RUN_TEST(test_a_corrupted_packet_is_counted_and_lost_alone);
    RUN_TEST(test_disconnected_driver_reads_nothing_into_events);
    RUN_TEST(test_points_through_the_assembler_make_whole_turns_on_the_walls);
    RUN_TEST(test_stamp_and_init_reject_bad_arguments);
    RUN_TEST(test_init_refuses_a_caller_built_with_other_capacities);
    RUN_TEST(test_a_driver_never_initialised_is_refused);
    RUN_TEST(test_next_deadline_serves_a_caller_that_never_blocks);
    return UNITY_END();
}
