"""Shared test set-up: import path, data locations and small helpers.

The tests run from a plain checkout (``python -m pytest tests/py``) without
installing the package: the ``tools`` folder is put on ``sys.path``.

Every test uses only the repository: the shipped excerpt of the Intel log
and the protocol vectors in ``tests/data/``.  The full logs are read by
``./tools/bench`` alone (see docs/reference/README.md).
"""

import gzip
import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
TOOLS_DIR = REPO_ROOT / "tools"
TEST_DATA = REPO_ROOT / "tests" / "data"
VECTORS = TEST_DATA / "vectors.json"

if str(TOOLS_DIR) not in sys.path:
    sys.path.insert(0, str(TOOLS_DIR))


def _require(path: Path, what: str) -> Path:
    if not path.is_file():
        pytest.fail(f"{what} not found: {path} (it is part of the repository)", pytrace=False)
    return path


def load_vectors() -> list:
    """The protocol vectors of docs/reference/protocols.md section 3."""
    return json.loads(_require(VECTORS, "protocol vectors").read_text())


@pytest.fixture(scope="session")
def head_log() -> Path:
    return _require(TEST_DATA / "intel_head.clf.gz", "shipped excerpt")


@pytest.fixture(scope="session")
def excerpt_capture(tmp_path_factory, head_log) -> Path:
    """The shipped excerpt as a capture (rsm-convert's default rendering)."""
    from rsm_tools import convert

    out = tmp_path_factory.mktemp("cap") / "head.cap"
    convert.convert(str(head_log), str(out))
    return out


@pytest.fixture(scope="session")
def head_relations() -> Path:
    return _require(TEST_DATA / "intel_head.relations", "shipped excerpt relations")


@pytest.fixture(scope="session")
def head_poses() -> Path:
    return _require(TEST_DATA / "intel_head-corrected-poses.txt", "shipped excerpt poses")


def subprocess_env() -> dict:
    """Environment for running ``python -m rsm_tools.*`` from the checkout."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(TOOLS_DIR) + (os.pathsep + env["PYTHONPATH"]
                                          if env.get("PYTHONPATH") else "")
    return env


def read_maybe_gz(path: Path) -> bytes:
    data = path.read_bytes()
    return gzip.decompress(data) if data[:2] == b"\x1f\x8b" else data


def build_dir() -> Path:
    """ctest's build directory (RSM_BUILD_DIR)."""
    build = os.environ.get("RSM_BUILD_DIR")
    if not build:
        pytest.fail("RSM_BUILD_DIR is not set: run these tests through ctest", pytrace=False)
    return Path(build)


def project_venv() -> Path:
    """The venv running the tests, whose console commands (rsm-evaluate,
    ...) the scripts under test call: the project's .venv under tools/test."""
    venv = Path(sys.executable).parent.parent
    if not (venv / "bin" / "rsm-evaluate").is_file():
        pytest.fail(f"no rsm-evaluate in {venv}/bin: run the tests with the project's .venv (tools/test)",
                    pytrace=False)
    return venv


def built_tool(relpath: str) -> Path:
    """A program built in the build directory, e.g. ``tools/nav/rsm-nav``."""
    exe = build_dir() / relpath
    if not exe.is_file():
        pytest.fail(f"{exe.name} not built at {exe}", pytrace=False)
    return exe


def rsm_nav_binary() -> Path:
    return built_tool("tools/nav/rsm-nav")


FAKEDEV_TIMEOUT = 30.0


class FakeDevices:
    """rsm-fakedev in a subprocess: ``paths`` maps ``robot``/``laser``/``ld06``/``rplidar`` to its
    pseudo-terminals; ``stop()`` ends it (SIGTERM) and returns its log, one
    dict per JSON line."""

    def __init__(self, tmp_path, *args):
        self.log_path = tmp_path / "fakedev.log"
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "rsm_tools.fakedev", "--log", str(self.log_path), *args],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=subprocess_env())
        flags = [f for f in ("--robot", "--lms", "--ld06", "--rplidar") if f in args]
        want = len(flags) if flags else 2
        out = b""
        end = time.monotonic() + FAKEDEV_TIMEOUT
        # Raw reads: both lines may come in one piece.
        while out.count(b"\n") < want and time.monotonic() < end:
            r, _, _ = select.select([self.proc.stdout], [], [], 0.1)
            if r:
                chunk = os.read(self.proc.stdout.fileno(), 4096)
                if not chunk:
                    break
                out += chunk
        lines = out.decode().splitlines()
        if len(lines) < want:
            self.proc.kill()
            self.proc.wait()
            pytest.fail(f"rsm-fakedev printed no paths: {self.proc.stderr.read().decode()}")
        self.paths = dict(line.split() for line in lines[:want])

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.wait(timeout=FAKEDEV_TIMEOUT)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        assert self.proc.returncode == 0, self.proc.stderr.read().decode()
        return [json.loads(line) for line in self.log_path.read_text().splitlines()]
