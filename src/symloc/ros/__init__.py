"""ROS 2: the node's logic (:mod:`symloc.ros.core`), TF without tf2, nav2's parameters, and the node.

The message conversions the node uses live in :mod:`symloc.msgs` (pure Python, shared with the
bag reader in :mod:`symloc.io.rosbag`). Only :mod:`symloc.ros.node` and
:mod:`symloc.ros.lifecycle` import rclpy (install with ``pip install '.[ros]'`` in symloc's checkout).
"""

from __future__ import annotations

__all__: list[str] = []
