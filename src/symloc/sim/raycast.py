"""Vectorised 2D ray casting against a :class:`~symloc.sim.world.World`.

A ray ``o + t d`` (``|d| = 1``, ``t > 0``) meets segment ``p + s e`` (``0 <= s <= 1``) where
``t = (p - o) x e / (d x e)`` and ``s = (p - o) x d / (d x e)`` (2D cross products); it meets the
circle ``|x - c| = r`` at the smallest positive root of ``t^2 + 2 t d.(o - c) + |o - c|^2 - r^2``
(the far root from inside a circular room). Everything is computed at once over rays x
primitives with NumPy broadcasting; no Python loop over beams.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.sim.world import World

__all__ = ["NearestHits", "RayHits", "ray_intersections", "raycast", "raycast_nearest"]

FloatArray = NDArray[np.float64]

_T_MIN = 1e-9
_BLOCK = 200


@dataclass(frozen=True, slots=True)
class NearestHits:
    """The nearest hit of each ray of a batch (see :func:`raycast_nearest`).

    Attributes
    ----------
    ranges : ndarray of shape (..., N)
        Distance [m] to the nearest primitive, ``inf`` where the ray hits nothing.
    materials : ndarray of shape (..., N), int64
        Material id of that primitive, -1 where the ray hits nothing.
    cos_incidence : ndarray of shape (..., N)
        ``|cos|`` of the angle between the ray and the surface normal there (1 head-on, 0 at
        grazing incidence; 0 where the ray hits nothing).
    primitives : ndarray of shape (..., N), int64
        Index of the primitive hit: ``0 .. S-1`` for the world's walls, ``S + c`` for its
        circle ``c``; -1 where the ray hits nothing.
    """

    ranges: FloatArray
    materials: NDArray[np.int64]
    cos_incidence: FloatArray
    primitives: NDArray[np.int64]


@dataclass(frozen=True, slots=True)
class RayHits:
    """Every intersection of a batch of rays with the primitives of a world.

    Attributes
    ----------
    t : ndarray of shape (..., N, P)
        Distance [m] along each ray to primitive p (``inf`` where it misses), P = S' + C'
        (walls first, then circles, of the primitives taller than ``min_height``).
    s : ndarray of shape (..., N, P)
        Where the ray meets the primitive [m]: distance from the wall's first end point, or arc
        length counter-clockwise from the circle's +x point.
    heights : ndarray of shape (P,)
        Height [m] of each primitive.
    materials : ndarray of shape (P,)
        Material id of each primitive.
    lengths : ndarray of shape (P,)
        Length [m] of each wall, circumference of each circle.
    cos_incidence : ndarray of shape (..., N, P)
        ``|cos|`` of the angle between the ray and the surface normal at the hit (1 head-on).
    is_circle : ndarray of shape (P,)
        True for circles, False for walls.
    tex_u : ndarray of shape (P, 2)
        Horizontal texture coordinates at ``s = 0`` and at ``s = length`` (walls: the world's
        ``wall_tex_u``; circles: 0 and 1).
    """

    t: FloatArray
    s: FloatArray
    heights: FloatArray
    materials: NDArray[np.int64]
    lengths: FloatArray
    cos_incidence: FloatArray
    is_circle: NDArray[np.bool_]
    tex_u: FloatArray


def ray_intersections(
    world: World,
    origins: ArrayLike,
    angles: ArrayLike,
    *,
    min_height: float = 0.0,
    skip_materials: tuple[int, ...] = (),
) -> RayHits:
    """Intersections of rays with every wall and circle taller than ``min_height``.

    Parameters
    ----------
    world : World
    origins : array of shape (..., 2)
        Ray origins x, y [m].
    angles : array of shape (..., N)
        World-frame ray directions [rad]; leading dimensions broadcast with ``origins``.
    min_height : float
        Primitives of height <= this [m] are ignored (a lidar mounted above them sees over).
    skip_materials : tuple of int
        Primitives of these materials are ignored too (the camera sees through glass).
    """
    o = np.asarray(origins, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    ox = o[..., 0][..., None, None]
    oy = o[..., 1][..., None, None]
    dx = np.cos(a)[..., None]
    dy = np.sin(a)[..., None]
    wk = np.asarray(world.wall_heights) > min_height
    ck = np.asarray(world.circle_heights) > min_height
    if skip_materials:
        skip = np.asarray(skip_materials, dtype=np.int64)
        wk &= ~np.isin(np.asarray(world.wall_materials), skip)
        ck &= ~np.isin(np.asarray(world.circle_materials), skip)
    walls = world.walls[wk]
    circles = world.circles[ck]
    parts_t = []
    parts_s = []
    parts_c = []
    if walls.shape[0]:
        px, py = walls[:, 0], walls[:, 1]
        ex, ey = walls[:, 2] - px, walls[:, 3] - py
        qx, qy = px - ox, py - oy
        denom = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            inv = 1.0 / denom
            t = (qx * ey - qy * ex) * inv
            u = (qx * dy - qy * dx) * inv
        ok = (t > _T_MIN) & (u >= 0.0) & (u <= 1.0)
        length = np.hypot(ex, ey)
        parts_t.append(np.where(ok, t, np.inf))
        parts_s.append(np.where(ok, u * length, 0.0))
        parts_c.append(np.abs(denom) / length)
    if circles.shape[0]:
        cx, cy, r = circles[:, 0], circles[:, 1], circles[:, 2]
        wx, wy = ox - cx, oy - cy
        b = dx * wx + dy * wy
        c = wx * wx + wy * wy - r * r
        disc = b * b - c
        with np.errstate(invalid="ignore"):
            sq = np.sqrt(disc)
        t1 = -b - sq
        t2 = -b + sq
        t = np.where(t1 > _T_MIN, t1, np.where(t2 > _T_MIN, t2, np.inf))
        t = np.where(disc >= 0.0, t, np.inf)
        hx = wx + t * dx
        hy = wy + t * dy
        with np.errstate(invalid="ignore"):
            phi = np.mod(np.arctan2(hy, hx), 2 * np.pi)
        parts_t.append(t)
        parts_s.append(np.where(np.isfinite(t), phi * r, 0.0))
        with np.errstate(invalid="ignore"):
            parts_c.append(np.where(np.isfinite(t), np.abs(b + t) / r, 0.0))
    shape = np.broadcast_shapes((*ox.shape[:-1], 1), dx.shape)[:-1]
    if not parts_t:
        empty = np.zeros((*shape, 0))
        return RayHits(
            empty,
            empty,
            np.zeros(0),
            np.zeros(0, dtype=np.int64),
            np.zeros(0),
            empty,
            np.zeros(0, dtype=bool),
            np.zeros((0, 2)),
        )
    t_all = np.concatenate([np.broadcast_to(p, shape + p.shape[-1:]) for p in parts_t], axis=-1)
    s_all = np.concatenate([np.broadcast_to(p, shape + p.shape[-1:]) for p in parts_s], axis=-1)
    c_all = np.concatenate([np.broadcast_to(p, shape + p.shape[-1:]) for p in parts_c], axis=-1)
    heights = np.concatenate(
        [np.asarray(world.wall_heights)[wk], np.asarray(world.circle_heights)[ck]]
    )
    materials = np.concatenate(
        [np.asarray(world.wall_materials)[wk], np.asarray(world.circle_materials)[ck]]
    )
    lengths = np.concatenate(
        [np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1]), 2 * np.pi * circles[:, 2]]
    )
    is_circle = np.concatenate(
        [np.zeros(walls.shape[0], dtype=bool), np.ones(circles.shape[0], dtype=bool)]
    )
    tex_u = np.concatenate(
        [np.asarray(world.wall_tex_u)[wk], np.tile(np.array([0.0, 1.0]), (circles.shape[0], 1))]
    )
    return RayHits(t_all, s_all, heights, materials, lengths, c_all, is_circle, tex_u)


def raycast(
    world: World, origins: ArrayLike, angles: ArrayLike, *, min_height: float = 0.0
) -> FloatArray:
    """Exact range [m] along each ray to the nearest wall or circle taller than ``min_height``.

    Parameters
    ----------
    world : World
    origins : array of shape (..., 2)
        Ray origins x, y [m] (e.g. ``(2,)`` for one scan, ``(M, 2)`` for M particles).
    angles : array of shape (..., N)
        World-frame ray directions [rad]; leading dimensions broadcast with ``origins``
        (e.g. ``(M, N)`` = particle headings + beam angles).
    min_height : float
        Walls and circles no taller than this [m] are invisible (the lidar's mount height).

    Returns
    -------
    ndarray of shape (..., N)
        Range to the first hit, ``inf`` where the ray hits nothing.
    """
    o = np.asarray(origins, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    shape = np.broadcast_shapes((*o.shape[:-1], 1), a.shape)
    ox = np.broadcast_to(o[..., 0][..., None], shape).ravel()
    oy = np.broadcast_to(o[..., 1][..., None], shape).ravel()
    ang = np.broadcast_to(a, shape).ravel()
    wk = world.wall_heights > min_height
    ck = world.circle_heights > min_height
    walls = world.walls[wk]
    circles = world.circles[ck]
    out = np.empty(ox.size)
    # Blocks of rays keep the (rays x primitives) temporaries in cache: 4x faster at 800 beams.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for i in range(0, ox.size, _BLOCK):
            sl = slice(i, i + _BLOCK)
            out[sl] = _nearest(walls, circles, ox[sl], oy[sl], ang[sl])
    return out.reshape(shape)


def _nearest(
    walls: FloatArray, circles: FloatArray, ox: FloatArray, oy: FloatArray, ang: FloatArray
) -> FloatArray:
    """Nearest hit ``(R,)`` of rays ``(R,)`` from ``(ox, oy)`` along ``ang``."""
    best = np.full(ox.shape, np.inf)
    ox = ox[:, None]
    oy = oy[:, None]
    dx = np.cos(ang)[:, None]
    dy = np.sin(ang)[:, None]
    if walls.shape[0]:
        px, py = walls[:, 0], walls[:, 1]
        ex, ey = walls[:, 2] - px, walls[:, 3] - py
        qx, qy = px - ox, py - oy
        inv = 1.0 / (dx * ey - dy * ex)
        t = (qx * ey - qy * ex) * inv
        u = (qx * dy - qy * dx) * inv
        t[~((t > _T_MIN) & (u >= 0.0) & (u <= 1.0))] = np.inf
        best = np.minimum(best, t.min(axis=-1))
    if circles.shape[0]:
        cx, cy, r = circles[:, 0], circles[:, 1], circles[:, 2]
        wx, wy = ox - cx, oy - cy
        b = dx * wx + dy * wy
        c = wx * wx + wy * wy - r * r
        disc = b * b - c
        sq = np.sqrt(disc)
        t1 = -b - sq
        t2 = -b + sq
        t = np.where(t1 > _T_MIN, t1, np.where(t2 > _T_MIN, t2, np.inf))
        t[~(disc >= 0.0)] = np.inf
        best = np.minimum(best, t.min(axis=-1))
    return best


def raycast_nearest(
    world: World,
    origins: ArrayLike,
    angles: ArrayLike,
    *,
    min_height: float = 0.0,
    skip_materials: tuple[int, ...] = (),
) -> NearestHits:
    """Range, material and incidence of the nearest hit along each ray.

    Like :func:`raycast` (same broadcasting, same blocks of rays), but it also says what was
    hit, which a lidar's fault model needs (glass, dark surfaces, the angle of incidence).

    Parameters
    ----------
    world : World
    origins : array of shape (..., 2)
        Ray origins x, y [m].
    angles : array of shape (..., N)
        World-frame ray directions [rad]; leading dimensions broadcast with ``origins``.
    min_height : float
        Walls and circles no taller than this [m] are invisible.
    skip_materials : tuple of int
        Primitives of these materials are ignored too (a beam that passes through glass).

    Returns
    -------
    NearestHits
        Arrays of the broadcast shape ``(..., N)``.
    """
    o = np.asarray(origins, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    shape = np.broadcast_shapes((*o.shape[:-1], 1), a.shape)
    ox = np.broadcast_to(o[..., 0][..., None], shape).ravel()
    oy = np.broadcast_to(o[..., 1][..., None], shape).ravel()
    ang = np.broadcast_to(a, shape).ravel()
    wk = np.asarray(world.wall_heights) > min_height
    ck = np.asarray(world.circle_heights) > min_height
    if skip_materials:
        skip = np.asarray(skip_materials, dtype=np.int64)
        wk &= ~np.isin(np.asarray(world.wall_materials), skip)
        ck &= ~np.isin(np.asarray(world.circle_materials), skip)
    walls = world.walls[wk]
    circles = world.circles[ck]
    mats = np.concatenate(
        [np.asarray(world.wall_materials)[wk], np.asarray(world.circle_materials)[ck]]
    )
    ids = np.concatenate([np.flatnonzero(wk), world.n_walls + np.flatnonzero(ck)])
    rng_out = np.empty(ox.size)
    mat_out = np.full(ox.size, -1, dtype=np.int64)
    prim_out = np.full(ox.size, -1, dtype=np.int64)
    cos_out = np.empty(ox.size)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for i in range(0, ox.size, _BLOCK):
            sl = slice(i, i + _BLOCK)
            t, idx, cos_i = _nearest_hit(walls, circles, ox[sl], oy[sl], ang[sl])
            rng_out[sl] = t
            hit = np.isfinite(t)
            if mats.size:
                mat_out[sl] = np.where(hit, mats[idx], -1)
                prim_out[sl] = np.where(hit, ids[idx], -1)
            cos_out[sl] = np.where(hit, cos_i, 0.0)
    return NearestHits(
        rng_out.reshape(shape),
        mat_out.reshape(shape),
        cos_out.reshape(shape),
        prim_out.reshape(shape),
    )


def _nearest_hit(
    walls: FloatArray, circles: FloatArray, ox: FloatArray, oy: FloatArray, ang: FloatArray
) -> tuple[FloatArray, NDArray[np.intp], FloatArray]:
    """Nearest range ``(R,)``, primitive index ``(R,)`` (walls first) and ``|cos|`` of
    incidence ``(R,)`` of rays ``(R,)``."""
    n = ox.size
    dx1 = np.cos(ang)
    dy1 = np.sin(ang)
    ox2 = ox[:, None]
    oy2 = oy[:, None]
    dx = dx1[:, None]
    dy = dy1[:, None]
    parts = []
    if walls.shape[0]:
        px, py = walls[:, 0], walls[:, 1]
        ex, ey = walls[:, 2] - px, walls[:, 3] - py
        qx, qy = px - ox2, py - oy2
        inv = 1.0 / (dx * ey - dy * ex)
        t = (qx * ey - qy * ex) * inv
        u = (qx * dy - qy * dx) * inv
        t[~((t > _T_MIN) & (u >= 0.0) & (u <= 1.0))] = np.inf
        parts.append(t)
    if circles.shape[0]:
        cx, cy, r = circles[:, 0], circles[:, 1], circles[:, 2]
        wx, wy = ox2 - cx, oy2 - cy
        b = dx * wx + dy * wy
        c = wx * wx + wy * wy - r * r
        disc = b * b - c
        sq = np.sqrt(disc)
        t1 = -b - sq
        t2 = -b + sq
        t = np.where(t1 > _T_MIN, t1, np.where(t2 > _T_MIN, t2, np.inf))
        t[~(disc >= 0.0)] = np.inf
        parts.append(t)
    if not parts:
        return np.full(n, np.inf), np.zeros(n, dtype=np.intp), np.zeros(n)
    t_all = parts[0] if len(parts) == 1 else np.concatenate(parts, axis=1)
    idx = np.argmin(t_all, axis=1)
    best = t_all[np.arange(n), idx]
    cos_i = np.zeros(n)
    s = walls.shape[0]
    is_wall = idx < s
    if s and np.any(is_wall):
        w = walls[idx[is_wall]]
        ex, ey = w[:, 2] - w[:, 0], w[:, 3] - w[:, 1]
        cos_i[is_wall] = np.abs(dx1[is_wall] * ey - dy1[is_wall] * ex) / np.hypot(ex, ey)
    is_circ = ~is_wall & np.isfinite(best)
    if np.any(is_circ):
        c = circles[idx[is_circ] - s]
        hx = ox[is_circ] + best[is_circ] * dx1[is_circ] - c[:, 0]
        hy = oy[is_circ] + best[is_circ] * dy1[is_circ] - c[:, 1]
        cos_i[is_circ] = np.abs(dx1[is_circ] * hx + dy1[is_circ] * hy) / c[:, 2]
    return best, idx, np.clip(cos_i, 0.0, 1.0)
