"""The C tools' command lines (getopt_long): the options, messages and exit
statuses they had before; 2 for a bad command line, 0 for --help (usage on
stdout), 1 when a named file cannot be used."""

import subprocess

import pytest

from conftest import built_tool, subprocess_env


def run(tool: str, *args: str):
    path = {"nav": "tools/nav/rsm-nav", "dump": "tools/dump/rsm-dump", "stages": "tools/bench-c/rsm-stages"}[tool]
    return subprocess.run([str(built_tool(path)), *args], capture_output=True, text=True, timeout=120,
                          env=subprocess_env())


@pytest.mark.parametrize("tool", ["nav", "dump", "stages"])
def test_help_prints_the_usage_on_stdout_and_exits_0(tool):
    for flag in ("--help", "-h"):
        res = run(tool, flag)
        assert res.returncode == 0 and res.stdout.startswith("usage: rsm-") and not res.stderr


def test_nav_refuses_what_it_cannot_place_with_the_usage(tmp_path, head_log):
    traj = str(tmp_path / "t.txt")
    for args, named in ((["--carmen"], "--carmen"), (["--bogus"], "--bogus"),
                        (["--carmen", str(head_log), "--trajectory", traj, "extra"], "extra"),
                        (["--carmen", str(head_log), "--trajectory", traj, "--initial-pose", "1", "2"],
                         "--initial-pose"),
                        (["--carmen", str(head_log), "--trajectory", traj, "--lidar", "ld06"], "--lidar")):
        res = run("nav", *args)
        assert res.returncode == 2, args
        assert f"rsm-nav: unexpected argument '{named}'" in res.stderr and "usage: rsm-nav" in res.stderr


def test_nav_values_keep_their_messages(tmp_path, head_log):
    base = ["--carmen", str(head_log), "--trajectory", str(tmp_path / "t.txt")]
    for extra, msg in ((["--method", "nope"], "rsm-nav: unknown method 'nope'"),
                       (["--lidar", "foo", "x"], "rsm-nav: --lidar takes ld06 or rplidar, not 'foo'"),
                       (["--lidar-keep", "0"], "rsm-nav: --lidar-keep takes 1 to 64, not '0'"),
                       (["--robot-baud", "-5"], "rsm-nav: bad baud rate '-5'"),
                       (["--seconds", "0"], "rsm-nav: bad duration '0'"),
                       (["--wheel-base", "abc"], "rsm-nav: bad value 'abc' for --wheel-base"),
                       (["--laser-pose", "1", "2"], "rsm-nav: --laser-pose needs three numbers: x y theta"),
                       (["--laser-pose", "1", "-2", "x"], "rsm-nav: bad --laser-pose (three numbers: x y theta)"),
                       (["--set", "nope=1"], "rsm-nav: unknown key in --set 'nope=1'")):
        res = run("nav", *base, *extra)
        assert res.returncode == 2 and msg in res.stderr, (extra, res.stderr)
    res = run("nav", *base, "--tum", str(tmp_path / "no" / "x.tum"))
    assert res.returncode == 1 and "rsm-nav: cannot write" in res.stderr


def test_nav_takes_negative_numbers_as_values(tmp_path, head_log):
    """Values of the options with three numbers may start with '-'."""
    res = run("nav", "--carmen", str(head_log), "--trajectory", str(tmp_path / "t.txt"), "--quiet",
              "--method", "odometry", "--laser-pose", "0.1", "-0.05", "-0.2", "--initial-pose", "-1", "2", "-0.5")
    assert res.returncode == 0, res.stderr
    first = (tmp_path / "t.txt").read_text().splitlines()
    pose = next(line for line in first if not line.startswith("#")).split()
    assert abs(float(pose[1]) + 1.0) < 1e-6 and abs(float(pose[3]) + 0.5) < 1e-6


def test_dump_options_and_its_input_in_any_order(tmp_path):
    empty = tmp_path / "empty.bin"
    empty.write_bytes(b"")
    assert run("dump", str(empty), "--protocol", "aria").returncode == 0
    assert run("dump", "--protocol", "aria", str(empty)).returncode == 0
    for args, msg in ((["--protocol"], "rsm-dump: unknown or incomplete option '--protocol'"),
                      (["--protocol", "lms", "--zz", "a"], "rsm-dump: unknown or incomplete option '--zz'"),
                      (["--protocol", "lms", "a", "b"], "rsm-dump: more than one input given ('b')"),
                      (["--protocol", "lms", "--baud", "0", "a"], "rsm-dump: --baud needs a positive integer"),
                      (["--protocol", "xx", "a"], "rsm-dump: unknown protocol 'xx'"),
                      (["--pretty", "a"], "rsm-dump: --protocol aria|lms|ld06|rplidar is required"),
                      (["--protocol", "lms"], "rsm-dump: no input given")):
        res = run("dump", *args)
        assert res.returncode == 2 and msg in res.stderr, (args, res.stderr)


def test_stages_bad_arguments_get_the_usage(head_log):
    for args in (["--carmen"], ["--bogus"], ["--carmen", str(head_log), "--method", "x"],
                 ["--carmen", str(head_log), "--clock", "x"], ["--carmen", str(head_log), "extra"], []):
        res = run("stages", *args)
        assert res.returncode == 2 and res.stderr.startswith("usage: rsm-stages"), (args, res.stderr)
