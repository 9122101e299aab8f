"""People walking: round obstacles that move along polylines at a steady walking speed.

A :class:`Person` is a vertical cylinder (radius ~0.2-0.3 m, height ~1.7 m, material
``MATERIAL_PERSON``) walking along its waypoints at ``speed`` [m/s]: to the last waypoint and
back again (``loop=False``) or round a closed loop (``loop=True``), starting ``phase`` [m] along
the way at t = 0. The lidar sees a person as a circle at the beam plane (legs and hips are
lumped into one cylinder), the camera as a tall plain obstacle in front of the walls.

:func:`people_world` turns the people at time t into a :class:`~symloc.sim.world.World` to merge
with the static one (``Room.world_at`` does that).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import WorldError
from symloc.sim.world import MATERIAL_PERSON, World

__all__ = ["PERSON_HEIGHT", "PERSON_RADIUS", "WALKING_SPEED", "Person", "people_world"]

FloatArray = NDArray[np.float64]

PERSON_RADIUS = 0.25
"""Default radius [m] of a walking person's footprint (shoulder width about 0.5 m)."""
PERSON_HEIGHT = 1.7
"""Default height [m] of a person."""
WALKING_SPEED = 1.0
"""Default walking speed [m/s] (people walk indoors at about 0.8-1.4 m/s)."""


@dataclass(frozen=True, eq=False)
class Person:
    """One person walking along a polyline.

    Parameters
    ----------
    waypoints : array of shape (P, 2)
        The path [m], P >= 2, with no zero-length leg.
    speed : float
        Walking speed [m/s], > 0.
    radius : float
        Footprint radius [m], > 0.
    height : float
        Height [m], > 0.
    loop : bool
        True: walk round the closed polygon of the waypoints; False: walk to the last waypoint
        and back.
    phase : float
        Distance [m] along the way at t = 0, >= 0.
    """

    waypoints: FloatArray
    speed: float = WALKING_SPEED
    radius: float = PERSON_RADIUS
    height: float = PERSON_HEIGHT
    loop: bool = False
    phase: float = 0.0

    def __post_init__(self) -> None:
        try:
            w = np.array(self.waypoints, dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise WorldError("Person.waypoints: expected (P, 2) coordinates") from err
        if w.ndim != 2 or w.shape[1] != 2 or w.shape[0] < 2 or not np.all(np.isfinite(w)):
            raise WorldError(
                f"Person.waypoints: expected >= 2 finite (x, y) points, got shape {w.shape}"
            )
        for name in ("speed", "radius", "height"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0):
                raise WorldError(f"Person.{name}: expected a finite value > 0, got {v}")
        if not (math.isfinite(float(self.phase)) and self.phase >= 0):
            raise WorldError(f"Person.phase: expected a finite value >= 0 m, got {self.phase}")
        legs = np.hypot(*np.diff(self._closed(w), axis=0).T)
        if np.any(legs <= 1e-9):
            i = int(np.flatnonzero(legs <= 1e-9)[0])
            raise WorldError(f"Person.waypoints[{i + 1}]: repeats the waypoint before it")
        w.setflags(write=False)
        object.__setattr__(self, "waypoints", w)

    def _closed(self, w: FloatArray) -> FloatArray:
        return np.vstack([w, w[:1]]) if self.loop else w

    @property
    def path(self) -> FloatArray:
        """The polyline ``(Q, 2)`` walked once round (closed when ``loop``)."""
        return self._closed(self.waypoints)

    @property
    def length(self) -> float:
        """Length [m] of one lap (loop) or of one way (to the end and back is twice this)."""
        return float(np.sum(np.hypot(*np.diff(self.path, axis=0).T)))

    @property
    def period(self) -> float:
        """Time [s] after which the motion repeats."""
        lap = self.length if self.loop else 2.0 * self.length
        return lap / self.speed

    def positions(self, times: ArrayLike) -> FloatArray:
        """Positions ``(T, 2)`` [m] at ``times`` ``(T,)`` [s]."""
        t = np.atleast_1d(np.asarray(times, dtype=np.float64))
        path = self.path
        cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
        total = cum[-1]
        s = self.phase + self.speed * t
        if self.loop:
            s = np.mod(s, total)
        else:
            s = np.mod(s, 2.0 * total)
            s = np.where(s > total, 2.0 * total - s, s)
        leg = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(cum) - 2)
        f = (s - cum[leg]) / (cum[leg + 1] - cum[leg])
        return np.asarray(path[leg] + f[:, None] * (path[leg + 1] - path[leg]), dtype=np.float64)

    def position(self, t: float) -> FloatArray:
        """Position ``(2,)`` [m] at time ``t`` [s]."""
        return np.asarray(self.positions([t])[0], dtype=np.float64)


def people_world(
    people: Sequence[Person],
    t: float,
    clear_of: tuple[ArrayLike, float] | None = None,
) -> World:
    """The people at time ``t`` [s] as circles (material ``MATERIAL_PERSON``).

    ``clear_of`` = (centre (2,) [m], radius [m]) of a round robot: a person whose path crosses
    it steps aside, to stand just touching it (moved straight away from its centre), as people
    do; their paths are scripted and know nothing of the robot, and a lidar inside a person
    would see only the person, all round it at a few centimetres (a robot that cannot exist:
    on the bench such scans fitted no pose of the map, and a small round room with three
    people walking its middle was never decided)."""
    if not people:
        return World()
    centres = np.array([p.position(t) for p in people])
    radii = np.array([p.radius for p in people])
    if clear_of is not None:
        centres = _stepped_aside(centres, radii, clear_of)
    return World(
        circles=np.column_stack([centres, radii]),
        circle_heights=np.array([p.height for p in people]),
        circle_materials=MATERIAL_PERSON,
    )


def _stepped_aside(
    centres: FloatArray, radii: FloatArray, clear_of: tuple[ArrayLike, float]
) -> FloatArray:
    """``centres`` (K, 2) [m] of people of ``radii`` (K,), those overlapping the round robot
    ``clear_of`` moved straight away from its centre to touch it (along +x from the exact
    centre)."""
    centre = np.asarray(clear_of[0], dtype=np.float64).reshape(-1)
    radius = float(clear_of[1])
    if centre.size not in (2, 3) or not np.all(np.isfinite(centre)):
        raise WorldError(
            f"people_world clear_of: expected a robot position (2,) or pose (3,), got {centre!r}"
        )
    if not (math.isfinite(radius) and radius >= 0.0):
        raise WorldError(f"people_world clear_of: expected a robot radius >= 0 m, got {radius!r}")
    centre = centre[:2]
    reach = radii + radius
    away = centres - centre
    dist = np.hypot(away[:, 0], away[:, 1])
    inside = dist < reach
    if not inside.any():
        return centres
    unit = np.where(
        dist[:, None] > 1e-9, away / np.maximum(dist, 1e-9)[:, None], np.array([1.0, 0.0])
    )
    out = centres.copy()
    out[inside] = centre + unit[inside] * reach[inside, None]
    return out
