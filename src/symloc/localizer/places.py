"""A place store without a visual map (the node without ``visual_map``, the CARMEN logs)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.localizer.types import Decision, DecisionStatus, Place
from symloc.symmetry.order import SymmetryOrder

__all__ = ["MemoryPlaces"]


class MemoryPlaces:
    """A place store with no visual map: nothing matches; mapped places live in memory only."""

    def __init__(self) -> None:
        self.places: list[Place] = []

    def candidates(self, gv_distance: float, order: SymmetryOrder) -> Sequence[Place]:
        """No stored place can decide anything (their images are not kept)."""
        return []

    def all_places(self) -> list[Place]:
        """The places mapped so far (none at start-up: nothing is stored between runs)."""
        return list(self.places)

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
        """Remember the place's geometry (images are dropped: no database to store them).

        ``headings`` [rad] (one per image) are accepted as a visual map's store takes them and
        dropped with the images.
        """
        place = Place(
            place_id=len(self.places) + 1,
            center=np.asarray(center, dtype=np.float64),
            heading0=float(heading0),
            m=len(images),
            order=order,
            gv_distance=float(gv_distance),
            kind=kind,
        )
        self.places.append(place)
        return place
