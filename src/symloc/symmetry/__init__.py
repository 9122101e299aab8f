"""Symmetry of the room around the robot from one laser scan (Section 4.2, generalised)."""

from __future__ import annotations

from symloc.symmetry.algorithm1 import Algorithm1Result, algorithm1
from symloc.symmetry.config import SymmetryConfig
from symloc.symmetry.gv_index import GVEntry, GVIndex
from symloc.symmetry.judge import fit_circle, judge_symmetry, rotational_order
from symloc.symmetry.order import SymmetryOrder
from symloc.symmetry.report import KINDS, SymmetryReport
from symloc.symmetry.scan_lines import ScanLines, scan_lines

__all__ = [
    "KINDS",
    "Algorithm1Result",
    "GVEntry",
    "GVIndex",
    "ScanLines",
    "SymmetryConfig",
    "SymmetryOrder",
    "SymmetryReport",
    "algorithm1",
    "fit_circle",
    "judge_symmetry",
    "rotational_order",
    "scan_lines",
]
