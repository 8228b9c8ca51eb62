/*
 * Self-test of the Unity-compatible core: a run in which every test passes
 * must print only PASS lines, end with "OK" and exit with status 0.
 * Marker comments are explained in selftest_cases.c.
 */
#include "unity.h"

static int fixture;
static int setup_calls;
static int teardown_calls;

void setUp(void)
{
    setup_calls++;
    fixture = 42;
}

void tearDown(void)
{
    teardown_calls++;
    fixture = 0;
}

void test_fixture_is_prepared(void)
{
    TEST_ASSERT_EQUAL_INT(42, fixture);
    fixture = 7; /* tearDown resets it before the next test */
}

void test_fixture_is_prepared_again(void)
{
    TEST_ASSERT_EQUAL_INT(42, fixture);
}

void test_setup_and_teardown_pair_up(void)
{
    TEST_ASSERT_EQUAL_INT(3, setup_calls);
    TEST_ASSERT_EQUAL_INT(2, teardown_calls);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_fixture_is_prepared); /* expect: PASS */
    RUN_TEST(test_fixture_is_prepared_again); /* expect: PASS */
    RUN_TEST(test_setup_and_teardown_pair_up); /* expect: PASS */
    /* expect-summary: 3 Tests 0 Failures 0 Ignored */
    return UNITY_END();
}
