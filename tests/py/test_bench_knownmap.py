"""The bench's section "Known map" (rsm_tools.bench.knownmap) on made-up
inputs: where the global starts go, how a first pose is judged against the
mapping run's, which starts count as held, the figures and floors of a log,
the report and how --only knownmap writes the section into an existing
report and manifest: no rsm-nav run, no full log."""

import json
import math
import struct
import zlib

import pytest

from rsm_tools import bench
from rsm_tools import evaluate as ev
from rsm_tools.bench import knownmap as km
from rsm_tools.bench.common import SECTION_TITLES, BenchError


def saved_map(tiles, fit=0.9, pose=(1.0, 2.0, 0.5), writes=7):
    """A made-up saved map (docs/mapfile.md): header, 40-byte tiles, CRC."""
    head = b"RSMM" + struct.pack("<HHIfBBBBBBHII", 1, 48, 0x1234, 0.05, 4, 3, 15, 3, 1, 1, 0, len(tiles), writes)
    head += struct.pack("<ffff", *pose, fit)
    assert len(head) == km.HEADER_BYTES
    body = head + b"".join(tiles)
    return body + struct.pack("<I", zlib.crc32(body))


def start(v="right", held=True, scan=5, work=1000, most=100, searches=1, scans=400, cap=400, fit=None):
    s = {"verdict": v, "held": held, "fit_ratio": fit, "first_trusted_scan": scan if v != "none" else None,
         "work": work, "max_work_per_scan": most, "searches": searches, "scans": scans, "cap": cap}
    return s


def test_starts_are_spread_evenly_from_the_logs_start():
    assert km.start_offsets(100.0, 4) == [0.0, 25.0, 50.0, 75.0]
    s = km.start_offsets(2691.287, 100)
    assert len(s) == 100 and s[0] == 0.0 and s[-1] < 2691.287
    assert all(math.isclose(b - a, 26.91287, abs_tol=0.002) for a, b in zip(s, s[1:]))
    assert km.start_offsets(100.0, 0) == [] and km.start_offsets(0.0, 5) == []


def test_tiles_of_a_saved_map_are_between_header_and_crc():
    tiles = [bytes([k]) * 40 for k in range(3)]
    a = saved_map(tiles, fit=0.86)
    b = saved_map(tiles, fit=0.03, pose=(5.0, 6.0, 1.0))  # the same map saved again by a frozen run
    assert a != b and km.map_tiles(a) == km.map_tiles(b) == b"".join(tiles)
    assert km.map_tile_count(a) == 3
    assert math.isclose(km.map_fit(a), 0.86, rel_tol=1e-6) and math.isclose(km.map_fit(b), 0.03, rel_tol=1e-6)
    assert km.map_tiles(saved_map([])) == b""
    with pytest.raises(BenchError):
        km.map_tiles(b"NOPE" + a[4:])
    with pytest.raises(BenchError):
        km.map_tiles(a[:40])


def test_a_first_pose_is_right_wrong_or_in_between():
    ref = (10.0, -5.0, 1.0)
    assert km.verdict((10.05, -5.05, 1.0 + math.radians(1.9)), ref) == "right"  # 0.071 m, 1.9 deg
    assert km.verdict((10.1, -5.0, 1.0), ref) == "right"  # on the limit
    assert km.verdict((10.2, -5.0, 1.0), ref) == "between"
    assert km.verdict((10.0, -5.0, 1.0 + math.radians(3.0)), ref) == "between"
    assert km.verdict((10.0, -5.51, 1.0), ref) == "wrong"
    assert km.verdict((10.0, -5.0, 1.0 - math.radians(5.1)), ref) == "wrong"
    assert km.verdict((10.9, -5.0, 1.0), ref) == "wrong"  # ACES's 0.9 m off
    assert km.verdict(None, ref) == "none"
    assert km.verdict((10.0, -5.0, 1.0), None) == "no reference"
    # headings compared across the wrap
    m, deg = km.pose_error((0.0, 0.0, math.pi - 0.01), (0.0, 0.0, -math.pi + 0.01))
    assert m == 0.0 and math.isclose(deg, math.degrees(0.02), rel_tol=1e-9)


def test_held_rule_on_the_first_scans_fit_ratio():
    assert km.held(0.8) is True and km.held(1.6) is True
    assert km.held(0.7999) is False and km.held(0.0) is False
    assert km.held(None) is None and km.held(float("nan")) is None


def test_trajectory_and_scan_log_are_read_from_their_first_line(tmp_path):
    t = tmp_path / "g.txt"
    t.write_text("# rsm-nav trajectory\n# source: x\n")
    assert km.first_pose(t) is None  # --global proved no pose: no line
    t.write_text("# rsm-nav trajectory\n976053859.281192 10.171115 -5.205734 1.618027\n976053859.4 10.2 -5.2 1.6\n")
    assert km.first_pose(t) == (976053859.281192, 10.171115, -5.205734, 1.618027)
    s = tmp_path / "g.scans"
    s.write_text("# rsm-nav scan log: timestamp[s] outcome tracking odometry recovered fit_ratio\n"
                 "976053857.376673 accepted tracking trusted 1 0.9747\n976053857.4 accepted tracking trusted 0 0.9\n")
    assert km.first_scan(s) == (976053857.376673, "accepted", 0.9747)
    s.write_text("# nothing\n")
    assert km.first_scan(s) is None


def test_a_start_is_judged_from_its_summary_and_first_pose():
    summary = {"scans": 400, "global": {"searches": 2, "found": 1, "not_proven": 1, "work": 123456,
                                        "max_work_per_scan": 20001, "first_trusted_scan": 17,
                                        "first_trusted_stamp": 100.5}}
    e = km.judge_start((100.5, 1.02, 2.0, 0.0), (1.0, 2.0, 0.0), summary, 0.95)
    assert e["verdict"] == "right" and e["held"] is True and e["first_trusted_scan"] == 17
    assert (e["work"], e["max_work_per_scan"], e["searches"]) == (123456, 20001, 2)
    assert math.isclose(e["error_m"], 0.02) and e["error_deg"] == 0.0 and e["stamp"] == 100.5
    none = {"scans": 400, "global": {"searches": 1, "found": 0, "work": 8e6, "max_work_per_scan": 21000,
                                     "first_trusted_scan": 0, "first_trusted_stamp": 0.0}}
    e = km.judge_start(None, None, none, 0.5)
    assert e["verdict"] == "none" and e["held"] is False and e["first_trusted_scan"] is None
    assert e["error_m"] is None and e["pose"] is None


def test_figures_of_a_log_count_unheld_starts_apart():
    starts = ([start("right", scan=3)] * 89 + [start("right", scan=40)] * 2 + [start("between", scan=8)]
              + [start("none", scans=120)] + [start("none")] * 2
              + [start("wrong", held=False, scan=4)] + [start("none", held=False)] * 3
              + [start("right", held=None, scan=6)])  # held check not judged: counted held
    s = km.aggregate(starts)
    assert (s["starts"], s["held"], s["not_held"], s["not_judged"]) == (100, 96, 4, 1)
    assert s["counts"]["right"] == 92 and s["right_within"] == 90  # two after 40 scans
    assert (s["counts"]["between"], s["counts"]["none"], s["counts"]["wrong"]) == (1, 3, 0)
    assert s["none_log_ended"] == 1  # ran 120 of its 400 scans: the log ended
    assert s["wrong_all"] == 1 and s["wrong_not_held"] == 1  # a wrong pose counts, held or not
    assert s["found_not_held"] == 1
    assert s["scans_to_pose"]["n"] == 93 and s["scans_to_pose"]["median"] == 3 and s["scans_to_pose"]["max"] == 40
    assert s["searches"] == 100
    assert km.right_needed(100) == 95 and km.right_needed(96) == 92 and km.right_needed(20) == 19
    assert km.right_needed(0) == 0


def section(per_log, cap=400, n=100):
    """A made-up result of run_knownmap: per log (starts, mapping, frozen, updates, identical, same)."""
    out = {"starts": n, "cap": cap, "jobs": 2, "within": km.WITHIN_SCANS, "held_note": km.HELD_NOTE,
           "seconds": 12.3, "logs": {}}
    for label, (starts, mp, fr, up, ident, same) in per_log.items():
        runs = {name: {"all": v, "all_rotation": 0.2, "local": v / 2, "local_rotation": 0.1, "matched": 10,
                       "writes": 5, "fit": 0.9, "seconds": 1.0}
                for name, v in (("mapping", mp), ("frozen", fr), ("updates", up))}
        out["logs"][label] = {
            "log": f"{label}.clf.gz", "scans": 1000, "span_s": 500.0,
            "round_trip": {"bytes": 104052, "tiles": 2600, "bytes_again": 104052, "tiles_again": 2600,
                           "identical": ident, "header_identical": False, "trajectory_same": same,
                           "fit": 0.8649, "fit_again": 0.0349},
            "state": {"state.persistent": 119072, "state.persistent.map": 114600,
                      "state.persistent.map.tile": 104000, "state.persistent.map.hash": 8192},
            "runs": runs, "starts": starts, "summary": km.aggregate(starts)}
    return out


def test_floors_on_made_up_numbers():
    good = [start("right", scan=4)] * 95 + [start("none")] * 5
    bad = [start("right", scan=4)] * 80 + [start("wrong", scan=2)] + [start("none")] * 9 + \
          [start("none", held=False)] * 10
    fl = km.knownmap_floors(section({"a": (good, 0.015, 0.015, 0.014, True, True),
                                     "b": (bad, 0.06, 5.75, 0.1069, True, False)}))
    got = [(f["log"], f["kind"], f["status"]) for f in fl]
    assert got == [("a", "knownmap-roundtrip", "PASS"), ("a", "knownmap-localization", "PASS"),
                   ("a", "knownmap-localization", "PASS"), ("a", "knownmap-global", "PASS"),
                   ("a", "knownmap-wrong", "PASS"),
                   ("b", "knownmap-roundtrip", "MISS"), ("b", "knownmap-localization", "MISS"),
                   ("b", "knownmap-localization", "MISS"), ("b", "knownmap-global", "MISS"),
                   ("b", "knownmap-wrong", "MISS"), (None, "knownmap-cost", "SKIP"), (None, "m4-real", "SKIP")]
    assert all(": known map, " in f["line"] and f["line"].startswith(f["status"] + " ") for f in fl)
    g = fl[8]
    assert (g["value"], g["limit"]) == (80, 86)  # 95 % of the 90 held starts
    assert "100 starts (10 not held by the map, counted apart): 80 of 90 held starts" in g["line"]
    assert "9 gave none within 400 scans" in g["line"]
    assert "1 gave a trusted pose more than 0.5 m or 5 deg off > 0" in fl[9]["line"]
    assert "0.8649 and 0.0349" in fl[5]["line"]  # why the trajectory differs: the header's fit
    assert "5.7500 m > the mapping run's 0.0600 m" in fl[6]["line"]
    # the M4's cost: one line, not per log, SKIP without the m4 stage's figures
    assert fl[10]["line"].startswith("SKIP Cortex-M4F: known map, global search, instructions per scan on the M4")
    assert "not measured (not run)" in fl[10]["line"]
    assert "median 4, worst 4 scans" in fl[3]["line"]
    # equal to the mapping run's error is at it: a PASS
    eq = km.knownmap_floors(section({"a": (good, 0.015, 0.015, 0.015, True, True)}))
    assert [f["status"] for f in eq if f["kind"] == "knownmap-localization"] == ["PASS", "PASS"]
    # no held start at all cannot pass
    none_held = km.knownmap_floors(section({"a": ([start("none", held=False)] * 3, 0.01, 0.01, 0.01, True, True)}))
    assert next(f for f in none_held if f["kind"] == "knownmap-global")["status"] == "MISS"
    assert km.knownmap_floors({"skipped": "--global-starts 0"}) == [] and km.knownmap_floors(None) == []


M4_GLOBAL = {"scans": 6, "max": 4336270.0, "mean": 3221949.5, "max_work": 100164, "work": 451232, "proven": True,
             "scans_to_pose": 6, "budget": 100000, "last_scan": 355, "pose": [4.8, -0.3, 0.07], "map_bytes": 10652,
             "map_tiles": 265, "mapped_scans": 350}


def test_the_cost_floor_judges_the_worst_scan_of_the_global_search_on_the_m4():
    good = [start("right", scan=4)] * 3
    s = section({"a": (good, 0.015, 0.015, 0.014, True, True), "b": (good, 0.015, 0.015, 0.014, True, True)}, n=3)
    s["m4_global"] = km.m4_global_entry({"cost": {}, "global": M4_GLOBAL})
    cost = [f for f in km.knownmap_floors(s) if f["kind"] == "knownmap-cost"]
    assert len(cost) == 1 and cost[0]["log"] is None  # one measurement, one line
    f = cost[0]
    assert f["status"] == "MISS" and (f["value"], f["limit"]) == (4336270.0, 1000000)
    for part in ("Cortex-M4F: known map, global search", "the excerpt's map (small: 265 tiles, 10 652 bytes",
                 "first 350 scans", "default global_budget (100 000 a scan)", "worst 4 336 270 > 1 000 000",
                 "mean 3 221 950 over 6 scans", "first proven pose after 6 scans"):
        assert part in f["line"], (part, f["line"])
    ok = dict(M4_GLOBAL, max=999999.0, proven=False, scans_to_pose=None, scans=100)
    f = km.m4_global_floor(ok)
    assert f["status"] == "PASS" and "999 999 <= 1 000 000" in f["line"]
    assert "no pose proven within 100 scans" in f["line"]
    # where the figures come from: the m4 stage, or why there are none
    assert km.m4_global_entry({"skipped": "--no-m4"}) == {"skipped": "--no-m4"}
    assert "skipped" in km.m4_global_entry(None) and "skipped" in km.m4_global_entry({"cost": {}})
    for why in ("--no-m4", km.ONLY_M4, "rsm-mapflash-host was not built"):
        f = km.m4_global_floor({"skipped": why})
        assert f["status"] == "SKIP" and f"not measured ({why})" in f["line"] and ": known map, " in f["line"]


def test_report_section_holds_the_tables_and_the_floors():
    s = section({"intel": ([start("right", scan=4)] * 3 + [start("none", held=False)], 0.0152, 0.0215, 0.0153,
                           True, True)}, n=4)
    s["provenance"] = {"date": "2026-12-04 21:00 UTC", "cpu": "CPU", "cores": 2, "compiler": "cc", "build_type":
                       "Release", "build_flags": "", "commit": "abc"}
    text = "\n".join(km.report_knownmap(s))
    assert text.startswith("### Known map\n\nMeasured 2026-12-04 21:00 UTC on CPU (2 cores)")
    for anchor in ("knownmap round trip", "knownmap localization", "knownmap global"):
        assert f"<!-- table: {anchor} -->" in text
    assert "| intel | 104 052 | 2 600 | 114 600 | 104 000 | yes | yes |" in text
    assert "| intel | localization, frozen | 0.0215 |" in text
    assert "| intel | 4 | 1 | 3 | 3 | 0 | 0 | 0 | 4 / 4 |" in text
    assert "fit_ratio" in text and "at least 0.8" in text  # the held rule is said
    # the M4's cost: on the excerpt's map and on each log's saved map
    assert "map-in-flash firmware" in text and "rsm_tools.m4cost global" in text
    for f in km.knownmap_floors(s):
        assert f["line"] in text
    assert km.report_knownmap(None)[-2] == "Not measured in this run."
    assert "--global-starts 0" in km.report_knownmap({"skipped": "--global-starts 0"})[-2]


REPORT = """# rsm benchmark results

## Headline

The issue's floors (section 7):

```
PASS intel: a
{old_headline}MISS aces: b
```

## 2. Robustness to outliers

### Faults

faults text
{old_section}
## 3. Sharp turns (the paper's Fig. 8)

text

## 7. The issue's floors

{count}

```
PASS intel: a
{old_headline}MISS aces: b
```

## 8. Where rsm loses
"""


def test_only_knownmap_splices_its_section_and_floors_into_a_report():
    first = REPORT.format(old_headline="", old_section="", count="1 PASS, 1 MISS:")
    floors = ["PASS intel: known map, round trip", "MISS intel: known map, global", "SKIP intel: known map, cost"]
    section_ = ["### Known map", "", "new text", ""]
    once = km.splice_report(first, section_, floors, SECTION_TITLES[2])
    assert once.count("### Known map") == 1
    assert once.index("### Faults") < once.index("### Known map\n\nnew text") < once.index("## 3. Sharp")
    assert "2 PASS, 2 MISS, 1 SKIP:" in once
    for block in once.split("```")[1::2]:
        assert block.splitlines()[1:] == ["PASS intel: a", "MISS aces: b"] + floors
    # again with other figures: replaced where they were, nothing doubled
    floors2 = ["PASS intel: known map, round trip", "PASS intel: known map, global"]
    twice = km.splice_report(once, ["### Known map", "", "newer text", ""], floors2, SECTION_TITLES[2])
    assert "new text" not in twice and twice.count("newer text") == 1
    assert "3 PASS, 1 MISS:" in twice
    for block in twice.split("```")[1::2]:
        assert block.splitlines()[1:] == ["PASS intel: a", "MISS aces: b"] + floors2
    assert twice.endswith("## 8. Where rsm loses\n")
    # the old lines in the middle of a block: the new ones take their place
    mid = REPORT.format(old_headline="MISS intel: known map, old\n", old_section="", count="1 PASS, 2 MISS:")
    out = km.splice_report(mid, section_, floors2, SECTION_TITLES[2])
    assert out.split("```")[1].splitlines()[1:] == ["PASS intel: a"] + floors2 + ["MISS aces: b"]
    with pytest.raises(BenchError):
        km.splice_report("# nothing\n", section_, floors, SECTION_TITLES[2])


def test_only_knownmap_says_why_the_m4_cost_is_not_measured(tmp_path, monkeypatch):
    """--only knownmap runs no firmware image: its cost line is a SKIP that says so."""
    made = section({"intel": ([start("right", scan=4)] * 3, 0.015, 0.015, 0.014, True, True)}, n=3)
    monkeypatch.setattr(km, "run_knownmap", lambda *a, **k: dict(made))
    out = tmp_path / "RESULTS.md"
    out.write_text(REPORT.format(old_headline="", old_section="", count="1 PASS, 1 MISS:"), encoding="utf-8")
    res, floors = km.run_only(tmp_path / "rsm-nav", [], tmp_path, 1, 3, 400, None, {}, out, SECTION_TITLES[2], 0)
    cost = [f for f in floors if f["kind"] == "knownmap-cost"]
    assert len(cost) == 1 and cost[0]["status"] == "SKIP" and km.ONLY_M4 in cost[0]["line"]
    assert res["m4_global"] == {"skipped": km.ONLY_M4}
    assert cost[0]["line"] in out.read_text(encoding="utf-8")
    assert json.loads((tmp_path / "bench.json").read_text())["knownmap"]["m4_global"] == {"skipped": km.ONLY_M4}


def test_only_knownmap_keeps_the_last_whole_benchs_m4_cost(tmp_path, monkeypatch):
    """After a whole bench (its manifest holds the M4 figures), --only
    knownmap keeps them, named as the whole bench's at its commit, and a
    second --only run keeps that name; their floor is judged as before."""
    made = section({"intel": ([start("right", scan=4)] * 3, 0.015, 0.015, 0.014, True, True)}, n=3)
    monkeypatch.setattr(km, "run_knownmap", lambda *a, **k: dict(made))
    out = tmp_path / "RESULTS.md"
    out.write_text(REPORT.format(old_headline="", old_section="", count="1 PASS, 1 MISS:"), encoding="utf-8")
    (tmp_path / "bench.json").write_text(json.dumps({"provenance": {"commit": "abc1234"},
                                                     "knownmap": {"m4_global": M4_GLOBAL}, "floors": []}))
    for _ in range(2):
        res, floors = km.run_only(tmp_path / "rsm-nav", [], tmp_path, 1, 3, 400, None, {}, out,
                                  SECTION_TITLES[2], 0)
        cost = [f for f in floors if f["kind"] == "knownmap-cost"]
        assert len(cost) == 1 and cost[0]["status"] == "MISS" and cost[0]["value"] == 4336270.0
        assert "kept from the whole bench at `abc1234`" in cost[0]["line"]
        assert res["m4_global"]["kept_from"] == "abc1234"
    assert km.kept_m4_global({"knownmap": {"m4_global": {"skipped": km.ONLY_M4}}}) == {"skipped": km.ONLY_M4}
    assert km.kept_m4_global({}) == {"skipped": km.ONLY_M4}


def test_the_target_section_shows_the_global_search():
    from rsm_tools.bench import report
    line = report.global_line(M4_GLOBAL)
    assert "265 tiles, global_budget 100 000" in line and "worst 4 336 270, mean 3 221 950 over 6 scans" in line
    assert line.endswith("first proven pose after 6 scans")
    assert report.global_line({"skipped": "rsm-mapflash-host was not built"}).endswith(
        "not measured (rsm-mapflash-host was not built)")
    m = {"compiler": "gcc", "qemu": "qemu", "icount_shift": 3, "images": {}, "global": M4_GLOBAL,
         "cost": {"scans": 600, "mean": 1.0, "p95": 2.0, "p99": 3.0, "max": 4.0, "stages": {"points": 1.0},
                  "calibration": {"insns": 200000, "measured": 200000.0, "per_tick": 5.0}},
         "host": {"skipped": "valgrind is not installed"}}
    text = "\n".join(report.report_m4(m))
    assert "<!-- table: speed m4 global -->" in text and "| instructions per scan, worst | 4 336 270 |" in text
    assert "| first proven pose after [scans] | 6 |" in text and "first 350 scans" in text
    assert any("global search" in l for l in report.m4_lines(m))
    m["global"] = {"skipped": "rsm-mapflash-host was not built"}
    assert "global search (map-in-flash image, the excerpt's map): not measured" in "\n".join(report.report_m4(m))


def test_only_knownmap_merges_into_the_manifest_after_the_faults_floors():
    man = {"accuracy": {"x": 1}, "floors": [{"kind": "peers", "line": "a"}, {"kind": "faults", "line": "b"},
                                            {"kind": "faults-recovery", "line": "c"}, {"kind": "data", "line": "d"}]}
    new = [{"kind": "knownmap-global", "line": "k1"}, {"kind": "knownmap-cost", "line": "k2"}]
    m = km.merge_manifest(man, {"starts": 3}, new)
    assert [f["line"] for f in m["floors"]] == ["a", "b", "c", "k1", "k2", "d"]
    assert m["knownmap"] == {"starts": 3} and m["accuracy"] == {"x": 1} and "knownmap" not in man
    m2 = km.merge_manifest(m, {"starts": 4}, new[:1])
    assert [f["line"] for f in m2["floors"]] == ["a", "b", "c", "k1", "d"]
    assert [f["line"] for f in km.merge_manifest({}, {}, new)["floors"]] == ["k1", "k2"]
    json.dumps(m2)


def test_bench_options_of_the_section():
    p = bench.build_parser()
    a = p.parse_args(["--only", "knownmap", "--global-starts", "7", "--global-scans", "50"])
    assert (a.only, a.global_starts, a.global_scans) == ("knownmap", 7, 50)
    a = p.parse_args([])
    assert a.only is None and a.global_starts is None and a.global_scans == km.START_SCANS
    with pytest.raises(SystemExit):
        p.parse_args(["--only", "accuracy"])
    text = p.format_help()
    assert "--only" in text and "knownmap" in text and "--global-starts" in text


# ---------------------------------------------------------------------------
# kidnapping


def test_kidnaps_are_placed_in_the_span_that_leaves_room():
    # 190 s of log: 100 s where a 60 s cut can begin with 30 s of log after it
    assert km.kidnap_offsets(190.0, 4) == [12.5, 37.5, 62.5, 87.5]
    offs = km.kidnap_offsets(2691.287, km.KIDNAP_RUNS)
    assert len(offs) == 20 and offs[0] > 0
    assert all(s + km.KIDNAP_S + km.KIDNAP_TAIL_S <= 2691.287 for s in offs)
    assert km.kidnap_offsets(90.0, 4) == [] and km.kidnap_offsets(500.0, 0) == []
    assert km.kidnap_offsets(100.0, 1, length=10.0, tail=10.0) == [40.0]


def test_scan_log_rows_are_read_in_file_order(tmp_path):
    s = tmp_path / "k.scans"
    s.write_text("# rsm-nav scan log: timestamp[s] outcome tracking odometry recovered fit_ratio\n"
                 "12.5 accepted tracking trusted 0 0.97\n12.4 searching lost trusted 0 0.0000\n\n")
    assert km.read_scan_log(s) == [(12.5, "accepted", "tracking"), (12.4, "searching", "lost")]


def kidnap_inputs():
    """A made-up run of 30 scans (stamps 1..30 s), the cut before stamp 11.
    The mapping run is at (t, 0, 0); the run's scans after the cut: 1-3
    trusted 2 m off, 4-5 lost and searching (no pose), 6 uncertain and right,
    7 trusted 5 cm off, 8 trusted 0.3 m off, 9 trusted with no mapping-run
    pose, 10 trusted 10 deg off, 11-20 trusted and right."""
    ref = [(float(t), float(t), 0.0, 0.0) for t in range(1, 31) if t != 19]
    rows, traj = [], []
    for t in range(1, 31):
        state, pose = "tracking", (float(t), 0.0, 0.0)
        if 11 <= t <= 13:
            pose = (t + 2.0, 0.0, 0.0)
        elif t in (14, 15):
            state, pose = "lost", None
        elif t == 16:
            state = "uncertain"
        elif t == 17:
            pose = (t + 0.05, 0.0, 0.0)
        elif t == 18:
            pose = (t + 0.3, 0.0, 0.0)
        elif t == 20:
            pose = (float(t), 0.0, math.radians(10.0))
        rows.append((float(t), "accepted" if pose else "searching", state))
        if pose:
            traj.append((float(t), *pose))
    return rows, ev.Trajectory(traj), ev.Trajectory(ref)


def test_a_kidnap_run_is_judged_from_the_first_scan_after_the_cut():
    rows, traj, ref = kidnap_inputs()
    e = km.judge_kidnap(rows, traj, ref, 11.0)
    assert e["cut_seen"] and e["after"] == 20
    assert e["before"] == {"tracking": "tracking", "verdict": "right"}
    assert e["found"] == 7  # scan 6 was right but not trusted
    assert (e["first_trusted"], e["first_lost"]) == (1, 4)
    assert (e["wrong"], e["first_wrong"], e["wrong_before_found"]) == (4, 1, 3)  # 2 m off three times, 10 deg once
    assert math.isclose(e["first_wrong_error"][0], 2.0) and e["first_wrong_error"][1] == 0.0
    assert e["no_reference"] == 1 and e["judged"] == 17
    # judged from the cut on: the same run cut later
    e = km.judge_kidnap(rows, traj, ref, 17.0)
    assert (e["found"], e["wrong"], e["first_wrong"], e["first_lost"]) == (1, 1, 4, None)
    # a cut the scan log does not hold: nothing judged, never found
    e = km.judge_kidnap(rows, traj, ref, 10.5)
    assert not e["cut_seen"] and e["found"] is None and e["wrong"] == 0


def test_a_kidnap_run_where_the_run_without_it_was_is_not_wrong():
    """Scans 1-3 after the cut are 2 m off the mapping run; the run without
    a kidnap was there too at scans 1-2 (tracking) but not at 3: 1-2 count
    apart and find the run again at 1, 3 stays wrong. Lost before, the
    control still counts; not tracking at a scan, not there."""
    rows, traj, ref = kidnap_inputs()
    c_rows = [(float(t), "accepted", "tracking") for t in range(1, 31)]
    c_traj = ev.Trajectory([(float(t), t + (2.0 if t in (11, 12) else 0.0), 0.0, 0.0) for t in range(1, 31)])
    e = km.judge_kidnap(rows, traj, ref, 11.0, (c_rows, c_traj))
    assert (e["as_control"], e["wrong"], e["first_wrong"]) == (2, 2, 3)  # scan 3 and the 10 deg one
    assert e["found"] == 1 and e["found_as_control"]
    assert e["wrong_before_found"] == 0
    lost_before = [(t, o, "lost" if t == 5.0 else s) for t, o, s in c_rows]
    assert km.judge_kidnap(rows, traj, ref, 11.0, (lost_before, c_traj))["as_control"] == 2
    e = km.judge_kidnap(rows, traj, ref, 11.0, ([(t, o, "lost") for t, o, _ in c_rows], c_traj))
    assert (e["as_control"], e["wrong"], e["found"], e["found_as_control"]) == (0, 4, 7, False)
    uncertain = [(t, o, "uncertain" if t == 11.0 else s) for t, o, s in c_rows]
    e = km.judge_kidnap(rows, traj, ref, 11.0, (uncertain, c_traj))
    assert (e["as_control"], e["wrong"], e["found"]) == (1, 3, 2)
    s = km.aggregate_kidnaps([{**kid(2), "as_control": 1, "found_as_control": True}, kid(3)])
    assert (s["as_control_runs"], s["as_control_scans"], s["found_as_control"]) == (1, 1, 1)


def kid(found, wrong=0, first_wrong=None, lost=None, k=0, before="right", searches=2, proven=1, control=None):
    """A kidnap run's entry; control: (found, wrong) of the run without a kidnap, from the same scan."""
    return {"k": k, "offset_s": 10.0 * k, "cut_seen": True, "found": found, "wrong": wrong,
            "first_wrong": first_wrong, "first_lost": lost, "before": {"tracking": "tracking", "verdict": before},
            "searches": searches, "searches_found": proven,
            "control": None if control is None else {"found": control[0], "wrong": control[1],
                                                     "first_wrong": 1 if control[1] else None, "first_lost": None}}


def test_kidnap_figures_of_a_log_and_mode():
    s = km.aggregate_kidnaps([kid(3, lost=2), kid(20, lost=4), kid(21, wrong=5, first_wrong=9), kid(None, wrong=1,
                                                                                                      first_wrong=2)])
    assert (s["runs"], s["found_within"], s["found"], s["never"]) == (4, 2, 3, 1)
    assert s["scans_to_found"] == {"n": 4, "median": 20.5, "max": None}  # the worst never came
    assert (s["wrong_runs"], s["wrong_scans"], s["earliest_wrong"]) == (2, 6, 2)
    assert s["lost_runs"] == 2 and s["first_lost"]["median"] == 3
    assert (s["searches"], s["searches_found"], s["right_before"], s["not_seen"]) == (8, 4, 4, 0)
    assert s["control_runs"] == 0
    s = km.aggregate_kidnaps([kid(3, control=(1, 0)), kid(5, before="wrong", control=(25, 3))])
    assert s["scans_to_found"] == {"n": 2, "median": 4, "max": 5} and s["right_before"] == 1
    assert (s["control_runs"], s["control_found_within"], s["control_wrong_runs"]) == (2, 1, 1)
    assert s["earliest_wrong"] is None and s["wrong_runs"] == 0
    # more than half never found: no median either
    assert km.aggregate_kidnaps([kid(None), kid(None), kid(2)])["scans_to_found"]["median"] is None


def kidnap_part(per_log, runs=3):
    """A made-up kidnapping part: per log, (frozen runs, updates runs)."""
    kd = {"runs": runs, "length_s": km.KIDNAP_S, "tail_s": km.KIDNAP_TAIL_S, "modes": ["frozen", "updates"],
          "within": km.WITHIN_SCANS, "note": km.KIDNAP_NOTE, "control_note": km.KIDNAP_CONTROL_NOTE, "seconds": 4.2,
          "logs": {}}
    for label, (frozen, updates) in per_log.items():
        r = {"frozen": frozen, "updates": updates}
        kd["logs"][label] = {"span_s": 500.0, "offsets": [10.0 * k for k in range(runs)], "runs": r,
                             "summary": {m: km.aggregate_kidnaps(v) for m, v in r.items()}}
    return kd


def test_kidnap_floors_and_report():
    good = [kid(2, k=0, control=(1, 0)), kid(20, k=1, control=(1, 0)), kid(5, k=2, control=(None, 40))]
    late = [kid(2, k=0), kid(21, k=1), kid(None, k=2, wrong=1234, first_wrong=8)]
    s = section({"a": ([start("right")] * 3, 0.015, 0.015, 0.014, True, True)}, n=3)
    s["kidnap"] = kidnap_part({"a": (good, late)})
    fl = [f for f in km.knownmap_floors(s) if f["kind"].startswith("knownmap-kidnap")]
    assert [(f["kind"], f["status"]) for f in fl] == [("knownmap-kidnap", "PASS"), ("knownmap-kidnap-wrong", "PASS"),
                                                      ("knownmap-kidnap", "MISS"), ("knownmap-kidnap-wrong", "MISS")]
    assert all(f["line"].startswith(f["status"] + " a: known map, kidnapping ") for f in fl)
    assert "frozen, 3 runs with a 60 s cut: 3 found again" in fl[0]["line"] and "median 5, worst 20" in fl[0]["line"]
    assert "with updates, 3 runs with a 60 s cut: 1 found again" in fl[2]["line"]
    assert "< 3" in fl[2]["line"] and "worst never (1 never)" in fl[2]["line"]
    assert "1 gave a trusted pose more than 0.5 m or 5 deg off after the cut (1 234 such scans in all, the earliest " \
           "at scan 8 after the cut) > 0" in fl[3]["line"]
    assert (fl[2]["value"], fl[2]["limit"], fl[3]["value"], fl[3]["limit"]) == (1, 3, 1, 0)
    text = "\n".join(km.report_knownmap(s))
    assert "<!-- table: knownmap kidnap -->" in text
    assert "| a | frozen | 3 | 3 | 3 | 5 / 20 | 0 | 0 / 0 | 0 | 3 | 6 / 3 | 2 / 1 |" in text
    assert "| a | with updates | 3 | 1 | 2 | 21 / never | 1 (1 234 scans) | 0 / 0 | 0 | 3 | 6 / 3 | n/a |" in text
    assert "a run is judged from the first scan after the cut" in text and "global_when_lost=1" in text
    assert "the run of the same mode on the log without a kidnap, which tracked there" in text
    assert "- a, with updates: never found again in runs 2; found again later (scan) in runs 1 (21); wrong trusted " \
           "scans (from scan) in runs 2 (1 234 from scan 8)." in text
    assert "- a, frozen" not in text
    for f in fl:
        assert f["line"] in text
    # skipped, or a manifest from before the part: said so, no floor
    s["kidnap"] = {"skipped": "--kidnap-runs 0"}
    assert "*Kidnapping*: not measured in this run (--kidnap-runs 0)." in km.report_knownmap(s)
    assert not [f for f in km.knownmap_floors(s) if f["kind"].startswith("knownmap-kidnap")]
    del s["kidnap"]
    assert "*Kidnapping*: not measured in this run." in km.report_knownmap(s)
    # a log too short for a cut: a SKIP line
    s["kidnap"] = kidnap_part({"a": ([], [])}, runs=0)
    fl = [f for f in km.knownmap_floors(s) if f["kind"].startswith("knownmap-kidnap")]
    assert [f["status"] for f in fl] == ["SKIP", "SKIP"] and "no room for a 60 s cut" in fl[0]["line"]


def test_bench_option_of_the_kidnapping():
    p = bench.build_parser()
    assert p.parse_args(["--only", "knownmap", "--kidnap-runs", "3"]).kidnap_runs == 3
    assert p.parse_args([]).kidnap_runs is None
    assert "--kidnap-runs" in p.format_help()


M4_REAL = {"scans": 60, "replay_scans": 600, "logs": {
    "aces": {"global": [{"offset_s": 136.5, "max": 899805.0, "mean": 862596.0, "scans": 60, "proven": False,
                         "max_work": 45200, "budget": 45000},
                        {"offset_s": 955.9, "max": 866395.0, "mean": 785755.0, "scans": 15, "proven": True,
                         "max_work": 45018, "budget": 45000}],
             "replay": {"scans": 600, "mean": 387355.0, "p99": 1055950.0, "max": 1800955.0,
                        "matching_worst": {"scan": 227, "insns": 1004665.0, "mapmatch": 963690.0},
                        "recovery_scans": 6,
                        "recovery_worst": {"scan": 269, "insns": 1800955.0, "mapmatch": 1643940.0}}}}}


def test_the_full_logs_cost_floors():
    floors = km.m4_real_floors(M4_REAL)
    assert [f["kind"] for f in floors] == ["m4-real-global", "m4-real-recovery"]
    g, r = floors
    # the worst scan of every search judged: both under the floor
    assert g["status"] == "PASS" and (g["value"], g["limit"]) == (899805.0, 1000000) and g["log"] == "aces"
    for part in ("worst scan 899 805 <= 1 000 000", "136 s: worst 899 805, mean 862 596 over 60 scans, none proven",
                 "956 s: worst 866 395", "global_budget (45 000)"):
        assert part in g["line"], (part, g["line"])
    # the recovery's costliest scan over it: a MISS naming the scan, the
    # costliest matching of all beside it
    assert r["status"] == "MISS" and r["value"] == 1800955.0
    for part in ("the 6 scans tracking recoveries took", "scan 269: 1 800 955 > 1 000 000", "1 643 940 matching",
                 "of all, scan 227: 1 004 665 (963 690 matching)", "p99 1 055 950", "first 600 scans"):
        assert part in r["line"], (part, r["line"])
    # under it: a PASS; no recovery in the scans: a SKIP saying so
    under = json.loads(json.dumps(M4_REAL))
    under["logs"]["aces"]["replay"]["recovery_worst"] = {"scan": 240, "insns": 736000.0, "mapmatch": 600000.0}
    assert km.m4_real_floors(under)[1]["status"] == "PASS"
    under["logs"]["aces"]["replay"]["recovery_worst"] = None
    none = km.m4_real_floors(under)[1]
    assert none["status"] == "SKIP" and "no tracking recovery in them" in none["line"]
    # not run: one SKIP line saying why
    skip = km.m4_real_floors({"skipped": "--no-m4"})
    assert len(skip) == 1 and skip[0]["status"] == "SKIP" and "--no-m4" in skip[0]["line"]
    assert km.m4_real_floors(None)[0]["status"] == "SKIP"


def test_a_log_is_cut_from_a_point_for_the_target(tmp_path):
    from rsm_tools import m4cost
    src = tmp_path / "in.clf"
    lines = []
    for k in range(10):
        t = 100.0 + k
        lines.append(f"ODOM 0 0 0 0 0 0 {t:.1f} host {t:.1f}\n")
        lines.append("FLASER 3 1 1 1 0 0 0 0 0 0 " + f"{t + 0.5:.1f} host {t + 0.5:.1f}\n")
        lines.append("# a comment line\n")
    src.write_text("".join(lines))
    out = tmp_path / "cut.clf"
    # from 4.2 s after the first record: the scan at 104.5 is the first kept
    assert m4cost.cut_log(src, out, 4.2, 3) == 3
    kept = out.read_text().splitlines()
    assert kept[0].startswith("FLASER") and " 104.5 " in kept[0]
    assert [l.split()[0] for l in kept] == ["FLASER", "ODOM", "FLASER", "ODOM", "FLASER"]
    assert all(not l.startswith("#") for l in kept)
    # past the end: what is left
    assert m4cost.cut_log(src, out, 8.0, 5) == 2
