"""The mapping stage from a recording: a bag in, the occupancy map and the visual map out.

:func:`map_from_bag` does, on a robot's own recording, what the bench's mapping trip does in
the simulator (:func:`symloc.bench.scenario.build_scenario` with ``keyframes``):

1. the bag's scans are paired offline with the odometry at their stamps, from its
   nav_msgs/Odometry topic or from ``odom -> base`` on ``/tf``, the laser's mount from
   ``/tf_static`` (:func:`symloc.ros.replay.pair_scans_offline`);
2. symloc's laser SLAM builds the occupancy grid, the scans' map poses and the map's own error
   estimate (:func:`symloc.slam.run_slam`, :mod:`symloc.slam.map_error`);
3. when the bag holds camera images, the keyframe rule (:class:`symloc.vision.keyframes
   .KeyframeRecorder`) picks images along the trip from the odometry at their stamps (ORB
   features extracted only for the images it looks at), and each kept one gets the SLAM map
   pose of the robot at its stamp (the SLAM pose of the nearest scan carried by the odometry
   between the two stamps) and its BoW vector.

:func:`save_bag_mapping` writes the result as the node and ``symloc replay`` read it: the map in
map_server format with ``symloc_slam.map_error`` in its YAML (the claim gate reads it), the
trajectory of the scans (TUM) and the visual map (SQLite, keyframes table, the vocabulary's
fingerprint in its metadata), each file atomically.

Conventions: poses (x [m], y [m], theta [rad]) of the robot's base; the map frame is the
odometry frame at the first scan (SLAM fixes its first pose at the first odometry pose); the
camera looks along the base's +x (as :class:`~symloc.vision.keyframes.Keyframe` assumes).
Images are taken to be stamped on the odometry's clock; images with no odometry at their
stamp are counted, never silently dropped.
"""

from __future__ import annotations

import bisect
import logging
import math
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError, DataFormatError
from symloc.geometry import compose, inverse
from symloc.io.rosbag import BagTopics, bag_topics, read_bag
from symloc.ros.pairing import OdometryBuffer
from symloc.ros.replay import (
    MIN_PAIRED_SHARE,
    ODOM_SOURCES,
    ScansWithOdometry,
    pair_scans_offline,
)
from symloc.slam.slam import SlamParams, SlamResult, run_slam
from symloc.vision.keyframes import Keyframe, KeyframeRecorder, KeyframeSettings
from symloc.vision.orb import OrbExtractor
from symloc.vision.vocabulary import Vocabulary

__all__ = [
    "BagMapping",
    "BagMappingFiles",
    "BagMappingSettings",
    "map_from_bag",
    "save_bag_mapping",
]

_LOG = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class BagMappingSettings:
    """How :func:`map_from_bag` maps a recording.

    Attributes
    ----------
    keyframes : KeyframeSettings
        The keyframe rule (the bench's mapping trip uses the same default).
    check_every : int
        Images between two covisibility checks while the pose rule does not fire (>= 1): the
        other images are not even decoded into features.
    visual_map : bool
        Record keyframes when the bag has images (False: the occupancy map only).
    transform_tolerance : float
        [s] how far a scan or an image may lie outside the odometry's stamps and still take
        the nearest reading, > 0.
    odom_source : str
        ``auto`` (the Odometry topic when the bag has one, else ``/tf``), ``topic`` or ``tf``.
    odom_frame, base_frame : str
        The odometry frame and the robot's base frame on ``/tf`` (``base_frame`` "": the frame
        the odometry frame's transforms lead to).
    """

    keyframes: KeyframeSettings = field(default_factory=KeyframeSettings)
    check_every: int = 5
    visual_map: bool = True
    transform_tolerance: float = 1.0
    odom_source: str = "auto"
    odom_frame: str = "odom"
    base_frame: str = ""

    def __post_init__(self) -> None:
        if isinstance(self.check_every, bool) or int(self.check_every) < 1:
            raise ConfigurationError(
                f"BagMappingSettings.check_every: expected an integer >= 1, got {self.check_every}"
            )
        if self.odom_source not in ODOM_SOURCES:
            raise ConfigurationError(
                f"BagMappingSettings.odom_source: expected one of {ODOM_SOURCES}, got"
                f" {self.odom_source!r}"
            )
        check_positive(self.transform_tolerance, "BagMappingSettings.transform_tolerance")


@dataclass(frozen=True)
class BagMapping:
    """What :func:`map_from_bag` built.

    Attributes
    ----------
    bag : Path
    slam : SlamResult
        ``.grid`` the occupancy grid, ``.map_error`` its own error estimate (or None).
    paired : ScansWithOdometry
        How the scans paired with the odometry (counts, reasons, clock notes, source).
    stamps : (N,) float
        [s] stamp of each scan used.
    poses : (N, 3) float
        Map pose of the robot's base at each scan (SLAM's sensor poses moved by the mount).
    truth : (N, 3) float
        The bag's ground truth at each scan (NaN rows where it has none; (0, 3) when the bag
        has no ground-truth topic).
    keyframes : list of Keyframe
        The keyframes with their map poses and BoW vectors (empty without images).
    image_topic : str
        The camera topic read ("" when the bag has none or ``visual_map`` is off).
    images : int
        Images read from the bag.
    images_looked_at : int
        Images whose ORB features were extracted for the keyframe rule.
    dropped : dict of str to int
        Images (and other messages) left out per reason.
    vocabulary : Vocabulary or None
        The vocabulary of the keyframes' BoW vectors.
    """

    bag: Path
    slam: SlamResult
    paired: ScansWithOdometry
    stamps: FloatArray
    poses: FloatArray
    truth: FloatArray
    keyframes: list[Keyframe]
    image_topic: str
    images: int
    images_looked_at: int
    dropped: dict[str, int]
    vocabulary: Vocabulary | None

    @property
    def keyframe_poses(self) -> FloatArray:
        """(K, 3) map poses of the keyframes."""
        return np.array([kf.pose for kf in self.keyframes], np.float64).reshape(-1, 3)


def _image_topic(path: str | Path, topics: BagTopics) -> str:
    """The camera topic :func:`read_bag` will read ("" when the bag has none)."""
    types = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage")
    found = {t: ty for t, (ty, n) in bag_topics(path).items() if ty in types and n > 0}
    if topics.image is not None:
        names = [topics.image, "/" + topics.image.lstrip("/"), topics.image.lstrip("/")]
        return next((n for n in names if n in found), "")
    usual = ("/camera/image_raw", "/camera/image_raw/compressed", "/image_raw")
    ranked = sorted(found, key=lambda n: (usual.index(n) if n in usual else len(usual), n))
    return ranked[0] if ranked else ""


def map_from_bag(
    path: str | Path,
    *,
    topics: BagTopics | None = None,
    slam_params: SlamParams | None = None,
    settings: BagMappingSettings | None = None,
    vocabulary: Vocabulary | None = None,
    extractor: OrbExtractor | None = None,
    progress: bool = False,
) -> BagMapping:
    """Map a recording: occupancy grid by SLAM, keyframes from its camera (module docstring).

    Parameters
    ----------
    path : str or Path
        ROS 1 ``.bag``, ROS 2 bag folder, or the ``.db3`` / ``.mcap`` inside one.
    topics : BagTopics, optional
        Topic names (default: by type; the ground truth only from ``ground_truth`` or the name
        given, and never used for mapping, only returned in :attr:`BagMapping.truth`).
    slam_params : SlamParams, optional
    settings : BagMappingSettings, optional
    vocabulary : Vocabulary, optional
        For the keyframes' BoW vectors (default: the shipped vocabulary).
    extractor : OrbExtractor, optional
    progress : bool
        tqdm bars on stderr for SLAM and the images.

    Raises
    ------
    DataFormatError
        Naming the bag and topic: not a bag, no scans, no odometry (topic or TF), or fewer than
        two scans (or less than :data:`~symloc.ros.replay.MIN_PAIRED_SHARE` of them) paired
        with odometry; a named image topic that is not in the bag.
    """
    cfg = settings if settings is not None else BagMappingSettings()
    prm = slam_params if slam_params is not None else SlamParams()
    tp = topics if topics is not None else BagTopics()
    bag = Path(path)
    listing = bag_topics(bag)
    scan_topics = sorted(t for t, (ty, _) in listing.items() if ty == "sensor_msgs/msg/LaserScan")
    if not scan_topics or all(listing[t][1] == 0 for t in scan_topics):
        raise DataFormatError(
            f"bag {bag}: expected sensor_msgs/LaserScan messages to map from, found none"
            f" (topics: {sorted(listing)}); record /scan"
        )
    paired = pair_scans_offline(
        bag,
        topics=tp,
        transform_tolerance=cfg.transform_tolerance,
        odom_source=cfg.odom_source,
        odom_frame=cfg.odom_frame,
        base_frame=cfg.base_frame,
    )
    n = len(paired.scans)
    if n < 2 or n < MIN_PAIRED_SHARE * paired.total:
        raise DataFormatError(
            f"bag {bag}: expected scans with odometry at their stamps to build a map (at least"
            f" {100 * MIN_PAIRED_SHARE:.0f} % of the bag's {paired.total} scans), got {n}"
            f" (odometry: {paired.source}; dropped: {paired.dropped or 'none'}); check the"
            " odometry topic or frames and that scans and odometry come from one clock"
        )
    _LOG.info("bag %s: %d of %d scans paired with %s", bag, n, paired.total, paired.source)
    slam = run_slam(paired.scans, paired.laser_odometry, prm, progress=progress, desc="slam")
    sensor_poses = np.asarray(slam.poses, dtype=np.float64)
    poses = (
        np.asarray(compose(sensor_poses, inverse(paired.mount)), dtype=np.float64).reshape(-1, 3)
        if np.any(paired.mount)
        else sensor_poses
    )
    stamps = np.array([s.stamp for s in paired.scans], dtype=np.float64)

    image_topic = _image_topic(bag, tp) if cfg.visual_map else ""
    if tp.image is not None and cfg.visual_map and not image_topic:
        raise DataFormatError(
            f"bag {bag}: image topic {tp.image!r} not found or empty; topics: {sorted(listing)}"
        )
    want_truth = tp.truth is not None
    kinds = ["truth"] if want_truth else []
    if image_topic:
        kinds.append("image")
    voc = vocabulary
    if image_topic and voc is None:
        from symloc.vision.default_vocabulary import default_vocabulary

        voc = default_vocabulary()
    recorder = KeyframeRecorder(
        lambda image: image,
        extractor if extractor is not None else OrbExtractor(),
        cfg.keyframes,
        check_every=cfg.check_every,
    )
    dropped: Counter[str] = Counter()
    truth_buf = OdometryBuffer()
    image_stamps: list[float] = []
    image_odom: list[FloatArray] = []
    n_images = 0
    if kinds:
        messages: Iterable[Any] = read_bag(
            bag,
            topics=BagTopics(
                scan=tp.scan, odom=tp.odom, image=image_topic or None, map=tp.map, truth=tp.truth
            ),
            on_error="skip",
            dropped=dropped,
            kinds=kinds,
        )
        if progress and image_topic:
            from tqdm import tqdm

            truth_names = [tp.truth, "/" + tp.truth.lstrip("/")] if tp.truth else []
            total = listing[image_topic][1] + next(
                (listing[t][1] for t in truth_names if t in listing), 0
            )
            messages = tqdm(messages, total=total, desc="images", unit="msg", leave=False)
        for m in messages:
            if m.kind == "truth":
                if not truth_buf.add(m.value, max_age=math.inf):
                    dropped["truth: stamp went backwards"] += 1
                continue
            n_images += 1
            reading = paired.readings.at(m.stamp, cfg.transform_tolerance)
            if isinstance(reading, str):
                dropped[f"image: {reading}"] += 1
                continue
            image_stamps.append(float(m.stamp))
            image_odom.append(np.asarray(reading.pose, dtype=np.float64))
            recorder.frame(len(image_stamps) - 1, image_odom[-1], m.value, float(m.stamp))
    no_odometry = sum(v for k, v in dropped.items() if k.startswith("image: "))
    if image_topic and no_odometry > 0.5 * n_images:
        _LOG.warning(
            "bag %s: most images on %s have no odometry at their stamp: is the camera stamped"
            " on another clock?",
            bag,
            image_topic,
        )
    keyframes: list[Keyframe] = []
    if recorder.frames and voc is not None:
        map_from_odom = _map_from_odom(poses, paired.odometry)

        def map_pose(i: int) -> FloatArray:
            j = _nearest(stamps, image_stamps[i])
            return np.asarray(compose(map_from_odom[j], image_odom[i]), dtype=np.float64)

        vocab = voc
        keyframes = recorder.keyframes(map_pose, lambda f: vocab.bow(f.descriptors))
    truth = np.zeros((0, 3))
    if truth_buf.stamps:
        rows = []
        for t in stamps:
            r = truth_buf.at(float(t), cfg.transform_tolerance)
            rows.append(np.full(3, np.nan) if isinstance(r, str) else np.asarray(r.pose))
        truth = np.asarray(rows, dtype=np.float64).reshape(-1, 3)
    for k, v in paired.dropped.items():
        dropped[k] += v
    return BagMapping(
        bag=bag,
        slam=slam,
        paired=paired,
        stamps=stamps,
        poses=poses,
        truth=truth,
        keyframes=keyframes,
        image_topic=image_topic,
        images=n_images,
        images_looked_at=recorder.captured,
        dropped=dict(dropped),
        vocabulary=voc if image_topic else None,
    )


def _map_from_odom(poses: FloatArray, odometry: FloatArray) -> FloatArray:
    """(N, 3) ``map_from_odom`` at each scan: its map pose times its inverse odometry pose."""
    out = [compose(p, inverse(o)) for p, o in zip(poses, odometry, strict=True)]
    return np.asarray(out, dtype=np.float64).reshape(-1, 3)


def _nearest(stamps: FloatArray, t: float) -> int:
    """Index of the stamp in the sorted ``stamps`` (N,) nearest to ``t``."""
    i = bisect.bisect_left(stamps.tolist(), t)
    if i == 0:
        return 0
    if i >= stamps.size:
        return int(stamps.size - 1)
    return i if stamps[i] - t < t - stamps[i - 1] else i - 1


@dataclass(frozen=True)
class BagMappingFiles:
    """The files :func:`save_bag_mapping` wrote: ``map_yaml`` (its image beside it),
    ``trajectory`` (TUM), ``visual_map`` (None without keyframes)."""

    map_yaml: Path
    trajectory: Path
    visual_map: Path | None


def save_bag_mapping(
    mapping: BagMapping,
    out: str | Path,
    name: str = "map",
    *,
    mode: str = "trinary",
    vocabulary_file: str | Path | None = None,
) -> BagMappingFiles:
    """Write ``mapping`` into the folder ``out``, each file atomically.

    ``<name>.yaml`` + its image (map_server; ``symloc_slam`` metadata with ``map_error``),
    ``<name>_trajectory.tum`` (the robot's map pose at each scan) and, when there are
    keyframes, ``<name>_visual.db`` (a new visual map holding them, with the fingerprint of
    the vocabulary: ``vocabulary_file`` names it for people, None: the shipped one).

    Raises
    ------
    MapFileError, DatabaseError
        The files cannot be written (naming the file).
    """
    from symloc.files.atomic import atomic_path
    from symloc.grid.map_io import save_map
    from symloc.io.tum import write_tum
    from symloc.vision.visual_map import VisualMap

    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    yaml_path = save_map(
        mapping.slam.grid, folder / name, mode=mode, extra=mapping.slam.map_metadata()
    )
    tum = folder / f"{name}_trajectory.tum"
    write_tum(tum, list(zip(mapping.stamps.tolist(), mapping.poses, strict=True)))
    db: Path | None = None
    if mapping.keyframes and mapping.vocabulary is not None:
        db = folder / f"{name}_visual.db"
        with atomic_path(db) as tmp:
            vm = VisualMap(tmp, journal="delete")
            try:
                vm.set_meta(
                    "vocabulary",
                    "default" if vocabulary_file is None else mapping.vocabulary.fingerprint(),
                )
                vm.set_meta(
                    "vocabulary_file",
                    "shipped" if vocabulary_file is None else str(vocabulary_file),
                )
                vm.set_meta("source", f"symloc map build --bag {mapping.bag}")
                vm.add_keyframes(mapping.keyframes)
            finally:
                vm.close()
    return BagMappingFiles(yaml_path, tum, db)
