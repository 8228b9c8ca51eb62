/* Tests of the P3-DX driver (src/drivers/p3dx.c) against a scripted fake robot on
 * the in-memory fakelink. */
#include <string.h>

#include "fakelink.h"
#include "rsm/aria.h"
#include "rsm/p3dx.h"
#include "rsm/status.h"
#include "unity.h"

/* ---- the fake robot ----------------------------------------------------------- */

typedef struct fake_robot {
    rsm_aria_parser_t parser;
    int sync_stage;      /* next SYNC expected: 0, 1, 2; 3 = synced (cmd 1 is OPEN) */
    int connected;       /* session open: SIPs and (if asked) encoder packets flow */
    int encoder_on;
    int enabled;
    int send_config;     /* answer CONFIG */
    int wrong_sync1;     /* answer the next SYNC1 with ID 0 */
    uint8_t auto_baud;   /* AutoBaud byte of the CONFIGpac */
    int ignore_hostbaud; /* accept HOSTBAUD but stay at the old rate */
    uint32_t hostbauds;  /* HOSTBAUD commands seen */
    uint32_t reply_delay_us;
    uint64_t next_sip_us;
    int32_t left;
    int32_t right;
    int32_t step_left;   /* encoder increment per SIP cycle */
    int32_t step_right;
    uint32_t opens;
    uint32_t closes;
    uint32_t configs;
    uint32_t pulses_while_connected;
} fake_robot_t;

static rsm_fakelink_t fl;
static rsm_link_t link;
static rsm_clock_t clk;
static fake_robot_t robot;
static rsm_p3dx_config_t cfg;
static rsm_p3dx_t drv;

#define T0_US 1000000u
#define SIP_CYCLE_US 100000u

static void robot_send(uint8_t id, const uint8_t *payload, size_t len)
{
    uint8_t buf[RSM_ARIA_MAX_PACKET];
    int n = rsm_aria_encode_raw(id, payload, len, buf, sizeof buf);
    TEST_ASSERT_GREATER_THAN_INT(0, n);
    rsm_fakelink_send(&fl, buf, (size_t)n, robot.reply_delay_us);
}

static size_t put_u16(uint8_t *p, size_t at, uint16_t v)
{
    p[at] = (uint8_t)(v & 0xFFu);
    p[at + 1u] = (uint8_t)(v >> 8);
    return at + 2u;
}

static size_t put_str(uint8_t *p, size_t at, const char *s)
{
    size_t n = strlen(s) + 1u;
    memcpy(p + at, s, n);
    return at + n;
}

/* A CONFIGpac with TicksMM 132, RevCount 32550, Watchdog 1500. */
static void robot_send_config(void)
{
    uint8_t p[200];
    size_t at = 0u;
    int i;
    memset(p, 0, sizeof p);
    at = put_str(p, at, "Pioneer");
    at = put_str(p, at, "p3dx-sh");
    at = put_str(p, at, "SN42");
    p[at++] = 0u;                                /* four_mot */
    for (i = 0; i < 5; i++) {
        at = put_u16(p, at, 300u);               /* tops, pwm */
    }
    at = put_str(p, at, "fakebot");
    p[at++] = 100u;                              /* sip cycle */
    p[at++] = 0u;                                /* host baud */
    p[at++] = 0u;                                /* aux1 baud */
    at = put_u16(p, at, 0u);                     /* gripper */
    at = put_u16(p, at, 1u);                     /* front sonar */
    p[at++] = 0u;                                /* rear sonar */
    at = put_u16(p, at, 110u);                   /* low battery */
    at = put_u16(p, at, 32550u);                 /* RevCount */
    at = put_u16(p, at, 1500u);                  /* Watchdog */
    p[at++] = 0u;                                /* normal mpacs */
    for (i = 0; i < 16; i++) {
        at = put_u16(p, at, 7u);                 /* stall .. trans_ki */
    }
    for (i = 0; i < 4; i++) {
        p[at++] = 0u;                            /* bumps, charger, sonar cycle */
    }
    p[at++] = robot.auto_baud;                   /* AutoBaud */
    p[at++] = 0u;                                /* has_gyro */
    at = put_u16(p, at, 0u);                     /* drift factor */
    p[at++] = 0u;                                /* aux2 */
    p[at++] = 0u;                                /* aux3 */
    at = put_u16(p, at, 132u);                   /* TicksMM */
    robot_send(RSM_ARIA_PAC_CONFIG, p, at);
}

static void robot_send_sip_and_encoder(void)
{
    uint8_t sip[34];
    uint8_t enc[8];
    uint32_t l;
    uint32_t r;
    memset(sip, 0, sizeof sip);
    sip[10] = 120u; /* battery */
    robot_send(RSM_ARIA_PAC_SIP_STOPPED, sip, sizeof sip);
    if (robot.encoder_on) {
        robot.left = (int32_t)((uint32_t)robot.left + (uint32_t)robot.step_left);
        robot.right = (int32_t)((uint32_t)robot.right + (uint32_t)robot.step_right);
        l = (uint32_t)robot.left;
        r = (uint32_t)robot.right;
        enc[0] = (uint8_t)l;
        enc[1] = (uint8_t)(l >> 8);
        enc[2] = (uint8_t)(l >> 16);
        enc[3] = (uint8_t)(l >> 24);
        enc[4] = (uint8_t)r;
        enc[5] = (uint8_t)(r >> 8);
        enc[6] = (uint8_t)(r >> 16);
        enc[7] = (uint8_t)(r >> 24);
        robot_send(RSM_ARIA_PAC_ENCODER, enc, sizeof enc);
    }
}

static int32_t int_arg(const rsm_aria_packet_t *pkt)
{
    const uint8_t *p = rsm_aria_payload(pkt);
    int32_t v;
    if (pkt->payload_len < 3u) {
        return 0;
    }
    v = (int32_t)p[1] | ((int32_t)p[2] << 8);
    return p[0] == RSM_ARIA_ARGTYPE_NINT ? -v : v;
}

static void robot_handle(const rsm_aria_packet_t *pkt)
{
    static const uint8_t sync2[] = "fakebot\0Pioneer\0p3dx-sh";
    const uint8_t cmd = pkt->id;
    if (robot.sync_stage < 3 && !robot.connected && cmd <= 2u) {
        if ((int)cmd != robot.sync_stage) {
            robot.sync_stage = 0;
            return;
        }
        if (cmd == 1u && robot.wrong_sync1) {
            robot.wrong_sync1 = 0;
            robot.sync_stage = 0;
            robot_send(0u, NULL, 0u);
            return;
        }
        if (cmd == 2u) {
            robot_send(2u, sync2, sizeof sync2);
        } else {
            robot_send(cmd, NULL, 0u);
        }
        robot.sync_stage++;
        return;
    }
    switch (cmd) {
    case RSM_ARIA_CMD_OPEN:
        if (robot.sync_stage == 3 && !robot.connected) {
            robot.connected = 1;
            robot.opens++;
            robot.next_sip_us = fl.now_us + SIP_CYCLE_US;
        }
        break;
    case RSM_ARIA_CMD_CLOSE:
        if (robot.connected) {
            robot.closes++;
        }
        robot.connected = 0;
        robot.encoder_on = 0;
        robot.sync_stage = 0;
        break;
    case RSM_ARIA_CMD_CONFIG:
        robot.configs++;
        if (robot.connected && robot.send_config) {
            robot_send_config();
        }
        break;
    case RSM_ARIA_CMD_ENCODER:
        robot.encoder_on = int_arg(pkt) > 0;
        break;
    case RSM_ARIA_CMD_ENABLE:
        robot.enabled = int_arg(pkt);
        break;
    case RSM_ARIA_CMD_PULSE:
        if (robot.connected) {
            robot.pulses_while_connected++;
        }
        break;
    case RSM_ARIA_CMD_HOSTBAUD: {
        /* Codes 0..4 = 9600, 19200, 38400, 57600, 115200; the robot moves
         * once the command is in. */
        static const uint32_t rates[5] = {9600u, 19200u, 38400u, 57600u, 115200u};
        const int32_t code = int_arg(pkt);
        robot.hostbauds++;
        if (!robot.ignore_hostbaud && code >= 0 && code < 5) {
            rsm_fakelink_set_peer_baud(&fl, rates[code]);
        }
        break;
    }
    default:
        break;
    }
}

static void robot_peer(rsm_fakelink_t *f, const uint8_t *data, size_t len, void *user)
{
    rsm_aria_packet_t pkt;
    size_t off = 0u;
    (void)f;
    (void)user;
    for (;;) {
        size_t used = 0u;
        int r = rsm_aria_parser_feed(&robot.parser, data + off, len - off, &used, &pkt);
        off += used;
        if (r != 1) {
            break;
        }
        robot_handle(&pkt);
    }
}

/* The robot's SIP clock. */
static void robot_tick(void)
{
    while (robot.connected && fl.now_us >= robot.next_sip_us) {
        robot_send_sip_and_encoder();
        robot.next_sip_us += SIP_CYCLE_US;
    }
}

/* One poll with the robot's clock run first; checks the no-blocking rule. */
static rsm_p3dx_event_type_t step(rsm_p3dx_event_t *ev)
{
    const uint64_t before = fl.now_us;
    robot_tick();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_poll(&drv, ev));
    TEST_ASSERT_LESS_OR_EQUAL_UINT64((uint64_t)cfg.read_timeout_us, fl.now_us - before);
    return ev->type;
}

/* Polls until an event of the given type or until max_us of fake time. */
static int run_until(rsm_p3dx_event_type_t want, uint64_t max_us, rsm_p3dx_event_t *ev)
{
    const uint64_t end = fl.now_us + max_us;
    while (fl.now_us < end) {
        if (step(ev) == want) {
            return 1;
        }
    }
    return 0;
}

static void run_for(uint64_t us)
{
    rsm_p3dx_event_t ev;
    const uint64_t end = fl.now_us + us;
    while (fl.now_us < end) {
        (void)step(&ev);
    }
}

static void connect_ok(void)
{
    rsm_p3dx_event_t ev;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_P3DX_CONNECTED, drv.state);
}

/* The bytes a connect sends up to its CONFIG request: SYNC0, SYNC1, SYNC2,
 * OPEN 1, CONFIG 1. Returns how many were written to out. */
static size_t expect_session_start(uint8_t *out, size_t cap)
{
    static int (*const steps[5])(uint8_t *, size_t) = {
        rsm_aria_encode_sync0, rsm_aria_encode_sync1, rsm_aria_encode_sync2,
        rsm_aria_encode_open_int1, rsm_aria_encode_config};
    size_t n = 0u;
    size_t i;
    for (i = 0u; i < 5u; i++) {
        const int k = steps[i](out + n, cap - n);
        TEST_ASSERT_GREATER_THAN_INT(0, k);
        n += (size_t)k;
    }
    return n;
}

void setUp(void)
{
    rsm_fakelink_init(&fl, T0_US, &link, &clk);
    memset(&robot, 0, sizeof robot);
    (void)rsm_aria_parser_init(&robot.parser);
    robot.send_config = 1;
    robot.reply_delay_us = 3000u;
    robot.step_left = 100;
    robot.step_right = 110;
    rsm_fakelink_set_peer(&fl, robot_peer, NULL);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_config_default(&cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_init(&drv, &link, &clk, &cfg));
}

void tearDown(void)
{
}

/* ---- tests ---------------------------------------------------------------------- */

void test_p3dx_init_should_reject_bad_arguments(void)
{
    rsm_p3dx_config_t bad = cfg;
    rsm_link_t nolink = link;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_init(NULL, &link, &clk, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_init(&drv, NULL, &clk, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_init(&drv, &link, NULL, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_init(&drv, &link, &clk, NULL));
    bad.read_timeout_us = 0u; /* a poll that never waits: the caller waits for all links */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_init(&drv, &link, &clk, &bad));
    bad = cfg;
    bad.sync_tries = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_init(&drv, &link, &clk, &bad));
    nolink.read = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_init(&drv, &nolink, &clk, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_config_default(NULL));
}

void test_p3dx_init_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* What rsm_p3dx_init passes for an application compiled with other
     * capacities (a driver of another size, or the same size by chance):
     * refused, and not one byte written. */
    static rsm_p3dx_t d;
    static rsm_p3dx_t before;
    memset(&d, 0x5A, sizeof d);
    memcpy(&before, &d, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_p3dx_init_checked(&d, sizeof d - 8u,
                                                                (unsigned long)RSM_CONFIG_FINGERPRINT, &link, &clk,
                                                                &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_p3dx_init_checked(&d, sizeof d,
                                                                (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul, &link,
                                                                &clk, &cfg));
    TEST_ASSERT_EQUAL_MEMORY(&before, &d, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_init(&d, &link, &clk, &cfg));
}

/* Every call on d refused (RSM_ERR_INVAL; no deadline), d untouched and
 * nothing sent. */
static void assert_p3dx_refused(rsm_p3dx_t *d)
{
    static rsm_p3dx_t before;
    rsm_odometry_config_t odo = rsm_odometry_config_default();
    const rsm_odometry_config_t odo_before = odo;
    rsm_p3dx_event_t ev;
    const size_t sent = fl.host_log_len;
    if (d != NULL) {
        memcpy(&before, d, sizeof before);
    }
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_connect(d));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_listen(d));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_poll(d, &ev));
    TEST_ASSERT_TRUE(rsm_p3dx_next_deadline_us(d) == UINT64_MAX);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_odometry_config(d, &odo));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_set_vel(d, 100, 0));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_set_vel2(d, 1, 1));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_stop(d));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_disconnect(d));
    TEST_ASSERT_EQUAL_MEMORY(&odo_before, &odo, sizeof odo);
    TEST_ASSERT_EQUAL_size_t(sent, fl.host_log_len);
    if (d != NULL) {
        TEST_ASSERT_EQUAL_MEMORY(&before, d, sizeof before);
    }
}

void test_p3dx_should_refuse_a_driver_never_initialised(void)
{
    /* Zeroed (connect, poll and the deadline read through its NULL config
     * and crashed), stale memory, and NULL. */
    static rsm_p3dx_t d;
    memset(&d, 0, sizeof d);
    assert_p3dx_refused(&d);
    memset(&d, 0x5A, sizeof d);
    assert_p3dx_refused(&d);
    assert_p3dx_refused(NULL);
    /* A failed init leaves it refused. */
    memset(&d, 0, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_init(&d, NULL, &clk, &cfg));
    assert_p3dx_refused(&d);
}

void test_p3dx_connect_should_put_the_link_at_the_configured_rate(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_set_baud(&link, 38400u)); /* a previous session's HOSTBAUD */
    fl.set_baud_calls = 0u;
    drv.baud = 38400u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    TEST_ASSERT_EQUAL_UINT32(9600u, fl.host_baud);
    TEST_ASSERT_EQUAL_UINT32(9600u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(1u, fl.set_baud_calls);
}

void test_p3dx_next_deadline_should_follow_the_timers_and_calibration_the_configpac(void)
{
    rsm_odometry_config_t odo = rsm_odometry_config_default();
    rsm_p3dx_event_t ev;
    TEST_ASSERT_TRUE(rsm_p3dx_next_deadline_us(&drv) == UINT64_MAX); /* IDLE: no timer */
    TEST_ASSERT_TRUE(rsm_p3dx_next_deadline_us(NULL) == UINT64_MAX);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    /* SYNC0 sent: its reply is awaited step_timeout_us. */
    TEST_ASSERT_TRUE(rsm_p3dx_next_deadline_us(&drv) == fl.now_us + cfg.step_timeout_us);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 5000000u, &ev));
    /* Connected: the keep-alive is the nearest timer. */
    TEST_ASSERT_TRUE(rsm_p3dx_next_deadline_us(&drv) == drv.last_tx_us + cfg.keepalive_us);
    /* The scripted robot reports TicksMM 132: 132000 ticks per metre, the rest kept. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_odometry_config(&drv, &odo));
    TEST_ASSERT_EQUAL_FLOAT(132000.0f, odo.ticks_per_m_left);
    TEST_ASSERT_EQUAL_FLOAT(132000.0f, odo.ticks_per_m_right);
    TEST_ASSERT_EQUAL_FLOAT(rsm_odometry_config_default().wheel_base_m, odo.wheel_base_m);
    TEST_ASSERT_EQUAL_UINT8(32u, odo.counter_bits);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_odometry_config(&drv, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_odometry_config(NULL, &odo));
}

void test_p3dx_listen_should_give_encoder_events_and_send_nothing(void)
{
    uint8_t pkt[2][16];
    uint8_t payload[8] = {0x10, 0x00, 0x00, 0x00, 0xFF, 0xFF, 0xFF, 0xFF}; /* 16, -1 */
    rsm_p3dx_event_t ev;
    int n0;
    int n1;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_listen(&drv));
    TEST_ASSERT_EQUAL_INT(RSM_P3DX_LISTENING, drv.state);
    TEST_ASSERT_TRUE(rsm_p3dx_next_deadline_us(&drv) == UINT64_MAX); /* no keep-alive, no link loss */
    n0 = rsm_aria_encode_raw(RSM_ARIA_PAC_ENCODER, payload, sizeof payload, pkt[0], sizeof pkt[0]);
    payload[0] = 0x30; /* 48: 32 ticks on */
    payload[4] = 0x01; /* 0xFFFFFF01 */
    n1 = rsm_aria_encode_raw(RSM_ARIA_PAC_ENCODER, payload, sizeof payload, pkt[1], sizeof pkt[1]);
    TEST_ASSERT_GREATER_THAN_INT(0, n0);
    TEST_ASSERT_GREATER_THAN_INT(0, n1);
    rsm_fakelink_inject(&fl, pkt[0], (size_t)n0, 1000u);
    rsm_fakelink_inject(&fl, pkt[1], (size_t)n1, 100000u);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_ENCODER, 500000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(16u, ev.encoder.sample.left);
    TEST_ASSERT_EQUAL_UINT32(0xFFFFFFFFu, ev.encoder.sample.right);
    TEST_ASSERT_EQUAL_UINT8(0u, ev.encoder.has_delta);
    TEST_ASSERT_EQUAL_UINT64(ev.stamp_us, ev.encoder.sample.stamp_us);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_ENCODER, 500000u, &ev));
    TEST_ASSERT_EQUAL_UINT8(1u, ev.encoder.has_delta);
    TEST_ASSERT_EQUAL_INT32(32, ev.encoder.d_left);
    TEST_ASSERT_EQUAL_INT32(-254, ev.encoder.d_right);
    /* Seconds of silence: no keep-alive, no LINK_LOST, nothing written. */
    TEST_ASSERT_EQUAL_INT(0, run_until(RSM_P3DX_EVENT_LINK_LOST, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)fl.n_writes);
    TEST_ASSERT_EQUAL_UINT32(0u, fl.set_baud_calls);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_disconnect(&drv));
    TEST_ASSERT_EQUAL_INT(RSM_P3DX_IDLE, drv.state);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)fl.n_writes);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_listen(NULL));
}

void test_p3dx_connect_should_complete_the_handshake_with_a_scripted_robot(void)
{
    uint8_t expect[64];
    size_t n = 0u;
    int k;

    connect_ok();
    /* SYNC0, SYNC1, SYNC2, OPEN 1, CONFIG 1, ENABLE 1, ENCODER 2, in order. */
    n = expect_session_start(expect, sizeof expect);
    k = rsm_aria_encode_enable(1, expect + n, sizeof expect - n);
    n += (size_t)k;
    k = rsm_aria_encode_encoder(1, expect + n, sizeof expect - n);
    n += (size_t)k;
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n, (uint32_t)fl.host_log_len);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, fl.host_log, n);

    TEST_ASSERT_EQUAL_UINT32(3u, drv.stats.sync_replies);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.config_packets);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.connects);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.reconnects);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.handshake_timeouts);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.handshake_retries);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.config_timeouts);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.parser.stats.checksum_errors);
    TEST_ASSERT_EQUAL_UINT16(132u, drv.ticks_mm);
    TEST_ASSERT_EQUAL_UINT16(32550u, drv.rev_count);
    TEST_ASSERT_EQUAL_UINT16(1500u, drv.watchdog_ms);
    TEST_ASSERT_EQUAL_MEMORY("p3dx-sh", drv.robot.subclass, 8u);
    TEST_ASSERT_EQUAL_MEMORY("Pioneer", drv.robot.robot_class, 8u);
    TEST_ASSERT_EQUAL_INT(1, robot.connected);
    TEST_ASSERT_EQUAL_INT(1, robot.enabled);
    TEST_ASSERT_EQUAL_INT(1, robot.encoder_on);
    TEST_ASSERT_EQUAL_UINT32(1u, fl.set_baud_calls);
}

void test_p3dx_connect_should_keep_config_defaults_when_no_configpac_arrives(void)
{
    rsm_p3dx_event_t ev;
    robot.send_config = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.config_timeouts);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.config_packets);
    TEST_ASSERT_EQUAL_UINT16(128u, drv.ticks_mm);
    TEST_ASSERT_EQUAL_UINT16(2000u, drv.watchdog_ms);
    /* Connected one config timeout after OPEN (+ reply latencies). */
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64(T0_US + cfg.config_timeout_us, ev.stamp_us);
}

void test_p3dx_poll_should_yield_encoder_ticks_including_32_bit_wrap(void)
{
    rsm_p3dx_event_t ev;
    int i;
    robot.left = 0x7FFFFF00;   /* wraps to negative after 3 steps of 100 */
    robot.right = -50;
    robot.step_left = 100;
    robot.step_right = 20;
    connect_ok();

    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_ENCODER, 500000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(0x7FFFFF64u, ev.encoder.sample.left);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)-30, ev.encoder.sample.right);
    TEST_ASSERT_EQUAL_UINT8(0u, ev.encoder.has_delta);
    TEST_ASSERT_EQUAL_UINT64(fl.now_us, ev.encoder.sample.stamp_us);
    for (i = 0; i < 3; i++) {
        TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_ENCODER, 500000u, &ev));
        TEST_ASSERT_EQUAL_UINT8(1u, ev.encoder.has_delta);
        TEST_ASSERT_EQUAL_INT32(100, ev.encoder.d_left);
        TEST_ASSERT_EQUAL_INT32(20, ev.encoder.d_right);
    }
    /* 0x7FFFFF64 + 300 wrapped past INT32_MAX. */
    TEST_ASSERT_EQUAL_UINT32(0x80000090u, ev.encoder.sample.left);
    TEST_ASSERT_EQUAL_UINT32(30u, ev.encoder.sample.right);
    TEST_ASSERT_EQUAL_UINT32(4u, drv.stats.encoder_packets);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT32(4u, drv.stats.sips);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.unknown_packets);
}

void test_p3dx_connect_should_close_a_stale_session_and_retry(void)
{
    rsm_p3dx_event_t ev;
    /* A previous client left the session open: SIPs are flowing. */
    robot.connected = 1;
    robot.sync_stage = 3;
    robot.next_sip_us = fl.now_us + 1000u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.stale_sessions);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.handshake_retries);
    TEST_ASSERT_EQUAL_UINT32(1u, robot.closes);
    TEST_ASSERT_EQUAL_UINT32(1u, robot.opens);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.connects);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.handshake_timeouts);
    TEST_ASSERT_EQUAL_UINT32(1u, (uint32_t)rsm_fakelink_find_write(&fl, 0u,
        (const uint8_t[]){0xFA, 0xFB, 0x06, 0x02, 0x3B, 0x01, 0x00, 0x03, 0x3B}, 9u));
}

void test_p3dx_connect_should_restart_at_sync0_on_a_wrong_reply(void)
{
    rsm_p3dx_event_t ev;
    robot.wrong_sync1 = 1;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.handshake_restarts);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.handshake_retries);
    TEST_ASSERT_EQUAL_UINT32(4u, drv.stats.sync_replies); /* 0, then 0, 1, 2 */
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.connects);
}

void test_p3dx_poll_should_report_link_loss_and_reconnect_when_the_robot_returns(void)
{
    rsm_p3dx_event_t ev;
    uint64_t lost_at;
    connect_ok();
    run_for(300000u);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.link_lost);

    /* The robot resets and the line goes dead. */
    fl.silent = 1;
    robot.connected = 0;
    robot.sync_stage = 0;
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_LINK_LOST, 5000000u, &ev));
    lost_at = ev.stamp_us;
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.link_lost);
    TEST_ASSERT_EQUAL_INT(RSM_P3DX_SYNC, drv.state);
    /* Between 2.0 and 2.1 s after the last SIP (cycle 100 ms). */
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64(drv.last_sip_us + cfg.link_lost_us, lost_at);

    /* One handshake timeout while silent, then the robot is back. */
    run_for(1500000u);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.handshake_timeouts);
    fl.silent = 0;
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 3000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(2u, drv.stats.handshake_timeouts);
    TEST_ASSERT_EQUAL_UINT32(2u, drv.stats.handshake_retries);
    TEST_ASSERT_EQUAL_UINT32(2u, drv.stats.connects);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.reconnects);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.baud_changes);
    TEST_ASSERT_EQUAL_UINT32(cfg.read_timeout_us, fl.max_read_timeout_us);
}

void test_p3dx_poll_should_send_a_pulse_after_500_ms_without_commands(void)
{
    static const uint8_t pulse[] = {0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00};
    size_t mark;
    size_t first;
    long w;
    connect_ok();
    mark = fl.n_writes;
    first = fl.host_log_len;
    run_for(450000u);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.keepalives);
    run_for(100000u);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.keepalives);
    TEST_ASSERT_EQUAL_UINT32(1u, (uint32_t)rsm_fakelink_count_host(&fl, first, pulse, sizeof pulse));
    w = rsm_fakelink_find_write(&fl, mark, pulse, sizeof pulse);
    TEST_ASSERT_GREATER_OR_EQUAL_INT32(0, (int32_t)w);
    TEST_ASSERT_EQUAL_UINT64(fl.writes[mark - 1u].at_us + cfg.keepalive_us, fl.writes[w].at_us);
    TEST_ASSERT_EQUAL_UINT32(1u, robot.pulses_while_connected);
    /* A command resets the keep-alive timer. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_set_vel(&drv, 100, 0));
    run_for(400000u);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.keepalives);
}

static int failing_write(void *ctx, const uint8_t *buf, size_t len)
{
    (void)ctx;
    (void)buf;
    (void)len;
    return RSM_ERR_IO;
}

void test_p3dx_poll_should_keep_the_keepalive_pace_when_writes_fail(void)
{
    rsm_p3dx_event_t ev;
    uint64_t start;
    uint32_t ka;
    uint32_t errors;
    int i;
    connect_ok();
    link.write = failing_write; /* the adapter is gone for writing; SIPs still come */
    start = fl.now_us;
    ka = drv.stats.keepalives;
    errors = drv.stats.write_errors;
    for (i = 0; i < 2000; ++i) {
        robot_tick();
        (void)rsm_p3dx_poll(&drv, &ev);
    }
    /* Every poll waits for something: 2000 polls take well over a second. */
    TEST_ASSERT_GREATER_THAN_UINT64(1000000u, fl.now_us - start);
    TEST_ASSERT_GREATER_THAN_UINT32(ka, drv.stats.keepalives);
    TEST_ASSERT_LESS_OR_EQUAL_UINT32(ka + 1u + (uint32_t)((fl.now_us - start) / cfg.keepalive_us),
                                     drv.stats.keepalives);
    TEST_ASSERT_EQUAL_UINT32(drv.stats.keepalives - ka, drv.stats.write_errors - errors);
}

void test_p3dx_set_vel_should_send_the_same_bytes_as_the_aria_encoder(void)
{
    uint8_t expect[64];
    size_t n = 0u;
    size_t first;
    int k;
    connect_ok();
    first = fl.host_log_len;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_set_vel(&drv, 300, -20));
    run_for(20000u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_set_vel2(&drv, -5, 5));
    run_for(20000u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_stop(&drv));
    run_for(20000u);
    k = rsm_aria_encode_vel(300, expect + n, sizeof expect - n);
    n += (size_t)k;
    k = rsm_aria_encode_rvel(-20, expect + n, sizeof expect - n);
    n += (size_t)k;
    k = rsm_aria_encode_vel2(-5, 5, expect + n, sizeof expect - n);
    n += (size_t)k;
    k = rsm_aria_encode_stop(expect + n, sizeof expect - n);
    n += (size_t)k;
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n, (uint32_t)(fl.host_log_len - first));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, fl.host_log + first, n);
    /* VEL2 -5/+5 is 1B FB 04 (protocols.md 1.5). */
    TEST_ASSERT_EQUAL_HEX8(0x1Bu, fl.host_log[first + 18u + 4u]);
    TEST_ASSERT_EQUAL_HEX8(0xFBu, fl.host_log[first + 18u + 5u]);
    TEST_ASSERT_EQUAL_HEX8(0x04u, fl.host_log[first + 18u + 6u]);
    TEST_ASSERT_EQUAL_UINT32(4u, drv.stats.commands);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_p3dx_set_vel(&drv, 40000, 0));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_p3dx_set_vel2(&drv, 128, 0));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_stop(NULL));
}

void test_p3dx_poll_should_count_garbage_and_bit_flips_and_keep_decoding(void)
{
    static const uint8_t garbage[] = {0x11, 0xFA, 0x22, 0x33, 0xFB, 0x44, 0x55};
    rsm_p3dx_event_t ev;
    uint32_t enc_before;
    uint32_t skipped_before;
    connect_ok();
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_ENCODER, 500000u, &ev));
    enc_before = drv.stats.encoder_packets;
    skipped_before = drv.parser.stats.bytes_skipped;

    /* Garbage between two SIP cycles, then a bit flip in the next SIP's
     * payload (byte 10 of the frame). */
    rsm_fakelink_inject(&fl, garbage, sizeof garbage, 0u);
    fl.flip_index = 10;
    run_for(SIP_CYCLE_US + 20000u);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.parser.stats.checksum_errors);
    /* Garbage (7 bytes) plus the re-examined tail of the corrupted SIP
     * (its 40 bytes minus the rejected first byte) are skipped. */
    TEST_ASSERT_EQUAL_UINT32(skipped_before + (uint32_t)sizeof garbage + 39u,
                             drv.parser.stats.bytes_skipped);
    /* The encoder packet right after the corrupted SIP is still decoded. */
    TEST_ASSERT_EQUAL_UINT32(enc_before + 1u, drv.stats.encoder_packets);
    run_for(3u * SIP_CYCLE_US);
    TEST_ASSERT_EQUAL_UINT32(enc_before + 4u, drv.stats.encoder_packets);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.parser.stats.checksum_errors);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.link_lost);
}

void test_p3dx_connect_should_probe_the_baud_rate(void)
{
    rsm_p3dx_event_t ev;
    rsm_fakelink_set_peer_baud(&fl, 38400u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 10000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(38400u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(38400u, fl.host_baud);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.baud_changes);
    TEST_ASSERT_EQUAL_UINT32(3u, drv.stats.handshake_timeouts);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.connects);
}

void test_p3dx_disconnect_should_stop_disable_the_motors_then_close(void)
{
    static const uint8_t close1[] = {0xFA, 0xFB, 0x06, 0x02, 0x3B, 0x01, 0x00, 0x03, 0x3B};
    uint8_t en0[12];
    uint8_t stop[12];
    rsm_p3dx_event_t ev;
    size_t mark;
    long ws;
    long we;
    long wc;
    int n;
    int ns;
    connect_ok();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_set_vel(&drv, 200, 0));
    run_for(20000u);
    mark = fl.n_writes;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_disconnect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_DISCONNECTED, 1000000u, &ev));
    n = rsm_aria_encode_enable(0, en0, sizeof en0);
    ns = rsm_aria_encode_stop(stop, sizeof stop);
    ws = rsm_fakelink_find_write(&fl, mark, stop, (size_t)ns);
    we = rsm_fakelink_find_write(&fl, mark, en0, (size_t)n);
    wc = rsm_fakelink_find_write(&fl, mark, close1, sizeof close1);
    /* STOP, ENABLE 0, CLOSE: the only writes, in this order. */
    TEST_ASSERT_EQUAL_INT32((int32_t)mark, (int32_t)ws);
    TEST_ASSERT_EQUAL_INT32((int32_t)mark + 1, (int32_t)we);
    TEST_ASSERT_EQUAL_INT32((int32_t)mark + 2, (int32_t)wc);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)mark + 3u, (uint32_t)fl.n_writes);
    TEST_ASSERT_EQUAL_UINT64(fl.writes[we].at_us + cfg.disconnect_wait_us, fl.writes[wc].at_us);
    TEST_ASSERT_EQUAL_INT(RSM_P3DX_IDLE, drv.state);
    TEST_ASSERT_EQUAL_INT(0, robot.connected);
    TEST_ASSERT_EQUAL_INT(0, robot.enabled);
    /* Idle: the commanded motion is not re-sent, nothing else goes out. */
    run_for(2000000u);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)mark + 3u, (uint32_t)fl.n_writes);
}

void test_p3dx_disconnect_should_close_a_session_still_waiting_for_the_configpac(void)
{
    static const uint8_t close1[] = {0xFA, 0xFB, 0x06, 0x02, 0x3B, 0x01, 0x00, 0x03, 0x3B};
    rsm_p3dx_event_t ev;
    robot.send_config = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    while (drv.state != RSM_P3DX_CONFIG_WAIT) {
        (void)step(&ev);
    }
    TEST_ASSERT_EQUAL_INT(1, robot.connected);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_disconnect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_DISCONNECTED, 1000000u, &ev));
    TEST_ASSERT_GREATER_OR_EQUAL_INT32(0, (int32_t)rsm_fakelink_find_write(&fl, 0u, close1,
                                                                          sizeof close1));
    TEST_ASSERT_EQUAL_INT(0, robot.connected);
    TEST_ASSERT_EQUAL_UINT32(1u, robot.closes);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.connects);
}

void test_p3dx_connect_should_switch_the_robot_to_host_baud_when_autobaud_allows(void)
{
    uint8_t expect[80];
    uint8_t hb[12];
    size_t n = 0u;
    long w;
    rsm_p3dx_event_t ev;
    int k;
    cfg.host_baud = 38400u;
    robot.auto_baud = 2u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 5000000u, &ev));
    /* ... CONFIG, then HOSTBAUD 2 (at 9600), PULSE (at 38400), ENABLE 1, ENCODER 2. */
    n = expect_session_start(expect, sizeof expect);
    k = rsm_aria_encode_hostbaud(RSM_ARIA_BAUD_38400, expect + n, sizeof expect - n);
    n += (size_t)k;
    k = rsm_aria_encode_pulse(expect + n, sizeof expect - n);
    n += (size_t)k;
    k = rsm_aria_encode_enable(1, expect + n, sizeof expect - n);
    n += (size_t)k;
    k = rsm_aria_encode_encoder(1, expect + n, sizeof expect - n);
    n += (size_t)k;
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n, (uint32_t)fl.host_log_len);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, fl.host_log, n);
    k = rsm_aria_encode_hostbaud(RSM_ARIA_BAUD_38400, hb, sizeof hb);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(((const uint8_t[]){0xFA, 0xFB, 0x06, 0x32, 0x3B, 0x02, 0x00}),
                                 hb, 7);
    w = rsm_fakelink_find_write(&fl, 0u, hb, (size_t)k);
    TEST_ASSERT_GREATER_OR_EQUAL_INT32(0, (int32_t)w);
    TEST_ASSERT_EQUAL_UINT32(1u, robot.hostbauds);
    TEST_ASSERT_EQUAL_UINT32(38400u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(38400u, fl.host_baud);
    TEST_ASSERT_EQUAL_UINT32(38400u, fl.peer_baud);
    TEST_ASSERT_EQUAL_UINT32(2u, fl.set_baud_calls);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.host_baud_switches);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.host_baud_failures);
    TEST_ASSERT_EQUAL_UINT8(2u, drv.auto_baud);
    /* Confirmed by a SIP at the new rate, within one SIP cycle or so. */
    TEST_ASSERT_LESS_OR_EQUAL_UINT64(fl.writes[w].at_us + 2u * SIP_CYCLE_US, ev.stamp_us);
    /* And packets keep coming at 38400. */
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_ENCODER, 500000u, &ev));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_ENCODER, 500000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(0u, drv.parser.stats.checksum_errors);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.link_lost);
}

void test_p3dx_connect_should_go_back_to_the_old_rate_when_nothing_comes_at_host_baud(void)
{
    uint8_t hb[12];
    long w;
    rsm_p3dx_event_t ev;
    const int k = rsm_aria_encode_hostbaud(RSM_ARIA_BAUD_57600, hb, sizeof hb);
    cfg.host_baud = 57600u;
    robot.auto_baud = 2u;
    robot.ignore_hostbaud = 1;
    connect_ok();
    w = rsm_fakelink_find_write(&fl, 0u, hb, (size_t)k);
    TEST_ASSERT_GREATER_OR_EQUAL_INT32(0, (int32_t)w);
    TEST_ASSERT_EQUAL_UINT32(1u, robot.hostbauds);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.host_baud_failures);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.host_baud_switches);
    TEST_ASSERT_EQUAL_UINT32(9600u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(9600u, fl.host_baud);
    TEST_ASSERT_EQUAL_UINT32(3u, fl.set_baud_calls);
    /* Connected only after the whole check time. */
    TEST_ASSERT_EQUAL_UINT64(fl.writes[w].at_us + cfg.baud_check_us, drv.last_sip_us);
    /* The check sent its keep-alive on time (at the rate it was trying). */
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.keepalives);
    /* Back at 9600 the robot is heard again. */
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_ENCODER, 500000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.link_lost);
}

void test_p3dx_connect_should_not_send_hostbaud_unless_the_robot_reports_autobaud_2(void)
{
    uint8_t hb[12];
    const int k = rsm_aria_encode_hostbaud(RSM_ARIA_BAUD_38400, hb, sizeof hb);
    cfg.host_baud = 38400u;
    robot.auto_baud = 1u;
    connect_ok();
    TEST_ASSERT_EQUAL_INT32(-1, (int32_t)rsm_fakelink_find_write(&fl, 0u, hb, (size_t)k));
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.host_baud_skipped);
    TEST_ASSERT_EQUAL_UINT32(9600u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(1u, fl.set_baud_calls);
    TEST_ASSERT_EQUAL_UINT32(0u, robot.hostbauds);
}

void test_p3dx_init_should_reject_a_host_baud_hostbaud_cannot_select(void)
{
    rsm_p3dx_config_t bad = cfg;
    bad.host_baud = 14400u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_init(&drv, &link, &clk, &bad));
    bad.host_baud = 115200u;
    bad.baud_check_us = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_p3dx_init(&drv, &link, &clk, &bad));
    bad.baud_check_us = 1u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_init(&drv, &link, &clk, &bad));
}

/* Writes at or after write index from whose bytes equal frame, and the
 * largest gap between two of them. */
static size_t count_frame_writes(size_t from, const uint8_t *frame, size_t len, uint64_t *max_gap)
{
    size_t count = 0u;
    long w = (long)from - 1;
    uint64_t last = 0u;
    *max_gap = 0u;
    while ((w = rsm_fakelink_find_write(&fl, (size_t)(w + 1), frame, len)) >= 0) {
        if (count > 0u && fl.writes[w].at_us - last > *max_gap) {
            *max_gap = fl.writes[w].at_us - last;
        }
        last = fl.writes[w].at_us;
        count++;
    }
    return count;
}

void test_p3dx_poll_should_resend_the_velocity_every_500_ms_while_moving(void)
{
    uint8_t vel[12];
    uint8_t rvel[12];
    uint8_t pulse[8];
    size_t mark;
    uint64_t gap;
    uint32_t ka;
    const int nv = rsm_aria_encode_vel(300, vel, sizeof vel);
    const int nr = rsm_aria_encode_rvel(-10, rvel, sizeof rvel);
    const int np = rsm_aria_encode_pulse(pulse, sizeof pulse);
    connect_ok();
    mark = fl.n_writes;
    ka = drv.stats.keepalives;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_set_vel(&drv, 300, -10));
    run_for(1700000u);
    /* Sent at once, then at 0.5, 1.0 and 1.5 s: exactly resend_us apart. */
    TEST_ASSERT_EQUAL_UINT32(4u, (uint32_t)count_frame_writes(mark, vel, (size_t)nv, &gap));
    TEST_ASSERT_EQUAL_UINT64(cfg.resend_us, gap);
    TEST_ASSERT_EQUAL_UINT32(4u, (uint32_t)count_frame_writes(mark, rvel, (size_t)nr, &gap));
    TEST_ASSERT_EQUAL_UINT32(3u, drv.stats.resends);
    /* The re-sends keep the watchdog fed: no PULSE while moving. */
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)count_frame_writes(mark, pulse, (size_t)np, &gap));
    TEST_ASSERT_EQUAL_UINT32(ka, drv.stats.keepalives);
}

void test_p3dx_poll_should_resend_a_stop_once_then_go_back_to_pulses(void)
{
    uint8_t stop[8];
    uint8_t vel2[12];
    uint8_t pulse[8];
    size_t mark;
    long w;
    uint64_t gap;
    const int ns = rsm_aria_encode_stop(stop, sizeof stop);
    const int nv = rsm_aria_encode_vel2(10, 12, vel2, sizeof vel2);
    const int np = rsm_aria_encode_pulse(pulse, sizeof pulse);
    connect_ok();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_set_vel2(&drv, 10, 12));
    run_for(1200000u);
    TEST_ASSERT_EQUAL_UINT32(3u, (uint32_t)count_frame_writes(0u, vel2, (size_t)nv, &gap));
    mark = fl.n_writes;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_stop(&drv));
    run_for(1900000u);
    /* STOP at once and once more 500 ms later; VEL2 no more. */
    TEST_ASSERT_EQUAL_UINT32(2u, (uint32_t)count_frame_writes(mark, stop, (size_t)ns, &gap));
    TEST_ASSERT_EQUAL_UINT64(cfg.resend_us, gap);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)count_frame_writes(mark, vel2, (size_t)nv, &gap));
    /* Then a PULSE every 500 ms. */
    TEST_ASSERT_EQUAL_UINT32(2u, (uint32_t)count_frame_writes(mark, pulse, (size_t)np, &gap));
    w = rsm_fakelink_find_write(&fl, mark, pulse, (size_t)np);
    TEST_ASSERT_EQUAL_UINT64(fl.writes[mark].at_us + 2u * cfg.resend_us, fl.writes[w].at_us);
    TEST_ASSERT_EQUAL_UINT32(3u, drv.stats.resends); /* two VEL2, one STOP */
    /* Zero speeds count as a stop too: sent, re-sent once, then PULSEs. */
    mark = fl.n_writes;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_set_vel(&drv, 0, 0));
    run_for(1900000u);
    TEST_ASSERT_EQUAL_UINT32(4u, drv.stats.resends);
    TEST_ASSERT_EQUAL_UINT32(2u, (uint32_t)count_frame_writes(mark, pulse, (size_t)np, &gap));
}

void test_p3dx_poll_should_forget_the_motion_when_the_link_is_lost(void)
{
    uint8_t vel[12];
    rsm_p3dx_event_t ev;
    size_t mark;
    uint64_t gap;
    const int nv = rsm_aria_encode_vel(250, vel, sizeof vel);
    connect_ok();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_set_vel(&drv, 250, 0));
    run_for(100000u);
    fl.silent = 1;
    robot.connected = 0;
    robot.sync_stage = 0;
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_LINK_LOST, 5000000u, &ev));
    fl.silent = 0;
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 5000000u, &ev));
    mark = fl.n_writes;
    run_for(2000000u);
    /* Never resumed by the driver itself after a reconnect. */
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)count_frame_writes(mark, vel, (size_t)nv, &gap));
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.reconnects);
}

void test_p3dx_session_should_never_leave_the_watchdog_without_a_command(void)
{
    rsm_p3dx_event_t ev;
    uint8_t open1[12];
    const int no = rsm_aria_encode_open_int1(open1, sizeof open1);
    long w;
    size_t i;
    /* No CONFIGpac: the driver waits config_timeout_us (1 s) in CONFIG_WAIT. */
    robot.send_config = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_set_vel(&drv, 100, 0));
    run_for(1300000u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_stop(&drv));
    run_for(3000000u);
    w = rsm_fakelink_find_write(&fl, 0u, open1, (size_t)no);
    TEST_ASSERT_GREATER_OR_EQUAL_INT32(0, (int32_t)w);
    for (i = (size_t)w + 1u; i < fl.n_writes; i++) {
        TEST_ASSERT_LESS_OR_EQUAL_UINT64(cfg.keepalive_us, fl.writes[i].at_us - fl.writes[i - 1u].at_us);
    }
    TEST_ASSERT_LESS_OR_EQUAL_UINT64(cfg.keepalive_us, fl.now_us - fl.writes[fl.n_writes - 1u].at_us);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT32(1u, drv.stats.keepalives);
}

void test_p3dx_poll_should_reconnect_at_the_same_rate_to_a_robot_whose_session_survived(void)
{
    rsm_p3dx_event_t ev;
    connect_ok();
    run_for(300000u);
    /* The cable is out for 4.5 s; the robot keeps its session (and its SIP
     * clock) all along, as a real one does. */
    fl.silent = 1;
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_LINK_LOST, 5000000u, &ev));
    run_for(2500000u);
    TEST_ASSERT_EQUAL_UINT32(2u, drv.stats.handshake_timeouts);
    fl.silent = 0;
    /* SIPs during the handshake: CLOSE the old session, start again, at the
     * rate that just carried a packet. */
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_CONNECTED, 3000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.stale_sessions);
    TEST_ASSERT_EQUAL_UINT32(1u, robot.closes);
    TEST_ASSERT_EQUAL_UINT32(2u, robot.opens);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.baud_changes);
    TEST_ASSERT_EQUAL_UINT32(1u, fl.set_baud_calls);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.reconnects);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_P3DX_EVENT_ENCODER, 500000u, &ev));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_p3dx_init_should_reject_bad_arguments);
    RUN_TEST(test_p3dx_init_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_p3dx_should_refuse_a_driver_never_initialised);
    RUN_TEST(test_p3dx_connect_should_put_the_link_at_the_configured_rate);
    RUN_TEST(test_p3dx_next_deadline_should_follow_the_timers_and_calibration_the_configpac);
    RUN_TEST(test_p3dx_listen_should_give_encoder_events_and_send_nothing);
    RUN_TEST(test_p3dx_connect_should_complete_the_handshake_with_a_scripted_robot);
    RUN_TEST(test_p3dx_connect_should_keep_config_defaults_when_no_configpac_arrives);
    RUN_TEST(test_p3dx_poll_should_yield_encoder_ticks_including_32_bit_wrap);
    RUN_TEST(test_p3dx_connect_should_close_a_stale_session_and_retry);
    RUN_TEST(test_p3dx_connect_should_restart_at_sync0_on_a_wrong_reply);
    RUN_TEST(test_p3dx_poll_should_report_link_loss_and_reconnect_when_the_robot_returns);
    RUN_TEST(test_p3dx_poll_should_send_a_pulse_after_500_ms_without_commands);
    RUN_TEST(test_p3dx_poll_should_keep_the_keepalive_pace_when_writes_fail);
    RUN_TEST(test_p3dx_set_vel_should_send_the_same_bytes_as_the_aria_encoder);
    RUN_TEST(test_p3dx_poll_should_count_garbage_and_bit_flips_and_keep_decoding);
    RUN_TEST(test_p3dx_connect_should_probe_the_baud_rate);
    RUN_TEST(test_p3dx_disconnect_should_stop_disable_the_motors_then_close);
    RUN_TEST(test_p3dx_disconnect_should_close_a_session_still_waiting_for_the_configpac);
    RUN_TEST(test_p3dx_connect_should_switch_the_robot_to_host_baud_when_autobaud_allows);
    RUN_TEST(test_p3dx_connect_should_go_back_to_the_old_rate_when_nothing_comes_at_host_baud);
    RUN_TEST(test_p3dx_connect_should_not_send_hostbaud_unless_the_robot_reports_autobaud_2);
    RUN_TEST(test_p3dx_init_should_reject_a_host_baud_hostbaud_cannot_select);
    RUN_TEST(test_p3dx_poll_should_resend_the_velocity_every_500_ms_while_moving);
    RUN_TEST(test_p3dx_poll_should_resend_a_stop_once_then_go_back_to_pulses);
    RUN_TEST(test_p3dx_poll_should_forget_the_motion_when_the_link_is_lost);
    RUN_TEST(test_p3dx_session_should_never_leave_the_watchdog_without_a_command);
    RUN_TEST(test_p3dx_poll_should_reconnect_at_the_same_rate_to_a_robot_whose_session_survived);
    return UNITY_END();
}
