"""The laser SLAM pipeline: local scan-to-submap matching, loop closures, GTSAM back end.

For every scan (Hess et al. 2016 structure, with Olson's correlative matcher):

1. **Predict** its local pose from the previous one and the odometry increment.
2. **Match** it against the oldest active submap (:func:`match_scan`, real-time window) and
   insert it into the active submaps (:class:`ActiveSubmaps`).
3. **Graph**: add the node, its intra-submap constraints and the odometry constraint.
4. **Loop closure** (every ``loop_every`` nodes): match the scan against the
   ``loop_max_candidates`` nearest finished older submaps whose predicted distance is below
   ``loop_search_distance`` with a wide window;
   a score >= ``loop_min_score`` adds a robust loop constraint. Loop constraints are sampled
   along the trajectory, as Cartographer samples them (its ``sampling_ratio``) but by
   distance: a submap is searched again only after the robot travelled
   ``loop_resample_distance`` since its last search, and ``loop_constrained_distance`` after
   a search that found a loop (the submap is then well constrained to the recent nodes).
5. **Optimise** with Levenberg-Marquardt every ``optimize_every`` nodes when new loop
   constraints arrived, and once at the end.

Finally all scans are integrated at their optimised poses into one log-odds grid, returned
as an :class:`~symloc.grid.OccupancyGrid`.
"""

from __future__ import annotations

import math
import time
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from tqdm import tqdm

from symloc._checks import check_array, check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import compose, inverse, relative
from symloc.grid.log_odds import InverseSensorModel, LogOddsGrid
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.scan import LaserScan
from symloc.slam.correlative_scan_matching import CsmParams, match_scan
from symloc.slam.pose_graph import PoseGraph, PoseGraphParams
from symloc.slam.submaps import ActiveSubmaps, Submap, SubmapParams

__all__ = ["SlamParams", "SlamResult", "run_slam", "scan_points"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SlamParams:
    """Settings of the whole pipeline.

    Parameters
    ----------
    submap : SubmapParams
    local_csm : CsmParams
        Real-time matching window around the odometry prediction.
    retry_csm : CsmParams
        Wider window tried when the real-time match scores below ``retry_below`` (odometry
        errors beyond the real-time window); the better of the two matches is kept.
    retry_below : float
        Score (0..1) under which the wider search runs.
    retry_margin : float
        The wide match replaces the real-time one only if it scores this much higher (a
        corridor gives many similar scores far from the odometry; a real odometry error gives
        a clearly better one).
    loop_csm : CsmParams
        Loop-closure window around the predicted pose in an older submap.
    graph : PoseGraphParams
    max_range : float
        Points farther than this [m] are not used for matching.
    voxel : float
        Points are thinned to one per ``voxel`` x ``voxel`` square [m] for matching (0: off).
    motion_filter_distance, motion_filter_angle : float
        A scan becomes a graph node (inserted into the submaps, searched for loop closures)
        only if the robot moved at least this far [m] or turned this much [rad] since the last
        node (Cartographer's motion filter); the final pose of another scan follows its last
        node. 0 and 0 make every scan a node.
    match_filtered_scans : bool
        Also scan-match the scans the motion filter drops (their pose then follows the match,
        not only the odometry); False saves their matching time.
    loop_every : int
        Search loop closures for every ``loop_every``-th node.
    loop_search_distance : float
        Largest distance [m] between a node's predicted position and the centre of a submap's
        nodes for a loop search.
    loop_min_score : float
        Minimum match score (mean likelihood, 0..1) to accept a loop closure.
    loop_skip_submaps : int
        The newest finished submaps skipped by the loop search (they are local matches).
    loop_max_candidates : int
        At most this many submaps (the nearest) are matched per searched node.
    loop_resample_distance : float
        Trajectory length [m] the robot must travel after a loop search of a submap before
        that submap is searched again (0: search it at every searched node).
    loop_constrained_distance : float
        Same after a search of the submap that found a loop closure (0: no extra wait).
    optimize_every : int
        Nodes between optimisations when new loop closures arrived.
    map_resolution : float
        Cell edge of the final map [m].
    table_cache_mb : float
        Memory budget [MiB] of the cached submap likelihood tables (least recently matched
        dropped first; a dropped table is rebuilt from the submap's occupied cells).
    """

    submap: SubmapParams = field(default_factory=SubmapParams)
    local_csm: CsmParams = field(
        default_factory=lambda: CsmParams(
            linear_window=0.6,
            angular_window=math.radians(30),
            coarse_factor=6,
            translation_weight=1.0,
            rotation_weight=1.0,
        )
    )
    retry_csm: CsmParams = field(
        default_factory=lambda: CsmParams(
            linear_window=1.5,
            angular_window=math.radians(40),
            coarse_factor=8,
            translation_weight=0.3,
            rotation_weight=0.3,
        )
    )
    retry_below: float = 0.6
    retry_margin: float = 0.1
    loop_csm: CsmParams = field(
        default_factory=lambda: CsmParams(
            linear_window=2.0, angular_window=math.radians(15), coarse_factor=8
        )
    )
    graph: PoseGraphParams = field(default_factory=PoseGraphParams)
    max_range: float = 40.0
    voxel: float = 0.05
    motion_filter_distance: float = 0.2
    motion_filter_angle: float = math.radians(10.0)
    match_filtered_scans: bool = False
    loop_every: int = 1
    loop_search_distance: float = 10.0
    loop_min_score: float = 0.6
    loop_skip_submaps: int = 1
    loop_max_candidates: int = 4
    loop_resample_distance: float = 3.0
    loop_constrained_distance: float = 6.0
    optimize_every: int = 20
    map_resolution: float = 0.05
    table_cache_mb: float = 48.0

    def __post_init__(self) -> None:
        check_positive(self.max_range, "SlamParams.max_range")
        check_positive(self.voxel, "SlamParams.voxel", allow_zero=True)
        check_positive(self.loop_search_distance, "SlamParams.loop_search_distance")
        check_positive(self.retry_margin, "SlamParams.retry_margin", allow_zero=True)
        check_positive(
            self.motion_filter_distance, "SlamParams.motion_filter_distance", allow_zero=True
        )
        check_positive(self.motion_filter_angle, "SlamParams.motion_filter_angle", allow_zero=True)
        check_positive(self.map_resolution, "SlamParams.map_resolution")
        check_positive(
            self.loop_resample_distance, "SlamParams.loop_resample_distance", allow_zero=True
        )
        check_positive(
            self.loop_constrained_distance, "SlamParams.loop_constrained_distance", allow_zero=True
        )
        if not 0.0 <= self.retry_below <= 1.0:
            raise ConfigurationError(
                f"SlamParams.retry_below: expected a value in [0, 1], got {self.retry_below}"
            )
        if not 0.0 <= self.loop_min_score <= 1.0:
            raise ConfigurationError(
                f"SlamParams.loop_min_score: expected a value in [0, 1], got {self.loop_min_score}"
            )
        check_positive(self.table_cache_mb, "SlamParams.table_cache_mb")
        for name in ("loop_every", "optimize_every", "loop_max_candidates"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ConfigurationError(f"SlamParams.{name}: expected an integer >= 1, got {v}")
        if int(self.loop_skip_submaps) != self.loop_skip_submaps or self.loop_skip_submaps < 0:
            raise ConfigurationError(
                f"SlamParams.loop_skip_submaps: expected an integer >= 0, got"
                f" {self.loop_skip_submaps}"
            )


@dataclass(frozen=True, eq=False)
class SlamResult:
    """Output of :func:`run_slam`.

    Attributes
    ----------
    poses : ndarray of shape (N, 3)
        Optimised global sensor pose of every scan.
    local_poses : ndarray of shape (N, 3)
        Front-end (scan matching only) poses.
    grid : OccupancyGrid
        Map from all scans at the optimised poses.
    loop_closures : list of (submap, scan index)
        Accepted loop constraints.
    n_submaps : int
    node_scans : ndarray of shape (K,)
        Scan index of each graph node (the scans kept by the motion filter).
    match_scores : ndarray of shape (N,)
        Local match score per scan (0 for the first).
    timings : dict of str to float
        Wall-clock seconds spent in ``frontend``, ``loop_search``, ``optimize``, ``map`` and
        ``total``; ``total_cpu`` is the process CPU time [s] (all threads), the fair measure
        on a shared machine.
    n_optimizations : int
    n_retries : int
        Scans whose real-time match was retried with the wide window.
    graph : PoseGraph or None
        The final pose graph (factors and optimised values).
    n_loop_searches : int
        Loop-closure scan matches run (node, submap pairs searched).
    rejected_loops : list of (submap, scan index, reason)
        Loop-closure candidates that matched but were not accepted, with the test they failed.
    warnings : list of str
        Why the result may be doubtful (empty when nothing was found); also written into the
        map's metadata by ``symloc map build``.
    """

    poses: FloatArray
    local_poses: FloatArray
    grid: OccupancyGrid
    loop_closures: list[tuple[int, int]]
    n_submaps: int
    node_scans: NDArray[np.intp]
    match_scores: FloatArray
    timings: dict[str, float]
    n_optimizations: int
    n_retries: int = 0
    graph: PoseGraph | None = None
    n_loop_searches: int = 0
    rejected_loops: list[tuple[int, int, str]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    @property
    def doubtful(self) -> bool:
        """True when :attr:`warnings` is not empty."""
        return bool(self.warnings)

    def summary(self) -> dict[str, object]:
        """Plain numbers (JSON-ready): sizes, loop closures, CPU time, warnings."""
        return {
            "scans": int(self.poses.shape[0]),
            "nodes": int(self.node_scans.size),
            "submaps": int(self.n_submaps),
            "loops_accepted": len(self.loop_closures),
            "loops_rejected": len(self.rejected_loops),
            "loop_searches": int(self.n_loop_searches),
            "retries": int(self.n_retries),
            "slam_cpu_s": float(self.timings.get("total_cpu", float("nan"))),
            "timings_s": {k: float(v) for k, v in self.timings.items()},
            "doubtful": self.doubtful,
            "warnings": list(self.warnings),
        }


def scan_points(scan: LaserScan, max_range: float, voxel: float) -> FloatArray:
    """End points ``(M, 2)`` [m] of ``scan`` within ``max_range``, thinned to one per voxel."""
    sp = scan.to_points()
    pts = sp.points[sp.ranges <= max_range]
    if voxel > 0 and pts.shape[0] > 1:
        keys = np.floor(pts / voxel).astype(np.int64)
        _, first = np.unique(keys[:, 0] * 2_000_003 + keys[:, 1], return_index=True)
        pts = pts[np.sort(first)]
    return pts


class _TableCache:
    """Keeps the likelihood tables of the most recently matched submaps within a byte budget."""

    def __init__(self, budget_mb: float) -> None:
        self.budget = int(budget_mb * 1024 * 1024)
        self.order: OrderedDict[int, Submap] = OrderedDict()

    def touch(self, sm: Submap) -> None:
        """``sm`` is about to be matched: newest; drop the oldest tables over the budget."""
        self.order.pop(sm.index, None)
        self.order[sm.index] = sm
        total = sum(s.nbytes for s in self.order.values() if s.has_table)
        while total > self.budget and len(self.order) > 1:
            _, old = self.order.popitem(last=False)
            if old.has_table:
                total -= old.nbytes
                old.release_table()


def run_slam(
    scans: Sequence[LaserScan],
    odometry: ArrayLike,
    params: SlamParams | None = None,
    *,
    progress: bool = True,
    desc: str = "slam",
) -> SlamResult:
    """Run laser SLAM over ``scans`` with odometry poses ``odometry`` (N, 3).

    Parameters
    ----------
    scans : sequence of LaserScan
        In time order; the sensor frame is the robot frame.
    odometry : array of shape (N, 3)
        Odometry pose at each scan (only increments are used; the first one fixes the map
        frame).
    params : SlamParams, optional
    progress : bool
        Show a tqdm bar on stderr.

    Returns
    -------
    SlamResult
    """
    prm = params if params is not None else SlamParams()
    odom = check_array(odometry, "odometry", shape=(None, 3))
    n = len(scans)
    if n == 0 or odom.shape[0] != n:
        raise ConfigurationError(f"odometry: expected one pose per scan ({n}), got {odom.shape[0]}")
    t_start = time.perf_counter()
    cpu_start = time.process_time()
    timings = {"frontend": 0.0, "loop_search": 0.0, "optimize": 0.0, "map": 0.0}
    active = ActiveSubmaps(prm.submap)
    graph = PoseGraph(prm.graph)
    cache = _TableCache(prm.table_cache_mb)
    local = np.zeros((n, 3))
    scores = np.zeros(n)
    global_from_local = np.zeros(3)
    pending_loops = 0
    n_opt = 0
    n_retries = 0
    n_loop_searches = 0
    submap_centres: dict[int, FloatArray] = {}
    node_scans: list[int] = []
    travel = 0.0  # trajectory length [m] of the nodes (front-end poses)
    next_search: dict[int, float] = {}  # submap -> travel from which it is searched again

    bar = tqdm(total=n, desc=desc, unit="scan", disable=not progress, leave=False)
    for i in range(n):
        t0 = time.perf_counter()
        pts = scan_points(scans[i], prm.max_range, prm.voxel)

        def _is_node(pose: FloatArray, i: int = i) -> bool:
            if not node_scans or i == n - 1:
                return True
            moved = relative(local[node_scans[-1]], pose)
            return (
                float(np.hypot(moved[0], moved[1])) >= prm.motion_filter_distance
                or abs(float(moved[2])) >= prm.motion_filter_angle
            )

        if i == 0:
            local[0] = odom[0]
        else:
            pred = compose(local[i - 1], relative(odom[i - 1], odom[i]))
            target = active.matching_submap
            if not prm.match_filtered_scans and not _is_node(pred):
                local[i] = pred  # dropped by the motion filter: odometry since the last scan
            elif target is not None and pts.shape[0] >= 3:
                cache.touch(target)
                init = relative(target.local_pose, pred)
                table = target.table()
                res = match_scan(table, pts, init, prm.local_csm)
                if res.score < prm.retry_below:
                    wide = match_scan(table, pts, init, prm.retry_csm)
                    n_retries += 1
                    if wide.score > res.score + prm.retry_margin:
                        res = wide
                local[i] = compose(target.local_pose, res.pose)
                scores[i] = res.score
            else:
                local[i] = pred
        is_node = _is_node(local[i])
        if not is_node:
            timings["frontend"] += time.perf_counter() - t0
            bar.update(1)
            continue
        k = len(node_scans)
        node_scans.append(i)
        n_before = len(active.submaps)
        touched = active.insert(k, local[i], scans[i])
        graph.add_node(k, compose(global_from_local, local[i]))
        for sm in active.submaps[n_before:]:
            graph.add_submap(sm.index, compose(global_from_local, sm.local_pose))
        for sm in touched:
            graph.add_intra(sm.index, k, sm.node_poses[-1])
        if k > 0:
            prev = node_scans[-2]
            graph.add_odometry(k - 1, k, relative(odom[prev], odom[i]))
            travel += float(np.hypot(*(local[i, :2] - local[prev, :2])))
        timings["frontend"] += time.perf_counter() - t0

        # loop closures against older finished submaps
        t1 = time.perf_counter()
        if k % prm.loop_every == 0 and pts.shape[0] >= 10:
            finished = [s for s in active.submaps if s.finished and k not in s.nodes]
            if prm.loop_skip_submaps:
                finished = finished[: -prm.loop_skip_submaps]
            node_g = compose(global_from_local, local[i])
            candidates = []
            for sm in finished:
                if sm.index not in submap_centres:
                    submap_centres[sm.index] = np.mean(np.array(sm.node_poses)[:, :2], axis=0)
                init = relative(graph.submap_pose(sm.index), node_g)
                dist = float(np.hypot(*(init[:2] - submap_centres[sm.index])))
                if dist <= prm.loop_search_distance:
                    candidates.append((dist, sm.index, init))
            candidates.sort(key=lambda c: c[0])
            for _, j, init in candidates[: prm.loop_max_candidates]:
                if travel < next_search.get(j, -math.inf):
                    continue  # sampled: searched (or constrained) too recently
                sm = active.submaps[j]
                cache.touch(sm)
                res = match_scan(sm.table(), pts, init, prm.loop_csm)
                n_loop_searches += 1
                found = res.score >= prm.loop_min_score
                if found:
                    graph.add_loop(sm.index, k, res.pose)
                    pending_loops += 1
                wait = prm.loop_constrained_distance if found else prm.loop_resample_distance
                next_search[sm.index] = travel + wait
        timings["loop_search"] += time.perf_counter() - t1

        if pending_loops and (k + 1) % prm.optimize_every == 0:
            t2 = time.perf_counter()
            graph.optimize()
            n_opt += 1
            pending_loops = 0
            global_from_local = compose(graph.node_pose(k), inverse(local[i]))
            timings["optimize"] += time.perf_counter() - t2
        bar.update(1)
    bar.close()
    t2 = time.perf_counter()
    graph.optimize()
    n_opt += 1
    node_poses = graph.node_poses()
    nodes = np.array(node_scans, dtype=np.intp)
    # every scan follows its last node: node pose composed with the front-end motion since it
    owner = np.searchsorted(nodes, np.arange(n), side="right") - 1
    poses = compose(node_poses[owner], relative(local[nodes[owner]], local))
    timings["optimize"] += time.perf_counter() - t2

    t3 = time.perf_counter()
    model = InverseSensorModel(
        p_hit=prm.submap.model.p_hit,
        p_miss=prm.submap.model.p_miss,
        p_min=prm.submap.model.p_min,
        p_max=prm.submap.model.p_max,
        max_range=prm.max_range,
        no_return_range=prm.submap.model.no_return_range,
    )
    grid = LogOddsGrid(prm.map_resolution, model, poses[0, :2])
    for i in range(n):
        grid.integrate(poses[i], scans[i])
    occ = grid.to_occupancy_grid(crop_margin=10)
    timings["map"] = time.perf_counter() - t3
    timings["total"] = time.perf_counter() - t_start
    timings["total_cpu"] = time.process_time() - cpu_start
    return SlamResult(
        poses=poses,
        local_poses=local,
        grid=occ,
        loop_closures=[(j, int(nodes[k])) for j, k in graph.loops],
        n_submaps=len(active.submaps),
        node_scans=nodes,
        match_scores=scores,
        timings=timings,
        n_optimizations=n_opt,
        n_retries=n_retries,
        n_loop_searches=n_loop_searches,
        graph=graph,
    )
