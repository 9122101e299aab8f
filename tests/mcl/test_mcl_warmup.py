"""The warm-up compiles every kernel of the per-scan path, for the types the path uses."""

from __future__ import annotations

import numba
import numpy as np
from mcl_fixtures import asymmetric_room, synthetic_scan

from symloc.features import split_kernels
from symloc.geometry import compose
from symloc.grid.fields import MapFields
from symloc.mcl import Amcl, AmclParams, ConfidenceJudge, aot, global_search, kernels
from symloc.mcl.warmup import warm_up
from symloc.odometry import OdometryReading
from symloc.symmetry import judge_symmetry


def _signatures() -> dict[str, int]:
    """Signatures ready to run of every kernel of the filter and the global search: numba's
    compiled ones, and the ahead-of-time build's (symloc.mcl.aot) when there is one."""
    out = {}
    for mod in (kernels, global_search, split_kernels):
        for name, obj in vars(mod).items():
            if isinstance(obj, (numba.core.registry.CPUDispatcher, aot.Kernel)):
                out[f"{mod.__name__}.{name}"] = len(obj.signatures)
    return out


def test_after_the_warm_up_a_first_scan_compiles_nothing() -> None:
    params = AmclParams(laser_model_type="likelihood_field_prob", max_particles=2000)
    spent = warm_up(params)
    assert spent > 0.0
    warmed = _signatures()
    assert warmed["symloc.mcl.kernels.endpoint_table_sum"] >= 1
    assert warmed["symloc.mcl.kernels.count_within"] >= 1
    assert warmed["symloc.mcl.kernels.move_diff"] >= 1
    assert warmed["symloc.features.split_kernels.segment"] >= 1
    # a node's first scans on another map, with thousands of particles (several threads)
    grid = asymmetric_room()
    amcl = Amcl(grid, params, np.random.default_rng(1))
    judge = ConfidenceJudge(amcl)
    rng = np.random.default_rng(2)
    true, odom = np.array([5.0, 3.0, 0.3]), np.array([1.0, 1.0, 0.0])
    amcl.initialize_pose(true, np.diag([0.05, 0.05, 0.01]))
    for i in range(5):
        res, _ = judge.update(OdometryReading(odom), synthetic_scan(grid, true, rng))
        step = np.array([0.3, 0.0, 0.0]) if i % 2 == 0 else np.array([0.0, 0.0, 0.3])
        true, odom = compose(true, step), compose(odom, step)
    global_search.GlobalSearch(MapFields.of(grid)).search(synthetic_scan(grid, true, rng))
    judge_symmetry(synthetic_scan(grid, true, rng))
    assert res.updated
    assert _signatures() == warmed  # nothing compiled anew
