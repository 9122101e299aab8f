"""GMapping (the paper's SLAM) as a same-run peer: build it, feed it symloc's input, read its poses.

GMapping's core (``ros-perception/openslam_gmapping``, commit :data:`GMAPPING_COMMIT`) is
compiled without ROS by the harness's ``build.sh`` (``../shared/peers/gmapping``, g++ only)
from a source checkout the user gives (``--peer-src``); nothing of GMapping is part of
symloc. The driver that runs it on a CARMEN log is ``gmapping_carmen.cpp`` beside this file:
the harness's driver plus the log's beam geometry (``--angleMin``, ``--angleIncrement``),
which ROS ``slam_gmapping`` also takes from each scan.

Input (:func:`write_peer_log`): one ``FLASER`` line per scan with symloc's ranges and the
odometry under test written into *both* pose fields, so that no corrected pose reaches the
peer. Parameters: the ROS ``slam_gmapping`` defaults (30 particles, linearUpdate 1 m,
angularUpdate 0.5 rad, srr 0.1, srt 0.2, str 0.1, stt 0.2, sigma 0.05, lsigma 0.075, ogain 3,
delta 0.05 m), maxRange = maxUrange = 49.99 m, the same for every log. Output: the best
particle's trajectory, one pose per scan (scans it did not process follow the odometry from
its last processed scan).
"""

from __future__ import annotations

import hashlib
import os
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_array
from symloc.bench.measure import MeasuredRun, run_measured
from symloc.errors import SymlocError
from symloc.files.atomic import atomic_open
from symloc.scan import LaserScan

__all__ = [
    "GMAPPING_COMMIT",
    "GMappingPeer",
    "PeerRun",
    "PeerUnavailableError",
    "find_peer_harness",
    "write_peer_log",
]

FloatArray = NDArray[np.float64]

#: The openslam_gmapping commit the harness was written for.
GMAPPING_COMMIT = "5105476edb125bd3e05df3583b5817c486238dec"
#: symloc's driver source (package data).
DRIVER = Path(__file__).with_name("gmapping_carmen.cpp")


class PeerUnavailableError(SymlocError):
    """A peer cannot be built or run here (no source, no harness, no compiler, it failed)."""


def find_peer_harness(name: str) -> Path | None:
    """``$SYMLOC_SHARED_PEERS/<name>`` or ``<repo>/../shared/peers/<name>``, if it exists."""
    env = os.environ.get("SYMLOC_SHARED_PEERS")
    cands = [Path(env) / name] if env else []
    cands.append(Path(__file__).resolve().parents[4] / ".." / "shared" / "peers" / name)
    for c in cands:
        if (c / "build.sh").is_file():
            return c.resolve()
    return None


def write_peer_log(
    path: str | Path,
    scans: Sequence[LaserScan],
    odometry: ArrayLike,
    stamps: ArrayLike | None = None,
) -> Path:
    """Write a CARMEN log of ``FLASER`` lines: the ranges and ``odometry`` (N, 3) as both poses.

    ``stamps`` (N,) [s] default to the scans' own. Returns ``path``.
    """
    odo = check_array(odometry, "odometry", shape=(len(scans), 3))
    st = (
        np.array([s.stamp for s in scans], dtype=np.float64)
        if stamps is None
        else np.asarray(stamps, dtype=np.float64).reshape(len(scans))
    )
    p = Path(path)
    with atomic_open(p, "w", encoding="ascii") as fh:
        for scan, pose, t in zip(scans, odo, st, strict=True):
            r = np.where(np.isfinite(scan.ranges), scan.ranges, scan.range_max)
            vals = " ".join(f"{v:.4f}" for v in r)
            xyz = f"{pose[0]:.6f} {pose[1]:.6f} {pose[2]:.6f}"
            fh.write(f"FLASER {r.size} {vals} {xyz} {xyz} {t:.6f} symloc {t:.6f}\n")
    return p


@dataclass(frozen=True, eq=False)
class PeerRun:
    """A peer's trajectory on one log.

    Attributes
    ----------
    name : str
    poses : ndarray of shape (N, 3)
        One pose per scan of the input.
    processed : ndarray of shape (N,)
        Scans the peer integrated (the others follow odometry from the last processed one).
    measured : MeasuredRun
        Peak memory and CPU time of the peer's process.
    """

    name: str
    poses: FloatArray
    processed: NDArray[np.bool_]
    measured: MeasuredRun


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "symloc" / "peers"


@dataclass(frozen=True)
class GMappingPeer:
    """A built GMapping driver. Use :meth:`build`, then :meth:`run` per log."""

    binary: Path
    name: str = "gmapping"

    @classmethod
    def build(
        cls,
        source: str | Path,
        *,
        harness: str | Path | None = None,
        build_dir: str | Path | None = None,
    ) -> GMappingPeer:
        """Compile GMapping from the checkout ``source`` with the harness's ``build.sh``.

        The build goes to ``build_dir`` (default ``~/.cache/symloc/peers/gmapping-<hash>``)
        and is reused when the driver binary is already there.

        Raises
        ------
        PeerUnavailableError
            ``source`` is not an openslam_gmapping checkout, the harness is missing, or the
            compiler failed (the message carries its last lines).
        """
        src = Path(source).expanduser().resolve()
        if not (src / "gridfastslam" / "gridslamprocessor.cpp").is_file():
            raise PeerUnavailableError(
                f"--peer-src {src}: expected an openslam_gmapping checkout (commit"
                f" {GMAPPING_COMMIT[:7]}; with the fetch tool: github:ros-perception/openslam_gmapping)"
            )
        har = Path(harness).resolve() if harness is not None else find_peer_harness("gmapping")
        if har is None or not (har / "build.sh").is_file():
            raise PeerUnavailableError(
                "GMapping harness not found: set SYMLOC_SHARED_PEERS to the folder holding"
                " gmapping/build.sh (../shared/peers)"
            )
        driver = DRIVER.read_bytes()
        key = hashlib.sha256(str(src).encode() + driver).hexdigest()[:12]
        out = Path(build_dir) if build_dir is not None else _cache_dir() / f"gmapping-{key}"
        binary = out / "gmapping_carmen_symloc"
        if binary.is_file():
            return cls(binary)
        out.mkdir(parents=True, exist_ok=True)
        env = {**os.environ, "GMAPPING_SRC": str(src), "BUILD": str(out)}
        steps = [
            ["bash", str(har / "build.sh")],
            [
                os.environ.get("CXX", "g++"),
                "-O3",
                "-DNDEBUG",
                "-std=c++11",
                "-w",
                f"-I{src / 'include'}",
                f"-I{out / 'gen'}",
                str(DRIVER),
                str(out / "libgmapping_core.a"),
                "-o",
                str(binary),
            ],
        ]
        for cmd in steps:
            try:
                done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
            except OSError as err:
                raise PeerUnavailableError(f"GMapping build: cannot run {cmd[0]!r}: {err}") from err
            if done.returncode != 0:
                tail = "\n".join((done.stdout + done.stderr).strip().splitlines()[-8:])
                raise PeerUnavailableError(f"GMapping build failed ({' '.join(cmd[:2])}):\n{tail}")
        return cls(binary)

    def run(
        self,
        log: str | Path,
        *,
        n_scans: int,
        angle_min: float,
        angle_increment: float,
        seed: int = 0,
        timeout: float | None = None,
    ) -> PeerRun:
        """Run on a log written by :func:`write_peer_log` with ``n_scans`` scans.

        Raises
        ------
        PeerUnavailableError
            The driver failed or gave another number of poses.
        """
        traj = Path(str(log) + ".gmapping.traj")
        m = run_measured(
            [
                self.binary,
                "--log",
                str(log),
                "--out",
                str(traj),
                "--seed",
                str(int(seed)),
                "--angleMin",
                repr(float(angle_min)),
                "--angleIncrement",
                repr(float(angle_increment)),
            ],
            timeout=timeout,
        )
        if m.returncode != 0 or not traj.is_file():
            tail = "\n".join(m.stderr.strip().splitlines()[-5:])
            why = "timed out" if m.timed_out else f"exit code {m.returncode}"
            raise PeerUnavailableError(f"gmapping on {log}: {why}\n{tail}")
        rows = np.loadtxt(traj, comments="#", ndmin=2)
        traj.unlink()
        if rows.shape[0] != n_scans or rows.shape[1] != 6:
            raise PeerUnavailableError(
                f"gmapping on {log}: expected {n_scans} poses, got {rows.shape[0]}"
            )
        return PeerRun(self.name, rows[:, 3:6].copy(), rows[:, 2] > 0, m)
