"""Record a simulated kidnapped-robot run as a ROS bag (``symloc sim record``).

The run is closed-loop: the robot is kidnapped to a random pose in a symmetric room inside the
textured lab; the symloc node logic (:class:`symloc.ros.core.NodeCore`, the same code the ROS
node runs) localizes it from the messages, and a driver carries out its requests (go to the
centre, face, rotate, capture an image) in the simulator. Every message the node consumes is
written to the bag first and read back from its serialised bytes, so the in-process run saw
exactly what a replay of the bag sees (``symloc replay`` reproduces its trajectory).

Topics: ``/map`` (nav_msgs/OccupancyGrid, transient local, once), ``/odom``
(nav_msgs/Odometry, odom -> base_link), ``/scan`` (sensor_msgs/LaserScan, frame ``laser``),
``/camera/image_raw`` (sensor_msgs/Image rgb8; or ``/camera/image_raw/compressed`` PNG),
``/ground_truth`` (nav_msgs/Odometry, map -> base_link, the simulator's true pose).

Beside the bag, an assets folder holds what a replay or the ROS node needs: ``map.yaml`` +
``map.<write id>.pgm`` (map_server format, when :mod:`symloc.grid.map_io` is available), ``places.db``
(the visual map from the mapping stage), ``vocabulary.bin``, ``params.yaml`` (node parameters),
``truth.tum`` and ``estimate.tum``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from symloc._checks import as_rng, check_positive
from symloc.bench.episode import RobotBody, drive_command
from symloc.bench.scenario import build_scenario
from symloc.errors import ConfigurationError
from symloc.files.atomic import atomic_write_text
from symloc.grid.map_io import save_map
from symloc.io.rosbag import BagFormat, BagWriter
from symloc.io.tum import TrajectoryPoint, write_tum
from symloc.localizer import Estimate, Status
from symloc.localizer.centering import CenteringConfig
from symloc.msgs.grid import grid_to_fields
from symloc.msgs.image import compressed_image_to_fields, image_to_fields
from symloc.msgs.odometry import odometry_to_fields
from symloc.msgs.scan import scan_from_msg, scan_to_fields
from symloc.odometry import OdometryReading
from symloc.ros.core import NodeCore, Outputs
from symloc.ros.params import NOT_PARAMETERS, NodeParams
from symloc.sim.lidar import simulate_scan
from symloc.sim.robot import DiffDriveRobot

__all__ = [
    "MappingDrive",
    "SimRecording",
    "SimSession",
    "prepare_session",
    "record_mapping_drive",
    "record_sim_run",
]

FloatArray = NDArray[np.float64]


@dataclass
class SimRecording:
    """What :func:`record_sim_run` produced.

    ``trajectory`` one point per scan used; ``truth`` (T, 4) t, x, y, theta; ``final`` the last
    estimate; ``final_error`` (position [m], heading [rad]) of the last tracked pose against the
    truth (NaN when it ended untracked); ``counts`` messages per topic.
    """

    bag: Path
    assets: Path
    params_path: Path
    params: NodeParams
    trajectory: list[TrajectoryPoint]
    truth: FloatArray
    final: Estimate
    final_error: tuple[float, float]
    start: FloatArray
    counts: dict[str, int] = field(default_factory=dict)
    dropped: dict[str, int] = field(default_factory=dict)
    steps: list[str] = field(default_factory=list)


def _save_map(grid: Any, assets: Path) -> Path | None:
    path = assets / "map.yaml"
    save_map(grid, path)
    return path


@dataclass
class SimSession:
    """A kidnapped robot in a simulated room with the maps the node needs (see
    :func:`prepare_session`). ``scan()``, ``image()`` and ``drive(v, w)`` advance the world."""

    scenario: Any
    body: Any
    rng: np.random.Generator
    params: NodeParams
    params_path: Path
    assets: Path
    start: FloatArray
    dt: float

    @property
    def grid(self) -> Any:
        """The occupancy grid (ground truth of what the lidar sees)."""
        return self.scenario.grid

    @property
    def time(self) -> float:
        """Simulated time [s] (the stamp of the current odometry)."""
        return float(self.body.odom.stamp)

    def odometry(self) -> OdometryReading:
        """The robot's current (noisy) odometry reading."""
        reading: OdometryReading = self.body.odom
        return reading

    def scan(self) -> Any:
        """A lidar scan from the true pose, stamped with the current time, frame ``laser``."""

        return simulate_scan(
            self.scenario.room.world,
            self.body.pose,
            self.scenario.preset,
            self.rng,
            stamp=self.time,
            frame_id="laser",
        )

    def image(self) -> NDArray[np.uint8]:
        """A camera image ``(H, W, 3)`` RGB from the true pose."""
        img: NDArray[np.uint8] = self.scenario.camera.render(
            self.scenario.room.world, self.body.pose, self.rng
        )
        return img

    def drive(self, v: float, w: float) -> OdometryReading:
        """Drive for one scan period; returns the new odometry reading."""
        reading: OdometryReading = self.body.drive(v, w, self.dt)
        return reading


def prepare_session(
    assets: str | Path,
    *,
    room: str = "square",
    textured: bool = True,
    seed: int = 0,
    max_particles: int = 2000,
    **param_changes: Any,
) -> SimSession:
    """Build the room in the lab, its maps (mapping stage), write the assets, kidnap the robot.

    ``assets`` receives ``places.db``, ``vocabulary.bin``, ``params.yaml`` (and ``map.yaml``
    when :mod:`symloc.grid.map_io` is available); it must not exist or be empty.
    ``param_changes`` override :class:`NodeParams` fields in ``params.yaml``.
    """
    import dataclasses

    assets_dir = Path(assets).resolve()  # params.yaml holds absolute paths
    if assets_dir.exists() and any(assets_dir.iterdir()):
        raise ConfigurationError(f"assets: {assets_dir} exists and is not empty")
    assets_dir.mkdir(parents=True, exist_ok=True)
    rng = as_rng(seed)
    scen = build_scenario(
        room, textured=textured, rng=rng, workdir=assets_dir, max_particles=max_particles
    )
    places_db = assets_dir / "places.db"
    scen.store.visual_map.close()
    db_files = sorted(assets_dir.glob("visual_map_*.sqlite"))
    if db_files:
        db_files[0].rename(places_db)
    for extra in assets_dir.glob("visual_map_*.sqlite-*"):
        extra.unlink()
    vocab_path = assets_dir / "vocabulary.bin"
    scen.store.vocabulary.save(vocab_path)
    map_yaml = _save_map(scen.grid, assets_dir)
    params = NodeParams(
        visual_map=str(places_db),
        vocabulary=str(vocab_path),
        lidar_preset=str(scen.preset.name),
        laser_frame_id="laser",
        seed=int(seed),
        # the bench's settings tree (Algorithm 1's comes back from lidar_preset)
        amcl=scen.settings.amcl,
        confidence=scen.settings.confidence,
        claim=scen.settings.claim,
        localizer=scen.settings.localizer,
        map_yaml=str(map_yaml) if map_yaml else "",
    )
    params = dataclasses.replace(params, **param_changes)
    params_path = assets_dir / "params.yaml"
    atomic_write_text(params_path, yaml.safe_dump(_params_doc(params), sort_keys=False))
    start = scen.random_pose(rng)
    body = RobotBody(DiffDriveRobot(start, rng=rng, world=scen.room.world))
    return SimSession(
        scenario=scen,
        body=body,
        rng=rng,
        params=params,
        params_path=params_path,
        assets=assets_dir,
        start=np.asarray(start),
        dt=1.0 / float(scen.preset.scan_rate),
    )


def record_sim_run(
    out: str | Path,
    *,
    room: str = "square",
    textured: bool = True,
    seed: int = 0,
    fmt: BagFormat = "ros2",
    compressed_images: bool = False,
    max_time: float = 60.0,
    max_particles: int = 2000,
    assets: str | Path | None = None,
    mode: str = "localize",
) -> SimRecording:
    """Simulate a kidnapped-robot run with symloc in the loop and record it (module doc).

    Parameters
    ----------
    out : path
        The bag to create (ROS 2: a folder; ROS 1: a ``.bag`` file). Must not exist.
    room : str
        A room name of :func:`symloc.sim.rooms.build_room` (inside the textured lab).
    seed : int
        Seeds the world's noise, the kidnapping and AMCL (printed by the CLI).
    max_time : float
        Simulated seconds before the run stops even if not settled.
    assets : path, optional
        Folder for the map, visual map, vocabulary, params and TUM files
        (default ``<out>_assets`` beside the bag). Must not exist or be empty.
    mode : {"localize", "build_visual_map"}
        ``build_visual_map`` runs the node in its visual-map building mode against a new, empty
        ``places_built.db`` in the assets folder, so the place is mapped (Algorithm 5 step 11).
    """

    check_positive(max_time, "max_time")
    out = Path(out)
    if out.exists():
        raise ConfigurationError(f"out: {out} exists already; choose a new path")
    assets_dir = Path(assets) if assets is not None else out.with_name(out.name + "_assets")
    changes: dict[str, Any] = {}
    if mode != "localize":
        built = Path(assets_dir).resolve() / "places_built.db"
        changes = {"mode": mode, "visual_map": str(built)}
    sim = prepare_session(
        assets_dir,
        room=room,
        textured=textured,
        seed=seed,
        max_particles=max_particles,
        **changes,
    )
    core = NodeCore(sim.params)
    centering = CenteringConfig()
    truth_rows: list[tuple[float, FloatArray]] = []
    trajectory: list[TrajectoryPoint] = []
    last: Outputs | None = None
    with BagWriter(out, fmt, compressed_images=compressed_images) as bag:

        def emit(topic: str, msgtype: str, fields: dict[str, Any], stamp: float, **kw: Any) -> Any:
            return bag.deserialize(bag.write_fields(topic, msgtype, fields, stamp, **kw), msgtype)

        grid_msg = emit(
            bag.map_topic,
            "nav_msgs/msg/OccupancyGrid",
            grid_to_fields(sim.grid, stamp=0.0),
            0.0,
            latched=True,
        )
        core.on_map(grid_msg)
        odom = sim.odometry()
        odom_fields = odometry_to_fields(odom)
        core.on_odom(emit(bag.odom_topic, "nav_msgs/msg/Odometry", odom_fields, odom.stamp))
        calm = 0
        while sim.time <= max_time:
            t = sim.time
            truth = sim.body.pose
            truth_rows.append((t, truth))
            bag.write_fields(
                bag.truth_topic,
                "nav_msgs/msg/Odometry",
                odometry_to_fields(OdometryReading(truth, t), frame_id="map"),
                t,
            )
            scan_msg = emit(
                bag.scan_topic, "sensor_msgs/msg/LaserScan", scan_to_fields(sim.scan()), t
            )
            last = core.on_scan(scan_msg)
            if not last.used:
                raise ConfigurationError(f"the node dropped a simulated scan: {dict(core.dropped)}")
            est = last.estimate
            trajectory.append(TrajectoryPoint(t, est.status.value, est.pose))
            if est.request is None and est.status in (Status.TRACKING, Status.AMBIGUOUS):
                calm += 1
                if calm >= 3:
                    break
            else:
                calm = 0
            if last.capture is not None:
                image = sim.image()
                if compressed_images:
                    fields = compressed_image_to_fields(image, stamp=t)
                    core.on_compressed_image(
                        emit(bag.image_topic, "sensor_msgs/msg/CompressedImage", fields, t)
                    )
                else:
                    fields = image_to_fields(image, stamp=t)
                    core.on_image(emit(bag.image_topic, "sensor_msgs/msg/Image", fields, t))
                continue
            v, w = drive_command(est.status, est.request, core_scan(scan_msg), centering)
            odom = sim.drive(v, w)
            odom_fields = odometry_to_fields(odom)
            core.on_odom(emit(bag.odom_topic, "nav_msgs/msg/Odometry", odom_fields, odom.stamp))
        counts = dict(bag.counts)
    store = getattr(core.localizer, "places", None)
    if store is not None and hasattr(store, "visual_map"):
        store.visual_map.close()
    assert last is not None
    final = last.estimate
    truth_final = sim.body.pose
    err = (math.nan, math.nan)
    if final.pose is not None:
        d = final.pose - truth_final
        err = (float(np.hypot(d[0], d[1])), abs(math.remainder(float(d[2]), 2 * math.pi)))
    write_tum(assets_dir / "truth.tum", truth_rows)
    write_tum(
        assets_dir / "estimate.tum",
        [(p.stamp, p.pose) for p in trajectory if p.pose is not None],
    )
    return SimRecording(
        bag=out,
        assets=assets_dir,
        params_path=sim.params_path,
        params=sim.params,
        trajectory=trajectory,
        truth=np.array([[t, *p] for t, p in truth_rows]),
        final=final,
        final_error=err,
        start=sim.start,
        counts=counts,
        dropped=dict(core.dropped),
        steps=list(getattr(core.localizer, "log", [])),
    )


def core_scan(msg: Any) -> Any:
    """The symloc scan of a LaserScan message (what the node's localizer saw)."""

    return scan_from_msg(msg)


def _params_doc(params: NodeParams) -> dict[str, Any]:
    """The ``symloc: ros__parameters:`` YAML document of ``params``."""
    from dataclasses import fields, is_dataclass

    def plain(value: Any) -> Any:
        if is_dataclass(value) and not isinstance(value, type):
            return {
                g.name: plain(getattr(value, g.name))
                for g in fields(value)
                if g.name != "ros_extras"
            }
        if isinstance(value, tuple):
            return [plain(v) for v in value]
        return value

    block = {f.name: plain(getattr(params, f.name)) for f in fields(params)}
    # not parameters of their own: mode sets allow_mapping; the older converged_* names
    for path in NOT_PARAMETERS:
        block["localizer"].pop(path.partition(".")[2], None)
    return {"symloc": {"ros__parameters": block}}


@dataclass
class MappingDrive:
    """What :func:`record_mapping_drive` wrote.

    ``bag`` the bag; ``truth`` (N, 4) t [s], x [m], y [m], theta [rad] of the robot in the
    world frame at each scan; ``world_from_odom`` (3,) the odometry frame's origin in the world
    (the start pose when the odometry starts there); ``grid`` the world rasterised (what the
    walls are); ``counts`` messages per topic.
    """

    bag: Path
    truth: FloatArray
    world_from_odom: FloatArray
    grid: Any
    counts: dict[str, int] = field(default_factory=dict)


def record_mapping_drive(
    out: str | Path,
    *,
    room: str = "rectangle",
    seed: int = 0,
    laps: float = 1.3,
    start_waypoint: int = 0,
    image_every: int = 2,
    odometry: str = "topic",
    odom_at_start: bool = True,
    preset: str = "lds01",
    scan_period: float = 0.2,
    fmt: BagFormat = "ros2",
) -> MappingDrive:
    """Drive ``laps`` times round a room of the textured lab and record it as a robot would.

    The robot drives along :func:`symloc.bench.exploration.exploration_path` from waypoint
    ``start_waypoint`` (turning on the spot, then straight), recording ``/scan`` (frame
    ``laser``, the ``preset`` lidar with its noise) every ``scan_period`` [s], the odometry at
    every scan (``odometry="topic"``: nav_msgs/Odometry on ``/odom``; ``"tf"``: ``odom ->
    base_footprint`` on ``/tf`` only), ``/tf_static`` (``base_footprint -> base_link ->
    laser``, the laser on the base's axis), a camera image on ``/camera/image_raw`` every
    ``image_every`` scans, and the true pose on ``/ground_truth`` (map frame = world frame).
    The odometry starts at the true start pose (``odom_at_start``, so a map built from the bag
    is in world coordinates) or at zero, as on a robot.

    Raises
    ------
    ConfigurationError
        ``out`` exists, an unknown room, preset or odometry source, or a collision on the path.
    """
    from symloc.bench.exploration import exploration_path
    from symloc.bench.scenario import DEFAULT_GV
    from symloc.geometry import compose, inverse
    from symloc.lidar_spec import PRESETS
    from symloc.sim.camera import Camera
    from symloc.sim.rasterize import world_to_grid
    from symloc.sim.robot import RobotConfig
    from symloc.sim.rooms import build_room

    out = Path(out)
    if out.exists():
        raise ConfigurationError(f"out: {out} exists already; choose a new path")
    if odometry not in ("topic", "tf"):
        raise ConfigurationError(f"odometry: expected 'topic' or 'tf', got {odometry!r}")
    if preset not in PRESETS:
        raise ConfigurationError(f"preset: expected one of {sorted(PRESETS)}, got {preset!r}")
    if int(image_every) < 1:
        raise ConfigurationError(f"image_every: expected an integer >= 1, got {image_every}")
    check_positive(scan_period, "scan_period")
    rng = as_rng(seed)
    r = build_room(room, DEFAULT_GV.get(room, 2.0), lab=True, textured=True)
    path = exploration_path(r, margin=0.5)
    n_wp = path.shape[0]
    k0 = int(start_waypoint) % n_wp
    targets = np.array([path[(k0 + k) % n_wp] for k in range(math.ceil(laps * n_wp) + 1)])
    heading = math.atan2(targets[1, 1] - targets[0, 1], targets[1, 0] - targets[0, 0])
    start = np.array([targets[0, 0], targets[0, 1], heading])
    origin = start if odom_at_start else np.zeros(3)
    robot = DiffDriveRobot(
        start, RobotConfig(max_v=0.7, max_w=3.0), rng, world=r.world, odom_origin=origin
    )
    lidar = PRESETS[preset]
    camera = Camera()
    truth: list[list[float]] = []
    dt = 0.05
    next_scan = 0.0
    with BagWriter(out, fmt) as bag:
        laser = np.zeros(3)
        bag.write_transforms(
            [("base_footprint", "base_link", laser), ("base_link", "laser", laser)],
            0.0,
            static=True,
        )

        def record() -> None:
            nonlocal next_scan
            while robot.time + 1e-9 >= next_scan:
                t, pose, odom = robot.time, robot.pose, robot.odometry()
                n = len(truth)
                if odometry == "topic":
                    bag.write_odometry(odom)
                else:
                    bag.write_transforms([("odom", "base_footprint", odom.pose)], t)
                bag.write_scan(simulate_scan(r.world, pose, lidar, rng, stamp=t, frame_id="laser"))
                if n % int(image_every) == 0:
                    bag.write_image(camera.render(r.world, pose, rng), t)
                bag.write_truth(pose, t)
                truth.append([t, *pose])
                next_scan += scan_period

        record()
        for goal in targets[1:]:
            pose = robot.pose
            turn = float(
                math.remainder(math.atan2(goal[1] - pose[1], goal[0] - pose[0]) - pose[2], math.tau)
            )
            steps = max(1, math.ceil(abs(turn) / (0.8 * dt)))
            for _ in range(steps):
                robot.step(0.0, turn / (steps * dt), dt)
                record()
            dist = float(np.hypot(*(goal - robot.pose[:2])))
            steps = max(1, math.ceil(dist / (0.3 * dt)))
            for _ in range(steps):
                if not robot.step(dist / (steps * dt), 0.0, dt):
                    raise ConfigurationError(f"record_mapping_drive: the path collides in {room}")
                record()
        counts = dict(bag.counts)
    world_from_odom = np.asarray(compose(start, inverse(origin)), dtype=np.float64)
    return MappingDrive(out, np.asarray(truth), world_from_odom, world_to_grid(r.world), counts)
