"""rsm-fakedev on its own: the fake P3-DX, LMS 2xx and RPLIDAR answer a
host that talks to their pseudo-terminals directly, as the real devices
would (protocols.md, lidars.md), and they notice a host at the wrong rate.

Waits are generous and never the thing being measured: every check is on
what came back, not on how fast. The fakes are --patient, so a test that
stalls for a while (a loaded machine) loses no byte of a stream, and what
must have happened before a check is waited for in the fake's log."""

import argparse
import math
import os
import select
import struct
import termios
import time
import tty

import pytest

from conftest import FakeDevices, load_vectors
from rsm_tools import fakedev, lidarstream, sim
from rsm_tools import protocols as p

TIMEOUT = 30.0


class Host:
    """The host end of one pseudo-terminal: raw, at a given rate."""

    def __init__(self, path, baud=9600):
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.fd)
        self.set_baud(baud)
        self.buf = bytearray()
        self.all = bytearray()   # every byte read, to count frames across reads

    def set_baud(self, baud):
        attrs = termios.tcgetattr(self.fd)
        attrs[4] = attrs[5] = getattr(termios, f"B{baud}")
        termios.tcsetattr(self.fd, termios.TCSANOW, attrs)

    def send(self, data):
        os.write(self.fd, data)

    def read_until(self, done, timeout=TIMEOUT):
        """Reads until done(bytes so far) is true; returns the bytes."""
        end = time.monotonic() + timeout
        while not done(bytes(self.buf)) and time.monotonic() < end:
            r, _, _ = select.select([self.fd], [], [], 0.1)
            if r:
                data = os.read(self.fd, 4096)
                self.buf += data
                self.all += data
        out = bytes(self.buf)
        self.buf.clear()
        return out

    def frames(self, protocol, data):
        fc = p.FrameCounter(protocol)
        fc.keep = True
        fc.feed(data)
        return fc.take()

    def close(self):
        os.close(self.fd)


def aria_types(host, data):
    return [p.aria_unframe(f)[0] for f in host.frames("aria", data)]


def until_aria(want_type, count=1):
    def done(data):
        fc = p.FrameCounter("aria")
        fc.feed(data)
        return fc.types.get(want_type, 0) >= count
    return done


def until_lms(want_cmd):
    def done(data):
        fc = p.FrameCounter("lms2xx")
        fc.feed(data)
        return fc.types.get(want_cmd, 0) >= 1
    return done


def handshake(host):
    """SYNC0, SYNC1, SYNC2 with their echoes; returns the SYNC2 reply."""
    for step in range(3):
        host.send(p.aria_packet(step))
        data = host.read_until(until_aria(step))
        frames = [f for f in host.frames("aria", data) if f[3] == step]
        assert frames, f"no reply to SYNC{step}: {data.hex()}"
    return frames[0]


def sips(host, data):
    return [p.decode_sip(f) for f in host.frames("aria", data) if f[3] in (0x32, 0x33)]


def read_alive(host, done, timeout=TIMEOUT):
    """host.read_until(done), with a PULSE to the robot every 0.2 s: its
    watchdog cannot stop it while this waits, however long the fake is held
    up (each turn of its loop takes what the host sent before it looks at
    the time)."""
    got = b""
    end = time.monotonic() + timeout
    while not done(got) and time.monotonic() < end:
        host.send(p.aria_command(p.CMD_PULSE))
        got += host.read_until(lambda d: done(got + d), timeout=0.2)
    return got


def read_all_sent_before(host, entry):
    """Reads until every SIP and ENCODER packet the robot had sent when it
    logged entry (its ``sips``/``encoders`` then) has arrived: what comes
    after that was sent after the logged event."""
    def done(_):
        fc = p.FrameCounter("aria")
        fc.feed(bytes(host.all))
        return (fc.types.get(0x32, 0) + fc.types.get(0x33, 0) >= entry["sips"]
                and fc.types.get(p.ARIA_ENCODER, 0) >= entry.get("encoders", 0))
    host.read_until(done)


def test_robot_handshake_config_sip_stream_motion_and_watchdog(tmp_path):
    fake = FakeDevices(tmp_path, "--robot", "--watchdog-ms", "1500", "--ticks-mm", "131", "--patient")
    host = Host(fake.paths["robot"])
    try:
        # Before OPEN nothing streams.
        assert host.read_until(lambda d: False, timeout=0.4) == b""
        reply = handshake(host)
        _, payload = p.aria_unframe(reply)
        assert payload.split(b"\x00")[:3] == [b"rsm-fakedev", b"Pioneer", b"p3dx-sh"]

        host.send(p.aria_command(p.CMD_OPEN, 1))
        host.send(p.aria_command(p.CMD_CONFIG, 1))
        data = host.read_until(until_aria(p.ARIA_CONFIGPAC))
        config = [f for f in host.frames("aria", data) if f[3] == p.ARIA_CONFIGPAC][0]
        assert config == p.encode_config_pac(p.AriaConfig(watchdog=1500, ticks_mm=131))

        # SIPs every cycle; ENCODER packets only once asked for.
        data = host.read_until(until_aria(0x32, 3))
        assert p.ARIA_ENCODER not in aria_types(host, data)
        host.send(p.aria_command(p.CMD_ENABLE, 1))
        host.send(p.aria_command(p.CMD_ENCODER, 2))
        host.send(p.aria_command(p.CMD_VEL, 200))
        data = read_alive(host, until_aria(0x33, 3))
        moving = [s for s in sips(host, data) if s.moving]
        assert moving[-1].lvel == 200 and moving[-1].rvel == 200 and moving[-1].flags & 1
        encs = [p.decode_encoder(f) for f in host.frames("aria", data) if f[3] == p.ARIA_ENCODER]
        assert len(encs) >= 2 and encs[-1][0] > encs[0][0] and encs[-1][1] > encs[0][1]

        # Nothing from the host for longer than the watchdog: the robot stops ...
        data = host.read_until(lambda d: any(not s.moving for s in sips(host, d)))
        assert any(not s.moving for s in sips(host, data))
        # ... and drives again once commands come back (motion resumes).
        data = read_alive(host, until_aria(0x33, 1))
        assert any(s.moving for s in sips(host, data))

        # VEL2 -5/+5 turns on the spot; STOP stops; CLOSE ends the stream.
        host.send(p.aria_vel2(-5, 5))
        data = read_alive(host, lambda d: any(s.lvel == -100 for s in sips(host, d)))
        assert any(s.lvel == -100 and s.rvel == 100 for s in sips(host, data))
        host.send(p.aria_command(p.CMD_STOP))
        host.read_until(lambda d: any(not s.moving for s in sips(host, d)))
        host.send(p.aria_command(p.CMD_CLOSE, 1))
        # Once what was sent before the CLOSE has come, nothing more does
        # (waiting for the fake's own record of it, not for some time).
        read_all_sent_before(host, fake.wait_log(lambda e: e["ev"] == "close", "the CLOSE")[0])
        assert host.read_until(lambda d: False, timeout=0.5) == b""
    finally:
        host.close()
        log = fake.stop()
    events = [e["ev"] for e in log if e["dev"] == "robot"]
    assert events.count("watchdog_stop") >= 1 and events.count("watchdog_resume") >= 1
    assert events.index("watchdog_stop") < events.index("watchdog_resume")
    summary = [e for e in log if e["ev"] == "summary"][0]
    assert summary["sessions"] == 1 and summary["closes"] == 1 and not summary["session"]


def test_robot_hostbaud_moves_the_robot_and_a_host_left_behind_hears_noise(tmp_path):
    fake = FakeDevices(tmp_path, "--robot", "--patient")
    host = Host(fake.paths["robot"])
    try:
        handshake(host)
        host.send(p.aria_command(p.CMD_OPEN, 1))
        host.read_until(until_aria(0x32, 1))
        host.send(p.aria_command(p.CMD_HOSTBAUD, 2))      # 38400, host stays at 9600
        # Everything from before the switch (the handshake's replies, the
        # SIPs it had sent, whole and in order), then only noise: never a
        # frame again, every byte garbled.
        switch = fake.wait_log(lambda e: e["ev"] == "baud", "the rate change")[0]
        read_all_sent_before(host, switch)

        def garbled_tail(_):
            tail = 0
            while tail < len(host.all) and 0xE0 <= host.all[-1 - tail] <= 0xEF:
                tail += 1
            return tail >= 200
        host.read_until(garbled_tail)
        heard = bytes(host.all)
        frames = host.frames("aria", heard)
        before = sum(len(f) for f in frames)
        assert heard[:before] == b"".join(frames)
        assert sum(1 for f in frames if f[3] in (0x32, 0x33)) == switch["sips"]
        noise = heard[before:]
        assert len(noise) >= 200 and all(0xE0 <= b <= 0xEF for b in noise)
        host.set_baud(38400)                                # now follow the robot
        host.read_until(lambda d: False, timeout=0.3)
        data = host.read_until(until_aria(0x32, 2))
        assert len(sips(host, data)) >= 2
    finally:
        host.close()
        log = fake.stop()
    bauds = [(e["old"], e["new"]) for e in log if e["ev"] == "baud"]
    assert bauds == [(9600, 38400)]


def test_laser_acks_naks_switches_rate_streams_and_answers_status(tmp_path):
    fake = FakeDevices(tmp_path, "--lms", "--units", "cm", "--patient")
    host = Host(fake.paths["laser"])
    try:
        # A request whose CRC is wrong gets a NAK and is not carried out.
        bad = bytearray(p.lms_telegram(0x20, b"\x24"))
        bad[-1] ^= 0x40
        host.send(bytes(bad))
        assert host.read_until(lambda d: len(d) >= 1) == bytes([p.LMS_NAK])
        assert host.read_until(lambda d: False, timeout=0.5) == b""   # no stream started

        # ACK, then the reply; a rate change answers at the old rate.
        host.send(p.lms_telegram(0x20, b"\x40"))
        data = host.read_until(until_lms(0xA0))
        assert data[0] == p.LMS_ACK
        assert p.lms_unframe(data[1:]) == (0x80, 0xA0, b"\x00\x10")
        host.send(p.lms_telegram(0x3B, struct.pack("<HH", 180, 50)))   # host still at 9600
        noise = host.read_until(lambda d: len(d) >= 1 + 13)
        assert noise[0] != p.LMS_ACK and host.frames("lms2xx", noise) == []
        host.set_baud(38400)

        host.send(p.lms_telegram(0x3B, struct.pack("<HH", 180, 25)))   # not a variant
        data = host.read_until(until_lms(0xBB))
        assert p.lms_unframe(data[1:])[2] == b"\x00\xb4\x00\x32\x00\x10"
        host.send(p.lms_telegram(0x74))
        data = host.read_until(until_lms(0xF4))
        block = p.lms_unframe(data[1:])[2]
        assert len(block) == 33 and block[5] == 0x00 and block[6] == 0x00   # 8 m mode, cm
        host.send(p.lms_telegram(0x31))
        data = host.read_until(until_lms(0xB1))
        status = p.lms_unframe(data[1:])[2]
        assert status[7] == 0x25 and struct.unpack_from("<H", status, 115)[0] == 0x8019

        # Continuous output: 0xB0 telegrams with no ACK in front, 361 values in cm.
        host.send(p.lms_telegram(0x20, b"\x24"))
        data = host.read_until(lambda d: len(host.frames("lms2xx", d)) >= 4)
        scans = [p.decode_b0(f) for f in host.frames("lms2xx", data) if f[4] == 0xB0]
        assert len(scans) >= 3
        assert all(s.count == 361 and s.units == p.UNITS_CM for s in scans)
        assert all(r is None or 0.05 < r <= 8.0 for r in scans[0].ranges())
        host.send(p.lms_telegram(0x20, b"\x25"))
        host.read_until(until_lms(0xA0))
        host.read_until(lambda d: False, timeout=0.3)
        assert host.read_until(lambda d: False, timeout=0.6) == b""      # stream stopped
        host.send(p.lms_telegram(0x55))                                  # unknown request
        data = host.read_until(until_lms(0x92))
        assert data[0] == p.LMS_ACK and p.lms_unframe(data[1:])[1] == 0x92
    finally:
        host.close()
        log = fake.stop()
    summary = [e for e in log if e["ev"] == "summary"][0]
    assert summary["naks"] == 1 and summary["baud"] == 38400 and summary["not_accepted"] == 1
    assert summary["garbled_frames"] >= 1 and summary["stream_starts"] == 1


def test_the_encoders_the_fakes_use_match_the_reference():
    vectors = {v["name"]: bytes.fromhex(v["hex"]) for v in load_vectors()}
    assert p.encode_sync2_reply("Robot1", "Pioneer", "p3dx-sh") == vectors["aria_sync2_reply_example"]
    _, payload = p.aria_unframe(vectors["aria_hostbaud_38400"])
    assert p.aria_int_value(payload) == 2
    _, payload = p.aria_unframe(vectors["aria_vel2_left-100_right+100"])
    assert p.aria_int_value(payload) == -1275               # word 0xFB05: left -5, right +5
    assert p.aria_int_value(b"") is None and p.aria_int_value(b"\x2b\x01A") is None
    # CONFIGpac: the fields protocols.md 1.12 lists, in order; the C decoder
    # reads it in test_live_active (TicksMM, watchdog, AutoBaud in rsm-nav's report).
    pac = p.encode_config_pac(p.AriaConfig(ticks_mm=0x1234, watchdog=0x0ABC, auto_baud=2))
    ptype, body = p.aria_unframe(pac)
    assert ptype == 0x20 and body.startswith(b"Pioneer\x00p3dx-sh\x00FAKE0001\x00")
    assert body.endswith(b"\x34\x12\x69\x00fake-1.0\x00")     # TicksMM, ShutdownVolts, firmware
    assert b"\xbc\x0a" in body
    block = p.lms_config_block(p.UNITS_MM, 0x03, 0x02)
    assert len(block) == 32 and block[4:7] == b"\x02\x03\x01"
    assert p.LMS_VARIANTS[(180, 50)] == (361, 0) and p.LMS_VARIANTS[(100, 25)] == (401, 4000)


def rplidar_vectors():
    """The documented requests and answers of tests/data/rplidar_frames.txt."""
    out = {}
    path = os.path.join(os.path.dirname(__file__), "..", "data", "rplidar_frames.txt")
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if line.strip() and not line.startswith("#"):
                kind, *hexes = line.split()
                if kind == "samples":
                    continue  # decoded values, not bytes
                out.setdefault(kind, []).append(bytes(int(h, 16) for h in hexes))
    return out


def test_rplidar_answers_requests_and_scans_the_simulated_world(tmp_path):
    """The fake RPLIDAR answers health, info and sample rate laid out as
    the documented vectors, keeps a motor command, ignores a request with a
    bad checksum, streams nodes of the simulated world after SCAN and
    stops at STOP."""
    vec = rplidar_vectors()
    stop, _reset, scan, get_info, get_health = vec["request"][:5]
    pwm_660 = vec["request"][7]
    fake = FakeDevices(tmp_path, "--rplidar", "--quiet", "--patient")
    host = Host(fake.paths["rplidar"], 115200)
    try:
        host.send(get_health)
        assert host.read_until(lambda d: len(d) >= 10) == vec["health"][0][:7] + b"\x00\x00\x00"
        host.send(get_info)
        info = host.read_until(lambda d: len(d) >= 27)
        assert len(info) == 27 and info[:11] == vec["info"][0][:11]   # model 0x18, firmware 1.29, hw 7
        host.send(b"\xa5\x59")                                         # GET_SAMPLERATE
        rate = host.read_until(lambda d: len(d) >= 11)
        assert rate[:7] == bytes.fromhex("a55a0400000015")
        assert struct.unpack("<HH", rate[7:]) == (556, 556)            # 360 nodes a turn at 5 Hz
        host.send(pwm_660[:-1] + bytes([pwm_660[-1] ^ 0xFF]))           # bad checksum: ignored
        host.send(pwm_660)
        host.send(scan)
        data = host.read_until(lambda d: len(d) >= 7 + 5 * 400)
        assert data[:7] == vec["nodes"][0][:7]                         # the standard-scan descriptor
        host.send(stop)
        host.read_until(lambda d: False, timeout=0.3)
        assert host.read_until(lambda d: False, timeout=0.5) == b""    # stopped
    finally:
        host.close()
        log = fake.stop()
    nodes = [data[k:k + 5] for k in range(7, len(data) - 4, 5)]
    body = fakedev.Body()  # the robot stands where the world's path starts
    for k, node in enumerate(nodes[:400]):
        start, not_start = node[0] & 1, (node[0] >> 1) & 1
        angle_q6 = struct.unpack_from("<H", node, 1)[0]
        assert start != not_start and angle_q6 & 1 == 1
        angle = (angle_q6 >> 1) / 64.0
        assert angle == k % 360 and start == (k % 360 == 0)
        r = sim.raycast(body.x, body.y, body.th - math.radians(angle), body.segs, body.circles,
                        fakedev.MAX_RANGE_M)
        want = round(r * 1000.0) if r < fakedev.MAX_RANGE_M else 0
        assert struct.unpack_from("<H", node, 3)[0] == 4 * want
        assert (node[0] >> 2) == (lidarstream.RPLIDAR_QUALITY if want else 0)
    summary = [e for e in log if e["ev"] == "summary" and e["dev"] == "rplidar"][0]
    assert summary["bad_requests"] == 1 and summary["motor"] == 660
    assert summary["scans_started"] == 1 and summary["stops"] == 1 and not summary["scanning"]
    assert [e["cmd"] for e in log if e["ev"] == "request"] == [0x52, 0x50, 0x59, 0xF0, 0x20, 0x25]


def test_a_patient_port_keeps_every_byte_for_a_host_that_stalls():
    """--patient: a host that stops reading for longer than the 0.2 s a
    device waits loses nothing (without it the rest of the frame goes, so a
    loaded machine changed what a test's host got)."""
    import threading

    port = fakedev.PtyPort("t", patient=True)
    got = bytearray()
    frame = bytes(range(256)) * 256  # 64 KiB: many times a pty's buffer

    def host():
        time.sleep(0.5)  # stalled
        while len(got) < len(frame):
            got.extend(os.read(port.slave, 65536))

    reader = threading.Thread(target=host)
    reader.start()
    try:
        port.write(frame, port.host_baud())
    finally:
        reader.join(timeout=60)
        port.close()
    assert bytes(got) == frame and port.overflows == 0


def test_drop_specs_cut_on_a_count_and_mend_on_a_signal():
    """--robot-drop/--lms-drop AFTER:FOR: seconds as before, or AFTER Nf (a
    count of frames sent) and FOR signal (until the device's signal)."""
    timed = fakedev.Cut(fakedev.parse_drop("2:3"))
    timed.sent(1000, 0.0)                      # frames do not start a timed cut
    assert timed.start is None
    timed.arm(10.0)
    assert not timed.active(11.9) and timed.active(12.0) and timed.active(14.9) and not timed.active(15.0)
    assert not timed.release(13.0) and timed.active(13.0)   # the signal ends only a cut held for it

    held = fakedev.Cut(fakedev.parse_drop("20f:signal"))
    held.arm(0.0)                              # nor does the clock start a counted one
    held.sent(19, 5.0)
    assert held.start is None and not held.active(5.0)
    held.sent(20, 6.0)
    assert held.active(6.0) and held.active(1e6)
    assert held.release(7.0) and not held.active(7.0) and not held.release(8.0)

    counted = fakedev.Cut(fakedev.parse_drop("5f:1.5"))
    counted.sent(5, 2.0)
    assert counted.active(3.4) and not counted.active(3.5)
    for bad in ("2", "x:1", "2:0", "-1:2", "0f:1", "-3f:1", "2f:forever", "2:3:4"):
        with pytest.raises(argparse.ArgumentTypeError):
            fakedev.parse_drop(bad)
