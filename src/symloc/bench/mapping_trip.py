"""The mapping stage (the paper's Figure 2): visual maps of the symmetric places, and
optionally keyframes all along the trip (:class:`KeyframeRecorder`).

While the occupancy grid is built, every scan is judged (Algorithm 1). At a symmetric place the
robot goes to the geometric centre and faces the middle between two adjacent corners
(Algorithm 2), captures M images turning clockwise by 360/M between them (Algorithm 3), and the
images are stored with the place's kind, order and G-V distance in the visual map database
(whose G-V column is the G-V index). The map pose of the centre and of direction 0 come from the
mapping pose source (the SLAM estimate; ground truth in a simulator).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import angle_diff, compose, wrap_angle
from symloc.localizer.centering import CenteringConfig
from symloc.localizer.directions import directions_for
from symloc.localizer.types import Place, SymmetryJudge
from symloc.vision.keyframes import KeyframeRecorder

from .episode import Body, CenteringRun, ImageFn, ScanFn, go_to_centre

__all__ = ["KeyframeRecorder", "MappedPlace", "directions_for", "known_places", "map_place"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class MappedPlace:
    """A place recorded by :func:`map_place`.

    ``place`` is what the store returned; ``images`` the M images in clockwise order;
    ``centering`` the Algorithm 2 run; ``headings`` (M,) map headings of the images [rad].
    """

    place: Place
    images: tuple[NDArray[np.uint8], ...]
    headings: FloatArray
    centering: CenteringRun


def _turn_by(
    body: Body, angle: float, dt: float, cfg: CenteringConfig, tol: float = math.radians(0.5)
) -> None:
    """Turn on the spot by ``angle`` [rad] measured by odometry."""
    start = float(body.odom.pose[2])
    for _ in range(2000):
        odom = body.odom
        remaining = float(angle_diff(angle, angle_diff(odom.pose[2], start)))
        if abs(remaining) <= tol:
            return
        w = float(
            np.clip(cfg.angular_gain * remaining, -cfg.max_angular_speed, cfg.max_angular_speed)
        )
        if abs(w * dt) > abs(remaining):
            w = remaining / dt
        body.drive(0.0, w, dt)


def map_place(
    body: Body,
    scan_at: ScanFn,
    image_at: ImageFn,
    judge: SymmetryJudge,
    add_place: Callable[..., Place],
    *,
    map_pose: Callable[[], FloatArray],
    dt: float = 0.2,
    config: CenteringConfig | None = None,
    true_centre: FloatArray | None = None,
    max_time: float = 120.0,
) -> MappedPlace | None:
    """Record the visual map of the symmetric place the robot is in; ``None`` if not symmetric.

    Parameters
    ----------
    body, scan_at, image_at : the simulated robot, lidar and camera.
    judge : SymmetryJudge
    add_place : callable
        ``add_place(center, heading0, order, gv_distance, kind, images, headings=...) -> Place``
        (a
        :class:`~symloc.localizer.types.PlaceStore`'s method).
    map_pose : callable
        The robot's current pose in the map frame (SLAM's estimate, or ground truth).
    true_centre : ndarray (2,), optional
        For the centering run's error report only.
    """
    cfg = config if config is not None else CenteringConfig()
    # go_to_centre explores towards the middle of the scan while no verdict is symmetric yet
    # (e.g. the far walls are beyond range) and gives up after ``explore_time``
    run = go_to_centre(
        body,
        scan_at,
        judge,
        true_centre=np.zeros(2) if true_centre is None else np.asarray(true_centre),
        config=cfg,
        dt=dt,
        max_time=max_time,
    )
    if run.phase != "done":
        return None
    verdict = judge(scan_at(body.pose))
    if not verdict.symmetric or verdict.center is None or verdict.order is None:
        return None
    kind, order, gv = verdict.kind, verdict.order, verdict.gv_distance
    if not math.isfinite(gv):
        return None  # no G-V distance (an open hallway): the place cannot be indexed
    m = directions_for(kind, order)
    pose0 = np.asarray(map_pose(), dtype=np.float64)
    centre = compose(pose0, np.array([*verdict.center, 0.0]))[:2]
    heading0 = float(pose0[2])
    images = [image_at(body.pose)]
    headings = [heading0]
    for _j in range(1, m):
        _turn_by(body, -2.0 * math.pi / m, dt, cfg)
        # square up on the nearest corner middle (odometry turns are not exact)
        for _ in range(3):
            v = judge(scan_at(body.pose))
            if not (v.symmetric and v.facing is not None) or abs(v.facing) <= cfg.facing_tolerance:
                break
            _turn_by(body, float(v.facing), dt, cfg)
        images.append(image_at(body.pose))
        headings.append(float(map_pose()[2]))
    place = add_place(centre, heading0, order, gv, kind, images, headings=headings)
    return MappedPlace(
        place=place,
        images=tuple(images),
        headings=np.asarray(wrap_angle(np.asarray(headings))),
        centering=run,
    )


def known_places(places: Sequence[MappedPlace]) -> list[Place]:
    """The localizer's ``known_places`` from mapped places."""
    return [p.place for p in places]
