"""rsm-fakedev: a fake Pioneer P3-DX, SICK LMS 2xx, LDRobot LD06 and Slamtec RPLIDAR on pseudo-terminals.

    rsm-fakedev [--robot] [--lms] [--ld06] [--rplidar] [--capture CAP] [--log FILE] [--seconds S]
                [--robot-drop AFTER:FOR] [--lms-drop AFTER:FOR]
                [--watchdog-ms MS] [--ticks-mm N] [--no-autobaud] [--units mm|cm]
                [--patient] [--quiet]

Creates one pseudo-terminal per device (the robot and the LMS when none of
``--robot``, ``--lms``, ``--ld06``, ``--rplidar`` is given) and prints one
``robot PATH`` / ``laser PATH`` / ``ld06 PATH`` / ``rplidar PATH`` line per
device on stdout, flushed, before anything else happens, so that another
program (``rsm-nav --robot PATH --lms PATH``, a test) can open them.  The
devices then answer like the real ones (protocols.md):

* P3-DX (ARCOS): SYNC0/SYNC1/SYNC2 echo handshake (the SYNC2 reply names
  the robot, class ``Pioneer``, subclass ``p3dx-sh``); on OPEN a standard SIP
  every 100 ms, followed by an ENCODER packet once ENCODER > 0 was asked
  for; CONFIG is answered with a CONFIGpac (AutoBaud 2 unless
  ``--no-autobaud``); HOSTBAUD moves the robot to the new rate; ENABLE,
  VEL, RVEL, ROTATE, VEL2, STOP, ESTOP drive it (motors only move while
  enabled); PULSE and every other valid command feed the watchdog: with no
  command for the watchdog time the robot stops, and moves again when
  commands come back; CLOSE ends the session.  Packets with a bad checksum
  are ignored, as ARCOS does.
* LMS 2xx: starts at 9600 Bd, not streaming, variant 180 deg / 0.5 deg.  Every
  request telegram is answered with ACK (0x06) then its reply, or with NAK
  (0x15) when its CRC is wrong.  0x20 changes the mode (0x24 continuous
  0xB0 output, 0x25 on request, 0x40/0x41/0x42 the rate: the 0xA0 reply
  goes out at the old rate, then the unit switches; 0x00 installation mode
  with the password); 0x3B sets the variant (0xBB); 0x74 reads the
  configuration block (0xF4: measuring mode 0x00, units as ``--units``);
  0x77 writes it (installation mode only); 0x31 status (0xB1), 0x3A type
  (0xBA), 0x30 one scan, 0x10 reset (0x91, later 0x90 at 9600 Bd).  Others
  get 0x92.  While streaming, one 0xB0 telegram goes out as soon as the
  previous one has left at the current rate (a 181-value scan about every
  96 ms at 38400 Bd, 385 ms at 9600).

Data: without ``--capture`` the robot drives as commanded in the ``rooms``
world of rsm-sim (wheel base 357 mm) and the laser ray-casts that world
from the robot's pose.  With ``--capture`` the devices play a capture's
ENCODER packets and 0xB0 telegrams (byte for byte; encoder counts scaled as
below) instead: scans in capture order, one per slot as above, and with every SIP
the encoder counts of the last ENCODER packet recorded before the next
scan to be sent (with no laser, the capture's own timing).  At the end of
the capture the last counts and the last scan are repeated.

Encoders: the robot counts ``--ticks-mm`` ticks per mm of travel, the
TicksMM its CONFIGpac reports (default 128): the simulated wheels, and a
capture's counts (recorded at 128 ticks per mm), are scaled by TicksMM/128
and rounded to the nearest tick, so a host that ignored the CONFIGpac would
see the wrong distances.

Rates: a pseudo-terminal carries bytes at any rate, but both ends can see
the rate the host set on it.  Each device keeps its own protocol rate and
garbles every byte it sends while the host's port is at another rate (so a
host that did not follow a rate change hears only noise); bytes from the
host are taken as sent at the right rate (a pseudo-terminal cannot tell
when the host changed its rate).

LD06 (``--ld06``, only when asked for; ``--robot --ld06`` is a cheap-lidar
robot): listens to nothing and sends, at 230400 Bd, one 47-byte packet of 12
points every 1/300 s: a head turning clockwise at 10 Hz, one point every
whole degree (rsm_tools.lidarstream), ray-cast in the ``rooms`` world from the
robot's pose at the time of each packet, so a robot the host drives turns
and moves under the turning head.  With ``--capture`` of an
``rsm-convert --lidar ld06`` capture it plays the capture's lidar records
instead, byte for byte, at their own times after the first, then stops
sending (the host sees the link go quiet).

RPLIDAR (``--rplidar``, only when asked for; ``--robot --rplidar`` is a
cheap-lidar robot): an A1-like unit at 115200 Bd that answers the requests
of docs/reference/lidars.md section 2: GET_HEALTH (good), GET_INFO (model
0x18, firmware 1.29, hardware 7), GET_SAMPLERATE (one node's time, for both
modes), SCAN and FORCE_SCAN (the standard-scan descriptor, then nodes until
STOP), RESET (a boot text; scanning stops), SET_MOTOR_PWM and
MOTOR_SPEED_CTRL (kept; the head turns whatever they say, as an A1's on
its adapter does); requests with a bad checksum and the express scans get
no answer.  The nodes: a head turning clockwise at 5 Hz, one node every
whole degree, 12 nodes every 1/150 s (9000 bytes a second, which 115200 Bd
carries), ray-cast in the ``rooms`` world as for the LD06; with
``--capture`` of an ``rsm-convert --lidar rplidar`` capture, the capture's
node records at their own times on the robot's clock (its session's start
is the capture's start; without a robot, the scan's start is), records
the head measured while nobody scanned being skipped.

Faults: ``--robot-drop AFTER:FOR`` cuts the robot's line FOR seconds,
AFTER seconds after its first session opened (nothing is received or sent;
the robot itself carries on, so its watchdog stops it and its session
stays open); ``--lms-drop`` likewise, counted from its first stream start.
AFTER may instead be a count of data frames, ``Nf``: the line goes once
the device has sent N (SIPs for the robot, 0xB0 scans for the laser); and
FOR may be ``signal``: the line stays cut until SIGUSR1 (the robot's) or
SIGUSR2 (the laser's) comes.  A test then cuts and mends the line on
events (what the host said, what the fake logged), not on the clock.

Load: a device whose host stops reading for 0.2 s drops the rest of the
frame it was sending (as a UART's receive buffer overruns).  With
``--patient`` it waits for the host however long, so that what a host
gets is the same on a loaded machine (a test's verdict then does not
depend on the load); SIGINT and SIGTERM still end the run.

``--log FILE`` writes one JSON object per line for everything the devices
do (handshake steps, commands with their argument and the host's rate at
that moment, rate changes, watchdog stops, requests, ACK/NAK, stream
starts and stops, cuts), and a ``summary`` object per device at exit.
SIGINT or SIGTERM (or ``--seconds``) ends the run, after the bytes the host
had already written are handled; exit status 0, 1 for an unreadable
capture, 2 for bad arguments (the C tools' convention).
"""

import argparse
import json
import math
import os
import select
import signal
import struct
import sys
import termios
import time
import tty
from typing import Dict, List, Optional, Sequence, Tuple

from . import capture as cap
from . import lidarstream
from . import protocols as proto
from . import sim

TICKS_PER_MM = 128.0
WHEEL_BASE_MM = 357.0
VEL2_DIVISOR = 20.0              # mm/s per VEL2 unit (p3dx-sh)
MAX_RANGE_M = 8.0
LMS_TYPE = b"LMS200;301063;V02.10 "
MIRROR_PERIOD_S = 1.0 / 75.0     # the LMS mirror turns at 75 Hz


def _rate_codes() -> Dict[int, int]:
    out = {}
    for rate in (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 500000):
        code = getattr(termios, f"B{rate}", None)
        if code is not None:
            out[code] = rate
    return out


RATE_OF_CODE = _rate_codes()


def garble(data: bytes) -> bytes:
    """What the far end hears at the wrong rate: bytes 0xE0..0xEF, never a
    header, STX, ACK or NAK (the same mangling as the C tests' fake link)."""
    return bytes(0xE0 | (b & 0x0F) for b in data)


class Log:
    """JSON lines, flushed one by one (a test may read them while we run)."""

    def __init__(self, path: Optional[str]) -> None:
        self.t0 = time.monotonic()
        self.fh = open(path, "w", encoding="utf-8") if path else None

    def __call__(self, dev: str, ev: str, **fields) -> None:
        if self.fh is None:
            return
        rec = {"t": round(time.monotonic() - self.t0, 4), "dev": dev, "ev": ev}
        rec.update(fields)
        self.fh.write(json.dumps(rec) + "\n")
        self.fh.flush()

    def close(self) -> None:
        if self.fh is not None:
            self.fh.close()
            self.fh = None


class PtyPort:
    """The device end of a pseudo-terminal; the slave stays open here too, so
    the host may open and close it at will without hang-ups."""

    def __init__(self, name: str, patient: bool = False) -> None:
        self.name = name
        self.patient = patient  # never drop a frame for a host that stopped reading
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self.slave)
        self.garbled = 0        # frames sent while the host's rate differed
        self.overflows = 0      # frames (partly) dropped because nobody read them

    def host_baud(self) -> int:
        """The rate the host has set on its end (0 if unknown)."""
        try:
            return RATE_OF_CODE.get(termios.tcgetattr(self.master)[5], 0)
        except termios.error:
            return 0

    def read(self) -> bytes:
        try:
            return os.read(self.master, 4096)
        except (BlockingIOError, InterruptedError):
            return b""
        except OSError:
            return b""   # EIO while nobody has the slave open: nothing to read

    def write(self, frame: bytes, baud: int) -> None:
        if self.host_baud() != baud:
            frame = garble(frame)
            self.garbled += 1
        view = memoryview(frame)
        deadline = time.monotonic() + 0.2
        while view:
            try:
                n = os.write(self.master, view)
                view = view[n:]
            except (BlockingIOError, InterruptedError):
                if not self.patient and time.monotonic() >= deadline:
                    self.overflows += 1   # the host stopped reading: drop the rest
                    return
                check_stop()              # a patient wait still ends at a signal
                select.select([], [self.master], [], 0.02)

    def close(self) -> None:
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass


class DropSpec:
    """``--robot-drop``/``--lms-drop AFTER:FOR``: AFTER seconds, or ``Nf``
    (once the device has sent N data frames); FOR seconds, or ``signal``
    (until the device's signal)."""

    def __init__(self, after: float, frames: Optional[int], dur: Optional[float]) -> None:
        self.after = after          # seconds (frames is None)
        self.frames = frames        # data frames sent, or None
        self.dur = dur              # seconds, or None: until the signal


class Cut:
    """A window during which a device's line is cut.  A cut that begins on
    a frame count or ends on a signal follows events, not the clock, so a
    test's verdict does not depend on how fast the host and the fake run."""

    def __init__(self, spec: Optional[DropSpec]) -> None:
        self.spec = spec
        self.start: Optional[float] = None
        self.end = math.inf
        self.state = False

    def arm(self, now: float) -> None:
        """The device's first session or stream: a cut in seconds counts from here."""
        if self.spec is not None and self.spec.frames is None and self.start is None:
            self.begin(now + self.spec.after)

    def sent(self, frames: int, now: float) -> None:
        """The device has sent this many data frames so far."""
        if self.spec is not None and self.spec.frames is not None and self.start is None \
                and frames >= self.spec.frames:
            self.begin(now)

    def begin(self, at: float) -> None:
        self.start = at
        if self.spec is not None and self.spec.dur is not None:
            self.end = at + self.spec.dur

    def release(self, now: float) -> bool:
        """The signal: a cut held until it ends now. False if none was on."""
        if self.spec is None or self.spec.dur is not None or not self.active(now):
            return False
        self.end = now
        return True

    def active(self, now: float) -> bool:
        return self.start is not None and self.start <= now < self.end


def scale_counts(counts: Tuple[int, int], ticks_mm: int) -> Tuple[int, int]:
    """Encoder counts at TICKS_PER_MM as a robot with ticks_mm ticks per mm
    counts them (nearest tick, halves away from zero)."""
    def one(c: int) -> int:
        scaled = abs(c) * ticks_mm
        q, r = divmod(scaled, int(TICKS_PER_MM))
        q += 1 if 2 * r >= TICKS_PER_MM else 0
        return q if c >= 0 else -q
    return one(counts[0]), one(counts[1])


class Body:
    """The simulated robot: pose (m, rad) in the rsm-sim ``rooms`` world and
    its wheel encoder counts (fractional ticks kept)."""

    def __init__(self) -> None:
        self.segs, self.circles, path = sim.world("rooms")
        self.x, self.y = path[0]
        self.th = math.atan2(path[1][1] - self.y, path[1][0] - self.x)
        self.left = 0.0
        self.right = 0.0

    def move(self, vl_mm_s: float, vr_mm_s: float, dt: float) -> None:
        dl = vl_mm_s * dt
        dr = vr_mm_s * dt
        ds = 0.5 * (dl + dr) / 1000.0
        dth = (dr - dl) / WHEEL_BASE_MM
        self.x += ds * math.cos(self.th + 0.5 * dth)
        self.y += ds * math.sin(self.th + 0.5 * dth)
        self.th = math.atan2(math.sin(self.th + dth), math.cos(self.th + dth))
        self.left += dl * TICKS_PER_MM
        self.right += dr * TICKS_PER_MM


class Playback:
    """A capture's ENCODER packets and 0xB0 telegrams, in order."""

    def __init__(self, path: str) -> None:
        header, records, _ = cap.read_capture(path)
        robot = next((c.id for c in header.channels if c.protocol == "aria"), None)
        laser = next((c.id for c in header.channels if c.protocol == "lms2xx"), None)
        lidar = next((c.id for c in header.channels if c.name == "lidar"), None)
        self.lidar: List[Tuple[int, bytes]] = [(r.timestamp, r.data) for r in records
                                               if r.channel == lidar and r.direction == cap.RX]
        self.lidar_model = header.metadata.get("laser.model", "")
        try:
            self.turn_hz = float(header.metadata.get("laser.turn_hz", "0"))
        except ValueError:
            self.turn_hz = 0.0
        aria = proto.FrameCounter("aria")
        lms = proto.FrameCounter("lms2xx")
        aria.keep = lms.keep = True
        self.encoders: List[Tuple[int, int, int]] = []    # (time us, left, right)
        self.scans: List[Tuple[int, bytes]] = []          # (time us, telegram)
        for r in records:
            if r.direction != cap.RX:
                continue
            if r.channel == robot:
                aria.feed(r.data)
                for f in aria.take():
                    if f[3] == proto.ARIA_ENCODER:
                        left, right = proto.decode_encoder(f)
                        self.encoders.append((r.timestamp, left, right))
            elif r.channel == laser:
                lms.feed(r.data)
                for f in lms.take():
                    if f[4] == 0xB0:
                        self.scans.append((r.timestamp, f))
        if not self.encoders and not self.scans and not self.lidar:
            raise cap.CaptureError("no ENCODER packets, 0xB0 telegrams or lidar records in the capture")
        stamps = [t for t, _, _ in self.encoders] + [t for t, _ in self.scans] + [t for t, _ in self.lidar[:1]]
        self.t_first = min(stamps)
        self.next_scan = 0          # index of the next scan to send
        self.enc_idx = 0
        self.ended_logged = False
        units = header.metadata.get("laser.units", "mm")
        self.units = proto.UNITS_CM if units == "cm" else proto.UNITS_MM

    def take_scan(self) -> Tuple[bytes, bool]:
        """The next scan (the last one again once the capture is over) and
        whether the capture is over."""
        if not self.scans:
            return b"", True
        if self.next_scan < len(self.scans):
            frame = self.scans[self.next_scan][1]
            self.next_scan += 1
            return frame, False
        return self.scans[-1][1], True

    def counts_until(self, t_us: int) -> Optional[Tuple[int, int]]:
        """Counts of the last ENCODER packet recorded at or before t_us."""
        while self.enc_idx + 1 < len(self.encoders) and self.encoders[self.enc_idx + 1][0] <= t_us:
            self.enc_idx += 1
        if not self.encoders or self.encoders[self.enc_idx][0] > t_us:
            return None
        _, left, right = self.encoders[self.enc_idx]
        return left, right

    def next_scan_time(self) -> int:
        """Capture time of the scan to be sent next (the end once all are sent)."""
        if self.next_scan < len(self.scans):
            return self.scans[self.next_scan][0]
        return max([t for t, _, _ in self.encoders[-1:]] + [t for t, _ in self.scans[-1:]])


class Device:
    """What the main loop needs of a fake device."""

    dev = ""

    def __init__(self, port: PtyPort, log: Log, body: Body, playback: Optional[Playback],
                 cut: Cut, protocol: str) -> None:
        self.port = port
        self.log = log
        self.body = body
        self.playback = playback
        self.cut = cut
        self.baud = 9600          # the protocol rate; both devices power up at 9600
        self.fc = proto.FrameCounter(protocol)
        self.fc.keep = True
        self.n: Dict[str, int] = {"dropped_rx_bytes": 0}

    def send(self, frame: bytes, now: float) -> bool:
        """Sends frame at the device's rate; False while the line is cut."""
        if self.cut.active(now):
            return False
        self.port.write(frame, self.baud)
        return True

    def receive(self, data: bytes, now: float) -> None:
        """Bytes from the host: framed, checked, handled (dropped while cut)."""
        if self.cut.active(now):
            self.n["dropped_rx_bytes"] += len(data)
            return
        bad = self.fc.bad
        self.fc.feed(data)
        if self.fc.bad != bad:
            self.on_bad(self.fc.bad - bad, now)
        for frame in self.fc.take():
            self.on_frame(frame, now)

    def on_bad(self, count: int, now: float) -> None:
        """count frames failed their checksum or CRC."""
        raise NotImplementedError

    def capture_over(self, over: bool, **fields) -> None:
        """A lidar playing a capture: logs its end once (``ended`` counter)."""
        if over and not self.n.get("ended"):
            self.n["ended"] = 1
            self.log(self.dev, "capture_end", **fields)

    def on_frame(self, frame: bytes, now: float) -> None:
        """A frame from the host whose checksum or CRC verified."""
        raise NotImplementedError

    def tick(self, now: float) -> None:
        raise NotImplementedError

    def due(self) -> float:
        """When tick next has something to do."""
        raise NotImplementedError

    def state(self) -> Dict[str, object]:
        """The device's state for its summary line."""
        raise NotImplementedError

    def summary(self) -> Dict[str, object]:
        out: Dict[str, object] = dict(self.n)
        out.update(baud=self.baud, garbled_frames=self.port.garbled, overflows=self.port.overflows)
        out.update(self.state())
        return out

    def progress(self) -> Dict[str, int]:
        """What a cut_start/cut_end log line says about the data sent so far."""
        raise NotImplementedError


class FakeRobot(Device):
    """ARCOS on a P3-DX, as far as the host protocol shows."""

    dev = "robot"

    def __init__(self, port: PtyPort, log: Log, body: Body, playback: Optional[Playback],
                 args: argparse.Namespace) -> None:
        super().__init__(port, log, body, playback, Cut(args.robot_drop), "aria")
        self.laser: Optional["FakeLaser"] = None
        self.config = proto.AriaConfig(watchdog=args.watchdog_ms, ticks_mm=args.ticks_mm,
                                       auto_baud=0 if args.no_autobaud else 2)
        self.watchdog_s = args.watchdog_ms / 1000.0
        self.cycle_s = self.config.sip_cycle / 1000.0
        self.stage = 0
        self.session = False
        self.enabled = False
        self.encoder_on = False
        self.motion = ("vel", 0.0, 0.0)        # ("vel", mm/s, deg/s) or ("wheels", mm/s, mm/s)
        self.tripped = False
        now = time.monotonic()
        self.last_cmd = now
        self.last_tick = now
        self.next_sip = now
        self.t_open: Optional[float] = None
        self.n.update(sips=0, encoders=0, pulses=0, commands=0, sessions=0, closes=0,
                      watchdog_stops=0, bad_checksums=0)

    # -- wire ---------------------------------------------------------------------
    def on_bad(self, count: int, now: float) -> None:
        self.n["bad_checksums"] += count       # ignored, as ARCOS does

    def on_frame(self, frame: bytes, now: float) -> None:
        ptype, payload = proto.aria_unframe(frame)
        self.handle(ptype, payload, now)

    # -- commands -------------------------------------------------------------------
    def handle(self, cmd: int, payload: bytes, now: float) -> None:
        arg = proto.aria_int_value(payload)
        if not self.session and cmd <= 2:
            name = f"SYNC{cmd}" if not (cmd == 1 and self.stage == 3) else "OPEN"
        else:
            name = proto.ARIA_COMMAND_NAMES.get(cmd, f"CMD{cmd}")
        self.log(self.dev, "command", cmd=cmd, name=name, arg=arg, session=self.session,
                 host_baud=self.port.host_baud(), baud=self.baud)
        if not self.session:
            self.handshake(cmd, now)
            return
        self.n["commands"] += 1
        self.last_cmd = now
        if self.tripped:
            self.tripped = False
            self.log(self.dev, "watchdog_resume")
        if cmd == proto.CMD_PULSE:
            self.n["pulses"] += 1
        elif cmd == proto.CMD_CLOSE:
            self.close_session(now)
        elif cmd == proto.CMD_ENABLE:
            self.enabled = bool(arg)
            self.log(self.dev, "motors", enabled=self.enabled)
        elif cmd == proto.CMD_CONFIG:
            self.config.host_baud = proto.ARIA_BAUD_RATES.index(self.baud)
            self.send(proto.encode_config_pac(self.config), now)
        elif cmd == proto.CMD_ENCODER:
            self.encoder_on = bool(arg and arg > 0)
        elif cmd == proto.CMD_VEL:
            self.motion = ("vel", float(arg or 0), self.motion[2] if self.motion[0] == "vel" else 0.0)
        elif cmd in (proto.CMD_RVEL, proto.CMD_ROTATE):
            self.motion = ("vel", self.motion[1] if self.motion[0] == "vel" else 0.0, float(arg or 0))
        elif cmd == proto.CMD_VEL2:
            word = (arg or 0) & 0xFFFF
            left = struct.unpack("b", bytes([word >> 8]))[0]
            right = struct.unpack("b", bytes([word & 0xFF]))[0]
            self.motion = ("wheels", left * VEL2_DIVISOR, right * VEL2_DIVISOR)
        elif cmd in (proto.CMD_STOP, proto.CMD_ESTOP):
            self.motion = ("vel", 0.0, 0.0)
        elif cmd == proto.CMD_SETO:
            self.body.x = self.body.y = self.body.th = 0.0
        elif cmd == proto.CMD_HOSTBAUD:
            if arg is not None and 0 <= arg < len(proto.ARIA_BAUD_RATES):
                old, self.baud = self.baud, proto.ARIA_BAUD_RATES[arg]
                self.log(self.dev, "baud", old=old, new=self.baud, sips=self.n["sips"])

    def handshake(self, cmd: int, now: float) -> None:
        if cmd == 0:
            self.send(proto.aria_packet(proto.ARIA_SYNC0), now)
            self.stage = 1
        elif cmd == 1 and self.stage == 3:
            self.open_session(now)
        elif cmd == self.stage and cmd in (1, 2):
            if cmd == 1:
                self.send(proto.aria_packet(proto.ARIA_SYNC1), now)
            else:
                self.send(proto.encode_sync2_reply(self.config.name, self.config.robot_type,
                                                   self.config.subtype), now)
            self.stage += 1
        else:
            self.stage = 0
        if not self.session:
            self.log(self.dev, "sync", stage=self.stage)

    def open_session(self, now: float) -> None:
        self.session = True
        self.enabled = False
        self.encoder_on = False
        self.motion = ("vel", 0.0, 0.0)
        self.tripped = False
        self.last_cmd = now
        self.next_sip = now + self.cycle_s
        self.n["sessions"] += 1
        if self.t_open is None:
            self.t_open = now
            self.cut.arm(now)
        self.log(self.dev, "open", baud=self.baud, host_baud=self.port.host_baud())

    def close_session(self, now: float) -> None:
        self.session = False
        self.stage = 0
        self.enabled = False
        self.encoder_on = False
        self.motion = ("vel", 0.0, 0.0)
        self.n["closes"] += 1
        self.log(self.dev, "close", sips=self.n["sips"], encoders=self.n["encoders"])

    # -- time -------------------------------------------------------------------------
    def wheel_speeds(self) -> Tuple[float, float]:
        if not self.session or not self.enabled or self.tripped:
            return 0.0, 0.0
        kind, a, b = self.motion
        if kind == "wheels":
            return a, b
        half = math.radians(b) * WHEEL_BASE_MM / 2.0
        return a - half, a + half

    def counts(self) -> Tuple[int, int]:
        return scale_counts(self.raw_counts(), self.config.ticks_mm)

    def raw_counts(self) -> Tuple[int, int]:
        """Counts at 128 ticks per mm."""
        if self.playback is None:
            return int(math.floor(self.body.left)), int(math.floor(self.body.right))
        if self.laser is not None:
            t = self.playback.next_scan_time()
        else:
            t = self.playback.t_first + int((time.monotonic() - (self.t_open or 0.0)) * 1e6)
        got = self.playback.counts_until(t)
        return got if got is not None else (self.playback.encoders[0][1],
                                            self.playback.encoders[0][2])

    def tick(self, now: float) -> None:
        vl, vr = self.wheel_speeds()
        if self.playback is None:
            self.body.move(vl, vr, now - self.last_tick)
        self.last_tick = now
        if not self.session:
            return
        if not self.tripped and now - self.last_cmd > self.watchdog_s:
            self.tripped = True
            self.n["watchdog_stops"] += 1
            self.log(self.dev, "watchdog_stop", silent_s=round(now - self.last_cmd, 3))
        if now < self.next_sip:
            return
        self.next_sip += self.cycle_s
        if self.next_sip < now:
            self.next_sip = now + self.cycle_s
        vl, vr = self.wheel_speeds()
        b = self.body
        sip = proto.Sip(xpos=int(round(b.x * 1000)), ypos=int(round(b.y * 1000)),
                        thpos=int(round(b.th * 4096 / (2 * math.pi))), lvel=int(vl), rvel=int(vr),
                        flags=0x0001 if self.enabled else 0x0000, moving=vl != 0.0 or vr != 0.0)
        self.n["sips"] += self.send(proto.encode_sip(sip), now)
        if self.encoder_on:
            self.n["encoders"] += self.send(proto.encode_encoder(*self.counts()), now)
        self.cut.sent(self.n["sips"], now)

    def due(self) -> float:
        return self.next_sip if self.session else math.inf

    def progress(self) -> Dict[str, int]:
        return {"encoders": self.n["encoders"], "sips": self.n["sips"]}

    def state(self) -> Dict[str, object]:
        return {"session": self.session, "enabled": self.enabled, "encoder_on": self.encoder_on}


class FakeLaser(Device):
    """A SICK LMS 2xx in its binary telegram protocol."""

    dev = "laser"

    def __init__(self, port: PtyPort, log: Log, body: Body, playback: Optional[Playback],
                 args: argparse.Namespace) -> None:
        super().__init__(port, log, body, playback, Cut(args.lms_drop), "lms2xx")
        self.units = playback.units if playback is not None else args.units
        self.measuring_mode = 0x00
        self.variant = (180, 50)
        self.streaming = False
        self.installation = False
        self.next_scan = math.inf
        self.power_on_at = math.inf
        self.t_stream: Optional[float] = None
        self.n.update(requests=0, acks=0, naks=0, not_accepted=0, scans=0, stream_starts=0)

    # -- wire -------------------------------------------------------------------------
    def reply(self, cmd: int, data: bytes, now: float) -> None:
        self.send(proto.lms_reply(cmd, data), now)

    def on_bad(self, count: int, now: float) -> None:
        for _ in range(count):
            # CRC or format error: NAK, and the request is not carried out.
            self.n["naks"] += 1
            self.log(self.dev, "nak")
            self.send(bytes([proto.LMS_NAK]), now)

    def on_frame(self, frame: bytes, now: float) -> None:
        adr, cmd, body = proto.lms_unframe(frame)
        if not adr & proto.LMS_REPLY_ADDR:     # a reply-shaped telegram is not for us
            self.handle(cmd, body, now)

    # -- requests -----------------------------------------------------------------------
    def handle(self, cmd: int, data: bytes, now: float) -> None:
        self.n["requests"] += 1
        self.log(self.dev, "request", cmd=cmd, data=data.hex(), host_baud=self.port.host_baud(),
                 baud=self.baud)
        self.n["acks"] += 1
        self.send(bytes([proto.LMS_ACK]), now)
        if cmd == proto.LMS_CMD_MODE and data:
            self.mode(data, now)
        elif cmd == proto.LMS_CMD_SET_VARIANT and len(data) == 4:
            angle, res = struct.unpack("<HH", data)
            ok = (angle, res) in proto.LMS_VARIANTS
            if ok:
                self.variant = (angle, res)
            self.log(self.dev, "variant", angle=angle, resolution=res, accepted=ok)
            self.reply(0xBB, bytes([1 if ok else 0]) + struct.pack("<HH", *self.variant), now)
        elif cmd == proto.LMS_CMD_GET_CONFIG and not data:
            self.log(self.dev, "config_read")
            self.reply(0xF4, self.config_block(), now)
        elif cmd == proto.LMS_CMD_SET_CONFIG and len(data) == proto.LMS_CONFIG_BLOCK_LEN:
            if not self.installation:
                self.not_accepted(now)
                return
            self.measuring_mode = data[5]
            self.units = proto.UNITS_MM if data[6] == 1 else proto.UNITS_CM
            self.log(self.dev, "config_write", measuring_mode=data[5], units=self.units)
            self.reply(0xF7, bytes([1]) + self.config_block(), now)
        elif cmd == proto.LMS_CMD_GET_STATUS and not data:
            self.reply(0xB1, self.status_block(), now)
        elif cmd == proto.LMS_CMD_GET_TYPE and not data:
            self.reply(0xBA, LMS_TYPE, now)
        elif cmd == proto.LMS_CMD_GET_VALUES and data == b"\x01":
            self.send(self.scan_frame(now), now)
        elif cmd == proto.LMS_CMD_RESET and not data:
            self.reply(proto.LMS_REPLY_RESET, b"", now)
            self.reset(now)
        else:
            self.not_accepted(now)

    def not_accepted(self, now: float) -> None:
        self.n["not_accepted"] += 1
        self.reply(proto.LMS_REPLY_NOT_ACK, b"", now)

    def mode(self, data: bytes, now: float) -> None:
        mode = data[0]
        if mode in proto.LMS_MODE_BAUD and len(data) == 1:
            new = proto.LMS_MODE_BAUD[mode]
            if new == 500000:        # RS-422 only; this is RS-232
                self.reply(0xA0, b"\x02", now)
                return
            self.reply(0xA0, b"\x00", now)   # at the old rate, then the switch
            old, self.baud = self.baud, new
            self.log(self.dev, "baud", old=old, new=new)
        elif mode == proto.LMS_MODE_CONTINUOUS and len(data) == 1:
            self.reply(0xA0, b"\x00", now)
            self.start_stream(now)
        elif mode == proto.LMS_MODE_ON_REQUEST and len(data) == 1:
            self.reply(0xA0, b"\x00", now)
            if self.streaming:
                self.streaming = False
                self.next_scan = math.inf
                self.log(self.dev, "stream_stop", scans=self.n["scans"])
        elif mode == proto.LMS_MODE_INSTALLATION and len(data) == 9:
            ok = data[1:] == b"SICK_LMS"
            self.installation = ok
            self.reply(0xA0, b"\x00" if ok else b"\x01", now)
        else:
            self.not_accepted(now)

    def start_stream(self, now: float) -> None:
        if self.streaming:
            return
        self.streaming = True
        self.next_scan = now
        self.n["stream_starts"] += 1
        if self.t_stream is None:
            self.t_stream = now
            self.cut.arm(now)
        self.log(self.dev, "stream_start", baud=self.baud, host_baud=self.port.host_baud(),
                 scans=self.n["scans"])

    def reset(self, now: float) -> None:
        self.streaming = False
        self.next_scan = math.inf
        self.installation = False
        self.variant = (180, 50)
        if self.baud != 9600:
            self.log(self.dev, "baud", old=self.baud, new=9600)
        self.baud = 9600
        self.power_on_at = now + 1.0
        self.log(self.dev, "reset")

    def config_block(self) -> bytes:
        return proto.lms_config_block(self.units, self.measuring_mode)

    def status_block(self) -> bytes:
        b = bytearray(152)
        b[0:7] = b"V02.10 "
        b[7] = proto.LMS_MODE_CONTINUOUS if self.streaming else proto.LMS_MODE_ON_REQUEST
        b[101] = self.measuring_mode
        struct.pack_into("<HH", b, 106, *self.variant)
        struct.pack_into("<H", b, 115, {9600: 0x8067, 19200: 0x8033, 38400: 0x8019}.get(self.baud, 0))
        b[121] = 1 if self.units == proto.UNITS_MM else 0
        return bytes(b)

    # -- scans ---------------------------------------------------------------------------
    def scan_frame(self, now: float) -> bytes:
        if self.playback is not None:
            frame, over = self.playback.take_scan()
            if over and not self.playback.ended_logged:
                self.playback.ended_logged = True
                self.log(self.dev, "capture_end")
            return frame
        count, start_cdeg = proto.LMS_VARIANTS[self.variant]
        step = self.variant[1]
        b = self.body
        ranges = []
        for i in range(count):
            bearing = math.radians((start_cdeg + i * step) / 100.0 - 90.0)
            ranges.append(sim.raycast(b.x, b.y, b.th + bearing, b.segs, b.circles, MAX_RANGE_M + 1.0))
        return proto.encode_b0_ranges(ranges, self.units, MAX_RANGE_M)

    def tick(self, now: float) -> None:
        if now >= self.power_on_at:
            self.power_on_at = math.inf
            self.reply(proto.LMS_REPLY_POWER_ON, LMS_TYPE, now)
        if not self.streaming or now < self.next_scan:
            return
        frame = self.scan_frame(now)
        if frame:
            self.n["scans"] += self.send(frame, now)
            self.cut.sent(self.n["scans"], now)
        # The next one as soon as this one has left at the current rate.
        self.next_scan = now + max(MIRROR_PERIOD_S, len(frame) * 10.0 / self.baud)

    def due(self) -> float:
        return min(self.next_scan, self.power_on_at)

    def progress(self) -> Dict[str, int]:
        return {"scans": self.n["scans"]}

    def state(self) -> Dict[str, object]:
        return {"streaming": self.streaming, "variant": list(self.variant), "units": self.units}


class FakeLD06(Device):
    """An LDRobot LD06: no commands, a packet every 1/300 s (see the module
    notes)."""

    dev = "ld06"
    PACKET_S = 1.0 / 300.0   # 12 points at 3600 points per second

    def __init__(self, port: PtyPort, log: Log, body: Body, playback: Optional[Playback],
                 args: argparse.Namespace) -> None:
        super().__init__(port, log, body, playback, Cut(None), "aria")
        self.baud = lidarstream.BAUD["ld06"]
        self.t0 = time.monotonic()
        self.next_due = self.t0
        self.angle = 0           # sensor angle of the next point, whole degrees
        self.record = 0          # next capture record
        self.n.update(packets=0, ended=0)
        if playback is not None and playback.lidar and playback.lidar_model != "ld06":
            raise cap.CaptureError(f"the capture's lidar is {playback.lidar_model!r}, not ld06")

    def receive(self, data: bytes, now: float) -> None:
        self.n["dropped_rx_bytes"] += len(data)  # the LD06 takes no commands

    def _rendered(self, now: float) -> bytes:
        b = self.body
        pts = []
        for j in range(lidarstream.LD06_POINTS):
            a = math.radians(self.angle + j)
            r = sim.raycast(b.x, b.y, b.th - a, b.segs, b.circles, MAX_RANGE_M)
            mm = int(round(r * 1000.0)) if r < MAX_RANGE_M else 0
            pts.append((mm, 200 if mm else 0))
        first = self.angle
        self.angle = (self.angle + lidarstream.LD06_POINTS) % lidarstream.POINTS_PER_TURN
        return lidarstream.ld06_packet(3600, first * 100, (first + lidarstream.LD06_POINTS - 1) * 100,
                                       int((now - self.t0) * 1000.0), pts)

    def tick(self, now: float) -> None:
        pb = self.playback
        if pb is not None and pb.lidar:
            while self.record < len(pb.lidar) and \
                    self.t0 + (pb.lidar[self.record][0] - pb.lidar[0][0]) / 1e6 <= now:
                if self.send(pb.lidar[self.record][1], now):
                    self.n["packets"] += 1
                self.record += 1
            self.capture_over(self.record == len(pb.lidar), packets=self.n["packets"])
            return
        while self.next_due <= now:
            if self.send(self._rendered(self.next_due), now):
                self.n["packets"] += 1
            self.next_due += self.PACKET_S

    def due(self) -> float:
        pb = self.playback
        if pb is not None and pb.lidar:
            if self.record >= len(pb.lidar):
                return math.inf
            return self.t0 + (pb.lidar[self.record][0] - pb.lidar[0][0]) / 1e6
        return self.next_due

    def progress(self) -> Dict[str, int]:
        return {"packets": self.n["packets"]}

    def state(self) -> Dict[str, object]:
        return {"angle": self.angle, "record": self.record}


class FakeRPLIDAR(Device):
    """A Slamtec RPLIDAR (A1-like) that answers the requests of
    docs/reference/lidars.md section 2 (see the module notes)."""

    dev = "rplidar"
    TURN_HZ = 5.0            # the sim world's head: 360 nodes a turn, 9000 bytes/s
    CHUNK = 12               # nodes sent together
    MODEL, FW_MINOR, FW_MAJOR, HARDWARE = 0x18, 29, 1, 7
    SERIAL = bytes(range(1, 17))
    BOOT_TEXT = b"RP LIDAR System.\r\nFirmware Ver 1.29 - rtm, HW Ver 7\r\nModel: 24\r\n"

    def __init__(self, port: PtyPort, log: Log, body: Body, playback: Optional[Playback],
                 args: argparse.Namespace) -> None:
        super().__init__(port, log, body, playback, Cut(None), "aria")
        self.baud = lidarstream.BAUD["rplidar"]
        self.robot: Optional["FakeRobot"] = None
        self.rx = bytearray()
        self.scanning = False
        self.t_scan = 0.0        # when the running scan began
        self.next_due = math.inf # the next chunk of the simulated world
        self.angle = 0           # sensor angle of the next node, whole degrees
        self.motor = 0           # last motor PWM or rpm asked for
        self.nodes: List[Tuple[int, bytes]] = []   # a capture's node records (not its descriptor)
        self.record = 0
        self.turn_hz = self.TURN_HZ
        self.n.update(requests=0, bad_requests=0, unsupported=0, scans_started=0, stops=0, resets=0,
                      node_chunks=0, skipped_records=0, ended=0)
        if playback is not None and playback.lidar:
            if playback.lidar_model != "rplidar":
                raise cap.CaptureError(f"the capture's lidar is {playback.lidar_model!r}, not rplidar")
            self.nodes = [(t, d) for t, d in playback.lidar if d != lidarstream.RPLIDAR_SCAN_DESCRIPTOR]
            self.turn_hz = float(playback.turn_hz or self.TURN_HZ)
        self.sample_us = int(round(1e6 / (self.turn_hz * lidarstream.POINTS_PER_TURN)))

    # -- requests -----------------------------------------------------------------------
    def receive(self, data: bytes, now: float) -> None:
        """Requests: A5 cmd, or A5 cmd size payload checksum (XOR of all before)."""
        self.rx += data
        while self.rx:
            if self.rx[0] != 0xA5:
                self.n["dropped_rx_bytes"] += 1
                del self.rx[0]
                continue
            if len(self.rx) < 2:
                return
            cmd = self.rx[1]
            if not cmd & 0x80:
                del self.rx[:2]
                self.handle(cmd, b"", now)
                continue
            if len(self.rx) < 3 or len(self.rx) < 4 + self.rx[2]:
                return
            n = self.rx[2]
            frame = bytes(self.rx[:4 + n])
            del self.rx[:4 + n]
            check = 0
            for b in frame[:-1]:
                check ^= b
            if check != frame[-1]:
                self.n["bad_requests"] += 1   # ignored, as the sensor does
                self.log(self.dev, "bad_request", data=frame.hex())
                continue
            self.handle(cmd, frame[3:-1], now)

    def answer(self, kind: int, body: bytes, now: float) -> None:
        desc = bytes([0xA5, 0x5A]) + len(body).to_bytes(4, "little") + bytes([kind])
        self.send(desc + body, now)

    def handle(self, cmd: int, payload: bytes, now: float) -> None:
        self.n["requests"] += 1
        self.log(self.dev, "request", cmd=cmd, data=payload.hex(), host_baud=self.port.host_baud())
        if cmd == 0x25:                                   # STOP
            self.n["stops"] += self.scanning
            self.scanning = False
            self.next_due = math.inf
        elif cmd == 0x40:                                 # RESET
            self.n["resets"] += 1
            self.scanning = False
            self.next_due = math.inf
            self.send(self.BOOT_TEXT, now)
        elif cmd == 0x52:                                 # GET_HEALTH: good
            self.answer(0x06, bytes([0, 0, 0]), now)
        elif cmd == 0x50:                                 # GET_INFO
            self.answer(0x04, bytes([self.MODEL, self.FW_MINOR, self.FW_MAJOR, self.HARDWARE]) + self.SERIAL,
                        now)
        elif cmd == 0x59:                                 # GET_SAMPLERATE
            self.answer(0x15, struct.pack("<HH", self.sample_us, self.sample_us), now)
        elif cmd in (0x20, 0x21):                         # SCAN, FORCE_SCAN
            self.send(lidarstream.RPLIDAR_SCAN_DESCRIPTOR, now)
            if not self.scanning:
                self.scanning = True
                self.t_scan = now
                self.next_due = now
                self.n["scans_started"] += 1
                self.log(self.dev, "scan_start")
        elif cmd in (0xF0, 0xA8) and len(payload) == 2:   # motor PWM / rpm
            self.motor = struct.unpack("<H", payload)[0]
            self.log(self.dev, "motor", value=self.motor)
        else:                                             # express scans and the rest: no answer
            self.n["unsupported"] += 1

    # -- the stream ---------------------------------------------------------------------
    def capture_time(self, now: float) -> int:
        """The capture's time (us) now: on the robot's clock when it plays the
        same capture (its session's start is the capture's start), else from
        the scan's start."""
        if self.robot is not None and self.robot.t_open is not None:
            return self.playback.t_first + int((now - self.robot.t_open) * 1e6)  # type: ignore[union-attr]
        return self.nodes[0][0] + int((now - self.t_scan) * 1e6)

    def _rendered(self) -> bytes:
        b = self.body
        out = bytearray()
        for j in range(self.CHUNK):
            a = self.angle + j
            r = sim.raycast(b.x, b.y, b.th - math.radians(a), b.segs, b.circles, MAX_RANGE_M)
            mm = int(round(r * 1000.0)) if r < MAX_RANGE_M else 0
            out += lidarstream.rplidar_node(a * 64, mm * 4, lidarstream.RPLIDAR_QUALITY if mm else 0, a == 0)
        self.angle = (self.angle + self.CHUNK) % lidarstream.POINTS_PER_TURN
        return bytes(out)

    def tick(self, now: float) -> None:
        if not self.scanning:
            return
        if self.nodes:
            t = self.capture_time(now)
            # records the head measured while nobody scanned are gone
            while self.record < len(self.nodes) and self.nodes[self.record][0] < t - 200000:
                self.record += 1
                self.n["skipped_records"] += 1
            while self.record < len(self.nodes) and self.nodes[self.record][0] <= t:
                self.n["node_chunks"] += self.send(self.nodes[self.record][1], now)
                self.record += 1
            self.capture_over(self.record == len(self.nodes), chunks=self.n["node_chunks"])
            return
        while self.next_due <= now:
            self.n["node_chunks"] += self.send(self._rendered(), now)
            self.next_due += self.CHUNK / (self.turn_hz * lidarstream.POINTS_PER_TURN)

    def due(self) -> float:
        if not self.scanning:
            return math.inf
        if self.nodes:
            if self.record >= len(self.nodes):
                return math.inf
            return time.monotonic() + max(0.0, (self.nodes[self.record][0] - self.capture_time(time.monotonic())) / 1e6)
        return self.next_due

    def progress(self) -> Dict[str, int]:
        return {"node_chunks": self.n["node_chunks"]}

    def state(self) -> Dict[str, object]:
        return {"scanning": self.scanning, "motor": self.motor, "record": self.record, "angle": self.angle}


def parse_drop(text: str) -> DropSpec:
    """AFTER:FOR: AFTER seconds or Nf frames, FOR seconds or ``signal``."""
    try:
        after_text, dur_text = text.split(":")
        frames = int(after_text[:-1]) if after_text.endswith("f") else None
        after = 0.0 if frames is not None else float(after_text)
        dur = None if dur_text == "signal" else float(dur_text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"want AFTER:FOR (AFTER seconds or Nf frames, FOR seconds or signal), got {text!r}") from None
    if after < 0 or (frames is not None and frames < 1) or (dur is not None and dur <= 0):
        raise argparse.ArgumentTypeError("AFTER must be >= 0 (Nf: N >= 1) and FOR > 0")
    return DropSpec(after, frames, dur)


class Stop(Exception):
    pass


_stopping: List[str] = []


def _note_stop(signum, frame):  # noqa: ARG001
    # Raised where the loop may stop (check_stop), never between a frame's
    # write and its count: a summary then counts every frame the host got.
    _stopping.append(signal.Signals(signum).name)


def check_stop() -> None:
    """Stop if SIGINT or SIGTERM came."""
    if _stopping:
        raise Stop(_stopping[0])


# The device whose ``signal`` cut each signal ends.
RELEASE_SIGNALS = {signal.SIGUSR1: "robot", signal.SIGUSR2: "laser"}
_released: List[str] = []


def _note_release(signum, frame):  # noqa: ARG001
    _released.append(RELEASE_SIGNALS[signal.Signals(signum)])


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-fakedev", description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", action="store_true", help="a fake P3-DX (default: both devices)")
    ap.add_argument("--lms", action="store_true", help="a fake LMS 2xx (default: both devices)")
    ap.add_argument("--ld06", action="store_true",
                    help="a fake LDRobot LD06 (only when asked for; with --robot, a cheap-lidar robot)")
    ap.add_argument("--rplidar", action="store_true",
                    help="a fake Slamtec RPLIDAR (only when asked for; with --robot, a cheap-lidar robot)")
    ap.add_argument("--capture", help="play this capture's encoder packets and scans")
    ap.add_argument("--log", help="write what the devices do, one JSON object per line")
    ap.add_argument("--seconds", type=float, default=0.0, help="stop after this long (0: at a signal)")
    ap.add_argument("--robot-drop", type=parse_drop, metavar="AFTER:FOR",
                    help="cut the robot's line FOR s, AFTER s after its first session opened "
                         "(AFTER Nf: once it has sent N SIPs; FOR signal: until SIGUSR1)")
    ap.add_argument("--lms-drop", type=parse_drop, metavar="AFTER:FOR",
                    help="cut the laser's line FOR s, AFTER s after its first stream started "
                         "(AFTER Nf: once it has sent N scans; FOR signal: until SIGUSR2)")
    ap.add_argument("--watchdog-ms", type=int, default=2000,
                    help="robot watchdog: stop after this long without a command (default 2000)")
    ap.add_argument("--ticks-mm", type=int, default=128,
                    help="TicksMM in the CONFIGpac, and the encoders' ticks per mm (default 128)")
    ap.add_argument("--no-autobaud", action="store_true",
                    help="CONFIGpac says AutoBaud 0 (the host should not send HOSTBAUD)")
    ap.add_argument("--units", choices=("mm", "cm"), default="mm", help="laser units (default mm)")
    ap.add_argument("--patient", action="store_true",
                    help="wait for a host that stops reading however long, dropping nothing (tests)")
    ap.add_argument("--quiet", action="store_true", help="print only the port paths and errors")
    a = ap.parse_args(argv)
    if not 100 <= a.watchdog_ms <= 65535 or not 1 <= a.ticks_mm <= 65535:
        ap.error("--watchdog-ms must be 100..65535 and --ticks-mm 1..65535")
    if a.seconds < 0:
        ap.error("--seconds must not be negative")
    want_robot = a.robot or not (a.lms or a.ld06 or a.rplidar)
    want_lms = a.lms or not (a.robot or a.ld06 or a.rplidar)

    playback = None
    if a.capture:
        try:
            playback = Playback(a.capture)
        except (OSError, cap.CaptureError) as exc:
            print(f"rsm-fakedev: cannot play {a.capture}: {exc}", file=sys.stderr)
            return 1

    signal.signal(signal.SIGTERM, _note_stop)
    signal.signal(signal.SIGINT, _note_stop)
    for sig in RELEASE_SIGNALS:
        signal.signal(sig, _note_release)
    log = Log(a.log)
    body = Body()
    devices: List[Device] = []
    try:
        robot = FakeRobot(PtyPort("robot", a.patient), log, body, playback, a) if want_robot else None
        laser = FakeLaser(PtyPort("laser", a.patient), log, body, playback, a) if want_lms else None
        if robot is not None:
            robot.laser = laser
            devices.append(robot)
        if laser is not None:
            devices.append(laser)
        if a.ld06:
            devices.append(FakeLD06(PtyPort("ld06", a.patient), log, body, playback, a))
        if a.rplidar:
            rplidar = FakeRPLIDAR(PtyPort("rplidar", a.patient), log, body, playback, a)
            rplidar.robot = robot
            devices.append(rplidar)
        for d in devices:
            print(f"{d.port.name} {d.port.path}", flush=True)
            log(d.dev, "start", path=d.port.path)
        if not a.quiet:
            print("rsm-fakedev: devices ready" + (f", playing {a.capture}" if a.capture else ""),
                  file=sys.stderr, flush=True)
        run(devices, log, time.monotonic() + a.seconds if a.seconds > 0 else math.inf)
        return 0
    except cap.CaptureError as exc:
        print(f"rsm-fakedev: cannot play {a.capture}: {exc}", file=sys.stderr)
        return 1
    except Stop as exc:
        if not a.quiet:
            print(f"rsm-fakedev: stopped by {exc.args[0]}", file=sys.stderr, flush=True)
        return 0
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        for d in devices:
            # What the host wrote before the end still counts (a host that
            # sent CLOSE and exited may be faster than this loop).
            for _ in range(64):
                data = d.port.read()
                if not data:
                    break
                d.receive(data, time.monotonic())
            log(d.dev, "summary", **d.summary())
            d.port.close()
        log.close()


def run(devices: Sequence[Device], log: Log, end: float) -> None:
    """The devices' event loop: bytes from the host as they come, and each
    device's timers, until ``end`` (monotonic seconds) or a Stop."""
    by_fd = {d.port.master: d for d in devices}
    while True:
        check_stop()
        now = time.monotonic()
        if now >= end:
            return
        due = min([d.due() for d in devices] + [end])
        ready, _, _ = select.select(list(by_fd), [], [], max(0.0, min(0.05, due - now)))
        now = time.monotonic()
        for fd in ready:
            data = by_fd[fd].port.read()
            if data:
                by_fd[fd].receive(data, now)
        while _released:
            dev = _released.pop(0)
            for d in devices:
                if d.dev == dev:
                    log(dev, "release", cut=d.cut.release(now))
        for d in devices:
            cut = d.cut.active(now)
            if cut != d.cut.state:
                d.cut.state = cut
                log(d.dev, "cut_start" if cut else "cut_end", **d.progress())
            d.tick(now)

if __name__ == "__main__":
    sys.exit(main())
