# SPDX-License-Identifier: GPL-3.0-or-later
"""Whether a gait's clips keep the timing they were captured with. A clip played one scene
frame per recorded frame (Blender's BVH importer without Scale FPS: a 120 fps capture in a
24 fps scene plays five times slower) bakes a patch of slow-motion strides that nothing
else flags: the planner plans with it as well as with any. Said, not refused: a stylised
slow walk is the animator's to choose."""

from collections.abc import Sequence

from ..kinematics.clip import Clip
from .cycle import detect_cycles

# Seconds a stride (two steps) of people walking or running takes: about 0.5 s sprinting to
# 1.8 s strolling (the shared CMU clips: 0.45 s to 1.17 s as their cycles are found);
# outside these the clip's timing is more likely wrong than meant.
STRIDE_SECONDS = (0.35, 2.5)
# A turn clip striding this many times faster or slower than the straight one was imported
# at another rate (a 120 fps clip and a 30 fps one read at one scene rate: 4 times); a run
# and its turn clip of CMU subject 16 stride 1.8 times apart as their cycles are found.
CLIPS_APART = 2.5


def timing_warnings(straight: Clip, turns: Sequence[Clip] = ()) -> list[str]:
    """What looks wrong with the timing of a gait's clips, each said with its likely cause
    and what to do (none: nothing). Clips whose cycles cannot be found are left to the
    bake, which refuses them."""
    try:
        info = detect_cycles(straight)
    except ValueError:
        return []
    period, speed = info.period, info.speed
    lo, hi = STRIDE_SECONDS
    out = []
    if not lo <= period <= hi:
        how = "slower" if period > hi else "faster"
        out.append(
            f"the straight clip '{straight.name}' takes {period:.2f} s a stride (two steps; "
            f"{speed:.2f} m/s) played at {straight.fps:g} fps, far {how} than people walk or run "
            f"({lo:g} to {hi:g} s): was it imported at another frame rate? Blender's BVH "
            f"importer without Scale FPS plays one scene frame per recorded frame (a 120 fps "
            f"capture five times slower at 24 fps); import it again with Scale FPS on, or "
            f"with Import Mocap Clips, which keeps its timing"
        )
    for clip in turns:
        try:
            other = detect_cycles(clip).period
        except ValueError:
            continue
        if max(other, period) / min(other, period) > CLIPS_APART:
            out.append(
                f"the turn clip '{clip.name}' takes {other:.2f} s a stride, the straight clip "
                f"'{straight.name}' {period:.2f} s: were they imported at different frame "
                f"rates? The patch plays every turn at the straight clip's pace"
            )
    return out
