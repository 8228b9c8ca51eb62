/* Importing an occupancy image as the persistent map: include/rsm/mapimport.h
 * has the contract, docs/mapfile.md ("Importing a ROS map") the rules. */
#include "rsm/mapimport.h"

#include <math.h>
#include <string.h>

#include "core/fmath.h"
#include "core/grid.h"
#include "rsm/status.h"
#include "map/mapstate.h"
#include "map/tilemap.h"
#include "map/tmap_read.h"

/* A pixel may span at most this many finest cells a side: each level
 * writes up to its square in samples. */
#define MAX_SPAN 256.0f

/* A cell coordinate u (in cells) that every level holds, as an integer;
 * 0 beyond the cells' range (or NaN). */
static int cell_coord(float u, int32_t *g)
{
    const float f = rsm_floorf(u);
    if (!(f > -(float)(RSM_TMAP_CELL_LIMIT - 2) && f < (float)(RSM_TMAP_CELL_LIMIT - 2))) {
        return 0;
    }
    *g = (int32_t)f;
    return 1;
}

static int map_localizer(const rsm_localizer_t *loc, int *rc)
{
    if (!rsm_localizer_ready(loc)) {
        *rc = RSM_ERR_INVAL;
        return 0;
    }
    if (loc->cfg->method != RSM_METHOD_MAP) {
        *rc = RSM_ERR_NOSYS;
        return 0;
    }
    return 1;
}

int rsm_localizer_import_begin(rsm_localizer_t *loc, rsm_import_report_t *report)
{
    int rc = RSM_OK;
    if (!map_localizer(loc, &rc)) {
        return rc;
    }
    rsm_tmap_reset(&loc->state.persistent.map);
    rsm_localizer_map_cleared(loc);
    if (report != NULL) {
        memset(report, 0, sizeof *report);
    }
    return RSM_OK;
}

int rsm_localizer_import_check(const rsm_localizer_t *loc, const rsm_import_grid_t *g)
{
    int rc = RSM_OK;
    if (!map_localizer(loc, &rc)) {
        return rc;
    }
    return g != NULL && g->res_m > 0.0f && g->res_m <= 1.0e3f && g->res_m <= MAX_SPAN * loc->cfg->tmap.cell_m &&
                   isfinite(g->origin_x) && isfinite(g->origin_y) && isfinite(g->yaw_rad) && g->width >= 1u &&
                   (g->coarse == RSM_IMPORT_SHARE || g->coarse == RSM_IMPORT_TOUCH)
               ? RSM_OK
               : RSM_ERR_INVAL;
}

/* How one level is written: its cursor, its cell side, and whether it
 * shares (bilinear) or marks whole cells. */
typedef struct level_pass {
    rsm_tmap_t *map;
    rsm_tmap_cursor_t cur;
    float inv_a;
    int share;
    uint32_t full;       /* value of a fully occupied cell */
    uint32_t cells;      /* writes made */
    uint32_t dropped;    /* writes lost: pool full */
    int outside;         /* a sample of the current pixel lay beyond the range */
} level_pass_t;

static void count(level_pass_t *p, int rc)
{
    if (rc == RSM_OK) {
        p->cells++;
    } else if (rc == RSM_ERR_NOMEM) {
        p->dropped++;
    } else {
        p->outside = 1;
    }
}

/* Writes the sample at world (x, y) into the pass's level. */
static void write_sample(level_pass_t *p, float x, float y)
{
    if (p->share) {
        const rsm_bilinear_t b = rsm_bilinear_at(x, y, p->inv_a);
        const float sat = (float)p->map->cfg.saturation;
        const float w[4] = {(1.0f - b.du) * (1.0f - b.dv), b.du * (1.0f - b.dv), (1.0f - b.du) * b.dv,
                            b.du * b.dv};
        uint32_t k;
        int32_t gx;
        int32_t gy;
        /* The same range as a whole cell's: the corner cell and the one
         * past it. */
        if (!cell_coord(x * p->inv_a, &gx) || !cell_coord(y * p->inv_a, &gy)) {
            p->outside = 1;
            return;
        }
        float top = 0.0f;
        for (k = 0; k < 4u; ++k) {
            top = w[k] > top ? w[k] : top;
        }
        for (k = 0; k < 4u; ++k) {
            /* The nearest centre gets the saturation, the others their
             * share relative to it: the same place of the wall between
             * the centres as the plain weights, the contrast of a wall
             * seen many times. */
            const uint32_t v = (uint32_t)(sat * w[k] / top + 0.5f);
            if (v > 0u) {
                count(p, rsm_tmap_raise(p->map, &p->cur, b.i + (int32_t)(k & 1u), b.j + (int32_t)(k >> 1), v));
            }
        }
    } else {
        int32_t gx;
        int32_t gy;
        /* The cell holding the sample (floor, as a return's): a wall on a
         * cell border is written on its upper side. Writing both sides
         * instead (a wall two cells thick, centred) left the finest level
         * flat across the wall: no pull, the match refused for want of
         * support at the true pose (measured, tests/unit/test_mapimport.c). */
        if (!cell_coord(x * p->inv_a, &gx) || !cell_coord(y * p->inv_a, &gy)) {
            p->outside = 1;
            return;
        }
        count(p, rsm_tmap_raise(p->map, &p->cur, gx, gy, p->full));
    }
}

int rsm_localizer_import_row(rsm_localizer_t *loc, const rsm_import_grid_t *grid, uint32_t row,
                             const uint8_t *occupied, rsm_import_report_t *report)
{
    rsm_tmap_t *map;
    float c;
    float s;
    uint32_t level;
    uint32_t occ = 0;
    uint32_t outside = 0;
    uint32_t cells = 0;
    uint32_t dropped = 0;
    uint32_t k;
    int rc = rsm_localizer_import_check(loc, grid);
    if (rc != RSM_OK) {
        return rc;
    }
    if (occupied == NULL) {
        return RSM_ERR_INVAL;
    }
    map = &loc->state.persistent.map;
    /* A write spread over the coming scans ends first: it holds the map's
     * current write counter, which the import writes with too. */
    (void)rsm_tmap_write_run(map, loc->frame.world, 0u);
    rsm_sincosf(grid->yaw_rad, &s, &c);
    for (k = 0; k < grid->width; ++k) {
        occ += occupied[k] != 0u ? 1u : 0u;
    }
    /* Level by level, so that one cursor at a time is in use (a slot a
     * write takes may have been another level's). */
    for (level = 0; occ > 0u && level < (uint32_t)map->cfg.levels; ++level) {
        level_pass_t p;
        /* Samples per pixel side: no farther apart than a cell, so that a
         * pixel coarser than the cell leaves no gap, or than a cell over
         * sqrt(2) in a turned image (a lattice turned by any angle leaves
         * no cell of side sqrt(2) times its spacing without a point); the
         * tolerance keeps an exact multiple from taking one sample more. */
        const float span = grid->res_m * map->inv_cell[level] * (s != 0.0f ? 1.41421356f : 1.0f);
        const uint32_t n = span > 1.0f ? (uint32_t)rsm_ceilf(span * (1.0f - 1.0e-5f)) : 1u;
        const float step = 1.0f / (float)n;
        p.map = map;
        rsm_tmap_cursor_init(&p.cur, level);
        p.inv_a = map->inv_cell[level];
        p.share = level >= (uint32_t)map->cfg.splat_from && grid->coarse == RSM_IMPORT_SHARE;
        p.full = RSM_TMAP_MAX_VALUE;
        p.cells = 0;
        p.dropped = 0;
        for (k = 0; k < grid->width; ++k) {
            uint32_t sx;
            uint32_t sy;
            if (occupied[k] == 0u) {
                continue;
            }
            p.outside = 0;
            for (sy = 0; sy < n; ++sy) {
                const float py = ((float)row + ((float)sy + 0.5f) * step) * grid->res_m;
                for (sx = 0; sx < n; ++sx) {
                    const float px = ((float)k + ((float)sx + 0.5f) * step) * grid->res_m;
                    write_sample(&p, grid->origin_x + c * px - s * py, grid->origin_y + s * px + c * py);
                }
            }
            /* Counted on the finest level, whose cells reach least far. */
            if (level == 0u && p.outside) {
                outside++;
            }
        }
        cells += p.cells;
        dropped += p.dropped;
    }
    if (report != NULL) {
        report->rows++;
        report->occupied += occ;
        report->cells += cells;
        report->dropped += dropped;
        report->outside += outside;
    }
    /* As after a load, with no fit known. */
    rsm_localizer_map_replaced(loc, 0.0f);
    return dropped > 0u ? RSM_ERR_NOMEM : RSM_OK;
}
