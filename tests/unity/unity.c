/*
 * unity.c - rsm's bundled, Unity-compatible unit-test core.
 *
 * Output format (one line per test, then a summary), identical to Unity's:
 *
 *     <file>:<line>:<test>:PASS
 *     <file>:<line>:<test>:FAIL: <what went wrong>[. <user message>]
 *     <file>:<line>:<test>:IGNORE[: <user message>]
 *     <file>:<line>:<test>:INFO: <text>              (TEST_MESSAGE)
 *
 *     -----------------------
 *     <n> Tests <f> Failures <i> Ignored
 *     OK | FAIL
 *
 * PASS lines carry the line of the RUN_TEST call; FAIL, IGNORE and INFO lines
 * carry the line of the statement that produced them.
 *
 * Fixed memory: no heap, and the only object with static storage is the
 * framework state `Unity` declared in unity_internals.h.
 */
#include "unity.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#ifndef UNITY_OUTPUT_CHAR
#define UNITY_OUTPUT_CHAR(c) ((void)putchar(c))
#endif
#ifndef UNITY_OUTPUT_FLUSH
#define UNITY_OUTPUT_FLUSH() ((void)fflush(stdout))
#endif

struct UNITY_STORAGE_T Unity;

/* =====================================================================
 * Output
 * =================================================================== */

static void out_char(char c)
{
    UNITY_OUTPUT_CHAR(c);
}

static void out_newline(void)
{
    out_char('\n');
}

static void out_hex_digits(UNITY_UINT value, unsigned digits)
{
    if (digits > 16u)
    {
        digits = 16u;
    }
    while (digits > 0u)
    {
        unsigned nibble;

        digits--;
        nibble = (unsigned)((value >> (4u * digits)) & 0xFu);
        out_char((char)(nibble < 10u ? '0' + (int)nibble : 'A' + (int)nibble - 10));
    }
}

/* Printable ASCII goes out as is; CR and LF as \r and \n; anything else as
 * \xHH, so every report stays on one line. */
static void out_visible(char c)
{
    const unsigned char byte = (unsigned char)c;

    if (byte >= 32u && byte <= 126u)
    {
        out_char(c);
    }
    else if (byte == 13u)
    {
        out_char('\\');
        out_char('r');
    }
    else if (byte == 10u)
    {
        out_char('\\');
        out_char('n');
    }
    else
    {
        out_char('\\');
        out_char('x');
        out_hex_digits(byte, 2u);
    }
}

void UnityPrint(const char *text)
{
    if (text == NULL)
    {
        return;
    }
    for (; *text != '\0'; ++text)
    {
        out_visible(*text);
    }
}

void UnityPrintLen(const char *text, UNITY_UINT32 length)
{
    UNITY_UINT32 i;

    if (text == NULL)
    {
        return;
    }
    for (i = 0u; i < length && text[i] != '\0'; ++i)
    {
        out_visible(text[i]);
    }
}

void UnityPrintNumberUnsigned(UNITY_UINT number)
{
    char digits[24];
    unsigned count = 0u;

    do
    {
        digits[count++] = (char)('0' + (int)(number % 10u));
        number /= 10u;
    } while (number != 0u);

    while (count > 0u)
    {
        out_char(digits[--count]);
    }
}

void UnityPrintNumber(UNITY_INT number)
{
    UNITY_UINT magnitude = (UNITY_UINT)number;

    if (number < 0)
    {
        out_char('-');
        magnitude = (UNITY_UINT)0u - magnitude; /* also right for the minimum */
    }
    UnityPrintNumberUnsigned(magnitude);
}

void UnityPrintNumberHex(UNITY_UINT number, unsigned nibbles)
{
    out_hex_digits(number, nibbles);
}

/* Shortest form with up to 7 significant digits, like printf("%.7g"); the
 * special values are spelled the way Unity spells them. */
void UnityPrintFloat(UNITY_FLOAT number)
{
    char text[40];
    int length;
    int i;

    if (isnan(number))
    {
        UnityPrint("nan");
        return;
    }
    if (number < 0.0f)
    {
        out_char('-');
        number = -number;
    }
    if (isinf(number))
    {
        UnityPrint("inf");
        return;
    }
    if (!(number > 0.0f))
    {
        out_char('0'); /* zero, including negative zero */
        return;
    }
    length = snprintf(text, sizeof text, "%.7g", (double)number);
    for (i = 0; i < length && i < (int)sizeof text - 1; ++i)
    {
        out_char(text[i]);
    }
}

static void out_value(UNITY_INT value, unsigned format)
{
    switch (format & 0xF0u)
    {
    case UNITY_RSM_SHOW_SIGNED:
        UnityPrintNumber(value);
        break;
    case UNITY_RSM_SHOW_UNSIGNED:
        UnityPrintNumberUnsigned((UNITY_UINT)value);
        break;
    default:
        out_char('0');
        out_char('x');
        out_hex_digits((UNITY_UINT)value, 2u * (format & 0x0Fu));
        break;
    }
}

/* "<file>:<line>:<test>:" */
static void out_location(UNITY_LINE_TYPE line)
{
    UnityPrint(Unity.TestFile);
    out_char(':');
    UnityPrintNumberUnsigned((UNITY_UINT)line);
    out_char(':');
    UnityPrint(Unity.CurrentTestName);
    out_char(':');
}

static void out_fail_head(UNITY_LINE_TYPE line)
{
    out_location(line);
    UnityPrint("FAIL:");
}

static void out_user_message(const char *message)
{
    if (message != NULL)
    {
        UnityPrint(". ");
        UnityPrint(message);
    }
}

static void out_quoted(const char *text, UNITY_UINT32 max_len, int bounded)
{
    if (text == NULL)
    {
        UnityPrint("NULL");
        return;
    }
    out_char('\'');
    if (bounded)
    {
        UnityPrintLen(text, max_len);
    }
    else
    {
        UnityPrint(text);
    }
    out_char('\'');
}

/* =====================================================================
 * Leaving a test
 * =================================================================== */

UNITY_RSM_NORETURN static void finish_failed(const char *message)
{
    out_user_message(message);
    Unity.CurrentTestFailed = 1u;
    UNITY_OUTPUT_FLUSH();
    TEST_ABORT();
}

/* Once a test has failed or been ignored, later checks (for example in
 * tearDown) leave silently so each test reports exactly one result. */
static void skip_if_already_decided(void)
{
    if (Unity.CurrentTestFailed != 0u || Unity.CurrentTestIgnored != 0u)
    {
        TEST_ABORT();
    }
}

/* Common entry checks of the array and memory assertions.  Returns 0 when
 * both pointers are the same (nothing to compare), 1 when the elements must
 * be compared; fails the test for an empty range or a single NULL side. */
static int check_ranges(const void *expected, const void *actual, UNITY_UINT32 count,
                        const char *message, UNITY_LINE_TYPE line)
{
    if (count == 0u)
    {
        out_fail_head(line);
        UnityPrint(" You Asked Me To Compare Nothing, Which Was Pointless.");
        finish_failed(message);
    }
    if (expected == actual)
    {
        return 0;
    }
    if (expected == NULL || actual == NULL)
    {
        out_fail_head(line);
        UnityPrint(expected == NULL ? " Expected pointer to be NULL" : " Actual pointer was NULL");
        finish_failed(message);
    }
    return 1;
}

/* =====================================================================
 * Integer assertions
 * =================================================================== */

static int is_signed_format(unsigned format)
{
    return (format & 0xF0u) == UNITY_RSM_SHOW_SIGNED;
}

/* -1, 0 or 1 as actual is below, equal to or above reference. */
static int order_of(UNITY_INT actual, UNITY_INT reference, unsigned format)
{
    if (is_signed_format(format))
    {
        return (actual > reference) - (actual < reference);
    }
    return ((UNITY_UINT)actual > (UNITY_UINT)reference) - ((UNITY_UINT)actual < (UNITY_UINT)reference);
}

void UnityRsmAssertCompare(UNITY_INT reference, UNITY_INT actual, unsigned op, unsigned format,
                           const char *message, UNITY_LINE_TYPE line)
{
    int order;
    int accepted;

    skip_if_already_decided();

    order = order_of(actual, reference, format);
    accepted = (order == 0 && (op & UNITY_RSM_OP_EQ) != 0u) ||
               (order > 0 && (op & UNITY_RSM_OP_GT) != 0u) ||
               (order < 0 && (op & UNITY_RSM_OP_LT) != 0u);
    if (accepted)
    {
        return;
    }

    out_fail_head(line);
    UnityPrint(" Expected ");
    if (op == UNITY_RSM_OP_EQ)
    {
        out_value(reference, format);
        UnityPrint(" Was ");
        out_value(actual, format);
    }
    else
    {
        out_value(actual, format);
        UnityPrint((op & UNITY_RSM_OP_GT) != 0u ? " to be greater than " : " to be less than ");
        if ((op & UNITY_RSM_OP_EQ) != 0u)
        {
            UnityPrint("or equal to ");
        }
        out_value(reference, format);
    }
    finish_failed(message);
}

void UnityRsmAssertWithin(UNITY_UINT delta, UNITY_INT expected, UNITY_INT actual, unsigned format,
                          const char *message, UNITY_LINE_TYPE line)
{
    UNITY_UINT distance;

    skip_if_already_decided();

    if (order_of(actual, expected, format) > 0)
    {
        distance = (UNITY_UINT)actual - (UNITY_UINT)expected;
    }
    else
    {
        distance = (UNITY_UINT)expected - (UNITY_UINT)actual;
    }
    if (distance <= delta)
    {
        return;
    }

    out_fail_head(line);
    UnityPrint(" Values Not Within Delta ");
    out_value((UNITY_INT)delta, format);
    UnityPrint(" Expected ");
    out_value(expected, format);
    UnityPrint(" Was ");
    out_value(actual, format);
    finish_failed(message);
}

/* Reads one array element of the width given by format; signed kinds are
 * sign-extended, unsigned and hex kinds zero-extended. */
static UNITY_INT load_element(const unsigned char *at, unsigned format)
{
    const int is_signed = is_signed_format(format);

    switch (format & 0x0Fu)
    {
    case 1u:
    {
        UNITY_UINT8 raw;
        memcpy(&raw, at, sizeof raw);
        return is_signed ? (UNITY_INT)(UNITY_INT8)raw : (UNITY_INT)raw;
    }
    case 2u:
    {
        UNITY_UINT16 raw;
        memcpy(&raw, at, sizeof raw);
        return is_signed ? (UNITY_INT)(UNITY_INT16)raw : (UNITY_INT)raw;
    }
    case 8u:
    {
        UNITY_UINT64 raw;
        memcpy(&raw, at, sizeof raw);
        return (UNITY_INT)raw;
    }
    default:
    {
        UNITY_UINT32 raw;
        memcpy(&raw, at, sizeof raw);
        return is_signed ? (UNITY_INT)(UNITY_INT32)raw : (UNITY_INT)raw;
    }
    }
}

void UnityRsmAssertIntArray(const void *expected, const void *actual, UNITY_UINT32 count,
                            unsigned format, const char *message, UNITY_LINE_TYPE line)
{
    const unsigned char *exp_bytes = (const unsigned char *)expected;
    const unsigned char *act_bytes = (const unsigned char *)actual;
    size_t width = format & 0x0Fu;
    UNITY_UINT32 i;

    skip_if_already_decided();
    if (width != 1u && width != 2u && width != 8u)
    {
        width = 4u;
    }
    if (!check_ranges(expected, actual, count, message, line))
    {
        return;
    }

    for (i = 0u; i < count; ++i)
    {
        const UNITY_INT want = load_element(exp_bytes + (size_t)i * width, format);
        const UNITY_INT got = load_element(act_bytes + (size_t)i * width, format);

        if (want != got)
        {
            out_fail_head(line);
            UnityPrint(" Element ");
            UnityPrintNumberUnsigned(i);
            UnityPrint(" Expected ");
            out_value(want, format);
            UnityPrint(" Was ");
            out_value(got, format);
            finish_failed(message);
        }
    }
}

/* =====================================================================
 * Strings and memory
 * =================================================================== */

void UnityRsmAssertString(const char *expected, const char *actual, UNITY_UINT32 max_len,
                          int bounded, const char *message, UNITY_LINE_TYPE line)
{
    int same = 1;

    skip_if_already_decided();

    if (expected != NULL && actual != NULL)
    {
        UNITY_UINT32 i;

        for (i = 0u; (!bounded || i < max_len) && (expected[i] != '\0' || actual[i] != '\0'); ++i)
        {
            if (expected[i] != actual[i])
            {
                same = 0;
                break;
            }
        }
    }
    else
    {
        same = (expected == actual); /* two NULLs are equal */
    }
    if (same)
    {
        return;
    }

    out_fail_head(line);
    UnityPrint(" Expected ");
    out_quoted(expected, max_len, bounded);
    UnityPrint(" Was ");
    out_quoted(actual, max_len, bounded);
    finish_failed(message);
}

void UnityRsmAssertMemory(const void *expected, const void *actual, UNITY_UINT32 length,
                          const char *message, UNITY_LINE_TYPE line)
{
    const unsigned char *exp_bytes = (const unsigned char *)expected;
    const unsigned char *act_bytes = (const unsigned char *)actual;
    UNITY_UINT32 i;

    skip_if_already_decided();
    if (!check_ranges(expected, actual, length, message, line))
    {
        return;
    }

    for (i = 0u; i < length; ++i)
    {
        if (exp_bytes[i] != act_bytes[i])
        {
            out_fail_head(line);
            UnityPrint(" Memory Mismatch. Byte ");
            UnityPrintNumberUnsigned(i);
            UnityPrint(" Expected ");
            out_value((UNITY_INT)exp_bytes[i], UNITY_RSM_FMT_HEX8);
            UnityPrint(" Was ");
            out_value((UNITY_INT)act_bytes[i], UNITY_RSM_FMT_HEX8);
            finish_failed(message);
        }
    }
}

/* =====================================================================
 * Floats
 * =================================================================== */

static UNITY_FLOAT magnitude_of(UNITY_FLOAT value)
{
    return value < 0.0f ? -value : value;
}

/* Two NaNs match, infinities match only themselves, anything else matches
 * when the distance is finite and not above |delta| (a NaN delta accepts). */
static int floats_close(UNITY_FLOAT delta, UNITY_FLOAT expected, UNITY_FLOAT actual)
{
    UNITY_FLOAT distance;

    if (isnan(expected) || isnan(actual))
    {
        return isnan(expected) && isnan(actual);
    }
    if (isinf(expected) || isinf(actual))
    {
        return isinf(expected) && isinf(actual) && ((expected < 0.0f) == (actual < 0.0f));
    }
    distance = magnitude_of(actual - expected);
    if (isinf(distance))
    {
        return 0;
    }
    return !(distance > magnitude_of(delta));
}

UNITY_RSM_NORETURN static void fail_float_pair(UNITY_FLOAT expected, UNITY_FLOAT actual, const char *message,
                            UNITY_LINE_TYPE line)
{
    out_fail_head(line);
    UnityPrint(" Expected ");
    UnityPrintFloat(expected);
    UnityPrint(" Was ");
    UnityPrintFloat(actual);
    finish_failed(message);
}

void UnityRsmAssertFloatWithin(UNITY_FLOAT delta, UNITY_FLOAT expected, UNITY_FLOAT actual,
                               const char *message, UNITY_LINE_TYPE line)
{
    skip_if_already_decided();
    if (!floats_close(delta, expected, actual))
    {
        fail_float_pair(expected, actual, message, line);
    }
}

void UnityRsmAssertFloatEqual(UNITY_FLOAT expected, UNITY_FLOAT actual, UNITY_FLOAT precision,
                              const char *message, UNITY_LINE_TYPE line)
{
    skip_if_already_decided();
    if (!floats_close(expected * precision, expected, actual))
    {
        fail_float_pair(expected, actual, message, line);
    }
}

void UnityRsmAssertFloatOrder(UNITY_FLOAT threshold, UNITY_FLOAT actual, unsigned op,
                              UNITY_FLOAT precision, const char *message, UNITY_LINE_TYPE line)
{
    int accepted;

    skip_if_already_decided();

    /* Written as "is it strictly on the right side" so NaN never passes. */
    accepted = ((op & UNITY_RSM_OP_GT) != 0u && actual > threshold) ||
               ((op & UNITY_RSM_OP_LT) != 0u && actual < threshold);
    if (!accepted && (op & UNITY_RSM_OP_EQ) != 0u)
    {
        accepted = floats_close(threshold * precision, threshold, actual);
    }
    if (accepted)
    {
        return;
    }

    out_fail_head(line);
    UnityPrint(" Expected ");
    UnityPrintFloat(actual);
    UnityPrint((op & UNITY_RSM_OP_GT) != 0u ? " to be greater than " : " to be less than ");
    if ((op & UNITY_RSM_OP_EQ) != 0u)
    {
        UnityPrint("or equal to ");
    }
    UnityPrintFloat(threshold);
    finish_failed(message);
}

void UnityRsmAssertFloatTrait(UNITY_FLOAT actual, unsigned trait, const char *message,
                              UNITY_LINE_TYPE line)
{
    const int wanted = (trait & UNITY_RSM_TRAIT_NOT) == 0u;
    const char *name;
    int present;

    skip_if_already_decided();

    switch (trait & 0x0Fu)
    {
    case UNITY_RSM_TRAIT_INF:
        name = "Infinity";
        present = isinf(actual) && actual > 0.0f;
        break;
    case UNITY_RSM_TRAIT_NEG_INF:
        name = "Negative Infinity";
        present = isinf(actual) && actual < 0.0f;
        break;
    case UNITY_RSM_TRAIT_NAN:
        name = "NaN";
        present = isnan(actual) ? 1 : 0;
        break;
    default:
        name = "Determinate";
        present = !isinf(actual) && !isnan(actual);
        break;
    }
    if (present == wanted)
    {
        return;
    }

    out_fail_head(line);
    UnityPrint(" Expected ");
    if (!wanted)
    {
        UnityPrint("Not ");
    }
    UnityPrint(name);
    UnityPrint(" Was ");
    UnityPrintFloat(actual);
    finish_failed(message);
}

void UnityRsmAssertFloatArray(const UNITY_FLOAT *expected, const UNITY_FLOAT *actual,
                              UNITY_UINT32 count, UNITY_FLOAT precision, const char *message,
                              UNITY_LINE_TYPE line)
{
    UNITY_UINT32 i;

    skip_if_already_decided();
    if (!check_ranges(expected, actual, count, message, line))
    {
        return;
    }

    for (i = 0u; i < count; ++i)
    {
        if (!floats_close(expected[i] * precision, expected[i], actual[i]))
        {
            out_fail_head(line);
            UnityPrint(" Element ");
            UnityPrintNumberUnsigned(i);
            UnityPrint(" Expected ");
            UnityPrintFloat(expected[i]);
            UnityPrint(" Was ");
            UnityPrintFloat(actual[i]);
            finish_failed(message);
        }
    }
}

/* =====================================================================
 * Fail, ignore, message
 * =================================================================== */

void UnityFail(const char *message, UNITY_LINE_TYPE line)
{
    skip_if_already_decided();

    out_location(line);
    UnityPrint("FAIL");
    if (message != NULL)
    {
        out_char(':');
        if (message[0] != ' ')
        {
            out_char(' ');
        }
        UnityPrint(message);
    }
    Unity.CurrentTestFailed = 1u;
    UNITY_OUTPUT_FLUSH();
    TEST_ABORT();
}

void UnityIgnore(const char *message, UNITY_LINE_TYPE line)
{
    skip_if_already_decided();

    out_location(line);
    UnityPrint("IGNORE");
    if (message != NULL)
    {
        UnityPrint(": ");
        UnityPrint(message);
    }
    Unity.CurrentTestIgnored = 1u;
    UNITY_OUTPUT_FLUSH();
    TEST_ABORT();
}

void UnityMessage(const char *message, UNITY_LINE_TYPE line)
{
    out_location(line);
    UnityPrint("INFO");
    if (message != NULL)
    {
        UnityPrint(": ");
        UnityPrint(message);
    }
    out_newline();
}

/* =====================================================================
 * Running tests
 * =================================================================== */

void UnitySetTestFile(const char *filename)
{
    Unity.TestFile = filename;
}

void UnityBegin(const char *filename)
{
    Unity.TestFile = filename;
    Unity.CurrentTestName = NULL;
    Unity.CurrentTestLineNumber = 0u;
    Unity.NumberOfTests = 0u;
    Unity.TestFailures = 0u;
    Unity.TestIgnores = 0u;
    Unity.CurrentTestFailed = 0u;
    Unity.CurrentTestIgnored = 0u;
}

void UnityConcludeTest(void)
{
    if (Unity.CurrentTestIgnored != 0u)
    {
        Unity.TestIgnores++;
    }
    else if (Unity.CurrentTestFailed != 0u)
    {
        Unity.TestFailures++;
    }
    else
    {
        out_location(Unity.CurrentTestLineNumber);
        UnityPrint("PASS");
    }
    Unity.CurrentTestFailed = 0u;
    Unity.CurrentTestIgnored = 0u;
    out_newline(); /* ends the PASS line or the FAIL/IGNORE line printed earlier */
    UNITY_OUTPUT_FLUSH();
}

void UnityDefaultTestRun(UnityTestFunction func, const char *func_name, int func_line)
{
    Unity.CurrentTestName = func_name;
    Unity.CurrentTestLineNumber = (UNITY_LINE_TYPE)func_line;
    Unity.NumberOfTests++;

    /* A failing assertion longjmps back to the matching TEST_PROTECT and
     * the remaining statements of that stage are skipped. */
    if (TEST_PROTECT())
    {
        setUp();
        func();
    }
    if (TEST_PROTECT())
    {
        tearDown();
    }
    UnityConcludeTest();
}

int UnityEnd(void)
{
    out_newline();
    UnityPrint("-----------------------");
    out_newline();
    UnityPrintNumberUnsigned(Unity.NumberOfTests);
    UnityPrint(" Tests ");
    UnityPrintNumberUnsigned(Unity.TestFailures);
    UnityPrint(" Failures ");
    UnityPrintNumberUnsigned(Unity.TestIgnores);
    UnityPrint(" Ignored ");
    out_newline();
    UnityPrint(Unity.TestFailures == 0u ? "OK" : "FAIL");
    out_newline();
    UNITY_OUTPUT_FLUSH();
    return (int)Unity.TestFailures;
}
