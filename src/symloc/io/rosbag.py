"""Read ROS 1 and ROS 2 bags into symloc types, and write ROS 2 (or ROS 1) bags.

Reading uses ``rosbags.highlevel.AnyReader``, so a ROS 1 ``.bag`` file, a ROS 2 bag directory
(sqlite3 ``.db3`` or ``.mcap`` storage) or the ``.db3`` / ``.mcap`` file inside one all work,
without ROS installed. Messages come out as :class:`BagMessage` records in log-time order whose
``value`` is a symloc type:

============  ==============================  ============================================
kind          ROS message type                value
============  ==============================  ============================================
``scan``      sensor_msgs/LaserScan           :class:`symloc.scan.LaserScan`
``odom``      nav_msgs/Odometry               :class:`symloc.odometry.OdometryReading`
``image``     sensor_msgs/Image or            ``(H, W, 3)`` uint8 RGB
              sensor_msgs/CompressedImage
``map``       nav_msgs/OccupancyGrid          :class:`symloc.grid.OccupancyGrid`
``truth``     nav_msgs/Odometry (map frame)   :class:`symloc.odometry.OdometryReading`
``initialpose``  PoseWithCovarianceStamped    ``(pose (3,), covariance (3, 3))``
``tf``        tf2_msgs/TFMessage (``/tf``)    list of :class:`symloc.msgs.transform.StampedTransform`
``tf_static`` tf2_msgs/TFMessage              list of :class:`symloc.msgs.transform.StampedTransform`
              (``/tf_static``)
============  ==============================  ============================================

Topics are found by message type unless named in :class:`BagTopics` (the usual name first,
``/scan``, ``/odom``, ...); the ground truth is only read from a topic named explicitly or
called ``ground_truth``, and a topic whose name says it is a reference (``ground_truth``,
``truth``, ``gt``, ``mocap``) is never taken for the robot's odometry by type. Both TF kinds
share one message type, so they are found by name only (``/tf`` and ``/tf_static``, or the
names given); a stamp of a TF message is that of its first transform (0 when empty).

Writing (:class:`BagWriter`) produces a ROS 2 bag (sqlite3 or MCAP storage) or a ROS 1 bag
with the same topics, serialised by a rosbags typestore; the map topic is offered with
transient-local durability, as map_server publishes it.
"""

from __future__ import annotations

import contextlib
import logging
from collections import Counter
from collections.abc import Callable, Collection, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from symloc.errors import DataFormatError
from symloc.grid import OccupancyGrid
from symloc.msgs.build import build_rosbags
from symloc.msgs.grid import grid_from_msg, grid_to_fields
from symloc.msgs.header import header_stamp
from symloc.msgs.image import (
    MAX_IMAGE_PIXELS,
    compressed_image_from_msg,
    compressed_image_to_fields,
    image_from_msg,
    image_to_fields,
)
from symloc.msgs.odometry import odometry_from_msg, odometry_to_fields
from symloc.msgs.pose import pose_with_covariance_from_msg, pose_with_covariance_to_fields
from symloc.msgs.scan import scan_from_msg, scan_to_fields
from symloc.msgs.transform import tf_message_fields, transform_fields, transforms_from_msg
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan

__all__ = [
    "BagFormat",
    "BagMessage",
    "BagTopics",
    "BagWriter",
    "bag_topics",
    "read_bag",
    "resolve_bag_path",
]

BagFormat = Literal["ros2", "mcap", "ros1"]

_LOG = logging.getLogger(__name__)

#: The ``dropped`` key of a bag that turned unreadable part-way.
_UNREADABLE = "<unreadable rest of the bag>"

_TYPES = {
    "scan": ("sensor_msgs/msg/LaserScan",),
    "odom": ("nav_msgs/msg/Odometry",),
    "image": ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"),
    "map": ("nav_msgs/msg/OccupancyGrid",),
    "truth": ("nav_msgs/msg/Odometry",),
    "initialpose": ("geometry_msgs/msg/PoseWithCovarianceStamped",),
    "tf": ("tf2_msgs/msg/TFMessage",),
    "tf_static": ("tf2_msgs/msg/TFMessage",),
}

#: Kinds found by their usual name only, never by type (several kinds share the type).
_BY_NAME_ONLY = {"tf": "/tf", "tf_static": "/tf_static"}


@dataclass(frozen=True, slots=True)
class BagTopics:
    """Topic names to read; ``None`` picks the first topic of the right type (see module doc)."""

    scan: str | None = None
    odom: str | None = None
    image: str | None = None
    map: str | None = None
    truth: str | None = "ground_truth"
    initialpose: str | None = None
    tf: str | None = None
    tf_static: str | None = None


@dataclass(frozen=True, slots=True)
class BagMessage:
    """One message of a bag, converted.

    Attributes
    ----------
    kind : str
        ``scan``, ``odom``, ``image``, ``map``, ``truth``, ``initialpose``, ``tf`` or
        ``tf_static``.
    topic : str
    stamp : float
        The message's header stamp [s].
    log_time : int
        When the message was recorded [ns].
    value : object
        The symloc value (see the module docstring).
    """

    kind: str
    topic: str
    stamp: float
    log_time: int
    value: Any


class _Ros2Folder(type(Path())):  # type: ignore[misc]
    """A ROS 2 bag folder whose name ends in ``.bag`` (``ros2 bag record -o run.bag``)."""

    @property
    def suffix(self) -> str:
        return ""


def resolve_bag_path(path: str | Path) -> Path:
    """The path AnyReader takes: a ROS 1 ``.bag`` file or a ROS 2 bag directory.

    A ``.db3`` or ``.mcap`` file is accepted when its folder holds the bag's ``metadata.yaml``.

    Raises
    ------
    DataFormatError
        The path does not exist or is not a bag.
    """
    p = Path(path)
    if not p.exists():
        raise DataFormatError(f"bag: {p} does not exist")
    if p.is_dir():
        if not (p / "metadata.yaml").is_file():
            raise DataFormatError(f"bag: {p} is a folder without metadata.yaml (not a ROS 2 bag)")
        # AnyReader tells ROS 1 from ROS 2 by the ".bag" suffix; a ROS 2 folder may carry it
        return _Ros2Folder(p) if p.suffix == ".bag" else p
    if p.suffix in (".db3", ".mcap"):
        if (p.parent / "metadata.yaml").is_file():
            return p.parent
        raise DataFormatError(
            f"bag: {p.name} has no metadata.yaml beside it; pass the ROS 2 bag folder"
        )
    if p.suffix == ".bag":
        return p
    raise DataFormatError(f"bag: {p} is neither a ROS 1 .bag file nor a ROS 2 bag folder")


def _pick_topics(connections: Any, topics: BagTopics, bag: Path | None = None) -> dict[str, str]:
    """topic -> kind for the connections to read (named topics first, then by type)."""
    by_topic: dict[str, str] = {}
    for c in connections:
        by_topic.setdefault(c.topic, c.msgtype)
    chosen: dict[str, str] = {}
    for kind, types in _TYPES.items():
        wanted = getattr(topics, kind)
        if wanted is None:
            continue
        names = [wanted, "/" + wanted.lstrip("/"), wanted.lstrip("/")]
        name = next((n for n in names if n in by_topic), None)
        if name is None:
            if kind == "truth":
                continue  # optional: only simulated or motion-captured runs have it
            raise DataFormatError(
                f"bag topic {wanted!r} for {kind} not found{f' in {bag}' if bag else ''};"
                f" topics: {sorted(by_topic)}"
            )
        if by_topic[name] not in types:
            raise DataFormatError(
                f"bag topic {name}{f' in {bag}' if bag else ''}: expected"
                f" {' or '.join(types)}, got {by_topic[name]}"
            )
        chosen[name] = kind
    for kind, types in _TYPES.items():
        if getattr(topics, kind) is not None or kind == "truth":
            continue
        if kind in _BY_NAME_ONLY:
            usual = _BY_NAME_ONLY[kind]
            name = next((n for n in (usual, usual.lstrip("/")) if n in by_topic), None)
            if name is not None and by_topic[name] in types and name not in chosen:
                chosen[name] = kind
            continue
        candidates = [
            name
            for name, msgtype in by_topic.items()
            if msgtype in types and name not in chosen and not _is_reference_topic(name)
        ]
        if candidates:
            chosen[min(candidates, key=lambda n: _auto_rank(kind, n))] = kind
    return chosen


#: The usual topic names per kind, preferred when a bag has several topics of a type.
_USUAL_NAMES = {
    "scan": ("/scan",),
    "odom": ("/odom", "/odometry/filtered", "/wheel/odometry"),
    "image": ("/camera/image_raw", "/camera/image_raw/compressed", "/image_raw"),
    "map": ("/map",),
    "initialpose": ("/initialpose",),
}


def _auto_rank(kind: str, name: str) -> tuple[int, str]:
    """Sort key of a topic picked by type: the usual names first, then by name."""
    usual = _USUAL_NAMES.get(kind, ())
    key = "/" + name.lstrip("/")
    return (usual.index(key) if key in usual else len(usual), name)


def _is_reference_topic(name: str) -> bool:
    """A ground-truth topic (``ground_truth``, ``/robot/truth``, ``gt``): an Odometry too, but
    never the robot's own odometry, so never picked by type (only when named)."""
    parts = [p for p in name.lower().split("/") if p]
    return any("truth" in p or p in ("gt", "mocap") for p in parts)


def _open_reader(bag: Path) -> Any:
    from rosbags.highlevel import AnyReader

    try:
        reader = AnyReader([bag])
        reader.open()
    except Exception as err:  # rosbags raises its own family (and worse on corrupt files)
        raise DataFormatError(
            f"bag {bag}: cannot open ({type(err).__name__}: {err}); truncated or corrupt?"
        ) from err
    return reader


def _close_reader(reader: Any) -> None:
    # closing a corrupt bag may fail too; there is nothing left to save
    with contextlib.suppress(Exception):
        reader.close()


def bag_topics(path: str | Path) -> dict[str, tuple[str, int]]:
    """Every topic of a bag with its message type and message count.

    Raises
    ------
    DataFormatError
        Not a bag, or one rosbags cannot open (naming the file).
    """
    bag = resolve_bag_path(path)
    reader = _open_reader(bag)
    out: dict[str, tuple[str, int]] = {}
    try:
        for c in reader.connections:
            prev = out.get(c.topic, (c.msgtype, 0))
            out[c.topic] = (c.msgtype, prev[1] + int(c.msgcount))
    except Exception as err:  # a connection record rosbags could not make sense of
        raise DataFormatError(f"bag {bag}: unreadable connection records: {err}") from err
    finally:
        _close_reader(reader)
    return out


def _convert(kind: str, msgtype: str, msg: Any, max_pixels: int) -> tuple[float, Any]:
    if kind == "scan":
        scan = scan_from_msg(msg)
        return scan.stamp, scan
    if kind in ("odom", "truth"):
        reading = odometry_from_msg(msg)
        return reading.stamp, reading
    if kind == "image":
        where = msgtype.rsplit("/", 1)[-1]
        img = (
            compressed_image_from_msg(msg, max_pixels=max_pixels)
            if msgtype.endswith("CompressedImage")
            else image_from_msg(msg, max_pixels=max_pixels)
        )
        return header_stamp(msg, where), img
    if kind == "map":
        return header_stamp(msg, "OccupancyGrid"), grid_from_msg(msg)
    if kind in ("tf", "tf_static"):
        transforms = transforms_from_msg(msg)
        return (transforms[0].stamp if transforms else 0.0), transforms
    pose_cov = pose_with_covariance_from_msg(msg)
    return header_stamp(msg, "PoseWithCovarianceStamped"), pose_cov


def read_bag(
    path: str | Path,
    *,
    topics: BagTopics | None = None,
    on_error: Literal["raise", "skip"] = "raise",
    dropped: Counter[str] | None = None,
    max_image_pixels: int = MAX_IMAGE_PIXELS,
    kinds: Collection[str] | None = None,
    report_skips: bool = True,
) -> Iterator[BagMessage]:
    """Yield the bag's scans, odometry, images, maps, ground truth and initial poses in order.

    Parameters
    ----------
    path : str or Path
        ROS 1 ``.bag``, ROS 2 bag folder, or the ``.db3`` / ``.mcap`` inside one.
    topics : BagTopics, optional
        Which topics to read; by default the first topic of each message type.
    on_error : {"raise", "skip"}
        A malformed message raises :class:`DataFormatError` (naming the topic, the log time and
        the field), or is skipped and counted in ``dropped[topic]``. A bag that turns
        unreadable part-way (truncated, corrupt) raises, or with ``"skip"`` ends there, counted
        in ``dropped["<unreadable rest of the bag>"]``: iterating never raises with ``"skip"``
        once the bag is open. Each skip is logged at DEBUG; when the iteration ends (or is
        closed), one WARNING line sums them up: the count per topic with the first reason of
        each (:func:`skip_summary`).
    dropped : Counter, optional
        Receives the number of skipped messages per topic.
    max_image_pixels : int
        Images of more pixels are malformed messages (refused before decoding).
    kinds : collection of str, optional
        Read only these kinds (their topics are still chosen, and checked, as for all kinds);
        the others' messages are not even deserialised. Default: every kind.
    report_skips : bool
        Log the summary line (False for a pass over a bag that another pass reports).

    Raises
    ------
    DataFormatError
        Not a bag, one that cannot be opened, a named topic is missing or of the wrong type,
        or (with ``on_error="raise"``) a malformed message or an unreadable part.
    """
    if on_error not in ("raise", "skip"):
        raise DataFormatError(f"on_error: expected 'raise' or 'skip', got {on_error!r}")
    if kinds is not None and set(kinds) - set(_TYPES):
        raise DataFormatError(
            f"kinds: expected some of {sorted(_TYPES)}, got {sorted(set(kinds) - set(_TYPES))}"
        )
    bag = resolve_bag_path(path)
    reader = _open_reader(bag)
    skipped: Counter[str] = Counter()
    first: dict[str, str] = {}
    try:
        chosen = _pick_topics(reader.connections, topics or BagTopics(), bag)
        if kinds is not None:
            chosen = {t: k for t, k in chosen.items() if k in kinds}
        conns = [c for c in reader.connections if c.topic in chosen]
        try:
            records = iter(reader.messages(connections=conns))
        except Exception as err:  # rosbags on a corrupt index
            raise DataFormatError(f"bag {bag}: cannot read its messages: {err}") from err
        n_read = 0
        while True:
            try:
                conn, log_time, raw = next(records)
            except StopIteration:
                break
            except Exception as err:  # truncated or corrupt storage: the rest is lost
                text = (
                    f"bag {bag}: unreadable after {n_read} messages"
                    f" ({type(err).__name__}: {err}); truncated or corrupt?"
                )
                if on_error == "raise":
                    raise DataFormatError(text) from err
                _LOG.debug("stopped: %s", text)
                skipped[_UNREADABLE] += 1
                first[_UNREADABLE] = f"after {n_read} messages ({type(err).__name__}: {err})"
                if dropped is not None:
                    dropped[_UNREADABLE] += 1
                break
            n_read += 1
            kind = chosen[conn.topic]
            try:
                msg = reader.deserialize(raw, conn.msgtype)
                stamp, value = _convert(kind, conn.msgtype, msg, max_image_pixels)
            except Exception as err:  # wrapped into one error family
                text = f"bag {bag} topic {conn.topic} at log time {log_time} ns: {err}"
                if on_error == "raise":
                    raise DataFormatError(text) from err
                _LOG.debug("skipped: %s", text)
                skipped[conn.topic] += 1
                first.setdefault(conn.topic, f"at log time {int(log_time) * 1e-9:.3f} s: {err}")
                if dropped is not None:
                    dropped[conn.topic] += 1
                continue
            yield BagMessage(kind, conn.topic, stamp, int(log_time), value)
    finally:  # also when the caller stops early (GeneratorExit)
        _close_reader(reader)
        if report_skips and skipped:
            _LOG.warning("%s", skip_summary(bag, skipped, first))


def skip_summary(bag: str | Path, skipped: Counter[str], first: dict[str, str]) -> str:
    """One line that sums up the messages :func:`read_bag` skipped.

    Parameters
    ----------
    bag : str or Path
        The bag, as named in the line.
    skipped : Counter
        Skipped messages per topic (``"<unreadable rest of the bag>"`` for a bag that turned
        unreadable part-way).
    first : dict of str to str
        The first reason per topic.

    Returns
    -------
    str
        ``bag B: skipped N undecodable message(s): /scan 5 (first at log time 1.300 s:
        <reason>); /odom 2 (...)``, the topics by count, most first; then, if so, ``; the rest
        of the bag is unreadable after M messages (<reason>)``.
    """
    per_topic = [(t, n) for t, n in skipped.most_common() if t != _UNREADABLE]
    total = sum(n for _, n in per_topic)
    parts = [f"{t} {n} (first {first.get(t, '?')})" for t, n in per_topic]
    head = f"skipped {total} undecodable message(s): " if per_topic else ""
    if skipped[_UNREADABLE]:
        parts.append(f"the rest of the bag is unreadable {first.get(_UNREADABLE, '')}".rstrip())
    return f"bag {bag}: {head}" + "; ".join(parts)


# ------------------------------------------------------------------------------------ writing


@dataclass
class BagWriter:
    """Write symloc data as a ROS 2 bag (``ros2``: sqlite3, ``mcap``) or a ROS 1 bag.

    Use as a context manager. Topic names default to the usual ones (``scan``, ``odom``,
    ``camera/image_raw``, ``map``, ``ground_truth``); each ``write_*`` stamps the log time
    with the message's own stamp.

    Parameters
    ----------
    path : str or Path
        The bag folder (ROS 2) or ``.bag`` file (ROS 1); must not exist yet.
    fmt : {"ros2", "mcap", "ros1"}
    compressed_images : bool
        Store images as sensor_msgs/CompressedImage (PNG, lossless) instead of raw rgb8.
    """

    path: str | Path
    fmt: BagFormat = "ros2"
    compressed_images: bool = False
    scan_topic: str = "/scan"
    odom_topic: str = "/odom"
    image_topic: str = "/camera/image_raw"
    map_topic: str = "/map"
    truth_topic: str = "/ground_truth"
    initialpose_topic: str = "/initialpose"
    tf_topic: str = "/tf"
    tf_static_topic: str = "/tf_static"
    counts: Counter[str] = field(default_factory=Counter)
    _writer: Any = field(default=None, init=False, repr=False)
    _typestore: Any = field(default=None, init=False, repr=False)
    _conns: dict[str, Any] = field(default_factory=dict, init=False, repr=False)
    _serialize: Callable[[Any, str], bytes] | None = field(default=None, init=False, repr=False)
    _last_log_time: int = field(default=-1, init=False, repr=False)

    def __post_init__(self) -> None:
        if self.fmt not in ("ros2", "mcap", "ros1"):
            raise DataFormatError(f"fmt: expected 'ros2', 'mcap' or 'ros1', got {self.fmt!r}")
        if self.compressed_images and self.image_topic == "/camera/image_raw":
            self.image_topic = "/camera/image_raw/compressed"

    def __enter__(self) -> BagWriter:
        self.open()
        return self

    def __exit__(
        self, et: type[BaseException] | None, ev: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def open(self) -> None:
        """Create the bag (the path must not exist)."""
        from rosbags.typesys import Stores, get_typestore

        p = Path(self.path)
        if p.exists():
            raise DataFormatError(f"bag: {p} exists already; choose a new path")
        if self.fmt == "ros1":
            from rosbags.rosbag1 import Writer as Writer1

            self._typestore = get_typestore(Stores.ROS1_NOETIC)
            self._writer = Writer1(p)
            self._serialize = self._typestore.serialize_ros1
        else:
            from rosbags.rosbag2 import StoragePlugin, Writer

            self._typestore = get_typestore(Stores.ROS2_HUMBLE)
            plugin = StoragePlugin.MCAP if self.fmt == "mcap" else StoragePlugin.SQLITE3
            self._writer = Writer(p, version=9, storage_plugin=plugin)
            self._serialize = self._typestore.serialize_cdr
        self._writer.open()

    def close(self) -> None:
        """Finish the bag (writes the ROS 2 metadata.yaml)."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def _connection(self, topic: str, msgtype: str, *, latched: bool = False) -> Any:
        conn = self._conns.get(topic)
        if conn is not None:
            return conn
        if self._writer is None:
            raise DataFormatError("BagWriter: open() it (or use it as a context manager) first")
        if self.fmt == "ros1":
            conn = self._writer.add_connection(
                topic, msgtype, typestore=self._typestore, latching=1 if latched else None
            )
        else:
            qos = [_transient_local_qos()] if latched else []
            conn = self._writer.add_connection(
                topic, msgtype, typestore=self._typestore, offered_qos_profiles=qos
            )
        self._conns[topic] = conn
        return conn

    def write_fields(
        self,
        topic: str,
        msgtype: str,
        fields: dict[str, Any],
        stamp: float,
        *,
        latched: bool = False,
    ) -> bytes:
        """Write one message given as a field dict at log time ``stamp`` [s]; returns its bytes.

        Log times are made strictly increasing (+1 ns on a tie) so readers keep the write order.
        """
        conn = self._connection(topic, msgtype, latched=latched)
        msg = build_rosbags(self._typestore, msgtype, fields)
        assert self._serialize is not None
        raw = self._serialize(msg, msgtype)
        # strictly increasing log times keep the write order when stamps tie
        log_time = max(round(stamp * 1e9), self._last_log_time + 1)
        self._last_log_time = log_time
        self._writer.write(conn, log_time, raw)
        self.counts[topic] += 1
        return raw

    def deserialize(self, raw: bytes, msgtype: str) -> Any:
        """Deserialise bytes this writer produced (the message a reader of the bag gets)."""
        if self.fmt == "ros1":
            return self._typestore.deserialize_ros1(raw, msgtype)
        return self._typestore.deserialize_cdr(raw, msgtype)

    def write_scan(self, scan: LaserScan) -> None:
        """A sensor_msgs/LaserScan."""
        self.write_fields(
            self.scan_topic, "sensor_msgs/msg/LaserScan", scan_to_fields(scan), scan.stamp
        )

    def write_odometry(self, reading: OdometryReading, *, frame_id: str = "odom") -> None:
        """A nav_msgs/Odometry on the odometry topic."""
        fields = odometry_to_fields(reading, frame_id=frame_id)
        self.write_fields(self.odom_topic, "nav_msgs/msg/Odometry", fields, reading.stamp)

    def write_truth(self, pose: ArrayLike, stamp: float) -> None:
        """The true pose (3,) as nav_msgs/Odometry in the map frame on the ground-truth topic."""
        fields = odometry_to_fields(OdometryReading(np.asarray(pose, float), stamp), frame_id="map")
        self.write_fields(self.truth_topic, "nav_msgs/msg/Odometry", fields, stamp)

    def write_image(self, image: ArrayLike, stamp: float, *, frame_id: str = "camera") -> None:
        """An ``(H, W, 3)`` uint8 RGB image (raw rgb8, or PNG when ``compressed_images``)."""
        if self.compressed_images:
            fields = compressed_image_to_fields(image, stamp=stamp, frame_id=frame_id)
            self.write_fields(self.image_topic, "sensor_msgs/msg/CompressedImage", fields, stamp)
        else:
            fields = image_to_fields(image, stamp=stamp, frame_id=frame_id)
            self.write_fields(self.image_topic, "sensor_msgs/msg/Image", fields, stamp)

    def write_map(self, grid: OccupancyGrid, stamp: float) -> None:
        """A nav_msgs/OccupancyGrid, offered transient-local (latched) like map_server's."""
        fields = grid_to_fields(grid, stamp=stamp)
        self.write_fields(self.map_topic, "nav_msgs/msg/OccupancyGrid", fields, stamp, latched=True)

    def write_transforms(
        self,
        transforms: Sequence[tuple[str, str, ArrayLike]],
        stamp: float,
        *,
        static: bool = False,
    ) -> None:
        """A tf2_msgs/TFMessage of planar ``(parent, child, parent_from_child (3,))`` transforms
        on ``/tf`` (or ``/tf_static``, offered transient-local as tf2's static broadcaster)."""
        fields = tf_message_fields(
            transform_fields(pose, stamp=stamp, parent=parent, child=child)
            for parent, child, pose in transforms
        )
        topic = self.tf_static_topic if static else self.tf_topic
        self.write_fields(topic, "tf2_msgs/msg/TFMessage", fields, stamp, latched=static)

    def write_initialpose(self, pose: ArrayLike, covariance: ArrayLike, stamp: float) -> None:
        """A geometry_msgs/PoseWithCovarianceStamped (as RViz's 2D Pose Estimate sends)."""
        fields = pose_with_covariance_to_fields(pose, covariance, stamp=stamp)
        self.write_fields(
            self.initialpose_topic, "geometry_msgs/msg/PoseWithCovarianceStamped", fields, stamp
        )


def _transient_local_qos() -> Any:
    from rosbags.interfaces import (
        Qos,
        QosDurability,
        QosHistory,
        QosLiveliness,
        QosReliability,
        QosTime,
    )

    zero = QosTime(0, 0)
    return Qos(
        QosHistory.KEEP_LAST,
        1,
        QosReliability.RELIABLE,
        QosDurability.TRANSIENT_LOCAL,
        zero,
        zero,
        QosLiveliness.AUTOMATIC,
        zero,
        False,
    )
