"""Visual orientation: ORB features, a DBoW2-compatible vocabulary, the visual map database
(symmetric places and keyframes along the mapping trip), the orientation decision at a
symmetric place (the paper's Algorithm 3) and the verification of pose hypotheses anywhere."""

from __future__ import annotations

from symloc.vision.bow import BowMatrix, BowVector, FeatureVector, Scoring, Weighting, score
from symloc.vision.default_vocabulary import default_vocabulary
from symloc.vision.keyframes import Keyframe, KeyframeSelector, KeyframeSettings
from symloc.vision.orb import OrbExtractor, OrbFeatures, OrbSettings
from symloc.vision.orientation import (
    OrientationConfig,
    OrientationDecision,
    decide_orientation,
    decide_with_retries,
)
from symloc.vision.place import Place, PlaceImage
from symloc.vision.verification import (
    HypothesisCheck,
    VerificationDecision,
    VerificationSettings,
    expected_keyframes,
    verify_hypotheses,
    verify_hypothesis,
)
from symloc.vision.visual_map import QueryResult, VisualMap
from symloc.vision.vocabulary import Vocabulary, load_dbow2_text, load_vocabulary, save_vocabulary

__all__ = [
    "BowMatrix",
    "BowVector",
    "FeatureVector",
    "HypothesisCheck",
    "Keyframe",
    "KeyframeSelector",
    "KeyframeSettings",
    "OrbExtractor",
    "OrbFeatures",
    "OrbSettings",
    "OrientationConfig",
    "OrientationDecision",
    "Place",
    "PlaceImage",
    "QueryResult",
    "Scoring",
    "VerificationDecision",
    "VerificationSettings",
    "VisualMap",
    "Vocabulary",
    "Weighting",
    "decide_orientation",
    "decide_with_retries",
    "default_vocabulary",
    "expected_keyframes",
    "load_dbow2_text",
    "load_vocabulary",
    "save_vocabulary",
    "score",
    "verify_hypotheses",
    "verify_hypothesis",
]
