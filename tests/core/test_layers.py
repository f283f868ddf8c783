# SPDX-License-Identifier: GPL-3.0-or-later
"""Layers (issue 19): a run locomotion patch of CMU subject 16 beside the walk, the choice
of layer by Eq. 5 cost, and traversal clips used only in the layers they declare."""

import numpy as np
import pytest

from motion_patches.kinematics import contacts
from motion_patches.kinematics.motion import concatenate
from motion_patches.kinematics.retarget import rig_map
from motion_patches.patch import gait as gait_mod
from motion_patches.patch import layers, locomotion_patch
from motion_patches.planning.planner import PlanError, SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment, Obstacle
from motion_patches.props.object_patch import ObjectPatch, PatchClip
from motion_patches.quality import metrics

from conftest import cmu


def max16(name):
    return cmu(name, folder="cmu16max")


@pytest.fixture(scope="module")
def run_clips(walk16):
    """CMU subject 16's run (16_35) and run with a right turn (16_53), 3ds Max naming,
    retargeted onto the same subject's CMU-named walk skeleton (16_15)."""
    straight, turn = max16("16_35"), max16("16_53")
    rig = rig_map(straight.skeleton, walk16.skeleton, label="clip")
    return rig.clip(straight), rig.clip(turn), rig


@pytest.fixture(scope="module")
def run_gait(run_clips):
    return gait_mod.build_gait("run", run_clips[0], (run_clips[1],))


@pytest.fixture(scope="module")
def run_patch(run_gait):
    return locomotion_patch.bake(run_gait, effort_rate=layers.effort_rate(run_gait))


def pillar(name, x, y, r=0.25):
    a = np.linspace(0, 2 * np.pi, 13)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def world_feet(gait, m):
    fj = contacts.foot_joints(gait.skeleton)
    return m.world_matrices(gait.skeleton)[:, fj][..., :3, 3]


def test_run_is_the_walking_subject_on_the_walk_skeleton(run_clips, walk16, run_gait, walk_gait):
    straight, _, rig = run_clips
    assert straight.skeleton.names == walk16.skeleton.names
    assert rig.scale == pytest.approx(1.0, abs=0.01)  # one subject: same hip height
    assert layers.has_flight(run_gait) and not layers.has_flight(walk_gait)
    # The recorded pace: 16_35 covers ~3.7 m in 1.35 s (SOURCES.txt), 16_15 walks 1.10 m/s.
    assert 2.4 < layers.speed(run_gait) < 3.2
    assert layers.speed(walk_gait) == pytest.approx(1.1, abs=0.1)
    # The right turn is recorded, the left turn mirrored from it, and says so.
    assert any("right turn" in n and "mirrored" not in n for n in run_gait.notes)
    assert any("left turn" in n and "(mirrored)" in n for n in run_gait.notes)


def test_run_tiles_follow_the_runs_pace(run_patch, run_gait, walk_patch, walk_gait):
    """Two straight cycles a side in each layer: the run's tile and node spacing are larger
    in proportion to its cycle, and its segments are whole run cycles."""
    assert run_patch.side == pytest.approx(2 * run_gait.cycle_distance)
    assert walk_patch.side == pytest.approx(2 * walk_gait.cycle_distance)
    ratio = run_gait.cycle_distance / walk_gait.cycle_distance
    assert ratio > 1.5
    assert run_patch.side / walk_patch.side == pytest.approx(ratio)
    assert run_patch.side / run_patch.nodes == pytest.approx(
        ratio * walk_patch.side / walk_patch.nodes
    )
    assert run_patch.stats["entry_share"] >= locomotion_patch.MIN_ENTRY_SHARE
    assert run_patch.effort_rate > 2 * walk_patch.effort_rate


def test_a_straight_run_alone_bakes(run_clips):
    g = gait_mod.build_gait("run", run_clips[0])
    patch = locomotion_patch.bake(g)
    assert len(g.loops) == 1 and patch.segment_count > 0
    assert patch.side == pytest.approx(2 * g.cycle_distance)


def test_run_paths_avoid_pillars_as_walk_paths_do(run_patch, walk_patch):
    """The same pillar field (0.25 m pillars, 0.25 m radius) planned in both layers: every
    ground point of either path keeps the radius from every pillar, and both reach the goal."""
    field = [(3, 0.6), (4.5, 1.5), (3.5, 2.8), (6, 0.2), (6.5, 2.5), (8.5, 1.0), (10, 2.2)]
    for patch in (walk_patch, run_patch):
        env = Environment(patch.side, patch.cells, radius=0.25)
        for n, (x, y) in enumerate(field):
            env.place(pillar(f"p{n}", x, y))
        plan = SegmentPlanner(patch, env).plan((0.5, 1.3, 0.0), (13.0, 1.3, 0.0))
        m = concatenate(plan_motions(patch, plan))
        assert not env.blocked(m.ground[:, :2]).any(), patch.layer
        assert np.allclose(m.ground[-1, :2], (13.0, 1.3), atol=1e-6)
        # The straight line is blocked: the path bends round the pillars.
        assert np.abs(m.ground[:, 1] - 1.3).max() > 0.3


def test_on_open_ground_walking_is_cheaper_and_chosen(run_patch, walk_patch):
    env_w = Environment(walk_patch.side, walk_patch.cells, radius=0.25)
    env_r = Environment(run_patch.side, run_patch.cells, radius=0.25)
    start, goal = (0.5, 0.5, 0.0), (12.0, 3.0, 0.3)
    walk = SegmentPlanner(walk_patch, env_w).plan(start, goal)
    run = SegmentPlanner(run_patch, env_r).plan(start, goal)
    assert walk.cost < run.cost
    assert layers.choose([walk.cost, run.cost]) == 0
    # A character that weighs only distance and turning finds running no dearer (within the
    # few centimetres the two lattices' paths differ by), and one that weighs effort only
    # finds it far dearer.
    walk_d = SegmentPlanner(walk_patch, env_w, 1.0, 0.5, 0.0).plan(start, goal)
    run_d = SegmentPlanner(run_patch, env_r, 1.0, 0.5, 0.0).plan(start, goal)
    assert run_d.cost == pytest.approx(walk_d.cost, rel=0.05)
    walk_e = SegmentPlanner(walk_patch, env_w, 0.0, 0.0, 1.0).plan(start, goal)
    run_e = SegmentPlanner(run_patch, env_r, 0.0, 0.0, 1.0).plan(start, goal)
    assert run_e.cost > 1.5 * walk_e.cost


def test_a_run_refused_says_run_not_walk(run_patch, walk_patch):
    """A goal facing away from a pillar right behind it: neither gait can arrive facing
    that way (it would come through the pillar), and each refusal names its own gait."""
    for patch in (walk_patch, run_patch):
        env = Environment(patch.side, patch.cells, radius=0.25)
        env.place(pillar("behind", 9.4, 1.0, 0.3))
        with pytest.raises(PlanError) as err:
            SegmentPlanner(patch, env, turn_in_place=False).plan((0.5, 1.0, 0.0), (10.0, 1.0, 0.0))
        said = str(err.value)
        assert f"no {patch.layer} can" in said or f"the {patch.layer} cannot" in said, said
        other = "walk" if patch.layer == "run" else "run"
        assert f"no {other} can" not in said and f"the {other} cannot" not in said, said


def test_planned_run_skates_like_its_source_clip(run_patch, run_gait, run_clips):
    """Foot skate of a planned run down a street (a start connector, straight run segments,
    a goal connector: no foot locking) within 1.25x the recording's own. Turning runs skate
    more (about 1.7x at a 90 degree turn, see the issue-19 report): foot locking pins them."""
    env = Environment(run_patch.side, run_patch.cells, radius=0.25)
    plan = SegmentPlanner(run_patch, env).plan((0.5, 0.5, 0.0), (14.0, 0.5, 0.0))
    m = concatenate(plan_motions(run_patch, plan, standing=False))
    planned = metrics.foot_skate(world_feet(run_gait, m), run_gait.fps, m.contacts)
    src = run_clips[0]
    planted, _, _ = contacts.foot_contacts(src)
    fj = contacts.foot_joints(src.skeleton)
    source = metrics.foot_skate(src.joint_positions()[:, fj], src.fps, planted)
    print(
        f"run skate: planned {planned['mean_cm_per_s']:.1f} cm/s, 16_35 "
        f"{source['mean_cm_per_s']:.1f} cm/s"
    )
    assert planned["planted_steps"] > 20
    assert planned["mean_cm_per_s"] <= 1.25 * source["mean_cm_per_s"]


def clip(layer_in, layer_out, kind="traversal"):
    return PatchClip("jump", kind, None, 1.0, layer_in, layer_out)


def test_traversal_clips_serve_the_layers_they_declare():
    assert layers.serves(clip("walk", "walk"), "walk")
    assert not layers.serves(clip("walk", "walk"), "run")
    assert layers.serves(clip("run", "run"), "run")
    assert not layers.serves(clip("walk", "run"), "run")  # entered walking: not a run clip
    assert layers.serves(clip("walk, run", "walk,run"), "run")
    assert layers.serves(clip("*", "*"), "run")
    prop = ObjectPatch(
        "chair",
        np.zeros((4, 2)),
        [clip("walk", "walk"), clip("run", "run"), clip("walk", "walk", "interaction")],
    )
    kept = layers.for_layer(prop, "run")
    assert [(c.layer_in, c.kind) for c in kept.clips] == [
        ("run", "traversal"),
        ("walk", "interaction"),
    ]
    assert layers.for_layer(prop, "walk").clips == [prop.clips[0], prop.clips[2]]
    assert len(prop.clips) == 3  # the prop itself is left as it was


def test_choose_takes_the_cheapest_layer_with_a_plan():
    assert layers.choose([3.0, 2.0]) == 1
    assert layers.choose([2.0, 2.0]) == 0
    assert layers.choose([None, 5.0]) == 1
    assert layers.choose([None, None]) is None
    with pytest.raises(ValueError, match="gait"):
        layers.check_gait("  ")


def test_blend_table_walk_to_run_ends_on_the_run_node_pose_without_a_pop(walk_patch, run_patch):
    """Each walk pose cluster has a blend into the run; the one from the walk's node pose
    starts on it and lands on the run's node pose (its pose distance to the run loop's
    first frame is zero within the stitch's tolerance, root continuous); the ground goes
    on at the blended pace; no joint turns more per frame at the joins than inside the
    walk and run cycles (99th percentile)."""
    from motion_patches.kinematics import poses, quat
    from motion_patches.patch import blend_table
    from motion_patches.planning.stitching import POSITION_TOLERANCE

    entries = blend_table.table(walk_patch, run_patch)
    assert len(entries) == walk_patch.pose_centres.shape[0]
    assert all(t.end_pose == run_patch.seg_pose[0, 0] for t in entries)
    assert all(
        0.5 * walk_patch.gait.frames <= t.frames <= 1.5 * walk_patch.gait.frames + 1
        for t in entries
    )
    m = blend_table.blend(walk_patch.gait, run_patch.gait, 0)  # from the walk's node pose
    lw, lr = walk_patch.gait.straight, run_patch.gait.straight
    offset = m.ground[-1]

    def dist(root, rot, ref_root, ref_rot):
        return float(
            np.abs(
                poses.pose_features(root[None], rot[None])
                - poses.pose_features(ref_root[None], ref_rot[None])
            ).max()
        )

    assert dist(m.root_local[0], m.rotations[0], lw.root_local[0], lw.rotations[0]) < 1e-6
    assert dist(m.root_local[-1], m.rotations[-1], lr.root_local[0], lr.rotations[0]) < 1e-6
    assert np.linalg.norm(m.root_local[-1] - lr.root_local[0]) < POSITION_TOLERANCE / 10
    # One cycle of the blend covers between a walk cycle and a run cycle of ground, straight.
    assert walk_patch.gait.cycle_distance < offset[0] < run_patch.gait.cycle_distance
    assert offset[1] == 0 and offset[2] == 0
    step = np.diff(m.ground[:, 0])
    assert (
        step.min() > 0 and step.max() < 1.5 * run_patch.gait.cycle_distance / lr.rotations.shape[0]
    )

    def joint_steps(rot):
        d = quat.mul(quat.conj(rot[:-1]), rot[1:])
        return 2 * np.arccos(np.clip(np.abs(d[..., 0]), 0, 1)).max(axis=1)

    inside = np.concatenate(
        [joint_steps(np.concatenate([lp.rotations, lp.rotations[:1]])) for lp in (lw, lr)]
    )
    joins = np.concatenate(
        [
            joint_steps(np.concatenate([lw.rotations[-1:], m.rotations[:2]])),
            joint_steps(np.concatenate([m.rotations[-2:], lr.rotations[1:2]])),
            joint_steps(m.rotations),
        ]
    )
    print(
        f"largest joint step: blend {np.degrees(joins.max()):.1f} deg, "
        f"99th percentile in the cycles {np.degrees(np.percentile(inside, 99)):.1f} deg"
    )
    assert joins.max() <= np.percentile(inside, 99)
    back = blend_table.table(run_patch, walk_patch)
    assert len(back) == run_patch.pose_centres.shape[0]
    assert all(t.end_pose == walk_patch.seg_pose[0, 0] for t in back)


# -- gait changes inside one plan (motion_patches.transitions) ---------------------------

CHAIR = np.array([[-0.2, -0.22], [0.2, -0.22], [0.2, 0.22], [-0.2, 0.22]])
LINE_X = 5.0


@pytest.fixture(scope="module")
def run_hurdle(walk_gait):
    """CMU 16_06, a standing forward jump (subject 16's only jump), declared here as a
    run-layer clip only: the walk cannot take it and must go round the chairs."""
    from motion_patches.props import object_patch as op

    c = op.patch_clip_from(cmu("16_06"), op.TRAVERSAL, walk_gait.fps, effort=8.0)
    c.layer_in = c.layer_out = "run"
    return c


def chair_world(patch, clip, half=5.0, pillars=()):
    """A line of chairs 0.5 m apart across the way at x = 5 (from -half to +half), each
    with the jump's copies every 10 degrees, and pillars; the props of ``patch``'s layer."""
    from motion_patches.props import object_patch as op

    env = Environment(patch.side, patch.cells, radius=0.25)
    props = []
    for k, y in enumerate(np.linspace(-half, half, int(round(2 * half / 0.5)) + 1)):
        o = op.ObjectPatch(f"chair{k}", CHAIR, pose=(LINE_X, y, 0.0))
        o.add_traversal_copies(clip)
        env.place(Obstacle(o.name, o.world_footprint()))
        props.append(layers.for_layer(o, patch.layer))
    for n, (x, y) in enumerate(pillars):
        env.place(pillar(f"pillar{n}", x, y))
    return env, props


def planners(walk_patch, run_patch, clip, **kw):
    return tuple(
        SegmentPlanner(p, *chair_world(p, clip, **kw)[:1], props=chair_world(p, clip, **kw)[1])
        for p in (walk_patch, run_patch)
    )


START, GOAL = (-4.0, 0.3, 0.0), (14.0, 0.3, 0.0)


@pytest.fixture(scope="module")
def gait_change(walk_patch, run_patch, run_hurdle):
    """Walk-only, run-only and walk -> run -> walk plans across a 10 m line of chairs."""
    from motion_patches.planning import transitions

    walk, run = planners(walk_patch, run_patch, run_hurdle)
    w, r = walk.plan(START, GOAL), run.plan(START, GOAL)
    mixed = transitions.compose(walk, run, START, GOAL)
    return walk, run, w, r, mixed, transitions.plan_layer_motions(mixed)


def layer_of(piece):
    return piece.kind if piece.kind in ("traversal", "transition") else piece.patch.layer


def test_auto_walks_runs_hurdles_and_walks_back_when_the_way_round_is_long(gait_change):
    walk, run, w, r, mixed, ms = gait_change
    assert w.stats["traversals_used"] == 0  # the jump is a run clip: the walk goes round
    whole = concatenate(plan_motions(walk.patch, w))
    at_line = whole.ground[np.argmax(whole.ground[:, 0] >= LINE_X)]
    assert abs(at_line[1]) > 5.0
    seq = [layer_of(p) for p in mixed.pieces]
    collapsed = [s for i, s in enumerate(seq) if i == 0 or s != seq[i - 1]]
    assert collapsed == ["walk", "transition", "run", "traversal", "run", "transition", "walk"]
    assert [p.label for p in mixed.pieces if p.kind == "transition"] == [
        "walk -> run",
        "run -> walk",
    ]
    costs = [w.stats["cost_shortened"], r.stats["cost_shortened"], mixed.cost]
    print(
        f"Eq. 5 cost: walk {costs[0]:.2f}, run {costs[1]:.2f}, walk+run {costs[2]:.2f} "
        f"(composed in {mixed.seconds:.2f} s, {mixed.stats['compositions_tried']} ways back "
        f"searched of {mixed.stats['compositions_bounded']})"
    )
    assert layers.choose(costs) == 2
    assert mixed.cost == pytest.approx(sum(p.cost for p in mixed.pieces))
    m = concatenate(ms)
    assert np.allclose(m.ground[-1, :2], GOAL[:2], atol=1e-6)
    assert np.allclose(m.ground[0, :2], START[:2], atol=1e-6)


def test_a_transition_lands_on_a_node_of_the_target_layer_within_the_stitch_threshold(
    gait_change,
):
    """The blend's end (its start state concatenated with the table's relative transform)
    is where the next piece begins, a node of the target layer's lattice in that piece's
    plan frame (on a tile edge, in a node slot, at a 45-degree heading), and the blend's
    last pose is the target's node pose: the pose distance to the target loop's phase 0 is
    within the stitch's pose tolerance of the best phase's."""
    from motion_patches.kinematics import poses
    from motion_patches.planning import shortcut, stitching, transitions
    from motion_patches.planning.plan_frame import state_to_local

    walk, run, _, _, mixed, ms = gait_change
    by_layer = {"walk": walk, "run": run}
    k = [i for i, p in enumerate(mixed.pieces) if p.kind == "transition"]
    assert len(k) == 2
    for i in k:
        t, nxt = mixed.pieces[i], mixed.pieces[i + 1]
        target = by_layer[t.transition.target]
        assert nxt.patch is target.patch
        end = transitions.after(t.frame, t.transition.offset)
        p, h = shortcut.entry_state(target, nxt)
        local_end = state_to_local(nxt.frame, end)
        err = np.linalg.norm(local_end[:2] - p)
        dh = abs((local_end[2] - h + np.pi) % (2 * np.pi) - np.pi)
        print(f"{t.label}: lands {err * 1000:.4f} mm, {np.degrees(dh):.5f} deg from the node")
        assert err < stitching.POSITION_TOLERANCE / 100 and dh < stitching.HEADING_TOLERANCE / 100
        side, n = target.patch.side, target.patch.nodes
        q = p / side - np.floor(p / side + 1e-9)  # place in the tile, 0..1
        on_edge = np.isclose(q, 0.0, atol=1e-6) | np.isclose(q, 1.0, atol=1e-6)
        assert on_edge.sum() == 1
        slot = q[~on_edge][0] * n - 0.5
        assert slot == pytest.approx(round(slot), abs=1e-6)
        assert (h / (np.pi / 4)) == pytest.approx(round(h / (np.pi / 4)), abs=1e-6)
        last = t.transition.motion
        d = stitching.phase_pose_distance(
            target.patch.gait, last.root_local[-1], last.rotations[-1]
        )
        assert d[0] <= stitching.POSE_TOLERANCE * d.min() + 1e-9
        # The next piece starts on that pose (its first frame, as synthesised).
        first = ms[i + 1]
        gap = np.abs(
            poses.pose_features(first.root_local[:1], first.rotations[:1])
            - poses.pose_features(last.root_local[-1:], last.rotations[-1:])
        ).max()
        loop = target.patch.gait.straight
        f = poses.pose_features(loop.root_local, loop.rotations)
        assert gap <= np.median(np.abs(np.diff(f, axis=0)).max(axis=1))


def joint_steps(rot):
    from motion_patches.kinematics import quat

    d = quat.mul(quat.conj(rot[:-1]), rot[1:])
    return 2 * np.arccos(np.clip(np.abs(d[..., 0]), 0, 1)).max(axis=1)


def test_the_gait_change_has_no_pop_and_no_root_jump(gait_change):
    """At every join of the walk -> run -> walk plan the largest joint step is below the
    99th percentile of the steps inside its pieces; the hips never move farther in a frame
    than 1.5 x the per-frame speed of the faster layer a piece plays in."""
    from motion_patches.planning import transitions

    walk, run, _, _, mixed, ms = gait_change
    m = concatenate(ms)
    steps = joint_steps(m.rotations)
    bounds = np.cumsum([x.frames - 1 for x in ms])[:-1]
    joins = np.concatenate([steps[b - 1 : b + 1] for b in bounds])
    inside = np.concatenate([joint_steps(x.rotations) for x in ms])
    p99 = np.percentile(inside, 99)
    print(
        f"largest joint step at a join {np.degrees(joins.max()):.1f} deg, p99 inside "
        f"{np.degrees(p99):.1f} deg"
    )
    assert joins.max() < p99
    skel = walk.patch.gait.skeleton
    first = 0
    for piece, x in zip(mixed.pieces, ms):
        hips = x.world_matrices(skel)[:, skel.root, :2, 3]
        fast = walk.patch if layer_of(piece) == "walk" else run.patch
        per_frame = layers.speed(fast.gait) / fast.gait.fps
        step = np.linalg.norm(np.diff(hips, axis=0), axis=1).max()
        assert step < 1.5 * per_frame, piece.label
        first += x.frames - 1
    # Ground track checks of the validator, each piece by its own layer's limits.
    assert transitions.glitches(mixed, ms) == []
    joined = m.world_matrices(skel)[:, skel.root, :2, 3]
    assert np.linalg.norm(np.diff(joined, axis=0), axis=1).max() < 1.5 * (
        layers.speed(run.patch.gait) / run.patch.gait.fps
    )


def test_where_walking_round_is_short_auto_walks(walk_patch, run_patch, run_hurdle):
    """Five chairs (a 2 m line): the run plan hurdles them and a walk -> run -> walk plan is
    found, but walking round is cheaper than either; on open ground there is nothing to
    run for (no composition is offered)."""
    from motion_patches.planning import transitions
    from motion_patches.planning.planner import PlanError

    walk, run = planners(walk_patch, run_patch, run_hurdle, half=1.0)
    w, r = walk.plan(START, GOAL), run.plan(START, GOAL)
    assert r.stats["traversals_used"] == 1
    mixed = transitions.compose(walk, run, START, GOAL).cost
    costs = [w.stats["cost_shortened"], r.stats["cost_shortened"], mixed]
    print("short line, Eq. 5 cost walk / run / walk+run:", costs)
    assert layers.choose(costs) == 0
    env_w = Environment(walk_patch.side, walk_patch.cells, radius=0.25)
    env_r = Environment(run_patch.side, run_patch.cells, radius=0.25)
    with pytest.raises(PlanError, match="no prop offers a run traversal clip"):
        transitions.compose(
            SegmentPlanner(walk_patch, env_w), SegmentPlanner(run_patch, env_r), START, GOAL
        )


def test_a_gait_change_avoids_pillars_in_every_layer(walk_patch, run_patch, run_hurdle):
    """Pillars before and after the chair line, on the straight way: the walk, blend and
    run pieces of the plan that changes gait keep the radius from every footprint (the
    hurdle clip alone crosses its chair)."""
    from motion_patches.planning import transitions

    field = [(0.5, 0.2), (2.8, 0.6), (7.5, 0.0), (10.5, 0.5)]
    walk, run = planners(walk_patch, run_patch, run_hurdle, pillars=field)
    mixed = transitions.compose(walk, run, START, GOAL)
    ms = transitions.plan_layer_motions(mixed)
    env = walk.world_env
    seen = set()
    for piece, m in zip(mixed.pieces, ms):
        if piece.kind == "traversal":
            continue
        seen.add(layer_of(piece))
        assert not env.blocked(m.ground[:, :2]).any(), piece.label
    assert seen == {"walk", "run", "transition"}
    g = concatenate(ms).ground
    near = [np.hypot(g[:, 0] - x, g[:, 1] - y).min() for x, y in field]
    print("closest approach to each pillar (m):", np.round(near, 3))
    assert min(near) >= 0.25 + 0.25 - 1e-6


def test_a_run_does_not_turn_on_the_spot(run_gait, walk_gait):
    """The turn in place is derived from a walk's turn loop; a runner slows to a walk to
    turn round, so a run layer (flight phase) loops as before."""
    from motion_patches.planning import turn_in_place

    assert turn_in_place.can_turn(walk_gait, *walk_gait.kappa_limits)
    assert not turn_in_place.can_turn(run_gait, *run_gait.kappa_limits)
