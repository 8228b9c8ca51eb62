/*
 * unity_internals.h - private part of rsm's bundled Unity-compatible test core.
 *
 * Test sources include "unity.h" only.  This header holds the types, the
 * single framework state object and the assertion entry points that the
 * public TEST_ASSERT_* macros in unity.h expand to.  Nothing here is meant
 * to be called directly by tests; names starting with UnityRsm / UNITY_RSM_
 * are private to this core and do not exist in upstream Unity.
 *
 * Written for rsm (C99, fixed memory: no heap, one state object).
 */
#ifndef RSM_UNITY_INTERNALS_H
#define RSM_UNITY_INTERNALS_H

#include <setjmp.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Marker so a build can tell which implementation it compiled against. */
#define UNITY_RSM_CORE 1

/* ---------------------------------------------------------------------
 * Types (names follow upstream Unity so tests that mention them build
 * against both implementations).
 * ------------------------------------------------------------------- */
typedef int8_t UNITY_INT8;
typedef int16_t UNITY_INT16;
typedef int32_t UNITY_INT32;
typedef int64_t UNITY_INT64;
typedef uint8_t UNITY_UINT8;
typedef uint16_t UNITY_UINT16;
typedef uint32_t UNITY_UINT32;
typedef uint64_t UNITY_UINT64;

/* Widest integer type every integer assertion is carried in. */
typedef long long UNITY_INT;
typedef unsigned long long UNITY_UINT;

typedef float UNITY_FLOAT;

typedef unsigned long UNITY_LINE_TYPE;
typedef unsigned long UNITY_COUNTER_TYPE;

typedef void (*UnityTestFunction)(void);

/* Relative tolerance used by TEST_ASSERT_EQUAL_FLOAT and the float
 * array/comparison assertions (same default as upstream Unity). */
#ifndef UNITY_FLOAT_PRECISION
#define UNITY_FLOAT_PRECISION (0.00001f)
#endif

#if defined(__GNUC__) || defined(__clang__)
#define UNITY_RSM_NORETURN __attribute__((noreturn))
#else
#define UNITY_RSM_NORETURN
#endif

/* ---------------------------------------------------------------------
 * The one piece of framework state.  It is global because a failing
 * assertion deep inside a test has to find the jump target of the
 * running test; everything else in the core is stateless.
 * ------------------------------------------------------------------- */
struct UNITY_STORAGE_T
{
    const char *TestFile;               /* __FILE__ given to UNITY_BEGIN()    */
    const char *CurrentTestName;        /* name passed by RUN_TEST            */
    UNITY_LINE_TYPE CurrentTestLineNumber; /* line of the RUN_TEST call      */
    UNITY_COUNTER_TYPE NumberOfTests;
    UNITY_COUNTER_TYPE TestFailures;
    UNITY_COUNTER_TYPE TestIgnores;
    UNITY_COUNTER_TYPE CurrentTestFailed;
    UNITY_COUNTER_TYPE CurrentTestIgnored;
    jmp_buf AbortFrame;                 /* where a failing assertion returns */
};

extern struct UNITY_STORAGE_T Unity;

/* ---------------------------------------------------------------------
 * Run control (public names shared with upstream Unity).
 * ------------------------------------------------------------------- */
void UnityBegin(const char *filename);
int UnityEnd(void);
void UnitySetTestFile(const char *filename);
void UnityDefaultTestRun(UnityTestFunction func, const char *func_name, int func_line);
void UnityConcludeTest(void);

UNITY_RSM_NORETURN void UnityFail(const char *message, UNITY_LINE_TYPE line);
UNITY_RSM_NORETURN void UnityIgnore(const char *message, UNITY_LINE_TYPE line);
void UnityMessage(const char *message, UNITY_LINE_TYPE line);

/* Output helpers; everything goes to stdout through putchar. */
void UnityPrint(const char *text);
void UnityPrintLen(const char *text, UNITY_UINT32 length);
void UnityPrintNumber(UNITY_INT number);
void UnityPrintNumberUnsigned(UNITY_UINT number);
void UnityPrintNumberHex(UNITY_UINT number, unsigned nibbles);
void UnityPrintFloat(UNITY_FLOAT number);

#define TEST_PROTECT() (setjmp(Unity.AbortFrame) == 0)
#define TEST_ABORT() longjmp(Unity.AbortFrame, 1)

#define TEST_LINE_NUM (Unity.CurrentTestLineNumber)
#define TEST_IS_IGNORED (Unity.CurrentTestIgnored)

/* ---------------------------------------------------------------------
 * Private assertion entry points.
 * ------------------------------------------------------------------- */

/* Comparison operators: bit 0 accepts equality, bit 1 accepts "greater",
 * bit 2 accepts "less".  Equality alone is the plain EQUAL assertion. */
#define UNITY_RSM_OP_EQ 0x1u
#define UNITY_RSM_OP_GT 0x2u
#define UNITY_RSM_OP_GE 0x3u
#define UNITY_RSM_OP_LT 0x4u
#define UNITY_RSM_OP_LE 0x5u

/* Display formats: high nibble says how a value is shown, low nibble is
 * the width in bytes (used for hex digits and array element size). */
#define UNITY_RSM_SHOW_SIGNED 0x10u
#define UNITY_RSM_SHOW_UNSIGNED 0x20u
#define UNITY_RSM_SHOW_HEX 0x40u

/* Float traits for TEST_ASSERT_FLOAT_IS_*; OR in NOT to negate. */
#define UNITY_RSM_TRAIT_INF 0x1u
#define UNITY_RSM_TRAIT_NEG_INF 0x2u
#define UNITY_RSM_TRAIT_NAN 0x3u
#define UNITY_RSM_TRAIT_DET 0x4u
#define UNITY_RSM_TRAIT_NOT 0x10u

void UnityRsmAssertCompare(UNITY_INT reference, UNITY_INT actual, unsigned op, unsigned format,
                           const char *message, UNITY_LINE_TYPE line);
void UnityRsmAssertWithin(UNITY_UINT delta, UNITY_INT expected, UNITY_INT actual, unsigned format,
                          const char *message, UNITY_LINE_TYPE line);
void UnityRsmAssertIntArray(const void *expected, const void *actual, UNITY_UINT32 count,
                            unsigned format, const char *message, UNITY_LINE_TYPE line);
void UnityRsmAssertString(const char *expected, const char *actual, UNITY_UINT32 max_len,
                          int bounded, const char *message, UNITY_LINE_TYPE line);
void UnityRsmAssertMemory(const void *expected, const void *actual, UNITY_UINT32 length,
                          const char *message, UNITY_LINE_TYPE line);
void UnityRsmAssertFloatWithin(UNITY_FLOAT delta, UNITY_FLOAT expected, UNITY_FLOAT actual,
                               const char *message, UNITY_LINE_TYPE line);
void UnityRsmAssertFloatEqual(UNITY_FLOAT expected, UNITY_FLOAT actual, UNITY_FLOAT precision,
                              const char *message, UNITY_LINE_TYPE line);
void UnityRsmAssertFloatOrder(UNITY_FLOAT threshold, UNITY_FLOAT actual, unsigned op,
                              UNITY_FLOAT precision, const char *message, UNITY_LINE_TYPE line);
void UnityRsmAssertFloatTrait(UNITY_FLOAT actual, unsigned trait, const char *message,
                              UNITY_LINE_TYPE line);
void UnityRsmAssertFloatArray(const UNITY_FLOAT *expected, const UNITY_FLOAT *actual,
                              UNITY_UINT32 count, UNITY_FLOAT precision, const char *message,
                              UNITY_LINE_TYPE line);

/* ---------------------------------------------------------------------
 * Per-kind plumbing used by the public macros.  KIND is one of
 * INT INT8 INT16 INT32 INT64 UINT UINT8 UINT16 UINT32 UINT64 size_t
 * HEX8 HEX16 HEX32 HEX64 PTR.  It is only ever token-pasted, so it is
 * never macro-expanded.
 *   UNITY_RSM_AS_<KIND>(x)    value narrowed to the kind, widened back
 *   UNITY_RSM_DELTA_<KIND>(d) tolerance of a WITHIN assertion
 *   UNITY_RSM_FMT_<KIND>      display format
 * ------------------------------------------------------------------- */
#define UNITY_RSM_AS_INT(x) ((UNITY_INT)(x))
#define UNITY_RSM_AS_INT8(x) ((UNITY_INT)(UNITY_INT8)(x))
#define UNITY_RSM_AS_INT16(x) ((UNITY_INT)(UNITY_INT16)(x))
#define UNITY_RSM_AS_INT32(x) ((UNITY_INT)(UNITY_INT32)(x))
#define UNITY_RSM_AS_INT64(x) ((UNITY_INT)(x))
#define UNITY_RSM_AS_UINT(x) ((UNITY_INT)(x))
#define UNITY_RSM_AS_UINT8(x) ((UNITY_INT)(UNITY_UINT8)(x))
#define UNITY_RSM_AS_UINT16(x) ((UNITY_INT)(UNITY_UINT16)(x))
#define UNITY_RSM_AS_UINT32(x) ((UNITY_INT)(UNITY_UINT32)(x))
#define UNITY_RSM_AS_UINT64(x) ((UNITY_INT)(x))
#define UNITY_RSM_AS_size_t(x) ((UNITY_INT)(x))
#define UNITY_RSM_AS_HEX8(x) ((UNITY_INT)(UNITY_UINT8)(x))
#define UNITY_RSM_AS_HEX16(x) ((UNITY_INT)(UNITY_UINT16)(x))
#define UNITY_RSM_AS_HEX32(x) ((UNITY_INT)(UNITY_UINT32)(x))
#define UNITY_RSM_AS_HEX64(x) ((UNITY_INT)(x))
#define UNITY_RSM_AS_PTR(x) ((UNITY_INT)(uintptr_t)(x))

#define UNITY_RSM_DELTA_INT(d) ((UNITY_UINT)(d))
#define UNITY_RSM_DELTA_INT8(d) ((UNITY_UINT)(UNITY_UINT8)(d))
#define UNITY_RSM_DELTA_INT16(d) ((UNITY_UINT)(UNITY_UINT16)(d))
#define UNITY_RSM_DELTA_INT32(d) ((UNITY_UINT)(UNITY_UINT32)(d))
#define UNITY_RSM_DELTA_INT64(d) ((UNITY_UINT)(d))
#define UNITY_RSM_DELTA_UINT(d) ((UNITY_UINT)(d))
#define UNITY_RSM_DELTA_UINT8(d) ((UNITY_UINT)(UNITY_UINT8)(d))
#define UNITY_RSM_DELTA_UINT16(d) ((UNITY_UINT)(UNITY_UINT16)(d))
#define UNITY_RSM_DELTA_UINT32(d) ((UNITY_UINT)(UNITY_UINT32)(d))
#define UNITY_RSM_DELTA_UINT64(d) ((UNITY_UINT)(d))
#define UNITY_RSM_DELTA_size_t(d) ((UNITY_UINT)(d))
#define UNITY_RSM_DELTA_HEX8(d) ((UNITY_UINT)(UNITY_UINT8)(d))
#define UNITY_RSM_DELTA_HEX16(d) ((UNITY_UINT)(UNITY_UINT16)(d))
#define UNITY_RSM_DELTA_HEX32(d) ((UNITY_UINT)(UNITY_UINT32)(d))
#define UNITY_RSM_DELTA_HEX64(d) ((UNITY_UINT)(d))

#define UNITY_RSM_FMT_INT (UNITY_RSM_SHOW_SIGNED | (unsigned)sizeof(int))
#define UNITY_RSM_FMT_INT8 (UNITY_RSM_SHOW_SIGNED | 1u)
#define UNITY_RSM_FMT_INT16 (UNITY_RSM_SHOW_SIGNED | 2u)
#define UNITY_RSM_FMT_INT32 (UNITY_RSM_SHOW_SIGNED | 4u)
#define UNITY_RSM_FMT_INT64 (UNITY_RSM_SHOW_SIGNED | 8u)
#define UNITY_RSM_FMT_UINT (UNITY_RSM_SHOW_UNSIGNED | (unsigned)sizeof(unsigned int))
#define UNITY_RSM_FMT_UINT8 (UNITY_RSM_SHOW_UNSIGNED | 1u)
#define UNITY_RSM_FMT_UINT16 (UNITY_RSM_SHOW_UNSIGNED | 2u)
#define UNITY_RSM_FMT_UINT32 (UNITY_RSM_SHOW_UNSIGNED | 4u)
#define UNITY_RSM_FMT_UINT64 (UNITY_RSM_SHOW_UNSIGNED | 8u)
#define UNITY_RSM_FMT_size_t (UNITY_RSM_SHOW_UNSIGNED | (unsigned)sizeof(size_t))
#define UNITY_RSM_FMT_HEX8 (UNITY_RSM_SHOW_HEX | 1u)
#define UNITY_RSM_FMT_HEX16 (UNITY_RSM_SHOW_HEX | 2u)
#define UNITY_RSM_FMT_HEX32 (UNITY_RSM_SHOW_HEX | 4u)
#define UNITY_RSM_FMT_HEX64 (UNITY_RSM_SHOW_HEX | 8u)
#define UNITY_RSM_FMT_PTR (UNITY_RSM_SHOW_HEX | (unsigned)sizeof(void *))

#define UNITY_RSM_LINE(line) ((UNITY_LINE_TYPE)(line))

#define UNITY_RSM_CHECK(condition, line, message)                                                  \
    do                                                                                             \
    {                                                                                              \
        if (!(condition))                                                                          \
        {                                                                                          \
            UnityFail((message), UNITY_RSM_LINE(line));                                            \
        }                                                                                          \
    } while (0)

#define UNITY_RSM_ORDER(kind, op, reference, actual, line, message)                                \
    UnityRsmAssertCompare(UNITY_RSM_AS_##kind(reference), UNITY_RSM_AS_##kind(actual), (op),       \
                          UNITY_RSM_FMT_##kind, (message), UNITY_RSM_LINE(line))

#define UNITY_RSM_EQUAL(kind, expected, actual, line, message)                                     \
    UNITY_RSM_ORDER(kind, UNITY_RSM_OP_EQ, expected, actual, line, message)

#define UNITY_RSM_WITHIN(kind, delta, expected, actual, line, message)                             \
    UnityRsmAssertWithin(UNITY_RSM_DELTA_##kind(delta), UNITY_RSM_AS_##kind(expected),             \
                         UNITY_RSM_AS_##kind(actual), UNITY_RSM_FMT_##kind, (message),             \
                         UNITY_RSM_LINE(line))

#define UNITY_RSM_ARRAY(kind, expected, actual, count, line, message)                              \
    UnityRsmAssertIntArray((const void *)(expected), (const void *)(actual),                       \
                           (UNITY_UINT32)(count), UNITY_RSM_FMT_##kind, (message),                 \
                           UNITY_RSM_LINE(line))

#define UNITY_RSM_FLOAT_ORDER(op, threshold, actual, line, message)                                \
    UnityRsmAssertFloatOrder((UNITY_FLOAT)(threshold), (UNITY_FLOAT)(actual), (op),                \
                             (UNITY_FLOAT)UNITY_FLOAT_PRECISION, (message), UNITY_RSM_LINE(line))

#define UNITY_RSM_FLOAT_TRAIT(trait, actual, line, message)                                        \
    UnityRsmAssertFloatTrait((UNITY_FLOAT)(actual), (trait), (message), UNITY_RSM_LINE(line))

#ifdef __cplusplus
}
#endif

#endif /* RSM_UNITY_INTERNALS_H */
