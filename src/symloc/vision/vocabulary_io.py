"""Vocabulary files: symloc's fast native binary format, and DBoW2's text format.

This module reads and writes the tree as arrays (:class:`VocabularyArrays`); the
:class:`~symloc.vision.vocabulary.Vocabulary` checks them and owns ``load`` / ``save``
(:func:`symloc.vision.vocabulary.load_vocabulary` and friends).

Native format (little-endian; all offsets in bytes)::

    0   8s   magic b"SYMLVOC\\0"
    8   u32  format version (1)
    12  u32  k                16  u32  L
    20  u32  scoring (DBoW2 code)   24  u32  weighting (DBoW2 code)
    28  u32  descriptor bytes (32)
    32  u64  number of nodes N (root included)
    40  u32  flags (bit 0: weights and parents zlib-compressed, see below)
    44  u32  CRC-32 of the stored payload
    48  u64  stored payload length
    56  8    reserved (zeros)
    64  payload: weights float64[N] | parent int32[N] | descriptors uint8[N * 32]

With flag bit 0 the payload is ``u64 n_z | zlib(weights | parent) (n_z bytes) | descriptors``:
weights and parents compress about tenfold, while trained binary descriptors are nearly random
(zlib saves ~6 % on them at the price of most of the load time), so they stay raw.

Loading is a single read plus ``np.frombuffer`` views, so a 1-million-word vocabulary loads in
well under a second.

Sizes are bounded before allocation: a file larger than :data:`MAX_VOCABULARY_BYTES` is refused
unread, the node count must fit in the payload that was read, and compressed weights are
inflated to at most the size the node count implies. DBoW2 text (plain or ``.gz``) is first
scanned in 1 MiB pieces without keeping them: more than :data:`MAX_TEXT_BYTES`, a line longer
than :data:`MAX_TEXT_LINE` characters, or lines shorter than a DBoW2 row can be on average (a
file of newlines) are refused before the text is held in memory.

DBoW2 text format (``TemplatedVocabulary::loadFromTextFile``, ORB-SLAM's ``ORBvoc.txt``): a
header line ``k L scoring weighting``, then one line per node after the root:
``parent isLeaf d0 d1 ... d31 weight`` (descriptor bytes as decimal integers).
"""

from __future__ import annotations

import gzip
import io
import struct
import warnings
import zlib
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from symloc.errors import VocabularyFileError
from symloc.files.atomic import atomic_open, atomic_write_text
from symloc.files.bounded import read_bytes_bounded

__all__ = [
    "MAGIC",
    "MAX_TEXT_BYTES",
    "MAX_TEXT_LINE",
    "MAX_VOCABULARY_BYTES",
    "TreeArrays",
    "VocabularyArrays",
    "parse_dbow2_text",
    "read_dbow2_text",
    "read_vocabulary",
    "write_dbow2_text",
    "write_vocabulary",
]

#: Largest vocabulary file, or decompressed DBoW2 text, read (ORB-SLAM's ORBvoc.txt is 145 MB).
MAX_VOCABULARY_BYTES = 256 * 2**20
#: Largest DBoW2 text, decompressed (ORB-SLAM's ORBvoc.txt is 145 MB); parsing holds ~4x it.
MAX_TEXT_BYTES = 160 * 2**20
#: Longest line of a DBoW2 text (a row is 35 numbers, under 200 characters).
MAX_TEXT_LINE = 4096
_MIN_MEAN_ROW = 60  # characters: a row is 2 + 32 integers and a weight
_CHUNK = 1 << 20

MAGIC = b"SYMLVOC\x00"
VERSION = 1
_HEADER = struct.Struct("<8sIIIIIIQIIQ8s")
HEADER_SIZE = _HEADER.size  # 64
DESC_BYTES = 32


class TreeArrays(Protocol):
    """What writing a vocabulary reads of it: a :class:`~symloc.vision.vocabulary.Vocabulary`
    or a :class:`VocabularyArrays`."""

    @property
    def k(self) -> int: ...
    @property
    def L(self) -> int: ...  # noqa: N802 (DBoW2's name)
    @property
    def scoring(self) -> int: ...
    @property
    def weighting(self) -> int: ...
    @property
    def parent(self) -> NDArray[np.int32]: ...
    @property
    def descriptors(self) -> NDArray[np.uint8]: ...
    @property
    def weights(self) -> NDArray[np.float64]: ...


@dataclass(frozen=True)
class VocabularyArrays:
    """A vocabulary's tree as read from a file, not yet checked as a tree.

    ``scoring`` and ``weighting`` are DBoW2's codes; ``source`` (the file) and ``where`` (the
    byte or line the tree starts at) name the place in an error found when the tree is checked
    (:meth:`symloc.vision.vocabulary.Vocabulary.from_arrays`).
    """

    k: int
    L: int
    scoring: int
    weighting: int
    parent: NDArray[np.int32]
    descriptors: NDArray[np.uint8]
    weights: NDArray[np.float64]
    source: str
    where: str


def write_vocabulary(voc: TreeArrays, path: str | Path, *, compress: bool = False) -> None:
    """Write ``voc`` in the native binary format (``compress``: zlib level 6 on weights and
    parents, descriptors raw)."""
    n = int(voc.parent.size)
    parent = voc.parent.astype("<i4").copy()
    parent[0] = -1
    head = voc.weights.astype("<f8").tobytes() + parent.tobytes()
    desc = np.ascontiguousarray(voc.descriptors, np.uint8).tobytes()
    if compress:
        z = zlib.compress(head, 6)
        payload = struct.pack("<Q", len(z)) + z + desc
    else:
        payload = head + desc
    header = _HEADER.pack(
        MAGIC,
        VERSION,
        voc.k,
        voc.L,
        int(voc.scoring),
        int(voc.weighting),
        DESC_BYTES,
        n,
        1 if compress else 0,
        zlib.crc32(payload) & 0xFFFFFFFF,
        len(payload),
        b"\x00" * 8,
    )
    with atomic_open(path, "wb") as fh:
        fh.write(header)
        fh.write(payload)


def read_vocabulary(path: str | Path) -> VocabularyArrays:
    """Read a vocabulary file: native binary, or DBoW2 text (detected by content).

    Raises
    ------
    VocabularyFileError
        The file is corrupt or truncated; the message names the byte (binary) or line (text).
    """
    path = Path(path)
    data = _read_bounded(path)  # one read: far faster than reading a header, then the rest
    if data[: len(MAGIC)] != MAGIC:
        if path.suffix == ".gz" or data[:2] == b"\x1f\x8b" or data[:1].isdigit():
            return read_dbow2_text(path)
        raise VocabularyFileError(
            f"{path}: byte 0: not a symloc vocabulary (magic {data[:8]!r}, expected {MAGIC!r})"
            " nor a DBoW2 text vocabulary"
        )
    return _parse_native(data, str(path))


def _read_bounded(path: Path) -> bytes:
    """The file's bytes: a regular file (not a FIFO or device) of at most
    :data:`MAX_VOCABULARY_BYTES`, refused unread otherwise."""
    return read_bytes_bounded(
        path, MAX_VOCABULARY_BYTES, what="the vocabulary file", error=VocabularyFileError
    )


def _gzip_chunks(data: bytes, name: str) -> Iterator[bytes]:
    """The decompressed content of gzip ``data`` in pieces of at most 1 MiB."""
    try:
        with gzip.GzipFile(fileobj=io.BytesIO(data)) as fh:
            while piece := fh.read(_CHUNK):
                yield piece
    except (OSError, EOFError, zlib.error) as err:
        raise VocabularyFileError(f"{name}: cannot decompress: {err}") from err


def _scan_text(chunks: Iterable[bytes], name: str) -> None:
    """Refuse a text over :data:`MAX_TEXT_BYTES`, with a line over :data:`MAX_TEXT_LINE`, or
    with more lines than a DBoW2 file of its size can have, holding one piece at a time."""
    total = newlines = 0
    run = 0  # characters since the last newline
    for piece in chunks:
        total += len(piece)
        if total > MAX_TEXT_BYTES:
            raise VocabularyFileError(
                f"{name}: more than {MAX_TEXT_BYTES:,} bytes of DBoW2 text; refused"
            )
        at = np.flatnonzero(np.frombuffer(piece, np.uint8) == 10)
        # lengths of the lines this piece ends (the first carries the previous run)
        ends = np.diff(at, prepend=-1) - 1
        if ends.size:
            ends[0] += run
        long = np.flatnonzero(ends > MAX_TEXT_LINE)
        run = len(piece) - int(at[-1]) - 1 if at.size else run + len(piece)
        if long.size or run > MAX_TEXT_LINE:
            line = newlines + 1 + (int(long[0]) if long.size else at.size)
            raise VocabularyFileError(
                f"{name}: line {line}: longer than {MAX_TEXT_LINE:,} characters"
                " (not a DBoW2 vocabulary)"
            )
        newlines += at.size
    if newlines > total // _MIN_MEAN_ROW + 16:
        raise VocabularyFileError(
            f"{name}: {newlines:,} lines in {total:,} bytes: shorter than DBoW2 rows"
            f" ({_MIN_MEAN_ROW} characters or more each)"
        )


def _parse_native(data: bytes, name: str) -> VocabularyArrays:
    if len(data) < HEADER_SIZE:
        raise VocabularyFileError(
            f"{name}: byte {len(data)}: truncated header ({len(data)} of {HEADER_SIZE} bytes)"
        )
    (_, version, k, L, scoring, weighting, dbytes, n, flags, crc, plen, _) = _HEADER.unpack_from(
        data
    )
    if version != VERSION:
        raise VocabularyFileError(
            f"{name}: byte 8: format version {version}, this symloc reads version {VERSION}"
        )
    checks = [
        (12, "k", k, 2 <= k <= 255),
        (16, "L", L, 1 <= L <= 32),
        (20, "scoring", scoring, scoring <= 5),
        (24, "weighting", weighting, weighting <= 3),
        (28, "descriptor bytes", dbytes, dbytes == DESC_BYTES),
        (32, "node count", n, n >= 1),
        (40, "flags", flags, flags <= 1),
    ]
    for off, field, value, ok in checks:
        if not ok:
            raise VocabularyFileError(f"{name}: byte {off}: invalid {field} {value}")
    stored = memoryview(data)[HEADER_SIZE:]
    if len(stored) != plen:
        raise VocabularyFileError(
            f"{name}: byte {HEADER_SIZE + min(len(stored), plen)}: payload is {len(stored)} bytes, "
            f"header says {plen} ({'truncated' if len(stored) < plen else 'trailing data'})"
        )
    if zlib.crc32(stored) & 0xFFFFFFFF != crc:
        raise VocabularyFileError(
            f"{name}: bytes {HEADER_SIZE}..{HEADER_SIZE + plen}: checksum mismatch (corrupt payload)"
        )
    if n * DESC_BYTES > len(stored):
        raise VocabularyFileError(
            f"{name}: byte 32: node count {n} needs {n * DESC_BYTES:,} bytes of descriptors,"
            f" the payload has {len(stored):,}"
        )
    head: bytes | memoryview = stored
    desc_buf: bytes | memoryview = stored
    desc_at = 12 * n
    if flags & 1:
        try:
            (nz,) = struct.unpack_from("<Q", stored, 0)
            inflate = zlib.decompressobj()
            # weights and parents of n nodes are 12 n bytes: inflate no more than that
            head = inflate.decompress(stored[8 : 8 + nz], 12 * n + 1)
        except (struct.error, zlib.error) as err:
            raise VocabularyFileError(
                f"{name}: byte {HEADER_SIZE}: cannot decompress weights and parents: {err}"
            ) from err
        desc_at = 8 + nz
    n_head = len(head) if flags & 1 else 12 * n
    n_desc = len(desc_buf) - desc_at
    if n_head != 12 * n or n_desc != n * DESC_BYTES:
        raise VocabularyFileError(
            f"{name}: byte {HEADER_SIZE}: payload holds {n_head} bytes of weights and parents and "
            f"{n_desc} of descriptors, {n} nodes need {12 * n} and {n * DESC_BYTES}"
        )
    weights = np.frombuffer(head, "<f8", n, 0)
    parent = np.frombuffer(head, "<i4", n, 8 * n)
    desc = np.frombuffer(desc_buf, np.uint8, n * DESC_BYTES, desc_at).reshape(n, DESC_BYTES)
    bad = np.flatnonzero((parent[1:] < 0) | (parent[1:] >= np.arange(1, n)))
    if bad.size:
        i = int(bad[0]) + 1
        off = HEADER_SIZE + 8 * n + 4 * i if not flags & 1 else HEADER_SIZE
        raise VocabularyFileError(
            f"{name}: byte {off}: node {i} has parent {int(parent[i])}, expected an earlier node"
        )
    return _build(name, k, L, scoring, weighting, parent, desc, weights, where="byte 64")


def _build(
    name: str,
    k: int,
    L: int,
    scoring: int,
    weighting: int,
    parent: NDArray[np.int32],
    desc: NDArray[np.uint8],
    weights: NDArray[np.float64],
    *,
    where: str,
) -> VocabularyArrays:
    return VocabularyArrays(k, L, scoring, weighting, parent, desc, weights, name, where)


def read_dbow2_text(path: str | Path) -> VocabularyArrays:
    """Read a DBoW2 text vocabulary (``ORBvoc.txt``; ``.gz`` accepted).

    Raises
    ------
    VocabularyFileError
        Naming the line (1-based) that is malformed.
    """
    path = Path(path)
    raw = _read_bounded(path)
    name = str(path)
    if path.suffix == ".gz" or raw[:2] == b"\x1f\x8b":
        _scan_text(_gzip_chunks(raw, name), name)  # first pass: nothing kept
        raw = b"".join(_gzip_chunks(raw, name))
    else:
        view = memoryview(raw)
        _scan_text((bytes(view[i : i + _CHUNK]) for i in range(0, len(raw), _CHUNK)), name)
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError as err:
        line = raw[: err.start].count(b"\n") + 1
        raise VocabularyFileError(f"{path}: line {line}: not ASCII text") from err
    return parse_dbow2_text(text, str(path))


def parse_dbow2_text(text: str, name: str = "<text>") -> VocabularyArrays:
    """Parse the content of a DBoW2 text vocabulary (see :func:`read_dbow2_text`)."""
    lines = text.split("\n")
    header = lines[0].split()
    if len(header) != 4:
        raise VocabularyFileError(
            f"{name}: line 1: expected header 'k L scoring weighting', got {lines[0][:60]!r}"
        )
    try:
        k, L, scoring, weighting = (int(t) for t in header)
    except ValueError as err:
        raise VocabularyFileError(f"{name}: line 1: header values must be integers") from err
    if not (2 <= k <= 20 and 1 <= L <= 10 and 0 <= scoring <= 5 and 0 <= weighting <= 3):
        raise VocabularyFileError(
            f"{name}: line 1: header out of range (k in 2..20, L in 1..10, scoring 0..5, "
            f"weighting 0..3), got {k} {L} {scoring} {weighting}"
        )
    body_idx = [i for i in range(1, len(lines)) if lines[i].strip()]
    n_rows = len(body_idx)
    ncol = 3 + DESC_BYTES
    rows: NDArray[np.float64]
    chunks = []
    chunk = 1 << 16  # lines per vectorised chunk (bounds the temporary arrays)
    for a in range(0, n_rows, chunk):
        part = body_idx[a : a + chunk]
        fast = _parse_rows_fast("\n".join(lines[i] for i in part), len(part), ncol)
        if fast is None:
            break
        chunks.append(fast)
    if sum(c.shape[0] for c in chunks) == n_rows and n_rows:
        flat, ok = np.concatenate(chunks).reshape(-1), True
    else:
        chunks.clear()
        body = "\n".join(lines[i] for i in body_idx)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                flat = np.fromstring(body, dtype=np.float64, sep=" ") if body else np.zeros(0)
            ok = flat.size == n_rows * ncol
        except (ValueError, DeprecationWarning):
            ok = False
    if not ok:
        for i in body_idx:
            toks = lines[i].split()
            if len(toks) != ncol:
                raise VocabularyFileError(
                    f"{name}: line {i + 1}: expected {ncol} values "
                    f"(parent isLeaf {DESC_BYTES} bytes weight), got {len(toks)}"
                )
            try:
                [float(t) for t in toks]
            except ValueError as err:
                raise VocabularyFileError(f"{name}: line {i + 1}: non-numeric value") from err
        raise VocabularyFileError(f"{name}: cannot parse")  # pragma: no cover
    rows = flat.reshape(n_rows, ncol)
    line_no = np.array(body_idx, np.int64) + 1
    ints = rows[:, : 2 + DESC_BYTES]
    n = n_rows + 1

    def fail(mask: NDArray[np.bool_], what: str) -> None:
        bad = np.flatnonzero(mask)
        if bad.size:
            raise VocabularyFileError(f"{name}: line {int(line_no[bad[0]])}: {what}")

    fail(
        np.any(ints != np.round(ints), axis=1),
        "parent, isLeaf and descriptor bytes must be integers",
    )
    parent = ints[:, 0].astype(np.int64)
    fail((parent < 0) | (parent >= np.arange(1, n)), "parent must be an earlier node id")
    leaf = ints[:, 1]
    fail((leaf != 0) & (leaf != 1), "isLeaf must be 0 or 1")
    db = ints[:, 2:]
    fail(np.any((db < 0) | (db > 255), axis=1), "descriptor bytes must be in 0..255")
    fail(~np.isfinite(rows[:, -1]), "weight must be finite")
    # consistency: a node flagged leaf must have no children, an inner node must have some
    counts = np.bincount(parent, minlength=n)[1:]
    fail((leaf == 1) & (counts > 0), "node is flagged as leaf but has children")
    fail((leaf == 0) & (counts == 0), "node is flagged as inner node but has no children")
    full_parent = np.concatenate([[-1], parent]).astype(np.int32)
    desc = np.zeros((n, DESC_BYTES), np.uint8)
    desc[1:] = db.astype(np.uint8)
    weights = np.concatenate([[0.0], rows[:, -1]])
    return _build(
        name, max(k, 2), L, scoring, weighting, full_parent, desc, weights, where="line 1"
    )


def _parse_rows_fast(body: str, n_rows: int, ncol: int) -> NDArray[np.float64] | None:
    """Vectorised parse of ``n_rows`` lines of ``ncol - 1`` unsigned integers and one float.

    Returns ``(n_rows, ncol)`` values, or None when the text is not exactly that (the caller
    then falls back to a slower parser that names the offending line).
    """
    if n_rows == 0:
        return None
    try:
        raw = body.encode("ascii")
    except UnicodeEncodeError:
        return None
    buf = np.frombuffer(raw, np.uint8)
    space = (buf == 32) | (buf == 10) | (buf == 9) | (buf == 13)
    edge = np.flatnonzero(np.diff(np.concatenate(([True], space, [True])).astype(np.int8)))
    edge = edge.astype(np.int32) if buf.size < 2**31 else edge
    starts, ends = edge[0::2], edge[1::2]
    if starts.size != n_rows * ncol:
        return None
    starts = starts.reshape(n_rows, ncol)
    ends = ends.reshape(n_rows, ncol)
    s_int, e_int = starts[:, :-1].ravel(), ends[:, :-1].ravel()
    length = e_int - s_int
    if length.max(initial=0) > 9:
        return None
    value = np.zeros(s_int.size, np.int64)
    for pos in range(int(length.max(initial=0))):
        live = pos < length
        digit = buf[np.where(live, s_int + pos, 0)].astype(np.int64) - 48
        if np.any(live & ((digit < 0) | (digit > 9))):
            return None
        value = np.where(live, value * 10 + digit, value)
    try:
        weights = np.array(
            [raw[a:b] for a, b in zip(starts[:, -1].tolist(), ends[:, -1].tolist(), strict=True)]
        ).astype(np.float64)
    except ValueError:
        return None
    out = np.empty((n_rows, ncol), np.float64)
    out[:, :-1] = value.reshape(n_rows, ncol - 1)
    out[:, -1] = weights
    return out


def write_dbow2_text(voc: TreeArrays, path: str | Path) -> None:
    """Write ``voc`` as a DBoW2 text vocabulary (``saveToTextFile`` layout, full precision)."""
    n = int(voc.parent.size)
    par = voc.parent.copy()
    par[0] = 0
    lines = [f"{voc.k} {voc.L}  {int(voc.scoring)} {int(voc.weighting)}"]
    leaf = (np.bincount(voc.parent[1:], minlength=n) == 0).astype(np.int64)  # node 0 unused
    desc = voc.descriptors
    for i in range(1, n):
        d = " ".join(map(str, desc[i].tolist()))
        lines.append(f"{int(par[i])} {int(leaf[i])} {d}  {float(voc.weights[i])!r}")
    atomic_write_text(path, "\n".join(lines) + "\n")
