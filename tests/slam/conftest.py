"""Small synthetic worlds for the SLAM tests: wall segments and an exact ray caster."""

from __future__ import annotations

import numpy as np
import pytest

from symloc.scan import LaserScan


def raycast(segments: np.ndarray, pose: np.ndarray, angles: np.ndarray, rmax: float) -> np.ndarray:
    """Exact ranges (B,) from ``pose`` along ``angles`` (sensor frame) to ``segments`` (S, 4)."""
    a = pose[2] + angles
    d = np.stack([np.cos(a), np.sin(a)], axis=1)[:, None, :]  # (B, 1, 2)
    p = segments[None, :, :2]
    q = segments[None, :, 2:] - segments[None, :, :2]
    o = pose[None, None, :2]
    den = d[..., 0] * q[..., 1] - d[..., 1] * q[..., 0]
    w = p - o
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * q[..., 1] - w[..., 1] * q[..., 0]) / den
        u = (w[..., 0] * d[..., 1] - w[..., 1] * d[..., 0]) / den
    ok = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1)
    t = np.where(ok, t, np.inf)
    r = t.min(axis=1)
    return np.where(r < rmax, r, np.inf)


def room_segments() -> np.ndarray:
    """An 8 m x 6 m room with an inner wall, a pillar and a diagonal: no symmetry."""
    pts = [
        (0, 0, 8, 0), (8, 0, 8, 6), (8, 6, 0, 6), (0, 6, 0, 0),
        (3, 0, 3, 1.5), (5.5, 4, 6.5, 4), (6.5, 4, 6.5, 5), (6.5, 5, 5.5, 5), (5.5, 5, 5.5, 4),
        (0, 4.5, 1.5, 6), (7, 1, 7.5, 1.5),
    ]  # fmt: skip
    # shifted off the 5 cm cell grid so walls do not sit exactly on cell boundaries
    return np.array(pts, dtype=float) + np.array([0.013, 0.027, 0.013, 0.027])


def make_scan(
    segments: np.ndarray,
    pose: np.ndarray,
    rng: np.random.Generator | None = None,
    n: int = 181,
    sigma: float = 0.01,
) -> LaserScan:
    angles = np.linspace(-np.pi / 2, np.pi / 2, n)
    r = raycast(segments, pose, angles, 12.0)
    if rng is not None:
        r = r + rng.normal(0, sigma, r.size)
    return LaserScan(-np.pi / 2, np.pi / (n - 1), 0.05, 12.0, r)


@pytest.fixture
def room() -> np.ndarray:
    return room_segments()
