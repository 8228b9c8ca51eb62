"""rsm_tools.consistency: the normalized error of the covariance rsm-nav
reports (issue 29, "a covariance that matches the real error")."""
import math
import random

import pytest

from rsm_tools import consistency as cs
from rsm_tools import evaluate as ev


def _cholesky3(m):
    l = [[0.0] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(i + 1):
            s = m[i][j] - sum(l[i][k] * l[j][k] for k in range(j))
            l[i][j] = math.sqrt(s) if i == j else s / l[j][j]
    return l


def _synthetic(n, cov, scale_reported=1.0, seed=5):
    """A wandering trajectory whose every pose is off the truth by a draw
    from cov (independent draws), the truth's consecutive relations, and
    the covariance the estimate reports (cov times scale_reported)."""
    rng = random.Random(seed)
    l = _cholesky3(cov)
    truth, est, rels, reported = [], ev.Trajectory(), [], {}
    x = y = th = 0.0
    for k in range(n):
        t = 1000.0 + 0.2 * k
        x += 0.1 * math.cos(th)
        y += 0.1 * math.sin(th)
        th = ev.wrap_angle(th + 0.05 * math.sin(0.01 * k))
        z = [rng.gauss(0.0, 1.0) for _ in range(3)]
        d = [sum(l[i][j] * z[j] for j in range(3)) for i in range(3)]
        truth.append((t, x, y, th))
        est.add(t, x + d[0], y + d[1], ev.wrap_angle(th + d[2]))
        reported[f"{t:.6f}"] = [[scale_reported * v for v in row] for row in cov]
    for a, b in zip(truth, truth[1:]):
        r = ev.between(a[1:], b[1:])
        rels.append(ev.Relation(a[0], b[0], r[0], r[1], r[2]))
    return est, rels, reported


COV = [[4e-4, 1e-4, 2e-5], [1e-4, 9e-4, -3e-5], [2e-5, -3e-5, 1e-4]]


def test_an_honest_covariance_gives_chi_square_3():
    est, rels, reported = _synthetic(4000, COV)
    res = cs.nees(est, rels, reported)
    assert res["relations"] == 3999
    assert 2.8 < res["mean"] < 3.2, res
    assert 2.1 < res["median"] < 2.6, res
    assert 0.93 < res["within95"] < 0.97, res
    assert 0.85 < res["heading_mean"] < 1.15, res


def test_an_overconfident_covariance_shows():
    est, rels, reported = _synthetic(4000, COV, scale_reported=0.1)
    honest = cs.nees(*_synthetic(4000, COV))
    res = cs.nees(est, rels, reported)
    assert res["mean"] == pytest.approx(10.0 * honest["mean"], rel=1e-6)
    assert res["within95"] < 0.5
    assert "NEES mean" in cs.describe(res)


def test_the_jacobians_are_the_derivatives():
    a, b = (0.3, -1.2, 2.5), (1.7, 0.4, -2.9)
    ja, jb = cs._jacobians(a, b)
    h = 1e-6
    base = ev.between(a, b)
    for k in range(3):
        for jac, which in ((ja, 0), (jb, 1)):
            p = [list(a), list(b)]
            p[which][k] += h
            moved = ev.between(tuple(p[0]), tuple(p[1]))
            for i in range(3):
                d = (ev.wrap_angle(moved[i] - base[i]) if i == 2 else moved[i] - base[i]) / h
                assert d == pytest.approx(jac[i][k], abs=1e-4)


def test_lines_without_a_covariance_and_zero_ones_are_left_out(tmp_path):
    log = tmp_path / "scans.txt"
    log.write_text("# rsm-nav scan log: ...\n"
                   "1000.000000 first tracking trusted 0 0.0000 0 0 0 0 0 0\n"
                   "1000.200000 accepted tracking trusted 0 1.0000\n"
                   "1000.400000 accepted tracking trusted 0 1.0000 1e-4 0 0 1e-4 0 1e-5\n"
                   "1000.600000 accepted tracking trusted 0 1.0000 1e-4 0 0 1e-4 0 1e-5\n")
    cov = cs.read_covariances(log)
    assert sorted(cov) == ["1000.000000", "1000.400000", "1000.600000"]
    est = ev.Trajectory()
    for t in (1000.0, 1000.2, 1000.4, 1000.6):
        est.add(t, 0.0, 0.0, 0.0)
    rels = [ev.Relation(1000.0, 1000.2, 0.0, 0.0, 0.0), ev.Relation(1000.0, 1000.4, 0.01, 0.0, 0.0),
            ev.Relation(1000.4, 1000.6, 0.01, 0.0, 0.0)]
    res = cs.nees(est, rels, cov)
    # the first needs 1000.2's covariance (none); the second's start is the
    # first scan, exact by definition (zeros), so its end's covariance alone
    # counts; the third has both
    assert res["relations"] == 2
    assert res["mean"] == pytest.approx(0.5 * (0.01 ** 2 / 1e-4 + 0.01 ** 2 / 2e-4))
    assert cs.nees(est, rels[:1], cov) == {"relations": 0}
