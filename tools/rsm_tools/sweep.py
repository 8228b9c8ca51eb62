"""One row of a settings comparison on the full logs (``./tools/sweep``).

Runs ``rsm-nav`` with the given ``--set`` values on every log of the shared
folder, clean and with 43 % of every scan's readings replaced by outliers
(one copy per seed, made once and kept in the bench's cache),
each at several ``map_update_m`` values: the all-relations error of one run
moves a lot with small changes (a few returns to earlier places either snap
back or keep a second copy), so one run says little. Prints one line per log
and variant: the mean and median of the all-relations translation error over
the runs, and the median of the local (<= 2 s) translation and rotation.

Needs only the logs (``NAME/NAME.clf.gz`` and ``NAME/NAME.relations`` under
``data/`` of the shared folder: ``--shared``, else ``RSM_SHARED_DIR``, else
``../shared`` beside the repository) and a built ``rsm-nav``.
"""

import argparse
import concurrent.futures
import os
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

from . import evaluate as ev
from .bench.measure import outlier_logs

DEFAULT_UPDATES = "0.34 0.37 0.40 0.43 0.46"


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-sweep", description=__doc__.split("\n\n")[0])
    ap.add_argument("--nav", required=True, help="the rsm-nav to run")
    ap.add_argument("--shared", type=Path, help="the shared folder (default: $RSM_SHARED_DIR, else ../shared)")
    ap.add_argument("--work", type=Path, required=True, help="folder for the trajectories")
    ap.add_argument("--cache", type=Path, required=True, help="folder of the outlier copies (the bench's cache)")
    ap.add_argument("--label", default="run", help="name of the row")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="passed to rsm-nav")
    ap.add_argument("--updates", default=os.environ.get("RSM_SWEEP_UPDATES", DEFAULT_UPDATES),
                    help=f"map_update_m values, space separated (default: {DEFAULT_UPDATES})")
    ap.add_argument("--seeds", default="7 8", help="outlier seeds, space separated; '' for clean only")
    ap.add_argument("--only", default="", help="run only these NAME-VARIANT pairs (e.g. 'aces-clean intel-s7')")
    ap.add_argument("--jobs", type=int, default=2, help="rsm-nav processes at a time (default 2)")
    a = ap.parse_args(argv)
    root = Path(__file__).resolve().parents[2]
    shared = a.shared or Path(os.environ.get("RSM_SHARED_DIR") or root.parent / "shared")
    logs = sorted(d.name for d in (shared / "data").glob("*/")
                  if (d / f"{d.name}.clf.gz").exists() and (d / f"{d.name}.relations").exists())
    if not logs:
        print(f"rsm-sweep: no logs in {shared / 'data'}", file=sys.stderr)
        return 1
    a.work.mkdir(parents=True, exist_ok=True)
    only = set(a.only.split())
    seeds = [int(s) for s in a.seeds.split()]
    srcs = {name: shared / "data" / name / f"{name}.clf.gz" for name in logs}
    copies, _ = outlier_logs([(srcs[name], 43, seed) for name in logs for seed in seeds
                              if not only or f"{name}-s{seed}" in only], a.cache, a.jobs)
    jobs: List[Tuple[str, str, Path, List[str]]] = []
    for name in logs:
        variants = [("clean", srcs[name])] + [(f"s{seed}", copies[(str(srcs[name]), 43, seed)])
                                               for seed in seeds if (str(srcs[name]), 43, seed) in copies]
        for variant, path in variants:
            if only and f"{name}-{variant}" not in only:
                continue
            for u in a.updates.split():
                out = a.work / f"{a.label}-{name}-{variant}-{u}.txt"
                cmd = [a.nav, "--carmen", str(path), "--trajectory", str(out), "--quiet",
                       "--set", f"map_update_m={u}"]
                for s in a.set:
                    cmd += ["--set", s]
                jobs.append((name, variant, out, cmd))

    def run(job):
        subprocess.run(job[3], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)

    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        list(pool.map(run, jobs))
    rows: Dict[Tuple[str, str], List[Tuple[float, float, float]]] = {}
    for name in logs:
        rels = ev.load_relations(shared / "data" / name / f"{name}.relations")
        for n, variant, out, _ in jobs:
            if n != name:
                continue
            traj = ev.load_trajectory(out)
            whole = ev.evaluate(traj, rels)
            local = ev.evaluate(traj, rels, max_span=ev.LOCAL_SPAN)
            kind = "clean" if variant == "clean" else "43%"
            rows.setdefault((name, kind), []).append(
                (whole["translation"]["mean"], local["translation"]["mean"], local["rotation"]["mean"]))
    for (name, kind), r in rows.items():
        print(f"{a.label} {name} {kind}: all mean {statistics.mean(x[0] for x in r):.3f} "
              f"median {statistics.median(x[0] for x in r):.3f} m over {len(r)} runs | local "
              f"{statistics.median(x[1] for x in r):.4f} m {statistics.median(x[2] for x in r):.3f} deg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
