/* Reading a ROS map into the persistent map: tools/nav/rosmap.h has the
 * contract. Host code: reads both files whole (heap), checks all of them,
 * then imports. */
#include "rosmap.h"
#include "heap.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rsm/status.h"

/* Larger YAML files are not maps. */
#define YAML_MAX_BYTES 65536L
/* Pixels an image may hold (a 20 km square at 1 m, 1 km at 5 cm). */
#define PGM_MAX_PIXELS 400000000.0

enum { MODE_TRINARY, MODE_SCALE, MODE_RAW };

typedef struct rosmap_yaml {
    char image[4096];
    double resolution;
    double origin[3];
    int negate;
    double occupied_thresh;
    double free_thresh;
    int mode;
    unsigned seen; /* bits: which keys were given */
} rosmap_yaml_t;

enum {
    SEEN_IMAGE = 1u,
    SEEN_RESOLUTION = 2u,
    SEEN_ORIGIN = 4u,
    SEEN_NEGATE = 8u,
    SEEN_OCCUPIED = 16u,
    SEEN_FREE = 32u,
    SEEN_MODE = 64u
};

static void say(char *err, size_t errcap, const char *fmt, ...)
{
    va_list ap;
    if (err == NULL || errcap == 0u) {
        return;
    }
    va_start(ap, fmt);
    (void)vsnprintf(err, errcap, fmt, ap);
    va_end(ap);
}

/* The whole file into a NUL-terminated heap buffer; NULL with err set. */
static unsigned char *read_all(const char *path, const char *what, long max_bytes, size_t *len, char *err,
                               size_t errcap)
{
    FILE *f = fopen(path, "rb");
    unsigned char *buf = NULL;
    size_t cap = 0;
    size_t n = 0;
    if (f == NULL) {
        say(err, errcap, "cannot open %s %s: %s", what, path, strerror(errno));
        return NULL;
    }
    for (;;) {
        size_t got;
        if (n + 1u >= cap) {
            unsigned char *nb;
            cap = cap ? cap * 2u : 65536u;
            nb = (unsigned char *)nav_realloc(buf, cap);
            if (nb == NULL) {
                say(err, errcap, "out of memory reading %s %s", what, path);
                nav_free(buf);
                (void)fclose(f);
                return NULL;
            }
            buf = nb;
        }
        got = fread(buf + n, 1, cap - n - 1u, f);
        n += got;
        if (max_bytes > 0 && n > (size_t)max_bytes) {
            say(err, errcap, "%s %s: larger than %ld bytes, not a map", what, path, max_bytes);
            nav_free(buf);
            (void)fclose(f);
            return NULL;
        }
        if (got == 0u) {
            break;
        }
    }
    if (ferror(f)) {
        say(err, errcap, "read error in %s %s: %s", what, path, strerror(errno));
        nav_free(buf);
        (void)fclose(f);
        return NULL;
    }
    (void)fclose(f);
    buf[n] = '\0';
    *len = n;
    return buf;
}

static char *trim(char *s)
{
    char *e;
    while (*s == ' ' || *s == '\t') {
        ++s;
    }
    e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r')) {
        *--e = '\0';
    }
    return s;
}

/* A quoted scalar ('...' or "...") unquoted in place; 0 if a quote is not
 * closed at the end. */
static int unquote(char **v)
{
    const size_t n = strlen(*v);
    if (n > 0u && (**v == '"' || **v == '\'')) {
        if (n < 2u || (*v)[n - 1u] != **v) {
            return 0;
        }
        (*v)[n - 1u] = '\0';
        ++*v;
    }
    return 1;
}

/* A whole finite number; 0 if v is anything else. */
static int number(const char *v, double *out)
{
    char *end;
    double d;
    if (*v == '\0') {
        return 0;
    }
    errno = 0;
    d = strtod(v, &end);
    while (*end == ' ' || *end == '\t') {
        ++end;
    }
    if (*end != '\0' || errno == ERANGE || !isfinite(d)) {
        return 0;
    }
    *out = d;
    return 1;
}

/* "[x, y, yaw]" */
static int parse_origin(char *v, double o[3])
{
    size_t n = strlen(v);
    char *p;
    int k;
    if (n < 2u || v[0] != '[' || v[n - 1u] != ']') {
        return 0;
    }
    v[n - 1u] = '\0';
    p = v + 1;
    for (k = 0; k < 3; ++k) {
        char *comma = strchr(p, ',');
        if ((k < 2) != (comma != NULL)) {
            return 0;
        }
        if (comma != NULL) {
            *comma = '\0';
        }
        if (!number(trim(p), &o[k])) {
            return 0;
        }
        p = comma != NULL ? comma + 1 : p;
    }
    return 1;
}

static int parse_yaml(char *text, const char *path, rosmap_yaml_t *y, char *err, size_t errcap)
{
    char *line = text;
    unsigned lineno = 0;
    memset(y, 0, sizeof *y);
    y->mode = MODE_TRINARY;
    while (line != NULL) {
        char *next = strchr(line, '\n');
        char *key;
        char *val;
        char *colon;
        char *hash;
        unsigned bit = 0;
        ++lineno;
        if (next != NULL) {
            *next++ = '\0';
        }
        /* A comment: '#' at the start or after a blank (not inside a
         * quoted file name such as 'map#2.pgm'). */
        for (hash = line; (hash = strchr(hash, '#')) != NULL; ++hash) {
            if (hash == line || hash[-1] == ' ' || hash[-1] == '\t') {
                *hash = '\0';
                break;
            }
        }
        key = trim(line);
        line = next;
        if (*key == '\0' || strcmp(key, "---") == 0 || strcmp(key, "...") == 0) {
            continue;
        }
        colon = strchr(key, ':');
        if (colon == NULL) {
            say(err, errcap, "%s:%u: not a 'key: value' line", path, lineno);
            return -1;
        }
        *colon = '\0';
        key = trim(key);
        val = trim(colon + 1);
        if (!unquote(&val)) {
            say(err, errcap, "%s:%u: %s: unclosed quote", path, lineno, key);
            return -1;
        }
        if (strcmp(key, "image") == 0) {
            bit = SEEN_IMAGE;
            if (*val == '\0' || strlen(val) >= sizeof y->image) {
                say(err, errcap, "%s:%u: image: %s", path, lineno, *val ? "path too long" : "empty");
                return -1;
            }
            strcpy(y->image, val);
        } else if (strcmp(key, "resolution") == 0) {
            bit = SEEN_RESOLUTION;
            if (!number(val, &y->resolution) || !(y->resolution > 0.0)) {
                say(err, errcap, "%s:%u: resolution '%s' is not a positive number of metres", path, lineno, val);
                return -1;
            }
        } else if (strcmp(key, "origin") == 0) {
            bit = SEEN_ORIGIN;
            if (!parse_origin(val, y->origin)) {
                say(err, errcap, "%s:%u: origin is not [x, y, yaw] of three numbers", path, lineno);
                return -1;
            }
        } else if (strcmp(key, "negate") == 0) {
            bit = SEEN_NEGATE;
            if (strcmp(val, "0") == 0 || strcmp(val, "false") == 0) {
                y->negate = 0;
            } else if (strcmp(val, "1") == 0 || strcmp(val, "true") == 0) {
                y->negate = 1;
            } else {
                say(err, errcap, "%s:%u: negate '%s' is not 0 or 1", path, lineno, val);
                return -1;
            }
        } else if (strcmp(key, "occupied_thresh") == 0 || strcmp(key, "free_thresh") == 0) {
            const int occ = key[0] == 'o';
            double *t = occ ? &y->occupied_thresh : &y->free_thresh;
            bit = occ ? SEEN_OCCUPIED : SEEN_FREE;
            if (!number(val, t) || *t < 0.0 || *t > 1.0) {
                say(err, errcap, "%s:%u: %s '%s' is not a number in [0, 1]", path, lineno, key, val);
                return -1;
            }
        } else if (strcmp(key, "mode") == 0) {
            bit = SEEN_MODE;
            if (strcmp(val, "trinary") == 0) {
                y->mode = MODE_TRINARY;
            } else if (strcmp(val, "scale") == 0) {
                y->mode = MODE_SCALE;
            } else if (strcmp(val, "raw") == 0) {
                y->mode = MODE_RAW;
            } else {
                say(err, errcap, "%s:%u: mode '%s' is not trinary, scale or raw", path, lineno, val);
                return -1;
            }
        } else {
            continue; /* another tool's key */
        }
        if ((y->seen & bit) != 0u) {
            say(err, errcap, "%s:%u: %s given twice", path, lineno, key);
            return -1;
        }
        y->seen |= bit;
    }
    {
        static const char *const names[] = {"image", "resolution", "origin", "negate", "occupied_thresh",
                                            "free_thresh"};
        unsigned k;
        for (k = 0; k < 6u; ++k) {
            if ((y->seen & (1u << k)) == 0u) {
                say(err, errcap, "%s: no '%s:' key (a ROS map YAML needs image, resolution, origin, negate, "
                                 "occupied_thresh and free_thresh)",
                    path, names[k]);
                return -1;
            }
        }
    }
    if (!(y->free_thresh < y->occupied_thresh)) {
        say(err, errcap, "%s: free_thresh %g is not below occupied_thresh %g", path, y->free_thresh,
            y->occupied_thresh);
        return -1;
    }
    return 0;
}

/* ---- PGM ---------------------------------------------------------------- */

typedef struct pgm {
    const unsigned char *b;
    size_t len;
    size_t at;
    const char *path;
} pgm_t;

/* Skips blanks and '#' comments. */
static void pgm_skip(pgm_t *p)
{
    while (p->at < p->len) {
        if (p->b[p->at] == '#') {
            while (p->at < p->len && p->b[p->at] != '\n' && p->b[p->at] != '\r') {
                p->at++;
            }
        } else if (isspace(p->b[p->at])) {
            p->at++;
        } else {
            break;
        }
    }
}

/* A decimal number after blanks and comments; -1 at the end, -2 for
 * anything else, -3 beyond limit. */
static long pgm_int(pgm_t *p, long limit)
{
    long v = 0;
    size_t start;
    pgm_skip(p);
    if (p->at >= p->len) {
        return -1;
    }
    start = p->at;
    while (p->at < p->len && isdigit(p->b[p->at])) {
        v = v * 10 + (long)(p->b[p->at] - '0');
        if (v > limit) {
            return -3;
        }
        p->at++;
    }
    if (p->at == start || (p->at < p->len && !isspace(p->b[p->at]) && p->b[p->at] != '#')) {
        return -2;
    }
    return v;
}

typedef struct pgm_image {
    uint32_t w;
    uint32_t h;
    uint32_t maxval;
    unsigned char *px; /* w * h, top row first */
} pgm_image_t;

static int read_pgm(const char *path, pgm_image_t *img, char *err, size_t errcap)
{
    size_t len = 0;
    /* No PGM this reader takes is larger: a device or a huge file is
     * refused before it fills memory. */
    unsigned char *buf = read_all(path, "image", (long)(PGM_MAX_PIXELS + 4096.0), &len, err, errcap);
    pgm_t p;
    long w;
    long h;
    long maxval;
    int ascii;
    size_t n;
    size_t k;
    if (buf == NULL) {
        return -1;
    }
    p.b = buf;
    p.len = len;
    p.at = 0;
    p.path = path;
    if (len < 2u || buf[0] != 'P' || (buf[1] != '5' && buf[1] != '2')) {
        say(err, errcap, "%s: not a PGM (P5 or P2): %s", path,
            len >= 2u && buf[0] == 'P' ? "another netpbm kind" : "no P5/P2 magic (PNG and others are not read)");
        nav_free(buf);
        return -1;
    }
    ascii = buf[1] == '2';
    p.at = 2;
    if (p.at < len && !isspace(buf[p.at]) && buf[p.at] != '#') {
        say(err, errcap, "%s: bad PGM magic", path);
        nav_free(buf);
        return -1;
    }
    w = pgm_int(&p, 1000000L);
    h = w > 0 ? pgm_int(&p, 1000000L) : w;
    maxval = h > 0 ? pgm_int(&p, 1000000L) : h;
    if (w == -1 || h == -1 || maxval == -1) {
        say(err, errcap, "%s: PGM header ends early (want width, height, maxval)", path);
        nav_free(buf);
        return -1;
    }
    if (w <= 0 || h <= 0) {
        say(err, errcap, "%s: PGM width and height must be whole numbers from 1 to 1000000", path);
        nav_free(buf);
        return -1;
    }
    if (maxval > 65535) {
        say(err, errcap, "%s: PGM maxval %ld is beyond 65535: not a PGM", path, maxval);
        nav_free(buf);
        return -1;
    }
    if (maxval > 255) {
        say(err, errcap, "%s: 16-bit PGM (maxval %ld) is not supported: save the map with 8 bits (maxval 255)",
            path, maxval);
        nav_free(buf);
        return -1;
    }
    if (maxval <= 0) {
        say(err, errcap, "%s: PGM maxval must be a whole number from 1 to 255", path);
        nav_free(buf);
        return -1;
    }
    if ((double)w * (double)h > PGM_MAX_PIXELS) {
        say(err, errcap, "%s: %ld x %ld pixels: more than %.0f", path, w, h, PGM_MAX_PIXELS);
        nav_free(buf);
        return -1;
    }
    n = (size_t)w * (size_t)h;
    img->w = (uint32_t)w;
    img->h = (uint32_t)h;
    img->maxval = (uint32_t)maxval;
    img->px = (unsigned char *)nav_malloc(n);
    if (img->px == NULL) {
        say(err, errcap, "%s: out of memory for %ld x %ld pixels", path, w, h);
        nav_free(buf);
        return -1;
    }
    if (!ascii) {
        /* Exactly one blank after maxval, then the rows. */
        if (p.at >= len) {
            say(err, errcap, "%s: truncated: no pixel data (want %ld x %ld)", path, w, h);
            goto fail;
        }
        p.at++;
        if (len - p.at < n) {
            const size_t got = len - p.at;
            say(err, errcap, "%s: truncated: %zu of %zu pixel bytes (row %zu of %ld is short; header says %ld x %ld)",
                path, got, n, got / (size_t)w + 1u, h, w, h);
            goto fail;
        }
        if (len - p.at > n) {
            say(err, errcap, "%s: %zu bytes after the last row: the size in the header (%ld x %ld) is wrong", path,
                len - p.at - n, w, h);
            goto fail;
        }
        memcpy(img->px, buf + p.at, n);
        for (k = 0; k < n; ++k) {
            if (img->px[k] > maxval) {
                say(err, errcap, "%s: pixel %zu of row %zu is %u, above maxval %ld", path, k % (size_t)w,
                    k / (size_t)w, (unsigned)img->px[k], maxval);
                goto fail;
            }
        }
    } else {
        for (k = 0; k < n; ++k) {
            const long v = pgm_int(&p, 65535L);
            if (v == -1) {
                say(err, errcap, "%s: truncated: %zu of %zu pixels (row %zu of %ld is short; header says %ld x %ld)",
                    path, k, n, k / (size_t)w + 1u, h, w, h);
                goto fail;
            }
            if (v < 0 || v > maxval) {
                say(err, errcap, "%s: pixel %zu of row %zu is not a number from 0 to maxval %ld", path,
                    k % (size_t)w, k / (size_t)w, maxval);
                goto fail;
            }
            img->px[k] = (unsigned char)v;
        }
        pgm_skip(&p);
        if (p.at < len) {
            say(err, errcap, "%s: data after the last pixel: the size in the header (%ld x %ld) is wrong", path, w,
                h);
            goto fail;
        }
    }
    nav_free(buf);
    return 0;
fail:
    nav_free(img->px);
    img->px = NULL;
    nav_free(buf);
    return -1;
}

/* map_server's reading of a pixel: occupied or not. */
static int occupied(const rosmap_yaml_t *y, uint32_t v, uint32_t maxval)
{
    double p;
    if (y->mode == MODE_RAW) {
        return v <= 100u && (double)v / 100.0 > y->occupied_thresh;
    }
    p = y->negate ? (double)v / (double)maxval : (double)(maxval - v) / (double)maxval;
    return p > y->occupied_thresh;
}

int rsm_rosmap_load(const char *yaml_path, rsm_localizer_t *loc, rsm_import_report_t *report, char *err,
                    size_t errcap)
{
    rosmap_yaml_t y;
    pgm_image_t img;
    rsm_import_grid_t grid;
    rsm_import_report_t rep;
    char image_path[8192];
    unsigned char *text;
    unsigned char *row;
    size_t len = 0;
    uint32_t r;
    int rc;
    say(err, errcap, "no error");
    if (yaml_path == NULL || loc == NULL) {
        say(err, errcap, "no map or no localizer given");
        return -1;
    }
    text = read_all(yaml_path, "map YAML", YAML_MAX_BYTES, &len, err, errcap);
    if (text == NULL) {
        return -1;
    }
    if (memchr(text, '\0', len) != NULL) {
        say(err, errcap, "%s: not a text file", yaml_path);
        nav_free(text);
        return -1;
    }
    rc = parse_yaml((char *)text, yaml_path, &y, err, errcap);
    nav_free(text);
    if (rc != 0) {
        return -1;
    }
    if (y.image[0] == '/') {
        (void)snprintf(image_path, sizeof image_path, "%s", y.image);
    } else {
        const char *slash = strrchr(yaml_path, '/');
        const int dir = slash != NULL ? (int)(slash - yaml_path + 1) : 0;
        if (strlen(yaml_path) + strlen(y.image) + 1u >= sizeof image_path) {
            say(err, errcap, "%s: image path too long", yaml_path);
            return -1;
        }
        (void)snprintf(image_path, sizeof image_path, "%.*s%s", dir, yaml_path, y.image);
    }
    grid.res_m = (float)y.resolution;
    grid.origin_x = (float)y.origin[0];
    grid.origin_y = (float)y.origin[1];
    grid.yaw_rad = (float)y.origin[2];
    grid.coarse = RSM_IMPORT_SHARE;
    /* What the import would refuse, refused before loc's map is emptied
     * (the width is the image's, read below: 1 stands in for it here). */
    grid.width = 1u;
    rc = rsm_localizer_import_check(loc, &grid);
    if (rc == RSM_ERR_INVAL) {
        say(err, errcap, "%s: resolution %g m or origin [%g, %g, %g] out of range: the resolution must be above 0,"
                         " at most 1000 m and no more than 256 of the map's %g m cells (or the localizer is not"
                         " initialised)", yaml_path, y.resolution, y.origin[0], y.origin[1], y.origin[2],
            loc->magic == (uint32_t)RSM_LOCALIZER_MAGIC && loc->cfg != NULL ? (double)loc->cfg->tmap.cell_m : 0.0);
        return -1;
    }
    memset(&img, 0, sizeof img);
    if (read_pgm(image_path, &img, err, errcap) != 0) {
        return -1;
    }
    grid.width = img.w;
    row = (unsigned char *)nav_malloc(img.w);
    if (row == NULL) {
        say(err, errcap, "out of memory");
        nav_free(img.px);
        return -1;
    }
    {
        /* A map with no wall gives nothing to localize in: refused while
         * loc is still as it was. */
        size_t k;
        const size_t n = (size_t)img.w * img.h;
        for (k = 0; k < n && !occupied(&y, img.px[k], img.maxval); ++k) {
        }
        if (k == n) {
            say(err, errcap, "%s: no occupied pixel in %s (occupied_thresh %g%s): nothing to localize in",
                yaml_path, image_path, y.occupied_thresh, y.negate ? ", negate" : "");
            nav_free(row);
            nav_free(img.px);
            return -1;
        }
    }
    /* Everything read and checked: only now is loc's map replaced. */
    rc = rsm_localizer_import_begin(loc, &rep);
    if (rc != RSM_OK) {
        say(err, errcap, "%s: cannot import into this localizer: %s%s", yaml_path, rsm_strerror(rc),
            rc == RSM_ERR_NOSYS ? " (a map is only for the map method)" : "");
        nav_free(row);
        nav_free(img.px);
        return -1;
    }
    for (r = 0; r < img.h; ++r) {
        const unsigned char *src = img.px + (size_t)r * img.w;
        uint32_t k;
        for (k = 0; k < img.w; ++k) {
            row[k] = (unsigned char)occupied(&y, src[k], img.maxval);
        }
        /* The PGM's first row is the map's top: row h - 1 from the origin. */
        rc = rsm_localizer_import_row(loc, &grid, img.h - 1u - r, row, &rep);
        if (rc != RSM_OK && rc != RSM_ERR_NOMEM) {
            say(err, errcap, "%s: resolution %g m or origin [%g, %g, %g] refused by the localizer (%s); its map "
                             "is left empty",
                yaml_path, y.resolution, y.origin[0], y.origin[1], y.origin[2], rsm_strerror(rc));
            nav_free(row);
            nav_free(img.px);
            (void)rsm_localizer_import_begin(loc, NULL);
            return -1;
        }
    }
    nav_free(row);
    nav_free(img.px);
    if (report != NULL) {
        *report = rep;
    }
    if (rep.dropped > 0u || rep.outside > 0u) {
        say(err, errcap,
            "%s: imported incomplete: %u cell writes dropped (the pool of %u tiles is full), %u of %u occupied "
            "pixels beyond the map's range",
            yaml_path, (unsigned)rep.dropped, (unsigned)RSM_TMAP_TILES, (unsigned)rep.outside,
            (unsigned)rep.occupied);
        return 1;
    }
    say(err, errcap, "%s: %u occupied pixels of %u x %u imported", yaml_path, (unsigned)rep.occupied,
        (unsigned)img.w, (unsigned)img.h);
    return 0;
}
