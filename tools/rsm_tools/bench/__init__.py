"""rsm-bench: measures rsm against the paper's method, ICP, odometry and the peers, and writes a report.

Every figure of rsm in the report is measured by this command; none is typed
in. The peers' figures are read from ``docs/reference/peers.md`` (``--peers``)
and shown beside them. The logs are every folder ``NAME`` of the
shared folder's ``data/`` that holds ``NAME.clf.gz`` and ``NAME.relations``
(the shared folder: ``--shared DIR``, else the ``RSM_SHARED_DIR`` environment
variable, the one setting for the full logs, else ``../shared`` beside the repository). The
report (``docs/RESULTS.md`` by default) has these sections:

1. Accuracy: relative-pose error (Kuemmerle et al. 2009, :mod:`rsm_tools.evaluate`)
   of rsm (the default method, the persistent map), rsm built with
   ``rsm/config_small.h``, the paper's method, the ICP baseline and odometry on
   every log, on all relations and on local ones (span <= 2 s), beside the
   peers' figures and the ratio of rsm's to the best peer's.
2. Robustness, the paper's experiment: a share of every scan's readings is
   replaced by random ranges (:mod:`rsm_tools.outliers`); the whole curve on
   the main log, 43 % and 60 % on every log; and rsm over many runs (the map
   update distance varied) clean and at 43 %, whose means the floors compare
   too; and rsm on copies of every log with odometry and sampling faults
   (:mod:`rsm_tools.faults`; the subsection "Faults", :mod:`.faults`); the
   Faults section's clean runs again with the fixed-point matcher the cores
   without an FPU build (:mod:`.fixedmatch`); and rsm on a map it saved: the round trip, localization mode, the global
   search from starts spread over every log and kidnaps (the subsection "Known map",
   :mod:`.knownmap`; ``--only knownmap`` runs it alone).
3. Sharp turns, the paper's Fig. 8: residuals at the local relations with the
   fastest true turn, and over all local relations binned by true rotation.
4. Speed: wall time per scan (rsm-nav), per stage (``rsm-stages``, the
   localizer's timing hook) and instructions per scan (callgrind inside
   ``rsm_localizer_scan``, first scans of every log, default and small
   configuration), in total and by stage; and on the target: instructions per
   scan and per stage of the replay firmware on an emulated Cortex-M4F (QEMU
   mps2-an386, ``-O2``, :mod:`rsm_tools.m4`) beside callgrind's count of the
   same excerpt on the host, with the images' flash, RAM and painted stack,
   the encoder steps counted in every scan; the same replay at ``-Os``, on
   a Cortex-M3 and a Cortex-M0+ with soft float (QEMU mps2-an385), and the
   RP2040 LD06 example's size (issue 33);
   and the global search's instructions per scan in the excerpt's map, from
   the map-in-flash firmware (the floor of the subsection "Known map").
5. Memory: the localizer state per part on this host (``rsm-stages``) and on
   Cortex-M4F (a cross build per configuration), flash per object, the
   example firmware, the stack of one localizer step.
6. Scaling: time, accuracy and state size against readings per scan, the
   paper's window, the persistent map's tile pool and the shipped presets.
7. The issue's floors, each a PASS or MISS line (a report, not an assertion),
   with the checks that need the full logs (:mod:`rsm_tools.fullchecks`; the
   logs as LD06 and RPLIDAR streams, :mod:`rsm_tools.lidarbench`; rsm
   against odometry alone in simulated bare corridors,
   :mod:`rsm_tools.corridors`; de-skew with encoder packets read in bursts,
   :mod:`.deskew`). ``--only capture`` and ``--only deskew`` print the
   capture path's and the bursts' lines alone.
8. Where rsm loses: generated from the numbers above.

Trajectories, summaries and a manifest (``bench.json``) are kept in the work
directory, so that the report can be checked against them; outlier logs are
cached and reused.  ``tools/bench`` sets up, builds ``build-release/`` and
runs this module with the full settings.  Python standard library only;
matplotlib, if installed, draws the plots.
"""

# The parts (each a module of this package) are imported here by the names
# the command and the tests use as rsm_tools.bench.NAME.
import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

from .. import corridors, fullchecks, lidarbench
from ..fullchecks import check
from .common import (ARM_CONFIGS, BenchError, CALLGRIND_SCANS, DEFAULT_MAP_LOG2, DEFAULT_MAX_BEAMS, DEFAULT_TILES,
    FIRST_SEED, HOST_PARTS, LEVELS, LOCAL_SPAN, MEMORY_TILES, METHODS, OTHER_LEVELS, PEER_COLUMNS, QUANTITIES,
    QUICK_LEVELS, QUICK_OTHER_LEVELS, QUICK_SPREAD_UPDATES, ROBUST_METHODS, ROTATION_BINS, SCALING_BEAMS,
    SCALING_MAP_LOG2, SCALING_PRESETS, SCALING_TILES, SCOPES, SECTION_TITLES, SEEDS, SMALL, SMALL_HEADER,
    SPEED_REPEATS, SPREAD_SEEDS, SPREAD_UPDATES, STAGES, TURNS, find_root, fmt_int, shown_path)
from .parse import (_peer_table, base_name, best_peers, callee_costs, callgrind_stages, fused_percent, load_peers,
    load_summary, localizer_breakdown, parse_callgraph_info, parse_callgrind, parse_cross_check, parse_nm_sizes,
    parse_peers, parse_size_archive, peer_speed, static_functions, worst_stack_path)
from .plots import plot_robustness, plot_scaling, plot_stages, plot_turns
from .measure import (build_fixed, build_small, cmake_cache, cpu_info, discover_logs, hash_log2_for, memory_growth, provenance,
    run_accuracy, run_arm_memory, run_callgrind, run_cross_check, run_host_stack, run_m4, run_memory, run_nav,
    run_robustness, run_scaling, run_speed, run_spread, run_stage_speed, run_stages, run_turns, scaling_variants,
    shared_dir, source_digest, spread_updates, stages_exe, variant_header, write_head)
from .faults import FAULT_NAMES, FAULT_RUNS, QUICK_FAULT_RUNS, fault_floors, report_faults, run_faults
from .knownmap import (KIDNAP_RUNS, QUICK_KIDNAP_RUNS, QUICK_STARTS, STARTS, START_SCANS, knownmap_floors,
    run_knownmap)
from . import deskew as _deskew
from . import fixedmatch as _fixedmatch
from . import knownmap as _knownmap
from . import navmemory as _navmemory
from .report import (FLOOR_LEVEL, FLOOR_ROBUST, PEER_FLOORS, _scope_name, before_label, check_floors,
    floor_inputs, losses, m4_floors, m4_lines, spread_floors, write_from_manifest)


def _integers(text: str, lowest: int, highest: Optional[int], rule: str) -> List[int]:
    """A comma-separated list of integers, sorted, each once, all within [lowest, highest]."""
    try:
        vals = sorted({int(v) for v in text.split(",") if v.strip()})
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of integers: {text!r}") from None
    if not vals or any(v < lowest or (highest is not None and v > highest) for v in vals):
        raise argparse.ArgumentTypeError(f"{rule}: {text!r}")
    return vals


def _levels(text: str) -> List[int]:
    return _integers(text, 0, 100, "levels must be within 0..100")


def _counts(text: str) -> List[int]:
    return _integers(text, 1, None, "values must be positive")


def _names(text: str) -> List[str]:
    known = [n for n, _ in ARM_CONFIGS]
    vals = [v.strip() for v in text.split(",") if v.strip()]
    if not vals or any(v not in known for v in vals):
        raise argparse.ArgumentTypeError(f"configurations are among {', '.join(known)}: {text!r}")
    return vals


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="rsm-bench",
        description="Measure rsm, the paper's method, its ICP baseline and odometry on every log of the shared "
                    "folder (accuracy beside the peers, robustness to outliers, speed, memory, the issue's floors) "
                    "and write docs/RESULTS.md. ./tools/bench builds and runs this.")
    p.add_argument("--root", type=Path, help="repository root (default: found from the current folder)")
    p.add_argument("--build-dir", type=Path, help="build with tools/nav/rsm-nav and tools/bench-c/rsm-stages "
                   "(default: ROOT/build-release)")
    p.add_argument("--shared", type=Path, help="the shared folder: its data/NAME/ folders holding NAME.clf.gz and "
                   "NAME.relations are the logs (default: the environment variable RSM_SHARED_DIR, else "
                   "ROOT/../shared)")
    p.add_argument("--peers", type=Path, help="the peers' figures (default: ROOT/docs/reference/peers.md)")
    p.add_argument("--small-build", type=Path, help=f"a Release build with RSM_USER_CONFIG={SMALL_HEADER} holding "
                   "rsm-nav and rsm-stages (default: the bench builds one in BUILD/bench-small)")
    p.add_argument("--levels", type=_levels, help="outlier percentages on the main log (default: "
                   + ",".join(map(str, LEVELS)) + "; quick: " + ",".join(map(str, QUICK_LEVELS)) + "); the other "
                   "logs run " + ",".join(map(str, OTHER_LEVELS)) + " (quick " + ",".join(map(str, QUICK_OTHER_LEVELS))
                   + ")")
    p.add_argument("--seeds", type=int, help=f"seeds per outlier level, counting from {FIRST_SEED} "
                   f"(default {SEEDS}; quick 1)")
    p.add_argument("--spread", type=int, help=f"map update distances of the runs over which the outlier floors are "
                   f"also judged, each clean, every other one at each spread seed's outliers (default "
                   f"{SPREAD_UPDATES}; quick {QUICK_SPREAD_UPDATES}; 0: skip)")
    p.add_argument("--spread-seeds", type=int, help=f"outlier seeds of those runs, counting from {FIRST_SEED} "
                   f"(default {SPREAD_SEEDS}; quick: as --seeds)")
    p.add_argument("--faults", type=int, help=f"runs per fault of the section Faults (rsm-faults on every log, "
                   f"twice as many clean runs; default {FAULT_RUNS}; quick {QUICK_FAULT_RUNS}; 0: skip)")
    p.add_argument("--global-starts", type=int, help=f"starts per log of the section Known map's global "
                   f"localization, spread evenly over the log (default {STARTS}; quick {QUICK_STARTS}; 0: skip the "
                   "section)")
    p.add_argument("--global-scans", type=int, default=START_SCANS, help=f"scans each of those starts runs at most "
                   f"(default {START_SCANS})")
    p.add_argument("--kidnap-runs", type=int, help=f"runs per log of the section Known map's kidnapping, one "
                   f"kidnap each, frozen and with updates (default {KIDNAP_RUNS}; quick {QUICK_KIDNAP_RUNS}; 0: skip "
                   "that part)")
    p.add_argument("--only", choices=("knownmap", "capture", "deskew", "faults"), help="run one section alone: "
                   "knownmap (the section Known map, written into the existing report and the work directory's "
                   "manifest, the rest left as it is; with --global-starts, --global-scans, --kidnap-runs, --quick, "
                   "--jobs, --shared, --output, --work-dir); capture (the capture path against the direct run and "
                   "its jittered runs, on every log; with --jitter-runs, --jobs, --shared, --work-dir), deskew "
                   "(de-skew with encoder packets in bursts; with --deskew-seconds, --work-dir) or faults (the "
                   "section Faults; with --faults, --fault-names, --odom-lines, --quick, --jobs, --shared, "
                   "--work-dir): these three print their lines and write WORK/only-NAME.json, and leave the report "
                   "as it is")
    p.add_argument("--fault-names", help="with --only faults: the faults to run, comma-separated (default all: "
                   + ", ".join(FAULT_NAMES) + "); the clean runs always")
    p.add_argument("--odom-lines", action="store_true", help="with --only faults: every run, clean or faulty, "
                   "rsm-nav --odom-lines on a log with its ODOM lines (each an odometry step of its own)")
    p.add_argument("--jitter-runs", type=int, help=f"direct runs with +-{fullchecks.JITTER_M * 1e6:g} um of odometry "
                   f"jitter beside the capture path (default {fullchecks.JITTER_RUNS}; quick "
                   f"{fullchecks.QUICK_JITTER_RUNS})")
    p.add_argument("--deskew-seconds", type=float, help=f"simulated drive per lidar of the de-skew-in-bursts line "
                   f"(default {_deskew.SECONDS:g}; quick {_deskew.QUICK_SECONDS:g})")
    p.add_argument("--speed-repeats", type=int, help=f"timed runs per method (default {SPEED_REPEATS}; quick 1)")
    p.add_argument("--callgrind-scans", type=int, default=CALLGRIND_SCANS,
                   help=f"scans from the start of every log counted by callgrind (default {CALLGRIND_SCANS})")
    p.add_argument("--jobs", type=int, default=2, help="rsm-nav processes at a time for untimed runs (default 2)")
    p.add_argument("--quick", action="store_true", help="one seed, fewer levels, one speed repeat, callgrind of rsm "
                   "only, no scaling builds")
    p.add_argument("--no-callgrind", action="store_true", help="skip the instruction counts")
    p.add_argument("--no-m4", action="store_true",
                   help="skip the Cortex-M4F images under QEMU (instructions per scan on the target)")
    p.add_argument("--no-cross-check", action="store_true", help="skip tools/cross-check")
    p.add_argument("--no-full-checks", action="store_true", help="skip the checks of rsm_tools.fullchecks (the "
                   "logs against their description, rsm against its baselines, reruns, the capture path)")
    p.add_argument("--no-plots", action="store_true", help="draw no plot")
    p.add_argument("--turns", type=int, default=TURNS, help=f"sharpest turns in the Fig. 8 table (default {TURNS})")
    p.add_argument("--no-stack", action="store_true", help="skip the painted stack measurement")
    p.add_argument("--no-arm-memory", action="store_true", help="skip the per-configuration Cortex-M4F builds")
    p.add_argument("--arm-configs", type=_names, help="Cortex-M4F configurations to build (default "
                   + ",".join(n for n, _ in ARM_CONFIGS) + ")")
    p.add_argument("--no-scaling", action="store_true", help="skip the scaling section")
    p.add_argument("--scaling-beams", type=_levels, help="readings per scan of the scaling runs (default "
                   + ",".join(map(str, SCALING_BEAMS)) + f"; quick {DEFAULT_MAX_BEAMS})")
    p.add_argument("--scaling-maps", type=_levels, help="RSM_MAP_SIZE_LOG2 values of the paper's window (default "
                   + ",".join(map(str, SCALING_MAP_LOG2)) + f"; quick {DEFAULT_MAP_LOG2})")
    p.add_argument("--scaling-tiles", type=_counts, help="RSM_TMAP_TILES values of rsm's tile pool (default "
                   + ",".join(map(str, SCALING_TILES)) + f"; quick {DEFAULT_TILES}); the presets "
                   + ", ".join(SCALING_PRESETS) + " run too, except in quick mode")
    p.add_argument("--output", type=Path, help="report (default: ROOT/docs/RESULTS.md)")
    p.add_argument("--plots-dir", type=Path, help="plots (default: ROOT/docs/results)")
    p.add_argument("--work-dir", type=Path, help="trajectories and manifest (default: BUILD/bench-work)")
    p.add_argument("--cache-dir", type=Path, help="outlier logs (default: BUILD/bench-cache)")
    return p


def _json_default(o):
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))


def _jsonable(o):
    """o with tuple keys (the peers' (scope, quantity)) joined by a space, for the manifest."""
    if isinstance(o, dict):
        return {(" ".join(map(str, k)) if isinstance(k, tuple) else k): _jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_jsonable(v) for v in o]
    return o


def _fault_names(args: argparse.Namespace) -> Tuple[str, ...]:
    """--fault-names as a tuple (every fault without it); refused when
    unknown, empty, or given without --only faults, as is --odom-lines
    without it."""
    if args.odom_lines and args.only != "faults":
        raise BenchError("--odom-lines goes with --only faults (the whole bench runs as the defaults do)")
    if args.fault_names is None:
        return FAULT_NAMES
    if args.only != "faults":
        raise BenchError("--fault-names goes with --only faults (the whole bench runs every fault)")
    names = tuple(n.strip() for n in args.fault_names.split(",") if n.strip())
    unknown = [n for n in names if n not in FAULT_NAMES]
    if unknown or not names:
        raise BenchError(f"--fault-names: unknown {', '.join(unknown) or '(none given)'}; "
                         f"known: {', '.join(FAULT_NAMES)}")
    return names


def run(args: argparse.Namespace) -> Path:
    t_start = time.monotonic()
    fault_names = _fault_names(args)  # a bad argument is refused before anything is built or read
    root = (args.root or find_root()).resolve()
    build = (args.build_dir or root / "build-release").resolve()
    nav = build / "tools" / "nav" / "rsm-nav"
    if not nav.is_file():
        raise BenchError(f"rsm-nav is not built: {nav} (run ./tools/bench, which builds it)")
    stages_bin = stages_exe(build)
    if not stages_bin.is_file() and args.only is None:
        raise BenchError(f"rsm-stages is not built: {stages_bin} (run ./tools/bench, which builds it)")
    shared = shared_dir(args.shared, root)
    data = shared / "data"
    logs = discover_logs(data)
    if not logs:
        raise BenchError(f"no log in {data}: the bench needs the full logs, each a folder NAME holding NAME.clf.gz "
                         "and NAME.relations (set the shared folder with --shared or RSM_SHARED_DIR; see "
                         "docs/reference/README.md)")
    levels = args.levels or (list(QUICK_LEVELS) if args.quick else list(LEVELS))
    if 0 not in levels:
        levels = [0] + levels  # the ratios need the clean figure
    other_levels = list(QUICK_OTHER_LEVELS if args.quick else OTHER_LEVELS)
    nseeds = args.seeds if args.seeds is not None else (1 if args.quick else SEEDS)
    repeats = args.speed_repeats if args.speed_repeats is not None else (1 if args.quick else SPEED_REPEATS)
    if nseeds < 1 or repeats < 1 or args.jobs < 1 or args.callgrind_scans < 1:
        raise BenchError("--seeds, --speed-repeats, --callgrind-scans and --jobs must be at least 1")
    seeds = list(range(FIRST_SEED, FIRST_SEED + nseeds))
    work = (args.work_dir or build / "bench-work").resolve()
    cache = (args.cache_dir or build / "bench-cache").resolve()
    output = (args.output or root / "docs" / "RESULTS.md").resolve()
    plots = (args.plots_dir or root / "docs" / "results").resolve()
    work.mkdir(parents=True, exist_ok=True)
    main_label, main_log, main_rel = logs[0]
    stage_seconds: Dict[str, float] = {}
    nstarts = args.global_starts if args.global_starts is not None else (QUICK_STARTS if args.quick else STARTS)
    if args.global_scans < 1:
        raise BenchError("--global-scans must be at least 1")
    nkidnap = args.kidnap_runs if args.kidnap_runs is not None else (QUICK_KIDNAP_RUNS if args.quick else KIDNAP_RUNS)
    km_jobs = max(args.jobs, os.cpu_count() or 1)  # the section's many short runs: every core
    if args.only == "knownmap":
        if nstarts < 1:
            raise BenchError("--only knownmap needs --global-starts of at least 1")
        print("rsm-bench: logs " + ", ".join(f"{l} ({shown_path(g, root)})" for l, g, _ in logs) + "; known map only",
              flush=True)
        km, floors = _knownmap.run_only(nav, logs, work, km_jobs, nstarts, args.global_scans,
                                        stages_bin if stages_bin.is_file() else None, provenance(root, build),
                                        output, SECTION_TITLES[2], nkidnap)
        print("rsm-bench: the section's floors:")
        for f in floors:
            print(f"  {f['line']}")
        print(f"rsm-bench: known map in {km['seconds']:.0f} s; wrote its section into {output} and "
              f"{work / 'bench.json'}")
        return output

    if args.only in ("capture", "deskew", "faults"):
        return _run_only_line(args, nav, logs, work, root, fault_names)

    def stage(name, fn, *a):
        print(f"rsm-bench: {name} ...", flush=True)
        t0 = time.monotonic()
        res = fn(*a)
        stage_seconds[name] = time.monotonic() - t0
        print(f"rsm-bench: {name} done in {stage_seconds[name]:.1f} s", flush=True)
        return res

    print("rsm-bench: logs " + ", ".join(f"{l} ({shown_path(g, root)})" for l, g, _ in logs), flush=True)
    prov = provenance(root, build)
    digest = source_digest(root)
    ctx = {"root": root, "provenance": prov, "main_label": main_label, "levels": levels,
           "other_levels": other_levels, "seeds": seeds, "speed_repeats": repeats, "jobs": args.jobs,
           "quick": args.quick, "data_dir": str(data)}
    peers_md = (args.peers or root / "docs" / "reference" / "peers.md").resolve()
    ctx["peers"] = load_peers(peers_md)
    if "skipped" in ctx["peers"]:
        print(f"rsm-bench: no peer figures: {ctx['peers']['skipped']} ({peers_md}); the peers are skipped",
              flush=True)
    else:
        text = peers_md.read_text(encoding="utf-8", errors="replace")
        ctx["peer_speed"] = peer_speed(text)
        ctx["peer_speed_table"] = _peer_table(text, "speed")
        ctx["peer_robustness"] = _peer_table(text, "robustness")
    if args.small_build:
        sb = args.small_build.resolve()
        small = {"nav": sb / "tools" / "nav" / "rsm-nav", "stages": stages_exe(sb), "dir": sb}
        for f in (small["nav"], small["stages"]):
            if not f.is_file():
                raise BenchError(f"{f} is missing in the --small-build tree")
    else:
        small = stage("small build", build_small, root, build, build / "bench-small")
    ctx["small_build"] = str(small["dir"])
    navs = {"default": nav, "small": small["nav"]}
    ctx["accuracy"] = stage("accuracy", run_accuracy, navs, logs, work, args.jobs)
    ctx["full_checks"] = ([check(None, "data", None, "full-log checks: not run (--no-full-checks)")]
                          if args.no_full_checks
                          else stage("full-log checks", fullchecks.run_all, shared, nav, logs, work / "full-checks",
                                     root, ctx["accuracy"], not args.quick, lambda s: None, _jitter_runs(args),
                                     args.jobs))
    ctx["deskew_bursts"] = stage("de-skew bursts", _deskew.run, nav, work, _deskew_seconds(args))
    ctx["lidar_streams"] = stage("lidar streams", lidarbench.run, nav, logs, work / "lidar-streams", ctx["accuracy"])
    ctx["corridors"] = stage("corridors", corridors.run, nav, work / "corridors", args.quick)
    ctx["speed"] = stage("speed", run_speed, nav, main_log, repeats, work)
    # one process at a time, like the speed runs: a long run alone, then a short one
    ctx["nav_memory"] = stage("rsm-nav memory", _navmemory.run, nav, main_log, work,
                              _navmemory.QUICK_SCANS if args.quick else _navmemory.SCANS)
    lv_by_log = {label: (levels if label == main_label else other_levels) for label, _, _ in logs}
    ctx["robustness"] = stage("robustness", run_robustness, nav, logs, ctx["accuracy"], lv_by_log, seeds, work,
                              cache, args.jobs)
    nspread = args.spread if args.spread is not None else (QUICK_SPREAD_UPDATES if args.quick else SPREAD_UPDATES)
    nsseeds = args.spread_seeds if args.spread_seeds is not None else (nseeds if args.quick else SPREAD_SEEDS)
    if nsseeds < 1:
        raise BenchError("--spread-seeds must be at least 1")
    ctx["spread"] = ({"skipped": "--spread 0"} if nspread <= 0 else
                     stage("spread", run_spread, nav, logs, FLOOR_LEVEL,
                           list(range(FIRST_SEED, FIRST_SEED + nsseeds)), spread_updates(nspread), work, cache,
                           args.jobs))
    nfaults = args.faults if args.faults is not None else (QUICK_FAULT_RUNS if args.quick else FAULT_RUNS)
    reuse = None if "skipped" in ctx["spread"] else (work / "spread", ctx["spread"]["updates"])
    ctx["faults"] = ({"skipped": "--faults 0"} if nfaults <= 0 else
                     stage("faults", run_faults, nav, logs, nfaults, work, args.jobs, reuse))
    ctx["fixed_match"] = ({"skipped": "--faults 0"} if "skipped" in ctx["faults"] else
                          stage("fixed-point matcher", _fixed_match_runs, root, build, logs, work, args.jobs,
                                ctx["faults"]))
    ctx["knownmap"] = ({"skipped": "--global-starts 0"} if nstarts <= 0 else
                       stage("known map", run_knownmap, nav, logs, work, km_jobs, nstarts, args.global_scans,
                             stages_bin, nkidnap))
    if "skipped" not in ctx["knownmap"]:
        ctx["knownmap"]["provenance"] = prov
    sanitized = cmake_cache(build).get("RSM_SANITIZE", "OFF").upper() in ("ON", "TRUE", "1", "YES")
    painted = not (args.no_stack or sanitized)
    if not painted:
        ctx["stack_note"] = ("--no-stack" if args.no_stack else
                             "the build is instrumented by AddressSanitizer, which moves frames off the stack")
    ctx["stages"] = stage("stages", run_stage_speed, stages_bin, main_log, repeats, painted)
    ctx["turns"] = stage("turns", run_turns, ctx["accuracy"][main_label]["runs"], main_rel,
                         ctx["stages"]["config"]["cell_m"], args.turns)
    cg_methods = ("rsm",) if args.quick else ROBUST_METHODS
    ctx["callgrind"] = ({"skipped": "--no-callgrind"} if args.no_callgrind
                        else stage("callgrind", run_callgrind, navs, logs, args.callgrind_scans, cg_methods, work,
                                   args.jobs, root))
    ctx["m4"] = ({"skipped": "--no-m4"} if args.no_m4
                 else stage("m4", run_m4, root, work, build / "port" / "baremetal" / "rsm-replay-host",
                            build / "port" / "baremetal" / "rsm-mapflash-host"))
    if "skipped" not in ctx["knownmap"]:
        # the section's cost floor is the M4's, measured in the stage above
        ctx["knownmap"]["m4_global"] = _knownmap.m4_global_entry(ctx["m4"])
        # and on the full logs, in the maps the section saved
        ctx["knownmap"]["m4_real"] = ({"skipped": "--no-m4"} if args.no_m4 else
                                      stage("m4 on the full logs", _knownmap.run_m4_real, logs, work,
                                            ctx["knownmap"]))
    ctx["memory"] = stage("memory", run_memory, {"default": stages_bin, "small": small["stages"]}, main_log, build)
    ctx["cross_check"] = ({"skipped": "--no-cross-check"} if args.no_cross_check
                          else stage("cross-check", run_cross_check, root))
    if args.no_arm_memory:
        ctx["arm_memory"] = {"skipped": "--no-arm-memory"}
    else:
        wanted = args.arm_configs or [n for n, _ in ARM_CONFIGS]
        ctx["arm_memory"] = stage("arm-memory", run_arm_memory, root, work,
                                  [c for c in ARM_CONFIGS if c[0] in wanted])
    ctx["host_stack"] = stage("host-stack", run_host_stack, root, build, work, args.jobs)
    if not args.no_scaling:
        beams = args.scaling_beams or ([DEFAULT_MAX_BEAMS] if args.quick else list(SCALING_BEAMS))
        maps = args.scaling_maps or ([DEFAULT_MAP_LOG2] if args.quick else list(SCALING_MAP_LOG2))
        tiles = args.scaling_tiles or ([DEFAULT_TILES] if args.quick else list(SCALING_TILES))
        ctx["scaling"] = stage("scaling", run_scaling, root, build, main_log, main_rel, work,
                               scaling_variants(beams, maps, tiles, () if args.quick else SCALING_PRESETS),
                               {SMALL_HEADER: small["stages"]})
    if args.no_plots:
        ctx["plot_note"] = ctx["turns_plot_note"] = ctx["stages"]["plot_note"] = "--no-plots"
        if ctx.get("scaling"):
            ctx["scaling"]["plot_note"] = "--no-plots"
    else:
        png = plots / "robustness.png"
        note = plot_robustness(ctx["robustness"]["logs"][main_label], png, prov,
                               ctx["accuracy"][main_label]["runs"]["odometry"]["errors"], main_label)
        if note:
            ctx["plot_note"] = note
        else:
            ctx["plot"] = os.path.relpath(png, output.parent).replace(os.sep, "/")
        for key, fn, name, target in (("turns", plot_turns, "turns.png", ctx),
                                      ("stages", plot_stages, "stages.png", ctx["stages"]),
                                      ("scaling", plot_scaling, "scaling.png", ctx.get("scaling"))):
            if not ctx.get(key):
                continue
            png = plots / name
            note = fn(ctx[key], png, prov)
            prefix = "turns_" if key == "turns" else ""
            if note:
                target[f"{prefix}plot_note"] = note
            else:
                target[f"{prefix}plot"] = os.path.relpath(png, output.parent).replace(os.sep, "/")
    if source_digest(root) != digest:
        ctx["sources_changed"] = ("the library's or the tools' sources changed while this run was measuring, so "
                                  "its figures may come from different code: run it again")
        print(f"rsm-bench: WARNING: {ctx['sources_changed']}", flush=True)
    ctx["floors"] = (check_floors(**floor_inputs(ctx)) + m4_floors(ctx.get("m4")) +
                     spread_floors(ctx.get("spread")) + fault_floors(ctx.get("faults")) +
                     _fixedmatch.floors(ctx.get("fixed_match")) +
                     knownmap_floors(ctx.get("knownmap")) + _navmemory.floors(ctx.get("nav_memory")) +
                     _deskew.floors(ctx.get("deskew_bursts")) +
                     ctx["full_checks"] +
                     ctx["lidar_streams"] + ctx["corridors"])
    ctx["losses"] = losses(ctx)
    ctx["elapsed"] = time.monotonic() - t_start
    ctx["stage_seconds"] = stage_seconds
    manifest = {k: v for k, v in ctx.items() if k != "root"}
    manifest["report"] = str(output)
    manifest["logs"] = [{"label": l, "log": str(g), "relations": str(r)} for l, g, r in logs]
    manifest_text = json.dumps(_jsonable(manifest), indent=1, default=_json_default, allow_nan=True)
    (work / "bench.json").write_text(manifest_text)
    # The report and the figures (committed beside the plots) are written from
    # the manifest, as rsm-bench-report does.
    write_from_manifest(json.loads(manifest_text), root, output, plots / "figures.json")
    print("rsm-bench: on the target:")
    for line in m4_lines(ctx.get("m4")):
        print(f"  {line}")
    print("rsm-bench: the issue's floors:")
    for f in ctx["floors"]:
        print(f"  {f['line']}")
    print(f"rsm-bench: wrote {output} in {ctx['elapsed']:.0f} s (work files in {work})")
    return output


def _fixed_match_runs(root: Path, build: Path, logs, work: Path, jobs: int, faults: dict) -> dict:
    """The fixed-point matcher's rsm-nav built beside the main build, then the
    Faults section's clean runs with it (bench/fixedmatch.py)."""
    nav_fixed = build_fixed(root, build, build / "bench-fixed")
    return _fixedmatch.run(nav_fixed, logs, work, jobs, faults)


def _jitter_runs(args: argparse.Namespace) -> int:
    n = args.jitter_runs if args.jitter_runs is not None else (
        fullchecks.QUICK_JITTER_RUNS if args.quick else fullchecks.JITTER_RUNS)
    if n < 0:
        raise BenchError("--jitter-runs must be at least 0")
    return n


def _deskew_seconds(args: argparse.Namespace) -> float:
    sec = args.deskew_seconds if args.deskew_seconds is not None else (
        _deskew.QUICK_SECONDS if args.quick else _deskew.SECONDS)
    if not sec >= 5.0:
        raise BenchError("--deskew-seconds must be at least 5")
    return sec


def _run_only_line(args: argparse.Namespace, nav: Path, logs, work: Path, root: Path,
                   fault_names: Sequence[str]) -> Path:
    """--only capture, deskew or faults: the lines alone, printed and kept in
    WORK/only-NAME.json (the report is the whole bench's and is left as it is)."""
    t0 = time.monotonic()
    if args.only == "capture":
        res: dict = {"checks": []}
        for label, log, rel in logs:
            print(f"rsm-bench: {label}: the capture path beside the direct run and its jittered runs", flush=True)
            d = work / "capture-path"
            d.mkdir(parents=True, exist_ok=True)
            relations = fullchecks.ev.load_relations(rel)
            direct = d / f"{label}-direct.txt"
            fullchecks.run_nav(nav, ["--carmen", str(log)], direct)
            errs = fullchecks.ev.evaluate_scopes(fullchecks.ev.load_trajectory(direct), relations)
            res["checks"] += fullchecks.check_capture_path(label, nav, log, relations, errs, d, direct,
                                                           _jitter_runs(args), args.jobs)
        lines = [c["line"] for c in res["checks"]]
    elif args.only == "faults":
        runs = args.faults if args.faults is not None else (QUICK_FAULT_RUNS if args.quick else FAULT_RUNS)
        if runs < 1:
            raise BenchError("--only faults needs --faults of at least 1")
        print("rsm-bench: logs " + ", ".join(f"{l} ({shown_path(g, root)})" for l, g, _ in logs)
              + f"; faults only: {', '.join(fault_names)}, {runs} runs each"
              + (", rsm-nav --odom-lines" if args.odom_lines else ""), flush=True)
        res = run_faults(nav, logs, runs, work, args.jobs, names=fault_names, odom_lines=args.odom_lines)
        lines = report_faults(res) + [f["line"] for f in fault_floors(res)]
    else:
        res = _deskew.run(nav, work, _deskew_seconds(args))
        lines = _deskew.report(res) + [f["line"] for f in _deskew.floors(res)]
    res["provenance"] = provenance(root, (args.build_dir or root / "build-release").resolve())
    res["seconds"] = time.monotonic() - t0
    out = work / f"only-{args.only}.json"
    out.write_text(json.dumps(res, indent=1, default=_json_default, allow_nan=True))
    for line in lines:
        print(line)
    print(f"rsm-bench: {args.only} in {res['seconds']:.0f} s; wrote {out}")
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        run(args)
    except BenchError as exc:
        print(f"rsm-bench: error: {exc}", file=sys.stderr)
        return 1
    return 0

