"""``SymmetryReport``: the typed verdict of the symmetry judgement."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.symmetry.order import SymmetryOrder

__all__ = ["KINDS", "SymmetryReport"]

FloatArray = NDArray[np.float64]

#: Every value ``SymmetryReport.kind`` takes.
KINDS = ("polygon", "circle", "rectangle", "hallway", "asymmetric", "unknown")


def _frozen(a: Any, shape_tail: tuple[int, ...]) -> FloatArray:
    arr = np.array(a, dtype=np.float64).reshape((-1, *shape_tail) if shape_tail else (-1,))
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, slots=True, eq=False)
class SymmetryReport:
    """What one laser scan says about the symmetry of the room around the robot.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`:

        - ``"polygon"``: a polygonal room; ``regular`` tells whether it is a regular n-gon
          (then ``order.k == n``); a non-regular polygon may still have a rotational symmetry
          (e.g. a rhombus, order 2);
        - ``"circle"``: a round room (the paper's "n = infinity"),
          ``order is SymmetryOrder.CIRCLE``;
        - ``"rectangle"``: four right angles, unequal sides, order 2;
        - ``"hallway"``: two parallel walls whose ends the laser does not reach, order 2 about
          a centre whose position along the hallway is undetermined;
        - ``"asymmetric"``: the room was measured but no rotation other than the identity
          maps it onto itself (order 1), or the symmetry test failed (see ``reason``);
        - ``"unknown"``: the scan does not allow a verdict (too few points, walls beyond
          range, field of view under 360 degrees); no order (``order is None``).
    symmetric : bool
        True when more than one pose explains the scan (order > 1).
    order : SymmetryOrder or None
        Symmetry order k, how many poses explain the scan: n for a regular n-gon, 2 for a
        rectangle / hallway / rhombus, :data:`SymmetryOrder.CIRCLE` for a circle, 1 for
        asymmetric; None for unknown (no verdict is not an order).
    regular : bool
        Regular polygon (all sides and angles equal) or circle.
    center : ndarray of shape (2,)
        Centre of the symmetry in the sensor frame [m]: the mean of the corners for a polygon,
        the least-squares centre for a circle, the point of the hallway's mid-line nearest the
        sensor for a hallway; NaN when not symmetric.
    corners : ndarray of shape (K, 2)
        Corners (wall intersections) in scan order, sensor frame [m]; empty when none.
    gv_distance : float
        G-V distance [m] (centre to vertex; the radius of a circle); NaN when undefined.
    residual : float
        How far [m] the measured geometry is from the claimed symmetry: the largest corner
        displacement under the symmetry rotation (polygon), the largest radial residual
        (circle), or the largest wall-to-line residual; NaN when nothing was measured.
    reason : str
        Why the verdict was reached; names the failed test when not symmetric.
    centroid : ndarray of shape (2,)
        The centroid the judgement tested the symmetry about (``centroid_method``), sensor frame
        [m]; NaN when not computed.
    centroid_method : str
        ``"area"`` or ``"mean"``.
    tolerance : float
        The tolerance [m] of the decisive test (NaN when none ran).
    n_points : int
        Valid points in the scan.
    n_lines : int
        Lines (walls) extracted.
    axis_angle : float
        Direction [rad] of the hallway axis or of the rectangle's first side; NaN otherwise.
    """

    kind: str
    symmetric: bool
    order: SymmetryOrder | None
    regular: bool
    center: FloatArray
    corners: FloatArray
    gv_distance: float
    residual: float
    reason: str
    centroid: FloatArray = field(default_factory=lambda: np.full(2, np.nan))
    centroid_method: str = "area"
    tolerance: float = math.nan
    n_points: int = 0
    n_lines: int = 0
    axis_angle: float = math.nan

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ConfigurationError(f"kind: expected one of {KINDS}, got {self.kind!r}")
        set_ = object.__setattr__
        set_(self, "center", _frozen(self.center, ()).reshape(2))
        set_(self, "corners", _frozen(self.corners, (2,)))
        set_(self, "centroid", _frozen(self.centroid, ()).reshape(2))
        if self.order is not None and not isinstance(self.order, SymmetryOrder):
            raise ConfigurationError(f"order: expected a SymmetryOrder or None, got {self.order!r}")
        if (self.order is None) != (self.kind == "unknown"):
            raise ConfigurationError(
                f"order: only an unknown verdict has no order (kind {self.kind!r}, "
                f"order {self.order!r})"
            )

    @property
    def continuous(self) -> bool:
        """True for a continuous symmetry (a circle: ``order is SymmetryOrder.CIRCLE``)."""
        return self.order is not None and self.order.is_circle

    @property
    def n_corners(self) -> int:
        """Number of corners found."""
        return int(self.corners.shape[0])

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form (JSON-friendly): ``order`` is an integer, the string ``"inf"`` for
        a circle, or 0 for an unknown verdict (the form every JSON output has kept)."""
        return {
            "kind": self.kind,
            "symmetric": self.symmetric,
            "order": 0 if self.order is None else self.order.to_json(),
            "regular": self.regular,
            "center": [float(v) for v in self.center],
            "corners": self.corners.tolist(),
            "gv_distance": float(self.gv_distance),
            "residual": float(self.residual),
            "reason": self.reason,
            "centroid": [float(v) for v in self.centroid],
            "centroid_method": self.centroid_method,
            "tolerance": float(self.tolerance),
            "n_points": self.n_points,
            "n_lines": self.n_lines,
            "axis_angle": float(self.axis_angle),
        }
