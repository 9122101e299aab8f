"""Tests of the inverse sensor model and the log-odds grid (symloc.grid.log_odds)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.grid.log_odds import (
    InverseSensorModel,
    LogOddsGrid,
    beam_cells,
    log_odds,
    probability,
)
from symloc.scan import LaserScan


def _scan(ranges: list[float], angle_min: float = 0.0, inc: float = 0.1) -> LaserScan:
    return LaserScan(angle_min, inc, 0.05, 10.0, np.array(ranges, dtype=float))


def test_single_beam_free_then_occupied() -> None:
    model = InverseSensorModel(no_return_range=0.0)
    free, hits = beam_cells(np.zeros(3), _scan([1.0]), model, 0.1, (-0.05, -0.05))
    # beam along +x from the centre of cell (0, 0): cells 0..9 free, cell 10 hit
    assert hits.tolist() == [[0, 10]]
    assert sorted(c for r, c in free.tolist()) == list(range(10))
    assert all(r == 0 for r, c in free.tolist())


def test_hit_cell_is_never_free() -> None:
    model = InverseSensorModel()
    angles = np.linspace(-1, 1, 50)
    scan = LaserScan(-1.0, 2.0 / 49, 0.05, 10.0, 2.0 + 0.3 * np.sin(5 * angles))
    free, hits = beam_cells(np.array([0.3, -0.2, 0.4]), scan, model, 0.05, (-5.0, -5.0))
    fset = {tuple(c) for c in free.tolist()}
    assert hits.shape[0] > 0
    assert not any(tuple(h) in fset for h in hits.tolist())


def test_no_return_beams_clear_only_up_to_configured_range() -> None:
    scan = _scan([math.inf])
    model = InverseSensorModel(no_return_range=2.0)
    free, hits = beam_cells(np.zeros(3), scan, model, 0.1, (-0.05, -0.05))
    assert hits.size == 0
    # the beam starts at the centre of cell 0 and ends 2.0 m further, inside cell 20
    assert free[:, 1].max() == 20
    off = InverseSensorModel(no_return_range=0.0)
    free0, hits0 = beam_cells(np.zeros(3), scan, off, 0.1, (-0.05, -0.05))
    assert free0.size == 0
    assert hits0.size == 0


def test_readings_beyond_max_range_are_truncated_without_hit() -> None:
    model = InverseSensorModel(max_range=1.0, no_return_range=0.0)
    free, hits = beam_cells(np.zeros(3), _scan([5.0]), model, 0.1, (-0.05, -0.05))
    assert hits.size == 0
    assert free[:, 1].max() == 10


def test_invalid_readings_do_nothing() -> None:
    model = InverseSensorModel()
    free, hits = beam_cells(np.zeros(3), _scan([math.nan, 0.01]), model, 0.1, (0.0, 0.0))
    assert free.size == 0
    assert hits.size == 0


def test_grid_grows_and_converts_to_occupancy_grid() -> None:
    g = LogOddsGrid(0.1)
    g.integrate(np.array([5.0, -3.0, math.pi / 2]), _scan([2.0], angle_min=0.0))
    occ = g.to_occupancy_grid()
    # the hit lies at (5, -1): occupied; the robot's cell is free; far cells unknown
    hit = occ.world_to_cell([[5.0, -1.0]])[0]
    assert occ.data[hit[0], hit[1]] == round(100 * 0.7)
    me = occ.world_to_cell([[5.0, -3.0]])[0]
    assert occ.data[me[0], me[1]] == round(100 * 0.4)
    assert (occ.data == -1).sum() > 0.9 * occ.data.size
    assert g.n_scans == 1


def test_repeated_updates_clamp() -> None:
    model = InverseSensorModel(p_max=0.9, p_min=0.2)
    g = LogOddsGrid(0.1, model)
    for _ in range(30):
        g.integrate(np.zeros(3), _scan([1.0]))
    assert g.values.max() == pytest.approx(log_odds(0.9), abs=1e-6)
    assert g.values.min() == pytest.approx(log_odds(0.2), abs=1e-6)


@settings(max_examples=30, deadline=None)
@given(st.floats(0.01, 0.99))
def test_log_odds_inverts(p: float) -> None:
    assert float(probability(log_odds(p))) == pytest.approx(p)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"p_hit": 0.4}, "expected 0 < p_min < p_miss < 0.5 < p_hit"),
        ({"p_miss": 0.6}, "expected 0 < p_min"),
        ({"max_range": 0.0}, "max_range: expected a value > 0"),
        ({"no_return_range": -1.0}, "no_return_range: expected a value >= 0"),
        ({"step": 1.5}, "step: expected <= 1 cell"),
    ],
)
def test_model_validation(kwargs: dict[str, float], match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        InverseSensorModel(**kwargs)


def test_grid_resolution_validation() -> None:
    with pytest.raises(ConfigurationError, match="resolution: expected a value > 0"):
        LogOddsGrid(0.0)


def test_crop_keeps_world_coordinates() -> None:
    g = LogOddsGrid(0.1)
    g.integrate(np.array([5.0, -3.0, 0.0]), _scan([2.03]))
    full = g.to_occupancy_grid()
    crop = g.to_occupancy_grid(crop_margin=2)
    assert crop.data.size < full.data.size
    hit = np.array([[7.03, -3.0]])
    a = full.world_to_cell(hit)[0]
    b = crop.world_to_cell(hit)[0]
    assert full.data[a[0], a[1]] == crop.data[b[0], b[1]] == 70


def _walk(n: int = 40) -> tuple[np.ndarray, list[LaserScan]]:
    rng = np.random.default_rng(3)
    poses, scans = [], []
    p = np.zeros(3)
    for _ in range(n):
        p = p + np.array([rng.normal(0.5, 0.3), rng.normal(0.2, 0.3), rng.normal(0.0, 0.3)])
        r = rng.uniform(0.5, 12.0, 180)
        r[rng.random(180) < 0.05] = 80.0  # no return
        r[rng.random(180) < 0.02] = np.nan
        scans.append(LaserScan(-math.pi / 2, math.pi / 179, 0.1, 50.0, r))
        poses.append(p.copy())
    return np.array(poses), scans


@pytest.mark.parametrize("clamp", [True, False])
def test_reserve_allocates_once_and_changes_nothing(clamp: bool) -> None:
    """A reserved grid grows into one buffer (no copy per growth step) through exactly the
    shapes, origins and values of an unreserved one."""
    poses, scans = _walk()
    model = InverseSensorModel(max_range=40.0)
    plain = LogOddsGrid(0.05, model, poses[0, :2], clamp=clamp)
    reserved = LogOddsGrid(0.05, model, poses[0, :2], clamp=clamp)
    reserved.reserve(poses, scans)
    first = None
    for p, s in zip(poses, scans, strict=True):
        plain.integrate(p, s)
        reserved.integrate(p, s)
        first = reserved.values if first is None else first
        assert reserved.shape == plain.shape
        assert np.array_equal(reserved.origin_xy, plain.origin_xy)
    assert np.array_equal(reserved.values, plain.values)
    assert np.shares_memory(first, reserved.values)  # the same memory from the first scan on
    a = plain.to_occupancy_grid(crop_margin=10)
    b = reserved.to_occupancy_grid(crop_margin=10)
    assert np.array_equal(a.data, b.data)
    assert np.array_equal(a.origin, b.origin)


def test_occupancy_grid_is_the_crop_of_the_full_conversion(monkeypatch: pytest.MonkeyPatch) -> None:
    """Converting only the cropped cells, a block of rows at a time, gives the crop of the
    whole grid converted at once."""
    import symloc.grid.log_odds as lo

    poses, scans = _walk(15)
    g = LogOddsGrid(0.05, InverseSensorModel(max_range=40.0), poses[0, :2], clamp=False)
    for p, s in zip(poses, scans, strict=True):
        g.integrate(p, s)
    full = g.occupancy_percent()
    full[~g.known_mask()] = -1
    monkeypatch.setattr(lo, "_BLOCK_CELLS", 1000)  # many blocks
    occ = g.to_occupancy_grid(crop_margin=3)
    rows = np.flatnonzero(g.known_mask().any(axis=1))
    cols = np.flatnonzero(g.known_mask().any(axis=0))
    r0, c0 = max(rows[0] - 3, 0), max(cols[0] - 3, 0)
    expected = full[r0 : rows[-1] + 4, c0 : cols[-1] + 4]
    assert np.array_equal(occ.data, expected)
    assert np.allclose(occ.origin[:2], g.origin_xy + np.array([c0, r0]) * 0.05)
    assert np.array_equal(g.to_occupancy_grid().data, full)
