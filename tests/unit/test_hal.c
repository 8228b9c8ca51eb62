/* Unit tests of the HAL helpers (src/drivers/hal.c) against a fake in-memory link. */
#include <string.h>

#include "rsm/hal.h"
#include "rsm/link_poll.h"
#include "rsm/status.h"
#include "unity.h"

/* A link whose input is a fixed byte string and whose output is a buffer;
 * each knob makes one callback misbehave in one way. */
typedef struct fake_link {
    const uint8_t *in;       /* bytes the read callback delivers */
    size_t in_len;
    size_t in_pos;
    size_t max_per_read;     /* 0 = no limit */
    int read_status;         /* if non-zero, read returns this */
    int read_overclaim;      /* read claims cap + 1 bytes */
    uint32_t last_timeout_us;
    int reads;

    uint8_t out[64];         /* bytes the write callback accepted */
    size_t out_len;
    size_t max_per_write;    /* 0 = no limit */
    size_t fail_after;       /* write returns write_status once out_len reaches this */
    int write_status;        /* 0 = never fail */
    int write_stall;         /* write returns 0 */
    int write_overclaim;     /* write claims len + 1 bytes */
    int writes;

    uint32_t baud;
    int set_baud_status;
    int flushes;
    uint64_t now;
    uint64_t read_advance;   /* clock microseconds each read takes */
} fake_link_t;

static fake_link_t fake;

static size_t min_size(size_t a, size_t b)
{
    return a < b ? a : b;
}

static int fake_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us)
{
    fake_link_t *f = (fake_link_t *)ctx;
    size_t n;
    f->reads++;
    f->last_timeout_us = timeout_us;
    f->now += f->read_advance;
    if (f->read_status != 0) {
        return f->read_status;
    }
    if (f->read_overclaim) {
        return (int)cap + 1;
    }
    n = min_size(cap, f->in_len - f->in_pos);
    if (f->max_per_read > 0u) {
        n = min_size(n, f->max_per_read);
    }
    if (n > 0u) {
        memcpy(buf, f->in + f->in_pos, n);
    }
    f->in_pos += n;
    return (int)n;
}

static int fake_write(void *ctx, const uint8_t *buf, size_t len)
{
    fake_link_t *f = (fake_link_t *)ctx;
    size_t n;
    f->writes++;
    if (f->write_status != 0 && f->out_len >= f->fail_after) {
        return f->write_status;
    }
    if (f->write_stall) {
        return 0;
    }
    if (f->write_overclaim) {
        return (int)len + 1;
    }
    n = min_size(len, sizeof f->out - f->out_len);
    if (f->max_per_write > 0u) {
        n = min_size(n, f->max_per_write);
    }
    if (f->write_status != 0) {
        n = min_size(n, f->fail_after - f->out_len);
    }
    memcpy(f->out + f->out_len, buf, n);
    f->out_len += n;
    return (int)n;
}

static int fake_set_baud(void *ctx, uint32_t baud)
{
    fake_link_t *f = (fake_link_t *)ctx;
    if (f->set_baud_status != 0) {
        return f->set_baud_status;
    }
    f->baud = baud;
    return RSM_OK;
}

static int fake_flush(void *ctx)
{
    fake_link_t *f = (fake_link_t *)ctx;
    f->flushes++;
    f->in_pos = f->in_len;
    return RSM_OK;
}

static uint64_t fake_now(void *ctx)
{
    fake_link_t *f = (fake_link_t *)ctx;
    return f->now;
}

static const uint8_t input[] = {0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01, 0x02, 0x03, 0x04, 0x05};
static rsm_link_t the_link;
static rsm_clock_t the_clock;

void setUp(void)
{
    memset(&fake, 0, sizeof fake);
    fake.in = input;
    fake.in_len = sizeof input;
    the_link.read = fake_read;
    the_link.write = fake_write;
    the_link.set_baud = fake_set_baud;
    the_link.flush = fake_flush;
    the_link.ctx = &fake;
    the_clock.now_us = fake_now;
    the_clock.ctx = &fake;
}

void tearDown(void)
{
}

/* ---- rsm_link_read ---------------------------------------------------------- */

void test_link_read_should_return_available_bytes_up_to_cap(void)
{
    uint8_t buf[4];
    TEST_ASSERT_EQUAL_INT(4, rsm_link_read(&the_link, buf, sizeof buf, 1000u));
    TEST_ASSERT_EQUAL_MEMORY(input, buf, 4);
    TEST_ASSERT_EQUAL_UINT32(1000u, fake.last_timeout_us);
    TEST_ASSERT_EQUAL_INT(4, rsm_link_read(&the_link, buf, sizeof buf, 0u));
    TEST_ASSERT_EQUAL_MEMORY(input + 4, buf, 4);
    TEST_ASSERT_EQUAL_INT(2, rsm_link_read(&the_link, buf, sizeof buf, 0u));
    TEST_ASSERT_EQUAL_MEMORY(input + 8, buf, 2);
}

void test_link_read_should_return_zero_when_nothing_arrives(void)
{
    uint8_t buf[4];
    fake.in_len = 0;
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&the_link, buf, sizeof buf, 500u));
    TEST_ASSERT_EQUAL_UINT32(500u, fake.last_timeout_us);
}

void test_link_read_should_allow_a_zero_capacity(void)
{
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&the_link, NULL, 0u, 0u));
}

void test_link_read_should_reject_null_arguments(void)
{
    uint8_t buf[4];
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_read(NULL, buf, sizeof buf, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_read(&the_link, NULL, 1u, 0u));
    TEST_ASSERT_EQUAL_INT(0, fake.reads);
}

void test_link_read_should_report_nosys_without_a_read_callback(void)
{
    uint8_t buf[4];
    the_link.read = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_link_read(&the_link, buf, sizeof buf, 0u));
}

void test_link_read_should_pass_callback_errors_through(void)
{
    uint8_t buf[4];
    fake.read_status = RSM_ERR_IO;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_read(&the_link, buf, sizeof buf, 0u));
}

void test_link_read_should_reject_a_callback_that_claims_more_than_cap(void)
{
    uint8_t buf[8];
    fake.read_overclaim = 1;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_read(&the_link, buf, 4u, 0u));
}

/* ---- rsm_link_write_all ----------------------------------------------------- */

void test_link_write_all_should_loop_over_short_writes(void)
{
    size_t written = 99;
    fake.max_per_write = 3;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_write_all(&the_link, input, sizeof input, &written));
    TEST_ASSERT_EQUAL_UINT32(sizeof input, written);
    TEST_ASSERT_EQUAL_UINT32(sizeof input, fake.out_len);
    TEST_ASSERT_EQUAL_MEMORY(input, fake.out, sizeof input);
    TEST_ASSERT_EQUAL_INT(4, fake.writes);
}

void test_link_write_all_should_accept_an_empty_write_without_calling_the_link(void)
{
    size_t written = 99;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_write_all(&the_link, NULL, 0u, &written));
    TEST_ASSERT_EQUAL_UINT32(0u, written);
    TEST_ASSERT_EQUAL_INT(0, fake.writes);
}

void test_link_write_all_should_stop_on_an_error_and_report_what_was_written(void)
{
    size_t written = 99;
    fake.max_per_write = 2;
    fake.fail_after = 5;
    fake.write_status = RSM_ERR_IO;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_write_all(&the_link, input, sizeof input, &written));
    TEST_ASSERT_EQUAL_UINT32(5u, written);
    TEST_ASSERT_EQUAL_MEMORY(input, fake.out, 5);
}

void test_link_write_all_should_time_out_when_a_write_makes_no_progress(void)
{
    size_t written = 99;
    fake.write_stall = 1;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_TIMEOUT, rsm_link_write_all(&the_link, input, sizeof input, &written));
    TEST_ASSERT_EQUAL_UINT32(0u, written);
    TEST_ASSERT_EQUAL_INT(1, fake.writes);
}

void test_link_write_all_should_reject_a_callback_that_claims_more_than_len(void)
{
    fake.write_overclaim = 1;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_write_all(&the_link, input, sizeof input, NULL));
}

void test_link_write_all_should_reject_null_arguments(void)
{
    size_t written = 99;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_write_all(NULL, input, sizeof input, &written));
    TEST_ASSERT_EQUAL_UINT32(0u, written);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_write_all(&the_link, NULL, 1u, NULL));
    the_link.write = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_link_write_all(&the_link, input, sizeof input, NULL));
    TEST_ASSERT_EQUAL_INT(0, fake.writes);
}

/* ---- rsm_link_set_baud, rsm_link_flush -------------------------------------- */

void test_link_set_baud_should_call_the_callback(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_set_baud(&the_link, 38400u));
    TEST_ASSERT_EQUAL_UINT32(38400u, fake.baud);
    fake.set_baud_status = RSM_ERR_RANGE;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_link_set_baud(&the_link, 12345u));
    TEST_ASSERT_EQUAL_UINT32(38400u, fake.baud);
}

void test_link_set_baud_should_report_nosys_when_the_link_has_no_baud(void)
{
    the_link.set_baud = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_link_set_baud(&the_link, 9600u));
}

void test_link_set_baud_should_reject_a_null_link_or_zero_baud(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_set_baud(NULL, 9600u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_set_baud(&the_link, 0u));
    TEST_ASSERT_EQUAL_UINT32(0u, fake.baud);
}

void test_link_flush_should_discard_pending_input(void)
{
    uint8_t buf[4];
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_flush(&the_link));
    TEST_ASSERT_EQUAL_INT(1, fake.flushes);
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&the_link, buf, sizeof buf, 0u));
}

void test_link_flush_should_report_nosys_or_inval(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_flush(NULL));
    the_link.flush = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_link_flush(&the_link));
}

/* ---- rsm_clock_now_us ------------------------------------------------------- */

void test_clock_now_us_should_read_the_clock(void)
{
    uint64_t t = 0;
    fake.now = 0x123456789ABCull;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_clock_now_us(&the_clock, &t));
    TEST_ASSERT_TRUE(t == 0x123456789ABCull);
}

void test_clock_now_us_should_leave_the_output_untouched_on_error(void)
{
    uint64_t t = 42;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_clock_now_us(NULL, &t));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_clock_now_us(&the_clock, NULL));
    the_clock.now_us = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_clock_now_us(&the_clock, &t));
    TEST_ASSERT_TRUE(t == 42u);
}

/* ---- the poll cycle: rsm_link_rx_*, rsm_link_poll ---------------------------- */

/* A driver that only records what the cycle asks of it. */
typedef struct trace_driver {
    rsm_link_rx_t rx;
    int drain_event_at;      /* 1-based call number of drain that reports an event */
    int timers_event_at;
    int silence_event;
    int drain_drops;         /* drain calls rsm_link_rx_drop on a non-empty chunk */
    uint64_t due_us;         /* what until_due returns */
    uint64_t drain_now[4];
    size_t drained;          /* bytes taken from the chunk in total */
    int drains;
    int timers;
} trace_driver_t;

static trace_driver_t drv;
static char calls[32];  /* one letter per callback, in call order: D T U S */
static size_t n_calls;

static void trace(char c)
{
    if (n_calls + 1u < sizeof calls) {
        calls[n_calls++] = c;
        calls[n_calls] = '\0';
    }
}

static int trace_drain(void *p, uint64_t now)
{
    trace_driver_t *d = (trace_driver_t *)p;
    trace('D');
    if (d->drains < 4) {
        d->drain_now[d->drains] = now;
    }
    d->drains++;
    d->drained += d->rx.len - d->rx.off;
    d->rx.off = d->rx.len;
    if (d->drain_drops && d->rx.len > 0u) {
        rsm_link_rx_drop(&d->rx);
    }
    return d->drains == d->drain_event_at;
}

static int trace_timers(void *p, uint64_t now)
{
    trace_driver_t *d = (trace_driver_t *)p;
    (void)now;
    trace('T');
    d->timers++;
    return d->timers == d->timers_event_at;
}

static uint64_t trace_until_due(const void *p, uint64_t now)
{
    const trace_driver_t *d = (const trace_driver_t *)p;
    (void)now;
    trace('U');
    return d->due_us;
}

static int trace_silence(void *p, uint64_t now)
{
    trace_driver_t *d = (trace_driver_t *)p;
    (void)now;
    trace('S');
    return d->silence_event;
}

static const rsm_link_poll_ops_t trace_ops = {trace_drain, trace_timers, trace_until_due,
                                              trace_silence};

static void trace_setup(uint32_t read_timeout_us, uint32_t byte_timeout_us)
{
    memset(&drv, 0, sizeof drv);
    memset(calls, 0, sizeof calls);
    n_calls = 0u;
    drv.due_us = UINT64_MAX;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_rx_init(&drv.rx, &the_link, &the_clock, read_timeout_us,
                                                   byte_timeout_us));
}

static size_t min_chunk(size_t n)
{
    return n < (size_t)RSM_LINK_RX_CHUNK ? n : (size_t)RSM_LINK_RX_CHUNK;
}

void test_link_rx_init_should_check_its_arguments(void)
{
    rsm_link_rx_t rx;
    rsm_link_t l = the_link;
    rsm_clock_t c = the_clock;
    memset(&rx, 0xA5, sizeof rx);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_rx_init(NULL, &the_link, &the_clock, 10u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_rx_init(&rx, NULL, &the_clock, 10u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_rx_init(&rx, &the_link, NULL, 10u, 0u));
    l.write = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_rx_init(&rx, &l, &the_clock, 10u, 0u));
    l = the_link;
    l.read = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_rx_init(&rx, &l, &the_clock, 10u, 0u));
    c.now_us = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_rx_init(&rx, &the_link, &c, 10u, 0u));
    TEST_ASSERT_EQUAL_HEX8(0xA5u, rx.buf[0]); /* untouched on error */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_rx_init(&rx, &the_link, &the_clock, 10u, 20u));
    TEST_ASSERT_EQUAL_PTR(&the_link, rx.link);
    TEST_ASSERT_EQUAL_PTR(&the_clock, rx.clock);
    TEST_ASSERT_EQUAL_UINT32(10u, rx.read_timeout_us);
    TEST_ASSERT_EQUAL_UINT32(20u, rx.byte_timeout_us);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rx.off);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rx.len);
    TEST_ASSERT_TRUE(rx.last_rx_us == 0u);
    TEST_ASSERT_EQUAL_INT(0, fake.reads);
    TEST_ASSERT_EQUAL_INT(0, fake.writes);
}

void test_link_rx_init_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* What rsm_link_rx_init passes for an application compiled with other
     * capacities (RSM_LINK_RX_CHUNK sizes the chunk), or with capacities
     * that give the same size: refused, and not one byte written. */
    rsm_link_rx_t rx;
    rsm_link_rx_t before;
    memset(&rx, 0xA5, sizeof rx);
    memcpy(&before, &rx, sizeof rx);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_link_rx_init_checked(&rx, sizeof rx - 8u,
                                                                   (unsigned long)RSM_CONFIG_FINGERPRINT, &the_link,
                                                                   &the_clock, 10u, 20u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_link_rx_init_checked(&rx, sizeof rx,
                                                                   (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul,
                                                                   &the_link, &the_clock, 10u, 20u));
    TEST_ASSERT_EQUAL_MEMORY(&before, &rx, sizeof rx);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_rx_init(&rx, &the_link, &the_clock, 10u, 20u));
}

void test_link_poll_should_run_the_steps_in_order_and_stamp_what_it_read(void)
{
    fake.now = 5000u;
    fake.read_advance = 700u;
    trace_setup(1000u, 100000u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    /* drain (left-overs), timers, until_due, read, drain (new bytes), timers */
    TEST_ASSERT_EQUAL_STRING("DTUDT", calls);
    TEST_ASSERT_EQUAL_INT(1, fake.reads);
    TEST_ASSERT_EQUAL_UINT32(1000u, fake.last_timeout_us);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)min_chunk(sizeof input), (uint32_t)drv.rx.len);
    TEST_ASSERT_EQUAL_MEMORY(input, drv.rx.buf, min_chunk(sizeof input));
    TEST_ASSERT_EQUAL_UINT32((uint32_t)min_chunk(sizeof input), (uint32_t)drv.drained);
    TEST_ASSERT_TRUE(drv.rx.stamp_us == 5700u);
    TEST_ASSERT_TRUE(drv.rx.last_rx_us == 5700u);
    TEST_ASSERT_TRUE(drv.drain_now[0] == 5000u);
    TEST_ASSERT_TRUE(drv.drain_now[1] == 5700u);
}

void test_link_poll_should_not_wait_past_the_next_deadline(void)
{
    trace_setup(1000u, 0u);
    drv.due_us = 250u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_UINT32(250u, fake.last_timeout_us);
    drv.due_us = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_UINT32(0u, fake.last_timeout_us);
    drv.due_us = 1001u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_UINT32(1000u, fake.last_timeout_us);
}

void test_link_poll_with_a_zero_read_timeout_should_never_wait(void)
{
    trace_setup(0u, 0u);
    drv.due_us = 250u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_INT(1, fake.reads);
    TEST_ASSERT_EQUAL_UINT32(0u, fake.last_timeout_us);
}

void test_link_next_deadline_should_be_now_plus_the_next_timer_or_now_with_bytes_left(void)
{
    fake.now = 5000u;
    trace_setup(1000u, 0u);
    TEST_ASSERT_TRUE(rsm_link_next_deadline(&drv.rx, &trace_ops, &drv) == UINT64_MAX);
    drv.due_us = 250u;
    TEST_ASSERT_TRUE(rsm_link_next_deadline(&drv.rx, &trace_ops, &drv) == 5250u);
    drv.due_us = UINT64_MAX - 10u; /* no overflow past the end of time */
    TEST_ASSERT_TRUE(rsm_link_next_deadline(&drv.rx, &trace_ops, &drv) == UINT64_MAX);
    drv.rx.len = 3u; /* a read left bytes unexamined: poll again at once */
    drv.rx.off = 1u;
    TEST_ASSERT_TRUE(rsm_link_next_deadline(&drv.rx, &trace_ops, &drv) == 5000u);
    TEST_ASSERT_TRUE(rsm_link_next_deadline(NULL, &trace_ops, &drv) == UINT64_MAX);
    TEST_ASSERT_TRUE(rsm_link_next_deadline(&drv.rx, NULL, &drv) == UINT64_MAX);
    TEST_ASSERT_EQUAL_INT(0, fake.reads); /* nothing read, nothing changed */
    TEST_ASSERT_EQUAL_STRING("UUU", calls);
}

void test_link_poll_should_stop_at_the_first_event(void)
{
    trace_setup(1000u, 0u);
    drv.drain_event_at = 1; /* left-overs already make an event: no read */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_STRING("D", calls);
    TEST_ASSERT_EQUAL_INT(0, fake.reads);

    trace_setup(1000u, 0u);
    drv.timers_event_at = 1; /* a timer fired: no read */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_STRING("DT", calls);
    TEST_ASSERT_EQUAL_INT(0, fake.reads);

    trace_setup(1000u, 0u);
    drv.drain_event_at = 2; /* the new bytes make an event: no second timers run */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_STRING("DTUD", calls);
    TEST_ASSERT_EQUAL_INT(1, fake.reads);
}

void test_link_poll_should_call_silence_only_after_the_byte_timeout(void)
{
    fake.now = 1000000u;
    fake.read_advance = 0u;
    trace_setup(1000u, 100000u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv)); /* bytes */
    TEST_ASSERT_EQUAL_STRING("DTUDT", calls);
    fake.in_len = fake.in_pos;                                              /* silence */
    fake.now += 99999u;
    n_calls = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_STRING("DTUT", calls);
    fake.now += 1u;
    n_calls = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_STRING("DTUST", calls);
    drv.silence_event = 1;
    n_calls = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_STRING("DTUS", calls);
}

void test_link_poll_should_return_a_read_error_and_stay_usable(void)
{
    trace_setup(1000u, 0u);
    fake.read_status = RSM_ERR_IO;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_STRING("DTU", calls);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)drv.rx.len);
    fake.read_status = 0;
    n_calls = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_STRING("DTUDT", calls);
}

void test_link_poll_should_refuse_null_arguments_and_missing_steps(void)
{
    rsm_link_poll_ops_t ops = trace_ops;
    trace_setup(1000u, 0u);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_poll(NULL, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_poll(&drv.rx, NULL, &drv));
    ops.silence = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_poll(&drv.rx, &ops, &drv));
    ops = trace_ops;
    ops.until_due = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_link_poll(&drv.rx, &ops, &drv));
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)n_calls);
    TEST_ASSERT_EQUAL_INT(0, fake.reads);
}

void test_link_rx_drop_should_flush_the_link_and_empty_the_chunk_even_inside_a_step(void)
{
    uint8_t buf[4];
    trace_setup(1000u, 0u);
    fake.in_len = 3u;
    drv.drain_drops = 1;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_poll(&drv.rx, &trace_ops, &drv));
    TEST_ASSERT_EQUAL_STRING("DTUDT", calls);
    TEST_ASSERT_EQUAL_UINT32(3u, (uint32_t)drv.drained);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)drv.rx.off);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)drv.rx.len);
    TEST_ASSERT_EQUAL_INT(1, fake.flushes);
    fake.in_len = sizeof input;             /* flush discards what the link holds */
    rsm_link_rx_drop(&drv.rx);
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&the_link, buf, sizeof buf, 0u));
    rsm_link_rx_drop(NULL);
    TEST_ASSERT_TRUE(rsm_link_rx_now(NULL) == 0u);
    fake.now = 77u;
    TEST_ASSERT_TRUE(rsm_link_rx_now(&drv.rx) == 77u);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_link_read_should_return_available_bytes_up_to_cap);
    RUN_TEST(test_link_read_should_return_zero_when_nothing_arrives);
    RUN_TEST(test_link_read_should_allow_a_zero_capacity);
    RUN_TEST(test_link_read_should_reject_null_arguments);
    RUN_TEST(test_link_read_should_report_nosys_without_a_read_callback);
    RUN_TEST(test_link_read_should_pass_callback_errors_through);
    RUN_TEST(test_link_read_should_reject_a_callback_that_claims_more_than_cap);
    RUN_TEST(test_link_write_all_should_loop_over_short_writes);
    RUN_TEST(test_link_write_all_should_accept_an_empty_write_without_calling_the_link);
    RUN_TEST(test_link_write_all_should_stop_on_an_error_and_report_what_was_written);
    RUN_TEST(test_link_write_all_should_time_out_when_a_write_makes_no_progress);
    RUN_TEST(test_link_write_all_should_reject_a_callback_that_claims_more_than_len);
    RUN_TEST(test_link_write_all_should_reject_null_arguments);
    RUN_TEST(test_link_set_baud_should_call_the_callback);
    RUN_TEST(test_link_set_baud_should_report_nosys_when_the_link_has_no_baud);
    RUN_TEST(test_link_set_baud_should_reject_a_null_link_or_zero_baud);
    RUN_TEST(test_link_flush_should_discard_pending_input);
    RUN_TEST(test_link_flush_should_report_nosys_or_inval);
    RUN_TEST(test_clock_now_us_should_read_the_clock);
    RUN_TEST(test_clock_now_us_should_leave_the_output_untouched_on_error);
    RUN_TEST(test_link_rx_init_should_check_its_arguments);
    RUN_TEST(test_link_rx_init_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_link_poll_should_run_the_steps_in_order_and_stamp_what_it_read);
    RUN_TEST(test_link_poll_should_not_wait_past_the_next_deadline);
    RUN_TEST(test_link_poll_with_a_zero_read_timeout_should_never_wait);
    RUN_TEST(test_link_next_deadline_should_be_now_plus_the_next_timer_or_now_with_bytes_left);
    RUN_TEST(test_link_poll_should_stop_at_the_first_event);
    RUN_TEST(test_link_poll_should_call_silence_only_after_the_byte_timeout);
    RUN_TEST(test_link_poll_should_return_a_read_error_and_stay_usable);
    RUN_TEST(test_link_poll_should_refuse_null_arguments_and_missing_steps);
    RUN_TEST(test_link_rx_drop_should_flush_the_link_and_empty_the_chunk_even_inside_a_step);
    return UNITY_END();
}
