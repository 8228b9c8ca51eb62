"""rsm-replay: play a capture's received bytes into serial ports or pseudo-terminals.

    rsm-replay CAP [--port CHANNEL=DEVICE ...] [--pty] [--speed X | --fast]
               [--wait-open] [--linger S] [--quiet]
    rsm-replay CAP --pty --lockstep [--linger S] [--quiet] --run PROGRAM ARGS...

Only rx records (device -> host) are played; tx records are what the host
sent and are skipped.  Each channel goes to the serial device named with
``--port`` (opened with pyserial at the channel's baud rate), or, with
``--pty``, to a pseudo-terminal created for it: one ``CHANNEL PATH`` line per
channel is printed on stdout (flushed) before playing starts, so another
program can open the paths.  Channels with neither are skipped.

Timing: recorded (``--speed 1``, default), scaled (``--speed 4`` = four times
faster), or ``--fast``: as fast as the reader takes the bytes (writes wait
while the pty buffer is full).  A recorded pause longer than ``--max-gap``
seconds (default 5, after scaling) is shortened to it and counted: a capture
paused for an hour, or a corrupt stamp, does not stall the replay.
``--wait-open`` waits for a reader to open every pty first.  Progress goes to
stderr; the summary has a line per channel with what the decoder its
protocol tag names (aria, lms2xx, ld06, rplidar) found in the bytes played:
frames, packets or nodes, and checksum/CRC failures.  Ctrl-C (SIGINT) or
SIGTERM stops the replay cleanly (exit status 0 after a "stopped" message).
Exit status 1: an unreadable capture, a port that cannot be opened, a
problem in the capture, or a reader that went away (closed its pty, or read
nothing for ``--stall`` seconds, default 10, while bytes waited).  Exit status 2: bad arguments (the C tools' convention).

``--run PROGRAM ARGS...`` starts the reader itself (``{CHANNEL}`` in its
arguments becomes that channel's pty path) and ends with it: the exit status
is the reader's when it fails, else 0.  ``--lockstep`` (with ``--run``) makes
the reader's result independent of the machine's speed and load (see
:mod:`rsm_tools.lockstep`): before each group of records with one timestamp
rsm-replay waits until the reader has read everything and is blocked waiting
for more, then writes the whole group while it is held there; timing options
are ignored, but not ``--stall``: a reader that reads nothing from a link
for that long while bytes wait there fails the replay.  The reader's clock can follow the capture's too: the
environment variable ``RSM_LOCKSTEP_CLOCK`` names a file that holds the
timestamp of the group written last (8 bytes, little-endian microseconds; 0
before the first), rewritten while the reader is held.  rsm-nav takes it as
its drivers' clock, so its live run then gets the very bytes and times a
capture-mode run gets.
"""

import argparse
import os
import select
import signal
import sys
import tempfile
import time
import tty
from typing import Dict, List, Optional, Sequence

from . import capture as cap
from . import lockstep as ls
from .protocols import FrameCounter


class Stop(Exception):
    pass


class ReaderGone(Exception):
    """Nobody reads a pty any more: writing would wait for ever."""


def _raise_stop(signum, frame):  # noqa: ARG001
    raise Stop(signal.Signals(signum).name)


class PtyOut:
    def __init__(self, name: str, stall_s: float = 10.0) -> None:
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self.name = name
        self.stall_s = stall_s
        self.seen_open = False
        os.set_blocking(self.master, False)

    def release_slave(self) -> None:
        if self.slave is not None:
            os.close(self.slave)
            self.slave = None

    def opened(self) -> bool:
        """True once someone has the slave open (the master no longer reports a hang-up)."""
        p = select.poll()
        p.register(self.master, select.POLLHUP)
        is_open = not any(ev & select.POLLHUP for _, ev in p.poll(0))
        self.seen_open = self.seen_open or is_open
        return is_open

    def write(self, data: bytes) -> None:
        """All of data, waiting while the buffer is full; ReaderGone when the
        reader that had the pty open closed it, or read nothing for stall_s."""
        view = memoryview(data)
        stalled = None
        while view:
            try:
                n = os.write(self.master, view)
            except BlockingIOError:
                n = 0
            if n > 0:
                view = view[n:]
                stalled = None
                continue
            if self.slave is None and self.seen_open and not self.opened():
                raise ReaderGone(f"the reader of {self.name} ({self.path}) closed it")
            now = time.monotonic()
            stalled = stalled if stalled is not None else now
            if now - stalled >= self.stall_s:
                raise ReaderGone(f"nothing read from {self.name} ({self.path}) for {self.stall_s:g} s")
            p = select.poll()
            p.register(self.master, select.POLLOUT)
            p.poll(100)

    def close(self) -> None:
        self.release_slave()
        os.close(self.master)


class SerialOut:
    def __init__(self, name: str, device: str, baud: int) -> None:
        import serial  # pyserial, the package's runtime dependency

        self.name = name
        self.path = device
        self.port = serial.Serial(device, baudrate=baud or 9600, timeout=1, write_timeout=None)

    def write(self, data: bytes) -> None:
        self.port.write(data)

    def close(self) -> None:
        try:
            self.port.flush()
        finally:
            self.port.close()


class Tally:
    """What was played, per channel, through the decoder its protocol tag
    names in the capture's header (the summary's per-channel lines)."""

    def __init__(self, header: cap.Header, outs) -> None:
        self.channels = [c for c in header.channels if c.id in outs]
        self.counters = {c.id: FrameCounter(c.protocol) for c in self.channels}
        self.bytes = {c.id: 0 for c in self.channels}

    def feed(self, rec: cap.Record) -> None:
        self.counters[rec.channel].feed(rec.data)
        self.bytes[rec.channel] += len(rec.data)

    def report(self) -> None:
        for c in self.channels:
            print(f"rsm-replay:   {c.name} ({c.protocol}): {self.bytes[c.id]} B, "
                  f"{self.counters[c.id].describe()}", file=sys.stderr, flush=True)


def played(reader, outs, limit: Optional[int]):
    """The records to play: received bytes of the channels with a port, at most ``limit``."""
    n = 0
    for rec in reader:
        if rec.direction != cap.RX or rec.channel not in outs:
            continue
        if limit is not None and n >= limit:
            return
        n += 1
        yield rec


def parse_ports(specs: Sequence[str]) -> Dict[str, str]:
    out = {}
    for s in specs:
        if "=" not in s:
            raise ValueError(f"--port wants CHANNEL=DEVICE, got {s!r}")
        k, v = s.split("=", 1)
        out[k] = v
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-replay", description=__doc__.split("\n\n")[0])
    ap.add_argument("capture", help="the capture file to play")
    ap.add_argument("--port", action="append", default=[], metavar="CHANNEL=DEVICE",
                    help="play channel CHANNEL into serial device DEVICE (repeatable)")
    ap.add_argument("--pty", action="store_true", help="create a pseudo-terminal per other channel")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--speed", type=float, default=1.0, help="time scale (2 = twice as fast)")
    g.add_argument("--fast", action="store_true", help="no pauses: as fast as the reader reads")
    ap.add_argument("--wait-open", action="store_true", help="wait until every pty is opened")
    ap.add_argument("--linger", type=float, default=1.0,
                    help="seconds to keep ptys open after the last byte (default 1)")
    ap.add_argument("--max-gap", type=float, default=5.0,
                    help="longest pause, seconds after scaling; longer ones are shortened (default 5)")
    ap.add_argument("--stall", type=float, default=10.0,
                    help="give up when a pty reader takes nothing for this long (default 10 s)")
    ap.add_argument("--quiet", action="store_true", help="print only the port paths and errors")
    ap.add_argument("--records", type=int, metavar="N",
                    help="play only the first N records (then the ports close, as if unplugged)")
    ap.add_argument("--lockstep", action="store_true",
                    help="feed the --run program one timestamp at a time, each when it waits for input")
    ap.add_argument("--run", nargs=argparse.REMAINDER, metavar="PROGRAM",
                    help="start PROGRAM ARGS... ({CHANNEL} = that pty's path) and end with it")
    a = ap.parse_args(argv)
    if not a.speed > 0 or not a.max_gap >= 0 or not a.stall > 0:
        ap.error("--speed and --stall must be positive, --max-gap not negative")
    if a.records is not None and a.records < 0:
        ap.error("--records must not be negative")
    if a.lockstep and not (a.pty and a.run):
        ap.error("--lockstep needs --pty and --run PROGRAM")
    try:
        ports = parse_ports(a.port)
    except ValueError as exc:
        ap.error(str(exc))

    signal.signal(signal.SIGTERM, _raise_stop)
    signal.signal(signal.SIGINT, _raise_stop)
    outs: Dict[int, object] = {}
    reader = None
    records = nbytes = 0
    t_first = t_last = None
    try:
        try:
            reader = cap.CaptureReader(a.capture)
        except (OSError, cap.CaptureError) as exc:
            print(f"rsm-replay: cannot read {a.capture}: {exc}", file=sys.stderr)
            return 1
        hdr = reader.header
        for name in ports:
            try:
                hdr.channel(name)
            except KeyError as exc:
                print(f"rsm-replay: {exc.args[0]}", file=sys.stderr)
                return 2
        for ch in hdr.channels:
            if ch.name in ports:
                try:
                    outs[ch.id] = SerialOut(ch.name, ports[ch.name], ch.baud)
                except Exception as exc:  # serial.SerialException, OSError
                    print(f"rsm-replay: cannot open port {ch.name} ({ports[ch.name]}): {exc}",
                          file=sys.stderr)
                    return 1
            elif a.pty:
                outs[ch.id] = PtyOut(ch.name, a.stall)
        if not outs:
            print("rsm-replay: nothing to play into: give --port CHANNEL=DEVICE or --pty",
                  file=sys.stderr)
            return 2
        for o in outs.values():
            print(f"{o.name} {o.path}", flush=True)
        ptys = [o for o in outs.values() if isinstance(o, PtyOut)]
        tally = Tally(hdr, outs)
        if a.run:
            return run_with(a, reader, outs, ptys, tally)
        if a.wait_open and ptys:
            for o in ptys:
                o.release_slave()
            if not a.quiet:
                print("rsm-replay: waiting for a reader to open " +
                      ", ".join(o.path for o in ptys), file=sys.stderr)
            while not all(o.opened() for o in ptys):
                time.sleep(0.02)
        start = time.monotonic()
        last_progress = 0.0
        shortened = 0
        for rec in played(reader, outs, a.records):
            if t_first is None:
                t_first = rec.timestamp
            if not a.fast:
                due = start + (rec.timestamp - t_first) / 1e6 / a.speed
                delay = due - time.monotonic()
                if delay > a.max_gap:
                    # The schedule moves on by what is cut, so later pauses keep their length.
                    start -= delay - a.max_gap
                    delay = a.max_gap
                    shortened += 1
                if delay > 0:
                    time.sleep(delay)
            outs[rec.channel].write(rec.data)  # type: ignore[attr-defined]
            tally.feed(rec)
            records += 1
            nbytes += len(rec.data)
            t_last = rec.timestamp
            now = time.monotonic()
            if not a.quiet and now - last_progress >= 0.5:
                last_progress = now
                print(f"\rrsm-replay: {(t_last - t_first) / 1e6:8.1f} s of capture, "
                      f"{records} records, {nbytes} bytes", end="", file=sys.stderr, flush=True)
        if not a.quiet:
            print(f"\rrsm-replay: done: {records} records, {nbytes} bytes"
                  + (f", {(t_last - t_first) / 1e6:.1f} s of capture" if t_first is not None else "")
                  + (f"; {shortened} pauses over {a.max_gap:g} s shortened" if shortened else ""),
                  file=sys.stderr, flush=True)
            tally.report()
        if ptys and a.linger > 0:
            time.sleep(a.linger)
        return 0
    except Stop as exc:
        print(f"\nrsm-replay: stopped by {exc.args[0]} after {records} records, {nbytes} bytes",
              file=sys.stderr, flush=True)
        return 0
    except cap.CaptureError as exc:
        print(f"\nrsm-replay: capture problem after {records} records: {exc}", file=sys.stderr)
        return 1
    except ReaderGone as exc:
        print(f"\nrsm-replay: stopped after {records} records, {nbytes} bytes: {exc}", file=sys.stderr)
        return 1
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        for o in outs.values():
            try:
                o.close()  # type: ignore[attr-defined]
            except Exception:  # noqa: BLE001
                pass
        if reader is not None:
            reader.close()


class LockstepClock:
    """The capture time of the group written last, in a file the reader
    may read (see the module notes)."""

    ENV = "RSM_LOCKSTEP_CLOCK"

    def __init__(self) -> None:
        self.dir = tempfile.TemporaryDirectory(prefix="rsm-lockstep-")
        self.path = os.path.join(self.dir.name, "clock")
        self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_TRUNC, 0o600)
        self.set(0)

    def set(self, t_us: int) -> None:
        os.pwrite(self.fd, int(t_us).to_bytes(8, "little"), 0)

    def environ(self) -> Dict[str, str]:
        return dict(os.environ, **{self.ENV: self.path})

    def close(self) -> None:
        os.close(self.fd)
        self.dir.cleanup()


def run_with(a, reader, outs, ptys, tally: Tally) -> int:
    """Starts the --run program on the ptys and plays into them, in lockstep
    with it when asked; returns the program's failure status, else 0."""
    import subprocess

    paths = {o.name: o.path for o in ptys}
    try:
        cmd = [arg.format(**paths) for arg in a.run]
    except (KeyError, IndexError, ValueError) as exc:
        print(f"rsm-replay: --run: no channel for {exc} in {' '.join(a.run)}", file=sys.stderr)
        return 2
    clock = LockstepClock() if a.lockstep else None
    try:
        child = subprocess.Popen(cmd, env=clock.environ() if clock is not None else None)
    except OSError as exc:
        print(f"rsm-replay: cannot start {cmd[0]}: {exc}", file=sys.stderr)
        if clock is not None:
            clock.close()
        return 1
    step = None
    records = nbytes = groups = 0
    status: Optional[int] = None
    for o in ptys:
        os.set_blocking(o.master, False)

    def write_to(out, data: bytes) -> None:
        """Writes all of data, waiting while the pty is full, unless the reader has ended."""
        view = memoryview(data)
        while view:
            try:
                view = view[os.write(out.master, view):]
            except BlockingIOError:
                if child.poll() is not None:
                    raise ls.ReaderGone(0) from None
                select.select([], [out.master], [], 0.1)

    try:
        if a.lockstep:
            step = ls.Lockstep(child.pid, [o.slave for o in ptys], stall_s=a.stall, names=[o.name for o in ptys])
        group: List[cap.Record] = []

        start = time.monotonic()
        t_first: Optional[int] = None

        def flush() -> None:
            nonlocal records, nbytes, groups, t_first
            if not group:
                return
            if step is not None:
                step.hold()
                clock.set(group[0].timestamp)  # type: ignore[union-attr]
            elif not a.fast:  # recorded timing, scaled
                if t_first is None:
                    t_first = group[0].timestamp
                delay = start + (group[0].timestamp - t_first) / 1e6 / a.speed - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
            written = {o.name: 0 for o in ptys}
            for rec in group:
                out = outs[rec.channel]
                write_to(out, rec.data)
                tally.feed(rec)
                written[out.name] += len(rec.data)  # type: ignore[attr-defined]
                records += 1
                nbytes += len(rec.data)
            if step is not None:
                step.release([written[o.name] for o in ptys])
            groups += 1
            group.clear()

        for rec in played(reader, outs, a.records):
            if group and rec.timestamp != group[0].timestamp:
                flush()
            group.append(rec)
        flush()
        if step is not None:
            step.detach()
            status = step.status
        if not a.quiet:
            print(f"rsm-replay: done: {records} records, {nbytes} bytes in {groups} groups"
                  + (f", lockstep with {step.retries} retries" if step is not None else ""),
                  file=sys.stderr, flush=True)
            tally.report()
        if a.linger > 0:
            time.sleep(a.linger)
    except ls.ReaderGone as exc:
        status = exc.status if step is not None and step.status is not None else None
        print(f"rsm-replay: {cmd[0]} ended after {records} records", file=sys.stderr)
    except ls.LockstepError as exc:
        print(f"rsm-replay: lockstep: {exc}", file=sys.stderr)
        child.kill()
        status = None
    finally:
        for o in outs.values():
            o.close()  # type: ignore[attr-defined]
        outs.clear()
        if clock is not None:
            clock.close()
    if status is None:
        rc = child.wait()
    else:  # reaped by the lockstep's waitpid
        rc = child.returncode = os.waitstatus_to_exitcode(status)
    if rc != 0:
        print(f"rsm-replay: {cmd[0]} exited with status {rc}", file=sys.stderr)
    return rc if rc > 0 else (1 if rc < 0 else 0)


if __name__ == "__main__":
    sys.exit(main())
