"""What a scan costs on the M4 on the full logs, under QEMU (mps2-an386,
``-icount``): the bench's check of the cost floors where the shipped
excerpt cannot show them.

- ``global``: the map-in-flash image (port/baremetal/mapflash/) searching a
  saved map (a pool-sized one: ``rsm-nav --save-map`` without a tile store)
  globally from a point of a log. The image is built with its input cut
  from the log (``RSM_REPLAY_LOG``) and the map put into its flash region
  by QEMU's loader, so that its first boot loads it; it localizes one scan
  and then searches from the next, each scan timed. Figures: the
  instructions of every scan of the search (``rsm_localizer_scan``).
- ``replay``: the replay image (port/baremetal/replay/) on a log's first
  scans: every scan's instructions and stages, the scan whose map matching
  cost most, and the costliest of the scans a tracking recovery took (the
  image's R lines: the scan that began one, those its search and proof
  were spread over, the scan it placed).

    python3 -m rsm_tools.m4cost global LOG MAP --offset S [--scans N] --work DIR
    python3 -m rsm_tools.m4cost replay LOG [--scans N] --work DIR

Needs arm-none-eabi-gcc, cmake, ninja and qemu-system-arm (./tools/test
installs them). Each call cross-builds its image (about half a minute).
"""

import argparse
import gzip
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Dict, List, Optional, Sequence

from . import m4

ROOT = Path(__file__).resolve().parents[2]
TOOLCHAIN = "toolchain-arm-none-eabi.cmake"
FLOOR = 1_000_000  # instructions a scan (issues 29 and 31)
# The map-in-flash image's phases for a search from a log's point: one
# scan localized from the saved pose (the first boot loads the map put
# into its region), then the search from the scan after it.
GLOBAL_DEFINES = ("RSM_MAPFLASH_MAP_SCANS=1u", "RSM_MAPFLASH_LOC_SCANS=0u", "RSM_MAPFLASH_GLOBAL_FROM=2u")


class M4CostError(RuntimeError):
    pass


def cut_log(src: Path, out: Path, offset_s: float, scans: int) -> int:
    """The FLASER and ODOM lines of src from offset_s seconds after its
    first one on, up to `scans` scans, into out; returns the scans."""
    opener = gzip.open if str(src).endswith(".gz") else open
    t0: Optional[float] = None
    n = 0
    lines: List[str] = []
    with opener(src, "rt") as f:
        for line in f:
            fields = line.split()
            if not fields or fields[0] not in ("FLASER", "ODOM"):
                continue
            stamp = float(fields[-3])
            t0 = stamp if t0 is None else t0
            if stamp < t0 + offset_s:
                continue
            lines.append(line)
            if fields[0] == "FLASER":
                n += 1
                if n >= scans:
                    break
    out.write_text("".join(lines))
    return n


def build(build_dir: Path, target: str, log: Path, defines: Sequence[str] = ()) -> Path:
    """The image `target` cross-built at -O2 with its input from log; its ELF."""
    flags = " ".join(["-O2", "-DNDEBUG"] + [f"-D{d}" for d in defines])
    cmds = [["cmake", "-S", str(ROOT), "-B", str(build_dir), "-G", "Ninja",
             f"-DCMAKE_TOOLCHAIN_FILE={ROOT / 'cmake' / TOOLCHAIN}", "-DCMAKE_BUILD_TYPE=Release",
             f"-DCMAKE_C_FLAGS_RELEASE={flags}", f"-DRSM_REPLAY_LOG={log}"],
            ["cmake", "--build", str(build_dir), "--parallel", "2", "--target", target]]
    for c in cmds:
        res = subprocess.run(c, capture_output=True, text=True)
        if res.returncode != 0:
            raise M4CostError(f"{' '.join(c)} failed:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}")
    return build_dir / "port" / "baremetal" / f"{target}.elf"


def global_cost(log: Path, map_file: Path, offset_s: float, scans: int, work: Path) -> Dict[str, object]:
    """The map-in-flash image's global search in map_file from offset_s
    seconds into log, at most `scans` scans: its figures (m4.global_costs)
    and every scan's (scan, outcome, search work, instructions)."""
    work.mkdir(parents=True, exist_ok=True)
    cut = work / "input.clf"
    if cut_log(log, cut, offset_s, scans + 2) < 3:
        raise M4CostError(f"{log}: fewer than 3 scans after {offset_s} s")
    defines = GLOBAL_DEFINES + (f"RSM_MAPFLASH_GLOBAL_SCANS={scans}u",)
    elf = build(work / "build", "rsm_mapflash_m4", cut, defines)
    # The region is the image's own (zeroed at load): without it, QEMU's
    # loader puts the map there and the first boot finds it.
    bare = work / "mapflash-bare.elf"
    res = subprocess.run(["arm-none-eabi-objcopy", "--remove-section", ".mapflash", str(elf), str(bare)],
                         capture_output=True, text=True)
    if res.returncode != 0:
        raise M4CostError(f"objcopy: {res.stderr}")
    region = subprocess.run(["arm-none-eabi-nm", str(elf)], capture_output=True, text=True).stdout
    addr = next((l.split()[0] for l in region.splitlines() if l.endswith(" rsm_mapflash_words")), None)
    if addr is None:
        raise M4CostError(f"{elf.name}: no rsm_mapflash_words")
    cmd = m4.qemu_command(bare) + ["-device", f"loader,file={map_file},addr=0x{addr},force-raw=on"]
    out = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, timeout=m4.TIMEOUT_S)
    text = out.stdout.decode(errors="replace")
    (work / "mapflash-m4.out").write_text(text)
    if out.returncode != 0 or "FAULT" in text or "L loaded" not in text:
        raise M4CostError(f"{bare.name}: exit {out.returncode}, no map loaded or a fault:\n{text[-2000:]}")
    m4.calibration(text)
    search = m4.global_search(text)
    figures = m4.global_costs(search)
    figures["rows"] = [(r[0], r[1], r[2], r[3] * m4.INSNS_PER_TICK) for r in search["rows"]]
    return figures


def replay_cost(log: Path, scans: int, work: Path) -> Dict[str, object]:
    """The replay image on log's first `scans` scans: m4.costs' figures and
    the scan whose map matching (stage mapmatch) cost most: (scan, its
    instructions, its map matching's)."""
    work.mkdir(parents=True, exist_ok=True)
    cut = work / "input.clf"
    cut_log(log, cut, 0.0, scans)
    elf = build(work / "build", "rsm_replay_m4", cut)
    text = m4.run(elf)
    (work / "replay-m4.out").write_text(text)
    c = m4.costs(text)
    mm = m4.STAGES.index("mapmatch")
    rows = [(int(r[0]), (int(r[1]) + int(r[-1])) * m4.INSNS_PER_TICK, int(r[2 + mm]) * m4.INSNS_PER_TICK)
            for r in m4.lines_of(text, "T")]
    worst = max(rows, key=lambda r: r[2])
    c["matching_worst"] = {"scan": worst[0], "insns": worst[1], "mapmatch": worst[2]}
    # The scans a tracking recovery took (R lines: the one that began it,
    # those its search and proof were spread over, the one it placed).
    took = {int(r[0]) for r in m4.lines_of(text, "R")}
    rec = [r for r in rows if r[0] in took]
    c["recovery_scans"] = len(rec)
    c["recovery_worst"] = None
    if rec:
        w = max(rec, key=lambda r: r[1])
        c["recovery_worst"] = {"scan": w[0], "insns": w[1], "mapmatch": w[2]}
    return c


def tools_missing() -> Optional[str]:
    for tool in ("arm-none-eabi-gcc", "arm-none-eabi-objcopy", "arm-none-eabi-nm", "qemu-system-arm", "cmake",
                 "ninja"):
        if shutil.which(tool) is None:
            return f"{tool} is not installed"
    return None


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-m4cost", description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    g = sub.add_parser("global", help="a global search in a saved map from a point of a log")
    g.add_argument("log", type=Path)
    g.add_argument("map", type=Path)
    g.add_argument("--offset", type=float, required=True, help="seconds into the log")
    g.add_argument("--scans", type=int, default=60)
    g.add_argument("--work", type=Path, required=True)
    r = sub.add_parser("replay", help="the replay image on a log's first scans")
    r.add_argument("log", type=Path)
    r.add_argument("--scans", type=int, default=600)
    r.add_argument("--work", type=Path, required=True)
    a = ap.parse_args(argv)
    missing = tools_missing()
    if missing:
        print(f"rsm-m4cost: {missing}", file=sys.stderr)
        return 2
    try:
        if a.what == "global":
            f = global_cost(a.log, a.map, a.offset, a.scans, a.work)
            for scan, outcome, w, insns in f["rows"]:
                print(f"scan {scan} outcome {outcome} work {w} instructions {insns:.0f}")
            print(f"worst {f['max']:.0f} mean {f['mean']:.0f} over {f['scans']} scans; proven {f['proven']}; "
                  f"floor {FLOOR}: {'met' if f['max'] <= FLOOR else 'MISSED'}")
        else:
            c = replay_cost(a.log, a.scans, a.work)
            w = c["matching_worst"]
            print(m4.format_costs(c))
            print(f"costliest matching: scan {w['scan']}, {w['insns']:.0f} instructions "
                  f"({w['mapmatch']:.0f} matching)")
            r = c["recovery_worst"]
            if r is None:
                print("no tracking recovery in these scans")
            else:
                print(f"tracking recoveries: {c['recovery_scans']} scans; the costliest, scan {r['scan']}: "
                      f"{r['insns']:.0f} instructions ({r['mapmatch']:.0f} matching); floor {FLOOR}: "
                      f"{'met' if r['insns'] <= FLOOR else 'MISSED'}")
    except (M4CostError, m4.M4Error, subprocess.TimeoutExpired) as e:
        print(f"rsm-m4cost: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
