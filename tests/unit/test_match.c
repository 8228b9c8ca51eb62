/* Tentative matches (eq. 10 plus the +-w box): nearest neighbour within
 * max_nn only, every current key point within +-w of that nearest one,
 * grouping by reference index, the cap and the dropped count. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "rsm/config.h"
#include "paper/match.h"
#include "rsm/status.h"
#include "unity.h"

#define CAP 64

static rsm_match_t out[RSM_MAX_MATCHES + CAP];
static rsm_point_t ref[RSM_MAX_MATCHES + 8];
static rsm_point_t cur[RSM_MAX_MATCHES + 8];

void setUp(void)
{
    memset(out, 0xEE, sizeof out);
}

void tearDown(void)
{
}

static rsm_point_t pt(float x, float y)
{
    rsm_point_t p;
    p.x = x;
    p.y = y;
    return p;
}

static void assert_match(uint16_t r, uint16_t c, const rsm_match_t *m)
{
    TEST_ASSERT_EQUAL_UINT16(r, m->ref);
    TEST_ASSERT_EQUAL_UINT16(c, m->cur);
}

void test_match_tentative_should_pair_within_max_nn_only(void)
{
    size_t dropped = 99;
    ref[0] = pt(0.0f, 0.0f);
    cur[0] = pt(0.3f, 0.0f);
    TEST_ASSERT_EQUAL_INT(0, rsm_match_tentative(ref, 1, cur, 1, 0.2f, 0.0f, out, CAP, &dropped));
    TEST_ASSERT_EQUAL_size_t(0, dropped);
    TEST_ASSERT_EQUAL_INT(0, rsm_match_tentative(ref, 1, cur, 1, 0.29f, 0.0f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(1, rsm_match_tentative(ref, 1, cur, 1, 0.31f, 0.0f, out, CAP, NULL));
    assert_match(0, 0, &out[0]);
    /* Distance counts in both axes (Euclidean, not per axis). */
    cur[0] = pt(0.2f, 0.2f); /* 0.283 away */
    TEST_ASSERT_EQUAL_INT(0, rsm_match_tentative(ref, 1, cur, 1, 0.25f, 0.0f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(1, rsm_match_tentative(ref, 1, cur, 1, 0.29f, 0.0f, out, CAP, NULL));
}

void test_match_tentative_should_take_the_nearest_current_point(void)
{
    ref[0] = pt(1.0f, -1.0f);
    cur[0] = pt(1.15f, -1.0f);
    cur[1] = pt(1.0f, -0.95f); /* nearest */
    cur[2] = pt(0.9f, -1.1f);
    TEST_ASSERT_EQUAL_INT(1, rsm_match_tentative(ref, 1, cur, 3, 0.5f, 0.0f, out, CAP, NULL));
    assert_match(0, 1, &out[0]);
}

void test_match_tentative_should_break_distance_ties_by_lower_index(void)
{
    ref[0] = pt(0.0f, 0.0f);
    cur[0] = pt(0.5f, 0.0f); /* too far */
    cur[1] = pt(0.1f, 0.0f);
    cur[2] = pt(-0.1f, 0.0f); /* same distance as cur[1] */
    TEST_ASSERT_EQUAL_INT(1, rsm_match_tentative(ref, 1, cur, 3, 0.2f, 0.0f, out, CAP, NULL));
    assert_match(0, 1, &out[0]);
}

void test_match_tentative_should_add_every_current_point_in_the_box_around_the_nearest(void)
{
    /* The box is +-w around the nearest current point, in both axes. */
    ref[0] = pt(0.0f, 0.0f);
    cur[0] = pt(0.20f, 0.0f);   /* 0.15 from the nearest in x: outside */
    cur[1] = pt(0.05f, 0.0f);   /* nearest */
    cur[2] = pt(0.09f, 0.04f);  /* box corner region: inside */
    cur[3] = pt(0.05f, 0.095f); /* 0.095 in y: outside */
    cur[4] = pt(0.06f, -0.045f); /* inside */
    cur[5] = pt(0.1f, 0.1f);    /* outside in y */
    TEST_ASSERT_EQUAL_INT(3, rsm_match_tentative(ref, 1, cur, 6, 0.1f, 0.05f, out, CAP, NULL));
    assert_match(0, 1, &out[0]);
    assert_match(0, 2, &out[1]);
    assert_match(0, 4, &out[2]);
    /* w = 0 leaves only the nearest. */
    TEST_ASSERT_EQUAL_INT(1, rsm_match_tentative(ref, 1, cur, 6, 0.1f, 0.0f, out, CAP, NULL));
    assert_match(0, 1, &out[0]);
}

void test_match_tentative_should_include_box_points_beyond_max_nn(void)
{
    /* Only the nearest neighbour is gated by max_nn; the box around it may
     * reach farther (the wrong ones are RANSAC's job). */
    ref[0] = pt(0.0f, 0.0f);
    cur[0] = pt(0.09f, 0.0f); /* nearest, within 0.1 */
    cur[1] = pt(0.13f, 0.0f); /* 0.13 from ref, but within w of cur[0] */
    TEST_ASSERT_EQUAL_INT(2, rsm_match_tentative(ref, 1, cur, 2, 0.1f, 0.05f, out, CAP, NULL));
    assert_match(0, 0, &out[0]);
    assert_match(0, 1, &out[1]);
}

void test_match_tentative_should_group_matches_by_reference_index(void)
{
    /* Three reference points, each with a cluster of current points. */
    ref[0] = pt(0.0f, 0.0f);
    ref[1] = pt(1.0f, 0.0f);
    ref[2] = pt(0.0f, 1.0f);
    ref[3] = pt(5.0f, 5.0f); /* nothing near: no match */
    cur[0] = pt(0.0f, 1.01f);
    cur[1] = pt(1.02f, 0.0f);
    cur[2] = pt(0.01f, 0.0f);
    cur[3] = pt(0.03f, 0.02f);
    cur[4] = pt(1.0f, 0.03f);
    cur[5] = pt(-0.02f, 1.03f);
    TEST_ASSERT_EQUAL_INT(6, rsm_match_tentative(ref, 4, cur, 6, 0.2f, 0.05f, out, CAP, NULL));
    assert_match(0, 2, &out[0]);
    assert_match(0, 3, &out[1]);
    assert_match(1, 1, &out[2]);
    assert_match(1, 4, &out[3]);
    assert_match(2, 0, &out[4]);
    assert_match(2, 5, &out[5]);
}

void test_match_tentative_should_let_one_current_point_serve_several_references(void)
{
    ref[0] = pt(0.0f, 0.0f);
    ref[1] = pt(0.1f, 0.0f);
    cur[0] = pt(0.05f, 0.0f);
    TEST_ASSERT_EQUAL_INT(2, rsm_match_tentative(ref, 2, cur, 1, 0.2f, 0.0f, out, CAP, NULL));
    assert_match(0, 0, &out[0]);
    assert_match(1, 0, &out[1]);
}

void test_match_tentative_should_cap_and_count_dropped_matches(void)
{
    size_t dropped = 0;
    size_t k;
    /* Three references, three current points each inside every box: 9. */
    ref[0] = pt(0.0f, 0.0f);
    ref[1] = pt(0.02f, 0.0f);
    ref[2] = pt(0.04f, 0.0f);
    cur[0] = pt(0.0f, 0.01f);
    cur[1] = pt(0.02f, 0.01f);
    cur[2] = pt(0.04f, 0.01f);
    TEST_ASSERT_EQUAL_INT(9, rsm_match_tentative(ref, 3, cur, 3, 0.1f, 0.05f, out, CAP, &dropped));
    TEST_ASSERT_EQUAL_size_t(0, dropped);
    memset(out, 0xEE, sizeof out);
    TEST_ASSERT_EQUAL_INT(5, rsm_match_tentative(ref, 3, cur, 3, 0.1f, 0.05f, out, 5, &dropped));
    TEST_ASSERT_EQUAL_size_t(4, dropped);
    for (k = 0; k < 5; ++k) {
        assert_match((uint16_t)(k / 3u), (uint16_t)(k % 3u), &out[k]);
    }
    TEST_ASSERT_EQUAL_HEX16(0xEEEE, out[5].ref); /* nothing written past cap */
    /* Cap 0: no output buffer needed, everything counted. */
    TEST_ASSERT_EQUAL_INT(0, rsm_match_tentative(ref, 3, cur, 3, 0.1f, 0.05f, NULL, 0, &dropped));
    TEST_ASSERT_EQUAL_size_t(9, dropped);
}

void test_match_tentative_should_drop_beyond_rsm_max_matches(void)
{
    /* RSM_MAX_MATCHES + 4 references in a row, each with its own current
     * point: an output of RSM_MAX_MATCHES (what the localizer passes) keeps
     * the first RSM_MAX_MATCHES references and drops 4. */
    const size_t n = (size_t)RSM_MAX_MATCHES + 4u;
    size_t dropped = 0;
    size_t k;
    for (k = 0; k < n; ++k) {
        ref[k] = pt(0.5f * (float)k, 0.0f);
        cur[k] = pt(0.5f * (float)k + 0.01f, 0.01f);
    }
    TEST_ASSERT_EQUAL_INT(RSM_MAX_MATCHES,
                          rsm_match_tentative(ref, n, cur, n, 0.1f, 0.05f, out, (size_t)RSM_MAX_MATCHES, &dropped));
    TEST_ASSERT_EQUAL_size_t(4, dropped);
    for (k = 0; k < (size_t)RSM_MAX_MATCHES; ++k) {
        assert_match((uint16_t)k, (uint16_t)k, &out[k]);
    }
}

void test_match_tentative_should_return_zero_for_empty_sets(void)
{
    size_t dropped = 5;
    ref[0] = pt(0.0f, 0.0f);
    cur[0] = pt(0.0f, 0.0f);
    TEST_ASSERT_EQUAL_INT(0, rsm_match_tentative(ref, 0, cur, 1, 0.1f, 0.05f, out, CAP, &dropped));
    TEST_ASSERT_EQUAL_size_t(0, dropped);
    TEST_ASSERT_EQUAL_INT(0, rsm_match_tentative(ref, 1, cur, 0, 0.1f, 0.05f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(0, rsm_match_tentative(NULL, 0, NULL, 0, 0.1f, 0.05f, NULL, 0, NULL));
}

void test_match_tentative_should_reject_invalid_arguments(void)
{
    ref[0] = pt(0.0f, 0.0f);
    cur[0] = pt(0.0f, 0.0f);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_match_tentative(NULL, 1, cur, 1, 0.1f, 0.05f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_match_tentative(ref, 1, NULL, 1, 0.1f, 0.05f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_match_tentative(ref, 1, cur, 1, 0.1f, 0.05f, NULL, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_match_tentative(ref, 65536u, cur, 1, 0.1f, 0.05f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_match_tentative(ref, 1, cur, 65536u, 0.1f, 0.05f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_match_tentative(ref, 1, cur, 1, -0.1f, 0.05f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_match_tentative(ref, 1, cur, 1, 0.1f, -0.05f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_match_tentative(ref, 1, cur, 1, NAN, 0.05f, out, CAP, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_match_tentative(ref, 1, cur, 1, 0.1f, NAN, out, CAP, NULL));
    TEST_ASSERT_EQUAL_HEX16(0xEEEE, out[0].ref); /* output untouched */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_match_tentative_should_pair_within_max_nn_only);
    RUN_TEST(test_match_tentative_should_take_the_nearest_current_point);
    RUN_TEST(test_match_tentative_should_break_distance_ties_by_lower_index);
    RUN_TEST(test_match_tentative_should_add_every_current_point_in_the_box_around_the_nearest);
    RUN_TEST(test_match_tentative_should_include_box_points_beyond_max_nn);
    RUN_TEST(test_match_tentative_should_group_matches_by_reference_index);
    RUN_TEST(test_match_tentative_should_let_one_current_point_serve_several_references);
    RUN_TEST(test_match_tentative_should_cap_and_count_dropped_matches);
    RUN_TEST(test_match_tentative_should_drop_beyond_rsm_max_matches);
    RUN_TEST(test_match_tentative_should_return_zero_for_empty_sets);
    RUN_TEST(test_match_tentative_should_reject_invalid_arguments);
    return UNITY_END();
}
