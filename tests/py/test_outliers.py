import gzip
import io
import subprocess
import sys
from fractions import Fraction

import pytest

from conftest import read_maybe_gz, subprocess_env
from rsm_tools.carmen import LogStats, parse_line, read_log
from rsm_tools.outliers import (
    DEFAULT_MAX_RANGE,
    inject_file,
    inject_line,
    inject_lines,
    main,
    outlier_count,
    scan_rng,
)


def _flaser(n, ts, r0=1.0):
    ranges = " ".join(f"{r0 + 0.01 * i:.2f}" for i in range(n))
    return (f"FLASER {n} {ranges} 0.100000 0.200000 0.300000 0.100000 0.200000 0.300000 "
            f"{ts:.6f} host {ts - 100:.6f}\n").encode()


def _rl1(n, ts):
    ranges = " ".join(f"{20 + 0.5 * i:.3f}" for i in range(n))
    rem = " ".join(f"{i}.0" for i in range(n))
    return (f"ROBOTLASER1 0 -1.5708 3.1416 0.0175 30.0 0.01 0 {n} {ranges} {n} {rem}  "
            f"1 2 0.1 1 2 0.1 0.3 0.01 0.5 0.2 0.0 {ts:.6f} host 0.0\r\n").encode()


def _synthetic_log():
    lines = [b"# header comment\n", b"PARAM robot_name x 0.0 h 0.0\n"]
    for i in range(30):
        lines.append(f"ODOM {i}.0 0 0 0 0 0 {100 + i * 0.1:.6f} host 0.0\n".encode())
        lines.append(_flaser(180 if i % 3 else 7, 100 + i * 0.1 + 0.05))
    lines.append(_rl1(40, 200.0))
    lines.append(b"FLASER 3 1.00 2.00\n")  # malformed: copied unchanged
    lines.append(b"\n")
    lines.append(b"ODOM 1 2 3 4 5 6 300.0 host 0.0")  # no final line end
    return lines


@pytest.mark.parametrize("percent,n,k", [
    (10, 180, 18), ("2.5", 180, 5), (2.5, 180, 5), ("0.25", 180, 0), (50, 3, 2),
    (100, 180, 180), (0, 180, 0), (Fraction(1, 3), 300, 1), (33, 7, 2), (10, 0, 0),
])
def test_outlier_count_rounds_half_up(percent, n, k):
    assert outlier_count(percent, n) == k


def test_outlier_count_rejects_bad_percent():
    for p in (-1, 101, "200"):
        with pytest.raises(ValueError):
            outlier_count(p, 10)


def test_scan_rng_is_derived_from_seed_and_index():
    a = [scan_rng(5, i).random() for i in range(3)]
    assert a == [scan_rng(5, i).random() for i in range(3)]
    assert len(set(a)) == 3
    assert scan_rng(6, 0).random() != a[0]


def test_injection_replaces_exactly_the_requested_count():
    lines = _synthetic_log()
    out = io.BytesIO()
    st = inject_lines(lines, out, percent=10, seed=42, min_range=0.5, max_range=6.0,
                      keep_indices=True)
    new_lines = out.getvalue().splitlines(keepends=True)
    assert len(new_lines) == len(lines)
    assert st.scans == 31 and st.skipped_malformed == 1
    scan_no = 0
    for old, new in zip(lines, new_lines):
        if not (old.startswith(b"FLASER") or old.startswith(b"ROBOTLASER1")) or old.startswith(
                b"FLASER 3 1.00 2.00"):
            assert new == old  # byte for byte
            continue
        a, b = parse_line(old.decode()), parse_line(new.decode())
        n = len(a.ranges)
        chosen = st.replaced_indices[scan_no]
        assert len(chosen) == len(set(chosen)) == outlier_count(10, n)
        assert chosen == sorted(chosen) and all(0 <= i < n for i in chosen)
        for i in range(n):
            if i in chosen:
                assert 0.5 <= b.ranges[i] <= 6.0
            else:
                assert b.ranges[i] == a.ranges[i]
        # nothing but the chosen range fields changed, line end included
        assert old.split()[: 2] == new.split()[: 2]
        first = 2 if a.kind == "FLASER" else 9
        old_t, new_t = old.split(), new.split()
        changed = [j - first for j in range(len(old_t)) if old_t[j] != new_t[j]]
        assert set(changed) <= set(chosen)
        assert old[-2:] == new[-2:]
        if a.kind == "ROBOTLASER1":
            assert b.remissions == a.remissions and b"  1 2 0.1" in new
            assert new.endswith(b"\r\n")
        scan_no += 1
    assert scan_no == 31
    assert st.replaced == sum(len(c) for c in st.replaced_indices) == 20 * 18 + 10 * 1 + 4
    assert st.readings == 20 * 180 + 10 * 7 + 40


def test_replacement_keeps_field_precision():
    line = _flaser(180, 123.0)
    new, chosen, n = inject_line(line, 0, 50, 1)
    assert n == 180 and len(chosen) == 90
    toks = new.split()
    for i in chosen:
        whole, frac = toks[2 + i].split(b".")
        assert len(frac) == 2
    rl = _rl1(40, 1.0)
    new, chosen, _ = inject_line(rl, 0, 50, 1, max_range=DEFAULT_MAX_RANGE)
    toks = new.split()
    assert all(len(toks[9 + i].split(b".")[1]) == 3 for i in chosen)


def test_same_seed_same_bytes_other_seed_differs(tmp_path):
    src = tmp_path / "in.log"
    src.write_bytes(b"".join(_synthetic_log()))
    outs = []
    for seed, name in ((7, "a.log"), (7, "b.log"), (8, "c.log"), (7, "d.clf.gz"),
                       (7, "e.clf.gz")):
        inject_file(src, tmp_path / name, 20, seed)
        outs.append((tmp_path / name).read_bytes())
    assert outs[0] == outs[1]
    assert outs[0] != outs[2]
    assert outs[3] == outs[4] and outs[3][:2] == b"\x1f\x8b"
    assert outs[3][4:8] == b"\0\0\0\0"  # gzip mtime 0
    assert gzip.decompress(outs[3]) == outs[0]
    # zero percent copies the file unchanged
    inject_file(src, tmp_path / "zero.log", 0, 7)
    assert (tmp_path / "zero.log").read_bytes() == src.read_bytes()


def test_independent_of_hash_randomisation(tmp_path):
    src = tmp_path / "in.log"
    src.write_bytes(b"".join(_synthetic_log()))
    results = []
    for hashseed in ("1", "2"):
        env = subprocess_env()
        env["PYTHONHASHSEED"] = hashseed
        dst = tmp_path / f"out{hashseed}.log"
        proc = subprocess.run(
            [sys.executable, "-m", "rsm_tools.outliers", str(src), str(dst),
             "--percent", "12.5", "--seed", "99", "--max-range", "5"],
            capture_output=True, text=True, env=env,
        )
        assert proc.returncode == 0, proc.stderr
        assert "31 scans" in proc.stdout and "1 malformed" in proc.stdout
        results.append(dst.read_bytes())
    assert results[0] == results[1]
    # and the in-process API agrees with the command line
    out = io.BytesIO()
    inject_lines(_synthetic_log(), out, "12.5", 99, max_range=5.0)
    assert out.getvalue() == results[0]


def test_cli_rejects_bad_arguments(tmp_path, capsys):
    src = tmp_path / "in.log"
    src.write_bytes(b"".join(_synthetic_log()))
    with pytest.raises(SystemExit):
        main([str(src), str(tmp_path / "o"), "--percent", "150", "--seed", "1"])
    assert main([str(src), str(tmp_path / "o"), "--percent", "5", "--seed", "1",
                 "--min-range", "9", "--max-range", "2"]) == 2
    assert "bad range interval" in capsys.readouterr().err


def test_real_excerpt_injection(head_log, tmp_path):
    a, b = tmp_path / "a.clf.gz", tmp_path / "b.clf.gz"
    st = inject_file(head_log, a, 10, 2009)
    inject_file(head_log, b, 10, 2009)
    assert a.read_bytes() == b.read_bytes()
    assert st.scans == 600 and st.replaced == 600 * 18 and st.readings == 600 * 180

    orig = list(read_log(head_log))
    stats = LogStats()
    noisy = list(read_log(a, stats=stats))
    assert stats.malformed_total == 0 and len(noisy) == len(orig)
    changed_total = 0
    for r0, r1 in zip(orig, noisy):
        if r0.kind != "FLASER":
            assert r1 == r0
            continue
        assert (r1.odom_pose, r1.laser_pose, r1.timestamp) == (r0.odom_pose, r0.laser_pose,
                                                               r0.timestamp)
        diff = [i for i in range(180) if r0.ranges[i] != r1.ranges[i]]
        # a replacement may by chance equal the original reading
        assert len(diff) <= 18
        assert all(0.2 <= r1.ranges[i] <= DEFAULT_MAX_RANGE for i in diff)
        changed_total += len(diff)
    assert changed_total >= 600 * 18 * 0.99
    # non-scan lines identical byte for byte
    plain_in = read_maybe_gz(head_log).splitlines()
    plain_out = read_maybe_gz(a).splitlines()
    assert [l for l in plain_in if not l.startswith(b"FLASER")] == [
        l for l in plain_out if not l.startswith(b"FLASER")]
