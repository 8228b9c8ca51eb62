import json
import math
import random
import subprocess
import sys

import pytest

from conftest import subprocess_env
from rsm_tools import evaluate as ev
from rsm_tools.carmen import time_key
from rsm_tools.evaluate import (
    Relation,
    Trajectory,
    between,
    compose,
    evaluate,
    load_poses,
    load_relations,
    odometry_trajectory,
    relations_from_poses,
    wrap_angle,
)


def _random_path(n=50, seed=1, t0=1000.0, dt=0.2):
    rng = random.Random(seed)
    pose = (rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-math.pi, math.pi))
    pts = []
    for i in range(n):
        pts.append((t0 + i * dt,) + pose)
        step = (rng.uniform(0, 0.3), rng.uniform(-0.05, 0.05), rng.uniform(-0.4, 0.4))
        pose = compose(pose, step)
    return pts


def _relations_of(pts, pairs):
    rels = []
    for i, j in pairs:
        d = between(pts[i][1:], pts[j][1:])
        rels.append(Relation(pts[i][0], pts[j][0], d[0], d[1], d[2]))
    return rels


# --------------------------------------------------------------------------- SE(2)


def test_wrap_angle():
    assert wrap_angle(0.0) == 0.0
    assert wrap_angle(math.pi) == pytest.approx(math.pi)
    assert wrap_angle(-math.pi) == pytest.approx(math.pi)  # (-pi, pi]
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert wrap_angle(-7.0) == pytest.approx(-7.0 + 2 * math.pi)
    for a in (-10.0, -3.2, 3.2, 10.0, 100.0):
        w = wrap_angle(a)
        assert -math.pi < w <= math.pi
        assert math.sin(w) == pytest.approx(math.sin(a)) and math.cos(w) == pytest.approx(math.cos(a))


def test_between_inverts_compose():
    rng = random.Random(7)
    for _ in range(100):
        a = (rng.uniform(-9, 9), rng.uniform(-9, 9), rng.uniform(-4, 4))
        d = (rng.uniform(-9, 9), rng.uniform(-9, 9), rng.uniform(-3, 3))
        b = compose(a, d)
        got = between(a, b)
        assert got[0] == pytest.approx(d[0]) and got[1] == pytest.approx(d[1])
        assert wrap_angle(got[2] - d[2]) == pytest.approx(0.0, abs=1e-12)
    # hand-checked: from a robot at (1, 1) facing +y, the point (1, 3) is 2 m ahead
    assert between((1, 1, math.pi / 2), (1, 3, math.pi / 2)) == pytest.approx((2.0, 0.0, 0.0))


# --------------------------------------------------------------------------- metric


def test_trajectory_equal_to_ground_truth_gives_zero_error():
    pts = _random_path()
    pairs = [(i, i + 1) for i in range(len(pts) - 1)] + [(0, 49), (10, 30)]
    rels = _relations_of(pts, pairs)
    res = evaluate(pts, rels)
    assert res["matched"] == len(rels) and res["unmatched"] == 0 and res["inexact"] == 0
    for key in ("translation", "rotation"):
        assert res[key]["count"] == len(rels)
        assert res[key]["mean"] == pytest.approx(0.0, abs=1e-9)
        assert res[key]["max"] == pytest.approx(0.0, abs=1e-9)


def test_metric_ignores_a_global_rigid_motion():
    pts = _random_path(seed=3)
    rels = _relations_of(pts, [(i, i + 3) for i in range(len(pts) - 3)])
    g = (12.0, -4.0, 2.5)
    moved = [(p[0],) + compose(g, p[1:]) for p in pts]
    res = evaluate(moved, rels)
    assert res["translation"]["max"] == pytest.approx(0.0, abs=1e-9)
    assert res["rotation"]["max"] == pytest.approx(0.0, abs=1e-9)


def test_known_perturbation_gives_known_error():
    pts = _random_path(seed=5)
    rels = _relations_of(pts, [(4, 5), (10, 20)])
    # perturb the second end of each relation in its own frame: the error of the
    # relation is then exactly the perturbation
    bad = {0: (0.03, -0.04, math.radians(2.0)), 1: (-0.3, 0.4, math.radians(-10.0))}
    est = list(pts)
    est[5] = (pts[5][0],) + compose(pts[5][1:], bad[0])
    est[20] = (pts[20][0],) + compose(pts[20][1:], bad[1])
    res = evaluate(est, rels, details=True)
    (_, _, e0t, e0r), (_, _, e1t, e1r) = res["errors"]
    assert e0t == pytest.approx(0.05) and e0r == pytest.approx(2.0)
    assert e1t == pytest.approx(0.5) and e1r == pytest.approx(10.0)
    tr, rot = res["translation"], res["rotation"]
    assert tr["mean"] == pytest.approx(0.275) and tr["std"] == pytest.approx(0.225)
    assert tr["max"] == pytest.approx(0.5)
    assert tr["rmse"] == pytest.approx(math.sqrt((0.05 ** 2 + 0.5 ** 2) / 2))
    assert rot["mean"] == pytest.approx(6.0) and rot["std"] == pytest.approx(4.0)
    assert rot["max"] == pytest.approx(10.0)


def test_translation_error_is_measured_in_the_true_relation_frame():
    # true motion: 1 m forward and a quarter turn left.  First estimate: the end
    # pose 0.1 m further along x, so the error is 0.1 m and no rotation.
    truth = Relation(0.0, 1.0, 1.0, 0.0, math.pi / 2)
    traj = [(0.0, 0.0, 0.0, 0.0), (1.0, 1.1, 0.0, math.pi / 2)]
    res = evaluate(traj, [truth], details=True)
    assert res["errors"][0][2] == pytest.approx(0.1)
    assert res["errors"][0][3] == pytest.approx(0.0, abs=1e-9)
    # Second estimate: the same end points, but the start heading is off by -3 deg.
    # The estimated relation is then turned by +3 deg: its end lies on a circle of
    # radius 1 m, 2 sin(1.5 deg) away from the true end.
    traj = [(0.0, 0.0, 0.0, math.radians(-3)), (1.0, 1.0, 0.0, math.pi / 2)]
    res = evaluate(traj, [truth], details=True)
    assert res["errors"][0][3] == pytest.approx(3.0)
    est = between((0.0, 0.0, math.radians(-3)), (1.0, 0.0, math.pi / 2))
    err = between((1.0, 0.0, math.pi / 2), est)
    assert res["errors"][0][2] == pytest.approx(math.hypot(err[0], err[1]))
    assert res["errors"][0][2] == pytest.approx(2 * math.sin(math.radians(1.5)))


@pytest.mark.parametrize("true_yaw,est_yaw,expected_deg", [
    (math.pi - 0.01, -math.pi + 0.02, math.degrees(0.03)),
    (-math.pi + 0.01, math.pi - 0.01, math.degrees(0.02)),
    (math.radians(179), math.radians(-179), 2.0),
    (math.radians(-90), math.radians(90), 180.0),
])
def test_rotation_error_wraps_around_pi(true_yaw, est_yaw, expected_deg):
    truth = Relation(1.0, 2.0, 0.5, 0.25, true_yaw)
    traj = Trajectory([(1.0, 0.0, 0.0, 0.0), (2.0, 0.5, 0.25, est_yaw)])
    res = evaluate(traj, [truth])
    assert res["rotation"]["mean"] == pytest.approx(expected_deg)
    assert res["translation"]["mean"] == pytest.approx(0.0, abs=1e-12)


def test_unmatched_tolerance_and_span_filters():
    traj = {10.0: (0, 0, 0), 11.0: (1, 0, 0), 12.0000004: (2, 0, 0), 20.0: (3, 0, 0)}
    rels = [
        (10.0, 11.0, 1.0, 0.0, 0.0),        # exact
        (11.0, 12.0, 1.0, 0.0, 0.0),        # 12.0000004 rounds to the same microsecond
        (11.0, 12.0006, 1.0, 0.0, 0.0),     # nearest within 1 ms: inexact
        (10.0, 15.0, 9.0, 9.0, 0.0),        # 15.0 is missing: unmatched
        (10.0, 20.0, 3.0, 0.0, 0.0),        # long span
    ]
    res = evaluate(traj, rels)
    assert (res["relations"], res["in_span"], res["matched"], res["unmatched"],
            res["inexact"]) == (5, 5, 4, 1, 1)
    assert res["translation"]["max"] == pytest.approx(0.0, abs=1e-12)
    res = evaluate(traj, rels, tolerance=0.0)
    assert (res["matched"], res["unmatched"], res["inexact"]) == (3, 2, 0)
    res = evaluate(traj, rels, tolerance=1e-4)
    assert (res["matched"], res["unmatched"]) == (3, 2)
    res = evaluate(traj, rels, max_span=2.0)
    assert (res["in_span"], res["matched"], res["unmatched"]) == (3, 3, 0)
    res = evaluate(traj, rels, min_span=2.0)
    assert (res["in_span"], res["matched"], res["unmatched"]) == (2, 1, 1)
    res = evaluate(traj, [])
    assert res["matched"] == 0 and math.isnan(res["translation"]["mean"])


def test_trajectory_duplicates_and_order():
    tr = Trajectory([(3.0, 3, 0, 0), (1.0, 1, 0, 0), (2.0, 2, 0, 0), (1.0, 9, 0, 0)])
    assert len(tr) == 3
    assert [p.t for p in tr.points()] == [1.0, 2.0, 3.0]
    assert tr.lookup(1.0) == (9, 0, 0)  # the last line for a timestamp wins
    assert tr.lookup(2.0009) == (2, 0, 0)
    assert tr.lookup(2.0011) is None
    assert tr.find(2.0) == ((2, 0, 0), True) and tr.find(2.0005)[1] is False


# --------------------------------------------------------------------------- files


def test_load_relations(tmp_path):
    p = tmp_path / "r.relations"
    p.write_text(
        "# t1 t2 x y z roll pitch yaw\n"
        "\n"
        "976052905.167303 976052911.885496 -0.056990 -0.128430 0.000000 0.000000 0.000000 -1.682210\n"
        "  1.5 2.5 1 2 0 0 0 3.0  \n"
    )
    rels = load_relations(p)
    assert rels == [
        Relation(976052905.167303, 976052911.885496, -0.05699, -0.12843, -1.68221),
        Relation(1.5, 2.5, 1.0, 2.0, 3.0),
    ]
    assert rels[0].span == pytest.approx(6.718193)
    p.write_text("1 2 3 4 5 6 7\n")
    with pytest.raises(ValueError, match="8 fields"):
        load_relations(p)
    p.write_text("1 2 3 4 5 6 7 eight\n")
    with pytest.raises(ValueError, match="non-numeric"):
        load_relations(p)


def test_load_poses_detects_format(tmp_path):
    a = tmp_path / "traj.txt"
    a.write_text("# t x y theta\n1.0 0 0 0\n\n2.0 1 0 0.5\n")
    b = tmp_path / "gt.txt"
    b.write_text("# t idx x y theta\n1.0 7 0 0 0\n2.0 9 1 0 0.5\n")
    ta, fa = load_poses(a)
    tb, fb = load_poses(b)
    assert (fa, fb) == ("trajectory", "corrected-poses")
    assert ta.points() == tb.points()
    assert tb.lookup(2.0) == (1.0, 0.0, 0.5)
    c = tmp_path / "bad.txt"
    c.write_text("1 2 3\n")
    with pytest.raises(ValueError, match="4 columns"):
        load_poses(c)
    c.write_text("1 2 3 4\n1 2 3 4 5\n")
    with pytest.raises(ValueError, match="expected 4 columns"):
        load_poses(c)


def test_relations_from_poses():
    pts = _random_path(n=10, dt=1.0)
    tr = Trajectory(pts)
    consecutive = relations_from_poses(tr)
    assert [(r.t1, r.t2) for r in consecutive] == [(pts[i][0], pts[i + 1][0]) for i in range(9)]
    within = relations_from_poses(tr, max_span=3.0)
    # spans 1, 2, 3: 9 + 8 + 7 pairs
    assert len(within) == 24
    assert evaluate(tr, within)["translation"]["max"] == pytest.approx(0.0, abs=1e-9)


# --------------------------------------------------------------------------- CLI


def _write_traj(path, pts):
    with open(path, "w") as fh:
        ev.write_trajectory(pts, fh, header="test trajectory")


def test_cli_json_and_exit_codes(tmp_path, capsys):
    pts = _random_path(n=20)
    traj = tmp_path / "t.txt"
    _write_traj(traj, pts)
    gt = tmp_path / "gt.txt"
    _write_traj(gt, pts)
    rc = ev.main([str(traj), "--ground-truth", str(gt), "--max-span", "0.5", "--json",
                  "--label", "self"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["label"] == "self"
    assert out["matched"] == 19 + 18  # spans 0.2 and 0.4 s
    assert out["translation"]["max"] < 1e-5  # written with 6 decimals

    # no relation matches: non-zero exit, but still a report
    rels = tmp_path / "r.relations"
    rels.write_text("5.0 6.0 1 0 0 0 0 0\n")
    rc = ev.main([str(traj), "--relations", str(rels)])
    captured = capsys.readouterr()
    assert rc != 0
    assert "0 matched, 1 unmatched" in captured.out
    assert "no relation matched" in captured.err

    rc = ev.main([str(traj), "--relations", str(tmp_path / "missing")])
    assert rc == 1


def test_cli_odometry_writes_trajectory(tmp_path):
    log = tmp_path / "x.log"
    log.write_text(
        "ODOM 0 0 0 0 0 0 1.0 h 0\n"
        "FLASER 2 1.00 2.00 9 9 9 0.100000 0.200000 0.300000 1.500000 h 0.5\n"
        "FLASER 2 1.00 2.00 9 9 9 0.400000 0.500000 0.600000 2.000000 h 1.0\n"
        "FLASER 2 1.00 bad 9 9 9 0.400000 0.500000 0.600000 2.500000 h 1.5\n"
    )
    out = tmp_path / "odom.txt"
    proc = subprocess.run(
        [sys.executable, "-m", "rsm_tools.evaluate", "--odometry", str(log),
         "--write-trajectory", str(out)],
        capture_output=True, text=True, env=subprocess_env(),
    )
    assert proc.returncode == 0, proc.stderr
    assert "non_numeric=1" in proc.stderr
    rows = [l for l in out.read_text().splitlines() if not l.startswith("#")]
    assert rows == ["1.500000 0.100000 0.200000 0.300000", "2.000000 0.400000 0.500000 0.600000"]


# --------------------------------------------------------------------------- real data


def _fmt(label, res):
    t, r = res["translation"], res["rotation"]
    return (f"{label:>10}: n={t['count']:4d}  trans mean {t['mean']:.4f} m std {t['std']:.4f} "
            f"max {t['max']:.3f}  rot mean {r['mean']:.3f} deg std {r['std']:.3f} "
            f"max {r['max']:.2f}")


def test_raw_odometry_error_on_the_excerpt_relations(head_log, head_relations):
    """The figures tests/data/README.md gives; the full log's (intel-SOURCE.md)
    are checked by ./tools/bench."""
    traj = Trajectory(odometry_trajectory(head_log))
    rels = load_relations(head_relations)
    assert len(traj) == 600 and len(rels) == 47
    all_res = evaluate(traj, rels)
    local2 = evaluate(traj, rels, max_span=2.0)
    print()
    for label, res in (("all", all_res), ("<= 2 s", local2)):
        print(_fmt(label, res))
    # every relation end is a FLASER timestamp: all match exactly
    assert all_res["matched"] == 47 and all_res["unmatched"] == 0 and all_res["inexact"] == 0
    assert all_res["translation"]["mean"] == pytest.approx(0.018, abs=0.0005)
    assert all_res["translation"]["max"] == pytest.approx(0.142, abs=0.0005)
    assert all_res["rotation"]["mean"] == pytest.approx(1.46, abs=0.005)
    assert local2["matched"] == 42
    assert local2["translation"]["mean"] == pytest.approx(0.012, abs=0.0005)
    assert local2["rotation"]["mean"] == pytest.approx(1.31, abs=0.005)


def test_corrected_poses_of_the_excerpt_sit_on_its_scans(head_log, head_poses, head_relations):
    """Each corrected pose is keyed to a scan's stamp (intel-SOURCE.md); none of
    the excerpt's 47 relations has both ends among its 28 poses, so matching
    them must find none (the full log's 90 are checked by ./tools/bench)."""
    gt, fmt = load_poses(head_poses)
    assert fmt == "corrected-poses" and len(gt) == 28
    scans = Trajectory(odometry_trajectory(head_log))
    assert all(scans.lookup(p.t, tolerance=0.0) is not None for p in gt.points())
    rels = load_relations(head_relations)
    times = {time_key(p.t) for p in gt.points()}
    covered = [r for r in rels if time_key(r.t1) in times and time_key(r.t2) in times]
    res = evaluate(gt, rels, tolerance=0.0)
    assert res["matched"] == len(covered) == 0 and res["unmatched"] == 47
