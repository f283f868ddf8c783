# SPDX-License-Identifier: GPL-3.0-or-later
"""Skeleton: bone hierarchy and rest matrices, and forward kinematics that match Blender.

Blender poses a bone as ``A_j = A_parent @ inv(rest_parent) @ rest_j @ basis_j`` where
``rest`` is the bone's armature-space rest matrix (``bone.matrix_local``) and ``basis`` the
pose channels. Reproducing that exactly lets the core compute foot positions, in-place
transforms and mirrors without Blender, and lets a test compare against the depsgraph.
"""

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from . import quat

T = TypeVar("T")


@dataclass
class Skeleton:
    names: list  # bone names, parents before children
    parents: np.ndarray  # (J,) int, -1 for the root
    rest: np.ndarray  # (J, 4, 4) armature-space rest matrices
    # Other names of bones: a rig a patch is retargeted onto answers to the names of the
    # patch bones it plays ({patch bone name: index}, motion_patches.retarget).
    aliases: dict = field(default_factory=dict, repr=False, compare=False)

    def index(self, name: str) -> int:
        return self.names.index(name)

    @property
    def root(self) -> int:
        return int(np.flatnonzero(self.parents < 0)[0])

    def find(self, *candidates: str) -> int | None:
        """Index of the first bone whose name (or alias) is one of ``candidates``
        (case-insensitive); failing that, of a bone whose name is one of them after a
        ``namespace:`` prefix (Mixamo's ``mixamorig:``) or a Rigify ``DEF-`` prefix."""
        lower = [n.lower() for n in self.names]
        aliases = {k.lower(): v for k, v in self.aliases.items()}
        for c in candidates:
            if c.lower() in aliases:
                return int(aliases[c.lower()])
            if c.lower() in lower:
                return lower.index(c.lower())
        bare = [re.sub(r"^def-", "", n.rsplit(":", 1)[-1]) for n in lower]
        for c in candidates:
            if c.lower() in bare:
                return bare.index(c.lower())
        raise KeyError(f"none of the bones {candidates} is in the skeleton")

    def local_rest(self) -> np.ndarray:
        """(J, 4, 4) rest matrix of each bone relative to its parent's rest matrix
        (read-only: made once per skeleton, every forward kinematics pass needs it)."""
        return _local_rest(self)

    def mirror_map(self) -> np.ndarray:
        """Index of each bone's left/right counterpart (itself when it has none)."""

        def swap(name):
            for a, b in (("Left", "Right"), ("left", "right"), ("LEFT", "RIGHT")):
                if a in name:
                    return name.replace(a, b)
                if b in name:
                    return name.replace(b, a)
            m = re.match(r"^([LR])([A-Z_.].*)$", name)
            if m:
                return ("R" if m.group(1) == "L" else "L") + m.group(2)
            m = re.match(r"^(.*[._])([LRlr])$", name)
            if m:
                other = {"L": "R", "R": "L", "l": "r", "r": "l"}[m.group(2)]
                return m.group(1) + other
            return name

        idx = {n: i for i, n in enumerate(self.names)}
        return np.array([idx.get(swap(n), i) for i, n in enumerate(self.names)])

    def to_dict(self) -> dict[str, Any]:
        return {"names": np.array(self.names), "parents": self.parents, "rest": self.rest}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Skeleton":
        return cls(
            [str(n) for n in d["names"]],
            np.asarray(d["parents"], int),
            np.asarray(d["rest"], float),
        )


def per_skeleton(fn: Callable[[Skeleton], T]) -> Callable[[Skeleton], T]:
    """``fn(skel)`` made once per skeleton object: what a write derives from the rig alone
    (its legs, its facing) is shared by every character of a crowd on that rig. A
    skeleton is never changed once made, so the entry is keyed by the object; it holds
    the skeleton, so the id is not reused while cached. Arrays come back read-only."""
    cache: dict[int, tuple[Skeleton, T]] = {}

    def once(skel):
        hit = cache.get(id(skel))
        if hit is None or hit[0] is not skel:
            if len(cache) >= 32:  # rigs made per write (retargeting) must not pile up
                cache.clear()
            value = fn(skel)
            if isinstance(value, np.ndarray):
                value.setflags(write=False)
            hit = cache[id(skel)] = (skel, value)
        return hit[1]

    once.__doc__, once.__name__ = fn.__doc__, fn.__name__
    once.__wrapped__ = fn  # type: ignore[attr-defined]
    return once


@per_skeleton
def _local_rest(skel: Skeleton) -> np.ndarray:
    """:meth:`Skeleton.local_rest`, computed."""
    out = skel.rest.copy()
    child = np.flatnonzero(skel.parents >= 0)
    out[child] = affine_inverse(skel.rest[skel.parents[child]]) @ skel.rest[child]
    return out


def affine_inverse(m: np.ndarray) -> np.ndarray:
    """Inverses of affine 4x4 matrices (..., 4, 4) (last row 0 0 0 1), in closed form: the
    3x3 part by its adjugate, the translation through it. LAPACK's general inverse costs a
    millisecond a call where its threads wait for a busy core, as they do beside a crowd's
    workers; this costs microseconds."""
    m = np.asarray(m, float)
    a, b, c = m[..., :3, 0], m[..., :3, 1], m[..., :3, 2]
    rows = np.stack((np.cross(b, c), np.cross(c, a), np.cross(a, b)), axis=-2)
    det = np.einsum("...i,...i->...", a, rows[..., 0, :])
    inv3 = rows / det[..., None, None]
    out = np.zeros(m.shape)
    out[..., :3, :3] = inv3
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", inv3, m[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def compose(rot: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """4x4 matrices from rotation quaternions (..., 4) and positions (..., 3)."""
    m = np.zeros(np.shape(pos)[:-1] + (4, 4))
    m[..., :3, :3] = quat.to_matrix(rot)
    m[..., :3, 3] = pos
    m[..., 3, 3] = 1.0
    return m


def forward_kinematics(skel: Skeleton, root_pos: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """Armature-space bone matrices (F, J, 4, 4).

    ``root_pos`` (F, 3) is the root bone's armature-space head position and
    ``rotations`` (F, J, 4) the pose rotation channels (``rotation_quaternion``) of every
    bone; non-root bones carry no translation channels (true of BVH skeletons).
    """
    rotations = np.asarray(rotations, float)
    nf, nj = rotations.shape[:2]
    local_rest = skel.local_rest()
    basis = quat.to_matrix(rotations)
    out = np.zeros((nf, nj, 4, 4))
    out[..., 3, 3] = 1.0
    r = skel.root
    out[:, r, :3, :3] = skel.rest[r, :3, :3] @ basis[:, r]
    out[:, r, :3, 3] = root_pos
    for j, p in enumerate(skel.parents):
        if p < 0:
            continue
        lr = local_rest[j]
        m = np.zeros((nf, 4, 4))
        m[:, :3, :3] = lr[:3, :3] @ basis[:, j]
        m[:, :3, 3] = lr[:3, 3]
        m[:, 3, 3] = 1.0
        out[:, j] = out[:, p] @ m
    return out


def root_location_to_position(skel: Skeleton, location: np.ndarray) -> np.ndarray:
    """Root bone ``location`` channels (F, 3) -> armature-space head positions."""
    r = skel.rest[skel.root]
    return np.asarray(location, float) @ r[:3, :3].T + r[:3, 3]


def root_position_to_location(skel: Skeleton, pos: np.ndarray) -> np.ndarray:
    """Inverse of :func:`root_location_to_position`."""
    r = skel.rest[skel.root]
    return (np.asarray(pos, float) - r[:3, 3]) @ r[:3, :3]


def local_rotations_from_global(skel: Skeleton, global_rot: np.ndarray) -> np.ndarray:
    """Pose rotation channels (F, J, 4) that give armature-space rotations (F, J, 3, 3)."""
    local_rest = skel.local_rest()
    nf, nj = global_rot.shape[:2]
    basis = np.empty((nf, nj, 3, 3))
    for j, p in enumerate(skel.parents):
        if p < 0:
            basis[:, j] = skel.rest[j, :3, :3].T @ global_rot[:, j]
        else:
            parent_and_rest = global_rot[:, p] @ local_rest[j, :3, :3]
            basis[:, j] = np.swapaxes(parent_and_rest, -1, -2) @ global_rot[:, j]
    return quat.make_continuous(quat.from_matrix(basis), axis=0)
