"""The measurements: every run of rsm-nav, rsm-stages, callgrind, the cross builds and QEMU; each returns a
JSON-able dict (the manifest bench.json holds them all)."""

import concurrent.futures
import datetime
import gzip
import hashlib
import json
import math
import os
import platform
import re
import shutil
import statistics
import subprocess
import time
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from .. import evaluate as ev
from .. import consistency, m4, outliers
from .common import (update_sweep, ARM_CONFIGS, ARM_CPU, BenchError, SCAN_SYMBOL, DEFAULT_MAP_LOG2, DEFAULT_MAX_BEAMS, DEFAULT_TILES,
    DRIVER_OBJECTS, KIND_METHODS, LOCAL_SPAN, M4_TARGETS, MAIN_LOG, MEMORY_TILES, METHODS, QUANTITIES,
    ROBUST_METHODS, ROTATION_BINS, SCALING_BEAMS, SCALING_MAP_LOG2, SCALING_PRESETS, SCALING_TILES, SCOPES,
    SMALL_HEADER, STAGES, STATE_SIZES, TIMING_STATS, TURNS, TURN_SEPARATION_SCANS, bin_label, measured_runs, ratio)
from .parse import (callee_costs, callgrind_ir, callgrind_stages, fused_percent, load_summary, localizer_breakdown,
    parse_callgrind, parse_cross_check, parse_nm_sizes, parse_size_archive, read_callgraph_dir, stack_bounds,
    static_functions)


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


SOURCE_GLOBS = ("src/*/*.[ch]", "include/rsm/*.h", "tools/nav/*.[ch]", "tools/bench-c/*.c", "port/baremetal/*.[ch]",
                "port/baremetal/*/*.[ch]", "port/baremetal/boards/*/*.[ch]")


def source_digest(root: Path) -> str:
    """A digest of the sources the measured programs are built from, to notice
    a change during a run (the figures would then come from different code)."""
    h = hashlib.sha256()
    for pattern in SOURCE_GLOBS:
        for f in sorted(root.glob(pattern)):
            h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


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


def run_nav(nav: Path, log: Path, method: str, traj: Path, prefix: Sequence[str] = (),
            extra: Sequence[str] = ()) -> dict:
    """Runs rsm-nav (optionally under a wrapper such as valgrind, with extra
    arguments such as --set); returns its summary text, the summary it wrote
    as JSON (``parsed``, see load_summary) and the wall time of the whole
    process."""
    traj.parent.mkdir(parents=True, exist_ok=True)
    summary = traj.with_suffix(".summary.json")
    cmd = [*prefix, str(nav), "--carmen", str(log), "--method", method,
           "--trajectory", str(traj), "--summary-json", str(summary), "--quiet", *extra]
    t0 = time.monotonic()
    res = subprocess.run(cmd, capture_output=True, text=True)
    elapsed = time.monotonic() - t0
    if res.returncode != 0:
        raise BenchError(f"{' '.join(cmd)} failed ({res.returncode}):\n{res.stderr}")
    return {"summary": res.stdout, "parsed": load_summary(summary), "stderr": res.stderr, "seconds": elapsed}


def parallel(fn, items: Iterable, jobs: int) -> list:
    """fn over items, ``jobs`` at a time (threads: the work is in subprocesses)."""
    items = list(items)
    if jobs <= 1 or len(items) <= 1:
        return [fn(i) for i in items]
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(fn, items))


def scoped_errors(traj: Path, relations: List[ev.Relation], details: bool = False) -> dict:
    """evaluate_scopes() of a trajectory file."""
    return ev.evaluate_scopes(ev.load_trajectory(traj), relations, details)


def _strip_errors(res: dict) -> dict:
    return {s: {k: v for k, v in r.items() if k != "errors"} for s, r in res.items()}


def log_label(log: Path, taken: Iterable[str] = ()) -> str:
    name = log.name
    for ext in (".gz", ".clf", ".log", ".txt"):
        if name.endswith(ext):
            name = name[: -len(ext)]
    label, k = name or "log", 2
    while label in taken:
        label = f"{name}-{k}"
        k += 1
    return label


def shared_dir(arg: Optional[Path], root: Path) -> Path:
    """The shared folder: --shared, else $RSM_SHARED_DIR (docs/reference/README.md), else ../shared."""
    if arg is not None:
        return Path(arg).resolve()
    env = os.environ.get("RSM_SHARED_DIR")
    return Path(env).resolve() if env else (root.parent / "shared").resolve()


def discover_logs(data: Path) -> List[Tuple[str, Path, Path]]:
    """(label, log, relations) of every folder NAME of ``data`` holding
    NAME.clf.gz (or NAME.clf) and NAME.relations; the main log (MAIN_LOG if
    there is one) first, the others by name."""
    out = []
    if data.is_dir():
        for d in sorted(p for p in data.iterdir() if p.is_dir()):
            rel = d / f"{d.name}.relations"
            logs = [d / f"{d.name}.clf.gz", d / f"{d.name}.clf"]
            log = next((f for f in logs if f.is_file()), None)
            if log is not None and rel.is_file():
                out.append((d.name, log.resolve(), rel.resolve()))
    out.sort(key=lambda t: (t[0] != MAIN_LOG, t[0]))
    return out


def run_accuracy(navs: Dict[str, Optional[Path]], logs: List[Tuple[str, Path, Path]], work: Path,
                 jobs: int) -> dict:
    """Every method of the default build and rsm of the small build on every log."""
    runs = measured_runs(METHODS, navs.get("small") is not None)
    tasks = [(label, log, run, m, navs[build]) for label, log, _ in logs for run, build, m in runs]

    def one(task):
        label, log, run_label, m, nav = task
        traj = work / "accuracy" / label / f"{run_label}.txt"
        # rsm's runs log each scan's covariance, checked against the error below
        extra = ["--scan-log", str(traj.with_suffix(".scans"))] if m == "rsm" else []
        return task, traj, run_nav(nav, log, m, traj, extra=extra)

    done = parallel(one, tasks, jobs)
    out = {}
    for label, log, rel in logs:
        relations = ev.load_relations(rel)
        runs = {}
        for (lab, _, run_label, m, _), traj, r in done:
            if lab != label:
                continue
            errs = scoped_errors(traj, relations, details=True)
            runs[run_label] = {
                "method": m,
                "trajectory": str(traj),
                "summary_text": r["summary"],
                "summary": r["parsed"],
                "errors": _strip_errors(errs),
                "per_relation": errs["all"]["errors"],
            }
            if m == "rsm":
                runs[run_label]["covariance"] = consistency.nees(
                    ev.load_trajectory(traj), relations, consistency.read_covariances(traj.with_suffix(".scans")))
        out[label] = {"log": str(log), "relations": str(rel), "relation_count": len(relations), "runs": runs}
    return out


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


def outlier_log_path(log: Path, level: int, seed: int, cache: Path, tag: str) -> Path:
    return cache / f"{log_label(log)}-{tag}-p{level}-s{seed}.clf.gz"


def outlier_logs(wanted: Sequence[Tuple[Path, int, int]], cache: Path,
                 jobs: int) -> Tuple[Dict[Tuple[str, int, int], Path], int]:
    """The outlier logs for every (log, level > 0, seed), from the cache (keyed
    by the log's digest) or made now, ``jobs`` at a time. Returns them by
    (str(log), level, seed) and how many were made."""
    cache.mkdir(parents=True, exist_ok=True)
    tags: Dict[str, str] = {}
    want = {}
    for log, level, seed in wanted:
        if level == 0:
            continue
        if str(log) not in tags:
            tags[str(log)] = file_digest(log)[:12]
        want[(str(log), level, seed)] = outlier_log_path(log, level, seed, cache, tags[str(log)])
    missing = [(k, p) for k, p in want.items() if not p.is_file()]
    if missing:
        with concurrent.futures.ProcessPoolExecutor(max_workers=max(1, jobs)) as pool:
            futs = [pool.submit(_make_outlier_log, k[0], str(p), k[1], k[2]) for k, p in missing]
            for f in futs:
                f.result()
    return want, len(missing)


def spread(values: Sequence[float]) -> dict:
    """Mean, min, max and count of the finite values, with the mean's
    standard error and the median."""
    vals = sorted(v for v in values if v is not None and math.isfinite(v))
    n = len(vals)
    if n == 0:
        return {"mean": float("nan"), "min": float("nan"), "max": float("nan"), "n": 0, "se": float("nan"),
                "median": float("nan")}
    mean = math.fsum(vals) / n
    se = math.sqrt(math.fsum((v - mean) ** 2 for v in vals) / (n - 1) / n) if n > 1 else float("nan")
    return {"mean": mean, "min": vals[0], "max": vals[-1], "n": n, "se": se, "median": statistics.median(vals)}


def run_robustness(nav: Path, logs: List[Tuple[str, Path, Path]], acc: dict, levels: Dict[str, Sequence[int]],
                   seeds: Sequence[int], work: Path, cache: Path, jobs: int) -> dict:
    """Per log: rsm, the paper's method and icp on the outlier logs of its
    levels and seeds; the table of means, spreads and ratios to the clean run
    (level 0 is the accuracy run itself)."""
    wanted = [(log, lv, sd) for label, log, _ in logs for lv in levels[label] for sd in seeds]
    paths, made = outlier_logs(wanted, cache, jobs)
    tasks = [(label, m, lv, sd) for label, log, _ in logs for lv in levels[label] if lv != 0
             for sd in seeds for m in ROBUST_METHODS]
    by_label = {label: (log, rel) for label, log, rel in logs}
    # The slowest runs (icp, high levels) first, so that the last ones are short.
    tasks.sort(key=lambda t: (t[1] != "icp", -t[2]))

    def one(task):
        label, m, level, seed = task
        traj = work / "robustness" / label / f"{m}-p{level}-s{seed}.txt"
        return task, traj, run_nav(nav, paths[(str(by_label[label][0]), level, seed)], m, traj)

    done = parallel(one, tasks, jobs)
    out = {"seeds": list(seeds), "outlier_logs_made": made, "logs": {}}
    for label, log, rel in logs:
        relations = ev.load_relations(rel)
        runs = []
        for m in ROBUST_METHODS:
            c = acc[label]["runs"][m]
            runs.append({"method": m, "level": 0, "seed": None, "trajectory": c["trajectory"],
                         "summary": c["summary"], "errors": c["errors"]})
        for (lab, m, level, seed), traj, r in sorted(done, key=lambda d: (d[0][2], d[0][3], d[0][1])):
            if lab != label:
                continue
            runs.append({"method": m, "level": level, "seed": seed, "trajectory": str(traj),
                         "log": str(paths[(str(log), level, seed)]), "summary": r["parsed"],
                         "errors": _strip_errors(scoped_errors(traj, relations))})
        lvls = sorted(set(levels[label]) | {0})
        table = {}
        for m in ROBUST_METHODS:
            for level in lvls:
                sel = [r for r in runs if r["method"] == m and r["level"] == level]
                row = {"seeds": [r["seed"] for r in sel],
                       "fused": spread([fused_percent(r["summary"]) for r in sel])}
                for sc in SCOPES:
                    for q in QUANTITIES:
                        row[f"{sc}.{q}"] = spread([r["errors"][sc][q]["mean"] for r in sel])
                table[f"{m}:{level}"] = row
        for m in ROBUST_METHODS:
            clean = table[f"{m}:0"]
            for level in lvls:
                row = table[f"{m}:{level}"]
                for key in [f"{sc}.{q}" for sc in SCOPES for q in QUANTITIES]:
                    row[key]["ratio"] = ratio(row[key]["mean"], clean[key]["mean"])
                    row[key]["ratio_max"] = ratio(row[key]["max"], clean[key]["mean"])
        out["logs"][label] = {"log": str(log), "relations": str(rel), "levels": lvls, "seeds": list(seeds),
                              "runs": runs, "table": table}
    return out


def spread_updates(count: int) -> List[float]:
    """map_update_m values of the spread section: 0.300, 0.305, ... m."""
    return update_sweep(count)


def run_spread(nav: Path, logs: List[Tuple[str, Path, Path]], level: int, seeds: Sequence[int],
               updates: Sequence[float], work: Path, cache: Path, jobs: int) -> dict:
    """Per log: rsm once per map_update_m of ``updates`` on the clean log,
    and at every other one of them on its copy at ``level`` % outliers for
    each seed. A run's all-relations error is one draw of a chaotic process
    (rounding alone moves it by a tenth, docs/map.md), and so is a seed's
    draw of phantoms, so the floors' ratios are also taken between the means
    of many runs over many seeds."""
    paths, made = outlier_logs([(log, level, sd) for _, log, _ in logs for sd in seeds], cache, jobs)
    noisy_updates = list(updates[::2])
    tasks = []
    for label, log, _ in logs:
        tasks += [(label, "clean", log, u) for u in updates]
        tasks += [(label, f"s{sd}", paths[(str(log), level, sd)], u) for sd in seeds for u in noisy_updates]

    def one(task):
        label, variant, path, u = task
        traj = work / "spread" / label / f"{variant}-{u:.3f}.txt"
        run_nav(nav, path, "rsm", traj, extra=("--set", f"map_update_m={u:g}"))
        return task, traj

    done = parallel(one, tasks, jobs)
    out = {"level": level, "seeds": list(seeds), "updates": list(updates), "noisy_updates": noisy_updates,
           "outlier_logs_made": made, "logs": {}}
    for label, _, rel in logs:
        relations = ev.load_relations(rel)
        vals: Dict[str, Dict[str, List[float]]] = {k: {sc: [] for sc in SCOPES} for k in ("clean", "noisy")}
        for (lab, variant, _, _), traj in done:
            if lab == label:
                e = scoped_errors(traj, relations)
                for sc in SCOPES:
                    vals["clean" if variant == "clean" else "noisy"][sc].append(e[sc]["translation"]["mean"])
        out["logs"][label] = {k: {sc: spread(v) for sc, v in d.items()} for k, d in vals.items()}
    return out


def run_speed(nav: Path, log: Path, repeats: int, work: Path) -> dict:
    """rsm and icp alternately, one process at a time, ``repeats`` times each."""
    runs = []
    for k in range(repeats):
        for m in ROBUST_METHODS:
            traj = work / "speed" / f"{m}-r{k + 1}.txt"
            r = run_nav(nav, log, m, traj)
            runs.append({"method": m, "repeat": k + 1, "trajectory": str(traj),
                         "summary_text": r["summary"], "summary": r["parsed"]})
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
    # each method against rsm (above 1: slower than rsm)
    out["ratio_median"] = {m: ratio(out["methods"][m]["median_us"], out["methods"]["rsm"]["median_us"])
                           for m in ROBUST_METHODS}
    out["ratio_p95"] = {m: ratio(out["methods"][m]["p95_us"], out["methods"]["rsm"]["p95_us"])
                        for m in ROBUST_METHODS}
    return out


_SCAN_LINE = re.compile(rb"^\s*(?:FLASER|ROBOTLASER1)\s")


def write_head(log: Path, out: Path, scans: int) -> int:
    """The log up to its ``scans``-th scan line (gzip, mtime 0, so that reruns
    give the same bytes); returns the scans written."""
    out.parent.mkdir(parents=True, exist_ok=True)
    n = 0
    tmp = out.with_name(out.name + f".tmp{os.getpid()}")
    opener = gzip.open if log.name.endswith(".gz") else open
    with opener(log, "rb") as src, open(tmp, "wb") as raw, \
            gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0) as dst:
        for line in src:
            dst.write(line)
            if _SCAN_LINE.match(line):
                n += 1
                if n >= scans:
                    break
    os.replace(tmp, out)
    return n


def run_callgrind(navs: Dict[str, Optional[Path]], logs: List[Tuple[str, Path, Path]], scans: int,
                  methods: Sequence[str], work: Path, jobs: int, root: Optional[Path] = None) -> dict:
    """Instructions inside rsm_localizer_scan on the first ``scans`` scans of
    every log: ``methods`` with the default build, rsm with the small one."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        return {"skipped": "valgrind is not installed"}
    helpers = static_functions((root / "src" / "localizer" / "localizer.c").read_text()) if root else []
    heads = {}
    for label, log, _ in logs:
        head = work / "callgrind" / f"{label}-head{scans}.clf.gz"
        heads[label] = {"log": str(head), "source": str(log), "scans": write_head(log, head, scans)}
    runs = measured_runs(methods, navs.get("small") is not None)
    # every log's runs of the default build, then the small build's (the manifest's order)
    tasks = sorted(((label, build, m, navs[build]) for label, _, _ in logs for _, build, m in runs),
                   key=lambda t: t[1] != "default")

    def one(task):
        label, config, m, nav = task
        out = work / "callgrind" / f"{label}-{config}-{m}.callgrind.out"
        traj = work / "callgrind" / f"{label}-{config}-{m}.txt"
        out.parent.mkdir(parents=True, exist_ok=True)
        prefix = [valgrind, "--tool=callgrind", f"--toggle-collect={SCAN_SYMBOL}",
                  f"--callgrind-out-file={out}"]
        r = run_nav(nav, Path(heads[label]["log"]), m, traj, prefix)
        sm = r["parsed"]
        ir = callgrind_ir(out)
        if ir == 0:
            raise BenchError(f"callgrind collected nothing in rsm_localizer_scan for {m} "
                             "(is the symbol in the binary?)")
        res = {"log": label, "config": config, "method": m, "out": str(out), "trajectory": str(traj),
               "scans": sm["scans"], "ir": ir, "ir_per_scan": ir / sm["scans"]}
        cg = parse_callgrind(out.read_text(errors="replace"))
        br = localizer_breakdown(cg, helpers)
        if br["total"] == ir:  # the breakdown accounts for every instruction collected
            res["breakdown"] = br
            res["stages"] = callgrind_stages(br, sm["scans"])
        else:
            res["breakdown_note"] = f"the call graph accounts for {br['total']} of {ir} instructions"
        if m == "rsm":
            res["mapmatch"] = callee_costs(cg, "rsm_mapmatch")
        return f"{label}:{config}:{m}", res

    runs = dict(parallel(one, tasks, jobs))
    return {"runs": runs, "heads": heads, "scans": scans, "methods": list(methods),
            "valgrind": first_line([valgrind, "--version"]) or "valgrind"}


def run_memory(exes: Dict[str, Optional[Path]], log: Path, build_dir: Path) -> dict:
    """sizeof the localizer state and its parts on this host, per
    configuration, from rsm-stages' JSON (one scan is enough)."""
    out = {"configs": {}}
    cache = cmake_cache(build_dir)
    out["compiler"] = compiler_name(build_dir, cache.get("CMAKE_C_COMPILER") or "cc")
    for name, exe in exes.items():
        if exe is None:
            continue
        j = run_stages(exe, log, "rsm", ["--limit", "1", "--clock", "none"])
        sizes = j["sizes"]
        other = sizes["rsm_localizer_t"] - sum(sizes[k] for k in MEMORY_TILES)
        out["configs"][name] = {"sizes": sizes, "config": j["config"], "other": other,
                                "header": SMALL_HEADER if name == "small" else None}
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
    r_ = out["methods"]["rsm"]["timing"]["call"]
    for key in ("median", "p95", "mean"):
        out[f"ratio_{key}"] = {m: ratio(out["methods"][m]["timing"]["call"][f"{key}_us"], r_[f"{key}_us"])
                               for m in ROBUST_METHODS}
    if stack:
        out["stack"] = {m: run_stages(exe, log, m, ["--stack"])["stack"] for m in ROBUST_METHODS}
    return out


def scan_order(traj: Path) -> Dict[float, int]:
    """Scan index (file order) of every timestamp of a trajectory that has one
    line per scan (rsm-nav writes one); the first occurrence counts."""
    out: Dict[float, int] = {}
    for k, p in enumerate(ev.read_poses(traj)[0]):
        out.setdefault(round(p.t, 6), k)
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
    wins = {o: {q: sum(1 for row in rows if row["residual"]["rsm"] and row["residual"][o]
                       and row["residual"]["rsm"][q] < row["residual"][o][q])
                for q in ("translation_cells", "rotation_deg")} for o in METHODS if o != "rsm"}
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


def state_probe(names: Sequence[Tuple[str, str, str]]) -> str:
    lines = ["/* Generated by rsm_tools.bench: sizes of the caller-owned state on the target. */",
             '#include "rsm/localizer.h"', '#include "rsm/p3dx.h"', '#include "rsm/sicklms.h"',
             '#include "rsm/sync.h"', ""]
    for k, (_, _, expr) in enumerate(names):
        lines.append(f"char rsm_size_{k}[{expr}];")
    return "\n".join(lines) + "\n"


def _config_flag(root: Path, header: Optional[str]) -> List[str]:
    return [f"-DRSM_USER_CONFIG={header}"] if header else []  # found on the include path


def _arm_size(elf: Path) -> dict:
    """Berkeley sizes of an image: flash = text + data, RAM = data + bss (stack included)."""
    try:
        return m4.image_size(elf)
    except m4.M4Error as e:
        raise BenchError(str(e))


def _symbol_bytes(elf: Path, names: Sequence[str]) -> int:
    res = subprocess.run(["arm-none-eabi-nm", "-S", str(elf)], capture_output=True, text=True)
    return sum(int(f[1], 16) for f in (l.split() for l in res.stdout.splitlines())
               if len(f) == 4 and f[3] in names)


def m4_global(elf: Path, mapflash_host: Optional[Path], replay_host: Optional[Path], work: Path) -> dict:
    """The global search's instructions per scan on the M4: the map-in-flash
    image's run with all of ``rsm-m4 mapflash``'s checks (its search as the
    host's, same source, rsm-mapflash-host), its figures (m4.global_costs)."""
    for exe, name in ((mapflash_host, "rsm-mapflash-host"), (replay_host, "rsm-replay-host")):
        if exe is None or not exe.is_file():
            return {"skipped": f"{name} was not built (its run is what the target's is checked against)"}
    try:
        return m4.mapflash_run(elf, mapflash_host, replay_host, work)[1]
    except m4.M4Error as e:
        raise BenchError(str(e))


def _cross_build(root: Path, b: Path, toolchain: str, opt: str, targets: Sequence[str]) -> Path:
    """A cross build of the images ``targets`` at ``opt`` with
    cmake/``toolchain`` in ``b``; returns the folder of the images."""
    cmd = ["cmake", "-S", str(root), "-B", str(b), "-G", "Ninja",
           f"-DCMAKE_TOOLCHAIN_FILE={root / 'cmake' / toolchain}",
           "-DCMAKE_BUILD_TYPE=Release", f"-DCMAKE_C_FLAGS_RELEASE={opt} -DNDEBUG"]
    for c in (cmd, ["cmake", "--build", str(b), "--parallel", "2", "--target", *targets]):
        res = subprocess.run(c, capture_output=True, text=True)
        if res.returncode != 0:
            raise BenchError(f"{' '.join(c)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")
    return b / "port" / "baremetal"


# The replay on the other builds (issue 33): the M4F at -Os, and the
# Cortex-M3 and the Cortex-M0+ with soft float on QEMU's mps2-an385 (an M3,
# which runs the M0+'s ARMv6-M code as it is): (key, toolchain, option,
# image, machine).
M4_VARIANTS = (("m4-Os", "toolchain-arm-none-eabi.cmake", "-Os", "rsm_replay_m4", m4.MACHINE),
               ("m3-O2", "toolchain-arm-cortex-m3.cmake", "-O2", "rsm_replay_m3", m4.MACHINE_M3),
               ("m0plus-O2", "toolchain-arm-cortex-m0plus.cmake", "-O2", "rsm_replay_m0plus", m4.MACHINE_M3))
# The Cortex-M0+ build (RP2040), which only links: its LD06 example's size
# (built in the M0+ replay's tree).
M0PLUS_IMAGE = "rsm_firmware_rp2040_ld06"


def _poses(text: str) -> List[str]:
    """The P lines of a replay's output (host or target): its trajectory."""
    return [l for l in text.splitlines() if l.startswith("P ")]


def run_m4_variants(root: Path, work: Path, host_out: Optional[str], fixed_out: Optional[str] = None) -> dict:
    """The replay built as M4_VARIANTS says, each run under QEMU: its
    instructions per scan (m4.costs), its image's sizes and whether its
    trajectory equals the host's (host_out, rsm-replay-host's output; None
    when it was not built); and the Cortex-M0+ image's sizes. The soft-float
    builds (M3, M0+) run the fixed-point map matcher (RSM_FIXED_MATCH, their
    default): theirs is compared with fixed_out, rsm-replay-host-fixed's."""
    out: Dict[str, dict] = {}
    for key, toolchain, opt, target, machine in M4_VARIANTS:
        extra = [M0PLUS_IMAGE] if key.startswith("m0plus") else []
        fw_dir = _cross_build(root, work / key, toolchain, opt, [target] + extra)
        elf = fw_dir / f"{target}.elf"
        try:
            text = m4.run(elf, machine=machine)
            cost = m4.costs(text)
        except m4.M4Error as e:
            raise BenchError(str(e))
        (work / f"{key}-replay.out").write_text(text)
        ref = fixed_out if key.startswith(("m3", "m0plus")) else host_out
        out[key] = {"machine": machine, "opt": opt, "cost": cost, "image": _arm_size(elf),
                    "identical": None if ref is None else _poses(text) == _poses(ref)}
        if extra:
            out["m0plus"] = {"image": _arm_size(fw_dir / f"{M0PLUS_IMAGE}.elf"), "name": M0PLUS_IMAGE}
    return out


def run_m4(root: Path, work: Path, replay_host: Optional[Path], mapflash_host: Optional[Path] = None) -> dict:
    """The firmware images cross-built at -O2 and run under QEMU (mps2-an386):
    instructions per scan and per stage of the replay firmware on the shipped
    excerpt, the known-loop calibration, each image's flash, RAM and painted
    stack; callgrind's count of the same excerpt through the same source on
    the host (rsm-replay-host), when valgrind is there; the global
    search's instructions per scan from the map-in-flash image (m4_global);
    and the replay at -Os, on a Cortex-M3 and the Cortex-M0+ image's size
    (run_m4_variants)."""
    for tool in ("arm-none-eabi-gcc", "arm-none-eabi-size", "arm-none-eabi-nm", "qemu-system-arm", "cmake",
                 "ninja"):
        if shutil.which(tool) is None:
            return {"skipped": f"{tool} is not installed"}
    b = work / "m4-O2"
    _cross_build(root, b, "toolchain-arm-none-eabi.cmake", "-O2", M4_TARGETS)
    fw_dir = b / "port" / "baremetal"
    replay_elf, example_elf = fw_dir / "rsm_replay_m4.elf", fw_dir / "rsm_firmware.elf"
    try:
        out = m4.run(replay_elf)
        cost = m4.costs(out)
        ex_dir = work / "m4-example"
        ex_dir.mkdir(parents=True, exist_ok=True)
        ex_out = m4.run(example_elf, [ex_dir / "robot.bin", ex_dir / "laser.bin"])
    except m4.M4Error as e:
        raise BenchError(str(e))
    (work / "m4-replay.out").write_text(out)
    ex_m = m4.lines_of(ex_out, "M")
    images = {"replay": {**_arm_size(replay_elf), "stack_used": cost["stack_used"],
                         "stack_size": cost["stack_size"],
                         "excerpt": _symbol_bytes(replay_elf, ("rsm_replay_scans", "rsm_replay_steps"))},
              "example": {**_arm_size(example_elf), "stack_used": int(ex_m[0][1]) if ex_m else None,
                          "stack_size": int(ex_m[0][3]) if ex_m else None, "excerpt": 0}}
    res_out = {"compiler": first_line(["arm-none-eabi-gcc", "--version"]) or "arm-none-eabi-gcc",
               "qemu": first_line(["qemu-system-arm", "--version"]) or "qemu-system-arm",
               "icount_shift": m4.ICOUNT_SHIFT, "cost": cost, "images": images,
               "global": m4_global(fw_dir / "rsm_mapflash_m4.elf", mapflash_host, replay_host, work / "m4-mapflash")}
    valgrind = shutil.which("valgrind")
    host_out = None
    if replay_host is None or not replay_host.is_file():
        res_out["host"] = {"skipped": "rsm-replay-host was not built"}
    elif valgrind is None:
        res_out["host"] = {"skipped": "valgrind is not installed"}
    else:
        cg_out = work / "m4-host.callgrind.out"
        r = subprocess.run([valgrind, "--tool=callgrind", f"--toggle-collect={SCAN_SYMBOL}",
                            f"--callgrind-out-file={cg_out}", str(replay_host)], capture_output=True, text=True)
        if r.returncode != 0:
            raise BenchError(f"callgrind of {replay_host} failed: {r.stderr[-2000:]}")
        host_out = r.stdout
        ir = callgrind_ir(cg_out)
        res_out["host"] = {"ir": ir, "scans": len(_poses(host_out)), "ir_per_scan": ir / max(1, len(_poses(host_out))),
                           "identical": _poses(host_out) == _poses(out)}
    if host_out is None and replay_host is not None and replay_host.is_file():
        # No valgrind: the host's output for the other builds all the same.
        h = subprocess.run([str(replay_host)], capture_output=True, text=True)
        if h.returncode != 0:
            raise BenchError(f"{replay_host} failed: {h.stderr[-2000:]}")
        host_out = h.stdout
    fixed_out = None
    fixed_host = None if replay_host is None else replay_host.with_name("rsm-replay-host-fixed")
    if fixed_host is not None and fixed_host.is_file():
        h = subprocess.run([str(fixed_host)], capture_output=True, text=True)
        if h.returncode != 0:
            raise BenchError(f"{fixed_host} failed: {h.stderr[-2000:]}")
        fixed_out = h.stdout
    res_out["variants"] = run_m4_variants(root, work, host_out, fixed_out)
    return res_out


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
               "-fcallgraph-info=su", f"-DRSM_USER_CONFIG={header or ''}"]
        for c in (cmd, ["cmake", "--build", str(b), "--target", "rsm", "rsm_port_baremetal", "rsm_firmware"]):
            res = subprocess.run(c, capture_output=True, text=True)
            if res.returncode != 0:
                raise BenchError(f"{' '.join(c)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")
        cfg = {"header": header or "rsm/config.h (defaults)"}
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

    core = [f for f in sorted((root / "src").glob("*/*.c")) if f.stem not in DRIVER_OBJECTS]
    for src, res in parallel(compile_one, core, jobs):
        if res.returncode != 0:
            return {"skipped": f"compiling {src.name} with -fcallgraph-info failed: "
                               + (res.stderr.strip().splitlines() or ["?"])[-1]}
    graph = read_callgraph_dir(d)
    return {"flags": " ".join(flags), "compiler": first_line([cc, "--version"]) or cc,
            "stack": stack_bounds(graph)}


def hash_log2_for(tiles: int) -> int:
    """The smallest tile index (log2 of its slots) config.h accepts for a pool:
    at least 4/3 slots per tile."""
    h = 4
    while (1 << h) * 3 < 4 * tiles:
        h += 1
    return h


def scaling_variants(beams: Sequence[int] = SCALING_BEAMS, maps: Sequence[int] = SCALING_MAP_LOG2,
                     tiles: Sequence[int] = SCALING_TILES, presets: Sequence[str] = SCALING_PRESETS) -> List[dict]:
    """The builds and runs of the scaling section. Readings: the log's scans
    resampled to N readings, RSM_MAX_BEAMS = N (the default 361 is the default
    build). Map: the log's own readings, RSM_MAP_SIZE_LOG2 = L (the paper's
    window). Tiles: the log's own readings, RSM_TMAP_TILES = T with the
    smallest index that fits. Presets: a shipped config header, the log's own
    readings."""
    out = []
    for n in beams:
        macros = {} if n == DEFAULT_MAX_BEAMS else {"RSM_MAX_BEAMS": n}
        out.append({"name": f"beams{n}", "kind": "beams", "value": n, "macros": macros, "resample": n})
    for lg in maps:
        macros = {} if lg == DEFAULT_MAP_LOG2 else {"RSM_MAP_SIZE_LOG2": lg}
        out.append({"name": f"map{lg}", "kind": "map", "value": lg, "macros": macros, "resample": None})
    for t in tiles:
        macros = {} if t == DEFAULT_TILES else {"RSM_TMAP_TILES": t, "RSM_TMAP_HASH_LOG2": hash_log2_for(t)}
        out.append({"name": f"tiles{t}", "kind": "tiles", "value": t, "macros": macros, "resample": None})
    for k, h in enumerate(presets):
        out.append({"name": Path(h).stem, "kind": "preset", "value": k, "macros": {}, "header": h,
                    "resample": None})
    for v in out:
        v["methods"] = list(KIND_METHODS[v["kind"]])
    return out


def variant_header(macros: Dict[str, int]) -> str:
    lines = ["/* Generated by rsm_tools.bench: a scaling variant of config.h. */",
             "#ifndef RSM_BENCH_VARIANT_H", "#define RSM_BENCH_VARIANT_H"]
    lines += [f"#define {k} {v}" for k, v in sorted(macros.items())]
    lines += ["#endif", ""]
    return "\n".join(lines)


def configure_build(root: Path, b: Path, main_build: Path, header, targets: Sequence[str],
                    options: Sequence[str] = ()) -> None:
    """A Release build of ``targets`` in ``b`` with RSM_USER_CONFIG=header (None:
    the default config.h) and the CMake ``options``, with the main build's
    compiler and warning settings."""
    cache = cmake_cache(main_build)
    cmd = ["cmake", "-S", str(root), "-B", str(b), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
           "-DRSM_BUILD_TESTS=OFF", *([f"-DRSM_USER_CONFIG={header}"] if header is not None else []), *options]
    if cache.get("CMAKE_C_COMPILER"):
        cmd.append(f"-DCMAKE_C_COMPILER={cache['CMAKE_C_COMPILER']}")
    if cache.get("RSM_WERROR"):
        cmd.append(f"-DRSM_WERROR={cache['RSM_WERROR']}")
    for c in (cmd, ["cmake", "--build", str(b), "--target", *targets]):
        res = subprocess.run(c, capture_output=True, text=True)
        if res.returncode != 0:
            raise BenchError(f"{' '.join(c)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")


def build_fixed(root: Path, main_build: Path, d: Path) -> Path:
    """rsm-nav with the fixed-point map matcher (RSM_FIXED_MATCH, what the
    cores without an FPU build) on this host, in ``d``."""
    configure_build(root, d, main_build, None, ("rsm-nav",), ("-DRSM_FIXED_MATCH=ON",))
    return d / "tools" / "nav" / "rsm-nav"


def build_small(root: Path, main_build: Path, d: Path) -> Dict[str, Path]:
    """rsm-nav and rsm-stages built with rsm/config_small.h in ``d``."""
    configure_build(root, d, main_build, SMALL_HEADER, ("rsm-nav", "rsm-stages"))
    return {"nav": d / "tools" / "nav" / "rsm-nav", "stages": stages_exe(d), "dir": d}


def build_variant(root: Path, work: Path, main_build: Path, variant: dict,
                  prebuilt: Optional[Dict[str, Path]] = None) -> Path:
    """rsm-stages for a variant: the main build's when the variant is the
    default, one already built for its header (``prebuilt``), else a Release
    build of its own with a generated RSM_USER_CONFIG."""
    if not variant["macros"] and not variant.get("header"):
        return stages_exe(main_build)
    if variant.get("header") and prebuilt and variant["header"] in prebuilt:
        return prebuilt[variant["header"]]
    d = work / "variants" / variant["name"]
    d.mkdir(parents=True, exist_ok=True)
    if variant.get("header"):
        header = variant["header"]  # on the library's include path
    else:
        header = d / "rsm_bench_variant.h"
        text = variant_header(variant["macros"])
        if not header.is_file() or header.read_text() != text:
            header.write_text(text)
    configure_build(root, d / "build", main_build, header, ("rsm-stages",))
    return stages_exe(d / "build")


def run_scaling(root: Path, main_build: Path, log: Path, relations_path: Path, work: Path,
                variants: Optional[List[dict]] = None, prebuilt: Optional[Dict[str, Path]] = None) -> dict:
    """Each variant's methods through rsm-stages, one process at a time (they
    are timed): time per scan, accuracy (local and all), fused share, sizes."""
    variants = variants if variants is not None else scaling_variants()
    relations = ev.load_relations(relations_path)
    rows = []
    for v in variants:
        exe = build_variant(root, work, main_build, v, prebuilt)
        for m in v["methods"]:
            extra = ["--clock", "ns"] + (["--beams", str(v["resample"])] if v["resample"] else [])
            traj = work / "scaling" / f"{v['name']}-{m}.txt"
            j = run_stages(exe, log, m, extra, traj)
            err = scoped_errors(traj, relations)
            rows.append({"variant": v["name"], "kind": v["kind"], "value": v["value"], "macros": v["macros"],
                         "method": m, "beams": j["beams"], "config": j["config"], "sizes": j["sizes"],
                         "call": j["timing"]["call"], "scans": j["scans"], "trajectory": str(traj),
                         "header": v.get("header"), "outcomes": j["outcomes"], "tmap": j.get("tmap"),
                         "fused": 100.0 * j["outcomes"]["accepted"] / j["scans"] if j["scans"] else float("nan"),
                         "local": {q: err["local"][q]["mean"] for q in QUANTITIES},
                         "all": {q: err["all"][q]["mean"] for q in QUANTITIES},
                         "matched": err["local"]["matched"]})
    return {"log": str(log), "variants": variants, "rows": rows, "growth": memory_growth(rows)}


def memory_growth(rows: Sequence[dict]) -> dict:
    """Bytes of rsm_localizer_t per reading of RSM_MAX_BEAMS, per cell of the
    paper's window and per tile of the pool, from the smallest and largest
    variant of each kind."""
    out = {}
    for kind, x in (("beams", lambda r: r["config"]["RSM_MAX_BEAMS"]),
                    ("map", lambda r: r["config"]["RSM_MAP_SIZE"] ** 2),
                    ("tiles", lambda r: r["config"]["RSM_TMAP_TILES"])):
        sel = sorted({(x(r), r["sizes"]["rsm_localizer_t"]) for r in rows if r["kind"] == kind})
        if len(sel) >= 2 and sel[-1][0] != sel[0][0]:
            out[kind] = {"from": sel[0], "to": sel[-1],
                         "bytes_per_unit": (sel[-1][1] - sel[0][1]) / (sel[-1][0] - sel[0][0])}
    return out
