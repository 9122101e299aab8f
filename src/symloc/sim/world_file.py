"""World files: a floor plan in YAML, loaded into a validated :class:`WorldSpec`.

A user describes a room once, in metres, and every simulator command (and the bench) runs it.
``WorldSpec.build()`` turns it into a :class:`~symloc.sim.rooms.Room`, whose rotational symmetry
order is computed from the geometry (:mod:`symloc.sim.symmetry_truth`), never declared. The full
reference with a complete example is ``docs/world_files.md``; in short::

    name: square-with-box
    description: free text            # optional
    seed: 7                            # optional: picks the wall textures (see lab)
    room:                              # exactly one of polygon | regular | circle | rectangle | corridor
      polygon: [[-2, -2], [2, -2], [2, 2], [-2, 2]]   # metres; walls numbered as listed
      # regular: {n: 8, gv: 3.0, center: [0, 0], yaw_deg: 0}   (gv: centre to vertex)
      # circle: {radius: 3.0, center: [0, 0]}
      # rectangle: {width: 4, depth: 2, center: [0, 0], yaw_deg: 0}
      # corridor: {length: 50, width: 2, center: [0, 0], yaw_deg: 0}   (along x)
      wall_height: 2.0                 # < 1 m: low boards inside a lab (the paper's setup)
      chamfer: 0.2                     # optional: cut every corner by 0.2 m (or one per corner)
    furniture:                         # optional; the lidar sees an item only above 0.3 m
      - box: {center: [1.45, 0.0], size: [0.5, 0.5], yaw_deg: 0, height: 0.8, material: wood}
      - cylinder: {center: [0.0, 1.0], radius: 0.2, height: 1.0}
    pillars:                           # optional; floor to ceiling (2.5 m) unless height given
      - {center: [1.0, 1.0], radius: 0.15}
      - {center: [-1.0, 1.0], size: [0.3, 0.3], yaw_deg: 45}
    glass:                             # optional free-standing glass panels
      - {from: [-1.0, -1.5], to: [0.0, -1.5], height: 2.0}
    doors:                             # optional
      - {wall: 0, at: 0.5, width: 0.9, open: true}
    lab: textured                      # textured | untextured | {textures: [...], size, margin}
    people:                            # optional, walking at ~1 m/s
      - {path: [[-1, -1], [1, -1], [1, 1]], speed: 1.0, radius: 0.25, loop: false}

Meaning of the less obvious keys:

- ``room.polygon``: counter-clockwise as written in the example; a clockwise list is accepted
  too (it has one orientation), but a self-intersecting or zero-area one, whose orientation is
  ambiguous, is an error. Wall i runs from vertex i to vertex i+1 as listed; for ``regular``
  and ``rectangle`` wall 0 is the bottom one (before ``yaw_deg``), for ``corridor`` the long
  wall at -y.
- ``room.wall_height``: walls of at least :data:`LAB_WALL_HEIGHT` (1 m) carry the wall
  textures themselves; lower walls are plain boards and the room stands in a lab (12 textured
  walls, 8 m x 10 m or larger, centred on the room) that the camera sees above them, as in the
  paper's real experiment. Boards lower than the lidar plane (0.3 m) leave the lidar looking at
  the lab.
- ``room.chamfer``: a corner cut [m] measured along both walls from the corner; one number
  for all corners or one per corner (0 for none). Equal cuts keep the room's symmetry.
- ``doors``: ``at`` is the door centre as a fraction of wall ``wall`` (for a circle, a
  fraction of the circumference counter-clockwise from the bottom); an open door is a gap, a
  closed one a wooden leaf flush with the wall (the lidar cannot tell it from the wall).
- ``lab``: ``textured`` gives every wall (or lab segment) its own texture (material
  ``MATERIAL_PHOTO + k``), ids 0, 1, 2, ... in order, or drawn from ``seed`` (distinct, from
  ``0 .. TEXTURE_POOL - 1``) when a seed is given; ``untextured`` gives plain painted walls;
  ``{textures: [...]}`` lists one entry per wall (tall walls: per room wall as numbered above,
  or per equal arc of a round room from the bottom counter-clockwise; boards: per lab segment,
  at least 4): an integer texture id, ``plain`` or ``dark``. Two walls with the same id show the
  same picture (perceptual aliasing). Corner cuts are plain walls. ``size: [w, d]`` and
  ``margin`` shape the lab (boards only).
- ``material`` (furniture, pillars): ``wood`` (furniture default), ``plain`` (pillar default),
  ``dark`` (low lidar reflectivity) or ``glass`` (the lidar sees through it).
- ``people``: each walks its ``path`` to the end and back (``loop: false``) or round it
  (``loop: true``), starting ``phase`` metres along it; paths must stay inside the room and
  ``radius`` clear of every wall and obstacle.
- ``generator: {family, seed}``: written by ``symloc sim world`` to record where a generated
  world came from; ignored when building.

Every error is a :class:`~symloc.errors.WorldError` whose message names the file, the key path
(``room.polygon[3]``, ``furniture[1].box.size``) and what was expected.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from symloc.errors import WorldError
from symloc.sim.people import PERSON_HEIGHT, PERSON_RADIUS, WALKING_SPEED, Person
from symloc.sim.rooms import (
    BOARD_HEIGHT,
    DOOR_WIDTH,
    FURNITURE_HEIGHT,
    HALLWAY_ASPECT,
    RECTANGLE_ASPECT,
    ROOM_NAMES,
    WALL_HEIGHT,
    Room,
    l_shaped_room,
    lab,
)
from symloc.sim.symmetry_truth import lidar_symmetry
from symloc.sim.world import (
    MATERIAL_BOARD,
    MATERIAL_DARK,
    MATERIAL_FURNITURE,
    MATERIAL_GLASS,
    MATERIAL_PHOTO,
    MATERIAL_WALL,
    World,
    points_in_polygon,
    segments_cross,
)

__all__ = [
    "LAB_WALL_HEIGHT",
    "ROOM_SHAPES",
    "TEXTURE_POOL",
    "DoorSpec",
    "FurnitureSpec",
    "GlassSpec",
    "LabSpec",
    "PersonSpec",
    "RoomSpec",
    "WorldSpec",
    "corner_points",
    "load_world_file",
    "room_spec",
    "save_world_file",
]

FloatArray = NDArray[np.float64]
Point = tuple[float, float]

LAB_WALL_HEIGHT = 1.0
"""Room walls lower than this [m] are boards and the room stands in a textured lab."""
TEXTURE_POOL = 10_000
"""Texture ids drawn from a world's seed lie in ``0 .. TEXTURE_POOL - 1``."""
ROOM_SHAPES = ("polygon", "regular", "circle", "rectangle", "corridor")
"""The keys of ``room`` that give its shape (exactly one per file)."""
MATERIALS = {
    "wood": MATERIAL_FURNITURE,
    "plain": MATERIAL_WALL,
    "dark": MATERIAL_DARK,
    "glass": MATERIAL_GLASS,
}
"""Material names of furniture and pillars."""
DOOR_HEIGHT = 2.0
"""Height [m] of a closed door's leaf (lower if the walls are lower)."""
PILLAR_HEIGHT = WALL_HEIGHT
GLASS_HEIGHT = 2.0

_COORD_LIMIT = 1000.0  # |x|, |y| [m]
_SIZE_LIMIT = 1000.0  # sizes [m]
_MAX_VERTICES = 200
_MAX_ITEMS = 200
_MIN_GAP = 0.01  # furniture keeps at least this [m] from walls and from each other
_CIRCLE_SAGITTA = 0.002  # facets of a round wall deviate at most this [m] from the circle
_BOUNDARY_VERTICES = 256  # outline of a round room for inside tests


# --------------------------------------------------------------------------------------------
# reading: small checks that name the key path
# --------------------------------------------------------------------------------------------


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


@dataclass(frozen=True)
class _Ctx:
    """Where a document came from, for error messages."""

    source: str

    def error(self, path: str, message: str) -> WorldError:
        return WorldError(f"{self.source}: {path}: {message}")


def _mapping(
    ctx: _Ctx, obj: Any, path: str, allowed: tuple[str, ...], required: tuple[str, ...] = ()
) -> dict[str, Any]:
    if not isinstance(obj, Mapping):
        raise ctx.error(
            path, f"expected a mapping with keys {', '.join(allowed)}; got {_show(obj)}"
        )
    for key in obj:
        if not isinstance(key, str) or key not in allowed:
            raise ctx.error(
                f"{path}.{key}" if path else str(key),
                f"unknown key; expected one of {', '.join(allowed)}",
            )
    for key in required:
        if key not in obj:
            raise ctx.error(f"{path}.{key}" if path else key, "missing; this key is required")
    return dict(obj)


def _number(
    ctx: _Ctx,
    obj: Any,
    path: str,
    *,
    low: float = -math.inf,
    high: float = math.inf,
    low_open: bool = False,
    unit: str = "m",
) -> float:
    if isinstance(obj, bool) or not isinstance(obj, (int, float)):
        hint = ""
        if isinstance(obj, str):
            hint = " (a string; YAML reads 1e3 as text: write 1.0e3)"
        raise ctx.error(path, f"expected a number [{unit}], got {_show(obj)}{hint}")
    value = float(obj)
    bad = not math.isfinite(value) or value > high or value < low or (low_open and value == low)
    if bad:
        lo = "(" if low_open else "["
        raise ctx.error(path, f"expected a number in {lo}{low}, {high}] {unit}, got {_show(obj)}")
    return value


def _integer(ctx: _Ctx, obj: Any, path: str, low: int, high: int) -> int:
    if isinstance(obj, bool) or not isinstance(obj, int) or not low <= obj <= high:
        raise ctx.error(path, f"expected an integer in [{low}, {high}], got {_show(obj)}")
    return int(obj)


def _boolean(ctx: _Ctx, obj: Any, path: str) -> bool:
    if not isinstance(obj, bool):
        raise ctx.error(path, f"expected true or false, got {_show(obj)}")
    return obj


def _string(ctx: _Ctx, obj: Any, path: str) -> str:
    if not isinstance(obj, str):
        raise ctx.error(path, f"expected a string, got {_show(obj)}")
    return obj


def _list(ctx: _Ctx, obj: Any, path: str, what: str, max_n: int = _MAX_ITEMS) -> list[Any]:
    if not isinstance(obj, list):
        raise ctx.error(path, f"expected a list of {what}, got {_show(obj)}")
    if len(obj) > max_n:
        raise ctx.error(path, f"expected at most {max_n} {what}, got {len(obj)}")
    return obj


def _point(ctx: _Ctx, obj: Any, path: str) -> Point:
    if not isinstance(obj, list) or len(obj) != 2:
        raise ctx.error(path, f"expected a point [x, y] in metres, got {_show(obj)}")
    lim = _COORD_LIMIT
    return (
        _number(ctx, obj[0], f"{path}[0]", low=-lim, high=lim),
        _number(ctx, obj[1], f"{path}[1]", low=-lim, high=lim),
    )


def _size(ctx: _Ctx, obj: Any, path: str) -> Point:
    if not isinstance(obj, list) or len(obj) != 2:
        raise ctx.error(path, f"expected a size [width, depth] in metres, got {_show(obj)}")
    return (
        _number(ctx, obj[0], f"{path}[0]", low=0.01, high=_SIZE_LIMIT),
        _number(ctx, obj[1], f"{path}[1]", low=0.01, high=_SIZE_LIMIT),
    )


def _points(ctx: _Ctx, obj: Any, path: str, min_n: int, max_n: int) -> tuple[Point, ...]:
    items = _list(ctx, obj, path, "[x, y] points", max_n)
    if len(items) < min_n:
        raise ctx.error(path, f"expected at least {min_n} [x, y] points, got {len(items)}")
    return tuple(_point(ctx, p, f"{path}[{i}]") for i, p in enumerate(items))


# --------------------------------------------------------------------------------------------
# the spec
# --------------------------------------------------------------------------------------------


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


@dataclass(frozen=True)
class WorldSpec:
    """A validated world file (see the module docstring); ``build()`` makes the Room.

    Constructing one validates the geometry (outline, doors, furniture inside the room and
    apart, people's paths clear) and raises :class:`~symloc.errors.WorldError` naming the key
    path; ``source`` (the file, for messages) does not take part in equality.
    """

    name: str
    room: RoomSpec
    furniture: tuple[FurnitureSpec, ...] = ()
    pillars: tuple[FurnitureSpec, ...] = ()
    glass: tuple[GlassSpec, ...] = ()
    doors: tuple[DoorSpec, ...] = ()
    lab: LabSpec = field(default_factory=LabSpec)
    people: tuple[PersonSpec, ...] = ()
    seed: int | None = None
    description: str = ""
    generator: tuple[str, int] | None = None
    source: str = field(default="<world>", compare=False)

    def __post_init__(self) -> None:
        _assemble(self)

    @staticmethod
    def from_dict(doc: Any, source: str = "<dict>") -> WorldSpec:
        """Parse and validate a world document (the mapping a YAML file holds)."""
        return _parse(doc, _Ctx(source))

    def to_dict(self) -> dict[str, Any]:
        """The world document (plain dicts, lists and numbers); ``from_dict`` reads it back."""
        out: dict[str, Any] = {"name": self.name}
        if self.description:
            out["description"] = self.description
        if self.generator is not None:
            out["generator"] = {"family": self.generator[0], "seed": self.generator[1]}
        if self.seed is not None:
            out["seed"] = self.seed
        out["room"] = self.room.to_dict()
        if self.furniture:
            out["furniture"] = [f.to_dict() for f in self.furniture]
        if self.pillars:
            out["pillars"] = [p.to_dict(pillar=True) for p in self.pillars]
        if self.glass:
            out["glass"] = [g.to_dict() for g in self.glass]
        if self.doors:
            out["doors"] = [d.to_dict() for d in self.doors]
        out["lab"] = self.lab.to_dict()
        if self.people:
            out["people"] = [p.to_dict() for p in self.people]
        return out

    def to_yaml(self) -> str:
        """The world file's text."""
        return str(yaml.safe_dump(self.to_dict(), sort_keys=False, default_flow_style=None))

    def build(self) -> Room:
        """The :class:`~symloc.sim.rooms.Room`, with its symmetry order computed.

        ``Room.center`` is the rotation centre when the lidar-visible geometry is symmetric, the
        area centroid of the outline otherwise; ``Room.gv_distance`` is the largest distance from
        it to a corner of the outline (the radius of a round room).
        """
        from dataclasses import replace

        room = _assemble(self)
        truth = lidar_symmetry(room.world, room.boundary)
        center = truth.center if truth.order != 1 else room.center
        gv = float(np.max(np.hypot(*(room.boundary - center).T)))
        shape = lidar_symmetry(_bare_walls(_outline(_Ctx(self.source), self.room))).order
        return replace(
            room,
            order=truth.order,
            shape_order=shape,
            symmetry=truth,
            center=center,
            gv_distance=gv,
        )


def load_world_file(path: str | Path) -> WorldSpec:
    """Read and validate a world file (YAML); errors name the file and the key path."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise WorldError(f"{p}: cannot read the world file: {err}") from err
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as err:
        raise WorldError(f"{p}: not valid YAML: {err}") from err
    return WorldSpec.from_dict(doc, str(p))


def save_world_file(spec: WorldSpec, path: str | Path, *, header: str = "") -> Path:
    """Write ``spec`` as YAML (``header`` lines become comments at the top); returns the path."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    lines = "".join(f"# {line}\n" for line in header.splitlines())
    p.write_text(lines + spec.to_yaml(), encoding="utf-8")
    return p


# --------------------------------------------------------------------------------------------
# parsing
# --------------------------------------------------------------------------------------------

_TOP_KEYS = (
    "name",
    "description",
    "seed",
    "generator",
    "room",
    "furniture",
    "pillars",
    "glass",
    "doors",
    "lab",
    "people",
)


def _parse(doc: Any, ctx: _Ctx) -> WorldSpec:
    if doc is None:
        raise ctx.error("(top)", "the world file is empty; expected a mapping with name and room")
    top = _mapping(ctx, doc, "", _TOP_KEYS, ("room",))
    name = _string(ctx, top.get("name", Path(ctx.source).stem or "world"), "name")
    description = _string(ctx, top.get("description", ""), "description")
    seed = None if top.get("seed") is None else _integer(ctx, top["seed"], "seed", 0, 2**63 - 1)
    generator = None
    if "generator" in top:
        g = _mapping(ctx, top["generator"], "generator", ("family", "seed"), ("family", "seed"))
        generator = (
            _string(ctx, g["family"], "generator.family"),
            _integer(ctx, g["seed"], "generator.seed", 0, 2**63 - 1),
        )
    room = _parse_room(ctx, top["room"])
    furniture = tuple(
        _parse_furniture(ctx, f, f"furniture[{i}]")
        for i, f in enumerate(_list(ctx, top.get("furniture", []), "furniture", "items"))
    )
    pillars = tuple(
        _parse_pillar(ctx, f, f"pillars[{i}]")
        for i, f in enumerate(_list(ctx, top.get("pillars", []), "pillars", "pillars"))
    )
    glass = tuple(
        _parse_glass(ctx, g, f"glass[{i}]")
        for i, g in enumerate(_list(ctx, top.get("glass", []), "glass", "panels"))
    )
    doors = tuple(
        _parse_door(ctx, d, f"doors[{i}]")
        for i, d in enumerate(_list(ctx, top.get("doors", []), "doors", "doors"))
    )
    lab_spec = _parse_lab(ctx, top.get("lab", "textured"))
    people = tuple(
        _parse_person(ctx, p, f"people[{i}]")
        for i, p in enumerate(_list(ctx, top.get("people", []), "people", "people", 50))
    )
    return WorldSpec(
        name=name,
        room=room,
        furniture=furniture,
        pillars=pillars,
        glass=glass,
        doors=doors,
        lab=lab_spec,
        people=people,
        seed=seed,
        description=description,
        generator=generator,
        source=ctx.source,
    )


def _parse_room(ctx: _Ctx, obj: Any) -> RoomSpec:
    r = _mapping(ctx, obj, "room", (*ROOM_SHAPES, "wall_height", "chamfer"))
    shapes = [k for k in ROOM_SHAPES if k in r]
    if len(shapes) != 1:
        got = ", ".join(shapes) if shapes else "none"
        raise ctx.error("room", f"expected exactly one of {', '.join(ROOM_SHAPES)}; got {got}")
    shape = shapes[0]
    wall_height = _number(
        ctx,
        r.get("wall_height", WALL_HEIGHT),
        "room.wall_height",
        low=0.0,
        high=100.0,
        low_open=True,
    )
    chamfer: tuple[float, ...] = ()
    if "chamfer" in r:
        c = r["chamfer"]
        if isinstance(c, list):
            chamfer = tuple(
                _number(ctx, x, f"room.chamfer[{i}]", low=0.0, high=_SIZE_LIMIT)
                for i, x in enumerate(_list(ctx, c, "room.chamfer", "corner cuts", _MAX_VERTICES))
            )
        else:
            chamfer = (_number(ctx, c, "room.chamfer", low=0.0, high=_SIZE_LIMIT),)
        if all(x == 0.0 for x in chamfer):
            chamfer = ()
    common: dict[str, Any] = {"shape": shape, "wall_height": wall_height, "chamfer": chamfer}
    path = f"room.{shape}"
    body = r[shape]
    if shape == "polygon":
        return RoomSpec(polygon=_points(ctx, body, path, 3, _MAX_VERTICES), **common)
    keys: dict[str, tuple[str, ...]] = {
        "regular": ("n", "gv"),
        "circle": ("radius",),
        "rectangle": ("width", "depth"),
        "corridor": ("length", "width"),
    }
    extra = ("center",) if shape == "circle" else ("center", "yaw_deg")
    m = _mapping(ctx, body, path, (*keys[shape], *extra), keys[shape])
    if "center" in m:
        common["center"] = _point(ctx, m["center"], f"{path}.center")
    if "yaw_deg" in m:
        common["yaw_deg"] = _number(
            ctx, m["yaw_deg"], f"{path}.yaw_deg", low=-360, high=360, unit="deg"
        )
    if shape == "regular":
        common["n"] = _integer(ctx, m["n"], f"{path}.n", 3, 64)
    for k in keys[shape]:
        if k != "n":
            common[k] = _number(ctx, m[k], f"{path}.{k}", low=0.3, high=_SIZE_LIMIT)
    return RoomSpec(**common)


def _material(ctx: _Ctx, obj: Any, path: str) -> str:
    name = _string(ctx, obj, path)
    if name not in MATERIALS:
        raise ctx.error(path, f"expected one of {', '.join(MATERIALS)}, got {_show(obj)}")
    return name


def _parse_solid(
    ctx: _Ctx, body: dict[str, Any], path: str, kind: str, height: float, material: str
) -> FurnitureSpec:
    center = _point(ctx, body["center"], f"{path}.center")
    h = height
    if "height" in body:
        h = _number(ctx, body["height"], f"{path}.height", low=0.0, high=100.0, low_open=True)
    mat = _material(ctx, body["material"], f"{path}.material") if "material" in body else material
    if kind == "box":
        yaw = 0.0
        if "yaw_deg" in body:
            yaw = _number(ctx, body["yaw_deg"], f"{path}.yaw_deg", low=-360, high=360, unit="deg")
        size = _size(ctx, body["size"], f"{path}.size")
        return FurnitureSpec("box", center, size=size, yaw_deg=yaw, height=h, material=mat)
    radius = _number(ctx, body["radius"], f"{path}.radius", low=0.01, high=_SIZE_LIMIT)
    return FurnitureSpec("cylinder", center, radius=radius, height=h, material=mat)


def _parse_furniture(ctx: _Ctx, obj: Any, path: str) -> FurnitureSpec:
    item = _mapping(ctx, obj, path, ("box", "cylinder"))
    if len(item) != 1:
        raise ctx.error(path, "expected exactly one of box, cylinder")
    kind = next(iter(item))
    p = f"{path}.{kind}"
    common = ("center", "height", "material")
    if kind == "box":
        body = _mapping(ctx, item[kind], p, (*common, "size", "yaw_deg"), ("center", "size"))
    else:
        body = _mapping(ctx, item[kind], p, (*common, "radius"), ("center", "radius"))
    return _parse_solid(ctx, body, p, kind, FURNITURE_HEIGHT, "wood")


def _parse_pillar(ctx: _Ctx, obj: Any, path: str) -> FurnitureSpec:
    body = _mapping(ctx, obj, path, ("center", "radius", "size", "yaw_deg", "height", "material"))
    if ("radius" in body) == ("size" in body):
        raise ctx.error(path, "expected exactly one of radius (round) or size (square)")
    if "center" not in body:
        raise ctx.error(f"{path}.center", "missing; this key is required")
    if "radius" in body and "yaw_deg" in body:
        raise ctx.error(
            f"{path}.yaw_deg",
            "unknown key for a round pillar; expected center, radius, height, material",
        )
    kind = "cylinder" if "radius" in body else "box"
    return _parse_solid(ctx, body, path, kind, PILLAR_HEIGHT, "plain")


def _parse_glass(ctx: _Ctx, obj: Any, path: str) -> GlassSpec:
    g = _mapping(ctx, obj, path, ("from", "to", "height"), ("from", "to"))
    h = GLASS_HEIGHT
    if "height" in g:
        h = _number(ctx, g["height"], f"{path}.height", low=0.0, high=100.0, low_open=True)
    a = _point(ctx, g["from"], f"{path}.from")
    b = _point(ctx, g["to"], f"{path}.to")
    if math.hypot(b[0] - a[0], b[1] - a[1]) < 0.05:
        raise ctx.error(path, "expected a panel at least 0.05 m long (from and to coincide)")
    return GlassSpec(a, b, h)


def _parse_door(ctx: _Ctx, obj: Any, path: str) -> DoorSpec:
    d = _mapping(ctx, obj, path, ("wall", "at", "width", "open"), ("wall",))
    return DoorSpec(
        wall=_integer(ctx, d["wall"], f"{path}.wall", 0, _MAX_VERTICES * 2),
        at=_number(ctx, d.get("at", 0.5), f"{path}.at", low=0.0, high=1.0, unit="fraction"),
        width=_number(ctx, d.get("width", 0.9), f"{path}.width", low=0.05, high=_SIZE_LIMIT),
        open=_boolean(ctx, d.get("open", True), f"{path}.open"),
    )


def _parse_lab(ctx: _Ctx, obj: Any) -> LabSpec:
    if isinstance(obj, str):
        if obj not in ("textured", "untextured"):
            raise ctx.error("lab", f"expected textured, untextured or a mapping, got {_show(obj)}")
        return LabSpec(textured=obj == "textured")
    m = _mapping(ctx, obj, "lab", ("textures", "textured", "size", "margin"))
    if "textures" in m and "textured" in m:
        raise ctx.error("lab", "expected textures or textured, not both")
    textures: list[int | str] = []
    for i, t in enumerate(_list(ctx, m.get("textures", []), "lab.textures", "textures", 1000)):
        if isinstance(t, str) and t in ("plain", "dark"):
            textures.append(t)
        elif isinstance(t, int) and not isinstance(t, bool) and 0 <= t < 10**9:
            textures.append(int(t))
        else:
            raise ctx.error(
                f"lab.textures[{i}]",
                f"expected a texture id (integer >= 0), plain or dark, got {_show(t)}",
            )
    if "textures" in m and not textures:
        raise ctx.error("lab.textures", "expected at least one entry")
    size = _size(ctx, m["size"], "lab.size") if "size" in m else None
    margin = _number(ctx, m.get("margin", 1.5), "lab.margin", low=0.0, high=_SIZE_LIMIT)
    textured = _boolean(ctx, m.get("textured", True), "lab.textured")
    return LabSpec(textured=textured, textures=tuple(textures), size=size, margin=margin)


def _parse_person(ctx: _Ctx, obj: Any, path: str) -> PersonSpec:
    keys = ("path", "speed", "radius", "height", "loop", "phase")
    p = _mapping(ctx, obj, path, keys, ("path",))
    return PersonSpec(
        path=_points(ctx, p["path"], f"{path}.path", 2, _MAX_VERTICES),
        speed=_number(
            ctx, p.get("speed", WALKING_SPEED), f"{path}.speed", low=0.05, high=3.0, unit="m/s"
        ),
        radius=_number(ctx, p.get("radius", PERSON_RADIUS), f"{path}.radius", low=0.1, high=0.5),
        height=_number(ctx, p.get("height", PERSON_HEIGHT), f"{path}.height", low=0.5, high=2.5),
        loop=_boolean(ctx, p.get("loop", False), f"{path}.loop"),
        phase=_number(ctx, p.get("phase", 0.0), f"{path}.phase", low=0.0, high=1e6),
    )


# --------------------------------------------------------------------------------------------
# geometry: outline, walls, furniture, validation
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Outline:
    corners: FloatArray  # (V, 2) polygon corners as listed (empty for a circle)
    boundary: FloatArray  # (B, 2) counter-clockwise interior outline after corner cuts
    straight: list[tuple[FloatArray, FloatArray]]  # wall i after the cuts (V entries)
    cuts: list[tuple[int, FloatArray, FloatArray]]  # corner i's cut facet
    circle: tuple[float, float, float] | None


def _rot(points: FloatArray, yaw_deg: float) -> FloatArray:
    th = math.radians(yaw_deg)
    rot = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    return np.asarray(points @ rot.T, dtype=np.float64)


def corner_points(room: RoomSpec) -> FloatArray:
    """The corners ``(V, 2)`` [m] of a polygonal room as its walls are numbered (not a circle)."""
    c = np.array(room.center, dtype=np.float64)
    if room.shape == "polygon":
        return np.array(room.polygon, dtype=np.float64)
    if room.shape == "regular":
        n = room.n
        ang = -math.pi / 2 - math.pi / n + 2 * math.pi * np.arange(n) / n
        local = room.gv * np.column_stack([np.cos(ang), np.sin(ang)])
    else:
        w, d = (room.width, room.depth) if room.shape == "rectangle" else (room.length, room.width)
        local = np.array([[-w / 2, -d / 2], [w / 2, -d / 2], [w / 2, d / 2], [-w / 2, d / 2]])
    return c + _rot(local, room.yaw_deg)


def _polygon_problem(v: FloatArray) -> tuple[int, str] | None:
    """The first problem of a polygon as (vertex index, message), or None if it is simple."""
    n = v.shape[0]
    nxt = np.roll(v, -1, axis=0)
    edge = nxt - v
    lengths = np.hypot(*edge.T)
    for i in range(n):
        if lengths[i] < 1e-6:
            return (i + 1) % n, f"repeats vertex [{i}] (a zero-length wall)"
    for i in range(n):
        a, b = edge[i - 1], edge[i]
        cross = a[0] * b[1] - a[1] * b[0]
        if abs(cross) <= 1e-9 * lengths[i - 1] * lengths[i] and float(a @ b) < 0:
            return (
                i,
                "folds back on the wall before it (a zero-width spike: clockwise or counter-clockwise is ambiguous)",
            )
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            if segments_cross(v[i], nxt[i], v[j], nxt[j]):
                return i, (
                    f"wall {i} ([{i}] to [{(i + 1) % n}]) crosses wall {j} ([{j}] to"
                    f" [{(j + 1) % n}]); expected a simple polygon, whose orientation is clear"
                )
    area2 = float(np.sum(v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]))
    if abs(area2) <= 1e-9 * float(np.max(lengths)) ** 2:
        return -1, "zero area (collinear vertices): counter-clockwise or clockwise is ambiguous"
    return None


def _ccw(v: FloatArray) -> FloatArray:
    nxt = np.roll(v, -1, axis=0)
    area2 = float(np.sum(v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]))
    return v if area2 > 0 else v[::-1].copy()


def _outline(ctx: _Ctx, room: RoomSpec) -> _Outline:
    if room.shape == "circle":
        if room.chamfer:
            raise ctx.error("room.chamfer", "a round room has no corners to cut")
        cx, cy = room.center
        r = room.radius
        ang = -math.pi / 2 + 2 * math.pi * np.arange(_BOUNDARY_VERTICES) / _BOUNDARY_VERTICES
        boundary = np.column_stack([cx + r * np.cos(ang), cy + r * np.sin(ang)])
        return _Outline(np.zeros((0, 2)), boundary, [], [], (cx, cy, r))
    v = corner_points(room)
    n = v.shape[0]
    problem = _polygon_problem(v)
    if problem is not None:
        idx, msg = problem
        path = "room.polygon" if room.shape == "polygon" else f"room.{room.shape}"
        where = f"{path}[{idx}]" if idx >= 0 and room.shape == "polygon" else path
        raise ctx.error(where, msg)
    cuts = room.chamfer
    if len(cuts) == 1:
        cuts = cuts * n
    if cuts and len(cuts) != n:
        raise ctx.error(
            "room.chamfer", f"expected one number or {n} (one per corner), got {len(cuts)}"
        )
    c = np.array(cuts if cuts else [0.0] * n)
    nxt = np.roll(v, -1, axis=0)
    lengths = np.hypot(*(nxt - v).T)
    for i in range(n):
        if c[i] + c[(i + 1) % n] > lengths[i] - 0.05:
            raise ctx.error(
                "room.chamfer",
                f"cuts of {c[i]} m and {c[(i + 1) % n]} m at corners {i} and {(i + 1) % n} leave"
                f" less than 0.05 m of wall {i} ({lengths[i]:.3f} m long)",
            )
    unit = (nxt - v) / lengths[:, None]
    straight = [(v[i] + c[i] * unit[i], nxt[i] - c[(i + 1) % n] * unit[i]) for i in range(n)]
    verts: list[FloatArray] = []
    facets: list[tuple[int, FloatArray, FloatArray]] = []
    for i in range(n):
        if c[i] > 0:
            p_in = straight[i - 1][1]
            p_out = straight[i][0]
            verts.extend([p_in, p_out])
            facets.append((i, p_in, p_out))
        else:
            verts.append(v[i])
    cut = np.array(verts)
    if cuts:
        problem = _polygon_problem(cut)
        if problem is not None:
            raise ctx.error(
                "room.chamfer", f"the cut outline is not a simple polygon: {problem[1]}"
            )
    return _Outline(v, _ccw(cut), straight, facets, None)


def _texture_ids(n: int, seed: int | None, first: int) -> list[int]:
    if seed is None:
        return list(range(first, first + n))
    rng = np.random.default_rng([seed, 0x7E57])
    return [int(k) for k in rng.choice(TEXTURE_POOL, size=n, replace=False)]


def _texture_material(t: int | str) -> int:
    if t == "plain":
        return MATERIAL_WALL
    if t == "dark":
        return MATERIAL_DARK
    return MATERIAL_PHOTO + int(t)


@dataclass
class _Walls:
    segs: list[FloatArray] = field(default_factory=list)
    mats: list[int] = field(default_factory=list)
    heights: list[float] = field(default_factory=list)
    tex_u: list[tuple[float, float]] = field(default_factory=list)

    def add(self, a: FloatArray, b: FloatArray, mat: int, h: float, u: tuple[float, float]) -> None:
        if float(np.hypot(*(b - a))) > 1e-9:
            self.segs.append(np.concatenate([a, b]))
            self.mats.append(mat)
            self.heights.append(h)
            self.tex_u.append(u)

    def world(self) -> World:
        if not self.segs:
            return World()
        return World(
            np.array(self.segs),
            np.array(self.heights),
            np.array(self.mats),
            wall_tex_u=np.array(self.tex_u),
        )


def _door_gaps(
    ctx: _Ctx, spec: WorldSpec, outline: _Outline
) -> dict[int, list[tuple[float, float, bool, int]]]:
    """Per wall, the door gaps as (start, end) [m along the wall, or rad for a circle]."""
    gaps: dict[int, list[tuple[float, float, bool, int]]] = {}
    for i, d in enumerate(spec.doors):
        path = f"doors[{i}]"
        if outline.circle is not None:
            r = outline.circle[2]
            if d.wall != 0:
                raise ctx.error(f"{path}.wall", f"a round room has one wall, 0; got {d.wall}")
            if d.width > r:
                raise ctx.error(
                    f"{path}.width",
                    f"{d.width} m is too wide for a round wall of radius {r} m (at most the radius)",
                )
            phi = -math.pi / 2 + 2 * math.pi * d.at
            half = math.asin(d.width / (2 * r))
            gaps.setdefault(0, []).append((phi - half, phi + half, d.open, i))
            continue
        n = outline.corners.shape[0]
        if d.wall >= n:
            raise ctx.error(f"{path}.wall", f"expected a wall index in [0, {n - 1}], got {d.wall}")
        a = outline.corners[d.wall]
        b = outline.corners[(d.wall + 1) % n]
        length = float(np.hypot(*(b - a)))
        sa, sb = outline.straight[d.wall]
        lo_ok = float(np.hypot(*(sa - a)))
        hi_ok = float(np.hypot(*(sb - a)))
        if d.width >= hi_ok - lo_ok - 0.02:
            raise ctx.error(
                f"{path}.width",
                f"a door of {d.width} m is wider than wall {d.wall} ({hi_ok - lo_ok:.3f} m of"
                " straight wall); expected a narrower door",
            )
        s0 = d.at * length - d.width / 2
        s1 = d.at * length + d.width / 2
        if s0 < lo_ok + 0.01 or s1 > hi_ok - 0.01:
            raise ctx.error(
                f"{path}.at",
                f"a door of {d.width} m centred at {d.at} of wall {d.wall} ({length:.3f} m) runs"
                " past the wall's end or corner cut; expected it to fit on the wall",
            )
        gaps.setdefault(d.wall, []).append((s0, s1, d.open, i))
    for wall, items in gaps.items():
        items.sort()
        for (_a0, a1, _, i), (b0, _b1, _, j) in itertools.pairwise(items):
            if b0 < a1 + 0.01:
                raise ctx.error(
                    f"doors[{max(i, j)}]", f"overlaps doors[{min(i, j)}] on wall {wall}"
                )
    return gaps


def _wall_materials(
    ctx: _Ctx, spec: WorldSpec, outline: _Outline, n_tiles: int
) -> tuple[list[int], list[int]]:
    """Materials of the walls (or round-wall tiles) and of the corner-cut facets."""
    n = n_tiles if outline.circle is not None else outline.corners.shape[0]
    n_cuts = len(outline.cuts)
    if spec.room.in_lab:
        return [MATERIAL_BOARD] * n, [MATERIAL_BOARD] * n_cuts
    lab_spec = spec.lab
    if lab_spec.textures:
        if outline.circle is None and len(lab_spec.textures) != n:
            raise ctx.error(
                "lab.textures",
                f"expected {n} entries (one per wall of the room), got {len(lab_spec.textures)}",
            )
        return [_texture_material(t) for t in lab_spec.textures], [MATERIAL_WALL] * n_cuts
    if not lab_spec.textured:
        return [MATERIAL_WALL] * n, [MATERIAL_WALL] * n_cuts
    ids = _texture_ids(n + n_cuts, spec.seed, 0)
    mats = [MATERIAL_PHOTO + k for k in ids]
    return mats[:n], mats[n:]


def _polygon_walls(
    ctx: _Ctx,
    spec: WorldSpec,
    outline: _Outline,
    gaps: dict[int, list[tuple[float, float, bool, int]]],
) -> _Walls:
    h = spec.room.wall_height
    mats, cut_mats = _wall_materials(ctx, spec, outline, 0)
    leaf_h = min(h, DOOR_HEIGHT)
    out = _Walls()
    n = outline.corners.shape[0]
    for i in range(n):
        a = outline.corners[i]
        b = outline.corners[(i + 1) % n]
        length = float(np.hypot(*(b - a)))
        unit = (b - a) / length
        sa, sb = outline.straight[i]
        s = float(np.hypot(*(sa - a)))
        end = float(np.hypot(*(sb - a)))
        for g0, g1, is_open, _ in gaps.get(i, []):
            out.add(a + s * unit, a + g0 * unit, mats[i], h, (s / length, g0 / length))
            if not is_open:
                out.add(a + g0 * unit, a + g1 * unit, MATERIAL_FURNITURE, leaf_h, (0.0, 1.0))
            s = g1
        out.add(a + s * unit, a + end * unit, mats[i], h, (s / length, end / length))
    for (_, p_in, p_out), m in zip(outline.cuts, cut_mats, strict=True):
        out.add(p_in, p_out, m, h, (0.0, 1.0))
    return out


def _circle_walls(
    ctx: _Ctx,
    spec: WorldSpec,
    outline: _Outline,
    gaps: dict[int, list[tuple[float, float, bool, int]]],
) -> World:
    assert outline.circle is not None
    cx, cy, r = outline.circle
    h = spec.room.wall_height
    explicit = bool(spec.lab.textures) and not spec.room.in_lab
    if not gaps and not explicit:
        mats, _ = _wall_materials(ctx, spec, outline, 1)
        return World(circles=np.array([[cx, cy, r]]), circle_heights=h, circle_materials=mats[0])
    n_tiles = len(spec.lab.textures) if explicit else max(1, round(2 * math.pi * r / h))
    mats, _ = _wall_materials(ctx, spec, outline, n_tiles)
    start = -math.pi / 2
    step = 2 * math.acos(max(-1.0, 1.0 - _CIRCLE_SAGITTA / r))
    k = max(64, math.ceil(2 * math.pi / step))
    breaks = [
        start + 2 * math.pi * np.arange(k + 1) / k,
        start + 2 * math.pi * np.arange(n_tiles + 1) / n_tiles,
    ]
    door_list = gaps.get(0, [])
    for g0, g1, _, _ in door_list:
        breaks.append(np.mod(np.array([g0, g1]) - start, 2 * math.pi) + start)
    th = np.unique(np.round(np.concatenate(breaks), 12))
    leaf_h = min(h, DOOR_HEIGHT)
    out = _Walls()
    tile_angle = 2 * math.pi / n_tiles
    for t0, t1 in itertools.pairwise(th):
        mid = 0.5 * (t0 + t1)
        if any(np.mod(mid - g0, 2 * math.pi) < (g1 - g0) for g0, g1, _, _ in door_list):
            continue
        tile = min(int((mid - start) // tile_angle), n_tiles - 1)
        u0 = (t0 - start) / tile_angle - tile
        u1 = (t1 - start) / tile_angle - tile
        a = np.array([cx + r * math.cos(t0), cy + r * math.sin(t0)])
        b = np.array([cx + r * math.cos(t1), cy + r * math.sin(t1)])
        out.add(a, b, mats[tile], h, (u0, u1))
    for g0, g1, is_open, _ in door_list:
        if not is_open:
            a = np.array([cx + r * math.cos(g0), cy + r * math.sin(g0)])
            b = np.array([cx + r * math.cos(g1), cy + r * math.sin(g1)])
            out.add(a, b, MATERIAL_FURNITURE, leaf_h, (0.0, 1.0))
    return out.world()


@dataclass(frozen=True)
class _Solid:
    path: str
    polygon: FloatArray | None  # filled polygon (box)
    circle: tuple[float, float, float] | None  # filled circle
    segment: FloatArray | None  # a thin panel (4,)

    def outline_points(self) -> FloatArray:
        if self.polygon is not None:
            return self.polygon
        if self.circle is not None:
            cx, cy, r = self.circle
            ang = 2 * math.pi * np.arange(32) / 32
            return np.column_stack([cx + r * np.cos(ang), cy + r * np.sin(ang)])
        assert self.segment is not None
        return self.segment.reshape(2, 2)

    def world(self) -> World:
        if self.circle is not None:
            return World(circles=np.array([self.circle]))
        if self.polygon is not None:
            p = self.polygon
            return World(np.column_stack([p, np.roll(p, -1, axis=0)]))
        assert self.segment is not None
        return World(self.segment[None])

    def contains(self, pts: FloatArray) -> NDArray[np.bool_]:
        if self.polygon is not None:
            return points_in_polygon(pts, self.polygon)
        if self.circle is not None:
            cx, cy, r = self.circle
            return np.asarray(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) < r)
        return np.zeros(pts.shape[0], dtype=bool)


def _gap(a: _Solid, b: _Solid) -> float:
    """Clearance [m] between two solids (<= 0 when they overlap)."""
    if np.any(a.contains(b.outline_points())) or np.any(b.contains(a.outline_points())):
        return -1.0
    if a.circle is not None and b.circle is not None:
        return float(
            math.hypot(a.circle[0] - b.circle[0], a.circle[1] - b.circle[1])
            - a.circle[2]
            - b.circle[2]
        )
    if a.circle is not None:
        a, b = b, a
    wa = a.world()
    if b.circle is not None:
        return float(wa.distance(np.array(b.circle[:2])[None])[0] - b.circle[2])
    wb = b.world()
    for sa in wa.walls:
        for sb in wb.walls:
            if segments_cross(sa[:2], sa[2:], sb[:2], sb[2:]):
                return 0.0
    return float(min(wa.distance(b.outline_points()).min(), wb.distance(a.outline_points()).min()))


def _solids(spec: WorldSpec) -> list[_Solid]:
    out: list[_Solid] = []
    for group, items in (("furniture", spec.furniture), ("pillars", spec.pillars)):
        for i, f in enumerate(items):
            path = f"{group}[{i}]" + (f".{f.kind}" if group == "furniture" else "")
            if f.kind == "box":
                out.append(_Solid(path, f.footprint(), None, None))
            else:
                out.append(_Solid(path, None, (f.center[0], f.center[1], f.radius), None))
    for i, g in enumerate(spec.glass):
        out.append(_Solid(f"glass[{i}]", None, None, np.array([*g.start, *g.end])))
    return out


def _check_solids(ctx: _Ctx, solids: list[_Solid], outline: _Outline, room_walls: World) -> None:
    corners = _wall_points(room_walls)
    for s in solids:
        pts = s.outline_points()
        inside = bool(np.all(points_in_polygon(pts, outline.boundary)))
        if s.circle is not None:
            gap = float(room_walls.distance(np.array(s.circle[:2])[None])[0] - s.circle[2])
        else:
            gap = float(room_walls.distance(pts).min())
            if corners.shape[0]:
                gap = min(gap, float(s.world().distance(corners).min()))
            for w in room_walls.walls:
                if any(segments_cross(a, b, w[:2], w[2:]) for a, b in _edges(s)):
                    gap = 0.0
        if not inside or gap < _MIN_GAP:
            raise ctx.error(
                s.path,
                f"lies outside the room or within {_MIN_GAP} m of its walls (clearance"
                f" {max(gap, 0.0):.3f} m); expected it inside the room",
            )
    for i, a in enumerate(solids):
        for b in solids[:i]:
            if _gap(a, b) < _MIN_GAP:
                raise ctx.error(a.path, f"overlaps {b.path} (or is within {_MIN_GAP} m of it)")


def _wall_points(w: World) -> FloatArray:
    pts = [w.walls[:, :2], w.walls[:, 2:]]
    return np.concatenate(pts) if w.n_walls else np.zeros((0, 2))


def _edges(s: _Solid) -> list[tuple[FloatArray, FloatArray]]:
    if s.polygon is not None:
        p = s.polygon
        return [(p[i], p[(i + 1) % len(p)]) for i in range(len(p))]
    if s.segment is not None:
        return [(s.segment[:2], s.segment[2:])]
    return []


def _solid_world(spec: WorldSpec) -> World:
    parts: list[World] = []
    for f in (*spec.furniture, *spec.pillars):
        mat = MATERIALS[f.material]
        if f.kind == "box":
            p = f.footprint()
            parts.append(World(np.column_stack([p, np.roll(p, -1, axis=0)]), f.height, mat))
        else:
            parts.append(
                World(
                    circles=np.array([[*f.center, f.radius]]),
                    circle_heights=f.height,
                    circle_materials=mat,
                )
            )
    for g in spec.glass:
        parts.append(World(np.array([[*g.start, *g.end]]), g.height, MATERIAL_GLASS))
    return World.merge(parts)


def _area_centroid(v: FloatArray) -> FloatArray:
    nxt = np.roll(v, -1, axis=0)
    cross = v[:, 0] * nxt[:, 1] - nxt[:, 0] * v[:, 1]
    a = cross.sum() / 2.0
    return np.array(
        [
            np.sum((v[:, 0] + nxt[:, 0]) * cross) / (6 * a),
            np.sum((v[:, 1] + nxt[:, 1]) * cross) / (6 * a),
        ]
    )


def _lab_world(ctx: _Ctx, spec: WorldSpec, boundary: FloatArray, center: FloatArray) -> World:
    ls = spec.lab
    w0, d0 = ls.size if ls.size is not None else (8.0, 10.0)
    xmin, ymin = boundary.min(axis=0)
    xmax, ymax = boundary.max(axis=0)
    # centred on the room: it must clear the room by the margin on both sides
    half_w = max(w0 / 2, center[0] - xmin + ls.margin, xmax - center[0] + ls.margin)
    half_d = max(d0 / 2, center[1] - ymin + ls.margin, ymax - center[1] + ls.margin)
    n_seg = len(ls.textures) if ls.textures else 12
    if n_seg < 4:
        raise ctx.error(
            "lab.textures", f"a lab has at least 4 walls; expected >= 4 entries, got {n_seg}"
        )
    geo = lab(
        2 * half_w, 2 * half_d, center=center, n_segments=n_seg, height=WALL_HEIGHT, textured=False
    )
    if ls.textures:
        mats = [_texture_material(t) for t in ls.textures]
    elif ls.textured:
        mats = [MATERIAL_PHOTO + k for k in _texture_ids(n_seg, spec.seed, 1)]
    else:
        mats = [MATERIAL_WALL] * n_seg
    return World(geo.walls, WALL_HEIGHT, np.array(mats))


def _check_lab_keys(ctx: _Ctx, spec: WorldSpec) -> None:
    if not spec.room.in_lab and (spec.lab.size is not None or spec.lab.margin != 1.5):
        raise ctx.error(
            "lab.size" if spec.lab.size is not None else "lab.margin",
            f"only used for a room of boards (room.wall_height < {LAB_WALL_HEIGHT} m) inside a lab",
        )


_KIND = {
    "regular": "polygon",
    "polygon": "polygon",
    "circle": "circle",
    "rectangle": "rectangle",
    "corridor": "corridor",
}


def _assemble(spec: WorldSpec) -> Room:
    """Validate ``spec`` and assemble its Room (orders not yet computed: 1, symmetry None)."""
    ctx = _Ctx(spec.source)
    _check_lab_keys(ctx, spec)
    outline = _outline(ctx, spec.room)
    gaps = _door_gaps(ctx, spec, outline)
    if outline.circle is None:
        room_world = _polygon_walls(ctx, spec, outline, gaps).world()
    else:
        room_world = _circle_walls(ctx, spec, outline, gaps)
    if spec.room.in_lab and spec.lab.textures and len(spec.lab.textures) < 4:
        raise ctx.error(
            "lab.textures",
            f"a lab has at least 4 walls; expected >= 4 entries, got {len(spec.lab.textures)}",
        )
    solids = _solids(spec)
    bare = _bare_walls(outline)
    _check_solids(ctx, solids, outline, bare)
    boundary = outline.boundary
    center = _area_centroid(boundary) if outline.circle is None else np.array(outline.circle[:2])
    parts = [room_world, _solid_world(spec)]
    if spec.room.in_lab:
        parts.append(_lab_world(ctx, spec, boundary, center))
    world = World.merge(parts)
    for i, p in enumerate(spec.people):
        for j in range(1, len(p.path) + (1 if p.loop else 0)):
            if math.dist(p.path[j - 1], p.path[j % len(p.path)]) < 1e-6:
                raise ctx.error(
                    f"people[{i}].path[{j % len(p.path)}]", "repeats the point before it"
                )
    people = tuple(p.person() for p in spec.people)
    obstacles = tuple(f.footprint() for f in (*spec.furniture, *spec.pillars) if f.kind == "box")
    circles = [
        [*f.center, f.radius] for f in (*spec.furniture, *spec.pillars) if f.kind == "cylinder"
    ]
    regular = spec.room.shape in ("regular", "circle") and not spec.room.chamfer
    if spec.room.shape == "rectangle":
        regular = math.isclose(spec.room.width, spec.room.depth) and not spec.room.chamfer
    room = Room(
        name=spec.name,
        kind=_KIND[spec.room.shape],
        world=world,
        boundary=boundary,
        corners=boundary.copy() if outline.circle is None else np.zeros((0, 2)),
        center=center,
        gv_distance=float(np.max(np.hypot(*(boundary - center).T))),
        shape_order=1,
        order=1,
        regular=regular,
        door=any(d.open for d in spec.doors),
        n_furniture=len(spec.furniture),
        wall_height=spec.room.wall_height,
        room_world=room_world,
        people=people,
        obstacles=obstacles,
        obstacle_circles=np.array(circles, dtype=np.float64).reshape(-1, 3),
    )
    _check_people(ctx, spec, room)
    return room


def _bare_walls(outline: _Outline) -> World:
    if outline.circle is not None:
        return World(circles=np.array([outline.circle]))
    b = outline.boundary
    return World(np.column_stack([b, np.roll(b, -1, axis=0)]))


def _check_people(ctx: _Ctx, spec: WorldSpec, room: Room) -> None:
    for i, p in enumerate(spec.people):
        pts = np.array(p.path, dtype=np.float64)
        closed = np.vstack([pts, pts[:1]]) if p.loop else pts
        for j in range(closed.shape[0] - 1):
            a, b = closed[j], closed[j + 1]
            length = float(np.hypot(*(b - a)))
            if length < 1e-6:
                raise ctx.error(
                    f"people[{i}].path[{(j + 1) % len(pts)}]", "repeats the point before it"
                )
            t = np.linspace(0.0, 1.0, max(2, math.ceil(length / 0.05) + 1))
            ok = room.is_free(a + t[:, None] * (b - a), p.radius)
            if not np.all(ok):
                raise ctx.error(
                    f"people[{i}].path[{j}]",
                    f"the leg to point [{(j + 1) % len(pts)}] leaves the room or passes within"
                    f" {p.radius} m (the person's radius) of a wall or obstacle",
                )


# --------------------------------------------------------------------------------------------
# the project's named rooms as world files
# --------------------------------------------------------------------------------------------


def room_spec(
    name: str,
    gv: float,
    *,
    lab: bool = True,
    textured: bool = True,
    door: bool = False,
    board_height: float = BOARD_HEIGHT,
) -> WorldSpec:
    """The world file of ``symloc.sim.rooms.build_room(name, gv, ...)`` (no furniture).

    Builds the same walls, materials and lab, so any of the named rooms can be written out
    with :func:`save_world_file` and edited.
    """
    key = str(name).lower().replace("-", "_")
    if key not in ROOM_NAMES:
        raise WorldError(
            f"room_spec: unknown room name {name!r}; expected one of {', '.join(ROOM_NAMES)}"
        )
    h = board_height if lab else WALL_HEIGHT
    sides = {"triangle": 3, "square": 4, "pentagon": 5, "hexagon": 6, "octagon": 8}
    doors: tuple[DoorSpec, ...] = ()
    if key in sides:
        room = RoomSpec("regular", n=sides[key], gv=gv, wall_height=h)
        edge = 2 * gv * math.sin(math.pi / sides[key])
    elif key == "circle":
        room = RoomSpec("circle", radius=gv, wall_height=h)
        edge = gv
    elif key in ("rectangle", "hallway"):
        aspect = RECTANGLE_ASPECT if key == "rectangle" else HALLWAY_ASPECT
        d = 2 * gv / math.hypot(aspect, 1.0)
        if key == "rectangle":
            room = RoomSpec("rectangle", width=aspect * d, depth=d, wall_height=h)
        else:
            room = RoomSpec("corridor", length=aspect * d, width=d, wall_height=h)
        edge = aspect * d
    else:
        unit = l_shaped_room(1.0)
        ell = l_shaped_room(gv / unit.gv_distance)
        room = RoomSpec(
            "polygon", polygon=tuple((float(x), float(y)) for x, y in ell.boundary), wall_height=h
        )
        edge = float(np.hypot(*(ell.boundary[1] - ell.boundary[0])))
    if door:
        width = DOOR_WIDTH if 0.8 * edge > DOOR_WIDTH else 0.4 * edge
        doors = (DoorSpec(wall=0, at=0.0 if key == "circle" else 0.5, width=width, open=True),)
    return WorldSpec(
        name=key,
        room=room,
        doors=doors,
        lab=LabSpec(textured=textured),
        description=f"symloc.sim.rooms.build_room({key!r}, {gv}, lab={lab}) as a world file",
    )
