"""``nav_msgs/OccupancyGrid`` <-> :class:`symloc.grid.OccupancyGrid`.

Both use the same layout (row-major, row 0 at the origin, -1 unknown, 0..100), so the
conversion only reshapes ``data`` to ``(height, width)`` and reads the origin pose.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symloc.errors import ConfigurationError, DataFormatError
from symloc.grid import OccupancyGrid
from symloc.grid.map_io import MAX_MAP_PIXELS
from symloc.msgs.fields import field, finite_field, numeric_array
from symloc.msgs.header import header_fields
from symloc.msgs.pose import pose_fields, pose_from_msg

__all__ = ["grid_from_msg", "grid_to_fields"]

_WHERE = "OccupancyGrid"


def grid_from_msg(msg: Any, *, max_cells: int = MAX_MAP_PIXELS) -> OccupancyGrid:
    """Convert a nav_msgs/OccupancyGrid to an :class:`OccupancyGrid`.

    ``max_cells`` caps ``width x height`` before the data is touched, as map files are capped
    (:data:`symloc.grid.map_io.MAX_MAP_PIXELS`, 64 Mi cells, by default): the localizer built
    on a map holds several arrays of its size.

    Raises
    ------
    DataFormatError
        Missing fields, a size that does not match ``len(data)``, values outside -1..100, more
        cells than ``max_cells``.
    """
    try:
        width = int(field(msg, "info.width", _WHERE))
        height = int(field(msg, "info.height", _WHERE))
    except (TypeError, ValueError, OverflowError) as err:
        raise DataFormatError(f"{_WHERE}.info.width/height: expected integers") from err
    if width <= 0 or height <= 0:
        raise DataFormatError(f"{_WHERE}.info: expected width, height > 0, got {width}x{height}")
    if width * height > max_cells:
        raise DataFormatError(
            f"{_WHERE}.info: {width} x {height} = {width * height:,} cells; at most"
            f" {max_cells:,} are accepted (max_map_cells, as map files: the localizer holds"
            " several arrays of the map's size)"
        )
    res = finite_field(msg, "info.resolution", _WHERE)
    if res <= 0:
        raise DataFormatError(f"{_WHERE}.info.resolution: expected > 0 m/cell, got {res}")
    origin = pose_from_msg(field(msg, "info.origin", _WHERE), f"{_WHERE}.info.origin")
    raw = field(msg, "data", _WHERE)
    if isinstance(raw, (bytes, bytearray)):
        data = np.frombuffer(raw, dtype=np.int8)
    else:
        data = numeric_array(raw, f"{_WHERE}.data", np.int16)
    if data.size != width * height:
        raise DataFormatError(
            f"{_WHERE}.data: expected width x height = {width} x {height} = {width * height}"
            f" cells, got {data.size}"
        )
    data = data.astype(np.int16)
    if np.any((data < -1) | (data > 100)):
        raise DataFormatError(f"{_WHERE}.data: values must be -1 (unknown) or 0..100")
    try:
        return OccupancyGrid(data.reshape(height, width).astype(np.int8), res, origin)
    except ConfigurationError as err:
        raise DataFormatError(f"{_WHERE}: {err}") from err


def grid_to_fields(grid: OccupancyGrid, *, stamp: float, frame_id: str = "map") -> dict[str, Any]:
    """A nav_msgs/OccupancyGrid field dict."""
    return {
        "header": header_fields(stamp, frame_id),
        "info": {
            "map_load_time": header_fields(stamp, frame_id)["stamp"],
            "resolution": grid.resolution,
            "width": grid.width,
            "height": grid.height,
            "origin": pose_fields(grid.origin),
        },
        "data": np.asarray(grid.data, dtype=np.int8).reshape(-1),
    }
