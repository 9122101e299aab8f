"""The relative heading of two views of a level camera on a robot driving on a flat floor.

Between two views the camera turns by a yaw ``theta`` about the vertical axis and moves
horizontally, in a direction ``phi`` of its own x-z plane (camera frame: x right, y down, z
forward, as in :mod:`symloc.vision.two_view`). The essential matrix of such a *planar motion*
has two degrees of freedom,

    ``E = [t]_x R_y(theta)``,  ``t = (sin phi, 0, cos phi)``,

(``phi`` and ``phi + pi`` give the same ``E``), and every match ``x_stored -> x_query`` (rays
through the undistorted keypoints) satisfies ``x_query^T E x_stored = 0``. Unlike a homography
it needs no planar scene (a round room's curved wall), and unlike the five-point essential
matrix it keeps the camera level, so a pure turn (no travel) is no degenerate case: every
``phi`` fits, and ``theta`` is still fixed by the points above and below the horizon.

:func:`planar_yaw` first searches ``(theta, phi)`` on a coarse grid (vectorised), scoring each
by the truncated Sampson distances [px] of all matches (a false match costs the same whatever
the model), then profiles the yaw around the best: for each yaw on a fine grid the best
``phi`` under a smooth robust loss (Cauchy), the minimum refined by a parabola. Its uncertainty
is read off the profile: the yaw interval where the cost stays within one ``sigma^2`` (the
inliers' residual variance) of its minimum. Driving forward past one wall, a yaw error can be
traded against the direction of travel almost for free (the valley turns ``phi`` about ten
times faster than ``theta``): the profile is wide, or a prior on ``phi`` (the odometry's
direction of travel) settles it. The profile assumes independent residuals; on a simulated
realistic camera the errors are several times what it says, so a caller adds a floor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError

__all__ = ["PlanarYaw", "planar_yaw", "sampson_planar", "travel_prior"]

FloatArray = NDArray[np.float64]

#: The profile of the yaw is computed this far [deg] either side of the robust best.
PROFILE_SPAN_DEG = 3.0

#: Most matches scored (the best-spread subset beyond it would not change the answer much).
MAX_MATCHES = 600


@dataclass(frozen=True)
class PlanarYaw:
    """A planar-motion fit between a stored view and a query view.

    Attributes
    ----------
    yaw : float
        Query heading minus stored heading [rad], counter-clockwise positive (NaN: no fit).
    sigma : float
        Its standard deviation [rad] from the profile (``inf`` when the cost does not rise by
        one variance within the fine search, i.e. the views do not fix the yaw).
    inliers : int
        Matches whose Sampson distance at the fit is within the truncation.
    matches : int
        Matches scored.
    direction : float
        Direction of travel ``phi`` [rad] in the stored camera's x-z plane, modulo pi (from
        +z towards +x).
    rms : float
        Root mean square Sampson distance [px] of the inliers.
    """

    yaw: float
    sigma: float
    inliers: int
    matches: int
    direction: float = math.nan
    rms: float = math.nan

    @property
    def fitted(self) -> bool:
        """True when a yaw was found."""
        return math.isfinite(self.yaw)


def _rays(points: FloatArray, K: FloatArray) -> FloatArray:
    """Rays ``(n, 3)`` (z = 1) of pixel positions ``(n, 2)``."""
    h = np.column_stack([points, np.ones(points.shape[0])])
    return np.asarray(h @ np.linalg.inv(K).T, np.float64)


def sampson_planar(
    rays_stored: ArrayLike, rays_query: ArrayLike, yaws: ArrayLike, phis: ArrayLike, focal: float
) -> FloatArray:
    """Squared Sampson distances [px^2] of matches under planar motions.

    Parameters
    ----------
    rays_stored, rays_query : (n, 3) arrays
        Rays (undistorted, ``K^-1 [u, v, 1]``) of the n matches in the stored and query views.
    yaws : (T,) array
        Candidate yaws [rad].
    phis : (T, P) or (P,) array
        Candidate directions of travel [rad] (per yaw, or shared).
    focal : float
        Focal length [px] (converts distances on the normalised image plane to pixels).

    Returns
    -------
    (T, P, n) float64
    """
    x1 = np.asarray(rays_stored, np.float64)
    x2 = np.asarray(rays_query, np.float64)
    th = np.asarray(yaws, np.float64).reshape(-1)
    ph = np.asarray(phis, np.float64)
    ph = np.broadcast_to(ph.reshape(1, -1) if ph.ndim == 1 else ph, (th.size, ph.shape[-1]))
    c, s = np.cos(th)[:, None, None], np.sin(th)[:, None, None]
    tx, tz = np.sin(ph)[:, :, None], np.cos(ph)[:, :, None]
    # R_y(theta) x1 = (c x0 + s x2, x1, -s x0 + c x2)
    a0 = c * x1[None, None, :, 0] + s * x1[None, None, :, 2]
    a1 = x1[None, None, :, 1]
    a2 = -s * x1[None, None, :, 0] + c * x1[None, None, :, 2]
    # E x1 = t x (R x1) with t = (tx, 0, tz)
    e0 = -tz * a1
    e1 = tz * a0 - tx * a2
    e2 = tx * a1
    num = x2[None, None, :, 0] * e0 + x2[None, None, :, 1] * e1 + x2[None, None, :, 2] * e2
    # E^T x2 = -R^T (t x x2); only its first two components enter
    q0, q1, q2 = x2[None, None, :, 0], x2[None, None, :, 1], x2[None, None, :, 2]
    b0 = -tz * q1
    b1 = tz * q0 - tx * q2
    b2 = tx * q1
    f0 = c * b0 - s * b2
    den = e0 * e0 + e1 * e1 + f0 * f0 + b1 * b1
    out: FloatArray = (focal * focal) * num * num / np.maximum(den, 1e-300)
    return out


def _profile(
    x1: FloatArray,
    x2: FloatArray,
    focal: float,
    yaws: FloatArray,
    phis: FloatArray,
    cap: float = math.inf,
    prior: tuple[float, float] | None = None,
    scale: float = math.inf,
) -> tuple[FloatArray, FloatArray]:
    """Least cost ``(T,)`` over the directions of travel ``phis`` (P,) (an even grid over
    [-pi/2, pi/2)) for each yaw, and the direction ``(T,)`` that gives it. A match costs its
    squared Sampson distance ``r^2``, at most ``cap``, or with a finite ``scale`` the Cauchy
    loss ``scale^2 log(1 + r^2 / scale^2)``; ``prior = (phi0, weight)`` adds
    ``weight * (phi - phi0)^2`` (modulo pi). Without a cap the best grid direction is refined by
    a parabola through it and its neighbours (the cost is then smooth in the yaw)."""

    def loss(r2: FloatArray) -> FloatArray:
        if math.isfinite(cap):
            return np.minimum(r2, cap)
        if math.isfinite(scale):
            return np.asarray(scale * scale * np.log1p(r2 / (scale * scale)), np.float64)
        return r2

    def penalty(ph: FloatArray) -> FloatArray:
        if prior is None:
            return np.zeros(ph.shape)
        d = (ph - prior[0] + math.pi / 2) % math.pi - math.pi / 2
        return np.asarray(prior[1] * d * d, np.float64)

    best = np.empty(yaws.size)
    arg = np.empty(yaws.size)
    step = float(phis[1] - phis[0]) if phis.size > 1 else 0.0
    # bound the (T, P, n) block to about 4 million values
    chunk = max(1, int(4_000_000 // max(1, phis.size * x1.shape[0])))
    for a in range(0, yaws.size, chunk):
        ys = yaws[a : a + chunk]
        r2 = sampson_planar(x1, x2, ys, phis, focal)
        cost = loss(r2).sum(axis=2)
        cost += penalty(phis)[None, :]
        k = np.argmin(cost, axis=1)
        rows = np.arange(cost.shape[0])
        c0 = cost[rows, k]
        ph = phis[k]
        if not math.isfinite(cap) and phis.size >= 3:
            # the direction grid wraps around (phi and phi + pi are the same motion)
            cm = cost[rows, (k - 1) % phis.size]
            cp = cost[rows, (k + 1) % phis.size]
            den = cm - 2.0 * c0 + cp
            ok = den > 0
            off = np.where(ok, 0.5 * (cm - cp) / np.where(ok, den, 1.0), 0.0)
            off = np.clip(off, -0.5, 0.5)
            ph = ph + off * step
            refined = np.array(
                [
                    float(loss(sampson_planar(x1, x2, ys[t : t + 1], ph[t : t + 1], focal)).sum())
                    for t in range(ys.size)
                ]
            )
            refined += penalty(ph)
            c0 = np.minimum(c0, refined)
            ph = np.where(refined <= cost[rows, k], ph, phis[k])
        best[a : a + chunk] = c0
        arg[a : a + chunk] = ph
    return best, arg


def _half_width(yaws: FloatArray, chi: FloatArray, k: int) -> float:
    """Distance [rad] from ``yaws[k]`` to where ``chi`` first reaches 1 on each side (the
    larger of the two, linearly interpolated); ``inf`` when it does not on a side."""
    widths = []
    for side in (-1, 1):
        idx = np.arange(k + side, -1 if side < 0 else yaws.size, side)
        hit = idx[chi[idx] >= 1.0]
        if hit.size == 0:
            return math.inf
        j = int(hit[0])
        prev = j - side
        lo, hi = float(chi[prev]), float(chi[j])
        frac = 1.0 if hi <= lo else (1.0 - lo) / (hi - lo)
        frac = min(max(frac, 0.0), 1.0)
        widths.append(abs(float(yaws[prev] - yaws[k])) + frac * abs(float(yaws[j] - yaws[prev])))
    return max(widths)


def planar_yaw(
    src: ArrayLike,
    dst: ArrayLike,
    K: ArrayLike,
    yaw0: float,
    window: float,
    *,
    threshold: float = 1.0,
    min_matches: int = 8,
    direction: float | None = None,
    direction_sigma: float = math.inf,
) -> PlanarYaw:
    """Fit a planar motion to the matches ``src -> dst``; return the yaw and its uncertainty.

    Parameters
    ----------
    src, dst : (n, 2) arrays
        Undistorted pixel positions of the matches in the stored and in the query view
        (:func:`symloc.vision.two_view.ratio_matches` of undistorted features).
    K : (3, 3) array
        Camera matrix [px].
    yaw0 : float
        Expected yaw [rad] (e.g. the relative heading of two map poses).
    window : float
        The yaw is searched within ``yaw0 +- window`` [rad], in (0, pi/2].
    threshold : float
        Expected Sampson distance [px] of a correct match; a match costs at most
        ``(2.5 threshold)^2``, and counts as an inlier below ``2.5 threshold``.
    min_matches : int
        Fewer matches: no fit.
    direction, direction_sigma : float, optional
        Expected direction of travel [rad] (``phi``, modulo pi) and its standard deviation
        [rad]: a prior that costs ``threshold^2 ((phi - direction) / direction_sigma)^2``.
        Driving straight at a wall the images hardly tell a yaw error from a turned direction of
        travel (the cost valley turns the direction about ten times faster than the yaw); the
        odometry's direction of travel settles it.
    """
    p1 = np.asarray(src, np.float64).reshape(-1, 2)
    p2 = np.asarray(dst, np.float64).reshape(-1, 2)
    Km = np.asarray(K, np.float64)
    if p1.shape != p2.shape:
        raise ConfigurationError(f"src, dst: {p1.shape[0]} and {p2.shape[0]} points")
    if not (math.isfinite(window) and 0.0 < window <= math.pi / 2):
        raise ConfigurationError(f"window: expected an angle in (0, pi/2] rad, got {window}")
    if not (math.isfinite(threshold) and threshold > 0):
        raise ConfigurationError(f"threshold: expected a distance > 0 px, got {threshold}")
    n = int(p1.shape[0])
    if n < max(2, min_matches):
        return PlanarYaw(math.nan, math.inf, 0, n)
    if n > MAX_MATCHES:
        keep = np.linspace(0, n - 1, MAX_MATCHES).round().astype(np.int64)
        p1, p2 = p1[keep], p2[keep]
    focal = float(Km[0, 0])
    x1, x2 = _rays(p1, Km), _rays(p2, Km)
    cap = (2.5 * threshold) ** 2
    prior = None
    if direction is not None and math.isfinite(direction) and direction_sigma < math.inf:
        if not direction_sigma > 0:
            raise ConfigurationError(
                f"direction_sigma: expected an angle > 0 rad, got {direction_sigma}"
            )
        prior = (float(direction), threshold**2 / direction_sigma**2)
    # 1. robust search: 0.25 deg x 3 deg over the window and every direction of travel
    coarse_yaws = yaw0 + np.arange(-window, window + 1e-12, math.radians(0.25))
    coarse_phis = np.radians(np.arange(-90.0, 90.0, 3.0))
    cost, phi = _profile(x1, x2, focal, coarse_yaws, coarse_phis, cap, prior)
    k = int(np.argmin(cost))
    r2 = sampson_planar(x1, x2, coarse_yaws[k : k + 1], phi[k : k + 1], focal)[0, 0]
    inl = r2 < cap
    if int(inl.sum()) < max(2, min_matches):
        return PlanarYaw(math.nan, math.inf, int(inl.sum()), n)
    # 2. the profile of a smooth robust loss (Cauchy, scale ``threshold``) over all matches:
    # smooth in the yaw, and no hard inlier set chosen at the coarse fit to bias it
    span = math.radians(PROFILE_SPAN_DEG)
    yaws = coarse_yaws[k] + np.arange(-span, span + 1e-12, math.radians(0.1))
    yaws = yaws[np.abs(yaws - yaw0) <= window + 1e-12]
    phis = np.radians(np.arange(-90.0, 90.0, 1.0))
    prof, pphi = _profile(x1, x2, focal, yaws, phis, prior=prior, scale=threshold)
    j = int(np.argmin(prof))
    yaw = float(yaws[j])
    travel = float(pphi[j])
    if 0 < j < yaws.size - 1:
        a, b, c = prof[j - 1], prof[j], prof[j + 1]
        den = a - 2.0 * b + c
        if den > 0:
            yaw += float(np.clip(0.5 * (a - c) / den, -0.5, 0.5)) * float(yaws[1] - yaws[0])
    r2 = sampson_planar(x1, x2, np.array([yaw]), np.array([travel]), focal)[0, 0]
    inl = r2 < cap
    var = max(float(r2[inl].mean()) if inl.any() else cap, 0.05)
    sigma = _half_width(yaws, (prof - prof[j]) / var, j)
    travel = float((travel + math.pi / 2) % math.pi - math.pi / 2)
    return PlanarYaw(yaw, sigma, int(inl.sum()), int(x1.shape[0]), travel, math.sqrt(var))


def travel_prior(
    relative_poses: ArrayLike, position_sigma: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """The direction of travel (``phi`` of :func:`planar_yaw`) that map poses predict, and how
    sure it is.

    Parameters
    ----------
    relative_poses : (M, 3) array
        The query view's robot pose in the stored view's robot frame (forward [m], left [m],
        turn [rad]; :func:`symloc.geometry.relative` of the two map poses).
    position_sigma : float or (M,) array
        Standard deviation [m] of that relative position.

    Returns
    -------
    direction, direction_sigma : (M,) float64
        ``phi`` [rad] in the stored camera's frame (x right, z forward; ``t = -R c``, ``c``
        the query camera's centre) and its standard deviation [rad], the position's std over
        the distance between the views.
    """
    rel = np.asarray(relative_poses, np.float64).reshape(-1, 3)
    c, sn = np.cos(rel[:, 2]), np.sin(rel[:, 2])
    cx, cz = -rel[:, 1], rel[:, 0]
    direction = np.arctan2(-(c * cx + sn * cz), -(-sn * cx + c * cz))
    sigma = np.arctan2(np.asarray(position_sigma, np.float64), np.hypot(rel[:, 0], rel[:, 1]))
    return np.asarray(direction, np.float64), np.broadcast_to(sigma, direction.shape).copy()
