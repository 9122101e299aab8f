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
        localizer:               # symloc.localizer.LocalizerConfig fields
          converged_weight: 0.9

Every value is checked; an unknown or invalid one raises
:class:`~symloc.errors.ConfigurationError` naming it. Nothing is reset to a default.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import yaml

from symloc.camera_model import check_dist_coeffs
from symloc.errors import ConfigurationError
from symloc.localizer import LocalizerConfig
from symloc.mcl.params import AmclParams

__all__ = ["MODES", "NodeParams"]

MODES = ("localize", "build_visual_map")


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
        origin looking along +x, as in the paper).
    scan_topic, odom_topic, map_topic, image_topic, compressed_image_topic, initialpose_topic
        Inputs. An empty ``image_topic`` or ``compressed_image_topic`` is not subscribed.
    amcl_pose_topic, particle_cloud_topic, status_topic, candidates_topic, goal_topic,
    capture_topic : str
        Outputs (see :mod:`symloc.ros.node`).
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
    accept_map_updates : bool
        A map whose size or origin differs from the first: rebuild the localizer on it (True),
        or drop it with a warning (False, the default; the pose is kept).
    transform_tolerance : float
        Largest gap [s] between a scan and the newest odometry before it is used.
    max_odom_age : float
        How much odometry history [s] is kept for interpolating at scan stamps.
    seed : int
        Seed of the filter's random numbers.
    amcl : AmclParams
    localizer : LocalizerConfig
    symmetry : dict
        Fields of :class:`symloc.symmetry.SymmetryConfig` overriding the preset's.
    """

    global_frame_id: str = "map"
    odom_frame_id: str = "odom"
    base_frame_id: str = "base_link"
    laser_frame_id: str = ""
    camera_frame_id: str = ""
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
    goal_topic: str = "goal_pose"
    capture_topic: str = "symloc/capture_request"
    sensor_qos: str = "best_effort"
    mode: str = "localize"
    visual_map: str = ""
    vocabulary: str = ""
    camera_intrinsics: tuple[float, ...] = ()
    camera_dist_coeffs: tuple[float, ...] = ()
    lidar_preset: str = ""
    map_yaml: str = ""
    accept_map_updates: bool = False
    transform_tolerance: float = 1.0
    max_odom_age: float = 10.0
    seed: int = 0
    amcl: AmclParams = field(default_factory=AmclParams)
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
        intr = tuple(self.camera_intrinsics)
        if intr and (
            len(intr) != 4
            or not all(isinstance(v, (int, float)) and math.isfinite(v) and v > 0 for v in intr)
        ):
            raise ConfigurationError(
                f"camera_intrinsics: expected 4 numbers fx, fy, cx, cy > 0 [px], got {intr!r}"
            )
        object.__setattr__(self, "camera_intrinsics", tuple(float(v) for v in intr))
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
        if not isinstance(self.accept_map_updates, bool):
            raise ConfigurationError(
                f"accept_map_updates: expected true/false, got {self.accept_map_updates!r}"
            )
        for name in ("transform_tolerance", "max_odom_age"):
            v = getattr(self, name)
            if (
                isinstance(v, bool)
                or not isinstance(v, (int, float))
                or not math.isfinite(v)
                or v <= 0
            ):
                raise ConfigurationError(f"{name}: expected a number > 0 s, got {v!r}")
            object.__setattr__(self, name, float(v))
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigurationError(f"seed: expected an integer >= 0, got {self.seed!r}")
        if not isinstance(self.amcl, AmclParams):
            raise ConfigurationError("amcl: expected an AmclParams")
        if not isinstance(self.localizer, LocalizerConfig):
            raise ConfigurationError("localizer: expected a LocalizerConfig")

    def symmetry_config(self) -> Any:
        """The :class:`symloc.symmetry.SymmetryConfig` of Algorithm 1 (preset + overrides)."""
        from symloc.symmetry import SymmetryConfig

        known = {f.name for f in fields(SymmetryConfig)}
        bad = sorted(set(self.symmetry) - known)
        if bad:
            raise ConfigurationError(f"symmetry.{bad[0]}: unknown (known: {sorted(known)})")
        if self.lidar_preset:
            from symloc.lidar_spec import PRESETS

            return SymmetryConfig.from_lidar(PRESETS[self.lidar_preset], **self.symmetry)
        return SymmetryConfig(**self.symmetry)

    @property
    def allow_mapping(self) -> bool:
        """Whether the localizer may build visual maps of unmatched places."""
        return self.mode == "build_visual_map"

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> NodeParams:
        """From a ``ros__parameters`` mapping (nested ``amcl`` and ``localizer`` blocks)."""
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
        if "amcl" in kwargs:
            kwargs["amcl"] = AmclParams.from_dict(kwargs["amcl"] or {})
        if "localizer" in kwargs:
            block = kwargs["localizer"] or {}
            if not isinstance(block, dict):
                raise ConfigurationError("localizer: expected a mapping of LocalizerConfig fields")
            known = {f.name for f in fields(LocalizerConfig)}
            bad = sorted(set(block) - known)
            if bad:
                raise ConfigurationError(f"localizer.{bad[0]}: unknown (known: {sorted(known)})")
            kwargs["localizer"] = LocalizerConfig(**block)
        return cls(**kwargs)

    @classmethod
    def from_yaml(cls, source: str | Path, *, node_name: str = "symloc") -> NodeParams:
        """Read the node's ``ros__parameters`` from a nav2-style YAML file (or YAML text).

        The block is looked up under ``node_name``, ``/node_name``, any namespaced
        ``ns/node_name`` or ``/**``; a file with none of them raises.
        """
        if isinstance(source, Path) or (
            isinstance(source, str) and "\n" not in source and source.endswith((".yaml", ".yml"))
        ):
            try:
                text = Path(source).read_text()
            except OSError as err:
                raise ConfigurationError(f"params file {source}: cannot read ({err})") from err
        else:
            text = str(source)
        try:
            doc = yaml.safe_load(text)
        except yaml.YAMLError as err:
            raise ConfigurationError(f"params: not valid YAML ({err})") from err
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
