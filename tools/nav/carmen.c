#include "carmen.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

int carmen_open(carmen_reader_t *r, const char *path)
{
    memset(&r->counts, 0, sizeof r->counts);
    r->gz = gzopen(path, "rb");
    return r->gz != NULL ? 0 : -1;
}

void carmen_close(carmen_reader_t *r)
{
    if (r->gz != NULL) {
        gzclose((gzFile)r->gz);
        r->gz = NULL;
    }
}

/* Splits line into at most cap whitespace-separated fields in place. */
static size_t split(char *line, char **f, size_t cap)
{
    size_t n = 0;
    char *p = line;
    while (*p != '\0') {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') {
            *p++ = '\0';
        }
        if (*p == '\0') {
            break;
        }
        if (n == cap) {
            return cap + 1;
        }
        f[n++] = p;
        while (*p != '\0' && *p != ' ' && *p != '\t' && *p != '\r' && *p != '\n') {
            ++p;
        }
    }
    return n;
}

static int num(const char *s, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return end != s && *end == '\0' && errno == 0;
}

#define MAX_FIELDS 4096

static carmen_kind_t parse_flaser(carmen_reader_t *r, char **f, size_t nf, carmen_record_t *rec)
{
    double v;
    size_t n;
    size_t i;
    if (nf < 2 || !num(f[1], &v) || v < 0.0 || v > 100000.0) {
        return CARMEN_EOF;
    }
    n = (size_t)v;
    if (nf < 2 + n + 9) {
        return CARMEN_EOF;
    }
    if (n > RSM_MAX_BEAMS) {
        r->counts.too_many_beams++;
        return CARMEN_SKIPPED;
    }
    for (i = 0; i < n; ++i) {
        if (!num(f[2 + i], &v)) {
            return CARMEN_EOF;
        }
        /* NaN stays NaN: the core counts and drops it. */
        rec->range_m[i] = (float)v;
    }
    {
        double ox;
        double oy;
        double ot;
        double ts;
        if (!num(f[2 + n + 3], &ox) || !num(f[2 + n + 4], &oy) || !num(f[2 + n + 5], &ot) || !num(f[2 + n + 6], &ts) ||
            !isfinite(ox) || !isfinite(oy) || !isfinite(ot) || !isfinite(ts)) {
            return CARMEN_EOF;
        }
        rec->odom.x = (float)ox;
        rec->odom.y = (float)oy;
        rec->odom.theta = (float)ot;
        rec->stamp_s = ts;
    }
    rec->count = n;
    rec->start_rad = -RSM_PI / 2.0f;
    /* The usual CARMEN reading: 180 beams at 1 degree from -90 degrees. */
    rec->step_rad = (r->fov179 && n > 1) ? RSM_PI / (float)(n - 1) : RSM_PI / (float)(n > 0 ? n : 1);
    rec->max_range_m = 0.0f;
    rec->kind = CARMEN_SCAN;
    return CARMEN_SCAN;
}

/* ROBOTLASER1 type start fov res maxrange acc remmode n r... m rem... lx ly lt rx ry rt tv rv fs ss ta ts host lts */
static carmen_kind_t parse_robotlaser(carmen_reader_t *r, char **f, size_t nf, carmen_record_t *rec)
{
    double start;
    double fov;
    double res;
    double maxr;
    double v;
    size_t n;
    size_t m;
    size_t i;
    size_t base;
    if (nf < 9 || !num(f[2], &start) || !num(f[3], &fov) || !num(f[4], &res) || !num(f[5], &maxr) ||
        !num(f[8], &v) || v < 0.0 || v > 100000.0) {
        return CARMEN_EOF;
    }
    n = (size_t)v;
    if (nf < 9 + n + 1) {
        return CARMEN_EOF;
    }
    if (!num(f[9 + n], &v) || v < 0.0 || v > 100000.0) {
        return CARMEN_EOF;
    }
    m = (size_t)v;
    base = 10 + n + m;
    if (nf < base + 14) {
        return CARMEN_EOF;
    }
    if (n > RSM_MAX_BEAMS) {
        r->counts.too_many_beams++;
        return CARMEN_SKIPPED;
    }
    for (i = 0; i < n; ++i) {
        if (!num(f[9 + i], &v)) {
            return CARMEN_EOF;
        }
        rec->range_m[i] = (float)v;
    }
    {
        double rx;
        double ry;
        double rt;
        double ts;
        if (!num(f[base + 3], &rx) || !num(f[base + 4], &ry) || !num(f[base + 5], &rt) || !num(f[base + 11], &ts) ||
            !isfinite(rx) || !isfinite(ry) || !isfinite(rt) || !isfinite(ts)) {
            return CARMEN_EOF;
        }
        rec->odom.x = (float)rx;
        rec->odom.y = (float)ry;
        rec->odom.theta = (float)rt;
        rec->stamp_s = ts;
    }
    rec->count = n;
    rec->start_rad = (float)start;
    rec->step_rad = (float)res;
    rec->max_range_m = (float)maxr;
    rec->kind = CARMEN_SCAN;
    return CARMEN_SCAN;
}

static carmen_kind_t parse_odom(char **f, size_t nf, carmen_record_t *rec)
{
    double x;
    double y;
    double t;
    double ts;
    if (nf < 8 || !num(f[1], &x) || !num(f[2], &y) || !num(f[3], &t) || !num(f[7], &ts) || !isfinite(x) ||
        !isfinite(y) || !isfinite(t) || !isfinite(ts)) {
        return CARMEN_EOF;
    }
    rec->odom.x = (float)x;
    rec->odom.y = (float)y;
    rec->odom.theta = (float)t;
    rec->stamp_s = ts;
    rec->count = 0;
    rec->kind = CARMEN_ODOM;
    return CARMEN_ODOM;
}

carmen_kind_t carmen_next(carmen_reader_t *r, carmen_record_t *rec)
{
    static const size_t cap = MAX_FIELDS;
    char *f[MAX_FIELDS];
    for (;;) {
        size_t nf;
        size_t len;
        carmen_kind_t k;
        if (gzgets((gzFile)r->gz, r->line, (int)sizeof r->line) == NULL) {
            return CARMEN_EOF;
        }
        r->counts.lines++;
        len = strlen(r->line);
        if (len == sizeof r->line - 1 && r->line[len - 1] != '\n') {
            /* Skip the rest of an over-long line. */
            int c;
            r->counts.too_long++;
            while ((c = gzgetc((gzFile)r->gz)) != -1 && c != '\n') {
            }
            continue;
        }
        nf = split(r->line, f, cap);
        if (nf == 0 || f[0][0] == '#') {
            r->counts.comments++;
            continue;
        }
        if (nf > cap) {
            r->counts.malformed++;
            continue;
        }
        if (strcmp(f[0], "FLASER") == 0) {
            k = parse_flaser(r, f, nf, rec);
        } else if (strcmp(f[0], "ROBOTLASER1") == 0) {
            k = parse_robotlaser(r, f, nf, rec);
        } else if (strcmp(f[0], "ODOM") == 0) {
            k = parse_odom(f, nf, rec);
        } else {
            r->counts.unknown++;
            continue;
        }
        if (k == CARMEN_SKIPPED) {
            continue;
        }
        if (k == CARMEN_EOF) {
            r->counts.malformed++;
            continue;
        }
        if (k == CARMEN_SCAN) {
            r->counts.scans++;
        } else {
            r->counts.odoms++;
        }
        return k;
    }
}
