"""Every setting of the localizer in one frozen tree (Cartographer's options tree, rule 4).

:class:`LocalizerSettings` holds what :func:`symloc.localizer.build.build_localizer` needs to
build the localizer, and nothing else: the node (ROS parameters, ``symloc ros node --params``),
bag replay, the bench, the demo and the experiments all fill one of these and hand it to the
one builder, so that two callers with equal settings build the same localizer.

The tree::

    LocalizerSettings
    |-- amcl        AmclParams        the filter, nav2_amcl's names and units
    |-- confidence  ConfidenceConfig  when AMCL's estimate counts as converged (symloc.mcl)
    |-- claim       ClaimConfig       the claim gate that keeps the published pose honest
    |-- localizer   LocalizerConfig   Algorithm 5's state machine and Algorithm 2's centering
    |-- symmetry    SymmetryConfig    Algorithm 1's tolerances (from the lidar's range noise)
    |-- laser_pose  (x [m], y [m], yaw [rad]) of the laser in the robot frame
    `-- seed        seed of AMCL's random numbers when the caller gives no generator

Visual mapping (Algorithm 5 step 11) is ``localizer.allow_mapping``. ROS parameters, YAML
files and CLI flags are only translated into this tree (:mod:`symloc.ros.params`,
:mod:`symloc.ros.nav2_params`); every block validates itself and an invalid value raises
:class:`~symloc.errors.ConfigurationError` naming the field. :func:`leaf_paths` lists every
leaf generically (``"claim.gate_sigmas"``), so a field added to or removed from a block needs
no change here.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from symloc.errors import ConfigurationError
from symloc.localizer.claim import ClaimConfig
from symloc.localizer.localizer import LocalizerConfig
from symloc.mcl.confidence import ConfidenceConfig
from symloc.mcl.params import AmclParams
from symloc.symmetry import SymmetryConfig

__all__ = ["BLOCKS", "LocalizerSettings", "leaf_paths", "leaf_values", "settings_from_leaves"]

#: The blocks of the tree and their classes, in the order of :class:`LocalizerSettings`.
BLOCKS: dict[str, type[Any]] = {
    "amcl": AmclParams,
    "confidence": ConfidenceConfig,
    "claim": ClaimConfig,
    "localizer": LocalizerConfig,
    "symmetry": SymmetryConfig,
}

#: Fields of a block that are not settings (bookkeeping), per block.
_NOT_SETTINGS: dict[str, frozenset[str]] = {"amcl": frozenset({"ros_extras"})}

#: The top-level leaves (not in a block).
TOP_LEVEL = ("laser_pose", "seed")


def block_fields(block: str) -> tuple[str, ...]:
    """The setting names of ``block`` (its dataclass fields, minus bookkeeping)."""
    skip = _NOT_SETTINGS.get(block, frozenset())
    return tuple(f.name for f in fields(BLOCKS[block]) if f.name not in skip)


def _pose3(value: Any) -> tuple[float, float, float]:
    if (
        isinstance(value, (str, bytes))
        or not hasattr(value, "__len__")
        or len(value) != 3
        or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(float(v))
            for v in value
        )
    ):
        raise ConfigurationError(
            f"laser_pose: expected 3 numbers x [m], y [m], yaw [rad], got {value!r}"
        )
    x, y, yaw = (float(v) for v in value)
    return (x, y, yaw)


@dataclass(frozen=True)
class LocalizerSettings:
    """Every setting of the localizer (see the module docstring for the tree).

    Attributes
    ----------
    amcl : AmclParams
        AMCL, with nav2_amcl's names, units and defaults.
    confidence : ConfidenceConfig
        The thresholds of AMCL's confidence judgement (convergence: weight share, x-y std [m],
        heading std [rad]; the scan check; the rival search).
    claim : ClaimConfig
        The claim gate (tolerance 0.1 m / 5 deg, gate sigmas, the odometry error model
        ``odometry_alphas`` that grows a carried pose's covariance, ...).
    localizer : LocalizerConfig
        The state machine (including ``allow_mapping``: map places that match nothing).
    symmetry : SymmetryConfig
        Algorithm 1 (``SymmetryConfig.from_lidar(preset)`` for a known scanner).
    laser_pose : tuple of 3 floats
        ``x [m], y [m], yaw [rad]`` of the laser in the robot frame (``base_from_laser``).
    seed : int
        Seed (>= 0) of AMCL's random numbers when the builder is given no generator.
    """

    amcl: AmclParams = field(default_factory=AmclParams)
    confidence: ConfidenceConfig = field(default_factory=ConfidenceConfig)
    claim: ClaimConfig = field(default_factory=ClaimConfig)
    localizer: LocalizerConfig = field(default_factory=LocalizerConfig)
    symmetry: SymmetryConfig = field(default_factory=SymmetryConfig)
    laser_pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    seed: int = 0

    def __post_init__(self) -> None:
        for name, cls in BLOCKS.items():
            value = getattr(self, name)
            if not isinstance(value, cls):
                raise ConfigurationError(
                    f"{name}: expected a {cls.__name__}, got {type(value).__name__}"
                )
        object.__setattr__(self, "laser_pose", _pose3(self.laser_pose))
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigurationError(f"seed: expected an integer >= 0, got {self.seed!r}")

    def replace(self, **changes: Any) -> LocalizerSettings:
        """A validated copy with top-level fields or dotted leaves (``"claim.patience"``)
        changed: ``settings.replace(seed=3, **{"localizer.allow_mapping": True})``."""
        return settings_from_leaves({**leaf_values(self), **changes})


def leaf_paths() -> tuple[str, ...]:
    """Every leaf of the tree as a dotted path (``"amcl.alpha1"``, ..., ``"seed"``)."""
    out = [f"{block}.{name}" for block in BLOCKS for name in block_fields(block)]
    return (*out, *TOP_LEVEL)


def leaf_values(settings: LocalizerSettings) -> dict[str, Any]:
    """``{dotted path: value}`` for every leaf of ``settings`` (:func:`leaf_paths`)."""
    out: dict[str, Any] = {}
    for block in BLOCKS:
        obj = getattr(settings, block)
        for name in block_fields(block):
            out[f"{block}.{name}"] = getattr(obj, name)
    for name in TOP_LEVEL:
        out[name] = getattr(settings, name)
    return out


def _wrap(name: str, build: Any) -> Any:
    try:
        return build()
    except ConfigurationError:
        raise
    except (TypeError, ValueError, OverflowError) as err:
        raise ConfigurationError(f"{name}: {err}") from err


def settings_from_leaves(
    values: Mapping[str, Any], base: LocalizerSettings | None = None
) -> LocalizerSettings:
    """Settings from dotted leaves (:func:`leaf_paths`), the others taken from ``base``.

    Raises
    ------
    ConfigurationError
        An unknown leaf (named) or an invalid value (named by its block's check).
    """
    start = base if base is not None else LocalizerSettings()
    known = set(leaf_paths())
    bad = sorted(set(values) - known)
    if bad:
        raise ConfigurationError(f"{bad[0]}: not a localizer setting")
    kwargs: dict[str, Any] = {}
    for block in BLOCKS:
        changes = {
            path.partition(".")[2]: tuple(v) if isinstance(v, list) else v
            for path, v in values.items()
            if path.startswith(block + ".")
        }
        current = getattr(start, block)
        if not changes:
            kwargs[block] = current
            continue
        kwargs[block] = _wrap(block, lambda c=current, ch=changes: dataclasses.replace(c, **ch))
    for name in TOP_LEVEL:
        kwargs[name] = values.get(name, getattr(start, name))
    settings: LocalizerSettings = _wrap("settings", lambda: LocalizerSettings(**kwargs))
    return settings
