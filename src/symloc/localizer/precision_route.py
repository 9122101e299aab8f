"""A route through the map's free space to one goal, for the drive where a claim is precise.

The claim gate withholds a claim whose only fault is its distance from the map's middle (the
map's scale error grows with it, and on a round map so does the position cost of a heading
error: :meth:`~symloc.localizer.claim.ClaimGate.middle_bound`);
the localizer then asks the driver to go towards the middle
(:func:`~symloc.localizer.phases.precision_request`). A straight line there crosses walls in
a U- or L-shaped room (on the dev split a U-shaped room stopped the robot 4.8 m short, facing
its inner wall), so the request names the next waypoint of a route instead.

:class:`FreeRoute` holds the travel cost from every cell of the map to the goal (scikit-image's
minimum-cost-path search, :class:`skimage.graph.MCP_Geometric`, over the free cells: those
closer than ``clearance`` to an obstacle cost ``narrow_cost`` times more, so the route keeps
clear of walls where it can, yet a robot standing near one still has a way out), computed once;
:meth:`FreeRoute.waypoint` traces the route back from a position and returns the point
``lookahead`` along it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from skimage.graph import MCP_Geometric

from symloc.grid.distance_field import DistanceField

__all__ = ["FreeRoute", "clear_free_cells"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def clear_free_cells(
    field: DistanceField, clearance: float, step: int
) -> tuple[IntArray, FloatArray, NDArray[np.bool_]]:
    """The free cells of ``field``'s grid strided by ``step``: their (row, col) on the strided
    grid (N, 2), their centres [m] (N, 2) (map frame), and which of them lie at least
    ``clearance`` [m] from every obstacle (N,)."""
    grid = field.grid
    cells = np.argwhere(grid.free_mask[::step, ::step]).astype(np.int64)
    if cells.shape[0] == 0:
        return cells, np.zeros((0, 2)), np.zeros(0, dtype=bool)
    world = np.asarray(grid.cell_to_world(cells * step), dtype=np.float64)
    return cells, world, field.lookup(world) >= clearance


class FreeRoute:
    """Routes to ``goal`` through the free cells of ``field``'s grid.

    Parameters
    ----------
    field : DistanceField
        The map's distance to the nearest obstacle [m] (its ``grid`` says which cells are free).
    goal : (2,) array
        Where every route ends [m] (map frame); a free cell.
    clearance : float
        Cells closer than this [m] to an obstacle are avoided where there is a way round.
    narrow_cost : float
        How much more a cell closer than ``clearance`` costs to cross, > 1.
    max_cells : int
        The search runs on the grid strided so that it has at most about this many cells (a
        large map is searched coarser; the route is a direction to drive, not a path to follow
        blindly).
    """

    def __init__(
        self,
        field: DistanceField,
        goal: FloatArray,
        clearance: float,
        *,
        narrow_cost: float = 20.0,
        max_cells: int = 1_000_000,
    ) -> None:
        grid = field.grid
        self.step = max(1, int(np.ceil(np.sqrt(grid.data.size / max_cells))))
        self.grid = grid
        self.shape = grid.data[:: self.step, :: self.step].shape
        cells, _, clear = clear_free_cells(field, clearance, self.step)
        cost = np.full(self.shape, -1.0)  # negative: impassable
        cost[cells[:, 0], cells[:, 1]] = np.where(clear, 1.0, narrow_cost)
        self._mcp = MCP_Geometric(cost)
        goal_cell = self._cell(np.asarray(goal, dtype=np.float64).reshape(2))
        self.reachable = cost[goal_cell] > 0
        self._costs = (
            self._mcp.find_costs([goal_cell])[0] if self.reachable else np.full(self.shape, np.inf)
        )

    def _cell(self, point: FloatArray) -> tuple[int, int]:
        """The (row, col) of ``point`` (2,) [m] on the strided grid, clipped to it."""
        rc = np.asarray(self.grid.world_to_cell(point.reshape(1, 2)), dtype=np.int64)[0]
        r, c = int(rc[0]) // self.step, int(rc[1]) // self.step
        return min(max(r, 0), self.shape[0] - 1), min(max(c, 0), self.shape[1] - 1)

    def waypoint(self, position: FloatArray, lookahead: float = 1.0) -> FloatArray | None:
        """The point [m] (2,) ``lookahead`` [m] along the route from ``position`` (2,) to the
        goal (the goal itself when nearer); None when no route leads there (``position`` off
        the free space, or cut off from the goal)."""
        cell = self._cell(np.asarray(position, dtype=np.float64).reshape(2))
        if not np.isfinite(self._costs[cell]):
            return None
        path = np.asarray(self._mcp.traceback(cell), dtype=np.float64)  # goal ... position
        points = np.asarray(self.grid.cell_to_world(path[::-1] * self.step), dtype=np.float64)
        along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points, axis=0).T))])
        k = int(np.searchsorted(along, lookahead))
        out: FloatArray = points[min(k, points.shape[0] - 1)].copy()
        return out
