"""rsm-demo: the figures and the picture of ./tools/demo.

    python -m rsm_tools.demo whole --relations REL --truth POSES --map MAP.pgm \\
        --run rsm=TRAJ --run "the paper's method=TRAJ" --run "odometry alone=TRAJ" \\
        -o PICTURE.png [--json FIGURES.json] [--dpi N]
    python -m rsm_tools.demo table FIGURES.json
    python -m rsm_tools.demo live TRAJ --relations REL [--scans N]

``whole`` scores each run on every relation and on the local ones (spans up
to 2 s), prints them as one short table and draws one picture: the map with
the first run's trajectory over the ground truth (the corrected poses,
anchored to that run at their first common stamp) and the odometry, beside
bars of each run's error. ``live`` prints one line for the short replay over
serial links. The tables are for people; ``--json`` is what a test reads, and ``table`` prints it again.
"""

import argparse
import json
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

from . import evaluate as ev
from . import plot as rp


class DemoError(Exception):
    pass


def _fig(v: float) -> str:
    """Three significant digits, no exponent (0.0152, 2.19, 39.2)."""
    return f"{v:.3g}" if v >= 0.001 else f"{v:.1e}"


def score(traj_path: str, relations: List[ev.Relation]) -> Dict[str, dict]:
    """Mean errors of one trajectory on all relations and on the local ones."""
    traj = ev.load_trajectory(traj_path)
    out = {}
    for scope, res in ev.evaluate_scopes(traj, relations).items():
        out[scope] = {"translation_m": res["translation"]["mean"], "rotation_deg": res["rotation"]["mean"],
                      "matched": res["matched"], "in_span": res["in_span"]}
    out["poses"] = len(traj)
    return out


def table(runs: Sequence[Tuple[str, Dict[str, dict]]]) -> List[str]:
    """The figures as a few lines of text, one run a line."""
    a, l = runs[0][1]["all"], runs[0][1]["local"]
    pad = " " * (max(len(label) for label, _ in runs) + 2)
    lines = ["mean relative-pose error (Kuemmerle et al. 2009)",
             f"{pad}{'all ' + str(a['in_span']) + ' relations':^23}   {'local: ' + str(l['in_span']) + ', up to 2 s':^23}",
             f"{pad}{'translation':>11}{'rotation':>12}   {'translation':>11}{'rotation':>12}"]
    for label, s in runs:
        cells = [f"{_fig(s[scope]['translation_m']):>9} m{_fig(s[scope]['rotation_deg']):>8} deg"
                 for scope in ("all", "local")]
        lines.append(f"  {label:<{len(pad) - 2}}{cells[0]}   {cells[1]}")
    return [line.rstrip() for line in lines]


def picture(out: str, runs: Sequence[Tuple[str, str, Dict[str, dict]]], map_arg: str, truth_path: str,
            title: str, dpi: int, longest_s: float) -> None:
    """Map and trajectories on the left, the runs' errors on the right."""
    plt = rp._matplotlib()
    first_label, first_path, _ = runs[0]
    first = rp.load_trajectory(first_path)
    truth = rp.align_to(rp.load_trajectory(truth_path), first)
    fig = plt.figure(figsize=(12, 6.2), dpi=dpi)
    grid = fig.add_gridspec(2, 2, width_ratios=(1.35, 1.0), hspace=0.45, wspace=0.5)
    ax = fig.add_subplot(grid[:, 0])
    rows, extent = rp.load_map(map_arg)
    ax.imshow(rows, cmap="gray", vmin=0.0, vmax=1.0, extent=extent, origin="upper", interpolation="nearest")
    # The view is the building (where rsm and the ground truth are); drifting
    # odometry leaves it, which is the point of the picture.
    xs = [p[1] for p in first] + [p[1] for p in truth]
    ys = [p[2] for p in first] + [p[2] for p in truth]
    for label, path, _ in runs[1:]:
        if "odometry" in label:
            t = rp.load_trajectory(path)
            ax.plot([p[1] for p in t], [p[2] for p in t], color="tab:blue", lw=0.8, alpha=0.8, label=label)
    ax.plot([p[1] for p in truth], [p[2] for p in truth], "o", color="black", ms=2.2,
            label=f"ground truth ({len(truth)} corrected poses)")
    ax.plot([p[1] for p in first], [p[2] for p in first], color="tab:orange", lw=1.0, label=first_label)
    ax.set_xlim(min(xs) - 2.0, max(xs) + 2.0)
    ax.set_ylim(min(ys) - 2.0, max(ys) + 2.0)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=11)
    ax.legend(loc="upper left", fontsize=8, framealpha=0.9)
    colours = {first_label: "tab:orange"}
    for scope, row, heading in (("all", 0, f"every relation (up to {longest_s / 60:.0f} min apart)"),
                                ("local", 1, f"local relations (up to {ev.LOCAL_SPAN:g} s apart)")):
        bx = fig.add_subplot(grid[row, 1])
        labels = [label for label, _, _ in runs]
        values = [s[scope]["translation_m"] for _, _, s in runs]
        rots = [s[scope]["rotation_deg"] for _, _, s in runs]
        bars = bx.barh(range(len(runs)), values, color=[colours.get(lb, "tab:gray") for lb in labels])
        bx.set_xscale("log")
        bx.set_yticks(range(len(runs)))
        bx.set_yticklabels(labels, fontsize=9)
        bx.invert_yaxis()
        bx.set_xlim(min(values) / 3, max(values) * 40)
        for b, v, r in zip(bars, values, rots):
            bx.text(v * 1.15, b.get_y() + b.get_height() / 2, f"{_fig(v)} m, {_fig(r)}°", va="center", fontsize=9)
        bx.set_xlabel("mean translation error [m], log scale", fontsize=9)
        bx.set_title(heading, fontsize=10)
    fig.savefig(out, format="png", bbox_inches="tight")
    plt.close(fig)


def parse_runs(specs: Sequence[str], ap: argparse.ArgumentParser) -> List[Tuple[str, str]]:
    runs = []
    for spec in specs:
        if "=" not in spec:
            ap.error(f"--run wants LABEL=FILE, got {spec!r}")
        label, path = spec.rsplit("=", 1)
        runs.append((label, path))
    if not runs:
        ap.error("give at least one --run LABEL=FILE (the first is the one drawn over the ground truth)")
    return runs


def whole(args, ap) -> int:
    runs = parse_runs(args.run, ap)
    relations = ev.load_relations(args.relations)
    scored = [(label, path, score(path, relations)) for label, path in runs]
    if args.json:
        Path(args.json).write_text(json.dumps({label: s for label, _, s in scored}, indent=1) + "\n")
    for line in table([(label, s) for label, _, s in scored]):
        print(line)
    longest = max(abs(r.t2 - r.t1) for r in relations)
    picture(args.output, scored, args.map, args.truth, args.title, args.dpi, longest)
    return 0


def show(path: str) -> int:
    runs = json.loads(Path(path).read_text())
    if not isinstance(runs, dict) or not runs:
        raise DemoError(f"{path}: no figures")
    first = next(iter(runs.values()))
    print(f"The whole log, {first['poses']} scans:")
    for line in table(list(runs.items())):
        print(line)
    labels = list(runs)
    if len(labels) > 1:
        best, last = runs[labels[0]]["all"]["translation_m"], runs[labels[-1]]["all"]["translation_m"]
        if best > 0:
            print(f"Over the whole run, {labels[0]}'s error is {last / best:.0f} times smaller than {labels[-1]}'s.")
    return 0


def live(args) -> int:
    relations = ev.load_relations(args.relations)
    traj = ev.load_trajectory(args.trajectory)
    if args.scans is not None and len(traj) != args.scans:
        raise DemoError(f"{args.trajectory}: {len(traj)} poses, not one for each of the {args.scans} scans")
    res = ev.evaluate(traj, relations, max_span=ev.LOCAL_SPAN, tolerance=0.0)
    print(f"   live: {len(traj)} scans fused from the serial links; local error "
          f"{_fig(res['translation']['mean'])} m, {_fig(res['rotation']['mean'])} deg "
          f"({res['matched']} relations up to {ev.LOCAL_SPAN:g} s)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="rsm-demo", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="what", required=True, metavar="{whole,live}")
    w = sub.add_parser("whole", prog="rsm-demo whole", help="the whole log's figures and the picture")
    w.add_argument("--relations", required=True, help="ground-truth relations (t1 t2 x y z roll pitch yaw)")
    w.add_argument("--truth", required=True, help="ground-truth poses drawn in the picture (corrected poses)")
    w.add_argument("--map", required=True, help="the map rsm-nav wrote (PGM with its YAML beside it)")
    w.add_argument("--run", action="append", default=[], metavar="LABEL=FILE",
                   help="a trajectory and its label (repeatable; the first is drawn over the ground truth)")
    w.add_argument("-o", "--output", required=True, metavar="OUT.png", help="the picture to write")
    w.add_argument("--json", metavar="OUT.json", help="write the figures as JSON too")
    w.add_argument("--title", default="", help="the map's title")
    w.add_argument("--dpi", type=int, default=100, help="picture resolution (default %(default)s)")
    tb = sub.add_parser("table", prog="rsm-demo table", help="print the figures `whole --json` wrote")
    tb.add_argument("figures", help="the JSON file of `whole --json`")
    lv = sub.add_parser("live", prog="rsm-demo live", help="one line on the live replay's trajectory")
    lv.add_argument("trajectory", help="the live run's trajectory, restamped to the log's stamps")
    lv.add_argument("--relations", required=True, help="the excerpt's relations")
    lv.add_argument("--scans", type=int, help="fail unless the trajectory has this many poses")
    return ap


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    try:
        if args.what == "whole":
            return whole(args, ap)
        if args.what == "table":
            return show(args.figures)
        return live(args)
    except (DemoError, rp.PlotError, OSError, ValueError) as exc:
        print(f"rsm-demo: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
