"""The arithmetic of the bench's section "Faults" (rsm_tools.bench.faults) on
made-up numbers, and how a run is judged (removed scans filled by odometry,
a mount composed back, slip copies left out) on small made-up logs: no
rsm-nav run, no full log."""

import math

import pytest

from rsm_tools import evaluate as ev
from rsm_tools import faults as flt
from rsm_tools.bench import faults as bf
from rsm_tools.carmen import pose_compose


def run_entry(values, odometry=None, recoveries=None, false=None):
    n = len(values)
    rec = recoveries or [0] * n
    return [{"k": k, "update": bf.fault_update(k), "all": v, "odometry_all": (odometry or [1.0] * n)[k],
             "recoveries": rec[k], "recoveries_judged": rec[k], "false_recoveries": (false or [0] * n)[k]}
            for k, v in enumerate(values)]


def section(clean, faults_, odometry_all=1.0, runs=None, false=None):
    """A made-up result of run_faults for one log (false: per fault, false
    recoveries per run)."""
    cs = bf.stats(clean)
    by_update = dict(zip(bf.clean_updates(len(clean)), clean))
    entry = {"log": "x.clf.gz", "relations": 10, "odometry": {"all": odometry_all, "local": 0.1, "matched": 10},
             "clean": cs, "clean_runs": [], "clean_reused": 0, "faults": {}}
    for name, vals in faults_.items():
        fr = run_entry(vals, recoveries=[1] * len(vals), false=(false or {}).get(name))
        entry["faults"][name] = {"runs": fr, **bf.summarize(fr, cs["median"], by_update)}
    n = runs or max(len(v) for v in faults_.values())
    return {"runs": n, "clean_runs": len(clean), "updates": [bf.fault_update(k) for k in range(n)],
            "clean_updates": bf.clean_updates(len(clean)), "faults": [{"name": k, "what": "made up"} for k in faults_],
            "recovery_note": bf.RECOVERY_NOTE, "logs": {"log": entry}}


def test_update_distances_of_the_runs():
    assert bf.fault_update(0) == 0.3 and bf.fault_update(19) == 0.49
    assert bf.clean_updates(4) == [0.3, 0.305, 0.31, 0.315]
    # the fault runs' distances are among the clean runs' (every other one)
    assert {bf.fault_update(k) for k in range(20)} <= set(bf.clean_updates(40))


def test_stats_median_worst_and_missing_runs():
    s = bf.stats([0.3, 0.1, 0.2, 0.4])
    assert (s["n"], s["missing"], s["median"], s["max"], s["min"]) == (4, 0, 0.25, 0.4, 0.1)
    s = bf.stats([0.3, float("nan"), 0.1, None])
    assert (s["n"], s["missing"], s["median"], s["min"]) == (2, 2, 0.2, 0.1)
    assert math.isnan(s["max"])  # a run without a figure: the worst is unknown
    s = bf.stats([])
    assert s["n"] == 0 and math.isnan(s["median"])


def test_summary_ratios_to_the_clean_median():
    fr = run_entry([0.02, 0.03, 0.05], odometry=[0.5, 0.7, 0.6], recoveries=[0, 2, 1])
    s = bf.summarize(fr, 0.02)
    assert s["median"] == 0.03 and s["max"] == 0.05
    assert math.isclose(s["x_median"], 1.5) and math.isclose(s["x_worst"], 2.5)
    assert s["odometry"]["median"] == 0.6 and (s["recoveries"]["median"], s["recoveries"]["max"]) == (1, 2)
    assert s["worst_update"] == 0.32 and s["worst_clean"] is None  # no clean run given
    s = bf.summarize(fr, 0.02, {0.3: 0.01, 0.31: 0.02, 0.32: 0.04})
    assert s["worst_clean"] == 0.04  # the clean run at the worst run's update distance


def test_floors_on_made_up_numbers():
    clean = [0.010] * 20 + [0.012] * 19 + [0.031]  # median 0.011, worst 0.031 = x2.82
    fa = section(clean, {
        "good": [0.011] * 10 + [0.0135] * 9 + [0.022],   # median 0.0123 <= x1.25, worst exactly x2
        "bad-median": [0.014] * 19 + [0.015],            # x1.27 median: MISS; worst x1.36: PASS
        "bad-worst": [0.011] * 19 + [0.0221],            # worst x2.01: MISS; median PASS
    }, odometry_all=0.030)
    f = bf.fault_floors(fa)
    got = [(x["kind"], x["status"]) for x in f]
    assert got == [("faults-clean", "PASS"),
                   ("faults", "PASS"), ("faults", "PASS"),
                   ("faults", "PASS"), ("faults", "MISS"),
                   ("faults", "MISS"), ("faults", "PASS"),
                   ("faults-recovery", "PASS")]
    assert math.isclose(f[0]["value"], 0.031 / 0.011) and f[0]["limit"] == 3.0
    assert f[0]["line"] == ("PASS log: clean, worst of 40 runs (map_update_m 0.3 to 0.495) 0.0310 m = x2.82 the "
                            "clean median 0.0110 m <= x3, all-relations translation")
    assert math.isclose(f[1]["value"], 2.0) and f[1]["limit"] == 2.0
    # the worst "good" run is run 19, at map_update_m 0.49: the clean run there is the 39th (0.012)
    assert f[1]["line"] == ("PASS log: good fault, worst of 20 runs 0.0220 m (the clean run at its map_update_m 0.49: "
                            "0.0120 m) = x2.00 the clean median 0.0110 m <= x2, < odometry alone 0.0300 m, "
                            "all-relations translation")
    assert f[4]["line"] == "MISS log: bad-median fault, median of 20 runs 0.0140 m = x1.27 the clean median > x1.25"
    assert "= x2.01 the clean median 0.0110 m > x2, < odometry alone" in f[5]["line"]
    assert f[-1]["line"].startswith("PASS log: false recoveries 0 of 60 judged in 60 fault runs (0 more not judged: "
                                    "no relation near) == 0")
    # one false recovery anywhere is a MISS
    fa = section(clean, {"good": [0.011] * 20}, odometry_all=0.030, false={"good": [0] * 19 + [1]})
    f = bf.fault_floors(fa)
    assert f[-1]["status"] == "MISS" and f[-1]["value"] == 1 and "false recoveries 1 of 20" in f[-1]["line"]
    # within x2 of the clean median but not below odometry alone: a MISS
    fa = section(clean, {"above-odometry": [0.011] * 19 + [0.0205]}, odometry_all=0.020)
    f = bf.fault_floors(fa)
    assert [x["status"] for x in f] == ["PASS", "MISS", "PASS", "PASS"]
    assert "x1.86 the clean median 0.0110 m <= x2, >= odometry alone 0.0200 m" in f[1]["line"]


def test_clean_floor_misses_a_wild_clean_run_and_unmeasured_is_skipped():
    fa = section([0.01] * 39 + [0.0301], {"x": [0.01, 0.01]})
    f = bf.fault_floors(fa)
    assert f[0]["status"] == "MISS" and "x3.01" in f[0]["line"] and "> x3" in f[0]["line"]
    fa = section([], {"x": [0.01]})
    assert [x["status"] for x in bf.fault_floors(fa)] == ["SKIP", "SKIP", "PASS"]
    # a fault run without a figure: the worst is unknown and cannot pass
    fa = section([0.01] * 4, {"x": [0.01, float("nan")]})
    f = bf.fault_floors(fa)
    assert f[1]["status"] == "MISS" and "worst of 2 runs n/a" in f[1]["line"]
    assert bf.fault_floors(None) == [] and bf.fault_floors({"skipped": "--faults 0"}) == []


def test_report_table_shows_the_figures():
    fa = section([0.010, 0.011, 0.012, 0.013], {"stall": [0.012, 0.020], "scale": [0.011, 0.0115]},
                 odometry_all=0.5)
    text = "\n".join(bf.report_faults(fa))
    assert "### Faults" in text and "<!-- table: faults -->" in text
    rows = [l for l in text.splitlines() if l.startswith("| log | fault |")]
    assert len(rows) == 1
    assert "| log | clean | 4 | 0.0115 | 0.0130 | 1.00 | 1.13 |  |  | 0.5000 |  |  |  |" in text
    # the worst stall run is run 1 (map_update_m 0.31), where the clean run made 0.012
    assert "| log | stall | 2 | 0.0160 | 0.0200 | 1.39 | 1.74 | 0.0120 (0.310) |  | 0.5000 | 1.0000 | 1 / 1 | 0 of 2 (+0) |" in text
    assert "False recoveries: a recovery is false when" in text
    assert "Not measured in this run (--faults 0)." in "\n".join(bf.report_faults({"skipped": "--faults 0"}))


def test_a_fault_that_removes_scans_is_set_beside_the_clean_runs_judged_alike():
    """For sparse, dropped or missing scans the clean run at the same
    map_update_m, judged as the faulty run is (dead reckoning over the
    scans the fault removed), is reported beside the median: the share of
    the error that the judge, not the fault, makes."""
    fa = section([0.010] * 4, {"sparse": [0.015, 0.016]})
    for r, cj in zip(fa["logs"]["log"]["faults"]["sparse"]["runs"], (0.012, 0.014)):
        r["clean_judged"] = cj
    fr = fa["logs"]["log"]["faults"]["sparse"]["runs"]
    fa["logs"]["log"]["faults"]["sparse"] = {"runs": fr, **bf.summarize(fr, 0.010)}
    f = bf.fault_floors(fa)
    assert f[2]["status"] == "MISS" and "x1.55 the clean median > x1.25" in f[2]["line"]
    assert "judged alike" in f[2]["line"] and "median 0.0130 m, the fault's median x1.19 that" in f[2]["line"]
    assert "| 0.0130 (x1.19) |" in "\n".join(bf.report_faults(fa))


def test_the_clean_run_judged_alike_is_dead_reckoned_over_the_removed_scans():
    """The clean run's poses at the scans the faulty run kept, the rest
    moved on by the faulty log's odometry; with a mount the clean run's
    laser pose (the clean log's laser is at the robot's origin) is taken
    back to the robot before and composed again after."""
    log = _log()
    res = flt.apply_faults(log, flt.FaultSpec(gaps=[(3.0, 4.0)]))  # scans 3..6 removed
    # the clean run drifts 0.01 m sideways a scan; the faulty run keeps what the fault kept
    clean = ev.Trajectory((s.stamp, s.odom[0], s.odom[1] + 0.01 * i, s.odom[2]) for i, s in enumerate(log.scans))
    run = ev.Trajectory((log.scans[o.src].stamp, *o.pose) for o in res.kept_scans)
    got = bf.clean_as_judged(clean, run, res)
    assert [t for t, *_ in got] == [s.stamp for s in log.scans]
    for i, (t, x, y, th) in enumerate(got):
        drift = 0.01 * (i if i not in (3, 4, 5, 6) else 2)  # the removed ones carry scan 2's offset on
        assert math.isclose(y, log.scans[i].odom[1] + drift, abs_tol=1e-9), i
    m = (0.22, 0.0, 0.0)
    res = flt.apply_faults(log, flt.FaultSpec(mount=m, gaps=[(3.0, 4.0)]))
    clean = ev.Trajectory((s.stamp, *s.laser) for s in log.scans)  # exact
    run = ev.Trajectory((log.scans[o.src].stamp, *o.pose) for o in res.kept_scans)
    for (t, x, y, th), s in zip(bf.clean_as_judged(clean, run, res), log.scans):
        assert math.isclose(x, s.laser[0], abs_tol=1e-9) and math.isclose(y, s.laser[1], abs_tol=1e-9)
        assert math.isclose(th, s.laser[2], abs_tol=1e-9)


def _log(n=12, mount=False):
    """A made-up log: the robot drives 0.1 m per scan along x, turning 0.05 rad per scan."""
    lines = []
    pose = (0.0, 0.0, 0.0)
    for i in range(n):
        p = " ".join(f"{v:.6f}" for v in pose)
        rng = " ".join(f"{2 + 0.01 * j:.2f}" for j in range(8))
        lines.append(f"FLASER 8 {rng} {p} {p} {100 + i:.6f} h {i:.6f}\n".encode())
        pose = pose_compose(pose, (0.1, 0.0, 0.05))
    return flt.load_lines(lines)


def test_removed_scans_are_judged_at_the_last_estimate_moved_by_odometry():
    log = _log()
    res = flt.apply_faults(log, flt.FaultSpec(gaps=[(3.0, 4.0)]))  # scans 3..6 removed
    assert [o.src for o in res.kept_scans] == [0, 1, 2, 7, 8, 9, 10, 11]
    # a made-up run: the estimates of the kept scans are the odometry moved by 1 m in y
    est = ev.Trajectory((log.scans[o.src].stamp, o.pose[0], o.pose[1] + 1.0, o.pose[2]) for o in res.kept_scans)
    got = bf.judged_trajectory(est, res)
    assert [t for t, *_ in got] == [s.stamp for s in log.scans]
    for (t, x, y, th), sc in zip(got, log.scans):
        assert math.isclose(x, sc.odom[0], abs_tol=1e-9) and math.isclose(y, sc.odom[1] + 1.0, abs_tol=1e-9)
    # the faulty log's odometry alone is judged at every scan too
    assert len(bf.odometry_alone(res)) == len(log.scans)


def test_a_moved_mount_is_judged_at_the_laser_and_slip_copies_not_at_all():
    log = _log()
    m = (0.22, 0.0, 0.0)
    res = flt.apply_faults(log, flt.FaultSpec(mount=m, slips=[(4, 3)]))
    assert len(res.out) == len(log.scans) + 2
    # the robot's estimate composed with the mount gives back the laser's (the original) pose
    est = ev.Trajectory()
    for o in res.out:
        t = o.stamp_us / 1e6 if o.stamp_us is not None else log.scans[o.src].stamp
        est.add(t, *res.poses[log.scan_event[o.src]] if not o.copy else o.pose)
    got = bf.judged_trajectory(est, res)
    assert [t for t, *_ in got] == [s.stamp for s in log.scans]
    first = got[0]
    assert math.isclose(first[1], log.scans[0].laser[0], abs_tol=1e-9)
    odo = bf.odometry_alone(res)
    assert all(math.isclose(a[3], b[3], abs_tol=1e-9) for a, b in zip(odo, got))


@pytest.mark.parametrize("name", bf.FAULT_NAMES)
def test_every_fault_plan_fits_a_short_log(name, head_log):
    log = flt.load_log(head_log)
    for k in range(3):
        spec = bf.plan(name, log, k, "head")
        res = flt.apply_faults(log, spec)
        assert res.summaries
        assert spec == bf.plan(name, log, k, "head")  # the same places for the same run
    if name in ("spike", "reset", "slip", "gap", "longgap"):
        assert len({flt.describe(bf.plan(name, log, k, "head")) for k in range(6)}) > 1  # places vary by run


def test_recovered_stamps_come_from_the_scan_log(tmp_path):
    slog = tmp_path / "s.scans"
    slog.write_text("# rsm-nav scan log: timestamp[s] outcome tracking odometry recovered fit_ratio\n"
                    "11.000000 accepted tracking trusted 1 0.9\n12.000000 accepted tracking trusted 0 0.9\n"
                    "13.000000 accepted tracking refuted 1 0.8\n15.000000 poor_fit uncertain trusted 0 0.1\n"
                    "5.000000 accepted tracking trusted 1 0.9\n")
    assert bf.recovered_stamps(slog) == [11.0, 13.0, 5.0]


def _rel(truth, t1, t2):
    return ev.Relation(t1, t2, *ev.between(truth(t1), truth(t2)))


def test_false_recoveries_are_told_by_the_relations_across_them():
    """A recovery at t is judged by the ground truth across it: relations
    with one end from t to 20 s after it (or to the next recovery) and the
    other up to 60 s before t. It is right when one of them agrees within
    0.3 m and 5 deg (the run may have gone wrong before a search put it
    right), false when none does, not judged with none at all. Relations
    that do not cross it cannot tell: a wrong pose tracked on agrees with
    itself."""
    def truth(t):
        return (0.1 * t, 0.0, 0.0)

    # right up to 9.9; a recovery at 10 lands 0.4 m off and tracking carries that on to 19.9; one at 20 lands
    # 6 deg off; one at 30 puts it right again after it went 1 m wrong at 29 (a pose 1 s before it)
    def run_pose(t):
        x, y, th = truth(t)
        if 10.0 <= t < 20.0:
            return (x, y + 0.4, th)
        if 20.0 <= t < 29.0:
            return pose_compose((x, y, th), (0.0, 0.0, math.radians(6.0)))
        if 29.0 <= t < 30.0:
            return (x, y + 1.0, th)
        return (x, y, th)

    stamps = [0.5 * i for i in range(0, 201)]
    judged = ev.Trajectory((t, *run_pose(t)) for t in stamps)
    rels = [_rel(truth, a, b) for a, b in ((5.0, 11.0), (12.0, 15.0), (15.0, 21.0), (29.0, 30.5), (25.0, 31.0),
                                           (1.0, 32.0), (60.0, 65.0))]
    # 10: 5->11 is off 0.4 m (12->15 does not cross it): false
    assert bf.false_recoveries([10.0], judged, rels) == (1, 1, 0)
    # 20 (the next recovery at 30): 15->21 off 6 deg: false; 30: 29->30.5 and 25->31 disagree (poses it
    # replaced), 1->32 agrees: right
    assert bf.false_recoveries([20.0, 30.0], judged, rels) == (2, 1, 0)
    # without the one at 30, 1->32 would answer for 20's pose carried on (and is right there)
    assert bf.false_recoveries([20.0], judged, rels) == (1, 0, 0)
    # without 1->32 nothing agrees at 30; a far end more than 60 s before does not count
    assert bf.false_recoveries([30.0], judged, [r for r in rels if r.t1 != 1.0]) == (1, 1, 0)
    far = [_rel(truth, 0.0, 70.0)]
    assert bf.false_recoveries([65.0], judged, far) == (0, 0, 1)
    # 62: 60->65 crosses it; 50: nothing crosses it within 20 s
    assert bf.false_recoveries([62.0, 50.0], judged, rels) == (1, 0, 1)
    # the next recovery ends the span a recovery answers for: with one at 10.5, 5->11 judges that one, not 10
    assert bf.false_recoveries([10.0, 10.5], judged, rels) == (1, 1, 1)
    # an end the run did not estimate (dead reckoning placed it) says nothing
    est = set(stamps) - {11.0}
    assert bf.false_recoveries([10.0], judged, rels, est) == (0, 0, 1)


def test_a_recovery_that_moves_as_the_clean_run_does_is_right():
    """Where every run jumps back onto a place mapped long before (drift put
    right at a loop), the relation across the jump is off in the clean run
    too: a recovery that moved over it as the clean run did is right."""
    def truth(t):
        return (0.1 * t, 0.0, 0.0)

    def jumped(t):
        x, y, th = truth(t)
        return (x, y + (0.35 if t >= 10.0 else 0.0), th)

    stamps = [0.5 * i for i in range(0, 41)]
    run = ev.Trajectory((t, *jumped(t)) for t in stamps)
    rels = [_rel(truth, 9.0, 10.5)]
    assert bf.false_recoveries([10.0], run, rels) == (1, 1, 0)
    clean = ev.Trajectory((t, *jumped(t)) for t in stamps)
    assert bf.false_recoveries([10.0], run, rels, None, clean) == (1, 0, 0)
    other = ev.Trajectory((t, *truth(t)) for t in stamps)  # the clean run did not jump: no excuse
    assert bf.false_recoveries([10.0], run, rels, None, other) == (1, 1, 0)


def test_a_recovery_that_lands_on_the_clean_run_after_a_long_wrong_stretch_is_right():
    """A run 0.4 m off since long before the span (a gap's step) that a
    search brings within 0.3 m and 5 deg of the clean run's pose at its scan
    is right, though every relation across it starts from a wrong pose (the
    issue's own test). One that jumps to 0.35 m off the clean run's other
    side is not."""
    def truth(t):
        return (0.1 * t, 0.0, 0.0)

    def run_pose(t, after):
        x, y, th = truth(t)
        return (x, y + (0.4 if t < 100.0 else after), th)

    stamps = [0.5 * i for i in range(0, 241)]
    rels = [_rel(truth, 70.0, 101.0), _rel(truth, 95.0, 110.0)]
    clean = ev.Trajectory((t, *truth(t)) for t in stamps)
    put_right = ev.Trajectory((t, *run_pose(t, 0.1)) for t in stamps)
    assert bf.false_recoveries([100.0], put_right, rels) == (1, 1, 0)
    assert bf.false_recoveries([100.0], put_right, rels, None, clean) == (1, 0, 0)
    short = ev.Trajectory((t, *run_pose(t, -0.35)) for t in stamps)
    assert bf.false_recoveries([100.0], short, rels, None, clean) == (1, 1, 0)
    # with no relation across it, it stays unjudged
    assert bf.false_recoveries([100.0], put_right, [_rel(truth, 20.0, 30.0)], None, clean) == (0, 0, 1)


def test_false_recoveries_are_judged_at_the_laser_with_a_mount():
    """With the laser off the robot's origin the judged trajectory holds the
    laser's pose (judged_trajectory composes the mount), as the relations do."""
    log = _log()
    m = (0.22, 0.0, 0.0)
    res = flt.apply_faults(log, flt.FaultSpec(mount=m))
    est = ev.Trajectory((log.scans[o.src].stamp, *o.pose) for o in res.kept_scans)
    judged = ev.Trajectory(bf.judged_trajectory(est, res))
    stamps = [s.stamp for s in log.scans]
    rels = [ev.Relation(stamps[a], stamps[b], *ev.between(log.scans[a].laser, log.scans[b].laser))
            for a, b in ((0, 5), (1, 6), (0, 8))]
    assert bf.false_recoveries([stamps[5]], judged, rels) == (1, 0, 0)
    # the robot's pose judged instead of the laser's would be off by the lever arm turned with the robot
    errs = [ev.relation_error(ev.between(tuple(est.lookup(r.t1, tolerance=0.0)), tuple(est.lookup(r.t2, tolerance=0.0))),
                              (r.x, r.y, r.yaw))[0] for r in rels]
    assert max(errs) > 0.01



def test_fault_names_are_checked_before_anything_runs(capsys):
    """--fault-names picks faults for --only faults; a name the bench does
    not know, an empty list, or the option without --only faults is refused
    with the known names, before any build or log is looked for."""
    from rsm_tools import bench

    assert bench.main(["--only", "faults", "--fault-names", "gap,nope"]) == 1
    err = capsys.readouterr().err
    assert "unknown nope" in err and "longgap" in err
    assert bench.main(["--only", "faults", "--fault-names", " , "]) == 1
    assert "(none given)" in capsys.readouterr().err
    assert bench.main(["--fault-names", "gap"]) == 1
    assert "goes with --only faults" in capsys.readouterr().err
    assert bench.main(["--odom-lines"]) == 1
    assert "--odom-lines goes with --only faults" in capsys.readouterr().err
