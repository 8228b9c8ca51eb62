"""rsm-record: record serial ports (real devices or ptys) into a capture file.

    rsm-record OUT.cap --port CHANNEL=DEVICE@BAUD[:protocol] ... [--seconds N]
                [--meta KEY=VALUE ...] [--quiet]

Every chunk of bytes read from a port becomes one rx record stamped with the
time it was read (microseconds since the Unix epoch, kept monotonic).  The
protocol (``aria``, ``lms2xx``, ``ld06``, ``rplidar`` or ``raw``; default
``raw``) is written into the capture's header and names the channel's
decoder, which drives the live counter on stderr: bytes, decoded frames
(ARIA packets, LMS telegrams, LD06 packets, RPLIDAR answers and nodes or
capsules) and the candidates that failed their checksum or CRC.

Stop with Ctrl-C or SIGTERM (exit status 0): every record read so far is in
the file (each is flushed as it is written).  A port that cannot be opened:
exit status 1 and no file is written.  A port that fails or vanishes during
the run: a message naming it and exit status 1, with the records already
written intact.  A bad command line: 2 (the C tools' convention).
"""

import argparse
import select
import signal
import sys
import time
from typing import List, Optional, Sequence, Tuple

from . import capture as cap
from .protocols import FrameCounter

EXIT_OPEN = 1
EXIT_VANISHED = 1


class Stop(Exception):
    pass


def _raise_stop(signum, frame):  # noqa: ARG001
    raise Stop(signal.Signals(signum).name)


def parse_port(spec: str) -> Tuple[str, str, int, str]:
    """``CHANNEL=DEVICE@BAUD[:protocol]`` -> (channel, device, baud, protocol)."""
    if "=" not in spec or "@" not in spec:
        raise ValueError(f"--port wants CHANNEL=DEVICE@BAUD[:protocol], got {spec!r}")
    name, rest = spec.split("=", 1)
    device, rest = rest.rsplit("@", 1)
    proto = "raw"
    if ":" in rest:
        rest, proto = rest.split(":", 1)
    if proto not in cap.PROTOCOLS:
        raise ValueError(f"unknown protocol {proto!r} in {spec!r} ({', '.join(cap.PROTOCOLS)})")
    try:
        baud = int(rest)
    except ValueError:
        raise ValueError(f"bad baud rate {rest!r} in {spec!r}") from None
    if not name or not device or baud <= 0:
        raise ValueError(f"bad --port {spec!r}")
    return name, device, baud, proto


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-record", description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="capture file to write")
    ap.add_argument("--port", action="append", required=True,
                    metavar="CHANNEL=DEVICE@BAUD[:protocol]",
                    help="a port to record as channel CHANNEL (robot, laser, ...) at BAUD; protocol aria, "
                         "lms2xx, ld06, rplidar or raw (default) names its decoder for the live counter "
                         "and goes into the capture's header; once per port")
    ap.add_argument("--seconds", type=float, help="stop after this many seconds")
    ap.add_argument("--meta", action="append", default=[], metavar="KEY=VALUE",
                    help="a metadata line for the capture's header (repeatable)")
    ap.add_argument("--quiet", action="store_true", help="print only errors (no live counter)")
    a = ap.parse_args(argv)
    try:
        specs = [parse_port(s) for s in a.port]
    except ValueError as exc:
        ap.error(str(exc))
    if len({s[0] for s in specs}) != len(specs):
        ap.error("channel names must be unique")
    meta = {}
    for kv in a.meta:
        if "=" not in kv:
            ap.error(f"--meta wants KEY=VALUE, got {kv!r}")
        k, v = kv.split("=", 1)
        meta[k] = v

    import serial  # pyserial, the package's runtime dependency

    signal.signal(signal.SIGTERM, _raise_stop)
    signal.signal(signal.SIGINT, _raise_stop)
    ports: List = []
    writer = None
    status = 0
    counters = [FrameCounter(p) for _, _, _, p in specs]
    nbytes = [0] * len(specs)

    def show(final: bool = False) -> None:
        parts = [f"{specs[i][0]} {nbytes[i]} B {counters[i].describe()}" for i in range(len(specs))]
        print("\rrsm-record: " + " | ".join(parts), end="\n" if final else "",
              file=sys.stderr, flush=True)

    try:
        for name, device, baud, _ in specs:
            try:
                ports.append(serial.Serial(device, baudrate=baud, timeout=0))
            except (serial.SerialException, OSError, ValueError) as exc:
                print(f"rsm-record: cannot open port {name} ({device}): {exc}", file=sys.stderr)
                return EXIT_OPEN
        channels = [cap.Channel(i, n, p, b) for i, (n, _, b, p) in enumerate(specs)]
        t0_wall = time.time_ns() // 1000
        t0_mono = time.monotonic_ns() // 1000
        meta.setdefault("created_by", "rsm-record")
        meta.setdefault("time.start_unix_us", str(t0_wall))
        writer = cap.CaptureWriter(a.out, channels, meta)
        if not a.quiet:
            for (name, device, baud, proto) in specs:
                print(f"rsm-record: recording {name} from {device} at {baud} Bd ({proto})",
                      file=sys.stderr, flush=True)
        fds = {p.fileno(): i for i, p in enumerate(ports)}
        last_show = 0.0
        end = time.monotonic() + a.seconds if a.seconds else None

        while end is None or time.monotonic() < end:
            ready, _, _ = select.select(list(fds), [], [], 0.1)
            for fd in ready:
                i = fds[fd]
                try:
                    data = ports[i].read(max(ports[i].in_waiting, 1))
                except (serial.SerialException, OSError) as exc:
                    writer.close()
                    print(f"\nrsm-record: port {specs[i][0]} ({specs[i][1]}) failed or vanished: "
                          f"{exc}; {writer.records} records already written are intact in {a.out}",
                          file=sys.stderr)
                    return EXIT_VANISHED
                if data:
                    ts = t0_wall + (time.monotonic_ns() // 1000 - t0_mono)
                    # counted first: once a chunk is in the file, the counters have it
                    nbytes[i] += len(data)
                    counters[i].feed(data)
                    writer.write(ts, i, data)
            now = time.monotonic()
            if not a.quiet and now - last_show >= 0.5:
                last_show = now
                show()
        if not a.quiet:
            show(True)
    except Stop as exc:
        if not a.quiet:
            print(f"\nrsm-record: stopped by {exc.args[0]}", file=sys.stderr)
            show(True)  # the final counts, whatever the live line last showed
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        if writer is not None:
            writer.close()
            if not a.quiet:
                print(f"rsm-record: {writer.records} records, {writer.bytes} bytes in {a.out}",
                      file=sys.stderr, flush=True)
        for p in ports:
            try:
                p.close()
            except Exception:  # noqa: BLE001
                pass
    return status


if __name__ == "__main__":
    sys.exit(main())
