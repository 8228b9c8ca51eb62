"""Parsers of what the measured programs print and of peers.md (callgrind, cross-check, nm/size, call graphs,
rsm-nav's JSON summary), and the analyses that only read their results."""

import json
import re
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from .common import BenchError, CHECKED, INDIRECT_TARGETS, PEER_COLUMNS, SCAN_SYMBOL, STACK_ROOTS


def load_summary(path: Path) -> dict:
    """rsm-nav's --summary-json: scans, outcome counts, per-scan wall times
    (median_us, p95_us); for the persistent-map method also its tiles
    (tmap), recovery searches (recovery) and the matches unpinned along a
    corridor (unpinned)."""
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


_CG_TOTALS = re.compile(r"^(?:totals|summary):\s+(\d+)", re.M)


def callgrind_ir(out_file: Path) -> int:
    m = _CG_TOTALS.search(out_file.read_text(errors="replace"))
    if not m:
        raise BenchError(f"no totals in callgrind output {out_file}")
    return int(m.group(1))


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


def localizer_breakdown(cg: dict, helpers: Iterable[str], root: str = SCAN_SYMBOL) -> dict:
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
        g for g in breakdown["group"] if g != SCAN_SYMBOL]}
    for row in out.values():
        row["ir_per_scan"] = row["ir"] / scans if scans else float("nan")
        row["functions"] = sorted(set(row["functions"]))
    return out


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
    out = {}
    for fn in STACK_ROOTS:
        # A root the API gives as a macro is the function it calls.
        sym = fn + CHECKED if fn + CHECKED in names else fn
        if sym in names:
            out[fn] = worst_stack_path(graph, sym, INDIRECT_TARGETS)
    return out


def read_callgraph_dir(d: Path) -> dict:
    files = sorted(d.rglob("*.ci"))
    if not files:
        raise BenchError(f"no -fcallgraph-info output under {d}")
    return parse_callgraph_info(f.read_text(errors="replace") for f in files)


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


def _peer_table(text: str, heading: str) -> Optional[dict]:
    for t in md_tables(text):
        if t["heading"].lower().startswith(heading):
            return {"header": t["header"], "rows": [r + [""] * (len(t["header"]) - len(r)) for r in t["rows"]]}
    return None
