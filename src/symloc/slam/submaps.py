"""Submaps: small log-odds grids built from consecutive scans (Hess et al. 2016, Section IV).

Each submap has its own frame (the local-SLAM pose of the first scan inserted) and an
axis-aligned :class:`~symloc.grid.log_odds.LogOddsGrid` in it. Like Cartographer, two
submaps are active at a time: every scan goes into both, scans are matched against the older
(fuller) one, and a submap is *finished* after ``scans_per_submap`` scans, when the next one
starts. The likelihood table used for matching is rebuilt lazily when the grid changed.
"""

from __future__ import annotations

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
    model : InverseSensorModel
    """

    resolution: float = 0.05
    scans_per_submap: int = 20
    sigma: float = 0.075
    table_refresh: int = 3
    model: InverseSensorModel = field(default_factory=InverseSensorModel)

    def __post_init__(self) -> None:
        check_positive(self.resolution, "SubmapParams.resolution")
        check_positive(self.sigma, "SubmapParams.sigma")
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
        self.grid = LogOddsGrid(params.resolution, params.model, (0.0, 0.0))
        self.nodes: list[int] = []
        self.node_poses: list[FloatArray] = []
        self.finished = False
        self._table: LikelihoodTable | None = None
        self._table_version = -1

    @property
    def n_scans(self) -> int:
        """Scans inserted so far."""
        return self.grid.n_scans

    def insert(self, node: int, local_pose: ArrayLike, scan: LaserScan) -> FloatArray:
        """Insert ``scan`` taken at ``local_pose`` (local frame); returns its pose in the submap."""
        p = relative(self.local_pose, np.asarray(local_pose, dtype=np.float64))
        self.grid.integrate(p, scan)
        self.nodes.append(int(node))
        self.node_poses.append(p)
        return p

    def table(self) -> LikelihoodTable:
        """Likelihood table of the current grid, in the submap frame (cached per version)."""
        stale = self.grid.n_scans - self._table_version
        if (
            self._table is None
            or stale >= self.params.table_refresh
            or (self.finished and stale > 0)
        ):
            occ = self.grid.values > 0.0
            self._table = LikelihoodTable.from_occupied(
                occ, self.grid.resolution, self.grid.origin_xy, self.params.sigma
            )
            self._table_version = self.grid.n_scans
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
                sm.finished = True
        return touched
