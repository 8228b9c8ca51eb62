"""The bench's line on de-skew with encoder packets read in bursts (issue
"Nothing lost, nothing silent"): a host that stalls and then reads its
backlog stamps two encoder packets microseconds apart, and de-skew once
extrapolated that "speed" and flung points by metres.

rsm-sim's curving drive (the rooms world, turns in place at 1.5 rad/s and
arcs at 0.5 m/s; the laser 0.12 m ahead, 0.03 m right, turned 0.3 rad) as an
LD06 and as an RPLIDAR capture, run through rsm-nav's lidar path in capture
mode with de-skew on, twice: as simulated (clean), and with the encoder
packets read in pairs, the first of each pair stamped BURST_US before the
second (late, as the backlog's reader saw it; the records are kept in time
order, so the pair's first now comes after the laser bytes that were read
before it). A third run, a reference and no floor, gets only the pairs'
second packets, each at its true time: the odometry the bursts leave
(half of it), stamped right, so what no burst handling can win back. Each
run is judged against the simulator's truth at each turn's
middle: the relative-pose error over spans up to LOCAL_SPAN_S ("local") and
over relations from every turn to every RELATION_STRIDE-th turn after it
("all relations").

The floors (the issue's): every pose of the burst run within FLOOR_M and
FLOOR_DEG of the clean run's pose at the same turn, and its mean errors,
local and over all relations, translation and rotation, at most FLOOR_X
times the clean run's. Capture mode is a function of the bytes, so the
figures are the same on every machine.

Run alone::

    python -m rsm_tools.bench.deskew --nav build-release/tools/nav/rsm-nav [--seconds S]
"""

import argparse
import math
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Dict, List, Optional, Sequence

from .. import capture as cap
from .. import evaluate as ev
from .. import sim
from .common import BenchError

KINDS = ("ld06", "rplidar")
SECONDS = 120.0        # of simulated drive, per lidar
QUICK_SECONDS = 40.0
BURST_US = 10          # the pair's first packet stamped this long before its second
MOUNT = (0.12, -0.03, 0.3)
LOCAL_SPAN_S = 1.0
RELATION_STRIDE = 5    # "all relations": every turn to every 5th turn after it
FLOOR_M = 0.1          # each burst-run pose from the clean run's, at most
FLOOR_DEG = 2.0
FLOOR_X = 1.1          # burst-run error over the clean run's, at most
FLOOR_EPS = 1e-9       # a ratio this close to its limit meets it


def in_bursts(src: Path, dst: Path, gap_us: int = BURST_US) -> int:
    """Writes ``src`` to ``dst`` with the robot channel's received records
    read in pairs: the first of each pair re-stamped gap_us before the
    second. Returns the pairs made."""
    head, recs, _ = cap.read_capture(src)
    robot = head.channel("robot").id
    enc = [i for i, r in enumerate(recs) if r.channel == robot and r.is_rx]
    stamps = [r.timestamp for r in recs]
    pairs = 0
    for a, b in zip(enc[0::2], enc[1::2]):
        if recs[b].timestamp - gap_us > recs[a].timestamp:
            stamps[a] = recs[b].timestamp - gap_us
            pairs += 1
    order = sorted(range(len(recs)), key=lambda i: (stamps[i], i))
    with cap.CaptureWriter(dst, head.channels, head.metadata) as w:
        for i in order:
            w.write(stamps[i], recs[i].channel, recs[i].data, recs[i].direction)
    return pairs


def halved(src: Path, dst: Path) -> int:
    """Writes ``src`` to ``dst`` without the first of each pair of the robot
    channel's received records (the reference run); returns the records
    dropped."""
    head, recs, _ = cap.read_capture(src)
    robot = head.channel("robot").id
    drop = set([i for i, r in enumerate(recs) if r.channel == robot and r.is_rx][0::2])
    with cap.CaptureWriter(dst, head.channels, head.metadata) as w:
        for i, r in enumerate(recs):
            if i not in drop:
                w.write(r.timestamp, r.channel, r.data, r.direction)
    return len(drop)


def run_nav(nav: Path, capf: Path, traj: Path) -> None:
    res = subprocess.run([str(nav), "--capture", str(capf), "--laser-pose", *(repr(v) for v in MOUNT),
                          "--trajectory", str(traj), "--quiet"], capture_output=True, text=True, timeout=3600)
    if res.returncode != 0:
        raise BenchError(f"rsm-nav --capture {capf.name} failed ({res.returncode}): {res.stderr.strip()[-300:]}")


def strided_relations(truth: ev.Trajectory, stride: int) -> List[ev.Relation]:
    """Relations from every truth pose to every stride-th pose after it."""
    pts = truth.points()
    out = []
    for i, a in enumerate(pts):
        for j in range(i + 1, len(pts), stride):
            b = pts[j]
            d = ev.between((a.x, a.y, a.theta), (b.x, b.y, b.theta))
            out.append(ev.Relation(a.t, b.t, d[0], d[1], d[2]))
    return out


def errors(traj: ev.Trajectory, local: Sequence[ev.Relation], every: Sequence[ev.Relation]) -> Dict[str, dict]:
    out = {}
    for scope, rels in (("local", local), ("all", every)):
        res = ev.evaluate(traj, rels, tolerance=0.001)
        out[scope] = {"translation": res["translation"]["mean"], "rotation": res["rotation"]["mean"],
                      "matched": res["matched"]}
    return out


def deviation(a: ev.Trajectory, b: ev.Trajectory) -> Dict[str, float]:
    """The largest distance and heading difference of b's poses from a's at
    the same turn (same stamp); the turns must be the same."""
    pa, pb = a.points(), b.points()
    if [round(p.t, 6) for p in pa] != [round(p.t, 6) for p in pb]:
        raise BenchError(f"the burst run has other turns than the clean run ({len(pb)} against {len(pa)})")
    dm = max((math.hypot(p.x - q.x, p.y - q.y) for p, q in zip(pa, pb)), default=0.0)
    dd = max((abs(math.degrees(ev.wrap_angle(p.theta - q.theta))) for p, q in zip(pa, pb)), default=0.0)
    return {"m": dm, "deg": dd}


def run_kind(nav: Path, kind: str, seconds: float, work: Path) -> dict:
    work.mkdir(parents=True, exist_ok=True)
    clean, truth_path, burst = work / f"{kind}.cap", work / f"{kind}-truth.txt", work / f"{kind}-bursts.cap"
    turns = sim.simulate(clean, truth_path, "rooms", seconds=seconds, lidar=kind, drive="curves",
                         laser_pose=MOUNT)
    pairs = in_bursts(clean, burst)
    halved(clean, work / f"{kind}-halved.cap")
    trajs = {}
    for name, capf in (("clean", clean), ("bursts", burst), ("halved", work / f"{kind}-halved.cap")):
        out = work / f"{kind}-{name}.txt"
        run_nav(nav, capf, out)
        trajs[name] = ev.load_trajectory(out)
    truth = ev.load_trajectory(truth_path)
    local = ev.relations_from_poses(truth, max_span=LOCAL_SPAN_S)
    every = strided_relations(truth, RELATION_STRIDE)
    return {"kind": kind, "seconds": seconds, "turns": turns, "pairs": pairs, "poses": len(trajs["clean"].points()),
            **{name: errors(t, local, every) for name, t in trajs.items()},
            "deviation": deviation(trajs["clean"], trajs["bursts"]),
            "halved_deviation": deviation(trajs["clean"], trajs["halved"])}


def run(nav: Path, work: Path, seconds: float = SECONDS, kinds: Sequence[str] = KINDS) -> dict:
    """The section's figures, one lidar after the other."""
    return {"burst_us": BURST_US, "runs": [run_kind(nav, k, seconds, work / "deskew-bursts") for k in kinds]}


def _ratio(a: float, b: float) -> float:
    return a / b if b > 0 else (1.0 if a == 0 else float("inf"))


def floors(res: Optional[dict]) -> List[dict]:
    """PASS, MISS or SKIP lines: per lidar, the poses' deviation and the error ratios."""
    from .common import floor as _floor

    what = "de-skew with encoder packets in bursts"
    if not res or "skipped" in res or not res.get("runs"):
        why = (res or {}).get("skipped", "not run")
        return [_floor("SKIP", "deskew-bursts", None, None, FLOOR_X, f"{what}: not measured ({why})")]
    out = []
    for r in res["runs"]:
        k, dev = r["kind"].upper(), r["deviation"]
        ok = dev["m"] <= FLOOR_M and dev["deg"] <= FLOOR_DEG
        out.append(_floor("PASS" if ok else "MISS", "deskew-bursts", r["kind"], max(dev["m"] / FLOOR_M,
                          dev["deg"] / FLOOR_DEG), 1.0,
                          f"{what} {res['burst_us']} us apart ({k}, {r['poses']} turns): every pose within "
                          f"{dev['m']:.3f} m and {dev['deg']:.2f} deg of the clean capture's "
                          f"({'<=' if ok else '>'} {FLOOR_M:g} m and {FLOOR_DEG:g} deg)"))
        for scope in ("local", "all"):
            parts, worst = [], 0.0
            for q, unit in (("translation", "m"), ("rotation", "deg")):
                mine, ref = r["bursts"][scope][q], r["clean"][scope][q]
                x = _ratio(mine, ref)
                worst = max(worst, x)
                parts.append(f"{q} {mine:.4f} {unit} = x{x:.3f} of {ref:.4f}")
            ok = worst <= FLOOR_X + FLOOR_EPS
            out.append(_floor("PASS" if ok else "MISS", "deskew-bursts", r["kind"], worst, FLOOR_X,
                              f"{what} ({k}): {'local' if scope == 'local' else 'all-relations'} error against "
                              f"the truth {'; '.join(parts)} ({'<=' if ok else '>'} x{FLOOR_X:g})"))
    return out


def report(res: Optional[dict]) -> List[str]:
    """The lines of the report (under the floors' section)."""
    if not res or "skipped" in res:
        return ["De-skew with encoder packets in bursts: not measured in this run"
                + (f" ({res['skipped']})" if res and "skipped" in res else "") + ".", ""]
    L = [f"De-skew with encoder packets read in pairs {res['burst_us']} us apart (`rsm_tools.bench.deskew`): "
         "rsm-sim's curving drive as a lidar capture, de-skew on, as simulated and with the pairs; mean error "
         f"against the truth, local (spans <= {LOCAL_SPAN_S:g} s) and over relations from every turn to every "
         f"{RELATION_STRIDE}th after it; the largest difference of a pose from the clean run's. The reference "
         "(no floor) keeps only each pair's second packet, stamped right: the odometry the bursts leave.", "",
         "| lidar | turns | encoder pairs | run | local error | all-relations error | largest pose difference |",
         "|---|---|---|---|---|---|---|"]
    for r in res["runs"]:
        for w, what in (("clean", "as simulated"), ("bursts", "in bursts"), ("halved", "reference: half, on time")):
            cells = [f"{r[w][s]['translation']:.4f} m {r[w][s]['rotation']:.3f} deg" for s in ("local", "all")]
            dev = {"clean": None, "bursts": r["deviation"], "halved": r.get("halved_deviation")}[w]
            L.append(f"| {r['kind'].upper()} ({r['seconds']:g} s) | {r['poses']} | {r['pairs']} | {what} | "
                     + " | ".join(cells) + (f" | {dev['m']:.3f} m {dev['deg']:.2f} deg |" if dev else " | |"))
    return L + [""]


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-bench-deskew", description=__doc__.split("\n\n")[0])
    ap.add_argument("--nav", type=Path, required=True, help="the rsm-nav to run")
    ap.add_argument("--seconds", type=float, default=SECONDS, help=f"simulated drive per lidar (default {SECONDS:g})")
    ap.add_argument("--work-dir", type=Path, help="keep the captures and trajectories here (default: a temporary "
                    "folder)")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        res = run(a.nav, a.work_dir or Path(tmp), a.seconds)
    for line in report(res):
        print(line)
    for f in floors(res):
        print(f["line"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
