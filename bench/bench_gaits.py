# SPDX-License-Identifier: GPL-3.0-or-later
"""Benchmark of the run layer and of gait changes (issue 19): run plans through random pillar
fields, and walk / run / walk -> run -> walk plans across random lines of chairs.

Prints numbers, asserts nothing about timing. Run from the repository root:

    .venv/blender-4.5/bin/python bench/bench_gaits.py [--layouts 20] [--lines 20] [--seed 0]

1. Bakes the walk patch (CMU 16_15 + 16_18) and the run patch (cmu16max 16_35 + 16_53,
   retargeted onto 16_15's skeleton, the left turns mirrored), as the tests do.
2. Run plans: bench_core's random pillar layouts (the same flags give the same layouts),
   planned in the run layer; plan time, nodes, metres, and foot skate without and with
   foot locking against 16_35's own.
3. Gait changes: ``--lines`` random chair lines across the way (chairs 0.5 m apart, 4 to
   16 m long, turned up to 30 degrees, the 16_06 jump a run-layer clip only), the start 5
   to 10 m before the line and the goal 5 to 10 m after it; each planned in the walk, in
   the run, and composed (:func:`motion_patches.planning.transitions.compose`); which is cheapest,
   and the time of each.
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
for p in (REPO, REPO / "bench"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

import bench_core as core  # noqa: E402

from motion_patches.kinematics import bvh, contacts, foot_lock
from motion_patches.kinematics.motion import Motion, concatenate
from motion_patches.kinematics.retarget import rig_map
from motion_patches.patch import gait as gait_mod
from motion_patches.patch import layers, locomotion_patch
from motion_patches.planning import transitions
from motion_patches.planning.planner import PlanError, SegmentPlanner, plan_motions
from motion_patches.props import object_patch as op
from motion_patches.props.environment import Environment, Obstacle
from motion_patches.quality import metrics

CHAIR = np.array([[-0.2, -0.22], [0.2, -0.22], [0.2, 0.22], [-0.2, 0.22]])
CHAIR_SPACING = 0.5  # metres between chair centres along a line


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    core.add_layout_arguments(p, layouts="random pillar layouts planned in the run layer")
    core.add_mocap_argument(p, "cmu/16_15, 16_18, 16_06 and cmu16max/16_35, 16_53 (.bvh)")
    p.add_argument("--lines", type=int, default=20, help="random chair lines (default 20)")
    p.add_argument("--json", metavar="PATH", help="also write all figures as JSON")
    return p.parse_args(argv)


def bake(mocap):
    """(walk patch, run patch, the run's straight source clip, the 16_06 jump as a
    run-layer traversal clip, seconds to bake the run)."""
    walk = bvh.read(mocap / "cmu" / "16_15.bvh")
    turn = bvh.read(mocap / "cmu" / "16_18.bvh")
    walk_patch = locomotion_patch.bake(gait_mod.build_gait("walk", walk, (turn,)))
    straight = bvh.read(mocap / "cmu16max" / "16_35.bvh")
    right = bvh.read(mocap / "cmu16max" / "16_53.bvh")
    rig = rig_map(straight.skeleton, walk.skeleton, label="clip")
    t0 = time.perf_counter()
    run_gait = gait_mod.build_gait("run", rig.clip(straight), (rig.clip(right),))
    run_patch = locomotion_patch.bake(run_gait, effort_rate=layers.effort_rate(run_gait))
    seconds = time.perf_counter() - t0
    jump = op.patch_clip_from(
        bvh.read(mocap / "cmu" / "16_06.bvh"), op.TRAVERSAL, walk_patch.gait.fps, effort=8.0
    )
    jump.layer_in = jump.layer_out = "run"
    return walk_patch, run_patch, rig.clip(straight), jump, seconds


def run_plans(patch, args):
    """bench_core's layouts planned in the run layer: one record per plan, and failures."""
    skel, fps = patch.gait.skeleton, patch.gait.fps
    records, failures = [], 0
    for n, (env, start, goal) in enumerate(core.layouts(patch, args)):
        planner = SegmentPlanner(patch, env, *args.weights)
        t0 = time.perf_counter()
        try:
            plan = planner.plan(start, goal)
        except PlanError as e:
            failures += 1
            print(f"  layout {n:3d}: no run plan: {e}")
            continue
        dt = time.perf_counter() - t0
        m = concatenate(plan_motions(patch, plan))
        m = Motion(  # as the API writes a plan: feet moving fast are not planted
            m.ground, m.root_local, m.rotations, foot_lock.still_contacts(skel, m, patch.gait.fps)
        )
        locked = Motion(
            m.ground, m.root_local, foot_lock.lock_feet(skel, m, fps=patch.gait.fps), m.contacts
        )
        rec = {
            "layout": n,
            "seconds": dt,
            "expansions": plan.expansions,
            "metres": float(np.linalg.norm(np.diff(m.ground[:, :2], axis=0), axis=1).sum()),
            "motion_seconds": (m.frames - 1) / fps,
            "frames_inside_obstacle": int(env.blocked(m.ground[:, :2]).sum()),
            "skate": metrics.foot_skate(core.foot_positions(m, skel), fps, m.contacts),
            "skate_locked": metrics.foot_skate(core.foot_positions(locked, skel), fps, m.contacts),
        }
        records.append(rec)
        print(
            f"  layout {n:3d}: {dt * 1000:7.1f} ms, {plan.expansions:6d} nodes, "
            f"{rec['metres']:5.1f} m in {rec['motion_seconds']:4.1f} s, skate "
            f"{rec['skate']['mean_cm_per_s']:.1f} cm/s ({rec['skate_locked']['mean_cm_per_s']:.1f} "
            f"locked)"
        )
    return records, failures


def chair_line(rng):
    """(chair poses, start, goal) of one random line across the way (+x)."""
    length = rng.uniform(4.0, 16.0)
    turn = np.radians(rng.uniform(-30.0, 30.0))
    centre = np.array([0.0, rng.uniform(-2.0, 2.0)])
    along = np.array([-np.sin(turn), np.cos(turn)])  # the line, across +x
    t = np.arange(-length / 2, length / 2 + 1e-9, CHAIR_SPACING)
    poses = [(*(centre + s * along), turn) for s in t]
    start = np.array([-rng.uniform(5.0, 10.0), rng.uniform(-1.0, 1.0), 0.0])
    goal = np.array([rng.uniform(5.0, 10.0), rng.uniform(-1.0, 1.0), 0.0])
    return poses, start, goal, length


def planner_of(patch, clip, poses, args):
    env = Environment(patch.side, patch.cells, args.radius)
    props = []
    for k, pose in enumerate(poses):
        o = op.ObjectPatch(f"chair{k}", CHAIR, pose=pose)
        o.add_traversal_copies(clip)
        env.place(Obstacle(o.name, o.world_footprint()))
        props.append(layers.for_layer(o, patch.layer))
    return SegmentPlanner(patch, env, *args.weights, props=props)


def gait_changes(walk_patch, run_patch, clip, args):
    """One record per random chair line: each layer's plan and the composition."""
    rng = np.random.default_rng(args.seed)
    out = []
    for n in range(args.lines):
        poses, start, goal, length = chair_line(rng)
        rec = {"line": n, "line_m": length, "start": start.tolist(), "goal": goal.tolist()}
        walk = planner_of(walk_patch, clip, poses, args)
        run = planner_of(run_patch, clip, poses, args)
        for name, planner in (("walk", walk), ("run", run)):
            t0 = time.perf_counter()
            try:
                plan = planner.plan(start, goal)
                rec[name] = {
                    "cost": plan.stats["cost_shortened"],
                    "seconds": time.perf_counter() - t0,
                    "traversals": plan.stats["traversals_used"],
                }
            except PlanError as e:
                rec[name] = {"cost": None, "seconds": time.perf_counter() - t0, "why": str(e)}
        t0 = time.perf_counter()
        try:
            mixed = transitions.compose(walk, run, start, goal)
            ms = transitions.plan_layer_motions(mixed)
            rec["walk+run"] = {
                "cost": mixed.cost,
                "seconds": time.perf_counter() - t0,
                "run_legs": mixed.stats["run_legs"],
                "ways_back": mixed.stats["compositions_tried"],
                "glitches": len(transitions.glitches(mixed, ms)),
                "frames_inside_obstacle": sum(
                    int(walk.world_env.blocked(m.ground[:, :2]).sum())
                    for p, m in zip(mixed.pieces, ms)
                    if p.kind != "traversal"
                ),
            }
        except PlanError as e:
            rec["walk+run"] = {"cost": None, "seconds": time.perf_counter() - t0, "why": str(e)}
        names = ("walk", "run", "walk+run")
        best = layers.choose([rec[k]["cost"] for k in names])
        rec["chosen"] = None if best is None else names[best]
        out.append(rec)
        print(
            f"  line {n:3d} ({length:4.1f} m): "
            + ", ".join(
                f"{k} "
                + ("-" if rec[k]["cost"] is None else f"{rec[k]['cost']:.2f}")
                + f" ({rec[k]['seconds'] * 1000:.0f} ms)"
                for k in names
            )
            + f" -> {rec['chosen']}"
        )
    return out


def markdown(res):
    r = res["run_plans"]
    t = core.stats([x["seconds"] * 1000 for x in r])
    nodes = core.stats([x["expansions"] for x in r])
    sk, skl = core.pooled_skate(r), core.pooled_skate(r, "skate_locked")
    g = res["gait_changes"]
    chosen = {k: sum(x["chosen"] == k for x in g) for k in ("walk", "run", "walk+run")}
    comp = [x["walk+run"] for x in g]
    ct = core.stats([c["seconds"] * 1000 for c in comp])
    wt = core.stats([x["walk"]["seconds"] * 1000 for x in g])
    rt = core.stats([x["run"]["seconds"] * 1000 for x in g])
    found = [c for c in comp if c["cost"] is not None]
    lines = [
        f"Machine: {res['machine']}",
        "",
        "| figure | value |",
        "|---|---|",
        f"| run bake (16_35 + 16_53) | {res['run_bake_seconds']:.2f} s |",
        f"| run plans through pillar fields | {len(r)} of {len(r) + res['run_failures']} |",
        f"| run plan time median / p95 | {t['median']:.1f} / {t['p95']:.1f} ms |",
        f"| run plan nodes median | {nodes['median']:.0f} |",
        f"| run frames with the root inside a pillar | "
        f"{sum(x['frames_inside_obstacle'] for x in r)} |",
        f"| run foot skate, planned (locked) / 16_35 | {sk['mean_cm_per_s']:.1f} "
        f"({skl['mean_cm_per_s']:.1f}) / {res['run_source_skate']:.1f} cm/s |",
        f"| chair lines: cheapest walk / run / walk+run | {chosen['walk']} / {chosen['run']} / "
        f"{chosen['walk+run']} of {len(g)} |",
        f"| walk+run composed | {len(found)} of {len(g)} lines |",
        f"| walk+run glitches / frames inside a chair (outside clips) | "
        f"{sum(c['glitches'] for c in found)} / "
        f"{sum(c['frames_inside_obstacle'] for c in found)} |",
        f"| compose time median / p95 | {ct['median']:.0f} / {ct['p95']:.0f} ms |",
        f"| walk plan / run plan time median | {wt['median']:.0f} / {rt['median']:.0f} ms |",
    ]
    return "\n".join(lines)


def main(argv=None):
    args = parse_args(argv)
    mocap = Path(args.mocap)
    missing = core.missing_mocap(mocap, ("16_15", "16_18", "16_06"))
    if missing:
        print(missing, file=sys.stderr)
        return 2
    print(core.machine())
    walk_patch, run_patch, run_src, jump, bake_s = bake(mocap)
    print(f"run patch: side {run_patch.side:.2f} m, {run_patch.segment_count} segments")
    planted, _, _ = contacts.foot_contacts(run_src)
    fj = contacts.foot_joints(run_src.skeleton)
    source = metrics.foot_skate(run_src.joint_positions()[:, fj], run_src.fps, planted)
    print("run plans:")
    records, failures = run_plans(run_patch, args)
    print("gait changes:")
    changes = gait_changes(walk_patch, run_patch, jump, args)
    res = {
        "machine": core.machine(),
        "run_bake_seconds": bake_s,
        "run_source_skate": source["mean_cm_per_s"],
        "run_plans": records,
        "run_failures": failures,
        "gait_changes": changes,
    }
    print()
    print(markdown(res))
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
