"""The map's error place by place (:mod:`symloc.slam.pose_marginals`,
:mod:`symloc.grid.map_error_field`): the pose graph's marginals, the final refinement's priors
left out and the rigid fit removed; small where matches tie every direction, growing along a
corridor that only odometry measures; saved with the map and read by the claim gate."""

from __future__ import annotations

import math
from pathlib import Path

import gtsam
import numpy as np
import pytest

from symloc.errors import ConfigurationError, MapFileError
from symloc.grid.fields import surface_distance_field
from symloc.grid.map_error_field import MapErrorField
from symloc.grid.map_io import read_map_yaml, save_map
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.localizer.claim import ClaimConfig, ClaimGate
from symloc.slam.pose_graph import PoseGraph
from symloc.slam.pose_marginals import map_error_field

LOOSE = 1.0e3  # the front end's std along a direction a scan does not constrain


def _corridor(n: int, step: float, along: float, across: float) -> PoseGraph:
    """``n`` nodes driving along +x by ``step`` [m]; odometry std ``along`` / ``across`` [m]
    per step (heading 1 mrad), and every node matched in one submap that fixes y and the
    heading but, like a corridor's walls, not x."""
    g = PoseGraph()
    g.add_submap(0, (0.0, 0.0, 0.0))
    match = np.diag([LOOSE**2, 0.01**2, 0.002**2])
    for i in range(n):
        g.add_node(i, (i * step, 0.0, 0.0))
        g.add_intra(0, i, (i * step, 0.0, 0.0), covariance=match)
        if i:
            odom = np.diag([along**2, across**2, 0.001**2])
            g.add_odometry(i - 1, i, (step, 0.0, 0.0), covariance=odom)
    return g


def test_node_information_gives_gtsams_marginals() -> None:
    g = _corridor(6, 1.0, 0.02, 0.02)
    info, columns = g.node_information()
    cov = np.linalg.inv(info.toarray())
    marginals = gtsam.Marginals(g.graph, g.values)
    for i in (0, 3, 5):
        want = marginals.marginalCovariance(gtsam.symbol("x", i))
        c = columns[i]
        assert np.allclose(cov[c : c + 3, c : c + 3], want, rtol=1e-6, atol=1e-12)


def test_a_corridor_is_unsure_along_its_axis_and_most_at_its_ends() -> None:
    field = map_error_field(_corridor(41, 1.0, 0.02, 0.02))
    assert field is not None
    std = np.sqrt(field.covariance[:, [0, 1], [0, 1]])  # (K, 2): along x, across
    # odometry alone along the axis: a random walk of 2 cm a step over 40 steps, the rigid
    # fit removed, leaves decimetres; across it the walls hold every node to a centimetre
    assert std[:, 0].max() > 0.03
    assert std[:, 1].max() < 0.012
    # the fit takes out a common shift and tilt: the ends, not the first node, are worst
    assert std[0, 0] > 1.5 * std[20, 0]
    assert std[-1, 0] > 1.5 * std[20, 0]
    # more odometry noise, more map error
    noisier = map_error_field(_corridor(41, 1.0, 0.05, 0.02))
    assert noisier is not None
    assert noisier.major_std.max() > 2 * field.major_std.max()


def test_the_refinements_priors_count_only_where_the_front_end_trusts_them() -> None:
    g = _corridor(21, 1.0, 0.02, 0.02)
    before = map_error_field(g)
    assert before is not None
    # the refinement measures every node against the map the nodes drew: counted as
    # optimised, tight priors (1 cm in every direction) make the corridor look known to a
    # few millimetres along its axis
    tight = np.diag([0.01**2, 0.01**2, 0.002**2])
    trusted = np.diag([LOOSE**2, 0.01**2, 0.002**2])  # the front end: x is unconstrained
    for i in range(21):
        g.add_map_prior(i, g.node_pose(i), tight, marginal_covariance=trusted)
    g.add_map_prior(20, g.node_pose(20), tight)  # no marginal covariance: left out
    marginal = map_error_field(g)
    assert marginal is not None
    along = np.sqrt(marginal.covariance[:, 0, 0])
    assert np.allclose(along, np.sqrt(before.covariance[:, 0, 0]), rtol=1e-3)
    info_all, _ = g.node_information(map_priors="all")
    info_none, _ = g.node_information(map_priors="none")
    info_marginal, _ = g.node_information()
    assert info_all.sum() > info_marginal.sum() > info_none.sum()
    with pytest.raises(ConfigurationError, match="map_priors"):
        g.node_information(map_priors="some")


def test_positions_follow_the_maps_shift_and_few_nodes_give_none() -> None:
    g = _corridor(10, 0.5, 0.02, 0.02)
    field = map_error_field(g, shift=np.array([0.1, -0.2]))
    assert field is not None
    assert np.allclose(field.xy[3], g.node_pose(3)[:2] - [0.1, -0.2])
    capped = map_error_field(g, max_nodes=4)
    assert capped is not None
    assert capped.xy.shape == (4, 2)
    assert map_error_field(_corridor(2, 1.0, 0.02, 0.02)) is None


def test_the_field_answers_with_the_nearest_place_and_round_trips_its_rows() -> None:
    cov = np.array([np.diag([1e-4, 4e-4]), np.diag([9e-4, 1e-4])])
    field = MapErrorField(np.array([[0.0, 0.0], [5.0, 0.0]]), cov)
    assert np.allclose(field.at((1.0, 1.0)), cov[0])
    assert np.allclose(field.at((4.0, -1.0)), cov[1])
    assert np.allclose(field.major_std, [0.02, 0.03])
    many = field.at(np.array([[1.0, 1.0], [4.0, -1.0], [6.0, 0.0]]))  # (N, 2) at once
    assert many.shape == (3, 2, 2)
    assert np.allclose(many, cov[[0, 1, 1]])
    again = MapErrorField.from_rows(field.rows(), "here")
    assert np.allclose(again.xy, field.xy)
    assert np.allclose(again.covariance, field.covariance)


@pytest.mark.parametrize(
    ("rows", "match"),
    [
        ([[0.0, 0.0, 1e-4]], "5 numbers"),
        ([[0.0, 0.0, -1e-4, 0.0, 1e-4]], "not a covariance"),
        ([[0.0, 0.0, 1e-4, 1e-3, 1e-4]], "not a covariance"),
        ([], "5 numbers"),
        ([["a", 0, 0, 0, 0]], "5 numbers"),
    ],
)
def test_bad_rows_name_where_they_came_from(rows: list[list[float]], match: str) -> None:
    with pytest.raises(ConfigurationError, match=rf"m\.yaml: field 'f'.*{match}"):
        MapErrorField.from_rows(rows, "m.yaml: field 'f'")


def _box() -> OccupancyGrid:
    data = np.zeros((60, 60), dtype=np.int8)
    data[[0, -1], :] = 100
    data[:, [0, -1]] = 100
    return OccupancyGrid(data, 0.05, (0.0, 0.0, 0.0))


def test_a_saved_map_carries_its_field(tmp_path: Path) -> None:
    field = MapErrorField(np.array([[1.0, 1.0], [2.0, 1.5]]), np.array([np.eye(2) * 1e-4] * 2))
    extra = {"symloc_slam": {"map_error": {"std_xy": 0.01, "field": field.rows()}}}
    meta = read_map_yaml(save_map(_box(), tmp_path / "m", extra=extra))
    assert meta.map_std_xy == pytest.approx(0.01)
    assert meta.map_error_field is not None
    assert np.allclose(meta.map_error_field.covariance, field.covariance)
    only = {"symloc_slam": {"map_error": {"field": field.rows()}}}
    meta = read_map_yaml(save_map(_box(), tmp_path / "only", extra=only))
    assert meta.map_std_xy is None
    assert meta.map_error_field is not None
    bad = {"symloc_slam": {"map_error": {"field": [[1.0, 2.0]]}}}
    with pytest.raises(MapFileError, match=r"bad\.yaml: field 'symloc_slam\.map_error\.field'"):
        read_map_yaml(save_map(_box(), tmp_path / "bad", extra=bad))
    scalar = {"symloc_slam": {"map_error": 0.02}}
    with pytest.raises(MapFileError, match=r"scalar\.yaml: field 'symloc_slam\.map_error'"):
        read_map_yaml(save_map(_box(), tmp_path / "scalar", extra=scalar))


def test_the_claim_gate_takes_the_field_where_it_is_larger() -> None:
    surface = surface_distance_field(_box())
    along = np.array([[0.05**2, 0.0], [0.0, 0.002**2]])  # 5 cm along x, 2 mm across
    field = MapErrorField(np.array([[1.5, 1.5]]), along[None])
    gate = ClaimGate(surface, config=ClaimConfig(map_std_xy=0.01), map_error_field=field)
    cov = gate.map_error(np.array([1.4, 1.6, 0.0]))
    # along x the field's 5 cm; across it the floor (1 cm), not the field's 2 mm
    assert cov[0, 0] == pytest.approx(0.05**2)
    assert cov[1, 1] == pytest.approx(0.01**2)
    assert cov[2, 2] == pytest.approx(math.radians(0.25) ** 2)
    off = ClaimGate(
        surface,
        config=ClaimConfig(map_std_xy=0.01, map_error_field=False),
        map_error_field=field,
    )
    assert np.allclose(off.map_error(np.array([1.4, 1.6, 0.0]))[:2, :2], np.eye(2) * 1e-4)
