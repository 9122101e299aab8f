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

from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.localizer import Decision, Localizer, Place
from symloc.ros.params import NodeParams

__all__ = ["MemoryPlaces", "make_localizer", "open_places"]


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


def open_places(path: str, *, create: bool) -> Any:
    """The place store for a visual-map file (``""``: :class:`MemoryPlaces`).

    Raises
    ------
    ConfigurationError
        The file is missing (and ``create`` is False) or the visual-map adapter is unavailable.
    """
    if not path:
        return MemoryPlaces()
    from pathlib import Path

    if not create and not Path(path).is_file():
        raise ConfigurationError(f"visual_map: {path} does not exist (mode localize)")
    try:
        from symloc.localizer.adapters import VisualMapStore  # type: ignore[attr-defined]
    except ImportError as err:
        raise ConfigurationError(
            "visual_map: symloc.localizer.adapters.VisualMapStore is not available in this"
            " version; run without a visual map"
        ) from err
    from symloc.vision.visual_map import VisualMap

    return VisualMapStore(VisualMap(path, create=create))


def make_localizer(grid: OccupancyGrid, params: NodeParams, *, places: Any = None) -> Localizer:
    """A globally initialised localizer on ``grid`` configured by ``params``."""
    from symloc.localizer.adapters import AmclTracker, GridScorer, ReportJudge
    from symloc.mcl.amcl import Amcl
    from symloc.symmetry import judge_symmetry

    amcl = Amcl(grid, params.amcl, rng=np.random.default_rng(params.seed))
    store = (
        places
        if places is not None
        else open_places(params.visual_map, create=params.allow_mapping)
    )
    config = dataclasses.replace(params.localizer, allow_mapping=params.allow_mapping)
    loc = Localizer(
        AmclTracker(amcl), ReportJudge(judge_symmetry), store, config, scorer=GridScorer(grid)
    )
    loc.reset_global()
    return loc
