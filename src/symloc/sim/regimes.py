"""Named sensor regimes: what the simulated robot's lidar, odometry and camera get wrong.

Three frozen regimes, each figure stated with its source (:meth:`SensorRegime.describe`; run
``python -m symloc.sim.regimes`` for the table):

- ``ideal``: the sensors symloc always simulated: the data sheet's zero-mean range noise only,
  exact actuation, nav2 AMCL's default odometry noise model (alphas 0.2), a distortion-free
  camera in constant light.
- ``realistic``: what a well-calibrated real robot gives: a data-sheet lidar with its real faults
  at typical rates (dropouts, angular binning, a unit's range bias, glass, dark surfaces, mixed
  pixels, motion skew), odometry with a 1-2 % distance and ~1 % rotation calibration error plus
  small zero-mean noise and occasional slip, a camera whose lens distorts (with a known
  calibration) and whose exposure and white balance drift between the mapping and the query
  session.
- ``heavy``: the same faults at several times the rate: the worst a robot plausibly sees (a
  dirty lidar window and a worn bearing, a glass-walled room, a worn wheel on a slippery floor,
  poor lighting).

Draws per robot and per session (every one from the caller's ``rng``, so a trial is reproducible
from its seed)::

    regime = get_regime("realistic")
    rng = np.random.default_rng(seed)
    lidar = regime.lidar(RPLIDAR_A2, rng)          # SimulatedLidar: this unit's bias, drawn once
    config = regime.robot_config(rng)               # RobotConfig: this robot's calibration error
    camera = regime.camera(rng)                     # Camera: this unit's lens, calibration known
    mapping = regime.camera_session(rng, "mapping") # the light of the mapping session
    query = regime.camera_session(rng, "query")     # ... and of the query session
    scan = lidar.scan(world, pose, twist=(v, w), stamp=t)
    image = camera.render(world, pose, rng, conditions=query.conditions(rng), twist=(v, w))

Where a figure comes from memory because this machine has no internet, its source says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from symloc._checks import as_rng
from symloc.errors import ConfigurationError
from symloc.lidar_spec import LidarPreset
from symloc.sim.camera import Camera, CameraConditions
from symloc.sim.lidar import LidarFaults, SimulatedLidar
from symloc.sim.robot import OdometryNoise, RobotConfig, WheelSlip

__all__ = [
    "REGIMES",
    "CameraSession",
    "CameraSpec",
    "OdometrySpec",
    "SensorRegime",
    "get_regime",
    "regimes_markdown",
]

Session = Literal["mapping", "query"]
SESSIONS = ("mapping", "query")


def _check_range(lo: float, hi: float, name: str, upper: float = 0.5) -> None:
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo <= hi < upper):
        raise ConfigurationError(f"{name}: expected 0 <= low <= high < {upper}, got ({lo}, {hi})")


@dataclass(frozen=True)
class OdometrySpec:
    """How a regime draws a robot's odometry and actuation errors.

    Parameters
    ----------
    noise : OdometryNoise
        Zero-mean odometry noise (Probabilistic Robotics Table 5.6 alphas).
    scale_error : (low, high)
        Magnitude range of the distance calibration error; each robot draws a magnitude
        uniformly and a random sign.
    rotation_error : (low, high)
        Magnitude range of the rotation (wheel-base) calibration error, drawn the same way.
    heading_drift_std : float
        Standard deviation [rad/m] of the heading drift per metre (unequal wheels), per robot.
    actuation_noise : float
        Per-wheel speed tracking error (fraction, per step).
    slip : WheelSlip
        Wheel slip episodes.
    wheel_base : float
        Distance between the wheels [m].
    """

    noise: OdometryNoise = field(default_factory=OdometryNoise)
    scale_error: tuple[float, float] = (0.0, 0.0)
    rotation_error: tuple[float, float] = (0.0, 0.0)
    heading_drift_std: float = 0.0
    actuation_noise: float = 0.0
    slip: WheelSlip = field(default_factory=WheelSlip)
    wheel_base: float = 0.23

    def __post_init__(self) -> None:
        _check_range(*self.scale_error, "OdometrySpec.scale_error")
        _check_range(*self.rotation_error, "OdometrySpec.rotation_error")
        if not (math.isfinite(self.heading_drift_std) and self.heading_drift_std >= 0):
            raise ConfigurationError(
                f"OdometrySpec.heading_drift_std: expected a value >= 0, got"
                f" {self.heading_drift_std}"
            )
        RobotConfig(
            noise=self.noise,
            actuation_noise=self.actuation_noise,
            slip=self.slip,
            wheel_base=self.wheel_base,
        )  # validates the rest

    def error_alphas(self) -> tuple[float, float, float, float]:
        """The whole odometry error of a robot of this spec as Table 5.6 alphas.

        What a user who measured such a robot (UMBmark runs on its floor) would declare to a
        localizer: each alpha is the zero-mean noise's plus the *mean square* of the
        systematic errors it would see, so a bias counts as much as a spread of its size.

        - alpha1 (rotation from rotation): the noise, the largest rotation calibration error
          squared, and slip while turning on the spot: the share of turning time spent in an
          episode (``rate * duration / (1 + rate * duration)``, a renewal process) times the
          mean square of the lost fraction (uniform in ``[fraction_min, fraction_max]``).
        - alpha2 (rotation from translation): the noise and the heading drift per metre squared.
        - alpha3 (translation from translation): the noise and the largest distance calibration
          error squared (slip under hard acceleration lasts a fraction of a second and is left
          out).
        - alpha4: the noise.

        Returns
        -------
        (4,) floats: alpha1 [rad^2/rad^2], alpha2 [rad^2/m^2], alpha3 [m^2/m^2], alpha4
        [m^2/rad^2]. The realistic regime gives about (0.0024, 0.0001, 0.0008, 0.0001), the heavy
        one (0.022, 0.0005, 0.0041, 0.0004).
        """
        n, s = self.noise, self.slip
        busy = s.rate * s.duration / (1.0 + s.rate * s.duration)
        lo, hi = s.fraction_min, s.fraction_max
        lost_sq = (lo * lo + lo * hi + hi * hi) / 3.0
        return (
            n.alpha1 + self.rotation_error[1] ** 2 + busy * lost_sq,
            n.alpha2 + self.heading_drift_std**2,
            n.alpha3 + self.scale_error[1] ** 2,
            n.alpha4,
        )


@dataclass(frozen=True)
class CameraSpec:
    """How a regime draws a camera unit and the light of its sessions.

    Parameters
    ----------
    dist_coeffs : tuple of 5 float
        Typical lens distortion ``(k1, k2, p1, p2, k3)``.
    dist_std : tuple of 5 float
        Unit-to-unit standard deviation of each coefficient.
    vignetting : float
        Brightness lost in the corners (fraction).
    session_exposure_std : float
        Standard deviation of the log of a session's exposure (the light of the day and the
        auto-exposure's response to it).
    session_white_balance_std : float
        Standard deviation of the log of a session's red and blue gains relative to green.
    capture_exposure_std : float
        Standard deviation of the log exposure from one capture to the next in a session.
    exposure_time : float
        Shutter time [s] of every capture (motion blur with the robot's turn rate).
    noise_sigma : float
        Pixel noise [grey levels].
    """

    dist_coeffs: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)
    dist_std: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)
    vignetting: float = 0.0
    session_exposure_std: float = 0.0
    session_white_balance_std: float = 0.0
    capture_exposure_std: float = 0.0
    exposure_time: float = 0.0
    noise_sigma: float = 2.0

    def __post_init__(self) -> None:
        if len(self.dist_coeffs) != 5 or len(self.dist_std) != 5:
            raise ConfigurationError("CameraSpec.dist_coeffs, dist_std: expected 5 values each")
        for name in (
            "session_exposure_std",
            "session_white_balance_std",
            "capture_exposure_std",
            "exposure_time",
            "noise_sigma",
        ):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ConfigurationError(f"CameraSpec.{name}: expected a value >= 0, got {v}")
        if any(not (math.isfinite(s) and s >= 0) for s in self.dist_std):
            raise ConfigurationError(
                f"CameraSpec.dist_std: expected values >= 0, got {self.dist_std}"
            )
        Camera(dist_coeffs=self.dist_coeffs, vignetting=self.vignetting)  # validates them


@dataclass(frozen=True)
class CameraSession:
    """The light of one session (mapping or query): each capture varies around it.

    Attributes
    ----------
    name : {"mapping", "query"}
    exposure : float
        The session's brightness relative to nominal.
    white_balance : tuple of 3 float
        The session's R, G, B gains (G = 1).
    spec : CameraSpec
        Per-capture variation, shutter time and noise.
    """

    name: str
    exposure: float
    white_balance: tuple[float, float, float]
    spec: CameraSpec

    def conditions(self, rng: np.random.Generator | int | None = None) -> CameraConditions:
        """The conditions of one capture in this session."""
        gen = as_rng(rng)
        s = self.spec
        jitter = (
            math.exp(float(gen.normal(0.0, s.capture_exposure_std)))
            if s.capture_exposure_std
            else 1.0
        )
        return CameraConditions(
            exposure=self.exposure * jitter,
            white_balance=self.white_balance,
            noise_sigma=s.noise_sigma,
            exposure_time=s.exposure_time,
        )


@dataclass(frozen=True)
class SensorRegime:
    """A named set of sensor error models, each figure with its source.

    Attributes
    ----------
    name : str
    summary : str
    lidar_faults : LidarFaults
    odometry : OdometrySpec
    camera_spec : CameraSpec
    sources : tuple of (key, source)
        Where each figure comes from; keys are the rows of :meth:`describe`.
    """

    name: str
    summary: str
    lidar_faults: LidarFaults = field(default_factory=LidarFaults)
    odometry: OdometrySpec = field(default_factory=OdometrySpec)
    camera_spec: CameraSpec = field(default_factory=CameraSpec)
    sources: tuple[tuple[str, str], ...] = field(default=(), repr=False)

    # ---- per-unit and per-session draws -------------------------------------------------

    def lidar(
        self, preset: LidarPreset, rng: np.random.Generator | int | None = None
    ) -> SimulatedLidar:
        """One lidar unit of ``preset`` with this regime's faults; its range offset and scale
        are drawn from ``rng`` here, and its scans draw from the same ``rng``."""
        return SimulatedLidar(preset, self.lidar_faults, as_rng(rng))

    def robot_config(
        self,
        rng: np.random.Generator | int | None = None,
        *,
        radius: float = 0.177,
        max_v: float = 0.7,
        max_w: float = 3.0,
        noise: OdometryNoise | None = None,
    ) -> RobotConfig:
        """One robot's :class:`RobotConfig`: its calibration errors drawn from ``rng``.

        ``noise`` replaces the regime's zero-mean odometry noise (e.g. a bench that has always
        used other alphas for its ideal robot); the systematic errors stay the regime's.
        """
        gen = as_rng(rng)
        o = self.odometry

        def signed(lo: float, hi: float) -> float:
            if hi <= 0.0:
                return 0.0
            mag = float(gen.uniform(lo, hi))
            return mag if gen.random() < 0.5 else -mag

        scale = signed(*o.scale_error)
        rot = signed(*o.rotation_error)
        drift = float(gen.normal(0.0, o.heading_drift_std)) if o.heading_drift_std else 0.0
        return RobotConfig(
            radius=radius,
            max_v=max_v,
            max_w=max_w,
            noise=o.noise if noise is None else noise,
            wheel_base=o.wheel_base,
            odom_scale_error=scale,
            odom_rotation_error=rot,
            odom_heading_drift=drift,
            actuation_noise=o.actuation_noise,
            slip=o.slip,
        )

    def camera(
        self, rng: np.random.Generator | int | None = None, *, base: Camera | None = None
    ) -> Camera:
        """One camera unit: ``base`` (default :class:`Camera`) with this unit's lens distortion
        (typical coefficients + unit-to-unit spread, drawn from ``rng``) and vignetting. Its
        :attr:`Camera.calibration` is what the robot is told."""
        gen = as_rng(rng)
        c = self.camera_spec
        cam = Camera() if base is None else base
        mean = np.asarray(c.dist_coeffs, dtype=np.float64)
        std = np.asarray(c.dist_std, dtype=np.float64)
        dist = mean + (std * gen.standard_normal(5) if np.any(std > 0) else 0.0)
        return replace(cam, dist_coeffs=tuple(float(d) for d in dist), vignetting=c.vignetting)

    def camera_session(
        self, rng: np.random.Generator | int | None, session: Session
    ) -> CameraSession:
        """The light of one session (``"mapping"`` or ``"query"``): its exposure and white
        balance, drawn from ``rng``. Both sessions are drawn from the same distribution; what
        the robot meets is their difference."""
        if session not in SESSIONS:
            raise ConfigurationError(f"session: expected 'mapping' or 'query', got {session!r}")
        gen = as_rng(rng)
        c = self.camera_spec
        exposure = (
            math.exp(float(gen.normal(0.0, c.session_exposure_std)))
            if c.session_exposure_std
            else 1.0
        )
        if c.session_white_balance_std:
            r, b = np.exp(gen.normal(0.0, c.session_white_balance_std, 2))
            wb = (float(r), 1.0, float(b))
        else:
            wb = (1.0, 1.0, 1.0)
        return CameraSession(session, exposure, wb, c)

    def camera_conditions(
        self, rng: np.random.Generator | int | None, session: Session
    ) -> CameraConditions:
        """One capture's conditions in a *fresh* session (:meth:`camera_session` then
        :meth:`CameraSession.conditions`). For several captures of one session, draw the
        session once and call its ``conditions`` per capture."""
        gen = as_rng(rng)
        return self.camera_session(gen, session).conditions(gen)

    # ---- documentation ----------------------------------------------------------------

    def describe(self) -> list[tuple[str, str, str]]:
        """Every figure of the regime: ``(quantity, value, source)`` rows."""
        src = dict(self.sources)
        f = self.lidar_faults
        o = self.odometry
        c = self.camera_spec

        def pct(x: float) -> str:
            return f"{100 * x:.3g} %"

        def rng_pct(lo: float, hi: float) -> str:
            return "0" if hi == 0 else f"+-{100 * lo:.3g}..{100 * hi:.3g} % (random sign)"

        glass = (
            "opaque (seen like a wall)"
            if f.glass_opaque
            else (
                f"reflects within {math.degrees(f.glass_reflect_angle):.3g} deg of the normal"
                f" with p {f.glass_reflect_prob:.3g}; else no return with p"
                f" {f.glass_no_return_prob:.3g}, else passes through"
            )
        )
        dark = (
            "seen like any surface"
            if not math.isfinite(f.dark_range_fraction)
            else (
                f"no return half the time at {f.dark_range_fraction:.3g} x range_max head-on;"
                f" power ~ cos(i) / r^2, log-power sd {f.dark_spread:.3g}"
            )
        )
        slip = (
            "none"
            if o.slip.rate == 0
            else (
                f"{o.slip.rate:.3g} episodes/s while turning on the spot or accelerating;"
                f" mean {o.slip.duration:.3g} s; {pct(o.slip.fraction_min)}-"
                f"{pct(o.slip.fraction_max)} of the motion lost"
            )
        )
        a = o.noise
        rows = [
            ("lidar range noise", "the preset's data-sheet sigma (band / 2)", "lidar.noise"),
            ("lidar random dropouts", pct(f.dropout_rate) + " of beams (NaN)", "lidar.dropout"),
            (
                "lidar angular jitter",
                f"sd {f.angle_jitter_bins:.3g} beam spacings",
                "lidar.jitter",
            ),
            (
                "lidar range bias (per unit)",
                f"offset sd {1000 * f.range_bias_std:.3g} mm, scale sd {pct(f.range_scale_std)}",
                "lidar.bias",
            ),
            ("lidar on glass", glass, "lidar.glass"),
            ("lidar on dark surfaces", dark, "lidar.dark"),
            (
                "lidar mixed pixels",
                f"p {f.mixed_pixel_prob:.3g} per depth edge (> {f.mixed_min_jump:.3g} m)",
                "lidar.mixed",
            ),
            (
                "lidar motion skew",
                "each beam from its own pose; stamp = first beam" if f.motion_skew else "off",
                "lidar.skew",
            ),
            (
                "odometry noise alphas",
                f"({a.alpha1:.3g}, {a.alpha2:.3g}, {a.alpha3:.3g}, {a.alpha4:.3g})",
                "odom.noise",
            ),
            ("odometry distance scale error", rng_pct(*o.scale_error), "odom.scale"),
            ("odometry rotation scale error", rng_pct(*o.rotation_error), "odom.rotation"),
            (
                "odometry heading drift",
                f"sd {math.degrees(o.heading_drift_std):.3g} deg/m",
                "odom.drift",
            ),
            (
                "actuation error",
                f"sd {pct(o.actuation_noise)} per wheel per step",
                "odom.actuation",
            ),
            ("wheel slip", slip, "odom.slip"),
            (
                "camera lens distortion",
                f"(k1, k2, p1, p2, k3) = {tuple(round(x, 5) for x in c.dist_coeffs)},"
                f" unit sd {tuple(round(x, 5) for x in c.dist_std)}",
                "camera.distortion",
            ),
            (
                "camera vignetting",
                f"{pct(c.vignetting)} darker in the corners",
                "camera.vignetting",
            ),
            (
                "camera session exposure",
                f"log-normal, sd {c.session_exposure_std:.3g} per session,"
                f" {c.capture_exposure_std:.3g} per capture",
                "camera.exposure",
            ),
            (
                "camera white balance",
                f"R/G and B/G log sd {c.session_white_balance_std:.3g} per session",
                "camera.wb",
            ),
            ("camera shutter (motion blur)", f"{1000 * c.exposure_time:.3g} ms", "camera.shutter"),
            ("camera pixel noise", f"sd {c.noise_sigma:.3g} grey levels", "camera.noise"),
        ]
        return [(q, v, src.get(key, "")) for q, v, key in rows]

    def markdown(self) -> str:
        """The :meth:`describe` table in Markdown."""
        lines = [f"**{self.name}**: {self.summary}", "", "| quantity | value | source |"]
        lines.append("| --- | --- | --- |")
        lines += [f"| {q} | {v} | {s} |" for q, v, s in self.describe()]
        return "\n".join(lines)


# --------------------------------------------------------------------------------------------
# the figures and their sources
# --------------------------------------------------------------------------------------------

_SRC_LIDAR_NOISE = (
    "data sheets, see symloc.lidar_spec (LDS-01: ROBOTIS e-Manual; RPLIDAR A2: Slamtec A2M8 data"
    " sheet; paper_15m: the paper's Gazebo sensor)"
)
_SRC_ODOM_TODAY = "nav2 AMCL defaults (alpha1..4 = 0.2), the model symloc always simulated"
_SRC_NONE = "ideal: none"

_IDEAL_SOURCES = (
    ("lidar.noise", _SRC_LIDAR_NOISE),
    ("lidar.dropout", "the preset's own dropout_rate (0 in every preset)"),
    ("lidar.jitter", _SRC_NONE),
    ("lidar.bias", _SRC_NONE),
    ("lidar.glass", _SRC_NONE),
    ("lidar.dark", _SRC_NONE),
    ("lidar.mixed", _SRC_NONE),
    ("lidar.skew", "ideal: an instantaneous scan"),
    ("odom.noise", _SRC_ODOM_TODAY),
    ("odom.scale", _SRC_NONE),
    ("odom.rotation", _SRC_NONE),
    ("odom.drift", _SRC_NONE),
    ("odom.actuation", "ideal: the robot moves exactly as commanded"),
    ("odom.slip", _SRC_NONE),
    ("camera.distortion", "ideal: a pinhole"),
    ("camera.vignetting", _SRC_NONE),
    ("camera.exposure", "ideal: the same light in every session"),
    ("camera.wb", _SRC_NONE),
    ("camera.shutter", "ideal: no motion blur"),
    ("camera.noise", "symloc's camera default (2 grey levels)"),
)

_REALISTIC_SOURCES = (
    ("lidar.noise", _SRC_LIDAR_NOISE),
    (
        "lidar.dropout",
        "engineering estimate: no data sheet states it; about 1 % invalid samples on matte indoor"
        " surfaces for a clean triangulation unit (from memory of published RPLIDAR/LDS scans,"
        " not measured here)",
    ),
    (
        "lidar.jitter",
        "rplidar_ros with angle_compensate bins each sample to the nearest of a fixed angular"
        " grid: a uniform +-half-bin error, sd = 1/sqrt(12) bin (from memory of the driver's"
        " source, not re-checked)",
    ),
    (
        "lidar.bias",
        "ROBOTIS LDS-01 page as recalled in symloc.lidar_spec: accuracy +-15 mm / +-5.0 % against"
        " precision +-10 mm / +-3.5 %; the difference (5 mm, 1.5 %) read as a 2-sigma band of a"
        " unit's systematic error",
    ),
    (
        "lidar.glass",
        "Garmin LIDAR-Lite note 'How the Garmin LIDAR-Lite products work with reflective"
        " surfaces': specular surfaces are seen only from near the normal; SICK LMS5xx operating"
        " instructions (8013796): the beam is deflected by reflective surfaces and an object"
        " behind may be detected. Cone and probabilities: engineering estimate (from memory of"
        " Foster et al. 2013, 'VisAGGE', glass seen within roughly 10-20 deg of its normal)",
    ),
    (
        "lidar.dark",
        "Slamtec RPLIDAR A3M1 specification: range 25 m on white, 10 m on black objects (0.4);"
        " the A2 data sheet gives the white range only. Received power ~ reflectivity cos(i) /"
        " r^2 (lidar range equation); spread: engineering estimate",
    ),
    (
        "lidar.mixed",
        "SICK LMS5xx operating instructions: a beam wider than an object's edge returns a"
        " corrupted value (mixed pixel); Ye and Borenstein 2002 report mixed pixels at edges of"
        " the SICK LMS 200 (from memory). Probability ~ footprint / beam spacing: engineering"
        " estimate",
    ),
    (
        "lidar.skew",
        "physics of a spinning lidar (one revolution per 1/scan_rate, 10 Hz for the A2);"
        " sensor_msgs/LaserScan: the header stamp is the first beam's acquisition time",
    ),
    (
        "odom.noise",
        "issue 21 / ../shared/peers/gmapping/README.md: alphas (0.0016, 0.0001, 0.0004, 0.0001)"
        " give 1-2 cm and 0.5-1 deg per scan at the median on the CARMEN logs",
    ),
    (
        "odom.scale",
        "issue 21 (distance x 1.015); Borenstein and Feng 1996 (UMBmark): wheel-diameter and"
        " wheel-base errors of a few percent dominate odometry before calibration",
    ),
    (
        "odom.rotation",
        "issue 21 (rotations x 0.99); Borenstein and Feng 1996: the effective wheel base of a"
        " robot differs from the nominal one by about 1 %",
    ),
    (
        "odom.drift",
        "Borenstein and Feng 1996: unequal wheel diameters (E_d) curve a straight run; a 0.07 %"
        " mismatch on a 0.23 m wheel base (Kobuki) gives 0.17 deg/m (engineering estimate)",
    ),
    (
        "odom.actuation",
        "engineering estimate: a wheel-speed PID tracks its set point within about 2 %",
    ),
    (
        "odom.slip",
        "Borenstein and Feng 1996 list slip on fast turns and hard acceleration as the main"
        " non-systematic error; rates and fractions: engineering estimate",
    ),
    (
        "camera.distortion",
        "measured: Raspberry Pi camera v2 calibration in UbiquityRobotics/raspicam_node"
        " camera_info/camerav2_1280x960.yaml (65 deg HFOV like symloc's camera); unit spread from"
        " the same repository's camerav2_410x308.yaml (k1 0.164, k2 -0.272, p1 0.0011, p2"
        " -0.0017)",
    ),
    (
        "camera.vignetting",
        "cos^4 law gives 38 % relative illumination at 38.6 deg (the corner of a 65 deg 4:3"
        " image); ISP lens-shading correction removes most of it: residual 20 % is an estimate",
    ),
    (
        "camera.exposure",
        "engineering estimate: auto-exposure targets a mean grey, so sessions differ by the"
        " scene's residual, 10-20 %",
    ),
    (
        "camera.wb",
        "engineering estimate: auto white balance under daylight, fluorescent or LED light leaves"
        " a few percent of colour cast",
    ),
    (
        "camera.shutter",
        "EN 12464-1 asks 500 lx for offices; a webcam there exposes 5-20 ms (engineering estimate)",
    ),
    ("camera.noise", "symloc's camera default (2 grey levels at low gain, estimate)"),
)

_HEAVY_REASONS = (
    ("lidar.noise", "unchanged: the data sheet's sigma"),
    ("lidar.dropout", "a dirty window: 5x the realistic rate (engineering estimate)"),
    ("lidar.jitter", "a worn bearing or uneven motor speed: 2x the binning error (estimate)"),
    (
        "lidar.bias",
        "the LDS-01 accuracy band itself (+-15 mm / +-5 %, as recalled) read as 2 sigma",
    ),
    ("lidar.glass", "a glass-walled room: a wider cone, fewer clean reflections (estimate)"),
    ("lidar.dark", "a dirty window: half the realistic range on dark surfaces (estimate)"),
    ("lidar.mixed", "2x the realistic probability (estimate)"),
    ("lidar.skew", "unchanged: physics of a spinning lidar"),
    ("odom.noise", "4x the variances of the realistic alphas (issue 21's regime)"),
    ("odom.scale", "a worn or under-inflated wheel: 3-5 % (Borenstein and Feng 1996 range)"),
    ("odom.rotation", "soft tyres, a load off centre: 2-4 % (Borenstein and Feng 1996 range)"),
    ("odom.drift", "3x the realistic drift (estimate)"),
    ("odom.actuation", "2.5x the realistic tracking error (estimate)"),
    ("odom.slip", "a slippery floor: 5x the episodes, up to 30 % lost (estimate)"),
    ("camera.distortion", "the measured Raspberry Pi v2 lens with 2x the unit spread"),
    ("camera.vignetting", "a cheap wide lens without shading correction: 2x (estimate)"),
    ("camera.exposure", "poor, changing light: 2.7x the realistic spread (estimate)"),
    ("camera.wb", "mixed daylight and artificial light: 3x the colour cast (estimate)"),
    ("camera.shutter", "dim light: 33 ms, a 30 fps camera's longest shutter"),
    ("camera.noise", "high gain in dim light: 3x the noise (estimate)"),
)
_HEAVY_SOURCES = tuple((k, "heavy: " + v) for k, v in _HEAVY_REASONS)

IDEAL = SensorRegime(
    name="ideal",
    summary="today's sensors: data-sheet range noise only, exact actuation, nav2 default"
    " odometry noise, a pinhole camera in constant light",
    sources=_IDEAL_SOURCES,
)

REALISTIC = SensorRegime(
    name="realistic",
    summary="a well-calibrated real robot: a data-sheet lidar with its real faults, 1-2 %"
    " odometry calibration error plus small noise, a distorting lens with a known calibration,"
    " light that differs between mapping and query",
    lidar_faults=LidarFaults(
        dropout_rate=0.01,
        angle_jitter_bins=1.0 / math.sqrt(12.0),
        range_bias_std=0.0025,
        range_scale_std=0.0075,
        glass_reflect_angle=math.radians(10.0),
        glass_reflect_prob=0.7,
        glass_no_return_prob=0.2,
        dark_range_fraction=0.4,
        dark_spread=0.5,
        mixed_pixel_prob=0.3,
        mixed_min_jump=0.1,
        motion_skew=True,
    ),
    odometry=OdometrySpec(
        noise=OdometryNoise(0.0016, 0.0001, 0.0004, 0.0001),
        scale_error=(0.01, 0.02),
        rotation_error=(0.005, 0.015),
        heading_drift_std=0.003,
        actuation_noise=0.02,
        slip=WheelSlip(rate=0.2, duration=0.3, fraction_min=0.05, fraction_max=0.15),
        wheel_base=0.23,
    ),
    camera_spec=CameraSpec(
        dist_coeffs=(0.1349735, -0.2335870, 0.0006697, 0.0048467, 0.0),
        dist_std=(0.015, 0.02, 0.0005, 0.003, 0.0),
        vignetting=0.2,
        session_exposure_std=0.15,
        session_white_balance_std=0.05,
        capture_exposure_std=0.03,
        exposure_time=0.01,
        noise_sigma=2.0,
    ),
    sources=_REALISTIC_SOURCES,
)

HEAVY = SensorRegime(
    name="heavy",
    summary="the worst a robot plausibly sees: a dirty lidar window, a glass-walled room, a worn"
    " wheel on a slippery floor, poor lighting",
    lidar_faults=LidarFaults(
        dropout_rate=0.05,
        angle_jitter_bins=2.0 / math.sqrt(12.0),
        range_bias_std=0.0075,
        range_scale_std=0.025,
        glass_reflect_angle=math.radians(15.0),
        glass_reflect_prob=0.5,
        glass_no_return_prob=0.4,
        dark_range_fraction=0.2,
        dark_spread=0.5,
        mixed_pixel_prob=0.6,
        mixed_min_jump=0.1,
        motion_skew=True,
    ),
    odometry=OdometrySpec(
        noise=OdometryNoise(0.0064, 0.0004, 0.0016, 0.0004),
        scale_error=(0.03, 0.05),
        rotation_error=(0.02, 0.04),
        heading_drift_std=0.009,
        actuation_noise=0.05,
        slip=WheelSlip(rate=1.0, duration=0.5, fraction_min=0.1, fraction_max=0.3),
        wheel_base=0.23,
    ),
    camera_spec=CameraSpec(
        dist_coeffs=(0.1349735, -0.2335870, 0.0006697, 0.0048467, 0.0),
        dist_std=(0.03, 0.04, 0.001, 0.006, 0.0),
        vignetting=0.4,
        session_exposure_std=0.4,
        session_white_balance_std=0.15,
        capture_exposure_std=0.08,
        exposure_time=0.033,
        noise_sigma=6.0,
    ),
    sources=_HEAVY_SOURCES,
)

REGIMES: dict[str, SensorRegime] = {r.name: r for r in (IDEAL, REALISTIC, HEAVY)}
"""The regimes by name: ``ideal``, ``realistic``, ``heavy``."""


def get_regime(name: str | SensorRegime) -> SensorRegime:
    """The regime called ``name`` (a :class:`SensorRegime` is returned as it is)."""
    if isinstance(name, SensorRegime):
        return name
    if name not in REGIMES:
        raise ConfigurationError(f"regime: expected one of {sorted(REGIMES)}, got {name!r}")
    return REGIMES[name]


def regimes_markdown() -> str:
    """One Markdown table of every figure in the three regimes, with the sources of the
    realistic figures and the reasons for the heavy ones (the README's section)."""
    ideal, real, heavy = (REGIMES[n].describe() for n in ("ideal", "realistic", "heavy"))
    lines = ["| quantity | ideal | realistic | heavy | source |", "| --- | --- | --- | --- | --- |"]
    for (q, vi, _), (_, vr, sr), (_, vh, sh) in zip(ideal, real, heavy, strict=True):
        why = sh.removeprefix("heavy: ")
        lines.append(f"| {q} | {vi} | {vr} | {vh} | {sr}. Heavy: {why} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    """Print the regimes' table (``python -m symloc.sim.regimes [NAME]``): all three side by
    side, or one regime with the source of each of its figures."""
    import sys

    args = sys.argv[1:] if argv is None else argv
    if args:
        print(get_regime(args[0]).markdown())
    else:
        print(regimes_markdown())


if __name__ == "__main__":
    main()
