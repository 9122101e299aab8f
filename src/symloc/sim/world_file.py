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
- ``metadata: {key: value}``: free notes about the world (numbers, strings, booleans), e.g. what
  a generator family records of its worlds (the ``furnished`` family: the base order and how
  much of the map overlaps itself under it); ignored when building.

Every error is a :class:`~symloc.errors.WorldError` whose message names the file, the key path
(``room.polygon[3]``, ``furniture[1].box.size``) and what was expected.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from symloc.errors import WorldError
from symloc.files.atomic import atomic_write_text
from symloc.files.bounded import load_yaml_bounded, read_text_bounded
from symloc.sim.people import PERSON_HEIGHT, PERSON_RADIUS, WALKING_SPEED
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
)
from symloc.sim.symmetry_truth import lidar_symmetry
from symloc.sim.world_build import assemble, bare_outline
from symloc.sim.world_spec import (
    GLASS_HEIGHT,
    MATERIALS,
    PILLAR_HEIGHT,
    ROOM_SHAPES,
    DoorSpec,
    ErrorContext,
    FurnitureSpec,
    GlassSpec,
    LabSpec,
    PersonSpec,
    RoomSpec,
)

__all__ = ["MetaValue", "WorldSpec", "load_world_file", "room_spec", "save_world_file"]

FloatArray = NDArray[np.float64]
Point = tuple[float, float]
MetaValue = bool | int | float | str
"""A value of :attr:`WorldSpec.metadata`."""

_COORD_LIMIT = 1000.0  # |x|, |y| [m]
_SIZE_LIMIT = 1000.0  # sizes [m]
_MAX_VERTICES = 200
_MAX_ITEMS = 200
#: Largest world file read [bytes]: far more than 200 vertices and 200 items of each kind need,
#: so a file of a million vertices is refused before it is parsed.
MAX_WORLD_FILE_BYTES = 2**20

# --------------------------------------------------------------------------------------------
# reading: small checks that name the key path
# --------------------------------------------------------------------------------------------


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _mapping(
    ctx: ErrorContext, obj: Any, path: str, allowed: tuple[str, ...], required: tuple[str, ...] = ()
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
    ctx: ErrorContext,
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


def _integer(ctx: ErrorContext, obj: Any, path: str, low: int, high: int) -> int:
    if isinstance(obj, bool) or not isinstance(obj, int) or not low <= obj <= high:
        raise ctx.error(path, f"expected an integer in [{low}, {high}], got {_show(obj)}")
    return int(obj)


def _boolean(ctx: ErrorContext, obj: Any, path: str) -> bool:
    if not isinstance(obj, bool):
        raise ctx.error(path, f"expected true or false, got {_show(obj)}")
    return obj


def _string(ctx: ErrorContext, obj: Any, path: str) -> str:
    if not isinstance(obj, str):
        raise ctx.error(path, f"expected a string, got {_show(obj)}")
    return obj


def _list(ctx: ErrorContext, obj: Any, path: str, what: str, max_n: int = _MAX_ITEMS) -> list[Any]:
    if not isinstance(obj, list):
        raise ctx.error(path, f"expected a list of {what}, got {_show(obj)}")
    if len(obj) > max_n:
        raise ctx.error(path, f"expected at most {max_n} {what}, got {len(obj)}")
    return obj


def _point(ctx: ErrorContext, obj: Any, path: str) -> Point:
    if not isinstance(obj, list) or len(obj) != 2:
        raise ctx.error(path, f"expected a point [x, y] in metres, got {_show(obj)}")
    lim = _COORD_LIMIT
    return (
        _number(ctx, obj[0], f"{path}[0]", low=-lim, high=lim),
        _number(ctx, obj[1], f"{path}[1]", low=-lim, high=lim),
    )


def _size(ctx: ErrorContext, obj: Any, path: str) -> Point:
    if not isinstance(obj, list) or len(obj) != 2:
        raise ctx.error(path, f"expected a size [width, depth] in metres, got {_show(obj)}")
    return (
        _number(ctx, obj[0], f"{path}[0]", low=0.01, high=_SIZE_LIMIT),
        _number(ctx, obj[1], f"{path}[1]", low=0.01, high=_SIZE_LIMIT),
    )


def _points(ctx: ErrorContext, obj: Any, path: str, min_n: int, max_n: int) -> tuple[Point, ...]:
    items = _list(ctx, obj, path, "[x, y] points", max_n)
    if len(items) < min_n:
        raise ctx.error(path, f"expected at least {min_n} [x, y] points, got {len(items)}")
    return tuple(_point(ctx, p, f"{path}[{i}]") for i, p in enumerate(items))


# --------------------------------------------------------------------------------------------
# the spec
# --------------------------------------------------------------------------------------------


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
    metadata: tuple[tuple[str, MetaValue], ...] = ()
    source: str = field(default="<world>", compare=False)

    def __post_init__(self) -> None:
        assemble(self)

    @property
    def meta(self) -> dict[str, MetaValue]:
        """``metadata`` as a dict (key -> number, string or boolean)."""
        return dict(self.metadata)

    @staticmethod
    def from_dict(doc: Any, source: str = "<dict>") -> WorldSpec:
        """Parse and validate a world document (the mapping a YAML file holds)."""
        return _parse(doc, ErrorContext(source))

    def to_dict(self) -> dict[str, Any]:
        """The world document (plain dicts, lists and numbers); ``from_dict`` reads it back."""
        out: dict[str, Any] = {"name": self.name}
        if self.description:
            out["description"] = self.description
        if self.generator is not None:
            out["generator"] = {"family": self.generator[0], "seed": self.generator[1]}
        if self.metadata:
            out["metadata"] = dict(self.metadata)
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

        room = assemble(self)
        truth = lidar_symmetry(room.world, room.boundary)
        center = truth.center if truth.order != 1 else room.center
        gv = float(np.max(np.hypot(*(room.boundary - center).T)))
        shape = lidar_symmetry(bare_outline(self)).order
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
    # a regular file of bounded size and nesting: parsed whole before any limit applies
    text = read_text_bounded(p, MAX_WORLD_FILE_BYTES, what="the world file", error=WorldError)
    doc = load_yaml_bounded(text, where=str(p), error=WorldError)
    return WorldSpec.from_dict(doc, str(p))


def save_world_file(spec: WorldSpec, path: str | Path, *, header: str = "") -> Path:
    """Write ``spec`` as YAML (``header`` lines become comments at the top); returns the path."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    lines = "".join(f"# {line}\n" for line in header.splitlines())
    atomic_write_text(p, lines + spec.to_yaml())
    return p


# --------------------------------------------------------------------------------------------
# parsing
# --------------------------------------------------------------------------------------------

_TOP_KEYS = (
    "name",
    "description",
    "seed",
    "generator",
    "metadata",
    "room",
    "furniture",
    "pillars",
    "glass",
    "doors",
    "lab",
    "people",
)


def _parse(doc: Any, ctx: ErrorContext) -> WorldSpec:
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
    metadata = _parse_metadata(ctx, top.get("metadata", {}))
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
        metadata=metadata,
        source=ctx.source,
    )


def _parse_metadata(ctx: ErrorContext, obj: Any) -> tuple[tuple[str, MetaValue], ...]:
    if not isinstance(obj, Mapping):
        raise ctx.error("metadata", f"expected a mapping of names to values, got {_show(obj)}")
    out: list[tuple[str, MetaValue]] = []
    for key, value in obj.items():
        if not isinstance(key, str):
            raise ctx.error(f"metadata.{key}", "expected a string key")
        ok = isinstance(value, (bool, int, str)) or (
            isinstance(value, float) and math.isfinite(value)
        )
        if not ok:
            raise ctx.error(
                f"metadata.{key}", f"expected a number, a string or true/false, got {_show(value)}"
            )
        out.append((key, value))
    return tuple(out)


def _parse_room(ctx: ErrorContext, obj: Any) -> RoomSpec:
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


def _material(ctx: ErrorContext, obj: Any, path: str) -> str:
    name = _string(ctx, obj, path)
    if name not in MATERIALS:
        raise ctx.error(path, f"expected one of {', '.join(MATERIALS)}, got {_show(obj)}")
    return name


def _parse_solid(
    ctx: ErrorContext, body: dict[str, Any], path: str, kind: str, height: float, material: str
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


def _parse_furniture(ctx: ErrorContext, obj: Any, path: str) -> FurnitureSpec:
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


def _parse_pillar(ctx: ErrorContext, obj: Any, path: str) -> FurnitureSpec:
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


def _parse_glass(ctx: ErrorContext, obj: Any, path: str) -> GlassSpec:
    g = _mapping(ctx, obj, path, ("from", "to", "height"), ("from", "to"))
    h = GLASS_HEIGHT
    if "height" in g:
        h = _number(ctx, g["height"], f"{path}.height", low=0.0, high=100.0, low_open=True)
    a = _point(ctx, g["from"], f"{path}.from")
    b = _point(ctx, g["to"], f"{path}.to")
    if math.hypot(b[0] - a[0], b[1] - a[1]) < 0.05:
        raise ctx.error(path, "expected a panel at least 0.05 m long (from and to coincide)")
    return GlassSpec(a, b, h)


def _parse_door(ctx: ErrorContext, obj: Any, path: str) -> DoorSpec:
    d = _mapping(ctx, obj, path, ("wall", "at", "width", "open"), ("wall",))
    return DoorSpec(
        wall=_integer(ctx, d["wall"], f"{path}.wall", 0, _MAX_VERTICES * 2),
        at=_number(ctx, d.get("at", 0.5), f"{path}.at", low=0.0, high=1.0, unit="fraction"),
        width=_number(ctx, d.get("width", 0.9), f"{path}.width", low=0.05, high=_SIZE_LIMIT),
        open=_boolean(ctx, d.get("open", True), f"{path}.open"),
    )


def _parse_lab(ctx: ErrorContext, obj: Any) -> LabSpec:
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


def _parse_person(ctx: ErrorContext, obj: Any, path: str) -> PersonSpec:
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
