"""The orientation decision on real photographs (not the simulator's renderings).

A "place" is made of four real photographs bundled with scikit-image (by default the
astronaut, the coffee cup, the cat Chelsea and the rocket; none of them is among the shipped
vocabulary's training images, see :mod:`symloc.vision.default_vocabulary`), one per direction,
each seen through a 640 x 480 pinhole camera (horizontal field of view 65 deg) looking at the
middle of the photo, which is enlarged to 960 x 720 so that the camera can turn a few degrees
without seeing past its edge.

Queries are realistic re-captures of each direction:

- the camera turned by a yaw of up to ``max_yaw`` (a rotation homography ``H = K R K^-1``
  applied with ``cv2.warpPerspective``), which the decision must read back as heading offset;
- and, on top of the yaw, one of: a scale change (the robot a little off the centre: zoom
  0.85-1.15), brightness/contrast change (gain 0.6-1.4, offset -40..40 grey levels), JPEG at
  quality 60, Gaussian noise (sigma 8 grey levels), a partial occlusion (a flat rectangle over
  25-40 % of the image), or all of them together.

Ambiguous places test that the decision says "undetermined" instead of a wrong direction:
the same photo on two opposite walls (a room that really looks the same both ways), a
near-duplicate (the second copy re-captured with another yaw, exposure and JPEG), a mirrored
copy (a reflection-symmetric room: the two views are mirror images, which ORB can tell apart,
so a correct decision is acceptable there and only a wrong one is a failure), and featureless
walls (flat paint), which must be refused.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from symloc._checks import as_rng
from symloc.errors import ConfigurationError
from symloc.symmetry.order import SymmetryOrder
from symloc.vision.orb import OrbExtractor
from symloc.vision.orientation import OrientationConfig, decide_orientation, decide_with_retries
from symloc.vision.place import Place, PlaceImage
from symloc.vision.visual_map import direction_headings
from symloc.vision.vocabulary import Vocabulary

__all__ = [
    "CONDITIONS",
    "PLACE_PHOTOS",
    "VIEW_K",
    "VIEW_SIZE",
    "CaseResult",
    "PhotoTrial",
    "PhotosResult",
    "example_views",
    "flat_wall",
    "load_scene",
    "make_place",
    "perturb",
    "run_photos",
    "view",
]

PLACE_PHOTOS = ("astronaut", "coffee", "chelsea", "rocket")
"""``skimage.data`` photos used as the four directions (not in the default vocabulary's
training set)."""

VIEW_SIZE = (640, 480)
SCENE_SIZE = (960, 720)
_F = 500.0
VIEW_K = np.array([[_F, 0.0, VIEW_SIZE[0] / 2], [0.0, _F, VIEW_SIZE[1] / 2], [0.0, 0.0, 1.0]])
"""Camera matrix of the views (f = 500 px, hfov 65.2 deg)."""

CONDITIONS = ("yaw", "scale", "photometric", "jpeg60", "noise", "occlusion", "combined")
"""Re-capture conditions; every one includes a random yaw."""


def load_scene(name: str) -> NDArray[np.uint8]:
    """A bundled ``skimage.data`` photo as a ``SCENE_SIZE`` RGB uint8 scene."""
    import skimage.data

    try:
        img = np.asarray(getattr(skimage.data, name)())
    except AttributeError as err:
        raise ConfigurationError(f"photo: skimage.data has no image {name!r}") from err
    if img.ndim == 2:
        img = np.repeat(img[:, :, None], 3, axis=2)
    img = img[:, :, :3]
    if img.dtype != np.uint8:
        img = np.clip(img * (255.0 if img.max() <= 1.0 else 1.0), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(cv2.resize(img, SCENE_SIZE, interpolation=cv2.INTER_CUBIC))


def flat_wall(rng: np.random.Generator | int | None = None) -> NDArray[np.uint8]:
    """A featureless scene: flat paint with +-3 grey levels of sensor noise."""
    gen = as_rng(rng)
    w, h = SCENE_SIZE
    base = np.array([200, 196, 188], np.int16)
    noise = gen.integers(-3, 4, size=(h, w, 1), dtype=np.int16)
    return np.asarray(np.clip(base + noise, 0, 255), np.uint8)


def view(scene: NDArray[np.uint8], yaw: float = 0.0, zoom: float = 1.0) -> NDArray[np.uint8]:
    """The 640 x 480 view of ``scene`` after the camera turned by ``yaw`` [rad] (CCW positive)
    and zoomed by ``zoom`` about the image centre (the robot slightly nearer or farther)."""
    w, h = VIEW_SIZE
    sw, sh = scene.shape[1], scene.shape[0]
    T = np.array([[1.0, 0.0, -(sw - w) / 2], [0.0, 1.0, -(sh - h) / 2], [0.0, 0.0, 1.0]])
    cx, cy = w / 2, h / 2
    Z = np.array([[zoom, 0.0, cx * (1 - zoom)], [0.0, zoom, cy * (1 - zoom)], [0.0, 0.0, 1.0]])
    c, s = math.cos(yaw), math.sin(yaw)
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    H = VIEW_K @ R @ np.linalg.inv(VIEW_K) @ Z @ T
    out = cv2.warpPerspective(
        scene, H, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
    )
    return np.asarray(out, np.uint8)


def _jpeg(img: NDArray[np.uint8], quality: int) -> NDArray[np.uint8]:
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:  # pragma: no cover - OpenCV failure
        raise RuntimeError("JPEG encoding failed")
    return np.asarray(cv2.imdecode(buf, cv2.IMREAD_UNCHANGED), np.uint8)


def perturb(
    scene: NDArray[np.uint8], condition: str, rng: np.random.Generator, max_yaw: float
) -> tuple[NDArray[np.uint8], float]:
    """A re-capture of ``scene`` under ``condition`` (see :data:`CONDITIONS`).

    Returns
    -------
    image : (480, 640, 3) uint8
    yaw : float
        The true heading offset [rad] of the query against the stored view (CCW positive).
    """
    if condition not in CONDITIONS:
        raise ConfigurationError(f"condition: expected one of {CONDITIONS}, got {condition!r}")
    yaw = float(rng.uniform(-max_yaw, max_yaw))
    every = condition == "combined"
    zoom = float(rng.uniform(0.85, 1.15)) if (every or condition == "scale") else 1.0
    img = view(scene, yaw, zoom).astype(np.float64)
    if every or condition == "photometric":
        img = img * rng.uniform(0.6, 1.4) + rng.uniform(-40.0, 40.0)
    if every or condition == "occlusion":
        h, w = img.shape[:2]
        frac = rng.uniform(0.25, 0.40)
        aspect = rng.uniform(0.6, 1.6)
        oh = min(h, round(math.sqrt(frac * h * w / aspect)))
        ow = min(w, round(frac * h * w / max(oh, 1)))
        y0, x0 = int(rng.integers(0, h - oh + 1)), int(rng.integers(0, w - ow + 1))
        img[y0 : y0 + oh, x0 : x0 + ow] = rng.uniform(0, 255, size=3)
    if every or condition == "noise":
        img = img + rng.normal(0.0, 8.0, size=img.shape)
    out = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    if every or condition == "jpeg60":
        out = _jpeg(out, 60)
    return out, yaw


def make_place(
    scenes: Sequence[NDArray[np.uint8]],
    vocabulary: Vocabulary,
    extractor: OrbExtractor,
    *,
    kind: str = "square",
    images: Sequence[NDArray[np.uint8]] | None = None,
) -> Place:
    """A place whose direction j stores the straight view of ``scenes[j]`` (or ``images[j]``)."""
    views = list(images) if images is not None else [view(s) for s in scenes]
    heads = direction_headings(0.0, len(views))
    pimgs = []
    for j, img in enumerate(views):
        f = extractor.extract(img)
        pimgs.append(PlaceImage(j, float(heads[j]), f, vocabulary.bow(f.descriptors)))
    return Place(
        place_id=0,
        center=np.array([0.0, 0.0]),
        heading0=0.0,
        m=len(pimgs),
        order=SymmetryOrder.CIRCLE if kind == "circle" else SymmetryOrder.finite(len(views)),
        gv_distance=0.0,
        kind=kind,
        images=tuple(pimgs),
    )


@dataclass(frozen=True)
class PhotoTrial:
    """One query and its decision."""

    case: str
    direction: int
    true_yaw_deg: float
    status: str
    decided_direction: int | None
    offset_deg: float
    best_score: float
    second_score: float
    inliers: int
    reason: str
    retry_status: str | None = None
    retry_direction: int | None = None

    @property
    def correct(self) -> bool:
        """Decided, and the right direction."""
        return self.status == "decided" and self.decided_direction == self.direction

    @property
    def wrong(self) -> bool:
        """Decided, but the wrong direction."""
        return self.status == "decided" and self.decided_direction != self.direction

    @property
    def heading_error_deg(self) -> float:
        """|decided offset - true yaw| [deg] (NaN unless correct)."""
        return abs(self.offset_deg - self.true_yaw_deg) if self.correct else math.nan


@dataclass(frozen=True)
class CaseResult:
    """Counts over the trials of one condition or ambiguity case."""

    case: str
    trials: int
    correct: int
    wrong: int
    undetermined: int
    refused: int
    heading_error_deg_median: float
    heading_error_deg_p95: float
    heading_error_deg_max: float
    note: str = ""
    retry_correct: int | None = None
    retry_wrong: int | None = None

    @property
    def accuracy(self) -> float:
        """Correct decisions / trials."""
        return self.correct / self.trials if self.trials else math.nan

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (with the accuracy)."""
        return {**asdict(self), "accuracy": self.accuracy}


@dataclass(frozen=True)
class PhotosResult:
    """All cases of :func:`run_photos`."""

    conditions: tuple[CaseResult, ...]
    ambiguity: tuple[CaseResult, ...]
    trials: tuple[PhotoTrial, ...] = field(repr=False)
    photos: tuple[str, ...] = PLACE_PHOTOS
    max_yaw_deg: float = 5.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "photos": list(self.photos),
            "max_yaw_deg": self.max_yaw_deg,
            "conditions": {c.case: c.to_dict() for c in self.conditions},
            "ambiguity": {c.case: c.to_dict() for c in self.ambiguity},
        }


def _summary(case: str, trials: Sequence[PhotoTrial], note: str = "") -> CaseResult:
    errs = np.array([t.heading_error_deg for t in trials if t.correct], float)
    has = errs.size > 0
    retried = [t for t in trials if t.retry_status is not None]
    return CaseResult(
        case=case,
        trials=len(trials),
        correct=sum(t.correct for t in trials),
        wrong=sum(t.wrong for t in trials),
        undetermined=sum(t.status == "undetermined" for t in trials),
        refused=sum(t.status == "refused" for t in trials),
        heading_error_deg_median=float(np.median(errs)) if has else math.nan,
        heading_error_deg_p95=float(np.percentile(errs, 95)) if has else math.nan,
        heading_error_deg_max=float(errs.max()) if has else math.nan,
        note=note,
        retry_correct=(
            sum(t.retry_status == "decided" and t.retry_direction == t.direction for t in retried)
            if retried
            else None
        ),
        retry_wrong=(
            sum(t.retry_status == "decided" and t.retry_direction != t.direction for t in retried)
            if retried
            else None
        ),
    )


def _trial(
    case: str,
    j: int,
    yaw: float,
    query: NDArray[np.uint8],
    place: Place,
    vocabulary: Vocabulary,
    extractor: OrbExtractor,
    config: OrientationConfig,
    capture: Callable[[int], NDArray[np.uint8]] | None = None,
) -> PhotoTrial:
    d = decide_orientation(query, place, vocabulary, VIEW_K, config, extractor=extractor)
    rs: str | None = None
    rd: int | None = None
    if capture is not None:
        r = decide_with_retries(capture, place, vocabulary, VIEW_K, config, extractor=extractor)
        rs, rd = r.status, r.direction
    return PhotoTrial(
        case=case,
        direction=j,
        true_yaw_deg=math.degrees(yaw),
        status=d.status,
        decided_direction=d.direction,
        offset_deg=math.degrees(d.heading_offset) if d.decided else math.nan,
        best_score=d.best_score,
        second_score=d.second_score,
        inliers=d.inliers,
        reason=d.reason,
        retry_status=rs,
        retry_direction=rd,
    )


def run_photos(
    vocabulary: Vocabulary,
    *,
    photos: Sequence[str] = PLACE_PHOTOS,
    trials_per_direction: int = 15,
    max_yaw_deg: float = 5.0,
    conditions: Sequence[str] = CONDITIONS,
    config: OrientationConfig | None = None,
    rng: np.random.Generator | int | None = None,
    progress: bool = True,
) -> PhotosResult:
    """Run every re-capture condition and ambiguity case on real photos.

    Parameters
    ----------
    vocabulary : Vocabulary
    photos : sequence of 4 ``skimage.data`` names
        The four directions (A, B, C, D). The ambiguity cases use A, B, D and a copy of A.
    trials_per_direction : int
        Queries per direction and case.
    max_yaw_deg : float
        Queries turn by a uniform yaw in ``[-max_yaw_deg, max_yaw_deg]`` [deg].
    conditions : sequence of str
        Subset of :data:`CONDITIONS`.
    config : OrientationConfig, optional
    rng : Generator, int or None
    progress : bool
        tqdm bar on stderr.

    Returns
    -------
    PhotosResult
    """
    from tqdm import tqdm

    if len(photos) != 4:
        raise ConfigurationError(f"photos: expected 4 photo names, got {len(photos)}")
    if int(trials_per_direction) != trials_per_direction or trials_per_direction < 1:
        raise ConfigurationError(
            f"trials_per_direction: expected an integer >= 1, got {trials_per_direction}"
        )
    if not (math.isfinite(max_yaw_deg) and 0.0 <= max_yaw_deg <= 40.0):
        raise ConfigurationError(f"max_yaw_deg: expected a value in [0, 40], got {max_yaw_deg}")
    for c in conditions:
        if c not in CONDITIONS:
            raise ConfigurationError(f"conditions: unknown {c!r}; expected some of {CONDITIONS}")
    gen = as_rng(rng)
    cfg = config or OrientationConfig()
    ext = OrbExtractor()
    max_yaw = math.radians(max_yaw_deg)
    scenes = [load_scene(n) for n in photos]
    A, B, _, D = scenes
    place = make_place(scenes, vocabulary, ext)

    mirrored = np.ascontiguousarray(A[:, ::-1])
    near = view(A, math.radians(2.0), 1.03).astype(np.float64) * 1.15 + 10.0
    near_img = _jpeg(np.clip(np.rint(near), 0, 255).astype(np.uint8), 75)
    flat = flat_wall(gen)
    amb_specs: list[tuple[str, list[NDArray[np.uint8]], list[NDArray[np.uint8]] | None, str]] = [
        ("duplicate", [A, B, A, D], None, "the same photo on opposite walls (directions 0, 2)"),
        (
            "near_duplicate",
            [A, B, A, D],
            [view(A), view(B), near_img, view(D)],
            "direction 2 is direction 0 re-captured (yaw 2 deg, zoom 1.03, exposure, JPEG 75)",
        ),
        (
            "mirrored",
            [A, B, mirrored, D],
            None,
            "direction 2 is direction 0 mirrored (a reflection-symmetric room); correct "
            "decisions are legitimate here, wrong ones are failures",
        ),
        ("featureless", [flat, B, flat, D], None, "directions 0 and 2 are flat paint"),
    ]

    total = trials_per_direction * 4 * (len(conditions) + len(amb_specs))
    out: list[PhotoTrial] = []
    with tqdm(total=total, desc="photo queries", unit="query", disable=not progress) as bar:
        for cond in conditions:
            for j in range(4):
                for _ in range(trials_per_direction):
                    q, yaw = perturb(scenes[j], cond, gen, max_yaw)
                    out.append(_trial(cond, j, yaw, q, place, vocabulary, ext, cfg))
                    bar.update()
        amb_results = []
        for name, sc, imgs, note in amb_specs:
            amb_place = make_place(sc, vocabulary, ext, images=imgs)
            case_trials = []
            for j in range(4):
                for _ in range(trials_per_direction):
                    q, yaw = perturb(
                        sc[j], "combined" if name != "featureless" else "yaw", gen, max_yaw
                    )
                    y0 = float(gen.uniform(-max_yaw, max_yaw))

                    def capture(
                        t: int, j: int = j, y0: float = y0, sc: list[Any] = sc
                    ) -> NDArray[np.uint8]:
                        # the robot turned clockwise t times: it faces direction j + t
                        return view(sc[(j + t) % 4], y0)

                    case_trials.append(
                        _trial(name, j, yaw, q, amb_place, vocabulary, ext, cfg, capture)
                    )
                    bar.update()
            out.extend(case_trials)
            amb_results.append(_summary(name, case_trials, note))

    cond_results = tuple(_summary(c, [t for t in out if t.case == c]) for c in conditions)
    return PhotosResult(
        conditions=cond_results,
        ambiguity=tuple(amb_results),
        trials=tuple(out),
        photos=tuple(photos),
        max_yaw_deg=float(max_yaw_deg),
    )


def example_views(
    photos: Sequence[str] = PLACE_PHOTOS,
    rng: np.random.Generator | int | None = None,
    max_yaw_deg: float = 5.0,
) -> list[tuple[str, NDArray[np.uint8]]]:
    """The stored view of each photo, then one re-capture per condition (for figures)."""
    gen = as_rng(rng)
    scenes = [load_scene(n) for n in photos]
    out = [
        (f"stored {j}: {n}", view(s)) for j, (n, s) in enumerate(zip(photos, scenes, strict=True))
    ]
    for i, cond in enumerate(("occlusion", "photometric", "combined")):
        img, yaw = perturb(scenes[i % len(scenes)], cond, gen, math.radians(max_yaw_deg))
        out.append((f"{cond}, yaw {math.degrees(yaw):+.1f} deg", img))
    return out
