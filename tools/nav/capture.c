/* Streaming reader for rsm capture files; see capture.h and docs/capture.md. */
#include "capture.h"
#include "heap.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

static const uint8_t cap_magic[8] = {0x89, 'R', 'S', 'M', 'C', 'A', 'P', '\n'};
#define CAP_WIN ((size_t)sizeof(((cap_reader *)0)->win))
#define CAP_MAX_HEADER (16u * 1024u * 1024u)

uint32_t cap_crc32(uint32_t crc, const uint8_t *p, size_t n)
{
    static uint32_t table[256];
    static int ready = 0;
    size_t i;
    if (!ready) {
        uint32_t k;
        for (k = 0; k < 256u; ++k) {
            uint32_t c = k;
            int b;
            for (b = 0; b < 8; ++b) {
                c = (c & 1u) ? (0xEDB88320u ^ (c >> 1)) : (c >> 1);
            }
            table[k] = c;
        }
        ready = 1;
    }
    crc = ~crc;
    for (i = 0; i < n; ++i) {
        crc = table[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
    }
    return ~crc;
}

/* ---- CRC of a span from two prefix CRCs --------------------------------------
 * For the CRC-32 used here, crc(A B) = crc(A) * x^(8 |B|) + crc(B) modulo
 * the polynomial (the initial and final inversions cancel), so
 * crc(B) = crc(A B) ^ (crc(A) * x^(8 |B|)). Polynomials are held reflected,
 * as the table-driven CRC holds them: bit 31 is x^0. */
#define CAP_POLY 0xEDB88320u

static uint32_t gf2_mul(uint32_t a, uint32_t b)
{
    uint32_t m = 1u << 31;
    uint32_t p = 0u;
    while (m != 0u && a != 0u) {
        if (a & m) {
            p ^= b;
            a &= ~m;
        }
        m >>= 1;
        b = (b & 1u) ? (b >> 1) ^ CAP_POLY : b >> 1;
    }
    return p;
}

/* x^(8 n) modulo the polynomial, by squaring: x^(2^k) for k = 3, 4, ... */
static uint32_t gf2_x8n(size_t n)
{
    uint32_t sq = 1u << 23; /* x^8 */
    uint32_t p = 1u << 31;  /* x^0 */
    while (n != 0u) {
        if (n & 1u) {
            p = gf2_mul(sq, p);
        }
        sq = gf2_mul(sq, sq);
        n >>= 1;
    }
    return p;
}

static uint16_t rd16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }

static uint32_t rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static uint64_t rd64(const uint8_t *p)
{
    return (uint64_t)rd32(p) | ((uint64_t)rd32(p + 4) << 32);
}

static int fail(cap_reader *r, int status, const char *msg)
{
    strncpy(r->error, msg, sizeof r->error - 1);
    r->error[sizeof r->error - 1] = '\0';
    return status;
}

const char *cap_status_name(int status)
{
    switch (status) {
    case CAP_OK: return "ok";
    case CAP_END: return "end";
    case CAP_ERR_IO: return "io";
    case CAP_ERR_HEADER: return "header";
    case CAP_ERR_CORRUPT: return "corrupt";
    case CAP_ERR_TRUNCATED: return "truncated";
    case CAP_ERR_ORDER: return "order";
    case CAP_ERR_CHANNEL: return "channel";
    case CAP_ERR_NOMEM: return "nomem";
    case CAP_ERR_BUFFER: return "buffer";
    default: return "unknown";
    }
}

const char *cap_error_text(const cap_reader *r) { return r->error; }

/* ---- header ------------------------------------------------------------------- */

static size_t read_full(FILE *fp, uint8_t *p, size_t n) { return fread(p, 1, n, fp); }

/* A read of the header failed: said as such, not as what the bytes read so
 * far would make of it ("bad magic"). */
static int io_fail(cap_reader *r)
{
    snprintf(r->error, sizeof r->error, "read error in the capture header: %s", strerror(errno));
    r->io_error = 1;
    return CAP_ERR_IO;
}

/* Whether p[0..n) is well-formed UTF-8 as Python decodes it (no overlong
 * forms, no surrogates, nothing past U+10FFFF): both readers must refuse
 * the same headers. */
static int valid_utf8(const uint8_t *p, size_t n)
{
    size_t i = 0;
    while (i < n) {
        const uint8_t c = p[i];
        size_t len;
        uint8_t lo = 0x80u;
        uint8_t hi = 0xBFu;
        size_t k;
        if (c < 0x80u) {
            ++i;
            continue;
        }
        if (c >= 0xC2u && c <= 0xDFu) {
            len = 2;
        } else if (c >= 0xE0u && c <= 0xEFu) {
            len = 3;
            lo = c == 0xE0u ? 0xA0u : 0x80u; /* no overlong */
            hi = c == 0xEDu ? 0x9Fu : 0xBFu; /* no surrogates */
        } else if (c >= 0xF0u && c <= 0xF4u) {
            len = 4;
            lo = c == 0xF0u ? 0x90u : 0x80u;
            hi = c == 0xF4u ? 0x8Fu : 0xBFu; /* up to U+10FFFF */
        } else {
            return 0;
        }
        if (n - i < len || p[i + 1] < lo || p[i + 1] > hi) {
            return 0;
        }
        for (k = 2; k < len; ++k) {
            if (p[i + k] < 0x80u || p[i + k] > 0xBFu) {
                return 0;
            }
        }
        i += len;
    }
    return 1;
}

int cap_open(cap_reader *r, FILE *fp, int lenient)
{
    uint8_t fixed[16], crcb[4];
    uint8_t *body;
    uint32_t hlen, crc;
    size_t got, off, i, nmeta, nch, text;
    char *out;

    memset(r, 0, offsetof(cap_reader, win));
    r->crc_end = 0;
    r->fp = fp;
    r->lenient = lenient;
    got = read_full(fp, fixed, sizeof fixed);
    if (got < sizeof fixed && ferror(fp)) {
        return io_fail(r);
    }
    if (got < 8 || memcmp(fixed, cap_magic, 8) != 0) {
        return fail(r, CAP_ERR_HEADER, "not an rsm capture file (bad magic)");
    }
    if (got < 16) {
        return fail(r, CAP_ERR_HEADER, "capture header truncated");
    }
    r->version = rd16(fixed + 8);
    if (r->version != 1u) {
        return fail(r, CAP_ERR_HEADER, "unsupported capture version");
    }
    hlen = rd32(fixed + 12);
    if (hlen > CAP_MAX_HEADER) {
        return fail(r, CAP_ERR_HEADER, "implausible header length");
    }
    body = (uint8_t *)nav_malloc(hlen ? hlen : 1u);
    if (body == NULL) {
        return fail(r, CAP_ERR_NOMEM, "out of memory for the capture header");
    }
    if (read_full(fp, body, hlen) < hlen || read_full(fp, crcb, 4) < 4) {
        nav_free(body);
        return ferror(fp) ? io_fail(r) : fail(r, CAP_ERR_HEADER, "capture header truncated");
    }
    crc = cap_crc32(cap_crc32(0, fixed, 16), body, hlen);
    if (crc != rd32(crcb)) {
        nav_free(body);
        return fail(r, CAP_ERR_HEADER, "capture header CRC mismatch (header corrupt)");
    }
    /* channels */
    if (hlen < 1u) goto malformed;
    nch = body[0];
    if (nch < 1u || nch > CAP_MAX_CHANNELS) goto malformed;
    off = 1;
    for (i = 0; i < nch; ++i) {
        size_t nl;
        cap_channel *c = &r->channels[i];
        if (off + 7u > hlen) goto malformed;
        c->id = body[off];
        c->protocol = body[off + 1] <= (uint8_t)CAP_PROTO_RPLIDAR ? body[off + 1] : (uint8_t)CAP_PROTO_RAW;
        c->baud = rd32(body + off + 2);
        nl = body[off + 6];
        off += 7;
        if (nl == 0u || off + nl > hlen || c->id == 255u || !valid_utf8(body + off, nl)) goto malformed;
        memcpy(c->name, body + off, nl);
        c->name[nl] = '\0';
        off += nl;
    }
    r->n_channels = nch;
    /* metadata: first pass checks and sizes, second copies */
    if (off + 2u > hlen) goto malformed;
    nmeta = rd16(body + off);
    off += 2;
    {
        size_t o = off;
        text = 0;
        for (i = 0; i < nmeta; ++i) {
            size_t kl, vl;
            if (o + 2u > hlen) goto malformed;
            kl = rd16(body + o);
            o += 2;
            if (o + kl + 4u > hlen || !valid_utf8(body + o, kl)) goto malformed;
            o += kl;
            vl = rd32(body + o);
            o += 4;
            if (vl > hlen - o || !valid_utf8(body + o, vl)) goto malformed;
            o += vl;
            text += kl + vl + 2u;
        }
        if (o != hlen) goto malformed;
    }
    r->meta_buf = (char *)nav_malloc(text ? text : 1u);
    r->meta_keys = (const char **)nav_malloc((nmeta ? nmeta : 1u) * sizeof(char *));
    r->meta_values = (const char **)nav_malloc((nmeta ? nmeta : 1u) * sizeof(char *));
    if (!r->meta_buf || !r->meta_keys || !r->meta_values) {
        nav_free(body);
        cap_close(r);
        return fail(r, CAP_ERR_NOMEM, "out of memory for the capture metadata");
    }
    out = r->meta_buf;
    for (i = 0; i < nmeta; ++i) {
        size_t kl = rd16(body + off), vl;
        off += 2;
        memcpy(out, body + off, kl);
        out[kl] = '\0';
        r->meta_keys[i] = out;
        out += kl + 1u;
        off += kl;
        vl = rd32(body + off);
        off += 4;
        memcpy(out, body + off, vl);
        out[vl] = '\0';
        r->meta_values[i] = out;
        out += vl + 1u;
        off += vl;
    }
    r->n_meta = nmeta;
    nav_free(body);
    r->base = 16u + (uint64_t)hlen + 4u;
    return CAP_OK;
malformed:
    nav_free(body);
    return fail(r, CAP_ERR_HEADER, "capture header body malformed");
}

void cap_close(cap_reader *r)
{
    nav_free(r->meta_buf);
    nav_free((void *)r->meta_keys);
    nav_free((void *)r->meta_values);
    r->meta_buf = NULL;
    r->meta_keys = NULL;
    r->meta_values = NULL;
    r->n_meta = 0;
}

const char *cap_meta(const cap_reader *r, const char *key)
{
    size_t i = r->n_meta;
    while (i-- > 0u) { /* the last of duplicated keys wins, as in Python */
        if (strcmp(r->meta_keys[i], key) == 0) {
            return r->meta_values[i];
        }
    }
    return NULL;
}

const cap_channel *cap_channel_by_id(const cap_reader *r, uint8_t id)
{
    size_t i;
    for (i = 0; i < r->n_channels; ++i) {
        if (r->channels[i].id == id) {
            return &r->channels[i];
        }
    }
    return NULL;
}

/* ---- buffered window ------------------------------------------------------------ */

static size_t avail(const cap_reader *r) { return r->end - r->start; }

/* Make need bytes available from win[start] if the file has them (need <= CAP_WIN). */
static int fill(cap_reader *r, size_t need)
{
    while (avail(r) < need && !r->eof) {
        size_t got;
        if (r->start + need > CAP_WIN) {
            memmove(r->win, r->win + r->start, avail(r));
            r->end -= r->start;
            r->start = 0;
            r->crc_end = 0; /* the prefix CRCs start again from the new win[0] */
        }
        errno = 0;
        got = fread(r->win + r->end, 1, CAP_WIN - r->end, r->fp);
        if (got < CAP_WIN - r->end && ferror(r->fp)) {
            /* A read error is not the end of the file: remember it (sticky),
             * so the caller is told instead of seeing a truncated tail. */
            if (!r->io_error) {
                r->io_errno = errno;
            }
            r->io_error = 1;
        }
        if (got == 0u) {
            r->eof = 1;
        }
        r->end += got;
    }
    return avail(r) >= need;
}

static void drop(cap_reader *r, size_t n)
{
    r->start += n;
    r->base += n;
    if (r->start == r->end) {
        r->start = r->end = 0;
        r->crc_end = 0;
    }
}

/* CRC-32 of win[a..b), a <= b <= end. */
static uint32_t span_crc(cap_reader *r, size_t a, size_t b)
{
    if (r->crc_end == 0u) {
        r->crc[0] = 0u;
    }
    while (r->crc_end < b) {
        r->crc[r->crc_end + 1u] = cap_crc32(r->crc[r->crc_end], r->win + r->crc_end, 1u);
        r->crc_end++;
        r->count.crc_bytes++;
    }
    return r->crc[b] ^ gf2_mul(gf2_x8n(b - a), r->crc[a]);
}

/* Size of a valid record at win[start+i], 0 if none (i < 65536). */
static size_t complete_at(cap_reader *r, size_t i)
{
    const uint8_t *b;
    size_t n, size;
    if (!fill(r, i + CAP_REC_HEAD)) return 0;
    b = r->win + r->start + i;
    if (b[0] != 'R' || b[1] != 'C') return 0;
    n = rd16(b + 2);
    size = CAP_REC_OVERHEAD + n;
    if (!fill(r, i + size)) return 0;
    b = r->win + r->start + i; /* fill may have moved the window */
    return span_crc(r, r->start + i, r->start + i + CAP_REC_HEAD + n) == rd32(b + CAP_REC_HEAD + n) ? size : 0u;
}

/* Skip to the next valid record after win[start]; 0 if none before EOF. */
static int resync(cap_reader *r)
{
    size_t i = 1;
    for (;;) {
        const uint8_t *b;
        if (i >= 65536u) { /* bytes before i are garbage either way */
            drop(r, i);
            i = 0;
        }
        if (!fill(r, i + 2u)) {
            return 0;
        }
        b = r->win + r->start + i;
        if (b[0] == 'R' && b[1] == 'C' && complete_at(r, i)) {
            drop(r, i);
            return 1;
        }
        ++i;
    }
}

/* The sticky read error: the bytes not yet delivered stay unread. */
static int io_failure(cap_reader *r)
{
    snprintf(r->error, sizeof r->error, "read error at byte %llu after %llu good records: %s",
             (unsigned long long)(r->base + avail(r)), (unsigned long long)r->count.records,
             r->io_errno != 0 ? strerror(r->io_errno) : "unknown cause");
    return CAP_ERR_IO;
}

static int problem(cap_reader *r, int status, const char *msg)
{
    fail(r, status, msg);
    return r->lenient ? CAP_OK : status;
}

int cap_next(cap_reader *r, cap_record *rec, uint8_t *buf, size_t cap)
{
    for (;;) {
        uint64_t off = r->base, ts;
        size_t size, n;
        int have_head, st;
        uint8_t ch, dir;
        const uint8_t *b;

        if (!fill(r, 1)) {
            return r->io_error ? io_failure(r) : CAP_END;
        }
        have_head = fill(r, CAP_REC_HEAD);
        size = complete_at(r, 0);
        if (size == 0u) {
            int incomplete;
            b = r->win + r->start;
            if (have_head) {
                int sync = b[0] == 'R' && b[1] == 'C';
                incomplete = sync && !fill(r, CAP_REC_OVERHEAD + rd16(b + 2));
            } else {
                incomplete = b[0] == 'R' && (avail(r) < 2u || b[1] == 'C');
            }
            if (resync(r)) {
                r->count.skipped_bytes += r->base - off;
                r->count.corrupt++;
                st = problem(r, CAP_ERR_CORRUPT, "corrupt capture record (bad sync or CRC)");
                if (st != CAP_OK) return st;
                continue;
            }
            if (r->io_error) {
                return io_failure(r); /* not a truncated or corrupt tail: the read failed */
            }
            r->count.skipped_bytes += r->base + avail(r) - off;
            drop(r, avail(r));
            if (incomplete) {
                r->count.truncated++;
                st = problem(r, CAP_ERR_TRUNCATED, "capture ends inside a record");
            } else {
                r->count.corrupt++;
                st = problem(r, CAP_ERR_CORRUPT, "corrupt capture data up to the end of the file");
            }
            return st != CAP_OK ? st : CAP_END;
        }
        b = r->win + r->start;
        n = rd16(b + 2);
        ts = rd64(b + 4);
        ch = b[12];
        dir = b[13];
        if (dir > 1u) {
            drop(r, size);
            r->count.corrupt++;
            st = problem(r, CAP_ERR_CORRUPT, "record with bad direction");
            if (st != CAP_OK) return st;
            continue;
        }
        if (cap_channel_by_id(r, ch) == NULL) {
            drop(r, size);
            r->count.unknown_channel++;
            st = problem(r, CAP_ERR_CHANNEL, "record for a channel id the header does not list");
            if (st != CAP_OK) return st;
            continue;
        }
        if (r->lenient && r->have_last && (ts < r->last_ts || ts - r->last_ts > CAP_MAX_STEP_US) &&
            !(r->have_far && (ts > r->far_ts ? ts - r->far_ts : r->far_ts - ts) <= CAP_MAX_STEP_US)) {
            /* One record far ahead would make every later one out of order,
             * and a clock that stepped back would lose every later one: the
             * record counts as out of order unless the next one agrees. */
            drop(r, size);
            r->have_far = 1;
            r->far_ts = ts;
            r->count.out_of_order++;
            (void)problem(r, CAP_ERR_ORDER,
                          ts < r->last_ts ? "record timestamp earlier than the previous one (not trusted alone)"
                                          : "record stamped over an hour after the previous one (not trusted alone)");
            continue;
        }
        if (!r->lenient && r->have_last && ts < r->last_ts) {
            drop(r, size);
            r->count.out_of_order++;
            st = problem(r, CAP_ERR_ORDER, "record timestamp earlier than the previous one");
            if (st != CAP_OK) return st;
            continue;
        }
        if (n > cap) {
            drop(r, size);
            return fail(r, CAP_ERR_BUFFER, "record longer than the caller buffer (skipped)");
        }
        memcpy(buf, b + CAP_REC_HEAD, n);
        drop(r, size);
        r->have_far = 0;
        r->have_last = 1;
        r->last_ts = ts;
        r->count.records++;
        r->count.bytes += n;
        rec->timestamp_us = ts;
        rec->channel = ch;
        rec->direction = dir;
        rec->length = (uint16_t)n;
        rec->offset = off;
        return CAP_OK;
    }
}

/* ---- test driver: prints a capture the way tests/py/test_capture.py does ----- */
#ifdef RSM_CAPTURE_DUMP_MAIN
#include <inttypes.h>

static const char *proto_name(uint8_t p)
{
    static const char *const names[] = {"raw", "aria", "lms2xx", "ld06", "rplidar"};
    return p < sizeof names / sizeof names[0] ? names[p] : "raw";
}

static const cap_reader *sort_reader;

static int cmp_meta(const void *a, const void *b)
{
    size_t i = *(const size_t *)a, j = *(const size_t *)b;
    return strcmp(sort_reader->meta_keys[i], sort_reader->meta_keys[j]);
}

static cap_reader reader;
static uint8_t recbuf[CAP_MAX_CHUNK];

int main(int argc, char **argv)
{
    int lenient = 0, st;
    const char *path;
    FILE *fp;
    size_t i, *idx;
    cap_record rec;

    if (argc == 3 && strcmp(argv[1], "--lenient") == 0) {
        lenient = 1;
        path = argv[2];
    } else if (argc == 2) {
        path = argv[1];
    } else {
        fprintf(stderr, "usage: capture_dump [--lenient] FILE.cap\n");
        return 2;
    }
    fp = fopen(path, "rb");
    if (fp == NULL) {
        perror(path);
        return 2;
    }
    st = cap_open(&reader, fp, lenient);
    if (st != CAP_OK) {
        printf("error %s\n", cap_status_name(st));
        fclose(fp);
        return 1;
    }
    for (i = 0; i < reader.n_channels; ++i) {
        const cap_channel *c = &reader.channels[i];
        printf("channel %u %s %s %" PRIu32 "\n", (unsigned)c->id, c->name, proto_name(c->protocol),
               c->baud);
    }
    idx = (size_t *)nav_malloc((reader.n_meta ? reader.n_meta : 1u) * sizeof *idx);
    if (idx == NULL) return 2;
    for (i = 0; i < reader.n_meta; ++i) idx[i] = i;
    sort_reader = &reader;
    qsort(idx, reader.n_meta, sizeof *idx, cmp_meta);
    for (i = 0; i < reader.n_meta; ++i) {
        const char *k = reader.meta_keys[idx[i]];
        if (i + 1u < reader.n_meta && strcmp(k, reader.meta_keys[idx[i + 1u]]) == 0) continue;
        printf("meta %s=%s\n", k, cap_meta(&reader, k));
    }
    nav_free(idx);
    while ((st = cap_next(&reader, &rec, recbuf, sizeof recbuf)) == CAP_OK) {
        printf("record %" PRIu64 " %" PRIu64 " %u %u %u ", rec.offset, rec.timestamp_us,
               (unsigned)rec.channel, (unsigned)rec.direction, (unsigned)rec.length);
        for (i = 0; i < rec.length; ++i) printf("%02x", (unsigned)recbuf[i]);
        printf("\n");
    }
    if (st != CAP_END) {
        printf("error %s\n", cap_status_name(st));
        cap_close(&reader);
        fclose(fp);
        return 1;
    }
    printf("end records=%" PRIu64 " corrupt=%" PRIu64 " truncated=%" PRIu64 " order=%" PRIu64
           " channel=%" PRIu64 " skipped=%" PRIu64 "\n",
           reader.count.records, reader.count.corrupt, reader.count.truncated,
           reader.count.out_of_order, reader.count.unknown_channel, reader.count.skipped_bytes);
    cap_close(&reader);
    fclose(fp);
    return 0;
}
#endif
