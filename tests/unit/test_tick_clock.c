/* Unit tests of the bare-metal tick clock (port/baremetal/tick_clock.c): a
 * 32-bit (or narrower) tick counter extended to 64-bit microseconds. */
#include <string.h>

#include "rsm/hal.h"
#include "rsm/status.h"
#include "tick_clock.h"
#include "unity.h"

static uint32_t counter; /* the fake hardware counter */
static int counter_reads;

static uint32_t read_counter(void *hw)
{
    (void)hw;
    counter_reads++;
    return counter;
}

static rsm_tick_clock_config_t cfg;
static rsm_tick_clock_t tc;

void setUp(void)
{
    counter = 0;
    counter_reads = 0;
    cfg.read_ticks = read_counter;
    cfg.hw = NULL;
    cfg.tick_hz = 1000u;
    cfg.counter_bits = 0u;
    memset(&tc, 0, sizeof tc);
}

void tearDown(void)
{
}

/* Exact microseconds for a tick total, computed independently. */
static uint64_t expected_us(uint64_t ticks, uint32_t hz)
{
    return ticks / hz * 1000000u + ticks % hz * 1000000u / hz;
}

static void assert_u64(uint64_t expected, uint64_t actual)
{
    TEST_ASSERT_EQUAL_UINT32_MESSAGE((uint32_t)(expected >> 32), (uint32_t)(actual >> 32), "high word");
    TEST_ASSERT_EQUAL_UINT32_MESSAGE((uint32_t)expected, (uint32_t)actual, "low word");
}

void test_tick_clock_init_should_reject_a_bad_config(void)
{
    rsm_clock_t hal_clock = {NULL, NULL};
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tick_clock_init(NULL, &cfg, &hal_clock));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tick_clock_init(&tc, NULL, &hal_clock));
    cfg.tick_hz = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tick_clock_init(&tc, &cfg, &hal_clock));
    cfg.tick_hz = 1000u;
    cfg.counter_bits = 33u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tick_clock_init(&tc, &cfg, &hal_clock));
    cfg.counter_bits = 0u;
    cfg.read_ticks = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tick_clock_init(&tc, &cfg, &hal_clock));
    TEST_ASSERT_NULL(hal_clock.now_us);
    TEST_ASSERT_NULL(hal_clock.ctx);
}

void test_tick_clock_now_us_should_start_at_zero_and_count_ticks(void)
{
    counter = 123456u; /* time zero is wherever the counter is at init */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tick_clock_init(&tc, &cfg, NULL));
    assert_u64(0u, rsm_tick_clock_now_us(&tc));
    counter += 5u;
    assert_u64(5000u, rsm_tick_clock_now_us(&tc));
    assert_u64(5000u, rsm_tick_clock_now_us(&tc));
    counter += 1995u;
    assert_u64(2000000u, rsm_tick_clock_now_us(&tc));
}

void test_tick_clock_init_should_fill_an_rsm_clock(void)
{
    rsm_clock_t hal_clock = {NULL, NULL};
    uint64_t t = 99u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tick_clock_init(&tc, &cfg, &hal_clock));
    TEST_ASSERT_EQUAL_PTR(&tc, hal_clock.ctx);
    counter = 250u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_clock_now_us(&hal_clock, &t));
    assert_u64(250000u, t);
}

void test_tick_clock_now_us_should_handle_the_32_bit_wrap(void)
{
    counter = 0xFFFFFFF0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tick_clock_init(&tc, &cfg, NULL));
    counter += 0x20u; /* wraps to 0x10 */
    TEST_ASSERT_EQUAL_UINT32(0x10u, counter);
    assert_u64(32000u, rsm_tick_clock_now_us(&tc));
}

void test_tick_clock_now_us_should_handle_a_narrow_counter(void)
{
    cfg.tick_hz = 1000000u;
    cfg.counter_bits = 16u;
    counter = 0xFFF0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tick_clock_init(&tc, &cfg, NULL));
    /* High bits the hardware does not have must be ignored. */
    counter = 0xABCD0010u;
    assert_u64(0x20u, rsm_tick_clock_now_us(&tc));
    counter = 0x0000FFFFu;
    assert_u64(0x20u + 0xFFEFu, rsm_tick_clock_now_us(&tc));
}

void test_tick_clock_now_us_should_be_exact_for_a_rate_that_does_not_divide_a_second(void)
{
    cfg.tick_hz = 32768u; /* a watch crystal */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tick_clock_init(&tc, &cfg, NULL));
    counter = 1u;
    assert_u64(30u, rsm_tick_clock_now_us(&tc)); /* 30.52 us, rounded down */
    counter = 32768u;
    assert_u64(1000000u, rsm_tick_clock_now_us(&tc));
    counter = 32768u + 16384u;
    assert_u64(1500000u, rsm_tick_clock_now_us(&tc));
}

void test_tick_clock_now_us_should_stay_exact_and_monotonic_over_many_wraps(void)
{
    static const uint32_t rates[] = {1000u, 3u, 32768u, 1000000u, 168000000u, 4000000000u};
    size_t r;
    for (r = 0; r < sizeof rates / sizeof rates[0]; ++r) {
        uint64_t total = 0;
        uint64_t last = 0;
        uint32_t step = 0x9E3779B9u; /* large, odd steps: many wraps, every residue */
        int i;
        cfg.tick_hz = rates[r];
        counter = 0xFFFFFF00u;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tick_clock_init(&tc, &cfg, NULL));
        for (i = 0; i < 5000; ++i) {
            uint64_t now;
            step = step * 1664525u + 1013904223u;
            counter += step;
            total += step;
            now = rsm_tick_clock_now_us(&tc);
            TEST_ASSERT_TRUE(now >= last);
            assert_u64(expected_us(total, rates[r]), now);
            last = now;
        }
    }
}

void test_tick_clock_now_us_should_read_the_counter_once_per_call(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tick_clock_init(&tc, &cfg, NULL));
    counter_reads = 0;
    (void)rsm_tick_clock_now_us(&tc);
    TEST_ASSERT_EQUAL_INT(1, counter_reads);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_tick_clock_init_should_reject_a_bad_config);
    RUN_TEST(test_tick_clock_now_us_should_start_at_zero_and_count_ticks);
    RUN_TEST(test_tick_clock_init_should_fill_an_rsm_clock);
    RUN_TEST(test_tick_clock_now_us_should_handle_the_32_bit_wrap);
    RUN_TEST(test_tick_clock_now_us_should_handle_a_narrow_counter);
    RUN_TEST(test_tick_clock_now_us_should_be_exact_for_a_rate_that_does_not_divide_a_second);
    RUN_TEST(test_tick_clock_now_us_should_stay_exact_and_monotonic_over_many_wraps);
    RUN_TEST(test_tick_clock_now_us_should_read_the_counter_once_per_call);
    return UNITY_END();
}
