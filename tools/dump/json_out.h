/* A small streaming JSON writer for rsm-dump: one object per top-level
 * value, compact (one line) or pretty (indented). Numbers are always
 * finite: a NaN or infinite double is written as null. */
#ifndef RSM_DUMP_JSON_OUT_H
#define RSM_DUMP_JSON_OUT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define JSON_OUT_MAX_DEPTH 16

/* Writer state, owned by the caller. */
typedef struct json_out {
    FILE *f;                            /* borrowed output stream */
    int pretty;                         /* 1: indent, 0: one line per value */
    int depth;                          /* open containers */
    int count[JSON_OUT_MAX_DEPTH];      /* members written per open container */
    int after_key;                      /* a key was just written */
} json_out_t;

/* Prepares w to write to f (kept, not owned). */
void json_out_init(json_out_t *w, FILE *f, int pretty);

/* Containers. json_end_obj/json_end_arr at depth 0 end the line. Nesting
 * deeper than JSON_OUT_MAX_DEPTH is flattened silently (never happens in
 * rsm-dump). */
void json_begin_obj(json_out_t *w);
void json_end_obj(json_out_t *w);
void json_begin_arr(json_out_t *w);
void json_end_arr(json_out_t *w);

/* A member name inside an object; the value call follows. */
void json_key(json_out_t *w, const char *key);

/* Values. json_str escapes len bytes as JSON text (bytes >= 0x80 and
 * control bytes as \u00XX, so any input gives valid output). */
void json_int(json_out_t *w, int64_t v);
void json_uint(json_out_t *w, uint64_t v);
void json_double(json_out_t *w, double v);
void json_bool(json_out_t *w, int v);
void json_null(json_out_t *w);
void json_strn(json_out_t *w, const char *s, size_t len);
void json_str(json_out_t *w, const char *s);
/* "0x" followed by width hex digits, as a string. */
void json_hex(json_out_t *w, uint32_t v, int width);
/* len bytes as a string of space-separated upper-case hex pairs. */
void json_hexbytes(json_out_t *w, const uint8_t *b, size_t len);

#endif /* RSM_DUMP_JSON_OUT_H */
