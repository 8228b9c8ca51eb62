"""The byte streams of the spinning lidars, rendered from logged scans.

Encoders for the LDRobot LD06/LD19 packet and the Slamtec RPLIDAR standard
scan (descriptor and 5-byte nodes), written from the layouts in
docs/reference/lidars.md, and :func:`render_turn`, which lays one logged scan
out as one turn of a sensor that measures every whole degree clockwise
(360 points a turn).  A logged beam lands on the sensor angle of its own
bearing (a CARMEN beam ``i`` of ``m`` is at ``-90 + i * 180 / m`` degrees,
counter-clockwise; the sensor angle is its negative), so the geometry stays
as logged; sensor angles no beam points at (the back half, and the odd
angles of a finer scan) carry "no return" (0).  The C decoders
(src/ld06.c, src/rplidar.c) read these streams back: tests/py/test_lidarstream.py.
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
