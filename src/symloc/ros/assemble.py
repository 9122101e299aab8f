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
from symloc.ros.params import NodeParams

__all__ = ["MemoryPlaces", "camera_matrix", "make_localizer", "open_places"]


class MemoryPlaces:
    """A place store with no visual map: nothing matches; mapped places live in memory only."""

    def __init__(self) -> None:
        self.places: list[Place] = []

    def candidates(self, gv_distance: float, order: int) -> Sequence[Place]:
        """No stored place can decide anything (their images are not kept)."""
        return []

    def decide(self, place: Place, image: NDArray[np.uint8]) -> Decision:
        """Never called (no candidates); answers ``no_match``."""
        return Decision(status="no_match", reason="no visual map loaded")

    def add_place(
        self,
        center: Any,
        heading0: float,
        order: int,
        gv_distance: float,
        kind: str,
        images: Sequence[NDArray[np.uint8]],
    ) -> Place:
        """Remember the place's geometry (images are dropped: no database to store them)."""
        place = Place(
            place_id=len(self.places) + 1,
            center=np.asarray(center, dtype=np.float64),
            heading0=float(heading0),
            m=len(images),
            order=int(order),
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

    Raises
    ------
    ConfigurationError
        The file is missing in ``localize`` mode.
    """
    path = params.visual_map
    if not path:
        return MemoryPlaces()
    from pathlib import Path

    from symloc.localizer.vision_store import VisionPlaceStore
    from symloc.vision import VisualMap, Vocabulary

    if not params.allow_mapping and not Path(path).is_file():
        raise ConfigurationError(f"visual_map: {path} does not exist (mode localize)")
    if params.vocabulary:
        vocab = Vocabulary.load(params.vocabulary)
    else:
        from symloc.vision.default_vocabulary import default_vocabulary

        vocab = default_vocabulary()
    return VisionPlaceStore(
        VisualMap(path, create=params.allow_mapping),
        vocab,
        camera_matrix(params),
        dist_coeffs=params.camera_dist_coeffs or None,
    )


def make_localizer(grid: OccupancyGrid, params: NodeParams, *, places: Any = None) -> Localizer:
    """A globally initialised localizer on ``grid`` configured by ``params``.

    AMCL draws from ``numpy.random.default_rng(params.seed)``, so two localizers made with the
    same parameters and fed the same messages give the same estimates.
    """
    from symloc.localizer.adapters import AmclTracker, GridScorer, ReportJudge
    from symloc.mcl.amcl import Amcl
    from symloc.symmetry import judge_symmetry

    amcl = Amcl(grid, params.amcl, rng=np.random.default_rng(params.seed))
    store = places if places is not None else open_places(params)
    known = list(store.all_places()) if hasattr(store, "all_places") else []
    config = dataclasses.replace(params.localizer, allow_mapping=params.allow_mapping)
    a = params.amcl
    loc = Localizer(
        AmclTracker(amcl),
        ReportJudge(judge_symmetry, config=params.symmetry_config()),
        store,
        config,
        scorer=GridScorer(grid),
        known_places=known,
        map_symmetries=map_symmetries(grid),
        claim_gate=ClaimGate(
            surface_distance_field(grid), (a.alpha1, a.alpha2, a.alpha3, a.alpha4)
        ),
    )
    loc.reset_global()
    return loc
