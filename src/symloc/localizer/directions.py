"""How many images a symmetric place keeps (M in Algorithm 3)."""

from __future__ import annotations

from symloc.errors import ConfigurationError
from symloc.symmetry.order import SymmetryOrder

__all__ = ["directions_for"]


def directions_for(kind: str, order: SymmetryOrder) -> int:
    """M, the number of images stored for a place.

    A regular k-gon: k (one per wall middle). A rectangle or hallway: 4 (its wall middles are
    90 degrees apart seen from the centre). A circle: 8, so that any query heading is
    within 22.5 degrees of a stored view and the homography can still measure the offset.
    """
    if kind == "circle" or order.k is None:
        return 8
    if kind in ("rectangle", "hallway"):
        return 4
    if order.k < 2:
        raise ConfigurationError(f"directions_for: order must be a circle or >= 2, got {order}")
    return order.k
