# SPDX-License-Identifier: GPL-3.0-or-later
"""Stretches of a character's own motion that play the gait's straight loop frame by frame,
found so they are played by one shared loop action instead of keyed per character.

Following a straight line at the loop's pace, space-curve following poses every frame
with the straight loop alone (its blend weight 1), one loop frame after the other: the
body is the loop itself, only the ground under it moves. On a crowd's plaza that is about
two thirds of every character's frames. Keyed in each character's body action those frames
were most of a crowd's file; played by a repeating NLA strip of one action per patch and
rig, they cost a strip. The ground track stays in the character's root action and the foot
lock keeps correcting the legs over it, as over a shared segment.

A stretch is found by comparing the motion itself with the loop (every bone, the root's
offset), never by what produced it, so a blend, a retarget or a hold that changes a frame
leaves that frame to the body action."""

from collections.abc import Sequence
from typing import Any

import numpy as np

from . import quat
from .motion import Motion
from .retime import resample

# every bone's quaternion this close to the loop's (single precision, as a crowd's motions
# travel, is 1e-7 away; 1e-5 is a thousandth of a degree)
SAME_QUAT = 1e-5
SAME_ROOT = 1e-6  # metres: the root's offset from the ground frame
SAME_PHASE = 1e-4  # loop frames: each frame as far on from the one before as the first
MIN_PACE, MAX_PACE = 0.8, 1.25  # loop frames per frame of a stretch
MIN_CYCLES = 1.0  # a stretch shorter than this many loops stays in the body action


def straight_loop(gait: Any, rig: Any = None) -> Motion:
    """Two cycles and one frame of the gait's straight loop in place (its ground frame
    still), on the character's rig (``rig``: a :class:`~.retarget.RigMap`, None for the
    patch's skeleton): what the shared loop action keys, so a strip may start anywhere in
    the cycle and play one whole cycle from there."""
    lp = gait.straight
    n = lp.frames
    ph = np.arange(2 * n + 1) % n
    m = Motion(np.zeros((ph.size, 3)), lp.root_local[ph], lp.rotations[ph], lp.contacts[ph])
    return rig.motion(m) if rig is not None else m


def one_cycle(gait: Any, rig: Any = None) -> Motion:
    """The first cycle and a frame of :func:`straight_loop` (its last frame the first
    again): what the shared loop action keys, its curves repeating it."""
    n = gait.straight.frames
    m = straight_loop(gait)
    m = Motion(m.ground[: n + 1], m.root_local[: n + 1], m.rotations[: n + 1], m.contacts[: n + 1])
    return rig.motion(m) if rig is not None else m


def loop_segments(patch: Any) -> frozenset[int]:
    """The patch's segments whose motion is :func:`straight_loop`'s (a straight segment
    of two cycles across the tile, whatever its heading: in place they are one motion), so
    a plan's segment strip plays the shared loop action instead of an action of its own
    with the same keys. Compared as motions (every bone, the root's offset, the contacts);
    cached on the patch."""
    found = patch.__dict__.get("_loop_segments")
    if found is None:
        loop = straight_loop(patch.gait)
        maybe = np.flatnonzero((np.abs(patch.seg_turn) < 1e-6) & (patch.seg_cycles == 2))
        found = frozenset(int(s) for s in maybe if _same_motion(patch.motion(int(s)), loop))
        patch.__dict__["_loop_segments"] = found
    return found


def _same_motion(a: Motion, b: Motion, tol: float = 1e-9) -> bool:
    """Whether two in-place motions pose every frame alike (to ``tol``)."""
    return (
        a.frames == b.frames
        and bool(np.array_equal(a.contacts, b.contacts))
        and float(np.abs(np.asarray(a.root_local) - b.root_local).max()) < tol
        and float(np.abs(np.asarray(a.rotations) - b.rotations).max()) < tol
    )


def period(loop: Motion) -> int:
    """Frames of one cycle of a :func:`straight_loop`."""
    return (loop.frames - 1) // 2


def phases(motion: Motion, loop: Motion) -> np.ndarray:
    """(F,) the loop's fractional frame each frame of ``motion`` plays, read from the root's
    offset (linear between loop frames), NaN where it is none: [0, period) where the
    motion's every bone is the loop's two neighbouring frames slerped there. Starting from
    and stopping at standing time-warps a walk (:func:`~.retime.eased`): past the ramp it
    plays the loop at its pace again, a fraction of a frame away from the loop's own."""
    p = period(loop)
    lr = np.asarray(loop.root_local[: p + 1], float)  # frame p is frame 0 again
    r = np.asarray(motion.root_local, float)
    f = motion.frames
    step = lr[1:] - lr[:-1]  # (p, 3)
    # the fraction along each of the loop's p steps, and how far off that step it lies
    rel = r[:, None, :] - lr[None, :-1]  # (F, p, 3)
    size = np.maximum(np.einsum("kc,kc->k", step, step), 1e-30)
    t = np.clip(np.einsum("fkc,kc->fk", rel, step) / size, 0.0, 1.0)
    off = np.linalg.norm(rel - t[..., None] * step[None], axis=2)
    k = np.argmin(off, axis=1)
    rows = np.arange(f)
    tk = t[rows, k]
    ok = off[rows, k] <= SAME_ROOT
    lo = np.asarray(loop.rotations[:p], float)[k]
    hi = np.asarray(loop.rotations[1 : p + 1], float)[k]
    want = quat.slerp(lo, hi, np.repeat(tk[:, None], lo.shape[1], axis=1))
    rot = np.asarray(motion.rotations, float)
    sign = np.where(np.einsum("fjc,fjc->fj", rot, want) < 0.0, -1.0, 1.0)
    off_rot = np.linalg.norm(rot - sign[..., None] * want, axis=2)
    ok &= np.all(off_rot <= SAME_QUAT, axis=1)
    out = np.where(ok, (k + tk) % p, np.nan)
    return out


def runs(
    motion: Motion, loop: Motion, min_frames: int | None = None
) -> list[tuple[int, int, float, float]]:
    """[(first frame, last frame, loop frame at the first, loop frames per frame)] of the
    stretches of ``motion`` (at the patch's rate) that play ``loop``
    (:func:`straight_loop`) at a steady pace (:func:`phases`; a walk fitted to a whole
    number of cycles along its path plays the loop a little faster or slower than
    recorded), each at least ``min_frames`` long (default :data:`MIN_CYCLES` loops)."""
    p = period(loop)
    if min_frames is None:
        min_frames = int(np.ceil(MIN_CYCLES * p))
    f = motion.frames
    if f < max(min_frames, 2):
        return []
    ph = phases(motion, loop)
    ok = np.isfinite(ph)
    d = np.full(f, np.nan)
    d[1:] = (ph[1:] - ph[:-1]) % p
    out = []
    start, pace = None, 0.0
    for i in range(f + 1):
        if start is not None and i < f and ok[i]:
            if i == start + 1 and MIN_PACE <= d[i] <= MAX_PACE:
                pace = d[i]
                continue
            if i > start + 1 and abs(d[i] - pace) <= SAME_PHASE:
                continue
        if start is not None and i - start >= min_frames:
            last = i - 1
            out.append((start, last, float(ph[start]), float(np.mean(d[start + 1 : last + 1]))))
        start = i if i < f and ok[i] else None
    return out


def scene_parts(
    piece_runs: list[tuple[int, int, float, float]], lo: int, hi: int, frames: int, p: int
) -> list[tuple[str, int, int, float, float]]:
    """The strips a piece played on scene frames ``lo`` .. ``hi`` (its ``frames`` frames
    at the patch's rate stretched over them) is cut into: [(kind "body" or "loop", first
    scene frame, last scene frame, first action frame, scale)], in order, each starting
    where the one before ends (the earlier strip plays that frame): a loop strip plays the
    loop (``p`` frames a cycle) from that frame on, ``scale`` scene frames per loop frame;
    a body strip's action frame is left 0 (the body action's rows are laid out after).
    A loop strip covers the whole scene frames inside its stretch; one that would cover
    less than a cycle is left to the body."""
    scale = (hi - lo) / float(max(frames - 1, 1))
    parts: list[tuple[str, int, int, float, float]] = []
    at = lo
    for a, b, k0, pace in piece_runs:
        sa = max(int(np.ceil(lo + a * scale - 1e-9)), at)
        sb = int(np.floor(lo + b * scale + 1e-9))
        loop_scale = scale / pace
        if sb <= sa or (sb - sa) < p * loop_scale:
            continue
        if sa > at:
            parts.append(("body", at, sa, 0.0, 1.0))
        parts.append(("loop", sa, sb, (k0 + pace * ((sa - lo) / scale - a)) % p, loop_scale))
        at = sb
    if at < hi or not parts:
        parts.append(("body", at, hi, 0.0, 1.0))
    return parts


# A character's own pieces are keyed on the scene's frames, with the feet locked, up to this
# many scene frames per patch frame (a 60 fps scene from a 30 fps patch, its pieces a little
# warped in time); above it on the patch's frames, played by scaled strips under a foot
# lock keyed on the scene's. Four walkers, cubic keys, against the patch's frames
# (bench_files): at 30/60 32.8 KB per character-second against 45.1, planted feet 0.26 mm
# from keys on every frame against 0.48, skate 2.38 cm/s against 2.35; at 30/90 39.4 against
# 51.4 KB but 3.31 against 2.71 cm/s, at 30/120 4.38 against 3.06 (the legs, held to an
# eighth of a degree, between the patch's frames).
SCENE_KEYS_UP_TO = 2.5


def keyed_on_scene_frames(motions: Sequence[Motion], bounds: Any, own: Sequence[int]) -> bool:
    """Whether a character's own pieces ``own`` are keyed on the scene's frames, not on the
    patch's: a scene at most :data:`SCENE_KEYS_UP_TO` times the patch's rate."""
    return sum(int(bounds[n + 1] - bounds[n]) for n in own) <= SCENE_KEYS_UP_TO * sum(
        motions[n].frames - 1 for n in own
    )


def played_parts(
    motions: Sequence[Motion], bounds: Any, own: Sequence[int], loop: Motion | None
) -> dict[int, list[tuple[str, int, int, float, float]]]:
    """{piece: :func:`scene_parts`} of the pieces ``own`` (those only their character plays;
    ``bounds``: the scene frames where the pieces start and the last ends): the strips
    each is played by. Loops only where the character's own pieces are keyed on the scene's
    frames (:func:`keyed_on_scene_frames`; else they are keyed on the patch's frames and
    played by scaled strips), and only when ``loop`` (:func:`straight_loop`)."""
    scene_keys = keyed_on_scene_frames(motions, bounds, own)
    parts = {}
    for n in own:
        lo, hi = int(bounds[n]), int(bounds[n + 1])
        found = runs(motions[n], loop) if loop is not None and scene_keys else []
        if found and loop is not None:
            parts[n] = scene_parts(found, lo, hi, motions[n].frames, period(loop))
        else:
            parts[n] = [("body", lo, hi, 0.0, 1.0)]
    if not any(k == "body" for n in own for k, *_ in parts[n]):  # nothing left to key
        parts = {n: [("body", int(bounds[n]), int(bounds[n + 1]), 0.0, 1.0)] for n in own}
    return parts


def on_loops(world: Motion, parts: dict, loop: Motion) -> Motion:
    """``world`` (the plan on the scene's frames) with the frames its loop strips play
    (``parts``: :func:`played_parts`) taken from the loop at the phase each plays there,
    as the strip plays them: the scene's frames between the patch's are otherwise
    slerped between two planned frames, each a slerp of two loop frames, a finger 2.7
    degrees and a toe 1.5 away (a 30 fps walk in a 24 fps scene). At the patch's rate
    they are the same frames."""
    p = period(loop)
    rows, phase = [], []
    for pieces in parts.values():
        for kind, a, b, first, scale in pieces:
            if kind == "loop":
                s = np.arange(a, b + 1)
                rows.append(s)
                phase.append(first + np.fmod(s - a, p * scale) / scale)
    if not rows:
        return world
    at = np.concatenate(rows)
    got = resample(loop, np.concatenate(phase))
    root, rot = world.root_local.copy(), np.array(world.rotations, float)
    root[at], rot[at] = got.root_local, got.rotations
    return Motion(world.ground, root, quat.make_continuous(rot, axis=0), world.contacts)
