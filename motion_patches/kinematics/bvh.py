# SPDX-License-Identifier: GPL-3.0-or-later
"""A small BVH reader for the core, so the core can be tested on real mocap without bpy.

Blender's bundled importer is what users go through (see the adapter); this reader builds
the same world motion (Y-up converted to Blender's Z-up, the same scale) with
rotation-free rest matrices, which is a valid :class:`Skeleton` for every core algorithm.
"""

import os

import numpy as np

from . import quat
from .clip import Clip
from .skeleton import Skeleton

CMU_SCALE = 0.056444
# BVH (x, y, z) with Y up -> Blender (x, -z, y) with Z up, as the bundled importer does.
Y_UP_TO_Z_UP = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])

_AXIS = {"X": np.array([1.0, 0, 0]), "Y": np.array([0, 1.0, 0]), "Z": np.array([0, 0, 1.0])}


def _axis_quat(axis, deg):
    a = np.radians(deg)[:, None] * 0.5
    v = _AXIS[axis][None] * np.sin(a)
    return np.concatenate((np.cos(a), v), axis=1)


def read(path: str | os.PathLike[str], scale: float = CMU_SCALE, name: str | None = None) -> Clip:
    """Clip of a BVH file: root position and per-joint rotations in Blender's axes."""
    with open(path) as fh:
        text = fh.read()
    head, _, motion = text.partition("MOTION")
    if not motion:
        raise ValueError(f"{path}: no MOTION section")
    tokens = head.split()
    names: list[str] = []
    parents: list[int] = []
    offsets: list[np.ndarray | None] = []
    channels: list[list[str]] = []
    stack: list[int] = []
    i, pending_end = 0, False
    while i < len(tokens):
        t = tokens[i]
        if t in ("ROOT", "JOINT"):
            names.append(tokens[i + 1])
            parents.append(stack[-1] if stack else -1)
            offsets.append(None)
            channels.append([])
            i += 2
        elif t == "End":
            pending_end = True
            i += 2
        elif t == "{":
            stack.append(-2 if pending_end else len(names) - 1)
            pending_end = False
            i += 1
        elif t == "}":
            stack.pop()
            i += 1
        elif t == "OFFSET":
            if stack and stack[-1] != -2 and offsets[stack[-1]] is None:
                offsets[stack[-1]] = np.array([float(x) for x in tokens[i + 1 : i + 4]])
            i += 4
        elif t == "CHANNELS":
            n = int(tokens[i + 1])
            channels[stack[-1]] = tokens[i + 2 : i + 2 + n]
            i += 2 + n
        else:
            i += 1
    lines = motion.strip().splitlines()
    nframes = int(lines[0].split(":")[1])
    frame_time = float(lines[1].split(":")[1])
    data = np.array([[float(x) for x in ln.split()] for ln in lines[2 : 2 + nframes]])
    if data.shape[0] != nframes:
        raise ValueError(f"{path}: header says {nframes} frames, found {data.shape[0]}")

    parent = np.array(parents)
    j = len(names)
    rest = np.tile(np.eye(4), (j, 1, 1))
    for k in range(j):
        off = Y_UP_TO_Z_UP @ offsets[k] * scale
        rest[k, :3, 3] = off + (rest[parent[k], :3, 3] if parent[k] >= 0 else 0.0)
    c = Y_UP_TO_Z_UP
    cq = quat.from_matrix(c)
    rot = np.tile(np.array([1.0, 0, 0, 0]), (nframes, j, 1))
    root_pos = np.zeros((nframes, 3))
    col = 0
    for k in range(j):
        q = np.tile(np.array([1.0, 0, 0, 0]), (nframes, 1))
        pos = np.zeros((nframes, 3))
        for ch in channels[k]:
            v = data[:, col]
            col += 1
            if ch.endswith("rotation"):
                q = quat.mul(q, _axis_quat(ch[0].upper(), v))
            else:
                pos[:, "XYZ".index(ch[0].upper())] = v
        # Conjugate into Z-up: R' = C R C^T.
        rot[:, k] = quat.mul(quat.mul(cq, q), quat.conj(cq))
        if parent[k] < 0:
            root_pos = (pos * scale) @ c.T + rest[k, :3, 3]
    rot = quat.make_continuous(rot, axis=0)
    return Clip(
        name or str(path).rsplit("/", 1)[-1].rsplit(".", 1)[0],
        Skeleton(names, parent, rest),
        1.0 / frame_time,
        root_pos,
        rot,
    )
