"""Python encoders (and small decoders) for the two serial protocols rsm reads.

* Pioneer P3-DX / ARCOS (ARIA client protocol): ``FA FB N ID payload CKH CKL``
  with the 16-bit pairwise-sum checksum over ID + payload (big-endian on the
  wire).  Encoders for commands, the ENCODER packet (0x90) and the standard
  SIP (0x32 stopped / 0x33 moving).
* SICK LMS 2xx binary telegrams: ``02 ADR LEN(u16 LE) CMD data CRC(u16 LE)``
  with the LMS CRC (generator 0x8005, previous-byte word, no reflection).
  Encoders for request/reply telegrams and the 0xB0 measured-values reply in
  cm or mm units, plus the single ACK/NAK bytes.

The C codecs in the library are authoritative; the decoders here are what the
host tools and the tests need.  Every encoder reproduces the published vectors
of the protocol reference byte for byte (tests/py/test_protocols.py).
"""

import struct
from dataclasses import dataclass, field
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from . import lidarstream

# --------------------------------------------------------------------------
# ARIA

ARIA_HEADER = b"\xfa\xfb"
ARIA_INTARG = 0x3B
ARIA_NINTARG = 0x1B
ARIA_STRARG = 0x2B

ARIA_SIP_STOPPED = 0x32
ARIA_SIP_MOVING = 0x33
ARIA_ENCODER = 0x90

ARIA_SYNC0, ARIA_SYNC1, ARIA_SYNC2 = 0x00, 0x01, 0x02
ARIA_CONFIGPAC = 0x20

# command numbers used by the tools (protocols.md 1.8)
CMD_PULSE, CMD_OPEN, CMD_CLOSE, CMD_ENABLE = 0, 1, 2, 4
CMD_SETO, CMD_ROTATE, CMD_VEL = 7, 9, 11
CMD_CONFIG, CMD_ENCODER, CMD_RVEL = 18, 19, 21
CMD_STOP, CMD_VEL2, CMD_HOSTBAUD, CMD_ESTOP = 29, 32, 50, 55

#: names of the commands above, for logs
ARIA_COMMAND_NAMES = {
    CMD_PULSE: "PULSE", CMD_OPEN: "OPEN", CMD_CLOSE: "CLOSE", CMD_ENABLE: "ENABLE",
    CMD_SETO: "SETO", CMD_ROTATE: "ROTATE", CMD_VEL: "VEL", CMD_CONFIG: "CONFIG",
    CMD_ENCODER: "ENCODER", CMD_RVEL: "RVEL", CMD_STOP: "STOP", CMD_VEL2: "VEL2",
    CMD_HOSTBAUD: "HOSTBAUD", CMD_ESTOP: "ESTOP",
}

#: HOSTBAUD codes 0..4 (protocols.md 1.8)
ARIA_BAUD_RATES = (9600, 19200, 38400, 57600, 115200)


def aria_checksum(body: bytes) -> int:
    """ARIA checksum over ID + payload: pairwise big-endian 16-bit sum, odd byte XORed."""
    c = 0
    n = len(body)
    i = 0
    while i + 1 < n:
        c = (c + ((body[i] << 8) | body[i + 1])) & 0xFFFF
        i += 2
    if n & 1:
        c ^= body[-1]
    return c


def aria_packet(ptype: int, payload: bytes = b"") -> bytes:
    """Frame ``ptype`` + ``payload`` as an ARIA packet (header, count, checksum)."""
    body = bytes([ptype & 0xFF]) + bytes(payload)
    if len(body) + 2 > 255:
        raise ValueError(f"ARIA payload too long: {len(payload)} bytes")
    ck = aria_checksum(body)
    return ARIA_HEADER + bytes([len(body) + 2]) + body + bytes([ck >> 8, ck & 0xFF])


def aria_int_arg(value: int) -> bytes:
    """An integer argument: 0x3B + u16 LE, or 0x1B + |value| for negatives."""
    if value >= 0:
        return bytes([ARIA_INTARG]) + struct.pack("<H", value & 0xFFFF)
    return bytes([ARIA_NINTARG]) + struct.pack("<H", (-value) & 0xFFFF)


def aria_command(cmd: int, arg: Optional[int] = None, string: Optional[bytes] = None,
                 nul: bool = True) -> bytes:
    """A host->robot command with no argument, an integer or a string argument.

    Strings are sent as ARIA does: 0x2B, length byte, characters, then a NUL
    that the length does not count (``nul=False`` drops it).
    """
    if string is not None:
        payload = bytes([ARIA_STRARG, len(string)]) + bytes(string) + (b"\x00" if nul else b"")
    elif arg is not None:
        payload = aria_int_arg(arg)
    else:
        payload = b""
    return aria_packet(cmd, payload)


def aria_int_value(payload: bytes) -> Optional[int]:
    """The integer argument of a command payload (0x3B/0x1B + u16 LE), or None."""
    if len(payload) < 3 or payload[0] not in (ARIA_INTARG, ARIA_NINTARG):
        return None
    v = payload[1] | (payload[2] << 8)
    return -v if payload[0] == ARIA_NINTARG else v


def encode_sync2_reply(name: str = "rsm-fakedev", robot_class: str = "Pioneer",
                       subclass: str = "p3dx-sh") -> bytes:
    """The robot's SYNC2 reply: name, class and subclass, each NUL-terminated."""
    text = b"".join(s.encode("ascii") + b"\x00" for s in (name, robot_class, subclass))
    return aria_packet(ARIA_SYNC2, text)


@dataclass
class AriaConfig:
    """Fields of a CONFIGpac (0x20) in wire order (protocols.md 1.12)."""

    robot_type: str = "Pioneer"
    subtype: str = "p3dx-sh"
    serial: str = "FAKE0001"
    four_mot: int = 0
    rot_vel_top: int = 500
    trans_vel_top: int = 2200
    rot_acc_top: int = 300
    trans_acc_top: int = 1000
    pwm_max: int = 1000
    name: str = "rsm-fakedev"
    sip_cycle: int = 100            # ms
    host_baud: int = 0              # HOSTBAUD code of the current rate
    aux1_baud: int = 0
    has_gripper: int = 0
    front_sonar: int = 1
    rear_sonar: int = 0
    low_battery: int = 110          # 0.1 V
    rev_count: int = 16570
    watchdog: int = 2000            # ms
    normal_mpacs: int = 0
    stall_val: int = 200
    stall_count: int = 100
    joy_vel: int = 300
    joy_rot_vel: int = 50
    rot_vel_max: int = 300
    trans_vel_max: int = 1200
    rot_accel: int = 100
    rot_decel: int = 100
    rot_kp: int = 40
    rot_kv: int = 20
    rot_ki: int = 0
    trans_accel: int = 300
    trans_decel: int = 300
    trans_kp: int = 40
    trans_kv: int = 20
    trans_ki: int = 0
    front_bumps: int = 5
    rear_bumps: int = 5
    charger: int = 0
    sonar_cycle: int = 40
    auto_baud: int = 2              # 2: the host may switch rates with HOSTBAUD
    has_gyro: int = 0
    drift_factor: int = 0
    aux2_baud: int = 0
    aux3_baud: int = 0
    ticks_mm: int = 128
    shutdown_volts: int = 105
    firmware: str = "fake-1.0"


def encode_config_pac(c: AriaConfig) -> bytes:
    """A CONFIGpac with the fields of ``c`` (little-endian integers, NUL-ended strings)."""
    def z(text: str) -> bytes:
        return text.encode("ascii") + b"\x00"

    p = z(c.robot_type) + z(c.subtype) + z(c.serial)
    p += struct.pack("<BHHHHH", c.four_mot, c.rot_vel_top, c.trans_vel_top, c.rot_acc_top,
                     c.trans_acc_top, c.pwm_max)
    p += z(c.name)
    p += struct.pack("<BBBHHBHHHB", c.sip_cycle, c.host_baud, c.aux1_baud, c.has_gripper,
                     c.front_sonar, c.rear_sonar, c.low_battery, c.rev_count, c.watchdog,
                     c.normal_mpacs)
    p += struct.pack("<16H", c.stall_val, c.stall_count, c.joy_vel, c.joy_rot_vel, c.rot_vel_max,
                     c.trans_vel_max, c.rot_accel, c.rot_decel, c.rot_kp, c.rot_kv, c.rot_ki,
                     c.trans_accel, c.trans_decel, c.trans_kp, c.trans_kv, c.trans_ki)
    p += struct.pack("<BBBBBBhBBHH", c.front_bumps, c.rear_bumps, c.charger, c.sonar_cycle,
                     c.auto_baud, c.has_gyro, c.drift_factor, c.aux2_baud, c.aux3_baud,
                     c.ticks_mm, c.shutdown_volts)
    p += z(c.firmware)
    return aria_packet(ARIA_CONFIGPAC, p)


def aria_vel2(left_units: int, right_units: int) -> bytes:
    """VEL2 (cmd 32): high byte left, low byte right, sent as a signed 16-bit int."""
    word = ((left_units & 0xFF) << 8) | (right_units & 0xFF)
    signed = word - 0x10000 if word & 0x8000 else word
    return aria_command(32, signed)


def _s32(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v & 0x80000000 else v


def encode_encoder(left: int, right: int) -> bytes:
    """ENCODER packet (0x90): two signed 32-bit tick counts, LSB first.

    Any integer is accepted and reduced modulo 2**32 (the counters wrap).
    """
    return aria_packet(ARIA_ENCODER, struct.pack("<ii", _s32(left), _s32(right)))


@dataclass
class Sip:
    """Fields of a standard SIP (0x32/0x33), raw units as on the wire."""

    xpos: int = 0            # 15 bits, mm
    ypos: int = 0            # 15 bits, mm
    thpos: int = 0           # s16, 2*pi/4096 rad
    lvel: int = 0            # mm/s
    rvel: int = 0            # mm/s
    battery: int = 120       # 0.1 V
    stall_bumpers: int = 0
    control: int = 0
    flags: int = 0x0001
    compass: int = 0
    sonar: List[Tuple[int, int]] = field(default_factory=list)  # (disc, range mm)
    grip_state: int = 0
    anport: int = 0
    analog: int = 0
    digin: int = 0
    digout: int = 0
    batteryx10: int = 0
    chargestate: int = 0
    rotvel: int = 0          # 0.1 deg/s
    faultflags: int = 0
    moving: bool = False


def encode_sip(s: Sip) -> bytes:
    """Standard SIP with the plain P3-DX layout (byte count 34 + 3n)."""
    p = struct.pack("<HHhhhBHhHBB", s.xpos & 0x7FFF, s.ypos & 0x7FFF, s.thpos, s.lvel, s.rvel,
                    s.battery, s.stall_bumpers, s.control, s.flags, s.compass, len(s.sonar))
    for disc, rng in s.sonar:
        p += struct.pack("<BH", disc, rng)
    p += struct.pack("<BBBBBHBhH", s.grip_state, s.anport, s.analog, s.digin, s.digout,
                     s.batteryx10, s.chargestate, s.rotvel, s.faultflags)
    return aria_packet(ARIA_SIP_MOVING if s.moving else ARIA_SIP_STOPPED, p)


def decode_sip(packet: bytes) -> Sip:
    ptype, payload = aria_unframe(packet)
    if ptype not in (ARIA_SIP_STOPPED, ARIA_SIP_MOVING):
        raise ValueError(f"not a standard SIP: type 0x{ptype:02X}")
    f = struct.unpack_from("<HHhhhBHhHBB", payload, 0)
    s = Sip(f[0] & 0x7FFF, f[1] & 0x7FFF, f[2], f[3], f[4], f[5], f[6], f[7], f[8], f[9])
    n = f[10]
    off = 19
    for _ in range(n):
        s.sonar.append(struct.unpack_from("<BH", payload, off))
        off += 3
    tail = payload[off:]
    if len(tail) >= 12:
        t = struct.unpack_from("<BBBBBHBhH", tail, 0)
        (s.grip_state, s.anport, s.analog, s.digin, s.digout, s.batteryx10, s.chargestate,
         s.rotvel, s.faultflags) = t
    s.moving = ptype == ARIA_SIP_MOVING
    return s


def aria_unframe(packet: bytes) -> Tuple[int, bytes]:
    """Check one complete ARIA packet; return (type, payload).  Raises ValueError."""
    if len(packet) < 6 or packet[:2] != ARIA_HEADER:
        raise ValueError("not an ARIA packet (header)")
    n = packet[2]
    if n < 3 or len(packet) != n + 3:
        raise ValueError(f"ARIA byte count {n} does not match length {len(packet)}")
    body = packet[3:n + 1]
    ck = (packet[n + 1] << 8) | packet[n + 2]
    if aria_checksum(body) != ck:
        raise ValueError("ARIA checksum mismatch")
    return body[0], bytes(body[1:])


def decode_encoder(packet: bytes) -> Tuple[int, int]:
    """(left, right) signed 32-bit counts of an ENCODER packet."""
    ptype, payload = aria_unframe(packet)
    if ptype != ARIA_ENCODER or len(payload) < 8:
        raise ValueError(f"not an ENCODER packet: type 0x{ptype:02X}, {len(payload)} bytes")
    return struct.unpack_from("<ii", payload, 0)


def tick_delta(new: int, old: int) -> int:
    """Difference of two 32-bit counters modulo 2**32, as a signed value."""
    return _s32(new - old)


# --------------------------------------------------------------------------
# SICK LMS 2xx

LMS_STX = 0x02
LMS_ACK = 0x06
LMS_NAK = 0x15
LMS_HOST_ADDR = 0x00
LMS_REPLY_ADDR = 0x80
LMS_STATUS_OK = 0x10

UNITS_CM = "cm"
UNITS_MM = "mm"
_UNIT_BITS = {UNITS_CM: 0x0000, UNITS_MM: 0x4000}
_UNIT_SCALE = {UNITS_CM: 0.01, UNITS_MM: 0.001}

# request codes (host -> LMS) and reply codes (LMS -> host), protocols.md 2.5/2.6
LMS_CMD_RESET, LMS_CMD_MODE, LMS_CMD_GET_VALUES, LMS_CMD_GET_STATUS = 0x10, 0x20, 0x30, 0x31
LMS_CMD_GET_TYPE, LMS_CMD_SET_VARIANT, LMS_CMD_GET_CONFIG, LMS_CMD_SET_CONFIG = 0x3A, 0x3B, 0x74, 0x77
LMS_REPLY_POWER_ON, LMS_REPLY_RESET, LMS_REPLY_NOT_ACK = 0x90, 0x91, 0x92
# 0x20 mode codes
LMS_MODE_INSTALLATION, LMS_MODE_CONTINUOUS, LMS_MODE_ON_REQUEST = 0x00, 0x24, 0x25
#: 0x20 baud-change modes and their rates
LMS_MODE_BAUD = {0x40: 38400, 0x41: 19200, 0x42: 9600, 0x48: 500000}
#: variants (angle deg, resolution 1/100 deg) -> (values per scan, angle of value 0 in 1/100 deg)
LMS_VARIANTS = {(180, 100): (181, 0), (180, 50): (361, 0), (100, 100): (101, 4000),
                (100, 50): (201, 4000), (100, 25): (401, 4000)}
LMS_CONFIG_BLOCK_LEN = 32


def lms_config_block(units: str = UNITS_MM, measuring_mode: int = 0x00,
                     availability: int = 0x00) -> bytes:
    """A 32-byte configuration block (0xF4/0x77, protocols.md 2.8): byte C
    availability, D measuring mode, E units; the rest plausible defaults."""
    b = bytearray(LMS_CONFIG_BLOCK_LEN)
    b[2] = 0x46                     # B: stop threshold (LMS200)
    b[3] = 0x00                     # B: peak threshold
    b[4] = availability & 0xFF
    b[5] = measuring_mode & 0xFF
    b[6] = 0x01 if units == UNITS_MM else 0x00
    return bytes(b)


LMS_MAX_VALUE = 0x1FF6          # largest distance in the 13-bit (8 m / 80 m) modes
LMS_NO_VALUE = 0x1FFF           # no valid measurement
LMS_TOO_FAR = 0x1FF7            # value larger than the maximum
LMS_ERROR_MIN = 0x1FF7          # 0x1FF7..0x1FFF are error codes


def lms_crc(data: bytes) -> int:
    """The LMS 2xx CRC-16 (sicktoolbox/Telegram Listing form)."""
    crc = 0
    prev = 0
    for b in data:
        if crc & 0x8000:
            crc = ((crc << 1) & 0xFFFF) ^ 0x8005
        else:
            crc = (crc << 1) & 0xFFFF
        crc ^= (prev << 8) | b
        prev = b
    return crc


def lms_telegram(cmd: int, data: bytes = b"", address: int = LMS_HOST_ADDR) -> bytes:
    """A framed telegram: STX, ADR, LEN (counts CMD + data), CMD, data, CRC LE."""
    ln = 1 + len(data)
    frame = bytes([LMS_STX, address & 0xFF]) + struct.pack("<H", ln) + bytes([cmd & 0xFF]) + bytes(data)
    return frame + struct.pack("<H", lms_crc(frame))


def lms_reply(cmd: int, data: bytes = b"", status: int = LMS_STATUS_OK,
              address: int = LMS_REPLY_ADDR) -> bytes:
    """A sensor->host reply: the data is followed by the status byte."""
    return lms_telegram(cmd, bytes(data) + bytes([status]), address)


def lms_unframe(frame: bytes) -> Tuple[int, int, bytes]:
    """Check one complete telegram; return (address, cmd, data incl. status)."""
    if len(frame) < 7 or frame[0] != LMS_STX:
        raise ValueError("not an LMS telegram (STX)")
    ln = struct.unpack_from("<H", frame, 2)[0]
    if len(frame) != ln + 6 or ln < 1:
        raise ValueError(f"LMS LEN {ln} does not match length {len(frame)}")
    crc = struct.unpack_from("<H", frame, 4 + ln)[0]
    if lms_crc(frame[:4 + ln]) != crc:
        raise ValueError("LMS CRC mismatch")
    return frame[1], frame[4], bytes(frame[5:4 + ln])


def range_to_raw(r: float, units: str = UNITS_MM, max_range: Optional[float] = None) -> int:
    """A range in metres as a 13-bit LMS value; out of range/invalid -> error codes.

    Non-finite, zero or negative ranges give 0x1FFF (no valid measurement);
    ranges beyond ``max_range`` or beyond what the units can carry (8.182 m in
    mm, 81.82 m in cm) give 0x1FF7 (value larger than the maximum).
    """
    if not (r == r) or r in (float("inf"), float("-inf")) or r <= 0.0:
        return LMS_NO_VALUE
    if max_range is not None and r > max_range:
        return LMS_TOO_FAR
    v = int(round(r / _UNIT_SCALE[units]))
    if v > LMS_MAX_VALUE:
        return LMS_TOO_FAR
    return v


def encode_b0(values: Sequence[int], units: str = UNITS_MM, status: int = LMS_STATUS_OK,
              address: int = LMS_REPLY_ADDR) -> bytes:
    """0xB0 measured-values reply carrying raw 16-bit words (flags included)."""
    n = len(values)
    if not 1 <= n <= 0x3FF:
        raise ValueError(f"0xB0 value count {n} out of 1..1023")
    cw = n | _UNIT_BITS[units]
    data = struct.pack("<H", cw) + struct.pack(f"<{n}H", *[v & 0xFFFF for v in values])
    return lms_reply(0xB0, data, status, address)


def encode_b0_ranges(ranges_m: Iterable[float], units: str = UNITS_MM,
                     max_range: Optional[float] = None, status: int = LMS_STATUS_OK) -> bytes:
    """0xB0 reply from ranges in metres (see :func:`range_to_raw`)."""
    return encode_b0([range_to_raw(r, units, max_range) for r in ranges_m], units, status)


@dataclass
class B0Scan:
    count: int
    units: str
    partial: bool
    raw: List[int]
    status: int

    def ranges(self, mask: int = 0x1FFF) -> List[Optional[float]]:
        """Distances in metres (13-bit default modes); None for error codes."""
        sc = _UNIT_SCALE[self.units]
        out: List[Optional[float]] = []
        for w in self.raw:
            d = w & mask
            out.append(None if d >= (mask & ~0x8) else d * sc)
        return out


def decode_b0(frame: bytes) -> B0Scan:
    _, cmd, data = lms_unframe(frame)
    if cmd != 0xB0:
        raise ValueError(f"not a 0xB0 telegram: 0x{cmd:02X}")
    cw = struct.unpack_from("<H", data, 0)[0]
    n = cw & 0x03FF
    ub = (cw >> 14) & 3
    if ub > 1:
        raise ValueError(f"reserved units bits in count word 0x{cw:04X}")
    if len(data) < 2 + 2 * n + 1:
        raise ValueError("0xB0 telegram shorter than its count word says")
    raw = list(struct.unpack_from(f"<{n}H", data, 2))
    return B0Scan(n, UNITS_MM if ub == 1 else UNITS_CM, bool(cw & 0x2000), raw, data[-1])


# --------------------------------------------------------------------------
# frame counting over a byte stream (for live counters and tests)


class FrameCounter:
    """Counts valid frames in a byte stream of one protocol, fed in chunks.

    ``protocol`` is ``"aria"``, ``"lms2xx"``, ``"ld06"`` or ``"rplidar"``
    (the lidars through the receivers of :mod:`rsm_tools.lidarstream`);
    other protocols count nothing.  ``types`` counts frames by packet type /
    reply code (the LD06: 0x54; the RPLIDAR: the answer type, 0 for a
    descriptor); ``bad`` counts candidates whose checksum or CRC failed.
    With ``keep`` set, the frames found are also appended to
    ``frames_seen`` (see :meth:`take`).
    """

    def __init__(self, protocol: str) -> None:
        self.protocol = protocol
        self.buf = bytearray()
        self.frames = 0
        self.bad = 0
        self.types: Dict[int, int] = {}
        self.frames_seen: List[bytes] = []
        self.keep = False
        self.receiver = {"ld06": lidarstream.LD06Receiver,
                         "rplidar": lidarstream.RplidarReceiver}.get(protocol, lambda: None)()

    def _ok(self, frame: bytes, t: int) -> None:
        self.frames += 1
        self.types[t] = self.types.get(t, 0) + 1
        if self.keep:
            self.frames_seen.append(bytes(frame))

    def take(self) -> List[bytes]:
        """The frames kept since the last call (``keep`` must be set)."""
        out, self.frames_seen = self.frames_seen, []
        return out

    def feed(self, data: bytes) -> None:
        if self.protocol == "aria":
            self._feed_aria(data)
        elif self.protocol == "lms2xx":
            self._feed_lms(data)
        elif self.protocol == "ld06":
            for frame in self.receiver.feed(data):
                self._ok(frame, frame[0])
            self.bad = self.receiver.crc_errors
        elif self.protocol == "rplidar":
            for t, frame in self.receiver.feed(data):
                self._ok(frame, t)
            self.bad = self.receiver.checksum_errors

    def describe(self) -> str:
        """The live counter's words: what was decoded and what failed its check."""
        r = self.receiver
        if self.protocol == "ld06":
            return (f"{self.frames} packets ({lidarstream.LD06_POINTS * self.frames} points), "
                    f"{r.crc_errors} CRC errors, {r.bad_fields} bad angles, {r.bytes_skipped} B skipped")
        if self.protocol == "rplidar":
            bad = r.bad_descriptors + r.bad_nodes + r.bad_capsules
            return (f"{r.descriptors} descriptors, {r.responses} responses, {r.nodes} nodes, "
                    f"{r.capsules} capsules, {r.checksum_errors} checksum errors, {bad} bad, "
                    f"{r.bytes_skipped} B skipped")
        if self.protocol in ("aria", "lms2xx"):
            what = "checksum" if self.protocol == "aria" else "CRC"
            return f"{self.frames} frames, {self.bad} {what} errors"
        return "not decoded (raw)"

    def _feed_aria(self, data: bytes) -> None:
        b = self.buf
        b += data
        while True:
            i = b.find(ARIA_HEADER)
            if i < 0:
                del b[:max(0, len(b) - 1)]
                return
            if i:
                del b[:i]
            if len(b) < 3:
                return
            n = b[2]
            if n < 3:
                del b[:1]
                continue
            if len(b) < n + 3:
                return
            frame = bytes(b[:n + 3])
            try:
                t, _ = aria_unframe(frame)
            except ValueError:
                self.bad += 1
                del b[:1]
                continue
            self._ok(frame, t)
            del b[:n + 3]

    def _feed_lms(self, data: bytes) -> None:
        b = self.buf
        b += data
        while True:
            i = b.find(bytes([LMS_STX]))
            if i < 0:
                b.clear()
                return
            if i:
                del b[:i]
            if len(b) < 4:
                return
            ln = b[2] | (b[3] << 8)
            if ln < 1 or ln > 814:
                del b[:1]
                continue
            if len(b) < ln + 6:
                return
            frame = bytes(b[:ln + 6])
            if lms_crc(frame[:4 + ln]) != (frame[4 + ln] | (frame[5 + ln] << 8)):
                self.bad += 1
                del b[:1]
                continue
            self._ok(frame, frame[4])
            del b[:ln + 6]
