"""The bench's line on rsm-nav's own memory over a long run
(rsm_tools.bench.navmemory): the scans fed over and over with their stamps
moving on, rsm-nav reading them from a named pipe, the floor's arithmetic.
On the shipped excerpt, a few thousand scans: no full log."""

import io

from conftest import rsm_nav_binary
from rsm_tools.bench import navmemory as nm


def test_passes_of_the_log_move_their_stamps_on(head_log):
    lines = nm.scan_lines(head_log)
    assert len(lines) == 600
    out = io.BytesIO()
    assert nm.write_scans(lines, 1500, out) == 1500
    got = out.getvalue().splitlines()
    assert len(got) == 1500
    stamps = [float(l.split()[-3]) for l in got]
    logger = [float(l.split()[-1]) for l in got]
    span = float(lines[-1].split()[-3]) - float(lines[0].split()[-3]) + 1.0
    # the second pass is the first moved on by the log's span and a second, field for field
    assert abs(stamps[600] - (stamps[0] + span)) < 1e-5 and abs(logger[1200] - (logger[0] + 2 * span)) < 1e-5
    assert got[0] == lines[0].rstrip(b"\n")
    assert got[600].split()[:-3] == lines[0].split()[:-3]  # readings and poses as they were
    # each pass starts after the last one's end
    assert stamps[600] > max(stamps[:600]) and stamps[1200] > max(stamps[600:1200])
    # written in two parts (the checkpoint between), the same lines
    parts = io.BytesIO()
    assert nm.write_scans(lines, 700, parts) == 700
    assert nm.write_scans(lines, 1500, parts, 700) == 800
    assert parts.getvalue() == out.getvalue()


def test_rsm_nav_reads_every_scan_from_the_pipe_and_says_its_peak(head_log, tmp_path):
    r = nm.run(rsm_nav_binary(), head_log, tmp_path, (300, 1500))["run"]
    assert r["scans"] == 1500 and r["poses"] == 1500  # every scan read, once
    assert r["checkpoint_scans"] == 300
    # the peak read from /proc on the way, then the summary's at the end: a peak never falls
    assert 0 < r["checkpoint_kib"] <= r["peak_kib"]
    assert not list((tmp_path / "nav-memory").glob("*.fifo"))  # the pipe is gone


def test_the_floor_judges_the_end_against_the_first_scans():
    def mem(a, b):
        return {"run": {"scans": 400000, "poses": 400000, "peak_kib": b, "checkpoint_scans": 10000,
                        "checkpoint_kib": a}}

    ok = nm.floors(mem(3000, 3150))[0]
    assert ok["status"] == "PASS" and "x1.050 of the same process's after 10 000 scans, 3 000 KiB <= x1.05" in ok["line"]
    bad = nm.floors(mem(3000, 8900))[0]  # what an array growing by 15 bytes a scan did
    assert bad["status"] == "MISS" and "400 000 scans 8 900 KiB = x2.967" in bad["line"]
    assert nm.floors(None)[0]["status"] == "SKIP" and nm.floors({"skipped": "x"})[0]["status"] == "SKIP"
    assert nm.floors({"run": {"scans": 5, "poses": 5, "peak_kib": 1}})[0]["status"] == "SKIP"
    assert "not measured" in nm.report(None)[0] and "3 150 KiB" in nm.report(mem(3000, 3150))[0]
