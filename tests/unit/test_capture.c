/* Unit tests of the C capture reader (tools/nav/capture.{h,c}).
 *
 * The golden files in tests/data/capture were written by the Python writer
 * (make_golden.py there); NAME.MODE.txt is what the Python reader makes of
 * each, and the C reader must make exactly the same (channels, metadata,
 * every record's offset, stamp, channel, direction and bytes, the counters
 * or the error that stops a strict reader). The other tests build small
 * files in memory and check one rule of docs/capture.md each. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture.h"
#include "test_support.h"
#include "unity.h"

static cap_reader reader; /* about 260 KiB: not on the stack */
static uint8_t recbuf[CAP_MAX_CHUNK];
static char got[1u << 16];
static char want[1u << 16];

void setUp(void) {}
void tearDown(void) {}

/* ---- helpers ---------------------------------------------------------------- */

static size_t put(char *out, size_t at, size_t cap, const char *s)
{
    const size_t n = strlen(s);
    TEST_ASSERT_TRUE_MESSAGE(at + n < cap, "dump buffer too small");
    memcpy(out + at, s, n + 1u);
    return at + n;
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* The reader's view of fp, in the format of make_golden.py's dump(). */
static void dump(FILE *fp, int lenient, char *out, size_t cap)
{
    char line[CAP_MAX_NAME + 64]; /* a channel line holds a whole name */
    const char *keys[64];
    size_t at = 0, i, n_keys = 0;
    cap_record rec;
    int st;
    out[0] = '\0';
    st = cap_open(&reader, fp, lenient);
    if (st != CAP_OK) {
        (void)snprintf(line, sizeof line, "error %s\n", cap_status_name(st));
        (void)put(out, at, cap, line);
        return;
    }
    for (i = 0; i < reader.n_channels; ++i) {
        const cap_channel *c = &reader.channels[i];
        const char *proto = c->protocol == CAP_PROTO_ARIA ? "aria" : c->protocol == CAP_PROTO_LMS2XX ? "lms2xx" : "raw";
        (void)snprintf(line, sizeof line, "channel %u %s %s %lu\n", (unsigned)c->id, c->name, proto,
                       (unsigned long)c->baud);
        at = put(out, at, cap, line);
    }
    for (i = 0; i < reader.n_meta && n_keys < 64u; ++i) {
        if (cap_meta(&reader, reader.meta_keys[i]) == reader.meta_values[i]) { /* the last of equal keys */
            keys[n_keys++] = reader.meta_keys[i];
        }
    }
    qsort(keys, n_keys, sizeof keys[0], cmp_str);
    for (i = 0; i < n_keys; ++i) {
        at = put(out, at, cap, "meta ");
        at = put(out, at, cap, keys[i]);
        at = put(out, at, cap, "=");
        at = put(out, at, cap, cap_meta(&reader, keys[i]));
        at = put(out, at, cap, "\n");
    }
    while ((st = cap_next(&reader, &rec, recbuf, sizeof recbuf)) == CAP_OK) {
        (void)snprintf(line, sizeof line, "record %llu %llu %u %u %u ", (unsigned long long)rec.offset,
                       (unsigned long long)rec.timestamp_us, (unsigned)rec.channel, (unsigned)rec.direction,
                       (unsigned)rec.length);
        at = put(out, at, cap, line);
        for (i = 0; i < rec.length; ++i) {
            (void)snprintf(line, sizeof line, "%02x", (unsigned)recbuf[i]);
            at = put(out, at, cap, line);
        }
        at = put(out, at, cap, "\n");
    }
    if (st != CAP_END) {
        (void)snprintf(line, sizeof line, "error %s\n", cap_status_name(st));
    } else {
        (void)snprintf(line, sizeof line, "end records=%llu corrupt=%llu truncated=%llu order=%llu channel=%llu "
                       "skipped=%llu\n", (unsigned long long)reader.count.records,
                       (unsigned long long)reader.count.corrupt, (unsigned long long)reader.count.truncated,
                       (unsigned long long)reader.count.out_of_order,
                       (unsigned long long)reader.count.unknown_channel,
                       (unsigned long long)reader.count.skipped_bytes);
    }
    (void)put(out, at, cap, line);
    cap_close(&reader);
}

static FILE *open_data(const char *name)
{
    char path[512];
    char rel[128];
    FILE *fp;
    (void)snprintf(rel, sizeof rel, "tests/data/capture/%s", name);
    TEST_ASSERT_NOT_NULL(rsm_test_source_path(path, sizeof path, rel));
    fp = fopen(path, "rb");
    TEST_ASSERT_NOT_NULL_MESSAGE(fp, path);
    return fp;
}

static void read_text(const char *name, char *out, size_t cap)
{
    FILE *fp = open_data(name);
    const size_t n = fread(out, 1u, cap - 1u, fp);
    TEST_ASSERT_TRUE(n < cap - 1u);
    out[n] = '\0';
    (void)fclose(fp);
}

static void check_golden(const char *cap_name, const char *txt_name, int lenient)
{
    FILE *fp = open_data(cap_name);
    dump(fp, lenient, got, sizeof got);
    (void)fclose(fp);
    read_text(txt_name, want, sizeof want);
    TEST_ASSERT_EQUAL_STRING(want, got);
}

/* A file in memory (tmpfile, so any C99 host runs it). */
static FILE *file_of(const uint8_t *bytes, size_t n)
{
    FILE *fp = tmpfile();
    TEST_ASSERT_NOT_NULL(fp);
    TEST_ASSERT_EQUAL_size_t(n, fwrite(bytes, 1u, n, fp));
    rewind(fp);
    return fp;
}

static size_t le(uint8_t *p, uint64_t v, size_t bytes)
{
    size_t i;
    for (i = 0; i < bytes; ++i) {
        p[i] = (uint8_t)(v >> (8u * i));
    }
    return bytes;
}

/* A header with channels 0 "a" (aria) and 1 "b" (raw) and one metadata entry
 * written twice (k=first, k=second). */
static size_t header(uint8_t *p)
{
    static const uint8_t body[] = {2, 0, 1, 0x00, 0x96, 0, 0, 1, 'a', 1, 0, 0x80, 0x25, 0, 0, 1, 'b',
                                   2, 0, 1, 0, 'k', 5, 0, 0, 0, 'f', 'i', 'r', 's', 't',
                                   1, 0, 'k', 6, 0, 0, 0, 's', 'e', 'c', 'o', 'n', 'd'};
    size_t n = 0;
    memcpy(p, "\x89RSMCAP\n", 8u);
    n += 8u;
    n += le(p + n, 1u, 2u);
    n += le(p + n, 0u, 2u);
    n += le(p + n, sizeof body, 4u);
    memcpy(p + n, body, sizeof body);
    n += sizeof body;
    n += le(p + n, cap_crc32(0u, p, n), 4u);
    return n;
}

static size_t record(uint8_t *p, uint64_t ts, uint8_t ch, uint8_t dir, const char *data)
{
    const size_t len = strlen(data);
    size_t n = 0;
    p[n++] = 'R';
    p[n++] = 'C';
    n += le(p + n, len, 2u);
    n += le(p + n, ts, 8u);
    p[n++] = ch;
    p[n++] = dir;
    memcpy(p + n, data, len);
    n += len;
    n += le(p + n, cap_crc32(0u, p, n), 4u);
    return n;
}

static uint8_t file[4096];

/* ---- golden files: the Python writer's bytes, the Python reader's view ----- */

void test_golden_good_file_reads_as_the_python_reader_reads_it(void)
{
    check_golden("good.cap", "good.strict.txt", 0);
    check_golden("good.cap", "good.lenient.txt", 1);
}

void test_golden_damaged_file_reads_as_the_python_reader_reads_it(void)
{
    check_golden("damaged.cap", "damaged.strict.txt", 0);
    check_golden("damaged.cap", "damaged.lenient.txt", 1);
}

/* ---- one rule each ---------------------------------------------------------- */

void test_crc32_is_zlibs(void)
{
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926u, cap_crc32(0u, (const uint8_t *)"123456789", 9u));
    /* in pieces, continuing from the previous value */
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926u, cap_crc32(cap_crc32(0u, (const uint8_t *)"1234", 4u),
                                                   (const uint8_t *)"56789", 5u));
    TEST_ASSERT_EQUAL_HEX32(0u, cap_crc32(0u, NULL, 0u));
}

void test_header_gives_channels_and_the_last_of_equal_metadata_keys(void)
{
    size_t n = header(file);
    FILE *fp = file_of(file, n);
    TEST_ASSERT_EQUAL_INT(CAP_OK, cap_open(&reader, fp, 0));
    TEST_ASSERT_EQUAL_size_t(2u, reader.n_channels);
    TEST_ASSERT_EQUAL_STRING("a", cap_channel_by_id(&reader, 0)->name);
    TEST_ASSERT_EQUAL_UINT8(CAP_PROTO_ARIA, cap_channel_by_id(&reader, 0)->protocol);
    TEST_ASSERT_EQUAL_UINT32(38400u, cap_channel_by_id(&reader, 0)->baud);
    TEST_ASSERT_EQUAL_UINT32(9600u, cap_channel_by_id(&reader, 1)->baud);
    TEST_ASSERT_NULL(cap_channel_by_id(&reader, 2));
    TEST_ASSERT_EQUAL_STRING("second", cap_meta(&reader, "k"));
    TEST_ASSERT_NULL(cap_meta(&reader, "missing"));
    TEST_ASSERT_EQUAL_INT(CAP_END, cap_next(&reader, &(cap_record){0}, recbuf, sizeof recbuf));
    cap_close(&reader);
    (void)fclose(fp);
}

void test_header_faults_are_fatal_in_either_mode(void)
{
    static const size_t flips[] = {0u, 8u, 16u, 30u}; /* magic, version, body, CRC area */
    size_t n = header(file);
    size_t k;
    int lenient;
    for (lenient = 0; lenient <= 1; ++lenient) {
        for (k = 0; k < sizeof flips / sizeof flips[0]; ++k) {
            FILE *fp;
            file[flips[k]] ^= 0x01u;
            fp = file_of(file, n);
            TEST_ASSERT_EQUAL_INT(CAP_ERR_HEADER, cap_open(&reader, fp, lenient));
            TEST_ASSERT_TRUE(cap_error_text(&reader)[0] != '\0');
            cap_close(&reader);
            (void)fclose(fp);
            file[flips[k]] ^= 0x01u;
        }
        { /* cut inside the header */
            FILE *fp = file_of(file, n - 1u);
            TEST_ASSERT_EQUAL_INT(CAP_ERR_HEADER, cap_open(&reader, fp, lenient));
            cap_close(&reader);
            (void)fclose(fp);
        }
    }
}

/* Reads every record; returns the status that ended the reading. */
static int read_all(const uint8_t *bytes, size_t n, int lenient, char *seen, size_t seen_cap)
{
    FILE *fp = file_of(bytes, n);
    cap_record rec;
    int st;
    size_t at = 0;
    seen[0] = '\0';
    TEST_ASSERT_EQUAL_INT(CAP_OK, cap_open(&reader, fp, lenient));
    while ((st = cap_next(&reader, &rec, recbuf, sizeof recbuf)) == CAP_OK) {
        char line[64];
        (void)snprintf(line, sizeof line, "%llu:%u:%u:%.*s ", (unsigned long long)rec.timestamp_us,
                       (unsigned)rec.channel, (unsigned)rec.direction, (int)rec.length, (const char *)recbuf);
        at = put(seen, at, seen_cap, line);
    }
    (void)fclose(fp);
    return st;
}

/* A strict reader stops with strict_status after the records strict_seen;
 * a lenient one reads to the end and delivers lenient_seen. The lenient
 * reader's counters are left in `reader` for the caller. */
static void expect_reads(size_t n, int strict_status, const char *strict_seen, const char *lenient_seen)
{
    char seen[256];
    TEST_ASSERT_EQUAL_INT(strict_status, read_all(file, n, 0, seen, sizeof seen));
    TEST_ASSERT_EQUAL_STRING(strict_seen, seen);
    cap_close(&reader);
    TEST_ASSERT_EQUAL_INT(CAP_END, read_all(file, n, 1, seen, sizeof seen));
    TEST_ASSERT_EQUAL_STRING(lenient_seen, seen);
}

void test_strict_stops_at_each_problem_after_the_good_records_and_lenient_counts_it(void)
{
    static const struct {
        uint64_t ts;
        uint8_t ch, dir;
        const char *data;
        int strict_status;
    } bad[] = {
        {5u, 0, 0, "early", CAP_ERR_ORDER},
        {20u, 9, 0, "nobody", CAP_ERR_CHANNEL},
        {20u, 0, 7, "sideways", CAP_ERR_CORRUPT},
    };
    size_t k;
    for (k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        size_t n = header(file);
        n += record(file + n, 10u, 0, 0, "a");
        n += record(file + n, bad[k].ts, bad[k].ch, bad[k].dir, bad[k].data);
        n += record(file + n, 30u, 1, 1, "b");
        expect_reads(n, bad[k].strict_status, "10:0:0:a ", "10:0:0:a 30:1:1:b ");
        TEST_ASSERT_EQUAL_UINT64(bad[k].strict_status == CAP_ERR_ORDER, reader.count.out_of_order);
        TEST_ASSERT_EQUAL_UINT64(bad[k].strict_status == CAP_ERR_CHANNEL, reader.count.unknown_channel);
        TEST_ASSERT_EQUAL_UINT64(bad[k].strict_status == CAP_ERR_CORRUPT, reader.count.corrupt);
        cap_close(&reader);
    }
}

void test_garbage_and_a_flipped_bit_cost_only_the_bytes_they_hit(void)
{
    size_t n = header(file);
    size_t r2;
    n += record(file + n, 10u, 0, 0, "a");
    memcpy(file + n, "xxRC\x01", 5u); /* garbage with a false sync */
    n += 5u;
    r2 = n;
    n += record(file + n, 11u, 0, 0, "flip");
    n += record(file + n, 12u, 1, 0, "c");
    file[r2 + 15u] ^= 0x40u; /* inside the data of the record at 11 us */
    expect_reads(n, CAP_ERR_CORRUPT, "10:0:0:a ", "10:0:0:a 12:1:0:c ");
    TEST_ASSERT_EQUAL_UINT64(1u, reader.count.corrupt); /* one resynchronisation */
    TEST_ASSERT_EQUAL_UINT64(5u + 18u + 4u, reader.count.skipped_bytes);
    cap_close(&reader);
}

void test_a_cut_last_record_is_truncated_and_ends_the_file(void)
{
    size_t n = header(file);
    size_t cut;
    n += record(file + n, 10u, 0, 0, "a");
    cut = n + 9u;
    n += record(file + n, 11u, 0, 0, "tail");
    (void)n;
    expect_reads(cut, CAP_ERR_TRUNCATED, "10:0:0:a ", "10:0:0:a ");
    TEST_ASSERT_EQUAL_UINT64(1u, reader.count.truncated);
    TEST_ASSERT_EQUAL_UINT64(1u, reader.count.records);
    cap_close(&reader);
}

void test_a_buffer_too_small_skips_that_record_only(void)
{
    FILE *fp;
    cap_record rec;
    size_t n = header(file);
    n += record(file + n, 10u, 0, 0, "longer than four");
    n += record(file + n, 11u, 0, 0, "ok");
    fp = file_of(file, n);
    TEST_ASSERT_EQUAL_INT(CAP_OK, cap_open(&reader, fp, 0));
    TEST_ASSERT_EQUAL_INT(CAP_ERR_BUFFER, cap_next(&reader, &rec, recbuf, 4u));
    TEST_ASSERT_EQUAL_INT(CAP_OK, cap_next(&reader, &rec, recbuf, 4u));
    TEST_ASSERT_EQUAL_UINT16(2u, rec.length);
    TEST_ASSERT_EQUAL_MEMORY("ok", recbuf, 2u);
    TEST_ASSERT_EQUAL_INT(CAP_END, cap_next(&reader, &rec, recbuf, 4u));
    cap_close(&reader);
    (void)fclose(fp);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_golden_good_file_reads_as_the_python_reader_reads_it);
    RUN_TEST(test_golden_damaged_file_reads_as_the_python_reader_reads_it);
    RUN_TEST(test_crc32_is_zlibs);
    RUN_TEST(test_header_gives_channels_and_the_last_of_equal_metadata_keys);
    RUN_TEST(test_header_faults_are_fatal_in_either_mode);
    RUN_TEST(test_strict_stops_at_each_problem_after_the_good_records_and_lenient_counts_it);
    RUN_TEST(test_garbage_and_a_flipped_bit_cost_only_the_bytes_they_hit);
    RUN_TEST(test_a_cut_last_record_is_truncated_and_ends_the_file);
    RUN_TEST(test_a_buffer_too_small_skips_that_record_only);
    return UNITY_END();
}
