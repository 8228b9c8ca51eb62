"""End to end in active mode: rsm-nav drives a fake P3-DX and a fake SICK
LMS 2xx (rsm-fakedev) over pseudo-terminals with the library's drivers, as it
would drive the real devices (no --listen).

What is checked is what the devices saw (rsm-fakedev's log: every command
and request, with the rate the host's port was at) and what reached the
localizer (rsm-nav's --events and trajectory): the handshakes, the rate
switches on both links, keep-alives, data byte for byte, and the shutdown
sequences; and, with the lines cut for a few seconds, link loss, the robot's
watchdog stopping it, and reconnection.

No verdict depends on the machine's speed or load: the fakes wait for a
host that stalls (--patient) rather than drop anything, each run ends once
rsm-nav has decoded enough (its events file, written as it goes; then
SIGTERM, the orderly shutdown a user's Ctrl-C gives), and the lines are cut
after a count of frames and mended only once the host has said it lost them.
"""

import math
import re
import signal
import subprocess

import pytest

from conftest import FakeDevices, LiveNav, events_so_far, rsm_nav_binary, wait_until
from rsm_tools import capture as cap
from rsm_tools.fakedev import scale_counts

NAV_TIMEOUT = 180



@pytest.fixture(scope="module")
def capture_events(tmp_path_factory, excerpt_capture):
    """What rsm-nav decodes from the same capture read as a file."""
    tmp = tmp_path_factory.mktemp("ref")
    events = tmp / "cap.events"
    res = subprocess.run([str(rsm_nav_binary()), "--capture", str(excerpt_capture), "--trajectory",
                          str(tmp / "cap.txt"), "--events", str(events), "--quiet"],
                         capture_output=True, text=True, timeout=NAV_TIMEOUT)
    assert res.returncode == 0, res.stderr
    return split_events(events)


def split_events(path):
    enc, scans = [], []
    for line in path.read_text().splitlines():
        (enc if line.startswith("E ") else scans).append(line)
    return enc, scans


def start_nav(tmp, paths, *extra):
    """rsm-nav live against the fakes: (the run, its trajectory, its events file)."""
    traj, events = tmp / "live.txt", tmp / "live.events"
    nav = LiveNav(tmp, "--robot", paths["robot"], "--lms", paths["laser"], "--trajectory", traj,
                  "--events", events, *extra)
    return nav, traj, events


def counted(events, scans, encoders):
    """True once the events hold encoders encoder packets, and scans scans
    decoded after the first encoder packet (so every one has odometry)."""
    lines = events_so_far(events)
    first = next((k for k, l in enumerate(lines) if l.startswith("E ")), None)
    if first is None:
        return False
    return (sum(1 for l in lines if l.startswith("E ")) >= encoders
            and sum(1 for l in lines[first:] if l.startswith("S ")) >= scans)


def finished(nav, traj, events, stop=False):
    try:
        stderr, _ = nav.finish(stop=stop)
    finally:
        nav.kill()
    assert nav.proc.returncode == 0, stderr
    rows = [l for l in traj.read_text().splitlines() if l and not l.startswith("#")]
    return stderr, rows, split_events(events)


def run_nav(tmp, paths, scans, encoders, *extra):
    """rsm-nav live until it has decoded that many scans (after the robot's
    first encoder packet) and encoder packets: a run bounded by counts."""
    nav, traj, events = start_nav(tmp, paths, *extra)
    try:
        wait_until(lambda: counted(events, scans, encoders) or nav.proc.poll() is not None,
                   f"{scans} scans and {encoders} encoder packets")
    except BaseException:
        nav.kill()
        raise
    return finished(nav, traj, events, stop=True)


def report(stderr, device):
    """The driver counters rsm-nav prints for a device at exit."""
    m = re.search(rf"rsm-nav: {device}: (\d+) Bd, (\d+) connects \((\d+) after a link loss\), "
                  rf"(\d+) link losses", stderr)
    assert m, stderr
    rate, connects, reconnects, losses = map(int, m.groups())
    counts = {"baud": rate, "connects": connects, "reconnects": reconnects, "losses": losses}
    for key, pattern in (("encoders", r"(\d+) encoder packets"), ("keepalives", r"(\d+) keep-alives"),
                         ("scans", r"(\d+) scans"), ("bad_scans", r"(\d+) bad scans")):
        line = re.search(rf"rsm-nav: {device}: .*", stderr).group(0)
        found = re.search(pattern, line)
        if found:
            counts[key] = int(found.group(1))
    return counts


def in_order(items, reference):
    """True if the items are found in reference in their order, an item
    allowed to repeat the one before it (the robot repeats its counts until
    the next scan goes out)."""
    j = 0
    for x in items:
        while j < len(reference) and reference[j] != x:
            j += 1
        if j == len(reference):
            return False
    return True


def scaled_event(line, ticks_mm):
    """An "E left right" events line as a robot counting ticks_mm per mm sends it."""
    _, left, right = line.split()
    return "E %d %d" % scale_counts((int(left), int(right)), ticks_mm)


def commands(log):
    """The robot's commands as (name, arg, host rate), in order."""
    return [(e["name"], e["arg"], e["host_baud"]) for e in log
            if e["dev"] == "robot" and e["ev"] == "command"]


def requests(log):
    """The laser's requests as (cmd byte, data hex, host rate), in order."""
    return [(e["cmd"], e["data"], e["host_baud"]) for e in log
            if e["dev"] == "laser" and e["ev"] == "request"]


def summary(log, device):
    return next(e for e in log if e["dev"] == device and e["ev"] == "summary")


def assert_orderly_shutdown(log, stderr):
    """STOP, ENABLE 0, CLOSE to the robot; 20 25 then 20 42 to the laser,
    which ends at 9600 Bd, not streaming."""
    cmds = commands(log)
    assert [(n, a) for n, a, _ in cmds[-3:]] == [("STOP", None), ("ENABLE", 0), ("CLOSE", 1)], cmds[-6:]
    robot = summary(log, "robot")
    assert not robot["session"] and not robot["enabled"]
    reqs = requests(log)
    assert [(c, d) for c, d, _ in reqs[-2:]] == [(0x20, "25"), (0x20, "42")], reqs[-4:]
    laser = summary(log, "laser")
    assert laser["baud"] == 9600 and not laser["streaming"]
    assert "robot disconnected (STOP, ENABLE 0, CLOSE sent)" in stderr
    assert "laser stopped and back at 9600 Bd" in stderr
    assert report(stderr, "laser")["baud"] == 9600


def test_active_mode_connects_switches_rates_streams_and_shuts_down(tmp_path, excerpt_capture,
                                                                   capture_events):
    fake = FakeDevices(tmp_path, "--capture", str(excerpt_capture), "--watchdog-ms", "4000",
                       "--ticks-mm", "131", "--patient")
    try:
        # 30 encoder packets: the robot was connected for at least 3 s of its
        # own SIP cycle, time for six keep-alives at one per 0.5 s (three
        # are asked for below).
        stderr, rows, (live_enc, live_scans) = run_nav(tmp_path, fake.paths, 60, 30)
    finally:
        log = fake.stop()
    cap_enc, cap_scans = capture_events

    # P3-DX handshake, CONFIG (decoded by the driver: the values are the
    # fake's, not the driver's defaults), then HOSTBAUD to 38400 since the
    # robot reports AutoBaud 2. (A handshake step retried on a slow machine
    # would only add commands before OPEN.)
    cmds = commands(log)
    names = [n for n, _, _ in cmds]
    assert names.count("OPEN") == 1, cmds
    i = names.index("OPEN")
    assert names[i - 3:i + 3] == ["SYNC0", "SYNC1", "SYNC2", "OPEN", "CONFIG", "HOSTBAUD"], cmds[:i + 4]
    assert cmds[i + 2][1] == 2                                      # code 2 = 38400
    assert "robot connected: rsm-fakedev (Pioneer p3dx-sh) at 38400 Bd; TicksMM 131, " \
           "watchdog 4000 ms, AutoBaud 2" in stderr
    robot_bauds = [(e["old"], e["new"]) for e in log if e["dev"] == "robot" and e["ev"] == "baud"]
    assert robot_bauds == [(9600, 38400)]
    # Up to HOSTBAUD the host's port was at 9600, after it at 38400: the
    # driver moved its own port too.
    assert all(rate == 9600 for _, _, rate in cmds[:i + 2]), cmds[:i + 2]
    assert all(rate == 38400 for _, _, rate in cmds[i + 3:]), cmds[i + 3:]
    after = [(n, a) for n, a, _ in cmds[i + 3:]]
    assert ("ENABLE", 1) in after and ("ENCODER", 2) in after
    # Keep-alives while idle: PULSEs, and the robot's watchdog never fired.
    assert names.count("PULSE") >= 3
    assert summary(log, "robot")["watchdog_stops"] == 0

    # LMS start-up: probe, rate switch to 38400 (reply at the old rate), variant,
    # configuration read, continuous output; the host port followed.
    reqs = requests(log)
    k = [(c, d) for c, d, _ in reqs].index((0x20, "40"))
    assert reqs[k - 1][:2] == (0x20, "25") and reqs[k - 1][2] == 9600 and reqs[k][2] == 9600
    assert [(c, d) for c, d, _ in reqs[k + 1:k + 4]] == [(0x3B, "b4006400"), (0x74, ""), (0x20, "24")]
    assert all(r == 38400 for _, _, r in reqs[k + 1:]), reqs
    laser_bauds = [(e["old"], e["new"]) for e in log if e["dev"] == "laser" and e["ev"] == "baud"]
    assert laser_bauds == [(9600, 38400), (38400, 9600)]
    assert "laser streaming at 38400 Bd (measuring mode 0x00, 13 distance bits)" in stderr

    # The data reached the localizer unchanged: scans byte for byte in
    # capture order (the fake sends them in order from the first), and
    # encoder readings that are the capture's, in its order.
    assert len(live_scans) >= 60, stderr
    assert in_order(live_scans, cap_scans), "a scan that is not the capture's, or out of order"
    assert live_scans[0] == cap_scans[0]
    assert len(rows) == len(live_scans)
    # The fake robot counts 131 ticks per mm: the capture's counts scaled.
    assert len(live_enc) >= 30, stderr
    assert in_order(live_enc, [scaled_event(e, 131) for e in cap_enc]), \
        "an encoder reading that is not the capture's, or out of order"
    assert "rsm-nav: odometry from the robot: 131000 ticks/m" in stderr
    robot, laser = report(stderr, "robot"), report(stderr, "laser")
    assert robot["connects"] == robot["reconnects"] + 1 and robot["baud"] == 38400
    assert laser["connects"] == laser["reconnects"] + 1 and laser["bad_scans"] == 0
    assert laser["scans"] == len(live_scans)

    assert_orderly_shutdown(log, stderr)


def test_active_mode_reports_link_loss_and_reconnects_after_the_lines_come_back(tmp_path):
    # Both lines are cut once each device has sent 20 frames (SIPs, scans),
    # and held cut until rsm-nav has said it lost them and the robot's
    # watchdog has stopped it: the order the checks below rely on comes from
    # the events, not from how fast either side ran. The robot comes back
    # first, so that its data after the reconnection is there before the
    # laser's 20 further scans end the run (--scans 40); the synthetic world
    # keeps the data flowing otherwise.
    fake = FakeDevices(tmp_path, "--patient", "--robot-drop", "20f:signal", "--lms-drop", "20f:signal")
    nav = None
    try:
        nav, traj, events = start_nav(tmp_path, fake.paths, "--scans", "40")
        nav.err.wait_for("robot link lost, reconnecting")
        nav.err.wait_for("laser link lost, starting again")
        fake.wait_log(lambda e: e["dev"] == "robot" and e["ev"] == "watchdog_stop", "the robot's watchdog stop")
        fake.signal(signal.SIGUSR1)                      # the robot's line back
        fake.wait_log(lambda e: e["dev"] == "robot" and e["ev"] == "open", "the robot's second session", count=2)
        sent = fake.wait_log(lambda e: e["dev"] == "robot" and e["ev"] == "cut_start", "the robot's cut")[0]
        wait_until(lambda: sum(1 for l in events_so_far(events) if l.startswith("E ")) > sent["encoders"],
                   "an encoder packet after the robot's reconnection")
        fake.signal(signal.SIGUSR2)                      # the laser's line back
        stderr, rows, (live_enc, live_scans) = finished(nav, traj, events)
    finally:
        if nav is not None:
            nav.kill()
        log = fake.stop()

    def at(dev, ev):
        return [e for e in log if e["dev"] == dev and e["ev"] == ev]

    # The driver noticed and said so, then connected again.
    assert "robot link lost, reconnecting" in stderr
    assert "laser link lost, starting again" in stderr
    robot, laser = report(stderr, "robot"), report(stderr, "laser")
    assert robot["losses"] >= 1 and robot["reconnects"] >= 1 and robot["connects"] >= 2, stderr
    assert laser["losses"] >= 1 and laser["reconnects"] >= 1 and laser["connects"] >= 2, stderr

    # The robot, cut off, stopped itself (watchdog), kept its session open,
    # and was closed and opened again once the line was back.
    cut_end = at("robot", "cut_end")[0]["t"]
    stops = at("robot", "watchdog_stop")
    assert stops and at("robot", "cut_start")[0]["t"] < stops[0]["t"] < cut_end
    assert any(e["t"] >= cut_end for e in at("robot", "watchdog_resume"))
    assert any(e["t"] >= cut_end for e in at("robot", "close"))
    opens = at("robot", "open")
    assert len(opens) >= 2 and opens[-1]["t"] >= cut_end
    assert opens[-1]["baud"] == 38400 and opens[-1]["host_baud"] == 38400
    # The laser streamed again after its cut.
    starts = at("laser", "stream_start")
    assert len(starts) >= 2 and starts[-1]["t"] >= at("laser", "cut_end")[0]["t"]

    # Data flowed after the reconnection: the drivers received more than the
    # fakes had sent before the cuts.
    assert at("laser", "cut_start")[0]["scans"] == 20
    assert robot["encoders"] > at("robot", "cut_start")[0]["encoders"]
    assert laser["scans"] >= 40 > at("laser", "cut_start")[0]["scans"]
    assert len(live_scans) == laser["scans"] and len(rows) == len(live_scans)
    assert len(live_enc) == robot["encoders"]

    assert_orderly_shutdown(log, stderr)


def rows_of(path):
    return [tuple(map(float, l.split()[1:])) for l in path.read_text().splitlines() if l and not l.startswith("#")]


def relative(a, b):
    """Pose b in the frame of pose a (x, y, theta)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    c, s = math.cos(a[2]), math.sin(a[2])
    dth = math.atan2(math.sin(b[2] - a[2]), math.cos(b[2] - a[2]))
    return (c * dx + s * dy, -s * dx + c * dy, dth)


def test_active_mode_takes_the_robots_ticksmm_and_tracks_as_well_as_with_128(tmp_path, excerpt_capture):
    """The fake robot counts TicksMM ticks per mm and says so in its
    CONFIGpac; rsm-nav sets the localizer's odometry from it
    (rsm_localizer_set_odometry). Run with odometry alone, so that nothing
    but the encoder geometry moves the estimate: over the same stretch of
    the excerpt, the motion rsm-nav reports with TicksMM 200 agrees with the
    capture-mode run as closely as with 128. Had the 200 been ignored, every
    distance would come out 200/128 times too long (about 1.6 m over this
    stretch). Only the shape of the motion between the first and the last
    scan both runs saw is compared, with margins far above what the live
    run's own encoder sampling moves (the live clock is not asserted)."""
    # The robot mostly stands or turns in place for its first 300 scans: start there.
    header, records, _ = cap.read_capture(excerpt_capture)
    laser_id = header.channel("laser").id
    laser_times = [r.timestamp for r in records if r.channel == laser_id and r.direction == cap.RX]
    t_cut = laser_times[300]  # one record per scan
    moving = tmp_path / "moving.cap"
    with cap.CaptureWriter(moving, header.channels, header.metadata) as w:
        for r in records:
            if r.timestamp >= t_cut:
                w.write(r.timestamp, r.channel, r.data, r.direction)
    ref_traj, ref_events = tmp_path / "ref.txt", tmp_path / "ref.events"
    res = subprocess.run([str(rsm_nav_binary()), "--capture", str(moving), "--method", "odometry",
                          "--trajectory", str(ref_traj), "--events", str(ref_events), "--quiet"],
                         capture_output=True, text=True, timeout=NAV_TIMEOUT)
    assert res.returncode == 0, res.stderr
    ref_rows = rows_of(ref_traj)
    _, ref_scans = split_events(ref_events)

    errors = {}
    for ticks_mm in (128, 200):
        run_dir = tmp_path / str(ticks_mm)
        run_dir.mkdir()
        fake = FakeDevices(run_dir, "--capture", str(moving), "--ticks-mm", str(ticks_mm), "--patient")
        try:
            stderr, rows, (_, live_scans) = run_nav(run_dir, fake.paths, 100, 10, "--method", "odometry")
        finally:
            fake.stop()
        assert f"odometry from the robot: {ticks_mm * 1000} ticks/m" in stderr
        live_rows = [tuple(map(float, r.split()[1:])) for r in rows]
        assert len(live_rows) == len(live_scans) >= 100, stderr
        # Compared from the first scan after the robot's first encoder packet
        # (a robot that connected after the laser started has no odometry
        # for the scans before).
        lines = (run_dir / "live.events").read_text().splitlines()
        first = next(k for k, l in enumerate(lines) if l.startswith("E "))
        k0 = sum(1 for l in lines[:first] if l.startswith("S "))
        # Each live scan is one of the capture's, in order (the last one repeats at the end).
        idx, j = [], 0
        for sc in live_scans:
            while ref_scans[j] != sc:
                j += 1
            idx.append(j)
        last = max(k for k in range(len(idx)) if idx[k] == idx[-1] and (k == 0 or idx[k - 1] != idx[k]))
        ref_move = relative(ref_rows[idx[k0]], ref_rows[idx[last]])
        live_move = relative(live_rows[k0], live_rows[last])
        path = sum(math.dist(ref_rows[k][:2], ref_rows[k + 1][:2]) for k in range(idx[k0], idx[last]))
        assert path > 1.5, "the stretch compared must move the robot"
        errors[ticks_mm] = (math.hypot(live_move[0] - ref_move[0], live_move[1] - ref_move[1]),
                            abs(math.atan2(math.sin(live_move[2] - ref_move[2]),
                                           math.cos(live_move[2] - ref_move[2]))))
        print(f"\nTicksMM {ticks_mm}: {path:.2f} m compared, off by {errors[ticks_mm][0]:.3f} m, "
              f"{math.degrees(errors[ticks_mm][1]):.2f} deg")
    for ticks_mm, (trans, rot) in errors.items():
        assert trans < 0.3 and rot < 0.15, (ticks_mm, errors)
    assert errors[200][0] < errors[128][0] + 0.15 and errors[200][1] < errors[128][1] + 0.08, errors
