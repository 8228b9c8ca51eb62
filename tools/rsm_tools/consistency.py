"""Whether the covariance rsm reports matches its real error.

rsm-nav's ``--scan-log`` ends each line with the pose's covariance (xx xy
xt yy yt tt). Against a log's ground-truth relations, each relation between
two scans that both carry one gives a normalized error

    NEES = e^T S^-1 e,   S = J1 P1 J1^T + J2 P2 J2^T

where e is the relation's error (the estimate's relative pose less the
true one) and J1, J2 the relative pose's Jacobians in the two poses. With
an honest covariance and independent errors at the two ends NEES follows a
chi-square law with 3 degrees of freedom: mean 3, median 2.37, 95 % below
7.81. Errors at nearby scans that share the map's own errors are not
independent, which lowers NEES: a figure far above 3 is overconfidence
whatever the correlation. The relations' own errors raise it too (on ACES
odometry alone is about as close to them locally as any matcher).

Used by the bench (accuracy section) and as a command:

    python3 -m rsm_tools.consistency TRAJECTORY RELATIONS SCAN_LOG [--max-span S]
"""
import argparse
import math
import statistics
import sys
from typing import Dict, List, Optional, Sequence

from . import evaluate as ev

CHI2_3_MEDIAN = 2.366
CHI2_3_95 = 7.815
Matrix = List[List[float]]


def read_covariances(path) -> Dict[str, Matrix]:
    """Stamp text (6 decimals) -> 3x3 covariance, from a scan log's lines
    that carry one (12 fields); lines without it are skipped."""
    out = {}
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            f = line.split()
            if len(f) < 12 or line.startswith("#"):
                continue
            try:
                xx, xy, xt, yy, yt, tt = (float(v) for v in f[6:12])
            except ValueError:
                continue
            out[f"{float(f[0]):.6f}"] = [[xx, xy, xt], [xy, yy, yt], [xt, yt, tt]]
    return out


def _jacobians(a: Sequence[float], b: Sequence[float]):
    """d between(a, b) / d a and / d b, analytically: r = R(-ta) (pb - pa),
    r_theta = tb - ta."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    ja = [[-c, -s, -s * dx + c * dy],
          [s, -c, -c * dx - s * dy],
          [0.0, 0.0, -1.0]]
    jb = [[c, s, 0.0],
          [-s, c, 0.0],
          [0.0, 0.0, 1.0]]
    return ja, jb


def _sandwich(j: Matrix, p: Matrix) -> Matrix:
    jp = [[sum(j[r][k] * p[k][c] for k in range(3)) for c in range(3)] for r in range(3)]
    return [[sum(jp[r][k] * j[c][k] for k in range(3)) for c in range(3)] for r in range(3)]


def _solve3(m: Matrix, v: Sequence[float]) -> Optional[List[float]]:
    """m^-1 v by Cramer's rule; None for a singular m."""
    def det(a):
        return (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
                - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
                + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))
    d = det(m)
    if not (abs(d) > 0.0) or not math.isfinite(d):
        return None
    out = []
    for col in range(3):
        mc = [[v[r] if c == col else m[r][c] for c in range(3)] for r in range(3)]
        out.append(det(mc) / d)
    return out


def nees(traj: ev.Trajectory, relations: Sequence[ev.Relation], cov: Dict[str, Matrix],
         max_span: Optional[float] = ev.LOCAL_SPAN) -> dict:
    """NEES over the relations (span at most max_span; None: all) whose two
    stamps the trajectory and the covariances both hold exactly. Returns
    the count, mean, median, the share below chi-square's 95 % point, the
    heading's own normalized error (mean, median: 1 and 0.45 when honest),
    and the median reported and real relative translation error (m)."""
    full, heading, sd, err = [], [], [], []
    for r in relations:
        if max_span is not None and r.span > max_span:
            continue
        a, b = traj.lookup(r.t1, tolerance=0.0), traj.lookup(r.t2, tolerance=0.0)
        pa, pb = cov.get(f"{r.t1:.6f}"), cov.get(f"{r.t2:.6f}")
        if a is None or b is None or pa is None or pb is None:
            continue
        a, b = tuple(a), tuple(b)
        est = ev.between(a, b)
        e = [est[0] - r.x, est[1] - r.y, ev.wrap_angle(est[2] - r.yaw)]
        ja, jb = _jacobians(a, b)
        sa, sb = _sandwich(ja, pa), _sandwich(jb, pb)
        s = [[sa[i][k] + sb[i][k] for k in range(3)] for i in range(3)]
        w = _solve3(s, e)
        if w is None or not s[2][2] > 0.0:
            continue
        full.append(sum(e[i] * w[i] for i in range(3)))
        heading.append(e[2] * e[2] / s[2][2])
        sd.append(math.sqrt(max(s[0][0] + s[1][1], 0.0)))
        err.append(math.hypot(e[0], e[1]))
    if not full:
        return {"relations": 0}
    return {"relations": len(full), "mean": statistics.fmean(full), "median": statistics.median(full),
            "within95": sum(1 for v in full if v <= CHI2_3_95) / len(full),
            "heading_mean": statistics.fmean(heading), "heading_median": statistics.median(heading),
            "reported_m": statistics.median(sd), "error_m": statistics.median(err)}


def describe(res: dict) -> str:
    if not res.get("relations"):
        return "no relation with a covariance at both ends"
    return (f"{res['relations']} relations: NEES mean {res['mean']:.1f}, median {res['median']:.1f} (honest: 3 and "
            f"{CHI2_3_MEDIAN:.2f}), {100.0 * res['within95']:.0f} % within chi-square's 95 % point (honest: 95 %); "
            f"heading alone median {res['heading_median']:.2f} (honest: 0.45); relative translation error median "
            f"{res['error_m']:.4f} m against a reported standard deviation median {res['reported_m']:.4f} m")


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m rsm_tools.consistency",
                                 description="NEES of rsm-nav's reported covariance against ground-truth relations")
    ap.add_argument("trajectory")
    ap.add_argument("relations")
    ap.add_argument("scan_log", help="rsm-nav --scan-log of the same run")
    ap.add_argument("--max-span", type=float, default=ev.LOCAL_SPAN,
                    help=f"relations spanning at most this many seconds (default {ev.LOCAL_SPAN:g}; 0: all)")
    a = ap.parse_args(argv)
    res = nees(ev.load_trajectory(a.trajectory), ev.load_relations(a.relations), read_covariances(a.scan_log),
               a.max_span if a.max_span > 0 else None)
    print(describe(res))
    return 0 if res.get("relations") else 1


if __name__ == "__main__":
    sys.exit(main())
