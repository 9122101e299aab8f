"""The likelihood-field sensor model, nav2_amcl's default (``likelihood_field``).

Thrun, Burgard and Fox (2005), Table 6.3, as ROS amcl implements it: each returning beam's end
point is looked up in the distance field ``d`` (clipped at ``laser_likelihood_max_dist``,
``max_dist`` off the map) and scores ``pz = z_hit exp(-d^2 / (2 sigma_hit^2)) + z_rand /
range_max``; the particle's weight is multiplied by ``1 + sum(pz^3)`` (amcl's ad-hoc
combination, kept for compatibility). Max-range readings are ignored.

The per-cell ``pz^3`` is precomputed into a padded float32 table, so a particle-beam pair costs
a few float32 operations and one table read: a compiled loop (:mod:`symloc.mcl.kernels`) over
particles and beams, on every core for large sets, with no temporary per pair.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from symloc.grid.distance_field import DistanceField
from symloc.mcl.beams import BeamSet
from symloc.mcl.kernels import endpoint_table_sum, split_over_threads

__all__ = [
    "endpoint_flat_indices",
    "endpoint_table_sums",
    "laser_poses_grid",
    "likelihood_field_weights",
]

FloatArray = NDArray[np.float64]

#: Particle-beam pairs processed per block (about 256 kB per float32 temporary).
CHUNK_ELEMENTS = 65536

#: Padded tables with this many cells or more (a 46,000 x 46,000 map) are read in NumPy blocks:
#: the compiled kernel indexes cells with 32-bit integers.
_INT32_CELLS = 2**31


def laser_poses_grid(
    field: DistanceField, particles: FloatArray, laser_pose: FloatArray
) -> FloatArray:
    """Laser poses ``(N, 3)`` in the grid frame: ``particle (+) laser_pose``, origin removed."""
    p = field.grid_frame_poses(particles)
    lp = np.asarray(laser_pose, dtype=np.float64)
    if lp[0] == 0.0 and lp[1] == 0.0 and lp[2] == 0.0:
        return p
    c = np.cos(p[:, 2])
    s = np.sin(p[:, 2])
    out = np.empty_like(p)
    out[:, 0] = p[:, 0] + c * lp[0] - s * lp[1]
    out[:, 1] = p[:, 1] + s * lp[0] + c * lp[1]
    out[:, 2] = p[:, 2] + lp[2]
    return out


def endpoint_flat_indices(
    field: DistanceField, laser_poses: FloatArray, ranges: FloatArray, angles: FloatArray
) -> NDArray[np.intp]:
    """Flat indices ``(N, B)`` into the padded tables of every beam end point.

    ``laser_poses`` are in the grid frame (see :func:`laser_poses_grid`); ``ranges`` and
    ``angles`` ``(B,)`` in metres / radians in the laser frame.
    """
    inv_res = 1.0 / field.grid.resolution
    bx = (ranges * np.cos(angles) * inv_res).astype(np.float32)
    by = (ranges * np.sin(angles) * inv_res).astype(np.float32)
    c = np.cos(laser_poses[:, 2]).astype(np.float32)[:, None]
    s = np.sin(laser_poses[:, 2]).astype(np.float32)[:, None]
    lx = (laser_poses[:, 0] * inv_res).astype(np.float32)[:, None]
    ly = (laser_poses[:, 1] * inv_res).astype(np.float32)[:, None]
    # x = lx + c*bx - s*by ; y = ly + s*bx + c*by, with two temporaries only.
    x = c * bx
    t = s * by
    x -= t
    x += lx
    y = s * bx
    np.multiply(c, by, out=t)
    y += t
    y += ly
    return field.padded_flat_index(x, y)


def endpoint_table_sums(
    field: DistanceField,
    laser_poses: FloatArray,
    ranges: FloatArray,
    angles: FloatArray,
    table: NDArray[np.float32],
    out: FloatArray | None = None,
) -> FloatArray:
    """``(N,)`` sums over beams of ``table`` at every beam's end point, in float64.

    The same cells as :func:`endpoint_flat_indices` and the same float64 sum as
    ``table[idx].sum(axis=1, dtype=np.float64)``, bit for bit, without the ``(N, B)``
    temporaries: a compiled loop, split over the cores when the set is large.
    """
    inv_res = 1.0 / field.grid.resolution
    bx = np.ascontiguousarray(ranges * np.cos(angles) * inv_res, dtype=np.float32)
    by = np.ascontiguousarray(ranges * np.sin(angles) * inv_res, dtype=np.float32)
    poses = np.ascontiguousarray(laser_poses, dtype=np.float64)
    n = poses.shape[0]
    res: FloatArray = np.empty(n) if out is None else out
    h2, w2 = field.padded.shape
    if h2 * w2 >= _INT32_CELLS:  # beyond the kernel's 32-bit cell index: blocks in NumPy
        step = max(1, CHUNK_ELEMENTS // max(1, bx.size))
        for s in range(0, n, step):
            idx = endpoint_flat_indices(field, poses[s : s + step].copy(), ranges, angles)
            res[s : s + step] = table[idx].sum(axis=1, dtype=np.float64)
        return res

    def run(start: int, stop: int) -> None:
        endpoint_table_sum(table, w2, h2, poses, inv_res, bx, by, start, stop, res)

    split_over_threads(n, n * bx.size, run)
    return res


def likelihood_field_weights(
    field: DistanceField,
    particles: FloatArray,
    beams: BeamSet,
    *,
    z_hit: float,
    z_rand: float,
    sigma_hit: float,
    laser_pose: FloatArray | None = None,
) -> FloatArray:
    """The likelihood-field factor ``(N,)`` of each particle for one scan.

    Parameters
    ----------
    field : DistanceField
        Distance field of the map clipped at ``laser_likelihood_max_dist``.
    particles : ndarray of shape (N, 3)
        Poses in the map frame.
    beams : BeamSet
        From :func:`symloc.mcl.beams.select_beams`; only returning beams are scored.
    z_hit, z_rand, sigma_hit : float
        Mixture weights and the hit standard deviation [m].
    laser_pose : ndarray of shape (3,), optional
        The laser's pose in the robot frame (``base_from_laser``).

    Returns
    -------
    ndarray of shape (N,)
        ``1 + sum_beams pz^3`` (>= 1); exactly 1 for every particle when no beam returned.
    """
    lp = np.zeros(3) if laser_pose is None else np.asarray(laser_pose, dtype=np.float64)
    hit = beams.hit
    n = particles.shape[0]
    if not hit.any():
        return np.ones(n)
    poses = laser_poses_grid(field, particles, lp)
    table = field.table("pz3", z_hit, z_rand, sigma_hit, beams.range_max)
    r, a = beams.ranges[hit], beams.angles[hit]
    total = endpoint_table_sums(field, poses, r, a, table)
    total += 1.0
    return total
