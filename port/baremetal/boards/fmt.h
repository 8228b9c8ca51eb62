/* Number formatting for the firmware images' console lines (no printf: it
 * would pull in most of newlib's stdio). Header-only, also used on the host by
 * the replay, whose output must be the same text on both. */
#ifndef RSM_BOARD_FMT_H
#define RSM_BOARD_FMT_H

#include <stddef.h>
#include <stdint.h>

#define RSM_FMT_DEC_MAX 10u /* digits of the largest uint32_t */

/* Writes v in decimal at the end of buf[RSM_FMT_DEC_MAX]; returns the index
 * of its first digit (the digits run to the end of buf). */
static inline size_t rsm_fmt_dec(char buf[RSM_FMT_DEC_MAX], uint32_t v)
{
    size_t n = RSM_FMT_DEC_MAX;
    do {
        buf[--n] = (char)('0' + (char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    return n;
}

/* Writes v as 8 lower-case hexadecimal digits into buf. */
static inline void rsm_fmt_hex(char buf[8], uint32_t v)
{
    int i;
    for (i = 0; i < 8; ++i) {
        buf[i] = "0123456789abcdef"[(v >> (28 - 4 * i)) & 0xFu];
    }
}

#endif /* RSM_BOARD_FMT_H */
