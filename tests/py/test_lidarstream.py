"""The spinning-lidar streams rsm-convert renders (rsm_tools.lidarstream),
read back by the C decoders through rsm-dump (tools/dump).

The Python encoders are checked against the byte vectors the C unit tests
use (tests/data/ld06_packets.txt, tests/data/rplidar_frames.txt); then the
shipped Intel excerpt is rendered as an LD06 and as an RPLIDAR stream and
every decoded point is compared with the logged beam at its bearing.
rsm-dump comes from the CMake build named by RSM_BUILD_DIR (ctest sets it).
"""

import json
import random
import math
import subprocess

import pytest

from conftest import TEST_DATA, FakeDevices, built_tool
from rsm_tools import capture as cap
from rsm_tools import convert, fakedev, lidarstream, sim
from rsm_tools.carmen import FLaser, read_log


def data_lines(name: str, key: str) -> list:
    return [line.split()[1:] for line in (TEST_DATA / name).read_text().splitlines()
            if line.startswith(key + " ")]


def test_ld06_packet_reproduces_the_c_vector():
    raw = [bytes(int(x, 16) for x in v) for v in data_lines("ld06_packets.txt", "packet")]
    fields = [[int(x) for x in v] for v in data_lines("ld06_packets.txt", "fields")]
    points = [[int(x) for x in v] for v in data_lines("ld06_packets.txt", "points")]
    assert len(raw) == 2
    for b, f, p in zip(raw, fields, points):
        pairs = list(zip(p[0::2], p[1::2]))
        assert lidarstream.ld06_packet(f[0], f[1], f[2], f[3], pairs) == b
    assert lidarstream.ld06_crc8(raw[0][:46]) == raw[0][46]


def test_rplidar_nodes_reproduce_the_c_vector():
    (nodes,) = [bytes(int(x, 16) for x in v) for v in data_lines("rplidar_frames.txt", "nodes")]
    assert nodes[:7] == lidarstream.RPLIDAR_SCAN_DESCRIPTOR
    # 90.5 deg, 1234.5 mm, quality 15, S; then 359.984375 deg, no return
    assert nodes[7:12] == lidarstream.rplidar_node(5792, 4938, 15, True)
    assert nodes[12:17] == lidarstream.rplidar_node(23039, 0, 0, False)


def test_turn_ranges_place_each_beam_at_its_bearing():
    st = lidarstream.TurnStats()
    ranges = [1.0 + i / 1000.0 for i in range(180)]
    ranges[3] = 0.0
    ranges[4] = float("nan")
    ranges[5] = 70.0
    mm = lidarstream.turn_ranges(ranges, lidarstream.LD06_MAX_MM, st)
    assert mm[90] == 1000          # beam 0: 90 deg to the right = 90 deg clockwise
    assert mm[0] == 1090           # beam 90: straight ahead
    assert mm[271] == 1179         # beam 179: 89 deg to the left
    assert mm[87] == mm[86] == 0   # beams 3 and 4: no return
    assert mm[85] == 0             # beam 5: 70 m does not fit 16 bits of mm
    assert all(mm[a] == 0 for a in range(91, 271))
    assert (st.beams, st.returns, st.no_return, st.too_far, st.unplaced) == (180, 177, 2, 1, 0)
    # a finer scan: 360 beams half a degree apart, the odd ones at no whole degree
    st = lidarstream.TurnStats()
    lidarstream.turn_ranges([1.0] * 360, lidarstream.LD06_MAX_MM, st)
    assert (st.returns, st.unplaced) == (180, 180)


def run_dump(*args) -> list:
    out = subprocess.run([str(built_tool("tools/dump/rsm-dump")), *args],
                         capture_output=True, text=True, timeout=120, check=True)
    return [json.loads(line) for line in out.stdout.splitlines()]


def dump(kind: str, stream: bytes, tmp_path) -> list:
    path = tmp_path / f"{kind}.bin"
    path.write_bytes(stream)
    return run_dump("--protocol", kind, str(path))


def dump_pty(path: str, packets: int) -> list:
    """rsm-dump reading an LD06 pseudo-terminal at 230400 Bd until it has
    decoded this many packets (a count, however fast either end runs)."""
    return run_dump("--protocol", "ld06", "--baud", "230400", "--count", str(packets), path)


def packet_key(o: dict) -> tuple:
    return (o["start_cdeg"], o["end_cdeg"], o["timestamp_ms"], tuple(p[1] for p in o["points"]))


def test_fakedev_plays_a_converted_capture_as_an_ld06(head_log, tmp_path):
    capture = tmp_path / "ld06.cap"
    convert.convert(str(head_log), str(capture), lidar="ld06")
    header, records, _ = cap.read_capture(capture)
    lidar = header.channel("lidar").id
    want = [packet_key(o) for o in dump("ld06", b"".join(
        r.data for r in records if r.channel == lidar), tmp_path)[:-1]]
    # --patient: the fake waits for rsm-dump rather than drop a packet, and
    # rsm-dump stops on a count, so what is read does not depend on the load.
    fake = FakeDevices(tmp_path, "--ld06", "--capture", str(capture), "--patient", "--quiet")
    try:
        objs = dump_pty(fake.paths["ld06"], 150)
    finally:
        log = fake.stop()
    packets = [o for o in objs if o.get("type") == "packet"]
    assert len(packets) == 150 and objs[-1]["end"] == "count"
    # The capture's packets in its order, none lost or changed. Those sent
    # before rsm-dump set 230400 Bd came garbled (never a header, so no
    # checksum error): the run starts further into the capture.
    got = [packet_key(o) for o in packets]
    first = want.index(got[0])
    assert got == want[first:first + len(got)]
    assert objs[-1]["checksum_errors"] == 0
    summary = [e for e in log if e.get("ev") == "summary" and e.get("dev") == "ld06"]
    assert summary and summary[0]["packets"] >= first + len(packets)


def test_fakedev_ld06_scans_the_simulated_world(tmp_path):
    fake = FakeDevices(tmp_path, "--ld06", "--patient", "--quiet")
    try:
        objs = dump_pty(fake.paths["ld06"], 60)  # a count, as above
    finally:
        fake.stop()
    packets = [o for o in objs if o.get("type") == "packet"]
    assert len(packets) == 60 and objs[-1]["checksum_errors"] == 0
    # none lost: each packet starts 12 degrees after the one before
    assert all((b["start_cdeg"] - a["start_cdeg"]) % 36000 == 1200 for a, b in zip(packets, packets[1:]))
    body = fakedev.Body()  # the robot stands where the world's path starts
    for o in packets:
        assert o["speed_dps"] == 3600 and (o["end_cdeg"] - o["start_cdeg"]) % 36000 == 1100
        for angle, rng, _q, _s in o["points"]:
            r = sim.raycast(body.x, body.y, body.th - math.radians(angle), body.segs, body.circles,
                            fakedev.MAX_RANGE_M)
            want = round(r * 1000.0) / 1000.0 if r < fakedev.MAX_RANGE_M else 0.0
            assert rng == pytest.approx(want, abs=1.5e-3)


@pytest.mark.parametrize("kind", ["ld06", "rplidar"])
def test_rendered_log_decodes_back_to_the_logged_beams(kind, head_log, tmp_path):
    out = tmp_path / f"{kind}.cap"
    st = convert.convert(str(head_log), str(out), lidar=kind)
    header, records, _ = cap.read_capture(out)
    lidar = header.channel("lidar")
    assert (lidar.protocol, lidar.baud) == ("raw", lidarstream.BAUD[kind])
    assert header.metadata["laser.model"] == kind
    stamps = [r.timestamp for r in records]
    assert stamps == sorted(stamps)
    objs = dump(kind, b"".join(r.data for r in records if r.channel == lidar.id), tmp_path)
    summary = objs[-1]
    assert summary["summary"] and summary["bytes_skipped"] == 0 and summary["checksum_errors"] == 0
    points = [p for o in objs[:-1] if o.get("points") for p in o["points"]]
    scans = [r for r in read_log(str(head_log), types=("FLASER",)) if isinstance(r, FLaser) and r.ranges]
    assert len(points) == 360 * len(scans) == 360 * (st.scans - st.empty_scans)
    limit = lidarstream.LD06_MAX_MM if kind == "ld06" else lidarstream.RPLIDAR_MAX_MM
    for k, scan in enumerate(scans):
        turn = points[360 * k:360 * (k + 1)]
        for a, (angle, rng, _quality, start) in enumerate(turn):
            assert angle == pytest.approx(a, abs=1e-9)
            assert start == (1 if kind == "rplidar" and a == 0 else 0)
            i = 90 - a if a <= 90 else 450 - a  # the beam at this angle's bearing
            want = 0
            if 0 <= i < len(scan.ranges) and math.isfinite(scan.ranges[i]) and scan.ranges[i] > 0:
                mm = int(round(scan.ranges[i] * 1000.0))
                want = mm if mm <= limit else 0
            assert rng == pytest.approx(want / 1000.0, abs=1e-6), (k, a)
    assert st.turns.returns == sum(1 for p in points if p[1] > 0)


# ---------------------------------------------------------------------------
# The Python receivers (rsm-record's and rsm-replay's counters) count as the
# C receivers do: every counter rsm-dump reports, on damaged streams fed in
# arbitrary chunks.

def capsule(start_q6: int, new_turn: bool, body: bytes) -> bytes:
    """An express capsule (docs/reference/lidars.md 2): sync nibbles, XOR of bytes 2..83."""
    rest = (start_q6 | (0x8000 if new_turn else 0)).to_bytes(2, "little") + body
    s = 0
    for x in rest:
        s ^= x
    return bytes([0xA0 | (s & 0x0F), 0x50 | (s >> 4)]) + rest


def damaged_streams() -> dict:
    rng = random.Random(14)
    pk = [lidarstream.ld06_packet(3600, (k * 1200) % 36000, (k * 1200 + 1100) % 36000, k,
                                  [(rng.randrange(1, 12000), rng.randrange(256)) for _ in range(12)])
          for k in range(30)]
    flipped = bytearray(pk[3])
    flipped[20] ^= 0x10                                      # CRC error
    bad_angle = lidarstream.ld06_packet(3600, 36000, 100, 0, [(1, 1)] * 12)  # CRC fine, start >= 360 deg
    ld06 = (b"\x00\x54\x2c\x13" + pk[0] + pk[1] + pk[2][:30] + pk[2] + bytes(flipped) + pk[4]
            + bad_angle + bytes(rng.randrange(256) for _ in range(300)) + b"".join(pk[5:]) + pk[0][:25])
    d = lidarstream.RPLIDAR_SCAN_DESCRIPTOR
    nodes = [lidarstream.rplidar_node(j * 64, rng.randrange(0, 40000), rng.randrange(64), j == 0)
             for j in range(360)]
    health = bytes([0xA5, 0x5A, 3, 0, 0, 0, 0x06]) + bytes([0, 0, 0])
    info = bytes([0xA5, 0x5A, 20, 0, 0, 0, 0x04]) + bytes(range(20))
    unknown = bytes([0xA5, 0x5A, 3, 0, 0, 0, 0x07])          # no such answer type
    bad_node = bytes([nodes[7][0] | 3]) + nodes[7][1:]        # S and not-S both set
    no_check = nodes[8][:1] + bytes([nodes[8][1] & 0xFE]) + nodes[8][2:]
    rp_nodes = (b"\x11" + health + unknown + info + d + b"".join(nodes[:7]) + bad_node + no_check
                + b"".join(nodes[9:]) + nodes[0][:3])
    caps = [capsule((k * 1000) % 23040, k % 23 == 0, bytes(rng.randrange(256) for _ in range(80)))
            for k in range(40)]
    bad_sum = bytearray(caps[5])
    bad_sum[40] ^= 1
    express = bytes([0xA5, 0x5A, 84, 0, 0, 0x40, 0x82])
    rp_caps = (health + express + b"".join(caps[:5]) + bytes(bad_sum) + b"".join(caps[6:])
               + capsule(0x7FFF, False, bytes(80)) + caps[0][:50])
    return {"ld06": [ld06], "rplidar": [rp_nodes, rp_caps]}


def feed_in_chunks(receiver, stream: bytes, seed: int) -> list:
    rng = random.Random(seed)
    got, i = [], 0
    while i < len(stream):
        n = rng.choice([1, 2, 5, 47, 84, 200])
        got += receiver.feed(stream[i:i + n])
        i += n
    return got


def test_python_receivers_count_every_byte_as_rsm_dump_does(tmp_path):
    for kind, streams in damaged_streams().items():
        for k, stream in enumerate(streams):
            objs = dump(kind, stream, tmp_path)
            summary = objs[-1]
            r = lidarstream.LD06Receiver() if kind == "ld06" else lidarstream.RplidarReceiver()
            frames = feed_in_chunks(r, stream, k)
            pending = len(r.buf)
            assert r.bytes_fed == len(stream) == summary["bytes"]
            # rsm-dump flushes at the end of the file: a partial candidate is skipped, one truncated
            assert (r.bytes_skipped + pending, 1 if pending else 0) == (summary["bytes_skipped"],
                                                                        summary["truncated"]), kind
            if kind == "ld06":
                assert (r.packets_ok, r.crc_errors, r.bad_fields) == (
                    summary["frames"], summary["checksum_errors"], summary["bad_fields"])
                # the flipped bit and the cut packet fail their CRC; the rest are lost candidates
                assert (r.packets_ok, r.bad_fields) == (29, 1) and r.crc_errors >= 2
                assert [f[4] | f[5] << 8 for f in frames] == [o["start_cdeg"] for o in objs[:-1]]
                assert r.bytes_skipped + pending + 47 * r.packets_ok == len(stream)
            else:
                assert (r.descriptors + r.responses + r.nodes + r.capsules, r.checksum_errors,
                        r.bad_descriptors, r.bad_nodes) == (
                    summary["frames"], summary["checksum_errors"], summary["bad_descriptors"],
                    summary["bad_nodes"])
                assert r.bytes_skipped + pending + r.bytes_framed == len(stream)
                if k == 0:   # two responses, the scan descriptor, the nodes; the unknown type rejected
                    assert (r.descriptors, r.responses, r.bad_descriptors) == (3, 2, 1)
                    # the two broken nodes rejected (resynchronising may find a node inside them)
                    assert 358 <= r.nodes <= 359 and r.bad_nodes >= 2
                    assert [t for t, _ in frames[:5]] == [0, 0x06, 0, 0x04, 0]
                else:        # 39 good capsules, one bad checksum, one start angle >= 360 deg
                    assert (r.capsules, r.checksum_errors, r.bad_capsules) == (39, 1, 1)
