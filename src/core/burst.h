/* Odometry read in bursts: the one rule the aligner (src/localizer/sync.c)
 * and the revolution assembler (src/drivers/revolution.c) share. Internal
 * to the library. */
#ifndef RSM_BURST_H
#define RSM_BURST_H

#include <stdint.h>

/* Two odometry samples this close were read from a backlog: sent one after
 * the other, a packet takes longer on the line (a 12-byte one takes 1 ms at
 * 115200 Bd), and a robot reports at 10 to 50 Hz. */
#define RSM_BURST_US 2000u

/* A sample stamped `stamp` arrives after `newest`, which came after
 * `before`. Read within RSM_BURST_US of the newest, and far sooner (under
 * an eighth) than the newest came after the one before, it is the second of
 * a burst (a host reading its backlog): the newest was measured earlier
 * than its stamp says. Odometry comes at a steady rate, so the newest is put
 * halfway between the one before and this one (*newest changes; 1 is
 * returned). Samples stamped apart unevenly but further, or at the same time
 * (a log replayed with its own timing, a step sent in pieces), are taken as
 * they come (0). */
static inline int rsm_burst_restamp(uint64_t before, uint64_t *newest, uint64_t stamp)
{
    const uint64_t nw = *newest;
    if (nw >= before && stamp > nw && stamp - nw <= RSM_BURST_US && (stamp - nw) * 8u < nw - before) {
        *newest = before + (stamp - before) / 2u;
        return 1;
    }
    return 0;
}

#endif /* RSM_BURST_H */
