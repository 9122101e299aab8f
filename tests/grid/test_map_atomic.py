"""Crash-safe map files: a map is the old one or the new one, never torn (issue 31)."""

from __future__ import annotations

import multiprocessing
import random
import threading
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from symloc.errors import MapFileError
from symloc.files.atomic import (
    atomic_path,
    atomic_write_text,
    remove_stale_temporaries,
    temporary_name,
    temporary_target,
)
from symloc.grid import OccupancyGrid, map_io
from symloc.grid.map_io import load_map, read_map_yaml, save_map

KILLS = 200


def _map(seed: int, size: int = 400) -> OccupancyGrid:
    """A map whose pixels, origin and resolution all differ from another seed's."""
    rng = np.random.default_rng(seed)
    data = rng.choice(np.array([-1, 0, 100], np.int8), size=(size, size), p=[0.2, 0.6, 0.2])
    return OccupancyGrid(data, 0.05 + 0.01 * seed, np.array([-1.0 - seed, 2.0 + seed, 0.1 * seed]))


def _which(grid: OccupancyGrid, maps: list[OccupancyGrid]) -> int:
    """The index of the map ``grid`` equals exactly, or -1 (a mix)."""
    for i, m in enumerate(maps):
        if (
            grid.data.shape == m.data.shape
            and np.array_equal(grid.data, m.data)
            and np.array_equal(grid.origin, m.origin)
            and grid.resolution == m.resolution
        ):
            return i
    return -1


def _overwrite_forever(
    path: Path, maps: list[OccupancyGrid], first: int, started: Any, saves: Any
) -> None:
    """The child: save the two maps alternately to ``path``, ``maps[first]`` first, until
    killed; ``saves`` counts the saves completed."""
    started.set()
    i = 0
    while True:
        save_map(maps[(first + i) % 2], path)
        i += 1
        saves.value = i


@pytest.mark.slow
def test_sigkill_during_map_overwrites_leaves_the_old_or_the_new_map(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """SIGKILL a process that overwrites a map, at a random moment, KILLS times; after each
    kill the map loads, exactly equal to one of the two maps (same pixel size, so only the
    write id tells a torn pair)."""
    maps = [_map(0), _map(1)]
    path = tmp_path / "m.yaml"
    t0 = time.monotonic()
    save_map(maps[0], path)
    save_time = time.monotonic() - t0
    current = 0
    ctx = multiprocessing.get_context("fork")
    rng = random.Random(31)
    outcomes: Counter[str] = Counter()
    completed: Counter[int] = Counter()
    mid_save = 0
    t0 = time.monotonic()
    for _ in range(KILLS):
        started = ctx.Event()
        saves = ctx.RawValue("l", 0)
        # the child's first save replaces the map there now with the other one
        args = (path, maps, 1 - current, started, saves)
        child = ctx.Process(target=_overwrite_forever, args=args)
        child.start()
        assert started.wait(20), "the writer did not start"
        time.sleep(rng.uniform(0.0, 2.5 * save_time))
        child.kill()  # SIGKILL
        child.join(20)
        assert child.exitcode == -9
        completed[min(int(saves.value), 2)] += 1
        names = {p.name for p in tmp_path.iterdir()}
        image = read_map_yaml(path).image.name
        if names - {"m.yaml", image}:
            mid_save += 1  # a temporary file or an image whose YAML was never written
        try:
            which = _which(load_map(path), maps)
        except MapFileError as err:  # pragma: no cover - the failure this test guards
            outcomes[f"error: {err}"] += 1
            continue
        if which < 0:
            outcomes["torn"] += 1
            continue
        outcomes["old" if which == current else "new"] += 1
        current = which
    elapsed = time.monotonic() - t0
    print(
        f"{KILLS} kills in {elapsed:.1f} s (one save {1000 * save_time:.0f} ms):"
        f" {dict(outcomes)}; {mid_save} left a partial save; saves completed before the kill"
        f" (0, 1, 2+): {completed[0]}, {completed[1]}, {completed[2]}"
    )
    assert outcomes["old"] + outcomes["new"] == KILLS, outcomes
    assert mid_save > 0, "no kill landed inside a save: the test proves nothing"
    # a later save removes what the killed saves left behind (here: at once)
    monkeypatch.setattr(map_io, "STALE_SECONDS", 0.0)
    save_map(maps[1], path)
    image = read_map_yaml(path).image.name
    assert {p.name for p in tmp_path.iterdir()} == {"m.yaml", image}
    assert _which(load_map(path), maps) == 1


def test_each_save_names_a_new_image_and_removes_the_replaced_one(tmp_path: Path) -> None:
    a, b = _map(0, 20), _map(1, 20)
    y = save_map(a, tmp_path / "m")
    first = read_map_yaml(y)
    assert first.write_id is not None
    assert first.image.name == f"m.{first.write_id}.pgm"
    save_map(b, y)
    second = read_map_yaml(y)
    assert second.image != first.image
    assert not first.image.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["m.yaml", second.image.name])
    assert _which(load_map(y), [a, b]) == 1


def test_a_legacy_image_named_after_the_stem_is_replaced(tmp_path: Path) -> None:
    """A map written before write ids (m.yaml + m.pgm) is overwritten cleanly."""
    y = save_map(_map(0, 10), tmp_path / "m")
    legacy = tmp_path / "m.pgm"
    read_map_yaml(y).image.rename(legacy)
    text = y.read_text().splitlines()
    y.write_text("\n".join(["image: m.pgm", *text[2:]]) + "\n")
    assert _which(load_map(y), [_map(0, 10)]) == 0
    save_map(_map(1, 10), y)
    assert not legacy.exists()
    assert _which(load_map(y), [_map(1, 10)]) == 0


def test_an_image_of_another_save_is_refused_by_write_id(tmp_path: Path) -> None:
    """A YAML and an image of the same size from two saves (as a non-atomic copy of a map
    folder could leave them) do not load as a map."""
    ya = save_map(_map(0, 12), tmp_path / "a" / "m")
    yb = save_map(_map(1, 12), tmp_path / "b" / "m")
    ia, ib = read_map_yaml(ya), read_map_yaml(yb)
    ib.image.write_bytes(ia.image.read_bytes())
    with pytest.raises(MapFileError, match=r"field 'write_id' is [0-9a-f]{8}.*do not belong"):
        load_map(yb)


def test_an_image_edited_by_hand_loads(tmp_path: Path) -> None:
    """An image without a write id (GIMP and other tools drop the PGM comment) is accepted."""
    import cv2

    y = save_map(_map(0, 12), tmp_path / "m")
    image = read_map_yaml(y).image
    pixels = cv2.imread(str(image), cv2.IMREAD_UNCHANGED)
    pixels[0, 0] = 0
    image.write_bytes(cv2.imencode(".pgm", pixels)[1].tobytes())
    assert load_map(y).data[-1, 0] == 100


def test_a_png_map_carries_its_write_id(tmp_path: Path) -> None:
    import cv2

    grid = OccupancyGrid(np.array([[-1, 0, 100], [10, 50, 90]], np.int8), 0.1)
    y = save_map(grid, tmp_path / "s", mode="scale")
    meta = read_map_yaml(y)
    assert map_io._image_write_id(meta.image.read_bytes()) == meta.write_id
    assert cv2.imread(str(meta.image), cv2.IMREAD_UNCHANGED).shape == (2, 3, 4)
    other = read_map_yaml(save_map(grid, tmp_path / "t", mode="scale"))
    meta.image.write_bytes(other.image.read_bytes())
    with pytest.raises(MapFileError, match="do not belong together"):
        load_map(y)


def test_a_size_mismatch_is_named(tmp_path: Path) -> None:
    y = save_map(_map(0, 12), tmp_path / "m")
    text = y.read_text().replace("width: 12", "width: 13")
    y.write_text(text)
    with pytest.raises(MapFileError, match=r"field 'width' is 13 pixels .* is 12"):
        load_map(y)


@pytest.mark.parametrize("write_id", ["'xyz'", "12", "'0123456789'"])
def test_a_malformed_write_id_is_named(tmp_path: Path, write_id: str) -> None:
    y = save_map(_map(0, 4), tmp_path / "m")
    lines = y.read_text().splitlines()
    lines[1] = f"write_id: {write_id}"
    y.write_text("\n".join(lines) + "\n")
    with pytest.raises(MapFileError, match="field 'write_id' must be 8 hex digits"):
        load_map(y)


def test_readers_during_saves_never_fail(tmp_path: Path) -> None:
    """A reader running while another thread overwrites the map sees whole maps."""
    maps = [_map(0, 60), _map(1, 60)]
    y = save_map(maps[0], tmp_path / "m")
    stop = threading.Event()

    def writer() -> None:
        i = 1
        while not stop.is_set():
            save_map(maps[i % 2], y)
            i += 1

    thread = threading.Thread(target=writer)
    thread.start()
    try:
        seen = [_which(load_map(y), maps) for _ in range(60)]
    finally:
        stop.set()
        thread.join()
    assert -1 not in seen


def test_atomic_writes_leave_the_target_alone_on_failure(tmp_path: Path) -> None:
    target = atomic_write_text(tmp_path / "x.json", "old\n")
    target.chmod(0o640)

    def fail_half_way() -> None:
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("killed")

    with pytest.raises(RuntimeError):
        fail_half_way()
    assert target.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["x.json"]
    atomic_write_text(target, "new\n")
    assert target.read_text() == "new\n"
    assert target.stat().st_mode & 0o777 == 0o640


def test_stale_temporaries_are_removed_only_when_old(tmp_path: Path) -> None:
    import os

    target = tmp_path / "x.yaml"
    stray = tmp_path / ".x.yaml.0123456789ab.tmp.yaml"
    stray.write_text("partial")
    assert remove_stale_temporaries(target) == 0  # fresh: perhaps a live writer's
    os.utime(stray, (time.time() - 3600, time.time() - 3600))
    assert remove_stale_temporaries(target) == 1
    assert not stray.exists()


def test_a_temporary_name_gives_back_its_target_and_nothing_else_does() -> None:
    for target in ("map.0123abcd.pgm", "map.yaml", "noext"):
        assert temporary_target(temporary_name(Path("/x") / target).name) == target
    for other in ("map.pgm", ".map.pgm.0123.tmp.pgm", ".map.pgm.0123456789ab.tmp.png", "x.tmp"):
        assert temporary_target(other) is None
