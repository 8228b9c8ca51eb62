/* LDRobot LD06 / LD19 packet codec: CRC-8, an incremental receiver and the
 * packet decoder. Pure code: no I/O, no heap, no global state. The listening
 * driver (rsm/ldlidar.h) sits on top of it.
 *
 * The sensor talks without being asked (230400 Bd, 8N1), a continuous
 * stream of 47-byte packets, multi-byte fields LSB first
 * (docs/reference/lidars.md section 1; sources in section 3):
 *     0     header 0x54
 *     1     VerLen 0x2C (packet type 1 in bits 5-7, 12 points in bits 0-4)
 *     2-3   speed, degrees per second
 *     4-5   start angle, 0.01 deg
 *     6-41  12 x (distance u16 in mm, intensity u8); distance 0 = no return
 *     42-43 end angle, 0.01 deg
 *     44-45 timestamp, ms (wraps at 30000)
 *     46    CRC-8 over bytes 0-45: polynomial 0x4D, initial value 0, no
 *           reflection, no final XOR
 * The angle of point i is start + i * (end - start) / 11, the difference
 * taken across 360 deg when end < start. Angles grow clockwise seen from
 * above. */
#ifndef RSM_LD06_H
#define RSM_LD06_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/lidar.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RSM_LD06_HEADER 0x54u
#define RSM_LD06_VERLEN 0x2Cu
#define RSM_LD06_POINTS 12u
#define RSM_LD06_PACKET 47u     /* bytes on the wire */
#define RSM_LD06_MAX_CDEG 36000u /* angles are below this */
#define RSM_LD06_MAX_TS_MS 30000u /* timestamps are below this (they wrap) */
/* The most a packet's 12 points can span, 0.01 deg: a real one spans about
 * 8 to 12 deg (4500 samples a second, 5 to 13 turns a second). */
#define RSM_LD06_MAX_SPAN_CDEG 3000u

/* CRC-8 of the LD06 packet (see above) over len bytes; 0 for len 0.
 * data may be NULL only when len is 0. Pure, reentrant. */
uint8_t rsm_ld06_crc8(const uint8_t *data, size_t len);

/* One decoded packet, fields as on the wire. */
typedef struct rsm_ld06_packet {
    uint16_t speed_dps;                     /* degrees per second */
    uint16_t start_cdeg;                    /* first point, 0.01 deg, < 36000 */
    uint16_t end_cdeg;                      /* last point, 0.01 deg, < 36000 */
    uint16_t timestamp_ms;                  /* sensor clock, ms */
    uint16_t distance_mm[RSM_LD06_POINTS];  /* 0: no return */
    uint8_t intensity[RSM_LD06_POINTS];
} rsm_ld06_packet_t;

/* Checks and decodes one packet of RSM_LD06_PACKET bytes.
 * Returns RSM_OK; RSM_ERR_INVAL for NULL pointers; RSM_ERR_PROTO if the
 * header or VerLen byte is wrong; RSM_ERR_CHECKSUM if the CRC does not
 * verify; RSM_ERR_RANGE for fields no real packet has (an angle of 36000 or
 * more, a timestamp of RSM_LD06_MAX_TS_MS or more, points spread over more
 * than RSM_LD06_MAX_SPAN_CDEG: a CRC-8 passes one false frame in 256). *out
 * is written only on RSM_OK. Pure, reentrant. */
int rsm_ld06_decode(const uint8_t *frame, rsm_ld06_packet_t *out);

/* Writes pkt as RSM_LD06_PACKET bytes, CRC included (for simulators,
 * converters and tests). Returns RSM_LD06_PACKET, RSM_ERR_INVAL for NULL
 * pointers or an angle of 36000 or more, RSM_ERR_NOMEM if cap is too small
 * (nothing written on error). Pure. */
int rsm_ld06_encode(const rsm_ld06_packet_t *pkt, uint8_t *out, size_t cap);

/* The packet's 12 points in order, angles interpolated as described above
 * and reduced to [0, 360), ranges in metres (0 kept as 0), quality = the
 * intensity, start 0. Returns RSM_LD06_POINTS or RSM_ERR_INVAL (NULL).
 * Pure. */
int rsm_ld06_points(const rsm_ld06_packet_t *pkt, rsm_lidar_point_t *out);

/* Receiver counters; they only grow (wrapping at 2^32). At any time
 *     bytes_fed = bytes_skipped + RSM_LD06_PACKET * packets_ok + pending
 * where pending is rsm_ld06_parser_pending (at most 46). */
typedef struct rsm_ld06_stats {
    uint32_t bytes_fed;     /* every byte given to rsm_ld06_parser_feed */
    uint32_t bytes_skipped; /* garbage between packets, the header byte of
                               every rejected candidate, bytes flushed */
    uint32_t packets_ok;    /* packets published */
    uint32_t crc_errors;    /* candidates whose CRC did not verify */
    uint32_t bad_fields;    /* CRC-valid candidates with an angle >= 360 deg, a timestamp
                               >= 30000 ms or points spread over more than 30 deg */
    uint32_t resyncs;       /* candidates rejected (bad VerLen, CRC, fields) */
    uint32_t truncated;     /* partial candidates dropped by a flush */
} rsm_ld06_stats_t;

/* Receiver state, caller owned. Members other than stats are private. */
typedef struct rsm_ld06_parser {
    uint8_t buf[RSM_LD06_PACKET];
    size_t n;
    rsm_ld06_stats_t stats;
} rsm_ld06_parser_t;

/* Empties *p and zeroes the counters. RSM_OK or RSM_ERR_INVAL (NULL). */
int rsm_ld06_parser_init(rsm_ld06_parser_t *p);

/* Feeds bytes in chunks of any size and stops at the first verified packet.
 * Hunts for 0x54 0x2C, collects 47 bytes and publishes them if the CRC
 * verifies and the angles are below 360 deg. A rejected candidate costs
 * only its header byte: the bytes after it are examined again, so a packet
 * that starts inside a corrupted one is still found.
 * Params: data may be NULL if len is 0; *consumed receives how many bytes of
 * data were taken; *out receives the packet when 1 is returned.
 * Returns 1 with a packet (call again with the rest of data), 0 when all of
 * data was taken, RSM_ERR_INVAL for NULL p, consumed or out, or NULL data
 * with len > 0 (nothing taken). Keeps no pointer to data. Reentrant per
 * parser. */
int rsm_ld06_parser_feed(rsm_ld06_parser_t *p, const uint8_t *data, size_t len, size_t *consumed,
                         rsm_ld06_packet_t *out);

/* Drops a partial packet (the line went silent, or the driver restarts):
 * its bytes count as skipped, and as one truncated packet if there were
 * any. Returns the bytes dropped, or RSM_ERR_INVAL (NULL). */
int rsm_ld06_parser_flush(rsm_ld06_parser_t *p);

/* Bytes of an incomplete packet held (0 between packets; 0 for NULL). */
size_t rsm_ld06_parser_pending(const rsm_ld06_parser_t *p);

#ifdef __cplusplus
}
#endif

#endif /* RSM_LD06_H */
