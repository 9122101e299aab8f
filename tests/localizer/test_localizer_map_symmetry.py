"""A symmetric map keeps a converged AMCL pose unearned (the 40 m hallway case)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.grid.fields import MapFields
from symloc.localizer import (
    Hypothesis,
    Localizer,
    LocalizerConfig,
    Status,
    SymmetryVerdict,
    TrackerResult,
    map_symmetry,
)
from symloc.localizer.map_symmetry import PARTIAL_OVERLAP, MapSymmetry, map_symmetries
from symloc.odometry import OdometryReading
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import build_room, hallway, l_shaped_room
from symloc.symmetry.order import SymmetryOrder


def test_map_symmetries_of_a_hallway_and_an_l_shape():
    hall = world_to_grid(hallway(20.0, 2.0).world, 0.05)
    found = map_symmetries(hall)
    assert [m.order for m in found] == [2]
    assert np.allclose(found[0].centre, [0.0, 0.0], atol=0.05)
    ell = world_to_grid(l_shaped_room(4.0).world, 0.05)
    assert map_symmetries(ell, min_overlap=0.9) == []
    # an L is three quarters of a square: a near symmetry of order 4, not an exact one
    assert [(m.order, m.overlap < 0.75) for m in map_symmetries(ell)] == [(4, True)]
    square = world_to_grid(build_room("square", 2.0, lab=False).world, 0.05)
    assert {m.order for m in map_symmetries(square, min_overlap=0.9)} == {2, 4}


def test_map_symmetries_rejects_bad_settings():
    grid = world_to_grid(hallway(10.0, 2.0).world, 0.05)
    with pytest.raises(ConfigurationError, match="tolerance"):
        map_symmetries(grid, tolerance=0.0)
    with pytest.raises(ConfigurationError, match="min_overlap"):
        map_symmetries(grid, min_overlap=1.5)
    with pytest.raises(ConfigurationError, match="min_partial"):
        map_symmetries(grid, min_overlap=0.6, min_partial=0.7)


def _walls(segments, lo, hi, res=0.05) -> OccupancyGrid:
    """A grid [lo, hi] x [lo, hi] (m) whose occupied cells are the wall ``segments``
    ((x0, y0), (x1, y1)) [m], one cell thick; the rest free."""
    n = round((hi - lo) / res)
    data = np.zeros((n, n), np.int8)
    for a, b in segments:
        a, b = np.asarray(a, float), np.asarray(b, float)
        t = np.linspace(0.0, 1.0, int(2 * np.hypot(*(b - a)) / res) + 2)
        cells = np.floor((a + t[:, None] * (b - a) - lo) / res).astype(int)
        data[cells[:, 1], cells[:, 0]] = 100
    return OccupancyGrid(data, res, np.array([lo, lo, 0.0]))


def _box(x0, y0, x1, y1):
    return [((x0, y0), (x1, y0)), ((x1, y0), (x1, y1)), ((x1, y1), (x0, y1)), ((x0, y1), (x0, y0))]


def test_a_box_off_centre_does_not_pull_the_centre_off_a_square():
    # a 4 m square about the origin with a 0.8 m box near a corner: the occupied cells'
    # centroid lies 0.3 m towards the box, where a quarter turn overlaps half the walls
    grid = _walls(_box(-2, -2, 2, 2) + _box(0.8, 0.7, 1.6, 1.5), -2.5, 2.5)
    found = {s.order: s for s in map_symmetries(grid, (2, 4)) if not s.partial}
    for k in (4, 2):
        assert found[k].overlap > 0.8
        assert np.hypot(*found[k].centre) <= 2 * grid.resolution


def test_the_bar_of_a_t_is_a_partial_symmetry():
    # a 10 m x 2.5 m bar (centre (0, 1.25)) with a 3 m x 5 m stem below it, off the middle
    tee = [
        ((-5, 2.5), (5, 2.5)),
        ((-5, 0), (-5, 2.5)),
        ((5, 0), (5, 2.5)),
        ((-5, 0), (0.5, 0)),
        ((3.5, 0), (5, 0)),
        ((0.5, 0), (0.5, -5)),
        ((3.5, 0), (3.5, -5)),
        ((0.5, -5), (3.5, -5)),
    ]
    grid = _walls(tee, -5.5, 5.5)
    assert map_symmetries(grid) == []  # no whole-map symmetry
    found = [s for s in map_symmetries(grid, min_partial=PARTIAL_OVERLAP) if s.order == 2]
    bar = min(found, key=lambda s: float(np.hypot(*(s.centre - [0.0, 1.25]))))
    assert bar.partial
    assert PARTIAL_OVERLAP <= bar.overlap < 0.6
    assert np.hypot(*(bar.centre - [0.0, 1.25])) <= 2 * grid.resolution


def test_a_corridor_has_one_centre_and_a_coarse_search_finds_it_too(monkeypatch):
    """A corridor's centres along its axis all overlap well (a ridge): one is reported. A map
    too large for one correlation at full resolution (MAX_FFT_CELLS) is searched on coarser
    cells first, and gives the same centre."""
    grid = world_to_grid(hallway(30.0, 2.0).world, 0.05)
    fine = map_symmetries(grid, (2, 3, 4), min_partial=PARTIAL_OVERLAP)
    assert [s.order for s in fine] == [2]
    monkeypatch.setattr(map_symmetry, "MAX_FFT_CELLS", 20_000)
    coarse = map_symmetries(grid, (2, 3, 4), min_partial=PARTIAL_OVERLAP)
    assert [s.order for s in coarse] == [2]
    assert np.hypot(*(coarse[0].centre - fine[0].centre)) <= 2 * grid.resolution
    assert coarse[0].overlap == pytest.approx(fine[0].overlap, abs=0.01)


class _Tracker:
    def __init__(self, result: TrackerResult) -> None:
        self.result = result

    def initialize_global(self) -> None:
        pass

    def initialize_pose(self, pose, covariance) -> None:
        pass

    def force_update(self) -> None:
        pass

    def update(self, odom, scan) -> TrackerResult:
        return self.result


class _Store:
    def candidates(self, gv_distance, order):
        return []


def _asym(scan) -> SymmetryVerdict:
    return SymmetryVerdict(
        False, SymmetryOrder.finite(1), "asymmetric", None, math.nan, reason="one end seen"
    )


@pytest.mark.parametrize("copy_fits", [True, False])
def test_converged_pose_is_earned_only_when_no_map_copy_fits(copy_fits):
    pose = np.array([15.0, 0.3, 0.2])
    cov = np.diag([0.02**2, 0.02**2, math.radians(1.0) ** 2])
    result = TrackerResult(pose, cov, (Hypothesis(pose, 1.0),), confident=True)

    def scorer(poses, scan):
        return np.array([1.0] + [0.95 if copy_fits else 0.2] * (len(poses) - 1))

    loc = Localizer(
        _Tracker(result),
        _asym,
        _Store(),
        LocalizerConfig(decide_here=False),  # the paper's path's copy check
        scorer=scorer,
        map_symmetries=[MapSymmetry(np.zeros(2), 2, 1.0)],
    )
    loc.reset_global()
    ests = [loc.update(OdometryReading(np.zeros(3)), None) for _ in range(6)]
    if copy_fits:
        assert all(e.status is Status.AMBIGUOUS and e.pose is None for e in ests)
        assert ests[-1].order == SymmetryOrder.finite(2)
        mirrored = ests[-1].hypotheses[1].pose
        assert np.allclose(mirrored[:2], [-15.0, -0.3])
    else:
        assert ests[-1].status is Status.TRACKING
        assert np.allclose(ests[-1].pose, pose)


@pytest.mark.parametrize("b", [2, 4, 8])
def test_coarse_counts_bound_every_shift_of_their_block(b):
    """The coarse correlation must never count fewer cells than any shift of its block
    (else the coarse search, and the screen that skips an order, would miss a symmetry);
    checked on every order and every shift of an asymmetric map, near its edges too."""
    data = np.zeros((60, 80), np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100
    data[15:25, 20:30] = 100
    data[40:43, 50:70] = 100
    grid = OccupancyGrid(data, 0.05)
    cells = map_symmetry._Cells.of(grid, MapFields.of(grid).obstacle_distance() <= 0.1, 3)
    for k in range(2, 13):
        turned = np.floor(cells.xy @ map_symmetry._rotation(k).T + 0.5).astype(np.intp)
        fine, lo = map_symmetry._shift_counts(cells, turned, 1)
        coarse, clo = map_symmetry._shift_counts(cells, turned, b)
        rows, cols = np.nonzero(fine > 0)
        block = np.floor_divide(np.column_stack([cols, rows]) + lo, b) - clo
        assert np.all(fine[rows, cols] <= coarse[block[:, 1], block[:, 0]])


def test_a_partial_symmetry_needs_its_centre_in_the_free_space():
    """A 10 m corridor (free inside, unknown outside; 59 % of the walls) and a 4 m x 3 m box
    in the unknown beside it (41 %): the box turns onto itself about a point the robot is never
    at and is left out; the corridor's half turn stays."""
    walls = [((-5, -1), (5, -1)), ((-5, 1), (5, 1)), *_box(-2, 2, 2, 5)]
    data = _walls(walls, -6.0, 6.0).data.copy()
    data[data == 0] = -1
    rows, cols = slice(round(5.05 / 0.05), round(6.95 / 0.05)), slice(20, 220)
    data[rows, cols][data[rows, cols] != 100] = 0  # the corridor's inside
    grid = OccupancyGrid(data, 0.05, np.array([-6.0, -6.0, 0.0]))
    found = map_symmetries(grid, (2,), min_partial=PARTIAL_OVERLAP)
    assert len(found) == 1
    assert found[0].partial
    assert np.hypot(*found[0].centre) <= 2 * grid.resolution
    data[data == -1] = 0  # the box's centre free: it is found
    free = map_symmetries(OccupancyGrid(data, 0.05, grid.origin), (2,), min_partial=0.4)
    assert any(np.hypot(*(s.centre - [0.0, 3.5])) <= 0.1 for s in free)


def test_window_counts_by_fft_equal_the_direct_counts(monkeypatch: pytest.MonkeyPatch) -> None:
    from symloc.localizer import map_symmetry as ms

    rng = np.random.default_rng(2)
    hits = rng.random((1500, 700)) < 0.2  # more than one FFT tile each way
    size = 24
    cells = np.column_stack(
        [rng.integers(-size - 3, 700 + 3, 5000), rng.integers(-size - 3, 1500 + 3, 5000)]
    ).astype(np.intp)
    monkeypatch.setattr(ms, "DIRECT_WINDOW_WORK", 1 << 62)
    direct = ms._window_counts(hits, cells, size)
    assert direct.shape == (size, size)
    monkeypatch.setattr(ms, "WINDOW_BYTES", 1 << 12)  # the direct sum in many parts
    assert np.array_equal(ms._window_counts(hits, cells, size), direct)
    monkeypatch.setattr(ms, "DIRECT_WINDOW_WORK", 0)
    assert np.array_equal(ms._window_counts(hits, cells, size), direct)


def _polygon(n: int, radius: float, centre=(0.0, 0.0), turn: float = 0.0):
    a = turn + 2.0 * np.pi * np.arange(n + 1) / n
    p = np.column_stack([np.cos(a), np.sin(a)]) * radius + np.asarray(centre)
    return [(tuple(p[i]), tuple(p[i + 1])) for i in range(n)]


@pytest.mark.parametrize(
    ("sides", "radius", "round_"),
    [(96, 3.0, True), (9, 2.0, False), (12, 3.0, False), (4, 3.0, False)],
)
def test_a_circle_is_round_and_a_polygon_is_not(sides, radius, round_):
    centre = (0.4, -0.3)
    grid = _walls(_polygon(sides, radius, centre, turn=0.1), -4.0, 4.0)
    found = map_symmetry.round_centre(grid, map_symmetries(grid))
    if round_:
        assert found is not None
        assert np.hypot(*(found - centre)) < 0.05
    else:
        assert found is None


def test_a_circle_with_a_box_inside_is_still_round():
    grid = _walls(_polygon(96, 3.0) + _box(1.0, 0.2, 1.3, 0.5), -4.0, 4.0)
    assert map_symmetry.round_centre(grid, map_symmetries(grid)) is not None


def _shelf_against_the_wall(radius: float, width: float, depth: float) -> OccupancyGrid:
    """A round room of ``radius`` [m] about the origin with a shelf ``width`` x ``depth`` [m]
    against its wall at +x, the wall behind the shelf unseen (as laser SLAM maps it)."""
    back = math.sqrt(radius**2 - (width / 2) ** 2)
    front = back - depth
    grid = _walls(
        _polygon(96, radius)
        + [((front, -width / 2), (front, width / 2))]
        + [((front, y), (back, y)) for y in (-width / 2, width / 2)],
        -radius - 1.0,
        radius + 1.0,
    )
    occupied = np.argwhere(grid.data == 100)
    xy = grid.cell_to_world(occupied)
    hidden = (xy[:, 0] > back) & (np.abs(xy[:, 1]) < width / 2 - grid.resolution)
    data = grid.data.copy()
    data[occupied[hidden, 0], occupied[hidden, 1]] = 0
    return OccupancyGrid(data, grid.resolution, grid.origin)


def test_a_round_room_with_a_shelf_against_its_wall_is_round():
    grid = _shelf_against_the_wall(3.0, 2.0, 0.5)
    syms = map_symmetries(grid)
    fields = MapFields.of(grid)
    cells = map_symmetry._Cells.of(fields.grid, fields.near_obstacle(0.05), 2)
    # the whole map no longer overlaps itself turned (the shelf and the wall it hides) ...
    assert map_symmetry._overlap(grid, cells, map_symmetry.ROUND_TURNS[0], np.zeros(2)) < 0.88
    # ... its enclosing wall does, but for the shelf's sectors
    found = map_symmetry.round_centre(grid, syms)
    assert found is not None
    assert np.hypot(*found) < 0.05
    share = map_symmetry._round_wall_share(grid, cells, found, 0.88)
    assert map_symmetry.ROUND_WALL_SHARE <= share < 1.0


def test_a_room_half_round_half_square_is_not_round():
    # a semicircle of radius 3 m closed by three sides of a 6 m x 3 m rectangle: its straight
    # walls show the laser (and SLAM) the turn about the centre
    half = [s for s in _polygon(96, 3.0) if s[0][1] >= -1e-9 and s[1][1] >= -1e-9]
    square = [((-3, 0), (-3, -3)), ((-3, -3), (3, -3)), ((3, -3), (3, 0))]
    grid = _walls([*half, *square], -4.0, 4.0)
    assert map_symmetry.round_centre(grid, [MapSymmetry(np.zeros(2), 12, 0.9)]) is None
