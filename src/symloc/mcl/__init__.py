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

#: Public name -> the module that defines it.
_EXPORTS = {
    "Amcl": "symloc.mcl.amcl",
    "AmclResult": "symloc.mcl.amcl",
    "NotInitializedError": "symloc.mcl.amcl",
    "ClusterStats": "symloc.mcl.clustering",
    "Hypothesis": "symloc.mcl.clustering",
    "cluster_particles": "symloc.mcl.clustering",
    "Confidence": "symloc.mcl.confidence",
    "ConfidenceConfig": "symloc.mcl.confidence",
    "ConfidenceJudge": "symloc.mcl.confidence",
    "ScanConsistency": "symloc.mcl.confidence",
    "assess": "symloc.mcl.confidence",
    "scan_consistency": "symloc.mcl.confidence",
    "AmclParams": "symloc.mcl.params",
    "RivalReport": "symloc.mcl.rival_search",
    "find_rival": "symloc.mcl.rival_search",
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


def _submodule_attributes() -> dict[str, list[str]]:
    """:data:`_EXPORTS` as lazy_loader wants it: submodule (relative) -> its public names."""
    out: dict[str, list[str]] = {}
    for name, module in _EXPORTS.items():
        out.setdefault(module.rsplit(".", 1)[-1], []).append(name)
    return out


# PEP 562 through scientific-python's lazy_loader (as scikit-image does)
__getattr__, __dir__, _ = lazy_loader.attach(__name__, submod_attrs=_submodule_attributes())
