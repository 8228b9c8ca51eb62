/* An in-memory rsm_link_t and a fake rsm_clock_t for driver tests.
 *
 * Time is simulated: the clock only moves when the driver reads (a read that
 * waits advances it, by at most the timeout it was given) or when a test
 * calls rsm_fakelink_advance. So a test can assert, from the clock alone,
 * that a driver never waited longer than it asked to.
 *
 * The far end is a scripted peer: a callback invoked with the bytes of every
 * host write (as the peer would see them), which answers by queueing bytes
 * with rsm_fakelink_send, each to arrive after a delay. Faults can be
 * injected into the peer -> host direction (dropped bytes, a flipped bit,
 * garbage, silence) and a "baud mismatch" garbles both directions while the
 * host's rate differs from the peer's. Both directions are logged.
 *
 * Test support only: one fakelink is a large struct (put it in a static),
 * nothing here is part of the library. */
#ifndef RSM_FAKELINK_H
#define RSM_FAKELINK_H

#include <stddef.h>
#include <stdint.h>

/* Relative path: rsm_testsupport is built without the library include
 * directory (it links no rsm variant, so the same objects serve the default
 * and the small-config tests). */
#include "rsm/hal.h"

#define RSM_FAKELINK_RX_CAP 16384u  /* bytes queued towards the host */
#define RSM_FAKELINK_LOG_CAP 16384u /* bytes logged per direction */
#define RSM_FAKELINK_MAX_WRITES 512u /* host writes remembered with their time */

typedef struct rsm_fakelink rsm_fakelink_t;

/* Called on every host write with the bytes the peer received (garbled if
 * the rates differ). It may call rsm_fakelink_send / _set_peer_baud. */
typedef void (*rsm_fakelink_peer_fn)(rsm_fakelink_t *fl, const uint8_t *data, size_t len,
                                     void *user);

/* One host write: when, and where its bytes are in host_log. */
typedef struct rsm_fakelink_write {
    uint64_t at_us;
    size_t offset;
    size_t len;
} rsm_fakelink_write_t;

struct rsm_fakelink {
    uint64_t now_us; /* the fake clock */

    /* peer -> host bytes not yet read, each with its arrival time */
    uint8_t rx[RSM_FAKELINK_RX_CAP];
    uint64_t rx_at[RSM_FAKELINK_RX_CAP];
    size_t rx_len;
    uint64_t last_arrival_us; /* arrivals stay in order */

    /* logs */
    uint8_t host_log[RSM_FAKELINK_LOG_CAP]; /* everything the host wrote */
    size_t host_log_len;
    uint8_t peer_log[RSM_FAKELINK_LOG_CAP]; /* everything the host could read */
    size_t peer_log_len;
    rsm_fakelink_write_t writes[RSM_FAKELINK_MAX_WRITES];
    size_t n_writes;

    /* the scripted peer */
    rsm_fakelink_peer_fn peer;
    void *peer_user;

    /* rates: host_baud follows set_baud; the peer talks at peer_baud */
    uint32_t host_baud;
    uint32_t peer_baud;
    int has_set_baud; /* 0: link.set_baud is NULL (no rate) */

    /* faults on the peer -> host direction */
    int silent;          /* peer callback not called, sends discarded */
    size_t drop_next;    /* discard this many of the next bytes sent */
    long flip_index;     /* flip bit 0 of the byte this many sends ahead; -1 none */

    /* statistics */
    uint32_t reads;
    uint32_t set_baud_calls;
    uint32_t flushes;
    uint32_t max_read_timeout_us;
    uint64_t max_read_wait_us; /* longest clock advance inside one read */
};

/* Resets fl: clock at start_us, rates 9600 on both sides, set_baud present,
 * no peer, no faults, empty logs. Fills link and clock (may be NULL) so that
 * they talk to fl. */
void rsm_fakelink_init(rsm_fakelink_t *fl, uint64_t start_us, rsm_link_t *link, rsm_clock_t *clock);

/* Installs the scripted peer (NULL for none). */
void rsm_fakelink_set_peer(rsm_fakelink_t *fl, rsm_fakelink_peer_fn peer, void *user);

/* Queues bytes from the peer, arriving delay_us after now (and not before
 * bytes queued earlier). Applies the injected faults and the baud garbling.
 * Bytes beyond the queue capacity are lost. */
void rsm_fakelink_send(rsm_fakelink_t *fl, const uint8_t *data, size_t len, uint32_t delay_us);

/* Queues bytes exactly as given (no faults, no garbling): line noise. */
void rsm_fakelink_inject(rsm_fakelink_t *fl, const uint8_t *data, size_t len, uint32_t delay_us);

/* The peer's rate; while it differs from the host's, bytes are garbled. */
void rsm_fakelink_set_peer_baud(rsm_fakelink_t *fl, uint32_t baud);

/* Moves the clock forward (time spent outside the driver). */
void rsm_fakelink_advance(rsm_fakelink_t *fl, uint64_t us);

/* Counts occurrences of pattern (len bytes) in the host log, from offset. */
size_t rsm_fakelink_count_host(const rsm_fakelink_t *fl, size_t from, const uint8_t *pattern,
                               size_t len);

/* Index of the first host write at or after write index from whose bytes
 * equal pattern; -1 if none. */
long rsm_fakelink_find_write(const rsm_fakelink_t *fl, size_t from, const uint8_t *pattern,
                             size_t len);

#endif /* RSM_FAKELINK_H */
