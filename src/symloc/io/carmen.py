"""Reader for CARMEN laser logs (``FLASER`` and ``ODOM`` messages), plain or gzip-compressed.

Line formats (fields separated by white space)::

    FLASER n r1 ... rn x y theta odom_x odom_y odom_theta timestamp hostname logger_timestamp
    ODOM x y theta tv rv accel timestamp hostname logger_timestamp

``x y theta`` of a ``FLASER`` line is the laser pose in the world frame (in the "corrected" logs
of the Radish repository it is the pose a SLAM system estimated, used here as the reference
trajectory); ``odom_*`` is the odometry pose at the scan. Readings at or above ``range_max``
mean "no return" (the logs use 50, 80 or 81.91 for that). ``PARAM`` lines are collected; ``#``
comments and blank lines are ignored; any other message type is skipped and counted in
:attr:`CarmenLog.skipped`.

Beam geometry (:func:`carmen_beam_geometry`): the ``n`` ranges span the front field of view
``fov`` (default 180 degrees) from ``-fov/2``; beam ``i`` points at ``-fov/2 + i * step``. The
step is the scanner's angular resolution: the ``laser_front_laser_resolution`` PARAM [deg]
where the log has it, else ``fov / (n - 1)`` for an odd ``n`` (a SICK LMS sweep with both ends,
181 or 361 beams) and ``fov / n`` for an even ``n`` (180 or 360 beams: the last beam of the
sweep dropped, beam 0 at -90 degrees). ``fov`` comes from the ``laser_front_laser_fov`` PARAM
where present. Checked against the data: with the corrected poses, the scans of every shared
log fit each other best with exactly this geometry (a two-parameter fit of step and centre
offset lands on it; ``pi / n`` for 181 and 361 beams, as GMapping's CARMEN reader uses, fits
worse: orebro 3.74 vs 3.47 cm mean point-to-point distance, acapulco 3.57 vs 3.34, csail 1.87
vs 1.81).

Precision: each scan is read as a sensor_msgs/LaserScan would carry it, its ranges, angles and
range limits rounded to float32 (:func:`symloc.scan.message_precision`; the logs' ranges are
millimetres or centimetres, which float32 holds to better than 3 um up to 50 m). So a log
read here and the same log written to a ROS bag (``symloc ros carmen-to-bag``) and read back
give one scan, bit for bit: SLAM's decisions turn on differences of 1e-7 (issue 28).
"""

from __future__ import annotations

import gzip
import math
import zlib
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import DataFormatError
from symloc.scan import LaserScan, message_precision

__all__ = [
    "CARMEN_FOV",
    "CarmenLog",
    "CarmenOdometry",
    "CarmenScan",
    "carmen_beam_geometry",
    "iter_carmen",
    "read_carmen",
    "stamps_usable",
]

FloatArray = NDArray[np.float64]

#: Field of view of a CARMEN front laser [rad] when the log does not state it.
CARMEN_FOV = math.pi

#: PARAM names that give the front laser's angular resolution [deg] (the second spelling is
#: the one of the fhw log).
_RESOLUTION_PARAMS = ("laser_front_laser_resolution", "laser_frontlaser_resolution")
#: PARAM name of the front laser's field of view (radians in the logs that have it; a value
#: above 2 pi is read as degrees, CARMEN's ini-file unit).
_FOV_PARAM = "laser_front_laser_fov"


def _param_float(params: dict[str, str], name: str) -> float | None:
    text = params.get(name)
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError as err:
        raise DataFormatError(f"PARAM {name}: expected a number, got {text!r}") from err
    if not (math.isfinite(value) and value > 0):
        raise DataFormatError(f"PARAM {name}: expected a value > 0, got {text!r}")
    return value


def carmen_beam_geometry(n: int, params: dict[str, str] | None = None) -> tuple[float, float]:
    """``(angle_min, angle_increment)`` [rad] of an ``n``-beam front laser scan.

    Parameters
    ----------
    n : int
        Number of readings of the ``FLASER`` line (>= 2).
    params : dict, optional
        The log's ``PARAM`` entries read so far: ``laser_front_laser_fov`` and
        ``laser_front_laser_resolution`` are used where present (see the module docstring).

    Raises
    ------
    DataFormatError
        A geometry PARAM is not a positive number, or ``n`` beams at the stated resolution
        would not fit in a full turn.

    Examples
    --------
    >>> import math
    >>> [round(math.degrees(v), 3) for v in carmen_beam_geometry(181)]
    [-90.0, 1.0]
    >>> [round(math.degrees(v), 3) for v in carmen_beam_geometry(180)]
    [-90.0, 1.0]
    >>> [round(math.degrees(v), 3) for v in carmen_beam_geometry(360, {"laser_front_laser_resolution": "0.5"})]
    [-90.0, 0.5]
    """
    prm = params or {}
    fov = _param_float(prm, _FOV_PARAM)
    if fov is not None and fov > 2.0 * math.pi + 1e-6:
        fov = math.radians(fov)
    res_deg = next(
        (v for v in (_param_float(prm, k) for k in _RESOLUTION_PARAMS) if v is not None), None
    )
    if res_deg is not None:
        step = math.radians(res_deg)
        if fov is None:
            fov = step * (n - 1) if n % 2 else step * n
    else:
        if fov is None:
            fov = CARMEN_FOV
        step = fov / (n - 1) if n % 2 else fov / n
    if step * (n - 1) > 2.0 * math.pi + 1e-6:
        raise DataFormatError(
            f"FLASER with {n} readings at {math.degrees(step):g} deg spacing: expected a"
            " field of view of at most 360 deg (check the laser resolution PARAM)"
        )
    return -fov / 2.0, step


@dataclass(frozen=True, slots=True, eq=False)
class CarmenScan:
    """One ``FLASER`` message.

    Attributes
    ----------
    scan : LaserScan
        The ranges with their beam geometry; ``scan.stamp`` is the message timestamp [s].
    laser_pose : ndarray of shape (3,)
        Laser pose x [m], y [m], theta [rad] in the world frame (the corrected pose).
    odom_pose : ndarray of shape (3,)
        Odometry pose at the scan (``odom_x odom_y odom_theta``).
    stamp : float
        Message timestamp [s].
    logger_stamp : float
        Logger timestamp [s].
    line : int
        1-based line number in the file.
    """

    scan: LaserScan
    laser_pose: FloatArray
    odom_pose: FloatArray
    stamp: float
    logger_stamp: float
    line: int


@dataclass(frozen=True, slots=True, eq=False)
class CarmenOdometry:
    """One ``ODOM`` message: pose ``(3,)`` [m, m, rad], velocities tv [m/s], rv [rad/s]."""

    pose: FloatArray
    tv: float
    rv: float
    accel: float
    stamp: float
    logger_stamp: float
    line: int


@dataclass(frozen=True, eq=False)
class CarmenLog:
    """Everything read from one log.

    Attributes
    ----------
    scans : list of CarmenScan
    odometry : list of CarmenOdometry
    params : dict of str to str
        ``PARAM name value`` entries.
    skipped : Counter
        Number of lines of each unknown message type that were skipped.
    """

    scans: list[CarmenScan]
    odometry: list[CarmenOdometry]
    params: dict[str, str] = field(default_factory=dict)
    skipped: Counter[str] = field(default_factory=Counter)

    @property
    def laser_poses(self) -> FloatArray:
        """``(N, 3)`` world laser poses of the scans (the corrected reference trajectory)."""
        return np.array([s.laser_pose for s in self.scans]).reshape(-1, 3)

    @property
    def odom_poses(self) -> FloatArray:
        """``(N, 3)`` odometry poses recorded with the scans."""
        return np.array([s.odom_pose for s in self.scans]).reshape(-1, 3)

    @property
    def stamps(self) -> FloatArray:
        """``(N,)`` scan timestamps [s]."""
        return np.array([s.stamp for s in self.scans], dtype=np.float64)

    @property
    def duration(self) -> float:
        """Time from the first to the last scan [s] (0 for fewer than two scans)."""
        if len(self.scans) < 2:
            return 0.0
        return float(self.scans[-1].stamp - self.scans[0].stamp)


def stamps_usable(stamps: ArrayLike) -> bool:
    """Whether a log's scan stamps [s] measure time: at least 90 % of consecutive stamps
    increase (orebro's are all 0 and csail's are truncated to six significant digits, so
    neither does). Fewer than two stamps: False."""
    t = np.asarray(stamps, dtype=np.float64).reshape(-1)
    if t.size < 2:
        return False
    return float(np.mean(np.diff(t) > 0)) >= 0.9


def _floats(tokens: list[str], what: str, lineno: int) -> FloatArray:
    try:
        out = np.array(tokens, dtype=np.float64)
    except ValueError as err:
        raise DataFormatError(f"line {lineno}: {what}: expected numbers, got {tokens!r}") from err
    if not np.all(np.isfinite(out)):
        raise DataFormatError(f"line {lineno}: {what}: expected finite numbers")
    return out


def _parse_flaser(
    tokens: list[str], lineno: int, range_max: float, params: dict[str, str]
) -> CarmenScan:
    if len(tokens) < 2:
        raise DataFormatError(f"line {lineno}: FLASER: missing the number of readings")
    try:
        n = int(tokens[1])
    except ValueError as err:
        raise DataFormatError(
            f"line {lineno}: FLASER number of readings: expected an integer, got {tokens[1]!r}"
        ) from err
    if n < 2:
        raise DataFormatError(f"line {lineno}: FLASER number of readings: expected >= 2, got {n}")
    want = n + 11
    if len(tokens) != want:
        raise DataFormatError(
            f"line {lineno}: FLASER with {n} readings: expected {want} fields, got {len(tokens)}"
        )
    ranges = _floats(tokens[2 : 2 + n], "FLASER ranges", lineno)
    poses = _floats(tokens[2 + n : 8 + n], "FLASER poses", lineno)
    stamp = _floats([tokens[8 + n]], "FLASER timestamp", lineno)[0]
    logger = _floats([tokens[10 + n]], "FLASER logger_timestamp", lineno)[0]
    if np.any(ranges < 0):
        raise DataFormatError(f"line {lineno}: FLASER ranges: expected values >= 0 m")
    try:
        angle_min, step = carmen_beam_geometry(n, params)
    except DataFormatError as err:
        raise DataFormatError(f"line {lineno}: {err}") from err
    scan = message_precision(
        LaserScan(
            angle_min=angle_min,
            angle_increment=step,
            range_min=0.0,
            range_max=range_max,
            ranges=ranges,
            stamp=float(stamp),
            frame_id="laser",
        )
    )
    return CarmenScan(scan, poses[:3], poses[3:], float(stamp), float(logger), lineno)


def _parse_odom(tokens: list[str], lineno: int) -> CarmenOdometry:
    if len(tokens) != 10:
        raise DataFormatError(f"line {lineno}: ODOM: expected 10 fields, got {len(tokens)}")
    v = _floats(tokens[1:7], "ODOM values", lineno)
    stamp = _floats([tokens[7]], "ODOM timestamp", lineno)[0]
    logger = _floats([tokens[9]], "ODOM logger_timestamp", lineno)[0]
    return CarmenOdometry(
        v[:3], float(v[3]), float(v[4]), float(v[5]), float(stamp), float(logger), lineno
    )


#: Longest line read [characters] (a FLASER line of 100 000 readings is about 700 kB).
MAX_LINE = 1 << 20
#: Most blank or comment lines in a row (a log's header comments are a few dozen lines): more
#: is not a log but padding, e.g. a small .gz that expands to hundreds of MiB of newlines,
#: refused at once instead of after a minute of reading nothing.
MAX_LINES_WITHOUT_DATA = 100_000
#: Most text read from one log [characters]: the largest public CARMEN logs are a few hundred
#: MB uncompressed.
MAX_LOG_CHARACTERS = 4 << 30


def _open_text(path: Path) -> Iterator[tuple[int, str]]:
    """The log's lines that are not blank or comments, with their 1-based numbers, each at most
    :data:`MAX_LINE` long; a truncated or corrupt gzip, a longer line, more than
    :data:`MAX_LINES_WITHOUT_DATA` blank or comment lines in a row or more than
    :data:`MAX_LOG_CHARACTERS` of text raise DataFormatError naming the file and the line."""
    with path.open("rb") as probe:
        magic = probe.read(2)
    opener = gzip.open if magic == b"\x1f\x8b" else open
    n = 0
    total = 0
    idle = 0  # blank or comment lines in a row
    try:
        with opener(path, "rt", encoding="ascii", errors="replace") as fh:
            while line := fh.readline(MAX_LINE + 1):
                n += 1
                if len(line) > MAX_LINE:
                    raise DataFormatError(f"{path}: line {n}: longer than {MAX_LINE:,} characters")
                total += len(line)
                if total > MAX_LOG_CHARACTERS:
                    raise DataFormatError(
                        f"{path}: line {n}: more than {MAX_LOG_CHARACTERS:,} characters of text;"
                        " expected a CARMEN log (a few hundred MB at most)"
                    )
                stripped = line.lstrip()
                if not stripped or stripped.startswith("#"):
                    idle += 1
                    if idle > MAX_LINES_WITHOUT_DATA:
                        raise DataFormatError(
                            f"{path}: lines {n - idle + 1}-{n}: {idle:,} blank or comment lines"
                            f" in a row (at most {MAX_LINES_WITHOUT_DATA:,}); expected CARMEN"
                            " messages (padding or a compression bomb?)"
                        )
                    continue
                idle = 0
                yield n, line
    except (OSError, EOFError, zlib.error) as err:
        raise DataFormatError(
            f"{path}: line {n + 1}: cannot read on ({type(err).__name__}: {err});"
            " truncated or corrupt file?"
        ) from err


def iter_carmen(
    path: str | Path,
    *,
    range_max: float = 50.0,
    skipped: Counter[str] | None = None,
    params: dict[str, str] | None = None,
) -> Iterator[CarmenScan | CarmenOdometry]:
    """Yield the ``FLASER`` and ``ODOM`` messages of a CARMEN log in file order.

    Parameters
    ----------
    path : str or Path
        Log file, plain text or gzip (detected from its first bytes).
    range_max : float
        Readings at or above this [m] are "no return" (default 50 m, below the 80 and 81.91
        m markers of SICK logs and equal to the marker of the ACES log).
    skipped : Counter, optional
        Incremented per unknown message type.
    params : dict, optional
        Filled with ``PARAM name value`` entries (the geometry PARAMs also set the beam
        geometry of the scans that follow them, see :func:`carmen_beam_geometry`).

    Raises
    ------
    DataFormatError
        A ``FLASER``/``ODOM``/``PARAM`` line is malformed (the message gives the line number;
        :func:`read_carmen` adds the file), a line is longer than :data:`MAX_LINE`, a gzip log
        is truncated or corrupt, or the file does not exist.
    """
    p = Path(path)
    if not p.is_file():
        raise DataFormatError(f"CARMEN log not found: {p}")
    if not (math.isfinite(range_max) and range_max > 0):
        raise DataFormatError(f"range_max: expected > 0 m, got {range_max}")
    seen: dict[str, str] = {}
    for lineno, raw in _open_text(p):
        tokens = raw.split()
        if not tokens or tokens[0].startswith("#"):
            continue
        kind = tokens[0]
        if kind == "FLASER":
            yield _parse_flaser(tokens, lineno, range_max, seen)
        elif kind == "ODOM":
            yield _parse_odom(tokens, lineno)
        elif kind == "PARAM":
            if len(tokens) < 3:
                raise DataFormatError(f"line {lineno}: PARAM: expected a name and a value")
            if tokens[1] in (_FOV_PARAM, *_RESOLUTION_PARAMS):
                try:
                    _param_float({tokens[1]: tokens[2]}, tokens[1])
                except DataFormatError as err:
                    raise DataFormatError(f"line {lineno}: {err}") from err
            seen[tokens[1]] = tokens[2]
            if params is not None:
                params[tokens[1]] = tokens[2]
        elif skipped is not None:
            skipped[kind] += 1


def read_carmen(path: str | Path, *, range_max: float = 50.0) -> CarmenLog:
    """Read a whole CARMEN log; see :func:`iter_carmen` for the parameters and errors.

    Examples
    --------
    >>> log = read_carmen("intel-corrected.log.gz")  # doctest: +SKIP
    >>> log.laser_poses.shape, log.skipped["NEFF"]  # doctest: +SKIP
    ((910, 3), 910)
    """
    skipped: Counter[str] = Counter()
    params: dict[str, str] = {}
    scans: list[CarmenScan] = []
    odom: list[CarmenOdometry] = []
    try:
        for msg in iter_carmen(path, range_max=range_max, skipped=skipped, params=params):
            if isinstance(msg, CarmenScan):
                scans.append(msg)
            else:
                odom.append(msg)
    except DataFormatError as err:
        text = str(err)
        if not text.startswith(str(path)) and "CARMEN log not found" not in text:
            raise DataFormatError(f"{path}: {text}") from err
        raise
    return CarmenLog(scans, odom, params, skipped)
