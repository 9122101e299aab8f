"""The node's glue to the one builder: the place store from its parameters, a global start.

:func:`make_localizer` (the default factory of :class:`~symloc.ros.core.NodeCore`, hence of
the node and of bag replay) opens the visual map named by the parameters and calls
:func:`symloc.localizer.build.build_localizer` with :meth:`NodeParams.settings`, the same
function the bench, the demo and the experiments build with. The localizer starts from a
global initialisation (nothing earned).

:func:`check_files` opens the files the parameters name once, so that the node's configure
(and ``symloc replay``) fails with the reason, as nav2 fails configure for a bad map, instead
of every map build failing later while the node answers ``lost`` to every scan.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from symloc.camera_model import pinhole_matrix
from symloc.errors import ConfigurationError, DatabaseError, SymlocError
from symloc.grid import OccupancyGrid
from symloc.localizer import Localizer
from symloc.localizer.build import build_localizer
from symloc.localizer.places import MemoryPlaces
from symloc.localizer.types import KeyframeStore, PlaceStore
from symloc.ros.params import NodeParams

__all__ = ["MemoryPlaces", "camera_matrix", "check_files", "make_localizer", "open_places"]


def camera_matrix(params: NodeParams) -> NDArray[np.float64]:
    """The (3, 3) intrinsics from ``params.camera_intrinsics`` (default: 640 x 480, 65 deg HFOV)."""
    if not params.camera_intrinsics:
        return pinhole_matrix()
    fx, fy, cx, cy = params.camera_intrinsics
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def open_places(params: NodeParams) -> PlaceStore:
    """The place store for ``params.visual_map`` (``""``: :class:`MemoryPlaces`).

    In ``localize`` mode the visual map is opened read-only.

    Raises
    ------
    ConfigurationError
        The file is missing in ``localize`` mode, or the map records another vocabulary than
        ``params.vocabulary``.
    """
    path = params.visual_map
    if not path:
        return MemoryPlaces()
    from pathlib import Path

    from symloc.localizer.vision_store import VisionPlaceStore
    from symloc.vision import VisualMap, Vocabulary

    if not params.allow_mapping and not Path(path).is_file():
        raise ConfigurationError(f"visual_map: {path} does not exist (mode localize)")
    from symloc.vision.default_vocabulary import default_vocabulary

    vocab = Vocabulary.load(params.vocabulary) if params.vocabulary else default_vocabulary()
    vmap = VisualMap(path, create=params.allow_mapping, readonly=not params.allow_mapping)
    stored = vmap.get_meta("vocabulary")
    want = default_vocabulary().fingerprint() if stored == "default" else stored
    if want is not None and want.startswith("sha256:") and want != vocab.fingerprint():
        vmap.close()
        made = "the shipped vocabulary" if stored == "default" else want[:19] + "..."
        raise ConfigurationError(
            f"vocabulary: the visual map {path} was made with {made}, not with"
            f" {params.vocabulary or 'the shipped vocabulary'}; set 'vocabulary' to its file"
        )
    return VisionPlaceStore(
        vmap, vocab, camera_matrix(params), dist_coeffs=params.camera_dist_coeffs or None
    )


def check_files(params: NodeParams) -> None:
    """Open the visual map and the vocabulary the parameters name, then close them.

    Raises
    ------
    ConfigurationError
        Naming the parameter (``visual_map`` or ``vocabulary``), the file and why it cannot be
        used: missing (the visual map in ``localize`` mode), not a file, of a newer schema,
        damaged or not a symloc file, or made with another vocabulary.
    """
    if params.visual_map:
        try:
            store = open_places(params)
        except ConfigurationError:
            raise
        except DatabaseError as err:
            raise ConfigurationError(f"visual_map: {err}") from err
        except SymlocError as err:  # the vocabulary file (VocabularyFileError, ...)
            raise ConfigurationError(f"vocabulary: {err}") from err
        vmap = getattr(store, "visual_map", None)
        if vmap is not None:
            vmap.close()
    elif params.vocabulary:
        from symloc.vision import Vocabulary

        try:
            Vocabulary.load(params.vocabulary)
        except SymlocError as err:
            raise ConfigurationError(f"vocabulary: {err}") from err


def make_localizer(
    grid: OccupancyGrid, params: NodeParams, *, places: PlaceStore | None = None
) -> Localizer:
    """A globally initialised localizer on ``grid`` configured by ``params``.

    :func:`~symloc.localizer.build.build_localizer` with ``params.settings()`` and the place
    store of :func:`open_places` (or ``places``), then :meth:`Localizer.reset_global`. AMCL
    draws from ``numpy.random.default_rng(params.seed)``, so two localizers made with the same
    parameters and fed the same messages give the same estimates. ``params.laser_pose`` (the
    node sets it from TF) goes to every part that reads scans. Scans of an upside-down laser
    arrive mirrored (the node does it). A visual map that holds keyframes is also the
    localizer's :class:`~symloc.localizer.types.KeyframeStore`: with ``localizer.decide_here``
    the camera decides where the robot stands (:mod:`symloc.localizer.decide_here`).

    Raises
    ------
    ConfigurationError
        The map has no occupied cell (a 1 x 1 map, a blank canvas: nothing a scan could match;
        the node then keeps waiting for a usable map) or no free cell, or a file named by the
        parameters cannot be used (:func:`open_places`).
    """
    if not np.any(grid.occupied_mask):
        raise ConfigurationError(
            "map: no occupied cell (occupancy > occupied_thresh): nothing a scan could match;"
            " waiting for a map with walls"
        )
    store = places if places is not None else open_places(params)
    # a visual map with keyframes lets the camera decide where the robot stands
    # (localizer.decide_here); a store without them leaves that to the paper's path
    keyframes = store if isinstance(store, KeyframeStore) else None
    rotation_std, position_std = _declared_round_map_error(store)
    loc = build_localizer(
        grid,
        params.settings(),
        places=store,
        keyframes=keyframes,
        map_std_xy=position_std,
        map_rotation_std=rotation_std,
    )
    loc.reset_global()
    return loc


def _declared_round_map_error(store: PlaceStore) -> tuple[float | None, float | None]:
    """The round map's rotation error [rad] and position error [m] the store's visual map
    declares (None: no visual map, or none declared;
    :func:`symloc.vision.gyro_drift.declared_round_map_error`)."""
    vmap = getattr(store, "visual_map", None)
    if vmap is None:
        return None, None
    from symloc.vision.gyro_drift import declared_round_map_error

    return declared_round_map_error(vmap)
