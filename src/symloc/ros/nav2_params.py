"""nav2's parameter files for the node: the ``amcl: ros__parameters:`` block as ROS parameters.

The node takes nav2_amcl's place, so it reads nav2's own ``nav2_params.yaml`` unchanged (the
``amcl:`` block of nav2's humble, jazzy, kilted and main branches, through ``--ros-args
--params-file``) and its parameters are real ROS parameters (``ros2 param get/set``). Names:

- nav2_amcl's filter parameters (``alpha1`` .. ``z_short``, ``laser_model_type``,
  ``robot_model_type``, ...) and symloc's three additions to them
  (:class:`symloc.mcl.AmclParams`) go to :attr:`NodeParams.amcl`;
- nav2_amcl's node parameters (frames, ``scan_topic``, ``map_topic``, ``tf_broadcast``,
  ``transform_tolerance``, ``first_map_only``, ``set_initial_pose``, ``initial_pose.x|y|yaw``,
  ``always_reset_initial_pose``, ``save_pose_rate``, ``initialize_at_saved_pose``,
  ``saved_pose_filepath``, ``random_seed``) and of nav2's lifecycle nodes
  (``bond_heartbeat_period``, ``autostart_node``) are :class:`NodeParams` fields of the same
  name (``random_seed`` >= 0 sets ``seed``; below 0, as nav2's -1, the filter is seeded from
  the time, unless symloc's own ``seed`` is given: :func:`time_seed`);
- symloc's own settings keep their names: the other :class:`NodeParams` fields
  (``laser_frame_id``, ``image_topic``, ``visual_map``, ``odom_source``, ``laser_pose``,
  ``mode``, ``lidar_preset``, ``seed``, ...) and one dotted block per part of the localizer's
  settings tree (:class:`symloc.localizer.settings.LocalizerSettings`):
  ``confidence.<field>`` (:class:`symloc.mcl.ConfidenceConfig`), ``claim.<field>``
  (:class:`symloc.localizer.claim.ClaimConfig`), ``localizer.<field>``
  (:class:`symloc.localizer.LocalizerConfig`; ``allow_mapping`` is ``mode``) and
  ``symmetry.<field>`` (:class:`symloc.symmetry.SymmetryConfig`, over ``lidar_preset``'s);
  ``amcl.<field>`` is accepted too (symloc's own nested layout), and
  ``localizer.converged_weight|converged_xy_std|converged_theta_std`` as older names of
  ``confidence.min_weight_share|max_xy_std|max_theta_std``
  (:data:`symloc.ros.params.ALIASES`); the block's fields are read from the dataclasses, so a
  field added to a block is a parameter without a change here;
- accepted and without effect, each for a reason (:data:`WITHOUT_EFFECT`).

Any other name is unknown: :func:`node_params_from_ros` raises
:class:`~symloc.errors.ConfigurationError` naming it, or, given ``on_unknown`` (the node, as
nav2_amcl ignores names it does not declare), reports it there and ignores it. An invalid value
always raises, naming it: nothing is reset to a default with a log line.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from symloc.errors import ConfigurationError
from symloc.files.bounded import MAX_PARAMS_FILE_BYTES, load_yaml_bounded, read_text_bounded
from symloc.localizer.settings import LocalizerSettings
from symloc.mcl.params import AmclParams
from symloc.ros.params import ALIASES, SETTINGS_BLOCKS, NodeParams, split_aliases

__all__ = [
    "NAV2_DEFAULTS",
    "WITHOUT_EFFECT",
    "node_params_from_ros",
    "parameter_defaults",
    "read_params_block",
    "ros_values",
    "seeded_from_time",
    "settings_from_ros",
    "settings_to_ros",
    "time_seed",
]

#: nav2_amcl's defaults where they differ from :class:`NodeParams`'s.
NAV2_DEFAULTS: dict[str, Any] = {"base_frame_id": "base_footprint"}

#: nav2 names the node accepts without effect, with their nav2 default and the reason.
WITHOUT_EFFECT: dict[str, tuple[Any, str]] = {
    "freespace_downsampling": (
        False,
        "symloc's global initialisation draws from the map's free cells itself",
    ),
    "allow_parameter_qos_overrides": (
        True,
        "QoS overrides of the scan subscription are always allowed (qos_overrides.*)",
    ),
    "introspection_mode": ("disabled", "rclpy's lifecycle node offers no service introspection"),
    "service_introspection_mode": (
        "disabled",
        "rclpy's lifecycle node offers no service introspection",
    ),
    "map_subscribe_transient_local": (True, "the map is always subscribed transient local"),
    "bond_disable_heartbeat_timeout": (True, "the node never times out its manager's bond"),
    "initial_pose.z": (0.0, "the localizer is 2-D: the initial pose's height is ignored"),
    "accept_map_updates": (
        False,
        "retired: every new map is taken, as nav2_amcl does, unless first_map_only is true",
    ),
}


def time_seed() -> int:
    """A seed from the clock (nav2_amcl's ``random_seed`` < 0), in 0 .. 2**31 - 1."""
    return int(time.time_ns() % (2**31 - 1))


def seeded_from_time(values: Mapping[str, Any]) -> bool:
    """True when these ROS parameter values seed the filter from the time: ``random_seed``
    below 0 (nav2's -1) and symloc's ``seed`` not given."""
    seed = values.get("random_seed")
    return (
        isinstance(seed, int)
        and not isinstance(seed, bool)
        and seed < 0
        and values.get("seed") is None
    )


_BLOCKS = (*SETTINGS_BLOCKS, "symmetry")
_AMCL = tuple(f.name for f in dataclasses.fields(AmclParams) if f.name != "ros_extras")
_NODE = tuple(f.name for f in dataclasses.fields(NodeParams) if f.name not in _BLOCKS)
#: dotted blocks (``confidence.*``, ``claim.*``, ``localizer.*``) -> their parameter fields
_DOTTED: dict[str, tuple[str, ...]] = {
    name: tuple(
        f.name
        for f in dataclasses.fields(cls)
        if f"{name}.{f.name}" not in ALIASES and (name, f.name) != ("localizer", "allow_mapping")
    )
    for name, cls in SETTINGS_BLOCKS.items()
    if name != "amcl"
}


def _symmetry_fields() -> tuple[str, ...]:
    from symloc.symmetry import SymmetryConfig

    return tuple(f.name for f in dataclasses.fields(SymmetryConfig))


def _ros_value(value: Any) -> Any:
    """A value as a ROS parameter holds it (tuples as lists; empty sequences as not set)."""
    if isinstance(value, tuple):
        return list(value) if value else None
    return value


def parameter_defaults() -> dict[str, Any]:
    """Every parameter the node declares, with its default (None: not set by default).

    Flat nav2 names for the filter and node settings (nav2_amcl's defaults), ``initial_pose.*``
    as nav2 spells it, ``confidence.*``, ``claim.*``, ``localizer.*`` and ``symmetry.*`` for
    symloc's blocks, the older names of :data:`symloc.ros.params.ALIASES` (not set by
    default), and the names of :data:`WITHOUT_EFFECT`.
    """
    params = NodeParams()
    out: dict[str, Any] = {}
    for name in _AMCL:
        out[name] = _ros_value(getattr(params.amcl, name))
    for name in _NODE:
        if name == "initial_pose":
            x, y, yaw = params.initial_pose
            out.update({"initial_pose.x": x, "initial_pose.y": y, "initial_pose.z": 0.0})
            out["initial_pose.yaw"] = yaw
            continue
        out[name] = _ros_value(NAV2_DEFAULTS.get(name, getattr(params, name)))
    out["random_seed"] = -1
    out["seed"] = None  # not set: nav2's random_seed decides (-1: from the time)
    for block, names in _DOTTED.items():
        for name in names:
            out[f"{block}.{name}"] = _ros_value(getattr(getattr(params, block), name))
    for name in _symmetry_fields():
        out[f"symmetry.{name}"] = None
    for name in ALIASES:
        out[name] = None  # declared (a params file may use them), not set by default
    for name, (default, _why) in WITHOUT_EFFECT.items():
        out[name] = default
    return out


def node_params_from_ros(
    values: Mapping[str, Any], *, on_unknown: Callable[[str], object] | None = None
) -> NodeParams:
    """:class:`NodeParams` from ROS parameter values (flat names as :func:`parameter_defaults`
    lists; a value of None is "not set").

    ``random_seed`` >= 0 sets ``seed``; below 0 with no ``seed`` given the seed comes from the
    time (:func:`time_seed`, :func:`seeded_from_time`), as in nav2_amcl.

    Parameters
    ----------
    values : mapping
    on_unknown : callable, optional
        Receives a line about each unknown name, which is then ignored (nav2_amcl's way);
        without it an unknown name raises.

    Raises
    ------
    ConfigurationError
        An unknown name (named; without ``on_unknown``) or an invalid value (named, with what
        was expected).
    """
    node: dict[str, Any] = {}
    amcl: dict[str, Any] = {}
    blocks: dict[str, dict[str, Any]] = {name: {} for name in _DOTTED}
    symmetry: dict[str, Any] = {}
    initial: dict[str, Any] = {}
    seed: Any = None
    sym_names = set(_symmetry_fields())
    for name, raw in values.items():
        if raw is None or name == "use_sim_time" or name.startswith("qos_overrides."):
            continue
        # ROS array parameters come as array.array or numpy arrays: plain lists
        value = raw.tolist() if hasattr(raw, "tolist") else raw
        head, _, tail = name.partition(".")
        if name in _AMCL:
            amcl[name] = value
        elif head == "amcl" and tail in _AMCL:
            if tail in amcl and amcl[tail] != value:
                raise ConfigurationError(f"parameter {name!r}: also given as {tail!r}, differently")
            amcl[tail] = value
        elif head in _DOTTED and tail:
            if tail not in _DOTTED[head] and name not in ALIASES:
                cls = SETTINGS_BLOCKS[head].__name__
                why = " (set by 'mode')" if name == "localizer.allow_mapping" else ""
                raise ConfigurationError(
                    f"parameter {name!r}: not a {cls} field{why} (known: {list(_DOTTED[head])})"
                )
            blocks[head][tail] = value
        elif head == "symmetry" and tail:
            if tail not in sym_names:
                raise ConfigurationError(
                    f"parameter {name!r}: not a SymmetryConfig field (known: {sorted(sym_names)})"
                )
            symmetry[tail] = value
        elif head == "initial_pose" and tail in ("x", "y", "z", "yaw"):
            initial[tail] = value
        elif name == "random_seed":
            seed = value
        elif name in _NODE and name != "initial_pose":
            node[name] = value
        elif name in WITHOUT_EFFECT:
            continue
        else:
            why = (
                f"parameter {name!r}: unknown to symloc (nav2_amcl's names, symloc's node"
                " settings, confidence.*, claim.*, localizer.* and symmetry.* are known; see"
                " symloc.ros.nav2_params)"
            )
            if on_unknown is None:
                raise ConfigurationError(why)
            on_unknown(why + ": ignored")
    if seed is not None:
        if isinstance(seed, bool) or not isinstance(seed, int):
            raise ConfigurationError(f"random_seed: expected an integer, got {seed!r}")
        if seed >= 0:
            node["seed"] = seed
        elif "seed" not in node:
            node["seed"] = time_seed()
    if initial:
        node["initial_pose"] = initial
    # every declared parameter has a value: an older name given beside its target's default
    # sets the target
    defaults = NodeParams()
    for alias, target in ALIASES.items():
        head, _, tail = target.partition(".")
        given = blocks[head]
        if (
            alias.partition(".")[2] in blocks["localizer"]
            and tail in given
            and given[tail] == getattr(getattr(defaults, head), tail)
        ):
            del given[tail]
    split_aliases(blocks["localizer"], blocks["confidence"])
    try:
        node["amcl"] = AmclParams.from_dict(amcl)
    except TypeError as err:
        raise ConfigurationError(f"parameters: {err}") from err
    for block, given in blocks.items():
        node[block] = given
    node["symmetry"] = symmetry
    return NodeParams.from_dict(node)


def ros_values(params: NodeParams) -> dict[str, Any]:
    """The ROS parameter values of ``params`` (the inverse of :func:`node_params_from_ros`)."""
    out: dict[str, Any] = {}
    for name in _AMCL:
        out[name] = _ros_value(getattr(params.amcl, name))
    for name in _NODE:
        if name == "initial_pose":
            x, y, yaw = params.initial_pose
            out.update({"initial_pose.x": x, "initial_pose.y": y, "initial_pose.yaw": yaw})
            continue
        out[name] = _ros_value(getattr(params, name))
    for block, names in _DOTTED.items():
        for name in names:
            out[f"{block}.{name}"] = _ros_value(getattr(getattr(params, block), name))
    for name, value in params.symmetry.items():
        out[f"symmetry.{name}"] = _ros_value(value)
    return out


def settings_to_ros(settings: LocalizerSettings, **others: Any) -> dict[str, Any]:
    """The ROS parameter values that give the localizer ``settings`` (``others``: node
    fields, e.g. ``visual_map``); the inverse of :func:`settings_from_ros`."""
    return ros_values(NodeParams.from_settings(settings, **others))


def settings_from_ros(values: Mapping[str, Any]) -> LocalizerSettings:
    """The localizer's settings from ROS parameter values (:func:`node_params_from_ros`)."""
    return node_params_from_ros(values).settings()


def _flatten(block: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in block.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(_flatten(value, name + "."))
        else:
            out[name] = value
    return out


def read_params_block(path: str | Path, node_name: str = "amcl") -> dict[str, Any]:
    """The flat ROS parameters a ``--params-file`` gives node ``node_name``, as rcl reads it:
    the ``ros__parameters`` of the blocks named ``/**``, ``node_name``, ``/node_name`` or
    ``<namespace>/node_name``, later blocks overriding earlier ones, nested mappings joined
    with dots (``initial_pose: {x: 1}`` is ``initial_pose.x``)."""
    text = read_text_bounded(
        path, MAX_PARAMS_FILE_BYTES, what="the params file", error=ConfigurationError
    )
    doc = load_yaml_bounded(text, where=f"params file {path}", error=ConfigurationError)
    if not isinstance(doc, dict):
        raise ConfigurationError(f"params file {path}: expected a mapping of node names")
    out: dict[str, Any] = {}
    found = False
    for key, value in doc.items():
        k = str(key).strip("/")
        if k in ("**", node_name) or k.endswith("/" + node_name):
            if not isinstance(value, dict) or not isinstance(value.get("ros__parameters"), dict):
                raise ConfigurationError(f"params file {path}: {key}: expected ros__parameters")
            out.update(_flatten(value["ros__parameters"]))
            found = True
    if not found:
        raise ConfigurationError(
            f"params file {path}: no block for node {node_name!r} (keys: {sorted(map(str, doc))})"
        )
    return out
