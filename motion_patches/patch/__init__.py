# SPDX-License-Identifier: GPL-3.0-or-later
"""The locomotion patch of a layer (paper Sec. 3, 5, 6): gait cycles and loops, curve
following, the tilable square of segments, layers and blends between them, patch files.

Never imports bpy."""
