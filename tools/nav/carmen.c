#include "carmen.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

int carmen_open(carmen_reader_t *r, const char *path)
{
    memset(&r->counts, 0, sizeof r->counts);
    r->error[0] = '\0';
    r->gz = gzopen(path, "rb");
    return r->gz != NULL ? 0 : -1;
}

const char *carmen_error(const carmen_reader_t *r)
{
    return r->error;
}

/* After gzgets or gzgetc found nothing more: 1 if that was a read error or
 * a damaged gzip stream (zlib's word for it kept), 0 at a clean end. */
static int stream_failed(carmen_reader_t *r)
{
    int code = Z_OK;
    const char *msg = gzerror((gzFile)r->gz, &code);
    if (code == Z_OK) {
        return 0;
    }
    if (r->error[0] == '\0') {
        snprintf(r->error, sizeof r->error, "%s after line %llu",
                 code == Z_ERRNO ? strerror(errno) : (msg != NULL ? msg : "read error"),
                 (unsigned long long)r->counts.lines);
    }
    return 1;
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

/* A decimal number (or inf, nan), as the Python reader takes it: strtod
 * alone would also take hexadecimal (0x10 as 16) and nan(...). */
static int num(const char *s, double *out)
{
    char *end;
    if (strpbrk(s, "xX(") != NULL) {
        return 0;
    }
    errno = 0;
    *out = strtod(s, &end);
    return end != s && *end == '\0' && errno == 0;
}

/* Fields f[0..n) all finite numbers (the fields the reader does not use,
 * checked as the Python reader checks them). */
static int finite_fields(char **f, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        double v;
        if (!num(f[i], &v) || !isfinite(v)) {
            return 0;
        }
    }
    return 1;
}

/* Three numbers from f[0..2]: 1 finite, 0 not numbers, -1 NaN or infinite. */
static int pose3(char **f, double v[3])
{
    int i;
    for (i = 0; i < 3; ++i) {
        if (!num(f[i], &v[i])) {
            return 0;
        }
    }
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]) ? 1 : -1;
}

/* The pose "to" seen from the pose "from", both in the same (odometry)
 * frame: the laser's mount from the robot and laser poses, or an odometry
 * increment. Doubles: log poses can be hundreds of metres from the origin,
 * where a float keeps only about 0.1 mm. */
rsm_pose_t carmen_between(const double from[3], const double to[3])
{
    const double dx = to[0] - from[0];
    const double dy = to[1] - from[1];
    const double c = cos(from[2]);
    const double s = sin(from[2]);
    const double dt = to[2] - from[2];
    rsm_pose_t m;
    m.x = (float)(c * dx + s * dy);
    m.y = (float)(-s * dx + c * dy);
    m.theta = (float)atan2(sin(dt), cos(dt));
    return m;
}

#define MAX_FIELDS 4096

static void set_odom(carmen_record_t *rec, const double pose[3])
{
    rec->odom_d[0] = pose[0];
    rec->odom_d[1] = pose[1];
    rec->odom_d[2] = pose[2];
    rec->odom.x = (float)pose[0];
    rec->odom.y = (float)pose[1];
    rec->odom.theta = (float)pose[2];
}

/* A count of readings: decimal digits only, as CARMEN writes it (%d) and
 * the Python reader takes it (0x10, 16.0, 1e1, +16 and NaN are malformed),
 * at most MAX_FIELDS. */
static int count_field(const char *s, size_t *out)
{
    size_t v = 0;
    const char *p = s;
    if (*p == '\0') {
        return 0;
    }
    for (; *p != '\0'; ++p) {
        if (*p < '0' || *p > '9') {
            return 0;
        }
        v = v * 10u + (size_t)(*p - '0');
        if (v > MAX_FIELDS) {
            return 0;
        }
    }
    *out = v;
    return 1;
}

static carmen_kind_t parse_flaser(carmen_reader_t *r, char **f, size_t nf, carmen_record_t *rec)
{
    double v;
    size_t n;
    size_t i;
    /* FLASER n r... lx ly lt ox oy ot ts host lts: exactly these fields */
    if (nf < 2 || !count_field(f[1], &n)) {
        return CARMEN_EOF;
    }
    if (nf != 2 + n + 9 || !finite_fields(&f[2 + n + 8], 1)) {
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
        double laser[3];
        double odom[3];
        double ts;
        const int lp = pose3(&f[2 + n], laser);
        const int op = pose3(&f[2 + n + 3], odom);
        if (lp == 0 || op == 0 || !num(f[2 + n + 6], &ts)) {
            return CARMEN_EOF;
        }
        if (lp < 0 || op < 0 || !isfinite(ts)) {
            return CARMEN_BAD_POSE;
        }
        set_odom(rec, odom);
        rec->stamp_s = ts;
        /* Identical triples (Intel, ACES) say nothing about the mount. */
        rec->has_mount = laser[0] != odom[0] || laser[1] != odom[1] || laser[2] != odom[2];
        if (rec->has_mount) {
            r->counts.flaser_offset++;
            rec->mount = carmen_between(odom, laser);
        }
    }
    rec->count = n;
    rec->start_rad = -RSM_PI / 2.0f;
    /* The usual CARMEN reading: 180 beams at 1 degree from -90 degrees. */
    rec->step_rad = (r->fov179 && n > 1) ? RSM_PI / (float)(n - 1) : RSM_PI / (float)(n > 0 ? n : 1);
    rec->max_range_m = 0.0f;
    rec->kind = CARMEN_SCAN;
    return CARMEN_SCAN;
}

/* ROBOTLASER1 type start fov res maxrange acc remmode n r... m rem... lx ly lt rx ry rt tv rv fs ss ta ts host lts
 * (base+0..2: the laser's pose, base+3..5: the robot's, both in the odometry
 * frame; the mount is the first seen from the second). */
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
    size_t code;
    if (nf < 9 || !count_field(f[1], &code) || !num(f[2], &start) || !num(f[3], &fov) || !num(f[4], &res) ||
        !num(f[5], &maxr) || !isfinite(start) || !isfinite(fov) || !isfinite(res) || !isfinite(maxr) ||
        !finite_fields(&f[6], 1) || !count_field(f[7], &code) || !count_field(f[8], &n)) {
        return CARMEN_EOF; /* the laser type (f[1]) and remission mode (f[7]) are counts too */
    }
    if (nf < 9 + n + 1 || !count_field(f[9 + n], &m)) {
        return CARMEN_EOF;
    }
    base = 10 + n + m;
    if (nf != base + 14 || !finite_fields(&f[base + 6], 5) || !finite_fields(&f[base + 13], 1)) {
        return CARMEN_EOF;
    }
    for (i = 0; i < m; ++i) {
        if (!num(f[10 + n + i], &v)) { /* remissions: numbers, NaN and inf as readings */
            return CARMEN_EOF;
        }
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
        double laser[3];
        double robot[3];
        double ts;
        const int lp = pose3(&f[base], laser);
        const int rp = pose3(&f[base + 3], robot);
        if (lp == 0 || rp == 0 || !num(f[base + 11], &ts)) {
            return CARMEN_EOF;
        }
        if (lp < 0 || rp < 0 || !isfinite(ts)) {
            return CARMEN_BAD_POSE;
        }
        set_odom(rec, robot);
        rec->stamp_s = ts;
        rec->has_mount = 1;
        rec->mount = carmen_between(robot, laser);
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
    /* ODOM x y theta tv rv accel ts host lts: exactly these fields */
    if (nf != 10 || !num(f[1], &x) || !num(f[2], &y) || !num(f[3], &t) || !num(f[7], &ts) ||
        !finite_fields(&f[4], 3) || !finite_fields(&f[9], 1)) {
        return CARMEN_EOF;
    }
    if (!isfinite(x) || !isfinite(y) || !isfinite(t) || !isfinite(ts)) {
        return CARMEN_BAD_POSE;
    }
    {
        const double pose[3] = {x, y, t};
        set_odom(rec, pose);
    }
    rec->stamp_s = ts;
    rec->count = 0;
    rec->has_mount = 0;
    rec->kind = CARMEN_ODOM;
    return CARMEN_ODOM;
}

/* Reads the next line into r->line; 0 at the end. Over-long lines are
 * counted and skipped. */
static int read_line(carmen_reader_t *r)
{
    const size_t last = sizeof r->line - 1;
    if (r->error[0] != '\0') {
        return -1;
    }
    for (;;) {
        /* gzgets ends what it stored with a NUL: at the very end only when
         * the buffer filled up. strlen cannot tell, a NUL inside the line
         * would make the rest of it read as a line of its own. */
        r->line[last] = 'x';
        if (gzgets((gzFile)r->gz, r->line, (int)sizeof r->line) == NULL) {
            return stream_failed(r) ? -1 : 0;
        }
        r->counts.lines++;
        if (r->line[last] == '\0' && r->line[last - 1] != '\n') {
            /* Skip the rest of an over-long line. */
            int c;
            r->counts.too_long++;
            while ((c = gzgetc((gzFile)r->gz)) != -1 && c != '\n') {
            }
            if (c == -1 && stream_failed(r)) {
                return -1;
            }
            continue;
        }
        return 1;
    }
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

/* 1 when a FLASER line's two pose triples differ (or cannot be told apart
 * cheaply), 0 when they are equal. Looks only at the line's last nine fields
 * (laser pose, odometry pose, stamp, host, logger stamp), so that a log whose
 * triples are all equal is checked without parsing its readings. */
static int flaser_triples_differ(const char *line)
{
    char tail[512];
    char *f[10];
    const char *p = line + strlen(line);
    double a[3];
    double b[3];
    size_t k;
    for (k = 0; k < 9; ++k) {
        while (p > line && is_space(p[-1])) {
            --p;
        }
        while (p > line && !is_space(p[-1])) {
            --p;
        }
    }
    if (strlen(p) >= sizeof tail) {
        return 1;
    }
    memcpy(tail, p, strlen(p) + 1);
    if (split(tail, f, 10) != 9 || pose3(&f[0], a) != 1 || pose3(&f[3], b) != 1) {
        return 1; /* the full parser decides */
    }
    return a[0] != b[0] || a[1] != b[1] || a[2] != b[2];
}

/* Parses the line in r->line; CARMEN_EOF for a malformed one. */
static carmen_kind_t parse_line(carmen_reader_t *r, carmen_record_t *rec, size_t *nfields)
{
    static const size_t cap = MAX_FIELDS;
    char *f[MAX_FIELDS];
    const size_t nf = split(r->line, f, cap);
    *nfields = nf;
    if (nf == 0 || f[0][0] == '#') {
        r->counts.comments++;
        return CARMEN_SKIPPED;
    }
    if (nf > cap) {
        return CARMEN_EOF;
    }
    if (strcmp(f[0], "FLASER") == 0) {
        rec->type = "FLASER";
        return parse_flaser(r, f, nf, rec);
    }
    if (strcmp(f[0], "ROBOTLASER1") == 0) {
        rec->type = "ROBOTLASER1";
        return parse_robotlaser(r, f, nf, rec);
    }
    if (strcmp(f[0], "ODOM") == 0) {
        rec->type = "ODOM";
        return parse_odom(f, nf, rec);
    }
    r->counts.unknown++;
    return CARMEN_SKIPPED;
}

carmen_kind_t carmen_next(carmen_reader_t *r, carmen_record_t *rec)
{
    for (;;) {
        size_t nf;
        carmen_kind_t k;
        const int got = read_line(r);
        if (got <= 0) {
            return got < 0 ? CARMEN_ERROR : CARMEN_EOF;
        }
        k = parse_line(r, rec, &nf);
        if (k == CARMEN_SKIPPED) {
            continue;
        }
        if (k == CARMEN_EOF || k == CARMEN_BAD_POSE) {
            r->counts.malformed++;
            if (k == CARMEN_BAD_POSE) {
                r->counts.bad_pose++;
            }
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

carmen_kind_t carmen_next_mount(carmen_reader_t *r, carmen_record_t *rec)
{
    for (;;) {
        size_t nf;
        const char *p;
        if (read_line(r) <= 0) {
            return CARMEN_EOF; /* the real pass reports errors */
        }
        p = r->line;
        while (is_space(*p)) {
            ++p;
        }
        if (strncmp(p, "ROBOTLASER1", 11) == 0 ||
            (strncmp(p, "FLASER", 6) == 0 && flaser_triples_differ(p))) {
            if (parse_line(r, rec, &nf) == CARMEN_SCAN && rec->has_mount) {
                return CARMEN_SCAN;
            }
        }
    }
}
