"""rsm-bench: measures rsm against the paper's method, ICP, odometry and the peers, and writes a report.

Every figure of rsm in the report is measured by this command; none is typed
in. The peers' figures are read from ``docs/reference/peers.md`` (``--peers``)
and shown beside them. The logs are every folder ``NAME`` of the
shared folder's ``data/`` that holds ``NAME.clf.gz`` and ``NAME.relations``
(the shared folder: ``--shared DIR``, else the ``RSM_SHARED_DIR`` environment
variable, the one setting for the full logs, else ``../shared`` beside the repository). The
report (``docs/RESULTS.md`` by default) has these sections:

1. Accuracy: relative-pose error (Kuemmerle et al. 2009, :mod:`rsm_tools.evaluate`)
   of rsm (the default method, the persistent map), rsm built with
   ``rsm/config_small.h``, the paper's method, the ICP baseline and odometry on
   every log, on all relations and on local ones (span <= 2 s), beside the
   peers' figures and the ratio of rsm's to the best peer's.
2. Robustness, the paper's experiment: a share of every scan's readings is
   replaced by random ranges (:mod:`rsm_tools.outliers`); the whole curve on
   the main log, 43 % and 60 % on every log.
3. Sharp turns, the paper's Fig. 8: residuals at the local relations with the
   fastest true turn, and over all local relations binned by true rotation.
4. Speed: wall time per scan (rsm-nav), per stage (``rsm-stages``, the
   localizer's timing hook) and instructions per scan (callgrind inside
   ``rsm_localizer_scan``, first scans of every log, default and small
   configuration), in total and by stage; and on the target: instructions per
   scan and per stage of the replay firmware on an emulated Cortex-M4F (QEMU
   mps2-an386, ``-O2``, :mod:`rsm_tools.m4`) beside callgrind's count of the
   same excerpt on the host, with the images' flash, RAM and painted stack.
5. Memory: the localizer state per part on this host (``rsm-stages``) and on
   Cortex-M4F (a cross build per configuration), flash per object, the
   example firmware, the stack of one localizer step.
6. Scaling: time, accuracy and state size against readings per scan, the
   paper's window, the persistent map's tile pool and the shipped presets.
7. The issue's floors, each a PASS or MISS line (a report, not an assertion),
   with the checks that need the full logs (:mod:`rsm_tools.fullchecks`; the
   logs as LD06 and RPLIDAR streams, :mod:`rsm_tools.lidarbench`).
8. Where rsm loses: generated from the numbers above.

Trajectories, summaries and a manifest (``bench.json``) are kept in the work
directory, so that the report can be checked against them; outlier logs are
cached and reused.  ``tools/bench`` sets up, builds ``build-release/`` and
runs this module with the full settings.  Python standard library only;
matplotlib, if installed, draws the plots.
"""

import argparse
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
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from . import evaluate as ev
from . import fullchecks, lidarbench, m4, outliers
from .fullchecks import check

# rsm-nav --method names: rsm is the default method (scan to persistent map),
# paper the paper's (key points + RANSAC against a scrolling window).
METHODS = ("rsm", "paper", "icp", "odometry")
ROBUST_METHODS = ("rsm", "paper", "icp")  # the methods that read the scans
SMALL = "rsm-small"  # rsm built with SMALL_HEADER (a run label, not a method)
SMALL_HEADER = "rsm/config_small.h"
METHOD_LABEL = {"rsm": "rsm", SMALL: "rsm, config_small", "paper": "paper's method", "icp": "icp",
                "odometry": "odometry"}
LEVELS = (0, 10, 20, 30, 43, 50, 60)
QUICK_LEVELS = (0, 43)
OTHER_LEVELS = (0, 43, 60)  # every log but the main one: the floor's level and the peers' second one
QUICK_OTHER_LEVELS = (0, 43)
FIRST_SEED = 7  # the seed of the peers' outlier runs; further seeds count up from it
SEEDS = 2
SPEED_REPEATS = 3
CALLGRIND_SCANS = 1000
LOCAL_SPAN = 2.0
SCOPES = ("local", "all")
QUANTITIES = ("translation", "rotation")
UNITS = {"translation": "m", "rotation": "deg"}
MAIN_LOG = "intel"  # the log the curve, turns, speed and the instruction floor use when present
SECTION_TITLES = (
    "1. Accuracy on the real logs",
    "2. Robustness to outliers",
    "3. Sharp turns (the paper's Fig. 8)",
    "4. Speed",
    "5. Memory",
    "6. Scaling",
    "7. The issue's floors",
    "8. Where rsm loses",
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


SOURCE_GLOBS = ("src/*.[ch]", "include/rsm/*.h", "tools/nav/*.[ch]", "tools/bench-c/*.c", "port/baremetal/*.[ch]",
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


def provenance_line(p: dict) -> str:
    flags = f", `{p['build_flags']}`" if p["build_flags"] else ""
    return (f"Measured {p['date']} on {p['cpu']} ({p['cores']} cores), {p['compiler']}, "
            f"{p['build_type']} build{flags}, commit `{p['commit']}`.")


# ---------------------------------------------------------------------------
# rsm-nav


def load_summary(path: Path) -> dict:
    """rsm-nav's --summary-json: scans, outcome counts, per-scan wall times
    (median_us, p95_us); for the persistent-map method also its tiles
    (tmap) and recovery searches (recovery)."""
    try:
        out = json.loads(Path(path).read_text())
    except (OSError, ValueError) as e:
        raise BenchError(f"rsm-nav wrote no readable summary {path}: {e}") from e
    out.setdefault("tmap", None)
    out.setdefault("recovery", None)
    if not isinstance(out.get("scans"), int) or "median_us" not in out:
        raise BenchError(f"rsm-nav's summary {path} lacks scans or times")
    return out


def fused_percent(summary: dict) -> float:
    s = summary["scans"] or 0
    return 100.0 * summary["outcomes"].get("accepted", 0) / s if s else float("nan")


def run_nav(nav: Path, log: Path, method: str, traj: Path, prefix: Sequence[str] = ()) -> dict:
    """Runs rsm-nav (optionally under a wrapper such as valgrind); returns its
    summary text, the summary it wrote as JSON (``parsed``, see
    load_summary) and the wall time of the whole process."""
    traj.parent.mkdir(parents=True, exist_ok=True)
    summary = traj.with_suffix(".summary.json")
    cmd = [*prefix, str(nav), "--carmen", str(log), "--method", method,
           "--trajectory", str(traj), "--summary-json", str(summary), "--quiet"]
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
    tasks = []
    for label, log, _ in logs:
        tasks += [(label, log, m, m, navs["default"]) for m in METHODS]
        if navs.get("small") is not None:
            tasks.append((label, log, SMALL, "rsm", navs["small"]))

    def one(task):
        label, log, run_label, m, nav = task
        traj = work / "accuracy" / label / f"{run_label}.txt"
        return task, traj, run_nav(nav, log, m, traj)

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
        out[label] = {"log": str(log), "relations": str(rel), "relation_count": len(relations), "runs": runs}
    return out


def run_labels(acc_log: dict) -> List[str]:
    """The runs of one log in report order."""
    order = ("rsm", SMALL, "paper", "icp", "odometry")
    return [k for k in order if k in acc_log["runs"]]


# ---------------------------------------------------------------------------
# peers (docs/reference/peers.md)

PEER_COLUMNS = (("all", "translation"), ("all", "rotation"), ("local", "translation"), ("local", "rotation"))


def md_tables(text: str) -> List[dict]:
    """Every Markdown table of a text: the heading it sits under, its header
    cells and its rows (cells stripped, bold marks removed)."""
    out = []
    heading = ""
    cur = None
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("#"):
            heading = s.lstrip("#").strip()
        if s.startswith("|") and s.endswith("|"):
            cells = [c.strip().replace("**", "").strip() for c in s[1:-1].split("|")]
            if cur is None:
                cur = {"heading": heading, "header": cells, "rows": []}
                out.append(cur)
            elif all(set(c) <= set("-: ") and c for c in cells):
                continue
            else:
                cur["rows"].append(cells)
        else:
            cur = None
    return out


def _number(cell: str) -> Optional[float]:
    m = re.match(r"^[-+]?\d+(?:\.\d+)?$", cell.replace(" ", ""))
    return float(m.group(0)) if m else None


def peer_kind(method: str) -> str:
    """odometry (odometry alone), before (an earlier rsm, "rsm (commit ...)") or peer."""
    low = method.lower()
    if low.startswith("odometry"):
        return "odometry"
    if re.match(r"^rsm\b", low):
        return "before"
    return "peer"


def parse_peers(text: str) -> dict:
    """The table "Accuracy" of peers.md: per log, its rows in file order, each
    with the method, its kind (peer_kind), the four figures by (scope,
    quantity) (None where the cell holds no number) and the text of any cell
    that is not a number (e.g. "diverges ..."). Also the date line, if any."""
    acc = None
    for t in md_tables(text):
        if t["heading"].lower().startswith("accuracy"):
            acc = t
            break
    if acc is None:
        raise BenchError("peers.md has no table under a heading \"Accuracy\"")
    head = [h.lower() for h in acc["header"]]
    try:
        i_log, i_method = head.index("log"), head.index("method")
        cols = {key: head.index(f"{key[0]} {key[1]}") for key in PEER_COLUMNS}
    except ValueError:
        raise BenchError(f"peers.md: unexpected header of the accuracy table: {acc['header']}") from None
    logs: Dict[str, List[dict]] = {}
    for row in acc["rows"]:
        row = row + [""] * (len(head) - len(row))
        values = {key: _number(row[i]) for key, i in cols.items()}
        notes = [row[i] for i in cols.values() if row[i] and _number(row[i]) is None]
        logs.setdefault(row[i_log], []).append({"method": row[i_method], "kind": peer_kind(row[i_method]),
                                                "values": values, "note": "; ".join(notes)})
    m = re.search(r"measured (\d{4}-\d\d-\d\d)", text)
    return {"accuracy": logs, "measured": m.group(1) if m else None}


def best_peers(rows: Sequence[dict]) -> Dict[Tuple[str, str], Optional[Tuple[float, str]]]:
    """Per (scope, quantity): the lowest figure among the peer rows (not
    odometry alone, not the earlier rsm) and whose it is; None if no peer has one."""
    out: Dict[Tuple[str, str], Optional[Tuple[float, str]]] = {}
    for key in PEER_COLUMNS:
        vals = [(r["values"][key], r["method"]) for r in rows
                if r["kind"] == "peer" and r["values"].get(key) is not None]
        out[key] = min(vals, key=lambda v: v[0]) if vals else None
    return out


def load_peers(path: Path) -> dict:
    if not path.is_file():
        return {"skipped": f"{path.name} is not on this machine", "path": str(path)}
    out = parse_peers(path.read_text(encoding="utf-8", errors="replace"))
    out["path"] = str(path)
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
    vals = [v for v in values if v is not None and math.isfinite(v)]
    if not vals:
        return {"mean": float("nan"), "min": float("nan"), "max": float("nan"), "n": 0}
    return {"mean": math.fsum(vals) / len(vals), "min": min(vals), "max": max(vals), "n": len(vals)}


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


_CG_TOTALS = re.compile(r"^(?:totals|summary):\s+(\d+)", re.M)


def callgrind_ir(out_file: Path) -> int:
    m = _CG_TOTALS.search(out_file.read_text(errors="replace"))
    if not m:
        raise BenchError(f"no totals in callgrind output {out_file}")
    return int(m.group(1))


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
    helpers = static_functions((root / "src" / "localizer.c").read_text()) if root else []
    heads = {}
    for label, log, _ in logs:
        head = work / "callgrind" / f"{label}-head{scans}.clf.gz"
        heads[label] = {"log": str(head), "source": str(log), "scans": write_head(log, head, scans)}
    tasks = [(label, "default", m, navs["default"]) for label, _, _ in logs for m in methods]
    if navs.get("small") is not None:
        tasks += [(label, "small", "rsm", navs["small"]) for label, _, _ in logs]

    def one(task):
        label, config, m, nav = task
        out = work / "callgrind" / f"{label}-{config}-{m}.callgrind.out"
        traj = work / "callgrind" / f"{label}-{config}-{m}.txt"
        out.parent.mkdir(parents=True, exist_ok=True)
        prefix = [valgrind, "--tool=callgrind", "--toggle-collect=rsm_localizer_scan",
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


def cg_run(cg: Optional[dict], label: str, config: str, method: str) -> Optional[dict]:
    """One callgrind run of run_callgrind's result, or None."""
    if not cg or "skipped" in cg:
        return None
    return cg["runs"].get(f"{label}:{config}:{method}")


# ---------------------------------------------------------------------------
# section 4: memory

# The parts of rsm_localizer_t in the report: (label, key of rsm-stages'
# "sizes", depth). Depth 0 parts tile the struct (the rest is the config
# pointer, stamps and padding); the methods' states share one union.
HOST_PARTS = (
    ("ekf", "ekf", 0),
    ("odo", "odo", 0),
    ("state (union of the three below)", "state", 0),
    ("state.persistent (rsm)", "state.persistent", 1),
    ("map.tile[] (tile pool)", "state.persistent.map.tile", 2),
    ("map.hash[] (tile index)", "state.persistent.map.hash", 2),
    ("state.paper (the paper's method)", "state.paper", 1),
    ("map (scrolling window)", "state.paper.map", 2),
    ("image", "state.paper.image", 2),
    ("ransac", "state.paper.ransac", 2),
    ("visited + harris + cands", "state.paper.harris", 2),
    ("key points and their points", "state.paper.keypoints", 2),
    ("matches", "state.paper.matches", 2),
    ("state.icp (icp)", "state.icp", 1),
    ("pts + world (the scan's points)", "points", 0),
    ("counters", "counters", 0),
    ("last report", "last", 0),
)
MEMORY_TILES = ("ekf", "odo", "state", "points", "counters", "last")
MEMORY_OTHER = ("rsm_localizer_config_t", "rsm_scan_t")


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


STAGES = ("points", "mapmatch", "grid", "harris", "match", "ransac", "refine", "icp", "ekf", "map")
STAGE_WHAT = {
    "points": "readings -> robot-frame points",
    "mapmatch": "coarse-to-fine alignment to the persistent map (rsm)",
    "grid": "map recentred, points -> scan image",
    "harris": "key points of scan and map",
    "match": "tentative matches",
    "ransac": "two-point RANSAC",
    "refine": "sub-cell alignment to the map",
    "icp": "ICP alignment (baseline)",
    "ekf": "measurement noise, gate, update",
    "map": "scan written into the map (rsm: every 0.4 m / 0.5 rad)",
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
    r_ = out["methods"]["rsm"]["timing"]["call"]
    for key in ("median", "p95", "mean"):
        out[f"ratio_{key}"] = {m: ratio(out["methods"][m]["timing"]["call"][f"{key}_us"], r_[f"{key}_us"])
                               for m in ROBUST_METHODS}
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
    "rsm_mapmatch": "mapmatch",
    "rsm_mapmatch_search": "mapmatch",
    "rsm_tmap_update": "map",
    "rsm_pose_between": "map",
    "rsm_pose_apply": "map",
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
CG_STAGE_ORDER = ("points", "mapmatch", "grid", "grid + map", "harris", "match", "ransac", "refine", "icp", "ekf",
                  "map", "other", "localizer")


def callee_costs(cg: dict, fn: str) -> dict:
    """Inclusive instructions of every function ``fn`` calls (by base name)
    and ``fn``'s own, to split one stage's function further."""
    callees: Dict[str, int] = {}
    for (caller, callee), (_, ir) in cg["calls"].items():
        if base_name(caller) == fn and base_name(callee) != fn:
            callees[base_name(callee)] = callees.get(base_name(callee), 0) + ir
    own = sum(c for f, c in cg["self"].items() if base_name(f) == fn)
    return {"own": own, "callees": callees, "total": own + sum(callees.values())}


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


# ---------------------------------------------------------------------------
# Cortex-M4F memory per module and configuration; static stack bound


# (name, RSM_USER_CONFIG on the library's include path; None: config.h's defaults)
ARM_CONFIGS = (("default", None), ("small", SMALL_HEADER))
ARM_CPU = ("-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard")
# Caller-owned state per module: (module, label, C expression); the localizer's
# parts are members of rsm_localizer_t, which also holds the reports. Labels
# indented by two spaces are parts of the localizer, by four parts of a part.
STATE_SIZES = (
    ("localizer.c", "rsm_localizer_t (all of the below)", "sizeof(rsm_localizer_t)"),
    ("ekf.c", "  ekf", "sizeof(((rsm_localizer_t *)0)->ekf)"),
    ("odometry.c", "  odo", "sizeof(((rsm_localizer_t *)0)->odo)"),
    ("localizer.c", "  state (union: one method's state)", "sizeof(((rsm_localizer_t *)0)->state)"),
    ("tilemap.c", "    state.persistent (rsm)", "sizeof(((rsm_localizer_t *)0)->state.persistent)"),
    ("tilemap.c", "      map.tile[] (tile pool)", "sizeof(((rsm_localizer_t *)0)->state.persistent.map.tile)"),
    ("tilemap.c", "      map.hash[] (tile index)", "sizeof(((rsm_localizer_t *)0)->state.persistent.map.hash)"),
    ("map.c", "    state.paper (the paper's method)", "sizeof(((rsm_localizer_t *)0)->state.paper)"),
    ("map.c", "      map (scrolling window)", "sizeof(((rsm_localizer_t *)0)->state.paper.map)"),
    ("grid.c", "      image", "sizeof(((rsm_localizer_t *)0)->state.paper.image)"),
    ("ransac.c", "      ransac", "sizeof(((rsm_localizer_t *)0)->state.paper.ransac)"),
    ("harris.c", "      visited + harris + cands",
     "sizeof(((rsm_localizer_t *)0)->state.paper.visited) + sizeof(((rsm_localizer_t *)0)->state.paper.harris)"
     " + sizeof(((rsm_localizer_t *)0)->state.paper.cands)"),
    ("match.c", "      key points and matches",
     "sizeof(((rsm_localizer_t *)0)->state.paper.kp_cur) * 2 + sizeof(((rsm_localizer_t *)0)->state.paper.pt_cur) * 2"
     " + sizeof(((rsm_localizer_t *)0)->state.paper.matches)"),
    ("icp.c", "    state.icp (icp)", "sizeof(((rsm_localizer_t *)0)->state.icp)"),
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
    return [f"-DRSM_USER_CONFIG={header}"] if header else []  # found on the include path


M4_TARGETS = ("rsm_firmware", "rsm_replay_m4")


def _arm_size(elf: Path) -> dict:
    """Berkeley sizes of an image: flash = text + data, RAM = data + bss (stack included)."""
    res = subprocess.run(["arm-none-eabi-size", str(elf)], capture_output=True, text=True)
    vals = res.stdout.splitlines()[-1].split() if res.returncode == 0 and res.stdout.strip() else []
    if len(vals) < 3:
        raise BenchError(f"arm-none-eabi-size {elf} gave no sizes: {res.stderr}")
    text, data, bss = (int(v) for v in vals[:3])
    return {"text": text, "data": data, "bss": bss, "flash": text + data, "ram": data + bss}


def _symbol_bytes(elf: Path, names: Sequence[str]) -> int:
    res = subprocess.run(["arm-none-eabi-nm", "-S", str(elf)], capture_output=True, text=True)
    return sum(int(f[1], 16) for f in (l.split() for l in res.stdout.splitlines())
               if len(f) == 4 and f[3] in names)


def run_m4(root: Path, work: Path, replay_host: Optional[Path]) -> dict:
    """The firmware images cross-built at -O2 and run under QEMU (mps2-an386):
    instructions per scan and per stage of the replay firmware on the shipped
    excerpt, the known-loop calibration, each image's flash, RAM and painted
    stack; and callgrind's count of the same excerpt through the same source
    on the host (rsm-replay-host), when valgrind is there."""
    for tool in ("arm-none-eabi-gcc", "arm-none-eabi-size", "arm-none-eabi-nm", "qemu-system-arm", "cmake",
                 "ninja"):
        if shutil.which(tool) is None:
            return {"skipped": f"{tool} is not installed"}
    b = work / "m4-O2"
    cmd = ["cmake", "-S", str(root), "-B", str(b), "-G", "Ninja",
           f"-DCMAKE_TOOLCHAIN_FILE={root / 'cmake' / 'toolchain-arm-none-eabi.cmake'}",
           "-DCMAKE_BUILD_TYPE=Release", "-DCMAKE_C_FLAGS_RELEASE=-O2 -DNDEBUG"]
    for c in (cmd, ["cmake", "--build", str(b), "--parallel", "2", "--target", *M4_TARGETS]):
        res = subprocess.run(c, capture_output=True, text=True)
        if res.returncode != 0:
            raise BenchError(f"{' '.join(c)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")
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
               "icount_shift": m4.ICOUNT_SHIFT, "cost": cost, "images": images}
    valgrind = shutil.which("valgrind")
    if replay_host is None or not replay_host.is_file():
        res_out["host"] = {"skipped": "rsm-replay-host was not built"}
    elif valgrind is None:
        res_out["host"] = {"skipped": "valgrind is not installed"}
    else:
        cg_out = work / "m4-host.callgrind.out"
        r = subprocess.run([valgrind, "--tool=callgrind", "--toggle-collect=rsm_localizer_scan",
                            f"--callgrind-out-file={cg_out}", str(replay_host)], capture_output=True, text=True)
        if r.returncode != 0:
            raise BenchError(f"callgrind of {replay_host} failed: {r.stderr[-2000:]}")
        host_p = [l for l in r.stdout.splitlines() if l.startswith("P ")]
        target_p = [l for l in out.splitlines() if l.startswith("P ")]
        ir = callgrind_ir(cg_out)
        res_out["host"] = {"ir": ir, "scans": len(host_p), "ir_per_scan": ir / max(1, len(host_p)),
                           "identical": host_p == target_p}
    return res_out


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
    for name, im in m["images"].items():
        stack = ("n/a" if im["stack_used"] is None else f"{fmt_int(im['stack_used'])} of {fmt_int(im['stack_size'])}")
        extra = f" (of which the excerpt {fmt_int(im['excerpt'])})" if im["excerpt"] else ""
        L.append(f"{name} image: flash {fmt_int(im['flash'])} bytes{extra}, RAM {fmt_int(im['ram'])} bytes "
                 f"(stack included), stack used {stack} bytes")
    return L


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
    return L


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

    core = [f for f in sorted((root / "src").glob("*.c")) if f.stem not in DRIVER_OBJECTS]
    for src, res in parallel(compile_one, core, jobs):
        if res.returncode != 0:
            return {"skipped": f"compiling {src.name} with -fcallgraph-info failed: "
                               + (res.stderr.strip().splitlines() or ["?"])[-1]}
    graph = read_callgraph_dir(d)
    return {"flags": " ".join(flags), "compiler": first_line([cc, "--version"]) or cc,
            "stack": stack_bounds(graph)}


# ---------------------------------------------------------------------------
# scaling: readings per scan, the paper's window, the tile pool, presets


SCALING_BEAMS = (181, 361, 721)
SCALING_MAP_LOG2 = (6, 7, 8)
SCALING_TILES = (600, 1200, 2600)
DEFAULT_MAX_BEAMS = 361
DEFAULT_MAP_LOG2 = 7
DEFAULT_TILES = 2600
# Shipped configuration presets (include paths) run as they are.
SCALING_PRESETS = (SMALL_HEADER, "rsm/config_host.h")
# The methods a kind of variant concerns: the window sizes only the paper's
# method, the tile pool only rsm's.
KIND_METHODS = {"beams": ROBUST_METHODS, "map": ("paper",), "tiles": ("rsm",), "preset": ("rsm", "paper")}


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


def configure_build(root: Path, b: Path, main_build: Path, header, targets: Sequence[str]) -> None:
    """A Release build of ``targets`` in ``b`` with RSM_USER_CONFIG=header, with
    the main build's compiler and warning settings."""
    cache = cmake_cache(main_build)
    cmd = ["cmake", "-S", str(root), "-B", str(b), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
           "-DRSM_BUILD_TESTS=OFF", f"-DRSM_USER_CONFIG={header}"]
    if cache.get("CMAKE_C_COMPILER"):
        cmd.append(f"-DCMAKE_C_COMPILER={cache['CMAKE_C_COMPILER']}")
    if cache.get("RSM_WERROR"):
        cmd.append(f"-DRSM_WERROR={cache['RSM_WERROR']}")
    for c in (cmd, ["cmake", "--build", str(b), "--target", *targets]):
        res = subprocess.run(c, capture_output=True, text=True)
        if res.returncode != 0:
            raise BenchError(f"{' '.join(c)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")


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


# ---------------------------------------------------------------------------
# plot


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


# ---------------------------------------------------------------------------
# section 7: the issue's floors (a report, not an assertion)

FLOOR_LEVEL = 43
FLOOR_ROBUST = {"local": 1.10, "all": 1.25}  # outlier error over the clean one, translation
FLOOR_ARM_BYTES = {"default": 128 * 1024, "small": 64 * 1024}
FLOOR_IR_PER_SCAN = 1.2e6
PEER_FLOORS = (("all", "translation"), ("local", "translation"), ("local", "rotation"))
# The figures the issue names (from the shorter peer table it quotes); peers.md
# lists more peer variants, some lower, and both are checked.
ISSUE_FLOORS = {
    "intel": {("all", "translation"): 0.102, ("local", "translation"): 0.0133, ("local", "rotation"): 0.26},
    "aces": {("all", "translation"): 0.076, ("local", "translation"): 0.040, ("local", "rotation"): 0.43},
}


def _scope_name(scope: str) -> str:
    return "all-relations" if scope == "all" else "local"


def _floor(status: str, kind: str, log: Optional[str], value, limit, text: str) -> dict:
    return {"status": status, "kind": kind, "log": log, "value": value, "limit": limit,
            "line": f"{status} {text}"}


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
                out.append(_floor("SKIP", "peers", log, mine, None, f"{what}: no peer figures (peers.md is not "
                                                                      "on this machine)"))
            elif b is None:
                out.append(_floor("SKIP", "peers", log, mine, None, f"{what}: peers.md has no peer figure "
                                                                      "for this log"))
            else:
                ok = mine <= b[0]
                out.append(_floor("PASS" if ok else "MISS", "peers", log, mine, b[0],
                                  f"{what} {'<=' if ok else '>'} {fmt_q(q, b[0])} {u}, the best peer's ({b[1]})"))
            lim = ISSUE_FLOORS.get(log, {}).get((scope, q))
            if lim is not None:
                ok = mine <= lim
                out.append(_floor("PASS" if ok else "MISS", "issue", log, mine, lim,
                                  f"{what} {'<=' if ok else '>'} {fmt_q(q, lim)} {u}, the issue's floor"))
    for log, r in robust.items():
        seeds = sorted(r["noisy"])
        for scope in SCOPES:
            lim = FLOOR_ROBUST[scope]
            clean = r["clean"][scope]
            what = f"{log}: {FLOOR_LEVEL} % outliers, {_scope_name(scope)} translation"
            if not seeds:
                out.append(_floor("SKIP", "robustness", log, None, lim, f"{what}: not measured"))
                continue
            ratios = [ratio(r["noisy"][sd][scope], clean) for sd in seeds]
            ok = all(math.isfinite(x) and x <= lim for x in ratios)
            shown = ", ".join(f"{fmt_q('translation', r['noisy'][sd][scope])} m = x{x:.3f} (seed {sd})"
                              for sd, x in zip(seeds, ratios))
            out.append(_floor("PASS" if ok else "MISS", "robustness", log, max(ratios), lim,
                              f"{what} {shown} of the clean {fmt_q('translation', clean)} m; "
                              f"{'every' if ok else 'not every'} seed <= x{lim:.2f}"))
    for name, lim in FLOOR_ARM_BYTES.items():
        b = arm_bytes.get(name)
        cfg = "the default config.h" if name == "default" else SMALL_HEADER
        what = f"Cortex-M4F: sizeof(rsm_localizer_t) with {cfg}"
        if b is None:
            out.append(_floor("SKIP", "memory", None, None, lim, f"{what}: not measured"))
        else:
            ok = b <= lim
            out.append(_floor("PASS" if ok else "MISS", "memory", None, b, lim,
                              f"{what} {fmt_int(b)} bytes ({b / 1024:.1f} KiB) {'<=' if ok else '>'} "
                              f"{lim // 1024} KiB"))
    if "skipped" in ir:
        out.append(_floor("SKIP", "instructions", ir.get("log"), None, FLOOR_IR_PER_SCAN,
                          f"instructions per scan: not measured ({ir['skipped']})"))
    else:
        v = ir["ir_per_scan"]
        ok = v <= FLOOR_IR_PER_SCAN
        out.append(_floor("PASS" if ok else "MISS", "instructions", ir["log"], v, FLOOR_IR_PER_SCAN,
                          f"{ir['log']}: {fmt_int(round(v))} instructions per scan (callgrind, first "
                          f"{ir['scans']} scans, default config.h) {'<=' if ok else '>'} "
                          f"{fmt_int(round(FLOOR_IR_PER_SCAN))}"))
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


# ---------------------------------------------------------------------------
# section 8: where rsm loses


def _better(a: float, b: float) -> bool:
    return a is not None and b is not None and math.isfinite(a) and math.isfinite(b) and a < b


_PEER_IR = re.compile(r"([0-9.]+)\s*M\b")


def peer_speed(text: str) -> List[dict]:
    """Rows of peers.md's speed table: method and instructions per scan (None
    where the cell is not "N M")."""
    out = []
    for t in md_tables(text):
        if not t["heading"].lower().startswith("speed"):
            continue
        head = [h.lower() for h in t["header"]]
        i_ir = next((i for i, h in enumerate(head) if h.startswith("instructions")), None)
        for row in t["rows"]:
            m = _PEER_IR.search(row[i_ir]) if i_ir is not None and i_ir < len(row) else None
            out.append({"method": row[0], "kind": peer_kind(row[0]),
                        "ir_per_scan": float(m.group(1)) * 1e6 if m else None})
    return out


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


# ---------------------------------------------------------------------------
# report parts


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
    if st.get("plot"):
        L += [f"![Time per stage, rsm, the paper's method and icp]({st['plot']})", ""]
    elif st.get("plot_note"):
        L += [f"No plot: {st['plot_note']}.", ""]
    return L


def _cg_columns(cg: dict, label: str) -> List[Tuple[str, dict]]:
    """The callgrind runs of one log in report order, with their column names."""
    out = []
    for config, m in (("default", "rsm"), ("small", "rsm"), ("default", "paper"), ("default", "icp")):
        r = cg_run(cg, label, config, m)
        if r is not None:
            out.append((SMALL if config == "small" else m, r))
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
              "count of each function it calls, per scan (include/rsm/mapmatch.h describes the steps: the "
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
    if sc.get("plot"):
        L += [f"![Scaling of time per scan, error and state size]({sc['plot']})", ""]
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
                          f"returns dropped; {rc.get('searches', 0)} recovery searches, {rc.get('taken', 0)} taken")
        if tm:
            L += ["Persistent map at the end of the log (rsm-nav summary): " + "; ".join(tm) + ".", ""]
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
    if ctx.get("plot"):
        L += [f"![Robustness curves on {main}: mean error against the share of outliers, rsm, the paper's method "
              f"and icp, odometry as a reference line]({ctx['plot']})", ""]
    elif ctx.get("plot_note"):
        L += [f"No plot: {ctx['plot_note']}.", ""]
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
    else:
        L += [f"Cortex-M4F sizes (tools/cross-check) not measured: {(xc or {}).get('skipped', 'disabled')}.", ""]
    L += report_arm_memory(am, root)
    L += report_stack(am, ctx.get("host_stack"), ctx.get("stages"), ctx.get("stack_note"))
    return L


def report_floors(ctx: dict) -> List[str]:
    floors = ctx.get("floors") or []
    n = {k: sum(1 for f in floors if f["status"] == k) for k in ("PASS", "MISS", "SKIP")}
    L = ["The floors of issue 10, each checked on this run's figures and printed as PASS or MISS (SKIP: not "
         "measured in this run). They are a report, not an assertion: the bench does not fail on a MISS. Peers: "
         "the lowest figure among the peers of peers.md for that log. Robustness: rsm with "
         f"{FLOOR_LEVEL} % outliers against its own clean run, translation, local <= x{FLOOR_ROBUST['local']:.2f} "
         f"and all relations <= x{FLOOR_ROBUST['all']:.2f}, at every seed. Memory: `sizeof(rsm_localizer_t)` "
         f"from the Cortex-M4F probe of section 5. Instructions: callgrind, section 4. Then the checks that need "
         f"the full logs (`rsm_tools.fullchecks`): the logs against their description in docs/reference, rsm "
         f"against ICP and odometry, a bit-identical rerun, and the capture path (`rsm-convert`, then "
         f"`rsm-nav --capture`) within x{fullchecks.CAPTURE_TOLERANCE:.2f} of the direct run.", "",
         f"{n['PASS']} PASS, {n['MISS']} MISS" + (f", {n['SKIP']} SKIP" if n["SKIP"] else "") + ":", "", "```"]
    L += [f["line"] for f in floors]
    L += ["```", ""]
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
        report_robustness(ctx, root),
        report_turns(ctx.get("turns"), main, root) + (
            [f"![Residuals at the sharpest turns and by true rotation]({ctx['turns_plot']})", ""]
            if ctx.get("turns") and ctx.get("turns_plot") else
            [f"No plot: {ctx['turns_plot_note']}.", ""] if ctx.get("turns_plot_note") else []),
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


def _counts(text: str) -> List[int]:
    try:
        vals = sorted({int(v) for v in text.split(",") if v.strip()})
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of integers: {text!r}") from None
    if not vals or any(v < 1 for v in vals):
        raise argparse.ArgumentTypeError(f"values must be positive: {text!r}")
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
        description="Measure rsm, the paper's method, its ICP baseline and odometry on every log of the shared "
                    "folder (accuracy beside the peers, robustness to outliers, speed, memory, the issue's floors) "
                    "and write docs/RESULTS.md. ./tools/bench builds and runs this.")
    p.add_argument("--root", type=Path, help="repository root (default: found from the current folder)")
    p.add_argument("--build-dir", type=Path, help="build with tools/nav/rsm-nav and tools/bench-c/rsm-stages "
                   "(default: ROOT/build-release)")
    p.add_argument("--shared", type=Path, help="the shared folder: its data/NAME/ folders holding NAME.clf.gz and "
                   "NAME.relations are the logs (default: the environment variable RSM_SHARED_DIR, else "
                   "ROOT/../shared)")
    p.add_argument("--peers", type=Path, help="the peers' figures (default: ROOT/docs/reference/peers.md)")
    p.add_argument("--small-build", type=Path, help=f"a Release build with RSM_USER_CONFIG={SMALL_HEADER} holding "
                   "rsm-nav and rsm-stages (default: the bench builds one in BUILD/bench-small)")
    p.add_argument("--levels", type=_levels, help="outlier percentages on the main log (default: "
                   + ",".join(map(str, LEVELS)) + "; quick: " + ",".join(map(str, QUICK_LEVELS)) + "); the other "
                   "logs run " + ",".join(map(str, OTHER_LEVELS)) + " (quick " + ",".join(map(str, QUICK_OTHER_LEVELS))
                   + ")")
    p.add_argument("--seeds", type=int, help=f"seeds per outlier level, counting from {FIRST_SEED} "
                   f"(default {SEEDS}; quick 1)")
    p.add_argument("--speed-repeats", type=int, help=f"timed runs per method (default {SPEED_REPEATS}; quick 1)")
    p.add_argument("--callgrind-scans", type=int, default=CALLGRIND_SCANS,
                   help=f"scans from the start of every log counted by callgrind (default {CALLGRIND_SCANS})")
    p.add_argument("--jobs", type=int, default=2, help="rsm-nav processes at a time for untimed runs (default 2)")
    p.add_argument("--quick", action="store_true", help="one seed, fewer levels, one speed repeat, callgrind of rsm "
                   "only, no scaling builds")
    p.add_argument("--no-callgrind", action="store_true", help="skip the instruction counts")
    p.add_argument("--no-m4", action="store_true",
                   help="skip the Cortex-M4F images under QEMU (instructions per scan on the target)")
    p.add_argument("--no-cross-check", action="store_true", help="skip tools/cross-check")
    p.add_argument("--no-full-checks", action="store_true", help="skip the checks of rsm_tools.fullchecks (the "
                   "logs against their description, rsm against its baselines, reruns, the capture path)")
    p.add_argument("--no-plots", action="store_true", help="draw no plot")
    p.add_argument("--turns", type=int, default=TURNS, help=f"sharpest turns in the Fig. 8 table (default {TURNS})")
    p.add_argument("--no-stack", action="store_true", help="skip the painted stack measurement")
    p.add_argument("--no-arm-memory", action="store_true", help="skip the per-configuration Cortex-M4F builds")
    p.add_argument("--arm-configs", type=_names, help="Cortex-M4F configurations to build (default "
                   + ",".join(n for n, _ in ARM_CONFIGS) + ")")
    p.add_argument("--no-scaling", action="store_true", help="skip the scaling section")
    p.add_argument("--scaling-beams", type=_levels, help="readings per scan of the scaling runs (default "
                   + ",".join(map(str, SCALING_BEAMS)) + f"; quick {DEFAULT_MAX_BEAMS})")
    p.add_argument("--scaling-maps", type=_levels, help="RSM_MAP_SIZE_LOG2 values of the paper's window (default "
                   + ",".join(map(str, SCALING_MAP_LOG2)) + f"; quick {DEFAULT_MAP_LOG2})")
    p.add_argument("--scaling-tiles", type=_counts, help="RSM_TMAP_TILES values of rsm's tile pool (default "
                   + ",".join(map(str, SCALING_TILES)) + f"; quick {DEFAULT_TILES}); the presets "
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


def _jsonable(o):
    """o with tuple keys (the peers' (scope, quantity)) joined by a space, for the manifest."""
    if isinstance(o, dict):
        return {(" ".join(map(str, k)) if isinstance(k, tuple) else k): _jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_jsonable(v) for v in o]
    return o


def _peer_table(text: str, heading: str) -> Optional[dict]:
    for t in md_tables(text):
        if t["heading"].lower().startswith(heading):
            return {"header": t["header"], "rows": [r + [""] * (len(t["header"]) - len(r)) for r in t["rows"]]}
    return None


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
    shared = shared_dir(args.shared, root)
    data = shared / "data"
    logs = discover_logs(data)
    if not logs:
        raise BenchError(f"no log in {data}: the bench needs the full logs, each a folder NAME holding NAME.clf.gz "
                         "and NAME.relations (set the shared folder with --shared or RSM_SHARED_DIR; see "
                         "docs/reference/README.md)")
    levels = args.levels or (list(QUICK_LEVELS) if args.quick else list(LEVELS))
    if 0 not in levels:
        levels = [0] + levels  # the ratios need the clean figure
    other_levels = list(QUICK_OTHER_LEVELS if args.quick else OTHER_LEVELS)
    nseeds = args.seeds if args.seeds is not None else (1 if args.quick else SEEDS)
    repeats = args.speed_repeats if args.speed_repeats is not None else (1 if args.quick else SPEED_REPEATS)
    if nseeds < 1 or repeats < 1 or args.jobs < 1 or args.callgrind_scans < 1:
        raise BenchError("--seeds, --speed-repeats, --callgrind-scans and --jobs must be at least 1")
    seeds = list(range(FIRST_SEED, FIRST_SEED + nseeds))
    work = (args.work_dir or build / "bench-work").resolve()
    cache = (args.cache_dir or build / "bench-cache").resolve()
    output = (args.output or root / "docs" / "RESULTS.md").resolve()
    plots = (args.plots_dir or root / "docs" / "results").resolve()
    work.mkdir(parents=True, exist_ok=True)
    main_label, main_log, main_rel = logs[0]
    stage_seconds: Dict[str, float] = {}

    def stage(name, fn, *a):
        print(f"rsm-bench: {name} ...", flush=True)
        t0 = time.monotonic()
        res = fn(*a)
        stage_seconds[name] = time.monotonic() - t0
        print(f"rsm-bench: {name} done in {stage_seconds[name]:.1f} s", flush=True)
        return res

    print("rsm-bench: logs " + ", ".join(f"{l} ({shown_path(g, root)})" for l, g, _ in logs), flush=True)
    prov = provenance(root, build)
    digest = source_digest(root)
    ctx = {"root": root, "provenance": prov, "main_label": main_label, "levels": levels,
           "other_levels": other_levels, "seeds": seeds, "speed_repeats": repeats, "jobs": args.jobs,
           "quick": args.quick, "data_dir": str(data)}
    peers_md = (args.peers or root / "docs" / "reference" / "peers.md").resolve()
    ctx["peers"] = load_peers(peers_md)
    if "skipped" in ctx["peers"]:
        print(f"rsm-bench: no peer figures: {ctx['peers']['skipped']} ({peers_md}); the peers are skipped",
              flush=True)
    else:
        text = peers_md.read_text(encoding="utf-8", errors="replace")
        ctx["peer_speed"] = peer_speed(text)
        ctx["peer_speed_table"] = _peer_table(text, "speed")
        ctx["peer_robustness"] = _peer_table(text, "robustness")
    if args.small_build:
        sb = args.small_build.resolve()
        small = {"nav": sb / "tools" / "nav" / "rsm-nav", "stages": stages_exe(sb), "dir": sb}
        for f in (small["nav"], small["stages"]):
            if not f.is_file():
                raise BenchError(f"{f} is missing in the --small-build tree")
    else:
        small = stage("small build", build_small, root, build, build / "bench-small")
    ctx["small_build"] = str(small["dir"])
    navs = {"default": nav, "small": small["nav"]}
    ctx["accuracy"] = stage("accuracy", run_accuracy, navs, logs, work, args.jobs)
    ctx["full_checks"] = ([check(None, "data", None, "full-log checks: not run (--no-full-checks)")]
                          if args.no_full_checks
                          else stage("full-log checks", fullchecks.run_all, shared, nav, logs, work / "full-checks",
                                     root, ctx["accuracy"], not args.quick))
    ctx["lidar_streams"] = stage("lidar streams", lidarbench.run, nav, logs, work / "lidar-streams", ctx["accuracy"])
    ctx["speed"] = stage("speed", run_speed, nav, main_log, repeats, work)
    lv_by_log = {label: (levels if label == main_label else other_levels) for label, _, _ in logs}
    ctx["robustness"] = stage("robustness", run_robustness, nav, logs, ctx["accuracy"], lv_by_log, seeds, work,
                              cache, args.jobs)
    sanitized = cmake_cache(build).get("RSM_SANITIZE", "OFF").upper() in ("ON", "TRUE", "1", "YES")
    painted = not (args.no_stack or sanitized)
    if not painted:
        ctx["stack_note"] = ("--no-stack" if args.no_stack else
                             "the build is instrumented by AddressSanitizer, which moves frames off the stack")
    ctx["stages"] = stage("stages", run_stage_speed, stages_bin, main_log, repeats, painted)
    ctx["turns"] = stage("turns", run_turns, ctx["accuracy"][main_label]["runs"], main_rel,
                         ctx["stages"]["config"]["cell_m"], args.turns)
    cg_methods = ("rsm",) if args.quick else ROBUST_METHODS
    ctx["callgrind"] = ({"skipped": "--no-callgrind"} if args.no_callgrind
                        else stage("callgrind", run_callgrind, navs, logs, args.callgrind_scans, cg_methods, work,
                                   args.jobs, root))
    ctx["m4"] = ({"skipped": "--no-m4"} if args.no_m4
                 else stage("m4", run_m4, root, work, build / "port" / "baremetal" / "rsm-replay-host"))
    ctx["memory"] = stage("memory", run_memory, {"default": stages_bin, "small": small["stages"]}, main_log, build)
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
        tiles = args.scaling_tiles or ([DEFAULT_TILES] if args.quick else list(SCALING_TILES))
        ctx["scaling"] = stage("scaling", run_scaling, root, build, main_log, main_rel, work,
                               scaling_variants(beams, maps, tiles, () if args.quick else SCALING_PRESETS),
                               {SMALL_HEADER: small["stages"]})
    if args.no_plots:
        ctx["plot_note"] = ctx["turns_plot_note"] = ctx["stages"]["plot_note"] = "--no-plots"
        if ctx.get("scaling"):
            ctx["scaling"]["plot_note"] = "--no-plots"
    else:
        png = plots / "robustness.png"
        note = plot_robustness(ctx["robustness"]["logs"][main_label], png, prov,
                               ctx["accuracy"][main_label]["runs"]["odometry"]["errors"], main_label)
        if note:
            ctx["plot_note"] = note
        else:
            ctx["plot"] = os.path.relpath(png, output.parent).replace(os.sep, "/")
        for key, fn, name, target in (("turns", plot_turns, "turns.png", ctx),
                                      ("stages", plot_stages, "stages.png", ctx["stages"]),
                                      ("scaling", plot_scaling, "scaling.png", ctx.get("scaling"))):
            if not ctx.get(key):
                continue
            png = plots / name
            note = fn(ctx[key], png, prov)
            prefix = "turns_" if key == "turns" else ""
            if note:
                target[f"{prefix}plot_note"] = note
            else:
                target[f"{prefix}plot"] = os.path.relpath(png, output.parent).replace(os.sep, "/")
    if source_digest(root) != digest:
        ctx["sources_changed"] = ("the library's or the tools' sources changed while this run was measuring, so "
                                  "its figures may come from different code: run it again")
        print(f"rsm-bench: WARNING: {ctx['sources_changed']}", flush=True)
    ctx["floors"] = check_floors(**floor_inputs(ctx)) + ctx["full_checks"] + ctx["lidar_streams"]
    ctx["losses"] = losses(ctx)
    ctx["elapsed"] = time.monotonic() - t_start
    ctx["stage_seconds"] = stage_seconds
    text = write_report(ctx)
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(text, encoding="utf-8")
    manifest = {k: v for k, v in ctx.items() if k != "root"}
    manifest["report"] = str(output)
    manifest["logs"] = [{"label": l, "log": str(g), "relations": str(r)} for l, g, r in logs]
    (work / "bench.json").write_text(json.dumps(_jsonable(manifest), indent=1, default=_json_default,
                                                allow_nan=True))
    print("rsm-bench: on the target:")
    for line in m4_lines(ctx.get("m4")):
        print(f"  {line}")
    print("rsm-bench: the issue's floors:")
    for f in ctx["floors"]:
        print(f"  {f['line']}")
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
