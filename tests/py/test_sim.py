"""rsm-sim: deterministic captures whose bytes agree with the ground truth."""

import math
import subprocess
import sys

from conftest import subprocess_env
from rsm_tools import capture as cap
from rsm_tools import convert as cv
from rsm_tools import protocols as p
from rsm_tools import sim


def load_truth(path):
    return [tuple(map(float, l.split())) for l in path.read_text().splitlines() if not l.startswith("#")]


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
    for w in ("corridor", "pillars", "rooms"):
        res = subprocess.run([sys.executable, "-m", "rsm_tools.sim", str(tmp_path / f"{w}.cap"),
                              "--truth", str(tmp_path / f"{w}.txt"), "--world", w, "--seconds", "2"],
                             capture_output=True, text=True, env=subprocess_env())
        assert res.returncode == 0, res.stderr
        assert "11 scans" in res.stderr
        h, recs, _ = cap.read_capture(tmp_path / f"{w}.cap")
        assert h.metadata["ground_truth"] == f"{w}.txt"
        assert sum(r.channel == 0 for r in recs) == 21
