"""rsm-m4: runs the Cortex-M4F firmware images under QEMU (mps2-an386) and checks them.

    python3 tools/rsm_tools/m4.py example ELF WORKDIR
    python3 tools/rsm_tools/m4.py example-ld06 ELF WORKDIR
    python3 tools/rsm_tools/m4.py example-rplidar ELF WORKDIR
    python3 tools/rsm_tools/m4.py example-rplidar-answered ELF WORKDIR
    python3 tools/rsm_tools/m4.py replay ELF HOST_EXE WORKDIR [--machine mps2-an385]
    python3 tools/rsm_tools/m4.py costs ELF [--machine mps2-an385]
    python3 tools/rsm_tools/m4.py size ELF --ram-max BYTES
    python3 tools/rsm_tools/m4.py mapflash ELF HOST_EXE REPLAY_HOST_EXE WORKDIR
    python3 tools/rsm_tools/m4.py mapstore ELF HOST_EXE REPLAY_HOST_EXE WORKDIR
    python3 tools/rsm_tools/m4.py profile ELF [--top N]

``example`` boots the example firmware with its two device ports on files and
checks the banner, the end-of-run summary and that the P3-DX handshake went
out on the robot port (SYNC0, repeated after each step timeout, which needs
SysTick interrupts) and something on the laser port.  ``example-ld06`` boots
the example built for an LD06 (RSM_FIRMWARE_LASER) with LD06 packets of a
head turning at 10 Hz in a 4 m square room on the laser port (a named pipe,
read by QEMU as the UART takes bytes): the banner names the LD06, the
firmware sends nothing on the laser port (the sensor takes no commands),
loses no byte, and turns the packets into scans; how many bytes QEMU hands
the UART per emulated millisecond is QEMU's business, so only "at least
one scan" is asserted, with a wide margin (about 9 of the 20 turns sent).
``example-rplidar`` boots the example built for an RPLIDAR with nothing
answering on the laser port: the driver's start-up goes out there and, the
unit silent, repeats on its own timers (STOP, GET_HEALTH sent three times,
then after the back-off STOP and GET_HEALTH again), timers that run on
SysTick.  ``example-rplidar-answered`` boots the same image with its laser
UART on the pseudo-terminal of ``rsm-fakedev --rplidar``, which answers
each request as the sensor does and streams the nodes of a head turning at
5 Hz in its ray-cast room: the fake must hear the driver's start-up in
order (STOP, GET_HEALTH, GET_INFO, GET_SAMPLERATE, SCAN; a request repeated
after a late answer counts once, and attempts cut short before the one that
started the scan, as a stalled host can cause, are allowed), and the
firmware must lose no byte and
assemble at least one scan.  The fake answers and streams in the host's
time, so this run lets the board's clock follow the host's while it idles
(``-icount sleep=on``); how many scans it gets then depends on the machine,
and only "at least one" is asserted.  ``replay`` boots the
replay firmware, checks its start-up, the instruction-count calibration (the
known loop) and that its trajectory equals the host's (``HOST_EXE``, the same
source built for the host) bit for bit; ``--machine mps2-an385`` runs the
Cortex-M3 build (soft float, rsm_replay_m3.elf) on QEMU's M3 board, the
same memory map and devices.  ``costs`` runs a replay image and prints
its instructions per scan (mean, p95, p99, max, each stage's mean; the
encoder steps included), the bench's figures for one image.  ``size`` prints an image's flash and RAM and
fails when the RAM is over ``--ram-max`` (the Cortex-M0+ image, which no
emulated board here runs).  Both fail on a fault report, a
non-zero exit status or a time-out: a locked-up image never hangs the test.
``profile`` runs an image once with QEMU's log of every block it executes
and prints the instructions spent in each function (a minute for the
replay; for finding where a scan's instructions go).

``mapflash`` boots the map-in-flash firmware (port/baremetal/mapflash) with
QEMU's resets allowed: its first boot must refuse the region (no map there),
map, save a map of N > 0 bytes and reset the system; the second boot, in the
same QEMU run, must load the same bytes, tiles and pose and localize, the map
frozen; both boots' lines must match ``HOST_EXE`` (rsm-mapflash-host, both
boots on the host) within MAPFLASH_HOST_TOL, and the localized poses must stay
within MAPFLASH_MAPPER_TOL of the uninterrupted mapping run
(``REPLAY_HOST_EXE``, rsm-replay-host) at the same scans.  Then the second
boot searches the map globally (``G`` and ``GE`` lines, mapflash.h): its
scans must have the host's outcomes and reads (``search_work``) and end the
same way, the last pose within MAPFLASH_HOST_TOL of the host's and, when
proven, within MAPFLASH_MAPPER_TOL of the uninterrupted run's; the check
prints the search's worst and mean instructions per scan on the M4 (the
target's clock ticks around each ``rsm_localizer_scan``, converted as the
replay's after the same calibration) and the scans to the proven pose.
``mapstore`` does the same with the image whose core has a pool smaller than
the excerpt's map (rsm_mapstore_m4.elf, rsm-mapstore-host): its mapping is
compared with the uninterrupted run within MAPFLASH_MAPPER_TOL (a pool that
lets tiles go clears less), and its ``T`` lines must show the map outgrowing
the pool while mapping, tiles taken back from flash while localizing, none
lost, the same on host and target.

QEMU runs with ``-icount shift=ICOUNT_SHIFT,sleep=off``: the virtual clock
advances exactly 2^shift ns per executed instruction, so the board's 25 MHz
timer counts one tick per 40 / 2^shift instructions, the same on every
machine, and idle time (WFI) is skipped (but for ``example-rplidar-answered``,
see above).  Python standard library only, so that ctest can run it with any
python3 (``rsm-fakedev`` too); ``rsm_tools.bench`` imports it.
"""

import argparse
import json
import math
import os
import re
import shutil
import statistics
import struct
import subprocess
import sys
import threading
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

ICOUNT_SHIFT = 3
TIMER_HZ = 25_000_000  # mps2-an386 SYSCLK, which clocks its APB timers
NS_PER_TICK = 1e9 / TIMER_HZ
INSNS_PER_TICK = NS_PER_TICK / (1 << ICOUNT_SHIFT)  # 5 at shift 3
TIMEOUT_S = 300
SYNC0 = bytes([0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00])  # ARIA SYNC0 packet (docs protocols.md 1.6)
STAGES = ("points", "grid", "harris", "match", "ransac", "refine", "icp", "ekf", "map", "mapmatch")
# The encoder steps (rsm_localizer_ticks) since the previous scan: the T
# lines' last field, outside the localizer's step time and added to it here.
ODOMETRY = "odometry"
MACHINE = "mps2-an386"      # Cortex-M4F
MACHINE_M3 = "mps2-an385"   # the same board with a Cortex-M3: no FPU, the soft-float images


class M4Error(RuntimeError):
    """A run or a check failed."""


def qemu_command(elf: Path, serial_files: Sequence[Path] = (), pipe: Optional[Path] = None,
                 tty: Optional[str] = None, machine: str = MACHINE) -> List[str]:
    """Console on stdio, then one UART per serial file (output only), then,
    with ``pipe``, one on the named pipes PIPE.in (input) and PIPE.out, or,
    with ``tty``, one on that terminal (a pseudo-terminal a device answers
    on; QEMU sets its rate as the firmware sets the UART's).  With a tty the
    virtual clock follows the host's while the board idles (``sleep=on``):
    the device on the other end answers and streams in the host's time."""
    qemu = shutil.which("qemu-system-arm")
    if qemu is None:
        raise M4Error("qemu-system-arm not found (Debian: qemu-system-arm; ./tools/test installs it)")
    cmd = [qemu, "-M", machine, "-kernel", str(elf), "-display", "none", "-monitor", "none",
           "-serial", "stdio"]
    for f in serial_files:
        cmd += ["-serial", f"file:{f}"]
    if pipe is not None:
        cmd += ["-chardev", f"pipe,id=fed,path={pipe}", "-serial", "chardev:fed"]
    if tty is not None:
        cmd += ["-chardev", f"serial,id=dev,path={tty}", "-serial", "chardev:dev"]
    cmd += ["-semihosting-config", "enable=on,target=native",
            "-icount", f"shift={ICOUNT_SHIFT},sleep={'on' if tty else 'off'}", "-no-reboot"]
    return cmd


def run(elf: Path, serial_files: Sequence[Path] = (), timeout: float = TIMEOUT_S,
        pipe: Optional[Path] = None, tty: Optional[str] = None, machine: str = MACHINE) -> str:
    """Console output of one run; M4Error unless it ended by itself with status 0."""
    cmd = qemu_command(elf, serial_files, pipe, tty, machine)
    try:
        res = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, timeout=timeout)
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"").decode(errors="replace")
        raise M4Error(f"{elf.name}: no exit within {timeout:.0f} s (locked up?); output so far:\n{out[-2000:]}")
    out = res.stdout.decode(errors="replace")
    if "FAULT" in out or res.returncode != 0:
        raise M4Error(f"{elf.name}: exit status {res.returncode}\n{out[-2000:]}\n"
                      f"{res.stderr.decode(errors='replace')[-2000:]}")
    return out


def lines_of(text: str, tag: str) -> List[List[str]]:
    return [l.split()[1:] for l in text.splitlines() if l.startswith(tag + " ")]


def check_console(out: str, laser: str) -> None:
    """The example's banner names the board and laser; its run ended with a summary."""
    if f"rsm example firmware on mps2-an386, laser: {laser}\n" not in out:
        raise M4Error(f"no banner naming the {laser} in:\n{out}")
    if "rsm example firmware: ran " not in out:
        raise M4Error(f"no end-of-run summary in:\n{out}")


def boot_example(elf: Path, work: Path, laser: str) -> Tuple[str, bytes, bytes]:
    """One run of an example image with its robot and laser ports on files:
    (console, robot port bytes, laser port bytes)."""
    work.mkdir(parents=True, exist_ok=True)
    robot, port = work / "robot.bin", work / "laser.bin"
    for f in (robot, port):
        f.unlink(missing_ok=True)
    out = run(elf, [robot, port])
    check_console(out, laser)
    return out, robot.read_bytes(), port.read_bytes()


def check_example(elf: Path, work: Path) -> str:
    _, sent, laser_sent = boot_example(elf, work, "LMS 2xx")
    n_sync = sent.count(SYNC0)
    # step_timeout_us is 1 s: SYNC0 at 0, 1, 2 and 3 s of the 3.5 s run.
    if n_sync < 3 or sent != SYNC0 * n_sync:
        raise M4Error(f"robot port: expected SYNC0 repeated at least 3 times, got {sent.hex()}")
    if not laser_sent.startswith(b"\x02"):
        raise M4Error(f"laser port: expected an LMS telegram (STX), got {laser_sent[:16].hex()}")
    return f"example: booted, {n_sync} SYNC0 on the robot port, {len(laser_sent)} bytes on the laser port"


def ld06_room(turns: int) -> bytes:
    """LD06 packets of a head turning clockwise at 10 Hz, one point a degree,
    in the middle of a 4 m square room."""
    try:
        from . import lidarstream
    except ImportError:  # run as a script: the package is beside this file
        sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
        from rsm_tools import lidarstream
    out = bytearray()
    for k in range(turns * lidarstream.POINTS_PER_TURN // lidarstream.LD06_POINTS):
        first = (k * lidarstream.LD06_POINTS) % lidarstream.POINTS_PER_TURN
        pts = []
        for a in range(first, first + lidarstream.LD06_POINTS):
            c, s = abs(math.cos(math.radians(a))), abs(math.sin(math.radians(a)))
            pts.append((int(round(2000.0 / max(c, s))), 200))
        out += lidarstream.ld06_packet(3600, first * 100, (first + lidarstream.LD06_POINTS - 1) * 100,
                                       k * 10 // 3, pts)
    return bytes(out)


def check_example_ld06(elf: Path, work: Path, turns: int = 20) -> str:
    work.mkdir(parents=True, exist_ok=True)
    robot, pipe = work / "robot.bin", work / "laser"
    fifo_in, fifo_out = Path(f"{pipe}.in"), Path(f"{pipe}.out")
    for f in (robot, fifo_in, fifo_out):
        f.unlink(missing_ok=True)
    os.mkfifo(fifo_in)
    os.mkfifo(fifo_out)
    sent = ld06_room(turns)
    heard = bytearray()

    def feed() -> None:
        with open(fifo_in, "wb") as fh:   # opens once QEMU opens its end
            try:
                fh.write(sent)
            except BrokenPipeError:
                pass                       # the run ended before taking it all

    def listen() -> None:
        with open(fifo_out, "rb") as fh:
            heard.extend(fh.read())

    threads = [threading.Thread(target=feed, daemon=True), threading.Thread(target=listen, daemon=True)]
    for t in threads:
        t.start()
    out = run(elf, [robot], pipe=pipe)
    for t in threads:
        t.join(timeout=10)
    check_console(out, "LD06")
    ms, scans, overflows = summary_counts(out)
    if not robot.read_bytes().startswith(SYNC0):
        raise M4Error(f"robot port: expected the P3-DX handshake, got {robot.read_bytes()[:16].hex()}")
    if heard:
        raise M4Error(f"laser port: the LD06 takes no commands, but the firmware sent {bytes(heard[:16]).hex()}")
    if overflows != 0 or scans < 1:
        raise M4Error(f"LD06 packets of {turns} turns gave {scans} scans, {overflows} receive overflows:\n{out}")
    return f"example-ld06: booted, {scans} scans from the LD06 port in {ms} ms, nothing sent to it"


RP_STOP, RP_HEALTH = bytes([0xA5, 0x25]), bytes([0xA5, 0x52])  # RPLIDAR requests (docs lidars.md 2)
# STOP, GET_HEALTH, GET_INFO, GET_SAMPLERATE, SCAN: the driver's start-up (src/drivers/slamtec.c)
RP_STARTUP = (0x25, 0x52, 0x50, 0x59, 0x20)


def summary_counts(out: str) -> Tuple[int, int, int]:
    """(ms run, scans, receive overflows) from the example's end-of-run line."""
    m = re.search(r"ran (\d+) ms: encoder events \d+, scans (\d+), receive overflows (\d+)", out)
    if m is None:
        raise M4Error(f"no end-of-run summary in:\n{out}")
    return int(m.group(1)), int(m.group(2)), int(m.group(3))


def fake_rplidar(log: Path) -> Tuple[subprocess.Popen, str]:
    """rsm-fakedev --rplidar (tools/rsm_tools/fakedev.py, its answers and its
    ray-cast room) on a pseudo-terminal: the process and the terminal's path."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(Path(__file__).resolve().parent.parent)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    proc = subprocess.Popen([sys.executable, "-m", "rsm_tools.fakedev", "--rplidar", "--quiet",
                             "--log", str(log), "--seconds", str(TIMEOUT_S)],
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, text=True, env=env)
    line = proc.stdout.readline().split() if proc.stdout is not None else []
    if len(line) != 2 or line[0] != "rplidar":
        proc.kill()
        proc.wait()
        raise M4Error(f"rsm-fakedev --rplidar did not name its terminal (got {line})")
    return proc, line[1]


def check_example_rplidar_answered(elf: Path, work: Path) -> str:
    """The RPLIDAR image against rsm-fakedev's RPLIDAR: the start-up requests
    in order (a request the firmware repeated, had an answer come late, is one
    step), the scan started, and turns of its nodes assembled into scans."""
    work.mkdir(parents=True, exist_ok=True)
    robot, log = work / "robot.bin", work / "fakedev.log"
    for f in (robot, log):
        f.unlink(missing_ok=True)
    fake, tty = fake_rplidar(log)
    try:
        out = run(elf, [robot], tty=tty)
    finally:
        fake.terminate()   # our own child, by its handle
        fake.wait(timeout=30)
    check_console(out, "RPLIDAR")
    ms, scans, overflows = summary_counts(out)
    events = [json.loads(l) for l in log.read_text().splitlines() if l.strip()]
    cmds = [e["cmd"] for e in events if e.get("ev") == "request"]
    steps = [c for i, c in enumerate(cmds) if i == 0 or c != cmds[i - 1]]
    summary = [e for e in events if e.get("ev") == "summary" and e.get("dev") == "rplidar"]
    # The attempt that started the scan must be the whole start-up in order;
    # attempts before it may have been cut short (a host that stalled past
    # the driver's reply timeout makes it start over from STOP).
    first_scan = steps.index(RP_STARTUP[-1]) if RP_STARTUP[-1] in steps else -1
    last_stop = max((i for i, c in enumerate(steps[:first_scan]) if c == RP_STARTUP[0]), default=-1)
    if first_scan < 0 or last_stop < 0 or tuple(steps[last_stop:first_scan + 1]) != RP_STARTUP:
        raise M4Error("the fake RPLIDAR heard " + " ".join(f"{c:02X}" for c in cmds) +
                      ", not STOP, GET_HEALTH, GET_INFO, GET_SAMPLERATE, SCAN")
    if not summary or summary[0].get("bad_requests") != 0 or summary[0].get("garbled_frames") != 0 \
            or summary[0].get("scans_started", 0) < 1:
        raise M4Error(f"the fake RPLIDAR's summary: {summary}")
    if not robot.read_bytes().startswith(SYNC0):
        raise M4Error(f"robot port: expected the P3-DX handshake, got {robot.read_bytes()[:16].hex()}")
    if overflows != 0 or scans < 1:
        raise M4Error(f"the RPLIDAR's nodes ({summary[0].get('node_chunks')} chunks of 12) gave {scans} scans, "
                      f"{overflows} receive overflows:\n{out}")
    return (f"example-rplidar: booted against rsm-fakedev --rplidar, start-up "
            f"{' '.join(f'{c:02X}' for c in steps[last_stop:first_scan + 1])} answered, {scans} scans from "
            f"{summary[0].get('node_chunks')} chunks of nodes in {ms} ms")


def check_example_rplidar(elf: Path, work: Path) -> str:
    _, robot, sent = boot_example(elf, work, "RPLIDAR")
    if not robot.startswith(SYNC0):
        raise M4Error(f"robot port: expected the P3-DX handshake, got {robot[:16].hex()}")
    # reply_timeout 0.5 s, three tries, back-off 1 s: in the 3.5 s run the
    # second start-up has begun
    want = RP_STOP + RP_HEALTH * 3 + RP_STOP + RP_HEALTH
    rest = sent[len(want):]
    if not sent.startswith(want) or rest != RP_HEALTH * (len(rest) // 2):
        raise M4Error(f"laser port: expected STOP, GET_HEALTH x3, STOP, GET_HEALTH..., got {sent.hex()}")
    return f"example-rplidar: booted, the RPLIDAR start-up sent and repeated ({len(sent)} bytes)"


def calibration(out: str) -> Dict[str, float]:
    """The known loop: 2 n instructions; its tick counts must match the model."""
    c = lines_of(out, "C")
    if len(c) != 1 or len(c[0]) != 4:
        raise M4Error(f"no calibration line in the output")
    n1, t1, n2, t2 = (int(v) for v in c[0])
    insns = 2 * (n2 - n1)
    measured = (t2 - t1) * INSNS_PER_TICK
    if abs(measured - insns) > INSNS_PER_TICK:
        raise M4Error(f"calibration: the known loop ran {insns} instructions, the timer says {measured:.0f} "
                      f"(icount shift {ICOUNT_SHIFT}, {INSNS_PER_TICK:g} per tick)")
    return {"insns": insns, "measured": measured, "per_tick": INSNS_PER_TICK}


def check_replay(elf: Path, host_exe: Path, work: Path, machine: str = MACHINE) -> str:
    work.mkdir(parents=True, exist_ok=True)
    out = run(elf, machine=machine)
    (work / "replay-m4.out").write_text(out)
    host = subprocess.run([str(host_exe)], capture_output=True, text=True, timeout=TIMEOUT_S)
    if host.returncode != 0:
        raise M4Error(f"{host_exe.name}: exit status {host.returncode}: {host.stderr}")
    (work / "replay-host.out").write_text(host.stdout)
    if "rsm replay: done" not in out:
        raise M4Error("the replay firmware did not finish")
    if f"rsm replay on {machine}\n" not in out:
        raise M4Error(f"the replay firmware does not name the board {machine} (an image for another core?)")
    cal = calibration(out)
    target_p = [l for l in out.splitlines() if l.startswith(("P ", "E "))]
    host_p = [l for l in host.stdout.splitlines() if l.startswith(("P ", "E "))]
    if not host_p or sum(1 for l in host_p if l.startswith("P ")) == 0:
        raise M4Error("the host replay wrote no pose")
    for i, (a, b) in enumerate(zip(host_p, target_p)):
        if a != b:
            raise M4Error(f"host and target differ first at line {i + 1}:\n  host   {a}\n  target {b}")
    if len(host_p) != len(target_p):
        raise M4Error(f"host wrote {len(host_p)} pose and summary lines, target {len(target_p)}")
    refused = re.search(r"^E .* out_of_order (\d+)", out, re.M)
    if refused is None or int(refused.group(1)) != 0:
        # A refused scan costs next to nothing: the cost figures would time
        # refusals, not steps (the excerpt's stamps are made monotonic).
        raise M4Error(f"the replay refused scans as out of order: {refused.group(0) if refused else 'no E line'}")
    return (f"replay: {len(host_p) - 1} poses equal bit for bit on host and {machine}; calibration "
            f"{cal['insns']} instructions measured as {cal['measured']:.0f}")


MAPFLASH_BANNER = "rsm mapflash on mps2-an386"
MAPFLASH_REFUSALS = (-13, -4, -7)  # RSM_ERR_FORMAT, _CHECKSUM, _IO: what a load of no map says
# Target against host: the same source and float flags, expected bit for bit.
MAPFLASH_HOST_TOL = (1e-3, 1e-3)   # m, rad
# Localizing in the frozen saved map against the mapper carrying on (both on
# the host): about 5 cm and 0.03 rad at worst on the excerpt's corridor.
MAPFLASH_MAPPER_TOL = (0.15, 0.08)  # m, rad
MAPFLASH_MAX_BOOTS = 2
# The map larger than the pool (rsm_mapstore_m4.elf, mapflash.h's
# RSM_MAPFLASH_STORE): its own banner and T lines.
MAPSTORE_BANNER = "rsm mapstore on mps2-an386"


def run_rebooting(elf: Path, banner: str, max_boots: int, timeout: float = 60.0) -> str:
    """Console output of one QEMU run in which the firmware may reset the
    system (no ``-no-reboot``: QEMU then loads the image's segments again
    and restarts it).  Killed at the boot after ``max_boots`` (a reset loop)
    or after ``timeout`` s; M4Error unless it ended by itself with status 0."""
    cmd = [c for c in qemu_command(elf) if c != "-no-reboot"]
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    timer = threading.Timer(timeout, proc.kill)  # our own child, by its handle
    timer.start()
    out: List[str] = []
    boots = 0
    try:
        assert proc.stdout is not None
        for raw in proc.stdout:
            line = raw.decode(errors="replace")
            out.append(line)
            if line.startswith(banner):
                boots += 1
                if boots > max_boots:
                    proc.kill()
                    break
        _, err = proc.communicate()
    finally:
        timer.cancel()
    text = "".join(out)
    if boots > max_boots:
        raise M4Error(f"{elf.name}: more than {max_boots} boots (a reset loop?); output so far:\n{text[-2000:]}")
    if proc.returncode != 0 or "FAULT" in text:
        raise M4Error(f"{elf.name}: exit status {proc.returncode} (killed after {timeout:.0f} s if negative)\n"
                      f"{text[-2000:]}\n{err.decode(errors='replace')[-2000:]}")
    return text


def split_boots(text: str, banner: str) -> List[str]:
    """The console output of each boot, from its banner on."""
    parts = [p for p in re.split(rf"^(?={re.escape(banner)})", text, flags=re.M) if p.startswith(banner)]
    return parts


def mapflash_info(boot: str, tag: str) -> Dict[str, object]:
    """The S saved or L loaded line of a boot: bytes, tiles, stamp, pose bits."""
    m = re.search(rf"^{tag} bytes (\d+) tiles (\d+) stamp (\d+) pose ([0-9a-f]{{8}}) ([0-9a-f]{{8}}) ([0-9a-f]{{8}})$",
                  boot, re.M)
    if m is None:
        raise M4Error(f"no '{tag}' line in:\n{boot[-2000:]}")
    return {"bytes": int(m.group(1)), "tiles": int(m.group(2)), "stamp": int(m.group(3)),
            "pose": (m.group(4), m.group(5), m.group(6))}


def _float_of(h: str) -> float:
    """A float from its IEEE bits in hexadecimal (the images' lines)."""
    return struct.unpack("<f", struct.pack("<I", int(h, 16)))[0]


def pose_lines(text: str) -> List[Tuple[int, int, float, float, float]]:
    """(scan, outcome, x, y, theta) of each P line."""
    f = _float_of
    return [(int(p[0]), int(p[1]), f(p[2]), f(p[3]), f(p[4])) for p in lines_of(text, "P") if len(p) == 5]


def compare_poses(what: str, got: Sequence[Tuple[int, int, float, float, float]],
                  ref: Dict[int, Tuple[int, int, float, float, float]], tol: Tuple[float, float],
                  outcomes: bool) -> Tuple[float, float]:
    """Every pose of got within tol (metres, radians) of ref's at the same
    scan (and the same outcome if asked); returns the largest differences."""
    worst = (0.0, 0.0)
    for p in got:
        r = ref.get(p[0])
        if r is None:
            raise M4Error(f"{what}: scan {p[0]} has no reference pose")
        d = math.hypot(p[2] - r[2], p[3] - r[3])
        a = abs(math.remainder(p[4] - r[4], 2.0 * math.pi))
        if not (d <= tol[0] and a <= tol[1]) or (outcomes and p[1] != r[1]):
            raise M4Error(f"{what}: scan {p[0]} at ({p[2]:.4f}, {p[3]:.4f}, {p[4]:.4f}) outcome {p[1]}, the "
                          f"reference at ({r[2]:.4f}, {r[3]:.4f}, {r[4]:.4f}) outcome {r[1]}: {d:.4f} m, "
                          f"{a:.4f} rad apart (tolerance {tol[0]} m, {tol[1]} rad)")
        worst = (max(worst[0], d), max(worst[1], a))
    return worst


def global_search(boot: str) -> Dict[str, object]:
    """The global search of a mapflash boot: its G lines as (scan, outcome,
    search_work, ticks) and its GE line (proven, scans, budget, pose as floats);
    M4Error when either is missing or they disagree on the scan count."""
    rows = []
    for g in lines_of(boot, "G"):
        if len(g) != 4 or not all(v.isdigit() for v in g):
            raise M4Error(f"a malformed G line: G {' '.join(g)}")
        rows.append(tuple(int(v) for v in g))
    m = re.search(r"^GE proven ([01]) scans (\d+) budget (\d+) pose ([0-9a-f]{8}) ([0-9a-f]{8}) ([0-9a-f]{8})$",
                  boot, re.M)
    if m is None:
        raise M4Error(f"no 'GE' line (the global search's end) in:\n{boot[-2000:]}")
    end = {"proven": m.group(1) == "1", "scans": int(m.group(2)), "budget": int(m.group(3)),
           "pose": tuple(_float_of(m.group(i)) for i in (4, 5, 6))}
    if not rows or end["scans"] != len(rows):
        raise M4Error(f"the global search's end says {end['scans']} scans, {len(rows)} G lines")
    return {"rows": rows, **end}


def compare_global(target: Dict[str, object], host: Dict[str, object], tol: Tuple[float, float]) -> None:
    """Target and host searched alike: the same scans, outcomes and
    search_work (the cost, the target's clock, apart), the same verdict, and
    the last pose within tol (metres, radians)."""
    t_rows = [r[:3] for r in target["rows"]]
    h_rows = [r[:3] for r in host["rows"]]
    for a, b in zip(h_rows, t_rows):
        if a != b:
            raise M4Error(f"global search: host scan {a[0]} outcome {a[1]} search_work {a[2]}, target scan "
                          f"{b[0]} outcome {b[1]} search_work {b[2]}")
    if len(t_rows) != len(h_rows) or target["proven"] != host["proven"] or target["budget"] != host["budget"]:
        raise M4Error(f"global search: host {len(h_rows)} scans (proven {host['proven']}, budget "
                      f"{host['budget']}), target {len(t_rows)} (proven {target['proven']}, budget "
                      f"{target['budget']})")
    tp, hp = target["pose"], host["pose"]
    compare_poses("global search, host", [(0, 0, *tp)], {0: (0, 0, *hp)}, tol, False)


def global_costs(search: Dict[str, object], per_tick: float = INSNS_PER_TICK) -> Dict[str, object]:
    """Instructions per scan of a global search (global_search of a target
    boot, whose C line checked the clock): worst and mean over its scans,
    the proving one included; reads; scans to the first proven pose."""
    insns = [r[3] * per_tick for r in search["rows"]]
    work = [r[2] for r in search["rows"]]
    return {"scans": len(insns), "max": max(insns), "mean": statistics.fmean(insns),
            "max_work": max(work), "work": sum(work), "proven": search["proven"],
            "scans_to_pose": search["scans"] if search["proven"] else None, "budget": search["budget"],
            "last_scan": search["rows"][-1][0], "pose": list(search["pose"])}


def check_mapflash(elf: Path, host_exe: Path, replay_host_exe: Path, work: Path, store: bool = False) -> str:
    return mapflash_run(elf, host_exe, replay_host_exe, work, store)[0]


def store_line(boot: str) -> Dict[str, int]:
    """The T line of a mapstore boot: the store's tiles and the map's counters."""
    m = re.search(r"^T store held (\d+) let_go (\d+) taken (\d+) lost (\d+)$", boot, re.M)
    if m is None:
        raise M4Error(f"no T line:\n{boot[-2000:]}")
    return dict(zip(("held", "let_go", "taken", "lost"), (int(v) for v in m.groups())))


def mapflash_run(elf: Path, host_exe: Path, replay_host_exe: Path, work: Path,
                 store: bool = False) -> Tuple[str, Dict[str, object]]:
    """check_mapflash's checks; returns its summary and the global search's
    figures on the M4 (global_costs). ``store``: the image whose map is
    larger than its pool (mapstore), checked as mapflash and for its T lines."""
    name = "mapstore" if store else "mapflash"
    banner = MAPSTORE_BANNER if store else MAPFLASH_BANNER
    work.mkdir(parents=True, exist_ok=True)
    out = run_rebooting(elf, banner, MAPFLASH_MAX_BOOTS)
    (work / f"{name}-m4.out").write_text(out)
    host = subprocess.run([str(host_exe)], capture_output=True, text=True, timeout=TIMEOUT_S)
    if host.returncode != 0:
        raise M4Error(f"{host_exe.name}: exit status {host.returncode}: {host.stderr}")
    (work / f"{name}-host.out").write_text(host.stdout)
    ref = subprocess.run([str(replay_host_exe)], capture_output=True, text=True, timeout=TIMEOUT_S)
    if ref.returncode != 0:
        raise M4Error(f"{replay_host_exe.name}: exit status {ref.returncode}: {ref.stderr}")
    boots = split_boots(out, banner)
    if len(boots) != 2:
        raise M4Error(f"expected two boots (a reset in between), got {len(boots)}:\n{out[-2000:]}")
    first, second = boots
    host_boots = split_boots(host.stdout, f"rsm {name} on host")
    if len(host_boots) != 2:
        raise M4Error(f"{host_exe.name}: expected two boots, got {len(host_boots)}")
    # First boot: no map in the region, refused; a map saved; the reset asked.
    refused = re.search(r"^L refused (-?\d+) ", first, re.M)
    if refused is None or int(refused.group(1)) not in MAPFLASH_REFUSALS or "L loaded" in first:
        raise M4Error(f"the first boot did not refuse the region (format, checksum or i/o):\n{first[-2000:]}")
    saved = mapflash_info(first, "S saved")
    if not (saved["bytes"] > 0 and saved["tiles"] > 0 and saved["bytes"] == 48 + 40 * saved["tiles"] + 4):
        raise M4Error(f"the first boot saved {saved}: not a map of 48 + 40 n + 4 bytes with n > 0 tiles")
    if not first.rstrip().endswith(f"rsm {name}: saved, resetting"):
        raise M4Error(f"the first boot did not end by resetting:\n{first[-2000:]}")
    # Second boot: the same map loaded, localized, frozen, done.
    if "L refused" in second:
        raise M4Error(f"the second boot refused the region: it did not keep the map over the reset:\n"
                      f"{second[-2000:]}")
    loaded = mapflash_info(second, "L loaded")
    if loaded != saved:
        raise M4Error(f"saved {saved}, loaded {loaded} after the reset")
    end = re.search(r"^E scans (\d+) accepted (\d+) map_bytes (\d+)$", second, re.M)
    target_map, target_loc = pose_lines(first), pose_lines(second)
    if end is None or not second.rstrip().endswith(f"rsm {name}: done"):
        raise M4Error(f"the second boot did not finish:\n{second[-2000:]}")
    if not target_map or not target_loc or int(end.group(1)) != len(target_loc):
        raise M4Error(f"{len(target_map)} poses mapping, {len(target_loc)} localizing, summary {end.group(0)}")
    if int(end.group(3)) != saved["bytes"]:
        raise M4Error(f"the frozen map grew from {saved['bytes']} to {end.group(3)} bytes")
    if target_loc[0][0] != target_map[-1][0] + 1:
        raise M4Error(f"localizing started at scan {target_loc[0][0]}, mapping ended at {target_map[-1][0]}")
    # The host's two boots: the same sizes and pose, and the same poses.
    for tag, tb, hb in (("S saved", first, host_boots[0]), ("L loaded", second, host_boots[1])):
        if mapflash_info(hb, tag) != mapflash_info(tb, tag):
            raise M4Error(f"'{tag}': host {mapflash_info(hb, tag)}, target {mapflash_info(tb, tag)}")
    host_map, host_loc = pose_lines(host_boots[0]), pose_lines(host_boots[1])
    if [p[0] for p in host_map] != [p[0] for p in target_map] or \
            [p[0] for p in host_loc] != [p[0] for p in target_loc]:
        raise M4Error("host and target posed other scans")
    compare_poses("mapping, host", target_map, {p[0]: p for p in host_map}, MAPFLASH_HOST_TOL, True)
    host_worst = compare_poses("localizing, host", target_loc, {p[0]: p for p in host_loc}, MAPFLASH_HOST_TOL, True)
    bits = sum(a == b for a, b in zip(lines_of(out, "P"), lines_of(host.stdout, "P")))
    # The uninterrupted run: mapping is its beginning (the same run, but
    # for a pool that lets tiles go: beams through a place only the store
    # holds do not clear it, rsm/tilestore.h); localizing in the saved map
    # stays near where it carries on.
    mapper = {p[0]: p for p in pose_lines(ref.stdout)}
    compare_poses("mapping, rsm-replay-host", target_map, mapper,
                  MAPFLASH_MAPPER_TOL if store else MAPFLASH_HOST_TOL, not store)
    stored = ""
    if store:
        # The map outgrew the pool while mapping and was saved whole; the
        # second boot took tiles back from flash, and the host did the same.
        t_map, t_loc = store_line(first), store_line(second)
        if t_map != store_line(host_boots[0]) or t_loc != store_line(host_boots[1]):
            raise M4Error(f"store: target {t_map}, {t_loc}; host {store_line(host_boots[0])}, "
                          f"{store_line(host_boots[1])}")
        if not (t_map["let_go"] > 0 and t_map["lost"] == 0 and t_map["held"] > 0
                and saved["tiles"] > t_map["held"]):
            raise M4Error(f"mapping: the map never outgrew the pool, or tiles were lost: {t_map}")
        if not (t_loc["held"] > 0 and t_loc["taken"] > 0 and t_loc["lost"] == 0):
            raise M4Error(f"localizing: no tile came back from flash, or tiles were lost: {t_loc}")
        stored = (f"; the pool held {saved['tiles'] - t_map['held']} of the map's {saved['tiles']} tiles when it "
                  f"was saved, localizing took {t_loc['taken']} back from flash")
    worst = compare_poses("localizing, the uninterrupted run", target_loc, mapper, MAPFLASH_MAPPER_TOL, False)
    # The global search in the loaded map: as the host's, and where it proves
    # a pose, near the uninterrupted run's at that scan.
    calibration(second)
    t_search, h_search = global_search(second), global_search(host_boots[1])
    if any(r[3] != 0 for r in h_search["rows"]):
        raise M4Error("the host's global search lines have a cost: the host has no clock to time them")
    compare_global(t_search, h_search, MAPFLASH_HOST_TOL)
    cost = {**global_costs(t_search), "map_bytes": saved["bytes"], "map_tiles": saved["tiles"],
            "mapped_scans": len(target_map)}
    if cost["proven"]:
        last = (cost["last_scan"], 0, *cost["pose"])
        compare_poses("global search, the uninterrupted run", [last], mapper, MAPFLASH_MAPPER_TOL, False)
    found = (f"a pose proven after {cost['scans']} scans" if cost["proven"]
             else f"no pose proven within {cost['scans']} scans")
    summary = (f"{name}: first boot refused the region ({refused.group(1)}), mapped {len(target_map)} scans, "
               f"saved {saved['bytes']} bytes ({saved['tiles']} tiles), reset; second boot loaded the same and "
               f"localized {len(target_loc)} scans in the frozen map: {bits} of {len(target_map) + len(target_loc)} "
               f"poses equal the host's bit for bit (largest difference {host_worst[0]:.2g} m, {host_worst[1]:.2g} "
               f"rad), within {worst[0]:.3f} m and {worst[1]:.3f} rad of the uninterrupted run; then a global search "
               f"in the map loaded again, as the host's: {found} ({cost['work']} reads, at most {cost['max_work']} "
               f"in one scan), instructions per scan on the M4 worst {cost['max']:.0f}, mean {cost['mean']:.0f}"
               f"{stored}")
    return summary, cost


def image_size(elf: Path) -> Dict[str, int]:
    """Berkeley sizes of an image (arm-none-eabi-size): flash = text + data,
    RAM = data + bss, the linker scripts' stack reserved in bss."""
    size = shutil.which("arm-none-eabi-size")
    if size is None:
        raise M4Error("arm-none-eabi-size not found (Debian: binutils-arm-none-eabi)")
    res = subprocess.run([size, str(elf)], capture_output=True, text=True)
    vals = res.stdout.splitlines()[-1].split() if res.returncode == 0 and res.stdout.strip() else []
    if len(vals) < 3 or not all(v.isdigit() for v in vals[:3]):
        raise M4Error(f"arm-none-eabi-size {elf} gave no sizes: {res.stderr}")
    text, data, bss = (int(v) for v in vals[:3])
    return {"text": text, "data": data, "bss": bss, "flash": text + data, "ram": data + bss}


def check_size(elf: Path, ram_max: int) -> str:
    """An image that only links (no emulator runs its core): its sizes, and
    M4Error when its RAM is over ram_max bytes."""
    s = image_size(elf)
    what = f"{elf.name}: flash {s['flash']} bytes, RAM {s['ram']} bytes (stack included)"
    if s["ram"] > ram_max:
        raise M4Error(f"{what}: over {ram_max}")
    return f"{what}, at most {ram_max}"


def percentile(values: Sequence[float], q: float) -> float:
    """Nearest-rank percentile (q in 0..100)."""
    s = sorted(values)
    k = max(0, min(len(s) - 1, int(-(-q * len(s) // 100)) - 1))
    return s[k]


def costs(out: str) -> dict:
    """Instructions per scan and per stage from a replay run's T lines: a
    scan's cost is its localizer step plus the encoder steps since the
    previous scan (the stage ``odometry``)."""
    t = lines_of(out, "T")
    if not t:
        raise M4Error("no T lines in the replay output")
    if any(len(r) != 3 + len(STAGES) for r in t):
        raise M4Error(f"a T line without {len(STAGES)} stages and the encoder steps (an older image?)")
    steps = [(int(r[1]) + int(r[-1])) * INSNS_PER_TICK for r in t]
    stages = {name: statistics.fmean(int(r[2 + i]) * INSNS_PER_TICK for r in t) for i, name in enumerate(STAGES)}
    stages[ODOMETRY] = statistics.fmean(int(r[-1]) * INSNS_PER_TICK for r in t)
    m = lines_of(out, "M")
    stack = int(m[0][1]) if m else None
    stack_size = int(m[0][3]) if m else None
    return {"scans": len(steps), "mean": statistics.fmean(steps), "p95": percentile(steps, 95),
            "p99": percentile(steps, 99), "max": max(steps), "stages": stages,
            "stack_used": stack, "stack_size": stack_size, "calibration": calibration(out)}


def format_costs(c: dict) -> str:
    """costs' figures, one line each: the statistics, then every stage's mean."""
    out = [f"{k} {round(c[k])}" for k in ("mean", "p95", "p99", "max")]
    out += [f"stage {k} {round(v)}" for k, v in c["stages"].items() if v > 0]
    return "\n".join([f"scans {c['scans']} (instructions per scan, encoder steps included)"] + out)


def profile_log(lines: Iterable[str]) -> Dict[str, int]:
    """Instructions executed per function, from QEMU's log of translated
    blocks and their executions (``-d in_asm,exec,nochain``): each block's
    instruction count (its ``IN:`` listing) times the times it ran (its
    ``Trace`` lines), summed by the function the block starts in. Inlined
    code counts in its caller. A block translated again at the same address
    (after an I/O access, under ``-icount``) counts at its last size."""
    size: Dict[int, int] = {}
    name: Dict[int, str] = {}
    runs: Dict[int, int] = {}
    block: Optional[int] = None
    func: Optional[str] = None
    for line in lines:
        if line.startswith("IN:"):
            func, block = line[3:].strip() or "?", None
        elif line.startswith("0x") and func is not None:
            pc = int(line.split(":", 1)[0], 16)
            if block is None:
                block, size[pc], name[pc] = pc, 0, func
            size[block] += 1
        elif line.startswith("Trace"):
            func = block = None
            fields = line.split("[", 1)[1].split("/") if "[" in line else []
            if len(fields) > 1:
                pc = int(fields[1], 16)
                runs[pc] = runs.get(pc, 0) + 1
        elif not line.strip():
            func = block = None
    per: Dict[str, int] = {}
    for pc, n in runs.items():
        key = name.get(pc, f"{pc:#x}")
        per[key] = per.get(key, 0) + n * size.get(pc, 0)
    return per


def profile(elf: Path, timeout: float = 20 * TIMEOUT_S, machine: str = MACHINE) -> Dict[str, int]:
    """profile_log of one run of a firmware image (its console discarded):
    slow (the log has a line per block executed), for finding where the
    instructions go, not for the figures the bench prints."""
    cmd = ["null" if c == "stdio" else c for c in qemu_command(elf, machine=machine)]
    cmd += ["-d", "in_asm,exec,nochain", "-D", "/dev/stdout"]
    with subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                          text=True, errors="replace") as proc:
        assert proc.stdout is not None
        try:
            per = profile_log(proc.stdout)
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise M4Error(f"{elf.name}: no exit within {timeout:.0f} s under the profile")
    if proc.returncode != 0:
        raise M4Error(f"{elf.name}: exit status {proc.returncode} under the profile")
    return per


def format_profile(per: Dict[str, int], top: int = 25) -> str:
    total = sum(per.values())
    rows = sorted(per.items(), key=lambda kv: -kv[1])[:top]
    out = [f"{n:>12,} {100.0 * n / total:5.1f} %  {f}" for f, n in rows] if total else []
    return "\n".join(out + [f"{total:>12,} in all"])


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-m4", description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("example", help="boot the example firmware and check it")
    e.add_argument("elf", type=Path, help="the example firmware image (rsm_firmware.elf)")
    e.add_argument("work", type=Path, help="folder for the devices' files and the console output")
    e6 = sub.add_parser("example-ld06", help="boot the example firmware built for an LD06, feed it packets")
    e6.add_argument("elf", type=Path, help="the example firmware image built for an LD06")
    e6.add_argument("work", type=Path, help="folder for the devices' files and the console output")
    e7 = sub.add_parser("example-rplidar", help="boot the example firmware built for an RPLIDAR")
    e7.add_argument("elf", type=Path, help="the example firmware image built for an RPLIDAR")
    e7.add_argument("work", type=Path, help="folder for the devices' files and the console output")
    e8 = sub.add_parser("example-rplidar-answered",
                        help="boot the example firmware built for an RPLIDAR against rsm-fakedev --rplidar")
    e8.add_argument("elf", type=Path, help="the example firmware image built for an RPLIDAR")
    e8.add_argument("work", type=Path, help="folder for the devices' files, the fake's log and the console output")
    r = sub.add_parser("replay", help="run the replay firmware and compare with the host")
    r.add_argument("elf", type=Path, help="the replay firmware image (rsm_replay_m4.elf)")
    r.add_argument("host_exe", type=Path, help="rsm-replay-host, whose trajectory the target's must equal")
    r.add_argument("work", type=Path, help="folder for the outputs")
    r.add_argument("--machine", default=MACHINE, help=f"QEMU machine (default {MACHINE}; {MACHINE_M3} for the "
                   "Cortex-M3 image, rsm_replay_m3.elf)")
    co = sub.add_parser("costs", help="run a replay image and print its instructions per scan, per stage")
    co.add_argument("elf", type=Path, help="a replay image, e.g. rsm_replay_m3.elf")
    co.add_argument("--machine", default=MACHINE, help=f"QEMU machine (default {MACHINE}; {MACHINE_M3} for the "
                    "soft-float images)")
    sz = sub.add_parser("size", help="an image's flash and RAM (stack included); fails over --ram-max")
    sz.add_argument("elf", type=Path, help="a firmware image, e.g. rsm_firmware_rp2040_ld06.elf")
    sz.add_argument("--ram-max", type=int, required=True, help="bytes of RAM the image may take at most")
    mf = sub.add_parser("mapflash", help="run the map-in-flash firmware over its reset and compare with the host")
    mf.add_argument("elf", type=Path, help="the map-in-flash firmware image (rsm_mapflash_m4.elf)")
    mf.add_argument("host_exe", type=Path, help="rsm-mapflash-host, both boots on the host")
    mf.add_argument("replay_host_exe", type=Path, help="rsm-replay-host, the uninterrupted run")
    mf.add_argument("work", type=Path, help="folder for the outputs")
    ms = sub.add_parser("mapstore", help="the same for the image whose map is larger than its pool")
    ms.add_argument("elf", type=Path, help="the image (rsm_mapstore_m4.elf)")
    ms.add_argument("host_exe", type=Path, help="rsm-mapstore-host, both boots on the host")
    ms.add_argument("replay_host_exe", type=Path, help="rsm-replay-host, the uninterrupted run")
    ms.add_argument("work", type=Path, help="folder for the outputs")
    pr = sub.add_parser("profile", help="instructions per function of one run (QEMU's block log; slow)")
    pr.add_argument("elf", type=Path, help="a firmware image, e.g. rsm_replay_m4.elf")
    pr.add_argument("--top", type=int, default=25, help="functions to print (default 25)")
    pr.add_argument("--machine", default=MACHINE, help=f"QEMU machine (default {MACHINE})")
    a = ap.parse_args(argv)
    try:
        if a.cmd == "example":
            print(check_example(a.elf, a.work))
        elif a.cmd == "example-ld06":
            print(check_example_ld06(a.elf, a.work))
        elif a.cmd == "example-rplidar":
            print(check_example_rplidar(a.elf, a.work))
        elif a.cmd == "example-rplidar-answered":
            print(check_example_rplidar_answered(a.elf, a.work))
        elif a.cmd in ("mapflash", "mapstore"):
            print(check_mapflash(a.elf, a.host_exe, a.replay_host_exe, a.work, a.cmd == "mapstore"))
        elif a.cmd == "profile":
            print(format_profile(profile(a.elf, machine=a.machine), a.top))
        elif a.cmd == "costs":
            print(format_costs(costs(run(a.elf, machine=a.machine))))
        elif a.cmd == "size":
            print(check_size(a.elf, a.ram_max))
        else:
            print(check_replay(a.elf, a.host_exe, a.work, a.machine))
    except M4Error as err:
        print(f"rsm-m4: FAIL: {err}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
