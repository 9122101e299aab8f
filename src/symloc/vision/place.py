"""A symmetric place and its stored views: the one record the visual map, the orientation
decision and the localizer all use.

:class:`~symloc.vision.visual_map.VisualMap` reads places (with their images) from its database;
:func:`~symloc.vision.orientation.decide_orientation` compares a query image with their stored
views; the localizer (:mod:`symloc.localizer`) reads the geometry (``center``, ``heading0``,
``m``, ``order``, ``gv_distance``, ``kind``, ``heading_reliable``) and never the images, so a
store without a database may build places with ``images=()``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.symmetry.order import SymmetryOrder

if TYPE_CHECKING:
    from symloc.vision.bow import BowVector
    from symloc.vision.orb import OrbFeatures

__all__ = ["UNANCHORED_LABEL", "Place", "PlaceImage"]

#: Label of a place whose stored headings came from odometry alone (``heading_reliable`` False).
UNANCHORED_LABEL = "heading-from-odometry"

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class PlaceImage:
    """One stored view of a place.

    Attributes
    ----------
    direction : int
        Clockwise index j in 0..M-1.
    heading : float
        Map heading [rad] the camera looked along.
    features : OrbFeatures
    bow : BowVector
    image : (H, W) or (H, W, 3) uint8 array or None
        Kept only when asked (it dominates the storage).
    """

    direction: int
    heading: float
    features: OrbFeatures
    bow: BowVector
    image: NDArray[np.uint8] | None = None


@dataclass(frozen=True, slots=True, eq=False)
class Place:
    """A symmetric place: its geometry, its G-V key and (when loaded) its M views.

    The ``m`` views were taken at the centre clockwise, view ``j`` nominally at
    ``heading0 - j * 2 pi / m`` (each :class:`PlaceImage` holds its measured heading).
    Equality is identity (``eq=False``): ``center`` is an array.

    Attributes
    ----------
    place_id : int
        The place's id in its store (the visual map's ``places.id``).
    center : ndarray of shape (2,)
        Centre x [m], y [m] in the map frame.
    heading0 : float
        Map-frame heading [rad] of direction 0 (stored view 0).
    m : int
        M, the number of stored directions, also when ``images`` were not loaded.
    order : SymmetryOrder
        Symmetry order k, or :data:`SymmetryOrder.CIRCLE` for a round room (an int is taken
        as a finite order ``k >= 1``). The visual map's column stores ``m`` for a circle (it
        needs an integer >= 1); :meth:`~symloc.vision.visual_map.VisualMap.place` turns it back.
    gv_distance : float
        G-V distance [m], the key of the G-V index.
    kind : str
        e.g. ``"square"``, ``"polygon"``, ``"circle"``, ``"rectangle"``.
    heading_reliable : bool
        False when the mapping pose could not observe heading there (laser SLAM in a round
        room carries only odometry's heading; stored with the label :data:`UNANCHORED_LABEL`):
        a decision at such a place gives a direction but not a pose the localizer may claim.
    images : tuple of PlaceImage
        The stored views in clockwise order (direction 0..M-1), or ``()`` when not loaded.
    label : str or None
        Free text stored with the place.
    """

    place_id: int
    center: FloatArray
    heading0: float
    m: int
    order: SymmetryOrder
    gv_distance: float
    kind: str = "polygon"
    heading_reliable: bool = True
    images: tuple[PlaceImage, ...] = ()
    label: str | None = None

    def __post_init__(self) -> None:
        # np.asarray returns a float64 array unchanged (same object, same bits).
        center = np.asarray(self.center, dtype=np.float64)
        if center.shape != (2,):
            raise ConfigurationError(
                f"Place.center: expected shape (2,) x, y, got {center.shape} "
                f"(place {self.place_id})"
            )
        object.__setattr__(self, "center", center)
        if not isinstance(self.order, SymmetryOrder):
            try:
                object.__setattr__(self, "order", SymmetryOrder.finite(self.order))
            except ConfigurationError as err:
                raise ConfigurationError(
                    f"Place.order: expected a SymmetryOrder or an integer k >= 1, got "
                    f"{self.order!r} (place {self.place_id})"
                ) from err
        if self.m < 0:
            raise ConfigurationError(f"Place.m: expected >= 0, got {self.m}")
        if self.images and len(self.images) != self.m:
            raise ConfigurationError(
                f"Place.images: {len(self.images)} views for m = {self.m} directions "
                f"(place {self.place_id})"
            )

    @property
    def pose(self) -> FloatArray:
        """Map pose ``(3,)`` of the centre facing direction 0: x [m], y [m], heading0 [rad]."""
        return np.array([self.center[0], self.center[1], self.heading0], dtype=np.float64)
