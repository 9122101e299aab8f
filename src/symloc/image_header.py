"""Image sizes read from file headers, so an image is bounded before it is decoded.

A 249 KB PNG can declare 16000 x 16000 pixels and cost gigabytes once decoded. Every image
symloc decodes (map files, photos, camera messages) first goes through :func:`image_header`,
which reads the declared width and height from the first bytes (PNG ``IHDR``, JPEG ``SOFn``,
PNM ``P1``-``P6``, BMP, TIFF), and :func:`check_image_size`, which refuses more pixels than
allowed. A format whose header is not read here is refused rather than decoded blind.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import DataFormatError

__all__ = [
    "HEADER_FORMATS",
    "MAX_PHOTO_PIXELS",
    "ImageHeader",
    "check_image_size",
    "image_header",
    "read_image_file",
]

#: The formats whose header :func:`image_header` reads.
HEADER_FORMATS = ("PNG", "JPEG", "PNM (PGM/PPM/PBM)", "BMP", "TIFF")

# JPEG start-of-frame markers (baseline, progressive, lossless, arithmetic); not C4/C8/CC
_SOF = {0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF}


@dataclass(frozen=True, slots=True)
class ImageHeader:
    """``format`` (``png``, ``jpeg``, ``pnm``, ``bmp``, ``tiff``), ``width``, ``height`` [px]."""

    format: str
    width: int
    height: int

    @property
    def pixels(self) -> int:
        """``width x height``."""
        return self.width * self.height


def _png(data: bytes, where: str) -> ImageHeader:
    if len(data) < 24 or data[12:16] != b"IHDR":
        raise DataFormatError(f"{where}: PNG without an IHDR header (truncated or corrupt)")
    w, h = struct.unpack(">II", data[16:24])
    return ImageHeader("png", w, h)


def _jpeg(data: bytes, where: str) -> ImageHeader:
    i, n = 2, len(data)
    while i + 4 <= n:
        if data[i] != 0xFF:
            raise DataFormatError(f"{where}: JPEG marker expected at byte {i} (corrupt)")
        marker = data[i + 1]
        if marker == 0xFF:  # fill byte
            i += 1
            continue
        if marker in (0x01, *range(0xD0, 0xD8)):  # TEM, RSTn: no length
            i += 2
            continue
        if marker in (0xD9, 0xDA):  # end of image or start of scan before any frame header
            break
        (length,) = struct.unpack(">H", data[i + 2 : i + 4])
        if length < 2:
            raise DataFormatError(f"{where}: JPEG segment of length {length} at byte {i}")
        if marker in _SOF:
            if i + 9 > n:
                break
            h, w = struct.unpack(">HH", data[i + 5 : i + 9])
            return ImageHeader("jpeg", w, h)
        i += 2 + length
    raise DataFormatError(f"{where}: JPEG without a frame header (truncated or corrupt)")


def _pnm(data: bytes, where: str) -> ImageHeader:
    fields: list[int] = []
    i, n = 2, min(len(data), 4096)
    while len(fields) < 2 and i < n:
        c = data[i : i + 1]
        if c == b"#":
            while i < n and data[i : i + 1] not in (b"\n", b"\r"):
                i += 1
        elif c.isdigit():
            j = i
            while j < n and data[j : j + 1].isdigit():
                j += 1
            if j - i > 10:
                raise DataFormatError(f"{where}: PNM header with a {j - i}-digit size")
            fields.append(int(data[i:j]))
            i = j
            continue
        elif not c.isspace():
            raise DataFormatError(f"{where}: PNM header: unexpected byte {c!r} at {i}")
        i += 1
    if len(fields) < 2:
        raise DataFormatError(f"{where}: PNM header without width and height (truncated)")
    return ImageHeader("pnm", fields[0], fields[1])


def _bmp(data: bytes, where: str) -> ImageHeader:
    if len(data) < 26:
        raise DataFormatError(f"{where}: BMP header truncated")
    (size,) = struct.unpack("<I", data[14:18])
    if size == 12:
        w, h = struct.unpack("<HH", data[18:22])
    else:
        w, h = struct.unpack("<ii", data[18:26])
    return ImageHeader("bmp", abs(w), abs(h))


def _tiff(data: bytes, where: str) -> ImageHeader:
    end = "<" if data[:2] == b"II" else ">"
    if len(data) < 8:
        raise DataFormatError(f"{where}: TIFF header truncated")
    (ifd,) = struct.unpack(end + "I", data[4:8])
    if ifd + 2 > len(data):
        raise DataFormatError(f"{where}: TIFF directory beyond the header bytes read")
    (count,) = struct.unpack(end + "H", data[ifd : ifd + 2])
    size: dict[int, int] = {}
    for k in range(count):
        at = ifd + 2 + 12 * k
        if at + 12 > len(data):
            break
        tag, typ = struct.unpack(end + "HH", data[at : at + 4])
        if tag in (256, 257):
            fmt = "H" if typ == 3 else "I"
            (size[tag],) = struct.unpack(end + fmt, data[at + 8 : at + 8 + struct.calcsize(fmt)])
    if 256 not in size or 257 not in size:
        raise DataFormatError(f"{where}: TIFF without ImageWidth / ImageLength tags")
    return ImageHeader("tiff", size[256], size[257])


def image_header(data: bytes | bytearray | memoryview, where: str) -> ImageHeader:
    """The format and declared size of the encoded image in ``data`` (its first bytes suffice:
    PNG 24, PNM a few dozen, JPEG up to its frame header).

    Raises
    ------
    DataFormatError
        Not one of :data:`HEADER_FORMATS`, or a truncated / corrupt header; ``where`` names the
        file or message field in the message.
    """
    b = bytes(data[:65536]) if not isinstance(data, bytes) else data
    if b[:8] == b"\x89PNG\r\n\x1a\n":
        return _png(b, where)
    if b[:2] == b"\xff\xd8":
        return _jpeg(b, where)
    if len(b) >= 2 and b[:1] == b"P" and b[1:2] in b"123456":
        return _pnm(b, where)
    if b[:2] == b"BM":
        return _bmp(b, where)
    if b[:4] in (b"II*\x00", b"MM\x00*"):
        return _tiff(b, where)
    raise DataFormatError(
        f"{where}: not an image format whose size can be read before decoding"
        f" (expected {', '.join(HEADER_FORMATS)})"
    )


def check_image_size(header: ImageHeader, max_pixels: int, where: str) -> ImageHeader:
    """Refuse an empty image or one of more than ``max_pixels`` pixels; returns ``header``."""
    if header.width <= 0 or header.height <= 0:
        raise DataFormatError(
            f"{where}: {header.format} header declares {header.width} x {header.height} pixels"
        )
    if header.pixels > max_pixels:
        raise DataFormatError(
            f"{where}: {header.format} header declares {header.width} x {header.height}"
            f" = {header.pixels:,} pixels; at most {max_pixels:,} allowed"
        )
    return header


#: Default bound on a photo's pixels (50 MP: larger than phone cameras' full resolution).
MAX_PHOTO_PIXELS = 50_000_000


def read_image_file(
    path: str | Path, *, max_pixels: int = MAX_PHOTO_PIXELS, flags: int | None = None
) -> NDArray[Any]:
    """Decode an image file with OpenCV after bounding it by its header.

    ``flags`` are ``cv2.imread`` flags (default ``IMREAD_UNCHANGED``). The file's size and its
    declared pixels are checked before anything is decoded.

    Raises
    ------
    DataFormatError
        Missing or unreadable file, a header not in :data:`HEADER_FORMATS`, more than
        ``max_pixels`` pixels, or data OpenCV cannot decode; the message names the file.
    """
    import cv2

    from symloc.files.bounded import read_bytes_bounded

    p = Path(path)
    # a regular file (a FIFO would block) no larger than any image of max_pixels needs
    raw = read_bytes_bounded(
        p, 8 * max_pixels + (1 << 20), what="the image file", error=DataFormatError
    )
    check_image_size(image_header(raw, str(p)), max_pixels, str(p))
    img = cv2.imdecode(
        np.frombuffer(raw, np.uint8), cv2.IMREAD_UNCHANGED if flags is None else flags
    )
    if img is None or img.size == 0:
        raise DataFormatError(f"{p}: OpenCV cannot decode it (truncated or corrupt)")
    return np.asarray(img)
