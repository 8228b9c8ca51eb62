/* libFuzzer target for the LD06 / LD19 codec (src/drivers/ld06.c).
 *
 * The input is a byte stream as it could come from the sensor. It is fed
 * to one receiver in chunks whose sizes come from the input and, byte by
 * byte, to a second one; both must publish the same packets and end with
 * the same counters, every byte accounted for. Every published packet must
 * encode back to the bytes that carried it and give 12 points in range.
 * Failed invariants stop the run with __builtin_trap(). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "rsm/ld06.h"
#include "rsm/status.h"

#include "fuzz_check.h"

typedef struct run_state {
    rsm_ld06_parser_t parser;
    uint32_t digest;
} run_state_t;

static void take(run_state_t *rs, const rsm_ld06_packet_t *pkt)
{
    uint8_t again[RSM_LD06_PACKET];
    rsm_ld06_packet_t back;
    rsm_lidar_point_t pts[RSM_LD06_POINTS];
    size_t i;
    CHECK(pkt->start_cdeg < RSM_LD06_MAX_CDEG && pkt->end_cdeg < RSM_LD06_MAX_CDEG);
    CHECK(rsm_ld06_encode(pkt, again, sizeof again) == (int)RSM_LD06_PACKET);
    CHECK(rsm_ld06_decode(again, &back) == RSM_OK);
    CHECK(memcmp(&back, pkt, sizeof back) == 0);
    CHECK(rsm_ld06_points(pkt, pts) == (int)RSM_LD06_POINTS);
    for (i = 0; i < RSM_LD06_POINTS; ++i) {
        CHECK(pts[i].angle_deg >= 0.0f && pts[i].angle_deg < 360.0f);
        CHECK(pts[i].range_m >= 0.0f && pts[i].range_m < 65.6f);
    }
    for (i = 0; i < RSM_LD06_PACKET; ++i) {
        rs->digest = (rs->digest ^ again[i]) * 16777619u;
    }
}

static void feed(run_state_t *rs, const uint8_t *data, size_t len)
{
    size_t done = 0;
    for (;;) {
        rsm_ld06_packet_t pkt;
        size_t used = (size_t)-1;
        const int r = rsm_ld06_parser_feed(&rs->parser, data + done, len - done, &used, &pkt);
        CHECK(r == 0 || r == 1);
        CHECK(used <= len - done);
        done += used;
        CHECK(rs->parser.stats.bytes_fed == rs->parser.stats.bytes_skipped +
                                                RSM_LD06_PACKET * rs->parser.stats.packets_ok +
                                                (uint32_t)rsm_ld06_parser_pending(&rs->parser));
        if (r == 0) {
            CHECK(done == len);
            return;
        }
        take(rs, &pkt);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    run_state_t chunked;
    run_state_t bytewise;
    uint32_t rng = 0x9E3779B9u ^ (uint32_t)size;
    size_t off = 0;
    size_t i;

    CHECK(rsm_ld06_parser_init(&chunked.parser) == RSM_OK);
    CHECK(rsm_ld06_parser_init(&bytewise.parser) == RSM_OK);
    chunked.digest = bytewise.digest = 2166136261u;
    while (off < size) {
        const size_t chunk = fuzz_next_chunk(&rng, size - off, 97u);
        feed(&chunked, data + off, chunk);
        off += chunk;
    }
    for (i = 0; i < size; ++i) {
        feed(&bytewise, data + i, 1u);
    }
    CHECK(chunked.digest == bytewise.digest);
    CHECK(memcmp(&chunked.parser.stats, &bytewise.parser.stats, sizeof chunked.parser.stats) == 0);
    CHECK(chunked.parser.stats.bytes_fed == (uint32_t)size);
    i = rsm_ld06_parser_pending(&chunked.parser);
    CHECK(rsm_ld06_parser_flush(&chunked.parser) == (int)i);
    CHECK(chunked.parser.stats.bytes_skipped + RSM_LD06_PACKET * chunked.parser.stats.packets_ok ==
          (uint32_t)size);
    if (size >= RSM_LD06_PACKET) {
        rsm_ld06_packet_t pkt;
        const int rc = rsm_ld06_decode(data, &pkt);
        CHECK(rc == RSM_OK || rc == RSM_ERR_PROTO || rc == RSM_ERR_CHECKSUM || rc == RSM_ERR_RANGE);
    }
    return 0;
}
