"""Locomotion patches to and from bytes (compressed npz), for the .blend and for files.

Only arrays and a JSON header go in, so a stored patch never runs code when loaded.
"""

import io
import json

import numpy as np

from .gait import Gait
from .locomotion_patch import LocomotionPatch

FORMAT = "motion_patches.locomotion_patch"
VERSION = 1
_ARRAYS = ("seg_entry", "seg_exit", "seg_scale", "seg_cycles", "seg_mask", "seg_length",
           "seg_turn", "seg_effort", "seg_pose", "pose_centres")


def patch_to_bytes(patch):
    header = {"format": FORMAT, "version": VERSION, "layer": patch.layer, "side": patch.side,
              "cells": patch.cells, "nodes": patch.nodes, "effort_rate": patch.effort_rate,
              "stats": patch.stats}
    arrays = {k: getattr(patch, k) for k in _ARRAYS}
    arrays.update(patch.gait.to_dict())
    arrays["header"] = np.array(json.dumps(header))
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return buf.getvalue()


def patch_from_bytes(data):
    """Inverse of :func:`patch_to_bytes`; ValueError on anything that is not a patch."""
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as z:
            d = {k: z[k] for k in z.files}
        header = json.loads(str(d["header"]))
    except Exception as exc:  # malformed bytes of any kind
        raise ValueError(f"not a stored locomotion patch ({exc})") from None
    if header.get("format") != FORMAT:
        raise ValueError("not a stored locomotion patch (wrong format tag)")
    if header.get("version", 0) > VERSION:
        raise ValueError(f"locomotion patch format {header['version']} is newer than this "
                         f"add-on reads ({VERSION}); update the add-on")
    gait = Gait.from_dict(d)
    return LocomotionPatch(
        header["layer"], gait, float(header["side"]), int(header["cells"]), int(header["nodes"]),
        float(header["effort_rate"]), *(d[k] for k in _ARRAYS[:8]),
        d["seg_pose"], d["pose_centres"], header["stats"])
