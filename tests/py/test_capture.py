"""Capture format: writer/reader round trip, every error path, lenient counts,
and the C reader (tools/nav/capture.c) agreeing with the Python reader."""

import io
import random
import shutil
import struct
import subprocess
import zlib
from pathlib import Path

import pytest

from conftest import REPO_ROOT
from rsm_tools import capture as cap

CHANNELS = [cap.Channel(0, "robot", "aria", 38400), cap.Channel(1, "laser", "lms2xx", 38400)]


def make_records(n=200, seed=1):
    rng = random.Random(seed)
    t = 1_000_000
    out = []
    for _ in range(n):
        t += rng.randrange(0, 5000)
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(0, 300)))
        # sync bytes inside the data must not confuse anyone
        if rng.random() < 0.2:
            data += cap.SYNC + data[:20]
        out.append((t, rng.randrange(2), rng.randrange(2), data))
    return out


def write_file(path, records, **kw):
    with cap.CaptureWriter(path, CHANNELS, {"source": "test", "robot.ticks_per_m": "128000"}, **kw) as w:
        for t, ch, d, data in records:
            w.write(t, ch, data, d)
    return path


def as_tuples(recs):
    return [(r.timestamp, r.channel, r.direction, r.data) for r in recs]


def test_round_trip_header_and_records(tmp_path):
    recs = make_records()
    f = write_file(tmp_path / "a.cap", recs)
    h, got, st = cap.read_capture(f)
    assert [(c.id, c.name, c.protocol, c.baud) for c in h.channels] == [
        (0, "robot", "aria", 38400), (1, "laser", "lms2xx", 38400)]
    assert h.metadata["source"] == "test" and h.metadata["units.time"] == "us"
    assert h.channel("laser").id == 1
    assert as_tuples(got) == recs
    assert st.records == len(recs) and st.corrupt == st.truncated == 0


def test_large_chunks_are_split_and_empty_chunks_kept(tmp_path):
    big = bytes(range(256)) * 600  # 153600 bytes
    with cap.CaptureWriter(tmp_path / "b.cap", CHANNELS) as w:
        w.write(5, "laser", big)
        w.write(6, "robot", b"", "tx")
    _, got, _ = cap.read_capture(tmp_path / "b.cap")
    assert [len(r.data) for r in got] == [65535, 65535, 22530, 0]
    assert b"".join(r.data for r in got[:3]) == big
    assert got[3].direction == cap.TX


def test_writer_rejects_out_of_order_and_unknown_channel_or_clamps(tmp_path):
    w = cap.CaptureWriter(tmp_path / "c.cap", CHANNELS)
    w.write(100, 0, b"a")
    with pytest.raises(cap.OutOfOrderError, match="earlier than the previous"):
        w.write(99, 0, b"b")
    with pytest.raises(cap.UnknownChannelError):
        w.write(200, 7, b"c")
    w.close()
    w = cap.CaptureWriter(tmp_path / "d.cap", CHANNELS, clamp=True)
    w.write(100, 0, b"a")
    assert w.write(90, 0, b"b") == 100
    w.close()
    assert w.clamped == 1
    assert [r.timestamp for r in cap.read_capture(tmp_path / "d.cap")[1]] == [100, 100]


def test_flushed_after_every_record(tmp_path):
    f = tmp_path / "e.cap"
    w = cap.CaptureWriter(f, CHANNELS)
    w.write(1, 0, b"hello")
    # not closed: another reader sees the record already
    assert as_tuples(cap.read_capture(f)[1]) == [(1, 0, 0, b"hello")]
    w.close()


def test_header_errors(tmp_path):
    good = write_file(tmp_path / "g.cap", make_records(3)).read_bytes()
    cases = {
        b"hello world, not a capture": "bad magic",
        good[:12]: "truncated",
        good[:30]: "truncated",
        good[:8] + b"\x02\x00" + good[10:]: "unsupported capture version 2",
        good[:20] + bytes([good[20] ^ 0x40]) + good[21:]: "CRC mismatch",
    }
    for data, msg in cases.items():
        with pytest.raises(cap.HeaderError, match=msg):
            cap.CaptureReader(io.BytesIO(data))


class PieceStream(io.RawIOBase):
    """A raw stream over data giving at most one byte per read (a pipe may),
    and failing with EIO once fail_after bytes were read, if given."""

    def __init__(self, data, fail_after=None):
        self.data, self.pos, self.fail_after = data, 0, fail_after

    def readable(self):
        return True

    def readinto(self, b):
        if self.fail_after is not None and self.pos >= self.fail_after:
            raise OSError(5, "Input/output error")
        piece = self.data[self.pos:self.pos + min(1, len(b))]
        b[:len(piece)] = piece
        self.pos += len(piece)
        return len(piece)


def test_header_read_in_pieces_or_failing_is_not_a_bad_header(tmp_path):
    """A header that arrives a byte per read is read whole (it was 'bad
    magic'), and a read error inside it is raised as the OSError it is,
    never as a HeaderError ('bad magic', 'truncated'; issue 30)."""
    recs = make_records(5)
    data = write_file(tmp_path / "p.cap", recs).read_bytes()
    assert as_tuples(cap.CaptureReader(PieceStream(data))) == recs
    for after in (0, 4, 20, 40):
        with pytest.raises(OSError) as ei:
            cap.CaptureReader(PieceStream(data, fail_after=after))
        assert not isinstance(ei.value, cap.CaptureError)


def corrupt_file(tmp_path, recs):
    """A capture with record 10 bit-flipped, garbage before record 20, and a cut last record."""
    f = write_file(tmp_path / "x.cap", recs)
    raw = bytearray(f.read_bytes())
    hsize = cap.CaptureReader(io.BytesIO(bytes(raw))).header_size
    offs = []
    o = hsize
    for t, ch, d, data in recs:
        offs.append(o)
        o += cap.REC_OVERHEAD + len(data)
    raw[offs[10] + 16] ^= 0x01          # inside record 10 (data or CRC)
    raw[offs[20]:offs[20]] = b"garbageRC\x05"  # junk including a false sync
    raw = raw[:-5]                       # truncate the last record
    f.write_bytes(bytes(raw))
    return f


def test_strict_reader_raises_after_yielding_good_records(tmp_path):
    recs = make_records(30)
    f = corrupt_file(tmp_path, recs)
    got = []
    with pytest.raises(cap.CorruptRecordError, match="corrupt capture record") as ei:
        for r in cap.CaptureReader(f):
            got.append(r)
    assert as_tuples(got) == recs[:10]
    assert ei.value.record == 10


def test_lenient_reader_counts_skips_and_resynchronises(tmp_path):
    recs = make_records(30)
    f = corrupt_file(tmp_path, recs)
    r = cap.CaptureReader(f, lenient=True)
    got = as_tuples(r)
    expect = recs[:10] + recs[11:29]
    assert got == expect
    assert r.stats.corrupt == 2 and r.stats.truncated == 1
    assert r.stats.skipped_bytes > 0
    assert "corrupt" in r.stats.summary()


def test_truncated_tail_strict(tmp_path):
    recs = make_records(5)
    f = write_file(tmp_path / "t.cap", recs)
    f.write_bytes(f.read_bytes()[:-3])
    got = []
    with pytest.raises(cap.TruncatedRecordError, match="ends inside a record"):
        for r in cap.CaptureReader(f):
            got.append(r)
    assert as_tuples(got) == recs[:4]


def raw_capture(records):
    """Hand-built file: bypasses the writer's checks."""
    h = cap.encode_header(cap.Header(CHANNELS))
    return h + b"".join(cap.encode_record(*r) for r in records)


def test_out_of_order_and_unknown_channel(tmp_path):
    data = raw_capture([(10, 0, 0, b"a"), (5, 0, 0, b"b"), (11, 9, 0, b"c"), (12, 1, 1, b"d")])
    with pytest.raises(cap.OutOfOrderError, match="earlier than the previous 10 us"):
        list(cap.CaptureReader(io.BytesIO(data)))
    r = cap.CaptureReader(io.BytesIO(data), lenient=True)
    assert as_tuples(r) == [(10, 0, 0, b"a"), (12, 1, 1, b"d")]
    assert r.stats.out_of_order == 1 and r.stats.unknown_channel == 1
    data = raw_capture([(10, 0, 0, b"a"), (11, 9, 0, b"c")])
    with pytest.raises(cap.UnknownChannelError, match="channel id 9"):
        list(cap.CaptureReader(io.BytesIO(data)))


def test_lenient_reader_follows_a_clock_that_steps_back(tmp_path):
    """An earlier stamp is not trusted alone (one record lost), but the next
    record stamped within an hour of it confirms the step: before, every
    record after a step back was skipped. A strict reader still raises."""
    recs = [(1000, 0, 0, b"a"), (1001, 1, 0, b"b"), (10, 0, 0, b"c"), (11, 1, 0, b"d"), (12, 0, 0, b"e")]
    data = raw_capture(recs)
    r = cap.CaptureReader(io.BytesIO(data), lenient=True)
    assert as_tuples(r) == [recs[0], recs[1], recs[3], recs[4]]
    assert r.stats.out_of_order == 1
    with pytest.raises(cap.OutOfOrderError, match="earlier than the previous 1001 us"):
        list(cap.CaptureReader(io.BytesIO(data)))


class CountingZlib:
    """zlib for the capture module, counting the bytes given to crc32."""

    def __init__(self):
        self.crc_bytes = 0

    def crc32(self, data, value=0):
        self.crc_bytes += len(data)
        return zlib.crc32(data, value)


def test_resync_over_false_record_starts_crcs_each_byte_about_once(tmp_path, monkeypatch):
    """512 KiB of "RC\\xff\\xff": a false record start every 4 bytes, each
    claiming 64 KiB. The reader CRCed each claim anew (issue 30: 7.2 s per
    MiB, some 17 GB through the CRC); now the file goes through it about
    once, and each false start at most two steps of the prefix grid more,
    whatever it claims. The work is counted, not timed."""
    recs = make_records(40, seed=9)
    good = write_file(tmp_path / "g.cap", recs).read_bytes()
    hsize = cap.CaptureReader(io.BytesIO(good)).header_size
    cut = hsize + sum(cap.REC_OVERHEAD + len(r[3]) for r in recs[:20])
    garbage = b"RC\xff\xff" * (1 << 17)
    f = tmp_path / "hostile.cap"
    f.write_bytes(good[:cut] + garbage + good[cut:])
    counting = CountingZlib()
    monkeypatch.setattr(cap, "zlib", counting)
    r = cap.CaptureReader(f, lenient=True)
    assert as_tuples(r) == recs
    assert (r.stats.corrupt, r.stats.skipped_bytes) == (1, len(garbage))
    size = f.stat().st_size
    false_starts = garbage.count(cap.SYNC)
    per_start = 128  # two steps of the prefix grid at most, never the 64 KiB claimed
    assert counting.crc_bytes <= 2 * size + per_start * false_starts, (counting.crc_bytes, size)
    assert 2 * cap._SpanCrc.GRID <= per_start
    assert r.stats.crc_bytes <= counting.crc_bytes  # the header's CRC is not a record's


def test_span_crc_is_zlibs_crc_of_the_span():
    rng = random.Random(11)
    buf = bytearray(rng.randrange(256) for _ in range(150_000))
    spans = cap._SpanCrc(buf, cap.ReadStats())
    for a, b in [(0, 0), (0, 1), (5, 70), (63, 64), (64, 128), (1, 150_000)] + [
            sorted((rng.randrange(150_001), rng.randrange(150_001))) for _ in range(300)]:
        assert spans.crc(a, b) == zlib.crc32(bytes(buf[a:b])), (a, b)


# ---------------------------------------------------------------------------
# C reader


@pytest.fixture(scope="module")
def c_reader(tmp_path_factory):
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.fail("no C compiler (gcc/cc) on PATH to build the capture reader test driver")
    out = tmp_path_factory.mktemp("cdrv") / "capture_dump"
    nav = REPO_ROOT / "tools" / "nav"
    cmd = [cc, "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wconversion", "-Werror",
           "-O1", "-DRSM_CAPTURE_DUMP_MAIN", "-I", str(nav), str(nav / "capture.c"), str(nav / "heap.c"), "-o", str(out)]
    res = subprocess.run(cmd, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    return out


def _golden_module():
    """tests/data/capture/make_golden.py, which also defines the dump format."""
    import importlib.util
    path = REPO_ROOT / "tests" / "data" / "capture" / "make_golden.py"
    spec = importlib.util.spec_from_file_location("make_golden", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


GOLDEN = _golden_module()


def python_dump(path, lenient):
    return GOLDEN.dump(path, lenient).splitlines()


def c_dump(exe, path, lenient):
    args = [str(exe)] + (["--lenient"] if lenient else []) + [str(path)]
    res = subprocess.run(args, capture_output=True, text=True, timeout=60)
    assert res.returncode in (0, 1), res.stderr
    return res.stdout.splitlines()


def test_c_reader_matches_python_on_good_file(tmp_path, c_reader):
    f = write_file(tmp_path / "good.cap", make_records(300, seed=5))
    for lenient in (False, True):
        py = python_dump(f, lenient)
        assert py[-1].startswith("end records=300")
        assert c_dump(c_reader, f, lenient) == py


def test_c_reader_matches_python_on_damaged_files(tmp_path, c_reader):
    recs = make_records(40, seed=7)
    files = [corrupt_file(tmp_path, recs)]
    good = write_file(tmp_path / "g.cap", recs).read_bytes()
    (tmp_path / "cut.cap").write_bytes(good[:-1])
    (tmp_path / "junk.cap").write_bytes(good + b"\x00\x01garbage!" * 3)
    (tmp_path / "half_sync.cap").write_bytes(good + b"R")
    (tmp_path / "badhdr.cap").write_bytes(good[:20] + b"\xff" + good[21:])
    (tmp_path / "order.cap").write_bytes(
        raw_capture([(10, 0, 0, b"a"), (5, 0, 0, b"b"), (11, 9, 0, b"c"), (12, 1, 1, b"d")]))
    # The clock steps back (confirmed by the next record), then one record far ahead alone.
    (tmp_path / "steps.cap").write_bytes(
        raw_capture([(100, 0, 0, b"a"), (40, 0, 0, b"b"), (41, 1, 0, b"c"), (45, 1, 0, b"d"),
                     (45 + 2 * cap.MAX_STEP_US, 0, 0, b"e"), (46, 0, 0, b"f")]))
    # False record starts over more than the reader's window, each claiming 64 KiB.
    (tmp_path / "false_starts.cap").write_bytes(good[:300] + b"RC\xff\xff" * (1 << 17) + good[300:])
    files += [tmp_path / n for n in ("cut.cap", "junk.cap", "half_sync.cap", "badhdr.cap", "order.cap",
                                     "steps.cap", "false_starts.cap")]
    for f in files:
        for lenient in (False, True):
            py = python_dump(f, lenient)
            assert c_dump(c_reader, f, lenient) == py, (f.name, lenient)


# ---------------------------------------------------------------------------
# golden files (tests/data/capture): the writer's bytes, the reader's view


def test_golden_files_are_what_the_writer_writes_and_the_reader_reads(tmp_path, c_reader):
    """make_golden.py remakes every committed file byte for byte, so the
    golden captures are the Python writer's and the .txt files the Python
    reader's view of them, which tests/unit/test_capture.c holds the C reader
    to; the C reader driver agrees here too."""
    committed = REPO_ROOT / "tests" / "data" / "capture"
    GOLDEN.make(tmp_path)
    names = sorted(p.name for p in committed.iterdir() if p.suffix in (".cap", ".txt"))
    assert names == ["damaged.cap", "damaged.lenient.txt", "damaged.strict.txt", "good.cap", "good.lenient.txt",
                     "good.strict.txt"]
    for name in names:
        assert (tmp_path / name).read_bytes() == (committed / name).read_bytes(), name
    for name in ("good", "damaged"):
        for mode in ("strict", "lenient"):
            want = (committed / f"{name}.{mode}.txt").read_text().splitlines()
            assert python_dump(committed / f"{name}.cap", mode == "lenient") == want
            assert c_dump(c_reader, committed / f"{name}.cap", mode == "lenient") == want
    # every kind of fault is in the damaged file, each counted once
    assert want[-1] == "end records=11 corrupt=3 truncated=1 order=1 channel=1 skipped=77"


def test_protocol_tags_read_alike_and_unknown_codes_read_as_raw(tmp_path, c_reader):
    """Codes 0-4 name raw, aria, lms2xx, ld06 and rplidar in both readers; a
    code neither knows reads as raw (docs/capture.md)."""
    names = ["raw", "aria", "lms2xx", "ld06", "rplidar"]
    channels = [cap.Channel(i, chr(ord("a") + i), n, 115200) for i, n in enumerate(names + ["raw"])]
    head = bytearray(cap.encode_header(cap.Header(channels)))
    assert [head[17 + 8 * i + 1] for i in range(6)] == [0, 1, 2, 3, 4, 0]
    head[17 + 8 * 5 + 1] = 9                       # channel f: a code from a later writer
    head[-4:] = struct.pack("<I", zlib.crc32(bytes(head[:-4])))
    f = tmp_path / "tags.cap"
    f.write_bytes(bytes(head) + cap.encode_record(1, 3, cap.RX, b"\x54\x2c"))
    h, recs, _ = cap.read_capture(f)
    assert [c.protocol for c in h.channels] == names + ["raw"]
    py = python_dump(f, False)
    assert [line.split()[3] for line in py if line.startswith("channel ")] == names + ["raw"]
    assert c_dump(c_reader, f, False) == py
