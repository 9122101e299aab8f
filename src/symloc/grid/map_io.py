"""ROS map_server / nav2_map_server map files: a YAML description plus a PGM/PNG image.

YAML keys (as map_server reads them): ``image`` (path, relative to the YAML's folder),
``resolution`` [m/pixel], ``origin`` ``[x, y, yaw]`` (pose of the lower-left pixel's corner),
``occupied_thresh``, ``free_thresh`` (fractions), ``negate`` (0/1 or bool) and optional
``mode`` (``trinary`` default, ``scale``, ``raw``).

Loading, as nav2_map_server's ``loadMapFromFile``: a pixel's ``shade`` is the mean of its colour
channels over 255 (in trinary mode an alpha channel is averaged in too); its occupancy is
``occ = 1 - shade`` (``shade`` with ``negate``);

- trinary: ``occ > occupied_thresh`` -> 100, ``occ < free_thresh`` -> 0, otherwise -1;
- scale: a transparent pixel -> -1, then as trinary, except that values between the thresholds
  become ``rint(100 (occ - free) / (occupied - free))``;
- raw: ``v = round(255 shade)``; 0..100 -> v, otherwise -1.

The image's top row is the map's last row (row 0 of the grid is at the origin).

Bounds, checked before anything is allocated: ``resolution`` within
:data:`~symloc.grid.occupancy_grid.MIN_RESOLUTION` .. ``MAX_RESOLUTION``, ``origin`` within
``MAX_ORIGIN``; the image's size is read from its header (:mod:`symloc.image_header`: PGM, PNG,
BMP, JPEG, TIFF) and refused above ``max_pixels`` (default :data:`MAX_MAP_PIXELS`) before it is
decoded; the conversion to occupancy works in blocks of rows, so its temporaries stay small.

Saving, as nav2's ``map_saver``: trinary writes 254 (free, ``<= rint(100 free_thresh)``),
0 (occupied, ``>= rint(100 occupied_thresh)``) and 205 (unknown); scale writes
``255 (100 - v) / 100`` with unknown cells transparent (RGBA PNG); raw writes ``v`` and
255 for unknown. A trinary map or any map in raw mode round-trips exactly.

Saving is crash-safe: a reader (or a process killed mid-save) sees the old map or the new one,
never a torn pair. Each save draws a *write id* (8 hex digits) and writes

1. the image as ``<stem>.<write id>.pgm`` (or ``.png``), a name no other save uses, atomically
   (:mod:`symloc.files.atomic`: a temporary file, fsync, rename);
2. the YAML last, atomically, naming that image and recording ``write_id: <write id>``;
3. then removes the image the previous YAML named (when it is one of this map's own images,
   ``<stem>.pgm`` or ``<stem>.<8 hex>.pgm``) and images of saves killed before their YAML
   (after :data:`~symloc.files.atomic.STALE_SECONDS`).

The write id is also stored inside the image (a PGM header comment ``# symloc write_id=<id>``
on the second line; a PNG ``tEXt`` chunk ``symloc_write_id`` right after ``IHDR``). A reader
that finds a YAML whose ``write_id`` differs from the one in its image, or whose ``width`` /
``height`` differ from the image's, refuses the pair with :class:`~symloc.errors.MapFileError`.
An image without a write id (another tool's, or one edited by hand) is accepted as it is.
``write_id`` is not a map_server key; map_server ignores it.
"""

from __future__ import annotations

import contextlib
import logging
import math
import re
import secrets
import stat
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml
from numpy.typing import NDArray

from symloc.errors import ConfigurationError, DataFormatError, MapFileError
from symloc.files.atomic import (
    STALE_SECONDS,
    atomic_write_bytes,
    atomic_write_text,
    remove_stale_temporaries,
    temporary_target,
)
from symloc.files.bounded import load_yaml_bounded, read_text_bounded
from symloc.grid.map_error_field import MapErrorField
from symloc.grid.occupancy_grid import MAX_ORIGIN, MAX_RESOLUTION, MIN_RESOLUTION, OccupancyGrid
from symloc.image_header import check_image_size, image_header

__all__ = [
    "MAP_MODES",
    "MAX_MAP_PIXELS",
    "MapMetadata",
    "grid_to_image",
    "image_to_grid",
    "load_map",
    "read_map_yaml",
    "save_map",
]

MAP_MODES = ("trinary", "scale", "raw")
#: Default bound on a map image's pixels (64 Mi: 8192 x 8192 cells, 410 m square at 5 cm).
MAX_MAP_PIXELS = 64 * 2**20
_BLOCK_PIXELS = 1 << 20  # pixels converted at a time by image_to_grid
_MAX_YAML_BYTES = 1 << 20
_NAME_MAX = 255  # bytes in one file name (Linux NAME_MAX)
log = logging.getLogger(__name__)
_WRITE_ID = re.compile(r"[0-9a-f]{8}")
_PGM_ID = re.compile(rb"P[25]\n# symloc write_id=([0-9a-f]{8})\n")
_PNG_ID_KEY = b"symloc_write_id\x00"


@dataclass(frozen=True, slots=True)
class MapMetadata:
    """The fields of a map YAML file, validated.

    Attributes
    ----------
    image : Path
        Image path (resolved against the YAML's folder).
    resolution : float
        Metres per pixel, > 0.
    origin : tuple of 3 floats
        x [m], y [m], yaw [rad] of the lower-left pixel's outer corner.
    occupied_thresh, free_thresh : float
        ``0 <= free_thresh < occupied_thresh <= 1``.
    negate : bool
    mode : str
        ``trinary``, ``scale`` or ``raw``.
    width, height : int or None
        Optional image size in pixels (not a map_server key; checked against the image when
        present).
    map_std_xy : float or None
        The map's own position error [m] (std) as the SLAM that built it estimated it
        (``symloc_slam: {map_error: {std_xy: ...}}``, written by ``symloc map build``; not a
        map_server key). None when the file does not say.
    map_error_field : MapErrorField or None
        The map's position error place by place (``symloc_slam: {map_error: {field: [[x, y,
        cov_xx, cov_xy, cov_yy], ...]}}``, :mod:`symloc.grid.map_error_field`). None when the
        file does not say.
    """

    image: Path
    resolution: float
    origin: tuple[float, float, float]
    occupied_thresh: float
    free_thresh: float
    negate: bool = False
    mode: str = "trinary"
    width: int | None = None
    height: int | None = None
    write_id: str | None = None
    map_std_xy: float | None = None
    map_error_field: MapErrorField | None = None


_FLOAT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


def _as_number(value: Any) -> float | None:
    """A YAML number; PyYAML (YAML 1.1) reads ``1e-3`` as a string, yaml-cpp as a number."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str) and _FLOAT.fullmatch(value.strip()):
        return float(value)
    return None


def _number(doc: dict[str, Any], key: str, path: Path) -> float:
    if key not in doc:
        raise MapFileError(f"{path}: missing required field '{key}'")
    value = doc[key]
    out_or_none = _as_number(value)
    if out_or_none is None:
        raise MapFileError(f"{path}: field '{key}' must be a number, got {value!r}")
    out = out_or_none
    if not math.isfinite(out):
        raise MapFileError(f"{path}: field '{key}' must be finite, got {value!r}")
    return out


def _check_thresholds(occupied: float, free: float, where: str) -> None:
    if not 0.0 <= free <= 1.0:
        raise MapFileError(f"{where}: field 'free_thresh' must be in [0, 1], got {free}")
    if not 0.0 <= occupied <= 1.0:
        raise MapFileError(f"{where}: field 'occupied_thresh' must be in [0, 1], got {occupied}")
    if not free < occupied:
        raise MapFileError(
            f"{where}: field 'free_thresh' ({free}) must be smaller than 'occupied_thresh'"
            f" ({occupied})"
        )


def read_map_yaml(path: str | Path) -> MapMetadata:
    """Parse and validate a map YAML file.

    Raises
    ------
    MapFileError
        The file is missing, is not YAML, lacks a field or has a field of the wrong type or
        range; the message names the field.
    """
    p = Path(path)
    # a regular file of at most _MAX_YAML_BYTES (a map YAML is a few lines), bounded nesting
    text = read_text_bounded(p, _MAX_YAML_BYTES, what="map YAML", error=MapFileError)
    doc = load_yaml_bounded(text, where=str(p), error=MapFileError)
    if not isinstance(doc, dict):
        raise MapFileError(f"{p}: expected a YAML mapping with the map fields, got {type(doc)}")
    if "image" not in doc:
        raise MapFileError(f"{p}: missing required field 'image'")
    image = doc["image"]
    if not isinstance(image, str) or not image.strip():
        raise MapFileError(f"{p}: field 'image' must be a non-empty file name, got {image!r}")
    if "\x00" in image or any(len(part.encode()) > _NAME_MAX for part in Path(image).parts):
        shown = image if len(image) <= 60 else f"{image[:40]!r}... ({len(image)} characters)"
        raise MapFileError(
            f"{p}: field 'image' must be a file name of at most {_NAME_MAX} bytes per path"
            f" component and no NUL byte, got {shown}"
        )
    resolution = _number(doc, "resolution", p)
    if not MIN_RESOLUTION <= resolution <= MAX_RESOLUTION:
        raise MapFileError(
            f"{p}: field 'resolution' must be {MIN_RESOLUTION:g}..{MAX_RESOLUTION:g} m/pixel,"
            f" got {resolution}"
        )
    if "origin" not in doc:
        raise MapFileError(f"{p}: missing required field 'origin'")
    origin = doc["origin"]
    values = [_as_number(v) for v in origin] if isinstance(origin, (list, tuple)) else []
    if (
        len(values) != 3
        or any(v is None for v in values)
        or not all(math.isfinite(v) for v in values if v is not None)
    ):
        raise MapFileError(
            f"{p}: field 'origin' must be 3 finite numbers [x, y, yaw], got {origin!r}"
        )
    ox, oy, oyaw = (float(v) for v in values if v is not None)
    if max(abs(ox), abs(oy)) > MAX_ORIGIN:
        raise MapFileError(
            f"{p}: field 'origin' must have |x|, |y| <= {MAX_ORIGIN:g} m, got {origin!r}"
        )
    occupied = _number(doc, "occupied_thresh", p)
    free = _number(doc, "free_thresh", p)
    _check_thresholds(occupied, free, str(p))
    negate_raw = doc.get("negate", 0)
    if isinstance(negate_raw, bool):
        negate = negate_raw
    elif isinstance(negate_raw, int) and negate_raw in (0, 1):
        negate = bool(negate_raw)
    else:
        raise MapFileError(f"{p}: field 'negate' must be 0, 1, true or false, got {negate_raw!r}")
    mode = doc.get("mode", "trinary")
    if not isinstance(mode, str) or mode.lower() not in MAP_MODES:
        raise MapFileError(f"{p}: field 'mode' must be one of {MAP_MODES}, got {mode!r}")
    size: dict[str, int | None] = {}
    for key in ("width", "height"):
        v = doc.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v <= 0):
            raise MapFileError(f"{p}: field '{key}' must be a positive integer, got {v!r}")
        size[key] = v
    write_id = doc.get("write_id")
    if write_id is not None and not (isinstance(write_id, str) and _WRITE_ID.fullmatch(write_id)):
        raise MapFileError(f"{p}: field 'write_id' must be 8 hex digits, got {write_id!r}")
    img = Path(image)
    if not img.is_absolute():
        img = p.parent / img
    map_std_xy, field = _map_error(doc, p)
    return MapMetadata(
        image=img,
        resolution=resolution,
        origin=(ox, oy, oyaw),
        occupied_thresh=occupied,
        free_thresh=free,
        negate=negate,
        mode=mode.lower(),
        width=size["width"],
        height=size["height"],
        write_id=write_id,
        map_std_xy=map_std_xy,
        map_error_field=field,
    )


#: The largest map error [m] a map file may declare (a map off by more is not a map).
_MAX_MAP_STD = 1.0


def _map_error(doc: dict[str, Any], path: Path) -> tuple[float | None, MapErrorField | None]:
    """``symloc_slam.map_error.std_xy`` [m] and ``.field`` of a map YAML ``doc`` (None each
    when absent)."""
    slam = doc.get("symloc_slam")
    if slam is None:
        return None, None
    err = slam.get("map_error") if isinstance(slam, dict) else None
    if err is None:
        return None, None
    if not isinstance(err, dict):
        raise MapFileError(
            f"{path}: field 'symloc_slam.map_error' must be a mapping with 'std_xy' and/or"
            f" 'field', got {err!r}"
        )
    field = None
    if err.get("field") is not None:
        try:
            field = MapErrorField.from_rows(
                err["field"], f"{path}: field 'symloc_slam.map_error.field'"
            )
        except ConfigurationError as exc:
            raise MapFileError(str(exc)) from None
    if err.get("std_xy") is None and field is not None:
        return None, field
    value = _as_number(err.get("std_xy"))
    if value is None or not math.isfinite(value) or not 0.0 <= value <= _MAX_MAP_STD:
        raise MapFileError(
            f"{path}: field 'symloc_slam.map_error.std_xy' must be a number of metres in"
            f" 0..{_MAX_MAP_STD:g}, got {err.get('std_xy')!r}"
        )
    return float(value), field


def image_to_grid(image: NDArray[Any], meta: MapMetadata) -> NDArray[np.int8]:
    """Convert an image as ``cv2.imread(..., IMREAD_UNCHANGED)`` returns it to grid data.

    Parameters
    ----------
    image : ndarray of shape (H, W), (H, W, 3) or (H, W, 4), uint8 or uint16
        Grey, BGR or BGRA pixels; the top row is the map's last row.
    meta : MapMetadata

    Returns
    -------
    ndarray of shape (H, W), int8
        Occupancy data with row 0 at the origin.
    """
    img = np.asarray(image)
    if img.ndim not in (2, 3) or (img.ndim == 3 and img.shape[2] not in (1, 2, 3, 4)):
        raise MapFileError(f"{meta.image}: expected a grey, BGR or BGRA image, got {img.shape}")
    h = img.shape[0]
    out = np.empty(img.shape[:2], dtype=np.int8)
    rows = max(1, _BLOCK_PIXELS // max(1, img.shape[1]))
    for r0 in range(0, h, rows):
        r1 = min(h, r0 + rows)
        # image row r is grid row h - 1 - r (the image's top row is the map's last row)
        out[h - r1 : h - r0] = _pixels_to_occupancy(img[r0:r1], meta)[::-1]
    return out


def _pixels_to_occupancy(img: NDArray[Any], meta: MapMetadata) -> NDArray[np.int8]:
    """Occupancy of a block of image rows (see :func:`image_to_grid`)."""
    scale = 65535.0 if img.dtype == np.uint16 else 255.0
    x = img.astype(np.float64) / scale
    alpha = None
    if x.ndim == 3:
        if x.shape[2] == 4:
            alpha = x[:, :, 3]
            colour = x[:, :, :3]
        else:
            colour = x[:, :, :3]
        channels = [colour[:, :, k] for k in range(colour.shape[2])]
    else:
        channels = [x]
    if meta.mode == "trinary" and alpha is not None:
        channels.append(alpha)
    shade = np.mean(np.stack(channels, axis=0), axis=0)
    occ = shade if meta.negate else 1.0 - shade
    out = np.full(shade.shape, -1, dtype=np.int8)
    if meta.mode == "raw":
        v = np.round(shade * 255.0)
        ok = (v >= 0) & (v <= 100)
        out[ok] = v[ok].astype(np.int8)
    else:
        occupied = occ > meta.occupied_thresh
        free = occ < meta.free_thresh
        out[occupied] = 100
        out[free] = 0
        if meta.mode == "scale":
            mid = ~(occupied | free)
            ratio = (occ - meta.free_thresh) / (meta.occupied_thresh - meta.free_thresh)
            out[mid] = np.rint(ratio[mid] * 100.0).astype(np.int8)
            if alpha is not None:
                out[alpha < 1.0] = -1
    return out


def grid_to_image(
    grid: OccupancyGrid,
    mode: str = "trinary",
    *,
    free_thresh: float | None = None,
    occupied_thresh: float | None = None,
) -> NDArray[np.uint8]:
    """Pixels for ``grid`` as nav2's map_saver writes them (top row = last grid row).

    Returns ``(H, W)`` uint8 for trinary and raw, ``(H, W, 4)`` BGRA for scale.
    """
    if mode not in MAP_MODES:
        raise MapFileError(f"mode: expected one of {MAP_MODES}, got {mode!r}")
    free = grid.free_thresh if free_thresh is None else float(free_thresh)
    occ = grid.occupied_thresh if occupied_thresh is None else float(occupied_thresh)
    _check_thresholds(occ, free, "save_map")
    d = grid.data[::-1].astype(np.int16)
    unknown = (d < 0) | (d > 100)
    if mode == "trinary":
        free_i = int(np.rint(free * 100.0))
        occ_i = int(np.rint(occ * 100.0))
        img = np.full(d.shape, 205, dtype=np.uint8)
        img[~unknown & (d <= free_i)] = 254
        img[~unknown & (d >= occ_i) & ~(d <= free_i)] = 0
        return img
    if mode == "raw":
        return np.where(unknown, 255, d).astype(np.uint8)
    grey = np.rint(255.0 * (100.0 - np.clip(d, 0, 100)) / 100.0).astype(np.uint8)
    grey[unknown] = 128
    alpha = np.where(unknown, 0, 255).astype(np.uint8)
    return np.dstack([grey, grey, grey, alpha])


def load_map(path: str | Path, *, max_pixels: int = MAX_MAP_PIXELS) -> OccupancyGrid:
    """Load a map_server map (YAML + image) as an :class:`OccupancyGrid`.

    Parameters
    ----------
    path : str or Path
        The map YAML.
    max_pixels : int
        Largest image (pixels) accepted; its size is read from the header before decoding.

    Raises
    ------
    MapFileError
        Malformed YAML or field (named), missing, unreadable or oversized image, or an image
        that does not belong to the YAML: its size disagrees with the YAML's optional
        ``width``/``height``, or its write id with the YAML's ``write_id``.
    """
    meta, raw = _read_pair(Path(path), max_pixels)
    where = f"{path}: field 'image' ({meta.image})"
    try:
        head = check_image_size(image_header(raw, where), max_pixels, where)
    except DataFormatError as err:
        raise MapFileError(str(err)) from err
    image_id = _image_write_id(raw)
    if meta.write_id is not None and image_id is not None and image_id != meta.write_id:
        raise MapFileError(
            f"{path}: field 'write_id' is {meta.write_id}, but image {meta.image.name} was"
            f" written by save {image_id}: the YAML and the image do not belong together"
        )
    img = cv2.imdecode(np.frombuffer(raw, np.uint8), cv2.IMREAD_UNCHANGED)
    del raw
    if img is None or img.size == 0:
        raise MapFileError(f"{path}: field 'image': cannot decode image {meta.image}")
    h, w = img.shape[:2]
    if (w, h) != (head.width, head.height):
        raise MapFileError(
            f"{where}: decoded {w} x {h} pixels, its header declared"
            f" {head.width} x {head.height} (corrupt)"
        )
    for key, want, got in (("width", meta.width, w), ("height", meta.height, h)):
        if want is not None and want != got:
            raise MapFileError(
                f"{path}: field '{key}' is {want} pixels but image {meta.image.name} is {got}:"
                " the YAML and the image do not belong together"
            )
    data = image_to_grid(img, meta)
    return OccupancyGrid(
        data,
        meta.resolution,
        np.array(meta.origin),
        meta.occupied_thresh,
        meta.free_thresh,
    )


def _read_pair(path: Path, max_pixels: int) -> tuple[MapMetadata, bytes]:
    """The YAML's fields and its image's bytes.

    A save running meanwhile may replace the YAML and remove the image the old YAML named;
    then the YAML is read again (a few times) rather than failing on the vanished image.
    """
    # a raw 16-bit RGBA image of max_pixels is the largest a bounded image can be
    max_bytes = 8 * max_pixels + (1 << 20)
    attempts = 3
    for attempt in range(attempts):
        meta = read_map_yaml(path)
        where = f"{path}: field 'image' ({meta.image})"
        try:
            st = meta.image.stat()
            if not stat.S_ISREG(st.st_mode):
                raise MapFileError(f"{where}: not a regular file")
            if st.st_size > max_bytes:
                raise MapFileError(
                    f"{where}: {st.st_size:,} bytes, more than any image of at most"
                    f" {max_pixels:,} pixels needs"
                )
            with meta.image.open("rb") as fh:
                # a regular file: its size bounds the read (more only if it grows meanwhile)
                raw = fh.read(min(st.st_size, max_bytes) + 1)
        except FileNotFoundError:
            if attempt + 1 < attempts and read_map_yaml(path).image != meta.image:
                continue  # replaced by a save meanwhile: read the new pair
            raise MapFileError(f"{path}: field 'image': file not found: {meta.image}") from None
        except OSError as err:
            raise MapFileError(f"{where}: cannot read ({err.strerror})") from err
        if len(raw) > max_bytes:
            raise MapFileError(
                f"{where}: more than {max_bytes:,} bytes, more than any image of at most"
                f" {max_pixels:,} pixels needs"
            )
        return meta, raw
    raise AssertionError("unreachable")  # pragma: no cover


def _image_write_id(raw: bytes) -> str | None:
    """The write id :func:`save_map` stored in an image, or None (another tool's image)."""
    m = _PGM_ID.match(raw[:32])
    if m is not None:
        return m.group(1).decode()
    # PNG: the tEXt chunk save_map puts right after IHDR (8 + 25 bytes)
    if raw[:8] == b"\x89PNG\r\n\x1a\n" and raw[37:41] == b"tEXt":
        (n,) = struct.unpack(">I", raw[33:37])
        text = raw[41 : 41 + n]
        if text.startswith(_PNG_ID_KEY):
            value = text[len(_PNG_ID_KEY) :].decode("latin-1")
            if _WRITE_ID.fullmatch(value):
                return value
    return None


def _encode_image(img: NDArray[np.uint8], fmt: str, write_id: str) -> bytes:
    """The image file's bytes, with ``write_id`` stored in it (see the module docstring)."""
    if fmt == "pgm":
        if img.ndim != 2:
            raise MapFileError(f"image_format: pgm needs a grey image, got shape {img.shape}")
        h, w = img.shape
        head = f"P5\n# symloc write_id={write_id}\n{w} {h}\n255\n".encode()
        return head + np.ascontiguousarray(img).tobytes()
    ok, buf = cv2.imencode(".png", img)
    if not ok:
        raise MapFileError(f"cannot encode a {img.shape} image as png")
    png = buf.tobytes()
    text = _PNG_ID_KEY + write_id.encode()
    chunk = struct.pack(">I", len(text)) + b"tEXt" + text
    chunk += struct.pack(">I", zlib.crc32(b"tEXt" + text) & 0xFFFFFFFF)
    return png[:33] + chunk + png[33:]


def _own_image(name: str, stem: str) -> bool:
    """Whether ``name`` is one of the images save_map writes for ``stem``."""
    for fmt in ("pgm", "png"):
        if name == f"{stem}.{fmt}":
            return True
        rest = name[len(stem) + 1 : -(len(fmt) + 1)]
        if (
            name.startswith(stem + ".")
            and name.endswith("." + fmt)
            and _WRITE_ID.fullmatch(rest) is not None
        ):
            return True
    return False


def save_map(
    grid: OccupancyGrid,
    path: str | Path,
    *,
    mode: str = "trinary",
    image_format: str | None = None,
    free_thresh: float | None = None,
    occupied_thresh: float | None = None,
    write_size: bool = True,
    extra: dict[str, Any] | None = None,
) -> Path:
    """Write ``grid`` as ``<stem>.yaml`` + ``<stem>.<write id>.pgm`` (``.png`` for scale).

    Crash-safe (see the module docstring): the image first, under a name unique to this save,
    then the YAML that names it, each atomically; then the previous save's image is removed.

    Parameters
    ----------
    grid : OccupancyGrid
    path : str or Path
        The YAML path or its stem (``maps/lab`` -> ``maps/lab.yaml`` + ``maps/lab.<id>.pgm``).
    mode : str
        ``trinary``, ``scale`` or ``raw``.
    image_format : str, optional
        ``pgm`` or ``png`` (default ``pgm``, ``png`` for scale, which needs transparency).
    free_thresh, occupied_thresh : float, optional
        Written thresholds (default: the grid's).
    write_size : bool
        Also write ``width`` and ``height`` (ignored by map_server, checked by :func:`load_map`).
    extra : dict, optional
        More top-level YAML keys (plain data), e.g. how the map was made and whether it is
        doubtful; map_server and :func:`load_map` ignore keys they do not know.

    Returns
    -------
    Path
        The YAML file written (:func:`read_map_yaml` names its image).
    """
    if mode not in MAP_MODES:
        raise MapFileError(f"mode: expected one of {MAP_MODES}, got {mode!r}")
    fmt = image_format or ("png" if mode == "scale" else "pgm")
    if fmt not in ("pgm", "png"):
        raise MapFileError(f"image_format: expected 'pgm' or 'png', got {fmt!r}")
    if mode == "scale" and fmt != "png":
        raise MapFileError("image_format: mode 'scale' needs transparency, use 'png'")
    p = Path(path)
    stem = p.with_suffix("") if p.suffix in (".yaml", ".yml") else p
    if extra and {"image", "write_id", "width", "height"} & set(extra):
        raise MapFileError(f"extra: keys {sorted(extra)} would override the map's own fields")
    free = grid.free_thresh if free_thresh is None else float(free_thresh)
    occ = grid.occupied_thresh if occupied_thresh is None else float(occupied_thresh)
    img = grid_to_image(grid, mode, free_thresh=free, occupied_thresh=occ)
    stem.parent.mkdir(parents=True, exist_ok=True)
    yaml_path = stem.with_name(stem.name + ".yaml")
    previous: Path | None = None
    with contextlib.suppress(MapFileError):
        previous = read_map_yaml(yaml_path).image
    write_id = secrets.token_hex(4)
    image_path = stem.with_name(f"{stem.name}.{write_id}.{fmt}")
    while image_path.exists() or image_path == previous:
        write_id = secrets.token_hex(4)
        image_path = stem.with_name(f"{stem.name}.{write_id}.{fmt}")
    try:
        atomic_write_bytes(image_path, _encode_image(img, fmt, write_id))
    except OSError as err:
        raise MapFileError(f"{image_path}: cannot write image ({err.strerror})") from err
    o = grid.origin
    lines = [
        f"image: {image_path.name}",
        f"write_id: '{write_id}'",
        f"mode: {mode}",
        f"resolution: {_yaml_float(grid.resolution)}",
        f"origin: [{_yaml_float(o[0])}, {_yaml_float(o[1])}, {_yaml_float(o[2])}]",
        "negate: 0",
        f"occupied_thresh: {_yaml_float(occ)}",
        f"free_thresh: {_yaml_float(free)}",
    ]
    if write_size:
        lines += [f"width: {grid.width}", f"height: {grid.height}"]
    text = "\n".join(lines) + "\n"
    if extra:
        text += yaml.safe_dump(dict(extra), sort_keys=False, default_flow_style=False)
    try:
        atomic_write_text(yaml_path, text)
    except OSError as err:
        with contextlib.suppress(OSError):
            image_path.unlink()
        raise MapFileError(f"{yaml_path}: cannot write map YAML ({err.strerror})") from err
    _remove_replaced(stem, yaml_path, image_path, previous)
    return yaml_path


def _remove_replaced(stem: Path, yaml_path: Path, image: Path, previous: Path | None) -> None:
    """Remove the image the replaced YAML named, and this map's abandoned images and
    temporary files (of saves killed before their YAML; older than STALE_SECONDS)."""
    if (
        previous is not None
        and previous != image
        and previous.parent == stem.parent
        and _own_image(previous.name, stem.name)
    ):
        with contextlib.suppress(OSError):
            previous.unlink()
            log.debug("%s: removed the replaced image %s", yaml_path, previous.name)

    def abandoned(candidate: Path) -> bool:
        target = temporary_target(candidate.name)  # a temporary file: the image it was for
        name = candidate.name if target is None else target
        return (
            candidate != image
            and _own_image(name, stem.name)
            and (target is not None or name not in (f"{stem.name}.pgm", f"{stem.name}.png"))
        )

    remove_stale_temporaries(yaml_path, older_than=STALE_SECONDS, extra=abandoned)


def _yaml_float(value: float) -> str:
    """``repr`` of a finite float that YAML 1.1 (PyYAML, map_server) reads back as a float:
    an exponent needs a dot in its mantissa (``1e-300`` would be read as a string)."""
    text = repr(float(value))
    mantissa, e, exponent = text.partition("e")
    if e and "." not in mantissa:
        return f"{mantissa}.0e{exponent}"
    return text
