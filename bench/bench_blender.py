# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender benchmark of the write path (issue 16, the Blender rows): NLA strips and crowds.

Prints numbers next to their targets, asserts nothing. Run from the repository root with a
Blender Python (bpy from PyPI):

    .venv/blender-4.5/bin/python bench/bench_blender.py [--sections strips,crowd] [--json out.json]

Set-up (not timed): the walk patch (CMU 16_15 + 16_18) baked through the API at 30 fps in a
fresh scene, the add-on enabled as an installed extension (tools/blender_session.py).

Sections:

* ``strips``: write 1,000 NLA strips through the API write path (``api._write``, what
  ``plan_path`` and ``plan_crowd`` call after the search: strips, root trajectory, foot
  lock, plan record; the scene's frame range fitted once after the writes, as
  ``plan_crowd`` does). One plan through a slalom of pillars, 36 m, is searched and
  synthesised once, unshortened (the search's own chain of segments: many strips; the
  shortening pass would join most of them into one connector); it is then written onto
  fresh characters (copies of the source armature) until 1,000 strips
  are written. The first write creates the plan's shared segment actions, the others
  reuse them, as characters of one crowd do. Timed with the foot lock and without.
* ``crowd``: plan and write 100 characters with ``api.plan_crowd`` (the user's path: the
  Plan Crowd operator and the CLI's ``crowd`` call it): 10 x 10 characters, each walking
  about 8 m along +X in its own lane, a few pillars between the lanes' ends. Timed end
  to end (search, synthesis, staggering, writing), with its split; then planned again
  over the first crowd (its actions replaced), as a user does after a change.

Each pass is followed by its floor: Blender's own share of those writes, replayed on
fresh characters from what they made with no numpy work (the same tracks, strips and
keys), and the strips alone on the actions already made.

The strips section also prints the process's CPU time per 1,000 strips: on a machine
shared with other work it moves far less from run to run than the wall-clock time.

``--profile N`` prints the N most expensive functions (cProfile, cumulative) of each section.
"""

import argparse
import contextlib
import cProfile
import io
import json
import os
import platform
import pstats
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(REPO / "tools"))
import blender_session  # noqa: E402

SECTIONS = ("strips", "crowd")
TARGETS = {"strips_s": 1.0, "crowd_s": 10.0, "crowd_1000_s": 60.0}


def crowd_target(n):
    """Seconds a crowd of n may take: 10 for 100, 60 for 1,000 (pro rata beyond)."""
    return TARGETS["crowd_s"] if n <= 100 else TARGETS["crowd_1000_s"] * n / 1000


STRIPS = 1000
CROWD = 100


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--sections",
        default=",".join(SECTIONS),
        help=f"comma-separated sections (default all: {','.join(SECTIONS)})",
    )
    p.add_argument(
        "--mocap",
        default=os.environ.get("MOTION_PATCHES_MOCAP", str(REPO.parent / "shared" / "mocap")),
    )
    p.add_argument(
        "--crowd",
        type=int,
        default=CROWD,
        help=f"crowd characters (default {CROWD}, a multiple of 10)",
    )
    p.add_argument("--strips", type=int, default=STRIPS, help=f"strips to write (default {STRIPS})")
    p.add_argument(
        "--workers",
        type=int,
        default=0,
        metavar="N",
        help="crowd section: plan the members on a Dask LocalCluster of N worker processes "
        "(its start counted; default 0: in this process)",
    )
    p.add_argument(
        "--rotation-mode",
        default="QUATERNION",
        choices=("QUATERNION", "XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX", "AXIS_ANGLE"),
        help="rotation mode of the written characters' bones (strips section; default "
        "QUATERNION, as the BVH importer leaves them)",
    )
    p.add_argument("--json", metavar="PATH", help="also write every figure as JSON")
    p.add_argument(
        "--profile",
        type=int,
        default=0,
        metavar="N",
        help="print the N most expensive functions of each section (cProfile)",
    )
    a = p.parse_args(argv)
    a.sections = [s for s in a.sections.split(",") if s]
    bad = set(a.sections) - set(SECTIONS)
    if bad:
        p.error(f"unknown sections {sorted(bad)}; choose from {', '.join(SECTIONS)}")
    return a


def profiled(n, fn, *args, **kw):
    """fn(*args, **kw), printing the n most expensive functions when n > 0."""
    if n <= 0:
        return fn(*args, **kw)
    prof = cProfile.Profile()
    out = prof.runcall(fn, *args, **kw)
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats("cumulative").print_stats(n)
    print(s.getvalue())
    return out


# Where a write's time goes: the foot-lock solve (core), the NLA writing (adapter: strips,
# keys, the foot-lock track), and two things api._write does with the result (the whole
# skeleton's world matrices, for the root's positions in the plan record; the record).
SPLIT = ("lock_feet", "write_plan", "world_matrices", "store_plan")


def timing(fn, spent, name):
    """``fn`` adding the seconds of each call to ``spent[name]``; a call made inside
    another timed one is left to that one (``spent`` counts each second once)."""

    def timed(*a, **kw):
        if spent.get("_inside"):
            return fn(*a, **kw)
        spent["_inside"] = True
        t0 = time.perf_counter()
        try:
            return fn(*a, **kw)
        finally:
            spent[name] = spent.get(name, 0.0) + time.perf_counter() - t0
            spent["_inside"] = False

    return timed


def baked_scene(bpy, api, mocap):
    """A fresh scene at 30 fps with the walk patch baked; returns (scene, source armature)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    cmu = Path(mocap) / "cmu"
    arm, acts = api.import_mocap([cmu / "16_15.bvh", cmu / "16_18.bvh"], name="Source")
    api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    scene.motion_patches.source_armature = arm
    return scene, arm


def character(bpy, source, name, x, y):
    ob = source.copy()
    ob.name = name
    ob.animation_data_clear()
    bpy.context.scene.collection.objects.link(ob)
    ob.location = (x, y, 0.0)
    return ob


def goal_empty(bpy, name, x, y, heading):
    """An empty facing ``heading`` along its -Y axis (the add-on's goal convention)."""
    import math

    ob = bpy.data.objects.new(name, None)
    bpy.context.scene.collection.objects.link(ob)
    ob.location = (x, y, 0.0)
    ob.rotation_euler = (0.0, 0.0, heading + math.pi / 2)
    return ob


def pillar(bpy, name, x, y, r=0.25, h=2.0):
    bpy.ops.mesh.primitive_cylinder_add(radius=r, depth=h, location=(x, y, h / 2))
    bpy.context.object.name = name


def section_strips(bpy, addon, args):
    """Write one searched plan onto fresh characters until STRIPS strips are written."""
    api = addon.api
    scene, source = baked_scene(bpy, api, args.mocap)
    for n in range(10):
        pillar(bpy, f"Pillar{n}", 4.0 + 3.0 * n, 1.0 if n % 2 else -1.0)
    goal = goal_empty(bpy, "Goal", 36.0, 0.5, 0.0)
    first = character(bpy, source, "Walker000", 0.0, 0.0)
    captured = {}
    write = api._write  # plan_path calls it as api.plan._write

    def spy(*a, **kw):
        captured["args"], captured["kw"] = a, kw
        return write(*a, **kw)

    planner = addon.motion_patches.planning.planner.SegmentPlanner
    plan = planner.plan

    def unshortened(self, *a, **kw):  # the search's own chain of segments, one strip each
        return plan(self, *a, **dict(kw, shorten=False))

    api.plan._write, planner.plan = spy, unshortened
    try:
        res = api.plan_path(scene, first, goal, frame_start=1)
    finally:
        api.plan._write, planner.plan = write, plan
    pieces = len(res.pieces)
    a, kw = captured["args"], captured["kw"]
    out = {
        "rotation_mode": args.rotation_mode,
        "pieces": pieces,
        "piece_labels": res.pieces,
        "plan_frames": res.frame_end - res.frame_start + 1,
    }
    nla = addon.adapter.nla
    kw = {k: v for k, v in kw.items() if k != "fit"}
    for lock in (True, False):
        # fresh segment actions: the first write creates them, as in a new file; the
        # characters of the last pass go, so each pass writes into the same scene
        for ob in [o for o in bpy.data.objects if o.name.startswith(("W0_", "W1_"))]:
            bpy.data.objects.remove(ob)
        for act in [
            x for x in bpy.data.actions if x.get(nla.SEGMENT_KEY) or x.get(nla.CHARACTER_KEY)
        ]:
            bpy.data.actions.remove(act)
        count = -(-args.strips // pieces)
        chars = [character(bpy, source, f"W{int(lock)}_{k:03d}", 0.0, 0.0) for k in range(count)]
        for c in chars:
            for pb in c.pose.bones:
                pb.rotation_mode = args.rotation_mode

        def write_all():
            """The writes of a crowd (plan_crowd): each character's write, then the
            scene's frame range fitted once (timed too)."""
            t = []
            for c in chars:
                t0 = time.perf_counter()
                # a[8]: the request's PlanSettings, here with the foot lock on or off
                write(a[0], c, *a[2:8], a[8].replaced(foot_lock=lock), *a[9:], fit=False, **kw)
                t.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            api._fit_frame_range(scene)
            return t, time.perf_counter() - t0

        spent = {}
        parts = [
            (addon.motion_patches.kinematics.foot_lock, "lock_feet"),
            (addon.adapter.nla, "write_plan"),
            (addon.motion_patches.kinematics.motion.Motion, "world_matrices"),
            (addon.adapter.storage, "store_plan"),
        ]
        kept = [getattr(owner, name) for owner, name in parts]
        for owner, name in parts:
            setattr(owner, name, timing(getattr(owner, name), spent, name))
        try:
            t0, c0 = time.perf_counter(), time.process_time()
            per, fit = profiled(args.profile, write_all)
            total, cpu = time.perf_counter() - t0, time.process_time() - c0
        finally:
            for (owner, name), fn in zip(parts, kept):
                setattr(owner, name, fn)
        strips = sum(len(c.animation_data.nla_tracks[nla.TRACK_MOTION].strips) for c in chars)
        key = "foot_lock" if lock else "no_foot_lock"
        split = {n: spent.get(n, 0.0) for n in SPLIT}
        floor, strips_alone = blender_floor(bpy, addon, source, chars)
        out[key] = {
            "characters": count,
            "strips": strips,
            "seconds": total,
            "s_per_1000_strips": total * 1000.0 / strips,
            "cpu_s_per_1000_strips": cpu * 1000.0 / strips,
            "first_write_s": per[0],
            "later_write_ms_median": 1e3 * sorted(per[1:])[len(per[1:]) // 2],
            "fit_frame_range_s": fit,
            "split_s": split,
            "blender_floor_s_per_1000_strips": floor * 1000.0 / strips,
            "strips_alone_s_per_1000_strips": strips_alone * 1000.0 / strips,
        }
        print(
            f"  {key}: {strips} strips on {count} characters in {total:.3f} s "
            f"({out[key]['s_per_1000_strips']:.3f} s per 1,000, CPU "
            f"{out[key]['cpu_s_per_1000_strips']:.3f} s; first write "
            f"{per[0] * 1e3:.0f} ms, later {out[key]['later_write_ms_median']:.1f} ms median; "
            f"frame range fitted once {fit * 1e3:.0f} ms)\n"
            f"    split: "
            + ", ".join(f"{n} {t:.3f} s" for n, t in split.items())
            + f", the rest of api._write {total - fit - sum(split.values()):.3f} s\n"
            f"    Blender's own share, replayed without numpy: "
            f"{out[key]['blender_floor_s_per_1000_strips']:.3f} s per 1,000 (tracks, strips "
            f"and the characters' own keys; the strips alone "
            f"{out[key]['strips_alone_s_per_1000_strips']:.3f} s)",
            flush=True,
        )
    return out


def blender_floor(bpy, addon, source, chars):
    """Blender's own share of the writes just timed, replayed on fresh characters from
    what they made, with no numpy work: the same NLA tracks and strips, and each
    character's own actions (connectors, root, foot lock) keyed again from their points
    read back (``keyframe_points.add`` + ``foreach_set``, then ``convert_to_samples`` where
    the write sampled). Also the strips alone (tracks and strips on the actions already
    there). Returns (seconds for all the characters, seconds for the strips alone)."""
    import numpy as np

    compat, nla = addon.adapter.compat, addon.adapter.nla
    curve_points = addon.adapter.actions.curve_points
    own = {}  # a character's action -> [(path, index, group, sampled, co float32)]
    layout = []
    for c in chars:
        tracks = []
        for tr in c.animation_data.nla_tracks:
            strips = []
            for st in tr.strips:
                act = st.action
                if act.get(nla.CHARACTER_KEY) and act.name not in own:
                    own[act.name] = [
                        (
                            fc.data_path,
                            fc.array_index,
                            fc.group.name if fc.group else None,
                            len(fc.keyframe_points) == 0,
                            curve_points(fc).astype(np.float32).ravel(),
                        )
                        for fc in compat.fcurves(act)
                    ]
                strips.append(
                    (st.name, int(st.frame_start), act, st.action_slot, st.blend_type, st.scale)
                )
            tracks.append((tr.name, strips))
        layout.append(tracks)

    def rekey(name):
        act, slot = compat.new_action(name + " floor")
        bag = compat.channelbag(act, slot, create=True)
        groups = {}
        for path, index, group, sampled, co in own[name]:
            fc = bag.fcurves.new(path, index=index)
            if group:
                fc.group = groups.get(group) or groups.setdefault(group, bag.groups.new(group))
            n = co.size // 2
            fc.keyframe_points.add(n)
            fc.keyframe_points.foreach_set("co", co)
            if sampled:
                fc.convert_to_samples(int(co[0]), int(co[-2]) + 1)
            else:
                fc.keyframe_points.foreach_set("interpolation", np.ones(n, np.int32))
                fc.update()
        return act, slot

    def replay(keys):
        obs = [character(bpy, source, f"Floor_{k:03d}", 0.0, 0.0) for k in range(len(chars))]
        before = set(bpy.data.actions)
        t0 = time.perf_counter()
        for ob, tracks in zip(obs, layout):
            ad = ob.animation_data_create()
            for name, strips in tracks:
                tr = ad.nla_tracks.new()
                tr.name = name
                for sname, start, act, slot, blend, scale in strips:
                    if keys and act.name in own:
                        act, slot = rekey(act.name)
                    st = tr.strips.new(sname, start, act)
                    compat.set_strip_slot(st, slot)
                    st.blend_type = blend
                    if abs(scale - 1.0) > 1e-9:
                        st.scale = scale
        took = time.perf_counter() - t0
        for ob in obs:
            bpy.data.objects.remove(ob)
        for act in set(bpy.data.actions) - before:
            bpy.data.actions.remove(act)
        return took

    return replay(True), replay(False)


class _Timed(list):
    """The wall seconds of each call of a function, and its ``cpu``: this process's CPU
    seconds in them (all its threads, not the Dask workers')."""

    cpu = 0.0


@contextlib.contextmanager
def _calls_timed(api, names):
    """{name: :class:`_Timed`} of the calls of ``api.crowd``'s functions ``names`` made
    inside the ``with`` (each wrapped, then put back)."""
    kept = {n: getattr(api.crowd, n) for n in names}
    timed = {n: _Timed() for n in names}

    def wrapped(name):
        def run(*a, **kw):
            t, c = time.perf_counter(), time.process_time()
            try:
                return kept[name](*a, **kw)
            finally:
                timed[name].append(time.perf_counter() - t)
                timed[name].cpu += time.process_time() - c

        return run

    for n in names:
        setattr(api.crowd, n, wrapped(n))
    try:
        yield timed
    finally:
        for n, f in kept.items():
            setattr(api.crowd, n, f)


@contextlib.contextmanager
def crowd_writes_timed(api):
    """A :class:`_Timed` of each crowd's writes (``api.crowd._write_all``, what
    ``plan_crowd`` calls: the writes, with what is prepared for them meanwhile) made inside
    the ``with``."""
    with _calls_timed(api, ["_write_all"]) as timed:
        yield timed["_write_all"]


@contextlib.contextmanager
def crowd_stages_timed(api, names=("_plan_each", "_resolve")):
    """{name: wall seconds} of the crowd stages ``names`` (functions of ``api.crowd`` that
    ``plan_crowd`` calls: its members planned, its resolution with its re-plans) run inside
    the ``with``, filled in when it ends."""
    seconds = dict.fromkeys(names, 0.0)
    with _calls_timed(api, names) as timed:
        yield seconds
    seconds.update({n: sum(t) for n, t in timed.items()})


def _crowd_planned(api, scene, pairs, args):
    """(result, seconds, the writes' seconds) of ``api.plan_crowd`` of ``pairs``."""
    t0 = time.perf_counter()
    with crowd_writes_timed(api) as writes:
        with api.cluster_executor(args.workers or None) as executor:
            res = profiled(
                args.profile, api.plan_crowd, scene, pairs, frame_start=1, executor=executor
            )
    return res, time.perf_counter() - t0, writes


def section_crowd(bpy, addon, args):
    """plan_crowd of ``args.crowd`` characters (10 lanes per column), end to end."""
    api = addon.api
    scene, source = baked_scene(bpy, api, args.mocap)
    pairs = []
    for i in range(args.crowd // 10):
        for j in range(10):
            x0, y = 14.0 * i, 1.6 * j
            pairs.append(
                (
                    character(bpy, source, f"C{i}{j}", x0, y),
                    goal_empty(bpy, f"G{i}{j}", x0 + 8.0, y + 0.3, 0.0),
                )
            )
        pillar(bpy, f"P{i}", 14.0 * i + 11.0, -1.5)
    bpy.ops.wm.save_as_mainfile(filepath=str(Path(tempfile.gettempdir()) / "bench_crowd0.blend"))
    before = (Path(tempfile.gettempdir()) / "bench_crowd0.blend").stat().st_size
    res, total, writes = _crowd_planned(api, scene, pairs, args)
    saved = Path(tempfile.gettempdir()) / "bench_crowd1.blend"
    t1 = time.perf_counter()
    bpy.ops.wm.save_as_mainfile(filepath=str(saved))
    save_s = time.perf_counter() - t1
    fps = api.scene_fps(scene)
    char_s = sum((p.frame_end - p.frame_start) / fps for p in res.plans)
    growth = (saved.stat().st_size - before) / 1024 / max(char_s, 1e-9)
    strips = sum(len(p.strips) for p in res.plans)
    for failed in res.failed:  # said, not only counted
        print(f"  not planned: {failed}", flush=True)
    # planned again, as a user does after changing something: the file now holds the first
    # crowd's actions, which the writes replace
    again, again_s, again_writes = _crowd_planned(api, scene, pairs, args)
    out = {
        "characters": len(pairs),
        "planned": len(res.plans),
        "failed": len(res.failed),
        "conflicts": len(res.conflicts),
        "strips": strips,
        "workers": args.workers,
        "seconds": total,
        "write_seconds": sum(writes),
        "plan_seconds": total - sum(writes),
        "save_seconds": save_s,
        "file_kb_per_character_second": growth,
        "again_seconds": again_s,
        "again_write_seconds": sum(again_writes),
        "again_planned": len(again.plans),
    }
    print(
        f"  {len(res.plans)} of {len(pairs)} planned ({len(res.failed)} failed), {strips} strips "
        f"in {total:.2f} s: writing {sum(writes):.2f} s, the rest (search, synthesis, "
        f"staggering) {total - sum(writes):.2f} s"
        + (f" on {args.workers} Dask workers" if args.workers else " in process")
        + f"; saved in {save_s:.2f} s, the file grew {growth:.0f} KB per character-second; "
        f"planned again over it in {again_s:.2f} s (writing {sum(again_writes):.2f} s, "
        f"{len(again.plans)} planned)",
        flush=True,
    )
    return out


def rows(res):
    def met(ok):
        return "met" if ok else "NOT met"

    out = []
    if "strips" in res:
        s = res["strips"]
        lock, free, mode = s["foot_lock"], s["no_foot_lock"], s["rotation_mode"]
        out.append(
            (
                "write 1,000 NLA strips (api write path, foot lock on)",
                f"< {TARGETS['strips_s']:g} s",
                f"{lock['s_per_1000_strips']:.2f} s per 1,000 ({lock['strips']} strips of a "
                f"{s['pieces']}-piece plan on {lock['characters']} characters"
                + ("" if mode == "QUATERNION" else f" with {mode} bones")
                + f"; without the foot lock {free['s_per_1000_strips']:.2f} s; Blender's own "
                f"share of it {lock['blender_floor_s_per_1000_strips']:.2f} s, the strips alone "
                f"{lock['strips_alone_s_per_1000_strips']:.2f} s)",
                met(lock["s_per_1000_strips"] < TARGETS["strips_s"]),
            )
        )
    if "crowd" in res:
        c = res["crowd"]
        out.append(
            (
                f"plan and write {c['characters']:,} characters (api.plan_crowd)",
                f"< {crowd_target(c['characters']):g} s",
                f"{c['seconds']:.2f} s ({c['planned']} planned, {c['strips']} strips; "
                f"writing {c['write_seconds']:.2f} s, search + synthesis + staggering "
                f"{c['plan_seconds']:.2f} s"
                + (f" on {c['workers']} Dask workers" if c["workers"] else " in process")
                + f"; saving {c['save_seconds']:.2f} s, "
                f"{c['file_kb_per_character_second']:.0f} KB per character-second; planned "
                f"again over it {c['again_seconds']:.2f} s, writing "
                f"{c['again_write_seconds']:.2f} s)",
                met(
                    c["seconds"] < crowd_target(c["characters"]) and c["planned"] == c["characters"]
                ),
            )
        )
    return out


def markdown(table):
    lines = ["| figure | target | value | |", "|---|---|---|---|"]
    lines += [f"| {a} | {b} | {c} | {d} |" for a, b, c, d in table]
    return "\n".join(lines)


def main(argv=None):
    args = parse_args(argv)
    bpy, addon = blender_session.start()
    import numpy as np

    res = {
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {np.__version__}, "
        f"Blender {bpy.app.version_string}"
    }
    for name in args.sections:
        print(f"{name} ...", flush=True)
        res[name] = (section_strips if name == "strips" else section_crowd)(bpy, addon, args)
    table = rows(res)
    res["table"] = [dict(zip(("figure", "target", "value", "met"), r)) for r in table]
    print()
    print(json.dumps({"machine": res["machine"], "rows": res["table"]}, ensure_ascii=False))
    print()
    print(markdown(table))
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=1, default=float)
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
