"""MapFields: one shared per-map cache of fields, each computed once and identical to before."""

from __future__ import annotations

import gc
import math
import pickle
import weakref

import numpy as np
import pytest
from scipy.ndimage import distance_transform_edt

import symloc.grid.fields as fields_mod
from symloc.errors import ConfigurationError
from symloc.geometry import compose
from symloc.grid import OccupancyGrid
from symloc.grid.distance_field import compute_distance_field, compute_surface_distance_field
from symloc.grid.fields import MapFields, distance_field, surface_distance_field
from symloc.localizer.adapters import AmclTracker, GridScorer
from symloc.localizer.build import grid_round_centre, grid_symmetries
from symloc.localizer.claim import ClaimGate
from symloc.localizer.map_symmetry import map_symmetries
from symloc.mcl import Amcl, AmclParams, ConfidenceJudge
from symloc.mcl.beam_model import raycast_grid
from symloc.mcl.rival_search import padded_field
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan


def asymmetric_room() -> OccupancyGrid:
    """An 8 m x 6 m room with two obstacles placed without symmetry (as tests/mcl's)."""
    d = np.zeros((120, 160), np.int8)
    d[0, :] = d[-1, :] = d[:, 0] = d[:, -1] = 100
    d[30:50, 40:60] = 100
    d[80:85, 100:140] = 100
    d[60:100, 20:24] = 100
    return OccupancyGrid(d, 0.05)


def synthetic_scan(grid: OccupancyGrid, pose: np.ndarray, rng: np.random.Generator) -> LaserScan:
    """A 360-degree, 180-beam scan ray cast on ``grid`` from ``pose`` with 1 cm noise."""
    n = 180
    ang = -np.pi + 2 * np.pi / n * np.arange(n)
    r = raycast_grid(grid, np.repeat(np.asarray(pose)[None, :2], n, 0), ang + pose[2], 12.0)
    r = np.where(r >= 12.0, np.inf, r + rng.normal(0.0, 0.01, n))
    return LaserScan(-np.pi, 2 * np.pi / n, 0.05, 12.0, r)


def test_one_cache_per_grid_object():
    g = asymmetric_room()
    f = MapFields.of(g)
    assert MapFields.of(g) is f
    assert MapFields.of(f) is f
    assert f.grid is g
    assert MapFields.of(asymmetric_room()) is not f  # another grid object, another cache
    assert distance_field(g, 2.0) is f.distance(2.0)
    assert surface_distance_field(f) is f.surface()
    with pytest.raises(ConfigurationError, match="expected an OccupancyGrid or MapFields"):
        MapFields.of(np.zeros((3, 3)))  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="expected an OccupancyGrid, got"):
        MapFields(np.zeros((3, 3)))  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="laser_likelihood_max_dist"):
        f.distance(0.0)


def test_the_cache_dies_with_its_grid_and_is_not_pickled():
    g = asymmetric_room()
    MapFields.of(g).distance(1.0)
    MapFields.of(g).grown(0.5)
    back = pickle.loads(pickle.dumps(g))
    assert "_map_fields" not in back.__dict__
    assert np.array_equal(back.data, g.data)
    alive = weakref.ref(g)
    del g
    gc.collect()
    assert alive() is None


def _old_blocked(g: OccupancyGrid) -> np.ndarray:
    free = np.zeros((g.height + 2, g.width + 2), dtype=bool)
    free[1:-1, 1:-1] = g.free_mask
    return distance_transform_edt(free, sampling=g.resolution).astype(np.float32)


def _old_grown(g: OccupancyGrid, max_dist: float) -> np.ndarray:
    pad = math.ceil(max_dist / g.resolution) + 1
    data = np.pad(g.data, pad, constant_values=-1)
    origin = compose(np.asarray(g.origin, dtype=np.float64), [-pad * g.resolution] * 2 + [0])
    big = OccupancyGrid(data, g.resolution, origin, g.occupied_thresh, g.free_thresh)
    return compute_distance_field(big, max_dist).padded


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and bool(np.array_equal(a, b))


def test_the_consumers_of_one_grid_compute_each_field_once(monkeypatch):
    calls: dict[str, int] = {"distance": 0, "surface": 0, "edt": 0, "obstacle": 0}

    def counted(name, fn):
        def wrapper(*a, **k):
            calls[name] += 1
            return fn(*a, **k)

        return wrapper

    monkeypatch.setattr(
        fields_mod, "compute_distance_field", counted("distance", compute_distance_field)
    )
    monkeypatch.setattr(
        fields_mod,
        "compute_surface_distance_field",
        counted("surface", compute_surface_distance_field),
    )
    monkeypatch.setattr(
        fields_mod, "distance_transform_edt", counted("edt", distance_transform_edt)
    )
    monkeypatch.setattr(
        fields_mod, "_obstacle_distance", counted("obstacle", fields_mod._obstacle_distance)
    )

    grid = asymmetric_room()
    rng = np.random.default_rng(4)
    a = 0.002
    lf = AmclParams(max_particles=800, min_particles=200, alpha1=a, alpha2=a, alpha3=a, alpha4=a)
    amcl = Amcl(grid, lf, rng=5)
    tracker = AmclTracker(amcl)
    scorer = GridScorer(grid)
    syms = map_symmetries(grid)
    gate = ClaimGate(surface_distance_field(grid))
    # a second filter with the beam model, a second judge, a second scorer: nothing new
    beam = Amcl(
        MapFields.of(grid),
        AmclParams(laser_model_type="beam", min_particles=50, max_particles=200),
        rng=1,
    )
    judge = ConfidenceJudge(beam)
    GridScorer(MapFields.of(grid))
    map_symmetries(MapFields.of(grid))

    true = np.array([5.0, 3.0, 0.3])
    tracker.initialize_pose(true, np.diag([0.01, 0.01, 0.001]))
    beam.initialize_pose(true, np.diag([0.01, 0.01, 0.001]))
    odom = np.array([1.0, 1.0, 0.0])
    for i in range(6):
        step = np.array([0.3, 0.0, 0.0]) if i % 2 == 0 else np.array([0.0, 0.0, 0.3])
        scan = synthetic_scan(grid, true, rng)
        tracker.update(OdometryReading(odom), scan)
        judge.update(OdometryReading(odom), scan)
        true, odom = compose(true, step), compose(odom, step)
    assert tracker.judge.n_rival_searches >= 1

    f = MapFields.of(grid)
    # likelihood field = consistency field (2.0 m > 0.4 m), the rival search's grown field,
    # the claim gate's surface field, the scorer's and symmetries' squared distances in cells
    # (2 bytes per cell; the float64 obstacle distance is not needed), the beam model's EDT
    assert dict(f.n_computed) == {
        "distance": 1,
        "grown": 1,
        "surface": 1,
        "obstacle_squared_cells": 1,
        "blocked_distance": 1,
    }
    # distance: the map's (the grown one is built from it and its edges); scipy's EDT: the
    # beam model's
    assert calls == {"distance": 1, "surface": 1, "edt": 1, "obstacle": 0}
    assert amcl.field is beam.field is tracker.judge.consistency_field is judge.consistency_field
    assert scorer._k is f.obstacle_squared_cells()[0]
    assert gate.field is f.surface()
    assert isinstance(syms, list)

    # the same numbers as the fields each consumer computed for itself before
    occ = grid.occupied_mask
    assert _same(f.obstacle_distance(), distance_transform_edt(~occ) * grid.resolution)
    k, metres = f.obstacle_squared_cells()
    assert k.dtype == np.uint16
    assert _same(metres[k], f.obstacle_distance())  # every cell is within the 2-byte reach
    for tol in (0.0, 0.05, 0.1, 0.37):
        assert np.array_equal(f.near_obstacle(tol), f.obstacle_distance() <= tol)
    assert _same(f.blocked_distance(), _old_blocked(grid))
    assert _same(f.distance(2.0).padded, compute_distance_field(grid, 2.0).padded)
    assert _same(f.surface(1.0).padded, compute_surface_distance_field(grid, 1.0).padded)
    assert _same(f.grown(2.0).padded, _old_grown(grid, 2.0))
    assert padded_field(grid, 2.0) is f.grown(2.0)
    assert not f.obstacle_distance().flags.writeable
    assert not f.blocked_distance().flags.writeable


def test_clear_forgets_the_fields():
    g = asymmetric_room()
    f = MapFields.of(g)
    a = f.distance(1.0)
    f.clear()
    b = f.distance(1.0)
    assert a is not b
    assert np.array_equal(a.padded, b.padded)
    assert f.n_computed["distance"] == 2


def test_the_map_symmetries_are_computed_once_per_map_and_kept_with_its_fields():
    g = asymmetric_room()
    first = grid_symmetries(g)
    assert grid_symmetries(g) is first
    assert MapFields.of(g).n_computed["map_symmetries"] == 1
    assert [s.order for s in first] == [s.order for s in map_symmetries(g)]
    MapFields.of(g).clear()
    assert grid_symmetries(g) is not first  # cleared with the fields
    assert MapFields.of(g).n_computed["map_symmetries"] == 2


def test_the_round_centre_is_computed_once_per_map():
    g = asymmetric_room()
    assert grid_round_centre(g) is None
    assert grid_round_centre(g) is None
    assert MapFields.of(g).n_computed["round_centre"] == 1


def test_the_lean_obstacle_distance_equals_scipys_value_for_value():
    rng = np.random.default_rng(7)
    for share, res, shape in (
        (0.002, 0.05, (300, 411)),
        (0.1, 0.013, (97, 64)),
        (0.5, 1.0, (5, 9)),
    ):
        occ = rng.random(shape) < share
        assert _same(fields_mod._obstacle_distance(occ, res), distance_transform_edt(~occ) * res)
    # no obstacle, and one cell farther than OpenCV's float32 keeps exact: scipy's path
    for occ in (np.zeros((4, 6), bool), np.zeros((2100, 3), bool)):
        occ[0, 0] = occ.shape[0] > 4
        assert _same(fields_mod._obstacle_distance(occ, 0.05), distance_transform_edt(~occ) * 0.05)


def test_the_integral_image_counts_the_free_cells_above_and_left():
    from symloc.grid.precomputation import _integral_image

    free = np.random.default_rng(3).random((600, 37)) < 0.7  # more rows than one band
    got = _integral_image(free)
    assert got.dtype == np.int32
    assert got.shape == (601, 38)
    assert not got[0].any()
    assert not got[:, 0].any()
    assert np.array_equal(got[1:, 1:], free.cumsum(axis=0).cumsum(axis=1))


def test_the_two_byte_obstacle_distance_is_exact_up_to_its_reach_and_clipped_beyond():
    from symloc.mcl.global_search import _clipped_distance

    d = np.zeros((40, 400), np.int8)
    d[:, 0] = 100  # the far end is 399 cells (more than the 256 of the reach) from a wall
    grid = OccupancyGrid(d, 0.05)
    f = MapFields(grid)
    k, metres = f.obstacle_squared_cells()
    full = f.obstacle_distance()
    inside = k < fields_mod.OBSTACLE_K_MAX
    assert not inside.all()
    assert np.array_equal(metres[k][inside], full[inside])
    assert (full[~inside] >= f.obstacle_reach()).all()
    # the global search's clipped distance: from the 2-byte field, or (a cap beyond its
    # reach) from the float64 one; the same values as min(obstacle distance, cap) both ways
    for cap in (0.2, 15.0):
        codes, table = _clipped_distance(f, cap)
        assert table[-1] == cap
        assert np.array_equal(table[codes], np.minimum(full, cap))


@pytest.mark.parametrize("seed", range(5))
def test_grown_field_from_the_maps_own_equals_its_own_transform(seed: int) -> None:
    """The grown field built from the map's own field and four edge strips is, value for
    value, the transform of the grown map (obstacles on the edges, small and thin maps)."""
    rng = np.random.default_rng(seed)
    h, w = [(60, 80), (7, 90), (90, 5), (1, 1), (33, 47)][seed]
    data = np.where(rng.random((h, w)) < 0.08, 100, np.where(rng.random((h, w)) < 0.5, 0, -1))
    data[0, : w // 2] = 100  # walls touching the map's edges
    data[:, -1] = 100
    grid = OccupancyGrid(data.astype(np.int8), 0.05, (1.0, -2.0, 0.0))
    for md in (0.3, 1.0, 2.0):
        direct = MapFields(grid).grown(md)  # no own field yet: one transform of the grown map
        fields = MapFields(grid)
        fields.distance(md)
        derived = fields.grown(md)
        assert derived.padded.shape == direct.padded.shape
        np.testing.assert_array_equal(derived.padded, direct.padded)
        np.testing.assert_array_equal(derived.grid.origin, direct.grid.origin)
        assert derived.max_dist == direct.max_dist
