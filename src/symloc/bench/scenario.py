"""The kidnapped-robot scenario in the simulator: maps, plain AMCL and symloc side by side.

:func:`build_scenario` builds a room inside a lab, its occupancy grid, and the visual map of the
room (the mapping stage, :func:`~symloc.bench.mapping_trip.map_place`). :func:`run_plain_amcl`
kidnaps the robot and runs AMCL with nav2 defaults from a global start while the robot drives a
seeded collision-free random path;
:func:`run_symloc` runs the :class:`~symloc.localizer.localizer.Localizer` from the same start.
:func:`classify` grades a final answer against the ground truth: correct (within 0.1 m and
5 degrees), a symmetric copy, confident wrong, or undetermined.

The occupancy grid comes from :func:`symloc.sim.rasterize.world_to_grid` (the ground-truth map of
what the lidar sees), and the mapping stage takes the robot's map pose from the simulator's
ground truth: in a real run both come from SLAM. Callers print this.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import as_rng
from symloc.errors import ConfigurationError, SymlocError, WorldError
from symloc.geometry import angle_diff
from symloc.geometry import compose as _compose
from symloc.geometry import inverse as _inverse
from symloc.grid.map_error_field import MapErrorField
from symloc.localizer.adapters import ReportJudge
from symloc.localizer.build import (
    build_localizer,
    enclosed_centroid,
    grid_round_centre,
    grid_symmetries,
)
from symloc.localizer.centering import CenteringConfig
from symloc.localizer.localizer import Localizer, LocalizerConfig, rotated_copies
from symloc.localizer.settings import LocalizerSettings
from symloc.localizer.types import Estimate, Status
from symloc.localizer.vision_store import UNANCHORED_LABEL, VisionPlaceStore
from symloc.mcl import Amcl, AmclParams, Confidence, ConfidenceJudge
from symloc.odometry import OdometryReading, twist_between
from symloc.scan import deskew
from symloc.sim.camera import Camera
from symloc.sim.gyro import L3G4200D, GyroOdometryBody, GyroSpec, SimulatedGyro
from symloc.sim.lidar import RPLIDAR_A2
from symloc.sim.rasterize import world_to_grid
from symloc.sim.robot import DiffDriveRobot, OdometryNoise, RobotConfig
from symloc.sim.rooms import Room, build_room, hallway, with_lab
from symloc.sim.symmetry_truth import truth_order
from symloc.sim.world import World
from symloc.slam import run_slam
from symloc.slam.localize_in_map import localize_in_map
from symloc.slam.map_error import R95
from symloc.symmetry import SymmetryConfig, SymmetryOrder, judge_symmetry
from symloc.vision import OrbExtractor, VisualMap, Vocabulary
from symloc.vision.default_vocabulary import default_vocabulary
from symloc.vision.gyro_drift import META_KEY as ROTATION_STD_META
from symloc.vision.gyro_drift import POSITION_META_KEY as POSITION_STD_META
from symloc.vision.gyro_drift import (
    DriftSettings,
    declared_round_map_error,
    round_room_keyframes,
)
from symloc.vision.keyframes import KeyframeSettings
from symloc.vision.rotation_averaging import HeadingAlignmentSettings
from symloc.vision.rotation_averaging import align_headings as align_keyframe_headings

from .episode import Episode, RobotBody, drive_waypoints, look_around_at, run_episode
from .exploration import coverage_stops, exploration_path, free_route
from .explore import ExploreDrive
from .mapping_trip import KeyframeRecorder, MappedPlace, map_place
from .sensors import ODOM_ALPHA, RobotHardware, SensorSetup, robot_hardware
from .slam_metrics import field_coverage, similarity_residuals, umeyama_se2, umeyama_se2_at

__all__ = [
    "DEFAULT_GV",
    "MAP_SOURCE",
    "Outcome",
    "Scenario",
    "build_scenario",
    "classify",
    "run_plain_amcl",
    "run_symloc",
]

FloatArray = NDArray[np.float64]

#: G-V distance [m] per room name: a 3 m square as in the paper, the others of similar size.
DEFAULT_GV = {
    "triangle": 2.0,
    "square": 3.0 / math.sqrt(2.0),
    "pentagon": 2.0,
    "hexagon": 2.0,
    "octagon": 2.0,
    "circle": 1.7,
    "rectangle": 2.2,
    "hallway": 3.2,
}

#: A true hallway: 40 m x 2 m, its ends beyond the 16 m RPLIDAR range from most of its length.
LONG_HALLWAY = "hallway_40m"
LONG_HALLWAY_SIZE = (40.0, 2.0)

MAP_SOURCE = (
    "occupancy grid: symloc.sim.rasterize.world_to_grid (ground truth of what the lidar sees); "
    "visual map poses: simulator ground truth (a real run takes both from SLAM)"
)

POSITION_TOL = 0.1
HEADING_TOL = math.radians(5.0)


def _vocabulary(rng: np.random.Generator) -> Any:
    """The shipped vocabulary if the vision part provides one, else a small one trained here."""
    try:
        return default_vocabulary()
    except (ImportError, OSError, SymlocError):
        return _trained_vocabulary()


_VOCAB_CACHE: dict[str, Any] = {}


def _trained_vocabulary() -> Any:
    """Fallback: a k=8, L=4 vocabulary from ORB features of scikit-image's bundled photos
    at several scales (the same photos the simulator hangs on the lab walls; the paper trains on
    1000 images taken near its lab)."""
    if "v" in _VOCAB_CACHE:
        return _VOCAB_CACHE["v"]
    import cv2
    from skimage import data

    names = [
        "astronaut",
        "coffee",
        "chelsea",
        "rocket",
        "hubble_deep_field",
        "camera",
        "coins",
        "moon",
        "clock",
        "brick",
        "grass",
        "gravel",
        "retina",
        "page",
        "immunohistochemistry",
    ]
    ext = OrbExtractor()
    docs = []
    for name in names:
        try:
            img = np.asarray(getattr(data, name)())
        except Exception:
            continue
        for scale in (1.0, 0.6, 0.35):
            im = cv2.resize(img, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
            feats = ext.extract(im)
            if len(feats):
                docs.append(feats.descriptors)
    vocab = Vocabulary.train(docs, k=8, L=4, rng=0, progress=False)
    _VOCAB_CACHE["v"] = vocab
    return vocab


@dataclass
class Scenario:
    """A room in a lab with its maps: everything a trial needs."""

    room: Any
    grid: Any
    preset: Any
    camera: Any
    #: Algorithm 1 as the mapping stage runs it (``settings.symmetry``)
    judge: ReportJudge
    store: VisionPlaceStore
    mapped: MappedPlace | None
    #: every setting of symloc's localizer (:func:`symloc.localizer.build.build_localizer`)
    settings: LocalizerSettings
    workdir: Path
    notes: list[str] = field(default_factory=list)
    slam_seconds: float = 0.0
    #: the map's own error [m] (std) as SLAM estimated it (None: not estimated; the claim gate
    #: then assumes its default, ``ClaimConfig.map_std_xy``)
    map_std_xy: float | None = None
    #: 95th percentile [m] of the mapping trip's SLAM pose error in the map frame (NaN: raster)
    slam_error_p95: float = math.nan
    #: evaluation only: the lap's SLAM pose error [m] at its 95th percentile once the map's
    #: scale is fitted too (a similarity alignment: what is left is the map's local
    #: distortion, which SLAM's own estimate ``map_std_xy`` claims to cover), the fitted scale
    #: error (a fraction) and the share of the lap's poses within the estimate's 95 % circle
    #: (NaN without an estimate)
    slam_local_error_p95: float = math.nan
    slam_scale_error: float = math.nan
    map_error_coverage: float = math.nan
    #: the map's position error place by place as SLAM estimated it from its pose graph
    #: (:mod:`symloc.slam.pose_marginals`; None: not estimated), given to the claim gate, and
    #: (evaluation only) the share of the lap's poses whose error (the truth aligned with the
    #: map's scale fitted) lies inside its 95 % ellipse there
    map_error_field: MapErrorField | None = None
    map_error_field_coverage: float = math.nan
    #: odometry noise alpha1..4 of the kidnapped robot (both methods), matched by both AMCLs
    odom_alpha: float = ODOM_ALPHA
    #: the sensor regime of the robot (:mod:`symloc.sim.regimes`)
    regime: str = "ideal"
    #: the one simulated robot that maps this world and is localized in it
    hardware: RobotHardware | None = None
    #: pose of the world frame in the map frame (3,): identity for a ground-truth raster; for a
    #: SLAM map, fixed by the mapping trip's first pose; graders compare claims with
    #: ``compose(map_from_world, true_pose)``
    map_from_world: FloatArray = field(default_factory=lambda: np.zeros(3))
    #: keyframes recorded along the mapping trip (``build_scenario(keyframes=...)``), stored in
    #: the visual map's ``keyframes`` table
    n_keyframes: int = 0
    #: evaluation only (never stored in the map): the true pose (N, 3) in the map frame of each
    #: stored keyframe's image, in keyframe id order, and the SLAM pose (N, 3) each had before
    #: its heading was aligned with the images
    keyframe_true_poses: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    keyframe_slam_poses: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))

    def to_map(self, world_pose: FloatArray) -> FloatArray:
        """A true pose (3,) in the map frame (where the localizer's claims live)."""
        return np.asarray(_compose(self.map_from_world, world_pose), dtype=np.float64)

    def sensors(self, rng: np.random.Generator, session: str = "query") -> SensorSetup:
        """The robot's sensors in one ``session`` (``"mapping"`` or ``"query"``)."""
        if self.hardware is None:
            raise ConfigurationError("Scenario.hardware: no robot drawn for this scenario")
        return self.hardware.session(rng, session)

    def robot(self, start: FloatArray, rng: np.random.Generator) -> RobotBody:
        """The kidnapped robot at ``start`` with odometry noise ``odom_alpha``."""

        a = self.odom_alpha
        cfg = RobotConfig(noise=OdometryNoise(a, a, a, a))
        return RobotBody(DiffDriveRobot(start, cfg, rng, world=self.room.world))

    def world_at(self, t: float, robot: ArrayLike | None = None) -> World:
        """What the sensors see at time ``t`` [s]: the static world plus anything moving
        (people step aside for a robot at ``robot``, a position (2,) or pose (3,) [m])."""
        moving = getattr(self.room, "world_at", None)
        world: World = self.room.world if moving is None else moving(t, robot)
        return world

    @property
    def amcl_params(self) -> Any:
        """symloc's AMCL settings (``settings.amcl``)."""
        return self.settings.amcl

    def localizer(
        self, rng: np.random.Generator, config: LocalizerConfig | None = None
    ) -> Localizer:
        """symloc's localizer on this scenario's maps, built as the node builds it
        (:func:`~symloc.localizer.build.build_localizer` with :attr:`settings`, this
        scenario's visual map, and ``rng``, the generator the trial draws everything from);
        ``config`` replaces ``settings.localizer``. Not initialised yet."""
        settings = self.settings
        if config is not None:
            settings = dataclasses.replace(settings, localizer=config)
        rotation_std, position_std = declared_round_map_error(self.store.visual_map)
        return build_localizer(
            self.grid,
            settings,
            places=self.store,
            rng=rng,
            keyframes=self.store,
            map_std_xy=_larger(self.map_std_xy, position_std),
            map_rotation_std=rotation_std,
            map_error_field=self.map_error_field,
        )

    def map_symmetries(self) -> list[Any]:
        """Rotational symmetries of the occupancy grid (computed once per grid)."""
        return list(grid_symmetries(self.grid))

    def plain_amcl_params(self) -> Any:
        """nav2 defaults (2000/500 particles, likelihood field), alpha1..4 matched to the robot."""

        a = self.odom_alpha
        return AmclParams(alpha1=a, alpha2=a, alpha3=a, alpha4=a)

    def scan_at(self, rng: np.random.Generator, session: str = "query") -> Any:
        """``scan(true_pose)`` of a robot standing still in the static world."""
        setup = self.sensors(rng, session)
        return lambda pose: setup.scan(self.room.world, pose, (0.0, 0.0), 0.0)

    def image_at(self, rng: np.random.Generator, session: str = "query") -> Any:
        """``image(true_pose)`` of a robot standing still in the static world."""
        setup = self.sensors(rng, session)
        return lambda pose: setup.image(self.room.world, pose, (0.0, 0.0))

    def random_pose(self, rng: np.random.Generator, margin: float = 0.35) -> FloatArray:
        """A random pose inside the room, at least ``margin`` [m] from every obstacle."""
        xy = self.room.positions_inside(200, margin=margin)
        p = xy[int(rng.integers(len(xy)))] + rng.uniform(-0.05, 0.05, 2)
        if float(self.room.world.distance(p[None, :])[0]) < margin:
            p = xy[int(rng.integers(len(xy)))]
        return np.array([p[0], p[1], rng.uniform(-math.pi, math.pi)])

    def close(self) -> None:
        self.store.visual_map.close()


def build_scenario(
    room_name: str | Room,
    *,
    textured: bool = True,
    rng: np.random.Generator | int | None = None,
    preset: Any = None,
    workdir: Path | None = None,
    max_particles: int = 5000,
    mapping_start: FloatArray | None = None,
    map_source: str = "slam",
    gyro: Any = "default",
    explore_laps: float = 0.0,
    regime: str = "ideal",
    keyframes: KeyframeSettings | bool | None = None,
    align_headings: HeadingAlignmentSettings | bool = False,
    explore_route: bool = True,
    explore_stops: float = 0.0,
) -> Scenario:
    """Build the room (inside a lab), its occupancy grid and its visual map.

    ``room_name`` is a name of :data:`symloc.sim.rooms.ROOM_NAMES` (built with
    :data:`DEFAULT_GV` inside the textured lab), ``"hallway_40m"``, or a ready
    :class:`~symloc.sim.rooms.Room` (e.g. from a world file or the world generator).
    ``explore_laps`` > 0 adds a drive along the room's outline after the mapping stage, so that
    SLAM sees rooms that the trip to the centre does not (concave rooms, furniture); with
    ``explore_route`` the driver steers around what stands in the way
    (:func:`~symloc.bench.exploration.free_route`), else it drives straight at each waypoint
    and skips the ones it cannot reach. ``explore_stops`` > 0 (with ``explore_laps``): after
    the lap the robot stops wherever it can reach a place farther than that [m] from its trip
    (:func:`~symloc.bench.exploration.coverage_stops`) and turns a full circle at each
    (:func:`~symloc.bench.episode.look_around_at`), so that the keyframes of the trip see the
    room's middle from every direction, not only its walls along the lap; the stops' scans are
    placed in the lap's map and do not change it.
    ``regime`` names the sensors of the mapping robot (:func:`symloc.bench.sensors.sensor_setup`).

    The mapping robot starts at ``mapping_start`` (default: a random pose in the room), goes to
    the centre with Algorithm 2 and stores M images (the mapping stage). ``map_source``
    ``"slam"`` builds the occupancy grid with :func:`symloc.slam.run_slam` from the scans of that
    trip and takes the image poses from SLAM; ``"raster"`` uses
    :func:`symloc.sim.rasterize.world_to_grid` and ground-truth poses.

    ``gyro`` (SLAM maps only): the mapping robot's odometry takes its heading from a simulated
    yaw-rate gyro (:class:`~symloc.sim.gyro.GyroSpec`; ``"default"`` is the Kobuki's
    :data:`~symloc.sim.gyro.L3G4200D`, None: wheel odometry only). In a round room, where
    laser SLAM cannot observe heading, the stored image headings then come from gyro-odometry
    and are trusted; without a gyro they are stored as heading-from-odometry and never yield a
    claimed pose.

    ``keyframes`` (SLAM maps only; default off, so the bench's numbers do not change): record
    keyframes along the whole mapping trip with this selection rule (True: the default
    :class:`~symloc.vision.keyframes.KeyframeSettings`), each with the SLAM pose of its scan,
    into the visual map's ``keyframes`` table (:attr:`Scenario.n_keyframes`; a note gives the
    bytes per square metre).

    ``align_headings`` (with ``keyframes``; default off): before they are stored, the keyframes'
    SLAM headings are made consistent with the relative headings their images measure
    (:func:`symloc.vision.rotation_averaging.align_headings`; True: the default
    :class:`~symloc.vision.rotation_averaging.HeadingAlignmentSettings`); a note gives what it
    changed and its cost. :attr:`Scenario.keyframe_slam_poses` keeps the SLAM poses and
    :attr:`Scenario.keyframe_true_poses` the truth, for evaluation.
    """
    if map_source not in ("slam", "raster"):
        raise ConfigurationError(f"map_source: expected 'slam' or 'raster', got {map_source!r}")
    if keyframes not in (None, False) and (map_source != "slam" or room_name == LONG_HALLWAY):
        raise ConfigurationError(
            "keyframes: recorded on SLAM mapping trips only (map_source='slam')"
        )

    if align_headings not in (None, False) and keyframes in (None, False):
        raise ConfigurationError("align_headings: aligns recorded keyframes (keyframes=...)")

    gen = as_rng(rng)
    preset = RPLIDAR_A2 if preset is None else preset
    if isinstance(room_name, Room):
        room = room_name
        room_name = room.name
        long_hallway = False
    else:
        gv = DEFAULT_GV.get(room_name, 2.0)
        long_hallway = room_name == LONG_HALLWAY
        if long_hallway:
            room = with_lab(hallway(*LONG_HALLWAY_SIZE, textured=textured), textured=textured)
            map_source = "raster"  # see the note below
        else:
            room = build_room(room_name, gv, lab=True, textured=textured)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    hardware = robot_hardware(regime, preset, Camera(), gen)
    camera = hardware.camera
    settings = LocalizerSettings(
        amcl=AmclParams(
            max_particles=max_particles,
            min_particles=500,
            alpha1=ODOM_ALPHA,
            alpha2=ODOM_ALPHA,
            alpha3=ODOM_ALPHA,
            alpha4=ODOM_ALPHA,
        ),
        symmetry=SymmetryConfig.from_lidar(preset),
    )
    judge = ReportJudge(judge_symmetry, config=settings.symmetry)
    wd = Path(workdir) if workdir is not None else Path(tempfile.mkdtemp(prefix="symloc-"))
    wd.mkdir(parents=True, exist_ok=True)
    db = wd / f"visual_map_{room_name}_{'textured' if textured else 'plain'}.sqlite"
    if db.exists():
        db.unlink()
    store = VisionPlaceStore(VisualMap(db), _vocabulary(gen), hardware.calibration)
    scen = Scenario(
        room=room,
        grid=grid,
        preset=preset,
        camera=camera,
        judge=judge,
        store=store,
        mapped=None,
        settings=settings,
        workdir=wd,
        notes=[MAP_SOURCE],
        regime=regime,
        hardware=hardware,
    )
    start = mapping_start if mapping_start is not None else scen.random_pose(gen)
    dt = 1.0 / float(preset.scan_rate)
    if map_source == "raster":
        robot = RobotBody(DiffDriveRobot(start, hardware.robot_config, gen, world=room.world))
        scen.mapped = map_place(
            robot,
            scen.scan_at(gen, "mapping"),
            scen.image_at(gen, "mapping"),
            judge,
            store.add_place,
            map_pose=lambda: robot.pose,
            dt=dt,
            true_centre=room.center,
        )
    else:
        spec = L3G4200D if isinstance(gyro, str) and gyro == "default" else gyro
        kf_settings = (
            KeyframeSettings()
            if keyframes is True
            else keyframes
            if isinstance(keyframes, KeyframeSettings)
            else None
        )
        align = (
            HeadingAlignmentSettings()
            if align_headings is True
            else align_headings
            if isinstance(align_headings, HeadingAlignmentSettings)
            else None
        )
        scen.mapped = _map_with_slam(
            scen,
            start,
            gen,
            dt,
            spec,
            explore_laps=explore_laps,
            explore_route=explore_route,
            explore_stops=explore_stops,
            keyframes=kf_settings,
            align=align,
        )
    if long_hallway:
        scen.notes.append(
            f"{room_name}: a {LONG_HALLWAY_SIZE[0]:g} m x {LONG_HALLWAY_SIZE[1]:g} m corridor; "
            "laser SLAM cannot fix position along a featureless corridor whose ends it does not "
            "see, so the occupancy grid is the ground-truth raster (this favours plain AMCL)"
        )
    if scen.mapped is None:
        scen.notes.append(
            f"mapping stage: no indexable symmetric place in the {room_name} (a hallway has no "
            "G-V distance); no visual map"
            if long_hallway
            else f"mapping stage: the {room_name} was not judged symmetric; no visual map"
        )
    return scen


def _drift_settings(gyro: GyroSpec) -> DriftSettings:
    """The drift fit's settings for the mapping robot's gyro: its data sheet's noise density,
    residual bias and scale (the fit's prior), as its user would declare them."""
    return DriftSettings(
        rate_noise_density=math.radians(gyro.noise_density),
        bias_std=math.radians(gyro.bias_std),
        scale_std=gyro.scale_std,
    )


def _map_with_slam(
    scen: Scenario,
    start: FloatArray,
    gen: np.random.Generator,
    dt: float,
    gyro: Any = None,
    *,
    explore_laps: float = 0.0,
    explore_route: bool = True,
    explore_stops: float = 0.0,
    keyframes: KeyframeSettings | None = None,
    align: HeadingAlignmentSettings | None = None,
) -> MappedPlace | None:
    """The mapping stage with SLAM (Figure 2): every scan of the trip to the centre, of the
    turn for the M images and of the lap along the walls goes to
    :func:`symloc.slam.run_slam`; the place's centre and image headings, measured in the
    odometry frame, are moved into the SLAM map frame with the SLAM pose of the scan taken at
    that moment. The scans of the stops to look around (``explore_stops``) are placed in the
    map SLAM drew (:func:`symloc.slam.localize_in_map.localize_in_map`), for their keyframes'
    poses; they do not change the map.

    The odometry starts at the robot's true start pose, so the SLAM map frame is anchored there
    and errors can be graded in world coordinates.
    """

    assert scen.hardware is not None
    robot: Any = RobotBody(
        DiffDriveRobot(
            start, scen.hardware.robot_config, gen, world=scen.room.world, odom_origin=start
        )
    )
    session = scen.sensors(gen, "mapping")
    if gyro is not None:
        robot = GyroOdometryBody(robot, SimulatedGyro(gyro, gen))
    scans: list[Any] = []
    odoms: list[FloatArray] = []
    stamps: list[float] = []
    truths: list[FloatArray] = []

    last_odom: list[OdometryReading] = []
    recorder = None
    if keyframes is not None:
        # the keyframes' camera draws its noise from a stream of its own (a jump of the trip's
        # generator, which stays untouched): the map, the places and every later draw are the
        # same with and without keyframes, so methods that do not use them are unchanged
        bits = gen.bit_generator
        kf_gen = (
            np.random.Generator(bits.jumped())
            if isinstance(bits, np.random.PCG64)
            else copy.deepcopy(gen)
        )
        kf_session = scen.hardware.session(kf_gen, "mapping")
        recorder = KeyframeRecorder(
            lambda pose: kf_session.image(
                scen.room.world, pose, getattr(robot, "twist", (0.0, 0.0))
            ),
            OrbExtractor(),
            keyframes,
        )

    def scan_rec(pose: FloatArray) -> Any:
        odom = robot.odom
        s = session.scan(scen.room.world, pose, getattr(robot, "twist", (0.0, 0.0)), odom.stamp)
        # the mapping software undoes the lidar's motion skew as the localizer does
        if last_odom:
            s = deskew(s, *twist_between(last_odom[-1], odom))
        last_odom[:] = [odom]
        scans.append(s)
        odoms.append(np.asarray(odom.pose))
        stamps.append(float(odom.stamp))
        truths.append(np.asarray(pose, dtype=np.float64))
        if recorder is not None:
            recorder.frame(len(scans) - 1, np.asarray(odom.pose), truths[-1], float(odom.stamp))
        return s

    marks: list[int] = []

    def map_pose() -> FloatArray:
        scan_rec(robot.pose)  # a scan at this very moment, for its SLAM pose
        marks.append(len(scans) - 1)
        return np.asarray(robot.odom.pose)

    deferred: list[tuple[Any, ...]] = []
    deferred_kw: list[dict[str, Any]] = []

    def add_later(*args: Any, **kw: Any) -> Any:
        deferred.append(args)
        deferred_kw.append(kw)
        return None

    mapped = map_place(
        robot,
        scan_rec,
        lambda pose: session.image(scen.room.world, pose, (0.0, 0.0)),
        scen.judge,
        add_later,
        map_pose=map_pose,
        dt=dt,
        true_centre=scen.room.center,
    )
    lap_end: int | None = None
    if explore_laps > 0:
        try:
            path = exploration_path(scen.room, margin=0.5)
        except WorldError as err:
            scen.notes.append(f"mapping stage: no exploration drive ({err})")
        else:
            # steered around what stands in the way, a hand's width clear of it
            radius = scen.hardware.robot_config.radius
            route = free_route(scen.room, radius + 0.15) if explore_route else None
            refused = drive_waypoints(
                robot, path, laps=explore_laps, dt=dt, on_step=scan_rec, route=route
            )
            scen.notes.append(
                f"mapping stage: drove {explore_laps:g} lap(s) along the room outline"
                + (f" ({refused} waypoints unreachable)" if refused else "")
            )
            lap_end = len(truths)
            if explore_stops > 0:
                stops = coverage_stops(
                    scen.room,
                    np.asarray(truths, dtype=np.float64)[:, :2],
                    reach=explore_stops,
                    clearance=radius + 0.15,
                    start=np.asarray(robot.pose, dtype=np.float64),
                )
                missed = look_around_at(robot, stops, dt=dt, on_step=scan_rec, route=route)
                scen.notes.append(
                    f"mapping stage: looked around at {stops.shape[0] - missed} stop(s), none "
                    f"farther than {explore_stops:g} m from a reachable place"
                    + (f" ({missed} unreachable)" if missed else "")
                )
    # SLAM draws the map from the trip up to the end of its lap; the stops to look around are
    # placed in that map (localize_in_map): minutes of turning in the middle of a round room
    # drift SLAM by a metre there (circle#0 of the dev split) and smear the walls
    lap_end = len(scans) if lap_end is None else lap_end
    t0 = time.perf_counter()
    slam = run_slam(scans[:lap_end], np.array(odoms[:lap_end]), progress=False)
    scen.slam_seconds = time.perf_counter() - t0
    scen.grid = slam.grid
    trip_poses = np.asarray(slam.poses, dtype=np.float64).reshape(-1, 3)
    if lap_end < len(scans):
        looked = localize_in_map(
            slam.grid, scans[lap_end:], np.array(odoms[lap_end - 1 :]), trip_poses[-1]
        )
        trip_poses = np.vstack([trip_poses, looked])
    # a map built with this lidar is a scaled copy of the room by the unit's range scale
    # error, which SLAM cannot see: the claim gate is told its data-sheet spread
    # (ClaimConfig.map_scale_std), as a user sets it for their lidar
    scale_std = scen.hardware.regime.lidar_faults.range_scale_std if scen.hardware else 0.0
    claim = dataclasses.replace(scen.settings.claim, map_scale_std=scale_std)
    if scen.hardware is not None:
        # and its wheels' error, as a user who measured them sets it (never below the
        # gate's default margin): a heavy regime's slip loses up to 30 % of a turn
        a1, a2, a3, a4 = np.maximum(
            claim.odometry_alphas, scen.hardware.regime.odometry.error_alphas()
        )
        claim = dataclasses.replace(
            claim, odometry_alphas=(float(a1), float(a2), float(a3), float(a4))
        )
    scen.settings = dataclasses.replace(scen.settings, claim=claim)
    scen.map_error_field = slam.map_error_field
    if slam.map_error is not None:
        scen.map_std_xy = slam.map_error.std_xy
        scen.notes.append(
            f"mapping trip: the map's own error (SLAM's estimate) {100 * slam.map_error.std_xy:.1f}"
            f" cm std, p95 {100 * slam.map_error.p95_xy:.1f} cm over {slam.map_error.nodes} nodes"
        )
    # The truth is expressed in the SLAM map frame by a rigid transform fitted to the trip
    # SLAM mapped (least squares over its positions, as ATE aligns trajectories), not by the
    # first pose alone: anchoring at the first pose would put all the drift SLAM left at the
    # far side of the room. Whatever distortion remains is error the localizer inherits.
    # A map drawn with a lidar whose ranges are off by a factor is the room scaled, which no
    # rigid frame fits everywhere: the truth frame is right at the middle of the mapped room,
    # the point the claim gate's map_scale_std grows from (build.enclosed_centroid), not at
    # the lap's centroid (plain umeyama_se2), which a lap that cannot reach a cross's arms put
    # 0.85 m off it (dev cross#0, heavy: a -5.2 % map; claims 12.6 cm off in that frame).
    lap_truths = np.asarray(truths[:lap_end], dtype=np.float64)
    rigid = umeyama_se2(lap_truths[:, :2], trip_poses[:lap_end, :2])
    middle = enclosed_centroid(scen.grid)
    scen.map_from_world = umeyama_se2_at(lap_truths[:, :2], trip_poses[:lap_end, :2], middle)
    # the same rotation: the two frames differ by one translation
    shift = float(np.hypot(*(scen.map_from_world[:2] - rigid[:2])))
    scen.notes.append(
        "mapping trip: the truth frame is right at the mapped room's middle (the map's scale"
        f" error grows from there), {100 * shift:.1f} cm from the frame right at the lap's centroid"
    )
    in_map = np.asarray(_compose(scen.map_from_world, np.array(truths)), dtype=np.float64)
    trip_err = np.hypot(*(trip_poses[:, :2] - in_map[:, :2]).T)
    slam_err = trip_err[:lap_end]
    scen.slam_error_p95 = float(np.percentile(slam_err, 95))
    scen.notes.append(
        f"mapping trip: SLAM pose error in the map frame mean {100 * slam_err.mean():.1f} cm, "
        f"p95 {100 * scen.slam_error_p95:.1f} cm, max {100 * slam_err.max():.1f} cm"
    )
    local = _local_error(scen, lap_truths[:, :2], trip_poses[:lap_end, :2])
    _field_coverage(scen, local, trip_poses[:lap_end, :2])
    if lap_end < len(truths):
        looks = trip_err[lap_end:]
        scen.notes.append(
            f"mapping trip: the stops' {looks.size} scans placed in the lap's map, pose error "
            f"mean {100 * looks.mean():.1f} cm, p95 {100 * np.percentile(looks, 95):.1f} cm"
        )
    scen.notes[0] = (
        f"occupancy grid: symloc.slam.run_slam over {lap_end} scans of the mapping trip; "
        "visual map poses: SLAM poses"
        + (
            f" (the {len(scans) - lap_end} scans of the stops: placed in that map)"
            if lap_end < len(scans)
            else ""
        )
    )
    drift = None
    odom_turn = np.unwrap(np.array([o[2] for o in odoms], np.float64))  # continuous heading
    if recorder is not None:
        vm = scen.store.visual_map
        vocab = scen.store.vocabulary
        kfs = recorder.keyframes(
            lambda i: trip_poses[i],
            lambda f: vocab.bow(f.descriptors),
        )
        scen.keyframe_slam_poses = np.array([kf.pose for kf in kfs], np.float64).reshape(-1, 3)
        scen.keyframe_true_poses = np.asarray(
            _compose(
                scen.map_from_world,
                np.array([truths[i] for i in recorder.indices], np.float64).reshape(-1, 3),
            ),
            dtype=np.float64,
        ).reshape(-1, 3)
        centre = grid_round_centre(slam.grid) if gyro is not None and kfs else None
        if centre is not None:
            # a round room: SLAM's headings wander, the gyro's drift smoothly; the images fit
            # its drift, and the claim gate is told how sure the result is
            fitted, drift = round_room_keyframes(
                kfs,
                odom_turn[recorder.indices],
                centre,
                scen.hardware.calibration,
                settings=_drift_settings(gyro),
                anchor=np.asarray(recorder.indices) < lap_end,
            )
            if drift is None:
                scen.notes.append(
                    "mapping trip: a round room whose images do not fix the gyro's drift: "
                    "keyframe headings from SLAM"
                )
            elif drift.heading_std >= scen.settings.claim.map_rotation_std:
                # too few pairs to trust: SLAM's stay
                scen.notes.append(
                    "mapping trip: round-room keyframe headings: the gyro's drift fitted to the "
                    f"images no surer ({math.degrees(drift.heading_std):.2f} deg) than the "
                    f"map's assumed rotation error "
                    f"({math.degrees(scen.settings.claim.map_rotation_std):.2f} deg): SLAM's kept"
                )
                drift = None
            else:
                kfs = fitted
            if drift is not None:
                # the localizer reads them back as the node does (Scenario.localizer)
                vm.set_meta(ROTATION_STD_META, repr(drift.heading_std))
                if math.isfinite(drift.position_std) and drift.position_std > 0.0:
                    vm.set_meta(POSITION_STD_META, repr(drift.position_std))
                scen.notes.append("mapping trip: " + drift.summary())
        if align is not None and kfs:
            aligned = align_keyframe_headings(kfs, scen.hardware.calibration, align)
            kfs = aligned.apply(kfs)
            scen.notes.append("mapping trip: " + aligned.summary())
        vm.add_keyframes(kfs)
        scen.n_keyframes = len(kfs)
        area = float(scen.room.area)
        scen.notes.append(
            f"mapping trip: {len(kfs)} keyframes of {recorder.captured} images looked at, "
            f"{vm.keyframe_bytes() / 1024:.0f} KiB ({vm.keyframe_bytes() / area / 1024:.1f} "
            f"KiB per m2 of the room's {area:.1f} m2)"
        )
    if mapped is None or not deferred:
        return None
    centre_o, heading0_o, order, gv, kind, images = deferred[0]
    headings_o = deferred_kw[0].get("headings") or [heading0_o]

    def to_map(i: int) -> FloatArray:
        k = marks[i]
        return np.asarray(_compose(slam.poses[k], _inverse(odoms[k])))

    t_c = to_map(0)
    centre = _compose(t_c, np.array([centre_o[0], centre_o[1], 0.0]))[:2]
    round_room = kind == "circle" or order.is_circle
    if drift is not None:
        # the keyframes' fitted gyro drift, at the moments the images were taken
        k = np.asarray(marks[: len(headings_o)], np.int64)
        offset = np.asarray(angle_diff(np.asarray(headings_o), odom_turn[k]), np.float64)
        headings = drift.correct(odom_turn[k] + offset, np.asarray(stamps)[k]).tolist()
    elif round_room and gyro is not None:
        # laser SLAM cannot observe heading in a round room; the gyro-odometry frame is the map
        # frame at the start (both start at the robot's start pose), so its headings are used
        headings = [float(h) for h in headings_o]
    else:
        headings = [float(h + to_map(i)[2]) for i, h in enumerate(headings_o)]
    # without a gyro, a round room's headings are wheel odometry's: not trusted
    label = UNANCHORED_LABEL if (round_room and gyro is None) else None
    if round_room and gyro is not None:
        scen.notes.append(
            "mapping stage: a round room gives laser SLAM no heading; image headings from "
            f"gyro-odometry ({gyro.source.split(':')[0]})"
            + (", its drift fitted to the keyframes' images" if drift is not None else "")
        )
    if label is not None:
        scen.notes.append(
            "mapping stage: a round room gives laser SLAM no heading; the visual map is stored "
            "as heading-from-odometry and the localizer will not claim a pose from it"
        )
    place = scen.store.add_place(
        centre, headings[0], order, gv, kind, images, headings=headings, label=label
    )
    return MappedPlace(
        place=place,
        images=mapped.images,
        headings=np.asarray(headings),
        centering=mapped.centering,
    )


@dataclass(frozen=True)
class Outcome:
    """A graded final answer: ``grade`` is correct / symmetric_copy / confident_wrong /
    undetermined; errors in m and rad (NaN without a pose)."""

    grade: str
    position_error: float
    heading_error: float
    copy_index: int | None
    confidence: float
    near_copy: int | None = None


def _field_coverage(scen: Scenario, errors: FloatArray, slam_xy: FloatArray) -> None:
    """The share of the lap's SLAM errors ``errors`` (N, 2) [m] at its positions ``slam_xy``
    (N, 2) [m], the truth aligned with the map's scale fitted (:func:`_local_error`: the scale
    is the claim gate's ``map_scale_std``, not the field's), inside the map error field's 95 %
    ellipse there: set on ``scen`` and noted."""
    field = scen.map_error_field
    if field is None:
        return
    scen.map_error_field_coverage = field_coverage(field, slam_xy, errors)
    scen.notes.append(
        f"mapping trip: the map error field (pose-graph marginals, {field.xy.shape[0]} places,"
        f" std median {100 * np.median(field.major_std):.1f} cm, max "
        f"{100 * field.major_std.max():.1f} cm) covers {100 * scen.map_error_field_coverage:.0f}"
        " % of the lap's errors (the map's scale fitted) at its 95 % ellipse"
    )


def _local_error(scen: Scenario, truth_xy: FloatArray, slam_xy: FloatArray) -> FloatArray:
    """The lap's SLAM error (N, 2 true and SLAM positions [m]) once the map's scale is fitted
    as well (:func:`~symloc.bench.slam_metrics.similarity_residuals`), and how much of it the map's
    own error estimate covers: set on ``scen`` and noted; returns the errors (N, 2) [m]."""
    errors, scale = similarity_residuals(truth_xy, slam_xy)
    local = np.hypot(*errors.T)
    scen.slam_local_error_p95 = float(np.percentile(local, 95))
    scen.slam_scale_error = scale - 1.0
    covered = ""
    if scen.map_std_xy is not None:
        scen.map_error_coverage = float(np.mean(local <= R95 * scen.map_std_xy))
        covered = (
            f"; the map's own error estimate covers {100 * scen.map_error_coverage:.0f} % "
            "of them at its 95 % circle"
        )
    scen.notes.append(
        f"mapping trip: with the map's scale fitted ({100 * scen.slam_scale_error:+.2f} %), "
        f"SLAM pose error mean {100 * local.mean():.1f} cm, p95 "
        f"{100 * scen.slam_local_error_p95:.1f} cm{covered}"
    )
    return errors


def classify(
    pose: FloatArray | None,
    confident: bool,
    true_pose: FloatArray,
    center: FloatArray,
    order: SymmetryOrder,
    confidence: float = math.nan,
) -> Outcome:
    """Grade ``pose`` against ``true_pose``; ``confident`` says whether it was claimed as known.

    A pose claimed but not within 0.1 m and 5 degrees is ``confident_wrong``; a pose not
    claimed (ambiguous, lost) is ``undetermined``. ``copy_index`` is the symmetric copy of the
    true pose (rotation by ``j * 360 / order`` about ``center``) nearest to ``pose``;
    ``near_copy`` is that index when ``pose`` lies within 0.3 m and 10 degrees of it.
    """
    if pose is None:
        return Outcome("undetermined", math.nan, math.nan, None, confidence)
    p = np.asarray(pose, dtype=np.float64)
    dpos = float(np.hypot(*(p[:2] - true_pose[:2])))
    dth = abs(float(angle_diff(p[2], true_pose[2])))
    copy = None
    if order.symmetric:
        copies = rotated_copies(true_pose, np.asarray(center), order)
        d = np.hypot(copies[:, 0] - p[0], copies[:, 1] - p[1]) + np.abs(
            np.asarray(angle_diff(copies[:, 2], p[2]))
        )
        copy = int(np.argmin(d))
        near = bool(
            np.hypot(copies[copy, 0] - p[0], copies[copy, 1] - p[1]) <= 0.3
            and abs(float(angle_diff(copies[copy, 2], p[2]))) <= math.radians(10.0)
        )
        near_copy = copy if near else None
    else:
        near_copy = None
    if not confident:
        return Outcome("undetermined", dpos, dth, copy, confidence, near_copy)
    if dpos <= POSITION_TOL and dth <= HEADING_TOL:
        return Outcome("correct", dpos, dth, 0, confidence, 0)
    return Outcome("confident_wrong", dpos, dth, copy, confidence, near_copy)


@dataclass
class AmclRun:
    """Plain AMCL after a kidnapping: final estimate, its cluster weight and std, particles.

    ``collisions`` counts motions the simulator refused (the drive must keep it at 0);
    ``path`` (T, 3) true poses of the drive.
    """

    true_pose: FloatArray
    estimate: FloatArray
    weight: float
    xy_std: float
    theta_std: float
    converged: bool
    particles: FloatArray
    outcome: Outcome
    time: float
    distance: float
    collisions: int = 0
    path: FloatArray | None = None
    confidence_reason: str = ""


#: What plain AMCL does by default in the experiments: the robot drives like this.
AMCL_DRIVE = "seeded random collision-free drive at 0.3 m/s (as amcl-symmetric)"


def run_plain_amcl(
    scen: Scenario,
    start: FloatArray,
    rng: np.random.Generator,
    *,
    duration: float = 45.0,
    params: Any = None,
    drive: str = "explore",
    w: float = 0.6,
) -> AmclRun:
    """Kidnap the robot to ``start``, initialise AMCL globally, drive, grade the final estimate.

    This is what a nav2 user gets: AMCL with nav2's defaults (``params`` None:
    :meth:`Scenario.plain_amcl_params`, 2000/500 particles, likelihood field, alphas matched to
    the robot), a global start, and the robot driven for
    ``duration`` [s]. ``drive`` ``"explore"`` (default) is a seeded collision-free random drive
    (:class:`~symloc.bench.explore.ExploreDrive`, the same kind as
    ``symloc experiment amcl-symmetric``); ``"spin"`` turns on the spot at ``w`` [rad/s].

    AMCL counts as confident by :func:`amcl_confident` (the project's one definition,
    ``locally_confident``: what nav2's filter alone can tell its user).
    """

    if drive not in ("explore", "spin"):
        raise ConfigurationError(f"drive: expected 'explore' or 'spin', got {drive!r}")
    amcl = Amcl(scen.grid, scen.plain_amcl_params() if params is None else params, rng)
    judge = ConfidenceJudge(amcl)  # the verdict, judged after every filter update
    amcl.initialize_global()
    robot = scen.robot(start, rng)
    scan_at = scen.scan_at(rng)
    dt = 1.0 / float(scen.preset.scan_rate)
    driver = ExploreDrive(scen.room.world.distance, rng)
    odom = robot.odom
    t = 0.0
    n = math.ceil(duration / dt)
    dist = 0.0
    path = [robot.pose]
    for _ in range(n):
        judge.update(odom, scan_at(robot.pose))
        v_i, w_i = driver.command(robot.pose, dt) if drive == "explore" else (0.0, w)
        before = robot.pose
        odom = robot.drive(v_i, w_i, dt)
        dist += float(np.hypot(*(robot.pose[:2] - before[:2])))
        path.append(robot.pose)
        t += dt
    result, conf = judge.update(odom, scan_at(robot.pose))
    cov = np.asarray(result.covariance)
    xy_std = math.sqrt(max(cov[0, 0], cov[1, 1]))
    th_std = math.sqrt(cov[2, 2])
    weight = float(result.weight)
    converged, rule = amcl_confident(conf)
    truth = robot.pose
    outcome = classify(
        np.asarray(result.estimate), converged, truth, scen.room.center, _order(scen), weight
    )
    return AmclRun(
        true_pose=truth,
        estimate=np.asarray(result.estimate),
        weight=weight,
        xy_std=xy_std,
        theta_std=th_std,
        converged=converged,
        particles=np.asarray(result.particles).copy(),
        outcome=outcome,
        time=t,
        distance=dist,
        collisions=robot.collisions,
        path=np.asarray(path),
        confidence_reason=rule,
    )


def amcl_confident(conf: Confidence | None) -> tuple[bool, str]:
    """Whether plain AMCL's verdict ``conf`` (its :class:`~symloc.mcl.ConfidenceJudge`'s on
    the last result) is confident the way a nav2 user can know, and why.

    The project's one definition, :mod:`symloc.mcl.confidence`, in its
    ``locally_confident`` form (checks 1-4: one dominant tight hypothesis whose scan agrees
    with the map, sustained): that is what the filter alone gives a nav2 user. Its check 5
    (a search of the whole map for a rival pose) is symloc's own addition and is used by the
    localizer before it claims a pose from AMCL alone; the reason string reports it too.
    """
    if conf is None:
        return False, "no confidence verdict"
    local = bool(conf.locally_confident)
    return local, str(conf.reason)


def _order(scen: Scenario) -> SymmetryOrder:
    return truth_order(scen.room.order)


@dataclass
class SymlocRun:
    """symloc after a kidnapping: the episode, the localizer, the graded outcome."""

    true_start: FloatArray
    true_final: FloatArray
    episode: Episode
    localizer: Localizer
    outcome: Outcome
    steps: list[str]
    collisions: int = 0


def run_symloc(
    scen: Scenario,
    start: FloatArray,
    rng: np.random.Generator,
    *,
    max_time: float = 150.0,
    config: LocalizerConfig | None = None,
) -> SymlocRun:
    """Kidnap the robot to ``start`` and run the localizer until it settles (or ``max_time``)."""

    loc = scen.localizer(rng, config)
    loc.reset_global()
    robot = scen.robot(start, rng)
    ep = run_episode(
        loc,
        robot,
        scen.scan_at(rng),
        scen.image_at(rng),
        odom_start=robot.odom,
        dt=1.0 / float(scen.preset.scan_rate),
        max_time=max_time,
        config=CenteringConfig(),
    )
    final: Estimate = ep.final
    truth = robot.pose
    confident = final.status is Status.TRACKING
    outcome = classify(final.pose, confident, truth, scen.room.center, _order(scen))
    return SymlocRun(
        true_start=np.asarray(start),
        true_final=truth,
        episode=ep,
        localizer=loc,
        outcome=outcome,
        steps=list(loc.log),
        collisions=robot.collisions,
    )


def odom_zero() -> OdometryReading:
    """An odometry reading at the origin (helper)."""
    return OdometryReading(np.zeros(3))


def _larger(a: float | None, b: float | None) -> float | None:
    """The larger of two optional stds (None: not given)."""
    given = [v for v in (a, b) if v is not None]
    return max(given) if given else None
