# SPDX-License-Identifier: GPL-3.0-or-later
"""Benchmark of the pure-numpy core: bake, plan through random pillar fields, placement.

Prints numbers, asserts nothing about timing. Run from the repository root:

    .venv/blender-4.5/bin/python bench/bench_core.py [--layouts 20] [--seed 0] [--json out.json]

1. Bakes the walk patch from CMU 16_15 (straight) and 16_18 (left turn, mirrored for right).
2. For ``--layouts`` random layouts: a square field of random 12-sided pillars and one
   start/goal pair 8-20 m apart (both clear of every pillar by the character's radius),
   plans with :class:`SegmentPlanner`, synthesises the motion of every piece, and measures
   plan time, nodes expanded, path length, occlusion computations and foot skate: the
   planner-labelled skate and the label-free measure (motion_patches.quality.foot_measure).
3. The source clip's own foot skate by both (the floor a synthesised motion is compared
   against).
4. Placement: placing and moving obstacles in a scene of 10 and of 1,000 obstacles.

A Markdown table of the figures is printed at the end (see bench/README.md for what each
number means); ``--json PATH`` also writes every figure and per-plan record as JSON.
"""

import argparse
import cProfile
import io
import json
import os
import platform
import pstats
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from motion_patches.kinematics import bvh, contacts, foot_lock
from motion_patches.kinematics import clip as clip_mod
from motion_patches.kinematics.motion import Motion, concatenate
from motion_patches.patch import gait as gait_mod
from motion_patches.patch import locomotion_patch
from motion_patches.planning.planner import PlanError, SegmentPlanner, plan_motions
from motion_patches.planning.settings import PLANNING as DEFAULTS
from motion_patches.props.environment import Environment, Obstacle
from motion_patches.quality import foot_measure, metrics

WEIGHTS = tuple(DEFAULTS[k] for k in ("alpha", "beta", "gamma"))

PILLAR_SIDES = 12


MOCAP_DEFAULT = os.environ.get("MOTION_PATCHES_MOCAP", str(REPO.parent / "shared" / "mocap"))


def add_layout_arguments(p, layouts="random layouts to plan", seed="random seed of the layouts"):
    """The arguments :func:`layouts` reads (layouts, seed, density, field) and the planning
    ones every bench takes (radius, weights): one definition for bench_core, bench_paths
    and bench_speed, so the same flags give the same layouts everywhere."""
    p.add_argument("--layouts", type=int, default=20, help=f"{layouts} (default 20)")
    p.add_argument("--seed", type=int, default=0, help=f"{seed} (default 0)")
    p.add_argument(
        "--density",
        type=float,
        default=0.1,
        help="pillars per square metre of the random fields (default 0.1)",
    )
    p.add_argument(
        "--field",
        type=float,
        default=30.0,
        help="side of the square random pillar fields in metres (default 30)",
    )
    p.add_argument(
        "--radius",
        type=float,
        default=DEFAULTS["radius"],
        help=f"character radius (default {DEFAULTS['radius']:g} m)",
    )
    p.add_argument(
        "--weights",
        type=float,
        nargs=3,
        default=WEIGHTS,
        metavar=("ALPHA", "BETA", "GAMMA"),
        help="Eq. 5 weights (default %s)" % " ".join(f"{w:g}" for w in WEIGHTS),
    )


def machine():
    """The machine line every bench prints first."""
    return (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {np.__version__}"
    )


def add_mocap_argument(p, holding):
    p.add_argument("--mocap", default=MOCAP_DEFAULT, help=f"folder holding {holding}")


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_layout_arguments(p)
    add_mocap_argument(p, "cmu/16_15.bvh and cmu/16_18.bvh")
    p.add_argument("--json", metavar="PATH", help="also write all figures as JSON")
    p.add_argument(
        "--profile",
        type=int,
        default=0,
        metavar="N",
        help="run cProfile over the first N plans and print the top functions",
    )
    return p.parse_args(argv)


# -- helpers ------------------------------------------------------------------------------


def pillar(name, x, y, r, sides=PILLAR_SIDES):
    a = np.linspace(0.0, 2.0 * np.pi, sides + 1)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def pillar_field(env, rng, count, lo, hi, prefix="p"):
    for n in range(count):
        x, y = rng.uniform(lo, hi, 2)
        env.place(pillar(f"{prefix}{n}", x, y, rng.uniform(0.2, 0.4)))


def start_goal(env, rng, field, dmin=8.0, dmax=20.0, inset=1.0, tries=10_000):
    """A start and goal (x, y, heading) dmin..dmax apart, inside the field, both clear."""
    for _ in range(tries):
        s = rng.uniform(inset, field - inset, 2)
        ang, d = rng.uniform(-np.pi, np.pi), rng.uniform(dmin, dmax)
        g = s + d * np.array([np.cos(ang), np.sin(ang)])
        if np.any(g < inset) or np.any(g > field - inset):
            continue
        if env.blocked(np.stack((s, g))).any():
            continue
        return (np.r_[s, rng.uniform(-np.pi, np.pi)], np.r_[g, rng.uniform(-np.pi, np.pi)])
    raise RuntimeError("no clear start/goal pair found; lower --density")


def layouts(patch, args):
    """The random layouts, in order: (environment, start, goal) per layout, ``args.layouts``
    of them from ``args.seed``. Every bench that says "bench_core's layouts" takes them
    from here, so the same seed gives the same layouts everywhere."""
    rng = np.random.default_rng(args.seed)
    count = int(round(args.density * args.field**2))
    for _ in range(args.layouts):
        env = Environment(patch.side, patch.cells, args.radius)
        pillar_field(env, rng, count, 0.0, args.field)
        start, goal = start_goal(env, rng, args.field)
        yield env, start, goal


def missing_mocap(mocap, names=("16_15", "16_18")):
    """The message for a missing clip of the walk patch, or None when all are there."""
    for name in names:
        path = Path(mocap) / "cmu" / f"{name}.bvh"
        if not path.is_file():
            return f"bench: {path} not found (use --mocap or MOTION_PATCHES_MOCAP)"
    return None


def stats(values):
    v = np.asarray(values, float)
    if v.size == 0:
        return {
            "mean": float("nan"),
            "median": float("nan"),
            "p95": float("nan"),
            "max": float("nan"),
            "n": 0,
        }
    return {
        "mean": float(v.mean()),
        "median": float(np.median(v)),
        "p95": float(np.percentile(v, 95)),
        "max": float(v.max()),
        "n": int(v.size),
    }


def foot_positions(motion, skel):
    return motion.world_matrices(skel)[:, contacts.foot_joints(skel)][..., :3, 3]


def pooled_skate(records, key="skate"):
    """Skate over every scored step of every path (weighted by planted steps)."""
    records = [{"skate": r[key]} for r in records]
    steps = np.array([r["skate"]["planted_steps"] for r in records], float)
    if steps.sum() == 0:
        return {
            "mean_cm_per_frame": float("nan"),
            "mean_cm_per_s": float("nan"),
            "worst_path_mean_cm_per_s": float("nan"),
            "planted_steps": 0,
        }
    per_frame = np.array([r["skate"]["mean_cm_per_frame"] for r in records])
    per_s = np.array([r["skate"]["mean_cm_per_s"] for r in records])
    ok = steps > 0
    return {
        "mean_cm_per_frame": float(np.sum(per_frame[ok] * steps[ok]) / steps.sum()),
        "mean_cm_per_s": float(np.sum(per_s[ok] * steps[ok]) / steps.sum()),
        "worst_path_mean_cm_per_s": float(per_s[ok].max()),
        "planted_steps": int(steps.sum()),
    }


def feet(motion, skel, fps):
    """The label-free foot figures (:mod:`motion_patches.quality.foot_measure`) of a motion:
    its toes and ankles (by bone role) in the world."""
    ankles, toes = foot_measure.foot_bones(skel)
    w = motion.world_matrices(skel)[..., :3, 3]
    return foot_measure.measure(w[:, toes], w[:, ankles], fps)


def pooled_feet(figures):
    """:func:`feet` of many paths together: skate and weighted skate over every scored step
    (weighted by steps), pops summed, the lowest swing clearance and the largest end-ankle
    offset of any path, and the worst path's mean skate."""

    def pool(key):
        steps = np.array([f[key]["steps"] for f in figures], float)
        mean = np.array([f[key]["mean_cm_per_s"] for f in figures])
        ok = steps > 0
        if not ok.any():
            return float("nan"), float("nan")
        return float(np.sum(mean[ok] * steps[ok]) / steps.sum()), float(mean[ok].max())

    skate, worst = pool("skate")
    weighted, worst_w = pool("weighted_skate")
    clear = [f["min_swing_clearance_cm"] for f in figures if f["swings"]]
    return {
        "skate_cm_per_s": skate,
        "worst_path_skate_cm_per_s": worst,
        "weighted_skate_cm_per_s": weighted,
        "worst_path_weighted_skate_cm_per_s": worst_w,
        "pops": int(sum(f["pops"] for f in figures)),
        "paths_with_pops": int(sum(f["pops"] > 0 for f in figures)),
        "min_swing_clearance_cm": float(min(clear)) if clear else float("nan"),
        "max_end_ankle_off_cm": float(max(f["max_end_ankle_off_cm"] for f in figures)),
    }


def feet_text(p, source):
    """A report cell: pooled label-free figures beside the source clip's by the same measure."""
    return (
        f"skate {p['skate_cm_per_s']:.1f} cm/s (worst path {p['worst_path_skate_cm_per_s']:.1f}), "
        f"height-weighted {p['weighted_skate_cm_per_s']:.1f} cm/s, {p['pops']} one-frame pops, "
        f"lowest swing clearance {p['min_swing_clearance_cm']:.1f} cm, end ankles within "
        f"{p['max_end_ankle_off_cm']:.1f} cm of standing; source clip: skate "
        f"{source['skate']['mean_cm_per_s']:.1f} cm/s, height-weighted "
        f"{source['weighted_skate']['mean_cm_per_s']:.1f} cm/s, {source['pops']} pops, "
        f"swing clearance {source['min_swing_clearance_cm']:.1f} cm"
    )


# -- sections -----------------------------------------------------------------------------


def bench_bake(mocap):
    straight = bvh.read(mocap / "cmu" / "16_15.bvh")
    turn = bvh.read(mocap / "cmu" / "16_18.bvh")
    t0 = time.perf_counter()
    gait = gait_mod.build_gait("walk", straight, (turn,))
    t1 = time.perf_counter()
    patch = locomotion_patch.bake(gait)
    t2 = time.perf_counter()
    st = patch.stats
    return (
        patch,
        straight,
        {
            "gait_seconds": t1 - t0,
            "bake_seconds": t2 - t1,
            "candidates": st["candidates"],
            "kept": st["kept"],
            "culled": st["culled"],
            "culled_by": st["culled_by"],
            "side_m": patch.side,
            "cells": patch.cells,
            "nodes": patch.nodes,
            "fps": gait.fps,
            "cycle_frames": gait.frames,
            "cycle_distance_m": gait.cycle_distance,
            "loops": len(gait.loops),
        },
    )


def bench_source_skate(straight, fps):
    src = clip_mod.resample(straight, fps)
    con, _, _ = contacts.foot_contacts(src)
    fj = contacts.foot_joints(src.skeleton)
    return metrics.foot_skate(src.joint_positions()[:, fj], fps, con)


def bench_plans(patch, args, profiler=None, reference=None):
    """Plans on the random layouts, measured; ``reference`` (J,): each bone's largest
    per-frame turn in the source clips (metrics.source_bone_steps), for the spin ratio."""
    count = int(round(args.density * args.field**2))
    alpha, beta, gamma = args.weights
    skel, fps = patch.gait.skeleton, patch.gait.fps
    records, failures = [], []
    for layout, (env, start, goal) in enumerate(layouts(patch, args)):
        planner = SegmentPlanner(patch, env, alpha, beta, gamma)
        prof = profiler if profiler is not None and layout < args.profile else None
        if prof:
            prof.enable()
        t0 = time.perf_counter()
        try:
            plan = planner.plan(start, goal)
        except PlanError as e:
            dt = time.perf_counter() - t0
            if prof:
                prof.disable()
            t1 = time.perf_counter()
            try:  # the same pair when any goal facing will do (a layout test's option)
                planner.plan(start, np.array([goal[0], goal[1], np.nan]))
                any_facing = time.perf_counter() - t1
            except PlanError:
                any_facing = None
            failures.append(
                {
                    "layout": layout,
                    "seconds": dt,
                    "start": start.tolist(),
                    "goal": goal.tolist(),
                    "message": str(e),
                    "occlusion_computations": plan.stats["occlusion_computations"],
                    "any_facing_seconds": any_facing,
                }
            )
            print(
                f"  layout {layout:3d}: FAILED after {dt * 1000:7.1f} ms: {e}; with any goal "
                f"facing: "
                + ("no path" if any_facing is None else f"found in {any_facing * 1000:.0f} ms")
            )
            continue
        dt = time.perf_counter() - t0
        if prof:
            prof.disable()
        t_any = time.perf_counter()
        try:  # the same pair when any goal facing will do
            planner.plan(start, np.array([goal[0], goal[1], np.nan]))
            any_s = time.perf_counter() - t_any
        except PlanError:
            any_s = None
        t1 = time.perf_counter()
        motions = plan_motions(patch, plan)
        m = concatenate(motions)
        synth = time.perf_counter() - t1
        ground = m.ground[:, :2]
        # As the API writes a plan: feet moving fast through a blend are not planted.
        m = Motion(m.ground, m.root_local, m.rotations, foot_lock.still_contacts(skel, m, fps))
        skate = metrics.foot_skate(foot_positions(m, skel), fps, m.contacts)
        t2 = time.perf_counter()
        locked = Motion(m.ground, m.root_local, foot_lock.lock_feet(skel, m, fps=fps), m.contacts)
        lock_s = time.perf_counter() - t2
        skate_locked = metrics.foot_skate(foot_positions(locked, skel), fps, m.contacts)
        feet_free, feet_locked = feet(m, skel, fps), feet(locked, skel, fps)
        spin = spin_locked = (float("nan"), "")
        if reference is not None:
            r, j = metrics.step_ratio(m.rotations, reference)
            rl, jl = metrics.step_ratio(locked.rotations, reference)
            spin, spin_locked = (r, skel.names[j]), (rl, skel.names[jl])
        rec = {
            "layout": layout,
            "seconds": dt,
            "synthesis_seconds": synth,
            "any_facing_seconds": any_s,
            "expansions": plan.expansions,
            "pieces": len(plan.pieces),
            "segments": sum(p.kind == "segment" for p in plan.pieces),
            "frames": m.frames,
            "motion_seconds": (m.frames - 1) / fps,
            "metres": float(np.linalg.norm(np.diff(ground, axis=0), axis=1).sum()),
            "straight_line_m": float(np.linalg.norm(goal[:2] - start[:2])),
            "occlusion_computations": plan.stats["occlusion_computations"],
            "frames_inside_obstacle": int(env.blocked(ground).sum()),
            "cost": plan.cost,
            "start": start.tolist(),
            "goal": goal.tolist(),
            "start_connectors": plan.stats.get("start_connectors"),
            "goal_connectors": plan.stats.get("goal_connectors"),
            "skate": skate,
            "skate_locked": skate_locked,
            "feet": feet_free,
            "feet_locked": feet_locked,
            "foot_lock_seconds": lock_s,
            "step_ratio": spin[0],
            "step_ratio_bone": spin[1],
            "step_ratio_locked": spin_locked[0],
            "step_ratio_locked_bone": spin_locked[1],
        }
        records.append(rec)
        print(
            f"  layout {layout:3d}: {dt * 1000:7.1f} ms, {plan.expansions:6d} nodes, "
            f"{rec['pieces']:3d} pieces, {rec['motion_seconds']:5.1f} s / {rec['metres']:5.1f} m "
            f"of motion ({rec['straight_line_m']:4.1f} m apart), "
            f"{plan.stats['occlusion_computations']:4d} tiles occluded, skate "
            f"{skate['mean_cm_per_frame']:.2f} cm/frame ({skate_locked['mean_cm_per_frame']:.2f} "
            f"locked)"
        )
    return records, failures, count


SPIN_RATIO = 1.6  # a bone turning this many times faster than in any source clip: a spin
FEW = 10  # props an animator moves at a time (bench_placement)
FEW_REPEATS = 15  # timed repetitions of those moves (the fastest kept)


def bench_placement(density, sizes=(10, 1000), seed=1, min_ops=2000, reocc_moves=40):
    """Per-obstacle cost of place / move / lazy re-occlusion in scenes of ``sizes`` obstacles.

    The scene area grows with the obstacle count (constant ``density``), so every tile
    holds about as many obstacles in both scenes and only the scene size differs. Placing
    and moving every obstacle once is repeated (at least 5 times, and until ``min_ops``
    operations are timed); the fastest repetition is reported (as timeit does), the
    least disturbed by other load on the machine. Placing ``FEW`` new props and moving
    ``FEW`` props over and over in the scene of n is timed too: what an animator does, and
    the per-prop work without the cache misses of touching every prop of a big scene.
    Re-occlusion: ``reocc_moves`` single moves, each of an obstacle whose old and new tiles
    were occluded beforehand (as if a plan had used them), timing the occlusion of those
    tiles again afterwards - the work a move leaves for the next plan.
    """
    out = {}
    rng = np.random.default_rng(seed)
    side, cells, radius = 2.6, 8, 0.25  # about the walk patch's tile size

    def random_pillar(name, field):
        return pillar(name, *rng.uniform(0, field, 2), rng.uniform(0.2, 0.4))

    for n in sizes:
        field = float(np.sqrt(n / density))
        reps = max(5, -(-min_ops // n))
        place, move = [], []
        for _ in range(reps):
            env = Environment(side, cells, radius)
            obs = [random_pillar(f"o{k}", field) for k in range(n)]
            new = [random_pillar(f"o{k}", field) for k in range(n)]
            t0 = time.perf_counter()
            for ob in obs:
                env.place(ob)
            t1 = time.perf_counter()
            for ob in new:  # same names: every obstacle moves once
                env.place(ob)
            t2 = time.perf_counter()
            place.append(t1 - t0)
            move.append(t2 - t1)
        place, move = float(np.min(place)), float(np.min(move))
        # An animator moves a few props at a time: the same FEW props moved min_ops times
        # in the scene of n (fastest of FEW_REPEATS after a warm-up). Moving every prop of
        # a big scene touches memory the cache no longer holds; this is the per-prop work.
        few_moves = [random_pillar(f"o{k % min(FEW, n)}", field) for k in range(min_ops)]
        added = [random_pillar(f"new{k}", field) for k in range(FEW)]
        few, few_place = [], []
        for rep in range(FEW_REPEATS + 1):  # the first untimed (a warm-up)
            t0 = time.perf_counter()
            for ob in few_moves:
                env.place(ob)
            few.append(time.perf_counter() - t0)
            spent = 0.0
            for _ in range(-(-min_ops // FEW)):  # FEW new props placed, then removed again
                t0 = time.perf_counter()
                for ob in added:
                    env.place(ob)
                spent += time.perf_counter() - t0
                for ob in added:
                    env.remove(ob.name)
            few_place.append(spent / (FEW * -(-min_ops // FEW)))
        few, few_place = float(np.min(few[1:])) / len(few_moves), float(np.min(few_place[1:]))
        # One move at a time, its tiles occluded beforehand as if a plan had used them.
        reocc, tiles, members = 0.0, 0, 0
        for m in range(reocc_moves):
            name = f"o{m % n}"
            new = random_pillar(name, field)
            touched = env._tiles_overlapping(env.obstacles[name]) | env._tiles_overlapping(new)
            for t in touched:
                env.free_cells(t)
            env.place(new)
            t0 = time.perf_counter()
            for t in touched:
                env.free_cells(t)
            reocc += time.perf_counter() - t0
            tiles += len(touched)
            members += sum(len(env.members(t)) for t in touched)
        out[n] = {
            "field_m": field,
            "repeats": reps,
            "tiles_with_obstacles": len(env._members),
            "place_scene_ms": place * 1e3,
            "place_us_per_obstacle": place / n * 1e6,
            "move_us_per_obstacle": move / n * 1e6,
            "place_few_us": few_place * 1e6,
            "move_few_us": few * 1e6,
            "reoccluded_tiles_per_moved_obstacle": tiles / reocc_moves,
            "reocclude_ms_per_moved_obstacle": reocc / reocc_moves * 1e3,
            "reocclude_ms_per_tile": reocc / max(tiles, 1) * 1e3,
            "obstacles_per_reoccluded_tile": members / max(tiles, 1),
        }
    return out


# -- report -------------------------------------------------------------------------------


def fmt_ms(s):
    return f"{s * 1000:.0f} ms"


def markdown(res):
    b, pl = res["bake"], res["plans"]
    a = res["args"]
    t, ex, oc = pl["seconds"], pl["expansions"], pl["occlusion_computations"]
    rows = [
        ("machine", f"{res['machine']}"),
        (
            "bake (walk patch, {:,} candidate curves)".format(b["candidates"]),
            f"{b['bake_seconds']:.1f} s; {b['kept']:,} segments kept, {b['culled']:,} culled ("
            + ", ".join(f"{k} {v:,}" for k, v in b["culled_by"].items())
            + ")",
        ),
        (
            "layouts",
            f"{a['layouts']} on a {a['field']:.0f} × {a['field']:.0f} m field, "
            f"{pl['pillars']} pillars each ({a['density']:g}/m², 12-sided, "
            f"r 0.2–0.4 m), "
            f"start–goal 8–20 m apart, radius {a['radius']:g} m, seed {a['seed']}",
        ),
        (
            "paths found",
            f"{pl['found']} / {a['layouts']} ({pl['failed']} PlanError"
            + (f": {pl['failure_kinds']}" if pl["failed"] else "")
            + ")"
            + (
                f"; with any goal facing {pl['found_any_facing']} of those {pl['failed']} are found"
                if pl["failed"]
                else ""
            ),
        ),
        (
            "plan time",
            f"mean {fmt_ms(t['mean'])}, median {fmt_ms(t['median'])}, "
            f"p95 {fmt_ms(t['p95'])}, max {fmt_ms(t['max'])}",
        ),
        (
            "plan time with any goal facing",
            f"median {fmt_ms(pl['any_facing_seconds']['median'])}; "
            f"{pl['any_facing_ratio']['median']:.2f}x the exact-facing "
            f"plan (median), {pl['any_facing_ratio']['max']:.2f}x at most",
        ),
        (
            "nodes expanded",
            f"mean {ex['mean']:,.0f}, median {ex['median']:,.0f}, "
            f"p95 {ex['p95']:,.0f}, max {ex['max']:,.0f}",
        ),
        ("tile occlusions computed per plan", f"mean {oc['mean']:.0f}, max {oc['max']:.0f}"),
        (
            "path length",
            f"mean {pl['motion_seconds']['mean']:.1f} s of motion "
            f"(max {pl['motion_seconds']['max']:.1f} s), "
            f"{pl['metres']['mean']:.1f} m (straight line "
            f"{pl['straight_line_m']['mean']:.1f} m)",
        ),
        ("pieces per path", f"mean {pl['pieces']['mean']:.1f} (start + segments + goal)"),
        ("motion synthesis per path", f"mean {fmt_ms(pl['synthesis_seconds']['mean'])}"),
        ("frames within the radius of a pillar", f"{pl['frames_inside_obstacle']}"),
        (
            "foot skate while planted",
            f"{pl['skate']['mean_cm_per_frame']:.2f} cm/frame, "
            f"{pl['skate']['mean_cm_per_s']:.1f} cm/s (worst path "
            f"{pl['skate']['worst_path_mean_cm_per_s']:.1f} cm/s); "
            f"source clip 16_15: "
            f"{res['source_skate']['mean_cm_per_frame']:.2f} cm/frame, "
            f"{res['source_skate']['mean_cm_per_s']:.1f} cm/s",
        ),
        (
            "foot skate with foot locking",
            f"{pl['skate_locked']['mean_cm_per_frame']:.2f} cm/frame, "
            f"{pl['skate_locked']['mean_cm_per_s']:.1f} cm/s (worst "
            f"path {pl['skate_locked']['worst_path_mean_cm_per_s']:.1f}"
            f" cm/s); leg IK {fmt_ms(pl['foot_lock_seconds']['mean'])}"
            f" per path",
        ),
        (
            "feet by the label-free measure (toe within 3 cm of its lowest for 0.2 s), "
            "without foot locking",
            feet_text(pl["feet"], res["source_feet"]),
        ),
        (
            "feet by the label-free measure, with foot locking",
            feet_text(pl["feet_locked"], res["source_feet"]),
        ),
        (
            "largest per-frame bone turn against the source clips' (16_15, 16_18, a bone "
            "or its mirror image; under 1 deg counts as 1)",
            f"median path {pl['step_ratio']['median']:.2f}x, worst {pl['step_ratio']['max']:.2f}x"
            f" ({pl['paths_stepping_over']['step_ratio']} paths over {SPIN_RATIO}x); with "
            f"foot locking median {pl['step_ratio_locked']['median']:.2f}x, worst "
            f"{pl['step_ratio_locked']['max']:.2f}x "
            f"({pl['paths_stepping_over']['step_ratio_locked']} over {SPIN_RATIO}x)",
        ),
    ]
    for n, p in res["placement"].items():
        rows.append(
            (
                f"placement, scene of {int(n):,} obstacles",
                f"place {p['place_us_per_obstacle']:.0f} µs, move "
                f"{p['move_us_per_obstacle']:.0f} µs per obstacle (whole scene "
                f"{p['place_scene_ms']:.2f} ms); lazy re-occlusion by the next plan "
                f"{p['reocclude_ms_per_moved_obstacle']:.1f} ms per moved obstacle "
                f"({p['reoccluded_tiles_per_moved_obstacle']:.1f} tiles of "
                f"{p['obstacles_per_reoccluded_tile']:.1f} obstacles, "
                f"{p['reocclude_ms_per_tile']:.1f} ms each)",
            )
        )
    out = ["| figure | value |", "|---|---|"]
    out += [f"| {k} | {v} |" for k, v in rows]
    return "\n".join(out)


def main(argv=None):
    args = parse_args(argv)
    mocap = Path(args.mocap)
    missing = missing_mocap(mocap)
    if missing:
        print(missing, file=sys.stderr)
        return 2
    t_all = time.perf_counter()
    print("bake ...", flush=True)
    patch, straight, bake = bench_bake(mocap)
    print(
        f"  {bake['bake_seconds']:.1f} s: {bake['kept']} segments kept, "
        f"{bake['culled']} culled {bake['culled_by']}"
    )
    print(f"plans on {args.layouts} random layouts ...", flush=True)
    profiler = cProfile.Profile() if args.profile else None
    turn = bvh.read(mocap / "cmu" / "16_18.bvh")
    reference = metrics.source_bone_steps(
        (straight, turn), patch.gait.fps, patch.gait.skeleton.mirror_map()
    )
    records, failures, pillars = bench_plans(patch, args, profiler, reference)
    print("source clip skate ...", flush=True)
    floor = bench_source_skate(straight, patch.gait.fps)
    source_feet = foot_measure.of_clip(clip_mod.resample(straight, patch.gait.fps))
    print("placement ...", flush=True)
    placement = bench_placement(args.density)

    kinds = {}
    for f in failures:
        k = (
            "unreachable"
            if "unreachable" in f["message"]
            else "no way out of the start"
            if "out of the start" in f["message"]
            else "no way into the goal"
            if "into the goal" in f["message"]
            else "no walk can arrive facing the goal's way"
            if "arrive at the goal facing" in f["message"]
            else "no walk can leave facing the start's way"
            if "leave the start facing" in f["message"]
            else "other"
        )
        kinds[k] = kinds.get(k, 0) + 1
    plans = {
        "pillars": pillars,
        "found": len(records),
        "failed": len(failures),
        "found_any_facing": sum(f["any_facing_seconds"] is not None for f in failures),
        "failure_kinds": ", ".join(f"{k} {v}" for k, v in kinds.items()),
        "failure_seconds": stats([f["seconds"] for f in failures]),
        "seconds": stats([r["seconds"] for r in records]),
        "any_facing_seconds": stats(
            [r["any_facing_seconds"] for r in records if r["any_facing_seconds"] is not None]
        ),
        "any_facing_ratio": stats(
            [
                r["any_facing_seconds"] / r["seconds"]
                for r in records
                if r["any_facing_seconds"] is not None
            ]
        ),
        "expansions": stats([r["expansions"] for r in records]),
        "occlusion_computations": stats([r["occlusion_computations"] for r in records]),
        "motion_seconds": stats([r["motion_seconds"] for r in records]),
        "metres": stats([r["metres"] for r in records]),
        "straight_line_m": stats([r["straight_line_m"] for r in records]),
        "pieces": stats([r["pieces"] for r in records]),
        "synthesis_seconds": stats([r["synthesis_seconds"] for r in records]),
        "frames_inside_obstacle": int(sum(r["frames_inside_obstacle"] for r in records)),
        "skate": pooled_skate(records),
        "skate_locked": pooled_skate(records, "skate_locked"),
        "feet": pooled_feet([r["feet"] for r in records]),
        "feet_locked": pooled_feet([r["feet_locked"] for r in records]),
        "foot_lock_seconds": stats([r["foot_lock_seconds"] for r in records]),
        "step_ratio": stats([r["step_ratio"] for r in records]),
        "step_ratio_locked": stats([r["step_ratio_locked"] for r in records]),
        "paths_stepping_over": {
            key: sum(r[key] > SPIN_RATIO for r in records)
            for key in ("step_ratio", "step_ratio_locked")
        },
    }
    res = {
        "machine": machine(),
        "args": {
            "layouts": args.layouts,
            "seed": args.seed,
            "density": args.density,
            "field": args.field,
            "radius": args.radius,
            "weights": list(args.weights),
        },
        "bake": bake,
        "plans": plans,
        "source_skate": floor,
        "source_feet": source_feet,
        "placement": {str(k): v for k, v in placement.items()},
        "records": records,
        "failures": failures,
        "total_seconds": time.perf_counter() - t_all,
    }
    if profiler is not None:
        for key in ("tottime", "cumulative"):
            s = io.StringIO()
            pstats.Stats(profiler, stream=s).strip_dirs().sort_stats(key).print_stats(15)
            print(f"\ncProfile of the first {min(args.profile, args.layouts)} plans, by {key}:")
            print("\n".join(ln for ln in s.getvalue().splitlines() if ln.strip())[:6000])

    print()
    print(markdown(res))
    print(f"\n(total {res['total_seconds']:.0f} s)")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=1)
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
