"""End to end over pseudo-terminals: rsm-replay plays a converted excerpt of
the real log into two ptys, rsm-nav reads them in live (listen-only) mode
through the POSIX port, and we check that the serial transport loses
nothing, that the result is as accurate as the core's floor, and that line
noise costs only the frames it hits.

The localizer's input order across the two links depends on scheduling when
an encoder packet and a scan arrive within microseconds of each other
(pseudo-terminals deliver asynchronously), "loses nothing" is checked on
what each link delivered: every encoder reading and every scan, bit for
bit, in order. The accuracy floor is checked on the deterministic capture
path over the same bytes; the live run's own figure is printed. (Ordering
the two links by time in live mode is open work: see the issue notes.)
"""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import REPO_ROOT, subprocess_env
from rsm_tools import capture as cap
from rsm_tools import convert
from rsm_tools import evaluate as ev


def nav_binary() -> Path:
    build = os.environ.get("RSM_BUILD_DIR")
    if not build:
        pytest.fail("RSM_BUILD_DIR is not set: run these tests through ctest", pytrace=False)
    exe = Path(build) / "tools" / "nav" / "rsm-nav"
    if not exe.is_file():
        pytest.fail(f"rsm-nav not built at {exe}", pytrace=False)
    return exe


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


def original_scan_stamps(path: Path):
    """Scan timestamps as the log had them (the converter clamps some)."""
    header, records, _ = cap.read_capture(path)
    laser = header.channel("laser").id
    stamps = [r.timestamp for r in records if r.channel == laser]
    for line in header.metadata.get("convert.clamped", "").splitlines():
        kind, idx, orig, _written = line.split()
        if kind == "FLASER":
            stamps[int(idx)] = int(orig)
    return [s / 1e6 for s in stamps]


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

    replay = subprocess.Popen([sys.executable, "-m", "rsm_tools.replay", str(excerpt_capture), "--pty",
                               "--wait-open", "--speed", "8", "--quiet"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=subprocess_env(),
                              cwd=REPO_ROOT)
    try:
        paths = {}
        deadline = time.time() + 30
        while len(paths) < 2 and time.time() < deadline:
            line = replay.stdout.readline()
            if not line:
                break
            name, path = line.split()
            paths[name] = path
        assert set(paths) == {"robot", "laser"}, (paths, replay.stderr.read() if replay.poll() is not None else "")
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
    stamps = original_scan_stamps(excerpt_capture)
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
    assert figures["live"]["translation"]["mean"] < 0.1, "live mode lost track"


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
