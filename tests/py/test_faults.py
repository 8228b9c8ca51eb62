"""Regression tests for the faults an adversarial audit found in rsm-nav's
input paths (issue 13): read errors, hostile captures and logs, timestamps
that poison what follows, and what rsm-nav says and returns about them.

Read errors are made by a preload library built with the tests
(tests/support/fault_shim.c): reading one named file fails with EIO after a
given number of bytes.
"""

import gzip
import math
import os
import re
import signal
import sys
import subprocess
import time
from pathlib import Path

import pytest

from conftest import REPO_ROOT, FakeDevices, LiveNav, build_dir, events_so_far, rsm_nav_binary, wait_until
from rsm_tools import capture as cap
from rsm_tools import evaluate as ev

NAV_TIMEOUT = 120


def shim_library() -> Path:
    lib = build_dir() / "tests" / "rsm_fault_shim.so"
    if not lib.is_file():
        pytest.fail(f"fault shim not built at {lib}", pytrace=False)
    return lib


def run_nav(*args, fault_path=None, fault_after=None, timeout=NAV_TIMEOUT, report_open=False):
    env = dict(os.environ)
    if fault_path is not None:
        env["LD_PRELOAD"] = str(shim_library())
        env["RSM_FAULT_PATH"] = str(fault_path)
        env["RSM_FAULT_AFTER"] = str(fault_after)
        if report_open:
            env["RSM_FAULT_REPORT_OPEN"] = "1"
        # Under ASan the runtime is not first in the library list: allowed here.
        env["ASAN_OPTIONS"] = (env.get("ASAN_OPTIONS", "") + ":verify_asan_link_order=0").lstrip(":")
    return subprocess.run([str(rsm_nav_binary()), *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, env=env)


def number(pattern: str, text: str) -> int:
    m = re.search(pattern, text)
    assert m, f"no {pattern!r} in:\n{text}"
    return int(m.group(1))


def nav_with_map(tmp_path: Path, lines, name: str, *extra: str):
    """Writes lines as the log NAME.clf and runs rsm-nav on it with --map
    m.pgm (and extra arguments); returns the run and the picture's path."""
    log = tmp_path / f"{name}.clf"
    log.write_text("\n".join(lines) + "\n")
    pgm = tmp_path / "m.pgm"
    return run_nav("--carmen", log, "--trajectory", tmp_path / "t.txt", "--map", pgm, "--quiet", *extra), pgm


def rows(path: Path):
    return [l for l in path.read_text().splitlines() if l and not l.startswith("#")]



def record_offsets(path: Path):
    with cap.CaptureReader(path) as r:
        return [rec.offset for rec in r]


def test_capture_read_error_at_a_record_boundary_stops_flushes_and_fails(tmp_path, excerpt_capture):
    offsets = record_offsets(excerpt_capture)
    cut = offsets[len(offsets) // 2]
    # What the records before the failure give, read from an intact file.
    part = tmp_path / "part.cap"
    part.write_bytes(excerpt_capture.read_bytes()[:cut])
    ref = run_nav("--capture", part, "--trajectory", tmp_path / "ref.txt", "--quiet")
    assert ref.returncode == 0, ref.stderr
    traj = tmp_path / "t.txt"
    res = run_nav("--capture", excerpt_capture, "--trajectory", traj, "--quiet",
                  fault_path=excerpt_capture, fault_after=cut)
    assert res.returncode == 1, res.stderr
    assert "read error" in res.stderr and "Input/output error" in res.stderr, res.stderr
    assert len(rows(traj)) > 100
    assert rows(traj) == rows(tmp_path / "ref.txt")


def test_capture_read_error_in_the_header_is_said_as_one(tmp_path, excerpt_capture):
    """Reading the capture's header fails (EIO after 4 and after 20 bytes):
    rsm-nav says it could not read it, not that the file is no capture
    (issue 30: "bad magic"), and fails."""
    for after in (4, 20):
        res = run_nav("--capture", excerpt_capture, "--trajectory", tmp_path / "t.txt", "--quiet",
                      fault_path=excerpt_capture, fault_after=after)
        assert res.returncode == 1, res.stderr
        assert "read error in the capture header" in res.stderr and "Input/output error" in res.stderr, res.stderr
        assert "bad magic" not in res.stderr and "truncated" not in res.stderr, res.stderr


def test_capture_run_closes_its_file(tmp_path, excerpt_capture):
    res = run_nav("--capture", excerpt_capture, "--trajectory", tmp_path / "t.txt", "--quiet",
                  fault_path=excerpt_capture, fault_after=1 << 40, report_open=True)
    assert res.returncode == 0, res.stderr
    assert "never closed" not in res.stderr, res.stderr


def test_capture_read_error_inside_a_record_is_an_error_not_a_truncated_tail(tmp_path, excerpt_capture):
    offsets = record_offsets(excerpt_capture)
    cut = offsets[len(offsets) // 3] + 7
    traj = tmp_path / "t.txt"
    res = run_nav("--capture", excerpt_capture, "--trajectory", traj, "--quiet",
                  fault_path=excerpt_capture, fault_after=cut)
    assert res.returncode == 1, res.stderr
    assert "read error" in res.stderr, res.stderr
    assert "truncated 1" not in res.stdout, res.stdout
    assert len(rows(traj)) > 50


def point_link(link: Path, target: str):
    tmp = link.with_name(link.name + ".new")
    if tmp.is_symlink():
        tmp.unlink()
    tmp.symlink_to(target)
    os.replace(tmp, link)


def test_active_mode_reopens_a_robot_that_vanished_and_came_back(tmp_path, excerpt_capture):
    """The fake robot is killed (an adapter pulled out) and started again
    behind the same name (plugged back in, as a udev symlink does): rsm-nav
    neither spins nor floods the dead line, reopens it with back-off, and
    takes the restarted counters as a new connection. Each step waits for
    what rsm-nav decoded or said, so none depends on the machine's speed."""
    robot = tmp_path / "robot"
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    first = FakeDevices(tmp_path / "a", "--robot", "--capture", str(excerpt_capture), "--patient")
    point_link(robot, first.paths["robot"])
    traj, events = tmp_path / "t.txt", tmp_path / "e.txt"

    def encoders():
        return sum(1 for l in events_so_far(events) if l.startswith("E "))

    t0 = time.monotonic()
    nav = LiveNav(tmp_path, "--robot", robot, "--trajectory", traj, "--events", events)
    second = None
    try:
        wait_until(lambda: encoders() > 20 or nav.proc.poll() is not None, "21 encoder packets")
        first.proc.send_signal(signal.SIGKILL)  # gone without a word
        first.proc.wait()
        robot.unlink()
        nav.err.wait_for("robot link " + str(robot) + " failed")
        before = encoders()
        second = FakeDevices(tmp_path / "b", "--robot", "--capture", str(excerpt_capture), "--patient")
        point_link(robot, second.paths["robot"])
        nav.err.wait_for("reopened")
        wait_until(lambda: encoders() > before or nav.proc.poll() is not None,
                   "an encoder packet from the robot plugged back in")
        err, out = nav.finish(stop=True)
        seconds = time.monotonic() - t0   # at least as long as rsm-nav ran
    finally:
        nav.kill()
        if second is not None:
            second.stop()
    assert nav.proc.returncode == 0, err
    assert "robot link " + str(robot) + " failed" in err, err
    assert "reopened" in err, err
    assert number(r"(\d+) connects \(", err) >= 2, err
    # One PULSE per 0.5 s at most while connected (the busy loop sent millions).
    assert number(r"(\d+) keep-alives", err) <= 2 * seconds + 4, err
    restarts = number(r"(\d+) counter restarts", out)
    assert restarts >= 2, out
    enc = [l for l in events.read_text().splitlines() if l.startswith("E ")]
    assert len(enc) > 20


# ---- CARMEN logs ------------------------------------------------------------------


@pytest.mark.parametrize("damage", ["truncated", "corrupt", "directory", "read_error"])
def test_carmen_log_that_cannot_be_read_to_the_end_is_an_error(tmp_path, head_log, damage):
    data = head_log.read_bytes()
    log = tmp_path / "log.clf.gz"
    fault = {}
    if damage == "truncated":
        log.write_bytes(data[:len(data) // 2])
        why = "unexpected end of file"
    elif damage == "corrupt":
        mid = bytearray(data)
        for i in range(len(mid) // 2, len(mid) // 2 + 40):
            mid[i] ^= 0x55
        log.write_bytes(bytes(mid))
        why = "log.clf.gz: "
    elif damage == "directory":
        log.mkdir()
        why = "Is a directory"
    else:
        log.write_bytes(data)
        fault = {"fault_path": log, "fault_after": len(data) // 2}
        why = "Input/output error"
    traj = tmp_path / "t.txt"
    res = run_nav("--carmen", log, "--trajectory", traj, "--quiet", **fault)
    assert res.returncode == 1, res.stderr
    assert "cannot read" in res.stderr and why in res.stderr, res.stderr
    if damage != "directory":
        assert len(rows(traj)) > 50  # what was read is kept


def flaser_lines(head_log, n):
    text = gzip.decompress(head_log.read_bytes()).decode()
    return [l for l in text.splitlines() if l.startswith("FLASER")][:n]


def test_carmen_reading_counts_that_are_not_whole_numbers_are_malformed(tmp_path, head_log):
    lines = flaser_lines(head_log, 30)
    for k, count in ((5, "nan"), (9, "1.5"), (13, "inf"), (17, "1e300")):
        f = lines[k].split()
        f[1] = count
        lines[k] = " ".join(f)
    log = tmp_path / "bad.clf"
    log.write_text("\n".join(lines) + "\n")
    res = run_nav("--carmen", log, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert "malformed 4" in res.stdout, res.stdout
    assert len(rows(tmp_path / "t.txt")) == 26


def test_both_carmen_readers_take_the_same_spellings_of_counts_and_numbers(tmp_path, head_log):
    """A count of readings is decimal digits alone (CARMEN writes %d) and a
    number is decimal: rsm-nav's reader took 0x10 (strtod reads hex) and
    16.0 as 16 where rsm-convert's refused them, and rsm-convert's took +16
    and 1_6 (int() reads both) where rsm-nav's refused 1_6 (issue 30)."""
    from rsm_tools import carmen as cm
    bad_counts = ["0x10", "16.0", "1e1", "+16", "1_6", "-16", "\u0661\u0666"]
    bad_numbers = ["0x1p3", "1_0.5", "nan(1)"]
    lines = []
    for k, line in enumerate(flaser_lines(head_log, 40)):
        f = line.split()
        n = int(f[1])
        f = ["FLASER", "016" if k == 0 else "16"] + f[2:18] + f[2 + n:]  # 16 readings, the pose and stamp
        if k < len(bad_counts):
            f[1] = bad_counts[k]
        elif k - len(bad_counts) < len(bad_numbers):
            f[5] = bad_numbers[k - len(bad_counts)]               # a reading
        lines.append(" ".join(f))
    log = tmp_path / "spelled.clf"
    log.write_text("\n".join(lines) + "\n", encoding="utf-8")
    reader = cm.LogReader(log)
    taken = len(list(reader))
    bad = len(bad_counts) + len(bad_numbers)
    assert (taken, reader.stats.malformed_total) == (40 - bad, bad), reader.stats.summary()
    res = run_nav("--carmen", log, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert re.search(rf"lines +40 \(scans {40 - bad}, .*malformed {bad},", res.stdout), res.stdout


def test_both_carmen_readers_take_the_same_fields_and_separators(tmp_path, head_log):
    """Fields are split at ASCII spaces, tabs, CRs and LFs, lines end at LF,
    every record has exactly its fields and each of them is checked: where
    the two readers differed (issue 30's remaining ones), rsm-nav's took a
    FLASER or ODOM line with an extra field, an ODOM tv, a logger stamp or
    a ROBOTLASER1 laser type, accuracy, remission mode, remission or safety
    field that is no number, and split at neither a no-break space nor a
    form feed, where rsm-convert's refused or split; and rsm-convert's
    ended a line at a lone CR, where rsm-nav's splits a field."""
    from rsm_tools import carmen as cm
    text = gzip.decompress(head_log.read_bytes()).decode()
    raw = [l for l in text.splitlines() if l.startswith(("FLASER", "ODOM"))][:60]
    flaser = [l for l in raw if l.startswith("FLASER")]
    odom = [l for l in raw if l.startswith("ODOM")]

    def robotlaser(line, **changes):
        rec = cm.parse_line(line)
        rl = cm.RobotLaser1(0, -math.pi / 2, math.pi, math.pi / 180, 81.9, 0.01, 0, rec.ranges, [],
                            rec.laser_pose, rec.odom_pose, 0.0, 0.0, 0.0, 0.0, 0.0, rec.timestamp, rec.host,
                            rec.logger_timestamp)
        f = cm.format_robotlaser1(rl).split(" ")
        for k, v in changes.items():
            f[int(k[1:]) if k[0] == "i" else len(f) - int(k[1:])] = v
        return " ".join(f)

    def odd(line, at, sep):
        """line with the space before field at (from the end) made sep"""
        f = line.split(" ")
        return " ".join(f[:-at]) + sep + " ".join(f[-at:])

    bad = [
        flaser[0] + " 0",                         # an extra field
        with_fields(flaser[1], p1="abc"),         # the logger stamp
        odd(flaser[2], 3, "\u00a0"),              # no-break space: one field
        odd(flaser[3], 3, "\f"),                  # form feed: one field
        odom[0] + " 0",
        " ".join(odom[1].split()[:4] + ["abc"] + odom[1].split()[5:]),   # tv
        " ".join(odom[2].split()[:-1] + ["nan"]),                         # logger stamp
        robotlaser(flaser[4], i1="1.5"),          # laser type
        robotlaser(flaser[5], i6="abc"),          # accuracy
        robotlaser(flaser[6], i7="x"),            # remission mode
        robotlaser(flaser[7], p8="inf"),          # tv
        robotlaser(flaser[8]) + " 0",
        robotlaser(flaser[9], i189="1 abc"),      # one remission, not a number
    ]
    good = [robotlaser(flaser[10]), robotlaser(flaser[11]), odd(flaser[12], 3, "\r"), odd(odom[3], 2, "\t")]
    lines = bad + good + raw[40:]
    log = tmp_path / "fields.clf"
    log.write_bytes(("\n".join(lines) + "\n").encode("utf-8"))
    reader = cm.LogReader(log)
    taken = list(reader)
    assert (len(taken), reader.stats.malformed_total) == (len(good) + len(raw[40:]), len(bad)), \
        reader.stats.summary()
    scans = sum(1 for r in taken if r.kind != "ODOM")
    res = run_nav("--carmen", log, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert re.search(rf"lines +{len(lines)} \(scans {scans}, odometry {len(taken) - scans}, .*malformed {len(bad)},",
                     res.stdout), res.stdout


def test_carmen_line_longer_than_the_buffer_with_a_nul_is_one_line(tmp_path, head_log):
    lines = flaser_lines(head_log, 10)
    # Over 64 KiB, with a NUL early on and what looks like a record after it.
    long_line = "COMMENT \0 " + lines[0] + " " + "x" * 70000
    log = tmp_path / "nul.clf"
    log.write_text("\n".join(lines[:5] + [long_line] + lines[5:]) + "\n")
    res = run_nav("--carmen", log, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert "too long 1" in res.stdout, res.stdout
    assert re.search(r"lines\s+11 ", res.stdout), res.stdout
    assert len(rows(tmp_path / "t.txt")) == 10


# ---- the --map picture ------------------------------------------------------------


def read_pgm(path: Path):
    data = path.read_bytes()
    head = data.split(b"\n", 4)
    w, h = map(int, head[2].split())
    pixels = head[4]
    assert len(pixels) == w * h
    return w, h, pixels


def yaml_origin(path: Path):
    for line in path.read_text().splitlines():
        if line.startswith("origin:"):
            x, y, _ = line.split("[", 1)[1].rstrip("]").split(",")
            return float(x), float(y)
    raise AssertionError("no origin in " + str(path))


def with_fields(line: str, **changes) -> str:
    """A FLASER line with some readings or pose fields replaced (the pose
    fields count from the end: odom x is -6, the stamp -3)."""
    f = line.split()
    for key, value in changes.items():
        f[int(key[1:]) if key[0] == "r" else len(f) - int(key[1:])] = value
    return " ".join(f)


def stamped(line: str, t: float) -> str:
    f = line.split()
    f[-3] = f"{t:.6f}"
    f[-1] = f"{t:.6f}"
    return " ".join(f)


def test_map_picture_has_each_scans_own_points_even_when_it_had_too_few(tmp_path, head_log):
    lines = flaser_lines(head_log, 40)
    for k in range(20, 40):
        f = lines[k].split()
        f[2:182] = ["0.00"] * 180            # too short: dropped
        f[2 + 85:2 + 95] = ["15.00"] * 10     # ten readings 15 m ahead: a FEW_POINTS scan
        lines[k] = " ".join(f)
    res, pgm = nav_with_map(tmp_path, lines, "few")
    assert res.returncode == 0, res.stderr
    assert re.search(r"^\s+few_points\s+20$", res.stdout, re.M), res.stdout
    w, h, px = read_pgm(pgm)
    x0, y0 = yaml_origin(tmp_path / "m.yaml")
    last = rows(tmp_path / "t.txt")[-1].split()
    rx, ry, rt = float(last[1]), float(last[2]), float(last[3])
    import math
    wx, wy = rx + 15.0 * math.cos(rt), ry + 15.0 * math.sin(rt)
    cx, cy = int((wx - x0) / 0.05), int((wy - y0) / 0.05)
    assert 0 <= cx < w and 0 <= cy < h, "the picture does not reach the few points"
    near = [px[(h - 1 - y) * w + x] for y in range(cy - 10, cy + 11) for x in range(cx - 10, cx + 11)
            if 0 <= x < w and 0 <= y < h]
    assert 0 in near


def write_repeated_log(path: Path, head_log, n: int):
    """n copies of one scan (a robot standing still), gzipped line by line
    so that this process stays small: a child's peak RSS as the kernel
    reports it is at least its parent's at the fork."""
    line = flaser_lines(head_log, 1)[0]
    with gzip.open(path, "wt") as f:
        for k in range(n):
            f.write(stamped(line, 1000.0 + 0.1 * k) + "\n")


def heap_peak(args) -> int:
    res = run_nav(*args)
    assert res.returncode == 0, res.stderr
    return number(r"heap +peak (\d+) bytes", res.stdout)


def test_map_picture_memory_does_not_grow_with_the_number_of_scans(tmp_path, head_log):
    """20 000 scans of a robot standing still: the picture's blocks are the
    ones 2 000 scans give, byte for byte, and far below what the old one
    took (it kept every point, 1.4 KB per scan: over 12 MiB here); and
    the picture is the one a tenth of the scans gives. rsm-nav counts its
    own blocks (tools/nav/heap.h), a figure no machine's load moves."""
    log = tmp_path / "still.clf.gz"
    write_repeated_log(log, head_log, 20000)
    short = tmp_path / "short.clf.gz"
    write_repeated_log(short, head_log, 2000)
    base = ["--trajectory", tmp_path / "t.txt", "--quiet"]
    without = heap_peak(["--carmen", log, *base])
    with_map = heap_peak(["--carmen", log, "--map", tmp_path / "m.pgm", *base])
    assert without < with_map < without + 1024 * 1024, (without, with_map)
    assert heap_peak(["--carmen", short, "--map", tmp_path / "s.pgm", *base]) == with_map
    assert (tmp_path / "m.pgm").read_bytes() == (tmp_path / "s.pgm").read_bytes()


def test_map_picture_with_no_points_at_first_and_a_teleport_far_away(tmp_path, head_log):
    lines = flaser_lines(head_log, 30)
    f = lines[0].split()
    f[2:182] = ["0.00"] * 180                       # the first scan has no usable point
    lines[0] = " ".join(f)
    lines[10] = with_fields(lines[10], o6="1e18")    # one pose 1e18 m away
    res, pgm = nav_with_map(tmp_path, lines, "far")
    assert res.returncode == 0, res.stderr
    assert "left out of the picture" in res.stderr, res.stderr
    assert pgm.read_bytes()[:2] == b"P5"


def test_map_picture_too_large_says_so(tmp_path, head_log):
    lines = flaser_lines(head_log, 30)
    for k in range(15, 30):
        lines[k] = with_fields(lines[k], o6=str(1500.0 + float(lines[k].split()[-6])))
    # The scans refute a 1.5 km step of odometry's (the map then stays
    # small); trusted, it spreads the map over 1.5 km.
    res, _ = nav_with_map(tmp_path, lines, "wide")
    assert res.returncode == 0 and "1 refuted by the scans" in res.stdout, res.stdout + res.stderr
    res, _ = nav_with_map(tmp_path, lines, "wide", "--set", "refute_margin=0")
    assert res.returncode == 1, res.stderr
    assert "would span" in res.stderr and "1000 m" in res.stderr, res.stderr


# ---- live mode ------------------------------------------------------------------------


def test_listen_mode_on_a_source_that_never_runs_dry_keeps_its_time_limit(tmp_path):
    res = run_nav("--robot", "/dev/zero", "--listen", "--seconds", "1", "--trajectory", tmp_path / "t.txt",
                  "--quiet", timeout=30)
    assert res.returncode == 0, res.stderr


def test_listen_mode_on_a_source_that_never_runs_dry_stops_at_a_signal(tmp_path):
    # Started with SIGTERM ignored (kept across exec until rsm-nav installs
    # its handler), and sent SIGTERM until it ends: a signal that came before
    # the handler is lost rather than fatal, so how fast rsm-nav starts does
    # not matter; one that never ends the run leaves it hung (failed).
    nav = subprocess.Popen([str(rsm_nav_binary()), "--robot", "/dev/zero", "--listen", "--trajectory",
                            str(tmp_path / "t.txt")], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_IGN))
    try:
        end = time.monotonic() + 60
        while nav.poll() is None and time.monotonic() < end:
            nav.send_signal(signal.SIGTERM)
            try:
                nav.wait(timeout=0.5)
            except subprocess.TimeoutExpired:
                pass
        _, err = nav.communicate(timeout=30)
    finally:
        if nav.poll() is None:
            nav.kill()
            nav.wait()
    assert nav.returncode == 0, err
    assert "stopped by signal" in err, err


def test_listen_mode_with_nothing_ever_arriving_fails(tmp_path):
    res = run_nav("--robot", "/dev/null", "--listen", "--seconds", "1", "--trajectory", tmp_path / "t.txt",
                  "--quiet", timeout=30)
    assert res.returncode == 1, res.stderr
    assert "nothing arrived" in res.stderr, res.stderr


def test_active_mode_with_no_device_ever_connecting_fails(tmp_path):
    """A pseudo-terminal nobody answers on: the drivers try for the whole run."""
    import pty
    master, slave = pty.openpty()
    try:
        res = run_nav("--robot", os.ttyname(slave), "--seconds", "2", "--trajectory", tmp_path / "t.txt",
                      "--quiet", timeout=60)
    finally:
        os.close(master)
        os.close(slave)
    assert res.returncode == 1, res.stderr
    assert "no robot ever connected" in res.stderr, res.stderr


def test_active_mode_backs_off_from_a_device_that_opens_and_fails_at_once(tmp_path):
    """An empty file opens and fails at the first poll, as a device that
    enumerates and dies does: the back-off (0.1 s doubling to 2 s) starts
    again only after a connection, not after every open (issue 30: thirty
    reopens in 3 s). The schedule allows four in 3 s; a slower machine
    makes fewer. Back-off is about real time, but the bounds hold on any
    machine: rsm-nav's own clock cannot run faster than the schedule, and the
    first reopen, due 0.1 s after the first poll, is made by the cycle that
    follows it, which comes before the time limit is checked (only a 2.9 s
    stall at the very start of the loop could leave none)."""
    dead = tmp_path / "dead"
    dead.write_bytes(b"")
    res = run_nav("--robot", dead, "--seconds", "3", "--trajectory", tmp_path / "t.txt", timeout=60)
    assert res.returncode == 1 and "no robot ever connected" in res.stderr, res.stderr
    assert 1 <= number(r"robot link reopened (\d+) times", res.stderr) <= 6, res.stderr


def wait_for_rows(path: Path, n: int, proc, limit: float = 60.0) -> None:
    """Until the live run's trajectory (flushed per pose) has n rows."""
    end = time.monotonic() + limit
    while time.monotonic() < end and proc.poll() is None:
        if path.is_file() and len(rows(path)) >= n:
            return
        time.sleep(0.1)
    pytest.fail(f"no {n} poses from the live run")


@pytest.mark.parametrize("how", ["silent", "vanished"])
def test_active_mode_run_whose_device_never_came_back_fails(tmp_path, excerpt_capture, how):
    """The laser goes quiet for good (its line cut) or both devices vanish
    (the fake killed) while the run goes on to its end: rsm-nav keeps and
    sums up what it got, says in one line which device was lost and did not
    come back, and exits 1 (issue 30: exit 0).

    The laser's line goes after 10 scans (a count), so the 5 poses waited
    for always come. That a device never came back can only be said of a
    run that ended on its own, and both end 3 s after a device was lost
    (--lost-exit), however long the start took: the vanished run after its
    links failed (the fake killed: an event, not a silence timed out, so a
    fake that stalls under load before it is killed cannot end the run
    early, as --idle-exit could), the silent one, whose robot still talks,
    after the laser was lost."""
    extra = ["--lms-drop", "10f:1000"] if how == "silent" else []
    fake = FakeDevices(tmp_path, "--capture", str(excerpt_capture), "--patient", *extra)
    # Named as udev names them: a pseudo-terminal's number may be taken
    # again by another test's, which the reopening must not find.
    links = {dev: tmp_path / dev for dev in ("robot", "laser")}
    for dev, link in links.items():
        point_link(link, fake.paths[dev])
    traj = tmp_path / "t.txt"
    end = ["--lost-exit", "3"]
    nav = subprocess.Popen([str(rsm_nav_binary()), "--robot", str(links["robot"]), "--lms", str(links["laser"]),
                            *end, "--trajectory", str(traj)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for_rows(traj, 5, nav)
        if how == "vanished":
            fake.proc.send_signal(signal.SIGKILL)  # gone without a word, never back
            fake.proc.wait()
            for link in links.values():
                link.unlink()
        out, err = nav.communicate(timeout=NAV_TIMEOUT)
    finally:
        if nav.poll() is None:
            nav.kill()
            nav.wait()
        if how == "silent":
            fake.stop()
    assert nav.returncode == 1, err
    last = err.strip().splitlines()[-1]
    assert re.fullmatch(r"rsm-nav: .*the laser link \S+ was lost [0-9.]+ s into the run and no scan came after that",
                        last), err
    assert ("the robot never connected again" in last) == (how == "vanished"), err
    assert "rsm-nav summary" in out and len(rows(traj)) >= 5, out


# ---- hostile captures -------------------------------------------------------------------


def test_capture_resync_over_false_record_starts_costs_one_crc_pass(tmp_path, excerpt_capture):
    """1 MiB of "RC\\xff\\xff": a false record start every 4 bytes, each
    claiming 64 KiB. The reader used to CRC each claim anew (39 s)."""
    data = excerpt_capture.read_bytes()
    offsets = record_offsets(excerpt_capture)
    cut = offsets[len(offsets) // 2]
    hostile = tmp_path / "hostile.cap"
    hostile.write_bytes(data[:cut] + b"RC\xff\xff" * (1 << 18) + data[cut:])
    res = run_nav("--capture", hostile, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert "corrupt 1," in res.stdout and f"{1 << 20} bytes skipped" in res.stdout, res.stdout
    checked = number(r"(\d+) checked by CRC", res.stdout)
    assert checked <= 2 * len(hostile.read_bytes()), res.stdout
    assert len(rows(tmp_path / "t.txt")) == len(rows_of_clean_run(tmp_path, excerpt_capture))


def rows_of_clean_run(tmp_path, capture):
    traj = tmp_path / "clean.txt"
    res = run_nav("--capture", capture, "--trajectory", traj, "--quiet")
    assert res.returncode == 0, res.stderr
    return rows(traj)


# ---- command line -------------------------------------------------------------------------


@pytest.mark.parametrize("kv, top", [("iterations=1e12", "4294967295"), ("min_hits=256", "255"),
                                     ("min_hits=257", "255"), ("seed=1.5", "4294967295"),
                                     ("k_den=2147483648", "2147483647"), ("rule=3", "2"), ("noise=-1", "1")])
def test_set_refuses_integers_that_do_not_fit_their_field(tmp_path, head_log, kv, top):
    res = run_nav("--carmen", head_log, "--trajectory", tmp_path / "t.txt", "--quiet", "--set", kv)
    assert res.returncode == 2, res.stderr
    assert f"a whole number from 0 to {top}" in res.stderr, res.stderr


def test_set_takes_integers_at_the_top_of_their_field(tmp_path, head_log):
    res = run_nav("--carmen", head_log, "--trajectory", tmp_path / "t.txt", "--quiet", "--method", "odometry",
                  "--set", "min_hits=255", "--set", "rule=2", "--set", "seed=4294967295")
    assert res.returncode == 0, res.stderr


# ---- coordinates far from the origin, and what the start pose messages say ---------------


def shifted_log(head_log, path: Path, dx: float):
    text = gzip.decompress(head_log.read_bytes()).decode()
    out = []
    for line in text.splitlines():
        f = line.split()
        if f and f[0] == "FLASER":
            for k in (-9, -8, -6, -5):  # laser x y, odometry x y
                f[k] = repr(float(f[k]) + dx)
            line = " ".join(f)
        out.append(line)
    path.write_text("\n".join(out) + "\n")


@pytest.mark.parametrize("method", ["rsm", "paper"])
def test_a_log_far_from_the_origin_tracks_as_it_does_near_it(tmp_path, head_log, method):
    """5e5 m out a float resolves 3 cm: rsm-nav runs the localizer in a
    frame centred on the start and adds the offset back to its outputs."""
    near = tmp_path / "near.txt"
    res = run_nav("--carmen", head_log, "--trajectory", near, "--quiet", "--method", method)
    assert res.returncode == 0, res.stderr
    for dx in (5e5, 2e6):
        log = tmp_path / f"far{dx:.0f}.clf"
        shifted_log(head_log, log, dx)
        far = tmp_path / f"far{dx:.0f}.txt"
        res_far = run_nav("--carmen", log, "--trajectory", far, "--quiet", "--method", method,
                          "--map", tmp_path / "m.pgm")
        assert res_far.returncode == 0, res_far.stderr
        if method == "paper" and dx > 1e6:
            # The log's text carries x + 2e6 m to fewer decimals, so a few
            # odometry increments differ in their last bit, and the paper's
            # method (RANSAC over key points) follows another path from such
            # a bit (docs/robustness.md). What must hold is that it tracks as
            # well: the same local error against the excerpt's relations.
            rel = ev.load_relations(REPO_ROOT / "tests" / "data" / "intel_head.relations")
            err_near = ev.evaluate(ev.load_trajectory(near), rel, max_span=2.0)["translation"]["mean"]
            err_far = ev.evaluate(ev.load_trajectory(far), rel, max_span=2.0)["translation"]["mean"]
            assert err_far < 1.25 * err_near, (err_near, err_far)
            continue
        outcomes = [l for l in res.stdout.splitlines() if l.startswith("    ")]
        assert outcomes == [l for l in res_far.stdout.splitlines() if l.startswith("    ")], res_far.stdout
        for a, b in zip(rows(near), rows(far)):
            a, b = a.split(), b.split()
            assert abs(float(a[1]) + dx - float(b[1])) < 1e-3 and abs(float(a[2]) + dx - float(b[2])) < 1e-3
        x0, _ = yaml_origin(tmp_path / "m.yaml")
        assert abs(x0 - dx) < 100.0


def with_metadata(src: Path, dst: Path, **meta):
    data = src.read_bytes()
    with open(src, "rb") as fh:
        header, size = cap.read_header(fh)
    for key, value in meta.items():
        header.metadata[key.replace("__", ".")] = value
    dst.write_bytes(cap.encode_header(header) + data[size:])
    return dst


def test_a_start_pose_that_is_not_finite_is_named(tmp_path, excerpt_capture):
    bad = with_metadata(excerpt_capture, tmp_path / "nan.cap", robot__initial_pose="nan 0 0")
    res = run_nav("--capture", bad, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 2, res.stderr
    assert "start pose from the capture's robot.initial_pose is not finite" in res.stderr, res.stderr
    assert "invalid configuration" not in res.stderr


def test_a_capture_with_nonsense_geometry_is_named(tmp_path, excerpt_capture):
    bad = with_metadata(excerpt_capture, tmp_path / "geom.cap", robot__ticks_per_m="nan")
    res = run_nav("--capture", bad, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 1, res.stderr
    assert "robot.ticks_per_m is 'nan', not a positive number" in res.stderr, res.stderr


# ---- one bad timestamp must not poison the rest ---------------------------------------------


def clamped_count(stdout: str) -> int:
    return number(r"timestamps +(\d+) clamped", stdout)


def test_one_odd_carmen_stamp_does_not_clamp_every_later_scan(tmp_path, head_log):
    lines = flaser_lines(head_log, 200)
    clean = tmp_path / "clean.clf"
    clean.write_text("\n".join(lines) + "\n")
    ref = run_nav("--carmen", clean, "--trajectory", tmp_path / "r.txt", "--quiet")
    assert ref.returncode == 0, ref.stderr
    odd = list(lines)
    odd[50] = with_fields(odd[50], o3="-5.0")                         # negative
    odd[120] = with_fields(odd[120], o3=f"{4e9:.6f}")                 # far future
    log = tmp_path / "odd.clf"
    log.write_text("\n".join(odd) + "\n")
    res = run_nav("--carmen", log, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert clamped_count(res.stdout) == clamped_count(ref.stdout), res.stdout
    assert "2 odd" in res.stdout, res.stdout
    assert len(rows(tmp_path / "t.txt")) == 200


def test_a_real_jump_of_the_clock_is_taken_once(tmp_path, head_log):
    lines = flaser_lines(head_log, 200)
    jumped = lines[:100] + [stamped(l, float(l.split()[-3]) + 7200.0) for l in lines[100:]]
    log = tmp_path / "jump.clf"
    log.write_text("\n".join(jumped) + "\n")
    clean = tmp_path / "clean.clf"
    clean.write_text("\n".join(lines) + "\n")
    ref = run_nav("--carmen", clean, "--trajectory", tmp_path / "r.txt", "--quiet")
    res = run_nav("--carmen", log, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert "1 odd" in res.stdout and "1 jumps of the clock" in res.stdout, res.stdout
    assert clamped_count(res.stdout) == clamped_count(ref.stdout), res.stdout


def restamped_capture(src: Path, dst: Path, changes: dict):
    """The capture with some records' stamps replaced (index -> stamp or a
    function of the old stamp), CRCs recomputed."""
    data = src.read_bytes()
    with open(src, "rb") as fh:
        _, size = cap.read_header(fh)
    with cap.CaptureReader(src) as r:
        recs = list(r)
    out = bytearray(data[:size])
    for k, rec in enumerate(recs):
        ts = rec.timestamp
        if k in changes:
            ts = changes[k](ts) if callable(changes[k]) else changes[k]
        out += cap.encode_record(ts, rec.channel, rec.direction, rec.data)
    dst.write_bytes(bytes(out))
    return len(recs)


def test_one_far_future_capture_record_does_not_drop_the_rest(tmp_path, excerpt_capture):
    n = restamped_capture(excerpt_capture, tmp_path / "far.cap", {300: 2 ** 62})
    res = run_nav("--capture", tmp_path / "far.cap", "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert re.search(rf"records\s+{n - 1} \(corrupt 0, truncated 0, out of order 1,", res.stdout), res.stdout
    _, recs, stats = cap.read_capture(tmp_path / "far.cap", lenient=True)
    assert (len(recs), stats.out_of_order) == (n - 1, 1)
    ref = rows_of_clean_run(tmp_path, excerpt_capture)
    assert len(rows(tmp_path / "t.txt")) >= len(ref) - 1


def test_a_capture_whose_clock_jumps_is_read_on(tmp_path, excerpt_capture):
    hour2 = 7_200_000_000
    n = restamped_capture(excerpt_capture, tmp_path / "jump.cap",
                          {k: (lambda t: t + hour2) for k in range(300, 100000)})
    res = run_nav("--capture", tmp_path / "jump.cap", "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert re.search(rf"records\s+{n - 1} \(corrupt 0, truncated 0, out of order 1,", res.stdout), res.stdout
    _, recs, stats = cap.read_capture(tmp_path / "jump.cap", lenient=True)
    assert (len(recs), stats.out_of_order) == (n - 1, 1)


def clock_steps(stdout: str):
    m = re.search(r"capture clock +(\d+) steps back, (\d+) jumps over an hour ahead", stdout)
    assert m, stdout
    return int(m.group(1)), int(m.group(2))


def test_a_capture_whose_clock_steps_back_is_read_on(tmp_path, excerpt_capture):
    """From record 300 on the clock reads three days earlier: every later
    record was skipped as out of order (issue 30: exit 0 with half the
    poses). The record after the first earlier one confirms the step; the
    drivers' time carries on across it, so the run is the clean one."""
    days3 = 3 * 86_400_000_000
    n = restamped_capture(excerpt_capture, tmp_path / "back.cap",
                          {k: (lambda t: t - days3) for k in range(300, 100000)})
    traj = tmp_path / "t.txt"
    res = run_nav("--capture", tmp_path / "back.cap", "--trajectory", traj, "--quiet")
    assert res.returncode == 0, res.stderr
    assert re.search(rf"records\s+{n - 1} \(corrupt 0, truncated 0, out of order 1,", res.stdout), res.stdout
    assert clock_steps(res.stdout) == (1, 0)
    _, recs, stats = cap.read_capture(tmp_path / "back.cap", lenient=True)
    assert (len(recs), stats.out_of_order) == (n - 1, 1)
    ref = rows_of_clean_run(tmp_path, excerpt_capture)
    got = rows(traj)
    assert len(got) == len(ref)
    # The one record lost is an encoder packet the next one makes up for.
    assert all(abs(float(a.split()[1]) - float(b.split()[1])) < 0.01 for a, b in zip(ref, got))


def test_an_rplidar_capture_whose_clock_jumps_keeps_every_scan(tmp_path, head_log):
    """The clock jumps two hours ahead mid-capture: the listen-only RPLIDAR
    driver took the jump for an hour's silence, gave the link up and waited
    for a scan descriptor that never came (issue 30: 309 of 598 poses,
    exit 0). Now no time passes across the jump, the summary counts it, and
    the trajectory keeps the capture's own stamps."""
    from rsm_tools import convert
    clean = tmp_path / "rp.cap"
    convert.convert(str(head_log), str(clean), lidar="rplidar")
    hour2 = 7_200_000_000
    with cap.CaptureReader(clean) as r:
        half = sum(1 for _ in r) // 2
    n = restamped_capture(clean, tmp_path / "jump.cap", {k: (lambda t: t + hour2) for k in range(half, 10 ** 6)})
    traj = tmp_path / "t.txt"
    res = run_nav("--capture", tmp_path / "jump.cap", "--trajectory", traj, "--quiet")
    assert res.returncode == 0, res.stderr
    assert re.search(rf"records\s+{n - 1} \(corrupt 0, truncated 0, out of order 1,", res.stdout), res.stdout
    assert clock_steps(res.stdout) == (0, 1)
    ref = rows_of_clean_run(tmp_path, clean)
    got = rows(traj)
    assert len(ref) > 500 and len(got) >= len(ref) - 1, (len(ref), len(got))
    assert float(got[-1].split()[0]) == pytest.approx(float(ref[-1].split()[0]) + 7200.0, abs=1e-6)


# ---- the C and Python capture readers refuse the same headers ---------------------------------


def raw_header(body: bytes) -> bytes:
    import struct
    import zlib
    fixed = cap.MAGIC + struct.pack("<HHI", 1, 0, len(body))
    return fixed + body + struct.pack("<I", zlib.crc32(fixed + body))


def header_body(name: bytes = b"robot", key: bytes = b"k", value: bytes = b"v", channels: int = 1) -> bytes:
    import struct
    body = bytes([channels])
    for i in range(channels):
        body += struct.pack("<BBIB", i, 1, 9600, len(name)) + name
    return body + struct.pack("<H", 1) + struct.pack("<H", len(key)) + key + struct.pack("<I", len(value)) + value


@pytest.mark.parametrize("body", [
    header_body(channels=0),
    header_body(name=b"\xff\xfe"),
    header_body(key=b"\xc3"),                  # cut short
    header_body(value=b"\xc0\xaf"),            # overlong
    header_body(value=b"\xed\xa0\x80"),        # a surrogate
    header_body(value=b"\xf4\x90\x80\x80"),    # past U+10FFFF
], ids=["no_channels", "name", "key_cut", "overlong", "surrogate", "too_high"])
def test_both_capture_readers_refuse_the_same_headers(tmp_path, body):
    import io
    path = tmp_path / "h.cap"
    path.write_bytes(raw_header(body))
    with pytest.raises(cap.HeaderError):
        cap.read_header(io.BytesIO(path.read_bytes()))
    res = run_nav("--capture", path, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 1, res.stderr
    assert "capture header body malformed" in res.stderr, res.stderr


def test_both_capture_readers_take_utf8_beyond_ascii(tmp_path):
    import io
    path = tmp_path / "h.cap"
    path.write_bytes(raw_header(header_body(name="läser".encode(), value="\U0010FFFF €".encode())))
    header, _ = cap.read_header(io.BytesIO(path.read_bytes()))
    assert header.channels[0].name == "läser"
    res = run_nav("--capture", path, "--trajectory", tmp_path / "t.txt", "--quiet")
    # the header is read; the capture holds no record, so no pose (issue 30: said, exit 1)
    assert res.returncode == 1 and res.stderr.startswith("rsm-nav: no pose: no scan came out of the capture"), \
        res.stderr


def test_a_run_that_makes_no_pose_says_so_and_fails(tmp_path, head_log):
    """A log or capture that yields no pose exits 1 with a one-line reason
    (issue 30: they exited 0 with nothing said): an empty or binary CARMEN
    file, a capture whose laser channel is empty, LD06 data tagged as
    RPLIDAR, an empty LMS channel before the LD06 one."""
    empty = tmp_path / "empty.clf"
    empty.write_text("")
    binary = tmp_path / "binary.clf"
    binary.write_bytes(bytes(range(256)) * 64)
    for log in (empty, binary):
        res = run_nav("--carmen", log, "--trajectory", tmp_path / "t.txt", "--quiet")
        assert res.returncode == 1, res.stderr
        assert res.stderr.strip().splitlines()[-1] == "rsm-nav: no pose: the log holds no usable laser scan", \
            res.stderr
    # the excerpt's robot channel alone: encoder packets, no scan
    from rsm_tools import convert
    full = tmp_path / "head.cap"
    convert.convert(str(head_log), str(full))
    h, recs, _ = cap.read_capture(full)
    robot = h.channel("robot").id
    only = tmp_path / "robot.cap"
    w = cap.CaptureWriter(only, h.channels, h.metadata)
    for r in recs:
        if r.channel == robot:
            w.write(r.timestamp, r.channel, r.data, r.direction)
    w.close()
    res = run_nav("--capture", only, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 1 and "rsm-nav: no pose: no scan came out of the capture" in res.stderr, res.stderr
    # the excerpt as an LD06 stream tagged as an RPLIDAR one, and with an
    # empty LMS channel before its own: the laser link read is not the LD06
    ld = tmp_path / "ld06.cap"
    convert.convert(str(head_log), str(ld), lidar="ld06")
    h, recs, _ = cap.read_capture(ld)
    lidar = next(c for c in h.channels if c.name != "robot")
    tagged = [cap.Channel(c.id, c.name, "rplidar" if c is lidar else c.protocol, c.baud) for c in h.channels]
    lms_first = ([c for c in h.channels if c is not lidar] + [cap.Channel(lidar.id + 1, "laser", "lms2xx", 38400)]
                 + [lidar])
    for name, chans, meta in (("tagged", tagged, {**h.metadata, "laser.model": "rplidar"}),
                              ("lms_first", lms_first, h.metadata)):
        path = tmp_path / f"{name}.cap"
        with cap.CaptureWriter(path, chans, meta) as w:
            for r in recs:
                w.write(r.timestamp, r.channel, r.data, r.direction)
        res = run_nav("--capture", path, "--trajectory", tmp_path / "t.txt", "--quiet")
        assert res.returncode == 1 and "rsm-nav: no pose: no scan came out of the capture" in res.stderr, \
            (name, res.stderr)


# ---- rsm-replay ---------------------------------------------------------------------------


def replay(*args, timeout=60):
    from conftest import subprocess_env
    return subprocess.Popen([sys.executable, "-m", "rsm_tools.replay", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=subprocess_env())


def tiny_capture(path: Path, stamps):
    import struct
    import zlib
    body = bytes([1]) + struct.pack("<BBIB", 0, 1, 9600, 5) + b"robot" + struct.pack("<H", 0)
    fixed = cap.MAGIC + struct.pack("<HHI", 1, 0, len(body))
    data = fixed + body + struct.pack("<I", zlib.crc32(fixed + body))
    for k, ts in enumerate(stamps):
        data += cap.encode_record(ts, 0, cap.RX, bytes([k]) * 10)
    path.write_bytes(data)


def test_replay_shortens_long_pauses_and_survives_the_last_stamp(tmp_path):
    """A pause of 1 s and one to 2^64-1 us (the latter was an OverflowError
    traceback, the former slept through)."""
    path = tmp_path / "gaps.cap"
    tiny_capture(path, [0, 1_000_000, 2 ** 64 - 1])
    proc = replay(path, "--pty", "--max-gap", "0.05", "--linger", "0")
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    assert "3 records" in err and "2 pauses over 0.05 s shortened" in err, err


def test_replay_stops_when_the_pty_reader_goes_away(tmp_path, excerpt_capture):
    proc = replay(excerpt_capture, "--pty", "--fast", "--wait-open", "--linger", "0", "--stall", "5")
    try:
        paths = {}
        while len(paths) < 2:
            line = proc.stdout.readline()
            assert line, proc.stderr.read()
            name, dev = line.split()
            paths[name] = dev
        fds = [os.open(dev, os.O_RDONLY | os.O_NOCTTY) for dev in paths.values()]
        os.read(fds[0], 100)
        for fd in fds:
            os.close(fd)  # the reader dies with most of the capture unread
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 1, err
    assert "closed it" in err or "nothing read" in err, err


# ---- rsm-convert ---------------------------------------------------------------------------


def run_convert(log, out):
    from conftest import subprocess_env
    return subprocess.run([sys.executable, "-m", "rsm_tools.convert", str(log), str(out)], capture_output=True,
                          text=True, timeout=120, env=subprocess_env())


def test_convert_takes_scans_without_readings_and_negative_stamps(tmp_path, head_log):
    lines = flaser_lines(head_log, 60)
    f = lines[10].split()
    lines[10] = " ".join(["FLASER", "0"] + f[182:])          # no readings
    for k in (0, 1, 30):
        lines[k] = stamped(lines[k], -5.0 - k)              # negative, at the start and inside
    log = tmp_path / "odd.clf"
    log.write_text("\n".join(lines) + "\n")
    out = tmp_path / "odd.cap"
    res = run_convert(log, out)
    assert res.returncode == 0, res.stderr
    assert "Traceback" not in res.stderr
    assert "1 FLASER lines without readings sent as odometry only" in res.stderr, res.stderr
    _, recs, _ = cap.read_capture(out)
    assert sum(1 for r in recs if r.channel == 1) == 59
    nav = run_nav("--capture", out, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert nav.returncode == 0, nav.stderr
    assert len(rows(tmp_path / "t.txt")) == 59


def test_convert_says_what_it_skipped(tmp_path, head_log):
    lines = flaser_lines(head_log, 30)
    f = lines[5].split()
    robotlaser = ("ROBOTLASER1 0 -1.5708 3.1416 0.0175 81.9 0.01 0 180 " + " ".join(f[2:182]) + " 0 "
                  + " ".join(f[182:188]) + " 0 0 0 0 0 " + " ".join(f[188:]))
    lines.insert(6, robotlaser)
    lines.insert(8, "FLASER 180 1.0 2.0")
    log = tmp_path / "mixed.clf"
    log.write_text("\n".join(lines) + "\n")
    res = run_convert(log, tmp_path / "mixed.cap")
    assert res.returncode == 0, res.stderr
    assert "not converted (only ODOM and FLASER are): 1 ROBOTLASER1" in res.stderr, res.stderr
    assert "malformed lines skipped: field_count=1" in res.stderr, res.stderr


def test_convert_reports_a_truncated_gzip_log(tmp_path, head_log):
    data = head_log.read_bytes()
    log = tmp_path / "cut.clf.gz"
    log.write_bytes(data[:len(data) // 2])
    res = run_convert(log, tmp_path / "cut.cap")
    assert res.returncode == 1, res.stderr  # a file that fails at run time, as the C tools say
    assert "Traceback" not in res.stderr and "cannot read" in res.stderr, res.stderr


# ---- a checksum-valid but corrupt ENCODER packet ------------------------------------------------


def test_a_corrupt_encoder_packet_that_passes_its_checksum_does_not_move_the_robot(tmp_path, excerpt_capture):
    """ARIA's additive checksum misses two opposite bit flips in one column:
    such a packet once sent the pose 8 km away for good."""
    from rsm_tools import protocols as proto
    data = excerpt_capture.read_bytes()
    with open(excerpt_capture, "rb") as fh:
        _, size = cap.read_header(fh)
    with cap.CaptureReader(excerpt_capture) as r:
        recs = list(r)
    robot = [k for k, rec in enumerate(recs) if rec.channel == 0]
    hit = robot[len(robot) // 2]
    left, right = proto.decode_encoder(recs[hit].data)
    out = bytearray(data[:size])
    for k, rec in enumerate(recs):
        payload = proto.encode_encoder(left + 2 ** 30, right) if k == hit else rec.data
        out += cap.encode_record(rec.timestamp, rec.channel, rec.direction, payload)
    bad = tmp_path / "corrupt.cap"
    bad.write_bytes(bytes(out))
    ref = rows_of_clean_run(tmp_path, excerpt_capture)
    res = run_nav("--capture", bad, "--trajectory", tmp_path / "t.txt", "--quiet")
    assert res.returncode == 0, res.stderr
    assert number(r"(\d+) implausible increments refused", res.stdout) >= 1, res.stdout
    got = rows(tmp_path / "t.txt")
    assert len(got) == len(ref)
    worst = max(abs(float(a.split()[1]) - float(b.split()[1])) + abs(float(a.split()[2]) - float(b.split()[2]))
                for a, b in zip(ref, got))
    assert worst < 0.2, worst
