"""Visual orientation: ORB features, a DBoW2-compatible vocabulary, the visual map database."""

from __future__ import annotations

from symloc.vision.bow import BowMatrix, BowVector, FeatureVector, Scoring, Weighting, score
from symloc.vision.orb import OrbExtractor, OrbFeatures, OrbSettings
from symloc.vision.visual_map import Place, PlaceImage, QueryResult, VisualMap
from symloc.vision.vocabulary import Vocabulary

__all__ = [
    "BowMatrix",
    "BowVector",
    "FeatureVector",
    "OrbExtractor",
    "OrbFeatures",
    "OrbSettings",
    "Place",
    "PlaceImage",
    "QueryResult",
    "Scoring",
    "VisualMap",
    "Vocabulary",
    "Weighting",
    "score",
]
