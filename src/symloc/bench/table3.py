"""The paper's Table 3 in the simulator: BoW similarity and orientation decisions at a centre.

At the centre of a square room inside the lab, the camera stores M = 4 images, facing the
middles of the walls in clockwise order (Algorithm 2's heading, Algorithm 3). Then, for each
direction, trials place the robot uniformly within ``radius`` of the centre (the paper's
Table 2 spread, 15 mm) with its heading off by up to ``max_heading_error``; each trial renders
a query image (with the camera's pixel noise), scores it against the four stored images and runs
:func:`~symloc.vision.orientation.decide_orientation`. The same is repeated in the untextured
lab, where the right answer is "undetermined" (or "refused"), never a direction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import as_rng
from symloc.geometry import angle_diff, wrap_angle
from symloc.sim.camera import Camera
from symloc.sim.rooms import build_room
from symloc.symmetry.order import SymmetryOrder
from symloc.vision.default_vocabulary import default_vocabulary
from symloc.vision.orb import OrbExtractor, OrbSettings
from symloc.vision.orientation import (
    OrientationConfig,
    OrientationDecision,
    decide_orientation,
    decide_with_retries,
)
from symloc.vision.place import Place, PlaceImage
from symloc.vision.vocabulary import Vocabulary

__all__ = [
    "Table3Result",
    "TrialOutcome",
    "camera_matrix",
    "run_table3",
    "store_place",
    "wall_headings",
]


def camera_matrix(camera: Any) -> NDArray[np.float64]:
    """3x3 intrinsics of a :class:`symloc.sim.camera.Camera` (square pixels, centred)."""
    f = float(camera.focal)
    return np.array([[f, 0.0, camera.width / 2.0], [0.0, f, camera.height / 2.0], [0.0, 0.0, 1.0]])


def wall_headings(corners: NDArray[np.float64], center: NDArray[np.float64]) -> NDArray[np.float64]:
    """Headings [rad] from the centre to the middles of adjacent corners, in clockwise order.

    Direction 0 is the wall middle with the heading closest to 0; the others follow clockwise
    (decreasing heading), as the paper stores them.
    """
    c = np.asarray(corners, float)
    mids = 0.5 * (c + np.roll(c, -1, axis=0)) - np.asarray(center, float)
    h = np.arctan2(mids[:, 1], mids[:, 0])
    h0 = h[int(np.argmin(np.abs(h)))]
    m = h.size
    return np.asarray(wrap_angle(h0 - np.arange(m) * 2.0 * math.pi / m), float)


def store_place(
    world: Any,
    center: NDArray[np.float64],
    headings: NDArray[np.float64],
    camera: Any,
    vocabulary: Vocabulary,
    extractor: OrbExtractor,
    rng: np.random.Generator,
    *,
    kind: str = "square",
    gv_distance: float = 0.0,
    keep_images: bool = False,
) -> Place:
    """Render and describe the M stored images at ``center`` (Algorithm 3)."""
    images = []
    for j, h in enumerate(headings):
        img = camera.render(world, [center[0], center[1], h], rng=rng)
        f = extractor.extract(img)
        images.append(
            PlaceImage(j, float(h), f, vocabulary.bow(f.descriptors), img if keep_images else None)
        )
    return Place(
        place_id=0,
        center=np.array([center[0], center[1]], float),
        heading0=float(headings[0]),
        m=len(images),
        order=SymmetryOrder.CIRCLE if kind == "circle" else SymmetryOrder.finite(len(headings)),
        gv_distance=float(gv_distance),
        kind=kind,
        images=tuple(images),
    )


@dataclass(frozen=True)
class TrialOutcome:
    """One query: true direction, true pose offsets and the decision."""

    direction: int
    offset_m: float
    heading_error_in: float
    decision: OrientationDecision
    heading_error_out: float
    retry: OrientationDecision | None = None


@dataclass
class Table3Result:
    """Everything Table 3 reports (see :meth:`to_dict`)."""

    similarity: NDArray[np.float64]
    trials: list[TrialOutcome]
    untextured: list[TrialOutcome]
    config: dict[str, Any] = field(default_factory=dict)
    untextured_sensitive: list[TrialOutcome] = field(default_factory=list)
    stored_images: list[NDArray[np.uint8]] = field(default_factory=list)
    example_query: NDArray[np.uint8] | None = None

    @staticmethod
    def _counts(trials: list[TrialOutcome]) -> dict[str, int]:
        dec = [t for t in trials if t.decision.decided]
        return {
            "trials": len(trials),
            "decided": len(dec),
            "correct": sum(t.decision.direction == t.direction for t in dec),
            "wrong": sum(t.decision.direction != t.direction for t in dec),
            "undetermined": sum(not t.decision.decided for t in trials),
            "refused": sum(t.decision.status == "refused" for t in trials),
            "retried": sum(t.retry is not None for t in trials),
            "correct_after_retries": sum(
                (t.decision.decided and t.decision.direction == t.direction)
                or (t.retry is not None and t.retry.decided and t.retry.direction == t.direction)
                for t in trials
            ),
            "wrong_after_retries": sum(
                (t.decision.decided and t.decision.direction != t.direction)
                or (t.retry is not None and t.retry.decided and t.retry.direction != t.direction)
                for t in trials
            ),
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        c = self._counts(self.trials)
        herr = np.array([abs(t.heading_error_out) for t in self.trials if t.decision.decided])
        hin = np.array([abs(t.heading_error_in) for t in self.trials if t.decision.decided])
        deg = np.degrees
        ratios = np.array(
            [
                t.decision.best_score / t.decision.second_score
                for t in self.trials
                if math.isfinite(t.decision.best_score) and t.decision.second_score > 0
            ]
        )
        return {
            "similarity": self.similarity.round(4).tolist(),
            "accuracy": c["correct"] / max(c["trials"], 1),
            "accuracy_with_retries": c["correct_after_retries"] / max(c["trials"], 1),
            "trials": c["trials"],
            "counts": c,
            "heading_error_deg_median": float(deg(np.median(herr))) if herr.size else math.nan,
            "heading_error_deg_p95": float(deg(np.percentile(herr, 95))) if herr.size else math.nan,
            "heading_error_deg_max": float(deg(herr.max())) if herr.size else math.nan,
            "heading_error_uncorrected_deg_median": float(deg(np.median(hin)))
            if hin.size
            else math.nan,
            "score_ratio_best_to_second": {
                "min": float(ratios.min()) if ratios.size else math.nan,
                "median": float(np.median(ratios)) if ratios.size else math.nan,
            },
            "untextured": self._counts(self.untextured),
            "untextured_sensitive_orb": {
                **self._counts(self.untextured_sensitive),
                "fast_threshold": self.config.get("sensitive_fast_threshold"),
                "mean_keypoints": float(
                    np.mean([t.decision.n_keypoints for t in self.untextured_sensitive])
                )
                if self.untextured_sensitive
                else math.nan,
            },
            "config": self.config,
        }


def _trials(
    world: Any,
    place: Place,
    camera: Any,
    vocabulary: Vocabulary,
    extractor: OrbExtractor,
    config: OrientationConfig,
    n_per_direction: int,
    radius: float,
    max_heading_error: float,
    rng: np.random.Generator,
    similarity: NDArray[np.float64] | None,
    progress: Any,
    examples: list[NDArray[np.uint8]] | None = None,
) -> list[TrialOutcome]:
    K = camera_matrix(camera)
    c = place.center
    out = []
    stored = [im.bow for im in place.images]
    for j, im in enumerate(place.images):
        for _ in range(n_per_direction):
            r = radius * math.sqrt(rng.uniform())
            a = rng.uniform(-math.pi, math.pi)
            dh = rng.uniform(-max_heading_error, max_heading_error)
            heading = im.heading + dh
            pose = [c[0] + r * math.cos(a), c[1] + r * math.sin(a), heading]
            img = camera.render(world, pose, rng=rng)
            if examples is not None and not examples:
                examples.append(img)
            f = extractor.extract(img)
            bow = vocabulary.bow(f.descriptors)
            if similarity is not None:
                similarity[j] += vocabulary.score_many(bow, stored)
            d = decide_orientation(f, place, vocabulary, K, config, query_bow=bow)
            err = float(angle_diff(d.heading, heading)) if d.decided else math.nan
            retry = None
            if not d.decided:
                # the paper's protocol: turn clockwise by 360/M and try again, up to M images
                step = 2.0 * math.pi / len(place.images)

                def capture(
                    t: int, pose: list[float] = pose, f: Any = f, step: float = step
                ) -> Any:
                    if t == 0:
                        return f
                    p = [pose[0], pose[1], pose[2] - t * step]
                    return extractor.extract(camera.render(world, p, rng=rng))

                retry = decide_with_retries(
                    capture, place, vocabulary, K, config, extractor=extractor
                )
            out.append(TrialOutcome(j, r, dh, d, err, retry))
            progress.update(1)
    return out


def run_table3(
    *,
    trials: int = 50,
    side: float = 3.0,
    radius: float = 0.015,
    max_heading_error: float = math.radians(5.0),
    vocabulary: Vocabulary | None = None,
    config: OrientationConfig | None = None,
    rng: np.random.Generator | int | None = 0,
    untextured: bool = True,
    sensitive_fast_threshold: int | None = 4,
    progress: bool = True,
) -> Table3Result:
    """Run the Table 3 protocol (see the module docstring).

    Parameters
    ----------
    trials : int
        Trials per direction (>= 1).
    side : float
        Side of the square room [m] (the paper's: 3 m).
    radius : float
        Robot position spread around the centre [m].
    max_heading_error : float
        Largest heading error [rad] of the robot when it captures the query.
    vocabulary : Vocabulary, optional
        Default: the shipped :func:`~symloc.vision.default_vocabulary.default_vocabulary`.
    untextured : bool
        Also run the untextured lab (the paper's failure case).
    sensitive_fast_threshold : int or None
        Also run the untextured lab with this (very low) FAST threshold, so that board edges and
        pixel noise give ORB keypoints and the decision, not the keypoint count, must refuse to
        pick a direction among four views that look alike. None skips it.
    """
    from tqdm import tqdm

    gen = as_rng(rng)
    voc = vocabulary or default_vocabulary()
    cfg = config or OrientationConfig()
    ext = OrbExtractor()
    cam = Camera()
    gv = side / math.sqrt(2.0)
    m = 4
    sim = np.zeros((m, m))
    result_cfg = {
        "room": f"square {side:g} m inside the textured lab",
        "trials_per_direction": trials,
        "radius_mm": radius * 1000,
        "max_heading_error_deg": math.degrees(max_heading_error),
        "vocabulary": repr(voc),
        "camera": f"{cam.width}x{cam.height}, hfov {math.degrees(cam.hfov):.0f} deg, noise {cam.noise_sigma}",
        "orientation": cfg.__dict__,
    }

    result_cfg["sensitive_fast_threshold"] = sensitive_fast_threshold
    worlds: list[tuple[str, bool, OrbExtractor]] = [("textured", True, ext)]
    if untextured:
        worlds.append(("untextured", False, ext))
        if sensitive_fast_threshold is not None:
            sens = OrbExtractor(OrbSettings(fast_threshold=int(sensitive_fast_threshold)))
            worlds.append(("untextured_sensitive", False, sens))
    outcomes: dict[str, list[TrialOutcome]] = {}
    stored: list[NDArray[np.uint8]] = []
    examples: list[NDArray[np.uint8]] = []
    with tqdm(total=len(worlds) * m * trials, desc="table3 trials", disable=not progress) as bar:
        for name, textured, wext in worlds:
            room = build_room("square", gv, lab=True, textured=textured)
            heads = wall_headings(room.corners, room.center)
            place = store_place(
                room.world,
                room.center,
                heads,
                cam,
                voc,
                wext,
                gen,
                gv_distance=gv,
                keep_images=True,
            )
            if textured:
                stored = [im.image for im in place.images if im.image is not None]
            outcomes[name] = _trials(
                room.world,
                place,
                cam,
                voc,
                wext,
                cfg,
                trials,
                radius,
                max_heading_error,
                gen,
                sim if textured else None,
                bar,
                examples if textured else None,
            )
    return Table3Result(
        sim / trials,
        outcomes["textured"],
        outcomes.get("untextured", []),
        result_cfg,
        outcomes.get("untextured_sensitive", []),
        stored,
        examples[0] if examples else None,
    )
