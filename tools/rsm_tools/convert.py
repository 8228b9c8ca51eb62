"""rsm-convert: a CARMEN log to a capture of the serial bytes a P3-DX and an LMS would send.

    rsm-convert LOG OUT.cap [--units auto|mm|cm] [--readings auto|180|181|361]
                [--ticks-per-m 128000] [--wheel-base 0.357] [--max-range M]
                [--start-ticks N] [--min-gap-ms 10] [--ground-truth NAME]

* Every odometry pose of the log (each ODOM line and the odometry triple of
  each FLASER line) becomes one ARIA ENCODER packet (0x90) on channel
  ``robot`` at the record's timestamp (three for a step one arc cannot
  reach, see :class:`TickEncoder`).  The 32-bit tick counts come from
  inverse differential-drive kinematics (see :func:`integrate`), accumulated
  as integers from the reconstructed pose, so quantisation never drifts.
* Every FLASER scan becomes one LMS 0xB0 telegram on channel ``laser``
  right after its ENCODER packet, at the same timestamp.  The range unit is
  chosen to keep what the log has (``--units auto``, the default): mm when
  the longest valid reading fits in 8.182 m, else cm (81.82 m).  Readings no
  unit can carry, or beyond ``--max-range``, go out as the LMS code "value
  larger than the maximum"; their number is printed and kept in the header
  (``convert.too_far``), never dropped silently.
* File order is kept.  The log's stamps go backwards at times because single
  records carry a stamp far off their neighbours'; the longest
  non-decreasing run of stamps is kept as it is and every stamp off it is
  re-placed by linear interpolation (by position) between its kept
  neighbours (see :func:`monotonic_stamps`).  Clamping instead would carry
  one stamp that jumped ahead onto every record after it, and a replay would
  deliver those records in one burst, losing their timing.  Records are then
  spaced ``--min-gap-ms`` apart (see :func:`spread_stamps`).  Moved stamps
  are counted, reported and listed in the header metadata
  ``convert.clamped`` (``kind index original_us written_us`` per line), so
  every original stamp can be recovered.

With ``--lidar ld06`` or ``--lidar rplidar`` the laser channel is a spinning
lidar's instead (channel ``lidar``, raw bytes): every FLASER scan becomes one
turn of an LD06 (30 packets of 12 points) or an RPLIDAR standard scan (360
nodes after one answer descriptor), the sensor measuring every whole degree
clockwise, each logged beam at the angle of its own bearing and the other
angles "no return" (:mod:`rsm_tools.lidarstream`).  A turn lasts
``1 / --lidar-hz`` seconds, or the time to the previous or next scan if that
is shorter, and its middle is the scan's stamp (the time the revolution
assembler gives a turn); its points are spread over it, but
they are one logged scan, taken at one instant: de-skew has nothing to
correct on such a stream.

Details (beam resampling, range codes) are in docs/capture.md.
"""

import argparse
import bisect
import math
import os
import sys
import zlib
from dataclasses import dataclass
from typing import Iterable, List, Optional, Sequence, Tuple, Union

from . import capture as cap
from . import lidarstream
from . import protocols as proto
from .carmen import FLaser, LogStats, Odom, read_log, time_key

Pose = Tuple[float, float, float]

DEFAULT_TICKS_PER_M = 128000.0
DEFAULT_WHEEL_BASE = 0.357
UNIT_LIMIT_M = {u: proto.LMS_MAX_VALUE * proto._UNIT_SCALE[u] for u in ("mm", "cm")}  # 8.182, 81.82
DEFAULT_MIN_GAP_US = 10000
ROBOT, LASER = 0, 1
POINTS_MIN_US = lidarstream.POINTS_PER_TURN  # a rendered turn lasts at least 1 us a point


def wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def integrate(pose: Pose, dl_ticks: int, dr_ticks: int, ticks_per_m: float,
              wheel_base: float) -> Pose:
    """Forward kinematics used everywhere in the tools (midpoint-heading step)::

        dl, dr = ticks / ticks_per_m;  ds = (dl + dr) / 2;  dth = (dr - dl) / B
        x += ds cos(th + dth/2);  y += ds sin(th + dth/2);  th += dth
    """
    dl = dl_ticks / ticks_per_m
    dr = dr_ticks / ticks_per_m
    ds = 0.5 * (dl + dr)
    dth = (dr - dl) / wheel_base
    x, y, th = pose
    m = th + 0.5 * dth
    return (x + ds * math.cos(m), y + ds * math.sin(m), wrap(th + dth))


class TickEncoder:
    """Turns a sequence of poses into integer wheel tick counts (inverse kinematics).

    Each step starts from the pose reconstructed from the ticks already issued
    (closed loop), so rounding never accumulates.  A differential drive cannot
    move sideways, but a logged odometry step can (rounding in the log, and
    steps the logging robot corrected).  So a step is one arc (one packet) when
    that lands within ``split_tol`` metres (default one tick of wheel travel,
    1 / ``ticks_per_m``) and ``split_tol_th`` radians of the target; otherwise
    it is three packets: turn on the spot to face the target (or face away from
    it, whichever turn is smaller), drive straight, turn on the spot to the
    target heading.  Turning on the spot (dl = -dr) and driving straight
    (dl = dr) are exact in the midpoint model, so the error after a split step
    is only the tick quantisation.  The turns of a split are motion the log
    did not have, all at one instant: a consumer that interpolates odometry
    between packets (a spinning lidar's turn stamped between them) sees part
    of them.  So a miss of at most ``coarse_tol`` metres (0.5 mm) is split
    only when facing the target takes at most ``max_face`` radians (a long
    enough step: 0.05 rad), else sent as the arc, and the closed loop takes
    the rest up at a later step.
    """

    def __init__(self, first: Pose, ticks_per_m: float, wheel_base: float, start: int = 0,
                 split_tol: Optional[float] = None, split_tol_th: float = 5e-5,
                 coarse_tol: float = 0.0005, max_face: float = 0.05) -> None:
        self.tpm = ticks_per_m
        self.base = wheel_base
        self.left = start
        self.right = start
        self.pose = first
        self.split_tol = 1.0 / ticks_per_m if split_tol is None else split_tol
        self.split_tol_th = split_tol_th
        self.coarse_tol = coarse_tol
        self.max_face = max_face
        self.splits = 0

    def _emit(self, dl: int, dr: int) -> Tuple[int, int]:
        self.left += dl
        self.right += dr
        self.pose = integrate(self.pose, dl, dr, self.tpm, self.base)
        return self.left, self.right

    def _arc(self, target: Pose) -> Tuple[int, int]:
        x, y, th = self.pose
        dth = wrap(target[2] - th)
        m = th + 0.5 * dth
        ds = (target[0] - x) * math.cos(m) + (target[1] - y) * math.sin(m)
        return (int(round((ds - 0.5 * dth * self.base) * self.tpm)),
                int(round((ds + 0.5 * dth * self.base) * self.tpm)))

    def _turn(self, dth: float) -> Optional[Tuple[int, int]]:
        t = int(round(0.5 * dth * self.base * self.tpm))
        return self._emit(-t, t) if t else None

    def step(self, target: Pose) -> List[Tuple[int, int]]:
        """Cumulative (left, right) counts of the packet(s) that reach ``target``."""
        dl, dr = self._arc(target)
        cand = integrate(self.pose, dl, dr, self.tpm, self.base)
        miss = math.hypot(cand[0] - target[0], cand[1] - target[1])
        dx, dy = target[0] - self.pose[0], target[1] - self.pose[1]
        turn = wrap(math.atan2(dy, dx) - self.pose[2])
        if abs(turn) > 0.5 * math.pi:
            turn = wrap(turn + math.pi)
        if abs(wrap(cand[2] - target[2])) <= self.split_tol_th and (
                miss <= self.split_tol or (miss <= self.coarse_tol and abs(turn) > self.max_face)):
            return [self._emit(dl, dr)]
        self.splits += 1
        out = []
        p = self._turn(turn)
        if p:
            out.append(p)
        th = self.pose[2]
        ds = dx * math.cos(th) + dy * math.sin(th)
        t = int(round(ds * self.tpm))
        if t:
            out.append(self._emit(t, t))
        p = self._turn(wrap(target[2] - self.pose[2]))
        if p:
            out.append(p)
        if not out:
            out.append(self._emit(0, 0))
        return out


def resample(ranges: Sequence[float], n: int) -> List[float]:
    """``m`` beams to ``n`` readings at the beams' own angles.

    n == m: unchanged.  Otherwise the beams are taken as CARMEN lays them out
    and rsm-nav reads them (beam i at i*180/m deg from the right; 180 beams at
    1 deg) and reading j of the LMS scan (at j*180/(n-1) deg) is the beam at
    exactly that angle, or NaN ("no valid measurement") when no beam is there:
    the 181st reading of a 1-degree scan, the odd readings of a half-degree
    one.  Every reading is a real measurement at its true bearing.
    """
    m = len(ranges)
    if n == m:
        return list(ranges)
    out = []
    for j in range(n):
        num = j * m  # beam index j*m/(n-1), when it is a whole beam
        i, rem = divmod(num, n - 1)
        out.append(ranges[i] if rem == 0 and i < m else float("nan"))
    return out


def valid_reading(r: float) -> bool:
    return math.isfinite(r) and r > 0.0


def pick_units(longest: float) -> str:
    """The finer unit that carries ``longest`` metres: mm up to 8.182 m, else cm."""
    return "mm" if proto.range_to_raw(longest, "mm") != proto.LMS_TOO_FAR else "cm"


def monotonic_stamps(stamps: Sequence[int]) -> List[int]:
    """Non-decreasing stamps that change as few of ``stamps`` as possible.

    The longest non-decreasing subsequence keeps its stamps; each other
    stamp is interpolated linearly (by position, rounded down) between the
    kept stamps before and after it, or takes the nearest kept stamp at
    either end.  A negative stamp is never kept (a capture cannot hold it);
    with no usable stamp at all every stamp becomes 0.  O(n log n).
    """
    n = len(stamps)
    if n == 0:
        return []
    if all(t < 0 for t in stamps):
        return [0] * n
    tails: List[int] = []      # tails[k]: index ending the best run of length k + 1
    tail_vals: List[int] = []
    prev = [-1] * n
    for i, t in enumerate(stamps):
        if t < 0:
            continue
        k = bisect.bisect_right(tail_vals, t)
        prev[i] = tails[k - 1] if k > 0 else -1
        if k == len(tails):
            tails.append(i)
            tail_vals.append(t)
        else:
            tails[k] = i
            tail_vals[k] = t
    keep = [False] * n
    i = tails[-1]
    while i >= 0:
        keep[i] = True
        i = prev[i]
    out = list(stamps)
    kept = [i for i in range(n) if keep[i]]
    j = 0  # kept[j] is the first kept index >= i
    for i in range(kept[-1] + 1):
        while kept[j] < i:
            j += 1
        if keep[i]:
            continue
        b = kept[j]
        a = kept[j - 1] if j > 0 else None
        if a is None:
            out[i] = stamps[b]
        else:
            out[i] = stamps[a] + (stamps[b] - stamps[a]) * (i - a) // (b - a)
    for i in range(kept[-1] + 1, n):
        out[i] = stamps[kept[-1]]
    return out


def spread_stamps(stamps: Sequence[int], min_gap_us: int) -> List[int]:
    """Non-decreasing ``stamps`` moved later where needed so that records are
    at least ``min_gap_us`` apart (0: unchanged).

    The logger stamped some runs of records within a millisecond although
    they are a robot cycle apart; two serial links do not keep the order of
    bytes written that close together, so a replay would mix the robot's and
    the laser's records up.  A record is never moved earlier, and the
    stamps catch up with the log at the next pause.
    """
    out: List[int] = []
    for t in stamps:
        if out and t < out[-1] + min_gap_us:
            t = out[-1] + min_gap_us
        out.append(t)
    return out


@dataclass
class ConvertStats:
    odom: int = 0
    scans: int = 0
    clamped: int = 0
    clamped_scans: int = 0
    max_clamp_us: int = 0
    split: int = 0
    packets: int = 0
    empty_scans: int = 0       # FLASER lines with no readings: odometry only, no telegram
    log: Optional[LogStats] = None
    units: str = "mm"
    longest_m: float = 0.0    # the longest valid reading of the log
    limit_m: float = 0.0      # the longest range sent: the unit's limit or --max-range
    too_far: int = 0          # valid readings beyond limit_m, sent as "too far"
    lidar: Optional[str] = None  # ld06 or rplidar: the laser is a spinning lidar
    turns: Optional[lidarstream.TurnStats] = None

    def summary(self) -> str:
        if self.lidar is not None:
            t = self.turns or lidarstream.TurnStats()
            return (f"{self.odom} ODOM + {self.scans} FLASER -> {self.packets} ENCODER packets and "
                    f"{self.scans - self.empty_scans} {self.lidar} turns; of {t.beams} beams {t.returns} "
                    f"sent, {t.no_return} without a return, {t.too_far} too far for the protocol, "
                    f"{t.unplaced} at no whole-degree bearing; {self.clamped} timestamps re-placed")
        text = (f"{self.odom} ODOM + {self.scans} FLASER -> {self.packets} ENCODER "
                f"packets and {self.scans - self.empty_scans} 0xB0 telegrams in {self.units} (longest "
                f"reading {self.longest_m:.3f} m); {self.clamped} timestamps re-placed "
                f"({self.clamped_scans} of scans, moved by at most {self.max_clamp_us / 1e6:.6f} s); "
                f"{self.split} odometry steps sent as 3 packets (sideways motion)")
        if self.empty_scans:
            text += f"; {self.empty_scans} FLASER lines without readings sent as odometry only"
        if self.log is not None:
            skipped = {k: v for k, v in self.log.records.items() if k not in ("ODOM", "FLASER")}
            if skipped:
                text += "; not converted (only ODOM and FLASER are): " + ", ".join(
                    f"{v} {k}" for k, v in sorted(skipped.items()))
            if self.log.malformed:
                text += "; malformed lines skipped: " + ", ".join(
                    f"{k}={v}" for k, v in sorted(self.log.malformed.items()))
                text += "".join(f"\n  line {n} ({kind}): {why}" for n, kind, why in self.log.examples[:5])
        return text

    def warning(self) -> Optional[str]:
        """The loud line about readings that could not be kept, or None."""
        if self.lidar is not None:
            t = self.turns
            if t is None or t.too_far + t.unplaced == 0:
                return None
            return (f"WARNING: {t.too_far} readings too far for {self.lidar} distances and {t.unplaced} "
                    f"beams at no whole-degree bearing were not sent")
        if self.too_far == 0:
            return None
        return (f"WARNING: {self.too_far} readings longer than {self.limit_m:.3f} m (the most that "
                f"{self.units} units{' and --max-range' if self.limit_m < UNIT_LIMIT_M[self.units] else ''} "
                f"carry) sent as 'value larger than the maximum' (0x1FF7); the longest was "
                f"{self.longest_m:.3f} m")


def pick_readings(beams: int) -> int:
    """The telegram size that keeps every beam of a log whose scans have at
    most ``beams`` beams: 361 (0.5 deg) past 181 beams, else 181 (1 deg, the
    181st reading of a 180-beam CARMEN scan sent as no value)."""
    return 361 if beams > 181 else 181


def convert(log, out, units: str = "auto", readings: Union[int, str] = "auto",
            ticks_per_m: float = DEFAULT_TICKS_PER_M, wheel_base: float = DEFAULT_WHEEL_BASE,
            max_range: Optional[float] = None, start_ticks: int = 0,
            ground_truth: Optional[str] = None, min_gap_us: int = DEFAULT_MIN_GAP_US,
            lidar: Optional[str] = None, lidar_hz: float = 10.0) -> ConvertStats:
    """Convert the CARMEN log ``log`` to the capture ``out``; returns the counts.

    units "auto" picks mm or cm by the longest valid reading (:func:`pick_units`);
    max_range None sends every reading the unit carries.  lidar "ld06" or
    "rplidar" renders the scans as that spinning lidar's stream instead of LMS
    telegrams, one turn per scan lasting at most 1 / lidar_hz seconds."""
    if lidar is not None and (lidar not in lidarstream.BAUD or not lidar_hz > 0.0):
        raise ValueError("lidar must be ld06 or rplidar, with a positive lidar_hz")
    if readings not in (180, 181, 361, "auto"):
        raise ValueError("readings must be 180, 181, 361 or auto")
    if units not in ("auto", "mm", "cm"):
        raise ValueError("units must be auto, mm or cm")
    st = ConvertStats(log=LogStats())
    recs = [r for r in read_log(log, types=("ODOM", "FLASER"), stats=st.log)]
    valid = [x for r in recs if isinstance(r, FLaser) for x in r.ranges if valid_reading(x)]
    st.longest_m = max(valid, default=0.0)
    if readings == "auto":
        # Keep what the log has, as units auto keeps its range (issue 30: a
        # 361-beam log lost every other beam to the default of 181).
        readings = pick_readings(max((len(r.ranges) for r in recs if isinstance(r, FLaser)), default=180))
    st.units = pick_units(st.longest_m) if units == "auto" else units
    units = st.units
    st.limit_m = UNIT_LIMIT_M[units] if max_range is None else min(max_range, UNIT_LIMIT_M[units])
    # what range_to_raw sends as "too far", counted without encoding every reading
    scale = proto._UNIT_SCALE[units]
    cut = math.inf if max_range is None else max_range
    st.too_far = sum(1 for x in valid if x > cut or round(x / scale) > proto.LMS_MAX_VALUE)
    # pass 1: monotonic timestamps (the table of re-placed ones goes into the header)
    clamped_lines = []
    original = [time_key(r.timestamp) for r in recs]
    stamps = spread_stamps(monotonic_stamps(original), min_gap_us)
    counters = {"ODOM": 0, "FLASER": 0}
    for r, t, w in zip(recs, original, stamps):
        idx = counters[r.kind]
        counters[r.kind] += 1
        if w != t:
            st.clamped += 1
            st.max_clamp_us = max(st.max_clamp_us, abs(w - t))
            if r.kind == "FLASER":
                st.clamped_scans += 1
            clamped_lines.append(f"{r.kind} {idx} {t} {w}")
    first = next((r.odom_pose if isinstance(r, FLaser) else r.pose for r in recs), (0.0, 0.0, 0.0))
    meta = {
        "source": os.path.basename(str(log)),
        "created_by": "rsm-convert",
        "robot.model": "p3dx-sh",
        "robot.ticks_per_m": repr(float(ticks_per_m)),
        "robot.wheel_base_m": repr(float(wheel_base)),
        "robot.kinematics": "midpoint",
        "robot.initial_pose": " ".join(repr(v) for v in first),
        "robot.start_ticks": str(start_ticks),
        "laser.model": "lms2xx",
        "laser.units": units,
        "laser.readings": str(readings),
        "laser.fov_deg": "180",
        "laser.measuring_mode": "0x00",
        "laser.max_range_m": repr(float(st.limit_m)),
        "laser.resampling": "none" if readings == 180 else "the beam at each reading's angle (beam i at i deg), "
                                                           "else no value",
        "convert.longest_m": repr(float(st.longest_m)),
        "convert.too_far": str(st.too_far),
        "convert.clamped_total": str(st.clamped),
        "convert.clamped": "\n".join(clamped_lines),
    }
    if ground_truth:
        meta["ground_truth"] = ground_truth
    channels = [cap.Channel(ROBOT, "robot", "aria", 38400), cap.Channel(LASER, "laser", "lms2xx", 38400)]
    if lidar is not None:
        for k in ("laser.units", "laser.readings", "laser.fov_deg", "laser.measuring_mode",
                  "laser.max_range_m", "laser.resampling", "convert.too_far"):
            del meta[k]
        meta.update({
            "laser.model": lidar,
            "laser.readings": str(lidarstream.POINTS_PER_TURN),
            "laser.turn_hz": repr(float(lidar_hz)),
            "laser.clockwise": "1",
            "laser.resampling": "each beam at the sensor angle of its bearing (beam i of m at "
                                "90 - i * 180 / m deg clockwise), else no return",
        })
        channels[LASER] = cap.Channel(LASER, "lidar", "raw", lidarstream.BAUD[lidar])
        st.lidar = lidar
        st.turns = lidarstream.TurnStats()
    # pass 2: tick counts (the split steps also go into the header)
    enc = TickEncoder(first, ticks_per_m, wheel_base, start_ticks)
    packets = []
    split = []
    for i, r in enumerate(recs):
        counts = enc.step(r.odom_pose if isinstance(r, FLaser) else r.pose)
        if len(counts) > 1:
            split.append(f"{i}:{len(counts)}")
        packets.append(counts)
    st.split = enc.splits
    meta["convert.split_steps"] = " ".join(split)
    if lidar is not None:
        _write_lidar_capture(out, channels, meta, recs, stamps, packets, st, lidar, lidar_hz)
        return st
    with cap.CaptureWriter(out, channels, meta) as w:
        for r, t, counts in zip(recs, stamps, packets):
            for lr in counts:
                w.write(t, ROBOT, proto.encode_encoder(*lr))
                st.packets += 1
            if isinstance(r, Odom):
                st.odom += 1
            else:
                st.scans += 1
                if not r.ranges:
                    st.empty_scans += 1  # no telegram can say "no readings"
                    continue
                rng = resample(r.ranges, readings)
                w.write(t, LASER, proto.encode_b0_ranges(rng, units, max_range))
    return st


def _write_lidar_capture(out, channels, meta, recs, stamps, packets, st: ConvertStats, lidar: str,
                         lidar_hz: float) -> None:
    """The records of a --lidar conversion, in time order: a turn's packets
    begin before the scan's stamp, so they interleave with earlier odometry."""
    turn_us = int(round(1e6 / lidar_hz))
    rows = []  # (time, order, channel, bytes)
    prev_scan = None
    scan_at = [t for r, t in zip(recs, stamps) if isinstance(r, FLaser) and r.ranges]
    k = 0
    for r, t, counts in zip(recs, stamps, packets):
        for lr in counts:
            rows.append((t, len(rows), ROBOT, proto.encode_encoder(*lr)))
            st.packets += 1
        if isinstance(r, Odom):
            st.odom += 1
            continue
        st.scans += 1
        if not r.ranges:
            st.empty_scans += 1
            continue
        # Centred on the scan's stamp (the assembler stamps a turn with its
        # middle), and no longer than the time to either neighbour: turns
        # never overlap.
        k += 1
        nxt = scan_at[k] if k < len(scan_at) else None
        span = turn_us
        for gap in ((t - prev_scan) if prev_scan is not None else None, (nxt - t) if nxt is not None else None):
            if gap is not None:
                span = min(span, gap)
        span = max(POINTS_MIN_US, span)
        prev_scan = t
        end = t + int(round(span * (lidarstream.POINTS_PER_TURN - 1) / (2 * lidarstream.POINTS_PER_TURN)))
        for at, data in lidarstream.render_turn(lidar, r.ranges, end, span, st.turns):
            rows.append((at, len(rows), LASER, data))
    rows.sort(key=lambda row: (row[0], row[1]))
    if lidar == "rplidar" and rows:
        first = next((row[0] for row in rows if row[2] == LASER), rows[0][0])
        rows.insert(0, (max(0, first - 1), -1, LASER, lidarstream.RPLIDAR_SCAN_DESCRIPTOR))
        rows.sort(key=lambda row: (row[0], row[1]))
    with cap.CaptureWriter(out, channels, meta) as w:
        for at, _order, ch, data in rows:
            w.write(at, ch, data)


def original_scan_stamps(path) -> List[int]:
    """Stamps (us) of the scans of a capture made by rsm-convert, as the log had
    them: one per laser record, with the stamps the converter moved restored
    from ``convert.clamped``."""
    header, records, _ = cap.read_capture(path)
    laser = header.channel("laser").id
    stamps = [r.timestamp for r in records if r.channel == laser and r.is_rx]
    for line in header.metadata.get("convert.clamped", "").splitlines():
        kind, idx, orig, _written = line.split()
        if kind == "FLASER" and int(idx) < len(stamps):
            stamps[int(idx)] = int(orig)
    return stamps


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-convert", description=__doc__.split("\n\n")[0])
    ap.add_argument("log", help="CARMEN log (plain or gzip)")
    ap.add_argument("out", help="capture file to write")
    ap.add_argument("--units", choices=("auto", "mm", "cm"), default="auto",
                    help="range unit of the 0xB0 telegrams; auto (default): mm when the log's longest valid "
                         "reading fits in 8.182 m, else cm (81.82 m)")
    ap.add_argument("--readings", choices=("auto", "180", "181", "361"), default="auto",
                    help="readings per LMS scan telegram; auto (default): 361 (180 deg at 0.5 deg) when the "
                         "log's scans have more than 181 beams, else 181 (at 1 deg)")
    ap.add_argument("--ticks-per-m", type=float, default=DEFAULT_TICKS_PER_M,
                    help=f"encoder ticks per metre of the encoder packets (default {DEFAULT_TICKS_PER_M:g})")
    ap.add_argument("--wheel-base", type=float, default=DEFAULT_WHEEL_BASE,
                    help=f"wheel base in metres the ticks are made with (default {DEFAULT_WHEEL_BASE:g})")
    ap.add_argument("--max-range", type=float, default=None,
                    help="longer ranges are sent as the LMS 'too far' code 0x1FF7 (default: only those the "
                         "unit cannot carry); every such reading is counted and reported")
    ap.add_argument("--min-gap-ms", type=float, default=DEFAULT_MIN_GAP_US / 1000.0,
                    help="least time between two records, so a replay keeps their order "
                         f"(default {DEFAULT_MIN_GAP_US / 1000.0:g}; 0 keeps the log's stamps)")
    ap.add_argument("--start-ticks", type=int, default=0,
                    help="initial value of both tick counters (wraps modulo 2^32)")
    ap.add_argument("--ground-truth", help="name of a ground-truth file to note in the metadata")
    ap.add_argument("--lidar", choices=sorted(lidarstream.BAUD),
                    help="render the scans as this spinning lidar's stream (channel 'lidar') "
                         "instead of LMS telegrams")
    ap.add_argument("--lidar-hz", type=float, default=10.0,
                    help="turns per second of the rendered lidar (default 10)")
    a = ap.parse_args(argv)
    if not a.lidar_hz > 0:
        ap.error("--lidar-hz must be positive")
    if a.min_gap_ms < 0:
        ap.error("--min-gap-ms must not be negative")
    if a.ticks_per_m <= 0 or a.wheel_base <= 0 or (a.max_range is not None and a.max_range <= 0):
        ap.error("--ticks-per-m, --wheel-base and --max-range must be positive")
    try:
        st = convert(a.log, a.out, a.units, a.readings if a.readings == "auto" else int(a.readings),
                     a.ticks_per_m, a.wheel_base,
                     a.max_range, a.start_ticks, a.ground_truth, int(round(a.min_gap_ms * 1000.0)),
                     a.lidar, a.lidar_hz)
    except (OSError, EOFError, zlib.error) as exc:
        # A truncated or corrupt gzip log ends in EOFError or zlib.error.
        print(f"rsm-convert: cannot read {a.log} to the end: {exc or type(exc).__name__}", file=sys.stderr)
        return 1
    print(f"rsm-convert: {st.summary()}", file=sys.stderr)
    warning = st.warning()
    if warning:
        print(f"rsm-convert: {warning}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
