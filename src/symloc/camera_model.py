"""The pinhole camera model shared by the robot's vision and the simulator's renderer.

Intrinsics follow OpenCV's convention (x right, y down, z along the optical axis), square pixels,
principal point at the image centre unless calibrated otherwise. Lens distortion follows
OpenCV's (and ROS camera_info's ``plumb_bob``) model: normalised image coordinates ``(x, y)``,
``r^2 = x^2 + y^2``, are distorted to

    x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
    y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y

with the coefficients in OpenCV's order ``(k1, k2, p1, p2, k3)``. A :class:`CameraModel` carries
a camera's calibration (as ``camera_calibration`` / ``cv2.calibrateCamera`` give it) and maps
distorted pixel positions to those of the ideal pinhole camera (:meth:`CameraModel.undistort_points`)
and back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError

__all__ = [
    "DEFAULT_HFOV",
    "DEFAULT_IMAGE_SIZE",
    "CameraModel",
    "check_dist_coeffs",
    "focal_from_hfov",
    "pinhole_matrix",
    "undistort_points",
]

DEFAULT_IMAGE_SIZE = (640, 480)
"""Default image ``(width, height)`` [pixels] of the simulated camera and the ROS node."""
DEFAULT_HFOV = math.radians(65.0)
"""Default horizontal field of view [rad]."""

FloatArray = NDArray[np.float64]


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


def check_dist_coeffs(value: ArrayLike | None, name: str = "dist_coeffs") -> tuple[float, ...]:
    """Distortion coefficients as a tuple of 5 floats ``(k1, k2, p1, p2, k3)``.

    Accepts None or an empty sequence (no distortion: all zero), 4 values ``(k1, k2, p1, p2)``
    or 5; anything else raises :class:`~symloc.errors.ConfigurationError` naming ``name``.
    """
    if value is None:
        return (0.0,) * 5
    try:
        arr = np.asarray(value, dtype=np.float64).ravel()
    except (TypeError, ValueError) as err:
        raise ConfigurationError(f"{name}: expected 4 or 5 numbers k1, k2, p1, p2[, k3]") from err
    if arr.size == 0:
        return (0.0,) * 5
    if arr.size not in (4, 5):
        raise ConfigurationError(
            f"{name}: expected 4 or 5 numbers k1, k2, p1, p2[, k3] (OpenCV order), got {arr.size}"
        )
    if not np.all(np.isfinite(arr)):
        raise ConfigurationError(f"{name}: contains NaN or infinite values")
    if arr.size == 4:
        arr = np.append(arr, 0.0)
    return tuple(float(v) for v in arr)


@dataclass(frozen=True)
class CameraModel:
    """A calibrated camera: image size, intrinsics and lens distortion.

    Parameters
    ----------
    width, height : int
        Image size [pixels].
    fx, fy : float
        Focal lengths [pixels], > 0.
    cx, cy : float
        Principal point [pixels].
    dist_coeffs : tuple of float
        OpenCV ``(k1, k2, p1, p2, k3)`` (4 or 5 values, or empty for none; stored as 5).
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    dist_coeffs: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            val = getattr(self, name)
            if int(val) != val or val < 1:
                raise ConfigurationError(f"CameraModel.{name}: expected an integer >= 1, got {val}")
        for name in ("fx", "fy"):
            val = getattr(self, name)
            if not (math.isfinite(val) and val > 0):
                raise ConfigurationError(f"CameraModel.{name}: expected a value > 0 px, got {val}")
        for name in ("cx", "cy"):
            if not math.isfinite(getattr(self, name)):
                raise ConfigurationError(f"CameraModel.{name}: expected a finite value [px]")
        object.__setattr__(
            self, "dist_coeffs", check_dist_coeffs(self.dist_coeffs, "CameraModel.dist_coeffs")
        )

    @classmethod
    def from_hfov(
        cls,
        width: int = DEFAULT_IMAGE_SIZE[0],
        height: int = DEFAULT_IMAGE_SIZE[1],
        hfov: float = DEFAULT_HFOV,
        dist_coeffs: ArrayLike | None = None,
    ) -> CameraModel:
        """Square pixels, principal point at the image centre, focal length from ``hfov``."""
        f = focal_from_hfov(width, hfov)
        return cls(width, height, f, f, width / 2.0, height / 2.0, check_dist_coeffs(dist_coeffs))

    @property
    def K(self) -> FloatArray:  # noqa: N802 (the usual name of the intrinsic matrix)
        """Intrinsic matrix ``(3, 3)`` [pixels]."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def has_distortion(self) -> bool:
        """True if any distortion coefficient is non-zero."""
        return any(c != 0.0 for c in self.dist_coeffs)

    def undistort_points(self, points: ArrayLike) -> FloatArray:
        """Pixel positions ``(N, 2)`` of the ideal pinhole camera (same ``K``) for distorted
        pixel positions ``(N, 2)`` (``cv2.undistortPoints`` with ``P = K``, 20 iterations)."""
        return undistort_points(points, self.K, self.dist_coeffs)

    def distort_points(self, points: ArrayLike) -> FloatArray:
        """Distorted pixel positions ``(N, 2)`` of ideal pinhole pixel positions ``(N, 2)``."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if not self.has_distortion or pts.shape[0] == 0:
            return pts.copy()
        x = (pts[:, 0] - self.cx) / self.fx
        y = (pts[:, 1] - self.cy) / self.fy
        obj = np.column_stack([x, y, np.ones_like(x)])
        out, _ = cv2.projectPoints(
            obj, np.zeros(3), np.zeros(3), self.K, np.asarray(self.dist_coeffs)
        )
        return np.asarray(out, dtype=np.float64).reshape(-1, 2)


def undistort_points(points: ArrayLike, K: ArrayLike, dist_coeffs: ArrayLike | None) -> FloatArray:
    """Ideal pinhole pixel positions ``(N, 2)`` of distorted pixel positions ``(N, 2)``.

    ``K`` is the ``(3, 3)`` intrinsic matrix; the result is expressed with the same ``K``
    (``cv2.undistortPoints(..., P=K)`` with 20 iterations). With no (or all-zero) coefficients the points are
    returned unchanged.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    d = check_dist_coeffs(dist_coeffs)
    if not any(d) or pts.shape[0] == 0:
        return pts.copy()
    Km = np.asarray(K, dtype=np.float64)
    out = cv2.undistortPoints(
        pts.reshape(-1, 1, 2), Km, np.asarray(d), R=None, P=Km, criteria=_UNDISTORT_CRITERIA
    )
    return np.asarray(out, dtype=np.float64).reshape(-1, 2)


# OpenCV's default (5 iterations) leaves 0.1-0.5 px near the corners of a strongly distorting
# lens; 20 iterations or 1e-9 in normalised coordinates reach the sub-millipixel level.
_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 20, 1e-9)
