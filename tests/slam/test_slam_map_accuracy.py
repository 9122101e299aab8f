"""The accuracy of SLAM's final map where a robot localizes: walls where they are."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import raycast
from symloc.scan import LaserScan
from symloc.slam import SlamParams, run_slam
from symloc.slam.map_refinement import density_table

#: a 12 m x 4 m room, off the 5 cm cell grid
ROOM = np.array(
    [(0, 0, 12, 0), (12, 0, 12, 4), (12, 4, 0, 4), (0, 4, 0, 0), (5, 4, 5, 3), (8, 0, 8, 0.6)],
    dtype=float,
) + np.array([0.013, 0.027, 0.013, 0.027])


def _scan(pose: np.ndarray, rng: np.random.Generator) -> LaserScan:
    n = 720
    angles = -math.pi + 2 * math.pi * np.arange(n) / n
    r = raycast(ROOM, pose, angles, 16.0) + rng.normal(0.0, 0.015, n)
    return LaserScan(-math.pi, 2 * math.pi / n, 0.15, 16.0, r)


def _wall_trip() -> tuple[list[LaserScan], np.ndarray]:
    """Looks at the bottom wall head-on from the middle of the room, then drives along it
    0.5 m away: the beams that reach its far parts graze it (the bench's exploration lap)."""
    rng = np.random.default_rng(4)
    still = np.tile([6.0, 2.0, -math.pi / 2], (40, 1))
    x = np.arange(1.0, 11.0, 0.1)
    along = np.column_stack([x, np.full(x.size, 0.55), np.zeros(x.size)])
    poses = np.vstack([still, along])
    return [_scan(p, rng) for p in poses], poses


def _face_distance(res: object, xs: np.ndarray) -> np.ndarray:
    """Distance [m] from points of the bottom wall's face to the nearest occupied cell."""
    grid = res.grid  # type: ignore[attr-defined]
    occ = grid.cell_to_world(np.argwhere(grid.occupied_mask))
    face = np.column_stack([xs, np.full(xs.size, 0.027)])
    d = np.hypot(face[:, None, 0] - occ[None, :, 0], face[:, None, 1] - occ[None, :, 1])
    return np.asarray(d.min(axis=1))


def test_final_map_keeps_a_grazed_wall_where_it_is() -> None:
    scans, truth = _wall_trip()
    xs = np.arange(1.0, 11.0, 0.05)
    res = run_slam(scans, truth, progress=False)
    assert np.abs(res.poses[:, :2] - truth[:, :2]).max() < 0.03
    # every point of the wall's face within a cell's diagonal of an occupied cell
    assert _face_distance(res, xs).max() < 0.05
    # clamped after every scan (as the submaps are), the grazing beams erase the face and
    # only the cells behind it, hit by the beams that overshoot, stay occupied
    clamped = run_slam(
        scans, truth, SlamParams(map_clamp=True, refine_rounds=0, map_error=False), progress=False
    )
    assert np.percentile(_face_distance(clamped, xs), 90) > 0.05


def test_density_table_ridge_lies_on_the_mean_of_the_points() -> None:
    rng = np.random.default_rng(0)
    x = rng.uniform(0.0, 2.0, 4000)
    y = 1.0 + rng.normal(0.0, 0.02, x.size)
    pts = np.column_stack([x, y])
    table = density_table(lambda: [pts[:2000], pts[2000:]], 0.025, 0.04, max_cells=10**6)
    assert table is not None
    # the points score best where they are (the ridge is on their mean, between cells too)
    shifts = np.linspace(-0.05, 0.05, 101)
    score = [float(table.interpolate(pts + np.array([0.0, dy]))[0].mean()) for dy in shifts]
    assert abs(shifts[int(np.argmax(score))]) <= 0.003
    val, _ = table.interpolate(pts)
    assert val.max() <= 1.0 + 1e-6
    assert density_table(lambda: [pts], 0.025, 0.04, max_cells=100) is None


@pytest.mark.parametrize("band_cells", [1000, 1 << 20])
def test_splat_accumulates_as_a_dense_float64_splat_would(
    band_cells: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """add_splat works a band of rows at a time; the counts are those of adding a
    dense float64 (H, W) splat rounded to float32, batch after batch."""
    import symloc.slam.map_refinement as mr
    from symloc.slam.map_refinement import add_splat, splat_points

    monkeypatch.setattr(mr, "_BAND_CELLS", band_cells)

    rng = np.random.default_rng(0)
    origin = np.array([-1.0, -2.0])
    shape = (300, 400)
    counts = np.zeros(shape, np.float32)
    dense = np.zeros(shape, np.float32)
    for _ in range(3):
        pts = rng.normal(3.0, 3.0, size=(20_000, 2))
        pts[:5000] = np.round(pts[:5000], 1)  # many points on the same cells
        add_splat(counts, pts, origin, 0.025)
        u = (pts - origin) / 0.025 - 0.5
        i0 = np.floor(u).astype(np.intp)
        f = u - i0
        acc = np.zeros(shape[0] * shape[1])
        for dc, dr in ((0, 0), (1, 0), (0, 1), (1, 1)):
            c, r = i0[:, 0] + dc, i0[:, 1] + dr
            w = (f[:, 0] if dc else 1 - f[:, 0]) * (f[:, 1] if dr else 1 - f[:, 1])
            ok = (c >= 0) & (c < shape[1]) & (r >= 0) & (r < shape[0])
            acc += np.bincount(r[ok] * shape[1] + c[ok], weights=w[ok], minlength=acc.size)
        dense += acc.reshape(shape).astype(np.float32)
    assert np.array_equal(counts, dense)
    assert np.array_equal(
        splat_points(pts, origin, 0.025, shape), acc.reshape(shape).astype(np.float32)
    )
