"""The README's commands and its program work as printed (issue 32).

The README once told newcomers to type commands that were not on the PATH
after set-up. Here its shell block that starts with `source tools/env.sh`
runs as printed, in bash, from a folder laid out as a clone (the repository's
tools/ and data/, the venv running these tests as .venv) with nothing on the
PATH but the system's; its C program is compiled and linked against the
built library; and tools/env.sh is checked on its own: which build it takes,
and that sourcing it twice adds nothing twice.
"""

import os
import re
import stat
import subprocess
from pathlib import Path

import pytest

from conftest import REPO_ROOT, build_dir, project_venv

README = REPO_ROOT / "README.md"
ENV_SH = REPO_ROOT / "tools" / "env.sh"


def blocks(lang: str):
    return re.findall(rf"^```{lang}\n(.*?)^```$", README.read_text(encoding="utf-8"), re.M | re.S)



def test_the_readme_commands_run_as_printed(tmp_path):
    block = [b for b in blocks("sh") if b.startswith("source tools/env.sh\n")]
    assert len(block) == 1, "the README has one block of commands that starts with `source tools/env.sh`"
    clone = tmp_path / "rsm"
    clone.mkdir()
    for name in ("tools", "data"):
        (clone / name).symlink_to(REPO_ROOT / name)
    (clone / ".venv").symlink_to(project_venv())
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "RSM_BUILD_DIR": str(build_dir()),
           "MPLBACKEND": "Agg"}
    res = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", block[0]], cwd=clone, env=env,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    assert "no rsm-nav" not in res.stderr and "no .venv" not in res.stderr, res.stderr
    poses = [l for l in (clone / "out" / "intel.txt").read_text().splitlines() if l and not l.startswith("#")]
    assert len(poses) == 13631
    m = re.search(r"^translation \[m\]: mean ([0-9.]+) .*\(n=2984\)$", res.stdout, re.M)
    assert m and float(m.group(1)) < 0.05, res.stdout
    assert (clone / "out" / "intel.png").read_bytes()[:4] == b"\x89PNG"


def test_the_smallest_program_compiles_and_links(tmp_path):
    code = [b for b in blocks("c") if "int main(void)" in b]
    assert len(code) == 1, "the README has one C program"
    src = tmp_path / "smallest.c"
    # The two functions the README leaves to the reader: no odometry, no scans.
    src.write_text(code[0] + "\nint next_step(rsm_motion_t *s) { (void)s; return 0; }\n"
                   "int next_scan(rsm_scan_t *s) { (void)s; return 0; }\n")
    lib = build_dir() / "librsm.a"
    assert lib.is_file(), f"{lib} not built"
    exe = tmp_path / "smallest"
    res = subprocess.run(["cc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-I", str(REPO_ROOT / "include"),
                          str(src), str(lib), "-lm", "-o", str(exe)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0 and run.stdout == "", (run.returncode, run.stdout)


def fake_tree(root: Path, builds) -> Path:
    (root / "tools").mkdir(parents=True)
    (root / "tools" / "env.sh").write_text(ENV_SH.read_text())
    (root / ".venv" / "bin").mkdir(parents=True)
    for b in builds:
        nav = root / b / "tools" / "nav" / "rsm-nav"
        nav.parent.mkdir(parents=True)
        nav.write_text(f"#!/bin/sh\necho {b}\n")
        nav.chmod(nav.stat().st_mode | stat.S_IXUSR)
    return root


def sourced(root: Path, script: str, extra_env=None) -> subprocess.CompletedProcess:
    env = {"PATH": "/usr/bin:/bin", "HOME": str(root)}
    env.update(extra_env or {})
    return subprocess.run(["bash", "-c", script], cwd=root, env=env, capture_output=True, text=True, timeout=60)


@pytest.mark.parametrize("builds,want", [(("build-demo",), "build-demo"), (("build", "build-demo"), "build")])
def test_env_sh_takes_the_test_build_before_the_demo_build(tmp_path, builds, want):
    root = fake_tree(tmp_path / "clone", builds)
    res = sourced(root, "source tools/env.sh && rsm-nav && source tools/env.sh && echo \"$PATH\"")
    assert res.returncode == 0, res.stderr
    name, path = res.stdout.splitlines()
    assert name == want
    parts = path.split(":")
    assert parts[0] == str(root / ".venv" / "bin") and parts[1] == str(root / want / "tools" / "nav")
    assert len(parts) == len(set(parts)), "sourcing twice added a folder twice"
    assert res.stderr == ""


def test_env_sh_takes_the_build_it_is_given_and_says_when_there_is_none(tmp_path):
    root = fake_tree(tmp_path / "clone", ("build", "other"))
    res = sourced(root, "source tools/env.sh other && rsm-nav")
    assert res.stdout.strip() == "other", res.stderr
    res = sourced(root, "source tools/env.sh && rsm-nav", {"RSM_BUILD_DIR": str(root / "other")})
    assert res.stdout.strip() == "other", res.stderr
    empty = fake_tree(tmp_path / "empty", ())
    res = sourced(empty, "source tools/env.sh; command -v rsm-nav || echo none")
    assert res.stdout.strip() == "none" and "no rsm-nav built yet" in res.stderr
    # Sourced from another folder it still finds its own tree.
    res = sourced(root, f"cd {os.sep} && source {root}/tools/env.sh && rsm-nav")
    assert res.stdout.strip() == "build", res.stderr
