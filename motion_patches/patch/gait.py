# SPDX-License-Identifier: GPL-3.0-or-later
"""Gait: the loops of one layer and parametric blending between them by curvature.

A straight loop and turn loops (slow / fast, left / right; a missing side is mirrored) are
ordered by their curvature. A curvature between two loops blends those two (pose slerp,
root and stride lerp), so a character following a space curve takes on the nuanced
posture and shorter stride of a real turn as the curve bends (paper Sec. 6).

Turn clips are optional: space-curve following bends the straight stride itself, so a
straight clip alone turns too, up to ``STRAIGHT_BEND_RADIUS`` (turn clips that turn
sharper widen the range).
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..kinematics import quat
from ..kinematics.clip import Clip, mirror
from ..kinematics.contacts import floor_level
from ..kinematics.inplace import facing_yaw
from ..kinematics.skeleton import Skeleton
from .cycle import Loop, best_cycle, cycle_turns, detect_cycles, extract_loop


@dataclass
class Gait:
    layer: str
    fps: float
    skeleton: Skeleton
    loops: list  # Loop, sorted by curvature; exactly one is straight
    notes: list = field(default_factory=list)  # provenance, e.g. "right turn mirrored from 16_18"
    turn_range: tuple | None = None  # sharpest (right, left) curvature: turn clips' one-cycle
    # windows, at least the straight stride's bend
    floor_height: float | None = None  # :meth:`floor`, stored with the patch (None: not yet
    # derived; it is then derived once, by forward kinematics of the straight loop)

    @property
    def frames(self) -> int:
        return self.loops[0].frames

    @property
    def straight(self) -> Loop:
        # Asked for in every connector and synthesis call: the loop list is fixed once a
        # gait is built, so its index is looked up once.
        key = id(self.loops), len(self.loops)
        cached = self.__dict__.get("_straight")
        if cached is None or cached[0] != key:
            i = int(np.argmin(np.abs([lp.curvature for lp in self.loops])))
            cached = self.__dict__["_straight"] = (key, i)
        return self.loops[cached[1]]

    @property
    def curvatures(self) -> np.ndarray:
        """Blend parameter of each loop: its curvature, the straight loop's taken as 0."""
        k = np.array([lp.curvature for lp in self.loops])
        k[np.argmin(np.abs(k))] = 0.0
        return k

    @property
    def cycle_distance(self) -> float:
        return self.straight.cycle_distance

    @property
    def kappa_limits(self) -> tuple[float, float]:
        """Curvature range the bake culls with: the loops, the sharpest one-cycle window
        of the turn clips and the straight stride's bend (``turn_range``)."""
        k = np.array([lp.curvature for lp in self.loops])
        lo, hi = float(min(k.min(), 0.0)), float(max(k.max(), 0.0))
        if self.turn_range is not None:
            lo, hi = min(lo, self.turn_range[0]), max(hi, self.turn_range[1])
        return lo, hi

    def weights(self, kappa: float | np.ndarray) -> np.ndarray:
        """(K, L) blend weights of the loops for curvatures (K,): two neighbours lerped."""
        k = self.curvatures
        if len(k) == 1:
            return np.ones(np.shape(kappa) + (1,))
        kap = np.clip(np.asarray(kappa, float), k[0], k[-1])
        hi = np.clip(np.searchsorted(k, kap, side="right"), 1, len(k) - 1)
        lo = hi - 1
        t = (kap - k[lo]) / np.maximum(k[hi] - k[lo], 1e-12)
        w = np.zeros(kap.shape + (len(k),))
        np.put_along_axis(w, lo[..., None], (1 - t)[..., None], axis=-1)
        np.put_along_axis(w, hi[..., None], t[..., None], axis=-1)
        return w

    def blended_distance(self, kappa: float | np.ndarray) -> np.ndarray:
        """Cycle distance at curvatures ``kappa``; equals ``weights(kappa) @ distances``."""
        return np.interp(kappa, self.curvatures, self.cycle_distances())

    def straight_weights(self, n: int) -> np.ndarray:
        w = np.zeros((n, len(self.loops)))
        w[:, int(np.argmin(np.abs(self.curvatures)))] = 1.0
        return w

    def floor(self) -> float:
        """Floor height under the straight loop (where interaction clips are put down).
        Kept once found (every plan, check and crowd member asks for it; it takes the
        loop's forward kinematics), for as long as the loop and skeleton are the same; a
        patch stores it (``floor_height``, read from the file), so it is not derived at all
        for a loaded patch."""
        lp = self.straight
        key = (lp, lp.root_local, lp.rotations, self.skeleton, self.fps)
        cached = self.__dict__.get("_floor")
        if cached is None and self.floor_height is not None:  # stored with the patch
            cached = self.__dict__["_floor"] = (key, float(self.floor_height))
        if (
            cached is None
            or any(a is not b for a, b in zip(cached[0][:4], key))
            or (cached[0][4] != self.fps)
        ):
            clip = Clip("loop", self.skeleton, self.fps, lp.root_local, lp.rotations)
            cached = self.__dict__["_floor"] = (key, float(floor_level(clip)))
            self.floor_height = cached[1]
        return cached[1]

    def cycle_distances(self) -> np.ndarray:
        return np.array([lp.cycle_distance for lp in self.loops])

    def steps(self, phase: int | np.ndarray, weights: np.ndarray) -> np.ndarray:
        """Distance travelled from frame ``phase`` to the next, blended (K,)."""
        st = np.stack([np.diff(lp.distance) for lp in self.loops], axis=1)  # (N, L)
        return np.sum(st[np.asarray(phase) % self.frames] * weights, axis=-1)

    def pose(
        self, phase: int | np.ndarray, weights: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Blended root_local (K, 3), rotations (K, J, 4), contacts (K, 4) at frame phases."""
        ph = np.asarray(phase) % self.frames
        root = np.zeros((ph.size, 3))
        for i, lp in enumerate(self.loops):
            root += lp.root_local[ph] * weights[:, i : i + 1]
        # Blend rotations pairwise: accumulate a running slerp in order of weight.
        order = np.argsort(-weights, axis=1)
        rot = np.empty((ph.size,) + self.loops[0].rotations.shape[1:])
        contacts = np.empty((ph.size, 4), bool)
        acc = np.zeros(ph.size)
        stacked = np.stack([lp.rotations[ph] for lp in self.loops], axis=1)  # (K, L, J, 4)
        cstack = np.stack([lp.contacts[ph] for lp in self.loops], axis=1)
        rows = np.arange(ph.size)
        first = order[:, 0]
        rot[:] = stacked[rows, first]
        # Planted only where every loop that contributes noticeably has the joint planted.
        contacts[:] = np.all(cstack | (weights < 0.1)[..., None], axis=1)
        acc[:] = weights[rows, first]
        for r in range(1, len(self.loops)):
            idx = order[:, r]
            w = weights[rows, idx]
            t = np.where(acc + w > 0, w / np.maximum(acc + w, 1e-12), 0.0)
            rot = quat.slerp(rot, stacked[rows, idx], np.repeat(t[:, None], rot.shape[1], 1))
            acc = acc + w
        return root, quat.make_continuous(rot), contacts

    def to_dict(self) -> dict[str, Any]:
        d = {
            "gait_layer": np.array(self.layer),
            "gait_fps": np.array(self.fps),
            "gait_turn_range": np.array(self.turn_range if self.turn_range else (0.0, 0.0)),
            "gait_count": np.array(len(self.loops)),
            "gait_notes": np.array(self.notes, dtype=str),
            "gait_floor": np.array(self.floor()),
        }
        d.update({"skel_" + k: v for k, v in self.skeleton.to_dict().items()})
        for i, lp in enumerate(self.loops):
            d.update(lp.to_dict(f"loop{i}_"))
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "Gait":
        skel = Skeleton.from_dict({k[5:]: d[k] for k in d if k.startswith("skel_")})
        loops = [Loop.from_dict(d, f"loop{i}_") for i in range(int(d["gait_count"]))]
        tr = tuple(float(v) for v in d["gait_turn_range"]) if "gait_turn_range" in d else None
        return cls(
            str(d["gait_layer"]),
            float(d["gait_fps"]),
            skel,
            loops,
            [str(n) for n in d["gait_notes"]],
            tr if tr and any(tr) else None,
            float(d["gait_floor"]) if "gait_floor" in d else None,  # older files: derived
        )


MIN_TURN = np.radians(10.0)  # a cycle turning less than this counts as straight

STRAIGHT_BEND_RADIUS = 1.0
"""Metres: the tightest turn a straight stride is bent to by space-curve following alone.

Chosen by measuring the synthesised motion: the straight loop followed along constant-
curvature arcs (4 cycles, no easing), each planted foot joint (ankle, toe) scored by how
far it strays, over one contact, from where it stands on average during that contact
(its drift), and by the mean planted-foot skate ("straight": the recording itself; the
other columns bend it left)::

    radius          straight   2.0 m   1.25 m   1.0 m   0.83 m   0.59 m
    16_15 drift       4.2      5.2     7.3      8.7    10.1     13.7  cm
          skate      10.3     13.4    17.6     20.7    24.0     32.6  cm/s
    02_01 drift       5.7      6.3     8.2      9.6    11.0     14.5  cm
          skate      14.6     18.2    22.5     25.7    29.1     38.0  cm/s
    02_02 drift       5.1      6.7     7.9      8.9    10.4     14.0  cm
          skate      16.5     21.3    27.5     32.3    37.4     50.5  cm/s

At 1 m every planted foot stays within 10 cm of where it stands (bent right too, but for
the brisk 02_02: 10.0 cm) and the skate at most doubles the recording's own (2.0x, 1.8x,
2.0x); at 0.8 m every clip's feet stray past 10 cm either way. For comparison the 16_15 +
16_18 turn gait, blending recorded turns, drifts 10.6 cm and skates 28.8 (left) to 33.9
(right) cm/s at 1 m, and is baked down to 0.59 m (16-23 cm). Foot locking pins what is
left. A wider default leaves the patch unable to connect: at 1.25 m only 58 % of
its entry states have a way on and 6 of 20 random pillar fields are planned (1 m: 75 %,
20 of 20; figures for 16_15, 8x8 cells, 8 nodes).
"""


def sharpest_turn(clip: Clip, cycle_frames: float) -> tuple[float, float]:
    """(most negative, most positive) heading change per metre over any window of one
    cycle: the curvature a turn clip really reaches, not only at strike-aligned cycles."""
    yaw = facing_yaw(clip)
    p = clip.root_pos[:, :2]
    dist = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))))
    n = max(1, min(int(round(cycle_frames)), clip.frames - 1))
    k = (yaw[n:] - yaw[:-n]) / np.maximum(dist[n:] - dist[:-n], 1e-6)
    return float(min(k.min(), 0.0)), float(max(k.max(), 0.0))


def build_gait(
    layer: str,
    straight: Clip,
    turns: Sequence[Clip] = (),
    fps: float = 30.0,
    mirror_turns: bool = True,
    bend_radius: float = STRAIGHT_BEND_RADIUS,
) -> Gait:
    """Gait of a layer from a straight clip and turn clips (all one skeleton).

    Every cycle of a turn clip that turns by at least ``MIN_TURN`` becomes a loop; when
    only one turning direction is present and ``mirror_turns`` is set, the mirror images are
    added and named as such. The curvature range (``turn_range``) reaches at least
    ``1 / bend_radius`` either way, what the straight stride follows alone, and further
    where a turn clip turns sharper. Raises ValueError on clips that are not locomotion.
    """
    if not bend_radius > 0:
        raise ValueError(f"the bend radius must be > 0 metres, not {bend_radius}")
    notes = []
    for c in (straight,) + tuple(turns):
        c.validate()
        if c.skeleton.names != straight.skeleton.names:
            raise ValueError(
                f"clip '{c.name}' has a different skeleton from '{straight.name}'; "
                f"one locomotion patch takes clips of one skeleton"
            )
    info = detect_cycles(straight)
    a, b = best_cycle(straight, info, "seam")
    frames = int(round((b - a) / straight.fps * fps))
    loops = [extract_loop(straight, a, b, frames, name=f"{straight.name} straight")]
    notes.append(f"straight: {straight.name} frames {a}-{b}")

    def turning_cycles(c, label=""):
        ci = detect_cycles(c)
        out = []
        for (s, e), t in zip(zip(ci.strikes[:-1], ci.strikes[1:]), cycle_turns(c, ci)):
            if abs(t) >= MIN_TURN:
                side = "left" if t > 0 else "right"
                out.append(
                    (
                        c,
                        s,
                        e,
                        f"{c.tags.get('mirrored_from', c.name)} {side} turn "
                        f"{np.degrees(abs(t)):.0f} deg{label}",
                    )
                )
        return out

    turn_loops = [tc for c in turns for tc in turning_cycles(c)]
    lo, hi = -1.0 / bend_radius, 1.0 / bend_radius
    for c in turns:
        right, left = sharpest_turn(c, detect_cycles(c).period * c.fps)
        lo, hi = min(lo, right), max(hi, left)
    has_left = any(lp[3].split(" ")[1] == "left" for lp in turn_loops)
    has_right = any(lp[3].split(" ")[1] == "right" for lp in turn_loops)
    if mirror_turns and turn_loops and has_left != has_right:
        # A mirrored clip's left strikes are the original's right strikes: detect them
        # again so every loop starts on a left-foot strike and phases line up.
        for c in turns:
            turn_loops += turning_cycles(mirror(c), " (mirrored)")
        lo, hi = min(lo, -hi), max(hi, -lo)
    for c, s, e, nm in turn_loops:
        loops.append(extract_loop(c, s, e, frames, name=nm))
        notes.append(f"turn: {nm}, frames {s}-{e}")
    loops.sort(key=lambda lp: lp.curvature)
    notes.append(
        f"turns: radius {1 / max(hi, 1e-9):.2f} m left, {1 / max(-lo, 1e-9):.2f} m right "
        f"at the sharpest (the straight stride alone bends to {bend_radius:.2f} m)"
    )
    return Gait(layer, float(fps), straight.skeleton, loops, notes, (lo, hi))
