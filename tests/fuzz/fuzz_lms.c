/* libFuzzer target for the SICK LMS 2xx codec (src/drivers/lms.c).
 *
 * The input is a byte stream as it could arrive from the serial line. It is
 * fed to one receiver in chunks whose split points come from the input (its
 * last byte seeds the chunk sizes) and, byte by byte, to a second receiver;
 * both must publish the same events and end with the same counters. Every
 * published telegram goes through every decoder, the whole input also goes
 * through rsm_lms_telegram_view, and an encoder round trip is checked.
 * Invariants that fail stop the run with __builtin_trap(). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "rsm/config.h"
#include "rsm/lms.h"
#include "rsm/status.h"

#include "fuzz_check.h"


typedef struct run_state {
    rsm_lms_parser_t parser;
    uint32_t events_hash; /* order-sensitive digest of every event */
    uint64_t published;   /* bytes inside published telegrams */
} run_state_t;

static uint32_t mix(uint32_t h, uint8_t b)
{
    return (h ^ b) * 16777619u;
}

/* Every decoder on a verified telegram. Failing decoders leave their
 * output untouched; succeeding ones give consistent fields. */
static void check_decoders(const rsm_lms_telegram_t *t)
{
    static const uint8_t bits[4] = {13, 14, 15, 16};
    rsm_lms_scan_t scan;
    rsm_lms_scan_t scan_before;
    rsm_lms_b0_format_t fmt;
    rsm_lms_mode_reply_t mode;
    rsm_lms_variant_reply_t variant;
    rsm_lms_text_reply_t text;
    rsm_lms_config_t cfg;
    rsm_lms_config_reply_t cfg_reply;
    uint8_t status;
    size_t b;
    size_t idx;
    int rc;

    for (b = 0; b < 8u; ++b) {
        CHECK(rsm_lms_b0_format_default(&fmt) == RSM_OK);
        fmt.distance_bits = bits[b % 4u];
        fmt.index_bytes = (uint8_t)((b / 4u) * 2u);
        memset(&scan, 0xA5, sizeof scan);
        memcpy(&scan_before, &scan, sizeof scan);
        rc = rsm_lms_decode_b0(t, &fmt, &scan);
        if (rc != RSM_OK) {
            CHECK(rc == RSM_ERR_PROTO || rc == RSM_ERR_NOMEM);
            CHECK(memcmp(&scan, &scan_before, sizeof scan) == 0);
            continue;
        }
        CHECK(t->cmd == RSM_LMS_REPLY_VALUES);
        CHECK(scan.count <= (size_t)RSM_MAX_BEAMS);
        CHECK(scan.count == (size_t)(scan.count_word & 0x03FFu));
        CHECK(t->data_len == 3u + 2u * scan.count + fmt.index_bytes);
        CHECK(scan.units == RSM_LMS_UNITS_CM || scan.units == RSM_LMS_UNITS_MM);
        CHECK(scan.status == t->data[t->data_len - 1u]);
        for (idx = 0; idx < scan.count; ++idx) {
            const rsm_lms_reading_t *r = &scan.reading[idx];
            const uint16_t dist = (uint16_t)(r->raw & scan.distance_mask);
            if (r->code == RSM_LMS_READING_OK) {
                CHECK(dist < (uint16_t)(scan.distance_mask - 8u));
                CHECK(r->range_m >= 0.0f && r->range_m <= 656.0f);
            } else {
                CHECK(r->code <= RSM_LMS_READING_RESERVED);
                CHECK(dist >= (uint16_t)(scan.distance_mask - 8u));
                CHECK(r->range_m == 0.0f);
            }
        }
        for (idx = 0; idx <= scan.count; ++idx) {
            float a = -1.0f;
            rc = rsm_lms_scan_angle(&scan, idx, &a);
            if (rc == RSM_OK) {
                CHECK(idx < scan.count && scan.step_cdeg != 0u);
                CHECK(a >= 0.0f && a <= 3.1416f);
            } else {
                CHECK(rc == RSM_ERR_RANGE && a == -1.0f);
            }
        }
    }

    if (t->data_len >= 1u) {
        rsm_lms_status_byte_t sb;
        CHECK(rsm_lms_decode_status_byte(t->data[t->data_len - 1u], &sb) == RSM_OK);
        CHECK(sb.severity <= 7u && sb.implausible <= 1u && sb.pollution <= 1u);
    }

    memset(&mode, 0xA5, sizeof mode);
    rc = rsm_lms_decode_mode_reply(t, &mode);
    CHECK(rc == RSM_OK || (rc == RSM_ERR_PROTO && mode.result == 0xA5u));
    CHECK(rc != RSM_OK || (t->cmd == RSM_LMS_REPLY_MODE && t->data_len == 2u));

    memset(&variant, 0xA5, sizeof variant);
    rc = rsm_lms_decode_variant_reply(t, &variant);
    CHECK(rc == RSM_OK || (rc == RSM_ERR_PROTO && variant.result == 0xA5u));
    CHECK(rc != RSM_OK || (t->cmd == RSM_LMS_REPLY_VARIANT && t->data_len == 6u));

    status = 0xA5u;
    rc = rsm_lms_decode_reset_reply(t, &status);
    CHECK(rc == RSM_OK || (rc == RSM_ERR_PROTO && status == 0xA5u));
    status = 0xA5u;
    rc = rsm_lms_decode_not_ack(t, &status);
    CHECK(rc == RSM_OK || (rc == RSM_ERR_PROTO && status == 0xA5u));

    memset(&text, 0xA5, sizeof text);
    rc = rsm_lms_decode_power_on(t, &text);
    if (rc == RSM_OK) {
        CHECK(text.text_len <= RSM_LMS_TEXT_MAX && text.text[text.text_len] == '\0');
        CHECK(text.text_len + 1u == t->data_len);
    } else {
        CHECK((rc == RSM_ERR_PROTO || rc == RSM_ERR_NOMEM) && text.status == 0xA5u);
    }
    memset(&text, 0xA5, sizeof text);
    rc = rsm_lms_decode_type_reply(t, &text);
    CHECK(rc == RSM_OK || rc == RSM_ERR_PROTO || rc == RSM_ERR_NOMEM);

    memset(&cfg, 0xA5, sizeof cfg);
    rc = rsm_lms_decode_config(t, &cfg);
    if (rc == RSM_OK) {
        uint8_t out[RSM_LMS_CONFIG_LONG + 8u];
        CHECK(cfg.block_len == RSM_LMS_CONFIG_SHORT || cfg.block_len == RSM_LMS_CONFIG_LONG);
        rc = rsm_lms_b0_format_from_config(&cfg, &fmt);
        CHECK(rc == RSM_OK || rc == RSM_ERR_PROTO);
        rc = rsm_lms_encode_config(out, sizeof out, 0x00, &cfg);
        CHECK(rc == RSM_ERR_INVAL || rc == (int)(cfg.block_len + 7u));
    } else {
        CHECK(rc == RSM_ERR_PROTO && cfg.status == 0xA5u);
    }
    memset(&cfg_reply, 0xA5, sizeof cfg_reply);
    rc = rsm_lms_decode_config_reply(t, &cfg_reply);
    CHECK(rc == RSM_OK || (rc == RSM_ERR_PROTO && cfg_reply.result == 0xA5u));
}

/* Checks one receiver event and folds it into the run's digest. */
static void take_event(run_state_t *rs, const rsm_lms_event_t *ev)
{
    rsm_lms_telegram_t again;
    const rsm_lms_telegram_t *t = &ev->telegram;
    size_t i;

    rs->events_hash = mix(rs->events_hash, (uint8_t)ev->type);
    if (ev->type != RSM_LMS_EVENT_TELEGRAM) {
        CHECK(ev->type == RSM_LMS_EVENT_ACK || ev->type == RSM_LMS_EVENT_NAK);
        CHECK(t->frame == NULL && t->frame_len == 0u);
        return;
    }
    /* inside the receiver's buffer, framed, CRC verified */
    CHECK(t->frame >= rs->parser.buf);
    CHECK(t->frame_len <= sizeof rs->parser.buf);
    CHECK((size_t)(t->frame - rs->parser.buf) <= sizeof rs->parser.buf - t->frame_len);
    CHECK(t->len >= 1u && t->len <= (uint16_t)RSM_LMS_MAX_LEN);
    CHECK(t->frame_len == (size_t)t->len + RSM_LMS_OVERHEAD);
    CHECK(t->data == t->frame + 5 && t->data_len == (size_t)t->len - 1u);
    CHECK(t->frame[0] == RSM_LMS_STX && (t->adr & RSM_LMS_REPLY_ADR) != 0u);
    CHECK(rsm_lms_telegram_view(t->frame, t->frame_len, &again) == RSM_OK);
    CHECK(again.cmd == t->cmd && again.len == t->len);
    for (i = 0; i < t->frame_len; ++i) {
        rs->events_hash = mix(rs->events_hash, t->frame[i]);
    }
    rs->published += t->frame_len;
    check_decoders(t);
}

static void feed(run_state_t *rs, const uint8_t *data, size_t len)
{
    size_t done = 0;
    for (;;) {
        rsm_lms_event_t ev;
        size_t used = (size_t)-1;
        const int r = rsm_lms_parser_feed(&rs->parser, data + done, len - done, &used, &ev);
        CHECK(r == 0 || r == 1);
        CHECK(used <= len - done);
        done += used;
        if (r == 0) {
            CHECK(done == len && ev.type == RSM_LMS_EVENT_NONE);
            return;
        }
        take_event(rs, &ev);
    }
}

static void finish(run_state_t *rs, size_t fed)
{
    rsm_lms_event_t ev;
    const rsm_lms_parser_stats_t *st = &rs->parser.stats;
    int r;
    while ((r = rsm_lms_parser_timeout(&rs->parser, &ev)) == 1) {
        take_event(rs, &ev);
    }
    CHECK(r == 0);
    CHECK(rs->parser.wr == rs->parser.head);
    /* every byte accounted for exactly once */
    CHECK((uint64_t)st->bytes_skipped + st->acks + st->naks + rs->published == (uint64_t)fed);
}

static void run_init(run_state_t *rs)
{
    CHECK(rsm_lms_parser_init(&rs->parser) == RSM_OK);
    rs->events_hash = 2166136261u;
    rs->published = 0u;
}

/* The encoder's output is received as exactly one identical telegram. */
static void check_round_trip(const uint8_t *data, size_t size)
{
    uint8_t frame[RSM_LMS_MAX_TELEGRAM];
    rsm_lms_parser_t p;
    rsm_lms_event_t ev;
    size_t used = 0;
    size_t n;
    int rc;

    if (size < 2u) {
        return;
    }
    n = size - 2u;
    if (n > (size_t)RSM_LMS_MAX_LEN - 1u) {
        n = (size_t)RSM_LMS_MAX_LEN - 1u;
    }
    rc = rsm_lms_encode(frame, sizeof frame, (uint8_t)(data[0] | 0x80u), data[1], data + 2, n);
    CHECK(rc == (int)(n + 7u));
    CHECK(rsm_lms_parser_init(&p) == RSM_OK);
    CHECK(rsm_lms_parser_feed(&p, frame, (size_t)rc, &used, &ev) == 1);
    CHECK(used == (size_t)rc && ev.type == RSM_LMS_EVENT_TELEGRAM);
    CHECK(ev.telegram.frame_len == (size_t)rc);
    CHECK(memcmp(ev.telegram.frame, frame, (size_t)rc) == 0);
    /* a CRC-valid telegram around arbitrary data reaches the decoders' deep
     * paths far more often than a stream where the CRC has to be found */
    check_decoders(&ev.telegram);
    CHECK(rsm_lms_parser_feed(&p, frame + used, 0u, &used, &ev) == 0);
    CHECK(p.stats.telegrams_ok == 1u && p.stats.bytes_skipped == 0u);
}

/* Checks an encoder result: an error, or a frame of the expected size that
 * verifies and carries the request command. */
static void check_request(int rc, const uint8_t *out, uint8_t cmd, uint8_t address)
{
    rsm_lms_telegram_t t;
    if (rc < 0) {
        CHECK(rc == RSM_ERR_INVAL);
        return;
    }
    CHECK(rc >= 7 && rc <= (int)RSM_LMS_MAX_TELEGRAM);
    CHECK(rsm_lms_telegram_view(out, (size_t)rc, &t) == RSM_OK);
    CHECK(t.cmd == cmd && t.adr == address);
}

/* Every request encoder with arguments taken from the input. */
static void check_encoders(const uint8_t *data, size_t size)
{
    uint8_t in[16];
    uint8_t out[64];
    rsm_lms_config_t cfg;
    uint8_t adr;
    uint16_t a;
    uint16_t b;
    static const uint32_t bauds[8] = {9600u, 19200u, 38400u, 500000u, 57600u, 0u, 115200u, 1u};

    memset(in, 0, sizeof in);
    memcpy(in, data, size < sizeof in ? size : sizeof in);
    adr = in[0];
    a = (uint16_t)(in[2] | (in[3] << 8));
    b = (uint16_t)(in[4] | (in[5] << 8));
    check_request(rsm_lms_encode_mode(out, sizeof out, adr, in[1]), out, 0x20u, adr);
    check_request(rsm_lms_encode_mode_installation(out, sizeof out, adr, in + 8), out, 0x20u,
                  adr);
    check_request(rsm_lms_encode_mode_mean(out, sizeof out, adr, in[1]), out, 0x20u, adr);
    check_request(rsm_lms_encode_mode_subrange(out, sizeof out, adr, a, b), out, 0x20u, adr);
    check_request(rsm_lms_encode_mode_baud(out, sizeof out, adr, bauds[in[1] & 7u]), out, 0x20u,
                  adr);
    check_request(rsm_lms_encode_request_scan(out, sizeof out, adr), out, 0x30u, adr);
    check_request(rsm_lms_encode_request_status(out, sizeof out, adr), out, 0x31u, adr);
    check_request(rsm_lms_encode_request_type(out, sizeof out, adr), out, 0x3Au, adr);
    check_request(rsm_lms_encode_variant(out, sizeof out, adr, (uint16_t)(a % 200u),
                                         (uint16_t)(b % 120u)),
                  out, 0x3Bu, adr);
    check_request(rsm_lms_encode_request_config(out, sizeof out, adr), out, 0x74u, adr);
    check_request(rsm_lms_encode_reset(out, sizeof out, adr), out, 0x10u, adr);
    memset(&cfg, 0, sizeof cfg);
    cfg.block_len = (size_t)(in[6] & 0x3Fu);
    cfg.measuring_mode = in[7];
    cfg.units = in[1];
    memcpy(cfg.block, in, sizeof in);
    check_request(rsm_lms_encode_config(out, sizeof out, adr, &cfg), out, 0x77u, adr);
    /* too small a buffer never writes */
    memset(out, 0xEE, sizeof out);
    CHECK(rsm_lms_encode_request_status(out, (size_t)(in[1] % 7u), 0u) == RSM_ERR_NOMEM);
    CHECK(out[0] == 0xEEu);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    run_state_t chunked;
    run_state_t bytewise;
    rsm_lms_telegram_t t;
    uint32_t rng;
    size_t off = 0;
    size_t i;
    int rc;

    /* chunked: split points seeded by the last byte and the size */
    run_init(&chunked);
    rng = 0x9E3779B9u ^ (uint32_t)size ^ ((size > 0u) ? ((uint32_t)data[size - 1u] << 24) : 0u);
    while (off < size) {
        size_t chunk;
        rng ^= rng << 13;
        rng ^= rng >> 17;
        rng ^= rng << 5;
        chunk = (size_t)(rng % 67u) + 1u;
        if (chunk > size - off) {
            chunk = size - off;
        }
        feed(&chunked, data + off, chunk);
        off += chunk;
    }
    finish(&chunked, size);

    /* byte by byte: same events, same counters */
    run_init(&bytewise);
    for (i = 0; i < size; ++i) {
        feed(&bytewise, data + i, 1u);
    }
    finish(&bytewise, size);
    CHECK(chunked.events_hash == bytewise.events_hash);
    CHECK(memcmp(&chunked.parser.stats, &bytewise.parser.stats, sizeof chunked.parser.stats) ==
          0);

    /* the whole input as one frame */
    rc = rsm_lms_telegram_view(data, size, &t);
    if (rc == RSM_OK) {
        check_decoders(&t);
    } else {
        CHECK(rc == RSM_ERR_AGAIN || rc == RSM_ERR_PROTO || rc == RSM_ERR_CHECKSUM ||
              (rc == RSM_ERR_INVAL && data == NULL));
    }

    check_round_trip(data, size);
    check_encoders(data, size);
    return 0;
}
