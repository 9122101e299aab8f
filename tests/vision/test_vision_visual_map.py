"""The SQLite visual map: round trip, G-V index, queries, error paths, crash safety."""

from __future__ import annotations

import math
import signal
import sqlite3
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from symloc.errors import ConfigurationError, DatabaseError
from symloc.symmetry.order import SymmetryOrder
from symloc.vision.bow import BowVector, Scoring
from symloc.vision.orb import OrbFeatures
from symloc.vision.visual_map import SCHEMA_VERSION, PlaceImage, VisualMap, direction_headings


def _image(direction: int, seed: int, n: int = 50, with_image: bool = False) -> PlaceImage:
    rng = np.random.default_rng(seed)
    kp = np.column_stack([rng.uniform(0, 640, (n, 2)), rng.uniform(5, 30, (n, 4))]).astype(
        np.float32
    )
    kp[:, 5] = np.floor(kp[:, 5] % 8)
    feats = OrbFeatures.from_arrays(kp, rng.integers(0, 256, (n, 32), dtype=np.uint8), (640, 480))
    words = np.unique(rng.integers(0, 1000, 20)).astype(np.int32)
    vals = rng.random(words.size)
    bow = BowVector(words, vals / vals.sum())
    img = rng.integers(0, 256, (48, 64, 3), dtype=np.uint8) if with_image else None
    return PlaceImage(direction, -direction * math.pi / 2, feats, bow, img)


def _add(vm: VisualMap, seed: int, gv: float = 1.0, m: int = 4, with_image: bool = False) -> int:
    return vm.add_place(
        kind="square",
        order=4,
        gv_distance=gv,
        pose=[1.0, 2.0, 0.3],
        images=[_image(j, seed * 10 + j, with_image=with_image) for j in range(m)],
    )


@pytest.mark.parametrize("journal", ["wal", "delete"])
def test_round_trip(tmp_path, journal: str) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "map.db"
    with VisualMap(path, journal=journal) as vm:
        pid = _add(vm, 1, with_image=True)
        vm.set_meta("vocabulary", "default k=10 L=4")
    with VisualMap(path, create=False) as vm:
        assert len(vm) == 1
        assert vm.get_meta("vocabulary") == "default k=10 L=4"
        p = vm.place(pid)
        assert p.kind == "square"
        assert p.order == SymmetryOrder.finite(4)
        assert p.pose.tolist() == [1.0, 2.0, 0.3]
        assert [im.direction for im in p.images] == [0, 1, 2, 3]
        for j, im in enumerate(p.images):
            ref = _image(j, 10 + j, with_image=True)
            assert np.array_equal(im.features.descriptors, ref.features.descriptors)
            assert np.array_equal(im.features.points, ref.features.points)
            assert np.array_equal(im.bow.words, ref.bow.words)
            assert np.array_equal(im.bow.values, ref.bow.values)
            assert np.array_equal(im.image, ref.image)
        assert vm.integrity_check() == "ok"
        assert (
            sqlite3.connect(path).execute("PRAGMA user_version").fetchone()[0]
            == SCHEMA_VERSION
            == 2
        )


def test_gv_index_and_query(tmp_path) -> None:  # type: ignore[no-untyped-def]
    with VisualMap(tmp_path / "m.db") as vm:
        a = _add(vm, 1, gv=1.00)
        b = _add(vm, 2, gv=1.05)
        _add(vm, 3, gv=2.0)
        assert vm.find_places(1.04, 0.1) == [(b, 1.05), (a, 1.0)]
        assert vm.find_places(1.04, 0.1, kind="circle") == []
        q = vm.place(b).images[2].bow
        res = vm.query(q, Scoring.L1_NORM)
        assert (res[0].place_id, res[0].direction) == (b, 2)
        assert res[0].score == pytest.approx(1.0)
        only_a = vm.query(q, "l1", place_id=a)
        assert {r.place_id for r in only_a} == {a}
        assert len(only_a) == 4
        vm.delete_place(b)  # the cache is invalidated by writes
        assert all(r.place_id != b for r in vm.query(q))


def test_headings_are_clockwise() -> None:
    h = direction_headings(0.0, 4)
    assert h == pytest.approx([0.0, -math.pi / 2, math.pi, math.pi / 2])


def test_error_paths(tmp_path) -> None:  # type: ignore[no-untyped-def]
    junk = tmp_path / "junk.db"
    junk.write_bytes(b"this is not an sqlite file at all" * 100)
    with pytest.raises(DatabaseError, match="not a symloc visual map"):
        VisualMap(junk)
    other = tmp_path / "other.db"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE t (x)")
    con.commit()
    con.close()
    with pytest.raises(DatabaseError, match="application_id 0x0"):
        VisualMap(other)
    newer = tmp_path / "newer.db"
    VisualMap(newer).close()
    con = sqlite3.connect(newer)
    con.execute("PRAGMA user_version = 7")
    con.commit()
    con.close()
    with pytest.raises(DatabaseError, match="schema version 7 is newer"):
        VisualMap(newer)
    with pytest.raises(DatabaseError, match="no visual map there"):
        VisualMap(tmp_path / "absent.db", create=False)
    with pytest.raises(DatabaseError, match="does not exist"):
        VisualMap(tmp_path / "no" / "dir.db")
    with pytest.raises(ConfigurationError, match="journal"):
        VisualMap(tmp_path / "j.db", journal="memory")
    with VisualMap(tmp_path / "ok.db") as vm:
        with pytest.raises(DatabaseError, match="no place with id 42"):
            vm.place(42)
        with pytest.raises(ConfigurationError, match=r"directions must be 0..1"):
            vm.add_place(
                kind="square",
                order=4,
                gv_distance=1.0,
                pose=[0, 0, 0],
                images=[_image(0, 1), _image(2, 2)],
            )
        with pytest.raises(ConfigurationError, match="order"):
            vm.add_place(
                kind="square", order=0, gv_distance=1.0, pose=[0, 0, 0], images=[_image(0, 1)]
            )
        with pytest.raises(ConfigurationError, match="gv_distance"):
            vm.add_place(
                kind="square", order=4, gv_distance=-1, pose=[0, 0, 0], images=[_image(0, 1)]
            )
        with pytest.raises(ConfigurationError, match="pose"):
            vm.add_place(kind="square", order=4, gv_distance=1, pose=[0, 0], images=[_image(0, 1)])
        with pytest.raises(ConfigurationError, match="at least one image"):
            vm.add_place(kind="square", order=4, gv_distance=1, pose=[0, 0, 0], images=[])
        assert len(vm) == 0


WRITER = textwrap.dedent(
    """
    import sys
    sys.path[:0] = [{tests!r}]
    from test_vision_visual_map import _add
    from symloc.vision.visual_map import VisualMap
    vm = VisualMap({path!r}, journal={journal!r})
    for seed in range(1, 1000):
        pid = _add(vm, seed, gv=float(seed), with_image=False)
        print(pid, seed, flush=True)
    """
)


@pytest.mark.parametrize("journal", ["wal", "delete"])
def test_killed_writer_loses_nothing_committed(tmp_path, journal: str) -> None:  # type: ignore[no-untyped-def]
    from pathlib import Path

    path = tmp_path / "crash.db"
    code = WRITER.format(tests=str(Path(__file__).parent), path=str(path), journal=journal)
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    committed = {}
    assert proc.stdout is not None
    for _ in range(5):
        pid, seed = proc.stdout.readline().split()
        committed[int(pid)] = int(seed)
    proc.send_signal(signal.SIGKILL)  # the writer is busy with the next place
    proc.wait()
    with VisualMap(path, create=False) as vm:
        assert vm.integrity_check() == "ok"
        ids = vm.place_ids()
        assert set(committed) <= set(ids)
        for pid in ids:  # every place present is whole (no half-written place)
            p = vm.place(pid)
            seed = int(p.gv_distance)
            assert len(p.images) == 4
            for j, im in enumerate(p.images):
                assert np.array_equal(
                    im.features.descriptors, _image(j, seed * 10 + j).features.descriptors
                )
        # and the map is still writable after the crash
        _add(vm, 999)
        assert len(vm) == len(ids) + 1


def test_damaged_record_is_reported(tmp_path) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "d.db"
    with VisualMap(path) as vm:
        pid = _add(vm, 1)
    con = sqlite3.connect(path)
    con.execute(
        "UPDATE images SET descriptors = x'0102' WHERE place_id = ? AND direction = 2", (pid,)
    )
    con.commit()
    con.close()
    with (
        VisualMap(path) as vm,
        pytest.raises(
            DatabaseError,
            match=r"direction 2: images\.descriptors: 2 bytes, expected \d+ \(damaged record\)",
        ),
    ):
        vm.place(pid)


_LOOSE = (
    "CREATE TABLE old AS SELECT * FROM {t}; DROP TABLE {t}; CREATE TABLE {t} ({cols});"
    " INSERT INTO {t} SELECT * FROM old; DROP TABLE old;"
)
_LOOSE_IMAGES = _LOOSE.format(
    t="images",
    cols="place_id INTEGER, direction INTEGER, heading REAL, width INTEGER, height INTEGER,"
    " n_features INTEGER, bow_words BLOB, bow_values BLOB, keypoints BLOB, descriptors BLOB,"
    " image_png BLOB",
)
_LOOSE_PLACES = _LOOSE.format(
    t="places",
    cols="id INTEGER PRIMARY KEY, kind TEXT, symmetry_order INTEGER, gv_distance REAL,"
    " x REAL, y REAL, heading REAL, n_directions INTEGER, label TEXT, created REAL",
)


def _damaged(tmp_path, sql: str) -> Path:  # type: ignore[no-untyped-def]
    path = tmp_path / "x.db"
    with VisualMap(path) as vm:
        _add(vm, 1)
    con = sqlite3.connect(path)
    con.executescript(sql)
    con.commit()
    con.close()
    return path


@pytest.mark.parametrize(
    ("sql", "match"),
    [
        ("DROP TABLE images;", r"table 'images' is missing"),
        (
            _LOOSE_IMAGES + "UPDATE images SET bow_words = NULL;",
            r"images\.bow_words: expected a BLOB, got NULL",
        ),
        ("UPDATE images SET keypoints = 'text';", r"images\.keypoints: expected a BLOB, got str"),
        ("UPDATE images SET n_features = 'many';", r"images\.n_features: expected an integer"),
        ("UPDATE images SET n_features = 1e12;", r"images\.n_features: expected an integer"),
        ("UPDATE places SET gv_distance = 'far';", r"places\.gv_distance: expected a finite"),
        (_LOOSE_PLACES + "UPDATE places SET kind = NULL;", r"places\.kind: expected text"),
        (
            "ALTER TABLE images RENAME COLUMN keypoints TO kp;",
            r"column images\.keypoints is missing",
        ),
        (
            "CREATE TABLE t2 AS SELECT * FROM meta; DROP TABLE meta;"
            " CREATE TABLE meta (key TEXT, value BLOB);",
            r"column meta\.value is declared BLOB, expected TEXT",
        ),
        ("UPDATE images SET image_png = x'89504e470d0a1a0a';", r"image_png: PNG without"),
    ],
)
def test_damaged_databases_name_table_and_column(tmp_path, sql: str, match: str) -> None:  # type: ignore[no-untyped-def]
    path = _damaged(tmp_path, sql)
    with pytest.raises(DatabaseError, match=match), VisualMap(path, create=False) as vm:
        vm.query(vm.place(vm.place_ids()[0]).images[0].bow)


def test_opening_for_reading_never_writes(tmp_path) -> None:  # type: ignore[no-untyped-def]
    empty = tmp_path / "empty.db"
    empty.write_bytes(b"")
    for kwargs in ({"create": False}, {"readonly": True}):
        with pytest.raises(DatabaseError, match="an empty database, not a symloc visual map"):
            VisualMap(empty, **kwargs)
        assert empty.read_bytes() == b""
    path = tmp_path / "m.db"
    with VisualMap(path) as vm:
        _add(vm, 1)
    before = path.read_bytes()
    with VisualMap(path, readonly=True) as vm:
        assert len(vm) == 1
        with pytest.raises(DatabaseError, match="cannot write"):
            vm.set_meta("x", "y")
    assert path.read_bytes() == before
