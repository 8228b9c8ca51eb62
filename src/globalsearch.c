/* Branch and bound over the whole map: src/globalsearch.h has the method,
 * docs/globalsearch.md the measurements. */
#include "globalsearch.h"

#include <math.h>
#include <string.h>

#include "fmath.h"
#include "rsm/status.h"

/* A pose is kept while it scores within this share of the best: its rivals
 * must be descended too, or a wrong winner could not be told apart. */
#define KEEP_SHARE 0.2f
/* Blocks of at most 2^MAX_BASE_H cells (beyond: RSM_ERR_NOMEM). */
#define MAX_BASE_H ((uint32_t)RSM_GLOBAL_MAX_BASE_H)
/* The first bound grid has blocks of 2^MIN_BASE_H cells: smaller windows
 * are read from the map's coarser levels (box_bound). */
#define MIN_BASE_H 2u

/* Floor division by 2^h for any sign. */
static int32_t floor_shift(int32_t v, uint32_t h)
{
    return v >= 0 ? (int32_t)((uint32_t)v >> h) : -(int32_t)(((uint32_t)(-(v + 1)) >> h) + 1u);
}

/* The level scored: the second coarsest (0.2 m cells by default). The
 * coarsest (0.4 m) is too full to tell places apart in a building:
 * measured on the Intel log, dozens of wrong poses put every point of a
 * scan on an occupied coarse cell. */
static uint32_t search_level(const rsm_tmap_t *map)
{
    return map->cfg.levels >= 2u ? (uint32_t)map->cfg.levels - 2u : 0u;
}

/* The level whose walls give the map's directions: one finer. */
static uint32_t direction_level(uint32_t level)
{
    return level > 0u ? level - 1u : 0u;
}

/* The smallest block exponent whose grid of a w-cell-wide map has at most
 * RSM_GLOBAL_SIDE blocks a side; MAX_BASE_H + 1 when none has. */
static uint32_t base_for(uint32_t w)
{
    uint32_t h = MIN_BASE_H;
    while (h <= MAX_BASE_H && ((w + (1u << h) - 1u) >> h) > (uint32_t)RSM_GLOBAL_SIDE) {
        ++h;
    }
    return h;
}

static uint32_t map_width(int32_t gx0, int32_t gy0, int32_t gx1, int32_t gy1)
{
    return (uint32_t)((gx1 - gx0 > gy1 - gy0 ? gx1 - gx0 : gy1 - gy0) + 1);
}

int rsm_global_check(const rsm_tmap_t *map)
{
    int32_t b[4];
    if (!rsm_tmap_bounds(map, search_level(map), &b[0], &b[1], &b[2], &b[3])) {
        return RSM_ERR_DEGENERATE;
    }
    return base_for(map_width(b[0], b[1], b[2], b[3])) <= MAX_BASE_H ? RSM_OK : RSM_ERR_NOMEM;
}

/* The blocks' maxima of the coarsest level into grid 0, then each grid's
 * 2 x 2 maxima into the next, down to one block. */
static int build_grids(rsm_global_t *g, uint8_t *grid, const rsm_tmap_t *map, int32_t gx0, int32_t gy0, int32_t gx1, int32_t gy1)
{
    const uint32_t level = g->level;
    const uint32_t w = map_width(gx0, gy0, gx1, gy1);
    uint32_t at = 0;
    uint32_t side;
    uint32_t s;
    uint32_t k;
    g->base_h = base_for(w);
    if (g->base_h > MAX_BASE_H) {
        return RSM_ERR_NOMEM;
    }
    g->ox = gx0;
    g->oy = gy0;
    side = (w + (1u << g->base_h) - 1u) >> g->base_h;
    g->grids = 0;
    for (;;) {
        if (g->grids == (uint32_t)RSM_GLOBAL_GRIDS || at + side * side > (uint32_t)RSM_GLOBAL_GRID_BYTES) {
            return RSM_ERR_NOMEM;
        }
        g->grid_at[g->grids] = at;
        g->grid_side[g->grids] = side;
        at += side * side;
        g->grids++;
        if (side == 1u) {
            break;
        }
        side = (side + 1u) >> 1;
    }
    memset(grid, 0, at);
    side = g->grid_side[0];
    for (s = 0; s < map->used; ++s) {
        const rsm_tile_t *t = &map->tile[s];
        uint32_t c;
        if ((t->stamp >> 30) != level) {
            continue;
        }
        for (c = 0; c < (uint32_t)RSM_TMAP_TILE_CELLS; ++c) {
            const uint32_t v = ((uint32_t)t->cell[c >> 1] >> ((c & 1u) << 2)) & 15u;
            if (v != 0u) {
                const int32_t gx = (int32_t)t->tx * RSM_TMAP_TILE_SIDE + (int32_t)(c & (RSM_TMAP_TILE_SIDE - 1u));
                const int32_t gy = (int32_t)t->ty * RSM_TMAP_TILE_SIDE + (int32_t)(c >> RSM_TMAP_TILE_LOG2);
                const uint32_t u = (uint32_t)(gx - gx0) >> g->base_h;
                const uint32_t vv = (uint32_t)(gy - gy0) >> g->base_h;
                uint8_t *cell = &grid[vv * side + u];
                if (v > *cell) {
                    *cell = (uint8_t)v;
                }
            }
        }
    }
    for (k = 1; k < g->grids; ++k) {
        const uint8_t *src = grid + g->grid_at[k - 1u];
        const uint32_t ss = g->grid_side[k - 1u];
        uint8_t *dst = grid + g->grid_at[k];
        const uint32_t ds = g->grid_side[k];
        uint32_t y;
        for (y = 0; y < ss; ++y) {
            uint32_t x;
            for (x = 0; x < ss; ++x) {
                uint8_t *d = &dst[(y >> 1) * ds + (x >> 1)];
                if (src[y * ss + x] > *d) {
                    *d = src[y * ss + x];
                }
            }
        }
    }
    g->top_h = g->base_h + g->grids - 1u;
    g->root_i = g->ox;
    g->root_j = g->oy;
    g->root_h = g->top_h;
    return RSM_OK;
}

/* Wall directions, half a turn in RSM_GLOBAL_BINS bins, of the line from
 * a to b, weighted by its length. */
static void add_direction(float *hist, float dx, float dy, float w)
{
    float a = rsm_atan2f(dy, dx);
    int32_t b;
    if (a < 0.0f) {
        a += RSM_PI;
    }
    b = (int32_t)(a * ((float)RSM_GLOBAL_BINS / RSM_PI));
    if (b >= RSM_GLOBAL_BINS) {
        b -= RSM_GLOBAL_BINS;
    }
    if (b >= 0) {
        hist[b] += w;
    }
}

/* The scan's wall directions: chords between readings four apart that lie
 * 0.1 to 0.6 m apart (shorter ones are noise, longer ones span gaps). */
static void scan_directions(rsm_global_t *g, const rsm_point_t *pts, size_t n)
{
    size_t k;
    memset(g->dir_scan, 0, sizeof g->dir_scan);
    for (k = 0; k + 4u < n; ++k) {
        const float dx = pts[k + 4u].x - pts[k].x;
        const float dy = pts[k + 4u].y - pts[k].y;
        const float d2 = dx * dx + dy * dy;
        if (d2 >= 0.01f && d2 <= 0.36f) {
            add_direction(g->dir_scan, dx, dy, sqrtf(d2));
        }
    }
}

int rsm_global_begin(rsm_global_t *g, uint8_t *grid, const rsm_tmap_t *map, const rsm_point_t *pts, size_t n,
                     const rsm_pose_t *at, float min_share)
{
    const uint32_t level = search_level(map);
    const float cell = rsm_tmap_cell(map, level);
    float range[RSM_GLOBAL_POINTS];
    int32_t gx0;
    int32_t gy0;
    int32_t gx1;
    int32_t gy1;
    float reach;
    uint32_t stride;
    uint32_t k;
    int rc;
    if (n < 8u) {
        return RSM_ERR_DEGENERATE;
    }
    if ((rc = rsm_global_check(map)) != RSM_OK) {
        return rc;
    }
    (void)rsm_tmap_bounds(map, level, &gx0, &gy0, &gx1, &gy1);
    g->level = level;
    g->npts = n < (size_t)RSM_GLOBAL_POINTS ? (uint32_t)n : (uint32_t)RSM_GLOBAL_POINTS;
    /* Taken evenly over the scan, stored in an order that jumps across it
     * (a stride coprime with their count), so that a pose's first points
     * already sample the whole scan and a poor pose is given up early. */
    stride = (g->npts * 5u) / 8u;
    while (stride > 1u) {
        uint32_t a = g->npts;
        uint32_t b = stride;
        while (b != 0u) {
            const uint32_t t = a % b;
            a = b;
            b = t;
        }
        if (a == 1u) {
            break;
        }
        --stride;
    }
    if (stride == 0u) {
        stride = 1u;
    }
    for (k = 0; k < g->npts; ++k) {
        const uint32_t pick = (k * stride) % g->npts;
        rsm_point_t p = pts[(size_t)pick * n / g->npts];
        uint32_t m = k;
        /* A reading far beyond any map (max_range_m is the caller's) is
         * pulled in to the map's reach: it lands on nothing either way,
         * and its cell offset stays a small integer. */
        const float far = (float)(RSM_TMAP_TILE_LIMIT * RSM_TMAP_TILE_SIDE) * rsm_tmap_cell(map, 0u);
        const float r = sqrtf(p.x * p.x + p.y * p.y);
        if (!(r <= far)) {
            const float shrink = r > 0.0f ? far / r : 0.0f;
            p.x *= shrink;
            p.y *= shrink;
        }
        g->pts[k] = p;
        range[k] = sqrtf(p.x * p.x + p.y * p.y);
        /* Insertion sort of the ranges, for their upper decile. */
        while (m > 0u && range[m - 1u] > range[m]) {
            const float t = range[m - 1u];
            range[m - 1u] = range[m];
            range[m] = t;
            --m;
        }
    }
    /* Headings so spaced that the scan's far points (its upper decile)
     * move one cell from one heading to the next. */
    reach = range[(g->npts * 9u) / 10u];
    if (reach < cell) {
        reach = cell;
    }
    {
        /* Capped as a float, before it becomes a count. */
        float h = ceilf(2.0f * RSM_PI * reach / cell);
        h = h < (float)RSM_GLOBAL_MAX_HEADINGS ? h : (float)RSM_GLOBAL_MAX_HEADINGS;
        g->headings = h > 8.0f ? (uint32_t)h : 8u;
        /* Even: a pose and the one turned half round are both searched
         * (a place that looks alike from there must be seen as a rival). */
        g->headings += g->headings & 1u;
    }
    g->step_rad = 2.0f * RSM_PI / (float)g->headings;
    if ((rc = build_grids(g, grid, map, gx0, gy0, gx1, gy1)) != RSM_OK) {
        return rc;
    }
    scan_directions(g, pts, n);
    memset(g->dir_map, 0, sizeof g->dir_map);
    g->dir_next = 0;
    g->at = *at;
    g->heading = 0;
    g->pass = 0;
    g->depth = 0;
    g->found = 0;
    g->floor_score = min_share * (float)g->npts;
    g->work = 0;
    return RSM_OK;
}

/* The map's wall directions from one tile of the direction level: the
 * gradient of its cell values (a 3 x 3 Sobel inside the tile) is normal to
 * its walls. Returns the cells looked at. */
static uint32_t tile_directions(rsm_global_t *g, const rsm_tile_t *t)
{
    const int32_t side = RSM_TMAP_TILE_SIDE;
    int32_t y;
    for (y = 1; y < side - 1; ++y) {
        int32_t x;
        for (x = 1; x < side - 1; ++x) {
            int32_t v[3][3];
            int32_t dy;
            float gx;
            float gy;
            for (dy = -1; dy <= 1; ++dy) {
                int32_t dx;
                for (dx = -1; dx <= 1; ++dx) {
                    const uint32_t c = (uint32_t)((y + dy) * side + x + dx);
                    v[dy + 1][dx + 1] = (int32_t)(((uint32_t)t->cell[c >> 1] >> ((c & 1u) << 2)) & 15u);
                }
            }
            gx = (float)((v[0][2] + 2 * v[1][2] + v[2][2]) - (v[0][0] + 2 * v[1][0] + v[2][0]));
            gy = (float)((v[2][0] + 2 * v[2][1] + v[2][2]) - (v[0][0] + 2 * v[0][1] + v[0][2]));
            if (gx != 0.0f || gy != 0.0f) {
                /* The wall runs across its normal (gx, gy). */
                add_direction(g->dir_map, -gy, gx, sqrtf(gx * gx + gy * gy));
            }
        }
    }
    return (uint32_t)((side - 2) * (side - 2));
}

/* How well the scan's wall directions, turned by each heading, fall on the
 * map's: the correlation of the two histograms, as a share of its best,
 * and the best within a bin either side (the bins are 4 degrees). A room
 * with no dominant direction agrees equally at every heading. */
static void direction_agreement(rsm_global_t *g)
{
    float corr[RSM_GLOBAL_BINS];
    float best = 0.0f;
    uint32_t s;
    for (s = 0; s < (uint32_t)RSM_GLOBAL_BINS; ++s) {
        float c = 0.0f;
        uint32_t b;
        for (b = 0; b < (uint32_t)RSM_GLOBAL_BINS; ++b) {
            c += g->dir_scan[b] * g->dir_map[(b + s) % (uint32_t)RSM_GLOBAL_BINS];
        }
        corr[s] = c;
        if (c > best) {
            best = c;
        }
    }
    for (s = 0; s < (uint32_t)RSM_GLOBAL_BINS; ++s) {
        const uint32_t l = (s + (uint32_t)RSM_GLOBAL_BINS - 1u) % (uint32_t)RSM_GLOBAL_BINS;
        const uint32_t r = (s + 1u) % (uint32_t)RSM_GLOBAL_BINS;
        float m = corr[s] > corr[l] ? corr[s] : corr[l];
        m = corr[r] > m ? corr[r] : m;
        g->agree[s] = best > 0.0f ? m / best : 1.0f;
    }
}

/* The passes over the headings: the best agreeing first, so that the
 * right pose is likely found early and raises the bar for the rest; below
 * the last, a heading is not searched. */
static const float pass_floor[] = {0.85f, 0.65f, 0.5f};
#define PASSES (sizeof pass_floor / sizeof pass_floor[0])

static int in_pass(const rsm_global_t *g, uint32_t a)
{
    float th = (float)a * g->step_rad;
    int32_t bin;
    float v;
    while (th >= RSM_PI) {
        th -= RSM_PI;
    }
    bin = (int32_t)(th * ((float)RSM_GLOBAL_BINS / RSM_PI) + 0.5f) % RSM_GLOBAL_BINS;
    v = g->agree[bin];
    return v >= pass_floor[g->pass] && (g->pass == 0u || v < pass_floor[g->pass - 1u]);
}

/* The points of heading a, as coarse-cell offsets from the pose's cell. */
static void offsets(const rsm_global_t *g, float cell, uint32_t a, int32_t *fx, int32_t *fy)
{
    const float th = (float)a * g->step_rad;
    const float c = rsm_cosf(th);
    const float s = rsm_sinf(th);
    const float inv = 1.0f / cell;
    uint32_t k;
    for (k = 0; k < g->npts; ++k) {
        const rsm_point_t *p = &g->pts[k];
        fx[k] = (int32_t)floorf((c * p->x - s * p->y) * inv);
        fy[k] = (int32_t)floorf((s * p->x + c * p->y) * inv);
    }
}

/* The largest value of grid gr over the blocks the window [u, u + 2^h] x
 * [v, v + 2^h] touches (two a side at most); 0 outside the grid. */
static uint32_t grid_max(const rsm_global_t *g, const uint8_t *grids, uint32_t gr, uint32_t h, int32_t u, int32_t v)
{
    const uint32_t side = g->grid_side[gr];
    const uint8_t *grid = grids + g->grid_at[gr];
    const int32_t u0 = floor_shift(u - g->ox, h);
    const int32_t u1 = floor_shift(u - g->ox + (int32_t)(1u << h), h);
    const int32_t v0 = floor_shift(v - g->oy, h);
    const int32_t v1 = floor_shift(v - g->oy + (int32_t)(1u << h), h);
    uint32_t best = 0;
    int32_t y;
    for (y = v0; y <= v1; ++y) {
        int32_t x;
        if (y < 0 || (uint32_t)y >= side) {
            continue;
        }
        for (x = u0; x <= u1; ++x) {
            if (x >= 0 && (uint32_t)x < side && grid[(uint32_t)y * side + (uint32_t)x] > best) {
                best = grid[(uint32_t)y * side + (uint32_t)x];
            }
        }
    }
    return best;
}

/* The most a pose of box (i, j, h) scores at this heading: each point's
 * largest cell value in its window, read from the map for small windows and
 * from the grids for large ones. Stops as soon as the points left could not
 * lift the sum to thr (each adds 1 at most): what it returns is then below
 * thr, which is all the caller asks. Adds the cells and blocks read to
 * *work. */
static float box_bound(const rsm_global_t *g, const uint8_t *grid, const rsm_tmap_t *map, const int32_t *fx, const int32_t *fy,
                       int32_t i, int32_t j, uint32_t h, float thr, uint32_t *work)
{
    float sum = 0.0f;
    uint32_t reads = 0;
    uint32_t k;
    for (k = 0; k < g->npts; ++k) {
        const int32_t u = fx[k] + i;
        const int32_t v = fy[k] + j;
        uint32_t best = 0;
        if (h >= g->base_h) {
            best = grid_max(g, grid, h - g->base_h, h, u, v);
            reads += 4u;
        } else {
            /* The window as a coarser level holds it (the level h up, or
             * the coarsest; for a leaf, the window's four cells themselves):
             * a coarse cell over a wall reads
             * about as high as the finest cell in it, so this bounds the
             * window in practice though not by construction; nothing is
             * taken without the proof that follows the search. Measured on
             * the Intel log: the same poses found as with every cell of the
             * window read, with a third fewer reads. */
            const uint32_t up = g->level + h < (uint32_t)map->cfg.levels ? h : (uint32_t)map->cfg.levels - 1u - g->level;
            const int32_t x0 = floor_shift(u, up);
            const int32_t y0 = floor_shift(v, up);
            const int32_t x1 = floor_shift(u + (int32_t)(1u << h), up);
            const int32_t y1 = floor_shift(v + (int32_t)(1u << h), up);
            int32_t yy;
            for (yy = y0; yy <= y1; ++yy) {
                int32_t xx;
                for (xx = x0; xx <= x1; ++xx) {
                    const uint32_t val = rsm_tmap_value(map, g->level + up, xx, yy);
                    reads++;
                    if (val > best) {
                        best = val;
                    }
                }
            }
        }
        sum += map->occ[best];
        if (sum + (float)(g->npts - k - 1u) < thr) {
            *work += reads;
            return sum;
        }
    }
    *work += reads;
    return sum;
}

/* The score a box must reach to be split or kept. */
static float threshold(const rsm_global_t *g)
{
    const float rel = g->found > 0u ? (1.0f - KEEP_SHARE) * g->cand[0].score : 0.0f;
    return rel > g->floor_score ? rel : g->floor_score;
}

/* Keeps a leaf among the best distinct poses: one within two lattice steps
 * and two heading steps of a better kept one is its basin, not a rival. */
static void keep(rsm_global_t *g, float cell, const rsm_pose_t *x, float score)
{
    const float near_m = 2.0f * cell + 1e-3f;
    const float near_rad = 2.0f * g->step_rad + 1e-4f;
    uint32_t m;
    uint32_t kept = 0;
    uint32_t at;
    for (m = 0; m < g->found; ++m) {
        const rsm_pose_t *o = &g->cand[m].pose;
        if (fabsf(o->x - x->x) <= near_m && fabsf(o->y - x->y) <= near_m &&
            fabsf(rsm_wrap_angle(o->theta - x->theta)) <= near_rad) {
            if (g->cand[m].score >= score) {
                return;
            }
        } else {
            g->cand[kept++] = g->cand[m];
        }
    }
    g->found = kept;
    /* Those the new best leaves behind by more than the share go. */
    while (g->found > 0u && g->cand[g->found - 1u].score < (1.0f - KEEP_SHARE) * score) {
        g->found--;
    }
    if (g->found == (uint32_t)RSM_GLOBAL_CANDIDATES) {
        if (!(score > g->cand[g->found - 1u].score)) {
            return;
        }
        g->found--;
    }
    for (at = g->found; at > 0u && g->cand[at - 1u].score < score; --at) {
        g->cand[at] = g->cand[at - 1u];
    }
    g->cand[at].pose = *x;
    g->cand[at].score = score;
    g->found++;
}

int rsm_global_run(rsm_global_t *g, const uint8_t *grid, const rsm_tmap_t *map, uint32_t budget, uint32_t *used)
{
    const float cell = rsm_tmap_cell(map, g->level);
    int32_t fx[RSM_GLOBAL_POINTS];
    int32_t fy[RSM_GLOBAL_POINTS];
    uint32_t work = 0;
    int more = 1;
    if (g->depth > 0u) {
        offsets(g, cell, g->heading - 1u, fx, fy);
    }
    /* First the map's wall directions, a tile at a time. */
    while (g->dir_next <= map->used) {
        if (budget > 0u && work >= budget) {
            break;
        }
        if (g->dir_next == map->used) {
            direction_agreement(g);
            g->dir_next++;
            break;
        }
        if ((map->tile[g->dir_next].stamp >> 30) == direction_level(g->level)) {
            work += tile_directions(g, &map->tile[g->dir_next]);
        }
        g->dir_next++;
    }
    for (;;) {
        rsm_global_box_t b;
        if (budget > 0u && work >= budget) {
            break;
        }
        if (g->depth == 0u) {
            while (g->pass < PASSES && (g->heading == g->headings || !in_pass(g, g->heading))) {
                if (g->heading == g->headings) {
                    g->heading = 0;
                    g->pass++;
                } else {
                    g->heading++;
                }
            }
            if (g->pass == PASSES) {
                more = 0;
                break;
            }
            offsets(g, cell, g->heading, fx, fy);
            g->heading++;
            b.i = g->root_i;
            b.j = g->root_j;
            b.h = g->root_h;
            b.bound = box_bound(g, grid, map, fx, fy, b.i, b.j, b.h, threshold(g), &work);
            if (b.bound >= threshold(g)) {
                g->stack[g->depth++] = b;
            }
            continue;
        }
        b = g->stack[--g->depth];
        if (b.bound < threshold(g)) {
            continue;
        }
        if (b.h == 0u) {
            rsm_pose_t x;
            x.x = (float)b.i * cell;
            x.y = (float)b.j * cell;
            x.theta = rsm_wrap_angle((float)(g->heading - 1u) * g->step_rad);
            keep(g, cell, &x, b.bound);
            continue;
        }
        {
            const uint32_t h = b.h - 1u;
            const int32_t half = (int32_t)(1u << h);
            rsm_global_box_t child[4];
            uint32_t c;
            uint32_t nc = 0;
            for (c = 0; c < 4u; ++c) {
                rsm_global_box_t ch;
                uint32_t at;
                ch.i = b.i + ((c & 1u) ? half : 0);
                ch.j = b.j + ((c & 2u) ? half : 0);
                ch.h = h;
                ch.bound = box_bound(g, grid, map, fx, fy, ch.i, ch.j, h, threshold(g), &work);
                if (ch.bound < threshold(g)) {
                    continue;
                }
                /* Ascending, so that the best is pushed last, popped first. */
                for (at = nc; at > 0u && child[at - 1u].bound > ch.bound; --at) {
                    child[at] = child[at - 1u];
                }
                child[at] = ch;
                nc++;
            }
            /* Three siblings wait per level at most: the stack holds them
             * (RSM_GLOBAL_STACK). */
            for (c = 0; c < nc && g->depth < (uint32_t)RSM_GLOBAL_STACK; ++c) {
                g->stack[g->depth++] = child[c];
            }
        }
    }
    g->work += work;
    if (used != NULL) {
        *used += work;
    }
    return more;
}

void rsm_global_window(rsm_global_t *g, const rsm_tmap_t *map, float x, float y, float radius_m)
{
    const float inv = 1.0f / rsm_tmap_cell(map, g->level);
    const float lim = (float)(RSM_TMAP_TILE_LIMIT * RSM_TMAP_TILE_SIDE);
    float fx0 = rsm_floorf((x - radius_m) * inv);
    float fy0 = rsm_floorf((y - radius_m) * inv);
    float w = rsm_floorf((x + radius_m) * inv) - fx0 + 1.0f;
    const float hgt = rsm_floorf((y + radius_m) * inv) - fy0 + 1.0f;
    uint32_t h = 0;
    w = hgt > w ? hgt : w;
    /* Far outside the map's range, or wider than the map: the whole map. */
    if (!(fx0 > -lim && fx0 < lim && fy0 > -lim && fy0 < lim && w >= 1.0f && w < lim)) {
        return;
    }
    while (h < g->top_h && (float)(1u << h) < w) {
        ++h;
    }
    if (h >= g->top_h) {
        return;
    }
    g->root_i = (int32_t)fx0;
    g->root_j = (int32_t)fy0;
    g->root_h = h;
}
