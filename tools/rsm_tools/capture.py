"""Reader and writer for rsm capture files (``.cap``): timestamped serial bytes.

The format is specified in ``docs/capture.md``.  In short (all integers
little-endian)::

    header:  magic "\\x89RSMCAP\\n" | u16 version (1) | u16 flags (0) |
             u32 body length H | body (H bytes) | u32 CRC-32 of all before
    body:    u8 channel count, then per channel:
                 u8 id | u8 protocol (0 raw, 1 aria, 2 lms2xx, 3 ld06, 4 rplidar) |
                 u32 baud |
                 u8 name length | name (UTF-8)
             u16 metadata count, then per entry:
                 u16 key length | key | u32 value length | value (UTF-8)
    record:  "RC" | u16 n | u64 timestamp (us) | u8 channel | u8 direction
             (0 rx = device to host, 1 tx = host to device) | n bytes |
             u32 CRC-32 of the 14 + n bytes before it

Errors are subclasses of :class:`CaptureError`.  A strict reader
(``lenient=False``) raises at the first problem, after yielding every good
record before it; a lenient reader counts problems in :class:`ReadStats`
and skips the offending records (see the module documentation in
``docs/capture.md`` for the exact rules, which the C reader shares).
"""

import os
import struct
import zlib
from dataclasses import dataclass, field
from typing import IO, Dict, Iterator, List, Optional, Sequence, Tuple, Union

MAGIC = b"\x89RSMCAP\n"
VERSION = 1
SYNC = b"RC"
REC_HEAD = struct.Struct("<2sHQBB")   # sync, n, timestamp, channel, direction
REC_HEAD_SIZE = REC_HEAD.size          # 14
REC_OVERHEAD = REC_HEAD_SIZE + 4       # + CRC
# Lenient readers do not trust alone a record stamped this much after the
# previous one (one hour), nor one stamped before it; the next record confirms
# either when it is stamped within this of it (docs/capture.md, "Far ahead",
# "Stepped back").
MAX_STEP_US = 3_600_000_000
MAX_CHUNK = 0xFFFF
MAX_CHANNELS = 32
RX, TX = 0, 1
DIRECTIONS = {"rx": RX, "tx": TX}

PROTOCOLS = {"raw": 0, "aria": 1, "lms2xx": 2, "ld06": 3, "rplidar": 4}
PROTOCOL_NAMES = {v: k for k, v in PROTOCOLS.items()}

#: metadata every writer adds unless given
DEFAULT_METADATA = {
    "units.time": "us",
    "units.length": "m",
    "units.angle": "rad",
}

PathLike = Union[str, "os.PathLike[str]"]


class CaptureError(Exception):
    """Base class: something is wrong with a capture file."""

    kind = "error"

    def __init__(self, message: str, offset: Optional[int] = None,
                 record: Optional[int] = None) -> None:
        where = []
        if offset is not None:
            where.append(f"byte offset {offset}")
        if record is not None:
            where.append(f"after {record} good records")
        super().__init__(message + (f" ({', '.join(where)})" if where else ""))
        self.offset = offset
        self.record = record


class HeaderError(CaptureError):
    """Bad magic, unsupported version, truncated header or header CRC mismatch."""

    kind = "header"


class CorruptRecordError(CaptureError):
    """A record whose sync, CRC or fields are wrong."""

    kind = "corrupt"


class TruncatedRecordError(CaptureError):
    """The file ends inside a record (e.g. the writer was killed mid-write)."""

    kind = "truncated"


class OutOfOrderError(CaptureError):
    """A record's timestamp is earlier than the one before it."""

    kind = "order"


class UnknownChannelError(CaptureError):
    """A record names a channel id that is not in the header."""

    kind = "channel"


@dataclass
class Channel:
    id: int
    name: str
    protocol: str = "raw"
    baud: int = 0

    def __post_init__(self) -> None:
        if not 0 <= self.id <= 254:
            raise ValueError(f"channel id {self.id} out of 0..254")
        if self.protocol not in PROTOCOLS:
            raise ValueError(f"unknown protocol {self.protocol!r}; one of {sorted(PROTOCOLS)}")
        if not self.name or len(self.name.encode()) > 255:
            raise ValueError("channel name must be 1..255 bytes")


@dataclass
class Header:
    channels: List[Channel]
    metadata: Dict[str, str] = field(default_factory=dict)
    version: int = VERSION

    def channel(self, key: Union[int, str]) -> Channel:
        for c in self.channels:
            if c.id == key or c.name == key:
                return c
        raise KeyError(f"no channel {key!r} in the capture (have: "
                       + ", ".join(f"{c.id}={c.name}" for c in self.channels) + ")")


@dataclass
class Record:
    timestamp: int      # microseconds
    channel: int
    direction: int      # RX or TX
    data: bytes
    offset: int = 0     # byte offset in the file

    @property
    def is_rx(self) -> bool:
        return self.direction == RX


@dataclass
class ReadStats:
    records: int = 0
    bytes: int = 0
    corrupt: int = 0          # records skipped as corrupt (each resync counts once)
    skipped_bytes: int = 0    # bytes passed over while resynchronising
    truncated: int = 0        # 1 if the file ended inside a record
    out_of_order: int = 0
    unknown_channel: int = 0
    # bytes run through the CRC: about the file's size however many false
    # record starts a resync meets (the C reader's crc_bytes)
    crc_bytes: int = 0
    problems: List[str] = field(default_factory=list)

    def summary(self) -> str:
        return (f"{self.records} records, {self.bytes} bytes; corrupt {self.corrupt} "
                f"({self.skipped_bytes} bytes skipped), truncated {self.truncated}, "
                f"out of order {self.out_of_order}, unknown channel {self.unknown_channel}")


# ---------------------------------------------------------------------------
# CRC-32 of a span from prefix CRCs, for the resync
#
# crc(A B) = crc(A) * x^(8 |B|) + crc(B) modulo the polynomial (zlib's initial
# and final inversions cancel), so crc(B) = crc(A B) ^ crc(A) * x^(8 |B|), as in
# tools/nav/capture.c.  Polynomials are held reflected: bit 31 is x^0.

CRC_POLY = 0xEDB88320


def _gf2_mul(a: int, b: int) -> int:
    p = 0
    m = 1 << 31
    while m and a:
        if a & m:
            p ^= b
            a &= ~m
        m >>= 1
        b = (b >> 1) ^ CRC_POLY if b & 1 else b >> 1
    return p


def _x8n(n: int) -> int:
    """x^(8 n) modulo the polynomial."""
    sq, p = 1 << 23, 1 << 31   # x^8, x^0
    while n:
        if n & 1:
            p = _gf2_mul(sq, p)
        sq = _gf2_mul(sq, sq)
        n >>= 1
    return p


# (k, d) -> four byte tables of the product with x^(8 d 16^k): a product is
# linear in each factor, so four table reads per hex digit of the length
# replace a pure-Python multiplication (made when first needed; a record's
# span, under 2^17 bytes, needs 61 at most).
_SHIFT_TABLES: Dict[Tuple[int, int], List[List[int]]] = {}


def _shift_table(k: int, d: int) -> List[List[int]]:
    t = _SHIFT_TABLES.get((k, d))
    if t is None:
        m = _x8n(d << (4 * k))
        unit = [_gf2_mul(m, 1 << bit) for bit in range(32)]
        t = []
        for pos in range(4):
            row = [0] * 256
            for v in range(1, 256):
                low = v & -v
                row[v] = row[v ^ low] ^ unit[8 * pos + low.bit_length() - 1]
            t.append(row)
        _SHIFT_TABLES[(k, d)] = t
    return t


def _crc_times_x8n(crc: int, n: int) -> int:
    """crc * x^(8 n) modulo the polynomial: a CRC moved on past n zero bytes' worth."""
    k = 0
    while n:
        d = n & 15
        if d:
            t = _shift_table(k, d)
            crc = t[0][crc & 255] ^ t[1][(crc >> 8) & 255] ^ t[2][(crc >> 16) & 255] ^ t[3][crc >> 24]
        n >>= 4
        k += 1
    return crc


class _SpanCrc:
    """CRC-32 of any span of a growing buffer, from CRCs of its prefixes kept
    every GRID bytes: the buffer goes through the CRC about once, and each
    span at most two grid steps more, however long it is (a resync CRCed
    each candidate's claim of up to 64 KiB anew: seconds per MiB of false
    record starts)."""

    GRID = 32

    def __init__(self, buf: bytearray, stats: "ReadStats") -> None:
        self.buf = buf
        self.stats = stats
        self.pre = [0]          # pre[k]: CRC of buf[:k * GRID]

    def prefix(self, p: int) -> int:
        g = self.GRID
        pre = self.pre
        while len(pre) <= p // g:
            k = len(pre)
            pre.append(zlib.crc32(memoryview(self.buf)[(k - 1) * g:k * g], pre[-1]))
            self.stats.crc_bytes += g
        base = p - p % g
        self.stats.crc_bytes += p - base
        return zlib.crc32(memoryview(self.buf)[base:p], pre[p // g])

    def crc(self, a: int, b: int) -> int:
        """CRC-32 of buf[a:b]."""
        return self.prefix(b) ^ _crc_times_x8n(self.prefix(a), b - a)


# ---------------------------------------------------------------------------
# header encoding


def encode_header(header: Header) -> bytes:
    if not header.channels or len(header.channels) > MAX_CHANNELS:
        raise ValueError(f"a capture needs 1..{MAX_CHANNELS} channels")
    ids = [c.id for c in header.channels]
    if len(set(ids)) != len(ids):
        raise ValueError(f"duplicate channel ids: {ids}")
    body = bytearray([len(header.channels)])
    for c in header.channels:
        name = c.name.encode()
        body += struct.pack("<BBIB", c.id, PROTOCOLS[c.protocol], c.baud, len(name)) + name
    meta = dict(DEFAULT_METADATA)
    meta.update(header.metadata)
    body += struct.pack("<H", len(meta))
    for k, v in meta.items():
        kb, vb = str(k).encode(), str(v).encode()
        if not kb or len(kb) > 0xFFFF:
            raise ValueError(f"bad metadata key {k!r}")
        body += struct.pack("<H", len(kb)) + kb + struct.pack("<I", len(vb)) + vb
    head = MAGIC + struct.pack("<HHI", VERSION, 0, len(body)) + bytes(body)
    return head + struct.pack("<I", zlib.crc32(head))


def _read_exact(fh: IO[bytes], n: int) -> bytes:
    """n bytes, fewer only at the end of the file: a raw stream (a pipe) may
    return less per read, which is not the end.  A read error raises."""
    out = b""
    while len(out) < n:
        chunk = fh.read(n - len(out))
        if not chunk:
            break
        out += chunk
    return out


def read_header(fh: IO[bytes]) -> Tuple[Header, int]:
    """Read and check the header; returns it and its size in bytes.  A read
    error is raised as the OSError it is, never a HeaderError."""
    fixed = _read_exact(fh, 16)
    if len(fixed) < 8 or fixed[:8] != MAGIC:
        raise HeaderError("not an rsm capture file (bad magic)", 0)
    if len(fixed) < 16:
        raise HeaderError("capture header truncated", len(fixed))
    version, flags, hlen = struct.unpack_from("<HHI", fixed, 8)
    if version != VERSION:
        raise HeaderError(f"unsupported capture version {version} (this reader reads {VERSION})", 8)
    if hlen > 16 * 1024 * 1024:
        raise HeaderError(f"implausible header length {hlen}", 12)
    body = _read_exact(fh, hlen)
    crc = _read_exact(fh, 4)
    if len(body) < hlen or len(crc) < 4:
        raise HeaderError("capture header truncated", 16 + len(body))
    if zlib.crc32(fixed + body) != struct.unpack("<I", crc)[0]:
        raise HeaderError("capture header CRC mismatch (header corrupt)", 16 + hlen)
    try:
        channels = []
        off = 1
        if not 1 <= body[0] <= MAX_CHANNELS:
            raise ValueError(f"{body[0]} channels (1 to {MAX_CHANNELS})")
        for _ in range(body[0]):
            cid, proto, baud, nl = struct.unpack_from("<BBIB", body, off)
            off += 7
            name = body[off:off + nl].decode()
            off += nl
            channels.append(Channel(cid, name, PROTOCOL_NAMES.get(proto, "raw"), baud))
        (nm,) = struct.unpack_from("<H", body, off)
        off += 2
        meta = {}
        for _ in range(nm):
            (kl,) = struct.unpack_from("<H", body, off)
            off += 2
            k = body[off:off + kl].decode()
            off += kl
            (vl,) = struct.unpack_from("<I", body, off)
            off += 4
            meta[k] = body[off:off + vl].decode()
            off += vl
        if off != hlen:
            raise ValueError("trailing bytes in the header body")
    except (struct.error, UnicodeDecodeError, ValueError, IndexError) as exc:
        raise HeaderError(f"capture header body malformed: {exc}", 16) from None
    return Header(channels, meta, version), 16 + hlen + 4


def encode_record(timestamp: int, channel: int, direction: int, data: bytes) -> bytes:
    head = REC_HEAD.pack(SYNC, len(data), timestamp, channel, direction) + bytes(data)
    return head + struct.pack("<I", zlib.crc32(head))


# ---------------------------------------------------------------------------
# writer


class CaptureWriter:
    """Streaming writer; every record is written whole and flushed at once.

    ``clamp=True`` turns an earlier-than-previous timestamp into the previous
    one (counted in :attr:`clamped`) instead of raising :class:`OutOfOrderError`.
    ``fsync=True`` also asks the OS to put every record on disk.
    """

    def __init__(self, target: Union[PathLike, IO[bytes]], channels: Sequence[Channel],
                 metadata: Optional[Dict[str, str]] = None, clamp: bool = False,
                 fsync: bool = False) -> None:
        self.header = Header(list(channels), dict(metadata or {}))
        head = encode_header(self.header)
        if hasattr(target, "write"):
            self.fh = target  # type: ignore[assignment]
            self._own = False
        else:
            self.fh = open(target, "wb")  # type: ignore[arg-type]
            self._own = True
        self._ids = {c.id for c in channels}
        self.clamp = clamp
        self.fsync = fsync
        self.clamped = 0
        self.records = 0
        self.bytes = 0
        self.last_ts: Optional[int] = None
        self._write(head)

    def _write(self, b: bytes) -> None:
        self.fh.write(b)
        self.fh.flush()
        if self.fsync:
            os.fsync(self.fh.fileno())

    def write(self, timestamp: int, channel: Union[int, str], data: bytes,
              direction: Union[int, str] = RX) -> int:
        """Write ``data`` (split into chunks of at most 65535 bytes); returns the stamp used."""
        if isinstance(channel, str):
            channel = self.header.channel(channel).id
        if isinstance(direction, str):
            direction = DIRECTIONS[direction]
        if channel not in self._ids:
            raise UnknownChannelError(f"channel id {channel} is not in the capture header")
        if direction not in (RX, TX):
            raise ValueError(f"bad direction {direction}")
        timestamp = int(timestamp)
        if not 0 <= timestamp < 2**64:
            raise ValueError(f"timestamp {timestamp} out of u64 range")
        if self.last_ts is not None and timestamp < self.last_ts:
            if not self.clamp:
                raise OutOfOrderError(
                    f"timestamp {timestamp} us is earlier than the previous {self.last_ts} us",
                    record=self.records)
            self.clamped += 1
            timestamp = self.last_ts
        self.last_ts = timestamp
        data = bytes(data)
        chunks = [data[i:i + MAX_CHUNK] for i in range(0, len(data), MAX_CHUNK)] or [b""]
        self._write(b"".join(encode_record(timestamp, channel, direction, c) for c in chunks))
        self.records += len(chunks)
        self.bytes += len(data)
        return timestamp

    def close(self) -> None:
        if self.fh is not None:
            try:
                self.fh.flush()
            finally:
                if self._own:
                    self.fh.close()
                self.fh = None  # type: ignore[assignment]

    def __enter__(self) -> "CaptureWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# ---------------------------------------------------------------------------
# reader


class CaptureReader:
    """Streaming reader.  Iterate to get :class:`Record` objects.

    The header is read (and checked) on construction: :attr:`header`.
    ``lenient=False`` (default) raises the first :class:`CaptureError` met;
    ``lenient=True`` counts problems in :attr:`stats` and skips them.
    ``channels`` optionally restricts the records yielded (others are still
    checked).
    """

    WINDOW = 1 << 18

    def __init__(self, source: Union[PathLike, IO[bytes]], lenient: bool = False) -> None:
        if hasattr(source, "read"):
            self.fh = source  # type: ignore[assignment]
            self._own = False
        else:
            self.fh = open(source, "rb")  # type: ignore[arg-type]
            self._own = True
        try:
            self.header, self.header_size = read_header(self.fh)
        except BaseException:
            self.close()
            raise
        self.lenient = lenient
        self.stats = ReadStats()
        self._ids = {c.id for c in self.header.channels}
        self._buf = bytearray()
        self._base = self.header_size   # file offset of _buf[0]
        self._eof = False
        self.last_ts: Optional[int] = None
        # lenient: a record far ahead of last_ts or before it skipped, stamped this
        self._far_ts: Optional[int] = None

    # buffered access -------------------------------------------------------
    def _fill(self, need: int) -> bool:
        """Make at least ``need`` bytes available from the buffer start if the file has them."""
        while len(self._buf) < need and not self._eof:
            chunk = self.fh.read(max(need - len(self._buf), 65536))
            if not chunk:
                self._eof = True
                break
            self._buf += chunk
        return len(self._buf) >= need

    def _drop(self, n: int) -> None:
        del self._buf[:n]
        self._base += n

    def _complete_at(self, i: int, spans: Optional[_SpanCrc] = None) -> int:
        """Size of a valid record starting at buffer index i, 0 if none (incomplete/CRC bad).
        spans: the buffer's prefix CRCs (a resync), else the record is CRCed."""
        if not self._fill(i + REC_HEAD_SIZE):
            return 0
        b = self._buf
        if b[i:i + 2] != SYNC:
            return 0
        n = b[i + 2] | (b[i + 3] << 8)
        size = REC_OVERHEAD + n
        if not self._fill(i + size):
            return 0
        end = i + REC_HEAD_SIZE + n
        crc = struct.unpack_from("<I", b, end)[0]
        if spans is not None:
            return size if spans.crc(i, end) == crc else 0
        self.stats.crc_bytes += end - i
        return size if zlib.crc32(memoryview(b)[i:end]) == crc else 0

    def _problem(self, exc: CaptureError) -> None:
        if not self.lenient:
            raise exc
        if len(self.stats.problems) < 50:
            self.stats.problems.append(str(exc))

    def _resync(self) -> bool:
        """Skip from buffer start to the next valid record; False if none before EOF."""
        i = 1
        spans = _SpanCrc(self._buf, self.stats)
        while True:
            if i >= self.WINDOW:
                # The bytes before i are garbage either way: the buffer stays
                # bounded whatever the length of the garbage.
                self.stats.skipped_bytes += i
                self._drop(i)
                spans = _SpanCrc(self._buf, self.stats)
                i = 0
            self._fill(i + REC_HEAD_SIZE)
            j = self._buf.find(SYNC, i)
            if j < 0:
                if self._eof:
                    return False
                # keep the last byte (could be the first half of a sync)
                keep = max(len(self._buf) - 1, 1)
                self.stats.skipped_bytes += keep
                self._drop(keep)
                spans = _SpanCrc(self._buf, self.stats)
                i = 0
                continue
            if self._complete_at(j, spans):
                self.stats.skipped_bytes += j
                self._drop(j)
                return True
            i = j + 1

    def __iter__(self) -> Iterator[Record]:
        st = self.stats
        while True:
            if not self._fill(1):
                return
            off = self._base
            have_head = self._fill(REC_HEAD_SIZE)
            size = self._complete_at(0)
            if not size:
                b = self._buf
                if have_head:
                    starts_sync = b[:2] == SYNC
                    n = b[2] | (b[3] << 8)
                    incomplete = starts_sync and not self._fill(REC_OVERHEAD + n)
                else:   # fewer than 14 bytes left in the file
                    starts_sync = SYNC.startswith(bytes(b[:2]))
                    incomplete = starts_sync
                if self._resync():
                    st.corrupt += 1
                    self._problem(CorruptRecordError(
                        "corrupt capture record (bad sync or CRC); resynchronised at byte "
                        f"{self._base}", off, st.records))
                    continue
                rest = len(self._buf)
                st.skipped_bytes += rest
                self._drop(rest)
                if incomplete:
                    st.truncated += 1
                    self._problem(TruncatedRecordError(
                        f"capture ends inside a record ({rest} bytes of it present)",
                        off, st.records))
                else:
                    st.corrupt += 1
                    self._problem(CorruptRecordError(
                        f"corrupt capture data up to the end of the file ({rest} bytes)",
                        off, st.records))
                return
            _, n, ts, ch, direction = REC_HEAD.unpack_from(self._buf, 0)
            data = bytes(self._buf[REC_HEAD_SIZE:REC_HEAD_SIZE + n])
            self._drop(size)
            if direction not in (RX, TX):
                st.corrupt += 1
                self._problem(CorruptRecordError(f"record with bad direction {direction}",
                                                 off, st.records))
                continue
            if ch not in self._ids:
                st.unknown_channel += 1
                self._problem(UnknownChannelError(
                    f"record for channel id {ch}, which the header does not list", off, st.records))
                continue
            if (self.lenient and self.last_ts is not None
                    and (ts < self.last_ts or ts - self.last_ts > MAX_STEP_US)
                    and not (self._far_ts is not None and abs(ts - self._far_ts) <= MAX_STEP_US)):
                # One record far ahead would make every later one out of order,
                # and a clock that stepped back would lose every later one: the
                # record counts as out of order unless the next one agrees.
                self._far_ts = ts
                st.out_of_order += 1
                how = ("earlier than" if ts < self.last_ts else "over an hour after")
                self._problem(OutOfOrderError(
                    f"record timestamp {ts} us is {how} the previous {self.last_ts} us "
                    "(not trusted alone)", off, st.records))
                continue
            if not self.lenient and self.last_ts is not None and ts < self.last_ts:
                st.out_of_order += 1
                self._problem(OutOfOrderError(
                    f"record timestamp {ts} us is earlier than the previous {self.last_ts} us",
                    off, st.records))
                continue
            self._far_ts = None
            self.last_ts = ts
            st.records += 1
            st.bytes += n
            yield Record(ts, ch, direction, data, off)

    def close(self) -> None:
        if self._own and self.fh is not None:
            self.fh.close()
        self.fh = None  # type: ignore[assignment]

    def __enter__(self) -> "CaptureReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def read_capture(path: PathLike, lenient: bool = False) -> Tuple[Header, List[Record], ReadStats]:
    """Read a whole capture into memory."""
    with CaptureReader(path, lenient=lenient) as r:
        recs = list(r)
        return r.header, recs, r.stats
