from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.features import (
    adjacent_corners,
    area_centroid,
    centroid,
    contour_gaps,
    contour_runs,
    fit_line_tls,
    intersect_lines,
    mean_centroid,
    polygon_area,
    split_and_merge,
)


def polyline(vertices: np.ndarray, per_edge: int, *, closed: bool) -> np.ndarray:
    """Points evenly spaced along the edges of a polyline (each edge without its end)."""
    v = np.asarray(vertices, dtype=float)
    ends = np.roll(v, -1, axis=0) if closed else v[1:]
    starts = v if closed else v[:-1]
    t = np.arange(per_edge)[:, None] / per_edge
    pts = [a + t * (b - a) for a, b in zip(starts, ends, strict=True)]
    if not closed:
        pts.append(v[-1:])
    return np.concatenate(pts)


SQUARE = np.array([[2.0, -1.0], [2.0, 3.0], [-2.0, 3.0], [-2.0, -1.0]])


def test_fit_line_tls_recovers_a_line_orthogonally() -> None:
    rng = np.random.default_rng(1)
    x = np.linspace(-3, 3, 200)
    pts = np.column_stack([x, 0.5 * x + 1.0]) + rng.normal(0, 0.002, (200, 2))
    normal, offset, center, rms = fit_line_tls(pts)
    # the line y = 0.5 x + 1  <=>  (-0.5, 1) / |.| . p = 1 / |.|
    want = np.array([-0.5, 1.0]) / np.hypot(0.5, 1.0)
    sign = np.sign(normal @ want)
    np.testing.assert_allclose(sign * normal, want, atol=1e-3)
    assert sign * offset == pytest.approx(1.0 / np.hypot(0.5, 1.0), abs=2e-3)
    assert rms < 0.004
    np.testing.assert_allclose(center, pts.mean(axis=0))


def test_fit_line_tls_needs_two_points() -> None:
    with pytest.raises(ConfigurationError, match="at least 2 points"):
        fit_line_tls([[1.0, 2.0]])


def test_split_and_merge_closed_square_gives_four_lines_and_exact_corners() -> None:
    pts = polyline(SQUARE, 40, closed=True)
    lines = split_and_merge(pts, 0.01, closed=True)
    assert len(lines) == 4
    assert np.all(lines.max_excess <= 1.0)
    corners = adjacent_corners(lines, tolerance=0.01)
    assert np.all(corners.seen)
    # every true corner is found once
    d = np.hypot(*(corners.points[:, None, :] - SQUARE[None, :, :]).transpose(2, 0, 1))
    assert np.all(d.min(axis=0) < 1e-9)
    np.testing.assert_allclose(np.abs(corners.turn), np.pi / 2, atol=1e-9)


def test_split_and_merge_open_polyline_and_collinear_merge() -> None:
    # an L: two legs; the first leg is sampled in two collinear halves that must merge
    v = np.array([[0.0, 0.0], [2.0, 0.0], [4.0, 0.0], [4.0, 3.0]])
    pts = polyline(v, 30, closed=False)
    lines = split_and_merge(pts, 0.005, closed=False)
    assert len(lines) == 2
    np.testing.assert_allclose(lines.lengths, [4.0, 3.0], atol=0.15)


def test_split_and_merge_noise_does_not_oversplit() -> None:
    rng = np.random.default_rng(3)
    pts = polyline(SQUARE, 100, closed=True)
    pts = pts + rng.normal(0, 0.01, pts.shape)
    lines = split_and_merge(pts, 5 * 0.01, closed=True)
    assert len(lines) == 4


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"points": np.zeros((1, 2)), "tolerance": 0.1}, "M >= 2"),
        ({"points": np.zeros((5, 3)), "tolerance": 0.1}, r"shape \(M, 2\)"),
        ({"points": np.ones((5, 2)), "tolerance": 0.0}, "tolerance"),
        ({"points": np.ones((5, 2)), "tolerance": 0.1, "min_points": 0}, "min_points"),
    ],
)
def test_split_and_merge_rejects_bad_input(kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        split_and_merge(**kwargs)


def test_contour_runs_bridges_dropouts_and_cuts_gaps() -> None:
    # 20 beams; beam 5 missing (dropout), beams 10-14 missing (gap)
    idx = np.array([0, 1, 2, 3, 4, 6, 7, 8, 9, 15, 16, 17, 18, 19])
    runs = contour_runs(idx, 20, max_dropout_beams=2, wrap=False)
    np.testing.assert_array_equal(runs, [[0, 9], [9, 14]])
    # with wrap, the last run continues into the first one
    runs = contour_runs(idx, 20, max_dropout_beams=2, wrap=True)
    np.testing.assert_array_equal(runs, [[9, 14 + 9]])
    # no gap at all: one closed run
    runs = contour_runs(np.arange(20), 20, max_dropout_beams=0, wrap=True)
    np.testing.assert_array_equal(runs, [[0, 20]])
    assert contour_runs(np.zeros(0, int), 20, max_dropout_beams=2, wrap=True).shape == (0, 2)


def test_intersect_lines_parallel_is_nan() -> None:
    out = intersect_lines([[0, 1], [0, 1]], [1.0, 1.0], [[1, 0], [0, 1]], [2.0, 3.0])
    np.testing.assert_allclose(out[0], [2.0, 1.0])
    assert np.all(np.isnan(out[1]))


def test_occlusion_corner_is_not_seen() -> None:
    # wall A along y=1 from x=-2 to x=0 (a box edge), then a far wall along y=3 from x=1 to x=3;
    # their lines are parallel: no corner at the jump
    a = np.column_stack([np.linspace(-2, 0, 30), np.full(30, 1.0)])
    b = np.column_stack([np.linspace(1, 3, 30), np.full(30, 3.0)])
    c = np.column_stack([np.full(30, 3.0), np.linspace(3, 5, 30)])
    lines = split_and_merge(np.concatenate([a, b, c]), 0.005, closed=False)
    assert len(lines) == 3
    corners = adjacent_corners(lines, tolerance=0.005)
    np.testing.assert_array_equal(corners.seen, [False, True])


def test_centroids_of_a_square_sampled_unevenly() -> None:
    # dense points on one wall, sparse on the others: the mean is pulled toward the dense wall,
    # the area centroid is not
    v = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    dense = np.column_stack([np.linspace(-1, 1, 200, endpoint=False), np.full(200, -1.0)])
    rest = polyline([*v[1:].tolist(), v[0].tolist()], 5, closed=False)[:-1]
    pts = np.concatenate([dense, rest])
    c_area, area = area_centroid(pts)
    np.testing.assert_allclose(c_area, [0.0, 0.0], atol=1e-9)
    assert area == pytest.approx(4.0)
    assert mean_centroid(pts)[1] < -0.5
    assert polygon_area(pts[::-1]) == pytest.approx(-4.0)
    np.testing.assert_allclose(centroid(pts, "area"), c_area)
    np.testing.assert_allclose(centroid(pts, "mean"), mean_centroid(pts))


def test_centroid_edge_cases() -> None:
    assert np.all(np.isnan(mean_centroid(np.zeros((0, 2)))))
    c, a = area_centroid(np.zeros((0, 2)))
    assert np.all(np.isnan(c))
    assert a == 0.0
    c, a = area_centroid([[1.0, 1.0], [3.0, 1.0]])
    np.testing.assert_allclose(c, [2.0, 1.0])
    c, a = area_centroid([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])  # collinear: no area
    np.testing.assert_allclose(c, [1.0, 1.0])
    assert polygon_area([[0, 0], [1, 0]]) == 0.0
    with pytest.raises(ConfigurationError, match="centroid: expected one of"):
        centroid(np.ones((3, 2)), "median")


@settings(max_examples=25, deadline=None)
@given(
    n=st.integers(3, 8),
    radius=st.floats(1.0, 8.0),
    rot=st.floats(-np.pi, np.pi),
)
def test_regular_polygon_lines_property(n: int, radius: float, rot: float) -> None:
    ang = rot + 2 * np.pi * np.arange(n) / n
    v = radius * np.column_stack([np.cos(ang), np.sin(ang)])
    pts = polyline(v, 25, closed=True)
    lines = split_and_merge(pts, 0.002, closed=True)
    assert len(lines) == n
    corners = adjacent_corners(lines, tolerance=0.002)
    d = np.hypot(*(corners.points[:, None, :] - v[None, :, :]).transpose(2, 0, 1))
    assert np.all(d.min(axis=0) < 1e-6)


def test_contour_gaps_counts_only_no_return_as_openings() -> None:
    # 12 beams: 3-5 invalid (dropout), 8-10 no return (door); points elsewhere
    no_return = np.zeros(12, bool)
    no_return[8:11] = True
    idx = np.array([0, 1, 2, 6, 7, 11])
    gaps = contour_gaps(idx, 12, max_dropout_beams=2, no_return=no_return, max_blind_beams=5)
    np.testing.assert_array_equal(gaps, [False, False, False, False, True, False])
    # the same gaps without the no-return mask: both are 3 missing beams
    gaps = contour_gaps(idx, 12, max_dropout_beams=2)
    np.testing.assert_array_equal(gaps, [False, False, True, False, True, False])
    # a long blind run opens the contour too
    gaps = contour_gaps(idx, 12, max_dropout_beams=2, no_return=no_return, max_blind_beams=2)
    assert gaps[2]
