from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.grid.fields import clear_distance_field_cache, distance_field


def _grid(occ_cells, shape=(20, 30), res=0.1, origin=(0.0, 0.0, 0.0)):
    d = np.zeros(shape, np.int8)
    for r, c in occ_cells:
        d[r, c] = 100
    return OccupancyGrid(d, res, np.array(origin))


def test_distances_match_brute_force_and_clip():
    g = _grid([(5, 5), (10, 20)])
    df = distance_field(g, 0.8)
    rr, cc = np.mgrid[0:20, 0:30]
    brute = np.minimum(np.hypot(rr - 5, cc - 5), np.hypot(rr - 10, cc - 20)) * 0.1
    # float32 storage: within a float32 rounding of the exact distance
    np.testing.assert_allclose(df.distances, np.minimum(brute, 0.8), rtol=1e-7, atol=0)
    assert df.distances.dtype == np.float32
    assert df.distances.max() == pytest.approx(0.8)
    assert df.padded.shape == (22, 32)
    assert df.padded[0, 0] == pytest.approx(0.8)


def test_cached_per_grid_and_max_dist():
    g = _grid([(1, 1)])
    assert distance_field(g, 2.0) is distance_field(g, 2.0)
    assert distance_field(g, 1.0) is not distance_field(g, 2.0)
    clear_distance_field_cache(g)
    a = distance_field(g, 2.0)
    assert a is distance_field(g, 2.0)


def test_lookup_world_points_and_off_map():
    g = _grid([(5, 5)], origin=(1.0, 2.0, 0.0))
    df = distance_field(g, 2.0)
    centre = g.cell_to_world([[5, 5]])[0]
    vals = df.lookup([centre, centre + np.array([0.3, 0.0]), [-50.0, 0.0], [1e9, 1e9]])
    np.testing.assert_allclose(vals, [0.0, 0.3, 2.0, 2.0], atol=1e-6)


def test_lookup_with_rotated_origin():
    g = _grid([(5, 5)], origin=(1.0, 2.0, 0.7))
    df = distance_field(g, 2.0)
    centre = g.cell_to_world([[5, 5]])[0]
    assert df.lookup([centre])[0] == pytest.approx(0.0, abs=1e-6)


def test_no_occupied_cell_gives_max_everywhere():
    df = distance_field(_grid([]), 1.5)
    assert np.all(df.distances == 1.5)


def test_tables():
    df = distance_field(_grid([(5, 5)]), 2.0)
    pz = df.table("pz", 0.5, 0.5, 0.2, 10.0).reshape(df.padded.shape)
    assert pz[6, 6] == pytest.approx(0.5 + 0.05)
    pz3 = df.table("pz3", 0.5, 0.5, 0.2, 10.0).reshape(df.padded.shape)
    assert pz3[6, 6] == pytest.approx(0.55**3, rel=1e-6)
    lg = df.table("logpz", 0.5, 0.5, 0.2, 10.0).reshape(df.padded.shape)
    assert lg[6, 6] == pytest.approx(np.log(0.55), rel=1e-6)
    assert df.table("pz", 0.5, 0.5, 0.2, 10.0) is df.table("pz", 0.5, 0.5, 0.2, 10.0)


def test_errors():
    g = _grid([(1, 1)])
    with pytest.raises(ConfigurationError, match="laser_likelihood_max_dist"):
        distance_field(g, 0.0)
    with pytest.raises(ConfigurationError, match="OccupancyGrid"):
        distance_field(np.zeros((3, 3)), 1.0)  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="kind"):
        distance_field(g, 1.0).table("bogus", 0.5, 0.5, 0.2, 10.0)


@settings(max_examples=25, deadline=None)
@given(st.floats(-3.0, 6.0), st.floats(-3.0, 5.0))
def test_lookup_never_exceeds_max_and_is_finite(x, y):
    df = distance_field(_grid([(3, 4), (15, 25)]), 1.0)
    v = df.lookup([[x, y]])[0]
    assert 0.0 <= v <= 1.0 + 1e-6


def _scipy_padded(target: np.ndarray, res: float, max_dist: float) -> np.ndarray:
    """The former definition: scipy's EDT in float64, clipped, then float32 with a border."""
    from scipy.ndimage import distance_transform_edt

    d = (
        np.minimum(distance_transform_edt(~target, sampling=res), max_dist)
        if target.any()
        else np.full(target.shape, max_dist)
    )
    out = np.full((d.shape[0] + 2, d.shape[1] + 2), max_dist, dtype=np.float32)
    out[1:-1, 1:-1] = d
    return out


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    density=st.sampled_from([0.0, 0.002, 0.02, 0.2, 0.7]),
    res=st.sampled_from([0.025, 0.03, 0.05, 0.1]),
    max_dist=st.sampled_from([0.3, 1.0, 2.0, 3.7]),
)
def test_distance_field_bit_identical_to_scipy_edt(seed, density, res, max_dist):
    rng = np.random.default_rng(seed)
    shape = tuple(int(v) for v in rng.integers(1, 120, 2))
    occ = rng.random(shape) < density
    g = OccupancyGrid(np.where(occ, 100, 0).astype(np.int8), res)
    np.testing.assert_array_equal(
        distance_field(g, max_dist).padded, _scipy_padded(occ, res, max_dist)
    )


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), res=st.sampled_from([0.05, 0.1]))
def test_surface_field_identical_to_scipy_definition(seed, res):
    from scipy.ndimage import binary_dilation
    from skimage.morphology import skeletonize

    from symloc.grid.fields import surface_distance_field

    rng = np.random.default_rng(seed)
    h, w = (int(v) for v in rng.integers(8, 90, 2))
    data = np.zeros((h, w), np.int8)
    data[rng.random((h, w)) < 0.15] = -1
    # thick walls: random rectangles of occupied cells
    for _ in range(int(rng.integers(0, 8))):
        r, c = int(rng.integers(0, h)), int(rng.integers(0, w))
        data[r : r + int(rng.integers(1, 6)), c : c + int(rng.integers(1, 30))] = 100
    g = OccupancyGrid(data, res)
    occ, free = g.occupied_mask, g.free_mask
    shell = occ & binary_dilation(free, iterations=2) if free.any() else occ
    centre = np.asarray(skeletonize(shell), dtype=bool) if shell.any() else shell
    np.testing.assert_array_equal(
        surface_distance_field(g, 1.0).padded, _scipy_padded(centre, res, 1.0)
    )


def _cell_by_cell(df, kind):
    """The table computed cell by cell (no shortcut through the transform's levels)."""
    import symloc.grid.distance_field as dfm

    keep = dfm._per_level
    dfm._per_level = lambda *a: None
    try:
        df._tables.clear()
        return df.table(kind, 0.9, 0.1, 0.2, 12.0).copy()
    finally:
        dfm._per_level = keep
        df._tables.clear()


@pytest.mark.parametrize(("max_dist", "res"), [(2.0, 0.05), (0.8, 0.1), (0.33, 0.07)])
def test_tables_from_the_levels_equal_the_cell_by_cell_tables(max_dist, res):
    import symloc.grid.distance_field as dfm

    rng = np.random.default_rng(4)
    d = np.zeros((90, 70), np.int8)
    d[rng.random(d.shape) < 0.01] = 100
    df = distance_field(OccupancyGrid(d, res), max_dist)
    src = df.padded.ravel()
    for kind in ("pz", "pz3", "logpz"):
        fast = dfm._per_level(src, res, max_dist, lambda v: v * np.float32(2.0))
        assert fast is not None  # every value is one of the transform's levels
        np.testing.assert_array_equal(fast, src * np.float32(2.0))
        want = _cell_by_cell(df, kind)
        got = df.table(kind, 0.9, 0.1, 0.2, 12.0)
        assert got.view(np.uint32).tolist() == want.view(np.uint32).tolist()  # bit for bit


def test_a_value_that_is_no_level_is_computed_cell_by_cell():
    import symloc.grid.distance_field as dfm

    df = distance_field(_grid([(5, 5)]), 2.0)
    odd = dfm.DistanceField(df.grid, 2.0, df.padded + np.float32(0.013))
    assert dfm._per_level(odd.padded.ravel(), 0.1, 2.0, lambda v: v) is None
    got = odd.table("logpz", 0.5, 0.5, 0.2, 10.0)
    want = np.log(
        0.5 * np.exp(-(odd.padded.ravel().astype(np.float64) ** 2) / (2 * 0.04)) + 0.05
    ).astype(np.float32)
    np.testing.assert_array_equal(got, want)
