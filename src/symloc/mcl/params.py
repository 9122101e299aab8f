"""AMCL settings with nav2_amcl's parameter names and defaults.

``AmclParams`` mirrors the ``amcl: ros__parameters:`` block of a nav2 ``nav2_params.yaml``
(nav2_amcl ``amcl_node.cpp`` declares the same names and defaults), so a user can bring an
existing tuning with :meth:`AmclParams.from_nav2_yaml`. Unlike nav2, an out-of-range value
raises :class:`~symloc.errors.ConfigurationError`; it is never reset to a default with a log
line. Parameters that only concern ROS plumbing (frame ids, topics, tf) are accepted from the
YAML and kept in :attr:`AmclParams.ros_extras` but play no role in the filter.

Three symloc additions (not nav2 names): ``hypothesis_min_weight`` (the weight fraction a
cluster needs to count as a well-weighted hypothesis), ``update_min_d_euclidean`` and
``laser_likelihood_exponent`` (default 1 = nav2): the scan likelihood is raised to this power
in (0, 1] before it multiplies the weights. Neighbouring beams are not independent, so the
product over beams of ``likelihood_field_prob`` is far too peaked (Thrun et al. 2005,
Section 6.3.4); an exponent < 1 tempers it and keeps the filter from collapsing onto one
wrong hypothesis after a single scan during global localization.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from symloc.errors import ConfigurationError

__all__ = ["LASER_MODELS", "MAX_PARTICLES", "MOTION_MODELS", "PARTICLE_MEMORY", "AmclParams"]

#: Most particles a filter may hold: a global update peaks at about 240 bytes per particle
#: (measured at 1 M particles: poses, weights, resampling copies, clusters), so 4 M particles
#: need about 1 GB. nav2's default is 2,000; symloc's global searches use up to 20,000.
MAX_PARTICLES = 4_000_000
#: Why :data:`MAX_PARTICLES` (said in every error that refuses more).
PARTICLE_MEMORY = "about 240 B per particle in an update: 4 M particles need about 1 GB"

#: Accepted ``laser_model_type`` values (nav2 names).
LASER_MODELS = ("likelihood_field", "likelihood_field_prob", "beam")

#: Accepted ``robot_model_type`` values: nav2 plugin names, plain names and ROS 1 amcl's
#: ``odom_model_type`` names (``diff``/``omni`` are ROS 1's uncorrected variants).
MOTION_MODELS = {
    "nav2_amcl::DifferentialMotionModel": "diff-corrected",
    "nav2_amcl::OmniMotionModel": "omni-corrected",
    "differential": "diff-corrected",
    "omnidirectional": "omni-corrected",
    "diff-corrected": "diff-corrected",
    "omni-corrected": "omni-corrected",
    "diff": "diff",
    "omni": "omni",
}

_ROS_ONLY = {
    "base_frame_id",
    "global_frame_id",
    "odom_frame_id",
    "scan_topic",
    "map_topic",
    "tf_broadcast",
    "transform_tolerance",
    "save_pose_rate",
    "set_initial_pose",
    "initial_pose",
    "always_reset_initial_pose",
    "first_map_only",
    "use_sim_time",
    "map_subscribe_transient_local",
    "bond_heartbeat_period",
    "introspection_mode",
    "service_introspection_mode",
}


@dataclass(frozen=True)
class AmclParams:
    """AMCL parameters (nav2_amcl names, units and defaults).

    Motion noise: ``alpha1`` rotation from rotation, ``alpha2`` rotation from translation,
    ``alpha3`` translation from translation, ``alpha4`` translation from rotation, ``alpha5``
    strafe from translation (omni only); all >= 0. Sensor: ``z_hit + z_rand (+ z_short + z_max
    for the beam model)`` weights in [0, 1]; ``sigma_hit`` [m] > 0; ``lambda_short`` [1/m] > 0;
    ``laser_likelihood_max_dist`` [m] > 0; ``laser_max_range`` / ``laser_min_range`` [m]
    (<= 0 means "use the scan's"); ``max_beams`` >= 2. Filter: ``min_particles`` <=
    ``max_particles``; ``pf_err`` in (0, 1); ``pf_z`` in (0.5, 1) is the *probability* whose
    standard normal quantile enters Fox's bound; ``recovery_alpha_slow`` <
    ``recovery_alpha_fast`` in [0, 1] (both 0 disables recovery); ``resample_interval`` >= 1;
    ``update_min_d`` [m] and ``update_min_a`` [rad] >= 0. Beam skipping (likelihood_field_prob
    only): ``do_beamskip``, ``beam_skip_distance`` [m], ``beam_skip_threshold`` and
    ``beam_skip_error_threshold`` in [0, 1].
    """

    alpha1: float = 0.2
    alpha2: float = 0.2
    alpha3: float = 0.2
    alpha4: float = 0.2
    alpha5: float = 0.2
    beam_skip_distance: float = 0.5
    beam_skip_error_threshold: float = 0.9
    beam_skip_threshold: float = 0.3
    do_beamskip: bool = False
    lambda_short: float = 0.1
    laser_likelihood_max_dist: float = 2.0
    laser_max_range: float = 100.0
    laser_min_range: float = -1.0
    laser_model_type: str = "likelihood_field"
    max_beams: int = 60
    max_particles: int = 2000
    min_particles: int = 500
    pf_err: float = 0.05
    pf_z: float = 0.99
    recovery_alpha_fast: float = 0.0
    recovery_alpha_slow: float = 0.0
    resample_interval: int = 1
    robot_model_type: str = "nav2_amcl::DifferentialMotionModel"
    sigma_hit: float = 0.2
    update_min_a: float = 0.2
    update_min_d: float = 0.25
    z_hit: float = 0.5
    z_max: float = 0.05
    z_rand: float = 0.5
    z_short: float = 0.05
    # symloc additions
    hypothesis_min_weight: float = 0.1
    update_min_d_euclidean: bool = True
    laser_likelihood_exponent: float = 1.0
    ros_extras: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for f in fields(self):
            if f.name in ("laser_model_type", "robot_model_type", "ros_extras"):
                continue
            v = getattr(self, f.name)
            if f.type in ("bool",) or isinstance(f.default, bool):
                if not isinstance(v, (bool, int)) or isinstance(v, float):
                    raise ConfigurationError(f"{f.name}: expected true/false, got {v!r}")
                set_(self, f.name, bool(v))
            elif isinstance(f.default, int):
                if isinstance(v, bool) or not (
                    isinstance(v, int) or (isinstance(v, float) and v.is_integer())
                ):
                    raise ConfigurationError(f"{f.name}: expected an integer, got {v!r}")
                set_(self, f.name, int(v))
            else:
                try:
                    fv = float(v)
                except (TypeError, ValueError) as err:
                    raise ConfigurationError(f"{f.name}: expected a number, got {v!r}") from err
                if not math.isfinite(fv):
                    raise ConfigurationError(f"{f.name}: expected a finite number, got {fv}")
                set_(self, f.name, fv)
        self._validate()

    def _validate(self) -> None:
        def need(cond: bool, name: str, expected: str) -> None:
            if not cond:
                raise ConfigurationError(
                    f"{name}: expected {expected}, got {getattr(self, name)!r}"
                )

        for n in ("alpha1", "alpha2", "alpha3", "alpha4", "alpha5"):
            need(getattr(self, n) >= 0.0, n, "a value >= 0")
        for n in ("z_hit", "z_rand", "z_short", "z_max"):
            need(0.0 <= getattr(self, n) <= 1.0, n, "a value in [0, 1]")
        need(self.z_hit + self.z_rand > 0.0, "z_hit", "z_hit + z_rand > 0")
        need(self.sigma_hit > 0.0, "sigma_hit", "a value > 0 m")
        need(self.lambda_short > 0.0, "lambda_short", "a value > 0 1/m")
        need(self.laser_likelihood_max_dist > 0.0, "laser_likelihood_max_dist", "a value > 0 m")
        need(
            self.laser_max_range <= 0.0 or self.laser_max_range > max(self.laser_min_range, 0.0),
            "laser_max_range",
            "<= 0 (use the scan's) or > laser_min_range",
        )
        need(self.laser_model_type in LASER_MODELS, "laser_model_type", f"one of {LASER_MODELS}")
        need(
            self.robot_model_type in MOTION_MODELS,
            "robot_model_type",
            f"one of {sorted(MOTION_MODELS)}",
        )
        need(self.max_beams >= 2, "max_beams", "an integer >= 2")
        need(self.min_particles >= 1, "min_particles", "an integer >= 1")
        need(self.max_particles >= self.min_particles, "max_particles", ">= min_particles")
        need(
            self.max_particles <= MAX_PARTICLES,
            "max_particles",
            f"at most {MAX_PARTICLES:,} ({PARTICLE_MEMORY})",
        )
        need(0.0 < self.pf_err < 1.0, "pf_err", "a value in (0, 1)")
        need(0.5 < self.pf_z < 1.0, "pf_z", "a probability in (0.5, 1)")
        need(0.0 <= self.recovery_alpha_slow <= 1.0, "recovery_alpha_slow", "a value in [0, 1]")
        need(0.0 <= self.recovery_alpha_fast <= 1.0, "recovery_alpha_fast", "a value in [0, 1]")
        need(
            self.recovery_alpha_slow == 0.0
            or self.recovery_alpha_fast == 0.0
            or self.recovery_alpha_slow < self.recovery_alpha_fast,
            "recovery_alpha_slow",
            "recovery_alpha_slow < recovery_alpha_fast (Thrun's augmented MCL)",
        )
        need(self.resample_interval >= 1, "resample_interval", "an integer >= 1")
        need(self.update_min_d >= 0.0, "update_min_d", "a value >= 0 m")
        need(self.update_min_a >= 0.0, "update_min_a", "a value >= 0 rad")
        need(self.beam_skip_distance > 0.0, "beam_skip_distance", "a value > 0 m")
        need(0.0 <= self.beam_skip_threshold <= 1.0, "beam_skip_threshold", "a value in [0, 1]")
        need(
            0.0 <= self.beam_skip_error_threshold <= 1.0,
            "beam_skip_error_threshold",
            "a value in [0, 1]",
        )
        need(0.0 < self.hypothesis_min_weight <= 1.0, "hypothesis_min_weight", "a value in (0, 1]")
        need(
            0.0 < self.laser_likelihood_exponent <= 1.0,
            "laser_likelihood_exponent",
            "a value in (0, 1]",
        )

    @property
    def motion_model(self) -> str:
        """Canonical motion model: ``diff``, ``diff-corrected``, ``omni`` or ``omni-corrected``."""
        return MOTION_MODELS[self.robot_model_type]

    @property
    def recovery_enabled(self) -> bool:
        """True when augmented-MCL random particle injection is on (both alphas > 0)."""
        return self.recovery_alpha_slow > 0.0 and self.recovery_alpha_fast > 0.0

    def replace(self, **changes: Any) -> AmclParams:
        """A validated copy with some fields changed."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        unknown = set(changes) - set(values)
        if unknown:
            raise ConfigurationError(f"AmclParams: unknown parameter(s) {sorted(unknown)}")
        values.update(changes)
        return AmclParams(**values)

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> AmclParams:
        """Build from a ``ros__parameters`` mapping; unknown names raise, ROS-only names kept."""
        if not isinstance(values, dict):
            raise ConfigurationError(
                f"amcl ros__parameters: expected a mapping, got {type(values).__name__}"
            )
        own = {f.name for f in fields(cls)} - {"ros_extras"}
        kwargs: dict[str, Any] = {}
        extras: dict[str, Any] = {}
        for key, value in values.items():
            if key in own:
                kwargs[key] = value
            elif key in _ROS_ONLY:
                extras[key] = value
            else:
                raise ConfigurationError(
                    f"amcl parameter {key!r}: not a nav2_amcl parameter that symloc knows"
                )
        return cls(**kwargs, ros_extras=extras)

    @classmethod
    def from_nav2_yaml(cls, source: str | Path) -> AmclParams:
        """Read the ``amcl: ros__parameters:`` block of a nav2 params file.

        ``source`` is a path to a YAML file or the YAML text itself. Also accepts the
        ``/**/amcl`` or namespaced keys (``robot1/amcl``) nav2 launch files use.
        """
        # here, not at the top: a process that only tracks does not load PyYAML
        from symloc.files.bounded import (
            MAX_PARAMS_FILE_BYTES,
            load_yaml_bounded,
            read_text_bounded,
        )

        text: str
        if isinstance(source, Path) or (
            isinstance(source, str) and "\n" not in source and source.endswith((".yaml", ".yml"))
        ):
            text = read_text_bounded(
                source, MAX_PARAMS_FILE_BYTES, what="the nav2 params file", error=ConfigurationError
            )
        else:
            text = str(source)
        doc = load_yaml_bounded(text, where="nav2 params", error=ConfigurationError)
        if not isinstance(doc, dict):
            raise ConfigurationError("nav2 params: expected a mapping with an 'amcl' key")
        block = None
        for key, value in doc.items():
            if str(key) == "amcl" or str(key).endswith("/amcl"):
                block = value
                break
        if block is None:
            raise ConfigurationError("nav2 params: no 'amcl:' block found")
        if not isinstance(block, dict) or "ros__parameters" not in block:
            raise ConfigurationError("nav2 params: the 'amcl:' block has no 'ros__parameters:'")
        return cls.from_dict(block["ros__parameters"] or {})
