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
import threading
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

# How long a test waits for an event (a line, a log entry) before calling the
# run hung: a safety net only, never what a verdict rests on.
EVENT_LIMIT = 120.0


def wait_until(check, what: str, limit: float = EVENT_LIMIT, poll: float = 0.05):
    """Polls check() until it returns something true, and returns that; a
    run that never gets there within limit seconds is hung: fail."""
    end = time.monotonic() + limit
    while True:
        got = check()
        if got:
            return got
        if time.monotonic() >= end:
            pytest.fail(f"waited {limit:.0f} s for {what}", pytrace=False)
        time.sleep(poll)


class Lines:
    """A running program's output, read line by line by a thread, so that a
    test can wait for a line (an event: what the program said) without
    blocking on the pipe."""

    def __init__(self, stream):
        self.lines = []
        self.closed = False
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._read, args=(stream,), daemon=True)
        self._thread.start()

    def _read(self, stream):
        for line in stream:
            with self._lock:
                self.lines.append(line)
        with self._lock:
            self.closed = True

    def text(self) -> str:
        with self._lock:
            return "".join(self.lines)

    def wait_for(self, needle: str, limit: float = EVENT_LIMIT) -> None:
        """Until a line holds needle (fails if the program ends first)."""
        def seen():
            text = self.text()
            if needle in text:
                return True
            if self.closed:
                pytest.fail(f"the program ended without saying {needle!r}:\n{text}", pytrace=False)
            return False
        wait_until(seen, repr(needle), limit)

    def finish(self) -> str:
        """Everything, once the program has closed its end."""
        self._thread.join(timeout=EVENT_LIMIT)
        return self.text()


class LiveNav:
    """rsm-nav running live (``args`` after the program), its stderr followed
    line by line (``err``, a Lines), its stdout into a file."""

    def __init__(self, tmp_path, *args):
        self.out_path = tmp_path / "nav.out"
        with open(self.out_path, "w", encoding="utf-8") as out:
            self.proc = subprocess.Popen([str(rsm_nav_binary()), *map(str, args)], stdout=out,
                                         stderr=subprocess.PIPE, text=True)
        self.err = Lines(self.proc.stderr)

    def finish(self, stop: bool = False, limit: float = EVENT_LIMIT):
        """Waits for the end (after SIGTERM if stop); returns (stderr, stdout).
        A run that does not end within limit seconds is hung: killed, fail."""
        if stop and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.wait(timeout=limit)
        except subprocess.TimeoutExpired:
            self.kill()
            pytest.fail(f"rsm-nav still running after {limit:.0f} s:\n{self.err.text()}", pytrace=False)
        return self.err.finish(), self.out_path.read_text()

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


def events_so_far(path) -> list:
    """The complete lines of an events file being written (rsm-nav flushes
    each line in a live run)."""
    if not path.is_file():
        return []
    text = path.read_text()
    return text[:text.rfind("\n") + 1].splitlines()


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

    def log(self):
        """The log so far (flushed line by line; a line being written is left out)."""
        out = []
        for line in self.log_path.read_text().splitlines():
            try:
                out.append(json.loads(line))
            except json.JSONDecodeError:
                break
        return out

    def wait_log(self, match, what: str, count: int = 1, limit: float = EVENT_LIMIT):
        """Until count log entries satisfy match(entry); returns them."""
        def found():
            got = [e for e in self.log() if match(e)]
            return got if len(got) >= count else None
        return wait_until(found, what, limit)

    def signal(self, sig) -> None:
        self.proc.send_signal(sig)

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
