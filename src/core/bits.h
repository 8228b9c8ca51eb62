/* Bit k of a byte array (bit k % 8 of byte k / 8): the per-point flags the
 * map writer passes around. Internal to the library. */
#ifndef RSM_BITS_H
#define RSM_BITS_H

#include <stddef.h>
#include <stdint.h>

static inline void rsm_bit_set(uint8_t *bits, size_t k)
{
    bits[k >> 3] = (uint8_t)((uint32_t)bits[k >> 3] | (1u << (k & 7u)));
}

static inline int rsm_bit_get(const uint8_t *bits, size_t k)
{
    return (int)(((uint32_t)bits[k >> 3] >> (k & 7u)) & 1u);
}

#endif /* RSM_BITS_H */
