"""The report: docs/RESULTS.md from the measured figures as the manifest (bench.json) holds them, and the
analyses written into that manifest before it: the issue's floors and "where rsm loses". rsm-bench writes
the report from the manifest it has just written; `rsm-bench-report MANIFEST` writes it again from a
manifest alone (the same text for the same manifest and repository)."""

import argparse
import json
import math
import re
import sys
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from .. import consistency, fullchecks, outliers
from .common import (CG_STAGE_ORDER, DRIVER_OBJECTS, HOST_PARTS, LOCAL_SPAN, MEMORY_OTHER, METHODS, PEER_COLUMNS,
    QUANTITIES, ROBUST_METHODS, RUNS, SCOPES, SECTION_TITLES, SMALL, SMALL_HEADER, STAGES, STAGE_WHAT, UNITS,
    BenchError, cg_run, find_root, floor, fmt_int, fmt_pct, fmt_q, fmt_ratio, provenance_line, ratio, run_build,
    run_labels, shown_path)
from . import figures
from .faults import report_faults
from . import fixedmatch as _fixedmatch
from .knownmap import report_knownmap
from .parse import best_peers, fused_percent


def m4_lines(m: Optional[dict]) -> List[str]:
    """What tools/bench prints about the target (and the report repeats)."""
    if not m or "skipped" in m:
        return [f"Cortex-M4F: not measured ({(m or {}).get('skipped', 'disabled')})"]
    c = m["cost"]
    L = [f"Cortex-M4F -O2 (QEMU mps2-an386, -icount shift={m['icount_shift']}), {c['scans']} scans of the "
         f"excerpt: instructions per scan mean {fmt_int(round(c['mean']))}, p95 {fmt_int(round(c['p95']))}, "
         f"p99 {fmt_int(round(c['p99']))}, max {fmt_int(round(c['max']))}"]
    h = m.get("host", {})
    if "skipped" not in h:
        L.append(f"host x86-64 (callgrind, same excerpt and source): {fmt_int(round(h['ir_per_scan']))} "
                 f"instructions per scan; trajectories {'bit-identical' if h['identical'] else 'DIFFERENT'}")
    L.append(global_line(m.get("global")))
    L += variant_lines(m.get("variants"))
    for name, im in m["images"].items():
        stack = ("n/a" if im["stack_used"] is None else f"{fmt_int(im['stack_used'])} of {fmt_int(im['stack_size'])}")
        extra = f" (of which the excerpt {fmt_int(im['excerpt'])})" if im["excerpt"] else ""
        L.append(f"{name} image: flash {fmt_int(im['flash'])} bytes{extra}, RAM {fmt_int(im['ram'])} bytes "
                 f"(stack included), stack used {stack} bytes")
    return L


VARIANT_NAMES = {"m4-Os": "Cortex-M4F -Os", "m3-O2": "Cortex-M3 soft float -O2",
                 "m0plus-O2": "Cortex-M0+ soft float -O2"}


def variant_lines(v: Optional[dict]) -> List[str]:
    """The replay at -Os, on the Cortex-M3 and the Cortex-M0+ image's size
    (run_m4's "variants"), a line each."""
    if not v:
        return []
    L = []
    for key, name in VARIANT_NAMES.items():
        x = v.get(key)
        if not x:
            continue
        c = x["cost"]
        same = {None: "", True: "; trajectory bit-identical to the host's",
                False: "; trajectory DIFFERENT from the host's"}[x["identical"]]
        L.append(f"{name} (QEMU {x['machine']}): instructions per scan mean {fmt_int(round(c['mean']))}, p95 "
                 f"{fmt_int(round(c['p95']))}, p99 {fmt_int(round(c['p99']))}, max {fmt_int(round(c['max']))}{same}")
    m0 = v.get("m0plus")
    if m0:
        L.append(f"Cortex-M0+ ({m0['name']}.elf, links only): flash {fmt_int(m0['image']['flash'])} bytes, RAM "
                 f"{fmt_int(m0['image']['ram'])} bytes (stack and the LD06's buffers included)")
    return L


def global_line(g: Optional[dict]) -> str:
    """The global search's cost on the target (run_m4's "global"), one line."""
    what = "global search (map-in-flash image, the excerpt's map"
    if not g or "skipped" in g:
        return f"{what}): not measured ({(g or {}).get('skipped', 'not run')})"
    found = (f"first proven pose after {g['scans_to_pose']} scans" if g["proven"] else
             f"no pose proven within {g['scans']} scans")
    return (f"{what}, {fmt_int(g['map_tiles'])} tiles, global_budget {fmt_int(g['budget'])}): instructions per scan "
            f"worst {fmt_int(round(g['max']))}, mean {fmt_int(round(g['mean']))} over {g['scans']} scans; {found}")


def report_m4(m: Optional[dict]) -> List[str]:
    L = ["### On the target: Cortex-M4F", ""]
    if not m or "skipped" in m:
        return L + [m4_lines(m)[0] + ".", ""]
    c = m["cost"]
    cal = c["calibration"]
    L += [f"The replay firmware (`port/baremetal/replay/`) runs the shipped excerpt (`tests/data/intel_head.clf.gz`, "
          f"encoder counts and scans compiled in) through the localizer, default configuration, built with "
          f"{m['compiler']} at `-O2`, on QEMU's mps2-an386 ({m['qemu']}) with `-icount shift={m['icount_shift']}`: "
          f"the virtual clock advances {1 << m['icount_shift']} ns per instruction, so the board's 25 MHz timer, "
          f"read by the localizer's `clock_fn`, counts one tick per {cal['per_tick']:g} instructions. Calibration: "
          f"a known loop of {fmt_int(cal['insns'])} instructions measured {fmt_int(round(cal['measured']))}. "
          "QEMU counts instructions, not cycles: on a real M4 at 168 MHz the cycles are at least as many "
          "(flash wait states, divides, loads).", ""]
    rows = [["mean", fmt_int(round(c["mean"]))], ["p95", fmt_int(round(c["p95"]))],
            ["p99", fmt_int(round(c["p99"]))], ["max", fmt_int(round(c["max"]))]]
    h = m.get("host", {})
    if "skipped" not in h:
        rows.append(["host x86-64, callgrind, mean", fmt_int(round(h["ir_per_scan"]))])
    L += md_table(["instructions per scan", "value"], rows, "speed m4")
    L += md_table(["stage", "M4 instructions per scan (mean)"],
                  [[k, fmt_int(round(v))] for k, v in c["stages"].items() if v > 0], "speed m4 stages")
    L += report_variants(m.get("variants"), c, (m.get("host") or {}).get("identical"))
    rows = []
    for name, im in m["images"].items():
        rows.append([name, fmt_int(im["flash"]), fmt_int(im["excerpt"]), fmt_int(im["ram"]),
                     "n/a" if im["stack_used"] is None else fmt_int(im["stack_used"]),
                     "n/a" if im["stack_size"] is None else fmt_int(im["stack_size"])])
    L += md_table(["image", "flash [bytes]", "of which excerpt", "RAM [bytes]", "stack used (painted)",
                   "stack reserved"], rows, "memory m4 images")
    if "skipped" not in h:
        L += [("The host's trajectory of the same excerpt is bit-identical to the target's."
               if h["identical"] else "WARNING: the host's trajectory differs from the target's."), ""]
    g = m.get("global")
    if not g or "skipped" in g:
        return L + [f"The {global_line(g)}.", ""]
    L += ["The global search (issue 31's cost floor; the subsection \"Known map\"): the map-in-flash firmware "
          f"(`port/baremetal/mapflash/`) maps the excerpt's first {g['mapped_scans']} scans, saves the map "
          f"({fmt_int(g['map_bytes'])} bytes, {fmt_int(g['map_tiles'])} tiles: a small map), resets, loads it, "
          "then sets the localizer up again, loads the map again and searches it globally with no pose "
          f"(`rsm_localizer_global`, default configuration: at most {fmt_int(g['budget'])} reads a scan) over the "
          "scans after the mapped ones, until a pose is trusted. Each `rsm_localizer_scan` is timed on the board's "
          "timer (the same calibration); its outcomes and reads equal those of the same source on the host "
          "(`rsm-m4 mapflash`).", ""]
    rows = [["scans searched", str(g["scans"])],
            ["first proven pose after [scans]", "none" if not g["proven"] else str(g["scans_to_pose"])],
            ["reads in one scan, at most", fmt_int(g["max_work"])], ["reads in all", fmt_int(g["work"])],
            ["instructions per scan, mean", fmt_int(round(g["mean"]))],
            ["instructions per scan, worst", fmt_int(round(g["max"]))]]
    L += md_table(["global search on the M4", "value"], rows, "speed m4 global")
    return L


def report_variants(v: Optional[dict], c: dict, same: Optional[bool]) -> List[str]:
    """The table of the replay's cost per build (the -O2 M4's c, whose
    trajectory is the host's or not by callgrind's run (same), beside
    run_m4_variants'), by stage, and the Cortex-M0+ image."""
    if not v:
        return []
    keys = [k for k in VARIANT_NAMES if k in v]
    costs = [c] + [v[k]["cost"] for k in keys]
    L = ["The same replay on the other builds (issue 33): the M4F at `-Os`, a Cortex-M3 with no FPU "
         "(`cmake/toolchain-arm-cortex-m3.cmake`, `-mfloat-abi=soft`: every float operation a call into libgcc) "
         "on QEMU's mps2-an385, the same board with an M3, and the Cortex-M0+ build "
         "(`cmake/toolchain-arm-cortex-m0plus.cmake`) on that M3 too: ARMv6-M code is a subset of the M3's, so "
         "these are the M0+'s instructions (its cycles are more: two-cycle loads and branches, flash wait "
         "states). Every figure counts the encoder steps since the previous scan (the stage odometry).", ""]
    rows = [[stat] + [fmt_int(round(x[stat])) for x in costs] for stat in ("mean", "p95", "p99", "max")]
    stages = [k for k in c["stages"] if any(x["stages"].get(k, 0) > 0 for x in costs)]
    rows += [[f"stage {k} (mean)"] + [fmt_int(round(x["stages"].get(k, 0.0))) for x in costs] for k in stages]
    said = {None: "n/a", True: "yes", False: "NO"}
    rows.append(["trajectory as the host's"] + [said[same]] + [said[v[k]["identical"]] for k in keys])
    L += md_table(["instructions per scan", "Cortex-M4F -O2"] + [VARIANT_NAMES[k] for k in keys], rows,
                  "speed m4 variants")
    m0 = v.get("m0plus")
    if m0:
        L += [f"The Cortex-M0+ build (`cmake/toolchain-arm-cortex-m0plus.cmake`) links the LD06 example for an "
              f"RP2040 (`{m0['name']}.elf`, docs/bringup-rp2040.md): flash {fmt_int(m0['image']['flash'])} bytes, "
              f"RAM {fmt_int(m0['image']['ram'])} bytes with its stack and the LD06's buffers.", ""]
    return L


FLOOR_LEVEL = 43


FLOOR_ROBUST = {"local": 1.10, "all": 1.25}  # outlier error over the clean one, translation


FLOOR_ARM_BYTES = {"default": 128 * 1024, "small": 64 * 1024}


FLOOR_IR_PER_SCAN = 1.2e6


# Issue 11's cost on the target: instructions per scan of the replay
# firmware (the excerpt, -O2, default configuration), the encoder steps
# included; issue 33's on the M4F at -Os and on a Cortex-M3 with soft
# float, and the RAM of the Cortex-M0+ image.
FLOOR_M4 = (("mean", 300000), ("p99", 600000))
FLOOR_M3 = (("mean", 1500000), ("p99", 3000000))
FLOOR_M0PLUS_RAM = 200 * 1024


PEER_FLOORS = (("all", "translation"), ("local", "translation"), ("local", "rotation"))


# The figures the issue names (issue 29: the peers as re-measured); peers.md
# lists more peer variants, some lower, and both are checked.
ISSUE_FLOORS = {
    "intel": {("all", "translation"): 0.023, ("local", "translation"): 0.0133, ("local", "rotation"): 0.26},
    "aces": {("all", "translation"): 0.076, ("local", "translation"): 0.040, ("local", "rotation"): 0.43},
}


def _scope_name(scope: str) -> str:
    return "all-relations" if scope == "all" else "local"


def check_floors(rsm: Dict[str, dict], peers: Optional[Dict[str, List[dict]]], robust: Dict[str, dict],
                 arm_bytes: Dict[str, Optional[int]], ir: dict) -> List[dict]:
    """The floors of the issue, each PASS, MISS or SKIP (not measured) with its line.

    rsm: per log, rsm's errors (errors[scope][quantity]["mean"]);
    peers: parse_peers()["accuracy"], or None when peers.md is absent;
    robust: per log, rsm's translation errors {"clean": {scope: m}, "noisy":
    {seed: {scope: m}}} at FLOOR_LEVEL % outliers; arm_bytes: sizeof
    (rsm_localizer_t) on Cortex-M4F per configuration (None: not measured);
    ir: {"log", "scans", "ir_per_scan"} of rsm at the default configuration,
    or {"skipped": why}."""
    out = []
    for log, e in rsm.items():
        rows = None if peers is None else peers.get(log)
        best = best_peers(rows) if rows else {}
        for scope, q in PEER_FLOORS:
            mine = e[scope][q]["mean"]
            u = UNITS[q]
            what = f"{log}: {_scope_name(scope)} {q} {fmt_q(q, mine)} {u}"
            b = best.get((scope, q))
            if peers is None:
                out.append(floor("SKIP", "peers", log, mine, None, f"{what}: no peer figures (peers.md is not "
                                                                     "on this machine)"))
            elif b is None:
                out.append(floor("SKIP", "peers", log, mine, None, f"{what}: peers.md has no peer figure "
                                                                     "for this log"))
            else:
                ok = mine <= b[0]
                out.append(floor("PASS" if ok else "MISS", "peers", log, mine, b[0],
                                 f"{what} {'<=' if ok else '>'} {fmt_q(q, b[0])} {u}, the best peer's ({b[1]})"))
            lim = ISSUE_FLOORS.get(log, {}).get((scope, q))
            if lim is not None:
                ok = mine <= lim
                out.append(floor("PASS" if ok else "MISS", "issue", log, mine, lim,
                                 f"{what} {'<=' if ok else '>'} {fmt_q(q, lim)} {u}, the issue's floor"))
    for log, r in robust.items():
        seeds = sorted(r["noisy"])
        for scope in SCOPES:
            lim = FLOOR_ROBUST[scope]
            clean = r["clean"][scope]
            what = f"{log}: {FLOOR_LEVEL} % outliers, {_scope_name(scope)} translation"
            if not seeds:
                out.append(floor("SKIP", "robustness", log, None, lim, f"{what}: not measured"))
                continue
            ratios = [ratio(r["noisy"][sd][scope], clean) for sd in seeds]
            ok = all(math.isfinite(x) and x <= lim for x in ratios)
            shown = ", ".join(f"{fmt_q('translation', r['noisy'][sd][scope])} m = x{x:.3f} (seed {sd})"
                              for sd, x in zip(seeds, ratios))
            out.append(floor("PASS" if ok else "MISS", "robustness", log, max(ratios), lim,
                             f"{what} {shown} of the clean {fmt_q('translation', clean)} m; "
                             f"{'every' if ok else 'not every'} seed <= x{lim:.2f}"))
    for name, lim in FLOOR_ARM_BYTES.items():
        b = arm_bytes.get(name)
        cfg = "the default config.h" if name == "default" else SMALL_HEADER
        what = f"Cortex-M4F: sizeof(rsm_localizer_t) with {cfg}"
        if b is None:
            out.append(floor("SKIP", "memory", None, None, lim, f"{what}: not measured"))
        else:
            ok = b <= lim
            out.append(floor("PASS" if ok else "MISS", "memory", None, b, lim,
                             f"{what} {fmt_int(b)} bytes ({b / 1024:.1f} KiB) {'<=' if ok else '>'} "
                             f"{lim // 1024} KiB"))
    if "skipped" in ir:
        out.append(floor("SKIP", "instructions", ir.get("log"), None, FLOOR_IR_PER_SCAN,
                         f"instructions per scan: not measured ({ir['skipped']})"))
    else:
        v = ir["ir_per_scan"]
        ok = v <= FLOOR_IR_PER_SCAN
        out.append(floor("PASS" if ok else "MISS", "instructions", ir["log"], v, FLOOR_IR_PER_SCAN,
                         f"{ir['log']}: {fmt_int(round(v))} instructions per scan (callgrind, first "
                         f"{ir['scans']} scans, default config.h) {'<=' if ok else '>'} "
                         f"{fmt_int(round(FLOOR_IR_PER_SCAN))}"))
    return out


def m4_floors(m4: Optional[dict]) -> List[dict]:
    """Issue 11's floors on the replay firmware's instructions per scan
    (run_m4) and issue 33's on its other builds, each PASS, MISS or SKIP."""
    m4 = m4 or {}
    variants = m4.get("variants") or {}
    why = m4.get("skipped", "not run")
    out: List[dict] = []
    builds = (("m4", "Cortex-M4F", "-O2", m4.get("cost"), FLOOR_M4),
              ("m4", "Cortex-M4F", "-Os", (variants.get("m4-Os") or {}).get("cost"), FLOOR_M4),
              ("m3", "Cortex-M3 soft float", "-O2", (variants.get("m3-O2") or {}).get("cost"), FLOOR_M3))
    for kind, core, opt, cost, floors in builds:
        for stat, lim in floors:
            what = (f"{core}: {stat} instructions per scan of the replay firmware (the excerpt, {opt}, QEMU, "
                    "encoder steps included)")
            if not cost:
                out.append(floor("SKIP", kind, None, None, lim, f"{what}: not measured ({why})"))
                continue
            v = cost[stat]
            ok = v <= lim
            out.append(floor("PASS" if ok else "MISS", kind, None, v, lim,
                             f"{what} {fmt_int(round(v))} {'<=' if ok else '>'} {fmt_int(lim)} "
                             f"(over {cost['scans']} scans)"))
    m3 = variants.get("m3-O2")
    what = "Cortex-M3 soft float: the replay's trajectory bit-identical to the host's (both fixed-point matcher)"
    if not m3 or m3["identical"] is None:
        out.append(floor("SKIP", "m3", None, None, None, f"{what}: not measured ({why if not m3 else 'no host run'})"))
    else:
        out.append(floor("PASS" if m3["identical"] else "MISS", "m3", None, m3["identical"], True,
                         f"{what}: {'yes' if m3['identical'] else 'no'} (over {m3['cost']['scans']} scans)"))
    m0 = variants.get("m0plus")
    what = f"Cortex-M0+: RAM of the RP2040 LD06 example, stack and lidar buffers included"
    if not m0:
        out.append(floor("SKIP", "m0plus", None, None, FLOOR_M0PLUS_RAM, f"{what}: not measured ({why})"))
    else:
        ram = m0["image"]["ram"]
        ok = ram <= FLOOR_M0PLUS_RAM
        out.append(floor("PASS" if ok else "MISS", "m0plus", None, ram, FLOOR_M0PLUS_RAM,
                         f"{what} {fmt_int(ram)} {'<=' if ok else '>'} {fmt_int(FLOOR_M0PLUS_RAM)} bytes (flash "
                         f"{fmt_int(m0['image']['flash'])})"))
    return out


def spread_ratio(noisy: dict, clean: dict) -> Tuple[float, float]:
    """The ratio of two sample means (measure.spread) and its standard error."""
    r = ratio(noisy["mean"], clean["mean"])
    rel = [x["se"] / x["mean"] for x in (noisy, clean) if x["n"] > 1 and x["mean"] > 0]
    se = r * math.sqrt(sum(v * v for v in rel)) if len(rel) == 2 and math.isfinite(r) else float("nan")
    return r, se


def spread_floors(sp: Optional[dict]) -> List[dict]:
    """The outlier floors again, between the means of the spread section's
    runs (run_spread) instead of between single runs."""
    out: List[dict] = []
    if not sp or "skipped" in sp:
        return out
    for log, r in sp["logs"].items():
        for scope in SCOPES:
            lim = FLOOR_ROBUST[scope]
            c, nz = r["clean"][scope], r["noisy"][scope]
            what = (f"{log}: {sp['level']} % outliers over {nz['n']} runs (seeds "
                    f"{' '.join(str(s) for s in sp['seeds'])}, map_update_m {sp['updates'][0]:g} to "
                    f"{sp['updates'][-1]:g}), {_scope_name(scope)} translation")
            if nz["n"] == 0 or c["n"] == 0:
                out.append(floor("SKIP", "robustness-runs", log, None, lim, f"{what}: not measured"))
                continue
            x, se = spread_ratio(nz, c)
            ok = math.isfinite(x) and x <= lim
            out.append(floor("PASS" if ok else "MISS", "robustness-runs", log, x, lim,
                             f"{what}, mean {fmt_q('translation', nz['mean'])} m = x{x:.3f} (+-{se:.3f}) of the "
                             f"clean runs' mean {fmt_q('translation', c['mean'])} m ({c['n']} runs) "
                             f"{'<=' if ok else '>'} x{lim:.2f}"))
    return out


def floor_inputs(ctx: dict) -> dict:
    """The arguments of check_floors from a bench run's results."""
    acc, rob, am, cg = ctx["accuracy"], ctx.get("robustness"), ctx.get("arm_memory"), ctx.get("callgrind")
    rsm = {label: a["runs"]["rsm"]["errors"] for label, a in acc.items()}
    pe = ctx.get("peers") or {}
    peers = None if "skipped" in pe or "accuracy" not in pe else pe["accuracy"]
    robust = {}
    for label, r in ((rob or {}).get("logs") or {}).items():
        if FLOOR_LEVEL not in r["levels"]:
            continue
        noisy = {x["seed"]: {sc: x["errors"][sc]["translation"]["mean"] for sc in SCOPES}
                 for x in r["runs"] if x["method"] == "rsm" and x["level"] == FLOOR_LEVEL}
        clean = {sc: acc[label]["runs"]["rsm"]["errors"][sc]["translation"]["mean"] for sc in SCOPES}
        robust[label] = {"clean": clean, "noisy": noisy}
    arm = {}
    for name in FLOOR_ARM_BYTES:
        c = ((am or {}).get("configs") or {}).get(name)
        arm[name] = c["state"][0]["bytes"] if c and c.get("state") else None
    main = ctx["main_label"]
    run = cg_run(cg, main, "default", "rsm")
    if run is not None:
        ir = {"log": main, "scans": run["scans"], "ir_per_scan": run["ir_per_scan"]}
    else:
        ir = {"log": main, "skipped": (cg or {}).get("skipped", "no callgrind run of rsm on " + main)}
    return {"rsm": rsm, "peers": peers, "robust": robust, "arm_bytes": arm, "ir": ir}


def _better(a: float, b: float) -> bool:
    return a is not None and b is not None and math.isfinite(a) and math.isfinite(b) and a < b


def losses(ctx: dict) -> List[str]:
    """Every measure of this run on which something else does better than
    rsm, as sentences; also the floors missed and the narrow wins."""
    acc = ctx["accuracy"]
    main = ctx["main_label"]
    items: List[str] = []
    floors = ctx.get("floors") or []
    missed = [f["line"][5:] for f in floors if f["status"] == "MISS"]
    if missed:
        items.append(f"Floors missed ({len(missed)} of {len(floors)}): " + "; ".join(missed) + ".")
    pe = ctx.get("peers") or {}
    peers = None if "skipped" in pe or "accuracy" not in pe else pe["accuracy"]
    for label, a in acc.items():
        e = a["runs"]["rsm"]["errors"]
        rows = (peers or {}).get(label) or []
        if peers is not None and rows:
            lost = []
            for scope, q in PEER_COLUMNS:
                mine = e[scope][q]["mean"]
                better = [r for r in rows if r["kind"] == "peer" and _better(r["values"][(scope, q)], mine)]
                if better:
                    lost.append(f"{_scope_name(scope)} {q} (rsm {fmt_q(q, mine)} {UNITS[q]}; "
                                + ", ".join(f"{r['method']} {fmt_q(q, r['values'][(scope, q)])}" for r in better)
                                + ")")
            if lost:
                items.append(f"On `{label}`, peers of peers.md are below rsm on: " + "; ".join(lost) + ".")
            else:
                items.append(f"On `{label}`, no peer of peers.md is below rsm in any of the four columns.")
            before = [r for r in rows if r["kind"] == "before"]
            for r in before:
                worse = [f"{_scope_name(sc)} {q} ({fmt_q(q, e[sc][q]['mean'])} vs {fmt_q(q, r['values'][(sc, q)])} "
                         f"{UNITS[q]})" for sc, q in PEER_COLUMNS if _better(r["values"][(sc, q)], e[sc][q]["mean"])]
                if worse:
                    items.append(f"On `{label}`, rsm is worse than the earlier rsm of peers.md ({r['method']}) on: "
                                 + "; ".join(worse) + ".")
        small = a["runs"].get(SMALL)
        if small:
            worse = [f"{_scope_name(sc)} {q} {fmt_q(q, small['errors'][sc][q]['mean'])} vs "
                     f"{fmt_q(q, e[sc][q]['mean'])} {UNITS[q]}" for sc, q in PEER_COLUMNS
                     if small["errors"][sc][q]["mean"] > 1.05 * e[sc][q]["mean"]]
            if worse:
                items.append(f"On `{label}`, rsm with `{SMALL_HEADER}` is more than 5 % worse than with the default "
                             "configuration: " + "; ".join(worse) + ".")
        for other in ("paper", "icp", "odometry"):
            if other not in a["runs"]:
                continue
            lost = []
            for sc in SCOPES:
                for q in QUANTITIES:
                    for stat in ("mean", "std", "max"):
                        mine = e[sc][q][stat]
                        theirs = a["runs"][other]["errors"][sc][q][stat]
                        if _better(theirs, mine):
                            lost.append(f"{sc} {q} {stat} ({fmt_q(q, theirs)} vs rsm's {fmt_q(q, mine)} {UNITS[q]})")
            if lost:
                items.append(f"On `{label}`, {other} beats rsm on: " + "; ".join(lost) + ".")
            else:
                items.append(f"On `{label}`, {other} beats rsm on no error measure (mean, std, max "
                             "of translation and rotation, local and all relations).")
    rob = ctx.get("robustness")
    for label, r in ((rob or {}).get("logs") or {}).items():
        t = r["table"]
        noisy = [lv for lv in r["levels"] if lv != 0]
        for other in ("paper", "icp"):
            lost = []
            for sc in SCOPES:
                for q in QUANTITIES:
                    k = f"{sc}.{q}"
                    for lv in noisy:
                        mine, theirs = t[f"rsm:{lv}"][k]["mean"], t[f"{other}:{lv}"][k]["mean"]
                        if _better(theirs, mine):
                            lost.append(f"{lv} % {sc} {q} ({fmt_q(q, theirs)} vs rsm's {fmt_q(q, mine)} {UNITS[q]})")
            items.append(f"With outliers on `{label}`, {other}'s mean error over the seeds is below rsm's at: "
                         + "; ".join(lost) + "." if lost else
                         f"With outliers on `{label}`, {other}'s mean error over the seeds is below rsm's at no "
                         "level, in no scope and in neither translation nor rotation.")
        odo = acc[label]["runs"]["odometry"]["errors"]
        above = []
        for sc in SCOPES:
            for q in QUANTITIES:
                lv_above = [lv for lv in noisy if _better(odo[sc][q]["mean"], t[f"rsm:{lv}"][f"{sc}.{q}"]["mean"])]
                if lv_above:
                    above.append(f"{sc} {q} at {', '.join(map(str, lv_above))} % (odometry "
                                 f"{fmt_q(q, odo[sc][q]['mean'])} {UNITS[q]})")
        if above:
            items.append(f"With outliers on `{label}`, rsm's mean error over the seeds is above that of odometry "
                         "alone (which reads no scans): " + "; ".join(above) + ".")
    speed = ctx.get("speed")
    if speed:
        sm = speed["methods"]
        for other in ("paper", "icp"):
            for key, what in (("median_us", "median"), ("p95_us", "95th-percentile")):
                if _better(sm[other][key], sm["rsm"][key]):
                    items.append(f"Speed on `{main}`: {other}'s {what} time per scan is lower than rsm's "
                                 f"({sm[other][key]:.1f} vs {sm['rsm'][key]:.1f} us).")
    cg = ctx.get("callgrind")
    for label in acc:
        mine = cg_run(cg, label, "default", "rsm")
        if mine is None:
            continue
        for other in ("paper", "icp"):
            theirs = cg_run(cg, label, "default", other)
            if theirs and _better(theirs["ir_per_scan"], mine["ir_per_scan"]):
                items.append(f"Instructions on `{label}`: {other} executes fewer per scan than rsm "
                             f"({fmt_int(round(theirs['ir_per_scan']))} vs {fmt_int(round(mine['ir_per_scan']))}, "
                             f"{fmt_ratio(mine['ir_per_scan'] / theirs['ir_per_scan'])} times fewer).")
        if label == main and ctx.get("peer_speed"):
            cheaper = [p for p in ctx["peer_speed"] if p["kind"] == "peer"
                       and _better(p["ir_per_scan"], mine["ir_per_scan"])]
            if cheaper:
                items.append(f"Instructions on `{main}`: peers of peers.md with fewer instructions per scan than "
                             f"rsm's {fmt_int(round(mine['ir_per_scan']))}: " + ", ".join(
                                 f"{p['method']} ({fmt_int(round(p['ir_per_scan']))})" for p in cheaper) + ".")
    am = ctx.get("arm_memory")
    if am and "skipped" not in am and "default" in am["configs"] and am["configs"]["default"].get("state"):
        st = {s["label"].strip(): s["bytes"] for s in am["configs"]["default"]["state"]}
        pers, paper = st.get("state.persistent (rsm)"), st.get("state.paper (the paper's method)")
        total = st.get("rsm_localizer_t (all of the below)")
        if pers and paper and pers > paper:
            items.append(f"Memory: the persistent map's tile pool makes rsm's state {fmt_int(pers)} bytes on "
                         f"Cortex-M4F, {fmt_ratio(pers / paper)} times the paper's method's ({fmt_int(paper)}); "
                         f"it sets the size of the union and of the whole localizer ({fmt_int(total)} bytes).")
    items += _turn_losses(ctx.get("turns"))
    items += _stage_losses(ctx.get("stages"))
    items += _scaling_losses(ctx.get("scaling"))
    # a narrow win is worth saying too
    for label, a in acc.items():
        for other in ("paper", "icp", "odometry"):
            for q in QUANTITIES:
                mine = a["runs"]["rsm"]["errors"]["local"][q]["mean"]
                theirs = a["runs"][other]["errors"]["local"][q]["mean"]
                if _better(mine, theirs) and mine > 0.9 * theirs:
                    items.append(f"On `{label}`, rsm's local {q} mean ({fmt_q(q, mine)} {UNITS[q]}) is only "
                                 f"{100 * (1 - mine / theirs):.1f} % below {other}'s ({fmt_q(q, theirs)} "
                                 f"{UNITS[q]}): a narrow margin.")
    # the all-relations caveat, with this run's numbers
    per = acc[main]["runs"]["rsm"]["per_relation"]
    longs = [e for e in per if abs(e[1] - e[0]) > LOCAL_SPAN]
    total = math.fsum(e[2] for e in per)
    caveat = ("Relations spanning minutes measure drift: rsm has no loop closure, so what its persistent map "
              "does not hold together over a loop is never corrected.")
    if per and longs and total > 0:
        share = math.fsum(e[2] for e in longs) / total
        longest = max(abs(e[1] - e[0]) for e in longs)
        over60 = sum(1 for e in longs if abs(e[1] - e[0]) > 60.0)
        items.append(f"On `{main}`, {len(longs)} of {len(per)} matched relations span more than {LOCAL_SPAN:g} s "
                     f"({over60} more than a minute, the longest {longest:.0f} s) and carry {100 * share:.1f} % of "
                     "rsm's summed translational error. " + caveat)
    return items


def _turn_losses(turns: Optional[dict]) -> List[str]:
    items = []
    if not turns or not turns["turns"]:
        return items
    n = len(turns["turns"])
    sm = turns["summary"]
    for other in ("paper", "icp", "odometry"):
        lost = []
        for q, label in (("translation_cells", "translation"), ("rotation_deg", "rotation")):
            idx = [str(k) for k, r in enumerate(turns["turns"], 1)
                   if r["residual"]["rsm"] and r["residual"][other]
                   and r["residual"][other][q] < r["residual"]["rsm"][q]]
            if idx:
                lost.append(f"{label} at {len(idx)} of {n} (turn{'s' if len(idx) > 1 else ''} {', '.join(idx)})")
        means = [q.split("_")[0] for q in ("translation_cells", "rotation_deg")
                 if _better(sm[other][q]["mean"], sm["rsm"][q]["mean"])]
        if lost:
            items.append(f"At the {n} sharpest turns, {other}'s residual is below rsm's in " + "; ".join(lost)
                         + (f"; its mean is lower in {', '.join(means)}" if means else "; rsm's means are still lower")
                         + ".")
    for other in ("paper", "icp", "odometry"):
        worse = [b for b in turns["bins"] if b["relations"]
                 and _better(b["methods"][other]["translation_cells"]["mean"],
                             b["methods"]["rsm"]["translation_cells"]["mean"])]
        if worse:
            items.append(f"By true rotation, {other}'s mean translation residual is below rsm's for the local "
                         "relations turning " + "; ".join(
                             f"{b['bin']} deg ({_cells(b['methods'][other]['translation_cells']['mean'])} vs "
                             f"{_cells(b['methods']['rsm']['translation_cells']['mean'])} cells, "
                             f"{b['relations']} relations)" for b in worse) + ".")
    return items


def _stage_losses(st: Optional[dict]) -> List[str]:
    if not st:
        return []
    t = st["methods"]["rsm"]["timing"]
    top = max(STAGES, key=lambda s_: t[s_]["mean_us"] if s_ in t else 0.0)
    share = 100.0 * t[top]["mean_us"] / t["step"]["mean_us"] if t["step"]["mean_us"] else float("nan")
    return [f"Speed: one stage dominates rsm's time per scan: {top} ({fmt_pct(share)} % of the mean step); rsm's "
            f"95th percentile is {fmt_ratio(ratio(t['call']['p95_us'], t['call']['median_us']))} times its median."]


def _scaling_losses(sc: Optional[dict]) -> List[str]:
    items = []
    if not sc:
        return items
    rows = sc["rows"]
    base = {m: [r for r in rows if r["method"] == m and not r["macros"] and not r.get("header")
                and r["kind"] in ("tiles", "map")] for m in ("rsm", "paper")}
    for r in rows:
        b = base.get(r["method"])
        if not b or (not r["macros"] and not r.get("header")) or r["kind"] == "beams":
            continue
        b0 = b[0]
        worse = [f"{sc_} {q} {fmt_q(q, r[sc_][q])} vs {fmt_q(q, b0[sc_][q])} {UNITS[q]}"
                 for sc_ in SCOPES for q in QUANTITIES if r[sc_][q] > 1.05 * b0[sc_][q]]
        if worse:
            what = (f"`{r['header']}`" if r.get("header")
                    else ", ".join(f"{k} {v}" for k, v in sorted(r["macros"].items())))
            items.append(f"Scaling: {r['method']} with {what} is more than 5 % worse than with the default "
                         "configuration: " + "; ".join(worse) + ".")
    for m in ROBUST_METHODS:
        beams = sorted((r for r in rows if r["kind"] == "beams" and r["method"] == m), key=lambda r: r["beams"])
        if len(beams) >= 2:
            lo, hi = beams[0], beams[-1]
            tr = ratio(hi["call"]["median_us"], lo["call"]["median_us"])
            better = all(hi["local"][q] < lo["local"][q] for q in QUANTITIES)
            items.append(f"Scaling: for {m}, {hi['beams']} readings per scan cost {fmt_ratio(tr)} times the median "
                         f"time of {lo['beams']} ({hi['beams'] / lo['beams']:.2f} times the readings)"
                         + ("" if better else " and do not lower both local errors (the resampled readings carry "
                                              "no new information)") + ".")
    return items


def _range(vals: Sequence[float]) -> str:
    lo, hi = min(vals), max(vals)
    return fmt_ratio(lo) if fmt_ratio(lo) == fmt_ratio(hi) else f"{fmt_ratio(lo)}..{fmt_ratio(hi)}"


def _us(v: Optional[float]) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.1f}"


def _us2(v: Optional[float]) -> str:
    """Microseconds with two decimals under 10 us (stages can be that short)."""
    if v is None or not math.isfinite(v):
        return "n/a"
    return f"{v:.2f}" if v < 10 else f"{v:.1f}"


def _cells(v: Optional[float]) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.2f}"


def _deg(v: Optional[float]) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.2f}"


def report_turns(tn: Optional[dict], main: str, root: Path) -> List[str]:
    if not tn:
        return ["Not measured in this run.", ""]
    cell_cm = tn["cell_m"] * 100
    L = [f"The paper's Fig. 8 is one scan pair at a sharp turn, (Δx, Δy, Δθ) = (43 mm, 27 mm, 14.63°) "
         "between the two scans: ICP (30 iterations) ends in a local minimum, the proposed method's "
         "residual is (1 cell, 1 cell, 0.25°). Here the same question is asked of the whole "
         f"`{main}` log: the {len(tn['turns'])} local relations (span <= {LOCAL_SPAN:g} s) with the fastest "
         "true turn, in degrees of true rotation per scan between the relation's two scans (counted in "
         "scans because the log's timestamps jitter), at most one per "
         f"{tn['separation']} scans; for each, the residual inverse(true) ∘ estimated of the trajectories of "
         f"section 1, as absolute values: Δx and Δy (in the frame of the true end pose) in cells of "
         f"{cell_cm:g} cm (the paper's grid, `grid.cell_m`, as `rsm-stages` reports it; rsm's own finest "
         "map cell is twice that) and Δθ in degrees; translation is the length of (Δx, Δy). Each method runs "
         "its whole filter along the relation's scans, so these are residuals of the tracked motion over the "
         "turn, not of one isolated scan match as in the paper.", ""]
    rows = []
    for k, r in enumerate(tn["turns"], 1):
        cells = [str(k), f"{r['t1_rel']:.1f}", f"{r['span']:.2f}", str(r["gap"]), f"{r['rotation_deg']:.1f}",
                 f"{r['translation_m']:.3f}"]
        for m in METHODS:
            e = r["residual"][m]
            cells += (["n/a", "n/a"] if e is None else
                      [f"{_cells(e['dx_cells'])}, {_cells(e['dy_cells'])}", _deg(e["rotation_deg"])])
        rows.append(cells)
    L += md_table(["turn", "t1 [s]", "span [s]", "scans", "true rotation [deg]", "true translation [m]"]
                  + [h for m in METHODS for h in (f"{m} Δx, Δy [cells]", f"{m} Δθ [deg]")], rows, "turns")
    rows = []
    for m in METHODS:
        s = tn["summary"][m]
        rows.append([m, str(s["translation_cells"]["n"]), _cells(s["dx_cells"]["mean"]), _cells(s["dy_cells"]["mean"]),
                     _cells(s["translation_cells"]["mean"]), _cells(s["translation_cells"]["max"]),
                     _deg(s["rotation_deg"]["mean"]), _deg(s["rotation_deg"]["max"])])
    L += [f"Over these {len(tn['turns'])} turns (t1 counted from the log's first scan):", ""]
    L += md_table(["method", "turns", "mean Δx [cells]", "mean Δy [cells]", "mean translation [cells]",
                   "max translation [cells]", "mean Δθ [deg]", "max Δθ [deg]"], rows, "turns summary")
    n = len(tn["turns"])
    L += ["; ".join(f"rsm's residual is below {o}'s at {w['translation_cells']} of {n} turns in translation and "
                    f"at {w['rotation_deg']} of {n} in rotation" for o, w in tn["rsm_better"].items()) + ".", ""]
    L += [f"Every local relation of `{main}`, by its true rotation: mean translation residual in cells and "
          "mean rotation residual in degrees.", ""]
    rows = []
    for b in tn["bins"]:
        cells = [b["bin"], str(b["relations"])]
        for m in METHODS:
            cells += [_cells(b["methods"][m]["translation_cells"]["mean"]), _deg(b["methods"][m]["rotation_deg"]["mean"])]
        rows.append(cells)
    L += md_table(["true rotation [deg]", "relations"] + [h for m in METHODS for h in (f"{m} [cells]", f"{m} [deg]")],
                  rows, "turns by rotation")
    return L


def report_stage_speed(st: Optional[dict], speed: Optional[dict], main: str) -> List[str]:
    if not st:
        return ["Per-stage times not measured in this run.", ""]
    L = ["### Per stage", "",
         f"`rsm-stages` (tools/bench-c) runs `{main}` as rsm-nav does (same trajectory, bit for bit) with "
         "the localizer's timing hook set: `rsm_localizer_config_t.clock_fn` reads CLOCK_MONOTONIC in "
         "nanoseconds and `rsm_localizer_scan` charges each stage the time from its start to the next "
         f"stage's. rsm, the paper's method and icp ran in turn, one process at a time, {st['repeats']} time(s) "
         "each, in this bench run; every figure is the median over the repeats. A stage's median and 95th "
         "percentile are over the scans that reached it (*scans*); its mean is over all scans, so the "
         "stage means add up to the whole step's mean (*share*). *whole step* is the hook's own total "
         "(first to last clock reading), *whole call* the call timed from outside. rsm's *map* stage writes "
         "the scan into the persistent map only after 0.4 m or 0.5 rad of travel, so most of its calls are "
         "a test and its 95th percentile is far above its median.", ""]
    rows = []
    mt = {m: st["methods"][m]["timing"] for m in ROBUST_METHODS}
    for s in STAGES + ("step", "call"):
        label = {"step": "whole step (hook)", "call": "whole call (timed outside)"}.get(s, s)
        cells = [label, STAGE_WHAT.get(s, "")]
        for m in ROBUST_METHODS:
            t = mt[m].get(s)
            if t is None or t["reached"] == 0:
                cells += ["0", "-", "-", "-", "-"]
                continue
            whole = s in ("step", "call")
            share = 100.0 * t["mean_us"] / mt[m]["step"]["mean_us"] if mt[m]["step"]["mean_us"] else float("nan")
            cells += [str(t["reached"]), _us2(t["median_us"] if whole else t["median_reached_us"]),
                      _us2(t["p95_us"] if whole else t["p95_reached_us"]), _us2(t["mean_us"]),
                      "" if s == "call" else fmt_pct(share)]
        rows.append(cells)
    for m in ROBUST_METHODS:
        if m == "rsm":
            continue
        rows.append([f"{m} / rsm", "whole call", ""]
                    + [""] * (5 * ROBUST_METHODS.index(m) - 1)
                    + ["", fmt_ratio(st["ratio_median"][m]), fmt_ratio(st["ratio_p95"][m]),
                       fmt_ratio(st["ratio_mean"][m]), ""]
                    + [""] * (5 * (len(ROBUST_METHODS) - ROBUST_METHODS.index(m) - 1)))
    L += md_table(["stage", "what"] + [h for m in ROBUST_METHODS for h in
                                      (f"{m} scans", f"{m} median [us]", f"{m} p95 [us]", f"{m} mean [us]",
                                       f"{m} share %")], rows, "speed stages")
    mo = mt["rsm"].get("motion")
    if mo:
        L += [f"Odometry prediction (`rsm_localizer_motion`, the EKF predict, once per scan): median "
              f"{_us2(mo['median_us'])} us, p95 {_us2(mo['p95_us'])} us (rsm run).", ""]
    if speed:
        parts = [f"{_us(mt[m]['call']['median_us'])} us for {m} (rsm-nav: {_us(speed['methods'][m]['median_us'])})"
                 for m in ROBUST_METHODS]
        L += ["With the hook the whole call's median is " + ", ".join(parts) + "; rsm-nav leaves the hook NULL. "
              "The clock readings cost little next to the stages, but two processes measured minutes apart "
              "differ by a few per cent anyway.", ""]
    L += plot_lines(st.get("plot"), st.get("plot_note"), "Time per stage, rsm, the paper's method and icp")
    return L


def _cg_columns(cg: dict, label: str) -> List[Tuple[str, dict]]:
    """The callgrind runs of one log in report order, with their column names."""
    out = []
    for run in RUNS:
        r = cg_run(cg, label, *run_build(run))
        if r is not None:
            out.append((run, r))
    return out


def report_callgrind(cg: Optional[dict], root: Path, main: str) -> List[str]:
    if not cg or "skipped" in cg:
        return [f"Instruction counts not measured: {(cg or {}).get('skipped', 'disabled')}.", ""]
    L = [f"Instructions executed inside `rsm_localizer_scan` (callgrind, `--toggle-collect=rsm_localizer_scan`, "
         f"{cg['valgrind']}) on the first {cg['scans']} scans of every log (all of it if shorter; `rsm-nav` on a "
         "copy of the log cut after that scan line), divided by the scans; *rsm-small* is rsm built with "
         f"`{SMALL_HEADER}`. These counts repeat exactly from run to run on the same binary.", ""]
    rows = []
    for label, h in cg["heads"].items():
        base = cg_run(cg, label, "default", "rsm")
        for name, r in _cg_columns(cg, label):
            rows.append([label, name, fmt_int(r["scans"]), fmt_int(r["ir"]), fmt_int(round(r["ir_per_scan"])),
                         fmt_ratio(ratio(r["ir_per_scan"], base["ir_per_scan"])) if base else "n/a"])
    L += md_table(["log", "run", "scans", "Ir collected", "Ir per scan", "x rsm"], rows, "speed callgrind")
    cols = _cg_columns(cg, main)
    if cols and all("stages" in r for _, r in cols):
        L += [f"By stage on `{main}`: the inclusive count of every function `rsm_localizer_scan` calls, grouped by "
              "the stage that calls it (`rsm_pose_between`, `rsm_pose_apply` and the sine/cosine of `to_world` "
              "run when rsm writes its map; `rsm_map_recenter` in both the paper's grid and map stages). "
              "*localizer* is `rsm_localizer_scan`'s own code with the static helpers the compiler inlined into "
              "it. Callgrind counts functions, not stages, so that part cannot be split further; the wall-time "
              "table below has the exact split.", ""]
        rows = []
        for stg in CG_STAGE_ORDER:
            if not any(stg in r["stages"] for _, r in cols):
                continue
            fns = sorted({f for _, r in cols for f in r["stages"].get(stg, {}).get("functions", [])})
            cells = [stg, ", ".join(f"`{f}`" for f in fns)]
            for _, r in cols:
                row = r["stages"].get(stg)
                cells += (["0", "0.0"] if row is None else
                          [fmt_int(round(row["ir_per_scan"])), fmt_pct(100.0 * row["ir"] / r["ir"])])
            rows.append(cells)
        L += md_table(["stage", "functions"] + [h for n, _ in cols for h in (f"{n} Ir per scan", f"{n} %")], rows,
                      "speed callgrind stages")
    details = [(label, "rsm", r) for label in cg["heads"] for r in [cg_run(cg, label, "default", "rsm")]
               if r and r.get("mapmatch") and r["mapmatch"]["total"]]
    if details:
        L += ["Inside `rsm_mapmatch` (rsm's matching, the default configuration): its own code and the inclusive "
              "count of each function it calls, per scan (src/map/mapmatch.h describes the steps: the "
              "heading fan, then Gauss-Newton from the coarsest level to the finest).", ""]
        fns = sorted({f for _, _, r in details for f in r["mapmatch"]["callees"]},
                     key=lambda f: -max(r["mapmatch"]["callees"].get(f, 0) for _, _, r in details))
        rows = []
        for f in ["(own code)"] + fns:
            cells = [f if f == "(own code)" else f"`{f}`"]
            for _, _, r in details:
                v = r["mapmatch"]["own"] if f == "(own code)" else r["mapmatch"]["callees"].get(f, 0)
                cells += [fmt_int(round(v / r["scans"])), fmt_pct(100.0 * v / r["mapmatch"]["total"])]
            rows.append(cells)
        L += md_table(["function"] + [h for label, _, _ in details for h in (f"{label} Ir per scan", f"{label} %")],
                      rows, "speed callgrind mapmatch")
    return L


def _kib(v: Optional[int]) -> str:
    return "n/a" if v is None else f"{v / 1024:.1f}"


# Measured once, when the LMS driver stopped keeping its own scan copies
# (issue 12); the tables above are this run's figures.
FIRMWARE_SCAN_COPIES = ("Scan copies: the LMS driver decodes each 0xB0 telegram straight into the application's "
                        "`rsm_scan_t` (the last argument of `rsm_sicklms_init`), where it used to keep a decoded "
                        "`rsm_lms_scan_t` and an `rsm_scan_t` of its own. Static objects of the example firmware's main "
                        "file, default configuration (`tools/cross-check`): 132 560 bytes before (commit 9ba4ebb, "
                        "`fw_laser` 7 096), 129 648 after (`fw_laser` 1 280 and the application's `fw_scan` 2 904), one "
                        "scan copy (2 912 bytes) less. The scan is still held by the driver's telegram buffer (its bytes "
                        "as received), `fw_scan`, the aligner's copy of a scan waiting for odometry (`rsm_sync_t`: the "
                        "next scan may arrive meanwhile) and the localizer's points in the robot and world frames.")


def object_kind(obj: str) -> str:
    stem = obj.split(".")[0]
    return "driver" if stem in DRIVER_OBJECTS else "core"


def report_arm_memory(am: Optional[dict], root: Path) -> List[str]:
    if not am:
        return ["Per-configuration Cortex-M4F sizes not measured in this run.", ""]
    if "skipped" in am:
        return [f"Per-configuration Cortex-M4F sizes not measured: {am['skipped']}.", ""]
    names = list(am["configs"])
    L = ["### Cortex-M4F per module and configuration", "",
         f"{am['compiler']}, MinSizeRel (-Os), cross-built by this bench for each configuration: "
         + "; ".join(f"*{n}* = `{am['configs'][n]['header']}`" for n in names)
         + ". Flash is text + rodata per object of `librsm.a`; *core* is the localizer pipeline, "
         "*driver* the P3-DX and LMS drivers with their protocol codecs and the HAL helpers. No object has "
         "static RAM (.data/.bss); all RAM is caller-owned state, listed below by module.", ""]
    objs = {}
    for n in names:
        for o in am["configs"][n]["objects"]:
            objs.setdefault(o["object"], {})[n] = o
    rows = []
    totals = {n: {"core": 0, "driver": 0, "ram": 0} for n in names}
    for obj in sorted(objs, key=lambda o: (object_kind(o), o)):
        cells = [obj, object_kind(obj)]
        for n in names:
            o = objs[obj].get(n)
            cells.append("n/a" if o is None else fmt_int(o["flash"]))
            if o is not None:
                totals[n][object_kind(obj)] += o["flash"]
                totals[n]["ram"] += o["ram"]
        cells.append(fmt_int(sum(objs[obj][n]["ram"] for n in names if n in objs[obj])))
        rows.append(cells)
    for kind in ("core", "driver"):
        rows.append([f"TOTAL {kind}", ""] + [fmt_int(totals[n][kind]) for n in names] + [""])
    rows.append(["TOTAL core + drivers", ""] + [fmt_int(totals[n]["core"] + totals[n]["driver"]) for n in names]
                + [fmt_int(sum(totals[n]["ram"] for n in names))])
    L += md_table(["object", "kind"] + [f"flash {n} [bytes]" for n in names] + ["static RAM (all configs)"],
                  rows, "memory arm configs flash")
    if all(am["configs"][n].get("state") for n in names):
        rows = []
        for k, item in enumerate(am["configs"][names[0]]["state"]):
            cells = [f"`{item['module']}`", item["label"].replace("  ", "&nbsp;&nbsp;")]
            for n in names:
                v = am["configs"][n]["state"][k]["bytes"]
                cells += [fmt_int(v) if v is not None else "n/a"]
            rows.append(cells)
        L += ["Caller-owned state on the target (`sizeof`, from a probe object built with the same compiler "
              "and configuration). The indented rows are the parts of `rsm_localizer_t` and of its parts; "
              "`state.persistent`, `state.paper` and `state.icp` share one union (one method runs per "
              "localizer), so the largest of them, rsm's tile pool, sets its size.", ""]
        L += md_table(["module", "state"] + [f"{n} [bytes]" for n in names], rows, "memory arm configs state")
    else:
        L += ["State sizes on the target not measured: "
              + "; ".join(am["configs"][n].get("state_note", "") for n in names) + ".", ""]
    rows = []
    for n in names:
        fw = am["configs"][n]["firmware"]
        if fw:
            stat = am["configs"][n]["firmware_statics"]
            rows.append([n, fmt_int(fw["text"]), fmt_int(fw["data"]), fmt_int(fw["bss"]), fmt_int(fw["dec"]),
                         fmt_int(sum(stat.values())), fmt_int(stat.get("fw_localizer", 0))])
    L += ["The example firmware (`port/baremetal`, one localizer, both drivers, two UART rings; "
          "`--gc-sections`, newlib-nano) per configuration:", ""]
    L += md_table(["config", "text", "data", "bss", "total", "firmware statics", "of which fw_localizer"], rows,
                  "memory arm configs firmware")
    return L


def report_stack(am: Optional[dict], hs: Optional[dict], st: Optional[dict], stack_note: Optional[str]) -> List[str]:
    L = ["### Stack of one localizer step", "",
         "Measured two ways. *Static*: every library source compiled with `-fstack-usage "
         "-fcallgraph-info=su` (GCC writes each function's frame size and its calls); the deepest path "
         "from each entry point through that call graph, summing the frames. Calls into libc/libm "
         "(listed) count 0, and so do calls through a pointer to the user's code (the optional timing "
         "hook in the localizer's stage bookkeeping, the aligner's result callback); the Harris patch "
         "callback (the paper's method) is resolved to the two functions the localizer passes (`patch_map`, "
         "`rsm_harris_patch_image`). `rsm_sync_*` (the odometry/scan aligner) call `rsm_localizer_scan` "
         "and `rsm_localizer_motion` themselves. *Painted* (host only): `rsm-stages --stack` runs every "
         "scan of the log in a fresh thread whose stack buffer was filled with a pattern, finds the "
         "lowest byte that lost it, and subtracts the same measure for a thread that calls an empty "
         "function with the same arguments; the maximum over all scans.", ""]
    rows = []
    def not_counted(s: dict) -> str:
        parts = [", ".join(s["unresolved"])] if s["unresolved"] else []
        if s["unknown_indirect"]:
            parts.append("calls through a pointer in " + ", ".join(s["unknown_indirect"]))
        return "; ".join(parts) or "none"

    builds = []
    if am and "skipped" not in am:
        builds += [(f"Cortex-M4F -Os, {n}", c["stack"]) for n, c in am["configs"].items()]
    if hs and "skipped" not in hs:
        builds.append((f"host `{hs['flags']}`", hs["stack"]))
    same = []
    for k, (label, stack) in enumerate(builds):
        if k > 0 and label.startswith("Cortex-M4F") and stack == builds[0][1]:
            same.append(label)  # another configuration with exactly the first one's bounds and paths
            continue
        for fn, s in stack.items():
            rows.append([label, "static", f"`{fn}`", fmt_int(s["bytes"]),
                         " → ".join(f"{a} {b}" for a, b in s["path"]), not_counted(s)])
    if st and st.get("stack"):
        for m in ROBUST_METHODS:
            s = st["stack"][m]
            rows.append(["host, this build", "painted", f"`rsm_localizer_scan` ({m})", fmt_int(s["scan_bytes"]),
                         f"max over {fmt_int(s['scans'])} scans; thread peak {fmt_int(s['peak_bytes'])} minus "
                         f"baseline {fmt_int(s['baseline_bytes'])}", "counted (they ran)"])
    if rows:
        L += md_table(["build", "method", "function", "bytes", "deepest path (frame bytes)",
                       "calls not counted (static)"], rows, "memory stack")
    if same:
        L += [f"{', '.join(same)}: the same bounds and paths as {builds[0][0]} (the capacities size "
              "buffers in the caller's state, not frames).", ""]
    if stack_note:
        L += [f"Painted measurement not made: {stack_note}.", ""]
    if hs and "skipped" in hs:
        L += [f"Host static bound not computed: {hs['skipped']}.", ""]
    return L


def report_scaling(sc: Optional[dict], main: str) -> List[str]:
    if not sc:
        return ["Not measured in this run.", ""]
    L = [f"Time per scan (whole call, rsm-stages, one run each, one process at a time) and mean error on `{main}` "
         "for builds with other capacities, each variant a Release build of its own with a generated "
         "`RSM_USER_CONFIG` (the default values come from the main build). *beams*: the log's 180-beam scans "
         "resampled to N readings over the same 179° field (linear in range between neighbouring readings "
         "closer than 0.1 m, otherwise the nearer reading) with `RSM_MAX_BEAMS` = N; they add readings, not "
         "information. *map*: the paper's scrolling window, `RSM_MAP_SIZE_LOG2` = L (the paper's method only; "
         "rsm does not use it). *tiles*: rsm's tile pool, `RSM_TMAP_TILES` = T with the smallest tile index "
         "config.h accepts (rsm only; when the pool is full the tiles written longest ago are reused, a coarse tile's age counting less, see docs/map.md). "
         "*preset*: a shipped configuration header as it is. *map* to *preset* use the log's own readings. "
         "*tiles used* is the persistent map's use of its pool at the end of the log (taken / evicted).", ""]
    rows = []
    kinds = ("beams", "map", "tiles", "preset")
    for r in sorted(sc["rows"], key=lambda r: (kinds.index(r["kind"]), r["value"], ROBUST_METHODS.index(r["method"]))):
        c = r["config"]
        cfg = (f"`{r['header']}`" if r.get("header") else
               ", ".join(f"{k} {v}" for k, v in sorted(r["macros"].items())) or "defaults")
        tm = r.get("tmap")
        rows.append([r["kind"], cfg, str(r["beams"]), r["method"], _us(r["call"]["median_us"]),
                     _us(r["call"]["p95_us"]),
                     fmt_q("translation", r["local"]["translation"]), fmt_q("rotation", r["local"]["rotation"]),
                     fmt_q("translation", r["all"]["translation"]), fmt_pct(r["fused"]),
                     f"{fmt_int(tm['used'])} / {fmt_int(c['RSM_TMAP_TILES'])} ({fmt_int(tm['allocated'])} / "
                     f"{fmt_int(tm['evicted'])})" if tm else "",
                     fmt_int(r["sizes"]["rsm_localizer_t"])])
    L += md_table(["varies", "config", "readings", "method", "median [us]", "p95 [us]", "local translation [m]",
                   "local rotation [deg]", "all translation [m]", "fused %", "tiles used (taken / evicted)",
                   "sizeof(rsm_localizer_t)"], rows, "scaling time")
    seen = {}
    for r in sc["rows"]:
        seen.setdefault(r["variant"], r)
    rows = []
    for v in sorted(seen.values(), key=lambda r: (kinds.index(r["kind"]), r["value"])):
        c, s = v["config"], v["sizes"]
        rows.append([v["variant"], str(c["RSM_MAX_BEAMS"]), str(c["RSM_MAP_SIZE"]), fmt_int(c["RSM_TMAP_TILES"]),
                     fmt_int(s["rsm_localizer_t"]), fmt_int(s["state.persistent"]), fmt_int(s["state.paper"]),
                     fmt_int(s["state.icp"]), fmt_int(s["points"]), fmt_int(s["rsm_scan_t"])])
    L += ["How the state grows with the capacities (bytes on this host):", ""]
    L += md_table(["variant", "RSM_MAX_BEAMS", "window side", "RSM_TMAP_TILES", "rsm_localizer_t",
                   "state.persistent", "state.paper", "state.icp", "points", "rsm_scan_t"], rows, "scaling memory")
    g = sc.get("growth", {})
    parts = []
    if "beams" in g:
        parts.append(f"{g['beams']['bytes_per_unit']:.1f} bytes of `rsm_localizer_t` per unit of RSM_MAX_BEAMS "
                     "(`pts` and `world`, and the paper's image and ICP points inside the union when they are the "
                     "larger member), and every `rsm_scan_t` grows with it too")
    if "map" in g:
        parts.append(f"{g['map']['bytes_per_unit']:.3f} bytes per cell of the paper's window (only while "
                     "`state.paper` is the union's largest member)")
    if "tiles" in g:
        parts.append(f"{g['tiles']['bytes_per_unit']:.1f} bytes per tile of rsm's pool (the tile and its share of "
                     "the index)")
    if parts:
        L += ["Growth between the smallest and largest variant: " + "; ".join(parts) + ".", ""]
    L += plot_lines(sc.get("plot"), sc.get("plot_note"), "Scaling of time per scan, error and state size")
    return L


def plot_lines(plot: Optional[str], note: Optional[str], alt: str) -> List[str]:
    """A section's picture, else why rsm-bench drew none (its plot_note), else nothing."""
    if plot:
        return [f"![{alt}]({plot})", ""]
    return [f"No plot: {note}.", ""] if note else []


def md_table(header: Sequence[str], rows: Iterable[Sequence[str]], anchor: str) -> List[str]:
    """A Markdown table preceded by an HTML comment naming it (the test finds it by that)."""
    out = [f"<!-- table: {anchor} -->", "| " + " | ".join(header) + " |",
           "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    out.append("")
    return out


def _peer_rows(ctx: dict, label: str) -> Optional[List[dict]]:
    pe = ctx.get("peers") or {}
    if "skipped" in pe or "accuracy" not in pe:
        return None
    return pe["accuracy"].get(label)


def before_label(method: str) -> str:
    """"rsm (commit 953a3c1)" -> "rsm before (commit 953a3c1)"."""
    m = re.match(r"^rsm\s*\((.*)\)\s*$", method)
    return f"rsm before ({m.group(1)})" if m else f"rsm before ({method})"


def summary_rows(ctx: dict, label: str) -> List[List[str]]:
    """The rows of one log in the headline table: this run's methods, the
    earlier rsm, the best peer per column and rsm's ratio to it."""
    a = ctx["accuracy"][label]
    rows = []
    for run in run_labels(a):
        e = a["runs"][run]["errors"]
        rows.append([label, run] + [fmt_q(q, e[sc][q]["mean"]) for sc, q in PEER_COLUMNS])
    peers = _peer_rows(ctx, label)
    if peers:
        for r in peers:
            if r["kind"] == "before":
                rows.append([label, before_label(r["method"])]
                            + [fmt_q(q, r["values"][(sc, q)]) for sc, q in PEER_COLUMNS])
        best = best_peers(peers)
        rows.append([label, "best peer"] + [
            "n/a" if best[k] is None else f"{fmt_q(k[1], best[k][0])} ({best[k][1]})" for k in PEER_COLUMNS])
        for run in ("rsm", SMALL):
            if run in a["runs"]:
                e = a["runs"][run]["errors"]
                rows.append([label, f"{run} / best peer"] + [
                    "n/a" if best[k] is None else fmt_ratio(ratio(e[k[0]][k[1]]["mean"], best[k][0]))
                    for k in PEER_COLUMNS])
    return rows


def report_accuracy(ctx: dict, root: Path) -> List[str]:
    acc = ctx["accuracy"]
    pe = ctx.get("peers") or {}
    L = [f"Relative-pose error of Kümmerle et al. 2009 (`rsm_tools.evaluate`, exact timestamps) of the "
         f"trajectories `rsm-nav --method rsm|paper|icp|odometry` writes; *rsm-small* is `rsm-nav --method rsm` "
         f"built with `{SMALL_HEADER}` (the microcontroller preset). *local*: relations spanning at most "
         f"{LOCAL_SPAN:g} s; *all*: every relation. Translation in m, rotation in degrees; std is the "
         "population standard deviation; *fused* is the share of scans whose measurement the filter accepted.", ""]
    if "skipped" in pe:
        L += [f"No peer figures: {pe['skipped']} (`{shown_path(Path(pe['path']), root)}`), so the peers' columns "
              "and the floors that need them are skipped.", ""]
    else:
        L += [f"The peers' figures are those of `{shown_path(Path(pe['path']), root)}` (measured "
              f"{pe.get('measured') or 'on a date it does not state'}; table \"Accuracy\"), typed in there, not "
              "measured by this run. *best peer* is the lowest figure of the column among the peers of that log; "
              "odometry alone and the earlier rsm of that table are not peers. The peers' own settings "
              "(parameters, range cuts) are described there.", ""]
    for label, a in acc.items():
        L += [f"### `{label}`", "",
              f"Log `{shown_path(Path(a['log']), root)}`, relations `{shown_path(Path(a['relations']), root)}` "
              f"({a['relation_count']} relations), {a['runs']['rsm']['summary']['scans']} scans.", ""]
        rows = []
        for run in run_labels(a):
            r = a["runs"][run]
            for sc in SCOPES:
                e = r["errors"][sc]
                rows.append([run, sc, str(e["matched"]), str(e["unmatched"])]
                            + [fmt_q(q, e[q][st]) for q in QUANTITIES for st in ("mean", "std", "max")]
                            + [fmt_pct(fused_percent(r["summary"]))])
        L += md_table(["method", "scope", "matched", "unmatched", "translation mean", "std", "max",
                       "rotation mean", "std", "max", "fused %"], rows, f"accuracy {label}")
        peers = _peer_rows(ctx, label)
        if peers:
            rows = []
            for run in run_labels(a):
                e = a["runs"][run]["errors"]
                rows.append([run, "this run"] + [fmt_q(q, e[sc][q]["mean"]) for sc, q in PEER_COLUMNS])
            for r in peers:
                kind = {"before": "peers.md, the earlier rsm", "odometry": "peers.md, not a peer"}.get(
                    r["kind"], "peers.md, peer")
                rows.append([r["method"], kind] + [
                    (fmt_q(q, r["values"][(sc, q)]) if r["values"][(sc, q)] is not None else (r["note"] or "n/a")
                     if (sc, q) == PEER_COLUMNS[0] else "") for sc, q in PEER_COLUMNS])
            rows += [[row[1], "peers.md" if row[1].startswith("best") else "ratio"] + row[2:]
                     for row in summary_rows(ctx, label)
                     if row[1].startswith(("best peer", "rsm / best", f"{SMALL} / best"))]
            L += ["Beside the peers (mean errors; columns as in peers.md):", ""]
            L += md_table(["method", "source", "all translation [m]", "all rotation [deg]", "local translation [m]",
                           "local rotation [deg]"], rows, f"peers {label}")
        elif "skipped" not in pe:
            L += [f"peers.md has no figures for `{label}`.", ""]
        oc = []
        for run in run_labels(a):
            o = a["runs"][run]["summary"]["outcomes"]
            oc.append(f"{run}: " + ", ".join(f"{k} {v}" for k, v in o.items()))
        L += ["Scan outcomes (rsm-nav summary): " + "; ".join(oc) + ".", ""]
        tm = []
        for run in ("rsm", SMALL):
            s = a["runs"].get(run, {}).get("summary")
            if s and s.get("tmap"):
                t, rc = s["tmap"], s.get("recovery") or {}
                tm.append(f"{run}: {fmt_int(t['writes'])} writes, tiles {'/'.join(map(str, t['tiles']))} per level, "
                          f"{fmt_int(t['taken'])} taken, {fmt_int(t['evicted'])} evicted, {fmt_int(t['dropped'])} "
                          f"returns dropped; {rc.get('searches', 0)} recovery searches, {rc.get('taken', 0)} taken; "
                          f"{fmt_int(s.get('unpinned', 0))} matches unpinned along a corridor")
        if tm:
            L += ["Persistent map at the end of the log (rsm-nav summary): " + "; ".join(tm) + ".", ""]
        cv = [f"{run}: {consistency.describe(a['runs'][run]['covariance'])}" for run in ("rsm", SMALL)
              if "covariance" in a["runs"].get(run, {})]
        if cv:
            L += [f"The covariance rsm reports against its error (`rsm_tools.consistency`, relations spanning at most "
                  f"{LOCAL_SPAN:g} s, the covariance of `--scan-log`; docs/robustness.md, \"The covariance\"): "
                  + "; ".join(cv) + ".", ""]
    return L


def report_robustness(ctx: dict, root: Path) -> List[str]:
    rob = ctx.get("robustness")
    if not rob:
        return ["Not measured in this run.", ""]
    main = ctx["main_label"]
    L = ["The paper's experiment: in every scan, the given share of the readings is replaced by uniform random "
         f"ranges (`rsm_tools.outliers`: up to {outliers.DEFAULT_MAX_RANGE:g} m, the same readings and values for "
         "every method at each seed). For each level: the mean over seeds of the mean error, its spread (min..max "
         "over the seeds) and its ratio to the same method's clean figure. Seeds "
         f"{', '.join(str(s) for s in rob['seeds'])} (7 is the peers' seed); 0 % is the clean log itself (the "
         f"accuracy run). The whole curve on `{main}`, the floor's {FLOOR_LEVEL} % and the peers' second level on "
         f"the other logs. {rob['outlier_logs_made']} outlier log(s) were generated in this run, the others came "
         "from the cache. peers.md's robustness table (below) drew its outliers up to each log's largest reading, "
         "so its ratios are beside, not equal to, these.", ""]
    for label, r in rob["logs"].items():
        for sc in SCOPES:
            title = (f"local relations (span <= {LOCAL_SPAN:g} s)" if sc == "local" else "all relations")
            L += [f"### `{label}`, {title}", ""]
            rows = []
            for lv in r["levels"]:
                for m in ROBUST_METHODS:
                    row = r["table"][f"{m}:{lv}"]
                    cells = [str(lv), m, str(row[f"{sc}.translation"]["n"])]
                    for q in QUANTITIES:
                        c = row[f"{sc}.{q}"]
                        cells += [fmt_q(q, c["mean"]), f"{fmt_q(q, c['min'])}..{fmt_q(q, c['max'])}",
                                  fmt_ratio(c["ratio"])]
                    cells.append(fmt_pct(row["fused"]["mean"]))
                    rows.append(cells)
            L += md_table(["outliers %", "method", "runs", "translation mean [m]", "min..max", "x clean",
                           "rotation mean [deg]", "min..max", "x clean", "fused %"], rows, f"robustness {label} {sc}")
    L += plot_lines(ctx.get("plot"), ctx.get("plot_note"),
                    f"Robustness curves on {main}: mean error against the share of outliers, rsm, the paper's "
                    "method and icp, odometry as a reference line")
    sp = ctx.get("spread")
    if sp and "skipped" not in sp:
        L += ["### Over many runs", "",
              "One run's all-relations error is one draw of a chaotic process: rounding alone moves it by about a "
              "tenth (docs/map.md), so the tables above, one run per seed, can pass or miss a floor by chance. "
              f"Here rsm ran once per `map_update_m` of {sp['updates'][0]:g}, {sp['updates'][1]:g}, ... "
              f"{sp['updates'][-1]:g} m ({len(sp['updates'])} values around the default 0.4) on every clean log, and "
              f"at every other one of them on its copies at {sp['level']} % outliers (seeds "
              f"{', '.join(str(s) for s in sp['seeds'])}; which phantoms a seed draws moves its runs' mean by more "
              "than a tenth): the mean error over the runs with its standard error, the median, and the ratio of "
              "the means with its standard error.", ""]
        rows = []
        for label, r in sp["logs"].items():
            for sc in SCOPES:
                c, nz = r["clean"][sc], r["noisy"][sc]
                x, se = spread_ratio(nz, c)
                rows.append([label, _scope_name(sc), str(c["n"]),
                             f"{fmt_q('translation', c['mean'])} +- {fmt_q('translation', c['se'])}",
                             fmt_q("translation", c["median"]), str(nz["n"]),
                             f"{fmt_q('translation', nz['mean'])} +- {fmt_q('translation', nz['se'])}",
                             fmt_q("translation", nz["median"]), f"{x:.2f} +- {se:.2f}"])
        L += md_table(["log", "relations", "clean runs", "clean mean [m]", "median", "outlier runs",
                       "outliers mean [m]", "median", "x clean (means)"], rows, "robustness spread")
    pt = ctx.get("peer_robustness")
    if pt:
        L += ["peers.md's robustness table, as it is there (local translation error at 43 % / 60 % outliers, "
              "times the clean figure; their injection):", ""]
        L += md_table(pt["header"], pt["rows"], "peers robustness")
    return L


def report_memory(ctx: dict, root: Path) -> List[str]:
    mem, xc, am = ctx.get("memory"), ctx.get("cross_check"), ctx.get("arm_memory")
    L = []
    if mem and mem.get("configs"):
        names = list(mem["configs"])
        c0 = mem["configs"][names[0]]["config"]
        L += [f"`sizeof` on this host ({mem['compiler']}) from `rsm-stages` (its JSON prints them), per configuration: "
              + "; ".join(f"*{n}* = `{mem['configs'][n]['header'] or 'rsm/config.h (defaults)'}`" for n in names)
              + f". Default capacities: {c0['RSM_MAX_BEAMS']} readings, a tile pool of "
              f"{fmt_int(c0['RSM_TMAP_TILES'])} tiles of {1 << c0['RSM_TMAP_TILE_LOG2']} x "
              f"{1 << c0['RSM_TMAP_TILE_LOG2']} cells over {c0['RSM_TMAP_LEVELS']} levels (finest cell "
              f"{c0['tmap_cell_m'] * 100:g} cm), the paper's window {c0['RSM_MAP_SIZE']} x {c0['RSM_MAP_SIZE']} "
              f"cells of {c0['cell_m'] * 100:g} cm. The three methods' states share one union.", ""]
        total = "rsm_localizer_t (total)"
        rows = [[total] + [x for n in names for x in (fmt_int(mem["configs"][n]["sizes"]["rsm_localizer_t"]),
                                                      _kib(mem["configs"][n]["sizes"]["rsm_localizer_t"]))]]
        for label, key, depth in HOST_PARTS:
            rows.append(["&nbsp;&nbsp;" * (depth + 1) + label]
                        + [x for n in names for x in (fmt_int(mem["configs"][n]["sizes"][key]),
                                                      _kib(mem["configs"][n]["sizes"][key]))])
        rows.append(["&nbsp;&nbsp;other (config pointer, stamps, padding)"]
                    + [x for n in names for x in (fmt_int(mem["configs"][n]["other"]),
                                                  _kib(mem["configs"][n]["other"]))])
        rows += [[k] + [x for n in names for x in (fmt_int(mem["configs"][n]["sizes"][k]),
                                                   _kib(mem["configs"][n]["sizes"][k]))] for k in MEMORY_OTHER]
        L += md_table(["part"] + [h for n in names for h in (f"{n} [bytes]", f"{n} [KiB]")], rows, "memory host")
    else:
        L += ["Host sizes not measured in this run.", ""]
    if xc and "skipped" not in xc:
        L += [f"Cortex-M4F (`tools/cross-check`, {xc['compiler']}, -Os, default configuration): flash (text + "
              "rodata) per object of the library and the bare-metal port.", ""]
        rows = [[o["library"], o["object"], fmt_int(o["text"]), fmt_int(o["rodata"]), fmt_int(o["flash"]),
                 fmt_int(o["ram"])] for o in xc["objects"]]
        rows += [[lib, "TOTAL", fmt_int(t["text"]), fmt_int(t["rodata"]), fmt_int(t["flash"]), fmt_int(t["ram"])]
                 for lib, t in xc["totals"].items()]
        L += md_table(["library", "object", "text", "rodata", "flash", "RAM"], rows, "memory arm objects")
        fw = xc["firmware"]
        L += ["The example firmware image (port/baremetal, `--gc-sections`, newlib-nano):", ""]
        L += md_table(["text", "data", "bss", "total"],
                      [[fmt_int(fw["text"]), fmt_int(fw["data"]), fmt_int(fw["bss"]), fmt_int(fw["dec"])]],
                      "memory arm firmware")
        if "fw_localizer" in xc["statics"]:
            L += [f"Of its bss, the localizer state (`fw_localizer`, i.e. `sizeof(rsm_localizer_t)` on the "
                  f"32-bit target) is {fmt_int(xc['statics']['fw_localizer'])} bytes; all static objects "
                  f"of the firmware's main file total {fmt_int(xc['statics'].get('total', 0))} bytes. "
                  "Checks: " + "; ".join(xc["checks"]) + ".", ""]
            L += [FIRMWARE_SCAN_COPIES, ""]
    else:
        L += [f"Cortex-M4F sizes (tools/cross-check) not measured: {(xc or {}).get('skipped', 'disabled')}.", ""]
    L += report_arm_memory(am, root)
    from .navmemory import report as nav_memory_report
    L += nav_memory_report(ctx.get("nav_memory"))
    L += report_stack(am, ctx.get("host_stack"), ctx.get("stages"), ctx.get("stack_note"))
    return L


def report_floors(ctx: dict) -> List[str]:
    floors = ctx.get("floors") or []
    n = {k: sum(1 for f in floors if f["status"] == k) for k in ("PASS", "MISS", "SKIP")}
    L = ["The floors of issues 10 and 11, each checked on this run's figures and printed as PASS or MISS (SKIP: not "
         "measured in this run). They are a report, not an assertion: the bench does not fail on a MISS. Peers: "
         "the lowest figure among the peers of peers.md for that log. Robustness: rsm with "
         f"{FLOOR_LEVEL} % outliers against its own clean run, translation, local <= x{FLOOR_ROBUST['local']:.2f} "
         f"and all relations <= x{FLOOR_ROBUST['all']:.2f}, at every seed. Memory: `sizeof(rsm_localizer_t)` "
         f"from the Cortex-M4F probe of section 5. Instructions: callgrind, section 4; on the target, issue 11's mean and "
         f"p99 of the replay firmware, section 4. Then the checks that need "
         f"the full logs (`rsm_tools.fullchecks`): the logs against their description in docs/reference, rsm "
         f"against ICP and odometry, a bit-identical rerun, and the capture path (`rsm-convert`, then "
         f"`rsm-nav --capture`): the direct run's poses until the robot first moves, local error within "
         f"x{fullchecks.CAPTURE_TOLERANCE:.2f} of the direct run's, all-relations error within the spread of "
         f"direct runs with +-{fullchecks.JITTER_M * 1e6:g} um of odometry jitter.", "",
         f"{n['PASS']} PASS, {n['MISS']} MISS" + (f", {n['SKIP']} SKIP" if n["SKIP"] else "") + ":", "", "```"]
    L += [f["line"] for f in floors]
    L += ["```", ""]
    from .deskew import report as deskew_report
    L += deskew_report(ctx.get("deskew_bursts"))
    return L


def headline_extras(ctx: dict) -> List[str]:
    out = []
    rob = ctx.get("robustness")
    for label, r in ((rob or {}).get("logs") or {}).items():
        if FLOOR_LEVEL in r["levels"]:
            x = r["table"][f"rsm:{FLOOR_LEVEL}"]
            out.append(f"with {FLOOR_LEVEL} % outliers rsm's translation error on `{label}` is "
                       f"{fmt_ratio(x['local.translation']['ratio'])} times its clean figure on local relations and "
                       f"{fmt_ratio(x['all.translation']['ratio'])} times on all")
    speed = ctx.get("speed")
    if speed:
        out.append(f"rsm's median time per scan on `{ctx['main_label']}` is "
                   f"{_us(speed['methods']['rsm']['median_us'])} us "
                   f"(paper's method {_us(speed['methods']['paper']['median_us'])}, icp "
                   f"{_us(speed['methods']['icp']['median_us'])})")
    cg = ctx.get("callgrind")
    r = cg_run(cg, ctx["main_label"], "default", "rsm")
    if r:
        p = cg_run(cg, ctx["main_label"], "default", "paper")
        out.append(f"rsm executes {fmt_int(round(r['ir_per_scan']))} instructions per scan (callgrind, first "
                   f"{r['scans']} scans of `{ctx['main_label']}`)"
                   + (f", {fmt_ratio(r['ir_per_scan'] / p['ir_per_scan'])} times the paper's method's" if p else ""))
    am = ctx.get("arm_memory")
    if am and "skipped" not in am:
        parts = [f"{fmt_int(c['state'][0]['bytes'])} bytes with `{c['header']}`" for c in am["configs"].values()
                 if c.get("state")]
        if parts:
            out.append("the localizer state on Cortex-M4F is " + " and ".join(parts))
        c = am["configs"].get("default")
        if c:
            stk = c["stack"]
            out.append(f"one localizer step needs at most {fmt_int(stk['rsm_localizer_scan']['bytes'])} bytes of "
                       "stack on Cortex-M4F (static bound, libm calls not counted)")
    tn = ctx.get("turns")
    if tn and tn["turns"]:
        sm = tn["summary"]
        out.append(f"at the {len(tn['turns'])} sharpest turns rsm's mean residual is "
                   f"{_cells(sm['rsm']['translation_cells']['mean'])} cells and "
                   f"{_deg(sm['rsm']['rotation_deg']['mean'])} "
                   f"deg (paper's method {_cells(sm['paper']['translation_cells']['mean'])} cells, "
                   f"{_deg(sm['paper']['rotation_deg']['mean'])} deg; odometry "
                   f"{_cells(sm['odometry']['translation_cells']['mean'])} cells, "
                   f"{_deg(sm['odometry']['rotation_deg']['mean'])} deg)")
    return out


def write_report(ctx: dict) -> str:
    root: Path = ctx["root"]
    prov = ctx["provenance"]
    pl = provenance_line(prov)
    acc = ctx["accuracy"]
    main = ctx["main_label"]
    L: List[str] = []
    L += [
        "# rsm benchmark results",
        "",
        "Generated by `./tools/bench` (`python -m rsm_tools.bench`); do not edit by hand. Every figure of this "
        "repository's methods below was measured by that command in the run described here; the peers' figures "
        "are read from docs/reference/peers.md.",
        "",
        pl,
        "",
    ]
    if ctx.get("sources_changed"):
        L += [f"**WARNING: {ctx['sources_changed']}.**", ""]
    L += [
        f"Bench settings: logs {', '.join(f'`{k}`' for k in acc)} (every folder of "
        f"`{shown_path(Path(ctx['data_dir']), root)}` with a log and its relations); outlier levels "
        f"{', '.join(str(v) for v in ctx['levels'])} % on `{main}`, "
        f"{', '.join(str(v) for v in ctx['other_levels'])} % on the others; {len(ctx['seeds'])} seed(s) per level "
        f"({', '.join(str(s) for s in ctx['seeds'])}); {ctx['speed_repeats']} speed repeat(s); "
        f"{ctx['jobs']} rsm-nav process(es) at a time" + (", quick mode" if ctx["quick"] else "") + ". "
        f"Whole bench: {ctx['elapsed']:.0f} s ("
        + ", ".join(f"{k} {v:.0f} s" for k, v in ctx["stage_seconds"].items()) + ").",
        "",
    ]
    L += ["## Headline", "", pl, "",
          f"Mean relative-pose error on every log (local = relations spanning at most {LOCAL_SPAN:g} s), "
          f"beside the peers of peers.md; *rsm-small* is rsm built with `{SMALL_HEADER}`; *rsm before* the "
          "earlier rsm as peers.md measured it.", ""]
    rows = [row for label in acc for row in summary_rows(ctx, label)]
    L += md_table(["log", "method", "all translation [m]", "all rotation [deg]", "local translation [m]",
                   "local rotation [deg]"], rows, "headline")
    pe = ctx.get("peers") or {}
    if "skipped" in pe:
        L += [f"No peer figures in this run: {pe['skipped']}.", ""]
    floors = ctx.get("floors") or []
    if floors:
        L += ["The issue's floors (section 7):", "", "```"] + [f["line"] for f in floors] + ["```", ""]
    extra = headline_extras(ctx)
    if extra:
        L += ["In this run: " + "; ".join(extra) + ".", ""]

    sections = (
        report_accuracy(ctx, root),
        report_robustness(ctx, root) + report_faults(ctx.get("faults")) +
        _fixedmatch.report(ctx.get("fixed_match")) + report_knownmap(ctx.get("knownmap")),
        report_turns(ctx.get("turns"), main, root) + plot_lines(
            ctx.get("turns") and ctx.get("turns_plot"), ctx.get("turns_plot_note"),
            "Residuals at the sharpest turns and by true rotation"),
        report_speed(ctx, root),
        report_memory(ctx, root),
        report_scaling(ctx.get("scaling"), main),
        report_floors(ctx),
        [f"- {item}" for item in ctx["losses"]] + [""],
    )
    for title, body in zip(SECTION_TITLES, sections):
        L += [f"## {title}", "", pl, ""] + body
    return "\n".join(L)


def report_speed(ctx: dict, root: Path) -> List[str]:
    speed, main = ctx.get("speed"), ctx["main_label"]
    L = []
    if speed:
        L += [f"Wall time of `rsm_localizer_scan` per scan, from rsm-nav's summary, on `{main}` "
              f"({speed['methods']['rsm']['scans']} scans). The methods ran in turn, one process at a time, "
              f"{speed['repeats']} time(s) each, in this bench run; the table gives the median over the repeats "
              "of each run's median and 95th percentile, and the range over the repeats. Wall times depend on the "
              "machine and its load.", ""]
        rows = []
        for m in ROBUST_METHODS:
            s_ = speed["methods"][m]
            rows.append([m, f"{s_['median_us']:.1f}", f"{s_['median_min']:.1f}..{s_['median_max']:.1f}",
                         f"{s_['p95_us']:.1f}", f"{s_['p95_min']:.1f}..{s_['p95_max']:.1f}"])
        for m in ROBUST_METHODS[1:]:
            rows.append([f"{m} / rsm", fmt_ratio(speed["ratio_median"][m]), "", fmt_ratio(speed["ratio_p95"][m]), ""])
        L += md_table(["method", "median [us]", "range", "p95 [us]", "range"], rows, "speed wall")
        ident = all(Path(r["trajectory"]).read_bytes() == Path(ctx["accuracy"][main]["runs"][r["method"]]["trajectory"])
                    .read_bytes() for r in speed["runs"])
        L += [("Every repeat wrote a trajectory bit-identical to the accuracy run's."
               if ident else "WARNING: a repeat wrote a trajectory that differs from the accuracy run's."), ""]
    else:
        L += ["Wall time not measured in this run.", ""]
    L += report_callgrind(ctx.get("callgrind"), root, main)
    L += report_m4(ctx.get("m4"))
    ps = ctx.get("peer_speed_table")
    if ps:
        L += ["peers.md's speed table, as it is there (its own runs, `-O2`; \"rsm\" there is the earlier rsm):", ""]
        L += md_table(ps["header"], ps["rows"], "peers speed")
    L += report_stage_speed(ctx.get("stages"), speed, main)
    return L


def context_from_manifest(manifest: dict, root: Path) -> dict:
    """The report's input from a manifest (bench.json, parsed): JSON keeps
    the peers' figures under "scope quantity" keys, the report reads them by
    (scope, quantity); and the repository root, which the manifest leaves out."""
    ctx = dict(manifest)
    ctx["root"] = root
    for rows in (ctx.get("peers") or {}).get("accuracy", {}).values():
        for r in rows:
            r["values"] = {tuple(k.split(" ", 1)): v for k, v in r["values"].items()}
    return ctx


def write_from_manifest(manifest: dict, root: Path, output: Path, figures_path: Path) -> None:
    """The report and the figures the README and the headers quote, from a
    manifest (bench.json, parsed): what rsm-bench writes after measuring and
    rsm-bench-report writes again. The figures first: the report reads its
    context in place."""
    ctx = context_from_manifest(manifest, root)
    figures.write(ctx, figures_path)
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(write_report(ctx), encoding="utf-8")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="rsm-bench-report",
                                description="Write rsm-bench's report again from its manifest (bench.json in the "
                                            "work directory), without measuring anything.")
    p.add_argument("manifest", type=Path, help="the manifest rsm-bench wrote (BUILD/bench-work/bench.json)")
    p.add_argument("--root", type=Path, help="repository root (default: found from the current folder)")
    p.add_argument("--output", type=Path, help="report (default: the one the manifest names)")
    p.add_argument("--figures", type=Path, help="the figures the README and the headers quote (default: "
                   "results/figures.json beside the report, as rsm-bench writes it)")
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Exit status as the C tools: 0 written, 1 a file could not be read or
    written, 2 a bad command line (argparse's own)."""
    args = build_parser().parse_args(argv)
    try:
        manifest = json.loads(args.manifest.read_text(encoding="utf-8"))
        root = (args.root or find_root()).resolve()
        output = args.output or Path(manifest["report"])
        write_from_manifest(manifest, root, output, args.figures or output.parent / "results" / "figures.json")
    except (OSError, ValueError, KeyError, BenchError) as exc:
        print(f"rsm-bench-report: error: {exc}", file=sys.stderr)
        return 1
    print(f"rsm-bench-report: wrote {output}")
    return 0
