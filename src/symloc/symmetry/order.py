"""``SymmetryOrder``: the rotational symmetry order of a place, finite ``k >= 1`` or a circle.

One type for every layer (the symmetry judgement, the localizer, the ROS status, the bench), so
that a circle and "unknown" cannot be confused: a circle is :data:`SymmetryOrder.CIRCLE`
(continuous symmetry, the paper's "n = infinity"), a room without symmetry is
``SymmetryOrder.finite(1)``, and "unknown" (too little range or field of view) is not an order
at all but ``None`` where an ``Optional[SymmetryOrder]`` is expected.

People read a circle's order as ``inf`` (``str``), JSON carries it as the string ``"inf"``
(:meth:`SymmetryOrder.to_json`); a finite order reads and serialises as its integer.

>>> SymmetryOrder.finite(4).step
1.5707963267948966
>>> str(SymmetryOrder.CIRCLE), SymmetryOrder.CIRCLE.to_json()
('inf', 'inf')
>>> SymmetryOrder.from_json(6) == SymmetryOrder.finite(6)
True
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass
from typing import ClassVar

from symloc.errors import ConfigurationError

__all__ = ["SymmetryOrder"]


@dataclass(frozen=True, slots=True)
class SymmetryOrder:
    """A rotational symmetry order: ``k`` poses explain the scan, or a circle (infinitely many).

    Build it with :meth:`finite` or use :data:`CIRCLE`; the constructor takes ``k`` (an int
    ``>= 1``) or ``None`` for a circle.

    Attributes
    ----------
    k : int or None
        The finite order (``>= 1``; 1 means no symmetry); None for a circle.
    """

    k: int | None

    CIRCLE: ClassVar[SymmetryOrder]

    def __post_init__(self) -> None:
        if self.k is None:
            return
        try:
            k = operator.index(self.k)  # int or numpy integer; not a float, not a bool
        except TypeError:
            k = 0
        if isinstance(self.k, bool) or k < 1:
            raise ConfigurationError(
                f"SymmetryOrder: expected an integer k >= 1 (or SymmetryOrder.CIRCLE), "
                f"got {self.k!r}"
            )
        object.__setattr__(self, "k", k)

    @classmethod
    def finite(cls, k: int) -> SymmetryOrder:
        """The finite order ``k >= 1`` (1: no symmetry, 2: a rectangle, n: a regular n-gon)."""
        return cls(k)

    @property
    def is_circle(self) -> bool:
        """True for continuous symmetry (a round room)."""
        return self.k is None

    @property
    def symmetric(self) -> bool:
        """True when more than one pose explains the scan (a circle, or ``k >= 2``)."""
        return self.k is None or self.k >= 2

    @property
    def step(self) -> float | None:
        """The smallest rotation [rad] that maps the place onto itself, ``2 pi / k``; None for a
        circle (any angle does)."""
        return None if self.k is None else 2.0 * math.pi / self.k

    def copies(self, circle_samples: int) -> int:
        """How many rotated copies of a pose to list: ``k``, or ``circle_samples`` for a circle."""
        return circle_samples if self.k is None else self.k

    def __str__(self) -> str:
        """As people read it: ``"inf"`` for a circle, else the integer."""
        return "inf" if self.k is None else str(self.k)

    def to_json(self) -> int | str:
        """JSON form: the integer ``k``, or the string ``"inf"`` for a circle."""
        return "inf" if self.k is None else self.k

    @classmethod
    def from_json(cls, value: object) -> SymmetryOrder:
        """Inverse of :meth:`to_json` (``"inf"`` or an integer ``>= 1``)."""
        if value == "inf":
            return cls.CIRCLE
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigurationError(
                f"SymmetryOrder.from_json: expected an integer >= 1 or 'inf', got {value!r}"
            )
        return cls(value)


SymmetryOrder.CIRCLE = SymmetryOrder(None)
