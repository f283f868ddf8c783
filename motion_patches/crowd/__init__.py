# SPDX-License-Identifier: GPL-3.0-or-later
"""Crowds of independently planned characters kept apart in space and time.

Never imports bpy."""
