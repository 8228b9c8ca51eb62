"""rsm-plot: PNG over a PGM/YAML map; clear failure without matplotlib."""

import subprocess
import sys

from conftest import subprocess_env
from rsm_tools import plot


def write_map(tmp_path):
    w, h = 40, 30
    px = bytes(255 if 2 < x < w - 3 and 2 < y < h - 3 else 0 for y in range(h) for x in range(w))
    (tmp_path / "m.pgm").write_bytes(b"P5\n# test map\n%d %d\n255\n" % (w, h) + px)
    (tmp_path / "m.yaml").write_text("image: m.pgm\nresolution: 0.1\norigin: [-1.0, -0.5, 0.0]\n"
                                     "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    (tmp_path / "gt.txt").write_text("# t x y th\n" + "".join(f"{i} {i * 0.1} {i * 0.05} 0\n" for i in range(20)))
    (tmp_path / "est.txt").write_text("".join(f"{i} {i * 0.1 + 0.02} {i * 0.05} 0\n" for i in range(20)))


def test_map_loading(tmp_path):
    write_map(tmp_path)
    rows, extent = plot.load_map(str(tmp_path / "m.pgm"))
    assert len(rows) == 30 and len(rows[0]) == 40
    assert extent == [-1.0, 3.0, -0.5, 2.5]
    assert rows[0][0] == 0.0 and rows[15][20] == 1.0
    assert plot.load_map(str(tmp_path / "m.yaml"))[1] == extent


def test_plot_writes_png(tmp_path):
    write_map(tmp_path)
    out = tmp_path / "o.png"
    res = subprocess.run([sys.executable, "-m", "rsm_tools.plot", "--map", str(tmp_path / "m.pgm"),
                          "--trajectory", f"rsm={tmp_path / 'est.txt'}", "--ground-truth",
                          str(tmp_path / "gt.txt"), "-o", str(out)],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 0, res.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 2000


def test_missing_matplotlib_names_the_extra(tmp_path):
    write_map(tmp_path)
    code = ("import sys; sys.modules['matplotlib'] = None\n"
            "from rsm_tools import plot\n"
            f"sys.exit(plot.main(['--trajectory', 'a={tmp_path / 'est.txt'}', '-o', '{tmp_path / 'x.png'}']))\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 1
    assert "matplotlib" in res.stderr and "rsm-tools[plot]" in res.stderr
    assert not (tmp_path / "x.png").exists()


def test_corrected_poses_load_and_align_rigidly_onto_a_trajectory(tmp_path):
    import math
    # ground truth in another frame: rotated by 90 deg and shifted
    (tmp_path / "gt5.txt").write_text("# ts idx x y th\n10.0 3 5.0 5.0 1.5707963\n20.0 7 5.0 6.0 1.5707963\n")
    truth = plot.load_trajectory(str(tmp_path / "gt5.txt"))
    assert truth[0] == (10.0, 5.0, 5.0, 1.5707963)
    traj = [(t * 1.0, 0.1 * t, 0.0, 0.0) for t in range(30)]
    got = plot.align_to(truth, traj)
    assert abs(got[0][1] - 1.0) < 1e-9 and abs(got[0][2]) < 1e-9 and abs(got[0][3]) < 1e-7
    # one metre along the ground truth's heading is one metre along +x here
    assert abs(got[1][1] - 2.0) < 1e-6 and abs(got[1][2]) < 1e-6
    assert abs(math.hypot(got[1][1] - got[0][1], got[1][2] - got[0][2]) - 1.0) < 1e-9
    try:
        plot.align_to(truth, [(99.0, 0.0, 0.0, 0.0)])
    except plot.PlotError as exc:
        assert "no ground-truth stamp" in str(exc)
    else:
        raise AssertionError("aligning without a common stamp must fail")
