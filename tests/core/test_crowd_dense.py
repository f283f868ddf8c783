# SPDX-License-Identifier: GPL-3.0-or-later
"""Dense crowds from the real walk: a four-way crossing of 40 between pillars and a
counter-flow of 40 through a 2 m doorway (another shuffle of its goals too, and a 2.5 m
doorway), planned, resolved and then checked on the motion itself: the pieces
re-synthesised with the holds laid in, played at a 24 fps scene from the 30 fps patch,
every root against every other on every frame and against the props."""

import time
from concurrent.futures import ThreadPoolExecutor
from functools import partial

import numpy as np
import pytest

from motion_patches.crowd import crowd, held_motion, members
from motion_patches.kinematics import retime, scene_rate
from motion_patches.kinematics.inplace import root_positions
from motion_patches.kinematics.motion import concatenate
from motion_patches.planning.pieces import PlanError
from motion_patches.planning.settings import PlanSettings
from motion_patches.props.environment import Environment, Obstacle

RADIUS = 0.25
SPACING = 2 * RADIUS
SLACK = 0.05  # resolved this much wider than checked (as api.plan_crowd does)
SCENE_FPS = 24.0


def pillar(name, x, y, r=0.35, sides=12):
    a = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def box(name, x0, y0, x1, y1):
    return Obstacle(name, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float))


def fourway(patch, per_side=10, half=10.5, seed=5):
    """A 21 m plaza, seven pillars in its middle, ``per_side`` walkers entering from each
    side and crossing to the far side, their goals there shuffled."""
    rng = np.random.default_rng(seed)
    env = Environment(patch.side, patch.cells, RADIUS)
    ring = [(3.5 * np.cos(a), 3.5 * np.sin(a)) for a in np.arange(6) * np.pi / 3 + 0.3]
    for k, (x, y) in enumerate([(0.0, 0.0)] + ring):
        env.place(pillar(f"pillar{k}", x, y))
    lane = np.linspace(-6.5, 6.5, per_side)
    ends, edge = [], half - 1.0
    for d, h in (((1, 0), 0.0), ((-1, 0), np.pi), ((0, 1), np.pi / 2), ((0, -1), -np.pi / 2)):
        d = np.array(d, float)
        side = np.array([-d[1], d[0]])
        goals = rng.permutation(per_side)
        for k in range(per_side):
            s = -edge * d + lane[k] * side
            g = (edge - 1.0) * d + (lane[goals[k]] + 0.7) * side
            ends.append((np.r_[s, h], np.r_[g, h]))
    return env, ends


def doorway(patch, per_side=20, gap=2.0, seed=5):
    """A wall with a ``gap`` m doorway; ``per_side`` walkers on each side, on a staggered
    grid 3 to 9 m from the wall, cross to shuffled places on the other side."""
    rng = np.random.default_rng(seed)
    env = Environment(patch.side, patch.cells, RADIUS)
    env.place(box("wall.s", -0.15, -14.0, 0.15, -gap / 2))
    env.place(box("wall.n", -0.15, gap / 2, 0.15, 14.0))
    grid = [
        (x, y + (1.5 if c % 2 else 0.0))
        for c, x in enumerate((3.0, 5.0, 7.0, 9.0))
        for y in np.linspace(-7.5, 4.5, per_side // 4)
    ]
    ends = []
    for sign, h in ((1, 0.0), (-1, np.pi)):
        order = rng.permutation(len(grid))
        for k, (x, y) in enumerate(grid):
            gx, gy = grid[order[k]]
            ends.append((np.r_[-sign * x, y, h], np.r_[sign * (gx + 1.0), gy + 0.75, h]))
    return env, ends


def plan_crowd(patch, env, ends, fps, max_wait, times=None, later=None):
    """The crowd as ``api.plan_crowd`` plans it, on the core: ([(pieces, plan)], schedules,
    ramp). Priority by distance; each member planned by the core
    (:func:`motion_patches.crowd.members.plan_member`: round the props and the others'
    standing spots, its motion at the scene's rate); holds, waits and re-routes timed on the
    scene's frames. ``times`` (a dict) gets the seconds of the members (re-plans included)
    and of resolution. ``later(replan)``: the ``replan_later`` of :func:`crowd.resolve`
    made of the re-plan (None: re-planned when its turn comes)."""
    times = {} if times is None else times
    for k in ("members", "resolve"):
        times[k] = 0.0
    ends = sorted(ends, key=lambda e: -np.linalg.norm(e[1][:2] - e[0][:2]))
    world = members.MemberWorld(
        patch,
        env,
        [],
        PlanSettings(radius=RADIUS),
        scene_fps=fps,
        rank_ends=ends,
        spot_names=[f"spot{m}" for m in range(len(ends))],
        spacing=SPACING + SLACK,  # the standing spots kept as the crowd is resolved
    )
    ramp = world.ramp

    def solve(i, extra=()):
        ends_i = (ends[i][0], ends[i][1], None, None)
        task = members.MemberTask(i, ends_i, rank=i, ghosts=list(extra))
        t0 = time.perf_counter()
        a = members.plan_member(task, world)
        times["members"] += time.perf_counter() - t0
        if isinstance(a, members.NoPlan):
            raise PlanError(a.text)
        return (members.unpacked(a.raw), a.plan), a.root_track, a.holdable

    versions = [[solve(i)] for i in range(len(ends))]

    def replan(k, discs):
        try:
            versions[k].append(solve(k, discs))
        except PlanError:
            return None
        return versions[k][-1][1:]

    t0, before = time.perf_counter(), times["members"]
    schedules, _ = crowd.resolve(
        [v[0][1] for v in versions],
        replan,
        SPACING + SLACK,
        RADIUS,
        fps,
        round(max_wait * fps),
        max(1, round(0.2 * fps)),
        ramp=ramp,
        holdable=[v[0][2] for v in versions],
        replan_later=None if later is None else later(replan),
    )
    re_plans = times["members"] - before
    times["resolve"] = time.perf_counter() - t0 - re_plans  # re-plans counted as members
    return [v[s.version][0] for v, s in zip(versions, schedules)], schedules, ramp


def written_roots(pieces, schedules, rate, ramp):
    """Root tracks of the motion as written: each hold laid into the piece it falls in
    (on the patch's frames, :func:`held_motion.held_piece`), the whole re-played at the
    scene's rate; what the resolver saw plays no part."""
    out = []
    for (raw, _), s in zip(pieces, schedules):
        raw = list(raw)
        for k, h in s.holds:
            pb, sb = scene_rate.piece_bounds([m.frames for m in raw], rate)
            i = int(np.searchsorted(sb, k, "right") - 1)
            span = int(sb[i + 1] - sb[i])
            if abs(rate - 1.0) < 1e-9:
                raw[i] = retime.held(raw[i], k - sb[i], h, ramp)
            else:
                raw[i] = held_motion.held_piece(raw[i], k - sb[i], h, ramp, span, rate)
        pb, sb = scene_rate.piece_bounds([m.frames for m in raw], rate)
        world = scene_rate.at_scene_rate(concatenate(raw), pb, sb)
        out.append(root_positions(world.ground, world.root_local)[:, :2])
    return out


def closest_and_inside(roots, delays, env):
    """(closest approach of two roots on any frame, root frames inside a prop)."""
    horizon = max(len(r) + d for r, d in zip(roots, delays)) + 1
    lines = np.stack([crowd.timeline(r, d, horizon) for r, d in zip(roots, delays)])
    closest = np.inf
    for i in range(len(lines) - 1):
        closest = min(closest, np.linalg.norm(lines[i + 1 :] - lines[i], axis=2).min())
    inside = sum(int(env.blocked(r, radius=0.0).sum()) for r in roots)
    return closest, inside


@pytest.mark.parametrize(
    "scene, max_wait",
    [
        (fourway, 4.0),
        (doorway, 15.0),
        (partial(doorway, seed=6), 15.0),  # another shuffle of the same places
        (partial(doorway, gap=2.5), 15.0),
    ],
    ids=["four-way", "doorway", "doorway-seed-6", "doorway-2.5-m"],
)
def test_a_dense_crowd_ends_with_no_two_roots_too_close(walk_patch, scene, max_wait, monkeypatch):
    """Planned, resolved with its re-plans worked out beside the resolution
    (:func:`re_planned_beside`) and written: no two roots too close on any frame, none in a
    prop, everyone at its goal. Through a doorway every path goes through one gap: nobody
    is placed while a walker is re-planned (a re-route would meet them), so the crowd is
    the one placed one by one in priority order."""
    env, ends = scene(walk_patch)
    pieces, schedules, ramp, meanwhile = re_planned_beside(
        walk_patch, env, ends, max_wait, monkeypatch
    )
    if scene is not fourway:
        assert meanwhile and not any(meanwhile), meanwhile
    assert len(pieces) == 40
    rate = SCENE_FPS / walk_patch.gait.fps
    roots = written_roots(pieces, schedules, rate, ramp)
    ranked = sorted(ends, key=lambda e: -np.linalg.norm(e[1][:2] - e[0][:2]))
    for r, (_, goal) in zip(roots, ranked):
        assert np.linalg.norm(r[-1] - goal[:2]) < 0.3  # every one arrives
    closest, inside = closest_and_inside(roots, [s.delay for s in schedules], env)
    assert inside == 0
    assert closest >= SPACING, closest
    assert max(s.delay for s in schedules) <= round(max_wait * SCENE_FPS)


def two_crossings(patch, per_side=5, apart=40.0):
    """Two four-way crossings (:func:`fourway`, ``per_side`` walkers a side) ``apart`` metres
    from each other: two crowds that never meet, resolved as one."""
    env, ends = fourway(patch, per_side)
    far, far_ends = fourway(patch, per_side, seed=6)
    for ob in far.obstacles.values():
        env.place(Obstacle("far." + ob.name, ob.polygon + (apart, 0.0)))
    shift = np.array([apart, 0.0, 0.0])
    return env, ends + [(s + shift, g + shift) for s, g in far_ends]


def re_planned_beside(patch, env, ends, max_wait, monkeypatch):
    """``plan_crowd`` with its re-plans asked for at once and worked out in another thread
    (as a cluster's worker does), their answers taken in the order asked: (pieces,
    schedules, ramp, [characters placed while each re-plan was worked out])."""
    events = []
    reserve = crowd.Reservations.reserve

    def placed(self, index, track, delay=0):
        events.append(("placed", index))
        return reserve(self, index, track, delay)

    monkeypatch.setattr(crowd.Reservations, "reserve", placed)
    pool = ThreadPoolExecutor(max_workers=1)

    class Asked:
        def __init__(self, replan, k, discs):
            events.append(("asked", k))
            self.k, self.future = k, pool.submit(replan, k, discs)

        def result(self):
            events.append(("taken", self.k))
            return self.future.result()

    try:
        pieces, beside, ramp = plan_crowd(
            patch, env, ends, SCENE_FPS, max_wait, later=lambda r: partial(Asked, r)
        )
    finally:
        pool.shutdown()
        monkeypatch.undo()
    meanwhile = []
    for n, (e, k) in enumerate(events):
        if e == "asked":
            assert events.count(("taken", k)) >= 1
            taken = events.index(("taken", k), n)
            meanwhile.append([j for x, j in events[n:taken] if x == "placed"])
    assert [k for e, k in events if e == "taken"] == [k for e, k in events if e == "asked"]
    return pieces, beside, ramp, meanwhile


def test_re_plans_worked_out_beside_the_resolution_give_the_same_crowd(walk_patch, monkeypatch):
    """Two crossings far apart: while a walker of one is re-planned in another thread,
    walkers of the other (whose paths keep clear of its path) are placed; the schedules are
    the same, to the bit, as when each re-plan is worked out when its answer is taken
    (what happens in process); the answers are taken in the order asked."""
    env, ends = two_crossings(walk_patch)
    _, alone, _ = plan_crowd(walk_patch, env, ends, SCENE_FPS, 4.0)
    _, beside, _, meanwhile = re_planned_beside(walk_patch, env, ends, 4.0, monkeypatch)
    assert [_schedule(s) for s in beside] == [_schedule(s) for s in alone]
    assert any(s.rerouted for s in beside)
    assert any(meanwhile), meanwhile


def _schedule(s):
    return (s.delay, s.holds, s.version, s.rank, s.track.tobytes())


def test_a_gap_one_walker_wide_is_taken_in_turn(walk_patch):
    """A 1 m gap fits one walker at a time: four each way cross it in turn, some holding or
    waiting for the gap to clear, and the motion as written keeps them apart."""
    env, ends = doorway(walk_patch, per_side=4, gap=1.0)
    pieces, schedules, ramp = plan_crowd(walk_patch, env, ends, SCENE_FPS, 15.0)
    assert len(pieces) == 8
    assert any(s.holds or s.delay for s in schedules)
    roots = written_roots(pieces, schedules, SCENE_FPS / walk_patch.gait.fps, ramp)
    ranked = sorted(ends, key=lambda e: -np.linalg.norm(e[1][:2] - e[0][:2]))
    for r, (_, goal) in zip(roots, ranked):
        assert np.linalg.norm(r[-1] - goal[:2]) < 0.3
    closest, inside = closest_and_inside(roots, [s.delay for s in schedules], env)
    assert inside == 0
    assert closest >= SPACING, closest
