"""The bench's line on rsm-nav's own memory over a long run (issue "Nothing
lost, nothing silent"): the peak resident set of one process after 10 000
scans and after 400 000, a day of a lidar at about 5 Hz. The library's state
is fixed by its configuration; what could grow is the program around it
(it once kept every scan's time for the percentiles: 15 bytes a scan).
The floor: the peak at the end at most FLOOR_X times the same process's
peak after the first 10 000 scans (read from /proc while it runs). Two
processes, one of each length, differed by up to 7 % from run to run of
the bench whatever their length (the pages a process happens to touch),
as much as the floor allows: one process against itself does not.

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


def write_scans(lines: Sequence[bytes], scans: int, out, start: int = 0) -> int:
    """Lines start .. scans - 1 of ``lines`` over and over to the binary
    stream out, each pass's stamps moved on by the span of the log plus one
    second; returns the lines written."""
    if not lines:
        raise BenchError("the log has no scan lines")
    first, last = float(lines[0].split()[-3]), float(lines[-1].split()[-3])
    span = max(last - first, 0.0) + 1.0
    n = start
    while n < scans:
        passes, at = divmod(n, len(lines))
        offset = passes * span
        chunk = lines[at:at + scans - n]
        for line in chunk:
            out.write(shifted(line, offset) if offset else line)
        n += len(chunk)
    return n - start


def vm_hwm_kib(pid: int) -> Optional[int]:
    """The peak resident set (Linux VmHWM, KiB) of a running process, or
    None where /proc does not say it."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return None


def peak_rss_kib(nav: Path, lines: Sequence[bytes], scans: int, work: Path, checkpoint: int) -> Dict[str, int]:
    """Runs rsm-nav on ``scans`` scans fed through a named pipe; returns its
    peak resident set (KiB, as its summary prints it), the scans it wrote a
    pose for, and its peak read from /proc once the first ``checkpoint``
    scans are in the pipe (rsm-nav is then at most the pipe's buffer, a few
    dozen scans, behind)."""
    if not 0 < checkpoint < scans:
        raise BenchError(f"a checkpoint of {checkpoint} scans is not within a run of {scans}")
    work.mkdir(parents=True, exist_ok=True)
    fifo = work / f"scans-{scans}.fifo"
    if fifo.exists():
        fifo.unlink()
    os.mkfifo(fifo)
    traj = work / f"trajectory-{scans}.txt"
    proc = subprocess.Popen([str(nav), "--carmen", str(fifo), "--trajectory", str(traj), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    written: List[int] = []
    at_checkpoint: List[Optional[int]] = []
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
                        n = write_scans(lines, checkpoint, fh)
                        fh.flush()
                        at_checkpoint.append(vm_hwm_kib(proc.pid))
                        written.append(n + write_scans(lines, scans, fh, checkpoint))
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
    if not at_checkpoint or at_checkpoint[0] is None:
        raise BenchError(f"no peak memory of rsm-nav in /proc after {checkpoint} scans (not Linux?)")
    return {"scans": written[-1], "poses": poses, "peak_kib": int(m.group(1)), "checkpoint_scans": checkpoint,
            "checkpoint_kib": at_checkpoint[0]}


def run(nav: Path, log: Path, work: Path, counts: Sequence[int] = SCANS) -> dict:
    """The section's figures: one process over the longest count, its peak
    read after the shortest too."""
    lines = scan_lines(log)
    return {"log": str(log),
            "run": peak_rss_kib(nav, lines, max(counts), work / "nav-memory", min(counts))}


def floors(mem: Optional[dict]) -> List[dict]:
    """PASS, MISS or SKIP: the process's peak at the end against its peak
    after the first scans."""
    what = "rsm-nav memory: peak resident set"
    r = (mem or {}).get("run") or {}
    if not mem or "skipped" in mem or "checkpoint_kib" not in r:
        why = (mem or {}).get("skipped", "not run")
        return [floor("SKIP", "memory-nav", None, None, FLOOR_X, f"{what}: not measured ({why})")]
    x = r["peak_kib"] / r["checkpoint_kib"]
    ok = x <= FLOOR_X
    return [floor("PASS" if ok else "MISS", "memory-nav", None, x, FLOOR_X,
                  f"{what} after {fmt_int(r['scans'])} scans {fmt_int(r['peak_kib'])} KiB = x{x:.3f} of the same "
                  f"process's after {fmt_int(r['checkpoint_scans'])} scans, {fmt_int(r['checkpoint_kib'])} KiB "
                  f"{'<=' if ok else '>'} x{FLOOR_X:g}")]


def report(mem: Optional[dict]) -> List[str]:
    """The lines of the report under "Memory"."""
    if not mem or "skipped" in mem:
        return ["rsm-nav's own memory over a long run: not measured in this run"
                + (f" ({mem['skipped']})" if mem and "skipped" in mem else "") + ".", ""]
    r = mem["run"]
    return [f"rsm-nav's own memory, peak resident set of one process (Linux VmHWM), the log's scans over and over "
            f"through a named pipe (`rsm_tools.bench.navmemory`): after {fmt_int(r['checkpoint_scans'])} scans "
            f"(read from /proc) {fmt_int(r['checkpoint_kib'])} KiB; after {fmt_int(r['scans'])} "
            f"({fmt_int(r['poses'])} poses written, its summary's) {fmt_int(r['peak_kib'])} KiB.", ""]
