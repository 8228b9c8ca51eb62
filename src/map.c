#include "rsm/map.h"

#include <math.h>
#include <string.h>

#include "rsm/status.h"

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
