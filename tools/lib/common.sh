# Shared helpers for tools/test, tools/demo, tools/cross-check and tools/fuzz.
# Source it from bash (set -euo pipefail in the caller); it defines functions
# and a few variables and runs nothing by itself.
# shellcheck shell=bash

RSM_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
RSM_JOBS=$(nproc 2>/dev/null || getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)
RSM_WERROR=${RSM_WERROR:-OFF}
RSM_VENV=${RSM_VENV:-"$RSM_ROOT/.venv"}
RSM_VENV_PY="$RSM_VENV/bin/python"

# Debian packages the build and the tests need (tools/test installs them).
# libclang-rt-dev carries libFuzzer (clang only recommends it); zlib1g-dev is
# for rsm-nav reading gzipped CARMEN logs; qemu-system-arm runs the firmware
# images on an emulated Cortex-M4F (the m4.* tests).
RSM_DEBS=(cmake ninja-build gcc g++ pkg-config libserialport-dev
          gcc-arm-none-eabi libnewlib-arm-none-eabi clang libclang-rt-dev
          python3-venv valgrind zlib1g-dev qemu-system-arm)
# Extra apt-get install options (tools/demo: --no-install-recommends).
RSM_APT_OPTS=()

# ---- messages and stages ------------------------------------------------------

rsm_info() { printf '%s\n' "$*"; }
rsm_warn() { printf 'warning: %s\n' "$*" >&2; }
rsm_die() { printf 'error: %s\n' "$*" >&2; exit 1; }

rsm_section() { printf '\n==== %s ====\n' "$*"; }

RSM_STAGE=""
RSM_TIMINGS=()
RSM_START=$(date +%s)

# Reports which stage failed when a script exits non-zero (set -e keeps its
# full effect inside stages because they are never run as a condition).
rsm_on_exit() {
    local rc=$?
    if [ "$rc" -ne 0 ] && [ -n "$RSM_STAGE" ]; then
        printf '\ntools/%s: FAILED in stage "%s" (exit %s)\n' "${0##*/}" "$RSM_STAGE" "$rc" >&2
    fi
}
trap rsm_on_exit EXIT

# rsm_stage TITLE COMMAND [ARGS...]: prints a header, runs the command and
# records how long it took. With RSM_STAGE_LOG set to a file (tools/demo), the
# header and the command's output go there and the stage prints one line,
# "TITLE ... done (N s)", or on failure the file's last lines; the command then
# runs as a condition (its status is checked), so set -e does not stop it early.
rsm_stage() {
    local title=$1 start end rc=0
    shift
    RSM_STAGE=$title
    start=$(date +%s)
    if [ -z "${RSM_STAGE_LOG:-}" ]; then
        rsm_section "$title"
        "$@"
    else
        printf '%s ... ' "$title"
        rsm_section "$title" >>"$RSM_STAGE_LOG"
        "$@" >>"$RSM_STAGE_LOG" 2>&1 || rc=$?
        if [ "$rc" -ne 0 ]; then
            printf 'failed; the end of %s:\n' "$RSM_STAGE_LOG"
            tail -n 15 "$RSM_STAGE_LOG"
            exit "$rc"
        fi
    fi
    end=$(date +%s)
    [ -z "${RSM_STAGE_LOG:-}" ] || printf 'done (%s s)\n' "$((end - start))"
    RSM_STAGE=""
    RSM_TIMINGS+=("$(printf '%5ss  %s' "$((end - start))" "$title")")
}

rsm_print_timings() {
    local t
    rsm_section "Timings"
    for t in "${RSM_TIMINGS[@]}"; do
        printf '%s\n' "$t"
    done
    printf '%5ss  total so far\n' "$(($(date +%s) - RSM_START))"
}

rsm_require_cmd() {
    local cmd=$1 hint=${2:-}
    command -v "$cmd" >/dev/null 2>&1 || rsm_die "'$cmd' not found${hint:+ ($hint)}"
}

# ---- system packages -------------------------------------------------------------

rsm_as_root() {
    if [ "$(id -u)" -eq 0 ]; then
        "$@"
    elif command -v sudo >/dev/null 2>&1; then
        sudo "$@"
    else
        rsm_die "need root to run: $* (and sudo is not installed)"
    fi
}

# Installs the Debian packages that are missing; does nothing (and touches no
# network) when all are there.
rsm_ensure_debs() {
    local missing=() p status
    if ! command -v dpkg-query >/dev/null 2>&1; then
        rsm_warn "not a Debian system: make sure these (or your system's equivalents) are installed: ${RSM_DEBS[*]}"
        return 0
    fi
    for p in "${RSM_DEBS[@]}"; do
        status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
        [ "$status" = installed ] || missing+=("$p")
    done
    if [ "${#missing[@]}" -eq 0 ]; then
        rsm_info "Debian packages: all ${#RSM_DEBS[@]} present"
        return 0
    fi
    rsm_info "Debian packages: installing ${missing[*]}"
    rsm_as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
    rsm_as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq -o Dpkg::Use-Pty=0 \
        ${RSM_APT_OPTS[@]+"${RSM_APT_OPTS[@]}"} "${missing[@]}" </dev/null
}

# ---- Python venv -------------------------------------------------------------------

rsm_sha256() { sha256sum "$1" | cut -d' ' -f1; }

# Creates .venv if needed and installs tools/ (with its test extras) into it,
# again only when tools/pyproject.toml has changed since the last install.
rsm_ensure_venv() {
    local pyproject="$RSM_ROOT/tools/pyproject.toml" stamp="$RSM_VENV/.rsm-pyproject.sha256" want
    if [ -x "$RSM_VENV_PY" ] && ! "$RSM_VENV_PY" -c 'import sys' >/dev/null 2>&1; then
        rsm_info "Python venv: $RSM_VENV is broken; recreating it"
        rm -rf "$RSM_VENV"
    fi
    if [ ! -x "$RSM_VENV_PY" ]; then
        rsm_require_cmd python3 "Debian: python3-venv"
        rsm_info "Python venv: creating .venv"
        python3 -m venv "$RSM_VENV"
    fi
    if [ ! -f "$pyproject" ]; then
        rsm_info "Python venv: no tools/pyproject.toml yet, so nothing to install into .venv"
        return 0
    fi
    want=$(rsm_sha256 "$pyproject")
    if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
        rsm_info "Python venv: .venv is up to date with tools/pyproject.toml"
        return 0
    fi
    rsm_info "Python venv: installing tools[test] into .venv (tools/pyproject.toml changed)"
    rm -f "$stamp"
    "$RSM_VENV_PY" -m pip install --disable-pip-version-check -q -e "$RSM_ROOT/tools[test]" </dev/null
    printf '%s\n' "$want" >"$stamp"
}

rsm_setup() {
    rsm_ensure_debs
    rsm_ensure_venv
}

# ---- CMake -----------------------------------------------------------------------

# rsm_cmake_configure DIR [CMAKE ARGS...]: configures DIR (relative to the
# source root) with Ninja, unless it is already configured from this source
# tree with exactly these arguments (and CMAKE_PREFIX_PATH); ninja itself re-runs CMake when a
# CMakeLists.txt changes. A build directory made by another generator or from
# another source tree is wiped first.
rsm_cmake_configure() {
    local dir="$RSM_ROOT/$1" stamp want cache home gen
    shift
    stamp="$dir/.rsm-configure-args"
    # CMAKE_PREFIX_PATH from the environment decides which Unity is found.
    want=$(printf '%s\n' "$@" "env CMAKE_PREFIX_PATH=${CMAKE_PREFIX_PATH:-}")
    cache="$dir/CMakeCache.txt"
    if [ -f "$cache" ]; then
        home=$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$cache")
        gen=$(sed -n 's/^CMAKE_GENERATOR:INTERNAL=//p' "$cache")
        if [ "$home" != "$RSM_ROOT" ] || [ "$gen" != Ninja ]; then
            rsm_info "${dir#"$RSM_ROOT"/}: made by another source tree or generator; starting afresh"
            rm -rf "$dir"
        fi
    fi
    if [ -f "$dir/build.ninja" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
        return 0
    fi
    rm -f "$stamp"
    cmake -S "$RSM_ROOT" -B "$dir" -G Ninja "$@"
    printf '%s\n' "$want" >"$stamp"
}

# The main host build: build/ with every test, against the venv's Python;
# the firmware tests required (RSM_TARGET_TESTS=ON), not skipped when the
# cross toolchain or QEMU is missing as a plain configure would.
rsm_build_main() {
    rsm_cmake_configure build -DRSM_WERROR="$RSM_WERROR" -DRSM_PYTHON="$RSM_VENV_PY" -DRSM_TARGET_TESTS=ON
    cmake --build "$RSM_ROOT/build" -j"$RSM_JOBS"
}
