/*
 * Self-test of the Unity-compatible core: passing, failing and ignored
 * tests whose exact output is checked by check_output.py.
 *
 * Every line the run must print is written next to the statement that
 * prints it, as a marker comment:
 *
 *   expect: TEXT           the result line for this test is
 *                          "<file>:<this line>:<test>:TEXT"; on a RUN_TEST
 *                          line it is the PASS line (at the RUN_TEST line,
 *                          or at the line given as RUN_TEST's 2nd argument)
 *   expect[NAME]: TEXT     the same, for test NAME (used in setUp/tearDown)
 *   expect-re...: REGEX    TEXT is a Python regular expression
 *   expect-summary: ...    the "N Tests F Failures I Ignored" line
 *
 * The markers sit in C comments, so the file compiles unchanged against
 * the bundled core and against an upstream Unity installation.
 */
#include "unity.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

static int setup_calls;
static int teardown_calls;
static int ran_after_failure;
static int ran_after_ignore;
static int ran_after_pass;
static int fail_in_teardown;

void setUp(void)
{
    setup_calls++;
}

void tearDown(void)
{
    teardown_calls++;
    if (fail_in_teardown)
    {
        fail_in_teardown = 0;
        TEST_FAIL_MESSAGE("teardown failed"); /* expect[test_teardown_failure_is_reported]: FAIL: teardown failed */
    }
}

/* ------------------------------------------------------------------ */
/* Everything in these two tests passes.                               */
/* ------------------------------------------------------------------ */

void test_integer_assertions_pass(void)
{
    int i = -3;
    unsigned int u = 7u;
    int8_t i8 = -100;
    int16_t i16 = -30000;
    int32_t i32 = -2000000000;
    int64_t i64 = -5000000000LL;
    uint8_t u8 = 200u;
    uint16_t u16 = 60000u;
    uint32_t u32 = 4000000000u;
    uint64_t u64 = 10000000000ULL;
    size_t sz = 12u;

    TEST_ASSERT(i < 0);
    TEST_ASSERT_MESSAGE(i < 0, "msg");
    TEST_ASSERT_TRUE(u == 7u);
    TEST_ASSERT_TRUE_MESSAGE(u == 7u, "msg");
    TEST_ASSERT_FALSE(u == 8u);
    TEST_ASSERT_FALSE_MESSAGE(u == 8u, "msg");
    TEST_ASSERT_UNLESS(u == 8u);
    TEST_ASSERT_UNLESS_MESSAGE(u == 8u, "msg");

    TEST_ASSERT_EQUAL(-3, i);
    TEST_ASSERT_EQUAL_MESSAGE(-3, i, "msg");
    TEST_ASSERT_NOT_EQUAL(3, i);
    TEST_ASSERT_NOT_EQUAL_MESSAGE(3, i, "msg");
    TEST_ASSERT_EQUAL_INT(-3, i);
    TEST_ASSERT_EQUAL_INT_MESSAGE(-3, i, "msg");
    TEST_ASSERT_EQUAL_INT8(-100, i8);
    TEST_ASSERT_EQUAL_INT8_MESSAGE(-100, i8, "msg");
    TEST_ASSERT_EQUAL_INT8(-1, 255); /* both narrowed to int8_t */
    TEST_ASSERT_EQUAL_INT16(-30000, i16);
    TEST_ASSERT_EQUAL_INT16_MESSAGE(-30000, i16, "msg");
    TEST_ASSERT_EQUAL_INT32(-2000000000, i32);
    TEST_ASSERT_EQUAL_INT32_MESSAGE(-2000000000, i32, "msg");
    TEST_ASSERT_EQUAL_INT64(-5000000000LL, i64);
    TEST_ASSERT_EQUAL_INT64_MESSAGE(-5000000000LL, i64, "msg");
    TEST_ASSERT_EQUAL_UINT(7u, u);
    TEST_ASSERT_EQUAL_UINT_MESSAGE(7u, u, "msg");
    TEST_ASSERT_EQUAL_UINT8(200u, u8);
    TEST_ASSERT_EQUAL_UINT8_MESSAGE(200u, u8, "msg");
    TEST_ASSERT_EQUAL_UINT8(0x1C8u, u8); /* both narrowed to uint8_t */
    TEST_ASSERT_EQUAL_UINT16(60000u, u16);
    TEST_ASSERT_EQUAL_UINT16_MESSAGE(60000u, u16, "msg");
    TEST_ASSERT_EQUAL_UINT32(4000000000u, u32);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(4000000000u, u32, "msg");
    TEST_ASSERT_EQUAL_UINT64(10000000000ULL, u64);
    TEST_ASSERT_EQUAL_UINT64_MESSAGE(10000000000ULL, u64, "msg");
    TEST_ASSERT_EQUAL_size_t(12u, sz);
    TEST_ASSERT_EQUAL_size_t_MESSAGE(12u, sz, "msg");
    TEST_ASSERT_EQUAL_HEX8(0xC8u, u8);
    TEST_ASSERT_EQUAL_HEX8_MESSAGE(0xC8u, u8, "msg");
    TEST_ASSERT_EQUAL_HEX16(0xEA60u, u16);
    TEST_ASSERT_EQUAL_HEX16_MESSAGE(0xEA60u, u16, "msg");
    TEST_ASSERT_EQUAL_HEX32(0xEE6B2800u, u32);
    TEST_ASSERT_EQUAL_HEX32_MESSAGE(0xEE6B2800u, u32, "msg");
    TEST_ASSERT_EQUAL_HEX(0xEE6B2800u, u32);

    TEST_ASSERT_GREATER_THAN(-4, i);
    TEST_ASSERT_GREATER_THAN_MESSAGE(-4, i, "msg");
    TEST_ASSERT_GREATER_THAN_INT(-4, i);
    TEST_ASSERT_GREATER_THAN_INT_MESSAGE(-4, i, "msg");
    TEST_ASSERT_GREATER_THAN_INT32(-2000000001, i32);
    TEST_ASSERT_GREATER_THAN_INT32_MESSAGE(-2000000001, i32, "msg");
    TEST_ASSERT_GREATER_THAN_UINT(6u, u);
    TEST_ASSERT_GREATER_THAN_UINT_MESSAGE(6u, u, "msg");
    TEST_ASSERT_GREATER_THAN_UINT32(3999999999u, u32);
    TEST_ASSERT_GREATER_THAN_UINT32_MESSAGE(3999999999u, u32, "msg");
    TEST_ASSERT_GREATER_THAN_size_t(11u, sz);
    TEST_ASSERT_GREATER_THAN_size_t_MESSAGE(11u, sz, "msg");
    TEST_ASSERT_GREATER_THAN_UINT64(1u, UINT64_MAX); /* unsigned, not -1 */

    TEST_ASSERT_LESS_THAN(-2, i);
    TEST_ASSERT_LESS_THAN_MESSAGE(-2, i, "msg");
    TEST_ASSERT_LESS_THAN_INT(-2, i);
    TEST_ASSERT_LESS_THAN_INT_MESSAGE(-2, i, "msg");
    TEST_ASSERT_LESS_THAN_INT32(0, i32);
    TEST_ASSERT_LESS_THAN_INT32_MESSAGE(0, i32, "msg");
    TEST_ASSERT_LESS_THAN_UINT(8u, u);
    TEST_ASSERT_LESS_THAN_UINT_MESSAGE(8u, u, "msg");
    TEST_ASSERT_LESS_THAN_UINT32(4000000001u, u32);
    TEST_ASSERT_LESS_THAN_UINT32_MESSAGE(4000000001u, u32, "msg");
    TEST_ASSERT_LESS_THAN_size_t(13u, sz);
    TEST_ASSERT_LESS_THAN_size_t_MESSAGE(13u, sz, "msg");
    TEST_ASSERT_LESS_THAN_UINT64(UINT64_MAX, 1u);

    TEST_ASSERT_GREATER_OR_EQUAL(-3, i);
    TEST_ASSERT_GREATER_OR_EQUAL_MESSAGE(-3, i, "msg");
    TEST_ASSERT_GREATER_OR_EQUAL_INT(-4, i);
    TEST_ASSERT_GREATER_OR_EQUAL_INT_MESSAGE(-3, i, "msg");
    TEST_ASSERT_GREATER_OR_EQUAL_INT32(-2000000000, i32);
    TEST_ASSERT_GREATER_OR_EQUAL_INT32_MESSAGE(-2000000000, i32, "msg");
    TEST_ASSERT_GREATER_OR_EQUAL_UINT(7u, u);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT_MESSAGE(6u, u, "msg");
    TEST_ASSERT_GREATER_OR_EQUAL_UINT32(4000000000u, u32);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT32_MESSAGE(4000000000u, u32, "msg");
    TEST_ASSERT_GREATER_OR_EQUAL_size_t(12u, sz);
    TEST_ASSERT_GREATER_OR_EQUAL_size_t_MESSAGE(12u, sz, "msg");

    TEST_ASSERT_LESS_OR_EQUAL(-3, i);
    TEST_ASSERT_LESS_OR_EQUAL_MESSAGE(-2, i, "msg");
    TEST_ASSERT_LESS_OR_EQUAL_INT(-3, i);
    TEST_ASSERT_LESS_OR_EQUAL_INT_MESSAGE(-3, i, "msg");
    TEST_ASSERT_LESS_OR_EQUAL_INT32(-2000000000, i32);
    TEST_ASSERT_LESS_OR_EQUAL_INT32_MESSAGE(-1, i32, "msg");
    TEST_ASSERT_LESS_OR_EQUAL_UINT(7u, u);
    TEST_ASSERT_LESS_OR_EQUAL_UINT_MESSAGE(8u, u, "msg");
    TEST_ASSERT_LESS_OR_EQUAL_UINT32(4000000000u, u32);
    TEST_ASSERT_LESS_OR_EQUAL_UINT32_MESSAGE(4000000000u, u32, "msg");
    TEST_ASSERT_LESS_OR_EQUAL_size_t(12u, sz);
    TEST_ASSERT_LESS_OR_EQUAL_size_t_MESSAGE(12u, sz, "msg");

    TEST_ASSERT_INT_WITHIN(2, -5, i);
    TEST_ASSERT_INT_WITHIN_MESSAGE(2, -1, i, "msg");
    TEST_ASSERT_INT32_WITHIN(10, -2000000005, i32);
    TEST_ASSERT_INT32_WITHIN_MESSAGE(10, -1999999995, i32, "msg");
    TEST_ASSERT_UINT_WITHIN(1u, 8u, u);
    TEST_ASSERT_UINT_WITHIN_MESSAGE(1u, 6u, u, "msg");
    TEST_ASSERT_UINT32_WITHIN(5u, 3999999995u, u32);
    TEST_ASSERT_UINT32_WITHIN_MESSAGE(5u, 4000000005u, u32, "msg");
}

void test_other_assertions_pass(void)
{
    int x = 5;
    int y = 5;
    const int *nothing = NULL;
    const char *text = "scan";
    const int ints[3] = {1, -2, 3};
    const int ints_copy[3] = {1, -2, 3};
    const int32_t i32s[2] = {-7, 2000000000};
    const int32_t i32s_copy[2] = {-7, 2000000000};
    const uint8_t u8s[3] = {0u, 128u, 255u};
    const uint8_t u8s_copy[3] = {0u, 128u, 255u};
    const uint16_t u16s[2] = {1u, 65535u};
    const uint16_t u16s_copy[2] = {1u, 65535u};
    const uint32_t u32s[2] = {0u, 4000000000u};
    const uint32_t u32s_copy[2] = {0u, 4000000000u};
    const float floats[3] = {0.5f, -1.25f, 1000.0f};
    const float floats_close[3] = {0.5f, -1.2500001f, 1000.001f};
    const unsigned char bytes[4] = {1u, 2u, 3u, 4u};
    const unsigned char bytes_copy[4] = {1u, 2u, 3u, 4u};

    TEST_ASSERT_NULL(nothing);
    TEST_ASSERT_NULL_MESSAGE(nothing, "msg");
    TEST_ASSERT_NOT_NULL(text);
    TEST_ASSERT_NOT_NULL_MESSAGE(text, "msg");
    TEST_ASSERT_EQUAL_PTR(&x, &x);
    TEST_ASSERT_EQUAL_PTR_MESSAGE(&y, &y, "msg");
    TEST_ASSERT_EQUAL_PTR(NULL, nothing);

    TEST_ASSERT_EQUAL_STRING("scan", text);
    TEST_ASSERT_EQUAL_STRING_MESSAGE("scan", text, "msg");
    TEST_ASSERT_EQUAL_STRING(NULL, NULL);
    TEST_ASSERT_EQUAL_STRING_LEN("scanner", text, 4);
    TEST_ASSERT_EQUAL_STRING_LEN_MESSAGE("scanner", text, 4, "msg");
    TEST_ASSERT_EQUAL_MEMORY(bytes, bytes_copy, sizeof bytes);
    TEST_ASSERT_EQUAL_MEMORY_MESSAGE(bytes, bytes_copy, sizeof bytes, "msg");

    TEST_ASSERT_EQUAL_INT_ARRAY(ints, ints_copy, 3);
    TEST_ASSERT_EQUAL_INT_ARRAY_MESSAGE(ints, ints_copy, 3, "msg");
    TEST_ASSERT_EQUAL_INT_ARRAY(ints, ints, 3);
    TEST_ASSERT_EQUAL_INT32_ARRAY(i32s, i32s_copy, 2);
    TEST_ASSERT_EQUAL_INT32_ARRAY_MESSAGE(i32s, i32s_copy, 2, "msg");
    TEST_ASSERT_EQUAL_UINT8_ARRAY(u8s, u8s_copy, 3);
    TEST_ASSERT_EQUAL_UINT8_ARRAY_MESSAGE(u8s, u8s_copy, 3, "msg");
    TEST_ASSERT_EQUAL_UINT16_ARRAY(u16s, u16s_copy, 2);
    TEST_ASSERT_EQUAL_UINT16_ARRAY_MESSAGE(u16s, u16s_copy, 2, "msg");
    TEST_ASSERT_EQUAL_UINT32_ARRAY(u32s, u32s_copy, 2);
    TEST_ASSERT_EQUAL_UINT32_ARRAY_MESSAGE(u32s, u32s_copy, 2, "msg");
    TEST_ASSERT_EQUAL_HEX8_ARRAY(u8s, u8s_copy, 3);
    TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(u8s, u8s_copy, 3, "msg");
    TEST_ASSERT_EQUAL_FLOAT_ARRAY(floats, floats_close, 3);
    TEST_ASSERT_EQUAL_FLOAT_ARRAY_MESSAGE(floats, floats_close, 3, "msg");

    TEST_ASSERT_FLOAT_WITHIN(0.25f, 1.0f, 1.125f);
    TEST_ASSERT_FLOAT_WITHIN_MESSAGE(0.25f, 1.0f, 0.875f, "msg");
    TEST_ASSERT_FLOAT_WITHIN(-0.25f, 1.0f, 1.125f); /* the sign of delta is ignored */
    TEST_ASSERT_EQUAL_FLOAT(1000.0f, 1000.001f);
    TEST_ASSERT_EQUAL_FLOAT_MESSAGE(-0.5f, -0.5f, "msg");
    TEST_ASSERT_EQUAL_FLOAT(INFINITY, INFINITY);
    TEST_ASSERT_EQUAL_FLOAT(NAN, NAN);
    TEST_ASSERT_GREATER_THAN_FLOAT(1.0f, 1.5f);
    TEST_ASSERT_GREATER_THAN_FLOAT_MESSAGE(-1.0f, 0.0f, "msg");
    TEST_ASSERT_LESS_THAN_FLOAT(1.0f, 0.5f);
    TEST_ASSERT_LESS_THAN_FLOAT_MESSAGE(0.0f, -0.25f, "msg");
    TEST_ASSERT_FLOAT_IS_NAN(NAN);
    TEST_ASSERT_FLOAT_IS_NAN_MESSAGE(NAN, "msg");
    TEST_ASSERT_FLOAT_IS_NOT_NAN(1.0f);
    TEST_ASSERT_FLOAT_IS_NOT_NAN_MESSAGE(INFINITY, "msg");
    TEST_ASSERT_FLOAT_IS_INF(INFINITY);
    TEST_ASSERT_FLOAT_IS_INF_MESSAGE(INFINITY, "msg");
    TEST_ASSERT_FLOAT_IS_NOT_INF(1.0f);
    TEST_ASSERT_FLOAT_IS_NOT_INF_MESSAGE(-INFINITY, "msg");
}

/* ------------------------------------------------------------------ */
/* Control flow                                                        */
/* ------------------------------------------------------------------ */

void test_failure_stops_the_test(void)
{
    TEST_ASSERT_EQUAL_INT(3, 4); /* expect: FAIL: Expected 3 Was 4 */
    ran_after_failure = 1;
}

void test_previous_test_was_cut_short(void)
{
    TEST_ASSERT_EQUAL_INT(0, ran_after_failure);
    /* setUp ran for this test, tearDown not yet; every earlier test got both. */
    TEST_ASSERT_EQUAL_INT(setup_calls - 1, teardown_calls);
}

void test_ignore_stops_the_test(void)
{
    TEST_IGNORE(); /* expect: IGNORE */
    ran_after_ignore = 1;
}

void test_ignore_with_message(void)
{
    TEST_IGNORE_MESSAGE("not ready"); /* expect: IGNORE: not ready */
}

void test_pass_stops_the_test(void)
{
    TEST_PASS();
    ran_after_pass = 1;
    TEST_FAIL_MESSAGE("not reached");
}

void test_pass_with_message(void)
{
    TEST_PASS_MESSAGE("done early"); /* expect: INFO: done early */
}

void test_earlier_stops_left_no_trace(void)
{
    TEST_ASSERT_EQUAL_INT(0, ran_after_ignore);
    TEST_ASSERT_EQUAL_INT(0, ran_after_pass);
}

void test_message_then_pass(void)
{
    TEST_MESSAGE("hello"); /* expect: INFO: hello */
}

void test_message_then_fail(void)
{
    TEST_MESSAGE("about to fail"); /* expect: INFO: about to fail */
    TEST_FAIL(); /* expect: FAIL */
}

void test_teardown_failure_is_reported(void)
{
    fail_in_teardown = 1;
}

void test_teardown_failure_after_failure_is_silent(void)
{
    fail_in_teardown = 1;
    TEST_FAIL_MESSAGE("body failed"); /* expect: FAIL: body failed */
}

void test_explicit_run_line(void)
{
    TEST_ASSERT_EQUAL_INT(0, fail_in_teardown);
}

/* ------------------------------------------------------------------ */
/* Failure messages                                                    */
/* ------------------------------------------------------------------ */

void test_fail_message(void)
{
    TEST_FAIL_MESSAGE("boom"); /* expect: FAIL: boom */
}

void test_fail_message_leading_space(void)
{
    TEST_FAIL_MESSAGE(" spaced"); /* expect: FAIL: spaced */
}

void test_assert_fails(void)
{
    TEST_ASSERT(1 == 2); /* expect: FAIL: Expression Evaluated To FALSE */
}

void test_assert_true_fails(void)
{
    TEST_ASSERT_TRUE(0); /* expect: FAIL: Expected TRUE Was FALSE */
}

void test_assert_false_fails(void)
{
    TEST_ASSERT_FALSE(1); /* expect: FAIL: Expected FALSE Was TRUE */
}

void test_assert_true_message_fails(void)
{
    TEST_ASSERT_TRUE_MESSAGE(0, "ctx"); /* expect: FAIL: ctx */
}

void test_assert_null_fails(void)
{
    int x = 0;
    TEST_ASSERT_NULL(&x); /* expect: FAIL: Expected NULL */
}

void test_assert_not_null_fails(void)
{
    TEST_ASSERT_NOT_NULL(NULL); /* expect: FAIL: Expected Non-NULL */
}

void test_not_equal_fails(void)
{
    TEST_ASSERT_NOT_EQUAL(5, 5); /* expect: FAIL: Expected Not-Equal */
}

void test_equal_fails(void)
{
    TEST_ASSERT_EQUAL(-1, 1); /* expect: FAIL: Expected -1 Was 1 */
}

void test_equal_int_message_fails(void)
{
    TEST_ASSERT_EQUAL_INT_MESSAGE(3, 4, "ctx"); /* expect: FAIL: Expected 3 Was 4. ctx */
}

void test_equal_int8_fails(void)
{
    TEST_ASSERT_EQUAL_INT8(-1, 1); /* expect: FAIL: Expected -1 Was 1 */
}

void test_equal_uint16_fails(void)
{
    TEST_ASSERT_EQUAL_UINT16(1u, 0x10002u); /* expect: FAIL: Expected 1 Was 2 */
}

void test_equal_uint32_fails(void)
{
    TEST_ASSERT_EQUAL_UINT32(4000000000u, 1u); /* expect: FAIL: Expected 4000000000 Was 1 */
}

void test_equal_int64_fails(void)
{
    TEST_ASSERT_EQUAL_INT64(-5000000000LL, 5000000000LL); /* expect: FAIL: Expected -5000000000 Was 5000000000 */
}

void test_equal_uint64_fails(void)
{
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, 0u); /* expect: FAIL: Expected 18446744073709551615 Was 0 */
}

void test_equal_size_t_fails(void)
{
    size_t n = 4u;
    TEST_ASSERT_EQUAL_size_t(3u, n); /* expect: FAIL: Expected 3 Was 4 */
}

void test_equal_hex8_fails(void)
{
    TEST_ASSERT_EQUAL_HEX8(0x0Au, 0xFBu); /* expect: FAIL: Expected 0x0A Was 0xFB */
}

void test_equal_hex16_fails(void)
{
    TEST_ASSERT_EQUAL_HEX16(0x1234u, 0xABCDu); /* expect: FAIL: Expected 0x1234 Was 0xABCD */
}

void test_equal_hex32_fails(void)
{
    TEST_ASSERT_EQUAL_HEX32(0xDEADBEEFu, 1u); /* expect: FAIL: Expected 0xDEADBEEF Was 0x00000001 */
}

void test_equal_ptr_fails(void)
{
    TEST_ASSERT_EQUAL_PTR((void *)(uintptr_t)0x1000u, (void *)(uintptr_t)0x2000u); /* expect-re: FAIL: Expected 0x0*1000 Was 0x0*2000 */
}

void test_greater_than_fails(void)
{
    TEST_ASSERT_GREATER_THAN(5, 3); /* expect: FAIL: Expected 3 to be greater than 5 */
}

void test_less_than_fails(void)
{
    TEST_ASSERT_LESS_THAN(5, 7); /* expect: FAIL: Expected 7 to be less than 5 */
}

void test_greater_or_equal_fails(void)
{
    TEST_ASSERT_GREATER_OR_EQUAL(5, 4); /* expect: FAIL: Expected 4 to be greater than or equal to 5 */
}

void test_less_or_equal_fails(void)
{
    TEST_ASSERT_LESS_OR_EQUAL(5, 6); /* expect: FAIL: Expected 6 to be less than or equal to 5 */
}

void test_less_than_int32_is_signed(void)
{
    TEST_ASSERT_LESS_THAN_INT32(-1, 0); /* expect: FAIL: Expected 0 to be less than -1 */
}

void test_greater_than_uint32_is_unsigned(void)
{
    TEST_ASSERT_GREATER_THAN_UINT32(4000000000u, 1u); /* expect: FAIL: Expected 1 to be greater than 4000000000 */
}

void test_less_than_uint64_is_unsigned(void)
{
    TEST_ASSERT_LESS_THAN_UINT64(1u, UINT64_MAX); /* expect: FAIL: Expected 18446744073709551615 to be less than 1 */
}

void test_uint64_within_is_unsigned(void)
{
    TEST_ASSERT_UINT64_WITHIN(1u, 0u, UINT64_MAX); /* expect: FAIL: Values Not Within Delta 1 Expected 0 Was 18446744073709551615 */
}

void test_greater_or_equal_size_t_fails(void)
{
    size_t n = 4u;
    TEST_ASSERT_GREATER_OR_EQUAL_size_t(5u, n); /* expect: FAIL: Expected 4 to be greater than or equal to 5 */
}

void test_less_or_equal_uint_message_fails(void)
{
    TEST_ASSERT_LESS_OR_EQUAL_UINT_MESSAGE(5u, 6u, "ctx"); /* expect: FAIL: Expected 6 to be less than or equal to 5. ctx */
}

void test_int_within_fails(void)
{
    TEST_ASSERT_INT_WITHIN(2, 10, 13); /* expect: FAIL: Values Not Within Delta 2 Expected 10 Was 13 */
}

void test_int32_within_fails(void)
{
    TEST_ASSERT_INT32_WITHIN(1, -5, 5); /* expect: FAIL: Values Not Within Delta 1 Expected -5 Was 5 */
}

void test_uint32_within_fails(void)
{
    TEST_ASSERT_UINT32_WITHIN(1u, 4000000000u, 3999999990u); /* expect: FAIL: Values Not Within Delta 1 Expected 4000000000 Was 3999999990 */
}

void test_int_array_fails(void)
{
    const int expected[3] = {1, 2, 3};
    const int actual[3] = {1, 2, 4};
    TEST_ASSERT_EQUAL_INT_ARRAY(expected, actual, 3); /* expect: FAIL: Element 2 Expected 3 Was 4 */
}

void test_int32_array_fails(void)
{
    const int32_t expected[1] = {-7};
    const int32_t actual[1] = {7};
    TEST_ASSERT_EQUAL_INT32_ARRAY_MESSAGE(expected, actual, 1, "ctx"); /* expect: FAIL: Element 0 Expected -7 Was 7. ctx */
}

void test_uint8_array_fails(void)
{
    const uint8_t expected[3] = {1u, 2u, 250u};
    const uint8_t actual[3] = {1u, 2u, 251u};
    TEST_ASSERT_EQUAL_UINT8_ARRAY(expected, actual, 3); /* expect: FAIL: Element 2 Expected 250 Was 251 */
}

void test_uint16_array_fails(void)
{
    const uint16_t expected[2] = {60000u, 1u};
    const uint16_t actual[2] = {60000u, 2u};
    TEST_ASSERT_EQUAL_UINT16_ARRAY(expected, actual, 2); /* expect: FAIL: Element 1 Expected 1 Was 2 */
}

void test_uint32_array_fails(void)
{
    const uint32_t expected[1] = {4000000000u};
    const uint32_t actual[1] = {1u};
    TEST_ASSERT_EQUAL_UINT32_ARRAY(expected, actual, 1); /* expect: FAIL: Element 0 Expected 4000000000 Was 1 */
}

void test_hex8_array_fails(void)
{
    const uint8_t expected[2] = {0x00u, 0xABu};
    const uint8_t actual[2] = {0x00u, 0xACu};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, actual, 2); /* expect: FAIL: Element 1 Expected 0xAB Was 0xAC */
}

void test_empty_array_fails(void)
{
    const int values[1] = {0};
    TEST_ASSERT_EQUAL_INT_ARRAY(values, values, 0); /* expect: FAIL: You Asked Me To Compare Nothing, Which Was Pointless. */
}

void test_null_array_fails(void)
{
    const int values[1] = {0};
    TEST_ASSERT_EQUAL_INT_ARRAY(values, NULL, 1); /* expect: FAIL: Actual pointer was NULL */
}

void test_float_array_fails(void)
{
    const float expected[2] = {1.0f, 2.0f};
    const float actual[2] = {1.0f, 2.5f};
    TEST_ASSERT_EQUAL_FLOAT_ARRAY(expected, actual, 2); /* expect: FAIL: Element 1 Expected 2 Was 2.5 */
}

void test_string_fails(void)
{
    TEST_ASSERT_EQUAL_STRING("abc", "abd"); /* expect: FAIL: Expected 'abc' Was 'abd' */
}

void test_string_null_fails(void)
{
    TEST_ASSERT_EQUAL_STRING("abc", NULL); /* expect: FAIL: Expected 'abc' Was NULL */
}

void test_string_escapes_control_characters(void)
{
    TEST_ASSERT_EQUAL_STRING_MESSAGE("a\nb", "a\tb", "ctx"); /* expect: FAIL: Expected 'a\nb' Was 'a\x09b'. ctx */
}

void test_string_len_fails(void)
{
    TEST_ASSERT_EQUAL_STRING_LEN("abcdef", "abcxyz", 4); /* expect: FAIL: Expected 'abcd' Was 'abcx' */
}

void test_memory_fails(void)
{
    const unsigned char expected[3] = {1u, 2u, 3u};
    const unsigned char actual[3] = {1u, 3u, 3u};
    TEST_ASSERT_EQUAL_MEMORY(expected, actual, 3); /* expect: FAIL: Memory Mismatch. Byte 1 Expected 0x02 Was 0x03 */
}

void test_float_within_fails(void)
{
    TEST_ASSERT_FLOAT_WITHIN(0.25f, 1.0f, 1.5f); /* expect: FAIL: Expected 1 Was 1.5 */
}

void test_float_within_message_fails(void)
{
    TEST_ASSERT_FLOAT_WITHIN_MESSAGE(0.5f, -2.0f, 2.0f, "ctx"); /* expect: FAIL: Expected -2 Was 2. ctx */
}

void test_equal_float_fails(void)
{
    TEST_ASSERT_EQUAL_FLOAT(2.5f, 2.25f); /* expect: FAIL: Expected 2.5 Was 2.25 */
}

void test_equal_float_zero_fails(void)
{
    TEST_ASSERT_EQUAL_FLOAT(-0.75f, 0.0f); /* expect: FAIL: Expected -0.75 Was 0 */
}

void test_float_large_values_print_with_exponent(void)
{
    TEST_ASSERT_FLOAT_WITHIN(1.0f, 16777216.0f, 33554432.0f); /* expect: FAIL: Expected 1.677722e+07 Was 3.355443e+07 */
}

void test_float_small_values_print(void)
{
    TEST_ASSERT_FLOAT_WITHIN(0.0f, 0.0009765625f, 0.5f); /* expect: FAIL: Expected 0.0009765625 Was 0.5 */
}

void test_float_tiny_values_print_with_exponent(void)
{
    TEST_ASSERT_FLOAT_WITHIN(0.0f, 9.5367431640625e-07f, 0.0f); /* expect: FAIL: Expected 9.536743e-07 Was 0 */
}

void test_greater_than_float_fails(void)
{
    TEST_ASSERT_GREATER_THAN_FLOAT(2.0f, 1.5f); /* expect: FAIL: Expected 1.5 to be greater than 2 */
}

void test_less_than_float_fails(void)
{
    TEST_ASSERT_LESS_THAN_FLOAT(2.0f, 3.0f); /* expect: FAIL: Expected 3 to be less than 2 */
}

void test_float_is_nan_fails(void)
{
    TEST_ASSERT_FLOAT_IS_NAN(1.0f); /* expect: FAIL: Expected NaN Was 1 */
}

void test_float_is_not_nan_fails(void)
{
    TEST_ASSERT_FLOAT_IS_NOT_NAN(NAN); /* expect: FAIL: Expected Not NaN Was nan */
}

void test_float_is_inf_fails(void)
{
    TEST_ASSERT_FLOAT_IS_INF(0.5f); /* expect: FAIL: Expected Infinity Was 0.5 */
}

void test_float_is_inf_means_positive(void)
{
    TEST_ASSERT_FLOAT_IS_INF(-INFINITY); /* expect: FAIL: Expected Infinity Was -inf */
}

void test_float_is_not_inf_fails(void)
{
    TEST_ASSERT_FLOAT_IS_NOT_INF_MESSAGE(INFINITY, "ctx"); /* expect: FAIL: Expected Not Infinity Was inf. ctx */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_integer_assertions_pass); /* expect: PASS */
    RUN_TEST(test_other_assertions_pass); /* expect: PASS */

    RUN_TEST(test_failure_stops_the_test);
    RUN_TEST(test_previous_test_was_cut_short); /* expect: PASS */
    RUN_TEST(test_ignore_stops_the_test);
    RUN_TEST(test_ignore_with_message);
    RUN_TEST(test_pass_stops_the_test); /* expect: PASS */
    RUN_TEST(test_pass_with_message); /* expect: PASS */
    RUN_TEST(test_earlier_stops_left_no_trace); /* expect: PASS */
    RUN_TEST(test_message_then_pass); /* expect: PASS */
    RUN_TEST(test_message_then_fail);
    RUN_TEST(test_teardown_failure_is_reported);
    RUN_TEST(test_teardown_failure_after_failure_is_silent);
    RUN_TEST(test_explicit_run_line, 4242); /* expect: PASS */

    RUN_TEST(test_fail_message);
    RUN_TEST(test_fail_message_leading_space);
    RUN_TEST(test_assert_fails);
    RUN_TEST(test_assert_true_fails);
    RUN_TEST(test_assert_false_fails);
    RUN_TEST(test_assert_true_message_fails);
    RUN_TEST(test_assert_null_fails);
    RUN_TEST(test_assert_not_null_fails);
    RUN_TEST(test_not_equal_fails);
    RUN_TEST(test_equal_fails);
    RUN_TEST(test_equal_int_message_fails);
    RUN_TEST(test_equal_int8_fails);
    RUN_TEST(test_equal_uint16_fails);
    RUN_TEST(test_equal_uint32_fails);
    RUN_TEST(test_equal_int64_fails);
    RUN_TEST(test_equal_uint64_fails);
    RUN_TEST(test_equal_size_t_fails);
    RUN_TEST(test_equal_hex8_fails);
    RUN_TEST(test_equal_hex16_fails);
    RUN_TEST(test_equal_hex32_fails);
    RUN_TEST(test_equal_ptr_fails);
    RUN_TEST(test_greater_than_fails);
    RUN_TEST(test_less_than_fails);
    RUN_TEST(test_greater_or_equal_fails);
    RUN_TEST(test_less_or_equal_fails);
    RUN_TEST(test_less_than_int32_is_signed);
    RUN_TEST(test_greater_than_uint32_is_unsigned);
    RUN_TEST(test_less_than_uint64_is_unsigned);
    RUN_TEST(test_uint64_within_is_unsigned);
    RUN_TEST(test_greater_or_equal_size_t_fails);
    RUN_TEST(test_less_or_equal_uint_message_fails);
    RUN_TEST(test_int_within_fails);
    RUN_TEST(test_int32_within_fails);
    RUN_TEST(test_uint32_within_fails);
    RUN_TEST(test_int_array_fails);
    RUN_TEST(test_int32_array_fails);
    RUN_TEST(test_uint8_array_fails);
    RUN_TEST(test_uint16_array_fails);
    RUN_TEST(test_uint32_array_fails);
    RUN_TEST(test_hex8_array_fails);
    RUN_TEST(test_empty_array_fails);
    RUN_TEST(test_null_array_fails);
    RUN_TEST(test_float_array_fails);
    RUN_TEST(test_string_fails);
    RUN_TEST(test_string_null_fails);
    RUN_TEST(test_string_escapes_control_characters);
    RUN_TEST(test_string_len_fails);
    RUN_TEST(test_memory_fails);
    RUN_TEST(test_float_within_fails);
    RUN_TEST(test_float_within_message_fails);
    RUN_TEST(test_equal_float_fails);
    RUN_TEST(test_equal_float_zero_fails);
    RUN_TEST(test_float_large_values_print_with_exponent);
    RUN_TEST(test_float_small_values_print);
    RUN_TEST(test_float_tiny_values_print_with_exponent);
    RUN_TEST(test_greater_than_float_fails);
    RUN_TEST(test_less_than_float_fails);
    RUN_TEST(test_float_is_nan_fails);
    RUN_TEST(test_float_is_not_nan_fails);
    RUN_TEST(test_float_is_inf_fails);
    RUN_TEST(test_float_is_inf_means_positive);
    RUN_TEST(test_float_is_not_inf_fails);
    /* expect-summary: 76 Tests 66 Failures 2 Ignored */
    return UNITY_END();
}
