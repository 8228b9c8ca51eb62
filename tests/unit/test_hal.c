/* Unit tests of the HAL helpers (src/hal.c) against a fake in-memory link. */
#include <string.h>

#include "rsm/hal.h"
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
    return UNITY_END();
}
