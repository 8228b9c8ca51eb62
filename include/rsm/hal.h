/* The hardware abstraction layer: a byte link and a clock, each a struct of
 * function pointers plus a user context pointer.
 *
 * The core and the codecs never touch a device. A driver (ARIA, LMS) is given
 * an rsm_link_t and an rsm_clock_t by the application, which fills them from a
 * port (port/posix: serial devices, ptys, files; port/baremetal: a UART ring
 * buffer and a tick clock) or from a test fake.
 *
 * Conventions for every callback:
 *   - ctx is the link's or clock's own ctx member, passed back untouched; the
 *     HAL never dereferences it.
 *   - Failures are negative rsm_status_t codes (RSM_ERR_IO, RSM_ERR_TIMEOUT,
 *     ...); counts are non-negative and never exceed the size passed in.
 *   - Buffers are borrowed for the duration of the call only; no callback
 *     keeps a pointer to them after it returns.
 *   - Callbacks are trusted code (see docs/robustness.md); the bytes they
 *     deliver are not.
 *
 * Callers should go through the rsm_link_* and rsm_clock_* helpers below:
 * they check for missing optional operations (RSM_ERR_NOSYS) and bad
 * arguments (RSM_ERR_INVAL) so that drivers need not. */
#ifndef RSM_HAL_H
#define RSM_HAL_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A bidirectional byte stream (a serial port, a UART, a replayed capture). */
typedef struct rsm_link {
    /* Required. Reads up to cap bytes into buf. Returns as soon as at least
     * one byte is available (it may return fewer than cap), or 0 once
     * timeout_us microseconds have passed with nothing received
     * (timeout_us == 0 polls: returns what is already buffered, or 0).
     * Negative rsm status on a link error (RSM_ERR_IO); end of a finite
     * stream (a capture file) is reported as RSM_ERR_IO as well, so that a
     * driver never waits forever on a file. Blocks for at most timeout_us
     * plus the implementation's scheduling slack. */
    int (*read)(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us);

    /* Required. Writes up to len bytes from buf. Returns the number written
     * (1..len; a short write is allowed), 0 if nothing could be written for
     * now (the implementation's own transmit timeout expired), or a negative
     * rsm status. May block until the bytes are handed to the hardware. */
    int (*write)(void *ctx, const uint8_t *buf, size_t len);

    /* Optional (NULL if the link has no baud rate, e.g. a file or a USB
     * CDC port). Changes the line rate, in bits per second; pending output
     * is sent at the old rate first where the hardware allows. Returns
     * RSM_OK, RSM_ERR_RANGE if the rate is not supported, or another
     * negative status. */
    int (*set_baud)(void *ctx, uint32_t baud);

    /* Optional (NULL if the link cannot discard input). Discards every byte
     * received but not yet read. Returns RSM_OK or a negative status. */
    int (*flush)(void *ctx);

    /* User context passed to every callback; may be NULL. Not owned: it must
     * stay valid as long as the link is used. */
    void *ctx;
} rsm_link_t;

/* A monotonic clock. */
typedef struct rsm_clock {
    /* Required. Microseconds since an arbitrary epoch (typically power-up);
     * never decreases. Must not block. Whether it may be called from an
     * interrupt is up to the implementation (the bare-metal tick clock may
     * not: see port/baremetal/tick_clock.h). */
    uint64_t (*now_us)(void *ctx);

    /* User context passed to now_us; may be NULL. Not owned. */
    void *ctx;
} rsm_clock_t;

/* ---- helpers ---------------------------------------------------------------
 * All of them are stateless: reentrant for distinct links, and exactly as
 * ISR-safe and thread-safe as the callbacks they call. None keeps a pointer
 * to its arguments after it returns. */

/* Reads up to cap bytes with the link's read semantics (see rsm_link_t.read).
 * cap is clamped to INT_MAX. Returns the byte count (0 on timeout), or:
 *   RSM_ERR_INVAL  link is NULL, or buf is NULL while cap > 0;
 *   RSM_ERR_NOSYS  link->read is NULL;
 *   RSM_ERR_IO     the callback claimed more bytes than cap (a broken port);
 *   any negative status the callback returned.
 * Bytes in buf beyond the returned count are unspecified. */
int rsm_link_read(const rsm_link_t *link, uint8_t *buf, size_t cap, uint32_t timeout_us);

/* Writes all len bytes, calling link->write until everything is written.
 * Returns RSM_OK when all bytes were accepted, or:
 *   RSM_ERR_INVAL    link is NULL, or buf is NULL while len > 0;
 *   RSM_ERR_NOSYS    link->write is NULL;
 *   RSM_ERR_TIMEOUT  a write call made no progress (returned 0);
 *   RSM_ERR_IO       the callback claimed more bytes than it was given;
 *   any negative status the callback returned.
 * If written is not NULL it receives the number of bytes accepted before the
 * function returned (len on RSM_OK, possibly fewer on an error). Blocks as
 * long as the callback blocks, at most once per chunk. */
int rsm_link_write_all(const rsm_link_t *link, const uint8_t *buf, size_t len, size_t *written);

/* Changes the line rate. RSM_OK, RSM_ERR_INVAL (link NULL or baud 0),
 * RSM_ERR_NOSYS (link->set_baud is NULL) or the callback's status. */
int rsm_link_set_baud(const rsm_link_t *link, uint32_t baud);

/* Discards pending input. RSM_OK, RSM_ERR_INVAL (link NULL), RSM_ERR_NOSYS
 * (link->flush is NULL; a caller that only wants a clean start may then
 * read with a zero timeout until nothing is left) or the callback's status. */
int rsm_link_flush(const rsm_link_t *link);

/* Writes the clock's current time, in microseconds, to *now_us. RSM_OK,
 * RSM_ERR_INVAL (clock or now_us NULL; *now_us untouched) or RSM_ERR_NOSYS
 * (clock->now_us is NULL; *now_us untouched). */
int rsm_clock_now_us(const rsm_clock_t *clock, uint64_t *now_us);

#ifdef __cplusplus
}
#endif

#endif /* RSM_HAL_H */
