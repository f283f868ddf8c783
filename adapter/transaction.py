# SPDX-License-Identifier: GPL-3.0-or-later
"""Writing a plan as one transaction: what can fail is checked before the first change, and
what writing changed is put back as it was when it fails anyway.

:func:`check_writable` refuses, before anything is written, what would make writing fail or
destroy user data: NLA tweak mode, frames Blender cannot hold, track names of the add-on
taken by tracks it did not make, and strips a user put on the add-on's own tracks (a
re-plan deletes those tracks). :class:`Snapshot` records a character's animation data (its
active action, every NLA track and strip, the actions they play), its plan record and the
scene's frame range; :func:`kept` restores them when the block raises, removing every action
made meanwhile. The actions a write would delete (the old connectors and root, once their
tracks are gone) are held by a fake user during the block, so they can be put back; after
a successful write, those left without a user are deleted as the write itself would.
"""

import contextlib
import json
import re

from . import compat, nla

_STRIP_FIELDS = (
    "action_frame_start",
    "action_frame_end",
    "scale",
    "repeat",
    "blend_type",
    "extrapolation",
    "blend_in",
    "blend_out",
    "use_auto_blend",
    "influence",
    "use_animated_influence",
    "mute",
    "use_reverse",
    "use_sync_length",
    "select",
)
_TRACK_FIELDS = ("mute", "is_solo", "lock", "select")
_AD_FIELDS = ("action_blend_type", "action_extrapolation", "action_influence")
_SUFFIX = re.compile(r"^(.*)\.\d{3}$")


def frame_limits(bpy):
    """(first, last) frame Blender accepts (the scene's current-frame range)."""
    p = bpy.types.Scene.bl_rna.properties["frame_current"]
    return int(p.hard_min), int(p.hard_max)


def check_writable(bpy, obj, first=None, last=None):
    """Why writing a plan on ``obj`` over frames ``first``..``last`` would fail or lose user
    data (a sentence), or None when it can be written."""
    lo, hi = frame_limits(bpy)
    if first is not None and not (lo <= first and last <= hi):
        return (
            f"frames {first}-{last} are outside what Blender holds ({lo} to {hi}): "
            f"choose a start frame between {lo} and {hi - (last - first)}"
        )
    ad = obj.animation_data
    if ad is None:
        return None
    if ad.use_tweak_mode:
        return (
            f"'{obj.name}' is in NLA tweak mode (a strip's action is being edited): leave "
            f"tweak mode (Tab in the NLA editor) and plan again"
        )
    owned = set(_owned(obj))
    for tr in ad.nla_tracks:
        if tr.name in (nla.TRACK_MOTION, nla.TRACK_ROOT, nla.TRACK_FOOT) and tr.name not in owned:
            return (
                f"'{obj.name}' has a track named '{tr.name}' that the add-on did not make "
                f"(planning names its own tracks so): rename that track"
            )
        if tr.name in owned and tr.name.startswith(nla.TRACK_PREFIX):
            for st in tr.strips:
                if not _ours(st.action, obj):
                    return (
                        f"the strip '{st.name}' (action "
                        f"'{st.action.name if st.action else 'none'}') on the add-on's "
                        f"track '{tr.name}' of '{obj.name}' was not made by the add-on and "
                        f"planning again would delete that track: move the strip to a "
                        f"track of your own"
                    )
    return None


def _owned(obj):
    try:
        return list(json.loads(obj.get(nla.TRACKS_KEY, "[]")))
    except (TypeError, ValueError):
        return []


def _ours(action, obj):
    return action is not None and (
        action.get(nla.SEGMENT_KEY) is not None or nla.made_for(action, obj)
    )


def _strip_record(st):
    rec = {k: getattr(st, k) for k in _STRIP_FIELDS if hasattr(st, k)}
    rec.update(
        name=st.name,
        action=st.action,
        frame_start=st.frame_start,
        frame_end=st.frame_end,
        slot=getattr(st, "action_slot", None),
    )
    return rec


def _track_record(tr):
    rec = {k: getattr(tr, k) for k in _TRACK_FIELDS}
    rec.update(name=tr.name, strips=[_strip_record(s) for s in tr.strips])
    return rec


def _same(tr, rec):
    """A track as recorded (its name and its strips' names, actions and frames)."""
    return (
        tr.name == rec["name"]
        and len(tr.strips) == len(rec["strips"])
        and all(
            s.name == r["name"]
            and s.action == r["action"]
            and s.frame_start == r["frame_start"]
            and s.frame_end == r["frame_end"]
            for s, r in zip(tr.strips, rec["strips"])
        )
    )


class Snapshot:
    """What planning may change on ``objects`` and ``scene``, recorded to be put back."""

    KEYS = (nla.TRACKS_KEY, nla.ACTIONS_KEY)

    def __init__(self, bpy, scene, objects, keys=()):
        self.bpy, self.scene = bpy, scene
        self.keys = self.KEYS + tuple(keys)
        self.actions = {a.as_pointer() for a in bpy.data.actions}
        self.frames = (scene.frame_start, scene.frame_end)
        self.scene_props = {k: scene.get(k) for k in keys}
        self.objects = []
        self.fake = {}
        self.made = set()  # pointers of the actions planning made for the objects
        tagged = None  # {character name: actions with that name tag}, made once if needed
        for ob in objects:
            ad = ob.animation_data
            rec = {"object": ob, "props": {k: ob.get(k) for k in self.keys}, "ad": None}
            if ad is not None:
                rec["ad"] = {k: getattr(ad, k) for k in _AD_FIELDS}
                rec["ad"].update(
                    action=ad.action,
                    slot=getattr(ad, "action_slot", None),
                    tracks=[(tr.as_pointer(), _track_record(tr)) for tr in ad.nla_tracks],
                )
                for _, t in rec["ad"]["tracks"]:
                    for s in t["strips"]:
                        self._hold(s["action"])
                self._hold(ad.action)
            if tagged is None and nla.owned_actions(ob) is None:
                tagged = nla.tagged_actions(bpy)
            for a in nla.actions_made_for(bpy, ob, tagged):
                self._hold(a)
                self.made.add(a.as_pointer())
            self.objects.append(rec)

    def _hold(self, action):
        """Keep ``action`` alive through the block (a fake user: writing deletes the
        character's old actions once no strip plays them)."""
        if action is not None and action.as_pointer() not in self.fake:
            self.fake[action.as_pointer()] = (action, action.use_fake_user)
            action.use_fake_user = True

    def _release(self):
        for action, had in self.fake.values():
            action.use_fake_user = had

    def commit(self):
        """After a successful write: the held actions get their own fake-user state back,
        the character's old actions no strip plays any more are deleted (as writing does
        when nothing is held), and new actions named ``name.001`` because the old one was
        still there take the name back."""
        self._release()
        actions = self.bpy.data.actions
        # in one batch: each removal on its own has Blender look through the whole file
        # (3,000 actions of a crowd planned again: 8.6 s)
        self.bpy.data.batch_remove(
            [a for a, _ in self.fake.values() if a.as_pointer() in self.made and a.users == 0]
        )
        renamed = {}
        for a in list(actions):
            if a.as_pointer() not in self.actions:
                m = _SUFFIX.match(a.name)
                if m and actions.get(m.group(1)) is None:
                    old, a.name = a.name, m.group(1)
                    renamed[old] = a.name
        for rec in self.objects:  # the characters keep their actions' names as they now are
            ob, owned = rec["object"], nla.owned_actions(rec["object"])
            if owned and renamed:
                ob[nla.ACTIONS_KEY] = json.dumps({k: renamed.get(v, v) for k, v in owned.items()})

    def restore(self):
        """Put everything recorded back; remove the tracks and actions made since."""
        for rec in self.objects:
            self._restore_object(rec)
        self.scene.frame_start, self.scene.frame_end = self.frames
        for k, v in self.scene_props.items():
            _set_prop(self.scene, k, v)
        self._release()
        self.bpy.data.batch_remove(
            [a for a in self.bpy.data.actions if a.as_pointer() not in self.actions]
        )

    def _restore_object(self, rec):
        ob = rec["object"]
        for k, v in rec["props"].items():
            _set_prop(ob, k, v)
        saved = rec["ad"]
        if saved is None:
            if ob.animation_data is not None:
                ob.animation_data_clear()
            return
        ad = ob.animation_data or ob.animation_data_create()
        if ad.use_tweak_mode:
            ad.use_tweak_mode = False
        before = dict(saved["tracks"])
        for tr in list(ad.nla_tracks):  # made since, or changed: removed (rebuilt below)
            old = before.get(tr.as_pointer())
            if old is None or not _same(tr, old):
                ad.nla_tracks.remove(tr)
        alive = {tr.as_pointer(): tr for tr in ad.nla_tracks}
        if saved["tracks"] and saved["tracks"][0][0] not in alive:
            # The bottom track is to be rebuilt, and Blender adds tracks only on top or
            # after another: rebuild the whole stack in its order.
            for tr in list(ad.nla_tracks):
                ad.nla_tracks.remove(tr)
            alive = {}
        prev = None
        for pointer, t in saved["tracks"]:
            tr = alive.get(pointer)
            if tr is None:
                tr = ad.nla_tracks.new(prev=prev)
                _rebuild(tr, t)
            prev = tr
        ad.action = saved["action"]
        if saved["action"] is not None and saved["slot"] is not None:
            ad.action_slot = saved["slot"]
        for k in _AD_FIELDS:
            setattr(ad, k, saved[k])


def _rebuild(tr, t):
    tr.name = t["name"]
    for s in t["strips"]:
        if s["action"] is None:
            continue
        st = tr.strips.new(s["name"], int(s["frame_start"]), s["action"])
        if s["slot"] is not None:
            compat.set_strip_slot(st, s["slot"])
        for k in _STRIP_FIELDS:
            if k in s and k not in ("use_animated_influence",):
                try:
                    setattr(st, k, s[k])
                except (AttributeError, TypeError, ValueError):
                    pass
        st.name = s["name"]
        st.frame_start = s["frame_start"]
        st.frame_end = s["frame_end"]
    for k in _TRACK_FIELDS:
        setattr(tr, k, t[k])


def _set_prop(idb, key, value):
    if value is None:
        if key in idb:
            del idb[key]
    else:
        idb[key] = value


@contextlib.contextmanager
def kept(bpy, scene, objects, keys=()):
    """Within the block ``objects``' animation data, their custom properties ``keys`` (and
    the add-on's track list), the scene's frame range and its properties ``keys`` may
    change; if the block raises, all of it is put back as it was (then the exception goes
    on); if not, :meth:`Snapshot.commit`."""
    snap = Snapshot(bpy, scene, objects, keys)
    try:
        yield snap
    except BaseException:
        snap.restore()
        raise
    snap.commit()


@contextlib.contextmanager
def made_undone_on_error(bpy, scene, collections=("objects", "armatures", "actions")):
    """When the block raises, remove the objects, armatures and actions it made (nothing
    that existed before is touched) and put the scene's frame rate back."""
    before = {c: set(getattr(bpy.data, c)) for c in collections}
    fps = (scene.render.fps, scene.render.fps_base)
    try:
        yield
    except BaseException:
        for c in collections:
            coll = getattr(bpy.data, c)
            for item in [x for x in coll if x not in before[c]]:
                coll.remove(item)
        scene.render.fps, scene.render.fps_base = fps
        raise
