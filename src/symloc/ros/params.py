"""Parameters of the symloc ROS 2 node: nav2-style YAML -> a frozen, validated dataclass.

The file has the layout of a nav2 ``params.yaml``::

    symloc:                      # the node name (or /** for every node)
      ros__parameters:
        global_frame_id: map
        odom_frame_id: odom
        base_frame_id: base_link
        scan_topic: scan
        visual_map: /data/places.db
        mode: localize           # or build_visual_map
        amcl:                    # nav2_amcl names and defaults (symloc.mcl.AmclParams)
          max_particles: 2000
          laser_model_type: likelihood_field
        confidence:              # symloc.mcl.ConfidenceConfig fields
          min_weight_share: 0.9
        claim:                   # symloc.localizer.claim.ClaimConfig fields
          gate_sigmas: 4.0
        localizer:               # symloc.localizer.LocalizerConfig fields
          flip_patience: 5
        symmetry: {}             # symloc.symmetry.SymmetryConfig fields over lidar_preset's

The localizer's settings (:class:`symloc.localizer.settings.LocalizerSettings`, what
:meth:`NodeParams.settings` returns and :func:`symloc.localizer.build.build_localizer` builds
from) are the blocks ``amcl``, ``confidence``, ``claim``, ``localizer`` and ``symmetry``
(with ``lidar_preset``), ``laser_pose``, ``seed`` and ``mode`` (``build_visual_map`` is
``localizer.allow_mapping``, which is not a parameter of its own). ``localizer.converged_weight``,
``converged_xy_std`` and ``converged_theta_std`` are the older names of
``confidence.min_weight_share``, ``max_xy_std`` and ``max_theta_std`` (:data:`ALIASES`): the
confidence judgement decides convergence. The other fields are the node's plumbing.

Every value is checked; an unknown or invalid one raises
:class:`~symloc.errors.ConfigurationError` naming it. Nothing is reset to a default.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from symloc.camera_model import check_dist_coeffs
from symloc.errors import ConfigurationError
from symloc.files.bounded import MAX_PARAMS_FILE_BYTES, load_yaml_bounded, read_text_bounded
from symloc.grid.map_io import MAX_MAP_PIXELS
from symloc.image_header import MAX_PHOTO_PIXELS as MAX_IMAGE_PIXELS
from symloc.localizer import LocalizerConfig
from symloc.localizer.claim import ClaimConfig
from symloc.localizer.settings import LocalizerSettings
from symloc.mcl.confidence import ConfidenceConfig
from symloc.mcl.params import AmclParams

__all__ = [
    "ALIASES",
    "MODES",
    "NOT_PARAMETERS",
    "SETTINGS_BLOCKS",
    "NodeParams",
    "config_block",
    "split_aliases",
]

MODES = ("localize", "build_visual_map")

#: Blocks of :class:`NodeParams` that are localizer settings, with their classes (``symmetry``
#: is a mapping of :class:`symloc.symmetry.SymmetryConfig` overrides of ``lidar_preset``).
SETTINGS_BLOCKS: dict[str, type[Any]] = {
    "amcl": AmclParams,
    "confidence": ConfidenceConfig,
    "claim": ClaimConfig,
    "localizer": LocalizerConfig,
}

#: Older parameter names -> the settings leaf they set (the confidence judgement decides
#: convergence; :class:`LocalizerConfig`'s fields of those names, while they exist, are unused).
ALIASES: dict[str, str] = {
    "localizer.converged_weight": "confidence.min_weight_share",
    "localizer.converged_xy_std": "confidence.max_xy_std",
    "localizer.converged_theta_std": "confidence.max_theta_std",
}

#: Settings leaves that are not parameters of their own (``mode`` sets allow_mapping; the
#: aliased names set the confidence fields).
NOT_PARAMETERS = frozenset({"localizer.allow_mapping", *ALIASES})


def config_block(name: str, cls: type[Any], block: Any) -> Any:
    """``cls(**block)`` from a ``name:`` mapping of its fields (an unknown or invalid field
    raises ConfigurationError naming ``name.field``)."""
    if isinstance(block, cls):
        return block
    if block is None:
        block = {}
    if not isinstance(block, dict):
        raise ConfigurationError(f"{name}: expected a mapping of {cls.__name__} fields")
    if cls is AmclParams:
        return _block(name, lambda: AmclParams.from_dict(block))
    known = {f.name for f in fields(cls)}
    if name == "localizer":
        known -= {"allow_mapping", *(a.partition(".")[2] for a in ALIASES)}
    bad = sorted(set(block) - known)
    if bad:
        if name == "localizer" and bad[0] == "allow_mapping":
            raise ConfigurationError(
                "localizer.allow_mapping: set by 'mode' (build_visual_map maps new places)"
            )
        raise ConfigurationError(f"{name}.{bad[0]}: unknown (known: {sorted(known)})")
    values = {k: tuple(v) if isinstance(v, list) else v for k, v in block.items()}
    return _block(name, lambda: cls(**values))


def split_aliases(localizer: dict[str, Any], confidence: dict[str, Any]) -> None:
    """Move the aliased ``localizer`` names (:data:`ALIASES`) into ``confidence`` (in place).

    Raises
    ------
    ConfigurationError
        An alias and its target are both given, with different values.
    """
    for alias, target in ALIASES.items():
        old, new = alias.partition(".")[2], target.partition(".")[2]
        if old not in localizer:
            continue
        value = localizer.pop(old)
        if new in confidence and confidence[new] != value:
            raise ConfigurationError(
                f"{alias}: the older name of {target}, which is also given, differently"
            )
        confidence[new] = value


def _pose3(value: Any, name: str) -> tuple[float, float, float]:
    """``(x, y, yaw)`` from a sequence of 3 numbers, or nav2's ``{x, y, z, yaw}`` mapping."""
    if isinstance(value, dict):
        unknown = sorted(set(value) - {"x", "y", "z", "yaw"})
        if unknown:
            raise ConfigurationError(f"{name}.{unknown[0]}: unknown (expected x, y, z, yaw)")
        value = (value.get("x", 0.0), value.get("y", 0.0), value.get("yaw", 0.0))
    if (
        isinstance(value, (str, bytes))
        or not hasattr(value, "__len__")
        or len(value) != 3
        or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in value
        )
    ):
        raise ConfigurationError(
            f"{name}: expected 3 numbers x [m], y [m], yaw [rad], got {value!r}"
        )
    x, y, yaw = (float(v) for v in value)
    return (x, y, yaw)


def _block(name: str, build: Any) -> Any:
    """``build()``, with a value of the wrong type reported as a ConfigurationError."""
    try:
        return build()
    except (TypeError, ValueError, OverflowError) as err:
        if isinstance(err, ConfigurationError):
            raise
        raise ConfigurationError(f"{name}: {err}") from err


def _topic(value: Any, name: str) -> str:
    if not isinstance(value, str) or not value or any(c.isspace() for c in value):
        raise ConfigurationError(f"{name}: expected a topic name without spaces, got {value!r}")
    return value


def _frame(value: Any, name: str, *, allow_empty: bool = False) -> str:
    if not isinstance(value, str) or (not value and not allow_empty):
        raise ConfigurationError(f"{name}: expected a frame id string, got {value!r}")
    return value.lstrip("/")


@dataclass(frozen=True)
class NodeParams:
    """Settings of ``symloc ros node`` (topics are relative, so namespaces and remapping apply).

    Attributes
    ----------
    global_frame_id, odom_frame_id, base_frame_id : str
        Frames of the map, of odometry (``Odometry.header.frame_id``) and of the robot
        (``Odometry.child_frame_id``). Messages in another frame are dropped and counted.
    laser_frame_id, camera_frame_id : str
        Frame a scan / an image must carry; empty accepts any (the sensors sit at the base
        origin looking along +x, as in the paper, unless TF or ``laser_pose`` says otherwise).
    laser_pose_source : {"tf", "parameters"}
        Where the laser's mount comes from: ``base_frame_id -> <scan frame>`` on
        ``/tf_static`` (as nav2_amcl; scans wait for it), or ``laser_pose`` and
        ``laser_upside_down`` (also what a bag replay without TF uses).
    laser_pose : sequence of 3 floats
        Where the laser sits on the robot, ``x [m], y [m], yaw [rad]`` in the base frame.
        With ``laser_upside_down`` the laser is mounted upside down (its scans are mirrored)
        and ``yaw`` is the heading of its x axis.
    scan_topic, odom_topic, map_topic, image_topic, compressed_image_topic, initialpose_topic
        Inputs. An empty ``image_topic`` or ``compressed_image_topic`` is not subscribed.
    amcl_pose_topic, particle_cloud_topic, status_topic, candidates_topic, goal_topic,
    capture_topic, axis_pose_topic : str
        Outputs (see :mod:`symloc.ros.node`). ``axis_pose_topic`` carries the pose of status
        ``axis`` (a corridor: heading known, position along its axis not; never on
        ``amcl_pose``).
    publish_goals : bool
        Publish the localizer's requests to move the robot (go to a centre, face a direction,
        rotate) as geometry_msgs/PoseStamped in the odometry frame on ``goal_topic``
        (``symloc/goal``). Off by default: a localization node does not command the robot;
        the requests are always in ``symloc/status``. To hand them to a navigator, enable it
        and point ``goal_topic`` at what drives the robot (see the node's README).
    sensor_qos : {"best_effort", "reliable"}
        Reliability of the scan, odometry and image subscriptions (nav2 uses best effort).
    mode : {"localize", "build_visual_map"}
        ``build_visual_map`` lets the localizer map places that match no stored one.
    visual_map : str
        Path of the SQLite visual map (``""``: none; with ``build_visual_map`` it is created).
    vocabulary : str
        ORB bag-of-words vocabulary file (symloc binary or DBoW2 text); ``""``: the shipped
        one. It must be the vocabulary the visual map was built with.
    camera_intrinsics : sequence of 4 floats
        ``fx, fy, cx, cy`` [px] of the camera; empty: the simulator's 640 x 480, 65 deg camera.
    camera_dist_coeffs : sequence of 4 or 5 floats
        The lens distortion ``k1, k2, p1, p2[, k3]`` (OpenCV / camera_info ``plumb_bob`` order)
        from the camera's calibration; empty: none. Keypoints are undistorted before the
        orientation decision's homographies.
    lidar_preset : str
        ``lds01``, ``rplidar_a2`` or ``paper_15m``: sets Algorithm 1's range noise from the
        scanner's data sheet; ``""``: Algorithm 1's defaults.
    map_yaml : str
        A map_server YAML to load at start-up instead of waiting for the map topic.
    transform_tolerance : float
        Largest gap [s] between a scan and the newest odometry before it is used; the
        ``map -> odom`` transform is stamped this far after its scan (nav2's meaning).
    tf_broadcast : bool
        Broadcast ``map -> odom`` on ``/tf`` once a pose is earned (nav2's name; see
        :mod:`symloc.ros.tf` for what is sent while the pose is not earned).
    first_map_only : bool
        Use the first map received and ignore every later one (nav2's name). Otherwise every
        new map rebuilds the localizer on it, the pose held kept (re-seeded, carried by
        odometry, and confirmed by the claim gate on the new map). The older
        ``accept_map_updates`` is retired: accepted with a warning, without effect.
    max_odom_age : float
        How much odometry history [s] is kept for interpolating at scan stamps.
    odom_source : {"tf", "topic"}
        Odometry from ``odom_frame_id -> base_frame_id`` on ``/tf``, as nav2_amcl reads it
        (needs ``tf2_msgs``: ``symloc ros setup``), or from ``nav_msgs/Odometry`` on
        ``odom_topic``.
    set_initial_pose, initial_pose : bool, sequence of 3 floats
        nav2's names: on activation, seed the filter at ``initial_pose`` = x [m], y [m],
        yaw [rad] (in a nav2 file the block ``initial_pose: {x, y, z, yaw}``; z is ignored).
    always_reset_initial_pose : bool
        nav2's name: on activation, forget the last pose instead of resuming from it.
    save_pose_rate : float
        nav2's name: how often [Hz] the last published pose is written to
        ``saved_pose_filepath`` while active (<= 0: never).
    initialize_at_saved_pose, saved_pose_filepath : bool, str
        nav2's names (main branch): on activation, seed the filter at the pose saved there
        (activation fails when the file is missing, as in nav2).
    bond_heartbeat_period : float
        nav2's name: the period [s] of the bond heartbeat to nav2's lifecycle manager while
        active (<= 0: no bond; then set the manager's ``bond_timeout`` to 0).
    autostart_node : bool
        nav2's name (main branch): configure and activate at start-up, without a lifecycle
        manager.
    max_stamp_jump : float
        A scan, odometry or image stamp further than this [s] from the node's clock (the last
        accepted stamp) is dropped, not adopted; three such stamps in a row that agree, from
        every sensor stream, are a clock jump and become the new time base
        (:mod:`symloc.ros.guards`).
    max_odom_speed : float
        Odometry that moves faster than this [m/s] between readings is dropped; three readings
        in a row that agree are an odometry reset, which the node absorbs (the localizer sees
        no motion across it).
    max_image_pixels : int
        Camera images of more pixels are refused before decoding (compressed ones by the size
        their header declares); at most 50,000,000 (3 bytes per decoded pixel).
    max_map_cells : int
        Maps on the map topic of more cells (``width x height``) are refused before their data
        is read, as map files are (default and largest 64 Mi cells, 8,192 x 8,192).
    seed : int
        Seed of the filter's random numbers (nav2's ``random_seed`` >= 0 sets it).
    amcl : AmclParams
        The filter (nav2_amcl's names).
    confidence : ConfidenceConfig
        When AMCL's estimate counts as converged (weight share, x-y std [m], heading std
        [rad]), the scan check and the rival search (:mod:`symloc.mcl.confidence`).
    claim : ClaimConfig
        The claim gate (:mod:`symloc.localizer.claim`).
    localizer : LocalizerConfig
        The state machine; its ``allow_mapping`` is set by ``mode``.
    symmetry : dict
        Fields of :class:`symloc.symmetry.SymmetryConfig` overriding the preset's.
    """

    global_frame_id: str = "map"
    odom_frame_id: str = "odom"
    base_frame_id: str = "base_link"
    laser_frame_id: str = ""
    camera_frame_id: str = ""
    laser_pose_source: str = "tf"
    laser_pose: tuple[float, ...] = (0.0, 0.0, 0.0)
    laser_upside_down: bool = False
    scan_topic: str = "scan"
    odom_topic: str = "odom"
    map_topic: str = "map"
    image_topic: str = "camera/image_raw"
    compressed_image_topic: str = "camera/image_raw/compressed"
    initialpose_topic: str = "initialpose"
    amcl_pose_topic: str = "amcl_pose"
    particle_cloud_topic: str = "particle_cloud"
    status_topic: str = "symloc/status"
    candidates_topic: str = "symloc/candidates"
    goal_topic: str = "symloc/goal"
    publish_goals: bool = False
    capture_topic: str = "symloc/capture_request"
    axis_pose_topic: str = "symloc/axis_pose"
    sensor_qos: str = "best_effort"
    mode: str = "localize"
    visual_map: str = ""
    vocabulary: str = ""
    camera_intrinsics: tuple[float, ...] = ()
    camera_dist_coeffs: tuple[float, ...] = ()
    lidar_preset: str = ""
    map_yaml: str = ""
    transform_tolerance: float = 1.0
    tf_broadcast: bool = True
    first_map_only: bool = False
    max_odom_age: float = 10.0
    odom_source: str = "tf"
    set_initial_pose: bool = False
    initial_pose: tuple[float, ...] = (0.0, 0.0, 0.0)
    always_reset_initial_pose: bool = False
    save_pose_rate: float = 0.5
    initialize_at_saved_pose: bool = False
    saved_pose_filepath: str = "/tmp/amcl_saved_pose"
    bond_heartbeat_period: float = 0.25
    autostart_node: bool = False
    max_stamp_jump: float = 5.0
    max_odom_speed: float = 10.0
    max_image_pixels: int = 5_000_000
    max_map_cells: int = MAX_MAP_PIXELS
    seed: int = 0
    amcl: AmclParams = field(default_factory=AmclParams)
    confidence: ConfidenceConfig = field(default_factory=ConfidenceConfig)
    claim: ClaimConfig = field(default_factory=ClaimConfig)
    localizer: LocalizerConfig = field(default_factory=LocalizerConfig)
    symmetry: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("global_frame_id", "odom_frame_id", "base_frame_id"):
            object.__setattr__(self, name, _frame(getattr(self, name), name))
        for name in ("laser_frame_id", "camera_frame_id"):
            object.__setattr__(self, name, _frame(getattr(self, name), name, allow_empty=True))
        for f in fields(self):
            if f.name.endswith("_topic"):
                value = getattr(self, f.name)
                if f.name in ("image_topic", "compressed_image_topic") and value == "":
                    continue
                _topic(value, f.name)
        if self.sensor_qos not in ("best_effort", "reliable"):
            raise ConfigurationError(
                f"sensor_qos: expected 'best_effort' or 'reliable', got {self.sensor_qos!r}"
            )
        if self.mode not in MODES:
            raise ConfigurationError(f"mode: expected one of {MODES}, got {self.mode!r}")
        if not isinstance(self.camera_intrinsics, (list, tuple)):
            raise ConfigurationError(
                "camera_intrinsics: expected a list of 4 numbers fx, fy, cx, cy [px], got"
                f" {self.camera_intrinsics!r}"
            )
        intr = tuple(self.camera_intrinsics)
        if intr and (
            len(intr) != 4
            or not all(
                isinstance(v, (int, float))
                and not isinstance(v, bool)
                and math.isfinite(v)
                and v > 0
                for v in intr
            )
        ):
            raise ConfigurationError(
                f"camera_intrinsics: expected 4 numbers fx, fy, cx, cy > 0 [px], got {intr!r}"
            )
        object.__setattr__(self, "camera_intrinsics", tuple(float(v) for v in intr))
        for name in ("laser_pose", "initial_pose"):
            object.__setattr__(self, name, _pose3(getattr(self, name), name))
        if not isinstance(self.laser_upside_down, bool):
            raise ConfigurationError(
                f"laser_upside_down: expected true/false, got {self.laser_upside_down!r}"
            )
        dist = self.camera_dist_coeffs
        if isinstance(dist, (str, bytes)) or any(isinstance(v, bool) for v in dist):
            raise ConfigurationError(
                f"camera_dist_coeffs: expected 4 or 5 numbers k1, k2, p1, p2[, k3], got {dist!r}"
            )
        if tuple(dist):
            object.__setattr__(
                self, "camera_dist_coeffs", check_dist_coeffs(dist, "camera_dist_coeffs")
            )
        else:
            object.__setattr__(self, "camera_dist_coeffs", ())
        if self.lidar_preset not in ("", "lds01", "rplidar_a2", "paper_15m"):
            raise ConfigurationError(
                "lidar_preset: expected '', 'lds01', 'rplidar_a2' or 'paper_15m',"
                f" got {self.lidar_preset!r}"
            )
        if not isinstance(self.symmetry, dict):
            raise ConfigurationError("symmetry: expected a mapping of SymmetryConfig fields")
        self.symmetry_config()  # validates the block
        for name in ("visual_map", "map_yaml", "vocabulary"):
            if not isinstance(getattr(self, name), str):
                raise ConfigurationError(f"{name}: expected a path string")
        if self.laser_pose_source not in ("tf", "parameters"):
            raise ConfigurationError(
                f"laser_pose_source: expected 'tf' or 'parameters', got {self.laser_pose_source!r}"
            )
        if self.odom_source not in ("tf", "topic"):
            raise ConfigurationError(
                f"odom_source: expected 'tf' or 'topic', got {self.odom_source!r}"
            )
        for name in ("save_pose_rate", "bond_heartbeat_period"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ConfigurationError(f"{name}: expected a number, got {v!r}")
            object.__setattr__(self, name, float(v))
        if not isinstance(self.saved_pose_filepath, str) or not self.saved_pose_filepath:
            raise ConfigurationError(
                f"saved_pose_filepath: expected a file path, got {self.saved_pose_filepath!r}"
            )
        for name in (
            "tf_broadcast",
            "first_map_only",
            "set_initial_pose",
            "always_reset_initial_pose",
            "initialize_at_saved_pose",
            "autostart_node",
        ):
            if not isinstance(getattr(self, name), bool):
                raise ConfigurationError(
                    f"{name}: expected true/false, got {getattr(self, name)!r}"
                )
        if not isinstance(self.publish_goals, bool):
            raise ConfigurationError(
                f"publish_goals: expected true/false, got {self.publish_goals!r}"
            )
        for name in ("transform_tolerance", "max_odom_age", "max_stamp_jump", "max_odom_speed"):
            v = getattr(self, name)
            if (
                isinstance(v, bool)
                or not isinstance(v, (int, float))
                or not math.isfinite(v)
                or v <= 0
            ):
                unit = "m/s" if name == "max_odom_speed" else "s"
                raise ConfigurationError(f"{name}: expected a number > 0 {unit}, got {v!r}")
            object.__setattr__(self, name, float(v))
        px = self.max_image_pixels
        if isinstance(px, bool) or not isinstance(px, int) or not 1 <= px <= MAX_IMAGE_PIXELS:
            raise ConfigurationError(
                f"max_image_pixels: expected an integer in [1, {MAX_IMAGE_PIXELS:,}] (a decoded"
                f" image holds 3 bytes per pixel), got {px!r}"
            )
        cells = self.max_map_cells
        if (
            isinstance(cells, bool)
            or not isinstance(cells, int)
            or not 1 <= cells <= MAX_MAP_PIXELS
        ):
            raise ConfigurationError(
                f"max_map_cells: expected an integer in [1, {MAX_MAP_PIXELS:,}] (the map file"
                " cap: the localizer holds several arrays of the map's size), got"
                f" {cells!r}"
            )
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigurationError(f"seed: expected an integer >= 0, got {self.seed!r}")
        for name, cls in SETTINGS_BLOCKS.items():
            if not isinstance(getattr(self, name), cls):
                raise ConfigurationError(f"{name}: expected a {cls.__name__}")
        if self.localizer.allow_mapping and not self.allow_mapping:
            raise ConfigurationError(
                "localizer.allow_mapping: set by 'mode' (build_visual_map maps new places)"
            )

    def symmetry_config(self) -> Any:
        """The :class:`symloc.symmetry.SymmetryConfig` of Algorithm 1 (preset + overrides)."""
        from symloc.symmetry import SymmetryConfig

        known = {f.name for f in fields(SymmetryConfig)}
        bad = sorted(set(self.symmetry) - known)
        if bad:
            raise ConfigurationError(f"symmetry.{bad[0]}: unknown (known: {sorted(known)})")
        try:
            if self.lidar_preset:
                from symloc.lidar_spec import PRESETS

                return SymmetryConfig.from_lidar(PRESETS[self.lidar_preset], **self.symmetry)
            return SymmetryConfig(**self.symmetry)
        except (TypeError, ValueError, OverflowError) as err:
            if isinstance(err, ConfigurationError):
                raise
            raise ConfigurationError(f"symmetry: {err}") from err

    @property
    def allow_mapping(self) -> bool:
        """Whether the localizer may build visual maps of unmatched places."""
        return self.mode == "build_visual_map"

    def settings(self) -> LocalizerSettings:
        """The localizer's settings (:class:`~symloc.localizer.settings.LocalizerSettings`):
        the blocks, ``lidar_preset`` + ``symmetry``, ``laser_pose``, ``seed``, and ``mode`` as
        ``localizer.allow_mapping``."""
        return LocalizerSettings(
            amcl=self.amcl,
            confidence=self.confidence,
            claim=self.claim,
            localizer=dataclasses.replace(self.localizer, allow_mapping=self.allow_mapping),
            symmetry=self.symmetry_config(),
            laser_pose=(self.laser_pose[0], self.laser_pose[1], self.laser_pose[2]),
            seed=self.seed,
        )

    @classmethod
    def from_settings(cls, settings: LocalizerSettings, **others: Any) -> NodeParams:
        """Node parameters whose :meth:`settings` are ``settings`` (``others``: plumbing
        fields such as ``visual_map``); Algorithm 1's settings become explicit ``symmetry``
        overrides with no ``lidar_preset``."""
        sym = {
            f.name: getattr(settings.symmetry, f.name)
            for f in fields(settings.symmetry)
            if getattr(settings.symmetry, f.name) is not None
        }
        mode = "build_visual_map" if settings.localizer.allow_mapping else "localize"
        kwargs: dict[str, Any] = {
            "amcl": settings.amcl,
            "confidence": settings.confidence,
            "claim": settings.claim,
            "localizer": settings.localizer,
            "symmetry": sym,
            "lidar_preset": "",
            "laser_pose": settings.laser_pose,
            "seed": settings.seed,
            "mode": mode,
        }
        kwargs.update(others)
        params: NodeParams = _block("parameters", lambda: cls(**kwargs))
        return params

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> NodeParams:
        """From a ``ros__parameters`` mapping (nested ``amcl``, ``confidence``, ``claim``,
        ``localizer`` and ``symmetry`` blocks)."""
        if not isinstance(values, dict):
            raise ConfigurationError("ros__parameters: expected a mapping")
        own = {f.name for f in fields(cls)}
        kwargs: dict[str, Any] = {}
        for key, value in values.items():
            if key == "use_sim_time":
                continue  # handled by rclpy itself
            if key not in own:
                raise ConfigurationError(
                    f"parameter {key!r}: unknown to symloc (known: {sorted(own)})"
                )
            kwargs[key] = value
        for name in ("localizer", "confidence"):
            if name in kwargs and not isinstance(kwargs[name] or {}, dict):
                cls_name = SETTINGS_BLOCKS[name].__name__
                raise ConfigurationError(f"{name}: expected a mapping of {cls_name} fields")
        if isinstance(kwargs.get("localizer"), dict):
            localizer = dict(kwargs["localizer"])
            confidence = dict(kwargs.get("confidence") or {})
            split_aliases(localizer, confidence)
            kwargs["localizer"] = localizer
            if confidence:
                kwargs["confidence"] = confidence
        for name, block_cls in SETTINGS_BLOCKS.items():
            if name in kwargs:
                kwargs[name] = config_block(name, block_cls, kwargs[name])
        params: NodeParams = _block("ros__parameters", lambda: cls(**kwargs))
        return params

    @classmethod
    def from_yaml(cls, source: str | Path, *, node_name: str = "symloc") -> NodeParams:
        """Read the node's ``ros__parameters`` from a nav2-style YAML file (or YAML text).

        The block is looked up under ``node_name``, ``/node_name``, any namespaced
        ``ns/node_name`` or ``/**``; a file with none of them raises.
        """
        is_file = isinstance(source, Path) or (
            isinstance(source, str) and "\n" not in source and source.endswith((".yaml", ".yml"))
        )
        if not is_file:
            return cls._from_text(str(source), node_name)
        text = read_text_bounded(
            source, MAX_PARAMS_FILE_BYTES, what="the params file", error=ConfigurationError
        )
        try:
            return cls._from_text(text, node_name)
        except ConfigurationError as err:  # say which file the bad field is in
            raise ConfigurationError(f"{source}: {err}") from err

    @classmethod
    def _from_text(cls, text: str, node_name: str) -> NodeParams:
        doc = load_yaml_bounded(text, where="params", error=ConfigurationError)
        if not isinstance(doc, dict):
            raise ConfigurationError(f"params: expected a mapping with a {node_name!r} key")
        for key, value in doc.items():
            k = str(key).strip("/")
            if k == node_name or k.endswith("/" + node_name) or k == "**":
                if not isinstance(value, dict) or "ros__parameters" not in value:
                    raise ConfigurationError(f"params {key}: expected a ros__parameters block")
                return cls.from_dict(value["ros__parameters"] or {})
        raise ConfigurationError(
            f"params: no block for node {node_name!r} (top-level keys: {sorted(map(str, doc))})"
        )
