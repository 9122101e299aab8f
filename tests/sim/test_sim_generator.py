"""The world generator: determinism, validity, computed orders, loadable YAML."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.sim.generator import FAMILIES, generate_world
from symloc.sim.rooms import ROBOT_RADIUS
from symloc.sim.world_file import load_world_file, save_world_file

SYMMETRIC = {
    "regular",
    "circle",
    "rectangle",
    "rhombus",
    "cross",
    "corridor_short",
    "corridor_long",
}


def test_family_natures() -> None:
    assert {n for n, f in FAMILIES.items() if f.symmetric} == SYMMETRIC
    for f in FAMILIES.values():
        assert f.description
        assert f.params
        assert all(lo < hi for lo, hi in f.params.values())


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_bare_rooms_have_the_family_nature(family: str, tmp_path: Path) -> None:
    for seed in range(2):
        spec = generate_world(family, seed, perturb=False)
        room = spec.build()
        if family == "circle":
            assert room.order == 0
        elif family in SYMMETRIC:
            assert room.order >= 2
        else:
            assert room.order == 1
        assert spec.generator == (family, seed)
        assert spec.seed == seed
        assert spec.name == f"{family}-{seed}"
        # a robot fits at the centre of a symmetric room and can sample poses everywhere
        if room.symmetric:
            assert room.is_free(room.center[None], ROBOT_RADIUS)[0]
        pose = room.sample_pose(seed)
        assert room.is_reachable(pose[None, :2])[0]
        # the YAML a user gets is loadable and the same world
        path = save_world_file(spec, tmp_path / f"{family}-{seed}.yaml")
        assert load_world_file(path) == spec


def test_deterministic_and_seed_dependent() -> None:
    a = generate_world("l_shape", 3, perturb=True)
    b = generate_world("l_shape", 3, perturb=True)
    c = generate_world("l_shape", 4, perturb=True)
    assert a == b
    assert a != c
    assert a.to_yaml() == b.to_yaml()


def test_perturbed_orders_are_computed() -> None:
    """Over a few seeds some perturbations keep the symmetry and some break it."""
    orders = []
    for s in range(10):
        spec = generate_world("regular", s, perturb=True)
        room = spec.build()
        orders.append(room.order)
        broke = any(d.open for d in spec.doors) or any(
            f.height > 0.3 and f.material != "glass" for f in spec.furniture
        )
        symmetric_items = "symmetric_furniture" in spec.description
        if broke and not symmetric_items:
            assert room.order == 1, spec.description
        assert "perturbed:" in spec.description
    assert any(o == 1 for o in orders)
    assert any(o >= 3 for o in orders)


def test_corridor_ends_visible_or_not() -> None:
    for s in range(2):
        short = generate_world("corridor_short", s, perturb=False).room
        long_ = generate_world("corridor_long", s, perturb=False).room
        assert short.length / 2 < 16.0 < long_.length / 2
        assert 40.0 <= long_.length <= 60.0


def test_generated_furniture_apart_and_people_clear() -> None:
    found_people = found_furniture = False
    for s in range(30):
        spec = generate_world("rectangle", s, perturb=True)
        room = spec.build()
        if spec.people:
            found_people = True
            for p in room.people:
                pts = p.positions(np.linspace(0.0, p.period, 50))
                assert np.all(room.is_free(pts, p.radius - 1e-6))
        if len(spec.furniture) >= 1:
            found_furniture = True
        if found_people and found_furniture:
            break
    assert found_people
    assert found_furniture


def test_bad_arguments() -> None:
    with pytest.raises(ConfigurationError, match="unknown family 'blob'; expected one of regular"):
        generate_world("blob", 0)
    with pytest.raises(ConfigurationError, match="seed must be an integer >= 0, got -1"):
        generate_world("circle", -1)
