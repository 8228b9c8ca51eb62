# Puts the project's commands on the PATH of the current shell: the C tools
# of a build (rsm-nav, rsm-dump, rsm-stages) and the Python tools of .venv
# (rsm-evaluate, rsm-plot, rsm-fakedev, ...). Source it, from bash or zsh:
#
#   source tools/env.sh          the build of ./tools/test (build/), else of
#                                ./tools/demo (build-demo/)
#   source tools/env.sh DIR      the tools of the build in DIR instead
#
# RSM_BUILD_DIR, when set (the tests set it), names the build as DIR does.
# Sourcing it again does not add the folders twice.
# shellcheck shell=bash

_rsm_root=$(cd "$(dirname "${BASH_SOURCE[0]:-$0}")/.." && pwd)

_rsm_build=${1:-${RSM_BUILD_DIR:-}}
if [ -z "$_rsm_build" ]; then
    for _rsm_d in build build-demo; do
        if [ -x "$_rsm_root/$_rsm_d/tools/nav/rsm-nav" ]; then
            _rsm_build=$_rsm_d
            break
        fi
    done
fi
case $_rsm_build in
    "") ;;
    /*) ;;
    *) _rsm_build=$_rsm_root/$_rsm_build ;;
esac

# Each folder goes in front of PATH unless there already: the build's tools,
# then .venv/bin in front of them.
_rsm_path_add() {
    if [ -d "$1" ]; then
        case ":$PATH:" in
            *":$1:"*) ;;
            *) PATH=$1:$PATH ;;
        esac
    fi
}
if [ -n "$_rsm_build" ]; then
    _rsm_path_add "$_rsm_build/tools/bench-c"
    _rsm_path_add "$_rsm_build/tools/dump"
    _rsm_path_add "$_rsm_build/tools/nav"
fi
_rsm_path_add "${RSM_VENV:-$_rsm_root/.venv}/bin"
export PATH

if [ -z "$_rsm_build" ] || [ ! -x "$_rsm_build/tools/nav/rsm-nav" ]; then
    echo "tools/env.sh: no rsm-nav built yet (run ./tools/demo or ./tools/test first)" >&2
fi
if [ ! -d "${RSM_VENV:-$_rsm_root/.venv}/bin" ]; then
    echo "tools/env.sh: no .venv yet (run ./tools/demo or ./tools/test first)" >&2
fi
unset _rsm_root _rsm_build _rsm_d
unset -f _rsm_path_add
