"""The ROS node's logic without rclpy: messages in, messages (field dicts) out.

:class:`NodeCore` receives messages (rclpy, rosbags or look-alikes) or already converted symloc
values, pairs each scan with the odometry at its stamp (interpolated), hands the localizer the
image it asked for, and returns what to publish as :class:`Outputs`. The live node offers scans
with :meth:`NodeCore.offer_scan`: a scan newer than the newest odometry waits for it (up to
``transform_tolerance``, as nav2_amcl's tf2 message filter) and is answered by
:meth:`NodeCore.ready_scans` after the odometry that covers it; :meth:`NodeCore.add_scan` answers
at once (a simulator or a bag whose odometry comes first). It survives bad input: a
malformed message, a scan of another length than the scans used, NaN poses, an unknown image
encoding, a message in the wrong frame, a map that changes size, stamps that go backwards. Each
is dropped, counted in :attr:`NodeCore.dropped` under a short reason, and reported through the
``warn`` callback (the first few of each reason, then every 100th); localization carries on.

It also never gets stuck (each case recovers within a few scans, :mod:`symloc.ros.guards`):

* a stamp far from the node's clock (odometry from the future, a clock jump) is dropped, not
  adopted; a clock jump that every stream confirms becomes the new time base;
* odometry that leaps faster than a robot moves, or to absurd coordinates, is dropped; a leap
  that persists (an odometry reset) is absorbed, the localizer seeing no motion across it;
* a stream whose newest stamps turn out to be outliers (its next messages keep coming older)
  forgets them;
* a map the localizer cannot be built on or localize in (no free cell, no occupied cell) is
  not stored, so it cannot stand in the way of a good map even with ``first_map_only``; scans
  that find no map say why the last map was refused;
* a new beam count that :data:`CONFIRM` scans in a row agree on becomes the beam count (the
  first scan used does not fix it for good);
* an initial pose outside the map, or with a covariance that is not a covariance of it, is
  rejected at the door;
* a localizer that fails three scans in a row is rebuilt (global initialisation);
* every scan gets a status, used or not (``Outputs.used``), so the drop counters are seen;
* camera images are decoded only while a capture is pending, bounded by ``max_image_pixels``.

Each recovery is counted in :attr:`NodeCore.recovered` and in the status.

:mod:`symloc.ros.node` wraps it in rclpy; ``symloc replay`` feeds it a bag.

With ``use_tf`` (the live node) it also reads TF as nav2_amcl does (:mod:`symloc.ros.tf`):
odometry from ``odom -> base`` transforms on ``/tf`` (:meth:`NodeCore.on_tf`), the laser's
mount from ``/tf_static`` (:meth:`NodeCore.on_tf_static`: the localizer is built for that
pose, scans of an upside-down laser are mirrored), and it returns the ``map -> odom``
transform to broadcast after each scan (:attr:`Outputs.tf`). Without TF the mount comes from
the ``laser_pose`` / ``laser_upside_down`` parameters.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import SymlocError
from symloc.geometry import compose, relative, wrap_angle
from symloc.grid import OccupancyGrid
from symloc.grid.map_error_field import MapErrorField
from symloc.localizer import Estimate, Localizer, RequestKind, Status
from symloc.msgs.fields import field as msg_field
from symloc.msgs.grid import grid_from_msg
from symloc.msgs.header import header_fields, header_frame, header_stamp
from symloc.msgs.image import compressed_image_from_msg, image_from_msg
from symloc.msgs.odometry import odometry_from_msg
from symloc.msgs.pose import (
    pose_array_to_fields,
    pose_stamped_to_fields,
    pose_with_covariance_from_msg,
    pose_with_covariance_to_fields,
)
from symloc.msgs.scan import scan_from_msg
from symloc.odometry import OdometryReading
from symloc.ros.assemble import make_localizer
from symloc.ros.guards import (
    CONFIRM,
    MAX_ODOM_COORDINATE,
    BeamCountGate,
    OdometryGate,
    StampGate,
)
from symloc.ros.pairing import (
    OdometryBuffer,
    Paired,
    ScanPairing,
)
from symloc.ros.params import NodeParams
from symloc.ros.status_msg import candidates_to_fields, status_to_fields
from symloc.ros.tf import (
    LaserMount,
    MapToOdom,
    TransformTree,
    laser_mount,
    odometry_from_transform,
    transforms_from_msg,
)
from symloc.scan import LaserScan, mirror

__all__ = ["LocalizerFactory", "NodeCore", "Outputs"]

FloatArray = NDArray[np.float64]
#: ``factory(grid, params) -> Localizer`` (default :func:`symloc.ros.assemble.make_localizer`).
LocalizerFactory = Callable[[OccupancyGrid, NodeParams], Localizer]
#: A pose kept across a rebuild: (pose (3,), covariance (3, 3), the odometry pose (3,) it
#: refers to or None, whether it is an operator's pose not yet confirmed).
_Seed = tuple[FloatArray, FloatArray, FloatArray | None, bool]

_WARN_FIRST = 5
_WARN_EVERY = 100
#: Scans in a row not used before the status says ``lost`` (localization is not happening).
STALE_SCANS = 5
#: Latest stamp a ROS time can carry [s] (``builtin_interfaces/Time.sec`` is an int32).
MAX_STAMP = float(2**31 - 1)


@dataclass
class Outputs:
    """What to publish after one scan (field dicts; ``None``: publish nothing on that topic).

    ``used`` tells whether the localizer took the scan. A scan that was dropped still gets a
    ``status`` (the last status, its reason saying why this scan was not used; ``lost`` after
    :data:`STALE_SCANS` unused scans in a row) and nothing else. ``amcl_pose``
    (PoseWithCovarianceStamped, map frame) only while tracking, as nav2_amcl publishes only
    poses it has; ``goal`` (PoseStamped, odom frame) for go-to-centre, face and rotate requests;
    ``capture`` (std_msgs/Header) for a capture request; ``axis_pose``
    (PoseWithCovarianceStamped, map frame) only with status ``axis``: the middle of the
    corridor segment with the decided heading and its elongated covariance, on its own topic
    (never ``amcl_pose``, and no ``map -> odom``: nothing that drives the robot may take it
    for a pose).
    """

    estimate: Estimate
    stamp: float
    status: dict[str, Any]
    candidates: dict[str, Any] | None = None
    particle_cloud: dict[str, Any] | None = None
    amcl_pose: dict[str, Any] | None = None
    goal: dict[str, Any] | None = None
    capture: dict[str, Any] | None = None
    axis_pose: dict[str, Any] | None = None
    used: bool = True
    #: The tracker's best pose (3,) at this scan, earned or not, carried by odometry from its
    #: last filter update to the scan (for logs such as ``replay_scans.tum``; never published
    #: as a pose).
    best_estimate: FloatArray | None = None
    #: tf2_msgs/TFMessage fields with ``map -> odom`` (None: nothing to broadcast)
    tf: dict[str, Any] | None = None


class NodeCore:
    """Message handling of the symloc node (pure Python; see the module docstring).

    Parameters
    ----------
    params : NodeParams
    factory : callable, optional
        ``factory(grid, params) -> Localizer``; called when the first usable map arrives.
    warn : callable, optional
        Receives warning lines (the rclpy node passes its logger).
    use_tf : bool
        TF is fed (:meth:`on_tf`, :meth:`on_tf_static`): with ``laser_pose_source: tf`` the
        laser's mount comes from it (scans wait for it), not from ``laser_pose``.
    """

    def __init__(
        self,
        params: NodeParams,
        *,
        factory: LocalizerFactory | None = None,
        warn: Callable[[str], object] | None = None,
        use_tf: bool = False,
    ) -> None:
        if factory is None:
            factory = make_localizer
        self.params = params
        self.factory = factory
        self.warn = warn or (lambda text: None)
        self.dropped: Counter[str] = Counter()
        self.recovered: Counter[str] = Counter()
        self.received: Counter[str] = Counter()
        self.grid: OccupancyGrid | None = None
        self._map_std_xy: float | None = None  # the map's own error, as its file declares it
        self._map_error_field: MapErrorField | None = None  # and place by place
        self.localizer: Localizer | None = None
        self.scans_used = 0
        self.last: Outputs | None = None
        self._odom = OdometryBuffer()
        self._clock = StampGate(params.max_stamp_jump)
        self._odom_gate = OdometryGate(params.max_odom_speed)
        self._backwards: Counter[str] = Counter()
        self._failures = 0
        self._unused = 0
        self._last_drop = ("", "")
        self._beams = BeamCountGate()
        #: why the last map was refused ("" when none was), told with scans that find no map
        self._map_refused = ""
        self._last_scan_stamp = -math.inf
        self._image: tuple[float, NDArray[np.uint8]] | None = None
        self._want_image_after: float | None = None
        self.use_tf = bool(use_tf)
        #: the frames seen on /tf_static and /tf
        self.tf = TransformTree()
        #: the laser's mount the localizer was built for (None until the first scan)
        self.mount: LaserMount | None = None
        self.map_odom = self._map_odom(params)
        #: scans waiting for the odometry at their stamp: (scan, arrival time or None)
        self._pairing = ScanPairing()
        #: the last operator pose (pose, covariance, odometry pose then or None) not yet
        #: confirmed by tracking: a rebuild of the localizer seeds it again
        self._seed: tuple[FloatArray, FloatArray, FloatArray | None] | None = None
        #: the last confirmed pose (pose, covariance, odometry pose at its scan)
        self._confirmed: tuple[FloatArray, FloatArray, FloatArray] | None = None
        #: the pose kept across a rebuild, applied at the next step (:meth:`_reseed`)
        self._pending_seed: _Seed | None = None
        #: the odometry pose at the tracker's last filter update: its estimate is the robot's
        #: pose then, carried by odometry to later scans (:meth:`_best_estimate`)
        self._update_odom: FloatArray | None = None

    # ------------------------------------------------------------------ bookkeeping

    def drop(self, reason: str, detail: str = "") -> None:
        """Count a dropped message and warn (first few of each reason, then every 100th)."""
        self.dropped[reason] += 1
        self._last_drop = (reason, detail)
        n = self.dropped[reason]
        if n <= _WARN_FIRST or n % _WARN_EVERY == 0:
            extra = f": {detail}" if detail else ""
            self.warn(f"dropped ({reason}, {n} so far){extra}; still localizing")

    def _recover(self, what: str, detail: str) -> None:
        self.recovered[what] += 1
        self.warn(f"recovered ({what}): {detail}")

    def _frame_ok(self, got: str, want: str, reason: str) -> bool:
        if want and got != want:
            self.drop(reason, f"frame {got!r}, expected {want!r}")
            return False
        return True

    def _time_ok(self, stamp: float, stream: str, received: float | None = None) -> bool:
        """The time gate (:class:`~symloc.ros.guards.StampGate`) for a scan, odom or image
        received at ``received`` [s] on the receiver's clock (a bag's log time; None: unknown)."""
        if not (math.isfinite(stamp) and 0.0 <= stamp <= MAX_STAMP):
            self.drop(
                f"{stream}: stamp out of range",
                f"{stamp}: expected 0 .. {MAX_STAMP} s (builtin_interfaces/Time)",
            )
            return False
        clock = self._clock.clock
        verdict = self._clock.check(stamp, stream, received)
        if verdict == "far":
            self.drop(
                f"{stream}: stamp jump",
                f"{stamp:.3f} s is more than max_stamp_jump = {self.params.max_stamp_jump:g} s"
                f" from the node's clock {clock:.3f} s; not adopted",
            )
            return False
        if verdict == "rebase":
            self._odom = OdometryBuffer()
            self._odom_gate.restart_clock()
            self._last_scan_stamp = -math.inf
            self._backwards.clear()
            self._image = None
            if self._want_image_after is not None:
                self._want_image_after = -math.inf
            self._recover(
                "time base",
                f"the clock jumped from {clock:.3f} s to {stamp:.3f} s and {CONFIRM} messages"
                " agree: new time base, odometry history cleared",
            )
        return True

    # ------------------------------------------------------------------ map

    def on_map(self, msg: Any) -> None:
        """A nav_msgs/OccupancyGrid message."""
        self.received["map"] += 1
        try:
            frame = header_frame(msg, "OccupancyGrid")
            grid = grid_from_msg(msg, max_cells=self.params.max_map_cells)
        except SymlocError as err:
            self.drop("map: malformed", str(err))
            return
        if not self._frame_ok(frame, self.params.global_frame_id, "map: wrong frame"):
            return
        self.set_map(grid)

    def set_map(
        self,
        grid: OccupancyGrid,
        *,
        map_std_xy: float | None = None,
        map_error_field: MapErrorField | None = None,
    ) -> bool:
        """Use ``grid`` as nav2_amcl does: the first usable map builds the localizer, and every
        new map after it rebuilds the localizer on it unless ``first_map_only``. A pose held
        at the update (a tracked pose, or an operator's pose not yet confirmed) is seeded on
        the new map at the next scan, carried by odometry to its stamp; the claim gate confirms it at the next scans
        when the new map still fits the scan (else the pose is given up and earned again). A
        map the localizer cannot be built on or localize in (no free cell, no occupied cell,
        ...) is dropped and not stored. Returns whether the map is now in use.

        ``map_std_xy`` [m]: the map's own error as its file declares it
        (:attr:`symloc.grid.map_io.MapMetadata.map_std_xy`); the claim gate assumes the larger
        of it and ``claim.map_std_xy``; ``map_error_field`` its error place by place
        (:attr:`~symloc.grid.map_io.MapMetadata.map_error_field`), read by the claim gate where
        it is larger (``claim.map_error_field``). A map from the topic declares neither."""
        old = self.grid
        if old is not None:
            same_geometry = (
                old.data.shape == grid.data.shape
                and old.resolution == grid.resolution
                and np.array_equal(old.origin, grid.origin)
            )
            if same_geometry and np.array_equal(old.data, grid.data):
                return True  # re-published (transient local): nothing new
            if self.params.first_map_only:
                return False  # nav2's first_map_only: later maps are ignored
        previous_std, self._map_std_xy = self._map_std_xy, map_std_xy
        previous_field, self._map_error_field = self._map_error_field, map_error_field
        try:
            localizer = self._build(grid)
        except SymlocError as err:
            self._map_std_xy = previous_std
            self._map_error_field = previous_field
            detail = f"{grid.width}x{grid.height} cells: {err}"
            self.drop("map: unusable", detail)
            self._map_refused = "the last map was refused: " + detail
            return False
        self._map_refused = ""
        seed = self._pose_to_keep()
        self.grid = grid
        self.localizer = localizer
        self._failures = 0
        if old is None:
            return True
        kept = self._reseed(seed)
        self.warn(
            f"new map {grid.width}x{grid.height} cells: localizer rebuilt on it"
            + (f"; pose kept at {kept}" if kept else "; no pose to keep")
        )
        return True

    @property
    def map_refused(self) -> str:
        """Why the last map offered was refused ("" when it was used)."""
        return self._map_refused

    def _build(self, grid: OccupancyGrid) -> Localizer:
        """The factory's localizer on ``grid`` with :meth:`_build_params`, its claim gate
        given the map's error field (:meth:`set_map`)."""
        localizer = self.factory(grid, self._build_params())
        gate = getattr(localizer, "claim_gate", None)  # a scripted localizer has none
        if gate is not None:
            gate.map_error_field = self._map_error_field
        return localizer

    def _build_params(self) -> NodeParams:
        """The parameters the localizer is built with: the laser pose is the mount's, and the
        claim gate's map error at least the map's own (:meth:`set_map`)."""
        params = self.params
        claim = params.claim.with_map_error(self._map_std_xy)
        if claim is not params.claim:
            params = dataclasses.replace(params, claim=claim)
        if self.mount is None:
            return params
        return dataclasses.replace(params, laser_pose=tuple(float(v) for v in self.mount.pose))

    @staticmethod
    def _map_odom(params: NodeParams) -> MapToOdom:
        return MapToOdom(
            global_frame=params.global_frame_id,
            odom_frame=params.odom_frame_id,
            tolerance=params.transform_tolerance,
            enabled=params.tf_broadcast,
        )

    def rebuild(self, why: str) -> None:
        """Build the localizer again on the current map (new settings or a new laser mount),
        seeded at the pose held (tracked, or an operator's pose not yet confirmed) at the next
        scan, carried by odometry to its stamp."""
        if self.grid is None:
            return
        seed = self._pose_to_keep()
        self.localizer = self._build(self.grid)
        kept = self._reseed(seed)
        self.warn(f"localizer rebuilt: {why}" + (f"; pose kept at {kept}" if kept else ""))

    def _pose_to_keep(self) -> _Seed | None:
        """The pose a rebuilt localizer starts from: ``(pose, covariance, odometry pose then,
        operator)``; None when no pose is held."""
        if self._pending_seed is not None:  # rebuilt again before the next scan
            return self._pending_seed
        held = self.localizer is not None and self._holds_pose()
        if self._confirmed is not None and (held or self._tracking_now()):
            pose, cov, then = self._confirmed
            return pose, cov, then, False
        if self._seed is not None:
            pose, cov, then_seed = self._seed
            return pose, cov, then_seed, True
        return None

    def _tracking_now(self) -> bool:
        return self.last is not None and self.last.estimate.status is Status.TRACKING

    @staticmethod
    def _carry(pose: FloatArray, then: FloatArray | None, now: FloatArray | None) -> FloatArray:
        if then is None or now is None:
            return np.asarray(pose, dtype=np.float64).copy()
        out = compose(np.asarray(pose, dtype=np.float64), relative(then, now))
        out[2] = wrap_angle(out[2])
        return out

    def _reseed(self, seed: _Seed | None) -> list[float] | None:
        """Seed the (new) localizer at ``seed`` (:meth:`_pose_to_keep`) at the next scan, carried
        by odometry to that scan's stamp (a fresh filter applies no motion before its first
        update, so a pose carried only to now would lag the robot); the pose as of now."""
        self._pending_seed = None
        if seed is None or self.localizer is None or self.grid is None:
            return None
        pose, cov, then, _ = seed
        now = self._odom.poses[-1] if self._odom.stamps else None
        carried = self._carry(pose, then, now)
        if self._pose_problem(carried, cov) is not None:
            return None
        self._pending_seed = seed
        rounded: list[float] = np.round(carried, 3).tolist()
        return rounded

    def _apply_pending_seed(self, odom: OdometryReading) -> None:
        """Before a step: seed a rebuilt localizer at the pose kept, carried to ``odom``."""
        seed, self._pending_seed = self._pending_seed, None
        if seed is None or self.localizer is None:
            return
        pose, cov, then, operator = seed
        carried = self._carry(pose, then, np.asarray(odom.pose, dtype=np.float64))
        if self._pose_problem(carried, cov) is not None:
            return
        self.localizer.set_pose(carried, cov)
        if operator:
            self._seed = (carried, cov, np.asarray(odom.pose, dtype=np.float64).copy())

    def reconfigure(self, params: NodeParams) -> None:
        """Use new (validated) parameters from now on; the localizer is rebuilt on them."""
        self.params = params
        old, self.map_odom = self.map_odom, self._map_odom(params)
        if (old.global_frame, old.odom_frame) == (
            self.map_odom.global_frame,
            self.map_odom.odom_frame,
        ):
            self.map_odom.last, self.map_odom.confirmed_at = old.last, old.confirmed_at
            self.map_odom.holding = old.holding
        if not (self.use_tf and params.laser_pose_source == "tf"):
            # the mount from the (maybe changed) laser_pose; a TF mount stays as it is
            self.mount = LaserMount(np.array(params.laser_pose), params.laser_upside_down)
        self.rebuild("parameters changed")

    def reinitialize_global(self) -> bool:
        """Forget the pose and localize globally again (nav2's
        ``reinitialize_global_localization``); False without a map."""
        if self.localizer is None:
            return False
        self.localizer.reset_global()
        self._seed = None
        self._confirmed = None
        self._pending_seed = None
        self.map_odom.forget()
        self.warn("global localization requested: pose forgotten, AMCL spread over the map")
        return True

    def request_nomotion_update(self) -> bool:
        """Update the filter with the next scan even if the robot did not move (nav2's
        ``request_nomotion_update``); False without a localizer that can."""
        if self.localizer is None:
            return False
        self.localizer.force_update()
        return True

    # ------------------------------------------------------------------ TF

    def on_tf(self, msg: Any) -> None:
        """A tf2_msgs/TFMessage from ``/tf``: frames, and odometry from ``odom -> base``."""
        self._on_any_tf(msg, static=False)

    def on_tf_static(self, msg: Any) -> None:
        """A tf2_msgs/TFMessage from ``/tf_static`` (the robot's geometry)."""
        self._on_any_tf(msg, static=True)

    def _on_any_tf(self, msg: Any, *, static: bool) -> None:
        self.received["tf_static" if static else "tf"] += 1
        try:
            transforms = transforms_from_msg(msg)
        except SymlocError as err:
            self.drop("tf: malformed", str(err))
            return
        p = self.params
        for t in transforms:
            self.tf.add(t, static=static)
            if static:
                continue
            reading = odometry_from_transform(
                t, self.tf, odom_frame=p.odom_frame_id, base_frame=p.base_frame_id
            )
            if reading is not None:
                self.add_odometry(reading)

    def _laser_mount(self, frame: str) -> LaserMount | str:
        """The mount of the laser whose scans carry ``frame`` (a str says why it is unknown);
        a new or changed mount rebuilds the localizer for it."""
        base = self.params.base_frame_id
        if not self.use_tf or self.params.laser_pose_source != "tf" or not frame:
            mount = LaserMount(np.array(self.params.laser_pose), self.params.laser_upside_down)
        elif frame == base:
            mount = LaserMount(np.zeros(3))
        else:
            m = self.tf.lookup(base, frame)
            if m is None:
                return f"no transform {base} -> {frame} on /tf_static yet"
            mount = laser_mount(m)
            if not mount.level:
                return (
                    f"the scan plane of {frame} is tilted {math.degrees(mount.tilt):.0f} deg"
                    " from the floor; a 2D localizer needs a level laser"
                )
        old = self.mount
        if (
            old is None
            or old.upside_down != mount.upside_down
            or not np.allclose(old.pose, mount.pose, atol=1e-6)
        ):
            self.mount = mount
            if old is not None or np.any(mount.pose != 0.0) or mount.upside_down:
                self.rebuild(
                    f"laser {frame or '(no frame)'} at {np.round(mount.pose, 3).tolist()}"
                    f"{' upside down' if mount.upside_down else ''}"
                )
        return self.mount if self.mount is not None else mount

    # ------------------------------------------------------------------ odometry, pose, images

    def on_odom(self, msg: Any) -> None:
        """A nav_msgs/Odometry message."""
        self.received["odom"] += 1
        try:
            reading = odometry_from_msg(msg)
            frame = header_frame(msg, "Odometry")
            child = str(msg_field(msg, "child_frame_id", "Odometry")).lstrip("/")
        except SymlocError as err:
            self.drop("odom: malformed", str(err))
            return
        if not self._frame_ok(frame, self.params.odom_frame_id, "odom: wrong frame"):
            return
        if not self._frame_ok(child, self.params.base_frame_id, "odom: wrong child frame"):
            return
        self.add_odometry(reading)

    def add_odometry(self, reading: OdometryReading, *, received: float | None = None) -> None:
        """An odometry reading (odom frame), through the time and odometry gates; ``received``
        [s]: when it was received on the receiver's own clock (a bag's log time), which tells a
        pause in the stream from a clock jump (:class:`~symloc.ros.guards.StampGate`)."""
        raw = np.asarray(reading.pose, dtype=np.float64)
        if OdometryGate.absurd(raw):
            self.drop(
                "odom: absurd pose",
                f"{raw.tolist()}: expected finite coordinates within {MAX_ODOM_COORDINATE:g} m",
            )
            return
        if not self._time_ok(reading.stamp, "odom", received):
            return
        verdict = self._odom_gate.check(reading.stamp, raw)
        if verdict == "far":
            self.drop(
                "odom: jump",
                f"{raw.round(3).tolist()} at {reading.stamp:.3f} s moves faster than"
                f" max_odom_speed = {self.params.max_odom_speed:g} m/s; not adopted",
            )
            return
        if verdict == "rebase":
            self._recover(
                "odometry reset",
                f"odometry leapt and {CONFIRM} readings agree: re-anchored, no motion assumed"
                " across the leap",
            )
        corrected = OdometryReading(self._odom_gate.correct(raw), reading.stamp)
        if self._odom.add(corrected, self.params.max_odom_age):
            self._backwards["odom"] = 0
            return
        self._backwards["odom"] += 1
        if self._backwards["odom"] < CONFIRM:
            self.drop("odom: stamp went backwards", f"{reading.stamp:.3f} s")
            return
        self._odom.forget_after(reading.stamp)
        self._odom.add(corrected, self.params.max_odom_age)
        self._backwards["odom"] = 0
        self._recover(
            "odometry stamps",
            f"{CONFIRM} readings in a row older than the newest: the newer ones were outliers"
            " and are forgotten",
        )

    def on_image(self, msg: Any) -> None:
        """A sensor_msgs/Image message (decoded only while a capture is pending)."""
        self._on_any_image(msg, image_from_msg, "Image")

    def on_compressed_image(self, msg: Any) -> None:
        """A sensor_msgs/CompressedImage message (decoded only while a capture is pending)."""
        self._on_any_image(msg, compressed_image_from_msg, "CompressedImage")

    def _on_any_image(self, msg: Any, convert: Callable[..., Any], where: str) -> None:
        self.received["image"] += 1
        if self._want_image_after is None:
            return  # nothing requested: not decoded, not kept
        try:
            stamp = header_stamp(msg, where)
            frame = header_frame(msg, where)
            img = convert(msg, max_pixels=self.params.max_image_pixels)
        except SymlocError as err:
            self.drop("image: malformed", str(err))
            return
        if not self._frame_ok(frame, self.params.camera_frame_id, "image: wrong frame"):
            return
        self.add_image(img, stamp)

    def add_image(
        self, image: NDArray[np.uint8], stamp: float, *, received: float | None = None
    ) -> None:
        """Keep the newest ``(H, W, 3)`` RGB image while a capture request is pending
        (``received`` as in :meth:`add_odometry`)."""
        if self._want_image_after is None:
            return
        img = np.asarray(image)
        if img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
            self.drop("image: malformed", f"expected (H, W, 3) uint8, got {img.shape} {img.dtype}")
            return
        if img.shape[0] * img.shape[1] > self.params.max_image_pixels:
            self.drop(
                "image: too large",
                f"{img.shape[1]} x {img.shape[0]} pixels; max_image_pixels is"
                f" {self.params.max_image_pixels:,}",
            )
            return
        if not self._time_ok(float(stamp), "image", received):
            return
        self._image = (float(stamp), img)

    def on_initialpose(self, msg: Any) -> None:
        """A geometry_msgs/PoseWithCovarianceStamped (RViz's 2D Pose Estimate)."""
        self.received["initialpose"] += 1
        try:
            frame = header_frame(msg, "PoseWithCovarianceStamped")
            pose, cov = pose_with_covariance_from_msg(msg)
            stamp = header_stamp(msg, "PoseWithCovarianceStamped")
        except SymlocError as err:
            self.drop("initialpose: malformed", str(err))
            return
        if not self._frame_ok(frame, self.params.global_frame_id, "initialpose: wrong frame"):
            return
        # as nav2_amcl: a pose given for an earlier time is moved by the odometry since then
        self.set_initial_pose(self.carried_to_now(pose, stamp), cov)

    def set_initial_pose(self, pose: FloatArray, covariance: FloatArray) -> bool:
        """Reseed the localizer at ``pose`` (3,) with ``covariance`` (3, 3), if both make sense
        on the map (inside it; a finite, symmetric, positive semi-definite covariance no wider
        than the map). Returns whether the pose was taken."""
        if self.localizer is None or self.grid is None:
            self.drop("initialpose: no map yet")
            return False
        problem = self._pose_problem(pose, covariance)
        if problem is not None:
            self.drop("initialpose: rejected", problem)
            return False
        pose = np.asarray(pose, dtype=np.float64).copy()
        cov = np.asarray(covariance, dtype=np.float64).copy()
        try:
            self.localizer.set_pose(pose, cov)
        except SymlocError as err:
            self.drop("initialpose: rejected", str(err))
            return False
        # kept until tracking confirms it: a rebuild of the localizer (the laser's mount found
        # on /tf_static at the first scan, new parameters, a new map) seeds it again
        self._seed = (pose, cov, self._odom.poses[-1].copy() if self._odom.stamps else None)
        self._confirmed = None
        self._pending_seed = None
        self.map_odom.forget()
        self.warn(f"initial pose set to {np.asarray(pose).round(3).tolist()}")
        return True

    def _pose_problem(self, pose: Any, covariance: Any) -> str | None:
        """Why ``pose`` / ``covariance`` cannot seed the localizer on the map (None: they can)."""
        assert self.grid is not None
        g = self.grid
        p = np.asarray(pose, dtype=np.float64).reshape(-1)
        c = np.asarray(covariance, dtype=np.float64)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            return f"pose {p.tolist()}: expected finite x, y, theta"
        xmin, xmax, ymin, ymax = g.extent()
        diag = math.hypot(xmax - xmin, ymax - ymin)
        inside = np.all(np.abs(p[:2] - g.origin[:2]) <= 2.0 * diag) and bool(
            g.in_bounds(g.world_to_cell(p[:2]))[0]
        )
        if not inside:
            return (
                f"pose ({p[0]:.6g}, {p[1]:.6g}) m is outside the map"
                f" ({g.width} x {g.height} cells of {g.resolution:g} m from"
                f" ({g.origin[0]:.3f}, {g.origin[1]:.3f}))"
            )
        if c.shape != (3, 3) or not np.all(np.isfinite(c)):
            return f"covariance: expected a finite 3 x 3 matrix, got shape {c.shape}"
        if not np.allclose(c, c.T, rtol=1e-6, atol=1e-9):
            return "covariance: expected a symmetric matrix"
        evals = np.linalg.eigvalsh(c)
        if evals.min() < -1e-9 * max(1.0, float(np.abs(evals).max())):
            return f"covariance: expected positive semi-definite, eigenvalues {evals.tolist()}"
        if max(c[0, 0], c[1, 1]) > diag**2:
            return (
                f"covariance: position variance {max(c[0, 0], c[1, 1]):.3g} m^2 is wider than"
                f" the map ({diag:.1f} m across)"
            )
        if c[2, 2] > (2.0 * math.pi) ** 2:
            return f"covariance: heading variance {c[2, 2]:.3g} rad^2 exceeds (2 pi)^2"
        return None

    def carried_to_now(self, pose: FloatArray, stamp: float) -> FloatArray:
        """``pose`` (3,) given for time ``stamp``, moved by the odometry since then to the
        newest odometry reading (as nav2_amcl treats an initial pose from the past); unchanged
        when the odometry history does not cover ``stamp``."""
        then = self._odom.at(stamp, self.params.transform_tolerance)
        if isinstance(then, str) or not self._odom.stamps:
            return np.asarray(pose, dtype=np.float64)
        now = self._odom.poses[-1]
        return compose(np.asarray(pose, dtype=np.float64), relative(then.pose, now))

    # ------------------------------------------------------------------ scans

    def on_scan(self, msg: Any) -> Outputs:
        """A sensor_msgs/LaserScan message: one localizer step if everything is in place.

        Always returns :class:`Outputs` (with at least a status); ``used`` says whether the
        localizer took the scan.
        """
        self.received["scan"] += 1
        try:
            scan = scan_from_msg(msg)
        except SymlocError as err:
            self.drop("scan: malformed", str(err))
            return self.unused_scan(None)
        return self.add_scan(scan)

    def receive_scan(self, msg: Any, now: float | None = None) -> list[Outputs]:
        """A sensor_msgs/LaserScan message as the live node takes it (:meth:`offer_scan`: it
        waits for the odometry at its stamp); the outputs of the scans answered now."""
        self.received["scan"] += 1
        try:
            scan = scan_from_msg(msg)
        except SymlocError as err:
            self.drop("scan: malformed", str(err))
            return [*self.ready_scans(now), self.unused_scan(None)]
        return self.offer_scan(scan, now)

    def add_scan(self, scan: LaserScan, *, received: float | None = None) -> Outputs:
        """One localizer step with ``scan`` now (see :meth:`on_scan`), for callers that cannot
        wait (a simulator that publishes odometry before its scan): the odometry at the scan's
        stamp, interpolated, or the newest reading when the scan is newer than it by at most
        ``transform_tolerance``. The live node waits instead (:meth:`offer_scan`). ``received``
        as in :meth:`add_odometry`."""
        admitted = self._admit(scan, received)
        if isinstance(admitted, Outputs):
            return admitted
        odom = self._odom.at(admitted.stamp, self.params.transform_tolerance)
        if isinstance(odom, str):
            self.drop(f"scan: {odom}", f"scan at {admitted.stamp:.3f} s")
            return self.unused_scan(admitted.stamp)
        return self._step(admitted, odom)

    def offer_scan(
        self, scan: LaserScan, now: float | None = None, *, received: float | None = None
    ) -> list[Outputs]:
        """A scan as nav2_amcl's tf2 message filter takes it: paired with the odometry at its
        own stamp (interpolated between the readings around it). A scan newer than the newest
        odometry is held until the odometry reaches its stamp (:meth:`ready_scans`, called
        after each odometry reading) and dropped, counted under :data:`~symloc.ros.pairing.NO_ODOM_AT_STAMP`,
        when it has waited more than ``transform_tolerance`` (``now`` - its arrival, on the
        node's clock; or a newer scan stamped that much later), or more than
        :data:`~symloc.ros.pairing.MAX_HELD_SCANS` wait. Returns the outputs of the scans answered now, in order
        (none while this one waits). ``received`` as in :meth:`add_odometry`."""
        admitted = self._admit(scan, received)
        if isinstance(admitted, Outputs):
            return [*self.ready_scans(now), admitted]
        held = self._pairing.newest_stamp
        if held is not None and admitted.stamp < held:
            self.drop("scan: stamp went backwards", f"{admitted.stamp:.3f} s (held scans)")
            return [*self.ready_scans(now), self.unused_scan(admitted.stamp)]
        self._pairing.hold(admitted, now)
        return self.ready_scans(now)

    @property
    def pauses(self) -> int:
        """Stamps taken as time that passed, not a clock jump: far from the node's clock but
        received as late as the stream's messages usually are (:class:`StampGate`)."""
        return self._clock.pauses

    @property
    def held_scans(self) -> int:
        """Scans waiting for the odometry at their stamp."""
        return len(self._pairing)

    def ready_scans(self, now: float | None = None) -> list[Outputs]:
        """Answer the held scans the odometry now covers, and drop those that waited too long
        (:meth:`offer_scan`); their outputs in order."""
        outs: list[Outputs] = []
        for item in self._pairing.release(self._odom, self.params.transform_tolerance, now):
            if isinstance(item, Paired):
                outs.append(self._step(item.scan, item.odom))
            else:
                self.drop(item.reason, item.detail)
                outs.append(self.unused_scan(item.scan.stamp))
        return outs

    def _admit(self, scan: LaserScan, received: float | None = None) -> LaserScan | Outputs:
        """The checks a scan passes before it is paired with odometry: the scan to use (mirrored
        for an upside-down laser), or the outputs of a scan not used."""
        if not self._frame_ok(scan.frame_id, self.params.laser_frame_id, "scan: wrong frame"):
            return self.unused_scan(scan.stamp)
        expected = self._beams.count
        verdict = self._beams.check(len(scan))
        if verdict == "far":
            self.drop(
                "scan: wrong length",
                f"{len(scan)} beams, expected {expected} (the beam count of the scans used);"
                f" {self._beams.pending} of {CONFIRM} scans in a row of {len(scan)} beams make"
                " it the new beam count",
            )
            return self.unused_scan(scan.stamp)
        if verdict == "rebase":
            self._recover(
                "beam count",
                f"{CONFIRM} scans in a row of {len(scan)} beams, not {expected}: the laser's beam"
                f" count is now {len(scan)}",
            )
        if not np.any(scan.valid_mask):
            self.drop(
                "scan: no valid readings", f"all {len(scan)} readings NaN, inf or out of range"
            )
            return self.unused_scan(scan.stamp)
        if not self._time_ok(scan.stamp, "scan", received):
            return self.unused_scan(scan.stamp)
        if scan.stamp < self._last_scan_stamp:
            self._backwards["scan"] += 1
            if self._backwards["scan"] < CONFIRM:
                self.drop("scan: stamp went backwards", f"{scan.stamp:.3f} s")
                return self.unused_scan(scan.stamp)
            self._recover(
                "scan stamps",
                f"{CONFIRM} scans in a row older than {self._last_scan_stamp:.3f} s: that stamp"
                " was an outlier and is forgotten",
            )
            self._last_scan_stamp = -math.inf
        self._backwards["scan"] = 0
        if self.localizer is None:
            self.drop("scan: no map yet", self._map_refused)
            return self.unused_scan(scan.stamp)
        mount = self._laser_mount(scan.frame_id)
        if isinstance(mount, str):
            self.drop("scan: no laser pose", mount)
            return self.unused_scan(scan.stamp)
        return mirror(scan) if mount.upside_down else scan

    def _step(self, scan: LaserScan, odom: OdometryReading) -> Outputs:
        """One localizer step with an admitted scan and the odometry at its stamp."""
        if self.localizer is None:  # cleaned up meanwhile
            self.drop("scan: no map yet")
            return self.unused_scan(scan.stamp)
        image = None
        want, got = self._want_image_after, self._image
        if want is not None and got is not None and got[0] >= want - 1e-9:
            image = got[1]
        try:
            self._apply_pending_seed(odom)
            est = self.localizer.update(odom, scan, image)
        except Exception as err:  # the node must keep localizing: count, rebuild if it persists
            self.drop("scan: rejected by the localizer", f"{type(err).__name__}: {err}")
            self._localizer_failed()
            return self.unused_scan(scan.stamp)
        last = self.localizer.last_result
        if last is None or getattr(last, "updated", True):
            self._update_odom = np.asarray(odom.pose, dtype=np.float64).copy()
        self._failures = 0
        self._unused = 0
        self._beams.used(len(scan))
        self._last_scan_stamp = scan.stamp
        self.scans_used += 1
        if image is not None:
            self._want_image_after = None
            self._image = None
        if est.status is Status.TRACKING and est.pose is not None and est.covariance is not None:
            self._seed = None  # the operator's pose (if any) is confirmed: tracking carries it
            self._confirmed = (
                np.asarray(est.pose, dtype=np.float64).copy(),
                np.asarray(est.covariance, dtype=np.float64).copy(),
                np.asarray(odom.pose, dtype=np.float64).copy(),
            )
        elif not self._holds_pose():
            self._confirmed = None
        out = self._outputs(est, scan.stamp, odom)
        self.last = out
        return out

    def _holds_pose(self) -> bool:
        """The localizer still vouches for its last confirmed pose (``Localizer.holds_pose``;
        a localizer without that property never does)."""
        return bool(getattr(self.localizer, "holds_pose", False))

    def _localizer_failed(self) -> None:
        """After :data:`~symloc.ros.guards.CONFIRM` failures in a row, rebuild the localizer."""
        self._failures += 1
        if self._failures < CONFIRM or self.grid is None:
            return
        self._failures = 0
        try:
            # built for the laser mount in use, as every other build (not params.laser_pose)
            self.localizer = self._build(self.grid)
        except SymlocError as err:
            self.drop("localizer: cannot be rebuilt", str(err))
            return
        self._recover(
            "localizer", f"{CONFIRM} scans in a row failed: rebuilt (global initialisation)"
        )

    def unused_scan(self, stamp: float | None = None) -> Outputs:
        """The outputs (a status only) for a scan the localizer did not take (:class:`Outputs`);
        ``stamp`` None: the node's clock."""
        self._unused += 1
        if stamp is None or not (math.isfinite(stamp) and 0.0 <= stamp <= MAX_STAMP):
            stamp = self._clock.clock if self._clock.clock is not None else 0.0
        reason, detail = self._last_drop
        why = f"scan not used ({reason}{': ' + detail if detail else ''})"
        last = self.last.estimate if self.last is not None else None
        if last is None or self._unused >= STALE_SCANS:
            n = "" if last is None else f"; no scan used for {self._unused} scans"
            est = Estimate(Status.LOST, reason=why + n)
        else:
            est = dataclasses.replace(last, request=None, reason=f"{why}; last: {last.reason}")
        p = self.params
        out = Outputs(
            estimate=est,
            stamp=stamp,
            status=status_to_fields(
                est,
                stamp=stamp,
                frame_id=p.global_frame_id,
                scans_used=self.scans_used,
                dropped=self.dropped,
                recovered=self.recovered,
                scan_used=False,
            ),
            used=False,
        )
        if self._unused < STALE_SCANS and self._holds_pose():
            # one scan late or unusable: the pose is still held, map -> odom carries on
            out.tf = self.map_odom.resend(stamp)
        self._add_map_to_odom(out, stamp)
        return out

    def _add_map_to_odom(self, out: Outputs, stamp: float) -> None:
        """The status says what the broadcast ``map -> odom`` is (:mod:`symloc.ros.tf`)."""
        for diag in out.status.get("status", []):
            diag.setdefault("values", []).append(
                {"key": "map_to_odom", "value": self.map_odom.describe(stamp)}
            )

    def _outputs(self, est: Estimate, stamp: float, odom: OdometryReading) -> Outputs:
        p = self.params
        out = Outputs(
            estimate=est,
            stamp=stamp,
            status=status_to_fields(
                est,
                stamp=stamp,
                frame_id=p.global_frame_id,
                scans_used=self.scans_used,
                dropped=self.dropped,
                recovered=self.recovered,
            ),
            candidates=candidates_to_fields(est, stamp=stamp, frame_id=p.global_frame_id),
            best_estimate=self._best_estimate(np.asarray(odom.pose, dtype=np.float64)),
        )
        out.tf = self.map_odom.step(est, stamp, odom.pose, holds=self._holds_pose())
        self._add_map_to_odom(out, stamp)
        particles = self._particles()
        if particles is not None:
            out.particle_cloud = pose_array_to_fields(
                particles, stamp=stamp, frame_id=p.global_frame_id
            )
        if est.status is Status.TRACKING and est.pose is not None and est.covariance is not None:
            out.amcl_pose = pose_with_covariance_to_fields(
                est.pose, est.covariance, stamp=stamp, frame_id=p.global_frame_id
            )
        if est.status is Status.AXIS and est.axis is not None:
            out.axis_pose = pose_with_covariance_to_fields(
                est.axis.pose, est.axis.covariance, stamp=stamp, frame_id=p.global_frame_id
            )
        req = est.request
        if req is None or req.kind is not RequestKind.CAPTURE_IMAGE:
            self._want_image_after = None
            self._image = None
        if req is not None:
            # goals are for the robot: in its own (uncorrected) odometry frame
            o = self._odom_gate.uncorrect(np.asarray(odom.pose, dtype=np.float64))
            if req.kind in (RequestKind.GO_TO_CENTRE, RequestKind.GO_TO) and req.target is not None:
                t = np.asarray(req.target, dtype=np.float64)
                goal = compose(o, np.array([t[0], t[1], math.atan2(t[1], t[0])]))
                out.goal = pose_stamped_to_fields(goal, stamp=stamp, frame_id=p.odom_frame_id)
            elif req.kind in (RequestKind.FACE_DIRECTION, RequestKind.ROTATE):
                goal = compose(o, np.array([0.0, 0.0, float(req.angle or 0.0)]))
                out.goal = pose_stamped_to_fields(goal, stamp=stamp, frame_id=p.odom_frame_id)
            elif req.kind is RequestKind.CAPTURE_IMAGE:
                # from the first request of a run: an image taken after it answers the repeats
                if self._want_image_after is None:
                    self._want_image_after = stamp
                frame = p.camera_frame_id or p.base_frame_id
                out.capture = header_fields(stamp, frame)
        return out

    def _best_estimate(self, odom: FloatArray) -> FloatArray | None:
        """The tracker's estimate as the robot's pose at the scan whose odometry pose is
        ``odom`` (3,): a filter that did not update at this scan (the robot moved less than
        ``update_min_d`` / ``update_min_a``) holds its estimate at its last update, so the
        estimate is carried by the odometry since then, as nav2's ``map -> odom`` places the
        robot between updates. None when there is no finite estimate."""
        last = None if self.localizer is None else self.localizer.last_result
        if last is None:
            return None
        arr = np.asarray(last.estimate, dtype=np.float64).reshape(-1)
        if arr.shape != (3,) or not np.all(np.isfinite(arr)):
            return None
        if not getattr(last, "updated", True) and self._update_odom is not None:
            return self._carry(arr, self._update_odom, odom)
        return arr.copy()

    def _particles(self) -> FloatArray | None:
        last = None if self.localizer is None else self.localizer.last_result
        if last is None or last.particles is None:
            return None
        arr = np.asarray(last.particles, dtype=np.float64).reshape(-1, 3)
        return arr if arr.size else None
