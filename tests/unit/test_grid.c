/* Grid: floor() cell indexing, the toroidal window, the binary image and the
 * three marking rules (docs/reference/method.md step 2). Holds for any RSM_MAP_SIZE_LOG2 and
 * RSM_IMAGE_MAX_CELLS. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "core/grid.h"
#include "unity.h"

#define N ((int32_t)RSM_MAP_SIZE)

/* Big state in static storage (convention: never on the test's stack). */
static rsm_image_t img;
static uint8_t seen[RSM_MAP_CELLS];

static rsm_grid_config_t cfg;
static rsm_window_t win; /* lower-left global cell (-8, -8): holds cells around the origin */

void setUp(void)
{
    rsm_image_reset(&img);
    cfg = rsm_grid_config_default();
    win.ox = -8;
    win.oy = -8;
}

void tearDown(void)
{
}

static size_t mark_one(rsm_grid_rule_t rule, float x, float y)
{
    rsm_point_t p;
    p.x = x;
    p.y = y;
    cfg.rule = rule;
    return rsm_image_mark_points(&img, &win, &cfg, &p, 1);
}

/* Number of set bits in the whole bitmap (independent of the cell list). */
static uint32_t popcount_bits(void)
{
    uint32_t total = 0;
    size_t w;
    for (w = 0; w < RSM_BITMAP_WORDS; ++w) {
        uint32_t v = img.bits[w];
        while (v != 0u) {
            v &= v - 1u;
            ++total;
        }
    }
    return total;
}

/* ---- indexing ------------------------------------------------------------ */

void test_grid_config_default_should_be_the_papers_values(void)
{
    const rsm_grid_config_t c = rsm_grid_config_default();
    TEST_ASSERT_EQUAL_FLOAT(0.05f, c.cell_m);
    TEST_ASSERT_EQUAL_FLOAT(0.005f, c.sigma_m);
    TEST_ASSERT_EQUAL_INT((int)RSM_GRID_SIGMA_TOUCH, (int)c.rule);
}

void test_grid_cell_of_should_floor_negative_coordinates(void)
{
    /* The paper's truncating (int) cast would give 0 for all of these. */
    TEST_ASSERT_EQUAL_INT32(-1, rsm_grid_cell_of(-0.01f, 0.05f));
    TEST_ASSERT_EQUAL_INT32(-1, rsm_grid_cell_of(-0.049f, 0.05f));
    TEST_ASSERT_EQUAL_INT32(-6, rsm_grid_cell_of(-0.26f, 0.05f));
    TEST_ASSERT_EQUAL_INT32(-20, rsm_grid_cell_of(-0.99f, 0.05f));
}

void test_grid_cell_of_should_give_equal_width_cells_either_side_of_zero(void)
{
    TEST_ASSERT_EQUAL_INT32(0, rsm_grid_cell_of(0.0f, 0.05f));
    TEST_ASSERT_EQUAL_INT32(0, rsm_grid_cell_of(0.01f, 0.05f));
    TEST_ASSERT_EQUAL_INT32(0, rsm_grid_cell_of(0.049f, 0.05f));
    TEST_ASSERT_EQUAL_INT32(1, rsm_grid_cell_of(0.051f, 0.05f));
    TEST_ASSERT_EQUAL_INT32(5, rsm_grid_cell_of(0.26f, 0.05f));
    TEST_ASSERT_EQUAL_INT32(12, rsm_grid_cell_of(1.23f, 0.1f));
    TEST_ASSERT_EQUAL_INT32(-13, rsm_grid_cell_of(-1.23f, 0.1f));
}

void test_window_contains_should_accept_exactly_the_window_cells(void)
{
    rsm_window_t w;
    w.ox = -10;
    w.oy = 5;
    TEST_ASSERT_TRUE(rsm_window_contains(&w, -10, 5));
    TEST_ASSERT_TRUE(rsm_window_contains(&w, -10 + N - 1, 5 + N - 1));
    TEST_ASSERT_TRUE(rsm_window_contains(&w, 0, 5 + N / 2));
    TEST_ASSERT_FALSE(rsm_window_contains(&w, -11, 5));
    TEST_ASSERT_FALSE(rsm_window_contains(&w, -10, 4));
    TEST_ASSERT_FALSE(rsm_window_contains(&w, -10 + N, 5));
    TEST_ASSERT_FALSE(rsm_window_contains(&w, -10, 5 + N));
    TEST_ASSERT_FALSE(rsm_window_contains(&w, -10 - N, 5));
    TEST_ASSERT_FALSE(rsm_window_contains(&w, 100000, 100000));
}

static void check_round_trip(int32_t ox, int32_t oy)
{
    rsm_window_t w;
    int32_t gx;
    int32_t gy;
    w.ox = ox;
    w.oy = oy;
    memset(seen, 0, sizeof seen);
    for (gy = oy; gy < oy + N; ++gy) {
        for (gx = ox; gx < ox + N; ++gx) {
            const uint32_t i = rsm_window_index(gx, gy);
            rsm_cell_t c;
            TEST_ASSERT_LESS_THAN_UINT32((uint32_t)RSM_MAP_CELLS, i);
            TEST_ASSERT_EQUAL_UINT8_MESSAGE(0, seen[i], "two window cells share one storage index");
            seen[i] = 1;
            c = rsm_window_cell(&w, i);
            TEST_ASSERT_EQUAL_INT32(gx, c.gx);
            TEST_ASSERT_EQUAL_INT32(gy, c.gy);
        }
    }
}

void test_window_index_should_round_trip_every_cell_of_any_window(void)
{
    check_round_trip(0, 0);
    check_round_trip(-37, 1000);
    check_round_trip(-N - 5, -3 * N + 1);
    check_round_trip(123457, -98765);
}

void test_window_index_should_wrap_toroidally(void)
{
    /* Cells N apart share storage: that is what lets the window scroll. */
    TEST_ASSERT_EQUAL_UINT32(rsm_window_index(3, 4), rsm_window_index(3 + N, 4));
    TEST_ASSERT_EQUAL_UINT32(rsm_window_index(3, 4), rsm_window_index(3, 4 - N));
    TEST_ASSERT_EQUAL_UINT32(rsm_window_index(-1, -1), (uint32_t)(N - 1) + (uint32_t)(N - 1) * (uint32_t)N);
    TEST_ASSERT_EQUAL_UINT32(5u + 2u * (uint32_t)N, rsm_window_index(5, 2));
}

/* ---- image ----------------------------------------------------------------- */

void test_image_set_should_set_list_and_report_new_cells_once(void)
{
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, 3, 4));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_set(&img, &win, 3, 4));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 3, 4));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_set(&img, &win, 3, 4));
    TEST_ASSERT_EQUAL_size_t(1, img.count);
    TEST_ASSERT_EQUAL_UINT32(rsm_window_index(3, 4), img.cells[0]);
    TEST_ASSERT_EQUAL_INT(1, rsm_image_set(&img, &win, -8, -8));
    TEST_ASSERT_EQUAL_size_t(2, img.count);
    /* Neighbours stay clear. */
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, 4, 4));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, 3, 5));
    TEST_ASSERT_EQUAL_UINT32(2, popcount_bits());
    TEST_ASSERT_EQUAL_UINT32(0, img.outside);
    TEST_ASSERT_EQUAL_UINT32(0, img.overflow);
}

void test_image_set_should_count_cells_outside_the_window(void)
{
    TEST_ASSERT_EQUAL_INT(0, rsm_image_set(&img, &win, -9, 0));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_set(&img, &win, 0, -8 + N));
    TEST_ASSERT_EQUAL_UINT32(2, img.outside);
    TEST_ASSERT_EQUAL_size_t(0, img.count);
    TEST_ASSERT_EQUAL_UINT32(0, popcount_bits());
    /* Reading outside gives 0 even where the torus would alias a set cell. */
    TEST_ASSERT_EQUAL_INT(1, rsm_image_set(&img, &win, 0, 0));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, N, 0));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, 0, -N));
}

void test_image_clear_should_cost_only_the_listed_cells(void)
{
    const uint32_t stray = rsm_window_index(7, 7);
    TEST_ASSERT_EQUAL_INT(1, rsm_image_set(&img, &win, 1, 1));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_set(&img, &win, -2, 5));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_set(&img, &win, 1000, 0));
    /* A bit set behind the image's back is not in the list: a clear that
     * walks only the list (no overflow) must leave it, which shows the cost
     * is O(listed cells), not O(window). */
    img.bits[stray >> 5] |= 1u << (stray & 31u);
    rsm_image_clear(&img);
    TEST_ASSERT_EQUAL_size_t(0, img.count);
    TEST_ASSERT_EQUAL_UINT32(0, img.outside);
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, 1, 1));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, -2, 5));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 7, 7));
    TEST_ASSERT_EQUAL_UINT32(1, popcount_bits());
}

void test_image_clear_should_wipe_everything_after_an_overflow(void)
{
    const uint32_t extra = 5u;
    const uint32_t total = (uint32_t)RSM_IMAGE_MAX_CELLS + extra;
    const uint32_t stray = rsm_window_index(-8 + N - 1, -8 + N - 1);
    uint32_t k;
    TEST_ASSERT_TRUE_MESSAGE(total <= (uint32_t)RSM_MAP_CELLS, "window too small for this test");
    for (k = 0; k < total; ++k) {
        const int32_t gx = -8 + (int32_t)(k % (uint32_t)N);
        const int32_t gy = -8 + (int32_t)(k / (uint32_t)N);
        TEST_ASSERT_EQUAL_INT(1, rsm_image_set(&img, &win, gx, gy));
    }
    TEST_ASSERT_EQUAL_size_t((size_t)RSM_IMAGE_MAX_CELLS, img.count);
    TEST_ASSERT_EQUAL_UINT32(extra, img.overflow);
    /* Unlisted cells are still drawn. */
    TEST_ASSERT_EQUAL_UINT32(total, popcount_bits());
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, -8 + (int32_t)((total - 1u) % (uint32_t)N),
                                           -8 + (int32_t)((total - 1u) / (uint32_t)N)));
    img.bits[stray >> 5] |= 1u << (stray & 31u);
    rsm_image_clear(&img);
    TEST_ASSERT_EQUAL_UINT32(0, popcount_bits());
    TEST_ASSERT_EQUAL_size_t(0, img.count);
    TEST_ASSERT_EQUAL_UINT32(0, img.overflow);
}

void test_image_reset_should_clear_every_bit_and_counter(void)
{
    memset(&img, 0xFF, sizeof img);
    rsm_image_reset(&img);
    TEST_ASSERT_EQUAL_UINT32(0, popcount_bits());
    TEST_ASSERT_EQUAL_size_t(0, img.count);
    TEST_ASSERT_EQUAL_UINT32(0, img.outside);
    TEST_ASSERT_EQUAL_UINT32(0, img.overflow);
}

/* ---- marking rules ----------------------------------------------------------- */
/* Cell side a = 0.05 m, sigma = 0.005 m: cell (0, 0) spans [0, 0.05)^2. */

void test_image_mark_points_should_mark_one_cell_for_a_central_point_under_every_rule(void)
{
    TEST_ASSERT_EQUAL_size_t(1, mark_one(RSM_GRID_SIGMA_INSIDE, 0.025f, 0.025f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 0));
    rsm_image_clear(&img);
    TEST_ASSERT_EQUAL_size_t(1, mark_one(RSM_GRID_SIGMA_TOUCH, 0.025f, 0.025f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 0));
    rsm_image_clear(&img);
    TEST_ASSERT_EQUAL_size_t(1, mark_one(RSM_GRID_NEAREST, 0.025f, 0.025f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 0));
    TEST_ASSERT_EQUAL_UINT32(1, popcount_bits());
}

void test_image_mark_points_should_drop_a_point_within_sigma_of_a_border_under_sigma_inside(void)
{
    TEST_ASSERT_EQUAL_size_t(0, mark_one(RSM_GRID_SIGMA_INSIDE, 0.002f, 0.025f));  /* west border */
    TEST_ASSERT_EQUAL_size_t(0, mark_one(RSM_GRID_SIGMA_INSIDE, 0.048f, 0.025f));  /* east */
    TEST_ASSERT_EQUAL_size_t(0, mark_one(RSM_GRID_SIGMA_INSIDE, 0.025f, 0.003f));  /* south */
    TEST_ASSERT_EQUAL_size_t(0, mark_one(RSM_GRID_SIGMA_INSIDE, 0.025f, 0.047f));  /* north */
    TEST_ASSERT_EQUAL_size_t(0, mark_one(RSM_GRID_SIGMA_INSIDE, -0.002f, 0.025f)); /* east side of cell -1 */
    TEST_ASSERT_EQUAL_UINT32(0, popcount_bits());
    /* Just beyond sigma from every border: marked. */
    TEST_ASSERT_EQUAL_size_t(1, mark_one(RSM_GRID_SIGMA_INSIDE, 0.006f, 0.044f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 0));
    TEST_ASSERT_EQUAL_size_t(1, mark_one(RSM_GRID_SIGMA_INSIDE, -0.044f, -0.006f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, -1, -1));
    TEST_ASSERT_EQUAL_UINT32(2, popcount_bits());
}

void test_image_mark_points_should_mark_two_cells_near_one_border_under_sigma_touch(void)
{
    TEST_ASSERT_EQUAL_size_t(2, mark_one(RSM_GRID_SIGMA_TOUCH, 0.002f, 0.025f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 0));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, -1, 0));
    TEST_ASSERT_EQUAL_UINT32(2, popcount_bits());
    rsm_image_clear(&img);
    TEST_ASSERT_EQUAL_size_t(2, mark_one(RSM_GRID_SIGMA_TOUCH, 0.025f, 0.048f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 0));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 1));
    TEST_ASSERT_EQUAL_UINT32(2, popcount_bits());
    rsm_image_clear(&img);
    /* Negative side: -0.002 lies in cell -1, 0.002 from its east border. */
    TEST_ASSERT_EQUAL_size_t(2, mark_one(RSM_GRID_SIGMA_TOUCH, -0.002f, -0.025f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, -1, -1));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, -1));
    TEST_ASSERT_EQUAL_UINT32(2, popcount_bits());
}

void test_image_mark_points_should_mark_the_corner_cell_only_when_the_circle_reaches_it(void)
{
    /* 0.004 from both borders: sqrt(2) * 0.004 = 0.0057 > sigma, so the
     * circle touches the west and south neighbours but not the corner. */
    TEST_ASSERT_EQUAL_size_t(3, mark_one(RSM_GRID_SIGMA_TOUCH, 0.004f, 0.004f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 0));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, -1, 0));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, -1));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, -1, -1));
    TEST_ASSERT_EQUAL_UINT32(3, popcount_bits());
    rsm_image_clear(&img);
    /* 0.002 from both: 0.0028 < sigma, all four cells. */
    TEST_ASSERT_EQUAL_size_t(4, mark_one(RSM_GRID_SIGMA_TOUCH, 0.002f, 0.002f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, -1, -1));
    TEST_ASSERT_EQUAL_UINT32(4, popcount_bits());
    rsm_image_clear(&img);
    /* The north-east corner of cell (0, 0). */
    TEST_ASSERT_EQUAL_size_t(4, mark_one(RSM_GRID_SIGMA_TOUCH, 0.048f, 0.048f));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 0));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 1, 0));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 0, 1));
    TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, 1, 1));
    TEST_ASSERT_EQUAL_UINT32(4, popcount_bits());
}

void test_image_mark_points_should_always_mark_one_cell_under_nearest(void)
{
    static const float xy[][2] = {{0.002f, 0.025f}, {0.004f, 0.004f}, {-0.002f, -0.002f}, {0.048f, 0.048f}};
    static const int32_t cell[][2] = {{0, 0}, {0, 0}, {-1, -1}, {0, 0}};
    size_t k;
    for (k = 0; k < sizeof xy / sizeof xy[0]; ++k) {
        rsm_image_clear(&img);
        TEST_ASSERT_EQUAL_size_t(1, mark_one(RSM_GRID_NEAREST, xy[k][0], xy[k][1]));
        TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, cell[k][0], cell[k][1]));
        TEST_ASSERT_EQUAL_UINT32(1, popcount_bits());
    }
}

void test_image_mark_points_should_return_only_newly_set_cells(void)
{
    rsm_point_t p[3];
    p[0].x = 0.025f;
    p[0].y = 0.025f;
    p[1].x = 0.03f; /* same cell */
    p[1].y = 0.02f;
    p[2].x = 0.075f;
    p[2].y = 0.025f;
    cfg.rule = RSM_GRID_NEAREST;
    TEST_ASSERT_EQUAL_size_t(2, rsm_image_mark_points(&img, &win, &cfg, p, 3));
    TEST_ASSERT_EQUAL_size_t(0, rsm_image_mark_points(&img, &win, &cfg, p, 3));
    TEST_ASSERT_EQUAL_size_t(2, img.count);
}

void test_image_mark_points_should_count_non_finite_and_huge_points_as_outside(void)
{
    rsm_point_t p[7];
    size_t k;
    const rsm_grid_rule_t rules[3] = {RSM_GRID_SIGMA_INSIDE, RSM_GRID_SIGMA_TOUCH, RSM_GRID_NEAREST};
    p[0].x = NAN;
    p[0].y = 0.0f;
    p[1].x = 0.0f;
    p[1].y = NAN;
    p[2].x = INFINITY;
    p[2].y = 0.0f;
    p[3].x = 0.0f;
    p[3].y = -INFINITY;
    p[4].x = 1.0e7f; /* finite, but far beyond any window */
    p[4].y = 0.0f;
    p[5].x = 0.0f;
    p[5].y = -3.0e9f;
    p[6].x = 100.025f; /* mid-cell, just outside the window */
    p[6].y = 0.025f;
    for (k = 0; k < 3; ++k) {
        rsm_image_clear(&img);
        cfg.rule = rules[k];
        TEST_ASSERT_EQUAL_size_t(0, rsm_image_mark_points(&img, &win, &cfg, p, 7));
        TEST_ASSERT_EQUAL_UINT32(7, img.outside);
        TEST_ASSERT_EQUAL_size_t(0, img.count);
        TEST_ASSERT_EQUAL_UINT32(0, popcount_bits());
    }
}

void test_image_mark_points_should_cover_a_wall_without_gaps(void)
{
    /* Points every 1 cm along y = 0.12 from x = -0.295 to 0.295 (a wall):
     * every cell column from -6 to 5 gets its row-2 cell (row 2 spans
     * [0.10, 0.15)) and nothing else. */
    rsm_point_t p[60];
    int32_t gx;
    size_t k;
    for (k = 0; k < 60; ++k) {
        p[k].x = -0.295f + 0.01f * (float)k;
        p[k].y = 0.12f;
    }
    cfg.rule = RSM_GRID_NEAREST;
    TEST_ASSERT_EQUAL_size_t(12, rsm_image_mark_points(&img, &win, &cfg, p, 60));
    for (gx = -6; gx <= 5; ++gx) {
        TEST_ASSERT_EQUAL_INT(1, rsm_image_get(&img, &win, gx, 2));
    }
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, -7, 2));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, 0, 1));
    TEST_ASSERT_EQUAL_INT(0, rsm_image_get(&img, &win, 0, 3));
    TEST_ASSERT_EQUAL_UINT32(12, popcount_bits());
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_grid_config_default_should_be_the_papers_values);
    RUN_TEST(test_grid_cell_of_should_floor_negative_coordinates);
    RUN_TEST(test_grid_cell_of_should_give_equal_width_cells_either_side_of_zero);
    RUN_TEST(test_window_contains_should_accept_exactly_the_window_cells);
    RUN_TEST(test_window_index_should_round_trip_every_cell_of_any_window);
    RUN_TEST(test_window_index_should_wrap_toroidally);
    RUN_TEST(test_image_set_should_set_list_and_report_new_cells_once);
    RUN_TEST(test_image_set_should_count_cells_outside_the_window);
    RUN_TEST(test_image_clear_should_cost_only_the_listed_cells);
    RUN_TEST(test_image_clear_should_wipe_everything_after_an_overflow);
    RUN_TEST(test_image_reset_should_clear_every_bit_and_counter);
    RUN_TEST(test_image_mark_points_should_mark_one_cell_for_a_central_point_under_every_rule);
    RUN_TEST(test_image_mark_points_should_drop_a_point_within_sigma_of_a_border_under_sigma_inside);
    RUN_TEST(test_image_mark_points_should_mark_two_cells_near_one_border_under_sigma_touch);
    RUN_TEST(test_image_mark_points_should_mark_the_corner_cell_only_when_the_circle_reaches_it);
    RUN_TEST(test_image_mark_points_should_always_mark_one_cell_under_nearest);
    RUN_TEST(test_image_mark_points_should_return_only_newly_set_cells);
    RUN_TEST(test_image_mark_points_should_count_non_finite_and_huge_points_as_outside);
    RUN_TEST(test_image_mark_points_should_cover_a_wall_without_gaps);
    return UNITY_END();
}
