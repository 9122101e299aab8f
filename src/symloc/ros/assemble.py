"""Assemble a :class:`~symloc.localizer.Localizer` from a map and the node's parameters.

AMCL (:class:`symloc.mcl.Amcl` with the nav2 parameters), Algorithm 1
(:func:`symloc.symmetry.judge_symmetry`), the grid scorer and the visual map, joined by the
localizer's own adapters. The localizer starts from a global initialisation (nothing earned).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.camera_model import pinhole_matrix
from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.grid.distance_field import surface_distance_field
from symloc.localizer import Decision, Localizer, Place
from symloc.localizer.claim import ClaimGate
from symloc.localizer.map_symmetry import map_symmetries
from symloc.localizer.types import DecisionStatus
from symloc.ros.params import NodeParams
from symloc.symmetry.order import SymmetryOrder

__all__ = ["MemoryPlaces", "camera_matrix", "make_localizer", "open_places"]


class MemoryPlaces:
    """A place store with no visual map: nothing matches; mapped places live in memory only."""

    def __init__(self) -> None:
        self.places: list[Place] = []

    def candidates(self, gv_distance: float, order: SymmetryOrder) -> Sequence[Place]:
        """No stored place can decide anything (their images are not kept)."""
        return []

    def decide(self, place: Place, image: NDArray[np.uint8]) -> Decision:
        """Never called (no candidates); answers ``no_match``."""
        return Decision(status=DecisionStatus.NO_MATCH, reason="no visual map loaded")

    def add_place(
        self,
        center: Any,
        heading0: float,
        order: SymmetryOrder,
        gv_distance: float,
        kind: str,
        images: Sequence[NDArray[np.uint8]],
        headings: Sequence[float] | None = None,
    ) -> Place:
        """Remember the place's geometry (images and their ``headings`` are dropped: no
        database to store them)."""
        place = Place(
            place_id=len(self.places) + 1,
            center=np.asarray(center, dtype=np.float64),
            heading0=float(heading0),
            m=len(images),
            order=0 if order.k is None else order.k,  # Place.order: 0 for a circle
            gv_distance=float(gv_distance),
            kind=kind,
        )
        self.places.append(place)
        return place


def camera_matrix(params: NodeParams) -> NDArray[np.float64]:
    """The (3, 3) intrinsics from ``params.camera_intrinsics`` (default: 640 x 480, 65 deg HFOV)."""
    if not params.camera_intrinsics:
        return pinhole_matrix()
    fx, fy, cx, cy = params.camera_intrinsics
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def open_places(params: NodeParams) -> Any:
    """The place store for ``params.visual_map`` (``""``: :class:`MemoryPlaces`).

    In ``localize`` mode the visual map is opened read-only.

    Raises
    ------
    ConfigurationError
        The file is missing in ``localize`` mode, or the map records another vocabulary than
        ``params.vocabulary``.
    """
    path = params.visual_map
    if not path:
        return MemoryPlaces()
    from pathlib import Path

    from symloc.localizer.vision_store import VisionPlaceStore
    from symloc.vision import VisualMap, Vocabulary

    if not params.allow_mapping and not Path(path).is_file():
        raise ConfigurationError(f"visual_map: {path} does not exist (mode localize)")
    from symloc.vision.default_vocabulary import default_vocabulary

    vocab = Vocabulary.load(params.vocabulary) if params.vocabulary else default_vocabulary()
    vmap = VisualMap(path, create=params.allow_mapping, readonly=not params.allow_mapping)
    stored = vmap.get_meta("vocabulary")
    want = default_vocabulary().fingerprint() if stored == "default" else stored
    if want is not None and want.startswith("sha256:") and want != vocab.fingerprint():
        vmap.close()
        made = "the shipped vocabulary" if stored == "default" else want[:19] + "..."
        raise ConfigurationError(
            f"vocabulary: the visual map {path} was made with {made}, not with"
            f" {params.vocabulary or 'the shipped vocabulary'}; set 'vocabulary' to its file"
        )
    return VisionPlaceStore(
        vmap, vocab, camera_matrix(params), dist_coeffs=params.camera_dist_coeffs or None
    )


def make_localizer(grid: OccupancyGrid, params: NodeParams, *, places: Any = None) -> Localizer:
    """A globally initialised localizer on ``grid`` configured by ``params``.

    AMCL draws from ``numpy.random.default_rng(params.seed)``, so two localizers made with the
    same parameters and fed the same messages give the same estimates. ``params.laser_pose``
    (the laser on the robot; the node sets it from TF) goes to every part that reads scans:
    AMCL, Algorithm 1's verdicts (turned into the robot frame), the scorer, the claim gate and
    the localizer's deskewing. Scans of an upside-down laser arrive mirrored (the node does it).
    """
    from symloc.localizer.adapters import AmclTracker, GridScorer, ReportJudge
    from symloc.mcl.amcl import Amcl
    from symloc.symmetry import judge_symmetry

    amcl = Amcl(grid, params.amcl, rng=np.random.default_rng(params.seed))
    laser = np.asarray(params.laser_pose, dtype=np.float64)
    store = places if places is not None else open_places(params)
    known = list(store.all_places()) if hasattr(store, "all_places") else []
    config = dataclasses.replace(params.localizer, allow_mapping=params.allow_mapping)
    loc = Localizer(
        AmclTracker(amcl, laser_pose=laser),
        ReportJudge(judge_symmetry, laser_pose=laser, config=params.symmetry_config()),
        store,
        config,
        scorer=GridScorer(grid, laser_pose=laser),
        known_places=known,
        map_symmetries=map_symmetries(grid),
        claim_gate=ClaimGate(surface_distance_field(grid), laser_pose=laser),
        laser_pose=laser,
    )
    loc.reset_global()
    return loc
