"""The one function that builds the localizer, for every caller (rule 12).

:func:`build_localizer` joins AMCL (:class:`symloc.mcl.Amcl`), Algorithm 1
(:func:`symloc.symmetry.judge_symmetry`), the grid scorer, the map's own symmetries, the claim
gate and a place store with the localizer's adapters, every part configured from one
:class:`~symloc.localizer.settings.LocalizerSettings`. The ROS node and bag replay
(:func:`symloc.ros.assemble.make_localizer`), the bench and the demo
(:meth:`symloc.bench.scenario.Scenario.localizer`) and the experiments
(:func:`symloc.experiments.amcl_carmen.symloc_claims`) all call it: what the bench measures is
what ``symloc ros node`` runs when both are given the same settings.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError

from symloc.grid import OccupancyGrid
from symloc.grid.fields import MapFields
from symloc.grid.map_error_field import MapErrorField
from symloc.localizer.adapters import (
    AmclTracker,
    GlobalSearchProposer,
    GridScorer,
    ReportJudge,
)
from symloc.localizer.claim import ClaimConfig, ClaimGate
from symloc.localizer.localizer import Localizer
from symloc.localizer.map_symmetry import (
    PARTIAL_OVERLAP,
    MapSymmetry,
    map_symmetries,
    round_centre,
)
from symloc.localizer.places import MemoryPlaces
from symloc.localizer.settings import LocalizerSettings
from symloc.localizer.types import KeyframeStore, PlaceStore, PoseProposer, Proposal
from symloc.mcl.amcl import Amcl
from symloc.mcl.global_search import GlobalSearch
from symloc.symmetry import judge_symmetry

__all__ = ["LazyProposer", "build_localizer", "enclosed_centroid", "grid_symmetries"]

FloatArray = NDArray[np.float64]
logger = logging.getLogger(__name__)


def grid_symmetries(grid: OccupancyGrid) -> list[MapSymmetry]:
    """:func:`~symloc.localizer.map_symmetry.map_symmetries` of ``grid``, the partial near
    symmetries included (down to
    :data:`~symloc.localizer.map_symmetry.PARTIAL_OVERLAP`), computed once per map and kept
    with its other derived fields (:meth:`MapFields.derived`)."""
    return MapFields.of(grid).derived("map_symmetries", _with_partial)


def _with_partial(grid: OccupancyGrid) -> list[MapSymmetry]:
    return map_symmetries(grid, min_partial=PARTIAL_OVERLAP)


def grid_round_centre(grid: OccupancyGrid) -> FloatArray | None:
    """:func:`~symloc.localizer.map_symmetry.round_centre` of ``grid`` (None: not round),
    computed once per map and kept with its other derived fields, as
    :func:`grid_symmetries`."""
    return MapFields.of(grid).derived("round_centre", lambda g: round_centre(g, grid_symmetries(g)))


def build_localizer(
    grid: OccupancyGrid,
    settings: LocalizerSettings,
    *,
    places: PlaceStore | None = None,
    rng: np.random.Generator | None = None,
    keyframes: KeyframeStore | None = None,
    map_std_xy: float | None = None,
    map_rotation_std: float | None = None,
    map_error_field: MapErrorField | None = None,
) -> Localizer:
    """The localizer on ``grid`` configured by ``settings``; not initialised yet.

    Parameters
    ----------
    grid : OccupancyGrid
        The map (AMCL's, the scorer's, the claim gate's and the map-symmetry search's).
    settings : LocalizerSettings
        Every setting (:mod:`symloc.localizer.settings`).
    places : PlaceStore, optional
        Where places are looked up and mapped (a
        :class:`~symloc.localizer.vision_store.VisionPlaceStore` over a visual map); None: a
        :class:`~symloc.localizer.places.MemoryPlaces` (no visual map). Its stored places
        (``all_places()``) are the localizer's known places.
    rng : numpy.random.Generator, optional
        AMCL's random numbers; None: ``numpy.random.default_rng(settings.seed)``. The bench
        passes the generator its trial draws everything from.
    keyframes : KeyframeStore, optional
        The visual map's keyframes (a :class:`~symloc.localizer.vision_store.VisionPlaceStore`
        is one), for deciding where the robot stands (``settings.localizer.decide_here``, which
        also builds the global scan-to-map search on ``grid``). Unused when that is off.
    map_std_xy : float, optional
        The map's own position error [m] (std) as the SLAM that built it estimated it
        (:mod:`symloc.slam.map_error`; a saved map's ``symloc_slam.map_error.std_xy``,
        :func:`symloc.grid.map_io.read_map_error`). The claim gate adds the larger of it and
        ``settings.claim.map_std_xy`` to every match's covariance, so on a map that disagrees
        with itself claims are withheld rather than wrong.
    map_rotation_std : float, optional
        A round map's rotation error about its centre [rad] (std) as measured where it was
        built (a visual map's declaration,
        :func:`symloc.vision.gyro_drift.declared_rotation_std`); it replaces the assumed
        ``settings.claim.map_rotation_std``.
    map_error_field : MapErrorField, optional
        The map's position error place by place (:mod:`symloc.slam.pose_marginals`; a saved
        map's ``symloc_slam.map_error.field``, :attr:`symloc.grid.map_io.MapMetadata.map_error_field`):
        the claim gate reads it where it exceeds the other (``settings.claim.map_error_field``).

    The caller starts it: :meth:`Localizer.reset_global` (lost, AMCL over the whole map) or
    :meth:`Localizer.set_pose`. ``settings.laser_pose`` goes to every part that reads scans:
    AMCL, Algorithm 1's verdicts (turned into the robot frame), the scorer, the claim gate and
    the localizer's deskewing.
    """
    gen = np.random.default_rng(settings.seed) if rng is None else rng
    fields = MapFields.of(grid)  # every part below shares the map's fields
    amcl = Amcl(fields, settings.amcl, gen)
    laser = np.asarray(settings.laser_pose, dtype=np.float64)
    store = places if places is not None else MemoryPlaces()
    known = list(store.all_places())
    # a laser at the robot's origin needs no turning of the verdicts (bit for bit the same)
    judge_laser = laser if np.any(laser != 0.0) else None
    decide = settings.localizer.decide_here

    # the global search proposes poses to decide among, and shows that the robot is
    # elsewhere before the claim gate gives a tracked pose up; without deciding here it is
    # built on the gate's first question (its precomputation costs memory on a large map)
    def search() -> GlobalSearchProposer:
        return GlobalSearchProposer(GlobalSearch(fields), laser_pose=laser)

    proposer: PoseProposer = search() if decide else LazyProposer(search)
    return Localizer(
        AmclTracker(amcl, laser_pose=laser, confidence=settings.confidence),
        ReportJudge(judge_symmetry, laser_pose=judge_laser, config=settings.symmetry),
        store,
        settings.localizer,
        scorer=GridScorer(fields, laser_pose=laser),
        known_places=known,
        map_symmetries=grid_symmetries(grid),
        claim_gate=ClaimGate(
            fields.surface(),
            config=_with_map_error(settings.claim, map_std_xy, map_rotation_std),
            laser_pose=laser,
            scale_centre=fields.derived("enclosed_centroid", enclosed_centroid),
            rotation_centre=grid_round_centre(grid),
            proposer=proposer,
            map_error_field=map_error_field,
        ),
        laser_pose=laser,
        proposer=proposer if decide else None,
        keyframes=keyframes if decide else None,
        grid=grid,
    )


def enclosed_centroid(grid: OccupancyGrid) -> FloatArray:
    """The mean [m] (2,) of the centres of ``grid``'s free cells inside the convex hull of its
    occupied cells (map frame): the middle of the mapped room, where a map that is a scaled
    copy of the room is right (the claim gate's ``scale_centre``).

    Free cells outside the walls' hull are space seen through glass or an open door, out to
    the lidar's range: in a glass-walled trapezoid of the dev split (heavy regime) they moved
    the mean of all free cells 2 m off the room's middle, outside the room, and the claim gate
    then put the map's scale error where it is not (claims 4.5-5.6 cm off published with a
    covariance that covered none of them). Every free cell counts when the occupied cells span
    no area (fewer than three, or on one line) or enclose no free cell; the grid's centre when
    no cell is free. Strided on a large grid (its mean, not its cells, is wanted)."""
    free = grid.free_mask
    step = max(1, int(np.sqrt(free.size / 1_000_000)))
    rows, cols = np.nonzero(free[::step, ::step])
    if rows.size == 0:
        middle = [[0.5 * (grid.height - 1), 0.5 * (grid.width - 1)]]
        return np.asarray(grid.cell_to_world(middle)[0], dtype=np.float64)
    cells = np.column_stack([rows, cols]).astype(np.float64) * step
    inside = _inside_hull(cells, np.argwhere(grid.occupied_mask[::step, ::step]) * step)
    if np.any(inside):
        cells = cells[inside]
    mean = cells.mean(axis=0, keepdims=True)
    return np.asarray(grid.cell_to_world(mean)[0], dtype=np.float64)


def _inside_hull(points: FloatArray, hull_of: NDArray[np.int64]) -> NDArray[np.bool_]:
    """(N,) True where ``points`` (N, 2) lie in the convex hull of ``hull_of`` (M, 2) (cell
    indices, half a cell of slack: a wall cell's centre is on the hull); all False when the
    hull spans no area."""
    if hull_of.shape[0] < 3:
        return np.zeros(points.shape[0], dtype=bool)
    try:
        hull = ConvexHull(hull_of.astype(np.float64))
    except QhullError:  # on one line: no area
        return np.zeros(points.shape[0], dtype=bool)
    # facets as a.x + b <= 0 inside (unit normals): chunks keep the (N, facets) table small
    out = np.empty(points.shape[0], dtype=bool)
    normals, offsets = hull.equations[:, :2], hull.equations[:, 2]
    for lo in range(0, points.shape[0], 65536):
        chunk = points[lo : lo + 65536]
        out[lo : lo + 65536] = np.all(chunk @ normals.T + offsets <= 0.5, axis=1)
    return out


def _with_map_error(
    claim: ClaimConfig, map_std_xy: float | None, map_rotation_std: float | None
) -> ClaimConfig:
    """``claim`` with its map error raised to ``map_std_xy`` [m] when that is larger and its
    round-map rotation error replaced by ``map_rotation_std`` [rad] when given, logged."""
    raised = claim.with_map_error(map_std_xy)
    if raised is not claim:
        logger.info(
            "claim gate: the map's own error %.3f m (std) replaces the default %.3f m",
            raised.map_std_xy,
            claim.map_std_xy,
        )
    if map_rotation_std is not None:
        logger.info(
            "claim gate: a round map's rotation error %.2f deg (std, measured) replaces the "
            "assumed %.2f deg",
            math.degrees(map_rotation_std),
            math.degrees(claim.map_rotation_std),
        )
        raised = dataclasses.replace(raised, map_rotation_std=float(map_rotation_std))
    return raised


class LazyProposer:
    """A :class:`~symloc.localizer.types.PoseProposer` built on its first :meth:`propose`
    by ``make`` (a zero-argument callable)."""

    def __init__(self, make: Callable[[], PoseProposer]) -> None:
        self._make = make
        self._proposer: PoseProposer | None = None

    def propose(self, scan: object) -> Proposal:
        if self._proposer is None:
            self._proposer = self._make()
        return self._proposer.propose(scan)
