#include "rsm/rplidar.h"

#include <string.h>

#include "rsm/status.h"
#include "core/bytes.h"

/* What the receiver expects next (rsm_rplidar_parser_t.mode). */
#define MODE_DESCRIPTOR 0u
#define MODE_RESPONSE 1u /* one answer of p->length bytes */
#define MODE_NODES 2u
#define MODE_CAPSULES 3u

#define FULL_TURN_Q6 (360u * 64u)
#define EXPRESS_SAMPLES 32u
#define DENSE_SAMPLES 40u

/* Verdicts of check(). */
#define NEED_MORE 0
#define COMPLETE 1
#define REJECT (-1)
#define REJECT_CHECKSUM (-2)
#define REJECT_FIELD (-3)

int rsm_rplidar_encode_request(uint8_t *out, size_t cap, uint8_t cmd, const uint8_t *payload,
                               size_t n)
{
    size_t i;
    uint8_t sum;
    if (out == NULL || n > RSM_RPLIDAR_MAX_PAYLOAD || (payload == NULL && n > 0u)) {
        return RSM_ERR_INVAL;
    }
    if (cap < (n == 0u ? 2u : n + 4u)) {
        return RSM_ERR_NOMEM;
    }
    out[0] = RSM_RPLIDAR_SYNC1;
    out[1] = cmd;
    if (n == 0u) {
        return 2;
    }
    out[2] = (uint8_t)n;
    memcpy(out + 3, payload, n);
    sum = 0u;
    for (i = 0; i < n + 3u; ++i) {
        sum = (uint8_t)(sum ^ out[i]);
    }
    out[n + 3u] = sum;
    return (int)(n + 4u);
}

int rsm_rplidar_encode_express_scan(uint8_t *out, size_t cap)
{
    static const uint8_t legacy[5] = {0u, 0u, 0u, 0u, 0u};
    return rsm_rplidar_encode_request(out, cap, RSM_RPLIDAR_CMD_EXPRESS_SCAN, legacy, sizeof legacy);
}

int rsm_rplidar_encode_motor(uint8_t *out, size_t cap, uint8_t cmd, uint16_t value)
{
    uint8_t v[2];
    if (cmd != RSM_RPLIDAR_CMD_MOTOR_SPEED && cmd != RSM_RPLIDAR_CMD_MOTOR_PWM) {
        return RSM_ERR_INVAL;
    }
    rsm_put_u16le(v, value);
    return rsm_rplidar_encode_request(out, cap, cmd, v, sizeof v);
}

int rsm_rplidar_encode_descriptor(uint8_t *out, size_t cap, uint32_t length, uint8_t mode,
                                  uint8_t type)
{
    uint32_t w;
    if (out == NULL || length >= (1ul << 30) || mode > 1u) {
        return RSM_ERR_INVAL;
    }
    if (cap < RSM_RPLIDAR_DESCRIPTOR) {
        return RSM_ERR_NOMEM;
    }
    w = length | ((uint32_t)mode << 30);
    out[0] = RSM_RPLIDAR_SYNC1;
    out[1] = RSM_RPLIDAR_SYNC2;
    out[2] = (uint8_t)(w & 0xFFu);
    out[3] = (uint8_t)((w >> 8) & 0xFFu);
    out[4] = (uint8_t)((w >> 16) & 0xFFu);
    out[5] = (uint8_t)(w >> 24);
    out[6] = type;
    return (int)RSM_RPLIDAR_DESCRIPTOR;
}

int rsm_rplidar_parser_init(rsm_rplidar_parser_t *p)
{
    if (p == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(p, 0, sizeof *p);
    p->mode = MODE_DESCRIPTOR;
    return RSM_OK;
}

int rsm_rplidar_parser_flush(rsm_rplidar_parser_t *p)
{
    if (p == NULL) {
        return RSM_ERR_INVAL;
    }
    if (p->have_prev) {
        p->stats.unpaired++;
    }
    p->have_prev = 0u;
    return rsm_drop_partial(&p->n, &p->stats.bytes_skipped, &p->stats.truncated);
}

int rsm_rplidar_parser_expect(rsm_rplidar_parser_t *p)
{
    const int dropped = rsm_rplidar_parser_flush(p);
    if (dropped >= 0) {
        p->mode = MODE_DESCRIPTOR;
    }
    return dropped;
}

int rsm_rplidar_parser_resume(rsm_rplidar_parser_t *p, uint8_t answer)
{
    int dropped;
    if (p == NULL || (answer != RSM_RPLIDAR_ANS_NODE && answer != RSM_RPLIDAR_ANS_CAPSULE &&
                      answer != RSM_RPLIDAR_ANS_DENSE)) {
        return RSM_ERR_INVAL;
    }
    dropped = rsm_rplidar_parser_flush(p);
    p->answer = answer;
    p->length = answer == RSM_RPLIDAR_ANS_NODE ? RSM_RPLIDAR_NODE : RSM_RPLIDAR_CAPSULE;
    p->mode = answer == RSM_RPLIDAR_ANS_NODE ? MODE_NODES : MODE_CAPSULES;
    return dropped;
}

size_t rsm_rplidar_parser_pending(const rsm_rplidar_parser_t *p)
{
    return p == NULL ? 0u : p->n;
}

/* The answers this receiver knows: type, length, send mode. */
static int known_descriptor(uint8_t type, uint32_t length, uint32_t mode)
{
    switch (type) {
    case RSM_RPLIDAR_ANS_INFO:
        return length == 20u && mode == 0u;
    case RSM_RPLIDAR_ANS_HEALTH:
        return length == 3u && mode == 0u;
    case RSM_RPLIDAR_ANS_SAMPLERATE:
        return length == 4u && mode == 0u;
    case RSM_RPLIDAR_ANS_NODE:
        return length == RSM_RPLIDAR_NODE && mode == 1u;
    case RSM_RPLIDAR_ANS_CAPSULE:
    case RSM_RPLIDAR_ANS_DENSE:
        return length == RSM_RPLIDAR_CAPSULE && mode == 1u;
    default:
        return 0;
    }
}

/* Judges the candidate buf[0..n) against what the mode expects: every
 * check whose bytes are there is made, so a prefix that cannot start a
 * frame is rejected at once. */
static int check(const rsm_rplidar_parser_t *p)
{
    const uint8_t *b = p->buf;
    const size_t n = p->n;
    switch (p->mode) {
    case MODE_DESCRIPTOR:
        if (b[0] != RSM_RPLIDAR_SYNC1 || (n >= 2u && b[1] != RSM_RPLIDAR_SYNC2)) {
            return REJECT;
        }
        if (n < RSM_RPLIDAR_DESCRIPTOR) {
            return NEED_MORE;
        }
        {
            const uint32_t w = rsm_get_u32le(b + 2);
            return known_descriptor(b[6], w & 0x3FFFFFFFu, w >> 30) ? COMPLETE : REJECT;
        }
    case MODE_RESPONSE:
        return n < p->length ? NEED_MORE : COMPLETE;
    case MODE_NODES:
        if (((b[0] ^ (b[0] >> 1)) & 1u) == 0u || (n >= 2u && (b[1] & 1u) == 0u) ||
            (n >= 3u && (rsm_get_u16le(b + 1) >> 1) >= FULL_TURN_Q6)) {
            return REJECT;
        }
        return n < RSM_RPLIDAR_NODE ? NEED_MORE : COMPLETE;
    default: /* MODE_CAPSULES */
        if ((b[0] >> 4) != 0xAu || (n >= 2u && (b[1] >> 4) != 0x5u)) {
            return REJECT;
        }
        if (n < RSM_RPLIDAR_CAPSULE) {
            return NEED_MORE;
        }
        {
            uint8_t sum = 0u;
            size_t i;
            for (i = 2; i < RSM_RPLIDAR_CAPSULE; ++i) {
                sum = (uint8_t)(sum ^ b[i]);
            }
            if (sum != (uint8_t)((b[0] & 0x0Fu) | (uint8_t)(b[1] << 4))) {
                return REJECT_CHECKSUM;
            }
        }
        return (rsm_get_u16le(b + 2) & 0x7FFFu) < FULL_TURN_Q6 ? COMPLETE : REJECT_FIELD;
    }
}

/* Drops the candidate's first byte, then every byte that cannot start a
 * candidate. A lost byte in a capsule stream breaks the pairing of
 * neighbouring capsules. */
static void resync(rsm_rplidar_parser_t *p)
{
    if (p->mode == MODE_CAPSULES && p->have_prev) {
        p->have_prev = 0u;
        p->stats.unpaired++;
    }
    do {
        memmove(p->buf, p->buf + 1, p->n - 1u);
        p->n--;
        p->stats.bytes_skipped++;
    } while (p->n > 0u && check(p) < 0);
}

/* Sample k of n of capsule c, the next capsule starting diff (1/64 deg)
 * after it: exact fractions of 1/64 deg kept in integers until the end. */
static void capsule_samples(const uint8_t *c, uint8_t answer, uint32_t diff,
                            rsm_rplidar_event_t *ev)
{
    const int32_t start = (int32_t)(rsm_get_u16le(c + 2) & 0x7FFFu);
    const int32_t turn = (int32_t)FULL_TURN_Q6;
    const uint32_t ns = answer == RSM_RPLIDAR_ANS_DENSE ? DENSE_SAMPLES : EXPRESS_SAMPLES;
    uint32_t k;
    for (k = 0; k < ns; ++k) {
        rsm_lidar_point_t *pt = &ev->points[k];
        /* angle in 1/(64 * ns) deg */
        int32_t a = start * (int32_t)ns + (int32_t)(diff * k);
        float mm;
        if (answer == RSM_RPLIDAR_ANS_DENSE) {
            mm = (float)rsm_get_u16le(c + 4 + 2u * k);
        } else {
            const uint8_t *cab = c + 4 + 5u * (k / 2u);
            const uint16_t d = rsm_get_u16le(cab + 2u * (k & 1u));
            const uint32_t low = (k & 1u) ? (uint32_t)(cab[4] >> 4) : (uint32_t)(cab[4] & 0x0Fu);
            const uint32_t offset_q3 = low | ((uint32_t)(d & 3u) << 4);
            a -= (int32_t)(offset_q3 * 8u * ns);
            mm = (float)(d >> 2);
        }
        while (a < 0) {
            a += turn * (int32_t)ns;
        }
        a %= turn * (int32_t)ns;
        pt->angle_deg = (float)a / (64.0f * (float)ns);
        pt->range_m = mm * 0.001f;
        pt->quality = 0u;
        pt->start = 0u;
    }
    ev->count = ns;
}

/* A verified frame in buf: acts on it and fills *ev. Returns 1 if *ev is an
 * event for the caller. */
static int take_frame(rsm_rplidar_parser_t *p, rsm_rplidar_event_t *ev)
{
    const uint8_t *b = p->buf;
    memset(ev, 0, sizeof *ev);
    p->stats.bytes_framed += (uint32_t)p->n;
    p->n = 0;
    switch (p->mode) {
    case MODE_DESCRIPTOR: {
        const uint32_t w = rsm_get_u32le(b + 2);
        p->stats.descriptors++;
        p->answer = b[6];
        p->length = w & 0x3FFFFFFFu;
        p->mode = (w >> 30) == 0u ? MODE_RESPONSE
                  : p->answer == RSM_RPLIDAR_ANS_NODE ? MODE_NODES
                                                      : MODE_CAPSULES;
        p->have_prev = 0u;
        ev->type = RSM_RPLIDAR_EVENT_DESCRIPTOR;
        ev->answer = p->answer;
        return 1;
    }
    case MODE_RESPONSE:
        p->stats.responses++;
        p->mode = MODE_DESCRIPTOR;
        ev->answer = p->answer;
        if (p->answer == RSM_RPLIDAR_ANS_INFO) {
            ev->type = RSM_RPLIDAR_EVENT_INFO;
            ev->info.model = b[0];
            ev->info.firmware_minor = b[1];
            ev->info.firmware_major = b[2];
            ev->info.hardware = b[3];
            memcpy(ev->info.serial, b + 4, sizeof ev->info.serial);
        } else if (p->answer == RSM_RPLIDAR_ANS_HEALTH) {
            ev->type = RSM_RPLIDAR_EVENT_HEALTH;
            ev->health.status = b[0];
            ev->health.error_code = rsm_get_u16le(b + 1);
        } else {
            ev->type = RSM_RPLIDAR_EVENT_SAMPLERATE;
            ev->samplerate.standard_us = rsm_get_u16le(b);
            ev->samplerate.express_us = rsm_get_u16le(b + 2);
        }
        return 1;
    case MODE_NODES:
        p->stats.nodes++;
        p->stats.points++;
        ev->type = RSM_RPLIDAR_EVENT_POINTS;
        ev->answer = p->answer;
        ev->count = 1;
        ev->points[0].quality = (uint8_t)(b[0] >> 2);
        ev->points[0].start = (uint8_t)(b[0] & 1u);
        ev->points[0].angle_deg = (float)(rsm_get_u16le(b + 1) >> 1) / 64.0f;
        ev->points[0].range_m = (float)rsm_get_u16le(b + 3) * 0.00025f;
        return 1;
    default: { /* MODE_CAPSULES */
        const uint16_t word = rsm_get_u16le(b + 2);
        int published = 0;
        p->stats.capsules++;
        if (p->have_prev) {
            const uint32_t prev = rsm_get_u16le(p->prev + 2) & 0x7FFFu;
            const uint32_t diff = ((word & 0x7FFFu) + FULL_TURN_Q6 - prev) % FULL_TURN_Q6;
            /* a new turn restarts the sensor's angle encoder (the protocol
             * notes): the previous capsule has no usable successor */
            if ((word & 0x8000u) == 0u && diff > 0u && diff <= RSM_RPLIDAR_MAX_CAPSULE_SPAN_Q6) {
                ev->type = RSM_RPLIDAR_EVENT_POINTS;
                ev->answer = p->answer;
                capsule_samples(p->prev, p->answer, diff, ev);
                p->stats.points += (uint32_t)ev->count;
                published = 1;
            } else {
                p->stats.unpaired++;
            }
        }
        memcpy(p->prev, b, RSM_RPLIDAR_CAPSULE);
        p->have_prev = 1u;
        return published;
    }
    }
}

int rsm_rplidar_parser_feed(rsm_rplidar_parser_t *p, const uint8_t *data, size_t len,
                            size_t *consumed, rsm_rplidar_event_t *out)
{
    size_t used = 0;
    if (p == NULL || consumed == NULL || out == NULL || (data == NULL && len > 0u)) {
        return RSM_ERR_INVAL;
    }
    *consumed = 0;
    out->type = RSM_RPLIDAR_EVENT_NONE;
    while (used < len) {
        int verdict;
        p->buf[p->n++] = data[used++];
        p->stats.bytes_fed++;
        verdict = check(p);
        if (verdict == COMPLETE) {
            if (take_frame(p, out)) {
                *consumed = used;
                return 1;
            }
        } else if (verdict < 0) {
            if (verdict == REJECT_CHECKSUM) {
                p->stats.checksum_errors++;
            } else if (verdict == REJECT_FIELD) {
                p->stats.bad_capsules++;
            } else if (p->mode == MODE_DESCRIPTOR && p->n == RSM_RPLIDAR_DESCRIPTOR) {
                p->stats.bad_descriptors++;
            } else if (p->mode == MODE_NODES) {
                p->stats.bad_nodes++;
            }
            resync(p);
        }
    }
    *consumed = used;
    out->type = RSM_RPLIDAR_EVENT_NONE;
    return 0;
}
