# SPDX-License-Identifier: GPL-3.0-or-later
"""Integer keys of low-level graph nodes: a tile and a local entry state, packed.

A node is where the character enters tile (i, j) in local entry state (edge, slot,
heading) of the locomotion patch; packing it in one int keeps the A* heap and its
dictionaries free of tuples and objects.
"""

from typing import Any

import numpy as np

from .locomotion_patch import LocomotionPatch, node_id, split_node_id

BIAS = 1 << 15
LOCAL = 256  # local entry ids per tile (EDGES * nodes * DIRECTIONS for 8 nodes)
NEXT_EDGE = np.array([2, 3, 0, 1])  # the neighbour's edge facing an exit edge
TILE_STEP = np.array([[0, -1], [1, 0], [0, 1], [-1, 0]])


def pack(i: int | np.ndarray, j: int | np.ndarray, local: int | np.ndarray) -> np.ndarray:
    return (
        (np.asarray(i, np.int64) + BIAS) * (2 * BIAS) + (np.asarray(j, np.int64) + BIAS)
    ) * LOCAL + local


def unpack(key: Any) -> tuple[Any, Any, Any]:
    local = key % LOCAL
    rest = key // LOCAL
    return rest // (2 * BIAS) - BIAS, rest % (2 * BIAS) - BIAS, local


def next_entry(patch: LocomotionPatch, tile: tuple[int, int], seg: int) -> tuple[int, int, int]:
    """(i, j, local entry id) of the node a segment walked in ``tile`` leads to."""
    e1, k1, h1 = split_node_id(patch.seg_exit[seg], patch.nodes)
    step = TILE_STEP[e1]
    return (
        tile[0] + int(step[0]),
        tile[1] + int(step[1]),
        int(node_id(NEXT_EDGE[e1], k1, h1, patch.nodes)),
    )
