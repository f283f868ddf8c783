# SPDX-License-Identifier: GPL-3.0-or-later
"""Glitch validator for baked segments and planned motion: pure functions on ground tracks.

A ground track is an (F, 3) array of x, y, heading per frame (``Motion.ground``: the
character's root on the ground). The validator looks for what a walk never does:

* **spin**: the heading turns more in one frame than the gait ever turns (a Hermite curve
  whose velocity vanishes, a cusp, flips its tangent angle by 180 degrees between two
  samples; the character spins round and back);
* **backwards**: the ground frame moves against the way it faces;
* **jump**: a step longer than the gait ever takes in one frame (anywhere), or, at a join
  between two pieces, the position or heading not continuous (the pieces' shared frame
  differs, or the velocity / turning rate changes at the join by more than the gait's own
  loops ever change it in one frame).

Limits come from the gait itself (:func:`limits`): its loops are the only motion a
locomotion piece is made of, so its per-frame maxima, times a margin, bound every frame a
correct segment or connector can contain.

Records are plain dicts (JSON-ready): ``frame`` (for a per-step quantity, the frame the
step arrives at: a step from frame i to i + 1 is reported at i + 1), ``kind`` ("spin",
"backwards", "jump"), ``value`` and ``limit`` (in ``unit``), and ``where`` (what was
measured); :func:`motion_glitches` adds ``piece``.

Never imports bpy.
"""

from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..kinematics.motion import Motion

MARGIN = 1.5  # over the gait's own per-frame maxima
BACKWARD_TOLERANCE = 1e-3  # m per frame against the heading before a step counts as backwards
JOIN_POSITION = 5e-3  # m: pieces' shared frame may differ by this much (numerical noise)
JOIN_HEADING = np.radians(0.5)
CLIPS = ("traversal", "interaction")  # recorded clips; every other piece kind is locomotion


@dataclass(frozen=True)
class Limits:
    """Per-frame maxima a locomotion ground track of one gait stays within."""

    heading: float  # rad per frame: largest |curvature| x largest step x margin
    step: float  # m per frame: largest loop step x margin
    accel: float  # m per frame^2: largest change of the step vector at a join
    backward: float  # m per frame a step may go against the heading
    join_position: float  # m between pieces' shared frames
    join_heading: float  # rad between pieces' shared frames
    margin: float

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


def _wrap(a):
    return (np.asarray(a, float) + np.pi) % (2.0 * np.pi) - np.pi


def limits(
    gait: Any,
    margin: float = MARGIN,
    backward: float = BACKWARD_TOLERANCE,
    join_position: float = JOIN_POSITION,
    join_heading: float = JOIN_HEADING,
) -> Limits:
    """The gait's own per-frame maxima, times ``margin``.

    ``gait`` is a :class:`~motion_patches.patch.gait.Gait`, or a locomotion patch (then the
    curvature range the bake culled with, ``stats["curvature_limits"]``, is included too).

    * heading: a locomotion piece follows a curve no more bent than the gait's curvature
      range (``kappa_limits``: the loops and the sharpest one-cycle window of the turn
      clips) at a speed no higher than its fastest loop frame, so it turns at most
      ``max|kappa| * max step`` per frame. Near segment ends the blend eases to the
      straight loop (longer steps) while the curve may still bend, so the largest step of
      any loop is used, not the sharp turn loop's own. For the CMU 16_15 / 16_18 walk:
      1.69 /m x 4.53 cm = 4.4 deg/frame (the sharp loop itself turns 3.3 deg/frame; the
      1,036 clean segments of today's bake at most 3.7); x 1.5 = 6.6 deg/frame.
    * step: the largest per-frame travel of any loop (4.53 cm, 1.36 m/s) x 1.5.
    * accel: the largest change of the per-frame step vector a loop shows (speed change
      within a cycle, seam included, plus the turn of a full step at the heading limit):
      a join where the velocity changes by more than this is not continuous. For the
      walk: (1.18 cm + 0.35 cm) x 1.5 = 2.3 cm/frame^2 (clean segments: at most 0.96).
    """
    patch_stats: dict[str, Any] = {}
    if hasattr(gait, "gait"):
        patch_stats = getattr(gait, "stats", {}) or {}
        gait = gait.gait
    k = list(gait.kappa_limits) + list(patch_stats.get("curvature_limits", ()))
    kappa = float(np.max(np.abs(k))) if k else 0.0
    steps = [np.diff(lp.distance) for lp in gait.loops]
    step = float(max(s.max() for s in steps))
    # Change of step length from frame to frame within each loop, across its seam too.
    dstep = float(max(np.abs(np.diff(np.r_[s, s[:1]])).max() for s in steps))
    heading = kappa * step
    return Limits(
        heading=heading * margin,
        step=step * margin,
        accel=(dstep + step * heading) * margin,
        backward=float(backward),
        join_position=float(join_position),
        join_heading=float(join_heading),
        margin=float(margin),
    )


def _record(frame, kind, value, limit, unit, where):
    return {
        "frame": int(frame),
        "kind": kind,
        "value": float(value),
        "limit": float(limit),
        "unit": unit,
        "where": where,
    }


def _step_flags(ground, lim):
    """Per-step measures (F - 1,) of a track: heading change, backward travel, step."""
    g = np.asarray(ground, float)
    d = np.diff(g[:, :2], axis=0)
    dh = _wrap(np.diff(g[:, 2]))  # the same as differences of the unwrapped heading
    step = np.hypot(d[:, 0], d[:, 1])
    c, s = np.cos(g[:, 2]), np.sin(g[:, 2])
    along = np.minimum(d[:, 0] * c[:-1] + d[:, 1] * s[:-1], d[:, 0] * c[1:] + d[:, 1] * s[1:])
    return dh, along, step


def ground_glitches(
    ground: np.ndarray, lim: Limits, joins: Sequence[int] = ()
) -> list[dict[str, Any]]:
    """Glitch records of one ground track (F, 3).

    Every step: |heading change| over ``lim.heading`` ("spin"; "jump" at a join step),
    travel against the heading (the smaller projection of the step on the headings of its
    two frames) below ``-lim.backward`` ("backwards"), a step over ``lim.step`` ("jump").
    At each join frame j (the frame two pieces share, counted in this track): the change
    of the step vector p[j+1] - 2 p[j] + p[j-1] over ``lim.accel``, and the change of the
    turning rate over twice ``lim.heading`` (a node may join a curve bending fully one
    way to one bending fully the other) are "jump"s. The heading is compared modulo 2 pi
    (unwrapped), so a walk turning round and round is clean.
    """
    g = np.asarray(ground, float)
    out: list[dict[str, Any]] = []
    if g.shape[0] < 2:
        return out
    join_steps = np.asarray(sorted({int(j) for j in joins}), int)
    dh, along, step = _step_flags(g, lim)
    join_step = np.zeros(step.size, bool)
    inner = join_steps[(join_steps >= 0) & (join_steps < step.size)]
    join_step[inner] = True  # the step leaving a join frame
    for i in np.flatnonzero(np.abs(dh) > lim.heading):
        out.append(
            _record(
                i + 1,
                "jump" if join_step[i] else "spin",
                abs(dh[i]),
                lim.heading,
                "rad/frame",
                "heading change",
            )
        )
    for i in np.flatnonzero(along < -lim.backward):
        out.append(
            _record(
                i + 1, "backwards", -along[i], lim.backward, "m/frame", "travel against the heading"
            )
        )
    for i in np.flatnonzero(step > lim.step):
        out.append(_record(i + 1, "jump", step[i], lim.step, "m/frame", "step length"))
    inner = join_steps[(join_steps >= 1) & (join_steps <= g.shape[0] - 2)]
    if inner.size:
        p = g[:, :2]
        acc = np.linalg.norm(p[inner + 1] - 2 * p[inner] + p[inner - 1], axis=1)
        ddh = np.abs(dh[inner] - dh[inner - 1])
        for j, a in zip(inner[acc > lim.accel], acc[acc > lim.accel]):
            out.append(_record(j, "jump", a, lim.accel, "m/frame^2", "velocity change at a join"))
        for j, a in zip(inner[ddh > 2 * lim.heading], ddh[ddh > 2 * lim.heading]):
            out.append(
                _record(
                    j, "jump", a, 2 * lim.heading, "rad/frame^2", "turning rate change at a join"
                )
            )
    out.sort(key=lambda r: (r["frame"], r["kind"]))
    return out


def _segment_grounds(patch):
    """Every baked segment's ground frames stacked (T, 3) and each one's first row (S + 1,)."""
    if hasattr(patch, "all_ground"):
        g, _, first = patch.all_ground()
        return np.asarray(g, float), np.asarray(first, int)
    parts = []
    for seg in range(patch.segment_count):
        g = patch.ground(seg)
        parts.append(np.asarray(g[0] if isinstance(g, tuple) else g, float))
    first = np.concatenate(([0], np.cumsum([p.shape[0] for p in parts])))
    return np.concatenate(parts), first


def _stacked_glitches(g, first, lim):
    """{track: records} of tracks stacked in ``g`` (T, 3), track k in rows
    first[k]:first[k + 1]; the steps from one track to the next are left out."""
    n = first.size - 1
    found = {}
    if g.shape[0] < 2:
        return found
    seg_of_step = np.repeat(np.arange(n), np.diff(first))[:-1]
    inside = np.ones(g.shape[0] - 1, bool)
    inside[first[1:-1] - 1] = False  # step from a track's last frame to the next's first
    dh, along, step = _step_flags(g, lim)

    def at_steps(bad, kind, values, limit, unit, where):
        for r, v in zip(bad, values):
            s = int(seg_of_step[r])
            found.setdefault(s, []).append(_record(r + 1 - first[s], kind, v, limit, unit, where))

    bad = np.flatnonzero(inside & (np.abs(dh) > lim.heading))
    at_steps(bad, "spin", np.abs(dh[bad]), lim.heading, "rad/frame", "heading change")
    bad = np.flatnonzero(inside & (along < -lim.backward))
    at_steps(bad, "backwards", -along[bad], lim.backward, "m/frame", "travel against the heading")
    bad = np.flatnonzero(inside & (step > lim.step))
    at_steps(bad, "jump", step[bad], lim.step, "m/frame", "step length")
    return found


def track_glitches(tracks: Sequence[np.ndarray], lim: Limits) -> dict[int, list[dict[str, Any]]]:
    """{index: records} of the ground tracks (a list of (F, 3) arrays) that glitch, all
    checked at once as :func:`ground_glitches` checks one (without joins): for a bake that
    wants to test candidate segments before it builds the patch."""
    tracks = [np.asarray(t, float) for t in tracks]
    if not tracks:
        return {}
    first = np.concatenate(([0], np.cumsum([t.shape[0] for t in tracks])))
    found = _stacked_glitches(np.concatenate(tracks), first, lim)
    for recs in found.values():
        recs.sort(key=lambda r: (r["frame"], r["kind"]))
    return dict(sorted(found.items()))


def segment_glitches(
    patch: Any, lim: Limits | None = None, details: bool = False
) -> list[int] | dict[int, list[dict[str, Any]]]:
    """Indices of the baked segments whose frames glitch (sorted list of ints).

    Each segment's ground track is checked as :func:`ground_glitches` does (all segments
    at once, as :func:`track_glitches`) and its ends against its nodes: the first frame
    must sit on the entry node with the entry heading and the last on the exit node with
    the exit heading (within ``lim.join_position`` / ``lim.join_heading``), as every join
    between segments in a plan is the shared node of two segments ("jump" at frame 0 or
    F - 1 otherwise). With ``details`` a dict {segment: records} is returned instead.
    About 0.5 s for the walk patch's 1,060 segments (their ground frames, cached by the
    patch, are most of it).
    """
    lim = limits(patch) if lim is None else lim
    g, first = _segment_grounds(patch)
    n = first.size - 1
    found = _stacked_glitches(g, first, lim)
    if hasattr(patch, "endpoints"):
        p0, d0, p1, d1 = patch.endpoints(np.arange(n))
        frames = np.diff(first)
        for rows, at, pos, d, where in (
            (first[:-1], np.zeros(n, int), p0, d0, "entry node"),
            (first[1:] - 1, frames - 1, p1, d1, "exit node"),
        ):
            dp = np.linalg.norm(g[rows, :2] - pos, axis=1)
            da = np.abs(_wrap(g[rows, 2] - np.arctan2(d[:, 1], d[:, 0])))
            for values, limit, unit, what in (
                (dp, lim.join_position, "m", " position"),
                (da, lim.join_heading, "rad", " heading"),
            ):
                for s in np.flatnonzero(values > limit):
                    found.setdefault(int(s), []).append(
                        _record(at[s], "jump", values[s], limit, unit, where + what)
                    )
    for recs in found.values():
        recs.sort(key=lambda r: (r["frame"], r["kind"]))
    if details:
        return dict(sorted(found.items()))
    return sorted(found)


def motion_glitches(
    motions: Sequence[Motion | np.ndarray], kinds: Sequence[Any], lim: Limits
) -> list[dict[str, Any]]:
    """Glitch records of a planned motion given piece by piece (frames of the concatenated
    motion, :func:`motion.concatenate`, which drops each piece's first frame).

    ``motions``: one Motion (or (F, 3) ground array) per piece; ``kinds``: each piece's
    kind (strings or objects with ``.kind``: "start", "segment", "part", "goal",
    "traversal", "interaction", ...).

    * Locomotion pieces (every kind but the clips: start and goal connectors, segments,
      parts, and any other piece the gait is synthesised along) are checked frame by
      frame against the gait's limits (:func:`ground_glitches`), including the frames
      eased onto a clip.
    * Traversal and interaction clips (a recorded jump, sitting down) are checked only at
      their joins. They are rigid copies of a recorded clip, so inside they can only do
      what the recording does: a check against the clip's own source maxima would pass by
      construction, and a check against the walk's limits would flag a real jump or a
      sit-down turning on the spot. What planning can break is where they meet the walk.
    * Every join: the two pieces' shared frame (the last of one, the first of the next)
      must agree within ``lim.join_position`` and ``lim.join_heading``. Between two
      locomotion pieces also the velocity and turning rate must carry on across the join
      (as :func:`ground_glitches` checks at joins); next to a clip only the shared frame,
      as a clip's speed differs from the walk's by nature.
    """
    grounds = [np.asarray(getattr(m, "ground", m), float) for m in motions]
    kinds = [getattr(k, "kind", k) for k in kinds]
    if len(kinds) != len(grounds):
        raise ValueError("one kind per motion")
    out = []
    offset = 0
    for i, (g, kind) in enumerate(zip(grounds, kinds)):
        if i > 0:
            a, prev = grounds[i - 1], kinds[i - 1]
            dp = float(np.linalg.norm(g[0, :2] - a[-1, :2]))
            da = float(abs(_wrap(g[0, 2] - a[-1, 2])))
            if dp > lim.join_position:
                out.append(
                    dict(
                        _record(
                            offset,
                            "jump",
                            dp,
                            lim.join_position,
                            "m",
                            f"{prev}-{kind} join position",
                        ),
                        piece=i,
                    )
                )
            if da > lim.join_heading:
                out.append(
                    dict(
                        _record(
                            offset,
                            "jump",
                            da,
                            lim.join_heading,
                            "rad",
                            f"{prev}-{kind} join heading",
                        ),
                        piece=i,
                    )
                )
            if prev not in CLIPS and kind not in CLIPS and a.shape[0] >= 2 and g.shape[0] >= 2:
                three = np.stack((a[-2], a[-1], g[1]))
                for r in ground_glitches(three, lim, joins=(1,)):
                    if r["where"].endswith("at a join"):
                        out.append(dict(r, frame=offset, piece=i))
        if kind not in CLIPS:
            for r in ground_glitches(g, lim):
                out.append(dict(r, frame=r["frame"] + offset, piece=i))
        offset += g.shape[0] - 1
    out.sort(key=lambda r: (r["frame"], r["kind"]))
    return out


def plan_glitches(
    patch: Any, plan: Any, motions: Sequence[Motion | np.ndarray], lim: Limits | None = None
) -> list[dict[str, Any]]:
    """:func:`motion_glitches` of a plan's played motions (``planner.plan_motions``)."""
    return motion_glitches(motions, plan.pieces, limits(patch) if lim is None else lim)


def count(records: Iterable[dict[str, Any]]) -> dict[str, int]:
    """{kind: number of records} of a list of glitch records."""
    out: dict[str, int] = {}
    for r in records:
        out[r["kind"]] = out.get(r["kind"], 0) + 1
    return out
