"""``GVIndex``: the G-V distances of known symmetric places (Algorithm 1 step 17; Algorithm 5
step 6 narrows the visual maps to compare by a lookup here).

In memory only; the SQLite persistence lives with the visual map.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from symloc._checks import check_finite_scalar, check_positive
from symloc.errors import ConfigurationError
from symloc.symmetry.order import SymmetryOrder

__all__ = ["GVEntry", "GVIndex"]


@dataclass(frozen=True, slots=True)
class GVEntry:
    """One symmetric place.

    Attributes
    ----------
    place_id : str
        Caller's key of the place (e.g. the visual map's name).
    gv_distance : float
        G-V distance [m] (> 0; ``math.inf`` is not allowed, a hallway has none).
    kind : str
        The report kind (``"polygon"``, ``"circle"``, ...).
    order : SymmetryOrder or None
        Symmetry order (:data:`SymmetryOrder.CIRCLE` for a circle); None when not given.
    center : tuple of float
        Centre of the place in the map frame [m], (x, y).
    """

    place_id: str
    gv_distance: float
    kind: str = "polygon"
    order: SymmetryOrder | None = None
    center: tuple[float, float] = (math.nan, math.nan)


@dataclass(slots=True)
class GVIndex:
    """G-V distances of the known symmetric places, sorted, with lookup within a tolerance.

    Examples
    --------
    >>> idx = GVIndex()
    >>> _ = idx.add("lab-square", 2.83, kind="polygon", order=SymmetryOrder.finite(4))
    >>> [e.place_id for e in idx.lookup(2.80, tolerance=0.05)]
    ['lab-square']
    """

    _entries: list[GVEntry] = field(default_factory=list)
    _keys: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __len__(self) -> int:
        return len(self._entries)

    def __iter__(self) -> Iterator[GVEntry]:
        return iter(self._entries)

    def __contains__(self, place_id: object) -> bool:
        return any(e.place_id == place_id for e in self._entries)

    def add(
        self,
        place_id: str,
        gv_distance: float,
        *,
        kind: str = "polygon",
        order: SymmetryOrder | None = None,
        center: Any = (math.nan, math.nan),
    ) -> GVEntry:
        """Add a place; raises if ``place_id`` is already there or the distance is not > 0.

        Raises
        ------
        ConfigurationError
            For an empty or duplicate ``place_id`` or a G-V distance that is not a finite
            number > 0.
        """
        if not isinstance(place_id, str) or not place_id:
            raise ConfigurationError(f"place_id: expected a non-empty string, got {place_id!r}")
        if place_id in self:
            raise ConfigurationError(f"place_id: {place_id!r} is already in the G-V index")
        gv = check_positive(gv_distance, "gv_distance")
        cx, cy = (float(v) for v in np.asarray(center, dtype=float).reshape(2))
        entry = GVEntry(place_id, gv, kind, order, (cx, cy))
        pos = int(np.searchsorted(self._keys, gv, side="right"))
        self._entries.insert(pos, entry)
        self._keys = np.insert(self._keys, pos, gv)
        return entry

    def add_report(self, place_id: str, report: Any, *, center: Any = None) -> GVEntry:
        """Add a place from a symmetric :class:`~symloc.symmetry.SymmetryReport`.

        Raises
        ------
        ConfigurationError
            If the report is not symmetric or has no G-V distance (a hallway).
        """
        if not report.symmetric or not math.isfinite(report.gv_distance):
            raise ConfigurationError(
                f"report: expected a symmetric place with a G-V distance, got kind"
                f" {report.kind!r} (gv_distance {report.gv_distance})"
            )
        return self.add(
            place_id,
            report.gv_distance,
            kind=report.kind,
            order=report.order,
            center=report.center if center is None else center,
        )

    def remove(self, place_id: str) -> None:
        """Remove a place; raises ``ConfigurationError`` if it is not there."""
        for i, e in enumerate(self._entries):
            if e.place_id == place_id:
                del self._entries[i]
                self._keys = np.delete(self._keys, i)
                return
        raise ConfigurationError(f"place_id: {place_id!r} is not in the G-V index")

    def lookup(self, gv_distance: float, *, tolerance: float) -> list[GVEntry]:
        """Places whose G-V distance is within ``tolerance`` [m] of ``gv_distance``, nearest
        first (ties in insertion order).

        Raises
        ------
        ConfigurationError
            For a non-finite distance or a negative tolerance.
        """
        gv = check_finite_scalar(gv_distance, "gv_distance")
        tol = check_positive(tolerance, "tolerance", allow_zero=True)
        lo = int(np.searchsorted(self._keys, gv - tol, side="left"))
        hi = int(np.searchsorted(self._keys, gv + tol, side="right"))
        hits = list(range(lo, hi))
        hits.sort(key=lambda i: abs(float(self._keys[i]) - gv))
        return [self._entries[i] for i in hits]

    def distances(self) -> np.ndarray:
        """All G-V distances [m], sorted ascending, shape (P,)."""
        return self._keys.copy()
