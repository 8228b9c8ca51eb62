"""Tests of rsm-faults (rsm_tools.faults) on the shipped excerpt of the Intel
log (tests/data/intel_head.clf.gz, 600 scans; the robot starts moving at scan
143) and on small logs made here. Every expectation is computed here from the
input log, independently of the tool's own code paths where it can be."""

import gzip
import math
import subprocess
import sys

import pytest

from conftest import REPO_ROOT, subprocess_env
from rsm_tools import faults
from rsm_tools.carmen import FLaser, LogStats, Odom, RobotLaser1, pose_compose, pose_in_frame, read_log

MOVING = 143  # first scan of the excerpt whose odometry differs from the first pose


def records(path):
    st = LogStats()
    recs = list(read_log(str(path), stats=st))
    assert st.malformed_total == 0, st.summary()
    return recs


def scans(path):
    return [r for r in records(path) if isinstance(r, (FLaser, RobotLaser1))]


def run(tmp_path, head_log, *args, name="out.clf"):
    out = tmp_path / name
    rc = faults.main([str(head_log), str(out), *map(str, args)])
    assert rc == 0
    return out


def close(a, b, tol=2e-6):
    return all(abs(x - y) <= tol for x, y in zip(a[:2], b[:2])) and abs(math.remainder(a[2] - b[2], 2 * math.pi)) <= tol


def step(a, b):
    return pose_in_frame(a, b)


@pytest.fixture(scope="module")
def original(head_log):
    return scans(head_log)


@pytest.fixture(scope="module")
def original_lines(head_log):
    with gzip.open(head_log, "rb") as fh:
        return fh.readlines()


def scan_lines(path):
    opener = gzip.open if str(path).endswith(".gz") else open
    with opener(path, "rb") as fh:
        return [l for l in fh if l.split(None, 1)[:1] in ([b"FLASER"], [b"ROBOTLASER1"])]


def test_the_excerpt_moves_where_the_tests_assume(original):
    assert len(original) == 600
    assert original[MOVING].odom_pose != original[0].odom_pose
    assert all(r.odom_pose == original[0].odom_pose for r in original[:MOVING])
    assert all(r.laser_pose == r.odom_pose for r in original)  # no mount in the Intel log


def test_stall_freezes_the_odometry_then_catches_up(tmp_path, head_log, original, original_lines, capsys):
    s, n = 300, 5
    out = run(tmp_path, head_log, "--stall", f"{n}@{s}")
    got = scans(out)
    assert len(got) == len(original)
    for i in range(s, s + n):
        assert got[i].odom_pose == original[s - 1].odom_pose
        assert got[i].laser_pose == got[i].odom_pose  # still no mount for rsm-nav
        assert got[i].ranges == original[i].ranges and got[i].timestamp == original[i].timestamp
    assert got[s + n].odom_pose == original[s + n].odom_pose
    # the frozen span moved: the stall is a real fault here
    assert original[s + n - 1].odom_pose != original[s - 1].odom_pose
    # every other scan line is the input's, byte for byte
    a, b = scan_lines(out), [l for l in original_lines if l.startswith((b"FLASER", b"ROBOTLASER1"))]
    assert [k for k in range(len(a)) if a[k] != b[k]] == list(range(s, s + n))
    # ODOM lines between scan s-1 and scan s+n report the frozen pose, standing still
    recs = records(out)
    idx = [k for k, r in enumerate(recs) if isinstance(r, FLaser)]
    odoms = [r for r in recs[idx[s - 1] + 1:idx[s + n]] if isinstance(r, Odom)]
    assert odoms and all(o.pose == original[s - 1].odom_pose and o.tv == 0 and o.rv == 0 for o in odoms)
    assert "stall: odometry frozen on scans 300..304" in capsys.readouterr().err


def test_stalls_at_the_strongest_turns(tmp_path, head_log, original, capsys):
    k, n, spacing = 3, 10, 40
    out = run(tmp_path, head_log, "--stall-at-turns", k, "--stall-len", n, "--stall-spacing", spacing)
    got = scans(out)
    th = [r.odom_pose[2] for r in original]
    turn = {s: abs(math.remainder(th[s + n] - th[s - 1], 2 * math.pi)) for s in range(1, len(th) - n)}
    err = capsys.readouterr().err
    line = next(l for l in err.splitlines() if "stall at turns" in l)
    placed = [int(v) for v in line.split("at scans ")[1].split(" (")[0].split(", ")]
    assert len(placed) == k and placed == sorted(placed)
    assert all(b - a >= n + spacing for a, b in zip(placed, placed[1:]))
    # the strongest turn of the whole log is among them, and none is weaker than
    # any window far enough from every chosen one
    assert max(turn.values()) in [turn[s] for s in placed]
    weakest = min(turn[s] for s in placed)
    free = [s for s in turn if all(abs(s - p) >= n + spacing for p in placed)]
    assert all(turn[s] <= weakest for s in free)
    for s in placed:
        assert all(got[i].odom_pose == original[s - 1].odom_pose for i in range(s, s + n))
        assert got[s + n].odom_pose == original[s + n].odom_pose


def test_stall_jitter_moves_the_stalls_by_the_seed(tmp_path, head_log, capsys):
    args = ("--stall-at-turns", 2, "--stall-len", 10, "--stall-jitter", 5)
    a = run(tmp_path, head_log, *args, "--seed", 1, name="a.clf").read_bytes()
    b = run(tmp_path, head_log, *args, "--seed", 1, name="b.clf").read_bytes()
    assert a == b
    places = set()
    for seed in range(6):
        run(tmp_path, head_log, *args, "--seed", seed, name="c.clf")
        err = capsys.readouterr().err
        places.add(next(l for l in err.splitlines() if "stall at turns" in l).split("at scans ")[1].split(" (")[0])
    assert len(places) > 1


def test_spike_changes_exactly_one_scan(tmp_path, head_log, original, original_lines):
    s, d = 400, (0.5, -0.25, 0.3)
    out = run(tmp_path, head_log, "--spike", f"{s}:{d[0]},{d[1]},{d[2]}")
    a = scan_lines(out)
    b = [l for l in original_lines if l.startswith(b"FLASER")]
    assert [k for k in range(len(a)) if a[k] != b[k]] == [s]
    got = scans(out)
    assert close(got[s].odom_pose, pose_compose(original[s].odom_pose, d))
    assert got[s].laser_pose == got[s].odom_pose
    # the spike in degrees says the same
    out2 = run(tmp_path, head_log, "--spike", f"{s}:{d[0]},{d[1]},{math.degrees(d[2])}deg", name="deg.clf")
    assert close(scans(out2)[s].odom_pose, got[s].odom_pose)


def test_reset_zeroes_the_odometry_and_keeps_every_later_step(tmp_path, head_log, original):
    s = 350
    out = run(tmp_path, head_log, "--reset", s)
    got = scans(out)
    assert got[s].odom_pose == (0.0, 0.0, 0.0)
    assert all(got[i].odom_pose == original[i].odom_pose for i in range(s))
    for i in range(s + 1, len(got)):
        assert close(step(got[i - 1].odom_pose, got[i].odom_pose), step(original[i - 1].odom_pose,
                                                                           original[i].odom_pose), 4e-6)
    # ODOM lines after scan s are in the new frame: their pose relative to scan s kept
    orig_recs, recs = records(head_log), records(out)
    assert len(orig_recs) == len(recs)
    seen, checked = 0, 0
    for a, b in zip(orig_recs, recs):
        if isinstance(a, FLaser):
            seen += 1
        elif seen > s:
            assert close(b.pose, pose_in_frame(original[s].odom_pose, a.pose), 4e-6)
            checked += 1
        else:
            assert b.pose == a.pose
    assert checked > 100


def test_scale_multiplies_translations_and_keeps_headings(tmp_path, head_log, original):
    f = 1.03
    out = run(tmp_path, head_log, "--scale", f)
    got = scans(out)
    moved = 0
    for i in range(1, len(got)):
        a = step(original[i - 1].odom_pose, original[i].odom_pose)
        b = step(got[i - 1].odom_pose, got[i].odom_pose)
        assert abs(b[0] - f * a[0]) <= 4e-6 and abs(b[1] - f * a[1]) <= 4e-6
        assert got[i].odom_pose[2] == original[i].odom_pose[2]
        moved += math.hypot(a[0], a[1]) > 0.01
    assert moved > 100
    odoms = [(a, b) for a, b in zip(records(head_log), records(out)) if isinstance(a, Odom)]
    assert all(abs(b.tv - f * a.tv) <= 1e-6 for a, b in odoms)


def test_slip_stands_still_while_the_odometry_runs_on(tmp_path, head_log, original):
    s, n = 420, 6
    out = run(tmp_path, head_log, "--slip", f"{s}:{n}")
    got = scans(out)
    assert len(got) == len(original) + n - 1
    copies = got[s + 1:s + n]
    for k, c in enumerate(copies, start=1):
        assert c.ranges == original[s].ranges  # the robot stands at scan s's place
        assert c.odom_pose == original[s + k].odom_pose  # wheels turning: the log's steps
        assert original[s].timestamp < c.timestamp < original[s + 1].timestamp
    assert [c.timestamp for c in copies] == sorted({c.timestamp for c in copies})
    # then the robot moves on from scan s's place: the log's steps from s, shifted
    rest = got[s + n:]
    assert [r.timestamp for r in rest] == [r.timestamp for r in original[s + 1:]]
    assert all(r.ranges == o.ranges for r, o in zip(rest, original[s + 1:]))
    prev = got[s + n - 1]
    for r, o, oprev in zip(rest, original[s + 1:], original[s:]):
        assert close(step(prev.odom_pose, r.odom_pose), step(oprev.odom_pose, o.odom_pose), 4e-6)
        prev = r
    assert math.dist(original[s].odom_pose[:2], original[s + n - 1].odom_pose[:2]) > 0.05  # it slipped


def test_every_m_keeps_a_scan_only_after_enough_motion(tmp_path, head_log, original):
    d, r = 0.2, 0.3
    out = run(tmp_path, head_log, "--every-m", d, "--every-rad", r)
    got = scans(out)
    want, ref = [], None
    for o in original:
        p = o.odom_pose
        if ref is None or math.dist(p[:2], ref[:2]) >= d or abs(math.remainder(p[2] - ref[2], 2 * math.pi)) >= r:
            want.append(o.timestamp)
            ref = p
    assert [g.timestamp for g in got] == want
    assert 10 < len(got) < len(original) // 2
    for a, b in zip(got, got[1:]):
        moved = math.dist(a.odom_pose[:2], b.odom_pose[:2])
        turned = abs(math.remainder(b.odom_pose[2] - a.odom_pose[2], 2 * math.pi))
        assert moved >= d or turned >= r
    assert sum(isinstance(x, Odom) for x in records(out)) == sum(isinstance(x, Odom) for x in records(head_log))


def test_drop_removes_that_share_of_scans_by_the_seed(tmp_path, head_log, original):
    a = scans(run(tmp_path, head_log, "--drop", 25, "--seed", 3, name="a.clf"))
    b = scans(run(tmp_path, head_log, "--drop", 25, "--seed", 4, name="b.clf"))
    assert len(a) == len(b) == 600 - 150
    ta, tb = [x.timestamp for x in a], [x.timestamp for x in b]
    assert ta != tb
    kept = {o.timestamp: o for o in original}
    assert all(x.odom_pose == kept[x.timestamp].odom_pose and x.ranges == kept[x.timestamp].ranges for x in a)


def test_gap_removes_the_scans_of_that_time_span(tmp_path, head_log, original):
    t0 = original[0].timestamp
    out = run(tmp_path, head_log, "--gap", "40:15")
    got = {g.timestamp for g in scans(out)}
    gone = [o for o in original if o.timestamp not in got]
    assert gone and all(t0 + 40 - 1e-6 <= o.timestamp < t0 + 55 + 1e-6 for o in gone)
    assert all(o.timestamp in got for o in original if not (t0 + 40 <= o.timestamp < t0 + 55))


def kidnap_ends(original, s, t):
    """(a, b, cut): the first scan stamped after the cut (b), the last one
    before it stamped before the cut (a), and the scans stamped within it
    (the Intel excerpt's stamps are not all in file order: some come after b)."""
    t0 = original[0].timestamp
    b = next(i for i, o in enumerate(original) if o.timestamp >= t0 + s + t)
    a = max(i for i in range(b) if original[i].timestamp < t0 + s)
    cut = [i for i, o in enumerate(original) if t0 + s <= o.timestamp < t0 + s + t]
    return a, b, cut


def test_kidnap_removes_the_span_and_hides_the_motion_across_it(tmp_path, head_log, original, capsys):
    s, t = 40, 15
    a, b, cut = kidnap_ends(original, s, t)
    assert set(range(a + 1, b)) <= set(cut) and len(cut) > 50
    out = run(tmp_path, head_log, "--kidnap", f"{s}:{t}")
    got = scans(out)
    src = [i for i in range(len(original)) if i not in cut]
    assert [g.timestamp for g in got] == [original[i].timestamp for i in src]
    # the robot really moved across the cut: the fault hides something
    assert math.dist(original[a].odom_pose[:2], original[b].odom_pose[:2]) > 0.05 or \
        abs(math.remainder(original[b].odom_pose[2] - original[a].odom_pose[2], 2 * math.pi)) > 0.1
    k = src.index(b)
    assert src[k - 1] == a
    assert all(got[j].odom_pose == original[i].odom_pose and got[j].ranges == original[i].ranges
               for j, i in enumerate(src[:k]))
    # no motion across the cut, to the character
    assert got[k].odom_pose == original[a].odom_pose and got[k].ranges == original[b].ranges
    assert got[k].laser_pose == got[k].odom_pose  # still no mount for rsm-nav
    # every later step is the log's own
    for j in range(k + 1, len(got)):
        assert close(step(got[j - 1].odom_pose, got[j].odom_pose),
                     step(original[src[j - 1]].odom_pose, original[src[j]].odom_pose), 4e-6)
    # the ODOM lines between scans a and b are gone; the later ones moved with the scans
    want, seen = [], 0
    for r in records(head_log):
        if isinstance(r, FLaser):
            seen += 1
        elif seen <= a:
            want.append(r.pose)
        elif seen > b:
            want.append(pose_compose(original[a].odom_pose, pose_in_frame(original[b].odom_pose, r.pose)))
    odoms = [r.pose for r in records(out) if isinstance(r, Odom)]
    assert len(odoms) == len(want) and all(close(g, w, 4e-6) for g, w in zip(odoms, want))
    err = capsys.readouterr().err
    assert f"kidnap: {len(cut)} scans removed with stamps 40 s to 55 s" in err
    assert f"between scans {a} and {b}" in err and f"stamped {original[b].timestamp:.6f}" in err


def test_kidnap_result_names_the_first_scan_after_each_cut(head_log, original):
    log = faults.load_log(head_log)
    spec = faults.FaultSpec(kidnaps=[(70.0, 10.0), (30.0, 5.0)], drop=20, seed=3)
    res = faults.apply_faults(log, spec)
    dropped = faults.apply_faults(log, faults.FaultSpec(drop=20, seed=3))  # the same draw without the kidnaps
    assert [(c.offset, c.length) for c in res.kidnaps] == [(30.0, 5.0), (70.0, 10.0)]  # in time order
    for c in res.kidnaps:
        a, b, cut = kidnap_ends(original, c.offset, c.length)
        assert (c.before, c.after) == (a, b)
        assert res.scan_pose(b) == res.scan_pose(a)
        # the first scan written after the cut, the drop's choice included
        first = next(o for o in res.kept_scans if o.src >= b)
        assert c.stamp == original[first.src].timestamp
        assert not any(o.src in cut for o in res.kept_scans)
        assert c.removed == sum(1 for o in dropped.kept_scans if o.src in cut) > 0
    assert "--drop 20 --kidnap 70:10 --kidnap 30:5 --seed 3" in faults.describe(spec)  # as given


def test_kidnap_at_a_slip_is_refused(tmp_path, head_log, original):
    a, b, _ = kidnap_ends(original, 40, 15)
    for s in (a, b):
        res = subprocess.run([sys.executable, "-m", "rsm_tools.faults", str(head_log), str(tmp_path / "o.clf"),
                              "--kidnap", "40:15", "--slip", f"{s}:3"], capture_output=True, text=True,
                             env=subprocess_env())
        assert res.returncode == 2 and f"--slip {s}:3: the slip's scan {s} is at the cut" in res.stderr
    assert run(tmp_path, head_log, "--kidnap", "40:15", "--slip", f"{b + 5}:3")


def test_mount_moves_the_robot_and_keeps_the_laser(tmp_path, head_log, original):
    m = (0.22, 0.03, 0.1)
    out = run(tmp_path, head_log, "--mount", ",".join(map(str, m)))
    got = scans(out)
    for g, o in zip(got, original):
        assert close(g.laser_pose, o.laser_pose, 2e-6)
        assert close(g.mount, m, 4e-6)  # what rsm-nav reads from the two triples
        assert g.ranges == o.ranges
    # odometry steps are now those of a point 0.22 m behind the laser: turning in place moves it
    moved = [math.dist(got[i].odom_pose[:2], got[i - 1].odom_pose[:2]) for i in range(1, len(got))]
    orig = [math.dist(original[i].odom_pose[:2], original[i - 1].odom_pose[:2]) for i in range(1, len(got))]
    assert moved != pytest.approx(orig, abs=1e-3)


def test_start_offsets_shift_the_first_beam_in_turn(tmp_path, head_log, original):
    out = run(tmp_path, head_log, "--start-offsets", "0,1,0.5")
    got = scans(out)
    assert len(got) == len(original)
    step_ = math.pi / 180
    for i, (g, o) in enumerate(zip(got, original)):
        off = (0.0, 1.0, 0.5)[i % 3]
        if off == 0.0:
            assert isinstance(g, FLaser) and g.ranges == o.ranges
            continue
        assert isinstance(g, RobotLaser1)
        assert g.start_angle == pytest.approx(-math.pi / 2 + math.radians(off), abs=1e-8)
        assert g.angular_res == pytest.approx(step_, abs=1e-8)
        assert g.robot_pose == o.odom_pose and g.laser_pose == o.laser_pose and g.timestamp == o.timestamp
        if off == 1.0:  # a whole beam: the readings from the second on
            assert g.ranges == o.ranges[1:]
            continue
        assert len(g.ranges) == len(o.ranges) - 1
        for j, r in enumerate(g.ranges):
            a, b = o.ranges[j], o.ranges[j + 1]
            if r >= g.max_range:  # no surface between the two: a no-return
                continue
            # a ray halfway between two returns hits the segment joining them: within their ranges
            assert min(a, b) - 0.006 <= r <= max(a, b) + 0.006
            if a == b:  # a flat surface square to the middle ray
                assert abs(r - a * math.cos(step_ / 2)) <= 0.006


def test_combined_faults_write_a_log_every_reader_parses(tmp_path, head_log):
    out = run(tmp_path, head_log, "--stall", "5@200", "--spike", "250:0.3,0,0.1", "--reset", "300",
              "--slip", "320:4", "--scale", "0.97", "--drop", "10", "--gap", "60:5", "--mount", "0.2,0,0",
              "--start-offsets", "0,0.25,0.5,0.75", "--seed", "9", name="all.clf.gz")
    recs = records(out)
    assert sum(isinstance(r, RobotLaser1) for r in recs) > 100
    with gzip.open(out, "rb") as fh:
        first = fh.readline()
    assert first.startswith(b"# rsm-faults --mount 0.2,0,0 --reset 300 --scale 0.97 --stall 5@200")


def test_same_arguments_give_the_same_bytes(tmp_path, head_log):
    args = ("--drop", 20, "--stall-at-turns", 2, "--stall-len", 8, "--stall-jitter", 3, "--slip", "400:3",
            "--start-offsets", "0,0.5", "--seed", 5)
    a = run(tmp_path, head_log, *args, name="a.clf.gz").read_bytes()
    b = run(tmp_path, head_log, *args, name="b.clf.gz").read_bytes()
    assert a == b
    assert a[4:8] == b"\0\0\0\0"  # gzip mtime 0
    c = run(tmp_path, head_log, *args[:-1], 6, name="c.clf.gz").read_bytes()
    assert c != a


@pytest.mark.parametrize("args", [
    [], ["--stall", "5"], ["--stall", "0@3"], ["--stall", "x@3"], ["--spike", "3:1,2"], ["--spike", "3:1,2,z"],
    ["--reset", "-1"], ["--slip", "3:1"], ["--scale", "-1"], ["--scale", "nan"], ["--drop", "120"],
    ["--gap", "5:0"], ["--gap", "5"], ["--kidnap", "5:0"], ["--kidnap", "-1:5"], ["--kidnap", "5"],
    ["--kidnap", "x:5"], ["--mount", "1,2"], ["--start-offsets", "-1"], ["--start-offsets", "50"],
    ["--every-m", "0"], ["--stall-at-turns", "3"], ["--stall-len", "3"], ["--seed", "x", "--scale", "1.1"],
])
def test_bad_arguments_exit_2(tmp_path, head_log, args, capsys):
    with pytest.raises(SystemExit) as e:
        faults.main([str(head_log), str(tmp_path / "o.clf"), *args])
    assert e.value.code == 2
    assert "error" in capsys.readouterr().err
    assert not (tmp_path / "o.clf").exists()


@pytest.mark.parametrize("args,what", [
    (["--stall", "10@595"], "--stall 10@595"), (["--spike", "600:1,0,0"], "scan 600 is not in the log"),
    (["--reset", "1000"], "scan 1000"), (["--slip", "598:5"], "--slip 598:5"),
    (["--stall-at-turns", "20", "--stall-len", "10", "--stall-spacing", "100"], "only"),
    (["--kidnap", "0:10"], "--kidnap 0:10: needs a scan before 0 s"), (["--kidnap", "100:30"], "spans 117.495 s"),
    (["--kidnap", "40:15", "--kidnap", "50:20"], "--kidnap 50:20: begins before scan"),
])
def test_faults_that_do_not_fit_the_log_exit_2_with_a_message(tmp_path, head_log, args, what):
    res = subprocess.run([sys.executable, "-m", "rsm_tools.faults", str(head_log), str(tmp_path / "o.clf"), *args],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 2, res.stderr
    assert "rsm-faults: error:" in res.stderr and what in res.stderr
    assert not (tmp_path / "o.clf").exists()


def test_unparsable_lines_are_copied_and_counted(tmp_path, capsys):
    src = tmp_path / "in.clf"
    lines = [b"# comment\n", b"PARAM x y\n"]
    for i in range(20):
        lines.append(f"ODOM {0.1 * i:.6f} 0.000000 0.000000 0.1 0 0 {100 + 0.2 * i:.6f} h 0\n".encode())
        rng = " ".join("2.00" for _ in range(10))
        p = f"{0.1 * i:.6f} 0.000000 0.000000"
        lines.append(f"FLASER 10 {rng} {p} {p} {100.1 + 0.2 * i:.6f} h 0\n".encode())
        if i == 5:
            lines.append(b"FLASER 10 1 2 3\n")
            lines.append(b"ODOM 1 2 nan 0 0 0 1 h 0\n")
    src.write_bytes(b"".join(lines))
    out = tmp_path / "out.clf"
    assert faults.main([str(src), str(out), "--scale", "2"]) == 0
    text = out.read_bytes()
    assert b"\nFLASER 10 1 2 3\n" in text and b"\nODOM 1 2 nan 0 0 0 1 h 0\n" in text and b"\nPARAM x y\n" in text
    err = capsys.readouterr().err
    assert "2 malformed scan or ODOM lines copied unchanged" in err and "20 scans in, 20 written" in err
    got = [r for r in read_log(str(out)) if isinstance(r, FLaser)]
    assert [round(g.odom_pose[0], 6) for g in got] == [round(0.2 * i, 6) for i in range(20)]


def test_console_script_is_declared():
    text = (REPO_ROOT / "tools" / "pyproject.toml").read_text(encoding="utf-8")
    assert 'rsm-faults = "rsm_tools.faults:main"' in text


def test_without_odom_lines_the_scan_lines_are_the_same(tmp_path, head_log):
    """The bench writes its faulty logs without ODOM lines (rsm-nav reads the
    odometry of the scan lines only): everything else is the full output's."""
    log = faults.load_log(head_log)
    res = faults.apply_faults(log, faults.FaultSpec(scale=1.05, stalls=[(5, 300)], slips=[(400, 3)]))
    full, short = tmp_path / "full.clf", tmp_path / "short.clf"
    with open(full, "wb") as fh:
        n1 = faults.write_result(res, fh)
    with open(short, "wb") as fh:
        n2 = faults.write_result(res, fh, odom_lines=False)
    assert n1 == n2 == 602
    keep = [l for l in full.read_bytes().splitlines(True) if not l.startswith(b"ODOM")]
    assert short.read_bytes() == b"".join(keep)
    assert any(l.startswith(b"ODOM") for l in full.read_bytes().splitlines())
