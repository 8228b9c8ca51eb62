"""rsm-restamp: a replayed run's poses get the log's own scan stamps."""

import subprocess
import sys

from conftest import subprocess_env
from rsm_tools import capture as cap
from rsm_tools import convert
from rsm_tools.carmen import read_log, time_key


def test_poses_get_the_original_scan_stamps_and_counts_must_agree(tmp_path, head_log):
    c = tmp_path / "h.cap"
    convert.convert(str(head_log), str(c))
    scans = [r for r in read_log(head_log, types=("FLASER",))]
    h, records, _ = cap.read_capture(c)
    assert int(h.metadata["convert.clamped_total"]) > 0  # some stamps were moved and come back
    traj = tmp_path / "live.txt"
    traj.write_text("# live\n" + "".join(f"{0.01 * k:.6f} {k} {-k} 0.5\n" for k in range(len(scans))))
    out = tmp_path / "out.txt"
    res = subprocess.run([sys.executable, "-m", "rsm_tools.restamp", str(traj), "--capture", str(c), "-o", str(out)],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 0, res.stderr
    rows = [l.split() for l in out.read_text().splitlines() if not l.startswith("#")]
    assert len(rows) == len(scans) == 600
    for k, (row, s) in enumerate(zip(rows, scans)):
        assert round(float(row[0]) * 1e6) == time_key(s.timestamp)
        assert row[1:] == [str(k), str(-k), "0.5"]
    # one pose short: refused, nothing written
    traj.write_text("".join(f"{k} 0 0 0\n" for k in range(599)))
    out2 = tmp_path / "out2.txt"
    res = subprocess.run([sys.executable, "-m", "rsm_tools.restamp", str(traj), "--capture", str(c), "-o", str(out2)],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 1 and "599 poses but" in res.stderr and not out2.exists()
    res = subprocess.run([sys.executable, "-m", "rsm_tools.restamp", str(traj), "--capture",
                          str(tmp_path / "missing.cap"), "-o", str(out2)],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 1 and "rsm-restamp:" in res.stderr
