#include "calib.h"

#include <stdint.h>

#include "board.h"

/* Exactly 2 n instructions (subs, bne) whatever the compiler does around it. */
static void __attribute__((noinline)) known_loop(uint32_t n)
{
#if defined(__ARM_ARCH_6M__)
    /* GCC writes ARMv6-M code in the divided syntax, whose Thumb-1 sub sets
     * the flags. */
    __asm__ volatile("1:\n\tsub %0, #1\n\tbne 1b" : "+l"(n) : : "cc");
#else
    __asm__ volatile("1:\n\tsubs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
#endif
}

static uint32_t time_loop(uint32_t n)
{
    const uint32_t t0 = rsm_board_cycles();
    known_loop(n);
    return rsm_board_cycles() - t0;
}

void rsm_calib_put(const rsm_replay_io_t *io)
{
    /* Two lengths: their difference cancels the call and the counter reads. */
    const uint32_t n1 = 1000u;
    const uint32_t n2 = 101000u;
    const uint32_t c1 = time_loop(n1);
    const uint32_t c2 = time_loop(n2);
    rsm_replay_put_str(io, "C ");
    rsm_replay_put_dec(io, n1);
    rsm_replay_put_str(io, " ");
    rsm_replay_put_dec(io, c1);
    rsm_replay_put_str(io, " ");
    rsm_replay_put_dec(io, n2);
    rsm_replay_put_str(io, " ");
    rsm_replay_put_dec(io, c2);
    rsm_replay_put_str(io, "\n");
}
