#include "json_out.h"

#include <inttypes.h>
#include <math.h>
#include <string.h>

void json_out_init(json_out_t *w, FILE *f, int pretty)
{
    memset(w, 0, sizeof *w);
    w->f = f;
    w->pretty = pretty ? 1 : 0;
}

static void indent(json_out_t *w)
{
    int i;
    fputc('\n', w->f);
    for (i = 0; i < w->depth; ++i) {
        fputs("  ", w->f);
    }
}

/* Separator and indentation before a value or a key. */
static void before_item(json_out_t *w)
{
    if (w->after_key) {
        w->after_key = 0;
        return;
    }
    if (w->depth > 0 && w->depth <= JSON_OUT_MAX_DEPTH) {
        if (w->count[w->depth - 1] > 0) {
            fputc(',', w->f);
        }
        w->count[w->depth - 1]++;
        if (w->pretty) {
            indent(w);
        }
    }
}

static void open_container(json_out_t *w, int c)
{
    before_item(w);
    fputc(c, w->f);
    if (w->depth < JSON_OUT_MAX_DEPTH) {
        w->count[w->depth] = 0;
    }
    w->depth++;
}

static void close_container(json_out_t *w, int c)
{
    int had = 0;
    if (w->depth <= 0) {
        return;
    }
    if (w->depth <= JSON_OUT_MAX_DEPTH) {
        had = w->count[w->depth - 1];
    }
    w->depth--;
    if (w->pretty && had > 0) {
        indent(w);
    }
    fputc(c, w->f);
    if (w->depth == 0) {
        fputc('\n', w->f);
    }
}

void json_begin_obj(json_out_t *w)
{
    open_container(w, '{');
}

void json_end_obj(json_out_t *w)
{
    close_container(w, '}');
}

void json_begin_arr(json_out_t *w)
{
    open_container(w, '[');
}

void json_end_arr(json_out_t *w)
{
    close_container(w, ']');
}

static void raw_str(json_out_t *w, const char *s, size_t len)
{
    size_t i;
    fputc('"', w->f);
    for (i = 0; i < len; ++i) {
        const unsigned char c = (unsigned char)s[i];
        if (c == '"' || c == '\\') {
            fputc('\\', w->f);
            fputc(c, w->f);
        } else if (c == '\n') {
            fputs("\\n", w->f);
        } else if (c == '\r') {
            fputs("\\r", w->f);
        } else if (c == '\t') {
            fputs("\\t", w->f);
        } else if (c < 0x20u || c >= 0x7Fu) {
            /* Protocol text is bytes, not UTF-8: keep each one visible. */
            fprintf(w->f, "\\u%04x", (unsigned)c);
        } else {
            fputc(c, w->f);
        }
    }
    fputc('"', w->f);
}

void json_key(json_out_t *w, const char *key)
{
    before_item(w);
    raw_str(w, key, strlen(key));
    fputs(w->pretty ? ": " : ":", w->f);
    w->after_key = 1;
}

void json_int(json_out_t *w, int64_t v)
{
    before_item(w);
    fprintf(w->f, "%" PRId64, v);
}

void json_uint(json_out_t *w, uint64_t v)
{
    before_item(w);
    fprintf(w->f, "%" PRIu64, v);
}

void json_double(json_out_t *w, double v)
{
    before_item(w);
    if (!isfinite(v)) {
        fputs("null", w->f);
        return;
    }
    /* Six significant digits: millimetres up to 100 m, tenths of a degree. */
    fprintf(w->f, "%.6g", v);
}

void json_bool(json_out_t *w, int v)
{
    before_item(w);
    fputs(v ? "true" : "false", w->f);
}

void json_null(json_out_t *w)
{
    before_item(w);
    fputs("null", w->f);
}

void json_strn(json_out_t *w, const char *s, size_t len)
{
    before_item(w);
    raw_str(w, s, len);
}

void json_str(json_out_t *w, const char *s)
{
    json_strn(w, s, strlen(s));
}

void json_hex(json_out_t *w, uint32_t v, int width)
{
    before_item(w);
    fprintf(w->f, "\"0x%0*" PRIX32 "\"", width, v);
}

void json_hexbytes(json_out_t *w, const uint8_t *b, size_t len)
{
    size_t i;
    before_item(w);
    fputc('"', w->f);
    for (i = 0; i < len; ++i) {
        fprintf(w->f, i == 0u ? "%02X" : " %02X", (unsigned)b[i]);
    }
    fputc('"', w->f);
}
