"""The branch-and-bound global search: agreement with the exhaustive search, symmetric rooms,
realistic scans, the budgets and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from mcl_fixtures import asymmetric_room, synthetic_scan

from symloc.errors import ConfigurationError
from symloc.geometry import compose, wrap_angle
from symloc.grid import OccupancyGrid
from symloc.grid.fields import MapFields
from symloc.grid.precomputation import build_precomputation_grids
from symloc.lidar_spec import RPLIDAR_A2
from symloc.mcl import global_search as gs
from symloc.mcl.beam_model import raycast_grid
from symloc.mcl.global_search import (
    GlobalSearch,
    GlobalSearchConfig,
    GlobalSearchResult,
    global_search,
)
from symloc.scan import LaserScan
from symloc.sim.lidar import simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.regimes import get_regime
from symloc.sim.rooms import l_shaped_room, rectangle_room, regular_polygon_room


# --------------------------------------------------------------------------- helpers
def _rays(grid: OccupancyGrid, pose: np.ndarray, n: int, range_max: float) -> np.ndarray:
    """Exact end points (robot frame) of ``n`` beams ray cast on ``grid`` from ``pose``."""
    ang = -np.pi + 2.0 * np.pi / n * np.arange(n)
    r = raycast_grid(grid, np.repeat(pose[None, :2], n, 0), ang + pose[2], range_max)
    ok = (r > 0) & (r < range_max)
    return np.column_stack([r[ok] * np.cos(ang[ok]), r[ok] * np.sin(ang[ok])])


def _heading_error(a: float, b: float) -> float:
    return abs(float(wrap_angle(a - b)))


def _near(pose: np.ndarray, truth: np.ndarray, xy: float, th: float) -> bool:
    return bool(np.hypot(*(pose[:2] - truth[:2])) <= xy and _heading_error(pose[2], truth[2]) <= th)


def _room_grid(room):  # type: ignore[no-untyped-def]
    return world_to_grid(room.world, 0.05)


def _rotated_about(centre: np.ndarray, pose: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    d = pose[:2] - centre
    return np.array(
        [centre[0] + c * d[0] - s * d[1], centre[1] + s * d[0] + c * d[1], pose[2] + angle]
    )


def _random_map(data: st.DataObject) -> OccupancyGrid:
    h = data.draw(st.integers(10, 26), label="h")
    w = data.draw(st.integers(10, 26), label="w")
    seed = data.draw(st.integers(0, 2**31 - 1), label="seed")
    rng = np.random.default_rng(seed)
    d = np.zeros((h, w), np.int8)
    d[0, :] = d[-1, :] = d[:, 0] = d[:, -1] = 100
    for _ in range(int(rng.integers(0, 5))):  # random boxes and bars
        r, c = rng.integers(1, h - 1), rng.integers(1, w - 1)
        d[r : r + int(rng.integers(1, 5)), c : c + int(rng.integers(1, 5))] = 100
    d[rng.random((h, w)) < 0.03] = -1
    if data.draw(st.booleans(), label="open edge"):
        d[0, w // 3 : w // 2] = 0  # points may leave the map
    origin = (
        data.draw(st.floats(-3, 3), label="ox"),
        data.draw(st.floats(-3, 3), label="oy"),
        data.draw(st.sampled_from([0.0, 0.3, -2.0]), label="oyaw"),
    )
    return OccupancyGrid(d, 0.05 * data.draw(st.sampled_from([1, 2]), label="res"), origin)


# --------------------------------------------------------------------------- settings
@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("hit_tolerance", -0.1, r"GlobalSearchConfig.hit_tolerance: expected a finite value"),
        ("hit_tolerance", float("nan"), "hit_tolerance: expected a number, got NaN"),
        ("hit_tolerance", "0.1", "hit_tolerance: expected a number"),
        ("min_score", 0.0, r"min_score: expected a finite value in \(0, 1\]"),
        ("min_score", 1.5, "min_score"),
        ("score_margin", 1.0, r"score_margin: expected a value in \[0, 1\)"),
        ("score_margin", -0.1, "score_margin"),
        ("angular_step", 1.0, "angular_step"),
        ("angular_step", -0.01, "angular_step"),
        ("step_range", 0.0, "step_range"),
        ("linear_window", -1.0, "linear_window: expected a value >= 0 m"),
        ("angular_window", 4.0, "angular_window"),
        ("nms_radius", -0.5, "nms_radius"),
        ("nms_angle", 3.5, "nms_angle"),
        ("max_points", 0, "max_points: expected an integer >= 1"),
        ("max_points", 2.5, "max_points: expected an integer"),
        ("max_points", True, "max_points: expected an integer"),
        ("depth", 13, r"depth: expected an integer in \[0, 12\]"),
        ("depth", -1, "depth"),
        ("max_nodes", 0, "max_nodes"),
        ("max_seconds", 0.0, "max_seconds: expected a value > 0 s"),
        ("max_hits", 0, "max_hits"),
        ("max_candidates", 0, "max_candidates"),
    ],
)
def test_config_errors_name_the_field(field: str, value: object, match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        GlobalSearchConfig(**{field: value})  # type: ignore[arg-type]


def test_config_defaults_are_valid_and_frozen() -> None:
    cfg = GlobalSearchConfig()
    assert cfg.min_score == 0.5
    assert math.isinf(cfg.linear_window)
    with pytest.raises(AttributeError):
        cfg.min_score = 0.7  # type: ignore[misc]


def test_bad_inputs_raise_clearly() -> None:
    grid = asymmetric_room()
    search = GlobalSearch(grid)
    scan = synthetic_scan(grid, np.array([2.0, 2.0, 0.3]), np.random.default_rng(0))
    with pytest.raises(ConfigurationError, match="scan: expected a LaserScan"):
        search.search(np.zeros(10))  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match=r"laser_pose: expected shape \(3,\)"):
        search.search(scan, laser_pose=np.zeros((2, 3)))
    with pytest.raises(ConfigurationError, match="laser_pose"):
        search.search(scan, laser_pose=[0.0, np.nan, 0.0])
    with pytest.raises(ConfigurationError, match="prior"):
        search.search(scan, prior=[1.0, 2.0])
    with pytest.raises(ConfigurationError, match=r"points: expected shape \(M, 2\)"):
        search.search_points(np.zeros((5, 3)))
    with pytest.raises(ConfigurationError, match="points: contains NaN"):
        search.search_points([[1.0, np.inf]])
    with pytest.raises(ConfigurationError, match="config: expected a GlobalSearchConfig"):
        GlobalSearch(grid, {"min_score": 0.5})  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="grid: expected an OccupancyGrid"):
        GlobalSearch(np.zeros((4, 4)))  # type: ignore[arg-type]


def test_a_scan_without_points_is_incomplete_not_an_error() -> None:
    grid = asymmetric_room()
    scan = LaserScan(-np.pi, 2 * np.pi / 90, 0.05, 12.0, np.full(90, np.inf))
    res = global_search(grid, scan)
    assert isinstance(res, GlobalSearchResult)
    assert res.candidates == ()
    assert not res.complete
    assert res.verdict == "incomplete"
    assert "no valid end points" in res.reason


# --------------------------------------------------------------------------- precomputation
def test_precomputation_levels_are_block_maxima_and_shared_per_map() -> None:
    rng = np.random.default_rng(3)
    d = np.where(rng.random((23, 31)) < 0.05, 100, 0).astype(np.int8)
    grid = OccupancyGrid(d, 0.05)
    fields = MapFields(grid)
    pyr = fields.precomputation_grids(0.05, 3)
    assert fields.precomputation_grids(0.05, 3) is pyr
    assert fields.n_computed["precomputation"] == 1
    hit = fields.obstacle_distance() <= 0.05
    big = np.zeros((23 + 16, 31 + 16), bool)
    big[8:-8, 8:-8] = hit
    for lvl in range(4):
        s = 1 << lvl
        for i in range(0, big.shape[0], 3):
            for j in range(0, big.shape[1], 2):
                want = big[i : i + s, j : j + s].any()
                assert pyr.level(lvl)[i, j] == want
    assert pyr.free_count(0, 23, 0, 31) == int(grid.free_mask.sum())
    assert pyr.free_count(5, 9, -3, 7) == int(grid.free_mask[5:9, 0:7].sum())
    assert pyr.nbytes > 0
    deep = fields.precomputation_grids(0.05, 9)  # beyond 8 levels: two bytes per cell
    assert deep.bits.dtype == np.uint16
    big9 = np.zeros((23 + 1024, 31 + 1024), bool)
    big9[512:-512, 512:-512] = hit
    for lvl in (0, 3, 8, 9):
        s = 1 << lvl
        want = np.array(
            [
                [big9[i : i + s, j : j + s].any() for j in range(500, 560, 3)]
                for i in range(500, 540, 3)
            ]
        )
        assert np.array_equal(deep.level(lvl)[500:540:3, 500:560:3], want)
    # no occupied cell: nothing is a hit
    empty = build_precomputation_grids(
        np.zeros((4, 4)), np.zeros((4, 4), bool), np.ones((4, 4), bool), 0.1, 1
    )
    assert not empty.bits.any()
    with pytest.raises(ConfigurationError, match="depth"):
        build_precomputation_grids(
            np.zeros((2, 2)), np.zeros((2, 2), bool), np.ones((2, 2), bool), 0.1, 13
        )


def test_search_reuses_the_maps_precomputation() -> None:
    grid = asymmetric_room()
    scan = synthetic_scan(grid, np.array([2.0, 2.0, 0.3]), np.random.default_rng(0))
    global_search(grid, scan)
    global_search(MapFields.of(grid), scan)
    assert MapFields.of(grid).n_computed["precomputation"] == 1


@settings(max_examples=25, deadline=None)
@given(st.data())
def test_block_bound_is_admissible(data: st.DataObject) -> None:
    """The bound of a block is at least the exact count at every position in it."""
    grid = _random_map(data)
    depth = data.draw(st.integers(1, 4), label="depth")
    pyr = MapFields(grid).precomputation_grids(0.05, depth)
    rng = np.random.default_rng(data.draw(st.integers(0, 1000), label="pts"))
    m = 15
    dr = rng.integers(-30, 31, m).astype(np.int32)
    dc = rng.integers(-30, 31, m).astype(np.int32)
    d = data.draw(st.integers(1, depth), label="level")
    s = 1 << d
    r0 = data.draw(st.integers(-s, grid.height), label="r0")
    c0 = data.draw(st.integers(-s, grid.width), label="c0")
    bound = gs.block_count_py(pyr.bits, d, pyr.pad, dr, dc, r0, c0)
    exact = max(
        gs.block_count_py(pyr.bits, 0, pyr.pad, dr, dc, r, c)
        for r in range(r0, r0 + s)
        for c in range(c0, c0 + s)
    )
    assert bound >= exact
    assert gs._block_count(pyr.bits, d, pyr.pad, dr, dc, r0, c0) == bound


# --------------------------------------------------------------------------- exhaustive agreement
@settings(max_examples=60, deadline=None)
@given(st.data())
def test_branch_and_bound_finds_exactly_what_the_exhaustive_search_finds(
    data: st.DataObject,
) -> None:
    grid = _random_map(data)
    free = np.argwhere(grid.free_mask)
    cell = free[data.draw(st.integers(0, len(free) - 1), label="cell")]
    xy = grid.cell_to_world(cell)[0]
    pose = np.array([xy[0], xy[1], data.draw(st.floats(-math.pi, math.pi), label="theta")])
    pts = _rays(grid, pose, data.draw(st.integers(6, 40), label="beams"), 3.0)
    pts = pts + np.random.default_rng(0).normal(0.0, 0.02, pts.shape)
    cfg = GlobalSearchConfig(
        hit_tolerance=data.draw(st.sampled_from([0.0, 0.05, 0.1]), label="tol"),
        min_score=data.draw(st.floats(0.2, 1.0), label="min_score"),
        score_margin=data.draw(st.floats(0.0, 0.5), label="margin"),
        angular_step=math.radians(data.draw(st.sampled_from([3.0, 10.0, 30.0]), label="step")),
        depth=data.draw(st.integers(0, 5), label="depth"),
        max_hits=data.draw(st.sampled_from([4, 200_000]), label="max_hits"),
    )
    prior = None
    if data.draw(st.booleans(), label="windowed"):
        cfg = GlobalSearchConfig(**{
            **{f: getattr(cfg, f) for f in cfg.__dataclass_fields__},
            "linear_window": data.draw(st.floats(0.0, 0.6), label="lw"),
            "angular_window": data.draw(st.floats(0.0, math.pi), label="aw"),
        })  # fmt: skip
        prior = pose + np.array([0.07, -0.04, 0.1])
    search = GlobalSearch(grid, cfg)
    bnb = search.hits(pts, prior=prior)
    ref = search.hits(pts, prior=prior, exhaustive=True)
    if not bnb.complete:  # only the hit buffer can run out here
        assert "max_hits" in bnb.reason
        assert bnb.count.size <= cfg.max_hits
        return
    assert bnb.best == ref.best
    assert bnb.need == ref.need
    assert bnb.key_set() == ref.key_set()
    assert bnb.n_positions == ref.n_positions
    if bnb.count.size:
        a = np.lexsort((bnb.col, bnb.row, bnb.heading))
        b = np.lexsort((ref.col, ref.row, ref.heading))
        np.testing.assert_allclose(bnb.fit[a], ref.fit[b], atol=1e-12)


def test_the_plain_python_twins_agree_with_the_exhaustive_search(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rng = np.random.default_rng(7)
    d = np.zeros((18, 22), np.int8)
    d[0, :] = d[-1, :] = d[:, 0] = d[:, -1] = 100
    d[5:8, 4:6] = 100
    d[12, 10:19] = 100
    grid = OccupancyGrid(d, 0.05, (0.3, -0.2, 0.0))
    pose = np.array([0.7, 0.5, 0.4])
    pts = _rays(grid, pose, 24, 2.0) + rng.normal(0, 0.01, (1, 2))
    cfg = GlobalSearchConfig(angular_step=math.radians(15.0), depth=3, min_score=0.3)
    search = GlobalSearch(grid, cfg)
    ref = search.hits(pts, exhaustive=True)
    monkeypatch.setattr(gs, "branch_and_bound", gs.branch_and_bound_py)
    monkeypatch.setattr(gs, "root_bounds", gs.root_bounds_py)
    py = search.hits(pts)
    assert py.complete
    assert py.key_set() == ref.key_set()
    assert ref.count.size > 0
    assert gs.free_in_py(search.pyramid.free_integral, np.array([0, 18, 0, 22]), 0, 18, 0, 22) == (
        int(grid.free_mask.sum())
    )
    assert gs.need_py(10, 10, 0.3, 0.0) == 10
    assert gs.need_py(0, 10, 0.3, 0.5) == 3


# --------------------------------------------------------------------------- rooms
def test_a_square_room_gives_four_candidates_a_quarter_turn_apart() -> None:
    room = regular_polygon_room(4, 3.5)
    grid = _room_grid(room)
    truth = np.array([room.center[0] + 0.9, room.center[1] - 0.5, 0.4])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 0, noise=False)
    res = global_search(grid, scan)
    assert res.complete
    assert len(res.candidates) == 4
    step = res.angular_step
    copies = [_rotated_about(room.center, truth, k * math.pi / 2) for k in range(4)]
    for cand in res.candidates:
        assert cand.score >= 0.95
        assert sum(_near(cand.pose, c, 0.1, step + 1e-9) for c in copies) == 1
    for c in copies:
        assert sum(_near(k.pose, c, 0.1, step + 1e-9) for k in res.candidates) == 1
    assert [c.score for c in res.candidates] == sorted(
        (c.score for c in res.candidates), reverse=True
    )


def test_a_rectangle_gives_two_candidates_a_half_turn_apart() -> None:
    room = rectangle_room(6.0, 4.0)
    grid = _room_grid(room)
    truth = np.array([room.center[0] - 1.1, room.center[1] + 0.6, -2.0])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 1, noise=False)
    res = global_search(grid, scan)
    assert res.complete
    assert len(res.candidates) == 2
    copies = [truth, _rotated_about(room.center, truth, math.pi)]
    for c in copies:
        assert sum(_near(k.pose, c, 0.1, res.angular_step + 1e-9) for k in res.candidates) == 1


def test_an_l_shaped_room_gives_one_candidate_at_the_truth() -> None:
    room = l_shaped_room(7.0)
    grid = _room_grid(room)
    truth = np.array([room.center[0] - 0.8, room.center[1] - 1.3, 2.5])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 2, noise=False)
    res = global_search(grid, scan)
    assert res.complete
    assert len(res.candidates) == 1
    assert res.n_distinct == 1
    assert _near(res.candidates[0].pose, truth, 2 * grid.resolution, res.angular_step + 1e-9)
    assert res.candidates[0].score >= 0.95
    assert res.threshold == pytest.approx(max(0.5, res.best_score - 0.1))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_realistic_scan_with_noise_and_dropouts_still_finds_the_truth(seed: int) -> None:
    """The simulator's realistic regime: data-sheet noise, this unit's range bias and scale,
    dropouts, mixed pixels."""
    room = l_shaped_room(8.0)
    grid = _room_grid(room)
    rng = np.random.default_rng(seed)
    lidar = get_regime("realistic").lidar(RPLIDAR_A2, rng)
    truth = np.array(
        [
            room.center[0] + rng.uniform(-1, 0.5),
            room.center[1] + rng.uniform(-1, 0.5),
            rng.uniform(-3, 3),
        ]
    )
    scan = lidar.scan(room.world, truth)
    assert np.isnan(scan.ranges).any() or not np.isfinite(scan.ranges).all()
    res = global_search(grid, scan)
    assert res.complete
    assert any(_near(c.pose, truth, 0.1, math.radians(1.5)) for c in res.candidates)
    assert _near(res.candidates[0].pose, truth, 0.1, math.radians(1.5))


def test_the_laser_mount_pose_and_a_rotated_map_origin_are_honoured() -> None:
    d = asymmetric_room().data
    grid = OccupancyGrid(d, 0.05, origin=(1.0, -2.0, 0.6))
    base = compose(grid.origin, [3.1, 2.4, -1.0])
    mount = np.array([0.2, -0.05, 0.3])
    laser = compose(base, mount)
    scan = synthetic_scan(grid, laser, np.random.default_rng(4), n=360)
    res = global_search(grid, scan, laser_pose=mount)
    assert res.complete
    assert len(res.candidates) == 1
    # off the lattice (half a cell in x and y): the heading that makes up for it is a step or
    # two away
    assert _near(res.candidates[0].pose, base, 2 * grid.resolution, math.radians(1.0))
    # without the mount pose the search finds the laser's pose instead
    res2 = global_search(grid, scan)
    assert _near(res2.candidates[0].pose, laser, 2 * grid.resolution, math.radians(1.0))


def test_a_prior_window_keeps_only_the_copy_inside_it() -> None:
    room = regular_polygon_room(4, 3.5)
    grid = _room_grid(room)
    truth = np.array([room.center[0] + 0.9, room.center[1] - 0.5, 0.4])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 0, noise=False)
    cfg = GlobalSearchConfig(linear_window=0.5, angular_window=math.radians(20.0))
    res = global_search(grid, scan, config=cfg, prior=truth + np.array([0.2, -0.1, 0.1]))
    assert res.complete
    assert len(res.candidates) == 1
    assert _near(res.candidates[0].pose, truth, 0.1, res.angular_step + 1e-9)
    assert res.n_positions < int(grid.free_mask.sum())


# --------------------------------------------------------------------------- budgets
def _square_case() -> tuple[OccupancyGrid, LaserScan]:
    room = regular_polygon_room(4, 3.5)
    truth = np.array([room.center[0] + 0.9, room.center[1] - 0.5, 0.4])
    return _room_grid(room), simulate_scan(room.world, truth, RPLIDAR_A2, 0, noise=False)


def test_the_node_budget_returns_an_incomplete_result() -> None:
    grid, scan = _square_case()
    full = global_search(grid, scan)
    assert full.complete
    cut = global_search(grid, scan, config=GlobalSearchConfig(max_nodes=full.n_nodes // 2))
    assert not cut.complete
    assert cut.verdict == "incomplete"
    assert "max_nodes" in cut.reason
    assert cut.n_nodes <= full.n_nodes // 2
    roots = global_search(grid, scan, config=GlobalSearchConfig(max_nodes=10))
    assert not roots.complete
    assert "roots exceed max_nodes=10" in roots.reason
    assert roots.candidates == ()
    assert roots.n_nodes == 0


def test_the_time_budget_returns_an_incomplete_result(monkeypatch: pytest.MonkeyPatch) -> None:
    grid, scan = _square_case()
    monkeypatch.setattr(gs, "_CHUNK_NODES", 1)  # check the clock after every root
    res = global_search(grid, scan, config=GlobalSearchConfig(max_seconds=1e-9))
    assert not res.complete
    assert "max_seconds" in res.reason


def test_too_many_poses_within_the_margin_is_incomplete() -> None:
    grid, scan = _square_case()
    res = global_search(grid, scan, config=GlobalSearchConfig(max_hits=5))
    assert not res.complete
    assert "max_hits=5" in res.reason
    capped = global_search(grid, scan, config=GlobalSearchConfig(max_candidates=2))
    assert capped.complete
    assert len(capped.candidates) == 2
    assert capped.n_distinct == 3  # counted up to max_candidates + 1
    assert capped.truncated
    assert not global_search(grid, scan).truncated


def test_headings_searched_on_several_threads_give_the_same_hits(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each thread prunes with its own threshold (never above the final one): the merged hits
    are the exhaustive search's."""
    from symloc.mcl import kernels

    grid = asymmetric_room()
    pose = np.array([2.2, 3.1, -0.7])
    pts = _rays(grid, pose, 90, 6.0)
    cfg = GlobalSearchConfig(angular_step=math.radians(4.0), min_score=0.3, score_margin=0.3)
    search = GlobalSearch(grid, cfg)
    ref = search.hits(pts, exhaustive=True)
    monkeypatch.setattr(kernels, "PARALLEL_MIN_PAIRS", 0)
    monkeypatch.setattr(kernels, "n_threads", lambda: 3)
    par = search.hits(pts)
    assert par.complete
    assert par.best == ref.best
    assert par.key_set() == ref.key_set()
