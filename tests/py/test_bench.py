"""Tests of rsm-bench's report machinery on the shipped excerpt.

The bench runs once (module fixture) in quick settings on
tests/data/intel_head.clf.gz with rsm-nav and rsm-stages from RSM_BUILD_DIR
(ctest sets it), plus one extra log made here (the excerpt with 10 %
outliers), one Cortex-M4F configuration (the small one) and the scaling
section with the default build only. The tests then read the report back and
check every figure against what evaluate() computes from the trajectories the
bench kept, and against the raw outputs of rsm-nav, rsm-stages and callgrind:
no expected number is typed into this file. The parsers and the pure helpers
are tested on small inputs made here.
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

from conftest import REPO_ROOT, build_dir, rsm_nav_binary, subprocess_env
from rsm_tools import bench
from rsm_tools import evaluate as ev
from rsm_tools import outliers

LEVELS = (0, 43)
SEEDS = 2


def sanitized(build: Path) -> bool:
    return bench.cmake_cache(build).get("RSM_SANITIZE", "OFF").upper() in ("ON", "TRUE", "1", "YES")


@pytest.fixture(scope="module")
def run(tmp_path_factory, head_log, head_relations):
    build = build_dir()
    rsm_nav_binary()  # the bench drives it: say so clearly if it is missing
    d = tmp_path_factory.mktemp("bench")
    extra = d / "head_o10.clf.gz"
    outliers.inject_file(head_log, extra, 10, seed=7)
    cmd = [sys.executable, "-m", "rsm_tools.bench", "--root", str(REPO_ROOT), "--build-dir", str(build),
           "--real-log", str(head_log), "--real-relations", str(head_relations),
           "--log", str(extra), "--relations", str(head_relations),
           "--quick", "--levels", ",".join(map(str, LEVELS)), "--seeds", str(SEEDS),
           "--no-cross-check", "--arm-configs", "small", "--output", str(d / "RESULTS.md"),
           "--plots-dir", str(d / "results"),
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
    text = section(run["report"], bench.SECTION_TITLES[-1])
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


# ---------------------------------------------------------------------------
# sharp turns (the paper's Fig. 8)


def _between(a, b):
    """inverse(a) o b, written out here independently of rsm_tools.evaluate."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    d = b[2] - a[2]
    return (c * dx + s * dy, -s * dx + c * dy, math.atan2(math.sin(d), math.cos(d)))


def _deg(yaw):
    return abs(math.degrees(math.atan2(math.sin(yaw), math.cos(yaw))))


def test_turns_are_the_fastest_local_turns_with_the_residuals_of_the_kept_trajectories(run):
    man, rels = run["manifest"], run["relations"]
    tn = man["turns"]
    cell = man["stages"]["config"]["cell_m"]
    assert tn["cell_m"] == cell > 0
    assert f"cells of {cell * 100:g} cm" in section(run["report"], bench.SECTION_TITLES[2])
    runs = man["accuracy"][man["logs"][0]["label"]]["runs"]
    # the scan order: the odometry run writes one line per scan of the log
    order = {}
    for k, line in enumerate(l for l in Path(runs["odometry"]["trajectory"]).read_text().splitlines()
                             if l and not l.startswith("#")):
        order.setdefault(round(float(line.split()[0]), 6), k)
    cands = []
    for r in rels:
        i1, i2 = order.get(round(r.t1, 6)), order.get(round(r.t2, 6))
        if r.span <= bench.LOCAL_SPAN and i1 is not None and i2 is not None and i1 != i2:
            cands.append((_deg(r.yaw) / abs(i2 - i1), r, 0.5 * (i1 + i2)))
    picked = tn["turns"]
    assert 0 < len(picked) <= bench.TURNS
    rates = [t["rate_deg_per_scan"] for t in picked]
    mids = [0.5 * (t["i1"] + t["i2"]) for t in picked]
    assert rates == sorted(rates, reverse=True)
    assert all(abs(a - b) >= tn["separation"] for i, a in enumerate(mids) for b in mids[:i])
    keys = {(t["t1"], t["t2"]) for t in picked}
    for rate, r, mid in cands:
        if (r.t1, r.t2) in keys:
            assert any(math.isclose(rate, x) for x in rates)
        elif len(picked) < bench.TURNS or rate > rates[-1]:
            # left out only because a faster turn already covers its stretch of the log
            assert any(abs(mid - m) < tn["separation"] and x >= rate for m, x in zip(mids, rates)), r
    trajs = {m: ev.load_trajectory(runs[m]["trajectory"]) for m in bench.METHODS}
    _, rows = table(run["report"], "turns")
    assert len(rows) == len(picked)
    for row, t in zip(rows, picked):
        rel = next(r for r in rels if (r.t1, r.t2) == (t["t1"], t["t2"]))
        assert int(row[3]) == abs(order[round(rel.t2, 6)] - order[round(rel.t1, 6)])
        assert shows(row[4], _deg(rel.yaw)) and shows(row[5], math.hypot(rel.x, rel.y))
        for k, m in enumerate(bench.METHODS):
            p1, p2 = trajs[m].find(rel.t1, 0.0)[0], trajs[m].find(rel.t2, 0.0)[0]
            e = _between((rel.x, rel.y, rel.yaw), _between(p1, p2))
            dx, dy = row[6 + 2 * k].split(", ")
            assert shows(dx, abs(e[0]) / cell) and shows(dy, abs(e[1]) / cell), (row, m)
            assert shows(row[7 + 2 * k], abs(math.degrees(e[2]))), (row, m)
    # the summary: means over the turns
    _, rows = table(run["report"], "turns summary")
    for row in rows:
        vals = [t["residual"][row[0]] for t in picked]
        assert int(row[1]) == len(vals)
        assert shows(row[4], sum(v["translation_cells"] for v in vals) / len(vals))
        assert shows(row[6], sum(v["rotation_deg"] for v in vals) / len(vals))
    # by true rotation: every local relation once; the means are evaluate()'s
    local = [r for r in rels if r.span <= bench.LOCAL_SPAN]
    _, rows = table(run["report"], "turns by rotation")
    assert sum(int(r[1]) for r in rows) == len(local)
    edges = list(bench.ROTATION_BINS) + [math.inf]
    for k, row in enumerate(rows):
        sel = [r for r in local if edges[k] <= _deg(r.yaw) < edges[k + 1]]
        assert int(row[1]) == len(sel)
        for j, m in enumerate(bench.METHODS):
            if not sel:
                assert row[2 + 2 * j] == "n/a"
                continue
            res = ev.evaluate(trajs[m], sel, tolerance=0.0)
            assert shows(row[2 + 2 * j], res["translation"]["mean"] / cell), (row, m)
            assert shows(row[3 + 2 * j], res["rotation"]["mean"]), (row, m)


# ---------------------------------------------------------------------------
# per-stage times, rsm-stages itself, callgrind by stage


def test_stage_table_is_the_median_over_the_rsm_stages_runs(run):
    st = run["manifest"]["stages"]
    _, rows = table(run["report"], "speed stages")
    by = {r[0]: r for r in rows}
    for k, m in enumerate(bench.ROBUST_METHODS):
        res = [r["result"] for r in st["runs"] if r["method"] == m]
        assert len(res) == st["repeats"] >= 1
        for one in res:
            tm = one["timing"]
            assert tm["step"]["n"] == tm["call"]["n"] == one["scans"] > 0
            # the stages tile each step, so their means add up to the step's mean
            assert math.isclose(sum(tm[s]["mean_us"] for s in bench.STAGES), tm["step"]["mean_us"],
                                rel_tol=1e-6, abs_tol=1e-3)
            # every step lies inside its call, so the order statistics do too
            assert tm["step"]["median_us"] <= tm["call"]["median_us"]
            assert tm["step"]["p95_us"] <= tm["call"]["p95_us"]
        off = 2 + 5 * k
        for s in bench.STAGES:
            cells = by[s][off:off + 5]
            reached = res[0]["timing"][s]["reached"]
            assert int(cells[0]) == reached
            if reached == 0:
                assert cells[1:4] == ["-", "-", "-"]
                continue
            for cell, stat in zip(cells[1:4], ("median_reached_us", "p95_reached_us", "mean_us")):
                vals = sorted(r["timing"][s][stat] for r in res)
                assert shows(cell, vals[len(vals) // 2]), (m, s, stat)
        call = sorted(r["timing"]["call"]["median_us"] for r in res)
        assert shows(by["whole call (timed outside)"][off + 1], call[len(call) // 2])
    reached = {m: {s for s in bench.STAGES if st["methods"][m]["timing"][s]["reached"]} for m in bench.ROBUST_METHODS}
    assert {"grid", "harris", "match", "ransac", "refine", "ekf", "map"} <= reached["rsm"]
    assert "icp" not in reached["rsm"]
    assert reached["icp"] == {"points", "icp", "ekf", "map"}
    assert shows(by["icp / rsm"][3], st["methods"]["icp"]["timing"]["call"]["median_us"]
                 / st["methods"]["rsm"]["timing"]["call"]["median_us"])


def test_rsm_stages_runs_the_log_exactly_as_rsm_nav(run, head_log, tmp_path):
    exe = bench.stages_exe(build_dir())
    runs = run["manifest"]["accuracy"][run["manifest"]["logs"][0]["label"]]["runs"]

    def data(p):
        return [l for l in Path(p).read_text().splitlines() if l and not l.startswith("#")]

    for m in bench.ROBUST_METHODS:
        for clock in ("ns", "none"):
            res = bench.run_stages(exe, head_log, m, ["--clock", clock], tmp_path / f"{m}-{clock}.txt")
            assert data(res["trajectory"]) == data(runs[m]["trajectory"]), (m, clock)
            assert (res["timing"]["step"] is None) == (clock == "none")
            assert res["timing"]["call"]["n"] == res["scans"]
    res = bench.run_stages(exe, head_log, "rsm", ["--beams", "361", "--limit", "50"])
    assert (res["scans"], res["beams_in"], res["beams"]) == (50, 180, 361)


def test_callgrind_stages_add_up_to_the_collected_instructions(run):
    cg = run["manifest"]["callgrind"]
    if "skipped" in cg:
        assert "speed callgrind stages" not in run["report"]
        return
    _, rows = table(run["report"], "speed callgrind stages")
    for k, m in enumerate(bench.ROBUST_METHODS):
        assert cg[m]["breakdown"]["total"] == cg[m]["ir"]
        assert sum(v["ir"] for v in cg[m]["stages"].values()) == cg[m]["ir"]
        for row in rows:
            v = cg[m]["stages"].get(row[0])
            assert number(row[2 + 2 * k]) == (round(v["ir_per_scan"]) if v else 0)
    assert cg["icp"]["stages"]["icp"]["ir"] > cg["icp"]["ir"] / 2
    assert "harris" in cg["rsm"]["stages"] and "harris" not in cg["icp"]["stages"]


def test_callgrind_parser_and_localizer_breakdown_on_a_made_up_profile():
    text = "\n".join([
        "events: Ir", "", "fn=(1) rsm_localizer_scan", "0 100",
        "cfn=(2) rsm_harris_detect", "calls=2 0", "0 500",
        "cfn=(3) step_rsm.isra.0", "calls=1 0", "0 300",
        "fn=(3)", "0 50", "cfn=(4) rsm_map_align", "calls=1 0", "0 250",
        "fn=(2)", "0 380", "cfn=(5) patch_map", "calls=10 0", "0 120",
        "fn=(5)", "+1 70", "-1 50", ""])
    cg = bench.parse_callgrind(text)
    assert cg["self"] == {"rsm_localizer_scan": 100, "step_rsm.isra.0": 50, "rsm_harris_detect": 380,
                          "patch_map": 120}
    assert cg["calls"][("rsm_harris_detect", "patch_map")] == [10, 120]
    # patch_map is a localizer helper, but called from inside Harris: not the localizer's own code
    br = bench.localizer_breakdown(cg, ["step_rsm", "patch_map", "fuse"])
    assert br["group"] == ["rsm_localizer_scan", "step_rsm"]
    assert (br["own"], br["callees"], br["total"]) == (150, {"rsm_harris_detect": 500, "rsm_map_align": 250}, 900)
    st = bench.callgrind_stages(br, 3)
    assert st["harris"]["ir"] == 500 and st["refine"]["ir"] == 250 and st["localizer"]["ir"] == 150
    assert math.isclose(st["harris"]["ir_per_scan"], 500 / 3)
    assert bench.base_name("rsm_harris_response.part.0") == "rsm_harris_response"
    assert bench.base_name("to_world.constprop.0.isra.0") == "to_world"
    assert bench.base_name("walk'2") == "walk"
    src = ("static int a(void)\n{\n    return 1;\n}\nint b(void);\nstatic const char *\nname_of(int x,\n"
           "        int y)\n{\n    return 0;\n}\nstatic int table[3];\n")
    assert bench.static_functions(src) == ["a", "name_of"]


# ---------------------------------------------------------------------------
# memory: Cortex-M4F per configuration, stack


def test_stack_depths_are_reported_and_consistent(run):
    man = run["manifest"]
    st = man["stages"]
    text = section(run["report"], bench.SECTION_TITLES[4])
    if sanitized(build_dir()):
        assert "stack" not in st and "Painted measurement not made" in text
    else:
        _, rows = table(run["report"], "memory stack")
        painted = [r for r in rows if r[1] == "painted"]
        assert len(painted) == len(bench.ROBUST_METHODS)
        for m, row in zip(bench.ROBUST_METHODS, painted):
            s = st["stack"][m]
            assert s["scan_bytes"] == s["peak_bytes"] - s["baseline_bytes"] > 0
            assert s["scans"] == st["methods"][m]["scans"]
            assert int(number(row[3])) == s["scan_bytes"]
    for where in [man["host_stack"]] + [c for c in (man["arm_memory"].get("configs") or {}).values()]:
        if "skipped" in where:
            continue
        for fn, s in where["stack"].items():
            assert s["path"][0][0] == fn
            assert sum(b for _, b in s["path"]) == s["bytes"] > 0
            assert not s["recursion"]


def test_arm_memory_of_the_small_configuration(run):
    am = run["manifest"]["arm_memory"]
    if "skipped" in am:
        assert "Per-configuration Cortex-M4F sizes not measured" in run["report"]
        return
    assert list(am["configs"]) == ["small"]
    c = am["configs"]["small"]
    assert c["header"] == "tests/config/small_config.h"
    sources = {p.name + ".obj" for p in (REPO_ROOT / "src").glob("*.c")}
    assert {o["object"] for o in c["objects"]} == sources
    for o in c["objects"]:
        assert o["flash"] == o["text"] + o["rodata"] > 0 and o["ram"] == 0
    state = {s["label"].strip(): s["bytes"] for s in c["state"]}
    total = state["rsm_localizer_t (all of the below)"]
    assert c["firmware_statics"]["fw_localizer"] == total
    parts = [v for k, v in state.items() if c["state"][[s["label"].strip() for s in c["state"]].index(k)]["label"]
             .startswith("  ") and "shares" not in k]
    assert sum(parts) <= total and all(p > 0 for p in parts)
    assert c["firmware"]["bss"] >= sum(c["firmware_statics"].values()) > total
    _, rows = table(run["report"], "memory arm configs flash")
    by = {r[0]: r for r in rows}
    assert int(number(by["TOTAL core + drivers"][2])) == sum(o["flash"] for o in c["objects"])
    _, rows = table(run["report"], "memory arm configs state")
    assert int(number(rows[0][2])) == total
    # the small config really is smaller than the default one (same compiler, this host's sizes)
    assert total < run["manifest"]["memory"]["sizes"]["rsm_localizer_t"]


def test_size_and_nm_parsers_on_made_up_output():
    text = "\n".join([
        "a.c.obj   (ex build/librsm.a):", "section      size   addr", ".text           0      0",
        ".text.f       120      0", ".rodata.x      12      0", ".bss            0      0",
        ".comment       50      0", "Total         182", "",
        "b.c.obj   (ex build/librsm.a):", "section      size   addr", ".text.g        40      0",
        ".data.v         4      0", ".bss.w          8      0", "Total          52", ""])
    objs = bench.parse_size_archive(text)
    assert [o["object"] for o in objs] == ["a.c.obj", "b.c.obj"]
    assert (objs[0]["text"], objs[0]["rodata"], objs[0]["flash"], objs[0]["ram"]) == (120, 12, 132, 0)
    assert (objs[1]["flash"], objs[1]["data"], objs[1]["bss"], objs[1]["ram"]) == (40, 4, 8, 12)
    nm = "00005f6c 00003b70 B rsm_size_0\n00005f30 0000003c B rsm_size_12\n00000000 00000010 B other\n"
    assert bench.parse_nm_sizes(nm) == {0: 0x3b70, 12: 0x3c}


def test_worst_stack_path_on_a_made_up_call_graph():
    a = "\n".join([
        'graph: { title: "a.c"',
        'node: { title: "top" label: "top\\na.c:1:1\\n100 bytes (static)" }',
        'node: { title: "a.c:helper" label: "helper\\na.c:9:1\\n40 bytes (static)" }',
        'node: { title: "memset" label: "__builtin_memset\\n<built-in>" shape : ellipse }',
        'node: { title: "deep" label: "deep\\nb.h:1:1" shape : ellipse }',
        'edge: { sourcename: "top" targetname: "a.c:helper" label: "a.c:3:5" }',
        'edge: { sourcename: "top" targetname: "deep" label: "a.c:4:5" }',
        'edge: { sourcename: "a.c:helper" targetname: "memset" }', "}"])
    b = "\n".join([
        'graph: { title: "b.c"',
        'node: { title: "deep" label: "deep\\nb.c:1:1\\n30 bytes (dynamic,bounded)" }',
        'node: { title: "__indirect_call" label: "Indirect Call Placeholder" shape : ellipse }',
        'node: { title: "b.c:cb_small" label: "cb_small\\nb.c:7:1\\n8 bytes (static)" }',
        'node: { title: "cb_big" label: "cb_big\\nb.c:9:1\\n50 bytes (static)" }',
        'edge: { sourcename: "deep" targetname: "__indirect_call" label: "b.c:2:3" }', "}"])
    g = bench.parse_callgraph_info([a, b])
    assert g["nodes"]["deep"]["bytes"] == 30 and "memset" not in g["nodes"]
    res = bench.worst_stack_path(g, "top", {"deep": ("cb_small", "cb_big")})
    assert res["bytes"] == 180 and [n for n, _ in res["path"]] == ["top", "deep", "cb_big"]
    assert res["unresolved"] == ["memset"] and res["dynamic"] == ["deep"] and not res["unknown_indirect"]
    res = bench.worst_stack_path(g, "top")
    assert res["bytes"] == 140 and [n for n, _ in res["path"]] == ["top", "helper"]
    assert res["unknown_indirect"] == ["deep"]
    # recursion is reported, not followed
    c = 'edge: { sourcename: "cb_big" targetname: "top" }'
    res = bench.worst_stack_path(bench.parse_callgraph_info([a, b, c]), "top", {"deep": ("cb_big",)})
    assert res["recursion"] == ["top"] and res["bytes"] == 180
    with pytest.raises(bench.BenchError):
        bench.worst_stack_path(g, "missing")


# ---------------------------------------------------------------------------
# scaling


def test_scaling_runs_of_the_default_build(run):
    man = run["manifest"]
    sc = man["scaling"]
    rels = run["relations"]
    assert [v["name"] for v in sc["variants"]] == ["beams361", "map7"]
    assert all(not v["macros"] for v in sc["variants"])
    acc = man["accuracy"][man["logs"][0]["label"]]["runs"]
    _, rows = table(run["report"], "scaling time")
    assert len(rows) == len(sc["rows"]) == 4
    for r in sc["rows"]:
        res = ev.evaluate(ev.load_trajectory(r["trajectory"]), rels, max_span=bench.LOCAL_SPAN, tolerance=0.0)
        for q in bench.QUANTITIES:
            assert math.isclose(r["local"][q], res[q]["mean"])
        row = [x for x in rows if x[0] == r["kind"] and x[4] == r["method"]]
        assert len(row) == 1
        assert int(row[0][2]) == r["beams"]
        assert shows(row[0][5], r["call"]["median_us"]) and shows(row[0][7], res["translation"]["mean"])
        if r["kind"] == "map":  # the log's own readings in the default build: the accuracy run's trajectory
            assert r["beams"] == 180
            assert Path(r["trajectory"]).read_text().splitlines()[2:] == \
                Path(acc[r["method"]]["trajectory"]).read_text().splitlines()[2:]
        else:
            assert r["beams"] == 361 and r["config"]["RSM_MAX_BEAMS"] >= 361


def test_scaling_variants_headers_and_growth(tmp_path):
    v = {x["name"]: x for x in bench.scaling_variants((181, 361, 721), (6, 7, 8), ("rsm/config_host.h",))}
    assert list(v) == ["beams181", "beams361", "beams721", "map6", "map7", "map8", "config_host"]
    assert v["config_host"]["header"] == "rsm/config_host.h" and v["config_host"]["resample"] is None
    assert v["beams361"]["macros"] == {} and v["map7"]["macros"] == {}
    assert v["beams721"]["macros"] == {"RSM_MAX_BEAMS": 721} and v["beams721"]["resample"] == 721
    assert v["map6"]["macros"] == {"RSM_MAP_SIZE_LOG2": 6} and v["map6"]["resample"] is None
    # the generated header really overrides config.h's defaults
    header = tmp_path / "variant.h"
    header.write_text(bench.variant_header({"RSM_MAX_BEAMS": 721, "RSM_MAP_SIZE_LOG2": 8}))
    probe = tmp_path / "probe.c"
    probe.write_text('#include "rsm/config.h"\n'
                     "typedef char beams_ok[(RSM_MAX_BEAMS == 721 && RSM_MAP_SIZE == 256) ? 1 : -1];\n"
                     "typedef char cells_ok[(RSM_IMAGE_MAX_CELLS == 2 * 721) ? 1 : -1];\n")
    cc = bench.cmake_cache(build_dir()).get("CMAKE_C_COMPILER") or "cc"
    res = subprocess.run([cc, "-std=c99", "-fsyntax-only", f"-I{REPO_ROOT / 'include'}",
                          f"-DRSM_USER_CONFIG={header}", str(probe)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    rows = [{"kind": "beams", "config": {"RSM_MAX_BEAMS": b, "RSM_MAP_SIZE": 128}, "sizes": {"rsm_localizer_t": s}}
            for b, s in ((181, 30000), (721, 43500))]
    rows += [{"kind": "map", "config": {"RSM_MAX_BEAMS": 361, "RSM_MAP_SIZE": m}, "sizes": {"rsm_localizer_t": s}}
             for m, s in ((64, 10000), (256, 90000))]
    g = bench.memory_growth(rows)
    assert math.isclose(g["beams"]["bytes_per_unit"], 13500 / 540)
    assert math.isclose(g["map"]["bytes_per_unit"], 80000 / (256 ** 2 - 64 ** 2))
    assert bench.memory_growth(rows[:1]) == {}
