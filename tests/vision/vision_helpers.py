"""Helpers of the vision tests (a uniquely named module, importable from the test files)."""

from __future__ import annotations

import math
from functools import lru_cache

import cv2
import numpy as np
import skimage.data

from symloc.vision.orb import OrbExtractor
from symloc.vision.vocabulary import Vocabulary

W, H, F = 640, 480, 500.0
K = np.array([[F, 0.0, W / 2], [0.0, F, H / 2], [0.0, 0.0, 1.0]])


def rotated_view(image: np.ndarray, yaw: float) -> np.ndarray:
    """The view of a flat photo after the camera turned by ``yaw`` [rad] (CCW positive)."""
    c, s = math.cos(yaw), math.sin(yaw)
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    src = cv2.resize(np.ascontiguousarray(image), (W, H))
    return cv2.warpPerspective(src, K @ R @ np.linalg.inv(K), (W, H))


@lru_cache(maxsize=1)
def extractor() -> OrbExtractor:
    """The default ORB extractor (500 features)."""
    return OrbExtractor()


@lru_cache(maxsize=1)
def trained_vocabulary() -> Vocabulary:
    """A k=10, L=4 vocabulary trained on bundled photos that are not the test's wall photos."""
    docs = []
    for name in ("camera", "brick", "grass", "gravel", "coins", "moon", "clock", "page"):
        img = getattr(skimage.data, name)()
        for s in (1.0, 0.75, 0.5):
            docs.append(extractor().extract(cv2.resize(img, None, fx=s, fy=s)).descriptors)
    return Vocabulary.train(docs, k=10, L=4, rng=1, progress=False)


@lru_cache(maxsize=1)
def wall_photos() -> list[np.ndarray]:
    """Four distinct photos standing for a square room's four walls."""
    return [
        skimage.data.astronaut(),
        skimage.data.coffee(),
        skimage.data.chelsea(),
        skimage.data.rocket(),
    ]
