# SPDX-License-Identifier: GPL-3.0-or-later
"""Planning a character's path (paper Sec. 4.1-4.4, 5): high-level tile search, the segment
search with its connectors, stitching of object patches, shortening, turns on the spot,
gait changes, props that move, and why a plan was refused.

Never imports bpy."""
