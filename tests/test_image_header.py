"""Image sizes from headers: every format symloc decodes is bounded before decoding."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from symloc.errors import DataFormatError
from symloc.image_header import check_image_size, image_header


@pytest.mark.parametrize(
    ("ext", "fmt", "channels"),
    [
        (".png", "png", 3),
        (".png", "png", 1),
        (".jpg", "jpeg", 3),
        (".pgm", "pnm", 1),
        (".ppm", "pnm", 3),
        (".bmp", "bmp", 3),
        (".tif", "tiff", 3),
    ],
)
def test_header_size_matches_the_decoded_image(ext: str, fmt: str, channels: int) -> None:
    img = np.random.default_rng(0).integers(0, 255, (37, 53, channels), dtype=np.uint8)
    ok, enc = cv2.imencode(ext, img.squeeze())
    assert ok
    head = image_header(enc.tobytes(), "test")
    assert (head.format, head.width, head.height) == (fmt, 53, 37)


def test_16_bit_pgm_header() -> None:
    data = b"P5\n# a comment\n65535 65535\n65535\n" + b"\x00" * 10
    head = image_header(data, "m.pgm")
    assert (head.width, head.height) == (65535, 65535)
    with pytest.raises(DataFormatError, match=r"m\.pgm: pnm header declares 65535 x 65535"):
        check_image_size(head, 10_000_000, "m.pgm")


@pytest.mark.parametrize(
    ("data", "match"),
    [
        (b"GIF89a....", "not an image format"),
        (b"", "not an image format"),
        (b"\x89PNG\r\n\x1a\n\x00\x00", "PNG without an IHDR"),
        (b"\xff\xd8\xff\xe0\x00\x10JFIF", "JPEG without a frame header"),
        (b"\xff\xd8\x00\x00\x00\x00", "JPEG marker expected"),
        (b"P5\n12", "PNM header without width and height"),
        (b"P5\n12345678901 2\n255\n", "11-digit size"),
        (b"II*\x00\xff\xff\x00\x00", "TIFF directory beyond"),
    ],
)
def test_bad_headers_name_the_input(data: bytes, match: str) -> None:
    with pytest.raises(DataFormatError, match=match):
        image_header(data, "where")


def test_zero_size_is_refused() -> None:
    head = image_header(b"P5 0 10 255\n", "z.pgm")
    with pytest.raises(DataFormatError, match="declares 0 x 10"):
        check_image_size(head, 100, "z.pgm")
