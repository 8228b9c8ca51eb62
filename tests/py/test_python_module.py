"""The Python module (port/python, docs/python.md): ``pip install .`` of the
repository, offline (no build isolation: the venv's setuptools builds it),
into a temporary folder, then the shipped excerpt localized through it.
Its trajectory must be rsm-nav --carmen's to the printed precision, line
for line; its map, configuration errors, counters and docs/python.md's
example are checked against what the C library does."""

import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import REPO_ROOT, rsm_nav_binary
from rsm_tools import carmen


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The folder `pip install --target` put the module in."""
    target = tmp_path_factory.mktemp("site")
    cmd = [sys.executable, "-m", "pip", "install", "--no-build-isolation", "--no-deps", "--no-index",
           "--no-cache-dir", "--disable-pip-version-check", "-q", "--target", str(target), str(REPO_ROOT)]
    # Built afresh (no objects of an earlier build reused), outside the checkout.
    env = dict(os.environ, RSM_PY_BUILD_DIR=str(tmp_path_factory.mktemp("build")))
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=env)
    assert run.returncode == 0, run.stdout + run.stderr
    return target


@pytest.fixture(scope="module")
def rsm(site):
    sys.path.insert(0, str(site))
    try:
        import rsm as module
    finally:
        sys.path.remove(str(site))
    # The installed copy, not a folder of the checkout.
    assert Path(module.__file__).resolve().parent == (site / "rsm").resolve()
    yield module
    del sys.modules["rsm"]


def flaser_records(path):
    return [r for r in carmen.read_log(path, types={"FLASER"})]


def stamp_us(seconds: float) -> int:
    # llround in rsm-nav (logrun_stamp_us); the excerpt's stamps are positive.
    return int(math.floor(seconds * 1e6 + 0.5))


def localize(rsm, records, config=None):
    """The excerpt as rsm-nav --carmen runs it: start at the first odometry
    pose, the step between log poses before each later scan, 180 beams of
    1 degree from -90, stamps clamped so that they never go backwards."""
    loc = rsm.Localizer(config, pose=records[0].odom_pose)
    start, step = np.float32(-math.pi / 2), np.float32(math.pi) / np.float32(180)
    last_us, prev, reports = 0, None, []
    for rec in records:
        if prev is not None:
            loc.motion(*rsm.odometry_step(prev, rec.odom_pose))
        prev = rec.odom_pose
        last_us = max(last_us, stamp_us(rec.timestamp))
        reports.append(loc.scan(last_us, rec.ranges, start=float(start), step=float(step)))
    return loc, reports


@pytest.fixture(scope="module")
def records(head_log):
    recs = flaser_records(head_log)
    assert len(recs) == 600 and all(len(r.ranges) == 180 and r.mount is None for r in recs)
    return recs


@pytest.fixture(scope="module")
def run(rsm, records):
    return localize(rsm, records)


def test_trajectory_equals_rsm_nav(run, records, head_log, tmp_path):
    loc, reports = run
    traj = tmp_path / "nav.txt"
    subprocess.run([str(rsm_nav_binary()), "--carmen", str(head_log), "--trajectory", str(traj), "--quiet"],
                   check=True, capture_output=True, timeout=300)
    want = [line for line in traj.read_text().splitlines() if not line.startswith("#")]
    got = ["%.6f %.6f %.6f %.6f" % ((rec.timestamp,) + rep.pose) for rec, rep in zip(records, reports)]
    assert len(want) == len(got) == 600
    diff = [(k, w, g) for k, (w, g) in enumerate(zip(want, got)) if w != g]
    assert not diff, diff[:5]
    # A run that localized: nearly every scan matched and fused, tracking at the end.
    counters = loc.counters()
    assert counters["scans"] == 600 and counters["motions"] == 599
    assert counters["outcome.first"] == 1 and counters["outcome.accepted"] >= 590
    assert loc.track == "tracking" and reports[-1].track == "tracking"
    assert loc.pose == reports[-1].pose
    # The report's covariance is the estimate's: symmetric, positive.
    cov = reports[-1].cov
    assert np.array_equal(cov, loc.covariance) and np.allclose(cov, cov.T)
    assert np.all(np.linalg.eigvalsh(cov) > 0.0)


def test_motion_grows_the_covariance(rsm, records):
    loc, reports = localize(rsm, records[:20])
    before, pose = loc.covariance, loc.pose
    assert pose == reports[-1].pose and np.array_equal(before, reports[-1].cov)
    loc.motion(0.5, 0.0, 0.2)
    after = loc.covariance
    assert np.trace(after) > np.trace(before) and np.allclose(after, after.T)
    # Half a metre ahead of the last estimate, turned by 0.2 rad.
    x, y, th = loc.pose
    assert x == pytest.approx(pose[0] + 0.5 * math.cos(pose[2]), abs=1e-5)
    assert y == pytest.approx(pose[1] + 0.5 * math.sin(pose[2]), abs=1e-5)
    assert th == pytest.approx(pose[2] + 0.2, abs=1e-5)


def test_map_is_a_numpy_array_of_the_map(run):
    loc, reports = run
    m = loc.map()
    x0, y0, x1, y1 = loc.map_bounds()
    assert m.cell == pytest.approx(0.05) and m.origin == (x0, y0)
    assert m.occupancy.dtype == np.float32
    assert m.occupancy.shape == (round((y1 - y0) / m.cell), round((x1 - x0) / m.cell))
    assert m.occupancy.min() >= 0.0 and m.occupancy.max() == 1.0
    occupied = m.occupancy > 0.0
    assert 2000 < occupied.sum() < 0.5 * occupied.size

    def cell_of(x, y):
        return int((y - y0) // m.cell), int((x - x0) // m.cell)

    # Where the robot stood is free: the map is not transposed or shifted.
    stood = [m.occupancy[cell_of(*rep.pose[:2])] for rep in reports]
    assert sum(v == 0.0 for v in stood) >= 0.95 * len(stood)
    # The last scan's returns, placed at the last pose, fall on walls.
    x, y, th = reports[-1].pose
    pts = loc.scan_points()
    assert pts.shape == (reports[-1].points, 2) and len(pts) > 100
    c, s = math.cos(th), math.sin(th)
    on_wall = 0
    for px, py in pts.astype(float):
        j, i = cell_of(x + c * px - s * py, y + s * px + c * py)
        on_wall += m.occupancy[max(j - 1, 0):j + 2, max(i - 1, 0):i + 2].max() > 0.0
    assert on_wall >= 0.9 * len(pts)
    # A coarser raster covers the same box.
    coarse = loc.map(cell=0.2)
    assert coarse.occupancy.shape == (round((y1 - y0) / 0.2), round((x1 - x0) / 0.2))
    assert coarse.extent == pytest.approx((x0, x1, y0, y1), abs=1e-4)
    assert m.world(0, 0) == pytest.approx((x0 + 0.025, y0 + 0.025))


def test_nan_ranges_are_counted_as_drops(rsm, records):
    rec = records[0]
    plain = rsm.Localizer(pose=rec.odom_pose)
    full = plain.scan(1, rec.ranges, start=-math.pi / 2, step=math.pi / 180)
    ranges = np.array(rec.ranges)
    ranges[[3, 50, 51, 120, 179]] = np.nan
    ranges[60] = np.inf
    loc = rsm.Localizer(pose=rec.odom_pose)
    rep = loc.scan(1, ranges, np.linspace(-math.pi / 2, math.pi / 2, 180))
    assert loc.counters()["drops.nan"] == 6 and plain.counters()["drops.nan"] == 0
    assert rep.points == full.points - 6 == len(loc.scan_points())


def test_config_errors_name_the_field(rsm):
    cases = [({"grid.sigma_m": -1.0, "method": rsm.METHOD_PAPER}, "grid.sigma_m"),
             ({"recover_m": -1.0}, "recover_m"),
             ({"odometry.wheel_base_m": 0.0}, "odometry.wheel_base_m"),
             ({"tmap.levels": 256}, "tmap.levels"),
             ({"lost_scans": 2.5}, "lost_scans"),
             ({"method": 7}, "method"),
             ({"map_update_m": 1e39}, "map_update_m"),
             ({"map_update_m": "0.3"}, "map_update_m"),
             ({"map_updates_m": 0.3}, "map_updates_m")]
    for config, field in cases:
        with pytest.raises(rsm.ConfigError) as err:
            rsm.Localizer(config)
        assert err.value.field == field and field in str(err.value) and err.value.code == rsm.ERR_INVAL
        assert isinstance(err.value, ValueError)
    # The fields given are those in force; the rest is the default.
    loc = rsm.Localizer({"map_update_m": 0.3, "lost_scans": 4, "method": rsm.METHOD_ICP})
    want = dict(rsm.default_config(), map_update_m=float(np.float32(0.3)), lost_scans=4, method=rsm.METHOD_ICP)
    assert loc.config == want


def test_bad_calls_raise_with_the_library_status(rsm, records):
    loc = rsm.Localizer(pose=records[0].odom_pose)
    with pytest.raises(rsm.Error) as err:
        loc.motion(float("nan"), 0.0, 0.0)
    assert err.value.code == rsm.ERR_RANGE and loc.counters()["bad_motions"] == 1
    loc.scan(2000, records[0].ranges, start=-math.pi / 2, step=math.pi / 180)
    with pytest.raises(rsm.Error) as err:
        loc.scan(1000, records[1].ranges, start=-math.pi / 2, step=math.pi / 180)
    assert err.value.code == rsm.ERR_ORDER and loc.counters()["outcome.out_of_order"] == 1
    with pytest.raises(ValueError):
        loc.scan(3000, np.ones(rsm.MAX_BEAMS + 1), start=0.0, step=0.001)
    with pytest.raises(rsm.Error) as err:
        rsm.Localizer({"method": rsm.METHOD_ODOMETRY}).map()
    assert err.value.code == rsm.ERR_NOSYS


def struct_fields(headers):
    """Every field of every typedef'd struct in the headers, by struct type:
    [(type, name), ...] (arrays and pointers marked by the name's suffix)."""
    text = re.sub(r"/\*.*?\*/", "", "\n".join(h.read_text() for h in headers), flags=re.S)
    out = {}
    for body, name in re.findall(r"typedef struct \w+ \{(.*?)\} (\w+);", text, flags=re.S):
        members = []
        for stmt in body.split(";"):
            m = re.fullmatch(r"\s*(?:const\s+)?(\w+)\s*(\*?)\s*(\w+)\s*(\[[^\]]*\])?\s*", stmt)
            if m:
                members.append((m.group(1), m.group(3) + ("*" if m.group(2) else "") + (m.group(4) or "")))
            elif stmt.strip():
                members.append(("?", stmt.strip()))
        out[name] = members
    return out


def test_every_config_field_is_there_in_the_headers_order(rsm):
    structs = struct_fields(sorted((REPO_ROOT / "include" / "rsm").glob("*.h")))

    def expand(type_name, prefix):
        for typ, name in structs[type_name]:
            if typ in structs:
                yield from expand(typ, prefix + name + ".")
            else:
                yield prefix + name

    # The timing hook (a function pointer and its context) is C's alone.
    want = [f for f in expand("rsm_localizer_config_t", "")
            if f != "clock_ctx*" and "(*clock_fn)" not in f]
    assert len(want) > 100 and list(rsm.config_fields()) == want


def test_python_md_example_runs(site):
    text = (REPO_ROOT / "docs" / "python.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "docs/python.md has no python example"
    run = subprocess.run([sys.executable, "-c", blocks[0]], cwd=REPO_ROOT, capture_output=True, text=True,
                         timeout=300, env=dict(os.environ, PYTHONPATH=str(site)))
    assert run.returncode == 0, run.stderr
    # It prints what it says it prints: the scans and the final pose.
    last = run.stdout.strip().splitlines()[-1]
    assert re.fullmatch(r"600 scans, 5\d\d accepted, final pose -?\d+\.\d+ -?\d+\.\d+ -?\d+\.\d+, tracking, "
                        r"map \d+ x \d+ cells", last), run.stdout
