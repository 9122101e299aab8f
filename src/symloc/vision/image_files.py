"""Users' own image files: reading them, camera intrinsics from a field of view, and a place
built from M photos taken at a room's centre (in clockwise order, as the paper stores them)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError, DataFormatError
from symloc.image_header import MAX_PHOTO_PIXELS, read_image_file
from symloc.vision.orb import OrbExtractor
from symloc.vision.visual_map import PlaceImage, direction_headings
from symloc.vision.vocabulary import IMAGE_SUFFIXES, Vocabulary

__all__ = [
    "IMAGE_SUFFIXES",
    "check_photo_size",
    "intrinsics_from_fov",
    "intrinsics_from_values",
    "place_images_from_files",
    "read_image",
]


def read_image(path: str | Path, *, max_pixels: int = MAX_PHOTO_PIXELS) -> NDArray[np.uint8]:
    """Read an image file as ``(H, W)`` grey or ``(H, W, 3)`` RGB uint8.

    The size its header declares is checked against ``max_pixels`` before decoding.

    Raises
    ------
    DataFormatError
        The file does not exist, is not an image OpenCV can decode, or is too large.
    """
    p = Path(path)
    if not p.is_file():
        raise DataFormatError(f"{p}: no such image file")
    try:
        img = read_image_file(p, max_pixels=max_pixels)
    except DataFormatError as err:
        why = str(err).removeprefix(f"{p}: ")
        raise DataFormatError(
            f"{p}: not a readable image ({why}; expected one of {', '.join(IMAGE_SUFFIXES)})"
        ) from err
    if img.dtype != np.uint8:
        img = cv2.convertScaleAbs(img, alpha=255.0 / max(float(img.max()), 1.0))
    if img.ndim == 3 and img.shape[2] == 4:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2RGB)
    elif img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
    return np.ascontiguousarray(img, np.uint8)


def check_photo_size(image: NDArray[Any], path: str | Path, extractor: OrbExtractor) -> None:
    """Refuse a photo with a side below ``extractor.min_image_side`` (ORB finds nothing in it).

    Raises
    ------
    DataFormatError
        Naming the file, its size and the minimum.
    """
    h, w = image.shape[:2]
    side = extractor.min_image_side
    if min(h, w) < side:
        raise DataFormatError(
            f"{path}: {w} x {h} pixels; a photo needs at least {side} x {side} pixels for ORB"
            " to find a keypoint"
        )


def intrinsics_from_fov(hfov_deg: float, width: int, height: int) -> NDArray[np.float64]:
    """Pinhole camera matrix ``(3, 3)`` of a ``width x height`` image with horizontal field of
    view ``hfov_deg`` [deg], square pixels and the principal point at the image centre."""
    if not (math.isfinite(hfov_deg) and 0.0 < hfov_deg < 180.0):
        raise ConfigurationError(f"hfov: expected a value in (0, 180) degrees, got {hfov_deg}")
    if width < 1 or height < 1:
        raise ConfigurationError(f"image size: expected positive, got {width}x{height}")
    f = 0.5 * width / math.tan(0.5 * math.radians(hfov_deg))
    return np.array([[f, 0.0, width / 2.0], [0.0, f, height / 2.0], [0.0, 0.0, 1.0]])


def intrinsics_from_values(fx: float, fy: float, cx: float, cy: float) -> NDArray[np.float64]:
    """Camera matrix ``(3, 3)`` from ``fx, fy, cx, cy`` [px] (fx, fy > 0)."""
    vals = (fx, fy, cx, cy)
    if not all(math.isfinite(v) for v in vals) or fx <= 0 or fy <= 0:
        raise ConfigurationError(
            f"intrinsics: expected finite fx, fy > 0 and cx, cy, got {list(vals)}"
        )
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def place_images_from_files(
    paths: Sequence[str | Path],
    vocabulary: Vocabulary,
    *,
    heading0: float = 0.0,
    extractor: OrbExtractor | None = None,
    keep_images: bool = False,
    min_keypoints: int = 0,
) -> list[PlaceImage]:
    """Describe M photos taken at a place's centre, given in clockwise order.

    Parameters
    ----------
    paths : sequence of M paths
        Direction j looks along ``heading0 - j * 2 pi / M``.
    vocabulary : Vocabulary
    heading0 : float
        Map heading [rad] of direction 0.
    extractor : OrbExtractor, optional
    keep_images : bool
        Also store the pixels (PNG) in the database.
    min_keypoints : int
        Raise when an image has fewer ORB keypoints (it would never be recognised).

    Returns
    -------
    list of PlaceImage
    """
    if not paths:
        raise ConfigurationError("images: expected at least one image file")
    ext = extractor or OrbExtractor()
    heads = direction_headings(heading0, len(paths))
    out = []
    for j, p in enumerate(paths):
        img = read_image(p)
        check_photo_size(img, p, ext)
        feats = ext.extract(img)
        if len(feats) < min_keypoints:
            raise DataFormatError(
                f"{p}: only {len(feats)} ORB keypoints (< {min_keypoints}); "
                "a featureless view cannot be told apart from the others"
            )
        out.append(
            PlaceImage(
                j,
                float(heads[j]),
                feats,
                vocabulary.bow(feats.descriptors),
                img if keep_images else None,
            )
        )
    return out
