import gzip
import math

import pytest

from rsm_tools.carmen import (
    FLaser,
    LogReader,
    LogStats,
    LogWriter,
    MalformedLine,
    Odom,
    RobotLaser1,
    format_record,
    parse_line,
    read_log,
    time_key,
)
from rsm_tools.fileio import open_text

ODOM_OK = "ODOM 1.000000 2.000000 0.500000 0.100000 -0.200000 0.000000 100.250000 host 0.250000"
FLASER_OK = ("FLASER 3 1.00 2.50 81.90 0.100000 0.200000 0.300000 "
             "0.400000 0.500000 0.600000 100.500000 host 0.500000")
RL1_OK = ("ROBOTLASER1 0 -1.570796 3.141593 0.017453 81.900000 0.010000 0 "
          "2 1.50 2.25 2 10.00 20.00 "
          "1.000000 2.000000 0.100000 1.100000 2.100000 0.200000 "
          "0.300000 0.010000 0.550000 0.250000 0.000000 100.750000 robot 0.750000")

SYNTHETIC = [
    "# a comment",
    "",
    ODOM_OK,
    "   ",
    FLASER_OK,
    RL1_OK,
    "PARAM robot_width 0.5 0.0 host 0.0",
    "SONAR 1 2 3",
    "PARAM x 1 0.0 host 0.0",
    "  # indented comment",
    # malformed, one per documented reason (and a few repeats)
    "ODOM 1.0 2.0 0.5 0.1 -0.2 0.0 100.3 host",                     # field_count
    "FLASER 3 1.00 2.50 0.1 0.2 0.3 0.4 0.5 0.6 100.6 host 0.6",      # field_count
    "FLASER",                                                         # field_count
    "FLASER abc 1.00 0.1 0.2 0.3 0.4 0.5 0.6 100.6 host 0.6",         # bad_count
    "FLASER -1 0.1 0.2 0.3 0.4 0.5 0.6 100.6 host 0.6",               # bad_count
    "ODOM 1.0 x1 0.5 0.1 -0.2 0.0 100.3 host 0.3",                    # non_numeric
    "ODOM 1.0 2.0 nan 0.1 -0.2 0.0 100.3 host 0.3",                   # non_finite
    "FLASER 1 1.00 0.1 0.2 0.3 0.4 0.5 0.6 inf host 0.6",             # non_finite
    RL1_OK.replace(" 2 10.00 20.00 ", " 3 10.00 20.00 "),             # field_count
    RL1_OK.replace("ROBOTLASER1 0 ", "ROBOTLASER1 zero "),            # bad_count
    # well-formed: non-finite readings are allowed
    "FLASER 2 nan inf 0.1 0.2 0.3 0.4 0.5 0.6 100.7 host 0.7",
    "FLASER 0 0.1 0.2 0.3 0.4 0.5 0.6 100.8 host 0.8",
]


def test_synthetic_counts():
    st = LogStats()
    recs = list(read_log(SYNTHETIC, stats=st))
    assert st.lines == len(SYNTHETIC)
    assert st.blank == 2
    assert st.comments == 2
    assert dict(st.unknown) == {"PARAM": 2, "SONAR": 1}
    assert dict(st.malformed) == {
        "field_count": 4,
        "bad_count": 3,
        "non_numeric": 1,
        "non_finite": 2,
    }
    assert dict(st.records) == {"ODOM": 1, "FLASER": 3, "ROBOTLASER1": 1}
    assert len(recs) == 5
    # every line is in exactly one bucket
    assert (st.blank + st.comments + st.unknown_total + st.malformed_total
            + sum(st.records.values())) == st.lines
    # the examples point at the right lines (1-based)
    first_bad = SYNTHETIC.index("ODOM 1.0 2.0 0.5 0.1 -0.2 0.0 100.3 host") + 1
    assert st.examples[0][:2] == (first_bad, "ODOM")
    assert "field_count" in st.summary() and "PARAM=2" in st.summary()


def test_parsed_values():
    recs = list(read_log(SYNTHETIC))
    odom, fl, rl, fl_nan, fl_empty = recs
    assert isinstance(odom, Odom)
    assert (odom.x, odom.y, odom.theta, odom.tv, odom.rv, odom.accel) == (1, 2, 0.5, 0.1, -0.2, 0)
    assert odom.timestamp == 100.25 and odom.host == "host" and odom.logger_timestamp == 0.25
    assert odom.lineno == 3

    assert isinstance(fl, FLaser)
    assert fl.ranges == [1.0, 2.5, 81.9] and fl.num_readings == 3
    assert fl.laser_pose == (0.1, 0.2, 0.3) and fl.odom_pose == (0.4, 0.5, 0.6)
    assert fl.timestamp == 100.5 and fl.logger_timestamp == 0.5

    assert isinstance(rl, RobotLaser1)
    assert rl.laser_type == 0 and rl.remission_mode == 0
    assert rl.start_angle == pytest.approx(-math.pi / 2, abs=1e-6)
    assert rl.fov == pytest.approx(math.pi, abs=1e-6)
    assert rl.max_range == 81.9 and rl.accuracy == 0.01
    assert rl.ranges == [1.5, 2.25] and rl.remissions == [10.0, 20.0]
    assert rl.laser_pose == (1.0, 2.0, 0.1) and rl.robot_pose == (1.1, 2.1, 0.2)
    assert rl.odom_pose == rl.robot_pose
    assert (rl.tv, rl.rv, rl.forward_safety, rl.side_safety, rl.turn_axis) == (
        0.3, 0.01, 0.55, 0.25, 0.0)
    assert rl.timestamp == 100.75 and rl.host == "robot"

    assert math.isnan(fl_nan.ranges[0]) and math.isinf(fl_nan.ranges[1])
    assert fl_empty.ranges == []


def test_parse_line_raises_with_reason():
    assert parse_line("# x") is None
    assert parse_line("") is None
    assert parse_line("TRUEPOS 1 2 3") is None
    with pytest.raises(MalformedLine) as exc:
        parse_line("ODOM 1 2 3")
    assert exc.value.reason == "field_count"


def test_type_filter_counts_but_does_not_parse_others():
    st = LogStats()
    recs = list(LogReader(SYNTHETIC, types=["ODOM"], stats=st))
    assert [r.kind for r in recs] == ["ODOM"]
    # FLASER/ROBOTLASER1 lines are counted as records without being checked
    assert st.records["FLASER"] == 8 and st.records["ROBOTLASER1"] == 3
    assert dict(st.malformed) == {"field_count": 1, "non_numeric": 1, "non_finite": 1}
    with pytest.raises(ValueError):
        LogReader(SYNTHETIC, types=["TRUEPOS"])


def test_plain_and_gzip_detected_by_magic(tmp_path):
    text = "\n".join(SYNTHETIC) + "\n"
    plain = tmp_path / "log.gz"          # misleading names on purpose
    packed = tmp_path / "log.txt"
    plain.write_text(text)
    packed.write_bytes(gzip.compress(text.encode()))
    st_a, st_b = LogStats(), LogStats()
    a = list(read_log(plain, stats=st_a))
    b = list(read_log(str(packed), stats=st_b))
    assert len(a) == 5
    assert format_record(a[0]) == format_record(b[0])
    assert [format_record(r) for r in a[:3]] == [format_record(r) for r in b[:3]]
    assert st_a.malformed == st_b.malformed and st_a.unknown == st_b.unknown


def test_crlf_line_ends(tmp_path):
    p = tmp_path / "crlf.log"
    p.write_bytes((ODOM_OK + "\r\n" + FLASER_OK + "\r\n").encode())
    st = LogStats()
    recs = list(read_log(p, stats=st))
    assert len(recs) == 2 and st.malformed_total == 0
    assert recs[1].logger_timestamp == 0.5


def test_writer_round_trip_exact():
    for line in (ODOM_OK, FLASER_OK, RL1_OK):
        rec = parse_line(line)
        assert format_record(rec) == line
        assert parse_line(format_record(rec)) == rec


def test_writer_stream_and_precision(tmp_path):
    rec = FLaser([1.004, 2.0], (0.1234567, 0.0, -0.0), (1.0, 2.0, 3.0), 12.3456789, "h", 0.5)
    line = format_record(rec)
    assert line == ("FLASER 2 1.00 2.00 0.123457 0.000000 -0.000000 1.000000 2.000000 "
                    "3.000000 12.345679 h 0.500000")
    p = tmp_path / "out.log"
    with open(p, "w") as fh:
        w = LogWriter(fh)
        w.comment("written by a test\nsecond line")
        w.write(parse_line(ODOM_OK))
        w.write_all([rec])
    lines = p.read_text().splitlines()
    assert lines[:2] == ["# written by a test", "# second line"]
    assert lines[2] == ODOM_OK
    back = list(read_log(p))
    assert back[1].ranges == [1.0, 2.0] and back[1].timestamp == 12.345679
    with pytest.raises(TypeError):
        format_record("ODOM")


def test_time_key():
    assert time_key(976052905.167303) == 976052905167303
    assert time_key(0.0000005) in (0, 1)
    assert time_key(1.9999996) == 2000000


def test_shipped_excerpt_round_trips(head_log):
    """Every ODOM/FLASER line of the real excerpt is reproduced exactly by the writer."""
    n = 0
    with open_text(head_log) as fh:
        for line in fh:
            rec = parse_line(line)
            if rec is None:
                continue
            assert format_record(rec) == line.rstrip("\r\n")
            n += 1
    assert n == 600 + 1177


def test_excerpt_counts_agree_with_a_plain_reading_of_its_lines(head_log):
    """The reader's counts on the shipped excerpt equal those of a plain
    split of its lines (tests/data/README.md: 600 scans, 1177 ODOM lines and
    4 comments); the full log's counts are checked by ./tools/bench."""
    lines = gzip.decompress(head_log.read_bytes()).decode().splitlines()
    kinds = [l.split()[0] for l in lines if l.strip()]
    stamps = [float(l.split()[-3]) for l in lines if l.startswith("FLASER ")]
    plain_backwards = sum(1 for a, b in zip(stamps, stamps[1:]) if b < a)
    st = LogStats()
    n_ranges = 0
    prev = None
    backwards = 0
    for rec in read_log(head_log, stats=st):
        if rec.kind == "FLASER":
            assert rec.num_readings == 180
            n_ranges += 180
            if prev is not None and rec.timestamp < prev:
                backwards += 1
            prev = rec.timestamp
    assert st.records["FLASER"] == kinds.count("FLASER") == 600
    assert st.records["ODOM"] == kinds.count("ODOM") == 1177
    assert st.malformed_total == 0 and st.unknown_total == 0
    assert st.comments == kinds.count("#") == 4
    assert n_ranges == 600 * 180
    assert backwards == plain_backwards and backwards > 0  # the ordering quirk of intel-SOURCE.md


# The robot at (1, 2, pi/2) with its laser 0.22 m ahead, 0.05 m to the left and
# turned 0.1 rad: in the odometry frame the laser sits at (1 - 0.05, 2 + 0.22).
RL1_MOUNTED = ("ROBOTLASER1 0 -1.570796 3.141593 0.785398 81.900000 0.010000 0 "
               "5 1.00 2.00 3.00 2.00 1.00 0 "
               "0.950000 2.220000 1.670796 1.000000 2.000000 1.570796 "
               "0.000000 0.000000 0.550000 0.250000 0.000000 100.000000 robot 0.000000")


def test_robotlaser1_mount_is_the_laser_pose_seen_from_the_robot():
    rec = parse_line(RL1_MOUNTED)
    assert rec.mount == pytest.approx((0.22, 0.05, 0.1), abs=2e-6)
    # RL1_OK: laser (1.0, 2.0, 0.1), robot (1.1, 2.1, 0.2): behind and to the right, turned back
    c, s = math.cos(0.2), math.sin(0.2)
    want = (c * -0.1 + s * -0.1, -s * -0.1 + c * -0.1, -0.1)
    assert parse_line(RL1_OK).mount == pytest.approx(want, abs=1e-9)


def test_flaser_mount_only_when_its_two_triples_differ(head_log):
    # FLASER_OK's triples differ: laser (0.1, 0.2, 0.3), odometry (0.4, 0.5, 0.6)
    m = parse_line(FLASER_OK).mount
    c, s = math.cos(0.6), math.sin(0.6)
    assert m == pytest.approx((c * -0.3 + s * -0.3, -s * -0.3 + c * -0.3, -0.3), abs=1e-9)
    same = parse_line("FLASER 2 1.00 2.00 0.5 -1.0 3.0 0.5 -1.0 3.0 10.0 host 0.0")
    assert same.mount is None
    # the shipped excerpt repeats the odometry pose in the laser triple
    assert all(r.mount is None for r in read_log(head_log, types=["FLASER"]))
