"""The compiled split of split-and-merge against the NumPy split it replaced.

``_split_numpy`` is ``symloc.features.split_and_merge._split`` as it was before the kernel
(main bad82ae), kept verbatim as the reference: the cuts must be the same integers on seeded
scans of many rooms and scanners, on noisy random polylines and on degenerate inputs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.features.split_and_merge import _Moments, _normals_offsets
from symloc.features.split_kernels import split_cuts, split_cuts_py
from symloc.sim.lidar import LDS01, PAPER_15M, RPLIDAR_A2, simulate_scan
from symloc.sim.rooms import build_room
from symloc.symmetry import SymmetryConfig


def _split_numpy(p: np.ndarray, tol: np.ndarray, first_cut: int | None, mom: _Moments) -> list[int]:
    """Split at the farthest point from the chord, recursively; returns sorted cut indices.

    A segment is kept whole when its TLS line holds every interior point within tolerance;
    otherwise it is cut at the interior point farthest from its chord. (Testing the chord
    itself, as the textbook does, over-splits: a chord between two noisy end points is tilted
    by their noise.) All segments of one recursion level are processed together.
    """
    m = p.shape[0]
    cuts = [0, m - 1]
    if first_cut is not None and 0 < first_cut < m - 1:
        cuts.append(first_cut)
        seg_i = np.array([0, first_cut], dtype=np.intp)
        seg_j = np.array([first_cut, m - 1], dtype=np.intp)
    else:
        seg_i = np.array([0], dtype=np.intp)
        seg_j = np.array([m - 1], dtype=np.intp)
    cs = mom.cs
    # contiguous coordinate columns: gathering from them is much cheaper than from rows of p
    px = np.ascontiguousarray(p[:, 0])
    py = np.ascontiguousarray(p[:, 1])
    new_cuts = []
    while seg_i.size:
        keep = seg_j - seg_i >= 2
        if not keep.all():
            seg_i, seg_j = seg_i[keep], seg_j[keep]
            if seg_i.size == 0:
                break
        n_in = seg_j - seg_i - 1
        ends = n_in.cumsum()
        first = ends - n_in
        idx = np.arange(int(ends[-1])) - (first - seg_i - 1).repeat(n_in)
        xi = px[idx]
        yi = py[idx]
        ti = tol[idx]
        # the segment's own line decides whether it is one wall (interior points: the moment
        # sums of [seg_i + 1, seg_j) never wrap)
        nx, ny, off = _normals_offsets(cs[:, seg_j] - cs[:, seg_i + 1])
        res = np.abs(xi * nx.repeat(n_in) + yi * ny.repeat(n_in) - off.repeat(n_in)) / ti
        bent = np.maximum.reduceat(res, first) > 1.0
        if not bent.all():
            if not bent.any():
                break
            # only the bent segments are cut: keep their points
            sel = bent.repeat(n_in)
            idx, xi, yi, ti = idx[sel], xi[sel], yi[sel], ti[sel]
            seg_i, seg_j, n_in = seg_i[bent], seg_j[bent], n_in[bent]
            ends = n_in.cumsum()
            first = ends - n_in
        # cut at the interior point farthest from the chord
        ax, ay = px[seg_i], py[seg_i]
        dx, dy = px[seg_j] - ax, py[seg_j] - ay
        length = np.hypot(dx, dy)
        qx = xi - ax.repeat(n_in)
        qy = yi - ay.repeat(n_in)
        cross = np.abs(dx.repeat(n_in) * qy - dy.repeat(n_in) * qx)
        safe = length > 1e-12
        if safe.all():
            dist = cross / length.repeat(n_in)
        else:
            dist = np.where(
                safe.repeat(n_in),
                cross / np.where(safe, length, 1.0).repeat(n_in),
                np.hypot(qx, qy),
            )
        ratio = dist / ti
        best = np.maximum.reduceat(ratio, first)
        split = best > 1.0
        if not split.any():
            break
        # first index of each segment's maximum
        cand = np.where(ratio == best.repeat(n_in), np.arange(idx.size), idx.size)
        arg = np.minimum.reduceat(cand, first)
        k = idx[arg[split]]
        new_cuts.append(k)
        seg_i, seg_j = (
            np.concatenate((seg_i[split], k)),
            np.concatenate((k, seg_j[split])),
        )
    if new_cuts:
        cuts.extend(np.concatenate(new_cuts).tolist())
    return sorted(cuts)


def _cuts(p: np.ndarray, tol: np.ndarray, first_cut: int | None, *, py: bool = False) -> list[int]:
    mom = _Moments(p)
    fn = split_cuts_py if py else split_cuts
    out = fn(
        mom.px, mom.py, np.ascontiguousarray(tol), mom.cs, -1 if first_cut is None else first_cut
    )
    assert out.dtype == np.int64
    return [int(v) for v in out]


def _first_cut(p: np.ndarray) -> int:
    d0 = p - p[0]
    return int((d0[:, 0] ** 2 + d0[:, 1] ** 2).argmax())


@pytest.mark.parametrize("room_name", ["hexagon", "square", "circle", "l_shaped", "triangle"])
def test_cuts_on_seeded_scans_equal_the_numpy_split(room_name: str) -> None:
    n_scans = 0
    for r_i, preset in enumerate((PAPER_15M, RPLIDAR_A2, LDS01)):
        gv = 2.0 if preset is LDS01 else 5.0
        room = build_room(room_name, gv, lab=False, furniture=r_i, rng=r_i)
        rng = np.random.default_rng(r_i)
        cfg = SymmetryConfig.from_lidar(preset)
        for pos in room.positions_inside(6):
            pose = np.r_[pos, rng.uniform(-math.pi, math.pi)]
            sp = simulate_scan(room.world, pose, preset, rng).to_points()
            p = sp.points
            if p.shape[0] < 4:
                continue
            tol = np.asarray(cfg.point_tolerance(sp.ranges), dtype=np.float64)
            fc = _first_cut(p)
            for first in (fc, None):
                assert _cuts(p, tol, first) == _split_numpy(p, tol, first, _Moments(p))
            n_scans += 1
    assert n_scans >= 10


def test_cuts_on_random_polylines_equal_the_numpy_split() -> None:
    rng = np.random.default_rng(11)
    for _ in range(200):
        n_v = int(rng.integers(2, 9))
        verts = rng.uniform(-5.0, 5.0, (n_v, 2))
        per = rng.integers(1, 40, n_v - 1)
        p = np.concatenate(
            [
                verts[i]
                + np.linspace(0, 1, int(per[i]), endpoint=False)[:, None]
                * (verts[i + 1] - verts[i])
                for i in range(n_v - 1)
            ]
            + [verts[-1:]]
        )
        p = p + rng.normal(0.0, rng.choice([0.0, 1e-3, 0.02]), p.shape)
        tol = rng.uniform(0.005, 0.05, size=(p.shape[0],))
        if p.shape[0] < 2:
            continue
        first = int(rng.integers(-1, p.shape[0]))
        want = _split_numpy(p, tol, first if first >= 0 else None, _Moments(p))
        assert _cuts(p, tol, first if first >= 0 else None) == want
        assert _cuts(p, tol, first if first >= 0 else None, py=True) == want


def test_degenerate_inputs() -> None:
    two = np.array([[0.0, 0.0], [1.0, 0.0]])
    assert _cuts(two, np.full(2, 0.01), None) == [0, 1]
    same = np.zeros((5, 2))  # a zero-length chord: distances from the end point
    assert _cuts(same, np.full(5, 0.01), None) == _split_numpy(
        same, np.full(5, 0.01), None, _Moments(same)
    )
    corner = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [2.0, 2.0]])
    assert _cuts(corner, np.full(5, 0.01), None) == [0, 2, 4]
