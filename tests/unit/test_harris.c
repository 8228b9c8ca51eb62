/* Integer Harris: exact responses on hand-built 5x5 patches, detection with
 * non-maximum suppression, the cap and the candidate capacity, determinism.
 *
 * Expected responses were computed by hand (single pixel) and with an
 * independent textbook implementation (Sobel kernels, 1-2-1 window,
 * R = k_den det - k_num trace^2, k = 1/25), not with the library's code. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "rsm/config.h"
#include "core/grid.h"
#include "paper/harris.h"
#include "rsm/status.h"
#include "synth.h"
#include "unity.h"

/* A detection buffer larger than any key point count used here. */
#define OUT_CAP 64

static rsm_image_t img;
static rsm_harris_work_t work;
static rsm_harris_work_t work2;
static rsm_cell_t cands[RSM_MAX_CANDIDATES + 16];
static rsm_keypoint_t out[OUT_CAP];
static rsm_keypoint_t out2[OUT_CAP];
static rsm_scan_t scan;
static rsm_point_t pts[RSM_MAX_BEAMS];

static rsm_window_t win;
static rsm_harris_config_t cfg;
static rsm_harris_image_src_t src;

void setUp(void)
{
    rsm_image_reset(&img);
    win.ox = -20;
    win.oy = -20;
    cfg = rsm_harris_config_default();
    src.img = &img;
    src.win = &win;
    memset(out, 0, sizeof out);
    memset(out2, 0, sizeof out2);
}

void tearDown(void)
{
}

/* A patch from five rows of '.'/'#', rows[0] being dy = -2 and column 0
 * being dx = -2 (bit (dy + 2) * 5 + (dx + 2), as documented in harris.h). */
static uint32_t patch_of(const char *const rows[5])
{
    uint32_t p = 0;
    uint32_t r;
    uint32_t c;
    for (r = 0; r < 5u; ++r) {
        for (c = 0; c < 5u; ++c) {
            if (rows[r][c] == '#') {
                p |= 1u << (r * 5u + c);
            }
        }
    }
    return p;
}

static void set_cell(int32_t gx, int32_t gy)
{
    TEST_ASSERT_EQUAL_INT(1, rsm_image_set(&img, &win, gx, gy));
}

/* Outline of a square with corners (0, 0) and (9, 9); candidates are its
 * cells row by row (y, then x), so the corners come in the order
 * (0,0), (9,0), (0,9), (9,9). Returns the candidate count. */
static size_t square_outline(void)
{
    size_t n = 0;
    int32_t y;
    int32_t x;
    for (y = 0; y <= 9; ++y) {
        for (x = 0; x <= 9; ++x) {
            if (x == 0 || x == 9 || y == 0 || y == 9) {
                set_cell(x, y);
                cands[n].gx = x;
                cands[n].gy = y;
                ++n;
            }
        }
    }
    return n;
}

static int32_t response_at(int32_t gx, int32_t gy)
{
    return rsm_harris_response(&cfg, rsm_harris_patch_image(&src, gx, gy));
}

static void assert_keypoint(int32_t gx, int32_t gy, int32_t response, const rsm_keypoint_t *kp)
{
    TEST_ASSERT_EQUAL_INT32(gx, kp->gx);
    TEST_ASSERT_EQUAL_INT32(gy, kp->gy);
    TEST_ASSERT_EQUAL_INT32(response, kp->response);
}

/* ---- response ------------------------------------------------------------ */

void test_harris_config_default_should_be_k_of_0_04_and_3x3_suppression(void)
{
    const rsm_harris_config_t c = rsm_harris_config_default();
    TEST_ASSERT_EQUAL_INT32(1, c.k_num);
    TEST_ASSERT_EQUAL_INT32(25, c.k_den);
    TEST_ASSERT_EQUAL_INT32(1, c.min_response);
    TEST_ASSERT_EQUAL_INT32(1, c.nms_radius);
}

void test_harris_response_should_be_zero_for_an_empty_or_full_patch(void)
{
    static const char *const full[5] = {"#####", "#####", "#####", "#####", "#####"};
    TEST_ASSERT_EQUAL_INT32(0, rsm_harris_response(&cfg, 0u));
    TEST_ASSERT_EQUAL_INT32(0, rsm_harris_response(&cfg, patch_of(full)));
}

void test_harris_response_should_be_negative_on_a_straight_line_or_edge(void)
{
    static const char *const hline[5] = {".....", ".....", "#####", ".....", "....."};
    static const char *const vline[5] = {"..#..", "..#..", "..#..", "..#..", "..#.."};
    static const char *const half[5] = {".....", ".....", "#####", "#####", "#####"};
    static const char *const diag[5] = {"#....", ".#...", "..#..", "...#.", "....#"};
    /* Sxx = 0, Syy = 128: det = 0, R = -128^2. */
    TEST_ASSERT_EQUAL_INT32(-16384, rsm_harris_response(&cfg, patch_of(hline)));
    TEST_ASSERT_EQUAL_INT32(-16384, rsm_harris_response(&cfg, patch_of(vline)));
    TEST_ASSERT_EQUAL_INT32(-36864, rsm_harris_response(&cfg, patch_of(half)));
    /* A diagonal line is an edge too: Sxx = Syy = 34, Sxy = -34. */
    TEST_ASSERT_EQUAL_INT32(-4624, rsm_harris_response(&cfg, patch_of(diag)));
}

void test_harris_response_should_match_the_hand_computed_value_for_a_single_cell(void)
{
    /* One set cell: Ix = [1 0 -1; 2 0 -2; 1 0 -1] over the 3x3 window, Iy its
     * transpose; with 1-2-1 weights Sxx = Syy = 2 + 16 + 2 = 20, Sxy = 0.
     * det = 400, trace = 40: R = 25 * 400 - 1 * 1600 = 8400. */
    static const char *const single[5] = {".....", ".....", "..#..", ".....", "....."};
    rsm_harris_config_t c = cfg;
    TEST_ASSERT_EQUAL_INT32(8400, rsm_harris_response(&cfg, patch_of(single)));
    c.k_num = 0; /* R = k_den * det */
    TEST_ASSERT_EQUAL_INT32(10000, rsm_harris_response(&c, patch_of(single)));
    c.k_num = 1;
    c.k_den = 1; /* R = det - trace^2 = 400 - 1600 */
    TEST_ASSERT_EQUAL_INT32(-1200, rsm_harris_response(&c, patch_of(single)));
}

void test_harris_response_should_be_positive_at_an_l_corner(void)
{
    static const char *const corner[5] = {".....", ".....", "..###", "..#..", "..#.."};
    static const char *const thick[5] = {".....", ".....", "..###", "..###", "..###"};
    /* Sxx = Syy = 66, Sxy = 34 (independent reference). */
    TEST_ASSERT_EQUAL_INT32(62576, rsm_harris_response(&cfg, patch_of(corner)));
    TEST_ASSERT_EQUAL_INT32(171500, rsm_harris_response(&cfg, patch_of(thick)));
}

void test_harris_response_should_peak_at_the_corner_of_an_l(void)
{
    int32_t best = INT32_MIN;
    int32_t best_x = 99;
    int32_t best_y = 99;
    int32_t k;
    for (k = 0; k <= 7; ++k) {
        set_cell(k, 0);
        if (k > 0) {
            set_cell(0, k);
        }
    }
    for (k = 0; k <= 7; ++k) {
        int32_t r = response_at(k, 0);
        if (r > best) {
            best = r;
            best_x = k;
            best_y = 0;
        }
        r = response_at(0, k);
        if (r > best) {
            best = r;
            best_x = 0;
            best_y = k;
        }
    }
    TEST_ASSERT_EQUAL_INT32(0, best_x);
    TEST_ASSERT_EQUAL_INT32(0, best_y);
    TEST_ASSERT_EQUAL_INT32(62576, best);
    /* Strictly weaker one cell along each arm, an edge in the middle. */
    TEST_ASSERT_LESS_THAN_INT32(62576, response_at(1, 0));
    TEST_ASSERT_LESS_THAN_INT32(62576, response_at(0, 1));
    TEST_ASSERT_EQUAL_INT32(-16384, response_at(4, 0));
    TEST_ASSERT_EQUAL_INT32(-16384, response_at(0, 4));
    /* And zero far from anything. */
    TEST_ASSERT_EQUAL_INT32(0, response_at(5, 5));
}

void test_harris_patch_image_should_lay_out_bits_row_by_row(void)
{
    set_cell(11, 8);  /* dx = +1, dy = -2 -> bit 3 */
    set_cell(8, 12);  /* dx = -2, dy = +2 -> bit 20 */
    set_cell(10, 10); /* centre -> bit 12 */
    set_cell(13, 10); /* dx = +3: outside the patch */
    TEST_ASSERT_EQUAL_HEX32((1u << 3) | (1u << 20) | (1u << 12), rsm_harris_patch_image(&src, 10, 10));
    /* Cells beyond the window read as clear. */
    TEST_ASSERT_EQUAL_HEX32(0u, rsm_harris_patch_image(&src, win.ox - 3, win.oy - 3));
}

/* ---- detection ------------------------------------------------------------- */

void test_harris_detect_should_return_the_four_square_corners_strongest_first(void)
{
    const size_t n = square_outline();
    size_t skipped = 99;
    int got;
    size_t k;
    TEST_ASSERT_EQUAL_size_t(36, n);
    got = rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, &skipped);
    TEST_ASSERT_EQUAL_size_t(0, skipped);
    /* 3x3 suppression keeps the four corners, then the eight cells two
     * along each side from a corner (R 14644). */
    TEST_ASSERT_EQUAL_INT(12, got);
    assert_keypoint(0, 0, 62576, &out[0]);
    assert_keypoint(9, 0, 62576, &out[1]);
    assert_keypoint(0, 9, 62576, &out[2]);
    assert_keypoint(9, 9, 62576, &out[3]);
    for (k = 4; k < 12; ++k) {
        TEST_ASSERT_EQUAL_INT32(14644, out[k].response);
    }
    /* Ties between equal responses follow candidate order. */
    assert_keypoint(2, 0, 14644, &out[4]);
    assert_keypoint(7, 0, 14644, &out[5]);
    assert_keypoint(0, 2, 14644, &out[6]);
    assert_keypoint(7, 9, 14644, &out[11]);
}

void test_harris_detect_should_break_ties_by_candidate_order(void)
{
    const size_t n = square_outline();
    size_t k;
    /* Reverse the candidate list: the equal corners come out reversed. */
    for (k = 0; k < n / 2; ++k) {
        const rsm_cell_t t = cands[k];
        cands[k] = cands[n - 1 - k];
        cands[n - 1 - k] = t;
    }
    TEST_ASSERT_EQUAL_INT(4, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, 4, NULL));
    assert_keypoint(9, 9, 62576, &out[0]);
    assert_keypoint(0, 9, 62576, &out[1]);
    assert_keypoint(9, 0, 62576, &out[2]);
    assert_keypoint(0, 0, 62576, &out[3]);
}

void test_harris_detect_should_suppress_within_nms_radius(void)
{
    const size_t n = square_outline();
    int got;
    int i;
    int j;
    /* No suppression: every candidate with R > min_response (20 of 36). */
    cfg.nms_radius = 0;
    TEST_ASSERT_EQUAL_INT(20, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, NULL));
    assert_keypoint(0, 0, 62576, &out[0]);
    assert_keypoint(1, 0, 50304, &out[4]);
    /* Radius 2 removes the secondary responses two cells from a corner. */
    cfg.nms_radius = 2;
    TEST_ASSERT_EQUAL_INT(4, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, NULL));
    /* A radius wider than the square leaves the single strongest. */
    cfg.nms_radius = 100;
    TEST_ASSERT_EQUAL_INT(1, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, NULL));
    assert_keypoint(0, 0, 62576, &out[0]);
    /* Radius 1: no two key points within one cell (Chebyshev). */
    cfg.nms_radius = 1;
    got = rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, NULL);
    for (i = 0; i < got; ++i) {
        for (j = i + 1; j < got; ++j) {
            const int32_t dx = out[i].gx - out[j].gx;
            const int32_t dy = out[i].gy - out[j].gy;
            TEST_ASSERT_TRUE(dx > 1 || dx < -1 || dy > 1 || dy < -1);
        }
    }
}

void test_harris_detect_should_keep_only_responses_above_min_response(void)
{
    const size_t n = square_outline();
    cfg.min_response = 62576; /* must be exceeded, not reached */
    TEST_ASSERT_EQUAL_INT(0, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, NULL));
    cfg.min_response = 62575;
    TEST_ASSERT_EQUAL_INT(4, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, NULL));
    cfg.min_response = 14644;
    TEST_ASSERT_EQUAL_INT(4, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, NULL));
    cfg.min_response = 14643;
    TEST_ASSERT_EQUAL_INT(12, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, NULL));
}

void test_harris_detect_should_truncate_at_cap_keeping_the_strongest(void)
{
    const size_t n = square_outline();
    TEST_ASSERT_EQUAL_INT(2, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, 2, NULL));
    assert_keypoint(0, 0, 62576, &out[0]);
    assert_keypoint(9, 0, 62576, &out[1]);
    TEST_ASSERT_EQUAL_INT32(0, out[2].response); /* untouched beyond cap */
    TEST_ASSERT_EQUAL_INT(0, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, NULL, 0, NULL));
}

void test_harris_detect_should_fill_rsm_max_keypoints_from_more_equal_corners(void)
{
    /* RSM_MAX_KEYPOINTS + 5 isolated cells three apart (independent 5x5
     * patches, each R = 8400): a detector capped at RSM_MAX_KEYPOINTS keeps
     * the first RSM_MAX_KEYPOINTS in candidate order. */
    static rsm_keypoint_t kps[RSM_MAX_KEYPOINTS + 1];
    const size_t n = (size_t)RSM_MAX_KEYPOINTS + 5u;
    const size_t per_row = (size_t)(RSM_MAP_SIZE - 24) / 3u;
    size_t k;
    TEST_ASSERT_TRUE(n <= (size_t)RSM_MAX_CANDIDATES);
    TEST_ASSERT_TRUE_MESSAGE((n / per_row + 1u) * 3u < (size_t)RSM_MAP_SIZE - 20u, "window too small for this test");
    for (k = 0; k < n; ++k) {
        cands[k].gx = (int32_t)(3u * (k % per_row));
        cands[k].gy = (int32_t)(3u * (k / per_row));
        set_cell(cands[k].gx, cands[k].gy);
    }
    kps[RSM_MAX_KEYPOINTS].response = -7;
    TEST_ASSERT_EQUAL_INT(RSM_MAX_KEYPOINTS, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n,
                                                               kps, RSM_MAX_KEYPOINTS, NULL));
    for (k = 0; k < (size_t)RSM_MAX_KEYPOINTS; ++k) {
        assert_keypoint(cands[k].gx, cands[k].gy, 8400, &kps[k]);
    }
    TEST_ASSERT_EQUAL_INT32(-7, kps[RSM_MAX_KEYPOINTS].response);
}

void test_harris_detect_should_skip_candidates_beyond_rsm_max_candidates(void)
{
    const size_t n = (size_t)RSM_MAX_CANDIDATES + 10u;
    size_t skipped = 0;
    size_t k;
    (void)square_outline();
    /* Every candidate sits on empty cells (R = 0) except one corner. */
    for (k = 0; k < n; ++k) {
        cands[k].gx = 15;
        cands[k].gy = 15;
    }
    cands[n - 1].gx = 0; /* beyond capacity: never evaluated */
    cands[n - 1].gy = 0;
    TEST_ASSERT_EQUAL_INT(0, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, &skipped));
    TEST_ASSERT_EQUAL_size_t(10, skipped);
    cands[n - 1].gx = 15;
    cands[n - 1].gy = 15;
    cands[RSM_MAX_CANDIDATES - 1].gx = 9; /* the last one that fits */
    cands[RSM_MAX_CANDIDATES - 1].gy = 9;
    TEST_ASSERT_EQUAL_INT(1, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, &skipped));
    TEST_ASSERT_EQUAL_size_t(10, skipped);
    assert_keypoint(9, 9, 62576, &out[0]);
    /* Exactly at capacity nothing is skipped. */
    TEST_ASSERT_EQUAL_INT(1, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands,
                                               (size_t)RSM_MAX_CANDIDATES, out, OUT_CAP, &skipped));
    TEST_ASSERT_EQUAL_size_t(0, skipped);
}

void test_harris_detect_should_reject_invalid_arguments(void)
{
    const size_t n = square_outline();
    rsm_harris_config_t bad = cfg;
    size_t skipped = 0;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_harris_detect(NULL, &work, rsm_harris_patch_image, &src, cands, n, out, 4, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_harris_detect(&cfg, NULL, rsm_harris_patch_image, &src, cands, n, out, 4, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_harris_detect(&cfg, &work, NULL, &src, cands, n, out, 4, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, NULL, n, out, 4, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, NULL, 4, NULL));
    bad.k_den = 0;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_harris_detect(&bad, &work, rsm_harris_patch_image, &src, cands, n, out, 4, NULL));
    bad = cfg;
    bad.k_num = -1;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_harris_detect(&bad, &work, rsm_harris_patch_image, &src, cands, n, out, 4, NULL));
    bad = cfg;
    bad.nms_radius = -1;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_harris_detect(&bad, &work, rsm_harris_patch_image, &src, cands, n, out, 4, NULL));
    /* No candidates is not an error. */
    TEST_ASSERT_EQUAL_INT(0, rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, NULL, 0, out, 4, &skipped));
    TEST_ASSERT_EQUAL_size_t(0, skipped);
}

void test_harris_detect_should_be_deterministic_on_a_scan_image(void)
{
    const rsm_synth_world_t world = rsm_synth_world_room();
    const rsm_synth_scan_config_t sc = rsm_synth_scan_config_default();
    const rsm_grid_config_t gc = rsm_grid_config_default();
    const rsm_pose_t pose = {-0.6f, -1.0f, 0.9f};
    size_t npts = 0;
    size_t n;
    size_t k;
    int got;
    int got2;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, &pose, &sc, NULL, 0u, &scan));
    for (k = 0; k < scan.count; ++k) {
        if (scan.range_m[k] < sc.max_range_m) {
            const float a = pose.theta + scan.angle_rad[k];
            pts[npts].x = pose.x + scan.range_m[k] * cosf(a);
            pts[npts].y = pose.y + scan.range_m[k] * sinf(a);
            ++npts;
        }
    }
    /* The window centred on the robot, as the localizer draws it. */
    win.ox = rsm_grid_cell_of(pose.x, gc.cell_m) - (int32_t)(RSM_MAP_SIZE / 2);
    win.oy = rsm_grid_cell_of(pose.y, gc.cell_m) - (int32_t)(RSM_MAP_SIZE / 2);
    (void)rsm_image_mark_points(&img, &win, &gc, pts, npts);
    n = img.count < (size_t)RSM_MAX_CANDIDATES ? img.count : (size_t)RSM_MAX_CANDIDATES;
    TEST_ASSERT_GREATER_THAN_size_t(20, n);
    for (k = 0; k < n; ++k) {
        cands[k] = rsm_window_cell(&win, img.cells[k]);
    }
    /* Scratch contents must not matter. */
    memset(&work, 0x5A, sizeof work);
    memset(&work2, 0xC3, sizeof work2);
    got = rsm_harris_detect(&cfg, &work, rsm_harris_patch_image, &src, cands, n, out, OUT_CAP, NULL);
    got2 = rsm_harris_detect(&cfg, &work2, rsm_harris_patch_image, &src, cands, n, out2, OUT_CAP, NULL);
    TEST_ASSERT_GREATER_OR_EQUAL_INT(4, got);
    TEST_ASSERT_EQUAL_INT(got, got2);
    TEST_ASSERT_EQUAL_MEMORY(out, out2, (size_t)got * sizeof out[0]);
    /* Strongest first, each above the threshold and equal to its own response. */
    for (k = 0; k < (size_t)got; ++k) {
        TEST_ASSERT_GREATER_THAN_INT32(cfg.min_response, out[k].response);
        TEST_ASSERT_EQUAL_INT32(response_at(out[k].gx, out[k].gy), out[k].response);
        if (k > 0) {
            TEST_ASSERT_TRUE(out[k - 1].response >= out[k].response);
        }
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_harris_config_default_should_be_k_of_0_04_and_3x3_suppression);
    RUN_TEST(test_harris_response_should_be_zero_for_an_empty_or_full_patch);
    RUN_TEST(test_harris_response_should_be_negative_on_a_straight_line_or_edge);
    RUN_TEST(test_harris_response_should_match_the_hand_computed_value_for_a_single_cell);
    RUN_TEST(test_harris_response_should_be_positive_at_an_l_corner);
    RUN_TEST(test_harris_response_should_peak_at_the_corner_of_an_l);
    RUN_TEST(test_harris_patch_image_should_lay_out_bits_row_by_row);
    RUN_TEST(test_harris_detect_should_return_the_four_square_corners_strongest_first);
    RUN_TEST(test_harris_detect_should_break_ties_by_candidate_order);
    RUN_TEST(test_harris_detect_should_suppress_within_nms_radius);
    RUN_TEST(test_harris_detect_should_keep_only_responses_above_min_response);
    RUN_TEST(test_harris_detect_should_truncate_at_cap_keeping_the_strongest);
    RUN_TEST(test_harris_detect_should_fill_rsm_max_keypoints_from_more_equal_corners);
    RUN_TEST(test_harris_detect_should_skip_candidates_beyond_rsm_max_candidates);
    RUN_TEST(test_harris_detect_should_reject_invalid_arguments);
    RUN_TEST(test_harris_detect_should_be_deterministic_on_a_scan_image);
    return UNITY_END();
}
