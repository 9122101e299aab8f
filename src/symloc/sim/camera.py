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

from symloc._checks import as_rng, check_finite_scalar
from symloc.camera_model import DEFAULT_HFOV, CameraModel, check_dist_coeffs, focal_from_hfov
from symloc.errors import ConfigurationError
from symloc.geometry import as_pose
from symloc.sim.raycast import RayHits, ray_intersections
from symloc.sim.textures import texture_atlas
from symloc.sim.world import MATERIAL_GLASS, MATERIAL_PHOTO, World

__all__ = ["CAMERA_MOUNT_HEIGHT", "Camera", "CameraConditions", "render"]

CAMERA_MOUNT_HEIGHT = 0.2
"""Default camera height [m]: below the lidar (0.3 m) and the 0.4 m boards, as in the paper."""


@dataclass(frozen=True)
class CameraConditions:
    """The conditions of one capture: exposure, white balance, noise and shutter time.

    A regime (:mod:`symloc.sim.regimes`) draws them per capture and per session (mapping and
    query sessions see different light). The defaults change nothing.

    Parameters
    ----------
    exposure : float
        Brightness relative to the nominal exposure (exposure time x gain x scene light), > 0.
    white_balance : tuple of 3 float
        Gain of the R, G and B channels, each > 0 (1, 1, 1: neutral).
    noise_sigma : float or None
        Pixel noise [grey levels] (None: the camera's ``noise_sigma``).
    exposure_time : float
        Shutter time [s] >= 0, for motion blur from the robot's turn rate.
    """

    exposure: float = 1.0
    white_balance: tuple[float, float, float] = (1.0, 1.0, 1.0)
    noise_sigma: float | None = None
    exposure_time: float = 0.0

    def __post_init__(self) -> None:
        e = check_finite_scalar(self.exposure, "CameraConditions.exposure")
        if e <= 0:
            raise ConfigurationError(f"CameraConditions.exposure: expected a value > 0, got {e}")
        wb = tuple(self.white_balance)
        if len(wb) != 3 or not all(
            isinstance(c, (int, float)) and math.isfinite(c) and c > 0 for c in wb
        ):
            raise ConfigurationError(
                f"CameraConditions.white_balance: expected 3 channel gains > 0, got {wb!r}"
            )
        object.__setattr__(self, "white_balance", tuple(float(c) for c in wb))
        if self.noise_sigma is not None:
            n = check_finite_scalar(self.noise_sigma, "CameraConditions.noise_sigma")
            if n < 0:
                raise ConfigurationError(
                    f"CameraConditions.noise_sigma: expected a value >= 0 grey levels, got {n}"
                )
        t = check_finite_scalar(self.exposure_time, "CameraConditions.exposure_time")
        if t < 0:
            raise ConfigurationError(
                f"CameraConditions.exposure_time: expected a value >= 0 s, got {t}"
            )


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
    dist_coeffs : tuple of float
        Lens distortion ``(k1, k2, p1, p2, k3)`` (OpenCV order; empty or zeros: none). The
        rendered image is distorted; :attr:`calibration` gives the matching calibration.
    vignetting : float
        Fraction of brightness lost in the image corners, in [0, 1) (0: none).
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
    dist_coeffs: tuple[float, ...] = ()
    vignetting: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "dist_coeffs", check_dist_coeffs(self.dist_coeffs, "Camera.dist_coeffs")
        )
        if not (math.isfinite(self.vignetting) and 0.0 <= self.vignetting < 1.0):
            raise ConfigurationError(
                f"Camera.vignetting: expected a fraction in [0, 1), got {self.vignetting}"
            )
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
    def calibration(self) -> CameraModel:
        """The camera's calibration as a robot would have it: intrinsics and distortion."""
        f = self.focal
        return CameraModel(
            int(self.width),
            int(self.height),
            f,
            f,
            self.width / 2.0,
            self.height / 2.0,
            self.dist_coeffs,
        )

    @property
    def has_distortion(self) -> bool:
        """True if the lens distorts (any non-zero coefficient)."""
        return any(c != 0.0 for c in self.dist_coeffs)

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
        *,
        conditions: CameraConditions | None = None,
        twist: tuple[float, float] = (0.0, 0.0),
    ) -> NDArray[np.uint8]:
        """Render the view from the robot at ``pose`` (x [m], y [m], theta [rad]).

        Parameters
        ----------
        world : World
        pose : array of shape (3,)
        rng : Generator, int or None
            Drives the pixel noise.
        conditions : CameraConditions, optional
            Exposure, white balance, noise and shutter time of this capture (default: the
            camera's own gain and noise, no blur).
        twist : (v, w)
            The robot's speed [m/s] and turn rate [rad/s] while the shutter is open (motion
            blur, with ``conditions.exposure_time``).

        Returns
        -------
        ndarray of shape (H, W, 3), uint8
            RGB image.
        """
        p = as_pose(pose)
        cond = conditions if conditions is not None else _NOMINAL
        W, H = int(self.width), int(self.height)
        if self.has_distortion:
            warp = _distortion_maps(W, H, self.focal, self.dist_coeffs)
            img = self._radiance(world, p, warp.canvas_w, warp.canvas_h)
        else:
            img = self._radiance(world, p, W, H)
        blur = self.focal * abs(float(twist[1])) * cond.exposure_time
        if blur >= 0.5:
            img = _box_blur_x(img, blur)
        if self.has_distortion:
            img = np.asarray(
                cv2.remap(
                    img, warp.map1, warp.map2, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
                ),
                dtype=np.float32,
            )
        if self.vignetting > 0.0:
            img *= _vignette(W, H, float(self.vignetting))[:, :, None]
        gain = float(self.gain) * cond.exposure
        wb = np.asarray(cond.white_balance, dtype=np.float32) * np.float32(gain)
        if np.any(wb != 1.0):
            img *= wb
        sigma = self.noise_sigma if cond.noise_sigma is None else cond.noise_sigma
        if sigma > 0:
            n = img.size
            bank = _noise_bank(n)
            off = int(as_rng(rng).integers(0, n))
            cv2.scaleAdd(bank[off : off + n].reshape(img.shape), float(sigma), img, img)
        np.clip(img, 0, 255, out=img)
        return img.astype(np.uint8)

    def _radiance(
        self, world: World, p: NDArray[np.float64], W: int, H: int
    ) -> NDArray[np.float32]:
        """The ideal pinhole image ``(H, W, 3)`` float32 (before gain and noise) of a ``W x H``
        canvas with this camera's focal length, centred on the optical axis."""
        f = self.focal
        cy = H / 2.0
        hc = self.mount_height
        u = np.arange(W) + 0.5
        alpha = np.arctan((W / 2.0 - u) / f)
        hits = ray_intersections(world, p[:2], p[2] + alpha, skip_materials=(MATERIAL_GLASS,))
        P = hits.t.shape[-1]
        img = np.empty((H, W, 3), dtype=np.float32)
        n_above = int(np.count_nonzero(np.arange(H) + 0.5 < cy))
        img[:n_above] = np.asarray(self.sky_color, dtype=np.float32)
        img[n_above:] = np.asarray(self.floor_color, dtype=np.float32)
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
                np.copyto(img, colors, where=has[:, :, None])
        return img

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


_NOMINAL = CameraConditions()


@dataclass(frozen=True)
class _Warp:
    """Remap tables from a distorted ``W x H`` image to the ideal canvas it is sampled from."""

    canvas_w: int
    canvas_h: int
    map1: NDArray[np.int16]
    map2: NDArray[np.uint16]


@lru_cache(maxsize=8)
def _distortion_maps(w: int, h: int, focal: float, dist: tuple[float, ...]) -> _Warp:
    """For each output pixel (OpenCV pixel coordinates, principal point ``(w/2, h/2)``), the
    position in the ideal canvas that shows its undistorted direction (fixed-point maps)."""
    K = np.array([[focal, 0.0, w / 2.0], [0.0, focal, h / 2.0], [0.0, 0.0, 1.0]])
    uu, vv = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    pts = np.column_stack([uu.ravel(), vv.ravel()]).reshape(-1, 1, 2)
    und = cv2.undistortPoints(pts, K, np.asarray(dist), criteria=_UNDISTORT_CRITERIA)
    xn = und.reshape(h, w, 2)
    ext_x = float(np.max(np.abs(xn[:, :, 0]))) * focal
    ext_y = float(np.max(np.abs(xn[:, :, 1]))) * focal
    cw = 2 * math.ceil(ext_x + 2.0)
    ch = 2 * math.ceil(ext_y + 2.0)
    # a canvas pixel index i looks along (i + 0.5 - cw / 2) / f
    mx = (xn[:, :, 0] * focal + cw / 2.0 - 0.5).astype(np.float32)
    my = (xn[:, :, 1] * focal + ch / 2.0 - 0.5).astype(np.float32)
    m1, m2 = cv2.convertMaps(mx, my, cv2.CV_16SC2)
    return _Warp(cw, ch, np.asarray(m1), np.asarray(m2))


_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 20, 1e-9)


@lru_cache(maxsize=8)
def _vignette(w: int, h: int, v: float) -> NDArray[np.float32]:
    """Relative brightness ``(h, w)``: ``1 - v (r / r_corner)^2`` about the image centre."""
    x = (np.arange(w, dtype=np.float32) + 0.5 - w / 2.0) / (w / 2.0)
    y = (np.arange(h, dtype=np.float32) + 0.5 - h / 2.0) / (w / 2.0)
    r2 = x[None, :] ** 2 + y[:, None] ** 2
    out = (1.0 - v * r2 / float(1.0 + (h / w) ** 2)).astype(np.float32)
    out.setflags(write=False)
    return out


def _box_blur_x(img: NDArray[np.float32], length: float) -> NDArray[np.float32]:
    """Horizontal box blur over ``length`` pixels (fractional: the end taps are weighted)."""
    n = math.ceil(length)
    if n % 2 == 0:
        n += 1
    k = np.zeros(n, dtype=np.float32)
    full = math.floor(length)
    if full % 2 == 0:
        full = max(full - 1, 1)
    c = n // 2
    k[c - full // 2 : c + full // 2 + 1] = 1.0
    rest = (length - full) / 2.0
    if rest > 0 and full + 2 <= n:
        k[c - full // 2 - 1] = rest
        k[c + full // 2 + 1] = rest
    k /= k.sum()
    out = cv2.filter2D(img, -1, k[None, :], borderType=cv2.BORDER_REPLICATE)
    return np.asarray(out, dtype=np.float32)


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
    *,
    conditions: CameraConditions | None = None,
    twist: tuple[float, float] = (0.0, 0.0),
) -> NDArray[np.uint8]:
    """Render ``world`` from ``pose`` with ``camera`` (default :class:`Camera`); see
    :meth:`Camera.render`."""
    cam = Camera() if camera is None else camera
    return cam.render(world, pose, rng, conditions=conditions, twist=twist)
