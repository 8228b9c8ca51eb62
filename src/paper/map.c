#include "paper/map.h"

#include <math.h>
#include <string.h>

#include "rsm/status.h"
#include "core/fmath.h"

static int finite_pos(float x, float y)
{
    return fabsf(x) < 1.0e6f && fabsf(y) < 1.0e6f;
}

static rsm_window_t window_around(float x, float y, float cell_m)
{
    rsm_window_t w;
    w.ox = rsm_grid_cell_of(x, cell_m) - RSM_MAP_SIZE / 2;
    w.oy = rsm_grid_cell_of(y, cell_m) - RSM_MAP_SIZE / 2;
    return w;
}

int rsm_map_init(rsm_map_t *map, float cell_m, float x_m, float y_m)
{
    if (map == NULL || !(cell_m > 0.0f) || !finite_pos(x_m, y_m)) {
        return RSM_ERR_INVAL;
    }
    memset(map->hits, 0, sizeof map->hits);
    map->cell_m = cell_m;
    map->win = window_around(x_m, y_m, cell_m);
    map->scrolls = 0;
    map->outside = 0;
    return RSM_OK;
}

/* Clears the storage of global columns [c0, c1) (all rows). */
static void clear_columns(rsm_map_t *map, int32_t c0, int32_t c1)
{
    int32_t c;
    uint32_t r;
    for (c = c0; c < c1; ++c) {
        const uint32_t col = (uint32_t)c & ((uint32_t)RSM_MAP_SIZE - 1u);
        for (r = 0; r < (uint32_t)RSM_MAP_SIZE; ++r) {
            map->hits[col | (r << RSM_MAP_SIZE_LOG2)] = 0;
        }
    }
}

/* Clears the storage of global rows [r0, r1) (all columns). */
static void clear_rows(rsm_map_t *map, int32_t r0, int32_t r1)
{
    int32_t r;
    for (r = r0; r < r1; ++r) {
        const uint32_t row = (uint32_t)r & ((uint32_t)RSM_MAP_SIZE - 1u);
        memset(&map->hits[row << RSM_MAP_SIZE_LOG2], 0, (size_t)RSM_MAP_SIZE);
    }
}

int rsm_map_recenter(rsm_map_t *map, float x_m, float y_m)
{
    rsm_window_t nw;
    int32_t dx;
    int32_t dy;
    if (!finite_pos(x_m, y_m)) {
        return RSM_ERR_INVAL;
    }
    nw = window_around(x_m, y_m, map->cell_m);
    dx = nw.ox - map->win.ox;
    dy = nw.oy - map->win.oy;
    if (dx <= RSM_MAP_SIZE / 4 && dx >= -RSM_MAP_SIZE / 4 && dy <= RSM_MAP_SIZE / 4 && dy >= -RSM_MAP_SIZE / 4) {
        return 0;
    }
    /* Storage that now belongs to cells entering the window must start empty. */
    if (dx >= RSM_MAP_SIZE || dx <= -RSM_MAP_SIZE || dy >= RSM_MAP_SIZE || dy <= -RSM_MAP_SIZE) {
        memset(map->hits, 0, sizeof map->hits);
    } else {
        if (dx > 0) {
            clear_columns(map, map->win.ox + RSM_MAP_SIZE, nw.ox + RSM_MAP_SIZE);
        } else if (dx < 0) {
            clear_columns(map, nw.ox, map->win.ox);
        }
        if (dy > 0) {
            clear_rows(map, map->win.oy + RSM_MAP_SIZE, nw.oy + RSM_MAP_SIZE);
        } else if (dy < 0) {
            clear_rows(map, nw.oy, map->win.oy);
        }
    }
    map->win = nw;
    map->scrolls++;
    return 1;
}

size_t rsm_map_add_points(rsm_map_t *map, const rsm_point_t *pts, size_t n)
{
    size_t k;
    size_t hit = 0;
    for (k = 0; k < n; ++k) {
        int32_t gx;
        int32_t gy;
        uint32_t i;
        if (!finite_pos(pts[k].x, pts[k].y)) {
            map->outside++;
            continue;
        }
        gx = rsm_grid_cell_of(pts[k].x, map->cell_m);
        gy = rsm_grid_cell_of(pts[k].y, map->cell_m);
        if (!rsm_window_contains(&map->win, gx, gy)) {
            map->outside++;
            continue;
        }
        i = rsm_window_index(gx, gy);
        if (map->hits[i] < 255u) {
            map->hits[i]++;
        }
        ++hit;
    }
    return hit;
}

/* Occupancy of one cell in [0, 1]. */
static float occupancy(const rsm_map_t *map, int32_t gx, int32_t gy, float inv_sat, uint8_t sat)
{
    const uint8_t h = rsm_map_hits(map, gx, gy);
    return (float)(h < sat ? h : sat) * inv_sat;
}

/* Bilinear occupancy at world (x, y) and its gradient per metre. */
static float sample(const rsm_map_t *map, float x, float y, float inv_sat, uint8_t sat, float *gx_out, float *gy_out)
{
    const float inv_a = 1.0f / map->cell_m;
    const rsm_bilinear_t b = rsm_bilinear_at(x, y, inv_a);
    const int32_t i = b.i;
    const int32_t j = b.j;
    const float du = b.du;
    const float dv = b.dv;
    const float m00 = occupancy(map, i, j, inv_sat, sat);
    const float m10 = occupancy(map, i + 1, j, inv_sat, sat);
    const float m01 = occupancy(map, i, j + 1, inv_sat, sat);
    const float m11 = occupancy(map, i + 1, j + 1, inv_sat, sat);
    *gx_out = ((m10 - m00) * (1.0f - dv) + (m11 - m01) * dv) * inv_a;
    *gy_out = ((m01 - m00) * (1.0f - du) + (m11 - m10) * du) * inv_a;
    return (m00 * (1.0f - du) + m10 * du) * (1.0f - dv) + (m01 * (1.0f - du) + m11 * du) * dv;
}

/* Normal equations of sum (1 - M)^2 at pose: upper triangle of J^T J in h,
 * J^T r in b. Returns the points with a non-zero map gradient (used); their
 * summed squared residual goes to *cost_used and the residual of every
 * finite point (those off the map count 1) to *total, which is the cost the
 * steps must decrease. */
static uint32_t normal_equations(const rsm_map_t *map, const rsm_point_t *pts, size_t n, const rsm_pose_t *pose,
                                 float inv_sat, uint8_t sat, float h[6], float b[3], float *cost_used, float *total)
{
    const float c = rsm_cosf(pose->theta);
    const float s = rsm_sinf(pose->theta);
    uint32_t used = 0;
    size_t k;
    memset(h, 0, 6 * sizeof h[0]);
    memset(b, 0, 3 * sizeof b[0]);
    *cost_used = 0.0f;
    *total = 0.0f;
    for (k = 0; k < n; ++k) {
        const float wx = pose->x + c * pts[k].x - s * pts[k].y;
        const float wy = pose->y + s * pts[k].x + c * pts[k].y;
        float dmx;
        float dmy;
        float m;
        float jt;
        float r;
        if (!(fabsf(wx) < 1.0e6f && fabsf(wy) < 1.0e6f)) {
            continue;
        }
        m = sample(map, wx, wy, inv_sat, sat, &dmx, &dmy);
        r = 1.0f - m;
        *total += r * r;
        if (dmx == 0.0f && dmy == 0.0f) {
            continue;
        }
        /* d(world)/d(theta) = (-s px - c py, c px - s py). */
        jt = dmx * (-s * pts[k].x - c * pts[k].y) + dmy * (c * pts[k].x - s * pts[k].y);
        h[0] += dmx * dmx;
        h[1] += dmx * dmy;
        h[2] += dmx * jt;
        h[3] += dmy * dmy;
        h[4] += dmy * jt;
        h[5] += jt * jt;
        b[0] += dmx * r;
        b[1] += dmy * r;
        b[2] += jt * r;
        *cost_used += r * r;
        ++used;
    }
    return used;
}

int rsm_map_align(const rsm_map_t *map, const rsm_point_t *pts, size_t n, const rsm_pose_t *start,
                  uint8_t saturation, uint32_t iterations, rsm_map_fit_t *fit)
{
    rsm_pose_t pose;
    uint32_t it;
    uint32_t used;
    float inv_sat;
    float h[6];
    float b[3];
    float cost_used;
    float total;
    if (map == NULL || (n > 0 && pts == NULL) || start == NULL || fit == NULL || saturation == 0u) {
        return RSM_ERR_INVAL;
    }
    inv_sat = 1.0f / (float)saturation;
    pose = *start;
    memset(fit, 0, sizeof *fit);
    fit->pose = *start;
    used = normal_equations(map, pts, n, &pose, inv_sat, saturation, h, b, &cost_used, &total);
    for (it = 0; it < iterations; ++it) {
        const float a00 = h[0], a01 = h[1], a02 = h[2], a11 = h[3], a12 = h[4], a22 = h[5];
        const float c00 = a11 * a22 - a12 * a12;
        const float c01 = a02 * a12 - a01 * a22;
        const float c02 = a01 * a12 - a02 * a11;
        const float det = a00 * c00 + a01 * c01 + a02 * c02;
        const float scale = (a00 + a11) * (a00 + a11) * a22;
        float dx;
        float dy;
        float dt;
        int halvings;
        int accepted = 0;
        if (used < 3u || !(fabsf(det) > 1.0e-9f * (scale > 0.0f ? scale : 1.0f))) {
            return it == 0 ? RSM_ERR_DEGENERATE : RSM_OK;
        }
        {
            const float c11 = a00 * a22 - a02 * a02;
            const float c12 = a01 * a02 - a00 * a12;
            const float c22 = a00 * a11 - a01 * a01;
            dx = (c00 * b[0] + c01 * b[1] + c02 * b[2]) / det;
            dy = (c01 * b[0] + c11 * b[1] + c12 * b[2]) / det;
            dt = (c02 * b[0] + c12 * b[1] + c22 * b[2]) / det;
        }
        /* A step beyond one cell means the linearisation is not valid. */
        if (!(fabsf(dx) < map->cell_m && fabsf(dy) < map->cell_m && fabsf(dt) < 0.05f)) {
            return it == 0 ? RSM_ERR_DEGENERATE : RSM_OK;
        }
        fit->info[0] = a00;
        fit->info[1] = a01;
        fit->info[2] = a02;
        fit->info[3] = a01;
        fit->info[4] = a11;
        fit->info[5] = a12;
        fit->info[6] = a02;
        fit->info[7] = a12;
        fit->info[8] = a22;
        fit->cost = cost_used / (float)used;
        fit->used = used;
        fit->iterations = it + 1u;
        /* The occupancy is bilinear between cell centres, so the cost has
         * kinks where a full Gauss-Newton step overshoots and cycles: take
         * the step only where it lowers the cost, halving it otherwise. */
        for (halvings = 0; halvings < 6 && !accepted; ++halvings) {
            rsm_pose_t cand;
            float ch[6];
            float cb[3];
            float ccost;
            float ctotal;
            uint32_t cused;
            cand.x = pose.x + dx;
            cand.y = pose.y + dy;
            cand.theta = rsm_wrap_angle(pose.theta + dt);
            cused = normal_equations(map, pts, n, &cand, inv_sat, saturation, ch, cb, &ccost, &ctotal);
            if (ctotal < total) {
                pose = cand;
                used = cused;
                memcpy(h, ch, sizeof h);
                memcpy(b, cb, sizeof b);
                cost_used = ccost;
                total = ctotal;
                accepted = 1;
            } else {
                dx *= 0.5f;
                dy *= 0.5f;
                dt *= 0.5f;
            }
        }
        fit->pose = pose;
        if (!accepted || (fabsf(dx) < 1.0e-4f && fabsf(dy) < 1.0e-4f && fabsf(dt) < 1.0e-4f)) {
            break;
        }
    }
    return RSM_OK;
}
