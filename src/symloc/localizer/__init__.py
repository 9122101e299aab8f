"""The symloc localizer: Algorithm 5 (state machine), Algorithm 2 (centering), mapping stage."""

from __future__ import annotations

from .config import LocalizerConfig
from .copies import rotated_copies, symmetry_consistent
from .localizer import Localizer
from .types import (
    Decision,
    DecisionStatus,
    Estimate,
    Hypothesis,
    Place,
    PlaceStore,
    Request,
    RequestKind,
    Status,
    SymmetryJudge,
    SymmetryVerdict,
    Tracker,
    TrackerResult,
)

__all__ = [
    "Decision",
    "DecisionStatus",
    "Estimate",
    "Hypothesis",
    "Localizer",
    "LocalizerConfig",
    "Place",
    "PlaceStore",
    "Request",
    "RequestKind",
    "Status",
    "SymmetryJudge",
    "SymmetryVerdict",
    "Tracker",
    "TrackerResult",
    "rotated_copies",
    "symmetry_consistent",
]
