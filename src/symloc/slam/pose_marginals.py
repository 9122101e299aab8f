"""Where the map is unsure of itself: the pose graph's marginals of its node positions.

A map drawn from a trip is as right, place by place, as the poses its scans were drawn at. The
pose graph knows how well each pose is fixed: its information matrix (odometry, the front
end's matches with their degenerate directions left loose, the loop closures;
:meth:`~symloc.slam.pose_graph.PoseGraph.node_information`) inverted gives every node's
covariance. In a room every node is tied to its neighbours by matches in all directions and
the covariances stay near a centimetre; along a 40-60 m corridor whose ends are out of the
lidar's range, only the odometry fixes how far the robot went, and the nodes' position along
the axis is uncertain by decimetres, as the map is there.

Two choices make the numbers mean what a user of the map needs:

- **The map frame is arbitrary.** The graph fixes it at the first node, so that node looks
  perfect and the far end carries all the drift. What matters is how the map is distorted, not
  where its frame is: the rigid motion (two translations and a rotation about the nodes'
  centroid) that best fits the nodes is removed from the joint covariance, as aligning a
  trajectory to the truth removes it (``e -> (I - A (A^T A)^-1 A^T) e``).
- **The final scan-to-map refinement counts only where the front end would trust it.** It
  measures every node against one map the nodes drew, and a direction each scan fixes weakly (a
  corridor's end wall 20 m away) looks, summed over hundreds of nodes, as sure as a wall beside
  the robot: each refinement prior enters with its directions below the front end's degeneracy
  threshold left loose (``map_priors="marginal"`` of
  :meth:`~symloc.slam.pose_graph.PoseGraph.node_information`). On the bench's dev worlds
  (realistic sensors): regular#0, median std 0.6 cm, 99 % of the lap's errors (0.3 cm median)
  inside the 95 % ellipse; rectangle#0, 0.6 cm, 100 %; corridor_long#1, whose along-axis drift
  reached 32 cm, see the README. With every prior counted as optimised the same corridor's
  estimate covered half its errors; with none, rooms read 0.9-1.5 cm and a user's replay in a
  4 x 3 m room tracked 89 of 134 scans instead of 123, every one of them within 4 cm.

At most ``max_nodes`` nodes (evenly spaced along the trip) are solved for: the cost is one
sparse factorisation of the graph plus ``2 * max_nodes`` solves.
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.sparse.linalg as spl
from numpy.typing import NDArray

from symloc.grid.map_error_field import MapErrorField
from symloc.slam.pose_graph import PoseGraph

__all__ = ["MAX_NODES", "map_error_field"]

FloatArray = NDArray[np.float64]

logger = logging.getLogger(__name__)

#: Nodes solved for at most (evenly spaced along the trip).
MAX_NODES = 600

_CHUNK = 64


def map_error_field(
    graph: PoseGraph, *, shift: FloatArray | None = None, max_nodes: int = MAX_NODES
) -> MapErrorField | None:
    """The map's position error, node by node, from ``graph``'s marginals (module docstring).

    Parameters
    ----------
    graph : PoseGraph
        Optimised; its nodes' current estimates are the map's poses.
    shift : (2,) array, optional
        Subtracted from the node positions [m]: the move of the map's origin after the graph
        (:attr:`symloc.slam.map_error.MapError.shift`), so that they are in the saved map's
        frame.
    max_nodes : int
        At most this many nodes, evenly spaced along the trip.

    Returns
    -------
    MapErrorField or None
        None with fewer than three nodes (no distortion to speak of) or when the graph's
        information is singular (a node no factor ties to the rest).
    """
    n = graph.n_nodes
    if n < 3:
        return None
    info, columns = graph.node_information()
    pick = np.unique(np.linspace(0, n - 1, min(n, max_nodes)).round().astype(np.intp))
    poses = graph.node_poses()[pick]
    cols = np.array([[columns[i], columns[i] + 1] for i in pick], dtype=np.intp).ravel()
    try:
        lu = spl.splu(info)
    except RuntimeError as exc:  # "Factor is exactly singular"
        logger.warning("map error field: the pose graph's information is singular (%s)", exc)
        return None
    joint = np.empty((cols.size, cols.size))  # each node's (dx, dy) in its own frame
    for lo in range(0, cols.size, _CHUNK):  # a few columns at a time: a large log's graph
        part = cols[lo : lo + _CHUNK]
        rhs = np.zeros((info.shape[0], part.size))
        rhs[part, np.arange(part.size)] = 1.0
        joint[:, lo : lo + part.size] = lu.solve(rhs)[cols]
    k = pick.size
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    turn = np.stack([np.stack([c, -s], axis=-1), np.stack([s, c], axis=-1)], axis=1)  # (K, 2, 2)
    # into the map frame: R_a J_ab R_b^T for every pair of nodes
    joint4 = np.einsum("aij,ajbl,bml->aibm", turn, joint.reshape(k, 2, k, 2), turn)
    joint = joint4.reshape(2 * k, 2 * k)
    centred = poses[:, :2] - poses[:, :2].mean(axis=0)
    rigid = np.zeros((2 * k, 3))
    rigid[0::2, 0] = 1.0
    rigid[1::2, 1] = 1.0
    rigid[0::2, 2] = -centred[:, 1]
    rigid[1::2, 2] = centred[:, 0]
    keep = np.eye(2 * k) - rigid @ np.linalg.solve(rigid.T @ rigid, rigid.T)
    joint = keep @ joint @ keep.T
    every = np.arange(k)
    blocks = joint.reshape(k, 2, k, 2)[every, :, every, :]  # (K, 2, 2): each node's own
    blocks = 0.5 * (blocks + blocks.transpose(0, 2, 1))
    xy = poses[:, :2] - (0.0 if shift is None else np.asarray(shift, dtype=np.float64))
    field = MapErrorField(xy, blocks)
    logger.info(
        "map error field: %d nodes, position std median %.3f m, max %.3f m",
        k,
        float(np.median(field.major_std)),
        float(field.major_std.max()),
    )
    return field
