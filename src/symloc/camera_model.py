"""The pinhole camera model shared by the robot's vision and the simulator's renderer.

Intrinsics follow OpenCV's convention (x right, y down, z along the optical axis), square pixels,
principal point at the image centre unless calibrated otherwise.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError

__all__ = ["DEFAULT_HFOV", "DEFAULT_IMAGE_SIZE", "focal_from_hfov", "pinhole_matrix"]

DEFAULT_IMAGE_SIZE = (640, 480)
"""Default image ``(width, height)`` [pixels] of the simulated camera and the ROS node."""
DEFAULT_HFOV = math.radians(65.0)
"""Default horizontal field of view [rad]."""


def focal_from_hfov(width: int, hfov: float) -> float:
    """Focal length [pixels] of a ``width``-pixel image with horizontal field of view ``hfov``."""
    if not (math.isfinite(hfov) and 0.0 < hfov < math.pi):
        raise ConfigurationError(f"hfov: expected a field of view in (0, pi) rad, got {hfov}")
    return (width / 2.0) / math.tan(hfov / 2.0)


def pinhole_matrix(
    width: int = DEFAULT_IMAGE_SIZE[0],
    height: int = DEFAULT_IMAGE_SIZE[1],
    hfov: float = DEFAULT_HFOV,
) -> NDArray[np.float64]:
    """Intrinsic matrix ``(3, 3)`` [pixels]: fx = fy from ``hfov``, principal point at the centre."""
    f = focal_from_hfov(width, hfov)
    return np.array([[f, 0.0, width / 2.0], [0.0, f, height / 2.0], [0.0, 0.0, 1.0]])
