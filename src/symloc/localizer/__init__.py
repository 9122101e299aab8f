"""The symloc localizer: Algorithm 5 (state machine), Algorithm 2 (centering), mapping stage."""

from __future__ import annotations

from .localizer import Localizer, LocalizerConfig, rotated_copies, symmetry_consistent
from .types import (
    Decision,
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
