/* Tests of the SICK LMS driver (src/drivers/sicklms.c) against a scripted fake LMS on
 * the in-memory fakelink. */
#include <string.h>

#include "fakelink.h"
#include "rsm/lms.h"
#include "rsm/scan.h"
#include "rsm/sicklms.h"
#include "rsm/status.h"
#include "unity.h"

/* ---- the fake LMS -------------------------------------------------------------- */

typedef struct fake_lms {
    uint8_t in[64];        /* request bytes being framed */
    size_t in_len;
    int streaming;
    uint16_t angle_deg;
    uint16_t res_cdeg;
    int nak_variant;       /* NAK this many variant requests */
    int ignore_variant;    /* never answer variant requests */
    int drop_baud_reply;   /* ACK a baud change, lose its 0xA0, switch anyway */
    uint8_t config_mode;   /* configuration byte D (measuring mode) */
    uint8_t config_units;  /* configuration byte E */
    int bit13_reading;     /* reading 10 carries bit 13 (a flag or a distance
                              bit, depending on the measuring mode) */
    uint32_t requests;     /* well-formed requests seen */
    uint32_t config_reads; /* 0x74 requests answered */
    uint32_t split_scan_us; /* the second half of each scan arrives this much later */
    uint64_t scan_sent_us;  /* when the last scan was sent */
    uint64_t next_scan_us;
} fake_lms_t;

static rsm_fakelink_t fl;
static rsm_link_t link;
static rsm_clock_t clk;
static fake_lms_t lms;
static rsm_sicklms_config_t cfg;
static rsm_sicklms_t drv;
static rsm_scan_t drv_scan; /* the caller's scan the driver decodes into */

#define T0_US 1000000u
#define SCAN_PERIOD_US 200000u
#define ACK_DELAY_US 5000u
#define REPLY_DELAY_US 10000u

static void lms_reply(uint8_t cmd, const uint8_t *data, size_t len, uint32_t delay_us)
{
    uint8_t buf[RSM_LMS_MAX_TELEGRAM];
    int n = rsm_lms_encode(buf, sizeof buf, 0x80u, cmd, data, len);
    TEST_ASSERT_GREATER_THAN_INT(0, n);
    rsm_fakelink_send(&fl, buf, (size_t)n, delay_us);
}

static void lms_ack(void)
{
    static const uint8_t ack = RSM_LMS_ACK;
    rsm_fakelink_send(&fl, &ack, 1u, ACK_DELAY_US);
}

/* A 181-value 0xB0 in mm: reading i is 500 + 10 i mm, except 3 (no echo,
 * 0x1FFF) and 100 (dazzled, 0x1FFE). */
static void lms_send_scan(void)
{
    uint8_t data[2u + 2u * 181u + 1u];
    size_t i;
    data[0] = 181u & 0xFFu;
    data[1] = (uint8_t)((181u >> 8) | 0x40u); /* units mm */
    for (i = 0u; i < 181u; i++) {
        uint16_t v = (uint16_t)(500u + 10u * i);
        if (i == 3u) {
            v = 0x1FFFu;
        } else if (i == 100u) {
            v = 0x1FFEu;
        } else if (i == 10u && lms.bit13_reading) {
            v = (uint16_t)(v | 0x2000u);
        }
        data[2u + 2u * i] = (uint8_t)(v & 0xFFu);
        data[3u + 2u * i] = (uint8_t)(v >> 8);
    }
    data[sizeof data - 1u] = 0x10u;
    lms.scan_sent_us = fl.now_us;
    if (lms.split_scan_us == 0u) {
        lms_reply(RSM_LMS_REPLY_VALUES, data, sizeof data, 0u);
    } else {
        uint8_t buf[RSM_LMS_MAX_TELEGRAM];
        const int n = rsm_lms_encode(buf, sizeof buf, 0x80u, RSM_LMS_REPLY_VALUES, data, sizeof data);
        TEST_ASSERT_GREATER_THAN_INT(0, n);
        rsm_fakelink_send(&fl, buf, 100u, 0u);
        rsm_fakelink_send(&fl, buf + 100, (size_t)n - 100u, lms.split_scan_us);
    }
}

static void lms_handle(uint8_t cmd, const uint8_t *data, size_t len)
{
    uint8_t r[8];
    lms.requests++;
    if (cmd == RSM_LMS_CMD_MODE && len >= 1u) {
        const uint8_t mode = data[0];
        uint32_t new_baud = 0u;
        if (mode == RSM_LMS_MODE_BAUD_38400) {
            new_baud = 38400u;
        } else if (mode == RSM_LMS_MODE_BAUD_19200) {
            new_baud = 19200u;
        } else if (mode == RSM_LMS_MODE_BAUD_9600) {
            new_baud = 9600u;
        }
        lms_ack();
        if (new_baud != 0u && lms.drop_baud_reply) {
            lms.drop_baud_reply = 0;
        } else {
            r[0] = RSM_LMS_MODE_RESULT_OK;
            r[1] = 0x10u;
            lms_reply(RSM_LMS_REPLY_MODE, r, 2u, REPLY_DELAY_US);
        }
        if (new_baud != 0u) {
            /* The reply went out at the old rate; the LMS switches now. */
            rsm_fakelink_set_peer_baud(&fl, new_baud);
        } else if (mode == RSM_LMS_MODE_CONTINUOUS) {
            lms.streaming = 1;
            lms.next_scan_us = fl.now_us + SCAN_PERIOD_US;
        } else if (mode == RSM_LMS_MODE_ON_REQUEST) {
            lms.streaming = 0;
        }
        return;
    }
    if (cmd == RSM_LMS_CMD_SET_VARIANT && len == 4u) {
        if (lms.ignore_variant) {
            return;
        }
        if (lms.nak_variant > 0) {
            static const uint8_t nak = RSM_LMS_NAK;
            lms.nak_variant--;
            rsm_fakelink_send(&fl, &nak, 1u, ACK_DELAY_US);
            return;
        }
        lms.angle_deg = (uint16_t)(data[0] | (data[1] << 8));
        lms.res_cdeg = (uint16_t)(data[2] | (data[3] << 8));
        lms_ack();
        r[0] = RSM_LMS_RESULT_ACCEPTED;
        memcpy(r + 1, data, 4u);
        r[5] = 0x10u;
        lms_reply(RSM_LMS_REPLY_VARIANT, r, 6u, REPLY_DELAY_US);
        return;
    }
    if (cmd == RSM_LMS_CMD_GET_CONFIG && len == 0u) {
        /* A 32-byte block: blanking 0, thresholds, no indices, then D and E. */
        uint8_t block[RSM_LMS_CONFIG_SHORT + 1u];
        memset(block, 0, sizeof block);
        block[2] = 0x46u;
        block[5] = lms.config_mode;
        block[6] = lms.config_units;
        block[RSM_LMS_CONFIG_SHORT] = 0x10u; /* status */
        lms.config_reads++;
        lms_ack();
        lms_reply(RSM_LMS_REPLY_CONFIG, block, sizeof block, REPLY_DELAY_US);
        return;
    }
    lms_ack();
}

/* Frames host requests (STX 00 LEN CMD data CRC) out of what the LMS hears;
 * anything else (garbled bytes) is dropped. */
static void lms_peer(rsm_fakelink_t *f, const uint8_t *data, size_t len, void *user)
{
    size_t i;
    (void)f;
    (void)user;
    for (i = 0u; i < len; i++) {
        if (lms.in_len < sizeof lms.in) {
            lms.in[lms.in_len++] = data[i];
        }
        for (;;) {
            size_t total;
            if (lms.in_len > 0u && lms.in[0] != RSM_LMS_STX) {
                memmove(lms.in, lms.in + 1, --lms.in_len);
                continue;
            }
            if (lms.in_len >= 2u && lms.in[1] != 0x00u) {
                memmove(lms.in, lms.in + 1, --lms.in_len);
                continue;
            }
            if (lms.in_len < 4u) {
                break;
            }
            total = (size_t)(lms.in[2] | (lms.in[3] << 8)) + 6u;
            if (total > sizeof lms.in) {
                memmove(lms.in, lms.in + 1, --lms.in_len);
                continue;
            }
            if (lms.in_len < total) {
                break;
            }
            if (rsm_lms_crc(lms.in, total - 2u) ==
                (uint16_t)(lms.in[total - 2u] | (lms.in[total - 1u] << 8))) {
                lms_handle(lms.in[4], lms.in + 5, total - 7u);
            }
            memmove(lms.in, lms.in + total, lms.in_len - total);
            lms.in_len -= total;
        }
    }
}

static void lms_tick(void)
{
    while (lms.streaming && fl.now_us >= lms.next_scan_us) {
        lms_send_scan();
        lms.next_scan_us += SCAN_PERIOD_US;
    }
}

/* One poll; checks that it waited no longer than the read timeout. */
static rsm_sicklms_event_type_t step(rsm_sicklms_event_t *ev)
{
    const uint64_t before = fl.now_us;
    lms_tick();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_poll(&drv, ev));
    TEST_ASSERT_LESS_OR_EQUAL_UINT64((uint64_t)cfg.read_timeout_us, fl.now_us - before);
    return ev->type;
}

static int run_until(rsm_sicklms_event_type_t want, uint64_t max_us, rsm_sicklms_event_t *ev)
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
    rsm_sicklms_event_t ev;
    const uint64_t end = fl.now_us + us;
    while (fl.now_us < end) {
        (void)step(&ev);
    }
}

static size_t count_writes(const uint8_t *frame, size_t len)
{
    size_t n = 0u;
    long w = -1;
    while ((w = rsm_fakelink_find_write(&fl, (size_t)(w + 1), frame, len)) >= 0) {
        n++;
    }
    return n;
}

static int frame_mode(uint8_t *out, size_t cap, uint8_t mode)
{
    return rsm_lms_encode_mode(out, cap, 0u, mode);
}

void setUp(void)
{
    rsm_fakelink_init(&fl, T0_US, &link, &clk);
    memset(&lms, 0, sizeof lms);
    lms.config_mode = RSM_LMS_MEAS_8M_FIELDS_AB_DAZZLE;
    lms.config_units = RSM_LMS_UNITS_MM;
    rsm_fakelink_set_peer(&fl, lms_peer, NULL);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_config_default(&cfg));
    cfg.baud = 9600u; /* most tests stay at the power-up rate */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_init(&drv, &link, &clk, &cfg, &drv_scan));
}

void tearDown(void)
{
}

/* ---- tests ----------------------------------------------------------------------- */

void test_sicklms_init_should_reject_bad_arguments(void)
{
    rsm_sicklms_config_t bad = cfg;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_init(NULL, &link, &clk, &cfg, &drv_scan));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_init(&drv, NULL, &clk, &cfg, &drv_scan));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_init(&drv, &link, &clk, NULL, &drv_scan));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_init(&drv, &link, &clk, &cfg, NULL));
    bad.resolution_cdeg = 25u; /* 180 deg at 0.25 deg is not a variant */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_init(&drv, &link, &clk, &bad, &drv_scan));
    bad = cfg;
    bad.address = 0x80u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_init(&drv, &link, &clk, &bad, &drv_scan));
    bad = cfg;
    bad.baud = 57600u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_init(&drv, &link, &clk, &bad, &drv_scan));
    bad = cfg;
    bad.max_tries = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_init(&drv, &link, &clk, &bad, &drv_scan));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_config_default(NULL));
}

void test_sicklms_init_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* What rsm_sicklms_init passes for an application compiled with other
     * capacities (its driver and its scan of another size, or of the same
     * size by chance): refused, and not one byte written. */
    static rsm_sicklms_t d;
    static rsm_sicklms_t before;
    memset(&d, 0x5A, sizeof d);
    memcpy(&before, &d, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_sicklms_init_checked(&d, sizeof d - 8u,
                                                                   (unsigned long)RSM_CONFIG_FINGERPRINT, &link, &clk,
                                                                   &cfg, &drv_scan));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_sicklms_init_checked(&d, sizeof d,
                                                                   (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul,
                                                                   &link, &clk, &cfg, &drv_scan));
    TEST_ASSERT_EQUAL_MEMORY(&before, &d, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_init(&d, &link, &clk, &cfg, &drv_scan));
}

/* Every call on d refused (RSM_ERR_INVAL; no deadline), d untouched and
 * nothing sent. */
static void assert_sicklms_refused(rsm_sicklms_t *d)
{
    static rsm_sicklms_t before;
    rsm_sicklms_event_t ev;
    const size_t sent = fl.host_log_len;
    if (d != NULL) {
        memcpy(&before, d, sizeof before);
    }
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_connect(d));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_listen(d));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_poll(d, &ev));
    TEST_ASSERT_TRUE(rsm_sicklms_next_deadline_us(d) == UINT64_MAX);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_disconnect(d));
    TEST_ASSERT_EQUAL_size_t(sent, fl.host_log_len);
    if (d != NULL) {
        TEST_ASSERT_EQUAL_MEMORY(&before, d, sizeof before);
    }
}

void test_sicklms_should_refuse_a_driver_never_initialised(void)
{
    /* Zeroed (connect and listen read through its NULL config and
     * crashed), stale memory, and NULL. */
    static rsm_sicklms_t d;
    memset(&d, 0, sizeof d);
    assert_sicklms_refused(&d);
    memset(&d, 0x5A, sizeof d);
    assert_sicklms_refused(&d);
    assert_sicklms_refused(NULL);
    /* A failed init leaves it refused. */
    memset(&d, 0, sizeof d);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_init(&d, &link, &clk, &cfg, NULL));
    assert_sicklms_refused(&d);
}

void test_sicklms_connect_should_set_the_variant_and_start_streaming(void)
{
    uint8_t expect[64];
    size_t n = 0u;
    rsm_sicklms_event_t ev;
    int k;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 5000000u, &ev));
    k = frame_mode(expect + n, sizeof expect - n, RSM_LMS_MODE_ON_REQUEST);
    n += (size_t)k;
    k = rsm_lms_encode_variant(expect + n, sizeof expect - n, 0u, 180u, 100u);
    n += (size_t)k;
    k = rsm_lms_encode_request_config(expect + n, sizeof expect - n, 0u);
    n += (size_t)k;
    k = frame_mode(expect + n, sizeof expect - n, RSM_LMS_MODE_CONTINUOUS);
    n += (size_t)k;
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n, (uint32_t)fl.host_log_len);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, fl.host_log, n);
    TEST_ASSERT_EQUAL_INT(RSM_SICKLMS_STREAMING, drv.state);
    TEST_ASSERT_EQUAL_UINT16(180u, lms.angle_deg);
    TEST_ASSERT_EQUAL_UINT16(100u, lms.res_cdeg);
    TEST_ASSERT_EQUAL_UINT32(4u, drv.stats.acks);
    TEST_ASSERT_EQUAL_UINT32(4u, drv.stats.telegrams);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.config_reads);
    TEST_ASSERT_EQUAL_UINT8(1u, drv.have_config);
    TEST_ASSERT_EQUAL_HEX8(0x46u, drv.config.stop_threshold);
    TEST_ASSERT_EQUAL_HEX8(RSM_LMS_UNITS_MM, drv.config.units);
    TEST_ASSERT_EQUAL_UINT8(13u, drv.format.distance_bits);
    TEST_ASSERT_EQUAL_UINT8(0u, drv.format.index_bytes);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.probes);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.retries);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.naks);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.baud_changes);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.connects);
    TEST_ASSERT_EQUAL_UINT32(9600u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(1u, fl.set_baud_calls);
}

void test_sicklms_connect_should_resend_no_sooner_than_30_ms_after_a_nak(void)
{
    uint8_t var[16];
    rsm_sicklms_event_t ev;
    long w1;
    long w2;
    int n = rsm_lms_encode_variant(var, sizeof var, 0u, 180u, 100u);
    lms.nak_variant = 1;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 5000000u, &ev));
    w1 = rsm_fakelink_find_write(&fl, 0u, var, (size_t)n);
    w2 = rsm_fakelink_find_write(&fl, (size_t)(w1 + 1), var, (size_t)n);
    TEST_ASSERT_GREATER_OR_EQUAL_INT32(0, (int32_t)w1);
    TEST_ASSERT_GREATER_THAN_INT32((int32_t)w1, (int32_t)w2);
    /* NAK at +5 ms, re-send 30 ms after it. */
    TEST_ASSERT_EQUAL_UINT64(fl.writes[w1].at_us + ACK_DELAY_US + cfg.nak_wait_us,
                             fl.writes[w2].at_us);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.naks);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.retries);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.errors);
    TEST_ASSERT_EQUAL_UINT32(2u, (uint32_t)count_writes(var, (size_t)n));
}

void test_sicklms_connect_should_retry_an_unacknowledged_request_three_times_then_fail(void)
{
    uint8_t var[16];
    rsm_sicklms_event_t ev;
    int n = rsm_lms_encode_variant(var, sizeof var, 0u, 180u, 100u);
    lms.ignore_variant = 1;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_ERROR, 5000000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_TIMEOUT, ev.status);
    TEST_ASSERT_EQUAL_UINT32(3u, (uint32_t)count_writes(var, (size_t)n));
    TEST_ASSERT_EQUAL_UINT32(3u, drv.stats.ack_timeouts);
    TEST_ASSERT_EQUAL_UINT32(2u, drv.stats.retries);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.errors);
    TEST_ASSERT_EQUAL_INT(RSM_SICKLMS_BACKOFF, drv.state);
    /* After the back-off the start-up begins again with a probe. */
    lms.ignore_variant = 0;
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(2u, drv.stats.probes);
}

void test_sicklms_connect_should_probe_and_find_a_unit_at_38400(void)
{
    rsm_sicklms_event_t ev;
    cfg.baud = 0u; /* stay at whatever rate answers */
    rsm_fakelink_set_peer_baud(&fl, 38400u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(38400u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(38400u, fl.host_baud);
    TEST_ASSERT_EQUAL_UINT32(2u, drv.stats.probes);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.ack_timeouts);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.baud_changes);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.errors);
}

void test_sicklms_connect_should_switch_to_38400_after_the_reply_at_the_old_rate(void)
{
    uint8_t b38[16];
    rsm_sicklms_event_t ev;
    int n = rsm_lms_encode_mode_baud(b38, sizeof b38, 0u, 38400u);
    cfg.baud = 38400u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(38400u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(38400u, fl.host_baud);
    TEST_ASSERT_EQUAL_UINT32(38400u, fl.peer_baud);
    TEST_ASSERT_EQUAL_UINT32(1u, (uint32_t)count_writes(b38, (size_t)n));
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.baud_changes);
    TEST_ASSERT_EQUAL_UINT32(5u, drv.stats.acks);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.retries);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.ack_timeouts);
    TEST_ASSERT_EQUAL_UINT32(180u, lms.angle_deg);
}

void test_sicklms_connect_should_reprobe_instead_of_repeating_a_lost_baud_change(void)
{
    uint8_t b38[16];
    rsm_sicklms_event_t ev;
    int n = rsm_lms_encode_mode_baud(b38, sizeof b38, 0u, 38400u);
    cfg.baud = 38400u;
    lms.drop_baud_reply = 1;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 10000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(1u, (uint32_t)count_writes(b38, (size_t)n));
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.reply_timeouts);
    TEST_ASSERT_EQUAL_UINT32(2u, drv.stats.probes); /* 9600, then 38400 first */
    TEST_ASSERT_EQUAL_UINT32(38400u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.errors);
}

void test_sicklms_poll_should_yield_robot_frame_scans_from_the_b0_stream(void)
{
    rsm_sicklms_event_t ev;
    const float deg = 3.14159265f / 180.0f;
    int i;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 5000000u, &ev));
    for (i = 0; i < 3; i++) {
        TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 1000000u, &ev));
        TEST_ASSERT_EQUAL_PTR(&drv_scan, ev.scan);
        TEST_ASSERT_EQUAL_UINT32(181u, (uint32_t)ev.scan->count);
        TEST_ASSERT_EQUAL_UINT64(fl.now_us, ev.scan->stamp_us);
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, -90.0f * deg, ev.scan->angle_rad[0]);
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.0f, ev.scan->angle_rad[90]);
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, 45.0f * deg, ev.scan->angle_rad[135]);
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, 90.0f * deg, ev.scan->angle_rad[180]);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.500f, ev.scan->range_m[0]);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.510f, ev.scan->range_m[1]);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.300f, ev.scan->range_m[180]);
        TEST_ASSERT_EQUAL_FLOAT(0.0f, ev.scan->range_m[3]);
        TEST_ASSERT_EQUAL_FLOAT(0.0f, ev.scan->range_m[100]);
    }
    TEST_ASSERT_EQUAL_UINT32(3u, drv.stats.scans);
    TEST_ASSERT_EQUAL_UINT32(6u, drv.stats.invalid_readings);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.bad_scans);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.crc_errors);
}

/* A scan of n readings of 1 m at scanner angles start + i * step (1/100 deg). */
static void lms_layout(rsm_lms_scan_t *raw, size_t n, uint16_t start_cdeg, uint16_t step_cdeg)
{
    size_t i;
    memset(raw, 0, sizeof *raw);
    raw->count = n;
    raw->start_cdeg = start_cdeg;
    raw->step_cdeg = step_cdeg;
    for (i = 0; i < n; i++) {
        raw->reading[i].range_m = 1.0f;
        raw->reading[i].code = RSM_LMS_READING_OK;
    }
}

void test_sicklms_to_scan_should_lay_out_bearings_as_a_carmen_scan_bit_for_bit(void)
{
    /* rsm-nav --carmen lays a 180-degree scan of n beams out as
     * rsm_scan_set_uniform(-pi/2, pi/n); the same readings from the LMS must
     * get the very same floats, or the capture path and the direct run of one
     * log see different points. */
    static rsm_lms_scan_t raw;
    static rsm_scan_t got;
    static rsm_scan_t want;
    static const struct { size_t n; uint16_t step; float carmen_n; } cases[] = {{181u, 100u, 180.0f},
                                                                               {361u, 50u, 360.0f}};
    size_t c;
    size_t i;
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        if (cases[c].n > RSM_MAX_BEAMS) {
            continue; /* a small build cannot hold a half-degree scan */
        }
        lms_layout(&raw, cases[c].n, 0u, cases[c].step);
        TEST_ASSERT_EQUAL_INT(0, rsm_sicklms_to_scan(&raw, 0u, &got));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_scan_set_uniform(&want, cases[c].n, -RSM_PI / 2.0f, RSM_PI / cases[c].carmen_n));
        TEST_ASSERT_EQUAL_MEMORY(want.angle_rad, got.angle_rad, cases[c].n * sizeof got.angle_rad[0]);
        /* Upside down: the mirror image, exactly. */
        TEST_ASSERT_EQUAL_INT(0, rsm_sicklms_to_scan(&raw, 1u, &got));
        for (i = 0; i < cases[c].n; i++) {
            TEST_ASSERT_TRUE(-want.angle_rad[i] == got.angle_rad[i]);
        }
    }
    /* The 100-degree variant: 40..140 deg on the scanner, -50..50 in the robot. */
    lms_layout(&raw, 101u, 4000u, 100u);
    TEST_ASSERT_EQUAL_INT(0, rsm_sicklms_to_scan(&raw, 0u, &got));
    for (i = 0; i < 101u; i++) {
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, ((float)i - 50.0f) * (RSM_PI / 180.0f), got.angle_rad[i]);
    }
}

void test_sicklms_to_scan_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* An application compiled with another RSM_MAX_BEAMS has a scan of
     * another size: its bearings would land past it. */
    static rsm_lms_scan_t raw;
    static rsm_scan_t got;
    static rsm_scan_t before;
    lms_layout(&raw, 101u, 4000u, 100u);
    memset(&got, 0x5A, sizeof got);
    memcpy(&before, &got, sizeof got);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_sicklms_to_scan_checked(&raw, 0u, &got, sizeof got - 8u,
                                                                      (unsigned long)RSM_CONFIG_FINGERPRINT));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_sicklms_to_scan_checked(&raw, 0u, &got, sizeof got,
                                                                      (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul));
    TEST_ASSERT_EQUAL_MEMORY(&before, &got, sizeof got);
    TEST_ASSERT_EQUAL_INT(0, rsm_sicklms_to_scan(&raw, 0u, &got));
    TEST_ASSERT_EQUAL_size_t(101u, got.count);
}

void test_sicklms_poll_should_count_a_corrupted_telegram_and_keep_streaming(void)
{
    rsm_sicklms_event_t ev;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 5000000u, &ev));
    fl.flip_index = 100; /* a data byte of the next scan */
    run_for(SCAN_PERIOD_US + 50000u);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.crc_errors);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.scans);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 1000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.scans);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.crc_errors);
}

void test_sicklms_poll_should_report_link_loss_and_reconnect(void)
{
    rsm_sicklms_event_t ev;
    uint64_t last_scan;
    cfg.baud = 38400u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 1000000u, &ev));
    last_scan = ev.stamp_us;

    /* The unit loses power: silence, then it is back at its power-up rate. */
    fl.silent = 1;
    lms.streaming = 0;
    rsm_fakelink_set_peer_baud(&fl, 9600u);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_LINK_LOST, 3000000u, &ev));
    TEST_ASSERT_EQUAL_UINT64(last_scan + cfg.stream_timeout_us, ev.stamp_us);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.link_lost);
    fl.silent = 0;
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 10000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(2u, drv.stats.connects);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.reconnects);
    TEST_ASSERT_EQUAL_UINT32(38400u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(38400u, fl.peer_baud);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 1000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(cfg.read_timeout_us, fl.max_read_timeout_us);
    TEST_ASSERT_LESS_OR_EQUAL_UINT64((uint64_t)cfg.read_timeout_us, fl.max_read_wait_us);
}

void test_sicklms_connect_should_decode_scans_with_the_measuring_mode_read_from_the_unit(void)
{
    rsm_sicklms_event_t ev;
    /* 16 m mode: bit 13 is a distance bit, so reading 10 is 0x2000 + 600 mm. */
    lms.config_mode = RSM_LMS_MEAS_16M_REFLECTOR;
    lms.bit13_reading = 1;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_CONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_MEAS_16M_REFLECTOR, drv.config.measuring_mode);
    TEST_ASSERT_EQUAL_UINT8(14u, drv.format.distance_bits);
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_UNITS_AUTO, drv.format.units);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 1000000u, &ev));
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 8.792f, ev.scan->range_m[10]);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.610f, ev.scan->range_m[11]);
    /* 0x1FFF is an ordinary distance in 14-bit modes (8.191 m). */
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 8.191f, ev.scan->range_m[3]);
    TEST_ASSERT_EQUAL_UINT32(1u, lms.config_reads);
}

void test_sicklms_connect_should_keep_the_flag_bits_in_the_default_measuring_mode(void)
{
    rsm_sicklms_event_t ev;
    lms.bit13_reading = 1;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT8(13u, drv.format.distance_bits);
    /* Bit 13 is a flag, not distance: the range is the 13 bits below it. */
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.600f, ev.scan->range_m[10]);
}

void test_sicklms_connect_should_refuse_a_unit_that_measures_reflectivity(void)
{
    uint8_t stream[16];
    rsm_sicklms_event_t ev;
    const int n = frame_mode(stream, sizeof stream, RSM_LMS_MODE_CONTINUOUS);
    lms.config_mode = RSM_LMS_MEAS_REFLECTIVITY;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_ERROR, 5000000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, ev.status);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.config_reads);
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_MEAS_REFLECTIVITY, drv.config.measuring_mode);
    TEST_ASSERT_EQUAL_INT(RSM_SICKLMS_BACKOFF, drv.state);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)count_writes(stream, (size_t)n));
    TEST_ASSERT_EQUAL_INT(0, lms.streaming);
}

void test_sicklms_connect_should_not_read_the_configuration_when_told_not_to(void)
{
    uint8_t req[16];
    rsm_sicklms_event_t ev;
    const int n = rsm_lms_encode_request_config(req, sizeof req, 0u);
    cfg.read_config = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)count_writes(req, (size_t)n));
    TEST_ASSERT_EQUAL_UINT8(0u, drv.have_config);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.config_reads);
}

/* Connects with working rate baud and waits for the first scan. */
static void streaming_at(uint32_t baud)
{
    rsm_sicklms_event_t ev;
    cfg.baud = baud;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(baud, drv.baud);
}

void test_sicklms_disconnect_should_stop_the_stream_then_return_to_the_power_up_rate(void)
{
    uint8_t stop[16];
    uint8_t b9600[16];
    rsm_sicklms_event_t ev;
    size_t mark;
    long ws;
    long wb;
    uint32_t scans;
    const int ns = frame_mode(stop, sizeof stop, RSM_LMS_MODE_ON_REQUEST);
    const int nb = rsm_lms_encode_mode_baud(b9600, sizeof b9600, 0u, 9600u);
    streaming_at(38400u);
    TEST_ASSERT_EQUAL_UINT32(38400u, fl.peer_baud);
    mark = fl.n_writes;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_disconnect(&drv));
    TEST_ASSERT_EQUAL_INT(RSM_SICKLMS_STOPPING, drv.state);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_DISCONNECTED, 10000000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_OK, ev.status);
    /* 20 25 first, then 20 42, each once, and nothing else. */
    ws = rsm_fakelink_find_write(&fl, mark, stop, (size_t)ns);
    wb = rsm_fakelink_find_write(&fl, mark, b9600, (size_t)nb);
    TEST_ASSERT_EQUAL_INT32((int32_t)mark, (int32_t)ws);
    TEST_ASSERT_EQUAL_INT32((int32_t)mark + 1, (int32_t)wb);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)mark + 2u, (uint32_t)fl.n_writes);
    TEST_ASSERT_EQUAL_INT(0, lms.streaming);
    TEST_ASSERT_EQUAL_UINT32(9600u, fl.peer_baud);
    TEST_ASSERT_EQUAL_UINT32(9600u, fl.host_baud);
    TEST_ASSERT_EQUAL_UINT32(9600u, drv.baud);
    TEST_ASSERT_EQUAL_INT(RSM_SICKLMS_IDLE, drv.state);
    TEST_ASSERT_EQUAL_UINT32(1u, drv.stats.disconnects);
    /* Idle: no scans, no requests, no link-loss. */
    scans = drv.stats.scans;
    run_for(3000000u);
    TEST_ASSERT_EQUAL_UINT32(scans, drv.stats.scans);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)mark + 2u, (uint32_t)fl.n_writes);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.link_lost);
    /* Already idle: nothing to do. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_disconnect(&drv));
    TEST_ASSERT_EQUAL_INT(RSM_SICKLMS_IDLE, drv.state);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_disconnect(NULL));
}

void test_sicklms_disconnect_at_the_power_up_rate_should_only_stop_the_stream(void)
{
    uint8_t stop[16];
    rsm_sicklms_event_t ev;
    size_t mark;
    const int ns = frame_mode(stop, sizeof stop, RSM_LMS_MODE_ON_REQUEST);
    streaming_at(9600u);
    mark = fl.n_writes;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_disconnect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_DISCONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_OK, ev.status);
    TEST_ASSERT_EQUAL_INT32((int32_t)mark, (int32_t)rsm_fakelink_find_write(&fl, mark, stop, (size_t)ns));
    TEST_ASSERT_EQUAL_UINT32((uint32_t)mark + 1u, (uint32_t)fl.n_writes);
    TEST_ASSERT_EQUAL_UINT32(1u, fl.set_baud_calls);
    TEST_ASSERT_EQUAL_INT(0, lms.streaming);
}

void test_sicklms_disconnect_should_give_up_on_a_silent_unit_after_max_tries(void)
{
    uint8_t stop[16];
    uint8_t b9600[16];
    rsm_sicklms_event_t ev;
    uint64_t started;
    size_t mark;
    const int ns = frame_mode(stop, sizeof stop, RSM_LMS_MODE_ON_REQUEST);
    const int nb = rsm_lms_encode_mode_baud(b9600, sizeof b9600, 0u, 9600u);
    streaming_at(38400u);
    fl.silent = 1;
    mark = fl.n_writes;
    started = fl.now_us;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_disconnect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_DISCONNECTED, 5000000u, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_TIMEOUT, ev.status);
    /* max_tries sends of 20 25, one ACK timeout each, and no baud change. */
    TEST_ASSERT_EQUAL_UINT32((uint32_t)mark + cfg.max_tries, (uint32_t)fl.n_writes);
    TEST_ASSERT_EQUAL_INT32((int32_t)mark, (int32_t)rsm_fakelink_find_write(&fl, mark, stop, (size_t)ns));
    TEST_ASSERT_EQUAL_INT32(-1, (int32_t)rsm_fakelink_find_write(&fl, mark, b9600, (size_t)nb));
    TEST_ASSERT_EQUAL_UINT64(started + (uint64_t)cfg.max_tries * cfg.ack_timeout_us, ev.stamp_us);
    TEST_ASSERT_EQUAL_INT(RSM_SICKLMS_IDLE, drv.state);
    TEST_ASSERT_EQUAL_UINT32(38400u, drv.baud);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.disconnects);
}

void test_sicklms_poll_should_stamp_a_scan_with_the_arrival_of_its_first_byte(void)
{
    rsm_sicklms_event_t ev;
    lms.split_scan_us = 40000u; /* the rest of the telegram is 40 ms behind */
    cfg.latency_us = 1500u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 5000000u, &ev));
    TEST_ASSERT_EQUAL_UINT64(lms.scan_sent_us + lms.split_scan_us, fl.now_us);
    TEST_ASSERT_EQUAL_UINT64(lms.scan_sent_us - cfg.latency_us, ev.scan->stamp_us);
    TEST_ASSERT_EQUAL_UINT64(ev.scan->stamp_us, ev.stamp_us);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 1000000u, &ev));
    TEST_ASSERT_EQUAL_UINT64(lms.scan_sent_us - cfg.latency_us, ev.scan->stamp_us);
    TEST_ASSERT_EQUAL_UINT32(0u, drv.stats.bad_scans);
}

void test_sicklms_next_deadline_should_follow_the_request_and_stream_timers(void)
{
    rsm_sicklms_event_t ev;
    TEST_ASSERT_TRUE(rsm_sicklms_next_deadline_us(&drv) == UINT64_MAX); /* IDLE */
    TEST_ASSERT_TRUE(rsm_sicklms_next_deadline_us(NULL) == UINT64_MAX);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_connect(&drv));
    /* The first probe is out: its ACK is awaited ack_timeout_us. */
    TEST_ASSERT_TRUE(rsm_sicklms_next_deadline_us(&drv) == fl.now_us + cfg.ack_timeout_us);
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 5000000u, &ev));
    /* Streaming: silence for stream_timeout_us after the last telegram is a link loss. */
    TEST_ASSERT_TRUE(rsm_sicklms_next_deadline_us(&drv) == drv.last_tel_us + cfg.stream_timeout_us);
}

void test_sicklms_listen_should_decode_and_stamp_scans_as_streaming_and_send_nothing(void)
{
    rsm_sicklms_event_t ev;
    lms.split_scan_us = 40000u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_listen(&drv));
    TEST_ASSERT_EQUAL_INT(RSM_SICKLMS_LISTENING, drv.state);
    TEST_ASSERT_TRUE(rsm_sicklms_next_deadline_us(&drv) == UINT64_MAX); /* no timer at all */
    lms_send_scan();
    TEST_ASSERT_EQUAL_INT(1, run_until(RSM_SICKLMS_EVENT_SCAN, 1000000u, &ev));
    /* The same rule as streaming: the arrival of the telegram's first byte. */
    TEST_ASSERT_EQUAL_UINT64(lms.scan_sent_us, ev.scan->stamp_us);
    TEST_ASSERT_EQUAL_UINT32(181u, (uint32_t)ev.scan->count);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.5f, ev.scan->range_m[0]);
    /* Silence is no link loss while listening, and nothing was ever sent. */
    TEST_ASSERT_EQUAL_INT(0, run_until(RSM_SICKLMS_EVENT_LINK_LOST, 3000000u, &ev));
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)fl.n_writes);
    TEST_ASSERT_EQUAL_UINT32(0u, fl.set_baud_calls);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_disconnect(&drv));
    TEST_ASSERT_EQUAL_INT(RSM_SICKLMS_IDLE, drv.state);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)fl.n_writes);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_sicklms_listen(NULL));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_sicklms_init_should_reject_bad_arguments);
    RUN_TEST(test_sicklms_init_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_sicklms_should_refuse_a_driver_never_initialised);
    RUN_TEST(test_sicklms_connect_should_set_the_variant_and_start_streaming);
    RUN_TEST(test_sicklms_connect_should_resend_no_sooner_than_30_ms_after_a_nak);
    RUN_TEST(test_sicklms_connect_should_retry_an_unacknowledged_request_three_times_then_fail);
    RUN_TEST(test_sicklms_connect_should_probe_and_find_a_unit_at_38400);
    RUN_TEST(test_sicklms_connect_should_switch_to_38400_after_the_reply_at_the_old_rate);
    RUN_TEST(test_sicklms_connect_should_reprobe_instead_of_repeating_a_lost_baud_change);
    RUN_TEST(test_sicklms_poll_should_yield_robot_frame_scans_from_the_b0_stream);
    RUN_TEST(test_sicklms_to_scan_should_lay_out_bearings_as_a_carmen_scan_bit_for_bit);
    RUN_TEST(test_sicklms_to_scan_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_sicklms_poll_should_count_a_corrupted_telegram_and_keep_streaming);
    RUN_TEST(test_sicklms_poll_should_report_link_loss_and_reconnect);
    RUN_TEST(test_sicklms_connect_should_decode_scans_with_the_measuring_mode_read_from_the_unit);
    RUN_TEST(test_sicklms_connect_should_keep_the_flag_bits_in_the_default_measuring_mode);
    RUN_TEST(test_sicklms_connect_should_refuse_a_unit_that_measures_reflectivity);
    RUN_TEST(test_sicklms_connect_should_not_read_the_configuration_when_told_not_to);
    RUN_TEST(test_sicklms_disconnect_should_stop_the_stream_then_return_to_the_power_up_rate);
    RUN_TEST(test_sicklms_disconnect_at_the_power_up_rate_should_only_stop_the_stream);
    RUN_TEST(test_sicklms_disconnect_should_give_up_on_a_silent_unit_after_max_tries);
    RUN_TEST(test_sicklms_poll_should_stamp_a_scan_with_the_arrival_of_its_first_byte);
    RUN_TEST(test_sicklms_next_deadline_should_follow_the_request_and_stream_timers);
    RUN_TEST(test_sicklms_listen_should_decode_and_stamp_scans_as_streaming_and_send_nothing);
    return UNITY_END();
}
