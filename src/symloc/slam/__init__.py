"""Laser SLAM: correlative scan matching against submaps, GTSAM pose graph, metrics."""

from __future__ import annotations

from symloc.slam.correlative_scan_matching import (
    CsmParams,
    LikelihoodTable,
    MatchResult,
    match_scan,
    refine_pose,
)
from symloc.slam.metrics import AteResult, RpeResult, ate, rpe
from symloc.slam.odometry_noise import DEFAULT_ALPHAS, noisy_odometry
from symloc.slam.pose_graph import PoseGraph, PoseGraphParams
from symloc.slam.slam import SlamParams, SlamResult, run_slam
from symloc.slam.submaps import ActiveSubmaps, Submap, SubmapParams

__all__ = [
    "DEFAULT_ALPHAS",
    "ActiveSubmaps",
    "AteResult",
    "CsmParams",
    "LikelihoodTable",
    "MatchResult",
    "PoseGraph",
    "PoseGraphParams",
    "RpeResult",
    "SlamParams",
    "SlamResult",
    "Submap",
    "SubmapParams",
    "ate",
    "match_scan",
    "noisy_odometry",
    "refine_pose",
    "rpe",
    "run_slam",
]
