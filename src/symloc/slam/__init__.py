"""Laser SLAM: correlative scan matching against submaps, GTSAM pose graph.

Its evaluation (ATE / RPE against a reference, simulated odometry noise) lives in
:mod:`symloc.bench.slam_metrics` and :mod:`symloc.sim.odometry_noise`.
"""

from __future__ import annotations

from symloc.slam.correlative_scan_matching import (
    CsmParams,
    LikelihoodTable,
    MatchResult,
    match_information,
    match_scan,
    refine_pose,
)
from symloc.slam.degeneracy import MatchConstraint, analyse_match, fuse
from symloc.slam.loop_closure import LoopCandidate, LoopVerifier, LoopVerifierParams
from symloc.slam.odometry_model import OdometryModel, OdometryModelParams
from symloc.slam.pose_graph import PoseGraph, PoseGraphParams
from symloc.slam.slam import SlamParams, SlamResult, run_slam, slam_input
from symloc.slam.submaps import ActiveSubmaps, Submap, SubmapParams

__all__ = [
    "ActiveSubmaps",
    "CsmParams",
    "LikelihoodTable",
    "LoopCandidate",
    "LoopVerifier",
    "LoopVerifierParams",
    "MatchConstraint",
    "MatchResult",
    "OdometryModel",
    "OdometryModelParams",
    "PoseGraph",
    "PoseGraphParams",
    "SlamParams",
    "SlamResult",
    "Submap",
    "SubmapParams",
    "analyse_match",
    "fuse",
    "match_information",
    "match_scan",
    "refine_pose",
    "run_slam",
    "slam_input",
]
