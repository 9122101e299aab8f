"""One trial of the bench: a robot that does not know where it is, symloc and plain AMCL.

Claims live in the map frame; the truth they are graded against is the robot's true pose
expressed in the map frame (:meth:`symloc.bench.scenario.Scenario.to_map`: the SLAM map's
frame is its mapping trip's first pose), so map distortion counts as error. A kidnap trial's
known start is given to the localizer in the map frame, as an operator would.

Two kinds of trial (:data:`TRIAL_KINDS`):

- ``global``: the robot is put down anywhere it fits (near walls too) and nobody tells the
  localizer where; it has ``claim_timeout`` seconds to publish a pose as tracking;
- ``kidnap``: the localizer is given the true start pose (as an operator's initial pose), the
  robot drives for ``kidnap_after`` seconds, then it is carried to another random pose and
  nobody tells the localizer (true kidnapping); it then has ``claim_timeout`` seconds.

After its first claim the robot keeps driving for ``track_time`` seconds, so that tracking is
graded too. Every scan's published pose is logged and graded by
:func:`symloc.bench.grading.grade_trial` (confident wrong if any tracking pose, at any scan, is
outside the tolerance).

The robot's driver carries out the localizer's requests (go to the centre, face, rotate,
capture an image); with no request it drives a seeded collision-free random path
(:class:`~symloc.bench.explore.ExploreDrive`), as a robot on a mission would. Plain AMCL (nav2's
filter alone, same settings, same sensors and start) drives the random path throughout; what it
"publishes as tracking" is its pose carried forward by odometry between filter updates (what
nav2's ``map -> odom`` transform gives a user) while its own filter is confident
(:func:`symloc.bench.scenario.amcl_confident`: checks 1-4 of :mod:`symloc.mcl.confidence`).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError, WorldError
from symloc.geometry import compose, relative
from symloc.localizer.centering import CenteringConfig
from symloc.localizer.types import Request, RequestKind, Status
from symloc.mcl import Amcl, ConfidenceJudge
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan
from symloc.sim.robot import DiffDriveRobot

from .episode import RobotBody, drive_command
from .explore import ExploreDrive
from .grading import TOLERANCE, ScanLog, Tolerance, TrialGrade, grade_trial
from .scenario import Scenario, amcl_confident

__all__ = [
    "DEFAULT_METHODS",
    "METHODS",
    "TRIAL_KINDS",
    "MethodResult",
    "TrialConfig",
    "TrialResult",
    "TrialSpec",
    "run_trial",
    "sample_free_pose",
]

FloatArray = NDArray[np.float64]

#: What a method publishes at one scan: status, pose (3,) or None, covariance (3, 3) or None,
#: reason, a request to the driver (or None), and the axis estimate (status ``axis``: its
#: pose (3,) and covariance (3, 3); None otherwise: graded for its heading, never a claim).
Published = tuple[
    str,
    FloatArray | None,
    FloatArray | None,
    str,
    Request | None,
    tuple[FloatArray, FloatArray] | None,
]

TRIAL_KINDS = ("global", "kidnap")
METHODS = ("symloc", "amcl", "decide", "centre")
"""symloc as shipped (its default settings: deciding from where the robot stands, the drive to
the centre as the last resort), plain AMCL (nav2's filter alone), symloc deciding from where the
robot stands (``LocalizerConfig.decide_here`` forced on: the laser proposes, the camera verifies
against the mapping trip's keyframes; the default since it beat the paper's path on the dev
split) and the paper's path alone (``decide_here`` off: AMCL, then the drive to the centre) on
the same trial. Appended only: each method's random stream is
``SeedSequence(seed).spawn(...)[2 + index]``, and a spawned child depends on its index alone, so
adding a method changes no other's numbers."""

#: The methods run unless asked otherwise: the three the decide issue compares.
DEFAULT_METHODS = ("symloc", "centre", "amcl")

#: ``decide_here`` each symloc method forces (None: the settings' own).
DECIDE_HERE: dict[str, bool | None] = {"symloc": None, "decide": True, "centre": False}


def needs_keyframes(methods: Sequence[str], default_decide_here: bool) -> bool:
    """Whether any of ``methods`` decides where the robot stands (it verifies against keyframes
    recorded along the mapping trip) given the settings' ``decide_here``."""
    return any(
        m in DECIDE_HERE and (default_decide_here if DECIDE_HERE[m] is None else DECIDE_HERE[m])
        for m in methods
    )


#: Initial pose covariance an operator gives with a known start (kidnap trials): 5 cm, 3 deg.
KNOWN_START_COV = np.diag([0.05**2, 0.05**2, math.radians(3.0) ** 2])


@dataclass(frozen=True)
class TrialConfig:
    """Durations [s] and the start-pose clearance [m] of a trial.

    ``clearance`` is the distance from any obstacle a start pose keeps: the robot's radius
    (0.177 m, a Kobuki) plus a few centimetres, so that starts include poses near walls.
    """

    claim_timeout: float = 60.0
    track_time: float = 20.0
    kidnap_after: float = 10.0
    clearance: float = 0.2
    tolerance: Tolerance = TOLERANCE

    def __post_init__(self) -> None:
        for name in ("claim_timeout", "track_time", "kidnap_after", "clearance"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigurationError(f"TrialConfig.{name}: expected a value > 0, got {value!r}")


@dataclass(frozen=True)
class TrialSpec:
    """Which trial: its world, index, kind and seed (everything random in it follows)."""

    world_id: str
    family: str
    index: int
    kind: str
    seed: int

    def __post_init__(self) -> None:
        if self.kind not in TRIAL_KINDS:
            raise ConfigurationError(
                f"TrialSpec.kind: expected one of {', '.join(TRIAL_KINDS)}, got {self.kind!r}"
            )


@dataclass(frozen=True)
class MethodResult:
    """One method's run of a trial: its grade, its last status and reason, and costs."""

    method: str
    grade: TrialGrade
    final_status: str
    final_reason: str
    collisions: int
    sim_time: float
    wall_time: float
    steps: tuple[str, ...] = ()


@dataclass(frozen=True)
class TrialResult:
    """Both methods on one trial (same world, start, kidnapping and sensors)."""

    spec: TrialSpec
    start: tuple[float, float, float]
    kidnap_to: tuple[float, float, float] | None
    results: dict[str, MethodResult] = field(default_factory=dict)


def sample_free_pose(
    scen: Scenario, rng: np.random.Generator, clearance: float, *, tries: int = 2000
) -> FloatArray:
    """A uniformly random pose ``(3,)`` inside the room, ``clearance`` [m] from every obstacle.

    Rejection sampling over the room's bounding box (uniform over the free space, walls'
    neighbourhood included); heading uniform.
    """
    sampler = getattr(scen.room, "sample_pose", None)
    if sampler is not None:
        pose: FloatArray = np.asarray(sampler(rng, clearance), dtype=np.float64)
        return pose
    lo = scen.room.boundary.min(axis=0)
    hi = scen.room.boundary.max(axis=0)
    for _ in range(tries):
        p = rng.uniform(lo, hi)
        if not bool(scen.room.contains(p[None])[0]):
            continue
        if float(scen.room.world.distance(p[None])[0]) < clearance:
            continue
        return np.array([p[0], p[1], rng.uniform(-math.pi, math.pi)])
    raise WorldError(
        f"sample_free_pose: no free pose with clearance {clearance} m in room {scen.room.name!r}"
    )


def _tuple(p: FloatArray) -> tuple[float, float, float]:
    return (float(p[0]), float(p[1]), float(p[2]))


def run_trial(
    scen: Scenario,
    spec: TrialSpec,
    config: TrialConfig | None = None,
    *,
    methods: tuple[str, ...] = DEFAULT_METHODS,
) -> TrialResult:
    """Run ``methods`` on the trial ``spec`` in ``scen``; every random draw follows ``spec.seed``."""
    cfg = config if config is not None else TrialConfig()
    bad = [m for m in methods if m not in METHODS]
    if bad:
        raise ConfigurationError(f"methods: unknown {bad}; expected some of {METHODS}")
    seeds = np.random.SeedSequence(spec.seed).spawn(2 + len(METHODS))
    place_rng = np.random.default_rng(seeds[0])
    start = sample_free_pose(scen, place_rng, cfg.clearance)
    kidnap_to = sample_free_pose(scen, place_rng, cfg.clearance) if spec.kind == "kidnap" else None
    out = TrialResult(spec, _tuple(start), None if kidnap_to is None else _tuple(kidnap_to))
    for i, method in enumerate(METHODS):
        if method not in methods:
            continue
        rng = np.random.default_rng(seeds[2 + i])
        out.results[method] = _run_method(method, scen, spec, cfg, start, kidnap_to, rng)
    return out


def _run_method(
    method: str,
    scen: Scenario,
    spec: TrialSpec,
    cfg: TrialConfig,
    start: FloatArray,
    kidnap_to: FloatArray | None,
    rng: np.random.Generator,
) -> MethodResult:
    wall0 = time.perf_counter()
    setup = scen.sensors(rng, "query")
    body = RobotBody(DiffDriveRobot(start, setup.robot_config, rng, world=scen.room.world))
    driver = ExploreDrive(scen.room.world.distance, rng)
    centering = CenteringConfig()
    dt = 1.0 / float(scen.preset.scan_rate)
    known_start = spec.kind == "kidnap"
    runner: _SymlocRunner | _AmclRunner = (
        _AmclRunner(scen, rng)
        if method == "amcl"
        else _SymlocRunner(scen, rng, decide_here=DECIDE_HERE[method])
    )
    runner.start(scen.to_map(start) if known_start else None)
    log = ScanLog()
    t = 0.0
    distance = 0.0
    twist = (0.0, 0.0)
    image: NDArray[np.uint8] | None = None
    kidnapped = kidnap_to is None
    kidnap_index = 0
    claim_window_start = 0.0
    deadline = cfg.claim_timeout if not known_start else cfg.kidnap_after
    claimed_after_start = False
    while True:
        if not kidnapped and t >= cfg.kidnap_after:
            assert kidnap_to is not None
            body.teleport(kidnap_to)
            kidnapped = True
            kidnap_index = len(log)
            claim_window_start = t
            claimed_after_start = False
            deadline = t + cfg.claim_timeout
        world = scen.world_at(t, body.pose)
        scan = setup.scan(world, body.pose, twist, t)
        status, pose, cov, reason, request, axis = runner.update(body.odom, scan, image)
        image = None
        log.append(t, scen.to_map(body.pose), status, pose, cov, distance, reason, axis)
        if pose is not None and kidnapped and not claimed_after_start:
            claimed_after_start = True
            deadline = max(t, claim_window_start) + cfg.track_time
        if t >= deadline:
            break
        if request is not None and request.kind is RequestKind.CAPTURE_IMAGE:
            image = setup.image(world, body.pose, (0.0, 0.0))
            v, w = 0.0, 0.0
        elif request is not None:
            v, w = drive_command(Status(status), request, scan, centering)
        else:
            v, w = driver.command(body.pose, dt)
        before = body.pose
        body.drive(v, w, dt)
        twist = (v, w)
        distance += float(np.hypot(*(body.pose[:2] - before[:2])))
        t += dt
    grade = grade_trial(log, tolerance=cfg.tolerance, start=kidnap_index)
    return MethodResult(
        method=method,
        grade=grade,
        final_status=log.status[-1],
        final_reason=log.reason[-1],
        collisions=body.collisions,
        sim_time=t,
        wall_time=time.perf_counter() - wall0,
        steps=runner.steps(),
    )


class _SymlocRunner:
    """symloc's localizer: publishes ``Estimate.pose`` while its status is tracking.

    ``decide_here`` overrides the settings' (None keeps them): deciding from where the robot
    stands verifies against the scenario's keyframes. Forced on, it needs them; the settings'
    default runs without them where the mapping trip recorded none (raster maps), the laser's
    proposals alone."""

    def __init__(
        self, scen: Scenario, rng: np.random.Generator, *, decide_here: bool | None = None
    ) -> None:
        config = None
        if decide_here is not None:
            if decide_here and scen.n_keyframes == 0:
                raise ConfigurationError(
                    "method 'decide': the scenario has no keyframes "
                    "(build_scenario(..., keyframes=True))"
                )
            config = dataclasses.replace(scen.settings.localizer, decide_here=decide_here)
        self.loc = scen.localizer(rng, config)

    def start(self, known: FloatArray | None) -> None:
        if known is None:
            self.loc.reset_global()
        else:
            self.loc.set_pose(known, KNOWN_START_COV)

    def update(
        self, odom: OdometryReading, scan: LaserScan, image: NDArray[np.uint8] | None
    ) -> Published:
        est = self.loc.update(odom, scan, image)
        tracking = est.status is Status.TRACKING
        axis = est.axis
        return (
            est.status.value,
            est.pose if tracking else None,
            est.covariance if tracking else None,
            est.reason,
            est.request,
            None if axis is None else (axis.pose, axis.covariance),
        )

    def steps(self) -> tuple[str, ...]:
        return tuple(self.loc.log[-20:])


class _AmclRunner:
    """Plain AMCL: publishes its estimate carried by odometry while its filter is confident."""

    def __init__(self, scen: Scenario, rng: np.random.Generator) -> None:
        self.amcl = Amcl(scen.grid, scen.plain_amcl_params(), rng)
        #: judges every filter result (forgets its verdict when the filter is re-initialised)
        self.judge = ConfidenceJudge(self.amcl)
        self._anchor: tuple[FloatArray, FloatArray] | None = None

    def start(self, known: FloatArray | None) -> None:
        if known is None:
            self.amcl.initialize_global()
        else:
            self.amcl.initialize_pose(known, KNOWN_START_COV)
        self._anchor = None

    def update(
        self, odom: OdometryReading, scan: LaserScan, image: NDArray[np.uint8] | None
    ) -> Published:
        res, conf = self.judge.update(odom, scan)
        odom_pose = np.asarray(odom.pose, dtype=np.float64)
        if res.updated or self._anchor is None:
            self._anchor = (np.asarray(res.estimate, dtype=np.float64), odom_pose.copy())
        est, odom_then = self._anchor
        carried = compose(est, relative(odom_then, odom_pose))
        confident, reason = amcl_confident(conf)
        status = "tracking" if confident else "not_confident"
        cov = np.asarray(res.covariance, dtype=np.float64)
        pose, pose_cov = (carried, cov) if confident else (None, None)
        return status, pose, pose_cov, reason, None, None

    def steps(self) -> tuple[str, ...]:
        return ()
