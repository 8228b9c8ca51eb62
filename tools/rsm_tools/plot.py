"""rsm-plot: trajectories drawn over an occupancy map image.

    rsm-plot [--map MAP.pgm|MAP.yaml] --trajectory LABEL=FILE ... [--ground-truth FILE]
             [--align-ground-truth LABEL] -o OUT.png [--title T]

The map is a PGM (P5 or P2) with a map_server YAML beside it (same stem,
``.yaml``) or given directly; ``resolution`` (m/pixel) and ``origin`` (x, y
of the lower-left pixel) place it in world coordinates.  Trajectory files
have ``timestamp x y theta`` lines (``#`` comments); the ground truth may
also be the dataset's corrected poses, ``timestamp scan_index x y theta``
(five columns).  Corrected poses live in another frame: with
``--align-ground-truth LABEL`` they are moved rigidly so that the first one
whose stamp is in trajectory LABEL (within 1 ms) coincides with LABEL's pose
there, and the drift after it shows.

Needs matplotlib, the optional extra ``plot``: ``pip install 'rsm-tools[plot]'``.
"""

import argparse
import bisect
import math
import sys
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

from . import evaluate as ev

EXTRA_HINT = ("rsm-plot needs matplotlib, which the core tools do not install; "
              "install the optional extra: pip install 'rsm-tools[plot]' (or: pip install matplotlib)")


class PlotError(Exception):
    pass


def read_pgm(path: Path) -> Tuple[int, int, int, List[int]]:
    """(width, height, maxval, pixels row-major, top row first)."""
    data = path.read_bytes()
    magic = data[:2]
    if magic not in (b"P5", b"P2"):
        raise PlotError(f"{path}: not a PGM image (P5/P2)")
    tokens: List[bytes] = []
    i = 2
    while len(tokens) < 3:
        while i < len(data) and data[i:i + 1].isspace():
            i += 1
        if data[i:i + 1] == b"#":
            while i < len(data) and data[i] not in (10, 13):
                i += 1
            continue
        j = i
        while j < len(data) and not data[j:j + 1].isspace():
            j += 1
        tokens.append(data[i:j])
        i = j
    w, h, maxval = (int(t) for t in tokens)
    if magic == b"P5":
        i += 1
        if maxval > 255:
            raise PlotError(f"{path}: 16-bit PGM not supported")
        px = list(data[i:i + w * h])
    else:
        px = [int(t) for t in data[i:].split()][: w * h]
    if len(px) != w * h:
        raise PlotError(f"{path}: PGM data too short")
    return w, h, maxval, px


def read_map_yaml(path: Path) -> dict:
    """The few map_server keys we need: image, resolution, origin."""
    out: dict = {}
    for line in path.read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if ":" not in line:
            continue
        k, v = (s.strip() for s in line.split(":", 1))
        if k == "origin":
            out[k] = [float(t) for t in v.strip("[]").split(",")]
        elif k == "resolution":
            out[k] = float(v)
        elif k == "image":
            out[k] = v.strip("'\"")
    if "resolution" not in out:
        raise PlotError(f"{path}: no resolution")
    out.setdefault("origin", [0.0, 0.0, 0.0])
    return out


def load_map(arg: str):
    """(pixels as rows top-first, extent [x0, x1, y0, y1]) for a PGM or YAML argument."""
    p = Path(arg)
    if p.suffix in (".yaml", ".yml"):
        meta = read_map_yaml(p)
        pgm = p.parent / meta.get("image", p.with_suffix(".pgm").name)
    else:
        pgm = p
        y = p.with_suffix(".yaml")
        meta = read_map_yaml(y) if y.is_file() else {"resolution": 0.05, "origin": [0.0, 0.0, 0.0]}
    w, h, maxval, px = read_pgm(pgm)
    res = meta["resolution"]
    x0, y0 = meta["origin"][0], meta["origin"][1]
    rows = [[v / maxval for v in px[r * w:(r + 1) * w]] for r in range(h)]
    return rows, [x0, x0 + w * res, y0, y0 + h * res]


Pose = Tuple[float, float, float, float]


def load_trajectory(path: str) -> List[Pose]:
    """(t, x, y, theta) rows in file order of a trajectory, a corrected-pose
    file or a TUM file (rsm_tools.evaluate.read_poses)."""
    return [tuple(p) for p in ev.read_poses(path)[0]]  # type: ignore[misc]


def align_to(truth: Sequence[Pose], traj: Sequence[Pose], tolerance: float = 1e-3) -> List[Pose]:
    """``truth`` moved rigidly so that its first pose with a stamp in ``traj``
    coincides with the trajectory's pose at that stamp."""
    times = sorted((r[0], i) for i, r in enumerate(traj))
    keys = [t for t, _ in times]
    for g in truth:
        k = bisect.bisect_left(keys, g[0] - tolerance)
        if k < len(keys) and abs(keys[k] - g[0]) <= tolerance:
            e = traj[times[k][1]]
            break
    else:
        raise PlotError("no ground-truth stamp is in the trajectory to align to")
    dth = e[3] - g[3]
    c, s = math.cos(dth), math.sin(dth)
    out = []
    for t, x, y, th in truth:
        dx, dy = x - g[1], y - g[2]
        out.append((t, e[1] + c * dx - s * dy, e[2] + s * dx + c * dy, th + dth))
    return out


def _matplotlib():
    try:
        import matplotlib
    except ImportError:
        raise PlotError(EXTRA_HINT) from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def plot(out: str, trajectories: Sequence[Tuple[str, str]], map_arg: Optional[str] = None,
         ground_truth: Optional[str] = None, title: Optional[str] = None,
         align_label: Optional[str] = None) -> None:
    loaded = [(label, load_trajectory(path)) for label, path in trajectories]
    truth = load_trajectory(ground_truth) if ground_truth else None
    if truth is not None and align_label is not None:
        ref = [t for label, t in loaded if label == align_label]
        if not ref:
            raise PlotError(f"--align-ground-truth {align_label}: no trajectory has that label")
        truth = align_to(truth, ref[0])
    plt = _matplotlib()
    fig, ax = plt.subplots(figsize=(8, 8), dpi=100)
    if map_arg:
        rows, extent = load_map(map_arg)
        ax.imshow(rows, cmap="gray", vmin=0.0, vmax=1.0, extent=extent, origin="upper",
                  interpolation="nearest")
    for label, t in loaded:
        ax.plot([r[1] for r in t], [r[2] for r in t], lw=1.2, label=label)
    if truth is not None:
        ax.plot([r[1] for r in truth], [r[2] for r in truth], "k--o", lw=1.0, ms=3, mfc="none",
                label="ground truth" + (f" (anchored to {align_label})" if align_label else ""))
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if title:
        ax.set_title(title)
    ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(out, format="png")
    plt.close(fig)


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-plot", description=__doc__.split("\n\n")[0])
    ap.add_argument("--map", help="PGM map (YAML beside it) or map_server YAML")
    ap.add_argument("--trajectory", action="append", default=[], metavar="LABEL=FILE",
                    help="a trajectory (t x y theta, corrected poses or TUM) drawn as LABEL (repeatable)")
    ap.add_argument("--ground-truth", metavar="FILE", help="ground-truth poses, drawn in black")
    ap.add_argument("--align-ground-truth", metavar="LABEL",
                    help="move the ground truth onto trajectory LABEL at their first common stamp")
    ap.add_argument("-o", "--output", required=True, metavar="OUT.png", help="the PNG to write")
    ap.add_argument("--title", help="the figure's title")
    a = ap.parse_args(argv)
    trajs = []
    for spec in a.trajectory:
        if "=" not in spec:
            ap.error(f"--trajectory wants LABEL=FILE, got {spec!r}")
        trajs.append(tuple(spec.split("=", 1)))
    if not trajs and not a.ground_truth:
        ap.error("nothing to plot: give --trajectory LABEL=FILE and/or --ground-truth FILE")
    try:
        plot(a.output, trajs, a.map, a.ground_truth, a.title, a.align_ground_truth)
    except (PlotError, OSError, ValueError) as exc:
        print(f"rsm-plot: {exc}", file=sys.stderr)
        return 1
    print(f"rsm-plot: wrote {a.output}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
