"""rsm-nav on a known map (issue 31): --save-map, --load-map (rsm maps and
ROS map_server maps), --freeze-map, --global and --skip-seconds, on the
shipped excerpt.

The floors on the full logs (100 global starts, localization mode over a
whole log) are the bench's (./tools/bench, section "Known map").
"""

import json
import math
import subprocess
from pathlib import Path

from conftest import rsm_nav_binary as nav_binary
from rsm_tools import evaluate as ev

HEADER = 48


def nav(log: Path, traj: Path, *extra: str, ok: bool = True) -> subprocess.CompletedProcess:
    cmd = [str(nav_binary()), "--carmen", str(log), "--trajectory", str(traj), "--quiet", *extra]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if ok:
        assert res.returncode == 0, f"rsm-nav failed ({res.returncode}): {res.stderr}"
    return res


def poses(traj: Path) -> dict:
    out = {}
    for line in traj.read_text().splitlines():
        if line and not line.startswith("#"):
            t, x, y, th = (float(v) for v in line.split()[:4])
            out[round(t, 6)] = (x, y, th)
    return out


def mean_error(traj: Path, relations: Path) -> float:
    res = ev.evaluate(ev.load_trajectory(traj), ev.load_relations(relations), tolerance=0.0)
    return res["translation"]["mean"]


def mapped(tmp_path: Path, head_log: Path) -> tuple:
    traj = tmp_path / "map.txt"
    rsmm = tmp_path / "map.rsmm"
    out = nav(head_log, traj, "--save-map", str(rsmm), "--map", str(tmp_path / "map.pgm")).stdout
    return traj, rsmm, out


def test_saved_map_has_the_documented_size_and_loads_frozen_unchanged(tmp_path, head_log, head_relations):
    traj, rsmm, out = mapped(tmp_path, head_log)
    data = rsmm.read_bytes()
    assert data[:4] == b"RSMM"
    tiles = int.from_bytes(data[24:28], "little")
    assert len(data) == HEADER + 40 * tiles + 4
    assert f"map saved       {rsmm}: {len(data)} bytes, {tiles} tiles" in out
    # Localization mode: the map read, never written; the tiles saved again
    # are the tiles loaded, and the run is as accurate as the mapping run.
    again = tmp_path / "again.rsmm"
    frozen = tmp_path / "frozen.txt"
    res = nav(head_log, frozen, "--load-map", str(rsmm), "--freeze-map", "--save-map", str(again),
              "--summary-json", str(tmp_path / "s.json"))
    assert f"loaded map      {rsmm}: {len(data)} bytes, {tiles} tiles, frozen" in res.stdout
    assert again.read_bytes()[HEADER:-4] == data[HEADER:-4]
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["tmap"]["writes"] == 0
    assert summary["loaded_map"] == {"bytes": len(data), "tiles": tiles}
    assert mean_error(frozen, head_relations) <= mean_error(traj, head_relations) + 0.002
    # With updates on, the map is written again.
    nav(head_log, tmp_path / "upd.txt", "--load-map", str(rsmm), "--summary-json", str(tmp_path / "u.json"))
    assert json.loads((tmp_path / "u.json").read_text())["tmap"]["writes"] > 0


def test_global_start_writes_nothing_until_a_pose_is_proven_and_that_pose_is_right(tmp_path, head_log):
    traj, rsmm, _ = mapped(tmp_path, head_log)
    ref = poses(traj)
    found = tmp_path / "g.txt"
    js = tmp_path / "g.json"
    res = nav(head_log, found, "--load-map", str(rsmm), "--global", "--skip-seconds", "20", "--freeze-map",
              "--summary-json", str(js))
    g = json.loads(js.read_text())["global"]
    assert g["found"] == 1 and g["searches"] >= 1
    assert g["max_work_per_scan"] <= 100000 + 16 * 32
    got = poses(found)
    first = next(iter(got))
    assert first == round(g["first_trusted_stamp"], 6)
    # Every scan before the first trusted one wrote no line (stamps in the
    # log's order: they may step back a little).
    order = list(ref)
    log_stamps = [t for t in order if t >= order[0] + 20.0]
    assert log_stamps.index(first) == g["first_trusted_scan"] - 1
    assert list(got) == log_stamps[g["first_trusted_scan"] - 1:]
    x, y, th = got[first]
    rx, ry, rth = ref[first]
    assert math.hypot(x - rx, y - ry) < 0.1
    assert abs(math.remainder(th - rth, 2 * math.pi)) < math.radians(2)
    assert "first pose      scan" in res.stdout


def test_global_near_a_rough_start_pose_proves_it_sooner(tmp_path, head_log):
    traj, rsmm, _ = mapped(tmp_path, head_log)
    ref = poses(traj)
    order = list(ref)
    start = next(t for t in order if t >= order[0] + 20.0)
    x, y, th = ref[start]
    runs = {}
    for name, opts in (("near", ["--global-near", "1.0"]), ("all", ["--global"])):
        js = tmp_path / f"{name}.json"
        out = tmp_path / f"{name}.txt"
        nav(head_log, out, "--load-map", str(rsmm), *opts, "--initial-pose", f"{x + 0.4:.4f}", f"{y - 0.3:.4f}",
            f"{th + 0.3:.4f}", "--skip-seconds", "20", "--freeze-map", "--summary-json", str(js))
        g = json.loads(js.read_text())["global"]
        got = poses(out)
        first = next(iter(got))
        gx, gy, gth = got[first]
        rx, ry, rth = ref[first]
        assert math.hypot(gx - rx, gy - ry) < 0.1, name
        assert abs(math.remainder(gth - rth, 2 * math.pi)) < math.radians(2), name
        runs[name] = g
    # The window cuts the search's reads; the proof's steps, counted in the
    # work too (3 000 a kept pose and round, 12 000 the winner), it does not
    # cut: the excerpt's whole-map search reads about as much as its proof.
    assert runs["near"]["work"] < runs["all"]["work"] * 0.7
    assert runs["near"]["first_trusted_scan"] <= runs["all"]["first_trusted_scan"]
    res = nav(head_log, tmp_path / "t.txt", "--load-map", str(rsmm), "--global-near", "-2", ok=False)
    assert res.returncode == 2 and "--global-near" in res.stderr


def test_ros_map_written_by_rsm_nav_loads_and_localizes(tmp_path, head_log, head_relations):
    traj, _, _ = mapped(tmp_path, head_log)
    ros = tmp_path / "ros.txt"
    res = nav(head_log, ros, "--load-map", str(tmp_path / "map.yaml"), "--freeze-map")
    assert "a ROS map" in res.stdout and ", frozen" in res.stdout
    assert mean_error(ros, head_relations) < 0.03


def test_damaged_or_foreign_maps_are_refused_with_a_reason(tmp_path, head_log):
    _, rsmm, _ = mapped(tmp_path, head_log)
    data = bytearray(rsmm.read_bytes())
    cases = {
        "flipped": (lambda d: d.__setitem__(len(d) // 2, d[len(d) // 2] ^ 0x10), "checksum mismatch"),
        "truncated": (lambda d: d.__delitem__(slice(len(d) - 7, len(d))), "ends early"),
        "foreign": (lambda d: d.__setitem__(0, ord("X")), "not a map of this format"),
    }
    for name, (damage, reason) in cases.items():
        bad = bytearray(data)
        damage(bad)
        path = tmp_path / f"{name}.rsmm"
        path.write_bytes(bytes(bad))
        res = nav(head_log, tmp_path / f"{name}.txt", "--load-map", str(path), ok=False)
        assert res.returncode != 0, name
        assert "is refused" in res.stderr and reason in res.stderr, (name, res.stderr)
    res = nav(head_log, tmp_path / "none.txt", "--load-map", str(tmp_path / "missing.rsmm"), ok=False)
    assert res.returncode != 0 and "cannot open the map" in res.stderr


def test_known_map_options_are_checked(tmp_path, head_log):
    res = nav(head_log, tmp_path / "t.txt", "--global", ok=False)
    assert res.returncode == 2 and "--load-map" in res.stderr
    for bad in ("-1", "x", "nan"):
        res = nav(head_log, tmp_path / "t.txt", "--skip-seconds", bad, ok=False)
        assert res.returncode == 2 and "--skip-seconds" in res.stderr, bad
    res = nav(head_log, tmp_path / "t.txt", "--method", "icp", "--save-map", str(tmp_path / "m"), ok=False)
    assert res.returncode == 2 and "--method rsm" in res.stderr
    res = nav(head_log, tmp_path / "t.txt", "--method", "icp", "--tile-store", "100", ok=False)
    assert res.returncode == 2 and "--method rsm" in res.stderr
    for bad in ("-1", "x", "1e3", str((1 << 28) + 1)):
        res = nav(head_log, tmp_path / "t.txt", "--tile-store", bad, ok=False)
        assert res.returncode == 2 and "--tile-store" in res.stderr, bad


def test_a_tile_store_the_pool_never_needs_changes_nothing(tmp_path, head_log):
    """The excerpt's map fits the pool: with a store behind it (rsm-nav
    --tile-store) nothing is let go, and the run and the saved map are the
    same bytes as without (tests/unit/test_tilestore.c tests a pool that
    overflows)."""
    plain, stored = tmp_path / "plain.txt", tmp_path / "stored.txt"
    nav(head_log, plain, "--save-map", str(tmp_path / "plain.rsmm"))
    js = tmp_path / "s.json"
    nav(head_log, stored, "--tile-store", "1000", "--save-map", str(tmp_path / "stored.rsmm"), "--summary-json",
        str(js))
    assert plain.read_bytes() == stored.read_bytes()
    assert (tmp_path / "plain.rsmm").read_bytes() == (tmp_path / "stored.rsmm").read_bytes()
    tmap = json.loads(js.read_text())["tmap"]
    assert tmap["stored"] == 0 and tmap["fetched"] == 0 and tmap["store_tiles"] == 0


def test_skip_seconds_starts_later_in_the_log(tmp_path, head_log):
    full = tmp_path / "full.txt"
    late = tmp_path / "late.txt"
    nav(head_log, full)
    nav(head_log, late, "--skip-seconds", "30")
    a = sorted(poses(full))
    b = sorted(poses(late))
    assert b[0] >= a[0] + 30.0 and b == [t for t in a if t >= a[0] + 30.0]
    short = tmp_path / "short.txt"
    nav(head_log, short, "--skip-seconds", "30", "--scans", "25")
    assert sorted(poses(short)) == b[:25]
    res = nav(head_log, short, "--skip-seconds", "1e9", ok=False)
    assert res.returncode == 1 and "no scan from --skip-seconds on" in res.stderr, res.stderr
    for bad in ("0", "-3", " -1", "x"):
        res = nav(head_log, short, "--scans", bad, ok=False)
        assert res.returncode == 2 and "--scans" in res.stderr, bad
