"""Streaming reader and writer for CARMEN text logs.

A CARMEN log has one record per line with whitespace-separated fields.  This
module understands three record types (units: metres, radians, seconds)::

    ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
    FLASER n r_1 .. r_n  x y theta  odom_x odom_y odom_theta
           ipc_timestamp ipc_hostname logger_timestamp
    ROBOTLASER1 laser_type start_angle fov angular_res max_range accuracy
           remission_mode n r_1 .. r_n m rem_1 .. rem_m
           laser_x laser_y laser_theta robot_x robot_y robot_theta
           tv rv forward_safety side_safety turn_axis
           ipc_timestamp ipc_hostname logger_timestamp

The reader never raises on bad input.  Every line falls in exactly one of
these buckets, counted in :class:`LogStats`:

* a parsed record (``records[type]``);
* a comment (first non-blank character ``#``) or a blank line;
* an unknown record type (``unknown[keyword]``), skipped;
* a malformed line of a known type (``malformed[reason]``), skipped.  The
  reasons are:

  ``field_count``
      the number of fields does not match the reading counts;
  ``bad_count``
      a reading count (``n``, ``m``) or an integer field (``laser_type``,
      ``remission_mode``) is not a non-negative integer written in decimal
      digits alone (``0x10``, ``16.0``, ``+16`` are not);
  ``non_numeric``
      a field that must be a number is not one in decimal (``0x10`` and
      ``1_000`` are not; ``inf`` and ``nan`` are numbers);
  ``non_finite``
      NaN or infinity in a field where it is not allowed.  Only range and
      remission readings may be non-finite (some drivers write ``inf`` or
      ``nan`` for "no return"); poses, velocities, angles and timestamps
      may not.

The laser's mount (its pose in the robot frame, x forward, y left, theta
counter-clockwise) is ``mount`` on a scan record: the laser pose seen from the
robot pose of the same line.  ROBOTLASER1 always carries it.  A FLASER line
carries it only when its two triples differ: CARMEN writes the odometry pose
composed with the laser offset in the first, but logs rebuilt without it (the
Intel and ACES logs) repeat the odometry pose there, which says nothing about
the mount, so ``mount`` is None for them.  rsm-nav reads it the same way.

The writer formats ODOM, FLASER and ROBOTLASER1 records with fixed decimals
(6 for poses, velocities and timestamps, 2 for ranges by default), so a line
printed with those precisions is reproduced exactly by ``format_record``.
"""

import math
import re
from collections import Counter
from dataclasses import dataclass, field
from typing import IO, Iterable, Iterator, List, Optional, Sequence, Tuple, Union

from .fileio import PathLike, open_text

Pose = Tuple[float, float, float]


def pose_in_frame(frame: Pose, pose: Pose) -> Pose:
    """``pose`` seen from ``frame`` (both in one frame): R(-t) (p - f), angle wrapped."""
    dx, dy = pose[0] - frame[0], pose[1] - frame[1]
    c, s = math.cos(frame[2]), math.sin(frame[2])
    dt = pose[2] - frame[2]
    return (c * dx + s * dy, -s * dx + c * dy, math.atan2(math.sin(dt), math.cos(dt)))


def pose_compose(a: Pose, b: Pose) -> Pose:
    """``b`` (given in ``a``'s frame) in the frame ``a`` is given in; angle wrapped."""
    c, s = math.cos(a[2]), math.sin(a[2])
    t = a[2] + b[2]
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], math.atan2(math.sin(t), math.cos(t)))


@dataclass
class Odom:
    """An ``ODOM`` record: raw wheel odometry."""

    x: float
    y: float
    theta: float
    tv: float
    rv: float
    accel: float
    timestamp: float
    host: str
    logger_timestamp: float
    lineno: int = field(default=0, compare=False)

    kind = "ODOM"

    @property
    def pose(self) -> Pose:
        return (self.x, self.y, self.theta)


@dataclass
class FLaser:
    """A ``FLASER`` record: a front laser scan with the poses at scan time."""

    ranges: List[float]
    laser_pose: Pose
    odom_pose: Pose
    timestamp: float
    host: str
    logger_timestamp: float
    lineno: int = field(default=0, compare=False)

    kind = "FLASER"

    @property
    def num_readings(self) -> int:
        return len(self.ranges)

    @property
    def mount(self) -> Optional[Pose]:
        """The laser's pose in the robot frame, or None when the two triples
        are equal (then the line says nothing about the mount)."""
        if self.laser_pose == self.odom_pose:
            return None
        return pose_in_frame(self.odom_pose, self.laser_pose)


@dataclass
class RobotLaser1:
    """A ``ROBOTLASER1`` record: a laser scan with its geometry and the robot state."""

    laser_type: int
    start_angle: float
    fov: float
    angular_res: float
    max_range: float
    accuracy: float
    remission_mode: int
    ranges: List[float]
    remissions: List[float]
    laser_pose: Pose
    robot_pose: Pose
    tv: float
    rv: float
    forward_safety: float
    side_safety: float
    turn_axis: float
    timestamp: float
    host: str
    logger_timestamp: float
    lineno: int = field(default=0, compare=False)

    kind = "ROBOTLASER1"

    @property
    def num_readings(self) -> int:
        return len(self.ranges)

    @property
    def odom_pose(self) -> Pose:
        """The robot pose, which CARMEN fills from odometry."""
        return self.robot_pose

    @property
    def mount(self) -> Pose:
        """The laser's pose in the robot frame."""
        return pose_in_frame(self.robot_pose, self.laser_pose)


Record = Union[Odom, FLaser, RobotLaser1]

SCAN_TYPES = ("FLASER", "ROBOTLASER1")
KNOWN_TYPES = ("ODOM",) + SCAN_TYPES

# For the tools that rewrite a log's lines as bytes and keep every field they
# do not change as it was written (rsm-outliers, rsm-faults).
SCAN_KEYS = tuple(t.encode("ascii") for t in SCAN_TYPES)
TOKEN = re.compile(rb"\S+")


def token_decimals(tok: bytes) -> int:
    """The digits after a number's decimal point as written (0 without one):
    a value written again keeps its field's precision."""
    dot = tok.find(b".")
    if dot < 0:
        return 0
    if tok[dot + 1:].isdigit():
        return len(tok) - dot - 1
    end = dot + 1
    while end < len(tok) and tok[end:end + 1].isdigit():
        end += 1
    return end - dot - 1


@dataclass
class LogStats:
    """What a pass over a log saw, line by line."""

    lines: int = 0
    blank: int = 0
    comments: int = 0
    records: Counter = field(default_factory=Counter)
    unknown: Counter = field(default_factory=Counter)
    malformed: Counter = field(default_factory=Counter)
    #: the first few malformed lines as (line number, record type, reason)
    examples: List[Tuple[int, str, str]] = field(default_factory=list)
    max_examples: int = 20

    @property
    def malformed_total(self) -> int:
        return sum(self.malformed.values())

    @property
    def unknown_total(self) -> int:
        return sum(self.unknown.values())

    def summary(self) -> str:
        parts = [f"{self.lines} lines"]
        for kind in KNOWN_TYPES:
            if self.records.get(kind):
                parts.append(f"{self.records[kind]} {kind}")
        parts.append(f"{self.comments} comments")
        if self.blank:
            parts.append(f"{self.blank} blank")
        if self.unknown:
            parts.append(
                "unknown: " + ", ".join(f"{k}={v}" for k, v in sorted(self.unknown.items()))
            )
        if self.malformed:
            parts.append(
                "malformed: " + ", ".join(f"{k}={v}" for k, v in sorted(self.malformed.items()))
            )
        return "; ".join(parts)


class MalformedLine(ValueError):
    """Raised inside the parser; carries one of the documented reasons."""

    def __init__(self, reason: str, detail: str = "") -> None:
        super().__init__(f"{reason}: {detail}" if detail else reason)
        self.reason = reason


_FIELD_SEP = re.compile(r"[ \t\r\n]+")


def split_fields(line: str) -> List[str]:
    """The fields of a line, split at ASCII spaces, tabs, CRs and LFs only,
    as rsm-nav's reader splits them: str.split() would also split at the
    other Unicode whitespace (no-break space, form feed, ...), where rsm-nav
    sees one field."""
    body = line.strip(" \t\r\n")
    return _FIELD_SEP.split(body) if body else []


def _num(tok: str, finite: bool = True) -> float:
    # Decimal, as rsm-nav's reader takes it: float() alone would also take
    # 1_000, digits of other scripts and whitespace around the number (a
    # form feed inside a field).
    if "_" in tok or not tok.isascii() or not tok.isprintable():
        raise MalformedLine("non_numeric", repr(tok))
    try:
        v = float(tok)
    except ValueError:
        raise MalformedLine("non_numeric", repr(tok)) from None
    if finite and not math.isfinite(v):
        raise MalformedLine("non_finite", repr(tok))
    return v


def _count(tok: str) -> int:
    # Decimal digits only, as CARMEN writes a count (%d) and rsm-nav's reader
    # takes it: int() alone would also take +16, 1_6 and digits of other
    # scripts (0x10 and 16.0 it refuses, as it should).
    if not (tok.isascii() and tok.isdigit()):
        raise MalformedLine("bad_count", repr(tok))
    return int(tok)


def _pose(tokens: Sequence[str], i: int) -> Pose:
    return (_num(tokens[i]), _num(tokens[i + 1]), _num(tokens[i + 2]))


def _parse_odom(t: Sequence[str], lineno: int) -> Odom:
    if len(t) != 10:
        raise MalformedLine("field_count", f"ODOM needs 10 fields, got {len(t)}")
    x, y, th, tv, rv, acc, ts = (_num(v) for v in t[1:8])
    return Odom(x, y, th, tv, rv, acc, ts, t[8], _num(t[9]), lineno)


def _parse_flaser(t: Sequence[str], lineno: int) -> FLaser:
    if len(t) < 2:
        raise MalformedLine("field_count", "FLASER without a reading count")
    n = _count(t[1])
    if len(t) != 11 + n:
        raise MalformedLine("field_count", f"FLASER with n={n} needs {11 + n} fields, got {len(t)}")
    ranges = [_num(v, finite=False) for v in t[2 : 2 + n]]
    i = 2 + n
    laser = _pose(t, i)
    odom = _pose(t, i + 3)
    ts = _num(t[i + 6])
    return FLaser(ranges, laser, odom, ts, t[i + 7], _num(t[i + 8]), lineno)


def _parse_robotlaser1(t: Sequence[str], lineno: int) -> RobotLaser1:
    # keyword + 7 header fields + n
    if len(t) < 9:
        raise MalformedLine("field_count", "ROBOTLASER1 header too short")
    laser_type = _count(t[1])
    start_angle, fov, res, max_range, accuracy = (_num(v) for v in t[2:7])
    remission_mode = _count(t[7])
    n = _count(t[8])
    j = 9 + n  # index of m
    if len(t) <= j:
        raise MalformedLine("field_count", f"ROBOTLASER1 with n={n} is too short")
    m = _count(t[j])
    want = 24 + n + m
    if len(t) != want:
        raise MalformedLine(
            "field_count", f"ROBOTLASER1 with n={n}, m={m} needs {want} fields, got {len(t)}"
        )
    ranges = [_num(v, finite=False) for v in t[9:j]]
    remissions = [_num(v, finite=False) for v in t[j + 1 : j + 1 + m]]
    i = j + 1 + m
    laser = _pose(t, i)
    robot = _pose(t, i + 3)
    tv, rv, fwd, side, turn = (_num(v) for v in t[i + 6 : i + 11])
    ts = _num(t[i + 11])
    return RobotLaser1(
        laser_type, start_angle, fov, res, max_range, accuracy, remission_mode,
        ranges, remissions, laser, robot, tv, rv, fwd, side, turn,
        ts, t[i + 12], _num(t[i + 13]), lineno,
    )


_PARSERS = {
    "ODOM": _parse_odom,
    "FLASER": _parse_flaser,
    "ROBOTLASER1": _parse_robotlaser1,
}


def parse_tokens(tokens: Sequence[str], lineno: int = 0) -> Record:
    """Parse the fields of one known record; raises :class:`MalformedLine`."""
    return _PARSERS[tokens[0]](tokens, lineno)


def parse_line(line: str, lineno: int = 0) -> Optional[Record]:
    """Parse one line.

    Returns the record, or None for a blank line, a comment or an unknown
    record type.  A malformed line of a known type raises
    :class:`MalformedLine` (whose ``reason`` is one of the documented ones).
    """
    tokens = split_fields(line)
    if not tokens or tokens[0].startswith("#") or tokens[0] not in _PARSERS:
        return None
    return parse_tokens(tokens, lineno)


class LogReader:
    """Iterate over the records of a CARMEN log, counting everything else.

    ``source`` is a path (plain or gzip, detected by magic bytes) or an
    iterable of text lines (e.g. an open text file or a list of strings).
    ``types`` optionally restricts which record types are parsed and
    yielded; lines of the other known types are still counted in
    ``stats.records`` but are not checked for well-formedness.

    The statistics in :attr:`stats` are complete once iteration has ended.
    """

    def __init__(
        self,
        source: Union[PathLike, Iterable[str]],
        types: Optional[Iterable[str]] = None,
        stats: Optional[LogStats] = None,
    ) -> None:
        self.source = source
        self.types = None if types is None else frozenset(types)
        if self.types is not None:
            bad = self.types - set(_PARSERS)
            if bad:
                raise ValueError(f"unknown record types requested: {sorted(bad)}")
        self.stats = stats if stats is not None else LogStats()

    def __iter__(self) -> Iterator[Record]:
        if isinstance(self.source, (str, bytes)) or hasattr(self.source, "__fspath__"):
            # lines end at LF alone, as rsm-nav reads them (a lone CR separates fields)
            with open_text(self.source, newline="\n") as fh:  # type: ignore[arg-type]
                yield from self._records(fh)
        else:
            yield from self._records(self.source)  # type: ignore[arg-type]

    def _records(self, lines: Iterable[str]) -> Iterator[Record]:
        st = self.stats
        wanted = self.types
        for lineno, line in enumerate(lines, start=1):
            st.lines += 1
            tokens = split_fields(line)
            if not tokens:
                st.blank += 1
                continue
            key = tokens[0]
            if key.startswith("#"):
                st.comments += 1
                continue
            parser = _PARSERS.get(key)
            if parser is None:
                st.unknown[key] += 1
                continue
            if wanted is not None and key not in wanted:
                st.records[key] += 1
                continue
            try:
                rec = parser(tokens, lineno)
            except MalformedLine as exc:
                st.malformed[exc.reason] += 1
                if len(st.examples) < st.max_examples:
                    st.examples.append((lineno, key, str(exc)))
                continue
            st.records[key] += 1
            yield rec


def read_log(
    source: Union[PathLike, Iterable[str]],
    types: Optional[Iterable[str]] = None,
    stats: Optional[LogStats] = None,
) -> Iterator[Record]:
    """Generator over the records of a log; pass ``stats`` to collect counts."""
    return iter(LogReader(source, types=types, stats=stats))


def first_scan_after_motion(source: Union[PathLike, Iterable[str]]) -> int:
    """The index (from 0) of the first FLASER scan whose odometry (any ODOM or
    FLASER pose since the first record) differs from the first pose: the
    scans before it saw the robot standing still.  The scan count if none."""
    scan, first, moved = -1, None, False
    for r in read_log(source, types=("ODOM", "FLASER")):
        pose = r.odom_pose if isinstance(r, FLaser) else r.pose
        first = pose if first is None else first
        moved = moved or pose != first
        if isinstance(r, FLaser):
            scan += 1
            if moved:
                return scan
    return scan + 1


# ---------------------------------------------------------------------------
# writer


def _f(v: float, decimals: int) -> str:
    return f"{v:.{decimals}f}"


def format_odom(rec: Odom, decimals: int = 6) -> str:
    vals = (rec.x, rec.y, rec.theta, rec.tv, rec.rv, rec.accel, rec.timestamp)
    return " ".join(
        ["ODOM"] + [_f(v, decimals) for v in vals] + [rec.host, _f(rec.logger_timestamp, decimals)]
    )


def format_flaser(rec: FLaser, range_decimals: int = 2, decimals: int = 6) -> str:
    parts = ["FLASER", str(len(rec.ranges))]
    parts += [_f(r, range_decimals) for r in rec.ranges]
    parts += [_f(v, decimals) for v in rec.laser_pose]
    parts += [_f(v, decimals) for v in rec.odom_pose]
    parts += [_f(rec.timestamp, decimals), rec.host, _f(rec.logger_timestamp, decimals)]
    return " ".join(parts)


def format_robotlaser1(
    rec: RobotLaser1, range_decimals: int = 2, remission_decimals: int = 2, decimals: int = 6
) -> str:
    parts = ["ROBOTLASER1", str(rec.laser_type)]
    parts += [_f(v, decimals) for v in (rec.start_angle, rec.fov, rec.angular_res,
                                          rec.max_range, rec.accuracy)]
    parts += [str(rec.remission_mode), str(len(rec.ranges))]
    parts += [_f(r, range_decimals) for r in rec.ranges]
    parts.append(str(len(rec.remissions)))
    parts += [_f(r, remission_decimals) for r in rec.remissions]
    parts += [_f(v, decimals) for v in rec.laser_pose]
    parts += [_f(v, decimals) for v in rec.robot_pose]
    parts += [_f(v, decimals) for v in (rec.tv, rec.rv, rec.forward_safety,
                                          rec.side_safety, rec.turn_axis)]
    parts += [_f(rec.timestamp, decimals), rec.host, _f(rec.logger_timestamp, decimals)]
    return " ".join(parts)


def format_record(rec: Record, range_decimals: int = 2, decimals: int = 6) -> str:
    """One log line for ``rec`` (without the line end)."""
    if isinstance(rec, Odom):
        return format_odom(rec, decimals)
    if isinstance(rec, FLaser):
        return format_flaser(rec, range_decimals, decimals)
    if isinstance(rec, RobotLaser1):
        return format_robotlaser1(rec, range_decimals, range_decimals, decimals)
    raise TypeError(f"not a CARMEN record: {type(rec).__name__}")


class LogWriter:
    """Write records (and comments) as CARMEN lines to a text stream."""

    def __init__(self, stream: IO[str], range_decimals: int = 2, decimals: int = 6) -> None:
        self.stream = stream
        self.range_decimals = range_decimals
        self.decimals = decimals

    def comment(self, text: str) -> None:
        for line in text.splitlines() or [""]:
            self.stream.write(f"# {line}".rstrip() + "\n")

    def write(self, rec: Record) -> None:
        self.stream.write(format_record(rec, self.range_decimals, self.decimals) + "\n")

    def write_all(self, records: Iterable[Record]) -> None:
        for rec in records:
            self.write(rec)


def time_key(t: float) -> int:
    """A timestamp as integer microseconds: the exact-match key used by the tools."""
    return int(round(t * 1e6))
