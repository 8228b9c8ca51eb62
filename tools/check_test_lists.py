#!/usr/bin/env python3
"""Check that hand-written Unity test mains run every test in their file.

rsm's unit tests (tests/unit/test_*.c) are plain Unity test files with a
hand-written main() instead of a generated runner.  This check keeps those
mains honest.  For every file given:

* each function defined at file scope as ``void test_xxx(void)`` (``static``
  allowed) must be run by a ``RUN_TEST(test_xxx)`` inside that file's main();
* each ``RUN_TEST(name)`` in main() must name a ``void name(void)`` function
  defined in the same file;
* no test may be run twice, and the file must have a main().

Comments, string literals and ``#if 0`` blocks are ignored, so a commented
out RUN_TEST does not count.  Problems are printed as ``file:line: message``
and the exit status is 1; 0 means every file is consistent; 2 means a usage
error (for example a file that cannot be read).

With no file arguments, tests/unit/test_*.c below the repository root (the
parent of this script's directory) are checked.

Pure Python 3 standard library.
"""

import argparse
import pathlib
import re
import sys

VOID_FUNCTION = re.compile(
    r"(?:\bstatic\s+)?(?:\binline\s+)?\bvoid\s+(?P<name>[A-Za-z_]\w*)\s*\(\s*(?:void)?\s*\)\s*$")
MAIN_FUNCTION = re.compile(r"\bint\s+main\s*\([^()]*\)\s*$")
RUN_TEST = re.compile(r"\bRUN_TEST\s*\(\s*(?P<name>[A-Za-z_]\w*)")
CONDITIONAL = re.compile(r"^\s*#\s*(?P<directive>if|ifdef|ifndef|elif|else|endif)\b(?P<rest>.*)$")


def blank(text):
    """Spaces in place of every character except newlines (keeps line numbers)."""
    return re.sub(r"[^\n]", " ", text)


def strip_comments_and_literals(source):
    """Replace comments and the contents of string/char literals by blanks."""
    out = []
    i = 0
    length = len(source)
    while i < length:
        two = source[i:i + 2]
        char = source[i]
        if two == "//":
            end = source.find("\n", i)
            end = length if end < 0 else end
            out.append(blank(source[i:end]))
            i = end
        elif two == "/*":
            end = source.find("*/", i + 2)
            end = length if end < 0 else end + 2
            out.append(blank(source[i:end]))
            i = end
        elif char in "\"'":
            j = i + 1
            while j < length and source[j] != char and source[j] != "\n":
                j += 2 if source[j] == "\\" else 1
            j = min(j + 1, length)
            out.append(char + blank(source[i + 1:j - 1]) + (source[j - 1] if j - 1 > i else ""))
            i = j
        else:
            out.append(char)
            i += 1
    return "".join(out)


def drop_if_zero_blocks(text):
    """Blank the lines inside ``#if 0`` groups (other conditionals stay)."""
    lines = text.split("\n")
    stack = []  # one entry per open conditional: True when that group is disabled
    for index, line in enumerate(lines):
        match = CONDITIONAL.match(line)
        if match:
            directive = match.group("directive")
            if directive in ("if", "ifdef", "ifndef"):
                stack.append(directive == "if" and match.group("rest").strip() == "0")
            elif directive in ("elif", "else") and stack:
                stack[-1] = False
            elif directive == "endif" and stack:
                stack.pop()
            lines[index] = ""
        elif any(stack):
            lines[index] = blank(line)
    return "\n".join(lines)


def line_of(text, index):
    return text.count("\n", 0, index) + 1


def scan(text):
    """Return (void functions {name: line}, main body (start, end) or None)."""
    functions = {}
    main_body = None
    depth = 0
    chunk_start = 0  # where the current file-scope declaration started
    open_at = None
    for index, char in enumerate(text):
        if char == "{":
            if depth == 0:
                head = text[chunk_start:index]
                function = VOID_FUNCTION.search(head)
                if function and function.group("name") not in functions:
                    functions[function.group("name")] = line_of(text, chunk_start + function.start("name"))
                open_at = index if MAIN_FUNCTION.search(head) else None
            depth += 1
        elif char == "}":
            depth = max(depth - 1, 0)
            if depth == 0:
                if open_at is not None and main_body is None:
                    main_body = (open_at, index)
                open_at = None
                chunk_start = index + 1
        elif char == ";" and depth == 0:
            chunk_start = index + 1
    return functions, main_body


def check_file(path):
    """Return (problems, number of tests) for one source file."""
    source = path.read_text(encoding="utf-8", errors="replace")
    text = drop_if_zero_blocks(strip_comments_and_literals(source))
    functions, main_body = scan(text)
    tests = {name: line for name, line in functions.items() if name.startswith("test_")}
    problems = []

    if main_body is None:
        problems.append((1, "no main() found, so none of its %d tests run" % len(tests)))
        return problems, len(tests)

    runs = {}
    start, end = main_body
    for match in RUN_TEST.finditer(text, start, end):
        runs.setdefault(match.group("name"), []).append(line_of(text, match.start()))

    for name, line in sorted(tests.items(), key=lambda item: item[1]):
        if name not in runs:
            problems.append((line, "%s is defined but main() never runs it: add RUN_TEST(%s);"
                             % (name, name)))
    for name, lines in sorted(runs.items(), key=lambda item: item[1][0]):
        if name not in functions:
            problems.append((lines[0], "RUN_TEST(%s) names no function 'void %s(void)' defined in "
                             "this file" % (name, name)))
        if len(lines) > 1:
            problems.append((lines[1], "RUN_TEST(%s) appears %d times in main()"
                             % (name, len(lines))))
    problems.sort()
    return problems, len(tests)


def default_files():
    root = pathlib.Path(__file__).resolve().parent.parent
    return sorted((root / "tests" / "unit").glob("test_*.c"))


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Check that every test_* function of a Unity test file is run from its main().")
    parser.add_argument("files", nargs="*", type=pathlib.Path,
                        help="test sources (default: tests/unit/test_*.c of this repository)")
    parser.add_argument("-q", "--quiet", action="store_true", help="print problems only")
    args = parser.parse_args(argv)

    files = args.files or default_files()
    if not files:
        print("check_test_lists: no test sources found (looked for tests/unit/test_*.c)")
        return 0

    failed_files = 0
    test_count = 0
    for path in files:
        try:
            problems, tests = check_file(path)
        except OSError as error:
            print("check_test_lists: cannot read %s: %s" % (path, error.strerror or error),
                  file=sys.stderr)
            return 2
        test_count += tests
        if problems:
            failed_files += 1
            for line, message in problems:
                print("%s:%d: %s" % (path, line, message))

    if failed_files:
        print("check_test_lists: %d of %d file(s) have tests that main() does not run as written"
              % (failed_files, len(files)))
        return 1
    if not args.quiet:
        print("check_test_lists: %d file(s), %d test(s), every test is run from main()"
              % (len(files), test_count))
    return 0


if __name__ == "__main__":
    sys.exit(main())
