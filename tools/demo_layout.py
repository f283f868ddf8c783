# SPDX-License-Identifier: GPL-3.0-or-later
"""The demo scene's layout, shared by tools/demo.py (Blender) and tools/plot_layout.py
(the README picture), so the picture always shows the demo's own pillars."""

import numpy as np

START = (0.0, 0.0, 0.0)  # x, y, heading (radians)
GOAL = (11.0, 5.0, 0.5)


def pillar_positions(seed=7, keep_clear=(START[:2], GOAL[:2])):
    """(x, y, radius) of pillars on a jittered grid, none within 1.2 m of start or goal."""
    rng = np.random.default_rng(seed)
    out = []
    for gx in np.arange(1.5, 12.0, 2.2):
        for gy in np.arange(-3.0, 8.0, 2.2):
            x, y = gx + rng.uniform(-0.5, 0.5), gy + rng.uniform(-0.5, 0.5)
            if min(np.hypot(x - a, y - b) for a, b in keep_clear) < 1.2:
                continue
            out.append((float(x), float(y), float(rng.uniform(0.18, 0.32))))
    return out
