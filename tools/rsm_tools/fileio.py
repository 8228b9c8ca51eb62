"""Small file helpers shared by the rsm tools.

Inputs may be plain text or gzip; which one is decided by the first two bytes
(the gzip magic number), not by the file name.  Outputs whose name ends in
``.gz`` are gzip-compressed deterministically: the gzip header carries no
file name and a modification time of 0, so the same content always gives the
same bytes.
"""

import gzip
import io
import os
from typing import IO, Union

GZIP_MAGIC = b"\x1f\x8b"

PathLike = Union[str, "os.PathLike[str]"]


def is_gzip(path: PathLike) -> bool:
    """True if the file starts with the gzip magic number."""
    with open(path, "rb") as fh:
        return fh.read(2) == GZIP_MAGIC


def open_binary(path: PathLike) -> IO[bytes]:
    """Open a file for reading bytes, transparently decompressing gzip."""
    raw = open(path, "rb")  # a BufferedReader, so peek() does not consume
    head = raw.peek(2)[:2]
    if head == GZIP_MAGIC:
        return _GzipOwning(raw, mode="rb")
    return raw


class _GzipOwning(gzip.GzipFile):
    """A GzipFile (reading or writing) that also closes the underlying raw file."""

    def __init__(self, raw: IO[bytes], **kwargs) -> None:
        super().__init__(fileobj=raw, **kwargs)
        self._owned_raw = raw

    def close(self) -> None:
        try:
            super().close()
        finally:
            self._owned_raw.close()


def open_text(path: PathLike, newline: str = "") -> IO[str]:
    """Open a plain or gzip text file for reading (UTF-8, undecodable bytes
    replaced); ``newline`` as io.TextIOWrapper's ("\n": lines end at LF
    alone, a lone CR stays inside its line)."""
    return io.TextIOWrapper(open_binary(path), encoding="utf-8", errors="replace", newline=newline)


def open_binary_output(path: PathLike) -> IO[bytes]:
    """Open an output file for bytes; gzip (mtime 0, no name) if it ends in ``.gz``."""
    if str(path).endswith(".gz"):
        raw = open(path, "wb")
        return _GzipOwning(raw, filename="", mode="wb", compresslevel=9, mtime=0)
    return open(path, "wb")


def open_text_output(path: PathLike) -> IO[str]:
    """Open a text output file (UTF-8, ``\\n`` line ends); gzip if it ends in ``.gz``."""
    return io.TextIOWrapper(open_binary_output(path), encoding="utf-8", newline="\n")
