import subprocess
import sys

import pytest

from conftest import TEST_DATA, read_maybe_gz, subprocess_env
from rsm_tools.carmen import LogStats, read_log, time_key
from rsm_tools.evaluate import evaluate, load_relations, odometry_trajectory
from rsm_tools.excerpt import excerpt_log, excerpt_poses, excerpt_relations, main


def _fl(ts):
    return f"FLASER 2 1.00 2.00 0 0 0 {ts:.1f} 0 0 {ts:.6f} h 0.0\n"


def _od(ts):
    return f"ODOM {ts:.1f} 0 0 0 0 0 {ts:.6f} h 0.0\n"


def _log_lines():
    """Scans at 10, 11, ..., 19 s; odometry every 0.5 s; a time-order quirk."""
    lines = ["# header\n"]
    for i in range(10):
        t = 10.0 + i
        lines += [_od(t - 0.25), _od(t + 0.25), _fl(t)]
    lines.insert(8, "PARAM robot x 12.2 h 0.0\n")
    lines.insert(9, "FLASER 9 1 2 3\n")  # malformed
    lines.insert(10, "# a comment in the middle\n")
    lines.append(_fl(14.5))  # written late, time goes backwards
    return lines


def _write(path, lines):
    path.write_text("".join(lines))
    return path


def test_first_scans_is_a_prefix_cut(tmp_path):
    lines = _log_lines()
    src = _write(tmp_path / "in.log", lines)
    res = excerpt_log(src, tmp_path / "out.log", first_scans=4)
    out = (tmp_path / "out.log").read_text().splitlines(keepends=True)
    last_scan = [i for i, l in enumerate(lines) if l == _fl(13.0)][0]
    assert out == lines[: last_scan + 1]
    assert res.scans == 4 and res.odom == 8 and res.malformed_kept == 1
    assert (res.t0, res.t1) == (10.0, 13.0)
    assert res.scan_index == {time_key(10.0 + i): i for i in range(4)}


def test_time_window(tmp_path):
    src = _write(tmp_path / "in.log", _log_lines())
    res = excerpt_log(src, tmp_path / "out.log", t0=12.0, t1=15.0)
    st = LogStats()
    recs = list(read_log(tmp_path / "out.log", stats=st))
    assert [r.timestamp for r in recs if r.kind == "FLASER"] == [12.0, 13.0, 14.0, 15.0, 14.5]
    assert [r.timestamp for r in recs if r.kind == "ODOM"] == [
        12.25, 12.75, 13.25, 13.75, 14.25, 14.75]
    assert st.comments == 2  # all comments are kept
    assert dict(st.unknown) == {"PARAM": 1}  # kept: its timestamp 12.2 is inside
    assert st.malformed_total == 0 and res.dropped_malformed == 1
    assert res.scans == 5 and (res.t0, res.t1) == (12.0, 15.0)
    with pytest.raises(ValueError):
        excerpt_log(src, tmp_path / "x.log", t0=3.0, t1=1.0)
    with pytest.raises(ValueError):
        excerpt_log(src, tmp_path / "x.log")


def test_relations_and_poses_follow_the_scans(tmp_path):
    src = _write(tmp_path / "in.log", _log_lines())
    rel = tmp_path / "in.relations"
    rel.write_text(
        "# relations\n"
        "12.000000 13.000000 1 0 0 0 0 0\n"
        "13.000000 14.500000 1 0 0 0 0 0\n"
        "11.000000 12.000000 1 0 0 0 0 0\n"       # t1 before the window
        "12.000000 12.500000 1 0 0 0 0 0\n"       # 12.5 is not a scan
        "15.000000 19.000000 1 0 0 0 0 0\n"       # t2 after the window
    )
    poses = tmp_path / "in.poses"
    poses.write_text("# poses\n11.0 1 0 0 0\n13.000000 3 1 2 3\n14.5 10 4 5 6\n")
    traj = tmp_path / "in.traj"
    traj.write_text("11.9 0 0 0\n12.0 0 0 0\n15.0 1 1 1\n15.1 2 2 2\n")
    res = excerpt_log(src, tmp_path / "out.log", t0=12.0, t1=15.0)
    assert excerpt_relations(rel, tmp_path / "out.relations", res) == (2, 5)
    assert (tmp_path / "out.relations").read_text().splitlines() == [
        "# relations", "12.000000 13.000000 1 0 0 0 0 0", "13.000000 14.500000 1 0 0 0 0 0"]
    assert excerpt_poses(poses, tmp_path / "out.poses", res) == (2, 3)
    # indices renumbered to the excerpt: scans 12, 13, 14, 15, 14.5 -> 0..4
    assert (tmp_path / "out.poses").read_text().splitlines() == [
        "# poses", "13.000000 1 1 2 3", "14.5 4 4 5 6"]
    assert excerpt_poses(traj, tmp_path / "out.traj", res) == (2, 4)
    assert (tmp_path / "out.traj").read_text().splitlines() == ["12.0 0 0 0", "15.0 1 1 1"]


def test_cli_gzip_output_is_deterministic(tmp_path):
    src = _write(tmp_path / "in.log", _log_lines())
    outs = []
    for name in ("a.clf.gz", "b.clf.gz"):
        assert main([str(src), str(tmp_path / name), "--first-scans", "3"]) == 0
        outs.append((tmp_path / name).read_bytes())
    assert outs[0] == outs[1] and outs[0][4:8] == b"\0\0\0\0"
    with pytest.raises(SystemExit):
        main([str(src), str(tmp_path / "c.log"), "--t0", "1"])


def test_excerpt_round_trip_on_shipped_data(head_log, head_relations, head_poses, tmp_path):
    """Cutting the shipped excerpt again, to its own size or span, changes nothing."""
    again = tmp_path / "again.clf.gz"
    proc = subprocess.run(
        [sys.executable, "-m", "rsm_tools.excerpt", str(head_log), str(again),
         "--first-scans", "600",
         "--relations", str(head_relations), str(tmp_path / "again.relations"),
         "--poses", str(head_poses), str(tmp_path / "again.poses")],
        capture_output=True, text=True, env=subprocess_env(),
    )
    assert proc.returncode == 0, proc.stderr
    assert "600 scans, 1177 ODOM" in proc.stdout
    # compare content: the compressed bytes depend on the zlib build
    assert read_maybe_gz(again) == read_maybe_gz(head_log)
    assert again.read_bytes()[4:8] == head_log.read_bytes()[4:8] == b"\0\0\0\0"
    assert (tmp_path / "again.relations").read_bytes() == head_relations.read_bytes()
    assert (tmp_path / "again.poses").read_bytes() == head_poses.read_bytes()

    # a time window over the excerpt's scans keeps all of its scans
    res = excerpt_log(head_log, tmp_path / "win.clf", first_scans=600)
    win = excerpt_log(head_log, tmp_path / "win.clf", t0=res.t0, t1=res.t1)
    assert win.scans == 600 and win.scan_index == res.scan_index
    assert excerpt_relations(head_relations, tmp_path / "win.relations", win) == (47, 47)

    # its odometry matches every relation exactly
    r = evaluate(odometry_trajectory(head_log), load_relations(head_relations), tolerance=0)
    assert r["matched"] == 47 and r["unmatched"] == 0


def test_shipped_excerpt_is_remade_from_a_longer_log(head_log, head_relations, head_poses, tmp_path):
    """tests/data was made by the command in tests/data/README.md from the
    full log (./tools/bench checks that on the full log itself). Here the
    full log is stood in for by the excerpt with 50 more scans after it, a
    relation reaching past the cut and pose rows beyond it: cutting at 600
    scans must give back the shipped files byte for byte."""
    head = read_maybe_gz(head_log).decode()
    last = [l for l in head.splitlines() if l.startswith("FLASER")][-1].split()
    t_last = float(last[-3])
    more = []
    for k in range(1, 51):
        f = list(last)
        f[-3] = f"{t_last + 0.2 * k:.6f}"
        more.append(" ".join(f))
    longer = tmp_path / "longer.clf"
    longer.write_text(head + "\n".join(more) + "\n")
    rel = tmp_path / "longer.relations"
    rel.write_text(head_relations.read_text() + f"{t_last:.6f} {t_last + 0.2:.6f} 0.1 0 0 0 0 0\n"
                   f"{t_last + 0.2:.6f} {t_last + 0.4:.6f} 0.1 0 0 0 0 0\n")
    poses = tmp_path / "longer.poses"
    poses.write_text(head_poses.read_text() + f"{t_last + 0.4:.6f} 602 1.0 2.0 0.5\n")

    res = excerpt_log(longer, tmp_path / "h.clf.gz", first_scans=600)
    assert read_maybe_gz(tmp_path / "h.clf.gz") == read_maybe_gz(head_log)
    excerpt_relations(rel, tmp_path / "h.relations", res)
    excerpt_poses(poses, tmp_path / "h.poses", res)
    assert (tmp_path / "h.relations").read_bytes() == head_relations.read_bytes()
    assert (tmp_path / "h.poses").read_bytes() == head_poses.read_bytes()
    assert res.relations_kept == 47 and res.poses_kept == 28
    # corrected poses keep their original scan indices (the cut starts at scan 0)
    for line in head_poses.read_text().splitlines():
        if not line.startswith("#"):
            t, idx = line.split()[:2]
            assert res.scan_index[time_key(float(t))] == int(idx)


def test_shipped_data_is_small():
    total = sum(p.stat().st_size for p in TEST_DATA.iterdir() if p.is_file())
    assert total < 300_000
