/* Little-endian fields of the wire formats (LD06, RPLIDAR) and a
 * receiver helper. Internal to the library. */
#ifndef RSM_BYTES_H
#define RSM_BYTES_H

#include <stddef.h>
#include <stdint.h>

static inline uint16_t rsm_get_u16le(const uint8_t *p)
{
    return (uint16_t)((uint32_t)p[0] | ((uint32_t)p[1] << 8));
}

static inline uint32_t rsm_get_u32le(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static inline void rsm_put_u16le(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}

/* A receiver drops the n bytes of its partial frame: they count as
 * skipped, and as one truncated frame if there were any. Returns n. */
static inline int rsm_drop_partial(size_t *n, uint32_t *skipped, uint32_t *truncated)
{
    const size_t had = *n;
    if (had > 0u) {
        *truncated += 1u;
        *skipped += (uint32_t)had;
    }
    *n = 0;
    return (int)had;
}

#endif /* RSM_BYTES_H */
