/* The poll cycle of a link driver, on the HAL (rsm/hal.h): what the P3-DX,
 * LMS and lidar drivers share, and what a new driver written on the HAL
 * uses. A port (a link and a clock) needs only rsm/hal.h. */
#ifndef RSM_LINK_POLL_H
#define RSM_LINK_POLL_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/hal.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- the poll cycle of a link driver -----------------------------------------
 * The drivers (rsm/p3dx.h, rsm/sicklms.h) are non-blocking state machines
 * run by a poll function, and every poll is the same cycle:
 *   1. examine the bytes left over from the previous read (a poll stops at
 *      the first event, so a read can hold more than one frame);
 *   2. run the timers;
 *   3. read the link once, waiting no longer than the read timeout and not
 *      past the next deadline;
 *   4. examine what arrived; or, when nothing did and the line has been
 *      silent for the inter-byte timeout, let the codec abandon a partial
 *      frame;
 *   5. run the timers again;
 * stopping as soon as a step produces an event. rsm_link_poll is that cycle;
 * a driver supplies the steps as callbacks (rsm_link_poll_ops_t) and keeps
 * one rsm_link_rx_t in its state. Usable by any driver written on the HAL. */

/* Receive state of one driver's link: the link, the clock, the two
 * timeouts, and the chunk of bytes read last. Caller owned (inside the
 * driver's state); buf, off, len, stamp_us and last_rx_us are read and
 * written by the driver's callbacks, the rest is set by rsm_link_rx_init. */
typedef struct rsm_link_rx {
    const rsm_link_t *link;   /* kept by pointer: must outlive the driver */
    const rsm_clock_t *clock; /* kept by pointer */
    uint32_t read_timeout_us; /* longest wait inside one poll (0: never wait,
                                 take what has arrived) */
    uint32_t byte_timeout_us; /* silence after which a partial frame is
                                 abandoned (0: at the first empty read) */
    uint8_t buf[RSM_LINK_RX_CHUNK];
    size_t off;               /* buf[off..len) not examined yet */
    size_t len;               /* bytes of the last read in buf */
    uint64_t stamp_us;        /* clock time right after the read that filled buf */
    uint64_t last_rx_us;      /* clock time of the last read that returned bytes */
    uint64_t bytes;           /* bytes received since rsm_link_rx_init */
} rsm_link_rx_t;

/* The steps of one driver, called with the driver's state pointer drv.
 * Each returns 1 once it has produced an event for the caller (the cycle
 * then stops), 0 otherwise; where the event goes is the driver's business.
 * All are required. */
typedef struct rsm_link_poll_ops {
    /* Examines rx->buf[rx->off..rx->len), advancing rx->off, until an event
     * or until the codec can complete nothing more (called also when no
     * bytes are left: a codec may hold complete frames of its own). now_us
     * is the clock time of this step. */
    int (*drain)(void *drv, uint64_t now_us);
    /* Runs the timers due at now_us. */
    int (*timers)(void *drv, uint64_t now_us);
    /* Microseconds from now_us until the next timer is due (0 if due now,
     * UINT64_MAX if none is set). Must not change drv. */
    uint64_t (*until_due)(const void *drv, uint64_t now_us);
    /* A read returned nothing and no byte has come for byte_timeout_us:
     * abandon a partial frame and examine what it held. */
    int (*silence)(void *drv, uint64_t now_us);
} rsm_link_poll_ops_t;

/* Sets *rx up for link and clock (kept by pointer) with an empty chunk and
 * last_rx_us 0. read_timeout_us 0 makes every poll non-blocking (the
 * caller waits for all its links at once, up to the drivers' next
 * deadlines). Returns RSM_OK, or RSM_ERR_INVAL for NULL pointers, a link
 * without read or write, or a clock without now_us (*rx untouched).
 * Nothing is read or sent. A macro, as rsm_localizer_init: it passes the
 * caller's sizeof(rsm_link_rx_t) and RSM_CONFIG_FINGERPRINT, so that a
 * caller compiled with other capacities than the library
 * (RSM_LINK_RX_CHUNK sizes the chunk) gets RSM_ERR_CONFIG, *rx untouched. */
#define rsm_link_rx_init(rx, link, clock, read_timeout_us, byte_timeout_us)                                  \
    rsm_link_rx_init_checked((rx), sizeof(rsm_link_rx_t), (unsigned long)RSM_CONFIG_FINGERPRINT, (link), (clock), \
                             (read_timeout_us), (byte_timeout_us))

int rsm_link_rx_init_checked(rsm_link_rx_t *rx, size_t rx_size, unsigned long fingerprint, const rsm_link_t *link,
                             const rsm_clock_t *clock, uint32_t read_timeout_us, uint32_t byte_timeout_us);

/* Discards received input: the link's pending bytes (rsm_link_flush, where
 * the link can) and the rest of the chunk. Safe to call from a callback of
 * rsm_link_poll (the chunk is then simply empty). No-op for NULL. */
void rsm_link_rx_drop(rsm_link_rx_t *rx);

/* The clock's current time, in microseconds; 0 for NULL or a clock that
 * cannot be read (rsm_clock_now_us failed). */
uint64_t rsm_link_rx_now(const rsm_link_rx_t *rx);

/* Clock time at which driver drv next needs rsm_link_poll whatever
 * arrives: now when bytes of the chunk are still unexamined, else now plus
 * ops->until_due (UINT64_MAX when no timer is set, or for NULL arguments).
 * A partial frame is abandoned at the first poll after byte_timeout_us of
 * silence, not at a deadline of its own. Changes nothing. */
uint64_t rsm_link_next_deadline(const rsm_link_rx_t *rx, const rsm_link_poll_ops_t *ops, const void *drv);

/* Runs the cycle above once for driver drv. The one read asks for at most
 * RSM_LINK_RX_CHUNK bytes with a timeout of min(read_timeout_us,
 * ops->until_due(...)); bytes read are stamped with the clock time right
 * after the read. Returns RSM_OK (whether or not an event came),
 * RSM_ERR_INVAL for NULL arguments or a NULL callback, or the negative
 * status of a failed read (the cycle then ends there; the driver stays
 * usable). Blocks no longer than the read timeout plus whatever the
 * callbacks spend (link writes). Not reentrant for one rx. */
int rsm_link_poll(rsm_link_rx_t *rx, const rsm_link_poll_ops_t *ops, void *drv);

#ifdef __cplusplus
}
#endif

#endif /* RSM_LINK_POLL_H */
