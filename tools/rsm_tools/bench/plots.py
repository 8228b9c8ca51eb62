"""The plots of the report (matplotlib, optional): each from the measured figures (JSON-able dicts), to a PNG."""

from pathlib import Path
from typing import Optional

from .common import (KIND_METHODS, LOCAL_SPAN, METHODS, QUANTITIES, ROBUST_METHODS, SCOPES, STAGES, UNITS,
    provenance_line)


NO_MATPLOTLIB = "matplotlib is not installed (it is the optional extra `rsm-tools[bench]`)"


def _pyplot():
    """matplotlib.pyplot on the file-only backend, or None without matplotlib."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    return plt


def _save(plt, fig, path: Path, prov: dict, rect) -> None:
    """Stamps the provenance line at the bottom and writes the PNG (no software tag,
    so reruns on the same data give the same bytes)."""
    fig.text(0.01, 0.005, provenance_line(prov).replace("`", ""), fontsize=6.5, ha="left", va="bottom")
    fig.tight_layout(rect=rect)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100, metadata={"Software": None})
    plt.close(fig)


def plot_turns(turns: dict, path: Path, prov: dict) -> Optional[str]:
    plt = _pyplot()
    if plt is None:
        return NO_MATPLOTLIB
    rows = turns["turns"]
    if not rows:
        return "no turn was found"
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5))
    x = list(range(1, len(rows) + 1))
    w = 0.8 / len(METHODS)
    for j, (key, unit) in enumerate((("translation_cells", "cells"), ("rotation_deg", "deg"))):
        ax = axes[0][j]
        for k, m in enumerate(METHODS):
            vals = [r["residual"][m][key] if r["residual"][m] else float("nan") for r in rows]
            ax.bar([v + (k - (len(METHODS) - 1) / 2) * w for v in x], vals, width=w, label=m)
        ax.set_xticks(x)
        ax.set_xticklabels([f"{i}\n{r['rotation_deg']:.0f}°" for i, r in zip(x, rows)], fontsize=7)
        ax.set_xlabel("turn (fastest first) and its true rotation")
        ax.set_ylabel(f"residual [{unit}]")
        ax.set_title(f"{'translation' if j == 0 else 'rotation'} residual at the {len(rows)} sharpest turns",
                     fontsize=10)
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize=8)
        ax = axes[1][j]
        labels = [b["bin"] for b in turns["bins"]]
        for m, style in zip(METHODS, ("o-", "d-.", "s--", "^:")):
            ax.plot(range(len(labels)), [b["methods"][m][key]["mean"] for b in turns["bins"]], style, label=m)
        ax.set_xticks(range(len(labels)))
        ax.set_xticklabels([f"{lab}\n(n={b['relations']})" for lab, b in zip(labels, turns["bins"])], fontsize=7)
        ax.set_xlabel(f"true rotation of the relation [deg] (local relations, span <= {LOCAL_SPAN:g} s)")
        ax.set_ylabel(f"mean residual [{unit}]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Residuals at sharp turns (cf. the paper's Fig. 8); 1 cell = {turns['cell_m'] * 100:g} cm",
                 fontsize=11)
    _save(plt, fig, path, prov, (0, 0.03, 1, 0.96))
    return None


def plot_scaling(sc: dict, path: Path, prov: dict) -> Optional[str]:
    plt = _pyplot()
    if plt is None:
        return NO_MATPLOTLIB
    fig, axes = plt.subplots(2, 2, figsize=(12, 8))
    styles = dict(zip(ROBUST_METHODS, ("o-", "d-.", "s--")))
    for ax, kind, xlabel in ((axes[0][0], "beams", "readings per scan"),
                             (axes[0][1], "map", "side of the paper's window [cells]")):
        for m in KIND_METHODS[kind]:
            sel = sorted((r for r in sc["rows"] if r["kind"] == kind and r["method"] == m),
                         key=lambda r: r["value"])
            if not sel:
                continue
            xs = [r["beams"] if kind == "beams" else r["config"]["RSM_MAP_SIZE"] for r in sel]
            ax.plot(xs, [r["call"]["median_us"] for r in sel], styles[m], label=f"{m} median")
            ax.plot(xs, [r["call"]["p95_us"] for r in sel], styles[m], alpha=0.4, label=f"{m} p95")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("time per scan [us]")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    ax = axes[1][0]
    sel = sorted((r for r in sc["rows"] if r["kind"] == "tiles"), key=lambda r: r["value"])
    if sel:
        xs = [r["value"] for r in sel]
        ax.plot(xs, [r["local"]["translation"] for r in sel], "o-", label="local translation [m]")
        ax.plot(xs, [r["all"]["translation"] for r in sel], "s--", label="all translation [m]")
        ax.set_yscale("log")
    ax.set_xlabel("RSM_TMAP_TILES (tiles in the pool)")
    ax.set_ylabel("rsm's mean error [m]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax = axes[1][1]
    for kind, style, xlabel, x in (
            ("beams", "o-", "RSM_MAX_BEAMS", lambda r: r["config"]["RSM_MAX_BEAMS"]),
            ("map", "s--", "window cells / 100", lambda r: r["config"]["RSM_MAP_SIZE"] ** 2 / 100),
            ("tiles", "^:", "tiles / 10", lambda r: r["config"]["RSM_TMAP_TILES"] / 10)):
        pts = sorted({(x(r), r["sizes"]["rsm_localizer_t"]) for r in sc["rows"] if r["kind"] == kind})
        if pts:
            ax.plot([p_[0] for p_ in pts], [p_[1] / 1024 for p_ in pts], style, label=xlabel)
    ax.set_xlabel("capacity")
    ax.set_ylabel("sizeof(rsm_localizer_t) [KiB]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.suptitle("Scaling: time per scan against readings and window size; rsm's error and the state "
                 "against capacities", fontsize=11)
    _save(plt, fig, path, prov, (0, 0.03, 1, 0.95))
    return None


def plot_stages(st: dict, path: Path, prov: dict) -> Optional[str]:
    plt = _pyplot()
    if plt is None:
        return NO_MATPLOTLIB
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
    ax = axes[0]
    labelled = set()
    for k, m in enumerate(ROBUST_METHODS):
        left = 0.0
        for s in STAGES:
            v = st["methods"][m]["timing"][s]["mean_us"]
            if v <= 0:
                continue
            ax.barh(k, v, left=left, label=s if s not in labelled else None, color=f"C{STAGES.index(s)}")
            labelled.add(s)
            left += v
    ax.set_yticks(range(len(ROBUST_METHODS)))
    ax.set_yticklabels(ROBUST_METHODS)
    ax.set_xlabel("mean time per scan [us] (stages stacked)")
    ax.legend(fontsize=7, ncol=3)
    ax.grid(True, axis="x", alpha=0.3)
    ax = axes[1]
    shown = [s for s in STAGES if any(st["methods"][m]["timing"][s]["reached"] for m in ROBUST_METHODS)]
    bars = [(m, q) for m in ROBUST_METHODS for q in ("median_reached_us", "p95_reached_us")]
    w = 0.8 / len(bars)
    for k, (m, q) in enumerate(bars):
        ax.bar([i + (k - (len(bars) - 1) / 2) * w for i in range(len(shown))],
               [st["methods"][m]["timing"][s][q] for s in shown], width=w,
               label=f"{m} {'median' if q.startswith('median') else 'p95'}")
    ax.set_xticks(range(len(shown)))
    ax.set_xticklabels(shown, fontsize=8)
    ax.set_yscale("log")
    ax.set_ylabel("time per scan that reached the stage [us]")
    ax.legend(fontsize=7)
    ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle("Time per stage of rsm_localizer_scan (timing hook, CLOCK_MONOTONIC)", fontsize=11)
    _save(plt, fig, path, prov, (0, 0.04, 1, 0.94))
    return None


def plot_robustness(rob: dict, path: Path, prov: dict, odometry: Optional[dict] = None,
                    label: str = "") -> Optional[str]:
    """Draws the robustness curves; returns None or why there is no plot."""
    plt = _pyplot()
    if plt is None:
        return NO_MATPLOTLIB
    levels = rob["levels"]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5), sharex=True)
    for i, s in enumerate(SCOPES):
        for j, q in enumerate(QUANTITIES):
            ax = axes[i][j]
            for m, style in zip(ROBUST_METHODS, ("o-", "d-.", "s--")):
                rows = [rob["table"][f"{m}:{lv}"][f"{s}.{q}"] for lv in levels]
                means = [r["mean"] for r in rows]
                err = [[r["mean"] - r["min"] for r in rows], [r["max"] - r["mean"] for r in rows]]
                ax.errorbar(levels, means, yerr=err, fmt=style, capsize=3, label=m)
            if odometry is not None:
                ax.axhline(odometry[s][q]["mean"], color="gray", linestyle=":",
                           label="odometry (uses no scans)")
            scope = f"local relations (span <= {LOCAL_SPAN:g} s)" if s == "local" else "all relations"
            ax.set_title(f"{q}, {scope}", fontsize=10)
            ax.set_ylabel(f"mean error [{UNITS[q]}]")
            ax.set_yscale("log")  # the methods differ by orders of magnitude on all relations
            ax.grid(True, which="both", alpha=0.3)
            if i == 1:
                ax.set_xlabel("outliers in every scan [%]")
            ax.legend(fontsize=8)
    n = len(rob["seeds"])
    fig.suptitle(f"Robustness on {label}: relative-pose error vs outliers (mean over {n} seed"
                 f"{'s' if n != 1 else ''}, bars min..max)", fontsize=11)
    _save(plt, fig, path, prov, (0, 0.03, 1, 0.96))
    return None
