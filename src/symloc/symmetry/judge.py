"""The generalised symmetry judgement: regular n-gons, circles, rectangles, hallways.

This goes past the paper's Algorithm 1 (square only, see :mod:`symloc.symmetry.algorithm1`)
while keeping its idea: the distances from a centroid to the room's vertices must be equal.

1. Points from the scan (eq. 1-2); fewer than ``min_points`` -> ``unknown``.
2. The contour is cut at gaps longer than a dropout (:func:`symloc.features.contour_runs`).
3. Closed contour (a full 360-degree scan without gap):

   a. **Circle** if every point lies within its tolerance of the least-squares circle and
      every point is equally far from the chosen centroid (the paper's "num_max = num_min =
      N"). Order infinite; centre = the circle's centre.
   b. Otherwise **split-and-merge** lines and their corners. A corner that is not seen
      (occlusion by furniture, a re-entrant room) or clutter off every wall -> ``asymmetric``.
   c. **Rotational symmetry** of the n corners about the chosen centroid: the largest
      k dividing n for which the rotation by 2 pi / k maps every corner onto the corner n/k
      places further (the paper's "equal G-V distances", "equal adjacent vertex distances",
      generalised). k == n is a regular n-gon; k == 2 with four right angles a rectangle.
      Tolerances are propagated from the range noise through the line fits to the corners.
      The centre is then refined to the mean of the corners (exact for a symmetric corner
      set), which is what a robot should drive to.

4. Open contour: two parallel walls on either side with both ends unseen is a **hallway**;
   a narrow opening in a straight wall is a door (``asymmetric``); walls beyond range or a
   partial field of view -> ``unknown``.

The centroid method matters in step 3: the paper's mean of points (``centroid="mean"``) is
pulled toward the near walls, so the equal-distance test fails for a robot away from the
centre; the area centroid of the scan polygon (default) is the room's centroid.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.features.centroid import CENTROID_METHODS, area_centroid, mean_centroid
from symloc.features.corners import adjacent_corners
from symloc.features.split_and_merge import (
    LineSet,
    _rolled,
    contour_gaps,
    contour_runs,
    split_and_merge,
)
from symloc.scan import LaserScan
from symloc.symmetry.config import SymmetryConfig
from symloc.symmetry.order import SymmetryOrder
from symloc.symmetry.report import SymmetryReport

__all__ = ["fit_circle", "judge_symmetry", "rotational_order"]

FloatArray = NDArray[np.float64]

_NAN2 = np.full(2, np.nan)
#: Hallway walls must be parallel to better than this [rad], whatever their fit uncertainty.
_MAX_HALLWAY_ANGLE = math.radians(3.0)
_NO_CORNERS = np.zeros((0, 2))


def fit_circle(points: FloatArray, *, refine: int = 2) -> tuple[FloatArray, float]:
    """Least-squares circle through points: algebraic (Kasa) fit, then Gauss-Newton steps.

    Parameters
    ----------
    points : ndarray of shape (M, 2), M >= 3
        [m].
    refine : int
        Gauss-Newton steps on the geometric distances (removes the algebraic fit's small bias).

    Returns
    -------
    center : ndarray of shape (2,)
        [m] (NaN if the points are collinear).
    radius : float
        [m] (NaN if the points are collinear).
    """
    x, y = points[:, 0], points[:, 1]
    n = float(points.shape[0])
    add = np.add.reduce
    xx, yy = x * x, y * y
    sx, sy = add(x), add(y)
    sxx, syy, sxy = add(xx), add(yy), add(x * y)
    z = xx + yy
    ata = np.array([[sxx, sxy, sx], [sxy, syy, sy], [sx, sy, n]])
    atb = np.array([add(x * z), add(y * z), add(z)])
    try:
        sol = np.linalg.solve(ata, atb)
    except np.linalg.LinAlgError:
        return np.full(2, np.nan), math.nan
    c = 0.5 * sol[:2]
    r2 = sol[2] + c @ c
    if not np.isfinite(r2) or r2 <= 0:
        return np.full(2, np.nan), math.nan
    r = math.sqrt(r2)
    for _ in range(refine):
        d = points - c
        dist = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)
        jac = np.column_stack([-d[:, 0] / dist, -d[:, 1] / dist, -np.ones_like(dist)])
        try:
            step = np.linalg.solve(jac.T @ jac, -(jac.T @ (dist - r)))
        except np.linalg.LinAlgError:
            break
        c = c + step[:2]
        r = r + float(step[2])
    return c, float(r)


def rotational_order(
    corners: FloatArray, center: FloatArray, tolerance: FloatArray
) -> tuple[int, FloatArray]:
    """Largest k for which rotating the corners by 2 pi / k about ``center`` maps corner i onto
    corner i + n/k (corners in counter-clockwise order).

    Parameters
    ----------
    corners : ndarray of shape (n, 2)
        [m], counter-clockwise.
    center : ndarray of shape (2,)
        [m].
    tolerance : ndarray of shape (n, n)
        ``tolerance[k - 1, i]`` [m] is the allowed displacement of corner i for order k
        (only divisors of n are read).

    Returns
    -------
    order : int
        k >= 1 (1 when no rotation but the identity fits).
    displacement : ndarray of shape (n,)
        Corner displacements [m] for the returned order when k > 1, else for the best k > 1
        tried (the smallest largest-excess), or zeros when n < 2.
    """
    n = corners.shape[0]
    rel = corners - center
    best: tuple[float, FloatArray] | None = None
    for k in range(n, 1, -1):
        if n % k:
            continue
        m = n // k
        ang = 2.0 * math.pi / k
        cs, sn = math.cos(ang), math.sin(ang)
        nxt = rel[(np.arange(n) + m) % n]
        disp = np.hypot(
            cs * rel[:, 0] - sn * rel[:, 1] - nxt[:, 0], sn * rel[:, 0] + cs * rel[:, 1] - nxt[:, 1]
        )
        excess = float(np.maximum.reduce(disp / tolerance[k - 1]))
        if excess <= 1.0:
            return k, disp
        if best is None or excess < best[0]:
            best = (excess, disp)
    return 1, (best[1] if best is not None else np.zeros(n))


def _report(kind: str, reason: str, **kw: object) -> SymmetryReport:
    base: dict[str, object] = {
        "symmetric": False,
        "order": None if kind == "unknown" else SymmetryOrder.finite(1),
        "regular": False,
        "center": _NAN2,
        "corners": _NO_CORNERS,
        "gv_distance": math.nan,
        "residual": math.nan,
    }
    base.update(kw)
    return SymmetryReport(kind=kind, reason=reason, **base)  # type: ignore[arg-type]


def _bearing_deg(p: FloatArray) -> float:
    return math.degrees(math.atan2(float(p[1]), float(p[0])))


def judge_symmetry(
    scan: LaserScan,
    *,
    config: SymmetryConfig | None = None,
    centroid: str = "area",
) -> SymmetryReport:
    """Judge whether the room around the robot is symmetric, from one laser scan.

    Parameters
    ----------
    scan : LaserScan
        One scan in the sensor frame; a full 360-degree scan is needed for a closed room.
    config : SymmetryConfig, optional
        Tolerances, derived from the range noise (default: a 1 cm scanner).
    centroid : {"area", "mean"}
        Centroid the equal-distance tests use: the area centroid of the scan polygon
        (default) or the paper's mean of points (eq. 3-4).

    Returns
    -------
    SymmetryReport
        Never raises on bad scan content: empty, all-invalid or too-small scans give
        ``kind == "unknown"`` with the reason.

    Raises
    ------
    ConfigurationError
        For an unknown centroid method, or a ``scan`` that is not a LaserScan.
    """
    cfg = SymmetryConfig() if config is None else config
    if not isinstance(cfg, SymmetryConfig):
        raise ConfigurationError(f"config: expected a SymmetryConfig, got {type(cfg).__name__}")
    if centroid not in CENTROID_METHODS:
        raise ConfigurationError(f"centroid: expected one of {CENTROID_METHODS}, got {centroid!r}")
    if not isinstance(scan, LaserScan):
        raise ConfigurationError(f"scan: expected a LaserScan, got {type(scan).__name__}")

    sp = scan.to_points()
    pts = sp.points
    m = pts.shape[0]
    n_beams = len(scan)
    common: dict[str, object] = {"centroid_method": centroid, "n_points": m}
    if m < cfg.min_points:
        return _report(
            "unknown",
            f"too few points: {m} valid of {n_beams} beams ({sp.n_invalid} invalid,"
            f" {sp.n_no_return} no return); need at least min_points={cfg.min_points}",
            **common,
        )
    full_circle = scan.angle_increment * n_beams >= 2.0 * math.pi - 1.5 * scan.angle_increment
    sig, tol = cfg.sigma_and_tolerance(sp.ranges)
    no_return = scan.no_return_mask
    gaps = contour_gaps(
        sp.indices,
        n_beams,
        max_dropout_beams=cfg.max_dropout_beams,
        no_return=no_return,
        max_blind_beams=cfg.max_blind_beams,
    )
    partial = not full_circle and cfg.partial_view
    closed = full_circle and not gaps.any()
    try:
        if closed:
            return _judge_closed(pts, tol, sig, cfg, centroid, common)
        runs = contour_runs(
            sp.indices,
            n_beams,
            wrap=not partial,
            max_dropout_beams=cfg.max_dropout_beams,
            no_return=no_return,
            max_blind_beams=cfg.max_blind_beams,
        )
        return _judge_open(
            scan, sp.indices, pts, tol, sig, runs, full_circle or partial, cfg, common
        )
    except (IndexError, ValueError, FloatingPointError, np.linalg.LinAlgError) as err:
        # a safety net: a scan this code did not foresee must not stop the robot
        return _report(
            "unknown",
            f"the judgement failed on this scan ({type(err).__name__}: {err}); please report it",
            **common,
        )


def _centroid_of(pts: FloatArray, method: str) -> FloatArray:
    return area_centroid(pts)[0] if method == "area" else mean_centroid(pts)


def _judge_closed(
    pts: FloatArray,
    tol: FloatArray,
    sig: FloatArray,
    cfg: SymmetryConfig,
    method: str,
    common: dict[str, object],
) -> SymmetryReport:
    m = pts.shape[0]
    cen = _centroid_of(pts, method)
    # standard deviation of the centroid from the point noise (random part only)
    sigma_c = 2.0 * math.sqrt(float(np.add.reduce(sig * sig) / m) / m)
    k = cfg.k_sigma
    common = {**common, "centroid": cen}

    # --- circle: every point on one circle, and equally far from the centroid ---
    c_fit, radius = fit_circle(pts, refine=0)
    maybe_circle = bool(np.isfinite(radius))
    if maybe_circle:
        # a polygon misses the circle by far: when every 8th point already misses it by more
        # than the refinement bound, the full test below fails too (the same values on a
        # subset; the margin keeps the two decisions equal whatever the last bit)
        d_sub = np.hypot(*(pts[::8] - c_fit).T) - radius
        maybe_circle = not float(np.maximum.reduce(np.abs(d_sub) / tol[::8])) > 3.0 + 1e-9
    if maybe_circle:
        d_fit = np.hypot(*(pts - c_fit).T) - radius
        # the algebraic fit is close to the geometric one for a circle; only refine candidates
        if float(np.maximum.reduce(np.abs(d_fit) / tol)) <= 3.0:
            c_fit, radius = fit_circle(pts, refine=2)
            d_fit = np.hypot(*(pts - c_fit).T) - radius
        if np.isfinite(radius) and float(np.maximum.reduce(np.abs(d_fit) / tol)) <= 1.0:
            r_c = np.hypot(*(pts - cen).T)
            spread = np.abs(r_c - float(np.mean(r_c)))
            tol_c = tol + 2.0 * k * sigma_c + cfg.model_tolerance
            worst = int(np.argmax(spread / tol_c))
            if spread[worst] > tol_c[worst]:
                return _report(
                    "asymmetric",
                    f"the points lie on a circle of radius {radius:.3f} m, but their distances"
                    f" from the {method} centroid are not equal: one differs by"
                    f" {spread[worst]:.3f} m > tolerance {tol_c[worst]:.3f} m (the centroid is"
                    f" {np.hypot(*(cen - c_fit)):.3f} m from the circle's centre)",
                    residual=float(np.max(np.abs(d_fit))),
                    tolerance=float(tol_c[worst]),
                    **common,
                )
            return SymmetryReport(
                kind="circle",
                symmetric=True,
                order=SymmetryOrder.CIRCLE,
                regular=True,
                center=c_fit,
                corners=_NO_CORNERS,
                gv_distance=radius,
                residual=float(np.max(np.abs(d_fit))),
                reason=f"round room: {m} points within tolerance of a circle of radius"
                f" {radius:.3f} m and equally far from the {method} centroid",
                tolerance=float(np.max(tol)),
                **common,  # type: ignore[arg-type]
            )

    # --- polygon: lines, corners ---
    lines = split_and_merge(pts, tol, closed=True, min_points=cfg.min_line_points)
    n_lines = len(lines)
    common = {**common, "n_lines": n_lines}
    short = lines.n_points < cfg.min_line_points
    n_clutter = int(lines.n_points[short].sum())
    if n_clutter > cfg.max_clutter_points:
        worst = int(np.flatnonzero(short)[0])
        return _report(
            "asymmetric",
            f"{n_clutter} points lie on {int(short.sum())} pieces shorter than"
            f" min_line_points={cfg.min_line_points} (clutter off every wall, first at bearing"
            f" {_bearing_deg(lines.centers[worst]):.1f} deg)",
            **common,
        )
    if n_lines < 3:
        return _report(
            "unknown",
            f"a closed contour that is neither a circle nor a polygon ({n_lines} lines)",
            **common,
        )
    if n_lines > cfg.max_polygon_sides:
        return _report(
            "asymmetric",
            f"{n_lines} walls, more than max_polygon_sides={cfg.max_polygon_sides}, and not a"
            " circle",
            **common,
        )
    rolled_sig: FloatArray = _rolled(sig, lines.roll)
    owner = np.arange(n_lines).repeat(lines.stops - lines.starts)
    n_l = lines.n_points.astype(np.float64)
    sig_l = np.sqrt(np.bincount(owner, rolled_sig * rolled_sig, minlength=n_lines) / n_l)
    sig_off = sig_l / np.sqrt(n_l)
    sig_ang = sig_l / (np.sqrt(n_l) * np.maximum(lines.spread, 1e-6))
    rolled_tol = _rolled(tol, lines.roll)
    end_tol = np.maximum(
        rolled_tol[lines.stops - 1], rolled_tol[lines.starts[(np.arange(n_lines) + 1) % n_lines]]
    )
    corners = adjacent_corners(lines, tolerance=end_tol)
    if not corners.seen.all():
        bad = int(np.flatnonzero(~corners.seen)[0])
        a, b = (int(v) for v in corners.pairs[bad])
        return _report(
            "asymmetric",
            f"the walls do not close: line {a} ends and line {b} starts"
            f" {corners.gap[bad]:.2f} m apart at bearing"
            f" {_bearing_deg(lines.endpoints[a, 1]):.1f} deg without meeting there (an occlusion:"
            " furniture or a re-entrant corner)",
            **common,
        )
    v = corners.points
    n = v.shape[0]
    # corner standard deviation from the two line fits
    a_idx, b_idx = corners.pairs[:, 0], corners.pairs[:, 1]
    va = (v - lines.centers[a_idx]) * lines.directions[a_idx]
    vb = (v - lines.centers[b_idx]) * lines.directions[b_idx]
    t_a = va[:, 0] + va[:, 1]
    t_b = vb[:, 0] + vb[:, 1]
    s_a = np.hypot(sig_off[a_idx], t_a * sig_ang[a_idx])
    s_b = np.hypot(sig_off[b_idx], t_b * sig_ang[b_idx])
    sig_v = np.hypot(s_a, s_b) / np.maximum(np.abs(np.sin(corners.turn)), 1e-3)
    tol_k = np.full((n, n), np.inf)
    for kk in range(2, n + 1):
        if n % kk == 0:
            mm = n // kk
            chord = 2.0 * math.sin(math.pi / kk)
            tol_k[kk - 1] = (
                k * np.sqrt(sig_v**2 + sig_v[(np.arange(n) + mm) % n] ** 2 + (chord * sigma_c) ** 2)
                + cfg.model_tolerance
            )
    order, disp = rotational_order(v, cen, tol_k)
    common = {**common, "corners": v}
    if order == 1:
        refined = v.mean(axis=0)
        order_ref, _ = rotational_order(v, refined, tol_k)
        hint = ""
        if order_ref > 1:
            hint = (
                f"; about the mean of the corners it would be order {order_ref}: the {method}"
                f" centroid is {np.hypot(*(cen - refined)):.3f} m off the centre"
            )
        return _report(
            "asymmetric",
            f"{n} corners, but no rotation about the {method} centroid maps them onto each"
            f" other (largest corner displacement {float(np.max(disp)):.3f} m for the best"
            f" order tried){hint}",
            residual=float(np.max(disp)) if disp.size else math.nan,
            **common,
        )
    center = v.mean(axis=0)
    _o, disp_ref = rotational_order(v, center, tol_k)
    dist = np.hypot(*(v - center).T)
    regular = order == n
    turns = corners.turn
    ang_tol = np.maximum(k * np.hypot(sig_ang[a_idx], sig_ang[b_idx]), cfg.min_angle_tolerance)
    right = bool(np.all(np.abs(np.abs(turns) - math.pi / 2) <= ang_tol))
    kind = "polygon"
    if regular:
        what = {3: "equilateral triangle", 4: "square"}.get(n, f"regular {n}-gon")
    elif n == 4 and order == 2 and right:
        kind = "rectangle"
        what = "rectangle"
    else:
        what = f"{n}-sided polygon with {order}-fold rotational symmetry"
    axis = math.atan2(float(lines.directions[0, 1]), float(lines.directions[0, 0]))
    return SymmetryReport(
        kind=kind,
        symmetric=True,
        order=SymmetryOrder.finite(order),
        regular=regular,
        center=center,
        gv_distance=float(np.mean(dist)) if regular or kind == "rectangle" else float(dist.max()),
        residual=float(np.maximum.reduce(disp_ref)),
        reason=f"{what}: rotating the {n} corners by 360/{order} deg about the {method}"
        f" centroid maps them onto each other within tolerance",
        tolerance=float(np.maximum.reduce(tol_k[order - 1])),
        axis_angle=axis if kind == "rectangle" else math.nan,
        **common,  # type: ignore[arg-type]
    )


def _judge_open(
    scan: LaserScan,
    indices: NDArray[np.intp],
    pts: FloatArray,
    tol: FloatArray,
    sig: FloatArray,
    runs: NDArray[np.intp],
    full_circle: bool,
    cfg: SymmetryConfig,
    common: dict[str, object],
) -> SymmetryReport:
    m = pts.shape[0]
    n_beams = len(scan)
    fov = math.degrees(scan.angle_increment * n_beams)
    partial = fov < 360.0 - 1.5 * math.degrees(scan.angle_increment)
    if not full_circle:
        return _report(
            "unknown",
            f"field of view {fov:.0f} deg < 360 deg: the room cannot be seen closed"
            " (SymmetryConfig.partial_view=True tests it for a hallway)",
            **common,
        )
    # fit lines per run
    all_lines: list[tuple[LineSet, NDArray[np.intp]]] = []
    run_lines: dict[int, LineSet] = {}
    for r, (start, stop) in enumerate(runs):
        idx = np.arange(int(start), int(stop)) % m
        if idx.size >= 2:
            run_lines[r] = split_and_merge(pts[idx], tol[idx], closed=False)
            all_lines.append((run_lines[r], idx))
    normals = np.concatenate([ls.normals for ls, _ in all_lines]) if all_lines else np.zeros((0, 2))
    offsets = np.concatenate([ls.offsets for ls, _ in all_lines]) if all_lines else np.zeros(0)
    npts = np.concatenate([ls.n_points for ls, _ in all_lines]) if all_lines else np.zeros(0, int)
    spread = np.concatenate([ls.spread for ls, _ in all_lines]) if all_lines else np.zeros(0)
    sig_mean = float(np.sqrt(np.mean(sig * sig)))
    common = {**common, "n_lines": int(npts.size)}
    n_missing = n_beams - m
    # --- hallway: two walls, parallel, on either side, both ends unseen ---
    big = np.flatnonzero(npts >= cfg.min_line_points)
    clutter = int(npts[npts < cfg.min_line_points].sum())
    if big.size == 2 and clutter <= cfg.max_clutter_points and runs.shape[0] == 2:
        i, j = big
        na, nb = normals[i], normals[j]
        oa, ob = offsets[i], offsets[j]
        if float(na @ nb) < 0:
            nb, ob = -nb, -ob
        cos_ = float(np.clip(abs(na @ nb), -1.0, 1.0))
        ang = math.acos(cos_)
        sa = sig_mean / (math.sqrt(npts[i]) * max(spread[i], 1e-6))
        sb = sig_mean / (math.sqrt(npts[j]) * max(spread[j], 1e-6))
        # a wall too short to give its direction to a few degrees is no hallway wall
        ang_tol = max(cfg.k_sigma * math.hypot(sa, sb), cfg.min_angle_tolerance)
        width = abs(oa - ob)
        long_walls = min(spread[i], spread[j]) * math.sqrt(12.0) >= width
        if ang <= min(ang_tol, _MAX_HALLWAY_ANGLE) and oa * ob < 0 and long_walls:
            nrm = na + nb
            nrm /= np.linalg.norm(nrm)
            mid = 0.5 * (oa + ob)
            center = nrm * mid  # foot of the perpendicular from the sensor on the mid-line
            width = abs(oa - ob)
            axis = math.atan2(float(nrm[0]), float(-nrm[1]))
            caveat = (
                f"; partial view of {fov:.0f} deg: the part outside the field of view was not"
                " seen and is assumed to continue the hallway"
                if partial
                else ""
            )
            return SymmetryReport(
                kind="hallway",
                symmetric=True,
                order=SymmetryOrder.finite(2),
                regular=False,
                center=center,
                corners=_NO_CORNERS,
                gv_distance=math.nan,
                residual=float(np.max(np.minimum(np.abs(pts @ na - oa), np.abs(pts @ nb - ob)))),
                reason=f"hallway {width:.2f} m wide: two parallel walls"
                f" ({math.degrees(ang):.2f} deg apart), both ends unseen ({n_missing} beams"
                " without a point); order 2 about a centre on the mid-line whose position"
                " along the hallway is undetermined (reported: the mid-line point nearest the"
                f" sensor){caveat}",
                tolerance=ang_tol,
                axis_angle=axis,
                **common,  # type: ignore[arg-type]
            )
    # --- a narrow opening in a straight wall: a door ---
    # (the middle of a straight wall is nearer than its ends, so a gap between two collinear
    # pieces of wall is never the sensor's range limit)
    dropouts: list[float] = []
    # (with a partial view, the last run and the first are not neighbours)
    for r in range(runs.shape[0] - 1 if partial else runs.shape[0]):
        r2 = (r + 1) % runs.shape[0]
        if r not in run_lines or r2 not in run_lines:
            continue
        end = int(runs[r, 1] - 1) % m
        nxt = int(runs[r2, 0]) % m
        width = float(np.hypot(*(pts[nxt] - pts[end])))
        la, lb = run_lines[r], run_lines[r2]
        on_a = abs(float(pts[nxt] @ la.normals[-1] - la.offsets[-1])) <= tol[nxt]
        on_b = abs(float(pts[end] @ lb.normals[0] - lb.offsets[0])) <= tol[end]
        # a gap whose edges are at the sensor's range limit is the range limit, not a door
        r_end = float(np.hypot(*pts[end]))
        r_nxt = float(np.hypot(*pts[nxt]))
        at_limit = max(r_end, r_nxt) >= scan.range_max - float(cfg.point_tolerance(scan.range_max))
        if width < cfg.min_door_width and on_a and on_b and not at_limit:
            dropouts.append(width)
            continue
        if width <= cfg.max_door_width and on_a and on_b and not at_limit:
            gap_beams = int((indices[nxt] - indices[end]) % n_beams) - 1
            return _report(
                "asymmetric",
                f"an opening {width:.2f} m wide ({gap_beams} beams without a point) in a"
                f" straight wall at bearing {_bearing_deg(0.5 * (pts[nxt] + pts[end])):.1f} deg:"
                " an open door or a gap in a wall breaks the symmetry",
                **common,
            )
    no_ret = int(np.count_nonzero(scan.no_return_mask))
    drop = (
        f"; {len(dropouts)} gap(s) in straight walls narrower than min_door_width="
        f"{cfg.min_door_width:g} m (widest {max(dropouts):.2f} m) are sensor dropouts, not doors"
        if dropouts
        else ""
    )
    if partial:
        return _report(
            "unknown",
            f"partial view of {fov:.0f} deg in {runs.shape[0]} runs of wall and {int(npts.size)}"
            " lines: not a hallway (two long parallel walls on either side), and nothing else"
            f" can be judged without seeing the whole room{drop}",
            **common,
        )
    return _report(
        "unknown",
        f"the contour is open in {runs.shape[0]} places ({no_ret} beams with no return within"
        f" {scan.range_max:g} m, {n_missing - no_ret} invalid): walls beyond the sensor's range"
        f" or a long dropout, so the room cannot be judged{drop}",
        **common,
    )
