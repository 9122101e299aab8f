"""``OccupancyGrid``: a 2D map with nav_msgs/OccupancyGrid semantics.

``data[row, col]`` holds -1 (unknown) or an occupancy 0..100. Row 0 is the row at the origin's
y (the bottom of a map_server image), column 0 at the origin's x. The origin is the world pose
``(x, y, yaw)`` of the outer corner of cell (0, 0); the grid's x axis points along the origin's
yaw. :meth:`OccupancyGrid.world_to_cell` and :meth:`OccupancyGrid.cell_to_world` are the one
pair of conversions every module uses.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError
from symloc.geometry import inverse, transform_points

__all__ = [
    "FREE",
    "MAX_ORIGIN",
    "MAX_RESOLUTION",
    "MIN_RESOLUTION",
    "OCCUPIED",
    "UNKNOWN",
    "OccupancyGrid",
]

UNKNOWN = -1
FREE = 0
OCCUPIED = 100
#: Cell sizes [m/cell] a map may have (a micrometre to 10 km); outside, cell indices overflow.
MIN_RESOLUTION = 1e-6
MAX_RESOLUTION = 1e4
#: Largest |origin x|, |origin y| [m] (cell arithmetic stays exact below it).
MAX_ORIGIN = 1e9

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """A 2D occupancy grid.

    Parameters
    ----------
    data : array of shape (H, W), int8
        -1 unknown, 0..100 occupancy probability in percent.
    resolution : float
        Cell edge [m/cell], in [:data:`MIN_RESOLUTION`, :data:`MAX_RESOLUTION`].
    origin : array of shape (3,)
        World pose x [m], y [m], yaw [rad] of the corner of cell (0, 0); |x|, |y| at most
        :data:`MAX_ORIGIN`.
    occupied_thresh, free_thresh : float
        Occupancy fractions above / below which a cell counts as occupied / free
        (map_server defaults 0.65 and 0.196).
    """

    data: NDArray[np.int8]
    resolution: float
    origin: FloatArray = field(default_factory=lambda: np.zeros(3))
    occupied_thresh: float = 0.65
    free_thresh: float = 0.196

    def __post_init__(self) -> None:
        d = np.asarray(self.data)
        if d.ndim != 2 or d.shape[0] == 0 or d.shape[1] == 0:
            raise ConfigurationError(
                f"OccupancyGrid.data: expected a non-empty (H, W) array, got {d.shape}"
            )
        if d.dtype.kind not in "iu":
            raise ConfigurationError(f"OccupancyGrid.data: expected integers, got dtype {d.dtype}")
        if int(d.min()) < -1 or int(d.max()) > 100:  # no (H, W) temporaries
            raise ConfigurationError("OccupancyGrid.data: values must be -1 (unknown) or 0..100")
        d = d.astype(np.int8, copy=True)
        d.setflags(write=False)
        res = float(self.resolution)
        if not np.isfinite(res) or not MIN_RESOLUTION <= res <= MAX_RESOLUTION:
            raise ConfigurationError(
                f"OccupancyGrid.resolution: expected {MIN_RESOLUTION:g}..{MAX_RESOLUTION:g}"
                f" m/cell, got {res}"
            )
        o = np.array(self.origin, dtype=np.float64)
        if o.shape != (3,) or not np.all(np.isfinite(o)):
            raise ConfigurationError(f"OccupancyGrid.origin: expected finite (x, y, yaw), got {o}")
        if np.any(np.abs(o[:2]) > MAX_ORIGIN):
            raise ConfigurationError(
                f"OccupancyGrid.origin: expected |x|, |y| <= {MAX_ORIGIN:g} m, got {o[:2]}"
            )
        if not 0.0 <= self.free_thresh < self.occupied_thresh <= 1.0:
            raise ConfigurationError(
                "OccupancyGrid thresholds: expected 0 <= free_thresh < occupied_thresh <= 1, got"
                f" free_thresh={self.free_thresh}, occupied_thresh={self.occupied_thresh}"
            )
        o.setflags(write=False)
        object.__setattr__(self, "data", d)
        object.__setattr__(self, "resolution", res)
        object.__setattr__(self, "origin", o)

    def __getstate__(self) -> dict[str, object]:
        """Pickle and copy the map only: its fields cache (:class:`symloc.grid.fields.MapFields`,
        stored on the grid) is recomputed where it is needed."""
        state = dict(self.__dict__)
        state.pop("_map_fields", None)
        return state

    @property
    def height(self) -> int:
        """Number of rows (cells along the grid's y)."""
        return int(self.data.shape[0])

    @property
    def width(self) -> int:
        """Number of columns (cells along the grid's x)."""
        return int(self.data.shape[1])

    @property
    def occupied_mask(self) -> NDArray[np.bool_]:
        """``(H, W)`` True where occupancy > occupied_thresh."""
        return self.data > self.occupied_thresh * 100.0

    @property
    def free_mask(self) -> NDArray[np.bool_]:
        """``(H, W)`` True where 0 <= occupancy < free_thresh."""
        return self.is_free(self.data)

    def is_free(self, values: ArrayLike) -> NDArray[np.bool_]:
        """:attr:`free_mask`'s test on some of this grid's occupancy ``values`` (any shape):
        for a few cells or a sub-sampled view without the whole map's mask."""
        v = np.asarray(values)
        out: NDArray[np.bool_] = (v >= 0) & (v < self.free_thresh * 100.0)
        return out

    @property
    def unknown_mask(self) -> NDArray[np.bool_]:
        """``(H, W)`` True where the cell is unknown (-1) or between the thresholds."""
        return ~(self.occupied_mask | self.free_mask)

    def world_to_cell(self, points: ArrayLike) -> NDArray[np.intp]:
        """World points ``(N, 2)`` [m] to cell indices ``(N, 2)`` as (row, col).

        Indices may fall outside the grid; check with :meth:`in_bounds`.
        """
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        local = (
            transform_points(inverse(self.origin), pts)
            if self.origin[2] != 0.0
            else (pts - self.origin[:2])
        )
        cells = np.floor(local / self.resolution).astype(np.intp)
        return cells[:, ::-1]

    def cell_to_world(self, cells: ArrayLike) -> FloatArray:
        """Cell indices ``(N, 2)`` as (row, col) to the world points ``(N, 2)`` of their centres."""
        rc = np.asarray(cells, dtype=np.float64).reshape(-1, 2)
        local = (rc[:, ::-1] + 0.5) * self.resolution
        if self.origin[2] == 0.0:
            return local + self.origin[:2]
        return transform_points(self.origin, local)

    def in_bounds(self, cells: ArrayLike) -> NDArray[np.bool_]:
        """``(N,)`` True where the (row, col) cells lie inside the grid."""
        rc = np.asarray(cells).reshape(-1, 2)
        return (
            (rc[:, 0] >= 0) & (rc[:, 0] < self.height) & (rc[:, 1] >= 0) & (rc[:, 1] < self.width)
        )

    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` [m] of the grid in its own axes, for plotting."""
        x0, y0 = float(self.origin[0]), float(self.origin[1])
        return (x0, x0 + self.width * self.resolution, y0, y0 + self.height * self.resolution)
