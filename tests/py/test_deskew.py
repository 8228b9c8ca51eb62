"""De-skew measured on rsm-sim's spinning lidar: a drive through the rooms
world that turns in place at 1.5 rad/s and drives arcs at 0.5 m/s turning
at up to 1 rad/s (--drive curves), the laser mounted off the centre and
turned (0.12 m ahead, 0.03 m right, 0.3 rad), every point ray-cast from
the pose the laser had at its own measuring time. The capture goes through
rsm-nav's lidar path (driver, revolution assembler, localizer) in capture
mode, with the assembler's de-skew on and off, and both trajectories are
compared with the simulator's truth at each turn's middle (the time the
assembler stamps a turn with).

Two errors are reported both ways: the relative-pose error over spans up
to 1 s (what a turn's skew spoils: each scan's own geometry), and the mean
absolute error along the whole run (which rsm, without loop closure, lets
drift; the matcher's drift dominates it, so it is printed, not held to a
margin). The verdict is on the first: de-skew on must cut the local error
to at most DESKEW_GAIN times the error without, in translation and
rotation. Capture mode is a function of the bytes, so the figures are the
same on every machine.
"""

import math
import subprocess

import pytest

from conftest import rsm_nav_binary as nav_binary
from rsm_tools import capture as cap
from rsm_tools import evaluate as ev
from rsm_tools import sim

MOUNT = ("0.12", "-0.03", "0.3")
SECONDS = 40.0
LOCAL_SPAN_S = 1.0
DESKEW_GAIN = 0.6  # de-skew on: local error at most this times the error without


@pytest.fixture(scope="module", params=["ld06", "rplidar"])
def spinning_run(request, tmp_path_factory):
    kind = request.param
    d = tmp_path_factory.mktemp(f"deskew_{kind}")
    capture, truth = d / "sim.cap", d / "truth.txt"
    turns = sim.simulate(capture, truth, "rooms", seconds=SECONDS, lidar=kind, drive="curves",
                         laser_pose=tuple(float(v) for v in MOUNT))
    return kind, d, capture, truth, turns


def run_nav(capture, out, *extra):
    res = subprocess.run([str(nav_binary()), "--capture", str(capture), "--laser-pose", *MOUNT,
                          "--trajectory", str(out), *extra], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    return res.stdout


def truth_errors(traj_path, truth_path):
    """(local translation m, local rotation deg, matched, unmatched, mean
    absolute position m, mean absolute heading deg) of a trajectory against
    the simulator's truth."""
    truth = ev.load_trajectory(truth_path)
    traj = ev.load_trajectory(traj_path)
    local = ev.evaluate(traj, ev.relations_from_poses(truth, max_span=LOCAL_SPAN_S), tolerance=0.001)
    at = {round(p.t, 3): p for p in truth.points()}
    pos, head = [], []
    for p in traj.points():
        q = at[round(p.t, 3)]  # every turn's stamp is a truth time (within a millisecond)
        pos.append(math.hypot(p.x - q.x, p.y - q.y))
        head.append(abs(math.degrees(ev.wrap_angle(p.theta - q.theta))))
    return (local["translation"]["mean"], local["rotation"]["mean"], local["matched"], local["unmatched"],
            sum(pos) / len(pos), sum(head) / len(head))


def test_deskew_on_beats_off_on_a_turning_and_curving_drive(spinning_run):
    kind, d, capture, truth, turns = spinning_run
    assert turns == int(SECONDS * sim.LIDAR_TURN_HZ[kind])
    on, off = d / "on.txt", d / "off.txt"
    summary = run_nav(capture, on)
    # every turn but the first (the assembler joins it mid-turn) and the last (never closed)
    assert f"{turns - 2} turns (1 partial)" in summary, summary
    run_nav(capture, off, "--no-deskew")
    e_on, e_off = truth_errors(on, truth), truth_errors(off, truth)
    print(f"\n{kind}, {SECONDS:g} s, turns in place at {sim.SPIN_RATE} rad/s and arcs:"
          f"\n  de-skew on:  local (<= {LOCAL_SPAN_S:g} s) {e_on[0]:.4f} m {e_on[1]:.3f} deg"
          f" ({e_on[2]} relations); absolute {e_on[4]:.4f} m {e_on[5]:.3f} deg"
          f"\n  de-skew off: local (<= {LOCAL_SPAN_S:g} s) {e_off[0]:.4f} m {e_off[1]:.3f} deg"
          f" ({e_off[2]} relations); absolute {e_off[4]:.4f} m {e_off[5]:.3f} deg")
    # the same relations, all but those of the first and last turns (which no scan has)
    assert e_on[2:4] == e_off[2:4] and e_on[3] <= 2 * LOCAL_SPAN_S * sim.LIDAR_TURN_HZ[kind]
    assert e_on[0] <= DESKEW_GAIN * e_off[0]
    assert e_on[1] <= DESKEW_GAIN * e_off[1]


def test_the_spinning_lidar_leaves_the_drive_as_it_was(spinning_run, tmp_path):
    """The same drive and encoder bytes as the LMS capture of the same run:
    only the laser channel differs."""
    kind, _, capture, _, _ = spinning_run
    lms = tmp_path / "lms.cap"
    sim.simulate(lms, tmp_path / "lms.txt", "rooms", seconds=SECONDS, drive="curves",
                 laser_pose=tuple(float(v) for v in MOUNT))
    def encoders(path):
        h, recs, _ = cap.read_capture(path)
        robot = h.channel("robot").id
        return [(r.timestamp, r.data) for r in recs if r.channel == robot]
    assert encoders(capture) == encoders(lms)
    h, recs, _ = cap.read_capture(capture)
    assert h.metadata["laser.model"] == kind and h.metadata["sim.drive"] == "curves"
    assert h.channel("lidar").protocol == "raw"
