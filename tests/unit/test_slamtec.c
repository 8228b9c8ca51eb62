/* Tests of the RPLIDAR driver (src/drivers/slamtec.c) against a scripted fake
 * RPLIDAR on the in-memory fakelink: the start-up sequence, standard and
 * dense express streams, motor commands, a unit reporting a health error,
 * unanswered requests, link loss and recovery, and the shutdown. */
#include <string.h>

#include "fakelink.h"
#include "rsm/rplidar.h"
#include "rsm/slamtec.h"
#include "rsm/status.h"
#include "unity.h"

#define T0_US 1000000u
#define NODE_US 500u      /* standard scan: 2000 samples per second */
#define NODE_Q6 58u       /* 0.90625 deg per node: 397 a turn */
#define CAPSULE_US 10000u /* dense: 40 samples per 10 ms */
#define CAPSULE_Q6 1152u  /* 18 deg per capsule: 20 a turn, 5 Hz */

typedef struct fake {
    uint8_t in[64];
    size_t in_len;
    int streaming;          /* 1 nodes, 2 dense capsules */
    int unplugged;          /* hears nothing, sends nothing */
    int answer_samplerate;
    int silent_health;
    uint8_t health[4];      /* status answered to the k-th GET_HEALTH */
    unsigned health_calls;
    unsigned resets;
    unsigned motor_cmds;
    uint16_t motor_value;
    uint32_t angle_q6;
    int first;
    uint64_t next_us;
} fake_t;

static rsm_fakelink_t fl;
static rsm_link_t link;
static rsm_clock_t clk;
static fake_t dev;
static rsm_slamtec_config_t cfg;
static rsm_slamtec_t drv;

static void answer(uint8_t type, uint32_t len, uint8_t mode, const uint8_t *body)
{
    uint8_t b[7 + 32];
    TEST_ASSERT_EQUAL_INT(7, rsm_rplidar_encode_descriptor(b, sizeof b, len, mode, type));
    if (body != NULL) {
        memcpy(b + 7, body, len);
    }
    rsm_fakelink_send(&fl, b, 7u + (body != NULL ? len : 0u), 1000u);
}

static void handle_request(uint8_t cmd, const uint8_t *payload, size_t n)
{
    static const uint8_t info[20] = {0x18, 29, 1, 7, 1, 2, 3, 4, 5, 6, 7, 8,
                                     9, 10, 11, 12, 13, 14, 15, 16};
    static const uint8_t rate[4] = {0xF4, 0x01, 0xFA, 0x00}; /* 500 us, 250 us */
    uint8_t health[3] = {0, 0, 0};
    switch (cmd) {
    case RSM_RPLIDAR_CMD_STOP:
        dev.streaming = 0;
        break;
    case RSM_RPLIDAR_CMD_RESET:
        dev.streaming = 0;
        dev.resets++;
        rsm_fakelink_inject(&fl, (const uint8_t *)"RP LIDAR System.\r\n", 18u, 2000u);
        break;
    case RSM_RPLIDAR_CMD_GET_HEALTH:
        health[0] = dev.health[dev.health_calls < 4u ? dev.health_calls : 3u];
        dev.health_calls++;
        if (!dev.silent_health) {
            answer(RSM_RPLIDAR_ANS_HEALTH, 3u, 0u, health);
        }
        break;
    case RSM_RPLIDAR_CMD_GET_INFO:
        answer(RSM_RPLIDAR_ANS_INFO, 20u, 0u, info);
        break;
    case RSM_RPLIDAR_CMD_GET_SAMPLERATE:
        if (dev.answer_samplerate) {
            answer(RSM_RPLIDAR_ANS_SAMPLERATE, 4u, 0u, rate);
        }
        break;
    case RSM_RPLIDAR_CMD_SCAN:
        answer(RSM_RPLIDAR_ANS_NODE, 5u, 1u, NULL);
        dev.streaming = 1;
        dev.first = 1;
        dev.next_us = fl.now_us + 2000u;
        break;
    case RSM_RPLIDAR_CMD_EXPRESS_SCAN:
        TEST_ASSERT_EQUAL_size_t(5, n);
        answer(RSM_RPLIDAR_ANS_DENSE, 84u, 1u, NULL);
        dev.streaming = 2;
        dev.first = 1;
        dev.next_us = fl.now_us + 2000u;
        break;
    case RSM_RPLIDAR_CMD_MOTOR_PWM:
    case RSM_RPLIDAR_CMD_MOTOR_SPEED:
        TEST_ASSERT_EQUAL_size_t(2, n);
        dev.motor_cmds++;
        dev.motor_value = (uint16_t)(payload[0] | (payload[1] << 8));
        break;
    default:
        TEST_FAIL_MESSAGE("unknown request");
    }
}

/* Frames the host's requests (checksums checked) and answers them. */
static void peer(rsm_fakelink_t *f, const uint8_t *data, size_t len, void *user)
{
    size_t i;
    (void)f;
    (void)user;
    if (dev.unplugged) {
        return;
    }
    for (i = 0; i < len; ++i) {
        size_t need;
        TEST_ASSERT_TRUE(dev.in_len < sizeof dev.in);
        dev.in[dev.in_len++] = data[i];
        TEST_ASSERT_EQUAL_HEX8(0xA5, dev.in[0]);
        if (dev.in_len < 2u) {
            continue;
        }
        if ((dev.in[1] & 0x80u) == 0u) {
            handle_request(dev.in[1], NULL, 0);
            dev.in_len = 0;
            continue;
        }
        if (dev.in_len < 3u) {
            continue;
        }
        need = 4u + dev.in[2];
        if (dev.in_len == need) {
            uint8_t x = 0;
            size_t k;
            for (k = 0; k + 1u < need; ++k) {
                x ^= dev.in[k];
            }
            TEST_ASSERT_EQUAL_HEX8(x, dev.in[need - 1u]);
            handle_request(dev.in[1], dev.in + 3, dev.in[2]);
            dev.in_len = 0;
        }
    }
}

static void send_node(uint32_t delay)
{
    uint8_t b[5];
    const uint16_t a = (uint16_t)((dev.angle_q6 << 1) | 1u);
    const int s = dev.first || dev.angle_q6 < NODE_Q6;
    b[0] = (uint8_t)((47u << 2) | (s ? 1u : 2u));
    b[1] = (uint8_t)(a & 0xFF);
    b[2] = (uint8_t)(a >> 8);
    b[3] = 0x40; /* 2000 mm in 1/4 mm: 8000 = 0x1F40 */
    b[4] = 0x1F;
    rsm_fakelink_send(&fl, b, 5, delay);
    dev.angle_q6 = (dev.angle_q6 + NODE_Q6) % 23040u;
    dev.first = 0;
}

static void send_capsule(uint32_t delay)
{
    uint8_t c[84];
    uint8_t x = 0;
    size_t k;
    const uint16_t w = (uint16_t)(dev.angle_q6 | (dev.first ? 0x8000u : 0u));
    c[2] = (uint8_t)(w & 0xFF);
    c[3] = (uint8_t)(w >> 8);
    for (k = 0; k < 40u; ++k) {
        c[4 + 2 * k] = 0xD0; /* 2000 mm */
        c[5 + 2 * k] = 0x07;
    }
    for (k = 2; k < 84u; ++k) {
        x ^= c[k];
    }
    c[0] = (uint8_t)(0xA0u | (x & 0x0Fu));
    c[1] = (uint8_t)(0x50u | (x >> 4));
    rsm_fakelink_send(&fl, c, sizeof c, delay);
    dev.angle_q6 = (dev.angle_q6 + CAPSULE_Q6) % 23040u;
    dev.first = 0;
}

static rsm_slamtec_event_type_t step(rsm_slamtec_event_t *ev)
{
    const uint32_t period = dev.streaming == 2 ? CAPSULE_US : NODE_US;
    while (dev.streaming && !dev.unplugged && dev.next_us <= fl.now_us + cfg.read_timeout_us) {
        const uint32_t delay = (uint32_t)(dev.next_us > fl.now_us ? dev.next_us - fl.now_us : 0u);
        if (dev.streaming == 2) {
            send_capsule(delay);
        } else {
            send_node(delay);
        }
        dev.next_us += period;
    }
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_poll(&drv, ev));
    return ev->type;
}

static int run_until(rsm_slamtec_event_type_t want, uint64_t max_us, rsm_slamtec_event_t *ev)
{
    const uint64_t end = fl.now_us + max_us;
    while (fl.now_us < end) {
        if (step(ev) == want) {
            return 1;
        }
    }
    return 0;
}

/* Index of the first host write at or after from equal to the request
 * cmd (with its payload); fails if there is none. */
static long expect_write(long from, uint8_t cmd, const uint8_t *payload, size_t n)
{
    uint8_t req[16];
    const int len = rsm_rplidar_encode_request(req, sizeof req, cmd, payload, n);
    long w;
    TEST_ASSERT_TRUE(len > 0);
    w = rsm_fakelink_find_write(&fl, (size_t)from, req, (size_t)len);
    TEST_ASSERT_TRUE_MESSAGE(w >= from, "request not written");
    return w;
}

void setUp(void)
{
    rsm_fakelink_init(&fl, T0_US, &link, &clk);
    rsm_fakelink_set_peer_baud(&fl, 115200u);
    memset(&dev, 0, sizeof dev);
    dev.answer_samplerate = 1;
    rsm_fakelink_set_peer(&fl, peer, NULL);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_config_default(&cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_init(&drv, &link, &clk, &cfg));
}

void tearDown(void) {}

void test_startup_asks_health_info_and_rate_then_scans(void)
{
    rsm_slamtec_event_t ev;
    long w;
    unsigned points = 0;
    uint64_t last_stamp = 0;
    float last_angle = -1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_connect(&drv));
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 2000000u, &ev));
    w = expect_write(0, RSM_RPLIDAR_CMD_STOP, NULL, 0);
    w = expect_write(w + 1, RSM_RPLIDAR_CMD_GET_HEALTH, NULL, 0);
    w = expect_write(w + 1, RSM_RPLIDAR_CMD_GET_INFO, NULL, 0);
    w = expect_write(w + 1, RSM_RPLIDAR_CMD_GET_SAMPLERATE, NULL, 0);
    w = expect_write(w + 1, RSM_RPLIDAR_CMD_SCAN, NULL, 0);
    TEST_ASSERT_EQUAL_UINT32(5, drv.stats.requests);
    TEST_ASSERT_EQUAL_UINT(0, dev.resets);
    TEST_ASSERT_EQUAL_HEX8(0x18, drv.info.model);
    TEST_ASSERT_EQUAL_UINT8(16, drv.info.serial[15]);
    TEST_ASSERT_EQUAL_UINT16(500, drv.samplerate.standard_us);
    TEST_ASSERT_EQUAL_UINT32(115200u, fl.host_baud);
    /* 800 nodes (two turns) in batches of at most 40 */
    while (points < 800u && run_until(RSM_SLAMTEC_EVENT_POINTS, 100000u, &ev)) {
        size_t i;
        TEST_ASSERT_TRUE(ev.count >= 1u && ev.count <= RSM_RPLIDAR_MAX_POINTS);
        for (i = 0; i < ev.count; ++i) {
            const rsm_lidar_point_t *p = &ev.points[i];
            TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.0f, p->range_m);
            TEST_ASSERT_EQUAL_UINT8(47, p->quality);
            TEST_ASSERT_TRUE(p->stamp_us >= last_stamp);
            if (last_angle >= 0.0f && p->angle_deg < last_angle) {
                TEST_ASSERT_EQUAL_UINT8(1, p->start); /* the turn's first node */
            } else if (last_angle >= 0.0f) {
                TEST_ASSERT_FLOAT_WITHIN(1e-4f, last_angle + (float)NODE_Q6 / 64.0f, p->angle_deg);
            }
            last_angle = p->angle_deg;
            last_stamp = p->stamp_us;
            points++;
        }
    }
    TEST_ASSERT_TRUE(points >= 800u);
    TEST_ASSERT_EQUAL_UINT32(points, drv.stats.points);
    TEST_ASSERT_EQUAL_UINT32(0, drv.parser.stats.bad_nodes + drv.parser.stats.bytes_skipped);
}

void test_express_scan_with_pwm_motor_gives_dense_capsule_samples(void)
{
    static const uint8_t pwm[2] = {0x58, 0x02}; /* 600 */
    rsm_slamtec_event_t ev;
    long w;
    unsigned events = 0;
    cfg.scan_mode = RSM_SLAMTEC_SCAN_EXPRESS;
    cfg.motor = RSM_SLAMTEC_MOTOR_PWM;
    cfg.motor_value = 600u;
    (void)rsm_slamtec_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 3000000u, &ev));
    w = expect_write(0, RSM_RPLIDAR_CMD_GET_SAMPLERATE, NULL, 0);
    w = expect_write(w + 1, RSM_RPLIDAR_CMD_MOTOR_PWM, pwm, 2);
    TEST_ASSERT_TRUE(expect_write(w + 1, RSM_RPLIDAR_CMD_EXPRESS_SCAN, (const uint8_t *)"\0\0\0\0\0", 5) > w);
    TEST_ASSERT_EQUAL_UINT16(600, dev.motor_value);
    while (events < 10u && run_until(RSM_SLAMTEC_EVENT_POINTS, 100000u, &ev)) {
        size_t k;
        TEST_ASSERT_EQUAL_size_t(40, ev.count);
        for (k = 1; k < 40u; ++k) {
            float d = ev.points[k].angle_deg - ev.points[0].angle_deg;
            if (d < 0.0f) {
                d += 360.0f;
            }
            /* 18 deg over 40 samples */
            TEST_ASSERT_FLOAT_WITHIN(1e-3f, 18.0f * (float)k / 40.0f, d);
            /* 250 us apart (GET_SAMPLERATE said so) */
            TEST_ASSERT_EQUAL_UINT64(ev.points[k - 1u].stamp_us + 250u, ev.points[k].stamp_us);
        }
        events++;
    }
    TEST_ASSERT_EQUAL_UINT(10, events);
}

void test_a_health_error_fails_and_the_next_attempt_resets_the_unit(void)
{
    rsm_slamtec_event_t ev;
    dev.health[0] = RSM_RPLIDAR_HEALTH_ERROR;
    dev.health[1] = RSM_RPLIDAR_HEALTH_WARNING;
    (void)rsm_slamtec_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_ERROR, 1000000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, ev.status);
    TEST_ASSERT_EQUAL_INT(RSM_SLAMTEC_BACKOFF, drv.state);
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 4000000u, &ev));
    TEST_ASSERT_EQUAL_UINT(1, dev.resets);
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.resets);
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.health_errors);
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.health_warnings);
    TEST_ASSERT_EQUAL_UINT8(RSM_RPLIDAR_HEALTH_WARNING, drv.health.status);
    /* the boot text after RESET was dropped, not taken for an answer */
    TEST_ASSERT_EQUAL_UINT32(0, drv.stats.unexpected);
}

void test_unanswered_requests_are_sent_max_tries_times_then_fail(void)
{
    rsm_slamtec_event_t ev;
    uint8_t req[2];
    uint64_t start = fl.now_us;
    dev.silent_health = 1;
    (void)rsm_slamtec_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_ERROR, 3000000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_TIMEOUT, ev.status);
    TEST_ASSERT_EQUAL_INT(2, rsm_rplidar_encode_request(req, sizeof req, RSM_RPLIDAR_CMD_GET_HEALTH, NULL, 0));
    TEST_ASSERT_EQUAL_size_t(cfg.max_tries, rsm_fakelink_count_host(&fl, 0, req, 2));
    TEST_ASSERT_EQUAL_UINT32(cfg.max_tries, drv.stats.timeouts);
    TEST_ASSERT_EQUAL_UINT32(cfg.max_tries - 1u, drv.stats.retries);
    /* STOP's pause, then max_tries answer waits */
    TEST_ASSERT_TRUE(ev.stamp_us >= start + cfg.stop_wait_us + cfg.max_tries * cfg.reply_timeout_us);
    TEST_ASSERT_TRUE(ev.stamp_us <= start + cfg.stop_wait_us + cfg.max_tries * cfg.reply_timeout_us +
                                        4u * cfg.read_timeout_us);
}

void test_old_firmware_without_samplerate_still_connects(void)
{
    rsm_slamtec_event_t ev;
    dev.answer_samplerate = 0;
    (void)rsm_slamtec_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 3000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.no_samplerate);
    TEST_ASSERT_EQUAL_UINT32(0, drv.stats.errors);
    TEST_ASSERT_EQUAL_UINT16(0, drv.samplerate.standard_us);
}

void test_a_silent_stream_is_a_link_loss_and_the_startup_runs_again(void)
{
    rsm_slamtec_event_t ev;
    uint8_t stop[2];
    (void)rsm_slamtec_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 2000000u, &ev));
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_POINTS, 100000u, &ev));
    dev.unplugged = 1;
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_LINK_LOST, 2u * cfg.stream_timeout_us, &ev));
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.link_lost);
    dev.unplugged = 0;
    dev.streaming = 0;
    dev.in_len = 0;
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.reconnects);
    (void)rsm_rplidar_encode_request(stop, sizeof stop, RSM_RPLIDAR_CMD_STOP, NULL, 0);
    TEST_ASSERT_TRUE(rsm_fakelink_count_host(&fl, 0, stop, 2) >= 2u);
}

void test_disconnect_stops_the_scan_and_the_motor(void)
{
    static const uint8_t zero[2] = {0, 0};
    rsm_slamtec_event_t ev;
    long w;
    cfg.motor = RSM_SLAMTEC_MOTOR_RPM;
    cfg.motor_value = 600u;
    (void)rsm_slamtec_connect(&drv);
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 3000000u, &ev));
    w = (long)fl.n_writes;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_disconnect(&drv));
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_DISCONNECTED, 200000u, &ev));
    w = expect_write(w, RSM_RPLIDAR_CMD_STOP, NULL, 0);
    (void)expect_write(w + 1, RSM_RPLIDAR_CMD_MOTOR_SPEED, zero, 2);
    TEST_ASSERT_EQUAL_UINT16(0, dev.motor_value);
    TEST_ASSERT_EQUAL_INT(RSM_SLAMTEC_IDLE, drv.state);
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.disconnects);
    TEST_ASSERT_FALSE(run_until(RSM_SLAMTEC_EVENT_POINTS, 100000u, &ev));
}

void test_init_rejects_bad_settings(void)
{
    rsm_slamtec_config_t bad = cfg;
    bad.max_tries = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_init(&drv, &link, &clk, &bad));
    bad = cfg;
    bad.scan_mode = 2u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_init(&drv, &link, &clk, &bad));
    bad = cfg;
    bad.motor = 3u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_init(&drv, &link, &clk, &bad));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_init(&drv, &link, NULL, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_connect(NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_poll(&drv, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_config_default(NULL));
}

/* Another host runs the sensor: the listener keeps its answers, follows
 * the scan from its descriptor, waits out a silence as a link loss and
 * picks the next scan up, and never writes a byte. */
void test_listen_decodes_a_scan_run_by_another_host_and_sends_nothing(void)
{
    static const uint8_t info[20] = {0x41, 24, 1, 5};
    static const uint8_t rate[4] = {0xF4, 0x01, 0xFA, 0x00};
    static const uint8_t health[3] = {1, 0x34, 0x12};
    rsm_slamtec_event_t ev;
    unsigned points = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_listen(&drv));
    TEST_ASSERT_EQUAL_INT(RSM_SLAMTEC_LISTENING, drv.state);
    answer(RSM_RPLIDAR_ANS_HEALTH, 3u, 0u, health);
    answer(RSM_RPLIDAR_ANS_INFO, 20u, 0u, info);
    answer(RSM_RPLIDAR_ANS_SAMPLERATE, 4u, 0u, rate);
    TEST_ASSERT_FALSE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 200000u, &ev)); /* answers only */
    TEST_ASSERT_EQUAL_HEX8(0x41, drv.info.model);
    TEST_ASSERT_EQUAL_UINT16(0x1234, drv.health.error_code);
    TEST_ASSERT_EQUAL_UINT16(500, drv.samplerate.standard_us);
    answer(RSM_RPLIDAR_ANS_NODE, 5u, 1u, NULL);
    dev.streaming = 1;
    dev.next_us = fl.now_us + 2000u;
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 100000u, &ev));
    while (points < 400u && run_until(RSM_SLAMTEC_EVENT_POINTS, 100000u, &ev)) {
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.0f, ev.points[0].range_m);
        points += (unsigned)ev.count;
    }
    TEST_ASSERT_TRUE(points >= 400u);
    dev.unplugged = 1;
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_LINK_LOST, cfg.stream_timeout_us + 100000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_SLAMTEC_LISTENING, drv.state);
    dev.unplugged = 0;
    dev.streaming = 0;
    answer(RSM_RPLIDAR_ANS_NODE, 5u, 1u, NULL);
    dev.streaming = 1;
    dev.next_us = fl.now_us + 2000u;
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 100000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(2, drv.stats.connects);
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.reconnects);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_disconnect(&drv));
    TEST_ASSERT_EQUAL_INT(RSM_SLAMTEC_IDLE, drv.state);
    TEST_ASSERT_FALSE(run_until(RSM_SLAMTEC_EVENT_POINTS, 100000u, &ev));
    TEST_ASSERT_EQUAL_size_t(0, fl.n_writes);
    TEST_ASSERT_EQUAL_UINT32(0, drv.stats.requests);
    TEST_ASSERT_EQUAL_UINT32(0, drv.stats.disconnects);
}

/* A listener whose stream went silent (a cable, a stalled hub) while the
 * host that runs the sensor never stopped it: no descriptor comes again,
 * and the stream is taken up again from its own bytes, however long the
 * silence (before, the listener awaited a descriptor for ever). */
static void listen_takes_up_a_stream_after_silence(int kind)
{
    rsm_slamtec_event_t ev;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_listen(&drv));
    if (kind == 2) {
        answer(RSM_RPLIDAR_ANS_DENSE, 84u, 1u, NULL);
    } else {
        answer(RSM_RPLIDAR_ANS_NODE, 5u, 1u, NULL);
    }
    dev.streaming = kind;
    dev.next_us = fl.now_us + 2000u;
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 100000u, &ev));
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_POINTS, 100000u, &ev));
    dev.unplugged = 1;
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_LINK_LOST, cfg.stream_timeout_us + 100000u, &ev));
    TEST_ASSERT_FALSE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 20000000u, &ev)); /* 20 s of silence */
    dev.unplugged = 0;
    dev.next_us = fl.now_us + 1234u; /* the stream as it runs: no descriptor */
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_CONNECTED, 1000000u, &ev));
    TEST_ASSERT_TRUE(run_until(RSM_SLAMTEC_EVENT_POINTS, 200000u, &ev));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.0f, ev.points[0].range_m);
    TEST_ASSERT_EQUAL_UINT32(2, drv.stats.connects);
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.reconnects);
    TEST_ASSERT_EQUAL_size_t(0, fl.n_writes);
}

void test_listen_takes_up_a_node_stream_again_after_a_long_silence(void)
{
    listen_takes_up_a_stream_after_silence(1);
}

void test_listen_takes_up_a_capsule_stream_again_after_a_long_silence(void)
{
    listen_takes_up_a_stream_after_silence(2);
}

/* With a zero read timeout the driver never waits inside a poll; a host
 * that sleeps until bytes come or the next deadline runs the whole
 * start-up, the scan, and sees the link loss exactly when due. */
void test_next_deadline_serves_a_caller_that_never_blocks(void)
{
    rsm_slamtec_event_t ev;
    unsigned points = 0;
    uint64_t due;
    TEST_ASSERT_TRUE(rsm_slamtec_next_deadline_us(&drv) == UINT64_MAX); /* IDLE */
    TEST_ASSERT_TRUE(rsm_slamtec_next_deadline_us(NULL) == UINT64_MAX);
    cfg.read_timeout_us = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_init(&drv, &link, &clk, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_connect(&drv));
    /* STOP went out: its pause */
    TEST_ASSERT_TRUE(rsm_slamtec_next_deadline_us(&drv) == fl.now_us + cfg.stop_wait_us);
    while (points < 400u) {
        const uint64_t before = fl.now_us;
        const rsm_slamtec_event_type_t t = step(&ev);
        TEST_ASSERT_TRUE(fl.now_us == before); /* the poll did not wait */
        if (t == RSM_SLAMTEC_EVENT_POINTS) {
            points += (unsigned)ev.count;
        } else if (t == RSM_SLAMTEC_EVENT_NONE) {
            due = rsm_slamtec_next_deadline_us(&drv);
            TEST_ASSERT_TRUE(due > fl.now_us && due != UINT64_MAX);
            if (drv.state == RSM_SLAMTEC_STREAMING) {
                TEST_ASSERT_TRUE(due == drv.last_data_us + cfg.stream_timeout_us);
            }
            /* the wait: bytes come within a millisecond here, or the deadline */
            rsm_fakelink_advance(&fl, due - fl.now_us < 1000u ? due - fl.now_us : 1000u);
        }
        TEST_ASSERT_TRUE(t != RSM_SLAMTEC_EVENT_ERROR && t != RSM_SLAMTEC_EVENT_LINK_LOST);
    }
    TEST_ASSERT_EQUAL_UINT32(1, drv.stats.connects);
    TEST_ASSERT_EQUAL_UINT32(0, drv.stats.retries);
    dev.unplugged = 1;
    (void)step(&ev);
    (void)step(&ev);
    due = rsm_slamtec_next_deadline_us(&drv);
    rsm_fakelink_advance(&fl, due - fl.now_us - 1u);
    TEST_ASSERT_EQUAL_INT(RSM_SLAMTEC_EVENT_NONE, step(&ev)); /* not yet */
    rsm_fakelink_advance(&fl, 1u);
    TEST_ASSERT_EQUAL_INT(RSM_SLAMTEC_EVENT_LINK_LOST, step(&ev));
    TEST_ASSERT_TRUE(ev.stamp_us == due);
    /* listening has no timer at all */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_listen(&drv));
    TEST_ASSERT_TRUE(rsm_slamtec_next_deadline_us(&drv) == UINT64_MAX);
}

void test_init_refuses_a_caller_built_with_other_capacities(void)
{
    /* What rsm_slamtec_init passes for an application compiled with other
     * capacities (RSM_LINK_RX_CHUNK sizes the driver): refused, and not one
     * byte written. */
    static rsm_slamtec_t d;
    static rsm_slamtec_t before;
    memset(&d, 0x5A, sizeof d);
    memcpy(&before, &d, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_slamtec_init_checked(&d, sizeof d - 8u,
                                                                   (unsigned long)RSM_CONFIG_FINGERPRINT, &link, &clk,
                                                                   &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_slamtec_init_checked(&d, sizeof d,
                                                                   (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul, &link,
                                                                   &clk, &cfg));
    TEST_ASSERT_EQUAL_MEMORY(&before, &d, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_init(&d, &link, &clk, &cfg));
}

/* Every call on d refused (RSM_ERR_INVAL; no deadline), d untouched and
 * nothing sent. */
static void assert_refused(rsm_slamtec_t *d)
{
    static rsm_slamtec_t before;
    rsm_slamtec_event_t ev;
    const size_t sent = fl.host_log_len;
    if (d != NULL) {
        memcpy(&before, d, sizeof before);
    }
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_connect(d));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_listen(d));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_poll(d, &ev));
    TEST_ASSERT_TRUE(rsm_slamtec_next_deadline_us(d) == UINT64_MAX);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_disconnect(d));
    TEST_ASSERT_EQUAL_size_t(sent, fl.host_log_len);
    if (d != NULL) {
        TEST_ASSERT_EQUAL_MEMORY(&before, d, sizeof before);
    }
}

void test_a_driver_never_initialised_is_refused(void)
{
    /* Zeroed (connect and listen read through its NULL config and
     * crashed), stale memory, NULL, and what a failed init left. */
    static rsm_slamtec_t d;
    memset(&d, 0, sizeof d);
    assert_refused(&d);
    memset(&d, 0x5A, sizeof d);
    assert_refused(&d);
    assert_refused(NULL);
    memset(&d, 0, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_slamtec_init(&d, &link, NULL, &cfg));
    assert_refused(&d);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_startup_asks_health_info_and_rate_then_scans);
    RUN_TEST(test_express_scan_with_pwm_motor_gives_dense_capsule_samples);
    RUN_TEST(test_a_health_error_fails_and_the_next_attempt_resets_the_unit);
    RUN_TEST(test_unanswered_requests_are_sent_max_tries_times_then_fail);
    RUN_TEST(test_old_firmware_without_samplerate_still_connects);
    RUN_TEST(test_a_silent_stream_is_a_link_loss_and_the_startup_runs_again);
    RUN_TEST(test_disconnect_stops_the_scan_and_the_motor);
    RUN_TEST(test_listen_decodes_a_scan_run_by_another_host_and_sends_nothing);
    RUN_TEST(test_listen_takes_up_a_node_stream_again_after_a_long_silence);
    RUN_TEST(test_listen_takes_up_a_capsule_stream_again_after_a_long_silence);
    RUN_TEST(test_init_rejects_bad_settings);
    RUN_TEST(test_init_refuses_a_caller_built_with_other_capacities);
    RUN_TEST(test_a_driver_never_initialised_is_refused);
    RUN_TEST(test_next_deadline_serves_a_caller_that_never_blocks);
    return UNITY_END();
}
