/* The map-in-flash firmware (mapflash.h) on mps2-an386: the "flash" is a
 * region of SSRAM1 that no loadable segment of the image covers
 * (boards/mps2_an386/mapflash.ld), so that QEMU's system reset, which
 * loads the image's segments again, leaves it as the previous boot wrote
 * it, and the start-up code, which zeroes only .bss and .ccm, does too.
 * After saving, the firmware resets the system (SYSRESETREQ) and the next
 * boot finds the map there. Each boot checks the cycle counter against a
 * known loop (the C line, calib.h), whose ticks time the global search's
 * scans. */
#include <stdint.h>

#include "board.h"
#include "calib.h"
#include "mapflash.h"

/* The region's bytes: a NOLOAD section, never zeroed by anyone; at power-up
 * they are whatever the memory holds, which the load refuses. */
uint32_t rsm_mapflash_words[RSM_MAPFLASH_REGION / 4u] __attribute__((section(".mapflash")));

/* Application Interrupt and Reset Control (ARMv7-M ARM, B3.2.6): the
 * write key, the priority grouping kept, SYSRESETREQ. */
#define AIRCR (*(volatile uint32_t *)0xE000ED0Cu)
#define AIRCR_VECTKEY (0x05FAu << 16)
#define AIRCR_PRIGROUP (7u << 8)
#define AIRCR_SYSRESETREQ (1u << 2)

static void system_reset(void)
{
    __asm__ volatile("dsb" ::: "memory"); /* the region's writes done first */
    AIRCR = AIRCR_VECTKEY | (AIRCR & AIRCR_PRIGROUP) | AIRCR_SYSRESETREQ;
    __asm__ volatile("dsb" ::: "memory");
    for (;;) { /* the reset takes effect */
    }
}

static void target_write(void *ctx, const char *s, size_t n)
{
    (void)ctx;
    rsm_board_console_write(s, n);
}

static uint32_t target_clock(void *ctx)
{
    (void)ctx;
    return rsm_board_cycles();
}

static rsm_mapflash_t fw_mapflash;

int main(void)
{
    rsm_mapflash_region_t flash;
    rsm_replay_io_t io;
    rsm_mapflash_result_t res;
    rsm_board_init();
    io.write = target_write;
    io.ctx = NULL;
    io.clock_fn = target_clock;
    io.clock_ctx = NULL;
    flash.bytes = (uint8_t *)rsm_mapflash_words;
    flash.size = (uint32_t)sizeof rsm_mapflash_words;
    rsm_replay_put_str(&io, RSM_MAPFLASH_NAME " on ");
    rsm_replay_put_str(&io, rsm_board_name);
    rsm_replay_put_str(&io, ", region at 0x");
    rsm_replay_put_hex(&io, (uint32_t)(uintptr_t)rsm_mapflash_words);
    rsm_replay_put_str(&io, "\n");
    rsm_calib_put(&io);
    res = rsm_mapflash_boot(&fw_mapflash, &flash, &io);
    if (res == RSM_MAPFLASH_RESET) {
        system_reset();
    }
    rsm_board_exit(res == RSM_MAPFLASH_DONE ? 0 : 1);
    return 0;
}
