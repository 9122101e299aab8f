"""World files, the spec half that reading and building share: the parts of a world and its names.

:mod:`symloc.sim.world_file` reads a YAML document into these parts (and a
:class:`~symloc.sim.world_file.WorldSpec` holding them); :mod:`symloc.sim.world_build` turns
any :class:`WorldParts` into walls, obstacles and a :class:`~symloc.sim.rooms.Room`. Neither
needs the other to know what a room, a piece of furniture or a door is: that is here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from symloc.errors import WorldError
from symloc.sim.people import PERSON_HEIGHT, PERSON_RADIUS, WALKING_SPEED, Person
from symloc.sim.rooms import FURNITURE_HEIGHT, WALL_HEIGHT
from symloc.sim.textures import TEXTURE_POOL_SIZE
from symloc.sim.world import MATERIAL_DARK, MATERIAL_FURNITURE, MATERIAL_GLASS, MATERIAL_WALL

__all__ = [
    "GLASS_HEIGHT",
    "LAB_WALL_HEIGHT",
    "MATERIALS",
    "PILLAR_HEIGHT",
    "ROOM_SHAPES",
    "TEXTURE_POOL",
    "DoorSpec",
    "ErrorContext",
    "FurnitureSpec",
    "GlassSpec",
    "LabSpec",
    "PersonSpec",
    "RoomSpec",
    "WorldParts",
]

FloatArray = NDArray[np.float64]
Point = tuple[float, float]

ROOM_SHAPES = ("polygon", "regular", "circle", "rectangle", "corridor")
"""The keys of ``room`` that give its shape (exactly one per file)."""
PILLAR_HEIGHT = WALL_HEIGHT
GLASS_HEIGHT = 2.0
LAB_WALL_HEIGHT = 1.0
"""Room walls lower than this [m] are boards and the room stands in a textured lab."""
TEXTURE_POOL = TEXTURE_POOL_SIZE
"""Texture ids drawn from a world's seed lie in ``0 .. TEXTURE_POOL - 1`` (the distinct textures of
:mod:`symloc.sim.textures`)."""
MATERIALS = {
    "wood": MATERIAL_FURNITURE,
    "plain": MATERIAL_WALL,
    "dark": MATERIAL_DARK,
    "glass": MATERIAL_GLASS,
}
"""Material names of furniture and pillars."""


@dataclass(frozen=True)
class ErrorContext:
    """Where a world document came from: every error message starts with it."""

    source: str

    def error(self, path: str, message: str) -> WorldError:
        return WorldError(f"{self.source}: {path}: {message}")


@dataclass(frozen=True)
class RoomSpec:
    """The room's outline and walls (``room`` in a world file).

    ``shape`` is one of :data:`ROOM_SHAPES`; only the fields of that shape are used:
    ``polygon`` (vertices [m]), ``regular`` (``n``, ``gv`` centre to vertex [m]), ``circle``
    (``radius`` [m]), ``rectangle`` (``width`` along x, ``depth`` along y [m]), ``corridor``
    (``length`` along x, ``width`` [m]); ``center`` [m] and ``yaw_deg`` [deg] place the last four
    (a circle ignores the yaw). ``chamfer`` is empty (no cuts), one cut for every corner, or one
    per corner [m].
    """

    shape: str
    polygon: tuple[Point, ...] = ()
    n: int = 0
    gv: float = 0.0
    radius: float = 0.0
    width: float = 0.0
    depth: float = 0.0
    length: float = 0.0
    center: Point = (0.0, 0.0)
    yaw_deg: float = 0.0
    wall_height: float = WALL_HEIGHT
    chamfer: tuple[float, ...] = ()

    @property
    def in_lab(self) -> bool:
        """True when the walls are low boards and the room stands in a lab."""
        return self.wall_height < LAB_WALL_HEIGHT

    def to_dict(self) -> dict[str, Any]:
        """The ``room`` mapping of a world file."""
        out: dict[str, Any] = {}
        c = [self.center[0], self.center[1]]
        placed = {} if self.center == (0.0, 0.0) else {"center": c}
        yaw = {} if self.yaw_deg == 0.0 else {"yaw_deg": self.yaw_deg}
        if self.shape == "polygon":
            out["polygon"] = [[x, y] for x, y in self.polygon]
        elif self.shape == "regular":
            out["regular"] = {"n": self.n, "gv": self.gv, **placed, **yaw}
        elif self.shape == "circle":
            out["circle"] = {"radius": self.radius, **placed}
        elif self.shape == "rectangle":
            out["rectangle"] = {"width": self.width, "depth": self.depth, **placed, **yaw}
        else:
            out["corridor"] = {"length": self.length, "width": self.width, **placed, **yaw}
        out["wall_height"] = self.wall_height
        if self.chamfer:
            out["chamfer"] = self.chamfer[0] if len(self.chamfer) == 1 else list(self.chamfer)
        return out


@dataclass(frozen=True)
class FurnitureSpec:
    """A box (``size`` [m] width x depth, turned by ``yaw_deg``) or a cylinder (``radius``)."""

    kind: str
    center: Point
    size: Point = (0.0, 0.0)
    radius: float = 0.0
    yaw_deg: float = 0.0
    height: float = FURNITURE_HEIGHT
    material: str = "wood"

    def footprint(self) -> FloatArray:
        """The box's corners ``(4, 2)`` [m] counter-clockwise (boxes only)."""
        w, d = self.size
        th = math.radians(self.yaw_deg)
        rot = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        local = np.array([[-w / 2, -d / 2], [w / 2, -d / 2], [w / 2, d / 2], [-w / 2, d / 2]])
        return np.asarray(np.array(self.center) + local @ rot.T, dtype=np.float64)

    def to_dict(self, *, pillar: bool = False) -> dict[str, Any]:
        """The mapping of one ``furniture`` entry (``pillar``: of one ``pillars`` entry)."""
        body: dict[str, Any] = {"center": list(self.center)}
        if self.kind == "box":
            body["size"] = list(self.size)
            if self.yaw_deg != 0.0:
                body["yaw_deg"] = self.yaw_deg
        else:
            body["radius"] = self.radius
        default_h, default_m = (PILLAR_HEIGHT, "plain") if pillar else (FURNITURE_HEIGHT, "wood")
        if not pillar or self.height != default_h:
            body["height"] = self.height
        if self.material != default_m:
            body["material"] = self.material
        return body if pillar else {self.kind: body}


@dataclass(frozen=True)
class GlassSpec:
    """A free-standing glass panel from ``start`` to ``end`` [m] (``from`` / ``to`` in a file)."""

    start: Point
    end: Point
    height: float = GLASS_HEIGHT

    def to_dict(self) -> dict[str, Any]:
        """The mapping of one ``glass`` entry."""
        return {"from": list(self.start), "to": list(self.end), "height": self.height}


@dataclass(frozen=True)
class DoorSpec:
    """A door of ``width`` [m] centred at fraction ``at`` of wall ``wall``; a gap if ``open``."""

    wall: int
    at: float = 0.5
    width: float = 0.9
    open: bool = True

    def to_dict(self) -> dict[str, Any]:
        """The mapping of one ``doors`` entry."""
        return {"wall": self.wall, "at": self.at, "width": self.width, "open": self.open}


@dataclass(frozen=True)
class LabSpec:
    """Wall textures (and the lab around a room of boards).

    ``textures`` empty: ``textured`` True gives each wall its own texture, False plain walls;
    otherwise one entry per wall (an int texture id, ``"plain"`` or ``"dark"``). ``size`` [m]
    (minimum lab width and depth, default 8 x 10) and ``margin`` [m] (lab wall to room, at
    least) apply to a room of boards.
    """

    textured: bool = True
    textures: tuple[int | str, ...] = ()
    size: Point | None = None
    margin: float = 1.5

    def to_dict(self) -> str | dict[str, Any]:
        """``"textured"``, ``"untextured"`` or the mapping form."""
        if not self.textures and self.size is None and self.margin == 1.5:
            return "textured" if self.textured else "untextured"
        out: dict[str, Any] = {}
        if self.textures:
            out["textures"] = list(self.textures)
        else:
            out["textured"] = self.textured
        if self.size is not None:
            out["size"] = list(self.size)
        if self.margin != 1.5:
            out["margin"] = self.margin
        return out


@dataclass(frozen=True)
class PersonSpec:
    """A person walking along ``path`` [m] (see :class:`symloc.sim.people.Person`)."""

    path: tuple[Point, ...]
    speed: float = WALKING_SPEED
    radius: float = PERSON_RADIUS
    height: float = PERSON_HEIGHT
    loop: bool = False
    phase: float = 0.0

    def person(self) -> Person:
        """The :class:`~symloc.sim.people.Person` that walks this path."""
        return Person(
            np.array(self.path, dtype=np.float64),
            speed=self.speed,
            radius=self.radius,
            height=self.height,
            loop=self.loop,
            phase=self.phase,
        )

    def to_dict(self) -> dict[str, Any]:
        """The mapping of one ``people`` entry."""
        out: dict[str, Any] = {"path": [list(p) for p in self.path], "speed": self.speed}
        out["radius"] = self.radius
        if self.height != PERSON_HEIGHT:
            out["height"] = self.height
        if self.loop:
            out["loop"] = True
        if self.phase != 0.0:
            out["phase"] = self.phase
        return out


class WorldParts(Protocol):
    """What building a world reads of it: :class:`~symloc.sim.world_file.WorldSpec` is one."""

    @property
    def name(self) -> str: ...
    @property
    def room(self) -> RoomSpec: ...
    @property
    def furniture(self) -> tuple[FurnitureSpec, ...]: ...
    @property
    def pillars(self) -> tuple[FurnitureSpec, ...]: ...
    @property
    def glass(self) -> tuple[GlassSpec, ...]: ...
    @property
    def doors(self) -> tuple[DoorSpec, ...]: ...
    @property
    def lab(self) -> LabSpec: ...
    @property
    def people(self) -> tuple[PersonSpec, ...]: ...
    @property
    def seed(self) -> int | None: ...
    @property
    def source(self) -> str: ...
