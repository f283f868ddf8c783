# SPDX-License-Identifier: GPL-3.0-or-later
"""Measures of motion and layouts that read only arrays: glitch validation, motion-quality
figures an animator cares about, layout spec files.

Never imports bpy."""
