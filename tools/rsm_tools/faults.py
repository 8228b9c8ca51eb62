"""Deterministic odometry and sampling faults in a CARMEN log (rsm-faults).

A robustness test for the localizer's use of odometry and of the scan
stream: the tool copies a CARMEN log (plain or gzip) and breaks it in one or
more documented ways, the same bytes for the same arguments every run (gzip
output is written with mtime 0, as rsm-outliers does).  docs/faults.md says
what each fault does and how the bench uses them; in short:

``--stall N@S``
    odometry frozen on scans S..S+N-1 (each reports scan S-1's pose), then
    the whole motion in one step at scan S+N (stall, then catch-up).
``--stall-at-turns K --stall-len N``
    K such stalls of N scans, placed at the K strongest turns of the log's
    odometry (the largest heading change over a stall), ``--stall-spacing``
    scans apart, each moved by up to ``--stall-jitter`` scans from the seed.
``--spike S:DX,DY,DTH``
    scan S's odometry displaced by (DX, DY, DTH) in the robot frame; the
    scans before and after it are unchanged.
``--reset S``
    the odometry counter restarts at zero at scan S: scan S reports
    (0, 0, 0) and every later pose is re-expressed relative to scan S's.
``--slip S:N``
    the wheels turn, the robot does not: N scans stand still at scan S's
    place (N-1 copies of scan S are inserted after it) while the odometry
    advances by the log's next N-1 steps; the rest of the log follows on
    from scan S's place, its odometry shifted by that phantom advance.
``--scale F``
    every odometry step's translation times F, headings unchanged.
``--every-m D`` / ``--every-rad R``
    a scan is kept only when the odometry moved D metres or turned R
    radians since the last kept one (a sparse recording).
``--drop P``, ``--gap S:T``
    P % of the scans dropped at random; every scan whose stamp lies S to
    S+T seconds after the log's first scan removed (a long gap).
``--kidnap S:T``
    the robot carried away: the scans (and ODOM lines) of S to S+T seconds
    removed as by ``--gap``, and the odometry from the first scan after the
    cut on re-expressed so that it reports no motion across the cut (that
    scan's pose is the last scan's before it; later steps unchanged).
``--mount X,Y,TH``
    the laser re-expressed as mounted at (X, Y, TH) on the robot: the
    ranges and the laser's world pose are kept, the robot's (odometry) pose
    is moved so that laser = robot (+) mount.  Run rsm-nav with
    ``--laser-pose X Y TH`` (it also reads the mount from the FLASER lines,
    whose two triples then differ).
``--start-offsets A,B,...``
    successive scans start these many degrees further on, in turn; a scan
    with a nonzero offset is written as a ROBOTLASER1 line (FLASER carries no
    start angle) whose readings are re-cast at the shifted angles.

Scan indices count the well-formed scan lines (FLASER and ROBOTLASER1) of
the input from 0.  Odometry is the pose each scan line carries (what rsm-nav
reads) and the ODOM lines, which are changed consistently with it.  Lines
the tool does not change are copied byte for byte; on a changed line only
the changed fields are rewritten (poses with the field's decimals, at least
6), except a line converted to ROBOTLASER1, which is written anew.
Malformed scan and ODOM lines are copied unchanged and counted, as
rsm-outliers does.  Each fault prints a one-line summary on stderr.
"""

import argparse
import hashlib
import io
import math
import random
import sys
from dataclasses import dataclass, field
from fractions import Fraction
from typing import IO, Dict, List, Optional, Sequence, Tuple

from .carmen import (SCAN_KEYS, TOKEN, MalformedLine, Pose, parse_tokens, pose_compose, pose_in_frame,
                     token_decimals)
from .fileio import PathLike, open_binary, open_binary_output
from .outliers import percent_argument

PROG = "rsm-faults"

# Tokens after the readings: laser pose, odometry pose, stamp, host, logger stamp
# (FLASER); laser pose, robot pose, tv, rv, two safeties, turn axis, stamp, host,
# logger stamp (ROBOTLASER1).
_TAIL = {b"FLASER": 9, b"ROBOTLASER1": 14}
_STAMP_IN_TAIL = {b"FLASER": 6, b"ROBOTLASER1": 11}

ZERO: Pose = (0.0, 0.0, 0.0)

# Two neighbouring readings are one surface (re-cast between them) when they
# differ by at most this much (metres, plus a share of the nearer one).
RECAST_TOL_M = 0.05
RECAST_TOL_REL = 0.25


class FaultError(ValueError):
    """A fault that does not fit this log (a bad argument for it: exit 2)."""


# ---------------------------------------------------------------------------
# geometry


def pose_inverse(p: Pose) -> Pose:
    c, s = math.cos(p[2]), math.sin(p[2])
    return (-(c * p[0] + s * p[1]), s * p[0] - c * p[1], -p[2])


def wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def step_size(a: Pose, b: Pose) -> Tuple[float, float]:
    """Distance and absolute heading change from a to b."""
    return math.hypot(b[0] - a[0], b[1] - a[1]), abs(wrap(b[2] - a[2]))


# ---------------------------------------------------------------------------
# the fault specification


@dataclass
class StallTurns:
    count: int
    length: int
    spacing: int = 50
    jitter: int = 0


@dataclass
class FaultSpec:
    """What to break; every list is applied in the order given below (the
    order of docs/faults.md): mount, resets, scale, stalls, spikes, slips,
    the kidnaps' odometry, then the selection of scans (every-m/rad, drop,
    gaps, the kidnaps' cuts), then offsets."""

    stalls: List[Tuple[int, int]] = field(default_factory=list)  # (length N, first scan S)
    stall_turns: Optional[StallTurns] = None
    spikes: List[Tuple[int, Pose]] = field(default_factory=list)
    resets: List[int] = field(default_factory=list)
    slips: List[Tuple[int, int]] = field(default_factory=list)  # (first scan S, scans N)
    scale: Optional[float] = None
    every_m: Optional[float] = None
    every_rad: Optional[float] = None
    drop: Optional[Fraction] = None  # percent
    gaps: List[Tuple[float, float]] = field(default_factory=list)  # (offset S s, length T s)
    kidnaps: List[Tuple[float, float]] = field(default_factory=list)  # (offset S s, length T s)
    mount: Optional[Pose] = None
    start_offsets: List[float] = field(default_factory=list)  # degrees
    seed: int = 0
    fov179: bool = False
    max_range: Optional[float] = None

    def empty(self) -> bool:
        return not (self.stalls or self.stall_turns or self.spikes or self.resets or self.slips
                    or self.scale is not None or self.every_m is not None or self.every_rad is not None
                    or self.drop is not None or self.gaps or self.kidnaps or self.mount is not None
                    or self.start_offsets)


def fault_rng(seed: int, what: str) -> random.Random:
    """The PRNG of one random choice, from the user seed and its name (SHA-256,
    so neither Python's hash randomisation nor the order of choices matters)."""
    digest = hashlib.sha256(f"rsm-faults:{seed}:{what}".encode("ascii")).digest()
    return random.Random(int.from_bytes(digest[:16], "big"))


# ---------------------------------------------------------------------------
# reading


@dataclass
class ScanInfo:
    __slots__ = ("line", "key", "n", "laser", "odom", "stamp", "logger", "same", "start", "step")
    line: int          # index of its line
    key: bytes         # FLASER or ROBOTLASER1
    n: int             # readings
    laser: Pose
    odom: Pose         # the robot's odometry pose
    stamp: float
    logger: float
    same: bool         # the laser triple's text equals the odometry triple's (no mount)
    start: Optional[float]  # ROBOTLASER1's start angle and step (FLASER: None)
    step: Optional[float]


@dataclass
class LoadedLog:
    """A CARMEN log held in memory: its lines and the odometry they carry.

    ``events`` are the ODOM and well-formed scan lines in file order, as
    (line index, scan index or -1); ``poses`` their odometry poses."""

    lines: List[bytes]
    events: List[Tuple[int, int]]
    poses: List[Pose]
    scans: List[ScanInfo]
    scan_event: List[int]
    malformed: int
    max_reading: float

    @property
    def first_stamp(self) -> float:
        return self.scans[0].stamp if self.scans else 0.0


def _decode(tokens: Sequence[bytes]) -> List[str]:
    try:
        return [t.decode("utf-8") for t in tokens]
    except UnicodeDecodeError:
        raise MalformedLine("non_numeric", "undecodable bytes") from None


def load_lines(lines) -> LoadedLog:
    """Read a log from an iterable of byte lines (with their line ends)."""
    out = LoadedLog([], [], [], [], [], 0, 0.0)
    max_reading = 0.0
    for raw in lines:
        idx = len(out.lines)
        out.lines.append(raw)
        head = raw.lstrip()
        key = head.split(None, 1)[0] if head else b""
        if key != b"ODOM" and key not in SCAN_KEYS:
            continue
        tokens = raw.split()
        try:
            rec = parse_tokens(_decode(tokens))
        except MalformedLine:
            out.malformed += 1
            continue
        if key == b"ODOM":
            out.events.append((idx, -1))
            out.poses.append(rec.pose)
            continue
        n = len(rec.ranges)
        for r in rec.ranges:
            if r > max_reading and math.isfinite(r):
                max_reading = r
        if key == b"FLASER":
            laser, odom = rec.laser_pose, rec.odom_pose
            same = tokens[2 + n:5 + n] == tokens[5 + n:8 + n]
            start = step = None
        else:
            laser, odom = rec.laser_pose, rec.robot_pose
            b = 10 + n + len(rec.remissions)
            same = tokens[b:b + 3] == tokens[b + 3:b + 6]
            start, step = rec.start_angle, rec.angular_res
        sc = len(out.scans)
        out.scans.append(ScanInfo(idx, key, n, laser, odom, rec.timestamp, rec.logger_timestamp, same, start, step))
        out.scan_event.append(len(out.events))
        out.events.append((idx, sc))
        out.poses.append(odom)
    out.max_reading = max_reading
    return out


def load_log(path: PathLike) -> LoadedLog:
    with open_binary(path) as fh:
        return load_lines(fh)


# ---------------------------------------------------------------------------
# applying the faults


@dataclass
class OutScan:
    src: int                     # the input scan whose readings it carries
    pose: Pose                   # its odometry (robot) pose
    stamp_us: Optional[int] = None  # a new stamp (copies), else the input's
    copy: bool = False
    kept: bool = True
    offset_deg: float = 0.0


@dataclass
class KidnapCut:
    """Where one kidnap cut the log (input scan indices)."""
    offset: float        # S, seconds after the first scan
    length: float        # T, seconds
    before: int          # the last scan before the cut
    after: int           # the first scan after it
    hidden: Tuple[float, float]  # what the odometry no longer reports across the cut: m, rad
    odom_removed: int = 0        # ODOM lines between the two scans
    removed: int = 0             # scans removed (set with the selection)
    stamp: Optional[float] = None  # the first scan written after the cut (None: none is)


@dataclass
class FaultResult:
    log: LoadedLog
    spec: FaultSpec
    poses: List[Pose]            # every event's odometry after the pose faults
    zero_velocity: set           # ODOM events whose velocities were zeroed (stalls)
    out: List[OutScan]           # the output scans in order, with kept flags
    summaries: List[str]
    stalls: List[Tuple[int, int]] = field(default_factory=list)  # every stall applied (N, S)
    recast_dropped: int = 0
    kidnaps: List[KidnapCut] = field(default_factory=list)  # in time order
    removed_odom: set = field(default_factory=set)  # ODOM events not written (kidnaps)

    def scan_pose(self, i: int) -> Pose:
        """Input scan i's odometry after the pose faults (slips included)."""
        return self.poses[self.log.scan_event[i]]

    @property
    def kept_scans(self) -> List[OutScan]:
        return [o for o in self.out if o.kept]

    def laser_mount(self, i: int) -> Pose:
        """The mount written on input scan i's line."""
        if self.spec.mount is not None:
            return self.spec.mount
        sc = self.log.scans[i]
        return ZERO if sc.same else pose_in_frame(sc.odom, sc.laser)


def _deg(rad: float) -> float:
    return math.degrees(rad)


def _check_scan(i: int, m: int, what: str) -> None:
    if not 0 <= i < m:
        raise FaultError(f"{what}: scan {i} is not in the log (scans 0..{m - 1})")


def turn_places(poses: Sequence[Pose], length: int, count: int, spacing: int) -> List[Tuple[int, float]]:
    """The first scans S of the ``count`` stalls of ``length`` scans whose
    catch-up turns most (|heading(S+length) - heading(S-1)|), greedily, each
    at least length + spacing scans from the others; with their turns (rad)."""
    m = len(poses)
    cands = [(abs(wrap(poses[s + length][2] - poses[s - 1][2])), s) for s in range(1, m - length)]
    cands.sort(key=lambda c: (-c[0], c[1]))
    chosen: List[Tuple[int, float]] = []
    for turn, s in cands:
        if all(abs(s - c) >= length + spacing for c, _ in chosen):
            chosen.append((s, turn))
            if len(chosen) == count:
                break
    return sorted(chosen)


def kidnap_places(log: LoadedLog, kidnaps: Sequence[Tuple[float, float]]) -> List[Tuple[float, float, int, int]]:
    """(S, T, a, b) of each kidnap in time order: b is the first scan stamped
    at or after S+T, a the last one before b stamped before S; every scan
    between them is stamped within [S, S+T). Raises FaultError when a kidnap
    has no scan on one side or begins before the scan ending the one before."""
    t0 = log.first_stamp
    stamps = [_us(sc.stamp) for sc in log.scans]
    span = max(sc.stamp for sc in log.scans) - t0 if log.scans else 0.0
    out: List[Tuple[float, float, int, int]] = []
    for g0, gl in sorted(kidnaps):
        lo, hi = _us(t0 + g0), _us(t0 + g0 + gl)
        b = next((i for i, t in enumerate(stamps) if t >= hi), None)
        a = None if b is None else next((i for i in range(b - 1, -1, -1) if stamps[i] < lo), None)
        if a is None:
            raise FaultError(f"--kidnap {g0:g}:{gl:g}: needs a scan before {g0:g} s and one at or after "
                             f"{g0 + gl:g} s after the first scan's (the log spans {span:.3f} s)")
        if out and a < out[-1][3]:
            raise FaultError(f"--kidnap {g0:g}:{gl:g}: begins before scan {out[-1][3]}, which ends the kidnap "
                             f"{out[-1][0]:g}:{out[-1][1]:g}")
        out.append((g0, gl, a, b))
    return out


def apply_faults(log: LoadedLog, spec: FaultSpec) -> FaultResult:
    """The faults of ``spec`` on ``log``; raises FaultError if one does not fit."""
    m = len(log.scans)
    if m == 0:
        raise FaultError("the log has no well-formed scan line")
    poses = list(log.poses)
    nev = len(poses)
    se = log.scan_event
    summaries: List[str] = []
    zero_v: set = set()
    n_odom = nev - m

    # 1. the mount: every robot pose moved so that the laser stays where it was
    if spec.mount is not None:
        minv = pose_inverse(spec.mount)
        first = log.scans[0]
        cur = ZERO if first.same else pose_in_frame(first.odom, first.laser)
        for e, (_, sc) in enumerate(log.events):
            if sc >= 0:
                s = log.scans[sc]
                cur = ZERO if s.same else pose_in_frame(s.odom, s.laser)
            poses[e] = pose_compose(pose_compose(poses[e], cur), minv)
        x, y, t = spec.mount
        summaries.append(f"mount: laser at x {x:.3f} m, y {y:.3f} m, theta {t:.4f} rad on the robot; {m} scans "
                         f"and {n_odom} ODOM lines moved to the robot's pose (laser poses kept); run rsm-nav with "
                         f"--laser-pose {x:g} {y:g} {t:g}")

    # 2. counter resets
    for s in sorted(spec.resets):
        _check_scan(s, m, "--reset")
        inv = pose_inverse(poses[se[s]])
        for e in range(se[s], nev):
            poses[e] = pose_compose(inv, poses[e])
        summaries.append(f"reset: odometry restarts from (0, 0, 0) at scan {s}; {m - s} scans and "
                         f"{sum(1 for e in range(se[s], nev) if log.events[e][1] < 0)} ODOM lines from there "
                         "re-expressed relative to it")

    # 3. scale: translations times F with unchanged headings is the path scaled about its start
    if spec.scale is not None:
        f = spec.scale
        x0, y0 = poses[0][0], poses[0][1]
        poses = [(x0 + f * (p[0] - x0), y0 + f * (p[1] - y0), p[2]) for p in poses]
        summaries.append(f"scale: every odometry step's translation x{f:g}, headings unchanged ({m} scans, "
                         f"{n_odom} ODOM lines; their tv too)")

    # 4. stalls, given and at the strongest turns
    stalls = list(spec.stalls)
    if spec.stall_turns is not None:
        st = spec.stall_turns
        places = turn_places([poses[se[i]] for i in range(m)], st.length, st.count, st.spacing)
        if len(places) < st.count:
            raise FaultError(f"--stall-at-turns {st.count}: only {len(places)} stalls of {st.length} scans fit "
                             f"{st.spacing} scans apart in {m} scans")
        rng = fault_rng(spec.seed, "stall-jitter")
        moved = []
        for s, turn in places:
            j = rng.randint(-st.jitter, st.jitter) if st.jitter > 0 else 0
            s2 = min(max(1, s + j), m - st.length - 1)
            moved.append((s2, turn))
            stalls.append((st.length, s2))
        summaries.append(f"stall at turns: {st.count} stalls of {st.length} scans at scans "
                         + ", ".join(str(s) for s, _ in moved)
                         + " (turns " + ", ".join(f"{_deg(t):.0f}" for _, t in moved) + " deg"
                         + (f"; moved by up to {st.jitter} scans, seed {spec.seed}" if st.jitter else "") + ")")
    for n, s in sorted(stalls, key=lambda v: v[1]):
        if n < 1 or s < 1 or s + n > m - 1:
            raise FaultError(f"--stall {n}@{s}: the stall needs scan {s - 1} before it and its catch-up scan "
                             f"{s + n} in the log (scans 0..{m - 1})")
        a, b = se[s - 1], se[s + n]
        frozen = poses[a]
        odoms = 0
        for e in range(a + 1, b):
            poses[e] = frozen
            if log.events[e][1] < 0:
                zero_v.add(e)
                odoms += 1
        d, t = step_size(frozen, poses[b])
        if spec.stall_turns is None or (n, s) in spec.stalls:
            summaries.append(f"stall: odometry frozen on scans {s}..{s + n - 1} ({n} scans, {odoms} ODOM lines) at "
                             f"scan {s - 1}'s pose, caught up at scan {s + n} by {d:.3f} m, {_deg(t):.1f} deg")

    # 5. spikes
    for s, d in spec.spikes:
        _check_scan(s, m, "--spike")
        poses[se[s]] = pose_compose(poses[se[s]], d)
        summaries.append(f"spike: scan {s}'s odometry displaced by x {d[0]:g} m, y {d[1]:g} m, theta {d[2]:g} rad "
                         "in the robot frame (1 scan; the steps into and out of it wrong)")

    # 6. slips: copies of scan S while the odometry runs on, the rest shifted
    copies: Dict[int, List[OutScan]] = {}
    last = -1
    for s, n in sorted(spec.slips):
        if n < 2 or s < 0 or s + n - 1 > m - 1:
            raise FaultError(f"--slip {s}:{n}: needs N >= 2 and scans {s}..{s + n - 1} in the log (scans 0..{m - 1})")
        if s <= last:
            raise FaultError(f"--slip {s}:{n}: two slips at one scan")
        last = s
        t0 = _us(log.scans[s].stamp)
        gap = _us(log.scans[s + 1].stamp) - t0
        made = []
        for k in range(1, n):
            stamp = t0 + (k * gap) // n if gap >= n else t0
            made.append(OutScan(s, poses[se[s + k]], stamp_us=stamp, copy=True))
        copies[s] = made
        shift = pose_compose(poses[se[s + n - 1]], pose_inverse(poses[se[s]]))
        d, t = step_size(poses[se[s]], poses[se[s + n - 1]])
        for e in range(se[s] + 1, nev):
            poses[e] = pose_compose(shift, poses[e])
        summaries.append(f"slip: the robot stands at scan {s} for {n} scans ({n - 1} copies of it inserted) while "
                         f"the odometry advances {d:.3f} m, {_deg(t):.1f} deg by the log's next steps; "
                         f"{m - s - 1} later scans follow on from scan {s}'s place, their odometry shifted by that")

    # 7. kidnaps' odometry: a carried robot's wheels do not turn, so the
    # odometry goes on from where it was lifted; last of the pose faults, so
    # that the step across the cut is zero whatever else was given
    cuts: List[KidnapCut] = []
    removed_odom: set = set()
    for g0, gl, a, b in kidnap_places(log, spec.kidnaps):
        for s, n in spec.slips:
            if a <= s <= b:
                # its copies would stand on either side of the cut
                raise FaultError(f"--kidnap {g0:g}:{gl:g} and --slip {s}:{n}: the slip's scan {s} is at the cut "
                                 f"(scans {a}..{b})")
        pa, pb = poses[se[a]], poses[se[b]]
        d, t = step_size(pa, pb)
        shift = pose_compose(pa, pose_inverse(pb))
        for e in range(se[b], nev):
            poses[e] = pose_compose(shift, poses[e])
        poses[se[b]] = pa  # exactly, not to rounding
        for s, made in copies.items():
            if s > b:
                for o in made:
                    o.pose = pose_compose(shift, o.pose)
        gone = [e for e in range(se[a] + 1, se[b]) if log.events[e][1] < 0]
        removed_odom.update(gone)
        cuts.append(KidnapCut(g0, gl, a, b, (d, t), len(gone)))

    out: List[OutScan] = []
    for i in range(m):
        out.append(OutScan(i, poses[se[i]]))
        out.extend(copies.get(i, ()))

    res = FaultResult(log, spec, poses, zero_v, out, summaries, stalls, kidnaps=cuts, removed_odom=removed_odom)

    # 8. selection
    if spec.every_m is not None or spec.every_rad is not None:
        dm = spec.every_m if spec.every_m is not None else math.inf
        dr = spec.every_rad if spec.every_rad is not None else math.inf
        ref = None
        kept = 0
        for o in out:
            if ref is not None:
                d, t = step_size(ref, o.pose)
                if d < dm and t < dr:
                    o.kept = False
                    continue
            ref = o.pose
            kept += 1
        what = " or ".join(v for v in ((f"{dm:g} m" if spec.every_m is not None else ""),
                                        (f"{dr:g} rad" if spec.every_rad is not None else "")) if v)
        summaries.append(f"sparse: {kept} of {len(out)} scans kept (a scan only after the odometry moved or "
                         f"turned {what} since the last kept one)")
    if spec.drop is not None:
        cand = [k for k, o in enumerate(out) if o.kept]
        k = math.floor(spec.drop * len(cand) / 100 + Fraction(1, 2))
        for j in fault_rng(spec.seed, "drop").sample(range(len(cand)), k):
            out[cand[j]].kept = False
        summaries.append(f"drop: {k} of {len(cand)} scans dropped at random ({float(spec.drop):g} %, "
                         f"seed {spec.seed})")
    t_first = log.first_stamp
    for g0, gl in spec.gaps:
        gone = _remove_span(out, log, _us(t_first + g0), _us(t_first + g0 + gl))
        summaries.append(f"gap: {gone} scans removed with stamps {g0:g} s to {g0 + gl:g} s after the first "
                         "scan's (ODOM lines kept)")
    for c in cuts:
        c.removed = _remove_span(out, log, _us(t_first + c.offset), _us(t_first + c.offset + c.length))
        first = next((o for o in out if o.kept and o.src >= c.after), None)
        c.stamp = None if first is None else _out_stamp_us(first, log) / 1e6
        after = "is not written" if c.stamp is None else f"is stamped {c.stamp:.6f}"
        summaries.append(f"kidnap: {c.removed} scans removed with stamps {c.offset:g} s to {c.offset + c.length:g} s "
                         f"after the first scan's, and the {c.odom_removed} ODOM lines between scans {c.before} and "
                         f"{c.after}; the odometry from scan {c.after} on goes on from scan {c.before}'s pose (the "
                         f"{c.hidden[0]:.3f} m, {_deg(c.hidden[1]):.1f} deg moved across the cut hidden); the first "
                         f"scan after the cut {after}")

    # 9. start offsets, in turn over the scans written
    if spec.start_offsets:
        k = 0
        converted = 0
        for o in out:
            if o.kept:
                o.offset_deg = spec.start_offsets[k % len(spec.start_offsets)]
                k += 1
                converted += o.offset_deg != 0.0
        res.recast_dropped = -1  # counted when written
        summaries.append(f"start offsets: {k} scans start in turn at +"
                         + ", +".join(f"{v:g}" for v in spec.start_offsets)
                         + f" deg; {converted} of them (nonzero offset) written as ROBOTLASER1 with their readings "
                         "re-cast at the shifted angles")
    return res


def _us(t: float) -> int:
    return int(round(t * 1e6))


def _out_stamp_us(o: OutScan, log: LoadedLog) -> int:
    return o.stamp_us if o.stamp_us is not None else _us(log.scans[o.src].stamp)


def _remove_span(out: List[OutScan], log: LoadedLog, lo: int, hi: int) -> int:
    """Unkeeps the output scans stamped in [lo, hi) (microseconds); returns how many."""
    gone = 0
    for o in out:
        if o.kept and lo <= _out_stamp_us(o, log) < hi:
            o.kept = False
            gone += 1
    return gone


# ---------------------------------------------------------------------------
# writing


def _num(v: float, decimals: int) -> bytes:
    text = f"{v:.{decimals}f}"
    if text.startswith("-") and float(text) == 0.0:
        text = text[1:]
    return text.encode("ascii")


def _pose_text(p: Pose, like: Sequence[bytes], decimals: int = 6) -> List[bytes]:
    return [_num(v, max(decimals, token_decimals(t))) for v, t in zip(p, like)]


def _splice(body: bytes, spans: Sequence[Tuple[int, int]], new: Dict[int, bytes]) -> bytes:
    """body with the tokens at spans[k] replaced by new[k]."""
    out = []
    pos = 0
    for k in sorted(new):
        a, b = spans[k]
        out.append(body[pos:a])
        out.append(new[k])
        pos = b
    out.append(body[pos:])
    return b"".join(out)


def _line_end(raw: bytes) -> Tuple[bytes, bytes]:
    body = raw.rstrip(b"\r\n")
    return body, raw[len(body):]


def _tail_spans(body: bytes, k: int) -> List[Tuple[int, int]]:
    """Spans of the last k tokens of a line."""
    parts = body.rsplit(None, k)
    start = len(body) - len(body.lstrip()) if len(parts) == k else len(parts[0])
    return [m.span() for m in TOKEN.finditer(body, start)][-k:]


def _recast(vals: List[float], start_k: int, frac: float, step: float,
            max_range: float) -> Tuple[List[Optional[float]], int]:
    """Readings re-cast at angles start_k + frac steps (frac in (0, 1)): the
    ray is intersected with the segment between the two neighbouring returns
    when they lie on one surface (within RECAST_TOL), else it is a no-return
    (None). Returns the readings and how many are no-returns."""
    out: List[Optional[float]] = []
    bad = 0
    dth = step
    phi = frac * step
    sin_d, sin_p, sin_r = math.sin(dth), math.sin(phi), math.sin(dth - phi)
    for j in range(start_k, len(vals) - 1):
        a, b = vals[j], vals[j + 1]
        ok = (math.isfinite(a) and math.isfinite(b) and 0.0 < a < max_range and 0.0 < b < max_range
              and abs(a - b) <= RECAST_TOL_M + RECAST_TOL_REL * min(a, b))
        if ok:
            den = a * sin_p + b * sin_r
            r = a * b * sin_d / den if den > 0 else None
            if r is None or not math.isfinite(r):
                ok = False
        if ok:
            out.append(r)
        else:
            out.append(None)
            bad += 1
    return out, bad


class _Writer:
    def __init__(self, res: FaultResult, pose_decimals: int = 6) -> None:
        self.res = res
        self.pose_decimals = pose_decimals  # at least, for the poses it rewrites
        self.log = res.log
        self.max_range = res.spec.max_range if res.spec.max_range is not None else self.log.max_reading
        self.recast_dropped = 0

    def odom_line(self, e: int) -> Optional[bytes]:
        idx, _ = self.log.events[e]
        new_pose = self.res.poses[e]
        zero = e in self.res.zero_velocity
        scale = self.res.spec.scale
        if new_pose == self.log.poses[e] and not zero and scale is None:
            return None
        raw = self.log.lines[idx]
        body, end = _line_end(raw)
        toks = body.split()
        if len(body) == sum(map(len, toks)) + len(toks) - 1:  # single spaces: spans from the lengths
            spans, pos = [], 0
            for t in toks:
                spans.append((pos, pos + len(t)))
                pos += len(t) + 1
        else:
            spans = [m.span() for m in TOKEN.finditer(body)]
        new = {}
        if new_pose != self.log.poses[e]:
            for k, v in enumerate(_pose_text(new_pose, toks[1:4], self.pose_decimals)):
                new[1 + k] = v
        if zero:
            new[4] = _num(0.0, max(1, token_decimals(toks[4])))
            new[5] = _num(0.0, max(1, token_decimals(toks[5])))
        elif scale is not None:
            new[4] = _num(float(toks[4]) * scale, max(6, token_decimals(toks[4])))
        return _splice(body, spans, new) + end

    def scan_line(self, o: OutScan) -> bytes:
        sc = self.log.scans[o.src]
        raw = self.log.lines[sc.line]
        if o.offset_deg != 0.0:
            return self.robotlaser(o, sc, raw)
        changed = o.pose != sc.odom or o.stamp_us is not None or self.res.spec.mount is not None
        if not changed:
            return raw
        body, end = _line_end(raw)
        k = _TAIL[sc.key]
        spans = _tail_spans(body, k)
        toks = [body[a:b] for a, b in spans]
        new = {}
        odom_text = _pose_text(o.pose, toks[3:6], self.pose_decimals)
        for j, v in enumerate(odom_text):
            new[3 + j] = v
        laser_text = self.laser_text(o, sc, toks[0:3], odom_text)
        for j, v in enumerate(laser_text):
            new[j] = v
        if o.stamp_us is not None:
            self.stamps(o, sc, toks, new, _STAMP_IN_TAIL[sc.key])
        return _splice(body, spans, new) + end

    def laser_text(self, o: OutScan, sc: ScanInfo, like: Sequence[bytes], odom_text: List[bytes]) -> List[bytes]:
        if self.res.spec.mount is None and sc.same:
            return list(odom_text)
        return _pose_text(pose_compose(o.pose, self.res.laser_mount(o.src)), like, self.pose_decimals)

    def stamps(self, o: OutScan, sc: ScanInfo, toks: Sequence[bytes], new: Dict[int, bytes], i: int) -> None:
        t = o.stamp_us / 1e6
        new[i] = _num(t, max(6, token_decimals(toks[i])))
        new[i + 2] = _num(sc.logger + (t - sc.stamp), max(6, token_decimals(toks[i + 2])))

    def robotlaser(self, o: OutScan, sc: ScanInfo, raw: bytes) -> bytes:
        body, end = _line_end(raw)
        toks = body.split()
        n = sc.n
        readings = toks[2:2 + n] if sc.key == b"FLASER" else toks[9:9 + n]
        if sc.key == b"FLASER":
            start = -math.pi / 2.0
            step = math.pi / (n - 1) if (self.res.spec.fov179 and n > 1) else math.pi / max(n, 1)
            head = [b"0"]  # laser type (FLASER does not say)
            tail_in = toks[2 + n:]
            vel = [b"0.000000"] * 5
            accuracy, remission_mode, max_range = 0.0, b"0", self.max_range
        else:
            start, step = sc.start, sc.step
            head = [toks[1]]
            m = int(toks[9 + n])
            tail_in = toks[10 + n + m:]
            vel = list(tail_in[6:11])
            accuracy, remission_mode, max_range = float(toks[6]), b"0", float(toks[5])
        off = math.radians(o.offset_deg)
        q = off / step
        k = int(math.floor(q + 1e-9))
        frac = q - k
        if frac < 1e-6 or frac > 1.0 - 1e-6:
            k = int(round(q))
            vals_text = readings[k:]
        else:
            vals = [float(t) for t in readings]
            recast, bad = _recast(vals, k, frac, step, max_range)
            self.recast_dropped += bad
            dec = max([2] + [token_decimals(t) for t in readings[:1]])
            no_return = _num(max_range, dec)
            vals_text = [no_return if r is None else _num(r, dec) for r in recast]
        nn = len(vals_text)
        if nn < 2:
            raise FaultError(f"--start-offsets {o.offset_deg:g}: leaves scan {o.src} with {nn} readings")
        lt = tail_in[0:3]
        odom_text = _pose_text(o.pose, tail_in[3:6], self.pose_decimals)
        laser_text = self.laser_text(o, sc, lt, odom_text)
        stamp_toks = list(tail_in[-3:])
        if o.stamp_us is not None:
            new: Dict[int, bytes] = {}
            self.stamps(o, sc, stamp_toks, new, 0)
            for j, v in new.items():
                stamp_toks[j] = v
        parts = [b"ROBOTLASER1", *head, _num(start + off, 9), _num((nn - 1) * step, 9), _num(step, 9),
                 _num(max_range, 2), _num(accuracy, 3), remission_mode, str(nn).encode(), *vals_text, b"0",
                 *laser_text, *odom_text, *vel, *stamp_toks]
        return b" ".join(parts) + (end or b"\n")

    def write(self, out: IO[bytes], comment: Optional[bytes] = None, odom_lines: bool = True) -> int:
        """Writes the faulty log (without its ODOM lines if not odom_lines);
        returns the scan lines written."""
        log, res = self.log, self.res
        replace: Dict[int, Optional[bytes]] = {}
        after: Dict[int, List[bytes]] = {}
        for e, (idx, sc) in enumerate(log.events):
            if sc < 0:
                if e in res.removed_odom:
                    replace[idx] = None
                    continue
                new = self.odom_line(e) if odom_lines else None
                if new is not None or not odom_lines:
                    replace[idx] = new
        written = 0
        for o in res.out:
            idx = log.scans[o.src].line
            if o.copy:
                if o.kept:
                    after.setdefault(idx, []).append(self.scan_line(o))
                    written += 1
                continue
            if not o.kept:
                replace[idx] = None
                continue
            written += 1
            new = self.scan_line(o)
            if new is not log.lines[idx]:
                replace[idx] = new
        chunks = []
        if comment:
            chunks.append(comment)
        for idx, raw in enumerate(log.lines):
            if idx in replace:
                new = replace[idx]
                if new is not None:
                    chunks.append(new)
            else:
                chunks.append(raw)
            extra = after.get(idx)
            if extra:
                if chunks and not chunks[-1].endswith(b"\n"):
                    chunks[-1] += b"\n"
                chunks.extend(x if x.endswith(b"\n") else x + b"\n" for x in extra)
        out.write(b"".join(chunks))
        res.recast_dropped = self.recast_dropped
        return written


def write_result(res: FaultResult, out: IO[bytes], comment: Optional[str] = None, odom_lines: bool = True) -> int:
    """Writes the faulty log of ``res`` to ``out``; returns the scan lines
    written. ``odom_lines=False`` leaves the ODOM lines out (rsm-nav reads the
    odometry of a CARMEN log from its scan lines only: the bench's runs)."""
    c = None if comment is None else ("# " + comment.replace("\n", " ") + "\n").encode("utf-8")
    return _Writer(res).write(out, c, odom_lines)


def write_poses(log: LoadedLog, poses: Sequence[Pose], out: IO[bytes], decimals: int = 6) -> int:
    """Writes ``log`` with every event's odometry pose replaced by ``poses``
    (one per ``log.events``; a scan's laser pose moves with it), at least
    ``decimals`` decimals, the rest of every line as it was; returns the scan
    lines written. For odometry moved by less than the log prints
    (fullchecks.jittered_log)."""
    res = FaultResult(log, FaultSpec(), list(poses), set(),
                      [OutScan(i, poses[e]) for i, e in enumerate(log.scan_event)], [])
    return _Writer(res, decimals).write(out)


def fault_file(src: PathLike, dst: PathLike, spec: FaultSpec, comment: Optional[str] = None) -> FaultResult:
    """Reads ``src``, applies ``spec``, writes ``dst`` (gzip, mtime 0, if it ends in .gz)."""
    log = load_log(src)
    res = apply_faults(log, spec)
    with open_binary_output(dst) as fout:
        write_result(res, fout, comment)
    return res


# ---------------------------------------------------------------------------
# command line


def _number(text: str, what: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{what}: not a number: {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{what}: not finite: {text!r}")
    return v


def _angle(text: str, what: str) -> float:
    """Radians, or degrees with a 'deg' suffix."""
    t = text.strip()
    if t.endswith("deg"):
        return math.radians(_number(t[:-3], what))
    return _number(t, what)


def _int(text: str, what: str, lo: int = 0) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{what}: not an integer: {text!r}") from None
    if v < lo:
        raise argparse.ArgumentTypeError(f"{what}: must be at least {lo}: {text!r}")
    return v


def _split(text: str, sep: str, count: int, what: str, form: str) -> List[str]:
    parts = text.split(sep)
    if len(parts) != count or not all(p.strip() for p in parts):
        raise argparse.ArgumentTypeError(f"{what} wants {form}, got {text!r}")
    return [p.strip() for p in parts]


def _stall(text: str) -> Tuple[int, int]:
    n, s = _split(text, "@", 2, "--stall", "N@S (scans, first scan)")
    return _int(n, "--stall N", 1), _int(s, "--stall S", 1)


def _spike(text: str) -> Tuple[int, Pose]:
    s, d = _split(text, ":", 2, "--spike", "S:DX,DY,DTH")
    dx, dy, dt = _split(d, ",", 3, "--spike", "S:DX,DY,DTH")
    return _int(s, "--spike S"), (_number(dx, "--spike DX"), _number(dy, "--spike DY"), _angle(dt, "--spike DTH"))


def _slip(text: str) -> Tuple[int, int]:
    s, n = _split(text, ":", 2, "--slip", "S:N (first scan, scans)")
    return _int(s, "--slip S"), _int(n, "--slip N", 2)


def _span(text: str, flag: str) -> Tuple[float, float]:
    """S:T of --gap and --kidnap: seconds after the first scan, seconds."""
    s, t = _split(text, ":", 2, flag, "S:T (seconds after the first scan, seconds)")
    a, b = _number(s, f"{flag} S"), _number(t, f"{flag} T")
    if a < 0 or b <= 0:
        raise argparse.ArgumentTypeError(f"{flag} wants S >= 0 and T > 0, got {text!r}")
    return a, b


def _gap(text: str) -> Tuple[float, float]:
    return _span(text, "--gap")


def _kidnap(text: str) -> Tuple[float, float]:
    return _span(text, "--kidnap")


def _mount(text: str) -> Pose:
    x, y, t = _split(text, ",", 3, "--mount", "X,Y,TH (m, m, rad)")
    return _number(x, "--mount X"), _number(y, "--mount Y"), _angle(t, "--mount TH")


def _offsets(text: str) -> List[float]:
    vals = [_number(v, "--start-offsets") for v in text.split(",") if v.strip()]
    if not vals or any(not 0.0 <= v <= 45.0 for v in vals):
        raise argparse.ArgumentTypeError(f"--start-offsets wants degrees within 0..45, comma separated, got {text!r}")
    return vals


def _scale(text: str) -> float:
    v = _number(text, "--scale")
    if v <= 0:
        raise argparse.ArgumentTypeError(f"--scale must be positive: {text!r}")
    return v


def _positive(what: str):
    def parse(text: str) -> float:
        v = _number(text, what)
        if v <= 0:
            raise argparse.ArgumentTypeError(f"{what} must be positive: {text!r}")
        return v
    return parse


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog=PROG,
        description="Copy a CARMEN log with odometry and sampling faults (stalls, spikes, counter resets, slip, "
                    "scale errors, sparse, dropped or missing scans, a kidnapped robot, another laser mount, "
                    "shifted start angles), "
                    "deterministically from a seed. Scan indices count the log's scan lines from 0; angles are "
                    "in radians unless written with 'deg' (start offsets: degrees). See docs/faults.md.")
    p.add_argument("input", help="CARMEN log (plain or gzip)")
    p.add_argument("output", help="output log; gzip-compressed (mtime 0) if the name ends in .gz")
    g = p.add_argument_group("odometry faults")
    g.add_argument("--stall", type=_stall, action="append", default=[], metavar="N@S",
                   help="odometry frozen for N scans from scan S, then caught up in one step (repeatable)")
    g.add_argument("--stall-at-turns", type=lambda t: _int(t, "--stall-at-turns", 1), metavar="K",
                   help="K stalls at the K strongest turns of the odometry (with --stall-len)")
    g.add_argument("--stall-len", type=lambda t: _int(t, "--stall-len", 1), metavar="N",
                   help="scans per automatic stall")
    g.add_argument("--stall-spacing", type=lambda t: _int(t, "--stall-spacing"), default=50, metavar="M",
                   help="scans at least between two automatic stalls (default %(default)s)")
    g.add_argument("--stall-jitter", type=lambda t: _int(t, "--stall-jitter"), default=0, metavar="J",
                   help="move each automatic stall by up to J scans, drawn from the seed (default 0)")
    g.add_argument("--spike", type=_spike, action="append", default=[], metavar="S:DX,DY,DTH",
                   help="scan S's odometry displaced by DX, DY (m), DTH in the robot frame (repeatable)")
    g.add_argument("--reset", type=lambda t: _int(t, "--reset"), action="append", default=[], metavar="S",
                   help="odometry restarts from (0, 0, 0) at scan S (repeatable)")
    g.add_argument("--slip", type=_slip, action="append", default=[], metavar="S:N",
                   help="the robot stands at scan S for N scans while the odometry runs on (repeatable)")
    g.add_argument("--scale", type=_scale, metavar="F", help="every odometry step's translation times F")
    g = p.add_argument_group("sampling faults")
    g.add_argument("--every-m", type=_positive("--every-m"), metavar="D",
                   help="keep a scan only after the odometry moved D m (or turned --every-rad) since the last kept")
    g.add_argument("--every-rad", type=_positive("--every-rad"), metavar="R",
                   help="keep a scan only after the odometry turned R rad (or moved --every-m)")
    g.add_argument("--drop", type=percent_argument, metavar="P", help="drop P %% of the scans at random")
    g.add_argument("--gap", type=_gap, action="append", default=[], metavar="S:T",
                   help="remove every scan stamped S to S+T seconds after the first scan (repeatable)")
    g.add_argument("--kidnap", type=_kidnap, action="append", default=[], metavar="S:T",
                   help="the robot carried away from S to S+T seconds after the first scan: those scans and "
                        "ODOM lines removed, the odometry after the cut going on from the pose before it "
                        "(repeatable)")
    g = p.add_argument_group("laser geometry")
    g.add_argument("--mount", type=_mount, metavar="X,Y,TH",
                   help="the laser mounted at X, Y (m), TH on the robot; laser poses kept, robot poses moved")
    g.add_argument("--start-offsets", type=_offsets, metavar="A,B,...",
                   help="successive scans start A, B, ... degrees further on, in turn (ROBOTLASER1 lines)")
    g.add_argument("--fov179", action="store_true",
                   help="FLASER beams span exactly 180 deg (pi/(n-1) steps), as rsm-nav --fov179; default pi/n")
    g.add_argument("--max-range", type=_positive("--max-range"), metavar="M",
                   help="max range (no-return code) written on converted FLASER lines (default: the log's "
                        "largest reading)")
    p.add_argument("--seed", type=int, default=0, help="seed of every random choice (default %(default)s)")
    return p


def describe(spec: FaultSpec) -> str:
    """The options that make ``spec``, in the order they are applied (the
    comment the tool writes at the top of its output)."""
    out = []
    if spec.mount is not None:
        out.append("--mount " + ",".join(f"{v:g}" for v in spec.mount))
    out += [f"--reset {s}" for s in spec.resets]
    if spec.scale is not None:
        out.append(f"--scale {spec.scale:g}")
    out += [f"--stall {n}@{s}" for n, s in spec.stalls]
    if spec.stall_turns is not None:
        st = spec.stall_turns
        out.append(f"--stall-at-turns {st.count} --stall-len {st.length} --stall-spacing {st.spacing} "
                   f"--stall-jitter {st.jitter}")
    out += [f"--spike {s}:" + ",".join(f"{v:g}" for v in d) for s, d in spec.spikes]
    out += [f"--slip {s}:{n}" for s, n in spec.slips]
    if spec.every_m is not None:
        out.append(f"--every-m {spec.every_m:g}")
    if spec.every_rad is not None:
        out.append(f"--every-rad {spec.every_rad:g}")
    if spec.drop is not None:
        out.append(f"--drop {float(spec.drop):g}")
    out += [f"--gap {a:g}:{b:g}" for a, b in spec.gaps]
    out += [f"--kidnap {a:g}:{b:g}" for a, b in spec.kidnaps]
    if spec.start_offsets:
        out.append("--start-offsets " + ",".join(f"{v:g}" for v in spec.start_offsets))
    if spec.fov179:
        out.append("--fov179")
    if spec.max_range is not None:
        out.append(f"--max-range {spec.max_range:g}")
    out.append(f"--seed {spec.seed}")
    return " ".join(out)


def spec_from_args(args: argparse.Namespace) -> FaultSpec:
    st = None
    if args.stall_at_turns is not None:
        st = StallTurns(args.stall_at_turns, args.stall_len, args.stall_spacing, args.stall_jitter)
    return FaultSpec(stalls=list(args.stall), stall_turns=st, spikes=list(args.spike), resets=list(args.reset),
                     slips=list(args.slip), scale=args.scale, every_m=args.every_m, every_rad=args.every_rad,
                     drop=args.drop, gaps=list(args.gap), kidnaps=list(args.kidnap), mount=args.mount,
                     start_offsets=args.start_offsets or [], seed=args.seed, fov179=args.fov179,
                     max_range=args.max_range)


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if (args.stall_at_turns is None) != (args.stall_len is None):
        parser.error("--stall-at-turns and --stall-len go together")
    spec = spec_from_args(args)
    if spec.empty():
        parser.error("no fault given (see --help)")
    try:
        log = load_log(args.input)
    except OSError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 1
    try:
        res = apply_faults(log, spec)
    except FaultError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    buf = io.BytesIO()
    try:
        written = write_result(res, buf, f"{PROG} {describe(spec)}")
    except FaultError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    try:
        with open_binary_output(args.output) as fout:
            fout.write(buf.getbuffer())
    except OSError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 1
    for s in res.summaries:
        if s.startswith("start offsets:"):
            s += f" ({res.recast_dropped} readings with no surface between their neighbours written as no-return)"
        print(f"{PROG}: {s}", file=sys.stderr)
    msg = f"{PROG}: {len(log.scans)} scans in, {written} written"
    if log.malformed:
        msg += f"; {log.malformed} malformed scan or ODOM lines copied unchanged"
    print(msg, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
