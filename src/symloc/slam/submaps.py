"""Submaps: small log-odds grids built from consecutive scans (Hess et al. 2016, Section IV).

Each submap has its own frame (the local-SLAM pose of the first scan inserted) and an
axis-aligned :class:`~symloc.grid.log_odds.LogOddsGrid` in it. Like Cartographer, two
submaps are active at a time: every scan goes into both, scans are matched against the older
(fuller) one, and a submap is *finished* after ``scans_per_submap`` scans, when the next one
starts. The likelihood table used for matching is rebuilt lazily when the grid changed.

Memory: a finished submap keeps only what matching needs, its occupied cells (``uint16`` row
and column within their bounding box); its log-odds grid is dropped. Its likelihood table is
rebuilt from them on demand (and released by the caller's cache), so the memory of all
finished submaps grows with the mapped walls, not with the scans or the free space.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import relative
from symloc.grid.log_odds import InverseSensorModel, LogOddsGrid
from symloc.scan import LaserScan
from symloc.slam.correlative_scan_matching import LikelihoodTable

__all__ = ["ActiveSubmaps", "Submap", "SubmapParams"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SubmapParams:
    """Submap settings.

    Parameters
    ----------
    resolution : float
        Cell edge [m].
    scans_per_submap : int
        Scans inserted into a submap before it is finished (the next one starts halfway).
    sigma : float
        Standard deviation [m] of the likelihood table ``exp(-d^2 / (2 sigma^2))``.
    table_refresh : int
        Rebuild the likelihood table of an unfinished submap after this many new scans
        (a finished submap's table is always current).
    table_margin : float
        Border [m] of zero likelihood around a table, at least the widest search window, so
        that matching needs no padded copy.
    model : InverseSensorModel
    """

    resolution: float = 0.05
    scans_per_submap: int = 20
    sigma: float = 0.075
    table_refresh: int = 3
    table_margin: float = 2.5
    model: InverseSensorModel = field(default_factory=InverseSensorModel)

    def __post_init__(self) -> None:
        check_positive(self.resolution, "SubmapParams.resolution")
        check_positive(self.sigma, "SubmapParams.sigma")
        check_positive(self.table_margin, "SubmapParams.table_margin", allow_zero=True)
        if int(self.scans_per_submap) != self.scans_per_submap or self.scans_per_submap < 2:
            raise ConfigurationError(
                "SubmapParams.scans_per_submap: expected an integer >= 2, got"
                f" {self.scans_per_submap}"
            )
        if int(self.table_refresh) != self.table_refresh or self.table_refresh < 1:
            raise ConfigurationError(
                f"SubmapParams.table_refresh: expected an integer >= 1, got {self.table_refresh}"
            )


class Submap:
    """One submap: its local pose, grid, inserted nodes and a cached likelihood table.

    Parameters
    ----------
    index : int
    local_pose : array of shape (3,)
        Pose of the submap frame in the local-SLAM frame.
    params : SubmapParams
    """

    def __init__(self, index: int, local_pose: ArrayLike, params: SubmapParams) -> None:
        self.index = int(index)
        self.local_pose = np.asarray(local_pose, dtype=np.float64).reshape(3).copy()
        self.params = params
        self.grid: LogOddsGrid | None = LogOddsGrid(params.resolution, params.model, (0.0, 0.0))
        self.nodes: list[int] = []
        self.node_poses: list[FloatArray] = []
        self.finished = False
        self._n_scans = 0
        self._table: LikelihoodTable | None = None
        self._table_version = -1
        # a finished submap: occupied cells (row, col) in the box starting at _box_origin
        self._occupied: NDArray[np.uint16] | None = None
        self._box_origin = np.zeros(2)
        self._box_shape = (0, 0)

    @property
    def n_scans(self) -> int:
        """Scans inserted so far."""
        return self._n_scans

    @property
    def nbytes(self) -> int:
        """Memory of the submap's map data (grid or occupied cells, and its table) [bytes]."""
        n = 0 if self.grid is None else int(self.grid.values.nbytes)
        n += 0 if self._occupied is None else int(self._occupied.nbytes)
        return n + (0 if self._table is None else self._table.nbytes)

    @property
    def has_table(self) -> bool:
        """True while a likelihood table is cached."""
        return self._table is not None

    def insert(self, node: int, local_pose: ArrayLike, scan: LaserScan) -> FloatArray:
        """Insert ``scan`` taken at ``local_pose`` (local frame); returns its pose in the submap."""
        if self.grid is None:
            raise ConfigurationError(f"submap {self.index}: finished, no more scans can go in")
        p = relative(self.local_pose, np.asarray(local_pose, dtype=np.float64))
        self.grid.integrate(p, scan)
        self._n_scans += 1
        self.nodes.append(int(node))
        self.node_poses.append(p)
        return p

    def finish(self) -> None:
        """Mark finished and keep only the occupied cells of the grid (drops the grid)."""
        self.finished = True
        if self.grid is None:
            return
        occ = self.grid.values > 0.0
        rows = np.flatnonzero(occ.any(axis=1))
        cols = np.flatnonzero(occ.any(axis=0))
        if rows.size:
            r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
        else:
            r0 = r1 = c0 = c1 = 0
        cells = np.argwhere(occ[r0:r1, c0:c1])
        self._occupied = cells.astype(np.uint16)
        self._box_shape = (max(int(r1 - r0), 1), max(int(c1 - c0), 1))
        self._box_origin = self.grid.origin_xy + np.array([c0, r0]) * self.grid.resolution
        self.grid = None
        self._table = None  # rebuilt from the cells (with the margin) when next matched
        self._table_version = -1

    def occupied_mask(self) -> tuple[NDArray[np.bool_], FloatArray]:
        """``(mask (H, W), origin_xy (2,))`` of the occupied cells in the submap frame."""
        if self.grid is not None:
            return self.grid.values > 0.0, self.grid.origin_xy
        assert self._occupied is not None
        mask = np.zeros(self._box_shape, dtype=bool)
        mask[self._occupied[:, 0], self._occupied[:, 1]] = True
        return mask, self._box_origin

    def table(self) -> LikelihoodTable:
        """Likelihood table of the current grid, in the submap frame (cached per version)."""
        stale = self._n_scans - self._table_version
        if (
            self._table is None
            or stale >= self.params.table_refresh
            or (self.finished and stale > 0)
        ):
            occ, origin = self.occupied_mask()
            margin = math.ceil(self.params.table_margin / self.params.resolution)
            self._table = LikelihoodTable.from_occupied(
                occ, self.params.resolution, origin, self.params.sigma, margin=margin
            )
            self._table_version = self._n_scans
        return self._table

    def release_table(self) -> None:
        """Drop the cached table (memory) of a submap that will not be matched soon."""
        self._table = None
        self._table_version = -1


class ActiveSubmaps:
    """Cartographer's pair of active submaps.

    ``insert`` puts a scan into the active submaps and returns the submaps it went into; the
    matching target is :attr:`matching_submap` (the oldest active one).
    """

    def __init__(self, params: SubmapParams) -> None:
        self.params = params
        self.submaps: list[Submap] = []

    @property
    def active(self) -> list[Submap]:
        """The (at most two) unfinished submaps, oldest first."""
        return [s for s in self.submaps[-2:] if not s.finished]

    @property
    def matching_submap(self) -> Submap | None:
        """The submap new scans are matched against (None before the first scan)."""
        act = self.active
        return act[0] if act else None

    def insert(self, node: int, local_pose: ArrayLike, scan: LaserScan) -> list[Submap]:
        """Insert a scan; start and finish submaps as needed. Returns the submaps touched."""
        n = self.params.scans_per_submap
        act = self.active
        if not act or act[-1].n_scans >= n // 2:
            self.submaps.append(Submap(len(self.submaps), local_pose, self.params))
        touched = self.active
        for sm in touched:
            sm.insert(node, local_pose, scan)
        for sm in touched:
            if sm.n_scans >= n:
                sm.finish()
        return touched
