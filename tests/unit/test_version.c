/* Unit tests for src/core/version.c: the library names the version its headers
 * carry, and the string is the three numbers. */
#include <stdio.h>
#include <string.h>

#include "rsm/rsm.h"
#include "unity.h"

void setUp(void)
{
}

void tearDown(void)
{
}

void test_version_should_be_the_headers_string(void)
{
    TEST_ASSERT_NOT_NULL(rsm_version());
    TEST_ASSERT_EQUAL_STRING(RSM_VERSION_STRING, rsm_version());
}

void test_version_string_should_be_major_minor_patch(void)
{
    char want[32];
    const int n = snprintf(want, sizeof want, "%d.%d.%d", RSM_VERSION_MAJOR, RSM_VERSION_MINOR, RSM_VERSION_PATCH);
    TEST_ASSERT_TRUE(n > 0 && (size_t)n < sizeof want);
    TEST_ASSERT_EQUAL_STRING(want, RSM_VERSION_STRING);
    TEST_ASSERT_EQUAL_STRING(want, rsm_version());
}

/* CMake read the numbers into project(VERSION); tests/CMakeLists.txt hands
 * PROJECT_VERSION to this file, so the package files and rsm.pc, which take
 * theirs from it, carry the header's version. */
void test_version_should_be_cmakes_project_version(void)
{
#ifdef RSM_TEST_PROJECT_VERSION
    TEST_ASSERT_EQUAL_STRING(RSM_TEST_PROJECT_VERSION, RSM_VERSION_STRING);
#else
    TEST_FAIL_MESSAGE("built without RSM_TEST_PROJECT_VERSION");
#endif
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_version_should_be_the_headers_string);
    RUN_TEST(test_version_string_should_be_major_minor_patch);
    RUN_TEST(test_version_should_be_cmakes_project_version);
    return UNITY_END();
}
