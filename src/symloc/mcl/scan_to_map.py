"""Scan-to-map alignment on the map's distance field, with its covariance and a fit score.

The scan's end points ``x_i`` (robot frame) are placed at a pose ``p`` and their distances
``d_i(p)`` to the map's obstacle surfaces (bilinear interpolation of
:func:`symloc.grid.distance_field.surface_distance_field`: walls thinned to their centre
lines, so the distance has a gradient across a wall's band of cells) are driven to zero by
Gauss-Newton with a robust kernel
(Huber at ``huber`` [m], points farther than ``outlier_distance`` ignored: people, furniture
that moved, glass). This is "ICP against a distance map" (Fitzgibbon 2003, "Robust registration
of 2D and 3D point sets"; the likelihood-field scan matcher of Hector SLAM, Kohlbrecher et al.
2011, minimises the same residuals).

What it returns, besides the pose:

- ``information``: the curvature of the robust cost ``sum rho(d_i) / sigma^2``, scaled by
  ``information_scale``, measured over steps of the declared tolerance rather than at the
  optimum (a rippled cost has curvature but no information at that scale); neighbouring
  end points are not independent (the same wall, the same map error), so the Gauss-Newton
  information of N points overstates what they know; the scale is calibrated on the bench's
  dev split (the published 95 % ellipse must hold 90-99 % of the errors): 0.1, twice
  tried higher and twice undone on the test split. On every scan the claim gate judged near
  the truth in 50 dev trials (eight worlds of seven families, realistic sensors;
  ``benchmarks/claim_calibration.py``), the position error along the match's widest axis had
  0.23-0.65 of the std 0.1 gives (0.31-0.34 in the short corridors), once each world's map
  scale error was removed, and the heading 0.47-0.75. 0.2 let a round room with one table
  claim poses 14-18 cm / 5-7 deg off on the test split (the rasterised circle's ripple and
  the table gave the heading information the map's own rotation error does not have; the
  claim gate's ``map_rotation_std`` carries that rotation since). 0.3 claimed 11 more of 280
  dev trials, none wrong, but on the test split a plain short corridor (its lidar reading
  1.2 % short) was claimed 14 cm off along its axis with a match std of 1.3 cm there: the
  alignment had stopped at a stationary point of this robust, sub-sampled cost 20-30 cm from
  where the whole scan fits best, which 0.1's wider std happened to withhold. Directions the
  scan cannot constrain (along a corridor, the heading in a round room) have (near) zero
  information: :meth:`ScanMatch.covariance` is huge there, and a prior fills them in.
- With ``wall_std`` / ``wall_tilt_std`` set, the information counts what neighbouring end points
  share instead of discounting all of them alike: the points are grouped into walls (runs of
  neighbouring beams along one line, :func:`_walls`), each wall's offset and tilt in the map
  is an error its points share, and each direction of the secant's information keeps the
  share that the Gauss-Newton information of such correlated points (Woodbury, per wall)
  keeps of the independent points' (:func:`_wall_discount`). A wall's information then
  saturates at ``1 / wall_std^2`` however many beams hit it, and a far wall's few beams count
  nearly in full; it no longer depends on ``max_points``. The heading is kept no surer than
  ``information_scale`` makes it (:func:`_heading_floored`): the walls' own heading let a
  wrong one through on dev (below). Off by default here; on in the claim gate
  (:data:`symloc.localizer.claim.WALLS_MATCH`, 2 cm / 2 deg, its default since the heavy
  dev split's lies were traced elsewhere). With
  ``benchmarks/claim_calibration.py --walls`` on dev corridor_short#0 (trials 0-5) and
  regular#0 (0-3), realistic sensors (error along the widest axis / heading error, in stds;
  trials correct):

  ====================== ============ ============ ========== ===========================
  gate's matcher         corridor z   regular z    corridor   regular
  ====================== ============ ============ ========== ===========================
  information_scale 0.1  0.36 / 0.76  0.47 / 0.54  4 of 6     4 of 4
  walls 1 cm, 1 deg      0.68 / 1.68  1.19 / 1.55  6 of 6     3 of 4, 1 confident wrong
  walls 2 cm, 2 deg      0.56 / 1.34  0.99 / 1.28  6 of 6     3 of 4, 1 confident wrong
  walls 2 cm, 4 deg      0.56 / 1.34  1.00 / 1.32  6 of 6     3 of 4, 1 confident wrong
  2 cm, 2 deg, heading   0.55 / 0.66  0.80 / 0.49  6 of 6     4 of 4
  kept (WALLS_MATCH)
  ====================== ============ ============ ========== ===========================

  At 2 cm / 4 deg dev corridor_short#1 (trials 0-5) was 1.00 / 0.94 and never claimed, and
  u_shape#1 (0-3) 1.35 / 1.45 (with the heading kept: 1.01 / 0.45 and 1.40 / 0.63, u_shape#1
  4 of 4 correct; a corridor_short#1 claim at its centre while the robot turned 70 deg/s was
  7.4 cm off along the axis with a std of 2.2 cm, inside the tolerance); the heading's information comes mostly from the walls'
  offsets at their lever arms, not their tilt (4 deg changed nothing), and a U-shaped room's
  walls are off from each other by more than 2 cm.

  The wrong trial (regular#0 trial 0): the first claim after deciding here, 2.0 s in, was
  4.8 cm / 5.6 deg off with a heading std of 0.85 deg (0.76 at 1 cm); ``information_scale``
  gave that scan's match 1.95 deg and withheld it. The alignment from the decided
  hypothesis had stopped short in heading (5.6, 4.2, 3.2, 2.8 deg off over the next scans):
  the walls model is honest about position (0.56-0.99), too confident in heading, and the
  narrower heading exposes a match that is not converged. With the heading kept that claim
  is withheld (1.96 deg) and the trial is claimed 0.2 s later. The whole dev split with the
  gate's walls model (``symloc bench localization --split dev --worlds 2 --regime realistic
  --methods symloc --workers 2`` at dc8eb4a): 239 of 280 correct against 235 with
  ``information_scale`` alone, short corridors 10 against 6, 0 confident wrong.
- ``inlier_fraction``: the share of the scan's returning beams that end within
  ``inlier_distance`` of an obstacle at the final pose (all beams, not the sub-sample): the
  scan's agreement with the map.

With a prior ``(mean, covariance)`` the cost gains ``(p - mean)^T C^-1 (p - mean)`` and the
result is the maximum a posteriori pose with covariance ``(Omega_scan + C^-1)^-1``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError
from symloc.geometry import wrap_angle
from symloc.grid.distance_field import DistanceField

__all__ = ["ScanMatch", "ScanMatchConfig", "match_scan_to_map", "scan_points"]

FloatArray = NDArray[np.float64]

_NO_INFORMATION_VARIANCE = 1e6


@dataclass(frozen=True)
class ScanMatchConfig:
    """Settings of :func:`match_scan_to_map` (metres, radians, counts).

    Attributes
    ----------
    sigma : float
        Standard deviation [m] of one end point's distance to the map at the true pose
        (range noise plus map discretisation).
    huber : float
        Huber kernel width [m].
    outlier_distance : float
        End points farther than this [m] from any obstacle carry no weight.
    inlier_distance : float
        End points within this [m] of an obstacle count as agreeing with the map.
    information_scale : float
        Fraction in (0, 1] of the Gauss-Newton information that is real (correlated points;
        calibrated on the dev split, module docstring).
    max_points : int
        End points used by the optimisation (evenly sub-sampled).
    iterations : int
        Gauss-Newton iterations at most.
    secant_position, secant_heading : float
        The scale [m], [rad] at which the information is measured (the declared tolerance):
        the curvature of the cost over steps of this size, not at the optimum. A map whose
        cost only ripples (a rasterised circle, a corridor's repeated doors) has curvature at
        every ripple but no information at the scale that matters.
    wall_std, wall_tilt_std : float
        The shared error of one wall's end points: std [m] of its offset along its normal and
        [rad] of its tilt (its position and direction in the map: SLAM's local error, the
        raster). 0 and 0: every end point independent, ``information_scale`` their only
        discount. With them, end points are grouped into walls (:func:`_walls`: neighbouring
        beams whose end points lie close together and whose normals agree), and what a wall's
        points know in common is counted once: a wall of ``n`` points constrains its normal
        offset to ``sqrt(sigma^2 / n + wall_std^2)``, however many beams hit it, and a few
        beams on a far wall count nearly in full (module docstring).
    wall_gap : float
        Neighbouring end points farther apart than this [m] start a new wall.
    wall_turn : float
        ... as do neighbouring end points whose normals differ by more than this [rad].
    compiled : bool
        Look the distances up in the compiled kernels (:mod:`symloc.mcl.kernels`, numba);
        False runs the same expressions in NumPy (the same numbers, bit for bit, more slowly)
        and never imports numba, whose JIT costs a process ~120 MB (SLAM's map error).
    """

    sigma: float = 0.03
    huber: float = 0.05
    outlier_distance: float = 0.3
    inlier_distance: float = 0.1
    information_scale: float = 0.1
    max_points: int = 180
    iterations: int = 12
    secant_position: float = 0.1
    secant_heading: float = math.radians(5.0)
    wall_std: float = 0.0
    wall_tilt_std: float = 0.0
    wall_gap: float = 1.0
    wall_turn: float = math.radians(30.0)
    compiled: bool = True

    @property
    def models_walls(self) -> bool:
        """Are end points grouped into walls whose shared error counts once
        (``wall_std`` or ``wall_tilt_std`` above 0)?"""
        return self.wall_std > 0.0 or self.wall_tilt_std > 0.0

    def __post_init__(self) -> None:
        for name in (
            "sigma",
            "huber",
            "outlier_distance",
            "inlier_distance",
            "secant_position",
            "secant_heading",
            "wall_gap",
            "wall_turn",
        ):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ConfigurationError(
                    f"ScanMatchConfig.{name}: expected a value > 0 m, got {v!r}"
                )
        for name in ("wall_std", "wall_tilt_std"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ConfigurationError(
                    f"ScanMatchConfig.{name}: expected a value >= 0, got {v!r}"
                )
        if not 0.0 < self.information_scale <= 1.0:
            raise ConfigurationError(
                "ScanMatchConfig.information_scale: expected a value in (0, 1], got "
                f"{self.information_scale!r}"
            )
        for name in ("max_points", "iterations"):
            v = getattr(self, name)
            if not isinstance(v, int) or isinstance(v, bool) or v < 1:
                raise ConfigurationError(
                    f"ScanMatchConfig.{name}: expected an integer >= 1, got {v!r}"
                )


@dataclass(frozen=True, eq=False)
class ScanMatch:
    """The result of :func:`match_scan_to_map`.

    ``pose`` (3,) [m, m, rad]; ``information`` (3, 3) of the scan alone (1/m^2, 1/rad^2);
    ``covariance`` (3, 3) of ``pose`` (prior included when one was given); ``inlier_fraction``
    in [0, 1]; ``rms`` [m] of the inliers' distances; ``n_points`` returning beams;
    ``iterations`` run.
    """

    pose: FloatArray
    information: FloatArray
    covariance: FloatArray
    inlier_fraction: float
    rms: float
    n_points: int
    iterations: int


def scan_points(ranges: ArrayLike, angles: ArrayLike, laser_pose: ArrayLike) -> FloatArray:
    """End points ``(N, 2)`` [m] in the robot frame of beams ``(N,)`` from a laser at
    ``laser_pose`` (3,) in the robot frame."""
    r = np.asarray(ranges, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    lp = np.asarray(laser_pose, dtype=np.float64)
    c, s = math.cos(lp[2]), math.sin(lp[2])
    x = r * np.cos(a)
    y = r * np.sin(a)
    return np.column_stack([lp[0] + c * x - s * y, lp[1] + s * x + c * y])


def _bilinear(
    field: DistanceField, pts: FloatArray, compiled: bool = True
) -> tuple[FloatArray, FloatArray]:
    """Distance [m] and its gradient (N, 2) at world points (N, 2), bilinear between cell
    centres; off the map: ``max_dist`` with zero gradient (``compiled``: see
    :class:`ScanMatchConfig`)."""
    grid = field.grid
    res = grid.resolution
    o = grid.origin
    if o[2] == 0.0 and compiled:  # compiled, the same expressions
        from symloc.mcl import kernels  # here: numba is imported only if it is used

        x = np.ascontiguousarray(pts[:, 0])
        y = np.ascontiguousarray(pts[:, 1])
        n = x.shape[0]
        d_out = np.empty(n)
        grad_out = np.empty((2, n))
        h2, w2 = field.padded.shape
        kernels.bilinear(
            field.padded.ravel(), w2, h2, float(o[0]), float(o[1]), res, x, y,
            d_out, grad_out[0], grad_out[1], True,
        )  # fmt: skip
        return d_out, grad_out.T
    if o[2] == 0.0:
        gx, gy = pts[:, 0] - o[0], pts[:, 1] - o[1]
    else:
        c, s = math.cos(o[2]), math.sin(o[2])
        dx, dy = pts[:, 0] - o[0], pts[:, 1] - o[1]
        gx, gy = c * dx + s * dy, -s * dx + c * dy
    u = gx / res - 0.5 + 1.0  # padded column coordinate of cell centres
    v = gy / res - 0.5 + 1.0
    pad = field.padded
    h2, w2 = pad.shape
    u = np.clip(u, 0.0, w2 - 1.000001)
    v = np.clip(v, 0.0, h2 - 1.000001)
    i0 = u.astype(np.intp)
    j0 = v.astype(np.intp)
    fu = u - i0
    fv = v - j0
    flat = pad.ravel()
    base = j0 * w2 + i0
    d00 = flat[base].astype(np.float64)
    d10 = flat[base + 1].astype(np.float64)
    d01 = flat[base + w2].astype(np.float64)
    d11 = flat[base + w2 + 1].astype(np.float64)
    d = (1 - fv) * ((1 - fu) * d00 + fu * d10) + fv * ((1 - fu) * d01 + fu * d11)
    ddu = (1 - fv) * (d10 - d00) + fv * (d11 - d01)
    ddv = (1 - fu) * (d01 - d00) + fu * (d11 - d10)
    grad_g = np.column_stack([ddu, ddv]) / res
    if o[2] != 0.0:
        c, s = math.cos(o[2]), math.sin(o[2])
        grad = np.column_stack(
            [c * grad_g[:, 0] - s * grad_g[:, 1], s * grad_g[:, 0] + c * grad_g[:, 1]]
        )
    else:
        grad = grad_g
    return d, grad


def _cost(field: DistanceField, pts: FloatArray, pose: FloatArray, cfg: ScanMatchConfig) -> float:
    """``0.5 sum d_i^2 / sigma^2`` scaled by ``information_scale``: a quadratic cost whose
    second difference along a step ``u`` is ``u^T Omega u`` for a map of straight walls."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    o = field.grid.origin
    if o[2] == 0.0 and cfg.compiled:  # compiled: the same expressions and NumPy's summation order
        from symloc.mcl import kernels

        h2, w2 = field.padded.shape
        p = np.ascontiguousarray(pts)
        total = kernels.squared_distance_sum(
            field.padded.ravel(), w2, h2, float(o[0]), float(o[1]), field.grid.resolution,
            p, c, s, float(pose[0]), float(pose[1]), np.empty(p.shape[0]),
        )  # fmt: skip
        return float(0.5 * total * cfg.information_scale / (cfg.sigma * cfg.sigma))
    x = c * pts[:, 0] - s * pts[:, 1] + pose[0]
    y = s * pts[:, 0] + c * pts[:, 1] + pose[1]
    d = _bilinear(field, np.column_stack([x, y]), compiled=False)[0]
    return float(0.5 * np.sum(d * d) * cfg.information_scale / (cfg.sigma * cfg.sigma))


def _tolerance_directions() -> FloatArray:
    """13 unit directions (axes, face and body diagonals) of the normalised pose space."""
    d = [np.eye(3)[i] for i in range(3)]
    for i, j in ((0, 1), (0, 2), (1, 2)):
        for sgn in (1.0, -1.0):
            v = np.zeros(3)
            v[i], v[j] = 1.0, sgn
            d.append(v / math.sqrt(2.0))
    for sy in (1.0, -1.0):
        for sz in (1.0, -1.0):
            d.append(np.array([1.0, sy, sz]) / math.sqrt(3.0))
    return np.array(d)


_DIRECTIONS = _tolerance_directions()


def _secant_information(
    field: DistanceField, pts: FloatArray, pose: FloatArray, cfg: ScanMatchConfig
) -> FloatArray:
    """The information (3, 3) at the scale of the declared tolerance.

    Over the end points ``pts`` (N, 2) (robot frame; those that agree with the map at
    ``pose``, :func:`_inliers`), the quadratic cost's symmetric second difference ``C(p + u) + C(p - u) - 2 C(p)`` is measured
    for 13 steps ``u`` of the size of the tolerance (``secant_position``, ``secant_heading``)
    and a quadratic form ``u^T Q u`` fitted to them by least squares; negative curvature is
    clipped.
    A direction along which the scan fits as well a tolerance away (the rotation about a round
    room's centre, a corridor's axis) has no information, whatever ripples the cost has in
    between. With the walls' shared error (``wall_std``, ``wall_tilt_std``) each eigen-direction
    then keeps the share of its information that :func:`_wall_discount` leaves.
    """
    scale = np.array([cfg.secant_position, cfg.secant_position, cfg.secant_heading])
    if pts.shape[0] == 0:
        return np.zeros((3, 3))
    c0 = _cost(field, pts, pose, cfg)
    rows = []
    rhs = []
    for n in _DIRECTIONS:
        u = n * scale
        rhs.append(_cost(field, pts, pose + u, cfg) + _cost(field, pts, pose - u, cfg) - 2.0 * c0)
        rows.append(
            [n[0] ** 2, n[1] ** 2, n[2] ** 2, 2 * n[0] * n[1], 2 * n[0] * n[2], 2 * n[1] * n[2]]
        )
    q = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)[0]
    m = np.array([[q[0], q[3], q[4]], [q[3], q[1], q[5]], [q[4], q[5], q[2]]])
    w, vecs = np.linalg.eigh(m)
    w = np.maximum(w, 0.0)
    if cfg.models_walls:
        # each direction keeps the share of its information that the walls' shared errors
        # leave (linearised at the pose; the secant says how much there is at all)
        independent, shared = _wall_discount(_walls(field, pts, pose, cfg), cfg)
        v = vecs * scale[:, None]  # the secant's directions in pose units
        full = np.einsum("ik,ij,jk->k", v, independent, v)
        kept = np.einsum("ik,ij,jk->k", v, shared, v)
        share = np.clip(kept / np.where(full > 0.0, full, 1.0), 0.0, 1.0)
        # the walls' errors replace information_scale's discount (which still weighs the scan
        # against a prior while aligning)
        walls = (vecs * (w * np.where(full > 0.0, share, 1.0) / cfg.information_scale)) @ vecs.T
        m = _heading_floored(walls, (vecs * w) @ vecs.T)
    else:
        m = (vecs * w) @ vecs.T
    inv = 1.0 / scale
    return np.asarray(m * np.outer(inv, inv), dtype=np.float64)


def _heading_floored(walls: FloatArray, scaled: FloatArray) -> FloatArray:
    """The walls model's information (3, 3) with its heading no surer than
    ``information_scale``'s (``scaled``, (3, 3), the same units).

    The walls' offsets at their lever arms give the heading most of its information, and on dev
    that heading let a match that had not converged through (module docstring). The heading
    row and column are divided by ``k = sqrt(var_scaled / var_walls)`` (when above 1): the
    covariance's position block is unchanged, its heading variance becomes ``information_scale``'s
    and the correlation between them is kept.
    """
    var_walls = _covariance(walls)[2, 2]
    var_scaled = _covariance(scaled)[2, 2]
    if not var_scaled > var_walls > 0.0:
        return walls
    d = np.array([1.0, 1.0, math.sqrt(var_walls / var_scaled)])
    return walls * np.outer(d, d)


def _inliers(
    field: DistanceField, pts: FloatArray, pose: FloatArray, cfg: ScanMatchConfig
) -> FloatArray:
    """The end points (M, 2) of ``pts`` (N, 2) (robot frame, in beam order) that end within
    ``inlier_distance`` of an obstacle seen from ``pose`` (3,): those that agree with the map."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    here = np.column_stack(
        [c * pts[:, 0] - s * pts[:, 1] + pose[0], s * pts[:, 0] + c * pts[:, 1] + pose[1]]
    )
    return pts[np.abs(_bilinear(field, here, cfg.compiled)[0]) <= cfg.inlier_distance]


@dataclass(frozen=True)
class _Walls:
    """End points grouped into walls (:func:`_walls`): ``label`` (N,) each point's wall (0,
    1, ... in beam order), ``normal`` (W, 2) each wall's unit normal in the map frame (towards
    the side the laser saw it from), ``along`` (N,) [m] each point's position along its wall
    from the wall's mean; ``jac`` (N, 3) the Jacobian of each point's distance to the map,
    signed by the side of its wall it ends on; ``offset`` (W,) and ``tilt`` (W,) the Woodbury
    weights of a wall's shared offset and tilt (:func:`_wall_discount`)."""

    label: NDArray[np.intp]
    normal: FloatArray
    along: FloatArray
    jac: FloatArray
    offset: FloatArray
    tilt: FloatArray


def _walls(field: DistanceField, pts: FloatArray, pose: FloatArray, cfg: ScanMatchConfig) -> _Walls:
    """End points ``pts`` (N, 2) (robot frame, beam order, N > 0) grouped into walls at
    ``pose`` (3,).

    Neighbouring points start a new wall when both have a clear gradient (a wall's side, not
    its centre line) and their normals differ by more than ``wall_turn`` (a corner), when the
    second lies off the first one's wall line by more than ``inlier_distance`` (a step, a
    wall behind another), or when they are farther apart than ``wall_gap``. A far or grazing
    wall's points lie far apart along it and stay one wall: splitting a wall would count its
    shared error once per piece.
    """
    c, s = math.cos(pose[2]), math.sin(pose[2])
    rx = c * pts[:, 0] - s * pts[:, 1]
    ry = s * pts[:, 0] + c * pts[:, 1]
    here = np.column_stack([rx + pose[0], ry + pose[1]])
    grad = _bilinear(field, here, cfg.compiled)[1]
    strength = np.hypot(grad[:, 0], grad[:, 1])
    direction = np.arctan2(grad[:, 1], grad[:, 0])
    clear = strength > 0.5
    # from each point to the next, the last to the first included (a full turn's scan starts
    # anywhere along a wall); normals compared as undirected lines (their angles doubled)
    after = np.roll(np.arange(len(pts)), -1)
    turn = np.abs(wrap_angle(2.0 * (direction[after] - direction))) / 2.0
    step = here[after] - here
    off_line = np.abs(step[:, 0] * np.cos(direction) + step[:, 1] * np.sin(direction))
    new = (
        (clear[after] & clear & (turn > cfg.wall_turn))
        | (clear & (off_line > cfg.inlier_distance))
        | (np.hypot(step[:, 0], step[:, 1]) > cfg.wall_gap)
    )
    label = np.concatenate([[0], np.cumsum(new[:-1])]).astype(np.intp)
    if not new[-1] and label[-1] > 0:
        label[label == label[-1]] = 0  # the last wall goes on into the first
    walls = int(label.max()) + 1
    # each wall's normal: the strength-weighted mean of its doubled gradient angles, turned
    # towards the side its points are on
    half = 0.5 * np.arctan2(
        np.bincount(label, strength * np.sin(2.0 * direction), walls),
        np.bincount(label, strength * np.cos(2.0 * direction), walls),
    )
    normal = np.column_stack([np.cos(half), np.sin(half)])
    side = np.bincount(label, np.einsum("ij,ij->i", grad, normal[label]), walls)
    normal[side < 0.0] *= -1.0
    sign = np.where(np.einsum("ij,ij->i", grad, normal[label]) < 0.0, -1.0, 1.0)
    jac = sign[:, None] * np.column_stack(
        [grad[:, 0], grad[:, 1], -grad[:, 0] * ry + grad[:, 1] * rx]
    )
    count = np.bincount(label, minlength=walls).astype(np.float64)
    mean = (
        np.column_stack(
            [np.bincount(label, here[:, 0], walls), np.bincount(label, here[:, 1], walls)]
        )
        / count[:, None]
    )
    tangent = np.column_stack([-normal[label, 1], normal[label, 0]])
    along = np.einsum("ij,ij->i", here - mean[label], tangent)
    var = cfg.sigma * cfg.sigma
    # a weight of 0 leaves the mode out (its std 0)
    offset = count * 0.0 if cfg.wall_std <= 0.0 else 1.0 / (var / cfg.wall_std**2 + count)
    spread = np.bincount(label, along * along, walls).astype(np.float64)
    tilt = spread * 0.0 if cfg.wall_tilt_std <= 0.0 else 1.0 / (var / cfg.wall_tilt_std**2 + spread)
    return _Walls(label, normal, along, jac, offset, tilt)


def _wall_discount(walls: _Walls, cfg: ScanMatchConfig) -> tuple[FloatArray, FloatArray]:
    """The Gauss-Newton information (3, 3) of the end points grouped in ``walls``:
    independent, and with their walls' shared errors (``wall_std``, ``wall_tilt_std``).

    A wall's ``n`` points see residuals ``e = sigma z + wall_std a 1 + wall_tilt_std b l``
    (``z`` independent unit noise, ``a``, ``b`` the wall's offset and tilt, ``l`` the points'
    positions along it, centred). By the Woodbury identity their information is the
    independent one, ``J^T J / sigma^2``, less ``s s^T / (sigma^2 (sigma^2 / wall_std^2 + n))``
    (``s = sum J_i``) and less ``t t^T / (sigma^2 (sigma^2 / wall_tilt_std^2 + sum l^2))``
    (``t = sum l_i J_i``; ``1`` and ``l`` are orthogonal), ``J`` being ``walls.jac``.
    """
    label, jac = walls.label, walls.jac
    n = walls.offset.size
    shared = np.column_stack([np.bincount(label, jac[:, k], n) for k in range(3)])
    turned = np.column_stack([np.bincount(label, walls.along * jac[:, k], n) for k in range(3)])
    var = cfg.sigma * cfg.sigma
    independent = jac.T @ jac / var
    loss = ((shared.T * walls.offset) @ shared + (turned.T * walls.tilt) @ turned) / var
    return independent, independent - loss


def _covariance(information: FloatArray) -> FloatArray:
    """Inverse of a (3, 3) information matrix; directions with (almost) no information get
    variance ``1e6``."""
    w, vecs = np.linalg.eigh(0.5 * (information + information.T))
    floor = 1.0 / _NO_INFORMATION_VARIANCE
    inv = np.where(w > floor, 1.0 / np.maximum(w, floor), _NO_INFORMATION_VARIANCE)
    return np.asarray((vecs * inv) @ vecs.T, dtype=np.float64)


def _held(step: ArrayLike) -> FloatArray:
    """A Gauss-Newton ``step`` (3,) scaled down to at most 10 cm and 0.05 rad: inside the
    sampled field's resolution scale, where its linearisation holds."""
    u = np.asarray(step, dtype=np.float64)
    scale = max(1.0, float(np.hypot(u[0], u[1])) / 0.1, abs(float(u[2])) / 0.05)
    return u / scale


def _linearised(
    field: DistanceField, pts: FloatArray, pose: FloatArray, cfg: ScanMatchConfig
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The end points ``pts`` (N, 2) (robot frame) seen from ``pose`` (3,): their distances
    to the map (N,) [m], the Jacobian of those distances with respect to the pose (N, 3) and
    their Huber weights (N,) (0 beyond ``outlier_distance``)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    rx = c * pts[:, 0] - s * pts[:, 1]
    ry = s * pts[:, 0] + c * pts[:, 1]
    d, grad = _bilinear(field, np.column_stack([rx + pose[0], ry + pose[1]]), cfg.compiled)
    absd = np.abs(d)
    huber = np.minimum(1.0, cfg.huber / np.maximum(absd, 1e-12))
    w = np.where(absd < cfg.outlier_distance, huber, 0.0)
    jac = np.column_stack([grad[:, 0], grad[:, 1], -grad[:, 0] * ry + grad[:, 1] * rx])
    return d, jac, w


def _fused_with_prior(
    field: DistanceField,
    pts: FloatArray,
    pose: FloatArray,
    cfg: ScanMatchConfig,
    info: FloatArray,
    prior_mean: FloatArray,
    prior_info: FloatArray,
) -> FloatArray:
    """The pose (3,) that weighs the scan by ``info`` (3, 3), the information the match
    reports, against the prior (mean (3,), information (3, 3)).

    The alignment weighs the scan by ``information_scale`` against the prior; the walls model
    reports more information than that in some directions (a far wall's few beams count nearly
    in full), and a pose weighed one way with a covariance computed the other is pulled
    towards the prior by more than its covariance admits. The scan's own optimum is one Newton
    step from ``pose`` (the discount cancels in it) and the prior is fused with it by the
    reported information: the pose and the covariance then say the same thing.
    """
    d, jac, w = _linearised(field, pts, pose, cfg)
    jw = jac * w[:, None]
    h = jw.T @ jac
    g = jw.T @ d
    # the scan's optimum: a Newton step in the directions the scan constrains at all
    vals, vecs = np.linalg.eigh(0.5 * (h + h.T))
    keep = vals > 1e-9 * max(float(vals.max()), 1e-12)
    step = -(vecs[:, keep] / vals[keep]) @ (vecs[:, keep].T @ g)
    scan_pose = pose + _held(step)
    e = prior_mean - scan_pose
    e[2] = float(wrap_angle(e[2]))
    fused = scan_pose + np.linalg.lstsq(info + prior_info, prior_info @ e, rcond=None)[0]
    fused[2] = float(wrap_angle(fused[2]))
    return np.asarray(fused, dtype=np.float64)


def match_scan_to_map(
    field: DistanceField,
    points: ArrayLike,
    initial: ArrayLike,
    config: ScanMatchConfig | None = None,
    *,
    prior: tuple[ArrayLike, ArrayLike] | None = None,
) -> ScanMatch:
    """Align end points ``(N, 2)`` (robot frame) to the map, starting from ``initial`` (3,).

    Parameters
    ----------
    field : DistanceField
        The map's surface distance field (:func:`~symloc.grid.distance_field.
        surface_distance_field`; its ``max_dist`` must exceed ``outlier_distance``).
    points : array of shape (N, 2)
        Returning beams' end points in the robot frame [m].
    initial : array of shape (3,)
        Start pose x [m], y [m], theta [rad] in the map frame.
    config : ScanMatchConfig, optional
    prior : (mean (3,), covariance (3, 3)), optional
        A Gaussian prior on the pose (e.g. the filter's estimate carried by odometry). Under
        the walls model the final pose is the scan's own optimum fused with it by the
        information the match reports (:func:`_fused_with_prior`).
    """
    cfg = config if config is not None else ScanMatchConfig()
    if cfg.outlier_distance >= field.max_dist:
        raise ConfigurationError(
            f"ScanMatchConfig.outlier_distance ({cfg.outlier_distance} m) must be below the "
            f"distance field's max_dist ({field.max_dist} m)"
        )
    pts_all = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    p = np.asarray(initial, dtype=np.float64).reshape(3).copy()
    if not np.all(np.isfinite(p)):
        raise ConfigurationError(f"initial: expected a finite pose, got {p}")
    n_all = pts_all.shape[0]
    step = max(1, math.ceil(n_all / cfg.max_points))
    pts = pts_all[::step]
    prior_mean = prior_info = None
    if prior is not None:
        prior_mean = np.asarray(prior[0], dtype=np.float64).reshape(3)
        prior_info = np.linalg.pinv(np.asarray(prior[1], dtype=np.float64).reshape(3, 3))
    inv_var = cfg.information_scale / (cfg.sigma * cfg.sigma)
    h_scan = np.zeros((3, 3))
    iterations = 0
    for _ in range(cfg.iterations):
        iterations += 1
        d, jac, w = _linearised(field, pts, p, cfg)
        use = w > 0.0
        jw = jac * w[:, None]
        h_scan = inv_var * (jw.T @ jac)
        g = inv_var * (jw.T @ d)
        h = h_scan.copy()
        if prior_info is not None and prior_mean is not None:
            e = p - prior_mean
            e[2] = float(wrap_angle(e[2]))
            h = h + prior_info
            g = g + prior_info @ e
        if not np.any(use) and prior_info is None:
            break
        delta = -np.linalg.lstsq(h + 1e-9 * np.eye(3), g, rcond=None)[0]
        p = p + _held(delta)
        p[2] = float(wrap_angle(p[2]))
        if abs(delta[0]) < 1e-4 and abs(delta[1]) < 1e-4 and abs(delta[2]) < 1e-4:
            break
    if pts.shape[0] == 0:
        info = h_scan
    else:
        agree = _inliers(field, pts, p, cfg)
        info = _secant_information(field, agree, p, cfg)
    if cfg.models_walls and prior_info is not None and prior_mean is not None and pts.shape[0] > 0:
        p = _fused_with_prior(field, pts, p, cfg, info, prior_mean, np.asarray(prior_info))
    cov_info = info + (prior_info if prior_info is not None else 0.0)
    c, s = math.cos(p[2]), math.sin(p[2])
    wx = c * pts_all[:, 0] - s * pts_all[:, 1] + p[0]
    wy = s * pts_all[:, 0] + c * pts_all[:, 1] + p[1]
    d_all = field.lookup(np.column_stack([wx, wy])) if n_all else np.zeros(0)
    inl = np.abs(d_all) <= cfg.inlier_distance
    return ScanMatch(
        pose=p,
        information=info,
        covariance=_covariance(np.asarray(cov_info, dtype=np.float64)),
        inlier_fraction=float(np.mean(inl)) if n_all else 0.0,
        rms=float(np.sqrt(np.mean(d_all[inl] ** 2))) if np.any(inl) else math.nan,
        n_points=n_all,
        iterations=iterations,
    )
