"""World files: loading, validation (every error path names the key), round trips, building."""

from __future__ import annotations

import copy
import math
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from symloc.errors import WorldError
from symloc.sim.rooms import ROOM_NAMES, build_room
from symloc.sim.world import (
    MATERIAL_BOARD,
    MATERIAL_DARK,
    MATERIAL_FURNITURE,
    MATERIAL_GLASS,
    MATERIAL_PHOTO,
    MATERIAL_WALL,
)
from symloc.sim.world_file import WorldSpec, load_world_file, room_spec, save_world_file
from symloc.sim.world_spec import TEXTURE_POOL

ISSUE_EXAMPLE = """\
name: square-with-box
room:                      # one of: polygon | regular | circle | rectangle
  polygon: [[-2, -2], [2, -2], [2, 2], [-2, 2]]   # metres, counter-clockwise
  # regular: {n: 8, gv: 3.0}   circle: {radius: 3.0}   rectangle: {width: 4, depth: 2}
  wall_height: 2.0
furniture:                 # optional; each seen by the lidar only if taller than its plane
  - box: {center: [1.45, 0.0], size: [0.5, 0.5], yaw_deg: 0, height: 0.8}
  - cylinder: {center: [0.0, 1.0], radius: 0.2, height: 1.0}
doors: [{wall: 0, at: 0.5, width: 0.9, open: true}]   # optional
lab: textured              # textured | untextured | {textures: [...]} per wall direction
"""


def _doc() -> dict[str, Any]:
    return dict(yaml.safe_load(ISSUE_EXAMPLE))


def _write(tmp_path: Path, text: str, name: str = "w.yaml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def test_issue_example_loads_and_builds(tmp_path: Path) -> None:
    spec = load_world_file(_write(tmp_path, ISSUE_EXAMPLE))
    assert spec.name == "square-with-box"
    assert spec.room.shape == "polygon"
    assert spec.room.wall_height == 2.0
    assert [f.kind for f in spec.furniture] == ["box", "cylinder"]
    room = spec.build()
    assert room.order == 1  # door and box
    assert room.shape_order == 4
    assert room.door
    assert room.n_furniture == 2
    assert room.world.n_circles == 1
    # the door is a 0.9 m gap in the middle of wall 0 (y = -2)
    assert room.world.distance(np.array([[0.0, -2.0]]))[0] == pytest.approx(0.45)
    # textured tall walls: wall 0's two pieces share one texture
    mats = np.asarray(room.world.wall_materials)
    photo = mats >= MATERIAL_PHOTO
    assert photo.sum() == 5
    assert len(set(mats[photo].tolist())) == 4


def test_round_trip_through_yaml(tmp_path: Path) -> None:
    doc = _doc()
    doc["seed"] = 11
    doc["room"]["chamfer"] = [0.1, 0.0, 0.2, 0.0]
    doc["pillars"] = [
        {"center": [-1.0, 1.0], "radius": 0.15},
        {"center": [-1.0, -1.0], "size": [0.3, 0.3], "yaw_deg": 45},
    ]
    doc["glass"] = [{"from": [-0.5, 1.5], "to": [0.5, 1.5], "height": 1.8}]
    doc["people"] = [
        {"path": [[-1.5, 0.0], [-0.5, 0.0], [-0.5, -0.4]], "speed": 1.1, "loop": True, "phase": 0.5}
    ]
    doc["lab"] = {"textures": [3, 3, "dark", 7]}
    spec = WorldSpec.from_dict(doc, "doc")
    path = save_world_file(spec, tmp_path / "out" / "w.yaml", header="a header\nline two")
    text = path.read_text()
    assert text.startswith("# a header\n# line two\n")
    again = load_world_file(path)
    assert again == spec
    assert again.to_dict() == spec.to_dict()
    a, b = spec.build(), again.build()
    assert np.array_equal(a.world.walls, b.world.walls)
    assert np.array_equal(a.world.wall_materials, b.world.wall_materials)


def test_explicit_textures_alias_and_dark() -> None:
    doc = _doc()
    doc["lab"] = {"textures": [5, 5, "dark", "plain"]}
    room = WorldSpec.from_dict(doc).build()
    mats = np.asarray(room.world.wall_materials)
    walls = room.world.walls
    bottom = mats[np.isclose(walls[:, 1], -2) & np.isclose(walls[:, 3], -2)]
    right = mats[np.isclose(walls[:, 0], 2) & np.isclose(walls[:, 2], 2)]
    assert set(bottom.tolist()) == {MATERIAL_PHOTO + 5}
    assert set(right.tolist()) == {MATERIAL_PHOTO + 5}
    assert MATERIAL_DARK in mats
    assert MATERIAL_WALL in mats


def test_seed_picks_distinct_textures() -> None:
    doc = _doc()
    doc["room"] = {"regular": {"n": 8, "gv": 3.0}}
    doc.pop("doors")
    doc.pop("furniture")
    a = WorldSpec.from_dict({**doc, "seed": 1}).build()
    b = WorldSpec.from_dict({**doc, "seed": 2}).build()
    ma, mb = np.asarray(a.world.wall_materials), np.asarray(b.world.wall_materials)
    assert len(set(ma.tolist())) == 8
    assert not np.array_equal(ma, mb)
    assert np.all((ma >= MATERIAL_PHOTO) & (ma < MATERIAL_PHOTO + TEXTURE_POOL))
    plain = WorldSpec.from_dict({**doc, "lab": "untextured"}).build()
    assert set(np.asarray(plain.world.wall_materials).tolist()) == {MATERIAL_WALL}


def test_boards_stand_in_a_lab() -> None:
    doc = {"name": "b", "room": {"rectangle": {"width": 3, "depth": 2}, "wall_height": 0.4}}
    room = WorldSpec.from_dict(doc).build()
    mats = np.asarray(room.world.wall_materials)
    assert np.sum(mats == MATERIAL_BOARD) == 4
    assert np.sum(mats >= MATERIAL_PHOTO) == 12
    assert room.wall_height == 0.4
    assert room.order == 2
    doc["lab"] = {"textures": [1, 2, 3, 4, 5, 6], "size": [12, 12], "margin": 2.0}
    room = WorldSpec.from_dict(doc).build()
    lab_walls = room.world.walls[np.asarray(room.world.wall_materials) >= MATERIAL_PHOTO]
    assert lab_walls.shape[0] == 6
    assert np.ptp(lab_walls[:, [0, 2]]) == pytest.approx(12.0)


def test_closed_door_glass_and_materials() -> None:
    doc = _doc()
    doc["doors"] = [{"wall": 1, "at": 0.5, "width": 0.9, "open": False}]
    doc["glass"] = [{"from": [-1.0, -1.5], "to": [0.0, -1.5]}]
    doc["furniture"] = [{"box": {"center": [1.0, 1.0], "size": [0.4, 0.4], "material": "dark"}}]
    room = WorldSpec.from_dict(doc).build()
    mats = np.asarray(room.world.wall_materials)
    assert np.sum(mats == MATERIAL_FURNITURE) == 1  # the leaf
    assert np.sum(mats == MATERIAL_GLASS) == 1
    assert np.sum(mats == MATERIAL_DARK) == 4
    assert not room.door
    assert room.order == 1


@pytest.mark.parametrize("name", ROOM_NAMES)
@pytest.mark.parametrize("lab", [False, True])
def test_named_rooms_are_world_files(name: str, lab: bool) -> None:
    a = build_room(name, 3.0, lab=lab)
    b = room_spec(name, 3.0, lab=lab).build()
    for attr in (
        "walls",
        "wall_heights",
        "wall_materials",
        "circles",
        "circle_materials",
        "wall_tex_u",
    ):
        assert np.allclose(
            np.asarray(getattr(a.world, attr)), np.asarray(getattr(b.world, attr))
        ), attr
    assert (a.order, a.shape_order) == (b.order, b.shape_order)
    assert np.allclose(a.center, b.center, atol=1e-9)
    assert a.gv_distance == pytest.approx(b.gv_distance)
    door = room_spec(name, 3.0, lab=lab, door=True).build()
    assert door.order == 1
    assert door.door
    if name != "circle":  # same gap; the round wall's facets differ
        assert np.allclose(build_room(name, 3.0, lab=lab, door=True).world.walls, door.world.walls)


def test_packaged_examples_load_and_build() -> None:
    folder = resources.files("symloc") / "data" / "worlds"
    names = sorted(p.name for p in folder.iterdir() if p.name.endswith(".yaml"))
    assert "square_with_box.yaml" in names
    assert len(names) >= 4
    for n in names:
        with resources.as_file(folder / n) as path:
            spec = load_world_file(path)
        room = spec.build()
        assert room.symmetry is not None
    with resources.as_file(folder / "square_with_box.yaml") as path:
        assert load_world_file(path).to_dict() == WorldSpec.from_dict(_doc()).to_dict()


# ------------------------------------------------------------------------------------------
# errors: each names the file, the key path and what was expected
# ------------------------------------------------------------------------------------------


def _set(doc: dict[str, Any], path: tuple[Any, ...], value: Any) -> dict[str, Any]:
    d = copy.deepcopy(doc)
    cur: Any = d
    for k in path[:-1]:
        cur = cur[k]
    cur[path[-1]] = value
    return d


ERRORS: list[tuple[tuple[Any, ...], Any, str]] = [
    (("colour",), "red", r"w\.yaml: colour: unknown key; expected one of name, "),
    (("room", "polygon"), [[0, 0], [1, 0]], r"room\.polygon: expected at least 3"),
    (
        ("room", "polygon"),
        [[0, 0], [2, 2], [2, 0], [0, 2]],
        r"room\.polygon\[0\]: wall 0 .* crosses wall 2 .*simple polygon",
    ),
    (
        ("room", "polygon"),
        [[0, 0], [1, 1], [2, 2]],
        r"room\.polygon\[0\]: folds back .*clockwise or counter-clockwise is ambiguous",
    ),
    (
        ("room", "polygon"),
        [[0, 0], [2, 0], [2, 0], [0, 2]],
        r"room\.polygon\[2\]: repeats vertex \[1\]",
    ),
    (
        ("room", "polygon", 3),
        [-2, "x"],
        r"room\.polygon\[3\]\[1\]: expected a number \[m\], got 'x'",
    ),
    (("room", "polygon", 3), [-2, "1e3"], r"YAML reads 1e3 as text"),
    (("room", "polygon", 1), [2], r"room\.polygon\[1\]: expected a point \[x, y\]"),
    (
        ("room", "wall_height"),
        -1,
        r"room\.wall_height: expected a number in \(0\.0, 100\.0\] m, got -1",
    ),
    (("room", "wall_height"), True, r"room\.wall_height: expected a number \[m\], got True"),
    (
        ("room", "regular"),
        {"n": 8},
        r"room: expected exactly one of polygon, regular, .*got polygon, regular",
    ),
    (("room",), {"regular": {"n": 8}}, r"room\.regular\.gv: missing; this key is required"),
    (
        ("room",),
        {"regular": {"n": 2, "gv": 3}},
        r"room\.regular\.n: expected an integer in \[3, 64\], got 2",
    ),
    (
        ("room",),
        {"circle": {"radius": 3, "yaw_deg": 4}},
        r"room\.circle\.yaw_deg: unknown key; expected one of radius, center",
    ),
    (
        ("room",),
        {"circle": {"radius": 3}, "chamfer": 0.1},
        r"room\.chamfer: a round room has no corners",
    ),
    (("room",), {"wall_height": 2}, r"room: expected exactly one of .*got none"),
    (
        ("room", "chamfer"),
        [0.1, 0.1],
        r"room\.chamfer: expected one number or 4 \(one per corner\), got 2",
    ),
    (
        ("room", "chamfer"),
        2.5,
        r"room\.chamfer: cuts of 2\.5 m and 2\.5 m at corners 0 and 1 leave less than",
    ),
    (("room", "chamfer"), -0.1, r"room\.chamfer: expected a number in \[0\.0, 1000\.0\] m"),
    (("furniture", 1), {"box": {"center": [0, 0]}}, r"furniture\[1\]\.box\.size: missing"),
    (
        ("furniture", 0, "box", "size"),
        [0.5],
        r"furniture\[0\]\.box\.size: expected a size \[width, depth\]",
    ),
    (
        ("furniture", 0, "box", "size"),
        [0.5, 0],
        r"furniture\[0\]\.box\.size\[1\]: expected a number in \[0\.01, 1000\.0\] m",
    ),
    (
        ("furniture", 0, "box", "center"),
        [3.0, 0.0],
        r"furniture\[0\]\.box: lies outside the room or within 0\.01 m of its walls",
    ),
    (("furniture", 0, "box", "center"), [1.9, 0.0], r"furniture\[0\]\.box: lies outside the room"),
    (
        ("furniture", 1, "cylinder", "center"),
        [1.45, 0.2],
        r"furniture\[1\]\.cylinder: overlaps furniture\[0\]\.box",
    ),
    (
        ("furniture", 1),
        {"box": {"center": [0, 0], "size": [1, 1]}, "cylinder": {}},
        r"furniture\[1\]: expected exactly one of box, cylinder",
    ),
    (
        ("furniture", 0, "box", "material"),
        "gold",
        r"furniture\[0\]\.box\.material: expected one of wood, plain, dark, glass, got 'gold'",
    ),
    (("furniture",), {"box": {}}, r"furniture: expected a list of items"),
    (
        ("doors", 0, "width"),
        4.5,
        r"doors\[0\]\.width: a door of 4\.5 m is wider than wall 0 \(4\.000 m",
    ),
    (("doors", 0, "wall"), 4, r"doors\[0\]\.wall: expected a wall index in \[0, 3\], got 4"),
    (
        ("doors", 0, "at"),
        0.05,
        r"doors\[0\]\.at: a door of 0\.9 m centred at 0\.05 of wall 0 .* runs past",
    ),
    (("doors", 0, "at"), 1.5, r"doors\[0\]\.at: expected a number in \[0\.0, 1\.0\] fraction"),
    (("doors", 0, "open"), "yes", r"doors\[0\]\.open: expected true or false, got 'yes'"),
    (
        ("doors",),
        [{"wall": 0, "width": 0.9}, {"wall": 0, "at": 0.6}],
        r"doors\[1\]: overlaps doors\[0\] on wall 0",
    ),
    (("lab",), "shiny", r"lab: expected textured, untextured or a mapping, got 'shiny'"),
    (
        ("lab",),
        {"textures": [1, 2, 3]},
        r"lab\.textures: expected 4 entries \(one per wall of the room\), got 3",
    ),
    (
        ("lab",),
        {"textures": [1, 2, 3, -4]},
        r"lab\.textures\[3\]: expected a texture id \(integer >= 0\), plain or dark",
    ),
    (("lab",), {"size": [9, 9]}, r"lab\.size: only used for a room of boards"),
    (
        ("pillars",),
        [{"center": [0, 0]}],
        r"pillars\[0\]: expected exactly one of radius \(round\) or size \(square\)",
    ),
    (
        ("pillars",),
        [{"center": [1.45, 0.0], "radius": 0.1}],
        r"pillars\[0\]: overlaps furniture\[0\]\.box",
    ),
    (
        ("glass",),
        [{"from": [0, 0], "to": [0, 0.01]}],
        r"glass\[0\]: expected a panel at least 0\.05 m long",
    ),
    (("glass",), [{"from": [-1, -1], "to": [-1, 3]}], r"glass\[0\]: lies outside the room"),
    (
        ("people",),
        [{"path": [[-1, -1]]}],
        r"people\[0\]\.path: expected at least 2 \[x, y\] points, got 1",
    ),
    (
        ("people",),
        [{"path": [[-1.5, -1.5], [1.5, 0.0]]}],
        r"people\[0\]\.path\[0\]: the leg to point \[1\] leaves the room or passes within 0\.25 m",
    ),
    (
        ("people",),
        [{"path": [[-1.5, -1.0], [-1.5, 1.0]], "speed": 9}],
        r"people\[0\]\.speed: expected a number in \[0\.05, 3\.0\] m/s",
    ),
    (
        ("people",),
        [{"path": [[-1.5, -1.0], [-1.5, -1.0], [0, 0]]}],
        r"people\[0\]\.path\[1\]: repeats the point before it",
    ),
    (("seed",), -3, r"seed: expected an integer in \[0, "),
    (
        ("lab",),
        {"textures": [1, 2, 3, 4], "textured": True},
        r"lab: expected textures or textured, not both",
    ),
    (("lab",), {"textures": []}, r"lab\.textures: expected at least one entry"),
    (("lab",), {"margin": 2.0}, r"lab\.margin: only used for a room of boards"),
    (("generator",), {"family": "x"}, r"generator\.seed: missing; this key is required"),
    (
        ("pillars",),
        [{"center": [0, 0], "radius": 0.1, "yaw_deg": 3}],
        r"pillars\[0\]\.yaw_deg: unknown key for a round pillar",
    ),
    (("pillars",), [{"radius": 0.1}], r"pillars\[0\]\.center: missing; this key is required"),
    (
        ("people",),
        [{"path": [[-1.5, -1.0], [-1.5, 1.0]], "loop": "no"}],
        r"people\[0\]\.loop: expected true or false",
    ),
    (("name",), 5, r"name: expected a string, got 5"),
]


@pytest.mark.parametrize(("path", "value", "match"), ERRORS)
def test_errors_name_file_and_key(
    tmp_path: Path, path: tuple[Any, ...], value: Any, match: str
) -> None:
    bad = _set(_doc(), path, value)
    f = _write(tmp_path, yaml.safe_dump(bad))
    with pytest.raises(WorldError, match=match) as info:
        load_world_file(f)
    assert str(info.value).startswith(f"{f}: ")


def test_file_level_errors(tmp_path: Path) -> None:
    with pytest.raises(WorldError, match=r"nope\.yaml: cannot read the world file"):
        load_world_file(tmp_path / "nope.yaml")
    with pytest.raises(WorldError, match=r"bad\.yaml: not valid YAML"):
        load_world_file(_write(tmp_path, "room: [unclosed", "bad.yaml"))
    with pytest.raises(WorldError, match=r"empty\.yaml: \(top\): the world file is empty"):
        load_world_file(_write(tmp_path, "", "empty.yaml"))
    with pytest.raises(WorldError, match=r"list\.yaml: : expected a mapping with keys name"):
        load_world_file(_write(tmp_path, "- 1\n- 2\n", "list.yaml"))
    with pytest.raises(WorldError, match=r"noroom\.yaml: room: missing; this key is required"):
        load_world_file(_write(tmp_path, "name: x\n", "noroom.yaml"))


def test_lab_of_boards_needs_four_walls() -> None:
    doc = {"name": "b", "room": {"rectangle": {"width": 3, "depth": 2}, "wall_height": 0.4}}
    with pytest.raises(
        WorldError, match=r"lab\.textures: a lab has at least 4 walls; expected >= 4"
    ):
        WorldSpec.from_dict({**doc, "lab": {"textures": [1, 2, 3]}})


def test_round_room_door_errors() -> None:
    doc = {"name": "c", "room": {"circle": {"radius": 2.0}}}
    with pytest.raises(WorldError, match=r"doors\[0\]\.wall: a round room has one wall, 0; got 1"):
        WorldSpec.from_dict({**doc, "doors": [{"wall": 1}]})
    with pytest.raises(WorldError, match=r"doors\[0\]\.width: 2\.5 m is too wide for a round wall"):
        WorldSpec.from_dict({**doc, "doors": [{"wall": 0, "width": 2.5}]})
    room = WorldSpec.from_dict({**doc, "doors": [{"wall": 0, "at": 0.25, "width": 1.0}]}).build()
    # the gap is centred on the +x side (a quarter turn from the bottom)
    assert room.world.distance(np.array([[2.0, 0.0]]))[0] == pytest.approx(0.5, abs=0.01)
    assert room.order == 1


def test_clockwise_polygon_keeps_its_wall_numbers() -> None:
    doc = _doc()
    doc["room"]["polygon"] = [[-2, -2], [-2, 2], [2, 2], [2, -2]]  # clockwise
    doc["doors"] = [{"wall": 0, "at": 0.5, "width": 0.9}]  # wall 0 is x = -2
    room = WorldSpec.from_dict(doc).build()
    assert room.world.distance(np.array([[-2.0, 0.0]]))[0] == pytest.approx(0.45)
    assert room.area == pytest.approx(16.0)


# ------------------------------------------------------------------------------------------
# malformed documents give WorldError and nothing else
# ------------------------------------------------------------------------------------------

_scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**6), 10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=6),
)
_values = st.recursive(
    _scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=5),
        st.dictionaries(
            st.sampled_from(
                ["center", "size", "radius", "n", "gv", "wall", "x", "path", "polygon"]
            ),
            inner,
            max_size=4,
        ),
    ),
    max_leaves=12,
)


def _paths(doc: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [prefix] if prefix else []
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += _paths(v, (*prefix, i))
    return out


BASE = _doc()
BASE["people"] = [{"path": [[-1.5, -1.0], [-1.5, 1.0]]}]
BASE["pillars"] = [{"center": [-1.0, 1.5], "radius": 0.1}]
PATHS = _paths(BASE)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(PATHS), value=_values, drop=st.booleans())
def test_malformed_documents_raise_only_world_error(
    path: tuple[Any, ...], value: Any, drop: bool
) -> None:
    doc = copy.deepcopy(BASE)
    cur: Any = doc
    for k in path[:-1]:
        cur = cur[k]
    if drop and isinstance(cur, dict):
        del cur[path[-1]]
    else:
        cur[path[-1]] = value
    message = ""
    try:
        spec = WorldSpec.from_dict(doc, "fuzz")
    except WorldError as err:
        message = str(err)
    if message:
        assert message.startswith("fuzz: ")
    else:
        assert spec == WorldSpec.from_dict(spec.to_dict())


@settings(max_examples=100, deadline=None)
@given(doc=_values)
def test_random_documents_raise_only_world_error(doc: Any) -> None:
    with pytest.raises(WorldError):
        WorldSpec.from_dict(doc, "fuzz")


def test_world_at_moves_people_and_sample_pose() -> None:
    doc = _doc()
    doc["people"] = [{"path": [[-1.5, -1.0], [-1.5, 1.0]], "speed": 1.0}]
    room = WorldSpec.from_dict(doc).build()
    assert room.world_at(0.0).n_circles == room.world.n_circles + 1
    p0 = room.world_at(0.0).circles[-1]
    p1 = room.world_at(1.5).circles[-1]
    assert p0[:2] == pytest.approx([-1.5, -1.0])
    assert p1[:2] == pytest.approx([-1.5, 0.5])
    assert room.world.n_circles == 1  # the static world has no people
    rng = np.random.default_rng(0)
    poses = np.array([room.sample_pose(rng) for _ in range(50)])
    assert np.all(room.is_free(poses[:, :2], 0.18))
    assert np.all(np.abs(poses[:, 2]) <= math.pi)


def test_the_documented_example_loads(tmp_path: Path) -> None:
    doc = Path(__file__).resolve().parents[2] / "docs" / "world_files.md"
    block = doc.read_text().split("```yaml\n")[1].split("```")[0]
    room = load_world_file(_write(tmp_path, block)).build()
    assert room.order == 1
    assert len(room.people) == 2
    assert room.world_at(3.0).n_circles == room.world.n_circles + 2


def test_metadata_round_trips_and_bad_values_name_the_key() -> None:
    doc = {
        "name": "m",
        "metadata": {"base_order": 4, "overlap": 0.95, "layout": "furniture", "ok": True},
        "room": {"circle": {"radius": 2.0}},
    }
    spec = WorldSpec.from_dict(doc)
    assert spec.meta == doc["metadata"]
    assert WorldSpec.from_dict(spec.to_dict()) == spec
    with pytest.raises(WorldError, match=r"metadata\.overlap: expected a number"):
        WorldSpec.from_dict({**doc, "metadata": {"overlap": [1, 2]}})
    with pytest.raises(WorldError, match="metadata: expected a mapping"):
        WorldSpec.from_dict({**doc, "metadata": [1]})
