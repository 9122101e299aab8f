"""KLD-sampling: how many particles the belief needs (Fox, IJRR 2003, eq. 7).

With ``k`` occupied histogram bins, drawing

``n = ceil((k - 1) / (2 eps) * (1 - 2 / (9 (k - 1)) + sqrt(2 / (9 (k - 1))) z)^3)``

samples keeps the KL divergence between the sample-based and the true (binned) belief below
``eps`` (``pf_err``) with probability ``1 - delta``, where ``z`` is the upper ``1 - delta``
*quantile of the standard normal*. nav2_amcl (and ROS 1 amcl) pass ``pf_z = 0.99`` straight
into ``z``; Fox's formula wants ``z = Phi^-1(0.99) = 2.326``. symloc keeps nav2's parameter
(the probability, default 0.99) and uses its quantile, so its bound is the one Fox proved, and
larger than nav2's for the same settings. The quantile is the standard library's
(:class:`statistics.NormalDist`, Wichura's AS 241, about 1e-16 relative): the filter's module
does not load scipy.special (a twentieth of a second and thousands of objects in a process
that only tracks).
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError

__all__ = ["kld_sample_count", "kld_stop_index", "pf_z_quantile"]


def pf_z_quantile(pf_z: float) -> float:
    """The standard normal quantile ``Phi^-1(pf_z)`` for a probability ``pf_z`` in (0.5, 1)."""
    if not 0.5 < pf_z < 1.0:
        raise ConfigurationError(f"pf_z: expected a probability in (0.5, 1), got {pf_z}")
    return NormalDist().inv_cdf(pf_z)


def kld_sample_count(
    k: ArrayLike, pf_err: float, z: float, min_particles: int, max_particles: int
) -> NDArray[np.int64]:
    """Fox's bound for ``k`` occupied bins, clamped to [min_particles, max_particles].

    Parameters
    ----------
    k : int or array of ints
        Number of non-empty histogram bins (``k <= 1`` gives ``max_particles``, as amcl).
    pf_err : float
        KL error bound epsilon in (0, 1).
    z : float
        The normal *quantile* (see :func:`pf_z_quantile`), not the probability.
    min_particles, max_particles : int
        Clamp.

    Returns
    -------
    ndarray of int64, the shape of ``k``.
    """
    if not 0.0 < pf_err < 1.0:
        raise ConfigurationError(f"pf_err: expected a value in (0, 1), got {pf_err}")
    if not math.isfinite(z):
        raise ConfigurationError(f"z: expected a finite quantile, got {z}")
    kk = np.asarray(k, dtype=np.float64)
    km1 = np.maximum(kk - 1.0, 1.0)
    b = 2.0 / (9.0 * km1)
    x = 1.0 - b + np.sqrt(b) * z
    n = np.ceil(km1 / (2.0 * pf_err) * x * x * x)
    n = np.where(kk <= 1.0, max_particles, n)
    return np.clip(n, min_particles, max_particles).astype(np.int64)


def kld_stop_index(
    bin_keys: NDArray[np.int64],
    pf_err: float,
    z: float,
    min_particles: int,
    max_particles: int,
) -> int:
    """How many of the samples (drawn in this order) KLD-sampling keeps.

    amcl draws samples one at a time and stops as soon as the count exceeds the bound for the
    bins occupied so far. Here all candidate samples are drawn at once (in random order) and
    the stopping point found in one vectorised pass: ``k_i`` is the number of distinct bins
    among the first ``i`` samples, and the answer is the first ``i`` with
    ``i > bound(k_i)`` (or all of them).
    """
    m = int(bin_keys.size)
    if m == 0:
        return 0
    _, first = np.unique(bin_keys, return_index=True)
    new_bin = np.zeros(m, dtype=np.int64)
    new_bin[first] = 1
    k = np.cumsum(new_bin)
    bound = kld_sample_count(k, pf_err, z, min_particles, max_particles)
    count = np.arange(1, m + 1)
    stop = np.flatnonzero(count > bound)
    return int(stop[0] + 1) if stop.size else m
