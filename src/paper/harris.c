#include "paper/harris.h"

#include "rsm/status.h"

/* 25-bit patch window must not overflow the structure-tensor sums. */
RSM_STATIC_ASSERT(harris_sums_fit, 16 * 16 * 2 < 32768);

rsm_harris_config_t rsm_harris_config_default(void)
{
    rsm_harris_config_t c;
    c.k_num = 1;
    c.k_den = 25;
    c.min_response = 1;
    c.nms_radius = 1;
    return c;
}

uint32_t rsm_harris_patch_image(const void *ctx, int32_t gx, int32_t gy)
{
    const rsm_harris_image_src_t *src = (const rsm_harris_image_src_t *)ctx;
    uint32_t patch = 0;
    uint32_t bit = 0;
    int32_t dy;
    int32_t dx;
    for (dy = -2; dy <= 2; ++dy) {
        for (dx = -2; dx <= 2; ++dx) {
            if (rsm_image_get(src->img, src->win, gx + dx, gy + dy)) {
                patch |= 1u << bit;
            }
            ++bit;
        }
    }
    return patch;
}

int32_t rsm_harris_response(const rsm_harris_config_t *cfg, uint32_t patch)
{
    static const int32_t w[3] = {1, 2, 1};
    int32_t p[5][5];
    int32_t sv[3][5]; /* vertical 1-2-1 smoothing of rows 1..3 */
    int32_t sh[5][3]; /* horizontal 1-2-1 smoothing of columns 1..3 */
    int32_t sxx = 0;
    int32_t syy = 0;
    int32_t sxy = 0;
    int32_t x;
    int32_t y;
    if (patch == 0u) {
        return 0; /* nothing occupied: no structure at all */
    }
    for (y = 0; y < 5; ++y) {
        for (x = 0; x < 5; ++x) {
            p[y][x] = (int32_t)((patch >> (uint32_t)(y * 5 + x)) & 1u);
        }
    }
    /* Sobel = 1-2-1 smoothing across the derivative direction, then a
     * central difference; smoothing once shares work between the nine
     * window pixels. */
    for (y = 1; y <= 3; ++y) {
        for (x = 0; x < 5; ++x) {
            sv[y - 1][x] = p[y - 1][x] + 2 * p[y][x] + p[y + 1][x];
        }
    }
    for (y = 0; y < 5; ++y) {
        for (x = 1; x <= 3; ++x) {
            sh[y][x - 1] = p[y][x - 1] + 2 * p[y][x] + p[y][x + 1];
        }
    }
    for (y = 1; y <= 3; ++y) {
        for (x = 1; x <= 3; ++x) {
            const int32_t ix = sv[y - 1][x + 1] - sv[y - 1][x - 1];
            const int32_t iy = sh[y + 1][x - 1] - sh[y - 1][x - 1];
            const int32_t wt = w[x - 1] * w[y - 1];
            sxx += wt * ix * ix;
            syy += wt * iy * iy;
            sxy += wt * ix * iy;
        }
    }
    {
        const int32_t det = sxx * syy - sxy * sxy;
        const int32_t tr = sxx + syy;
        return cfg->k_den * det - cfg->k_num * tr * tr;
    }
}

/* Sift-down for a max-heap of candidate indices keyed by response, with the
 * lower index winning ties so that the order is fully deterministic. */
static int before(const rsm_harris_work_t *wk, uint32_t a, uint32_t b)
{
    if (wk->response[a] != wk->response[b]) {
        return wk->response[a] < wk->response[b];
    }
    return a > b;
}

static void sift_down(rsm_harris_work_t *wk, size_t root, size_t n)
{
    for (;;) {
        size_t child = 2 * root + 1;
        uint32_t tmp;
        if (child >= n) {
            return;
        }
        if (child + 1 < n && before(wk, wk->order[child], wk->order[child + 1])) {
            ++child;
        }
        if (!before(wk, wk->order[root], wk->order[child])) {
            return;
        }
        tmp = wk->order[root];
        wk->order[root] = wk->order[child];
        wk->order[child] = tmp;
        root = child;
    }
}

int rsm_harris_detect(const rsm_harris_config_t *cfg, rsm_harris_work_t *work, rsm_patch_fn patch,
                      const void *ctx, const rsm_cell_t *cands, size_t n, rsm_keypoint_t *out, size_t cap,
                      size_t *skipped)
{
    size_t m = 0;
    size_t i;
    size_t heap;
    size_t kept = 0;
    if (cfg == NULL || work == NULL || patch == NULL || (n > 0 && cands == NULL) || (cap > 0 && out == NULL) ||
        cfg->k_den <= 0 || cfg->k_num < 0 || cfg->nms_radius < 0) {
        return RSM_ERR_INVAL;
    }
    if (skipped != NULL) {
        *skipped = n > RSM_MAX_CANDIDATES ? n - RSM_MAX_CANDIDATES : 0;
    }
    if (n > RSM_MAX_CANDIDATES) {
        n = RSM_MAX_CANDIDATES;
    }
    for (i = 0; i < n; ++i) {
        const int32_t r = rsm_harris_response(cfg, patch(ctx, cands[i].gx, cands[i].gy));
        if (r > cfg->min_response) {
            work->response[i] = r;
            work->order[m++] = (uint32_t)i;
        }
    }
    /* Heap-select strongest first; stop as soon as cap key points are kept. */
    for (i = m / 2; i-- > 0;) {
        sift_down(work, i, m);
    }
    heap = m;
    while (heap > 0 && kept < cap) {
        const uint32_t best = work->order[0];
        const rsm_cell_t c = cands[best];
        size_t k;
        int suppressed = 0;
        work->order[0] = work->order[--heap];
        sift_down(work, 0, heap);
        for (k = 0; k < kept; ++k) {
            const int32_t ddx = out[k].gx - c.gx;
            const int32_t ddy = out[k].gy - c.gy;
            if (ddx <= cfg->nms_radius && ddx >= -cfg->nms_radius && ddy <= cfg->nms_radius &&
                ddy >= -cfg->nms_radius) {
                suppressed = 1;
                break;
            }
        }
        if (!suppressed) {
            out[kept].gx = c.gx;
            out[kept].gy = c.gy;
            out[kept].response = work->response[best];
            ++kept;
        }
    }
    return (int)kept;
}
