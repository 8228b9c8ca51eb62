"""Deterministic outlier injection into a CARMEN log.

A robustness test for scan matching: in every laser scan (FLASER and
ROBOTLASER1 lines) a fixed share of the range readings is replaced by
uniformly random ranges, as if the laser saw phantom obstacles.

For a scan of ``n`` readings, exactly ``k = round(P/100 * n)`` distinct
readings are replaced (rounded half up, computed exactly from the decimal
text of P).  Each replacement is drawn uniformly from ``[min_range,
max_range]``; the default maximum is 8.0 m, a typical short range for a small
robot's laser, well inside the Intel log's readings.

Determinism: each scan gets its own ``random.Random`` whose seed is derived
with SHA-256 from the user seed and the scan's 0-based index among the scan
lines of the file.  Neither Python's string-hash randomisation nor the order
in which scans are processed changes the result, and the same seed gives the
same output file, byte for byte (gzip output is written with mtime 0).

Only the text of the chosen range fields changes.  Every other line, and
every other field and separator on a scan line, is copied byte for byte.
A replacement is printed with as many decimals as the field it replaces (at
least 2).  Scan lines that cannot be parsed are copied unchanged and counted.
"""

import argparse
import hashlib
import math
import random
import sys
from dataclasses import dataclass, field
from fractions import Fraction
from typing import IO, Iterable, List, Optional, Sequence, Tuple, Union

from .carmen import SCAN_KEYS, TOKEN, MalformedLine, parse_tokens, token_decimals
from .fileio import PathLike, open_binary, open_binary_output

DEFAULT_MIN_RANGE = 0.2
DEFAULT_MAX_RANGE = 8.0



@dataclass
class InjectionStats:
    lines: int = 0
    scans: int = 0
    readings: int = 0
    replaced: int = 0
    skipped_malformed: int = 0
    #: per scan (in file order), the indices that were replaced
    replaced_indices: List[List[int]] = field(default_factory=list)


def outlier_count(percent: Union[str, float, Fraction], n: int) -> int:
    """round(percent/100 * n), half up, computed exactly."""
    p = Fraction(str(percent)) if not isinstance(percent, Fraction) else percent
    if p < 0 or p > 100:
        raise ValueError(f"percent must be within [0, 100], got {percent}")
    return math.floor(p * n / 100 + Fraction(1, 2))


def scan_rng(seed: int, scan_index: int) -> random.Random:
    """The PRNG of one scan, derived from the user seed and the scan index."""
    digest = hashlib.sha256(f"rsm-outliers:{seed}:{scan_index}".encode("ascii")).digest()
    return random.Random(int.from_bytes(digest[:16], "big"))


def _format_range(v: float, decimals: int, lo: float, hi: float) -> bytes:
    text = f"{v:.{decimals}f}"
    if not lo <= float(text) <= hi:  # rounding left the interval: print it exactly
        text = repr(v)
    return text.encode("ascii")


def _range_field_offset(key: bytes) -> int:
    """Index of the first range reading among a scan line's tokens."""
    return 2 if key == b"FLASER" else 9


def inject_line(
    line: bytes,
    scan_index: int,
    percent: Union[str, float, Fraction],
    seed: int,
    min_range: float = DEFAULT_MIN_RANGE,
    max_range: float = DEFAULT_MAX_RANGE,
) -> Tuple[bytes, List[int], int]:
    """Inject outliers into one scan line.

    Returns the new line, the sorted indices of the replaced readings and the
    number of readings in the scan.

    Raises :class:`MalformedLine` if the line is not a well-formed scan.
    """
    spans = [m.span() for m in TOKEN.finditer(line)]
    tokens = [line[a:b] for a, b in spans]
    try:
        text_tokens = [t.decode("utf-8") for t in tokens]
    except UnicodeDecodeError:
        raise MalformedLine("non_numeric", "undecodable bytes") from None
    rec = parse_tokens(text_tokens)  # validates the whole line
    n = len(rec.ranges)
    k = outlier_count(percent, n)
    rng = scan_rng(seed, scan_index)
    chosen = sorted(rng.sample(range(n), k))
    first = _range_field_offset(tokens[0])
    out = bytearray()
    pos = 0
    for i in chosen:
        a, b = spans[first + i]
        value = rng.uniform(min_range, max_range)
        out += line[pos:a]
        out += _format_range(value, max(2, token_decimals(tokens[first + i])), min_range, max_range)
        pos = b
    out += line[pos:]
    return bytes(out), chosen, n


def inject_lines(
    lines: Iterable[bytes],
    out: IO[bytes],
    percent: Union[str, float, Fraction],
    seed: int,
    min_range: float = DEFAULT_MIN_RANGE,
    max_range: float = DEFAULT_MAX_RANGE,
    keep_indices: bool = False,
) -> InjectionStats:
    """Copy ``lines`` (bytes, with their line ends) to ``out``, injecting outliers."""
    if not (math.isfinite(min_range) and math.isfinite(max_range)) or min_range > max_range:
        raise ValueError(f"bad range interval [{min_range}, {max_range}]")
    outlier_count(percent, 0)  # validates percent
    st = InjectionStats()
    for line in lines:
        st.lines += 1
        head = line.lstrip()
        key = head.split(None, 1)[0] if head else b""
        if key not in SCAN_KEYS:
            out.write(line)
            continue
        try:
            new, chosen, n = inject_line(line, st.scans, percent, seed, min_range, max_range)
        except MalformedLine:
            st.skipped_malformed += 1
            out.write(line)
            continue
        st.scans += 1
        st.replaced += len(chosen)
        st.readings += n
        if keep_indices:
            st.replaced_indices.append(chosen)
        out.write(new)
    return st


def inject_file(
    src: PathLike,
    dst: PathLike,
    percent: Union[str, float, Fraction],
    seed: int,
    min_range: float = DEFAULT_MIN_RANGE,
    max_range: float = DEFAULT_MAX_RANGE,
) -> InjectionStats:
    """Inject outliers into the log ``src`` (plain or gzip) and write ``dst``.

    ``dst`` is gzip-compressed (deterministically) if its name ends in ``.gz``.
    """
    with open_binary(src) as fin, open_binary_output(dst) as fout:
        return inject_lines(fin, fout, percent, seed, min_range, max_range)


def percent_argument(text: str) -> Fraction:
    """An argparse type: a share in per cent, 0 to 100, exact (rsm-outliers,
    rsm-faults --drop)."""
    try:
        p = Fraction(text)
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if p < 0 or p > 100:
        raise argparse.ArgumentTypeError(f"must be within [0, 100]: {text}")
    return p


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="rsm-outliers",
        description=(
            "Replace a fixed percentage of the range readings of every laser scan in a "
            "CARMEN log by uniform random ranges, deterministically from a seed."
        ),
    )
    p.add_argument("input", help="CARMEN log (plain or gzip)")
    p.add_argument("output", help="output log; gzip-compressed if the name ends in .gz")
    p.add_argument("--percent", type=percent_argument, required=True,
                   help="share of readings to replace in each scan, 0..100; the count per "
                        "scan is round(P/100 * n), halves rounded up")
    p.add_argument("--seed", type=int, required=True, help="integer seed")
    p.add_argument("--min-range", type=float, default=DEFAULT_MIN_RANGE,
                   help="smallest injected range in m (default: %(default)g)")
    p.add_argument("--max-range", type=float, default=DEFAULT_MAX_RANGE,
                   help="largest injected range in m (default: %(default)g)")
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = build_parser().parse_args(argv)
    if not (math.isfinite(args.min_range) and math.isfinite(args.max_range)) or args.min_range > args.max_range:
        # A command-line error (2), as the C tools say; reading or writing failing is 1.
        print(f"rsm-outliers: error: bad range interval [{args.min_range}, {args.max_range}]", file=sys.stderr)
        return 2
    try:
        st = inject_file(args.input, args.output, args.percent, args.seed,
                         args.min_range, args.max_range)
    except (OSError, ValueError) as exc:
        print(f"rsm-outliers: error: {exc}", file=sys.stderr)
        return 1
    msg = (f"{st.scans} scans, {st.replaced} of {st.readings} readings replaced "
           f"({float(args.percent):g}% requested, seed {args.seed})")
    if st.skipped_malformed:
        msg += f"; {st.skipped_malformed} malformed scan lines copied unchanged"
    print(msg)
    return 0


if __name__ == "__main__":
    sys.exit(main())
