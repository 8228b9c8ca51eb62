"""rsm-bench: measures rsm against its ICP baseline and odometry and writes a report.

Every figure in the report is measured by this command; none is typed in.
The report (``docs/RESULTS.md`` by default) has five sections:

1. Accuracy: relative-pose error (Kuemmerle et al. 2009, :mod:`rsm_tools.evaluate`)
   of rsm, icp and odometry on the real log (and on any extra ``--log`` /
   ``--relations`` pairs), on all relations and on local ones (span <= 2 s).
2. Robustness, the paper's experiment: a share of every scan's readings is
   replaced by random ranges (:mod:`rsm_tools.outliers`), several seeds per
   level; errors per level with their spread and their ratio to the clean run.
3. Speed: wall time per scan from rsm-nav's summary (rsm and icp, the same
   bench run, one process at a time) and instructions per scan counted by
   callgrind inside ``rsm_localizer_scan`` on the shipped excerpt.
4. Memory: ``sizeof(rsm_localizer_t)`` and its parts from a small C program
   built against the library, and the Cortex-M4F sizes printed by
   ``tools/cross-check``.
5. Where rsm loses: generated from the numbers above.

Trajectories, summaries and a manifest (``bench.json``) are kept in the work
directory, so that the report can be checked against them; outlier logs are
cached and reused.  ``tools/bench`` sets up, builds ``build-release/`` and
runs this module with the full settings.  Python standard library only;
matplotlib, if installed, draws the robustness curves.
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
    "3. Speed",
    "4. Memory",
    "5. Where rsm loses",
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


def run_callgrind(nav: Path, log: Path, work: Path, jobs: int) -> dict:
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        return {"skipped": "valgrind is not installed"}

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
        return m, {"out": str(out), "scans": s["scans"], "ir": ir, "ir_per_scan": ir / s["scans"]}

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
# plot


def plot_robustness(rob: dict, path: Path, prov: dict, odometry: Optional[dict] = None) -> Optional[str]:
    """Draws the robustness curves; returns None or why there is no plot."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return "matplotlib is not installed (it is the optional extra `rsm-tools[bench]`)"
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
    fig.text(0.01, 0.005, provenance_line(prov).replace("`", ""), fontsize=6.5, ha="left", va="bottom")
    fig.tight_layout(rect=(0, 0.03, 1, 0.96))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100, metadata={"Software": None})
    plt.close(fig)
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


def _range(vals: Sequence[float]) -> str:
    lo, hi = min(vals), max(vals)
    return fmt_ratio(lo) if fmt_ratio(lo) == fmt_ratio(hi) else f"{fmt_ratio(lo)}..{fmt_ratio(hi)}"


def _per_seed(rob: dict, m: str, level: int, s: str, q: str) -> List[float]:
    rows = sorted((r for r in rob["runs"] if r["method"] == m and r["level"] == level),
                  key=lambda r: (r["seed"] is None, r["seed"]))
    return [r["errors"][s][q]["mean"] for r in rows]


# ---------------------------------------------------------------------------
# the report


def md_table(header: Sequence[str], rows: Iterable[Sequence[str]], anchor: str) -> List[str]:
    """A Markdown table preceded by an HTML comment naming it (the test finds it by that)."""
    out = [f"<!-- table: {anchor} -->", "| " + " | ".join(header) + " |",
           "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    out.append("")
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

    # 3. speed
    L += [f"## {SECTION_TITLES[2]}", "", pl, ""]
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
    else:
        L += [f"Instruction counts not measured: {(cg or {}).get('skipped', 'disabled')}.", ""]

    # 4. memory
    L += [f"## {SECTION_TITLES[3]}", "", pl, ""]
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

    # 5. losses
    L += [f"## {SECTION_TITLES[4]}", "", pl, ""]
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
    ctx["callgrind"] = ({"skipped": "--no-callgrind"} if args.no_callgrind
                        else stage("callgrind", run_callgrind, nav, cg_log, work, args.jobs))
    ctx["memory"] = stage("memory", run_memory, root, build, work)
    ctx["cross_check"] = ({"skipped": "--no-cross-check"} if args.no_cross_check
                          else stage("cross-check", run_cross_check, root))
    if args.no_plots:
        ctx["plot_note"] = "--no-plots"
    else:
        png = plots / "robustness.png"
        note = plot_robustness(ctx["robustness"], png, prov,
                               ctx["accuracy"][main_label]["runs"]["odometry"]["errors"])
        if note:
            ctx["plot_note"] = note
        else:
            ctx["plot"] = os.path.relpath(png, output.parent).replace(os.sep, "/")
    ctx["losses"] = losses(ctx["accuracy"], main_label, ctx["robustness"], ctx["speed"],
                           ctx["callgrind"], ctx["memory"])
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
