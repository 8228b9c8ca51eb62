"""The figures the README and the public headers quote, taken from the bench's manifest.

The manifest (bench.json in the work directory) is megabytes of runs and
this machine's paths, so it stays out of the repository; these few figures
go to docs/results/figures.json beside the plots, written by every bench run
and by rsm-bench-report, and committed. tests/py/test_figures.py checks each
figure the README and include/rsm/*.h state against that file, so a figure in
prose cannot drift from what the bench last measured.
"""

import json
from pathlib import Path
from typing import Optional

from .common import PEER_COLUMNS, RUNS
from .parse import best_peers


def _q(scope: str, quantity: str) -> str:
    return f"{scope}_{quantity}"


def _accuracy(ctx: dict) -> dict:
    out = {}
    for log, acc in (ctx.get("accuracy") or {}).items():
        runs = {}
        for run in RUNS:  # the accuracy section's runs, under their names
            if run in acc.get("runs", {}):
                e = acc["runs"][run]["errors"]
                runs[run] = {_q(sc, q): e[sc][q]["mean"] for sc, q in PEER_COLUMNS}
        peers = ((ctx.get("peers") or {}).get("accuracy") or {}).get(log) or []
        best = best_peers(peers) if peers else {}
        runs["best peer"] = {_q(sc, q): {"value": v[0], "method": v[1]}
                             for (sc, q), v in best.items() if v is not None}
        for r in peers:
            if r["kind"] == "before":
                runs["rsm before"] = {_q(sc, q): r["values"].get((sc, q)) for sc, q in PEER_COLUMNS}
        out[log] = runs
    return out


def _state(am: Optional[dict], label: str = "rsm_localizer_t (all of the below)") -> dict:
    out = {}
    for cfg, c in ((am or {}).get("configs") or {}).items():
        rows = [r["bytes"] for r in c.get("state", []) if r["label"] == label]
        if rows:
            out[cfg] = rows[0]
    return out


def _stack(am: Optional[dict]) -> dict:
    c = ((am or {}).get("configs") or {}).get("default") or {}
    return {root: s["bytes"] for root, s in (c.get("stack") or {}).items()}


def extract(ctx: dict) -> dict:
    """The quoted figures of a manifest read by report.context_from_manifest
    (peers keyed by (scope, quantity)); absent sections are left out."""
    prov = ctx.get("provenance") or {}
    out = {"provenance": {k: prov.get(k) for k in ("commit", "date", "cpu", "cores", "compiler", "build_flags")},
           "command": "./tools/bench", "accuracy": _accuracy(ctx)}
    m4_state = _state(ctx.get("arm_memory"))
    if m4_state:
        out["m4_state_bytes"] = m4_state
        out["m4_stack_bound_bytes"] = _stack(ctx.get("arm_memory"))
    host = {r["variant"]: r["sizes"]["rsm_localizer_t"] for r in (ctx.get("scaling") or {}).get("rows", [])
            if r.get("kind") == "preset" and r.get("method") == "rsm"}
    for cfg, c in ((ctx.get("memory") or {}).get("configs") or {}).items():
        host.setdefault(f"config_{cfg}" if cfg == "small" else cfg, c["sizes"]["rsm_localizer_t"])
    if host:
        out["host_state_bytes"] = host
    cost = (ctx.get("m4") or {}).get("cost")
    if cost:
        out["m4_instructions_per_scan"] = {k: cost[k] for k in ("scans", "mean", "p95", "p99", "max")}
        out["m4_stack_painted_bytes"] = cost.get("stack_used")
    cg = ((ctx.get("callgrind") or {}).get("runs") or {}).get("intel:default:rsm")
    if cg:
        out["host_instructions_per_scan"] = {"scans": cg["scans"], "mean": cg["ir_per_scan"]}
    return out


def write(ctx: dict, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(extract(ctx), indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return path
