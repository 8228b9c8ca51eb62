"""What every part of rsm-bench shares: the methods, levels and sections it knows, its error, number formats."""

import math
import os
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

from ..evaluate import LOCAL_SPAN  # noqa: F401 (the sections take it from here)


# rsm-nav --method names: rsm is the default method (scan to persistent map),
# paper the paper's (key points + RANSAC against a scrolling window).
METHODS = ("rsm", "paper", "icp", "odometry")


ROBUST_METHODS = ("rsm", "paper", "icp")  # the methods that read the scans


SMALL = "rsm-small"  # rsm built with SMALL_HEADER (a run label, not a method)


SMALL_HEADER = "rsm/config_small.h"


# The runs on a log, in the report's order (and under these names in
# figures.json): each method with the default build, and rsm with the small one.
RUNS = ("rsm", SMALL, "paper", "icp", "odometry")


def run_build(run: str) -> Tuple[str, str]:
    """A run's build ("default", or "small": SMALL_HEADER) and its rsm-nav --method."""
    return ("small", "rsm") if run == SMALL else ("default", run)


def measured_runs(methods: Sequence[str], small: bool) -> List[Tuple[str, str, str]]:
    """(run, build, method) of the runs a section makes: ``methods`` with the
    default build, then rsm with the small build when there is one."""
    return [(run, *run_build(run)) for run in (*methods, *((SMALL,) if small else ()))]


METHOD_LABEL = {"rsm": "rsm", SMALL: "rsm, config_small", "paper": "paper's method", "icp": "icp",
                "odometry": "odometry"}


LEVELS = (0, 10, 20, 30, 43, 50, 60)


QUICK_LEVELS = (0, 43)


OTHER_LEVELS = (0, 43, 60)  # every log but the main one: the floor's level and the peers' second one


QUICK_OTHER_LEVELS = (0, 43)


FIRST_SEED = 7  # the seed of the peers' outlier runs; further seeds count up from it


SEEDS = 2
# rsm's default map_update_m (src/localizer/localizer.c; test_bench checks they agree).
# The many-run sections vary it around this value: one run's result depends
# on where its writes fall, and a robot gets one run.
DEFAULT_MAP_UPDATE_M = 0.4


def update_sweep(count: int, step: float = 0.0125) -> List[float]:
    """map_update_m of the many-run sections: 0.75, 0.75 + step, ... times
    the default (count of them)."""
    return [round(DEFAULT_MAP_UPDATE_M * (0.75 + step * k), 4) for k in range(count)]

# The spread section: rsm once per map_update_m of 0.75, 0.7625, ... times
# the default (this many values, up to 1.24 times) on the clean logs, and at every
# other of them on the outlier copies of each of SPREAD_SEEDS seeds: which
# phantoms a seed draws moves the mean of its runs by more than a tenth,
# so the ratio is taken over many seeds, not many runs of two.
SPREAD_UPDATES = 40
QUICK_SPREAD_UPDATES = 4
SPREAD_SEEDS = 7


SPEED_REPEATS = 3


CALLGRIND_SCANS = 1000


SCOPES = ("local", "all")


QUANTITIES = ("translation", "rotation")


UNITS = {"translation": "m", "rotation": "deg"}


MAIN_LOG = "intel"  # the log the curve, turns, speed and the instruction floor use when present


SECTION_TITLES = (
    "1. Accuracy on the real logs",
    "2. Robustness to outliers",
    "3. Sharp turns (the paper's Fig. 8)",
    "4. Speed",
    "5. Memory",
    "6. Scaling",
    "7. The issue's floors",
    "8. Where rsm loses",
)


class BenchError(RuntimeError):
    """A stage of the bench could not run."""


def fmt_q(quantity: str, v: float) -> str:
    """A translation in m (4 decimals) or a rotation in degrees (3 decimals)."""
    if v is None or not math.isfinite(v):
        return "n/a"
    return f"{v:.4f}" if quantity == "translation" else f"{v:.3f}"


def fmt_ratio(v: float) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.2f}"


def fmt_pct(v: float) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.1f}"


def fmt_int(v: int) -> str:
    return f"{v:,}".replace(",", " ")


def ratio(a: float, b: float) -> float:
    if b is None or a is None or b == 0 or not (math.isfinite(a) and math.isfinite(b)):
        return float("nan")
    return a / b


def find_root(start: Optional[Path] = None) -> Path:
    """The repository root: the first folder upwards holding include/rsm/localizer.h."""
    for base in ((start or Path.cwd()).resolve(), Path(__file__).resolve().parent):
        for d in (base, *base.parents):
            if (d / "include" / "rsm" / "localizer.h").is_file():
                return d
    raise BenchError("cannot find the rsm repository root (include/rsm/localizer.h); use --root")


def shown_path(path: Path, root: Path) -> str:
    """How a path is written into the report: relative to the repository root
    when it is inside it or beside it (../shared), else only its file name."""
    try:
        rel = os.path.relpath(Path(path).resolve(), root)
    except ValueError:
        return Path(path).name
    if rel.startswith(os.pardir + os.sep + os.pardir) or os.path.isabs(rel):
        return Path(path).name
    return rel.replace(os.sep, "/")


PEER_COLUMNS = (("all", "translation"), ("all", "rotation"), ("local", "translation"), ("local", "rotation"))


# The parts of rsm_localizer_t in the report: (label, key of rsm-stages'
# "sizes", depth). Depth 0 parts tile the struct (the rest is the config
# pointer, stamps and padding); the methods' states share one union.
HOST_PARTS = (
    ("ekf", "ekf", 0),
    ("odo", "odo", 0),
    ("state (union of the three below)", "state", 0),
    ("state.persistent (rsm)", "state.persistent", 1),
    ("map.tile[] (tile pool)", "state.persistent.map.tile", 2),
    ("map.hash[] (tile index)", "state.persistent.map.hash", 2),
    ("state.paper (the paper's method)", "state.paper", 1),
    ("map (scrolling window)", "state.paper.map", 2),
    ("image", "state.paper.image", 2),
    ("ransac", "state.paper.ransac", 2),
    ("visited + harris + cands", "state.paper.harris", 2),
    ("key points and their points", "state.paper.keypoints", 2),
    ("matches", "state.paper.matches", 2),
    ("state.icp (icp)", "state.icp", 1),
    ("pts + world (the scan's points)", "points", 0),
    ("counters", "counters", 0),
    ("last report", "last", 0),
)


MEMORY_TILES = ("ekf", "odo", "state", "points", "counters", "last")


MEMORY_OTHER = ("rsm_localizer_config_t", "rsm_scan_t")


STAGES = ("points", "mapmatch", "grid", "harris", "match", "ransac", "refine", "icp", "ekf", "map")


STAGE_WHAT = {
    "points": "readings -> robot-frame points",
    "mapmatch": "coarse-to-fine alignment to the persistent map (rsm)",
    "grid": "map recentred, points -> scan image",
    "harris": "key points of scan and map",
    "match": "tentative matches",
    "ransac": "two-point RANSAC",
    "refine": "sub-cell alignment to the map",
    "icp": "ICP alignment (baseline)",
    "ekf": "measurement noise, gate, update",
    "map": "scan written into the map (rsm: every 0.4 m / 0.5 rad)",
}


TIMING_STATS = ("mean_us", "median_us", "p95_us", "max_us", "median_reached_us", "p95_reached_us")


CG_STAGE_ORDER = ("points", "mapmatch", "grid", "grid + map", "harris", "match", "ransac", "refine", "icp", "ekf",
                  "map", "other", "localizer")


TURNS = 12


TURN_SEPARATION_SCANS = 25


ROTATION_BINS = (0.0, 2.0, 5.0, 10.0, 20.0, 30.0)  # degrees; the last bin is open


def bin_label(k: int) -> str:
    lo = ROTATION_BINS[k]
    return f">= {lo:g}" if k == len(ROTATION_BINS) - 1 else f"{lo:g}-{ROTATION_BINS[k + 1]:g}"


# (name, RSM_USER_CONFIG on the library's include path; None: config.h's defaults)
ARM_CONFIGS = (("default", None), ("small", SMALL_HEADER))


ARM_CPU = ("-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard")


# Caller-owned state per module: (module, label, C expression); the localizer's
# parts are members of rsm_localizer_t, which also holds the reports. Labels
# indented by two spaces are parts of the localizer, by four parts of a part.
STATE_SIZES = (
    ("localizer.c", "rsm_localizer_t (all of the below)", "sizeof(rsm_localizer_t)"),
    ("ekf.c", "  ekf", "sizeof(((rsm_localizer_t *)0)->ekf)"),
    ("odometry.c", "  odo", "sizeof(((rsm_localizer_t *)0)->odo)"),
    ("localizer.c", "  state (union: one method's state)", "sizeof(((rsm_localizer_t *)0)->state)"),
    ("tilemap.c", "    state.persistent (rsm)", "sizeof(((rsm_localizer_t *)0)->state.persistent)"),
    ("tilemap.c", "      map.tile[] (tile pool)", "sizeof(((rsm_localizer_t *)0)->state.persistent.map.tile)"),
    ("tilemap.c", "      map.hash[] (tile index)", "sizeof(((rsm_localizer_t *)0)->state.persistent.map.hash)"),
    ("map.c", "    state.paper (the paper's method)", "sizeof(((rsm_localizer_t *)0)->state.paper)"),
    ("map.c", "      map (scrolling window)", "sizeof(((rsm_localizer_t *)0)->state.paper.map)"),
    ("grid.c", "      image", "sizeof(((rsm_localizer_t *)0)->state.paper.image)"),
    ("ransac.c", "      ransac", "sizeof(((rsm_localizer_t *)0)->state.paper.ransac)"),
    ("harris.c", "      visited + harris + cands",
     "sizeof(((rsm_localizer_t *)0)->state.paper.visited) + sizeof(((rsm_localizer_t *)0)->state.paper.harris)"
     " + sizeof(((rsm_localizer_t *)0)->state.paper.cands)"),
    ("match.c", "      key points and matches",
     "sizeof(((rsm_localizer_t *)0)->state.paper.kp_cur) * 2 + sizeof(((rsm_localizer_t *)0)->state.paper.pt_cur) * 2"
     " + sizeof(((rsm_localizer_t *)0)->state.paper.matches)"),
    ("icp.c", "    state.icp (icp)", "sizeof(((rsm_localizer_t *)0)->state.icp)"),
    ("scan.c", "  points (robot and world frame)", "sizeof(((rsm_localizer_t *)0)->pts) * 2"),
    ("localizer.c", "rsm_localizer_config_t", "sizeof(rsm_localizer_config_t)"),
    ("scan.c", "rsm_scan_t (one scan buffer)", "sizeof(rsm_scan_t)"),
    ("p3dx.c", "rsm_p3dx_t", "sizeof(rsm_p3dx_t)"),
    ("p3dx.c", "rsm_p3dx_config_t", "sizeof(rsm_p3dx_config_t)"),
    ("sicklms.c", "rsm_sicklms_t", "sizeof(rsm_sicklms_t)"),
    ("sicklms.c", "rsm_sicklms_config_t", "sizeof(rsm_sicklms_config_t)"),
    ("sync.c", "rsm_sync_t (odometry/scan aligner, holds one scan)", "sizeof(rsm_sync_t)"),
)


# Entry points whose stack the report bounds (those the library has).
# The functions behind the macros that pass the caller's capacities
# (rsm_localizer_scan -> rsm_localizer_scan_checked): what a profiler or a
# call graph sees; the report keeps the names the API gives.
CHECKED = "_checked"
SCAN_SYMBOL = "rsm_localizer_scan" + CHECKED
STACK_ROOTS = ("rsm_localizer_scan", "rsm_localizer_motion", "rsm_sync_scan", "rsm_sync_encoder", "rsm_sync_poll")


# Callbacks the core calls through a pointer (for the static stack bound).
INDIRECT_TARGETS = {"rsm_harris_detect": ("patch_map", "rsm_harris_patch_image")}


# The images the bench runs under QEMU: the example, the replay (instructions per scan) and the
# map-in-flash firmware (the global search's instructions per scan, the section "Known map").
M4_TARGETS = ("rsm_firmware", "rsm_replay_m4", "rsm_mapflash_m4")


SCALING_BEAMS = (181, 361, 721)


SCALING_MAP_LOG2 = (6, 7, 8)


SCALING_TILES = (600, 1200, 2600)


DEFAULT_MAX_BEAMS = 361


DEFAULT_MAP_LOG2 = 7


DEFAULT_TILES = 2600


# Shipped configuration presets (include paths) run as they are.
SCALING_PRESETS = (SMALL_HEADER, "rsm/config_host.h")


# The methods a kind of variant concerns: the window sizes only the paper's
# method, the tile pool only rsm's.
KIND_METHODS = {"beams": ROBUST_METHODS, "map": ("paper",), "tiles": ("rsm",), "preset": ("rsm", "paper")}


DRIVER_OBJECTS = ("aria", "lms", "p3dx", "sicklms", "hal", "link_poll")


def floor(status: str, kind: str, log: Optional[str], value, limit, text: str) -> dict:
    """One of the issue's floors (or a full-log check): PASS, MISS or SKIP,
    the measure (``kind``, ``log``, ``value`` against ``limit``) for the
    manifest, and the line the report and rsm-bench print."""
    return {"status": status, "kind": kind, "log": log, "value": value, "limit": limit, "line": f"{status} {text}"}


def cg_run(cg: Optional[dict], label: str, config: str, method: str) -> Optional[dict]:
    """One callgrind run of run_callgrind's result, or None."""
    if not cg or "skipped" in cg:
        return None
    return cg["runs"].get(f"{label}:{config}:{method}")


def run_labels(acc_log: dict) -> List[str]:
    """The runs of one log in report order."""
    return [k for k in RUNS if k in acc_log["runs"]]


def provenance_line(p: dict) -> str:
    flags = f", `{p['build_flags']}`" if p["build_flags"] else ""
    return (f"Measured {p['date']} on {p['cpu']} ({p['cores']} cores), {p['compiler']}, "
            f"{p['build_type']} build{flags}, commit `{p['commit']}`.")
