"""nav2_amcl's ``likelihood_field_prob`` sensor model, with optional beam skipping.

Same per-beam score as the likelihood field, ``pz = z_hit exp(-d^2 / 2 sigma_hit^2) + z_rand
/ range_max`` (an end point off the map scores ``z_hit exp(-max_dist^2 / 2 sigma_hit^2)``),
but combined as a true product, ``weight *= exp(sum log pz)``.

Beam skipping (Thrun et al. 2005, Section 6.3.3; ``do_beamskip``): a beam is kept only if the
fraction of particles whose end point lies within ``beam_skip_distance`` of an obstacle
exceeds ``beam_skip_threshold``; beams that most particles cannot explain (a person in front
of the robot) are skipped. If the skipped fraction reaches ``beam_skip_error_threshold`` the
filter is probably lost and every beam is used.

Returned as log-factors, so the filter can normalise without underflow (nav2 multiplies
``exp(log_p)`` directly and can underflow to zero with many beams).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.grid.distance_field import DistanceField
from symloc.mcl.beams import BeamSet
from symloc.mcl.likelihood_field import (
    endpoint_flat_indices,
    endpoint_table_sums,
    laser_poses_grid,
)

__all__ = ["BeamSkipReport", "likelihood_field_prob_log_weights"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class BeamSkipReport:
    """What beam skipping did: beams used, skipped, and whether it fell back to all beams."""

    n_beams: int
    n_skipped: int
    fell_back: bool


def likelihood_field_prob_log_weights(
    field: DistanceField,
    particles: FloatArray,
    beams: BeamSet,
    *,
    z_hit: float,
    z_rand: float,
    sigma_hit: float,
    laser_pose: FloatArray | None = None,
    do_beamskip: bool = False,
    beam_skip_distance: float = 0.5,
    beam_skip_threshold: float = 0.3,
    beam_skip_error_threshold: float = 0.9,
) -> tuple[FloatArray, BeamSkipReport]:
    """Log-likelihood ``(N,)`` of each particle (``sum log pz`` over the used beams).

    Parameters as :func:`symloc.mcl.likelihood_field.likelihood_field_weights`, plus nav2's
    beam-skip settings. Returns the log-factors and a :class:`BeamSkipReport`.
    """
    lp = np.zeros(3) if laser_pose is None else np.asarray(laser_pose, dtype=np.float64)
    hit = beams.hit
    n = particles.shape[0]
    nb = int(np.count_nonzero(hit))
    if nb == 0:
        return np.zeros(n), BeamSkipReport(0, 0, False)
    poses = laser_poses_grid(field, particles, lp)
    table = field.table("logpz", z_hit, z_rand, sigma_hit, beams.range_max)
    r, a = beams.ranges[hit], beams.angles[hit]
    if not do_beamskip:
        return endpoint_table_sums(field, poses, r, a, table), BeamSkipReport(nb, 0, False)
    idx = endpoint_flat_indices(field, poses, r, a)
    logs = table[idx]
    near = field.padded.ravel()[idx] < beam_skip_distance
    frac = near.mean(axis=0)
    mask = frac > beam_skip_threshold
    skipped = int(nb - np.count_nonzero(mask))
    # nav2 compares with the number of sub-sampled beams (returning or not).
    fell_back = skipped >= beams.n_steps * beam_skip_error_threshold
    if fell_back:
        return logs.sum(axis=1, dtype=np.float64), BeamSkipReport(nb, skipped, True)
    return logs[:, mask].sum(axis=1, dtype=np.float64), BeamSkipReport(nb, skipped, False)
