/* ARIA client protocol codec: checksum, encoders, receiver, decoders.
 * See rsm/aria.h for the contracts. No I/O, no heap, no static state. */
#include "rsm/aria.h"

#include <string.h>

#include "rsm/geom.h"
#include "core/check.h"

RSM_STATIC_ASSERT(aria_buffer_holds_any_frame, RSM_ARIA_MAX_PACKET >= 258);

/* Payload bytes of a SIP before the sonar readings, and per reading. */
#define SIP_FIXED_LEN 19u
#define SIP_SONAR_LEN 3u

/* ---- checksum ---------------------------------------------------------------- */

uint16_t rsm_aria_checksum(const uint8_t *body, size_t len)
{
    uint32_t acc = 0u;
    size_t i = 0u;

    if (body == NULL) {
        return 0u;
    }
    for (; i + 1u < len; i += 2u) {
        acc += ((uint32_t)body[i] << 8) | (uint32_t)body[i + 1u];
    }
    if (i < len) {
        acc ^= (uint32_t)body[i];
    }
    return (uint16_t)(acc & 0xFFFFu);
}

/* ---- encoders ------------------------------------------------------------------ */

int rsm_aria_encode_raw(uint8_t id, const uint8_t *payload, size_t len, uint8_t *out, size_t cap)
{
    size_t total;
    uint16_t sum;

    if (out == NULL || (payload == NULL && len > 0u)) {
        return RSM_ERR_INVAL;
    }
    if (len > RSM_ARIA_MAX_PAYLOAD) {
        return RSM_ERR_RANGE;
    }
    total = len + 6u;
    if (cap < total) {
        return RSM_ERR_NOMEM;
    }
    out[0] = (uint8_t)RSM_ARIA_SYNC_1;
    out[1] = (uint8_t)RSM_ARIA_SYNC_2;
    out[2] = (uint8_t)(len + 3u); /* <= 255 by the check above */
    out[3] = id;
    if (len > 0u) {
        memcpy(out + 4, payload, len);
    }
    sum = rsm_aria_checksum(out + 3, len + 1u);
    out[len + 4u] = (uint8_t)(sum >> 8);
    out[len + 5u] = (uint8_t)(sum & 0xFFu);
    return (int)total;
}

int rsm_aria_encode(uint8_t cmd, rsm_aria_arg_kind_t kind, int32_t value, const char *str,
                    size_t str_len, uint8_t *out, size_t cap)
{
    uint8_t payload[RSM_ARIA_MAX_CMD_PAYLOAD];
    size_t len = 0u;

    if (out == NULL) {
        return RSM_ERR_INVAL;
    }
    switch (kind) {
    case RSM_ARIA_ARG_NONE:
        break;
    case RSM_ARIA_ARG_INT: {
        uint32_t mag;
        if (value > RSM_ARIA_INT_MAX || value < -RSM_ARIA_INT_MAX) {
            return RSM_ERR_RANGE;
        }
        if (value >= 0) {
            payload[0] = (uint8_t)RSM_ARIA_ARGTYPE_INT;
            mag = (uint32_t)value;
        } else {
            payload[0] = (uint8_t)RSM_ARIA_ARGTYPE_NINT;
            mag = (uint32_t)(-value); /* value >= -32767: no overflow */
        }
        payload[1] = (uint8_t)(mag & 0xFFu);
        payload[2] = (uint8_t)(mag >> 8);
        len = 3u;
        break;
    }
    case RSM_ARIA_ARG_STR: {
        size_t k;
        if (str == NULL && str_len > 0u) {
            return RSM_ERR_INVAL;
        }
        if (str_len > RSM_ARIA_MAX_STR_ARG) {
            return RSM_ERR_RANGE;
        }
        payload[0] = (uint8_t)RSM_ARIA_ARGTYPE_STR;
        payload[1] = (uint8_t)str_len;
        for (k = 0u; k < str_len; ++k) {
            /* Characters go out as their byte values. */
            payload[2u + k] = (uint8_t)(unsigned char)str[k];
        }
        payload[2u + str_len] = 0u;
        len = str_len + 3u;
        break;
    }
    default:
        return RSM_ERR_INVAL;
    }
    /* No payload bytes at all for NONE: nothing of payload[] is read. */
    return rsm_aria_encode_raw(cmd, (len > 0u) ? payload : NULL, len, out, cap);
}

int rsm_aria_encode_none(uint8_t cmd, uint8_t *out, size_t cap)
{
    return rsm_aria_encode(cmd, RSM_ARIA_ARG_NONE, 0, NULL, 0u, out, cap);
}

int rsm_aria_encode_int(uint8_t cmd, int32_t value, uint8_t *out, size_t cap)
{
    return rsm_aria_encode(cmd, RSM_ARIA_ARG_INT, value, NULL, 0u, out, cap);
}

int rsm_aria_encode_str(uint8_t cmd, const char *str, size_t str_len, uint8_t *out, size_t cap)
{
    return rsm_aria_encode(cmd, RSM_ARIA_ARG_STR, 0, str, str_len, out, cap);
}

int rsm_aria_encode_sync0(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_none((uint8_t)RSM_ARIA_CMD_SYNC0, out, cap);
}

int rsm_aria_encode_sync1(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_none((uint8_t)RSM_ARIA_CMD_SYNC1, out, cap);
}

int rsm_aria_encode_sync2(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_none((uint8_t)RSM_ARIA_CMD_SYNC2, out, cap);
}

int rsm_aria_encode_pulse(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_none((uint8_t)RSM_ARIA_CMD_PULSE, out, cap);
}

int rsm_aria_encode_open(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_none((uint8_t)RSM_ARIA_CMD_OPEN, out, cap);
}

int rsm_aria_encode_open_int1(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_OPEN, 1, out, cap);
}

int rsm_aria_encode_close(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_none((uint8_t)RSM_ARIA_CMD_CLOSE, out, cap);
}

int rsm_aria_encode_close_int1(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_CLOSE, 1, out, cap);
}

int rsm_aria_encode_enable(int on, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_ENABLE, on ? 1 : 0, out, cap);
}

int rsm_aria_encode_encoder(int on, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_ENCODER, on ? 2 : 0, out, cap);
}

int rsm_aria_encode_sonar(int on, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_SONAR, on ? 1 : 0, out, cap);
}

int rsm_aria_encode_config(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_CONFIG, 1, out, cap);
}

int rsm_aria_encode_seto(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_none((uint8_t)RSM_ARIA_CMD_SETO, out, cap);
}

int rsm_aria_encode_seta(int32_t mm_s2, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_SETA, mm_s2, out, cap);
}

int rsm_aria_encode_setv(int32_t mm_s, uint8_t *out, size_t cap)
{
    if (out != NULL && mm_s < 0) {
        return RSM_ERR_RANGE;
    }
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_SETV, mm_s, out, cap);
}

int rsm_aria_encode_setrv(int32_t deg_s, uint8_t *out, size_t cap)
{
    if (out != NULL && deg_s < 0) {
        return RSM_ERR_RANGE;
    }
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_SETRV, deg_s, out, cap);
}

int rsm_aria_encode_vel(int32_t mm_s, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_VEL, mm_s, out, cap);
}

int rsm_aria_encode_rvel(int32_t deg_s, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_RVEL, deg_s, out, cap);
}

int rsm_aria_encode_rotate(int32_t deg_s, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_ROTATE, deg_s, out, cap);
}

int rsm_aria_encode_head(int32_t deg, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_HEAD, deg, out, cap);
}

int rsm_aria_encode_dhead(int32_t deg, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_DHEAD, deg, out, cap);
}

int rsm_aria_encode_move(int32_t mm, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_MOVE, mm, out, cap);
}

int rsm_aria_encode_vel2(int32_t left, int32_t right, uint8_t *out, size_t cap)
{
    uint32_t word;
    int32_t value;

    if (out == NULL) {
        return RSM_ERR_INVAL;
    }
    if (left > RSM_ARIA_VEL2_MAX || left < -RSM_ARIA_VEL2_MAX || right > RSM_ARIA_VEL2_MAX ||
        right < -RSM_ARIA_VEL2_MAX) {
        return RSM_ERR_RANGE;
    }
    /* Two's-complement bytes: high = left, low = right. */
    word = (((uint32_t)left & 0xFFu) << 8) | ((uint32_t)right & 0xFFu);
    /* The word read as a signed 16-bit value; |left| <= 127 keeps it
     * within [-32767, 32767]. */
    value = (word >= 0x8000u) ? (int32_t)word - 65536 : (int32_t)word;
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_VEL2, value, out, cap);
}

int rsm_aria_encode_stop(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_none((uint8_t)RSM_ARIA_CMD_STOP, out, cap);
}

int rsm_aria_encode_estop(uint8_t *out, size_t cap)
{
    return rsm_aria_encode_none((uint8_t)RSM_ARIA_CMD_ESTOP, out, cap);
}

int rsm_aria_encode_hostbaud(uint8_t code, uint8_t *out, size_t cap)
{
    if (out != NULL && code > RSM_ARIA_BAUD_115200) {
        return RSM_ERR_RANGE;
    }
    return rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_HOSTBAUD, (int32_t)code, out, cap);
}

int rsm_aria_encode_tty2(const char *str, size_t len, uint8_t *out, size_t cap)
{
    return rsm_aria_encode_str((uint8_t)RSM_ARIA_CMD_TTY2, str, len, out, cap);
}

int rsm_aria_baud_code(uint32_t baud)
{
    switch (baud) {
    case 9600u: return (int)RSM_ARIA_BAUD_9600;
    case 19200u: return (int)RSM_ARIA_BAUD_19200;
    case 38400u: return (int)RSM_ARIA_BAUD_38400;
    case 57600u: return (int)RSM_ARIA_BAUD_57600;
    case 115200u: return (int)RSM_ARIA_BAUD_115200;
    default: return RSM_ERR_RANGE;
    }
}

/* ---- receiver ------------------------------------------------------------------ *
 *
 * The parser holds at most one candidate frame, always starting at buf[0].
 * buf[0 .. scan) have been examined and form a valid prefix:
 *   scan == 0: nothing examined (hunting);
 *   scan == 1: buf[0] == FA;
 *   scan == 2: buf[0..1] == FA FB;
 *   scan >= 3: buf[2] = N >= 3 and the frame needs N + 3 bytes.
 * buf[scan .. have) are bytes held but not yet examined: they exist only
 * after a rejection, when the rejected candidate's first byte is dropped
 * and the rest is examined again. New input is appended only when
 * scan == have, i.e. to a candidate prefix, and never beyond the frame
 * length N + 3 <= 258, so have <= 258 <= RSM_ARIA_MAX_PACKET always. */

static size_t frame_need(const rsm_aria_parser_t *p)
{
    return (size_t)p->buf[2] + 3u;
}

/* Drops the first k held bytes and restarts the examination. */
static void drop_front(rsm_aria_parser_t *p, size_t k)
{
    if (k >= p->have) {
        p->have = 0u;
    } else {
        memmove(p->buf, p->buf + k, p->have - k);
        p->have -= k;
    }
    p->scan = 0u;
}

/* Rejects the current candidate: its first byte goes, the rest is kept
 * for a new examination. */
static void reject(rsm_aria_parser_t *p)
{
    drop_front(p, 1u);
}

/* Called when buf[0 .. N+3) are all held. Publishes the frame if the
 * checksum verifies (returns 1), otherwise rejects it (returns 0). */
static int finish(rsm_aria_parser_t *p, rsm_aria_packet_t *out)
{
    size_t need = frame_need(p);
    uint16_t want = (uint16_t)(((uint32_t)p->buf[need - 2u] << 8) | (uint32_t)p->buf[need - 1u]);

    if (rsm_aria_checksum(p->buf + 3, need - 5u) != want) {
        p->stats.checksum_errors++;
        reject(p);
        return 0;
    }
    memcpy(out->frame, p->buf, need);
    out->frame_len = need;
    out->payload_len = need - 6u;
    out->id = p->buf[3];
    p->stats.packets_ok++;
    drop_front(p, need);
    return 1;
}

/* Examines held byte buf[scan] (scan < have). Returns 1 if a packet was
 * published into out. */
static int step_held(rsm_aria_parser_t *p, rsm_aria_packet_t *out)
{
    size_t need;

    if (p->scan == 0u) {
        size_t k = 1u;
        if (p->buf[0] == RSM_ARIA_SYNC_1) {
            p->scan = 1u;
            return 0;
        }
        while (k < p->have && p->buf[k] != RSM_ARIA_SYNC_1) {
            ++k;
        }
        p->stats.bytes_skipped += (uint32_t)k;
        drop_front(p, k);
        return 0;
    }
    if (p->scan == 1u) {
        if (p->buf[1] == RSM_ARIA_SYNC_2) {
            p->scan = 2u;
        } else {
            /* The FA was not a header; the byte after it is examined anew. */
            p->stats.bytes_skipped++;
            drop_front(p, 1u);
        }
        return 0;
    }
    if (p->scan == 2u) {
        if (p->buf[2] < RSM_ARIA_MIN_COUNT) {
            p->stats.bad_length++;
            reject(p);
            return 0;
        }
    }
    need = frame_need(p);
    p->scan = (p->have < need) ? p->have : need;
    if (p->scan == need) {
        return finish(p, out);
    }
    return 0;
}

/* Abandons the current candidate prefix (scan == have > 0) after a line
 * timeout. */
static int abandon(rsm_aria_parser_t *p)
{
    if (p->have >= 2u) {
        p->stats.truncated++;
        reject(p);
        return 1;
    }
    p->stats.bytes_skipped++;
    drop_front(p, 1u);
    return 0;
}

int rsm_aria_parser_init_checked(rsm_aria_parser_t *p, size_t p_size, unsigned long fingerprint)
{
    if (!RSM_SAME_BUILD(rsm_aria_parser_t, p_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (p == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(p, 0, sizeof(*p));
    return RSM_OK;
}

int rsm_aria_parser_feed_checked(rsm_aria_parser_t *p, const uint8_t *data, size_t len, size_t *consumed,
                                 rsm_aria_packet_t *out, size_t out_size, unsigned long fingerprint)
{
    size_t i = 0u;

    if (!RSM_SAME_BUILD(rsm_aria_packet_t, out_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (consumed != NULL) {
        *consumed = 0u;
    }
    if (p == NULL || consumed == NULL || out == NULL || (data == NULL && len > 0u)) {
        return RSM_ERR_INVAL;
    }
    for (;;) {
        if (p->scan < p->have) {
            if (step_held(p, out)) {
                *consumed = i;
                return 1;
            }
            continue;
        }
        if (p->have > 0u && p->stale) {
            (void)abandon(p);
            continue;
        }
        if (p->have == 0u) {
            p->stale = 0;
        }
        if (i == len) {
            break;
        }
        if (p->have == 0u) {
            /* Hunting with nothing held: skip straight to the next FA. */
            const void *hit = memchr(data + i, (int)RSM_ARIA_SYNC_1, len - i);
            size_t k = (hit == NULL) ? (len - i) : (size_t)((const uint8_t *)hit - (data + i));
            p->stats.bytes_skipped += (uint32_t)k;
            i += k;
            if (i == len) {
                break;
            }
            p->buf[0] = data[i++];
            p->have = 1u;
            p->scan = 1u;
            continue;
        }
        if (p->have < 3u) {
            /* Header byte: examined by step_held on the next turn. */
            p->buf[p->have++] = data[i++];
            continue;
        }
        {
            /* Body: copy as much of the frame as is available. */
            size_t need = frame_need(p);
            size_t n = need - p->have;
            if (n > len - i) {
                n = len - i;
            }
            memcpy(p->buf + p->have, data + i, n);
            p->have += n;
            p->scan = p->have;
            i += n;
            if (p->have == need && finish(p, out)) {
                *consumed = i;
                return 1;
            }
        }
    }
    *consumed = len;
    return 0;
}

int rsm_aria_parser_timeout(rsm_aria_parser_t *p)
{
    int counted = 0;

    if (p == NULL) {
        return RSM_ERR_INVAL;
    }
    if (p->have == 0u) {
        return 0;
    }
    if (p->scan == p->have) {
        counted = abandon(p);
    }
    p->stale = (p->have > 0u) ? 1 : 0;
    return counted;
}

size_t rsm_aria_parser_pending(const rsm_aria_parser_t *p)
{
    return (p == NULL) ? 0u : p->have;
}

/* ---- packets ------------------------------------------------------------------- */

const uint8_t *rsm_aria_payload(const rsm_aria_packet_t *pkt)
{
    return (pkt == NULL) ? NULL : pkt->frame + 4;
}

int rsm_aria_packet_build_checked(rsm_aria_packet_t *pkt, size_t pkt_size, unsigned long fingerprint, uint8_t id,
                                  const uint8_t *payload, size_t len)
{
    int n;

    if (!RSM_SAME_BUILD(rsm_aria_packet_t, pkt_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (pkt == NULL || (payload == NULL && len > 0u)) {
        return RSM_ERR_INVAL;
    }
    if (len > RSM_ARIA_MAX_PAYLOAD) {
        return RSM_ERR_RANGE;
    }
    n = rsm_aria_encode_raw(id, payload, len, pkt->frame, sizeof(pkt->frame));
    if (n < 0) {
        return n;
    }
    pkt->id = id;
    pkt->payload_len = len;
    pkt->frame_len = (size_t)n;
    return RSM_OK;
}

/* A packet the decoders can trust to stay inside its own arrays. */
static int packet_ok(const rsm_aria_packet_t *pkt)
{
    return pkt != NULL && pkt->frame_len <= RSM_ARIA_MAX_PACKET && pkt->frame_len >= 6u &&
           pkt->payload_len + 6u == pkt->frame_len && pkt->frame[3] == pkt->id;
}

/* ---- little-endian reader ------------------------------------------------------- */

typedef struct reader {
    const uint8_t *p;
    size_t len;
    size_t pos;
} reader_t;

static size_t left_in(const reader_t *r)
{
    return r->len - r->pos;
}

static int get_u8(reader_t *r, uint8_t *v)
{
    if (left_in(r) < 1u) {
        return 0;
    }
    *v = r->p[r->pos++];
    return 1;
}

static int get_s8(reader_t *r, int8_t *v)
{
    uint8_t u;
    if (!get_u8(r, &u)) {
        return 0;
    }
    *v = (int8_t)((int32_t)u - ((u & 0x80u) ? 256 : 0));
    return 1;
}

static int get_u16(reader_t *r, uint16_t *v)
{
    if (left_in(r) < 2u) {
        return 0;
    }
    *v = (uint16_t)((uint32_t)r->p[r->pos] | ((uint32_t)r->p[r->pos + 1u] << 8));
    r->pos += 2u;
    return 1;
}

static int16_t s16_of(uint16_t u)
{
    return (int16_t)((int32_t)u - ((u & 0x8000u) ? 65536 : 0));
}

static int get_s16(reader_t *r, int16_t *v)
{
    uint16_t u;
    if (!get_u16(r, &u)) {
        return 0;
    }
    *v = s16_of(u);
    return 1;
}

static int get_u32(reader_t *r, uint32_t *v)
{
    if (left_in(r) < 4u) {
        return 0;
    }
    *v = (uint32_t)r->p[r->pos] | ((uint32_t)r->p[r->pos + 1u] << 8) |
         ((uint32_t)r->p[r->pos + 2u] << 16) | ((uint32_t)r->p[r->pos + 3u] << 24);
    r->pos += 4u;
    return 1;
}

static int32_t s32_of(uint32_t u)
{
    if (u <= 0x7FFFFFFFu) {
        return (int32_t)u;
    }
    return (int32_t)(u - 0x80000000u) - INT32_MAX - 1;
}

/* Reads a string ended by a NUL (consumed) or, when nul_required is 0, by
 * the end of the data. Copies what fits into dst (size RSM_ARIA_STR_SIZE,
 * always NUL-terminated) and sets *cut when characters were dropped.
 * Returns 0 (dst untouched) when a required NUL is missing. */
static int get_str(reader_t *r, char *dst, int nul_required, int *cut)
{
    size_t end = r->pos;
    size_t n;
    size_t k;

    while (end < r->len && r->p[end] != 0u) {
        ++end;
    }
    if (end == r->len && nul_required) {
        return 0;
    }
    n = end - r->pos;
    *cut = (n > RSM_ARIA_STR_SIZE - 1u) ? 1 : 0;
    if (n > RSM_ARIA_STR_SIZE - 1u) {
        n = RSM_ARIA_STR_SIZE - 1u;
    }
    for (k = 0u; k < n; ++k) {
        /* Bytes become chars of the same bit pattern. */
        dst[k] = (char)r->p[r->pos + k];
    }
    dst[n] = '\0';
    r->pos = (end < r->len) ? end + 1u : end;
    return 1;
}

/* ---- decoders ----------------------------------------------------------------- */

int rsm_aria_decode_sync(const rsm_aria_packet_t *pkt)
{
    if (!packet_ok(pkt) || pkt->id > RSM_ARIA_PAC_SYNC2) {
        return RSM_ERR_INVAL;
    }
    return (int)pkt->id;
}

int rsm_aria_decode_sync2_checked(const rsm_aria_packet_t *pkt, rsm_aria_sync2_t *out, size_t out_size,
                                  unsigned long fingerprint)
{
    rsm_aria_sync2_t s;
    reader_t r;
    char *dst[3];
    unsigned i;

    if (!RSM_SAME_BUILD(rsm_aria_sync2_t, out_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (!packet_ok(pkt) || out == NULL || pkt->id != RSM_ARIA_PAC_SYNC2) {
        return RSM_ERR_INVAL;
    }
    memset(&s, 0, sizeof(s));
    dst[0] = s.name;
    dst[1] = s.robot_class;
    dst[2] = s.subclass;
    r.p = pkt->frame + 4;
    r.len = pkt->payload_len;
    r.pos = 0u;
    for (i = 0u; i < 3u && left_in(&r) > 0u; ++i) {
        int cut = 0;
        (void)get_str(&r, dst[i], 0, &cut);
        if (cut) {
            s.truncated = (uint8_t)(s.truncated | (1u << i));
        }
        s.present = (uint8_t)(i + 1u);
    }
    *out = s;
    return RSM_OK;
}

int rsm_aria_decode_sip_checked(const rsm_aria_packet_t *pkt, rsm_aria_sip_t *out, size_t out_size,
                                unsigned long fingerprint)
{
    rsm_aria_sip_t s;
    reader_t r;
    uint16_t u;
    size_t k;

    if (!RSM_SAME_BUILD(rsm_aria_sip_t, out_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (!packet_ok(pkt) || out == NULL ||
        (pkt->id != RSM_ARIA_PAC_SIP_STOPPED && pkt->id != RSM_ARIA_PAC_SIP_MOVING)) {
        return RSM_ERR_INVAL;
    }
    if (pkt->payload_len < SIP_FIXED_LEN ||
        pkt->payload_len < SIP_FIXED_LEN + SIP_SONAR_LEN * (size_t)pkt->frame[4u + 18u]) {
        return RSM_ERR_RANGE;
    }
    memset(&s, 0, sizeof(s));
    r.p = pkt->frame + 4;
    r.len = pkt->payload_len;
    r.pos = 0u;
    s.type = pkt->id;
    /* The fixed part and the sonar block are known to fit. */
    (void)get_u16(&r, &u);
    s.xpos = (uint16_t)(u & 0x7FFFu);
    (void)get_u16(&r, &u);
    s.ypos = (uint16_t)(u & 0x7FFFu);
    (void)get_s16(&r, &s.thpos);
    (void)get_s16(&r, &s.l_vel);
    (void)get_s16(&r, &s.r_vel);
    (void)get_u8(&r, &s.battery);
    (void)get_u16(&r, &s.stall_and_bumpers);
    (void)get_s16(&r, &s.control);
    (void)get_u16(&r, &s.flags);
    (void)get_u8(&r, &s.compass);
    (void)get_u8(&r, &s.sonar_count);
    for (k = 0u; k < (size_t)s.sonar_count; ++k) {
        rsm_aria_sonar_t reading;
        (void)get_u8(&r, &reading.num);
        (void)get_u16(&r, &reading.range);
        if (k < RSM_ARIA_MAX_SONAR) {
            s.sonar[k] = reading;
            s.sonar_len = k + 1u;
        }
    }
    /* Everything after the sonar block only while bytes remain. */
    do {
        if (!get_u8(&r, &s.grip_state)) break;
        s.present |= RSM_ARIA_SIP_HAS_GRIP_STATE;
        if (!get_u8(&r, &s.anport)) break;
        s.present |= RSM_ARIA_SIP_HAS_ANPORT;
        if (!get_u8(&r, &s.analog)) break;
        s.present |= RSM_ARIA_SIP_HAS_ANALOG;
        if (!get_u8(&r, &s.digin)) break;
        s.present |= RSM_ARIA_SIP_HAS_DIGIN;
        if (!get_u8(&r, &s.digout)) break;
        s.present |= RSM_ARIA_SIP_HAS_DIGOUT;
        if (!get_u16(&r, &s.battery_x10)) break;
        s.present |= RSM_ARIA_SIP_HAS_BATTERY_X10;
        if (!get_u8(&r, &s.charge_state)) break;
        s.present |= RSM_ARIA_SIP_HAS_CHARGE_STATE;
        if (!get_s16(&r, &s.rot_vel)) break;
        s.present |= RSM_ARIA_SIP_HAS_ROT_VEL;
        if (!get_u16(&r, &s.fault_flags)) break;
        s.present |= RSM_ARIA_SIP_HAS_FAULT_FLAGS;
        if (!get_s16(&r, &s.lat_vel)) break;
        s.present |= RSM_ARIA_SIP_HAS_LAT_VEL;
        if (!get_s8(&r, &s.temperature)) break;
        s.present |= RSM_ARIA_SIP_HAS_TEMPERATURE;
        if (!get_s8(&r, &s.state_of_charge)) break;
        s.present |= RSM_ARIA_SIP_HAS_STATE_OF_CHARGE;
        if (!get_u32(&r, &s.uc_time)) break;
        s.present |= RSM_ARIA_SIP_HAS_UC_TIME;
        if (!get_u32(&r, &s.flags3)) break;
        s.present |= RSM_ARIA_SIP_HAS_FLAGS3;
    } while (0);
    *out = s;
    return RSM_OK;
}

int rsm_aria_decode_encoder(const rsm_aria_packet_t *pkt, rsm_aria_encoder_t *out)
{
    reader_t r;
    uint32_t l;
    uint32_t rr;

    if (!packet_ok(pkt) || out == NULL || pkt->id != RSM_ARIA_PAC_ENCODER) {
        return RSM_ERR_INVAL;
    }
    r.p = pkt->frame + 4;
    r.len = pkt->payload_len;
    r.pos = 0u;
    if (!get_u32(&r, &l) || !get_u32(&r, &rr)) {
        return RSM_ERR_RANGE;
    }
    out->left = s32_of(l);
    out->right = s32_of(rr);
    return RSM_OK;
}

int rsm_aria_decode_config_checked(const rsm_aria_packet_t *pkt, rsm_aria_config_t *out, size_t out_size,
                                   unsigned long fingerprint)
{
    rsm_aria_config_t c;
    reader_t r;
    int cut = 0;
    int ok;

    if (!RSM_SAME_BUILD(rsm_aria_config_t, out_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (!packet_ok(pkt) || out == NULL || pkt->id != RSM_ARIA_PAC_CONFIG) {
        return RSM_ERR_INVAL;
    }
    memset(&c, 0, sizeof(c));
    r.p = pkt->frame + 4;
    r.len = pkt->payload_len;
    r.pos = 0u;

#define CFG_STR(dst, bit)                                                                          \
    (get_str(&r, (dst), 1, &cut) && ((c.truncated = (uint8_t)(c.truncated | (cut ? (bit) : 0u))), 1))
    ok = CFG_STR(c.robot_type, 0x01u) && CFG_STR(c.subtype, 0x02u) &&
         CFG_STR(c.serial_num, 0x04u) && get_u8(&r, &c.four_mot) &&
         get_u16(&r, &c.rot_vel_top) && get_u16(&r, &c.trans_vel_top) &&
         get_u16(&r, &c.rot_acc_top) && get_u16(&r, &c.trans_acc_top) &&
         get_u16(&r, &c.pwm_max) && CFG_STR(c.name, 0x08u) && get_u8(&r, &c.sip_cycle) &&
         get_u8(&r, &c.host_baud) && get_u8(&r, &c.aux1_baud) && get_u16(&r, &c.has_gripper) &&
         get_u16(&r, &c.front_sonar) && get_u8(&r, &c.rear_sonar) &&
         get_u16(&r, &c.low_battery) && get_u16(&r, &c.rev_count) &&
         get_u16(&r, &c.watchdog) && get_u8(&r, &c.normal_mpacs) &&
         get_u16(&r, &c.stall_val) && get_u16(&r, &c.stall_count) &&
         get_u16(&r, &c.joy_vel) && get_u16(&r, &c.joy_rot_vel) &&
         get_u16(&r, &c.rot_vel_max) && get_u16(&r, &c.trans_vel_max) &&
         get_u16(&r, &c.rot_accel) && get_u16(&r, &c.rot_decel) && get_u16(&r, &c.rot_kp) &&
         get_u16(&r, &c.rot_kv) && get_u16(&r, &c.rot_ki) && get_u16(&r, &c.trans_accel) &&
         get_u16(&r, &c.trans_decel) && get_u16(&r, &c.trans_kp) &&
         get_u16(&r, &c.trans_kv) && get_u16(&r, &c.trans_ki) &&
         get_u8(&r, &c.front_bumps) && get_u8(&r, &c.rear_bumps) && get_u8(&r, &c.charger) &&
         get_u8(&r, &c.sonar_cycle) && get_u8(&r, &c.auto_baud) && get_u8(&r, &c.has_gyro) &&
         get_s16(&r, &c.drift_factor) && get_u8(&r, &c.aux2_baud) &&
         get_u8(&r, &c.aux3_baud) && get_u16(&r, &c.ticks_mm);
#undef CFG_STR
    if (!ok) {
        return RSM_ERR_RANGE;
    }
    if (get_u16(&r, &c.shutdown_volts)) {
        c.present |= RSM_ARIA_CONFIG_HAS_SHUTDOWN_VOLTS;
        if (left_in(&r) > 0u) {
            (void)get_str(&r, c.firmware, 0, &cut);
            if (cut) {
                c.truncated = (uint8_t)(c.truncated | 0x10u);
            }
            c.present |= RSM_ARIA_CONFIG_HAS_FIRMWARE;
        }
    }
    *out = c;
    return RSM_OK;
}

/* ---- odometry helpers ------------------------------------------------------------- */

int16_t rsm_aria_pos_delta15(uint16_t now, uint16_t prev)
{
    uint32_t d = ((uint32_t)(now & 0x7FFFu) - (uint32_t)(prev & 0x7FFFu) + 0x4000u) & 0x7FFFu;
    return (int16_t)((int32_t)d - 0x4000);
}

float rsm_aria_th_to_rad(int32_t th_units)
{
    /* Reduce in integers first so that the float step is exact-ish and
     * the result lands in (-pi, pi]. */
    int32_t t = th_units % 4096;
    if (t <= -2048) {
        t += 4096;
    } else if (t > 2048) {
        t -= 4096;
    }
    return (float)t * (RSM_TWO_PI / 4096.0f);
}
