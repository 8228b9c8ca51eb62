"""The README's and the public headers' figures agree with the bench's last
manifest (issue 32).

A figure typed into prose goes stale: the localizer header said "about 48
KiB" long after the state had grown to 125 KiB. ./tools/bench (and
rsm-bench-report) writes the figures these texts quote from its manifest
into docs/results/figures.json; this test reads the README and
include/rsm/*.h and fails when one of them states a number that file
contradicts, or states a measured figure (metres, degrees, bytes, KiB,
instructions) that no check here covers, so that a new one cannot slip in
unchecked.
"""

import json
import re
from pathlib import Path
from typing import Callable, Dict, List, Tuple

import pytest

from conftest import REPO_ROOT

from rsm_tools.bench import figures as bench_figures

FIGURES = REPO_ROOT / "docs" / "results" / "figures.json"
README = REPO_ROOT / "README.md"
HEADERS = REPO_ROOT / "include" / "rsm"

# A number as the texts write it (thousands apart by a space) and a unit the bench measures in.
MEASURED = re.compile(r"(?<![\w.])(\d{1,3}(?: \d{3})+|\d+(?:\.\d+)?) ?(m|°|KiB|bytes|instructions)(?!\w)")

# Figures in the headers that are arithmetic on the capacities, not measurements.
HEADER_ARITHMETIC = {("config.h", "2 KiB"), ("config.h", "8 KiB"), ("config.h", "1.34 bytes")}


@pytest.fixture(scope="module")
def fig() -> dict:
    return json.loads(FIGURES.read_text(encoding="utf-8"))


def number(text: str) -> float:
    return float(text.replace(" ", ""))


def shown(text: str, value: float) -> bool:
    """``text`` is ``value`` rounded to the digits it shows."""
    t = text.replace(" ", "")
    decimals = len(t.split(".", 1)[1]) if "." in t else 0
    return abs(float(t) - value) <= 0.5 * 10 ** -decimals * (1 + 1e-9)


def about(text: str, value: float) -> bool:
    """"about N": within 5 %."""
    return abs(number(text) - value) <= 0.05 * value


def kib(b: float) -> float:
    return b / 1024.0


def test_rounding_rules():
    assert shown("0.0152", 0.015166) and not shown("0.0153", 0.015166)
    assert shown("2.19", 2.1881) and shown("127 880", 127880) and not shown("127 880", 127904)
    assert about("125", kib(127880)) and not about("48", kib(127880))


# ---- the README ------------------------------------------------------------------------------

ROW_METHOD = {"rsm": "rsm", "rsm, config_small.h": "rsm-small", "the paper's method": "paper",
              "odometry alone": "odometry", "best peer": "best peer"}
COLUMNS = (("all_translation", "m"), ("all_rotation", "°"), ("local_translation", "m"), ("local_rotation", "°"))
CELL = re.compile(r"^(\d+(?:\.\d+)?) ?(m|°)(?: \((.+)\))?$")


def readme_table(text: str, fig: dict) -> Tuple[List[Tuple[int, int]], List[str], int]:
    """Checks every cell of the README's results table; returns the spans
    checked, the disagreements, and the number of rows."""
    spans, bad, rows = [], [], 0
    for m in re.finditer(r"^\| (Intel|ACES) \|(.+)\|$", text, re.M):
        log = m.group(1).lower()
        cells = [c.strip() for c in m.group(2).split("|")]
        method = ROW_METHOD.get(cells[0].replace("*", "").replace("`", "").strip())
        if method is None:
            bad.append(f"README: a results row of an unknown method: {m.group(0)}")
            continue
        rows += 1
        want = fig["accuracy"][log][method]
        for (key, unit), cell in zip(COLUMNS, cells[1:]):
            c = CELL.match(cell.replace("**", "").strip())
            if not c or c.group(2) != unit:
                bad.append(f"README: {log} {method} {key}: cannot read {cell!r}")
                continue
            value, peer = (want[key]["value"], want[key]["method"]) if method == "best peer" else (want[key], None)
            if not shown(c.group(1), value) or c.group(3) != peer:
                bad.append(f"README: {log} {method} {key} says {cell!r}; the manifest: {value:.6g}"
                           + (f" ({peer})" if peer else ""))
        spans.append(m.span())
    return spans, bad, rows


Check = Callable[[dict, List[str]], List[bool]]

# Each sentence of the README that quotes the bench, and what each of its numbers must agree with.
README_PROSE: List[Tuple[str, Check]] = [
    (r"state is ([\d ]+) bytes with the default\s+capacities and ([\d ]+) bytes with `rsm/config_small\.h`",
     lambda f, g: [shown(g[0], f["m4_state_bytes"]["default"]), shown(g[1], f["m4_state_bytes"]["small"])]),
    (r"at\s+most ([\d ]+) bytes of\s+stack \(static bound\)",
     lambda f, g: [shown(g[0], f["m4_stack_bound_bytes"]["rsm_localizer_scan"])]),
    (r"([\d ]+)\s+instructions per scan on average, ([\d ]+) at the 99th percentile",
     lambda f, g: [shown(g[0], f["m4_instructions_per_scan"]["mean"]),
                   shown(g[1], f["m4_instructions_per_scan"]["p99"])]),
    (r"static rsm_localizer_t loc; +/\* about (\d+) KiB",
     lambda f, g: [about(g[0], kib(f["m4_state_bytes"]["default"]))]),
    (r"commit `([0-9a-f]{7,12})`, (\d{4}-\d\d-\d\d)\)",
     lambda f, g: [f["provenance"]["commit"].startswith(g[0]), f["provenance"]["date"].startswith(g[1])]),
]


def check_prose(name: str, text: str, rules, fig: dict) -> Tuple[List[Tuple[int, int]], List[str]]:
    spans, bad = [], []
    for pattern, check in rules:
        found = list(re.finditer(pattern, text))
        if not found:
            bad.append(f"{name}: no sentence matches {pattern!r} (reworded? then change its check here)")
        for m in found:
            if not all(check(fig, list(m.groups()))):
                bad.append(f"{name}: {m.group(0)!r} disagrees with the manifest")
            spans.append(m.span())
    return spans, bad


def unchecked(name: str, text: str, spans: List[Tuple[int, int]], allowed=()) -> List[str]:
    out = []
    for m in MEASURED.finditer(text):
        if any(a <= m.start() and m.end() <= b for a, b in spans) or m.group(0) in allowed:
            continue
        line = text.count("\n", 0, m.start()) + 1
        out.append(f"{name}:{line}: {m.group(0)!r} is checked against nothing (add a check here or drop it)")
    return out


def test_readme_figures_agree_with_the_manifest(fig):
    text = README.read_text(encoding="utf-8")
    spans, bad, rows = readme_table(text, fig)
    assert rows >= 8, "the README's results table is gone or unreadable"
    prose_spans, prose_bad = check_prose("README.md", text, README_PROSE, fig)
    bad += prose_bad + unchecked("README.md", text, spans + prose_spans)
    assert not bad, "\n".join(bad)


# ---- the headers -----------------------------------------------------------------------------

HEADER_PROSE: Dict[str, List[Tuple[str, Check]]] = {
    "localizer.h": [(r"about (\d+) KiB with the\s+default config\.h and (\d+) KiB with rsm/config_small\.h "
                     r"on a 32-bit target",
                     lambda f, g: [about(g[0], kib(f["m4_state_bytes"]["default"])),
                                   about(g[1], kib(f["m4_state_bytes"]["small"]))])],
    "config_small.h": [(r"microcontrollers with (\d+) KiB of RAM to spare",
                        lambda f, g: [f["m4_state_bytes"]["small"] <= number(g[0]) * 1024]),
                       (r"Under (\d+) KiB of localizer\s+state",
                        lambda f, g: [f["m4_state_bytes"]["small"] < number(g[0]) * 1024])],
    "config_host.h": [(r"About (\d+) KiB of state",
                       lambda f, g: [about(g[0], kib(f["host_state_bytes"]["config_host"]))])],
}


def comment_text(path: Path) -> str:
    """The header with comment leaders ("\\n * ") folded into spaces, so a
    sentence wrapped over lines reads as one."""
    return re.sub(r"\n[ \t]*\*(?!/)[ \t]?", " ", path.read_text(encoding="utf-8"))


def test_header_figures_agree_with_the_manifest(fig):
    bad = []
    for path in sorted(HEADERS.glob("*.h")):
        text = comment_text(path)
        spans, b = check_prose(path.name, text, HEADER_PROSE.get(path.name, []), fig)
        bad += b
        allowed = {t for n, t in HEADER_ARITHMETIC if n == path.name}
        # Bytes in the headers are mostly protocol lengths; state sizes are
        # given in KiB or as "about N bytes", and those are measured.
        for m in MEASURED.finditer(text):
            figure = m.group(0)
            approx = text[max(0, m.start() - 6):m.start()].lower().endswith("about ")
            if (m.group(2) == "KiB" or (m.group(2) == "bytes" and approx)) and figure not in allowed \
                    and not any(a <= m.start() and m.end() <= e for a, e in spans):
                bad.append(f"{path.name}: {figure!r} is checked against nothing (add a check here or drop it)")
    assert not bad, "\n".join(bad)


# ---- the file itself -------------------------------------------------------------------------

def test_the_figures_file_is_the_extract_of_a_manifest(fig):
    """figures.json holds what rsm_tools.bench.figures takes from a
    manifest, and nothing of the machine it ran on but its description."""
    assert fig["command"] == "./tools/bench"
    assert set(fig["accuracy"]) >= {"intel", "aces"}
    for log in ("intel", "aces"):
        assert set(fig["accuracy"][log]) >= {"rsm", "rsm-small", "paper", "odometry", "best peer"}

    def strings(o):
        if isinstance(o, dict):
            return [s for v in o.values() for s in strings(v)]
        if isinstance(o, list):
            return [s for v in o for s in strings(v)]
        return [o] if isinstance(o, str) else []

    # No file of the machine the bench ran on: only its description.
    assert not [s for s in strings(fig) if "/" in s and not s.startswith("./tools/")]


def test_extract_takes_the_quoted_figures_from_a_manifest():
    errors = {sc: {q: {"mean": v} for q, v in (("translation", t), ("rotation", r))}
              for sc, t, r in (("all", 0.5, 5.0), ("local", 0.01, 0.2))}
    peers = [{"kind": "peer", "method": "P", "values": {("all", "translation"): 0.4, ("all", "rotation"): 6.0,
                                                         ("local", "translation"): 0.02,
                                                         ("local", "rotation"): 0.1}},
             {"kind": "peer", "method": "Q", "values": {("all", "translation"): 0.3, ("all", "rotation"): 7.0,
                                                         ("local", "translation"): 0.03,
                                                         ("local", "rotation"): 0.3}},
             {"kind": "odometry", "method": "odometry alone", "values": {("all", "translation"): 0.1}}]
    ctx = {"provenance": {"commit": "abc1234", "date": "2026-01-02 03:04 UTC", "cpu": "c", "cores": 2,
                          "compiler": "g", "build_flags": "-O3", "python": "3"},
           "accuracy": {"intel": {"runs": {"rsm": {"errors": errors}, "odometry": {"errors": errors}}}},
           "peers": {"accuracy": {"intel": peers}},
           "arm_memory": {"configs": {"default": {"state": [{"label": "rsm_localizer_t (all of the below)",
                                                             "bytes": 1000}, {"label": "  ekf", "bytes": 64}],
                                                  "stack": {"rsm_localizer_scan": {"bytes": 96}}}}},
           "m4": {"cost": {"scans": 3, "mean": 10.0, "p95": 11.0, "p99": 12.0, "max": 13.0, "stack_used": 90}}}
    out = bench_figures.extract(ctx)
    assert out["provenance"] == {"commit": "abc1234", "date": "2026-01-02 03:04 UTC", "cpu": "c", "cores": 2,
                                 "compiler": "g", "build_flags": "-O3"}
    assert out["accuracy"]["intel"]["rsm"]["all_translation"] == 0.5
    assert out["accuracy"]["intel"]["rsm"]["local_rotation"] == 0.2
    best = out["accuracy"]["intel"]["best peer"]
    assert best["all_translation"] == {"value": 0.3, "method": "Q"}  # odometry alone is no peer
    assert best["all_rotation"] == {"value": 6.0, "method": "P"}
    assert out["m4_state_bytes"] == {"default": 1000}
    assert out["m4_stack_bound_bytes"] == {"rsm_localizer_scan": 96}
    assert out["m4_instructions_per_scan"]["p99"] == 12.0 and "host_state_bytes" not in out
