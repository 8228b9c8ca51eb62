"""rsm_tools.m4 (the QEMU runner of the firmware images) on made-up console
output: the cost figures, the calibration check, the generator of the
replay's input and the map-in-flash image's lines (its global search's
costs and its agreement with the host's).  The images themselves run in the
m4.* ctest entries."""

import re

import pytest

from conftest import TEST_DATA
from rsm_tools import m4


def _output(steps, c=(1000, 400, 101000, 40400), odo=0):
    lines = ["rsm replay on mps2-an386", "C " + " ".join(str(v) for v in c)]
    for i, s in enumerate(steps):
        lines.append(f"P {i} 0 00000000 00000000 00000000")
        stages = [0] * len(m4.STAGES)
        stages[0], stages[-1] = 10, s - 10
        lines.append(f"T {i} {s} " + " ".join(str(v) for v in stages) + f" {odo}")
    lines += ["E scans 3 accepted 3 motions 3", "M stack 1900 of 16384 cycles_hz 25000000", "rsm replay: done"]
    return "\n".join(lines) + "\n"


def test_costs_are_ticks_times_instructions_per_tick():
    steps = list(range(100, 300))  # ticks per scan
    res = m4.costs(_output(steps))
    k = m4.INSNS_PER_TICK
    assert res["scans"] == 200
    assert res["mean"] == pytest.approx(k * sum(steps) / len(steps))
    assert res["p95"] == k * 289 and res["p99"] == k * 297 and res["max"] == k * 299  # nearest rank
    assert res["stages"]["points"] == 10 * k
    assert res["stages"]["mapmatch"] == pytest.approx(k * (sum(steps) / len(steps) - 10))
    assert res["stack_used"] == 1900 and res["stack_size"] == 16384


def test_costs_count_the_encoder_steps_in_each_scan():
    k = m4.INSNS_PER_TICK
    res = m4.costs(_output([100, 200, 300], odo=7))
    assert res["mean"] == pytest.approx(k * 207) and res["max"] == k * 307
    assert res["stages"]["odometry"] == 7 * k and res["stages"]["mapmatch"] == pytest.approx(k * 190)
    # A T line of an older image, without the encoder steps, is refused, not misread.
    old = "\n".join(l.rsplit(" ", 1)[0] if l.startswith("T ") else l for l in _output([100]).splitlines())
    with pytest.raises(m4.M4Error, match="encoder steps"):
        m4.costs(old)


def test_costs_are_printed_a_figure_a_line():
    text = m4.format_costs(m4.costs(_output([100, 200, 300], odo=2)))
    lines = text.splitlines()
    assert lines[0].startswith("scans 3 ") and lines[1] == f"mean {round(m4.INSNS_PER_TICK * 202)}"
    assert f"stage odometry {round(2 * m4.INSNS_PER_TICK)}" in lines and not any("stage icp" in l for l in lines)


def test_size_check_fails_over_the_ram_limit(tmp_path, monkeypatch):
    class Res:
        returncode = 0
        stdout = "   text    data     bss     dec     hex filename\n 100000    1000  150000  251000   3d478 x.elf\n"
        stderr = ""
    monkeypatch.setattr(m4.shutil, "which", lambda name: "/bin/true")
    monkeypatch.setattr(m4.subprocess, "run", lambda *a, **k: Res())
    assert m4.image_size(tmp_path / "x.elf") == {"text": 100000, "data": 1000, "bss": 150000, "flash": 101000,
                                                 "ram": 151000}
    assert "RAM 151000 bytes" in m4.check_size(tmp_path / "x.elf", 151000)
    with pytest.raises(m4.M4Error, match="over 150999"):
        m4.check_size(tmp_path / "x.elf", 150999)


def test_qemu_command_runs_the_machine_asked():
    if m4.shutil.which("qemu-system-arm") is None:
        pytest.fail("qemu-system-arm is not installed (./tools/test installs it)")
    from pathlib import Path
    cmd = m4.qemu_command(Path("x.elf"), machine=m4.MACHINE_M3)
    assert cmd[cmd.index("-M") + 1] == "mps2-an385"
    assert m4.qemu_command(Path("x.elf"))[cmd.index("-M") + 1] == "mps2-an386"


def test_calibration_fails_when_the_timer_does_not_count_instructions():
    ok = m4.calibration(_output([100]))
    assert ok["insns"] == 200000 and ok["measured"] == 200000
    # one tick off is the resolution; two ticks off is a wrong model
    m4.calibration(_output([100], c=(1000, 400, 101000, 40401)))
    with pytest.raises(m4.M4Error, match="calibration"):
        m4.calibration(_output([100], c=(1000, 400, 101000, 40402)))
    with pytest.raises(m4.M4Error):
        m4.calibration("no such line\n")


def test_qemu_command_counts_instructions_and_ends_by_semihosting(tmp_path):
    if m4.shutil.which("qemu-system-arm") is None:
        pytest.fail("qemu-system-arm is not installed (./tools/test installs it)")
    cmd = m4.qemu_command(tmp_path / "x.elf", [tmp_path / "a.bin"])
    assert "mps2-an386" in cmd and f"shift={m4.ICOUNT_SHIFT},sleep=off" in cmd
    assert "enable=on,target=native" in cmd and f"file:{tmp_path / 'a.bin'}" in cmd


def test_generated_excerpt_has_every_scan_after_its_pose(tmp_path):
    import subprocess
    import sys
    from pathlib import Path
    gen = Path(__file__).resolve().parents[2] / "port" / "baremetal" / "replay" / "gen_replay_data.py"
    out = tmp_path / "d.c"
    subprocess.run([sys.executable, str(gen), str(TEST_DATA / "intel_head.clf.gz"), str(out), "--scans", "5"],
                   check=True)
    text = out.read_text()
    assert "rsm_replay_scan_count = 5u;" in text
    steps = re.findall(r"^    \{(\d+)u, (\d+)u, (\d+)u\},$", text, re.M)
    scans = [int(s[2]) for s in steps if s[2] != "0"]
    assert scans == [1, 2, 3, 4, 5]
    rows = re.findall(r"^    \{(\d+)u, \{([0-9, ]+)\}\},$", text, re.M)
    assert len(rows) == 5 and all(len(r[1].split(",")) == 180 for r in rows)
    assert int(rows[0][0]) == 0 and int(rows[1][0]) > 0  # stamps from the first scan


def test_generated_excerpt_makes_stamps_that_go_backwards_monotonic_as_rsm_convert_does(tmp_path):
    import subprocess
    import sys
    from pathlib import Path
    from rsm_tools.carmen import FLaser, read_log
    from rsm_tools.convert import monotonic_stamps
    gen = Path(__file__).resolve().parents[2] / "port" / "baremetal" / "replay" / "gen_replay_data.py"
    out = tmp_path / "d.c"
    subprocess.run([sys.executable, str(gen), str(TEST_DATA / "intel_head.clf.gz"), str(out), "--scans", "40"],
                   check=True)
    stamps = [int(v) for v in re.findall(r"^    \{(\d+)u, \{[0-9, ]+\}\},$", out.read_text(), re.M)]
    log = [r.timestamp for r in read_log(TEST_DATA / "intel_head.clf.gz", types=("FLASER",))
           if isinstance(r, FLaser)][:40]
    raw = [round((t - log[0]) * 1e6) for t in log]
    back = [i for i in range(1, 40) if log[i] < log[i - 1]]
    assert back, "the excerpt's first 40 scans have a stamp going backwards (the case under test)"
    assert all(b >= a for a, b in zip(stamps, stamps[1:]))
    assert stamps == monotonic_stamps(raw)  # as rsm-convert re-places them
    assert all(stamps[i] != raw[i] or stamps[i - 1] != raw[i - 1] for i in back)  # each backward step moved
    # one stamp moved per step backwards (here the one that had jumped ahead), the rest the log's own
    assert sum(a != b for a, b in zip(stamps, raw)) == len(back)


def test_profile_counts_each_block_by_its_size_times_its_runs():
    log = """----------------
IN: alpha
0x00000100:  b508       push     {r3, lr}
0x00000102:  4813       ldr      r0, [pc, #0x4c]
0x00000104:  d207       bhs      #0x110

Trace 0: 0x7f0000000100 [00800408/00000100/00000110/ff020200] alpha
----------------
IN: beta
0x00000200:  3a01       subs     r2, #1
0x00000202:  d1fd       bne      #0x200

Trace 0: 0x7f0000000200 [00800408/00000200/00000110/ff020200] beta
Trace 0: 0x7f0000000200 [00800408/00000200/00000110/ff020200] beta
Trace 0: 0x7f0000000200 [00800408/00000200/00000110/ff020200] beta
Trace 0: 0x7f0000000100 [00800408/00000100/00000110/ff020200] alpha
----------------
IN: alpha
0x00000106:  4770       bx       lr

Trace 0: 0x7f0000000300 [00800408/00000106/00000110/ff020200] alpha
"""
    per = m4.profile_log(log.splitlines(keepends=True))
    assert per == {"alpha": 3 * 2 + 1, "beta": 2 * 3}
    text = m4.format_profile(per, top=1)
    assert text.splitlines()[0].endswith("alpha") and text.splitlines()[-1].strip() == "13 in all"


def _mapflash_boots(saved="S saved bytes 92 tiles 1 stamp 3 pose 3f800000 00000000 00000000"):
    first = (f"{m4.MAPFLASH_BANNER}, region at 0x00200000\nF region 106496 page 4096\n"
             "L refused -13 not a map of this format, version or build\n"
             "P 0 1 00000000 00000000 00000000\nP 1 0 3f800000 00000000 00000000\n"
             f"{saved}\nrsm mapflash: saved, resetting\n")
    second = (f"{m4.MAPFLASH_BANNER}, region at 0x00200000\nF region 106496 page 4096\n"
              f"{saved.replace('S saved', 'L loaded')}\nP 2 0 3f800000 3dcccccd 00000000\n"
              "E scans 1 accepted 1 map_bytes 92\nrsm mapflash: done\n")
    return first, second


def test_mapflash_output_splits_into_boots_and_reads_the_map_lines():
    first, second = _mapflash_boots()
    boots = m4.split_boots("qemu noise\n" + first + second, m4.MAPFLASH_BANNER)
    assert boots == [first, second]
    saved = m4.mapflash_info(first, "S saved")
    assert saved == {"bytes": 92, "tiles": 1, "stamp": 3, "pose": ("3f800000", "00000000", "00000000")}
    assert m4.mapflash_info(second, "L loaded") == saved
    with pytest.raises(m4.M4Error, match="L loaded"):
        m4.mapflash_info(first, "L loaded")
    assert m4.pose_lines(second) == [(2, 0, 1.0, pytest.approx(0.1), 0.0)]


def test_mapflash_pose_comparison_fails_beyond_its_tolerance():
    got = [(5, 0, 1.0, 2.0, 3.1)]
    ref = {5: (5, 0, 1.0, 2.05, -3.1)}  # headings either side of pi: 0.083 rad apart
    worst = m4.compare_poses("t", got, ref, (0.1, 0.1), True)
    assert worst[0] == pytest.approx(0.05) and worst[1] == pytest.approx(2 * m4.math.pi - 6.2)
    with pytest.raises(m4.M4Error, match="scan 5"):
        m4.compare_poses("t", got, ref, (0.01, 0.1), False)
    with pytest.raises(m4.M4Error, match="outcome"):
        m4.compare_poses("t", [(5, 3, 1.0, 2.0, 3.1)], ref, (0.1, 0.1), True)
    with pytest.raises(m4.M4Error, match="no reference"):
        m4.compare_poses("t", [(6, 0, 1.0, 2.0, 3.1)], ref, (0.1, 0.1), True)


def test_mapflash_run_lets_qemu_reset_and_stops_a_reset_loop(tmp_path, monkeypatch):
    """run_rebooting drops -no-reboot and kills a run that boots too often
    (a fake qemu that prints the banner forever)."""
    fake = tmp_path / "qemu-system-arm"
    fake.write_text("#!/bin/sh\nfor a in \"$@\"; do [ \"$a\" = -no-reboot ] && exit 3; done\n"
                    f"while :; do echo '{m4.MAPFLASH_BANNER}, region'; done\n")
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", f"{tmp_path}{m4.os.pathsep}{m4.os.environ.get('PATH', '')}")
    with pytest.raises(m4.M4Error, match="more than 2 boots"):
        m4.run_rebooting(tmp_path / "x.elf", m4.MAPFLASH_BANNER, 2, timeout=30)


def _search_boot(rows, proven=1, scans=None, pose="3f800000 3dcccccd 00000000", c=(1000, 400, 101000, 40400)):
    """A second mapflash boot's global search: the C line, G lines (scan,
    outcome, search_work, ticks) and the GE line."""
    lines = [f"{m4.MAPFLASH_BANNER}, region at 0x00200000", "C " + " ".join(str(v) for v in c),
             "E scans 1 accepted 1 map_bytes 92"]
    lines += [f"G {s} {o} {w} {t}" for s, o, w, t in rows]
    lines += [f"GE proven {proven} scans {len(rows) if scans is None else scans} budget 100000 pose {pose}",
              "rsm mapflash: done"]
    return "\n".join(lines) + "\n"


SEARCH = [(350, 11, 64344, 598960), (351, 11, 100012, 867254), (352, 0, 0, 348908)]


def test_mapflash_global_search_costs_are_ticks_times_instructions_per_tick():
    boot = _search_boot(SEARCH)
    m4.calibration(boot)  # the C line the costs rest on
    g = m4.global_search(boot)
    assert g["rows"] == SEARCH and g["proven"] and g["scans"] == 3
    assert g["pose"] == (1.0, pytest.approx(0.1), 0.0)
    c = m4.global_costs(g)
    k = m4.INSNS_PER_TICK
    assert c["max"] == 867254 * k and c["mean"] == pytest.approx(k * (598960 + 867254 + 348908) / 3)
    assert c["scans"] == 3 and c["scans_to_pose"] == 3 and c["last_scan"] == 352 and c["budget"] == 100000
    assert c["work"] == 64344 + 100012 and c["max_work"] == 100012
    # a search that proved nothing has no scans to a pose, but its costs
    c = m4.global_costs(m4.global_search(_search_boot(SEARCH[:2], proven=0)))
    assert c["scans_to_pose"] is None and not c["proven"] and c["max"] == 867254 * k


def test_mapflash_global_search_lines_must_be_whole():
    with pytest.raises(m4.M4Error, match="GE"):
        m4.global_search(_search_boot(SEARCH).replace("GE proven", "GX proven"))
    with pytest.raises(m4.M4Error, match="says 5 scans, 3 G lines"):
        m4.global_search(_search_boot(SEARCH, scans=5))
    with pytest.raises(m4.M4Error, match="malformed"):
        m4.global_search(_search_boot(SEARCH).replace("G 351 11 100012 867254", "G 351 11 100012"))
    with pytest.raises(m4.M4Error, match="0 G lines"):
        m4.global_search(_search_boot([], scans=0))


def test_mapflash_global_search_host_and_target_agree_but_for_the_cost():
    target = m4.global_search(_search_boot(SEARCH))
    host_rows = [(s, o, w, 0) for s, o, w, _ in SEARCH]
    m4.compare_global(target, m4.global_search(_search_boot(host_rows)), m4.MAPFLASH_HOST_TOL)
    other = list(host_rows)
    other[1] = (351, 11, 100013, 0)  # one read more
    with pytest.raises(m4.M4Error, match="search_work 100013"):
        m4.compare_global(target, m4.global_search(_search_boot(other)), m4.MAPFLASH_HOST_TOL)
    other[1] = (351, 0, 100012, 0)  # another outcome
    with pytest.raises(m4.M4Error, match="outcome 0"):
        m4.compare_global(target, m4.global_search(_search_boot(other)), m4.MAPFLASH_HOST_TOL)
    with pytest.raises(m4.M4Error, match="proven"):  # the host searched on
        m4.compare_global(target, m4.global_search(_search_boot(host_rows + [(353, 11, 5, 0)], proven=0)),
                          m4.MAPFLASH_HOST_TOL)
    with pytest.raises(m4.M4Error, match="budget 200000"):
        m4.compare_global(target, m4.global_search(_search_boot(host_rows).replace("budget 100000", "budget 200000")),
                          m4.MAPFLASH_HOST_TOL)
    with pytest.raises(m4.M4Error, match="global search, host"):  # 0.1 m away in y
        m4.compare_global(target, m4.global_search(_search_boot(host_rows, pose="3f800000 3e4ccccd 00000000")),
                          m4.MAPFLASH_HOST_TOL)
