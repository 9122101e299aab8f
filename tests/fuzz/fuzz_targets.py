"""Bad inputs for every file loader, every command and the node logic (hypothesis strategies),
and the guard that runs one input: only symloc's error types may come out, within a time bound.

Used by ``tests/fuzz/test_fuzz.py`` (CI: asserts no escape) and by
``benchmarks/fuzz_report.py`` (counts inputs and escapes per target, also against older code).
Every strategy draws *bad or borderline* inputs: wrong types, NaN, huge and negative numbers,
declared sizes far beyond the data, truncated and bit-flipped files, compression bombs.
"""

from __future__ import annotations

import contextlib
import gzip
import io
import math
import os
import signal
import sqlite3
import struct
import zlib
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
from hypothesis import strategies as st

from symloc.errors import SymlocError

#: Seconds one input may take before it counts as a hang (``benchmarks/fuzz_report.py`` sets
#: ``SYMLOC_FUZZ_TIME_BOUND=60``, the issue's bound).
TIME_BOUND = float(os.environ.get("SYMLOC_FUZZ_TIME_BOUND", "10"))
#: Inputs per target and outcome: ``counts[target][outcome]``.
counts: dict[str, Counter[str]] = {}
#: The command line being run (``benchmarks/fuzz_report.py`` names it beside an escape).
last_argv: list[list[str]] = [[]]


class Hang(Exception):  # noqa: N818 - it is what happened
    """An input took longer than :data:`TIME_BOUND`."""


@contextlib.contextmanager
def time_bound(seconds: float = TIME_BOUND) -> Iterator[None]:
    """Raise :class:`Hang` in the main thread when the block runs longer than ``seconds``."""

    def on_alarm(signum: int, frame: Any) -> None:
        raise Hang(f"input ran longer than {seconds} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def guard(target: str, fn: Callable[[], Any], *, allowed: tuple[type, ...] = (SymlocError,)) -> str:
    """Run one input; returns ``ok``, ``refused`` (an allowed error) or ``escape: <Type>: msg``
    and counts it under ``target``."""
    try:
        with time_bound():
            fn()
        outcome = "ok"
    except allowed:
        outcome = "refused"
    except Exception as err:  # the point of the fuzz suite: anything else is an escape
        outcome = f"escape: {type(err).__name__}: {str(err)[:160]}"
    counts.setdefault(target, Counter())[outcome.split(":")[0]] += 1
    return outcome


# ----------------------------------------------------------------------- building blocks

bad_floats = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300, 1e154, 5e-324, 2.0**63]),
)
bad_ints = st.one_of(
    st.integers(-(2**64), 2**64),
    st.sampled_from([0, -1, 1, 2**31 - 1, 2**31, 2**32, 2**63 - 1, 65535, 16000]),
)
scalars = st.one_of(
    bad_floats, bad_ints, st.text(max_size=12), st.none(), st.booleans(), st.binary(max_size=8)
)
values = st.one_of(scalars, st.lists(scalars, max_size=5))


def png_header(width: int, height: int, tail: bytes = b"") -> bytes:
    """A PNG signature and an IHDR chunk declaring ``width x height`` (8-bit RGB), then ``tail``."""
    ihdr = struct.pack(">IIBBBBB", width & 0xFFFFFFFF, height & 0xFFFFFFFF, 8, 2, 0, 0, 0)
    crc = struct.pack(">I", zlib.crc32(b"IHDR" + ihdr))
    return b"\x89PNG\r\n\x1a\n" + struct.pack(">I", 13) + b"IHDR" + ihdr + crc + tail


def jpeg_header(width: int, height: int, tail: bytes = b"") -> bytes:
    """JPEG SOI and a SOF0 segment declaring ``width x height``, then ``tail``."""
    sof = b"\xff\xc0" + struct.pack(">HBHHB", 11, 8, height & 0xFFFF, width & 0xFFFF, 1)
    return b"\xff\xd8" + sof + b"\x01\x11\x00" + tail


def small_png(rng_bytes: bytes) -> bytes:
    import cv2

    side = 2 + rng_bytes[0] % 30 if rng_bytes else 4
    img = np.frombuffer(
        (rng_bytes * (side * side))[: side * side] or b"\x00" * side * side, np.uint8
    )
    _, enc = cv2.imencode(".png", img.reshape(side, side))
    return bytes(enc.tobytes())


@st.composite
def image_bytes(draw: st.DrawFn) -> bytes:
    """Encoded-image bytes: valid, declaring absurd sizes, truncated, corrupt, or random."""
    kind = draw(st.sampled_from(["png_decl", "jpeg_decl", "pgm", "valid", "cut", "flip", "random"]))
    w = draw(st.one_of(st.integers(0, 70000), st.sampled_from([0, 1, 16000, 65535, 2**31])))
    h = draw(st.one_of(st.integers(0, 70000), st.sampled_from([0, 1, 16000, 65535, 2**31])))
    tail = draw(st.binary(max_size=300))
    if kind == "png_decl":
        return png_header(w, h, tail)
    if kind == "jpeg_decl":
        return jpeg_header(w, h, tail)
    if kind == "pgm":
        maxval = draw(st.sampled_from([255, 65535, 0, 70000]))
        magic = draw(st.sampled_from([b"P5", b"P2", b"P6", b"P1", b"P4"]))
        return magic + f"\n{w} {h}\n{maxval}\n".encode() + tail
    valid = small_png(draw(st.binary(min_size=1, max_size=64)))
    if kind == "valid":
        return valid
    if kind == "cut":
        return valid[: draw(st.integers(0, len(valid)))]
    if kind == "flip":
        b = bytearray(valid)
        for _ in range(draw(st.integers(1, 20))):
            b[draw(st.integers(0, len(b) - 1))] = draw(st.integers(0, 255))
        return bytes(b)
    return draw(st.binary(max_size=400))


# ----------------------------------------------------------------------- map files


@st.composite
def map_files(draw: st.DrawFn) -> tuple[str, bytes]:
    """A map YAML text (valid, or with 1-3 fields made bad, or garbage) and the bytes of the
    image it names (valid, declaring absurd sizes, truncated, corrupt or random)."""
    fields: dict[str, Any] = {
        "image": "m.pgm",
        "resolution": 0.05,
        "origin": [0.0, 0.0, 0.0],
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
        "negate": 0,
        "mode": "trinary",
    }
    bad = {
        "image": st.sampled_from(["m.png", "", "missing.pgm", "/", "..", "m.pgm\x00"]),
        "resolution": st.one_of(bad_floats, scalars),
        "origin": st.one_of(
            st.lists(bad_floats, min_size=3, max_size=3), st.lists(scalars, max_size=4), scalars
        ),
        "occupied_thresh": st.one_of(bad_floats, scalars),
        "free_thresh": st.one_of(bad_floats, scalars),
        "negate": scalars,
        "mode": st.one_of(st.sampled_from(["scale", "raw", "x"]), scalars),
    }
    for key in draw(st.lists(st.sampled_from(sorted(bad)), max_size=3, unique=True)):
        if draw(st.integers(0, 3)) == 0:
            fields.pop(key)
        else:
            fields[key] = draw(bad[key])
    if draw(st.booleans()):
        fields["width"] = draw(st.one_of(values, st.integers(1, 40)))
        fields["height"] = draw(st.one_of(values, st.integers(1, 40)))
    lines = [f"{k}: {v!r}" if not isinstance(v, str) else f"{k}: '{v}'" for k, v in fields.items()]
    text = "\n".join(lines) + "\n"
    if draw(st.integers(0, 9)) == 0:
        text = draw(st.text(max_size=200))
    return text, draw(image_bytes())


def load_map_file(folder: Path, text: str, image: bytes) -> None:
    from symloc.grid.map_io import load_map

    (folder / "m.pgm").write_bytes(image)
    (folder / "m.png").write_bytes(image)
    y = folder / "map.yaml"
    y.write_bytes(text.encode("utf-8", "surrogatepass"))
    load_map(y)


# ----------------------------------------------------------------------- vocabularies


@st.composite
def vocabulary_files(draw: st.DrawFn) -> tuple[str, bytes]:
    """(file name, bytes) of a native or DBoW2-text vocabulary, bad in some way."""
    kind = draw(st.sampled_from(["native", "native_z", "text", "gz", "random"]))
    if kind.startswith("native"):
        n = draw(st.one_of(st.integers(0, 50), st.sampled_from([2**31, 2**40, 2**63])))
        compress = kind == "native_z"
        if compress:
            # weights + parents: a small stream that inflates to far more than 12 n
            raw_len = draw(st.integers(0, 1 << 22))
            z = zlib.compress(b"\x00" * raw_len, 9)
            payload = struct.pack("<Q", len(z)) + z + draw(st.binary(max_size=64 * 32))
        else:
            payload = draw(st.binary(max_size=64 * 44))
        if draw(st.booleans()):
            crc = zlib.crc32(payload) & 0xFFFFFFFF
        else:
            crc = draw(st.integers(0, 2**32 - 1))
        plen = len(payload) if draw(st.booleans()) else draw(st.integers(0, 2**64 - 1))
        header = struct.pack(
            "<8sIIIIIIQIIQ8s",
            b"SYMLVOC\x00",
            draw(st.sampled_from([1, 1, 1, 0, 2, 2**32 - 1])),
            draw(st.integers(0, 300)),
            draw(st.integers(0, 40)),
            draw(st.integers(0, 7)),
            draw(st.integers(0, 5)),
            draw(st.sampled_from([32, 32, 0, 64])),
            n % 2**64,
            1 if compress else draw(st.integers(0, 3)),
            crc,
            plen % 2**64,
            b"\x00" * 8,
        )
        return "v.symvoc", header + payload
    if kind in ("text", "gz"):
        head = draw(
            st.one_of(
                st.just("10 5 0 0"),
                st.builds(lambda *v: " ".join(map(str, v)), bad_ints, bad_ints, bad_ints, bad_ints),
                st.text(max_size=20),
            )
        )
        rows = draw(
            st.lists(
                st.lists(
                    st.one_of(st.integers(-5, 300), bad_floats, st.text(max_size=3)), max_size=36
                ),
                max_size=8,
            )
        )
        text = head + "\n" + "\n".join(" ".join(map(str, r)) for r in rows) + "\n"
        data = text.encode("utf-8", "replace")
        if kind == "gz":
            if draw(st.booleans()):
                data = gzip.compress(data + b"\n" * draw(st.integers(0, 1 << 22)))
            else:
                data = gzip.compress(data)[: draw(st.integers(0, 40))]
            return "v.txt.gz", data
        return "v.txt", data
    return draw(st.sampled_from(["v.symvoc", "v.txt", "v.gz"])), draw(st.binary(max_size=300))


def load_vocabulary_file(folder: Path, name: str, data: bytes) -> None:
    from symloc.vision.vocabulary import load_vocabulary

    p = folder / name
    p.write_bytes(data)
    load_vocabulary(p)


# ----------------------------------------------------------------------- CARMEN logs

_FIELD = st.one_of(
    st.integers(-5, 400).map(str),
    bad_floats.map(repr),
    st.sampled_from(["nan", "inf", "-inf", "1e999", "", "x", "0x10"]),
)


@st.composite
def carmen_logs(draw: st.DrawFn) -> tuple[str, bytes]:
    lines = []
    for _ in range(draw(st.integers(0, 12))):
        kind = draw(st.sampled_from(["FLASER", "ODOM", "PARAM", "ROBOTLASER1", "#", "NEFF", ""]))
        if kind == "FLASER":
            n = draw(st.one_of(st.integers(-3, 12), st.sampled_from([10**9, 2**63])))
            k = draw(st.one_of(st.just(min(max(n, 0) + 9, 40)), st.integers(0, 30)))
            lines.append(
                " ".join(["FLASER", str(n), *draw(st.lists(_FIELD, min_size=k, max_size=k))])
            )
        elif kind == "ODOM":
            lines.append(" ".join(["ODOM", *draw(st.lists(_FIELD, max_size=12))]))
        else:
            lines.append(" ".join([kind, *draw(st.lists(_FIELD, max_size=4))]))
    data = "\n".join(lines).encode()
    how = draw(st.sampled_from(["plain", "gz", "gz_cut", "random"]))
    if how == "gz":
        return "log.gz", gzip.compress(data)
    if how == "gz_cut":
        z = gzip.compress(data * 5)
        return "log.gz", z[: draw(st.integers(0, len(z)))]
    if how == "random":
        return "log", draw(st.binary(max_size=300))
    return "log", data


def read_carmen_file(folder: Path, name: str, data: bytes) -> None:
    from symloc.io.carmen import read_carmen

    p = folder / name
    p.write_bytes(data)
    read_carmen(p)


# ----------------------------------------------------------------------- visual maps

_COLUMNS = {
    "images": ["direction", "heading", "width", "height", "n_features", "bow_words", "bow_values",
               "keypoints", "descriptors", "image_png", "place_id"],
    "places": ["kind", "symmetry_order", "gv_distance", "x", "y", "heading", "label", "n_directions"],
    "meta": ["value", "key"],
}  # fmt: skip
_LOOSE = {
    "images": "place_id INTEGER, direction INTEGER, heading REAL, width INTEGER, height INTEGER,"
    " n_features INTEGER, bow_words BLOB, bow_values BLOB, keypoints BLOB, descriptors BLOB,"
    " image_png BLOB",
    "places": "id INTEGER PRIMARY KEY, kind TEXT, symmetry_order INTEGER, gv_distance REAL,"
    " x REAL, y REAL, heading REAL, n_directions INTEGER, label TEXT, created REAL",
}


@st.composite
def db_mutations(draw: st.DrawFn) -> list[tuple[str, Any]]:
    """SQL mutations of a valid visual map (and byte-level ones, marked ``bytes``)."""
    out: list[tuple[str, Any]] = []
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(
            st.sampled_from(["update", "update", "drop", "pragma", "bytes", "cut", "empty"])
        )
        if kind == "update":
            table = draw(st.sampled_from(sorted(_COLUMNS)))
            col = draw(st.sampled_from(_COLUMNS[table]))
            value = draw(
                st.one_of(
                    bad_ints.filter(lambda v: -(2**63) <= v < 2**63),
                    bad_floats,
                    st.text(max_size=8),
                    st.binary(max_size=40),
                    st.none(),
                    st.just(png_header(16000, 16000)),
                )
            )
            out.append(("update", (table, col, value)))
        elif kind == "drop":
            out.append(("sql", draw(st.sampled_from([
                "DROP TABLE images", "DROP TABLE places", "DROP TABLE meta",
                "ALTER TABLE images RENAME COLUMN keypoints TO kp", "DELETE FROM images",
                "UPDATE meta SET value = '/etc/passwd' WHERE key = 'vocabulary'",
            ]))))  # fmt: skip
        elif kind == "pragma":
            out.append(("sql", draw(st.sampled_from([
                "PRAGMA user_version = 99", "PRAGMA user_version = 0",
                "PRAGMA application_id = 7", "PRAGMA application_id = 0",
            ]))))  # fmt: skip
        else:
            out.append((kind, draw(st.binary(min_size=1, max_size=16))))
    return out


def loosen(path: Path) -> None:
    """Recreate the tables without NOT NULL constraints, so mutations can store NULLs."""
    con = sqlite3.connect(path)
    try:
        for table, cols in _LOOSE.items():
            con.executescript(
                f"CREATE TABLE old AS SELECT * FROM {table}; DROP TABLE {table};"
                f" CREATE TABLE {table} ({cols}); INSERT INTO {table} SELECT * FROM old;"
                " DROP TABLE old;"
            )
        con.commit()
        con.execute("PRAGMA journal_mode = delete")
    finally:
        con.close()


def apply_db_mutations(path: Path, mutations: list[tuple[str, Any]]) -> None:
    """Apply ``mutations`` to the (loosened, see :func:`loosen`) database file at ``path``."""
    con = sqlite3.connect(path)
    try:
        con.execute("PRAGMA synchronous = OFF")
        for kind, arg in mutations:
            with contextlib.suppress(sqlite3.Error):
                if kind == "update":
                    table, col, value = arg
                    con.execute(f"UPDATE {table} SET {col} = ?", (value,))
                elif kind == "sql":
                    con.execute(arg)
        con.commit()
    finally:
        con.close()
    data = bytearray(path.read_bytes())
    for kind, arg in mutations:
        if kind == "bytes" and data:
            for i, b in enumerate(arg):
                data[(i * 7919 + b * 104729) % len(data)] = b
        elif kind == "cut":
            data = data[: (arg[0] * 997) % (len(data) + 1)]
        elif kind == "empty":
            data = bytearray()
    path.write_bytes(bytes(data))


def read_visual_map(path: Path, readonly: bool) -> None:
    import inspect

    from symloc.vision.bow import BowVector
    from symloc.vision.visual_map import VisualMap

    before = path.read_bytes()
    kwargs = {"readonly": readonly} if "readonly" in inspect.signature(VisualMap).parameters else {}
    try:
        with VisualMap(path, create=False, **kwargs) as vm:
            vm.get_meta("vocabulary")
            len(vm)
            for pid in vm.place_ids():
                place = vm.place(pid)
                vm.find_places(place.gv_distance, 0.5)
            vm.query(BowVector(np.array([1, 2], np.int32), np.array([0.5, 0.5])))
    finally:
        if readonly:
            assert path.read_bytes() == before, "a visual map opened read-only was written"


# ----------------------------------------------------------------------- bags


@st.composite
def bag_mutations(draw: st.DrawFn) -> tuple[str, str, int, bytes]:
    """(bag format, mutation, position seed, bytes) for one of the small valid bags."""
    fmt = draw(st.sampled_from(["ros2", "mcap", "ros1"]))
    how = draw(st.sampled_from(["flip", "flip", "cut", "zero", "metadata"]))
    return fmt, how, draw(st.integers(0, 2**31)), draw(st.binary(min_size=1, max_size=24))


def mutate_bag(src: Path, dst: Path, how: str, seed: int, data: bytes) -> Path:
    """Copy the bag ``src`` to ``dst`` and damage its storage file (or its metadata.yaml)."""
    import shutil

    if src.is_dir():
        shutil.copytree(src, dst)
        store = next(f for f in dst.iterdir() if f.suffix in (".db3", ".mcap"))
    else:
        shutil.copy(src, dst)
        store = dst
    if how == "metadata" and dst.is_dir():
        meta = dst / "metadata.yaml"
        text = meta.read_bytes()
        at = seed % max(len(text), 1)
        meta.write_bytes(text[:at] + data + text[at + len(data) :])
        return dst
    b = bytearray(store.read_bytes())
    if how == "cut":
        b = b[: seed % (len(b) + 1)]
    elif how == "zero":
        at = seed % max(len(b), 1)
        b[at : at + 4096] = bytes(len(b[at : at + 4096]))
    else:
        for i, x in enumerate(data):
            b[(seed + i * 104729) % len(b)] = x
    store.write_bytes(bytes(b))
    return dst


def read_bag_skip(path: Path) -> None:
    """``read_bag(on_error="skip")`` must not raise once the bag is open: only at opening."""
    from symloc.io.rosbag import bag_topics, read_bag

    bag_topics(path)
    messages = read_bag(path, on_error="skip")
    first = True
    while True:
        try:
            next(messages)
        except StopIteration:
            break
        except SymlocError:
            if not first:
                raise AssertionError("read_bag(on_error='skip') raised while iterating") from None
            raise
        first = False


# ----------------------------------------------------------------------- node parameters


@st.composite
def params_yaml(draw: st.DrawFn) -> str:
    from symloc.ros.params import NodeParams

    keys = [f.name for f in NodeParams.__dataclass_fields__.values()] + ["bogus", "amcl.x"]
    block = {k: draw(values) for k in draw(st.lists(st.sampled_from(keys), max_size=6))}
    lines = "\n".join(f"    {k}: {v!r}" for k, v in block.items())
    text = (
        f"symloc:\n  ros__parameters:\n{lines}\n" if block else "symloc:\n  ros__parameters: {}\n"
    )
    if draw(st.integers(0, 4)) == 0:
        text = draw(st.text(max_size=120))
    return text


# ----------------------------------------------------------------------- node messages


# Strategies built once (building them inside every draw costs hypothesis a validation each).
_OFFSET = st.one_of(st.floats(-1.0, 1.0), st.sampled_from([20.0, 1e6, -1000.0, -1e9]))
_SEC = st.one_of(st.none(), bad_ints, st.text(max_size=3))
_SOME = st.integers(0, 9)
_FRAME_BAD = st.one_of(st.text(max_size=6), st.none(), bad_ints)
_XY = st.one_of(st.tuples(bad_floats, bad_floats), st.just((0.5, 0.5)))
_QUAT = st.one_of(
    st.just((0.0, 0.0, 0.0, 1.0)),
    st.tuples(bad_floats, bad_floats, bad_floats, bad_floats),
    st.just((0.0, 0.0, 0.0, 0.0)),
)
_KIND = st.sampled_from(["scan", "scan", "odom", "odom", "map", "image", "cimage", "init"])
_N = st.one_of(st.integers(0, 40), st.just(36))
_RANGE_BAD = st.one_of(bad_floats, st.just(2.0))
_ANGLE = st.one_of(st.just(None), bad_floats)
_CHILD = st.one_of(st.just("base_link"), st.text(max_size=4), bad_ints)
_SIDE = st.one_of(st.integers(-2, 30), bad_ints)
_CELLS = st.lists(st.integers(-128, 127), max_size=40)
_PIX = st.one_of(st.integers(0, 8), bad_ints)
_STEP = st.one_of(st.integers(0, 32), bad_ints)
_ENC = st.sampled_from(["rgb8", "mono16", "bgra8", "yuv422", ""])
_FMT = st.sampled_from(["png", "jpeg", "", "rgb8; jpeg compressed bgr8"])
_COV_BAD = st.one_of(
    st.lists(bad_floats, min_size=36, max_size=36), st.lists(bad_floats, max_size=40)
)
_IMAGE = image_bytes()
_BYTES = st.binary(max_size=200)


def _value(draw: st.DrawFn, good: Any, bad: Any) -> Any:
    """``good`` most of the time, else a draw from ``bad``."""
    return good if draw(_SOME) < 6 else draw(bad)


def _header(draw: st.DrawFn, base: float, frame: str) -> Any:
    t = base + draw(_OFFSET)
    sec: Any = int(t) if draw(_SOME) < 8 else draw(_SEC)
    nsec: Any = int((t % 1) * 1e9) if draw(_SOME) < 8 else draw(_SEC)
    stamp = SimpleNamespace(sec=sec, nanosec=nsec)
    return SimpleNamespace(stamp=stamp, frame_id=_value(draw, frame, _FRAME_BAD))


def _maybe_drop(draw: st.DrawFn, ns: SimpleNamespace) -> SimpleNamespace:
    if draw(_SOME) == 0 and vars(ns):
        delattr(ns, sorted(vars(ns))[draw(st.integers(0, len(vars(ns)) - 1))])
    return ns


def _pose(draw: st.DrawFn) -> Any:
    x, y = draw(_XY)
    q = draw(_QUAT)
    return SimpleNamespace(
        position=SimpleNamespace(x=x, y=y, z=0.0),
        orientation=_maybe_drop(draw, SimpleNamespace(x=q[0], y=q[1], z=q[2], w=q[3])),
    )


@st.composite
def node_messages(draw: st.DrawFn, base: float) -> tuple[str, Any]:
    """One message for the node (kind, look-alike message), malformed in some way."""
    kind = draw(_KIND)
    msg: SimpleNamespace
    if kind == "scan":
        n = draw(_N)
        how = draw(_SOME)
        ranges: Any = [2.0] * n
        if how >= 7:
            ranges = draw(st.lists(_RANGE_BAD, min_size=n, max_size=n))
        elif how == 6:
            ranges = draw(st.one_of(st.text(max_size=4), st.none()))
        msg = SimpleNamespace(
            header=_header(draw, base, "laser"),
            angle_min=_value(draw, -math.pi, bad_floats),
            angle_max=_value(draw, math.pi, bad_floats),
            angle_increment=_value(draw, 2 * math.pi / 36, bad_floats),
            time_increment=0.0,
            scan_time=0.0,
            range_min=_value(draw, 0.1, bad_floats),
            range_max=_value(draw, 8.0, bad_floats),
            ranges=ranges,
            intensities=[],
        )
    elif kind == "odom":
        msg = SimpleNamespace(
            header=_header(draw, base, "odom"),
            child_frame_id=_value(draw, "base_link", _CHILD),
            pose=SimpleNamespace(pose=_pose(draw), covariance=[0.0] * 36),
        )
    elif kind == "map":
        w, h = draw(_SIDE), draw(_SIDE)
        cells = max(0, min(w, 30)) * max(0, min(h, 30))
        how = draw(_SOME)
        data: Any = [100] * cells
        if how >= 7:
            data = draw(_CELLS)
        elif how == 6:
            data = draw(_BYTES)
        info = SimpleNamespace(
            width=w, height=h, resolution=_value(draw, 0.05, bad_floats), origin=_pose(draw)
        )
        msg = SimpleNamespace(header=_header(draw, base, "map"), info=info, data=data)
    elif kind == "image":
        msg = SimpleNamespace(
            header=_header(draw, base, "camera"),
            height=draw(_PIX),
            width=draw(_PIX),
            step=draw(_STEP),
            encoding=draw(_ENC),
            is_bigendian=draw(st.sampled_from([0, 1, 7])),
            data=draw(_BYTES),
        )
    elif kind == "cimage":
        msg = SimpleNamespace(
            header=_header(draw, base, "camera"), format=draw(_FMT), data=draw(_IMAGE)
        )
    else:
        good = [0.25 if i in (0, 7, 35) else 0.0 for i in range(36)]
        msg = SimpleNamespace(
            header=_header(draw, base, "map"),
            pose=SimpleNamespace(pose=_pose(draw), covariance=_value(draw, good, _COV_BAD)),
        )
    return kind, _maybe_drop(draw, msg)


def feed(core: Any, kind: str, msg: Any) -> Any:
    """Hand one message to a NodeCore."""
    handler = {
        "scan": core.on_scan,
        "odom": core.on_odom,
        "map": core.on_map,
        "image": core.on_image,
        "cimage": core.on_compressed_image,
        "init": core.on_initialpose,
    }[kind]
    return handler(msg)


# ----------------------------------------------------------------------- the command line


def command_leaves() -> dict[tuple[str, ...], Any]:
    """Every leaf command of the ``symloc`` parser tree (path of words -> its parser)."""
    import argparse

    from symloc.cli.main import build_parser

    out: dict[tuple[str, ...], Any] = {}

    def walk(parser: Any, path: tuple[str, ...]) -> None:
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if not subs:
            out[path] = parser
        for action in subs:
            for name, sub in action.choices.items():
                walk(sub, (*path, name))

    walk(build_parser(), ())
    return out


GARBAGE_FILES = (
    "empty",
    "random.bin",
    "random.png",
    "cut.gz",
    "folder",
    "missing",
    "fifo",
    "dev_zero",
)


def make_garbage_files(folder: Path) -> dict[str, Path]:
    """Files a command may be pointed at: empty, random bytes, a truncated gzip, a folder, a
    FIFO (a reader that opens it blocks), ``/dev/zero`` (endless, reports 0 bytes)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = {name: folder / name for name in GARBAGE_FILES}
    paths["dev_zero"] = Path("/dev/zero")
    if not paths["fifo"].exists():
        os.mkfifo(paths["fifo"])
    paths["empty"].write_bytes(b"")
    paths["random.bin"].write_bytes(bytes(range(256)) * 3)
    paths["random.png"].write_bytes(png_header(40000, 40000, b"\x00" * 64))
    paths["cut.gz"].write_bytes(gzip.compress(b"FLASER 3 1 2 3\n" * 50)[:60])
    paths["folder"].mkdir(exist_ok=True)
    (paths["folder"] / "x.png").write_bytes(b"not an image")
    return paths


BAD_VALUES = ["-1", "0", "nan", "inf", "-inf", "1e999", "abc", "", "1.5", "99999999999999999999"]
#: Values no numeric or choice option accepts.
INVALID = ["abc", "nan", "1e999", "", "0x1", "--"]
#: Commands that would run a simulation or an experiment when their options are valid.
RUNS = ("demo", "experiment", "sim", "bench")
#: Commands that would run a node until stopped, or build packages, when their options are valid.
RUNS_PATHS = {("ros", "node"), ("ros", "setup")}


def _is_flag(a: Any) -> bool:
    import argparse

    return isinstance(a, (argparse._StoreTrueAction, argparse._StoreFalseAction))


def _takes_file(a: Any) -> bool:
    from symloc.cli import options

    return not a.choices and (
        a.type is None or a.type in (Path, options.output_folder, options.output_file)
    )


@st.composite
def command_lines(
    draw: st.DrawFn, leaves: dict[tuple[str, ...], Any], files: dict[str, Path]
) -> list[str]:
    """A command line that must fail cleanly and quickly: commands that read files get garbage
    files (and random values); commands that would run a simulation get one value no option
    accepts, so they stop at argument validation."""
    path = draw(st.sampled_from(sorted(leaves)))
    parser = leaves[path]
    argv = list(path)
    actions = [
        a
        for a in parser._actions
        if a.option_strings and a.dest not in ("help", "ros_args", "world", "room")
    ]
    positionals = [a for a in parser._actions if not a.option_strings]
    for _ in positionals:
        argv.append(str(files[draw(st.sampled_from(GARBAGE_FILES))]))
    chosen = draw(st.lists(st.sampled_from(actions), max_size=4, unique_by=id)) if actions else []
    required = [a for a in actions if a.required]
    if path == ("symmetry", "judge"):
        argv += [
            draw(st.sampled_from(["--carmen", "--bag"])),
            str(files[draw(st.sampled_from(GARBAGE_FILES))]),
        ]
        chosen = [a for a in chosen if a.dest not in ("carmen", "bag")]
    if path == ("map", "build"):
        argv += ["--carmen", str(files[draw(st.sampled_from(GARBAGE_FILES))])]
        chosen = [a for a in chosen if a.dest != "carmen"]
    for a in list(dict.fromkeys([*required, *chosen])):
        flag = a.option_strings[-1]
        if _is_flag(a):
            argv.append(flag)
            continue
        nargs = a.nargs if isinstance(a.nargs, int) else 1
        if _takes_file(a):
            vals = [str(files[draw(st.sampled_from(GARBAGE_FILES))]) for _ in range(nargs)]
        elif a.choices:
            vals = [draw(st.sampled_from([*map(str, a.choices), "abc"])) for _ in range(nargs)]
        else:
            vals = [draw(st.sampled_from(BAD_VALUES)) for _ in range(nargs)]
        argv += [flag, *vals]
    if path[0] in RUNS or path in RUNS_PATHS:
        checked = [a for a in actions if not _is_flag(a) and not _takes_file(a)]
        if checked:
            a = draw(st.sampled_from(checked))
            nargs = a.nargs if isinstance(a.nargs, int) else 1
            argv += [a.option_strings[-1], *[draw(st.sampled_from(INVALID))] * nargs]
        else:
            argv.append("--no-such-option")
    return argv


def _exit_and_output(main: Callable[[list[str]], int], argv: list[str]) -> tuple[Any, str, str]:
    """``main(argv)`` with its output captured: its exit code (returned, or argparse's
    ``SystemExit`` code) and what it wrote to standard output and standard error."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code: Any = main(argv)
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def run_command(argv: list[str]) -> None:
    """``symloc ARGV`` in process: a usage error (exit 2), a ``symloc: error`` line (exit 2) or
    another exit code are fine; an exception escaping ``main`` or a traceback is not."""
    last_argv[0] = list(argv)
    from symloc.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main(argv)
        except SystemExit as exc:
            if exc.code not in (0, 2):
                raise AssertionError(f"argparse exit code {exc.code}") from None
    if "Traceback" in err.getvalue():
        raise AssertionError("a traceback was printed")


# ----------------------------------------------------------------------- output paths

#: Bad values for an output folder / an output file (names of :func:`bad_output_value`).
BAD_FOLDER_OUTPUTS = ("existing_file", "under_a_file", "dev_null", "fifo", "empty", "nul", "long")
BAD_FILE_OUTPUTS = (
    "existing_folder",
    "under_a_file",
    "dev_null",
    "fifo",
    "empty",
    "nul",
    "long",
    "slash",
)


def output_options(leaves: dict[tuple[str, ...], Any]) -> list[tuple[tuple[str, ...], Any, str]]:
    """Every (command, action, "folder" | "file") whose action names a path the command
    writes (typed :func:`symloc.cli.options.output_folder` / ``output_file``)."""
    from symloc.cli import options

    out = []
    for path, parser in sorted(leaves.items()):
        for a in parser._actions:
            if a.type is options.output_folder:
                out.append((path, a, "folder"))
            elif a.type is options.output_file:
                out.append((path, a, "file"))
    return out


def bad_output_value(kind: str, folder: Path, tail: str) -> str:
    """A path of the bad ``kind`` inside ``folder`` (created as needed)."""
    f = folder / "a_file"
    f.write_text("keep me")
    d = folder / "a_folder"
    d.mkdir(exist_ok=True)
    fifo = folder / "a_fifo"
    if not fifo.exists():
        os.mkfifo(fifo)
    return {
        "existing_file": str(f),
        "existing_folder": str(d),
        "under_a_file": str(f / tail / "x"),
        "dev_null": "/dev/null",
        "fifo": str(fifo),
        "empty": "",
        "nul": str(folder / f"a\x00{tail}"),
        "long": str(folder / (tail * (300 // max(1, len(tail)) + 1))),
        "slash": str(d / tail) + "/",
    }[kind]


@st.composite
def output_path_cases(
    draw: st.DrawFn, outputs: list[tuple[tuple[str, ...], Any, str]], folder: Path
) -> tuple[list[str], str, str]:
    """(argv, the option's name as argparse says it, the bad value): one output of one command
    given a path of the wrong kind; the other positionals get a plain file."""
    path, action, kind = draw(st.sampled_from(outputs))
    bad = draw(st.sampled_from(BAD_FOLDER_OUTPUTS if kind == "folder" else BAD_FILE_OUTPUTS))
    tail = draw(st.text("abcxyz_-.0123456789", min_size=1, max_size=8))
    value = bad_output_value(bad, folder, tail)
    if action.option_strings:
        flag = draw(st.sampled_from(action.option_strings))
        return [*path, flag, value], flag, value
    return list(path), action.dest, value  # a positional: run_output_case places it


def run_output_case(argv: list[str], name: str, value: str, leaves: dict[Any, Any]) -> None:
    """``symloc ARGV`` with one bad output: a usage error naming the option and the path (exit
    2) before anything is written; anything else is an escape."""
    last_argv[0] = list(argv)
    from symloc.cli.main import main

    if tuple(argv) in leaves:  # a positional output: the other positionals get a plain file
        positionals = [a for a in leaves[tuple(argv)]._actions if not a.option_strings]
        argv = [*argv, *(value if a.dest == name else __file__ for a in positionals)]
    code, _, text = _exit_and_output(main, argv)
    if code != 2:
        raise AssertionError(f"exit {code} for a bad output path: {argv}\n{text[-400:]}")
    shown = value or repr(value)
    if f"argument {name}: {shown} " not in text:
        raise AssertionError(f"the error does not name {name} and {shown!r}: {text[-300:]}")
    if "Traceback" in text:
        raise AssertionError("a traceback was printed")


# ----------------------------------------------------------------------- missing data sets

#: Kinds of a data argument that holds nothing usable.
MISSING = ("missing", "empty_folder", "empty_file", "random", "fifo", "dev_zero", "other_logs")
_LOG_NAMES = ("intel", "aces", "freiburg-079", "fr079", "nope")


def missing_value(kind: str, folder: Path) -> str:
    """A data path of ``kind`` in ``folder``: nothing a command can use."""
    if kind == "missing":
        return str(folder / "no" / "such")
    if kind == "empty_folder":
        d = folder / "empty_dir"
        d.mkdir(exist_ok=True)
        return str(d)
    if kind == "other_logs":  # a folder of logs with other names, and garbage "logs"
        d = folder / "other_logs"
        d.mkdir(exist_ok=True)
        (d / "csail-corrected.log.gz").write_bytes(b"\x1f\x8b garbage")
        (d / "README").write_text("not a log")
        return str(d)
    if kind == "empty_file":
        (folder / "empty_file").write_bytes(b"")
        return str(folder / "empty_file")
    if kind == "random":
        (folder / "random.bin").write_bytes(bytes(range(256)) * 5)
        return str(folder / "random.bin")
    if kind == "fifo":
        fifo = folder / "data_fifo"
        if not fifo.exists():
            os.mkfifo(fifo)
        return str(fifo)
    return "/dev/zero"


@st.composite
def missing_data_cases(draw: st.DrawFn, folder: Path) -> list[str]:
    """A command that reads a data set, pointed at one that is not there (or holds nothing):
    it must fail (exit code != 0) quickly and without a traceback, never skip and succeed."""
    data = missing_value(draw(st.sampled_from(MISSING)), folder)
    other = missing_value(draw(st.sampled_from(MISSING)), folder)
    names = draw(st.lists(st.sampled_from(_LOG_NAMES), min_size=1, max_size=3))
    carmen = [n for n in names if n in ("intel", "aces", "freiburg-079")] or ["intel"]
    out = str(folder / "out")
    templates = [
        ["experiment", "slam", "--worlds", "--logs", *names, "--data", data, "--out", out],
        ["experiment", "slam", "--worlds", "--data", data, "--out", out],
        ["experiment", "amcl-carmen", "--logs", *names, "--data", data, "--out", out],
        ["experiment", "symmetry-carmen", "--logs", *carmen, "--data", data, "--out", out],
        ["bench", "slam", "--carmen", data, "--logs", *names, "--out", out],
        ["map", "build", "--carmen", data, "--out", out],
        ["symmetry", "judge", "--carmen", data, "--index", str(draw(st.integers(-5, 5)))],
        ["symmetry", "judge", "--bag", data],
        ["replay", data, "--out", out],
        ["replay", data, "--map", other, "--out", out],
        ["places", "list", "--db", data],
        ["places", "keyframes", "--db", data],
        ["places", "decide", "--db", data, "--query", other],
        ["places", "remove", "--db", data, "--place", "1"],
        ["vocab", "info", data],
        ["vocab", "train", data, "--out", out],
        ["ros", "carmen-to-bag", data, "--out", out],
        ["ros", "check-params", data],
        ["sim", "render", "--world", data, "--out", out],
        ["demo", "--world", data, "--out", out],
    ]
    return draw(st.sampled_from(templates))


def run_missing_data(argv: list[str]) -> None:
    """``symloc ARGV`` on a data set that is not there: exit code != 0, no traceback."""
    last_argv[0] = list(argv)
    from symloc.cli.main import main

    code, stdout, text = _exit_and_output(main, argv)
    if "Traceback" in text:
        raise AssertionError("a traceback was printed")
    if code == 0:
        raise AssertionError(f"silent success on missing data: {argv}\n{stdout[-300:]}")
    if code == 2 and "error" not in text:
        raise AssertionError(f"exit 2 without an error message: {argv}")


# ----------------------------------------------------------------------- numeric bounds


def bounded_options(leaves: dict[tuple[str, ...], Any]) -> list[tuple[tuple[str, ...], Any]]:
    """Every (command, action) whose type is a :class:`symloc.cli.options.Bounded`."""
    from symloc.cli import options

    return [
        (path, a)
        for path, parser in sorted(leaves.items())
        for a in parser._actions
        if isinstance(a.type, options.Bounded) and a.option_strings
    ]


@st.composite
def out_of_bounds_cases(
    draw: st.DrawFn, bounded: list[tuple[tuple[str, ...], Any]]
) -> tuple[list[str], str]:
    """(argv, flag): one bounded option given a value beyond its bound (by a hair or by
    orders of magnitude), the other options left at their defaults."""
    path, action = draw(st.sampled_from(bounded))
    t = action.type
    integral = "int" in t.__name__
    sides = [s for s, b in (("high", t.high), ("low", t.low)) if b is not None]
    side = draw(st.sampled_from(sides))
    if side == "high":
        factor = draw(st.sampled_from([1.0001, 1.5, 10.0, 1e3, 1e9, 1e100, 1e300]))
        value: float = t.high * factor + (1 if integral else 0)
    else:
        value = t.low * draw(st.sampled_from([0.999, 0.5, 1e-3, 1e-9, 1e-300]))
        if integral:
            value = math.floor(t.low) - draw(st.integers(1, 3))
            if value < 1 and "positive" in t.__name__:
                value = 0
    text = str(int(value)) if integral and math.isfinite(value) else repr(value)
    if integral and draw(st.booleans()) and side == "high":
        text = str(draw(st.sampled_from([2**31, 2**63, 10**30, int(t.high) + 1])))
    flag = draw(st.sampled_from(action.option_strings))
    nargs = action.nargs if isinstance(action.nargs, int) else 1
    return [*path, flag, *[text] * nargs], flag


def run_out_of_bounds(argv: list[str], flag: str) -> None:
    """A value beyond a bound: a usage error naming the option and the bound (exit 2)."""
    last_argv[0] = list(argv)
    from symloc.cli.main import main

    code, _, text = _exit_and_output(main, argv)
    if code != 2 or f"argument {flag}: expected" not in text:
        raise AssertionError(f"exit {code} for {argv}: {text[-300:]}")


# ----------------------------------------------------------------------- special files

#: Paths that are not regular files (a reader that opens a FIFO blocks; /dev/zero never ends
#: and reports 0 bytes; /dev/urandom never ends either), or lead to one.
SPECIAL = ("fifo", "dev_zero", "dev_urandom", "folder", "link_to_fifo", "missing", "dev_null")


def special_path(kind: str, folder: Path) -> Path:
    """A path of ``kind`` (see :data:`SPECIAL`) in ``folder``."""
    fifo = folder / "s_fifo"
    if not fifo.exists():
        os.mkfifo(fifo)
    link = folder / "s_link"
    if not link.is_symlink():
        link.symlink_to(fifo)
    (folder / "s_folder").mkdir(exist_ok=True)
    return {
        "fifo": fifo,
        "dev_zero": Path("/dev/zero"),
        "dev_urandom": Path("/dev/urandom"),
        "dev_null": Path("/dev/null"),
        "folder": folder / "s_folder",
        "link_to_fifo": link,
        "missing": folder / "s_missing",
    }[kind]


def _load(loader: str, path: Path) -> None:
    if loader == "map":
        from symloc.grid.map_io import load_map

        load_map(path)
    elif loader == "world":
        from symloc.sim.world_file import load_world_file

        load_world_file(path)
    elif loader == "node params":
        from symloc.ros.params import NodeParams

        NodeParams.from_yaml(path)
    elif loader == "nav2 params":
        from symloc.mcl.params import AmclParams

        AmclParams.from_nav2_yaml(path)
    elif loader == "vocabulary":
        from symloc.vision.vocabulary import load_vocabulary

        load_vocabulary(path)
    elif loader == "photo":
        from symloc.vision.image_files import read_image

        read_image(path)
    elif loader == "carmen":
        from symloc.io.carmen import read_carmen

        read_carmen(path)
    elif loader == "bag":
        read_bag_skip(path)
    elif loader == "visual map":
        from symloc.vision.visual_map import VisualMap

        VisualMap(path, readonly=True).close()


LOADERS = (
    "map",
    "world",
    "node params",
    "nav2 params",
    "vocabulary",
    "photo",
    "carmen",
    "bag",
    "visual map",
)


@st.composite
def special_file_cases(draw: st.DrawFn, folder: Path) -> tuple[str, Path]:
    """(loader, path): one library loader given a special file (or a map YAML naming one)."""
    loader = draw(st.sampled_from(LOADERS))
    path = special_path(draw(st.sampled_from(SPECIAL)), folder)
    if loader == "map" and draw(st.booleans()):  # the YAML is fine, its image is special
        y = folder / "special_map.yaml"
        y.write_text(
            f"image: {path}\nresolution: 0.05\norigin: [0, 0, 0]\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\nnegate: 0\n"
        )
        path = y
    return loader, path


def load_special(loader: str, path: Path) -> None:
    """A loader on a special file: a symloc error (or acceptance of /dev/null as empty where
    that is a valid empty input), quickly: never a hang or an endless read."""
    last_argv[0] = [loader, str(path)]
    _load(loader, path)
