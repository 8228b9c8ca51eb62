"""rsm-restamp: give the trajectory of a replayed capture the log's own scan stamps.

    rsm-restamp TRAJECTORY --capture CAP -o OUT

rsm-nav in live mode stamps each pose with the time its scan arrived, which
says nothing about the log a capture was converted from.  When the capture
was made by rsm-convert (one 0xB0 telegram per laser record), the k-th pose
is the k-th scan's, so it gets that scan's stamp as the log had it (undoing
the converter's moved stamps, see docs/capture.md).  Then rsm-evaluate and
rsm-plot can match it against ground truth.  The trajectory must have one
pose per scan; anything else is an error (exit status 1), as is a capture
that cannot be read; a bad command line exits with 2, as the C tools do.
"""

import argparse
import sys
from pathlib import Path
from typing import List, Optional, Sequence

from . import capture as cap
from .convert import original_scan_stamps


def restamp(trajectory: str, capture: str) -> List[str]:
    """The trajectory's lines with the capture's scan stamps; raises ValueError on a count mismatch."""
    stamps = original_scan_stamps(capture)
    comments, rows = [], []
    for line in Path(trajectory).read_text().splitlines():
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            comments.append(s)
        else:
            rows.append(s.split())
    if len(rows) != len(stamps):
        raise ValueError(f"{trajectory} has {len(rows)} poses but {capture} has {len(stamps)} scans: "
                         "a pose per scan is needed (was a scan lost or refused?)")
    out = comments + [f"# stamps: the log's scan stamps from {Path(capture).name} (rsm-restamp)"]
    for t, r in zip(stamps, rows):
        out.append(f"{t / 1e6:.6f} " + " ".join(r[1:]))
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-restamp", description=__doc__.split("\n\n")[0])
    ap.add_argument("trajectory", help="rsm-nav's trajectory of the replayed capture (one pose per scan)")
    ap.add_argument("--capture", required=True, help="the capture that was replayed")
    ap.add_argument("-o", "--output", required=True, help="the restamped trajectory to write")
    a = ap.parse_args(argv)
    try:
        lines = restamp(a.trajectory, a.capture)
    except (OSError, cap.CaptureError, KeyError) as exc:
        print(f"rsm-restamp: {exc}", file=sys.stderr)
        return 1
    except ValueError as exc:
        print(f"rsm-restamp: {exc}", file=sys.stderr)
        return 1
    Path(a.output).write_text("\n".join(lines) + "\n")
    print(f"rsm-restamp: wrote {a.output} ({len(lines)} lines)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
