/* Unit tests of the SICK LMS 2xx codec (src/drivers/lms.c): every lms_* vector of
 * the protocol reference, then fault injection on the receiver (garbage,
 * bit flips, truncation, bad LEN fields) with exact counters. The expected
 * counters of the fault-injection tests come from ref_scan() below, a
 * whole-buffer reading of the framing rules of rsm/lms.h that shares no
 * code with the incremental receiver. */
#include "unity.h"

#include <stdint.h>
#include <string.h>

#include "rsm/config.h"
#include "rsm/lms.h"
#include "rsm/status.h"

void setUp(void) {}
void tearDown(void) {}

/* ---- vectors (hex exactly as in the protocol reference) ----------------- */

static const uint8_t v_status_request[] = {0x02, 0x00, 0x01, 0x00, 0x31, 0x15, 0x12};
static const uint8_t v_request_measured_values[] = {0x02, 0x00, 0x02, 0x00,
                                                    0x30, 0x01, 0x31, 0x18};
static const uint8_t v_mode_continuous[] = {0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08};
static const uint8_t v_mode_stop[] = {0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08};
static const uint8_t v_mode_installation[] = {0x02, 0x00, 0x0A, 0x00, 0x20, 0x00, 0x53, 0x49,
                                              0x43, 0x4B, 0x5F, 0x4C, 0x4D, 0x53, 0xBE, 0xC5};
static const uint8_t v_baud_38400[] = {0x02, 0x00, 0x02, 0x00, 0x20, 0x40, 0x50, 0x08};
static const uint8_t v_baud_19200[] = {0x02, 0x00, 0x02, 0x00, 0x20, 0x41, 0x51, 0x08};
static const uint8_t v_baud_9600[] = {0x02, 0x00, 0x02, 0x00, 0x20, 0x42, 0x52, 0x08};
static const uint8_t v_baud_500000[] = {0x02, 0x00, 0x02, 0x00, 0x20, 0x48, 0x58, 0x08};
static const uint8_t v_variant_180deg_100cdeg[] = {0x02, 0x00, 0x05, 0x00, 0x3B, 0xB4,
                                                   0x00, 0x64, 0x00, 0x97, 0x49};
static const uint8_t v_variant_180deg_50cdeg[] = {0x02, 0x00, 0x05, 0x00, 0x3B, 0xB4,
                                                  0x00, 0x32, 0x00, 0x3B, 0x1F};
static const uint8_t v_variant_100deg_25cdeg[] = {0x02, 0x00, 0x05, 0x00, 0x3B, 0x64,
                                                  0x00, 0x19, 0x00, 0xE7, 0x72};
static const uint8_t v_variant_100deg_100cdeg[] = {0x02, 0x00, 0x05, 0x00, 0x3B, 0x64,
                                                   0x00, 0x64, 0x00, 0x1D, 0x0F};
static const uint8_t v_reset[] = {0x02, 0x00, 0x01, 0x00, 0x10, 0x34, 0x12};
static const uint8_t v_request_type[] = {0x02, 0x00, 0x01, 0x00, 0x3A, 0x1E, 0x12};
static const uint8_t v_read_config[] = {0x02, 0x00, 0x01, 0x00, 0x74, 0x50, 0x12};
static const uint8_t v_ack_then_mode_response[] = {0x06, 0x02, 0x80, 0x03, 0x00,
                                                   0xA0, 0x00, 0x10, 0x16, 0x0A};
static const uint8_t v_mode_response_addr81[] = {0x02, 0x81, 0x03, 0x00, 0xA0,
                                                 0x00, 0x10, 0x36, 0x1A};
static const uint8_t v_reset_reply_0x91[] = {0x06, 0x02, 0x80, 0x02, 0x00,
                                             0x91, 0x10, 0x79, 0x30};
static const uint8_t v_powerup_quick_manual[] = {
    0x02, 0x81, 0x17, 0x00, 0x90, 0x4C, 0x4D, 0x53, 0x32, 0x30, 0x30, 0x3B, 0x33, 0x30, 0x31,
    0x30, 0x36, 0x33, 0x3B, 0x56, 0x30, 0x32, 0x2E, 0x30, 0x36, 0x20, 0x13, 0x64, 0x5A};
static const uint8_t v_powerup_captured[] = {
    0x02, 0x80, 0x17, 0x00, 0x90, 0x4C, 0x4D, 0x53, 0x32, 0x30, 0x30, 0x3B, 0x33, 0x30, 0x31,
    0x30, 0x36, 0x33, 0x3B, 0x56, 0x30, 0x32, 0x2E, 0x31, 0x30, 0x20, 0x10, 0x63, 0x5E};
static const uint8_t v_b0_short_cm[] = {0x02, 0x80, 0x0E, 0x00, 0xB0, 0x05, 0x00,
                                        0xFA, 0x00, 0xFF, 0x1F, 0xB0, 0x04, 0xFE,
                                        0x1F, 0x2C, 0x21, 0x10, 0x35, 0xA7};
static const uint8_t v_b0_short_mm[] = {0x02, 0x80, 0x0A, 0x00, 0xB0, 0x03, 0x40, 0xF6,
                                        0x1F, 0x01, 0x00, 0xA0, 0x0F, 0x10, 0x79, 0x03};
static const uint8_t v_bb_variant_ok[] = {0x02, 0x80, 0x07, 0x00, 0xBB, 0x01, 0xB4,
                                          0x00, 0x32, 0x00, 0x10, 0x03, 0x9D};
/* lms_b0_captured_361_mm: a real 732-byte scan (180 deg / 0.5 deg, mm);
 * tests/data/lms_b0_captured_361_mm.txt. */
static const uint8_t v_b0_captured_361_mm[732] = {
    0x02, 0x80, 0xD6, 0x02, 0xB0, 0x69, 0x41, 0xCB, 0x08, 0xCB, 0x08, 0xC2,
    0x08, 0xC2, 0x08, 0xC3, 0x08, 0xBA, 0x08, 0xB9, 0x08, 0xB0, 0x08, 0x9E,
    0x08, 0x89, 0x08, 0x62, 0x08, 0x44, 0x08, 0x21, 0x08, 0x13, 0x08, 0xF8,
    0x07, 0xE9, 0x07, 0xE9, 0x07, 0xE2, 0x07, 0xE7, 0x07, 0xE8, 0x07, 0xE5,
    0x07, 0xF0, 0x07, 0xE8, 0x07, 0xE8, 0x07, 0xEA, 0x07, 0xE3, 0x07, 0xE3,
    0x07, 0xE5, 0x07, 0xD0, 0x07, 0xC2, 0x07, 0xB8, 0x07, 0xC3, 0x07, 0x44,
    0x07, 0x32, 0x07, 0x20, 0x07, 0x1F, 0x07, 0x17, 0x07, 0x01, 0x07, 0x2B,
    0x07, 0x55, 0x07, 0x5F, 0x07, 0x57, 0x07, 0x43, 0x07, 0x58, 0x07, 0x15,
    0x08, 0xB8, 0x08, 0xC2, 0x08, 0xAB, 0x08, 0x44, 0x08, 0xED, 0x07, 0xA7,
    0x07, 0x5E, 0x07, 0x1C, 0x07, 0xD4, 0x06, 0x86, 0x06, 0x82, 0x06, 0xCB,
    0x06, 0x11, 0x09, 0x1B, 0x09, 0x24, 0x09, 0x2D, 0x09, 0x36, 0x09, 0x36,
    0x09, 0x3F, 0x09, 0x3F, 0x09, 0xD5, 0x08, 0x34, 0x08, 0xF3, 0x07, 0x07,
    0x08, 0x05, 0x08, 0x15, 0x08, 0x1D, 0x08, 0x1A, 0x08, 0x2B, 0x08, 0x15,
    0x08, 0x16, 0x08, 0x15, 0x08, 0x09, 0x08, 0xFB, 0x07, 0xD8, 0x07, 0x02,
    0x08, 0xEC, 0x07, 0xC7, 0x07, 0x7F, 0x07, 0x90, 0x07, 0xA1, 0x12, 0x75,
    0x12, 0x37, 0x10, 0x20, 0x0F, 0xE9, 0x0E, 0xA5, 0x0E, 0x65, 0x0E, 0x30,
    0x0E, 0xFC, 0x0D, 0xCB, 0x0D, 0x9B, 0x0D, 0x72, 0x0D, 0x3E, 0x0D, 0x11,
    0x0D, 0xE0, 0x0C, 0xB3, 0x0C, 0x93, 0x0C, 0x67, 0x0C, 0x42, 0x0C, 0x25,
    0x0C, 0x3D, 0x0C, 0x3E, 0x0C, 0x06, 0x0C, 0xEC, 0x0B, 0xD9, 0x0B, 0xF6,
    0x0B, 0xF2, 0x0B, 0x0A, 0x0C, 0x17, 0x0C, 0x32, 0x0C, 0x43, 0x0C, 0x5E,
    0x0C, 0x79, 0x0C, 0x6D, 0x0C, 0x51, 0x0C, 0x3C, 0x0C, 0x30, 0x0C, 0x31,
    0x0C, 0x3F, 0x0C, 0x75, 0x0C, 0xCC, 0x0C, 0x0F, 0x0D, 0x1C, 0x0D, 0x89,
    0x0D, 0xD6, 0x0D, 0x0A, 0x0C, 0xC6, 0x0B, 0xC9, 0x0D, 0xD3, 0x0D, 0xCF,
    0x0D, 0xBE, 0x0D, 0xA3, 0x0D, 0x93, 0x0D, 0x87, 0x0D, 0x10, 0x0D, 0x6E,
    0x0D, 0x92, 0x0D, 0xA5, 0x0D, 0xAC, 0x0D, 0xAC, 0x0D, 0xA9, 0x0D, 0x73,
    0x0D, 0x6C, 0x0D, 0x60, 0x0D, 0x63, 0x0D, 0x5C, 0x0D, 0x4D, 0x0D, 0x45,
    0x0D, 0x36, 0x0D, 0x1C, 0x0D, 0x13, 0x0D, 0xD6, 0x0C, 0xD5, 0x0C, 0x18,
    0x0D, 0x1C, 0x0D, 0x16, 0x0D, 0x1C, 0x0D, 0xF1, 0x0C, 0xE9, 0x0C, 0xE2,
    0x0C, 0xDC, 0x0C, 0xE5, 0x0C, 0xD2, 0x0C, 0xCD, 0x0C, 0xE6, 0x0C, 0xD2,
    0x0C, 0xD8, 0x0C, 0xD0, 0x0C, 0xDB, 0x0C, 0xD7, 0x0C, 0xE1, 0x0C, 0xD5,
    0x0C, 0xD7, 0x0C, 0xDC, 0x0C, 0xDB, 0x0C, 0xD9, 0x0C, 0xE4, 0x0C, 0xE4,
    0x0C, 0xE6, 0x0C, 0xE2, 0x0C, 0xE8, 0x0C, 0xE8, 0x0C, 0xEC, 0x0C, 0xFB,
    0x0C, 0xED, 0x0C, 0xF1, 0x0C, 0xF6, 0x0C, 0xFD, 0x0C, 0x03, 0x0D, 0x07,
    0x0D, 0x0A, 0x0D, 0x1D, 0x0D, 0x1E, 0x0D, 0x27, 0x0D, 0x36, 0x0D, 0x44,
    0x0D, 0x3C, 0x0D, 0x37, 0x0D, 0x41, 0x0D, 0x4A, 0x0D, 0x54, 0x0D, 0x62,
    0x0D, 0x5B, 0x0D, 0x62, 0x0D, 0x77, 0x0D, 0x76, 0x0A, 0x71, 0x0A, 0x83,
    0x0A, 0x82, 0x0A, 0x81, 0x0A, 0x80, 0x0A, 0x81, 0x0A, 0x82, 0x0A, 0x72,
    0x0A, 0x92, 0x0A, 0x98, 0x0D, 0xB1, 0x0C, 0xBC, 0x0C, 0x26, 0x0C, 0x89,
    0x0B, 0x20, 0x0B, 0x3D, 0x0B, 0xA8, 0x0B, 0xAF, 0x0B, 0xB4, 0x0B, 0xC0,
    0x0B, 0xC6, 0x0B, 0xD0, 0x0B, 0xDA, 0x0B, 0xE2, 0x0B, 0xE8, 0x0B, 0xED,
    0x0B, 0xF8, 0x0B, 0x0A, 0x0C, 0x03, 0x0C, 0x0F, 0x0C, 0x35, 0x0C, 0x41,
    0x0C, 0x39, 0x0C, 0x28, 0x0C, 0xF2, 0x0B, 0xB7, 0x0B, 0x5A, 0x0E, 0xCF,
    0x0D, 0x92, 0x0B, 0xB9, 0x08, 0x45, 0x08, 0x43, 0x08, 0xAB, 0x08, 0x26,
    0x0B, 0x4F, 0x0B, 0x83, 0x0B, 0x30, 0x0C, 0x7F, 0x0D, 0x37, 0x11, 0x68,
    0x0F, 0x70, 0x0B, 0x41, 0x0B, 0x7A, 0x22, 0x65, 0x22, 0x63, 0x22, 0x58,
    0x22, 0x49, 0x22, 0x43, 0x22, 0x3E, 0x22, 0x33, 0x22, 0x2C, 0x22, 0x25,
    0x22, 0x1D, 0x22, 0x15, 0x22, 0x15, 0x22, 0x18, 0x22, 0x07, 0x22, 0x05,
    0x22, 0x00, 0x22, 0xFF, 0x21, 0xFD, 0x21, 0xF8, 0x21, 0xF1, 0x21, 0xE3,
    0x21, 0xE0, 0x21, 0xD9, 0x21, 0xD2, 0x21, 0xD7, 0x21, 0xCB, 0x21, 0xD0,
    0x21, 0xDA, 0x21, 0xCF, 0x21, 0xCF, 0x21, 0xD0, 0x21, 0xCB, 0x21, 0xCA,
    0x21, 0xC2, 0x21, 0xC2, 0x21, 0xB9, 0x21, 0xB9, 0x21, 0xB4, 0x21, 0xB0,
    0x21, 0xAF, 0x21, 0x9E, 0x21, 0x97, 0x21, 0x98, 0x21, 0xA4, 0x21, 0xA1,
    0x21, 0x9C, 0x21, 0xC2, 0x21, 0xC3, 0x21, 0xBF, 0x21, 0xBF, 0x21, 0xC1,
    0x21, 0xB4, 0x21, 0xB8, 0x21, 0xBF, 0x21, 0xC3, 0x21, 0xBD, 0x21, 0xC8,
    0x21, 0xCA, 0x21, 0xC0, 0x21, 0xD0, 0x21, 0xD1, 0x21, 0xC5, 0x21, 0xCA,
    0x21, 0xD1, 0x21, 0xF0, 0x21, 0x32, 0x22, 0x2F, 0x22, 0x2B, 0x22, 0x2F,
    0x22, 0x2A, 0x22, 0x2F, 0x22, 0x2F, 0x22, 0x4F, 0x22, 0x5D, 0x22, 0x5E,
    0x22, 0x70, 0x22, 0x86, 0x22, 0xB5, 0x22, 0xCC, 0x22, 0x1C, 0x23, 0x3C,
    0x05, 0x48, 0x05, 0xD4, 0x21, 0x2F, 0x23, 0xFE, 0x22, 0xC0, 0x22, 0x2B,
    0x23, 0x3C, 0x05, 0x3A, 0x05, 0x33, 0x05, 0x33, 0x05, 0x28, 0x05, 0x1E,
    0x05, 0x1B, 0x23, 0xB1, 0x22, 0xD7, 0x22, 0x18, 0x05, 0x10, 0x64, 0x47,
};

#define ARRAY_LEN(a) (sizeof(a) / sizeof((a)[0]))

/* ---- helpers ------------------------------------------------------------ */

static void assert_encoded(const uint8_t *expected, size_t expected_len, int n,
                           const uint8_t *buf)
{
    TEST_ASSERT_EQUAL_INT((int)expected_len, n);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, buf, expected_len);
}

/* A verified view of a complete frame held in a test array. */
static rsm_lms_telegram_t view_of(const uint8_t *frame, size_t len)
{
    rsm_lms_telegram_t t;
    memset(&t, 0, sizeof t);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_telegram_view(frame, len, &t));
    return t;
}

static uint32_t fnv1a(const uint8_t *b, size_t n)
{
    uint32_t h = 2166136261u;
    size_t i;
    for (i = 0; i < n; ++i) {
        h ^= b[i];
        h *= 16777619u;
    }
    return h;
}

/* Deterministic PRNG for garbage and chunk sizes (xorshift32). */
static uint32_t prng_next(uint32_t *s)
{
    uint32_t x = *s;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *s = x;
    return x;
}

/* What a run published, in order, and the counters at its end. */
#define LOG_MAX 1024u
typedef struct ev_rec {
    int type;
    size_t len;
    uint32_t hash;
} ev_rec_t;

typedef struct run_log {
    ev_rec_t ev[LOG_MAX];
    size_t n;
    rsm_lms_parser_stats_t st;
} run_log_t;

static void log_clear(run_log_t *log)
{
    memset(log, 0, sizeof *log);
}

static void log_add(run_log_t *log, int type, const uint8_t *frame, size_t len)
{
    TEST_ASSERT_TRUE(log->n < LOG_MAX);
    log->ev[log->n].type = type;
    log->ev[log->n].len = len;
    log->ev[log->n].hash = (frame != NULL) ? fnv1a(frame, len) : 0u;
    log->n++;
}

/* Records a parser event after checking that a published telegram is
 * consistent: LEN + 6 bytes, STX, reply address, CRC verified. */
static void log_event(run_log_t *log, const rsm_lms_event_t *ev)
{
    if (ev->type == RSM_LMS_EVENT_TELEGRAM) {
        rsm_lms_telegram_t again;
        const rsm_lms_telegram_t *t = &ev->telegram;
        TEST_ASSERT_EQUAL_size_t((size_t)t->len + 6u, t->frame_len);
        TEST_ASSERT_EQUAL_size_t((size_t)t->len - 1u, t->data_len);
        TEST_ASSERT_EQUAL_HEX8(0x02, t->frame[0]);
        TEST_ASSERT_TRUE((t->adr & 0x80u) != 0u);
        TEST_ASSERT_TRUE(t->data == t->frame + 5);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_telegram_view(t->frame, t->frame_len, &again));
        log_add(log, (int)ev->type, t->frame, t->frame_len);
    } else {
        TEST_ASSERT_TRUE(ev->type == RSM_LMS_EVENT_ACK || ev->type == RSM_LMS_EVENT_NAK);
        TEST_ASSERT_NULL(ev->telegram.frame);
        log_add(log, (int)ev->type, NULL, 0u);
    }
}

/* Feeds one chunk, handling every event, until the chunk is used up. */
static void feed_chunk(rsm_lms_parser_t *p, const uint8_t *data, size_t len, run_log_t *log)
{
    size_t done = 0;
    for (;;) {
        rsm_lms_event_t ev;
        size_t used = (size_t)-1;
        const int r = rsm_lms_parser_feed(p, data + done, len - done, &used, &ev);
        TEST_ASSERT_TRUE(r == 0 || r == 1);
        TEST_ASSERT_TRUE(used <= len - done);
        done += used;
        if (r == 0) {
            TEST_ASSERT_EQUAL_size_t(len, done);
            TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_NONE, ev.type);
            return;
        }
        log_event(log, &ev);
    }
}

/* Handles the events of a timeout until the receiver is empty. */
static void drain_timeout(rsm_lms_parser_t *p, run_log_t *log)
{
    rsm_lms_event_t ev;
    int r;
    while ((r = rsm_lms_parser_timeout(p, &ev)) == 1) {
        log_event(log, &ev);
    }
    TEST_ASSERT_EQUAL_INT(0, r);
    TEST_ASSERT_EQUAL_size_t(0u, p->wr - p->head);
}

enum { CHUNK_WHOLE = 0, CHUNK_BYTES = 1, CHUNK_RANDOM = 2 };

/* Feeds s[0..n) in chunks of the given kind. */
static void feed_stream(rsm_lms_parser_t *p, const uint8_t *s, size_t n, int chunking,
                        uint32_t seed, run_log_t *log)
{
    size_t off = 0;
    uint32_t rng = seed | 1u;
    while (off < n) {
        size_t chunk = n - off;
        if (chunking == CHUNK_BYTES) {
            chunk = 1u;
        } else if (chunking == CHUNK_RANDOM) {
            chunk = (size_t)(prng_next(&rng) % 97u) + 1u;
        }
        if (chunk > n - off) {
            chunk = n - off;
        }
        feed_chunk(p, s + off, chunk, log);
        off += chunk;
    }
}

/* Fresh receiver over s[0..n), then (optionally) a timeout drain. */
static void run_parser(const uint8_t *s, size_t n, int chunking, int final_timeout,
                       run_log_t *log)
{
    rsm_lms_parser_t p;
    log_clear(log);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_parser_init(&p));
    feed_stream(&p, s, n, chunking, 0x2545F491u, log);
    if (final_timeout) {
        drain_timeout(&p, log);
    }
    log->st = p.stats;
}

/* Reference reading of the framing rules over a whole buffer: hunt for ACK,
 * NAK or STX + reply ADR; reject LEN 0 or > RSM_LMS_MAX_LEN; publish on a
 * good CRC and continue after the telegram; on any rejection drop only the
 * STX and continue with the next byte. A candidate cut by the end of the
 * buffer is abandoned the same way if final_timeout is set, otherwise the
 * scan stops there (the receiver keeps those bytes). */
static void ref_scan(const uint8_t *s, size_t n, int final_timeout, run_log_t *log)
{
    size_t i = 0;
    while (i < n) {
        const uint8_t b = s[i];
        int cut = 0;
        if (b == 0x06u) {
            log->st.acks++;
            log_add(log, RSM_LMS_EVENT_ACK, NULL, 0u);
            i++;
            continue;
        }
        if (b == 0x15u) {
            log->st.naks++;
            log_add(log, RSM_LMS_EVENT_NAK, NULL, 0u);
            i++;
            continue;
        }
        if (b != 0x02u) {
            log->st.bytes_skipped++;
            i++;
            continue;
        }
        if (n - i < 2u) {
            cut = 1;
        } else if ((s[i + 1] & 0x80u) == 0u) {
            log->st.bytes_skipped++;
            i++;
            continue;
        } else if (n - i < 4u) {
            cut = 1;
        } else {
            const size_t field = (size_t)s[i + 2] | ((size_t)s[i + 3] << 8);
            if (field == 0u || field > (size_t)RSM_LMS_MAX_LEN) {
                log->st.bad_length++;
                log->st.bytes_skipped++;
                i++;
                continue;
            }
            if (n - i < field + 6u) {
                cut = 1;
            } else {
                const size_t total = field + 6u;
                const uint16_t sent = (uint16_t)(s[i + total - 2u] | (s[i + total - 1u] << 8));
                if (rsm_lms_crc(s + i, total - 2u) == sent) {
                    log->st.telegrams_ok++;
                    log_add(log, RSM_LMS_EVENT_TELEGRAM, s + i, total);
                    i += total;
                } else {
                    log->st.crc_errors++;
                    log->st.bytes_skipped++;
                    i++;
                }
                continue;
            }
        }
        if (cut) {
            if (!final_timeout) {
                return;
            }
            log->st.truncated++;
            log->st.bytes_skipped++;
            i++;
        }
    }
}

static void assert_stats_equal(const rsm_lms_parser_stats_t *want,
                               const rsm_lms_parser_stats_t *got)
{
    TEST_ASSERT_EQUAL_UINT32(want->bytes_skipped, got->bytes_skipped);
    TEST_ASSERT_EQUAL_UINT32(want->crc_errors, got->crc_errors);
    TEST_ASSERT_EQUAL_UINT32(want->bad_length, got->bad_length);
    TEST_ASSERT_EQUAL_UINT32(want->truncated, got->truncated);
    TEST_ASSERT_EQUAL_UINT32(want->telegrams_ok, got->telegrams_ok);
    TEST_ASSERT_EQUAL_UINT32(want->acks, got->acks);
    TEST_ASSERT_EQUAL_UINT32(want->naks, got->naks);
}

static void assert_logs_equal(const run_log_t *want, const run_log_t *got)
{
    size_t i;
    assert_stats_equal(&want->st, &got->st);
    TEST_ASSERT_EQUAL_size_t(want->n, got->n);
    for (i = 0; i < want->n; ++i) {
        TEST_ASSERT_EQUAL_INT(want->ev[i].type, got->ev[i].type);
        TEST_ASSERT_EQUAL_size_t(want->ev[i].len, got->ev[i].len);
        TEST_ASSERT_EQUAL_HEX32(want->ev[i].hash, got->ev[i].hash);
    }
}

/* Every fed byte is skipped, an ACK/NAK, or inside a published telegram. */
static void assert_conserved(const run_log_t *log, size_t fed)
{
    size_t i;
    size_t in_telegrams = 0;
    for (i = 0; i < log->n; ++i) {
        in_telegrams += log->ev[i].len;
    }
    TEST_ASSERT_EQUAL_size_t(fed, (size_t)log->st.bytes_skipped + log->st.acks +
                                      log->st.naks + in_telegrams);
}

/* Builds a 0xB0 reply (ADR 0x80) with the given count word and n words. */
static int build_b0(uint8_t *out, size_t cap, uint16_t cw, const uint16_t *words, size_t n,
                    uint8_t status)
{
    uint8_t data[2u + 2u * 406u + 1u];
    size_t i;
    TEST_ASSERT_TRUE(n <= 406u);
    data[0] = (uint8_t)(cw & 0xFFu);
    data[1] = (uint8_t)(cw >> 8);
    for (i = 0; i < n; ++i) {
        data[2u + 2u * i] = (uint8_t)(words[i] & 0xFFu);
        data[3u + 2u * i] = (uint8_t)(words[i] >> 8);
    }
    data[2u + 2u * n] = status;
    return rsm_lms_encode(out, cap, 0x80u, 0xB0u, data, 3u + 2u * n);
}

/* ---- CRC ---------------------------------------------------------------- */

void test_rsm_lms_crc_should_match_the_worked_example(void)
{
    /* installation-mode request: CRC 0xC5BE over the first 14 bytes */
    TEST_ASSERT_EQUAL_HEX16(0xC5BE, rsm_lms_crc(v_mode_installation, 14));
    /* short check: status request */
    TEST_ASSERT_EQUAL_HEX16(0x1215, rsm_lms_crc(v_status_request, 5));
    /* partial prefix from the step table: after byte 7 ('I') crc = 0xF2AF */
    TEST_ASSERT_EQUAL_HEX16(0xF2AF, rsm_lms_crc(v_mode_installation, 8));
    TEST_ASSERT_EQUAL_HEX16(0x2C18, rsm_lms_crc(v_mode_installation, 9));
    TEST_ASSERT_EQUAL_HEX16(0x0000, rsm_lms_crc(v_mode_installation, 0));
    TEST_ASSERT_EQUAL_HEX16(0x0000, rsm_lms_crc(NULL, 0));
}

/* ---- request vectors: encoders reproduce them byte for byte -------------- */

void test_rsm_lms_encode_request_status_should_reproduce_lms_status_request(void)
{
    uint8_t buf[32];
    assert_encoded(v_status_request, sizeof v_status_request,
                   rsm_lms_encode_request_status(buf, sizeof buf, 0x00), buf);
    assert_encoded(v_status_request, sizeof v_status_request,
                   rsm_lms_encode(buf, sizeof buf, 0x00, 0x31, NULL, 0), buf);
}

void test_rsm_lms_encode_request_scan_should_reproduce_lms_request_measured_values(void)
{
    uint8_t buf[32];
    assert_encoded(v_request_measured_values, sizeof v_request_measured_values,
                   rsm_lms_encode_request_scan(buf, sizeof buf, 0x00), buf);
}

void test_rsm_lms_encode_mode_should_reproduce_lms_mode_continuous(void)
{
    uint8_t buf[32];
    assert_encoded(v_mode_continuous, sizeof v_mode_continuous,
                   rsm_lms_encode_mode(buf, sizeof buf, 0x00, RSM_LMS_MODE_CONTINUOUS), buf);
}

void test_rsm_lms_encode_mode_should_reproduce_lms_mode_stop(void)
{
    uint8_t buf[32];
    assert_encoded(v_mode_stop, sizeof v_mode_stop,
                   rsm_lms_encode_mode(buf, sizeof buf, 0x00, RSM_LMS_MODE_ON_REQUEST), buf);
}

void test_rsm_lms_encode_mode_installation_should_reproduce_lms_mode_installation(void)
{
    static const uint8_t password[8] = {'S', 'I', 'C', 'K', '_', 'L', 'M', 'S'};
    uint8_t buf[32];
    assert_encoded(v_mode_installation, sizeof v_mode_installation,
                   rsm_lms_encode_mode_installation(buf, sizeof buf, 0x00, NULL), buf);
    memset(buf, 0, sizeof buf);
    assert_encoded(v_mode_installation, sizeof v_mode_installation,
                   rsm_lms_encode_mode_installation(buf, sizeof buf, 0x00, password), buf);
}

void test_rsm_lms_encode_mode_baud_should_reproduce_lms_baud_38400(void)
{
    uint8_t buf[32];
    assert_encoded(v_baud_38400, sizeof v_baud_38400,
                   rsm_lms_encode_mode_baud(buf, sizeof buf, 0x00, 38400u), buf);
    assert_encoded(v_baud_38400, sizeof v_baud_38400,
                   rsm_lms_encode_mode(buf, sizeof buf, 0x00, RSM_LMS_MODE_BAUD_38400), buf);
}

void test_rsm_lms_encode_mode_baud_should_reproduce_lms_baud_19200(void)
{
    uint8_t buf[32];
    assert_encoded(v_baud_19200, sizeof v_baud_19200,
                   rsm_lms_encode_mode_baud(buf, sizeof buf, 0x00, 19200u), buf);
    assert_encoded(v_baud_19200, sizeof v_baud_19200,
                   rsm_lms_encode_mode(buf, sizeof buf, 0x00, RSM_LMS_MODE_BAUD_19200), buf);
}

void test_rsm_lms_encode_mode_baud_should_reproduce_lms_baud_9600(void)
{
    uint8_t buf[32];
    assert_encoded(v_baud_9600, sizeof v_baud_9600,
                   rsm_lms_encode_mode_baud(buf, sizeof buf, 0x00, 9600u), buf);
    assert_encoded(v_baud_9600, sizeof v_baud_9600,
                   rsm_lms_encode_mode(buf, sizeof buf, 0x00, RSM_LMS_MODE_BAUD_9600), buf);
}

void test_rsm_lms_encode_mode_baud_should_reproduce_lms_baud_500000(void)
{
    uint8_t buf[32];
    assert_encoded(v_baud_500000, sizeof v_baud_500000,
                   rsm_lms_encode_mode_baud(buf, sizeof buf, 0x00, 500000u), buf);
    assert_encoded(v_baud_500000, sizeof v_baud_500000,
                   rsm_lms_encode_mode(buf, sizeof buf, 0x00, RSM_LMS_MODE_BAUD_500000), buf);
}

void test_rsm_lms_encode_variant_should_reproduce_lms_variant_180deg_100cdeg(void)
{
    uint8_t buf[32];
    assert_encoded(v_variant_180deg_100cdeg, sizeof v_variant_180deg_100cdeg,
                   rsm_lms_encode_variant(buf, sizeof buf, 0x00, 180u, 100u), buf);
}

void test_rsm_lms_encode_variant_should_reproduce_lms_variant_180deg_50cdeg(void)
{
    uint8_t buf[32];
    assert_encoded(v_variant_180deg_50cdeg, sizeof v_variant_180deg_50cdeg,
                   rsm_lms_encode_variant(buf, sizeof buf, 0x00, 180u, 50u), buf);
}

void test_rsm_lms_encode_variant_should_reproduce_lms_variant_100deg_25cdeg(void)
{
    uint8_t buf[32];
    assert_encoded(v_variant_100deg_25cdeg, sizeof v_variant_100deg_25cdeg,
                   rsm_lms_encode_variant(buf, sizeof buf, 0x00, 100u, 25u), buf);
}

void test_rsm_lms_encode_variant_should_reproduce_lms_variant_100deg_100cdeg(void)
{
    uint8_t buf[32];
    assert_encoded(v_variant_100deg_100cdeg, sizeof v_variant_100deg_100cdeg,
                   rsm_lms_encode_variant(buf, sizeof buf, 0x00, 100u, 100u), buf);
}

void test_rsm_lms_encode_reset_should_reproduce_lms_reset(void)
{
    uint8_t buf[32];
    assert_encoded(v_reset, sizeof v_reset, rsm_lms_encode_reset(buf, sizeof buf, 0x00), buf);
}

void test_rsm_lms_encode_request_type_should_reproduce_lms_request_type(void)
{
    uint8_t buf[32];
    assert_encoded(v_request_type, sizeof v_request_type,
                   rsm_lms_encode_request_type(buf, sizeof buf, 0x00), buf);
}

void test_rsm_lms_encode_request_config_should_reproduce_lms_read_config(void)
{
    uint8_t buf[32];
    assert_encoded(v_read_config, sizeof v_read_config,
                   rsm_lms_encode_request_config(buf, sizeof buf, 0x00), buf);
}

/* ---- response vectors: decoders recover every listed field -------------- */

void test_rsm_lms_parser_feed_should_decode_lms_ack_then_mode_response(void)
{
    rsm_lms_parser_t p;
    rsm_lms_event_t ev;
    rsm_lms_mode_reply_t reply;
    size_t used = 0;
    const uint8_t *s = v_ack_then_mode_response;
    const size_t n = sizeof v_ack_then_mode_response;

    TEST_ASSERT_EQUAL_HEX16(0x0A16, rsm_lms_crc(s + 1, n - 3));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_parser_init(&p));
    /* ACK and reply in one chunk: the ACK comes first, alone */
    TEST_ASSERT_EQUAL_INT(1, rsm_lms_parser_feed(&p, s, n, &used, &ev));
    TEST_ASSERT_EQUAL_size_t(1, used);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_ACK, ev.type);
    TEST_ASSERT_EQUAL_INT(1, rsm_lms_parser_feed(&p, s + 1, n - 1, &used, &ev));
    TEST_ASSERT_EQUAL_size_t(n - 1, used);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_TELEGRAM, ev.type);
    TEST_ASSERT_EQUAL_HEX8(0x80, ev.telegram.adr);
    TEST_ASSERT_EQUAL_UINT16(3, ev.telegram.len);
    TEST_ASSERT_EQUAL_HEX8(0xA0, ev.telegram.cmd);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_mode_reply(&ev.telegram, &reply));
    TEST_ASSERT_EQUAL_HEX8(RSM_LMS_MODE_RESULT_OK, reply.result);
    TEST_ASSERT_EQUAL_HEX8(0x10, reply.status);
    TEST_ASSERT_EQUAL_INT(0, rsm_lms_parser_feed(&p, s + n, 0, &used, &ev));
    TEST_ASSERT_EQUAL_size_t(0, used);
    TEST_ASSERT_EQUAL_UINT32(1, p.stats.acks);
    TEST_ASSERT_EQUAL_UINT32(1, p.stats.telegrams_ok);
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.bytes_skipped);
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.naks);
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.crc_errors);
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.bad_length);
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.truncated);
}

void test_rsm_lms_decode_mode_reply_should_decode_lms_mode_response_addr81(void)
{
    rsm_lms_mode_reply_t reply;
    const rsm_lms_telegram_t t = view_of(v_mode_response_addr81, sizeof v_mode_response_addr81);
    TEST_ASSERT_EQUAL_HEX16(0x1A36, rsm_lms_crc(v_mode_response_addr81, 7));
    TEST_ASSERT_EQUAL_HEX8(0x81, t.adr);
    TEST_ASSERT_EQUAL_HEX8(0xA0, t.cmd);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_mode_reply(&t, &reply));
    TEST_ASSERT_EQUAL_HEX8(0x00, reply.result);
    TEST_ASSERT_EQUAL_HEX8(0x10, reply.status);
}

void test_rsm_lms_decode_reset_reply_should_decode_lms_reset_reply_0x91(void)
{
    run_log_t log;
    uint8_t status = 0;
    rsm_lms_telegram_t t;
    run_parser(v_reset_reply_0x91, sizeof v_reset_reply_0x91, CHUNK_WHOLE, 1, &log);
    TEST_ASSERT_EQUAL_size_t(2, log.n);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_ACK, log.ev[0].type);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_TELEGRAM, log.ev[1].type);
    TEST_ASSERT_EQUAL_UINT32(1, log.st.acks);
    TEST_ASSERT_EQUAL_UINT32(1, log.st.telegrams_ok);
    TEST_ASSERT_EQUAL_HEX16(0x3079, rsm_lms_crc(v_reset_reply_0x91 + 1, 6));
    t = view_of(v_reset_reply_0x91 + 1, sizeof v_reset_reply_0x91 - 1);
    TEST_ASSERT_EQUAL_HEX8(0x80, t.adr);
    TEST_ASSERT_EQUAL_UINT16(2, t.len);
    TEST_ASSERT_EQUAL_HEX8(0x91, t.cmd);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_reset_reply(&t, &status));
    TEST_ASSERT_EQUAL_HEX8(0x10, status);
}

void test_rsm_lms_decode_power_on_should_decode_lms_powerup_quick_manual(void)
{
    rsm_lms_text_reply_t r;
    rsm_lms_status_byte_t sb;
    const rsm_lms_telegram_t t = view_of(v_powerup_quick_manual, sizeof v_powerup_quick_manual);
    TEST_ASSERT_EQUAL_HEX16(0x5A64, rsm_lms_crc(v_powerup_quick_manual, 27));
    TEST_ASSERT_EQUAL_HEX8(0x81, t.adr);
    TEST_ASSERT_EQUAL_UINT16(23, t.len);
    TEST_ASSERT_EQUAL_HEX8(0x90, t.cmd);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_power_on(&t, &r));
    TEST_ASSERT_EQUAL_STRING("LMS200;301063;V02.06 ", r.text);
    TEST_ASSERT_EQUAL_size_t(21, r.text_len);
    TEST_ASSERT_EQUAL_HEX8(0x13, r.status);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_status_byte(r.status, &sb));
    TEST_ASSERT_EQUAL_UINT8(3, sb.severity);
    TEST_ASSERT_EQUAL_UINT8(0, sb.implausible);
    TEST_ASSERT_EQUAL_UINT8(0, sb.pollution);
}

void test_rsm_lms_decode_power_on_should_decode_lms_powerup_captured(void)
{
    rsm_lms_text_reply_t r;
    const rsm_lms_telegram_t t = view_of(v_powerup_captured, sizeof v_powerup_captured);
    TEST_ASSERT_EQUAL_HEX16(0x5E63, rsm_lms_crc(v_powerup_captured, 27));
    TEST_ASSERT_EQUAL_HEX8(0x80, t.adr);
    TEST_ASSERT_EQUAL_UINT16(23, t.len);
    TEST_ASSERT_EQUAL_HEX8(0x90, t.cmd);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_power_on(&t, &r));
    TEST_ASSERT_EQUAL_STRING("LMS200;301063;V02.10 ", r.text);
    TEST_ASSERT_EQUAL_size_t(21, r.text_len);
    TEST_ASSERT_EQUAL_HEX8(0x10, r.status);
    /* the same text layout is what 0xBA carries, but the CMD must match */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_type_reply(&t, &r));
}

void test_rsm_lms_decode_b0_should_decode_lms_b0_short_cm(void)
{
    static const uint16_t raw[5] = {0x00FA, 0x1FFF, 0x04B0, 0x1FFE, 0x212C};
    static const uint16_t dist13[5] = {250, 8191, 1200, 8190, 300};
    static const uint8_t flags[5] = {0, 0, 0, 0, 1};
    static const uint8_t code[5] = {RSM_LMS_READING_OK, RSM_LMS_READING_NO_ECHO,
                                    RSM_LMS_READING_OK, RSM_LMS_READING_DAZZLED,
                                    RSM_LMS_READING_OK};
    rsm_lms_scan_t scan;
    size_t i;
    const rsm_lms_telegram_t t = view_of(v_b0_short_cm, sizeof v_b0_short_cm);
    TEST_ASSERT_EQUAL_HEX16(0xA735, rsm_lms_crc(v_b0_short_cm, 18));
    TEST_ASSERT_EQUAL_HEX8(0xB0, t.cmd);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, NULL, &scan));
    TEST_ASSERT_EQUAL_HEX16(0x0005, scan.count_word);
    TEST_ASSERT_EQUAL_size_t(5, scan.count);
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_UNITS_CM, scan.units);
    TEST_ASSERT_EQUAL_HEX16(0x1FFF, scan.distance_mask);
    TEST_ASSERT_EQUAL_HEX8(0x10, scan.status);
    TEST_ASSERT_EQUAL_UINT8(0, scan.partial);
    TEST_ASSERT_EQUAL_UINT8(0, scan.index_len);
    for (i = 0; i < 5; ++i) {
        TEST_ASSERT_EQUAL_HEX16(raw[i], scan.reading[i].raw);
        TEST_ASSERT_EQUAL_UINT16(dist13[i], scan.reading[i].raw & scan.distance_mask);
        TEST_ASSERT_EQUAL_UINT8(flags[i], scan.reading[i].flags);
        TEST_ASSERT_EQUAL_UINT8(code[i], scan.reading[i].code);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.50f, scan.reading[0].range_m);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, scan.reading[1].range_m);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 12.00f, scan.reading[2].range_m);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, scan.reading[3].range_m);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 3.00f, scan.reading[4].range_m);
}

void test_rsm_lms_decode_b0_should_decode_lms_b0_short_mm(void)
{
    static const uint16_t mm[3] = {8182, 1, 4000};
    rsm_lms_scan_t scan;
    rsm_lms_b0_format_t fmt;
    size_t i;
    const rsm_lms_telegram_t t = view_of(v_b0_short_mm, sizeof v_b0_short_mm);
    TEST_ASSERT_EQUAL_HEX16(0x0379, rsm_lms_crc(v_b0_short_mm, 14));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_b0_format_default(&fmt));
    fmt.units = RSM_LMS_UNITS_MM; /* an explicit expectation that holds */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, &fmt, &scan));
    TEST_ASSERT_EQUAL_HEX16(0x4003, scan.count_word);
    TEST_ASSERT_EQUAL_size_t(3, scan.count);
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_UNITS_MM, scan.units);
    TEST_ASSERT_EQUAL_HEX8(0x10, scan.status);
    for (i = 0; i < 3; ++i) {
        TEST_ASSERT_EQUAL_UINT16(mm[i], scan.reading[i].raw);
        TEST_ASSERT_EQUAL_UINT8(RSM_LMS_READING_OK, scan.reading[i].code);
        TEST_ASSERT_EQUAL_UINT8(0, scan.reading[i].flags);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 8.182f, scan.reading[0].range_m);
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.001f, scan.reading[1].range_m);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 4.000f, scan.reading[2].range_m);
}

void test_rsm_lms_decode_variant_reply_should_decode_lms_bb_variant_ok(void)
{
    rsm_lms_variant_reply_t r;
    const rsm_lms_telegram_t t = view_of(v_bb_variant_ok, sizeof v_bb_variant_ok);
    TEST_ASSERT_EQUAL_HEX16(0x9D03, rsm_lms_crc(v_bb_variant_ok, 11));
    TEST_ASSERT_EQUAL_HEX8(0xBB, t.cmd);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_variant_reply(&t, &r));
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_RESULT_ACCEPTED, r.result);
    TEST_ASSERT_EQUAL_UINT16(180, r.angle_deg);
    TEST_ASSERT_EQUAL_UINT16(50, r.resolution_cdeg);
    TEST_ASSERT_EQUAL_HEX8(0x10, r.status);
}

void test_rsm_lms_decode_b0_should_decode_lms_b0_captured_361_mm(void)
{
    rsm_lms_scan_t scan;
    rsm_lms_scan_t before;
    const rsm_lms_telegram_t t = view_of(v_b0_captured_361_mm, sizeof v_b0_captured_361_mm);
    TEST_ASSERT_EQUAL_HEX16(0x4764, rsm_lms_crc(v_b0_captured_361_mm, 730));
    TEST_ASSERT_EQUAL_HEX8(0x80, t.adr);
    TEST_ASSERT_EQUAL_UINT16(726, t.len);
    TEST_ASSERT_EQUAL_HEX8(0xB0, t.cmd);
    memset(&scan, 0xA5, sizeof scan);
    memcpy(&before, &scan, sizeof scan);
#if RSM_MAX_BEAMS >= 361
    {
        static const uint16_t first5[5] = {2251, 2251, 2242, 2242, 2243};
        size_t i;
        size_t flagged = 0;
        size_t first_flagged = 0;
        float angle = -1.0f;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, NULL, &scan));
        TEST_ASSERT_EQUAL_HEX16(0x4169, scan.count_word);
        TEST_ASSERT_EQUAL_size_t(361, scan.count);
        TEST_ASSERT_EQUAL_UINT8(RSM_LMS_UNITS_MM, scan.units);
        TEST_ASSERT_EQUAL_HEX8(0x10, scan.status);
        for (i = 0; i < 5; ++i) {
            TEST_ASSERT_EQUAL_UINT16(first5[i], scan.reading[i].raw);
        }
        TEST_ASSERT_EQUAL_UINT16(3289, scan.reading[180].raw);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, 3.289f, scan.reading[180].range_m);
        for (i = 0; i < 361; ++i) {
            TEST_ASSERT_EQUAL_UINT8(RSM_LMS_READING_OK, scan.reading[i].code);
            if (scan.reading[i].flags != 0u) {
                if (flagged == 0u) {
                    first_flagged = i;
                }
                flagged++;
            }
        }
        TEST_ASSERT_EQUAL_size_t(89, flagged);
        TEST_ASSERT_EQUAL_size_t(263, first_flagged);
        TEST_ASSERT_EQUAL_HEX16(0x227A, scan.reading[263].raw);
        /* 13-bit measuring mode: bit 13 is the field-A flag, 634 mm */
        TEST_ASSERT_EQUAL_UINT8(1, scan.reading[263].flags);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.634f, scan.reading[263].range_m);
        /* 180 deg at 0.5 deg: reading 180 looks straight ahead */
        TEST_ASSERT_EQUAL_UINT16(0, scan.start_cdeg);
        TEST_ASSERT_EQUAL_UINT16(50, scan.step_cdeg);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_scan_angle(&scan, 180, &angle));
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.5707963f, angle);
    }
#else
    /* small config: 361 readings do not fit; rejected cleanly, untouched */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_lms_decode_b0(&t, NULL, &scan));
    TEST_ASSERT_EQUAL_MEMORY(&before, &scan, sizeof scan);
#endif
}

/* ---- encoders: argument checks ------------------------------------------ */

void test_rsm_lms_encode_variant_should_reject_illegal_combinations(void)
{
    uint8_t buf[32];
    memset(buf, 0xEE, sizeof buf);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_variant(buf, sizeof buf, 0, 180u, 25u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_variant(buf, sizeof buf, 0, 180u, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_variant(buf, sizeof buf, 0, 100u, 10u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_variant(buf, sizeof buf, 0, 90u, 100u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_variant(buf, sizeof buf, 0, 0u, 50u));
    TEST_ASSERT_EQUAL_HEX8(0xEE, buf[0]);
    TEST_ASSERT_EQUAL_INT(11, rsm_lms_encode_variant(buf, sizeof buf, 0, 100u, 50u));
    TEST_ASSERT_EQUAL_HEX8(0x32, buf[7]);
}

void test_rsm_lms_encode_mode_should_reject_modes_that_need_parameters(void)
{
    uint8_t buf[32];
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL,
                          rsm_lms_encode_mode(buf, sizeof buf, 0, RSM_LMS_MODE_INSTALLATION));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_mode(buf, sizeof buf, 0, RSM_LMS_MODE_MEAN));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL,
                          rsm_lms_encode_mode(buf, sizeof buf, 0, RSM_LMS_MODE_SUBRANGE));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_mode(buf, sizeof buf, 0, 0x43u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_mode_baud(buf, sizeof buf, 0, 57600u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_mode_baud(buf, sizeof buf, 0, 0u));
    TEST_ASSERT_EQUAL_INT(8, rsm_lms_encode_mode(buf, sizeof buf, 0, RSM_LMS_MODE_DIAGNOSTIC));
    TEST_ASSERT_EQUAL_HEX8(0x10, buf[5]);
    TEST_ASSERT_EQUAL_HEX16(rsm_lms_crc(buf, 6), (uint16_t)(buf[6] | (buf[7] << 8)));
}

void test_rsm_lms_encode_mode_mean_should_encode_the_sample_count(void)
{
    uint8_t buf[32];
    uint8_t expected[32];
    static const uint8_t d[2] = {0x26, 10};
    TEST_ASSERT_EQUAL_INT(9, rsm_lms_encode(expected, sizeof expected, 0x00, 0x20, d, 2));
    assert_encoded(expected, 9, rsm_lms_encode_mode_mean(buf, sizeof buf, 0x00, 10), buf);
    TEST_ASSERT_EQUAL_HEX8(0x03, buf[2]); /* LEN: CMD, mode, count */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_mode_mean(buf, sizeof buf, 0x00, 0));
}

void test_rsm_lms_encode_mode_subrange_should_encode_first_and_last(void)
{
    uint8_t buf[32];
    static const uint8_t head[10] = {0x02, 0x00, 0x06, 0x00, 0x20, 0x27, 0x01, 0x00, 0x69, 0x01};
    TEST_ASSERT_EQUAL_INT(12, rsm_lms_encode_mode_subrange(buf, sizeof buf, 0x00, 1, 361));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(head, buf, 10);
    TEST_ASSERT_EQUAL_HEX16(rsm_lms_crc(buf, 10), (uint16_t)(buf[10] | (buf[11] << 8)));
    TEST_ASSERT_EQUAL_INT(12, rsm_lms_encode_mode_subrange(buf, sizeof buf, 0x00, 401, 401));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_mode_subrange(buf, sizeof buf, 0, 0, 10));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_mode_subrange(buf, sizeof buf, 0, 11, 10));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_mode_subrange(buf, sizeof buf, 0, 1, 402));
}

void test_rsm_lms_encode_should_reject_small_buffers_and_bad_arguments(void)
{
    uint8_t buf[32];
    memset(buf, 0xEE, sizeof buf);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_lms_encode_request_status(buf, 6, 0x00));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_lms_encode_mode_installation(buf, 15, 0x00, NULL));
    TEST_ASSERT_EQUAL_HEX8(0xEE, buf[0]);
    TEST_ASSERT_EQUAL_INT(7, rsm_lms_encode_request_status(buf, 7, 0x00));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_request_status(NULL, 7, 0x00));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_reset(buf, sizeof buf, 0x80));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode(buf, sizeof buf, 0x00, 0x31, NULL, 3));
    /* a request to an LMS at address 1 */
    TEST_ASSERT_EQUAL_INT(7, rsm_lms_encode_request_status(buf, sizeof buf, 0x01));
    TEST_ASSERT_EQUAL_HEX8(0x01, buf[1]);
}

void test_rsm_lms_encode_should_accept_up_to_the_largest_legal_len(void)
{
    static uint8_t data[RSM_LMS_MAX_LEN];
    static uint8_t buf[RSM_LMS_MAX_TELEGRAM + 8];
    rsm_lms_telegram_t t;
    const size_t max_data = (size_t)RSM_LMS_MAX_LEN - 1u;
    memset(data, 0x5A, sizeof data);
    TEST_ASSERT_EQUAL_INT((int)(max_data + 7u),
                          rsm_lms_encode(buf, sizeof buf, 0x80, 0xB0, data, max_data));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_telegram_view(buf, max_data + 7u, &t));
    TEST_ASSERT_EQUAL_UINT16(RSM_LMS_MAX_LEN, t.len);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL,
                          rsm_lms_encode(buf, sizeof buf, 0x80, 0xB0, data, max_data + 1u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM,
                          rsm_lms_encode(buf, max_data + 6u, 0x80, 0xB0, data, max_data));
}

/* A 0xF4 reply around a recognisable 32- or 34-byte block. */
static int build_config_reply(uint8_t *out, size_t cap, uint8_t cmd, size_t block_len,
                              int with_result)
{
    uint8_t d[2u + RSM_LMS_CONFIG_LONG];
    size_t k = 0;
    size_t i;
    if (with_result) {
        d[k++] = 0x01;
    }
    for (i = 0; i < block_len; ++i) {
        d[k + i] = (uint8_t)(0x40u + i);
    }
    d[k + 0] = 0x34; /* blanking 0x1234 */
    d[k + 1] = 0x12;
    d[k + 2] = 0x46; /* stop threshold */
    d[k + 3] = 0x01; /* peak threshold */
    d[k + 4] = 0x02; /* availability: real-time indices */
    d[k + 5] = 0x00; /* D: 8 m, fields A/B + dazzle */
    d[k + 6] = 0x00; /* E: cm */
    d[k + block_len] = 0x10;
    return rsm_lms_encode(out, cap, 0x80, cmd, d, k + block_len + 1u);
}

void test_rsm_lms_decode_config_should_give_fields_and_write_back_changing_only_units(void)
{
    uint8_t frame[64];
    uint8_t out[64];
    uint8_t expected[64];
    uint8_t block[RSM_LMS_CONFIG_LONG];
    rsm_lms_config_t cfg;
    rsm_lms_b0_format_t fmt;
    rsm_lms_telegram_t t;
    size_t len;
    size_t bl;

    for (bl = RSM_LMS_CONFIG_SHORT; bl <= RSM_LMS_CONFIG_LONG; bl += 2u) {
        const int n = build_config_reply(frame, sizeof frame, 0xF4, bl, 0);
        TEST_ASSERT_EQUAL_INT((int)(bl + 8u), n);
        len = (size_t)n;
        t = view_of(frame, len);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_config(&t, &cfg));
        TEST_ASSERT_EQUAL_size_t(bl, cfg.block_len);
        TEST_ASSERT_EQUAL_HEX16(0x1234, cfg.blanking);
        TEST_ASSERT_EQUAL_HEX8(0x46, cfg.stop_threshold);
        TEST_ASSERT_EQUAL_HEX8(0x01, cfg.peak_threshold);
        TEST_ASSERT_EQUAL_HEX8(0x02, cfg.availability);
        TEST_ASSERT_EQUAL_HEX8(RSM_LMS_MEAS_8M_FIELDS_AB_DAZZLE, cfg.measuring_mode);
        TEST_ASSERT_EQUAL_HEX8(RSM_LMS_UNITS_CM, cfg.units);
        TEST_ASSERT_EQUAL_HEX8(0x10, cfg.status);
        TEST_ASSERT_EQUAL_HEX8_ARRAY(frame + 5, cfg.block, bl);

        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_b0_format_from_config(&cfg, &fmt));
        TEST_ASSERT_EQUAL_UINT8(RSM_LMS_UNITS_CM, fmt.units);
        TEST_ASSERT_EQUAL_UINT8(13, fmt.distance_bits);
        TEST_ASSERT_EQUAL_UINT8(2, fmt.index_bytes);

        /* read-modify-write of byte E only */
        cfg.units = RSM_LMS_UNITS_MM;
        memcpy(block, frame + 5, bl);
        block[6] = 0x01;
        TEST_ASSERT_EQUAL_INT((int)(bl + 7u), rsm_lms_encode(expected, sizeof expected, 0x00,
                                                             0x77, block, bl));
        assert_encoded(expected, bl + 7u, rsm_lms_encode_config(out, sizeof out, 0x00, &cfg), out);
    }
}

void test_rsm_lms_encode_config_should_reject_unknown_codes(void)
{
    uint8_t frame[64];
    uint8_t out[64];
    rsm_lms_config_t cfg;
    rsm_lms_telegram_t t;
    const int n = build_config_reply(frame, sizeof frame, 0xF4, RSM_LMS_CONFIG_SHORT, 0);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_config(&t, &cfg));
    cfg.units = 0x02; /* unverified 10 cm code */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_config(out, sizeof out, 0, &cfg));
    cfg.units = RSM_LMS_UNITS_MM;
    cfg.measuring_mode = 0x07;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_config(out, sizeof out, 0, &cfg));
    cfg.measuring_mode = RSM_LMS_MEAS_REFLECTIVITY;
    TEST_ASSERT_EQUAL_INT(39, rsm_lms_encode_config(out, sizeof out, 0, &cfg));
    cfg.block_len = 33;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_config(out, sizeof out, 0, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_encode_config(out, sizeof out, 0, NULL));
}

void test_rsm_lms_decode_config_reply_should_give_result_and_echo(void)
{
    uint8_t frame[64];
    rsm_lms_config_reply_t r;
    rsm_lms_config_t cfg;
    rsm_lms_telegram_t t;
    const int n = build_config_reply(frame, sizeof frame, 0xF7, RSM_LMS_CONFIG_LONG, 1);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_config_reply(&t, &r));
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_RESULT_ACCEPTED, r.result);
    TEST_ASSERT_EQUAL_size_t(RSM_LMS_CONFIG_LONG, r.config.block_len);
    TEST_ASSERT_EQUAL_HEX16(0x1234, r.config.blanking);
    TEST_ASSERT_EQUAL_HEX8(0x10, r.config.status);
    TEST_ASSERT_EQUAL_HEX8(0x40 + 33, r.config.block[33]);
    /* an F7 is not an F4 */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_config(&t, &cfg));
}

void test_rsm_lms_b0_format_from_config_should_map_measuring_modes(void)
{
    static const uint8_t modes[8] = {0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x0F};
    static const uint8_t bits[8] = {13, 13, 13, 14, 14, 15, 15, 16};
    rsm_lms_config_t cfg;
    rsm_lms_b0_format_t fmt;
    rsm_lms_b0_format_t before;
    size_t i;
    memset(&cfg, 0, sizeof cfg);
    cfg.units = RSM_LMS_UNITS_MM;
    for (i = 0; i < 8; ++i) {
        cfg.measuring_mode = modes[i];
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_b0_format_from_config(&cfg, &fmt));
        TEST_ASSERT_EQUAL_UINT8(bits[i], fmt.distance_bits);
        TEST_ASSERT_EQUAL_UINT8(RSM_LMS_UNITS_MM, fmt.units);
        TEST_ASSERT_EQUAL_UINT8(0, fmt.index_bytes);
    }
    memcpy(&before, &fmt, sizeof fmt);
    cfg.measuring_mode = RSM_LMS_MEAS_REFLECTIVITY;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_b0_format_from_config(&cfg, &fmt));
    cfg.measuring_mode = 0x00;
    cfg.units = 0x02;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_b0_format_from_config(&cfg, &fmt));
    TEST_ASSERT_EQUAL_MEMORY(&before, &fmt, sizeof fmt);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_b0_format_from_config(NULL, &fmt));
}

/* ---- decoders: other replies and errors ---------------------------------- */

void test_rsm_lms_decode_not_ack_should_give_the_status(void)
{
    uint8_t frame[16];
    uint8_t status = 0;
    rsm_lms_mode_reply_t mode;
    rsm_lms_telegram_t t;
    static const uint8_t d[1] = {0x10};
    const int n = rsm_lms_encode(frame, sizeof frame, 0x80, 0x92, d, 1);
    TEST_ASSERT_EQUAL_INT(8, n);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_not_ack(&t, &status));
    TEST_ASSERT_EQUAL_HEX8(0x10, status);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_mode_reply(&t, &mode));
}

void test_rsm_lms_decode_type_reply_should_copy_the_text(void)
{
    uint8_t frame[64];
    uint8_t d[RSM_LMS_TEXT_MAX + 2u];
    rsm_lms_text_reply_t r;
    rsm_lms_text_reply_t before;
    rsm_lms_telegram_t t;
    int n;
    memcpy(d, "LMS291;S05;V02.30 ABC", 21);
    d[21] = 0x10;
    n = rsm_lms_encode(frame, sizeof frame, 0x80, 0xBA, d, 22);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_type_reply(&t, &r));
    TEST_ASSERT_EQUAL_STRING("LMS291;S05;V02.30 ABC", r.text);
    TEST_ASSERT_EQUAL_HEX8(0x10, r.status);
    /* one character too many for RSM_LMS_TEXT_MAX */
    memset(d, 'x', sizeof d);
    n = rsm_lms_encode(frame, sizeof frame, 0x80, 0xBA, d, RSM_LMS_TEXT_MAX + 2u);
    t = view_of(frame, (size_t)n);
    memcpy(&before, &r, sizeof r);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_lms_decode_type_reply(&t, &r));
    TEST_ASSERT_EQUAL_MEMORY(&before, &r, sizeof r);
}

void test_rsm_lms_decode_status_byte_should_split_the_actionable_bits(void)
{
    rsm_lms_status_byte_t s;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_status_byte(0x10, &s));
    TEST_ASSERT_EQUAL_HEX8(0x10, s.raw);
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_SEVERITY_NONE, s.severity);
    TEST_ASSERT_EQUAL_UINT8(0, s.implausible);
    TEST_ASSERT_EQUAL_UINT8(0, s.pollution);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_status_byte(0xC4, &s));
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_SEVERITY_FATAL, s.severity);
    TEST_ASSERT_EQUAL_UINT8(1, s.implausible);
    TEST_ASSERT_EQUAL_UINT8(1, s.pollution);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_status_byte(0x42, &s));
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_SEVERITY_WARNING, s.severity);
    TEST_ASSERT_EQUAL_UINT8(1, s.implausible);
    TEST_ASSERT_EQUAL_UINT8(0, s.pollution);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_decode_status_byte(0x10, NULL));
}

void test_rsm_lms_decoders_should_reject_wrong_commands_and_lengths_untouched(void)
{
    uint8_t frame[32];
    rsm_lms_mode_reply_t mode;
    rsm_lms_variant_reply_t var;
    rsm_lms_scan_t scan;
    rsm_lms_text_reply_t text;
    uint8_t status = 0xEE;
    rsm_lms_telegram_t t;
    static const uint8_t d3[3] = {0x00, 0x10, 0x10};
    int n;

    memset(&mode, 0xA5, sizeof mode);
    memset(&var, 0xA5, sizeof var);
    memset(&text, 0xA5, sizeof text);
    /* 0xA0 with one data byte too many */
    n = rsm_lms_encode(frame, sizeof frame, 0x80, 0xA0, d3, 3);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_mode_reply(&t, &mode));
    TEST_ASSERT_EQUAL_HEX8(0xA5, mode.result);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_variant_reply(&t, &var));
    TEST_ASSERT_EQUAL_HEX8(0xA5, var.result);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_reset_reply(&t, &status));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_not_ack(&t, &status));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_power_on(&t, &text));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, NULL, &scan));
    TEST_ASSERT_EQUAL_HEX8(0xEE, status);
    TEST_ASSERT_EQUAL_HEX8(0xA5, (uint8_t)text.text[0]);
    /* 0x91 with a data byte before the status */
    n = rsm_lms_encode(frame, sizeof frame, 0x80, 0x91, d3, 2);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_reset_reply(&t, &status));
    TEST_ASSERT_EQUAL_HEX8(0xEE, status);
    /* NULL arguments */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_decode_mode_reply(NULL, &mode));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_decode_mode_reply(&t, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_decode_b0(&t, NULL, NULL));
}

void test_rsm_lms_telegram_view_should_check_framing_and_crc(void)
{
    uint8_t f[sizeof v_b0_short_mm + 1];
    rsm_lms_telegram_t t;
    memset(&t, 0xA5, sizeof t);
    memcpy(f, v_b0_short_mm, sizeof v_b0_short_mm);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_lms_telegram_view(f, 3, &t));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_AGAIN, rsm_lms_telegram_view(f, sizeof v_b0_short_mm - 1, &t));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_telegram_view(f, sizeof f, &t));
    f[9] ^= 0x01;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CHECKSUM, rsm_lms_telegram_view(f, sizeof v_b0_short_mm, &t));
    f[9] ^= 0x01;
    f[0] = 0x03;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_telegram_view(f, sizeof v_b0_short_mm, &t));
    f[0] = 0x02;
    f[2] = 0x00; /* LEN 0 */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_telegram_view(f, sizeof v_b0_short_mm, &t));
    TEST_ASSERT_EQUAL_HEX8(0xA5, t.cmd);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_telegram_view(NULL, 5, &t));
}

/* ---- 0xB0 details -------------------------------------------------------- */

void test_rsm_lms_decode_b0_should_reject_a_count_that_disagrees_with_len(void)
{
    uint8_t frame[64];
    uint16_t words[6] = {100, 200, 300, 400, 500, 600};
    rsm_lms_scan_t scan;
    rsm_lms_scan_t before;
    rsm_lms_telegram_t t;
    int n;
    memset(&scan, 0x5A, sizeof scan);
    memcpy(&before, &scan, sizeof scan);
    /* count word says 5, LEN carries 6 values */
    n = build_b0(frame, sizeof frame, 0x4005, words, 6, 0x10);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, NULL, &scan));
    /* count word says 7 */
    n = build_b0(frame, sizeof frame, 0x4007, words, 6, 0x10);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, NULL, &scan));
    /* count word 6 but the format expects 2 index bytes */
    {
        rsm_lms_b0_format_t fmt;
        (void)rsm_lms_b0_format_default(&fmt);
        fmt.index_bytes = 2;
        n = build_b0(frame, sizeof frame, 0x4006, words, 6, 0x10);
        t = view_of(frame, (size_t)n);
        TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, &fmt, &scan));
        /* ... and accepts them when they are there (count 5 + 2 bytes) */
        n = build_b0(frame, sizeof frame, 0x4005, words, 6, 0x10);
        t = view_of(frame, (size_t)n);
        TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, NULL, &scan));
        TEST_ASSERT_EQUAL_MEMORY(&before, &scan, sizeof scan);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, &fmt, &scan));
        TEST_ASSERT_EQUAL_size_t(5, scan.count);
        TEST_ASSERT_EQUAL_UINT8(2, scan.index_len);
        TEST_ASSERT_EQUAL_HEX8(600 & 0xFF, scan.index[0]);
        TEST_ASSERT_EQUAL_HEX8(600 >> 8, scan.index[1]);
    }
    /* too short for a count word */
    {
        static const uint8_t st[2] = {0x00, 0x10};
        n = rsm_lms_encode(frame, sizeof frame, 0x80, 0xB0, st + 1, 1);
        t = view_of(frame, (size_t)n);
        TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, NULL, &scan));
        n = rsm_lms_encode(frame, sizeof frame, 0x80, 0xB0, st, 2);
        t = view_of(frame, (size_t)n);
        TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, NULL, &scan));
    }
}

void test_rsm_lms_decode_b0_should_check_units(void)
{
    uint8_t frame[64];
    uint16_t words[2] = {100, 200};
    rsm_lms_scan_t scan;
    rsm_lms_b0_format_t fmt;
    rsm_lms_telegram_t t;
    int n;
    (void)rsm_lms_b0_format_default(&fmt);
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_UNITS_AUTO, fmt.units);
    TEST_ASSERT_EQUAL_UINT8(13, fmt.distance_bits);
    /* reserved units 1x */
    n = build_b0(frame, sizeof frame, 0x8002, words, 2, 0x10);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, NULL, &scan));
    n = build_b0(frame, sizeof frame, 0xC002, words, 2, 0x10);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, NULL, &scan));
    /* cm telegram while mm is required */
    n = build_b0(frame, sizeof frame, 0x0002, words, 2, 0x10);
    t = view_of(frame, (size_t)n);
    fmt.units = RSM_LMS_UNITS_MM;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_b0(&t, &fmt, &scan));
    fmt.units = RSM_LMS_UNITS_CM;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, &fmt, &scan));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.0f, scan.reading[1].range_m);
    /* a bad format */
    fmt.units = 0x05;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_decode_b0(&t, &fmt, &scan));
    fmt.units = RSM_LMS_UNITS_AUTO;
    fmt.distance_bits = 12;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_decode_b0(&t, &fmt, &scan));
    fmt.distance_bits = 13;
    fmt.index_bytes = 3;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_decode_b0(&t, &fmt, &scan));
}

void test_rsm_lms_decode_b0_should_map_every_error_code_to_invalid(void)
{
    static const uint8_t bits[4] = {13, 14, 15, 16};
    static const uint8_t codes[9] = {
        RSM_LMS_READING_TOO_FAR,       /* top - 8 */
        RSM_LMS_READING_RESERVED,      /* top - 7 */
        RSM_LMS_READING_RESERVED,      /* top - 6 */
        RSM_LMS_READING_CHANNEL_ERROR, /* top - 5 */
        RSM_LMS_READING_SNR_LOW,       /* top - 4 */
        RSM_LMS_READING_RESERVED,      /* top - 3 */
        RSM_LMS_READING_OVERFLOW,      /* top - 2 */
        RSM_LMS_READING_DAZZLED,       /* top - 1 */
        RSM_LMS_READING_NO_ECHO        /* top */
    };
    uint8_t frame[64];
    uint16_t words[10];
    rsm_lms_scan_t scan;
    rsm_lms_b0_format_t fmt;
    rsm_lms_telegram_t t;
    size_t b;
    size_t i;
    (void)rsm_lms_b0_format_default(&fmt);
    for (b = 0; b < 4; ++b) {
        const uint16_t top = (uint16_t)((1ul << bits[b]) - 1ul);
        words[0] = (uint16_t)(top - 9u); /* largest ordinary distance */
        for (i = 0; i < 9; ++i) {
            words[1 + i] = (uint16_t)(top - 8u + i);
        }
        fmt.distance_bits = bits[b];
        TEST_ASSERT_TRUE(build_b0(frame, sizeof frame, 0x400A, words, 10, 0x10) > 0);
        t = view_of(frame, 2u * 10u + 10u);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, &fmt, &scan));
        TEST_ASSERT_EQUAL_HEX16(top, scan.distance_mask);
        TEST_ASSERT_EQUAL_UINT8(RSM_LMS_READING_OK, scan.reading[0].code);
        TEST_ASSERT_FLOAT_WITHIN(1e-3f, (float)(top - 9u) / 1000.0f, scan.reading[0].range_m);
        for (i = 0; i < 9; ++i) {
            TEST_ASSERT_EQUAL_UINT8(codes[i], scan.reading[1 + i].code);
            TEST_ASSERT_TRUE(scan.reading[1 + i].range_m == 0.0f);
        }
    }
    /* 13-bit codes stay codes whatever the flag bits above them */
    fmt.distance_bits = 13;
    words[0] = 0xFFFF; /* all flags + no echo */
    words[1] = 0x3FFE; /* field A + dazzled */
    TEST_ASSERT_TRUE(build_b0(frame, sizeof frame, 0x4002, words, 2, 0x10) > 0);
    t = view_of(frame, 2u * 2u + 10u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, &fmt, &scan));
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_READING_NO_ECHO, scan.reading[0].code);
    TEST_ASSERT_EQUAL_UINT8(7, scan.reading[0].flags);
    TEST_ASSERT_EQUAL_UINT8(RSM_LMS_READING_DAZZLED, scan.reading[1].code);
    TEST_ASSERT_EQUAL_UINT8(1, scan.reading[1].flags);
}

void test_rsm_lms_decode_b0_should_use_the_configured_distance_bits(void)
{
    /* the captured scan's first flagged word, read in 13- and 14-bit modes */
    uint8_t frame[32];
    uint16_t words[1] = {0x227A};
    rsm_lms_scan_t scan;
    rsm_lms_b0_format_t fmt;
    rsm_lms_telegram_t t;
    (void)rsm_lms_b0_format_default(&fmt);
    TEST_ASSERT_TRUE(build_b0(frame, sizeof frame, 0x4001, words, 1, 0x10) > 0);
    t = view_of(frame, 2u + 10u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, &fmt, &scan));
    TEST_ASSERT_EQUAL_UINT8(1, scan.reading[0].flags);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.634f, scan.reading[0].range_m);
    fmt.distance_bits = 14;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, &fmt, &scan));
    TEST_ASSERT_EQUAL_UINT8(0, scan.reading[0].flags);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 8.826f, scan.reading[0].range_m);
    fmt.distance_bits = 16;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, &fmt, &scan));
    TEST_ASSERT_EQUAL_UINT8(0, scan.reading[0].flags);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 8.826f, scan.reading[0].range_m);
}

/* Readings in the largest 0xB0 telegram the receiver accepts:
 * LEN = CMD + count word + 2 per reading + status <= RSM_LMS_MAX_LEN. */
#define LMS_MAX_READINGS ((size_t)((RSM_LMS_MAX_LEN - 4u) / 2u))

/* The decoder refuses more readings than RSM_MAX_BEAMS (RSM_ERR_NOMEM,
 * output untouched). Under the default and small configurations a legal
 * telegram can carry that many; under a larger RSM_MAX_BEAMS (the host
 * preset's 721) no telegram the receiver accepts can, so there the largest
 * legal telegram must decode whole, and the limit is checked on a telegram
 * described by hand, as a caller with its own framing could pass. */
void test_rsm_lms_decode_b0_should_reject_more_readings_than_rsm_max_beams(void)
{
    static uint16_t words[RSM_MAX_BEAMS + 1];
    static uint8_t frame[RSM_LMS_MAX_TELEGRAM];
    static uint8_t data[2u + 2u * (RSM_MAX_BEAMS + 1u) + 1u];
    rsm_lms_scan_t scan;
    rsm_lms_scan_t before;
    rsm_lms_telegram_t t;
    const size_t fit = (size_t)RSM_MAX_BEAMS < LMS_MAX_READINGS ? (size_t)RSM_MAX_BEAMS : LMS_MAX_READINGS;
    const size_t over = (size_t)RSM_MAX_BEAMS + 1u;
    size_t i;
    int n;
    for (i = 0; i < over; ++i) {
        words[i] = (uint16_t)(1000u + i);
    }
    /* as many readings as both the decoder and the receiver take: all decoded */
    n = build_b0(frame, sizeof frame, (uint16_t)(0x4000u | fit), words, fit, 0x10);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, NULL, &scan));
    TEST_ASSERT_EQUAL_size_t(fit, scan.count);
    TEST_ASSERT_EQUAL_UINT16(1000u + fit - 1u, scan.reading[fit - 1u].raw);
    /* one reading over RSM_MAX_BEAMS is refused, output untouched */
    if (over <= LMS_MAX_READINGS) {
        n = build_b0(frame, sizeof frame, (uint16_t)(0x4000u | over), words, over, 0x10);
        t = view_of(frame, (size_t)n);
    } else {
        /* no legal telegram carries more than LMS_MAX_READINGS */
        TEST_ASSERT_TRUE(build_b0(frame, sizeof frame, (uint16_t)(0x4000u | (LMS_MAX_READINGS + 1u)), words,
                                  LMS_MAX_READINGS + 1u, 0x10) < 0);
        data[0] = (uint8_t)((0x4000u | over) & 0xFFu);
        data[1] = (uint8_t)((0x4000u | over) >> 8);
        for (i = 0; i < over; ++i) {
            data[2u + 2u * i] = (uint8_t)(words[i] & 0xFFu);
            data[3u + 2u * i] = (uint8_t)(words[i] >> 8);
        }
        data[2u + 2u * over] = 0x10;
        memset(&t, 0, sizeof t);
        t.adr = 0x80u;
        t.cmd = 0xB0u;
        t.data = data;
        t.data_len = 3u + 2u * over;
        t.len = (uint16_t)(1u + t.data_len);
    }
    memset(&scan, 0x5A, sizeof scan);
    memcpy(&before, &scan, sizeof scan);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_lms_decode_b0(&t, NULL, &scan));
    TEST_ASSERT_EQUAL_MEMORY(&before, &scan, sizeof scan);
}

/* Decodes an n-reading full scan and checks start/step and two angles. */
static void check_geometry(size_t n, uint16_t start, uint16_t step)
{
    static uint16_t words[405];
    static uint8_t frame[RSM_LMS_MAX_TELEGRAM];
    rsm_lms_scan_t scan;
    rsm_lms_telegram_t t;
    float a = -1.0f;
    size_t i;
    int len;
    for (i = 0; i < n; ++i) {
        words[i] = 1500;
    }
    len = build_b0(frame, sizeof frame, (uint16_t)(0x4000u | n), words, n, 0x10);
    t = view_of(frame, (size_t)len);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, NULL, &scan));
    TEST_ASSERT_EQUAL_UINT16(start, scan.start_cdeg);
    TEST_ASSERT_EQUAL_UINT16(step, scan.step_cdeg);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_scan_angle(&scan, 0, &a));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, (float)start * 3.14159265f / 18000.0f, a);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_scan_angle(&scan, n - 1u, &a));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, (float)(start + (n - 1u) * step) * 3.14159265f / 18000.0f,
                             a);
    a = -1.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_lms_scan_angle(&scan, n, &a));
    TEST_ASSERT_TRUE(a == -1.0f);
}

void test_rsm_lms_scan_angle_should_follow_the_variant_of_the_count(void)
{
    check_geometry(181, 0, 100);    /* 180 deg, 1 deg: 0..180 */
    check_geometry(101, 4000, 100); /* 100 deg, 1 deg: 40..140 */
#if RSM_MAX_BEAMS >= 201
    check_geometry(201, 4000, 50); /* 100 deg, 0.5 deg: 40..140 */
#endif
#if RSM_MAX_BEAMS >= 361
    check_geometry(361, 0, 50); /* 180 deg, 0.5 deg: 0..180 */
#endif
#if RSM_MAX_BEAMS >= 401
    check_geometry(401, 4000, 25); /* 100 deg, 0.25 deg: 40..140 */
#endif
}

void test_rsm_lms_scan_angle_should_refuse_unknown_geometry(void)
{
    uint8_t frame[64];
    uint16_t words[5] = {1, 2, 3, 4, 5};
    rsm_lms_scan_t scan;
    rsm_lms_telegram_t t;
    float a = -1.0f;
    (void)build_b0(frame, sizeof frame, 0x4005, words, 5, 0x10);
    t = view_of(frame, 2u * 5u + 10u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, NULL, &scan));
    TEST_ASSERT_EQUAL_UINT16(0, scan.step_cdeg);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_lms_scan_angle(&scan, 0, &a));
    TEST_ASSERT_TRUE(a == -1.0f);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_scan_angle(NULL, 0, &a));
}

void test_rsm_lms_decode_b0_should_leave_partial_scans_without_angles(void)
{
    static uint16_t words[181];
    static uint8_t frame[RSM_LMS_MAX_TELEGRAM];
    rsm_lms_scan_t scan;
    rsm_lms_telegram_t t;
    float a = -1.0f;
    size_t i;
    int n;
    for (i = 0; i < 181; ++i) {
        words[i] = 700;
    }
    /* mm, partial scan (bit 13), partial index 2 (bits 11-12), 181 values */
    n = build_b0(frame, sizeof frame, (uint16_t)(0x4000u | 0x2000u | 0x1000u | 181u), words,
                 181, 0x10);
    t = view_of(frame, (size_t)n);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, NULL, &scan));
    TEST_ASSERT_EQUAL_size_t(181, scan.count);
    TEST_ASSERT_EQUAL_UINT8(1, scan.partial);
    TEST_ASSERT_EQUAL_UINT8(2, scan.partial_index);
    TEST_ASSERT_EQUAL_UINT16(0, scan.step_cdeg);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_lms_scan_angle(&scan, 0, &a));
}

/* ---- receiver ------------------------------------------------------------ */

void test_rsm_lms_parser_feed_should_report_a_nak(void)
{
    static const uint8_t s[] = {0x15};
    rsm_lms_parser_t p;
    rsm_lms_event_t ev;
    size_t used = 99;
    (void)rsm_lms_parser_init(&p);
    TEST_ASSERT_EQUAL_INT(1, rsm_lms_parser_feed(&p, s, 1, &used, &ev));
    TEST_ASSERT_EQUAL_size_t(1, used);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_NAK, ev.type);
    TEST_ASSERT_EQUAL_INT(0, rsm_lms_parser_feed(&p, s + 1, 0, &used, &ev));
    TEST_ASSERT_EQUAL_size_t(0, used);
    TEST_ASSERT_EQUAL_UINT32(1, p.stats.naks);
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.acks);
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.bytes_skipped);
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.telegrams_ok);
}

void test_rsm_lms_parser_feed_should_not_see_ack_nak_or_stx_inside_a_telegram(void)
{
    /* a 0x92 reply whose data holds 06, 15, 02 80 and a fake header */
    static const uint8_t d[8] = {0x06, 0x15, 0x02, 0x80, 0x03, 0x00, 0x06, 0x10};
    uint8_t frame[32];
    uint8_t s[64];
    run_log_t log;
    int n = rsm_lms_encode(frame, sizeof frame, 0x80, 0x92, d, sizeof d);
    const size_t fl = (size_t)n;
    s[0] = 0x06;
    memcpy(s + 1, frame, fl);
    s[1 + fl] = 0x15;
    run_parser(s, fl + 2u, CHUNK_BYTES, 1, &log);
    TEST_ASSERT_EQUAL_size_t(3, log.n);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_ACK, log.ev[0].type);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_TELEGRAM, log.ev[1].type);
    TEST_ASSERT_EQUAL_HEX32(fnv1a(frame, fl), log.ev[1].hash);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_NAK, log.ev[2].type);
    TEST_ASSERT_EQUAL_UINT32(1, log.st.acks);
    TEST_ASSERT_EQUAL_UINT32(1, log.st.naks);
    TEST_ASSERT_EQUAL_UINT32(1, log.st.telegrams_ok);
    TEST_ASSERT_EQUAL_UINT32(0, log.st.bytes_skipped);
}

void test_rsm_lms_parser_feed_should_reject_invalid_arguments(void)
{
    rsm_lms_parser_t p;
    rsm_lms_event_t ev;
    size_t used = 7;
    (void)rsm_lms_parser_init(&p);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_parser_feed(NULL, v_reset, 7, &used, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_parser_feed(&p, NULL, 7, &used, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_parser_feed(&p, v_reset, 7, NULL, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_parser_feed(&p, v_reset, 7, &used, NULL));
    TEST_ASSERT_EQUAL_size_t(7, used);
    TEST_ASSERT_EQUAL_INT(0, rsm_lms_parser_feed(&p, NULL, 0, &used, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_parser_init(NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_parser_timeout(NULL, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_parser_timeout(&p, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_lms_parser_flush(NULL));
}

void test_rsm_lms_parser_flush_should_drop_held_bytes_as_skipped(void)
{
    rsm_lms_parser_t p;
    rsm_lms_event_t ev;
    size_t used = 0;
    (void)rsm_lms_parser_init(&p);
    TEST_ASSERT_EQUAL_size_t(0, rsm_lms_parser_pending(&p));
    TEST_ASSERT_EQUAL_INT(0, rsm_lms_parser_feed(&p, v_b0_short_mm, 9, &used, &ev));
    TEST_ASSERT_EQUAL_size_t(9, rsm_lms_parser_pending(&p));
    TEST_ASSERT_EQUAL_size_t(0, rsm_lms_parser_pending(NULL));
    TEST_ASSERT_EQUAL_INT(9, rsm_lms_parser_flush(&p));
    TEST_ASSERT_EQUAL_size_t(0, rsm_lms_parser_pending(&p));
    TEST_ASSERT_EQUAL_UINT32(9, p.stats.bytes_skipped);
    TEST_ASSERT_EQUAL_INT(0, rsm_lms_parser_flush(&p));
    TEST_ASSERT_EQUAL_INT(0, rsm_lms_parser_timeout(&p, &ev));
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.truncated);
    TEST_ASSERT_EQUAL_INT(1, rsm_lms_parser_feed(&p, v_b0_short_mm, sizeof v_b0_short_mm, &used,
                                                 &ev));
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_TELEGRAM, ev.type);
}

/* Builds a stream: STX, reply ADR and the LEN field value `field`, then a
 * good telegram. Returns its length. */
static size_t bad_len_stream(uint8_t *s, uint16_t field)
{
    s[0] = 0x02;
    s[1] = 0x80;
    s[2] = (uint8_t)(field & 0xFFu);
    s[3] = (uint8_t)(field >> 8);
    memcpy(s + 4, v_b0_short_mm, sizeof v_b0_short_mm);
    return 4u + sizeof v_b0_short_mm;
}

void test_rsm_lms_parser_feed_should_reject_len_0_max_plus_1_and_0xffff(void)
{
    static const uint16_t bad[3] = {0x0000, (uint16_t)(RSM_LMS_MAX_LEN + 1), 0xFFFF};
    uint8_t s[64];
    run_log_t log;
    run_log_t want;
    size_t i;
    for (i = 0; i < 3; ++i) {
        const size_t n = bad_len_stream(s, bad[i]);
        run_parser(s, n, CHUNK_RANDOM, 0, &log);
        TEST_ASSERT_EQUAL_UINT32(1, log.st.bad_length);
        TEST_ASSERT_EQUAL_UINT32(4, log.st.bytes_skipped);
        TEST_ASSERT_EQUAL_UINT32(1, log.st.telegrams_ok);
        TEST_ASSERT_EQUAL_UINT32(0, log.st.crc_errors);
        TEST_ASSERT_EQUAL_UINT32(0, log.st.truncated);
        TEST_ASSERT_EQUAL_size_t(1, log.n);
        TEST_ASSERT_EQUAL_HEX32(fnv1a(v_b0_short_mm, sizeof v_b0_short_mm), log.ev[0].hash);
        log_clear(&want);
        ref_scan(s, n, 0, &want);
        assert_logs_equal(&want, &log);
    }
}

void test_rsm_lms_parser_feed_should_accept_len_1_and_the_largest_legal_len(void)
{
    static uint8_t s[RSM_LMS_MAX_TELEGRAM + 64];
    static uint8_t data[RSM_LMS_MAX_LEN];
    run_log_t log;
    rsm_lms_parser_t p;
    rsm_lms_event_t ev;
    uint8_t status = 0;
    size_t used = 0;
    size_t n1;
    size_t n2;
    size_t i;
    /* LEN 1: CMD only, no status byte */
    TEST_ASSERT_EQUAL_INT(7, rsm_lms_encode(s, sizeof s, 0x80, 0x91, NULL, 0));
    n1 = 7;
    (void)rsm_lms_parser_init(&p);
    TEST_ASSERT_EQUAL_INT(1, rsm_lms_parser_feed(&p, s, n1, &used, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_TELEGRAM, ev.type);
    TEST_ASSERT_EQUAL_UINT16(1, ev.telegram.len);
    TEST_ASSERT_EQUAL_size_t(0, ev.telegram.data_len);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_PROTO, rsm_lms_decode_reset_reply(&ev.telegram, &status));
    /* LEN = RSM_LMS_MAX_LEN right behind it */
    for (i = 0; i < sizeof data; ++i) {
        data[i] = (uint8_t)(i * 7u);
    }
    n2 = (size_t)rsm_lms_encode(s + n1, sizeof s - n1, 0x80, 0xB0, data,
                                (size_t)RSM_LMS_MAX_LEN - 1u);
    TEST_ASSERT_EQUAL_size_t((size_t)RSM_LMS_MAX_LEN + 6u, n2);
    run_parser(s, n1 + n2, CHUNK_RANDOM, 1, &log);
    TEST_ASSERT_EQUAL_size_t(2, log.n);
    TEST_ASSERT_EQUAL_size_t(n2, log.ev[1].len);
    TEST_ASSERT_EQUAL_HEX32(fnv1a(s + n1, n2), log.ev[1].hash);
    TEST_ASSERT_EQUAL_UINT32(2, log.st.telegrams_ok);
    TEST_ASSERT_EQUAL_UINT32(0, log.st.bytes_skipped);
    TEST_ASSERT_EQUAL_UINT32(0, log.st.bad_length);
}

void test_rsm_lms_parser_feed_should_find_a_largest_telegram_inside_a_failed_candidate(void)
{
    /* A candidate announcing the largest LEN swallows the start of a real
     * largest telegram; after its CRC fails the real one must still come out
     * whole (it starts mid-buffer and runs past the buffer end). */
    static uint8_t s[2u * RSM_LMS_MAX_TELEGRAM];
    static uint8_t data[RSM_LMS_MAX_LEN];
    run_log_t log;
    run_log_t want;
    const size_t fake = 10;
    size_t n;
    size_t i;
    for (i = 0; i < sizeof data; ++i) {
        data[i] = (uint8_t)(0x30u + (i % 40u));
    }
    s[0] = 0x02;
    s[1] = 0x80;
    s[2] = (uint8_t)(RSM_LMS_MAX_LEN & 0xFF);
    s[3] = (uint8_t)(RSM_LMS_MAX_LEN >> 8);
    for (i = 4; i < fake; ++i) {
        s[i] = 0x41;
    }
    n = fake + (size_t)rsm_lms_encode(s + fake, sizeof s - fake, 0x80, 0xB0, data,
                                      (size_t)RSM_LMS_MAX_LEN - 1u);
    for (i = 0; i < 3; ++i) {
        run_parser(s, n, (int)i, 1, &log);
        TEST_ASSERT_EQUAL_UINT32(1, log.st.crc_errors);
        TEST_ASSERT_EQUAL_UINT32(1, log.st.telegrams_ok);
        TEST_ASSERT_EQUAL_UINT32(fake, log.st.bytes_skipped);
        TEST_ASSERT_EQUAL_HEX32(fnv1a(s + fake, n - fake), log.ev[0].hash);
        log_clear(&want);
        ref_scan(s, n, 1, &want);
        assert_logs_equal(&want, &log);
    }
}

/* Flips every bit of tele in turn, follows it with enough copies of good to
 * complete any candidate, and checks the receiver against the reference. */
static void check_every_bit_flip(const uint8_t *tele, size_t tl, const uint8_t *good,
                                 size_t gl)
{
    static uint8_t s[2u * RSM_LMS_MAX_TELEGRAM + 64u];
    run_log_t log;
    run_log_t want;
    const size_t copies = (size_t)RSM_LMS_MAX_TELEGRAM / gl + 2u;
    const uint32_t good_hash = fnv1a(good, gl);
    size_t bit;
    size_t i;
    size_t n = tl;
    TEST_ASSERT_TRUE(tl + copies * gl <= sizeof s);
    for (i = 0; i < copies; ++i) {
        memcpy(s + tl + i * gl, good, gl);
        n += gl;
    }
    for (bit = 0; bit < tl * 8u; ++bit) {
        const size_t at = bit / 8u;
        memcpy(s, tele, tl);
        s[at] = (uint8_t)(s[at] ^ (1u << (bit % 8u)));
        run_parser(s, n, CHUNK_RANDOM, 1, &log);
        log_clear(&want);
        ref_scan(s, n, 1, &want);
        assert_logs_equal(&want, &log);
        /* the damaged telegram never comes out, every good one does */
        TEST_ASSERT_EQUAL_UINT32(copies, log.st.telegrams_ok);
        for (i = 0; i < log.n; ++i) {
            if (log.ev[i].type == RSM_LMS_EVENT_TELEGRAM) {
                TEST_ASSERT_EQUAL_HEX32(good_hash, log.ev[i].hash);
            }
        }
        TEST_ASSERT_EQUAL_UINT32(0, log.st.truncated);
        assert_conserved(&log, n);
        TEST_ASSERT_EQUAL_UINT32(tl, log.st.bytes_skipped + log.st.acks + log.st.naks);
        if (at >= 2u || (at == 1u && bit % 8u != 7u)) {
            /* STX and reply address intact: the candidate is rejected */
            TEST_ASSERT_TRUE(log.st.crc_errors + log.st.bad_length >= 1u);
        }
        if (at >= 4u || (at == 1u && bit % 8u != 7u)) {
            /* LEN intact too: exactly one CRC error, unless the flip made a
             * new candidate that fails on its own */
            TEST_ASSERT_TRUE(log.st.crc_errors >= 1u);
        }
    }
}

void test_rsm_lms_parser_feed_should_survive_every_bit_flip_of_a_b0_telegram(void)
{
    rsm_lms_parser_t p;
    rsm_lms_event_t ev;
    rsm_lms_scan_t scan;
    size_t used = 0;
    uint8_t s[2u * sizeof v_b0_short_mm];
    check_every_bit_flip(v_b0_short_mm, sizeof v_b0_short_mm, v_b0_short_mm,
                         sizeof v_b0_short_mm);
    /* and the next good telegram decodes: one flip shown end to end */
    memcpy(s, v_b0_short_mm, sizeof v_b0_short_mm);
    memcpy(s + sizeof v_b0_short_mm, v_b0_short_mm, sizeof v_b0_short_mm);
    s[8] ^= 0x10;
    (void)rsm_lms_parser_init(&p);
    TEST_ASSERT_EQUAL_INT(1, rsm_lms_parser_feed(&p, s, sizeof s, &used, &ev));
    TEST_ASSERT_EQUAL_size_t(sizeof s, used);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&ev.telegram, NULL, &scan));
    TEST_ASSERT_EQUAL_UINT16(8182, scan.reading[0].raw);
    TEST_ASSERT_EQUAL_UINT32(1, p.stats.crc_errors);
    TEST_ASSERT_EQUAL_UINT32(16, p.stats.bytes_skipped);
    TEST_ASSERT_EQUAL_UINT32(1, p.stats.telegrams_ok);
}

void test_rsm_lms_parser_feed_should_survive_every_bit_flip_of_a_mode_reply(void)
{
    const uint8_t *reply = v_ack_then_mode_response + 1;
    const size_t rl = sizeof v_ack_then_mode_response - 1u;
    rsm_lms_parser_t p;
    rsm_lms_event_t ev;
    rsm_lms_mode_reply_t mode;
    size_t used = 0;
    uint8_t s[32];
    check_every_bit_flip(reply, rl, reply, rl);
    memcpy(s, reply, rl);
    memcpy(s + rl, reply, rl);
    s[5] ^= 0x01; /* result 0x00 -> 0x01 */
    (void)rsm_lms_parser_init(&p);
    TEST_ASSERT_EQUAL_INT(1, rsm_lms_parser_feed(&p, s, 2u * rl, &used, &ev));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_mode_reply(&ev.telegram, &mode));
    TEST_ASSERT_EQUAL_HEX8(0x00, mode.result);
    TEST_ASSERT_EQUAL_UINT32(1, p.stats.crc_errors);
    TEST_ASSERT_EQUAL_UINT32(rl, p.stats.bytes_skipped);
}

void test_rsm_lms_parser_feed_should_recover_after_truncation_at_every_offset(void)
{
    static uint8_t s[2u * RSM_LMS_MAX_TELEGRAM];
    const size_t tl = sizeof v_b0_short_mm;
    const size_t copies = (size_t)RSM_LMS_MAX_TELEGRAM / tl + 2u;
    const uint32_t good_hash = fnv1a(v_b0_short_mm, tl);
    run_log_t log;
    run_log_t want;
    size_t cut;
    size_t i;
    for (cut = 0; cut < tl; ++cut) {
        size_t n = cut;
        memcpy(s, v_b0_short_mm, cut);
        for (i = 0; i < copies; ++i) {
            memcpy(s + n, v_b0_short_mm, tl);
            n += tl;
        }
        /* without a timeout: the later telegrams complete the candidate */
        run_parser(s, n, CHUNK_RANDOM, 1, &log);
        log_clear(&want);
        ref_scan(s, n, 1, &want);
        assert_logs_equal(&want, &log);
        TEST_ASSERT_EQUAL_UINT32(copies, log.st.telegrams_ok);
        TEST_ASSERT_EQUAL_UINT32(cut, log.st.bytes_skipped);
        TEST_ASSERT_EQUAL_UINT32(0, log.st.truncated);
        TEST_ASSERT_EQUAL_UINT32(cut >= 2u ? 1u : 0u, log.st.crc_errors + log.st.bad_length);
        TEST_ASSERT_EQUAL_UINT32(cut == 2u ? 1u : 0u, log.st.bad_length);
        for (i = 0; i < log.n; ++i) {
            TEST_ASSERT_EQUAL_HEX32(good_hash, log.ev[i].hash);
        }
    }
}

void test_rsm_lms_parser_timeout_should_abandon_a_truncated_telegram_at_every_offset(void)
{
    const size_t tl = sizeof v_b0_short_mm;
    run_log_t log;
    size_t cut;
    size_t chunking;
    for (chunking = 0; chunking < 3; ++chunking) {
        for (cut = 0; cut < tl; ++cut) {
            rsm_lms_parser_t p;
            rsm_lms_event_t ev;
            log_clear(&log);
            (void)rsm_lms_parser_init(&p);
            feed_stream(&p, v_b0_short_mm, cut, (int)chunking, 7u, &log);
            TEST_ASSERT_EQUAL_size_t(0, log.n);
            drain_timeout(&p, &log);
            TEST_ASSERT_EQUAL_size_t(0, log.n);
            TEST_ASSERT_EQUAL_UINT32(cut > 0u ? 1u : 0u, p.stats.truncated);
            TEST_ASSERT_EQUAL_UINT32(cut, p.stats.bytes_skipped);
            TEST_ASSERT_EQUAL_UINT32(0, p.stats.crc_errors);
            TEST_ASSERT_EQUAL_UINT32(0, p.stats.bad_length);
            /* the next telegram is received whole and alone */
            feed_stream(&p, v_b0_short_mm, tl, (int)chunking, 9u, &log);
            TEST_ASSERT_EQUAL_size_t(1, log.n);
            TEST_ASSERT_EQUAL_HEX32(fnv1a(v_b0_short_mm, tl), log.ev[0].hash);
            TEST_ASSERT_EQUAL_UINT32(1, p.stats.telegrams_ok);
            TEST_ASSERT_EQUAL_UINT32(cut, p.stats.bytes_skipped);
            TEST_ASSERT_EQUAL_INT(0, rsm_lms_parser_timeout(&p, &ev));
        }
    }
}

/* Garbage biased towards the bytes the receiver reacts to. */
static size_t put_garbage(uint8_t *s, size_t n, uint32_t *rng)
{
    static const uint8_t hot[8] = {0x02, 0x80, 0x81, 0x06, 0x15, 0x00, 0x03, 0xB0};
    size_t i;
    for (i = 0; i < n; ++i) {
        const uint32_t r = prng_next(rng);
        s[i] = ((r & 3u) == 0u) ? hot[(r >> 2) & 7u] : (uint8_t)(r >> 8);
    }
    return n;
}

typedef struct tele_ref {
    const uint8_t *b;
    size_t n;
} tele_ref_t;

static const tele_ref_t sensor_vectors[] = {
    {v_ack_then_mode_response + 1, sizeof v_ack_then_mode_response - 1},
    {v_mode_response_addr81, sizeof v_mode_response_addr81},
    {v_reset_reply_0x91 + 1, sizeof v_reset_reply_0x91 - 1},
    {v_powerup_quick_manual, sizeof v_powerup_quick_manual},
    {v_powerup_captured, sizeof v_powerup_captured},
    {v_b0_short_cm, sizeof v_b0_short_cm},
    {v_b0_short_mm, sizeof v_b0_short_mm},
    {v_bb_variant_ok, sizeof v_bb_variant_ok},
    {v_b0_captured_361_mm, sizeof v_b0_captured_361_mm},
};

/* A stream of the sensor vectors with garbage before, between and inside
 * some of them; intact[] receives the hashes of the undamaged ones. */
static size_t build_garbage_stream(uint8_t *s, size_t cap, uint32_t seed, uint32_t *intact,
                                   size_t *n_intact)
{
    uint32_t rng = seed;
    size_t n = 0;
    size_t k = 0;
    size_t round;
    for (round = 0; round < 120u; ++round) {
        const tele_ref_t *t = &sensor_vectors[prng_next(&rng) % ARRAY_LEN(sensor_vectors)];
        const size_t g = (size_t)(prng_next(&rng) % 24u);
        const int damage = (prng_next(&rng) % 4u) == 0u;
        if (n + g + t->n + 8u > cap) {
            break;
        }
        n += put_garbage(s + n, g, &rng);
        if (damage) {
            const size_t at = 1u + (size_t)(prng_next(&rng) % (uint32_t)(t->n - 1u));
            const size_t ins = 1u + (size_t)(prng_next(&rng) % 5u);
            memcpy(s + n, t->b, at);
            n += at;
            n += put_garbage(s + n, ins, &rng);
            memcpy(s + n, t->b + at, t->n - at);
            n += t->n - at;
        } else {
            memcpy(s + n, t->b, t->n);
            n += t->n;
            intact[k++] = fnv1a(t->b, t->n);
        }
    }
    n += put_garbage(s + n, 11, &rng);
    *n_intact = k;
    return n;
}

void test_rsm_lms_parser_feed_should_lose_no_telegram_to_random_garbage(void)
{
    static uint8_t s[40000];
    static uint32_t intact[200];
    static run_log_t log;
    static run_log_t want;
    uint32_t seed;
    for (seed = 1; seed <= 8u; ++seed) {
        size_t n_intact = 0;
        size_t i;
        size_t k = 0;
        const size_t n = build_garbage_stream(s, sizeof s, seed * 0x9E3779B9u, intact, &n_intact);
        TEST_ASSERT_TRUE(n_intact > 40u);
        run_parser(s, n, CHUNK_RANDOM, 1, &log);
        /* every intact telegram, in order, and nothing else */
        for (i = 0; i < log.n; ++i) {
            if (log.ev[i].type == RSM_LMS_EVENT_TELEGRAM) {
                TEST_ASSERT_TRUE(k < n_intact);
                TEST_ASSERT_EQUAL_HEX32(intact[k], log.ev[i].hash);
                k++;
            }
        }
        TEST_ASSERT_EQUAL_size_t(n_intact, k);
        TEST_ASSERT_EQUAL_UINT32(n_intact, log.st.telegrams_ok);
        assert_conserved(&log, n);
        log_clear(&want);
        ref_scan(s, n, 1, &want);
        assert_logs_equal(&want, &log);
    }
}

void test_rsm_lms_parser_feed_should_give_the_same_events_byte_by_byte_as_whole(void)
{
    static uint8_t s[40000];
    static uint32_t intact[200];
    static run_log_t whole;
    static run_log_t bytes;
    static run_log_t random;
    size_t n_intact = 0;
    const size_t n = build_garbage_stream(s, sizeof s, 0xC0FFEEu, intact, &n_intact);
    size_t with_timeout;
    for (with_timeout = 0; with_timeout < 2; ++with_timeout) {
        run_parser(s, n, CHUNK_WHOLE, (int)with_timeout, &whole);
        run_parser(s, n, CHUNK_BYTES, (int)with_timeout, &bytes);
        run_parser(s, n, CHUNK_RANDOM, (int)with_timeout, &random);
        assert_logs_equal(&whole, &bytes);
        assert_logs_equal(&whole, &random);
        TEST_ASSERT_EQUAL_UINT32(n_intact, whole.st.telegrams_ok);
    }
}

void test_rsm_lms_parser_feed_should_handle_ack_and_telegram_in_one_chunk_after_garbage(void)
{
    /* garbage, ACK + 0x91 reply, then ACK + 0xA0 reply, in one chunk */
    uint8_t s[64];
    run_log_t log;
    size_t n = 0;
    static const uint8_t junk[5] = {0x00, 0xFF, 0x02, 0x7F, 0x33};
    memcpy(s + n, junk, sizeof junk);
    n += sizeof junk;
    memcpy(s + n, v_reset_reply_0x91, sizeof v_reset_reply_0x91);
    n += sizeof v_reset_reply_0x91;
    memcpy(s + n, v_ack_then_mode_response, sizeof v_ack_then_mode_response);
    n += sizeof v_ack_then_mode_response;
    run_parser(s, n, CHUNK_WHOLE, 0, &log);
    TEST_ASSERT_EQUAL_size_t(4, log.n);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_ACK, log.ev[0].type);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_TELEGRAM, log.ev[1].type);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_ACK, log.ev[2].type);
    TEST_ASSERT_EQUAL_INT(RSM_LMS_EVENT_TELEGRAM, log.ev[3].type);
    TEST_ASSERT_EQUAL_UINT32(5, log.st.bytes_skipped);
    TEST_ASSERT_EQUAL_UINT32(2, log.st.acks);
    TEST_ASSERT_EQUAL_UINT32(2, log.st.telegrams_ok);
    TEST_ASSERT_EQUAL_UINT32(0, log.st.naks);
    TEST_ASSERT_EQUAL_UINT32(0, log.st.crc_errors);
    TEST_ASSERT_EQUAL_UINT32(0, log.st.bad_length);
    TEST_ASSERT_EQUAL_UINT32(0, log.st.truncated);
}

/* ---- capacities: callers built with other capacities than the library ---------- */

void test_rsm_lms_parser_init_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* What rsm_lms_parser_init passes for an application compiled with
     * other capacities (RSM_LMS_MAX_TELEGRAM sizes the parser), or with
     * capacities that give the same size: refused, not one byte written. */
    static rsm_lms_parser_t p;
    static rsm_lms_parser_t before;
    memset(&p, 0x5A, sizeof p);
    memcpy(&before, &p, sizeof p);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_lms_parser_init_checked(&p, sizeof p - 8u,
                                                                      (unsigned long)RSM_CONFIG_FINGERPRINT));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_lms_parser_init_checked(&p, sizeof p,
                                                                      (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul));
    TEST_ASSERT_EQUAL_MEMORY(&before, &p, sizeof p);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_parser_init(&p));
}

void test_rsm_lms_decode_b0_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* RSM_MAX_BEAMS sizes the readings: another build's scan would get
     * them, and the header fields after them, past its end. */
    static rsm_lms_scan_t scan;
    static rsm_lms_scan_t before;
    const rsm_lms_telegram_t t = view_of(v_b0_short_cm, sizeof v_b0_short_cm);
    memset(&scan, 0x5A, sizeof scan);
    memcpy(&before, &scan, sizeof scan);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_lms_decode_b0_checked(&t, NULL, &scan, sizeof scan - 8u,
                                                                    (unsigned long)RSM_CONFIG_FINGERPRINT));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_lms_decode_b0_checked(&t, NULL, &scan, sizeof scan,
                                                                    (unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul));
    TEST_ASSERT_EQUAL_MEMORY(&before, &scan, sizeof scan);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_lms_decode_b0(&t, NULL, &scan));
    TEST_ASSERT_EQUAL_size_t(5u, scan.count);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_rsm_lms_crc_should_match_the_worked_example);
    RUN_TEST(test_rsm_lms_encode_request_status_should_reproduce_lms_status_request);
    RUN_TEST(test_rsm_lms_encode_request_scan_should_reproduce_lms_request_measured_values);
    RUN_TEST(test_rsm_lms_encode_mode_should_reproduce_lms_mode_continuous);
    RUN_TEST(test_rsm_lms_encode_mode_should_reproduce_lms_mode_stop);
    RUN_TEST(test_rsm_lms_encode_mode_installation_should_reproduce_lms_mode_installation);
    RUN_TEST(test_rsm_lms_encode_mode_baud_should_reproduce_lms_baud_38400);
    RUN_TEST(test_rsm_lms_encode_mode_baud_should_reproduce_lms_baud_19200);
    RUN_TEST(test_rsm_lms_encode_mode_baud_should_reproduce_lms_baud_9600);
    RUN_TEST(test_rsm_lms_encode_mode_baud_should_reproduce_lms_baud_500000);
    RUN_TEST(test_rsm_lms_encode_variant_should_reproduce_lms_variant_180deg_100cdeg);
    RUN_TEST(test_rsm_lms_encode_variant_should_reproduce_lms_variant_180deg_50cdeg);
    RUN_TEST(test_rsm_lms_encode_variant_should_reproduce_lms_variant_100deg_25cdeg);
    RUN_TEST(test_rsm_lms_encode_variant_should_reproduce_lms_variant_100deg_100cdeg);
    RUN_TEST(test_rsm_lms_encode_reset_should_reproduce_lms_reset);
    RUN_TEST(test_rsm_lms_encode_request_type_should_reproduce_lms_request_type);
    RUN_TEST(test_rsm_lms_encode_request_config_should_reproduce_lms_read_config);
    RUN_TEST(test_rsm_lms_parser_feed_should_decode_lms_ack_then_mode_response);
    RUN_TEST(test_rsm_lms_decode_mode_reply_should_decode_lms_mode_response_addr81);
    RUN_TEST(test_rsm_lms_decode_reset_reply_should_decode_lms_reset_reply_0x91);
    RUN_TEST(test_rsm_lms_decode_power_on_should_decode_lms_powerup_quick_manual);
    RUN_TEST(test_rsm_lms_decode_power_on_should_decode_lms_powerup_captured);
    RUN_TEST(test_rsm_lms_decode_b0_should_decode_lms_b0_short_cm);
    RUN_TEST(test_rsm_lms_decode_b0_should_decode_lms_b0_short_mm);
    RUN_TEST(test_rsm_lms_decode_variant_reply_should_decode_lms_bb_variant_ok);
    RUN_TEST(test_rsm_lms_decode_b0_should_decode_lms_b0_captured_361_mm);
    RUN_TEST(test_rsm_lms_encode_variant_should_reject_illegal_combinations);
    RUN_TEST(test_rsm_lms_encode_mode_should_reject_modes_that_need_parameters);
    RUN_TEST(test_rsm_lms_encode_mode_mean_should_encode_the_sample_count);
    RUN_TEST(test_rsm_lms_encode_mode_subrange_should_encode_first_and_last);
    RUN_TEST(test_rsm_lms_encode_should_reject_small_buffers_and_bad_arguments);
    RUN_TEST(test_rsm_lms_encode_should_accept_up_to_the_largest_legal_len);
    RUN_TEST(test_rsm_lms_decode_config_should_give_fields_and_write_back_changing_only_units);
    RUN_TEST(test_rsm_lms_encode_config_should_reject_unknown_codes);
    RUN_TEST(test_rsm_lms_decode_config_reply_should_give_result_and_echo);
    RUN_TEST(test_rsm_lms_b0_format_from_config_should_map_measuring_modes);
    RUN_TEST(test_rsm_lms_decode_not_ack_should_give_the_status);
    RUN_TEST(test_rsm_lms_decode_type_reply_should_copy_the_text);
    RUN_TEST(test_rsm_lms_decode_status_byte_should_split_the_actionable_bits);
    RUN_TEST(test_rsm_lms_decoders_should_reject_wrong_commands_and_lengths_untouched);
    RUN_TEST(test_rsm_lms_telegram_view_should_check_framing_and_crc);
    RUN_TEST(test_rsm_lms_decode_b0_should_reject_a_count_that_disagrees_with_len);
    RUN_TEST(test_rsm_lms_decode_b0_should_check_units);
    RUN_TEST(test_rsm_lms_decode_b0_should_map_every_error_code_to_invalid);
    RUN_TEST(test_rsm_lms_decode_b0_should_use_the_configured_distance_bits);
    RUN_TEST(test_rsm_lms_decode_b0_should_reject_more_readings_than_rsm_max_beams);
    RUN_TEST(test_rsm_lms_scan_angle_should_follow_the_variant_of_the_count);
    RUN_TEST(test_rsm_lms_scan_angle_should_refuse_unknown_geometry);
    RUN_TEST(test_rsm_lms_decode_b0_should_leave_partial_scans_without_angles);
    RUN_TEST(test_rsm_lms_parser_feed_should_report_a_nak);
    RUN_TEST(test_rsm_lms_parser_feed_should_not_see_ack_nak_or_stx_inside_a_telegram);
    RUN_TEST(test_rsm_lms_parser_feed_should_reject_invalid_arguments);
    RUN_TEST(test_rsm_lms_parser_flush_should_drop_held_bytes_as_skipped);
    RUN_TEST(test_rsm_lms_parser_feed_should_reject_len_0_max_plus_1_and_0xffff);
    RUN_TEST(test_rsm_lms_parser_feed_should_accept_len_1_and_the_largest_legal_len);
    RUN_TEST(test_rsm_lms_parser_feed_should_find_a_largest_telegram_inside_a_failed_candidate);
    RUN_TEST(test_rsm_lms_parser_feed_should_survive_every_bit_flip_of_a_b0_telegram);
    RUN_TEST(test_rsm_lms_parser_feed_should_survive_every_bit_flip_of_a_mode_reply);
    RUN_TEST(test_rsm_lms_parser_feed_should_recover_after_truncation_at_every_offset);
    RUN_TEST(test_rsm_lms_parser_timeout_should_abandon_a_truncated_telegram_at_every_offset);
    RUN_TEST(test_rsm_lms_parser_feed_should_lose_no_telegram_to_random_garbage);
    RUN_TEST(test_rsm_lms_parser_feed_should_give_the_same_events_byte_by_byte_as_whole);
    RUN_TEST(test_rsm_lms_parser_feed_should_handle_ack_and_telegram_in_one_chunk_after_garbage);
    RUN_TEST(test_rsm_lms_parser_init_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_rsm_lms_decode_b0_should_refuse_a_caller_built_with_other_capacities);
    return UNITY_END();
}
