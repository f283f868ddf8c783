# SPDX-License-Identifier: GPL-3.0-or-later
"""Foot figures from world positions alone: no planner label enters them.

The planner's skate (:func:`motion_patches.quality.metrics.foot_skate`) scores the frames
the plan labels planted, after feet moving fast are dropped from those labels; a foot that
slides fast on the floor is then not counted. A measure must not depend on the labels it
grades, so this one finds the plants itself, from the toe and ankle positions of every
frame and the frame rate:

- **planted**: the toe stays within 3 cm of its lowest height for at least 0.2 s;
  **skate** is its horizontal speed on those frames;
- **height-weighted skate** (the motion-synthesis literature's): on every frame step whose
  toe is under 2.5 cm above its lowest, the horizontal speed times ``2 - 2^(h / 2.5 cm)``
  (full weight on the floor, none at 2.5 cm);
- **pops**: a planted toe still, then one frame's jump over 1 cm, then still again;
- **swing clearance**: of every swing (the toe faster than 1 m/s for at least 0.1 s), its
  lowest height above the toe's own planted height (recorded walks stay 1.2 to 1.6 cm
  above: CMU 16_15 1.6, 02_01 1.2);
- **ankle heights** on the first and last frame against the standing height, the ankle's
  height while its foot is planted (how far a motion starts or ends on tiptoe or with a
  foot in the air).
"""

from collections.abc import Sequence

import numpy as np

from ..kinematics.clip import Clip
from ..kinematics.contacts import foot_joints, runs
from ..kinematics.retarget import roles
from ..kinematics.skeleton import Skeleton

PLANT_TOLERANCE = 0.03  # metres above the toe's lowest
PLANT_SECONDS = 0.2  # a plant lasts at least this long
WEIGHT_HEIGHT = 0.025  # metres: the height-weighted skate's cut-off
POP_JUMP = 0.01  # metres in one frame
POP_STILL = 0.0025  # metres per frame: a toe this slow is still
SWING_SPEED = 1.0  # m/s
SWING_SECONDS = 0.1


def foot_bones(skel: Skeleton) -> tuple[list[int], list[int]]:
    """([left ankle, right ankle], [left toe, right toe]) bone indices of ``skel`` by bone
    role (the foot and toe of any naming convention :func:`roles` knows; the patch's names
    otherwise). The ankle is the foot bone's head, the toe the toe bone's head. ValueError
    when neither finds them."""
    found = roles(skel)[1]
    if all(r in found for r in ("foot.L", "foot.R", "toe.L", "toe.R")):
        return [found["foot.L"], found["foot.R"]], [found["toe.L"], found["toe.R"]]
    fj = list(foot_joints(skel))
    if any(i is None for i in fj):
        raise ValueError("the skeleton has no foot and toe bones of a known naming")
    return [int(fj[0]), int(fj[2])], [int(fj[1]), int(fj[3])]


def of_clip(clip: Clip) -> dict:
    """:func:`measure` of a clip's own feet (a source recording, the floor a synthesised
    motion is held against)."""
    ankles, toes = foot_bones(clip.skeleton)
    p = clip.joint_positions()
    return measure(p[:, toes], p[:, ankles], clip.fps)


def _long_runs(flags: np.ndarray, min_frames: int) -> np.ndarray:
    """``flags`` (F,) with runs of True shorter than ``min_frames`` cleared."""
    out = np.zeros_like(flags, bool)
    starts, ends = runs(flags)
    for a, b in zip(starts, ends):
        if b - a >= min_frames:
            out[a:b] = True
    return out


def _frames(seconds: float, fps: float) -> int:
    return max(int(round(seconds * fps)), 1)


def planted(toe: np.ndarray, fps: float) -> np.ndarray:
    """(F, K) whether each toe (positions (F, K, 3)) is planted: within
    ``PLANT_TOLERANCE`` of its lowest height for at least ``PLANT_SECONDS``."""
    toe = np.asarray(toe, float)
    near = toe[..., 2] - toe[..., 2].min(axis=0) <= PLANT_TOLERANCE
    n = _frames(PLANT_SECONDS, fps)
    return np.stack([_long_runs(near[:, k], n) for k in range(near.shape[1])], axis=1)


def _stats(v: np.ndarray) -> dict[str, float]:
    if v.size == 0:
        nan = float("nan")
        return {"mean_cm_per_s": nan, "p95_cm_per_s": nan, "max_cm_per_s": nan, "steps": 0}
    return {
        "mean_cm_per_s": float(v.mean()),
        "p95_cm_per_s": float(np.percentile(v, 95)),
        "max_cm_per_s": float(v.max()),
        "steps": int(v.size),
    }


def measure(
    toe: np.ndarray,
    ankle: np.ndarray,
    fps: float,
    standing: Sequence[float] | np.ndarray | None = None,
) -> dict:
    """The figures of the module docstring from toe and ankle world positions (F, K, 3),
    K feet, at ``fps``. ``standing``: each ankle's height above its toe's floor when the
    character stands; default the median on the frames the foot is planted (a rest pose is
    no standing pose: CMU's rests its ankles 3 cm above the toes, a planted one stands 5 to
    6 cm above them).

    Lengths in cm, speeds in cm/s; ``skate`` and ``weighted_skate`` pool both feet."""
    toe, ankle = np.asarray(toe, float), np.asarray(ankle, float)
    lowest = toe[..., 2].min(axis=0)  # (K,)
    h = toe[..., 2] - lowest  # (F, K) toe above its lowest
    plant = planted(toe, fps)
    step = np.diff(toe, axis=0)  # (F-1, K, 3)
    hstep = np.linalg.norm(step[..., :2], axis=-1)  # metres per frame
    speed = hstep * fps * 100.0  # cm/s
    both = plant[1:] & plant[:-1]

    # height-weighted skate: on steps whose toe is under the cut-off (mean of the two frames)
    hm = 0.5 * (h[1:] + h[:-1])
    low = hm < WEIGHT_HEIGHT
    weighted = speed * (2.0 - np.power(2.0, hm / WEIGHT_HEIGHT))

    # pops: still, one jump over POP_JUMP, still again, all on planted frames
    jump = np.linalg.norm(step, axis=-1)
    pops, worst = 0, 0.0
    for i in range(1, jump.shape[0] - 1):
        for k in range(jump.shape[1]):
            if (
                jump[i, k] > POP_JUMP
                and jump[i - 1, k] < POP_STILL
                and jump[i + 1, k] < POP_STILL
                and plant[i - 1 : i + 3, k].all()
            ):
                pops += 1
                worst = max(worst, float(jump[i, k]))

    # swing clearance: the lowest toe height, above its planted height, of each swing
    swing_min = []
    n_swing = _frames(SWING_SECONDS, fps)
    for k in range(toe.shape[1]):
        base = float(np.median(h[plant[:, k], k])) if plant[:, k].any() else 0.0
        starts, ends = runs(speed[:, k] > SWING_SPEED * 100.0)
        for a, b in zip(starts, ends):
            if b - a >= n_swing:
                # steps a..b-1 span frames a..b; the clearance of the frames in flight
                swing_min.append(float(h[a : b + 1, k].min() - base))
    clearance = np.asarray(swing_min) * 100.0

    # ankle heights on the first and last frame, above the toe's floor, against standing
    ah = ankle[..., 2] - lowest  # (F, K)
    if standing is None:
        standing = [
            float(np.median(ah[plant[:, k], k])) if plant[:, k].any() else float("nan")
            for k in range(ah.shape[1])
        ]
    standing = np.asarray(standing, float)
    ends_off = np.abs(np.stack((ah[0], ah[-1])) - standing[None]) * 100.0  # (2, K)

    return {
        "planted_fraction": float(plant.mean()),
        "skate": _stats(speed[both]),
        "weighted_skate": _stats(weighted[low]),
        "pops": pops,
        "max_pop_cm": worst * 100.0,
        "swings": int(clearance.size),
        "min_swing_clearance_cm": float(clearance.min()) if clearance.size else float("nan"),
        "standing_ankle_cm": (standing * 100.0).tolist(),
        "first_ankle_cm": (ah[0] * 100.0).tolist(),
        "last_ankle_cm": (ah[-1] * 100.0).tolist(),
        "max_end_ankle_off_cm": float(np.nanmax(ends_off)) if np.isfinite(ends_off).any() else 0.0,
    }


def summary(m: dict) -> str:
    """One line of :func:`measure`'s figures for reports."""
    return (
        f"skate {m['skate']['mean_cm_per_s']:.1f} cm/s (p95 {m['skate']['p95_cm_per_s']:.1f}), "
        f"weighted {m['weighted_skate']['mean_cm_per_s']:.1f} cm/s, {m['pops']} pops, "
        f"swing clearance {m['min_swing_clearance_cm']:.1f} cm, end ankles off standing "
        f"{m['max_end_ankle_off_cm']:.1f} cm"
    )
