# SPDX-License-Identifier: GPL-3.0-or-later
"""The only place where Blender data meets the core: actions, objects, NLA, storage.

Data flows one way: Blender data -> adapter -> core arrays -> adapter -> Blender data.
"""
