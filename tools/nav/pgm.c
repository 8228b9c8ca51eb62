#include "pgm.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int hitlist_add(hitlist_t *h, const rsm_point_t *p, size_t n)
{
    if (h->count + n > h->cap) {
        size_t cap = h->cap ? h->cap * 2 : 65536;
        rsm_point_t *np;
        while (cap < h->count + n) {
            cap *= 2;
        }
        np = (rsm_point_t *)realloc(h->pts, cap * sizeof *np);
        if (np == NULL) {
            return -1;
        }
        h->pts = np;
        h->cap = cap;
    }
    memcpy(h->pts + h->count, p, n * sizeof *p);
    h->count += n;
    return 0;
}

void hitlist_free(hitlist_t *h)
{
    free(h->pts);
    h->pts = NULL;
    h->count = h->cap = 0;
}

int pgm_write_map(const char *pgm_path, const hitlist_t *h, float res)
{
    float minx = 0.0f;
    float miny = 0.0f;
    float maxx = 0.0f;
    float maxy = 0.0f;
    size_t i;
    size_t w;
    size_t hgt;
    unsigned char *img;
    unsigned short *cnt;
    FILE *f;
    char yaml[4096];
    const char *base;
    size_t len;
    for (i = 0; i < h->count; ++i) {
        const rsm_point_t *p = &h->pts[i];
        if (i == 0 || p->x < minx) minx = p->x;
        if (i == 0 || p->y < miny) miny = p->y;
        if (i == 0 || p->x > maxx) maxx = p->x;
        if (i == 0 || p->y > maxy) maxy = p->y;
    }
    minx -= 1.0f;
    miny -= 1.0f;
    maxx += 1.0f;
    maxy += 1.0f;
    w = (size_t)ceilf((maxx - minx) / res);
    hgt = (size_t)ceilf((maxy - miny) / res);
    if (w == 0 || hgt == 0 || w > 20000 || hgt > 20000) {
        return -1;
    }
    cnt = (unsigned short *)calloc(w * hgt, sizeof *cnt);
    img = (unsigned char *)malloc(w * hgt);
    if (cnt == NULL || img == NULL) {
        free(cnt);
        free(img);
        return -1;
    }
    for (i = 0; i < h->count; ++i) {
        const size_t cx = (size_t)((h->pts[i].x - minx) / res);
        const size_t cy = (size_t)((h->pts[i].y - miny) / res);
        if (cx < w && cy < hgt && cnt[cy * w + cx] < 65535u) {
            cnt[cy * w + cx]++;
        }
    }
    for (i = 0; i < w * hgt; ++i) {
        /* Two hits make a wall; a single stray hit is shown faint. */
        img[i] = cnt[i] >= 2 ? 0 : (cnt[i] == 1 ? 120 : 205);
    }
    f = fopen(pgm_path, "wb");
    if (f == NULL) {
        free(cnt);
        free(img);
        return -1;
    }
    fprintf(f, "P5\n# rsm-nav map, %.3f m per pixel\n%zu %zu\n255\n", (double)res, w, hgt);
    /* PGM rows run top to bottom; the map's y axis runs up. */
    for (i = hgt; i-- > 0;) {
        fwrite(img + i * w, 1, w, f);
    }
    free(cnt);
    free(img);
    if (fclose(f) != 0) {
        return -1;
    }
    len = strlen(pgm_path);
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
            base, (double)res, (double)minx, (double)miny);
    return fclose(f) == 0 ? 0 : -1;
}
