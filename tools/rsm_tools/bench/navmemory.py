"""The bench's line on rsm-nav's own memory over a long run (issue "Nothing
lost, nothing silent"): the peak resident set of one process over 10 000
scans and over 400 000, a day of a lidar at about 5 Hz. The library's state
is fixed by its configuration; what could grow is the program around it
(it once kept every scan's time for the percentiles: 15 bytes a scan).
The floor: the long run's peak at most FLOOR_X times the short one's.

The scans are the main log's scan lines over and over, each pass's stamps
moved on past the last pass's, fed through a named pipe so that no file of
hundreds of megabytes is written. Each pass starts where the robot started
(odometry jumps back): the localizer refutes that step or searches, which
costs time, not memory."""

import errno
import gzip
import os
import re
import subprocess
import threading
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence

from .common import BenchError, floor, fmt_int

SCANS = (10_000, 400_000)
QUICK_SCANS = (2_000, 20_000)  # --quick: the same line, a shorter run
FLOOR_X = 1.05  # the long run's peak resident set over the short run's, at most


def scan_lines(log: Path) -> List[bytes]:
    """The log's FLASER and ROBOTLASER1 lines, as they are."""
    opener = gzip.open if log.name.endswith(".gz") else open
    with opener(log, "rb") as fh:
        return [l if l.endswith(b"\n") else l + b"\n" for l in fh
                if l.startswith((b"FLASER ", b"ROBOTLASER1 "))]


def shifted(line: bytes, offset: float) -> bytes:
    """A scan line with its two stamps (the third-last and the last field)
    moved on by offset seconds."""
    f = line.split()
    f[-3] = b"%.6f" % (float(f[-3]) + offset)
    f[-1] = b"%.6f" % (float(f[-1]) + offset)
    return b" ".join(f) + b"\n"


def write_scans(lines: Sequence[bytes], scans: int, out) -> int:
    """``scans`` lines of ``lines`` over and over to the binary stream out,
    each pass's stamps moved on by the span of the log plus one second;
    returns the lines written."""
    if not lines:
        raise BenchError("the log has no scan lines")
    first, last = float(lines[0].split()[-3]), float(lines[-1].split()[-3])
    span = max(last - first, 0.0) + 1.0
    n = 0
    offset = 0.0
    while n < scans:
        for line in lines[:scans - n]:
            out.write(shifted(line, offset) if offset else line)
        n += min(len(lines), scans - n)
        offset += span
    return n


def peak_rss_kib(nav: Path, lines: Sequence[bytes], scans: int, work: Path) -> Dict[str, int]:
    """Runs rsm-nav on ``scans`` scans fed through a named pipe; returns its
    peak resident set (KiB, as its summary prints it) and the scans it wrote
    a pose for."""
    work.mkdir(parents=True, exist_ok=True)
    fifo = work / f"scans-{scans}.fifo"
    if fifo.exists():
        fifo.unlink()
    os.mkfifo(fifo)
    traj = work / f"trajectory-{scans}.txt"
    proc = subprocess.Popen([str(nav), "--carmen", str(fifo), "--trajectory", str(traj), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    written: List[int] = []
    error: List[BaseException] = []
    ended = threading.Event()  # set once rsm-nav has ended

    def feed():
        # Served once, when rsm-nav opens it (it looks up no mount in a log
        # that is not a regular file): a reader at its end would take a
        # second pass as more of the log.
        try:
            while not ended.is_set():
                try:
                    fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
                except OSError as e:
                    if e.errno != errno.ENXIO:  # ENXIO: no reader yet
                        raise
                    time.sleep(0.01)
                    continue
                os.set_blocking(fd, True)
                try:
                    with os.fdopen(fd, "wb") as fh:
                        written.append(write_scans(lines, scans, fh))
                except BrokenPipeError:
                    pass
                return
        except BaseException as e:  # reported below, after rsm-nav has ended
            error.append(e)

    t = threading.Thread(target=feed)
    t.start()
    out, err = proc.communicate()
    ended.set()
    t.join()
    stdout, stderr = out.decode(errors="replace"), err.decode(errors="replace")
    fifo.unlink()
    if error:
        raise BenchError(f"feeding rsm-nav {scans} scans: {error[0]}")
    if proc.returncode != 0:
        raise BenchError(f"rsm-nav on {scans} scans failed ({proc.returncode}): {stderr[-2000:]}")
    poses = sum(1 for l in traj.read_text().splitlines() if l and not l.startswith("#"))
    traj.unlink()
    if not written:
        raise BenchError(f"rsm-nav ended before it had read the {scans} scans")
    # rsm-nav's own figure (Linux VmHWM): the rusage of a child counts the
    # memory of the Python that forked it
    m = re.search(r"^\s*memory\s+peak (\d+) KiB resident", stdout, re.M)
    if m is None:
        raise BenchError(f"rsm-nav printed no peak memory (not Linux?):\n{stdout[-1000:]}")
    return {"scans": written[-1], "poses": poses, "peak_kib": int(m.group(1))}


def run(nav: Path, log: Path, work: Path, counts: Sequence[int] = SCANS) -> dict:
    """The section's figures: one run per count, one process at a time."""
    lines = scan_lines(log)
    return {"log": str(log), "runs": [peak_rss_kib(nav, lines, n, work / "nav-memory") for n in counts]}


def floors(mem: Optional[dict]) -> List[dict]:
    """PASS, MISS or SKIP: the longest run's peak against the shortest's."""
    what = "rsm-nav memory: peak resident set"
    if not mem or "skipped" in mem or len(mem.get("runs") or []) < 2:
        why = (mem or {}).get("skipped", "not run")
        return [floor("SKIP", "memory-nav", None, None, FLOOR_X, f"{what}: not measured ({why})")]
    short, long_ = mem["runs"][0], mem["runs"][-1]
    x = long_["peak_kib"] / short["peak_kib"]
    ok = x <= FLOOR_X
    return [floor("PASS" if ok else "MISS", "memory-nav", None, x, FLOOR_X,
                  f"{what} over {fmt_int(long_['scans'])} scans {fmt_int(long_['peak_kib'])} KiB = x{x:.3f} of "
                  f"{fmt_int(short['scans'])} scans' {fmt_int(short['peak_kib'])} KiB "
                  f"{'<=' if ok else '>'} x{FLOOR_X:g}")]


def report(mem: Optional[dict]) -> List[str]:
    """The lines of the report under "Memory"."""
    if not mem or "skipped" in mem:
        return ["rsm-nav's own memory over a long run: not measured in this run"
                + (f" ({mem['skipped']})" if mem and "skipped" in mem else "") + ".", ""]
    rows = "; ".join(f"{fmt_int(r['scans'])} scans ({fmt_int(r['poses'])} poses written): "
                     f"{fmt_int(r['peak_kib'])} KiB" for r in mem["runs"])
    return [f"rsm-nav's own memory, peak resident set of one process (its summary's, Linux VmHWM), the log's "
            "scans over and over "
            f"through a named pipe (`rsm_tools.bench.navmemory`): {rows}.", ""]
