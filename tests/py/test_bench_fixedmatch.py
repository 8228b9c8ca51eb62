"""The floors and report of the bench's fixed-point matcher check
(rsm_tools.bench.fixedmatch) on made-up numbers: no build, no rsm-nav run."""

from rsm_tools.bench import fixedmatch as fm


def section(fixed, float_median, float_max):
    runs = list(fixed)
    return {"nav": "x", "updates": [0.3 + 0.005 * k for k in range(len(runs))],
            "logs": {"intel": {"runs": runs, "median": sorted(runs)[len(runs) // 2], "max": max(runs),
                               "float_median": float_median, "float_max": float_max}}}


def lines(fx):
    return [f["line"] for f in fm.floors(fx)]


def test_a_fixed_build_within_the_tolerance_passes_both_floors():
    fx = section([0.0150, 0.0151, 0.0152, 0.0180], 0.0151, 0.0182)
    got = lines(fx)
    assert len(got) == 2 and all(l.startswith("PASS ") for l in got), got
    assert "x1.007 the float build's 0.0151 m" in got[0]
    assert "x1.18 its median" in got[1] and "the float build's worst 0.0182 m" in got[1]


def test_a_median_off_by_more_than_the_tolerance_or_a_long_tail_misses():
    off = lines(section([0.0170, 0.0171, 0.0172], 0.0151, 0.0182))
    assert off[0].startswith("MISS ") and off[1].startswith("PASS "), off
    tail = lines(section([0.0150, 0.0151, 0.0152, 0.0500], 0.0151, 0.0182))
    assert tail[0].startswith("PASS ") and tail[1].startswith("MISS "), tail
    # exactly at the edges: within
    edge = section([0.0151 * (1 + fm.MEDIAN_TOLERANCE)] * 3, 0.0151, 0.0182)
    assert lines(edge)[0].startswith("PASS ")


def test_nothing_measured_gives_no_floor_and_no_report():
    assert fm.floors(None) == [] and fm.report(None) == []
    assert fm.floors({"skipped": "--faults 0"}) == [] and fm.report({"skipped": "--faults 0"}) == []


def test_the_report_has_a_row_per_log():
    rep = fm.report(section([0.0150, 0.0151, 0.0152], 0.0151, 0.0182))
    assert rep[0] == "### The fixed-point matcher"
    assert "| intel | 3 | 0.0151 | 0.0152 | 0.0151 | 0.0182 |" in rep
