# SPDX-License-Identifier: GPL-3.0-or-later
import numpy as np
import pytest

from motion_patches.kinematics.motion import concatenate
from motion_patches.planning.planner import SegmentPlanner, plan_motions
from motion_patches.props import object_patch as op
from motion_patches.props.environment import Environment, Obstacle

from conftest import cmu

CHAIR = np.array([[-0.2, -0.22], [0.2, -0.22], [0.2, 0.22], [-0.2, 0.22]])


@pytest.fixture(scope="module")
def hurdle_clip(walk_gait):
    # CMU 16_06, a real standing forward jump (the closest recorded hurdle), effort T = 8.
    return op.patch_clip_from(cmu("16_06"), op.TRAVERSAL, walk_gait.fps, effort=8.0)


def chair_line(patch, clip, n=11, x=5.0, half=2.5):
    env = Environment(patch.side, patch.cells, 0.25)
    props = []
    for k, y in enumerate(np.linspace(-half, half, n)):
        o = op.ObjectPatch(f"chair{k}", CHAIR, pose=(x, y, 0.0))
        o.add_traversal_copies(clip)
        env.place(Obstacle(o.name, o.world_footprint()))
        props.append(o)
    return env, props


def scattered_chairs(patch, clip, seed, n):
    env = Environment(patch.side, patch.cells, 0.25)
    props, r = [], np.random.default_rng(seed)
    for k in range(n):
        pose = (r.uniform(2, 8), r.uniform(-2, 3), r.uniform(0, np.pi))
        o = op.ObjectPatch(f"c{k}", CHAIR, pose=pose)
        o.add_traversal_copies(clip, step_deg=30)
        env.place(Obstacle(o.name, o.world_footprint()))
        props.append(o)
    return env, props


def test_jump_clip_is_anchored_at_its_apex_and_faces_along_x(hurdle_clip):
    e, x = hurdle_clip.entry, hurdle_clip.exit
    assert e[0] < -0.4 and x[0] > 0.4 and abs(e[1]) < 1e-6 and abs(x[1]) < 1e-6
    assert 1.1 < hurdle_clip.length() < 1.4  # SOURCES: 1.26 m
    assert abs(e[2]) < 1e-6


def test_a_clip_without_root_motion_is_refused(walk16):
    from motion_patches.kinematics.clip import Clip

    still = Clip(
        "still",
        walk16.skeleton,
        walk16.fps,
        np.repeat(walk16.root_pos[:1], 40, 0),
        np.repeat(walk16.rotations[:1], 40, 0),
    )
    with pytest.raises(ValueError, match="no root motion"):
        op.patch_clip_from(still, op.TRAVERSAL, 30.0)


def test_copies_every_ten_degrees_skip_those_landing_on_the_prop(hurdle_clip):
    long_wall = op.ObjectPatch(
        "wall", np.array([[-0.1, -1.0], [0.1, -1.0], [0.1, 1.0], [-0.1, 1.0]])
    )
    chair = op.ObjectPatch("chair", CHAIR)
    assert chair.add_traversal_copies(hurdle_clip) == 36
    kept = long_wall.add_traversal_copies(hurdle_clip)
    assert 0 < kept < 36  # jumping along the wall would land on it
    for c in long_wall.clips:
        ends = np.array([c.entry[:2], c.exit[:2]])
        assert np.all(np.abs(ends[:, 1]) > 1.0) or np.all(np.abs(ends[:, 0]) > 0.1)


def test_density_bins_sort_every_copy_by_its_ends(hurdle_clip):
    chair = op.ObjectPatch("chair", CHAIR)
    chair.add_traversal_copies(hurdle_clip)
    rects, bins = chair.density_bins()
    assert rects.shape == (op.BINS * op.BINS, 4) and bins.shape == (36, 2)
    for c, (b_in, b_out) in zip(chair.clips, bins):
        x0, y0, x1, y1 = rects[b_in]
        assert x0 - 1e-9 <= c.entry[0] <= x1 + 1e-9 and y0 - 1e-9 <= c.entry[1] <= y1 + 1e-9


def test_occluded_bins_are_the_bins_each_footprint_overlaps(hurdle_clip):
    """occluded_bins (bins tested only where their bounds meet a footprint's) marks the
    bins whose world rectangle overlaps another prop's footprint, as testing every bin
    against every footprint does; some bins are occluded, most are not."""
    from motion_patches.props.environment import polygons_within

    rng = np.random.default_rng(7)
    marked = total = 0
    for k in range(12):
        chair = op.ObjectPatch("chair", CHAIR, pose=(0.0, 0.0, float(rng.uniform(-np.pi, np.pi))))
        chair.add_traversal_copies(hurdle_clip)
        others = []
        for n in range(6):
            x, y, h = rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(-np.pi, np.pi)
            o = op.ObjectPatch(f"o{n}", CHAIR * rng.uniform(0.5, 2.0), pose=(x, y, h))
            others.append(Obstacle(o.name, o.world_footprint()))
        got = chair.occluded_bins(others)
        rects, _ = chair.density_bins()
        want = np.zeros(len(rects), bool)
        for b, (x0, y0, x1, y1) in enumerate(rects):
            poly = chair.to_world(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
            want[b] = any(polygons_within(poly, ob.polygon, 0.0) for ob in others)
        assert np.array_equal(got, want), k
        marked += int(want.sum())
        total += want.size
    assert 0 < marked < total / 2, (marked, total)


def test_hurried_character_hurdles_the_chair_line_unhurried_walks_around(walk_patch, hurdle_clip):
    start, goal = (1.0, 0.3, 0.0), (9.0, 0.3, 0.0)
    env, props = chair_line(walk_patch, hurdle_clip)
    hurried = SegmentPlanner(walk_patch, env, 4.0, 0.5, 0.1, props=props).plan(start, goal)
    env, props = chair_line(walk_patch, hurdle_clip)
    calm = SegmentPlanner(walk_patch, env, 0.3, 0.1, 3.0, props=props).plan(start, goal)
    assert hurried.stats["traversals_used"] == 1
    assert calm.stats["traversals_used"] == 0
    # Outside the traversal clip the root never enters a footprint (grown by the radius).
    for plan in (hurried, calm):
        ms = plan_motions(walk_patch, plan)
        for piece, m in zip(plan.pieces, ms):
            if piece.kind != "traversal":
                assert not env.blocked(m.ground[:, :2]).any(), piece.label
        whole = concatenate(ms)
        assert np.allclose(whole.ground[-1, :2], goal[:2], atol=1e-6)
        assert np.linalg.norm(np.diff(whole.ground[:, :2], axis=0), axis=1).max() < 0.1


def test_dynamic_and_static_stitching_find_paths_of_equal_cost(walk_patch, hurdle_clip):
    """Lazy (dynamic) and up-front (static) stitching search the same graph: on every
    layout both find a path (a PlanError fails the test) of the same cost, with the same
    number of chairs jumped; and the layouts are ones where jumping pays, in some of them."""
    jumped = []
    for seed in range(8):
        rng = np.random.default_rng(seed)
        start = (0.5, 0.5, 0.0)
        goal = (10.0, float(rng.uniform(-1, 2)), 0.0)
        plans = []
        for mode in ("dynamic", "static"):
            env, props = scattered_chairs(walk_patch, hurdle_clip, seed, 8)
            plans.append(
                SegmentPlanner(walk_patch, env, 3.0, 0.5, 0.1, props=props, mode=mode).plan(
                    start, goal
                )
            )
        assert np.isclose(plans[0].cost, plans[1].cost), seed
        used = [sum(p.kind == "traversal" for p in plan.pieces) for plan in plans]
        assert used[0] == used[1], seed
        jumped.append(used[0])
    print("chairs jumped per layout:", jumped)
    assert sum(n > 0 for n in jumped) >= 2, jumped


def test_per_tile_observer_stitches_the_chair_line_lazily(walk_patch, hurdle_clip):
    """The paper's rule fires in the chair line's tile for the hurried walker; copies in
    tiles the search never enters are never stitched, so dynamic stitching does no more
    copies than the global rule (every copy whose estimate is below the plan's cost; on
    this layout in the start-anchored plan frame, exactly those) and far fewer than
    static; a walker who walks around stitches fewer than static."""
    start, goal = (1.0, 0.3, 0.0), (9.0, 0.3, 0.0)
    for weights, traversals in (((4.0, 0.5, 0.1), 1), ((0.3, 0.1, 3.0), 0)):
        plans = {}
        for mode in ("dynamic", "static"):
            env, props = chair_line(walk_patch, hurdle_clip)
            planner = SegmentPlanner(walk_patch, env, *weights, props=props, mode=mode)
            plans[mode] = planner.plan(start, goal)
        dyn, sta = plans["dynamic"].stats, plans["static"].stats
        assert np.isclose(plans["dynamic"].cost, plans["static"].cost)
        assert dyn["traversals_used"] == sta["traversals_used"] == traversals
        assert dyn["copies_stitched"] == (
            dyn["copies_stitched_by_tile"] + dyn["copies_stitched_at_goal"]
        )
        assert sta["copies_stitched_by_tile"] == sta["copies_stitched_at_goal"] == 0
        assert dyn["copies_stitched"] < sta["copies_stitched"] / 2, (dyn, sta)
        if traversals:
            assert dyn["copies_stitched_by_tile"] > 0
            with planner.framed(np.array(start), np.array(goal)) as (local_start, _, _):
                below = sum(
                    e <= plans["dynamic"].cost for e, *_ in planner.traversal_estimates(local_start)
                )
            assert dyn["copies_stitched"] <= below


def test_goal_backstop_stitches_copies_bounded_between_the_last_node_and_the_goal(
    walk_patch, hurdle_clip
):
    """On this layout some copies' bounds lie between the f of the last node the search
    takes off and the goal's (the goal connectors cost more than the heuristic of their
    nodes): the backstop stitches them when the goal comes off, and the walker jumps a
    chair on the path static stitching finds. (That the backstop is needed for
    optimality is shown on a small graph in test_astar.)"""
    args = ((0.5, 0.0, 0.0), (10.0, 0.5, 0.0))
    plans = {}
    for mode in ("dynamic", "static"):
        env, props = scattered_chairs(walk_patch, hurdle_clip, 39, 14)
        plans[mode] = SegmentPlanner(walk_patch, env, 4.2, 0.5, 0.75, props=props, mode=mode).plan(
            *args
        )
    dyn = plans["dynamic"].stats
    assert dyn["copies_stitched_at_goal"] > 0 and dyn["traversals_used"] >= 1
    assert np.isclose(plans["dynamic"].cost, plans["static"].cost)


def test_moving_a_prop_changes_the_path(walk_patch, hurdle_clip):
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    y = 0.5 * walk_patch.side  # the middle of a tile row
    wall = Obstacle(
        "wall", np.array([[4.8, y - 1.5], [5.2, y - 1.5], [5.2, y + 1.5], [4.8, y + 1.5]])
    )
    env.place(wall)
    a = SegmentPlanner(walk_patch, env).plan((1.0, y, 0.0), (9.0, y, 0.0))
    env.place(Obstacle("wall", wall.polygon + [0.0, 4.0]))  # moved out of the way, same name
    b = SegmentPlanner(walk_patch, env).plan((1.0, y, 0.0), (9.0, y, 0.0))
    assert [p.label for p in a.pieces] != [p.label for p in b.pieces]
    assert b.cost < a.cost


def test_traversal_probability_keeps_a_chair_line_tile_passable(walk_patch, hurdle_clip):
    from motion_patches.planning import traversal_probability as tp
    from motion_patches.planning.high_level import TilePlanner

    env, props = chair_line(walk_patch, hurdle_clip)
    planner = SegmentPlanner(walk_patch, env, 4.0, 0.5, 0.1, props=props)
    tile = env.tile_of((5.0, 0.3))
    psi = tp.accessibility(walk_patch, props[0], env.radius)
    assert 0.0 < psi <= 1.0
    upsilon = TilePlanner(walk_patch, env).upsilon(tile)
    tau = planner.tile_tau(tile)
    assert upsilon[3, 1] == 0.0  # no walk crosses the line west to east ...
    assert tau[3, 1] > 0.2  # ... but the jump likely does (Eq. 3)
    with_tau = TilePlanner(walk_patch, env, traversal=planner.tile_tau)
    assert np.isfinite(with_tau.edge_cost(tile, 3, 1))
    assert np.isinf(TilePlanner(walk_patch, env).edge_cost(tile, 3, 1))


def test_corridor_planning_with_traversals_matches_the_full_search(walk_patch, hurdle_clip):
    env, props = chair_line(walk_patch, hurdle_clip)
    full = SegmentPlanner(walk_patch, env, 4.0, 0.5, 0.1, props=props).plan(
        (1.0, 0.3, 0), (9.0, 0.3, 0)
    )
    env, props = chair_line(walk_patch, hurdle_clip)
    corr = SegmentPlanner(walk_patch, env, 4.0, 0.5, 0.1, props=props).plan(
        (1.0, 0.3, 0), (9.0, 0.3, 0), use_corridor=True
    )
    assert corr.stats["high_level_tiles"] > 0 and corr.stats["traversals_used"] == 1
    assert corr.cost <= 1.1 * full.cost


def test_stand_up_walk_and_sit_down_on_retargeted_real_clips(walk_patch, walk_gait, stand_walk_sit):
    assert op.ends_lower(cmu("13_05")) and not op.ends_lower(cmu("13_05_standup"))
    plan = stand_walk_sit[0]
    kinds = [p.kind for p in plan.pieces]
    assert kinds[0] == "interaction" and kinds[-1] == "interaction"
    m = concatenate(plan_motions(walk_patch, plan))
    assert np.linalg.norm(np.diff(m.ground[:, :2], axis=0), axis=1).max() < 0.1
    # Seated at the end, over chair B: the root is low and above the seat.
    wm = m.world_matrices(walk_gait.skeleton)
    hips = wm[-1, walk_gait.skeleton.root, :3, 3]
    assert hips[2] < 0.7 and np.linalg.norm(hips[:2] - (8.0, 3.0)) < 0.25


def test_stitching_keeps_the_cheapest_clear_connections_and_lists_every_pair(
    walk_patch, hurdle_clip, monkeypatch
):
    """stitch_table tests the used parts cheapest first and stops once MAX_PER_END are
    clear: the connections kept are those of testing every candidate (MAX_PER_END
    lifted) cut to the cheapest MAX_PER_END; stitch() lists every entry x exit pair of
    the table with its summed cost. On these chairs some ends have more clear
    candidates than are kept (the early stop is exercised)."""
    from motion_patches.planning import stitching

    env, props = scattered_chairs(walk_patch, hurdle_clip, 3, 14)
    weights = (1.0, 0.5, 0.2)
    tables, full = [], []
    for prop in props:
        for ci, clip in enumerate(prop.clips):
            if clip.kind == "traversal":
                tables.append(stitching.stitch_table(walk_patch, env, prop, ci, *weights))
    with monkeypatch.context() as m:
        m.setattr(stitching, "MAX_PER_END", 10**6)
        for prop in props:
            for ci, clip in enumerate(prop.clips):
                if clip.kind == "traversal":
                    full.append(stitching.stitch_table(walk_patch, env, prop, ci, *weights))
    cut = 0
    for got, every in zip(tables, full):
        assert (got is None) == (every is None)
        if got is None:
            continue
        for mine, theirs in ((got[0], every[0]), (got[1], every[1])):
            assert [(c.segment, c.frame, c.cost) for c in mine] == [
                (c.segment, c.frame, c.cost) for c in theirs[: stitching.MAX_PER_END]
            ]
            cut += len(theirs) > stitching.MAX_PER_END
    assert cut > 0
    copies = [(p, i) for p in props for i, c in enumerate(p.clips) if c.kind == "traversal"]
    listed = 0
    for (prop, ci), table in zip(copies, tables):
        edges = stitching.stitch(walk_patch, env, prop, ci, *weights)
        if table is None:
            assert edges == []
            continue
        ins, outs, from_keys, to_keys, clip_cost = table
        assert len(edges) == len(ins) * len(outs)
        for st in edges:
            a, b = ins.index(st.entry), outs.index(st.exit)
            assert (st.from_key, st.to_key) == (from_keys[a], to_keys[b])
            assert st.cost == st.entry.cost + clip_cost + st.exit.cost
        listed += len(edges)
    assert listed > 0


def test_part_speed_is_the_fastest_part_of_any_segment(walk_patch):
    """part_speed, from the stacked ground frames at once, equals the fastest average
    speed of a segment's first frame to a later one or a frame to its last (2 frames
    apart or more) found segment by segment; it is above the gait's fastest cycle
    average, which is why the bounds of a part's effort use it."""
    from motion_patches.planning import stitching

    fps, best = walk_patch.gait.fps, 0.0
    for seg in range(walk_patch.segment_count):
        _, arc = walk_patch.ground(seg)
        for f in range(2, arc.size):
            best = max(best, (arc[f] - arc[0]) * fps / f)
            best = max(best, (arc[-1] - arc[-1 - f]) * fps / f)
    assert np.isclose(stitching.part_speed(walk_patch), best, rtol=1e-12)
    planner = SegmentPlanner(walk_patch, Environment(walk_patch.side, walk_patch.cells, 0.25))
    print(f"part speed {best:.3f} m/s, fastest cycle average {planner.max_speed:.3f} m/s")
    assert best > planner.max_speed


@pytest.mark.parametrize("seed", (3, 39))
def test_bound_through_a_node_is_below_every_stitched_edge_from_it(walk_patch, hurdle_clip, seed):
    """The observer's bound through a node (taken off with g = 0 here) is at most the
    cost of every edge a stitched copy adds from that node + the heuristic of the node
    it leads to: the cost + heuristic of paths through the copy from that node; and it
    comes within a quarter metre's walk (alpha = 1) of that for some edge (it is not a
    trivial bound)."""
    from motion_patches.planning import stitching

    env, props = scattered_chairs(walk_patch, hurdle_clip, seed, 14)
    weights = (1.0, 0.5, 0.2)
    planner = SegmentPlanner(walk_patch, env, *weights, props=props)
    start, goal = np.array((0.5, 0.0, 0.0)), np.array((10.0, 0.5, 0.0))
    gaps, edges = [], 0
    with planner.framed(start, goal) as (local_start, _, _):
        copies = planner.traversal_estimates(local_start)
        through = planner.through(copies)
        for idx, (_, pi, ci, *_) in enumerate(copies):
            table = stitching.stitch_table(walk_patch, planner.env, planner.props[pi], ci, *weights)
            if table is None:
                continue
            ins, outs, from_keys, to_keys, clip_cost = table
            for a, from_key in zip(ins, from_keys):
                bound = through([from_key], [planner.heuristic_of(from_key)], np.array([idx]))[0, 0]
                for b, to_key in zip(outs, to_keys):
                    cost = a.cost + clip_cost + b.cost + planner.heuristic_of(to_key)
                    gaps.append(cost - bound)
                    edges += 1
        # With ``below`` (one node) the bounds under it are the full ones, the rest no
        # higher than the full ones: the observer's cheap first pass loses nothing.
        every, left_lower, kept = np.arange(len(copies)), 0, 0
        for key in sorted(planner.entries(planner.block((0, 0)))[0].tolist())[:60]:
            f = planner.heuristic_of(key) + 1.0
            full = through([key], [f], every)[0]
            below = full + np.random.default_rng(key).normal(0.0, 0.5, full.size)
            cheap = through([key], [f], every, below=below)[0]
            under = full < below
            assert np.array_equal(cheap[under], full[under]) and np.all(cheap <= full)
            left_lower += np.count_nonzero(cheap < full)
            kept += np.count_nonzero(under)
            # Far under every bound: nothing to lower, the bounds given are answered.
            far = full - 100.0
            assert np.array_equal(through([key], [f], every, below=far)[0], far)
        assert left_lower > 0 and kept > 0, (left_lower, kept)
        # Many nodes at once (the observer's first bound of a copy) as one by one.
        keys = sorted(planner.entries(planner.block((0, 0)))[0].tolist())[:60]
        fs = [planner.heuristic_of(k) + 1.0 for k in keys]
        rows = np.stack([through([k], [f], every)[0] for k, f in zip(keys, fs)])
        assert np.allclose(through(keys, fs, every), rows, rtol=0, atol=1e-12)
    gaps = np.array(gaps)
    print(f"{edges} edges, bound below cost by {gaps.min():.3f} .. {gaps.max():.3f}")
    assert edges > 100
    assert gaps.min() >= -1e-9
    assert gaps.min() < 0.25


def test_stitch_candidates_are_each_segments_nearest_frame(walk_patch, hurdle_clip, monkeypatch):
    """The entry and exit candidates of stitching (rows cached per cell, nearest frames
    found for every segment at once) are, segment by segment over all its frames, the
    frame nearest the keyframe (the first of equally near ones) of each segment through
    the keyframe's cell, kept when within the tolerances and 2 frames of the segment's
    ends; nothing else stands near (the chair itself is excluded), so every candidate
    is kept (MAX_PER_END lifted)."""
    from motion_patches.planning import stitching

    monkeypatch.setattr(stitching, "MAX_PER_END", 10**6)
    ground, _, first = walk_patch.all_ground()
    n, found = walk_patch.gait.frames, 0
    for angle in np.radians(np.arange(0.0, 360.0, 45.0)):
        env, props = chair_line(walk_patch, hurdle_clip, n=1, x=4.1 + angle / 7, half=0.0)
        prop = props[0]
        prop.pose = (prop.pose[0], 0.3 + angle / 11, float(angle))
        for ci, clip in enumerate(prop.clips):
            world = prop.world_clip(clip)
            for at_entry, state, pose in (
                (True, world.ground[0], 0),
                (False, world.ground[-1], -1),
            ):
                d_pose = stitching.phase_pose_distance(
                    walk_patch.gait, clip.motion.root_local[pose], clip.motion.rotations[pose]
                )
                phase_ok = d_pose <= stitching.POSE_TOLERANCE * d_pose.min()
                got = stitching._candidates(
                    walk_patch, env, state, phase_ok, prop.name, at_entry, 1.0, 0.5, 0.2
                )
                tile = env.tile_of(state[:2])
                local = state[:2] - np.array(tile, float) * walk_patch.side
                c = walk_patch.cell_size
                cell = int(
                    min(max(local[1] // c, 0), walk_patch.cells - 1) * walk_patch.cells
                    + min(max(local[0] // c, 0), walk_patch.cells - 1)
                )
                want = []
                for seg in range(walk_patch.segment_count):
                    if not int(walk_patch.seg_mask[seg]) >> cell & 1:
                        continue
                    g = ground[first[seg] : first[seg + 1]]
                    dist = np.hypot(g[:, 0] - local[0], g[:, 1] - local[1])
                    f = int(np.argmin(dist))
                    dh = abs((g[f, 2] - state[2] + np.pi) % (2 * np.pi) - np.pi)
                    if (
                        2 <= f <= len(g) - 3
                        and dist[f] <= stitching.POSITION_TOLERANCE
                        and dh <= stitching.HEADING_TOLERANCE
                        and phase_ok[f % n]
                    ):
                        err = dist[f] / stitching.POSITION_TOLERANCE
                        want.append((seg, f, err + dh / stitching.HEADING_TOLERANCE))
                mine = sorted((k.segment, k.frame, k.error) for k in got)
                assert [(s, f) for s, f, _ in mine] == [(s, f) for s, f, _ in sorted(want)]
                assert np.allclose([e for *_, e in mine], [e for *_, e in sorted(want)])
                found += len(mine)
    print("candidates compared:", found)
    assert found > 50


@pytest.fixture(scope="module")
def floored_jump(walk_gait):
    """16_06 put down on the walk's floor, as tagging and planning place it."""
    return op.patch_clip_from(
        cmu("16_06"), op.TRAVERSAL, walk_gait.fps, effort=8.0, floor=walk_gait.floor()
    )


def test_the_jump_s_clearance_is_where_its_body_passes_over_the_footprint(walk_gait, floored_jump):
    """16_06 is a standing broad jump: over a chair's footprint its lowest bone passes about
    18 cm above the floor; over a deeper box (1 m along the jump) it cannot clear at all."""
    points = op.body_points(floored_jump, walk_gait.skeleton)
    chair = op.clearance_over(points, CHAIR, walk_gait.floor())
    box = np.array([[-0.5, -1.5], [0.5, -1.5], [0.5, 1.5], [-0.5, 1.5]])
    deep = op.clearance_over(points, box, walk_gait.floor())
    assert 0.12 < chair < 0.25 and deep < chair
    far = CHAIR + (10.0, 0.0)  # nothing passes over a footprint off the clip's way
    assert op.clearance_over(points, far) == float("inf")


@pytest.mark.parametrize("height, kept", [(0.10, True), (0.50, False)])
def test_copies_that_do_not_clear_the_prop_are_not_offered(walk_gait, floored_jump, height, kept):
    prop = op.ObjectPatch("chair", CHAIR, height=height)
    assert prop.add_traversal_copies(floored_jump) > 0
    prop.keep_clearing(walk_gait.skeleton, walk_gait.floor())
    assert bool(prop.traversals()) == kept
    if kept:
        assert prop.too_low == []
    else:
        ((name, clears, high),) = prop.too_low
        assert name == floored_jump.name and clears < high == 0.5


def test_a_prop_of_unknown_height_keeps_every_copy(walk_gait, floored_jump):
    prop = op.ObjectPatch("chair", CHAIR)
    n = prop.add_traversal_copies(floored_jump)
    prop.keep_clearing(walk_gait.skeleton, walk_gait.floor())
    assert len(prop.traversals()) == n
