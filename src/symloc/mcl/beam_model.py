"""The beam (ray-casting) sensor model, nav2_amcl's ``beam`` laser model.

Thrun, Burgard and Fox (2005), Table 6.1, as ROS amcl implements it: for each particle and
beam the expected range ``r*`` is ray cast on the map (the ray stops at the first cell that is
not free, i.e. occupied or unknown, or at the map edge, and is capped at ``range_max``), and

``pz = z_hit N(r - r*; sigma_hit) [unnormalised] + z_short lambda exp(-lambda r) [r < r*]
+ z_max [r == range_max] + z_rand / range_max [r < range_max]``;

the weight is multiplied by ``1 + sum(pz^3)``. No-return readings count as ``range_max``.

Ray casting is vectorised over all particle-beam pairs by *sphere tracing* on the distance
field of the non-free cells: each ray advances by the distance to the nearest blocking cell
(less a cell of margin, at least half a cell), so a ray needs a few dozen steps rather than
one per cell. The loop is over steps, not particles or beams.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from symloc.grid.fields import MapFields
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.mcl.beams import BeamSet

__all__ = ["beam_model_weights", "raycast_grid"]

FloatArray = NDArray[np.float64]


def raycast_grid(
    grid: OccupancyGrid | MapFields, origins: FloatArray, angles: FloatArray, range_max: float
) -> FloatArray:
    """Range [m] from each origin along each angle to the first non-free cell.

    Parameters
    ----------
    grid : OccupancyGrid or MapFields
        The map (or its shared fields: the distance to the nearest non-free cell is read
        from :meth:`~symloc.grid.fields.MapFields.blocked_distance`).
    origins : ndarray of shape (M, 2)
        Ray origins in the map frame [m].
    angles : ndarray of shape (M,)
        Ray directions in the map frame [rad].
    range_max : float
        Cap [m]; rays that hit nothing within it return ``range_max``.

    Returns
    -------
    ndarray of shape (M,)
        Ranges; 0 for a ray that starts in a non-free cell or off the map.
    """
    fields = MapFields.of(grid)
    tab = fields.blocked_distance()
    grid = fields.grid
    o = np.asarray(origins, dtype=np.float64).reshape(-1, 2)
    a = np.asarray(angles, dtype=np.float64).reshape(-1) - grid.origin[2]
    if grid.origin[2] != 0.0:
        c0, s0 = np.cos(-grid.origin[2]), np.sin(-grid.origin[2])
        d = o - grid.origin[:2]
        o = np.column_stack([c0 * d[:, 0] - s0 * d[:, 1], s0 * d[:, 0] + c0 * d[:, 1]])
    else:
        o = o - grid.origin[:2]
    h2, w2 = tab.shape
    flat = tab.ravel()
    res = grid.resolution
    m = o.shape[0]
    out = np.full(m, float(range_max))
    t = np.zeros(m)
    dx = np.cos(a)
    dy = np.sin(a)
    active = np.arange(m)
    ox, oy = o[:, 0], o[:, 1]
    for _ in range(int(4 * range_max / res) + 8):
        if active.size == 0:
            break
        ta = t[active]
        cx = np.clip((ox[active] + ta * dx[active]) / res + 1.0, 0.0, w2 - 1).astype(np.intp)
        cy = np.clip((oy[active] + ta * dy[active]) / res + 1.0, 0.0, h2 - 1).astype(np.intp)
        dist = flat[cy * w2 + cx]
        blocked = dist <= 0.0
        out[active[blocked]] = np.minimum(ta[blocked], range_max)
        step = np.maximum(dist - 1.25 * res, 0.5 * res)
        ta = ta + step
        t[active] = ta
        keep = (~blocked) & (ta < range_max)
        active = active[keep]
    return out


def beam_model_weights(
    grid: OccupancyGrid | MapFields,
    particles: FloatArray,
    beams: BeamSet,
    *,
    z_hit: float,
    z_short: float,
    z_max: float,
    z_rand: float,
    sigma_hit: float,
    lambda_short: float,
    laser_pose: FloatArray | None = None,
) -> FloatArray:
    """The beam-model factor ``(N,)`` of each particle for one scan (``1 + sum pz^3``).

    ``particles`` ``(N, 3)`` in the map frame; ``beams`` from
    :func:`symloc.mcl.beams.select_beams` (no-return beams hold ``range_max``).
    """
    lp = np.zeros(3) if laser_pose is None else np.asarray(laser_pose, dtype=np.float64)
    n = particles.shape[0]
    nb = beams.ranges.size
    if nb == 0:
        return np.ones(n)
    c = np.cos(particles[:, 2])
    s = np.sin(particles[:, 2])
    lx = particles[:, 0] + c * lp[0] - s * lp[1]
    ly = particles[:, 1] + s * lp[0] + c * lp[1]
    lth = particles[:, 2] + lp[2]
    origins = np.repeat(np.column_stack([lx, ly]), nb, axis=0)
    ang = (lth[:, None] + beams.angles[None, :]).ravel()
    expected = raycast_grid(grid, origins, ang, beams.range_max).reshape(n, nb)
    r = beams.ranges[None, :]
    z = r - expected
    pz = z_hit * np.exp(-(z * z) / (2.0 * sigma_hit * sigma_hit))
    pz += np.where(z < 0.0, z_short * lambda_short * np.exp(-lambda_short * r), 0.0)
    no_ret = ~beams.hit[None, :]
    pz += np.where(no_ret, z_max, z_rand / beams.range_max)
    out: FloatArray = 1.0 + np.sum(pz**3, axis=1)
    return out
