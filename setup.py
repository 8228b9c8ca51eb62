"""Builds the Python module (port/python): the library's sources
(src/, with the default config.h) and the shim port/python/rsm_py.c, as
one shared object rsm/_native*.so that rsm/__init__.py loads with ctypes.

It is compiled as an extension so that the wheel is tagged for this
platform, but it includes no Python header: the shim is plain C99."""

import os
import re
from pathlib import Path

from setuptools import setup, Extension
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
BUILD_DIR = os.environ.get("RSM_PY_BUILD_DIR") or "build-python"


def version() -> str:
    text = (ROOT / "include" / "rsm" / "version.h").read_text(encoding="utf-8")
    parts = [re.search(rf"^#define RSM_VERSION_{p} +([0-9]+)$", text, re.M).group(1)
             for p in ("MAJOR", "MINOR", "PATCH")]
    return ".".join(parts)


def sources() -> list:
    # Relative paths, as setuptools wants; src/LAYER/*.c as CMake globs them.
    found = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "src").glob("*/*.c"))
    return found + ["port/python/rsm_py.c"]


def headers() -> list:
    # Any header changed rebuilds the object (setuptools looks at the
    # sources and these only).
    return sorted(p.relative_to(ROOT).as_posix() for d in ("include", "src") for p in (ROOT / d).rglob("*.h"))



class BuildNoInit(build_ext):
    """No PyInit_ function is exported: ctypes loads the object, Python's
    import never does."""

    def get_export_symbols(self, ext):
        return []


native = Extension(
    "rsm._native",
    sources=sources(),
    depends=headers(),
    # Internal headers are included by their layer's folder ("map/tilemap.h",
    # docs/layering.md): src/ is the one folder to search.
    include_dirs=["include", "src"],
    define_macros=[("RSM_WITH_ICP", "1")],
    # As CMake builds the library (rsm_float_flags): the same float bits
    # as rsm-nav, so a trajectory from Python equals the C tool's.
    extra_compile_args=["-std=c99", "-O2", "-ffp-contract=off", "-fno-math-errno"],
    libraries=["m"],
)

setup(
    version=version(),
    packages=["rsm"],
    package_dir={"rsm": "port/python/rsm"},
    ext_modules=[native],
    cmdclass={"build_ext": BuildNoInit},
    # Out of the CMake build folder build/ (the build* folders are ignored
    # by git), or where RSM_PY_BUILD_DIR says (the test builds afresh there).
    options={"build": {"build_base": BUILD_DIR}, "egg_info": {"egg_base": BUILD_DIR}},
)
