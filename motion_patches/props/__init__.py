# SPDX-License-Identifier: GPL-3.0-or-later
"""Props on the ground (paper Sec. 4): obstacles, footprints, tiles and cells, object patches
that carry traversal and interaction clips, and which props block a way.

Never imports bpy."""
