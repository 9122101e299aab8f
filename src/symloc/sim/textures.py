"""Surface textures for the simulated camera: a pool of wall textures and plain materials.

Material ``MATERIAL_PHOTO + k`` shows texture ``k % TEXTURE_POOL_SIZE`` of a deterministic pool
of 4096 distinct textures:

- ``k < 16``: the photographs scikit-image ships inside its wheel (``skimage.data``; nothing is
  downloaded at run time): astronaut, coffee, chelsea (a cat), rocket, the Hubble deep field,
  the left view of the Middlebury motorcycle stereo pair, an immunohistochemistry slide, the
  cameraman, coins, the moon, a clock, a brick wall, grass, gravel, a retina and a printed page
  (the textures of symloc's rooms since the beginning);
- ``k >= 16``: procedural posters and walls built from crops, flips and colour changes of
  those photos plus synthetic content (text, shapes, shelves, tiles, windows, notice boards,
  signs), seeded by ``k`` alone (:mod:`symloc.sim.poster`).

Plain materials are a flat colour with faint (+-3 grey level) noise, like a matte painted
surface (board, wall, wood, a dark surface, glass seen head-on). ``MATERIAL_PERSON`` is a
person: hair and face, a patterned shirt, trousers and shoes, different all around (one
texture spans a person's circumference).

Each texture is a ``TEXTURE_SIZE`` square and comes with a mip-map pyramid (each level half the
previous one, box-filtered), so that a far wall is sampled like a camera would integrate it,
not aliased into pixel noise.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.sim.poster import procedural_texture
from symloc.sim.world import (
    MATERIAL_BOARD,
    MATERIAL_DARK,
    MATERIAL_FURNITURE,
    MATERIAL_GLASS,
    MATERIAL_PERSON,
    MATERIAL_PHOTO,
    MATERIAL_WALL,
)

__all__ = [
    "PHOTO_NAMES",
    "PLAIN_COLORS",
    "TEXTURE_POOL_SIZE",
    "TEXTURE_SIZE",
    "TextureAtlas",
    "load_photo",
    "material_texture",
    "person_texture",
    "pool_texture",
    "texture_atlas",
]

TEXTURE_SIZE = 768
"""Edge [pixels] of every texture (level 0 of its mip-map); photos are resized to it with
bicubic interpolation, so a near wall is magnified smoothly, not in blocks."""

PHOTO_NAMES = (
    "astronaut",
    "coffee",
    "chelsea",
    "rocket",
    "hubble_deep_field",
    "motorcycle_left",
    "immunohistochemistry",
    "camera",
    "coins",
    "moon",
    "clock",
    "brick",
    "grass",
    "gravel",
    "retina",
    "page",
)
"""The ``skimage.data`` photographs, in material order."""

TEXTURE_POOL_SIZE = 4096
"""Number of distinct wall textures: ``MATERIAL_PHOTO + k`` shows texture ``k % 4096``."""

PLAIN_COLORS: dict[int, tuple[int, int, int]] = {
    MATERIAL_BOARD: (196, 188, 170),
    MATERIAL_WALL: (205, 205, 200),
    MATERIAL_FURNITURE: (130, 95, 60),
    MATERIAL_GLASS: (176, 196, 204),
    MATERIAL_DARK: (34, 33, 36),
}
"""RGB of the plain materials (board, painted wall, wood, glass, a dark surface). The camera
sees through glass (:mod:`symloc.sim.camera`); its colour is only used if a caller asks for it."""

_N_LEVELS = 7  # 768 .. 12


@lru_cache(maxsize=32)
def load_photo(index: int, size: int = TEXTURE_SIZE) -> NDArray[np.uint8]:
    """Photograph ``index % len(PHOTO_NAMES)`` as a ``(size, size, 3)`` uint8 RGB array."""
    import skimage.data

    name = PHOTO_NAMES[int(index) % len(PHOTO_NAMES)]
    if name == "motorcycle_left":
        img = skimage.data.stereo_motorcycle()[0]  # type: ignore[no-untyped-call]
    else:
        img = getattr(skimage.data, name)()
    img = np.asarray(img)
    if img.dtype == bool:
        img = img.astype(np.uint8) * 255
    if img.ndim == 2:
        img = np.repeat(img[:, :, None], 3, axis=2)
    img = np.ascontiguousarray(img[:, :, :3]).astype(np.uint8)
    interp = cv2.INTER_AREA if min(img.shape[:2]) >= size else cv2.INTER_CUBIC
    out = np.asarray(cv2.resize(img, (size, size), interpolation=interp), dtype=np.uint8)
    out.setflags(write=False)
    return out


def pool_texture(k: int, size: int = TEXTURE_SIZE) -> NDArray[np.uint8]:
    """Texture ``k % TEXTURE_POOL_SIZE`` of the pool, ``(size, size, 3)`` uint8 RGB."""
    i = int(k) % TEXTURE_POOL_SIZE
    if i < len(PHOTO_NAMES):
        return load_photo(i, size)
    return procedural_texture(i, size, load_photo)


def person_texture(size: int = TEXTURE_SIZE) -> NDArray[np.uint8]:
    """A person seen all around, ``(size, size, 3)`` uint8: rows top to bottom are hair and
    face (12 %), a shirt (12-52 %), trousers (52-94 %) and shoes; columns go once around the
    person, with the clothes of five people side by side so that people look different from
    different sides."""
    rng = np.random.default_rng(0x9E0)
    s = int(size)
    img = np.empty((s, s, 3), dtype=np.uint8)
    rows = (np.array([0.0, 0.05, 0.12, 0.52, 0.94, 1.0]) * s).astype(int)
    n = 5
    edges = np.linspace(0, s, n + 1).astype(int)
    for i in range(n):
        x0, x1 = edges[i], edges[i + 1]
        hair = rng.integers(10, 110, 3)
        skin = np.array([224, 172, 140]) * rng.uniform(0.45, 1.05)
        shirt = rng.integers(20, 240, 3)
        shirt2 = rng.integers(20, 240, 3)
        trousers = rng.integers(15, 90, 3) + np.array([0, 0, int(rng.integers(0, 80))])
        img[rows[0] : rows[1], x0:x1] = hair
        img[rows[1] : rows[2], x0:x1] = np.clip(skin, 0, 255)
        band = img[rows[2] : rows[3], x0:x1]
        band[:] = shirt
        style = i % 3
        if style == 0:  # stripes
            pitch = max(2, s // int(rng.integers(20, 60)))
            band[(np.arange(band.shape[0]) // pitch) % 2 == 1] = shirt2
        elif style == 1:  # checks
            pitch = max(2, s // int(rng.integers(15, 40)))
            yy, xx = np.mgrid[0 : band.shape[0], 0 : band.shape[1]]
            band[((yy // pitch) + (xx // pitch)) % 2 == 1] = shirt2
        else:  # a print on the front
            cx, cy = band.shape[1] // 2, band.shape[0] // 2
            cv2.circle(band, (cx, cy), band.shape[1] // 4, tuple(int(c) for c in shirt2), -1)
            cv2.putText(
                band,
                "SYM",
                (cx - band.shape[1] // 4, cy),
                cv2.FONT_HERSHEY_DUPLEX,
                s / 700.0,
                (240, 240, 240),
                max(1, s // 300),
                cv2.LINE_AA,
            )
        img[rows[3] : rows[4], x0:x1] = trousers
        img[rows[4] : rows[5], x0:x1] = rng.integers(5, 60, 3)
    # folds: faint darker vertical lines
    img[:, :: max(2, s // 48)] = (img[:, :: max(2, s // 48)] * 0.8).astype(np.uint8)
    img.setflags(write=False)
    return img


@lru_cache(maxsize=32)
def material_texture(material: int, size: int = TEXTURE_SIZE) -> NDArray[np.uint8]:
    """The ``(size, size, 3)`` uint8 texture of a material id."""
    m = int(material)
    if m >= MATERIAL_PHOTO:
        return pool_texture(m - MATERIAL_PHOTO, size)
    if m == MATERIAL_PERSON:
        return person_texture(size)
    if m not in PLAIN_COLORS:
        raise ConfigurationError(
            f"material: unknown material id {m}; expected one of"
            f" {sorted([*PLAIN_COLORS, MATERIAL_PERSON])} or >= {MATERIAL_PHOTO} (a wall texture)"
        )
    rng = np.random.default_rng(1000 + m)  # fixed: a material always looks the same
    base = np.array(PLAIN_COLORS[m], dtype=np.int16)
    tex = base + rng.integers(-3, 4, size=(size, size, 1), dtype=np.int16)
    out: NDArray[np.uint8] = np.clip(tex, 0, 255).astype(np.uint8)
    out.setflags(write=False)
    return out


class TextureAtlas:
    """Mip-mapped textures of a set of materials in one flat array for vectorised lookup.

    Parameters
    ----------
    materials : tuple of int
        Material ids, sorted ascending.

    Attributes
    ----------
    texels : ndarray of shape (M * L, 3), uint8
        For each material, all mip levels concatenated (level l is ``(size >> l)^2`` texels);
        material row ``i`` starts at ``i * row_length``.
    packed : ndarray of shape (M * L,), uint32
        The same texels packed as R, G, B, 255 bytes.
    offsets : ndarray of shape (levels,)
        Start of each level inside a material's row.
    """

    def __init__(self, materials: tuple[int, ...], size: int = TEXTURE_SIZE) -> None:
        self.materials = np.array(materials, dtype=np.int64)
        self.size = int(size)
        levels: list[int] = []
        s = self.size
        while s >= 8 and len(levels) < _N_LEVELS:
            levels.append(s)
            s //= 2
        self.level_sizes = np.array(levels, dtype=np.int64)
        self.offsets = np.concatenate([[0], np.cumsum(self.level_sizes**2)[:-1]]).astype(np.int64)
        total = int(np.sum(self.level_sizes**2))
        packed = np.empty(len(materials) * total, dtype=np.uint32)
        for i, m in enumerate(materials):
            img = material_texture(m, self.size)
            for lvl, ls in enumerate(levels):
                if lvl:
                    img = np.asarray(
                        cv2.resize(img, (int(ls), int(ls)), interpolation=cv2.INTER_AREA),
                        dtype=np.uint8,
                    )
                off = i * total + int(self.offsets[lvl])
                rgba = cv2.cvtColor(np.ascontiguousarray(img), cv2.COLOR_RGB2RGBA)
                packed[off : off + ls * ls] = np.asarray(rgba).view(np.uint32).ravel()
        #: the texels packed as one uint32 each (R, G, B, 255 bytes), for 1-D gathers
        self.packed = packed
        #: the same texels as an ``(M * L, 3)`` view (no copy)
        self.texels = packed.view(np.uint8).reshape(-1, 4)[:, :3]
        self.row_length = total

    @property
    def n_levels(self) -> int:
        """Number of mip levels."""
        return int(self.level_sizes.size)

    def index_of(self, materials: NDArray[np.int64]) -> NDArray[np.int64]:
        """Atlas row of each material id (ids must be in the atlas)."""
        return np.searchsorted(self.materials, materials)

    def sample(
        self,
        rows: NDArray[np.int64],
        u: NDArray[np.float64],
        v: NDArray[np.float64],
        footprint: NDArray[np.float64],
    ) -> NDArray[np.uint8]:
        """Nearest-texel colours ``(..., 3)`` at texture coordinates ``u, v`` in [0, 1).

        ``footprint`` is the size of one image pixel in level-0 texels; the mip level is
        ``floor(log2(footprint))`` (clamped).
        """
        lvl = np.clip(np.floor(np.log2(np.maximum(footprint, 1.0))), 0, self.n_levels - 1)
        lvl = lvl.astype(np.int64)
        ls = self.level_sizes[lvl]
        tx = np.clip((u * ls).astype(np.int64), 0, ls - 1)
        ty = np.clip((v * ls).astype(np.int64), 0, ls - 1)
        flat = rows * self.row_length + self.offsets[lvl] + ty * ls + tx
        return np.asarray(self.texels[flat], dtype=np.uint8)


@lru_cache(maxsize=8)
def texture_atlas(materials: tuple[int, ...], size: int = TEXTURE_SIZE) -> TextureAtlas:
    """A cached :class:`TextureAtlas` for the sorted material ids ``materials``."""
    return TextureAtlas(tuple(sorted(set(materials))), size)
