"""Tests of rsm-bench's report machinery on the shipped excerpt.

The bench runs once (module fixture) in quick settings on
tests/data/intel_head.clf.gz with rsm-nav from RSM_BUILD_DIR (ctest sets it),
plus one extra log made here (the excerpt with 10 % outliers). The tests then
read the report back and check every figure against what evaluate() computes
from the trajectories the bench kept, and against the raw outputs of rsm-nav
and callgrind: no expected number is typed into this file.
"""

import json
import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO_ROOT, subprocess_env
from rsm_tools import bench
from rsm_tools import evaluate as ev
from rsm_tools import outliers

LEVELS = (0, 43)
SEEDS = 2


def build_dir() -> Path:
    build = os.environ.get("RSM_BUILD_DIR")
    if not build:
        pytest.fail("RSM_BUILD_DIR is not set: run these tests through ctest", pytrace=False)
    exe = Path(build) / "tools" / "nav" / "rsm-nav"
    if not exe.is_file():
        pytest.fail(f"rsm-nav not built at {exe}", pytrace=False)
    return Path(build)


def sanitized(build: Path) -> bool:
    return bench.cmake_cache(build).get("RSM_SANITIZE", "OFF").upper() in ("ON", "TRUE", "1", "YES")


@pytest.fixture(scope="module")
def run(tmp_path_factory, head_log, head_relations):
    build = build_dir()
    d = tmp_path_factory.mktemp("bench")
    extra = d / "head_o10.clf.gz"
    outliers.inject_file(head_log, extra, 10, seed=7)
    cmd = [sys.executable, "-m", "rsm_tools.bench", "--root", str(REPO_ROOT), "--build-dir", str(build),
           "--real-log", str(head_log), "--real-relations", str(head_relations),
           "--log", str(extra), "--relations", str(head_relations),
           "--quick", "--levels", ",".join(map(str, LEVELS)), "--seeds", str(SEEDS),
           "--no-cross-check", "--output", str(d / "RESULTS.md"), "--plots-dir", str(d / "results"),
           "--work-dir", str(d / "work"), "--cache-dir", str(d / "cache")]
    # Valgrind cannot run an ASan binary; the instruction counts are then left out.
    if sanitized(build) or shutil.which("valgrind") is None:
        cmd.append("--no-callgrind")
    res = subprocess.run(cmd, env=subprocess_env(), capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, f"rsm-bench failed ({res.returncode}):\n{res.stdout}\n{res.stderr}"
    report = (d / "RESULTS.md").read_text(encoding="utf-8")
    manifest = json.loads((d / "work" / "bench.json").read_text())
    return {"report": report, "manifest": manifest, "dir": d, "relations": ev.load_relations(head_relations)}


# ---------------------------------------------------------------------------
# reading the report back


def table(report: str, anchor: str):
    """Header and rows (lists of cell strings) of the table named by its anchor comment."""
    lines = report.splitlines()
    marker = f"<!-- table: {anchor} -->"
    assert marker in lines, f"no table {anchor!r} in the report"
    i = lines.index(marker) + 1
    cells = []
    while i < len(lines) and lines[i].startswith("|"):
        cells.append([c.strip() for c in lines[i].strip().strip("|").split("|")])
        i += 1
    header, sep, rows = cells[0], cells[1], cells[2:]
    assert all(set(c) <= set("-:") for c in sep)
    assert all(len(r) == len(header) for r in rows), anchor
    return header, rows


def number(cell: str) -> float:
    return float(cell.replace(" ", ""))


def decimals(cell: str) -> int:
    return len(cell.split(".")[1]) if "." in cell else 0


def shows(cell: str, value: float) -> bool:
    """True if the cell is ``value`` rounded to the cell's own number of decimals."""
    return abs(number(cell) - value) <= 0.5 * 10 ** -decimals(cell) + 1e-9


def section(report: str, title: str) -> str:
    start = report.index(f"## {title}")
    nxt = report.find("\n## ", start + 1)
    return report[start:] if nxt < 0 else report[start:nxt]


def scoped(traj, relations):
    t = ev.load_trajectory(traj)
    return {"all": ev.evaluate(t, relations, tolerance=0.0),
            "local": ev.evaluate(t, relations, max_span=2.0, tolerance=0.0)}


# ---------------------------------------------------------------------------


def test_report_has_every_section_and_states_where_it_was_measured(run):
    report = run["report"]
    for title in ("Headline",) + bench.SECTION_TITLES:
        assert f"\n## {title}\n" in report, title
    model, cores = bench.cpu_info()
    head = subprocess.run(["git", "-C", str(REPO_ROOT), "rev-parse", "--short=12", "HEAD"],
                          capture_output=True, text=True).stdout.strip()
    for title in bench.SECTION_TITLES:
        text = section(report, title)
        assert f"on {model} ({cores} cores)" in text, title
        assert f"commit `{head}" in text, title
        assert re.search(r"Measured \d{4}-\d\d-\d\d \d\d:\d\d UTC", text), title
    # no path of this machine: only repository-relative paths and file names
    assert str(REPO_ROOT) not in report
    assert str(run["dir"]) not in report


def test_accuracy_figures_are_those_of_evaluate_on_the_kept_trajectories(run):
    man, rels = run["manifest"], run["relations"]
    labels = [l["label"] for l in man["logs"]]
    assert len(labels) == 2
    for label in labels:
        _, rows = table(run["report"], f"accuracy {label}")
        seen = 0
        for method in bench.METHODS:
            traj = man["accuracy"][label]["runs"][method]["trajectory"]
            data = [l for l in Path(traj).read_text().splitlines() if l and not l.startswith("#")]
            assert len(data) == man["accuracy"][label]["runs"][method]["summary"]["scans"] > 0
            res = scoped(traj, rels)
            for scope in bench.SCOPES:
                row = [r for r in rows if r[0] == method and r[1] == scope]
                assert len(row) == 1, (label, method, scope)
                row = row[0]
                e = res[scope]
                assert e["unmatched"] == 0 and e["matched"] > 0
                assert int(row[2]) == e["matched"] and int(row[3]) == e["unmatched"]
                for k, (q, stat) in enumerate((q, s) for q in bench.QUANTITIES for s in ("mean", "std", "max")):
                    assert shows(row[4 + k], e[q][stat]), (label, method, scope, q, stat, row[4 + k])
                seen += 1
        assert seen == len(rows) == 6
    # the headline repeats the main log's means
    _, rows = table(run["report"], "headline")
    for row in rows:
        res = scoped(man["accuracy"][labels[0]]["runs"][row[0]]["trajectory"], rels)
        got = [res[s][q]["mean"] for s in bench.SCOPES for q in bench.QUANTITIES]
        assert all(shows(c, v) for c, v in zip(row[1:], got)), row


def test_robustness_figures_are_mean_and_spread_over_seeds_of_evaluate(run):
    man, rels = run["manifest"], run["relations"]
    runs = man["robustness"]["runs"]
    assert sorted({r["level"] for r in runs}) == list(LEVELS)
    per = {}
    for r in runs:
        if r["level"] > 0:
            assert Path(r["log"]).parent == run["dir"] / "cache"
        per.setdefault((r["method"], r["level"]), []).append(scoped(r["trajectory"], rels))
    for (method, level), got in per.items():
        assert len(got) == (1 if level == 0 else SEEDS), (method, level)
    # different seeds really are different data
    noisy = [r for r in runs if r["method"] == "rsm" and r["level"] > 0]
    assert len({Path(r["log"]).read_bytes() for r in noisy}) == SEEDS
    for scope in bench.SCOPES:
        _, rows = table(run["report"], f"robustness {scope}")
        assert len(rows) == len(LEVELS) * len(bench.ROBUST_METHODS)
        for row in rows:
            level, method = int(row[0]), row[1]
            got = per[(method, level)]
            assert int(row[2]) == len(got)
            for k, q in enumerate(bench.QUANTITIES):
                vals = [g[scope][q]["mean"] for g in got]
                clean = per[(method, 0)][0][scope][q]["mean"]
                mean = sum(vals) / len(vals)
                lo, hi = row[4 + 3 * k].split("..")
                assert shows(row[3 + 3 * k], mean), (row, q)
                assert shows(lo, min(vals)) and shows(hi, max(vals)), (row, q)
                assert shows(row[5 + 3 * k], mean / clean), (row, q)


def test_speed_figures_come_from_the_rsm_nav_summaries_and_callgrind(run):
    man = run["manifest"]
    _, rows = table(run["report"], "speed wall")
    by = {r[0]: r for r in rows}
    median = {}
    for m in bench.ROBUST_METHODS:
        texts = [r["summary_text"] for r in man["speed"]["runs"] if r["method"] == m]
        assert texts
        vals = sorted(float(re.search(r"median ([0-9.]+) us", t).group(1)) for t in texts)
        median[m] = vals[len(vals) // 2]
        assert shows(by[m][1], median[m]), by[m]
        assert number(by[m][3]) >= number(by[m][1])  # p95 >= median
    assert shows(by["icp / rsm"][1], median["icp"] / median["rsm"])
    cg = man["callgrind"]
    if "skipped" in cg:
        assert "Instruction counts not measured" in run["report"]
        return
    _, rows = table(run["report"], "speed callgrind")
    by = {r[0]: r for r in rows}
    per_scan = {}
    for m in bench.ROBUST_METHODS:
        text = Path(cg[m]["out"]).read_text()
        ir = int(re.search(r"^totals:\s+(\d+)", text, re.M).group(1))
        traj = Path(cg[m]["out"]).with_name(f"{m}.txt")
        scans = len([l for l in traj.read_text().splitlines() if l and not l.startswith("#")])
        assert ir > 0 and scans > 0
        assert number(by[m][1]) == scans and number(by[m][2]) == ir
        per_scan[m] = ir / scans
        assert shows(by[m][3], per_scan[m])
    assert shows(by["icp / rsm"][3], per_scan["icp"] / per_scan["rsm"])


def test_memory_table_adds_up(run):
    _, rows = table(run["report"], "memory host")
    size = {r[0]: int(number(r[1])) for r in rows}
    total = size["rsm_localizer_t (total)"]
    assert total > 0
    assert sum(size[k] for k in bench.MEMORY_TILES) + size["other (pointer, stamps, padding)"] == total
    assert size["work (union of the two below)"] >= max(size["work.rsm (visited + harris + cands)"],
                                                        size["work.icp"])
    assert "Cortex-M4F sizes not measured: --no-cross-check" in run["report"]


def test_where_rsm_loses_lists_exactly_the_measures_where_the_others_are_lower(run):
    man, rels = run["manifest"], run["relations"]
    text = section(run["report"], bench.SECTION_TITLES[4])
    for entry in man["logs"]:
        label = entry["label"]
        res = {m: scoped(man["accuracy"][label]["runs"][m]["trajectory"], rels) for m in bench.METHODS}
        for other in ("icp", "odometry"):
            expected = {f"{s} {q} {st}" for s in bench.SCOPES for q in bench.QUANTITIES
                        for st in ("mean", "std", "max")
                        if res[other][s][q][st] < res["rsm"][s][q][st]}
            line = [l for l in text.splitlines() if l.startswith(f"- On `{label}`, {other} beats rsm on")]
            assert len(line) == 1, (label, other)
            named = set(re.findall(r"((?:local|all) (?:translation|rotation) (?:mean|std|max)) \(", line[0]))
            assert named == expected, (label, other, line[0])
    # robustness: the levels where icp's mean over the seeds is below rsm's
    means = {}
    for r in man["robustness"]["runs"]:
        if r["level"] > 0:
            res = scoped(r["trajectory"], rels)
            for s in bench.SCOPES:
                for q in bench.QUANTITIES:
                    means.setdefault((r["method"], r["level"], s, q), []).append(res[s][q]["mean"])
    expected = {f"{lv} % {s} {q}" for (m, lv, s, q), v in means.items()
                if m == "icp" and sum(v) / len(v) < sum(means[("rsm", lv, s, q)]) / len(v)}
    line = [l for l in text.splitlines() if l.startswith("- With outliers, icp's mean error over the seeds")]
    assert len(line) == 1
    named = set(re.findall(r"(\d+ % (?:local|all) (?:translation|rotation)) \(", line[0]))
    assert named == expected, line[0]
    assert bool(expected) != ("at no level" in line[0])
    # robustness: where rsm does worse than odometry alone
    odo = scoped(man["accuracy"][man["logs"][0]["label"]]["runs"]["odometry"]["trajectory"], rels)
    expected = {}
    for (m, lv, s, q), v in sorted(means.items()):
        if m == "rsm" and sum(v) / len(v) > odo[s][q]["mean"]:
            expected.setdefault(f"{s} {q}", []).append(lv)
    line = [l for l in text.splitlines() if l.startswith("- With outliers, rsm's mean error over the seeds")]
    assert len(line) == 1
    named = {k: [int(x) for x in lv.split(", ")]
             for k, lv in re.findall(r"((?:local|all) (?:translation|rotation)) at ([\d, ]+) %", line[0])}
    assert named == expected, line[0]
    assert "no scan matcher without loop closure gets them right" in text


def test_cross_check_output_is_parsed():
    # The layout tools/cross-check prints (values here only exercise the parser).
    text = "\n".join([
        "ok: no object references malloc, calloc, realloc or free",
        "ok: no object has .data, .bss or COMMON data (all state is caller-owned)",
        "",
        "Cortex-M4F, -Os, per object (bytes; flash = text + rodata, RAM = data + bss):",
        "  library                    object                      text  rodata   data    bss   flash    RAM",
        "  librsm.a                   a.c.obj                       10       2      0      0      12      0",
        "  librsm.a                   b.c.obj                       20       0      0      0      20      0",
        "  librsm.a                   TOTAL                         30       2      0      0      32      0",
        "",
        "Example firmware image (port/baremetal/rsm_firmware.elf), linked with --gc-sections and newlib-nano:",
        "     text\t   data\t    bss\t    dec\t    hex\tfilename",
        "      100\t      4\t    200\t    304\t    130\tbuild-arm/port/baremetal/rsm_firmware.elf",
        "",
        "Static RAM the firmware reserves for rsm state (objects in firmware_main.c, by size):",
        "        8  fw_clock",
        "      150  fw_localizer",
        "      158  total",
        "",
        "cross-check: all checks passed",
    ])
    p = bench.parse_cross_check(text)
    assert [o["object"] for o in p["objects"]] == ["a.c.obj", "b.c.obj"]
    assert p["objects"][0]["flash"] == p["objects"][0]["text"] + p["objects"][0]["rodata"]
    assert p["totals"]["librsm.a"]["flash"] == sum(o["flash"] for o in p["objects"])
    assert p["firmware"] == {"text": 100, "data": 4, "bss": 200, "dec": 304}
    assert p["statics"]["fw_localizer"] == 150 and p["statics"]["total"] == 158
    assert len(p["checks"]) == 2 and p["passed"]


def test_summary_parser_reads_outcomes_and_times():
    text = ("rsm-nav summary\n  method          rsm\n  scans           12\n    accepted       9\n"
            "    jump           3\n  readings dropped: nan 0, too short 0, too long 1\n"
            "  time per scan   median 98.1 us, p95 167.6 us (this machine, wall clock)\n")
    s = bench.parse_summary(text)
    assert s["scans"] == 12 and s["outcomes"] == {"accepted": 9, "jump": 3}
    assert s["median_us"] == 98.1 and s["p95_us"] == 167.6
    assert math.isclose(bench.fused_percent(s), 75.0)
    with pytest.raises(bench.BenchError):
        bench.parse_summary("no summary here")
