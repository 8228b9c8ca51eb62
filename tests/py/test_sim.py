"""rsm-sim: deterministic captures whose bytes agree with the ground truth."""

import math
import subprocess
import sys

import pytest

from conftest import subprocess_env
from rsm_tools import capture as cap
from rsm_tools import convert as cv
from rsm_tools import evaluate as ev
from rsm_tools import protocols as p
from rsm_tools import sim


def load_truth(path):
    return [tuple(p) for p in ev.read_poses(path)[0]]


def odometry(h, recs):
    pose = tuple(float(v) for v in h.metadata["robot.initial_pose"].split())
    prev = None
    out = {}
    for r in recs:
        if r.channel != 0:
            continue
        l, rr = p.decode_encoder(r.data)
        if prev is not None:
            pose = cv.integrate(pose, p.tick_delta(l, prev[0]), p.tick_delta(rr, prev[1]),
                                sim.TICKS_PER_M, sim.WHEEL_BASE)
        prev = (l, rr)
        out[r.timestamp] = pose
    return out


def test_clean_sim_odometry_and_scans_match_truth(tmp_path):
    out, truth = tmp_path / "s.cap", tmp_path / "t.txt"
    n = sim.simulate(out, truth, "rooms", seconds=12)
    assert n == 61
    h, recs, _ = cap.read_capture(out)
    rows = load_truth(truth)
    assert len(rows) == n
    odo = odometry(h, recs)
    for t, x, y, th in rows:
        ox, oy, oth = odo[int(round(t * 1e6))]
        assert math.hypot(ox - x, oy - y) < 0.002 and abs(cv.wrap(oth - th)) < 0.001
    segs, circles, _ = sim.world("rooms")
    scans = [p.decode_b0(r.data) for r in recs if r.channel == 1]
    assert all(s.count == 181 and s.units == "mm" for s in scans)
    for (t, x, y, th), s in zip(rows[::10], scans[::10]):
        for j, got in enumerate(s.ranges()):
            true = sim.raycast(x, y, th + math.radians(j - 90), segs, circles)
            if true <= 8.0:
                assert abs(got - true) <= 0.0005 + 1e-9
            else:
                assert got is None


def test_noise_is_seeded_and_present(tmp_path):
    def run(seed, name):
        (tmp_path / name).mkdir()
        out = tmp_path / name / "s.cap"
        sim.simulate(out, tmp_path / name / "t.txt", "pillars", seconds=4, slip=0.05,
                     range_noise=0.02, outliers=0.1, seed=seed)
        return out.read_bytes()
    a, b, c = run(7, "a"), run(7, "b"), run(8, "c")
    assert a == b and a != c
    clean = tmp_path / "clean.cap"
    sim.simulate(clean, tmp_path / "clean.txt", "pillars", seconds=4)
    _, noisy, _ = cap.read_capture(tmp_path / "a" / "s.cap")
    _, ok, _ = cap.read_capture(clean)
    sn = [p.decode_b0(r.data).ranges() for r in noisy if r.channel == 1]
    sc = [p.decode_b0(r.data).ranges() for r in ok if r.channel == 1]
    diffs = [a - b for u, v in zip(sn, sc) for a, b in zip(u, v) if a is not None and b is not None]
    short = sum(1 for d in diffs if d < -0.1)
    assert 0.05 < short / len(diffs) < 0.15        # outliers
    assert 0.01 < sum(abs(d) for d in diffs) / len(diffs) < 0.2


def test_command_line_worlds(tmp_path):
    for w in ("corridor", "pillars", "rooms", "hall", "building"):
        res = subprocess.run([sys.executable, "-m", "rsm_tools.sim", str(tmp_path / f"{w}.cap"),
                              "--truth", str(tmp_path / f"{w}.txt"), "--world", w, "--seconds", "2"],
                             capture_output=True, text=True, env=subprocess_env())
        assert res.returncode == 0, res.stderr
        assert "11 scans" in res.stderr
        h, recs, _ = cap.read_capture(tmp_path / f"{w}.cap")
        assert h.metadata["ground_truth"] == f"{w}.txt"
        assert sum(r.channel == 0 for r in recs) == 21


def test_building_world_has_doors_only_in_its_outer_walls():
    """The building: a ring of 2 m corridors; door recesses 0.3 m deep open
    into the outer walls (the wall is cut there), the block's walls are bare;
    the hall is a bare 40 m corridor with its ends 39 m apart seen from the start."""
    segs, circles, path = sim.world("building")
    assert circles == [] and path[0] == (1, 1)
    down, up = -math.pi / 2, math.pi / 2
    assert sim.raycast(4.75, 1.0, down, segs, circles) == pytest.approx(1.3)   # in front of a door
    assert sim.raycast(3.0, 1.0, down, segs, circles) == pytest.approx(1.0)    # a bare stretch
    assert sim.raycast(4.75, 1.0, up, segs, circles) == pytest.approx(1.0)     # the block: no doors
    assert sim.raycast(39.0, 4.85, 0.0, segs, circles) == pytest.approx(1.3)   # a door in the east wall
    segs, circles, path = sim.world("hall")
    assert sim.raycast(1.0, 1.0, 0.0, segs, circles) == pytest.approx(39.0)
    assert sim.raycast(20.0, 1.0, down, segs, circles) == pytest.approx(1.0)


def test_carmen_log_with_a_mounted_laser(tmp_path):
    """--carmen: the same drive as the capture; ROBOTLASER1 lines carry the odometry
    pose and the laser pose composed from it, and the ranges are ray-cast from the
    laser, mirrored when it is upside down."""
    from rsm_tools import carmen as cm

    mount = (0.22, 0.05, 0.1)
    segs, circles, _ = sim.world("rooms")
    sim.simulate(tmp_path / "c.cap", tmp_path / "c.txt", "rooms", seconds=8)
    plain = load_truth(tmp_path / "c.txt")
    for upside in (False, True):
        log, truth = tmp_path / f"m{upside}.clf", tmp_path / f"m{upside}.txt"
        n = sim.simulate(log, truth, "rooms", seconds=8, carmen=True, laser_pose=mount, upside_down=upside)
        rows = load_truth(truth)
        assert n == 41 and rows == plain
        st = cm.LogStats()
        recs = list(cm.read_log(log, stats=st))
        assert st.malformed_total == 0 and dict(st.records) == {"ODOM": 81, "ROBOTLASER1": 41}
        scans = [r for r in recs if r.kind == "ROBOTLASER1"]
        for (t, x, y, th), r in zip(rows, scans):
            assert r.timestamp == pytest.approx(t, abs=1e-6)
            assert r.mount == pytest.approx(mount, abs=2e-5)
            rx, ry, rth = r.robot_pose   # odometry, exact here but for tick quantisation
            assert math.hypot(rx - x, ry - y) < 0.002 and abs(cv.wrap(rth - th)) < 0.001
            assert r.num_readings == 181 and r.start_angle == pytest.approx(-math.pi / 2, abs=1e-6)
        for (t, x, y, th), r in zip(rows[::10], scans[::10]):
            lx = x + math.cos(th) * mount[0] - math.sin(th) * mount[1]
            ly = y + math.sin(th) * mount[0] + math.cos(th) * mount[1]
            for j, got in enumerate(r.ranges):
                a = math.radians(j - 90) * (-1 if upside else 1)
                true = sim.raycast(lx, ly, th + mount[2] + a, segs, circles)
                if true <= sim.MAX_RANGE:
                    assert got == pytest.approx(true, abs=0.0005 + 1e-9)
                else:
                    assert got == sim.CARMEN_NO_RETURN


def test_mount_recorded_in_a_capture_only_when_off_centre(tmp_path):
    sim.simulate(tmp_path / "a.cap", tmp_path / "a.txt", "pillars", seconds=2)
    sim.simulate(tmp_path / "b.cap", tmp_path / "b.txt", "pillars", seconds=2,
                 laser_pose=(0.22, 0.0, 0.0), upside_down=True)
    ha, ra, _ = cap.read_capture(tmp_path / "a.cap")
    hb, rb, _ = cap.read_capture(tmp_path / "b.cap")
    assert "sim.laser_pose" not in ha.metadata
    assert hb.metadata["sim.laser_upside_down"] == "1"
    assert [float(v) for v in hb.metadata["sim.laser_pose"].split()] == [0.22, 0.0, 0.0]
    # the robot's bytes are the same, the laser's are not
    assert [r.data for r in ra if r.channel == 0] == [r.data for r in rb if r.channel == 0]
    assert [r.data for r in ra if r.channel == 1] != [r.data for r in rb if r.channel == 1]


def test_command_line_carmen_and_bad_laser_pose(tmp_path):
    base = [sys.executable, "-m", "rsm_tools.sim", str(tmp_path / "s.clf.gz"), "--truth", str(tmp_path / "t.txt"),
            "--seconds", "2", "--carmen"]
    res = subprocess.run(base + ["--laser-pose", "0.22", "0", "0", "--upside-down"],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 0, res.stderr
    assert "11 scans" in res.stderr and "(CARMEN)" in res.stderr
    from rsm_tools import carmen as cm
    scans = [r for r in cm.read_log(tmp_path / "s.clf.gz") if r.kind == "ROBOTLASER1"]
    assert len(scans) == 11 and scans[0].mount == pytest.approx((0.22, 0.0, 0.0), abs=2e-6)
    for bad in (["nan", "0", "0"], ["9", "0", "0"], ["0.2", "x", "0"]):
        res = subprocess.run(base + ["--laser-pose", *bad], capture_output=True, text=True, env=subprocess_env())
        assert res.returncode == 2 and "--laser-pose" in res.stderr, res.stderr
