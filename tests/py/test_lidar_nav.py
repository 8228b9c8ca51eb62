"""The cheap-lidar floor on the shipped Intel excerpt: the log rendered as an
LD06 stream (rsm-convert --lidar ld06) and run through rsm-nav's lidar path
(the LD06 driver and the revolution assembler in tools/nav/devices.c) tracks
within 10 % of the direct rsm-nav --carmen run, on the local relations and
on all of them.

What is asserted is deterministic. The capture-mode run (the recorded bytes
through the same drivers on a memory link, stamped with the record times) is
a function of the bytes alone, and carries the verdict. Over pseudo-terminals
(rsm-replay --lockstep into rsm-nav --robot --lidar ld06 --listen) every
byte, packet and turn must arrive unchanged, which the events show; its
trajectory is not asserted: a lockstep replay runs faster than the sensor
turns, and the LD06 driver stamps its points from the arrival times and the
head's speed, so the odometry each turn is fused with depends on the
machine. Its figures are printed.

De-skew is off here: each rendered turn is one logged scan, measured at one
instant, so moving its points by the motion over the turn would only add
error (the converter says so too); de-skew is measured in
tests/unit/test_revolution.c.
"""

import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO_ROOT, rsm_nav_binary as nav_binary, subprocess_env
from rsm_tools import capture as cap
from rsm_tools import convert
from rsm_tools import evaluate as ev

TOLERANCE = 1.10  # the floor: within 10 % of the direct run


def rows(path: Path):
    return [list(map(float, l.split())) for l in path.read_text().splitlines() if l and not l.startswith("#")]


@pytest.fixture(scope="module")
def direct(tmp_path_factory, head_log):
    out = tmp_path_factory.mktemp("direct") / "direct.txt"
    res = subprocess.run([str(nav_binary()), "--carmen", str(head_log), "--trajectory", str(out), "--quiet"],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    return rows(out)


@pytest.fixture(scope="module")
def ld06_capture(tmp_path_factory, head_log):
    out = tmp_path_factory.mktemp("ld06") / "ld06.cap"
    convert.convert(str(head_log), str(out), lidar="ld06")
    return out


def errors(traj, relations):
    out = {}
    for name, kw in (("local", {"max_span": 2.0}), ("all", {})):
        r = ev.evaluate(traj, relations, tolerance=0.0, **kw)
        out[name] = (r["matched"], r["unmatched"], r["translation"]["mean"], r["rotation"]["mean"])
    return out


def lidar_traj(path: Path, direct_rows):
    """The lidar run's poses at the log's scan stamps. The first turn is
    dropped (the assembler drops the turn it joined) and the last one never
    ends (no later turn starts): turn k is the log's scan k + 1."""
    got = rows(path)
    assert len(got) == len(direct_rows) - 2
    return [(direct_rows[k + 1][0], *p[1:]) for k, p in enumerate(got)]


def run_capture_mode(capture: Path, tmp: Path):
    traj, events = tmp / "cap.txt", tmp / "cap.events"
    res = subprocess.run([str(nav_binary()), "--capture", str(capture), "--no-deskew", "--trajectory", str(traj),
                          "--events", str(events), "--quiet"], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    return traj, events, res.stdout


def test_ld06_stream_tracks_within_ten_percent_of_the_direct_run(tmp_path, ld06_capture, direct, head_relations):
    traj, _, summary = run_capture_mode(ld06_capture, tmp_path)
    assert "18000 packets, 216000 points, 598 turns (1 partial); CRC errors 0, bytes skipped 0" in summary, summary
    rel = ev.load_relations(head_relations)
    lidar = errors(lidar_traj(traj, direct), rel)
    ref = errors([tuple(r) for r in direct], rel)
    for name in ("local", "all"):
        (m, u, t, r), (m0, _, t0, r0) = lidar[name], ref[name]
        print(f"\nLD06 stream {name}: {t:.4f} m {r:.3f} deg; direct {t0:.4f} m {r0:.3f} deg ({m} relations)")
        assert u <= 1 and m >= m0 - 1  # the first scan has no turn
        assert t <= TOLERANCE * t0, (name, t, t0)
        assert r <= TOLERANCE * r0, (name, r, r0)


def test_ld06_stream_over_ptys_delivers_every_turn_unchanged(tmp_path, ld06_capture, direct, head_relations):
    _, cap_events, _ = run_capture_mode(ld06_capture, tmp_path)
    header, _, _ = cap.read_capture(ld06_capture)
    x0 = header.metadata["robot.initial_pose"].split()
    traj, events = tmp_path / "live.txt", tmp_path / "live.events"
    cmd = [sys.executable, "-m", "rsm_tools.replay", str(ld06_capture), "--pty", "--lockstep", "--linger", "0.2",
           "--run", str(nav_binary()), "--robot", "{robot}", "--lidar", "ld06", "{lidar}", "--listen",
           "--no-deskew", "--initial-pose", *x0, "--trajectory", str(traj), "--events", str(events)]
    res = subprocess.run(cmd, capture_output=True, text=True, env=subprocess_env(), cwd=REPO_ROOT, timeout=600)
    assert res.returncode == 0, res.stderr
    assert "2221 encoder packets, 598 scans" in res.stderr, res.stderr
    assert events.read_text() == cap_events.read_text()
    live = errors(lidar_traj(traj, direct), ev.load_relations(head_relations))
    for name in ("local", "all"):
        print(f"\nLD06 over ptys (lockstep, not asserted) {name}: {live[name][2]:.4f} m {live[name][3]:.3f} deg")


def test_lidar_flags_are_checked(tmp_path, ld06_capture):
    res = subprocess.run([str(nav_binary()), "--robot", "/dev/null", "--lidar", "vlp16", "/dev/null",
                          "--trajectory", str(tmp_path / "t.txt")], capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and "ld06 or rplidar" in res.stderr
    res = subprocess.run([str(nav_binary()), "--capture", str(ld06_capture), "--lidar-keep", "0",
                          "--trajectory", str(tmp_path / "t.txt")], capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and "--lidar-keep" in res.stderr
    rp = tmp_path / "rp.cap"
    convert.convert(str(REPO_ROOT / "tests" / "data" / "intel_head.clf.gz"), str(rp), lidar="rplidar")
    res = subprocess.run([str(nav_binary()), "--capture", str(rp), "--trajectory", str(tmp_path / "t.txt")],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 1 and "cannot listen only" in res.stderr
