"""rsm-bench: measures rsm against its ICP baseline and odometry and writes a report.

Every figure in the report is measured by this command; none is typed in.
The report (``docs/RESULTS.md`` by default) has seven sections:

1. Accuracy: relative-pose error (Kuemmerle et al. 2009, :mod:`rsm_tools.evaluate`)
   of rsm, icp and odometry on the real log (and on any extra ``--log`` /
   ``--relations`` pairs), on all relations and on local ones (span <= 2 s).
2. Robustness, the paper's experiment: a share of every scan's readings is
   replaced by random ranges (:mod:`rsm_tools.outliers`), several seeds per
   level; errors per level with their spread and their ratio to the clean run.
3. Sharp turns, the paper's Fig. 8: the residuals (cells and degrees) of the
   three trajectories at the local relations with the fastest true turn, and
   over all local relations binned by their true rotation.
4. Speed: wall time per scan from rsm-nav's summary (rsm and icp, the same
   bench run, one process at a time); per-stage times from ``rsm-stages``
   (tools/bench-c), which runs the log with the localizer's timing hook;
   instructions per scan counted by callgrind inside ``rsm_localizer_scan``
   on the shipped excerpt, in total and by the functions it calls.
5. Memory: ``sizeof(rsm_localizer_t)`` and its parts from a small C program
   built against the library; the Cortex-M4F sizes printed by
   ``tools/cross-check``; per module and per configuration (default and
   ``tests/config/small_config.h``) from Cortex-M4F builds of this bench;
   the stack of one localizer step, statically (``-fstack-usage
   -fcallgraph-info=su`` and the call graph) and by painting a thread's stack
   (``rsm-stages --stack``).
6. Scaling: time per scan against readings per scan (the log resampled) and
   map size, each a build with its own ``RSM_USER_CONFIG``; the state's size.
7. Where rsm loses: generated from the numbers above.

Trajectories, summaries and a manifest (``bench.json``) are kept in the work
directory, so that the report can be checked against them; outlier logs are
cached and reused.  ``tools/bench`` sets up, builds ``build-release/`` and
runs this module with the full settings.  Python standard library only;
matplotlib, if installed, draws the plots.
"""

import argparse
import concurrent.futures
import datetime
import hashlib
import json
import math
import os
import platform
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from . import evaluate as ev
from . import outliers

METHODS = ("rsm", "icp", "odometry")
ROBUST_METHODS = ("rsm", "icp")
LEVELS = (0, 10, 20, 30, 43, 50, 60)
QUICK_LEVELS = (0, 20, 43)
SEEDS = 3
SPEED_REPEATS = 3
LOCAL_SPAN = 2.0
SCOPES = ("local", "all")
QUANTITIES = ("translation", "rotation")
UNITS = {"translation": "m", "rotation": "deg"}
SECTION_TITLES = (
    "1. Accuracy on the real log",
    "2. Robustness to outliers",
    "3. Sharp turns (the paper's Fig. 8)",
    "4. Speed",
    "5. Memory",
    "6. Scaling",
    "7. Where rsm loses",
)


class BenchError(RuntimeError):
    """A stage of the bench could not run."""


# ---------------------------------------------------------------------------
# formatting (the test reads the report back with the same precision rules)


def fmt_q(quantity: str, v: float) -> str:
    """A translation in m (4 decimals) or a rotation in degrees (3 decimals)."""
    if v is None or not math.isfinite(v):
        return "n/a"
    return f"{v:.4f}" if quantity == "translation" else f"{v:.3f}"


def fmt_ratio(v: float) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.2f}"


def fmt_pct(v: float) -> str:
    return "n/a" if v is None or not math.isfinite(v) else f"{v:.1f}"


def fmt_int(v: int) -> str:
    return f"{v:,}".replace(",", " ")


def ratio(a: float, b: float) -> float:
    if b is None or a is None or b == 0 or not (math.isfinite(a) and math.isfinite(b)):
        return float("nan")
    return a / b


# ---------------------------------------------------------------------------
# paths and provenance


def find_root(start: Optional[Path] = None) -> Path:
    """The repository root: the first folder upwards holding include/rsm/localizer.h."""
    for base in ((start or Path.cwd()).resolve(), Path(__file__).resolve().parent):
        for d in (base, *base.parents):
            if (d / "include" / "rsm" / "localizer.h").is_file():
                return d
    raise BenchError("cannot find the rsm repository root (include/rsm/localizer.h); use --root")


def shown_path(path: Path, root: Path) -> str:
    """How a path is written into the report: relative to the repository root
    when it is inside it or beside it (../shared), else only its file name."""
    try:
        rel = os.path.relpath(Path(path).resolve(), root)
    except ValueError:
        return Path(path).name
    if rel.startswith(os.pardir + os.sep + os.pardir) or os.path.isabs(rel):
        return Path(path).name
    return rel.replace(os.sep, "/")


def cmake_cache(build_dir: Path) -> Dict[str, str]:
    cache = {}
    f = build_dir / "CMakeCache.txt"
    if f.is_file():
        for line in f.read_text(errors="replace").splitlines():
            m = re.match(r"^([A-Za-z_][A-Za-z0-9_]*):[A-Z]+=(.*)$", line)
            if m:
                cache[m.group(1)] = m.group(2)
    return cache


def first_line(cmd: Sequence[str]) -> Optional[str]:
    try:
        res = subprocess.run(list(cmd), capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return None
    lines = (res.stdout or res.stderr).strip().splitlines()
    return lines[0].strip() if res.returncode == 0 and lines else None


def cpu_info() -> Tuple[str, int]:
    """CPU model name (from /proc/cpuinfo where there is one) and logical cores."""
    model = None
    cores = 0
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as fh:
            for line in fh:
                key, _, value = line.partition(":")
                key = key.strip()
                if key == "processor":
                    cores += 1
                elif key in ("model name", "Model", "cpu model") and model is None:
                    model = value.strip()
    except OSError:
        pass
    return model or platform.processor() or platform.machine() or "unknown CPU", cores or (os.cpu_count() or 0)


def git_commit(root: Path) -> str:
    """Short hash of HEAD, with ``+changes`` if tracked or untracked files other
    than the generated report differ from it."""
    head = first_line(["git", "-C", str(root), "rev-parse", "--short=12", "HEAD"]) or "unknown"
    try:
        res = subprocess.run(["git", "-C", str(root), "status", "--porcelain"],
                             capture_output=True, text=True, timeout=60)
        changed = [l[3:] for l in res.stdout.splitlines() if l.strip()]
    except (OSError, subprocess.TimeoutExpired):
        changed = []
    changed = [p for p in changed if not (p.startswith("docs/RESULTS.md") or p.startswith("docs/results"))]
    return head + (" +changes" if changed else "")


def compiler_name(build_dir: Path, cc: str) -> str:
    """``GNU 12.2.0 (first line of cc --version)``: CMake's compiler id and
    version for the build, with the compiler's own version line."""
    ident = ""
    for f in sorted(build_dir.glob("CMakeFiles/*/CMakeCCompiler.cmake")):
        text = f.read_text(errors="replace")
        cid = re.search(r'set\(CMAKE_C_COMPILER_ID "([^"]*)"\)', text)
        ver = re.search(r'set\(CMAKE_C_COMPILER_VERSION "([^"]*)"\)', text)
        if cid and ver:
            ident = f"{cid.group(1)} {ver.group(1)}"
    line = first_line([cc, "--version"]) or Path(cc).name
    return f"{ident} ({line})" if ident else line


def provenance(root: Path, build_dir: Path) -> dict:
    model, cores = cpu_info()
    cache = cmake_cache(build_dir)
    cc = cache.get("CMAKE_C_COMPILER") or "cc"
    build_type = cache.get("CMAKE_BUILD_TYPE", "")
    flags = cache.get(f"CMAKE_C_FLAGS_{build_type.upper()}", "") if build_type else ""
    return {
        "cpu": model,
        "cores": cores,
        "compiler": compiler_name(build_dir, cc),
        "build_type": build_type or "default",
        "build_flags": " ".join((cache.get("CMAKE_C_FLAGS", "") + " " + flags).split()),
        "commit": git_commit(root),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "python": platform.python_version(),
    }


def provenance_line(p: dict) -> str:
    flags = f", `{p['build_flags']}`" if p["build_flags"] else ""
    return (f"Measured {p['date']} on {p['cpu']} ({p['cores']} cores), {p['compiler']}, "
            f"{p['build_type']} build{flags}, commit `{p['commit']}`.")


# ---------------------------------------------------------------------------
# rsm-nav


_SUMMARY_TIME = re.compile(r"time per scan\s+median\s+([0-9.]+)\s*us,\s*p95\s+([0-9.]+)\s*us")
_SUMMARY_SCANS = re.compile(r"^\s+scans\s+(\d+)\s*$")
_SUMMARY_OUTCOME = re.compile(r"^\s{4}([a-z_]+)\s+(\d+)\s*$")


def parse_summary(text: str) -> dict:
    """Scans, outcome counts and per-scan wall times from rsm-nav's summary."""
    out = {"scans": None, "outcomes": {}, "median_us": None, "p95_us": None}
    in_outcomes = False
    for line in text.splitlines():
        m = _SUMMARY_SCANS.match(line)
        if m:
            out["scans"] = int(m.group(1))
            in_outcomes = True
            continue
        m = _SUMMARY_OUTCOME.match(line)
        if in_outcomes and m:
            out["outcomes"][m.group(1)] = int(m.group(2))
            continue
        in_outcomes = False
        m = _SUMMARY_TIME.search(line)
        if m:
            out["median_us"] = float(m.group(1))
            out["p95_us"] = float(m.group(2))
    if out["scans"] is None or out["median_us"] is None:
        raise BenchError("rsm-nav printed no summary:\n" + text)
    return out


def fused_percent(summary: dict) -> float:
    s = summary["scans"] or 0
    return 100.0 * summary["outcomes"].get("accepted", 0) / s if s else float("nan")


def run_nav(nav: Path, log: Path, method: str, traj: Path, prefix: Sequence[str] = ()) -> dict:
    """Runs rsm-nav (optionally under a wrapper such as valgrind); returns its
    summary text and the wall time of the whole process."""
    traj.parent.mkdir(parents=True, exist_ok=True)
    cmd = [*prefix, str(nav), "--carmen", str(log), "--method", method,
           "--trajectory", str(traj), "--quiet"]
    t0 = time.monotonic()
    res = subprocess.run(cmd, capture_output=True, text=True)
    elapsed = time.monotonic() - t0
    if res.returncode != 0:
        raise BenchError(f"{' '.join(cmd)} failed ({res.returncode}):\n{res.stderr}")
    return {"summary": res.stdout, "stderr": res.stderr, "seconds": elapsed}


def parallel(fn, items: Iterable, jobs: int) -> list:
    """fn over items, ``jobs`` at a time (threads: the work is in subprocesses)."""
    items = list(items)
    if jobs <= 1 or len(items) <= 1:
        return [fn(i) for i in items]
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(fn, items))


# ---------------------------------------------------------------------------
# evaluation


def scoped_errors(traj: Path, relations: List[ev.Relation], details: bool = False) -> dict:
    """evaluate() on all relations and on local ones, exact timestamps only."""
    t = ev.load_trajectory(traj)
    return {
        "all": ev.evaluate(t, relations, tolerance=0.0, details=details),
        "local": ev.evaluate(t, relations, max_span=LOCAL_SPAN, tolerance=0.0),
    }


def _strip_errors(res: dict) -> dict:
    return {s: {k: v for k, v in r.items() if k != "errors"} for s, r in res.items()}


# ---------------------------------------------------------------------------
# section 1: accuracy


def log_label(log: Path, taken: Iterable[str]) -> str:
    name = log.name
    for ext in (".gz", ".clf", ".log", ".txt"):
        if name.endswith(ext):
            name = name[: -len(ext)]
    label, k = name or "log", 2
    while label in taken:
        label = f"{name}-{k}"
        k += 1
    return label


def run_accuracy(nav: Path, logs: List[Tuple[str, Path, Path]], work: Path, jobs: int) -> dict:
    tasks = [(label, log, m) for label, log, _ in logs for m in METHODS]

    def one(task):
        label, log, m = task
        traj = work / "accuracy" / label / f"{m}.txt"
        return task, traj, run_nav(nav, log, m, traj)

    done = parallel(one, tasks, jobs)
    out = {}
    for label, log, rel in logs:
        relations = ev.load_relations(rel)
        runs = {}
        for (lab, _, m), traj, r in done:
            if lab != label:
                continue
            errs = scoped_errors(traj, relations, details=True)
            runs[m] = {
                "trajectory": str(traj),
                "summary_text": r["summary"],
                "summary": parse_summary(r["summary"]),
                "errors": _strip_errors(errs),
                "per_relation": errs["all"]["errors"],
            }
        out[label] = {"log": str(log), "relations": str(rel), "relation_count": len(relations), "runs": runs}
    return out


# ---------------------------------------------------------------------------
# section 2: robustness


def file_digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _make_outlier_log(src: str, dst: str, level: int, seed: int) -> str:
    tmp = f"{dst}.tmp{os.getpid()}"
    outliers.inject_file(src, tmp, level, seed)
    os.replace(tmp, dst)
    return dst


def outlier_logs(log: Path, levels: Sequence[int], seeds: Sequence[int], cache: Path,
                 jobs: int) -> Tuple[Dict[Tuple[int, int], Path], int]:
    """The outlier logs (level > 0) for every seed, from the cache or made now.
    Returns them and how many were made."""
    cache.mkdir(parents=True, exist_ok=True)
    tag = file_digest(log)[:12]
    stem = log_label(log, ())
    want = {}
    for level in levels:
        if level == 0:
            continue
        for seed in seeds:
            want[(level, seed)] = cache / f"{stem}-{tag}-p{level}-s{seed}.clf.gz"
    missing = [(k, p) for k, p in want.items() if not p.is_file()]
    if missing:
        with concurrent.futures.ProcessPoolExecutor(max_workers=max(1, jobs)) as pool:
            futs = [pool.submit(_make_outlier_log, str(log), str(p), k[0], k[1]) for k, p in missing]
            for f in futs:
                f.result()
    return want, len(missing)


def spread(values: Sequence[float]) -> dict:
    vals = [v for v in values if v is not None and math.isfinite(v)]
    if not vals:
        return {"mean": float("nan"), "min": float("nan"), "max": float("nan"), "n": 0}
    return {"mean": math.fsum(vals) / len(vals), "min": min(vals), "max": max(vals), "n": len(vals)}


def run_robustness(nav: Path, log: Path, relations_path: Path, clean_runs: dict, levels: Sequence[int],
                   seeds: Sequence[int], work: Path, cache: Path, jobs: int) -> dict:
    logs, made = outlier_logs(log, levels, seeds, cache, jobs)
    tasks = [(m, level, seed) for level in levels if level != 0 for seed in seeds for m in ROBUST_METHODS]

    def one(task):
        m, level, seed = task
        traj = work / "robustness" / f"{m}-p{level}-s{seed}.txt"
        return task, traj, run_nav(nav, logs[(level, seed)], m, traj)

    done = parallel(one, tasks, jobs)
    relations = ev.load_relations(relations_path)
    runs = []
    for m in ROBUST_METHODS:  # level 0 is the clean log itself: the accuracy runs
        c = clean_runs[m]
        runs.append({"method": m, "level": 0, "seed": None, "trajectory": c["trajectory"],
                     "summary": c["summary"], "errors": c["errors"]})
    for (m, level, seed), traj, r in done:
        runs.append({"method": m, "level": level, "seed": seed, "trajectory": str(traj),
                     "log": str(logs[(level, seed)]), "summary": parse_summary(r["summary"]),
                     "errors": _strip_errors(scoped_errors(traj, relations))})
    table = {}
    for m in ROBUST_METHODS:
        for level in levels:
            sel = [r for r in runs if r["method"] == m and r["level"] == level]
            row = {"seeds": [r["seed"] for r in sel],
                   "fused": spread([fused_percent(r["summary"]) for r in sel])}
            for s in SCOPES:
                for q in QUANTITIES:
                    row[f"{s}.{q}"] = spread([r["errors"][s][q]["mean"] for r in sel])
            table[f"{m}:{level}"] = row
    for m in ROBUST_METHODS:
        clean = table[f"{m}:0"]
        for level in levels:
            row = table[f"{m}:{level}"]
            for key in [f"{s}.{q}" for s in SCOPES for q in QUANTITIES]:
                row[key]["ratio"] = ratio(row[key]["mean"], clean[key]["mean"])
    return {"log": str(log), "relations": str(relations_path), "levels": list(levels),
            "seeds": list(seeds), "outlier_logs_made": made, "runs": runs, "table": table}


# ---------------------------------------------------------------------------
# section 3: speed


def run_speed(nav: Path, log: Path, repeats: int, work: Path) -> dict:
    """rsm and icp alternately, one process at a time, ``repeats`` times each."""
    runs = []
    for k in range(repeats):
        for m in ROBUST_METHODS:
            traj = work / "speed" / f"{m}-r{k + 1}.txt"
            r = run_nav(nav, log, m, traj)
            runs.append({"method": m, "repeat": k + 1, "trajectory": str(traj),
                         "summary_text": r["summary"], "summary": parse_summary(r["summary"])})
    out = {"log": str(log), "repeats": repeats, "runs": runs, "methods": {}}
    for m in ROBUST_METHODS:
        sel = [r["summary"] for r in runs if r["method"] == m]
        med = sorted(s["median_us"] for s in sel)
        p95 = sorted(s["p95_us"] for s in sel)
        out["methods"][m] = {
            "median_us": med[len(med) // 2], "median_min": med[0], "median_max": med[-1],
            "p95_us": p95[len(p95) // 2], "p95_min": p95[0], "p95_max": p95[-1],
            "scans": sel[0]["scans"],
        }
    out["ratio_median"] = ratio(out["methods"]["icp"]["median_us"], out["methods"]["rsm"]["median_us"])
    out["ratio_p95"] = ratio(out["methods"]["icp"]["p95_us"], out["methods"]["rsm"]["p95_us"])
    return out


_CG_TOTALS = re.compile(r"^(?:totals|summary):\s+(\d+)", re.M)


def callgrind_ir(out_file: Path) -> int:
    m = _CG_TOTALS.search(out_file.read_text(errors="replace"))
    if not m:
        raise BenchError(f"no totals in callgrind output {out_file}")
    return int(m.group(1))


def run_callgrind(nav: Path, log: Path, work: Path, jobs: int, root: Optional[Path] = None) -> dict:
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        return {"skipped": "valgrind is not installed"}
    helpers = static_functions((root / "src" / "localizer.c").read_text()) if root else []

    def one(m):
        out = work / "callgrind" / f"{m}.callgrind.out"
        traj = work / "callgrind" / f"{m}.txt"
        out.parent.mkdir(parents=True, exist_ok=True)
        prefix = [valgrind, "--tool=callgrind", "--toggle-collect=rsm_localizer_scan",
                  f"--callgrind-out-file={out}"]
        r = run_nav(nav, log, m, traj, prefix)
        s = parse_summary(r["summary"])
        ir = callgrind_ir(out)
        if ir == 0:
            raise BenchError(f"callgrind collected nothing in rsm_localizer_scan for {m} "
                             "(is the symbol in the binary?)")
        res = {"out": str(out), "scans": s["scans"], "ir": ir, "ir_per_scan": ir / s["scans"]}
        br = localizer_breakdown(parse_callgrind(out.read_text(errors="replace")), helpers)
        if br["total"] == ir:  # the breakdown accounts for every instruction collected
            res["breakdown"] = br
            res["stages"] = callgrind_stages(br, s["scans"])
        else:
            res["breakdown_note"] = f"the call graph accounts for {br['total']} of {ir} instructions"
        return m, res

    res = dict(parallel(one, ROBUST_METHODS, jobs))
    res["ratio"] = ratio(res["icp"]["ir_per_scan"], res["rsm"]["ir_per_scan"])
    res["log"] = str(log)
    res["valgrind"] = first_line([valgrind, "--version"]) or "valgrind"
    return res


# ---------------------------------------------------------------------------
# section 4: memory

# (label, C expression) of the parts of rsm_localizer_t listed in the report.
MEMORY_PARTS = (
    ("ekf", "sizeof loc.ekf"),
    ("odo", "sizeof loc.odo"),
    ("map", "sizeof loc.map"),
    ("image", "sizeof loc.image"),
    ("ransac", "sizeof loc.ransac"),
    ("work (union of the two below)", "sizeof loc.work"),
    ("work.rsm (visited + harris + cands)", "sizeof loc.work.rsm"),
    ("work.icp", "sizeof loc.work.icp"),
    ("kp_cur + kp_ref", "sizeof loc.kp_cur + sizeof loc.kp_ref"),
    ("pt_cur + pt_ref", "sizeof loc.pt_cur + sizeof loc.pt_ref"),
    ("matches", "sizeof loc.matches"),
    ("pts + world", "sizeof loc.pts + sizeof loc.world"),
    ("counters + last report", "sizeof loc.counters + sizeof loc.last"),
)
# Parts that tile the struct (the rest is pointers, stamps and padding).
MEMORY_TILES = ("ekf", "odo", "map", "image", "ransac", "work (union of the two below)",
                "kp_cur + kp_ref", "pt_cur + pt_ref", "matches", "pts + world",
                "counters + last report")
MEMORY_OTHER = ("rsm_localizer_config_t", "rsm_scan_t")
MEMORY_MACROS = ("RSM_MAX_BEAMS", "RSM_MAP_SIZE", "RSM_MAX_KEYPOINTS", "RSM_MAX_CANDIDATES",
                 "RSM_MAX_MATCHES", "RSM_ICP_MAX_POINTS")


def memory_program() -> str:
    lines = [
        "/* Generated by rsm_tools.bench: sizes of the localizer state. */",
        "#include <stdio.h>",
        '#include "rsm/localizer.h"',
        '#include "rsm/status.h"',
        "",
        "static rsm_localizer_t loc;",
        "static rsm_localizer_config_t cfg;",
        "",
        "int main(void)",
        "{",
        "    rsm_pose_t x0 = {0.0f, 0.0f, 0.0f};",
        "    cfg = rsm_localizer_config_default();",
        "    if (rsm_localizer_init(&loc, &cfg, &x0, NULL) != RSM_OK) {",
        '        fprintf(stderr, "default config rejected\\n");',
        "        return 1;",
        "    }",
        '    printf("size|rsm_localizer_t|%lu\\n", (unsigned long)sizeof loc);',
    ]
    for label, expr in MEMORY_PARTS:
        lines.append(f'    printf("part|{label}|%lu\\n", (unsigned long)({expr}));')
    for t in MEMORY_OTHER:
        lines.append(f'    printf("size|{t}|%lu\\n", (unsigned long)sizeof({t}));')
    for mac in MEMORY_MACROS:
        lines.append(f'    printf("macro|{mac}|%lu\\n", (unsigned long)({mac}));')
    lines += ["    return 0;", "}", ""]
    return "\n".join(lines)


def run_memory(root: Path, build_dir: Path, work: Path) -> dict:
    cache = cmake_cache(build_dir)
    cc = cache.get("CMAKE_C_COMPILER") or shutil.which("cc") or "cc"
    libs = [p for p in (build_dir / "librsm.a", build_dir / "librsm.so") if p.exists()]
    if not libs:
        return {"skipped": f"no librsm in {shown_path(build_dir, root)}"}
    d = work / "memory"
    d.mkdir(parents=True, exist_ok=True)
    src = d / "rsm_sizes.c"
    exe = d / "rsm_sizes"
    src.write_text(memory_program())
    cmd = [cc, "-std=c99", "-O1", f"-I{root / 'include'}"]
    if cache.get("RSM_USER_CONFIG"):
        cmd.append(f"-DRSM_USER_CONFIG={cache['RSM_USER_CONFIG']}")
    if cache.get("RSM_SANITIZE", "OFF").upper() in ("ON", "TRUE", "1", "YES"):
        cmd.append("-fsanitize=address,undefined")
    cmd += [str(src), "-o", str(exe), str(libs[0]), "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        raise BenchError(f"building the size probe failed:\n{' '.join(cmd)}\n{res.stderr}")
    res = subprocess.run([str(exe)], capture_output=True, text=True)
    if res.returncode != 0:
        raise BenchError(f"the size probe failed:\n{res.stderr}")
    out = {"sizes": {}, "parts": {}, "macros": {}, "compiler": first_line([cc, "--version"]) or cc}
    for line in res.stdout.splitlines():
        kind, name, value = line.split("|")
        out[{"size": "sizes", "part": "parts", "macro": "macros"}[kind]][name] = int(value)
    total = out["sizes"]["rsm_localizer_t"]
    out["other"] = total - sum(out["parts"][k] for k in MEMORY_TILES)
    return out


def parse_cross_check(text: str) -> dict:
    """Objects, totals, firmware image sizes and the checks from tools/cross-check's output."""
    out = {"objects": [], "totals": {}, "firmware": None, "statics": {}, "checks": [], "passed": False}
    mode = None
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("ok:") or s.startswith("FAIL:"):
            out["checks"].append(s)
        if s.startswith("cross-check: all checks passed"):
            out["passed"] = True
        if "per object" in s and "flash" in s:
            mode = "objects"
            continue
        if s.startswith("Example firmware image"):
            mode = "firmware"
            continue
        if s.startswith("Static RAM"):
            mode = "statics"
            continue
        f = s.split()
        if mode == "objects" and len(f) == 8 and all(x.isdigit() for x in f[2:]):
            row = dict(zip(("text", "rodata", "data", "bss", "flash", "ram"), map(int, f[2:])))
            row.update(library=f[0], object=f[1])
            if f[1] == "TOTAL":
                out["totals"][f[0]] = row
            else:
                out["objects"].append(row)
        elif mode == "firmware" and len(f) >= 5 and all(x.isdigit() for x in f[:4]):
            out["firmware"] = dict(zip(("text", "data", "bss", "dec"), map(int, f[:4])))
        elif mode == "statics" and len(f) == 2 and f[0].isdigit():
            out["statics"][f[1]] = int(f[0])
    return out


def run_cross_check(root: Path) -> dict:
    script = root / "tools" / "cross-check"
    if not script.is_file():
        return {"skipped": "tools/cross-check is missing"}
    if shutil.which("arm-none-eabi-gcc") is None:
        return {"skipped": "arm-none-eabi-gcc is not installed"}
    res = subprocess.run([str(script)], cwd=root, capture_output=True, text=True)
    parsed = parse_cross_check(res.stdout)
    if res.returncode != 0 or not parsed["objects"] or parsed["firmware"] is None:
        raise BenchError(f"tools/cross-check failed ({res.returncode}):\n{res.stdout}\n{res.stderr}")
    parsed["compiler"] = first_line(["arm-none-eabi-gcc", "--version"]) or "arm-none-eabi-gcc"
    return parsed


# ---------------------------------------------------------------------------
# rsm-stages (tools/bench-c): stage times, stack depth, sizes


STAGES = ("points", "grid", "harris", "match", "ransac", "refine", "icp", "ekf", "map")
STAGE_WHAT = {
    "points": "readings -> robot-frame points",
    "grid": "map recentred, points -> scan image",
    "harris": "key points of scan and map",
    "match": "tentative matches",
    "ransac": "two-point RANSAC",
    "refine": "sub-cell alignment to the map",
    "icp": "ICP alignment (baseline)",
    "ekf": "measurement noise, gate, update",
    "map": "scan superimposed on the map",
}
TIMING_STATS = ("mean_us", "median_us", "p95_us", "max_us", "median_reached_us", "p95_reached_us")


def stages_exe(build: Path) -> Path:
    return build / "tools" / "bench-c" / "rsm-stages"


def run_stages(exe: Path, log: Path, method: str, extra: Sequence[str] = (),
               traj: Optional[Path] = None) -> dict:
    """Runs rsm-stages once; returns its JSON (and the wall time of the process)."""
    cmd = [str(exe), "--carmen", str(log), "--method", method, *extra]
    if traj is not None:
        traj.parent.mkdir(parents=True, exist_ok=True)
        cmd += ["--trajectory", str(traj)]
    t0 = time.monotonic()
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        raise BenchError(f"{' '.join(cmd)} failed ({res.returncode}):\n{res.stderr}")
    try:
        out = json.loads(res.stdout)
    except ValueError as exc:
        raise BenchError(f"rsm-stages printed no JSON ({exc}):\n{res.stdout[:2000]}") from None
    out["seconds"] = time.monotonic() - t0
    if traj is not None:
        out["trajectory"] = str(traj)
    return out


def median_of(values: Sequence[float]) -> float:
    """The middle element of the sorted values (the upper one of an even count),
    as rsm-nav and rsm-stages take medians."""
    vals = sorted(values)
    return vals[len(vals) // 2] if vals else float("nan")


def combine_timing(results: Sequence[dict]) -> dict:
    """Per timing key (stages, step, call, motion): the median over the runs of
    each statistic; counts from the first run (every run sees the same scans)."""
    out = {}
    for key in STAGES + ("step", "call", "motion"):
        stats = [r["timing"][key] for r in results if r["timing"].get(key)]
        if not stats:
            continue
        row = {s: median_of([st[s] for st in stats]) for s in TIMING_STATS}
        row["min_median_us"] = min(st["median_us"] for st in stats)
        row["max_median_us"] = max(st["median_us"] for st in stats)
        row["n"] = stats[0]["n"]
        row["reached"] = stats[0]["reached"]
        out[key] = row
    return out


def run_stage_speed(exe: Path, log: Path, repeats: int, stack: bool) -> dict:
    """rsm and icp alternately through rsm-stages with the clock hook,
    ``repeats`` times each; then one painted-stack run per method."""
    runs = []
    for k in range(repeats):
        for m in ROBUST_METHODS:
            runs.append({"method": m, "repeat": k + 1, "result": run_stages(exe, log, m, ["--clock", "ns"])})
    out = {"log": str(log), "repeats": repeats, "runs": runs, "methods": {}}
    for m in ROBUST_METHODS:
        sel = [r["result"] for r in runs if r["method"] == m]
        out["methods"][m] = {"timing": combine_timing(sel), "scans": sel[0]["scans"],
                             "beams": sel[0]["beams"], "outcomes": sel[0]["outcomes"]}
    out["config"] = runs[0]["result"]["config"]
    out["sizes"] = runs[0]["result"]["sizes"]
    r_, i_ = out["methods"]["rsm"]["timing"]["call"], out["methods"]["icp"]["timing"]["call"]
    out["ratio_median"] = ratio(i_["median_us"], r_["median_us"])
    out["ratio_p95"] = ratio(i_["p95_us"], r_["p95_us"])
    out["ratio_mean"] = ratio(i_["mean_us"], r_["mean_us"])
    if stack:
        out["stack"] = {m: run_stages(exe, log, m, ["--stack"])["stack"] for m in ROBUST_METHODS}
    return out


# ---------------------------------------------------------------------------
# callgrind: instructions per function called from rsm_localizer_scan


def parse_callgrind(text: str) -> dict:
    """Self cost per function and inclusive cost per call edge (caller, callee)
    from a callgrind output file (first event only, name compression resolved)."""
    names: Dict[str, str] = {}
    self_cost: Dict[str, int] = {}
    calls: Dict[Tuple[str, str], List[int]] = {}
    fn = None
    pending = None  # (callee, count) after a calls= line: the next cost line is the call's
    cfn = None

    def name_of(spec: str) -> str:
        m = re.match(r"^\((\d+)\)(?:\s+(.*))?$", spec.strip())
        if not m:
            return spec.strip()
        if m.group(2) is not None:
            names[m.group(1)] = m.group(2)
        return names.get(m.group(1), f"({m.group(1)})")

    for line in text.splitlines():
        if not line:
            continue
        if line.startswith("fn="):
            fn = name_of(line[3:])
            pending = None
        elif line.startswith("cfn="):
            cfn = name_of(line[4:])
        elif line.startswith("calls="):
            pending = (cfn, int(line[6:].split()[0]))
        elif line[0].isdigit() or line[0] in "+-*":
            parts = line.split()
            cost = int(parts[1]) if len(parts) > 1 else 0
            if fn is None:
                continue
            if pending is not None:
                e = calls.setdefault((fn, pending[0]), [0, 0])
                e[0] += pending[1]
                e[1] += cost
                pending = None
            else:
                self_cost[fn] = self_cost.get(fn, 0) + cost
    return {"self": self_cost, "calls": calls}


def base_name(fn: str) -> str:
    """A function's name without GCC's clone suffixes and callgrind's recursion mark."""
    fn = fn.split("'")[0]
    return re.sub(r"\.(?:isra|part|constprop|cold|lto_priv|localalias)(?:\.\d+)*.*$", "", fn)


def static_functions(source: str) -> List[str]:
    """Names of the file-scope static functions defined in a C source."""
    return re.findall(r"^static\s+(?:inline\s+)?[A-Za-z_][\w\s\*]*?\b([A-Za-z_]\w*)\s*\([^;]*?\)\s*\{",
                      source, re.M | re.S)


def localizer_breakdown(cg: dict, helpers: Iterable[str], root: str = "rsm_localizer_scan") -> dict:
    """Instructions of one rsm_localizer_scan call tree, split into the code of
    the localizer itself (root and the static helpers it calls directly, wherever
    the compiler left them out of line) and the inclusive cost of every other
    function it calls. The parts add up to the root's inclusive cost."""
    helpers = set(helpers)
    group = {root}
    changed = True
    while changed:
        changed = False
        for (caller, callee) in cg["calls"]:
            if base_name(caller) in group and base_name(callee) in helpers and base_name(callee) not in group:
                group.add(base_name(callee))
                changed = True
    own = sum(c for f, c in cg["self"].items() if base_name(f) in group)
    callees: Dict[str, int] = {}
    counts: Dict[str, int] = {}
    for (caller, callee), (n, ir) in cg["calls"].items():
        if base_name(caller) in group and base_name(callee) not in group:
            k = base_name(callee)
            callees[k] = callees.get(k, 0) + ir
            counts[k] = counts.get(k, 0) + n
    return {"group": sorted(group), "own": own, "callees": callees, "calls": counts,
            "total": own + sum(callees.values())}


# Stage of each function rsm_localizer_scan calls (by name); functions called
# from two stages are shown as such.
CALLEE_STAGE = {
    "rsm_scan_to_points": "points",
    "rsm_image_clear": "grid",
    "rsm_image_mark_points": "grid",
    "rsm_map_recenter": "grid + map",
    "cosf": "grid + map",
    "sinf": "grid + map",
    "sincosf": "grid + map",
    "rsm_harris_detect": "harris",
    "ceilf": "harris",
    "rsm_match_tentative": "match",
    "rsm_ransac_estimate": "ransac",
    "rsm_wrap_angle": "ransac",
    "rsm_map_align": "refine",
    "rsm_mat3_inverse": "refine",
    "rsm_icp_align": "icp",
    "rsm_ekf_mahalanobis": "ekf",
    "rsm_ekf_update": "ekf",
    "rsm_map_add_points": "map",
    "rsm_icp_set_reference": "map",
}
CG_STAGE_ORDER = ("points", "grid", "grid + map", "harris", "match", "ransac", "refine", "icp", "ekf", "map",
                  "other", "localizer")


def callgrind_stages(breakdown: dict, scans: int) -> Dict[str, dict]:
    """Instructions per scan by stage (CALLEE_STAGE; unknown callees: other;
    the localizer's own code: localizer), with the functions counted."""
    out: Dict[str, dict] = {}
    for fn, ir in breakdown["callees"].items():
        plain = re.sub(r"_(?:fma4?|avx2?|avx512\w*|sse\d*)$", "", fn.lstrip("_"))
        st = CALLEE_STAGE.get(fn, CALLEE_STAGE.get(plain, "other"))
        row = out.setdefault(st, {"ir": 0, "functions": []})
        row["ir"] += ir
        row["functions"].append(fn)
    out["localizer"] = {"ir": breakdown["own"], "functions": ["rsm_localizer_scan"] + [
        g for g in breakdown["group"] if g != "rsm_localizer_scan"]}
    for row in out.values():
        row["ir_per_scan"] = row["ir"] / scans if scans else float("nan")
        row["functions"] = sorted(set(row["functions"]))
    return out


# ---------------------------------------------------------------------------
# sharp turns (the paper's Fig. 8)


TURNS = 12
TURN_SEPARATION_SCANS = 25
ROTATION_BINS = (0.0, 2.0, 5.0, 10.0, 20.0, 30.0)  # degrees; the last bin is open


def scan_order(traj: Path) -> Dict[float, int]:
    """Scan index (file order) of every timestamp of a trajectory that has one
    line per scan (rsm-nav writes one); the first occurrence counts."""
    out: Dict[float, int] = {}
    k = 0
    with open(traj, encoding="utf-8") as fh:
        for line in fh:
            s = line.strip()
            if not s or s.startswith("#"):
                continue
            t = round(float(s.split()[0]), 6)
            out.setdefault(t, k)
            k += 1
    return out


def sharpest_turns(relations: Sequence[ev.Relation], order: Dict[float, int], n: int,
                   max_span: float = LOCAL_SPAN, separation: int = TURN_SEPARATION_SCANS) -> List[dict]:
    """The n local relations with the fastest true turn, in degrees of true
    rotation per scan between their two scans (scan counts, not timestamps:
    the log's timestamps jitter), at most one per stretch of ``separation``
    scans; fastest first."""
    cands = []
    for r in relations:
        if r.span > max_span:
            continue
        i1, i2 = order.get(round(r.t1, 6)), order.get(round(r.t2, 6))
        if i1 is None or i2 is None or i1 == i2:
            continue
        gap = abs(i2 - i1)
        rot = abs(math.degrees(ev.wrap_angle(r.yaw)))
        cands.append({"relation": r, "i1": min(i1, i2), "i2": max(i1, i2), "gap": gap, "rotation_deg": rot,
                      "rate_deg_per_scan": rot / gap, "translation_m": math.hypot(r.x, r.y)})
    cands.sort(key=lambda c: (-c["rate_deg_per_scan"], c["i1"]))
    picked: List[dict] = []
    for c in cands:
        mid = 0.5 * (c["i1"] + c["i2"])
        if all(abs(mid - 0.5 * (p["i1"] + p["i2"])) >= separation for p in picked):
            picked.append(c)
            if len(picked) == n:
                break
    return picked


def relation_residual(traj: ev.Trajectory, rel: ev.Relation) -> Optional[Tuple[float, float, float]]:
    """(dx, dy, dtheta) of inverse(true) o estimated for one relation: metres in
    the frame of the relation's second pose, degrees; None if an end is missing."""
    p1, ok1 = traj.find(rel.t1, 0.0)
    p2, ok2 = traj.find(rel.t2, 0.0)
    if p1 is None or p2 is None:
        return None
    est = ev.between(p1, p2)
    e = ev.between((rel.x, rel.y, rel.yaw), est)
    return e[0], e[1], math.degrees(e[2])


def _rot_bin(deg: float) -> int:
    k = 0
    for i, lo in enumerate(ROTATION_BINS):
        if deg >= lo:
            k = i
    return k


def bin_label(k: int) -> str:
    lo = ROTATION_BINS[k]
    return f">= {lo:g}" if k == len(ROTATION_BINS) - 1 else f"{lo:g}-{ROTATION_BINS[k + 1]:g}"


def run_turns(runs: dict, relations_path: Path, cell_m: float, n: int = TURNS) -> dict:
    """Residuals of rsm, icp and odometry at the n sharpest turns of the log and
    over every local relation binned by its true rotation."""
    relations = ev.load_relations(relations_path)
    trajs = {m: ev.load_trajectory(runs[m]["trajectory"]) for m in METHODS}
    order = scan_order(Path(runs["odometry"]["trajectory"]))
    t0 = min(order) if order else 0.0
    turns = sharpest_turns(relations, order, n)
    rows = []
    for c in turns:
        r = c["relation"]
        res = {}
        for m in METHODS:
            e = relation_residual(trajs[m], r)
            res[m] = None if e is None else {
                "dx_cells": abs(e[0]) / cell_m, "dy_cells": abs(e[1]) / cell_m,
                "translation_cells": math.hypot(e[0], e[1]) / cell_m, "rotation_deg": abs(e[2])}
        rows.append({"t1": r.t1, "t2": r.t2, "t1_rel": r.t1 - t0, "span": r.span, "i1": c["i1"], "i2": c["i2"],
                     "gap": c["gap"], "rotation_deg": c["rotation_deg"], "translation_m": c["translation_m"],
                     "rate_deg_per_scan": c["rate_deg_per_scan"], "residual": res})
    summary = {}
    for m in METHODS:
        vals = [row["residual"][m] for row in rows if row["residual"][m] is not None]
        summary[m] = {k: spread([v[k] for v in vals]) for k in ("dx_cells", "dy_cells", "translation_cells",
                                                                 "rotation_deg")}
    wins = {q: sum(1 for row in rows if row["residual"]["rsm"] and row["residual"]["icp"]
                   and row["residual"]["rsm"][q] < row["residual"]["icp"][q])
            for q in ("translation_cells", "rotation_deg")}
    bins = []
    for k in range(len(ROTATION_BINS)):
        sel = [r for r in relations if r.span <= LOCAL_SPAN
               and _rot_bin(abs(math.degrees(ev.wrap_angle(r.yaw)))) == k]
        row = {"bin": bin_label(k), "relations": len(sel), "methods": {}}
        for m in METHODS:
            errs = [relation_residual(trajs[m], r) for r in sel]
            errs = [e for e in errs if e is not None]
            row["methods"][m] = {"translation_cells": spread([math.hypot(e[0], e[1]) / cell_m for e in errs]),
                                 "rotation_deg": spread([abs(e[2]) for e in errs])}
        bins.append(row)
    return {"relations": str(relations_path), "cell_m": cell_m, "n": n, "separation": TURN_SEPARATION_SCANS,
            "turns": rows, "summary": summary, "rsm_better": wins, "bins": bins}


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
    w = 0.27
    for j, (key, unit) in enumerate((("translation_cells", "cells"), ("rotation_deg", "deg"))):
        ax = axes[0][j]
        for k, m in enumerate(METHODS):
            vals = [r["residual"][m][key] if r["residual"][m] else float("nan") for r in rows]
            ax.bar([v + (k - 1) * w for v in x], vals, width=w, label=m)
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
        for m, style in zip(METHODS, ("o-", "s--", "^:")):
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


# ---------------------------------------------------------------------------
# Cortex-M4F memory per module and configuration; static stack bound


ARM_CONFIGS = (("default", None), ("small", "tests/config/small_config.h"))
ARM_CPU = ("-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard")
# Caller-owned state per module: (module, label, C expression); the localizer's
# parts are members of rsm_localizer_t, which also holds the reports.
STATE_SIZES = (
    ("localizer.c", "rsm_localizer_t (all of the below)", "sizeof(rsm_localizer_t)"),
    ("ekf.c", "  ekf", "sizeof(((rsm_localizer_t *)0)->ekf)"),
    ("odometry.c", "  odo", "sizeof(((rsm_localizer_t *)0)->odo)"),
    ("map.c", "  map", "sizeof(((rsm_localizer_t *)0)->map)"),
    ("grid.c", "  image", "sizeof(((rsm_localizer_t *)0)->image)"),
    ("ransac.c", "  ransac", "sizeof(((rsm_localizer_t *)0)->ransac)"),
    ("harris.c", "  work.rsm (harris + candidates)", "sizeof(((rsm_localizer_t *)0)->work.rsm)"),
    ("icp.c", "  work.icp (shares work.rsm's memory)", "sizeof(((rsm_localizer_t *)0)->work.icp)"),
    ("match.c", "  key points and matches",
     "sizeof(((rsm_localizer_t *)0)->kp_cur) * 2 + sizeof(((rsm_localizer_t *)0)->pt_cur) * 2"
     " + sizeof(((rsm_localizer_t *)0)->matches)"),
    ("scan.c", "  points (robot and world frame)", "sizeof(((rsm_localizer_t *)0)->pts) * 2"),
    ("localizer.c", "rsm_localizer_config_t", "sizeof(rsm_localizer_config_t)"),
    ("scan.c", "rsm_scan_t (one scan buffer)", "sizeof(rsm_scan_t)"),
    ("p3dx.c", "rsm_p3dx_t", "sizeof(rsm_p3dx_t)"),
    ("p3dx.c", "rsm_p3dx_config_t", "sizeof(rsm_p3dx_config_t)"),
    ("sicklms.c", "rsm_sicklms_t", "sizeof(rsm_sicklms_t)"),
    ("sicklms.c", "rsm_sicklms_config_t", "sizeof(rsm_sicklms_config_t)"),
    ("sync.c", "rsm_sync_t (odometry/scan aligner, holds one scan)", "sizeof(rsm_sync_t)"),
)
# Entry points whose stack the report bounds (those the library has).
STACK_ROOTS = ("rsm_localizer_scan", "rsm_localizer_motion", "rsm_sync_scan", "rsm_sync_encoder", "rsm_sync_poll")
# Callbacks the core calls through a pointer (for the static stack bound).
INDIRECT_TARGETS = {"rsm_harris_detect": ("patch_map", "rsm_harris_patch_image")}


def state_probe(names: Sequence[Tuple[str, str, str]]) -> str:
    lines = ["/* Generated by rsm_tools.bench: sizes of the caller-owned state on the target. */",
             '#include "rsm/localizer.h"', '#include "rsm/p3dx.h"', '#include "rsm/sicklms.h"',
             '#include "rsm/sync.h"', ""]
    for k, (_, _, expr) in enumerate(names):
        lines.append(f"char rsm_size_{k}[{expr}];")
    return "\n".join(lines) + "\n"


def parse_nm_sizes(text: str, prefix: str = "rsm_size_") -> Dict[int, int]:
    """{k: size} of the symbols ``prefix<k>`` in ``nm -S`` output."""
    out = {}
    for line in text.splitlines():
        f = line.split()
        if len(f) == 4 and f[3].startswith(prefix) and f[3][len(prefix):].isdigit():
            out[int(f[3][len(prefix):])] = int(f[1], 16)
    return out


def parse_size_archive(text: str) -> List[dict]:
    """Per member of ``size -A -d ARCHIVE`` output: text, rodata, data, bss."""
    out, cur = [], None
    for line in text.splitlines():
        m = re.match(r"^(\S+)\s+\(ex\s", line)
        if m:
            cur = {"object": m.group(1), "text": 0, "rodata": 0, "data": 0, "bss": 0}
            out.append(cur)
            continue
        f = line.split()
        if cur is None or len(f) < 2 or not f[0].startswith(".") or not f[1].isdigit():
            continue
        sec, size = f[0], int(f[1])
        for kind, pat in (("text", r"^\.text(\.|$)"), ("rodata", r"^\.rodata(\.|$)"),
                          ("data", r"^\.(s|t)?data(\.|$)"), ("bss", r"^\.(s|t)?bss(\.|$)")):
            if re.match(pat, sec):
                cur[kind] += size
    for o in out:
        o["flash"] = o["text"] + o["rodata"]
        o["ram"] = o["data"] + o["bss"]
    return out


_CI_NODE = re.compile(r'^node:\s*\{\s*title:\s*"([^"]*)"\s*label:\s*"([^"]*)"(.*)\}\s*$')
_CI_EDGE = re.compile(r'^edge:\s*\{\s*sourcename:\s*"([^"]*)"\s*targetname:\s*"([^"]*)"')
_CI_BYTES = re.compile(r"(\d+) bytes \(([a-z,]+)\)")


def parse_callgraph_info(texts: Iterable[str]) -> dict:
    """Merges GCC -fcallgraph-info=su files: {title: {name, bytes, kind}} for the
    functions defined, and the call edges; titles of static functions carry
    their file, external callees only their name."""
    nodes: Dict[str, dict] = {}
    edges: Dict[str, List[str]] = {}
    for text in texts:
        for line in text.splitlines():
            m = _CI_NODE.match(line.strip())
            if m:
                title, label = m.group(1), m.group(2)
                b = _CI_BYTES.search(label)
                if b:
                    nodes[title] = {"name": label.split("\\n")[0], "bytes": int(b.group(1)), "kind": b.group(2)}
                continue
            m = _CI_EDGE.match(line.strip())
            if m:
                edges.setdefault(m.group(1), [])
                if m.group(2) not in edges[m.group(1)]:
                    edges[m.group(1)].append(m.group(2))
    return {"nodes": nodes, "edges": edges}


def worst_stack_path(graph: dict, root: str, indirect: Optional[Dict[str, Sequence[str]]] = None) -> dict:
    """Deepest stack over the call graph from ``root``: the sum of the frames on
    the worst path. Calls to functions outside the graph (libc, libm) count 0
    and are listed; indirect calls resolve through ``indirect`` (by caller
    name) or count 0 and are listed; recursion is reported."""
    nodes, edges = graph["nodes"], graph["edges"]
    indirect = indirect or {}
    by_name: Dict[str, List[str]] = {}
    for t, nd in nodes.items():
        by_name.setdefault(nd["name"], []).append(t)
    unresolved, unknown_indirect, dynamic, recursion = set(), set(), set(), set()
    memo: Dict[str, Tuple[int, List[str]]] = {}

    def depth(t: str, stack: Tuple[str, ...]) -> Tuple[int, List[str]]:
        if t in memo:
            return memo[t]
        if t in stack:
            recursion.add(nodes[t]["name"] if t in nodes else t)
            return 0, []
        nd = nodes[t]
        if nd["kind"] != "static":
            dynamic.add(nd["name"])
        best, best_path = 0, []
        for callee in edges.get(t, []):
            targets = []
            if callee == "__indirect_call":
                names = indirect.get(nd["name"])
                if not names:
                    unknown_indirect.add(nd["name"])
                    continue
                for nm in names:
                    targets += by_name.get(nm, [])
            elif callee in nodes:
                targets = [callee]
            elif by_name.get(callee):
                targets = by_name[callee]
            else:
                unresolved.add(callee)
                continue
            for c in targets:
                d, p = depth(c, stack + (t,))
                if d > best:
                    best, best_path = d, p
        memo[t] = (nd["bytes"] + best, [t] + best_path)
        return memo[t]

    roots = [root] if root in nodes else by_name.get(root, [])
    if not roots:
        raise BenchError(f"{root} is not in the call graph")
    total, path = depth(roots[0], ())
    return {"bytes": total, "path": [(nodes[t]["name"], nodes[t]["bytes"]) for t in path],
            "unresolved": sorted(unresolved), "unknown_indirect": sorted(unknown_indirect),
            "dynamic": sorted(dynamic), "recursion": sorted(recursion)}


def stack_bounds(graph: dict) -> Dict[str, dict]:
    names = {nd["name"] for nd in graph["nodes"].values()}
    return {fn: worst_stack_path(graph, fn, INDIRECT_TARGETS) for fn in STACK_ROOTS if fn in names}


def read_callgraph_dir(d: Path) -> dict:
    files = sorted(d.rglob("*.ci"))
    if not files:
        raise BenchError(f"no -fcallgraph-info output under {d}")
    return parse_callgraph_info(f.read_text(errors="replace") for f in files)


def _config_flag(root: Path, header: Optional[str]) -> List[str]:
    return [f"-DRSM_USER_CONFIG={(root / header).resolve()}"] if header else []


def run_arm_memory(root: Path, work: Path, configs: Sequence[Tuple[str, Optional[str]]] = ARM_CONFIGS) -> dict:
    """Per configuration: a Cortex-M4F MinSizeRel build with -fstack-usage and
    -fcallgraph-info=su; flash per object, state sizes on the target, the example
    firmware image and its static RAM, and the static stack bound of
    rsm_localizer_scan."""
    for tool in ("arm-none-eabi-gcc", "arm-none-eabi-size", "arm-none-eabi-nm", "cmake", "ninja"):
        if shutil.which(tool) is None:
            return {"skipped": f"{tool} is not installed"}
    out = {"compiler": first_line(["arm-none-eabi-gcc", "--version"]) or "arm-none-eabi-gcc", "configs": {}}
    for name, header in configs:
        b = work / f"arm-{name}"
        cmd = ["cmake", "-S", str(root), "-B", str(b), "-G", "Ninja",
               f"-DCMAKE_TOOLCHAIN_FILE={root / 'cmake' / 'toolchain-arm-none-eabi.cmake'}",
               "-DCMAKE_BUILD_TYPE=MinSizeRel", "-DCMAKE_C_FLAGS_MINSIZEREL=-Os -DNDEBUG -fstack-usage "
               "-fcallgraph-info=su", f"-DRSM_USER_CONFIG={(root / header).resolve() if header else ''}"]
        for c in (cmd, ["cmake", "--build", str(b), "--target", "rsm", "rsm_port_baremetal", "rsm_firmware"]):
            res = subprocess.run(c, capture_output=True, text=True)
            if res.returncode != 0:
                raise BenchError(f"{' '.join(c)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")
        cfg = {"header": header or "include/rsm/config.h (defaults)"}
        res = subprocess.run(["arm-none-eabi-size", "-A", "-d", str(b / "librsm.a")], capture_output=True, text=True)
        cfg["objects"] = parse_size_archive(res.stdout)
        probe = b / "rsm_state_probe.c"
        probe.write_text(state_probe(STATE_SIZES))
        obj = b / "rsm_state_probe.o"
        c = ["arm-none-eabi-gcc", *ARM_CPU, "-std=c99", "-Os", "-fno-common", f"-I{root / 'include'}",
             *_config_flag(root, header), "-c", str(probe), "-o", str(obj)]
        res = subprocess.run(c, capture_output=True, text=True)
        if res.returncode != 0:
            cfg["state"] = None
            cfg["state_note"] = "the state probe did not compile: " + res.stderr.strip().splitlines()[-1]
        else:
            nm = subprocess.run(["arm-none-eabi-nm", "-S", str(obj)], capture_output=True, text=True).stdout
            sizes = parse_nm_sizes(nm)
            cfg["state"] = [{"module": mod, "label": lab, "bytes": sizes.get(k)}
                            for k, (mod, lab, _) in enumerate(STATE_SIZES)]
        fw = b / "port" / "baremetal" / "rsm_firmware.elf"
        size = subprocess.run(["arm-none-eabi-size", str(fw)], capture_output=True, text=True).stdout
        f = size.splitlines()[1].split() if len(size.splitlines()) > 1 else []
        cfg["firmware"] = dict(zip(("text", "data", "bss", "dec"), map(int, f[:4]))) if len(f) >= 4 else None
        fw_obj = b / "port" / "baremetal" / "CMakeFiles" / "rsm_firmware.dir" / "firmware_main.c.obj"
        own = {l.split()[-1] for l in subprocess.run(["arm-none-eabi-nm", str(fw_obj)], capture_output=True,
                                                     text=True).stdout.splitlines()
               if len(l.split()) >= 2 and l.split()[-2] in ("b", "B", "d", "D")}
        statics = {}
        for line in subprocess.run(["arm-none-eabi-nm", "-S", str(fw)], capture_output=True,
                                   text=True).stdout.splitlines():
            p = line.split()
            if len(p) == 4 and p[2] in ("b", "B", "d", "D") and p[3] in own:
                statics[p[3]] = int(p[1], 16)
        cfg["firmware_statics"] = statics
        graph = read_callgraph_dir(b / "CMakeFiles" / "rsm.dir")
        cfg["stack"] = stack_bounds(graph)
        out["configs"][name] = cfg
    return out


def run_host_stack(root: Path, build_dir: Path, work: Path, jobs: int = 2) -> dict:
    """The static stack bound of rsm_localizer_scan for the host build: the
    core's sources (not the drivers') compiled with the build's compiler and
    flags plus -fstack-usage -fcallgraph-info=su (objects for the analysis only)."""
    cache = cmake_cache(build_dir)
    cc = cache.get("CMAKE_C_COMPILER") or shutil.which("cc") or "cc"
    bt = cache.get("CMAKE_BUILD_TYPE", "")
    flags = (cache.get("CMAKE_C_FLAGS", "") + " " + cache.get(f"CMAKE_C_FLAGS_{bt.upper()}", "")).split()
    d = work / "host-stack"
    if d.exists():
        shutil.rmtree(d)
    d.mkdir(parents=True)
    user = [f"-DRSM_USER_CONFIG={cache['RSM_USER_CONFIG']}"] if cache.get("RSM_USER_CONFIG") else []

    def compile_one(src: Path):
        c = [cc, *flags, "-std=c99", "-fstack-usage", "-fcallgraph-info=su", f"-I{root / 'include'}", *user,
             "-c", str(src), "-o", str(d / (src.stem + ".o"))]
        return src, subprocess.run(c, capture_output=True, text=True, cwd=d)

    core = [f for f in sorted((root / "src").glob("*.c")) if f.stem not in DRIVER_OBJECTS]
    for src, res in parallel(compile_one, core, jobs):
        if res.returncode != 0:
            return {"skipped": f"compiling {src.name} with -fcallgraph-info failed: "
                               + (res.stderr.strip().splitlines() or ["?"])[-1]}
    graph = read_callgraph_dir(d)
    return {"flags": " ".join(flags), "compiler": first_line([cc, "--version"]) or cc,
            "stack": stack_bounds(graph)}


# ---------------------------------------------------------------------------
# scaling: readings per scan and map size


SCALING_BEAMS = (181, 361, 721)
SCALING_MAP_LOG2 = (6, 7, 8)
DEFAULT_MAX_BEAMS = 361
DEFAULT_MAP_LOG2 = 7
# Shipped configuration presets (include paths) run as they are.
SCALING_PRESETS = ("rsm/config_host.h",)


def scaling_variants(beams: Sequence[int] = SCALING_BEAMS, maps: Sequence[int] = SCALING_MAP_LOG2,
                     presets: Sequence[str] = SCALING_PRESETS) -> List[dict]:
    """The builds and runs of the scaling section. Readings: the log's scans
    resampled to N readings, RSM_MAX_BEAMS = N (the default 361 is the default
    build). Map: the log's own readings, RSM_MAP_SIZE_LOG2 = L. Presets: a
    shipped config header, the log's own readings."""
    out = []
    for n in beams:
        macros = {} if n == DEFAULT_MAX_BEAMS else {"RSM_MAX_BEAMS": n}
        out.append({"name": f"beams{n}", "kind": "beams", "value": n, "macros": macros, "resample": n})
    for lg in maps:
        macros = {} if lg == DEFAULT_MAP_LOG2 else {"RSM_MAP_SIZE_LOG2": lg}
        out.append({"name": f"map{lg}", "kind": "map", "value": lg, "macros": macros, "resample": None})
    for k, h in enumerate(presets):
        out.append({"name": Path(h).stem, "kind": "preset", "value": k, "macros": {}, "header": h,
                    "resample": None})
    return out


def variant_header(macros: Dict[str, int]) -> str:
    lines = ["/* Generated by rsm_tools.bench: a scaling variant of config.h. */",
             "#ifndef RSM_BENCH_VARIANT_H", "#define RSM_BENCH_VARIANT_H"]
    lines += [f"#define {k} {v}" for k, v in sorted(macros.items())]
    lines += ["#endif", ""]
    return "\n".join(lines)


def build_variant(root: Path, work: Path, main_build: Path, variant: dict) -> Path:
    """rsm-stages for a variant: the main build's when the variant is the
    default, else a Release build of its own with a generated RSM_USER_CONFIG."""
    if not variant["macros"] and not variant.get("header"):
        return stages_exe(main_build)
    d = work / "variants" / variant["name"]
    d.mkdir(parents=True, exist_ok=True)
    if variant.get("header"):
        header = variant["header"]  # on the library's include path
    else:
        header = d / "rsm_bench_variant.h"
        text = variant_header(variant["macros"])
        if not header.is_file() or header.read_text() != text:
            header.write_text(text)
    b = d / "build"
    cache = cmake_cache(main_build)
    cmd = ["cmake", "-S", str(root), "-B", str(b), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
           "-DRSM_BUILD_TESTS=OFF", f"-DRSM_USER_CONFIG={header}"]
    if cache.get("CMAKE_C_COMPILER"):
        cmd.append(f"-DCMAKE_C_COMPILER={cache['CMAKE_C_COMPILER']}")
    for c in (cmd, ["cmake", "--build", str(b), "--target", "rsm-stages"]):
        res = subprocess.run(c, capture_output=True, text=True)
        if res.returncode != 0:
            raise BenchError(f"{' '.join(c)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")
    return stages_exe(b)


def run_scaling(root: Path, main_build: Path, log: Path, relations_path: Path, work: Path,
                variants: Optional[List[dict]] = None) -> dict:
    variants = variants if variants is not None else scaling_variants()
    relations = ev.load_relations(relations_path)
    rows = []
    for v in variants:
        exe = build_variant(root, work, main_build, v)
        for m in ROBUST_METHODS:
            extra = ["--clock", "ns"] + (["--beams", str(v["resample"])] if v["resample"] else [])
            traj = work / "scaling" / f"{v['name']}-{m}.txt"
            j = run_stages(exe, log, m, extra, traj)
            err = ev.evaluate(ev.load_trajectory(traj), relations, max_span=LOCAL_SPAN, tolerance=0.0)
            rows.append({"variant": v["name"], "kind": v["kind"], "value": v["value"], "macros": v["macros"],
                         "method": m, "beams": j["beams"], "config": j["config"], "sizes": j["sizes"],
                         "call": j["timing"]["call"], "scans": j["scans"], "trajectory": str(traj),
                         "header": v.get("header"), "outcomes": j["outcomes"],
                         "fused": 100.0 * j["outcomes"]["accepted"] / j["scans"] if j["scans"] else float("nan"),
                         "local": {q: err[q]["mean"] for q in QUANTITIES}, "matched": err["matched"]})
    return {"log": str(log), "variants": variants, "rows": rows, "growth": memory_growth(rows)}


def memory_growth(rows: Sequence[dict]) -> dict:
    """Bytes of rsm_localizer_t per reading of RSM_MAX_BEAMS and per map cell,
    from the smallest and largest variant of each kind."""
    out = {}
    for kind, x in (("beams", lambda r: r["config"]["RSM_MAX_BEAMS"]),
                    ("map", lambda r: r["config"]["RSM_MAP_SIZE"] ** 2)):
        sel = sorted({(x(r), r["sizes"]["rsm_localizer_t"]) for r in rows if r["kind"] == kind})
        if len(sel) >= 2 and sel[-1][0] != sel[0][0]:
            out[kind] = {"from": sel[0], "to": sel[-1],
                         "bytes_per_unit": (sel[-1][1] - sel[0][1]) / (sel[-1][0] - sel[0][0])}
    return out


def plot_scaling(sc: dict, path: Path, prov: dict) -> Optional[str]:
    plt = _pyplot()
    if plt is None:
        return NO_MATPLOTLIB
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2))
    for ax, kind, xlabel in ((axes[0], "beams", "readings per scan"),
                             (axes[1], "map", "map side [cells]")):
        for m, style in zip(ROBUST_METHODS, ("o-", "s--")):
            sel = sorted((r for r in sc["rows"] if r["kind"] == kind and r["method"] == m),
                         key=lambda r: r["value"])
            xs = [r["beams"] if kind == "beams" else r["config"]["RSM_MAP_SIZE"] for r in sel]
            ax.plot(xs, [r["call"]["median_us"] for r in sel], style, label=f"{m} median")
            ax.plot(xs, [r["call"]["p95_us"] for r in sel], style, alpha=0.4, label=f"{m} p95")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("time per scan [us]")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    ax = axes[2]
    for kind, style, xlabel in (("beams", "o-", "RSM_MAX_BEAMS"), ("map", "s--", "map cells / 100")):
        sel = sorted({(r["config"]["RSM_MAX_BEAMS"] if kind == "beams" else r["config"]["RSM_MAP_SIZE"] ** 2 / 100,
                       r["sizes"]["rsm_localizer_t"]) for r in sc["rows"] if r["kind"] == kind})
        ax.plot([s[0] for s in sel], [s[1] / 1024 for s in sel], style, label=xlabel)
    ax.set_xlabel("capacity")
    ax.set_ylabel("sizeof(rsm_localizer_t) [KiB]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.suptitle("Scaling: time per scan against readings and map size; state size against capacities",
                 fontsize=11)
    _save(plt, fig, path, prov, (0, 0.04, 1, 0.94))
    return None


def plot_stages(st: dict, path: Path, prov: dict) -> Optional[str]:
    plt = _pyplot()
    if plt is None:
        return NO_MATPLOTLIB
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
    ax = axes[0]
    for k, m in enumerate(ROBUST_METHODS):
        left = 0.0
        for s in STAGES:
            v = st["methods"][m]["timing"][s]["mean_us"]
            if v <= 0:
                continue
            ax.barh(k, v, left=left, label=s if k == 0 or s == "icp" else None,
                    color=f"C{STAGES.index(s)}")
            left += v
    ax.set_yticks(range(len(ROBUST_METHODS)))
    ax.set_yticklabels(ROBUST_METHODS)
    ax.set_xlabel("mean time per scan [us] (stages stacked)")
    ax.legend(fontsize=7, ncol=3)
    ax.grid(True, axis="x", alpha=0.3)
    ax = axes[1]
    shown = [s for s in STAGES if any(st["methods"][m]["timing"][s]["reached"] for m in ROBUST_METHODS)]
    w = 0.2
    for k, (m, q) in enumerate((("rsm", "median_reached_us"), ("rsm", "p95_reached_us"),
                                 ("icp", "median_reached_us"), ("icp", "p95_reached_us"))):
        ax.bar([i + (k - 1.5) * w for i in range(len(shown))],
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


# ---------------------------------------------------------------------------
# plot


def plot_robustness(rob: dict, path: Path, prov: dict, odometry: Optional[dict] = None) -> Optional[str]:
    """Draws the robustness curves; returns None or why there is no plot."""
    plt = _pyplot()
    if plt is None:
        return NO_MATPLOTLIB
    levels = rob["levels"]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5), sharex=True)
    for i, s in enumerate(SCOPES):
        for j, q in enumerate(QUANTITIES):
            ax = axes[i][j]
            for m, style in zip(ROBUST_METHODS, ("o-", "s--")):
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
            ax.grid(True, alpha=0.3)
            if i == 1:
                ax.set_xlabel("outliers in every scan [%]")
            ax.legend(fontsize=8)
    n = len(rob["seeds"])
    fig.suptitle(f"Robustness: relative-pose error vs outliers (mean over {n} seed"
                 f"{'s' if n != 1 else ''}, bars min..max)", fontsize=11)
    _save(plt, fig, path, prov, (0, 0.03, 1, 0.96))
    return None


# ---------------------------------------------------------------------------
# section 5: where rsm loses


def _better(a: float, b: float) -> bool:
    return math.isfinite(a) and math.isfinite(b) and a < b


def losses(acc: dict, main_label: str, rob: Optional[dict], speed: Optional[dict],
           cg: Optional[dict], mem: Optional[dict]) -> List[str]:
    items = []
    # accuracy, every log
    for label, a in acc.items():
        runs = a["runs"]
        for other in ("icp", "odometry"):
            lost = []
            for s in SCOPES:
                for q in QUANTITIES:
                    for stat in ("mean", "std", "max"):
                        mine = runs["rsm"]["errors"][s][q][stat]
                        theirs = runs[other]["errors"][s][q][stat]
                        if _better(theirs, mine):
                            lost.append(f"{s} {q} {stat} ({fmt_q(q, theirs)} vs rsm's "
                                        f"{fmt_q(q, mine)} {UNITS[q]})")
            if lost:
                items.append(f"On `{label}`, {other} beats rsm on: " + "; ".join(lost) + ".")
            else:
                items.append(f"On `{label}`, {other} beats rsm on no error measure (mean, std, max "
                             f"of translation and rotation, local and all relations).")
    # robustness
    if rob:
        t = rob["table"]
        noisy = [lv for lv in rob["levels"] if lv != 0]
        lost, seed_lost, narrow, worse_ratio = [], [], [], []
        for s in SCOPES:
            for q in QUANTITIES:
                k = f"{s}.{q}"
                clean_r, clean_i = t["rsm:0"][k]["mean"], t["icp:0"][k]["mean"]
                for lv in noisy:
                    r, i = t[f"rsm:{lv}"][k], t[f"icp:{lv}"][k]
                    pairs = list(zip(_per_seed(rob, "icp", lv, s, q), _per_seed(rob, "rsm", lv, s, q)))
                    seeds_lost = sum(1 for a_, b_ in pairs if a_ < b_)
                    if _better(i["mean"], r["mean"]):
                        lost.append(f"{lv} % {s} {q} ({fmt_q(q, i['mean'])} vs rsm's "
                                    f"{fmt_q(q, r['mean'])} {UNITS[q]}; icp lower with {seeds_lost} "
                                    f"of {len(pairs)} seeds)")
                    elif seeds_lost:
                        seed_lost.append(f"{lv} % {s} {q} ({seeds_lost} of {len(pairs)} seeds; the "
                                         f"means are still rsm {fmt_q(q, r['mean'])} vs icp "
                                         f"{fmt_q(q, i['mean'])} {UNITS[q]})")
                    if _better(r["mean"], i["mean"]) and r["mean"] > 0.9 * i["mean"]:
                        narrow.append(f"{lv} % {s} {q} ({fmt_q(q, r['mean'])} vs icp's "
                                      f"{fmt_q(q, i['mean'])} {UNITS[q]}, {100 * (1 - r['mean'] / i['mean']):.1f} % "
                                      f"below; clean: {100 * (1 - clean_r / clean_i):.1f} % below)")
                worse = [lv for lv in noisy if math.isfinite(t[f"icp:{lv}"][k]["ratio"])
                         and t[f"rsm:{lv}"][k]["ratio"] > t[f"icp:{lv}"][k]["ratio"]]
                if worse:
                    rr = [t[f"rsm:{lv}"][k]["ratio"] for lv in worse]
                    ir = [t[f"icp:{lv}"][k]["ratio"] for lv in worse]
                    worse_ratio.append(
                        f"{s} {q} at {', '.join(map(str, worse))} % (rsm {_range(rr)}x, icp {_range(ir)}x)")
        if lost:
            items.append("With outliers, icp's mean error over the seeds is below rsm's at: "
                         + "; ".join(lost) + ".")
        else:
            items.append("With outliers, icp's mean error over the seeds is below rsm's at no level, in "
                         "no scope and in neither translation nor rotation.")
        if seed_lost:
            items.append("With outliers, icp beats rsm on the same outlier log (same seed) at: "
                         + "; ".join(seed_lost) + ".")
        odo = acc[main_label]["runs"]["odometry"]["errors"]
        above = []
        for s in SCOPES:
            for q in QUANTITIES:
                lv_above = [lv for lv in noisy if _better(odo[s][q]["mean"], t[f"rsm:{lv}"][f"{s}.{q}"]["mean"])]
                if lv_above:
                    vals = [t[f"rsm:{lv}"][f"{s}.{q}"]["mean"] for lv in lv_above]
                    shown = (fmt_q(q, vals[0]) if len(vals) == 1
                             else f"{fmt_q(q, min(vals))}..{fmt_q(q, max(vals))}")
                    above.append(f"{s} {q} at {', '.join(map(str, lv_above))} % (rsm {shown} vs "
                                 f"odometry {fmt_q(q, odo[s][q]['mean'])} {UNITS[q]})")
        if above:
            items.append("With outliers, rsm's mean error over the seeds is above that of odometry alone "
                         "(which reads no scans): " + "; ".join(above) + ".")
        else:
            items.append("With outliers, rsm's mean error over the seeds stays below that of odometry "
                         "alone at every level, in both scopes, in translation and rotation.")
        if narrow:
            items.append("With outliers, rsm stays ahead of icp by less than 10 % at: " + "; ".join(narrow) + ".")
        if worse_ratio:
            items.append("Relative to its own clean figure, rsm's mean error grows more than icp's: "
                         + "; ".join(worse_ratio) + ". (A ratio compares each method with its own clean "
                         "run; icp starts from a worse one.)")
    if speed:
        if _better(speed["methods"]["icp"]["median_us"], speed["methods"]["rsm"]["median_us"]):
            items.append(f"icp's median time per scan is lower than rsm's "
                         f"({speed['methods']['icp']['median_us']:.1f} vs "
                         f"{speed['methods']['rsm']['median_us']:.1f} us).")
        if _better(speed["methods"]["icp"]["p95_us"], speed["methods"]["rsm"]["p95_us"]):
            items.append(f"icp's 95th-percentile time per scan is lower than rsm's "
                         f"({speed['methods']['icp']['p95_us']:.1f} vs "
                         f"{speed['methods']['rsm']['p95_us']:.1f} us).")
    if cg and "skipped" not in cg and _better(cg["icp"]["ir_per_scan"], cg["rsm"]["ir_per_scan"]):
        items.append(f"icp executes fewer instructions per scan than rsm "
                     f"({cg['icp']['ir_per_scan']:.0f} vs {cg['rsm']['ir_per_scan']:.0f}).")
    if mem and "skipped" not in mem:
        p = mem["parts"]
        r_, i_ = p["work.rsm (visited + harris + cands)"], p["work.icp"]
        if r_ > i_:
            items.append(f"Memory: rsm's scratch ({fmt_int(r_)} bytes) is larger than the ICP "
                         f"baseline's ({fmt_int(i_)} bytes), so it sets the size of the shared union.")
    # a narrow win is worth saying too
    a = acc[main_label]
    for other in ("icp", "odometry"):
        for q in QUANTITIES:
            mine = a["runs"]["rsm"]["errors"]["local"][q]["mean"]
            theirs = a["runs"][other]["errors"]["local"][q]["mean"]
            if _better(mine, theirs) and mine > 0.9 * theirs:
                items.append(f"On `{main_label}`, rsm's local {q} mean ({fmt_q(q, mine)} {UNITS[q]}) is "
                             f"only {100 * (1 - mine / theirs):.1f} % below {other}'s "
                             f"({fmt_q(q, theirs)} {UNITS[q]}): a narrow margin.")
    # the all-relations caveat, with this run's numbers
    per = a["runs"]["rsm"]["per_relation"]
    longs = [e for e in per if abs(e[1] - e[0]) > LOCAL_SPAN]
    total = math.fsum(e[2] for e in per)
    caveat = ("Relations spanning minutes are loop closures: rsm, like the ICP baseline and "
              "odometry, has no loop closure, so its drift over minutes is never corrected, and no "
              "scan matcher without loop closure gets them right. On a log with many of them the "
              "all-relations figures are dominated by them: they measure drift, not matching "
              "quality, and change a lot with small changes.")
    if per and longs and total > 0:
        share = math.fsum(e[2] for e in longs) / total
        longest = max(abs(e[1] - e[0]) for e in longs)
        over60 = sum(1 for e in longs if abs(e[1] - e[0]) > 60.0)
        items.append(
            f"On `{main_label}`, {len(longs)} of {len(per)} matched relations span more than "
            f"{LOCAL_SPAN:g} s ({over60} more than a minute, the longest {longest:.0f} s) and carry "
            f"{100 * share:.1f} % of rsm's summed translational error"
            + (": they dominate the all-relations figures. " if share > 0.5 else ". ") + caveat)
    else:
        items.append(f"On `{main_label}` no matched relation spans more than {LOCAL_SPAN:g} s. " + caveat)
    return items


def more_losses(turns: Optional[dict], st: Optional[dict], sc: Optional[dict], am: Optional[dict],
                hs: Optional[dict]) -> List[str]:
    """Items of "where rsm loses" from the sections added for issue 6."""
    items = []
    if turns and turns["turns"]:
        n = len(turns["turns"])
        sm = turns["summary"]
        for other in ("icp", "odometry"):
            lost = []
            for q, label in (("translation_cells", "translation"), ("rotation_deg", "rotation")):
                idx = [str(k) for k, r in enumerate(turns["turns"], 1)
                       if r["residual"]["rsm"] and r["residual"][other]
                       and r["residual"][other][q] < r["residual"]["rsm"][q]]
                if idx:
                    lost.append(f"{label} at {len(idx)} of {n} (turn{'s' if len(idx) > 1 else ''} "
                                f"{', '.join(idx)})")
            means = [q for q in ("translation_cells", "rotation_deg")
                     if _better(sm[other][q]["mean"], sm["rsm"][q]["mean"])]
            if lost:
                items.append(f"At the {n} sharpest turns, {other}'s residual is below rsm's in "
                             + "; ".join(lost) + (f"; its mean is lower in {', '.join(m_.split('_')[0] for m_ in means)}"
                                                  if means else "; rsm's means are still lower") + ".")
        for other in ("icp", "odometry"):
            worse = [b for b in turns["bins"] if b["relations"]
                     and _better(b["methods"][other]["translation_cells"]["mean"],
                                 b["methods"]["rsm"]["translation_cells"]["mean"])]
            if worse:
                items.append(f"By true rotation, {other}'s mean translation residual is below rsm's for the "
                             "local relations turning " + "; ".join(
                                 f"{b['bin']} deg ({_cells(b['methods'][other]['translation_cells']['mean'])} vs "
                                 f"{_cells(b['methods']['rsm']['translation_cells']['mean'])} cells, "
                                 f"{b['relations']} relations)" for b in worse) + ".")
    if st:
        t = st["methods"]["rsm"]["timing"]
        top = max(STAGES, key=lambda s_: t[s_]["mean_us"] if s_ in t else 0.0)
        share = 100.0 * t[top]["mean_us"] / t["step"]["mean_us"] if t["step"]["mean_us"] else float("nan")
        items.append(f"Speed: one stage dominates rsm's time per scan: {top} ({fmt_pct(share)} % of the mean "
                     f"step); rsm's 95th percentile is {fmt_ratio(ratio(t['call']['p95_us'], t['call']['median_us']))} "
                     "times its median.")
        if st.get("stack") and hs and "skipped" not in hs:
            bound = hs["stack"]["rsm_localizer_scan"]["bytes"]
            painted = max(st["stack"][m]["scan_bytes"] for m in ROBUST_METHODS)
            if painted > bound:
                items.append(f"Stack: the painted depth ({fmt_int(painted)} bytes) exceeds the host's static "
                             f"bound ({fmt_int(bound)} bytes, libc/libm calls not counted): those calls add "
                             "the difference.")
    if sc:
        rows = [r for r in sc["rows"] if r["method"] == "rsm"]
        for kind, default in (("map", DEFAULT_MAP_LOG2), ("beams", DEFAULT_MAX_BEAMS)):
            base = [r for r in rows if r["kind"] == kind and r["value"] == default]
            if not base:
                continue
            b0 = base[0]
            for r in sorted((r for r in rows if r["kind"] == kind and r["value"] != default), key=lambda r: r["value"]):
                worse = [q for q in QUANTITIES if r["local"][q] > 1.05 * b0["local"][q]]
                what = (f"a {r['config']['RSM_MAP_SIZE']}-cell map" if kind == "map"
                        else f"{r['beams']} resampled readings")
                dflt = (f"{b0['config']['RSM_MAP_SIZE']} cells" if kind == "map" else f"{b0['beams']} readings")
                if worse:
                    items.append(f"Scaling: with {what} rsm's local error is more than 5 % above that with "
                                 f"{dflt}: " + "; ".join(f"{q} {fmt_q(q, r['local'][q])} vs "
                                                         f"{fmt_q(q, b0['local'][q])} {UNITS[q]}" for q in worse) + ".")
        base = [r for r in rows if r["kind"] == "map" and r["value"] == DEFAULT_MAP_LOG2]
        for r in (r for r in rows if r["kind"] == "preset"):
            if base:
                worse = [q for q in QUANTITIES if r["local"][q] > 1.05 * base[0]["local"][q]]
                if worse:
                    items.append(f"Scaling: the preset `{r['header']}` has a local error more than 5 % above the "
                                 "default configuration's: " + "; ".join(
                                     f"{q} {fmt_q(q, r['local'][q])} vs {fmt_q(q, base[0]['local'][q])} {UNITS[q]}"
                                     for q in worse) + ".")
        beams = sorted((r for r in rows if r["kind"] == "beams"), key=lambda r: r["beams"])
        if len(beams) >= 2:
            lo, hi = beams[0], beams[-1]
            tr = ratio(hi["call"]["median_us"], lo["call"]["median_us"])
            rr = hi["beams"] / lo["beams"]
            better = all(hi["local"][q] < lo["local"][q] for q in QUANTITIES)
            items.append(f"Scaling: {hi['beams']} readings per scan cost {fmt_ratio(tr)} times the median time "
                         f"of {lo['beams']} ({rr:.2f} times the readings)"
                         + ("" if better else " and do not lower both local errors (the resampled readings "
                                              "carry no new information)") + ".")
    return items


def _range(vals: Sequence[float]) -> str:
    lo, hi = min(vals), max(vals)
    return fmt_ratio(lo) if fmt_ratio(lo) == fmt_ratio(hi) else f"{fmt_ratio(lo)}..{fmt_ratio(hi)}"


def _per_seed(rob: dict, m: str, level: int, s: str, q: str) -> List[float]:
    rows = sorted((r for r in rob["runs"] if r["method"] == m and r["level"] == level),
                  key=lambda r: (r["seed"] is None, r["seed"]))
    return [r["errors"][s][q]["mean"] for r in rows]


# ---------------------------------------------------------------------------
# report parts of the sections added for issue 6


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
         f"{cell_cm:g} cm (the default `grid.cell_m`, as `rsm-stages` reports it) and Δθ in degrees; "
         "translation is the length of (Δx, Δy). Each method runs its whole filter along the relation's scans, so these are residuals "
         "of the tracked motion over the turn, not of one isolated scan match as in the paper.", ""]
    rows = []
    for k, r in enumerate(tn["turns"], 1):
        cells = [str(k), f"{r['t1_rel']:.1f}", f"{r['span']:.2f}", str(r["gap"]), f"{r['rotation_deg']:.1f}",
                 f"{r['translation_m']:.3f}"]
        for m in METHODS:
            e = r["residual"][m]
            cells += (["n/a", "n/a"] if e is None else
                      [f"{_cells(e['dx_cells'])}, {_cells(e['dy_cells'])}", _deg(e["rotation_deg"])])
        rows.append(cells)
    L += md_table(["turn", "t1 [s]", "span [s]", "scans", "true rotation [deg]", "true translation [m]",
                   "rsm Δx, Δy [cells]", "rsm Δθ [deg]", "icp Δx, Δy [cells]", "icp Δθ [deg]",
                   "odometry Δx, Δy [cells]", "odometry Δθ [deg]"], rows, "turns")
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
    L += [f"rsm's residual is below icp's at {tn['rsm_better']['translation_cells']} of {n} turns in "
          f"translation and at {tn['rsm_better']['rotation_deg']} of {n} in rotation.", ""]
    L += [f"Every local relation of `{main}`, by its true rotation: mean translation residual in cells and "
          "mean rotation residual in degrees.", ""]
    rows = []
    for b in tn["bins"]:
        cells = [b["bin"], str(b["relations"])]
        for m in METHODS:
            cells += [_cells(b["methods"][m]["translation_cells"]["mean"]), _deg(b["methods"][m]["rotation_deg"]["mean"])]
        rows.append(cells)
    L += md_table(["true rotation [deg]", "relations", "rsm [cells]", "rsm [deg]", "icp [cells]", "icp [deg]",
                   "odometry [cells]", "odometry [deg]"], rows, "turns by rotation")
    return L


def report_stage_speed(st: Optional[dict], speed: Optional[dict], main: str) -> List[str]:
    if not st:
        return ["Per-stage times not measured in this run.", ""]
    L = ["### Per stage", "",
         f"`rsm-stages` (tools/bench-c) runs `{main}` as rsm-nav does (same trajectory, bit for bit) with "
         "the localizer's timing hook set: `rsm_localizer_config_t.clock_fn` reads CLOCK_MONOTONIC in "
         "nanoseconds and `rsm_localizer_scan` charges each stage the time from its start to the next "
         f"stage's. rsm and icp ran alternately, one process at a time, {st['repeats']} time(s) each, in "
         "this bench run; every figure is the median over the repeats. A stage's median and 95th "
         "percentile are over the scans that reached it (*scans*); its mean is over all scans, so the "
         "stage means add up to the whole step's mean (*share*). *whole step* is the hook's own total "
         "(first to last clock reading), *whole call* the call timed from outside.", ""]
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
    rows.append(["icp / rsm", "whole call", "", fmt_ratio(st["ratio_median"]), fmt_ratio(st["ratio_p95"]),
                 fmt_ratio(st["ratio_mean"]), "", "", "", "", "", ""])
    L += md_table(["stage", "what", "rsm scans", "rsm median [us]", "rsm p95 [us]", "rsm mean [us]", "rsm share %",
                   "icp scans", "icp median [us]", "icp p95 [us]", "icp mean [us]", "icp share %"], rows,
                  "speed stages")
    mo = mt["rsm"].get("motion")
    if mo:
        L += [f"Odometry prediction (`rsm_localizer_motion`, the EKF predict, once per scan): median "
              f"{_us2(mo['median_us'])} us, p95 {_us2(mo['p95_us'])} us (rsm run).", ""]
    if speed:
        a, b = speed["methods"]["rsm"]["median_us"], mt["rsm"]["call"]["median_us"]
        c, d = speed["methods"]["icp"]["median_us"], mt["icp"]["call"]["median_us"]
        L += [f"With the hook the whole call's median is {_us(b)} us for rsm and {_us(d)} us for icp; "
              f"rsm-nav, which leaves the hook NULL, measured {_us(a)} and {_us(c)} us above "
              f"({fmt_ratio(ratio(b, a))} and {fmt_ratio(ratio(d, c))} times): the clock readings cost little "
              "next to the stages, but two processes measured minutes apart differ by a few per cent anyway.", ""]
    if st.get("plot"):
        L += [f"![Time per stage, rsm and icp]({st['plot']})", ""]
    elif st.get("plot_note"):
        L += [f"No plot: {st['plot_note']}.", ""]
    return L


def report_callgrind_stages(cg: Optional[dict]) -> List[str]:
    if not cg or "skipped" in cg or "stages" not in cg.get("rsm", {}):
        return []
    L = ["Instructions per scan by stage, from the same callgrind runs: the inclusive count of every "
         "function `rsm_localizer_scan` calls, grouped by the stage that calls it (`rsm_map_recenter` and "
         "the sine/cosine of `to_world` run in both the grid and the map stage). *localizer* is "
         "`rsm_localizer_scan`'s own code with the static helpers the compiler inlined into it: the listing "
         "of the map cells near the scan that are Harris candidates, the candidate copies, `to_world`, the "
         "noise models and the stage bookkeeping. Callgrind counts functions, not stages, so that part "
         "cannot be split further; the wall-time table above has the exact split.", ""]
    rows = []
    for stg in CG_STAGE_ORDER:
        if not any(stg in cg[m]["stages"] for m in ROBUST_METHODS):
            continue
        fns = sorted({f for m in ROBUST_METHODS for f in cg[m]["stages"].get(stg, {}).get("functions", [])})
        cells = [stg, ", ".join(f"`{f}`" for f in fns)]
        for m in ROBUST_METHODS:
            row = cg[m]["stages"].get(stg)
            if row is None:
                cells += ["0", "0.0"]
            else:
                cells += [fmt_int(round(row["ir_per_scan"])), fmt_pct(100.0 * row["ir"] / cg[m]["ir"])]
        rows.append(cells)
    L += md_table(["stage", "functions", "rsm Ir per scan", "rsm %", "icp Ir per scan", "icp %"], rows,
                  "speed callgrind stages")
    return L


def _kib(v: Optional[int]) -> str:
    return "n/a" if v is None else f"{v / 1024:.1f}"


DRIVER_OBJECTS = ("aria", "lms", "p3dx", "sicklms", "hal")


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
              "and configuration). The indented rows are the parts of `rsm_localizer_t`; `work.rsm` and "
              "`work.icp` share one union.", ""]
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
         "callback is resolved to the two functions the localizer passes (`patch_map`, "
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
    L = [f"Time per scan (whole call, rsm-stages, one run each) on `{main}` against readings per scan and "
         "map size, each variant a Release build of its own with a generated `RSM_USER_CONFIG` (the "
         "default values come from the main build). Readings: the log's 180-beam scans are resampled to N "
         "readings over the same 179° field (linear in range between neighbouring readings closer than "
         "0.1 m, otherwise the nearer reading) with `RSM_MAX_BEAMS` = N; they add readings, not "
         "information. Map: the log's own 180 readings with `RSM_MAP_SIZE_LOG2` = L. *preset*: a shipped "
         "configuration header as it is, with the log's own readings. The local error (relations spanning "
         "at most 2 s), the share of scans fused and the scans refused by the gate (*jump*) show what each "
         "variant does to accuracy.", ""]
    rows = []
    for r in sorted(sc["rows"], key=lambda r: (r["kind"], r["value"], r["method"])):
        c = r["config"]
        cfg = (f"`{r['header']}`" if r.get("header") else
               ", ".join(f"{k} {v}" for k, v in sorted(r["macros"].items())) or "defaults")
        rows.append([r["kind"], cfg, str(r["beams"]), f"{c['RSM_MAP_SIZE']} x {c['RSM_MAP_SIZE']}", r["method"],
                     _us(r["call"]["median_us"]), _us(r["call"]["p95_us"]), fmt_q("translation", r["local"]["translation"]),
                     fmt_q("rotation", r["local"]["rotation"]), fmt_pct(r["fused"]), str(r["outcomes"].get("jump", 0)),
                     fmt_int(r["sizes"]["rsm_localizer_t"])])
    L += md_table(["varies", "config", "readings", "map [cells]", "method", "median [us]", "p95 [us]",
                   "local translation [m]", "local rotation [deg]", "fused %", "gated (jump)",
                   "sizeof(rsm_localizer_t)"], rows, "scaling time")
    seen = {}
    for r in sc["rows"]:
        seen.setdefault(r["variant"], r)
    rows = []
    for v in sorted(seen.values(), key=lambda r: (r["kind"], r["value"])):
        c, s = v["config"], v["sizes"]
        rows.append([v["variant"], str(c["RSM_MAX_BEAMS"]), str(c["RSM_MAP_SIZE"]), fmt_int(s["rsm_localizer_t"]),
                     fmt_int(s["map"]), fmt_int(s["image"]), fmt_int(s["work"]), fmt_int(s["ransac"]),
                     fmt_int(s["points"]), fmt_int(s["rsm_scan_t"])])
    L += ["How the state grows with the capacities (bytes on this host):", ""]
    L += md_table(["variant", "RSM_MAX_BEAMS", "map side", "rsm_localizer_t", "map", "image", "work", "ransac",
                   "points", "rsm_scan_t"], rows, "scaling memory")
    gated = sorted((r for r in sc["rows"] if r["kind"] == "beams" and r["method"] == "rsm"), key=lambda r: r["beams"])
    if len(gated) >= 2 and gated[-1]["outcomes"].get("jump", 0) > gated[0]["outcomes"].get("jump", 0):
        L += ["With more readings rsm refuses more scans at the gate ("
              + ", ".join(f"{fmt_int(r['outcomes'].get('jump', 0))} at {r['beams']}" for r in gated)
              + " readings): the refined measurement's covariance is the map fit's cost times the inverse of "
              "JᵀJ, a sum over the points, so it shrinks as points are added, while interpolated readings "
              "are not independent of their neighbours. The measurement noise was tuned with 180 readings.", ""]
    g = sc.get("growth", {})
    parts = []
    if "beams" in g:
        parts.append(f"{g['beams']['bytes_per_unit']:.1f} bytes of `rsm_localizer_t` per unit of RSM_MAX_BEAMS "
                     "(the members it sizes: `pts` and `world`, the image's cell list through "
                     "RSM_IMAGE_MAX_CELLS = 2 x RSM_MAX_BEAMS, and the ICP points inside the work union), and "
                     "every `rsm_scan_t` grows with it too")
    if "map" in g:
        parts.append(f"{g['map']['bytes_per_unit']:.3f} bytes per map cell (the members it sizes: the map's hit "
                     "counts, the scan image's bitmap and the bitmap of listed reference candidates)")
    if parts:
        L += ["Growth between the smallest and largest variant: " + "; ".join(parts) + ".", ""]
    if sc.get("plot"):
        L += [f"![Scaling of time per scan and state size]({sc['plot']})", ""]
    elif sc.get("plot_note"):
        L += [f"No plot: {sc['plot_note']}.", ""]
    return L


# ---------------------------------------------------------------------------
# the report


def md_table(header: Sequence[str], rows: Iterable[Sequence[str]], anchor: str) -> List[str]:
    """A Markdown table preceded by an HTML comment naming it (the test finds it by that)."""
    out = [f"<!-- table: {anchor} -->", "| " + " | ".join(header) + " |",
           "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    out.append("")
    return out


def headline_extras(ctx: dict) -> List[str]:
    """Headline sentences from the sections added for issue 6."""
    out = []
    tn = ctx.get("turns")
    if tn and tn["turns"]:
        sm = tn["summary"]
        out.append(f"at the {len(tn['turns'])} sharpest turns rsm's mean residual is "
                   f"{_cells(sm['rsm']['translation_cells']['mean'])} cells and {_deg(sm['rsm']['rotation_deg']['mean'])} deg "
                   f"(icp {_cells(sm['icp']['translation_cells']['mean'])} cells, {_deg(sm['icp']['rotation_deg']['mean'])} deg; "
                   f"odometry {_cells(sm['odometry']['translation_cells']['mean'])} cells, "
                   f"{_deg(sm['odometry']['rotation_deg']['mean'])} deg)")
    st = ctx.get("stages")
    if st:
        t = st["methods"]["rsm"]["timing"]
        top = max(STAGES, key=lambda s_: t[s_]["mean_us"] if s_ in t else 0.0)
        out.append(f"rsm's slowest stage is {top} ({fmt_pct(100.0 * t[top]['mean_us'] / t['step']['mean_us'])} % "
                   f"of the mean step, median {_us2(t[top]['median_reached_us'])} us)")
    am = ctx.get("arm_memory")
    if am and "skipped" not in am:
        c = am["configs"]
        if "default" in c:
            stk = c["default"]["stack"]
            via = (f", {fmt_int(stk['rsm_sync_scan']['bytes'])} through the aligner's `rsm_sync_scan`"
                   if "rsm_sync_scan" in stk else "")
            out.append(f"one localizer step needs at most {fmt_int(stk['rsm_localizer_scan']['bytes'])} "
                       f"bytes of stack on Cortex-M4F{via} (static bound, libm calls not counted)")
        if "small" in c and c["small"].get("firmware") and c["small"].get("state"):
            out.append(f"with `{c['small']['header']}` the state is "
                       f"{fmt_int(c['small']['state'][0]['bytes'])} bytes and the example firmware "
                       f"{fmt_int(c['small']['firmware']['bss'] + c['small']['firmware']['data'])} bytes of RAM and "
                       f"{fmt_int(c['small']['firmware']['text'])} bytes of flash")
    return out


def write_report(ctx: dict) -> str:
    root: Path = ctx["root"]
    prov = ctx["provenance"]
    pl = provenance_line(prov)
    acc, rob, speed, cg, mem, xc = (ctx.get(k) for k in ("accuracy", "robustness", "speed",
                                                        "callgrind", "memory", "cross_check"))
    main = ctx["main_label"]
    L: List[str] = []
    L += [
        "# rsm benchmark results",
        "",
        "Generated by `./tools/bench` (`python -m rsm_tools.bench`); do not edit by hand. Every "
        "number below was measured by that command in the run described here.",
        "",
        pl,
        "",
        f"Bench settings: outlier levels {', '.join(str(v) for v in ctx['levels'])} %, "
        f"{len(ctx['seeds'])} seed(s) per level ({', '.join(str(s) for s in ctx['seeds'])}), "
        f"{ctx['speed_repeats']} speed repeat(s), {ctx['jobs']} rsm-nav process(es) at a time"
        + (", quick mode" if ctx["quick"] else "") + ". "
        f"Whole bench: {ctx['elapsed']:.0f} s ("
        + ", ".join(f"{k} {v:.0f} s" for k, v in ctx["stage_seconds"].items()) + ").",
        "",
    ]
    # headline
    ma = acc[main]["runs"]
    hl = []
    for m in METHODS:
        e = ma[m]["errors"]
        hl.append([m] + [fmt_q(q, e[s][q]["mean"]) for s in SCOPES for q in QUANTITIES])
    L += ["## Headline", "",
          f"Mean relative-pose error on `{main}` (local = relations spanning at most "
          f"{LOCAL_SPAN:g} s):", ""]
    L += md_table(["method", "local translation [m]", "local rotation [deg]",
                   "all translation [m]", "all rotation [deg]"], hl, "headline")
    extra = []
    if rob:
        top = max(lv for lv in rob["levels"])
        for lv in rob["levels"]:
            if lv == 0:
                continue
            if lv == 43 or (43 not in rob["levels"] and lv == top):
                r = rob["table"][f"rsm:{lv}"]["local.translation"]
                extra.append(f"with {lv} % outliers rsm's local translation error is "
                             f"{fmt_q('translation', r['mean'])} m, {fmt_ratio(r['ratio'])} times its "
                             "clean figure")
    if speed:
        extra.append(f"icp takes {fmt_ratio(speed['ratio_median'])} times rsm's median wall time per scan")
    if cg and "skipped" not in cg:
        extra.append(f"icp executes {fmt_ratio(cg['ratio'])} times rsm's instructions per scan (callgrind)")
    if mem and "skipped" not in mem:
        extra.append(f"the localizer state is {fmt_int(mem['sizes']['rsm_localizer_t'])} bytes on "
                     "this host" + (f" and {fmt_int(xc['statics']['fw_localizer'])} bytes on Cortex-M4F"
                                    if xc and "skipped" not in xc and "fw_localizer" in xc["statics"] else ""))
    extra += headline_extras(ctx)
    if extra:
        L += ["In this run: " + "; ".join(extra) + ".", ""]

    # 1. accuracy
    L += [f"## {SECTION_TITLES[0]}", "", pl, ""]
    L += [f"Relative-pose error of Kümmerle et al. 2009 (`rsm_tools.evaluate`, exact timestamps) "
          f"of the trajectories `rsm-nav --method rsm|icp|odometry` writes. *local*: relations "
          f"spanning at most {LOCAL_SPAN:g} s; *all*: every relation. Translation in m, rotation in "
          "degrees; std is the population standard deviation; *fused* is the share of scans whose "
          "measurement the filter accepted.", ""]
    for label, a in acc.items():
        L += [f"### `{label}`", "",
              f"Log `{shown_path(Path(a['log']), root)}`, relations "
              f"`{shown_path(Path(a['relations']), root)}` ({a['relation_count']} relations), "
              f"{a['runs']['rsm']['summary']['scans']} scans.", ""]
        rows = []
        for m in METHODS:
            r = a["runs"][m]
            for s in SCOPES:
                e = r["errors"][s]
                rows.append([m, s, str(e["matched"]), str(e["unmatched"])]
                            + [fmt_q(q, e[q][st]) for q in QUANTITIES for st in ("mean", "std", "max")]
                            + [fmt_pct(fused_percent(r["summary"]))])
        L += md_table(["method", "scope", "matched", "unmatched", "translation mean", "std", "max",
                       "rotation mean", "std", "max", "fused %"], rows, f"accuracy {label}")
        oc = []
        for m in METHODS:
            o = a["runs"][m]["summary"]["outcomes"]
            oc.append(f"{m}: " + ", ".join(f"{k} {v}" for k, v in o.items()))
        L += ["Scan outcomes (rsm-nav summary): " + "; ".join(oc) + ".", ""]

    # 2. robustness
    L += [f"## {SECTION_TITLES[1]}", "", pl, ""]
    if not rob:
        L += ["Not measured in this run.", ""]
    else:
        L += [f"The paper's experiment on `{main}`: in every scan, the given share of the readings "
              "is replaced by uniform random ranges (`rsm_tools.outliers`, the same readings and "
              "values for rsm and icp at each seed). For each level: the mean over seeds of the "
              "mean error, its spread (min..max over the seeds) and its ratio to the same method's "
              f"clean figure. Seeds {', '.join(str(s) for s in rob['seeds'])}; 0 % is the clean log "
              f"itself (one run). {rob['outlier_logs_made']} outlier log(s) were generated in this "
              "run, the others came from the cache.", ""]
        for s in SCOPES:
            title = (f"Local relations (span <= {LOCAL_SPAN:g} s)" if s == "local" else "All relations")
            L += [f"### {title}", ""]
            rows = []
            for lv in rob["levels"]:
                for m in ROBUST_METHODS:
                    row = rob["table"][f"{m}:{lv}"]
                    cells = [str(lv), m, str(row[f'{s}.translation']["n"])]
                    for q in QUANTITIES:
                        c = row[f"{s}.{q}"]
                        cells += [fmt_q(q, c["mean"]), f"{fmt_q(q, c['min'])}..{fmt_q(q, c['max'])}",
                                  fmt_ratio(c["ratio"])]
                    cells.append(fmt_pct(row["fused"]["mean"]))
                    rows.append(cells)
            L += md_table(["outliers %", "method", "runs", "translation mean [m]", "min..max",
                           "x clean", "rotation mean [deg]", "min..max", "x clean", "fused %"],
                          rows, f"robustness {s}")
        if ctx.get("plot"):
            L += [f"![Robustness curves: mean error against the share of outliers, rsm and icp, "
                  f"odometry as a reference line]({ctx['plot']})", ""]
        elif ctx.get("plot_note"):
            L += [f"No plot: {ctx['plot_note']}.", ""]

    # 3. sharp turns
    L += [f"## {SECTION_TITLES[2]}", "", pl, ""]
    L += report_turns(ctx.get("turns"), main, root)
    if ctx.get("turns") and ctx.get("turns_plot"):
        L += [f"![Residuals of rsm, icp and odometry at the sharpest turns and by true rotation]"
              f"({ctx['turns_plot']})", ""]
    elif ctx.get("turns_plot_note"):
        L += [f"No plot: {ctx['turns_plot_note']}.", ""]

    # 4. speed
    L += [f"## {SECTION_TITLES[3]}", "", pl, ""]
    if speed:
        L += [f"Wall time of `rsm_localizer_scan` per scan, from rsm-nav's summary, on `{main}` "
              f"({speed['methods']['rsm']['scans']} scans). rsm and icp ran alternately, one process at "
              f"a time, {speed['repeats']} time(s) each, in this bench run; the table gives the "
              "median over the repeats of each run's median and 95th percentile, and the range "
              "over the repeats. Wall times depend on the machine and its load.", ""]
        rows = []
        for m in ROBUST_METHODS:
            s_ = speed["methods"][m]
            rows.append([m, f"{s_['median_us']:.1f}", f"{s_['median_min']:.1f}..{s_['median_max']:.1f}",
                         f"{s_['p95_us']:.1f}", f"{s_['p95_min']:.1f}..{s_['p95_max']:.1f}"])
        rows.append(["icp / rsm", fmt_ratio(speed["ratio_median"]), "", fmt_ratio(speed["ratio_p95"]), ""])
        L += md_table(["method", "median [us]", "range", "p95 [us]", "range"], rows, "speed wall")
        ident = all(Path(r["trajectory"]).read_bytes() == Path(acc[main]["runs"][r["method"]]["trajectory"]).read_bytes()
                    for r in speed["runs"])
        L += [("Every repeat wrote a trajectory bit-identical to the accuracy run's."
               if ident else "WARNING: a repeat wrote a trajectory that differs from the accuracy run's."), ""]
    else:
        L += ["Wall time not measured in this run.", ""]
    if cg and "skipped" not in cg:
        L += [f"Instructions executed inside `rsm_localizer_scan` (callgrind, "
              f"`--toggle-collect=rsm_localizer_scan`, {cg['valgrind']}) on "
              f"`{shown_path(Path(cg['log']), root)}`, divided by the scans. These counts repeat "
              "exactly from run to run on the same binary.", ""]
        rows = [[m, fmt_int(cg[m]["scans"]), fmt_int(cg[m]["ir"]), fmt_int(round(cg[m]["ir_per_scan"]))]
                for m in ROBUST_METHODS]
        rows.append(["icp / rsm", "", "", fmt_ratio(cg["ratio"])])
        L += md_table(["method", "scans", "Ir collected", "Ir per scan"], rows, "speed callgrind")
        L += report_callgrind_stages(cg)
    else:
        L += [f"Instruction counts not measured: {(cg or {}).get('skipped', 'disabled')}.", ""]
    L += report_stage_speed(ctx.get("stages"), speed, main)

    # 5. memory
    L += [f"## {SECTION_TITLES[4]}", "", pl, ""]
    if mem and "skipped" not in mem:
        mac = mem["macros"]
        L += [f"`sizeof` on this host ({mem['compiler']}), default `config.h` (beams "
              f"{mac['RSM_MAX_BEAMS']}, map {mac['RSM_MAP_SIZE']} x {mac['RSM_MAP_SIZE']} cells, "
              f"{mac['RSM_MAX_KEYPOINTS']} key points, {mac['RSM_MAX_CANDIDATES']} candidates, "
              f"{mac['RSM_MAX_MATCHES']} matches), from a probe program built against the library "
              "and run with the default runtime config.", ""]
        rows = [["rsm_localizer_t (total)", fmt_int(mem["sizes"]["rsm_localizer_t"]),
                 f"{mem['sizes']['rsm_localizer_t'] / 1024:.1f}"]]
        rows += [[k, fmt_int(v), f"{v / 1024:.1f}"] for k, v in mem["parts"].items()]
        rows.append(["other (pointer, stamps, padding)", fmt_int(mem["other"]), f"{mem['other'] / 1024:.1f}"])
        rows += [[k, fmt_int(mem["sizes"][k]), f"{mem['sizes'][k] / 1024:.1f}"] for k in MEMORY_OTHER]
        L += md_table(["part", "bytes", "KiB"], rows, "memory host")
    else:
        L += [f"Host sizes not measured: {(mem or {}).get('skipped', 'disabled')}.", ""]
    am = ctx.get("arm_memory")
    if xc and "skipped" not in xc:
        L += [f"Cortex-M4F (`tools/cross-check`, {xc['compiler']}, -Os): flash (text + rodata) per "
              "object of the library and the bare-metal port.", ""]
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
    else:
        L += [f"Cortex-M4F sizes not measured: {(xc or {}).get('skipped', 'disabled')}.", ""]
    L += report_arm_memory(am, root)
    L += report_stack(am, ctx.get("host_stack"), ctx.get("stages"), ctx.get("stack_note"))

    # 6. scaling
    L += [f"## {SECTION_TITLES[5]}", "", pl, ""]
    L += report_scaling(ctx.get("scaling"), main)

    # 7. losses
    L += [f"## {SECTION_TITLES[6]}", "", pl, ""]
    L += [f"- {item}" for item in ctx["losses"]]
    L.append("")
    return "\n".join(L)


# ---------------------------------------------------------------------------
# command line


def _levels(text: str) -> List[int]:
    try:
        vals = sorted({int(v) for v in text.split(",") if v.strip()})
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of integers: {text!r}") from None
    if not vals or any(v < 0 or v > 100 for v in vals):
        raise argparse.ArgumentTypeError(f"levels must be within 0..100: {text!r}")
    return vals


def _names(text: str) -> List[str]:
    known = [n for n, _ in ARM_CONFIGS]
    vals = [v.strip() for v in text.split(",") if v.strip()]
    if not vals or any(v not in known for v in vals):
        raise argparse.ArgumentTypeError(f"configurations are among {', '.join(known)}: {text!r}")
    return vals


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="rsm-bench",
        description="Measure rsm, its ICP baseline and odometry (accuracy, robustness to outliers, "
                    "speed, memory) and write docs/RESULTS.md. ./tools/bench builds and runs this.")
    p.add_argument("--root", type=Path, help="repository root (default: found from the current folder)")
    p.add_argument("--build-dir", type=Path, help="build with tools/nav/rsm-nav and librsm.a "
                   "(default: ROOT/build-release)")
    p.add_argument("--real-log", type=Path, help="the main log (default: ROOT/../shared/data/intel/intel.clf.gz)")
    p.add_argument("--real-relations", type=Path, help="its relations (default: intel.relations beside it)")
    p.add_argument("--log", type=Path, action="append", default=[], help="extra CARMEN log for the "
                   "accuracy section (repeatable, each with a --relations)")
    p.add_argument("--relations", type=Path, action="append", default=[], help="relations of the "
                   "matching --log")
    p.add_argument("--callgrind-log", type=Path, help="log for instruction counts "
                   "(default: ROOT/tests/data/intel_head.clf.gz)")
    p.add_argument("--levels", type=_levels, help="outlier percentages (default: "
                   + ",".join(map(str, LEVELS)) + "; quick: " + ",".join(map(str, QUICK_LEVELS)) + ")")
    p.add_argument("--seeds", type=int, help=f"seeds per outlier level (default {SEEDS}; quick 1)")
    p.add_argument("--speed-repeats", type=int, help=f"timed runs per method (default {SPEED_REPEATS}; quick 1)")
    p.add_argument("--jobs", type=int, default=2, help="rsm-nav processes at a time (default 2)")
    p.add_argument("--quick", action="store_true", help="one seed, fewer levels, one speed repeat")
    p.add_argument("--no-callgrind", action="store_true", help="skip the instruction counts")
    p.add_argument("--no-cross-check", action="store_true", help="skip tools/cross-check")
    p.add_argument("--no-plots", action="store_true", help="draw no plot")
    p.add_argument("--turns", type=int, default=TURNS, help=f"sharpest turns in the Fig. 8 table (default {TURNS})")
    p.add_argument("--no-stack", action="store_true", help="skip the painted stack measurement")
    p.add_argument("--no-arm-memory", action="store_true", help="skip the per-configuration Cortex-M4F builds")
    p.add_argument("--arm-configs", type=_names, help="Cortex-M4F configurations to build (default "
                   + ",".join(n for n, _ in ARM_CONFIGS) + ")")
    p.add_argument("--no-scaling", action="store_true", help="skip the scaling section")
    p.add_argument("--scaling-beams", type=_levels, help="readings per scan of the scaling runs (default "
                   + ",".join(map(str, SCALING_BEAMS)) + f"; quick {DEFAULT_MAX_BEAMS})")
    p.add_argument("--scaling-maps", type=_levels, help="RSM_MAP_SIZE_LOG2 values of the scaling runs (default "
                   + ",".join(map(str, SCALING_MAP_LOG2)) + f"; quick {DEFAULT_MAP_LOG2}); the presets "
                   + ", ".join(SCALING_PRESETS) + " run too, except in quick mode")
    p.add_argument("--output", type=Path, help="report (default: ROOT/docs/RESULTS.md)")
    p.add_argument("--plots-dir", type=Path, help="plots (default: ROOT/docs/results)")
    p.add_argument("--work-dir", type=Path, help="trajectories and manifest (default: BUILD/bench-work)")
    p.add_argument("--cache-dir", type=Path, help="outlier logs (default: BUILD/bench-cache)")
    return p


def _json_default(o):
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))


def run(args: argparse.Namespace) -> Path:
    t_start = time.monotonic()
    root = (args.root or find_root()).resolve()
    build = (args.build_dir or root / "build-release").resolve()
    nav = build / "tools" / "nav" / "rsm-nav"
    if not nav.is_file():
        raise BenchError(f"rsm-nav is not built: {nav} (run ./tools/bench, which builds it)")
    stages_bin = stages_exe(build)
    if not stages_bin.is_file():
        raise BenchError(f"rsm-stages is not built: {stages_bin} (run ./tools/bench, which builds it)")
    real_log = (args.real_log or root.parent / "shared" / "data" / "intel" / "intel.clf.gz").resolve()
    real_rel = (args.real_relations or real_log.parent / "intel.relations").resolve()
    for f, what in ((real_log, "the real log"), (real_rel, "its relations")):
        if not f.is_file():
            raise BenchError(f"{what} is missing: {f} (the Intel dataset belongs in ../shared/data/intel/)")
    if len(args.log) != len(args.relations):
        raise BenchError("give one --relations for every --log")
    levels = args.levels or (list(QUICK_LEVELS) if args.quick else list(LEVELS))
    if 0 not in levels:
        levels = [0] + levels  # the ratios need the clean figure
    nseeds = args.seeds if args.seeds is not None else (1 if args.quick else SEEDS)
    repeats = args.speed_repeats if args.speed_repeats is not None else (1 if args.quick else SPEED_REPEATS)
    if nseeds < 1 or repeats < 1 or args.jobs < 1:
        raise BenchError("--seeds, --speed-repeats and --jobs must be at least 1")
    seeds = list(range(1, nseeds + 1))
    work = (args.work_dir or build / "bench-work").resolve()
    cache = (args.cache_dir or build / "bench-cache").resolve()
    output = (args.output or root / "docs" / "RESULTS.md").resolve()
    plots = (args.plots_dir or root / "docs" / "results").resolve()
    cg_log = (args.callgrind_log or root / "tests" / "data" / "intel_head.clf.gz").resolve()
    work.mkdir(parents=True, exist_ok=True)

    logs: List[Tuple[str, Path, Path]] = []
    for log, rel in [(real_log, real_rel)] + list(zip(args.log, args.relations)):
        logs.append((log_label(log, [l[0] for l in logs]), log.resolve(), rel.resolve()))
    main_label = logs[0][0]
    stage_seconds: Dict[str, float] = {}

    def stage(name, fn, *a):
        print(f"rsm-bench: {name} ...", flush=True)
        t0 = time.monotonic()
        res = fn(*a)
        stage_seconds[name] = time.monotonic() - t0
        print(f"rsm-bench: {name} done in {stage_seconds[name]:.1f} s", flush=True)
        return res

    prov = provenance(root, build)
    ctx = {"root": root, "provenance": prov, "main_label": main_label, "levels": levels, "seeds": seeds,
           "speed_repeats": repeats, "jobs": args.jobs, "quick": args.quick}
    ctx["accuracy"] = stage("accuracy", run_accuracy, nav, logs, work, args.jobs)
    ctx["speed"] = stage("speed", run_speed, nav, real_log, repeats, work)
    ctx["robustness"] = stage("robustness", run_robustness, nav, real_log, real_rel,
                              ctx["accuracy"][main_label]["runs"], levels, seeds, work, cache, args.jobs)
    sanitized = cmake_cache(build).get("RSM_SANITIZE", "OFF").upper() in ("ON", "TRUE", "1", "YES")
    painted = not (args.no_stack or sanitized)
    if not painted:
        ctx["stack_note"] = ("--no-stack" if args.no_stack else
                             "the build is instrumented by AddressSanitizer, which moves frames off the stack")
    ctx["stages"] = stage("stages", run_stage_speed, stages_bin, real_log, repeats, painted)
    ctx["turns"] = stage("turns", run_turns, ctx["accuracy"][main_label]["runs"], real_rel,
                         ctx["stages"]["config"]["cell_m"], args.turns)
    ctx["callgrind"] = ({"skipped": "--no-callgrind"} if args.no_callgrind
                        else stage("callgrind", run_callgrind, nav, cg_log, work, args.jobs, root))
    ctx["memory"] = stage("memory", run_memory, root, build, work)
    ctx["cross_check"] = ({"skipped": "--no-cross-check"} if args.no_cross_check
                          else stage("cross-check", run_cross_check, root))
    if args.no_arm_memory:
        ctx["arm_memory"] = {"skipped": "--no-arm-memory"}
    else:
        wanted = args.arm_configs or [n for n, _ in ARM_CONFIGS]
        ctx["arm_memory"] = stage("arm-memory", run_arm_memory, root, work,
                                  [c for c in ARM_CONFIGS if c[0] in wanted])
    ctx["host_stack"] = stage("host-stack", run_host_stack, root, build, work, args.jobs)
    if not args.no_scaling:
        beams = args.scaling_beams or ([DEFAULT_MAX_BEAMS] if args.quick else list(SCALING_BEAMS))
        maps = args.scaling_maps or ([DEFAULT_MAP_LOG2] if args.quick else list(SCALING_MAP_LOG2))
        ctx["scaling"] = stage("scaling", run_scaling, root, build, real_log, real_rel, work,
                               scaling_variants(beams, maps, () if args.quick else SCALING_PRESETS))
    if args.no_plots:
        ctx["plot_note"] = ctx["turns_plot_note"] = ctx["stages"]["plot_note"] = "--no-plots"
        if ctx.get("scaling"):
            ctx["scaling"]["plot_note"] = "--no-plots"
    else:
        png = plots / "robustness.png"
        note = plot_robustness(ctx["robustness"], png, prov,
                               ctx["accuracy"][main_label]["runs"]["odometry"]["errors"])
        if note:
            ctx["plot_note"] = note
        else:
            ctx["plot"] = os.path.relpath(png, output.parent).replace(os.sep, "/")
        png = plots / "turns.png"
        note = plot_turns(ctx["turns"], png, prov)
        if note:
            ctx["turns_plot_note"] = note
        else:
            ctx["turns_plot"] = os.path.relpath(png, output.parent).replace(os.sep, "/")
        png = plots / "stages.png"
        note = plot_stages(ctx["stages"], png, prov)
        if note:
            ctx["stages"]["plot_note"] = note
        else:
            ctx["stages"]["plot"] = os.path.relpath(png, output.parent).replace(os.sep, "/")
        if ctx.get("scaling"):
            png = plots / "scaling.png"
            note = plot_scaling(ctx["scaling"], png, prov)
            if note:
                ctx["scaling"]["plot_note"] = note
            else:
                ctx["scaling"]["plot"] = os.path.relpath(png, output.parent).replace(os.sep, "/")
    ctx["losses"] = losses(ctx["accuracy"], main_label, ctx["robustness"], ctx["speed"],
                           ctx["callgrind"], ctx["memory"])
    ctx["losses"] += more_losses(ctx["turns"], ctx["stages"], ctx.get("scaling"), ctx.get("arm_memory"),
                                 ctx.get("host_stack"))
    ctx["elapsed"] = time.monotonic() - t_start
    ctx["stage_seconds"] = stage_seconds
    text = write_report(ctx)
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(text, encoding="utf-8")
    manifest = {k: v for k, v in ctx.items() if k != "root"}
    manifest["report"] = str(output)
    manifest["logs"] = [{"label": l, "log": str(g), "relations": str(r)} for l, g, r in logs]
    (work / "bench.json").write_text(json.dumps(manifest, indent=1, default=_json_default,
                                                allow_nan=True))
    print(f"rsm-bench: wrote {output} in {ctx['elapsed']:.0f} s (work files in {work})")
    return output


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        run(args)
    except BenchError as exc:
        print(f"rsm-bench: error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
