"""Other SLAM systems run on exactly symloc's input, for side-by-side benchmarks.

A peer is built from its own source, outside symloc (nothing of it is shipped here), by the
harness in ``../shared/peers/<name>`` (or ``$SYMLOC_SHARED_PEERS/<name>``); only the driver
that feeds it a CARMEN log lives in this package. See :mod:`symloc.bench.peers.gmapping`.
"""

from __future__ import annotations

from symloc.bench.peers.gmapping import (
    GMAPPING_COMMIT,
    GMappingPeer,
    PeerRun,
    PeerUnavailableError,
    find_peer_harness,
    write_peer_log,
)

__all__ = [
    "GMAPPING_COMMIT",
    "GMappingPeer",
    "PeerRun",
    "PeerUnavailableError",
    "find_peer_harness",
    "write_peer_log",
]
