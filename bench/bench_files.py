# SPDX-License-Identifier: GPL-3.0-or-later
"""Benchmark of what a crowd adds to a .blend, and what it costs Blender to play.

A few characters walk about 9 m each (``api.plan_crowd``); the .blend is saved before and
after the plan and the growth is divided by the character-seconds planned. The same crowd
is planned three times from the same saved scene, its actions stored three ways:

* ``every``: a linear key on every frame of every channel (the reference the others are
  measured against: what the plan plays, as keyed);
* ``linear``: linear keys within 1e-5, else one sample per frame (the storage before
  cubic keys);
* ``cubic``: cubic keys within 0.5 degrees and 1 mm (``adapter.actions.CUBIC``, the
  default).

For each it prints KB per character-second, the largest rotation error of any bone against
``every`` on the evaluated rig (degrees: the bone's rotation relative to its parent, and
its rotation in the world), the hips' largest offset (mm), the planted foot joints' largest
offset (mm) and the feet's skate while planted (cm/s; both on the plan's contact labels)
and ``scene.frame_set`` milliseconds per armature. Cases: patch baked at 30 and 120 fps,
scenes at 24, 30 and 60 fps. The table also says how far each storage is from
``TARGET_KB`` per character-second. On Blender 4.x (whose files this reads as saved,
uncompressed: ``blend_blocks.py``) a second table splits the cubic keys' growth by what
its bytes hold: sampled frames, keys, F-curves, strings and records, the rest.

    .venv/blender-4.5/bin/python bench/bench_files.py [--json out.json] [--cases 30/30,120/24]
"""

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import blend_blocks  # noqa: E402

REPO = HERE.parent
STORAGES = ("every", "linear", "cubic")
CASES = ("30/30", "30/24", "30/60", "120/30", "120/24")  # patch fps / scene fps
TARGET_KB = 25.0  # per character-second
TARGET_DEG = 0.5


def set_storage(addon, how):
    """Make every action of a plan be stored ``how``: one of STORAGES, or "cubic A" for
    cubic keys within A degrees."""
    act_io = addon.adapter.actions
    if how.startswith("cubic "):
        act_io.COMPACT = act_io.Tolerance(np.radians(float(how.split()[1])))
        return
    act_io.COMPACT = {"every": None, "linear": act_io.LINEAR_TOL, "cubic": act_io.CUBIC}[how]


def bake(bpy, api, mocap, patch_fps, path):
    """Save a scene with the walk patch baked at ``patch_fps`` to ``path``."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = int(patch_fps), 1.0  # clips imported at it
    cmu = Path(mocap) / "cmu"
    arm, acts = api.import_mocap([cmu / "16_15.bvh", cmu / "16_18.bvh"], name="Source")
    api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    scene.motion_patches.source_armature = arm
    bpy.ops.wm.save_as_mainfile(filepath=str(path))


def plan_crowd(bpy, api, baked, scene_fps, n, storage, addon, out):
    """Open ``baked``, set the scene rate, plan ``n`` walkers with ``storage``, save to
    ``out``. Returns (scene, characters, KB added per character-second, seconds)."""
    bpy.ops.wm.open_mainfile(filepath=str(baked))
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = int(scene_fps), 1.0
    src = scene.motion_patches.source_armature
    pairs = []
    for k in range(n):
        y = 1.2 * (k - (n - 1) / 2)
        ob = src.copy()
        ob.name = f"W{k:02d}"
        ob.animation_data_clear()
        scene.collection.objects.link(ob)
        ob.location = (-4.5, y, 0.0)
        ob.rotation_euler = (0.0, 0.0, np.pi / 2)  # the rig's rest faces -Y: face +X
        goal = bpy.data.objects.new(f"Goal{k:02d}", None)
        scene.collection.objects.link(goal)
        goal.location = (4.5, y + (0.3 if k % 2 else -0.3), 0.0)
        goal.rotation_euler = (0.0, 0.0, np.pi / 2)
        pairs.append((ob, goal, {}))
    base = Path(out).with_suffix(".base.blend")  # the characters there, not yet planned
    bpy.ops.wm.save_as_mainfile(filepath=str(base), copy=True)
    kept = addon.adapter.actions.COMPACT
    set_storage(addon, storage)
    try:
        res = api.plan_crowd(scene, pairs, frame_start=1, radius=0.25, max_wait_seconds=4.0)
    finally:
        addon.adapter.actions.COMPACT = kept
    chars = [bpy.data.objects[p.character] for p in res.plans]
    seconds = sum(p.frame_end - p.frame_start for p in res.plans) / scene_fps
    bpy.ops.wm.save_as_mainfile(filepath=str(out), copy=True)
    grown = os.path.getsize(out) - os.path.getsize(base)
    return scene, chars, grown / 1024.0 / seconds, seconds


def evaluate(bpy, scene, chars):
    """Through the depsgraph, frame by frame: {name: (F, B, 4, 4) world matrices of every
    pose bone}, the bone names, the frames, and ``frame_set`` ms per armature."""
    end = int(scene.frame_end)
    frames = np.arange(int(scene.frame_start), end + 1)
    names = [pb.name for pb in chars[0].pose.bones]
    out = {c.name: np.empty((frames.size, len(names), 4, 4)) for c in chars}
    spent = 0.0
    for i, f in enumerate(frames):
        t0 = time.perf_counter()
        scene.frame_set(int(f))
        spent += time.perf_counter() - t0
        dg = bpy.context.evaluated_depsgraph_get()
        for c in chars:
            ev = c.evaluated_get(dg)
            mw = np.array(ev.matrix_world)
            for b, pb in enumerate(ev.pose.bones):
                out[c.name][i, b] = mw @ np.array(pb.matrix)
    return out, names, frames, 1000.0 * spent / frames.size / max(len(chars), 1)


def _rotation(m):
    r = m[..., :3, :3]
    return r / np.linalg.norm(r, axis=-2, keepdims=True)


def _angle(a, b):
    """Angle (degrees) between rotation matrices (..., 3, 3)."""
    rel = np.einsum("...ji,...jk->...ik", a, b)
    c = np.clip((np.trace(rel, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    return np.degrees(np.arccos(c))


def errors(ref, got, chars):
    """Largest bone rotation error (degrees) relative to its parent and in the world, and
    the largest hips offset (mm), of ``got`` against ``ref`` (:func:`evaluate`)."""
    local, world, hips = 0.0, 0.0, 0.0
    for c in chars:
        a, b = ref[c.name], got[c.name]
        parents = [
            [pb.name for pb in c.pose.bones].index(pb.parent.name) if pb.parent else -1
            for pb in c.pose.bones
        ]
        ra, rb = _rotation(a), _rotation(b)
        world = max(world, float(_angle(ra, rb).max()))
        for j, p in enumerate(parents):
            if p < 0:
                hips = max(hips, 1000.0 * float(np.abs(a[:, j, :3, 3] - b[:, j, :3, 3]).max()))
                continue
            la = np.einsum("fji,fjk->fik", ra[:, p], ra[:, j])
            lb = np.einsum("fji,fjk->fik", rb[:, p], rb[:, j])
            local = max(local, float(_angle(la, lb).max()))
    return local, world, hips


def planted_offsets(api, ref, got, chars, names, frames):
    """Largest offset (mm) of a planted foot joint of ``got`` from ``ref`` (:func:`evaluate`)
    on the frames the plan labels it planted: the foot lock holds where it held."""
    out = 0.0
    for c in chars:
        meta, arrays = api.load_plan_record(c)
        feet = [names.index(n) for n in meta["foot_names"]]
        mine = np.flatnonzero((frames >= meta["frame_start"]) & (frames <= meta["frame_end"]))
        n = min(len(mine), len(arrays["contacts"]))
        a = ref[c.name][mine[:n]][:, feet][..., :3, 3]
        b = got[c.name][mine[:n]][:, feet][..., :3, 3]
        off = np.linalg.norm(a - b, axis=-1)[np.asarray(arrays["contacts"][:n], bool)]
        out = max(out, 1000.0 * float(off.max(initial=0.0)))
    return out


def skate(api, metrics, scene, chars, mats, names, frames):
    """Mean planted-foot skate (cm/s) over the characters, from the evaluated rig."""
    fps = api.scene_fps(scene)
    out = []
    for c in chars:
        meta, arrays = api.load_plan_record(c)
        feet = [names.index(n) for n in meta["foot_names"]]
        mine = (frames >= meta["frame_start"]) & (frames <= meta["frame_end"])
        pos = mats[c.name][mine][:, feet][..., :3, 3]
        n = min(len(pos), len(arrays["contacts"]))
        out.append(metrics.foot_skate(pos[:n], fps, arrays["contacts"][:n])["mean_cm_per_s"])
    return float(np.mean(out))


def measure_case(bpy, addon, baked, scene_fps, n, tmp, angles=()):
    """Every storage of one case: {storage: row}."""
    api = addon.api
    metrics = addon.motion_patches.quality.metrics
    rows, ref = {}, None
    for how in STORAGES + tuple(f"cubic {a:g}" for a in angles):
        out = Path(tmp) / f"{how}.blend"
        scene, chars, kb, secs = plan_crowd(bpy, api, baked, scene_fps, n, how, addon, out)
        mats, names, frames, ms = evaluate(bpy, scene, chars)
        row = {
            "kb_per_char_s": kb,
            "char_s": secs,
            "frame_set_ms": ms,
            "skate_cm_s": skate(api, metrics, scene, chars, mats, names, frames),
        }
        try:  # what the growth is made of (Blender 4.x saves a format this reads)
            grown = blend_blocks.growth(out.with_suffix(".base.blend"), out)
            row["kb_per_char_s_by_kind"] = {k: b / 1024.0 / secs for k, b in grown}
        except ValueError:
            pass
        if ref is None:
            ref = mats
        row["local_deg"], row["world_deg"], row["hips_mm"] = errors(ref, mats, chars)
        row["planted_mm"] = planted_offsets(api, ref, mats, chars, names, frames)
        rows[how] = row
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--characters", type=int, default=4)
    ap.add_argument("--json")
    ap.add_argument("--angles", default="", help="cubic keys within these degrees too")
    ap.add_argument(
        "--no-loop-strips",
        action="store_true",
        help="key every stretch of straight walking in each character's own action (no "
        "shared loop action plays it): what sharing it saves",
    )
    args = ap.parse_args(argv)
    sys.path.insert(0, str(REPO / "tools"))
    import blender_session

    bpy, addon = blender_session.start()
    if args.no_loop_strips:  # no stretch is long enough (the crowd is keyed in process)
        addon.motion_patches.kinematics.loop_strips.MIN_CYCLES = 1e9
    mocap = Path(os.environ.get("MOTION_PATCHES_MOCAP", REPO.parent / "shared" / "mocap"))
    if not mocap.is_dir():
        mocap = Path("/work/shared/mocap")
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        baked = {}
        for case in args.cases.split(","):
            patch_fps, scene_fps = (int(x) for x in case.split("/"))
            if patch_fps not in baked:
                baked[patch_fps] = Path(tmp) / f"patch{patch_fps}.blend"
                bake(bpy, addon.api, mocap, patch_fps, baked[patch_fps])
            angles = [float(a) for a in args.angles.split(",") if a]
            results[case] = measure_case(
                bpy, addon, baked[patch_fps], scene_fps, args.characters, tmp, angles
            )
            print(json.dumps({case: results[case]}), flush=True)
    print(json.dumps(results, indent=1))
    head = (
        "| patch/scene fps | storage | KB per char-s | bone deg (local / world) | hips mm "
        "| planted feet mm | skate cm/s | frame_set ms/armature |"
    )
    print(head)
    print("|" + "---|" * 8)
    for case, rows in results.items():
        for how, r in rows.items():
            met = "" if r["kb_per_char_s"] <= TARGET_KB else f" (over {TARGET_KB:g})"
            print(
                f"| {case} | {how} | {r['kb_per_char_s']:.1f}{met} | {r['local_deg']:.3f} / "
                f"{r['world_deg']:.3f} | {r['hips_mm']:.2f} | {r['planted_mm']:.2f} | "
                f"{r['skate_cm_s']:.2f} | {r['frame_set_ms']:.3f} |"
            )
    # where the cubic keys' growth goes, case by case (Blender 4.x files), largest first
    by_kind = {c: rows["cubic"].get("kb_per_char_s_by_kind", {}) for c, rows in results.items()}
    first = next(iter(by_kind.values()), {})
    kinds = sorted({k for d in by_kind.values() for k in d}, key=lambda k: -first.get(k, 0.0))
    if kinds:
        print("\n| cubic, KB per char-s | " + " | ".join(by_kind) + " |")
        print("|" + "---|" * (len(by_kind) + 1))
        for k in kinds:
            print(f"| {k} | " + " | ".join(f"{d.get(k, 0.0):.1f}" for d in by_kind.values()) + " |")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
