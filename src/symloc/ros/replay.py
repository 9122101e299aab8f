"""Run the localizer over a recorded bag (``symloc replay``).

The bag's messages go through :class:`symloc.ros.core.NodeCore` (the ROS node's own logic) in
record order, as the live node takes them: odometry, images and maps are buffered, and every
scan waits for the odometry at its own stamp (nav2_amcl's tf2 message filter: odometry at
another rate than the scans, or recorded in bursts after them, still pairs) and is then one
localizer step with the odometry interpolated at its stamp and, when the localizer asked for
one, the newest image. Each message's log time is the receiving clock, so a pause in the
recording (a robot that sent nothing while it stood still, a log that keeps only the scans where
the robot moved) is time that passed, not a clock jump, and stamps on another clock than the
recorder's are fine (:class:`symloc.ros.guards.StampGate`). The result is the status, the earned
pose and the tracker's best estimate at every scan (``symloc replay`` writes the earned poses
and every scan's estimate as TUM trajectories), and :attr:`ReplayResult.verdict`: whether the
recording could be used, and if not why.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import DataFormatError
from symloc.geometry import compose
from symloc.grid import OccupancyGrid
from symloc.grid.map_error_field import MapErrorField
from symloc.io.bag_clocks import ClockOffsets, clock_offsets, stream_lags
from symloc.io.rosbag import BagMessage, BagTopics, bag_topics, read_bag
from symloc.io.tum import TrajectoryPoint
from symloc.localizer import Estimate
from symloc.odometry import OdometryReading
from symloc.ros.assemble import check_files
from symloc.ros.core import LocalizerFactory, NodeCore, Outputs
from symloc.ros.pairing import OdometryBuffer
from symloc.ros.params import NodeParams
from symloc.ros.tf import TransformTree, laser_mount, odometry_from_transform
from symloc.scan import mirror

__all__ = [
    "MAX_DROPPED_SHARE",
    "MIN_PAIRED_SHARE",
    "ODOM_SOURCES",
    "BagMap",
    "ReplayResult",
    "ReplayVerdict",
    "ScansWithOdometry",
    "bag_clock_offsets",
    "build_map_from_bag",
    "pair_scans_offline",
    "replay_bag",
    "replay_verdict",
    "restamped",
    "scans_with_odometry",
]

FloatArray = NDArray[np.float64]


@dataclass
class ReplayResult:
    """The localizer's answers over a bag.

    ``trajectory`` one point per scan used; ``truth`` (T, 4) t, x, y, theta from the bag's
    ground-truth topic (empty if none); ``grid`` the map used; ``final`` the last estimate;
    ``dropped`` messages dropped per reason; ``received`` messages per kind; ``recovered``
    the node's recoveries per kind (a time base or an odometry reset); ``pauses`` stamps taken
    as a pause in the recording; ``scans`` scans in the bag; ``clock_notes`` streams found on
    another clock and re-stamped (:mod:`symloc.io.bag_clocks`); ``steps`` the localizer's log.
    """

    trajectory: list[TrajectoryPoint]
    truth: FloatArray
    grid: OccupancyGrid | None
    final: Estimate | None
    dropped: dict[str, int] = field(default_factory=dict)
    received: dict[str, int] = field(default_factory=dict)
    steps: list[str] = field(default_factory=list)
    particles: FloatArray | None = None
    recovered: dict[str, int] = field(default_factory=dict)
    pauses: int = 0
    scans: int = 0
    clock_notes: list[str] = field(default_factory=list)

    @property
    def scans_dropped(self) -> int:
        """Scans of the bag the localizer did not take."""
        return self.scans - len(self.trajectory)

    @property
    def verdict(self) -> ReplayVerdict:
        """Whether the recording could be used (:func:`replay_verdict`)."""
        return replay_verdict(self)


@dataclass(frozen=True)
class ReplayVerdict:
    """``usable``: the localizer took enough of the bag's scans for its answers to mean
    something; ``text``: one line that says so, or what went wrong and what to check."""

    usable: bool
    text: str


#: Share of the scans that may be dropped before a replay is judged unusable.
MAX_DROPPED_SHARE = 0.2


def replay_verdict(res: ReplayResult) -> ReplayVerdict:
    """Judge a replay: usable when at most :data:`MAX_DROPPED_SHARE` of the bag's scans were
    dropped and the odometry was never re-anchored; otherwise name the main reasons (drops by
    reason, clock jumps taken as new time bases, odometry leaps) and what they point to."""
    if res.scans == 0:
        return ReplayVerdict(False, "the bag holds no LaserScan message (check --scan-topic)")
    if res.grid is None:
        return ReplayVerdict(False, "no map: give --map or record the map topic")
    used, n = len(res.trajectory), res.scans
    share = (n - used) / n
    scan_drops = sorted(
        ((k, v) for k, v in res.dropped.items() if k.startswith("scan")), key=lambda kv: -kv[1]
    )
    resets = res.recovered.get("odometry reset", 0)
    jumps = res.recovered.get("time base", 0)
    head = f"{used} of {n} scans used ({100.0 * share:.1f} % dropped)"
    if res.pauses:
        head += f"; {res.pauses} pauses in the recording taken as time that passed"
    problems: list[str] = []
    if share > MAX_DROPPED_SHARE:
        reasons = ", ".join(f"{k} x{v}" for k, v in scan_drops[:3]) or "see dropped"
        problems.append(f"too many scans dropped ({reasons})")
        if any("odometry" in k for k, _ in scan_drops):
            problems.append(
                "the scans' stamps are not covered by the odometry's: check that both come"
                " from the same clock and that the odometry topic was recorded (--odom-topic)"
            )
    if resets:
        problems.append(
            f"the odometry leapt {resets} times faster than max_odom_speed and was re-anchored"
            " (no motion assumed across each leap): the localizer saw wrong motion"
        )
    if jumps:
        problems.append(
            f"{jumps} clock jumps taken as new time bases (odometry history cleared):"
            " stamps that jump without the recording's log time jumping with them"
        )
    if problems:
        return ReplayVerdict(
            False, f"recording not usable as it is: {head}; " + "; ".join(problems)
        )
    return ReplayVerdict(True, f"recording usable: {head}")


#: The kinds of bag messages a replay feeds the node (TF is read for mapping only).
_REPLAYED = ("scan", "odom", "image", "map", "truth", "initialpose")


def replay_bag(
    path: str | Path,
    params: NodeParams,
    *,
    grid: OccupancyGrid | None = None,
    map_std_xy: float | None = None,
    map_error_field: MapErrorField | None = None,
    topics: BagTopics | None = None,
    factory: LocalizerFactory | None = None,
    warn: Callable[[str], object] | None = None,
    progress: bool = False,
) -> ReplayResult:
    """Replay ``path`` through the node logic; ``grid`` overrides the bag's map topic, with
    ``map_std_xy`` [m] its own error and ``map_error_field`` its error place by place when its
    file declares them (:meth:`NodeCore.set_map`).

    Malformed messages are skipped and counted (``dropped["<topic>: malformed in bag"]``).
    Scans still waiting for their odometry when the bag ends are dropped and counted.

    Raises
    ------
    ConfigurationError
        The visual map or vocabulary the parameters name cannot be used
        (:func:`symloc.ros.assemble.check_files`).
    """
    if factory is None:
        check_files(params)  # a bad visual map or vocabulary: one clear error, not 0 poses
    core = NodeCore(params, factory=factory, warn=warn)
    if grid is not None:
        core.set_map(grid, map_std_xy=map_std_xy, map_error_field=map_error_field)
    bag_dropped: Counter[str] = Counter()
    truth: list[list[float]] = []
    trajectory: list[TrajectoryPoint] = []
    clocks = bag_clock_offsets(path, topics, params.transform_tolerance)
    for note in clocks.notes:
        (warn or (lambda text: None))(note)
    total = None
    if progress:
        total = sum(n for _, n in bag_topics(path).values())
    messages: Any = read_bag(
        path, topics=topics, on_error="skip", dropped=bag_dropped, kinds=_REPLAYED
    )
    if progress:
        from tqdm import tqdm

        messages = tqdm(messages, total=total, desc="replay", unit="msg")
    n_scans = 0
    received = 0.0

    def keep(outs: list[Outputs]) -> None:
        for out in outs:
            if out.used:
                est = out.estimate
                trajectory.append(
                    TrajectoryPoint(
                        out.stamp, est.status.value, est.pose, out.best_estimate, est.reason
                    )
                )

    for raw in messages:
        m = restamped(raw, clocks.shift(raw.kind))
        received = m.log_time * 1e-9  # the recorder's clock: when the message arrived
        if m.kind == "scan":
            n_scans += 1
            keep(core.offer_scan(m.value, received, received=received))
        elif m.kind == "odom":
            core.add_odometry(m.value, received=received)
            keep(core.ready_scans(received))
        elif m.kind == "image":
            core.add_image(m.value, m.stamp, received=received)
        elif m.kind == "map":
            if grid is None:
                core.set_map(m.value)
        elif m.kind == "truth":
            truth.append([m.stamp, *m.value.pose])
        elif m.kind == "initialpose":
            pose, cov = m.value
            core.set_initial_pose(pose, cov)
    # the bag ended: scans still waiting for odometry get none
    keep(core.ready_scans(received + core.params.transform_tolerance + 1.0))
    store = getattr(core.localizer, "places", None)
    if store is not None and hasattr(store, "visual_map"):
        store.visual_map.close()
    dropped = dict(core.dropped)
    for topic, n in bag_dropped.items():
        dropped[f"{topic}: malformed in bag"] = n
    return ReplayResult(
        trajectory=trajectory,
        truth=np.array(truth).reshape(-1, 4),
        grid=core.grid,
        final=core.last.estimate if core.last is not None else None,
        dropped=dropped,
        received=dict(core.received),
        steps=list(getattr(core.localizer, "log", [])),
        particles=core._particles() if core.localizer is not None else None,
        recovered=dict(core.recovered),
        pauses=core.pauses,
        scans=n_scans,
        clock_notes=list(clocks.notes),
    )


def bag_clock_offsets(path: str | Path, topics: BagTopics | None, tolerance: float) -> ClockOffsets:
    """The streams of the bag on another clock than its odometry (:mod:`symloc.io.bag_clocks`),
    from a first pass over its scans and odometry (images are not decoded for it)."""
    wanted = dataclasses.replace(topics or BagTopics(), truth=None)
    kinds = ("scan", "odom")
    # the replay's own pass reports the skipped messages: this one stays quiet
    messages = read_bag(path, topics=wanted, on_error="skip", report_skips=False)
    lags = stream_lags(m for m in messages if m.kind in kinds)
    return clock_offsets(lags, tolerance)


def restamped(m: BagMessage, shift: float) -> BagMessage:
    """``m`` with its stamp moved by ``shift`` [s] (a scan's own stamp too); ``m`` if 0."""
    if shift == 0.0:
        return m
    value = m.value
    if m.kind == "scan":
        value = value.with_ranges(value.ranges, stamp=value.stamp + shift)
    return dataclasses.replace(m, stamp=m.stamp + shift, value=value)


@dataclass(frozen=True)
class ScansWithOdometry:
    """A bag's scans paired with the odometry at their stamps, for mapping.

    ``scans`` in time order (mirrored when the laser is mounted upside down); ``odometry``
    (N, 3) x [m], y [m], theta [rad] of the robot's base in the odometry frame at each scan;
    ``dropped`` messages left out per reason; ``total`` scans in the bag; ``clock_notes``
    streams re-stamped onto the odometry's clock; ``readings`` every odometry reading of the
    bag (to look up the odometry at other stamps, e.g. images'); ``source`` where the odometry
    came from (``topic /odom``, ``TF odom -> base_footprint``); ``mount`` (3,)
    ``base_from_laser`` in the plane (zeros when ``/tf_static`` does not link the laser to the
    base); ``laser_frame`` the scans' frame.
    """

    scans: list[Any]
    odometry: FloatArray
    dropped: dict[str, int]
    total: int
    clock_notes: list[str]
    readings: OdometryBuffer = field(default_factory=OdometryBuffer)
    source: str = ""
    mount: FloatArray = field(default_factory=lambda: np.zeros(3))
    laser_frame: str = ""

    @property
    def laser_odometry(self) -> FloatArray:
        """(N, 3) the laser's pose in the odometry frame at each scan (what SLAM takes: its
        sensor frame is the robot frame): :attr:`odometry` composed with :attr:`mount`."""
        if not np.any(self.mount):
            return self.odometry
        return np.asarray(compose(self.odometry, self.mount), dtype=np.float64).reshape(-1, 3)


#: Where a bag's odometry may come from (:func:`pair_scans_offline`).
ODOM_SOURCES = ("auto", "topic", "tf")


def pair_scans_offline(
    path: str | Path,
    *,
    topics: BagTopics | None = None,
    transform_tolerance: float = 1.0,
    odom_source: str = "auto",
    odom_frame: str = "odom",
    base_frame: str = "",
) -> ScansWithOdometry:
    """Every scan of the bag with the odometry pose at its stamp, knowing the whole bag.

    Unlike the live node, mapping may look ahead: each scan gets the odometry interpolated at
    its stamp from the readings on both sides, whenever in the bag they were recorded (odometry
    at another rate than the scans, late or in bursts). Odometry readings whose stamp is older
    than an earlier reading's are outliers and left out; a scan stamped before the previous
    scan is left out (mapping needs time order); a scan within ``transform_tolerance`` [s]
    before the first or after the last reading takes that reading, one further away gets none.
    Streams on another clock than the odometry's are re-stamped first
    (:mod:`symloc.io.bag_clocks`). Each is counted in ``dropped``.

    The odometry comes from the bag's nav_msgs/Odometry topic (``odom_source="topic"``) or
    from the ``odom_frame -> base_frame`` transforms on ``/tf`` (``"tf"``; ``base_frame`` ""
    takes the frame the odometry frame's transforms lead to); ``"auto"`` takes the topic when
    the bag has one, else TF. When ``/tf_static`` links the scans' frame to the base, the
    laser's mount is returned (:attr:`ScansWithOdometry.mount`), and the scans of a laser
    mounted upside down are mirrored.

    Raises
    ------
    DataFormatError
        ``odom_source`` is not one of :data:`ODOM_SOURCES`, the odometry it names is not in
        the bag (naming the bag, the topic or frames, and what it holds), or the laser's scan
        plane is tilted.
    """
    if odom_source not in ODOM_SOURCES:
        raise DataFormatError(f"odom_source: expected one of {ODOM_SOURCES}, got {odom_source!r}")
    wanted = dataclasses.replace(topics or BagTopics(), truth=None)
    dropped: Counter[str] = Counter()
    kinds = ("scan", "odom", "tf_static") + (() if odom_source == "topic" else ("tf",))
    messages = list(read_bag(path, topics=wanted, on_error="skip", dropped=dropped, kinds=kinds))
    odom_topics = sorted({m.topic for m in messages if m.kind == "odom"})
    use_tf = odom_source == "tf" or (odom_source == "auto" and not odom_topics)
    tree = TransformTree()
    for m in messages:
        if m.kind == "tf_static":
            for t in m.value:
                tree.add(t, static=True)
    if use_tf and odom_source == "auto" and not any(m.kind == "tf" for m in messages):
        raise DataFormatError(
            f"bag {path}: expected odometry, on a nav_msgs/Odometry topic or as {odom_frame} ->"
            f" base transforms on /tf; the bag has neither (topics: {sorted(bag_topics(path))})"
        )
    if use_tf:
        messages, source = _tf_odometry(path, messages, tree, odom_frame, base_frame)
    elif not odom_topics:
        raise DataFormatError(
            f"bag {path}: expected odometry on a nav_msgs/Odometry topic"
            f"{f' ({wanted.odom})' if wanted.odom else ''}, found none"
            f" (topics: {sorted(bag_topics(path))}); record /odom, or /tf with {odom_frame} ->"
            " base"
        )
    else:
        source = f"topic {odom_topics[0]}"
    messages = [m for m in messages if m.kind in ("scan", "odom")]
    clocks = clock_offsets(stream_lags(messages), transform_tolerance)
    buf = OdometryBuffer()
    raw_scans: list[Any] = []
    for m in messages:
        m = restamped(m, clocks.shift(m.kind))
        if m.kind == "odom":
            if not buf.add(m.value, max_age=math.inf):
                dropped["odom: stamp went backwards"] += 1
        else:
            raw_scans.append(m.value)
    laser_frame = raw_scans[0].frame_id if raw_scans else ""
    mount = np.zeros(3)
    upside_down = False
    if use_tf:
        bases = [source.rpartition("-> ")[2]]
    else:
        bases = [base_frame] if base_frame else ["base_footprint", "base_link"]
    for base in bases:
        m44 = tree.lookup(base, laser_frame) if laser_frame and laser_frame != base else None
        if m44 is None:
            continue
        lm = laser_mount(m44)
        if not lm.level:
            raise DataFormatError(
                f"bag {path}: the scan plane of {laser_frame} is tilted"
                f" {math.degrees(lm.tilt):.0f} deg from the floor (/tf_static {base} ->"
                f" {laser_frame}); a 2D map needs a level laser"
            )
        mount, upside_down = lm.pose, lm.upside_down
        break
    scans: list[Any] = []
    odom: list[FloatArray] = []
    last = -math.inf
    for scan in raw_scans:
        if scan.stamp < last:
            dropped["scan: stamp went backwards"] += 1
            continue
        reading = buf.at(scan.stamp, transform_tolerance)
        if (
            isinstance(reading, str)
            and buf.stamps
            and 0 < buf.stamps[0] - scan.stamp <= transform_tolerance
        ):
            reading = OdometryReading(buf.poses[0], buf.stamps[0])  # as after the last reading
        if isinstance(reading, str):
            dropped[f"scan: {reading}"] += 1
            continue
        last = scan.stamp
        scans.append(mirror(scan) if upside_down else scan)
        odom.append(np.asarray(reading.pose))
    return ScansWithOdometry(
        scans,
        np.asarray(odom, dtype=np.float64).reshape(-1, 3),
        dict(dropped),
        len(raw_scans),
        list(clocks.notes),
        readings=buf,
        source=source,
        mount=np.asarray(mount, dtype=np.float64),
        laser_frame=laser_frame,
    )


def _tf_odometry(
    path: str | Path,
    messages: list[BagMessage],
    tree: TransformTree,
    odom_frame: str,
    base_frame: str,
) -> tuple[list[BagMessage], str]:
    """``messages`` with the bag's odometry topic replaced by ``odom_frame -> base_frame``
    readings from ``/tf`` (kind ``odom``), and where they came from (``TF odom -> base``)."""
    tf_msgs = [m for m in messages if m.kind == "tf"]
    children = Counter(t.child for m in tf_msgs for t in m.value if t.parent == odom_frame)
    if not children:
        parents = sorted({f"{t.parent} -> {t.child}" for m in tf_msgs for t in m.value})
        raise DataFormatError(
            f"bag {path}: expected odometry as {odom_frame} -> base transforms on /tf, found"
            f" {'no /tf messages' if not tf_msgs else 'only ' + ', '.join(parents[:6])};"
            " record /odom (nav_msgs/Odometry) or /tf, or name the odometry frame"
        )
    base = base_frame or children.most_common(1)[0][0]
    out: list[BagMessage] = []
    for m in messages:
        if m.kind == "odom":
            continue
        if m.kind != "tf":
            out.append(m)
            continue
        for t in m.value:
            tree.add(t, static=False)
            reading = odometry_from_transform(t, tree, odom_frame=odom_frame, base_frame=base)
            if reading is not None:
                out.append(dataclasses.replace(m, kind="odom", stamp=t.stamp, value=reading))
    if not any(m.kind == "odom" for m in out):
        raise DataFormatError(
            f"bag {path}: /tf has {odom_frame} -> {sorted(children)} but none leads to the base"
            f" frame {base!r} (through /tf_static); name the base frame"
        )
    return out, f"TF {odom_frame} -> {base}"


def scans_with_odometry(
    path: str | Path, *, topics: BagTopics | None = None, transform_tolerance: float = 1.0
) -> tuple[list[Any], FloatArray, dict[str, int]]:
    """The bag's scans and the odometry pose (N, 3) at each scan's stamp (interpolated);
    the scans left out are counted in the returned ``dropped`` dict (reason -> count).
    See :func:`pair_scans_offline`."""
    got = pair_scans_offline(path, topics=topics, transform_tolerance=transform_tolerance)
    return got.scans, got.odometry, got.dropped


#: Share of a bag's scans that must pair with odometry for a map to be built from it.
MIN_PAIRED_SHARE = 0.8


@dataclass(frozen=True)
class BagMap:
    """A map built from a bag: ``slam`` the :class:`symloc.slam.slam.SlamResult` (``.grid``,
    ``.poses`` (N, 3) the laser's poses in the map frame), ``stamps`` (N,) [s] of the scans used, ``paired`` how
    the scans were paired with odometry."""

    slam: Any
    stamps: FloatArray
    paired: ScansWithOdometry


def build_map_from_bag(
    path: str | Path, *, topics: BagTopics | None = None, slam_params: Any = None
) -> BagMap:
    """Build the occupancy grid from a bag's scans and odometry with symloc's SLAM
    (the scans paired by :func:`pair_scans_offline`).

    Raises
    ------
    DataFormatError
        Fewer than two scans pair with odometry, or fewer than :data:`MIN_PAIRED_SHARE` of
        the bag's scans do (the map would be built from a fraction of the recording; the
        message names the reasons).
    """
    from symloc.slam.slam import run_slam  # lazy: the SLAM stack (GTSAM) only for --build-map

    got = pair_scans_offline(path, topics=topics)
    n = len(got.scans)
    if n < 2 or n < MIN_PAIRED_SHARE * got.total:
        raise DataFormatError(
            f"bag {path}: expected scans with odometry at their stamps to build a map (at least"
            f" {100 * MIN_PAIRED_SHARE:.0f} % of the bag's scans), got {n} of {got.total} (dropped:"
            f" {got.dropped or 'none'}); check --odom-topic and that scans and odometry come"
            " from one clock"
        )
    slam = run_slam(got.scans, got.laser_odometry, slam_params, progress=True, desc="slam (bag)")
    stamps = np.array([s.stamp for s in got.scans], dtype=np.float64)
    return BagMap(slam, stamps, got)
