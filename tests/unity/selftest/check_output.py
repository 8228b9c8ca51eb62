#!/usr/bin/env python3
"""Run a Unity-style test executable and check its output line by line.

The expected output is derived from marker comments in the test's C source
(see the header of selftest_cases.c for the marker syntax):

* one result line per RUN_TEST, in RUN_TEST order, each preceded by any
  INFO lines of that test, formatted "<file>:<line>:<test>:<text>";
* then an empty line, a line of 23 dashes, "N Tests F Failures I Ignored "
  (with Unity's trailing space) and "OK" or "FAIL";
* and an exit status equal to the number of failures.

Only the directory part of the file name is ignored (compilers differ in
what __FILE__ holds); everything else must match exactly.

With --self-check the script also proves that the comparison is not
vacuous: it perturbs the expectation in several ways and requires every
perturbation to be reported as a mismatch.

Pure Python 3 standard library.
"""

import argparse
import os
import re
import subprocess
import sys

MARKER = re.compile(r"/\*\s*expect(?P<regex>-re)?(?:\[(?P<name>\w+)\])?:\s?(?P<text>.*?)\s*\*/")
SUMMARY = re.compile(r"/\*\s*expect-summary:\s*(?P<text>.*?)\s*\*/")
FUNCTION = re.compile(r"^\s*(?:static\s+)?void\s+(?P<name>\w+)\s*\(\s*void\s*\)")
MAIN = re.compile(r"^\s*int\s+main\s*\(")
RUN_TEST = re.compile(r"\bRUN_TEST\s*\(\s*(?P<name>\w+)\s*(?:,\s*(?P<line>\d+)\s*)?\)")
DASHES = "-" * 23


class AuthoringError(Exception):
    """The markers in the test source are inconsistent."""


class Expected:
    """One expected output line: exact text, or a regular expression."""

    def __init__(self, text, is_regex=False):
        self.text = text
        self.is_regex = is_regex

    def matches(self, line):
        if self.is_regex:
            return re.fullmatch(self.text, line) is not None
        return line == self.text

    def __repr__(self):
        return ("re:" if self.is_regex else "") + repr(self.text)


def verdict_of(text):
    return text.split(":", 1)[0].strip()


def parse_source(path):
    """Return (expected lines, expected exit status) for the source file."""
    base = os.path.basename(path)
    current = None
    runs = []  # (test name, reported line, marker or None)
    own_markers = {}  # test -> markers written inside that test's body
    named_markers = {}  # test -> markers attributed with expect[NAME]
    summary = None

    with open(path, encoding="utf-8") as handle:
        for number, line in enumerate(handle, 1):
            function = FUNCTION.match(line)
            if function:
                current = function.group("name")
            elif MAIN.match(line):
                current = "main"

            stated = SUMMARY.search(line)
            if stated:
                summary = stated.group("text")
                continue

            marker = MARKER.search(line)
            entry = None
            if marker:
                entry = (number, bool(marker.group("regex")), marker.group("text"))

            run = RUN_TEST.search(line)
            if run and current == "main":
                if marker and marker.group("name"):
                    raise AuthoringError("%s:%d: expect[NAME] on a RUN_TEST line" % (base, number))
                reported = int(run.group("line")) if run.group("line") else number
                runs.append((run.group("name"), reported, entry))
                continue

            if entry is None:
                continue
            if marker.group("name"):
                named_markers.setdefault(marker.group("name"), []).append(entry)
            elif current is None or current == "main":
                raise AuthoringError("%s:%d: marker outside a test function" % (base, number))
            else:
                own_markers.setdefault(current, []).append(entry)

    run_names = [name for name, _, _ in runs]
    for owner in list(own_markers) + list(named_markers):
        if owner not in run_names:
            raise AuthoringError("%s: markers for %s, which is never run" % (base, owner))
    if summary is None:
        raise AuthoringError("%s: no expect-summary marker" % base)

    lines = []
    failures = ignores = 0
    for name, reported, run_marker in runs:
        entries = [(n, r, t) for (n, r, t) in own_markers.get(name, [])]
        entries += named_markers.get(name, [])
        if run_marker is not None:
            entries.append((reported, run_marker[1], run_marker[2]))
        verdicts = [verdict_of(text) for (_, _, text) in entries if verdict_of(text) != "INFO"]
        if len(verdicts) != 1 or verdict_of(entries[-1][2]) != verdicts[0]:
            raise AuthoringError(
                "%s: test %s needs exactly one final PASS/FAIL/IGNORE marker, has %r"
                % (base, name, verdicts))
        if verdicts[0] == "PASS" and run_marker is None:
            raise AuthoringError("%s: PASS for %s belongs on its RUN_TEST line" % (base, name))
        if verdicts[0] not in ("PASS", "FAIL", "IGNORE"):
            raise AuthoringError("%s: unknown verdict %r for %s" % (base, verdicts[0], name))
        failures += verdicts[0] == "FAIL"
        ignores += verdicts[0] == "IGNORE"
        for number, is_regex, text in entries:
            prefix = "%s:%d:%s:" % (base, number, name)
            if is_regex:
                lines.append(Expected(re.escape(prefix) + text, True))
            else:
                lines.append(Expected(prefix + text))

    computed = "%d Tests %d Failures %d Ignored" % (len(runs), failures, ignores)
    if summary != computed:
        raise AuthoringError("%s: expect-summary says %r but the markers add up to %r"
                             % (base, summary, computed))
    lines += [Expected(""), Expected(DASHES), Expected(computed + " "),
              Expected("OK" if failures == 0 else "FAIL")]
    return lines, failures


def run_binary(command, base, timeout):
    try:
        proc = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        print("check_output: %s did not finish within %d s" % (command[0], timeout))
        sys.exit(1)
    text = proc.stdout.decode("utf-8", "replace")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    strip_dir = re.compile(r"^.*[/\\](?=" + re.escape(base) + r":)")
    lines = [strip_dir.sub("", line.rstrip("\r")) for line in lines]
    return lines, proc.returncode, proc.stderr.decode("utf-8", "replace"), text


def compare(expected, actual, want_status, status):
    """Return a list of human-readable problems (empty when all matches)."""
    problems = []
    for index in range(max(len(expected), len(actual))):
        want = expected[index] if index < len(expected) else None
        got = actual[index] if index < len(actual) else None
        if want is None:
            problems.append("output line %d is extra: %r" % (index + 1, got))
        elif got is None:
            problems.append("output line %d is missing, expected %r" % (index + 1, want))
        elif not want.matches(got):
            problems.append("output line %d differs:\n    expected %r\n    actual   %r"
                            % (index + 1, want, got))
    if status is None or status < 0:
        problems.append("the test program died (status %r)" % status)
    elif status != want_status % 256:
        problems.append("exit status %d, expected %d" % (status, want_status % 256))
    return problems


def perturbations(expected, want_status):
    """Yield (description, expected lines, expected status) that must all fail."""
    first = expected[0]
    changed = Expected(first.text + "x", first.is_regex)
    yield "one character appended to the first line", [changed] + expected[1:], want_status
    yield "first line dropped", expected[1:], want_status
    yield "last result line dropped", expected[:-5] + expected[-4:], want_status
    if len(expected) > 5:
        swapped = list(expected)
        swapped[0], swapped[1] = swapped[1], swapped[0]
        yield "first two lines swapped", swapped, want_status
    yield "exit status off by one", expected, want_status + 1
    final = Expected("FAIL" if expected[-1].text == "OK" else "OK")
    yield "final verdict flipped", expected[:-1] + [final], want_status


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", required=True, help="C source holding the expect markers")
    parser.add_argument("--timeout", type=int, default=60, help="seconds before giving up")
    parser.add_argument("--self-check", action="store_true",
                        help="also require that perturbed expectations are rejected")
    parser.add_argument("command", nargs=argparse.REMAINDER,
                        help="-- followed by the test executable and its arguments")
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no test executable given")

    try:
        expected, want_status = parse_source(args.source)
    except AuthoringError as error:
        print("check_output: bad expectations: %s" % error)
        return 2

    base = os.path.basename(args.source)
    actual, status, stderr, raw = run_binary(command, base, args.timeout)
    problems = compare(expected, actual, want_status, status)
    if problems:
        print("check_output: %s does not behave as %s expects" % (command[0], base))
        print("---- output ----")
        sys.stdout.write(raw)
        if stderr:
            print("---- stderr ----")
            sys.stdout.write(stderr)
        print("---- problems ----")
        for problem in problems:
            print(problem)
        return 1

    if args.self_check:
        missed = []
        for description, lines, status_wanted in perturbations(expected, want_status):
            if not compare(lines, actual, status_wanted, status):
                missed.append(description)
        if missed:
            print("check_output: the comparison failed to notice: %s" % ", ".join(missed))
            return 1
        print("check_output: comparison rejects every perturbed expectation")

    print("check_output: %d output lines and exit status %d match %s"
          % (len(expected), status, base))
    return 0


if __name__ == "__main__":
    sys.exit(main())
