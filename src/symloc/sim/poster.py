"""Procedural wall textures: a deterministic pool of thousands of distinct posters and walls.

Texture ``k`` of the pool (:func:`procedural_texture`) is drawn from a generator seeded with
``k`` alone, so it is the same on every machine and in every process, and nothing is
downloaded: the ingredients are the 16 photographs bundled with scikit-image
(:func:`symloc.sim.textures.load_photo`), cropped, flipped and recoloured, and synthetic content
drawn with OpenCV. Eight families, chosen by the seed:

- ``poster``: one photo crop, sometimes framed, with a title band of text;
- ``collage``: a grid of 2-9 photo crops on a coloured board;
- ``shelves``: a bookcase, shelves of books of random widths, heights and colours, some boxes;
- ``tiles``: a tiled wall of 2-4 colours with grout lines, sometimes with a poster on it;
- ``window``: a painted wall with one or two windows showing a photo crop as the view;
- ``shapes``: abstract art or signage, random circles, rectangles, polygons, lines and text;
- ``notices``: a cork board with pinned notes of text and small pictures;
- ``signage``: large text lines, arrows and a logo on a coloured panel.

Every texture is ``size x size`` RGB uint8; building one at 768 x 768 takes about 5-15 ms
(``benchmarks/bench_sim.py``).
"""

from __future__ import annotations

import math
import string
from collections.abc import Callable

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["POSTER_KINDS", "poster_kind", "procedural_texture"]

Image = NDArray[np.uint8]
PhotoFn = Callable[[int, int], Image]

_FONTS = (
    cv2.FONT_HERSHEY_SIMPLEX,
    cv2.FONT_HERSHEY_DUPLEX,
    cv2.FONT_HERSHEY_COMPLEX,
    cv2.FONT_HERSHEY_TRIPLEX,
    cv2.FONT_HERSHEY_PLAIN,
    cv2.FONT_HERSHEY_SCRIPT_SIMPLEX,
    cv2.FONT_HERSHEY_COMPLEX_SMALL,
)
_PHOTO_SOURCE = 768  # edge [px] of the photos that crops are cut from
_CHARS = string.ascii_uppercase + string.ascii_lowercase + string.digits + "  -&.:/"


def _colour(rng: np.random.Generator, lo: int = 0, hi: int = 256) -> tuple[int, int, int]:
    c = rng.integers(lo, hi, 3)
    return (int(c[0]), int(c[1]), int(c[2]))


def _contrast(c: tuple[int, int, int], rng: np.random.Generator) -> tuple[int, int, int]:
    """A colour that stands out against ``c`` (dark on light, light on dark)."""
    lum = 0.3 * c[0] + 0.59 * c[1] + 0.11 * c[2]
    return _colour(rng, 0, 70) if lum > 128 else _colour(rng, 185, 256)


def _word(rng: np.random.Generator, n: int) -> str:
    return "".join(_CHARS[i] for i in rng.integers(0, len(_CHARS), n)).strip() or "A"


def _text(
    img: Image,
    rng: np.random.Generator,
    box: tuple[int, int, int, int],
    colour: tuple[int, int, int],
    lines: int,
) -> None:
    """Up to ``lines`` lines of random text inside ``box`` = (x0, y0, x1, y1)."""
    x0, y0, x1, y1 = box
    w, h = x1 - x0, y1 - y0
    if w < 16 or h < 10:
        return
    font = _FONTS[int(rng.integers(len(_FONTS)))]
    line_h = h / max(1, lines)
    for i in range(lines):
        s = _word(rng, int(rng.integers(4, 18)))
        thick = int(rng.integers(1, 4))
        (tw, th), _ = cv2.getTextSize(s, font, 1.0, thick)
        scale = min(0.8 * line_h / max(th, 1), 0.95 * w / max(tw, 1))
        if scale <= 0.15:
            continue
        scale *= float(rng.uniform(0.6, 1.0))
        thick = max(1, round(thick * scale))
        (tw, th), _ = cv2.getTextSize(s, font, scale, thick)
        tx = x0 + int(rng.uniform(0, max(1, w - tw)))
        ty = int(y0 + (i + 0.5) * line_h + th / 2)
        cv2.putText(img, s, (tx, ty), font, scale, colour, thick, cv2.LINE_AA)


def _recolour(img: Image, rng: np.random.Generator) -> Image:
    """A colour change: channel swap, hue rotation, grey with a tint, or contrast/gamma."""
    mode = int(rng.integers(5))
    if mode == 0:
        return img
    if mode == 1:
        return np.ascontiguousarray(img[:, :, rng.permutation(3)])
    if mode == 2:
        hsv = cv2.cvtColor(img, cv2.COLOR_RGB2HSV)
        hsv[:, :, 0] = (hsv[:, :, 0].astype(np.int16) + int(rng.integers(20, 160))) % 180
        return np.asarray(cv2.cvtColor(hsv, cv2.COLOR_HSV2RGB), dtype=np.uint8)
    if mode == 3:
        g = cv2.cvtColor(img, cv2.COLOR_RGB2GRAY).astype(np.float32) / 255.0
        tint = rng.uniform(0.5, 1.0, 3).astype(np.float32) * 255.0
        return np.asarray(g[:, :, None] * tint[None, None, :], dtype=np.uint8)
    gamma = float(rng.uniform(0.5, 2.0))
    lut = np.clip(255.0 * (np.arange(256) / 255.0) ** gamma, 0, 255).astype(np.uint8)
    return np.asarray(cv2.LUT(img, lut), dtype=np.uint8)


def _photo_crop(rng: np.random.Generator, photo: PhotoFn, w: int, h: int) -> Image:
    """A recoloured, possibly flipped crop of a bundled photo, resized to ``w x h``."""
    src = photo(int(rng.integers(16)), _PHOTO_SOURCE)
    n = src.shape[0]
    aspect = w / max(h, 1)
    frac = float(rng.uniform(0.3, 1.0))
    cw = int(n * frac * min(1.0, aspect))
    ch = int(n * frac * min(1.0, 1.0 / aspect))
    cw, ch = max(cw, 8), max(ch, 8)
    x0 = int(rng.integers(0, n - cw + 1))
    y0 = int(rng.integers(0, n - ch + 1))
    crop = src[y0 : y0 + ch, x0 : x0 + cw]
    if rng.random() < 0.5:
        crop = crop[:, ::-1]
    if rng.random() < 0.15:
        crop = crop[::-1]
    interp = cv2.INTER_AREA if cw >= w else cv2.INTER_LINEAR
    out = np.asarray(cv2.resize(np.ascontiguousarray(crop), (w, h), interpolation=interp))
    return _recolour(out.astype(np.uint8), rng)


def _board(rng: np.random.Generator, s: int, colour: tuple[int, int, int] | None = None) -> Image:
    c = _colour(rng) if colour is None else colour
    img = np.empty((s, s, 3), dtype=np.uint8)
    img[:] = c
    if rng.random() < 0.4:  # a soft vertical gradient
        g = np.linspace(float(rng.uniform(0.7, 1.0)), float(rng.uniform(0.7, 1.0)), s)
        col = (np.asarray(c, dtype=np.float32)[None, :] * g[:, None].astype(np.float32)).astype(
            np.uint8
        )
        img[:] = col[:, None, :]
    return img


def _poster(rng: np.random.Generator, s: int, photo: PhotoFn) -> Image:
    img = _photo_crop(rng, photo, s, s)
    if rng.random() < 0.5:
        b = int(s * rng.uniform(0.02, 0.08))
        frame = _colour(rng)
        cv2.rectangle(img, (0, 0), (s - 1, s - 1), frame, 2 * b)
    if rng.random() < 0.7:
        band = _colour(rng)
        y0 = int(s * rng.choice([0.0, rng.uniform(0.6, 0.8)]))
        y1 = y0 + int(s * rng.uniform(0.12, 0.22))
        cv2.rectangle(img, (0, y0), (s - 1, y1), band, -1)
        _text(img, rng, (int(0.05 * s), y0, int(0.95 * s), y1), _contrast(band, rng), 1)
    return img


def _collage(rng: np.random.Generator, s: int, photo: PhotoFn) -> Image:
    img = _board(rng, s)
    gx, gy = int(rng.integers(1, 4)), int(rng.integers(1, 4))
    if gx * gy == 1:
        gx = 2
    gap = int(s * rng.uniform(0.01, 0.05))
    cw = (s - (gx + 1) * gap) // gx
    ch = (s - (gy + 1) * gap) // gy
    for i in range(gx):
        for j in range(gy):
            x = gap + i * (cw + gap)
            y = gap + j * (ch + gap)
            img[y : y + ch, x : x + cw] = _photo_crop(rng, photo, cw, ch)
    return img


def _shelves(rng: np.random.Generator, s: int, _photo: PhotoFn) -> Image:
    img = _board(rng, s, _colour(rng, 60, 200))
    n = int(rng.integers(3, 7))
    wood = _colour(rng, 60, 170)
    board = max(3, int(s * rng.uniform(0.015, 0.03)))
    pitch = s / n
    for k in range(n):
        y_floor = int((k + 1) * pitch) - board
        top = int(k * pitch) + board
        x = int(rng.integers(0, int(0.05 * s) + 1))
        while x < s:
            if rng.random() < 0.08:  # a gap or a box
                w = int(s * rng.uniform(0.04, 0.12))
                if rng.random() < 0.5:
                    hb = int((y_floor - top) * rng.uniform(0.3, 0.7))
                    col = _colour(rng)
                    cv2.rectangle(img, (x, y_floor - hb), (x + w, y_floor), col, -1)
                    _text(img, rng, (x, y_floor - hb, x + w, y_floor), _contrast(col, rng), 1)
                x += w
                continue
            w = int(s * rng.uniform(0.012, 0.04))
            hb = int((y_floor - top) * rng.uniform(0.55, 0.97))
            col = _colour(rng, 20, 235)
            cv2.rectangle(img, (x, y_floor - hb), (x + w - 1, y_floor), col, -1)
            if rng.random() < 0.6:
                yy = y_floor - int(hb * rng.uniform(0.2, 0.8))
                cv2.line(img, (x, yy), (x + w - 1, yy), _contrast(col, rng), max(1, w // 6))
            x += w + int(rng.integers(0, 3))
        cv2.rectangle(img, (0, y_floor), (s - 1, y_floor + board), wood, -1)
    return img


def _tiles(rng: np.random.Generator, s: int, photo: PhotoFn) -> Image:
    n = int(rng.integers(5, 20))
    palette = np.array([_colour(rng) for _ in range(int(rng.integers(2, 5)))], dtype=np.int16)
    pick = rng.integers(0, len(palette), (n, n))
    if rng.random() < 0.5:  # a regular pattern instead of a random one
        ii, jj = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        pick = (ii + jj * int(rng.integers(1, 3))) % len(palette)
    small = palette[pick] + rng.integers(-12, 13, (n, n, 3))
    small = np.clip(small, 0, 255).astype(np.uint8)
    img = np.asarray(cv2.resize(small, (s, s), interpolation=cv2.INTER_NEAREST), dtype=np.uint8)
    grout = _colour(rng, 150, 256) if rng.random() < 0.6 else _colour(rng, 0, 90)
    gw = max(1, int(s / n * rng.uniform(0.04, 0.12)))
    for k in range(n + 1):
        p = min(s - 1, round(k * s / n))
        img[:, max(0, p - gw // 2) : p + gw // 2 + 1] = grout
        img[max(0, p - gw // 2) : p + gw // 2 + 1, :] = grout
    if rng.random() < 0.35:
        w = int(s * rng.uniform(0.3, 0.55))
        h = int(w * rng.uniform(0.7, 1.4))
        x, y = int(rng.integers(0, s - w)), int(rng.integers(0, s - h))
        img[y : y + h, x : x + w] = _photo_crop(rng, photo, w, h)
    return img


def _window(rng: np.random.Generator, s: int, photo: PhotoFn) -> Image:
    wall = _colour(rng, 120, 245)
    img = _board(rng, s, wall)
    count = int(rng.integers(1, 3))
    for i in range(count):
        w = int(s * rng.uniform(0.25, 0.4))
        h = int(s * rng.uniform(0.35, 0.6))
        x = int(s * (i + 0.5) / count - w / 2 + rng.uniform(-0.05, 0.05) * s)
        x = int(np.clip(x, 0, s - w))
        y = int(s * rng.uniform(0.1, 0.3))
        view = _photo_crop(rng, photo, w, h)
        sky = np.linspace(1.0, 0.0, h)[:, None, None] ** 2 * float(rng.uniform(0.0, 0.6))
        blue = np.array([150, 190, 235], dtype=np.float32)
        view = np.clip(view * (1 - sky) + blue * sky, 0, 255).astype(np.uint8)
        img[y : y + h, x : x + w] = view
        frame = _colour(rng, 180, 256) if rng.random() < 0.7 else _colour(rng, 20, 90)
        t = max(3, int(s * rng.uniform(0.01, 0.025)))
        cv2.rectangle(img, (x, y), (x + w, y + h), frame, t)
        cv2.line(img, (x + w // 2, y), (x + w // 2, y + h), frame, t)
        if rng.random() < 0.6:
            cv2.line(img, (x, y + h // 2), (x + w, y + h // 2), frame, t)
        cv2.rectangle(img, (x - t, y + h), (x + w + t, y + h + 2 * t), frame, -1)
    return img


def _shapes(rng: np.random.Generator, s: int, _photo: PhotoFn) -> Image:
    img = _board(rng, s)
    for _ in range(int(rng.integers(8, 40))):
        col = _colour(rng)
        kind = int(rng.integers(4))
        c = (int(rng.integers(0, s)), int(rng.integers(0, s)))
        r = int(s * rng.uniform(0.02, 0.2))
        filled = -1 if rng.random() < 0.7 else int(rng.integers(2, 8))
        if kind == 0:
            cv2.circle(img, c, r, col, filled, cv2.LINE_AA)
        elif kind == 1:
            cv2.rectangle(img, (c[0] - r, c[1] - r // 2), (c[0] + r, c[1] + r // 2), col, filled)
        elif kind == 2:
            k = int(rng.integers(3, 7))
            ang = np.sort(rng.uniform(0, 2 * math.pi, k))
            pts = np.column_stack([c[0] + r * np.cos(ang), c[1] + r * np.sin(ang)])
            cv2.fillPoly(img, [pts.astype(np.int32)], col, cv2.LINE_AA)
        else:
            e = (int(rng.integers(0, s)), int(rng.integers(0, s)))
            cv2.line(img, c, e, col, int(rng.integers(2, 12)), cv2.LINE_AA)
    if rng.random() < 0.6:
        y = int(s * rng.uniform(0.05, 0.8))
        _text(img, rng, (int(0.05 * s), y, int(0.95 * s), y + int(0.15 * s)), _colour(rng), 1)
    return img


def _notices(rng: np.random.Generator, s: int, photo: PhotoFn) -> Image:
    cork = (np.array([168, 124, 78]) + rng.integers(-25, 26, 3)).astype(np.int16)
    grain = rng.integers(-18, 19, (s, s, 1), dtype=np.int16)
    img: Image = np.clip(cork[None, None, :] + grain, 0, 255).astype(np.uint8)
    for _ in range(int(rng.integers(5, 15))):
        w = int(s * rng.uniform(0.12, 0.3))
        h = int(s * rng.uniform(0.12, 0.3))
        x, y = int(rng.integers(0, s - w)), int(rng.integers(0, s - h))
        paper = _colour(rng, 200, 256)
        cv2.rectangle(img, (x, y), (x + w, y + h), paper, -1)
        if rng.random() < 0.3 and w > 20 and h > 20:
            ph = h // 2
            img[y + 4 : y + ph, x + 4 : x + w - 4] = _photo_crop(rng, photo, w - 8, ph - 4)
            _text(img, rng, (x + 4, y + ph, x + w - 4, y + h - 4), _colour(rng, 0, 80), 2)
        else:
            _text(img, rng, (x + 4, y + 4, x + w - 4, y + h - 4), _colour(rng, 0, 80), 4)
        cv2.circle(img, (x + w // 2, y + 6), max(3, s // 150), _colour(rng), -1, cv2.LINE_AA)
    return img


def _signage(rng: np.random.Generator, s: int, _photo: PhotoFn) -> Image:
    bg = _colour(rng)
    img = _board(rng, s, bg)
    fg = _contrast(bg, rng)
    n = int(rng.integers(2, 6))
    _text(img, rng, (int(0.05 * s), int(0.05 * s), int(0.95 * s), int(0.7 * s)), fg, n)
    # an arrow and a round logo
    y = int(0.82 * s)
    x0, x1 = int(s * rng.uniform(0.05, 0.3)), int(s * rng.uniform(0.6, 0.95))
    if rng.random() < 0.5:
        x0, x1 = x1, x0
    cv2.arrowedLine(img, (x0, y), (x1, y), fg, max(3, s // 60), cv2.LINE_AA, tipLength=0.2)
    if rng.random() < 0.7:
        c = (int(s * rng.uniform(0.1, 0.9)), int(s * rng.uniform(0.1, 0.6)))
        r = int(s * rng.uniform(0.05, 0.12))
        cv2.circle(img, c, r, _colour(rng), -1, cv2.LINE_AA)
        cv2.circle(img, c, r // 2, _colour(rng), max(2, r // 5), cv2.LINE_AA)
    return img


_BUILDERS: dict[str, Callable[[np.random.Generator, int, PhotoFn], Image]] = {
    "poster": _poster,
    "collage": _collage,
    "shelves": _shelves,
    "tiles": _tiles,
    "window": _window,
    "shapes": _shapes,
    "notices": _notices,
    "signage": _signage,
}

POSTER_KINDS = tuple(_BUILDERS)
"""The families of :func:`procedural_texture`, in the order the seed picks them."""

_SEED = 0x5E75


def poster_kind(k: int) -> str:
    """The family of pool texture ``k``."""
    rng = np.random.default_rng((_SEED, int(k)))
    return POSTER_KINDS[int(rng.integers(len(POSTER_KINDS)))]


def procedural_texture(k: int, size: int, photo: PhotoFn) -> Image:
    """Texture ``k`` of the procedural pool, ``(size, size, 3)`` uint8 RGB.

    ``photo(index, size)`` returns a bundled photo (:func:`symloc.sim.textures.load_photo`).
    Deterministic: the same ``k`` and ``size`` always give the same image.
    """
    rng = np.random.default_rng((_SEED, int(k)))
    kind = POSTER_KINDS[int(rng.integers(len(POSTER_KINDS)))]
    img = _BUILDERS[kind](rng, int(size), photo)
    out = np.ascontiguousarray(img, dtype=np.uint8)
    out.setflags(write=False)
    return out
