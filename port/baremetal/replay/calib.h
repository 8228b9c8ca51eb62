/* The check of the board's cycle counter, for the target images that time
 * scans (replay_target.c, mapflash_target.c): the counter's ticks around a
 * known loop of exactly 2 n instructions, twice, on one line
 *   C <n1> <ticks1> <n2> <ticks2>
 * against which tools/rsm_tools/m4.py checks its model of the counter (one
 * tick per 40 / 2^shift instructions under QEMU's -icount) before turning
 * the images' ticks into instructions. Target only. */
#ifndef RSM_CALIB_H
#define RSM_CALIB_H

#include "replay.h"

/* Times the loop at n1 = 1000 and n2 = 101000 and writes the C line. */
void rsm_calib_put(const rsm_replay_io_t *io);

#endif /* RSM_CALIB_H */
