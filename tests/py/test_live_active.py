"""End to end in active mode: rsm-nav drives a fake P3-DX and a fake SICK
LMS 2xx (rsm-fakedev) over pseudo-terminals with the library's drivers, as it
would drive the real devices (no --listen).

What is checked is what the devices saw (rsm-fakedev's log: every command
and request, with the rate the host's port was at) and what reached the
localizer (rsm-nav's --events and trajectory): the handshakes, the rate
switches on both links, keep-alives, data byte for byte, and the shutdown
sequences; and, with the lines cut for a few seconds, link loss, the robot's
watchdog stopping it, and reconnection.

Timing is never asserted: the runs are long compared with what they need
(a handshake takes well under a second), and every count has a wide margin.
"""

import re
import subprocess

import pytest

from conftest import FakeDevices, rsm_nav_binary

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


def run_nav(tmp, paths, seconds):
    traj, events = tmp / "live.txt", tmp / "live.events"
    res = subprocess.run([str(rsm_nav_binary()), "--robot", paths["robot"], "--lms", paths["laser"],
                          "--seconds", str(seconds), "--trajectory", str(traj), "--events", str(events)],
                         capture_output=True, text=True, timeout=NAV_TIMEOUT + seconds)
    assert res.returncode == 0, res.stderr
    rows = [l for l in traj.read_text().splitlines() if l and not l.startswith("#")]
    return res.stderr, rows, split_events(events)


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
                       "--ticks-mm", "131")
    try:
        stderr, rows, (live_enc, live_scans) = run_nav(tmp_path, fake.paths, 8)
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
    assert len(live_scans) >= 10, stderr
    assert in_order(live_scans, cap_scans), "a scan that is not the capture's, or out of order"
    assert live_scans[0] == cap_scans[0]
    assert len(rows) == len(live_scans)
    assert len(live_enc) >= 10, stderr
    assert in_order(live_enc, cap_enc), "an encoder reading that is not the capture's, or out of order"
    robot, laser = report(stderr, "robot"), report(stderr, "laser")
    assert robot["connects"] == robot["reconnects"] + 1 and robot["baud"] == 38400
    assert laser["connects"] == laser["reconnects"] + 1 and laser["bad_scans"] == 0
    assert laser["scans"] == len(live_scans)

    assert_orderly_shutdown(log, stderr)


def test_active_mode_reports_link_loss_and_reconnects_after_the_lines_come_back(tmp_path):
    # Both lines are cut for a few seconds, two seconds after each device
    # started; the synthetic world keeps the data flowing otherwise.
    fake = FakeDevices(tmp_path, "--robot-drop", "2:3", "--lms-drop", "2:2.5")
    try:
        stderr, rows, (live_enc, live_scans) = run_nav(tmp_path, fake.paths, 15)
    finally:
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
    assert robot["encoders"] > at("robot", "cut_start")[0]["encoders"]
    assert laser["scans"] > at("laser", "cut_start")[0]["scans"]
    assert len(live_scans) == laser["scans"] and len(rows) == len(live_scans)
    assert len(live_enc) == robot["encoders"]

    assert_orderly_shutdown(log, stderr)
