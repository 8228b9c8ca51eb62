#include "rsm/ld06.h"

#include <string.h>

#include "rsm/status.h"
#include "core/bytes.h"

#define CRC_POLY 0x4Du

uint8_t rsm_ld06_crc8(const uint8_t *data, size_t len)
{
    uint8_t crc = 0u;
    size_t i;
    if (data == NULL) {
        return 0u;
    }
    for (i = 0; i < len; ++i) {
        unsigned b;
        crc = (uint8_t)(crc ^ data[i]);
        for (b = 0; b < 8u; ++b) {
            crc = (uint8_t)((crc & 0x80u) ? ((unsigned)crc << 1) ^ CRC_POLY : (unsigned)crc << 1);
        }
    }
    return crc;
}

int rsm_ld06_decode(const uint8_t *frame, rsm_ld06_packet_t *out)
{
    rsm_ld06_packet_t pkt;
    size_t i;
    if (frame == NULL || out == NULL) {
        return RSM_ERR_INVAL;
    }
    if (frame[0] != RSM_LD06_HEADER || frame[1] != RSM_LD06_VERLEN) {
        return RSM_ERR_PROTO;
    }
    if (rsm_ld06_crc8(frame, RSM_LD06_PACKET - 1u) != frame[RSM_LD06_PACKET - 1u]) {
        return RSM_ERR_CHECKSUM;
    }
    pkt.speed_dps = rsm_get_u16le(frame + 2);
    pkt.start_cdeg = rsm_get_u16le(frame + 4);
    for (i = 0; i < RSM_LD06_POINTS; ++i) {
        pkt.distance_mm[i] = rsm_get_u16le(frame + 6 + 3u * i);
        pkt.intensity[i] = frame[8 + 3u * i];
    }
    pkt.end_cdeg = rsm_get_u16le(frame + 42);
    pkt.timestamp_ms = rsm_get_u16le(frame + 44);
    /* A CRC-8 passes one false frame in 256 (a header inside a cut packet,
     * the real one behind it): fields no real packet has refuse most of
     * them, and the receiver looks for the real packet inside the refused
     * frame. The speed is not judged: converted logs write any. */
    if (pkt.start_cdeg >= RSM_LD06_MAX_CDEG || pkt.end_cdeg >= RSM_LD06_MAX_CDEG ||
        pkt.timestamp_ms >= RSM_LD06_MAX_TS_MS ||
        (pkt.end_cdeg + RSM_LD06_MAX_CDEG - pkt.start_cdeg) % RSM_LD06_MAX_CDEG > RSM_LD06_MAX_SPAN_CDEG) {
        return RSM_ERR_RANGE;
    }
    *out = pkt;
    return RSM_OK;
}

int rsm_ld06_encode(const rsm_ld06_packet_t *pkt, uint8_t *out, size_t cap)
{
    size_t i;
    if (pkt == NULL || out == NULL || pkt->start_cdeg >= RSM_LD06_MAX_CDEG ||
        pkt->end_cdeg >= RSM_LD06_MAX_CDEG) {
        return RSM_ERR_INVAL;
    }
    if (cap < RSM_LD06_PACKET) {
        return RSM_ERR_NOMEM;
    }
    out[0] = RSM_LD06_HEADER;
    out[1] = RSM_LD06_VERLEN;
    rsm_put_u16le(out + 2, pkt->speed_dps);
    rsm_put_u16le(out + 4, pkt->start_cdeg);
    for (i = 0; i < RSM_LD06_POINTS; ++i) {
        rsm_put_u16le(out + 6 + 3u * i, pkt->distance_mm[i]);
        out[8 + 3u * i] = pkt->intensity[i];
    }
    rsm_put_u16le(out + 42, pkt->end_cdeg);
    rsm_put_u16le(out + 44, pkt->timestamp_ms);
    out[46] = rsm_ld06_crc8(out, RSM_LD06_PACKET - 1u);
    return (int)RSM_LD06_PACKET;
}

int rsm_ld06_points(const rsm_ld06_packet_t *pkt, rsm_lidar_point_t *out)
{
    uint32_t span;
    size_t i;
    if (pkt == NULL || out == NULL) {
        return RSM_ERR_INVAL;
    }
    /* the sweep crosses 0 deg when the end is below the start */
    span = ((uint32_t)pkt->end_cdeg + RSM_LD06_MAX_CDEG - pkt->start_cdeg) % RSM_LD06_MAX_CDEG;
    for (i = 0; i < RSM_LD06_POINTS; ++i) {
        /* in 1/1100 deg, exact in integers: start * 11 + span * i */
        uint32_t a = (uint32_t)pkt->start_cdeg * (RSM_LD06_POINTS - 1u) + span * (uint32_t)i;
        a %= RSM_LD06_MAX_CDEG * (RSM_LD06_POINTS - 1u);
        out[i].angle_deg = (float)a / (100.0f * (float)(RSM_LD06_POINTS - 1u));
        out[i].range_m = (float)pkt->distance_mm[i] * 0.001f;
        out[i].quality = pkt->intensity[i];
        out[i].start = 0u;
    }
    return (int)RSM_LD06_POINTS;
}

int rsm_ld06_parser_init(rsm_ld06_parser_t *p)
{
    if (p == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(p, 0, sizeof *p);
    return RSM_OK;
}

/* Drops the candidate's first byte and any bytes after it that cannot
 * start a packet; what remains is a shorter candidate to complete. */
static void resync(rsm_ld06_parser_t *p)
{
    p->stats.resyncs++;
    do {
        memmove(p->buf, p->buf + 1, p->n - 1u);
        p->n--;
        p->stats.bytes_skipped++;
    } while (p->n > 0u && (p->buf[0] != RSM_LD06_HEADER ||
                           (p->n >= 2u && p->buf[1] != RSM_LD06_VERLEN)));
}

int rsm_ld06_parser_feed(rsm_ld06_parser_t *p, const uint8_t *data, size_t len, size_t *consumed,
                         rsm_ld06_packet_t *out)
{
    size_t used = 0;
    if (p == NULL || consumed == NULL || out == NULL || (data == NULL && len > 0u)) {
        return RSM_ERR_INVAL;
    }
    *consumed = 0;
    while (used < len) {
        const uint8_t b = data[used++];
        p->stats.bytes_fed++;
        if (p->n == 0u && b != RSM_LD06_HEADER) {
            p->stats.bytes_skipped++;
            continue;
        }
        p->buf[p->n++] = b;
        if (p->n == 2u && b != RSM_LD06_VERLEN) {
            resync(p);
        } else if (p->n == RSM_LD06_PACKET) {
            const int rc = rsm_ld06_decode(p->buf, out);
            if (rc == RSM_OK) {
                p->n = 0;
                p->stats.packets_ok++;
                *consumed = used;
                return 1;
            }
            if (rc == RSM_ERR_CHECKSUM) {
                p->stats.crc_errors++;
            } else {
                p->stats.bad_fields++;
            }
            resync(p);
        }
    }
    *consumed = used;
    return 0;
}

int rsm_ld06_parser_flush(rsm_ld06_parser_t *p)
{
    if (p == NULL) {
        return RSM_ERR_INVAL;
    }
    return rsm_drop_partial(&p->n, &p->stats.bytes_skipped, &p->stats.truncated);
}

size_t rsm_ld06_parser_pending(const rsm_ld06_parser_t *p)
{
    return p == NULL ? 0u : p->n;
}
