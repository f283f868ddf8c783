# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender benchmark of layout checks (``api.check_layout``, the CLI's ``check``): what a check
costs beyond the plans inside it, first call and second call of an unchanged scene, and
``check`` over many .blend files in one process against one process per file.

Prints JSON and a table, asserts nothing. Run from the repository root with a Blender Python:

    .venv/blender-4.5/bin/python bench/bench_check.py [--files 20] [--json out.json]

Set-up (not timed): the walk patch (CMU 16_15 + 16_18) baked through the API at 30 fps, then
scenes built as a level designer builds them: Blender cubes and cylinders as props, goals as
empties, a walker copied from the source armature; each scene saved as a .blend file.

* ``open``: open ground, two pairs.
* ``pillars``: 40 pillars in a jittered grid between the start and the goals.
* ``gap``: two walls across the way with a 1.6 m gap between them.
* ``uturn``: a 6 m wall in front of the walker, its goal behind the wall (round its end).

Per scene, ``check`` is the wall-clock time of ``api.check_layout`` and ``plan`` the sum of
the planner's own seconds of its pairs (``plan_seconds``); the ratio is check / plan. A
first call is the first after the file is opened, with nothing of the scene kept in the
process (every footprint and planner dropped: ``scene_io.forget_footprints``,
``layout_check.forget``; the patch itself is already loaded: one file's patch is decoded
once per process, as before): its plans are the plans the check ran, both cold. Each scene
gets ``--first`` such calls, its file opened again for each, and the median of their
ratios is its figure (the range is printed beside it; the very first, the process's first
check, is in the JSON with the others). The second is the
same call again (median of ``--repeat``): it reads the scene again and answers every pair
from the figures kept for its unchanged world, so it is set against the plans it stands
for as they run warm, in the planners it keeps (``plan 2nd``: the figures dropped, the
planners kept, the check run again, median of ``--repeat``).

The machine may be shared: each call's time on the main thread's CPU clock
(``time.thread_time``; the plan's added up around ``SegmentPlanner.plan``) is printed
beside it, a ratio other processes move less than the wall clock's.

``level``: one cold check of many pairs in a level of many props (``--level PROPS,PAIRS``,
default 5,000 pillars, linked copies on a jittered 3 m grid, and 200 pairs, each from a
point of an aisle to a goal empty up to 12 m away along the aisles): what reading the
scene costs when it is large, against the plans of its pairs. Then a walker planned and
written there (``api.plan_path``, 12 m along the aisles, three times, the median): the
call against its planner's own CPU time; and a crowd of 50 walkers there
(``api.plan_crowd`` in this process, each 9.5 m along and across the aisles).

``batch``: ``blender -c motion_patches check`` over N distinct layouts (the four scenes in
turn, their goals moved 10 cm more each round, so no pair is answered from another file's
plan), each with its spec beside it, in one process (the CLI's handler given every file)
against N processes each checking one file (``python -c`` starting bpy and the add-on, as a
CI job running N commands would). Both count the start of Python, bpy and the add-on.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(REPO / "tools"))
sys.path.insert(0, str(HERE))
import blender_session  # noqa: E402

SCENES = ("open", "pillars", "gap", "uturn")
TARGET_RATIO = 1.2
MEDIANS = ("first_ratio", "first_cpu_ratio", "second_ratio", "second_cpu_ratio")


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--mocap",
        default=os.environ.get("MOTION_PATCHES_MOCAP", str(REPO.parent / "shared" / "mocap")),
    )
    p.add_argument(
        "--first", type=int, default=5, help="first (cold) calls per scene timed (median)"
    )
    p.add_argument(
        "--repeat", type=int, default=3, help="second calls and warm plans timed (median)"
    )
    p.add_argument("--files", type=int, default=20, help="files of the batch section (0: skip)")
    p.add_argument(
        "--level",
        default="5000,200",
        help="props,pairs of the level section ('' skips it)",
    )
    p.add_argument("--json", metavar="PATH", help="also write every figure as JSON")
    p.add_argument("--profile", action="store_true", help="cProfile the first calls")
    return p.parse_args(argv)


def box(bpy, name, x, y, sx, sy, h=2.0):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(x, y, h / 2))
    ob = bpy.context.object
    ob.name = name
    ob.scale = (sx, sy, h)
    return ob


def build(bpy, api, kind, source, path, shift=0.0):
    """Scene ``kind`` on the baked file: props, a walker, goals as empties (moved ``shift``
    metres along y: the batch's files differ); saved to ``path``. Returns its layout spec."""
    import math

    import numpy as np
    from bench_blender import character, goal_empty, pillar

    scene = bpy.context.scene
    for ob in [o for o in scene.objects if o is not source]:
        bpy.data.objects.remove(ob)
    character(bpy, source, "Walker", 0.0, 0.0)
    pairs = []
    if kind == "open":
        goal_empty(bpy, "Goal", 8.0, 3.0, 0.3)
        goal_empty(bpy, "Goal2", 5.0, -4.0, -1.0)
        pairs = [("Walker", "Goal"), ([0.0, 0.0, 0.0], "Goal2")]
    elif kind == "pillars":
        rng = np.random.default_rng(7)
        for n in range(40):
            i, j = divmod(n, 8)
            x, y = 2.0 + 1.6 * i, -5.6 + 1.6 * j
            x, y = x + rng.uniform(-0.3, 0.3), y + rng.uniform(-0.3, 0.3)
            pillar(bpy, f"Pillar{n:02d}", float(x), float(y))
        goal_empty(bpy, "Goal", 11.0, 2.0, 0.0)
        goal_empty(bpy, "Goal2", 10.5, -4.0, -0.5)
        pairs = [("Walker", "Goal"), ([0.0, 0.0, 0.0], "Goal2")]
    elif kind == "gap":
        box(bpy, "WallA", 4.0, 2.7, 0.2, 4.0)
        box(bpy, "WallB", 4.0, -2.7, 0.2, 4.0)
        box(bpy, "WallC", 8.0, 3.2, 0.2, 4.0)
        box(bpy, "WallD", 8.0, -2.2, 0.2, 4.0)
        goal_empty(bpy, "Goal", 11.0, 0.0, 0.0)
        goal_empty(bpy, "Goal2", 11.0, 2.0, math.pi / 2)
        pairs = [("Walker", "Goal"), ([0.0, 1.0, 0.0], "Goal2")]
    elif kind == "uturn":
        box(bpy, "Wall", 3.0, 1.0, 0.2, 6.0)
        goal_empty(bpy, "Goal", 5.0, 0.0, math.pi)
        goal_empty(bpy, "Goal2", 5.0, 2.0, 0.0)
        pairs = [("Walker", "Goal"), ([0.0, 2.0, 0.0], "Goal2")]
    for ob in scene.objects:
        if ob.type == "EMPTY":
            ob.location.y += shift
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    spec = {"radius": 0.25, "pairs": []}
    for n, (start, goal) in enumerate(pairs):
        pair = {"name": f"{kind} {n + 1}", "goal": goal}
        pair["character" if isinstance(start, str) else "start"] = start
        spec["pairs"].append(pair)
    return spec


class PlanClock:
    """Thread CPU seconds spent in ``SegmentPlanner.plan`` (the planner's own, as its
    ``plan_seconds`` are wall seconds) while installed."""

    def __init__(self, addon):
        self.cls = sys.modules[addon.__name__ + ".motion_patches.planning.planner"].SegmentPlanner
        self.plan, self.seconds = self.cls.plan, 0.0
        clock = self

        def plan(planner, *args, **kwargs):
            t0 = time.thread_time()
            try:
                return clock.plan(planner, *args, **kwargs)
            finally:
                clock.seconds += time.thread_time() - t0

        self.cls.plan = plan


def timed_check(api, bpy, spec, clock, profile=False):
    """(check wall s, plan wall s, check thread CPU s, plan thread CPU s, results)."""
    clock.seconds = 0.0
    t0, c0 = time.perf_counter(), time.thread_time()
    if profile:
        import cProfile
        import io
        import pstats

        prof = cProfile.Profile()
        results = prof.runcall(api.check_layout, bpy.context.scene, spec)
        check, cpu = time.perf_counter() - t0, time.thread_time() - c0
        s = io.StringIO()
        pstats.Stats(prof, stream=s).sort_stats("cumulative").print_stats(25)
        print(s.getvalue())
    else:
        results = api.check_layout(bpy.context.scene, spec)
        check, cpu = time.perf_counter() - t0, time.thread_time() - c0
    plan = sum(r["plan_seconds"] or 0.0 for r in results)
    return check, plan, cpu, clock.seconds, results


def section_scenes(bpy, api, args, files, clock):
    addon_name = api.__name__.rsplit(".", 1)[0]
    layout_check = sys.modules[addon_name + ".motion_patches.planning.layout_check"]
    rows = []
    for kind, (path, spec) in files.items():
        first = []
        for n in range(args.first):  # cold: the file opened, nothing of it kept
            bpy.ops.wm.open_mainfile(filepath=str(path))
            api.storage.load_patch(bpy.context.scene)  # decoded once per process, as before
            api.scene_io.forget_footprints()
            layout_check.forget()
            first.append(timed_check(api, bpy, spec, clock, args.profile and n == 0))
        res = first[-1][4]
        second = [timed_check(api, bpy, spec, clock) for _ in range(args.repeat)]
        warm = []
        for _ in range(args.repeat):  # the same plans in the kept planners, figures dropped
            layout_check.forget(planners=False)
            warm.append(timed_check(api, bpy, spec, clock))
        ratios = [t[0] / t[1] for t in first]
        cpu_ratios = [t[2] / t[3] for t in first]
        c2 = statistics.median(t[0] for t in second)
        cc2 = statistics.median(t[2] for t in second)
        p2 = statistics.median(t[1] for t in warm)
        pc2 = statistics.median(t[3] for t in warm)
        rows.append(
            {
                "scene": kind,
                "pairs": len(res),
                "reached": sum(r["reachable"] for r in res),
                "first_check_ms": statistics.median(t[0] for t in first) * 1e3,
                "first_plan_ms": statistics.median(t[1] for t in first) * 1e3,
                "first_ratio": statistics.median(ratios),
                "first_ratios": ratios,
                "first_check_cpu_ms": statistics.median(t[2] for t in first) * 1e3,
                "first_plan_cpu_ms": statistics.median(t[3] for t in first) * 1e3,
                "first_cpu_ratio": statistics.median(cpu_ratios),
                "first_cpu_ratios": cpu_ratios,
                "second_check_ms": c2 * 1e3,
                "second_plan_ms": p2 * 1e3,
                "second_ratio": c2 / p2,
                "second_check_cpu_ms": cc2 * 1e3,
                "second_plan_cpu_ms": pc2 * 1e3,
                "second_cpu_ratio": cc2 / pc2,
            }
        )
    return rows


CHILD = """
import sys
sys.path.insert(0, {tools!r})
import blender_session
bpy, addon = blender_session.start()
sys.exit(addon.cli.main(sys.argv[1:]))
"""


def batch_files(bpy, api, args, base, tmp):
    """``args.files`` distinct layouts (the four scenes in turn, goals moved 10 cm more each
    round), each with its spec beside it (NAME.layout.json)."""
    blends = []
    for n in range(args.files):
        kind = SCENES[n % len(SCENES)]
        bpy.ops.wm.open_mainfile(filepath=str(base))
        path = tmp / f"layout_{n:02d}.blend"
        spec = build(bpy, api, kind, bpy.data.objects["Source"], path, 0.1 * (n // len(SCENES)))
        (tmp / f"layout_{n:02d}.layout.json").write_text(json.dumps(spec))
        blends.append(path)
    return blends


def section_batch(blends):
    """N files checked in one process against N processes of one file each."""
    child = CHILD.format(tools=str(REPO / "tools"))
    t0 = time.perf_counter()
    one = subprocess.run(
        [sys.executable, "-c", child, "check", *map(str, blends), "--json"],
        capture_output=True,
        text=True,
    )
    one_s = time.perf_counter() - t0
    doc = json.loads(one.stdout) if one.stdout.strip() else {}
    t0 = time.perf_counter()
    codes = []
    for b in blends:
        r = subprocess.run(
            [sys.executable, "-c", child, "check", str(b)], capture_output=True, text=True
        )
        codes.append(r.returncode)
    many_s = time.perf_counter() - t0
    return {
        "files": len(blends),
        "pairs": len(doc.get("pairs", [])),
        "reused": sum(p["reused"] for p in doc.get("pairs", [])),
        "one_process_s": one_s,
        "one_process_exit": one.returncode,
        "separate_processes_s": many_s,
        "separate_exits": sorted(set(codes)),
        "speedup": many_s / one_s,
        **({"one_process_stderr": one.stderr[-400:]} if one.returncode else {}),
    }


def section_level(bpy, api, args, base, clock):
    """One cold check of ``args.level``'s pairs among its props (see the module's doc)."""
    import numpy as np
    from bench_blender import character, goal_empty, pillar

    props, pairs = (int(x) for x in args.level.split(","))
    bpy.ops.wm.open_mainfile(filepath=str(base))
    scene = bpy.context.scene
    for ob in [o for o in scene.objects if o.name != "Source"]:
        bpy.data.objects.remove(ob)
    rng = np.random.default_rng(3)
    side = int(np.ceil(np.sqrt(props)))
    first = None
    for n in range(props):
        i, j = divmod(n, side)
        x, y = 3.0 * i + rng.uniform(-0.4, 0.4), 3.0 * j + rng.uniform(-0.4, 0.4)
        if first is None:
            pillar(bpy, f"Pillar{n}", float(x), float(y))
            first = bpy.context.object
        else:  # linked copies, as a level designer duplicates a prop (Alt+D)
            ob = first.copy()
            ob.name = f"Pillar{n}"
            ob.location = (float(x), float(y), first.location.z)
            scene.collection.objects.link(ob)
    spec = {"radius": 0.25, "pairs": []}
    for k in range(pairs):
        sx, sy = (3.0 * rng.integers(0, side - 1, size=2) + 1.5).tolist()
        gx, gy = (
            3.0 * np.floor((np.array([sx, sy]) + rng.uniform(-12, 12, 2)) / 3.0) + 1.5
        ).tolist()
        goal_empty(bpy, f"Goal{k}", gx, gy, 0.0)
        spec["pairs"].append({"name": f"pair {k}", "start": [sx, sy, 0.0], "goal": f"Goal{k}"})
    addon_name = api.__name__.rsplit(".", 1)[0]
    sys.modules[addon_name + ".motion_patches.planning.layout_check"].forget()
    api.scene_io.forget_footprints()
    check, plan, cpu, plan_cpu, res = timed_check(api, bpy, spec, clock)
    walker = character(bpy, bpy.data.objects["Source"], "Walker", 1.5, 1.5)
    goal = goal_empty(bpy, "WalkerGoal", 13.5, 10.5, 0.0)
    calls = []
    for _ in range(3):
        clock.seconds = 0.0
        t0, c0 = time.perf_counter(), time.thread_time()
        api.plan_path(scene, walker, goal)
        calls.append((time.perf_counter() - t0, time.thread_time() - c0, clock.seconds))
    one = sorted(calls)[1]
    crowd = []
    for k in range(50):
        x, y = 1.5 + 6.0 * (k % 10), 4.5 + 6.0 * (k // 10)
        crowd.append(
            (
                character(bpy, bpy.data.objects["Source"], f"Crowd{k}", x, y),
                goal_empty(bpy, f"CrowdGoal{k}", x + 9.0, y + 3.0, 0.0),
            )
        )
    t0 = time.perf_counter()
    res_crowd = api.plan_crowd(scene, crowd, frame_start=1)
    crowd_s = time.perf_counter() - t0
    return {
        "props": props,
        "pairs": pairs,
        "reached": sum(bool(r["reachable"]) for r in res),
        "check_s": check,
        "plan_s": plan,
        "ratio": check / plan,
        "cpu_ratio": cpu / plan_cpu,
        "plan_path_s": one[0],
        "plan_path_cpu_s": one[1],
        "planner_cpu_s": one[2],
        "crowd_s": crowd_s,
        "crowd_planned": len(res_crowd.plans),
    }


def table(rows, batch, level=None):
    head = (
        f"{'scene':<8} {'pairs':>5} {'check 1st':>10} {'plan 1st':>9} {'ratio':>6} "
        f"{'range':>10} {'cpu':>6} {'check 2nd':>10} {'plan 2nd':>9} {'ratio':>6} {'cpu':>6}"
    )
    out = [head, "-" * len(head)]
    for r in rows:
        spread = f"{min(r['first_ratios']):.2f}-{max(r['first_ratios']):.2f}"
        out.append(
            f"{r['scene']:<8} {r['reached']}/{r['pairs']:<3} "
            f"{r['first_check_ms']:>8.1f}ms {r['first_plan_ms']:>7.1f}ms "
            f"{r['first_ratio']:>5.2f}x {spread:>10} {r['first_cpu_ratio']:>5.2f}x "
            f"{r['second_check_ms']:>8.1f}ms {r['second_plan_ms']:>7.1f}ms "
            f"{r['second_ratio']:>5.2f}x {r['second_cpu_ratio']:>5.2f}x"
        )
    m = {k: statistics.median(r[k] for r in rows) for k in MEDIANS}
    out.append(
        f"median check/plan: first {m['first_ratio']:.2f}x (cpu {m['first_cpu_ratio']:.2f}x), "
        f"second {m['second_ratio']:.2f}x (cpu {m['second_cpu_ratio']:.2f}x) "
        f"(target: at most {TARGET_RATIO}x first, 1.0x second)"
    )
    if level:
        out.append(
            f"level of {level['props']} props, {level['pairs']} pairs ({level['reached']} "
            f"reached), first check: {level['check_s']:.1f} s against its plans' "
            f"{level['plan_s']:.1f} s: {level['ratio']:.2f}x (cpu {level['cpu_ratio']:.2f}x); "
            f"a walker planned and written there: {level['plan_path_s']:.2f} s (cpu "
            f"{level['plan_path_cpu_s']:.2f} s), its planner {level['planner_cpu_s']:.3f} s; "
            f"a crowd of 50 there: {level['crowd_s']:.1f} s ({level['crowd_planned']} planned)"
        )
    if batch:
        out.append(
            f"check over {batch['files']} .blend files ({batch['pairs']} pairs): one process "
            f"{batch['one_process_s']:.1f} s (exit {batch['one_process_exit']}), "
            f"{batch['files']} processes {batch['separate_processes_s']:.1f} s "
            f"(exits {batch['separate_exits']}): {batch['speedup']:.1f}x"
        )
    return "\n".join(out), m


def main(argv=None):
    args = parse_args(argv)
    bpy, addon = blender_session.start()
    api = addon.api
    from bench_blender import baked_scene

    tmp = Path(tempfile.mkdtemp(prefix="bench_check-"))
    scene, source = baked_scene(bpy, api, args.mocap)
    base = tmp / "baked.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(base))
    files = {}
    for kind in SCENES:
        bpy.ops.wm.open_mainfile(filepath=str(base))
        src = bpy.data.objects["Source"]
        path = tmp / f"{kind}.blend"
        files[kind] = (path, build(bpy, api, kind, src, path))
    clock = PlanClock(addon)
    rows = section_scenes(bpy, api, args, files, clock)
    level = section_level(bpy, api, args, base, clock) if args.level else None
    batch = section_batch(batch_files(bpy, api, args, base, tmp)) if args.files else None
    text, medians = table(rows, batch, level)
    doc = {
        "scenes": rows,
        **{f"median_{k}": v for k, v in medians.items()},
        "target_ratio": TARGET_RATIO,
        **({"level": level} if level else {}),
        **({"batch": batch} if batch else {}),
    }
    print(json.dumps(doc, indent=1))
    print(text)
    if args.json:
        Path(args.json).write_text(json.dumps(doc, indent=1))


if __name__ == "__main__":
    main()
