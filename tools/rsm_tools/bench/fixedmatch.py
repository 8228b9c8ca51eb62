"""The bench's check of the fixed-point map matcher (issue 33, docs/fpu-less.md):
the cores without an FPU build RSM_FIXED_MATCH and so compute their own
trajectory, equal bit for bit to this host's build of the same arithmetic
(the firmware replays' check) but not to the float build's. Its accuracy is
held to the float build's over the same many runs the Faults section makes
clean: the 2 x FAULT_RUNS runs per log that change only ``map_update_m``.

Floors, per log: the fixed build's median all-relations translation within
MEDIAN_TOLERANCE of the float build's (the float build's own median moves
by about that with a change of a micrometre to its reads), and its worst run
at most CLEAN_WORST_X times its median, the clean runs' own floor."""
import statistics
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

from .. import evaluate as ev
from .common import floor
from .faults import errors

MEDIAN_TOLERANCE = 0.05
CLEAN_WORST_X = 3.0


def run(nav_fixed: Path, logs: Sequence[Tuple[str, Path, Path]], work: Path, jobs: int, faults: dict) -> dict:
    """The Faults section's clean runs again with ``nav_fixed``; ``faults`` is
    that section's manifest entry (its update distances and float figures)."""
    from .measure import parallel, run_nav

    ups = faults["clean_updates"]
    tasks = [(label, log, u) for label, log, _ in logs for u in ups]

    def one(task):
        label, log, u = task
        traj = work / "fixed-match" / label / f"clean-{u:.3f}.txt"
        run_nav(nav_fixed, log, "rsm", traj, extra=("--set", f"map_update_m={u:g}"))
        return task, traj

    done = parallel(one, tasks, jobs)
    out = {"nav": str(nav_fixed), "updates": list(ups), "logs": {}}
    for label, _, rel in logs:
        relations = ev.load_relations(rel)
        alls = [errors(ev.load_trajectory(traj), relations)["all"] for (lab, _, _), traj in done if lab == label]
        fl = faults["logs"][label]["clean"]
        out["logs"][label] = {"runs": alls, "median": statistics.median(alls), "max": max(alls),
                              "float_median": fl["median"], "float_max": fl["max"]}
    return out


def floors(fx: Optional[dict]) -> List[dict]:
    if not fx or "logs" not in fx:
        return []
    out = []
    for label, e in fx["logs"].items():
        ratio = e["median"] / e["float_median"]
        ok = abs(ratio - 1.0) <= MEDIAN_TOLERANCE + 1e-9  # the edge itself is within
        out.append(floor("PASS" if ok else "MISS", "fixed-match", label, ratio, MEDIAN_TOLERANCE,
                         f"{label}: fixed-point matcher (RSM_FIXED_MATCH, the soft-float cores' arithmetic), "
                         f"{len(e['runs'])} clean runs, median all-relations translation {e['median']:.4f} m = "
                         f"x{ratio:.3f} the float build's {e['float_median']:.4f} m (within "
                         f"x{1 - MEDIAN_TOLERANCE:.2f} to x{1 + MEDIAN_TOLERANCE:.2f})"))
        ok = e["max"] <= CLEAN_WORST_X * e["median"]
        out.append(floor("PASS" if ok else "MISS", "fixed-match-worst", label, e["max"] / e["median"], CLEAN_WORST_X,
                         f"{label}: fixed-point matcher, worst of {len(e['runs'])} clean runs {e['max']:.4f} m = "
                         f"x{e['max'] / e['median']:.2f} its median (<= x{CLEAN_WORST_X:g}; the float build's worst "
                         f"{e['float_max']:.4f} m)"))
    return out


def report(fx: Optional[dict]) -> List[str]:
    if not fx or "logs" not in fx:
        return []
    L = ["### The fixed-point matcher", "",
         "The cores without an FPU build the map matcher in fixed point (`RSM_FIXED_MATCH`, docs/fpu-less.md), "
         "so their trajectory is their own. This host's build of it (`-DRSM_FIXED_MATCH=ON`), over the clean runs "
         "of the Faults section (the same `map_update_m` values), beside the float build's; all-relations "
         "translation in m.", "",
         "| log | runs | fixed median | fixed worst | float median | float worst |",
         "|---|---|---|---|---|---|"]
    for label, e in fx["logs"].items():
        L.append(f"| {label} | {len(e['runs'])} | {e['median']:.4f} | {e['max']:.4f} | {e['float_median']:.4f} | "
                 f"{e['float_max']:.4f} |")
    return L + [""]
