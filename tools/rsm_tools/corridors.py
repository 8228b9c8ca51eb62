"""Bare corridors in simulation: rsm against odometry alone where the logs have none.

Intel and ACES have doors or clutter every few metres.  Along bare walls
nothing in a scan fixes the position along the corridor, which should then
be odometry's to keep; a scan-to-map matcher can instead be pulled back
along the walls by how they were written (``docs/map.md``, "Bare
corridors").  ``./tools/bench`` simulates two worlds of ``rsm-sim`` as CARMEN
logs: ``hall``, a bare 40 m corridor driven there and back, and
``building``, a 112 m ring of corridors with door recesses in its outer
walls, each with 1 and 3 cm of range noise and wheels that slip
(``--slip 0.08``), and runs rsm-nav's default method and odometry alone on
them.  The measure is the mean translation error of every pair of poses at
most 30 s apart, against the simulator's true poses; each line is a PASS
when rsm's is below odometry's, a MISS when it is not (the issue's failure
on an unseen log: worse than odometry alone).

The simulator is seeded, so the logs and the figures are the same on every
machine.  Logs are kept in the work folder and reused when their settings
match.

Run alone::

    python -m rsm_tools.corridors --nav build-release/tools/nav/rsm-nav --work /tmp/corridors
"""

import argparse
import sys
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

from . import evaluate as ev
from . import sim
from .bench.measure import run_nav
from .fullchecks import check

#: (world, seconds) of the full bench; --quick drives each for QUICK_SECONDS
WORLDS: Tuple[Tuple[str, float], ...] = (("hall", 180.0), ("building", 900.0))
QUICK_SECONDS = 40.0
NOISES_M = (0.01, 0.03)
SLIP = 0.08
SEED = 5
SPAN_S = 30.0


def simulate(work: Path, world: str, seconds: float, noise: float) -> Tuple[Path, Path]:
    """The log and its truth, made once per settings."""
    stem = f"{world}-{seconds:g}s-noise{noise:g}-slip{SLIP:g}-seed{SEED}"
    log, truth = work / f"{stem}.clf.gz", work / f"{stem}.truth.txt"
    if not (log.is_file() and truth.is_file()):
        sim.simulate(log, truth, world, seconds=seconds, slip=SLIP, range_noise=noise, seed=SEED, carmen=True)
    return log, truth


def span_error(traj: Path, truth: Path) -> float:
    """Mean translation error of the pose pairs up to SPAN_S apart."""
    rels = ev.relations_from_poses(ev.load_trajectory(truth), max_span=SPAN_S)
    return ev.evaluate(ev.load_trajectory(traj), rels)["translation"]["mean"]


def run(nav: Path, work: Path, quick: bool = False) -> List[dict]:
    """One PASS/MISS line per world and noise level."""
    work.mkdir(parents=True, exist_ok=True)
    out = []
    for world, seconds in WORLDS:
        secs = QUICK_SECONDS if quick else seconds
        for noise in NOISES_M:
            log, truth = simulate(work, world, secs, noise)
            errs = {}
            for method in ("rsm", "odometry"):
                traj = work / f"{log.name[:-len('.clf.gz')]}.{method}.txt"
                run_nav(nav, log, method, traj)
                errs[method] = span_error(traj, truth)
            mine, odo = errs["rsm"], errs["odometry"]
            out.append(check(mine < odo, "corridors", world,
                             f"{world} (rsm-sim, {secs:g} s, range noise {noise * 100:g} cm, wheel slip {SLIP:g}): "
                             f"rsm {mine:.4f} m against odometry alone {odo:.4f} m, mean translation error of pose "
                             f"pairs up to {SPAN_S:g} s apart",
                             value=mine, limit=odo))
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-corridors", description=__doc__.split("\n\n")[0])
    ap.add_argument("--nav", required=True, type=Path, help="the rsm-nav to run")
    ap.add_argument("--work", required=True, type=Path, help="folder for the logs and trajectories")
    ap.add_argument("--quick", action="store_true", help=f"drive each world {QUICK_SECONDS:g} s only")
    a = ap.parse_args(argv)
    for c in run(a.nav, a.work, a.quick):
        print(c["line"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
