"""Baked patches stored inside the .blend (scene property group, base64 payload).

Decoded patches are cached by content hash so planning does not re-decode them.
"""

import base64
import hashlib
import json

from ..motion_patches import serialize

_cache = {}


def patch_items(scene):
    return scene.motion_patches.patches


def store_patch(scene, patch, name):
    """Save (or replace) patch ``name`` in the scene; returns the stored item."""
    data = serialize.patch_to_bytes(patch)
    items = patch_items(scene)
    item = items.get(name) or items.add()
    item.name = name
    item.layer = patch.layer
    item.payload = base64.b64encode(data).decode("ascii")
    item.stats = json.dumps(patch.stats)
    item.fps = patch.gait.fps
    _cache[hashlib.sha1(item.payload.encode()).hexdigest()] = patch
    return item


def _item(scene, name=None):
    items = patch_items(scene)
    if not len(items):
        raise ValueError("no locomotion patch is baked in this scene; bake one first")
    if name:
        item = items.get(name)
        if item is None:
            raise ValueError(f"no locomotion patch named '{name}' (have: "
                             f"{', '.join(i.name for i in items)})")
    else:
        i = scene.motion_patches.active_patch_index
        item = items[i] if 0 <= i < len(items) else items[0]
    return item


def patch_key(scene, name=None):
    """Short content hash of a stored patch: names the shared segment actions it made."""
    return hashlib.sha1(_item(scene, name).payload.encode()).hexdigest()[:12]


def load_patch(scene, name=None):
    """The stored patch ``name`` (or the active/first one); ValueError when there is none."""
    item = _item(scene, name)
    key = hashlib.sha1(item.payload.encode()).hexdigest()
    if key not in _cache:
        _cache[key] = serialize.patch_from_bytes(base64.b64decode(item.payload))
    return _cache[key]


def export_patch(scene, name, path):
    patch = load_patch(scene, name)
    with open(path, "wb") as fh:
        fh.write(serialize.patch_to_bytes(patch))


def import_patch(scene, path, name=None):
    with open(path, "rb") as fh:
        patch = serialize.patch_from_bytes(fh.read())
    return store_patch(scene, patch, name or patch.layer)
