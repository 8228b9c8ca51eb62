#include "tick_clock.h"

#include <stddef.h>

#include "rsm/status.h"

static uint64_t tick_clock_now_cb(void *ctx)
{
    return rsm_tick_clock_now_us((rsm_tick_clock_t *)ctx);
}

int rsm_tick_clock_init(rsm_tick_clock_t *tc, const rsm_tick_clock_config_t *cfg,
                        rsm_clock_t *clock)
{
    uint32_t bits;
    if (tc == NULL || cfg == NULL || cfg->read_ticks == NULL || cfg->tick_hz == 0u ||
        cfg->counter_bits > 32u) {
        return RSM_ERR_INVAL;
    }
    bits = cfg->counter_bits == 0u ? 32u : (uint32_t)cfg->counter_bits;
    tc->cfg = cfg;
    /* 32 is special-cased: shifting a 32-bit value by 32 is undefined. */
    tc->mask = bits == 32u ? UINT32_MAX : (uint32_t)((1u << bits) - 1u);
    tc->last_ticks = cfg->read_ticks(cfg->hw) & tc->mask;
    tc->sub_ticks = 0u;
    tc->seconds = 0u;
    if (clock != NULL) {
        clock->now_us = tick_clock_now_cb;
        clock->ctx = tc;
    }
    return RSM_OK;
}

uint64_t rsm_tick_clock_now_us(rsm_tick_clock_t *tc)
{
    const uint32_t hz = tc->cfg->tick_hz;
    const uint32_t now = tc->cfg->read_ticks(tc->cfg->hw) & tc->mask;
    /* Modular difference: correct across one wrap of the counter. */
    const uint32_t delta = (now - tc->last_ticks) & tc->mask;
    const uint32_t rem = delta % hz;
    tc->last_ticks = now;
    tc->seconds += delta / hz;
    /* sub_ticks + rem >= hz, written so that it cannot overflow 32 bits even
     * for tick rates above 2^31 Hz. */
    if (rem >= hz - tc->sub_ticks) {
        tc->sub_ticks = rem - (hz - tc->sub_ticks);
        tc->seconds += 1u;
    } else {
        tc->sub_ticks += rem;
    }
    /* sub_ticks < hz, so the fraction is below one second and the product
     * below 2^52: exact. */
    return tc->seconds * 1000000u + ((uint64_t)tc->sub_ticks * 1000000u) / hz;
}
