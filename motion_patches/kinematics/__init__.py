# SPDX-License-Identifier: GPL-3.0-or-later
"""Skeletons, clips and synthesised motion as arrays: forward kinematics, in-place
ground frames, retargeting, foot contacts and foot locking, starts and stops, compact keys.

Never imports bpy."""
