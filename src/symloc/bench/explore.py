"""A seeded, collision-free exploratory drive (what a nav2 user does to let AMCL converge).

The same kind of drive as ``symloc experiment amcl-symmetric``: forward at ``speed`` with a
random turn rate redrawn every ``redraw`` seconds; when the point ``lookahead`` metres ahead
comes closer than ``clearance`` to an obstacle, the robot stops and turns on the spot in one
direction for a random while (it never pushes into a wall). The drive is open-loop in the
robot's true pose, as a teleoperator watching the robot would drive it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError

__all__ = ["ExploreConfig", "ExploreDrive"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ExploreConfig:
    """Settings of :class:`ExploreDrive`.

    speed [m/s] forward speed; max_turn [rad/s] largest random turn rate while driving;
    redraw [s] between random turn rates; lookahead [m] and clearance [m] of the obstacle check;
    spin [rad/s] turn rate when avoiding; spin_time (lo, hi) [s] random avoiding duration.
    """

    speed: float = 0.3
    max_turn: float = 0.8
    redraw: float = 1.0
    lookahead: float = 0.35
    clearance: float = 0.25
    spin: float = 1.5
    spin_time: tuple[float, float] = (0.5, 1.5)
    body_clearance: float = 0.26

    def __post_init__(self) -> None:
        for name in (
            "speed",
            "max_turn",
            "redraw",
            "lookahead",
            "clearance",
            "spin",
            "body_clearance",
        ):
            check_positive(getattr(self, name), name)
        lo, hi = self.spin_time
        if not 0.0 < lo <= hi:
            raise ConfigurationError(
                f"spin_time: expected 0 < lo <= hi [s], got {self.spin_time!r}"
            )


class ExploreDrive:
    """Commands ``(v, w)`` for a random collision-free drive.

    Parameters
    ----------
    distance : callable
        ``distance(points (N, 2)) -> (N,)`` distance [m] to the nearest obstacle
        (e.g. ``World.distance``).
    rng : Generator
        Source of the random turn rates (seeded by the caller).
    config : ExploreConfig, optional
    """

    def __init__(self, distance, rng: np.random.Generator, config: ExploreConfig | None = None):  # type: ignore[no-untyped-def]
        self.distance = distance
        self.rng = rng
        self.config = config if config is not None else ExploreConfig()
        self._w = 0.0
        self._since = math.inf
        self._spin_left = 0.0
        self._spin_dir = 1.0

    def _blocked(self, pose: FloatArray) -> bool:
        c = self.config
        u = np.array([math.cos(pose[2]), math.sin(pose[2])])
        pts = np.stack([pose[:2] + c.lookahead * u, pose[:2], pose[:2] + 0.1 * u])
        d = np.asarray(self.distance(pts), dtype=np.float64)
        return bool(d[0] < c.clearance or (d[1] < c.body_clearance and d[2] < d[1]))

    def command(self, pose: FloatArray, dt: float) -> tuple[float, float]:
        """The command for the next ``dt`` [s] from the true pose (3,)."""
        c = self.config
        p = np.asarray(pose, dtype=np.float64)
        if self._spin_left > 0.0:
            self._spin_left -= dt
            return 0.0, self._spin_dir * c.spin
        if self._blocked(p):
            self._spin_left = float(self.rng.uniform(*c.spin_time)) - dt
            self._spin_dir = 1.0 if self.rng.random() < 0.5 else -1.0
            return 0.0, self._spin_dir * c.spin
        if self._since >= c.redraw:
            self._w = float(self.rng.uniform(-c.max_turn, c.max_turn))
            self._since = 0.0
        self._since += dt
        return c.speed, self._w
