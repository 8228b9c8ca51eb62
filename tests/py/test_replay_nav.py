"""End to end over pseudo-terminals: rsm-replay plays a converted excerpt of
the real log into two ptys, rsm-nav reads them in live (listen-only) mode
through the POSIX port, and we check that the serial transport loses
nothing, that the result is as accurate as the core's floor, and that line
noise costs only the frames it hits.

Two links do not keep the relative order of bytes written within a fraction
of a millisecond of each other, so rsm-nav stamps what arrives and the
aligner (src/sync.c) fuses each scan with the odometry of its own time; the
converter spaces records 10 ms apart (1.25 ms at the 8x replay speed here).
The live trajectory then equals the capture-mode one whenever the machine
wakes rsm-nav within that spacing; a loaded machine may not, so equality is
checked where it is deterministic: on every input, bit for bit, and on a
capture whose laser records arrive up to 0.3 ms before or after their
encoder packets (the jitter the aligner absorbs). The live run's error must
still be within the core's floor, and how many of its poses equal the
capture-mode ones is printed.
"""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import REPO_ROOT, rsm_nav_binary as nav_binary, subprocess_env
from rsm_tools import capture as cap
from rsm_tools import convert
from rsm_tools import evaluate as ev


@pytest.fixture(scope="module")
def excerpt_capture(tmp_path_factory, head_log):
    out = tmp_path_factory.mktemp("cap") / "head.cap"
    convert.convert(str(head_log), str(out))
    return out


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


def test_replay_over_ptys_delivers_every_frame_and_the_capture_tracks_within_the_floor(
        tmp_path, excerpt_capture, head_relations):
    cap_traj, cap_events, _ = run_capture_mode(excerpt_capture, tmp_path)
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

    # Accuracy against the ground truth, with the log's own timestamps per scan.
    stamps = [t / 1e6 for t in convert.original_scan_stamps(excerpt_capture)]
    rels = ev.load_relations(head_relations)
    figures = {}
    for name, path in (("capture", cap_traj), ("live", live_traj)):
        rows = [l.split() for l in path.read_text().splitlines() if l and not l.startswith("#")]
        assert len(rows) == len(stamps)
        traj = [(stamps[i], float(r[1]), float(r[2]), float(r[3])) for i, r in enumerate(rows)]
        local = ev.evaluate(traj, rels, max_span=2.0, tolerance=0.0)
        assert local["unmatched"] == 0 and local["matched"] > 40
        figures[name] = local
        print(f"\n{name}: local {local['translation']['mean']:.4f} m, {local['rotation']['mean']:.3f} deg")
    assert figures["capture"]["translation"]["mean"] <= 0.03
    assert figures["live"]["translation"]["mean"] <= 0.03
    same = sum(a == b for a, b in zip(poses(cap_traj), poses(live_traj)))
    print(f"live poses equal to capture mode: {same} of {len(stamps)}")


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
    header, _, _ = cap.read_capture(excerpt_capture)
    x0 = header.metadata.get("robot.initial_pose", "0 0 0").split()
    replay, paths = start_replay(excerpt_capture, "4")
    try:
        traj = tmp_path / "t.txt"
        nav = subprocess.Popen([str(nav_binary()), "--robot", paths["robot"], "--lms", paths["laser"], "--listen",
                                "--initial-pose", *x0, "--trajectory", str(traj)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(4.0)
        replay.kill()  # both pseudo-terminals vanish at once
        out, err = nav.communicate(timeout=60)
    finally:
        if replay.poll() is None:
            replay.kill()
        replay.wait(timeout=30)
    assert nav.returncode == 0, err
    assert "robot link" in err and "laser link" in err and "ended" in err
    rows = [l.split() for l in traj.read_text().splitlines() if l and not l.startswith("#")]
    assert 10 < len(rows) < 600, len(rows)
    assert all(len(r) == 4 for r in rows)
    assert "rsm-nav summary" in out and f"scans           {len(rows)}" in out
