"""rsm-convert: CARMEN log -> capture; decoded bytes reproduce the log."""

import math
import subprocess
import sys

import pytest

from conftest import read_maybe_gz, subprocess_env
from rsm_tools import capture as cap
from rsm_tools import convert as cv
from rsm_tools import protocols as p
from rsm_tools.carmen import FLaser, read_log, time_key


def log_records(path):
    return list(read_log(path, types=("ODOM", "FLASER")))


def odometry_from_capture(header, records):
    """Integrate the ENCODER packets; the pose of log step i is the pose after its last packet."""
    tpm = float(header.metadata["robot.ticks_per_m"])
    base = float(header.metadata["robot.wheel_base_m"])
    pose = tuple(float(v) for v in header.metadata["robot.initial_pose"].split())
    start = int(header.metadata["robot.start_ticks"])
    per_step = {}
    for item in header.metadata["convert.split_steps"].split():
        i, n = item.split(":")
        per_step[int(i)] = int(n)
    enc = [p.decode_encoder(r.data) for r in records if r.channel == 0]
    prev = (p._s32(start), p._s32(start))
    out = []
    k = 0
    step = 0
    while k < len(enc):
        for _ in range(per_step.get(step, 1)):
            left, right = enc[k]
            pose = cv.integrate(pose, p.tick_delta(left, prev[0]), p.tick_delta(right, prev[1]), tpm, base)
            prev = (left, right)
            k += 1
        out.append(pose)
        step += 1
    return out


@pytest.mark.parametrize("start_ticks", [0, 2**31 - 20000])
def test_encoder_packets_reproduce_log_odometry(tmp_path, head_log, start_ticks):
    out = tmp_path / "h.cap"
    st = cv.convert(head_log, out, start_ticks=start_ticks)
    recs = log_records(head_log)
    h, got, rst = cap.read_capture(out)
    assert rst.corrupt == rst.truncated == 0
    assert st.odom == 1177 and st.scans == 600
    poses = odometry_from_capture(h, got)
    want = [r.odom_pose if isinstance(r, FLaser) else r.pose for r in recs]
    assert len(poses) == len(want) == 1777
    dmax = max(math.hypot(a[0] - b[0], a[1] - b[1]) for a, b in zip(poses, want))
    amax = max(abs(cv.wrap(a[2] - b[2])) for a, b in zip(poses, want))
    # The heading within one tick of difference between the wheels (1 / (tpm
    # B)); the position within one tick of wheel travel, except short steps
    # whose miss, under 0.5 mm, would take a turn of over 0.05 rad to mend.
    tpm, base = float(h.metadata["robot.ticks_per_m"]), float(h.metadata["robot.wheel_base_m"])
    miss = sorted(math.hypot(a[0] - b[0], a[1] - b[1]) for a, b in zip(poses, want))
    assert dmax <= 0.0005, dmax
    assert miss[len(miss) * 3 // 4] <= 1.0 / tpm, miss[len(miss) * 3 // 4]
    assert amax <= 1.0 / (tpm * base) + 1e-9, amax
    if start_ticks:  # the counters really wrapped
        enc = [p.decode_encoder(r.data) for r in got if r.channel == 0]
        assert any(l < 0 for l, _ in enc) or any(r < 0 for _, r in enc)


def test_timestamps_monotonic_spread_and_recoverable(tmp_path, head_log):
    out = tmp_path / "h.cap"
    st = cv.convert(head_log, out)
    recs = log_records(head_log)
    h, got, _ = cap.read_capture(out)  # strict reader: would raise on disorder
    ts = [r.timestamp for r in got]
    assert ts == sorted(ts)
    # records of different log lines are at least the default gap apart
    distinct = sorted(set(ts))
    assert min(b - a for a, b in zip(distinct, distinct[1:])) >= cv.DEFAULT_MIN_GAP_US
    assert st.clamped == int(h.metadata["convert.clamped_total"]) > 0
    table = {}
    for line in h.metadata["convert.clamped"].splitlines():
        kind, idx, orig, written = line.split()
        table[(kind, int(idx))] = (int(orig), int(written))
    # laser telegram k carries scan k's stamp, or its new stamp recorded in the table
    scans = [r for r in recs if r.kind == "FLASER"]
    laser = [r for r in got if r.channel == 1]
    assert len(laser) == len(scans) == 600
    for k, (s, rec) in enumerate(zip(scans, laser)):
        orig, written = table.get(("FLASER", k), (time_key(s.timestamp), rec.timestamp))
        assert orig == time_key(s.timestamp) and written == rec.timestamp


def beam_of(j: int, readings: int):
    """The CARMEN beam (1 degree apart) at reading j of an LMS scan, or None."""
    if readings == 180:
        return j
    i, rem = divmod(j * 180, readings - 1)
    return i if rem == 0 and i < 180 else None


@pytest.mark.parametrize("units,readings,max_range", [("mm", 180, 8.0), ("mm", 181, 8.0), ("cm", 361, 50.0),
                                                      ("cm", 181, 50.0), ("auto", 181, None)])
def test_b0_ranges_equal_log_ranges(tmp_path, head_log, units, readings, max_range):
    out = tmp_path / "h.cap"
    st = cv.convert(head_log, out, units=units, readings=readings, max_range=max_range)
    want_units = "cm" if units == "auto" else units
    assert st.units == want_units
    limit = min(max_range or math.inf, 81.82 if want_units == "cm" else 8.182)
    scans = [r for r in log_records(head_log) if r.kind == "FLASER"]
    _, got, _ = cap.read_capture(out)
    laser = [r for r in got if r.channel == 1]
    res = 0.001 if want_units == "mm" else 0.01
    n_valid = n_far = n_none = 0
    for s, rec in zip(scans, laser):
        b0 = p.decode_b0(rec.data)
        assert b0.count == readings and b0.units == want_units and b0.status == 0x10
        got_r = b0.ranges()
        for j, g in enumerate(got_r):
            i = beam_of(j, readings)
            if i is None:  # no beam at this bearing
                assert g is None and b0.raw[j] == p.LMS_NO_VALUE
                n_none += 1
                continue
            r = s.ranges[i]
            if r > limit:
                assert g is None and b0.raw[j] == p.LMS_TOO_FAR
                n_far += 1
            else:
                assert abs(g - r) <= res / 2 + 1e-9, (j, g, r)
                n_valid += 1
    assert n_valid > 10000 and n_far > 100
    assert n_none == {180: 0, 181: 1, 361: 181}[readings] * len(scans)
    assert st.too_far == n_far


def test_units_cover_the_longest_reading_or_the_clamp_is_loud(tmp_path, head_log):
    """The excerpt reaches 81.83 m (the Intel log's no-return value): cm is
    chosen, and the readings past 81.82 m are counted and printed. A log
    whose readings all fit in 8.182 m gets mm, with nothing clamped."""
    scans = [r for r in log_records(head_log) if r.kind == "FLASER"]
    longest = max(x for s in scans for x in s.ranges)
    beyond = sum(1 for s in scans for x in s.ranges if x > 81.82)
    assert longest > 81.82 and beyond > 0
    out = tmp_path / "h.cap"
    res = subprocess.run([sys.executable, "-m", "rsm_tools.convert", str(head_log), str(out)],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 0, res.stderr
    assert f"in cm (longest reading {longest:.3f} m)" in res.stderr
    assert f"WARNING: {beyond} readings longer than 81.820 m" in res.stderr
    h, _, _ = cap.read_capture(out)
    assert h.metadata["laser.units"] == "cm" and h.metadata["convert.too_far"] == str(beyond)

    # The same log with every reading cut to 8 m: mm, and no warning.
    short = tmp_path / "short.clf"
    lines = []
    for line in read_maybe_gz(head_log).decode().splitlines():
        f = line.split()
        if f and f[0] == "FLASER":
            n = int(f[1])
            f[2:2 + n] = [f"{min(float(x), 8.0):.2f}" for x in f[2:2 + n]]
        lines.append(" ".join(f))
    short.write_text("\n".join(lines) + "\n")
    res = subprocess.run([sys.executable, "-m", "rsm_tools.convert", str(short), str(out)],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 0, res.stderr
    assert "in mm (longest reading 8.000 m)" in res.stderr and "WARNING" not in res.stderr
    assert cap.read_capture(out)[0].metadata["convert.too_far"] == "0"


def test_command_line(tmp_path, head_log):
    out = tmp_path / "c.cap"
    res = subprocess.run([sys.executable, "-m", "rsm_tools.convert", str(head_log), str(out),
                          "--units", "cm", "--readings", "361", "--ticks-per-m", "100000",
                          "--wheel-base", "0.4", "--max-range", "30"],
                         capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 0, res.stderr
    assert "600 0xB0 telegrams" in res.stderr and "timestamps re-placed" in res.stderr
    h, got, _ = cap.read_capture(out)
    assert h.metadata["laser.units"] == "cm" and h.metadata["robot.ticks_per_m"] == "100000.0"
    assert h.metadata["source"] == "intel_head.clf.gz"
    assert [c.protocol for c in h.channels] == ["aria", "lms2xx"]
    res = subprocess.run([sys.executable, "-m", "rsm_tools.convert", str(tmp_path / "missing.clf"),
                          str(out)], capture_output=True, text=True, env=subprocess_env())
    assert res.returncode == 1 and "missing.clf" in res.stderr


def test_monotonic_stamps_keep_the_longest_run_and_re_place_the_glitches():
    # one stamp jumped ahead (at 2), one fell behind (at 6): only they move
    got = cv.monotonic_stamps([100, 200, 900, 300, 400, 500, 50, 700])
    assert got == [100, 200, 250, 300, 400, 500, 600, 700]
    assert cv.monotonic_stamps([]) == []
    assert cv.monotonic_stamps([5, 5, 5]) == [5, 5, 5]
    # glitches at the ends take the nearest kept stamp
    assert cv.monotonic_stamps([900, 100, 200, 300, 10]) == [100, 100, 200, 300, 300]


def test_spread_stamps_keeps_a_least_gap_and_catches_up():
    assert cv.spread_stamps([0, 1, 2, 100, 200], 10) == [0, 10, 20, 100, 200]
    assert cv.spread_stamps([0, 0, 0, 25], 10) == [0, 10, 20, 30]
    assert cv.spread_stamps([3, 4, 5], 0) == [3, 4, 5]


def test_readings_auto_keeps_the_logs_beams(tmp_path, head_log):
    """--readings auto (the default) keeps what the log has (issue 30: a
    361-beam log lost every other beam to the old default of 181): 181
    readings for the excerpt's 180 beams, 361 for the same scans given as
    361 beams at half a degree (each beam twice), every beam at its reading."""
    from conftest import read_maybe_gz

    st = cv.convert(head_log, tmp_path / "a.cap")
    h, _, _ = cap.read_capture(tmp_path / "a.cap")
    assert h.metadata["laser.readings"] == "181"
    lines = []
    for line in read_maybe_gz(head_log).decode().splitlines():
        f = line.split()
        if f and f[0] == "FLASER":
            n = int(f[1])
            r = f[2:2 + n]
            half = [v for k in range(n) for v in (r[k], r[k])] + [r[-1]]
            line = " ".join(["FLASER", str(len(half)), *half, *f[2 + n:]])
        lines.append(line)
    wide = tmp_path / "wide.clf"
    wide.write_text("\n".join(lines) + "\n")
    cv.convert(wide, tmp_path / "w.cap")
    h, recs, _ = cap.read_capture(tmp_path / "w.cap")
    assert h.metadata["laser.readings"] == "361"
    assert st.scans > 0
