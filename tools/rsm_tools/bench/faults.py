"""The bench's section "Faults": rsm on copies of every log with odometry and sampling faults (rsm-faults).

For every fault of FAULTS and every log, ``runs`` runs of rsm-nav (default
20), run k at map_update_m = (0.75 + 0.025 k) times the default and with the
fault placed by seed k; beside them ``2 runs`` clean runs (0.75, 0.7625, ...
times the default: the spread
section's, whose trajectories are reused when it ran) and odometry alone.
The error of a run is the mean all-relations translation error (Kuemmerle
et al.) of its trajectory, keyed by the original log's scans:

* a scan the fault removed (sparse, dropped, in a gap) is given the last
  estimate moved on by the faulty log's odometry since (what a robot reports
  between scans), so every run is judged on every relation;
* with the laser moved off the robot's origin (sparse) the estimate is the
  laser's pose (robot pose (+) mount), as the relations are;
* the copies a slip inserts carry their own stamps and are not judged.

"Odometry alone" is the clean log's odometry; the faulty log's own
odometry is in the table too. The floors (FLOOR_*): the worst run of each
fault at most x2 the clean runs' median and below odometry alone, the median
at most x1.25; the worst clean run at most x3 the clean median. rsm-nav
writes which scans a recovery search placed (--scan-log). A recovery is
judged by the ground truth: the relations across it, one end within
FALSE_RECOVERY_AFTER_S after its scan (and before the next recovery) and the
other up to FALSE_RECOVERY_SPAN_S before, both at scans the run estimated,
or by the clean run's motion over them. When none of
them agrees within FALSE_RECOVERY_M and FALSE_RECOVERY_DEG (in the judged
trajectory above) the recovery is a false one, and the floor on them is
zero; with no such relation it is counted as not judged. (Comparing a
recovery with the clean run's pose, each seen from a pose some seconds
before, called false the recoveries that put right a run which had gone
wrong before them.)
"""

import bisect
import hashlib
import math
import os
import random
import statistics
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

from .. import evaluate as ev
from .. import faults as flt
from ..carmen import Pose, pose_compose
from .common import BenchError, floor, fmt_q, ratio, update_sweep

FAULT_RUNS = 20
QUICK_FAULT_RUNS = 2
CLEAN_PER_FAULT_RUN = 2  # clean runs per log: this many times the runs per fault (40 by default)

FLOOR_WORST_X = 2.0     # the worst faulty run over the clean median, all relations
FLOOR_MEDIAN_X = 1.25   # the faulty runs' median over the clean median
FLOOR_CLEAN_WORST_X = 3.0  # the worst clean run over the clean median
FLOOR_EPS = 1e-9  # a ratio this close to its limit meets it (0.022 / 0.011 is 2.0000000000000004)
FALSE_RECOVERY_M = 0.3
FALSE_RECOVERY_DEG = 5.0
FALSE_RECOVERY_AFTER_S = 20.0  # relations with an end this soon after a recovery (and before the next) judge it ...
FALSE_RECOVERY_SPAN_S = 60.0  # ... and the other end up to this long before it (a building-wide drift is no recovery's)

STALL_TURNS = 6
STALL_LEN = 10
STALL_SPACING = 50
STALL_JITTER = 5
SPIKE = (0.5, 0.25, 0.3)  # m, m, rad; signs drawn per run
SLIP_LEN = 10
SLIP_MIN_M = 0.2          # a slip is placed where the robot moves at least this far over it
SCALE = 1.03
SPARSE_M = 0.2
SPARSE_RAD = 0.3
SPARSE_MOUNT = (0.22, 0.0, 0.0)
SPARSE_OFFSETS = (0.0, 0.25, 0.5, 0.75)  # degrees
DROP_PERCENT = 25
GAP_S = 15.0
LONG_GAP_S = 120.0  # gaps of minutes (issue 29): odometry over them comes in one step

# (name, what it does) in report order.
FAULTS = (
    ("stall", f"odometry frozen for {STALL_LEN} scans at the {STALL_TURNS} strongest turns (moved by up to "
              f"{STALL_JITTER} scans per seed), then caught up in one step"),
    ("spike", f"one scan's odometry displaced by {SPIKE[0]:g} m, {SPIKE[1]:g} m, {SPIKE[2]:g} rad in the robot "
              "frame (signs per seed)"),
    ("reset", "the odometry counter restarts from zero at one scan"),
    ("slip", f"the robot stands still for {SLIP_LEN} scans while the odometry advances (wheels slip)"),
    ("scale", f"every odometry translation x{SCALE:g}"),
    ("sparse", f"a scan only every {SPARSE_M:g} m / {SPARSE_RAD:g} rad, the laser {SPARSE_MOUNT[0]:g} m ahead of "
               "the axle, start angles +" + ", +".join(f"{v:g}" for v in SPARSE_OFFSETS) + " deg in turn"),
    ("drop", f"{DROP_PERCENT} % of the scans dropped at random"),
    ("gap", f"no scan for {GAP_S:g} s once"),
    ("longgap", f"no scan for {LONG_GAP_S:g} s once (odometry over it in one step, metres and tens of degrees off "
                "on Intel)"),
)
FAULT_NAMES = tuple(n for n, _ in FAULTS)

RECOVERY_NOTE = ("a recovery is false when no relation across it (one end within "
                 f"{FALSE_RECOVERY_AFTER_S:g} s after its scan and before the next recovery, the other up to "
                 f"{FALSE_RECOVERY_SPAN_S:g} s before, both at scans the run estimated) agrees, with the ground truth "
                 "or with the clean run's motion over it at the same map_update_m, within "
                 f"{FALSE_RECOVERY_M:g} m and {FALSE_RECOVERY_DEG:g} deg, and it does not land that near the clean "
                 "run's pose at its scan; with no such relation it is not judged "
                 "(rsm-nav --scan-log says which scans a search placed)")


def fault_update(k: int) -> float:
    """map_update_m of fault run k: 0.75 + 0.025 k times the default."""
    return update_sweep(k + 1, 0.025)[k]


def clean_updates(count: int) -> List[float]:
    """map_update_m of the clean runs: the spread section's values."""
    return update_sweep(count)


def _rng(*what) -> random.Random:
    digest = hashlib.sha256(("rsm-bench-faults:" + ":".join(map(str, what))).encode()).digest()
    return random.Random(int.from_bytes(digest[:16], "big"))


def _moving_places(log: flt.LoadedLog, length: int, min_m: float) -> List[int]:
    """Scans S whose odometry moves at least min_m over S..S+length-1."""
    p = [s.odom for s in log.scans]
    return [s for s in range(len(p) - length)
            if math.hypot(p[s + length - 1][0] - p[s][0], p[s + length - 1][1] - p[s][1]) >= min_m]


def _middle(log: flt.LoadedLog, rng: random.Random, candidates: Optional[Sequence[int]] = None) -> int:
    """A scan in the middle 80 % of the log (among candidates when some are there)."""
    m = len(log.scans)
    lo, hi = m // 10, max(m // 10, (9 * m) // 10 - 1)
    c = [s for s in (candidates or ()) if lo <= s <= hi]
    return rng.choice(c) if c else rng.randint(lo, hi)


def plan(name: str, log: flt.LoadedLog, k: int, label: str = "") -> flt.FaultSpec:
    """The fault spec of run k of fault ``name`` on ``log``."""
    rng = _rng(name, label, k)
    if name == "stall":
        return flt.FaultSpec(stall_turns=flt.StallTurns(STALL_TURNS, STALL_LEN, STALL_SPACING, STALL_JITTER), seed=k)
    if name == "spike":
        s = _middle(log, rng)
        d = tuple(v * rng.choice((-1.0, 1.0)) for v in SPIKE)
        return flt.FaultSpec(spikes=[(s, d)], seed=k)
    if name == "reset":
        return flt.FaultSpec(resets=[_middle(log, rng)], seed=k)
    if name == "slip":
        return flt.FaultSpec(slips=[(_middle(log, rng, _moving_places(log, SLIP_LEN, SLIP_MIN_M)), SLIP_LEN)],
                             seed=k)
    if name == "scale":
        return flt.FaultSpec(scale=SCALE, seed=k)
    if name == "sparse":
        j = k % len(SPARSE_OFFSETS)
        offs = list(SPARSE_OFFSETS[j:] + SPARSE_OFFSETS[:j])
        return flt.FaultSpec(every_m=SPARSE_M, every_rad=SPARSE_RAD, mount=SPARSE_MOUNT, start_offsets=offs, seed=k)
    if name == "drop":
        return flt.FaultSpec(drop=DROP_PERCENT, seed=k)
    if name in ("gap", "longgap"):
        length = GAP_S if name == "gap" else LONG_GAP_S
        dur = log.scans[-1].stamp - log.first_stamp
        lo, hi = 0.1 * dur, max(0.1 * dur, 0.9 * dur - length)
        return flt.FaultSpec(gaps=[(round(rng.uniform(lo, hi), 3), length)], seed=k)
    raise BenchError(f"unknown fault {name!r}")


# ---------------------------------------------------------------------------
# judging a run


def judged_trajectory(traj: ev.Trajectory, res: flt.FaultResult) -> List[Tuple[float, float, float, float]]:
    """The run's pose at every scan of the original log (see the module's
    docstring): the estimate where the scan was run, else the last estimate
    moved by the faulty log's odometry; the laser's pose when the fault
    moved the laser off the robot's origin."""
    log = res.log
    mount = res.spec.mount
    out = []
    last: Optional[Tuple[Pose, Pose]] = None  # (estimate, odometry) of the last scan with an estimate
    for i, sc in enumerate(log.scans):
        odo = res.scan_pose(i)
        est = traj.lookup(sc.stamp, tolerance=0.0)
        if est is None:
            if last is None:
                continue
            est = pose_compose(last[0], ev.between(last[1], odo))
        else:
            est = tuple(est)
        last = (est, odo)
        shown = pose_compose(est, mount) if mount is not None else est
        out.append((sc.stamp, shown[0], shown[1], shown[2]))
    return out


REMOVING = ("sparse", "drop", "gap", "longgap")  # faults whose removed scans the judge dead-reckons


def clean_as_judged(clean: ev.Trajectory, run: ev.Trajectory,
                    res: flt.FaultResult) -> List[Tuple[float, float, float, float]]:
    """The clean run judged as ``run`` is: its poses at the scans the faulty
    run has, the others dead-reckoned by judged_trajectory. Dead reckoning
    over the removed scans costs accuracy whatever the matcher does; this is
    what the same matcher, unhurt by the fault, scores under that judge. The
    clean log's laser is at the robot's origin, so with a mount its pose is
    taken back to the robot's."""
    back = ev.between(res.spec.mount, (0.0, 0.0, 0.0)) if res.spec.mount is not None else None
    kept = ev.Trajectory()
    for p in clean.points():
        if run.lookup(p.t, tolerance=0.0) is not None:
            q = (p.x, p.y, p.theta)
            kept.add(p.t, *(pose_compose(q, back) if back is not None else q))
    return judged_trajectory(kept, res)


def odometry_alone(res: flt.FaultResult) -> List[Tuple[float, float, float, float]]:
    """The faulty log's odometry at every scan of the original log (laser pose with a mount)."""
    out = []
    for i, sc in enumerate(res.log.scans):
        p = res.scan_pose(i)
        if res.spec.mount is not None:
            p = pose_compose(p, res.spec.mount)
        out.append((sc.stamp, p[0], p[1], p[2]))
    return out


def errors(traj, relations) -> Dict[str, float]:
    """Mean translation error on all relations and on local ones, exact stamps."""
    s = ev.evaluate_scopes(traj, relations)
    return {"all": s["all"]["translation"]["mean"], "local": s["local"]["translation"]["mean"],
            "matched": s["all"]["matched"]}


def recovered_stamps(scan_log: Path) -> List[float]:
    """Stamps of the scans a recovery search placed, from rsm-nav --scan-log
    (stamp outcome tracking odometry recovered fit_ratio)."""
    out = []
    for line in Path(scan_log).read_text().splitlines():
        f = line.split()
        if f and not line.startswith("#") and len(f) >= 5 and f[4] == "1":
            out.append(float(f[0]))
    return out


def _agrees(pose, ref) -> bool:
    """Whether pose is within FALSE_RECOVERY_M and FALSE_RECOVERY_DEG of ref
    (a relation's motion, or a pose)."""
    dt, dr = ev.relation_error(pose, ref)
    return dt <= FALSE_RECOVERY_M and math.degrees(abs(dr)) <= FALSE_RECOVERY_DEG


def false_recoveries(stamps: Sequence[float], judged: ev.Trajectory, relations: Sequence[ev.Relation],
                     estimated: Optional[set] = None, clean: Optional[ev.Trajectory] = None) -> Tuple[int, int, int]:
    """(judged, false, not judged) of the recoveries at ``stamps``. A
    recovery at t is judged by the relations across it: one end from t to
    FALSE_RECOVERY_AFTER_S after it or to the next recovery, whichever comes
    first, the other up to FALSE_RECOVERY_SPAN_S before t, both at scans
    the run estimated (in
    ``estimated``, when given: an end dead reckoning placed says nothing of
    the recovery). ``judged`` is the run's trajectory as judged_trajectory
    gives it (the laser's pose). The recovery is right when one of them
    agrees within FALSE_RECOVERY_M and FALSE_RECOVERY_DEG: a run can have
    gone wrong some seconds before a search put it right, so a recovery is
    false only when it agrees with no pose of the run in that span. With
    ``clean`` (the clean run at the same map_update_m, laser poses) a
    relation also agrees when the run moved over it as the clean run did:
    where every run jumps back onto a place mapped long before (a drift put
    right at a loop), the jump is the map's, not the fault's; and a
    recovery that relations cross is right too when it lands within
    FALSE_RECOVERY_M and FALSE_RECOVERY_DEG of the clean run's pose at its
    scan (the issue's own test): a run that went wrong long before (more
    than the span) and that a search put right has no right pose for a
    relation to start from. Relations that do not cross the recovery
    cannot tell: a wrong pose tracked on stays consistent with itself."""
    span = FALSE_RECOVERY_SPAN_S
    n_judged = n_false = n_not = 0
    order = sorted(stamps)
    for t in stamps:
        # the recovery's pose as tracking carried it on, until the next recovery takes over
        i = bisect.bisect_right(order, t)
        end = min(t + FALSE_RECOVERY_AFTER_S, order[i]) if i < len(order) else t + FALSE_RECOVERY_AFTER_S
        seen = agreed = False
        for r in relations:
            a, b = sorted((r.t1, r.t2))
            if not (t <= b < end and t - span <= a < t):
                continue
            if estimated is not None and (a not in estimated or b not in estimated):
                continue
            pa, pb = judged.lookup(r.t1, tolerance=0.0), judged.lookup(r.t2, tolerance=0.0)
            if pa is None or pb is None:
                continue
            seen = True
            moved = ev.between(tuple(pa), tuple(pb))
            refs = [(r.x, r.y, r.yaw)]
            if clean is not None:
                ca, cb = clean.lookup(r.t1, tolerance=0.0), clean.lookup(r.t2, tolerance=0.0)
                if ca is not None and cb is not None:
                    refs.append(ev.between(tuple(ca), tuple(cb)))
            agreed = any(_agrees(moved, ref) for ref in refs)
            if agreed:
                break
        if seen and not agreed and clean is not None:
            at, ref = judged.lookup(t, tolerance=0.0), clean.lookup(t, tolerance=0.0)
            agreed = at is not None and ref is not None and _agrees(tuple(at), tuple(ref))
        if not seen:
            n_not += 1
        else:
            n_judged += 1
            n_false += 0 if agreed else 1
    return n_judged, n_false, n_not


def stats(values: Sequence[float]) -> dict:
    """Median, worst, best and count of the finite values (worst: NaN when a
    run has no figure, so that a floor on it cannot pass)."""
    vals = sorted(v for v in values if v is not None and math.isfinite(v))
    missing = len(values) - len(vals)
    if not vals:
        return {"n": 0, "missing": missing, "median": float("nan"), "max": float("nan"), "min": float("nan")}
    return {"n": len(vals), "missing": missing, "median": statistics.median(vals),
            "max": vals[-1] if missing == 0 else float("nan"), "min": vals[0]}


def summarize(fault_runs: Sequence[dict], clean_median: float,
              clean_by_update: Optional[Dict[float, float]] = None) -> dict:
    """A fault's figures on one log from its runs: stats of the all-relations
    error, of the faulty log's odometry alone and of the recoveries taken,
    the ratios of median and worst to the clean median, and the clean run's
    error at the worst run's update distance (``clean_by_update``): one
    run's figure is partly luck (docs/map.md), and that says how much."""
    s = stats([r["all"] for r in fault_runs])
    s["odometry"] = stats([r["odometry_all"] for r in fault_runs])
    s["recoveries"] = stats([r["recoveries"] for r in fault_runs])
    judged = [r for r in fault_runs if r.get("false_recoveries") is not None]
    s["false_recoveries"] = sum(r["false_recoveries"] for r in judged)
    s["recoveries_judged"] = sum(r["recoveries_judged"] for r in judged)
    s["recoveries_unjudged"] = sum(r.get("recoveries_unjudged") or 0 for r in judged)
    s["runs_judged"] = len(judged)
    s["x_median"] = ratio(s["median"], clean_median)
    s["x_worst"] = ratio(s["max"], clean_median)
    finite = [r for r in fault_runs if r["all"] is not None and math.isfinite(r["all"])]
    worst = max(finite, key=lambda r: r["all"]) if finite else None
    s["worst_update"] = worst.get("update") if worst else None
    s["worst_clean"] = (clean_by_update or {}).get(s["worst_update"])
    s["clean_judged"] = stats([r["clean_judged"] for r in fault_runs if r.get("clean_judged") is not None])
    s["x_median_judged"] = ratio(s["median"], s["clean_judged"]["median"]) if s["clean_judged"]["n"] else None
    return s


# ---------------------------------------------------------------------------
# measuring


def run_faults(nav: Path, logs: Sequence[Tuple[str, Path, Path]], runs: int, work: Path, jobs: int,
               reuse: Optional[Tuple[Path, Sequence[float]]] = None, names: Sequence[str] = FAULT_NAMES,
               odom_lines: bool = False) -> dict:
    """Every fault of ``names`` ``runs`` times on every log, and 2 x runs clean
    runs per log. ``reuse`` is (folder, update distances) of clean runs made
    in this bench run (the spread section's FOLDER/LABEL/clean-U.txt): those
    are evaluated instead of run again. With ``odom_lines`` every run, clean
    or faulty, is ``rsm-nav --odom-lines`` on a log with its ODOM lines (the
    faulty copies written with theirs; nothing reused). Returns the manifest
    entry of the section."""
    from .measure import parallel, run_nav

    ncl = CLEAN_PER_FAULT_RUN * runs
    lines_flag = ("--odom-lines",) if odom_lines else ()
    if odom_lines:
        reuse = None
    cups = clean_updates(ncl)
    loaded: Dict[str, flt.LoadedLog] = {}
    rels: Dict[str, list] = {}
    for label, log, rel in logs:
        loaded[label] = flt.load_log(log)
        rels[label] = ev.load_relations(rel)
    tasks = [(label, "clean", j) for label, _, _ in logs for j in range(ncl)]
    tasks += [(label, name, k) for label, _, _ in logs for name in names for k in range(runs)]
    by_label = {label: log for label, log, _ in logs}

    def one(task):
        label, name, k = task
        d = work / "faults" / label
        d.mkdir(parents=True, exist_ok=True)
        if name == "clean":
            u = cups[k]
            old = reuse[0] / label / f"clean-{u:.3f}.txt" if reuse is not None and u in reuse[1] else None
            if old is not None and old.is_file():
                traj_path, summary, reused = old, None, True
            else:
                traj_path = d / f"clean-{u:.3f}.txt"
                summary = run_nav(nav, by_label[label], "rsm", traj_path,
                                  extra=("--set", f"map_update_m={u:g}", *lines_flag))["parsed"]
                reused = False
            e = errors(ev.load_trajectory(traj_path), rels[label])
            rec = (summary or {}).get("recovery") or {}
            return task, {"update": u, "trajectory": str(traj_path), "reused": reused,
                          "recoveries": rec.get("taken"), **e}
        u = fault_update(k)
        spec = plan(name, loaded[label], k, label)
        res = flt.apply_faults(loaded[label], spec)
        path = d / f"{name}-{k}.clf"
        tmp = d / f"{name}-{k}.clf.tmp{os.getpid()}"
        with open(tmp, "wb") as fh:
            # the ODOM lines only for --odom-lines: rsm-nav --carmen reads them only then, and without them
            # the run is the same for half the writing
            written = flt.write_result(res, fh, "rsm-faults " + flt.describe(spec), odom_lines=odom_lines)
        os.replace(tmp, path)
        traj_path = d / f"{name}-{k}.txt"
        slog = d / f"{name}-{k}.scans"
        extra = ["--set", f"map_update_m={u:g}", "--scan-log", str(slog), *lines_flag]
        if spec.mount is not None:
            extra += ["--laser-pose", *(f"{v:g}" for v in spec.mount)]
        try:
            r = run_nav(nav, path, "rsm", traj_path, extra=extra)
        finally:
            path.unlink()
        summary = r["parsed"]
        e = errors(judged_trajectory(ev.load_trajectory(traj_path), res), rels[label])
        o = errors(odometry_alone(res), rels[label])
        rec = summary.get("recovery") or {}
        return task, {"k": k, "update": u, "spec": flt.describe(spec), "faults": res.summaries,
                      "scans_written": written, "trajectory": str(traj_path),
                      "recovered_at": recovered_stamps(slog), "mount": spec.mount,
                      "recoveries": rec.get("taken"), "searches": rec.get("searches"),
                      "odometry_faults": summary.get("odometry_faults"),
                      "odometry_all": o["all"], "odometry_local": o["local"], **e}

    # The runs of the big logs first, so that the last ones are short.
    sizes = {label: len(loaded[label].scans) for label in loaded}
    tasks.sort(key=lambda t: -sizes[t[0]])
    done = parallel(one, tasks, jobs)
    out = {"runs": runs, "clean_runs": ncl, "updates": [fault_update(k) for k in range(runs)],
           "clean_updates": cups, "faults": [{"name": n, "what": w} for n, w in FAULTS if n in names],
           "recovery_note": RECOVERY_NOTE, "odom_lines": odom_lines, "logs": {}}
    for label, log, rel in logs:
        clean = [r for (lab, name, _), r in done if lab == label and name == "clean"]
        clean.sort(key=lambda r: r["update"])
        odo = errors([(s.stamp, *s.odom) for s in loaded[label].scans], rels[label])
        cs = stats([r["all"] for r in clean])
        entry = {"log": str(log), "relations": len(rels[label]), "odometry": odo, "clean": cs,
                 "clean_runs": clean, "clean_reused": sum(1 for r in clean if r["reused"]), "faults": {}}
        clean_traj = {r["update"]: r["trajectory"] for r in clean}
        for name in names:
            fr = sorted((r for (lab, n, _), r in done if lab == label and n == name), key=lambda r: r["k"])
            for r in fr:
                ref = clean_traj.get(r["update"])
                clean_run = ev.load_trajectory(Path(ref)) if ref is not None else None
                run_traj = ev.load_trajectory(Path(r["trajectory"]))
                res = flt.apply_faults(loaded[label], plan(name, loaded[label], r["k"], label))
                r["recoveries_judged"], r["false_recoveries"], r["recoveries_unjudged"] = false_recoveries(
                    r["recovered_at"], ev.Trajectory(judged_trajectory(run_traj, res)), rels[label],
                    {p.t for p in run_traj.points()}, clean_run)
                if clean_run is not None and name in REMOVING:
                    r["clean_judged"] = errors(clean_as_judged(clean_run, run_traj, res), rels[label])["all"]
            entry["faults"][name] = {"runs": fr, **summarize(fr, cs["median"], {r["update"]: r["all"] for r in clean})}
        out["logs"][label] = entry
    return out


# ---------------------------------------------------------------------------
# floors and report


def _judged_alike(f: dict) -> str:
    """For a fault that removes scans: the clean runs judged the same way."""
    cj = f.get("clean_judged") or {}
    if not cj.get("n"):
        return ""
    return (f" (the clean runs judged alike, the scans the fault removed dead-reckoned: median "
            f"{fmt_q('translation', cj['median'])} m, the fault's median x{f['x_median_judged']:.2f} that)")


def fault_floors(fa: Optional[dict]) -> List[dict]:
    """The section's floors, each PASS, MISS or SKIP, from run_faults' result."""
    out: List[dict] = []
    if not fa or "skipped" in fa:
        return out
    for label, e in fa["logs"].items():
        c = e["clean"]
        cm = c["median"]
        odo = e["odometry"]["all"]
        ups = fa["clean_updates"]
        what = f"{label}: clean, worst of {c['n']} runs" + (f" (map_update_m {ups[0]:g} to {ups[-1]:g})" if ups else "")
        if c["n"] == 0:
            out.append(floor("SKIP", "faults-clean", label, None, FLOOR_CLEAN_WORST_X, f"{what}: not measured"))
        else:
            x = ratio(c["max"], cm)
            ok = math.isfinite(x) and x <= FLOOR_CLEAN_WORST_X + FLOOR_EPS
            out.append(floor("PASS" if ok else "MISS", "faults-clean", label, x, FLOOR_CLEAN_WORST_X,
                             f"{what} {fmt_q('translation', c['max'])} m = x{x:.2f} the clean median "
                             f"{fmt_q('translation', cm)} m {'<=' if ok else '>'} x{FLOOR_CLEAN_WORST_X:g}, "
                             "all-relations translation"))
        for name, f in e["faults"].items():
            head = f"{label}: {name} fault"
            if f["n"] == 0 or c["n"] == 0:
                out.append(floor("SKIP", "faults", label, None, FLOOR_WORST_X, f"{head}: not measured"))
                continue
            n_runs = f["n"] + f["missing"]
            xw = f["x_worst"]
            under = math.isfinite(xw) and xw <= FLOOR_WORST_X + FLOOR_EPS
            ok = under and f["max"] < odo
            same = ("" if f.get("worst_clean") is None else
                    f" (the clean run at its map_update_m {f['worst_update']:g}: "
                    f"{fmt_q('translation', f['worst_clean'])} m)")
            out.append(floor("PASS" if ok else "MISS", "faults", label, xw, FLOOR_WORST_X,
                             f"{head}, worst of {n_runs} runs {fmt_q('translation', f['max'])} m{same} = x{xw:.2f} "
                             f"the clean median {fmt_q('translation', cm)} m {'<=' if under else '>'} "
                             f"x{FLOOR_WORST_X:g}, {'<' if f['max'] < odo else '>='} odometry alone "
                             f"{fmt_q('translation', odo)} m, all-relations translation"))
            xm = f["x_median"]
            ok = math.isfinite(xm) and xm <= FLOOR_MEDIAN_X + FLOOR_EPS
            out.append(floor("PASS" if ok else "MISS", "faults", label, xm, FLOOR_MEDIAN_X,
                             f"{head}, median of {n_runs} runs {fmt_q('translation', f['median'])} m = x{xm:.2f} "
                             f"the clean median {'<=' if ok else '>'} x{FLOOR_MEDIAN_X:g}" + _judged_alike(f)))
    for label, e in fa["logs"].items():
        fr = [f for f in e["faults"].values() if f.get("runs_judged")]
        if not fr:
            out.append(floor("SKIP", "faults-recovery", label, None, 0,
                             f"{label}: false recoveries: no fault run was judged"))
            continue
        false = sum(f["false_recoveries"] for f in fr)
        judged = sum(f["recoveries_judged"] for f in fr)
        runs = sum(f["runs_judged"] for f in fr)
        unjudged = sum(f.get("recoveries_unjudged") or 0 for f in fr)
        out.append(floor("PASS" if false == 0 else "MISS", "faults-recovery", label, false, 0,
                         f"{label}: false recoveries {false} of {judged} judged in {runs} fault runs "
                         f"({unjudged} more not judged: no relation near) "
                         f"{'==' if false == 0 else '>'} 0 ({RECOVERY_NOTE})"))
    return out


def _m(v: Optional[float]) -> str:
    return fmt_q("translation", v) if v is not None else "n/a"


def report_faults(fa: Optional[dict]) -> List[str]:
    """The report's subsection "Faults" (under section 2)."""
    L = ["### Faults", ""]
    if not fa:
        return L + ["Not measured in this run.", ""]
    if "skipped" in fa:
        return L + [f"Not measured in this run ({fa['skipped']}).", ""]
    L += ["rsm on copies of every log broken by `rsm-faults` (docs/faults.md): odometry stalls, spikes, a counter "
          "reset, wheel slip, a scale error, and sparse, dropped or missing scans. "
          f"Each fault {fa['runs']} times per log, run k at `map_update_m` = {fa['updates'][0]:.3f} + "
          f"{fa['updates'][1] - fa['updates'][0] if len(fa['updates']) > 1 else 0.0:.4f} k m "
          f"with the fault placed by seed k; {fa['clean_runs']} clean runs per log at "
          + ", ".join(f"{u:g}" for u in fa["clean_updates"][:2]) + ", ... m. "
          "Error: mean all-relations translation error of a run; a scan the fault removed is given the last "
          "estimate moved by the faulty log's odometry, and a laser off the robot's origin is judged at the "
          "laser's pose, so every run is judged on every relation. Worst and median over the runs, each beside "
          "the clean runs' median, and the clean run at the worst run's update distance (one run's figure is partly "
          "luck: when that clean run is as bad, the fault is not what made the worst run bad); for the faults that "
          "remove scans, the clean runs judged alike (their poses at the scans the fault removed dead-reckoned the "
          "same way: what the judge costs a matcher the fault did not hurt); odometry alone on "
          "the clean log and on the faulty one (median over the runs); recoveries: rsm-nav's count of recoveries "
          "taken (median and most in a run).", ""]
    if fa.get("odom_lines"):
        L += ["Every run here, clean or faulty, fed the logs' `ODOM` lines as odometry steps of their own "
              "(`rsm-nav --odom-lines`, the faulty copies written with theirs): not the bench's default.", ""]
    for f in fa["faults"]:
        L.append(f"- *{f['name']}*: {f['what']}.")
    L.append("")
    rows = []
    for label, e in fa["logs"].items():
        c = e["clean"]
        rows.append([label, "clean", str(c["n"]), _m(c["median"]), _m(c["max"]), "1.00",
                     f"{ratio(c['max'], c['median']):.2f}", "", "", _m(e["odometry"]["all"]), "", "", ""])
        for name, f in e["faults"].items():
            rc = f["recoveries"]
            rows.append([label, name, str(f["n"] + f["missing"]), _m(f["median"]), _m(f["max"]),
                         f"{f['x_median']:.2f}", f"{f['x_worst']:.2f}",
                         "n/a" if f.get("worst_clean") is None else f"{_m(f['worst_clean'])} ({f['worst_update']:.3f})",
                         "" if not (f.get("clean_judged") or {}).get("n") else
                         f"{_m(f['clean_judged']['median'])} (x{f['x_median_judged']:.2f})",
                         _m(e["odometry"]["all"]),
                         _m(f["odometry"]["median"]),
                         "n/a" if rc["n"] == 0 else f"{rc['median']:g} / {rc['max']:g}",
                         "n/a" if not f.get("runs_judged") else
                         f"{f['false_recoveries']} of {f['recoveries_judged']} (+{f.get('recoveries_unjudged') or 0})"])
    from .report import md_table
    L += md_table(["log", "fault", "runs", "median [m]", "worst [m]", "median x clean", "worst x clean",
                   "clean at the worst's distance [m] (map_update_m)",
                   "clean judged alike, median [m] (fault's median x that)", "odometry alone [m]", "faulty odometry [m]",
                   "recoveries", "false recoveries of judged (+ not judged)"], rows, "faults")
    L += [f"False recoveries: {RECOVERY_NOTE}.", ""]
    return L
