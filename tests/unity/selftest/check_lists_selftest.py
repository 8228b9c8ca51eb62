#!/usr/bin/env python3
"""Self-test of tools/check_test_lists.py.

Writes small test sources to a temporary directory, runs the checker on
each and compares its exit status and reported problems with what each
case must produce.  Pure Python 3 standard library.

usage: check_lists_selftest.py PATH/TO/check_test_lists.py
"""

import os
import subprocess
import sys
import tempfile

GOOD = r"""
#include "unity.h"
void setUp(void) {}
void tearDown(void) {}
static int helper(int x) { return x + 1; }
void test_one(void) { TEST_ASSERT_EQUAL_INT(2, helper(1)); }
static void test_two(void)
{
    const char *text = "RUN_TEST(test_not_a_call) { ";
    TEST_ASSERT_NOT_NULL(text);
}
void test_three (void) {}
#if 0
void test_disabled(void) {}
#endif
int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_one);
    RUN_TEST( test_two );
    RUN_TEST(test_three, 99);
    return UNITY_END();
}
"""

MISSING = r"""
#include "unity.h"
void setUp(void) {}
void tearDown(void) {}
void test_listed(void) {}
void test_forgotten(void) {}
void test_commented_out(void) {}
int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_listed);
    /* RUN_TEST(test_commented_out); */
    // RUN_TEST(test_commented_out);
    return UNITY_END();
}
"""

UNDEFINED = r"""
#include "unity.h"
void setUp(void) {}
void tearDown(void) {}
void test_real(void) {}
void test_declared_only(void);
int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_real);
    RUN_TEST(test_typo);
    RUN_TEST(test_declared_only);
    RUN_TEST(test_real);
    return UNITY_END();
}
"""

NO_MAIN = r"""
#include "unity.h"
void test_orphan(void) {}
"""

# (file name, source, expected exit status, substrings that must appear)
CASES = [
    ("test_good.c", GOOD, 0, ["1 file(s), 3 test(s)"]),
    ("test_missing.c", MISSING, 1, [
        "test_missing.c:5: test_forgotten is defined but main() never runs it",
        "test_missing.c:6: test_commented_out is defined but main() never runs it",
    ]),
    ("test_undefined.c", UNDEFINED, 1, [
        "test_undefined.c:10: RUN_TEST(test_typo) names no function",
        "test_undefined.c:11: RUN_TEST(test_declared_only) names no function",
        "test_undefined.c:12: RUN_TEST(test_real) appears 2 times",
    ]),
    ("test_no_main.c", NO_MAIN, 1, ["test_no_main.c:1: no main() found"]),
]

# Lines that must NOT be reported.
FORBIDDEN = ["test_listed", "test_disabled", "test_not_a_call", "test_good.c:"]


def run(checker, *files):
    proc = subprocess.run([sys.executable, checker] + list(files), stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, check=False)
    return proc.returncode, proc.stdout.decode("utf-8", "replace")


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    checker = sys.argv[1]
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for name, source, status, needles in CASES:
            path = os.path.join(tmp, name)
            with open(path, "w", encoding="utf-8") as handle:
                handle.write(source.lstrip("\n"))
            paths.append(path)
            got_status, output = run(checker, path)
            if got_status != status:
                failures.append("%s: exit status %d, expected %d\n%s" % (name, got_status, status, output))
            for needle in needles:
                if needle not in output:
                    failures.append("%s: missing %r in\n%s" % (name, needle, output))
            for needle in FORBIDDEN:
                if needle in output and needle not in "".join(needles):
                    failures.append("%s: unexpected %r in\n%s" % (name, needle, output))

        # Several files at once: any bad file makes the whole run fail.
        got_status, output = run(checker, *paths)
        if got_status != 1 or "3 of 4 file(s)" not in output:
            failures.append("all files: status %d\n%s" % (got_status, output))

        # An unreadable file is a usage error, not a pass.
        got_status, output = run(checker, os.path.join(tmp, "does_not_exist.c"))
        if got_status != 2:
            failures.append("missing file: status %d, expected 2\n%s" % (got_status, output))

    if failures:
        print("check_lists_selftest: %d problem(s)" % len(failures))
        for failure in failures:
            print("----\n" + failure)
        return 1
    print("check_lists_selftest: all %d cases behave as expected" % (len(CASES) + 2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
