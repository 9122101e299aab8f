"""Trajectory error metrics exactly as the ``evo`` package defines them, in SE(2).

- **ATE** (evo ``evo_ape`` with ``--align``, ``translation_part``): the estimate is first
  aligned to the reference with Umeyama's least-squares rigid alignment (rotation and
  translation, no scale; Umeyama 1991), then ``E_i = ||t_ref_i - t_aligned_i||`` and the
  statistics (RMSE, mean, median, std, min, max) are taken over all poses.
- **RPE** (evo ``evo_rpe``, ``delta=1``, ``delta_unit=frames``, ``all_pairs=False``): for the
  index pairs ``(i, i + delta)`` with ``i = 0, delta, 2 delta, ...``, the relative error
  ``E_ij = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)`` (Q reference, P estimate); its translation norm
  [m] and rotation angle [rad] give the two RMSEs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from symloc._checks import check_array
from symloc.errors import ConfigurationError
from symloc.geometry import compose, inverse, relative, rotation_matrix, wrap_angle

__all__ = [
    "AteResult",
    "MapAgreement",
    "RpeResult",
    "ate",
    "field_coverage",
    "map_agreement",
    "rpe",
    "similarity_residuals",
    "umeyama_se2",
    "umeyama_se2_at",
    "umeyama_sim2",
]

if TYPE_CHECKING:
    from symloc.grid.map_error_field import MapErrorField

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class AteResult:
    """Absolute trajectory error statistics [m] and the alignment used.

    ``alignment`` ``(3,)`` is the SE(2) pose ``ref_from_est`` applied to the estimate;
    ``errors`` ``(N,)`` the per-pose translation errors [m].
    """

    rmse: float
    mean: float
    median: float
    std: float
    min: float
    max: float
    errors: FloatArray
    alignment: FloatArray


@dataclass(frozen=True, slots=True)
class RpeResult:
    """Relative pose error RMSEs: translation [m] and rotation [rad], over ``n_pairs`` pairs."""

    trans_rmse: float
    rot_rmse: float
    trans_mean: float
    rot_mean: float
    n_pairs: int
    delta: int


def _pair(reference: ArrayLike, estimate: ArrayLike) -> tuple[FloatArray, FloatArray]:
    ref = check_array(reference, "reference", shape=(None, 3))
    est = check_array(estimate, "estimate", shape=(None, 3))
    if ref.shape != est.shape:
        raise ConfigurationError(
            f"estimate: expected as many poses as reference ({ref.shape[0]}), got {est.shape[0]}"
        )
    return ref, est


def _umeyama(source: ArrayLike, target: ArrayLike, *, scaled: bool) -> tuple[FloatArray, float]:
    """Umeyama's (1991) least-squares alignment of points ``source`` (N, 2) onto ``target``
    with the reflection guard: the pose ``(3,)`` and the scale (1 unless ``scaled``)."""
    src = check_array(source, "source", shape=(None, 2))
    dst = check_array(target, "target", shape=(None, 2))
    if src.shape != dst.shape or src.shape[0] < 2:
        raise ConfigurationError("source/target: expected the same number (>= 2) of points")
    mu_s = src.mean(axis=0)
    mu_d = dst.mean(axis=0)
    cov = (dst - mu_d).T @ (src - mu_s) / src.shape[0]
    u, d, vt = np.linalg.svd(cov)
    s = np.eye(2)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        s[1, 1] = -1.0
    rot = u @ s @ vt
    scale = 1.0
    if scaled:
        var_s = float(np.mean(np.sum((src - mu_s) ** 2, axis=1)))
        if var_s <= 0.0:
            raise ConfigurationError("source: expected points that are not all the same")
        scale = float(np.trace(np.diag(d) @ s)) / var_s
    t = mu_d - scale * rot @ mu_s
    return np.array([t[0], t[1], np.arctan2(rot[1, 0], rot[0, 0])]), scale


def umeyama_se2(source: ArrayLike, target: ArrayLike) -> FloatArray:
    """Least-squares rigid alignment (no scale) of points ``source`` (N, 2) onto ``target``.

    Returns the pose ``(3,)`` ``target_from_source`` minimising
    ``sum ||target_i - R source_i - t||^2`` (Umeyama 1991, with the reflection guard).
    """
    return _umeyama(source, target, scaled=False)[0]


def umeyama_sim2(source: ArrayLike, target: ArrayLike) -> tuple[FloatArray, float]:
    """Least-squares similarity alignment of points ``source`` (N, 2) onto ``target``: the
    pose ``(3,)`` and scale ``c`` minimising ``sum ||target_i - c R source_i - t||^2``
    (Umeyama 1991, with the reflection guard; evo's ``--correct_scale``)."""
    return _umeyama(source, target, scaled=True)


def similarity_residuals(truth_xy: ArrayLike, slam_xy: ArrayLike) -> tuple[FloatArray, float]:
    """What remains of a trip's SLAM positions ``slam_xy`` (N, 2) [m] once the true positions
    ``truth_xy`` (N, 2) are aligned onto them by a similarity (:func:`umeyama_sim2`): the
    error vectors (N, 2) [m] in the map frame, and the scale. A lidar whose ranges are
    ``(1 + s)`` times too long draws the whole room ``(1 + s)`` times too large, consistently
    (with odometry whose own scale is off by 1-2 %, nothing on the robot can tell it); a rigid
    fit would leave ``s`` times the distance from its centre as error: this one leaves the
    map's distortion."""
    slam = check_array(slam_xy, "slam_xy", shape=(None, 2))
    pose, scale = umeyama_sim2(truth_xy, slam)
    truth = np.asarray(truth_xy, dtype=np.float64)
    errors: FloatArray = slam - (scale * truth @ rotation_matrix(pose[2]).T + pose[:2])
    return errors, scale


#: chi2.ppf(0.95, 2): a 2-D error inside its covariance's 95 % ellipse has a squared
#: Mahalanobis distance at most this (the square of ``symloc.slam.map_error.R95``).
CHI2_2DOF_95 = -2.0 * math.log(0.05)


def field_coverage(
    field: MapErrorField, xy: ArrayLike, errors: ArrayLike, floor_std: float = 0.0
) -> float:
    """The share of the errors ``errors`` (N, 2) [m] at positions ``xy`` (N, 2) [m] (map frame)
    that lie inside the 95 % ellipse of the map's error field
    (:class:`~symloc.grid.map_error_field.MapErrorField`: the covariance of the place nearest
    each position), its eigenvalues raised to ``floor_std`` [m] squared (the claim gate's
    ``map_std_xy``, :meth:`symloc.localizer.claim.ClaimGate.map_error`); NaN for no errors."""
    err = check_array(errors, "errors", shape=(None, 2))
    if err.shape[0] == 0:
        return math.nan
    values, vectors = np.linalg.eigh(field.at(np.asarray(xy, dtype=np.float64)))
    # a place the graph pins exactly has a zero eigenvalue: any error there is outside
    values = np.maximum(values, max(floor_std**2, 1e-12))
    along = np.einsum("nij,ni->nj", vectors, err)
    return float(np.mean(np.sum(along**2 / values, axis=1) <= CHI2_2DOF_95))


def umeyama_se2_at(source: ArrayLike, target: ArrayLike, anchor: ArrayLike) -> FloatArray:
    """The rigid alignment ``target_from_source`` (3,) of points ``source`` (N, 2) onto
    ``target`` (N, 2) that agrees with their similarity alignment (:func:`umeyama_sim2`) at
    ``anchor`` (2,), a point of the target frame.

    When the target is a scaled copy of the source (a map drawn by a lidar whose ranges are
    off by a factor), no rigid frame fits it everywhere: every one is right at one point and
    off by the scale error times the distance from it. :func:`umeyama_se2` puts that point at
    the source's centroid; this puts it at ``anchor``, with the same rotation.
    """
    sim, scale = umeyama_sim2(source, target)
    rot = rotation_matrix(sim[2])
    at = np.asarray(anchor, dtype=np.float64).reshape(2)
    at_source = rot.T @ (at - sim[:2]) / scale
    t = at - rot @ at_source
    return np.array([t[0], t[1], sim[2]])


def ate(reference: ArrayLike, estimate: ArrayLike, *, align: bool = True) -> AteResult:
    """Absolute trajectory error of ``estimate`` (N, 3) against ``reference`` (N, 3).

    With ``align`` (evo's ``-a``), the estimate is rigidly aligned to the reference first.
    """
    ref, est = _pair(reference, estimate)
    if ref.shape[0] < 2:
        raise ConfigurationError("reference: expected at least 2 poses")
    align_pose = umeyama_se2(est[:, :2], ref[:, :2]) if align else np.zeros(3)
    aligned = compose(align_pose, est)
    err = np.linalg.norm(aligned[:, :2] - ref[:, :2], axis=1)
    return AteResult(
        rmse=float(np.sqrt(np.mean(err**2))),
        mean=float(np.mean(err)),
        median=float(np.median(err)),
        std=float(np.std(err)),
        min=float(np.min(err)),
        max=float(np.max(err)),
        errors=err,
        alignment=align_pose,
    )


def rpe(reference: ArrayLike, estimate: ArrayLike, *, delta: int = 1) -> RpeResult:
    """Relative pose error of ``estimate`` (N, 3) against ``reference`` over ``delta`` frames."""
    ref, est = _pair(reference, estimate)
    if not isinstance(delta, (int, np.integer)) or delta < 1:
        raise ConfigurationError(f"delta: expected an integer >= 1 frame, got {delta!r}")
    ids = np.arange(0, ref.shape[0], delta)
    if ids.size < 2:
        raise ConfigurationError(f"reference: expected more than delta={delta} poses")
    i, j = ids[:-1], ids[1:]
    e = compose(inverse(relative(ref[i], ref[j])), relative(est[i], est[j]))
    trans = np.linalg.norm(e[:, :2], axis=1)
    rot = np.abs(wrap_angle(e[:, 2]))
    return RpeResult(
        trans_rmse=float(np.sqrt(np.mean(trans**2))),
        rot_rmse=float(np.sqrt(np.mean(rot**2))),
        trans_mean=float(np.mean(trans)),
        rot_mean=float(np.mean(rot)),
        n_pairs=int(i.size),
        delta=int(delta),
    )


@dataclass(frozen=True, slots=True)
class MapAgreement:
    """Agreement of an estimated grid with a ground-truth grid.

    Attributes
    ----------
    fraction : float
        Of the cells classified (free or occupied) in both maps, the fraction whose class in
        the estimate is found in the truth within ``tolerance`` cells (0: the same cell).
    n_cells : int
        Cells compared.
    occupied_fraction, free_fraction : float
        The same fraction restricted to the estimate's occupied / free cells.
    coverage : float
        Fraction of the truth's free cells that the estimate classifies (free or occupied).
    tolerance : int
        Chebyshev tolerance in truth cells.
    """

    fraction: float
    n_cells: int
    occupied_fraction: float
    free_fraction: float
    coverage: float
    tolerance: int


def map_agreement(estimate: Any, truth: Any, *, tolerance: int = 0) -> MapAgreement:
    """Compare two :class:`~symloc.grid.OccupancyGrid` in the same world frame.

    Each estimate cell is classified as occupied / free with the estimate's thresholds and
    looked up at its centre in the truth; unknown cells in either map are left out.
    """
    if int(tolerance) != tolerance or tolerance < 0:
        raise ConfigurationError(f"tolerance: expected an integer >= 0, got {tolerance!r}")
    est_occ = estimate.occupied_mask
    est_free = estimate.free_mask
    rows, cols = np.nonzero(est_occ | est_free)
    centres = estimate.cell_to_world(np.column_stack([rows, cols]))
    tc = truth.world_to_cell(centres)
    inside = truth.in_bounds(tc)
    t_occ = truth.occupied_mask
    t_free = truth.free_mask
    if tolerance:
        size = 2 * int(tolerance) + 1
        t_occ_tol = ndimage.binary_dilation(t_occ, np.ones((size, size), bool))
        t_free_tol = ndimage.binary_dilation(t_free, np.ones((size, size), bool))
    else:
        t_occ_tol, t_free_tol = t_occ, t_free
    tc_in = tc[inside]
    r_in, c_in = rows[inside], cols[inside]
    known = t_occ[tc_in[:, 0], tc_in[:, 1]] | t_free[tc_in[:, 0], tc_in[:, 1]]
    tc_k = tc_in[known]
    e_occ = est_occ[r_in[known], c_in[known]]
    agree_occ = e_occ & t_occ_tol[tc_k[:, 0], tc_k[:, 1]]
    agree_free = ~e_occ & t_free_tol[tc_k[:, 0], tc_k[:, 1]]
    n = int(tc_k.shape[0])
    n_occ = int(e_occ.sum())
    covered = np.zeros(truth.data.shape, bool)
    covered[tc_k[:, 0], tc_k[:, 1]] = True
    n_truth_free = int(t_free.sum())
    return MapAgreement(
        fraction=float((agree_occ | agree_free).sum() / n) if n else 0.0,
        n_cells=n,
        occupied_fraction=float(agree_occ.sum() / n_occ) if n_occ else 0.0,
        free_fraction=float(agree_free.sum() / (n - n_occ)) if n - n_occ else 0.0,
        coverage=float((covered & t_free).sum() / n_truth_free) if n_truth_free else 0.0,
        tolerance=int(tolerance),
    )
