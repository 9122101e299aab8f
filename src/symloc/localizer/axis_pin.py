"""The end walls pin a corridor's axis: an axis family reduced to one pose per heading class.

The global search lists every pose whose share of fitting beams is within its margin of the
best (:class:`~symloc.mcl.global_search.GlobalSearchConfig` ``score_margin``). In a corridor
whose ends are in the lidar's range the few beams on an end wall are a smaller share of the
scan than that margin, so the poses all along the corridor survive and the laser's hypotheses
look like a long corridor's axis family (:mod:`symloc.localizer.axis`), although the end
walls fix the position along it (dev corridor_short#1, 15 m: 9 of 10 trials ended on the axis
or on the way to the centre, the camera's heading decided and the position never claimed).

:func:`pin_axis` profiles the whole scan's fit (:func:`~symloc.localizer.best_fit.fit_profile`,
every beam, clipped) along each heading class' line across the whole map: where the end walls
are seen, one stretch fits clearly better than anywhere else on the line, and the class becomes
the single pose aligned there. Both classes pinned, the two poses (one the half-turned copy of
the other in a symmetric corridor) go to the camera as any two hypotheses do, and a verified one
is claimed only through the claim gate, whose precision test needs the end walls' information.
A line with no such stretch (a long corridor, ends out of range; a corridor with repeated
doors), a line running into space the map does not cover (the robot may stand beyond the
mapped end) or an alignment that leaves the line keeps the axis as it was.

So does a corridor longer than twice the lidar's range (``range_max`` of the scan, the same
lidar that mapped it), whatever pins the scan: its mapping trip drove a stretch with neither
end in range, where laser SLAM takes the motion along the axis from odometry alone, and the
map is off along the axis there by more than the claim gate's map error assumes (dev
corridor_long#1: pinned near the corridor's middle, 20 m from either end, then claimed 7-9 cm
off with a std of 1.8 cm, every claim inside the 10 cm tolerance but 4-5 stds off). The
claim gate now reads the map's error place by place (:mod:`symloc.slam.pose_marginals`),
which says decimetres there; with this rule and the gate's long-stretch rule both deleted
(d37584b, pin and walls model on) dev long corridors gave one claimed trial, 8.4 cm off at
worst, so the rule stays.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import wrap_angle

from .axis import line_reach, map_corners, open_stretch, runs_out
from .axis_phase import two_class_family
from .best_fit import fit_profile
from .context import Context, Inputs

__all__ = ["PIN_GAIN", "pin_axis"]

#: The pin's measured gain (``LocalizerConfig.axis_pin_gain``'s default; 1 turns it off).
PIN_GAIN = 0.25

FloatArray = NDArray[np.float64]


def pin_axis(ctx: Context, inp: Inputs, poses: FloatArray) -> tuple[FloatArray, FloatArray] | None:
    """One pose per heading class (2, 3), best fit first, with the share of beams that fit
    each (2,), where the scan pins the axis family of ``poses`` (K, 3) (the laser's survivors,
    best first); None when they are no axis family or a class is not pinned (module
    docstring).

    Settings: ``LocalizerConfig.axis_pin_step`` [m] between profiled positions,
    ``axis_pin_apart`` [m] and ``axis_pin_gain`` (the best fit must be this share lower than
    the fit anywhere farther than ``axis_pin_apart`` from it).
    """
    cfg = ctx.config
    gate, grid = ctx.gate, ctx.grid
    if gate is None or grid is None or cfg.axis_pin_gain >= 1.0:
        return None
    family = two_class_family(cfg, poses)
    if family is None:
        return None
    reach = float(getattr(inp.scan, "range_max", math.inf))
    points = gate.points(inp.scan)  # type: ignore[arg-type]
    if points.shape[0] < gate.config.min_beams:
        return None
    clip = gate.match_config.outlier_distance
    pinned: list[FloatArray] = []
    fits: list[float] = []
    for c in (0, 1):
        seg = family.segment(c)
        lo, hi = line_reach(seg, map_corners(grid))
        if runs_out(seg, grid, seg.lo, -1) or runs_out(seg, grid, seg.hi, +1):
            return None
        if open_stretch(seg, grid, 0.5 * (seg.lo + seg.hi)) > 2.0 * reach:
            return None
        s = np.arange(lo, hi + 0.5 * cfg.axis_pin_step, cfg.axis_pin_step)
        if s.size < 3:
            return None
        start = seg.at(lo)[0]
        profile = fit_profile(gate.field, points, start, seg.unit, s - lo, clip)
        k = int(np.argmin(profile))
        far = np.abs(s - s[k]) > cfg.axis_pin_apart
        if not np.any(far):
            return None
        rival = float(np.min(profile[far]))
        if not rival > 0.0 or 1.0 - float(profile[k]) / rival < cfg.axis_pin_gain:
            return None
        at = seg.at(s[k])[0]
        aligned, fit = gate.fit(at, inp.scan)  # type: ignore[arg-type]
        moved = float(np.hypot(*(aligned[:2] - at[:2])))
        turned = abs(float(wrap_angle(aligned[2] - at[2])))
        if (
            fit < cfg.decide_min_fit
            or moved > max(cfg.axis_max_spread, 2.0 * cfg.axis_pin_step)
            or turned > cfg.axis_heading_spread
        ):
            return None
        pinned.append(aligned)
        fits.append(fit)
    order = np.argsort(-np.asarray(fits), kind="stable")
    return (
        np.asarray(np.array(pinned)[order], dtype=np.float64),
        np.asarray(fits, dtype=np.float64)[order],
    )
