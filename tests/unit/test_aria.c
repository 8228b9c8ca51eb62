/* Unit tests of the ARIA codec (rsm/aria.h).
 *
 * Every aria_* vector of tests/data/vectors.json is a test named
 * after it, with its bytes embedded below: encoders must reproduce the
 * host -> robot vectors byte for byte, decoders must recover every listed
 * field of the robot -> host vectors. The rest injects faults (garbage,
 * bit flips, truncation, bad byte counts) and checks exact counters,
 * partly against a tiny whole-stream reference model of the receiver
 * rules (ref_parse) that shares no code with the library. */
#include <string.h>

#include "rsm/aria.h"
#include "rsm/odometry.h"
#include "unity.h"

/* ---- reference vectors (vectors.json, bytes in wire order) ------------------ */

/* aria_sync0: 0x0000 */
static const uint8_t V_SYNC0[] = {0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00};
/* aria_sync1: 0x0001 */
static const uint8_t V_SYNC1[] = {0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01};
/* aria_sync2: 0x0002 */
static const uint8_t V_SYNC2[] = {0xFA, 0xFB, 0x03, 0x02, 0x00, 0x02};
/* aria_sync2_reply_example: 0x1382 */
static const uint8_t V_SYNC2_REPLY_EXAMPLE[] = {0xFA, 0xFB, 0x1A, 0x02, 0x52, 0x6F, 0x62, 0x6F, 0x74, 0x31, 0x00, 0x50, 0x69, 0x6F, 0x6E, 0x65, 0x65, 0x72, 0x00, 0x70, 0x33, 0x64, 0x78, 0x2D, 0x73, 0x68, 0x00, 0x13, 0x82};
/* aria_pulse: 0x0000 */
static const uint8_t V_PULSE[] = {0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00};
/* aria_open_int1: 0x023B */
static const uint8_t V_OPEN_INT1[] = {0xFA, 0xFB, 0x06, 0x01, 0x3B, 0x01, 0x00, 0x02, 0x3B};
/* aria_close_int1: 0x033B */
static const uint8_t V_CLOSE_INT1[] = {0xFA, 0xFB, 0x06, 0x02, 0x3B, 0x01, 0x00, 0x03, 0x3B};
/* aria_enable_1: 0x053B */
static const uint8_t V_ENABLE_1[] = {0xFA, 0xFB, 0x06, 0x04, 0x3B, 0x01, 0x00, 0x05, 0x3B};
/* aria_enable_0: 0x043B */
static const uint8_t V_ENABLE_0[] = {0xFA, 0xFB, 0x06, 0x04, 0x3B, 0x00, 0x00, 0x04, 0x3B};
/* aria_sonar_0: 0x1C3B */
static const uint8_t V_SONAR_0[] = {0xFA, 0xFB, 0x06, 0x1C, 0x3B, 0x00, 0x00, 0x1C, 0x3B};
/* aria_seta_1000: 0xED3E */
static const uint8_t V_SETA_1000[] = {0xFA, 0xFB, 0x06, 0x05, 0x3B, 0xE8, 0x03, 0xED, 0x3E};
/* aria_seta_neg1000: 0xED1E */
static const uint8_t V_SETA_NEG1000[] = {0xFA, 0xFB, 0x06, 0x05, 0x1B, 0xE8, 0x03, 0xED, 0x1E};
/* aria_seto: 0x0007 */
static const uint8_t V_SETO[] = {0xFA, 0xFB, 0x03, 0x07, 0x00, 0x07};
/* aria_encoder_on: 0x153B */
static const uint8_t V_ENCODER_ON[] = {0xFA, 0xFB, 0x06, 0x13, 0x3B, 0x02, 0x00, 0x15, 0x3B};
/* aria_encoder_once: 0x143B */
static const uint8_t V_ENCODER_ONCE[] = {0xFA, 0xFB, 0x06, 0x13, 0x3B, 0x01, 0x00, 0x14, 0x3B};
/* aria_encoder_off: 0x133B */
static const uint8_t V_ENCODER_OFF[] = {0xFA, 0xFB, 0x06, 0x13, 0x3B, 0x00, 0x00, 0x13, 0x3B};
/* aria_config_request: 0x133B */
static const uint8_t V_CONFIG_REQUEST[] = {0xFA, 0xFB, 0x06, 0x12, 0x3B, 0x01, 0x00, 0x13, 0x3B};
/* aria_vel_300: 0x373C */
static const uint8_t V_VEL_300[] = {0xFA, 0xFB, 0x06, 0x0B, 0x3B, 0x2C, 0x01, 0x37, 0x3C};
/* aria_vel_neg300: 0x371C */
static const uint8_t V_VEL_NEG300[] = {0xFA, 0xFB, 0x06, 0x0B, 0x1B, 0x2C, 0x01, 0x37, 0x1C};
/* aria_rvel_neg30: 0x331B */
static const uint8_t V_RVEL_NEG30[] = {0xFA, 0xFB, 0x06, 0x15, 0x1B, 0x1E, 0x00, 0x33, 0x1B};
/* aria_rotate_15: 0x183B */
static const uint8_t V_ROTATE_15[] = {0xFA, 0xFB, 0x06, 0x09, 0x3B, 0x0F, 0x00, 0x18, 0x3B};
/* aria_head_90: 0x663B */
static const uint8_t V_HEAD_90[] = {0xFA, 0xFB, 0x06, 0x0C, 0x3B, 0x5A, 0x00, 0x66, 0x3B};
/* aria_dhead_neg45: 0x3A1B */
static const uint8_t V_DHEAD_NEG45[] = {0xFA, 0xFB, 0x06, 0x0D, 0x1B, 0x2D, 0x00, 0x3A, 0x1B};
/* aria_move_500: 0xFC3C */
static const uint8_t V_MOVE_500[] = {0xFA, 0xFB, 0x06, 0x08, 0x3B, 0xF4, 0x01, 0xFC, 0x3C};
/* aria_stop: 0x001D */
static const uint8_t V_STOP[] = {0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1D};
/* aria_estop: 0x0037 */
static const uint8_t V_ESTOP[] = {0xFA, 0xFB, 0x03, 0x37, 0x00, 0x37};
/* aria_hostbaud_38400: 0x343B */
static const uint8_t V_HOSTBAUD_38400[] = {0xFA, 0xFB, 0x06, 0x32, 0x3B, 0x02, 0x00, 0x34, 0x3B};
/* aria_vel2_left+100_right-100: 0x1B40 */
static const uint8_t V_VEL2_LEFT_PLUS100_RIGHT_MINUS100[] = {0xFA, 0xFB, 0x06, 0x20, 0x3B, 0xFB, 0x05, 0x1B, 0x40};
/* aria_vel2_left-100_right+100: 0x1B1F */
static const uint8_t V_VEL2_LEFT_MINUS100_RIGHT_PLUS100[] = {0xFA, 0xFB, 0x06, 0x20, 0x1B, 0xFB, 0x04, 0x1B, 0x1F};
/* aria_str_tty2_AB: 0x6E6C */
static const uint8_t V_STR_TTY2_AB[] = {0xFA, 0xFB, 0x08, 0x2A, 0x2B, 0x02, 0x41, 0x42, 0x00, 0x6E, 0x6C};
/* aria_sip_stopped_2sonar: 0x5285 */
static const uint8_t V_SIP_STOPPED_2SONAR[] = {0xFA, 0xFB, 0x28, 0x32, 0xE8, 0x03, 0xBC, 0x7F, 0x00, 0x04, 0x64, 0x00, 0x78, 0x00, 0x7D, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x02, 0x00, 0xF4, 0x01, 0x03, 0x88, 0x13, 0x00, 0x00, 0x00, 0xFF, 0x00, 0x7D, 0x00, 0x00, 0x0B, 0x00, 0x00, 0x00, 0x52, 0x85};
/* aria_sip_moving_wrapped: 0x397E */
static const uint8_t V_SIP_MOVING_WRAPPED[] = {0xFA, 0xFB, 0x22, 0x33, 0x0A, 0x00, 0x05, 0x00, 0x00, 0xFC, 0x38, 0xFF, 0x4C, 0xFF, 0x76, 0x01, 0x01, 0x00, 0x00, 0x21, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xFF, 0x00, 0x76, 0x00, 0x00, 0xE7, 0xFF, 0x00, 0x00, 0x39, 0x7E};
/* aria_encoder_packet: 0x77B9 */
static const uint8_t V_ENCODER_PACKET[] = {0xFA, 0xFB, 0x0B, 0x90, 0x40, 0xE2, 0x01, 0x00, 0x0F, 0x04, 0xF6, 0xFF, 0x77, 0xB9};
/* aria_encoder_packet_wrapped: 0x117C */
static const uint8_t V_ENCODER_PACKET_WRAPPED[] = {0xFA, 0xFB, 0x0B, 0x90, 0x34, 0x00, 0x00, 0x80, 0xD0, 0xFF, 0xFF, 0x7F, 0x11, 0x7C};

#define N_OF(a) (sizeof(a) / sizeof((a)[0]))

/* ---- helpers ------------------------------------------------------------------- */

static rsm_aria_parser_t parser;

void setUp(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&parser));
}

void tearDown(void)
{
}

/* Checksum written out from the protocol text, independent of the library. */
static uint16_t ref_checksum(const uint8_t *body, size_t len)
{
    uint32_t sum = 0u;
    size_t i;
    for (i = 0u; i + 1u < len; i += 2u) {
        sum = (sum + (uint32_t)body[i] * 256u + (uint32_t)body[i + 1u]) & 0xFFFFu;
    }
    if ((len & 1u) != 0u) {
        sum ^= (uint32_t)body[len - 1u];
    }
    return (uint16_t)sum;
}

/* Checks an encoder result against a request vector: byte count, bytes,
 * the vector's checksum, and that the frame parses back to one packet. */
static void check_request(const uint8_t *expect, size_t n, int got, const uint8_t *buf, uint8_t cmd,
                          uint16_t checksum)
{
    rsm_aria_parser_t p;
    rsm_aria_packet_t pkt;
    size_t used = 0u;

    TEST_ASSERT_EQUAL_INT((int)n, got);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, buf, n);
    TEST_ASSERT_EQUAL_HEX16(checksum, rsm_aria_checksum(expect + 3, n - 5u));
    TEST_ASSERT_EQUAL_HEX16(checksum, ref_checksum(expect + 3, n - 5u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&p));
    TEST_ASSERT_EQUAL_INT(1, rsm_aria_parser_feed(&p, buf, n, &used, &pkt));
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n, (uint32_t)used);
    TEST_ASSERT_EQUAL_UINT8(cmd, pkt.id);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)(n - 6u), (uint32_t)pkt.payload_len);
}

/* Feeds one whole frame and expects exactly that frame back. */
static void feed_one(const uint8_t *frame, size_t n, rsm_aria_packet_t *pkt)
{
    rsm_aria_parser_t p;
    size_t used = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&p));
    TEST_ASSERT_EQUAL_INT(1, rsm_aria_parser_feed(&p, frame, n, &used, pkt));
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n, (uint32_t)used);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n, (uint32_t)pkt->frame_len);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(frame, pkt->frame, n);
    TEST_ASSERT_EQUAL_UINT32(1u, p.stats.packets_ok);
}

static void expect_stats(uint32_t skipped, uint32_t cks, uint32_t bad, uint32_t ok, uint32_t trunc,
                         const rsm_aria_parser_stats_t *s)
{
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(skipped, s->bytes_skipped, "bytes_skipped");
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(cks, s->checksum_errors, "checksum_errors");
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(bad, s->bad_length, "bad_length");
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(ok, s->packets_ok, "packets_ok");
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(trunc, s->truncated, "truncated");
}

/* Deterministic PRNG for the fault-injection tests (xorshift32). */
static uint32_t prng_next(uint32_t *state)
{
    uint32_t x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *state = x;
    return x;
}

/* A garbage byte, biased towards the sync bytes to provoke false headers. */
static uint8_t garbage_byte(uint32_t *state)
{
    uint32_t r = prng_next(state);
    switch (r & 7u) {
    case 0u:
    case 1u: return 0xFAu;
    case 2u: return 0xFBu;
    default: return (uint8_t)(r >> 8);
    }
}

/* ---- reference model -------------------------------------------------------------
 * The receiver rules applied to a whole stream that ends with a line
 * timeout: at each position either a verified frame (skip it), or the byte
 * is passed over and the next position examined. */

#define REF_MAX_PACKETS 512u

typedef struct ref_result {
    rsm_aria_parser_stats_t stats;
    size_t n_packets;
    size_t start[REF_MAX_PACKETS];
    size_t len[REF_MAX_PACKETS];
} ref_result_t;

static void ref_parse(const uint8_t *s, size_t n, ref_result_t *r)
{
    size_t pos = 0u;
    memset(r, 0, sizeof(*r));
    while (pos < n) {
        size_t need;
        if (s[pos] != 0xFAu || pos + 1u >= n || s[pos + 1u] != 0xFBu) {
            r->stats.bytes_skipped++;
        } else if (pos + 2u >= n) {
            r->stats.truncated++;
        } else if (s[pos + 2u] < 3u) {
            r->stats.bad_length++;
        } else if (pos + (need = (size_t)s[pos + 2u] + 3u) > n) {
            r->stats.truncated++;
        } else if (ref_checksum(s + pos + 3u, need - 5u) !=
                   (uint16_t)((uint32_t)s[pos + need - 2u] * 256u + s[pos + need - 1u])) {
            r->stats.checksum_errors++;
        } else {
            TEST_ASSERT_TRUE(r->n_packets < REF_MAX_PACKETS);
            r->start[r->n_packets] = pos;
            r->len[r->n_packets] = need;
            r->n_packets++;
            r->stats.packets_ok++;
            pos += need;
            continue;
        }
        pos++;
    }
}

/* Streams s through the library parser in chunks of `chunk` bytes (0: all
 * at once), then signals a timeout and drains; every published packet and
 * every counter must equal the reference model's. */
static void run_against_ref(const uint8_t *s, size_t n, size_t chunk, const ref_result_t *ref)
{
    rsm_aria_parser_t p;
    rsm_aria_packet_t pkt;
    size_t off = 0u;
    size_t k = 0u;
    int r;

    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&p));
    for (;;) {
        size_t len = (chunk == 0u || n - off < chunk) ? n - off : chunk;
        size_t used = 0u;
        r = rsm_aria_parser_feed(&p, s + off, len, &used, &pkt);
        TEST_ASSERT_TRUE(r == 0 || r == 1);
        TEST_ASSERT_TRUE(used <= len);
        off += used;
        if (r == 1) {
            TEST_ASSERT_TRUE(k < ref->n_packets);
            TEST_ASSERT_EQUAL_UINT32((uint32_t)ref->len[k], (uint32_t)pkt.frame_len);
            TEST_ASSERT_EQUAL_MEMORY(s + ref->start[k], pkt.frame, ref->len[k]);
            k++;
            continue;
        }
        TEST_ASSERT_EQUAL_UINT32((uint32_t)len, (uint32_t)used);
        if (off == n) {
            break;
        }
    }
    (void)rsm_aria_parser_timeout(&p);
    for (;;) {
        size_t used = 1u;
        r = rsm_aria_parser_feed(&p, NULL, 0u, &used, &pkt);
        TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)used);
        if (r != 1) {
            break;
        }
        TEST_ASSERT_TRUE(k < ref->n_packets);
        TEST_ASSERT_EQUAL_UINT32((uint32_t)ref->len[k], (uint32_t)pkt.frame_len);
        TEST_ASSERT_EQUAL_MEMORY(s + ref->start[k], pkt.frame, ref->len[k]);
        k++;
    }
    TEST_ASSERT_EQUAL_INT(0, r);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)ref->n_packets, (uint32_t)k);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rsm_aria_parser_pending(&p));
    expect_stats(ref->stats.bytes_skipped, ref->stats.checksum_errors, ref->stats.bad_length,
                 ref->stats.packets_ok, ref->stats.truncated, &p.stats);
}

/* Appends n bytes to a stream buffer. */
static void put(uint8_t *s, size_t cap, size_t *len, const uint8_t *src, size_t n)
{
    TEST_ASSERT_TRUE(*len + n <= cap);
    memcpy(s + *len, src, n);
    *len += n;
}

/* ---- checksum ------------------------------------------------------------------- */

void test_checksum_should_match_protocol_worked_examples(void)
{
    static const uint8_t sync1[] = {0x01};
    static const uint8_t enable1[] = {0x04, 0x3B, 0x01, 0x00};
    static const uint8_t seta_neg[] = {0x05, 0x1B, 0xE8, 0x03};
    static const uint8_t tty2[] = {0x2A, 0x2B, 0x02, 0x41, 0x42, 0x00};
    static const uint8_t two[] = {0x07, 0x3B};
    static const uint8_t wrap[] = {0xFF, 0xFF, 0x00, 0x02};

    TEST_ASSERT_EQUAL_HEX16(0x0000u, rsm_aria_checksum(NULL, 0u));
    TEST_ASSERT_EQUAL_HEX16(0x0001u, rsm_aria_checksum(sync1, sizeof(sync1)));
    TEST_ASSERT_EQUAL_HEX16(0x053Bu, rsm_aria_checksum(enable1, sizeof(enable1)));
    TEST_ASSERT_EQUAL_HEX16(0xED1Eu, rsm_aria_checksum(seta_neg, sizeof(seta_neg)));
    TEST_ASSERT_EQUAL_HEX16(0x6E6Cu, rsm_aria_checksum(tty2, sizeof(tty2)));
    TEST_ASSERT_EQUAL_HEX16(0x073Bu, rsm_aria_checksum(two, sizeof(two)));
    /* 0xFFFF + 0x0002 overflows and keeps the low 16 bits. */
    TEST_ASSERT_EQUAL_HEX16(0x0001u, rsm_aria_checksum(wrap, sizeof(wrap)));
}

/* ---- request vectors (host -> robot) ----------------------------------------------- */

void test_encode_sync0_should_match_aria_sync0(void)
{
    uint8_t buf[16];
    check_request(V_SYNC0, sizeof(V_SYNC0), rsm_aria_encode_sync0(buf, sizeof(buf)), buf, 0u, 0x0000u);
}

void test_encode_sync1_should_match_aria_sync1(void)
{
    uint8_t buf[16];
    check_request(V_SYNC1, sizeof(V_SYNC1), rsm_aria_encode_sync1(buf, sizeof(buf)), buf, 1u, 0x0001u);
    /* The bare OPEN is the same packet. */
    check_request(V_SYNC1, sizeof(V_SYNC1), rsm_aria_encode_open(buf, sizeof(buf)), buf, 1u, 0x0001u);
}

void test_encode_sync2_should_match_aria_sync2(void)
{
    uint8_t buf[16];
    check_request(V_SYNC2, sizeof(V_SYNC2), rsm_aria_encode_sync2(buf, sizeof(buf)), buf, 2u, 0x0002u);
    /* The bare CLOSE is the same packet. */
    check_request(V_SYNC2, sizeof(V_SYNC2), rsm_aria_encode_close(buf, sizeof(buf)), buf, 2u, 0x0002u);
}

void test_encode_pulse_should_match_aria_pulse(void)
{
    uint8_t buf[16];
    check_request(V_PULSE, sizeof(V_PULSE), rsm_aria_encode_pulse(buf, sizeof(buf)), buf, 0u, 0x0000u);
    check_request(V_PULSE, sizeof(V_PULSE),
                  rsm_aria_encode((uint8_t)RSM_ARIA_CMD_PULSE, RSM_ARIA_ARG_NONE, 0, NULL, 0u, buf,
                                  sizeof(buf)),
                  buf, 0u, 0x0000u);
}

void test_encode_open_int1_should_match_aria_open_int1(void)
{
    uint8_t buf[16];
    check_request(V_OPEN_INT1, sizeof(V_OPEN_INT1), rsm_aria_encode_open_int1(buf, sizeof(buf)), buf,
                  1u, 0x023Bu);
}

void test_encode_close_int1_should_match_aria_close_int1(void)
{
    uint8_t buf[16];
    check_request(V_CLOSE_INT1, sizeof(V_CLOSE_INT1), rsm_aria_encode_close_int1(buf, sizeof(buf)),
                  buf, 2u, 0x033Bu);
}

void test_encode_enable_should_match_aria_enable_1(void)
{
    uint8_t buf[16];
    check_request(V_ENABLE_1, sizeof(V_ENABLE_1), rsm_aria_encode_enable(1, buf, sizeof(buf)), buf, 4u,
                  0x053Bu);
    /* Any non-zero switch value means on. */
    check_request(V_ENABLE_1, sizeof(V_ENABLE_1), rsm_aria_encode_enable(7, buf, sizeof(buf)), buf, 4u,
                  0x053Bu);
}

void test_encode_enable_should_match_aria_enable_0(void)
{
    uint8_t buf[16];
    check_request(V_ENABLE_0, sizeof(V_ENABLE_0), rsm_aria_encode_enable(0, buf, sizeof(buf)), buf, 4u,
                  0x043Bu);
}

void test_encode_sonar_should_match_aria_sonar_0(void)
{
    uint8_t buf[16];
    check_request(V_SONAR_0, sizeof(V_SONAR_0), rsm_aria_encode_sonar(0, buf, sizeof(buf)), buf, 28u,
                  0x1C3Bu);
}

void test_encode_seta_should_match_aria_seta_1000(void)
{
    uint8_t buf[16];
    check_request(V_SETA_1000, sizeof(V_SETA_1000), rsm_aria_encode_seta(1000, buf, sizeof(buf)), buf,
                  5u, 0xED3Eu);
}

void test_encode_seta_should_match_aria_seta_neg1000(void)
{
    uint8_t buf[16];
    check_request(V_SETA_NEG1000, sizeof(V_SETA_NEG1000), rsm_aria_encode_seta(-1000, buf, sizeof(buf)),
                  buf, 5u, 0xED1Eu);
    TEST_ASSERT_EQUAL_HEX8(RSM_ARIA_ARGTYPE_NINT, buf[4]);
}

void test_encode_seto_should_match_aria_seto(void)
{
    uint8_t buf[16];
    check_request(V_SETO, sizeof(V_SETO), rsm_aria_encode_seto(buf, sizeof(buf)), buf, 7u, 0x0007u);
}

void test_encode_encoder_should_match_aria_encoder_on(void)
{
    uint8_t buf[16];
    check_request(V_ENCODER_ON, sizeof(V_ENCODER_ON), rsm_aria_encode_encoder(1, buf, sizeof(buf)), buf,
                  19u, 0x153Bu);
}

void test_encode_int_should_match_aria_encoder_once(void)
{
    uint8_t buf[16];
    check_request(V_ENCODER_ONCE, sizeof(V_ENCODER_ONCE),
                  rsm_aria_encode_int((uint8_t)RSM_ARIA_CMD_ENCODER, 1, buf, sizeof(buf)), buf, 19u,
                  0x143Bu);
}

void test_encode_encoder_should_match_aria_encoder_off(void)
{
    uint8_t buf[16];
    check_request(V_ENCODER_OFF, sizeof(V_ENCODER_OFF), rsm_aria_encode_encoder(0, buf, sizeof(buf)),
                  buf, 19u, 0x133Bu);
}

void test_encode_config_should_match_aria_config_request(void)
{
    uint8_t buf[16];
    check_request(V_CONFIG_REQUEST, sizeof(V_CONFIG_REQUEST), rsm_aria_encode_config(buf, sizeof(buf)),
                  buf, 18u, 0x133Bu);
}

void test_encode_vel_should_match_aria_vel_300(void)
{
    uint8_t buf[16];
    check_request(V_VEL_300, sizeof(V_VEL_300), rsm_aria_encode_vel(300, buf, sizeof(buf)), buf, 11u,
                  0x373Cu);
}

void test_encode_vel_should_match_aria_vel_neg300(void)
{
    uint8_t buf[16];
    check_request(V_VEL_NEG300, sizeof(V_VEL_NEG300), rsm_aria_encode_vel(-300, buf, sizeof(buf)), buf,
                  11u, 0x371Cu);
}

void test_encode_rvel_should_match_aria_rvel_neg30(void)
{
    uint8_t buf[16];
    check_request(V_RVEL_NEG30, sizeof(V_RVEL_NEG30), rsm_aria_encode_rvel(-30, buf, sizeof(buf)), buf,
                  21u, 0x331Bu);
}

void test_encode_rotate_should_match_aria_rotate_15(void)
{
    uint8_t buf[16];
    check_request(V_ROTATE_15, sizeof(V_ROTATE_15), rsm_aria_encode_rotate(15, buf, sizeof(buf)), buf,
                  9u, 0x183Bu);
}

void test_encode_head_should_match_aria_head_90(void)
{
    uint8_t buf[16];
    check_request(V_HEAD_90, sizeof(V_HEAD_90), rsm_aria_encode_head(90, buf, sizeof(buf)), buf, 12u,
                  0x663Bu);
}

void test_encode_dhead_should_match_aria_dhead_neg45(void)
{
    uint8_t buf[16];
    check_request(V_DHEAD_NEG45, sizeof(V_DHEAD_NEG45), rsm_aria_encode_dhead(-45, buf, sizeof(buf)),
                  buf, 13u, 0x3A1Bu);
}

void test_encode_move_should_match_aria_move_500(void)
{
    uint8_t buf[16];
    check_request(V_MOVE_500, sizeof(V_MOVE_500), rsm_aria_encode_move(500, buf, sizeof(buf)), buf, 8u,
                  0xFC3Cu);
}

void test_encode_stop_should_match_aria_stop(void)
{
    uint8_t buf[16];
    check_request(V_STOP, sizeof(V_STOP), rsm_aria_encode_stop(buf, sizeof(buf)), buf, 29u, 0x001Du);
}

void test_encode_estop_should_match_aria_estop(void)
{
    uint8_t buf[16];
    check_request(V_ESTOP, sizeof(V_ESTOP), rsm_aria_encode_estop(buf, sizeof(buf)), buf, 55u, 0x0037u);
}

void test_encode_hostbaud_should_match_aria_hostbaud_38400(void)
{
    uint8_t buf[16];
    int code = rsm_aria_baud_code(38400u);
    TEST_ASSERT_EQUAL_INT(2, code);
    check_request(V_HOSTBAUD_38400, sizeof(V_HOSTBAUD_38400),
                  rsm_aria_encode_hostbaud((uint8_t)code, buf, sizeof(buf)), buf, 50u, 0x343Bu);
}

void test_encode_vel2_should_match_aria_vel2_left_plus100_right_minus100(void)
{
    uint8_t buf[16];
    /* +100 / -100 mm/s at Vel2Divisor 20: +5 / -5 units, word 0x05FB. */
    check_request(V_VEL2_LEFT_PLUS100_RIGHT_MINUS100, sizeof(V_VEL2_LEFT_PLUS100_RIGHT_MINUS100),
                  rsm_aria_encode_vel2(5, -5, buf, sizeof(buf)), buf, 32u, 0x1B40u);
    TEST_ASSERT_EQUAL_HEX8(RSM_ARIA_ARGTYPE_INT, buf[4]);
}

void test_encode_vel2_should_match_aria_vel2_left_minus100_right_plus100(void)
{
    uint8_t buf[16];
    /* Word 0xFB05 = -1275 as s16: NINTARG, magnitude 1275 = 0x04FB. */
    check_request(V_VEL2_LEFT_MINUS100_RIGHT_PLUS100, sizeof(V_VEL2_LEFT_MINUS100_RIGHT_PLUS100),
                  rsm_aria_encode_vel2(-5, 5, buf, sizeof(buf)), buf, 32u, 0x1B1Fu);
    TEST_ASSERT_EQUAL_HEX8(RSM_ARIA_ARGTYPE_NINT, buf[4]);
}

void test_encode_tty2_should_match_aria_str_tty2_AB(void)
{
    uint8_t buf[16];
    check_request(V_STR_TTY2_AB, sizeof(V_STR_TTY2_AB), rsm_aria_encode_tty2("AB", 2u, buf, sizeof(buf)),
                  buf, 42u, 0x6E6Cu);
    /* Length byte 2 does not count the trailing NUL. */
    TEST_ASSERT_EQUAL_HEX8(0x02u, buf[5]);
    TEST_ASSERT_EQUAL_HEX8(0x00u, buf[8]);
}

/* ---- response vectors (robot -> host) --------------------------------------------- */

void test_decode_sync_should_recognise_aria_sync0_sync1_sync2_echoes(void)
{
    rsm_aria_packet_t pkt;
    feed_one(V_SYNC0, sizeof(V_SYNC0), &pkt);
    TEST_ASSERT_EQUAL_INT(0, rsm_aria_decode_sync(&pkt));
    feed_one(V_SYNC1, sizeof(V_SYNC1), &pkt);
    TEST_ASSERT_EQUAL_INT(1, rsm_aria_decode_sync(&pkt));
    feed_one(V_SYNC2, sizeof(V_SYNC2), &pkt);
    TEST_ASSERT_EQUAL_INT(2, rsm_aria_decode_sync(&pkt));
    /* A SIP during the handshake is not a SYNC reply. */
    feed_one(V_SIP_STOPPED_2SONAR, sizeof(V_SIP_STOPPED_2SONAR), &pkt);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_sync(&pkt));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_sync(NULL));
}

void test_decode_sync2_should_recover_aria_sync2_reply_example(void)
{
    rsm_aria_packet_t pkt;
    rsm_aria_sync2_t s;

    feed_one(V_SYNC2_REPLY_EXAMPLE, sizeof(V_SYNC2_REPLY_EXAMPLE), &pkt);
    TEST_ASSERT_EQUAL_HEX16(0x1382u, rsm_aria_checksum(pkt.frame + 3, pkt.frame_len - 5u));
    TEST_ASSERT_EQUAL_INT(2, rsm_aria_decode_sync(&pkt));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sync2(&pkt, &s));
    TEST_ASSERT_EQUAL_STRING("Robot1", s.name);
    TEST_ASSERT_EQUAL_STRING("Pioneer", s.robot_class);
    TEST_ASSERT_EQUAL_STRING("p3dx-sh", s.subclass);
    TEST_ASSERT_EQUAL_UINT8(3u, s.present);
    TEST_ASSERT_EQUAL_UINT8(0u, s.truncated);
}

void test_decode_sip_should_recover_aria_sip_stopped_2sonar(void)
{
    rsm_aria_packet_t pkt;
    rsm_aria_sip_t s;

    feed_one(V_SIP_STOPPED_2SONAR, sizeof(V_SIP_STOPPED_2SONAR), &pkt);
    TEST_ASSERT_EQUAL_HEX16(0x5285u, rsm_aria_checksum(pkt.frame + 3, pkt.frame_len - 5u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkt, &s));
    TEST_ASSERT_EQUAL_HEX8(0x32u, s.type);
    TEST_ASSERT_EQUAL_UINT16(1000u, s.xpos);
    TEST_ASSERT_EQUAL_UINT16(32700u, s.ypos);
    TEST_ASSERT_EQUAL_INT16(1024, s.thpos);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 1.5707963f, rsm_aria_th_to_rad(s.thpos)); /* 90 deg */
    TEST_ASSERT_EQUAL_INT16(100, s.l_vel);
    TEST_ASSERT_EQUAL_INT16(120, s.r_vel);
    TEST_ASSERT_EQUAL_UINT8(125u, s.battery);
    TEST_ASSERT_EQUAL_HEX16(0x0000u, s.stall_and_bumpers);
    TEST_ASSERT_EQUAL_INT16(0, s.control);
    TEST_ASSERT_EQUAL_HEX16(0x0001u, s.flags);
    TEST_ASSERT_TRUE((s.flags & RSM_ARIA_FLAGS_MOTORS_ENABLED) != 0u);
    TEST_ASSERT_EQUAL_UINT8(0u, s.compass);
    TEST_ASSERT_EQUAL_UINT8(2u, s.sonar_count);
    TEST_ASSERT_EQUAL_UINT32(2u, (uint32_t)s.sonar_len);
    TEST_ASSERT_EQUAL_UINT8(0u, s.sonar[0].num);
    TEST_ASSERT_EQUAL_UINT16(500u, s.sonar[0].range);
    TEST_ASSERT_EQUAL_UINT8(3u, s.sonar[1].num);
    TEST_ASSERT_EQUAL_UINT16(5000u, s.sonar[1].range);
    TEST_ASSERT_EQUAL_UINT8(0u, s.grip_state);
    TEST_ASSERT_EQUAL_UINT8(0u, s.anport);
    TEST_ASSERT_EQUAL_UINT8(0u, s.analog);
    TEST_ASSERT_EQUAL_HEX8(0xFFu, s.digin);
    TEST_ASSERT_EQUAL_HEX8(0x00u, s.digout);
    TEST_ASSERT_EQUAL_UINT16(125u, s.battery_x10);
    TEST_ASSERT_EQUAL_UINT8(0u, s.charge_state);
    TEST_ASSERT_EQUAL_INT16(11, s.rot_vel); /* 1.1 deg/s */
    TEST_ASSERT_EQUAL_HEX16(0x0000u, s.fault_flags);
    TEST_ASSERT_EQUAL_HEX32(0x01FFu, s.present); /* through FAULTFLAGS, no tail */
}

void test_decode_sip_should_recover_aria_sip_moving_wrapped(void)
{
    rsm_aria_packet_t pkt;
    rsm_aria_sip_t s;

    feed_one(V_SIP_MOVING_WRAPPED, sizeof(V_SIP_MOVING_WRAPPED), &pkt);
    TEST_ASSERT_EQUAL_HEX16(0x397Eu, rsm_aria_checksum(pkt.frame + 3, pkt.frame_len - 5u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkt, &s));
    TEST_ASSERT_EQUAL_HEX8(0x33u, s.type);
    TEST_ASSERT_EQUAL_UINT16(10u, s.xpos);
    TEST_ASSERT_EQUAL_INT16(18, rsm_aria_pos_delta15(s.xpos, 32760u)); /* previous 32760 */
    TEST_ASSERT_EQUAL_UINT16(5u, s.ypos);
    TEST_ASSERT_EQUAL_INT16(-1024, s.thpos);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, -1.5707963f, rsm_aria_th_to_rad(s.thpos)); /* -90 deg */
    TEST_ASSERT_EQUAL_INT16(-200, s.l_vel);
    TEST_ASSERT_EQUAL_INT16(-180, s.r_vel);
    TEST_ASSERT_EQUAL_UINT8(118u, s.battery);
    TEST_ASSERT_EQUAL_HEX16(0x0101u, s.stall_and_bumpers);
    TEST_ASSERT_TRUE((s.stall_and_bumpers & RSM_ARIA_STALL_LEFT) != 0u);
    TEST_ASSERT_TRUE((s.stall_and_bumpers & RSM_ARIA_STALL_RIGHT) != 0u);
    TEST_ASSERT_EQUAL_HEX16(0x0021u, s.flags);
    TEST_ASSERT_TRUE((s.flags & RSM_ARIA_FLAGS_MOTORS_ENABLED) != 0u);
    TEST_ASSERT_TRUE((s.flags & RSM_ARIA_FLAGS_ESTOP) != 0u);
    TEST_ASSERT_EQUAL_UINT8(0u, s.sonar_count);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)s.sonar_len);
    TEST_ASSERT_EQUAL_HEX8(0xFFu, s.digin);
    TEST_ASSERT_EQUAL_UINT16(118u, s.battery_x10);
    TEST_ASSERT_EQUAL_INT16(-25, s.rot_vel); /* -2.5 deg/s */
    TEST_ASSERT_EQUAL_HEX16(0x0000u, s.fault_flags);
    TEST_ASSERT_EQUAL_HEX32(0x01FFu, s.present);
}

void test_decode_encoder_should_recover_aria_encoder_packet(void)
{
    rsm_aria_packet_t pkt;
    rsm_aria_encoder_t e;

    feed_one(V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET), &pkt);
    TEST_ASSERT_EQUAL_HEX16(0x77B9u, rsm_aria_checksum(pkt.frame + 3, pkt.frame_len - 5u));
    TEST_ASSERT_EQUAL_HEX8(0x90u, pkt.id);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_encoder(&pkt, &e));
    TEST_ASSERT_EQUAL_INT32(123456, e.left);
    TEST_ASSERT_EQUAL_INT32(-654321, e.right);
}

void test_decode_encoder_should_recover_aria_encoder_packet_wrapped(void)
{
    rsm_aria_packet_t pkt;
    rsm_aria_encoder_t e;

    feed_one(V_ENCODER_PACKET_WRAPPED, sizeof(V_ENCODER_PACKET_WRAPPED), &pkt);
    TEST_ASSERT_EQUAL_HEX16(0x117Cu, rsm_aria_checksum(pkt.frame + 3, pkt.frame_len - 5u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_encoder(&pkt, &e));
    TEST_ASSERT_EQUAL_INT32(-2147483596, e.left);
    TEST_ASSERT_EQUAL_INT32(2147483600, e.right);
    TEST_ASSERT_EQUAL_INT32(100, rsm_odometry_count_delta((uint32_t)(e.left), (uint32_t)(2147483600), 32u));
    TEST_ASSERT_EQUAL_INT32(-100, rsm_odometry_count_delta((uint32_t)(e.right), (uint32_t)(-2147483596), 32u));
}

/* ---- encoder errors and limits --------------------------------------------------------- */

void test_encode_int_should_reject_magnitudes_above_32767(void)
{
    static const uint8_t vel_max[] = {0xFA, 0xFB, 0x06, 0x0B, 0x3B, 0xFF, 0x7F, 0x0A, 0xBA};
    static const uint8_t vel_min[] = {0xFA, 0xFB, 0x06, 0x0B, 0x1B, 0xFF, 0x7F, 0x0A, 0x9A};
    uint8_t buf[16];
    uint8_t before[16];

    memset(buf, 0xA5, sizeof(buf));
    memcpy(before, buf, sizeof(buf));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_vel(32768, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_vel(-32768, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_int(11u, INT32_MIN, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_int(11u, INT32_MAX, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_MEMORY(before, buf, sizeof(buf));
    check_request(vel_max, sizeof(vel_max), rsm_aria_encode_vel(32767, buf, sizeof(buf)), buf, 11u,
                  0x0ABAu);
    check_request(vel_min, sizeof(vel_min), rsm_aria_encode_vel(-32767, buf, sizeof(buf)), buf, 11u,
                  0x0A9Au);
}

void test_encode_should_leave_buffer_untouched_when_capacity_is_short(void)
{
    uint8_t buf[16];
    uint8_t before[16];

    memset(buf, 0x5A, sizeof(buf));
    memcpy(before, buf, sizeof(buf));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_aria_encode_enable(1, buf, 8u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_aria_encode_stop(buf, 5u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_aria_encode_sync0(buf, 0u));
    TEST_ASSERT_EQUAL_MEMORY(before, buf, sizeof(buf));
    /* Exactly enough is enough. */
    TEST_ASSERT_EQUAL_INT(9, rsm_aria_encode_enable(1, buf, 9u));
    TEST_ASSERT_EQUAL_INT(6, rsm_aria_encode_stop(buf, 6u));
}

void test_encode_tty2_should_fail_with_nomem_when_string_is_too_long_for_buffer(void)
{
    uint8_t buf[64];
    uint8_t before[64];
    char text[40];

    memset(text, 'x', sizeof(text));
    memset(buf, 0x77, sizeof(buf));
    memcpy(before, buf, sizeof(buf));
    /* "AB" needs 11 bytes. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_aria_encode_tty2("AB", 2u, buf, 10u));
    /* 40 characters need 49 bytes. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_aria_encode_tty2(text, sizeof(text), buf, 48u));
    TEST_ASSERT_EQUAL_MEMORY(before, buf, sizeof(buf));
    TEST_ASSERT_EQUAL_INT(49, rsm_aria_encode_tty2(text, sizeof(text), buf, 49u));
    TEST_ASSERT_EQUAL_HEX8(40u, buf[5]);
    TEST_ASSERT_EQUAL_HEX8(0x00u, buf[46]);
}

void test_encode_str_should_reject_strings_longer_than_the_payload_limit(void)
{
    uint8_t buf[RSM_ARIA_MAX_PACKET];
    char text[RSM_ARIA_MAX_STR_ARG + 1u];
    rsm_aria_packet_t pkt;

    memset(text, 'q', sizeof(text));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_str(42u, text, sizeof(text), buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT((int)RSM_ARIA_MAX_STR_ARG + 9,
                          rsm_aria_encode_str(42u, text, RSM_ARIA_MAX_STR_ARG, buf, sizeof(buf)));
    /* The longest string makes the largest command payload, 200 bytes. */
    feed_one(buf, RSM_ARIA_MAX_STR_ARG + 9u, &pkt);
    TEST_ASSERT_EQUAL_UINT32(RSM_ARIA_MAX_CMD_PAYLOAD, (uint32_t)pkt.payload_len);
    /* An empty string is length 0 plus the NUL. */
    TEST_ASSERT_EQUAL_INT(9, rsm_aria_encode_str(42u, NULL, 0u, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_HEX8(0x00u, buf[5]);
}

void test_encode_should_reject_null_pointers_and_unknown_kinds(void)
{
    uint8_t buf[16];

    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_encode_stop(NULL, 16u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_encode_vel(10, NULL, 16u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_encode_setv(-10, NULL, 16u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_encode_vel2(1, 1, NULL, 16u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_encode_tty2(NULL, 3u, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_encode_raw(0x32u, NULL, 3u, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL,
                          rsm_aria_encode(11u, (rsm_aria_arg_kind_t)7, 0, NULL, 0u, buf, sizeof(buf)));
}

void test_encode_should_reject_out_of_range_command_arguments(void)
{
    uint8_t buf[16];

    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_setv(-1, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_setrv(-1, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(9, rsm_aria_encode_setv(0, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(9, rsm_aria_encode_setrv(100, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_HEX8(RSM_ARIA_CMD_SETRV, buf[3]);
    TEST_ASSERT_EQUAL_HEX8(100u, buf[5]);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_hostbaud(5u, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(9, rsm_aria_encode_hostbaud(4u, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_vel2(128, 0, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_vel2(-128, 0, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_vel2(0, 128, buf, sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_vel2(0, -128, buf, sizeof(buf)));
}

void test_baud_code_should_map_the_five_host_rates(void)
{
    TEST_ASSERT_EQUAL_INT(0, rsm_aria_baud_code(9600u));
    TEST_ASSERT_EQUAL_INT(1, rsm_aria_baud_code(19200u));
    TEST_ASSERT_EQUAL_INT(2, rsm_aria_baud_code(38400u));
    TEST_ASSERT_EQUAL_INT(3, rsm_aria_baud_code(57600u));
    TEST_ASSERT_EQUAL_INT(4, rsm_aria_baud_code(115200u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_baud_code(4800u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_baud_code(0u));
}

/* The robot side of VEL2 (as the emulator decodes it): read the type byte
 * and u16, negate for NINTARG, take the high byte as left, low as right. */
void test_encode_vel2_should_round_trip_every_wheel_pair(void)
{
    int32_t left;
    int32_t right;
    uint8_t buf[16];

    for (left = -RSM_ARIA_VEL2_MAX; left <= RSM_ARIA_VEL2_MAX; ++left) {
        for (right = -RSM_ARIA_VEL2_MAX; right <= RSM_ARIA_VEL2_MAX; ++right) {
            int32_t v;
            uint32_t word;
            int32_t got_left;
            int32_t got_right;
            TEST_ASSERT_EQUAL_INT(9, rsm_aria_encode_vel2(left, right, buf, sizeof(buf)));
            TEST_ASSERT_EQUAL_HEX16(ref_checksum(buf + 3, 4u),
                                    (uint16_t)((uint32_t)buf[7] * 256u + buf[8]));
            v = (int32_t)((uint32_t)buf[5] | ((uint32_t)buf[6] << 8));
            TEST_ASSERT_TRUE(v <= 32767);
            if (buf[4] == RSM_ARIA_ARGTYPE_NINT) {
                v = -v;
            } else {
                TEST_ASSERT_EQUAL_HEX8(RSM_ARIA_ARGTYPE_INT, buf[4]);
            }
            word = (uint32_t)v & 0xFFFFu;
            got_left = (int32_t)(word >> 8);
            got_right = (int32_t)(word & 0xFFu);
            if (got_left > 127) {
                got_left -= 256;
            }
            if (got_right > 127) {
                got_right -= 256;
            }
            TEST_ASSERT_EQUAL_INT32(left, got_left);
            TEST_ASSERT_EQUAL_INT32(right, got_right);
        }
    }
}

void test_encode_raw_should_frame_byte_count_255_and_reject_more(void)
{
    uint8_t payload[RSM_ARIA_MAX_PAYLOAD + 1u];
    uint8_t buf[RSM_ARIA_MAX_PACKET + 8u];
    rsm_aria_packet_t pkt;
    size_t i;

    for (i = 0u; i < sizeof(payload); ++i) {
        payload[i] = (uint8_t)(i * 7u);
    }
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_encode_raw(0x77u, payload, sizeof(payload), buf,
                                                             sizeof(buf)));
    TEST_ASSERT_EQUAL_INT(258, rsm_aria_encode_raw(0x77u, payload, RSM_ARIA_MAX_PAYLOAD, buf,
                                                   sizeof(buf)));
    TEST_ASSERT_EQUAL_HEX8(0xFFu, buf[2]);
    feed_one(buf, 258u, &pkt);
    TEST_ASSERT_EQUAL_UINT32(RSM_ARIA_MAX_PAYLOAD, (uint32_t)pkt.payload_len);
    TEST_ASSERT_EQUAL_MEMORY(payload, rsm_aria_payload(&pkt), RSM_ARIA_MAX_PAYLOAD);
}

/* ---- receiver -------------------------------------------------------------------- */

/* Feeds a whole buffer (in `chunk`-byte pieces, 0 = at once), storing up to
 * max published packets; returns how many were published. Checks the
 * byte conservation law of rsm_aria_parser_stats_t after every call. */
static size_t feed_all(rsm_aria_parser_t *p, const uint8_t *s, size_t n, size_t chunk,
                       rsm_aria_packet_t *pkts, size_t max)
{
    size_t off = 0u;
    size_t count = 0u;
    uint32_t fed_before = p->stats.bytes_skipped + p->stats.bad_length + p->stats.checksum_errors +
                          p->stats.truncated + (uint32_t)rsm_aria_parser_pending(p);
    uint32_t published = 0u;

    for (;;) {
        rsm_aria_packet_t pkt;
        size_t len = (chunk == 0u || n - off < chunk) ? n - off : chunk;
        size_t used = 0u;
        int r = rsm_aria_parser_feed(p, s + off, len, &used, &pkt);
        TEST_ASSERT_TRUE(r == 0 || r == 1);
        TEST_ASSERT_TRUE(used <= len);
        off += used;
        if (r == 1) {
            TEST_ASSERT_TRUE(count < max);
            pkts[count++] = pkt;
            published += (uint32_t)pkt.frame_len;
        }
        TEST_ASSERT_TRUE(rsm_aria_parser_pending(p) <= 258u);
        TEST_ASSERT_EQUAL_UINT32(fed_before + (uint32_t)off,
                                 published + p->stats.bytes_skipped + p->stats.bad_length +
                                     p->stats.checksum_errors + p->stats.truncated +
                                     (uint32_t)rsm_aria_parser_pending(p));
        if (r == 0 && off == n) {
            break;
        }
    }
    return count;
}

void test_parser_feed_should_reject_invalid_arguments(void)
{
    rsm_aria_packet_t pkt;
    size_t used = 99u;

    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_parser_init(NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_parser_feed(NULL, V_SYNC0, 6u, &used, &pkt));
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)used);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_parser_feed(&parser, V_SYNC0, 6u, NULL, &pkt));
    used = 99u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_parser_feed(&parser, V_SYNC0, 6u, &used, NULL));
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)used);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_parser_feed(&parser, NULL, 6u, &used, &pkt));
    TEST_ASSERT_EQUAL_INT(0, rsm_aria_parser_feed(&parser, NULL, 0u, &used, &pkt));
    expect_stats(0u, 0u, 0u, 0u, 0u, &parser.stats);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rsm_aria_parser_pending(NULL));
}

void test_parser_feed_should_publish_unknown_ids(void)
{
    static const uint8_t gyro_payload[] = {0x01, 0x02, 0x03};
    uint8_t s[128];
    size_t n = 0u;
    rsm_aria_packet_t pkts[4];
    rsm_aria_sip_t sip;
    int w;

    w = rsm_aria_encode_raw(0x77u, NULL, 0u, s, sizeof(s));
    TEST_ASSERT_EQUAL_INT(6, w);
    n += (size_t)w;
    w = rsm_aria_encode_raw((uint8_t)RSM_ARIA_PAC_GYRO, gyro_payload, sizeof(gyro_payload), s + n,
                            sizeof(s) - n);
    TEST_ASSERT_EQUAL_INT(9, w);
    n += (size_t)w;
    put(s, sizeof(s), &n, V_SIP_STOPPED_2SONAR, sizeof(V_SIP_STOPPED_2SONAR));
    TEST_ASSERT_EQUAL_UINT32(3u, (uint32_t)feed_all(&parser, s, n, 0u, pkts, 4u));
    TEST_ASSERT_EQUAL_HEX8(0x77u, pkts[0].id);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)pkts[0].payload_len);
    TEST_ASSERT_EQUAL_HEX8(0x98u, pkts[1].id);
    TEST_ASSERT_EQUAL_MEMORY(gyro_payload, rsm_aria_payload(&pkts[1]), sizeof(gyro_payload));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_sip(&pkts[0], &sip));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkts[2], &sip));
    expect_stats(0u, 0u, 0u, 3u, 0u, &parser.stats);
}

void test_parser_feed_should_not_end_a_packet_at_sync_bytes_in_its_payload(void)
{
    /* A payload that contains a complete SYNC0 frame. */
    static const uint8_t inner[] = {0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00, 0xFA, 0xFB};
    uint8_t s[64];
    rsm_aria_packet_t pkts[4];
    int w = rsm_aria_encode_raw(0xB0u, inner, sizeof(inner), s, sizeof(s));

    TEST_ASSERT_EQUAL_INT(14, w);
    TEST_ASSERT_EQUAL_UINT32(1u, (uint32_t)feed_all(&parser, s, (size_t)w, 1u, pkts, 4u));
    TEST_ASSERT_EQUAL_HEX8(0xB0u, pkts[0].id);
    TEST_ASSERT_EQUAL_MEMORY(inner, rsm_aria_payload(&pkts[0]), sizeof(inner));
    expect_stats(0u, 0u, 0u, 1u, 0u, &parser.stats);
}

void test_parser_feed_should_count_bad_length_for_byte_counts_0_1_2(void)
{
    uint8_t n_byte;

    for (n_byte = 0u; n_byte < 3u; ++n_byte) {
        uint8_t s[32];
        size_t n = 0u;
        rsm_aria_packet_t pkts[2];
        uint8_t head[3];
        head[0] = 0xFAu;
        head[1] = 0xFBu;
        head[2] = n_byte;
        put(s, sizeof(s), &n, head, sizeof(head));
        put(s, sizeof(s), &n, V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&parser));
        TEST_ASSERT_EQUAL_UINT32(1u, (uint32_t)feed_all(&parser, s, n, 0u, pkts, 2u));
        TEST_ASSERT_EQUAL_HEX8_ARRAY(V_ENCODER_PACKET, pkts[0].frame, sizeof(V_ENCODER_PACKET));
        /* FA is the rejected header, FB and N are re-examined and skipped. */
        expect_stats(2u, 0u, 1u, 1u, 0u, &parser.stats);
        TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rsm_aria_parser_pending(&parser));
    }
}

void test_parser_feed_should_handle_byte_count_255(void)
{
    uint8_t payload[RSM_ARIA_MAX_PAYLOAD];
    uint8_t s[2u * RSM_ARIA_MAX_PACKET];
    size_t n = 0u;
    rsm_aria_packet_t pkts[4];
    size_t i;
    int w;

    for (i = 0u; i < sizeof(payload); ++i) {
        payload[i] = (uint8_t)(255u - i);
    }
    /* A valid frame with N = 255 is published, whole. */
    w = rsm_aria_encode_raw(0x41u, payload, sizeof(payload), s, sizeof(s));
    TEST_ASSERT_EQUAL_INT(258, w);
    n = (size_t)w;
    put(s, sizeof(s), &n, V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET));
    TEST_ASSERT_EQUAL_UINT32(2u, (uint32_t)feed_all(&parser, s, n, 3u, pkts, 4u));
    TEST_ASSERT_EQUAL_UINT32(258u, (uint32_t)pkts[0].frame_len);
    TEST_ASSERT_EQUAL_UINT32(252u, (uint32_t)pkts[0].payload_len);
    TEST_ASSERT_EQUAL_MEMORY(payload, rsm_aria_payload(&pkts[0]), sizeof(payload));
    expect_stats(0u, 0u, 0u, 2u, 0u, &parser.stats);

    /* A false header FA FB FF swallows the next frame; silence releases it. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&parser));
    n = 0u;
    s[n++] = 0xFAu;
    s[n++] = 0xFBu;
    s[n++] = 0xFFu;
    put(s, sizeof(s), &n, V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET));
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)feed_all(&parser, s, n, 0u, pkts, 4u));
    TEST_ASSERT_EQUAL_UINT32(17u, (uint32_t)rsm_aria_parser_pending(&parser));
    TEST_ASSERT_EQUAL_INT(1, rsm_aria_parser_timeout(&parser));
    TEST_ASSERT_EQUAL_UINT32(1u, (uint32_t)feed_all(&parser, NULL, 0u, 0u, pkts, 4u));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(V_ENCODER_PACKET, pkts[0].frame, sizeof(V_ENCODER_PACKET));
    expect_stats(2u, 0u, 0u, 1u, 1u, &parser.stats);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rsm_aria_parser_pending(&parser));
}

void test_parser_feed_should_find_a_frame_inside_a_failed_candidate(void)
{
    static const uint8_t head[] = {0xFA, 0xFB, 0x10}; /* claims 19 bytes */
    static const uint8_t tail[] = {0x00, 0x00};
    uint8_t s[96];
    size_t n = 0u;
    size_t chunk;

    put(s, sizeof(s), &n, head, sizeof(head));
    put(s, sizeof(s), &n, V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET));
    put(s, sizeof(s), &n, tail, sizeof(tail));
    put(s, sizeof(s), &n, V_SIP_MOVING_WRAPPED, sizeof(V_SIP_MOVING_WRAPPED));
    for (chunk = 0u; chunk < 20u; ++chunk) {
        rsm_aria_packet_t pkts[4];
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&parser));
        TEST_ASSERT_EQUAL_UINT32(2u, (uint32_t)feed_all(&parser, s, n, chunk, pkts, 4u));
        TEST_ASSERT_EQUAL_HEX8_ARRAY(V_ENCODER_PACKET, pkts[0].frame, sizeof(V_ENCODER_PACKET));
        TEST_ASSERT_EQUAL_HEX8_ARRAY(V_SIP_MOVING_WRAPPED, pkts[1].frame,
                                     sizeof(V_SIP_MOVING_WRAPPED));
        /* One failed candidate; FB, 10 and the two zeros skipped. */
        expect_stats(4u, 1u, 0u, 2u, 0u, &parser.stats);
    }
}

void test_parser_timeout_should_release_a_frame_held_in_a_partial_candidate(void)
{
    static const uint8_t head[] = {0xFA, 0xFB, 0x40}; /* claims 67 bytes */
    uint8_t s[32];
    size_t n = 0u;
    size_t used = 9u;
    rsm_aria_packet_t pkt;

    put(s, sizeof(s), &n, head, sizeof(head));
    put(s, sizeof(s), &n, V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET));
    TEST_ASSERT_EQUAL_INT(0, rsm_aria_parser_feed(&parser, s, n, &used, &pkt));
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n, (uint32_t)used);
    TEST_ASSERT_EQUAL_UINT32(17u, (uint32_t)rsm_aria_parser_pending(&parser));
    TEST_ASSERT_EQUAL_INT(1, rsm_aria_parser_timeout(&parser));
    expect_stats(0u, 0u, 0u, 0u, 1u, &parser.stats);
    TEST_ASSERT_EQUAL_INT(1, rsm_aria_parser_feed(&parser, NULL, 0u, &used, &pkt));
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)used);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(V_ENCODER_PACKET, pkt.frame, sizeof(V_ENCODER_PACKET));
    TEST_ASSERT_EQUAL_INT(0, rsm_aria_parser_feed(&parser, NULL, 0u, &used, &pkt));
    expect_stats(2u, 0u, 0u, 1u, 1u, &parser.stats);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rsm_aria_parser_pending(&parser));
}

void test_parser_timeout_should_keep_bytes_from_before_the_silence_apart(void)
{
    /* A partial frame (stale) followed after the silence by a fresh frame:
     * the stale bytes must not absorb the fresh ones. */
    static const uint8_t stale[] = {0x55, 0xFA, 0xFB, 0x0B, 0x90, 0x01, 0xFA, 0xFB, 0x28};
    rsm_aria_packet_t pkts[2];

    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)feed_all(&parser, stale, sizeof(stale), 0u, pkts, 2u));
    TEST_ASSERT_EQUAL_INT(1, rsm_aria_parser_timeout(&parser));
    TEST_ASSERT_EQUAL_UINT32(1u, (uint32_t)feed_all(&parser, V_ENCODER_PACKET,
                                                    sizeof(V_ENCODER_PACKET), 0u, pkts, 2u));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(V_ENCODER_PACKET, pkts[0].frame, sizeof(V_ENCODER_PACKET));
    /* 55 skipped; the first candidate truncated by the timeout; FB 0B 90
     * 01 skipped; the inner FA FB 28 truncated as stale; FB 28 skipped. */
    expect_stats(7u, 0u, 0u, 1u, 2u, &parser.stats);
}

void test_parser_timeout_should_do_nothing_when_idle(void)
{
    static const uint8_t lone = 0xFAu;
    rsm_aria_packet_t pkts[1];

    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_parser_timeout(NULL));
    TEST_ASSERT_EQUAL_INT(0, rsm_aria_parser_timeout(&parser));
    expect_stats(0u, 0u, 0u, 0u, 0u, &parser.stats);
    /* A lone FA is not a packet: skipped, not truncated. */
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)feed_all(&parser, &lone, 1u, 0u, pkts, 1u));
    TEST_ASSERT_EQUAL_INT(0, rsm_aria_parser_timeout(&parser));
    expect_stats(1u, 0u, 0u, 0u, 0u, &parser.stats);
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rsm_aria_parser_pending(&parser));
}

/* Good frames the fault-injection streams are made of. */
static const uint8_t *const good_frames[] = {V_SIP_STOPPED_2SONAR, V_SIP_MOVING_WRAPPED,
                                             V_ENCODER_PACKET, V_ENCODER_PACKET_WRAPPED,
                                             V_SYNC2_REPLY_EXAMPLE, V_SYNC0};
static const size_t good_sizes[] = {sizeof(V_SIP_STOPPED_2SONAR), sizeof(V_SIP_MOVING_WRAPPED),
                                    sizeof(V_ENCODER_PACKET), sizeof(V_ENCODER_PACKET_WRAPPED),
                                    sizeof(V_SYNC2_REPLY_EXAMPLE), sizeof(V_SYNC0)};

#define STREAM_CAP 16384u
#define MAX_FRAMES 200u

/* Builds garbage + frame + garbage + frame ... into s. When corrupt_every
 * is non-zero, every corrupt_every-th frame gets 1..4 garbage bytes
 * inserted inside it. Records where the intact frames are. */
static size_t build_garbage_stream(uint8_t *s, uint32_t seed, size_t frames, size_t corrupt_every,
                                   size_t *start, size_t *len, size_t *n_intact)
{
    uint32_t st = seed;
    size_t n = 0u;
    size_t f;

    *n_intact = 0u;
    for (f = 0u; f < frames; ++f) {
        size_t g = (size_t)(prng_next(&st) % 24u);
        size_t which = (size_t)(prng_next(&st) % N_OF(good_frames));
        const uint8_t *fr = good_frames[which];
        size_t fl = good_sizes[which];
        uint8_t raw[64];
        size_t k;

        if ((prng_next(&st) & 3u) == 0u) {
            /* A random, valid frame with a random ID. */
            uint8_t payload[40];
            size_t pl = (size_t)(prng_next(&st) % sizeof(payload));
            int w;
            for (k = 0u; k < pl; ++k) {
                payload[k] = (uint8_t)prng_next(&st);
            }
            w = rsm_aria_encode_raw((uint8_t)prng_next(&st), payload, pl, raw, sizeof(raw));
            TEST_ASSERT_TRUE(w > 0);
            fr = raw;
            fl = (size_t)w;
        }
        TEST_ASSERT_TRUE(n + g + fl + 8u <= STREAM_CAP);
        for (k = 0u; k < g; ++k) {
            s[n++] = garbage_byte(&st);
        }
        if (corrupt_every != 0u && f % corrupt_every == corrupt_every - 1u) {
            size_t at = 1u + (size_t)(prng_next(&st) % (uint32_t)(fl - 1u));
            size_t extra = 1u + (size_t)(prng_next(&st) % 4u);
            memcpy(s + n, fr, at);
            n += at;
            for (k = 0u; k < extra; ++k) {
                s[n++] = garbage_byte(&st);
            }
            memcpy(s + n, fr + at, fl - at);
            n += fl - at;
        } else {
            start[*n_intact] = n;
            len[*n_intact] = fl;
            (*n_intact)++;
            memcpy(s + n, fr, fl);
            n += fl;
        }
    }
    return n;
}

/* The reference output must be exactly the intact frames. */
static void expect_ref_is_intact_frames(const ref_result_t *ref, const size_t *start,
                                        const size_t *len, size_t n_intact)
{
    size_t k;
    TEST_ASSERT_EQUAL_UINT32((uint32_t)n_intact, (uint32_t)ref->n_packets);
    for (k = 0u; k < n_intact; ++k) {
        TEST_ASSERT_EQUAL_UINT32((uint32_t)start[k], (uint32_t)ref->start[k]);
        TEST_ASSERT_EQUAL_UINT32((uint32_t)len[k], (uint32_t)ref->len[k]);
    }
}

void test_parser_feed_should_lose_no_frame_to_garbage_before_and_between_frames(void)
{
    uint8_t s[STREAM_CAP];
    size_t start[MAX_FRAMES];
    size_t len[MAX_FRAMES];
    size_t n_intact;
    ref_result_t ref;
    size_t n = build_garbage_stream(s, 0x1234567u, 150u, 0u, start, len, &n_intact);

    TEST_ASSERT_EQUAL_UINT32(150u, (uint32_t)n_intact);
    ref_parse(s, n, &ref);
    expect_ref_is_intact_frames(&ref, start, len, n_intact);
    /* The garbage did provoke false headers. */
    TEST_ASSERT_TRUE(ref.stats.checksum_errors + ref.stats.bad_length > 10u);
    run_against_ref(s, n, 0u, &ref);
    run_against_ref(s, n, 1u, &ref);
    run_against_ref(s, n, 7u, &ref);
    run_against_ref(s, n, 300u, &ref);
}

void test_parser_feed_should_lose_only_the_frames_with_garbage_inside(void)
{
    uint8_t s[STREAM_CAP];
    size_t start[MAX_FRAMES];
    size_t len[MAX_FRAMES];
    size_t n_intact;
    ref_result_t ref;
    size_t n = build_garbage_stream(s, 0xC0FFEEu, 150u, 3u, start, len, &n_intact);

    TEST_ASSERT_EQUAL_UINT32(100u, (uint32_t)n_intact);
    ref_parse(s, n, &ref);
    expect_ref_is_intact_frames(&ref, start, len, n_intact);
    TEST_ASSERT_TRUE(ref.stats.checksum_errors >= 50u);
    run_against_ref(s, n, 0u, &ref);
    run_against_ref(s, n, 1u, &ref);
    run_against_ref(s, n, 13u, &ref);
}

void test_parser_feed_should_give_the_same_result_one_byte_at_a_time(void)
{
    uint8_t s[STREAM_CAP];
    size_t start[MAX_FRAMES];
    size_t len[MAX_FRAMES];
    size_t n_intact;
    rsm_aria_parser_t whole;
    rsm_aria_parser_t bytewise;
    size_t n = build_garbage_stream(s, 0xBADC0DEu, 61u, 4u, start, len, &n_intact);
    ref_result_t ref;
    size_t off = 0u;
    size_t a = 0u;
    size_t b = 0u;
    rsm_aria_packet_t pa;
    rsm_aria_packet_t pb;
    int ra;
    int rb;

    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&whole));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&bytewise));
    /* No timeout at all: pure streaming, compared packet by packet. */
    for (;;) {
        size_t used = 0u;
        ra = rsm_aria_parser_feed(&whole, s + off, n - off, &used, &pa);
        off += used;
        if (ra != 1) {
            break;
        }
        a++;
        /* Advance the byte-wise parser to its next packet. */
        for (;;) {
            size_t u = 0u;
            rb = rsm_aria_parser_feed(&bytewise, s + b, (b < n) ? 1u : 0u, &u, &pb);
            b += u;
            if (rb == 1) {
                break;
            }
            TEST_ASSERT_TRUE(b < n);
        }
        TEST_ASSERT_EQUAL_UINT32((uint32_t)pa.frame_len, (uint32_t)pb.frame_len);
        TEST_ASSERT_EQUAL_MEMORY(pa.frame, pb.frame, pa.frame_len);
        /* Both have consumed the same input when the packet completes. */
        TEST_ASSERT_EQUAL_UINT32((uint32_t)off, (uint32_t)b);
    }
    while (b < n || rb == 1) {
        size_t u = 0u;
        rb = rsm_aria_parser_feed(&bytewise, s + b, (b < n) ? 1u : 0u, &u, &pb);
        b += u;
        TEST_ASSERT_TRUE(rb == 0);
    }
    /* Every intact frame came out, in order; a damaged one may come out
     * too when the inserted garbage happens to restore it (a sync byte
     * inserted right before the byte it duplicates). */
    ref_parse(s, n, &ref);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)ref.n_packets, (uint32_t)a);
    TEST_ASSERT_TRUE(a >= n_intact);
    {
        size_t i = 0u;
        size_t k;
        for (k = 0u; k < ref.n_packets && i < n_intact; ++k) {
            if (ref.start[k] == start[i]) {
                i++;
            }
        }
        TEST_ASSERT_EQUAL_UINT32((uint32_t)n_intact, (uint32_t)i);
    }
    expect_stats(whole.stats.bytes_skipped, whole.stats.checksum_errors, whole.stats.bad_length,
                 whole.stats.packets_ok, whole.stats.truncated, &bytewise.stats);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)rsm_aria_parser_pending(&whole),
                             (uint32_t)rsm_aria_parser_pending(&bytewise));
    if (rsm_aria_parser_pending(&whole) > 0u) {
        TEST_ASSERT_EQUAL_MEMORY(whole.buf, bytewise.buf, rsm_aria_parser_pending(&whole));
    }
}

void test_parser_feed_should_hold_at_most_one_frame_of_bytes(void)
{
    uint8_t s[4096];
    rsm_aria_packet_t pkts[8];
    uint32_t st = 99u;
    size_t i;

    for (i = 0u; i < sizeof(s); ++i) {
        uint32_t r = prng_next(&st) % 4u;
        s[i] = (r == 0u) ? 0xFAu : (r == 1u) ? 0xFBu : (r == 2u) ? 0xFFu : (uint8_t)prng_next(&st);
    }
    /* feed_all checks pending <= 258 and the conservation law per call. */
    (void)feed_all(&parser, s, sizeof(s), 5u, pkts, N_OF(pkts));
    (void)rsm_aria_parser_timeout(&parser);
    (void)feed_all(&parser, NULL, 0u, 0u, pkts, N_OF(pkts));
    TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rsm_aria_parser_pending(&parser));
}

/* One bit flipped in frame x, between good frames G1 x G2 G3. Expected
 * counters follow from the receiver rules, given that x holds no FA after
 * its header:
 *   byte 0 or 1 (header): no candidate starts, all of x is skipped;
 *   byte 2 (N): N' < 3 is a bad length; a candidate that fits in the
 *     bytes up to the end of G3 fails its checksum; a longer one is cut
 *     by the final timeout; either way x after its FA is skipped;
 *   any later byte: a checksum error (a one-bit change always changes the
 *     sum), x after its FA skipped.
 * G1, G2 and G3 are always published, whatever the flip. */
static void check_bit_flips(const uint8_t *x, size_t xn)
{
    uint8_t s[256];
    size_t j;
    unsigned b;

    for (j = 1u; j < xn; ++j) {
        TEST_ASSERT_TRUE(x[j] != 0xFAu);
    }
    for (j = 0u; j < xn; ++j) {
        for (b = 0u; b < 8u; ++b) {
            size_t n = 0u;
            size_t at;
            size_t count;
            rsm_aria_packet_t pkts[4];
            rsm_aria_encoder_t enc;
            rsm_aria_sip_t sip;
            ref_result_t ref;
            uint8_t flipped = (uint8_t)(x[j] ^ (1u << b));
            uint32_t skipped = (uint32_t)xn - 1u;
            uint32_t cks = 0u;
            uint32_t bad = 0u;
            uint32_t trunc = 0u;

            put(s, sizeof(s), &n, V_ENCODER_PACKET_WRAPPED, sizeof(V_ENCODER_PACKET_WRAPPED));
            at = n;
            put(s, sizeof(s), &n, x, xn);
            s[at + j] = flipped;
            put(s, sizeof(s), &n, V_SIP_MOVING_WRAPPED, sizeof(V_SIP_MOVING_WRAPPED));
            put(s, sizeof(s), &n, V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET));

            if (j < 2u) {
                skipped = (uint32_t)xn;
            } else if (j == 2u) {
                if (flipped < 3u) {
                    bad = 1u;
                } else if ((size_t)flipped + 3u <= n - at) {
                    cks = 1u;
                } else {
                    trunc = 1u;
                }
            } else {
                TEST_ASSERT_TRUE(flipped != 0xFAu);
                cks = 1u;
            }

            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&parser));
            count = feed_all(&parser, s, n, 0u, pkts, 4u);
            (void)rsm_aria_parser_timeout(&parser);
            count += feed_all(&parser, NULL, 0u, 0u, pkts + count, 4u - count);
            TEST_ASSERT_EQUAL_UINT32(3u, (uint32_t)count);
            TEST_ASSERT_EQUAL_HEX8_ARRAY(V_ENCODER_PACKET_WRAPPED, pkts[0].frame,
                                         sizeof(V_ENCODER_PACKET_WRAPPED));
            TEST_ASSERT_EQUAL_HEX8_ARRAY(V_SIP_MOVING_WRAPPED, pkts[1].frame,
                                         sizeof(V_SIP_MOVING_WRAPPED));
            TEST_ASSERT_EQUAL_HEX8_ARRAY(V_ENCODER_PACKET, pkts[2].frame, sizeof(V_ENCODER_PACKET));
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkts[1], &sip));
            TEST_ASSERT_EQUAL_UINT16(10u, sip.xpos);
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_encoder(&pkts[2], &enc));
            TEST_ASSERT_EQUAL_INT32(123456, enc.left);
            expect_stats(skipped, cks, bad, 3u, trunc, &parser.stats);

            ref_parse(s, n, &ref);
            expect_stats(skipped, cks, bad, 3u, trunc, &ref.stats);
            run_against_ref(s, n, 1u, &ref);
        }
    }
}

void test_parser_feed_should_recover_from_a_flipped_bit_anywhere_in_a_sip(void)
{
    check_bit_flips(V_SIP_STOPPED_2SONAR, sizeof(V_SIP_STOPPED_2SONAR));
}

void test_parser_feed_should_recover_from_a_flipped_bit_anywhere_in_an_encoder_packet(void)
{
    check_bit_flips(V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET));
}

/* Frame x cut after k bytes, a timeout, then a good frame. */
static void check_truncation_with_timeout(const uint8_t *x, size_t xn)
{
    size_t k;

    for (k = 0u; k < xn; ++k) {
        rsm_aria_packet_t pkts[2];
        rsm_aria_sip_t sip;
        int expect_trunc = (k >= 2u) ? 1 : 0;

        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&parser));
        TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)feed_all(&parser, x, k, 0u, pkts, 2u));
        TEST_ASSERT_EQUAL_UINT32((uint32_t)k, (uint32_t)rsm_aria_parser_pending(&parser));
        TEST_ASSERT_EQUAL_INT(expect_trunc, rsm_aria_parser_timeout(&parser));
        TEST_ASSERT_EQUAL_UINT32(1u, (uint32_t)feed_all(&parser, V_SIP_MOVING_WRAPPED,
                                                        sizeof(V_SIP_MOVING_WRAPPED), 1u, pkts, 2u));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkts[0], &sip));
        TEST_ASSERT_EQUAL_INT16(-1024, sip.thpos);
        /* The cut frame's bytes after its FA are skipped (a lone FA too). */
        expect_stats((k >= 2u) ? (uint32_t)k - 1u : (uint32_t)k, 0u, 0u, 1u, (uint32_t)expect_trunc,
                     &parser.stats);
        TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rsm_aria_parser_pending(&parser));
    }
}

void test_parser_timeout_should_count_a_sip_cut_at_every_offset_as_truncated(void)
{
    check_truncation_with_timeout(V_SIP_STOPPED_2SONAR, sizeof(V_SIP_STOPPED_2SONAR));
}

void test_parser_timeout_should_count_an_encoder_packet_cut_at_every_offset_as_truncated(void)
{
    check_truncation_with_timeout(V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET));
}

/* Frame x cut after k bytes and followed at once (no timeout) by 20 good
 * frames: the cut frame completes with bytes of the good ones, fails its
 * checksum, and the good ones are found again inside it. 20 * 14 bytes
 * exceed the longest possible candidate (FA FB FA: 253 bytes). */
static void check_truncation_without_timeout(const uint8_t *x, size_t xn, size_t chunk)
{
    uint8_t s[512];
    size_t k;

    for (k = 1u; k < xn; ++k) {
        rsm_aria_packet_t pkts[24];
        size_t n = 0u;
        size_t i;

        put(s, sizeof(s), &n, x, k);
        for (i = 0u; i < 20u; ++i) {
            put(s, sizeof(s), &n, V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET));
        }
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&parser));
        TEST_ASSERT_EQUAL_UINT32(20u, (uint32_t)feed_all(&parser, s, n, chunk, pkts, N_OF(pkts)));
        for (i = 0u; i < 20u; ++i) {
            TEST_ASSERT_EQUAL_HEX8_ARRAY(V_ENCODER_PACKET, pkts[i].frame, sizeof(V_ENCODER_PACKET));
        }
        expect_stats((uint32_t)k - 1u + ((k == 1u) ? 1u : 0u), (k >= 2u) ? 1u : 0u, 0u, 20u, 0u,
                     &parser.stats);
        TEST_ASSERT_EQUAL_UINT32(0u, (uint32_t)rsm_aria_parser_pending(&parser));
    }
}

void test_parser_feed_should_recover_frames_after_a_cut_sip_without_timeout(void)
{
    check_truncation_without_timeout(V_SIP_STOPPED_2SONAR, sizeof(V_SIP_STOPPED_2SONAR), 0u);
    check_truncation_without_timeout(V_SIP_STOPPED_2SONAR, sizeof(V_SIP_STOPPED_2SONAR), 1u);
}

void test_parser_feed_should_recover_frames_after_a_cut_encoder_packet_without_timeout(void)
{
    check_truncation_without_timeout(V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET), 0u);
    check_truncation_without_timeout(V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET), 1u);
}

/* ---- decoders: short, wrong and extended packets ------------------------------------- */

/* Payload of the aria_sip_stopped_2sonar vector (37 bytes). */
#define SIP2_PAYLOAD (V_SIP_STOPPED_2SONAR + 4)
#define SIP2_PAYLOAD_LEN (sizeof(V_SIP_STOPPED_2SONAR) - 6u)

void test_decode_sip_should_reject_a_sip_shorter_than_its_sonar_count(void)
{
    rsm_aria_packet_t pkt;
    rsm_aria_sip_t s;
    rsm_aria_sip_t before;
    uint8_t payload[64];
    size_t len;

    memset(&s, 0xA5, sizeof(s));
    memcpy(&before, &s, sizeof(s));
    /* Two readings claimed, the second one cut: 24 < 19 + 3 * 2. */
    for (len = 0u; len < 25u; ++len) {
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x32u, SIP2_PAYLOAD, len));
        TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_decode_sip(&pkt, &s));
        TEST_ASSERT_EQUAL_MEMORY(&before, &s, sizeof(s));
    }
    /* Exactly the sonar block: valid, with no later field. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x32u, SIP2_PAYLOAD, 25u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkt, &s));
    TEST_ASSERT_EQUAL_UINT32(2u, (uint32_t)s.sonar_len);
    TEST_ASSERT_EQUAL_UINT16(5000u, s.sonar[1].range);
    TEST_ASSERT_EQUAL_HEX32(0u, s.present);
    /* The full payload claiming 7 readings needs 40 bytes: too short. */
    memcpy(payload, SIP2_PAYLOAD, SIP2_PAYLOAD_LEN);
    payload[18] = 7u;
    memset(&s, 0xA5, sizeof(s));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x33u, payload, SIP2_PAYLOAD_LEN));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_decode_sip(&pkt, &s));
    TEST_ASSERT_EQUAL_MEMORY(&before, &s, sizeof(s));
    /* The same through the receiver: the frame is fine, the SIP is not. */
    {
        uint8_t frame[80];
        int w = rsm_aria_encode_raw(0x33u, payload, SIP2_PAYLOAD_LEN, frame, sizeof(frame));
        TEST_ASSERT_EQUAL_INT(43, w);
        feed_one(frame, (size_t)w, &pkt);
        TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_decode_sip(&pkt, &s));
        TEST_ASSERT_EQUAL_MEMORY(&before, &s, sizeof(s));
    }
}

/* The vector's SIP with every optional tail field appended. */
static size_t sip_with_tail(uint8_t *payload)
{
    static const uint8_t tail[] = {
        0xD4, 0xFE,             /* lateral velocity -300 mm/s */
        0xFB,                   /* temperature -5 C */
        0x57,                   /* state of charge 87 % */
        0x78, 0x56, 0x34, 0x12, /* controller time 0x12345678 us */
        0x01, 0x00, 0x00, 0xA5  /* FLAGS3 0xA5000001 */
    };
    memcpy(payload, SIP2_PAYLOAD, SIP2_PAYLOAD_LEN);
    memcpy(payload + SIP2_PAYLOAD_LEN, tail, sizeof(tail));
    return SIP2_PAYLOAD_LEN + sizeof(tail);
}

void test_decode_sip_should_decode_the_optional_tail(void)
{
    uint8_t payload[64];
    size_t len = sip_with_tail(payload);
    rsm_aria_packet_t pkt;
    rsm_aria_sip_t s;

    TEST_ASSERT_EQUAL_UINT32(49u, (uint32_t)len);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x32u, payload, len));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkt, &s));
    TEST_ASSERT_EQUAL_HEX32(0x3FFFu, s.present);
    TEST_ASSERT_EQUAL_INT16(11, s.rot_vel);
    TEST_ASSERT_EQUAL_INT16(-300, s.lat_vel);
    TEST_ASSERT_EQUAL_INT8(-5, s.temperature);
    TEST_ASSERT_EQUAL_INT8(87, s.state_of_charge);
    TEST_ASSERT_EQUAL_HEX32(0x12345678u, s.uc_time);
    TEST_ASSERT_EQUAL_HEX32(0xA5000001u, s.flags3);
}

void test_decode_sip_should_flag_optional_fields_only_when_complete(void)
{
    /* Payload offset at which each optional field ends, in wire order. */
    static const size_t ends[] = {26u, 27u, 28u, 29u, 30u, 32u, 33u, 35u, 37u, 39u, 40u, 41u, 45u, 49u};
    uint8_t payload[64];
    size_t full = sip_with_tail(payload);
    size_t len;

    for (len = 25u; len <= full; ++len) {
        rsm_aria_packet_t pkt;
        rsm_aria_sip_t s;
        uint32_t expect = 0u;
        size_t f;
        for (f = 0u; f < N_OF(ends); ++f) {
            if (ends[f] <= len) {
                expect |= 1u << f;
            }
        }
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x32u, payload, len));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkt, &s));
        TEST_ASSERT_EQUAL_HEX32(expect, s.present);
        /* Absent fields read as zero. */
        if ((expect & RSM_ARIA_SIP_HAS_DIGIN) == 0u) {
            TEST_ASSERT_EQUAL_HEX8(0u, s.digin);
        } else {
            TEST_ASSERT_EQUAL_HEX8(0xFFu, s.digin);
        }
        if ((expect & RSM_ARIA_SIP_HAS_BATTERY_X10) == 0u) {
            TEST_ASSERT_EQUAL_UINT16(0u, s.battery_x10);
        } else {
            TEST_ASSERT_EQUAL_UINT16(125u, s.battery_x10);
        }
        if ((expect & RSM_ARIA_SIP_HAS_FLAGS3) == 0u) {
            TEST_ASSERT_EQUAL_HEX32(0u, s.flags3);
        }
        if ((expect & RSM_ARIA_SIP_HAS_UC_TIME) == 0u) {
            TEST_ASSERT_EQUAL_HEX32(0u, s.uc_time);
        }
    }
}

void test_decode_sip_should_keep_at_most_max_sonar_readings(void)
{
    uint8_t payload[RSM_ARIA_MAX_PAYLOAD];
    size_t count = RSM_ARIA_MAX_SONAR + 8u;
    size_t len;
    size_t i;
    rsm_aria_packet_t pkt;
    rsm_aria_sip_t s;

    if (count > 70u) {
        count = 70u; /* keeps the payload within one frame */
    }
    memcpy(payload, SIP2_PAYLOAD, 18u);
    payload[18] = (uint8_t)count;
    for (i = 0u; i < count; ++i) {
        payload[19u + 3u * i] = (uint8_t)(i & 31u);
        payload[20u + 3u * i] = (uint8_t)((1000u + i) & 0xFFu);
        payload[21u + 3u * i] = (uint8_t)((1000u + i) >> 8);
    }
    len = 19u + 3u * count;
    /* GRIP_STATE .. BATTERYX10 after the readings. */
    payload[len++] = 4u;
    payload[len++] = 1u;
    payload[len++] = 200u;
    payload[len++] = 0x0Fu;
    payload[len++] = 0xF0u;
    payload[len++] = 0x30u;
    payload[len++] = 0x01u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x33u, payload, len));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkt, &s));
    TEST_ASSERT_EQUAL_UINT8((uint8_t)count, s.sonar_count);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)((count < RSM_ARIA_MAX_SONAR) ? count : RSM_ARIA_MAX_SONAR),
                             (uint32_t)s.sonar_len);
    for (i = 0u; i < s.sonar_len; ++i) {
        TEST_ASSERT_EQUAL_UINT8((uint8_t)(i & 31u), s.sonar[i].num);
        TEST_ASSERT_EQUAL_UINT16((uint16_t)(1000u + i), s.sonar[i].range);
    }
    TEST_ASSERT_EQUAL_UINT8(4u, s.grip_state);
    TEST_ASSERT_EQUAL_UINT8(1u, s.anport);
    TEST_ASSERT_EQUAL_UINT8(200u, s.analog);
    TEST_ASSERT_EQUAL_HEX8(0x0Fu, s.digin);
    TEST_ASSERT_EQUAL_HEX8(0xF0u, s.digout);
    TEST_ASSERT_EQUAL_UINT16(0x0130u, s.battery_x10);
    TEST_ASSERT_EQUAL_HEX32(0x003Fu, s.present);
}

void test_decode_sip_should_mask_xpos_and_ypos_to_15_bits(void)
{
    uint8_t payload[64];
    rsm_aria_packet_t pkt;
    rsm_aria_sip_t s;

    memcpy(payload, SIP2_PAYLOAD, SIP2_PAYLOAD_LEN);
    payload[1] = (uint8_t)(payload[1] | 0x80u); /* XPOS 1000 | 0x8000 */
    payload[3] = (uint8_t)(payload[3] | 0x80u); /* YPOS 32700 | 0x8000 */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x32u, payload, SIP2_PAYLOAD_LEN));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkt, &s));
    TEST_ASSERT_EQUAL_UINT16(1000u, s.xpos);
    TEST_ASSERT_EQUAL_UINT16(32700u, s.ypos);
}

void test_decode_should_reject_wrong_ids_and_inconsistent_packets(void)
{
    rsm_aria_packet_t sip_pkt;
    rsm_aria_packet_t enc_pkt;
    rsm_aria_packet_t bad;
    rsm_aria_sip_t s;
    rsm_aria_encoder_t e;
    rsm_aria_config_t c;
    rsm_aria_sync2_t y;
    rsm_aria_sip_t s0;
    rsm_aria_encoder_t e0;

    feed_one(V_SIP_STOPPED_2SONAR, sizeof(V_SIP_STOPPED_2SONAR), &sip_pkt);
    feed_one(V_ENCODER_PACKET, sizeof(V_ENCODER_PACKET), &enc_pkt);
    memset(&s, 0x3C, sizeof(s));
    memset(&e, 0x3C, sizeof(e));
    memcpy(&s0, &s, sizeof(s));
    memcpy(&e0, &e, sizeof(e));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_sip(&enc_pkt, &s));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_encoder(&sip_pkt, &e));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_config(&sip_pkt, &c));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_sync2(&sip_pkt, &y));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_sip(NULL, &s));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_sip(&sip_pkt, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_encoder(&enc_pkt, NULL));
    /* Lengths that disagree with each other are refused before any read. */
    bad = enc_pkt;
    bad.payload_len = 300u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_encoder(&bad, &e));
    bad = enc_pkt;
    bad.frame_len = RSM_ARIA_MAX_PACKET + 1u;
    bad.payload_len = RSM_ARIA_MAX_PACKET - 5u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_encoder(&bad, &e));
    bad = sip_pkt;
    bad.id = 0x33u; /* frame[3] still says 0x32 */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_decode_sip(&bad, &s));
    TEST_ASSERT_EQUAL_MEMORY(&s0, &s, sizeof(s));
    TEST_ASSERT_EQUAL_MEMORY(&e0, &e, sizeof(e));
    TEST_ASSERT_NULL(rsm_aria_payload(NULL));
}

void test_packet_build_should_match_the_receiver_output(void)
{
    rsm_aria_packet_t built;
    rsm_aria_packet_t parsed;
    uint8_t big[RSM_ARIA_MAX_PAYLOAD + 1u];

    feed_one(V_SIP_MOVING_WRAPPED, sizeof(V_SIP_MOVING_WRAPPED), &parsed);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&built, 0x33u, V_SIP_MOVING_WRAPPED + 4,
                                                        sizeof(V_SIP_MOVING_WRAPPED) - 6u));
    TEST_ASSERT_EQUAL_HEX8(parsed.id, built.id);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)parsed.payload_len, (uint32_t)built.payload_len);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)parsed.frame_len, (uint32_t)built.frame_len);
    TEST_ASSERT_EQUAL_MEMORY(parsed.frame, built.frame, parsed.frame_len);
    memset(big, 0, sizeof(big));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_packet_build(&built, 1u, big, sizeof(big)));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_packet_build(&built, 1u, NULL, 1u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_aria_packet_build(NULL, 1u, big, 1u));
}

void test_decode_encoder_should_need_8_bytes_and_ignore_extra_ones(void)
{
    static const uint8_t payload[] = {0x40, 0xE2, 0x01, 0x00, 0x0F, 0x04, 0xF6, 0xFF, 0xEE, 0xDD};
    rsm_aria_packet_t pkt;
    rsm_aria_encoder_t e;
    size_t len;

    e.left = 77;
    e.right = 78;
    for (len = 0u; len < 8u; ++len) {
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x90u, payload, len));
        TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_decode_encoder(&pkt, &e));
        TEST_ASSERT_EQUAL_INT32(77, e.left);
        TEST_ASSERT_EQUAL_INT32(78, e.right);
    }
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x90u, payload, sizeof(payload)));
    TEST_ASSERT_EQUAL_UINT8(13u, pkt.frame[2]); /* N = 13 */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_encoder(&pkt, &e));
    TEST_ASSERT_EQUAL_INT32(123456, e.left);
    TEST_ASSERT_EQUAL_INT32(-654321, e.right);
}

void test_decode_encoder_should_give_exact_deltas_across_counter_wrap_around(void)
{
    uint8_t s[16u * 14u];
    size_t n = 0u;
    rsm_aria_packet_t pkts[16];
    uint32_t left = (uint32_t)INT32_MAX - 2500u;       /* climbs through +2^31 */
    uint32_t right = (uint32_t)INT32_MIN + 2500u;      /* falls through -2^31 */
    rsm_aria_encoder_t prev;
    size_t i;

    for (i = 0u; i < 16u; ++i) {
        uint8_t payload[8];
        uint32_t l = left + 1000u * (uint32_t)i;
        uint32_t r = right - 1000u * (uint32_t)i;
        int w;
        payload[0] = (uint8_t)l;
        payload[1] = (uint8_t)(l >> 8);
        payload[2] = (uint8_t)(l >> 16);
        payload[3] = (uint8_t)(l >> 24);
        payload[4] = (uint8_t)r;
        payload[5] = (uint8_t)(r >> 8);
        payload[6] = (uint8_t)(r >> 16);
        payload[7] = (uint8_t)(r >> 24);
        w = rsm_aria_encode_raw(0x90u, payload, sizeof(payload), s + n, sizeof(s) - n);
        TEST_ASSERT_EQUAL_INT(14, w);
        n += (size_t)w;
    }
    TEST_ASSERT_EQUAL_UINT32(16u, (uint32_t)feed_all(&parser, s, n, 3u, pkts, N_OF(pkts)));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_encoder(&pkts[0], &prev));
    TEST_ASSERT_EQUAL_INT32(INT32_MAX - 2500, prev.left);
    TEST_ASSERT_EQUAL_INT32(INT32_MIN + 2500, prev.right);
    for (i = 1u; i < 16u; ++i) {
        rsm_aria_encoder_t cur;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_encoder(&pkts[i], &cur));
        TEST_ASSERT_EQUAL_INT32(1000, rsm_odometry_count_delta((uint32_t)(cur.left), (uint32_t)(prev.left), 32u));
        TEST_ASSERT_EQUAL_INT32(-1000, rsm_odometry_count_delta((uint32_t)(cur.right), (uint32_t)(prev.right), 32u));
        prev = cur;
    }
    /* The counters did wrap. */
    TEST_ASSERT_TRUE(prev.left < 0);
    TEST_ASSERT_TRUE(prev.right > 0);
}

/* ---- CONFIG and SYNC2 strings ------------------------------------------------------------ */

typedef struct writer {
    uint8_t *p;
    size_t len;
    size_t cap;
} writer_t;

static void w_u8(writer_t *w, uint32_t v)
{
    TEST_ASSERT_TRUE(w->len < w->cap);
    w->p[w->len++] = (uint8_t)(v & 0xFFu);
}

static void w_u16(writer_t *w, uint32_t v)
{
    w_u8(w, v & 0xFFu);
    w_u8(w, (v >> 8) & 0xFFu);
}

static void w_str(writer_t *w, const char *str)
{
    size_t i;
    for (i = 0u; str[i] != '\0'; ++i) {
        w_u8(w, (uint32_t)(unsigned char)str[i]);
    }
    w_u8(w, 0u);
}

/* A synthetic CONFIGpac in the documented field order: every u16 field k
 * (0-based, in order) holds 1000 + k and every u8 field holds 10 + k so
 * that any shift in the order shows. Returns the payload length and, in
 * *required, the length up to and including TicksMM. */
static size_t build_config(uint8_t *buf, size_t cap, const char *name, size_t *required)
{
    writer_t w;
    w.p = buf;
    w.len = 0u;
    w.cap = cap;
    w_str(&w, "Pioneer");
    w_str(&w, "p3dx-sh");
    w_str(&w, "DX-0042");
    w_u8(&w, 10u);   /* four_mot */
    w_u16(&w, 1000u); /* rot_vel_top */
    w_u16(&w, 1001u); /* trans_vel_top */
    w_u16(&w, 1002u); /* rot_acc_top */
    w_u16(&w, 1003u); /* trans_acc_top */
    w_u16(&w, 1004u); /* pwm_max */
    w_str(&w, name);
    w_u8(&w, 100u);  /* sip_cycle */
    w_u8(&w, 11u);   /* host_baud */
    w_u8(&w, 12u);   /* aux1_baud */
    w_u16(&w, 1005u); /* has_gripper */
    w_u16(&w, 1006u); /* front_sonar */
    w_u8(&w, 13u);   /* rear_sonar */
    w_u16(&w, 1007u); /* low_battery */
    w_u16(&w, 1008u); /* rev_count */
    w_u16(&w, 2000u); /* watchdog */
    w_u8(&w, 14u);   /* normal_mpacs */
    w_u16(&w, 1009u); /* stall_val */
    w_u16(&w, 1010u); /* stall_count */
    w_u16(&w, 1011u); /* joy_vel */
    w_u16(&w, 1012u); /* joy_rot_vel */
    w_u16(&w, 1013u); /* rot_vel_max */
    w_u16(&w, 1014u); /* trans_vel_max */
    w_u16(&w, 1015u); /* rot_accel */
    w_u16(&w, 1016u); /* rot_decel */
    w_u16(&w, 1017u); /* rot_kp */
    w_u16(&w, 1018u); /* rot_kv */
    w_u16(&w, 1019u); /* rot_ki */
    w_u16(&w, 1020u); /* trans_accel */
    w_u16(&w, 1021u); /* trans_decel */
    w_u16(&w, 1022u); /* trans_kp */
    w_u16(&w, 1023u); /* trans_kv */
    w_u16(&w, 1024u); /* trans_ki */
    w_u8(&w, 15u);   /* front_bumps */
    w_u8(&w, 16u);   /* rear_bumps */
    w_u8(&w, 17u);   /* charger */
    w_u8(&w, 18u);   /* sonar_cycle */
    w_u8(&w, 2u);    /* auto_baud */
    w_u8(&w, 19u);   /* has_gyro */
    w_u16(&w, 0xFF38u); /* drift_factor -200 */
    w_u8(&w, 20u);   /* aux2_baud */
    w_u8(&w, 21u);   /* aux3_baud */
    w_u16(&w, 128u); /* ticks_mm */
    *required = w.len;
    w_u16(&w, 1025u); /* shutdown_volts */
    w_str(&w, "ARCOS 1.9");
    w_u16(&w, 0xBEEFu); /* a later field (GyroCW), ignored */
    return w.len;
}

void test_decode_config_should_recover_every_field_through_ticks_mm(void)
{
    uint8_t payload[RSM_ARIA_MAX_PAYLOAD];
    size_t required;
    size_t len = build_config(payload, sizeof(payload), "Robot1", &required);
    uint8_t frame[RSM_ARIA_MAX_PACKET];
    rsm_aria_packet_t pkt;
    rsm_aria_config_t c;
    int w = rsm_aria_encode_raw((uint8_t)RSM_ARIA_PAC_CONFIG, payload, len, frame, sizeof(frame));

    TEST_ASSERT_TRUE(w > 0);
    feed_one(frame, (size_t)w, &pkt);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_config(&pkt, &c));
    TEST_ASSERT_EQUAL_STRING("Pioneer", c.robot_type);
    TEST_ASSERT_EQUAL_STRING("p3dx-sh", c.subtype);
    TEST_ASSERT_EQUAL_STRING("DX-0042", c.serial_num);
    TEST_ASSERT_EQUAL_UINT8(10u, c.four_mot);
    TEST_ASSERT_EQUAL_UINT16(1000u, c.rot_vel_top);
    TEST_ASSERT_EQUAL_UINT16(1001u, c.trans_vel_top);
    TEST_ASSERT_EQUAL_UINT16(1002u, c.rot_acc_top);
    TEST_ASSERT_EQUAL_UINT16(1003u, c.trans_acc_top);
    TEST_ASSERT_EQUAL_UINT16(1004u, c.pwm_max);
    TEST_ASSERT_EQUAL_STRING("Robot1", c.name);
    TEST_ASSERT_EQUAL_UINT8(100u, c.sip_cycle);
    TEST_ASSERT_EQUAL_UINT8(11u, c.host_baud);
    TEST_ASSERT_EQUAL_UINT8(12u, c.aux1_baud);
    TEST_ASSERT_EQUAL_UINT16(1005u, c.has_gripper);
    TEST_ASSERT_EQUAL_UINT16(1006u, c.front_sonar);
    TEST_ASSERT_EQUAL_UINT8(13u, c.rear_sonar);
    TEST_ASSERT_EQUAL_UINT16(1007u, c.low_battery);
    TEST_ASSERT_EQUAL_UINT16(1008u, c.rev_count);
    TEST_ASSERT_EQUAL_UINT16(2000u, c.watchdog);
    TEST_ASSERT_EQUAL_UINT8(14u, c.normal_mpacs);
    TEST_ASSERT_EQUAL_UINT16(1009u, c.stall_val);
    TEST_ASSERT_EQUAL_UINT16(1010u, c.stall_count);
    TEST_ASSERT_EQUAL_UINT16(1011u, c.joy_vel);
    TEST_ASSERT_EQUAL_UINT16(1012u, c.joy_rot_vel);
    TEST_ASSERT_EQUAL_UINT16(1013u, c.rot_vel_max);
    TEST_ASSERT_EQUAL_UINT16(1014u, c.trans_vel_max);
    TEST_ASSERT_EQUAL_UINT16(1015u, c.rot_accel);
    TEST_ASSERT_EQUAL_UINT16(1016u, c.rot_decel);
    TEST_ASSERT_EQUAL_UINT16(1017u, c.rot_kp);
    TEST_ASSERT_EQUAL_UINT16(1018u, c.rot_kv);
    TEST_ASSERT_EQUAL_UINT16(1019u, c.rot_ki);
    TEST_ASSERT_EQUAL_UINT16(1020u, c.trans_accel);
    TEST_ASSERT_EQUAL_UINT16(1021u, c.trans_decel);
    TEST_ASSERT_EQUAL_UINT16(1022u, c.trans_kp);
    TEST_ASSERT_EQUAL_UINT16(1023u, c.trans_kv);
    TEST_ASSERT_EQUAL_UINT16(1024u, c.trans_ki);
    TEST_ASSERT_EQUAL_UINT8(15u, c.front_bumps);
    TEST_ASSERT_EQUAL_UINT8(16u, c.rear_bumps);
    TEST_ASSERT_EQUAL_UINT8(17u, c.charger);
    TEST_ASSERT_EQUAL_UINT8(18u, c.sonar_cycle);
    TEST_ASSERT_EQUAL_UINT8(2u, c.auto_baud);
    TEST_ASSERT_EQUAL_UINT8(19u, c.has_gyro);
    TEST_ASSERT_EQUAL_INT16(-200, c.drift_factor);
    TEST_ASSERT_EQUAL_UINT8(20u, c.aux2_baud);
    TEST_ASSERT_EQUAL_UINT8(21u, c.aux3_baud);
    TEST_ASSERT_EQUAL_UINT16(128u, c.ticks_mm);
    TEST_ASSERT_EQUAL_UINT16(1025u, c.shutdown_volts);
    TEST_ASSERT_EQUAL_STRING("ARCOS 1.9", c.firmware);
    TEST_ASSERT_EQUAL_HEX32(RSM_ARIA_CONFIG_HAS_SHUTDOWN_VOLTS | RSM_ARIA_CONFIG_HAS_FIRMWARE,
                            c.present);
    TEST_ASSERT_EQUAL_HEX8(0u, c.truncated);
}

void test_decode_config_should_reject_a_packet_ending_before_ticks_mm(void)
{
    uint8_t payload[RSM_ARIA_MAX_PAYLOAD];
    size_t required;
    size_t full = build_config(payload, sizeof(payload), "Robot1", &required);
    size_t len;
    rsm_aria_config_t c;
    rsm_aria_config_t before;

    memset(&c, 0x6B, sizeof(c));
    memcpy(&before, &c, sizeof(c));
    for (len = 0u; len < required; ++len) {
        rsm_aria_packet_t pkt;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x20u, payload, len));
        TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_decode_config(&pkt, &c));
        TEST_ASSERT_EQUAL_MEMORY(&before, &c, sizeof(c));
    }
    /* From TicksMM on, the optional fields appear one by one. */
    for (len = required; len <= full; ++len) {
        rsm_aria_packet_t pkt;
        uint32_t expect = 0u;
        if (len >= required + 2u) {
            expect |= RSM_ARIA_CONFIG_HAS_SHUTDOWN_VOLTS;
        }
        if (len >= required + 3u) {
            expect |= RSM_ARIA_CONFIG_HAS_FIRMWARE;
        }
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x20u, payload, len));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_config(&pkt, &c));
        TEST_ASSERT_EQUAL_UINT16(128u, c.ticks_mm);
        TEST_ASSERT_EQUAL_HEX32(expect, c.present);
        if (len >= required + 12u) {
            TEST_ASSERT_EQUAL_STRING("ARCOS 1.9", c.firmware);
        } else if (len == required + 3u) {
            TEST_ASSERT_EQUAL_STRING("A", c.firmware);
        } else if (len < required + 3u) {
            TEST_ASSERT_EQUAL_STRING("", c.firmware);
        }
    }
}

void test_decode_config_should_cut_long_strings_and_keep_later_fields(void)
{
    char long_name[RSM_ARIA_STR_SIZE + 20u];
    uint8_t payload[RSM_ARIA_MAX_PAYLOAD];
    size_t required;
    size_t len;
    rsm_aria_packet_t pkt;
    rsm_aria_config_t c;

    memset(long_name, 'n', sizeof(long_name) - 1u);
    long_name[sizeof(long_name) - 1u] = '\0';
    len = build_config(payload, sizeof(payload), long_name, &required);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x20u, payload, len));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_config(&pkt, &c));
    TEST_ASSERT_EQUAL_UINT32(RSM_ARIA_STR_SIZE - 1u, (uint32_t)strlen(c.name));
    TEST_ASSERT_EQUAL_MEMORY(long_name, c.name, RSM_ARIA_STR_SIZE - 1u);
    TEST_ASSERT_EQUAL_HEX8(0x08u, c.truncated);
    TEST_ASSERT_EQUAL_UINT8(100u, c.sip_cycle);
    TEST_ASSERT_EQUAL_UINT16(2000u, c.watchdog);
    TEST_ASSERT_EQUAL_UINT16(128u, c.ticks_mm);
    /* A firmware string too long for its array, ended by the payload end. */
    len = required + 2u;
    memset(payload + len, 'f', RSM_ARIA_STR_SIZE + 5u);
    len += RSM_ARIA_STR_SIZE + 5u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x20u, payload, len));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_config(&pkt, &c));
    TEST_ASSERT_EQUAL_UINT32(RSM_ARIA_STR_SIZE - 1u, (uint32_t)strlen(c.firmware));
    TEST_ASSERT_EQUAL_HEX8(0x18u, c.truncated);
    TEST_ASSERT_EQUAL_HEX32(RSM_ARIA_CONFIG_HAS_SHUTDOWN_VOLTS | RSM_ARIA_CONFIG_HAS_FIRMWARE,
                            c.present);
    /* A required string without its NUL. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x20u, payload, 5u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, rsm_aria_decode_config(&pkt, &c));
}

void test_decode_sync2_should_cut_long_names_and_count_missing_strings(void)
{
    uint8_t payload[RSM_ARIA_MAX_PAYLOAD];
    rsm_aria_packet_t pkt;
    rsm_aria_sync2_t s;
    writer_t w;
    char long_name[RSM_ARIA_STR_SIZE + 9u];

    memset(long_name, 'L', sizeof(long_name) - 1u);
    long_name[sizeof(long_name) - 1u] = '\0';
    w.p = payload;
    w.len = 0u;
    w.cap = sizeof(payload);
    w_str(&w, long_name);
    w_str(&w, "Pioneer");
    w_str(&w, "p3dx-sh");
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 2u, payload, w.len));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sync2(&pkt, &s));
    TEST_ASSERT_EQUAL_UINT32(RSM_ARIA_STR_SIZE - 1u, (uint32_t)strlen(s.name));
    TEST_ASSERT_EQUAL_STRING("Pioneer", s.robot_class);
    TEST_ASSERT_EQUAL_STRING("p3dx-sh", s.subclass);
    TEST_ASSERT_EQUAL_UINT8(3u, s.present);
    TEST_ASSERT_EQUAL_HEX8(0x01u, s.truncated);

    /* Name, then a class without its NUL, then nothing. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 2u, V_SYNC2_REPLY_EXAMPLE + 4, 14u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sync2(&pkt, &s));
    TEST_ASSERT_EQUAL_STRING("Robot1", s.name);
    TEST_ASSERT_EQUAL_STRING("Pioneer", s.robot_class);
    TEST_ASSERT_EQUAL_STRING("", s.subclass);
    TEST_ASSERT_EQUAL_UINT8(2u, s.present);

    /* An empty reply. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 2u, NULL, 0u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sync2(&pkt, &s));
    TEST_ASSERT_EQUAL_UINT8(0u, s.present);
    TEST_ASSERT_EQUAL_STRING("", s.name);
}

/* ---- odometry helpers ---------------------------------------------------------------- */

void test_pos_delta15_should_wrap_modulo_32768(void)
{
    TEST_ASSERT_EQUAL_INT16(18, rsm_aria_pos_delta15(10u, 32760u));
    TEST_ASSERT_EQUAL_INT16(-18, rsm_aria_pos_delta15(32760u, 10u));
    TEST_ASSERT_EQUAL_INT16(0, rsm_aria_pos_delta15(1234u, 1234u));
    TEST_ASSERT_EQUAL_INT16(500, rsm_aria_pos_delta15(1500u, 1000u));
    /* Bit 15 is not part of the position. */
    TEST_ASSERT_EQUAL_INT16(18, rsm_aria_pos_delta15((uint16_t)(10u | 0x8000u), 32760u));
    /* The ends of the range. */
    TEST_ASSERT_EQUAL_INT16(16383, rsm_aria_pos_delta15(16383u, 0u));
    TEST_ASSERT_EQUAL_INT16(-16384, rsm_aria_pos_delta15(16384u, 0u));
    TEST_ASSERT_EQUAL_INT16(-1, rsm_aria_pos_delta15(32767u, 0u));
}

void test_odometry_count_delta_should_wrap_aria_counts_modulo_2_pow_32(void)
{
    TEST_ASSERT_EQUAL_INT32(100, rsm_odometry_count_delta((uint32_t)(-2147483596), (uint32_t)(2147483600), 32u));
    TEST_ASSERT_EQUAL_INT32(-100, rsm_odometry_count_delta((uint32_t)(2147483600), (uint32_t)(-2147483596), 32u));
    TEST_ASSERT_EQUAL_INT32(1, rsm_odometry_count_delta((uint32_t)(INT32_MIN), (uint32_t)(INT32_MAX), 32u));
    TEST_ASSERT_EQUAL_INT32(-1, rsm_odometry_count_delta((uint32_t)(INT32_MAX), (uint32_t)(INT32_MIN), 32u));
    TEST_ASSERT_EQUAL_INT32(INT32_MIN, rsm_odometry_count_delta((uint32_t)(INT32_MIN), (uint32_t)(0), 32u));
    TEST_ASSERT_EQUAL_INT32(INT32_MAX, rsm_odometry_count_delta((uint32_t)(INT32_MAX), (uint32_t)(0), 32u));
    TEST_ASSERT_EQUAL_INT32(-777, rsm_odometry_count_delta((uint32_t)(-1000), (uint32_t)(-223), 32u));
}

void test_th_to_rad_should_use_4096_units_per_turn(void)
{
    const float pi = 3.14159265f;
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, rsm_aria_th_to_rad(0));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, pi / 2.0f, rsm_aria_th_to_rad(1024));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, -pi / 2.0f, rsm_aria_th_to_rad(-1024));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, pi, rsm_aria_th_to_rad(2048));
    /* -pi is not in (-pi, pi]: it maps to +pi. */
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, pi, rsm_aria_th_to_rad(-2048));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, -pi + pi / 2048.0f, rsm_aria_th_to_rad(2049));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, rsm_aria_th_to_rad(4096));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, pi / 2.0f, rsm_aria_th_to_rad(5120));
    /* A difference of two THPOS readings, wrapped: 4000 - 100 = -196 units. */
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, -196.0f * pi / 2048.0f, rsm_aria_th_to_rad(4000 - 100 - 4096));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, -196.0f * pi / 2048.0f, rsm_aria_th_to_rad(3900));
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 1024.0f * pi / 2048.0f, rsm_aria_th_to_rad(-32768 + 1024));
}

/* ---- capacities: callers built with other capacities than the library ---------- */

/* The wrong size and the wrong fingerprint the _checked functions refuse:
 * what an application compiled with other capacities passes (a struct of
 * another size, or of the same size by chance). */
#define WRONG_SIZE(obj) (sizeof(obj) - 8u)
#define WRONG_PRINT ((unsigned long)RSM_CONFIG_FINGERPRINT ^ 1ul)
#define OWN_PRINT ((unsigned long)RSM_CONFIG_FINGERPRINT)

void test_parser_init_should_refuse_a_caller_built_with_other_capacities(void)
{
    static rsm_aria_parser_t p;
    static rsm_aria_parser_t before;
    memset(&p, 0x5A, sizeof p);
    memcpy(&before, &p, sizeof p);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_parser_init_checked(&p, WRONG_SIZE(p), OWN_PRINT));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_parser_init_checked(&p, sizeof p, WRONG_PRINT));
    TEST_ASSERT_EQUAL_MEMORY(&before, &p, sizeof p);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&p));
}

void test_parser_feed_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* The packet it would publish is the caller's: nothing is taken, and
     * neither the parser nor the packet nor *consumed is written. */
    static rsm_aria_parser_t p;
    static rsm_aria_parser_t p_before;
    static rsm_aria_packet_t pkt;
    static rsm_aria_packet_t pkt_before;
    size_t used = 77u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_parser_init(&p));
    memcpy(&p_before, &p, sizeof p);
    memset(&pkt, 0x5A, sizeof pkt);
    memcpy(&pkt_before, &pkt, sizeof pkt);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_parser_feed_checked(&p, V_SYNC0, sizeof(V_SYNC0), &used, &pkt,
                                                                       WRONG_SIZE(pkt), OWN_PRINT));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_parser_feed_checked(&p, V_SYNC0, sizeof(V_SYNC0), &used, &pkt,
                                                                       sizeof pkt, WRONG_PRINT));
    TEST_ASSERT_EQUAL_MEMORY(&pkt_before, &pkt, sizeof pkt);
    TEST_ASSERT_EQUAL_MEMORY(&p_before, &p, sizeof p);
    TEST_ASSERT_EQUAL_size_t(77u, used);
    TEST_ASSERT_EQUAL_INT(1, rsm_aria_parser_feed(&p, V_SYNC0, sizeof(V_SYNC0), &used, &pkt));
}

void test_packet_build_should_refuse_a_caller_built_with_other_capacities(void)
{
    static const uint8_t payload[2] = {1u, 2u};
    static rsm_aria_packet_t pkt;
    static rsm_aria_packet_t before;
    memset(&pkt, 0x5A, sizeof pkt);
    memcpy(&before, &pkt, sizeof pkt);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_packet_build_checked(&pkt, WRONG_SIZE(pkt), OWN_PRINT, 0x90u,
                                                                        payload, sizeof payload));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_packet_build_checked(&pkt, sizeof pkt, WRONG_PRINT, 0x90u,
                                                                        payload, sizeof payload));
    TEST_ASSERT_EQUAL_MEMORY(&before, &pkt, sizeof pkt);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_packet_build(&pkt, 0x90u, payload, sizeof payload));
}

void test_decode_sync2_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* RSM_ARIA_STR_SIZE sizes the three strings. */
    static rsm_aria_packet_t pkt;
    static rsm_aria_sync2_t out;
    static rsm_aria_sync2_t before;
    feed_one(V_SYNC2_REPLY_EXAMPLE, sizeof(V_SYNC2_REPLY_EXAMPLE), &pkt);
    memset(&out, 0x5A, sizeof out);
    memcpy(&before, &out, sizeof out);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_decode_sync2_checked(&pkt, &out, WRONG_SIZE(out), OWN_PRINT));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_decode_sync2_checked(&pkt, &out, sizeof out, WRONG_PRINT));
    TEST_ASSERT_EQUAL_MEMORY(&before, &out, sizeof out);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sync2(&pkt, &out));
}

void test_decode_sip_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* RSM_ARIA_MAX_SONAR sizes the readings. */
    static rsm_aria_packet_t pkt;
    static rsm_aria_sip_t out;
    static rsm_aria_sip_t before;
    feed_one(V_SIP_STOPPED_2SONAR, sizeof(V_SIP_STOPPED_2SONAR), &pkt);
    memset(&out, 0x5A, sizeof out);
    memcpy(&before, &out, sizeof out);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_decode_sip_checked(&pkt, &out, WRONG_SIZE(out), OWN_PRINT));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_decode_sip_checked(&pkt, &out, sizeof out, WRONG_PRINT));
    TEST_ASSERT_EQUAL_MEMORY(&before, &out, sizeof out);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_sip(&pkt, &out));
}

void test_decode_config_should_refuse_a_caller_built_with_other_capacities(void)
{
    /* RSM_ARIA_STR_SIZE sizes the five strings. */
    uint8_t payload[RSM_ARIA_MAX_PAYLOAD];
    uint8_t frame[RSM_ARIA_MAX_PACKET];
    size_t required;
    const size_t len = build_config(payload, sizeof(payload), "Robot1", &required);
    const int w = rsm_aria_encode_raw((uint8_t)RSM_ARIA_PAC_CONFIG, payload, len, frame, sizeof(frame));
    static rsm_aria_packet_t pkt;
    static rsm_aria_config_t out;
    static rsm_aria_config_t before;
    TEST_ASSERT_TRUE(w > 0);
    feed_one(frame, (size_t)w, &pkt);
    memset(&out, 0x5A, sizeof out);
    memcpy(&before, &out, sizeof out);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_decode_config_checked(&pkt, &out, WRONG_SIZE(out), OWN_PRINT));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_aria_decode_config_checked(&pkt, &out, sizeof out, WRONG_PRINT));
    TEST_ASSERT_EQUAL_MEMORY(&before, &out, sizeof out);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_aria_decode_config(&pkt, &out));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_checksum_should_match_protocol_worked_examples);
    RUN_TEST(test_encode_sync0_should_match_aria_sync0);
    RUN_TEST(test_encode_sync1_should_match_aria_sync1);
    RUN_TEST(test_encode_sync2_should_match_aria_sync2);
    RUN_TEST(test_encode_pulse_should_match_aria_pulse);
    RUN_TEST(test_encode_open_int1_should_match_aria_open_int1);
    RUN_TEST(test_encode_close_int1_should_match_aria_close_int1);
    RUN_TEST(test_encode_enable_should_match_aria_enable_1);
    RUN_TEST(test_encode_enable_should_match_aria_enable_0);
    RUN_TEST(test_encode_sonar_should_match_aria_sonar_0);
    RUN_TEST(test_encode_seta_should_match_aria_seta_1000);
    RUN_TEST(test_encode_seta_should_match_aria_seta_neg1000);
    RUN_TEST(test_encode_seto_should_match_aria_seto);
    RUN_TEST(test_encode_encoder_should_match_aria_encoder_on);
    RUN_TEST(test_encode_int_should_match_aria_encoder_once);
    RUN_TEST(test_encode_encoder_should_match_aria_encoder_off);
    RUN_TEST(test_encode_config_should_match_aria_config_request);
    RUN_TEST(test_encode_vel_should_match_aria_vel_300);
    RUN_TEST(test_encode_vel_should_match_aria_vel_neg300);
    RUN_TEST(test_encode_rvel_should_match_aria_rvel_neg30);
    RUN_TEST(test_encode_rotate_should_match_aria_rotate_15);
    RUN_TEST(test_encode_head_should_match_aria_head_90);
    RUN_TEST(test_encode_dhead_should_match_aria_dhead_neg45);
    RUN_TEST(test_encode_move_should_match_aria_move_500);
    RUN_TEST(test_encode_stop_should_match_aria_stop);
    RUN_TEST(test_encode_estop_should_match_aria_estop);
    RUN_TEST(test_encode_hostbaud_should_match_aria_hostbaud_38400);
    RUN_TEST(test_encode_vel2_should_match_aria_vel2_left_plus100_right_minus100);
    RUN_TEST(test_encode_vel2_should_match_aria_vel2_left_minus100_right_plus100);
    RUN_TEST(test_encode_tty2_should_match_aria_str_tty2_AB);
    RUN_TEST(test_decode_sync_should_recognise_aria_sync0_sync1_sync2_echoes);
    RUN_TEST(test_decode_sync2_should_recover_aria_sync2_reply_example);
    RUN_TEST(test_decode_sip_should_recover_aria_sip_stopped_2sonar);
    RUN_TEST(test_decode_sip_should_recover_aria_sip_moving_wrapped);
    RUN_TEST(test_decode_encoder_should_recover_aria_encoder_packet);
    RUN_TEST(test_decode_encoder_should_recover_aria_encoder_packet_wrapped);
    RUN_TEST(test_encode_int_should_reject_magnitudes_above_32767);
    RUN_TEST(test_encode_should_leave_buffer_untouched_when_capacity_is_short);
    RUN_TEST(test_encode_tty2_should_fail_with_nomem_when_string_is_too_long_for_buffer);
    RUN_TEST(test_encode_str_should_reject_strings_longer_than_the_payload_limit);
    RUN_TEST(test_encode_should_reject_null_pointers_and_unknown_kinds);
    RUN_TEST(test_encode_should_reject_out_of_range_command_arguments);
    RUN_TEST(test_baud_code_should_map_the_five_host_rates);
    RUN_TEST(test_encode_vel2_should_round_trip_every_wheel_pair);
    RUN_TEST(test_encode_raw_should_frame_byte_count_255_and_reject_more);
    RUN_TEST(test_parser_feed_should_reject_invalid_arguments);
    RUN_TEST(test_parser_feed_should_publish_unknown_ids);
    RUN_TEST(test_parser_feed_should_not_end_a_packet_at_sync_bytes_in_its_payload);
    RUN_TEST(test_parser_feed_should_count_bad_length_for_byte_counts_0_1_2);
    RUN_TEST(test_parser_feed_should_handle_byte_count_255);
    RUN_TEST(test_parser_feed_should_find_a_frame_inside_a_failed_candidate);
    RUN_TEST(test_parser_timeout_should_release_a_frame_held_in_a_partial_candidate);
    RUN_TEST(test_parser_timeout_should_keep_bytes_from_before_the_silence_apart);
    RUN_TEST(test_parser_timeout_should_do_nothing_when_idle);
    RUN_TEST(test_parser_feed_should_lose_no_frame_to_garbage_before_and_between_frames);
    RUN_TEST(test_parser_feed_should_lose_only_the_frames_with_garbage_inside);
    RUN_TEST(test_parser_feed_should_give_the_same_result_one_byte_at_a_time);
    RUN_TEST(test_parser_feed_should_hold_at_most_one_frame_of_bytes);
    RUN_TEST(test_parser_feed_should_recover_from_a_flipped_bit_anywhere_in_a_sip);
    RUN_TEST(test_parser_feed_should_recover_from_a_flipped_bit_anywhere_in_an_encoder_packet);
    RUN_TEST(test_parser_timeout_should_count_a_sip_cut_at_every_offset_as_truncated);
    RUN_TEST(test_parser_timeout_should_count_an_encoder_packet_cut_at_every_offset_as_truncated);
    RUN_TEST(test_parser_feed_should_recover_frames_after_a_cut_sip_without_timeout);
    RUN_TEST(test_parser_feed_should_recover_frames_after_a_cut_encoder_packet_without_timeout);
    RUN_TEST(test_decode_sip_should_reject_a_sip_shorter_than_its_sonar_count);
    RUN_TEST(test_decode_sip_should_decode_the_optional_tail);
    RUN_TEST(test_decode_sip_should_flag_optional_fields_only_when_complete);
    RUN_TEST(test_decode_sip_should_keep_at_most_max_sonar_readings);
    RUN_TEST(test_decode_sip_should_mask_xpos_and_ypos_to_15_bits);
    RUN_TEST(test_decode_should_reject_wrong_ids_and_inconsistent_packets);
    RUN_TEST(test_packet_build_should_match_the_receiver_output);
    RUN_TEST(test_decode_encoder_should_need_8_bytes_and_ignore_extra_ones);
    RUN_TEST(test_decode_encoder_should_give_exact_deltas_across_counter_wrap_around);
    RUN_TEST(test_decode_config_should_recover_every_field_through_ticks_mm);
    RUN_TEST(test_decode_config_should_reject_a_packet_ending_before_ticks_mm);
    RUN_TEST(test_decode_config_should_cut_long_strings_and_keep_later_fields);
    RUN_TEST(test_decode_sync2_should_cut_long_names_and_count_missing_strings);
    RUN_TEST(test_pos_delta15_should_wrap_modulo_32768);
    RUN_TEST(test_odometry_count_delta_should_wrap_aria_counts_modulo_2_pow_32);
    RUN_TEST(test_th_to_rad_should_use_4096_units_per_turn);
    RUN_TEST(test_parser_init_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_parser_feed_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_packet_build_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_decode_sync2_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_decode_sip_should_refuse_a_caller_built_with_other_capacities);
    RUN_TEST(test_decode_config_should_refuse_a_caller_built_with_other_capacities);
    return UNITY_END();
}
