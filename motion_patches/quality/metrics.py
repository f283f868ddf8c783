# SPDX-License-Identifier: GPL-3.0-or-later
"""Motion-quality figures an animator cares about, from per-frame positions only.

Foot skate is the horizontal speed of a foot joint on frames where it is planted (labels
from the source clip, carried through synthesis by phase), reported in cm/s and cm/frame;
measured the same way on the source clip, it gives the floor a synthesised motion is
compared against.
"""

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..kinematics import quat
from ..kinematics.clip import Clip


def foot_skate(foot_pos: np.ndarray, fps: float, planted: np.ndarray) -> dict[str, float]:
    """Skate statistics of foot joint positions (F, K, 3) with planted labels (F, K).

    A joint is scored on a frame step when it is planted on both frames of the step.
    Returns mean / p95 / max in cm/s and cm/frame and the number of scored steps.
    """
    foot_pos = np.asarray(foot_pos, float)
    planted = np.asarray(planted, bool)
    both = planted[1:] & planted[:-1]
    step = np.linalg.norm(np.diff(foot_pos[..., :2], axis=0), axis=-1)
    v = step[both] * 100.0  # cm per frame
    if v.size == 0:
        return {
            "mean_cm_per_frame": float("nan"),
            "p95_cm_per_frame": float("nan"),
            "mean_cm_per_s": float("nan"),
            "p95_cm_per_s": float("nan"),
            "max_cm_per_s": float("nan"),
            "planted_steps": 0,
        }
    return {
        "mean_cm_per_frame": float(v.mean()),
        "p95_cm_per_frame": float(np.percentile(v, 95)),
        "mean_cm_per_s": float(v.mean() * fps),
        "p95_cm_per_s": float(np.percentile(v, 95) * fps),
        "max_cm_per_s": float(v.max() * fps),
        "planted_steps": int(v.size),
    }


def distance_to_polyline(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """Distance of each point (N, 2) to a polyline (M, 2)."""
    p = np.asarray(points, float)[:, None, :]
    a = np.asarray(polyline, float)[None, :-1, :]
    b = np.asarray(polyline, float)[None, 1:, :]
    ab = b - a
    t = np.clip(np.sum((p - a) * ab, -1) / np.maximum(np.sum(ab * ab, -1), 1e-12), 0, 1)
    d = np.linalg.norm(p - (a + t[..., None] * ab), axis=-1)
    return d.min(axis=1)


def angle_difference(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """Signed smallest difference a - b of angles (radians)."""
    return (np.asarray(a) - np.asarray(b) + np.pi) % (2 * np.pi) - np.pi


def boundary_pops(
    local_rotations: np.ndarray, boundaries: Sequence[int] | np.ndarray, fps: float
) -> dict[str, float]:
    """Largest joint rotation jump (degrees) across strip boundaries, against its floor.

    ``local_rotations`` (F, J, 4); ``boundaries`` frame indices where a new strip starts.
    Returns the largest angular step at a boundary and the 99th percentile of steps
    elsewhere, so a pop shows as a boundary step far above ordinary motion.
    """
    q = np.asarray(local_rotations, float)
    steps = np.degrees(quat.angle_between(q[1:], q[:-1])).max(axis=1)  # (F-1,)
    b = np.asarray([i - 1 for i in boundaries if 1 <= i < q.shape[0]], int)
    mask = np.ones(steps.shape[0], bool)
    mask[b] = False
    return {
        "max_boundary_jump_deg": float(steps[b].max()) if b.size else 0.0,
        "p99_step_deg": float(np.percentile(steps[mask], 99)) if mask.any() else 0.0,
    }


def bone_steps(local_rotations: np.ndarray, stride: int = 1) -> np.ndarray:
    """(F - stride, J) degrees each bone turns over ``stride`` frames."""
    q = np.asarray(local_rotations, float)
    return np.degrees(quat.angle_between(q[stride:], q[:-stride]))


def source_bone_steps(
    clips: Sequence[Clip], fps: float, mirror_map: np.ndarray | None = None
) -> np.ndarray:
    """(J,) each bone's largest per-frame turn in the source ``clips`` at ``fps`` (a clip
    of another rate sampled every round(its fps / fps) frames), or its left / right
    counterpart's when ``mirror_map`` is given (a gait's mirrored loops move a left hand as
    the recorded right hand moved). What a synthesised motion's :func:`bone_steps` are
    held against: a bone stepping far faster than in any source is a spin."""
    steps: float | np.ndarray = 0.0
    for c in clips:
        stride = max(int(round(c.fps / fps)), 1)
        steps = np.maximum(steps, bone_steps(c.rotations, stride).max(axis=0))
    out = np.asarray(steps, float)
    return out if mirror_map is None else np.maximum(out, out[np.asarray(mirror_map)])


def step_ratio(
    local_rotations: np.ndarray, reference: np.ndarray, floor_deg: float = 1.0
) -> tuple[float, int]:
    """(worst ratio, joint index): the largest per-frame turn of any bone over that bone's
    ``reference`` (:func:`source_bone_steps`), steps under ``floor_deg`` counted as that
    (bones the sources barely move)."""
    r = bone_steps(local_rotations).max(axis=0) / np.maximum(reference, floor_deg)
    j = int(np.argmax(r))
    return float(r[j]), j
