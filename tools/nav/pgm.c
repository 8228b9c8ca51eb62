#include "pgm.h"
#include "heap.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Border of unknown cells around what was seen, metres. */
#define PGM_MARGIN_M 1.0f

int hitmap_init(hitmap_t *h, float res_m)
{
    memset(h, 0, sizeof *h);
    if (!(res_m > 0.0f) || !isfinite(res_m)) {
        return -1;
    }
    h->res_m = res_m;
    return 0;
}

void hitmap_free(hitmap_t *h)
{
    nav_free(h->keys);
    nav_free(h->hits);
    h->keys = NULL;
    h->hits = NULL;
    h->cap = h->count = 0;
}

/* Cell coordinates offset into 32 unsigned bits each; never 0 for a used
 * cell (|cx|, |cy| < 2^30, see hitmap_add). */
static uint64_t pack(int32_t cx, int32_t cy)
{
    return ((uint64_t)((uint32_t)cx ^ 0x80000000u) << 32) | (uint64_t)((uint32_t)cy ^ 0x80000000u);
}

static size_t slot_of(const hitmap_t *h, uint64_t key)
{
    uint64_t x = key * 0x9E3779B97F4A7C15ull;
    size_t i = (size_t)(x >> 20) & (h->cap - 1u);
    while (h->keys[i] != 0u && h->keys[i] != key) {
        i = (i + 1u) & (h->cap - 1u);
    }
    return i;
}

static int grow(hitmap_t *h)
{
    hitmap_t n = *h;
    size_t i;
    n.cap = h->cap ? h->cap * 2u : 4096u;
    n.keys = (uint64_t *)nav_calloc(n.cap, sizeof *n.keys);
    n.hits = (uint8_t *)nav_calloc(n.cap, sizeof *n.hits);
    if (n.keys == NULL || n.hits == NULL) {
        nav_free(n.keys);
        nav_free(n.hits);
        return -1;
    }
    for (i = 0; i < h->cap; ++i) {
        if (h->keys[i] != 0u) {
            const size_t j = slot_of(&n, h->keys[i]);
            n.keys[j] = h->keys[i];
            n.hits[j] = h->hits[i];
        }
    }
    nav_free(h->keys);
    nav_free(h->hits);
    *h = n;
    return 0;
}

int hitmap_add(hitmap_t *h, const rsm_point_t *p, size_t n)
{
    size_t k;
    for (k = 0; k < n; ++k) {
        float fx;
        float fy;
        int32_t cx;
        int32_t cy;
        uint64_t key;
        size_t i;
        /* Range first: the float-to-integer conversion is then defined. */
        if (!(fabsf(p[k].x) < PGM_MAX_COORD_M && fabsf(p[k].y) < PGM_MAX_COORD_M)) {
            h->far++;
            continue;
        }
        fx = floorf(p[k].x / h->res_m);
        fy = floorf(p[k].y / h->res_m);
        if (!(fabsf(fx) < 1.0e9f && fabsf(fy) < 1.0e9f)) {
            h->far++;
            continue;
        }
        cx = (int32_t)fx;
        cy = (int32_t)fy;
        if ((h->count + 1u) * 2u > h->cap && grow(h) != 0) {
            return -1;
        }
        key = pack(cx, cy);
        i = slot_of(h, key);
        if (h->keys[i] == 0u) {
            h->keys[i] = key;
            if (h->count == 0u || cx < h->min_x) h->min_x = cx;
            if (h->count == 0u || cy < h->min_y) h->min_y = cy;
            if (h->count == 0u || cx > h->max_x) h->max_x = cx;
            if (h->count == 0u || cy > h->max_y) h->max_y = cy;
            h->count++;
        }
        if (h->hits[i] < 255u) {
            h->hits[i]++;
        }
    }
    return 0;
}

static int write_yaml(const char *pgm_path, float res, double x0, double y0)
{
    char yaml[4096];
    const char *base;
    size_t len = strlen(pgm_path);
    FILE *f;
    if (len + 6 > sizeof yaml) {
        return -1;
    }
    memcpy(yaml, pgm_path, len + 1);
    if (len > 4 && strcmp(yaml + len - 4, ".pgm") == 0) {
        yaml[len - 4] = '\0';
    }
    strcat(yaml, ".yaml");
    base = strrchr(pgm_path, '/');
    base = base ? base + 1 : pgm_path;
    f = fopen(yaml, "w");
    if (f == NULL) {
        return -1;
    }
    fprintf(f, "image: %s\nresolution: %.6f\norigin: [%.6f, %.6f, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
            base, (double)res, x0, y0);
    return fclose(f) == 0 ? 0 : -1;
}

int pgm_write_map(const char *pgm_path, const hitmap_t *h, double off_x, double off_y, double *w_m, double *h_m)
{
    const int64_t margin = (int64_t)ceilf(PGM_MARGIN_M / h->res_m);
    int64_t x0;
    int64_t y0;
    int64_t w;
    int64_t hgt;
    unsigned char *img;
    size_t i;
    FILE *f;
    if (h->count == 0u) {
        return 0;
    }
    x0 = (int64_t)h->min_x - margin;
    y0 = (int64_t)h->min_y - margin;
    w = (int64_t)h->max_x + margin + 1 - x0;
    hgt = (int64_t)h->max_y + margin + 1 - y0;
    *w_m = (double)w * (double)h->res_m;
    *h_m = (double)hgt * (double)h->res_m;
    if (w > PGM_MAX_SIDE || hgt > PGM_MAX_SIDE) {
        return PGM_TOO_LARGE;
    }
    img = (unsigned char *)nav_malloc((size_t)w * (size_t)hgt);
    if (img == NULL) {
        return -1;
    }
    memset(img, 205, (size_t)w * (size_t)hgt);
    for (i = 0; i < h->cap; ++i) {
        if (h->keys[i] != 0u) {
            const int64_t cx = (int64_t)(int32_t)((uint32_t)(h->keys[i] >> 32) ^ 0x80000000u) - x0;
            const int64_t cy = (int64_t)(int32_t)(((uint32_t)h->keys[i]) ^ 0x80000000u) - y0;
            /* Two hits make a wall; a single stray hit is shown faint. */
            img[(size_t)cy * (size_t)w + (size_t)cx] = h->hits[i] >= 2u ? 0 : 120;
        }
    }
    f = fopen(pgm_path, "wb");
    if (f == NULL) {
        nav_free(img);
        return -1;
    }
    fprintf(f, "P5\n# rsm-nav map, %.3f m per pixel\n%lld %lld\n255\n", (double)h->res_m, (long long)w,
            (long long)hgt);
    /* PGM rows run top to bottom; the map's y axis runs up. */
    for (i = (size_t)hgt; i-- > 0;) {
        fwrite(img + i * (size_t)w, 1, (size_t)w, f);
    }
    nav_free(img);
    if (fclose(f) != 0) {
        return -1;
    }
    return write_yaml(pgm_path, h->res_m, off_x + (double)x0 * (double)h->res_m, off_y + (double)y0 * (double)h->res_m);
}
