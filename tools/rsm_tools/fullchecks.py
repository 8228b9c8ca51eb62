"""The checks that need the full logs, printed as PASS or MISS lines.

The unit and end-to-end tests use only the repository (the excerpt in
``tests/data``).  What can only be checked on the full logs of the shared data
folder (``RSM_SHARED_DIR``, see docs/reference/README.md) is here, and
``./tools/bench`` runs it and prints its lines with the other floors:

* the Intel log is the one its description documents (docs/reference/
  intel-SOURCE.md: record counts, the 631 stamps that go backwards, raw
  odometry against the relations, the corrected poses against them);
* the shipped excerpt is the log's beginning, byte for byte, and its relations
  and poses are those of the full files (tests/data/README.md);
* on every log, rsm is more accurate than the ICP baseline and odometry alone
  on every measure, and a second run is bit-identical;
* the capture path (rsm-convert, then ``rsm-nav --capture``) gives the direct
  run's poses (``rsm-nav --carmen``) until the robot first moves; its local
  error is within 2 % of the direct run's; and its all-relations error is
  within the spread of JITTER_RUNS direct runs whose odometry is moved by up
  to +-JITTER_M (the encoder counts carry the log's odometry only to about a
  tick, and one flipped decision of the matcher moves a run's all-relations
  error by more than 2 %, so one run's ratio is chance: docs/capture.md);
* a figure that depends on the machine's speed and load, so it is no test: the
  shipped excerpt replayed over pseudo-terminals in real time (8x) into
  ``rsm-nav --listen``, its local error against the 0.03 m floor and how many
  poses equal the capture-mode run's.

Each check is a dict ``{"status": PASS|MISS|SKIP, "kind", "log", "value",
"limit", "line"}``, as the bench's floors are.  Run alone::

    python -m rsm_tools.fullchecks --nav build/tools/nav/rsm-nav [--shared DIR]
"""

import argparse
import os
import random
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

from . import capture as cap
from . import convert
from . import evaluate as ev
from . import faults as flt
from .carmen import LogStats, first_scan_after_motion, read_log, time_key
from .excerpt import excerpt_log, excerpt_poses, excerpt_relations
from .fileio import open_binary

LIVE_SPEED = "8"
LIVE_FLOOR = 0.03          # local translation of the real-time live run on the excerpt, m
CAPTURE_TOLERANCE = 1.02   # capture-path local error over the direct run's, at most
JITTER_RUNS = 30           # direct runs with jittered odometry: the all-relations spread (a run of the
                           # same kind lies above all N one time in N + 1: 10 missed by chance on ACES)
QUICK_JITTER_RUNS = 2
JITTER_M = 0.5e-6          # each odometry coordinate moved by up to this, m
INTEL_LOCAL_FLOOR = 0.03   # rsm's local translation error on Intel, m
# The Intel log as docs/reference/intel-SOURCE.md describes it.
INTEL_FACTS = {"FLASER": 13631, "ODOM": 26915, "comments": 4, "readings": 180, "backwards": 631}


def unpacked(path: Path) -> bytes:
    with open_binary(path) as f:
        return f.read()


def check(ok: Optional[bool], kind: str, log: Optional[str], text: str, value=None, limit=None) -> dict:
    """A check as the bench's floors are (SKIP when ``ok`` is None)."""
    from .bench.common import floor  # imported here: the bench imports this module

    return floor("SKIP" if ok is None else ("PASS" if ok else "MISS"), kind, log, value, limit, text)


# ---------------------------------------------------------------------------
# the Intel log and its description


def check_intel_log(log: Path) -> List[dict]:
    st = LogStats()
    backwards = bad_count = 0
    prev = None
    for rec in read_log(log, stats=st):
        if rec.kind != "FLASER":
            continue
        bad_count += rec.num_readings != INTEL_FACTS["readings"]
        if prev is not None and rec.timestamp < prev:
            backwards += 1
        prev = rec.timestamp
    got = {"FLASER": st.records.get("FLASER", 0), "ODOM": st.records.get("ODOM", 0), "comments": st.comments,
           "backwards": backwards}
    ok = (all(got[k] == INTEL_FACTS[k] for k in got) and bad_count == 0
          and st.malformed_total == 0 and st.unknown_total == 0)
    text = ", ".join(f"{k} {got[k]}" for k in got)
    want = ", ".join(f"{k} {INTEL_FACTS[k]}" for k in got)
    return [check(ok, "data", "intel", f"intel: the log as intel-SOURCE.md describes it: {text}; scans not of "
                  f"{INTEL_FACTS['readings']} readings {bad_count}, malformed {st.malformed_total}, unknown "
                  f"{st.unknown_total} (documented: {want}, 0, 0, 0)")]


def _near(v: float, want: float, tol: float) -> bool:
    return abs(v - want) <= tol


def check_intel_odometry(log: Path, relations: Path) -> List[dict]:
    """Raw odometry against the relations: the figures intel-SOURCE.md gives."""
    traj = ev.Trajectory(ev.odometry_trajectory(log))
    rels = ev.load_relations(relations)
    res = ev.evaluate(traj, rels)
    short = ev.evaluate(traj, [r for r in rels if r.span < 5.0])
    long_ = ev.evaluate(traj, [r for r in rels if r.span >= 5.0])
    ok = (res["matched"] == len(rels) and res["unmatched"] == 0 and res["inexact"] == 0
          and short["matched"] == 1732 and _near(short["translation"]["mean"], 0.022, 0.001)
          and long_["matched"] == 1252 and _near(long_["translation"]["mean"], 17.5, 0.1)
          and _near(long_["translation"]["max"], 70.0, 0.5))
    return [check(ok, "data", "intel", f"intel: raw odometry, {res['matched']} of {len(rels)} relations matched "
                  f"exactly; under 5 s: {short['matched']}, {short['translation']['mean']:.4f} m mean; 5 s and "
                  f"over: {long_['matched']}, {long_['translation']['mean']:.2f} m mean, "
                  f"{long_['translation']['max']:.1f} m max (documented: 1732, 0.022 m; 1252, 17.5 m, 70 m)")]


def check_intel_poses(poses: Path, relations: Path) -> List[dict]:
    gt, fmt = ev.load_poses(poses)
    res = ev.evaluate(gt, ev.load_relations(relations), tolerance=0.0)
    t, r = res["translation"], res["rotation"]
    ok = (fmt == "corrected-poses" and len(gt) == 910 and res["matched"] == 90 and _near(t["mean"], 0.036, 0.001)
          and _near(t["max"], 0.179, 0.001) and _near(r["mean"], 0.42, 0.01))
    return [check(ok, "data", "intel", f"intel: corrected poses ({len(gt)}) against the relations: {res['matched']} "
                  f"covered, {t['mean']:.4f} m / {r['mean']:.3f} deg mean, {t['max']:.3f} m max (documented: "
                  "910 poses, 90, 0.036 m / 0.42 deg, 0.179 m)")]


def check_excerpt(d: Path, test_data: Path, work: Path) -> List[dict]:
    """tests/data is the real log's beginning, remade by rsm-excerpt."""
    head_log = test_data / "intel_head.clf.gz"
    out = work / "intel_head.clf.gz"
    res = excerpt_log(d / "intel.clf.gz", out, first_scans=600)
    excerpt_relations(d / "intel.relations", work / "h.relations", res)
    excerpt_poses(d / "intel-corrected-poses.txt", work / "h.poses", res)
    same = {
        "log": unpacked(out) == unpacked(head_log),
        "relations": (work / "h.relations").read_bytes() == (test_data / "intel_head.relations").read_bytes(),
        "poses": (work / "h.poses").read_bytes() == (test_data / "intel_head-corrected-poses.txt").read_bytes(),
        "prefix": unpacked(d / "intel.clf.gz").startswith(unpacked(head_log)),
    }
    # every relation with both ends among the kept scans is kept
    rels = ev.load_relations(d / "intel.relations")
    inside = [r for r in rels if time_key(r.t1) in res.scan_index and time_key(r.t2) in res.scan_index]
    same["all relations inside"] = ev.load_relations(test_data / "intel_head.relations") == inside
    bad = [k for k, v in same.items() if not v]
    return [check(not bad, "data", "intel", "intel: tests/data is the log's first 600 scans with their relations "
                  "and poses, remade by rsm-excerpt" + (f" (differs: {', '.join(bad)})" if bad else ""))]


# ---------------------------------------------------------------------------
# rsm on every log


def run_nav(nav: Path, args: Sequence[str], traj: Path) -> str:
    res = subprocess.run([str(nav), *args, "--trajectory", str(traj), "--quiet"], capture_output=True, text=True,
                         timeout=3600)
    if res.returncode != 0:
        raise RuntimeError(f"rsm-nav {' '.join(args)} failed ({res.returncode}): {res.stderr.strip()}")
    return res.stdout


def check_baselines(label: str, errs: Dict[str, Dict[str, dict]]) -> List[dict]:
    """errs: method -> scope -> evaluate() result, for rsm, icp and odometry."""
    lost = []
    for other in ("icp", "odometry"):
        for scope in ("all", "local"):
            for q in ("translation", "rotation"):
                mine, theirs = errs["rsm"][scope][q]["mean"], errs[other][scope][q]["mean"]
                if not mine < theirs:
                    lost.append(f"{other} {scope} {q} ({theirs:.4f} <= rsm {mine:.4f})")
    out = [check(not lost, "baselines", label, f"{label}: rsm below ICP and odometry alone in translation and "
                 "rotation, all and local relations" + (f"; not on: {'; '.join(lost)}" if lost else ""))]
    if label == "intel":
        v = errs["rsm"]["local"]["translation"]["mean"]
        out.append(check(v <= INTEL_LOCAL_FLOOR, "baselines", label, f"intel: rsm local translation {v:.4f} m "
                         f"{'<=' if v <= INTEL_LOCAL_FLOOR else '>'} {INTEL_LOCAL_FLOOR} m", v, INTEL_LOCAL_FLOOR))
    return out


def check_rerun(label: str, nav: Path, log: Path, traj: Path, work: Path) -> List[dict]:
    again = work / f"{label}-again.txt"
    run_nav(nav, ["--carmen", str(log)], again)
    same = again.read_bytes() == traj.read_bytes()
    return [check(same, "rerun", label, f"{label}: a second rsm run is bit-identical to the first")]


def capture_poses(capf: Path, traj: Path) -> List[Tuple[float, float, float, float]]:
    """A capture run's poses, each at its scan's stamp in the log."""
    stamps = [t / 1e6 for t in convert.original_scan_stamps(capf)]
    rows = ev.read_poses(traj)[0]
    if len(rows) != len(stamps):
        raise RuntimeError(f"{traj}: {len(rows)} poses for {len(stamps)} scans")
    return [(stamps[i], r.x, r.y, r.theta) for i, r in enumerate(rows)]


def jittered_log(log: Path, out: Path, seed: int, jitter_m: float = JITTER_M) -> None:
    """The log with every odometry x and y (ODOM and scan lines) moved by a
    uniform draw within +-jitter_m (seeded); a scan's laser pose moves with
    its odometry. Poses are written with 9 decimals, finer than the jitter;
    other lines and fields are as they were."""
    rng = random.Random(seed)
    loaded = flt.load_log(log)
    poses = []
    for x, y, theta in loaded.poses:
        dx, dy = rng.uniform(-jitter_m, jitter_m), rng.uniform(-jitter_m, jitter_m)
        poses.append((x + dx, y + dy, theta))
    with open(out, "wb") as dst:
        flt.write_poses(loaded, poses, dst, decimals=9)


def jitter_spread(nav: Path, label: str, log: Path, relations: List[ev.Relation], work: Path, runs: int,
                  jobs: int = 2) -> List[float]:
    """The all-relations mean translation error of ``runs`` direct runs on
    copies of the log with jittered odometry (seeds 1..runs)."""
    from concurrent.futures import ThreadPoolExecutor

    def one(seed: int) -> float:
        jl, traj = work / f"{label}-jitter{seed}.clf", work / f"{label}-jitter{seed}.txt"
        jittered_log(log, jl, seed)
        run_nav(nav, ["--carmen", str(jl)], traj)
        jl.unlink()
        return ev.evaluate_scopes(ev.load_trajectory(traj), relations)["all"]["translation"]["mean"]

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        return list(pool.map(one, range(1, runs + 1)))


def check_capture_path(label: str, nav: Path, log: Path, relations: List[ev.Relation],
                       direct: Dict[str, dict], work: Path, direct_traj: Path, jitter_runs: int = JITTER_RUNS,
                       jobs: int = 2) -> List[dict]:
    """The log as serial bytes (rsm-convert) through rsm-nav --capture, beside
    the direct run: the same poses until the robot first moves (the inputs
    are the same bits until then), the local error within CAPTURE_TOLERANCE
    of the direct run's, and the all-relations error within the spread of
    ``jitter_runs`` direct runs with odometry jittered by +-JITTER_M."""
    capf = work / f"{label}.cap"
    st = convert.convert(log, capf)
    traj = work / f"{label}-capture.txt"
    run_nav(nav, ["--capture", str(capf)], traj)
    got = ev.evaluate_scopes(capture_poses(capf, traj), relations)
    mine, theirs = ev.printed_poses(traj), ev.printed_poses(direct_traj)
    same = next((k for k, (a, b) in enumerate(zip(mine, theirs)) if a != b), min(len(mine), len(theirs)))
    still = first_scan_after_motion(log)
    out = [check(same >= still, "capture", label, f"{label}: capture path: the first {same} poses equal to the "
                 f"direct run's ({'>=' if same >= still else '<'} {still}, the scans before the robot first moves)",
                 same, still)]
    mine_l, ref_l = got["local"]["translation"]["mean"], direct["local"]["translation"]["mean"]
    r = mine_l / ref_l if ref_l > 0 else float("inf")
    ok = r <= CAPTURE_TOLERANCE
    out.append(check(ok, "capture", label, f"{label}: capture path ({st.units}, {st.too_far} readings past "
                     f"{st.limit_m:.2f} m) local translation {mine_l:.4f} m = x{r:.3f} of the direct run's "
                     f"{ref_l:.4f} m ({'<=' if ok else '>'} x{CAPTURE_TOLERANCE:.2f})", r, CAPTURE_TOLERANCE))
    mine_a, ref_a = got["all"]["translation"]["mean"], direct["all"]["translation"]["mean"]
    spread = jitter_spread(nav, label, log, relations, work, jitter_runs, jobs) if jitter_runs > 0 else []
    if not spread:
        out.append(check(None, "capture", label, f"{label}: capture path all-relations translation {mine_a:.4f} m "
                         f"(direct {ref_a:.4f} m): no jittered direct run to judge it by"))
        return out
    lo, hi = min(spread), max(spread)
    ok = mine_a <= hi
    out.append(check(ok, "capture", label, f"{label}: capture path all-relations translation {mine_a:.4f} m "
                     f"{'<=' if ok else '>'} {hi:.4f} m, the worst of {len(spread)} direct runs with +-"
                     f"{JITTER_M * 1e6:g} um of odometry jitter ({lo:.4f} to {hi:.4f} m, median "
                     f"{sorted(spread)[len(spread) // 2]:.4f}; the direct run {ref_a:.4f} m; capture "
                     f"x{mine_a / ref_a if ref_a > 0 else float('inf'):.3f} of it)", mine_a, hi))
    return out


def check_live_replay(nav: Path, root: Path, work: Path) -> List[dict]:
    """The shipped excerpt through rsm-replay --speed 8 into rsm-nav --listen (timing-dependent: a figure)."""
    data = root / "tests" / "data"
    capf = work / "excerpt.cap"
    convert.convert(data / "intel_head.clf.gz", capf)
    ref = work / "excerpt-capture.txt"
    run_nav(nav, ["--capture", str(capf)], ref)
    live = work / "excerpt-live.txt"
    x0 = cap.read_capture(capf)[0].metadata.get("robot.initial_pose", "0 0 0").split()
    res = subprocess.run([sys.executable, "-m", "rsm_tools.replay", str(capf), "--pty", "--speed", LIVE_SPEED,
                          "--linger", "0.5", "--quiet", "--run", str(nav), "--robot", "{robot}", "--lms", "{laser}",
                          "--listen", "--initial-pose", *x0, "--trajectory", str(live), "--quiet"],
                         capture_output=True, text=True, timeout=600, env=_tools_env())
    if res.returncode != 0:
        return [check(False, "live", "excerpt", f"excerpt: live replay failed: {res.stderr.strip()[-200:]}")]
    rels = ev.load_relations(data / "intel_head.relations")
    got = ev.evaluate_scopes(capture_poses(capf, live), rels)["local"]["translation"]["mean"]
    want = ev.evaluate_scopes(capture_poses(capf, ref), rels)["local"]["translation"]["mean"]
    same = sum(a == b for a, b in zip(ev.printed_poses(live), ev.printed_poses(ref)))
    ok = got <= LIVE_FLOOR
    return [check(ok, "live", "excerpt", f"excerpt replayed in real time ({LIVE_SPEED}x) into rsm-nav --listen: "
                  f"local translation {got:.4f} m ({'<=' if ok else '>'} {LIVE_FLOOR} m; capture mode {want:.4f} m), "
                  f"{same} of {len(ev.printed_poses(ref))} poses equal to capture mode's (this machine, this load)",
                  got, LIVE_FLOOR)]


def _tools_env() -> dict:
    """The environment for ``python -m rsm_tools.*`` from this checkout."""
    env = dict(os.environ)
    tools = str(Path(__file__).resolve().parents[1])
    env["PYTHONPATH"] = tools + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


# ---------------------------------------------------------------------------


def run_all(shared: Path, nav: Path, logs: Sequence[Tuple[str, Path, Path]], work: Path, root: Path,
            accuracy: Optional[dict] = None, live: bool = True,
            say: Callable[[str], None] = lambda s: None, jitter_runs: Optional[int] = None,
            jobs: int = 2) -> List[dict]:
    """Every check on ``logs`` ((label, log, relations)); ``accuracy`` is the
    bench's accuracy section when it ran (its rsm, icp and odometry
    trajectories are reused), else they are run here; ``live`` False skips
    the real-time replay (and runs QUICK_JITTER_RUNS jittered direct runs
    instead of JITTER_RUNS, unless ``jitter_runs`` says)."""
    if jitter_runs is None:
        jitter_runs = JITTER_RUNS if live else QUICK_JITTER_RUNS
    work.mkdir(parents=True, exist_ok=True)
    out: List[dict] = []
    intel = shared / "data" / "intel"
    if (intel / "intel.clf.gz").is_file():
        say("the Intel log against its description")
        out += check_intel_log(intel / "intel.clf.gz")
        if (intel / "intel.relations").is_file():
            out += check_intel_odometry(intel / "intel.clf.gz", intel / "intel.relations")
        if (intel / "intel-corrected-poses.txt").is_file():
            out += check_intel_poses(intel / "intel-corrected-poses.txt", intel / "intel.relations")
            out += check_excerpt(intel, root / "tests" / "data", work)
    else:
        out.append(check(None, "data", "intel", "intel: the shared folder has no data/intel/intel.clf.gz, so the "
                         "log's description and the shipped excerpt are not checked"))
    if live:
        say("the excerpt replayed in real time")
        out += check_live_replay(nav, root, work)
    else:
        out.append(check(None, "live", "excerpt", "excerpt replayed in real time: not run (quick)"))
    for label, log, rel in logs:
        say(f"{label}: baselines, rerun, capture path")
        relations = ev.load_relations(rel)
        errs, trajs = {}, {}
        for m in ("rsm", "icp", "odometry"):
            run = ((accuracy or {}).get(label) or {}).get("runs", {}).get(m)
            traj = Path(run["trajectory"]) if run else work / f"{label}-{m}.txt"
            if not run:
                run_nav(nav, ["--carmen", str(log), "--method", m], traj)
            trajs[m] = traj
            errs[m] = ev.evaluate_scopes(ev.load_trajectory(traj), relations)
        out += check_baselines(label, errs)
        out += check_rerun(label, nav, log, trajs["rsm"], work)
        out += check_capture_path(label, nav, log, relations, errs["rsm"], work, trajs["rsm"], jitter_runs, jobs)
    return out


def cli_logs(prog: str, doc: str, argv: Optional[Sequence[str]]):
    """The command line the full-log modules share (--nav, --shared, --root):
    (args, repository root, shared folder, logs); exits with 1 when the
    shared folder holds no log."""
    from .bench.common import find_root
    from .bench.measure import discover_logs, shared_dir  # one definition, the bench's

    ap = argparse.ArgumentParser(prog=prog, description=doc.split("\n\n")[0])
    ap.add_argument("--nav", type=Path, required=True, help="the rsm-nav to run (a Release build)")
    ap.add_argument("--shared", type=Path, help="the shared folder (default: $RSM_SHARED_DIR, else ../shared)")
    ap.add_argument("--root", type=Path, help="repository root (default: found from the current folder)")
    a = ap.parse_args(argv)
    root = (a.root or find_root()).resolve()
    shared = shared_dir(a.shared, root)
    logs = discover_logs(shared / "data")
    if not logs:
        print(f"{prog}: no log in {shared / 'data'} (set RSM_SHARED_DIR or --shared)", file=sys.stderr)
        sys.exit(1)
    return a, root, shared, logs


def main(argv: Optional[Sequence[str]] = None) -> int:
    a, root, shared, logs = cli_logs("rsm-fullchecks", __doc__, argv)
    with tempfile.TemporaryDirectory() as tmp:
        res = run_all(shared, a.nav, logs, Path(tmp), root, say=lambda s: print(f"rsm-fullchecks: {s}",
                                                                                  file=sys.stderr, flush=True))
    for c in res:
        print(c["line"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
