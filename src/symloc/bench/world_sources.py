"""Where a sweep's worlds come from, and the dev/test split of their seeds.

A :class:`WorldRef` names one world: a built-in room (``builtin``: the nine rooms of the
README's table, each inside the textured lab), a world file (``file``: YAML,
:mod:`symloc.sim.world_file`), or a generated world (``generated``: a family of
:data:`symloc.sim.generator.FAMILIES` and a seed). Refs are small and picklable; a worker
builds the world itself with :func:`build_world`.

The split: world ``i`` of a family gets seed ``SPLIT_BASE[split] + i``; the ``dev`` seeds
(0, 1, 2, ...) are the only ones thresholds and defaults are tuned on, the ``test`` seeds
(1,000,000, 1,000,001, ...) are where figures are reported. The two never overlap.

A world's robot (its lidar unit, camera lens and wheel calibration, drawn from the sensor
regime) and its mapping run are seeded by :attr:`WorldRef.robot_seed`, trial ``i`` by
:meth:`WorldRef.trial_seed`: both from the world's family and seed together, so each world of a
split has a robot of its own and no two worlds share a noise stream. (Until 2026-11-29 both came
from the seed alone: every family's world of one seed had the same lidar, and a split of two
seeds had two lidars.)
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from symloc.errors import ConfigurationError
from symloc.sim.generator import FAMILIES, generate_world
from symloc.sim.rooms import Room, build_room, hallway, with_lab
from symloc.sim.world_file import WorldSpec, load_world_file

__all__ = [
    "BUILTIN_ROOMS",
    "SPLIT_BASE",
    "WorldRef",
    "build_world",
    "builtin_refs",
    "family_refs",
    "file_refs",
    "split_seeds",
    "world_spec",
]

SPLIT_BASE = {"dev": 0, "test": 1_000_000}
"""First world seed of each split."""

#: The nine rooms of the README's table: name -> (builder name, G-V [m], textured lab).
BUILTIN_ROOMS: dict[str, tuple[str, float, bool]] = {
    "triangle": ("triangle", 2.0, True),
    "square": ("square", 3.0 / 2**0.5, True),
    "pentagon": ("pentagon", 2.0, True),
    "hexagon": ("hexagon", 2.0, True),
    "circle": ("circle", 1.7, True),
    "rectangle": ("rectangle", 2.2, True),
    "hallway": ("hallway", 3.2, True),
    "hallway_40m": ("hallway_40m", 0.0, True),
    "square_untextured": ("square", 3.0 / 2**0.5, False),
}


@dataclass(frozen=True)
class WorldRef:
    """One world of a sweep: ``source`` is ``builtin`` (``name`` a key of
    :data:`BUILTIN_ROOMS`), ``file`` (``name`` a path) or ``generated`` (``name`` a family);
    ``seed`` draws a generated world (unused otherwise)."""

    source: str
    name: str
    seed: int = 0

    @property
    def family(self) -> str:
        """The row a world's trials are counted under."""
        if self.source == "file":
            return f"file:{self.name.rsplit('/', 1)[-1]}"
        return self.name

    @property
    def world_id(self) -> str:
        """Unique within a sweep: ``family#seed``."""
        return f"{self.family}#{self.seed}"

    @property
    def robot_seed(self) -> int:
        """Seed of this world's robot and mapping run (``build_scenario``'s ``rng``): from the
        family and the seed together, so two families' worlds of one seed get different
        robots."""
        return _derived_seed(self.family, self.seed)

    def trial_seed(self, index: int) -> int:
        """Seed of trial ``index`` (>= 0) on this world, independent of every other world's
        and trial's."""
        if index < 0:
            raise ConfigurationError(f"index: expected a trial index >= 0, got {index}")
        return _derived_seed(self.family, self.seed, index)


def _derived_seed(family: str, *keys: int) -> int:
    """A 32-bit seed from ``family`` and the non-negative integers ``keys`` (NumPy's
    ``SeedSequence`` hashing: stable across runs, machines and NumPy versions)."""
    entropy = [zlib.crc32(family.encode("utf-8")), *keys]
    return int(np.random.SeedSequence(entropy).generate_state(1, np.uint32)[0])


def split_seeds(split: str, count: int, offset: int = 0) -> list[int]:
    """``count`` world seeds of ``split`` (``dev`` or ``test``), from ``offset``."""
    if split not in SPLIT_BASE:
        raise ConfigurationError(f"split: expected 'dev' or 'test', got {split!r}")
    if count < 1:
        raise ConfigurationError(f"count: expected >= 1 worlds, got {count}")
    return [SPLIT_BASE[split] + offset + i for i in range(count)]


def builtin_refs(names: Sequence[str], seeds: Sequence[int]) -> list[WorldRef]:
    """Every built-in room of ``names`` with every seed (a new map per seed)."""
    bad = [n for n in names if n not in BUILTIN_ROOMS]
    if bad:
        raise ConfigurationError(
            f"room: unknown {', '.join(bad)}; expected some of {', '.join(BUILTIN_ROOMS)}"
        )
    return [WorldRef("builtin", n, s) for n in names for s in seeds]


def family_refs(families: Sequence[str], seeds: Sequence[int]) -> list[WorldRef]:
    """Worlds by name: a generator family (one world per seed) or a built-in room (a new map
    per seed); unknown names raise, listing both."""
    bad = [n for n in families if n not in FAMILIES and n not in BUILTIN_ROOMS]
    if bad:
        raise ConfigurationError(
            f"families: unknown {', '.join(bad)}; generator families: {', '.join(FAMILIES)}; "
            f"built-in rooms: {', '.join(BUILTIN_ROOMS)}"
        )
    return [
        WorldRef("generated" if n in FAMILIES else "builtin", n, s) for n in families for s in seeds
    ]


def file_refs(paths: Sequence[str], seeds: Sequence[int]) -> list[WorldRef]:
    """Every world file of ``paths`` with every seed (validated here, so a bad file fails
    before the sweep starts)."""
    for path in paths:
        load_world_file(path)
    return [WorldRef("file", str(p), s) for p in paths for s in seeds]


def world_spec(ref: WorldRef) -> WorldSpec | None:
    """The world file a generated or file ref names (None for a built-in room)."""
    if ref.source == "generated":
        return generate_world(ref.name, ref.seed)
    if ref.source == "file":
        return load_world_file(ref.name)
    return None


def build_world(ref: WorldRef) -> Room:
    """The :class:`~symloc.sim.rooms.Room` a ref names."""
    spec = world_spec(ref) if ref.source in ("generated", "file") else None
    if spec is not None:
        return spec.build()
    if ref.source == "builtin":
        if ref.name not in BUILTIN_ROOMS:
            raise ConfigurationError(f"room: unknown built-in room {ref.name!r}")
        builder, gv, textured = BUILTIN_ROOMS[ref.name]
        if builder == "hallway_40m":
            room = with_lab(hallway(40.0, 2.0, textured=textured), textured=textured)
        else:
            room = build_room(builder, gv, lab=True, textured=textured)
        return room
    raise ConfigurationError(
        f"world source: expected 'builtin', 'file' or 'generated', got {ref.source!r}"
    )
