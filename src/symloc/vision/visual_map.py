"""The visual map: an SQLite database of symmetric places and their M images (Algorithm 3, step 5).

Each place ("node" in the paper) is a symmetric room: its kind, symmetry order and G-V distance
(this table is the persistent G-V index), the map pose of its centre with the heading of
direction 0, and M images taken at the centre in clockwise order (direction j looks along
``heading - j * 2 pi / M``), each with its BoW vector, ORB keypoints and descriptors, and
optionally the image itself (PNG).

Keyframes (schema version 2) are views recorded all along the mapping trip, each with the map
pose it was taken from, its ORB keypoints and descriptors, its BoW vector and optionally the
image (:class:`~symloc.vision.keyframes.Keyframe`); they let a pose hypothesis anywhere on the
map be checked against what the camera sees (:mod:`symloc.vision.verification`). A version-1
file (places only) is upgraded in place, in one transaction, when it is opened with
``create=True``; opened for reading it stays version 1 and has no keyframes.

Every write is one transaction; the journal is WAL with ``synchronous=FULL``, so a process that
dies mid-write loses only the place it was writing. The file carries ``PRAGMA application_id``
(``'SYML'``) and the schema version in ``PRAGMA user_version``.

A damaged or foreign file gives :class:`~symloc.errors.DatabaseError` naming the file, the table
and column and what was expected, never a raw ``sqlite3`` or NumPy error: the tables and their
columns are checked when the map is opened, every value when it is read (a NULL blob, a
text-typed column, a record of the wrong length). Opened for reading (``create=False``) a map is
never written to: an empty file does not get a schema, and ``readonly=True`` opens it read-only.
"""

from __future__ import annotations

import math
import sqlite3
import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError, DatabaseError, DataFormatError
from symloc.geometry import wrap_angle
from symloc.image_header import check_image_size, image_header
from symloc.symmetry.order import SymmetryOrder
from symloc.vision.bow import BowMatrix, BowVector, Scoring, parse_scoring, score_many
from symloc.vision.keyframes import Keyframe
from symloc.vision.orb import OrbFeatures
from symloc.vision.place import UNANCHORED_LABEL, Place, PlaceImage

__all__ = [
    "APPLICATION_ID",
    "OLDEST_SCHEMA_VERSION",
    "SCHEMA_VERSION",
    "Keyframe",
    "Place",
    "PlaceImage",
    "QueryResult",
    "VisualMap",
    "direction_headings",
]

APPLICATION_ID = 0x53594D4C  # 'SYML'
SCHEMA_VERSION = 2
#: Oldest schema version this symloc opens (version 1 has no ``keyframes`` table).
OLDEST_SCHEMA_VERSION = 1

_KEYFRAMES_SCHEMA = """
CREATE TABLE keyframes (
    id INTEGER PRIMARY KEY,
    x REAL NOT NULL, y REAL NOT NULL, heading REAL NOT NULL,
    stamp REAL NOT NULL,
    width INTEGER NOT NULL, height INTEGER NOT NULL,
    n_features INTEGER NOT NULL,
    bow_words BLOB NOT NULL, bow_values BLOB NOT NULL,
    keypoints BLOB NOT NULL, descriptors BLOB NOT NULL,
    image_png BLOB
);
CREATE INDEX keyframes_xy ON keyframes (x, y);
"""

_SCHEMA_V1 = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE places (
    id INTEGER PRIMARY KEY,
    kind TEXT NOT NULL,
    symmetry_order INTEGER NOT NULL CHECK (symmetry_order >= 1),
    gv_distance REAL NOT NULL,
    x REAL NOT NULL, y REAL NOT NULL, heading REAL NOT NULL,
    n_directions INTEGER NOT NULL CHECK (n_directions >= 1),
    label TEXT,
    created REAL NOT NULL
);
CREATE INDEX places_gv ON places (gv_distance);
CREATE TABLE images (
    place_id INTEGER NOT NULL REFERENCES places (id) ON DELETE CASCADE,
    direction INTEGER NOT NULL,
    heading REAL NOT NULL,
    width INTEGER NOT NULL, height INTEGER NOT NULL,
    n_features INTEGER NOT NULL,
    bow_words BLOB NOT NULL, bow_values BLOB NOT NULL,
    keypoints BLOB NOT NULL, descriptors BLOB NOT NULL,
    image_png BLOB,
    PRIMARY KEY (place_id, direction)
);
"""
_SCHEMA = _SCHEMA_V1 + _KEYFRAMES_SCHEMA


#: The columns each table must have (name -> declared type).
_COLUMNS: dict[str, dict[str, str]] = {
    "meta": {"key": "TEXT", "value": "TEXT"},
    "places": {
        "id": "INTEGER",
        "kind": "TEXT",
        "symmetry_order": "INTEGER",
        "gv_distance": "REAL",
        "x": "REAL",
        "y": "REAL",
        "heading": "REAL",
        "n_directions": "INTEGER",
        "label": "TEXT",
        "created": "REAL",
    },
    "images": {
        "place_id": "INTEGER",
        "direction": "INTEGER",
        "heading": "REAL",
        "width": "INTEGER",
        "height": "INTEGER",
        "n_features": "INTEGER",
        "bow_words": "BLOB",
        "bow_values": "BLOB",
        "keypoints": "BLOB",
        "descriptors": "BLOB",
        "image_png": "BLOB",
    },
}
#: Columns of the ``keyframes`` table (schema version 2).
_KEYFRAME_COLUMNS: dict[str, str] = {
    "id": "INTEGER",
    "x": "REAL",
    "y": "REAL",
    "heading": "REAL",
    "stamp": "REAL",
    "width": "INTEGER",
    "height": "INTEGER",
    "n_features": "INTEGER",
    "bow_words": "BLOB",
    "bow_values": "BLOB",
    "keypoints": "BLOB",
    "descriptors": "BLOB",
    "image_png": "BLOB",
}
#: Largest stored image (pixels) decoded from ``images.image_png``.
MAX_STORED_IMAGE_PIXELS = 50_000_000
#: Most ORB features one stored image may claim.
MAX_FEATURES = 1_000_000


def direction_headings(heading0: float, m: int) -> NDArray[np.float64]:
    """Headings [rad] of the M clockwise directions: ``heading0 - j * 2 pi / M``, wrapped."""
    return np.asarray(wrap_angle(heading0 - np.arange(m) * (2.0 * math.pi / m)), np.float64)


@dataclass(frozen=True)
class QueryResult:
    """One scored stored image."""

    place_id: int
    direction: int
    score: float


def _encode_png(image: NDArray[np.uint8]) -> bytes:
    import cv2

    arr: NDArray[Any] = np.ascontiguousarray(image)
    if arr.ndim == 3:
        arr = cv2.cvtColor(arr, cv2.COLOR_RGB2BGR)
    ok, buf = cv2.imencode(".png", arr)
    if not ok:  # pragma: no cover - OpenCV failure
        raise DatabaseError("image: PNG encoding failed")
    return bytes(buf.tobytes())


def _decode_png(blob: bytes, where: str) -> NDArray[np.uint8]:
    import cv2

    try:
        head = check_image_size(image_header(blob, where), MAX_STORED_IMAGE_PIXELS, where)
    except DataFormatError as err:
        raise DatabaseError(str(err)) from err
    if head.format != "png":
        raise DatabaseError(f"{where}: expected a PNG, got {head.format}")
    arr = cv2.imdecode(np.frombuffer(blob, np.uint8), cv2.IMREAD_UNCHANGED)
    if arr is None:
        raise DatabaseError(f"{where}: cannot decode the stored PNG")
    if arr.ndim == 3:
        arr = cv2.cvtColor(arr, cv2.COLOR_BGR2RGB)
    return np.asarray(arr, np.uint8)


def _blob(value: Any, where: str) -> bytes:
    """A BLOB column's value, refusing NULL and other types."""
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value)
    kind = "NULL" if value is None else type(value).__name__
    raise DatabaseError(f"{where}: expected a BLOB, got {kind}")


def _int(value: Any, where: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise DatabaseError(f"{where}: expected an integer in {low}..{high}, got {value!r}")
    return int(value)


def _real(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise DatabaseError(f"{where}: expected a finite number, got {value!r}")
    return float(value)


def _text(value: Any, where: str, *, null: bool = False) -> str | None:
    if value is None and null:
        return None
    if not isinstance(value, str):
        raise DatabaseError(f"{where}: expected text, got {value!r}")
    return value


def _decode_features(
    n: int, size: tuple[int, int], blobs: Sequence[Any], at: str
) -> tuple[OrbFeatures, BowVector]:
    """ORB features and BoW vector from the four BLOB columns ``bow_words, bow_values,
    keypoints, descriptors`` of a stored view (``at`` names the row in errors)."""
    words = _blob(blobs[0], f"{at}.bow_words")
    values = _blob(blobs[1], f"{at}.bow_values")
    kp_b = _blob(blobs[2], f"{at}.keypoints")
    desc_b = _blob(blobs[3], f"{at}.descriptors")
    for name, blob, need in (
        ("keypoints", kp_b, 24 * n),
        ("descriptors", desc_b, 32 * n),
        ("bow_values", values, 2 * len(words)),
    ):
        if len(blob) != need:
            raise DatabaseError(f"{at}.{name}: {len(blob)} bytes, expected {need} (damaged record)")
    if len(words) % 4:
        raise DatabaseError(f"{at}.bow_words: {len(words)} bytes, not whole int32 words")
    try:
        kp = np.frombuffer(kp_b, "<f4").reshape(n, 6)
        desc = np.frombuffer(desc_b, np.uint8).reshape(n, 32)
        bow = BowVector(np.frombuffer(words, "<i4"), np.frombuffer(values, "<f8"))
        feats = OrbFeatures.from_arrays(kp, desc, size)
    except (ValueError, DataFormatError) as err:
        raise DatabaseError(f"{at}: damaged image record: {err}") from err
    return feats, bow


def _encode_view(features: OrbFeatures, bow: BowVector) -> tuple[Any, ...]:
    """The columns ``width, height, n_features, bow_words, bow_values, keypoints,
    descriptors`` of a stored view."""
    return (
        int(features.image_size[0]),
        int(features.image_size[1]),
        len(features),
        bow.words.astype("<i4").tobytes(),
        bow.values.astype("<f8").tobytes(),
        features.keypoint_array().astype("<f4").tobytes(),
        np.ascontiguousarray(features.descriptors, np.uint8).tobytes(),
    )


class VisualMap:
    """The visual map database (SQLite).

    Parameters
    ----------
    path : str or Path
        Database file (``":memory:"`` for a throw-away map).
    create : bool
        Create the file (and the schema in a new or empty file) when needed. False: the file
        must already be a symloc visual map; nothing is written on opening.
    journal : {"wal", "delete"}
        SQLite journal mode: write-ahead log (default) or rollback journal.
    readonly : bool
        Open read-only (implies ``create=False``): writes raise :class:`DatabaseError`.

    Raises
    ------
    DatabaseError
        The file is not a symloc visual map (or an empty one opened for reading), has a newer
        schema, a missing table or column, or cannot be opened.
    """

    def __init__(
        self,
        path: str | Path,
        *,
        create: bool = True,
        journal: str = "wal",
        readonly: bool = False,
    ) -> None:
        if journal not in ("wal", "delete"):
            raise ConfigurationError(f"journal: expected 'wal' or 'delete', got {journal!r}")
        self.path = str(path)
        self.readonly = bool(readonly)
        create = create and not self.readonly
        if self.path != ":memory:":
            p = Path(self.path)
            if not p.exists() and not create:
                raise DatabaseError(f"{p}: no visual map there")
            if p.exists() and not p.is_file():
                raise DatabaseError(f"{p}: not a file")
            if not p.parent.is_dir():
                raise DatabaseError(f"{p}: folder {p.parent} does not exist")
        try:
            if self.readonly and self.path != ":memory:":
                uri = Path(self.path).resolve().as_uri() + "?mode=ro"
                self._con = sqlite3.connect(uri, uri=True, isolation_level=None, timeout=30.0)
            else:
                self._con = sqlite3.connect(self.path, isolation_level=None, timeout=30.0)
        except sqlite3.Error as err:
            raise DatabaseError(f"{self.path}: cannot open: {err}") from err
        self._cache: tuple[BowMatrix, NDArray[np.int64], NDArray[np.int64]] | None = None
        self._kf_cache: tuple[BowMatrix, NDArray[np.int64]] | None = None
        self.schema_version = SCHEMA_VERSION
        try:
            self._init_schema(journal, create)
        except sqlite3.DatabaseError as err:
            self._con.close()
            raise DatabaseError(
                f"{self.path}: not a symloc visual map (SQLite says: {err})"
            ) from err
        except DatabaseError:
            self._con.close()
            raise

    @contextmanager
    def _reading(self, what: str) -> Iterator[None]:
        """Turn SQLite and decoding errors met while reading ``what`` into DatabaseError."""
        try:
            yield
        except DatabaseError:
            raise
        except sqlite3.Error as err:
            raise DatabaseError(f"{self.path}: {what}: {err}") from err
        except (TypeError, ValueError, OverflowError) as err:
            raise DatabaseError(f"{self.path}: {what}: damaged record: {err}") from err

    # ------------------------------------------------------------------ lifecycle
    def _init_schema(self, journal: str, create: bool) -> None:
        con = self._con
        app_id = con.execute("PRAGMA application_id").fetchone()[0]
        version = con.execute("PRAGMA user_version").fetchone()[0]
        n_tables = con.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]
        if app_id == 0 and version == 0 and n_tables == 0:
            if not create:
                raise DatabaseError(
                    f"{self.path}: an empty database, not a symloc visual map (opened for"
                    " reading: nothing is written to it)"
                )
            con.execute("BEGIN IMMEDIATE")
            for stmt in _SCHEMA.split(";"):
                if stmt.strip():
                    con.execute(stmt)
            con.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            con.execute("INSERT INTO meta VALUES ('created_by', 'symloc')")
            con.execute("COMMIT")
        elif app_id != APPLICATION_ID:
            raise DatabaseError(
                f"{self.path}: not a symloc visual map (SQLite application_id {app_id:#x}, "
                f"expected {APPLICATION_ID:#x})"
            )
        elif version > SCHEMA_VERSION:
            raise DatabaseError(
                f"{self.path}: schema version {version} is newer than this symloc reads "
                f"({SCHEMA_VERSION}); upgrade symloc"
            )
        elif version < OLDEST_SCHEMA_VERSION:
            raise DatabaseError(f"{self.path}: schema version {version} is not a valid version")
        elif version < SCHEMA_VERSION and create:
            self._migrate(version)
        self.schema_version = int(con.execute("PRAGMA user_version").fetchone()[0])
        self._check_tables()
        if self.path != ":memory:" and not self.readonly:
            con.execute(f"PRAGMA journal_mode = {journal}")
        con.execute("PRAGMA synchronous = FULL")
        con.execute("PRAGMA foreign_keys = ON")

    def _migrate(self, version: int) -> None:
        """Upgrade a version-1 file in place, in one transaction (a crash leaves version 1)."""
        con = self._con
        con.execute("BEGIN IMMEDIATE")
        try:
            # re-read under the write lock: another process may have migrated it meanwhile
            if int(con.execute("PRAGMA user_version").fetchone()[0]) == version == 1:
                for stmt in _KEYFRAMES_SCHEMA.split(";"):
                    if stmt.strip():
                        con.execute(stmt)
                con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
                con.execute(
                    "INSERT OR REPLACE INTO meta VALUES ('migrated_from', ?)", (str(version),)
                )
            con.execute("COMMIT")
        except BaseException:
            con.execute("ROLLBACK")
            raise

    def _check_tables(self) -> None:
        tables = dict(_COLUMNS)
        if self.schema_version >= 2:
            tables["keyframes"] = _KEYFRAME_COLUMNS
        for table, cols in tables.items():
            have = {
                str(r[1]): str(r[2]).upper()
                for r in self._con.execute(f"PRAGMA table_info({table})")
            }
            if not have:
                raise DatabaseError(f"{self.path}: table '{table}' is missing")
            for col, typ in cols.items():
                if col not in have:
                    raise DatabaseError(f"{self.path}: column {table}.{col} is missing")
                if have[col] != typ:
                    raise DatabaseError(
                        f"{self.path}: column {table}.{col} is declared {have[col] or 'untyped'},"
                        f" expected {typ}"
                    )

    def close(self) -> None:
        """Close the connection (checkpointing the WAL)."""
        self._con.close()

    def __enter__(self) -> VisualMap:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __len__(self) -> int:
        with self._reading("places"):
            return int(self._con.execute("SELECT count(*) FROM places").fetchone()[0])

    # ------------------------------------------------------------------ meta
    def set_meta(self, key: str, value: str) -> None:
        """Store a metadata string (e.g. the vocabulary that made the BoW vectors)."""
        with self._transaction():
            self._con.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, str(value)))

    def get_meta(self, key: str) -> str | None:
        """Return a metadata string or None."""
        with self._reading(f"meta {key!r}"):
            row = self._con.execute("SELECT value FROM meta WHERE key = ?", (key,)).fetchone()
        return None if row is None else _text(row[0], f"{self.path}: meta.value of {key!r}")

    # ------------------------------------------------------------------ writes
    class _Tx:
        def __init__(self, con: sqlite3.Connection, path: str) -> None:
            self.con = con
            self.path = path

        def __enter__(self) -> sqlite3.Connection:
            try:
                self.con.execute("BEGIN IMMEDIATE")
            except sqlite3.Error as err:
                raise DatabaseError(f"{self.path}: cannot write: {err}") from err
            return self.con

        def __exit__(self, exc_type: Any, exc: BaseException | None, tb: object) -> None:
            if exc_type is None:
                try:
                    self.con.execute("COMMIT")
                except sqlite3.Error as err:
                    raise DatabaseError(f"{self.path}: cannot write: {err}") from err
                return
            self.con.execute("ROLLBACK")
            if isinstance(exc, sqlite3.Error):
                raise DatabaseError(f"{self.path}: cannot write: {exc}") from exc

    def _transaction(self) -> VisualMap._Tx:
        self._cache = None
        self._kf_cache = None
        return VisualMap._Tx(self._con, self.path)

    def add_place(
        self,
        *,
        kind: str,
        order: SymmetryOrder | int,
        gv_distance: float,
        pose: ArrayLike,
        images: Sequence[PlaceImage],
        label: str | None = None,
    ) -> int:
        """Store a place and its M images in one transaction; return its id.

        Parameters
        ----------
        kind : str
        order : SymmetryOrder or int
            Symmetry order (an int is a finite order >= 1). The column stores a circle's
            number of directions M (it needs an integer >= 1; :meth:`place` reads the circle
            back from ``kind == "circle"``).
        gv_distance : float
            G-V distance [m].
        pose : (3,) array
            Map pose of the centre; theta is the heading of direction 0.
        images : sequence of PlaceImage
            M >= 1 images whose directions are exactly 0..M-1 (clockwise).
        label : str, optional
        """
        if not kind:
            raise ConfigurationError("kind: expected a non-empty string")
        if isinstance(order, SymmetryOrder):
            order = len(images) if order.k is None else order.k
        if int(order) != order or order < 1:
            raise ConfigurationError(f"order: expected an integer >= 1, got {order}")
        gv = float(gv_distance)
        if not math.isfinite(gv) or gv < 0:
            raise ConfigurationError(
                f"gv_distance: expected a finite value >= 0, got {gv_distance}"
            )
        p = np.asarray(pose, np.float64).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ConfigurationError(f"pose: expected 3 finite values (x, y, theta), got {pose!r}")
        if not images:
            raise ConfigurationError("images: expected at least one image")
        dirs = sorted(int(im.direction) for im in images)
        if dirs != list(range(len(images))):
            raise ConfigurationError(
                f"images: directions must be 0..{len(images) - 1} (clockwise), got {dirs}"
            )
        rows = []
        for im in images:
            feat = im.features
            rows.append(
                (
                    int(im.direction),
                    float(im.heading),
                    *_encode_view(feat, im.bow),
                    None if im.image is None else _encode_png(im.image),
                )
            )
        with self._transaction() as con:
            cur = con.execute(
                "INSERT INTO places (kind, symmetry_order, gv_distance, x, y, heading, "
                "n_directions, label, created) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (kind, int(order), gv, *map(float, p), len(images), label, time.time()),
            )
            pid = int(cur.lastrowid or 0)
            con.executemany(
                "INSERT INTO images VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                [(pid, *r) for r in rows],
            )
        return pid

    def delete_place(self, place_id: int) -> None:
        """Remove a place and its images."""
        with self._transaction() as con:
            con.execute("DELETE FROM places WHERE id = ?", (int(place_id),))

    # ------------------------------------------------------------------ reads
    def place_ids(self) -> list[int]:
        """Ids of all places, ascending."""
        with self._reading("places.id"):
            rows = self._con.execute("SELECT id FROM places ORDER BY id").fetchall()
        return [_int(r[0], f"{self.path}: places.id", 0, 2**62) for r in rows]

    def place(self, place_id: int, *, with_images: bool = True) -> Place:
        """Load one place with its images in clockwise order."""
        where = f"{self.path}: place {place_id}"
        with self._reading(f"place {place_id}"):
            row = self._con.execute(
                "SELECT kind, symmetry_order, gv_distance, x, y, heading, label FROM places "
                "WHERE id = ?",
                (int(place_id),),
            ).fetchone()
            if row is None:
                raise DatabaseError(f"{self.path}: no place with id {place_id}")
            rows = self._con.execute(
                "SELECT direction, heading, width, height, n_features, bow_words, bow_values, "
                "keypoints, descriptors, image_png FROM images WHERE place_id = ? "
                "ORDER BY direction",
                (int(place_id),),
            ).fetchall()
            imgs = [self._image_record(r, where, with_images) for r in rows]
            # read in column order, so a damaged row reports its first bad column
            kind = str(_text(row[0], f"{where}: places.kind"))
            stored_order = _int(row[1], f"{where}: places.symmetry_order", 1, 1_000_000)
            gv_distance = _real(row[2], f"{where}: places.gv_distance")
            x = _real(row[3], f"{where}: places.x")
            y = _real(row[4], f"{where}: places.y")
            heading = _real(row[5], f"{where}: places.heading")
            label = _text(row[6], f"{where}: places.label", null=True)
            return Place(
                place_id=int(place_id),
                center=np.array([x, y], np.float64),
                heading0=heading,
                m=len(imgs),
                # the column holds a circle's number of directions (it needs an integer >= 1)
                order=SymmetryOrder.CIRCLE
                if kind == "circle"
                else SymmetryOrder.finite(stored_order),
                gv_distance=gv_distance,
                kind=kind,
                heading_reliable=label != UNANCHORED_LABEL,
                images=tuple(imgs),
                label=label,
            )

    def _image_record(self, r: Sequence[Any], where: str, with_images: bool) -> PlaceImage:
        d = _int(r[0], f"{where}: images.direction", 0, 1_000_000)
        at = f"{where} direction {d}: images"
        n = _int(r[4], f"{at}.n_features", 0, MAX_FEATURES)
        size = (
            _int(r[2], f"{at}.width", 0, 1_000_000),
            _int(r[3], f"{at}.height", 0, 1_000_000),
        )
        feats, bow = _decode_features(n, size, r[5:9], at)
        image = None
        if with_images and r[9] is not None:
            image = _decode_png(_blob(r[9], f"{at}.image_png"), f"{at}.image_png")
        return PlaceImage(d, _real(r[1], f"{at}.heading"), feats, bow, image)

    def find_places(
        self,
        gv_distance: float,
        tolerance: float,
        *,
        kind: str | None = None,
        order: int | None = None,
    ) -> list[tuple[int, float]]:
        """The G-V index: places whose G-V distance is within ``tolerance`` [m], nearest first.

        Returns
        -------
        list of (place_id, gv_distance)
        """
        sql = "SELECT id, gv_distance FROM places WHERE gv_distance BETWEEN ? AND ?"
        args: list[Any] = [float(gv_distance) - tolerance, float(gv_distance) + tolerance]
        if kind is not None:
            sql += " AND kind = ?"
            args.append(kind)
        if order is not None:
            sql += " AND symmetry_order = ?"
            args.append(int(order))
        with self._reading("places (G-V index)"):
            found = self._con.execute(sql, args).fetchall()
        rows = [
            (
                _int(a, f"{self.path}: places.id", 0, 2**62),
                _real(b, f"{self.path}: places.gv_distance"),
            )
            for a, b in found
        ]
        return sorted(rows, key=lambda r: abs(r[1] - gv_distance))

    def _bow_cache(self) -> tuple[BowMatrix, NDArray[np.int64], NDArray[np.int64]]:
        if self._cache is None:
            with self._reading("images (BoW vectors)"):
                rows = self._con.execute(
                    "SELECT place_id, direction, bow_words, bow_values FROM images "
                    "ORDER BY place_id, direction"
                ).fetchall()
                vecs = []
                for r in rows:
                    at = f"{self.path}: place {r[0]} direction {r[1]}: images"
                    _int(r[0], f"{at}.place_id", 0, 2**62)
                    _int(r[1], f"{at}.direction", 0, 1_000_000)
                    words = _blob(r[2], f"{at}.bow_words")
                    values = _blob(r[3], f"{at}.bow_values")
                    if len(words) % 4 or len(values) != 2 * len(words):
                        raise DatabaseError(f"{at}.bow_words/bow_values: lengths disagree")
                    vecs.append(
                        BowVector(np.frombuffer(words, "<i4"), np.frombuffer(values, "<f8"))
                    )
            self._cache = (
                BowMatrix.stack(vecs),
                np.array([r[0] for r in rows], np.int64),
                np.array([r[1] for r in rows], np.int64),
            )
        return self._cache

    def query(
        self,
        bow: BowVector,
        scoring: Scoring | int | str = Scoring.L1_NORM,
        *,
        place_id: int | None = None,
        max_results: int | None = None,
    ) -> list[QueryResult]:
        """Score ``bow`` against stored images (all, or one place's), best first.

        The BoW vectors are cached in memory after the first query (invalidated by writes).
        """
        sc = parse_scoring(scoring)
        matrix, pids, dirs = self._bow_cache()
        scores = score_many(bow, matrix, sc)
        idx = np.arange(scores.size)
        if place_id is not None:
            idx = idx[pids == int(place_id)]
        order = idx[np.argsort(-scores[idx], kind="stable")]
        if max_results is not None:
            order = order[:max_results]
        return [QueryResult(int(pids[i]), int(dirs[i]), float(scores[i])) for i in order]

    # ------------------------------------------------------------------ keyframes
    def _keyframes_table(self, writing: bool) -> bool:
        """True when the file has a keyframes table; a write to a version-1 file opened
        without ``create`` (so not migrated) raises."""
        if self.schema_version >= 2:
            return True
        if writing:
            raise DatabaseError(
                f"{self.path}: schema version {self.schema_version} has no keyframes table; "
                "open the map with create=True (and not read-only) to upgrade it"
            )
        return False

    def add_keyframes(self, keyframes: Sequence[Keyframe]) -> list[int]:
        """Store keyframes in one transaction (all or none); return their ids in order."""
        self._keyframes_table(writing=True)
        rows = []
        for i, kf in enumerate(keyframes):
            if not isinstance(kf, Keyframe):
                raise ConfigurationError(
                    f"keyframes[{i}]: expected a Keyframe, got {type(kf).__name__}"
                )
            rows.append(
                (
                    *map(float, kf.pose),
                    float(kf.stamp),
                    *_encode_view(kf.features, kf.bow),
                    None if kf.image is None else _encode_png(kf.image),
                )
            )
        ids: list[int] = []
        with self._transaction() as con:
            for r in rows:
                cur = con.execute(
                    "INSERT INTO keyframes (x, y, heading, stamp, width, height, n_features, "
                    "bow_words, bow_values, keypoints, descriptors, image_png) "
                    "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                    r,
                )
                ids.append(int(cur.lastrowid or 0))
        return ids

    def add_keyframe(self, keyframe: Keyframe) -> int:
        """Store one keyframe (one transaction); return its id."""
        return self.add_keyframes([keyframe])[0]

    def delete_keyframes(self, ids: Sequence[int] | None = None) -> None:
        """Remove the keyframes ``ids`` (all of them when None), in one transaction."""
        if not self._keyframes_table(writing=True):  # pragma: no cover - raised above
            return
        with self._transaction() as con:
            if ids is None:
                con.execute("DELETE FROM keyframes")
            else:
                con.executemany("DELETE FROM keyframes WHERE id = ?", [(int(i),) for i in ids])

    def set_keyframe_headings(
        self,
        ids: Sequence[int],
        headings: ArrayLike,
        *,
        meta: Mapping[str, str] | None = None,
    ) -> None:
        """Replace the headings [rad] of the keyframes ``ids`` (positions unchanged), and write
        the ``meta`` strings, in one transaction: all or none (an unknown id changes nothing).

        Parameters
        ----------
        ids : sequence of N int
        headings : (N,) array
            New map headings [rad] (stored wrapped).
        meta : mapping of str to str, optional
            Metadata written with them (e.g. how the headings were aligned).
        """
        self._keyframes_table(writing=True)
        kid = [int(i) for i in ids]
        h = np.asarray(headings, np.float64).reshape(-1)
        if h.size != len(kid) or not np.all(np.isfinite(h)):
            raise ConfigurationError(f"headings: expected {len(kid)} finite headings [rad]")
        if len(set(kid)) != len(kid):
            raise ConfigurationError("ids: expected distinct keyframe ids")
        wrapped = np.asarray(wrap_angle(h), np.float64).tolist()
        with self._transaction() as con:
            for i, th in zip(kid, wrapped, strict=True):
                cur = con.execute("UPDATE keyframes SET heading = ? WHERE id = ?", (th, i))
                if cur.rowcount != 1:
                    raise DatabaseError(f"{self.path}: no keyframe with id {i}")
            for key, value in (meta or {}).items():
                con.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (str(key), str(value)))

    def keyframe_count(self) -> int:
        """Number of stored keyframes (0 in a version-1 file)."""
        if not self._keyframes_table(writing=False):
            return 0
        with self._reading("keyframes"):
            return int(self._con.execute("SELECT count(*) FROM keyframes").fetchone()[0])

    def keyframe_poses(self) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """Ids ``(N,)`` and map poses ``(N, 3)`` of all keyframes, by id (cheap: no features)."""
        if not self._keyframes_table(writing=False):
            return np.zeros(0, np.int64), np.zeros((0, 3))
        with self._reading("keyframes (poses)"):
            rows = self._con.execute(
                "SELECT id, x, y, heading FROM keyframes ORDER BY id"
            ).fetchall()
        ids = np.array([_int(r[0], f"{self.path}: keyframes.id", 0, 2**62) for r in rows], np.int64)
        poses = np.array(
            [
                [
                    _real(v, f"{self.path}: keyframe {r[0]}: keyframes.{c}")
                    for c, v in zip(("x", "y", "heading"), r[1:], strict=True)
                ]
                for r in rows
            ],
            np.float64,
        ).reshape(-1, 3)
        return ids, poses

    def keyframes(
        self, ids: Sequence[int] | None = None, *, with_images: bool = False
    ) -> list[Keyframe]:
        """Load keyframes (all, by id; or those of ``ids`` in that order)."""
        if not self._keyframes_table(writing=False):
            if ids:
                raise DatabaseError(f"{self.path}: no keyframe with id {int(ids[0])}")
            return []
        cols = (
            "id, x, y, heading, stamp, width, height, n_features, bow_words, bow_values, "
            "keypoints, descriptors, " + ("image_png" if with_images else "NULL")
        )
        with self._reading("keyframes"):
            if ids is None:
                rows = self._con.execute(f"SELECT {cols} FROM keyframes ORDER BY id").fetchall()
            else:
                rows = []
                for i in ids:
                    row = self._con.execute(
                        f"SELECT {cols} FROM keyframes WHERE id = ?", (int(i),)
                    ).fetchone()
                    if row is None:
                        raise DatabaseError(f"{self.path}: no keyframe with id {int(i)}")
                    rows.append(row)
            return [self._keyframe_record(r) for r in rows]

    def keyframe(self, keyframe_id: int, *, with_image: bool = False) -> Keyframe:
        """Load one keyframe."""
        return self.keyframes([keyframe_id], with_images=with_image)[0]

    def _keyframe_record(self, r: Sequence[Any]) -> Keyframe:
        kid = _int(r[0], f"{self.path}: keyframes.id", 0, 2**62)
        at = f"{self.path}: keyframe {kid}: keyframes"
        pose = np.array(
            [_real(r[1], f"{at}.x"), _real(r[2], f"{at}.y"), _real(r[3], f"{at}.heading")]
        )
        stamp = _real(r[4], f"{at}.stamp")
        size = (_int(r[5], f"{at}.width", 0, 1_000_000), _int(r[6], f"{at}.height", 0, 1_000_000))
        n = _int(r[7], f"{at}.n_features", 0, MAX_FEATURES)
        feats, bow = _decode_features(n, size, r[8:12], at)
        image = None
        if r[12] is not None:
            image = _decode_png(_blob(r[12], f"{at}.image_png"), f"{at}.image_png")
        return Keyframe(pose, feats, bow, stamp=stamp, keyframe_id=kid, image=image)

    def _keyframe_bow_cache(self) -> tuple[BowMatrix, NDArray[np.int64]]:
        if self._kf_cache is None:
            vecs: list[BowVector] = []
            kids: list[int] = []
            if self._keyframes_table(writing=False):
                with self._reading("keyframes (BoW vectors)"):
                    rows = self._con.execute(
                        "SELECT id, bow_words, bow_values FROM keyframes ORDER BY id"
                    ).fetchall()
                    for r in rows:
                        kid = _int(r[0], f"{self.path}: keyframes.id", 0, 2**62)
                        at = f"{self.path}: keyframe {kid}: keyframes"
                        words = _blob(r[1], f"{at}.bow_words")
                        values = _blob(r[2], f"{at}.bow_values")
                        if len(words) % 4 or len(values) != 2 * len(words):
                            raise DatabaseError(f"{at}.bow_words/bow_values: lengths disagree")
                        vecs.append(
                            BowVector(np.frombuffer(words, "<i4"), np.frombuffer(values, "<f8"))
                        )
                        kids.append(kid)
            self._kf_cache = (BowMatrix.stack(vecs), np.array(kids, np.int64))
        return self._kf_cache

    def query_keyframes(
        self,
        bow: BowVector,
        scoring: Scoring | int | str = Scoring.L1_NORM,
        *,
        ids: Sequence[int] | None = None,
        max_results: int | None = None,
    ) -> list[tuple[int, float]]:
        """Score ``bow`` against stored keyframes (all, or those of ``ids``), best first.

        Returns
        -------
        list of (keyframe_id, score)
        """
        sc = parse_scoring(scoring)
        matrix, kids = self._keyframe_bow_cache()
        if kids.size == 0:
            return []
        scores = score_many(bow, matrix, sc)
        idx = np.arange(scores.size)
        if ids is not None:
            idx = idx[np.isin(kids, np.asarray(list(ids), np.int64))]
        order = idx[np.argsort(-scores[idx], kind="stable")]
        if max_results is not None:
            order = order[:max_results]
        return [(int(kids[i]), float(scores[i])) for i in order]

    def keyframe_bytes(self) -> int:
        """Bytes the keyframes' records hold (poses, features, BoW vectors, images if kept)."""
        if not self._keyframes_table(writing=False):
            return 0
        with self._reading("keyframes (size)"):
            row = self._con.execute(
                "SELECT count(*), coalesce(sum(length(bow_words) + length(bow_values) + "
                "length(keypoints) + length(descriptors) + coalesce(length(image_png), 0)), 0) "
                "FROM keyframes"
            ).fetchone()
        # 4 REAL and 3 INTEGER columns and the id, 8 bytes each
        return int(row[1]) + 64 * int(row[0])

    def integrity_check(self) -> str:
        """SQLite's ``PRAGMA integrity_check`` result (``"ok"`` when sound)."""
        with self._reading("integrity check"):
            return str(self._con.execute("PRAGMA integrity_check").fetchone()[0])

    def checkpoint(self) -> None:
        """Fold the WAL into the main file (so the file size is the map's size)."""
        self._con.execute("PRAGMA wal_checkpoint(TRUNCATE)")
