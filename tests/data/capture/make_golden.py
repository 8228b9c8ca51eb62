"""Writes the golden captures of tests/data/capture with the Python writer.

    PYTHONPATH=tools python tests/data/capture/make_golden.py tests/data/capture

good.cap is what rsm_tools.capture.CaptureWriter writes for a fixed set of
channels, metadata and records; damaged.cap is the same bytes with one fault
of every kind the reading rules name (docs/capture.md): garbage with a false
sync between two records, a bit flipped inside a record, a record with a bad
direction, one for a channel the header does not list, one stamped before the
record it follows, and a last record cut short.  For each file and each mode
(strict, lenient) NAME.MODE.txt is what the Python reader makes of it, in the
format of tests/py/test_capture.py (python_dump); tests/unit/test_capture.c
requires the C reader to make exactly the same.  tests/py/test_capture.py
requires this script to reproduce the committed files byte for byte.
"""

import sys
from pathlib import Path
from typing import List

from rsm_tools import capture as cap

CHANNELS = [cap.Channel(0, "robot", "aria", 38400), cap.Channel(1, "laser", "lms2xx", 9600),
            cap.Channel(200, "gps spare", "raw", 115200)]
METADATA = {"source": "golden", "created_by": "make_golden.py", "robot.initial_pose": "1.5 -2.25 0.125",
            "empty": "", "units.time": "us"}


def records() -> List[tuple]:
    """(timestamp, channel, direction, data): every record kind the format allows."""
    out = [
        (0, 0, cap.RX, bytes(range(16))),
        (0, 1, cap.RX, b""),                                   # empty record
        (1000, 1, cap.TX, b"\x02\x00\x02\x00\x20\x24\x34\x08"),
        (1000, 0, cap.RX, b"RC" + bytes(40) + b"RC\x05\x00"),  # sync bytes inside the data
        (2500, 200, cap.RX, bytes((7 * i) & 0xFF for i in range(700))),
    ]
    t = 2500
    for k in range(6):
        t += 125 * k
        out.append((t, k % 2, cap.RX, bytes((k + i) & 0xFF for i in range(3 + 11 * k))))
    out.append((2**64 - 1, 0, cap.RX, b"last"))              # the largest stamp
    return out


def write_good(path: Path) -> List[int]:
    """Writes good.cap; returns the byte offset of every record."""
    with cap.CaptureWriter(path, CHANNELS, METADATA) as w:
        pass
    offs = []
    o = path.stat().st_size
    with cap.CaptureWriter(path, CHANNELS, METADATA) as w:
        for t, ch, d, data in records():
            offs.append(o)
            o += cap.REC_OVERHEAD + len(data)
            w.write(t, ch, data, d)
    return offs


def write_damaged(good: Path, offs: List[int], path: Path) -> None:
    raw = bytearray(good.read_bytes())
    tail = raw[offs[-1]:]
    raw = raw[:offs[-1]]
    raw[offs[7] + 20] ^= 0x10                                  # a flipped bit in record 7
    raw[offs[3]:offs[3]] = b"noise RC\x03\x00 more"            # garbage with a false sync before record 3
    raw += cap.encode_record(9000, 0, 2, b"bad direction")
    raw += cap.encode_record(9000, 7, cap.RX, b"unknown channel")
    raw += cap.encode_record(10, 1, cap.RX, b"too early")
    raw += cap.encode_record(9001, 1, cap.RX, b"fine again")
    raw += tail[:-3]                                           # the last record cut short
    path.write_bytes(bytes(raw))


def dump(path: Path, lenient: bool) -> str:
    """What the Python reader makes of a file (tests/py/test_capture.py's format)."""
    lines = []
    r = None
    try:
        r = cap.CaptureReader(path, lenient=lenient)
        for c in r.header.channels:
            lines.append(f"channel {c.id} {c.name} {c.protocol} {c.baud}")
        for k in sorted(r.header.metadata):
            lines.append(f"meta {k}={r.header.metadata[k]}")
        for rec in r:
            lines.append(f"record {rec.offset} {rec.timestamp} {rec.channel} {rec.direction} "
                         f"{len(rec.data)} {rec.data.hex()}")
        s = r.stats
        lines.append(f"end records={s.records} corrupt={s.corrupt} truncated={s.truncated} "
                     f"order={s.out_of_order} channel={s.unknown_channel} skipped={s.skipped_bytes}")
    except cap.CaptureError as exc:
        lines.append(f"error {exc.kind}")
    finally:
        if r is not None:
            r.close()
    return "\n".join(lines) + "\n"


def make(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    offs = write_good(out / "good.cap")
    write_damaged(out / "good.cap", offs, out / "damaged.cap")
    for name in ("good", "damaged"):
        for mode in ("strict", "lenient"):
            (out / f"{name}.{mode}.txt").write_text(dump(out / f"{name}.cap", mode == "lenient"))


if __name__ == "__main__":
    make(Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent))
