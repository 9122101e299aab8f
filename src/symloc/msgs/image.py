"""``sensor_msgs/Image`` and ``sensor_msgs/CompressedImage`` <-> RGB arrays.

symloc's camera images are ``(H, W, 3)`` uint8 RGB. Raw images in the encodings ``rgb8``,
``bgr8``, ``rgba8``, ``bgra8``, ``mono8`` / ``8UC1``, ``8UC3`` (taken as BGR, OpenCV's order),
``mono16`` / ``16UC1`` (scaled by 1/256) are read, honouring ``step`` (row padding) and
``is_bigendian``; any other encoding raises :class:`~symloc.errors.DataFormatError`.
Compressed images (PNG, JPEG; see :mod:`symloc.image_header`) are decoded with OpenCV.

Both refuse an image of more than ``max_pixels`` pixels (default :data:`MAX_IMAGE_PIXELS`)
before allocating or decoding it: raw images by ``height x width``, compressed ones by the size
their header declares.
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from symloc.errors import DataFormatError
from symloc.image_header import check_image_size, image_header
from symloc.msgs.fields import field
from symloc.msgs.header import header_fields

__all__ = [
    "MAX_IMAGE_PIXELS",
    "SUPPORTED_ENCODINGS",
    "compressed_image_from_msg",
    "compressed_image_to_fields",
    "image_from_msg",
    "image_to_fields",
]

# encoding -> (channels, bytes per channel)
SUPPORTED_ENCODINGS: dict[str, tuple[int, int]] = {
    "rgb8": (3, 1),
    "bgr8": (3, 1),
    "rgba8": (4, 1),
    "bgra8": (4, 1),
    "mono8": (1, 1),
    "8UC1": (1, 1),
    "8UC3": (3, 1),
    "mono16": (1, 2),
    "16UC1": (1, 2),
}

Image = NDArray[np.uint8]

#: Default bound on a camera image's pixels (5 MP; the node's ``max_image_pixels``).
MAX_IMAGE_PIXELS = 5_000_000


def _as_bytes(data: Any, where: str) -> NDArray[np.uint8]:
    if isinstance(data, (bytes, bytearray, memoryview)):
        return np.frombuffer(data, dtype=np.uint8)
    try:
        arr = np.asarray(data)
    except (TypeError, ValueError) as err:
        raise DataFormatError(f"{where}: expected bytes") from err
    if arr.dtype != np.uint8:
        try:
            arr = arr.astype(np.uint8)
        except (TypeError, ValueError) as err:
            raise DataFormatError(f"{where}: expected bytes") from err
    return arr.reshape(-1)


def image_from_msg(msg: Any, *, max_pixels: int = MAX_IMAGE_PIXELS) -> Image:
    """Convert a sensor_msgs/Image to ``(H, W, 3)`` uint8 RGB.

    Raises
    ------
    DataFormatError
        Unknown ``encoding``, zero size, more than ``max_pixels`` pixels, or ``data`` shorter
        than ``height x step``.
    """
    where = "Image"
    enc = str(field(msg, "encoding", where))
    if enc not in SUPPORTED_ENCODINGS:
        raise DataFormatError(
            f"{where}.encoding: unsupported encoding {enc!r}; expected one of"
            f" {sorted(SUPPORTED_ENCODINGS)}"
        )
    ch, depth = SUPPORTED_ENCODINGS[enc]
    try:
        h, w, step = (int(field(msg, k, where)) for k in ("height", "width", "step"))
    except (TypeError, ValueError, OverflowError) as err:
        raise DataFormatError(f"{where}.height/width/step: expected integers") from err
    if h <= 0 or w <= 0:
        raise DataFormatError(f"{where}.height/width: expected > 0, got {h}x{w}")
    if h * w > max_pixels:
        raise DataFormatError(
            f"{where}.height/width: {w} x {h} = {w * h:,} pixels; at most {max_pixels:,} allowed"
        )
    row = w * ch * depth
    if step < row:
        raise DataFormatError(f"{where}.step: expected >= width x {ch * depth} = {row}, got {step}")
    buf = _as_bytes(field(msg, "data", where), f"{where}.data")
    if buf.size < h * step:
        raise DataFormatError(
            f"{where}.data: expected height x step = {h * step} bytes, got {buf.size}"
        )
    rows = buf[: h * step].reshape(h, step)[:, :row]
    if depth == 2:
        big = bool(int(getattr(msg, "is_bigendian", 0)))
        px16 = rows.copy().view(">u2" if big else "<u2").reshape(h, w)
        gray = (px16 >> 8).astype(np.uint8)
        return np.repeat(gray[:, :, None], 3, axis=2)
    px = rows.reshape(h, w, ch)
    if ch == 1:
        return np.repeat(px, 3, axis=2)
    if enc in ("bgr8", "bgra8", "8UC3"):
        return np.ascontiguousarray(px[:, :, 2::-1])
    return np.ascontiguousarray(px[:, :, :3])


def compressed_image_from_msg(msg: Any, *, max_pixels: int = MAX_IMAGE_PIXELS) -> Image:
    """Decode a sensor_msgs/CompressedImage (PNG, JPEG) to ``(H, W, 3)`` uint8 RGB.

    Raises
    ------
    DataFormatError
        Empty data, a header that is not PNG or JPEG, more than ``max_pixels`` pixels declared,
        or data OpenCV cannot decode.
    """
    where = "CompressedImage"
    buf = _as_bytes(field(msg, "data", where), f"{where}.data")
    fmt = str(getattr(msg, "format", ""))
    if buf.size == 0:
        raise DataFormatError(f"{where}.data: empty (format {fmt!r})")
    head = image_header(buf[: 1 << 20].tobytes(), f"{where}.data")
    if head.format not in ("png", "jpeg"):
        raise DataFormatError(f"{where}.data: {head.format} image; expected PNG or JPEG")
    check_image_size(head, max_pixels, f"{where}.data")
    bgr = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    if bgr is None:
        raise DataFormatError(f"{where}.data: OpenCV could not decode it (format {fmt!r})")
    return np.ascontiguousarray(bgr[:, :, ::-1])


def _check_rgb(image: Any) -> Image:
    img = np.asarray(image)
    if img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
        raise DataFormatError(f"image: expected (H, W, 3) uint8 RGB, got {img.shape} {img.dtype}")
    return img


def image_to_fields(image: Any, *, stamp: float, frame_id: str = "camera") -> dict[str, Any]:
    """A sensor_msgs/Image field dict (``rgb8``) from ``(H, W, 3)`` uint8 RGB."""
    img = _check_rgb(image)
    h, w, _ = img.shape
    return {
        "header": header_fields(stamp, frame_id),
        "height": h,
        "width": w,
        "encoding": "rgb8",
        "is_bigendian": 0,
        "step": 3 * w,
        "data": np.ascontiguousarray(img).reshape(-1),
    }


def compressed_image_to_fields(
    image: Any, *, stamp: float, frame_id: str = "camera", fmt: str = "png"
) -> dict[str, Any]:
    """A sensor_msgs/CompressedImage field dict; ``fmt`` is ``png`` (lossless) or ``jpeg``."""
    img = _check_rgb(image)
    if fmt not in ("png", "jpeg"):
        raise DataFormatError(f"fmt: expected 'png' or 'jpeg', got {fmt!r}")
    ok, enc = cv2.imencode(".png" if fmt == "png" else ".jpg", img[:, :, ::-1])
    if not ok:
        raise DataFormatError(f"image: OpenCV could not encode it as {fmt}")
    return {
        "header": header_fields(stamp, frame_id),
        "format": f"rgb8; {fmt} compressed bgr8",
        "data": enc.reshape(-1),
    }
