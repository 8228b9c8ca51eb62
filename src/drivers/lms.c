/* SICK LMS 2xx telegram codec. See rsm/lms.h for the contracts. */
#include "rsm/lms.h"

#include <string.h>

#include "rsm/geom.h"
#include "rsm/status.h"
#include "core/check.h"

/* Capacity checks: the parser buffer must hold the largest telegram it may
 * accept, and a 401-value 0xB0 telegram must be acceptable. */
RSM_STATIC_ASSERT(lms_buffer_holds_max_len, RSM_LMS_MAX_LEN + 6 <= RSM_LMS_MAX_TELEGRAM);
RSM_STATIC_ASSERT(lms_max_len_holds_401, RSM_LMS_MAX_LEN >= 806);

#define LMS_MAX_LEN ((size_t)RSM_LMS_MAX_LEN)
#define LMS_BUF_CAP ((size_t)RSM_LMS_MAX_TELEGRAM)

/* ---- small helpers ------------------------------------------------------ */

static uint16_t get_u16(const uint8_t *b)
{
    return (uint16_t)((unsigned)b[0] | ((unsigned)b[1] << 8));
}

static void put_u16(uint8_t *b, uint16_t v)
{
    b[0] = (uint8_t)(v & 0xFFu);
    b[1] = (uint8_t)(v >> 8);
}

/* ---- CRC ---------------------------------------------------------------- */

uint16_t rsm_lms_crc(const uint8_t *data, size_t len)
{
    uint16_t crc = 0u;
    uint8_t prev = 0u;
    size_t i;

    if (data == NULL) {
        return 0u;
    }
    for (i = 0; i < len; ++i) {
        const uint8_t b = data[i];
        const uint16_t pair = (uint16_t)(((unsigned)prev << 8) | (unsigned)b);
        if ((crc & 0x8000u) != 0u) {
            crc = (uint16_t)(((unsigned)crc << 1) ^ 0x8005u);
        } else {
            crc = (uint16_t)((unsigned)crc << 1);
        }
        crc = (uint16_t)(crc ^ pair);
        prev = b;
    }
    return crc;
}

/* ---- telegram view ------------------------------------------------------- */

/* Fills a view of a frame whose framing and CRC the caller has checked. */
static void make_view(const uint8_t *frame, size_t frame_len, rsm_lms_telegram_t *out)
{
    out->frame = frame;
    out->frame_len = frame_len;
    out->adr = frame[1];
    out->len = get_u16(frame + 2);
    out->cmd = frame[4];
    out->data = frame + 5;
    out->data_len = (size_t)out->len - 1u;
}

/* CRC of a complete frame (LEN + 6 bytes) verifies. */
static int frame_crc_ok(const uint8_t *frame, size_t frame_len)
{
    const uint16_t sent = get_u16(frame + frame_len - 2u);
    return rsm_lms_crc(frame, frame_len - 2u) == sent;
}

int rsm_lms_telegram_view(const uint8_t *frame, size_t len, rsm_lms_telegram_t *out)
{
    size_t field;

    if (frame == NULL || out == NULL) {
        return RSM_ERR_INVAL;
    }
    if (len >= 1u && frame[0] != RSM_LMS_STX) {
        return RSM_ERR_PROTO;
    }
    if (len < 4u) {
        return RSM_ERR_AGAIN;
    }
    field = get_u16(frame + 2);
    if (field == 0u || field > LMS_MAX_LEN) {
        return RSM_ERR_PROTO;
    }
    if (len < field + RSM_LMS_OVERHEAD) {
        return RSM_ERR_AGAIN;
    }
    if (len > field + RSM_LMS_OVERHEAD) {
        return RSM_ERR_PROTO;
    }
    if (!frame_crc_ok(frame, len)) {
        return RSM_ERR_CHECKSUM;
    }
    make_view(frame, len, out);
    return RSM_OK;
}

/* ---- encoders ------------------------------------------------------------ */

int rsm_lms_encode(uint8_t *out, size_t cap, uint8_t adr, uint8_t cmd, const uint8_t *data,
                   size_t data_len)
{
    size_t total;
    uint16_t crc;

    if (out == NULL || (data == NULL && data_len != 0u)) {
        return RSM_ERR_INVAL;
    }
    if (data_len >= LMS_MAX_LEN) { /* LEN = 1 + data_len must stay <= max */
        return RSM_ERR_INVAL;
    }
    total = data_len + 1u + RSM_LMS_OVERHEAD;
    if (cap < total) {
        return RSM_ERR_NOMEM;
    }
    out[0] = (uint8_t)RSM_LMS_STX;
    out[1] = adr;
    put_u16(out + 2, (uint16_t)(data_len + 1u));
    out[4] = cmd;
    if (data_len != 0u) {
        memcpy(out + 5, data, data_len);
    }
    crc = rsm_lms_crc(out, total - 2u);
    put_u16(out + total - 2u, crc);
    return (int)total;
}

/* Requests go to an LMS address 0x00..0x7F. */
static int encode_request(uint8_t *out, size_t cap, uint8_t address, uint8_t cmd,
                          const uint8_t *data, size_t data_len)
{
    if (address >= RSM_LMS_REPLY_ADR) {
        return RSM_ERR_INVAL;
    }
    return rsm_lms_encode(out, cap, address, cmd, data, data_len);
}

int rsm_lms_encode_mode(uint8_t *out, size_t cap, uint8_t address, uint8_t mode)
{
    switch (mode) {
    case RSM_LMS_MODE_DIAGNOSTIC:
    case RSM_LMS_MODE_CONTINUOUS:
    case RSM_LMS_MODE_ON_REQUEST:
    case RSM_LMS_MODE_BAUD_38400:
    case RSM_LMS_MODE_BAUD_19200:
    case RSM_LMS_MODE_BAUD_9600:
    case RSM_LMS_MODE_BAUD_500000:
        break;
    default:
        return RSM_ERR_INVAL;
    }
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_MODE, &mode, 1u);
}

int rsm_lms_encode_mode_installation(uint8_t *out, size_t cap, uint8_t address,
                                     const uint8_t *password)
{
    static const char default_password[] = RSM_LMS_DEFAULT_PASSWORD;
    uint8_t d[1u + RSM_LMS_PASSWORD_LEN];

    d[0] = (uint8_t)RSM_LMS_MODE_INSTALLATION;
    if (password != NULL) {
        memcpy(d + 1, password, RSM_LMS_PASSWORD_LEN);
    } else {
        memcpy(d + 1, default_password, RSM_LMS_PASSWORD_LEN);
    }
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_MODE, d, sizeof d);
}

int rsm_lms_encode_mode_mean(uint8_t *out, size_t cap, uint8_t address, uint8_t samples)
{
    uint8_t d[2];

    if (samples == 0u) {
        return RSM_ERR_INVAL;
    }
    d[0] = (uint8_t)RSM_LMS_MODE_MEAN;
    d[1] = samples;
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_MODE, d, sizeof d);
}

int rsm_lms_encode_mode_subrange(uint8_t *out, size_t cap, uint8_t address, uint16_t first,
                                 uint16_t last)
{
    uint8_t d[5];

    if (first < 1u || first > last || last > 401u) {
        return RSM_ERR_INVAL;
    }
    d[0] = (uint8_t)RSM_LMS_MODE_SUBRANGE;
    put_u16(d + 1, first);
    put_u16(d + 3, last);
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_MODE, d, sizeof d);
}

int rsm_lms_encode_mode_baud(uint8_t *out, size_t cap, uint8_t address, uint32_t baud)
{
    uint8_t mode;

    switch (baud) {
    case 9600u:
        mode = (uint8_t)RSM_LMS_MODE_BAUD_9600;
        break;
    case 19200u:
        mode = (uint8_t)RSM_LMS_MODE_BAUD_19200;
        break;
    case 38400u:
        mode = (uint8_t)RSM_LMS_MODE_BAUD_38400;
        break;
    case 500000u:
        mode = (uint8_t)RSM_LMS_MODE_BAUD_500000;
        break;
    default:
        return RSM_ERR_INVAL;
    }
    return rsm_lms_encode_mode(out, cap, address, mode);
}

int rsm_lms_encode_request_scan(uint8_t *out, size_t cap, uint8_t address)
{
    static const uint8_t one_scan = 0x01u;
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_GET_VALUES, &one_scan, 1u);
}

int rsm_lms_encode_request_status(uint8_t *out, size_t cap, uint8_t address)
{
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_GET_STATUS, NULL, 0u);
}

int rsm_lms_encode_request_type(uint8_t *out, size_t cap, uint8_t address)
{
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_GET_TYPE, NULL, 0u);
}

int rsm_lms_encode_variant(uint8_t *out, size_t cap, uint8_t address, uint16_t angle_deg,
                           uint16_t resolution_cdeg)
{
    uint8_t d[4];
    int legal;

    if (angle_deg == 180u) {
        legal = resolution_cdeg == 100u || resolution_cdeg == 50u;
    } else if (angle_deg == 100u) {
        legal = resolution_cdeg == 100u || resolution_cdeg == 50u || resolution_cdeg == 25u;
    } else {
        legal = 0;
    }
    if (!legal) {
        return RSM_ERR_INVAL;
    }
    put_u16(d, angle_deg);
    put_u16(d + 2, resolution_cdeg);
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_SET_VARIANT, d, sizeof d);
}

int rsm_lms_encode_request_config(uint8_t *out, size_t cap, uint8_t address)
{
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_GET_CONFIG, NULL, 0u);
}

int rsm_lms_encode_reset(uint8_t *out, size_t cap, uint8_t address)
{
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_RESET, NULL, 0u);
}

/* Distance bits of a measuring mode, 0 for codes that carry no ranges or
 * are not listed. */
static uint8_t measuring_mode_bits(uint8_t mode)
{
    switch (mode) {
    case RSM_LMS_MEAS_8M_FIELDS_AB_DAZZLE:
    case RSM_LMS_MEAS_8M_REFLECTOR:
    case RSM_LMS_MEAS_8M_FIELDS_ABC:
        return 13u;
    case RSM_LMS_MEAS_16M_REFLECTOR:
    case RSM_LMS_MEAS_16M_FIELDS_AB:
        return 14u;
    case RSM_LMS_MEAS_32M_REFLECTOR:
    case RSM_LMS_MEAS_32M_FIELD_A:
        return 15u;
    case RSM_LMS_MEAS_32M_IMMEDIATE:
        return 16u;
    default:
        return 0u;
    }
}

static int units_ok(uint8_t units)
{
    return units == RSM_LMS_UNITS_CM || units == RSM_LMS_UNITS_MM;
}

int rsm_lms_encode_config(uint8_t *out, size_t cap, uint8_t address, const rsm_lms_config_t *cfg)
{
    uint8_t block[RSM_LMS_CONFIG_LONG];

    if (cfg == NULL) {
        return RSM_ERR_INVAL;
    }
    if (cfg->block_len != RSM_LMS_CONFIG_SHORT && cfg->block_len != RSM_LMS_CONFIG_LONG) {
        return RSM_ERR_INVAL;
    }
    if (!units_ok(cfg->units)) {
        return RSM_ERR_INVAL;
    }
    if (measuring_mode_bits(cfg->measuring_mode) == 0u &&
        cfg->measuring_mode != RSM_LMS_MEAS_REFLECTIVITY) {
        return RSM_ERR_INVAL;
    }
    memcpy(block, cfg->block, cfg->block_len);
    put_u16(block, cfg->blanking);
    block[2] = cfg->stop_threshold;
    block[3] = cfg->peak_threshold;
    block[4] = cfg->availability;
    block[5] = cfg->measuring_mode;
    block[6] = cfg->units;
    return encode_request(out, cap, address, (uint8_t)RSM_LMS_CMD_SET_CONFIG, block,
                          cfg->block_len);
}

/* ---- incremental receiver ------------------------------------------------ */

static void clear_event(rsm_lms_event_t *out)
{
    memset(out, 0, sizeof *out);
    out->type = RSM_LMS_EVENT_NONE;
}

int rsm_lms_parser_init_checked(rsm_lms_parser_t *p, size_t p_size, unsigned long fingerprint)
{
    if (!RSM_SAME_BUILD(rsm_lms_parser_t, p_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (p == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(p, 0, sizeof *p);
    return RSM_OK;
}

/* Rejects the candidate at head: its STX is dropped and every byte after it
 * becomes unexamined again. */
static void reject_candidate(rsm_lms_parser_t *p)
{
    p->stats.bytes_skipped++;
    p->head++;
    p->pos = p->head;
}

/* Publishes a one-byte ACK or NAK event. */
static rsm_lms_event_type_t publish_byte(rsm_lms_event_t *out, rsm_lms_event_type_t type)
{
    clear_event(out);
    out->type = type;
    return type;
}

/* Examines the byte at pos (pos < wr) as byte number pos - head of the
 * candidate (0 while hunting). Returns the event type published, or
 * RSM_LMS_EVENT_NONE. */
static rsm_lms_event_type_t examine(rsm_lms_parser_t *p, rsm_lms_event_t *out)
{
    const size_t have = p->pos - p->head; /* candidate bytes before this one */
    const uint8_t b = p->buf[p->pos];
    size_t field;

    if (have == 0u) { /* hunting */
        p->pos++;
        if (b == RSM_LMS_STX) {
            return RSM_LMS_EVENT_NONE; /* candidate started */
        }
        p->head = p->pos;
        if (b == RSM_LMS_ACK) {
            p->stats.acks++;
            return publish_byte(out, RSM_LMS_EVENT_ACK);
        }
        if (b == RSM_LMS_NAK) {
            p->stats.naks++;
            return publish_byte(out, RSM_LMS_EVENT_NAK);
        }
        p->stats.bytes_skipped++;
        return RSM_LMS_EVENT_NONE;
    }
    if (have == 1u && (b & RSM_LMS_REPLY_ADR) == 0u) {
        reject_candidate(p); /* not a reply address: the STX was noise */
        return RSM_LMS_EVENT_NONE;
    }
    p->pos++;
    if (have < 3u) {
        return RSM_LMS_EVENT_NONE; /* ADR or LEN low byte */
    }
    field = get_u16(p->buf + p->head + 2);
    if (have == 3u) {
        if (field == 0u || field > LMS_MAX_LEN) {
            p->stats.bad_length++;
            reject_candidate(p);
        }
        return RSM_LMS_EVENT_NONE;
    }
    if (have + 1u < field + RSM_LMS_OVERHEAD) {
        return RSM_LMS_EVENT_NONE; /* more to come */
    }
    /* complete: LEN + 6 bytes from head */
    if (!frame_crc_ok(p->buf + p->head, field + RSM_LMS_OVERHEAD)) {
        p->stats.crc_errors++;
        reject_candidate(p);
        return RSM_LMS_EVENT_NONE;
    }
    p->stats.telegrams_ok++;
    clear_event(out);
    out->type = RSM_LMS_EVENT_TELEGRAM;
    make_view(p->buf + p->head, field + RSM_LMS_OVERHEAD, &out->telegram);
    p->head = p->pos;
    return RSM_LMS_EVENT_TELEGRAM;
}

/* Empties the buffer indices when nothing is held, and moves the held bytes
 * to the front when the buffer end is reached. */
static void tidy(rsm_lms_parser_t *p)
{
    if (p->head == p->wr) {
        p->head = 0u;
        p->pos = 0u;
        p->wr = 0u;
    } else if (p->wr == LMS_BUF_CAP && p->head > 0u) {
        const size_t held = p->wr - p->head;
        memmove(p->buf, p->buf + p->head, held);
        p->pos -= p->head;
        p->head = 0u;
        p->wr = held;
    }
}

int rsm_lms_parser_feed(rsm_lms_parser_t *p, const uint8_t *data, size_t len, size_t *consumed,
                        rsm_lms_event_t *out)
{
    size_t used = 0u;

    if (p == NULL || consumed == NULL || out == NULL || (data == NULL && len != 0u)) {
        return RSM_ERR_INVAL;
    }
    clear_event(out);
    for (;;) {
        if (p->pos == p->wr) {
            tidy(p);
            if (used == len) {
                break;
            }
            /* Only an incomplete candidate is held here, and a candidate
             * never exceeds LMS_MAX_LEN + 6 <= LMS_BUF_CAP bytes, so after
             * tidy() there is room for one more byte. */
            if (p->wr >= LMS_BUF_CAP) {
                /* Unreachable by the invariant above; drop the candidate
                 * rather than write out of bounds. */
                reject_candidate(p);
                continue;
            }
            p->buf[p->wr++] = data[used++];
        }
        if (examine(p, out) != RSM_LMS_EVENT_NONE) {
            *consumed = used;
            return 1;
        }
    }
    *consumed = used;
    return 0;
}

int rsm_lms_parser_timeout(rsm_lms_parser_t *p, rsm_lms_event_t *out)
{
    if (p == NULL || out == NULL) {
        return RSM_ERR_INVAL;
    }
    clear_event(out);
    for (;;) {
        if (p->pos < p->wr) {
            if (examine(p, out) != RSM_LMS_EVENT_NONE) {
                return 1;
            }
        } else if (p->head < p->pos) {
            p->stats.truncated++;
            reject_candidate(p);
        } else {
            tidy(p);
            return 0;
        }
    }
}

int rsm_lms_parser_flush(rsm_lms_parser_t *p)
{
    size_t held;

    if (p == NULL) {
        return RSM_ERR_INVAL;
    }
    held = p->wr - p->head;
    p->stats.bytes_skipped += (uint32_t)held;
    p->head = 0u;
    p->pos = 0u;
    p->wr = 0u;
    return (int)held;
}

size_t rsm_lms_parser_pending(const rsm_lms_parser_t *p)
{
    return p == NULL ? 0u : p->wr - p->head;
}

/* ---- decoders ------------------------------------------------------------ */

int rsm_lms_decode_status_byte(uint8_t status, rsm_lms_status_byte_t *out)
{
    if (out == NULL) {
        return RSM_ERR_INVAL;
    }
    out->raw = status;
    out->severity = (uint8_t)(status & 0x07u);
    out->implausible = (uint8_t)((status >> 6) & 0x01u);
    out->pollution = (uint8_t)((status >> 7) & 0x01u);
    return RSM_OK;
}

int rsm_lms_b0_format_default(rsm_lms_b0_format_t *fmt)
{
    if (fmt == NULL) {
        return RSM_ERR_INVAL;
    }
    fmt->units = (uint8_t)RSM_LMS_UNITS_AUTO;
    fmt->distance_bits = 13u;
    fmt->index_bytes = 0u;
    return RSM_OK;
}

int rsm_lms_b0_format_from_config(const rsm_lms_config_t *cfg, rsm_lms_b0_format_t *fmt)
{
    uint8_t bits;

    if (cfg == NULL || fmt == NULL) {
        return RSM_ERR_INVAL;
    }
    bits = measuring_mode_bits(cfg->measuring_mode);
    if (bits == 0u || !units_ok(cfg->units)) {
        return RSM_ERR_PROTO;
    }
    fmt->units = cfg->units;
    fmt->distance_bits = bits;
    fmt->index_bytes = (uint8_t)(((cfg->availability & 0x02u) != 0u) ? 2u : 0u);
    return RSM_OK;
}

/* Reason code for a distance field value at offset (mask - distance) from
 * the top of the field, for offsets 0..8. */
static uint8_t reading_code(uint16_t offset_from_top)
{
    switch (offset_from_top) {
    case 0u:
        return (uint8_t)RSM_LMS_READING_NO_ECHO; /* 0x1FFF */
    case 1u:
        return (uint8_t)RSM_LMS_READING_DAZZLED; /* 0x1FFE */
    case 2u:
        return (uint8_t)RSM_LMS_READING_OVERFLOW; /* 0x1FFD */
    case 4u:
        return (uint8_t)RSM_LMS_READING_SNR_LOW; /* 0x1FFB */
    case 5u:
        return (uint8_t)RSM_LMS_READING_CHANNEL_ERROR; /* 0x1FFA */
    case 8u:
        return (uint8_t)RSM_LMS_READING_TOO_FAR; /* 0x1FF7 */
    default:
        return (uint8_t)RSM_LMS_READING_RESERVED; /* 0x1FFC, 0x1FF9, 0x1FF8 */
    }
}

/* Scanner geometry of a full scan with n readings. */
static void scan_geometry(size_t n, uint16_t *start_cdeg, uint16_t *step_cdeg)
{
    *start_cdeg = 0u;
    *step_cdeg = 0u;
    switch (n) {
    case 181u:
        *step_cdeg = 100u;
        break;
    case 361u:
        *step_cdeg = 50u;
        break;
    case 101u:
        *start_cdeg = 4000u;
        *step_cdeg = 100u;
        break;
    case 201u:
        *start_cdeg = 4000u;
        *step_cdeg = 50u;
        break;
    case 401u:
        *start_cdeg = 4000u;
        *step_cdeg = 25u;
        break;
    default:
        break;
    }
}

int rsm_lms_b0_open(const rsm_lms_telegram_t *t, const rsm_lms_b0_format_t *fmt, rsm_lms_b0_view_t *out)
{
    rsm_lms_b0_format_t f;
    rsm_lms_b0_view_t v;
    size_t i;

    if (t == NULL || out == NULL || t->data == NULL) {
        return RSM_ERR_INVAL;
    }
    if (fmt == NULL) {
        (void)rsm_lms_b0_format_default(&f);
    } else {
        f = *fmt;
    }
    if (f.distance_bits < 13u || f.distance_bits > 16u || f.index_bytes > 2u ||
        (f.units != RSM_LMS_UNITS_AUTO && !units_ok(f.units))) {
        return RSM_ERR_INVAL;
    }
    if (t->cmd != RSM_LMS_REPLY_VALUES || t->data_len < 3u) {
        return RSM_ERR_PROTO;
    }
    v.count_word = get_u16(t->data);
    v.count = (size_t)(v.count_word & 0x03FFu);
    v.units = (uint8_t)(v.count_word >> 14);
    if (!units_ok(v.units) || (f.units != RSM_LMS_UNITS_AUTO && f.units != v.units)) {
        return RSM_ERR_PROTO;
    }
    if (t->data_len != 2u + 2u * v.count + (size_t)f.index_bytes + 1u) {
        return RSM_ERR_PROTO;
    }
    if (v.count > (size_t)RSM_MAX_BEAMS) {
        return RSM_ERR_NOMEM;
    }
    v.values = t->data + 2u;
    v.distance_bits = f.distance_bits;
    v.distance_mask = (uint16_t)((1ul << f.distance_bits) - 1ul);
    v.partial = (uint8_t)((v.count_word >> 13) & 0x01u);
    v.partial_index = (uint8_t)((v.count_word >> 11) & 0x03u);
    v.index_len = f.index_bytes;
    v.index[0] = 0u;
    v.index[1] = 0u;
    for (i = 0; i < (size_t)f.index_bytes; ++i) {
        v.index[i] = t->data[2u + 2u * v.count + i];
    }
    v.status = t->data[t->data_len - 1u];
    if (v.partial != 0u) {
        v.start_cdeg = 0u;
        v.step_cdeg = 0u;
    } else {
        scan_geometry(v.count, &v.start_cdeg, &v.step_cdeg);
    }
    *out = v;
    return RSM_OK;
}

rsm_lms_reading_t rsm_lms_b0_reading(const rsm_lms_b0_view_t *v, size_t i)
{
    const uint16_t raw = get_u16(v->values + 2u * i);
    const uint16_t mask = v->distance_mask;
    const uint16_t dist = (uint16_t)(raw & mask);
    const float scale = (v->units == RSM_LMS_UNITS_MM) ? 1000.0f : 100.0f;
    rsm_lms_reading_t r;
    r.raw = raw;
    r.flags = (uint8_t)(v->distance_bits < 16u ? (unsigned)raw >> v->distance_bits : 0u);
    if (dist >= (uint16_t)(mask - 8u)) {
        r.code = reading_code((uint16_t)(mask - dist));
        r.range_m = 0.0f;
    } else {
        r.code = (uint8_t)RSM_LMS_READING_OK;
        r.range_m = (float)dist / scale;
    }
    return r;
}

int rsm_lms_decode_b0_checked(const rsm_lms_telegram_t *t, const rsm_lms_b0_format_t *fmt, rsm_lms_scan_t *out,
                              size_t out_size, unsigned long fingerprint)
{
    rsm_lms_b0_view_t v;
    size_t i;
    int rc;

    if (!RSM_SAME_BUILD(rsm_lms_scan_t, out_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (out == NULL) {
        return RSM_ERR_INVAL;
    }
    if ((rc = rsm_lms_b0_open(t, fmt, &v)) != RSM_OK) {
        return rc;
    }
    for (i = 0; i < v.count; ++i) {
        out->reading[i] = rsm_lms_b0_reading(&v, i);
    }
    out->count = v.count;
    out->count_word = v.count_word;
    out->distance_mask = v.distance_mask;
    out->units = v.units;
    out->partial = v.partial;
    out->partial_index = v.partial_index;
    out->index_len = v.index_len;
    out->index[0] = v.index[0];
    out->index[1] = v.index[1];
    out->status = v.status;
    out->start_cdeg = v.start_cdeg;
    out->step_cdeg = v.step_cdeg;
    return RSM_OK;
}

int rsm_lms_scan_angle(const rsm_lms_scan_t *scan, size_t i, float *angle_rad)
{
    uint32_t cdeg;

    if (scan == NULL || angle_rad == NULL) {
        return RSM_ERR_INVAL;
    }
    if (i >= scan->count || scan->step_cdeg == 0u) {
        return RSM_ERR_RANGE;
    }
    cdeg = (uint32_t)scan->start_cdeg + (uint32_t)i * (uint32_t)scan->step_cdeg;
    *angle_rad = (float)cdeg * (RSM_PI / 18000.0f);
    return RSM_OK;
}

/* Common checks of the fixed-layout decoders. */
static int check_reply(const rsm_lms_telegram_t *t, const void *out, uint8_t cmd)
{
    if (t == NULL || out == NULL || t->data == NULL) {
        return RSM_ERR_INVAL;
    }
    if (t->cmd != cmd) {
        return RSM_ERR_PROTO;
    }
    return RSM_OK;
}

int rsm_lms_decode_mode_reply(const rsm_lms_telegram_t *t, rsm_lms_mode_reply_t *out)
{
    const int rc = check_reply(t, out, (uint8_t)RSM_LMS_REPLY_MODE);
    if (rc != RSM_OK) {
        return rc;
    }
    if (t->data_len != 2u) {
        return RSM_ERR_PROTO;
    }
    out->result = t->data[0];
    out->status = t->data[1];
    return RSM_OK;
}

int rsm_lms_decode_variant_reply(const rsm_lms_telegram_t *t, rsm_lms_variant_reply_t *out)
{
    const int rc = check_reply(t, out, (uint8_t)RSM_LMS_REPLY_VARIANT);
    if (rc != RSM_OK) {
        return rc;
    }
    if (t->data_len != 6u) {
        return RSM_ERR_PROTO;
    }
    out->result = t->data[0];
    out->angle_deg = get_u16(t->data + 1);
    out->resolution_cdeg = get_u16(t->data + 3);
    out->status = t->data[5];
    return RSM_OK;
}

int rsm_lms_decode_reset_reply(const rsm_lms_telegram_t *t, uint8_t *status)
{
    const int rc = check_reply(t, status, (uint8_t)RSM_LMS_REPLY_RESET);
    if (rc != RSM_OK) {
        return rc;
    }
    if (t->data_len != 1u) {
        return RSM_ERR_PROTO;
    }
    *status = t->data[0];
    return RSM_OK;
}

int rsm_lms_decode_not_ack(const rsm_lms_telegram_t *t, uint8_t *status)
{
    const int rc = check_reply(t, status, (uint8_t)RSM_LMS_REPLY_NOT_ACK);
    if (rc != RSM_OK) {
        return rc;
    }
    if (t->data_len < 1u) {
        return RSM_ERR_PROTO;
    }
    *status = t->data[t->data_len - 1u];
    return RSM_OK;
}

static int decode_text(const rsm_lms_telegram_t *t, rsm_lms_text_reply_t *out, uint8_t cmd)
{
    size_t n;
    const int rc = check_reply(t, out, cmd);
    if (rc != RSM_OK) {
        return rc;
    }
    if (t->data_len < 1u) {
        return RSM_ERR_PROTO;
    }
    n = t->data_len - 1u;
    if (n > RSM_LMS_TEXT_MAX) {
        return RSM_ERR_NOMEM;
    }
    memcpy(out->text, t->data, n);
    memset(out->text + n, 0, sizeof out->text - n);
    out->text_len = n;
    out->status = t->data[n];
    return RSM_OK;
}

int rsm_lms_decode_power_on(const rsm_lms_telegram_t *t, rsm_lms_text_reply_t *out)
{
    return decode_text(t, out, (uint8_t)RSM_LMS_REPLY_POWER_ON);
}

int rsm_lms_decode_type_reply(const rsm_lms_telegram_t *t, rsm_lms_text_reply_t *out)
{
    return decode_text(t, out, (uint8_t)RSM_LMS_REPLY_TYPE);
}

/* Fills a config from block_len bytes at b and a status byte. */
static void fill_config(rsm_lms_config_t *c, const uint8_t *b, size_t block_len, uint8_t status)
{
    memset(c->block, 0, sizeof c->block);
    memcpy(c->block, b, block_len);
    c->block_len = block_len;
    c->blanking = get_u16(b);
    c->stop_threshold = b[2];
    c->peak_threshold = b[3];
    c->availability = b[4];
    c->measuring_mode = b[5];
    c->units = b[6];
    c->status = status;
}

int rsm_lms_decode_config(const rsm_lms_telegram_t *t, rsm_lms_config_t *out)
{
    size_t block_len;
    const int rc = check_reply(t, out, (uint8_t)RSM_LMS_REPLY_CONFIG);
    if (rc != RSM_OK) {
        return rc;
    }
    if (t->data_len != RSM_LMS_CONFIG_SHORT + 1u && t->data_len != RSM_LMS_CONFIG_LONG + 1u) {
        return RSM_ERR_PROTO;
    }
    block_len = t->data_len - 1u;
    fill_config(out, t->data, block_len, t->data[block_len]);
    return RSM_OK;
}

int rsm_lms_decode_config_reply(const rsm_lms_telegram_t *t, rsm_lms_config_reply_t *out)
{
    size_t block_len;
    const int rc = check_reply(t, out, (uint8_t)RSM_LMS_REPLY_SET_CONFIG);
    if (rc != RSM_OK) {
        return rc;
    }
    if (t->data_len != RSM_LMS_CONFIG_SHORT + 2u && t->data_len != RSM_LMS_CONFIG_LONG + 2u) {
        return RSM_ERR_PROTO;
    }
    block_len = t->data_len - 2u;
    out->result = t->data[0];
    fill_config(&out->config, t->data + 1, block_len, t->data[1u + block_len]);
    return RSM_OK;
}
