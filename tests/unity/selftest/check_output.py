#!/usr/bin/env python3
"""Run a Unity-style test executable and check how it behaved.

The expected behaviour is derived from marker comments in the test's C
source (see the header of selftest_cases.c for the marker syntax):

* one result per RUN_TEST, in RUN_TEST order, each preceded by any INFO
  lines of that test: its verdict (PASS, FAIL, IGNORE, INFO), the test's
  name and the source line it points at (the failing assertion, the
  ignore, the message; for a PASS the RUN_TEST line);
* a message the test itself passed (the last string literal of a
  ..._MESSAGE(...) call on the marked line) must appear in that result;
* the counts "N Tests F Failures I Ignored", the final OK or FAIL, and an
  exit status equal to the number of failures.

The wording Unity adds (e.g. "Expected 3 Was 4", its punctuation, extra
details such as "Character N", how NaN is spelled) is not checked: it
differs between Unity releases (2.6 and 2.7 do), while the behaviour above
does not. Lines of other forms are ignored.

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


class AuthoringError(Exception):
    """The markers in the test source are inconsistent."""


RESULT = re.compile(r"^(?P<line>\d+):(?P<test>\w+):(?P<verdict>PASS|FAIL|IGNORE|INFO)(?P<rest>.*)$")
COUNTS = re.compile(r"(?P<tests>\d+)\s+Tests\s+(?P<failures>\d+)\s+Failures\s+(?P<ignored>\d+)\s+Ignored")
MESSAGE_CALL = re.compile(r"\w*MESSAGE\s*\(")
STRING = re.compile(r'"((?:[^"\\]|\\.)*)"')


class Result:
    """One result of a run: verdict, test, source line and the text after the verdict."""

    def __init__(self, verdict, test, line, message=None):
        self.verdict = verdict
        self.test = test
        self.line = line
        self.message = message

    def key(self):
        return (self.verdict, self.test, self.line)

    def __repr__(self):
        return "%s:%d:%s" % (self.test, self.line, self.verdict) + (
            " with %r" % self.message if self.message else "")


class Expected(Result):
    """An expected result; its message, when the test passed one, must appear in the actual one."""

    def matches(self, result):
        if result is None or self.key() != result.key():
            return False
        return self.message is None or squash(self.message) in squash(result.message or "")


def squash(text):
    """Text without whitespace: Unity releases differ in the spaces around messages."""
    return re.sub(r"\s+", "", text)


def user_message(source_line):
    """The message a ..._MESSAGE(...) call on this line passes (its last string literal), if any."""
    if not MESSAGE_CALL.search(source_line):
        return None
    literals = STRING.findall(source_line.split("/*")[0])
    message = literals[-1].strip() if literals else ""
    return message or None


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
    with open(path, encoding="utf-8") as handle:
        source = handle.read().split("\n")
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
        for number, _, text in entries:
            message = user_message(source[number - 1]) if number != reported else None
            lines.append(Expected(verdict_of(text), name, number, message))

    computed = "%d Tests %d Failures %d Ignored" % (len(runs), failures, ignores)
    if summary != computed:
        raise AuthoringError("%s: expect-summary says %r but the markers add up to %r"
                             % (base, summary, computed))
    return Behaviour(lines, (len(runs), failures, ignores), "OK" if failures == 0 else "FAIL"), failures


class Behaviour:
    """Results in order, the counts (tests, failures, ignored) and the final verdict."""

    def __init__(self, results, counts, final):
        self.results = results
        self.counts = counts
        self.final = final


def behaviour_of(lines):
    """What a run's output says: its results, its counts, its final verdict."""
    results, counts, final = [], None, None
    for line in lines:
        m = RESULT.match(line)
        if m:
            results.append(Result(m.group("verdict"), m.group("test"), int(m.group("line")), m.group("rest")))
            continue
        c = COUNTS.search(line)
        if c:
            counts = (int(c.group("tests")), int(c.group("failures")), int(c.group("ignored")))
            continue
        word = line.strip()
        if counts is not None and word in ("OK", "FAIL", "FAILED"):
            final = "FAIL" if word.startswith("FAIL") else "OK"
    return Behaviour(results, counts, final)


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
    # Results of this source only, without its file name (compilers differ in what __FILE__ holds).
    own = re.compile(r"^(?:.*[/\\])?" + re.escape(base) + r":")
    lines = [own.sub("", line.rstrip("\r")) if own.match(line) else line.rstrip("\r") for line in lines]
    return lines, proc.returncode, proc.stderr.decode("utf-8", "replace"), text


def compare(expected, actual_lines, want_status, status):
    """Return a list of human-readable problems (empty when all matches)."""
    problems = []
    actual = behaviour_of(actual_lines)
    for index in range(max(len(expected.results), len(actual.results))):
        want = expected.results[index] if index < len(expected.results) else None
        got = actual.results[index] if index < len(actual.results) else None
        if want is None:
            problems.append("result %d is extra: %r" % (index + 1, got))
        elif got is None:
            problems.append("result %d is missing, expected %r" % (index + 1, want))
        elif not want.matches(got):
            problems.append("result %d differs:\n    expected %r\n    actual   %r" % (index + 1, want, got))
    if actual.counts != expected.counts:
        problems.append("counts (tests, failures, ignored) %r, expected %r" % (actual.counts, expected.counts))
    if actual.final != expected.final:
        problems.append("final verdict %r, expected %r" % (actual.final, expected.final))
    if status is None or status < 0:
        problems.append("the test program died (status %r)" % status)
    elif status != want_status % 256:
        problems.append("exit status %d, expected %d" % (status, want_status % 256))
    return problems


def perturbations(expected, want_status):
    """Yield (description, expected behaviour, expected status) that must all fail."""
    res = expected.results

    def variant(results=None, counts=None, final=None):
        return Behaviour(res if results is None else results, counts or expected.counts, final or expected.final)

    first = res[0]
    other = "FAIL" if first.verdict != "FAIL" else "PASS"
    yield "first verdict changed", variant([Expected(other, first.test, first.line, first.message)] + res[1:]), \
        want_status
    yield "first line number off by one", variant([Expected(first.verdict, first.test, first.line + 1,
                                                            first.message)] + res[1:]), want_status
    yield "first test renamed", variant([Expected(first.verdict, first.test + "x", first.line,
                                                  first.message)] + res[1:]), want_status
    with_message = [i for i, e in enumerate(res) if e.message]
    if with_message:
        i = with_message[0]
        e = res[i]
        changed = list(res)
        changed[i] = Expected(e.verdict, e.test, e.line, e.message + "x")
        yield "a message changed", variant(changed), want_status
    yield "first result dropped", variant(res[1:]), want_status
    yield "last result dropped", variant(res[:-1]), want_status
    if len(res) > 1:
        yield "first two results swapped", variant([res[1], res[0]] + res[2:]), want_status
    tests, failures, ignored = expected.counts
    yield "ignored count off by one", variant(counts=(tests, failures, ignored + 1)), want_status
    yield "exit status off by one", expected, want_status + 1
    yield "final verdict flipped", variant(final="FAIL" if expected.final == "OK" else "OK"), want_status


def rewordings(lines):
    """Yield (description, output) that say the same in other words, as other
    Unity releases do; the comparison must accept them all."""
    yield "no space after the verdict's colon", [re.sub(r":(PASS|FAIL|IGNORE|INFO): ", r":\1:", l) for l in lines]
    yield "details appended to every failure", [l + " Character 3." if RESULT.match(l) and ":FAIL" in l else l
                                                 for l in lines]
    yield "other spellings of special values", [re.sub(r"\b(nan|inf)\b", lambda m: m.group(1).upper(), l)
                                                for l in lines]
    yield "assertion texts reworded", [re.sub(r"Expected ", "Wanted ", l) for l in lines]


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
        refused = [d for d, lines in rewordings(actual) if compare(expected, lines, want_status, status)]
        if refused:
            print("check_output: the comparison depends on wording: %s" % ", ".join(refused))
            return 1
        messages = sum(1 for e in expected.results if e.message)
        print("check_output: comparison rejects every perturbed expectation and accepts every rewording "
              "(%d results carry a message of the test's own)" % messages)

    print("check_output: %d results, the counts and exit status %d match %s"
          % (len(expected.results), status, base))
    return 0


if __name__ == "__main__":
    sys.exit(main())
