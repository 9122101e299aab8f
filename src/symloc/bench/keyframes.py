"""The paper's Figure 14: storage of M images per place against a keyframe every 5 degrees.

The robot turns one full circle in place at the centre of the square room. symloc stores M = 4
images (one per wall middle); a keyframe policy like ORB-SLAM's, as the paper describes it, adds
an image every ``step`` of rotation (72 for 5 degrees). Both are written to a visual-map
database (features, BoW vectors, and optionally the PNG images) and the bytes on disk counted.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import as_rng
from symloc.bench.table3 import store_place, wall_headings
from symloc.sim.camera import Camera
from symloc.sim.rooms import build_room
from symloc.vision.default_vocabulary import default_vocabulary
from symloc.vision.orb import OrbExtractor
from symloc.vision.visual_map import VisualMap
from symloc.vision.vocabulary import Vocabulary

__all__ = ["KeyframePolicyResult", "map_bytes", "run_keyframes"]


@dataclass(frozen=True)
class KeyframePolicyResult:
    """Storage of one policy after a full turn.

    Attributes
    ----------
    name : str
    angles_deg : (n,) float
        Rotation [deg] at which each image was added.
    bytes_features : int
        Database size [bytes] with features and BoW vectors.
    bytes_with_images : int
        Database size [bytes] when the PNG images are kept too.
    n_features : int
        Total ORB features stored.
    """

    name: str
    angles_deg: NDArray[np.float64]
    bytes_features: int
    bytes_with_images: int
    n_features: int

    @property
    def count(self) -> int:
        """Number of stored images."""
        return int(self.angles_deg.size)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "name": self.name,
            "count": self.count,
            "bytes_features": self.bytes_features,
            "bytes_with_images": self.bytes_with_images,
            "n_features": self.n_features,
            "angles_deg": self.angles_deg.round(3).tolist(),
        }


def map_bytes(place: Any, *, keep_images: bool, folder: Path) -> int:
    """Bytes on disk of a visual map holding only ``place`` (WAL folded in)."""
    path = folder / f"map_{place.m}_{int(keep_images)}.db"
    path.unlink(missing_ok=True)
    with VisualMap(path, journal="delete") as vm:
        imgs = (
            place.images
            if keep_images
            else tuple(
                type(im)(im.direction, im.heading, im.features, im.bow, None) for im in place.images
            )
        )
        vm.add_place(
            kind=place.kind,
            order=place.order,
            gv_distance=place.gv_distance,
            pose=place.pose,
            images=imgs,
        )
        vm.checkpoint()
    return path.stat().st_size


def run_keyframes(
    *,
    m: int = 4,
    step_deg: float = 5.0,
    side: float = 3.0,
    vocabulary: Vocabulary | None = None,
    rng: np.random.Generator | int | None = 0,
) -> list[KeyframePolicyResult]:
    """Store one full turn with M images and with a keyframe every ``step_deg`` degrees."""

    gen = as_rng(rng)
    voc = vocabulary or default_vocabulary()
    ext = OrbExtractor()
    cam = Camera()
    gv = side / math.sqrt(2.0)
    room = build_room("square", gv, lab=True, textured=True)
    h0 = float(wall_headings(room.corners, room.center)[0])
    n_kf = round(360.0 / step_deg)
    policies = [
        (f"symloc (M = {m})", np.arange(m, dtype=np.float64) * 360.0 / m),
        (f"keyframe every {step_deg:g} deg", np.arange(n_kf, dtype=np.float64) * step_deg),
    ]
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, angles in policies:
            heads = h0 - np.radians(angles)  # turning clockwise
            place = store_place(
                room.world, room.center, heads, cam, voc, ext, gen, gv_distance=gv, keep_images=True
            )
            out.append(
                KeyframePolicyResult(
                    name,
                    angles,
                    map_bytes(place, keep_images=False, folder=Path(tmp)),
                    map_bytes(place, keep_images=True, folder=Path(tmp)),
                    sum(len(im.features) for im in place.images),
                )
            )
    return out
