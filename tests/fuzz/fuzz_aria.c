/* libFuzzer target for the ARIA codec (rsm/aria.h).
 *
 * The input is treated as a received byte stream and run through the
 * receiver four times:
 *   A  all at once, then a line timeout and a drain;
 *   B  one byte per call, same ending;
 *   C  chunk sizes taken from the input itself, same ending;
 *   D  chunk sizes and timeout points taken from the input itself.
 * A, B and C must publish identical packets and end with identical
 * counters, and A must agree with a whole-stream reference model of the
 * receiver rules. Every published packet must be a well-formed frame
 * whose checksum verifies, and goes through every decoder. During each
 * run: consumed <= len, counters never decrease, the held bytes never
 * exceed one frame and the byte conservation law of the stats holds.
 * The input also drives the encoders (command, argument, capacity) and
 * each encoded frame must parse back to itself.
 * Any violation executes __builtin_trap().
 *
 * Seeds: corpus/fuzz_aria/ holds the robot -> host vectors of
 * tests/data/vectors.json as raw files, plus a few streams mixing them with
 * garbage, bit flips, cuts and false headers. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "rsm/aria.h"
#include "rsm/odometry.h"

#include "fuzz_check.h"


int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* What a run produced: packet count, byte total and an order-sensitive hash. */
typedef struct digest {
    uint32_t count;
    uint32_t bytes;
    uint32_t hash;
    rsm_aria_parser_stats_t stats;
} digest_t;

static uint32_t hash_bytes(uint32_t h, const uint8_t *p, size_t n)
{
    size_t i;
    for (i = 0u; i < n; ++i) {
        h = (h ^ p[i]) * 16777619u;
    }
    return h;
}

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

/* The receiver rules over a whole stream that ends with a timeout. */
static void ref_parse(const uint8_t *s, size_t n, digest_t *d)
{
    size_t pos = 0u;
    memset(d, 0, sizeof(*d));
    d->hash = 2166136261u;
    while (pos < n) {
        size_t need = 0u;
        if (s[pos] != 0xFAu || pos + 1u >= n || s[pos + 1u] != 0xFBu) {
            d->stats.bytes_skipped++;
        } else if (pos + 2u >= n) {
            d->stats.truncated++;
        } else if (s[pos + 2u] < 3u) {
            d->stats.bad_length++;
        } else if (pos + (need = (size_t)s[pos + 2u] + 3u) > n) {
            d->stats.truncated++;
        } else if (ref_checksum(s + pos + 3u, need - 5u) !=
                   (uint16_t)((uint32_t)s[pos + need - 2u] * 256u + s[pos + need - 1u])) {
            d->stats.checksum_errors++;
        } else {
            d->stats.packets_ok++;
            d->count++;
            d->bytes += (uint32_t)need;
            d->hash = hash_bytes(d->hash, s + pos, need);
            pos += need;
            continue;
        }
        pos++;
    }
}

static int strings_terminated(const char *s, size_t cap)
{
    return memchr(s, '\0', cap) != NULL;
}

/* Structural checks of one published packet, then every decoder. */
static void check_packet(const rsm_aria_packet_t *pkt)
{
    const uint8_t *f = pkt->frame;
    size_t n = pkt->frame_len;
    const uint8_t *pl = rsm_aria_payload(pkt);
    rsm_aria_packet_t copy;
    int r;

    CHECK(n >= RSM_ARIA_MIN_PACKET && n <= 258u);
    CHECK(f[0] == RSM_ARIA_SYNC_1 && f[1] == RSM_ARIA_SYNC_2);
    CHECK((size_t)f[2] + 3u == n && f[2] >= RSM_ARIA_MIN_COUNT);
    CHECK(pkt->payload_len + 6u == n);
    CHECK(pkt->id == f[3]);
    CHECK(pl == f + 4);
    CHECK(rsm_aria_checksum(f + 3, n - 5u) == (uint16_t)(((uint32_t)f[n - 2u] << 8) | f[n - 1u]));
    CHECK(ref_checksum(f + 3, n - 5u) == rsm_aria_checksum(f + 3, n - 5u));
    CHECK(rsm_aria_packet_build(&copy, pkt->id, pl, pkt->payload_len) == RSM_OK);
    CHECK(copy.frame_len == n && memcmp(copy.frame, f, n) == 0);

    r = rsm_aria_decode_sync(pkt);
    CHECK(pkt->id <= 2u ? r == (int)pkt->id : r == RSM_ERR_INVAL);

    {
        rsm_aria_sync2_t y;
        rsm_aria_sync2_t y0;
        memset(&y, 0xA5, sizeof(y));
        y0 = y;
        r = rsm_aria_decode_sync2(pkt, &y);
        if (pkt->id == RSM_ARIA_PAC_SYNC2) {
            CHECK(r == RSM_OK && y.present <= 3u && y.truncated <= 7u);
            CHECK(strings_terminated(y.name, sizeof(y.name)));
            CHECK(strings_terminated(y.robot_class, sizeof(y.robot_class)));
            CHECK(strings_terminated(y.subclass, sizeof(y.subclass)));
        } else {
            CHECK(r == RSM_ERR_INVAL && memcmp(&y, &y0, sizeof(y)) == 0);
        }
    }
    {
        rsm_aria_sip_t s;
        rsm_aria_sip_t s0;
        memset(&s, 0xA5, sizeof(s));
        s0 = s;
        r = rsm_aria_decode_sip(pkt, &s);
        if (pkt->id == RSM_ARIA_PAC_SIP_STOPPED || pkt->id == RSM_ARIA_PAC_SIP_MOVING) {
            size_t claimed = (pkt->payload_len >= 19u) ? 19u + 3u * (size_t)pl[18] : 0u;
            if (pkt->payload_len < 19u || pkt->payload_len < claimed) {
                CHECK(r == RSM_ERR_RANGE && memcmp(&s, &s0, sizeof(s)) == 0);
            } else {
                size_t keep = (pl[18] < RSM_ARIA_MAX_SONAR) ? pl[18] : RSM_ARIA_MAX_SONAR;
                CHECK(r == RSM_OK);
                CHECK(s.type == pkt->id && s.sonar_count == pl[18] && s.sonar_len == keep);
                CHECK(s.xpos <= 0x7FFFu && s.ypos <= 0x7FFFu);
                /* Optional fields form a prefix of the wire order. */
                CHECK((s.present & (s.present + 1u)) == 0u && s.present <= 0x3FFFu);
            }
        } else {
            CHECK(r == RSM_ERR_INVAL && memcmp(&s, &s0, sizeof(s)) == 0);
        }
    }
    {
        rsm_aria_encoder_t e;
        rsm_aria_encoder_t e0;
        memset(&e, 0xA5, sizeof(e));
        e0 = e;
        r = rsm_aria_decode_encoder(pkt, &e);
        if (pkt->id == RSM_ARIA_PAC_ENCODER && pkt->payload_len >= 8u) {
            uint32_t l = (uint32_t)pl[0] | ((uint32_t)pl[1] << 8) | ((uint32_t)pl[2] << 16) |
                         ((uint32_t)pl[3] << 24);
            CHECK(r == RSM_OK && (uint32_t)e.left == l);
            CHECK((uint32_t)rsm_odometry_count_delta((uint32_t)(e.left), (uint32_t)(e.right), 32u) ==
                  (uint32_t)e.left - (uint32_t)e.right);
        } else {
            CHECK((r == RSM_ERR_INVAL || r == RSM_ERR_RANGE) && memcmp(&e, &e0, sizeof(e)) == 0);
            CHECK(pkt->id == RSM_ARIA_PAC_ENCODER ? r == RSM_ERR_RANGE : r == RSM_ERR_INVAL);
        }
    }
    {
        rsm_aria_config_t c;
        rsm_aria_config_t c0;
        memset(&c, 0xA5, sizeof(c));
        c0 = c;
        r = rsm_aria_decode_config(pkt, &c);
        if (r == RSM_OK) {
            CHECK(pkt->id == RSM_ARIA_PAC_CONFIG);
            CHECK(strings_terminated(c.robot_type, sizeof(c.robot_type)));
            CHECK(strings_terminated(c.subtype, sizeof(c.subtype)));
            CHECK(strings_terminated(c.serial_num, sizeof(c.serial_num)));
            CHECK(strings_terminated(c.name, sizeof(c.name)));
            CHECK(strings_terminated(c.firmware, sizeof(c.firmware)));
            CHECK(c.present <= 3u && c.present != RSM_ARIA_CONFIG_HAS_FIRMWARE);
        } else {
            CHECK(memcmp(&c, &c0, sizeof(c)) == 0);
            CHECK(pkt->id == RSM_ARIA_PAC_CONFIG ? r == RSM_ERR_RANGE : r == RSM_ERR_INVAL);
        }
    }
    {
        /* Helpers on payload-derived values. */
        uint16_t a = (uint16_t)(((uint32_t)f[n - 2u] << 8) | f[n - 1u]);
        uint16_t b = (uint16_t)(((uint32_t)f[3] << 8) | f[2]);
        int16_t d = rsm_aria_pos_delta15(a, b);
        float th = rsm_aria_th_to_rad((int32_t)a - (int32_t)b);
        CHECK(d >= -16384 && d <= 16383);
        CHECK((((uint32_t)(b & 0x7FFFu) + (uint32_t)(int32_t)d) & 0x7FFFu) == (a & 0x7FFFu));
        CHECK(th > -3.1416f && th < 3.1416f);
    }
}

static void check_monotonic(const rsm_aria_parser_stats_t *before, const rsm_aria_parser_stats_t *now)
{
    CHECK(now->bytes_skipped >= before->bytes_skipped);
    CHECK(now->checksum_errors >= before->checksum_errors);
    CHECK(now->bad_length >= before->bad_length);
    CHECK(now->packets_ok >= before->packets_ok);
    CHECK(now->truncated >= before->truncated);
}

/* One feed call with all invariant checks; returns its result. */
static int feed_checked(rsm_aria_parser_t *p, const uint8_t *s, size_t len, size_t *used,
                        digest_t *d, uint32_t *fed)
{
    rsm_aria_parser_stats_t before = p->stats;
    rsm_aria_packet_t pkt;
    int r;

    *used = 12345u;
    r = rsm_aria_parser_feed(p, s, len, used, &pkt);
    CHECK(r == 0 || r == 1);
    CHECK(*used <= len);
    CHECK(r == 1 || *used == len);
    check_monotonic(&before, &p->stats);
    *fed += (uint32_t)*used;
    if (r == 1) {
        check_packet(&pkt);
        CHECK(p->stats.packets_ok == before.packets_ok + 1u);
        d->count++;
        d->bytes += (uint32_t)pkt.frame_len;
        d->hash = hash_bytes(d->hash, pkt.frame, pkt.frame_len);
    } else {
        CHECK(p->stats.packets_ok == before.packets_ok);
    }
    CHECK(rsm_aria_parser_pending(p) <= 258u);
    CHECK(*fed == d->bytes + p->stats.bytes_skipped + p->stats.bad_length +
                      p->stats.checksum_errors + p->stats.truncated +
                      (uint32_t)rsm_aria_parser_pending(p));
    return r;
}

static void finish_run(rsm_aria_parser_t *p, digest_t *d, uint32_t *fed)
{
    size_t used;
    rsm_aria_parser_stats_t before = p->stats;
    int t = rsm_aria_parser_timeout(p);
    CHECK(t == 0 || t == 1);
    CHECK(p->stats.truncated == before.truncated + (uint32_t)t);
    while (feed_checked(p, NULL, 0u, &used, d, fed) == 1) {
        CHECK(used == 0u);
    }
    CHECK(rsm_aria_parser_pending(p) == 0u);
    d->stats = p->stats;
}

/* Feeds s in pieces: chunk 0 = all at once, 1 = byte-wise, 2 = sizes
 * from the data, 3 = sizes and timeouts from the data. */
static void run(const uint8_t *s, size_t n, int mode, digest_t *d)
{
    rsm_aria_parser_t p;
    size_t off = 0u;
    uint32_t fed = 0u;

    memset(d, 0, sizeof(*d));
    d->hash = 2166136261u;
    CHECK(rsm_aria_parser_init(&p) == RSM_OK);
    while (off < n) {
        size_t len = n - off;
        size_t used;
        if (mode == 1) {
            len = 1u;
        } else if (mode >= 2) {
            len = 1u + (size_t)((s[off] * 31u + off) % 67u);
            if (len > n - off) {
                len = n - off;
            }
            if (mode == 3 && (s[off] & 0x1Fu) == 0x1Fu) {
                rsm_aria_parser_stats_t before = p.stats;
                int t = rsm_aria_parser_timeout(&p);
                CHECK(t == 0 || t == 1);
                check_monotonic(&before, &p.stats);
            }
        }
        while (feed_checked(&p, s + off, len, &used, d, &fed) == 1) {
            off += used;
            len -= used;
        }
        off += used;
    }
    CHECK(fed == (uint32_t)n);
    finish_run(&p, d, &fed);
}

static int same(const digest_t *a, const digest_t *b)
{
    return a->count == b->count && a->bytes == b->bytes && a->hash == b->hash &&
           memcmp(&a->stats, &b->stats, sizeof(a->stats)) == 0;
}

/* Encoders: the first bytes choose the command, argument and capacity. */
static void fuzz_encoders(const uint8_t *data, size_t size)
{
    uint8_t out[RSM_ARIA_MAX_PACKET + 4u];
    uint8_t pattern[sizeof(out)];
    uint8_t cmd;
    int kind;
    int32_t value;
    size_t cap;
    size_t str_len;
    size_t need;
    int r;

    if (size < 5u) {
        return;
    }
    cmd = data[0];
    kind = data[1] % 4; /* 3 is not a valid kind */
    value = (int32_t)(((uint32_t)data[2] << 8) | data[3]) - 32768;
    if ((data[1] & 0x80u) != 0u) {
        value *= 2; /* reach beyond +-32767 too */
    }
    cap = (size_t)data[4] + ((data[1] & 0x40u) ? 4u : 0u);
    str_len = size - 5u;

    memset(out, 0xC3, sizeof(out));
    memcpy(pattern, out, sizeof(out));
    r = rsm_aria_encode(cmd, (rsm_aria_arg_kind_t)kind, value, (const char *)(data + 5), str_len, out,
                        cap);
    if (kind == 3) {
        CHECK(r == RSM_ERR_INVAL);
    } else if (kind == RSM_ARIA_ARG_INT && (value > 32767 || value < -32767)) {
        CHECK(r == RSM_ERR_RANGE);
    } else if (kind == RSM_ARIA_ARG_STR && str_len > RSM_ARIA_MAX_STR_ARG) {
        CHECK(r == RSM_ERR_RANGE);
    } else {
        need = (kind == RSM_ARIA_ARG_NONE) ? 6u : (kind == RSM_ARIA_ARG_INT) ? 9u : str_len + 9u;
        if (cap < need) {
            CHECK(r == RSM_ERR_NOMEM);
        } else {
            rsm_aria_parser_t p;
            rsm_aria_packet_t pkt;
            size_t used = 0u;
            const uint8_t *pl;
            CHECK(r == (int)need);
            CHECK(memcmp(out + need, pattern + need, sizeof(out) - need) == 0);
            CHECK(rsm_aria_parser_init(&p) == RSM_OK);
            CHECK(rsm_aria_parser_feed(&p, out, need, &used, &pkt) == 1 && used == need);
            check_packet(&pkt);
            CHECK(pkt.id == cmd && pkt.frame_len == need && memcmp(pkt.frame, out, need) == 0);
            pl = rsm_aria_payload(&pkt);
            if (kind == RSM_ARIA_ARG_INT) {
                int32_t mag = (int32_t)((uint32_t)pl[1] | ((uint32_t)pl[2] << 8));
                CHECK(pl[0] == (value < 0 ? RSM_ARIA_ARGTYPE_NINT : RSM_ARIA_ARGTYPE_INT));
                CHECK((value < 0 ? -mag : mag) == value);
            } else if (kind == RSM_ARIA_ARG_STR) {
                CHECK(pl[0] == RSM_ARIA_ARGTYPE_STR && pl[1] == (uint8_t)str_len);
                CHECK(memcmp(pl + 2, data + 5, str_len) == 0 && pl[2u + str_len] == 0u);
            }
            return;
        }
    }
    CHECK(memcmp(out, pattern, sizeof(out)) == 0);
}

/* VEL2: the robot's reading of the sent word gives the two wheels back. */
static void fuzz_vel2(const uint8_t *data, size_t size)
{
    uint8_t out[16];
    int32_t left;
    int32_t right;
    int r;

    if (size < 2u) {
        return;
    }
    left = (int32_t)data[0] - ((data[0] & 0x80u) ? 256 : 0);
    right = (int32_t)data[1] - ((data[1] & 0x80u) ? 256 : 0);
    r = rsm_aria_encode_vel2(left, right, out, sizeof(out));
    if (left < -127 || right < -127) {
        CHECK(r == RSM_ERR_RANGE);
    } else {
        uint32_t v = (uint32_t)out[5] | ((uint32_t)out[6] << 8);
        uint32_t word = (out[4] == RSM_ARIA_ARGTYPE_NINT) ? (0x10000u - v) & 0xFFFFu : v;
        CHECK(r == 9 && v <= 32767u);
        CHECK(out[4] == RSM_ARIA_ARGTYPE_INT || out[4] == RSM_ARIA_ARGTYPE_NINT);
        CHECK((uint8_t)(word >> 8) == data[0] && (uint8_t)(word & 0xFFu) == data[1]);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    digest_t a;
    digest_t b;
    digest_t c;
    digest_t d;
    digest_t ref;

    if (size > 65536u) {
        return 0;
    }
    run(data, size, 0, &a);
    run(data, size, 1, &b);
    run(data, size, 2, &c);
    run(data, size, 3, &d);
    ref_parse(data, size, &ref);
    CHECK(same(&a, &b));
    CHECK(same(&a, &c));
    CHECK(same(&a, &ref));
    CHECK(d.stats.packets_ok == d.count);
    fuzz_encoders(data, size);
    fuzz_vel2(data, size);
    return 0;
}
