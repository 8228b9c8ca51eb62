"""The README's first command, ./tools/demo, run end to end (issues 30, 32).

The demo once failed on every fresh clone because a command it called had
been renamed and nothing ran it. This test runs the script itself, from its
first line to its last, inside the finished build (RSM_DEMO_BUILD: set-up
and build are tools/test's stages), with the live run fed in lockstep
(RSM_DEMO_LOCKSTEP: rsm-replay --lockstep), so that every figure is a
function of the shipped bytes and not of the machine's load. It checks what
the demo promises a newcomer: the whole Intel log's figures, with rsm far
ahead of odometry and of the paper's method, the picture, the live replay of
the excerpt, and all of it in at most about 40 lines that end with the
figures and the picture's path.
"""

import json
import re
import subprocess
from pathlib import Path

import pytest

from conftest import REPO_ROOT, build_dir, project_venv

MAX_LINES = 40
ROW = re.compile(r"^  (rsm|the paper's method|odometry alone) +([0-9.]+) m +([0-9.]+) deg +([0-9.]+) m +([0-9.]+) deg$",
                 re.M)



@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("demo")
    out = tmp / "out"
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp), "RSM_DEMO_BUILD": str(build_dir()),
           "RSM_DEMO_LOCKSTEP": "1", "RSM_DEMO_OUT": str(out), "RSM_VENV": str(project_venv()),
           "MPLBACKEND": "Agg"}
    res = subprocess.run(["bash", str(REPO_ROOT / "tools" / "demo")], capture_output=True, text=True, env=env,
                         cwd=REPO_ROOT, timeout=600)
    assert res.returncode == 0, res.stdout[-4000:] + res.stderr[-4000:]
    return res, out


def poses(path: Path) -> int:
    return sum(1 for line in path.read_text().splitlines() if line and not line.startswith("#"))


def test_the_demo_is_short_and_ends_with_the_figures_and_the_picture(demo):
    res, out = demo
    lines = (res.stdout + res.stderr).splitlines()
    assert len(lines) <= MAX_LINES, res.stdout + res.stderr
    assert "error" not in res.stderr.lower() and "warning" not in res.stderr.lower(), res.stderr
    last = res.stdout.rstrip("\n").splitlines()
    assert last[-1] == f"picture: {out / 'intel.png'}"
    rows = ROW.findall("\n".join(last[-8:]))
    assert [r[0] for r in rows] == ["rsm", "the paper's method", "odometry alone"], res.stdout
    png = out / "intel.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000


def test_the_whole_log_figures_show_what_rsm_is_for(demo):
    res, out = demo
    figures = json.loads((out / "whole.json").read_text())
    assert list(figures) == ["rsm", "the paper's method", "odometry alone"]
    for label, f in figures.items():
        assert f["poses"] == 13631, label  # one pose a scan of the whole log
        assert f["all"]["matched"] == f["all"]["in_span"] == 2984, label
        assert f["local"]["matched"] == f["local"]["in_span"] > 1000, label
    rsm, paper, odo = (figures[k] for k in ("rsm", "the paper's method", "odometry alone"))
    # The building: odometry drifts metres, rsm stays within centimetres.
    assert odo["all"]["translation_m"] > 2.0 and odo["all"]["rotation_deg"] > 10.0
    assert rsm["all"]["translation_m"] < 0.05 and rsm["all"]["rotation_deg"] < 0.5
    assert rsm["all"]["translation_m"] < odo["all"]["translation_m"] / 50
    assert rsm["all"]["translation_m"] < paper["all"]["translation_m"] / 10
    # Between consecutive scans too, rsm is the best of the three.
    for q in ("translation_m", "rotation_deg"):
        assert rsm["local"][q] < paper["local"][q] and rsm["local"][q] < odo["local"][q], q
    assert rsm["local"]["rotation_deg"] < odo["local"]["rotation_deg"] / 3
    # The printed table is these figures, to three digits.
    printed = {r[0]: [float(v) for v in r[1:]] for r in ROW.findall(res.stdout)}
    for label, f in figures.items():
        want = [f["all"]["translation_m"], f["all"]["rotation_deg"], f["local"]["translation_m"],
                f["local"]["rotation_deg"]]
        assert printed[label] == pytest.approx(want, rel=0.005), label
    for name in ("whole-rsm.txt", "whole-paper.txt", "whole-odometry.txt"):
        assert poses(out / name) == 13631, name
    assert (out / "whole-map.pgm").read_bytes().startswith(b"P5")


def test_the_live_replay_fuses_every_scan_of_the_excerpt(demo):
    res, out = demo
    assert poses(out / "live.txt") == 600, "the live run must fuse every scan of the excerpt"
    assert (out / "live-map.pgm").read_bytes().startswith(b"P5")
    m = re.search(r"live: 600 scans fused from the serial links; local error ([0-9.]+) m, ([0-9.]+) deg", res.stdout)
    assert m, res.stdout
    # Within the core's floor on the excerpt (relations up to 2 s).
    assert float(m.group(1)) <= 0.03 and float(m.group(2)) <= 0.5, m.group(0)
