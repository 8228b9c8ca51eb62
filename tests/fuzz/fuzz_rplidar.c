/* libFuzzer target for the RPLIDAR codec (src/drivers/rplidar.c).
 *
 * The input's first byte chooses when the driver would have sent a request
 * (rsm_rplidar_parser_expect every so many bytes, or never); the rest is a
 * byte stream from the sensor. It is fed to one receiver in chunks whose
 * sizes come from the input and, byte by byte, to a second one (with the
 * expect calls at the same stream offsets); both must publish the same
 * events and end with the same counters, every byte accounted for.
 * Failed invariants stop the run with __builtin_trap(). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "rsm/rplidar.h"
#include "rsm/status.h"

#include "fuzz_check.h"

typedef struct run_state {
    rsm_rplidar_parser_t parser;
    uint32_t digest;
    size_t fed;
} run_state_t;

static uint32_t mix(uint32_t h, const void *p, size_t n)
{
    const uint8_t *b = (const uint8_t *)p;
    size_t i;
    for (i = 0; i < n; ++i) {
        h = (h ^ b[i]) * 16777619u;
    }
    return h;
}

static void take(run_state_t *rs, const rsm_rplidar_event_t *ev)
{
    size_t i;
    CHECK(ev->type >= RSM_RPLIDAR_EVENT_DESCRIPTOR && ev->type <= RSM_RPLIDAR_EVENT_POINTS);
    CHECK(ev->count <= RSM_RPLIDAR_MAX_POINTS);
    CHECK(ev->type == RSM_RPLIDAR_EVENT_POINTS || ev->count == 0u);
    for (i = 0; i < ev->count; ++i) {
        CHECK(ev->points[i].angle_deg >= 0.0f && ev->points[i].angle_deg < 360.0f);
        CHECK(ev->points[i].range_m >= 0.0f && ev->points[i].range_m < 65.6f);
    }
    rs->digest = mix(rs->digest, ev, sizeof *ev); /* events are zeroed before filling */
}

static void check_counts(const rsm_rplidar_parser_t *p)
{
    CHECK(p->stats.bytes_fed ==
          p->stats.bytes_skipped + p->stats.bytes_framed + (uint32_t)rsm_rplidar_parser_pending(p));
    CHECK(rsm_rplidar_parser_pending(p) < RSM_RPLIDAR_MAX_FRAME);
}

/* Feeds data, calling expect whenever the stream offset is a multiple of
 * every (0: never). */
static void feed(run_state_t *rs, const uint8_t *data, size_t len, size_t every)
{
    size_t done = 0;
    while (done < len) {
        size_t part = len - done;
        if (every > 0u) {
            const size_t to_next = every - rs->fed % every;
            part = part < to_next ? part : to_next;
        }
        {
            size_t off = 0;
            for (;;) {
                rsm_rplidar_event_t ev;
                size_t used = (size_t)-1;
                const int r = rsm_rplidar_parser_feed(&rs->parser, data + done + off, part - off,
                                                      &used, &ev);
                CHECK(r == 0 || r == 1);
                CHECK(used <= part - off);
                off += used;
                check_counts(&rs->parser);
                if (r == 0) {
                    CHECK(off == part && ev.type == RSM_RPLIDAR_EVENT_NONE);
                    break;
                }
                take(rs, &ev);
            }
        }
        done += part;
        rs->fed += part;
        if (every > 0u && rs->fed % every == 0u) {
            CHECK(rsm_rplidar_parser_expect(&rs->parser) >= 0);
            check_counts(&rs->parser);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    run_state_t chunked;
    run_state_t bytewise;
    uint32_t rng = 0x85EBCA6Bu ^ (uint32_t)size;
    size_t every;
    size_t off = 0;
    size_t i;

    if (size < 1u) {
        return 0;
    }
    every = data[0] < 16u ? 0u : (size_t)data[0] * 3u;
    data++;
    size--;
    memset(&chunked, 0, sizeof chunked);
    memset(&bytewise, 0, sizeof bytewise);
    CHECK(rsm_rplidar_parser_init(&chunked.parser) == RSM_OK);
    CHECK(rsm_rplidar_parser_init(&bytewise.parser) == RSM_OK);
    chunked.digest = bytewise.digest = 2166136261u;
    while (off < size) {
        const size_t chunk = fuzz_next_chunk(&rng, size - off, 173u);
        feed(&chunked, data + off, chunk, every);
        off += chunk;
    }
    for (i = 0; i < size; ++i) {
        feed(&bytewise, data + i, 1u, every);
    }
    CHECK(chunked.digest == bytewise.digest);
    CHECK(memcmp(&chunked.parser.stats, &bytewise.parser.stats, sizeof chunked.parser.stats) == 0);
    CHECK(chunked.parser.stats.bytes_fed == (uint32_t)size);
    return 0;
}
