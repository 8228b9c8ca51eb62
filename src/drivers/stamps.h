/* Point stamps of the lidar drivers (ldlidar.c, slamtec.c). Internal to
 * the library. */
#ifndef RSM_STAMPS_H
#define RSM_STAMPS_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/lidar.h"

/* t - back, or 0 if back is larger. */
static inline uint64_t rsm_stamp_before(uint64_t t, uint64_t back)
{
    return t > back ? t - back : 0u;
}

/* Microseconds one byte takes on an 8N1 line at baud (0: unknown rate). */
static inline uint64_t rsm_byte_us(uint32_t baud)
{
    return baud > 0u ? 10000000u / baud : 0u;
}

/* Keeps point stamps in measuring order across packets: frames that came
 * in one read are stamped from one clock time, so a later frame's first
 * points could precede the earlier frame's last ones. Such a frame is moved
 * later, as a whole, to start at *last_us. Updates *last_us to the newest
 * stamp; returns 1 if the frame was moved. */
static inline int rsm_stamps_in_order(rsm_lidar_point_t *p, size_t n, uint64_t *last_us)
{
    int moved = 0;
    size_t i;
    if (n == 0u) {
        return 0;
    }
    if (p[0].stamp_us < *last_us) {
        const uint64_t shift = *last_us - p[0].stamp_us;
        for (i = 0; i < n; ++i) {
            p[i].stamp_us += shift;
        }
        moved = 1;
    }
    *last_us = p[n - 1u].stamp_us;
    return moved;
}

#endif /* RSM_STAMPS_H */
