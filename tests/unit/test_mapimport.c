/* Importing an occupancy image as the persistent map (issue 31, item 4):
 * the synthetic room rasterised at the finest cell and at twice it, imported
 * row by row, then a robot driven through the room with exact odometry on
 * the frozen map stays on its true path; a scan at the true pose fits the
 * imported walls and one displaced does not; a source coarser than the cell
 * leaves no gap; the pool's limit is reported; bad arguments and other
 * methods are refused with the localizer untouched. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "rsm/config.h"
#include "rsm/localizer.h"
#include "rsm/mapimport.h"
#include "rsm/status.h"
#include "synth.h"
#include "map/tilemap.h"
#include "unity.h"

#define STEP_US 100000u
#define PATH_CAP 400u
#define IMG_MAX 400u

static rsm_localizer_t loc;
static rsm_localizer_t before;
static rsm_localizer_config_t cfg;
static rsm_synth_scan_config_t scan_cfg;
static rsm_scan_t scan;
static rsm_pose_t path[PATH_CAP];
static size_t path_len;
static uint8_t img[IMG_MAX][IMG_MAX];
static uint8_t row_buf[4096];
static const rsm_pose_t origin_pose = {0.0f, 0.0f, 0.0f};

/* The image: width x height pixels of res metres, its bottom-left corner at
 * (ox, oy); img[0] is the bottom row. */
static uint32_t img_w;
static uint32_t img_h;

void setUp(void)
{
    cfg = rsm_localizer_config_default();
    cfg.map_frozen = 1u;
    scan_cfg = rsm_synth_scan_config_default();
    memset(img, 0, sizeof img);
}

void tearDown(void)
{
}

static const rsm_tmap_t *map_of(const rsm_localizer_t *l)
{
    return &l->state.persistent.map;
}

/* Marks every pixel a wall of the world passes through (samples an eighth
 * of a pixel apart along each segment). */
static void rasterise(const rsm_synth_world_t *w, float res, float ox, float oy)
{
    size_t s;
    img_w = (uint32_t)(5.0f / res);
    img_h = (uint32_t)(4.5f / res);
    TEST_ASSERT_TRUE(img_w <= IMG_MAX && img_h <= IMG_MAX);
    for (s = 0; s < w->count; ++s) {
        const rsm_synth_segment_t *g = &w->seg[s];
        const float len = hypotf(g->x1 - g->x0, g->y1 - g->y0);
        const uint32_t n = (uint32_t)(len / (res / 8.0f)) + 1u;
        uint32_t k;
        for (k = 0; k <= n; ++k) {
            const float t = (float)k / (float)n;
            const float x = g->x0 + t * (g->x1 - g->x0);
            const float y = g->y0 + t * (g->y1 - g->y0);
            const int32_t i = (int32_t)floorf((x - ox) / res);
            const int32_t j = (int32_t)floorf((y - oy) / res);
            TEST_ASSERT_TRUE(i >= 0 && j >= 0 && (uint32_t)i < img_w && (uint32_t)j < img_h);
            img[j][i] = 1u;
        }
    }
}

/* Imports the image, top row first as a PGM holds it. Returns the last
 * row's status (RSM_OK unless the pool filled). */
static int import_image(rsm_localizer_t *l, float res, float ox, float oy, uint8_t coarse, rsm_import_report_t *rep)
{
    rsm_import_grid_t g;
    uint32_t r;
    int worst = RSM_OK;
    g.res_m = res;
    g.origin_x = ox;
    g.origin_y = oy;
    g.yaw_rad = 0.0f;
    g.width = img_w;
    g.coarse = coarse;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(l, rep));
    for (r = img_h; r-- > 0u;) {
        const int rc = rsm_localizer_import_row(l, &g, r, img[r], rep);
        TEST_ASSERT_TRUE(rc == RSM_OK || rc == RSM_ERR_NOMEM);
        if (rc != RSM_OK) {
            worst = rc;
        }
    }
    return worst;
}

/* The room of rsm_synth_world_room without the corridor (its doorway
 * closed), so that the small configuration's pool holds it: walls on
 * multiples of 5 cm, the finest cells' borders (the worst case). */
static const rsm_synth_segment_t room_segments[] = {
    {-2.0f, -1.5f, -0.3f, -1.5f}, {-0.3f, -1.5f, -0.3f, -1.8f}, {-0.3f, -1.8f, 0.3f, -1.8f},
    {0.3f, -1.8f, 0.3f, -1.5f},   {0.3f, -1.5f, 2.0f, -1.5f},   {2.0f, -1.5f, 2.0f, 1.5f},
    {2.0f, 1.5f, -2.0f, 1.5f},    {-2.0f, 1.5f, -2.0f, -1.5f},  {0.5f, 0.2f, 1.1f, 0.2f},
    {1.1f, 0.2f, 1.1f, 0.6f},     {1.1f, 0.6f, 0.5f, 0.6f},     {0.5f, 0.6f, 0.5f, 0.2f},
    {-1.0f, -0.6f, -0.8f, -0.6f}, {-0.8f, -0.6f, -0.8f, -0.4f}, {-0.8f, -0.4f, -1.0f, -0.4f},
    {-1.0f, -0.4f, -1.0f, -0.6f},
};

static rsm_synth_world_t room(void)
{
    rsm_synth_world_t w;
    w.seg = room_segments;
    w.count = sizeof room_segments / sizeof room_segments[0];
    return w;
}

/* A tour of the room (as test_mapfile's), away from the box and pillar. */
static void make_path(void)
{
    static const rsm_synth_leg_t legs[] = {{1.0f, 0.0f}, {0.0f, 1.2f}, {0.6f, 0.0f}, {0.0f, -2.4f}, {1.2f, 0.3f}};
    const rsm_pose_t start = {-1.2f, -0.8f, 0.0f};
    path_len = rsm_synth_path(&start, legs, sizeof legs / sizeof legs[0], 0.05f, 0.05f, path, PATH_CAP);
    TEST_ASSERT_TRUE(path_len > 40u);
}

typedef struct run_result {
    float max_pos;
    float mean_pos;
    float max_ang;
    uint32_t tiles;
    uint32_t accepted; /* scans whose match was fused */
} run_result_t;

/* The room imported from an image of res metres (its pixels centred on the
 * walls, which lie on multiples of 5 cm), then the tour on the frozen map
 * from the true start displaced by (dx, dy, dth) with exact odometry. */
static run_result_t run_room(float res, uint8_t coarse, float dx, float dy, float dth)
{
    const rsm_synth_world_t world = room();
    const float ox = -2.5f - 0.5f * res;
    const float oy = -2.5f - 0.5f * res;
    rsm_import_report_t rep;
    run_result_t out = {0.0f, 0.0f, 0.0f, 0u, 0u};
    size_t k;
    rsm_pose_t start;
    make_path();
    start = path[0];
    start.x += dx;
    start.y += dy;
    start.theta += dth;
    rasterise(&world, res, ox, oy);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &start, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, import_image(&loc, res, ox, oy, coarse, &rep));
    TEST_ASSERT_EQUAL_UINT32(img_h, rep.rows);
    TEST_ASSERT_TRUE(rep.occupied > 50u);
    TEST_ASSERT_EQUAL_UINT32(0u, rep.dropped);
    TEST_ASSERT_EQUAL_UINT32(0u, rep.outside);
    out.tiles = map_of(&loc)->used;
    for (k = 0; k < path_len; ++k) {
        rsm_localizer_report_t r;
        rsm_pose_t est;
        float e;
        if (k > 0u) {
            const rsm_motion_t u = rsm_synth_motion(&path[k - 1u], &path[k], NULL);
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_motion(&loc, &u));
        }
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, &path[k], &scan_cfg, NULL, (uint64_t)k * STEP_US, &scan));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &r));
        /* Every scan is matched against the imported map, none is a first. */
        TEST_ASSERT_TRUE(r.outcome != RSM_SCAN_FIRST);
        out.accepted += r.outcome == RSM_SCAN_ACCEPTED ? 1u : 0u;
        est = rsm_localizer_pose(&loc);
        e = rsm_synth_pos_error(&est, &path[k]);
        out.max_pos = e > out.max_pos ? e : out.max_pos;
        out.mean_pos += e / (float)path_len;
        e = rsm_synth_angle_error(&est, &path[k]);
        out.max_ang = e > out.max_ang ? e : out.max_ang;
    }
    /* The estimate is the match's, not odometry's alone (which is exact). */
    {
        char m[64];
        (void)snprintf(m, sizeof m, "accepted %u of %u", (unsigned)out.accepted, (unsigned)path_len);
        TEST_ASSERT_TRUE_MESSAGE(out.accepted * 5u >= (uint32_t)path_len * 4u, m);
    }
    /* Frozen: the map is as imported. */
    TEST_ASSERT_EQUAL_UINT32(out.tiles, map_of(&loc)->used);
    return out;
}

/* The bound on the position error: test_localizer's for the localizer on
 * its own map of this room. Its walls lie on the finest cells' borders
 * (synth.h: the worst case), where the finest level reads a wall up to half
 * a cell off along x and along y: a / sqrt(2), plus 1.5 cm of the
 * matcher's own. */
static float pos_bound(float res)
{
    const float a = res > cfg.tmap.cell_m ? res : cfg.tmap.cell_m;
    return 0.7072f * a + 0.015f;
}

static void test_localizes_on_room_imported_at_cell(void)
{
    const run_result_t r = run_room(cfg.tmap.cell_m, RSM_IMPORT_SHARE, 0.0f, 0.0f, 0.0f);
    char msg[160];
    (void)snprintf(msg, sizeof msg, "res 1 cell: max %.4f m mean %.4f m max %.4f rad, %u tiles", (double)r.max_pos,
                   (double)r.mean_pos, (double)r.max_ang, (unsigned)r.tiles);
    TEST_MESSAGE(msg);
    TEST_ASSERT_TRUE_MESSAGE(r.max_pos < pos_bound(cfg.tmap.cell_m), msg);
    TEST_ASSERT_TRUE_MESSAGE(r.mean_pos < pos_bound(cfg.tmap.cell_m), msg);
    TEST_ASSERT_TRUE_MESSAGE(r.max_ang < 0.03f, msg);
}

static void test_localizes_on_room_imported_at_twice_the_cell(void)
{
    const run_result_t r = run_room(2.0f * cfg.tmap.cell_m, RSM_IMPORT_SHARE, 0.0f, 0.0f, 0.0f);
    char msg[160];
    (void)snprintf(msg, sizeof msg, "res 2 cells: max %.4f m mean %.4f m max %.4f rad, %u tiles", (double)r.max_pos,
                   (double)r.mean_pos, (double)r.max_ang, (unsigned)r.tiles);
    TEST_MESSAGE(msg);
    /* A pixel of two cells is written two cells thick (three on a
     * border): the same bound with the pixel for the cell. */
    TEST_ASSERT_TRUE_MESSAGE(r.max_pos < pos_bound(2.0f * cfg.tmap.cell_m), msg);
    TEST_ASSERT_TRUE_MESSAGE(r.mean_pos < pos_bound(cfg.tmap.cell_m), msg);
    /* Measured: 0.022 rad with 5 cm cells, 0.048 with 10 cm ones (a 20 cm
     * pixel in the small configuration's 3.2 m window). */
    TEST_ASSERT_TRUE_MESSAGE(r.max_ang < 0.6f * cfg.tmap.cell_m, msg);
}

/* Shared and touched coarse levels, started 12 cm and 0.08 rad off the true
 * pose (the coarse levels must pull the estimate in): printed, and the
 * shared levels localize at least as well. */
static void test_shared_coarse_levels_against_touched(void)
{
    const run_result_t sh = run_room(cfg.tmap.cell_m, RSM_IMPORT_SHARE, 0.12f, -0.08f, 0.08f);
    const run_result_t to = run_room(cfg.tmap.cell_m, RSM_IMPORT_TOUCH, 0.12f, -0.08f, 0.08f);
    char msg[200];
    (void)snprintf(msg, sizeof msg, "off start: share max %.4f mean %.4f; touch max %.4f mean %.4f", (double)sh.max_pos,
                   (double)sh.mean_pos, (double)to.max_pos, (double)to.mean_pos);
    TEST_MESSAGE(msg);
    TEST_ASSERT_TRUE_MESSAGE(sh.mean_pos < pos_bound(cfg.tmap.cell_m), msg);
    TEST_ASSERT_TRUE_MESSAGE(sh.mean_pos <= to.mean_pos + 0.002f, msg);
}

/* Mean occupancy on a level under a scan's points placed at pose. */
static float fit_at(const rsm_localizer_t *l, uint32_t level, const rsm_pose_t *pose)
{
    float sum = 0.0f;
    size_t n = 0;
    size_t k;
    for (k = 0; k < scan.count; ++k) {
        rsm_point_t p;
        rsm_point_t w;
        float gx;
        float gy;
        if (!(scan.range_m[k] < 10.0f)) {
            continue;
        }
        p.x = scan.range_m[k] * cosf(scan.angle_rad[k]);
        p.y = scan.range_m[k] * sinf(scan.angle_rad[k]);
        w = rsm_pose_apply(pose, &p);
        sum += rsm_tmap_sample(map_of(l), level, w.x, w.y, &gx, &gy);
        ++n;
    }
    TEST_ASSERT_TRUE(n > 50u);
    return sum / (float)n;
}

/* A scan at the true pose lies on the imported walls on every level; the
 * same scan 3 finest cells off along x and y (and turned by 0.1 rad) lies
 * mostly off them on the finest level. */
static void test_scan_fits_imported_map(void)
{
    const rsm_synth_world_t world = room();
    const float res = cfg.tmap.cell_m;
    const float ox = -2.5f - 0.5f * res;
    const float oy = -2.5f - 0.5f * res;
    rsm_import_report_t rep;
    rsm_pose_t off;
    uint32_t level;
    size_t k;
    make_path();
    rasterise(&world, res, ox, oy);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &path[0], NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, import_image(&loc, res, ox, oy, RSM_IMPORT_SHARE, &rep));
    for (k = 0; k < path_len; k += 20u) {
        char msg[120];
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, &path[k], &scan_cfg, NULL, 0u, &scan));
        for (level = 0; level < cfg.tmap.levels; ++level) {
            const float f = fit_at(&loc, level, &path[k]);
            (void)snprintf(msg, sizeof msg, "pose %u level %u fit %.3f", (unsigned)k, (unsigned)level, (double)f);
            /* The finest level holds a wall on a border in the cell above
             * it, whose centre is half a cell from the return: the return
             * reads half occupied there, nothing on the other side; the
             * shared coarse levels read nearly full. */
            TEST_ASSERT_TRUE_MESSAGE(f > (level == 0u ? 0.3f : 0.6f), msg);
        }
        off = path[k];
        off.x += 3.0f * res;
        off.y -= 3.0f * res;
        off.theta += 0.1f;
        {
            const float f = fit_at(&loc, 0u, &off);
            (void)snprintf(msg, sizeof msg, "pose %u displaced fit %.3f", (unsigned)k, (double)f);
            TEST_ASSERT_TRUE_MESSAGE(f < 0.15f, msg);
        }
    }
}

/* A source coarser than the cell (3.3 cells a pixel, and turned by 0.3 rad)
 * leaves no gap on the finest level: every cell along a row of occupied
 * pixels is held, on both sides of the pixels' centre line. */
static void test_coarse_source_leaves_no_gap(void)
{
    const float a = cfg.tmap.cell_m;
    rsm_import_grid_t g;
    rsm_import_report_t rep;
    const float yaws[2] = {0.0f, 0.3f};
    uint32_t y;
    for (y = 0; y < 2u; ++y) {
        const float c = cosf(yaws[y]);
        const float s = sinf(yaws[y]);
        uint32_t k;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &origin_pose, NULL));
        memset(row_buf, 1, 12);
        g.res_m = 3.3f * a;
        g.origin_x = 0.013f;
        g.origin_y = -0.021f;
        g.yaw_rad = yaws[y];
        g.width = 12u;
        g.coarse = RSM_IMPORT_SHARE;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&loc, &rep));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_row(&loc, &g, 2u, row_buf, &rep));
        TEST_ASSERT_EQUAL_UINT32(12u, rep.occupied);
        TEST_ASSERT_EQUAL_UINT32(1u, rep.rows);
        /* Walk the pixels' centre line and two lines a quarter of a pixel
         * either side of it, from the first pixel's centre to the last's,
         * a tenth of a cell at a time. */
        for (k = 0; k <= 10u * 11u * 33u / 10u; ++k) {
            int side;
            for (side = -1; side <= 1; ++side) {
                const float u = (0.5f * g.res_m) + (float)k * 0.1f * a;  /* along the row */
                const float v = (2.5f + (float)side / 4.0f) * g.res_m;   /* across it */
                const float wx = g.origin_x + c * u - s * v;
                const float wy = g.origin_y + s * u + c * v;
                const int32_t gx = (int32_t)floorf(wx / a);
                const int32_t gy = (int32_t)floorf(wy / a);
                char msg[96];
                (void)snprintf(msg, sizeof msg, "yaw %.1f at %.3f m side %d: cell %d %d", (double)yaws[y],
                               (double)u, side, (int)gx, (int)gy);
                TEST_ASSERT_EQUAL_UINT8_MESSAGE(RSM_TMAP_MAX_VALUE, rsm_tmap_value(map_of(&loc), 0u, gx, gy), msg);
            }
        }
        /* And nothing beyond the row's pixels. */
        {
            const float v = 4.2f * g.res_m;
            const float u = 6.0f * g.res_m;
            TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(map_of(&loc), 0u, (int32_t)floorf((g.origin_x + c * u - s * v) / a),
                                                       (int32_t)floorf((g.origin_y + s * u + c * v) / a)));
        }
    }
}

/* A pixel finer than the cell marks the cell of its centre, fully, on the
 * finest level; on a shared level, a pixel on a cell centre gives that cell
 * the saturation and its neighbours nothing, one half way between two
 * centres gives each half. */
static void test_fine_source_and_shares(void)
{
    const float a = cfg.tmap.cell_m;
    rsm_import_grid_t g;
    const rsm_tmap_t *m;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &origin_pose, NULL));
    TEST_ASSERT_TRUE(cfg.tmap.levels >= 2u && cfg.tmap.splat_from == 1u);
    m = map_of(&loc);
    memset(row_buf, 0, sizeof row_buf);
    g.res_m = 0.25f * a;
    g.yaw_rad = 0.0f;
    g.width = 8u;
    g.coarse = RSM_IMPORT_SHARE;
    /* Pixel 0's centre at the centre of level-1 cell (4, 4). */
    g.origin_x = 4.5f * 2.0f * a - 0.125f * a;
    g.origin_y = 4.5f * 2.0f * a - 0.125f * a;
    row_buf[0] = 1u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&loc, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    /* On the finest level that centre is the corner of four cells: the
     * cell above and right of it takes it (floor, as a return's). */
    TEST_ASSERT_EQUAL_UINT8(RSM_TMAP_MAX_VALUE, rsm_tmap_value(m, 0u, 9, 9));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 0u, 8, 9));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 0u, 9, 8));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 0u, 8, 8));
    TEST_ASSERT_EQUAL_UINT8(cfg.tmap.saturation, rsm_tmap_value(m, 1u, 4, 4));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 1u, 5, 4));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 1u, 4, 5));
    /* Pixel 4 sits one level-1 cell further: (4 + 0.5) * 2a + 4 * a / 4 =
     * half way between the centres of cells (4, 4) and (5, 4). */
    memset(row_buf, 0, sizeof row_buf);
    row_buf[4] = 1u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&loc, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    TEST_ASSERT_EQUAL_UINT8(cfg.tmap.saturation, rsm_tmap_value(m, 1u, 4, 4));
    TEST_ASSERT_EQUAL_UINT8(cfg.tmap.saturation, rsm_tmap_value(m, 1u, 5, 4));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 1u, 4, 5));
    /* Pixel 2: a quarter of the way from (4, 4)'s centre to (5, 4)'s:
     * the nearer full, the other a third of it (0.25 / 0.75). */
    memset(row_buf, 0, sizeof row_buf);
    row_buf[2] = 1u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&loc, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    TEST_ASSERT_EQUAL_UINT8(cfg.tmap.saturation, rsm_tmap_value(m, 1u, 4, 4));
    TEST_ASSERT_EQUAL_UINT8((uint8_t)((float)cfg.tmap.saturation / 3.0f + 0.5f), rsm_tmap_value(m, 1u, 5, 4));
    row_buf[2] = 0u;
    /* Touched instead: the cell holding the centre, fully. */
    g.coarse = RSM_IMPORT_TOUCH;
    row_buf[4] = 0u;
    row_buf[1] = 1u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&loc, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    TEST_ASSERT_EQUAL_UINT8(RSM_TMAP_MAX_VALUE, rsm_tmap_value(m, 1u, 4, 4));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 1u, 5, 4));
    /* A fine pixel marks only the cell of its centre: pixel 1's is a
     * quarter cell into level-0 column 9. */
    TEST_ASSERT_EQUAL_UINT8(RSM_TMAP_MAX_VALUE, rsm_tmap_value(m, 0u, 9, 9));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 0u, 9, 8));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 0u, 8, 9));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 0u, 10, 9));
}

/* After a row the next scan is matched, as after a load: have_scan, the
 * write pose at the estimate, no fit yet. */
static void test_row_sets_continuation(void)
{
    const rsm_pose_t p = {0.4f, -0.2f, 0.3f};
    rsm_import_grid_t g = {0.05f, 0.0f, 0.0f, 0.0f, 4u, RSM_IMPORT_SHARE};
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &p, NULL));
    loc.state.persistent.fit = 0.7f;
    TEST_ASSERT_EQUAL_UINT8(0u, loc.have_scan);
    memset(row_buf, 1, 4);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&loc, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    TEST_ASSERT_EQUAL_UINT8(1u, loc.have_scan);
    TEST_ASSERT_EQUAL_MEMORY(&loc.ekf.x, &loc.state.persistent.written, sizeof p);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, loc.state.persistent.fit);
    TEST_ASSERT_TRUE(map_of(&loc)->used > 0u);
}

/* An image with more walls than the pool holds: every row is written as
 * far as it fits, the rest is counted, nothing imported is evicted. */
static void test_pool_full_is_counted(void)
{
    rsm_import_grid_t g;
    rsm_import_report_t rep;
    uint32_t r;
    uint32_t nomem = 0;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &origin_pose, NULL));
    g.res_m = cfg.tmap.cell_m;
    g.origin_x = 0.0f;
    g.origin_y = 0.0f;
    g.yaw_rad = 0.0f;
    g.width = (uint32_t)sizeof row_buf;
    g.coarse = RSM_IMPORT_SHARE;
    memset(row_buf, 0, sizeof row_buf);
    for (r = 0; r < g.width; r += 3u) {
        row_buf[r] = 1u; /* a wall every third pixel: a tile per 8 x 8 pixels */
    }
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&loc, &rep));
    for (r = 0; r < 600u; r += 4u) {
        const int rc = rsm_localizer_import_row(&loc, &g, r, row_buf, &rep);
        TEST_ASSERT_TRUE(rc == RSM_OK || rc == RSM_ERR_NOMEM);
        nomem += rc == RSM_ERR_NOMEM ? 1u : 0u;
    }
    TEST_ASSERT_TRUE(nomem > 0u);
    TEST_ASSERT_TRUE(rep.dropped > 0u);
    TEST_ASSERT_EQUAL_UINT32(rep.dropped, map_of(&loc)->counters.dropped);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)RSM_TMAP_TILES, map_of(&loc)->used);
    TEST_ASSERT_EQUAL_UINT32(0u, map_of(&loc)->counters.evicted);
    TEST_ASSERT_EQUAL_UINT32(150u, rep.rows);
    /* The first row went in whole: its walls read on the finest level. */
    TEST_ASSERT_EQUAL_UINT8(RSM_TMAP_MAX_VALUE, rsm_tmap_value(map_of(&loc), 0u, 0, 0));
    TEST_ASSERT_EQUAL_UINT8(RSM_TMAP_MAX_VALUE, rsm_tmap_value(map_of(&loc), 0u, 3, 0));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(map_of(&loc), 0u, 1, 0));
}

/* Pixels beyond the map's coordinate range are counted, not written. */
static void test_outside_is_counted(void)
{
    rsm_import_grid_t g = {0.05f, 1.0e9f, 0.0f, 0.0f, 4u, RSM_IMPORT_SHARE};
    rsm_import_report_t rep;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &origin_pose, NULL));
    memset(row_buf, 1, 4);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&loc, &rep));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_row(&loc, &g, 0u, row_buf, &rep));
    TEST_ASSERT_EQUAL_UINT32(4u, rep.outside);
    TEST_ASSERT_EQUAL_UINT32(4u, rep.occupied);
    TEST_ASSERT_EQUAL_UINT32(0u, rep.cells);
    TEST_ASSERT_EQUAL_UINT32(0u, map_of(&loc)->used);
}

static void assert_untouched(void)
{
    TEST_ASSERT_EQUAL_MEMORY(&before, &loc, sizeof loc);
}

static void test_bad_arguments_refused(void)
{
    const rsm_import_grid_t good = {0.05f, 0.0f, 0.0f, 0.0f, 4u, RSM_IMPORT_SHARE};
    rsm_import_grid_t g;
    rsm_localizer_config_t other;
    rsm_import_report_t rep;
    memset(row_buf, 1, 4);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &origin_pose, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&loc, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_row(&loc, &good, 1u, row_buf, NULL));
    before = loc;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_begin(NULL, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(NULL, &good, 0u, row_buf, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, NULL, 0u, row_buf, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &good, 0u, NULL, NULL));
    g = good;
    g.res_m = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    g.res_m = -0.05f;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    g.res_m = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    g.res_m = INFINITY;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    g.res_m = 300.0f * cfg.tmap.cell_m; /* beyond 256 cells a pixel */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    g = good;
    g.origin_x = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    g = good;
    g.origin_y = -INFINITY;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    g = good;
    g.yaw_rad = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    g = good;
    g.width = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    g = good;
    g.coarse = 2u;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &g, 0u, row_buf, NULL));
    assert_untouched();
    /* Never initialised. */
    memset(&loc, 0, sizeof loc);
    before = loc;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_begin(&loc, &rep));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_import_row(&loc, &good, 0u, row_buf, &rep));
    assert_untouched();
    /* Another method: no persistent map. */
    other = cfg;
    other.method = RSM_METHOD_ODOMETRY;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &other, &origin_pose, NULL));
    before = loc;
    memset(&rep, 0xA5, sizeof rep);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_localizer_import_begin(&loc, &rep));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_localizer_import_row(&loc, &good, 0u, row_buf, &rep));
    assert_untouched();
    TEST_ASSERT_EQUAL_UINT32(0xA5A5A5A5u, rep.rows);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_localizes_on_room_imported_at_cell);
    RUN_TEST(test_localizes_on_room_imported_at_twice_the_cell);
    RUN_TEST(test_shared_coarse_levels_against_touched);
    RUN_TEST(test_scan_fits_imported_map);
    RUN_TEST(test_coarse_source_leaves_no_gap);
    RUN_TEST(test_fine_source_and_shares);
    RUN_TEST(test_row_sets_continuation);
    RUN_TEST(test_pool_full_is_counted);
    RUN_TEST(test_outside_is_counted);
    RUN_TEST(test_bad_arguments_refused);
    return UNITY_END();
}
