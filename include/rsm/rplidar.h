/* Slamtec RPLIDAR serial protocol codec: request encoders, an incremental
 * receiver and the answer decoders. Pure code: no I/O, no heap, no global
 * state. The driver that owns the serial port (rsm/slamtec.h) sits on
 * top of it. Facts and sources: docs/reference/lidars.md section 2.
 *
 * Requests (host -> sensor):
 *     A5 cmd                                   (no payload)
 *     A5 cmd size payload[size] checksum       (checksum = XOR of every
 *                                               byte before it, A5 included)
 * Answers (sensor -> host) start with a 7-byte descriptor
 *     A5 5A len_mode(u32 LE: bits 0-29 length, bits 30-31 send mode) type
 * followed by one answer of `length` bytes (send mode 0), or by answers of
 * `length` bytes until the next request (send mode 1: the scan streams).
 * Multi-byte fields are LSB first.
 *
 * Answers decoded here:
 *     0x04 device info, 20 bytes: model, firmware minor, firmware major,
 *          hardware, serial number[16]
 *     0x06 health, 3 bytes: status (0 good, 1 warning, 2 error), error code
 *     0x15 sample rate, 4 bytes: standard and express sample time, us
 *     0x81 standard scan node, 5 bytes, streamed:
 *          byte 0: bit 0 S (first point of a new turn), bit 1 not-S,
 *                  bits 2-7 quality
 *          byte 1-2: bit 0 check bit (always 1), bits 1-15 angle, 1/64 deg
 *          byte 3-4: distance, 1/4 mm (0: no measurement)
 *     0x82 express capsule, 84 bytes, streamed:
 *          byte 0: bits 4-7 sync 0xA, bits 0-3 checksum low nibble
 *          byte 1: bits 4-7 sync 0x5, bits 0-3 checksum high nibble
 *          byte 2-3: bits 0-14 start angle (1/64 deg), bit 15 new turn
 *          16 cabins of 5 bytes: distance 1 (u16: bits 2-15 mm, bits 0-1 =
 *          bits 4-5 of offset 1), distance 2 (same with offset 2), a byte
 *          with offset 1 bits 0-3 (low nibble) and offset 2 bits 0-3 (high
 *          nibble); offsets in 1/8 deg
 *          checksum = XOR of bytes 2-83
 *     0x85 dense capsule, 84 bytes, streamed: bytes 0-3 as 0x82, then 40
 *          distances (u16, mm)
 * A capsule's samples lie between its start angle and the next capsule's:
 * sample k of n (32 express, 40 dense) is at
 *     start + k * (next_start - start) / n  [- offset_k for express]
 * so the samples of a capsule are published when the next one arrives.
 * Angles grow clockwise seen from above. */
#ifndef RSM_RPLIDAR_H
#define RSM_RPLIDAR_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/lidar.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RSM_RPLIDAR_SYNC1 0xA5u
#define RSM_RPLIDAR_SYNC2 0x5Au

/* Request codes. */
#define RSM_RPLIDAR_CMD_STOP 0x25u         /* stop scanning; no answer */
#define RSM_RPLIDAR_CMD_SCAN 0x20u         /* standard scan (0x81 nodes) */
#define RSM_RPLIDAR_CMD_FORCE_SCAN 0x21u
#define RSM_RPLIDAR_CMD_RESET 0x40u        /* reboot the core; no answer */
#define RSM_RPLIDAR_CMD_GET_INFO 0x50u     /* answer 0x04 */
#define RSM_RPLIDAR_CMD_GET_HEALTH 0x52u   /* answer 0x06 */
#define RSM_RPLIDAR_CMD_GET_SAMPLERATE 0x59u /* answer 0x15 */
#define RSM_RPLIDAR_CMD_EXPRESS_SCAN 0x82u /* answer 0x82 or 0x85 capsules */
#define RSM_RPLIDAR_CMD_MOTOR_SPEED 0xA8u  /* motor speed in rpm (C1, S-series) */
#define RSM_RPLIDAR_CMD_MOTOR_PWM 0xF0u    /* motor PWM (A2/A3 accessory board) */

/* Answer types. */
#define RSM_RPLIDAR_ANS_INFO 0x04u
#define RSM_RPLIDAR_ANS_HEALTH 0x06u
#define RSM_RPLIDAR_ANS_SAMPLERATE 0x15u
#define RSM_RPLIDAR_ANS_NODE 0x81u
#define RSM_RPLIDAR_ANS_CAPSULE 0x82u
#define RSM_RPLIDAR_ANS_DENSE 0x85u

#define RSM_RPLIDAR_DESCRIPTOR 7u   /* bytes */
#define RSM_RPLIDAR_NODE 5u
#define RSM_RPLIDAR_CAPSULE 84u     /* express and dense alike */
#define RSM_RPLIDAR_MAX_FRAME 84u   /* longest answer the receiver holds */
#define RSM_RPLIDAR_MAX_POINTS 40u  /* points in one event (a dense capsule) */
#define RSM_RPLIDAR_MAX_PAYLOAD 32u /* longest request payload encoded */
/* Capsules whose start angles differ by more than this (1/64 deg) are not
 * neighbours: the first one's samples are dropped (counted). */
#define RSM_RPLIDAR_MAX_CAPSULE_SPAN_Q6 (180u * 64u)

/* Health status codes. */
#define RSM_RPLIDAR_HEALTH_GOOD 0u
#define RSM_RPLIDAR_HEALTH_WARNING 1u
#define RSM_RPLIDAR_HEALTH_ERROR 2u

/* ---- encoders ---------------------------------------------------------
 * Each writes one request into out[0..cap) and returns its length (> 0);
 * RSM_ERR_INVAL for NULL out or a bad argument, RSM_ERR_NOMEM if cap is
 * too small; nothing is written on error. Pure, reentrant. */

/* Generic: A5 cmd, plus size, payload and checksum when n > 0 (n at most
 * RSM_RPLIDAR_MAX_PAYLOAD; payload may be NULL only if n is 0). */
int rsm_rplidar_encode_request(uint8_t *out, size_t cap, uint8_t cmd, const uint8_t *payload,
                               size_t n);

/* EXPRESS_SCAN in the default (legacy) working mode: payload 5 zero bytes
 * (mode, flags u16, parameter u16). 9 bytes. */
int rsm_rplidar_encode_express_scan(uint8_t *out, size_t cap);

/* Motor command with one u16 payload: cmd RSM_RPLIDAR_CMD_MOTOR_SPEED (rpm)
 * or RSM_RPLIDAR_CMD_MOTOR_PWM (duty, 0 stops), else RSM_ERR_INVAL. 6 bytes. */
int rsm_rplidar_encode_motor(uint8_t *out, size_t cap, uint8_t cmd, uint16_t value);

/* An answer descriptor (for simulators and tests): length below 2^30, mode
 * 0 or 1. 7 bytes. */
int rsm_rplidar_encode_descriptor(uint8_t *out, size_t cap, uint32_t length, uint8_t mode,
                                  uint8_t type);

/* ---- decoded answers -------------------------------------------------- */

typedef struct rsm_rplidar_info {
    uint8_t model;
    uint8_t firmware_minor;
    uint8_t firmware_major;
    uint8_t hardware;
    uint8_t serial[16];
} rsm_rplidar_info_t;

typedef struct rsm_rplidar_health {
    uint8_t status;      /* RSM_RPLIDAR_HEALTH_* (other values passed on) */
    uint16_t error_code;
} rsm_rplidar_health_t;

typedef struct rsm_rplidar_samplerate {
    uint16_t standard_us; /* time of one standard-scan sample */
    uint16_t express_us;  /* time of one express-scan sample */
} rsm_rplidar_samplerate_t;

/* ---- incremental receiver --------------------------------------------- */

typedef enum rsm_rplidar_event_type {
    RSM_RPLIDAR_EVENT_NONE = 0,
    RSM_RPLIDAR_EVENT_DESCRIPTOR = 1, /* ev.answer: the type announced */
    RSM_RPLIDAR_EVENT_INFO = 2,       /* ev.info */
    RSM_RPLIDAR_EVENT_HEALTH = 3,     /* ev.health */
    RSM_RPLIDAR_EVENT_SAMPLERATE = 4, /* ev.samplerate */
    RSM_RPLIDAR_EVENT_POINTS = 5      /* ev.points[0..count): one node, or the
                                         samples of one capsule */
} rsm_rplidar_event_type_t;

typedef struct rsm_rplidar_event {
    rsm_rplidar_event_type_t type;
    uint8_t answer; /* answer type of the descriptor (DESCRIPTOR) or of the
                       stream the points came from (POINTS) */
    rsm_rplidar_info_t info;
    rsm_rplidar_health_t health;
    rsm_rplidar_samplerate_t samplerate;
    size_t count;
    rsm_lidar_point_t points[RSM_RPLIDAR_MAX_POINTS];
} rsm_rplidar_event_t;

/* Counters; they only grow (wrapping at 2^32). At any time
 *     bytes_fed = bytes_skipped + bytes_framed + pending
 * with pending = rsm_rplidar_parser_pending (below RSM_RPLIDAR_MAX_FRAME). */
typedef struct rsm_rplidar_stats {
    uint32_t bytes_fed;       /* every byte given to the receiver */
    uint32_t bytes_skipped;   /* garbage, first bytes of rejected candidates,
                                 bytes dropped by rsm_rplidar_parser_expect */
    uint32_t bytes_framed;    /* bytes of accepted descriptors and answers */
    uint32_t descriptors;     /* descriptors accepted */
    uint32_t bad_descriptors; /* A5 5A candidates of an unknown type, length
                                 or mode (resynchronised) */
    uint32_t responses;       /* info, health and sample-rate answers */
    uint32_t nodes;           /* standard-scan nodes accepted */
    uint32_t bad_nodes;       /* node candidates failing S/not-S, the check
                                 bit or angle < 360 deg (resynchronised) */
    uint32_t capsules;        /* express or dense capsules accepted */
    uint32_t checksum_errors; /* capsule candidates whose checksum failed */
    uint32_t bad_capsules;    /* capsule candidates with sync nibbles right,
                                 checksum right, but a start angle >= 360 deg */
    uint32_t unpaired;        /* capsules whose samples were never published:
                                 the next capsule was lost, flagged a new turn,
                                 or lay more than MAX_CAPSULE_SPAN away */
    uint32_t points;          /* points published */
    uint32_t truncated;       /* partial candidates dropped by _expect */
} rsm_rplidar_stats_t;

/* Receiver state, caller owned. Members other than stats are private. */
typedef struct rsm_rplidar_parser {
    uint8_t buf[RSM_RPLIDAR_MAX_FRAME];
    size_t n;
    uint8_t mode;    /* what the bytes are expected to be */
    uint8_t answer;  /* answer type of the current stream or response */
    uint32_t length; /* answer length announced by the descriptor */
    uint8_t prev[RSM_RPLIDAR_CAPSULE]; /* the capsule waiting for its successor */
    uint8_t have_prev;
    rsm_rplidar_stats_t stats;
} rsm_rplidar_parser_t;

/* Empties *p, zeroes the counters, and awaits a descriptor.
 * RSM_OK or RSM_ERR_INVAL (NULL). */
int rsm_rplidar_parser_init(rsm_rplidar_parser_t *p);

/* Tells the receiver that a request was sent: whatever it holds is dropped
 * (counted as skipped; as truncated if a candidate was partial) and it awaits
 * the next descriptor. The driver calls it before every request. Returns
 * the bytes dropped or RSM_ERR_INVAL (NULL). */
int rsm_rplidar_parser_expect(rsm_rplidar_parser_t *p);

/* Drops a partial frame (the line went silent) but goes on awaiting what
 * it awaited: a descriptor, the answer, or the stream. Counted as in
 * _expect (a capsule waiting for its successor is dropped too, as
 * unpaired). Returns the bytes dropped or RSM_ERR_INVAL (NULL). */
int rsm_rplidar_parser_flush(rsm_rplidar_parser_t *p);

/* Takes the bytes from here on as the stream of answer type `answer`
 * (RSM_RPLIDAR_ANS_NODE, _CAPSULE or _DENSE) without its descriptor: for a
 * listener that lost a stream another host still runs (its descriptor
 * went by long ago). A partial candidate is dropped as in _flush. Returns
 * the bytes dropped, or RSM_ERR_INVAL (NULL, another answer type). */
int rsm_rplidar_parser_resume(rsm_rplidar_parser_t *p, uint8_t answer);

/* Feeds bytes in chunks of any size and stops at the first event.
 * Awaiting a descriptor, the receiver hunts for A5 5A and accepts only the
 * descriptors listed above (type, length and send mode must agree); after
 * one it takes the answer (send mode 0, then awaits a descriptor again) or
 * the stream of nodes or capsules (send mode 1, until _expect). A candidate
 * that fails a check costs only its first byte: the bytes after it are
 * examined again. A standard-scan node has no checksum: a node is accepted
 * when S and not-S differ, the check bit is 1 and the angle is below 360
 * deg; capsules must have their sync nibbles and checksum.
 * Params, returns and ownership as rsm_ld06_parser_feed: 1 with an event in
 * *out, 0 when all of data was taken, RSM_ERR_INVAL for bad pointers. */
int rsm_rplidar_parser_feed(rsm_rplidar_parser_t *p, const uint8_t *data, size_t len,
                            size_t *consumed, rsm_rplidar_event_t *out);

/* Bytes of an incomplete descriptor or answer held (0 for NULL). */
size_t rsm_rplidar_parser_pending(const rsm_rplidar_parser_t *p);

#ifdef __cplusplus
}
#endif

#endif /* RSM_RPLIDAR_H */
