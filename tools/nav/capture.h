/* Streaming reader for rsm capture files (.cap), host only.
 *
 * Format: docs/capture.md.  The rules for corrupt, truncated, out-of-order
 * and unknown-channel records are the same as in tools/rsm_tools/capture.py:
 * a strict reader stops with an error status at the first problem (every
 * good record before it has been delivered); a lenient reader counts the
 * problem, skips the record and goes on (a truncated tail ends the file).
 */
#ifndef RSM_NAV_CAPTURE_H
#define RSM_NAV_CAPTURE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define CAP_MAX_CHANNELS 32
#define CAP_MAX_NAME 255
#define CAP_MAX_CHUNK 65535u
#define CAP_REC_HEAD 14u
#define CAP_REC_OVERHEAD 18u
/* Lenient readers do not trust alone a record stamped this much after the
 * previous one (one hour, in microseconds), nor one stamped before it; the
 * next record confirms either when it is stamped within this of it. */
#define CAP_MAX_STEP_US 3600000000ull

enum cap_status {
    CAP_OK = 0,              /* a record was delivered */
    CAP_END = 1,             /* no more records */
    CAP_ERR_IO = -1,         /* read error from the stream */
    CAP_ERR_HEADER = -2,     /* bad magic/version/CRC, truncated or malformed header */
    CAP_ERR_CORRUPT = -3,    /* corrupt record (sync, CRC, direction) */
    CAP_ERR_TRUNCATED = -4,  /* the file ends inside a record */
    CAP_ERR_ORDER = -5,      /* timestamp earlier than the previous record's */
    CAP_ERR_CHANNEL = -6,    /* channel id not in the header */
    CAP_ERR_NOMEM = -7,      /* header too large to hold */
    CAP_ERR_BUFFER = -8      /* caller buffer smaller than the record (record skipped) */
};

enum cap_protocol {
    CAP_PROTO_RAW = 0,
    CAP_PROTO_ARIA = 1,
    CAP_PROTO_LMS2XX = 2,
    CAP_PROTO_LD06 = 3,
    CAP_PROTO_RPLIDAR = 4
};
enum cap_direction { CAP_RX = 0, CAP_TX = 1 };

typedef struct {
    uint8_t id;
    uint8_t protocol;            /* enum cap_protocol (other codes read as raw) */
    uint32_t baud;
    char name[CAP_MAX_NAME + 1]; /* NUL-terminated */
} cap_channel;

typedef struct {
    uint64_t timestamp_us;
    uint8_t channel;
    uint8_t direction;           /* enum cap_direction */
    uint16_t length;             /* bytes in the caller buffer */
    uint64_t offset;             /* byte offset of the record in the file */
} cap_record;

typedef struct {
    uint64_t records;
    uint64_t bytes;
    uint64_t corrupt;
    uint64_t skipped_bytes;
    uint64_t truncated;
    uint64_t out_of_order;
    uint64_t unknown_channel;
    uint64_t crc_bytes;          /* bytes run through the CRC: about the file size, however
                                  * many false record starts a resync meets */
} cap_counters;

typedef struct {
    FILE *fp;
    int lenient;
    uint16_t version;
    size_t n_channels;
    cap_channel channels[CAP_MAX_CHANNELS];
    /* metadata: n_meta entries, keys and values NUL-terminated inside meta_buf */
    size_t n_meta;
    char *meta_buf;
    const char **meta_keys;
    const char **meta_values;
    cap_counters count;
    int have_last;
    uint64_t last_ts;
    int have_far;                /* lenient: a record far ahead of last_ts or before it was skipped ... */
    uint64_t far_ts;             /* ... stamped this (docs/capture.md, "Far ahead", "Stepped back") */
    uint64_t base;               /* file offset of win[start] */
    size_t start, end;           /* valid bytes are win[start..end) */
    int eof;
    int io_error;                /* a read failed: every later cap_next returns CAP_ERR_IO */
    int io_errno;                /* errno of the first failed read (0 if unknown) */
    char error[160];
    uint8_t win[1u << 18];
    /* crc[j]: CRC-32 of win[0..j), valid for j <= crc_end: the CRC of any
     * span of the window is then two table reads and a shift, so that a
     * resync over candidates claiming 64 KiB each does not CRC each anew. */
    size_t crc_end;
    uint32_t crc[(1u << 18) + 1u];
} cap_reader;

/* Reads and checks the header.  Returns CAP_OK or an error status (see
 * cap_error_text).  The reader is large (~1.3 MiB): do not put it on a small
 * stack.  fp stays owned by the caller. */
int cap_open(cap_reader *r, FILE *fp, int lenient);

/* The next record: its bytes go to buf (capacity cap bytes; 65535 always
 * suffices).  Returns CAP_OK, CAP_END or an error status.  A read error is
 * CAP_ERR_IO in strict and lenient readers alike, never a truncated record
 * or the end; it is sticky (every later call returns it again), so a caller
 * must stop on it rather than skip it. */
int cap_next(cap_reader *r, cap_record *rec, uint8_t *buf, size_t cap);

/* Metadata value for key (NUL-terminated), or NULL. */
const char *cap_meta(const cap_reader *r, const char *key);

/* Channel with this id, or NULL. */
const cap_channel *cap_channel_by_id(const cap_reader *r, uint8_t id);

/* Message for the last error (empty if none). */
const char *cap_error_text(const cap_reader *r);

/* Short name of a status: "ok", "end", "io", "header", "corrupt", ... */
const char *cap_status_name(int status);

/* Frees the metadata; does not close fp. */
void cap_close(cap_reader *r);

/* CRC-32 (IEEE 802.3, as zlib's crc32) of n bytes, continuing from crc. */
uint32_t cap_crc32(uint32_t crc, const uint8_t *p, size_t n);

#endif
