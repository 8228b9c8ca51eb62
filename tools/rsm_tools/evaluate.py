"""Relative-pose error of a 2D trajectory against ground-truth relations.

The metric follows R. Kuemmerle et al., "On measuring the accuracy of SLAM
algorithms", Autonomous Robots 27, 2009: instead of comparing absolute poses,
it compares relative motions between pairs of time stamps.

For a relation (t1, t2, x, y, yaw), the true motion ``D`` is the pose at t2
expressed in the frame of the pose at t1.  The estimated motion is
``E = inverse(P(t1)) o P(t2)`` from the trajectory under test.  The error of
the relation is ``inverse(D) o E``; its translational part is the norm of its
(x, y) and its rotational part is the absolute wrapped angle ``E.yaw - D.yaw``
(reported in degrees).

File formats (whitespace-separated, ``#`` comments and blank lines ignored):

* trajectory: ``timestamp x y theta``
* relations: ``t1 t2 x y z roll pitch yaw`` (z, roll and pitch are ignored)
* corrected poses: ``timestamp scan_index x y theta`` (told apart from a
  trajectory by its five columns)

Timestamps are matched exactly at microsecond resolution first; failing that,
the nearest trajectory time within ``tolerance`` seconds is used.  Relations
with an end that is not found are counted as *unmatched*, not as errors.
Matches made by the nearest-time fallback are counted as *inexact*: beware
that some logs hold distinct scans less than a millisecond apart (the Intel
log has about 1500 such pairs), so with a sparse trajectory the fallback can
pick a neighbouring scan; ``--tolerance 0`` turns the fallback off.

Statistics are the count, mean, population standard deviation, maximum and
root-mean-square of the per-relation errors.
"""

import argparse
import bisect
import json
import math
import sys
from typing import Dict, Iterable, List, NamedTuple, Optional, Sequence, Tuple, Union

from .carmen import FLaser, LogReader, LogStats, RobotLaser1, time_key
from .fileio import PathLike, open_text, open_text_output

Pose = Tuple[float, float, float]

DEFAULT_TOLERANCE = 1e-3

# The "local" relations (docs/RESULTS.md, the demo, the full-log checks): those
# spanning at most this long, s. Beside them, "all": every relation.
LOCAL_SPAN = 2.0


class Relation(NamedTuple):
    t1: float
    t2: float
    x: float
    y: float
    yaw: float

    @property
    def span(self) -> float:
        return abs(self.t2 - self.t1)


class TrajectoryPoint(NamedTuple):
    t: float
    x: float
    y: float
    theta: float


# ---------------------------------------------------------------------------
# SE(2) helpers


def wrap_angle(a: float) -> float:
    """Wrap an angle to (-pi, pi]."""
    w = math.remainder(a, 2.0 * math.pi)
    if w <= -math.pi:
        w += 2.0 * math.pi
    return w


def compose(a: Pose, b: Pose) -> Pose:
    """a o b: the pose b, given in the frame a, expressed in a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap_angle(a[2] + b[2]))


def between(a: Pose, b: Pose) -> Pose:
    """inverse(a) o b: the pose b expressed in the frame of a."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    c, s = math.cos(a[2]), math.sin(a[2])
    return (c * dx + s * dy, -s * dx + c * dy, wrap_angle(b[2] - a[2]))


def relation_error(estimated: Pose, true: Pose) -> Tuple[float, float]:
    """(translation in m, rotation in rad) of ``inverse(true) o estimated``."""
    e = between(true, estimated)
    return math.hypot(e[0], e[1]), abs(wrap_angle(estimated[2] - true[2]))


# ---------------------------------------------------------------------------
# trajectories


class Trajectory:
    """Timestamped 2D poses with exact-then-nearest timestamp lookup.

    If a timestamp occurs more than once, the last pose given for it wins.
    """

    def __init__(self, points: Iterable[Sequence[float]] = ()) -> None:
        self._by_key: Dict[int, Pose] = {}
        self._times: List[float] = []
        self._keys: List[int] = []
        self._sorted = True
        for p in points:
            self.add(p[0], p[1], p[2], p[3])

    def add(self, t: float, x: float, y: float, theta: float) -> None:
        k = time_key(t)
        if k not in self._by_key:
            if self._times and t < self._times[-1]:
                self._sorted = False
            self._times.append(t)
            self._keys.append(k)
        self._by_key[k] = (x, y, theta)

    def __len__(self) -> int:
        return len(self._by_key)

    def points(self) -> List[TrajectoryPoint]:
        """The poses in time order."""
        self._sort()
        return [TrajectoryPoint(t, *self._by_key[k]) for t, k in zip(self._times, self._keys)]

    def _sort(self) -> None:
        if not self._sorted:
            order = sorted(range(len(self._times)), key=self._times.__getitem__)
            self._times = [self._times[i] for i in order]
            self._keys = [self._keys[i] for i in order]
            self._sorted = True

    def lookup(self, t: float, tolerance: float = DEFAULT_TOLERANCE) -> Optional[Pose]:
        """The pose at ``t``: exact microsecond match, else nearest within tolerance."""
        return self.find(t, tolerance)[0]

    def find(self, t: float, tolerance: float = DEFAULT_TOLERANCE) -> Tuple[Optional[Pose], bool]:
        """Like :meth:`lookup`, also telling whether the match was exact."""
        pose = self._by_key.get(time_key(t))
        if pose is not None:
            return pose, True
        if tolerance <= 0 or not self._times:
            return None, False
        self._sort()
        i = bisect.bisect_left(self._times, t)
        best = None
        for j in (i - 1, i):
            if 0 <= j < len(self._times):
                d = abs(self._times[j] - t)
                if d <= tolerance and (best is None or d < best[0]):
                    best = (d, j)
        if best is None:
            return None, False
        return self._by_key[self._keys[best[1]]], False


def _data_rows(path: PathLike) -> Iterable[Tuple[int, List[str]]]:
    with open_text(path) as fh:
        for lineno, line in enumerate(fh, start=1):
            tokens = line.split()
            if not tokens or tokens[0].startswith("#"):
                continue
            yield lineno, tokens


def _floats(tokens: Sequence[str], path: PathLike, lineno: int) -> List[float]:
    try:
        vals = [float(v) for v in tokens]
    except ValueError:
        raise ValueError(f"{path}:{lineno}: non-numeric field in {' '.join(tokens)!r}") from None
    if not all(math.isfinite(v) for v in vals):
        raise ValueError(f"{path}:{lineno}: non-finite value in {' '.join(tokens)!r}")
    return vals


def read_poses(path: PathLike) -> Tuple[List[TrajectoryPoint], str]:
    """Every pose of a trajectory file in file order (repeated stamps kept):
    the one reader of the package's trajectory files, which load_poses and
    the other tools build on. Reads a trajectory (4 columns), a
    corrected-poses file (5 columns) or a TUM file (8 columns: t x y z qx qy
    qz qw, as ``rsm-nav --tum`` writes; the heading is the yaw of the
    quaternion).

    Returns the poses and the detected format, ``"trajectory"``,
    ``"corrected-poses"`` or ``"tum"``.  The format is decided by the first
    data row; every row must then have the same number of columns.
    """
    rows: List[TrajectoryPoint] = []
    ncols = None
    for lineno, tokens in _data_rows(path):
        if ncols is None:
            ncols = len(tokens)
            if ncols not in (4, 5, 8):
                raise ValueError(
                    f"{path}:{lineno}: expected 4 columns (t x y theta), 5 "
                    f"(t scan_index x y theta) or 8 (TUM: t x y z qx qy qz qw), got {ncols}"
                )
        elif len(tokens) != ncols:
            raise ValueError(f"{path}:{lineno}: expected {ncols} columns, got {len(tokens)}")
        v = _floats(tokens, path, lineno)
        if ncols == 4:
            rows.append(TrajectoryPoint(v[0], v[1], v[2], v[3]))
        elif ncols == 5:
            rows.append(TrajectoryPoint(v[0], v[2], v[3], v[4]))
        else:
            qx, qy, qz, qw = v[4:8]
            rows.append(TrajectoryPoint(v[0], v[1], v[2],
                                        math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))))
    if ncols is None:
        return rows, "trajectory"
    return rows, {4: "trajectory", 5: "corrected-poses", 8: "tum"}[ncols]


def load_poses(path: PathLike) -> Tuple[Trajectory, str]:
    """read_poses as a Trajectory (looked up by stamp; a repeated stamp's
    last pose wins), with the detected format."""
    rows, fmt = read_poses(path)
    return Trajectory(rows), fmt


def printed_poses(path: PathLike) -> List[List[str]]:
    """``x y theta`` of every line of a trajectory file, as printed: two runs
    whose lines compare equal gave the same poses to the printed digits."""
    with open(path) as f:
        return [line.split()[1:] for line in f if line.strip() and not line.startswith("#")]


def load_trajectory(path: PathLike) -> Trajectory:
    """Load a ``timestamp x y theta`` file (a 5-column corrected-poses file works too)."""
    return load_poses(path)[0]


def load_relations(path: PathLike) -> List[Relation]:
    """Load a relations file: ``t1 t2 x y z roll pitch yaw`` per line."""
    rels = []
    for lineno, tokens in _data_rows(path):
        if len(tokens) != 8:
            raise ValueError(
                f"{path}:{lineno}: a relation needs 8 fields (t1 t2 x y z roll pitch yaw), "
                f"got {len(tokens)}"
            )
        v = _floats(tokens, path, lineno)
        rels.append(Relation(v[0], v[1], v[2], v[3], v[7]))
    return rels


def write_relations(rels: Iterable[Relation], stream) -> None:
    """Write relations in the 8-field format."""
    for r in rels:
        stream.write(
            f"{r.t1:.6f} {r.t2:.6f} {r.x:.6f} {r.y:.6f} 0.000000 0.000000 0.000000 {r.yaw:.6f}\n"
        )


def relations_from_poses(
    traj: Trajectory, max_span: Optional[float] = None
) -> List[Relation]:
    """Ground-truth relations from ground-truth poses.

    Always relates each pose to the next one in time; with ``max_span`` it also
    relates every pair of poses at most ``max_span`` seconds apart.
    """
    pts = traj.points()
    pairs = set()
    for i in range(len(pts) - 1):
        pairs.add((i, i + 1))
    if max_span is not None:
        for i in range(len(pts)):
            j = i + 1
            while j < len(pts) and pts[j].t - pts[i].t <= max_span:
                pairs.add((i, j))
                j += 1
    rels = []
    for i, j in sorted(pairs):
        a, b = pts[i], pts[j]
        d = between((a.x, a.y, a.theta), (b.x, b.y, b.theta))
        rels.append(Relation(a.t, b.t, d[0], d[1], d[2]))
    return rels


def odometry_trajectory(log: PathLike, stats: Optional[LogStats] = None) -> List[TrajectoryPoint]:
    """The raw odometry path of a CARMEN log: one point per scan, in file order.

    Uses the odometry pose of each FLASER line (the robot pose of a
    ROBOTLASER1 line) and the scan's ipc timestamp.
    """
    pts = []
    for rec in LogReader(log, types=("FLASER", "ROBOTLASER1"), stats=stats):
        if isinstance(rec, FLaser):
            p = rec.odom_pose
        else:
            assert isinstance(rec, RobotLaser1)
            p = rec.robot_pose
        pts.append(TrajectoryPoint(rec.timestamp, p[0], p[1], p[2]))
    return pts


def write_trajectory(points: Iterable[Sequence[float]], stream, header: str = "") -> None:
    """Write ``timestamp x y theta`` lines (6 decimals)."""
    if header:
        for line in header.splitlines():
            stream.write(f"# {line}\n")
    for p in points:
        stream.write(f"{p[0]:.6f} {p[1]:.6f} {p[2]:.6f} {p[3]:.6f}\n")


# ---------------------------------------------------------------------------
# evaluation


def _stats(values: Sequence[float]) -> Dict[str, float]:
    n = len(values)
    if n == 0:
        return {"count": 0, "mean": float("nan"), "std": float("nan"),
                "max": float("nan"), "rmse": float("nan")}
    mean = math.fsum(values) / n
    var = math.fsum((v - mean) ** 2 for v in values) / n
    return {
        "count": n,
        "mean": mean,
        "std": math.sqrt(var),
        "max": max(values),
        "rmse": math.sqrt(math.fsum(v * v for v in values) / n),
    }


def _as_trajectory(traj) -> Trajectory:
    if isinstance(traj, Trajectory):
        return traj
    if isinstance(traj, dict):
        return Trajectory((t,) + tuple(p) for t, p in traj.items())
    return Trajectory(traj)


def evaluate(
    traj: Union[Trajectory, Iterable[Sequence[float]], Dict[float, Sequence[float]]],
    relations: Iterable[Sequence[float]],
    max_span: Optional[float] = None,
    min_span: Optional[float] = None,
    tolerance: float = DEFAULT_TOLERANCE,
    details: bool = False,
) -> dict:
    """Relative-pose error of ``traj`` on ``relations``.

    ``traj`` is a :class:`Trajectory`, an iterable of ``(t, x, y, theta)`` or a
    dict ``{t: (x, y, theta)}``.  ``relations`` holds :class:`Relation` values
    or ``(t1, t2, x, y, yaw)`` tuples.  Relations with ``|t2 - t1|`` above
    ``max_span`` or below ``min_span`` are left out before matching.

    Returns a dict with ``relations`` (given), ``in_span``, ``matched``,
    ``unmatched``, ``inexact`` (matched relations with an end found only by
    the nearest-time fallback), and ``translation`` (m) and ``rotation`` (deg) statistics,
    each ``{count, mean, std, max, rmse}``.  With ``details=True`` it also
    holds ``errors``: one ``(t1, t2, trans_m, rot_deg)`` per matched relation.
    """
    tr = _as_trajectory(traj)
    total = in_span = 0
    unmatched = inexact = 0
    trans: List[float] = []
    rot: List[float] = []
    errors = []
    for r in relations:
        total += 1
        t1, t2, x, y, yaw = (float(v) for v in r[:5])
        span = abs(t2 - t1)
        if max_span is not None and span > max_span:
            continue
        if min_span is not None and span < min_span:
            continue
        in_span += 1
        p1, exact1 = tr.find(t1, tolerance)
        p2, exact2 = tr.find(t2, tolerance)
        if p1 is None or p2 is None:
            unmatched += 1
            continue
        if not (exact1 and exact2):
            inexact += 1
        est = between(p1, p2)
        et, er = relation_error(est, (x, y, yaw))
        er = math.degrees(er)
        trans.append(et)
        rot.append(er)
        if details:
            errors.append((t1, t2, et, er))
    out = {
        "relations": total,
        "in_span": in_span,
        "matched": len(trans),
        "unmatched": unmatched,
        "inexact": inexact,
        "max_span": max_span,
        "min_span": min_span,
        "translation": _stats(trans),
        "rotation": _stats(rot),
    }
    if details:
        out["errors"] = errors
    return out


def evaluate_scopes(traj, relations: Sequence[Relation], details: bool = False) -> Dict[str, dict]:
    """:func:`evaluate` on every relation ("all", with ``details``) and on the
    local ones (span up to LOCAL_SPAN), matching exact stamps only: a
    trajectory of rsm-nav has a pose at every scan's stamp, and a near miss
    would be another scan's pose."""
    return {"all": evaluate(traj, relations, tolerance=0.0, details=details),
            "local": evaluate(traj, relations, max_span=LOCAL_SPAN, tolerance=0.0)}


def format_result(res: dict, label: str = "") -> str:
    """Human-readable multi-line summary of an :func:`evaluate` result."""
    lines = []
    if label:
        lines.append(f"label: {label}")
    span = []
    if res.get("min_span") is not None:
        span.append(f">= {res['min_span']:g} s")
    if res.get("max_span") is not None:
        span.append(f"<= {res['max_span']:g} s")
    lines.append(
        f"relations: {res['relations']} given, {res['in_span']} in span"
        + (f" ({', '.join(span)})" if span else "")
        + f", {res['matched']} matched, {res['unmatched']} unmatched"
    )
    if res.get("inexact"):
        lines.append(
            f"warning: {res['inexact']} matched relations used the nearest pose within the "
            "tolerance instead of an exact timestamp"
        )
    for key, unit in (("translation", "m"), ("rotation", "deg")):
        s = res[key]
        lines.append(
            f"{key} [{unit}]: mean {s['mean']:.6f} std {s['std']:.6f} "
            f"max {s['max']:.6f} rmse {s['rmse']:.6f} (n={s['count']})"
        )
    return "\n".join(lines)


def _json_safe(obj):
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
    return obj


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="rsm-evaluate",
        description=(
            "Relative-pose error (Kuemmerle et al. 2009) of a 2D trajectory against "
            "ground-truth relations or poses."
        ),
    )
    p.add_argument("trajectory", nargs="?",
                   help="trajectory file: 'timestamp x y theta' per line")
    p.add_argument("--odometry", metavar="LOG",
                   help="use the raw odometry of a CARMEN log (the odometry pose of each "
                        "scan line) as the trajectory")
    p.add_argument("--write-trajectory", metavar="OUT",
                   help="write the trajectory evaluated (e.g. from --odometry) to OUT")
    gt = p.add_mutually_exclusive_group()
    gt.add_argument("--relations", metavar="FILE",
                    help="relations file: 't1 t2 x y z roll pitch yaw' per line")
    gt.add_argument("--ground-truth", metavar="FILE",
                    help="ground-truth poses: a trajectory file, or 'timestamp scan_index x y "
                         "theta' corrected poses; relations are built between consecutive poses "
                         "and all pairs within --max-span")
    p.add_argument("--max-span", type=float, metavar="SECONDS",
                   help="keep only relations with |t2 - t1| <= SECONDS")
    p.add_argument("--min-span", type=float, metavar="SECONDS",
                   help="keep only relations with |t2 - t1| >= SECONDS")
    p.add_argument("--tolerance", type=float, default=DEFAULT_TOLERANCE, metavar="SECONDS",
                   help="timestamp matching tolerance (default: %(default)g s)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--label", default="", help="a name for this run, echoed in the output")
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if (args.trajectory is None) == (args.odometry is None):
        parser.error("give exactly one of TRAJECTORY or --odometry LOG")
    if args.relations is None and args.ground_truth is None and args.write_trajectory is None:
        parser.error("nothing to do: give --relations, --ground-truth or --write-trajectory")

    try:
        if args.odometry is not None:
            st = LogStats()
            points = odometry_trajectory(args.odometry, stats=st)
            if st.malformed_total:
                print(f"rsm-evaluate: {args.odometry}: {st.summary()}", file=sys.stderr)
            traj = Trajectory(points)
        else:
            traj = load_trajectory(args.trajectory)
            points = traj.points()

        if args.write_trajectory is not None:
            with open_text_output(args.write_trajectory) as out:
                header = ""
                if args.odometry is not None:
                    header = "raw odometry of each scan: timestamp x y theta"
                write_trajectory(points, out, header)
            if args.relations is None and args.ground_truth is None:
                print(f"wrote {len(points)} poses to {args.write_trajectory}")
                return 0

        if args.relations is not None:
            rels = load_relations(args.relations)
        else:
            gt, _fmt = load_poses(args.ground_truth)
            rels = relations_from_poses(gt, args.max_span)
    except (OSError, ValueError) as exc:
        print(f"rsm-evaluate: error: {exc}", file=sys.stderr)
        return 1

    res = evaluate(traj, rels, max_span=args.max_span, min_span=args.min_span,
                   tolerance=args.tolerance)
    if args.json:
        out = dict(res)
        if args.label:
            out["label"] = args.label
        print(json.dumps(_json_safe(out), indent=2, sort_keys=True))
    else:
        print(format_result(res, args.label))
    if res["matched"] == 0:
        print("rsm-evaluate: no relation matched the trajectory", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
