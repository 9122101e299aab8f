"""The compiled segmentation of split-and-merge against the NumPy code it replaced.

``split_and_merge_numpy`` (beside this file) holds that code as it was at main bad82ae: the
split's cuts must be the same integers, and the lines (every field of the LineSet) the same
bits, on seeded scans of many rooms and scanners (closed contours and open runs), on noisy
random polylines and on degenerate inputs.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
from split_and_merge_numpy import _split, split_and_merge_numpy

from symloc.features.split_and_merge import LineSet, _Moments, split_and_merge
from symloc.features.split_kernels import segment, segment_py, split_cuts, split_cuts_py
from symloc.sim.lidar import LDS01, PAPER_15M, RPLIDAR_A2, simulate_scan
from symloc.sim.rooms import build_room
from symloc.symmetry import SymmetryConfig


def _cuts(p: np.ndarray, tol: np.ndarray, first_cut: int | None, *, py: bool = False) -> list[int]:
    mom = _Moments(p)
    fn = split_cuts_py if py else split_cuts
    out = fn(np.stack([mom.px, mom.py, tol]), mom.cs, -1 if first_cut is None else first_cut)
    assert out.dtype == np.int64
    return [int(v) for v in out]


def _seeded_runs(
    room_name: str, seed: int
) -> Iterator[tuple[np.ndarray, np.ndarray, SymmetryConfig, np.random.Generator]]:
    """Points, tolerances [m], the scanner's config and the rng of seeded scans of a room by
    three scanners (a G-V of 5 m, 2 m for the 3.5 m LDS-01), 6 positions each."""
    for r_i, preset in enumerate((PAPER_15M, RPLIDAR_A2, LDS01)):
        gv = 2.0 if preset is LDS01 else 5.0
        room = build_room(room_name, gv, lab=False, furniture=r_i, rng=r_i)
        rng = np.random.default_rng(seed + r_i)
        cfg = SymmetryConfig.from_lidar(preset)
        for pos in room.positions_inside(6):
            pose = np.r_[pos, rng.uniform(-math.pi, math.pi)]
            sp = simulate_scan(room.world, pose, preset, rng).to_points()
            if sp.points.shape[0] >= 4:
                tol = np.asarray(cfg.point_tolerance(sp.ranges), dtype=np.float64)
                yield sp.points, tol, cfg, rng


@pytest.mark.parametrize("room_name", ["hexagon", "square", "circle", "l_shaped", "triangle"])
def test_cuts_on_seeded_scans_equal_the_numpy_split(room_name: str) -> None:
    n_scans = 0
    for p, tol, _cfg, _rng in _seeded_runs(room_name, 0):
        d0 = p - p[0]
        for first in (int((d0[:, 0] ** 2 + d0[:, 1] ** 2).argmax()), None):
            assert _cuts(p, tol, first) == _split(p, tol, first, _Moments(p))
        n_scans += 1
    assert n_scans >= 10


def test_cuts_on_random_polylines_equal_the_numpy_split() -> None:
    rng = np.random.default_rng(11)
    for _ in range(200):
        n_v = int(rng.integers(2, 9))
        verts = rng.uniform(-5.0, 5.0, (n_v, 2))
        per = rng.integers(1, 40, n_v - 1)
        p = np.concatenate(
            [
                verts[i]
                + np.linspace(0, 1, int(per[i]), endpoint=False)[:, None]
                * (verts[i + 1] - verts[i])
                for i in range(n_v - 1)
            ]
            + [verts[-1:]]
        )
        p = p + rng.normal(0.0, rng.choice([0.0, 1e-3, 0.02]), p.shape)
        tol = rng.uniform(0.005, 0.05, size=(p.shape[0],))
        if p.shape[0] < 2:
            continue
        first = int(rng.integers(-1, p.shape[0]))
        want = _split(p, tol, first if first >= 0 else None, _Moments(p))
        assert _cuts(p, tol, first if first >= 0 else None) == want
        assert _cuts(p, tol, first if first >= 0 else None, py=True) == want


def test_degenerate_inputs() -> None:
    two = np.array([[0.0, 0.0], [1.0, 0.0]])
    assert _cuts(two, np.full(2, 0.01), None) == [0, 1]
    same = np.zeros((5, 2))  # a zero-length chord: distances from the end point
    assert _cuts(same, np.full(5, 0.01), None) == _split(
        same, np.full(5, 0.01), None, _Moments(same)
    )
    corner = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [2.0, 2.0]])
    assert _cuts(corner, np.full(5, 0.01), None) == [0, 2, 4]


def _same_lines(a: LineSet, b: LineSet) -> None:
    assert (a.roll, a.closed) == (b.roll, b.closed)
    for name in (
        "starts",
        "stops",
        "normals",
        "offsets",
        "centers",
        "directions",
        "n_points",
        "spread",
        "rms",
        "max_excess",
        "endpoints",
    ):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype, name
        assert x.shape == y.shape, name
        assert x.tobytes() == y.tobytes(), name


@pytest.mark.parametrize("room_name", ["hexagon", "square", "circle", "l_shaped", "hallway"])
def test_lines_on_seeded_scans_equal_the_numpy_split_and_merge(room_name: str) -> None:
    """Closed contours (whole scans) and open runs (scans cut into pieces)."""
    for p, tol, cfg, rng in _seeded_runs(room_name, 10):
        tol_before = tol.copy()
        for closed in (True, False):
            _same_lines(
                split_and_merge(p, tol, closed=closed, min_points=cfg.min_line_points),
                split_and_merge_numpy(p, tol, closed=closed, min_points=cfg.min_line_points),
            )
        assert tol.tobytes() == tol_before.tobytes()  # the caller's array is not rolled
        k = int(rng.integers(2, p.shape[0] - 1))
        for run in (slice(0, k), slice(k, None)):
            _same_lines(split_and_merge(p[run], tol[run]), split_and_merge_numpy(p[run], tol[run]))


def test_lines_on_random_contours_equal_the_numpy_split_and_merge() -> None:
    rng = np.random.default_rng(21)
    for _ in range(150):
        n_v = int(rng.integers(3, 9))
        ang = np.sort(rng.uniform(0.0, 2.0 * math.pi, n_v))
        verts = np.c_[np.cos(ang), np.sin(ang)] * rng.uniform(1.0, 6.0, (n_v, 1))
        verts = np.vstack([verts, verts[:1]])
        per = rng.integers(1, 60, n_v)
        p = np.concatenate(
            [
                verts[i]
                + np.linspace(0, 1, int(per[i]), endpoint=False)[:, None]
                * (verts[i + 1] - verts[i])
                for i in range(n_v)
            ]
        )
        p = p + rng.normal(0.0, rng.choice([0.0, 1e-3, 0.01]), p.shape)
        tol = rng.uniform(0.005, 0.05, size=(p.shape[0],))
        closed = bool(rng.random() < 0.7)
        min_points = int(rng.integers(1, 12))
        _same_lines(
            split_and_merge(p, tol, closed=closed, min_points=min_points),
            split_and_merge_numpy(p, tol, closed=closed, min_points=min_points),
        )


def test_segment_matches_its_python_definition() -> None:
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, 2.0 * math.pi, 90, endpoint=False)
    r = 3.0 / np.maximum(np.abs(np.cos(t)), np.abs(np.sin(t)))  # a square around the sensor
    p = np.c_[r * np.cos(t), r * np.sin(t)] + rng.normal(0.0, 0.005, (90, 2))
    outs = []
    for fn in (segment, segment_py):
        pts = np.stack([p[:, 0], p[:, 1], np.full(90, 0.03)])
        pieces, shift = fn(pts, 40, True, 32)
        outs.append((pieces.tolist(), int(shift), pts.tobytes()))
    assert outs[0] == outs[1]
    assert len(outs[0][0][0]) == 4


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_pieces_with_non_finite_points_equal_the_numpy_split_and_merge() -> None:
    """NaN and infinite coordinates (no scan gives them, a caller might): the same pieces,
    NaN comparisons and first-NaN argmins included."""
    rng = np.random.default_rng(0)
    for i in range(300):
        m = int(rng.integers(2, 80))
        p = rng.normal(0.0, 3.0, (m, 2))
        if i % 3 == 0:
            p[rng.integers(0, m)] = np.nan
        if i % 5 == 0:
            p[rng.integers(0, m)] = np.inf
        tol = rng.uniform(0.01, 0.2, size=(m,))
        for closed in (True, False):
            a = split_and_merge(p, tol, closed=closed)
            b = split_and_merge_numpy(p, tol, closed=closed)
            assert (a.starts.tolist(), a.stops.tolist(), a.roll) == (
                b.starts.tolist(),
                b.stops.tolist(),
                b.roll,
            )
