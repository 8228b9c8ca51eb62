/* The replay: feeds a localizer the compiled-in excerpt (replay_data.h) and
 * writes its trajectory, the same source on the host and on the target, so
 * that the two outputs can be compared bit for bit (tests: m4.*).
 *
 * Output, one line each, numbers in hexadecimal where they are floats' bits:
 *   P <scan> <outcome> <x> <y> <theta>    pose after each scan (IEEE bits)
 *   T <scan> <step> <stage 0> .. <stage 9> <odo>  the report's clock_fn times
 *                                         (when a clock is given), decimal, in
 *                                         its unit; odo: the encoder steps
 *                                         (rsm_localizer_ticks) since the
 *                                         previous scan, outside step
 *   E scans <n> accepted <n> motions <n>   counters at the end */
#ifndef RSM_REPLAY_H
#define RSM_REPLAY_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/localizer.h"
#include "rsm/scan.h"

typedef struct rsm_replay_io {
    void (*write)(void *ctx, const char *s, size_t n); /* required */
    void *ctx;
    uint32_t (*clock_fn)(void *clock_ctx);             /* optional: T lines */
    void *clock_ctx;
} rsm_replay_io_t;

/* Caller-owned state (static in the images: about as large as the localizer). */
typedef struct rsm_replay {
    rsm_localizer_config_t cfg;
    rsm_localizer_t loc;
    rsm_scan_t scan;
    rsm_localizer_report_t rep;
} rsm_replay_t;

/* Runs the whole excerpt with the default configuration; returns RSM_OK or
 * the first error of rsm_localizer_init. */
int rsm_replay_run(rsm_replay_t *r, const rsm_replay_io_t *io);

/* Line helpers, for the images' own lines. */
void rsm_replay_put_str(const rsm_replay_io_t *io, const char *s);
void rsm_replay_put_dec(const rsm_replay_io_t *io, uint32_t v);
void rsm_replay_put_hex(const rsm_replay_io_t *io, uint32_t v);

#endif /* RSM_REPLAY_H */
