"""Monte Carlo localization: motion and sensor models, KLD-sampling, recovery, clustering, AMCL.

A NumPy port of nav2_amcl's filter with its parameter names and defaults, vectorised over
particles and beams, with its known weaknesses fixed (see :mod:`symloc.mcl.amcl`).

The names below are imported from their modules on first use, so that importing one module of
the package (SLAM's map error uses :mod:`symloc.mcl.scan_to_map`) does not load the filter
and its compiled kernels (numba).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import lazy_loader

if TYPE_CHECKING:
    from symloc.mcl.amcl import Amcl, AmclResult, NotInitializedError
    from symloc.mcl.clustering import ClusterStats, Hypothesis, cluster_particles
    from symloc.mcl.confidence import (
        Confidence,
        ConfidenceConfig,
        ConfidenceJudge,
        ScanConsistency,
        assess,
        scan_consistency,
    )
    from symloc.mcl.params import AmclParams
    from symloc.mcl.rival_search import RivalReport, find_rival

#: Submodule -> the public names it defines (imported on first use).
_SUBMODULE_ATTRS = {
    "amcl": ["Amcl", "AmclResult", "NotInitializedError"],
    "clustering": ["ClusterStats", "Hypothesis", "cluster_particles"],
    "confidence": [
        "Confidence",
        "ConfidenceConfig",
        "ConfidenceJudge",
        "ScanConsistency",
        "assess",
        "scan_consistency",
    ],
    "params": ["AmclParams"],
    "rival_search": ["RivalReport", "find_rival"],
}

__all__ = [
    "Amcl",
    "AmclParams",
    "AmclResult",
    "ClusterStats",
    "Confidence",
    "ConfidenceConfig",
    "ConfidenceJudge",
    "Hypothesis",
    "NotInitializedError",
    "RivalReport",
    "ScanConsistency",
    "assess",
    "cluster_particles",
    "find_rival",
    "scan_consistency",
]


# PEP 562 through scientific-python's lazy_loader (as scikit-image does)
__getattr__, __dir__, _ = lazy_loader.attach(__name__, submod_attrs=_SUBMODULE_ATTRS)
