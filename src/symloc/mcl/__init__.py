"""Monte Carlo localization: motion and sensor models, KLD-sampling, recovery, clustering, AMCL.

A NumPy port of nav2_amcl's filter with its parameter names and defaults, vectorised over
particles and beams, with its known weaknesses fixed (see :mod:`symloc.mcl.amcl`).
"""

from __future__ import annotations

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
