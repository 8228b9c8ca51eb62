"""rsm-sim: a small 2-D world, a scripted drive, and the serial bytes a P3-DX and an LMS would send.

    rsm-sim OUT.cap --truth OUT.txt [--world rooms|corridor|pillars|hall|building] [--seconds N]
            [--slip X] [--range-noise M] [--outliers P] [--seed S]
            [--carmen] [--laser-pose X Y THETA] [--upside-down]
            [--lidar ld06|rplidar] [--drive loop|curves]

The world is line segments and circles.  The robot follows a closed loop of
waypoints at 0.4 m/s (turning on the spot at each corner), integrated at
100 Hz.  Every 100 ms it emits an ENCODER packet (P3-DX, 128000 ticks/m,
wheel base 0.357 m); every 200 ms a 181-reading LMS 0xB0 scan in mm (180 deg
at 1 deg, max range 8 m, 0x1FF7 beyond) ray-cast from the true pose.

Noise: ``--slip X`` scales each wheel's measured travel by (1 + N(0, X)) per
step; ``--range-noise M`` adds N(0, M) metres to every reading;
``--outliers P`` replaces a reading, with probability P, by a uniform range
between 0.1 m and the true one (something in front of the wall).  Everything
comes from one seeded generator, so a seed gives the same bytes.

The truth file has one ``timestamp x y theta`` line per scan (seconds,
metres, radians), the same timestamps as the scans' records.

``--carmen`` writes a CARMEN log instead of a capture (gzip if OUT ends in
``.gz``): an ODOM line at every encoder packet's time with the pose
integrated from the measured ticks, and a ROBOTLASER1 line per scan (181
readings in metres to 1 mm, 81.9 for no return as CARMEN writes for a SICK)
whose robot pose is that odometry pose and whose laser pose is it composed
with the mount, as CARMEN's robot module writes them.

``--laser-pose X Y THETA`` puts the laser off the robot's centre (metres,
radians, robot frame: x forward, y left, theta counter-clockwise) and
``--upside-down`` turns it over (a reading at angle a in the laser's own frame
then points at -a): the scans are ray-cast from there.  A capture records the
mount only as metadata (``sim.laser_pose``, ``sim.laser_upside_down``); a
CARMEN log carries the pose in its ROBOTLASER1 lines and nothing says
"upside down", as in real logs.  The truth stays the robot's centre.

``--lidar ld06|rplidar`` puts a spinning lidar where the LMS was (a capture
only): a head turning clockwise, one point every whole degree (360 a turn),
each point ray-cast from the laser's pose at its own measuring time (the
robot's motion within the 10 ms integration step interpolated), so a turn
taken while the robot moves is skewed as a real one is.  The LD06 turns at
10 Hz and sends 12-point packets (230400 Bd); the RPLIDAR at 5 Hz (what
115200 Bd carries) sends the standard-scan descriptor, then its nodes, 12
to a record; each record is stamped with its last point's time.  The truth
file then has one line per whole turn, at its middle (the time the
revolution assembler stamps a turn with).  ``--drive curves`` drives the
waypoints differently, to exercise de-skew: arcs at 0.5 m/s turning at up to
1 rad/s, and turns in place at 1.5 rad/s where a waypoint lies more than
0.8 rad off the heading.
"""

import argparse
import math
import random
import sys
from typing import List, Optional, Sequence, Tuple

from . import capture as cap
from . import carmen as cm
from . import lidarstream
from . import protocols as proto
from .convert import integrate, wrap
from .fileio import open_text_output

Segment = Tuple[float, float, float, float]
Circle = Tuple[float, float, float]

TICKS_PER_M = 128000.0
WHEEL_BASE = 0.357
SPEED = 0.4
TURN_RATE = 0.8
DT = 0.01
MAX_RANGE = 8.0
CARMEN_NO_RETURN = 81.9     # what CARMEN writes (and gives as max range) for a SICK
T0_US = 1_000_000_000_000  # 1e6 s: an arbitrary epoch
LIDAR_TURN_HZ = {"ld06": 10.0, "rplidar": 5.0}
CURVE_SPEED = 0.5          # --drive curves: arcs at this speed (m/s),
CURVE_MAX_TURN = 1.0       # turning at most this fast (rad/s),
SPIN_RATE = 1.5            # and turns in place at this rate (rad/s)
SPIN_ABOVE = 0.8           # when the waypoint lies this far off (rad)
CURVE_REACH = 0.3          # a waypoint counts as reached this close (m)


def _box(x0, y0, x1, y1) -> List[Segment]:
    return [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]


def world(name: str) -> Tuple[List[Segment], List[Circle], List[Tuple[float, float]]]:
    """(segments, circles, waypoints) of a named world."""
    if name == "rooms":
        segs = _box(0, 0, 10, 8)
        segs += [(5, 0, 5, 3), (5, 5, 5, 8), (0, 4, 2, 4), (3, 4, 5, 4), (7, 4, 10, 4)]
        circles = [(8, 6.5, 0.3), (2, 2, 0.25)]
        path = [(1.5, 1.2), (3.5, 1.5), (4.0, 4.5), (6.0, 4.5), (8.5, 2.0), (8.0, 5.2),
                (6.0, 6.5), (2.5, 6.5), (1.5, 5.0)]
    elif name == "corridor":
        segs = [(0, 0, 30, 0), (0, 2, 30, 2), (0, 0, 0, 2), (30, 0, 30, 2)]
        segs += [(x, 0, x, 0.3) for x in range(3, 30, 4)] + [(x, 2, x, 1.7) for x in range(5, 30, 4)]
        circles = []
        path = [(1, 1), (29, 1)]
    elif name == "pillars":
        segs = _box(0, 0, 12, 12)
        circles = [(3 + 3 * i, 3 + 3 * j, 0.3) for i in range(3) for j in range(3)]
        path = [(1.5, 1.5), (10.5, 1.5), (10.5, 10.5), (1.5, 10.5)]
    elif name == "hall":
        # A bare 40 m corridor, 2 m wide: nothing in sight fixes the
        # position along it, which is then odometry's to keep.
        segs = _box(0, 0, 40, 2)
        circles = []
        path = [(1, 1), (39, 1)]
    elif name == "building":
        # A ring of 2 m corridors round a 36 x 16 m block (a 112 m lap).
        # The block's walls are bare; the outer walls have door recesses
        # (0.9 m wide, 0.3 m deep) at irregular places, the only thing
        # that fixes the position along a corridor.
        doors_x = {0: (4.3, 9.1, 15.7, 21.2, 26.6, 33.9), 20: (6.2, 11.8, 18.4, 24.9, 30.3, 35.5)}
        doors_y = {0: (3.1, 7.4, 12.9, 16.2), 40: (4.4, 9.8, 15.1)}
        segs = _box(2, 2, 38, 18)
        for y, xs in doors_x.items():
            d = -0.3 if y == 0 else 0.3
            ends = [0.0] + [v for x in xs for v in (x, x + 0.9)] + [40.0]
            segs += [(ends[i], y, ends[i + 1], y) for i in range(0, len(ends), 2)]
            for x in xs:
                segs += [(x, y, x, y + d), (x, y + d, x + 0.9, y + d), (x + 0.9, y + d, x + 0.9, y)]
        for x, ys in doors_y.items():
            d = -0.3 if x == 0 else 0.3
            ends = [0.0] + [v for y in ys for v in (y, y + 0.9)] + [20.0]
            segs += [(x, ends[i], x, ends[i + 1]) for i in range(0, len(ends), 2)]
            for y in ys:
                segs += [(x, y, x + d, y), (x + d, y, x + d, y + 0.9), (x + d, y + 0.9, x, y + 0.9)]
        circles = []
        path = [(1, 1), (39, 1), (39, 19), (1, 19)]
    else:
        raise ValueError(f"unknown world {name!r}")
    return segs, circles, path


def raycast(x: float, y: float, a: float, segs: Sequence[Segment], circles: Sequence[Circle],
            max_range: float = 1e9) -> float:
    dx, dy = math.cos(a), math.sin(a)
    best = max_range
    for x0, y0, x1, y1 in segs:
        ex, ey = x1 - x0, y1 - y0
        den = dx * ey - dy * ex
        if abs(den) < 1e-12:
            continue
        wx, wy = x0 - x, y0 - y
        t = (wx * ey - wy * ex) / den
        u = (wx * dy - wy * dx) / den
        if t > 1e-9 and -1e-12 <= u <= 1 + 1e-12 and t < best:
            best = t
    for cx, cy, r in circles:
        fx, fy = x - cx, y - cy
        b = fx * dx + fy * dy
        c = fx * fx + fy * fy - r * r
        disc = b * b - c
        if disc >= 0:
            t = -b - math.sqrt(disc)
            if 1e-9 < t < best:
                best = t
    return best


class _CarmenOut:
    """The CARMEN log writer: ODOM per encoder packet, ROBOTLASER1 per scan,
    with the odometry integrated from the ticks as rsm-nav would."""

    def __init__(self, path, pose: cm.Pose, mount: cm.Pose, header: str) -> None:
        self.fh = open_text_output(path)
        self.w = cm.LogWriter(self.fh, range_decimals=3)
        self.w.comment(header)
        self.odom = pose
        self.prev_odom = pose
        self.ticks = None
        self.mount = mount
        self.t0 = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.fh.close()

    def encoder(self, t: float, left: int, right: int) -> None:
        if self.t0 is None:
            self.t0 = t
        if self.ticks is not None:
            self.prev_odom = self.odom
            self.odom = integrate(self.odom, left - self.ticks[0], right - self.ticks[1],
                                  TICKS_PER_M, WHEEL_BASE)
        self.ticks = (left, right)
        x, y, th = self.odom
        self.w.write(cm.Odom(x, y, th, *self._velocity(), 0.0, t, "rsm-sim", t - self.t0))

    def _velocity(self) -> Tuple[float, float]:
        d = cm.pose_in_frame(self.prev_odom, self.odom)
        return d[0] / (10 * DT), d[2] / (10 * DT)

    def scan(self, t: float, ranges: List[float]) -> None:
        tv, rv = self._velocity()
        self.w.write(cm.RobotLaser1(
            0, -math.pi / 2, math.pi, math.radians(1.0), CARMEN_NO_RETURN, 0.01, 0,
            ranges, [], cm.pose_compose(self.odom, self.mount), self.odom,
            tv, rv, 0.0, 0.0, 0.0, t, "rsm-sim", t - self.t0))


class _SpinningLidar:
    """The spinning head of ``--lidar``: points at fixed times, gathered
    into the protocol's records (see the module's text)."""

    def __init__(self, kind: str, writer, channel: int) -> None:
        self.kind = kind
        self.w = writer
        self.ch = channel
        self.period_us = 1e6 / (LIDAR_TURN_HZ[kind] * lidarstream.POINTS_PER_TURN)
        self.index = 0                  # the next point, counted from T0_US
        self.pending: List[Tuple[int, int]] = []   # (angle, mm) of the record being filled
        if kind == "rplidar":
            writer.write(T0_US, channel, lidarstream.RPLIDAR_SCAN_DESCRIPTOR)

    def point_us(self, i: int) -> float:
        return T0_US + i * self.period_us

    def mid_turn_us(self, turn: int) -> float:
        """Middle of a whole turn: halfway between its first and last points."""
        return self.point_us(turn * lidarstream.POINTS_PER_TURN + (lidarstream.POINTS_PER_TURN - 1) / 2.0)

    def add(self, mm: int) -> None:
        """The next point's distance (0: no return); writes a full record."""
        angle = self.index % lidarstream.POINTS_PER_TURN
        self.pending.append((angle, mm))
        self.index += 1
        if len(self.pending) < lidarstream.LD06_POINTS:
            return
        t = int(round(self.point_us(self.index - 1)))
        first = self.pending[0][0]
        if self.kind == "ld06":
            speed = int(round(360.0 * LIDAR_TURN_HZ["ld06"]))
            data = lidarstream.ld06_packet(speed, first * 100, self.pending[-1][0] * 100, t // 1000,
                                           [(d, 200 if d else 0) for _, d in self.pending])
        else:
            data = b"".join(lidarstream.rplidar_node(a * 64, d * 4, lidarstream.RPLIDAR_QUALITY if d else 0, a == 0)
                            for a, d in self.pending)
        self.w.write(t, self.ch, data)
        self.pending = []


def _measured(r: float, rng: random.Random, outliers: float, range_noise: float) -> float:
    """A true range as the laser reports it: an outlier in front of the wall
    with probability ``outliers``, then N(0, range_noise) added (only within
    MAX_RANGE; beyond it stays beyond)."""
    if r <= MAX_RANGE:
        if outliers and rng.random() < outliers:
            r = rng.uniform(0.1, r)
        if range_noise:
            r = max(0.001, r + rng.gauss(0.0, range_noise))
    return r


def _pose_at(step: Tuple[float, float, float, float, float, float], t_us: float) -> Tuple[float, float, float]:
    """The true pose at t_us within an integration step (start time, pose,
    ds, dth): the midpoint model's arc, a fraction of the way along."""
    t0, x, y, th, ds, dth = step
    f = (t_us - t0) / 10_000
    return (x + f * ds * math.cos(th + 0.5 * f * dth), y + f * ds * math.sin(th + 0.5 * f * dth), th + f * dth)


def _drive(x: float, y: float, th: float, gx: float, gy: float, curves: bool) -> Tuple[float, float, bool]:
    """(v, omega, reached) towards the waypoint (gx, gy)."""
    err = wrap(math.atan2(gy - y, gx - x) - th)
    if math.hypot(gx - x, gy - y) < (CURVE_REACH if curves else 0.05):
        return 0.0, 0.0, True
    if curves:
        if abs(err) > SPIN_ABOVE:
            return 0.0, math.copysign(SPIN_RATE, err), False
        return CURVE_SPEED, max(-CURVE_MAX_TURN, min(CURVE_MAX_TURN, 2.5 * err)), False
    if abs(err) > 0.05:
        return 0.0, max(-TURN_RATE, min(TURN_RATE, 3.0 * err)), False
    return SPEED, 2.0 * err, False


def simulate(out, truth, world_name: str = "rooms", seconds: float = 60.0, slip: float = 0.0,
             range_noise: float = 0.0, outliers: float = 0.0, seed: int = 1,
             carmen: bool = False, laser_pose: cm.Pose = (0.0, 0.0, 0.0),
             upside_down: bool = False, lidar: Optional[str] = None, drive: str = "loop") -> int:
    """Write the capture (or with ``carmen`` the CARMEN log) and the truth
    file; returns the number of scans (whole turns with ``lidar``).
    ``laser_pose`` and ``upside_down`` mount the laser, ``lidar`` makes it
    a spinning one, ``drive`` picks the motion (see the module's text)."""
    if lidar is not None and (carmen or lidar not in LIDAR_TURN_HZ):
        raise ValueError("lidar: ld06 or rplidar, in a capture only")
    if drive not in ("loop", "curves"):
        raise ValueError("drive: loop or curves")
    segs, circles, path = world(world_name)
    rng = random.Random(seed)
    x, y = path[0]
    th = math.atan2(path[1][1] - y, path[1][0] - x)
    wp = 1
    left = right = 0            # measured ticks (integers)
    lacc = racc = 0.0           # fractional ticks carried over
    mx, my, mt = laser_pose
    flip = -1.0 if upside_down else 1.0
    channels = [cap.Channel(0, "robot", "aria", 38400), cap.Channel(1, "laser", "lms2xx", 38400)]
    meta = {
        "created_by": "rsm-sim", "source": f"rsm-sim world={world_name} seed={seed}",
        "robot.model": "p3dx-sh", "robot.ticks_per_m": repr(TICKS_PER_M),
        "robot.wheel_base_m": repr(WHEEL_BASE), "robot.kinematics": "midpoint",
        "robot.initial_pose": f"{x!r} {y!r} {th!r}", "robot.start_ticks": "0",
        "laser.model": "lms2xx", "laser.units": "mm", "laser.readings": "181",
        "laser.fov_deg": "180", "laser.measuring_mode": "0x00", "laser.max_range_m": repr(MAX_RANGE),
        "sim.slip": repr(slip), "sim.range_noise_m": repr(range_noise),
        "sim.outliers": repr(outliers), "sim.seconds": repr(seconds),
        "ground_truth": str(getattr(truth, "name", truth)).rsplit("/", 1)[-1],
    }
    if lidar is not None:
        channels[1] = cap.Channel(1, "lidar", "raw", lidarstream.BAUD[lidar])
        for key in ("laser.units", "laser.fov_deg", "laser.measuring_mode"):
            del meta[key]
        meta.update({"laser.model": lidar, "laser.readings": str(lidarstream.POINTS_PER_TURN),
                     "laser.turn_hz": repr(LIDAR_TURN_HZ[lidar]), "laser.clockwise": "1"})
    if drive != "loop":  # only then, so that the default drive gives the same bytes as ever
        meta["sim.drive"] = drive
    mounted = tuple(laser_pose) != (0.0, 0.0, 0.0) or upside_down
    if mounted:  # only then, so that a centred laser gives the same bytes as ever
        meta["sim.laser_pose"] = f"{mx!r} {my!r} {mt!r}"
        meta["sim.laser_upside_down"] = "1" if upside_down else "0"
    if carmen:
        header = (f"rsm-sim world={world_name} seed={seed} seconds={seconds!r} slip={slip!r} "
                  f"range_noise_m={range_noise!r} outliers={outliers!r}\n"
                  f"laser pose on the robot {mx!r} {my!r} {mt!r}"
                  + (", upside down" if upside_down else ""))
        sink = _CarmenOut(out, (x, y, th), (mx, my, mt), header)
    else:
        sink = cap.CaptureWriter(out, channels, meta)
    steps = int(round(seconds / DT))
    scans = 0
    with sink as w, open(truth, "w") as tf:
        tf.write("# timestamp x y theta   (rsm-sim ground truth at each "
                 + ("whole turn's middle)\n" if lidar else "scan)\n"))
        head = _SpinningLidar(lidar, w, 1) if lidar is not None else None
        steps_seen: List[Tuple[float, float, float, float, float, float]] = []
        for k in range(steps + 1):
            t_us = T0_US + k * 10_000
            if k % 10 == 0:
                if carmen:
                    w.encoder(t_us / 1e6, left, right)
                else:
                    w.write(t_us, 0, proto.encode_encoder(left, right))
            # motion for the next step: towards the waypoint
            v, om, reached = _drive(x, y, th, *path[wp], drive == "curves")
            if reached:
                wp = (wp + 1) % len(path)
            dl = (v - 0.5 * om * WHEEL_BASE) * DT
            dr = (v + 0.5 * om * WHEEL_BASE) * DT
            ds, dth = 0.5 * (dl + dr), (dr - dl) / WHEEL_BASE
            if head is not None:
                steps_seen.append((t_us, x, y, th, ds, dth))
                del steps_seen[:-200]  # two seconds: more than a turn
                # every point measured during this step, from the pose it had then
                t_end = t_us + 10_000 if k < steps else t_us
                while head.point_us(head.index) < t_end:
                    px, py, pth = _pose_at(steps_seen[-1], head.point_us(head.index))
                    c, s_ = math.cos(pth), math.sin(pth)
                    a = pth + mt - flip * math.radians(head.index % lidarstream.POINTS_PER_TURN)
                    r = _measured(raycast(px + c * mx - s_ * my, py + s_ * mx + c * my, a, segs, circles,
                                          MAX_RANGE + 1), rng, outliers, range_noise)
                    head.add(int(round(r * 1000.0)) if r <= MAX_RANGE else 0)
                    turn = head.index // lidarstream.POINTS_PER_TURN
                    if head.index % lidarstream.POINTS_PER_TURN == 0:
                        # a turn is whole: the truth at its middle
                        tm = head.mid_turn_us(turn - 1)
                        step = next(h for h in reversed(steps_seen) if h[0] <= tm)
                        mx_, my_, mth_ = _pose_at(step, tm)
                        tf.write(f"{tm / 1e6:.6f} {mx_:.6f} {my_:.6f} {wrap(mth_):.6f}\n")
                        scans += 1
            elif k % 20 == 0:
                vals = []
                ranges = []
                # the laser's own pose; beam j sits at (j - 90) deg in its own frame
                c, s = math.cos(th), math.sin(th)
                lx, ly = x + c * mx - s * my, y + s * mx + c * my
                for j in range(181):
                    a = th + mt + flip * math.radians(j - 90)
                    r = _measured(raycast(lx, ly, a, segs, circles, MAX_RANGE + 1), rng, outliers, range_noise)
                    if carmen:
                        ranges.append(r if r <= MAX_RANGE else CARMEN_NO_RETURN)
                    else:
                        vals.append(proto.range_to_raw(r, "mm", MAX_RANGE))
                if carmen:
                    w.scan(t_us / 1e6, ranges)
                else:
                    w.write(t_us, 1, proto.encode_b0(vals, "mm"))
                tf.write(f"{t_us / 1e6:.6f} {x:.6f} {y:.6f} {th:.6f}\n")
                scans += 1
            # truth: midpoint step
            x += ds * math.cos(th + 0.5 * dth)
            y += ds * math.sin(th + 0.5 * dth)
            th = wrap(th + dth)
            # measured ticks with slip
            ml = dl * (1.0 + rng.gauss(0.0, slip)) if slip else dl
            mr = dr * (1.0 + rng.gauss(0.0, slip)) if slip else dr
            lacc += ml * TICKS_PER_M
            racc += mr * TICKS_PER_M
            il, ir = int(math.floor(lacc)), int(math.floor(racc))
            lacc -= il
            racc -= ir
            left += il
            right += ir
    return scans


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="rsm-sim", description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="capture file to write")
    ap.add_argument("--truth", required=True, help="ground-truth trajectory to write")
    ap.add_argument("--world", choices=("rooms", "corridor", "pillars", "hall", "building"), default="rooms",
                    help="the world driven through (default rooms)")
    ap.add_argument("--seconds", type=float, default=60.0, help="length of the drive (default 60)")
    ap.add_argument("--slip", type=float, default=0.0,
                    help="each wheel's measured travel scaled by 1 + N(0, X) per step (default 0)")
    ap.add_argument("--range-noise", type=float, default=0.0,
                    help="N(0, M) metres added to every reading (default 0)")
    ap.add_argument("--outliers", type=float, default=0.0,
                    help="probability that a reading is replaced by a shorter random range (default 0)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the one random generator (default 1)")
    ap.add_argument("--carmen", action="store_true",
                    help="write OUT as a CARMEN log (ODOM + ROBOTLASER1) instead of a capture")
    ap.add_argument("--laser-pose", type=float, nargs=3, metavar=("X", "Y", "THETA"),
                    default=(0.0, 0.0, 0.0),
                    help="the laser's pose on the robot (m, m, rad; x forward, y left)")
    ap.add_argument("--upside-down", action="store_true", help="the laser is mounted upside down")
    ap.add_argument("--lidar", choices=("ld06", "rplidar"),
                    help="a spinning lidar instead of the LMS, each point measured at its own time")
    ap.add_argument("--drive", choices=("loop", "curves"), default="loop",
                    help="loop: straight legs, slow turns on the spot; curves: arcs and fast turns in place")
    a = ap.parse_args(argv)
    if a.lidar and a.carmen:
        ap.error("--lidar writes a capture, not a CARMEN log")
    if a.seconds <= 0 or a.slip < 0 or a.range_noise < 0 or not 0 <= a.outliers <= 1:
        ap.error("--seconds > 0, --slip >= 0, --range-noise >= 0, 0 <= --outliers <= 1")
    if not all(math.isfinite(v) for v in a.laser_pose) or math.hypot(*a.laser_pose[:2]) > 5.0:
        ap.error("--laser-pose: finite numbers, the laser within 5 m of the robot's centre")
    n = simulate(a.out, a.truth, a.world, a.seconds, a.slip, a.range_noise, a.outliers, a.seed,
                 carmen=a.carmen, laser_pose=tuple(a.laser_pose), upside_down=a.upside_down,
                 lidar=a.lidar, drive=a.drive)
    print(f"rsm-sim: {n} scans, {a.seconds:g} s in world {a.world} -> {a.out}"
          f"{' (CARMEN)' if a.carmen else ''}, truth {a.truth}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
