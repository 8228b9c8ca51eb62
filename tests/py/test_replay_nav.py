"""End to end over pseudo-terminals: rsm-replay plays a converted excerpt of
the real log into two ptys, rsm-nav reads them in live (listen-only) mode
through the POSIX port, and we check that the serial transport loses
nothing, that the result is the capture-mode one, and that line noise costs
only the frames it hits.

Only what is deterministic is asserted. Played in real time (8x), every
byte and frame arrives, in order on each link, whatever the load. What the
live run makes of them depends on when the machine wakes it (it stamps what
arrives), so its trajectory is compared fed in lockstep (rsm-replay
--lockstep: each instant's records are written while rsm-nav waits for
input, and it reads them in one wake-up): then it equals the capture-mode
trajectory bit for bit, on any machine. The accuracy of the real-time run
is a figure of ./tools/bench (rsm_tools.fullchecks), not a verdict here.
"""

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import REPO_ROOT, rsm_nav_binary as nav_binary, subprocess_env
from rsm_tools import capture as cap
from rsm_tools import convert
from rsm_tools import evaluate as ev



def per_channel(events: Path):
    enc, scans = [], []
    for line in events.read_text().splitlines():
        (enc if line.startswith("E ") else scans).append(line)
    return enc, scans


def start_replay(capture: Path, speed: str):
    """rsm-replay playing ``capture`` into two new ptys; returns the process and
    the ``{"robot": path, "laser": path}`` it printed."""
    replay = subprocess.Popen([sys.executable, "-m", "rsm_tools.replay", str(capture), "--pty",
                               "--wait-open", "--speed", speed, "--quiet"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=subprocess_env(),
                              cwd=REPO_ROOT)
    paths = {}
    while len(paths) < 2:
        line = replay.stdout.readline()
        if not line:
            replay.kill()
            pytest.fail(f"rsm-replay printed no pty paths: {replay.stderr.read()}", pytrace=False)
        name, path = line.split()
        paths[name] = path
    assert set(paths) == {"robot", "laser"}, paths
    return replay, paths


def run_capture_mode(capture: Path, tmp: Path):
    traj, events = tmp / "cap.txt", tmp / "cap.events"
    res = subprocess.run([str(nav_binary()), "--capture", str(capture), "--trajectory", str(traj),
                          "--events", str(events), "--quiet"], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    return traj, events, res.stdout


def test_replay_over_ptys_delivers_every_frame_in_real_time(tmp_path, excerpt_capture):
    _, cap_events, _ = run_capture_mode(excerpt_capture, tmp_path)
    header, _, _ = cap.read_capture(excerpt_capture)
    x0 = header.metadata.get("robot.initial_pose", "0 0 0").split()

    replay, paths = start_replay(excerpt_capture, "8")
    try:
        live_traj, live_events = tmp_path / "live.txt", tmp_path / "live.events"
        res = subprocess.run([str(nav_binary()), "--robot", paths["robot"], "--lms", paths["laser"], "--listen",
                              "--initial-pose", *x0, "--trajectory", str(live_traj), "--events", str(live_events),
                              "--quiet"], capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stderr
    finally:
        replay.wait(timeout=60)
    assert replay.returncode == 0, replay.stderr.read()

    cap_enc, cap_scans = per_channel(cap_events)
    live_enc, live_scans = per_channel(live_events)
    assert len(cap_scans) == 600 and len(cap_enc) > 2000
    assert live_enc == cap_enc, "the robot link lost or changed encoder packets"
    assert live_scans == cap_scans, "the laser link lost or changed scans"
    assert len(poses(live_traj)) == 600


def run_lockstep(capture: Path, tmp: Path, *nav_args: str, records=None):
    """rsm-nav live on the ptys of rsm-replay --lockstep; returns its trajectory and events files."""
    header, _, _ = cap.read_capture(capture)
    x0 = header.metadata.get("robot.initial_pose", "0 0 0").split()
    traj, events = tmp / "lock.txt", tmp / "lock.events"
    cmd = [sys.executable, "-m", "rsm_tools.replay", str(capture), "--pty", "--lockstep", "--linger", "0.2"]
    if records is not None:
        cmd += ["--records", str(records)]
    cmd += ["--run", str(nav_binary()), "--robot", "{robot}", "--lms", "{laser}", "--listen",
            "--initial-pose", *x0, "--trajectory", str(traj), "--events", str(events), *nav_args]
    res = subprocess.run(cmd, capture_output=True, text=True, env=subprocess_env(), cwd=REPO_ROOT, timeout=600)
    assert res.returncode == 0, res.stderr
    return traj, events, res


def test_live_run_fed_in_lockstep_is_the_capture_mode_run_bit_for_bit(tmp_path, excerpt_capture, head_relations):
    cap_traj, cap_events, _ = run_capture_mode(excerpt_capture, tmp_path)
    live_traj, live_events, res = run_lockstep(excerpt_capture, tmp_path, "--quiet")
    assert "600 exact" in res.stdout, res.stdout
    # every event in the same order across both links, every pose the same
    assert live_events.read_text() == cap_events.read_text()
    assert poses(live_traj) == poses(cap_traj) and len(poses(cap_traj)) == 600

    # and the capture-mode run is within the core's floor, with the log's own stamps
    stamps = [t / 1e6 for t in convert.original_scan_stamps(excerpt_capture)]
    traj = [(stamps[i], *map(float, p)) for i, p in enumerate(poses(cap_traj))]
    local = ev.evaluate(traj, ev.load_relations(head_relations), max_span=2.0, tolerance=0.0)
    assert local["unmatched"] == 0 and local["matched"] > 40
    print(f"\ncapture and lockstep live: local {local['translation']['mean']:.4f} m, "
          f"{local['rotation']['mean']:.3f} deg")
    assert local["translation"]["mean"] <= 0.03


def poses(path: Path):
    return [l.split()[1:] for l in path.read_text().splitlines() if l and not l.startswith("#")]


def test_arrival_jitter_within_the_snap_does_not_change_the_trajectory(tmp_path, excerpt_capture):
    """Each scan telegram moved 0.3 ms after its encoder packet, or 0.3 ms
    before it (and ahead of it in the file), as two links deliver them."""
    header, records, _ = cap.read_capture(excerpt_capture)
    laser = header.channel("laser").id
    jittered = tmp_path / "jitter.cap"
    out = []
    flip = 0
    for r in records:
        if r.channel != laser:
            out.append(r)
            continue
        flip ^= 1
        if flip:
            out.append(cap.Record(r.timestamp + 300, r.channel, r.direction, r.data))
        else:
            k = len(out)
            while k > 0 and out[k - 1].timestamp == r.timestamp and out[k - 1].channel != laser:
                k -= 1
            out.insert(k, cap.Record(r.timestamp - 300, r.channel, r.direction, r.data))
    with cap.CaptureWriter(jittered, header.channels, header.metadata) as w:
        for r in out:
            w.write(r.timestamp, r.channel, r.data, r.direction)
    ref_traj, _, _ = run_capture_mode(excerpt_capture, tmp_path)
    ref = poses(ref_traj)
    res = subprocess.run([str(nav_binary()), "--capture", str(jittered), "--trajectory", str(tmp_path / "j.txt"),
                          "--quiet"], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert "600 exact" in res.stdout, res.stdout
    assert poses(tmp_path / "j.txt") == ref


def test_line_noise_costs_only_the_frames_it_hits(tmp_path, excerpt_capture):
    header, records, _ = cap.read_capture(excerpt_capture)
    laser = header.channel("laser").id
    robot = header.channel("robot").id
    noisy = tmp_path / "noisy.cap"
    laser_seen = robot_seen = 0
    hit_scans = 0
    hit_encoders = 0
    with cap.CaptureWriter(noisy, header.channels, header.metadata) as w:
        for r in records:
            data = bytearray(r.data)
            if r.channel == laser:
                laser_seen += 1
                if laser_seen == 100:
                    data = bytearray(b"\x02\x80\xff\x13garbage\x06\x15") + data   # garbage before a scan
                elif laser_seen == 200:
                    data[50] ^= 0x10                                          # a flipped bit
                    hit_scans += 1
                elif laser_seen == 300:
                    continue                                                  # a dropped chunk
                elif laser_seen == 400:
                    data += b"\xaa\x02\x80"                                  # garbage after a scan
            elif r.channel == robot:
                robot_seen += 1
                if robot_seen == 500:
                    data[5] ^= 0x01
                    hit_encoders += 1
                elif robot_seen == 900:
                    data = data[: len(data) // 2]                             # a truncated packet
                    hit_encoders += 1
            w.write(r.timestamp, r.channel, bytes(data))
    _, clean_events, _ = run_capture_mode(excerpt_capture, tmp_path)
    noisy_dir = tmp_path / "n"
    noisy_dir.mkdir()
    _, noisy_events, summary = run_capture_mode(noisy, noisy_dir)
    clean_enc, clean_scans = per_channel(clean_events)
    noisy_enc, noisy_scans = per_channel(noisy_events)
    # Exactly the damaged scans are missing; every other scan is decoded unchanged.
    assert len(noisy_scans) == len(clean_scans) - hit_scans - 1
    missing = [s for s in clean_scans if s not in noisy_scans]
    assert len(missing) <= hit_scans + 1
    assert len(noisy_enc) == len(clean_enc) - hit_encoders
    assert "CRC errors 1" in summary, summary
    assert "checksum errors" in summary


def test_missing_devices_and_a_corrupt_capture_get_a_clear_message(tmp_path):
    res = subprocess.run([str(nav_binary()), "--robot", str(tmp_path / "no-such-tty"), "--lms",
                          str(tmp_path / "no-such-tty2"), "--listen", "--trajectory", str(tmp_path / "t.txt")],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 1 and "cannot open" in res.stderr and "no-such-tty" in res.stderr
    bad = tmp_path / "bad.cap"
    bad.write_bytes(b"\x89RSMCAP\n\x01\x00" + b"\xff" * 40)  # right magic, garbage after it
    res = subprocess.run([str(nav_binary()), "--capture", str(bad), "--trajectory", str(tmp_path / "t.txt")],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 1 and "not a readable capture" in res.stderr


def test_links_vanishing_mid_run_keep_what_was_written(tmp_path, excerpt_capture):
    """The replay stops after 1000 records and both ptys vanish at once:
    rsm-nav says so and keeps a pose for every scan it had been sent."""
    _, records, _ = cap.read_capture(excerpt_capture)
    header, _, _ = cap.read_capture(excerpt_capture)
    laser = header.channel("laser").id
    sent = sum(1 for r in records[:1000] if r.channel == laser)
    traj, _, res = run_lockstep(excerpt_capture, tmp_path, records=1000)
    assert "robot link" in res.stderr and "laser link" in res.stderr and "ended" in res.stderr
    rows = [l.split() for l in traj.read_text().splitlines() if l and not l.startswith("#")]
    assert 10 < len(rows) == sent < 600
    assert all(len(r) == 4 for r in rows)
    assert "rsm-nav summary" in res.stdout and re.search(rf"^\s+scans\s+{len(rows)}$", res.stdout, re.M)


def test_a_live_run_killed_keeps_the_poses_it_made(tmp_path, excerpt_capture):
    """Live mode writes each pose as it comes (issue 30: kill -9 after 8 s
    left an empty trajectory though 80 scans were fused): while rsm-nav
    runs on the replayed links, its trajectory file grows to ten complete
    pose lines, and after kill -9 they are all there."""
    header, _, _ = cap.read_capture(excerpt_capture)
    x0 = header.metadata.get("robot.initial_pose", "0 0 0").split()
    replay, paths = start_replay(excerpt_capture, "4")
    traj = tmp_path / "live.txt"
    nav = subprocess.Popen([str(nav_binary()), "--robot", paths["robot"], "--lms", paths["laser"], "--listen",
                            "--initial-pose", *x0, "--trajectory", str(traj), "--quiet"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        end = time.monotonic() + 120.0
        while time.monotonic() < end and len(poses(traj) if traj.exists() else []) < 10:
            time.sleep(0.2)
        nav.kill()
        nav.wait(timeout=30)
    finally:
        replay.kill()
        replay.wait(timeout=30)
    rows = poses(traj)
    assert len(rows) >= 10, traj.read_text() if traj.exists() else "no file"
    assert all(len(r) == 3 for r in rows)
