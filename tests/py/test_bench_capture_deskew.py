"""Two lines of the bench, run small: the capture path judged by the spread
of jittered direct runs (rsm_tools.fullchecks.check_capture_path, on the
shipped excerpt), and de-skew with encoder packets read in bursts
(rsm_tools.bench.deskew, on a short rsm-sim drive). Capture mode and
--carmen runs are functions of their input, so the verdicts below do not
depend on the machine; the floors themselves are a report (PASS/MISS), and
here only their arithmetic and what they are measured on are held."""

import math

from conftest import rsm_nav_binary
from rsm_tools import capture as cap
from rsm_tools import evaluate as ev
from rsm_tools import fullchecks as fc
from rsm_tools import sim
from rsm_tools.bench import deskew as dk
from rsm_tools.carmen import FLaser, Odom, read_log


def test_jittered_log_moves_only_the_odometry_within_half_a_micrometre(head_log, tmp_path):
    out = tmp_path / "j.clf"
    fc.jittered_log(head_log, out, seed=3)
    a, b = list(read_log(str(head_log))), list(read_log(str(out)))
    assert len(a) == len(b) and len(a) > 600
    moved = 0
    for r, s in zip(a, b):
        assert type(r) is type(s) and r.timestamp == s.timestamp
        if isinstance(r, FLaser):
            assert r.ranges == s.ranges
            poses = [(r.laser_pose, s.laser_pose), (r.odom_pose, s.odom_pose)]
            # the two poses move together: no mount appears
            assert math.isclose(s.laser_pose[0] - r.laser_pose[0], s.odom_pose[0] - r.odom_pose[0], abs_tol=2e-9)
        else:
            assert isinstance(r, Odom)
            poses = [((r.x, r.y, r.theta), (s.x, s.y, s.theta))]
        for p, q in poses:
            assert abs(q[0] - p[0]) <= fc.JITTER_M + 1e-9 and abs(q[1] - p[1]) <= fc.JITTER_M + 1e-9
            assert q[2] == p[2]
            moved += (q[0], q[1]) != (p[0], p[1])
    assert moved > len(a)  # nearly every pose moved
    again = tmp_path / "k.clf"
    fc.jittered_log(head_log, again, seed=3)
    assert again.read_bytes() == out.read_bytes()  # seeded


def test_capture_path_is_judged_by_the_spread_of_jittered_direct_runs(head_log, head_relations, tmp_path):
    nav = rsm_nav_binary()
    rels = ev.load_relations(head_relations)
    direct = tmp_path / "direct.txt"
    fc.run_nav(nav, ["--carmen", str(head_log)], direct)
    errs = ev.evaluate_scopes(ev.load_trajectory(direct), rels)
    lines = fc.check_capture_path("head", nav, head_log, rels, errs, tmp_path, direct, jitter_runs=3)
    assert [c["kind"] for c in lines] == ["capture"] * 3
    same, local, every = lines
    assert same["status"] == "PASS" and same["value"] >= same["limit"] >= 100  # the excerpt: 143 scans still
    assert local["limit"] == fc.CAPTURE_TOLERANCE
    assert local["status"] == ("PASS" if local["value"] <= fc.CAPTURE_TOLERANCE else "MISS")
    assert "the worst of 3 direct runs with +-0.5 um of odometry jitter" in every["line"]
    assert every["status"] == ("PASS" if every["value"] <= every["limit"] else "MISS")
    spread = [ev.evaluate_scopes(ev.load_trajectory(tmp_path / f"head-jitter{k}.txt"), rels)["all"]["translation"]["mean"]
              for k in (1, 2, 3)]
    assert every["limit"] == max(spread)
    # the jitter does what it is for: the direct runs part
    assert len({round(v, 9) for v in spread}) > 1
    assert not list(tmp_path.glob("*.clf"))  # the jittered copies are not kept
    none = fc.check_capture_path("head", nav, head_log, rels, errs, tmp_path, direct, jitter_runs=0)
    assert none[-1]["status"] == "SKIP"


def test_encoder_packets_in_bursts_keep_every_byte_and_the_time_order(tmp_path):
    clean, burst = tmp_path / "c.cap", tmp_path / "b.cap"
    sim.simulate(clean, tmp_path / "t.txt", "rooms", seconds=6.0, lidar="ld06", drive="curves")
    pairs = dk.in_bursts(clean, burst)
    h, a, _ = cap.read_capture(clean)
    _, b, _ = cap.read_capture(burst)
    robot = h.channel("robot").id
    enc_a = [r for r in a if r.channel == robot]
    enc_b = [r for r in b if r.channel == robot]
    assert pairs == len(enc_a) // 2 and pairs >= 25
    assert [r.data for r in enc_a] == [r.data for r in enc_b]
    assert [r.data for r in a if r.channel != robot] == [r.data for r in b if r.channel != robot]
    for k in range(pairs):
        assert enc_b[2 * k].timestamp == enc_b[2 * k + 1].timestamp - dk.BURST_US
        assert enc_b[2 * k + 1].timestamp == enc_a[2 * k + 1].timestamp
    stamps = [r.timestamp for r in b]
    assert stamps == sorted(stamps)
    # the late packets now come after laser bytes that were read before them
    assert [r.channel for r in a] != [r.channel for r in b]


def test_deskew_in_bursts_runs_small_and_its_floors_say_what_they_measured(tmp_path):
    res = dk.run(rsm_nav_binary(), tmp_path, seconds=8.0)
    assert [r["kind"] for r in res["runs"]] == list(dk.KINDS)
    for r in res["runs"]:
        assert r["poses"] == r["turns"] - 2 and r["pairs"] >= 30
        for run in ("clean", "bursts", "halved"):
            assert r[run]["local"]["matched"] > 0 and r[run]["all"]["matched"] > r[run]["local"]["matched"] / 4
    lines = dk.floors(res)
    assert len(lines) == 3 * len(dk.KINDS)
    for r, (pose, local, every) in zip(res["runs"], zip(*[iter(lines)] * 3)):
        dev = r["deviation"]
        assert pose["status"] == ("PASS" if dev["m"] <= dk.FLOOR_M and dev["deg"] <= dk.FLOOR_DEG else "MISS")
        for f, scope in ((local, "local"), (every, "all")):
            worst = max(r["bursts"][scope][q] / r["clean"][scope][q] for q in ("translation", "rotation"))
            assert math.isclose(f["value"], worst)
            assert f["status"] == ("PASS" if worst <= dk.FLOOR_X + dk.FLOOR_EPS else "MISS")
    table = dk.report(res)
    assert sum(1 for l in table if l.startswith("| LD06") or l.startswith("| RPLIDAR")) == 3 * len(dk.KINDS)
    assert dk.floors(None)[0]["status"] == "SKIP" and "not measured" in dk.report(None)[0]


def test_deskew_in_bursts_meets_the_issues_floors_on_a_short_drive(tmp_path):
    """Issue 30's floor, on 20 s of the curving drive: every burst-run pose
    within 0.1 m and 2 deg of the clean run's, errors within x1.1. De-skewing
    each turn when it ended missed it on the RPLIDAR (2.31 deg, local x2.2):
    its late pairs came after the turn, whose end was extrapolated. A turn
    now waits for odometry past its end."""
    res = dk.run(rsm_nav_binary(), tmp_path, seconds=20.0)
    lines = dk.floors(res)
    assert len(lines) == 3 * len(dk.KINDS)
    assert [f["status"] for f in lines] == ["PASS"] * len(lines), [f["line"] for f in lines]


def test_deskew_floor_arithmetic_on_made_up_figures():
    def q(t, r):
        return {"translation": t, "rotation": r, "matched": 10}

    run = {"kind": "ld06", "seconds": 10.0, "turns": 100, "pairs": 50, "poses": 98,
           "clean": {"local": q(0.01, 0.1), "all": q(0.02, 0.2)},
           "bursts": {"local": q(0.011, 0.1), "all": q(0.02, 0.23)},
           "halved": {"local": q(0.01, 0.1), "all": q(0.02, 0.2)},
           "deviation": {"m": 0.05, "deg": 2.5}, "halved_deviation": {"m": 0.0, "deg": 0.0}}
    pose, local, every = dk.floors({"burst_us": 10, "runs": [run]})
    assert pose["status"] == "MISS" and "2.50 deg" in pose["line"]  # 0.05 m passes, 2.5 deg does not
    assert local["status"] == "PASS" and math.isclose(local["value"], 1.1)  # x1.1 exactly meets it
    assert every["status"] == "MISS" and "x1.150" in every["line"]
