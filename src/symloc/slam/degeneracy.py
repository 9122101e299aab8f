"""Which directions a scan match constrains, and fusing a match with the odometry prediction.

A scan matched against a long featureless corridor fixes its distance to the walls and its
heading, but not its position along the corridor; in an open hall or with few returns it
may fix nothing. The scan's own geometry says which (:func:`scan_information`): each point
with close neighbours along the scan has a surface normal ``n``, and moving the scan by
``(dx, dy, dtheta)`` moves it off its surfaces by ``n . (dx, dy) + dtheta * (p x n)``; the
3 x 3 ``J^T J / N`` of these point-to-line residuals (the Hessian of point-to-line ICP) has
small eigenvalues along the directions no surface faces. After scaling the heading by a
length ``L`` (the median range of the points, so that a radian and a metre weigh what they
move the points), its eigenvectors with small eigenvalues are the unconstrained directions
(Zhang, Kaess and Singh 2016, "On degeneracy of optimization-based state estimation
problems"). The scan is used rather than the submap: a submap's walls end where the map ends,
which a match reads as a feature that is not there.

:func:`analyse_match` turns the information into a :class:`MatchConstraint`: the covariance
of the match, ``sigma^2`` (the matcher's own error) in every constrained direction divided by
its relative strength, and effectively infinite along degenerate ones (relative eigenvalue
below ``threshold``, or too few points with a surface). :func:`fuse` combines the match with the
odometry prediction by their covariances (one Kalman update): along a degenerate direction
the prediction is kept, so the position along a corridor drifts only as the odometry does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.geometry import wrap_angle

__all__ = ["UNCONSTRAINED_SIGMA", "MatchConstraint", "analyse_match", "fuse", "scan_information"]

FloatArray = NDArray[np.float64]

#: Standard deviation [m or rad] given to a direction the match does not constrain.
UNCONSTRAINED_SIGMA = 1.0e3


@dataclass(frozen=True, slots=True)
class MatchConstraint:
    """What one scan match says about the pose.

    Attributes
    ----------
    covariance : ndarray of shape (3, 3)
        Covariance of the matched pose (x [m], y [m], theta [rad]).
    strengths : ndarray of shape (3,)
        Relative eigenvalues of the scaled curvature (largest 1), ascending.
    directions : ndarray of shape (3, 3)
        Matching eigenvectors as columns (scaled coordinates x, y, L * theta).
    n_degenerate : int
        Directions the match does not constrain (0: a full constraint; 3: none).
    length : float
        The scaling length L [m].
    """

    covariance: FloatArray
    strengths: FloatArray
    directions: FloatArray
    n_degenerate: int
    length: float

    @property
    def degenerate(self) -> bool:
        """True when at least one direction is unconstrained."""
        return self.n_degenerate > 0


def scan_information(
    points: ArrayLike, *, max_gap: float = 0.3, gap_per_metre: float = 0.05
) -> tuple[FloatArray, int]:
    """``(J^T J / N (3, 3), points with a normal)`` of a scan's point-to-line residuals.

    ``points`` (N, 2) [m] in beam order (sensor frame). A point gets the normal of the chord
    between its two neighbours when both lie within ``max_gap + gap_per_metre * range`` [m]
    of it; others (isolated points, edges) contribute nothing.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if pts.shape[0] < 3:
        return np.zeros((3, 3)), 0
    prev, cur, nxt = pts[:-2], pts[1:-1], pts[2:]
    rng = np.hypot(cur[:, 0], cur[:, 1])
    gap = max_gap + gap_per_metre * rng
    ok = (np.hypot(*(cur - prev).T) <= gap) & (np.hypot(*(nxt - cur).T) <= gap)
    chord = nxt[ok] - prev[ok]
    norm = np.hypot(chord[:, 0], chord[:, 1])
    good = norm > 1e-9
    chord, c = chord[good], cur[ok][good]
    n = np.column_stack([-chord[:, 1], chord[:, 0]]) / norm[good][:, None]
    jac = np.column_stack([n[:, 0], n[:, 1], c[:, 0] * n[:, 1] - c[:, 1] * n[:, 0]])
    return np.asarray(jac.T @ jac / pts.shape[0], dtype=np.float64), int(jac.shape[0])


def analyse_match(
    information: ArrayLike,
    points: ArrayLike,
    sigma_trans: float,
    *,
    sigma_rot: float = 0.0,
    threshold: float = 0.05,
    min_strength: float = 0.0,
) -> MatchConstraint:
    """Covariance and degeneracy of a match from its curvature (see the module docstring).

    Parameters
    ----------
    information : array of shape (3, 3)
        ``J^T J / N`` of the scan (:func:`scan_information`) or of the match.
    points : array of shape (N, 2)
        The matched points (sensor frame) [m], for the length scale.
    sigma_trans : float
        Standard deviation [m] of the match along its best-constrained direction.
    sigma_rot : float
        Standard deviation [rad] of the match's heading on top of what ``sigma_trans`` at
        the scan's length scale implies (a matcher's heading error is not only its
        translation error seen from afar).
    threshold : float
        Relative eigenvalue below which a direction counts as unconstrained.
    min_strength : float
        Largest eigenvalue below which the whole match counts as unconstrained (in the units
        of ``information``; for :func:`scan_information`, the fraction of points with a
        surface facing the best-constrained direction).
    """
    info = np.asarray(information, dtype=np.float64).reshape(3, 3)
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    length = float(np.median(np.hypot(pts[:, 0], pts[:, 1]))) if pts.shape[0] else 1.0
    length = min(max(length, 1.0), 10.0)
    scale = np.array([1.0, 1.0, 1.0 / length])  # x_scaled = x / scale: (x, y, L theta)
    h = info * scale[:, None] * scale[None, :]
    h = 0.5 * (h + h.T)
    lam, vec = np.linalg.eigh(h)
    lam = np.maximum(lam, 0.0)
    top = float(lam[-1])
    strengths = lam / top if top > 0 else np.zeros(3)
    weak = top <= min_strength
    bad = (strengths < threshold) | weak
    var = np.where(bad, UNCONSTRAINED_SIGMA**2, sigma_trans**2 / np.maximum(strengths, threshold))
    cov_scaled = (vec * var[None, :]) @ vec.T
    cov = cov_scaled * scale[:, None] * scale[None, :]
    cov[2, 2] += sigma_rot**2
    return MatchConstraint(
        covariance=0.5 * (cov + cov.T),
        strengths=strengths,
        directions=vec,
        n_degenerate=int(bad.sum()),
        length=length,
    )


def fuse(
    prediction: ArrayLike,
    prediction_cov: ArrayLike,
    match: ArrayLike,
    match_cov: ArrayLike,
) -> tuple[FloatArray, FloatArray]:
    """One Kalman update of ``prediction`` (3,) by ``match`` (3,), in the same frame.

    Returns the fused pose (3,) and its covariance (3, 3). Along a direction the match does
    not constrain (huge ``match_cov``), the prediction is kept.
    """
    p = np.asarray(prediction, dtype=np.float64).reshape(3)
    m = np.asarray(match, dtype=np.float64).reshape(3)
    pc = np.asarray(prediction_cov, dtype=np.float64).reshape(3, 3)
    mc = np.asarray(match_cov, dtype=np.float64).reshape(3, 3)
    innov = m - p
    innov[2] = float(wrap_angle(innov[2]))
    gain = pc @ np.linalg.inv(pc + mc)
    out = p + gain @ innov
    out[2] = math.remainder(float(out[2]), 2.0 * math.pi)
    cov = (np.eye(3) - gain) @ pc
    return out, 0.5 * (cov + cov.T)
