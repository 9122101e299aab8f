"""Occupancy grids (nav_msgs/OccupancyGrid semantics), map files, distance fields."""

from __future__ import annotations

from symloc.grid.occupancy_grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

__all__ = ["FREE", "OCCUPIED", "UNKNOWN", "OccupancyGrid"]
