"""The map's own position error, place by place, as the SLAM that built it estimated it.

A :class:`MapErrorField` holds K places (the positions of the mapping trip's nodes, map frame)
and a 2 x 2 position covariance at each: how far the walls drawn from there may be from where
the map puts them, once the map as a whole is aligned to the world
(:mod:`symloc.slam.pose_marginals`). A pose is given the covariance of the nearest place.

Saved in a map's YAML as ``symloc_slam.map_error.field``: one row ``[x, y, cov_xx, cov_xy,
cov_yy]`` per place (metres, square metres; :meth:`MapErrorField.rows`,
:meth:`MapErrorField.from_rows`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from symloc.errors import ConfigurationError

__all__ = ["MapErrorField"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class MapErrorField:
    """Position covariances of the map at K places.

    Attributes
    ----------
    xy : ndarray of shape (K, 2)
        Where [m] (map frame).
    covariance : ndarray of shape (K, 2, 2)
        The map's position error there [m^2] (symmetric, positive semi-definite).
    """

    xy: FloatArray
    covariance: FloatArray
    _tree: cKDTree = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        xy = np.asarray(self.xy, dtype=np.float64)
        cov = np.asarray(self.covariance, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2 or xy.shape[0] == 0:
            raise ConfigurationError(f"MapErrorField.xy: expected shape (K>0, 2), got {xy.shape}")
        if cov.shape != (xy.shape[0], 2, 2):
            raise ConfigurationError(
                f"MapErrorField.covariance: expected shape ({xy.shape[0]}, 2, 2), got {cov.shape}"
            )
        if not (np.all(np.isfinite(xy)) and np.all(np.isfinite(cov))):
            raise ConfigurationError("MapErrorField: expected finite positions and covariances")
        object.__setattr__(self, "xy", xy)
        object.__setattr__(self, "covariance", 0.5 * (cov + cov.transpose(0, 2, 1)))
        object.__setattr__(self, "_tree", cKDTree(xy))

    def at(self, xy: ArrayLike) -> FloatArray:
        """The covariance (..., 2, 2) [m^2] of the place nearest each of ``xy`` (..., 2) [m]."""
        _, k = self._tree.query(np.asarray(xy, dtype=np.float64))
        return np.array(self.covariance[k])

    @cached_property
    def major_std(self) -> FloatArray:
        """(K,) the std [m] along each place's least certain direction."""
        major: FloatArray = np.sqrt(np.maximum(np.linalg.eigvalsh(self.covariance)[:, 1], 0.0))
        return major

    def rows(self) -> list[list[float]]:
        """``[x, y, cov_xx, cov_xy, cov_yy]`` per place (the YAML form)."""
        c = self.covariance
        table = np.column_stack([self.xy, c[:, 0, 0], c[:, 0, 1], c[:, 1, 1]])
        return [[float(f"{v:.6g}") for v in row] for row in table]

    @classmethod
    def from_rows(cls, rows: Sequence[Sequence[float]], where: str) -> MapErrorField:
        """Read :meth:`rows`; ``where`` names the file and field in errors."""
        try:
            table = np.asarray(rows, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ConfigurationError(
                f"{where}: expected rows of 5 numbers [x, y, cov_xx, cov_xy, cov_yy] ({exc})"
            ) from None
        if table.ndim != 2 or table.shape[1] != 5 or table.shape[0] == 0:
            raise ConfigurationError(
                f"{where}: expected rows of 5 numbers [x, y, cov_xx, cov_xy, cov_yy], got an"
                f" array of shape {table.shape}"
            )
        cov = np.empty((table.shape[0], 2, 2))
        cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 0], cov[:, 1, 1] = (
            table[:, 2],
            table[:, 3],
            table[:, 3],
            table[:, 4],
        )
        bad = (
            (cov[:, 0, 0] < 0)
            | (cov[:, 1, 1] < 0)
            | (cov[:, 0, 1] ** 2 > cov[:, 0, 0] * cov[:, 1, 1] * (1 + 1e-6) + 1e-12)
        )
        if np.any(bad) or not np.all(np.isfinite(table)):
            raise ConfigurationError(
                f"{where}: row {int(np.flatnonzero(bad | ~np.isfinite(table).all(1))[0])} is not"
                " finite or not a covariance (cov_xx, cov_yy >= 0, cov_xy^2 <= cov_xx cov_yy)"
            )
        return cls(table[:, :2], cov)
