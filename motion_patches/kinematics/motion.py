# SPDX-License-Identifier: GPL-3.0-or-later
"""Motion: synthesised animation as a ground trajectory plus in-place body channels."""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from . import quat
from .inplace import to_world
from .skeleton import Skeleton, forward_kinematics


@dataclass
class Motion:
    ground: np.ndarray  # (F, 3) x, y, heading of the ground frame (the armature object)
    root_local: np.ndarray  # (F, 3) root position in ground coordinates
    rotations: np.ndarray  # (F, J, 4) in-place rotation channels
    contacts: np.ndarray  # (F, 4) planted flags from the source loops

    @property
    def frames(self) -> int:
        return self.ground.shape[0]

    def transformed(self, dx: float, dy: float, dheading: float = 0.0) -> "Motion":
        """The same motion with its ground frame moved by a rigid transform of the plane."""
        c, s = np.cos(dheading), np.sin(dheading)
        g = self.ground.copy()
        g[:, 0] = c * self.ground[:, 0] - s * self.ground[:, 1] + dx
        g[:, 1] = s * self.ground[:, 0] + c * self.ground[:, 1] + dy
        g[:, 2] = self.ground[:, 2] + dheading
        return Motion(g, self.root_local, self.rotations, self.contacts)

    def world_matrices(self, skel: Skeleton) -> np.ndarray:
        pos, rot = to_world(skel, self.ground, self.root_local, self.rotations)
        return forward_kinematics(skel, pos, rot)


def sliced(m: Motion, start: int, stop: int) -> Motion:
    """Frames ``start`` to ``stop`` (inclusive) of a motion."""
    sl = slice(start, stop + 1)
    return Motion(m.ground[sl], m.root_local[sl], m.rotations[sl], m.contacts[sl])


EASE_RATE = np.radians(3.0)  # radians per frame a bone is eased at, at most, onto a clip


def ease_to(m: Motion, target: Motion, frames: int, at_end: bool = True) -> Motion:
    """The motion with its last (or first) ``frames`` frames eased onto ``target``'s first
    (or last) frame: ground offset and body channels, smoothstep weights, so a stitch
    between two clips lands without a jump. A bone whose rotation differs by more than
    ``EASE_RATE`` per frame over ``frames`` (another take's hips or shoulders, held
    differently) is eased over as many more frames as keep it to that rate, so it does
    not snap round; the legs, matched by the stitch, keep the short window."""
    n = min(frames, m.frames - 1)
    if at_end:
        src, tgt = m.frames - 1, 0
    else:
        src, tgt = 0, target.frames - 1
    f = np.arange(m.frames)
    # Frames from the end (start) the blend reaches back, per joint.
    q0, q1 = m.rotations[src], target.rotations[tgt]
    angle = 2.0 * np.arccos(np.clip(np.abs(np.sum(q0 * q1, axis=-1)), 0.0, 1.0))  # (J,)
    span = np.clip(np.ceil(angle / EASE_RATE), n, max(m.frames - 1, 1)).astype(int)
    span = np.maximum(span, 1)

    def weights(k):  # (F, K) smoothstep from 0 to 1 over the last (first) k frames
        k = np.asarray(k, float)
        t = (f[:, None] - (m.frames - 1 - k)) / k if at_end else (k - f[:, None]) / k
        t = np.clip(t, 0.0, 1.0)
        return t * t * (3 - 2 * t)

    w = weights([max(n, 1)])[:, 0] if n > 0 else np.zeros(m.frames)
    g = m.ground.copy()
    dg = target.ground[tgt] - m.ground[src]
    dg[2] = (dg[2] + np.pi) % (2 * np.pi) - np.pi
    g += w[:, None] * dg[None]
    root = m.root_local + w[:, None] * (target.root_local[tgt] - m.root_local[src])[None]
    tq = np.broadcast_to(q1, m.rotations.shape)
    wj = weights(span) if n > 0 else np.zeros(m.rotations.shape[:2])
    rot = quat.slerp(m.rotations, tq, wj)
    con = m.contacts & (w[:, None] < 0.5) | target.contacts[tgt][None] & (w[:, None] >= 0.5)
    return Motion(g, root, quat.make_continuous(rot, axis=0), con)


def concatenate(parts: Sequence[Motion]) -> Motion:
    """Join motions end to start; each part's first frame repeats the previous last frame."""
    keep = [parts[0]] + [
        Motion(p.ground[1:], p.root_local[1:], p.rotations[1:], p.contacts[1:]) for p in parts[1:]
    ]
    g = np.concatenate([p.ground for p in keep])
    g[:, 2] = np.unwrap(g[:, 2])
    return Motion(
        g,
        np.concatenate([p.root_local for p in keep]),
        np.concatenate([p.rotations for p in keep]),
        np.concatenate([p.contacts for p in keep]),
    )
