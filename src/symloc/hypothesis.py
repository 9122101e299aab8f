"""A pose hypothesis: one candidate pose with its weight.

The one record for the concept, shared by the particle filter (:mod:`symloc.mcl.clustering`
reports each particle cluster as one, with its own covariance and particle count) and by the
localizer (:mod:`symloc.localizer`, whose ambiguous estimates list the ``k`` rotated copies of a
pose as hypotheses with neither). It lives with the core types so that both can use it without
either depending on the other for it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError

__all__ = ["Hypothesis"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True, eq=False)
class Hypothesis:
    """One candidate pose with its weight; a particle cluster also carries its spread.

    Equality is identity (``eq=False``): the fields are arrays, whose ``==`` is elementwise,
    so a field-by-field ``__eq__`` would raise or mislead; compare ``pose`` with NumPy instead.

    Attributes
    ----------
    pose : ndarray of shape (3,)
        x [m], y [m], theta [rad] in the map frame (for a cluster: the weighted mean position
        and circular-mean heading of its particles).
    weight : float
        Share of the probability (0..1; the weights of a set of hypotheses sum to <= 1). For
        a cluster: the sum of its particles' normalised weights.
    covariance : ndarray of shape (3, 3) or None
        Weighted covariance of (x, y, theta) [m^2, m rad, rad^2] of a cluster's particles;
        None for a candidate pose that is not a cluster.
    n_particles : int
        Number of particles in the cluster; 0 for a candidate pose that is not a cluster.
    """

    pose: FloatArray
    weight: float
    covariance: FloatArray | None = None
    n_particles: int = 0

    def __post_init__(self) -> None:
        # np.asarray returns a float64 array unchanged (same object, same bits).
        pose = np.asarray(self.pose, dtype=np.float64)
        if pose.shape != (3,):
            raise ConfigurationError(
                f"Hypothesis.pose: expected shape (3,) x, y, theta, got {pose.shape}"
            )
        object.__setattr__(self, "pose", pose)
        object.__setattr__(self, "weight", float(self.weight))
        if self.covariance is not None:
            cov = np.asarray(self.covariance, dtype=np.float64)
            if cov.shape != (3, 3):
                raise ConfigurationError(
                    f"Hypothesis.covariance: expected shape (3, 3), got {cov.shape}"
                )
            object.__setattr__(self, "covariance", cov)
        if self.n_particles < 0:
            raise ConfigurationError(
                f"Hypothesis.n_particles: expected >= 0, got {self.n_particles}"
            )
        object.__setattr__(self, "n_particles", int(self.n_particles))
