"""A pinhole camera that renders a :class:`~symloc.sim.world.World` by ray casting columns.

The camera sits at the robot's base origin at ``mount_height`` [m], its optical axis level and
aligned with the laser's +x axis (as in the paper, Sec. 5.2). Image column ``u`` looks along
``alpha_u = atan((cx - u - 0.5) / f)`` (left of the axis is positive, counter-clockwise), with
``f = (W / 2) / tan(hfov / 2)`` [pixels]. One 2D ray per column finds every wall and circle it
crosses; a wall at depth ``z`` (along the optical axis) with height ``h`` covers the image rows
between ``cy - f (h - c) / z`` (its top) and ``cy + f c / z`` (its foot on the floor), ``c``
being the camera height. Because every wall stands on the floor, a nearer wall hides exactly the
part of a farther wall below the nearer wall's top, so each column is resolved by sorting its
hits by depth and taking a running minimum of their tops (painter's algorithm without a loop
over walls). Wall texels come from real photographs (see :mod:`symloc.sim.textures`), mip-mapped
by distance; surfaces are shaded by the angle of incidence; the floor and the space above the
walls are plain. Lighting gain and Gaussian pixel noise are configurable and seeded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import as_rng
from symloc.camera_model import DEFAULT_HFOV, focal_from_hfov
from symloc.errors import ConfigurationError
from symloc.geometry import as_pose
from symloc.sim.raycast import RayHits, ray_intersections
from symloc.sim.textures import texture_atlas
from symloc.sim.world import MATERIAL_PHOTO, World

__all__ = ["CAMERA_MOUNT_HEIGHT", "Camera", "render"]

CAMERA_MOUNT_HEIGHT = 0.2
"""Default camera height [m]: below the lidar (0.3 m) and the 0.4 m boards, as in the paper."""


@dataclass(frozen=True)
class Camera:
    """Pinhole camera settings.

    Parameters
    ----------
    width, height : int
        Image size [pixels] (the paper's camera is 1280 x 960; default 640 x 480).
    hfov : float
        Horizontal field of view [rad], in (0, pi).
    mount_height : float
        Height [m] of the optical centre above the floor, > 0.
    gain : float
        Lighting gain applied to every colour, > 0 (1 = nominal exposure).
    noise_sigma : float
        Standard deviation of Gaussian pixel noise [grey levels], >= 0.
    floor_color, sky_color : tuple of int
        RGB of the plain floor and of whatever lies above the walls (the ceiling).
    near : float
        Surfaces closer than this [m] are clipped.
    """

    width: int = 640
    height: int = 480
    hfov: float = DEFAULT_HFOV
    mount_height: float = CAMERA_MOUNT_HEIGHT
    gain: float = 1.0
    noise_sigma: float = 2.0
    floor_color: tuple[int, int, int] = (118, 112, 104)
    sky_color: tuple[int, int, int] = (232, 232, 236)
    near: float = 0.05

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            val = getattr(self, name)
            if int(val) != val or val < 8:
                raise ConfigurationError(f"Camera.{name}: expected an integer >= 8, got {val}")
        if not (math.isfinite(self.hfov) and 0.0 < self.hfov < math.pi):
            raise ConfigurationError(
                f"Camera.hfov: expected a field of view in (0, pi) rad, got {self.hfov}"
            )
        if not (math.isfinite(self.mount_height) and self.mount_height > 0):
            raise ConfigurationError(
                f"Camera.mount_height: expected a height > 0 m, got {self.mount_height}"
            )
        if not (math.isfinite(self.gain) and self.gain > 0):
            raise ConfigurationError(f"Camera.gain: expected a value > 0, got {self.gain}")
        if not (math.isfinite(self.noise_sigma) and self.noise_sigma >= 0):
            raise ConfigurationError(
                f"Camera.noise_sigma: expected a value >= 0 grey levels, got {self.noise_sigma}"
            )
        if not (math.isfinite(self.near) and self.near > 0):
            raise ConfigurationError(f"Camera.near: expected a distance > 0 m, got {self.near}")
        for name in ("floor_color", "sky_color"):
            col = getattr(self, name)
            if len(col) != 3 or any(not 0 <= c <= 255 for c in col):
                raise ConfigurationError(f"Camera.{name}: expected 3 values in 0..255, got {col}")

    @property
    def focal(self) -> float:
        """Focal length [pixels]."""
        return focal_from_hfov(self.width, self.hfov)

    @property
    def intrinsics(self) -> NDArray[np.float64]:
        """Intrinsic matrix ``(3, 3)`` [pixels]: fx = fy = focal, principal point at the image
        centre, in OpenCV's convention (x right, y down, z along the optical axis)."""
        return np.array(
            [
                [self.focal, 0.0, self.width / 2.0],
                [0.0, self.focal, self.height / 2.0],
                [0.0, 0.0, 1.0],
            ]
        )

    @property
    def vfov(self) -> float:
        """Vertical field of view [rad] (square pixels)."""
        return 2.0 * math.atan((self.height / 2.0) / self.focal)

    @property
    def column_angles(self) -> NDArray[np.float64]:
        """Horizontal angle ``(W,)`` [rad] of each column's ray relative to the optical axis."""
        u = np.arange(self.width) + 0.5
        return np.asarray(np.arctan((self.width / 2.0 - u) / self.focal), dtype=np.float64)

    def render(
        self,
        world: World,
        pose: ArrayLike,
        rng: np.random.Generator | int | None = None,
    ) -> NDArray[np.uint8]:
        """Render the view from the robot at ``pose`` (x [m], y [m], theta [rad]).

        Returns an ``(H, W, 3)`` uint8 RGB image; ``rng`` drives the pixel noise.
        """
        p = as_pose(pose)
        W, H = int(self.width), int(self.height)
        f = self.focal
        cy = H / 2.0
        hc = self.mount_height
        alpha = self.column_angles
        hits = ray_intersections(world, p[:2], p[2] + alpha)
        P = hits.t.shape[-1]
        gain = np.float32(self.gain)
        img = np.empty((H, W, 3), dtype=np.float32)
        n_above = int(np.count_nonzero(np.arange(H) + 0.5 < cy))
        img[:n_above] = np.asarray(self.sky_color, dtype=np.float32) * gain
        img[n_above:] = np.asarray(self.floor_color, dtype=np.float32) * gain
        if P:
            cos_a = np.cos(alpha)[:, None]
            z = hits.t * cos_a  # (W, P) depth along the optical axis
            z[hits.t < self.near] = np.inf
            order = np.argsort(z, axis=1)
            z = np.take_along_axis(z, order, axis=1)
            h = hits.heights[order]
            finite = np.isfinite(z)
            zs = np.where(finite, z, 1.0)
            top = cy - f * (h - hc) / zs
            bot = cy + f * hc / zs
            a = np.ceil(top - 0.5).astype(np.int64)  # first covered row
            b = np.floor(bot - 0.5).astype(np.int64)  # last covered row
            a = np.where(finite, a, H + 1)
            nearer_top = np.minimum.accumulate(a, axis=1)
            limit = np.concatenate([np.full((W, 1), H + 1), nearer_top[:, :-1]], axis=1) - 1
            b = np.minimum(np.minimum(b, limit), H - 1)
            a = np.maximum(a, 0)
            ok = finite & (a <= b)
            cols = np.broadcast_to(np.arange(W)[:, None], (W, P))
            k1 = np.broadcast_to(np.arange(1, P + 1)[None, :], (W, P))
            idx = np.concatenate([a[ok] * W + cols[ok], (b[ok] + 1) * W + cols[ok]])
            wts = np.concatenate([k1[ok], -k1[ok]]).astype(np.float64)
            diff = np.bincount(idx, wts, minlength=(H + 2) * W)[: H * W].reshape(H, W)
            # label + 1 of the visible hit per pixel (0 = none); int16 cumsum is the fast one
            label1 = np.cumsum(np.rint(diff).astype(np.int16), axis=0, dtype=np.int16)
            has = label1 > 0
            if np.any(has):
                colors = self._shade_walls(hits, order, z, h, label1)
                colors *= gain
                np.copyto(img, colors, where=has[:, :, None])
        if self.noise_sigma > 0:
            n = img.size
            bank = _noise_bank(n)
            off = int(as_rng(rng).integers(0, n))
            cv2.scaleAdd(bank[off : off + n].reshape(img.shape), float(self.noise_sigma), img, img)
        np.clip(img, 0, 255, out=img)
        return img.astype(np.uint8)

    def _shade_walls(
        self,
        hits: RayHits,
        order: NDArray[np.intp],
        z: NDArray[np.float64],
        h: NDArray[np.float64],
        label1: NDArray[np.int16],
    ) -> NDArray[np.float32]:
        """Colours ``(H, W, 3)`` of the wall pixels (``label1 > 0``; others are don't-care)."""
        H, W = label1.shape
        P = order.shape[1]
        f = self.focal
        cy = self.height / 2.0
        hc = self.mount_height
        # A photographed circle (a round room's wall) shows one photo per tile of about its
        # height, photos k, k+1, ... around it, so that every direction looks different.
        mats = hits.materials
        n_tiles = np.where(
            hits.is_circle & (mats >= MATERIAL_PHOTO),
            np.maximum(1, np.rint(hits.lengths / hits.heights)),
            1,
        ).astype(np.int64)
        first = np.repeat(np.cumsum(n_tiles) - n_tiles, n_tiles)
        all_mats = np.unique(np.repeat(mats, n_tiles) + np.arange(int(n_tiles.sum())) - first)
        atlas = texture_atlas(tuple(all_mats.tolist()))
        # Per (column, hit) quantities; per pixel only the texture row varies, linearly.
        zs = np.where(np.isfinite(z), z, 1.0)
        tiles = n_tiles[order]
        u0 = hits.tex_u[order, 0]
        du = (hits.tex_u[order, 1] - u0) * tiles
        lengths = hits.lengths[order] / np.abs(du)  # metres spanned by one whole texture
        cos_i = np.take_along_axis(hits.cos_incidence, order, axis=1)
        tex_u = u0 + np.take_along_axis(hits.s, order, axis=1) / hits.lengths[order] * du
        tile = np.clip(np.floor(tex_u).astype(np.int64), 0, tiles - 1)
        tex_u -= tile
        # one image pixel spans z / f metres on the wall; the texture spans the whole wall
        footprint = (zs / f) * atlas.size / np.minimum(lengths, h)
        footprint /= np.maximum(cos_i, 0.2)
        lvl = np.clip(np.floor(np.log2(np.maximum(footprint, 1.0))), 0, atlas.n_levels - 1)
        lvl = lvl.astype(np.int64)
        ls = atlas.level_sizes[lvl]
        tx = np.clip((tex_u * ls).astype(np.int64), 0, ls - 1)
        base = atlas.index_of(mats[order] + tile) * atlas.row_length + atlas.offsets[lvl] + tx
        # texture row at image row r (pixel centre r + 0.5):
        # (1 - (hc + (cy - r - 0.5) z / f) / h) * ls = inter + slope * r
        slope = (zs / (f * h) * ls).astype(np.float32).ravel()
        inter = ((1.0 - hc / h) * ls - (cy - 0.5) * (zs / (f * h) * ls)).astype(np.float32).ravel()
        shade = (0.55 + 0.45 * cos_i).astype(np.float32).ravel()
        lsm1 = (ls - 1).astype(np.float32).ravel()
        ls32 = ls.astype(np.int32).ravel()
        base32 = base.astype(np.int32 if base.max() < 2**31 else np.int64).ravel()
        # per pixel: index into the raveled (W, P) tables
        key = np.maximum(label1.astype(np.int32) - 1, 0)
        key += (np.arange(W, dtype=np.int32) * P)[None, :]
        row = np.arange(H, dtype=np.float32)[:, None]
        ty = inter.take(key)
        ty += slope.take(key) * row
        np.clip(ty, 0.0, lsm1.take(key), out=ty)
        flat = base32.take(key) + ty.astype(base32.dtype) * ls32.take(key)
        rgbx = atlas.packed.take(flat).view(np.uint8).reshape(H, W, 4)
        colors = rgbx[:, :, :3].astype(np.float32)
        colors *= shade.take(key)[:, :, None]
        return np.asarray(colors, dtype=np.float32)


@lru_cache(maxsize=4)
def _noise_bank(n: int) -> NDArray[np.float32]:
    """``2 n`` fixed standard-normal samples; an image takes a random window of ``n`` of them.

    Drawing 3 x 640 x 480 normals per image would cost more than the rest of the render, so each
    image uses a seeded random offset into this bank: within an image the noise is i.i.d.
    N(0, 1) x ``noise_sigma``; two images get different windows of the same sequence.
    """
    bank = np.random.default_rng(0x5EED).standard_normal(2 * n, dtype=np.float32)
    bank.setflags(write=False)
    return bank


def render(
    world: World,
    pose: ArrayLike,
    camera: Camera | None = None,
    rng: np.random.Generator | int | None = None,
) -> NDArray[np.uint8]:
    """Render ``world`` from ``pose`` with ``camera`` (default :class:`Camera`); see
    :meth:`Camera.render`."""
    return (Camera() if camera is None else camera).render(world, pose, rng)
