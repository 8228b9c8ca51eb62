"""rsm-replay into pseudo-terminals and rsm-record from pseudo-terminals."""

import os
import select
import signal
import subprocess
import sys
import time
import tty

import pytest

from conftest import subprocess_env
from rsm_tools import capture as cap
from rsm_tools import convert as cv
from rsm_tools import lidarstream
from rsm_tools import protocols as p


def start(module, *args):
    return subprocess.Popen([sys.executable, "-m", f"rsm_tools.{module}", *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=subprocess_env())


def read_pty_lines(proc, n):
    out = {}
    for _ in range(n):
        line = proc.stdout.readline()
        assert line, proc.stderr.read()
        name, path = line.split()
        out[name] = path
    return out


def drain(fds, want, timeout=30.0):
    got = {fd: bytearray() for fd in fds}
    end = time.monotonic() + timeout
    while any(len(got[fd]) < want[fd] for fd in fds) and time.monotonic() < end:
        r, _, _ = select.select(fds, [], [], 0.2)
        for fd in r:
            try:
                got[fd] += os.read(fd, 65536)
            except OSError:
                pass
    return got


@pytest.fixture(scope="module")
def head_cap(tmp_path_factory, head_log):
    out = tmp_path_factory.mktemp("rp") / "h.cap"
    cv.convert(head_log, out, units="mm", readings=361)
    return out


def expected(path):
    h, recs, _ = cap.read_capture(path)
    return {c.name: b"".join(r.data for r in recs if r.channel == c.id and r.is_rx) for c in h.channels}


def test_replay_fast_into_ptys_delivers_every_byte(head_cap):
    want = expected(head_cap)
    proc = start("replay", head_cap, "--pty", "--fast", "--wait-open", "--linger", "0.5")
    try:
        paths = read_pty_lines(proc, 2)
        assert set(paths) == {"robot", "laser"}
        fds = {}
        for name, path in paths.items():
            fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
            tty.setraw(fd)
            fds[name] = fd
        got = drain(list(fds.values()), {fds[n]: len(want[n]) for n in fds})
        for n, fd in fds.items():
            assert bytes(got[fd]) == want[n], n
            os.close(fd)
        _, err = proc.communicate(timeout=20)
        assert proc.returncode == 0, err
        assert "done" in err
    finally:
        if proc.poll() is None:
            proc.kill()
    # the bytes parse as the expected frames
    fc = p.FrameCounter("lms2xx")
    fc.feed(want["laser"])
    assert fc.types == {0xB0: 600}


def test_replay_timed_stops_cleanly_on_sigint_and_sigterm(head_cap):
    for sig in (signal.SIGINT, signal.SIGTERM):
        # --wait-open: nothing is sent before both ptys are open, so the
        # time measured from before the opens bounds the replay's own pacing
        # from below, however late the test got to open them.
        proc = start("replay", head_cap, "--pty", "--speed", "1", "--wait-open")
        try:
            paths = read_pty_lines(proc, 2)
            t0 = time.monotonic()
            fd = os.open(paths["robot"], os.O_RDWR | os.O_NOCTTY)
            tty.setraw(fd)
            laser = os.open(paths["laser"], os.O_RDWR | os.O_NOCTTY)
            tty.setraw(laser)
            got = drain([fd, laser], {fd: 200, laser: 0}, timeout=60)
            assert len(got[fd]) >= 200
            elapsed = time.monotonic() - t0
            proc.send_signal(sig)
            _, err = proc.communicate(timeout=10)
            os.close(fd)
            os.close(laser)
            assert proc.returncode == 0, err
            assert f"stopped by {sig.name}" in err
            assert elapsed > 0.5  # recorded timing: 200 bytes of 14-byte packets at ~10 Hz
        finally:
            if proc.poll() is None:
                proc.kill()


def test_replay_errors(tmp_path, head_cap):
    res = subprocess.run([sys.executable, "-m", "rsm_tools.replay", str(head_cap), "--port",
                          "robot=" + str(tmp_path / "no-such-tty")],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 1 and "cannot open port robot" in res.stderr
    res = subprocess.run([sys.executable, "-m", "rsm_tools.replay", str(head_cap), "--port", "sonar=x"],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 2 and "no channel 'sonar'" in res.stderr
    bad = tmp_path / "bad.cap"
    bad.write_bytes(b"nope")
    res = subprocess.run([sys.executable, "-m", "rsm_tools.replay", str(bad), "--pty"],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 1 and "bad magic" in res.stderr


def clocked_reader(tmp_path):
    """A --run reader of the robot and laser ptys that prints ``start T``,
    then ``T BYTES`` for every wake-up that brought bytes: T the time in
    the RSM_LOCKSTEP_CLOCK file then, BYTES what it read on both links."""
    reader = tmp_path / "clocked.py"
    reader.write_text(
        "import os, select, sys, tty\n"
        "clock = os.open(os.environ['RSM_LOCKSTEP_CLOCK'], os.O_RDONLY)\n"
        "def now(): return int.from_bytes(os.pread(clock, 8, 0), 'little')\n"
        "print('start', now())\n"
        "fds = [os.open(p, os.O_RDONLY | os.O_NOCTTY) for p in sys.argv[1:3]]\n"
        "for fd in fds: tty.setraw(fd)\n"
        "while fds:\n"
        "    ready, _, _ = select.select(fds, [], [], 60)\n"
        "    t, got = now(), 0\n"
        "    for fd in ready:\n"
        "        try:\n"
        "            data = os.read(fd, 65536)\n"
        "        except OSError:\n"
        "            data = b''\n"
        "        if not data:\n"
        "            fds.remove(fd)\n"
        "        got += len(data)\n"
        "    if got:\n"
        "        print(t, got)\n")
    return reader


def wakeups(stdout):
    """The clocked reader's lines, parsed (rsm-replay's path lines left out)."""
    return [[int(v) if v.isdigit() else v for v in l.split()] for l in stdout.splitlines()
            if not l.startswith(("robot ", "laser "))]


def test_replay_runs_its_reader_and_reports_how_it_ended(tmp_path, head_cap):
    """--run: the reader gets the pty paths, rsm-replay ends with it and
    returns its failure; --lockstep feeds it every record; wrong uses are refused."""
    def replay(*args):
        return subprocess.run([sys.executable, "-m", "rsm_tools.replay", str(head_cap), *map(str, args)],
                              capture_output=True, text=True, env=subprocess_env(), timeout=300)

    res = replay("--pty", "--lockstep")
    assert res.returncode == 2 and "--lockstep needs --pty and --run" in res.stderr
    res = replay("--pty", "--run", "true", "{sonar}")
    assert res.returncode == 2 and "no channel" in res.stderr
    res = replay("--pty", "--fast", "--linger", "0", "--run", sys.executable, "-c", "import sys; sys.exit(3)")
    assert res.returncode == 3 and "exited with status 3" in res.stderr
    # the clocked reader, fed in lockstep, the first 300 records only
    reader = clocked_reader(tmp_path)
    _, records, _ = cap.read_capture(head_cap)
    want = sum(len(r.data) for r in records[:300] if r.direction == cap.RX)
    res = replay("--pty", "--lockstep", "--records", "300", "--linger", "0.2", "--run", sys.executable, reader,
                 "{robot}", "{laser}")
    assert res.returncode == 0, res.stderr
    assert sum(t_got[1] for t_got in wakeups(res.stdout)[1:]) == want
    assert "300 records" in res.stderr and "lockstep with" in res.stderr


def test_lockstep_gives_the_reader_each_instants_capture_time(tmp_path, head_cap):
    """--lockstep: the file RSM_LOCKSTEP_CLOCK names holds 0 before the first
    instant, then, whenever the reader wakes up to bytes, the capture time
    of exactly the records it finds: each instant (the records with one
    timestamp, on both links) arrives whole, in one wake-up, with its own
    time."""
    reader = clocked_reader(tmp_path)
    _, records, _ = cap.read_capture(head_cap)
    want = []
    for r in [r for r in records if r.direction == cap.RX][:200]:
        if want and want[-1][0] == r.timestamp:
            want[-1][1] += len(r.data)
        else:
            want.append([r.timestamp, len(r.data)])
    res = subprocess.run([sys.executable, "-m", "rsm_tools.replay", str(head_cap), "--pty", "--lockstep",
                          "--records", "200", "--linger", "0.2", "--run", sys.executable, str(reader),
                          "{robot}", "{laser}"], capture_output=True, text=True, env=subprocess_env(), timeout=300)
    assert res.returncode == 0, res.stderr
    got = wakeups(res.stdout)
    assert got[0] == ["start", 0]
    assert got[1:] == want


# ---------------------------------------------------------------------------
# rsm-record


def make_pty():
    m, s = os.openpty()
    tty.setraw(s)
    return m, s, os.ttyname(s)


def wait_recording(proc, n):
    for _ in range(n):
        line = proc.stderr.readline()
        assert "recording" in line, line + proc.stderr.read()


def wait_for_bytes(path, want: int, timeout: float = 60.0) -> None:
    """Until the capture being written holds ``want`` data bytes (each record
    is flushed whole, so a lenient read of the growing file is exact)."""
    end = time.monotonic() + timeout
    got = -1
    while time.monotonic() < end:
        if path.exists():
            got = cap.read_capture(path, lenient=True)[2].bytes
            if got >= want:
                return
        time.sleep(0.05)
    raise AssertionError(f"{path} holds {got} of {want} bytes")


def record_two(out, specs, streams, chunk: int) -> str:
    """rsm-record of two ptys (``specs``: ``CHANNEL=@BAUD:protocol``, the
    pty's path put in), fed ``streams`` in chunks, stopped by SIGINT once the
    file holds every byte; returns its stderr."""
    (m1, s1, path1), (m2, s2, path2) = make_pty(), make_pty()
    proc = start("record", out, "--port", specs[0].replace("=@", f"={path1}@"), "--port",
                 specs[1].replace("=@", f"={path2}@"))
    try:
        wait_recording(proc, 2)
        for m, data in ((m1, streams[0]), (m2, streams[1])):
            for i in range(0, len(data), chunk):
                os.write(m, data[i:i + chunk])
        wait_for_bytes(out, len(streams[0]) + len(streams[1]))
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
        for fd in (m1, s1, m2, s2):
            os.close(fd)
    assert proc.returncode == 0, err
    return err


def test_record_two_ptys_then_ctrl_c(tmp_path):
    out = tmp_path / "rec.cap"
    enc = b"".join(p.encode_encoder(i * 100, -i * 100) for i in range(50))
    scans = b"".join(p.encode_b0_ranges([1.0 + i * 0.001] * 181) for i in range(5))
    err = record_two(out, ["robot=@38400:aria", "laser=@38400:lms2xx"], [enc, scans], 70)
    assert "stopped by SIGINT" in err
    assert err.splitlines()[-2] == ("rsm-record: robot 700 B 50 frames, 0 checksum errors | "
                                    "laser 1860 B 5 frames, 0 CRC errors"), err
    h, recs, st = cap.read_capture(out)
    assert [(c.name, c.protocol, c.baud) for c in h.channels] == [
        ("robot", "aria", 38400), ("laser", "lms2xx", 38400)]
    assert b"".join(r.data for r in recs if r.channel == 0) == enc
    assert b"".join(r.data for r in recs if r.channel == 1) == scans
    ts = [r.timestamp for r in recs]
    assert ts == sorted(ts)


def test_record_port_vanishes_and_missing_port(tmp_path):
    m, s, path = make_pty()
    out = tmp_path / "v.cap"
    proc = start("record", out, "--port", f"robot={path}@9600:aria")
    try:
        wait_recording(proc, 1)
        os.write(m, p.encode_encoder(1, 2))
        wait_for_bytes(out, len(p.encode_encoder(1, 2)))  # recorded, however slowly rsm-record runs
        os.close(s)
        os.close(m)   # the device goes away
        _, err = proc.communicate(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 1, err
    assert "port robot" in err and "vanished" in err
    _, recs, st = cap.read_capture(out)
    assert b"".join(r.data for r in recs) == p.encode_encoder(1, 2)
    res = subprocess.run([sys.executable, "-m", "rsm_tools.record", str(tmp_path / "n.cap"), "--port",
                          f"robot={tmp_path / 'ttyNONE'}@9600"],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 1 and "cannot open port robot" in res.stderr
    assert not (tmp_path / "n.cap").exists()


def lidar_streams():
    """An LD06 stream with one packet's CRC broken, and an RPLIDAR's health
    answer, scan descriptor and one turn of nodes."""
    pk = [lidarstream.ld06_packet(3600, (k * 1200) % 36000, (k * 1200 + 1100) % 36000, k,
                                  [(1000 + k, 200)] * 12) for k in range(100)]
    broken = bytearray(pk[50])
    broken[10] ^= 0x01
    ld06 = b"".join(pk[:50]) + bytes(broken) + b"".join(pk[51:])
    health = bytes([0xA5, 0x5A, 3, 0, 0, 0, 0x06, 0, 0, 0])
    rp = health + lidarstream.RPLIDAR_SCAN_DESCRIPTOR + b"".join(
        lidarstream.rplidar_node(j * 64, 4000 + j, 47, j == 0) for j in range(360))
    return ld06, rp


LD06_COUNTS = "99 packets (1188 points), 1 CRC errors, 0 bad angles, 47 B skipped"
RPLIDAR_COUNTS = "2 descriptors, 1 responses, 360 nodes, 0 capsules, 0 checksum errors, 0 bad, 0 B skipped"


def test_record_and_replay_know_the_lidar_channels(tmp_path):
    """:ld06 and :rplidar tags: the header carries them, rsm-record's counter
    and rsm-replay's summary decode the channel (packets and nodes, CRC and
    checksum failures) with the receivers of rsm_tools.lidarstream."""
    ld06, rp = lidar_streams()
    out = tmp_path / "lidars.cap"
    # chunks of 500 bytes cut the packets and nodes
    err = record_two(out, ["ld=@230400:ld06", "rp=@115200:rplidar"], [ld06, rp], 500)
    final = err.splitlines()[-2]   # the counters after "stopped by SIGINT"; then the file line
    assert final == (f"rsm-record: ld {len(ld06)} B {LD06_COUNTS} | rp {len(rp)} B {RPLIDAR_COUNTS}"), err
    h, recs, _ = cap.read_capture(out)
    assert [(c.name, c.protocol, c.baud) for c in h.channels] == [("ld", "ld06", 230400),
                                                                  ("rp", "rplidar", 115200)]
    assert b"".join(r.data for r in recs if r.channel == 0) == ld06
    assert b"".join(r.data for r in recs if r.channel == 1) == rp

    # rsm-replay plays the recording and says what each tagged channel carried
    proc = start("replay", out, "--pty", "--fast", "--wait-open", "--linger", "0.2")
    try:
        paths = read_pty_lines(proc, 2)
        fds = {}
        for name, path in paths.items():
            fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
            tty.setraw(fd)
            fds[name] = fd
        got = drain(list(fds.values()), {fds["ld"]: len(ld06), fds["rp"]: len(rp)})
        assert bytes(got[fds["ld"]]) == ld06 and bytes(got[fds["rp"]]) == rp
        _, err = proc.communicate(timeout=20)
    finally:
        for fd in fds.values():
            os.close(fd)
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert f"rsm-replay:   ld (ld06): {len(ld06)} B, {LD06_COUNTS}" in err.splitlines(), err
    assert f"rsm-replay:   rp (rplidar): {len(rp)} B, {RPLIDAR_COUNTS}" in err.splitlines(), err


def test_record_refuses_an_unknown_protocol_tag(tmp_path):
    res = subprocess.run([sys.executable, "-m", "rsm_tools.record", str(tmp_path / "n.cap"), "--port",
                          "lidar=/dev/null@230400:ld19"], capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 2 and "unknown protocol 'ld19'" in res.stderr
    assert "ld06" in res.stderr and "rplidar" in res.stderr
    assert not (tmp_path / "n.cap").exists()


def test_lockstep_obeys_stall_when_the_reader_leaves_a_link_unread(tmp_path, head_cap):
    """--lockstep with a reader that opens both links but reads only the
    robot's: the laser's bytes wait for ever, so rsm-replay gives up after
    --stall seconds, names the link, and fails (issue 30: it hung)."""
    reader = tmp_path / "one_link.py"
    reader.write_text(
        "import os, select, sys\n"
        "robot = os.open(sys.argv[1], os.O_RDONLY | os.O_NOCTTY)\n"
        "laser = os.open(sys.argv[2], os.O_RDONLY | os.O_NOCTTY)\n"
        "while True:\n"
        "    r, _, _ = select.select([robot], [], [], 5.0)\n"
        "    if r and not os.read(robot, 4096):\n"
        "        break\n")
    res = subprocess.run([sys.executable, "-m", "rsm_tools.replay", str(head_cap), "--pty", "--lockstep",
                          "--stall", "1", "--linger", "0", "--run", sys.executable, str(reader), "{robot}", "{laser}"],
                         capture_output=True, text=True, env=subprocess_env(), timeout=120)
    assert res.returncode != 0, res.stderr
    assert "read nothing from laser for 1 s" in res.stderr, res.stderr
