/*
 * unity.h - rsm's bundled, Unity-compatible unit-test core (public API).
 *
 * The project's unit tests are written against the API of the Unity C test
 * framework (ThrowTheSwitch).  When CMake finds an installed Unity it is used
 * instead of this file; otherwise this small core provides the same macro
 * names, argument orders and output format for the subset listed in
 * tests/unity/README.md, so a test source compiles unchanged against both.
 *
 * Usage, as with Unity:
 *
 *     #include "unity.h"
 *     void setUp(void) {}
 *     void tearDown(void) {}
 *     void test_answer(void) { TEST_ASSERT_EQUAL_INT(42, answer()); }
 *     int main(void)
 *     {
 *         UNITY_BEGIN();
 *         RUN_TEST(test_answer);
 *         return UNITY_END();
 *     }
 *
 * A failing assertion prints one result line and leaves the running test
 * through longjmp (TEST_PROTECT/TEST_ABORT); tearDown() still runs and the
 * next test starts normally.
 */
#ifndef RSM_UNITY_H
#define RSM_UNITY_H

#include "unity_internals.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Provided by every test source. */
void setUp(void);
void tearDown(void);

/* Declared for compatibility; this core never calls them itself. */
void suiteSetUp(void);
int suiteTearDown(int num_failures);

/* ---------------------------------------------------------------------
 * Running tests
 * ------------------------------------------------------------------- */
#define UNITY_BEGIN() UnityBegin(__FILE__)
#define UNITY_END() UnityEnd()

/* RUN_TEST(func) or RUN_TEST(func, line): the reported line defaults to the
 * line of the RUN_TEST call. */
#define RUN_TEST(...) UNITY_RSM_RUN_TEST_AT(__VA_ARGS__, __LINE__, 0)
#define UNITY_RSM_RUN_TEST_AT(func, line, ...) UnityDefaultTestRun(func, #func, line)

/* ---------------------------------------------------------------------
 * Pass, fail, ignore, message
 * ------------------------------------------------------------------- */
#define TEST_FAIL()                    UnityFail(NULL, UNITY_RSM_LINE(__LINE__))
#define TEST_FAIL_MESSAGE(message)     UnityFail((message), UNITY_RSM_LINE(__LINE__))
#define TEST_IGNORE()                  UnityIgnore(NULL, UNITY_RSM_LINE(__LINE__))
#define TEST_IGNORE_MESSAGE(message)   UnityIgnore((message), UNITY_RSM_LINE(__LINE__))
#define TEST_MESSAGE(message)          UnityMessage((message), UNITY_RSM_LINE(__LINE__))
#define TEST_PASS()                    TEST_ABORT()
#define TEST_PASS_MESSAGE(message)                                                                 \
    do                                                                                             \
    {                                                                                              \
        UnityMessage((message), UNITY_RSM_LINE(__LINE__));                                         \
        TEST_ABORT();                                                                              \
    } while (0)

/* ---------------------------------------------------------------------
 * Boolean and pointer checks
 * ------------------------------------------------------------------- */
#define TEST_ASSERT(condition)                          UNITY_RSM_CHECK((condition), __LINE__, " Expression Evaluated To FALSE")
#define TEST_ASSERT_MESSAGE(condition, message)         UNITY_RSM_CHECK((condition), __LINE__, (message))
#define TEST_ASSERT_TRUE(condition)                     UNITY_RSM_CHECK((condition), __LINE__, " Expected TRUE Was FALSE")
#define TEST_ASSERT_TRUE_MESSAGE(condition, message)    UNITY_RSM_CHECK((condition), __LINE__, (message))
#define TEST_ASSERT_UNLESS(condition)                   UNITY_RSM_CHECK(!(condition), __LINE__, " Expression Evaluated To TRUE")
#define TEST_ASSERT_UNLESS_MESSAGE(condition, message)  UNITY_RSM_CHECK(!(condition), __LINE__, (message))
#define TEST_ASSERT_FALSE(condition)                    UNITY_RSM_CHECK(!(condition), __LINE__, " Expected FALSE Was TRUE")
#define TEST_ASSERT_FALSE_MESSAGE(condition, message)   UNITY_RSM_CHECK(!(condition), __LINE__, (message))
#define TEST_ASSERT_NULL(pointer)                       UNITY_RSM_CHECK(((pointer) == NULL), __LINE__, " Expected NULL")
#define TEST_ASSERT_NULL_MESSAGE(pointer, message)      UNITY_RSM_CHECK(((pointer) == NULL), __LINE__, (message))
#define TEST_ASSERT_NOT_NULL(pointer)                   UNITY_RSM_CHECK(((pointer) != NULL), __LINE__, " Expected Non-NULL")
#define TEST_ASSERT_NOT_NULL_MESSAGE(pointer, message)  UNITY_RSM_CHECK(((pointer) != NULL), __LINE__, (message))

/* Plain != on the two operands, like Unity's default shorthand. */
#define TEST_ASSERT_NOT_EQUAL(expected, actual)                   UNITY_RSM_CHECK(((expected) != (actual)), __LINE__, " Expected Not-Equal")
#define TEST_ASSERT_NOT_EQUAL_MESSAGE(expected, actual, message)  UNITY_RSM_CHECK(((expected) != (actual)), __LINE__, (message))

/* ---------------------------------------------------------------------
 * Integers.  Each kind narrows both operands to its type first (INT8 uses
 * int8_t, UINT16 uses uint16_t, ...); INT, UINT, INT64, UINT64 and size_t
 * compare the full value.  HEX kinds compare unsigned and print in hex.
 * ------------------------------------------------------------------- */
/* Integer equality (expected, actual). */
#define TEST_ASSERT_EQUAL(expected, actual)                                         UNITY_RSM_EQUAL(INT, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_MESSAGE(expected, actual, message)                        UNITY_RSM_EQUAL(INT, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_INT(expected, actual)                                     UNITY_RSM_EQUAL(INT, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT_MESSAGE(expected, actual, message)                    UNITY_RSM_EQUAL(INT, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_INT8(expected, actual)                                    UNITY_RSM_EQUAL(INT8, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT8_MESSAGE(expected, actual, message)                   UNITY_RSM_EQUAL(INT8, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_INT16(expected, actual)                                   UNITY_RSM_EQUAL(INT16, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT16_MESSAGE(expected, actual, message)                  UNITY_RSM_EQUAL(INT16, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_INT32(expected, actual)                                   UNITY_RSM_EQUAL(INT32, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT32_MESSAGE(expected, actual, message)                  UNITY_RSM_EQUAL(INT32, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_INT64(expected, actual)                                   UNITY_RSM_EQUAL(INT64, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT64_MESSAGE(expected, actual, message)                  UNITY_RSM_EQUAL(INT64, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT(expected, actual)                                    UNITY_RSM_EQUAL(UINT, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT_MESSAGE(expected, actual, message)                   UNITY_RSM_EQUAL(UINT, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT8(expected, actual)                                   UNITY_RSM_EQUAL(UINT8, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT8_MESSAGE(expected, actual, message)                  UNITY_RSM_EQUAL(UINT8, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT16(expected, actual)                                  UNITY_RSM_EQUAL(UINT16, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT16_MESSAGE(expected, actual, message)                 UNITY_RSM_EQUAL(UINT16, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT32(expected, actual)                                  UNITY_RSM_EQUAL(UINT32, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT32_MESSAGE(expected, actual, message)                 UNITY_RSM_EQUAL(UINT32, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT64(expected, actual)                                  UNITY_RSM_EQUAL(UINT64, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT64_MESSAGE(expected, actual, message)                 UNITY_RSM_EQUAL(UINT64, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_size_t(expected, actual)                                  UNITY_RSM_EQUAL(size_t, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_size_t_MESSAGE(expected, actual, message)                 UNITY_RSM_EQUAL(size_t, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX8(expected, actual)                                    UNITY_RSM_EQUAL(HEX8, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX8_MESSAGE(expected, actual, message)                   UNITY_RSM_EQUAL(HEX8, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX16(expected, actual)                                   UNITY_RSM_EQUAL(HEX16, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX16_MESSAGE(expected, actual, message)                  UNITY_RSM_EQUAL(HEX16, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX32(expected, actual)                                   UNITY_RSM_EQUAL(HEX32, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX32_MESSAGE(expected, actual, message)                  UNITY_RSM_EQUAL(HEX32, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX64(expected, actual)                                   UNITY_RSM_EQUAL(HEX64, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX64_MESSAGE(expected, actual, message)                  UNITY_RSM_EQUAL(HEX64, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_PTR(expected, actual)                                     UNITY_RSM_EQUAL(PTR, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_PTR_MESSAGE(expected, actual, message)                    UNITY_RSM_EQUAL(PTR, expected, actual, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX(expected, actual)                                     UNITY_RSM_EQUAL(HEX32, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX_MESSAGE(expected, actual, message)                    UNITY_RSM_EQUAL(HEX32, expected, actual, __LINE__, message)

/* Integer ordering (threshold, actual): actual > threshold. */
#define TEST_ASSERT_GREATER_THAN(threshold, actual)                                 UNITY_RSM_ORDER(INT, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_MESSAGE(threshold, actual, message)                UNITY_RSM_ORDER(INT, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_INT(threshold, actual)                             UNITY_RSM_ORDER(INT, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_INT_MESSAGE(threshold, actual, message)            UNITY_RSM_ORDER(INT, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_INT8(threshold, actual)                            UNITY_RSM_ORDER(INT8, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_INT8_MESSAGE(threshold, actual, message)           UNITY_RSM_ORDER(INT8, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_INT16(threshold, actual)                           UNITY_RSM_ORDER(INT16, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_INT16_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(INT16, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_INT32(threshold, actual)                           UNITY_RSM_ORDER(INT32, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_INT32_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(INT32, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_INT64(threshold, actual)                           UNITY_RSM_ORDER(INT64, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_INT64_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(INT64, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_UINT(threshold, actual)                            UNITY_RSM_ORDER(UINT, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT_MESSAGE(threshold, actual, message)           UNITY_RSM_ORDER(UINT, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_UINT8(threshold, actual)                           UNITY_RSM_ORDER(UINT8, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT8_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(UINT8, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_UINT16(threshold, actual)                          UNITY_RSM_ORDER(UINT16, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT16_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(UINT16, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_UINT32(threshold, actual)                          UNITY_RSM_ORDER(UINT32, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT32_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(UINT32, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_UINT64(threshold, actual)                          UNITY_RSM_ORDER(UINT64, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT64_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(UINT64, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_size_t(threshold, actual)                          UNITY_RSM_ORDER(size_t, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_size_t_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(size_t, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_HEX8(threshold, actual)                            UNITY_RSM_ORDER(HEX8, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_HEX8_MESSAGE(threshold, actual, message)           UNITY_RSM_ORDER(HEX8, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_HEX16(threshold, actual)                           UNITY_RSM_ORDER(HEX16, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_HEX16_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(HEX16, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_HEX32(threshold, actual)                           UNITY_RSM_ORDER(HEX32, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_HEX32_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(HEX32, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_THAN_HEX64(threshold, actual)                           UNITY_RSM_ORDER(HEX64, UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_HEX64_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(HEX64, UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)

/* Integer ordering (threshold, actual): actual < threshold. */
#define TEST_ASSERT_LESS_THAN(threshold, actual)                                    UNITY_RSM_ORDER(INT, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_MESSAGE(threshold, actual, message)                   UNITY_RSM_ORDER(INT, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_INT(threshold, actual)                                UNITY_RSM_ORDER(INT, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_INT_MESSAGE(threshold, actual, message)               UNITY_RSM_ORDER(INT, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_INT8(threshold, actual)                               UNITY_RSM_ORDER(INT8, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_INT8_MESSAGE(threshold, actual, message)              UNITY_RSM_ORDER(INT8, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_INT16(threshold, actual)                              UNITY_RSM_ORDER(INT16, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_INT16_MESSAGE(threshold, actual, message)             UNITY_RSM_ORDER(INT16, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_INT32(threshold, actual)                              UNITY_RSM_ORDER(INT32, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_INT32_MESSAGE(threshold, actual, message)             UNITY_RSM_ORDER(INT32, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_INT64(threshold, actual)                              UNITY_RSM_ORDER(INT64, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_INT64_MESSAGE(threshold, actual, message)             UNITY_RSM_ORDER(INT64, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_UINT(threshold, actual)                               UNITY_RSM_ORDER(UINT, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_UINT_MESSAGE(threshold, actual, message)              UNITY_RSM_ORDER(UINT, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_UINT8(threshold, actual)                              UNITY_RSM_ORDER(UINT8, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_UINT8_MESSAGE(threshold, actual, message)             UNITY_RSM_ORDER(UINT8, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_UINT16(threshold, actual)                             UNITY_RSM_ORDER(UINT16, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_UINT16_MESSAGE(threshold, actual, message)            UNITY_RSM_ORDER(UINT16, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_UINT32(threshold, actual)                             UNITY_RSM_ORDER(UINT32, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_UINT32_MESSAGE(threshold, actual, message)            UNITY_RSM_ORDER(UINT32, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_UINT64(threshold, actual)                             UNITY_RSM_ORDER(UINT64, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_UINT64_MESSAGE(threshold, actual, message)            UNITY_RSM_ORDER(UINT64, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_size_t(threshold, actual)                             UNITY_RSM_ORDER(size_t, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_size_t_MESSAGE(threshold, actual, message)            UNITY_RSM_ORDER(size_t, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_HEX8(threshold, actual)                               UNITY_RSM_ORDER(HEX8, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_HEX8_MESSAGE(threshold, actual, message)              UNITY_RSM_ORDER(HEX8, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_HEX16(threshold, actual)                              UNITY_RSM_ORDER(HEX16, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_HEX16_MESSAGE(threshold, actual, message)             UNITY_RSM_ORDER(HEX16, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_HEX32(threshold, actual)                              UNITY_RSM_ORDER(HEX32, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_HEX32_MESSAGE(threshold, actual, message)             UNITY_RSM_ORDER(HEX32, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_HEX64(threshold, actual)                              UNITY_RSM_ORDER(HEX64, UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_HEX64_MESSAGE(threshold, actual, message)             UNITY_RSM_ORDER(HEX64, UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)

/* Integer ordering (threshold, actual): actual >= threshold. */
#define TEST_ASSERT_GREATER_OR_EQUAL(threshold, actual)                             UNITY_RSM_ORDER(INT, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_MESSAGE(threshold, actual, message)            UNITY_RSM_ORDER(INT, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT(threshold, actual)                         UNITY_RSM_ORDER(INT, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT_MESSAGE(threshold, actual, message)        UNITY_RSM_ORDER(INT, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT8(threshold, actual)                        UNITY_RSM_ORDER(INT8, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT8_MESSAGE(threshold, actual, message)       UNITY_RSM_ORDER(INT8, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT16(threshold, actual)                       UNITY_RSM_ORDER(INT16, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT16_MESSAGE(threshold, actual, message)      UNITY_RSM_ORDER(INT16, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT32(threshold, actual)                       UNITY_RSM_ORDER(INT32, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT32_MESSAGE(threshold, actual, message)      UNITY_RSM_ORDER(INT32, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT64(threshold, actual)                       UNITY_RSM_ORDER(INT64, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT64_MESSAGE(threshold, actual, message)      UNITY_RSM_ORDER(INT64, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT(threshold, actual)                        UNITY_RSM_ORDER(UINT, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT_MESSAGE(threshold, actual, message)       UNITY_RSM_ORDER(UINT, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT8(threshold, actual)                       UNITY_RSM_ORDER(UINT8, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT8_MESSAGE(threshold, actual, message)      UNITY_RSM_ORDER(UINT8, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT16(threshold, actual)                      UNITY_RSM_ORDER(UINT16, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT16_MESSAGE(threshold, actual, message)     UNITY_RSM_ORDER(UINT16, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT32(threshold, actual)                      UNITY_RSM_ORDER(UINT32, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT32_MESSAGE(threshold, actual, message)     UNITY_RSM_ORDER(UINT32, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT64(threshold, actual)                      UNITY_RSM_ORDER(UINT64, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT64_MESSAGE(threshold, actual, message)     UNITY_RSM_ORDER(UINT64, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_size_t(threshold, actual)                      UNITY_RSM_ORDER(size_t, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_size_t_MESSAGE(threshold, actual, message)     UNITY_RSM_ORDER(size_t, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_HEX8(threshold, actual)                        UNITY_RSM_ORDER(HEX8, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_HEX8_MESSAGE(threshold, actual, message)       UNITY_RSM_ORDER(HEX8, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_HEX16(threshold, actual)                       UNITY_RSM_ORDER(HEX16, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_HEX16_MESSAGE(threshold, actual, message)      UNITY_RSM_ORDER(HEX16, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_HEX32(threshold, actual)                       UNITY_RSM_ORDER(HEX32, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_HEX32_MESSAGE(threshold, actual, message)      UNITY_RSM_ORDER(HEX32, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_HEX64(threshold, actual)                       UNITY_RSM_ORDER(HEX64, UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_HEX64_MESSAGE(threshold, actual, message)      UNITY_RSM_ORDER(HEX64, UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)

/* Integer ordering (threshold, actual): actual <= threshold. */
#define TEST_ASSERT_LESS_OR_EQUAL(threshold, actual)                                UNITY_RSM_ORDER(INT, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_MESSAGE(threshold, actual, message)               UNITY_RSM_ORDER(INT, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_INT(threshold, actual)                            UNITY_RSM_ORDER(INT, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT_MESSAGE(threshold, actual, message)           UNITY_RSM_ORDER(INT, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_INT8(threshold, actual)                           UNITY_RSM_ORDER(INT8, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT8_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(INT8, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_INT16(threshold, actual)                          UNITY_RSM_ORDER(INT16, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT16_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(INT16, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_INT32(threshold, actual)                          UNITY_RSM_ORDER(INT32, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT32_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(INT32, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_INT64(threshold, actual)                          UNITY_RSM_ORDER(INT64, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT64_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(INT64, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT(threshold, actual)                           UNITY_RSM_ORDER(UINT, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(UINT, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT8(threshold, actual)                          UNITY_RSM_ORDER(UINT8, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT8_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(UINT8, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT16(threshold, actual)                         UNITY_RSM_ORDER(UINT16, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT16_MESSAGE(threshold, actual, message)        UNITY_RSM_ORDER(UINT16, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT32(threshold, actual)                         UNITY_RSM_ORDER(UINT32, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT32_MESSAGE(threshold, actual, message)        UNITY_RSM_ORDER(UINT32, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT64(threshold, actual)                         UNITY_RSM_ORDER(UINT64, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT64_MESSAGE(threshold, actual, message)        UNITY_RSM_ORDER(UINT64, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_size_t(threshold, actual)                         UNITY_RSM_ORDER(size_t, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_size_t_MESSAGE(threshold, actual, message)        UNITY_RSM_ORDER(size_t, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_HEX8(threshold, actual)                           UNITY_RSM_ORDER(HEX8, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_HEX8_MESSAGE(threshold, actual, message)          UNITY_RSM_ORDER(HEX8, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_HEX16(threshold, actual)                          UNITY_RSM_ORDER(HEX16, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_HEX16_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(HEX16, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_HEX32(threshold, actual)                          UNITY_RSM_ORDER(HEX32, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_HEX32_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(HEX32, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_HEX64(threshold, actual)                          UNITY_RSM_ORDER(HEX64, UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_HEX64_MESSAGE(threshold, actual, message)         UNITY_RSM_ORDER(HEX64, UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)

/* Integer ranges (delta, expected, actual): |actual - expected| <= delta. */
#define TEST_ASSERT_INT_WITHIN(delta, expected, actual)                             UNITY_RSM_WITHIN(INT, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_INT_WITHIN_MESSAGE(delta, expected, actual, message)            UNITY_RSM_WITHIN(INT, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_INT8_WITHIN(delta, expected, actual)                            UNITY_RSM_WITHIN(INT8, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_INT8_WITHIN_MESSAGE(delta, expected, actual, message)           UNITY_RSM_WITHIN(INT8, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_INT16_WITHIN(delta, expected, actual)                           UNITY_RSM_WITHIN(INT16, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_INT16_WITHIN_MESSAGE(delta, expected, actual, message)          UNITY_RSM_WITHIN(INT16, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_INT32_WITHIN(delta, expected, actual)                           UNITY_RSM_WITHIN(INT32, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_INT32_WITHIN_MESSAGE(delta, expected, actual, message)          UNITY_RSM_WITHIN(INT32, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_INT64_WITHIN(delta, expected, actual)                           UNITY_RSM_WITHIN(INT64, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_INT64_WITHIN_MESSAGE(delta, expected, actual, message)          UNITY_RSM_WITHIN(INT64, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_UINT_WITHIN(delta, expected, actual)                            UNITY_RSM_WITHIN(UINT, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_UINT_WITHIN_MESSAGE(delta, expected, actual, message)           UNITY_RSM_WITHIN(UINT, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_UINT8_WITHIN(delta, expected, actual)                           UNITY_RSM_WITHIN(UINT8, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_UINT8_WITHIN_MESSAGE(delta, expected, actual, message)          UNITY_RSM_WITHIN(UINT8, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_UINT16_WITHIN(delta, expected, actual)                          UNITY_RSM_WITHIN(UINT16, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_UINT16_WITHIN_MESSAGE(delta, expected, actual, message)         UNITY_RSM_WITHIN(UINT16, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_UINT32_WITHIN(delta, expected, actual)                          UNITY_RSM_WITHIN(UINT32, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_UINT32_WITHIN_MESSAGE(delta, expected, actual, message)         UNITY_RSM_WITHIN(UINT32, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_UINT64_WITHIN(delta, expected, actual)                          UNITY_RSM_WITHIN(UINT64, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_UINT64_WITHIN_MESSAGE(delta, expected, actual, message)         UNITY_RSM_WITHIN(UINT64, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_size_t_WITHIN(delta, expected, actual)                          UNITY_RSM_WITHIN(size_t, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_size_t_WITHIN_MESSAGE(delta, expected, actual, message)         UNITY_RSM_WITHIN(size_t, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_HEX8_WITHIN(delta, expected, actual)                            UNITY_RSM_WITHIN(HEX8, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_HEX8_WITHIN_MESSAGE(delta, expected, actual, message)           UNITY_RSM_WITHIN(HEX8, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_HEX16_WITHIN(delta, expected, actual)                           UNITY_RSM_WITHIN(HEX16, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_HEX16_WITHIN_MESSAGE(delta, expected, actual, message)          UNITY_RSM_WITHIN(HEX16, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_HEX32_WITHIN(delta, expected, actual)                           UNITY_RSM_WITHIN(HEX32, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_HEX32_WITHIN_MESSAGE(delta, expected, actual, message)          UNITY_RSM_WITHIN(HEX32, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_HEX64_WITHIN(delta, expected, actual)                           UNITY_RSM_WITHIN(HEX64, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_HEX64_WITHIN_MESSAGE(delta, expected, actual, message)          UNITY_RSM_WITHIN(HEX64, delta, expected, actual, __LINE__, message)
#define TEST_ASSERT_HEX_WITHIN(delta, expected, actual)                             UNITY_RSM_WITHIN(HEX32, delta, expected, actual, __LINE__, NULL)
#define TEST_ASSERT_HEX_WITHIN_MESSAGE(delta, expected, actual, message)            UNITY_RSM_WITHIN(HEX32, delta, expected, actual, __LINE__, message)

/* Integer arrays (expected, actual, num_elements). */
#define TEST_ASSERT_EQUAL_INT_ARRAY(expected, actual, num_elements)                 UNITY_RSM_ARRAY(INT, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(INT, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_INT8_ARRAY(expected, actual, num_elements)                UNITY_RSM_ARRAY(INT8, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT8_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(INT8, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_INT16_ARRAY(expected, actual, num_elements)               UNITY_RSM_ARRAY(INT16, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT16_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(INT16, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_INT32_ARRAY(expected, actual, num_elements)               UNITY_RSM_ARRAY(INT32, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT32_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(INT32, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_INT64_ARRAY(expected, actual, num_elements)               UNITY_RSM_ARRAY(INT64, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_INT64_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(INT64, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT_ARRAY(expected, actual, num_elements)                UNITY_RSM_ARRAY(UINT, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(UINT, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT8_ARRAY(expected, actual, num_elements)               UNITY_RSM_ARRAY(UINT8, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT8_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(UINT8, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT16_ARRAY(expected, actual, num_elements)              UNITY_RSM_ARRAY(UINT16, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT16_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(UINT16, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT32_ARRAY(expected, actual, num_elements)              UNITY_RSM_ARRAY(UINT32, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT32_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(UINT32, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_UINT64_ARRAY(expected, actual, num_elements)              UNITY_RSM_ARRAY(UINT64, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_UINT64_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(UINT64, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, actual, num_elements)                UNITY_RSM_ARRAY(HEX8, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(HEX8, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX16_ARRAY(expected, actual, num_elements)               UNITY_RSM_ARRAY(HEX16, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX16_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(HEX16, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX32_ARRAY(expected, actual, num_elements)               UNITY_RSM_ARRAY(HEX32, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX32_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(HEX32, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX64_ARRAY(expected, actual, num_elements)               UNITY_RSM_ARRAY(HEX64, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX64_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(HEX64, expected, actual, num_elements, __LINE__, message)
#define TEST_ASSERT_EQUAL_HEX_ARRAY(expected, actual, num_elements)                 UNITY_RSM_ARRAY(HEX32, expected, actual, num_elements, __LINE__, NULL)
#define TEST_ASSERT_EQUAL_HEX_ARRAY_MESSAGE(expected, actual, num_elements, message) UNITY_RSM_ARRAY(HEX32, expected, actual, num_elements, __LINE__, message)

/* ---------------------------------------------------------------------
 * Strings and memory
 * ------------------------------------------------------------------- */
#define TEST_ASSERT_EQUAL_STRING(expected, actual)                                                 \
    UnityRsmAssertString((const char *)(expected), (const char *)(actual), 0u, 0, NULL,            \
                         UNITY_RSM_LINE(__LINE__))
#define TEST_ASSERT_EQUAL_STRING_MESSAGE(expected, actual, message)                                \
    UnityRsmAssertString((const char *)(expected), (const char *)(actual), 0u, 0, (message),       \
                         UNITY_RSM_LINE(__LINE__))
#define TEST_ASSERT_EQUAL_STRING_LEN(expected, actual, len)                                        \
    UnityRsmAssertString((const char *)(expected), (const char *)(actual), (UNITY_UINT32)(len), 1, \
                         NULL, UNITY_RSM_LINE(__LINE__))
#define TEST_ASSERT_EQUAL_STRING_LEN_MESSAGE(expected, actual, len, message)                       \
    UnityRsmAssertString((const char *)(expected), (const char *)(actual), (UNITY_UINT32)(len), 1, \
                         (message), UNITY_RSM_LINE(__LINE__))
#define TEST_ASSERT_EQUAL_MEMORY(expected, actual, len)                                            \
    UnityRsmAssertMemory((const void *)(expected), (const void *)(actual), (UNITY_UINT32)(len),    \
                         NULL, UNITY_RSM_LINE(__LINE__))
#define TEST_ASSERT_EQUAL_MEMORY_MESSAGE(expected, actual, len, message)                           \
    UnityRsmAssertMemory((const void *)(expected), (const void *)(actual), (UNITY_UINT32)(len),    \
                         (message), UNITY_RSM_LINE(__LINE__))

/* ---------------------------------------------------------------------
 * Single-precision floats (double assertions are not provided)
 * ------------------------------------------------------------------- */
#define TEST_ASSERT_FLOAT_WITHIN(delta, expected, actual)                                          \
    UnityRsmAssertFloatWithin((UNITY_FLOAT)(delta), (UNITY_FLOAT)(expected), (UNITY_FLOAT)(actual),\
                              NULL, UNITY_RSM_LINE(__LINE__))
#define TEST_ASSERT_FLOAT_WITHIN_MESSAGE(delta, expected, actual, message)                         \
    UnityRsmAssertFloatWithin((UNITY_FLOAT)(delta), (UNITY_FLOAT)(expected), (UNITY_FLOAT)(actual),\
                              (message), UNITY_RSM_LINE(__LINE__))

/* Equal within UNITY_FLOAT_PRECISION relative to expected. */
#define TEST_ASSERT_EQUAL_FLOAT(expected, actual)                                                  \
    UnityRsmAssertFloatEqual((UNITY_FLOAT)(expected), (UNITY_FLOAT)(actual),                       \
                             (UNITY_FLOAT)UNITY_FLOAT_PRECISION, NULL, UNITY_RSM_LINE(__LINE__))
#define TEST_ASSERT_EQUAL_FLOAT_MESSAGE(expected, actual, message)                                 \
    UnityRsmAssertFloatEqual((UNITY_FLOAT)(expected), (UNITY_FLOAT)(actual),                       \
                             (UNITY_FLOAT)UNITY_FLOAT_PRECISION, (message), UNITY_RSM_LINE(__LINE__))

#define TEST_ASSERT_EQUAL_FLOAT_ARRAY(expected, actual, num_elements)                              \
    UnityRsmAssertFloatArray((const UNITY_FLOAT *)(expected), (const UNITY_FLOAT *)(actual),       \
                             (UNITY_UINT32)(num_elements), (UNITY_FLOAT)UNITY_FLOAT_PRECISION,     \
                             NULL, UNITY_RSM_LINE(__LINE__))
#define TEST_ASSERT_EQUAL_FLOAT_ARRAY_MESSAGE(expected, actual, num_elements, message)             \
    UnityRsmAssertFloatArray((const UNITY_FLOAT *)(expected), (const UNITY_FLOAT *)(actual),       \
                             (UNITY_UINT32)(num_elements), (UNITY_FLOAT)UNITY_FLOAT_PRECISION,     \
                             (message), UNITY_RSM_LINE(__LINE__))

/* Float ordering (threshold, actual). */
#define TEST_ASSERT_GREATER_THAN_FLOAT(threshold, actual)                    UNITY_RSM_FLOAT_ORDER(UNITY_RSM_OP_GT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_THAN_FLOAT_MESSAGE(threshold, actual, message)   UNITY_RSM_FLOAT_ORDER(UNITY_RSM_OP_GT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_GREATER_OR_EQUAL_FLOAT(threshold, actual)                UNITY_RSM_FLOAT_ORDER(UNITY_RSM_OP_GE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_FLOAT_MESSAGE(threshold, actual, message) UNITY_RSM_FLOAT_ORDER(UNITY_RSM_OP_GE, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_THAN_FLOAT(threshold, actual)                       UNITY_RSM_FLOAT_ORDER(UNITY_RSM_OP_LT, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_THAN_FLOAT_MESSAGE(threshold, actual, message)      UNITY_RSM_FLOAT_ORDER(UNITY_RSM_OP_LT, threshold, actual, __LINE__, message)
#define TEST_ASSERT_LESS_OR_EQUAL_FLOAT(threshold, actual)                   UNITY_RSM_FLOAT_ORDER(UNITY_RSM_OP_LE, threshold, actual, __LINE__, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_FLOAT_MESSAGE(threshold, actual, message)  UNITY_RSM_FLOAT_ORDER(UNITY_RSM_OP_LE, threshold, actual, __LINE__, message)

/* Special values.  IS_INF means +infinity, as in Unity. */
#define TEST_ASSERT_FLOAT_IS_INF(actual)                             UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_INF, actual, __LINE__, NULL)
#define TEST_ASSERT_FLOAT_IS_INF_MESSAGE(actual, message)            UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_INF, actual, __LINE__, message)
#define TEST_ASSERT_FLOAT_IS_NEG_INF(actual)                         UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NEG_INF, actual, __LINE__, NULL)
#define TEST_ASSERT_FLOAT_IS_NEG_INF_MESSAGE(actual, message)        UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NEG_INF, actual, __LINE__, message)
#define TEST_ASSERT_FLOAT_IS_NAN(actual)                             UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NAN, actual, __LINE__, NULL)
#define TEST_ASSERT_FLOAT_IS_NAN_MESSAGE(actual, message)            UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NAN, actual, __LINE__, message)
#define TEST_ASSERT_FLOAT_IS_DETERMINATE(actual)                     UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_DET, actual, __LINE__, NULL)
#define TEST_ASSERT_FLOAT_IS_DETERMINATE_MESSAGE(actual, message)    UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_DET, actual, __LINE__, message)
#define TEST_ASSERT_FLOAT_IS_NOT_INF(actual)                         UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NOT | UNITY_RSM_TRAIT_INF, actual, __LINE__, NULL)
#define TEST_ASSERT_FLOAT_IS_NOT_INF_MESSAGE(actual, message)        UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NOT | UNITY_RSM_TRAIT_INF, actual, __LINE__, message)
#define TEST_ASSERT_FLOAT_IS_NOT_NEG_INF(actual)                     UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NOT | UNITY_RSM_TRAIT_NEG_INF, actual, __LINE__, NULL)
#define TEST_ASSERT_FLOAT_IS_NOT_NEG_INF_MESSAGE(actual, message)    UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NOT | UNITY_RSM_TRAIT_NEG_INF, actual, __LINE__, message)
#define TEST_ASSERT_FLOAT_IS_NOT_NAN(actual)                         UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NOT | UNITY_RSM_TRAIT_NAN, actual, __LINE__, NULL)
#define TEST_ASSERT_FLOAT_IS_NOT_NAN_MESSAGE(actual, message)        UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NOT | UNITY_RSM_TRAIT_NAN, actual, __LINE__, message)
#define TEST_ASSERT_FLOAT_IS_NOT_DETERMINATE(actual)                 UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NOT | UNITY_RSM_TRAIT_DET, actual, __LINE__, NULL)
#define TEST_ASSERT_FLOAT_IS_NOT_DETERMINATE_MESSAGE(actual, message) UNITY_RSM_FLOAT_TRAIT(UNITY_RSM_TRAIT_NOT | UNITY_RSM_TRAIT_DET, actual, __LINE__, message)

#ifdef __cplusplus
}
#endif

#endif /* RSM_UNITY_H */
