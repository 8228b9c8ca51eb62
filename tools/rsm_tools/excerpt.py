"""Cut a CARMEN log, and its ground truth, to a number of scans or a time window.

Two ways to choose what is kept:

``--first-scans N``
    The log is cut right after its N-th scan line (FLASER or ROBOTLASER1,
    counting well-formed ones in file order).  Every line before the cut is
    kept unchanged: comments, ODOM lines and anything else.
``--t0 T0 --t1 T1``
    Records whose ipc timestamp lies in ``[T0, T1]`` are kept, together with
    all comment lines.  The ipc timestamp is the third field from the end,
    as in every CARMEN record; unknown record types are kept by that rule
    too, malformed lines of known types are dropped.

Kept lines are copied byte for byte.  The output is gzip-compressed
(deterministically: no name, mtime 0) if its name ends in ``.gz``.

The ground truth is cut to match:

* a relations file (``t1 t2 x y z roll pitch yaw``) keeps the relations
  whose two ends are both timestamps of kept scans (hence both inside the
  window), copied unchanged;
* a corrected-poses file (``timestamp scan_index x y theta``) keeps the rows
  whose timestamp is that of a kept scan, with ``scan_index`` renumbered to
  the scan's 0-based index in the excerpt; a 4-column trajectory file
  (``timestamp x y theta``) keeps the rows inside the window.

Comment lines of the ground-truth files are kept.
"""

import argparse
import math
import sys
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence, Tuple

from .carmen import KNOWN_TYPES, SCAN_TYPES, MalformedLine, parse_tokens, time_key
from .fileio import PathLike, open_binary, open_binary_output

@dataclass
class ExcerptResult:
    """What an excerpt kept; ``t0``/``t1`` span the kept scans' timestamps."""

    lines_in: int = 0
    lines_out: int = 0
    scans: int = 0
    odom: int = 0
    dropped_malformed: int = 0
    malformed_kept: int = 0
    t0: float = math.inf
    t1: float = -math.inf
    #: microsecond key of each kept scan -> its 0-based index in the excerpt
    scan_index: Dict[int, int] = field(default_factory=dict)
    relations_kept: int = 0
    relations_total: int = 0
    poses_kept: int = 0
    poses_total: int = 0


def _line_kind(tokens: List[str]) -> Optional[str]:
    if not tokens:
        return "blank"
    if tokens[0].startswith("#"):
        return "comment"
    return tokens[0]


def excerpt_log(
    src: PathLike,
    dst: PathLike,
    first_scans: Optional[int] = None,
    t0: Optional[float] = None,
    t1: Optional[float] = None,
) -> ExcerptResult:
    """Write the excerpt of ``src`` to ``dst``; see the module doc for the rules."""
    if (first_scans is None) == (t0 is None or t1 is None):
        raise ValueError("give either first_scans or both t0 and t1")
    if first_scans is not None and first_scans < 1:
        raise ValueError("first_scans must be at least 1")
    if t0 is not None and t1 is not None and t0 > t1:
        raise ValueError("t0 must not be after t1")
    res = ExcerptResult()
    with open_binary(src) as fin, open_binary_output(dst) as fout:
        for raw in fin:
            res.lines_in += 1
            tokens = raw.decode("utf-8", errors="replace").split()
            kind = _line_kind(tokens)
            rec = None
            if kind in KNOWN_TYPES:
                try:
                    rec = parse_tokens(tokens)
                except MalformedLine:
                    rec = None
            if first_scans is not None:
                keep = True
                if kind in KNOWN_TYPES and rec is None:
                    res.malformed_kept += 1  # part of the cut: copied, not dropped
            else:
                if kind == "blank":
                    keep = False
                elif kind == "comment":
                    keep = True
                elif kind in KNOWN_TYPES:
                    keep = rec is not None and t0 <= rec.timestamp <= t1
                    if rec is None:
                        res.dropped_malformed += 1
                else:
                    try:
                        ts = float(tokens[-3]) if len(tokens) >= 4 else math.nan
                    except ValueError:
                        ts = math.nan
                    keep = t0 <= ts <= t1
            if not keep:
                continue
            fout.write(raw)
            res.lines_out += 1
            if rec is not None and kind in SCAN_TYPES:
                res.scan_index[time_key(rec.timestamp)] = res.scans
                res.scans += 1
                res.t0 = min(res.t0, rec.timestamp)
                res.t1 = max(res.t1, rec.timestamp)
            elif rec is not None:
                res.odom += 1
            if first_scans is not None and res.scans >= first_scans:
                break
    return res


def _filter_rows(src: PathLike, dst: PathLike, keep: Callable[[bytes, List[str]], Optional[bytes]]) -> Tuple[int, int]:
    """Copies the text file ``src`` to ``dst``: comment lines as they are,
    blank ones not, each other line as ``keep(line, fields)`` returns it
    (None: left out); returns (kept, total) of those other lines."""
    kept = total = 0
    with open_binary_output(dst) as fout, open_binary(src) as fin:
        for raw in fin:
            tokens = raw.decode("utf-8", errors="replace").split()
            if not tokens:
                continue
            if tokens[0].startswith("#"):
                fout.write(raw)
                continue
            total += 1
            out = keep(raw, tokens)
            if out is not None:
                fout.write(out)
                kept += 1
    return kept, total


def excerpt_relations(src: PathLike, dst: PathLike, res: ExcerptResult) -> Tuple[int, int]:
    """Keep the relations whose two ends are kept scans; returns (kept, total)."""
    def keep(raw: bytes, tokens: List[str]) -> Optional[bytes]:
        if len(tokens) != 8:
            raise ValueError(f"{src}: a relation needs 8 fields, got {len(tokens)}")
        k1, k2 = time_key(float(tokens[0])), time_key(float(tokens[1]))
        return raw if k1 in res.scan_index and k2 in res.scan_index else None

    res.relations_kept, res.relations_total = _filter_rows(src, dst, keep)
    return res.relations_kept, res.relations_total


def excerpt_poses(src: PathLike, dst: PathLike, res: ExcerptResult) -> Tuple[int, int]:
    """Cut a corrected-poses (or trajectory) file to the excerpt; returns (kept, total)."""
    def keep(raw: bytes, tokens: List[str]) -> Optional[bytes]:
        t = float(tokens[0])
        if len(tokens) == 5:  # corrected poses: the scan index renumbered
            idx = res.scan_index.get(time_key(t))
            return None if idx is None else (" ".join([tokens[0], str(idx)] + tokens[2:]) + "\n").encode("utf-8")
        if len(tokens) == 4:
            return raw if res.t0 <= t <= res.t1 else None
        raise ValueError(f"{src}: expected 4 or 5 columns, got {len(tokens)}")

    res.poses_kept, res.poses_total = _filter_rows(src, dst, keep)
    return res.poses_kept, res.poses_total


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="rsm-excerpt",
        description="Cut a CARMEN log and its ground truth to a number of scans or a time window.",
    )
    p.add_argument("input", help="CARMEN log (plain or gzip)")
    p.add_argument("output", help="output log; gzip-compressed (mtime 0) if it ends in .gz")
    sel = p.add_mutually_exclusive_group(required=True)
    sel.add_argument("--first-scans", type=int, metavar="N",
                     help="keep everything up to and including the N-th scan line")
    sel.add_argument("--t0", type=float, help="window start (ipc timestamp, s)")
    p.add_argument("--t1", type=float, help="window end (ipc timestamp, s), with --t0")
    p.add_argument("--relations", nargs=2, metavar=("IN", "OUT"),
                   help="also cut a relations file")
    p.add_argument("--poses", nargs=2, metavar=("IN", "OUT"),
                   help="also cut a corrected-poses (or trajectory) file")
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.t0 is not None and args.t1 is None:
        parser.error("--t0 needs --t1")
    if args.t1 is not None and args.t0 is None:
        parser.error("--t1 needs --t0")
    try:
        res = excerpt_log(args.input, args.output, args.first_scans, args.t0, args.t1)
        msg = f"{res.scans} scans, {res.odom} ODOM, {res.lines_out} lines written"
        if res.scans:
            msg += f"; scans span {res.t0:.6f} .. {res.t1:.6f} ({res.t1 - res.t0:.3f} s)"
        if res.dropped_malformed:
            msg += f"; {res.dropped_malformed} malformed lines dropped"
        if res.malformed_kept:
            msg += f"; {res.malformed_kept} malformed lines copied"
        print(msg)
        if args.first_scans is not None and res.scans < args.first_scans:
            print(f"rsm-excerpt: warning: the log has only {res.scans} scans", file=sys.stderr)
        if args.relations:
            kept, total = excerpt_relations(args.relations[0], args.relations[1], res)
            print(f"relations: {kept} of {total} kept")
        if args.poses:
            kept, total = excerpt_poses(args.poses[0], args.poses[1], res)
            print(f"poses: {kept} of {total} kept")
    except (OSError, ValueError) as exc:
        print(f"rsm-excerpt: error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
