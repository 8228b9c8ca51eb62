/* Unit tests of the bare-metal UART ring and its rsm_link_t glue
 * (port/baremetal/uart_ring.c), with a fake clock and a fake transmitter. */
#include <string.h>

#include "rsm/hal.h"
#include "rsm/status.h"
#include "uart_ring.h"
#include "unity.h"

#define RING RSM_UART_RING_SIZE

static rsm_uart_ring_t ring;

/* A clock that advances step_us on every read and, when inject_at is reached,
 * pushes a byte into the ring as the RX interrupt would. */
typedef struct fake_clock {
    uint64_t now;
    uint64_t step_us;
    int calls;
    int inject_at; /* 0 = never */
    uint8_t inject_byte;
} fake_clock_t;

static fake_clock_t fclock;

static uint64_t fake_now(void *ctx)
{
    fake_clock_t *c = (fake_clock_t *)ctx;
    c->calls++;
    c->now += c->step_us;
    if (c->inject_at != 0 && c->calls == c->inject_at) {
        (void)rsm_uart_ring_push(&ring, c->inject_byte);
    }
    return c->now;
}

/* A transmitter that records bytes and can fail after a given count. */
typedef struct fake_uart {
    uint8_t sent[32];
    size_t sent_len;
    size_t fail_after; /* fail once sent_len reaches this; 0 = never */
    uint32_t baud;
    int idles;
} fake_uart_t;

static fake_uart_t fuart;

static int fake_tx_byte(void *hw, uint8_t byte)
{
    fake_uart_t *u = (fake_uart_t *)hw;
    if ((u->fail_after != 0u && u->sent_len >= u->fail_after) || u->sent_len >= sizeof u->sent) {
        return RSM_ERR_TIMEOUT;
    }
    u->sent[u->sent_len++] = byte;
    return RSM_OK;
}

static int fake_set_baud(void *hw, uint32_t baud)
{
    fake_uart_t *u = (fake_uart_t *)hw;
    u->baud = baud;
    return RSM_OK;
}

static void fake_idle(void *hw)
{
    fake_uart_t *u = (fake_uart_t *)hw;
    u->idles++;
}

static rsm_clock_t clock_hal;
static rsm_uart_link_config_t uart_cfg;
static rsm_uart_link_t uart;
static rsm_link_t uart_link;

void setUp(void)
{
    memset(&ring, 0xA5, sizeof ring); /* init must not rely on zeroed memory */
    rsm_uart_ring_init(&ring);
    memset(&fclock, 0, sizeof fclock);
    fclock.step_us = 100u;
    memset(&fuart, 0, sizeof fuart);
    clock_hal.now_us = fake_now;
    clock_hal.ctx = &fclock;
    uart_cfg.tx_byte = fake_tx_byte;
    uart_cfg.set_baud = fake_set_baud;
    uart_cfg.idle = fake_idle;
    uart_cfg.hw = &fuart;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_uart_link_init(&uart, &uart_cfg, &ring, &clock_hal, &uart_link));
}

void tearDown(void)
{
}

static uint8_t pattern(uint32_t i)
{
    return (uint8_t)((i * 7u + 3u) & 0xFFu);
}

/* ---- the ring ----------------------------------------------------------------- */

void test_ring_init_should_leave_the_ring_empty(void)
{
    uint8_t out[4];
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_uart_ring_count(&ring));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_uart_ring_overflows(&ring));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_uart_ring_pop(&ring, out, sizeof out));
}

void test_ring_pop_should_return_bytes_in_arrival_order(void)
{
    uint8_t out[8];
    TEST_ASSERT_EQUAL_INT(1, rsm_uart_ring_push(&ring, 0x10));
    TEST_ASSERT_EQUAL_INT(1, rsm_uart_ring_push(&ring, 0x20));
    TEST_ASSERT_EQUAL_INT(1, rsm_uart_ring_push(&ring, 0x30));
    TEST_ASSERT_EQUAL_UINT32(3u, rsm_uart_ring_count(&ring));
    TEST_ASSERT_EQUAL_UINT32(2u, rsm_uart_ring_pop(&ring, out, 2));
    TEST_ASSERT_EQUAL_UINT8(0x10, out[0]);
    TEST_ASSERT_EQUAL_UINT8(0x20, out[1]);
    TEST_ASSERT_EQUAL_UINT32(1u, rsm_uart_ring_pop(&ring, out, sizeof out));
    TEST_ASSERT_EQUAL_UINT8(0x30, out[0]);
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_uart_ring_count(&ring));
}

void test_ring_push_should_drop_the_newest_byte_when_full(void)
{
    static uint8_t out[RING + 1];
    uint32_t i;
    for (i = 0; i < RING; ++i) {
        TEST_ASSERT_EQUAL_INT(1, rsm_uart_ring_push(&ring, pattern(i)));
    }
    TEST_ASSERT_EQUAL_UINT32(RING, rsm_uart_ring_count(&ring));
    TEST_ASSERT_EQUAL_INT(0, rsm_uart_ring_push(&ring, 0xEE));
    TEST_ASSERT_EQUAL_INT(0, rsm_uart_ring_push(&ring, 0xEF));
    TEST_ASSERT_EQUAL_UINT32(2u, rsm_uart_ring_overflows(&ring));
    TEST_ASSERT_EQUAL_UINT32(RING, rsm_uart_ring_count(&ring));
    /* The oldest bytes survive; the dropped ones never appear. */
    TEST_ASSERT_EQUAL_UINT32(RING, rsm_uart_ring_pop(&ring, out, sizeof out));
    for (i = 0; i < RING; ++i) {
        TEST_ASSERT_EQUAL_UINT8(pattern(i), out[i]);
    }
    /* Space frees up again once the consumer has read. */
    TEST_ASSERT_EQUAL_INT(1, rsm_uart_ring_push(&ring, 0x42));
    TEST_ASSERT_EQUAL_UINT32(2u, rsm_uart_ring_overflows(&ring));
}

void test_ring_should_keep_order_across_many_wrap_arounds(void)
{
    static uint8_t out[RING];
    uint32_t pushed = 0;
    uint32_t popped = 0;
    uint32_t round;
    /* Uneven chunk sizes make the slots fall at every offset of the buffer. */
    for (round = 0; round < 200u; ++round) {
        const uint32_t burst = (round * 37u) % (RING / 2u) + 1u;
        size_t n;
        size_t i;
        uint32_t k;
        for (k = 0; k < burst; ++k) {
            TEST_ASSERT_EQUAL_INT(1, rsm_uart_ring_push(&ring, pattern(pushed)));
            ++pushed;
        }
        n = rsm_uart_ring_pop(&ring, out, (round % 3u == 0u) ? burst / 2u + 1u : sizeof out);
        for (i = 0; i < n; ++i) {
            TEST_ASSERT_EQUAL_UINT8(pattern(popped), out[i]);
            ++popped;
        }
    }
    TEST_ASSERT_TRUE(pushed > 4u * RING);
    TEST_ASSERT_EQUAL_UINT32(pushed - popped, rsm_uart_ring_count(&ring));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_uart_ring_overflows(&ring));
}

void test_ring_should_survive_the_32_bit_index_wrap(void)
{
    uint8_t out[16];
    uint32_t i;
    /* Start just below 2^32 as if 4 GiB had already passed through. */
    ring.head = 0xFFFFFFFAu;
    ring.tail = 0xFFFFFFFAu;
    for (i = 0; i < 12u; ++i) {
        TEST_ASSERT_EQUAL_INT(1, rsm_uart_ring_push(&ring, pattern(i)));
    }
    TEST_ASSERT_EQUAL_UINT32(6u, ring.head);
    TEST_ASSERT_EQUAL_UINT32(12u, rsm_uart_ring_count(&ring));
    TEST_ASSERT_EQUAL_UINT32(12u, rsm_uart_ring_pop(&ring, out, sizeof out));
    for (i = 0; i < 12u; ++i) {
        TEST_ASSERT_EQUAL_UINT8(pattern(i), out[i]);
    }
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_uart_ring_count(&ring));
}

void test_ring_push_buf_should_store_what_fits_and_count_the_rest(void)
{
    static uint8_t in[RING + 10];
    static uint8_t out[RING + 10];
    uint32_t i;
    for (i = 0; i < sizeof in; ++i) {
        in[i] = pattern(i);
    }
    TEST_ASSERT_EQUAL_INT(1, rsm_uart_ring_push(&ring, 0x99));
    TEST_ASSERT_EQUAL_UINT32(RING - 1u, rsm_uart_ring_push_buf(&ring, in, sizeof in));
    TEST_ASSERT_EQUAL_UINT32(11u, rsm_uart_ring_overflows(&ring));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_uart_ring_push_buf(&ring, in, 5));
    TEST_ASSERT_EQUAL_UINT32(16u, rsm_uart_ring_overflows(&ring));
    TEST_ASSERT_EQUAL_UINT32(RING, rsm_uart_ring_pop(&ring, out, sizeof out));
    TEST_ASSERT_EQUAL_UINT8(0x99, out[0]);
    TEST_ASSERT_EQUAL_MEMORY(in, out + 1, RING - 1u);
}

void test_ring_clear_should_discard_pending_bytes(void)
{
    uint8_t out[4];
    (void)rsm_uart_ring_push(&ring, 1);
    (void)rsm_uart_ring_push(&ring, 2);
    rsm_uart_ring_clear(&ring);
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_uart_ring_count(&ring));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_uart_ring_pop(&ring, out, sizeof out));
    (void)rsm_uart_ring_push(&ring, 3);
    TEST_ASSERT_EQUAL_UINT32(1u, rsm_uart_ring_pop(&ring, out, sizeof out));
    TEST_ASSERT_EQUAL_UINT8(3, out[0]);
}

/* ---- the ring as a link --------------------------------------------------------- */

void test_uart_link_init_should_reject_missing_parts(void)
{
    rsm_uart_link_t u;
    rsm_link_t l;
    rsm_uart_link_config_t cfg = uart_cfg;
    rsm_clock_t c = clock_hal;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_uart_link_init(NULL, &cfg, &ring, &c, &l));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_uart_link_init(&u, NULL, &ring, &c, &l));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_uart_link_init(&u, &cfg, NULL, &c, &l));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_uart_link_init(&u, &cfg, &ring, NULL, &l));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_uart_link_init(&u, &cfg, &ring, &c, NULL));
    c.now_us = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_uart_link_init(&u, &cfg, &ring, &c, &l));
    c = clock_hal;
    cfg.tx_byte = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_uart_link_init(&u, &cfg, &ring, &c, &l));
}

void test_uart_link_read_should_return_buffered_bytes_at_once(void)
{
    uint8_t out[2];
    (void)rsm_uart_ring_push(&ring, 0xFA);
    (void)rsm_uart_ring_push(&ring, 0xFB);
    (void)rsm_uart_ring_push(&ring, 0x03);
    TEST_ASSERT_EQUAL_INT(2, rsm_link_read(&uart_link, out, sizeof out, 1000000u));
    TEST_ASSERT_EQUAL_UINT8(0xFA, out[0]);
    TEST_ASSERT_EQUAL_UINT8(0xFB, out[1]);
    TEST_ASSERT_EQUAL_INT(1, rsm_link_read(&uart_link, out, sizeof out, 1000000u));
    TEST_ASSERT_EQUAL_UINT8(0x03, out[0]);
    TEST_ASSERT_EQUAL_INT(0, fclock.calls);
}

void test_uart_link_read_should_poll_without_the_clock_when_the_timeout_is_zero(void)
{
    uint8_t out[4];
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&uart_link, out, sizeof out, 0u));
    TEST_ASSERT_EQUAL_INT(0, fclock.calls);
    TEST_ASSERT_EQUAL_INT(0, fuart.idles);
}

void test_uart_link_read_should_time_out_after_the_given_time(void)
{
    uint8_t out[4];
    uint64_t start;
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&uart_link, out, sizeof out, 1000u));
    /* The first clock read starts the wait; it ends on the first read at or
     * past start + 1000 us, with 100 us per read: exactly 10 later reads. */
    start = 100u;
    TEST_ASSERT_EQUAL_INT(11, fclock.calls);
    TEST_ASSERT_TRUE(fclock.now - start >= 1000u);
    TEST_ASSERT_TRUE(fclock.now - start < 1100u);
    TEST_ASSERT_EQUAL_INT(10, fuart.idles);
}

void test_uart_link_read_should_return_a_byte_that_arrives_while_waiting(void)
{
    uint8_t out[4];
    fclock.inject_at = 4;
    fclock.inject_byte = 0x5A;
    TEST_ASSERT_EQUAL_INT(1, rsm_link_read(&uart_link, out, sizeof out, 1000000u));
    TEST_ASSERT_EQUAL_UINT8(0x5A, out[0]);
    TEST_ASSERT_EQUAL_INT(4, fclock.calls);
}

void test_uart_link_read_should_return_a_byte_that_arrives_on_the_last_tick(void)
{
    uint8_t out[4];
    /* The byte lands during the clock read that also ends the wait. */
    fclock.inject_at = 11;
    fclock.inject_byte = 0x77;
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&uart_link, out, sizeof out, 1000u));
    TEST_ASSERT_EQUAL_INT(1, rsm_link_read(&uart_link, out, sizeof out, 0u));
    TEST_ASSERT_EQUAL_UINT8(0x77, out[0]);
}

void test_uart_link_read_should_busy_poll_without_an_idle_hook(void)
{
    uint8_t out[4];
    uart_cfg.idle = NULL;
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&uart_link, out, sizeof out, 500u));
    TEST_ASSERT_EQUAL_INT(0, fuart.idles);
    TEST_ASSERT_EQUAL_INT(6, fclock.calls);
}

void test_uart_link_write_should_send_every_byte(void)
{
    static const uint8_t msg[] = {0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00};
    size_t written = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_write_all(&uart_link, msg, sizeof msg, &written));
    TEST_ASSERT_EQUAL_UINT32(sizeof msg, written);
    TEST_ASSERT_EQUAL_UINT32(sizeof msg, fuart.sent_len);
    TEST_ASSERT_EQUAL_MEMORY(msg, fuart.sent, sizeof msg);
}

void test_uart_link_write_should_report_a_stuck_transmitter(void)
{
    static const uint8_t msg[] = {1, 2, 3, 4, 5};
    size_t written = 0;
    fuart.fail_after = 3;
    TEST_ASSERT_EQUAL_INT(3, uart_link.write(uart_link.ctx, msg, sizeof msg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_TIMEOUT, uart_link.write(uart_link.ctx, msg + 3, 2));
    fuart.sent_len = 0;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_TIMEOUT, rsm_link_write_all(&uart_link, msg, sizeof msg, &written));
    TEST_ASSERT_EQUAL_UINT32(3u, written);
}

void test_uart_link_set_baud_should_reach_the_board_or_report_nosys(void)
{
    rsm_uart_link_t u;
    rsm_link_t l;
    rsm_uart_link_config_t cfg = uart_cfg;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_set_baud(&uart_link, 38400u));
    TEST_ASSERT_EQUAL_UINT32(38400u, fuart.baud);
    cfg.set_baud = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_uart_link_init(&u, &cfg, &ring, &clock_hal, &l));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_link_set_baud(&l, 9600u));
}

void test_uart_link_flush_should_empty_the_ring(void)
{
    uint8_t out[4];
    (void)rsm_uart_ring_push(&ring, 1);
    (void)rsm_uart_ring_push(&ring, 2);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_link_flush(&uart_link));
    TEST_ASSERT_EQUAL_INT(0, rsm_link_read(&uart_link, out, sizeof out, 0u));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_ring_init_should_leave_the_ring_empty);
    RUN_TEST(test_ring_pop_should_return_bytes_in_arrival_order);
    RUN_TEST(test_ring_push_should_drop_the_newest_byte_when_full);
    RUN_TEST(test_ring_should_keep_order_across_many_wrap_arounds);
    RUN_TEST(test_ring_should_survive_the_32_bit_index_wrap);
    RUN_TEST(test_ring_push_buf_should_store_what_fits_and_count_the_rest);
    RUN_TEST(test_ring_clear_should_discard_pending_bytes);
    RUN_TEST(test_uart_link_init_should_reject_missing_parts);
    RUN_TEST(test_uart_link_read_should_return_buffered_bytes_at_once);
    RUN_TEST(test_uart_link_read_should_poll_without_the_clock_when_the_timeout_is_zero);
    RUN_TEST(test_uart_link_read_should_time_out_after_the_given_time);
    RUN_TEST(test_uart_link_read_should_return_a_byte_that_arrives_while_waiting);
    RUN_TEST(test_uart_link_read_should_return_a_byte_that_arrives_on_the_last_tick);
    RUN_TEST(test_uart_link_read_should_busy_poll_without_an_idle_hook);
    RUN_TEST(test_uart_link_write_should_send_every_byte);
    RUN_TEST(test_uart_link_write_should_report_a_stuck_transmitter);
    RUN_TEST(test_uart_link_set_baud_should_reach_the_board_or_report_nosys);
    RUN_TEST(test_uart_link_flush_should_empty_the_ring);
    return UNITY_END();
}
