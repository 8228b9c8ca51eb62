/* The replay firmware: the excerpt through the localizer on the target, with
 * the cost of every scan (T lines, in the board's cycle counter's unit), a
 * known loop that checks that unit (C line) and the stack used (M line).
 *
 *   C <n1> <counts1> <n2> <counts2>  counter ticks around a known loop (calib.h)
 *   M stack <bytes used> of <bytes> cycles_hz <rate>
 * then "rsm replay: done" and exit status 0 (semihosting on QEMU). */
#include <stdint.h>

#include "board.h"
#include "calib.h"
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
    rsm_calib_put(&io);
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
