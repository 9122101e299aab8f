"""Correlative scan matching must recover a known offset (symloc.slam.correlative_scan_matching)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import make_scan
from symloc.errors import ConfigurationError
from symloc.geometry import angle_diff
from symloc.grid.log_odds import LogOddsGrid
from symloc.slam.correlative_scan_matching import (
    CsmParams,
    LikelihoodTable,
    match_scan,
    refine_pose,
    score_pose,
)
from symloc.slam.slam import scan_points


def _table(room: np.ndarray, poses: list[np.ndarray]) -> LikelihoodTable:
    g = LogOddsGrid(0.05)
    rng = np.random.default_rng(7)
    for p in poses:
        for _ in range(3):
            g.integrate(p, make_scan(room, p, rng, n=361))
    return LikelihoodTable.from_occupied(g.values > 0, 0.05, g.origin_xy, 0.075)


@pytest.mark.parametrize(
    "offset",
    [(0.25, -0.18, math.radians(9.0)), (-0.4, 0.3, math.radians(-14.0)), (0.0, 0.0, 0.0)],
)
def test_recovers_known_offset(room: np.ndarray, offset: tuple[float, float, float]) -> None:
    true = np.array([4.0, 3.0, 0.3])
    table = _table(room, [np.array([4.2, 2.8, 0.0]), np.array([3.8, 3.2, 2.0])])
    scan = make_scan(room, true, np.random.default_rng(1))
    pts = scan_points(scan, 12.0, 0.0)
    guess = true + np.array(offset)
    res = match_scan(
        table, pts, guess, CsmParams(linear_window=0.5, angular_window=math.radians(20))
    )
    assert np.hypot(*(res.pose[:2] - true[:2])) < 0.03
    assert abs(angle_diff(res.pose[2], true[2])) < math.radians(0.7)
    assert res.score > 0.8
    assert res.n_candidates < res.n_total  # branch and bound pruned most of the window


def test_branch_and_bound_equals_exhaustive_search(room: np.ndarray) -> None:
    true = np.array([2.0, 4.0, -0.5])
    table = _table(room, [true])
    pts = scan_points(make_scan(room, true), 12.0, 0.0)
    guess = true + np.array([0.12, -0.1, 0.05])
    kw = {"linear_window": 0.2, "angular_window": 0.1, "refine": False}
    bnb = match_scan(table, pts, guess, CsmParams(coarse_factor=4, **kw))
    full = match_scan(table, pts, guess, CsmParams(coarse_factor=1, **kw))
    assert bnb.search_score == pytest.approx(full.search_score)
    np.testing.assert_allclose(bnb.pose, full.pose)


def test_refinement_improves_score(room: np.ndarray) -> None:
    true = np.array([5.0, 2.0, 1.0])
    table = _table(room, [true])
    pts = scan_points(make_scan(room, true), 12.0, 0.0)
    start = true + np.array([0.03, -0.02, 0.01])
    refined = refine_pose(table, pts, start)
    assert score_pose(table, pts, refined) > score_pose(table, pts, start)
    assert np.hypot(*(refined[:2] - true[:2])) < 0.02


def test_empty_scan_returns_guess(room: np.ndarray) -> None:
    table = _table(room, [np.array([4.0, 3.0, 0.0])])
    res = match_scan(table, np.zeros((0, 2)), np.array([1.0, 2.0, 0.5]))
    np.testing.assert_array_equal(res.pose, [1.0, 2.0, 0.5])
    assert res.score == 0.0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"linear_window": -1.0}, "linear_window: expected a value >= 0"),
        ({"coarse_factor": 0}, "coarse_factor: expected an integer >= 1"),
        ({"refine_iterations": -1}, "refine_iterations: expected an integer >= 0"),
        ({"rotation_weight": -1.0}, "rotation_weight: expected a value >= 0"),
    ],
)
def test_params_validation(kwargs: dict[str, float], match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        CsmParams(**kwargs)


def test_table_validation() -> None:
    with pytest.raises(ConfigurationError, match=r"LikelihoodTable\.values: expected"):
        LikelihoodTable(np.zeros(3), 0.05, (0, 0))


def test_coarse_scores_do_not_depend_on_how_headings_are_grouped(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The coarse level is scored a group of headings at a time (bounded memory): every
    grouping gives exactly the scores of one gather over all headings."""
    import symloc.slam.correlative_scan_matching as csm

    rng = np.random.default_rng(1)
    coarse = rng.random((300, 300)).astype(np.float32)
    k, n, nb = 37, 150, 9
    cells = rng.integers(20, 250, size=(k, n, 2)).astype(np.intp)
    inside = rng.random((k, n)) > 0.1
    offs = (np.arange(nb) * 4 - 16).astype(np.intp)
    rr = cells[:, :, 0, None, None] + offs[None, None, :, None]
    cc = cells[:, :, 1, None, None] + offs[None, None, None, :]
    one_gather = np.where(inside[:, :, None, None], coarse[rr, cc], 0.0).sum(axis=1) / n
    for budget in (1, 5_000, 1 << 30):
        monkeypatch.setattr(csm, "_GATHER_BUDGET", budget)
        out = csm._coarse_scores(coarse, cells, inside, offs, n)
        assert out.dtype == np.float64
        assert np.array_equal(out, one_gather.astype(np.float64))
