"""A pose's heading measured from keyframe features that the map places in the room.

Planar motion between a query image and a keyframe
(:mod:`symloc.vision.heading_refinement`) leaves the length of the translation free: where the
walls are about as far away as the two views are apart, a yaw error trades against a sideways
direction of travel. In a small round room (dev circle#18, 17 m^2) fits of queries 0.5 m from
the keyframes at the mapped centre were 1-9 deg off, about 5 deg typically, with profiles that
claimed 0.1-1.5 deg; no two agreed, and the robot never claimed a pose there.

The keyframe's map pose and the map itself fix that length. Each keyframe feature's image
column is a ray from the keyframe's camera; the map's walls end it at a point of the room (a
landmark, found by sphere tracing the map's distance field). The query features that match
them are bearings to known points. The pose is then searched along the one degree of freedom
the laser leaves open: a turn about a centre (a round room's centre: position and heading turn
together; any other point: the heading about a position the laser already set). The turn whose
predicted bearings explain the most matches within ``inlier`` wins (a robust grid search over
``window``), refined by least squares on its inliers; its standard deviation comes from the
residuals and the geometry, with a floor.

The camera is level, at the robot's base origin, looking along the heading (as
:class:`~symloc.vision.keyframes.Keyframe` says); bearings are counter-clockwise positive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_integer, exact_real
from symloc.errors import ConfigurationError
from symloc.geometry import turn_about, wrap_angle
from symloc.grid.distance_field import DistanceField
from symloc.vision.keyframes import Keyframe
from symloc.vision.orb import OrbFeatures
from symloc.vision.two_view import ratio_matches, undistorted

__all__ = [
    "LandmarkHeading",
    "LandmarkSettings",
    "column_bearings",
    "landmark_heading",
    "wall_points",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LandmarkSettings:
    """How a heading is measured from map-placed keyframe features (module docstring).

    Attributes
    ----------
    window : float
        The turn is searched within this angle [rad] of the pose, in (0, pi/2].
    step : float
        Grid step [rad] of the search, > 0 (the least-squares refinement goes below it).
    inlier : float
        A match whose bearing the turn explains within this angle [rad] is an inlier, > 0.
    min_inliers : int
        Fewest inlier matches of a measurement, >= 3.
    min_share : float
        Fewest inliers as a share of the matches whose ray hit a wall, in (0, 1]: a turn that
        explains a small share may be a repeated texture's.
    floor : float
        Standard deviation [rad] added in quadrature to the measurement's own: the keyframe's
        stored heading and the map's walls are not exact, and every landmark shares them.
    max_range : float
        Rays that meet no wall within this distance [m] give no landmark, > 0.
    lowe_ratio : float
        Lowe's ratio of the ORB matching, in (0, 1).
    """

    window: float = math.radians(12.0)
    step: float = math.radians(0.05)
    inlier: float = math.radians(0.5)
    min_inliers: int = 20
    min_share: float = 0.4
    floor: float = math.radians(0.3)
    max_range: float = 20.0
    lowe_ratio: float = 0.8

    def __post_init__(self) -> None:
        def bad(name: str, what: str) -> ConfigurationError:
            return ConfigurationError(
                f"LandmarkSettings.{name}: expected {what}, got {getattr(self, name)!r}"
            )

        for name in ("step", "inlier", "floor", "max_range"):
            v = exact_real(getattr(self, name))
            if not (math.isfinite(v) and v > 0):
                raise bad(name, "a finite value > 0")
        if not 0 < exact_real(self.window) <= math.pi / 2:
            raise bad("window", "an angle in (0, pi/2] rad")
        if not 0 < exact_real(self.min_share) <= 1:
            raise bad("min_share", "a share in (0, 1]")
        if not 0 < exact_real(self.lowe_ratio) < 1:
            raise bad("lowe_ratio", "a value in (0, 1)")
        check_integer(self.min_inliers, "LandmarkSettings.min_inliers", 3)


@dataclass(frozen=True)
class LandmarkHeading:
    """One keyframe's measurement: the pose turned by ``turn`` [rad] about the centre is
    ``pose`` (3,); ``sigma`` [rad] is the heading's std from the bearings alone, ``std``
    [rad] with the floor; ``inliers`` of ``landmarks`` matches with a landmark."""

    turn: float
    pose: FloatArray
    sigma: float
    std: float
    inliers: int
    landmarks: int
    keyframe_id: int

    @property
    def heading(self) -> float:
        """The measured heading [rad], map frame."""
        return float(self.pose[2])


def column_bearings(points: ArrayLike, K: ArrayLike) -> FloatArray:
    """Bearings (N,) [rad] of undistorted pixel positions ``points`` (N, 2) relative to the
    optical axis, counter-clockwise (left) positive, for the camera matrix ``K`` (3, 3)."""
    p = np.asarray(points, np.float64).reshape(-1, 2)
    Km = np.asarray(K, np.float64)
    return np.asarray(np.arctan2(Km[0, 2] - p[:, 0], Km[0, 0]), np.float64)


def wall_points(
    pose: ArrayLike, bearings: ArrayLike, field: DistanceField, max_range: float
) -> FloatArray:
    """Where rays from ``pose`` (3,) at ``bearings`` (N,) [rad] meet the map's walls, (N, 2)
    [m]; NaN rows for rays that meet none within ``max_range`` [m].

    Sphere tracing: each ray advances by the distance to the nearest occupied cell (at least a
    quarter cell) until it is within half a cell of one; the point is good to about half a cell.
    """
    p = np.asarray(pose, np.float64).reshape(3)
    b = np.asarray(bearings, np.float64).reshape(-1)
    res = float(field.grid.resolution)
    d = np.stack([np.cos(p[2] + b), np.sin(p[2] + b)], axis=1)
    t = np.zeros(b.size)
    hit = np.zeros(b.size, dtype=bool)
    live = np.ones(b.size, dtype=bool)
    for _ in range(4 * int(max_range / res) + 8):
        if not live.any():
            break
        idx = np.flatnonzero(live)
        at = p[:2] + d[idx] * t[idx, None]
        dist = field.lookup(at)
        done = dist <= 0.5 * res
        hit[idx[done]] = True
        live[idx[done]] = False
        go = idx[~done]
        t[go] += np.maximum(dist[~done] - 0.5 * res, 0.25 * res)
        live[go[t[go] > max_range]] = False
    out = p[:2] + d * t[:, None]
    out[~hit] = np.nan
    return np.asarray(out, np.float64)


def _bearing_residuals(poses: FloatArray, landmarks: FloatArray, seen: FloatArray) -> FloatArray:
    """(T, N) seen bearing minus the bearing each of ``poses`` (T, 3) predicts of
    ``landmarks`` (N, 2), wrapped."""
    dx = landmarks[None, :, 0] - poses[:, None, 0]
    dy = landmarks[None, :, 1] - poses[:, None, 1]
    predicted = np.arctan2(dy, dx) - poses[:, None, 2]
    return np.asarray(wrap_angle(seen[None, :] - predicted), np.float64)


def landmark_heading(
    pose: ArrayLike,
    query: OrbFeatures,
    keyframe: Keyframe,
    K: ArrayLike,
    field: DistanceField,
    centre: ArrayLike | None = None,
    settings: LandmarkSettings | None = None,
    *,
    dist_coeffs: tuple[float, ...] = (),
) -> LandmarkHeading | None:
    """Measure the turn of ``pose`` (3,) about ``centre`` (2,) [m] (default: the pose's own
    position) that makes the query's features point at the keyframe's, placed on the map.

    ``query`` holds the query image's features as the camera gave them (undistorted here with
    ``K`` (3, 3) and ``dist_coeffs``); ``keyframe`` its map pose and features; ``field`` the
    map's distance field. None when too few matches land on a wall or too few agree
    (``min_inliers``, ``min_share``) or the best turn lies on the edge of the search window.
    """
    s = settings if settings is not None else LandmarkSettings()
    p = np.asarray(pose, np.float64).reshape(-1)
    if p.size != 3 or not np.all(np.isfinite(p)):
        raise ConfigurationError(f"pose: expected 3 finite values (x, y, theta), got {p}")
    c = p[:2].copy() if centre is None else np.asarray(centre, np.float64).reshape(-1)
    if c.size != 2 or not np.all(np.isfinite(c)):
        raise ConfigurationError(f"centre: expected 2 finite values (x, y), got {c}")
    Km = np.asarray(K, np.float64)
    dist = tuple(float(x) for x in dist_coeffs)
    src, dst = ratio_matches(
        undistorted(query, Km, dist), undistorted(keyframe.features, Km, dist), s.lowe_ratio
    )
    # ratio_matches(query, stored) -> (stored points, query points)
    stored_px, query_px = src, dst
    if stored_px.shape[0] < s.min_inliers:
        return None
    marks = wall_points(keyframe.pose, column_bearings(stored_px, Km), field, s.max_range)
    ok = np.all(np.isfinite(marks), axis=1)
    n = int(np.count_nonzero(ok))
    if n < s.min_inliers:
        return None
    marks, seen = marks[ok], column_bearings(query_px, Km)[ok]
    turns = np.arange(-s.window, s.window + 0.5 * s.step, s.step)
    res = _bearing_residuals(turn_about(p, c, turns).reshape(-1, 3), marks, seen)
    cost = np.sum(np.minimum(np.square(res), s.inlier**2), axis=1)
    best = int(np.argmin(cost))
    if best in (0, turns.size - 1):
        return None  # the optimum may lie outside the window
    inl = np.abs(res[best]) < s.inlier
    k = int(np.count_nonzero(inl))
    if k < s.min_inliers or k < s.min_share * n:
        return None
    # Gauss-Newton on the inliers' bearings, the derivative by a central difference
    turn = float(turns[best])
    h = 1e-4
    for _ in range(5):
        r0 = _bearing_residuals(turn_about(p, c, np.array([turn])).reshape(-1, 3), marks, seen)
        rp = _bearing_residuals(turn_about(p, c, np.array([turn + h])).reshape(-1, 3), marks, seen)
        rm = _bearing_residuals(turn_about(p, c, np.array([turn - h])).reshape(-1, 3), marks, seen)
        J = (rp[0, inl] - rm[0, inl]) / (2 * h)
        jj = float(J @ J)
        if jj <= 0:
            return None
        delta = -float(J @ r0[0, inl]) / jj
        turn += delta
        if abs(delta) < 1e-7:
            break
    r = _bearing_residuals(turn_about(p, c, np.array([turn])).reshape(-1, 3), marks, seen)[0, inl]
    sigma_b = float(np.sqrt(np.sum(np.square(r)) / max(k - 1, 1)))
    sigma = sigma_b / math.sqrt(jj)
    out = np.asarray(turn_about(p, c, np.array([turn])), np.float64).reshape(3)
    out[2] = float(wrap_angle(out[2]))
    return LandmarkHeading(
        turn, out, sigma, math.hypot(sigma, s.floor), k, n, int(keyframe.keyframe_id)
    )
