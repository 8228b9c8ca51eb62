"""The bench's section "Known map": rsm on a map it saved (issue 31), every log, the default configuration.

For every log:

1. *Round trip*: the whole log with ``rsm-nav --save-map`` (the pool's map
   alone, the default memory); then the whole log again with ``--load-map
   MAP --freeze-map --save-map AGAIN``: the tiles of AGAIN (every byte between the 48-byte
   header and the 4-byte CRC, docs/mapfile.md) must be those of MAP, and a
   frozen run on AGAIN must write the same trajectory as the one on MAP
   (the header differs: it holds the pose and the fit at the save). The
   saved size and tiles are shown beside the map's part of the localizer
   state (rsm-stages' ``sizeof``).
   Then the whole log mapped again with a tile store behind the pool
   (``--tile-store STORE_TILES``, rsm/tilestore.h), so that the saved map
   holds the whole building (the mapping run): every run below loads it with
   such a store.
2. *Localization mode*: the whole log on the saved map, frozen
   (``--freeze-map``) and with updates (``--load-map`` alone), from the log's
   first pose as the mapping run; the error of the bench
   (:mod:`rsm_tools.evaluate`, all relations and local ones, exact stamps)
   beside the mapping run's. Floor: at or below the mapping run's.
3. *Global localization*: ``starts`` starts spread evenly over the log (start
   k at k/starts of its span), each ``--load-map MAP --freeze-map --global
   --skip-seconds S --scans CAP``: no start pose, the log resumed at S, at
   most CAP scans. The first trusted pose (the trajectory's first line) is
   compared with the mapping run's pose at the same stamp: *right* within
   RIGHT_M and RIGHT_DEG, *wrong* beyond WRONG_M or WRONG_DEG, else *between*;
   *none* when no pose came within the CAP scans. Scans to it
   (``first_trusted_scan``), the map cells the search read in all
   (``work``) and in one scan (``max_work_per_scan``) come from rsm-nav's
   summary. A start whose surroundings the saved map does not hold (the pool
   evicted them) is counted apart: see HELD_NOTE.
4. *Kidnapping*: ``kidnaps`` runs per log (default KIDNAP_RUNS), run k on a
   copy of the log with one kidnap (:mod:`rsm_tools.faults`, ``--kidnap
   S:KIDNAP_S``: the scans of KIDNAP_S seconds removed, the odometry made to
   report no motion across the cut) at (k + 0.5)/kidnaps of the span that
   leaves room for it and KIDNAP_TAIL_S seconds after it; each run the whole
   copy on MAP with ``--set global_when_lost=1``, frozen and with updates
   (KIDNAP_MODES). A run is judged from the first scan after the cut (scan
   1) to its end, see KIDNAP_NOTE: the scans to the first trusted pose that
   is right, and the trusted poses that are wrong. Beside them, not a floor:
   the same judge on a run of the log without a kidnap (the control, one per
   log and mode), from the same scans, which says what the judge makes of a
   run the kidnap did not disturb (on ACES the mapping run's pose is no
   exact reference: docs/globalsearch.md).

The floors (issue 31): the round trip bit for bit; localization mode at or
below the mapping run's all-relations error, frozen and with updates; at
least FLOOR_RIGHT_SHARE of the held starts right within WITHIN_SCANS scans;
no start wrong; after every kidnap, in both modes, a trusted right pose
within WITHIN_SCANS scans and no trusted wrong one. The issue's cost floor,
at most FLOOR_GLOBAL_M4 instructions per scan of the global search on the
M4, is judged twice: the bench's m4 stage runs the map-in-flash firmware
under QEMU, whose global search in the excerpt's small map, at the default
global_budget, is timed scan by scan (:func:`rsm_tools.m4.mapflash_run`;
one line); and, after it, the same firmware searches each log's saved pool
map from M4_REAL_STARTS (:func:`run_m4_real`, rsm_tools.m4cost), beside
the replay firmware on each log's first scans, whose costliest scan a
tracking recovery took is issue 29's floor. SKIP lines where the stages did not
run, as with ``--only knownmap``.
"""

import math
import os
import statistics
import struct
import subprocess
import time
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

from .. import evaluate as ev
from .. import faults as flt
from .. import m4cost
from .common import BenchError, LOCAL_SPAN, floor, fmt_int, fmt_q, provenance_line, ratio

STARTS = 100          # global starts per log
QUICK_STARTS = 10
START_SCANS = 400     # scans a global start runs at most (CAP)
RIGHT_M = 0.1
RIGHT_DEG = 2.0
WRONG_M = 0.5
WRONG_DEG = 5.0
WITHIN_SCANS = 20     # the first trusted pose within this many scans
# The near starts: the mapping run's pose at the start made this wrong
# (0.5 m, 0.3 rad), then `--global-near NEAR_RADIUS_M` from there: a robot
# switched on where it was switched off, or one whose estimate is near.
NEAR_OFFSET = (0.4, -0.3, 0.3)
NEAR_RADIUS_M = 1.0
FLOOR_RIGHT_SHARE = 0.95  # of the held starts: 95 of 100
HELD_FIT = 0.8        # a start's first scan's fit_ratio on the saved map from the right pose, at least
REF_TOLERANCE = 0.1   # s: the mapping run's pose at a stamp it lacks exactly, the nearest within this
HEADER_BYTES = 48
CRC_BYTES = 4
MARK = "known map"    # every floor line of the section holds ": known map, " (the report's splice finds them)
# The map the section localizes in is kept whole by a tile store behind the
# pool (rsm/tilestore.h): what the pool lets go goes there, and comes back
# where the robot is. In rsm-nav it is memory (40 bytes a tile); on a robot,
# flash or external RAM. The round trip is of the pool's map alone.
STORE_TILES = 65536
STORE = ("--tile-store", str(STORE_TILES))
FLOOR_GLOBAL_M4 = 1000000  # instructions per scan of the global search on the M4, at most (issue 31)
ONLY_M4 = ("--only knownmap runs no firmware image: the whole bench measures it in its m4 stage, on the "
           "map-in-flash firmware")

HELD_NOTE = (f"a start's surroundings count as held by the saved map when rsm-nav, started in localization mode on "
             f"it from the mapping run's pose at the start's first scan (`--load-map MAP --freeze-map --initial-pose "
             f"POSE --skip-seconds S --scans 1 --scan-log`), gives that scan a fit_ratio (its fit over the fit saved "
             f"with the map) of at least {HELD_FIT:g}; below, the saved map does not hold the place as the mapping run "
             f"then saw it (it holds an older version of it, placed elsewhere) and the start is counted apart")

VERDICTS = ("right", "between", "wrong", "none", "no reference")

KIDNAP_RUNS = 20      # kidnaps per log (one per run)
QUICK_KIDNAP_RUNS = 2
KIDNAP_S = 60.0       # the cut: seconds of log the robot is carried through
KIDNAP_TAIL_S = 30.0  # seconds of log after the cut, at least
# (mode, rsm-nav options beside --load-map MAP --set global_when_lost=1)
KIDNAP_MODES = (("frozen", ("--freeze-map",)), ("updates", ()))
KIDNAP_NOTE = (f"a run is judged from the first scan after the cut (scan 1) to its end, at every scan with a "
               f"trajectory line and a mapping-run pose at its stamp (exact): a scan is trusted when rsm-nav's "
               f"scan log says `tracking`; the run is found again at its first trusted scan within {RIGHT_M:g} m and "
               f"{RIGHT_DEG:g} deg of the mapping run's pose; a trusted scan more than {WRONG_M:g} m or "
               f"{WRONG_DEG:g} deg off is wrong, wherever it comes")
# Where the mapping run is no reference (on ACES its pose early in the log is
# about a metre off the map it ended with), the same run on the log without
# the kidnap says where localization on that map puts the robot.
KIDNAP_CONTROL_NOTE = (f"a trusted scan off the mapping run's pose but within {RIGHT_M:g} m and {RIGHT_DEG:g} deg of "
                       "the run of the same mode on the log without a kidnap, which tracked there too, is where "
                       "localization on that map puts the robot, kidnap or not: it counts as found again, and apart "
                       "from the wrong ones (the mapping run's pose is off there)")


# ---------------------------------------------------------------------------
# pure parts (the tests' subject)


def start_offsets(span_s: float, n: int) -> List[float]:
    """--skip-seconds of n starts spread evenly over a log of span_s seconds:
    k span/n for k = 0..n-1 (ms resolution)."""
    return [round(k * span_s / n, 3) for k in range(n)] if n > 0 and span_s > 0 else []


def map_tiles(data: bytes) -> bytes:
    """The tiles of a saved map: everything between the header and the CRC."""
    if len(data) < HEADER_BYTES + CRC_BYTES or data[:4] != b"RSMM":
        raise BenchError(f"not a saved map ({len(data)} bytes)")
    return data[HEADER_BYTES:len(data) - CRC_BYTES]


def map_fit(data: bytes) -> float:
    """The header's fit at the save (offset 44, little-endian single)."""
    map_tiles(data)
    return struct.unpack("<f", data[44:48])[0]


def map_tile_count(data: bytes) -> int:
    """The header's tile count (offset 24, little-endian)."""
    map_tiles(data)
    return int.from_bytes(data[24:28], "little")


def pose_error(est: Sequence[float], ref: Sequence[float]) -> Tuple[float, float]:
    """(distance in m, |heading difference| in deg) of two (x, y, theta) poses."""
    return (math.hypot(est[0] - ref[0], est[1] - ref[1]),
            abs(math.degrees(ev.wrap_angle(est[2] - ref[2]))))


def verdict(est: Optional[Sequence[float]], ref: Optional[Sequence[float]]) -> str:
    """right, wrong, between (see the module's docstring), none (no pose) or
    no reference (the mapping run has no pose at that stamp)."""
    if est is None:
        return "none"
    if ref is None:
        return "no reference"
    m, deg = pose_error(est, ref)
    if m <= RIGHT_M and deg <= RIGHT_DEG:
        return "right"
    if m > WRONG_M or deg > WRONG_DEG:
        return "wrong"
    return "between"


def first_pose(traj: Path) -> Optional[Tuple[float, float, float, float]]:
    """The first line of a trajectory (stamp, x, y, theta), or None."""
    rows, _ = ev.read_poses(traj)
    return tuple(rows[0]) if rows else None


def first_scan(scan_log: Path) -> Optional[Tuple[float, str, Optional[float]]]:
    """(stamp, outcome, fit_ratio) of the first line of rsm-nav --scan-log
    (stamp outcome tracking odometry recovered fit_ratio), or None."""
    for line in Path(scan_log).read_text().splitlines():
        f = line.split()
        if not f or line.startswith("#"):
            continue
        return float(f[0]), f[1], (float(f[5]) if len(f) >= 6 else None)
    return None


def held(fit_ratio: Optional[float]) -> Optional[bool]:
    """Whether the saved map holds a start's surroundings (HELD_NOTE); None: not judged."""
    if fit_ratio is None or not math.isfinite(fit_ratio):
        return None
    return fit_ratio >= HELD_FIT


def judge_start(found: Optional[Sequence[float]], ref: Optional[Sequence[float]], summary: dict,
                fit_ratio: Optional[float]) -> dict:
    """One start's entry: found is the first trajectory line (stamp, x, y,
    theta) or None, ref the mapping run's (x, y, theta) at its stamp, summary
    rsm-nav's JSON summary of the global run, fit_ratio the held check's."""
    g = summary.get("global") or {}
    v = verdict(found[1:] if found else None, ref)
    out = {"verdict": v, "held": held(fit_ratio), "fit_ratio": fit_ratio,
           "scans": summary.get("scans"), "searches": g.get("searches"), "work": g.get("work"),
           "max_work_per_scan": g.get("max_work_per_scan"),
           "first_trusted_scan": (g.get("first_trusted_scan") or None) if found else None,
           "stamp": found[0] if found else None, "pose": list(found[1:]) if found else None,
           "ref": list(ref) if ref is not None else None, "error_m": None, "error_deg": None}
    if found and ref is not None:
        out["error_m"], out["error_deg"] = pose_error(found[1:], ref)
    return out


def _stat(values: Sequence[Optional[float]]) -> dict:
    vals = sorted(v for v in values if v is not None)
    if not vals:
        return {"n": 0, "median": None, "max": None}
    return {"n": len(vals), "median": statistics.median(vals), "max": vals[-1]}


def aggregate(starts: Sequence[dict], within: int = WITHIN_SCANS) -> dict:
    """The figures of one log's starts: how many ran, were held (a start not
    judged counts as held), right, right within ``within`` scans, between,
    wrong, none; wrong among all starts, held or not; scans to the first
    pose of the held starts that gave one; work in all and in one scan."""
    kept = [s for s in starts if s["held"] is not False]
    count = {v: sum(1 for s in kept if s["verdict"] == v) for v in VERDICTS}
    found = [s for s in kept if s["verdict"] not in ("none",)]
    right_within = sum(1 for s in kept if s["verdict"] == "right" and s["first_trusted_scan"] is not None
                       and s["first_trusted_scan"] <= within)
    return {"starts": len(starts), "held": len(kept), "not_held": len(starts) - len(kept),
            "not_judged": sum(1 for s in starts if s["held"] is None),
            "counts": count, "right_within": right_within, "within": within,
            "none_log_ended": sum(1 for s in kept if s["verdict"] == "none" and s["scans"] is not None
                                  and s.get("cap") is not None and s["scans"] < s["cap"]),
            "wrong_all": sum(1 for s in starts if s["verdict"] == "wrong"),
            "wrong_not_held": sum(1 for s in starts if s["verdict"] == "wrong" and s["held"] is False),
            "found_not_held": sum(1 for s in starts if s["verdict"] != "none" and s["held"] is False),
            "scans_to_pose": _stat([s["first_trusted_scan"] for s in found]),
            "work": _stat([s["work"] for s in starts]),
            "work_to_pose": _stat([s["work"] for s in found]),
            "max_work_per_scan": _stat([s["max_work_per_scan"] for s in starts]),
            "searches": sum(s["searches"] or 0 for s in starts),
            "scans_run": _stat([s["scans"] for s in starts])}


def right_needed(held_starts: int) -> int:
    """Right starts the floor asks of ``held_starts`` held ones (95 of 100)."""
    return math.ceil(FLOOR_RIGHT_SHARE * held_starts - 1e-9)


def kidnap_offsets(span_s: float, n: int, length: float = KIDNAP_S, tail: float = KIDNAP_TAIL_S) -> List[float]:
    """S (seconds after the first scan) of n kidnaps of ``length`` s: kidnap k
    at (k + 0.5)/n of the span that leaves room for the cut and ``tail`` s of
    log after it (ms resolution); none when the log is too short."""
    room = span_s - length - tail
    if n <= 0 or room <= 0:
        return []
    return [round((k + 0.5) * room / n, 3) for k in range(n)]


def read_scan_log(path: Path) -> List[Tuple[float, str, str]]:
    """(stamp, outcome, tracking) of every line of rsm-nav --scan-log, in order."""
    rows = []
    for line in Path(path).read_text().splitlines():
        f = line.split()
        if len(f) >= 3 and not line.startswith("#"):
            rows.append((float(f[0]), f[1], f[2]))
    return rows


def judge_kidnap(rows: Sequence[Tuple[float, str, str]], traj: ev.Trajectory, ref: ev.Trajectory,
                 cut_stamp: float,
                 control: Optional[Tuple[Sequence[Tuple[float, str, str]], ev.Trajectory]] = None) -> dict:
    """One kidnap run (KIDNAP_NOTE): ``rows`` its scan log, ``traj`` its
    trajectory, ``ref`` the mapping run's, ``cut_stamp`` the stamp of the
    first scan after the cut. Scans are counted from that scan, which is 1.
    found: the first trusted right scan (None: never); wrong: the trusted
    wrong scans after the cut, first_wrong the first of them; first_trusted,
    first_lost: the first scan trusted, reported lost; before: the last
    judged scan before the cut (tracking state and verdict), whether the run
    was right when the robot was carried off. With ``control`` (the scan
    log and trajectory of the same run on the log without a kidnap), a
    trusted scan that is wrong against the mapping run but right against
    the control there is the reference's, not the run's
    (KIDNAP_CONTROL_NOTE): counted in
    as_control, not in wrong; such a scan also finds the run again. The
    control must track at that scan (it may have been lost before: two
    runs that agree there, one carried off and one not, agree on where
    localization on that map puts the robot)."""
    out = {"cut_seen": False, "after": 0, "judged": 0, "found": None, "first_trusted": None, "first_lost": None,
           "wrong": 0, "first_wrong": None, "first_wrong_error": None, "wrong_before_found": 0,
           "no_reference": 0, "before": None, "as_control": 0, "found_as_control": False}
    c_rows = {ev.time_key(r[0]): r[2] for r in control[0]} if control is not None else {}

    def as_control(stamp: float, est) -> bool:
        """The run is where the unkidnapped run, tracking there, was."""
        if control is None or c_rows.get(ev.time_key(stamp)) != "tracking":
            return False
        c = control[1].lookup(stamp, 0.0)
        return c is not None and verdict(est, c) == "right"

    key = ev.time_key(cut_stamp)
    i0 = next((i for i, r in enumerate(rows) if ev.time_key(r[0]) == key), None)
    if i0 is None:
        return out
    out["cut_seen"] = True
    out["after"] = len(rows) - i0
    for stamp, _, tracking in reversed(rows[:i0]):
        est, r = traj.lookup(stamp, 0.0), ref.lookup(stamp, 0.0)
        if est is not None and r is not None:
            out["before"] = {"tracking": tracking, "verdict": verdict(est, r)}
            break
    for j, (stamp, _, tracking) in enumerate(rows[i0:], start=1):
        trusted = tracking == "tracking"
        if tracking == "lost" and out["first_lost"] is None:
            out["first_lost"] = j
        est = traj.lookup(stamp, 0.0)
        if est is None:
            continue  # a search under way writes no pose
        if trusted and out["first_trusted"] is None:
            out["first_trusted"] = j
        r = ref.lookup(stamp, 0.0)
        if r is None:
            out["no_reference"] += 1
            continue
        out["judged"] += 1
        if not trusted:
            continue
        v = verdict(est, r)
        if v != "right" and as_control(stamp, est):
            if v == "wrong":
                out["as_control"] += 1
            if out["found"] is None:
                out["found"] = j
                out["found_as_control"] = True
            continue
        if v == "right" and out["found"] is None:
            out["found"] = j
        elif v == "wrong":
            out["wrong"] += 1
            if out["found"] is None:
                out["wrong_before_found"] += 1
            if out["first_wrong"] is None:
                out["first_wrong"] = j
                out["first_wrong_error"] = list(pose_error(est, r))
    return out


def _stat_never(values: Sequence[Optional[int]]) -> dict:
    """Median and worst of scan counts where None is never (counted as
    infinitely many): either is None when it falls on a never."""
    vals = sorted(math.inf if v is None else v for v in values)
    if not vals:
        return {"n": 0, "median": None, "max": None}
    med, top = statistics.median(vals), vals[-1]
    return {"n": len(vals), "median": None if math.isinf(med) else med, "max": None if math.isinf(top) else top}


def aggregate_kidnaps(runs: Sequence[dict], within: int = WITHIN_SCANS) -> dict:
    """The figures of one log's kidnap runs in one mode: found again within
    ``within`` scans, at all, never; scans to found (median, worst; None:
    never); runs with a wrong trusted pose and those scans; runs reported
    lost after the cut; runs right before the cut; the global searches."""
    found = [r["found"] for r in runs]
    return {"runs": len(runs), "within": within,
            "found_within": sum(1 for v in found if v is not None and v <= within),
            "found": sum(1 for v in found if v is not None), "never": sum(1 for v in found if v is None),
            "scans_to_found": _stat_never(found),
            "wrong_runs": sum(1 for r in runs if r["wrong"]), "wrong_scans": sum(r["wrong"] for r in runs),
            "as_control_runs": sum(1 for r in runs if r.get("as_control")),
            "as_control_scans": sum(r.get("as_control") or 0 for r in runs),
            "found_as_control": sum(1 for r in runs if r.get("found_as_control")),
            "first_wrong": _stat([r["first_wrong"] for r in runs]),
            "earliest_wrong": min((r["first_wrong"] for r in runs if r["first_wrong"] is not None), default=None),
            "lost_runs": sum(1 for r in runs if r["first_lost"] is not None),
            "first_lost": _stat([r["first_lost"] for r in runs]),
            "not_seen": sum(1 for r in runs if not r["cut_seen"]),
            "right_before": sum(1 for r in runs if (r.get("before") or {}).get("verdict") == "right"),
            "searches": sum(r.get("searches") or 0 for r in runs),
            "searches_found": sum(r.get("searches_found") or 0 for r in runs),
            "control_runs": sum(1 for r in runs if r.get("control")),
            "control_found_within": sum(1 for r in runs if r.get("control") and r["control"]["found"] is not None
                                        and r["control"]["found"] <= within),
            "control_wrong_runs": sum(1 for r in runs if r.get("control") and r["control"]["wrong"])}


# ---------------------------------------------------------------------------
# measuring


def _nav(nav: Path, log: Path, traj: Path, extra: Sequence[str], no_pose_ok: bool = False) -> dict:
    """rsm-nav --carmen LOG (the default method) with a JSON summary beside
    the trajectory; a --global run that proved no pose exits 1 and is taken
    when no_pose_ok. Returns the parsed summary, and the process' wall time."""
    from .parse import load_summary

    traj.parent.mkdir(parents=True, exist_ok=True)
    summary = traj.with_suffix(".summary.json")
    cmd = [str(nav), "--carmen", str(log), "--method", "rsm", "--trajectory", str(traj),
           "--summary-json", str(summary), "--quiet", *extra]
    t0 = time.monotonic()
    res = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.monotonic() - t0
    if res.returncode != 0 and not (no_pose_ok and res.returncode == 1 and "no pose" in res.stderr
                                    and summary.is_file()):
        raise BenchError(f"{' '.join(cmd)} failed ({res.returncode}):\n{res.stderr}")
    out = load_summary(summary)
    out["seconds"] = seconds
    return out


def _errors(traj: Path, relations) -> dict:
    s = ev.evaluate_scopes(ev.load_trajectory(traj), relations)
    a, l_ = s["all"], s["local"]
    return {"all": a["translation"]["mean"], "all_rotation": a["rotation"]["mean"],
            "local": l_["translation"]["mean"], "local_rotation": l_["rotation"]["mean"], "matched": a["matched"]}


def _data_lines(traj: Path) -> List[str]:
    return [line for line in Path(traj).read_text().splitlines() if line.strip() and not line.startswith("#")]


def map_state_bytes(stages: Optional[Path], log: Path) -> Optional[dict]:
    """The map's part of the localizer state on this host (rsm-stages' sizes), or None without rsm-stages."""
    if stages is None or not Path(stages).is_file():
        return None
    from .measure import run_stages
    s = run_stages(stages, log, "rsm", ["--limit", "1", "--clock", "none"])["sizes"]
    return {k: s.get(k) for k in ("state.persistent", "state.persistent.map", "state.persistent.map.tile",
                                  "state.persistent.map.hash")}


def run_knownmap(nav: Path, logs: Sequence[Tuple[str, Path, Path]], work: Path, jobs: int,
                 starts: int = STARTS, cap: int = START_SCANS, stages: Optional[Path] = None,
                 kidnaps: int = KIDNAP_RUNS) -> dict:
    """The section on every log (see the module's docstring); returns its
    manifest entry. ``jobs`` rsm-nav processes at a time; ``kidnaps`` 0
    skips the kidnapping part."""
    from .measure import parallel

    t_start = time.monotonic()
    d = work / "knownmap"

    def mapping(task):
        label, log, rel = task
        o = d / label
        m, again = o / "map.rsmm", o / "map-again.rsmm"
        for f in (m, again):
            if f.exists():
                f.unlink()
        pool = o / "map-pool.rsmm"
        if pool.exists():
            pool.unlink()
        # the round trip: the map of the pool alone (the default memory)
        s_pool = _nav(nav, log, o / "mapping-pool.txt", ["--save-map", str(pool)])
        s_rt = _nav(nav, log, o / "roundtrip.txt", ["--load-map", str(pool), "--freeze-map", "--save-map",
                                                    str(again)])
        _nav(nav, log, o / "roundtrip-again.txt", ["--load-map", str(again), "--freeze-map"])
        # the rest on the map of the pool and its store: the whole building
        s_map = _nav(nav, log, o / "mapping.txt", [*STORE, "--save-map", str(m)])
        s_frozen = _nav(nav, log, o / "frozen.txt", [*STORE, "--load-map", str(m), "--freeze-map"])
        s_upd = _nav(nav, log, o / "updates.txt", [*STORE, "--load-map", str(m)])
        return task, s_pool, s_rt, s_map, s_frozen, s_upd

    out = {"starts": starts, "cap": cap, "jobs": jobs, "within": WITHIN_SCANS, "right_m": RIGHT_M,
           "right_deg": RIGHT_DEG, "wrong_m": WRONG_M, "wrong_deg": WRONG_DEG, "held_fit": HELD_FIT,
           "held_note": HELD_NOTE, "share": FLOOR_RIGHT_SHARE, "logs": {}}
    maps = parallel(mapping, list(logs), jobs)
    tasks = []
    for (label, log, rel), s_pool, s_rt, s_map, s_frozen, s_upd in maps:
        o = d / label

        def figures(name: str, summary: dict) -> dict:
            return {**_errors(o / f"{name}.txt", relations), "writes": (summary["tmap"] or {}).get("writes"),
                    "fit": summary.get("fit"), "seconds": summary["seconds"]}

        relations = ev.load_relations(rel)
        data, again = (o / "map-pool.rsmm").read_bytes(), (o / "map-again.rsmm").read_bytes()
        stored = (o / "map.rsmm").read_bytes()
        traj = ev.read_poses(o / "mapping.txt")[0]
        span = traj[-1].t - traj[0].t if traj else 0.0
        entry = {
            "log": str(log), "scans": s_map["scans"], "span_s": span,
            "round_trip": {"bytes": len(data), "tiles": map_tile_count(data), "bytes_again": len(again),
                           "tiles_again": map_tile_count(again), "identical": map_tiles(data) == map_tiles(again),
                           "header_identical": data[:HEADER_BYTES] == again[:HEADER_BYTES],
                           "trajectory_same": (_data_lines(o / "roundtrip.txt")
                                               == _data_lines(o / "roundtrip-again.txt")),
                           "loaded": s_rt.get("loaded_map"), "fit": map_fit(data), "fit_again": map_fit(again)},
            "stored_map": {"bytes": len(stored), "tiles": map_tile_count(stored), "store_tiles": STORE_TILES,
                           "held_in_store": (s_map["tmap"] or {}).get("store_tiles"),
                           "let_go": (s_map["tmap"] or {}).get("stored"),
                           "taken_back": (s_map["tmap"] or {}).get("fetched"),
                           "taken_back_frozen": (s_frozen["tmap"] or {}).get("fetched")},
            "state": map_state_bytes(stages, log),
            "runs": {"pool": figures("mapping-pool", s_pool), "mapping": figures("mapping", s_map),
                     "frozen": figures("frozen", s_frozen),
                     "updates": figures("updates", s_upd)},
            "offsets": start_offsets(span, starts)}
        out["logs"][label] = entry
        tasks += [(label, log, k, s) for k, s in enumerate(entry["offsets"])]
    refs = {label: ev.load_trajectory(d / label / "mapping.txt") for label in out["logs"]}

    def one(task):
        label, log, k, s = task
        o = d / label / "starts"
        m = str(d / label / "map.rsmm")
        g_traj, g_scans = o / f"global-{k}.txt", o / f"global-{k}.scans"
        summ = _nav(nav, log, g_traj, [*STORE, "--load-map", m, "--freeze-map", "--global", "--skip-seconds",
                                       f"{s:.3f}",
                                       "--scans", str(cap), "--scan-log", str(g_scans)], no_pose_ok=True)
        found = first_pose(g_traj)
        ref = None
        if found is not None:
            ref = refs[label].lookup(found[0], tolerance=REF_TOLERANCE)
        # the held check: the first scan from the mapping run's pose there
        fit = None
        first = first_scan(g_scans)
        start_ref = refs[label].lookup(first[0], tolerance=REF_TOLERANCE) if first else None
        if start_ref is not None:
            h_traj, h_scans = o / f"held-{k}.txt", o / f"held-{k}.scans"
            _nav(nav, log, h_traj, [*STORE, "--load-map", m, "--freeze-map", "--initial-pose",
                                    *(f"{v:.6f}" for v in start_ref), "--skip-seconds", f"{s:.3f}", "--scans", "1",
                                    "--scan-log", str(h_scans)])
            h = first_scan(h_scans)
            if h is not None and abs(h[0] - first[0]) < 1e-6:
                fit = h[2]
        e = judge_start(found, ref, summ, fit)
        e.update({"k": k, "skip_s": s, "cap": cap, "first_stamp": first[0] if first else None,
                  "seconds": summ["seconds"]})
        if start_ref is not None:
            n_traj = o / f"near-{k}.txt"
            rough = [v + dv for v, dv in zip(start_ref, NEAR_OFFSET)]
            n_summ = _nav(nav, log, n_traj, [*STORE, "--load-map", m, "--freeze-map", "--global-near",
                                             f"{NEAR_RADIUS_M:g}",
                                             "--initial-pose", *(f"{v:.6f}" for v in rough), "--skip-seconds",
                                             f"{s:.3f}", "--scans", str(cap)], no_pose_ok=True)
            n_found = first_pose(n_traj)
            n_ref = refs[label].lookup(n_found[0], tolerance=REF_TOLERANCE) if n_found is not None else None
            e["near"] = judge_start(n_found, n_ref, n_summ, fit)
            e["near"]["cap"] = cap
        return task, e

    done = parallel(one, tasks, jobs)
    for label, entry in out["logs"].items():
        entry["starts"] = sorted((e for (lab, _, _, _), e in done if lab == label), key=lambda e: e["k"])
        entry["summary"] = aggregate(entry["starts"])
        entry["summary_near"] = aggregate([e["near"] for e in entry["starts"] if "near" in e])
    out["kidnap"] = (run_kidnaps(nav, logs, d, jobs, kidnaps, refs) if kidnaps > 0
                     else {"skipped": "--kidnap-runs 0"})
    out["seconds"] = time.monotonic() - t_start
    return out


def run_kidnaps(nav: Path, logs: Sequence[Tuple[str, Path, Path]], d: Path, jobs: int, runs: int,
                refs: dict) -> dict:
    """The kidnapping part (the module's docstring, item 4) on the maps the
    mapping runs saved in ``d``/LOG/map.rsmm, judged against their
    trajectories ``refs``; returns its manifest entry (per log the runs of
    each mode, each with its control's figures, and their summary)."""
    from .measure import parallel

    t0 = time.monotonic()
    loaded = {label: flt.load_log(log) for label, log, _ in logs}
    out = {"runs": runs, "length_s": KIDNAP_S, "tail_s": KIDNAP_TAIL_S, "modes": [m for m, _ in KIDNAP_MODES],
           "within": WITHIN_SCANS, "note": KIDNAP_NOTE, "control_note": KIDNAP_CONTROL_NOTE, "logs": {}}
    tasks = []
    for label, _, _ in logs:
        lg = loaded[label]
        span = max(sc.stamp for sc in lg.scans) - lg.first_stamp if lg.scans else 0.0
        offs = kidnap_offsets(span, runs)
        out["logs"][label] = {"span_s": span, "offsets": offs}
        tasks += [(label, k, s) for k, s in enumerate(offs)] + ([(label, None, None)] if offs else [])
    logs_by = {label: log for label, log, _ in logs}

    def nav_kidnap(label, path, mode, flags, name):
        traj, slog = d / label / "kidnap" / f"{name}.txt", d / label / "kidnap" / f"{name}.scans"
        summ = _nav(nav, path, traj, [*STORE, "--load-map", str(d / label / "map.rsmm"), *flags,
                                      "--set", "global_when_lost=1", "--scan-log", str(slog)])
        return summ, read_scan_log(slog), ev.load_trajectory(traj)

    def one(task):
        label, k, s = task
        o = d / label / "kidnap"
        o.mkdir(parents=True, exist_ok=True)
        if k is None:  # the control: the log itself
            return task, {mode: nav_kidnap(label, logs_by[label], mode, flags, f"control-{mode}")[1:]
                          for mode, flags in KIDNAP_MODES}
        spec = flt.FaultSpec(kidnaps=[(s, KIDNAP_S)])
        res = flt.apply_faults(loaded[label], spec)
        cut = res.kidnaps[0]
        path = o / f"kidnap-{k}.clf"
        tmp = o / f"kidnap-{k}.clf.tmp{os.getpid()}"
        with open(tmp, "wb") as fh:
            # rsm-nav --carmen reads the odometry of the scan lines only: no ODOM lines
            flt.write_result(res, fh, "rsm-faults " + flt.describe(spec), odom_lines=False)
        os.replace(tmp, path)
        got = {}
        try:
            for mode, flags in KIDNAP_MODES:
                # judged below, beside the control's run (KIDNAP_CONTROL_NOTE)
                summ = nav_kidnap(label, path, mode, flags, f"{mode}-{k}")[0]
                g, rec = summ.get("global") or {}, summ.get("recovery") or {}
                got[mode] = {"k": k, "offset_s": s, "cut_stamp": cut.stamp, "removed": cut.removed,
                             "hidden_m": cut.hidden[0], "hidden_deg": math.degrees(cut.hidden[1]),
                             "scans": summ.get("scans"), "searches": g.get("searches"),
                             "searches_found": g.get("found"), "not_proven": g.get("not_proven"),
                             "work": g.get("work"), "max_work_per_scan": g.get("max_work_per_scan"),
                             "recoveries": rec.get("taken"), "seconds": summ["seconds"]}
        finally:
            path.unlink()
        return task, got

    # the big log's runs first, so that the last ones are short
    tasks.sort(key=lambda tk: -len(loaded[tk[0]].scans))
    done = parallel(one, tasks, jobs)
    for label, entry in out["logs"].items():
        mine = [g for (_, k, _), g in sorted((tg for tg in done if tg[0][0] == label and tg[0][1] is not None),
                                             key=lambda tg: tg[0][1])]
        control = next((g for (lab, k, _), g in done if lab == label and k is None), None)
        entry["runs"] = {mode: [g[mode] for g in mine] for mode, _ in KIDNAP_MODES}
        for mode, _ in KIDNAP_MODES:
            for r in entry["runs"][mode]:
                c = judge_kidnap(*control[mode], refs[label], r["cut_stamp"])
                r["control"] = {key: c[key] for key in ("found", "wrong", "first_wrong", "first_lost")}
                name = d / label / "kidnap" / f"{mode}-{r['k']}"
                r.update(judge_kidnap(read_scan_log(name.with_suffix(".scans")),
                                      ev.load_trajectory(name.with_suffix(".txt")), refs[label], r["cut_stamp"],
                                      control[mode]))
        entry["summary"] = {mode: aggregate_kidnaps(entry["runs"][mode]) for mode, _ in KIDNAP_MODES}
    out["seconds"] = time.monotonic() - t0
    return out


# ---------------------------------------------------------------------------
# floors and report


def _n(v) -> str:
    return "n/a" if v is None else fmt_int(round(v))


def knownmap_floors(km: Optional[dict]) -> List[dict]:
    """The section's floors, each PASS, MISS or SKIP, from run_knownmap's result."""
    out: List[dict] = []
    if not km or "skipped" in km:
        return out
    for label, e in km["logs"].items():
        head = f"{label}: {MARK}, "
        rt = e["round_trip"]
        ok = rt["identical"] and rt["trajectory_same"] and rt["tiles"] == rt["tiles_again"]
        out.append(floor("PASS" if ok else "MISS", "knownmap-roundtrip", label, int(ok), 1,
                         f"{head}round trip: saved ({fmt_int(rt['bytes'])} bytes, {fmt_int(rt['tiles'])} tiles), "
                         f"loaded frozen and saved again: the tiles {'identical' if rt['identical'] else 'DIFFER'} "
                         "bit for bit, a frozen run on the map saved again "
                         + ("the same trajectory as on the saved map" if rt["trajectory_same"] else
                            "ANOTHER trajectory than on the saved map (the headers differ: the fit at the save "
                            f"{rt['fit']:.4f} and {rt['fit_again']:.4f}, the bar of a recovery)")))
        mp = e["runs"]["mapping"]["all"]
        for mode, what in (("frozen", "frozen"), ("updates", "with updates")):
            v = e["runs"][mode]["all"]
            ok = v is not None and mp is not None and math.isfinite(v) and v <= mp
            out.append(floor("PASS" if ok else "MISS", "knownmap-localization", label, v, mp,
                             f"{head}localization mode {what}, whole log: all-relations translation "
                             f"{fmt_q('translation', v)} m {'<=' if ok else '>'} the mapping run's "
                             f"{fmt_q('translation', mp)} m (x{ratio(v, mp):.2f})"))
        s = e["summary"]
        need = right_needed(s["held"])
        ok = s["held"] > 0 and s["right_within"] >= need
        sp = s["scans_to_pose"]
        timing = (f"first trusted pose after median {_n(sp['median'])}, worst {_n(sp['max'])} scans of the "
                  f"{sp['n']} held starts that gave one" if sp["n"] else "no held start gave a trusted pose")
        out.append(floor("PASS" if ok else "MISS", "knownmap-global", label, s["right_within"], need,
                         f"{head}global localization, {s['starts']} starts ({s['not_held']} not held by the map, "
                         f"counted apart): {s['right_within']} of {s['held']} held starts right (within "
                         f"{RIGHT_M:g} m and {RIGHT_DEG:g} deg of the mapping run) within {s['within']} scans "
                         f"{'>=' if ok else '<'} {need} ({FLOOR_RIGHT_SHARE * 100:g} %); "
                         f"{s['counts']['none']} gave none within {km['cap']} scans; {timing}"))
        ok = s["wrong_all"] == 0
        out.append(floor("PASS" if ok else "MISS", "knownmap-wrong", label, s["wrong_all"], 0,
                         f"{head}global localization, {s['starts']} starts: {s['wrong_all']} gave a trusted pose "
                         f"more than {WRONG_M:g} m or {WRONG_DEG:g} deg off "
                         + (f"({s['wrong_not_held']} of them not held) " if s["wrong_not_held"] else "")
                         + f"{'==' if ok else '>'} 0"))
        out += kidnap_floors(km.get("kidnap"), label)
    out.append(m4_global_floor(km.get("m4_global")))
    out += m4_real_floors(km.get("m4_real"))
    return out


def m4_global_entry(m4: Optional[dict]) -> dict:
    """The figures of the cost floor from the bench's m4 stage (run_m4's
    "global"), or why there are none."""
    if not m4 or "skipped" in m4:
        return {"skipped": (m4 or {}).get("skipped", "the m4 stage did not run")}
    return m4.get("global") or {"skipped": "the m4 stage ran no map-in-flash image"}


def m4_global_floor(g: Optional[dict]) -> dict:
    """The issue's cost floor: the worst scan of the global search on the M4
    (m4_global_entry) against FLOOR_GLOBAL_M4; SKIP without its figures."""
    what = f"Cortex-M4F: {MARK}, global search, instructions per scan on the M4"
    if not g or "skipped" in g:
        return floor("SKIP", "knownmap-cost", None, None, FLOOR_GLOBAL_M4,
                     f"{what} <= {fmt_int(FLOOR_GLOBAL_M4)}: not measured ({(g or {}).get('skipped', 'not run')})")
    ok = g["max"] <= FLOOR_GLOBAL_M4
    found = (f"first proven pose after {g['scans_to_pose']} scans" if g["proven"] else
             f"no pose proven within {g['scans']} scans")
    kept = (f" (kept from the whole bench at `{g['kept_from']}`: --only knownmap runs no firmware)"
            if g.get("kept_from") else "")
    return floor("PASS" if ok else "MISS", "knownmap-cost", None, g["max"], FLOOR_GLOBAL_M4,
                 f"{what}{kept}, the excerpt's map (small: {fmt_int(g['map_tiles'])} tiles, {fmt_int(g['map_bytes'])} "
                 f"bytes, mapped from its first {g['mapped_scans']} scans; the map-in-flash firmware, -O2, QEMU) at "
                 f"the default global_budget ({fmt_int(g['budget'])} a scan): worst "
                 f"{fmt_int(round(g['max']))} {'<=' if ok else '>'} {fmt_int(FLOOR_GLOBAL_M4)}, mean "
                 f"{fmt_int(round(g['mean']))} over {g['scans']} scans (at most {fmt_int(g['max_work'])} work in "
                 f"one); {found}")


# The M4's cost on the full logs (rsm_tools.m4cost): a global search in
# each log's pool-sized saved map (map-pool.rsmm) from the global starts at
# these shares of the starts (percent), each at most M4_REAL_SCANS scans;
# and the replay image on each log's first M4_REPLAY_SCANS scans: the
# costliest scan a tracking recovery took (ACES has two recoveries there,
# from scans 239 and 269), beside the costliest map matching of all.
M4_REAL_STARTS = (10, 50, 90)
M4_REAL_SCANS = 60
M4_REPLAY_SCANS = 600


def run_m4_real(logs: Sequence[Tuple[str, Path, Path]], work: Path, km: dict) -> dict:
    """M4 instructions per scan on the full logs: the global search in each
    log's saved pool map at M4_REAL_STARTS, and the replay of its first
    M4_REPLAY_SCANS scans (rsm_tools.m4cost)."""
    missing = m4cost.tools_missing()
    if missing:
        return {"skipped": missing}
    out = {"scans": M4_REAL_SCANS, "replay_scans": M4_REPLAY_SCANS, "logs": {}}
    try:
        for label, log, _ in logs:
            entry = (km.get("logs") or {}).get(label)
            pool = work / "knownmap" / label / "map-pool.rsmm"
            if not entry or not pool.is_file():
                continue
            offsets = entry["offsets"]
            searches = []
            for share in M4_REAL_STARTS:
                s = offsets[min(len(offsets) - 1, share * len(offsets) // 100)]
                f = m4cost.global_cost(Path(log), pool, s, M4_REAL_SCANS, work / "m4real" / label / f"global-{share}")
                searches.append({"offset_s": s, "max": f["max"], "mean": f["mean"], "scans": f["scans"],
                                 "proven": f["proven"], "max_work": f["max_work"], "budget": f["budget"]})
            r = m4cost.replay_cost(Path(log), M4_REPLAY_SCANS, work / "m4real" / label / "replay")
            out["logs"][label] = {"global": searches,
                                  "replay": {k: r.get(k) for k in ("scans", "mean", "p99", "max", "matching_worst",
                                                                   "recovery_scans", "recovery_worst")}}
    except m4cost.M4CostError as e:
        raise BenchError(str(e))
    return out


def m4_real_floors(m: Optional[dict]) -> List[dict]:
    """The cost floors on the full logs (run_m4_real): the global search's
    worst scan (issue 31) and the costliest scan a tracking recovery took in
    the replay (issue 29), each at most FLOOR_GLOBAL_M4; SKIP without them
    (or without a recovery in the replay's scans)."""
    what = f"Cortex-M4F: {MARK}, the full logs"
    if not m or "skipped" in m:
        return [floor("SKIP", "m4-real", None, None, FLOOR_GLOBAL_M4,
                      f"{what}, instructions per scan: not measured ({(m or {}).get('skipped', 'not run')})")]
    out = []
    for label, e in m["logs"].items():
        g = e["global"]
        worst = max(x["max"] for x in g)
        ok = worst <= FLOOR_GLOBAL_M4
        starts = ", ".join(f"{x['offset_s']:.0f} s: worst {fmt_int(round(x['max']))}, mean {fmt_int(round(x['mean']))} "
                           f"over {x['scans']} scans{'' if x['proven'] else ', none proven'}" for x in g)
        out.append(floor("PASS" if ok else "MISS", "m4-real-global", label, worst, FLOOR_GLOBAL_M4,
                         f"{what}: {label}: global search in the saved pool map on the M4 (map-in-flash "
                         f"firmware, -O2, QEMU; rsm_tools.m4cost), default global_budget ({fmt_int(g[0]['budget'])}): "
                         f"worst scan {fmt_int(round(worst))} {'<=' if ok else '>'} {fmt_int(FLOOR_GLOBAL_M4)} "
                         f"instructions ({starts})"))
        r = e["replay"]
        w = r["matching_worst"]
        rw = r.get("recovery_worst")
        head = f"{what}: {label}: the replay firmware on the first {r['scans']} scans (-O2, QEMU)"
        rest = (f"; the costliest map matching of all, scan {w['scan']}: {fmt_int(round(w['insns']))} "
                f"({fmt_int(round(w['mapmatch']))} matching); all scans: mean {fmt_int(round(r['mean']))}, "
                f"p99 {fmt_int(round(r['p99']))}, worst {fmt_int(round(r['max']))}")
        if rw is None:
            out.append(floor("SKIP", "m4-real-recovery", label, None, FLOOR_GLOBAL_M4,
                             f"{head}: no tracking recovery in them{rest}"))
            continue
        ok = rw["insns"] <= FLOOR_GLOBAL_M4
        out.append(floor("PASS" if ok else "MISS", "m4-real-recovery", label, rw["insns"], FLOOR_GLOBAL_M4,
                         f"{head}: the costliest of the {r['recovery_scans']} scans tracking recoveries took "
                         f"(recover_budget), scan {rw['scan']}: {fmt_int(round(rw['insns']))} "
                         f"{'<=' if ok else '>'} {fmt_int(FLOOR_GLOBAL_M4)} instructions "
                         f"({fmt_int(round(rw['mapmatch']))} matching){rest}"))
    return out


MODE_WHAT = {"frozen": "frozen", "updates": "with updates"}


def _scans_text(v, never: int) -> str:
    """A scan count of _stat_never: None is never (when some run never was)."""
    return ("never" if never else "n/a") if v is None else _n(v)


def kidnap_floors(kd: Optional[dict], label: str) -> List[dict]:
    """The kidnapping part's floors on one log, per mode: every run found
    again within its WITHIN_SCANS scans, and no trusted wrong pose."""
    if not kd or "skipped" in kd or label not in kd.get("logs", {}):
        return []
    e = kd["logs"][label]
    out = []
    head = f"{label}: {MARK}, kidnapping"
    for mode in kd["modes"]:
        s = e["summary"][mode]
        n = s["runs"]
        what = f"{head} {MODE_WHAT.get(mode, mode)}, {n} runs"
        if n == 0:
            out.append(floor("SKIP", "knownmap-kidnap", label, None, None,
                             f"{what}: not measured (the log has no room for a {kd['length_s']:g} s cut)"))
            continue
        sp = s["scans_to_found"]
        ok = s["found_within"] == n
        out.append(floor("PASS" if ok else "MISS", "knownmap-kidnap", label, s["found_within"], n,
                         f"{what} with a {kd['length_s']:g} s cut: {s['found_within']} found again (a trusted pose "
                         f"within {RIGHT_M:g} m and {RIGHT_DEG:g} deg of the mapping run's) within {s['within']} "
                         f"scans of the cut {'==' if ok else '<'} {n}; scans to it median "
                         f"{_scans_text(sp['median'], s['never'])}, worst {_scans_text(sp['max'], s['never'])}"
                         + (f" ({s['never']} never)" if s["never"] else "")
                         + (f"; {s['found_as_control']} of them found where the run without a kidnap was"
                            if s.get("found_as_control") else "")))
        ok = s["wrong_runs"] == 0
        out.append(floor("PASS" if ok else "MISS", "knownmap-kidnap-wrong", label, s["wrong_runs"], 0,
                         f"{what}: {s['wrong_runs']} gave a trusted pose more than {WRONG_M:g} m or "
                         f"{WRONG_DEG:g} deg off after the cut "
                         + (f"({_n(s['wrong_scans'])} such scans in all, the earliest at scan "
                            f"{_n(s['earliest_wrong'])} after the cut) " if s["wrong_runs"] else "")
                         + f"{'==' if ok else '>'} 0"
                         + (f" ({_n(s['as_control_scans'])} more such scans in {s['as_control_runs']} runs where the "
                            "run without a kidnap was: the mapping run's pose is off there)"
                            if s.get("as_control_runs") else "")))
    return out


def report_kidnap(kd: Optional[dict]) -> List[str]:
    """The kidnapping part of the subsection "Known map"."""
    if not kd:
        return ["*Kidnapping*: not measured in this run.", ""]
    if "skipped" in kd:
        return [f"*Kidnapping*: not measured in this run ({kd['skipped']}).", ""]
    from .report import md_table

    n = kd["runs"]
    L = [f"*Kidnapping*: {n} runs per log, run k on a copy of the log with one kidnap of {kd['length_s']:g} s "
         f"(`rsm-faults --kidnap S:{kd['length_s']:g}`, docs/faults.md: the scans of those seconds removed and the "
         "odometry made to report no motion across the cut, as a robot carried elsewhere) at S = (k + 0.5)/"
         f"{n} of the span that leaves room for the cut and {kd['tail_s']:g} s of log after it; each run the whole "
         "copy on the saved map from the log's first pose, `--load-map MAP --set global_when_lost=1`, frozen "
         f"(`--freeze-map`) and with updates. Judged: {kd['note']}; {kd.get('control_note', 'n/a')}. Lost: the "
         "first scan reported lost after the "
         "cut; right before: the run was right at the last scan before the cut; global searches: rsm-nav's count "
         "over the whole runs, before the cut too, and those that proved a pose. Without a kidnap (not a floor): "
         "one run of the log itself per mode, with the same options, judged the same way from each run's first "
         "scan after the cut: runs whose scan there or a later one within the limit was trusted and right, and "
         "runs with a wrong trusted scan from there on; what the judge makes of a run no kidnap disturbed. "
         f"This part took {kd['seconds']:.0f} s.", ""]
    rows = []
    for label, e in kd["logs"].items():
        for mode in kd["modes"]:
            s = e["summary"][mode]
            sp, fl = s["scans_to_found"], s["first_lost"]
            rows.append([label, MODE_WHAT.get(mode, mode), str(s["runs"]), str(s["found_within"]), str(s["found"]),
                         f"{_scans_text(sp['median'], s['never'])} / {_scans_text(sp['max'], s['never'])}",
                         f"{s['wrong_runs']}" + (f" ({_n(s['wrong_scans'])} scans)" if s["wrong_scans"] else ""),
                         f"{s.get('found_as_control', 0)} / {s.get('as_control_runs', 0)}"
                         + (f" ({_n(s['as_control_scans'])} scans)" if s.get("as_control_scans") else ""),
                         f"{s['lost_runs']}" + (f" (median scan {_n(fl['median'])})" if fl["n"] else ""),
                         str(s["right_before"]), f"{s['searches']} / {s['searches_found']}",
                         (f"{s['control_found_within']} / {s['control_wrong_runs']}" if s.get("control_runs")
                          else "n/a")])
    L += md_table(["log", "mode", "runs", f"found again within {kd['within']} scans", "found again",
                   "scans to found again, median / worst", "runs with a wrong trusted pose",
                   "found again / runs off the mapping run, where the run without a kidnap was",
                   "runs reported lost (first lost scan)", "right before the cut", "global searches / proven",
                   f"without a kidnap: right within {kd['within']} scans / runs with a wrong trusted pose"],
                  rows, "knownmap kidnap")
    missed = []
    for label, e in kd["logs"].items():
        for mode in kd["modes"]:
            runs = e["runs"][mode]
            never = [str(r["k"]) for r in runs if r["found"] is None]
            late = [f"{r['k']} ({_n(r['found'])})" for r in runs
                    if r["found"] is not None and r["found"] > kd["within"]]
            wrong = [f"{r['k']} ({_n(r['wrong'])} from scan {_n(r['first_wrong'])})" for r in runs if r["wrong"]]
            parts = ([f"never found again in runs {', '.join(never)}"] if never else []) + \
                    ([f"found again later (scan) in runs {', '.join(late)}"] if late else []) + \
                    ([f"wrong trusted scans (from scan) in runs {', '.join(wrong)}"] if wrong else [])
            if parts:
                missed.append(f"- {label}, {MODE_WHAT.get(mode, mode)}: " + "; ".join(parts) + ".")
    if missed:
        L += ["The runs that missed a floor:", ""] + missed + [""]
    return L


def _f(v, fmt="{:.2f}") -> str:
    return "n/a" if v is None or (isinstance(v, float) and not math.isfinite(v)) else fmt.format(v)


def report_knownmap(km: Optional[dict]) -> List[str]:
    """The report's subsection "Known map" (under section 2, after "Faults")."""
    from .report import md_table

    L = ["### Known map", ""]
    if not km:
        return L + ["Not measured in this run.", ""]
    if "skipped" in km:
        return L + [f"Not measured in this run ({km['skipped']}).", ""]
    if km.get("provenance"):
        L += [provenance_line(km["provenance"]), ""]
    L += ["rsm on a map it saved (issue 31), every log, the default configuration; "
          f"this section took {km['seconds']:.0f} s with {km['jobs']} rsm-nav process(es) at a time. "
          "*Round trip*: the whole log with `rsm-nav --save-map` (the pool's map alone: the default memory), "
          "then again with `--load-map MAP --freeze-map --save-map AGAIN`; the tiles of the two files (every byte between the 48-byte header "
          "and the CRC, docs/mapfile.md; the header holds the pose and the fit at the save) compared, and a frozen "
          "run on AGAIN compared line by line with the one on MAP. The map's part of the localizer state is "
          "rsm-stages' `sizeof(state.persistent.map)` on this host. "
          f"*The map localized in*: the whole log mapped again with a tile store behind the pool (`--tile-store "
          f"{STORE_TILES}`, rsm/tilestore.h, docs/map.md: what the pool lets go is kept there and comes back where "
          "the robot is, so that the saved map holds the whole building); every run below loads it with such a "
          "store. "
          "*Localization mode*: the whole log on the saved map, frozen (`--freeze-map`) and with updates "
          "(`--load-map` alone), from the log's first pose as the mapping run; mean relative-pose error "
          f"(all relations and local ones, span <= {LOCAL_SPAN:g} s) beside the mapping run's. "
          f"*Global localization*: {km['starts']} starts per log spread evenly over it (start k at k/{km['starts']} "
          f"of its span), each `--load-map MAP --freeze-map --global --skip-seconds S --scans {km['cap']}`: no start "
          "pose, the log resumed at S, the global search at its default budget of work per scan. The first trusted "
          f"pose (the trajectory's first line) against the mapping run's pose at that stamp: right within "
          f"{RIGHT_M:g} m and {RIGHT_DEG:g} deg, wrong beyond {WRONG_M:g} m or {WRONG_DEG:g} deg, else between; "
          f"none: no pose within the {km['cap']} scans (or the scans the log had left). Scans to the first trusted "
          "pose (rsm-nav's `first_trusted_scan`, counted from the start), the search's work in all "
          f"(`work`) and in one scan (`max_work_per_scan`). Held: {km['held_note']}. "
          "The issue's cost floor, instructions per scan on the M4, is measured on the target: the map-in-flash "
          "firmware (`port/baremetal/mapflash/`, -O2, QEMU mps2-an386; the subsection \"On the target: "
          "Cortex-M4F\") searches the excerpt's small map globally at the default budget and times each scan; "
          "and the same firmware, built with its input cut from each log (`python3 -m rsm_tools.m4cost global`), "
          "searches the log's saved pool map (the map-in-flash region filled by QEMU's loader) from the starts at "
          f"{', '.join(str(p) for p in M4_REAL_STARTS)} % of the starts, at most {M4_REAL_SCANS} scans each, beside "
          f"the replay firmware on each log's first {M4_REPLAY_SCANS} scans (`python3 -m rsm_tools.m4cost "
          "replay`), whose costliest scan that a tracking recovery took (its first, those its search and proof were "
          "spread over, the one it placed) is issue 29's floor. "
          "The search's work is counted in units of about 18 M4 instructions (src/map/globalsearch.h).", ""]
    rows = []
    for label, e in km["logs"].items():
        rt, st = e["round_trip"], e.get("state") or {}
        rows.append([label, fmt_int(rt["bytes"]), fmt_int(rt["tiles"]),
                     _n(st.get("state.persistent.map")), _n(st.get("state.persistent.map.tile")),
                     "yes" if rt["identical"] else "NO", "yes" if rt["trajectory_same"] else "NO"])
    L += md_table(["log", "saved [B]", "tiles", "map in the state [B]", "of which the tile pool [B]",
                   "tiles identical after a frozen load and save", "same trajectory on the map saved again"],
                  rows, "knownmap round trip")
    rows = []
    for label, e in km["logs"].items():
        sm = e.get("stored_map")
        if sm:
            rows.append([label, fmt_int(sm["bytes"]), fmt_int(sm["tiles"]), _n(sm["held_in_store"]),
                         _n(sm["let_go"]), _n(sm["taken_back"]), _n(sm["taken_back_frozen"])])
    if rows:
        L += md_table(["log", "saved with the store [B]", "tiles", "of them in the store at the save",
                       "let go into the store while mapping", "taken back while mapping",
                       "taken back by the frozen run"], rows, "knownmap store")
    rows = []
    for label, e in km["logs"].items():
        mp = e["runs"]["mapping"]["all"]
        for name, what in (("pool", "mapping run, the pool alone (not a floor)"),
                           ("mapping", "mapping run with the store (--save-map)"), ("frozen", "localization, frozen"),
                           ("updates", "localization, with updates")):
            r = e["runs"].get(name)
            if r is None:
                continue
            rows.append([label, what, fmt_q("translation", r["all"]), fmt_q("rotation", r["all_rotation"]),
                         fmt_q("translation", r["local"]), fmt_q("rotation", r["local_rotation"]),
                         _f(ratio(r["all"], mp)), _n(r["writes"]), _f(r["fit"], "{:.4f}")])
    L += md_table(["log", "run", "all translation [m]", "all rotation [deg]", "local translation [m]",
                   "local rotation [deg]", "all x mapping", "map writes", "fit"], rows, "knownmap localization")
    rows = []
    for label, e in km["logs"].items():
        s = e["summary"]
        c = s["counts"]
        sp, w, wp = s["scans_to_pose"], s["work"], s["max_work_per_scan"]
        rows.append([label, str(s["starts"]), str(s["not_held"]), str(c["right"]), str(s["right_within"]),
                     str(c["between"]), str(s["wrong_all"]),
                     str(c["none"]) + (f" ({s['none_log_ended']} where the log ended first)" if s["none_log_ended"]
                                       else "") + (f" (+{c['no reference']} no reference)" if c["no reference"]
                                                   else ""),
                     f"{_n(sp['median'])} / {_n(sp['max'])}", f"{_n(w['median'])} / {_n(w['max'])}",
                     f"{_n(wp['median'])} / {_n(wp['max'])}"])
    head = ["log", "starts", "not held", "right", f"right within {km['within']} scans", "between",
            "wrong (all starts)", f"none within {km['cap']} scans",
            "scans to the first pose (starts that gave one), median / worst",
            "work per start, median / worst", "most work in one scan, median / worst"]
    L += md_table(head, rows, "knownmap global")
    near = [(label, e["summary_near"]) for label, e in km["logs"].items() if e.get("summary_near")]
    if near:
        L += [f"*Near a rough start* (not a floor of the issue): the same starts, the mapping run's pose there made "
              f"wrong by ({NEAR_OFFSET[0]:g} m, {NEAR_OFFSET[1]:g} m, {NEAR_OFFSET[2]:g} rad) and given as "
              f"`--initial-pose` with `--global-near {NEAR_RADIUS_M:g}` (docs/globalsearch.md): a robot switched "
              "on where it was switched off. Judged as above.", ""]
        rows = []
        for label, s in near:
            c = s["counts"]
            sp, w, wp = s["scans_to_pose"], s["work"], s["max_work_per_scan"]
            rows.append([label, str(s["starts"]), str(s["not_held"]), str(c["right"]), str(s["right_within"]),
                         str(c["between"]), str(s["wrong_all"]), str(c["none"]),
                         f"{_n(sp['median'])} / {_n(sp['max'])}", f"{_n(w['median'])} / {_n(w['max'])}",
                         f"{_n(wp['median'])} / {_n(wp['max'])}"])
        L += md_table(head, rows, "knownmap near")
    L += report_kidnap(km.get("kidnap"))
    L += ["The section's floors (also in section 7):", "", "```"]
    L += [f["line"] for f in knownmap_floors(km)]
    L += ["```", ""]
    return L


# ---------------------------------------------------------------------------
# --only knownmap: the section written into an existing report


def _is_floor_block(lines: Sequence[str]) -> bool:
    body = [l for l in lines if l.strip()]
    return bool(body) and all(l.split()[0] in ("PASS", "MISS", "SKIP") for l in body)


def splice_report(text: str, section: Sequence[str], floors: Sequence[str], next_title: str) -> str:
    """The report ``text`` with its subsection "Known map" replaced by
    ``section`` (or put before the section ``## next_title`` when it has
    none), and in every block of floor lines the lines of this section
    (``: known map, ``) replaced by ``floors``, the count of PASS and MISS
    above section 7's block recounted."""
    lines = text.split("\n")
    out: List[str] = []
    i = 0
    while i < len(lines):
        if lines[i] != "```":
            out.append(lines[i])
            i += 1
            continue
        j = i + 1
        while j < len(lines) and lines[j] != "```":
            j += 1
        block = lines[i + 1:j]
        if j < len(lines) and _is_floor_block(block):
            block = splice_floor_lines(block, floors)
            # the count line "N PASS, M MISS[, K SKIP]:" right above the block
            if len(out) >= 2 and out[-1] == "" and out[-2].endswith(":") and " PASS, " in out[-2]:
                n = {k: sum(1 for l in block if l.split() and l.split()[0] == k) for k in ("PASS", "MISS", "SKIP")}
                out[-2] = f"{n['PASS']} PASS, {n['MISS']} MISS" + (f", {n['SKIP']} SKIP" if n["SKIP"] else "") + ":"
        out += ["```"] + block + (["```"] if j < len(lines) else [])
        i = j + 1
    lines = out
    start = next((k for k, l in enumerate(lines) if l == "### Known map"), None)
    if start is not None:
        end = next((k for k in range(start + 1, len(lines)) if lines[k].startswith(("## ", "### "))), len(lines))
        return "\n".join(lines[:start] + list(section) + lines[end:])
    at = next((k for k, l in enumerate(lines) if l == f"## {next_title}"), None)
    if at is None:
        raise BenchError(f"the report has no section \"{next_title}\" to put \"Known map\" before")
    return "\n".join(lines[:at] + list(section) + lines[at:])


def _place(old: Sequence, new: Sequence, mine, after=None) -> list:
    """``old`` with the items ``mine`` picks replaced by ``new``: where the
    first of them was, else after the last item ``after`` picks, else at the end."""
    at = next((k for k, x in enumerate(old) if mine(x)), None)
    kept = [x for x in old if not mine(x)]
    if at is None:
        last = [k for k, x in enumerate(kept) if after is not None and after(x)]
        at = last[-1] + 1 if last else len(kept)
    else:
        at = sum(1 for x in old[:at] if not mine(x))
    return kept[:at] + list(new) + kept[at:]


def splice_floor_lines(block: Sequence[str], floors: Sequence[str]) -> List[str]:
    """A block of floor lines with this section's replaced by ``floors`` (in place, else at the end)."""
    return _place(list(block), floors, lambda l: f": {MARK}, " in l)


def merge_manifest(manifest: dict, km: dict, floors: Sequence[dict]) -> dict:
    """A manifest (bench.json) with this section's entry and floors replaced
    (its floors where they were, else after the section Faults')."""
    out = dict(manifest)
    out["knownmap"] = km
    out["floors"] = _place(list(manifest.get("floors") or []), floors,
                           lambda f: str(f.get("kind", "")).startswith("knownmap"),
                           lambda f: str(f.get("kind", "")).startswith("faults"))
    return out


def kept_m4_global(manifest: dict) -> dict:
    """The M4 cost of the global search for --only knownmap, which runs no
    firmware: the last whole bench's figures from its manifest, named as
    such (its commit), else skipped with ONLY_M4."""
    old = (manifest.get("knownmap") or {}).get("m4_global") or {}
    if "skipped" in old or "max" not in old:
        return {"skipped": ONLY_M4}
    commit = old.get("kept_from") or (manifest.get("provenance") or {}).get("commit", "?")
    return {**old, "kept_from": commit}


def run_only(nav: Path, logs: Sequence[Tuple[str, Path, Path]], work: Path, jobs: int, starts: int, cap: int,
             stages: Optional[Path], prov: dict, output: Path, next_title: str,
             kidnaps: int = KIDNAP_RUNS) -> Tuple[dict, List[dict]]:
    """rsm-bench --only knownmap: this section alone, written into the
    manifest of the work directory (bench.json, made when there is none) and
    spliced into the existing report ``output`` (its subsection and its floor
    lines; the rest of the report is left as it is)."""
    import json

    if not output.is_file():
        raise BenchError(f"--only knownmap writes its section into an existing report, and {output} is missing "
                         "(run the whole bench once first)")
    km = run_knownmap(nav, logs, work, jobs, starts, cap, stages, kidnaps)
    km["provenance"] = prov
    path = work / "bench.json"
    manifest = json.loads(path.read_text()) if path.is_file() else {"provenance": prov, "report": str(output),
                                                                    "only": "knownmap"}
    km["m4_global"] = kept_m4_global(manifest)
    floors = knownmap_floors(km)
    path.write_text(json.dumps(merge_manifest(manifest, km, floors), indent=1, allow_nan=True))
    text = output.read_text(encoding="utf-8")
    output.write_text(splice_report(text, report_knownmap(km), [f["line"] for f in floors], next_title),
                      encoding="utf-8")
    return km, floors
