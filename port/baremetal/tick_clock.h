/* Bare-metal clock: a free-running up-counter of up to 32 bits (a tick count
 * incremented by SysTick, a 32-bit timer, or the DWT cycle counter) extended
 * to a 64-bit microsecond clock that fills an rsm_clock_t.
 *
 * The counter may wrap as often as it likes, as long as rsm_tick_clock_now_us
 * (or the rsm_clock_t it fills) is called at least once per wrap period:
 *   1 kHz SysTick tick count, 32 bits:   49.7 days
 *   1 MHz timer, 32 bits:                71.6 minutes
 *   168 MHz DWT->CYCCNT, 32 bits:        25.5 seconds
 *   1 MHz timer, 16 bits:                65.5 milliseconds
 * Every link read that waits calls the clock, so a main loop that services
 * its links meets this easily; an idle firmware must still call it.
 *
 * The 64-bit result cannot overflow in practice (2^64 us is 584,000 years):
 * whole seconds and the sub-second remainder are kept apart, so no product
 * ever exceeds 64 bits and the arithmetic is exact for any tick rate.
 *
 * Not ISR-safe: now_us updates the state, so call it from one context only
 * (the main loop). An interrupt that needs a time stamp should latch the raw
 * counter and let the main loop convert it. */
#ifndef RSM_TICK_CLOCK_H
#define RSM_TICK_CLOCK_H

#include <stdint.h>

#include "rsm/hal.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Returns the current raw counter value (only the low counter_bits are
 * used). Must not block; typically a single volatile register or variable
 * read. hw is the config's hw. */
typedef uint32_t (*rsm_tick_read_fn)(void *hw);

/* Constant description of the counter; kept by pointer (make it static const). */
typedef struct rsm_tick_clock_config {
    rsm_tick_read_fn read_ticks; /* required */
    void *hw;                    /* passed to read_ticks; not dereferenced */
    uint32_t tick_hz;            /* counter increments per second; required, > 0 */
    uint8_t counter_bits;        /* counter width, 1..32; 0 means 32 */
} rsm_tick_clock_config_t;

/* Mutable state: treat as private. */
typedef struct rsm_tick_clock {
    const rsm_tick_clock_config_t *cfg; /* kept by pointer */
    uint32_t mask;                      /* 2^counter_bits - 1 */
    uint32_t last_ticks;                /* counter value at the previous call */
    uint32_t sub_ticks;                 /* ticks past the last whole second, < tick_hz */
    uint64_t seconds;                   /* whole seconds since init */
} rsm_tick_clock_t;

/* Validates cfg (read_ticks set, tick_hz > 0, counter_bits <= 32), latches
 * the counter's current value as time zero and, if clock is not NULL, fills
 * *clock so that clock->now_us(clock->ctx) calls rsm_tick_clock_now_us on tc
 * (clock->ctx points at tc, so tc must outlive it). Returns RSM_OK or
 * RSM_ERR_INVAL (tc and *clock untouched). Not ISR-safe. */
int rsm_tick_clock_init(rsm_tick_clock_t *tc, const rsm_tick_clock_config_t *cfg,
                        rsm_clock_t *clock);

/* Microseconds since rsm_tick_clock_init, rounded down; monotonic as long as
 * it is called at least once per counter wrap period (see above). Main-loop
 * context only. */
uint64_t rsm_tick_clock_now_us(rsm_tick_clock_t *tc);

#ifdef __cplusplus
}
#endif

#endif /* RSM_TICK_CLOCK_H */
