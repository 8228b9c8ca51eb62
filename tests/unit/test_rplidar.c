/* Unit tests of the RPLIDAR codec (src/drivers/rplidar.c): requests, descriptors
 * and answers of tests/data/rplidar_frames.txt; capsules laid out here from
 * the documented layout; the receiver under garbage, bit flips, truncation
 * and arbitrary chunking, with exact counters. */
#include "unity.h"

#include <stdint.h>
#include <string.h>

#include "rsm/rplidar.h"
#include "rsm/status.h"
#include "test_support.h"

void setUp(void) {}
void tearDown(void) {}

#define DATA "tests/data/rplidar_frames.txt"
#define CAP RSM_RPLIDAR_CAPSULE
#define MAX_EVENTS 64u

static size_t load_bytes(const char *key, size_t idx, uint8_t *out, size_t cap)
{
    unsigned long v[512];
    size_t n = rsm_test_data_values(DATA, key, idx, 16, v, cap < 512u ? cap : 512u);
    size_t i;
    TEST_ASSERT_TRUE(n > 0u);
    for (i = 0; i < n; ++i) {
        out[i] = (uint8_t)v[i];
    }
    return n;
}

static void assert_invariant(const rsm_rplidar_parser_t *p)
{
    TEST_ASSERT_EQUAL_UINT32(p->stats.bytes_fed,
                             p->stats.bytes_skipped + p->stats.bytes_framed +
                                 (uint32_t)rsm_rplidar_parser_pending(p));
}

/* Events of one run; the receiver is fed in chunks from the generator
 * (seed 0: everything at once). */
typedef struct run {
    rsm_rplidar_parser_t p;
    rsm_rplidar_event_t ev[MAX_EVENTS];
    size_t n;
} run_t;

static void feed(run_t *r, const uint8_t *data, size_t len, uint32_t seed)
{
    size_t off = 0;
    while (off < len) {
        const size_t chunk = rsm_test_chunk(&seed, len - off, 90u);
        size_t done = 0;
        while (done < chunk) {
            size_t used = 0;
            rsm_rplidar_event_t e;
            const int rc = rsm_rplidar_parser_feed(&r->p, data + off + done, chunk - done, &used, &e);
            TEST_ASSERT_TRUE(rc == 0 || rc == 1);
            done += used;
            if (rc == 1) {
                TEST_ASSERT_TRUE(r->n < MAX_EVENTS);
                r->ev[r->n++] = e;
            } else {
                TEST_ASSERT_EQUAL_INT(RSM_RPLIDAR_EVENT_NONE, e.type);
            }
            assert_invariant(&r->p);
        }
        off += chunk;
    }
}

static void run_init(run_t *r)
{
    memset(r, 0, sizeof *r);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rplidar_parser_init(&r->p));
}

/* ---- capsules laid out from the documented layout --------------------- */

static void seal(uint8_t *c, uint16_t start_q6, int new_turn)
{
    uint8_t sum = 0;
    size_t i;
    const uint16_t w = (uint16_t)(start_q6 | (new_turn ? 0x8000u : 0u));
    c[2] = (uint8_t)(w & 0xFF);
    c[3] = (uint8_t)(w >> 8);
    for (i = 2; i < CAP; ++i) {
        sum ^= c[i];
    }
    c[0] = (uint8_t)(0xA0u | (sum & 0x0Fu));
    c[1] = (uint8_t)(0x50u | (sum >> 4));
}

/* A dense capsule: 40 distances, mm. */
static void dense(uint8_t *c, uint16_t start_q6, int new_turn, uint16_t mm0)
{
    size_t k;
    for (k = 0; k < 40u; ++k) {
        const uint16_t d = (uint16_t)(mm0 + k);
        c[4 + 2 * k] = (uint8_t)(d & 0xFF);
        c[5 + 2 * k] = (uint8_t)(d >> 8);
    }
    seal(c, start_q6, new_turn);
}

/* The capsule checksum rule, written out again. */
static int sum_ok(const uint8_t *c)
{
    uint8_t x = 0;
    size_t i;
    for (i = 2; i < CAP; ++i) {
        x ^= c[i];
    }
    return (c[0] >> 4) == 0xA && (c[1] >> 4) == 0x5 && x == (uint8_t)((c[0] & 0x0F) | (c[1] << 4));
}

static const uint8_t dense_descriptor[7] = {0xA5, 0x5A, 0x54, 0x00, 0x00, 0x40, 0x85};

/* ---- requests, descriptors, answers ------------------------------------ */

void test_encoders_reproduce_the_data_file_requests(void)
{
    uint8_t want[16];
    uint8_t out[16];
    static const uint8_t plain[5] = {RSM_RPLIDAR_CMD_STOP, RSM_RPLIDAR_CMD_RESET,
                                     RSM_RPLIDAR_CMD_SCAN, RSM_RPLIDAR_CMD_GET_INFO,
                                     RSM_RPLIDAR_CMD_GET_HEALTH};
    size_t i;
    size_t n;
    for (i = 0; i < 5u; ++i) {
        n = load_bytes("request", i, want, sizeof want);
        TEST_ASSERT_EQUAL_INT((int)n, rsm_rplidar_encode_request(out, sizeof out, plain[i], NULL, 0));
        TEST_ASSERT_EQUAL_HEX8_ARRAY(want, out, n);
    }
    n = load_bytes("request", 5, want, sizeof want);
    TEST_ASSERT_EQUAL_INT((int)n, rsm_rplidar_encode_express_scan(out, sizeof out));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want, out, n);
    n = load_bytes("request", 6, want, sizeof want);
    TEST_ASSERT_EQUAL_INT((int)n, rsm_rplidar_encode_motor(out, sizeof out, RSM_RPLIDAR_CMD_MOTOR_SPEED, 600));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want, out, n);
    n = load_bytes("request", 7, want, sizeof want);
    TEST_ASSERT_EQUAL_INT((int)n, rsm_rplidar_encode_motor(out, sizeof out, RSM_RPLIDAR_CMD_MOTOR_PWM, 660));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want, out, n);
    /* errors write nothing */
    memset(out, 0xEE, sizeof out);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rsm_rplidar_encode_express_scan(out, 8));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rplidar_encode_motor(out, sizeof out, 0x20, 1));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rplidar_encode_request(out, sizeof out, 0x20, NULL, 1));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rplidar_encode_descriptor(out, sizeof out, 5, 2, 0x81));
    TEST_ASSERT_EQUAL_HEX8(0xEE, out[0]);
    TEST_ASSERT_EQUAL_INT(7, rsm_rplidar_encode_descriptor(out, sizeof out, 84, 1, 0x85));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(dense_descriptor, out, 7);
}

void test_info_and_health_answers_decode(void)
{
    uint8_t b[64];
    size_t n = load_bytes("info", 0, b, sizeof b);
    size_t m;
    run_t r;
    size_t i;
    m = load_bytes("health", 0, b + n, sizeof b - n);
    run_init(&r);
    feed(&r, b, n + m, 0);
    TEST_ASSERT_EQUAL_size_t(4, r.n);
    TEST_ASSERT_EQUAL_INT(RSM_RPLIDAR_EVENT_DESCRIPTOR, r.ev[0].type);
    TEST_ASSERT_EQUAL_HEX8(RSM_RPLIDAR_ANS_INFO, r.ev[0].answer);
    TEST_ASSERT_EQUAL_INT(RSM_RPLIDAR_EVENT_INFO, r.ev[1].type);
    TEST_ASSERT_EQUAL_HEX8(0x18, r.ev[1].info.model);
    TEST_ASSERT_EQUAL_UINT8(1, r.ev[1].info.firmware_major);
    TEST_ASSERT_EQUAL_UINT8(29, r.ev[1].info.firmware_minor);
    TEST_ASSERT_EQUAL_UINT8(7, r.ev[1].info.hardware);
    for (i = 0; i < 16u; ++i) {
        TEST_ASSERT_EQUAL_HEX8(0x11u * i, r.ev[1].info.serial[i]);
    }
    TEST_ASSERT_EQUAL_INT(RSM_RPLIDAR_EVENT_DESCRIPTOR, r.ev[2].type);
    TEST_ASSERT_EQUAL_INT(RSM_RPLIDAR_EVENT_HEALTH, r.ev[3].type);
    TEST_ASSERT_EQUAL_UINT8(RSM_RPLIDAR_HEALTH_WARNING, r.ev[3].health.status);
    TEST_ASSERT_EQUAL_HEX16(0x1234, r.ev[3].health.error_code);
    TEST_ASSERT_EQUAL_UINT32(2, r.p.stats.descriptors);
    TEST_ASSERT_EQUAL_UINT32(2, r.p.stats.responses);
    TEST_ASSERT_EQUAL_UINT32(n + m, r.p.stats.bytes_framed);
    TEST_ASSERT_EQUAL_UINT32(0, r.p.stats.bytes_skipped);
}

void test_standard_scan_nodes_decode(void)
{
    uint8_t b[32];
    const size_t n = load_bytes("nodes", 0, b, sizeof b);
    run_t r;
    run_init(&r);
    feed(&r, b, n, 0);
    TEST_ASSERT_EQUAL_size_t(3, r.n);
    TEST_ASSERT_EQUAL_HEX8(RSM_RPLIDAR_ANS_NODE, r.ev[0].answer);
    TEST_ASSERT_EQUAL_INT(RSM_RPLIDAR_EVENT_POINTS, r.ev[1].type);
    TEST_ASSERT_EQUAL_size_t(1, r.ev[1].count);
    TEST_ASSERT_EQUAL_UINT8(1, r.ev[1].points[0].start);
    TEST_ASSERT_EQUAL_UINT8(15, r.ev[1].points[0].quality);
    TEST_ASSERT_EQUAL_FLOAT(90.5f, r.ev[1].points[0].angle_deg);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 1.2345f, r.ev[1].points[0].range_m);
    TEST_ASSERT_EQUAL_UINT8(0, r.ev[2].points[0].start);
    TEST_ASSERT_EQUAL_FLOAT(359.984375f, r.ev[2].points[0].angle_deg);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, r.ev[2].points[0].range_m);
    TEST_ASSERT_EQUAL_UINT32(2, r.p.stats.nodes);
    TEST_ASSERT_EQUAL_UINT32(0, r.p.stats.bad_nodes + r.p.stats.bytes_skipped);
}

/* The listed samples of the first capsule of a capsule stream. */
static void check_capsule_vector(const char *key, size_t nsamples)
{
    uint8_t b[7 + 2 * CAP];
    unsigned long s[12];
    size_t i;
    run_t r;
    const size_t n = load_bytes(key, 0, b, sizeof b);
    const size_t idx = strcmp(key, "express") == 0 ? 0u : 1u;
    TEST_ASSERT_EQUAL_size_t(sizeof b, n);
    TEST_ASSERT_EQUAL_size_t(12, rsm_test_data_values(DATA, "samples", idx, 10, s, 12));
    run_init(&r);
    feed(&r, b, n, 0);
    TEST_ASSERT_EQUAL_size_t(2, r.n); /* descriptor, then the first capsule's samples */
    TEST_ASSERT_EQUAL_INT(RSM_RPLIDAR_EVENT_POINTS, r.ev[1].type);
    TEST_ASSERT_EQUAL_size_t(nsamples, r.ev[1].count);
    for (i = 0; i < 4u; ++i) {
        const rsm_lidar_point_t *pt = &r.ev[1].points[s[3 * i]];
        TEST_ASSERT_FLOAT_WITHIN(1e-4f, (float)s[3 * i + 1] / 10000.0f, pt->angle_deg);
        TEST_ASSERT_FLOAT_WITHIN(1e-6f, (float)s[3 * i + 2] / 1000.0f, pt->range_m);
    }
    for (i = 0; i < nsamples; ++i) {
        TEST_ASSERT_TRUE(r.ev[1].points[i].angle_deg >= 0.0f && r.ev[1].points[i].angle_deg < 360.0f);
    }
    TEST_ASSERT_EQUAL_UINT32(2, r.p.stats.capsules);
    TEST_ASSERT_EQUAL_UINT32(nsamples, r.p.stats.points);
    TEST_ASSERT_EQUAL_UINT32(0, r.p.stats.bytes_skipped + r.p.stats.unpaired);
}

void test_express_capsules_decode_with_angle_offsets(void)
{
    check_capsule_vector("express", 32);
}

void test_dense_capsules_decode_across_zero(void)
{
    check_capsule_vector("dense", 40);
}

/* ---- receiver faults ---------------------------------------------------- */

#define NCAPS 5u

/* descriptor + NCAPS dense capsules 25 deg apart */
static size_t dense_stream(uint8_t *s)
{
    size_t len = 0;
    unsigned k;
    memcpy(s, dense_descriptor, 7);
    len = 7;
    for (k = 0; k < NCAPS; ++k) {
        dense(s + len, (uint16_t)(k * 1600u), 0, (uint16_t)(1000u + 100u * k));
        len += CAP;
    }
    return len;
}

void test_any_chunking_gives_the_same_events_and_counters(void)
{
    uint8_t s[7 + NCAPS * CAP + 40];
    size_t len = dense_stream(s);
    static run_t whole;
    static run_t chunked;
    uint32_t seed;
    run_init(&whole);
    feed(&whole, s, len, 0);
    TEST_ASSERT_EQUAL_size_t(NCAPS, whole.n); /* descriptor + 4 capsules' samples */
    TEST_ASSERT_EQUAL_UINT32(4u * 40u, whole.p.stats.points);
    TEST_ASSERT_EQUAL_FLOAT(1000.0f * 0.001f, whole.ev[1].points[0].range_m);
    TEST_ASSERT_EQUAL_FLOAT(25.0f * 3.0f + 25.0f * 39.0f / 40.0f, whole.ev[4].points[39].angle_deg);
    for (seed = 1; seed < 60u; ++seed) {
        size_t i;
        run_init(&chunked);
        feed(&chunked, s, len, seed * 2246822519u);
        TEST_ASSERT_EQUAL_size_t(whole.n, chunked.n);
        for (i = 0; i < whole.n; ++i) {
            TEST_ASSERT_EQUAL_MEMORY(&whole.ev[i], &chunked.ev[i], sizeof whole.ev[i]);
        }
        TEST_ASSERT_EQUAL_MEMORY(&whole.p.stats, &chunked.p.stats, sizeof whole.p.stats);
    }
}

void test_every_single_bit_flip_in_a_capsule_is_caught(void)
{
    uint8_t clean[7 + NCAPS * CAP];
    const size_t len = dense_stream(clean);
    size_t bit;
    for (bit = 0; bit < CAP * 8u; ++bit) {
        static run_t r;
        uint8_t s[sizeof clean];
        memcpy(s, clean, len);
        s[7 + 2 * CAP + bit / 8u] ^= (uint8_t)(1u << (bit % 8u)); /* capsule 2 */
        run_init(&r);
        feed(&r, s, len, (uint32_t)bit + 1u);
        /* capsule 2 lost: capsules 1 and 2 publish nothing (no successor,
         * no trusted one), 0->1 and 3->4 do */
        TEST_ASSERT_EQUAL_size_t(3, r.n);
        TEST_ASSERT_EQUAL_FLOAT(0.0f, r.ev[1].points[0].angle_deg);
        TEST_ASSERT_EQUAL_FLOAT(75.0f, r.ev[2].points[0].angle_deg);
        TEST_ASSERT_EQUAL_UINT32(CAP, r.p.stats.bytes_skipped);
        TEST_ASSERT_EQUAL_UINT32(NCAPS - 1u, r.p.stats.capsules);
        TEST_ASSERT_EQUAL_UINT32(1, r.p.stats.unpaired);
        /* a flip in a sync nibble rejects at once; anywhere else the
         * checksum (a XOR of every byte) catches it */
        TEST_ASSERT_EQUAL_UINT32((bit < 16u && bit % 8u >= 4u) ? 0u : 1u, r.p.stats.checksum_errors);
    }
}

void test_truncated_capsule_is_skipped_and_the_next_one_found(void)
{
    size_t keep;
    for (keep = 1; keep < CAP; ++keep) {
        static run_t r;
        uint8_t s[7 + NCAPS * CAP];
        size_t len = dense_stream(s);
        /* cut capsule 2 after keep bytes */
        memmove(s + 7 + 2 * CAP + keep, s + 7 + 3 * CAP, 2 * CAP);
        len -= CAP - keep;
        run_init(&r);
        feed(&r, s, len, (uint32_t)keep);
        TEST_ASSERT_EQUAL_size_t(3, r.n);
        TEST_ASSERT_EQUAL_UINT32(keep, r.p.stats.bytes_skipped);
        TEST_ASSERT_EQUAL_UINT32(NCAPS - 1u, r.p.stats.capsules);
        /* the cut capsule and the next one's first bytes may carry a valid
         * checksum by chance (1 in 256, here at keep 39): accepted, then the
         * next capsule's rest is the garbage; the counts stay the same */
        TEST_ASSERT_EQUAL_UINT32(keep >= 2u && !sum_ok(s + 7 + 2 * CAP) ? 1u : 0u,
                                 r.p.stats.checksum_errors);
    }
}

void test_new_turn_flag_and_far_successor_leave_a_capsule_unpaired(void)
{
    uint8_t s[7 + 3 * CAP];
    run_t r;
    memcpy(s, dense_descriptor, 7);
    dense(s + 7, 0, 0, 500);
    dense(s + 7 + CAP, 1600, 1, 600);      /* new turn: capsule 0 has no successor */
    dense(s + 7 + 2 * CAP, 1600 + 12000, 0, 700); /* 187.5 deg later: too far */
    run_init(&r);
    feed(&r, s, sizeof s, 0);
    TEST_ASSERT_EQUAL_size_t(1, r.n);
    TEST_ASSERT_EQUAL_UINT32(2, r.p.stats.unpaired);
    TEST_ASSERT_EQUAL_UINT32(3, r.p.stats.capsules);
    TEST_ASSERT_EQUAL_UINT32(0, r.p.stats.points);
}

void test_garbage_bad_descriptor_and_bad_nodes_are_counted(void)
{
    uint8_t s[64];
    size_t len = 0;
    run_t r;
    static const uint8_t garbage[3] = {0x00, 0x13, 0x5A};
    static const uint8_t unknown[7] = {0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x99};
    uint8_t nodes[32];
    const size_t n = load_bytes("nodes", 0, nodes, sizeof nodes);
    memcpy(s, garbage, 3);
    len = 3;
    memcpy(s + len, unknown, 7);
    len += 7;
    memcpy(s + len, nodes, 7); /* the scan descriptor */
    len += 7;
    s[len++] = 0x3C; /* S = 0 and not-S = 0: no node starts here */
    memcpy(s + len, nodes + 7, n - 7);
    len += n - 7;
    run_init(&r);
    feed(&r, s, len, 0);
    TEST_ASSERT_EQUAL_size_t(3, r.n);
    TEST_ASSERT_EQUAL_UINT32(1, r.p.stats.bad_descriptors);
    TEST_ASSERT_EQUAL_UINT32(1, r.p.stats.bad_nodes);
    TEST_ASSERT_EQUAL_UINT32(3 + 7 + 1, r.p.stats.bytes_skipped);
    TEST_ASSERT_EQUAL_UINT32(2, r.p.stats.nodes);
}

void test_expect_drops_a_partial_answer_and_awaits_a_descriptor(void)
{
    uint8_t s[7 + NCAPS * CAP];
    const size_t len = dense_stream(s);
    run_t r;
    run_init(&r);
    feed(&r, s, 7 + CAP + 30, 0);
    TEST_ASSERT_EQUAL_size_t(30, rsm_rplidar_parser_pending(&r.p));
    TEST_ASSERT_EQUAL_INT(30, rsm_rplidar_parser_expect(&r.p));
    TEST_ASSERT_EQUAL_UINT32(1, r.p.stats.truncated);
    TEST_ASSERT_EQUAL_UINT32(1, r.p.stats.unpaired); /* capsule 0 waited */
    assert_invariant(&r.p);
    /* capsules without a descriptor are garbage now */
    feed(&r, s + 7 + 2 * CAP, CAP, 0);
    TEST_ASSERT_EQUAL_UINT32(30 + CAP, r.p.stats.bytes_skipped);
    feed(&r, s, len, 0);
    TEST_ASSERT_EQUAL_UINT32(1u + NCAPS, r.p.stats.capsules);
    TEST_ASSERT_EQUAL_UINT32(2, r.p.stats.descriptors);
}

void test_parser_rejects_bad_arguments(void)
{
    rsm_rplidar_parser_t p;
    rsm_rplidar_event_t e;
    size_t used = 3;
    const uint8_t b = 0xA5;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rplidar_parser_init(NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rplidar_parser_expect(NULL));
    (void)rsm_rplidar_parser_init(&p);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rplidar_parser_feed(&p, NULL, 1, &used, &e));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rplidar_parser_feed(&p, &b, 1, NULL, &e));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_rplidar_parser_feed(&p, &b, 1, &used, NULL));
    TEST_ASSERT_EQUAL_UINT32(0, p.stats.bytes_fed);
    TEST_ASSERT_EQUAL_size_t(0, rsm_rplidar_parser_pending(NULL));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_encoders_reproduce_the_data_file_requests);
    RUN_TEST(test_info_and_health_answers_decode);
    RUN_TEST(test_standard_scan_nodes_decode);
    RUN_TEST(test_express_capsules_decode_with_angle_offsets);
    RUN_TEST(test_dense_capsules_decode_across_zero);
    RUN_TEST(test_any_chunking_gives_the_same_events_and_counters);
    RUN_TEST(test_every_single_bit_flip_in_a_capsule_is_caught);
    RUN_TEST(test_truncated_capsule_is_skipped_and_the_next_one_found);
    RUN_TEST(test_new_turn_flag_and_far_successor_leave_a_capsule_unpaired);
    RUN_TEST(test_garbage_bad_descriptor_and_bad_nodes_are_counted);
    RUN_TEST(test_expect_drops_a_partial_answer_and_awaits_a_descriptor);
    RUN_TEST(test_parser_rejects_bad_arguments);
    return UNITY_END();
}
