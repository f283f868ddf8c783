# SPDX-License-Identifier: GPL-3.0-or-later
"""Crowd benchmark of the core: plan time and memory for 10, 100 and 1,000 characters.

Prints numbers, asserts nothing. Run from the repository root:

    .venv/blender-4.5/bin/python bench/bench_crowd.py [--sizes 10,100,1000] [--json out.json]

Each size is a plaza of pillars and benches (boxes), its area growing with the crowd
(``--area`` m² per character), where two groups cross: half walk east, half west, each
10-14 m, starts and goals at least a metre from every other. The crowd is planned the way
``api.plan_crowd`` does it, on the core alone: priority by distance, each path planned
round the props and the others' standing spots (:func:`motion_patches.crowd.crowd.standing_spots`),
its motion synthesised (each a task of :func:`motion_patches.crowd.members.plan_member`, run in
this process or on Dask LocalClusters: ``--workers``, the same members checked), then
:func:`motion_patches.crowd.crowd.resolve` (idle holds, waits, re-routes) and the final check
:func:`motion_patches.crowd.crowd.conflicts_of`. Times are split into the members (path and
motion), the re-plans while resolving, resolution and the final check. Memory: the peak
traced by ``tracemalloc`` over the resolution and check (run a second time, traced; not with
``--no-trace``), and the process's peak resident size after each size (``resource``; it only
grows, sizes run in increasing order). Per character, milliseconds of each stage, and of this
process's CPU time resolving (what wall time is not on a machine shared with other work).
The scale targets: 1,000 characters in under 60 s, 10,000 in under 15 minutes within 8 GB
(``--sizes 10000 --workers 2 --no-trace --scenes ""``), resolution costing about as much per
character at 100, 1,000 and 10,000.

``--written 1000`` plans the plaza of that size again through ``api.plan_crowd`` in Blender
(the props as meshes on their footprints, the characters copies of the baked source, goals
as empties; its members on ``--written-workers`` Dask workers, 2 by default) and saves the
.blend before and after: seconds planning + resolving, writing, saving, and the file's
growth per character-second (Blender 4.5 saves uncompressed, 5.0 and later compressed).

Then two dense scenes at a 24 fps scene from the 30 fps patch (``--scenes``, the ones
tests/core/test_crowd_dense.py checks, built by it): a four-way crossing of 40 among seven
pillars on a 21 m plaza and a counter-flow of 40 through a 2 m doorway. Each is measured on
the motion as written (holds laid into the pieces, re-played at the scene's rate): the pairs
of roots closer than the spacing on some frame, the closest approach and root frames inside
a prop.
"""

import argparse
import cProfile
import io
import json
import pickle
import pstats
import resource
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
for p in (str(REPO), str(HERE), str(REPO / "tests" / "core")):
    if p not in sys.path:
        sys.path.insert(0, p)

import bench_core as core  # noqa: E402
import test_crowd_dense as dense  # noqa: E402

from motion_patches import cluster
from motion_patches.crowd import crowd, members
from motion_patches.planning.settings import PlanSettings
from motion_patches.props.environment import Environment, Obstacle

RADIUS = 0.25
SPACING = 2 * RADIUS


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--sizes",
        default="10,100,1000",
        help="crowd sizes, comma-separated ('': none, only --written)",
    )
    p.add_argument("--area", type=float, default=12.0, help="plaza m² per character")
    p.add_argument("--seed", type=int, default=17)
    p.add_argument("--max-wait", type=float, default=4.0, help="longest wait / hold, s")
    core.add_mocap_argument(p, "cmu/16_15.bvh and cmu/16_18.bvh")
    p.add_argument(
        "--profile",
        type=int,
        default=0,
        metavar="N",
        help="cProfile the crowd of size N and print the top functions",
    )
    p.add_argument(
        "--scenes",
        default="four-way,doorway",
        help="dense scenes to run after the sizes (four-way, doorway; empty: none)",
    )
    p.add_argument(
        "--workers",
        default="1,2",
        help="the members planned on Dask LocalClusters of these many worker processes, "
        "each in turn (0: in this process); the crowd is resolved once",
    )
    p.add_argument(
        "--no-trace",
        action="store_true",
        help="skip the second, traced resolution (its peak is then not measured; tracing "
        "doubles the resolution's time, long at 10,000 characters)",
    )
    p.add_argument(
        "--written",
        default="",
        help="crowd sizes also planned, resolved and written into a .blend by api.plan_crowd "
        "in Blender on the same plaza, the file saved (comma-separated; empty: none)",
    )
    p.add_argument(
        "--written-workers",
        type=int,
        default=2,
        help="Dask LocalCluster workers of the written crowds (0: in Blender's process)",
    )
    p.add_argument(
        "--no-loop-strips",
        action="store_true",
        help="written crowds: every own frame in the characters' body actions, no stretch "
        "played by the shared loop action (the file and frame_set as before it); with "
        "--written-workers 0",
    )
    p.add_argument(
        "--members-cache",
        type=Path,
        help="a folder: each size's members are kept there once planned and read back after "
        "(the same members for the resolution of another version of the code; the members' "
        "seconds are then not measured)",
    )
    p.add_argument("--json", type=Path, help="also write the full results here")
    args = p.parse_args(argv)
    if args.no_loop_strips and args.written_workers:
        p.error("--no-loop-strips keys the crowd in Blender's process: add --written-workers 0")
    args.workers = [int(w) for w in args.workers.split(",")]
    return args


def plaza(patch, n, args):
    """(environment, [(start, goal)] in priority order, plaza side): pillars and benches
    on a square of ``n * area`` m², two groups crossing it east and west."""
    rng = np.random.default_rng(args.seed + n)
    side = max(20.0, float(np.sqrt(n * args.area)))
    env = Environment(patch.side, patch.cells, RADIUS)
    core.pillar_field(env, rng, int(0.02 * side * side), 2.0, side - 2.0)
    for k in range(int(0.01 * side * side)):  # benches: 1.6 x 0.5 m boxes, any direction
        c, a = rng.uniform(2.0, side - 2.0, 2), rng.uniform(0, np.pi)
        u, v = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
        env.place(
            Obstacle(
                f"bench{k}",
                np.array(
                    [
                        c + 0.8 * u + 0.25 * v,
                        c - 0.8 * u + 0.25 * v,
                        c - 0.8 * u - 0.25 * v,
                        c + 0.8 * u - 0.25 * v,
                    ]
                ),
            )
        )
    taken, ends = np.empty((0, 2)), []
    while len(ends) < n:
        east = len(ends) % 2 == 0
        s = rng.uniform(1.0, side - 1.0, 2)
        g = s + np.array([rng.uniform(10.0, 14.0) * (1 if east else -1), rng.uniform(-3, 3)])
        pts = np.stack((s, g))
        if (g < 1.0).any() or (g > side - 1.0).any() or env.blocked(pts).any():
            continue
        if len(taken) and np.linalg.norm(taken[:, None] - pts[None], axis=2).min() < 1.0:
            continue
        taken = np.vstack((taken, pts))
        h = 0.0 if east else np.pi
        ends.append((np.r_[s, h], np.r_[g, h]))
    ends.sort(key=lambda e: -np.linalg.norm(e[1][:2] - e[0][:2]))
    return env, ends, side


def member_world(patch, env, ends):
    """The world every member of a bench crowd is planned in (the planner's defaults)."""
    return members.MemberWorld(
        patch,
        env,
        [],
        PlanSettings(radius=RADIUS),
        scene_fps=patch.gait.fps,
        rank_ends=ends,
        spot_names=[f"spot{m}" for m in range(len(ends))],
        spacing=SPACING,
    )


def member_task(ends, i, ghosts=()):
    """Member i: round the spots where the others stand still (and ``ghosts``)."""
    return members.MemberTask(i, (ends[i][0], ends[i][1], None, None), rank=i, ghosts=ghosts)


def fingerprint(answers):
    """What must not depend on where the members were planned."""
    return [
        (a.entry, a.plan.cost, a.root_track.tobytes())
        if isinstance(a, members.Member)
        else (a.entry, a.kind)
        for a in answers
    ]


def plan_members(patch, env, ends, workers):
    """(answers, seconds, cluster start seconds) of every member planned on ``workers``
    Dask worker processes (0: in this process)."""
    t0 = time.perf_counter()
    ex = cluster.executor(workers or None)
    started = time.perf_counter() - t0
    try:
        t0 = time.perf_counter()
        tasks = [member_task(ends, i) for i in range(len(ends))]
        answers = ex.map(members.plan_member, tasks, world=member_world(patch, env, ends))
        return answers, time.perf_counter() - t0, started
    finally:
        ex.close()


def run_crowd(patch, n, args):
    env, ends, side = plaza(patch, n, args)
    fps = patch.gait.fps
    ramp = members.MemberWorld(patch, env, [], PlanSettings(), scene_fps=fps).ramp
    by_workers, answers = {}, None
    cache = args.members_cache and args.members_cache / f"members_{n}_{args.seed}.pkl"
    if cache and cache.exists():  # the same members, to compare resolutions side by side
        with open(cache, "rb") as f:  # streamed: 10,000 members are 2.4 GB pickled
            answers = pickle.load(f)
        by_workers = {w: {"members_s": float("nan"), "cluster_start_s": 0.0} for w in args.workers}
    for w in args.workers if answers is None else ():
        got, secs, started = plan_members(patch, env, ends, w)
        by_workers[w] = {"members_s": secs, "cluster_start_s": started}
        if answers is None:
            answers = got
        elif fingerprint(got) != fingerprint(answers):
            raise SystemExit(f"{w} workers planned other members than {args.workers[0]}")
    if cache and not cache.exists():
        cache.parent.mkdir(parents=True, exist_ok=True)
        with open(cache, "wb") as f:
            pickle.dump(answers, f, protocol=pickle.HIGHEST_PROTOCOL)
    planned = [a for a in answers if isinstance(a, members.Member)]
    tracks = [a.root_track for a in planned]
    masks = [a.holdable for a in planned]
    index = [a.entry for a in planned]
    world = member_world(patch, env, ends)
    t = {"replan": 0.0, "replan_cpu": 0.0}

    def replan(k, discs):
        t0, c0 = time.perf_counter(), time.process_time()
        a = members.plan_member(member_task(ends, index[k], discs), world)
        t["replan"] += time.perf_counter() - t0
        t["replan_cpu"] += time.process_time() - c0
        return None if isinstance(a, members.NoPlan) else (a.root_track, a.holdable)

    wait = round(args.max_wait * fps)
    t0, c0 = time.perf_counter(), time.process_time()
    schedules, left = crowd.resolve(
        list(tracks),
        replan,
        SPACING,
        RADIUS,
        fps,
        wait,
        max(1, round(0.2 * fps)),
        ramp=ramp,
        holdable=masks,
    )
    t_resolve = time.perf_counter() - t0 - t["replan"]  # re-plans counted apart
    # this process's CPU time too: on a machine shared with other work, wall time is not
    cpu_resolve = time.process_time() - c0 - t["replan_cpu"]
    finals = [s.track for s in schedules]
    delays = [s.delay for s in schedules]
    t0 = time.perf_counter()
    final = crowd.conflicts_of(finals, delays, SPACING)
    t_check = time.perf_counter() - t0
    for c in final:  # said, not only counted: who, where they start and end, how close
        a, b = (index[c[k]] for k in ("a", "b"))
        print(
            f"  left: characters {a} and {b} {c['distance_m']:.3f} m apart on frame "
            f"{c['frame']} ({c['frames']} frames); {a} from {np.round(ends[a][0][:2], 2)} to "
            f"{np.round(ends[a][1][:2], 2)} waiting {delays[c['a']]}, {b} from "
            f"{np.round(ends[b][0][:2], 2)} to {np.round(ends[b][1][:2], 2)} waiting "
            f"{delays[c['b']]}",
            flush=True,
        )
    # memory of resolution and check, traced (a second run: tracing slows it)
    peak = float("nan")
    if not args.no_trace:
        tracemalloc.start()
        crowd.resolve(
            list(tracks),
            lambda k, d: None,
            SPACING,
            RADIUS,
            fps,
            wait,
            max(1, round(0.2 * fps)),
            ramp=ramp,
            holdable=masks,
        )
        crowd.conflicts_of(finals, delays, SPACING)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    frames = [len(s.track) + s.delay for s in schedules]
    last = by_workers[args.workers[-1]]["members_s"]
    rest = {"replans": t["replan"], "resolve": t_resolve, "check": t_check}
    return {
        "characters": n,
        "plaza_m": round(side, 1),
        "props": len(env.obstacles),
        "planned": len(planned),
        "no_path": n - len(planned),
        "holds": sum(bool(s.holds) for s in schedules),
        "waits": sum(s.delay > 0 for s in schedules),
        "rerouted": sum(s.rerouted for s in schedules),
        "conflicts_left": len(final),
        "conflicts_resolve": len(left),
        "frames_max": int(max(frames)) if frames else 0,
        "members_by_workers": {str(w): v for w, v in by_workers.items()},
        "seconds": {"members": last, **rest, "total": last + sum(rest.values())},
        "resolve_ms_per_character": 1000 * t_resolve / max(len(tracks), 1),
        "cpu_seconds": {"replans": t["replan_cpu"], "resolve": cpu_resolve},
        "ms_per_character": {
            k: 1000 * v / max(n, 1) for k, v in (("members", last), *rest.items())
        },
        "resolve_peak_mb": peak / 2**20,
        "process_max_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def blender_plaza(bpy, bb, api, env, ends, source):
    """The bench plaza built in Blender the way a user builds one: every prop a mesh
    standing on its footprint (pillars as cylinders' prisms, benches as boxes), the
    characters copies of the baked source facing their start heading, goals as empties
    facing -Y along the goal heading. Returns [(armature, goal)] in the plaza's order."""
    for ob in env.obstacles.values():
        poly = np.asarray(ob.polygon, float)
        k = len(poly)
        verts = [(x, y, z) for z in (0.0, 1.0) for x, y in poly]
        faces = [tuple(range(k))[::-1], tuple(range(k, 2 * k))]
        faces += [(i, (i + 1) % k, k + (i + 1) % k, k + i) for i in range(k)]
        mesh = bpy.data.meshes.new(ob.name)
        mesh.from_pydata(verts, [], faces)
        bpy.context.scene.collection.objects.link(bpy.data.objects.new(ob.name, mesh))
    pairs = []
    for m, (start, goal) in enumerate(ends):
        arm = bb.character(bpy, source, f"C{m:05d}", start[0], start[1])
        arm.rotation_euler = (0.0, 0.0, start[2] + np.pi / 2)  # the rest faces -Y
        pairs.append((arm, bb.goal_empty(bpy, f"G{m:05d}", goal[0], goal[1], goal[2])))
    return pairs


def peak_rss_reset():
    """Start this process's peak RSS afresh (Linux: ``/proc/self/clear_refs``), so the written
    run's peak is not the core runs' before it in the same process; False where it cannot."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
        return True
    except OSError:
        return False


def peak_rss_mb(since_reset):
    """This process's peak RSS in MB: since :func:`peak_rss_reset` (VmHWM) if it worked, else
    over its whole life."""
    if since_reset:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def cpu_seconds():
    """(this process's CPU seconds, its child processes' (a LocalCluster's nannies and
    workers, as long as they live)), user and system time together."""
    import psutil  # a dependency of distributed, which the written run needs anyway

    me = psutil.Process()
    mine = sum(me.cpu_times()[:2])
    theirs = 0.0
    for child in me.children(recursive=True):
        try:
            theirs += sum(child.cpu_times()[:2])
        except psutil.Error:  # ended meanwhile
            pass
    return mine, theirs


def run_written(n, args):
    """The plaza of ``n`` planned, resolved and written into a .blend by
    ``api.plan_crowd`` in Blender (its members on a Dask LocalCluster of ``--written-workers``
    processes), the file saved before and after: seconds by stage, the file's growth per
    character-second, conflicts left."""
    import bench_blender as bb  # Blender's part of the benches: started only when asked
    import blender_session

    if "bpy" not in sys.modules:
        blender_session.start()
    bpy = sys.modules["bpy"]
    addon = sys.modules[f"bl_ext.{blender_session.REPO_MODULE}.motion_patches"]
    api = addon.api
    if args.no_loop_strips:  # no stretch is long enough (set in this process only)
        addon.motion_patches.kinematics.loop_strips.MIN_CYCLES = 1e9
    scene, source = bb.baked_scene(bpy, api, args.mocap)
    env, ends, _ = plaza(api.storage.load_patch(scene), n, args)  # the same plaza
    pairs = blender_plaza(bpy, bb, api, env, ends, source)
    folder = Path(tempfile.mkdtemp(prefix="bench_crowd-"))
    bpy.ops.wm.save_as_mainfile(filepath=str(folder / "before.blend"))
    reset = peak_rss_reset()  # the scene built, before planning
    t0 = time.perf_counter()
    with bb.crowd_writes_timed(api) as writes, bb.crowd_stages_timed(api) as stages:
        with api.cluster_executor(args.written_workers or None) as executor:
            # the workers' CPU read while they live (their start included)
            cpu0 = cpu_seconds()
            res = api.plan_crowd(scene, pairs, frame_start=1, executor=executor)
            cpu1 = cpu_seconds()
    total = time.perf_counter() - t0
    peak_written = peak_rss_mb(reset)
    frame_set_ms = frame_set_per_armature(bpy, scene, res, len(pairs))
    overlay_ms = overlay_redrawn(bpy, addon, scene, pairs)
    t1 = time.perf_counter()
    bpy.ops.wm.save_as_mainfile(filepath=str(folder / "after.blend"))
    save = time.perf_counter() - t1
    fps = api.scene_fps(scene)
    char_s = sum((p.frame_end - p.frame_start) / fps for p in res.plans)
    grown = (folder / "after.blend").stat().st_size - (folder / "before.blend").stat().st_size
    for f in folder.iterdir():
        f.unlink()
    folder.rmdir()
    return {
        "characters": n,
        "planned": len(res.plans),
        "failed": len(res.failed),
        "conflicts_left": len(res.conflicts),
        "workers": args.written_workers,
        "seconds": {
            "plan_resolve": total - sum(writes),
            "members": stages["_plan_each"],  # of plan_resolve
            "resolve": stages["_resolve"],  # of plan_resolve, its re-plans included
            "write": sum(writes),
            "write_cpu": writes.cpu,  # Blender's process (its keys fitted elsewhere or not)
            "planned_resolved_written": total,
            "save": save,
            "with_save": total + save,
        },
        # CPU the run took, whichever process it ran in: with N cores the wall time cannot
        # be less than their sum over N
        "cpu_seconds": {"blender": cpu1[0] - cpu0[0], "workers": cpu1[1] - cpu0[1]},
        "character_seconds": char_s,
        "file_kb_per_character_second": grown / 1024 / max(char_s, 1e-9),
        "blender": bpy.app.version_string,
        # from the scene built to the crowd written, and to the file saved (Blender's save
        # has a peak of its own); the core runs before it in this process left out
        "peak_rss_written_mb": peak_written,
        "process_max_rss_mb": peak_rss_mb(reset),
        "frame_set_ms_per_armature": frame_set_ms,
        "overlay_ms": overlay_ms,
        "loop_strips": not args.no_loop_strips,
    }


def overlay_redrawn(bpy, addon, scene, pairs):
    """Milliseconds the planner overlay takes to make what it draws of the crowd written:
    first (nothing kept), then with another character active (its grid drawn instead), and
    the check every redraw makes of whether anything it draws changed (the median of 10)."""
    overlay = addon.panels.overlay
    layer = bpy.context.view_layer
    getattr(addon.api.overlay, "_drawn", {}).clear()  # (the code before kept none)
    out = {}
    for name, active in (("first", pairs[0][0]), ("another_active", pairs[-1][0])):
        layer.objects.active = active
        t0 = time.perf_counter()
        overlay.plan_buffers(scene)
        out[name] = 1000.0 * (time.perf_counter() - t0)
    checks = []
    for _ in range(10):
        t0 = time.perf_counter()
        overlay._plans_key(scene)
        checks.append(1000.0 * (time.perf_counter() - t0))
    out["every_redraw"] = float(np.median(checks))
    return out


def frame_set_per_armature(bpy, scene, res, armatures, frames=24, passes=3):
    """Milliseconds of Blender's CPU a ``scene.frame_set`` takes per armature of the crowd
    written, on ``frames`` frames spread over it (the fastest of ``passes``): what playing
    the crowd costs, whatever its actions' layout."""
    last = max(p.frame_end for p in res.plans)
    at = np.linspace(1, last, frames).round().astype(int)
    best = np.inf
    for _ in range(passes):
        t0 = time.process_time()
        for f in at:
            scene.frame_set(int(f))
        best = min(best, time.process_time() - t0)
    return 1000.0 * best / frames / max(armatures, 1)


def written_markdown(rows):
    out = [
        "| characters | Blender | workers | planned | conflicts left | plan + resolve s "
        "| of which members s | of which resolution s "
        "| write s | write CPU s, Blender's process | planned, resolved and written s "
        "| CPU s, Blender's process / workers "
        "| save s | with the save s "
        "| KB per character-second | peak RSS MB written / saved "
        "| frame_set ms per armature | loop strips |",
        "|" + "---|" * 18,
    ]
    for r in rows:
        s = r["seconds"]
        out.append(
            f"| {r['characters']} | {r['blender']} | {r['workers']} "
            f"| {r['planned']}/{r['characters']} | {r['conflicts_left']} "
            f"| {s['plan_resolve']:.1f} | {s['members']:.1f} | {s['resolve']:.1f} "
            f"| {s['write']:.1f} | {s['write_cpu']:.1f} "
            f"| {s['planned_resolved_written']:.1f} "
            f"| {r['cpu_seconds']['blender']:.1f} / {r['cpu_seconds']['workers']:.1f} "
            f"| {s['save']:.1f} | {s['with_save']:.1f} "
            f"| {r['file_kb_per_character_second']:.1f} "
            f"| {r['peak_rss_written_mb']:.0f} / {r['process_max_rss_mb']:.0f} "
            f"| {r['frame_set_ms_per_armature']:.3f} | {'on' if r['loop_strips'] else 'off'} |"
        )
    return "\n".join(out)


SCENES = {"four-way": (dense.fourway, 4.0), "doorway": (dense.doorway, 15.0)}


def run_scene(patch, name):
    """A dense scene planned as api.plan_crowd does, measured on the motion as written."""
    build, wait = SCENES[name]
    env, ends = build(patch)
    times = {}
    pieces, schedules, ramp = dense.plan_crowd(patch, env, ends, dense.SCENE_FPS, wait, times=times)
    t0 = time.perf_counter()
    roots = dense.written_roots(pieces, schedules, dense.SCENE_FPS / patch.gait.fps, ramp)
    delays = [s.delay for s in schedules]
    left = crowd.conflicts_of(roots, delays, dense.SPACING)
    closest, inside = dense.closest_and_inside(roots, delays, env)
    times["check"] = time.perf_counter() - t0
    n = len(ends)
    return {
        "scene": name,
        "characters": n,
        "planned": len(pieces),
        "max_wait_s": wait,
        "holds": sum(len(s.holds) for s in schedules),
        "waits": sum(s.delay > 0 for s in schedules),
        "rerouted": sum(s.rerouted for s in schedules),
        "conflicts_left": len(left),
        "closest_m": float(closest),
        "root_frames_in_props": inside,
        "seconds": {**times, "total": sum(times.values())},
        "ms_per_character": {k: 1000 * v / n for k, v in times.items()},
    }


def scene_markdown(rows):
    out = [
        "| scene | planned | holds | waits | re-routed | conflicts left | closest m | in props "
        "| seconds | members ms/ch | resolve ms/ch | check ms/ch |",
        "|" + "---|" * 12,
    ]
    for r in rows:
        m = r["ms_per_character"]
        out.append(
            f"| {r['scene']} | {r['planned']}/{r['characters']} | {r['holds']} | {r['waits']} "
            f"| {r['rerouted']} | {r['conflicts_left']} | {r['closest_m']:.3f} "
            f"| {r['root_frames_in_props']} | {r['seconds']['total']:.1f} | {m['members']:.0f} "
            f"| {m['resolve']:.0f} | {m['check']:.0f} |"
        )
    return "\n".join(out)


def markdown(rows):
    workers = list(rows[0]["members_by_workers"]) if rows else []
    label = {"0": "in process", "1": "1 worker"}
    cols = [f"members s, {label.get(w, w + ' workers')}" for w in workers]
    out = [
        "| characters | plaza | planned | no path | holds | waits | re-routed | conflicts left | "
        + " | ".join(cols)
        + " | re-plans s | resolve s | check s | total s | ms per character | resolve ms/ch "
        "| resolve CPU ms/ch | resolve peak MB | max RSS MB |",
        "|" + "---|" * (17 + len(cols)),
    ]
    for r in rows:
        s, by = r["seconds"], r["members_by_workers"]
        out.append(
            f"| {r['characters']} | {r['plaza_m']} m | {r['planned']} | {r['no_path']} "
            f"| {r['holds']} | {r['waits']} | {r['rerouted']} | {r['conflicts_left']} | "
            + " | ".join(f"{by[w]['members_s']:.1f}" for w in workers)
            + f" | {s['replans']:.1f} | {s['resolve']:.2f} | {s['check']:.2f} | {s['total']:.1f} "
            f"| {1000 * s['total'] / r['characters']:.0f} | {r['resolve_ms_per_character']:.0f} "
            f"| {1000 * r['cpu_seconds']['resolve'] / max(r['planned'], 1):.0f} "
            f"| {r['resolve_peak_mb']:.1f} | {r['process_max_rss_mb']:.0f} |"
        )
    return "\n".join(out)


def main(argv=None):
    args = parse_args(argv)
    missing = core.missing_mocap(Path(args.mocap))
    if missing:
        print(missing, file=sys.stderr)
        return 2
    print("bake ...", flush=True)
    patch, _, bake = core.bench_bake(Path(args.mocap))
    res = {
        "machine": core.machine(),
        "args": {k: str(v) for k, v in vars(args).items() if k != "json"},
        "crowds": [],
    }
    for n in sorted(int(s) for s in args.sizes.split(",") if s.strip()):
        print(f"{n} characters ...", flush=True)
        if n == args.profile:
            prof = cProfile.Profile()
            prof.enable()
        r = run_crowd(patch, n, args)
        if n == args.profile:
            prof.disable()
            buf = io.StringIO()
            pstats.Stats(prof, stream=buf).sort_stats("cumulative").print_stats(25)
            print(buf.getvalue())
        print(f"  {json.dumps(r)}", flush=True)
        res["crowds"].append(r)
    res["written"] = []
    for n in sorted(int(s) for s in args.written.split(",") if s):
        print(f"{n} characters written in Blender ...", flush=True)
        r = run_written(n, args)
        print(f"  {json.dumps(r)}", flush=True)
        res["written"].append(r)
    res["scenes"] = []
    for name in [s for s in args.scenes.split(",") if s]:
        print(f"{name} ...", flush=True)
        r = run_scene(patch, name)
        print(f"  {json.dumps(r)}", flush=True)
        res["scenes"].append(r)
    print()
    print(json.dumps({k: res[k] for k in ("machine", "crowds", "written", "scenes")}))
    print()
    print(markdown(res["crowds"]))
    if res["written"]:
        print()
        print(written_markdown(res["written"]))
    if res["scenes"]:
        print()
        print(scene_markdown(res["scenes"]))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(res, indent=1))
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
