"""The byte streams of the spinning lidars: rendered from logged scans, and
received (framed and counted) by the host tools.

Encoders for the LDRobot LD06/LD19 packet and the Slamtec RPLIDAR standard
scan (descriptor and 5-byte nodes), written from the layouts in
docs/reference/lidars.md, and :func:`render_turn`, which lays one logged scan
out as one turn of a sensor that measures every whole degree clockwise
(360 points a turn).  A logged beam lands on the sensor angle of its own
bearing (a CARMEN beam ``i`` of ``m`` is at ``-90 + i * 180 / m`` degrees,
counter-clockwise; the sensor angle is its negative), so the geometry stays
as logged; sensor angles no beam points at (the back half, and the odd
angles of a finer scan) carry "no return" (0).  The C decoders
(src/drivers/ld06.c, src/drivers/rplidar.c) read these streams back: tests/py/test_lidarstream.py.
:class:`LD06Receiver` and :class:`RplidarReceiver` are those C receivers'
Python twins, for rsm-record's and rsm-replay's counters.
"""

import math
from dataclasses import dataclass
from typing import List, Sequence, Tuple

POINTS_PER_TURN = 360
LD06_POINTS = 12
LD06_MAX_MM = 0xFFFF
RPLIDAR_MAX_MM = 0xFFFF // 4  # the q2 distance field is 16 bits
RPLIDAR_QUALITY = 47          # a typical quality for a return (0 for none)
RPLIDAR_SCAN_DESCRIPTOR = bytes([0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81])
BAUD = {"ld06": 230400, "rplidar": 115200}


def _crc8_step(crc: int) -> int:
    for _ in range(8):
        crc = ((crc << 1) ^ 0x4D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


# One byte of the CRC at a time (the bitwise rule above, tabulated once):
# rendering a whole log's turns calls it for every packet.
_CRC8_TABLE = bytes(_crc8_step(v) for v in range(256))


def ld06_crc8(data: bytes) -> int:
    """CRC-8 of the LD06 packet: polynomial 0x4D, initial 0, MSB first."""
    crc = 0
    for b in data:
        crc = _CRC8_TABLE[crc ^ b]
    return crc


def ld06_packet(speed_dps: int, start_cdeg: int, end_cdeg: int, timestamp_ms: int,
                points: Sequence[Tuple[int, int]]) -> bytes:
    """One 47-byte packet; points are 12 (distance_mm, intensity) pairs."""
    if len(points) != LD06_POINTS:
        raise ValueError("an LD06 packet carries 12 points")
    body = bytearray([0x54, 0x2C])
    body += int(speed_dps).to_bytes(2, "little") + int(start_cdeg).to_bytes(2, "little")
    for mm, intensity in points:
        body += int(mm).to_bytes(2, "little") + bytes([intensity])
    body += int(end_cdeg).to_bytes(2, "little") + int(timestamp_ms % 30000).to_bytes(2, "little")
    body.append(ld06_crc8(bytes(body)))
    return bytes(body)


def rplidar_node(angle_q6: int, distance_q2: int, quality: int, start: bool) -> bytes:
    """One standard-scan node: S and not-S, quality, check bit, angle, distance."""
    b0 = (quality << 2) | (1 if start else 2)
    return bytes([b0]) + ((angle_q6 << 1) | 1).to_bytes(2, "little") + int(distance_q2).to_bytes(2, "little")


@dataclass
class TurnStats:
    """What rendering did to the logged readings."""
    beams: int = 0       # logged beams looked at
    returns: int = 0     # sent as a distance
    no_return: int = 0   # invalid in the log (0, negative, NaN): sent as 0
    too_far: int = 0     # beyond what the protocol's field carries: sent as 0
    unplaced: int = 0    # beams at no whole-degree bearing: not sent


def turn_ranges(ranges: Sequence[float], max_mm: int, stats: TurnStats) -> List[int]:
    """The 360 distances (mm, 0 = no return) of one turn at sensor angles
    0..359 (clockwise) from one logged scan."""
    out = [0] * POINTS_PER_TURN
    m = len(ranges)
    for i, r in enumerate(ranges):
        stats.beams += 1
        num = -90 * m + i * 180  # bearing * m, degrees
        if num % m != 0:
            stats.unplaced += 1
            continue
        angle = (-(num // m)) % POINTS_PER_TURN
        if not (math.isfinite(r) and r > 0.0):
            stats.no_return += 1
            continue
        mm = int(round(r * 1000.0))
        if mm > max_mm or mm == 0:
            stats.too_far += 1
            continue
        out[angle] = mm
        stats.returns += 1
    return out


def render_turn(kind: str, ranges: Sequence[float], end_us: int, turn_us: int,
                stats: TurnStats) -> List[Tuple[int, bytes]]:
    """One logged scan as one turn of an LD06 or RPLIDAR (standard scan):
    (time_us, bytes) records, each at the time of the last point it carries;
    the turn starts at sensor angle 0 and its last point is measured at
    end_us, points turn_us / 360 apart."""
    if kind not in BAUD:
        raise ValueError("kind must be ld06 or rplidar")
    step = turn_us / POINTS_PER_TURN
    at = [end_us - int(round((POINTS_PER_TURN - 1 - j) * step)) for j in range(POINTS_PER_TURN)]
    records = []
    if kind == "ld06":
        mm = turn_ranges(ranges, LD06_MAX_MM, stats)
        speed = int(round(360.0 * 1e6 / turn_us))
        for first in range(0, POINTS_PER_TURN, LD06_POINTS):
            last = first + LD06_POINTS - 1
            pts = [(mm[j], 200 if mm[j] else 0) for j in range(first, last + 1)]
            records.append((at[last], ld06_packet(min(speed, 0xFFFF), first * 100, last * 100,
                                                  at[last] // 1000, pts)))
    else:
        mm = turn_ranges(ranges, RPLIDAR_MAX_MM, stats)
        for first in range(0, POINTS_PER_TURN, LD06_POINTS):  # 12 nodes a record
            chunk = b"".join(rplidar_node(j * 64, mm[j] * 4, RPLIDAR_QUALITY if mm[j] else 0, j == 0)
                             for j in range(first, first + LD06_POINTS))
            records.append((at[first + LD06_POINTS - 1], chunk))
    return records


# --------------------------------------------------------------------------
# Receivers: the Python twins of the C receivers in src/drivers/ld06.c and
# src/drivers/rplidar.c (same framing, same resynchronisation, counters under the
# same names), for the host tools' live counters.  tests/py/test_lidarstream.py
# checks every counter against rsm-dump's on clean and damaged streams.

LD06_HEADER, LD06_VERLEN, LD06_PACKET = 0x54, 0x2C, 47
LD06_MAX_CDEG = 36000


class LD06Receiver:
    """Streaming LD06/LD19 packet receiver; :meth:`feed` returns the whole
    packets (47 bytes each) that passed the CRC and the angle checks."""

    def __init__(self) -> None:
        self.buf = bytearray()
        self.bytes_fed = self.bytes_skipped = 0
        self.packets_ok = self.crc_errors = self.bad_fields = self.resyncs = 0

    def _resync(self) -> None:
        # drop the candidate's first byte and whatever cannot start a packet
        b = self.buf
        self.resyncs += 1
        while True:
            del b[0]
            self.bytes_skipped += 1
            if not b or (b[0] == LD06_HEADER and (len(b) < 2 or b[1] == LD06_VERLEN)):
                return

    def feed(self, data: bytes) -> List[bytes]:
        out = []
        b = self.buf
        for x in data:
            self.bytes_fed += 1
            if not b and x != LD06_HEADER:
                self.bytes_skipped += 1
                continue
            b.append(x)
            if len(b) == 2 and x != LD06_VERLEN:
                self._resync()
            elif len(b) == LD06_PACKET:
                if ld06_crc8(bytes(b[:-1])) != b[-1]:
                    self.crc_errors += 1
                elif (b[4] | b[5] << 8) >= LD06_MAX_CDEG or (b[42] | b[43] << 8) >= LD06_MAX_CDEG:
                    self.bad_fields += 1
                else:
                    self.packets_ok += 1
                    out.append(bytes(b))
                    b.clear()
                    continue
                self._resync()
        return out


RP_DESCRIPTOR, RP_RESPONSE, RP_NODES, RP_CAPSULES = range(4)
RP_NODE, RP_CAPSULE, RP_FULL_TURN_Q6 = 5, 84, 360 * 64
#: answer type -> (length, send mode) of the answers the receiver knows
RP_ANSWERS = {0x04: (20, 0), 0x06: (3, 0), 0x15: (4, 0), 0x81: (RP_NODE, 1),
              0x82: (RP_CAPSULE, 1), 0x85: (RP_CAPSULE, 1)}
_NEED, _DONE, _REJECT, _BAD_SUM, _BAD_FIELD = 0, 1, -1, -2, -3


class RplidarReceiver:
    """Streaming receiver of an RPLIDAR's answers (descriptor, responses,
    standard-scan nodes, express/dense capsules); :meth:`feed` returns
    ``(answer_type, frame)`` for every accepted descriptor (type 0),
    response and node or capsule."""

    def __init__(self) -> None:
        self.buf = bytearray()
        self.mode = RP_DESCRIPTOR
        self.answer = 0
        self.length = 0
        self.bytes_fed = self.bytes_skipped = self.bytes_framed = 0
        self.descriptors = self.bad_descriptors = self.responses = 0
        self.nodes = self.bad_nodes = self.capsules = 0
        self.checksum_errors = self.bad_capsules = 0

    def expect(self) -> None:
        """A request went out: drop a partial candidate, await a descriptor."""
        self.bytes_skipped += len(self.buf)
        self.buf.clear()
        self.mode = RP_DESCRIPTOR

    def _check(self) -> int:
        b, n = self.buf, len(self.buf)
        if self.mode == RP_DESCRIPTOR:
            if b[0] != 0xA5 or (n >= 2 and b[1] != 0x5A):
                return _REJECT
            if n < 7:
                return _NEED
            w = int.from_bytes(b[2:6], "little")
            return _DONE if RP_ANSWERS.get(b[6]) == (w & 0x3FFFFFFF, w >> 30) else _REJECT
        if self.mode == RP_RESPONSE:
            return _NEED if n < self.length else _DONE
        if self.mode == RP_NODES:
            if (not (b[0] ^ (b[0] >> 1)) & 1 or (n >= 2 and not b[1] & 1)
                    or (n >= 3 and (b[1] | b[2] << 8) >> 1 >= RP_FULL_TURN_Q6)):
                return _REJECT
            return _NEED if n < RP_NODE else _DONE
        if b[0] >> 4 != 0xA or (n >= 2 and b[1] >> 4 != 0x5):
            return _REJECT
        if n < RP_CAPSULE:
            return _NEED
        s = 0
        for x in b[2:]:
            s ^= x
        if s != (b[0] & 0x0F) | ((b[1] << 4) & 0xF0):
            return _BAD_SUM
        return _DONE if (b[2] | b[3] << 8) & 0x7FFF < RP_FULL_TURN_Q6 else _BAD_FIELD

    def _take(self) -> Tuple[int, bytes]:
        frame = bytes(self.buf)
        self.bytes_framed += len(frame)
        self.buf.clear()
        if self.mode == RP_DESCRIPTOR:
            self.descriptors += 1
            self.answer = frame[6]
            self.length = int.from_bytes(frame[2:6], "little") & 0x3FFFFFFF
            self.mode = (RP_RESPONSE if frame[5] >> 6 == 0 else
                         RP_NODES if self.answer == 0x81 else RP_CAPSULES)
            return 0, frame
        if self.mode == RP_RESPONSE:
            self.responses += 1
            self.mode = RP_DESCRIPTOR
        elif self.mode == RP_NODES:
            self.nodes += 1
        else:
            self.capsules += 1
        return self.answer, frame

    def feed(self, data: bytes) -> List[Tuple[int, bytes]]:
        out = []
        for x in data:
            self.buf.append(x)
            self.bytes_fed += 1
            verdict = self._check()
            if verdict == _DONE:
                out.append(self._take())
            elif verdict < 0:
                if verdict == _BAD_SUM:
                    self.checksum_errors += 1
                elif verdict == _BAD_FIELD:
                    self.bad_capsules += 1
                elif self.mode == RP_DESCRIPTOR and len(self.buf) == 7:
                    self.bad_descriptors += 1
                elif self.mode == RP_NODES:
                    self.bad_nodes += 1
                while True:  # drop the first byte, then whatever cannot start a candidate
                    del self.buf[0]
                    self.bytes_skipped += 1
                    if not self.buf or self._check() >= 0:
                        break
        return out
