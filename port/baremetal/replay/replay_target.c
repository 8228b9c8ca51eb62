/* The replay firmware: the excerpt through the localizer on the target, with
 * the cost of every scan (T lines, in the board's cycle counter's unit), a
 * known loop that checks that unit (C line) and the stack used (M line).
 *
 *   C <n1> <counts1> <n2> <counts2>  counter ticks around known_loop(n1), (n2)
 *   M stack <bytes used> of <bytes> cycles_hz <rate>
 * then "rsm replay: done" and exit status 0 (semihosting on QEMU). */
#include <stdint.h>

#include "board.h"
#include "replay.h"
#include "rsm/status.h"

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

/* Exactly 2 n instructions (subs, bne) whatever the compiler does around it. */
static void __attribute__((noinline)) known_loop(uint32_t n)
{
    __asm__ volatile("1:\n\tsubs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
}

static uint32_t time_loop(uint32_t n)
{
    const uint32_t t0 = rsm_board_cycles();
    known_loop(n);
    return rsm_board_cycles() - t0;
}

/* State of the replay: static, the application's (the library keeps none). */
static rsm_replay_t fw_replay;
/* Start-up checks: .data copied, .bss zeroed. */
static volatile uint32_t fw_data_word = 0x600DDA7Au;
static volatile uint32_t fw_bss_word;

int main(void)
{
    rsm_replay_io_t io;
    int rc;
    rsm_board_init();
    io.write = target_write;
    io.ctx = NULL;
    io.clock_fn = target_clock;
    io.clock_ctx = NULL;
    rsm_replay_put_str(&io, "rsm replay on ");
    rsm_replay_put_str(&io, rsm_board_name);
    rsm_replay_put_str(&io, "\n");
    if (fw_data_word != 0x600DDA7Au || fw_bss_word != 0u) {
        rsm_replay_put_str(&io, "FAULT: start-up did not initialise .data or .bss\n");
        rsm_board_exit(1);
    }
    {
        const uint32_t n1 = 1000u;
        const uint32_t n2 = 101000u;
        const uint32_t c1 = time_loop(n1);
        const uint32_t c2 = time_loop(n2);
        rsm_replay_put_str(&io, "C ");
        rsm_replay_put_dec(&io, n1);
        rsm_replay_put_str(&io, " ");
        rsm_replay_put_dec(&io, c1);
        rsm_replay_put_str(&io, " ");
        rsm_replay_put_dec(&io, n2);
        rsm_replay_put_str(&io, " ");
        rsm_replay_put_dec(&io, c2);
        rsm_replay_put_str(&io, "\n");
    }
    rc = rsm_replay_run(&fw_replay, &io);
    if (rc != RSM_OK) {
        rsm_replay_put_str(&io, "FAULT: ");
        rsm_replay_put_str(&io, rsm_strerror(rc));
        rsm_replay_put_str(&io, "\n");
        rsm_board_exit(1);
    }
    rsm_replay_put_str(&io, "M stack ");
    rsm_replay_put_dec(&io, (uint32_t)rsm_stack_used());
    rsm_replay_put_str(&io, " of ");
    rsm_replay_put_dec(&io, (uint32_t)rsm_stack_size());
    rsm_replay_put_str(&io, " cycles_hz ");
    rsm_replay_put_dec(&io, rsm_board_cycles_hz());
    rsm_replay_put_str(&io, "\nrsm replay: done\n");
    rsm_board_exit(0);
    return 0;
}
