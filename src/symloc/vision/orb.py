"""ORB feature extraction with OpenCV (Rublee et al., 2011), as the paper uses (500 features).

The extractor accepts grey or colour images of any size and returns plain arrays: keypoint
positions, their scale/orientation attributes, and the 256-bit descriptors packed as 32 bytes
(the layout DBoW2, DBoW3 and ORB-SLAM use).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from operator import attrgetter
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError, DataFormatError

__all__ = ["OrbExtractor", "OrbFeatures", "OrbSettings", "to_grey_uint8"]

#: Bytes per ORB descriptor (256 bits).
DESCRIPTOR_BYTES = 32

_KP_ATTRS = attrgetter("size", "angle", "response", "octave")
_KP_DTYPE = np.dtype(
    [("size", np.float32), ("angle", np.float32), ("response", np.float32), ("octave", np.int32)]
)


@dataclass(frozen=True)
class OrbSettings:
    """Settings of ``cv2.ORB_create`` (names follow OpenCV; defaults are OpenCV's and ORB-SLAM's).

    Attributes
    ----------
    n_features : int
        Maximum number of features kept (the paper uses 500).
    scale_factor : float
        Pyramid decimation ratio, > 1.
    n_levels : int
        Number of pyramid levels, >= 1.
    edge_threshold : int
        Border [px] where no feature is detected; should match ``patch_size``.
    first_level : int
        Pyramid level of the source image.
    wta_k : int
        Points compared per BRIEF element (2, 3 or 4); only 2 gives DBoW-compatible descriptors.
    patch_size : int
        Size [px] of the patch used by the oriented BRIEF descriptor.
    fast_threshold : int
        FAST corner threshold (intensity difference, 0..255).
    score_type : str
        ``"harris"`` or ``"fast"`` keypoint ranking.
    threads : int
        OpenCV threads during one extraction (restored afterwards); 0 keeps OpenCV's setting.
        ORB on a 640 x 480 image gains nothing from a second thread even on an idle machine
        (fastest runs 2.7 ms either way) and loses under load (median 10.3 ms with 2 threads
        against 7.7 ms with 1 on a 2-core machine at load 6; ``benchmarks/bench_vision.py``).
    """

    n_features: int = 500
    scale_factor: float = 1.2
    n_levels: int = 8
    edge_threshold: int = 31
    first_level: int = 0
    wta_k: int = 2
    patch_size: int = 31
    fast_threshold: int = 20
    score_type: str = "harris"
    threads: int = 1

    def __post_init__(self) -> None:
        if int(self.threads) != self.threads or self.threads < 0:
            raise ConfigurationError(f"threads: expected an integer >= 0, got {self.threads}")
        if int(self.n_features) != self.n_features or self.n_features < 1:
            raise ConfigurationError(f"n_features: expected an integer >= 1, got {self.n_features}")
        if not (np.isfinite(self.scale_factor) and self.scale_factor > 1.0):
            raise ConfigurationError(f"scale_factor: expected a value > 1, got {self.scale_factor}")
        if int(self.n_levels) != self.n_levels or self.n_levels < 1:
            raise ConfigurationError(f"n_levels: expected an integer >= 1, got {self.n_levels}")
        if self.edge_threshold < 0:
            raise ConfigurationError(
                f"edge_threshold: expected an integer >= 0, got {self.edge_threshold}"
            )
        if not 0 <= self.first_level < self.n_levels:
            raise ConfigurationError(
                f"first_level: expected 0 <= first_level < n_levels, got {self.first_level}"
            )
        if self.wta_k != 2:
            raise ConfigurationError(
                f"wta_k: only 2 gives 32-byte binary descriptors for a vocabulary, got {self.wta_k}"
            )
        if self.patch_size < 2:
            raise ConfigurationError(f"patch_size: expected an integer >= 2, got {self.patch_size}")
        if not 0 <= self.fast_threshold <= 255:
            raise ConfigurationError(
                f"fast_threshold: expected an integer in [0, 255], got {self.fast_threshold}"
            )
        if self.score_type not in ("harris", "fast"):
            raise ConfigurationError(
                f"score_type: expected 'harris' or 'fast', got {self.score_type!r}"
            )


@dataclass(frozen=True)
class OrbFeatures:
    """ORB keypoints and descriptors of one image.

    Attributes
    ----------
    points : (N, 2) float32
        Keypoint positions (u, v) [px] in the source image (u right, v down).
    sizes : (N,) float32
        Keypoint diameters [px].
    angles : (N,) float32
        Keypoint orientations [deg], OpenCV convention.
    responses : (N,) float32
        Corner responses.
    octaves : (N,) int32
        Pyramid level each keypoint was found at.
    descriptors : (N, 32) uint8
        Packed 256-bit descriptors.
    image_size : tuple of int
        (width, height) of the source image [px].
    """

    points: NDArray[np.float32]
    sizes: NDArray[np.float32]
    angles: NDArray[np.float32]
    responses: NDArray[np.float32]
    octaves: NDArray[np.int32]
    descriptors: NDArray[np.uint8]
    image_size: tuple[int, int] = field(default=(0, 0))

    def __len__(self) -> int:
        return int(self.points.shape[0])

    @classmethod
    def empty(cls, image_size: tuple[int, int] = (0, 0)) -> OrbFeatures:
        """Return a feature set with no keypoints."""
        f = np.zeros(0, np.float32)
        return cls(
            points=np.zeros((0, 2), np.float32),
            sizes=f,
            angles=f.copy(),
            responses=f.copy(),
            octaves=np.zeros(0, np.int32),
            descriptors=np.zeros((0, DESCRIPTOR_BYTES), np.uint8),
            image_size=image_size,
        )

    def keypoint_array(self) -> NDArray[np.float32]:
        """Return ``(N, 6)`` float32 rows ``u, v, size, angle, response, octave`` (for storage)."""
        return np.column_stack(
            [self.points, self.sizes, self.angles, self.responses, self.octaves.astype(np.float32)]
        ).astype(np.float32)

    @classmethod
    def from_arrays(
        cls, keypoints: ArrayLike, descriptors: ArrayLike, image_size: tuple[int, int] = (0, 0)
    ) -> OrbFeatures:
        """Rebuild features from :meth:`keypoint_array` rows and ``(N, 32)`` descriptors."""
        kp = np.asarray(keypoints, np.float32).reshape(-1, 6)
        desc = np.ascontiguousarray(np.asarray(descriptors, np.uint8).reshape(-1, DESCRIPTOR_BYTES))
        if kp.shape[0] != desc.shape[0]:
            raise DataFormatError(
                f"keypoints: {kp.shape[0]} rows but descriptors has {desc.shape[0]} rows"
            )
        return cls(
            points=np.ascontiguousarray(kp[:, :2]),
            sizes=kp[:, 2].copy(),
            angles=kp[:, 3].copy(),
            responses=kp[:, 4].copy(),
            octaves=kp[:, 5].astype(np.int32),
            descriptors=desc,
            image_size=image_size,
        )


def to_grey_uint8(image: ArrayLike) -> NDArray[np.uint8]:
    """Convert an image to a contiguous 8-bit grey array.

    Parameters
    ----------
    image : (H, W), (H, W, 1), (H, W, 3) RGB or (H, W, 4) RGBA array
        uint8, bool, or float in [0, 1].

    Returns
    -------
    (H, W) uint8
    """
    img: NDArray[Any] = np.asarray(image)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[:, :, 0]
    if img.ndim not in (2, 3) or (img.ndim == 3 and img.shape[2] not in (3, 4)):
        raise DataFormatError(
            f"image: expected shape (H, W), (H, W, 3) or (H, W, 4), got {img.shape}"
        )
    if img.shape[0] < 1 or img.shape[1] < 1:
        raise DataFormatError(f"image: empty image of shape {img.shape}")
    if img.dtype == np.bool_:
        img = img.astype(np.uint8) * 255
    elif img.dtype.kind == "f":
        if not np.all(np.isfinite(img)):
            raise DataFormatError("image: contains NaN or infinite values")
        img = np.clip(np.rint(img * 255.0), 0, 255).astype(np.uint8)
    elif img.dtype != np.uint8:
        if img.dtype.kind not in "ui":
            raise DataFormatError(f"image: unsupported dtype {img.dtype}")
        img = np.clip(img, 0, 255).astype(np.uint8)
    if img.ndim == 3:
        code = cv2.COLOR_RGBA2GRAY if img.shape[2] == 4 else cv2.COLOR_RGB2GRAY
        img = cv2.cvtColor(np.ascontiguousarray(img), code)
    return np.ascontiguousarray(img)


class OrbExtractor:
    """Extract ORB features with OpenCV.

    Parameters
    ----------
    settings : OrbSettings, optional
        Detector and descriptor settings (500 features by default).
    """

    def __init__(self, settings: OrbSettings | None = None) -> None:
        self.settings = settings if settings is not None else OrbSettings()
        s = self.settings
        self._orb = cv2.ORB_create(  # type: ignore[attr-defined]
            nfeatures=int(s.n_features),
            scaleFactor=float(s.scale_factor),
            nlevels=int(s.n_levels),
            edgeThreshold=int(s.edge_threshold),
            firstLevel=int(s.first_level),
            WTA_K=int(s.wta_k),
            scoreType=cv2.ORB_HARRIS_SCORE if s.score_type == "harris" else cv2.ORB_FAST_SCORE,
            patchSize=int(s.patch_size),
            fastThreshold=int(s.fast_threshold),
        )

    @property
    def min_image_side(self) -> int:
        """The smallest side [px] of an image in which ORB can find a keypoint: every keypoint
        lies ``edge_threshold`` pixels inside the border (and OpenCV's pyramid fails on an
        image one pixel wide); with ``first_level > 0`` the image is enlarged first."""
        s = self.settings
        enlarged = float(s.scale_factor) ** int(s.first_level)
        return max(2, math.ceil((2 * int(s.edge_threshold) + 1) / enlarged))

    def extract(self, image: ArrayLike, mask: ArrayLike | None = None) -> OrbFeatures:
        """Detect keypoints and compute descriptors.

        Parameters
        ----------
        image : (H, W) or (H, W, 3|4) array
            Grey or RGB(A) image, uint8 or float in [0, 1].
        mask : (H, W) array, optional
            Non-zero where features may be detected.

        Returns
        -------
        OrbFeatures
            At most ``settings.n_features`` features (fewer on a textureless image; none on an
            image with a side below :attr:`min_image_side`).
        """
        grey = to_grey_uint8(image)
        size = (int(grey.shape[1]), int(grey.shape[0]))
        cv_mask = None
        if mask is not None:
            m = np.asarray(mask)
            if m.shape != grey.shape:
                raise DataFormatError(f"mask: expected shape {grey.shape}, got {m.shape}")
            cv_mask = (m != 0).astype(np.uint8) * 255
        if min(size) < self.min_image_side:
            return OrbFeatures.empty(size)  # no keypoint fits; OpenCV would fail on 1 px
        threads = int(self.settings.threads)
        previous = cv2.getNumThreads()
        if threads and threads != previous:
            cv2.setNumThreads(threads)
            try:
                keypoints, descriptors = self._orb.detectAndCompute(grey, cv_mask)
            finally:
                cv2.setNumThreads(previous)
        else:
            keypoints, descriptors = self._orb.detectAndCompute(grey, cv_mask)
        if descriptors is None or len(keypoints) == 0:
            return OrbFeatures.empty(size)
        n = len(keypoints)
        # cv2.KeyPoint_convert is C++; one attrgetter pass for the rest (2.3x faster than
        # Python attribute access per keypoint: 0.10 instead of 0.23 ms for 500 keypoints)
        points = np.asarray(cv2.KeyPoint_convert(keypoints), np.float32).reshape(n, 2)  # type: ignore[attr-defined]
        attrs = np.fromiter(map(_KP_ATTRS, keypoints), dtype=_KP_DTYPE, count=n)
        return OrbFeatures(
            points=np.ascontiguousarray(points),
            sizes=np.ascontiguousarray(attrs["size"]),
            angles=np.ascontiguousarray(attrs["angle"]),
            responses=np.ascontiguousarray(attrs["response"]),
            octaves=np.ascontiguousarray(attrs["octave"]),
            descriptors=np.ascontiguousarray(descriptors, dtype=np.uint8),
            image_size=size,
        )
