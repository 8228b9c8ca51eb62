"""Shared test set-up: import path, data locations and small helpers.

The tests run from a plain checkout (``python -m pytest tests/py``) without
installing the package: the ``tools`` folder is put on ``sys.path``.

The real dataset is expected in ``../shared/data/intel/`` relative to the
repository root.  Tests that need it FAIL (they do not skip) when it is absent.
"""

import gzip
import os
import sys
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
TOOLS_DIR = REPO_ROOT / "tools"
TEST_DATA = REPO_ROOT / "tests" / "data"
INTEL_DIR = REPO_ROOT.parent / "shared" / "data" / "intel"

INTEL_FILES = ("intel.clf.gz", "intel.relations", "intel-corrected-poses.txt")

if str(TOOLS_DIR) not in sys.path:
    sys.path.insert(0, str(TOOLS_DIR))


def _require(path: Path, what: str) -> Path:
    if not path.is_file():
        pytest.fail(
            f"{what} not found: {path}\n"
            "The real Intel Research Lab dataset must sit in ../shared/data/intel/ relative "
            "to the repository root (files: " + ", ".join(INTEL_FILES) + ").",
            pytrace=False,
        )
    return path


def require_intel_dir() -> Path:
    """The real dataset folder.

    Called inside a test body (not as a fixture), so that a missing dataset
    shows as a FAILED test, not as a set-up error or a skip.
    """
    for name in INTEL_FILES:
        _require(INTEL_DIR / name, f"real dataset file {name}")
    return INTEL_DIR


@pytest.fixture(scope="session")
def head_log() -> Path:
    return _require(TEST_DATA / "intel_head.clf.gz", "shipped excerpt")


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
