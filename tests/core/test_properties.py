# SPDX-License-Identifier: GPL-3.0-or-later
"""Property suite: thousands of random and adversarial layouts, every plan checked for what
must always hold (issue: nothing lost, nothing crossed).

Kinds of layout, drawn from one seeded generator: random pillar fields, thin fences (2 cm
boards, as a plane wall becomes), tiny props (a few centimetres), start and goal close
together, and walls with a gap. For each: either a plan, whose ground path never comes
within the radius of a footprint (to the sampling precision), whose hips never enter one,
whose pieces join without a jump or a spin, and which ends on the goal facing the goal's way;
or a refusal whose message says why. Run with ``-s`` to see the counts the README quotes.
"""

import os

import numpy as np
import pytest

from motion_patches.kinematics.inplace import to_world
from motion_patches.kinematics.motion import concatenate
from motion_patches.planning.planner import PlanError, SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment, Obstacle
from motion_patches.quality import validate

LAYOUTS = int(os.environ.get("MOTION_PATCHES_PROPERTY_LAYOUTS", "2000"))
KINDS = ("pillars", "fences", "tiny", "close", "gap")
RADIUS = 0.25
SAMPLING_SLACK = 0.004  # metres: between 4 cm path samples a walk may cut a corner this much


def disc(name, x, y, r, sides=12):
    a = np.linspace(0, 2 * np.pi, sides + 1)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def board(name, p, q, thickness=0.02):
    p, q = np.asarray(p, float), np.asarray(q, float)
    d = (q - p) / max(np.linalg.norm(q - p), 1e-9)
    n = np.array([-d[1], d[0]]) * thickness / 2
    return Obstacle(name, np.array([p - n, q - n, q + n, p + n]))


def layout(kind, rng, patch):
    """(environment, start, goal) of one layout of ``kind``."""
    env = Environment(patch.side, patch.cells, RADIUS)
    obs = []
    if kind == "pillars":
        for k in range(int(rng.integers(5, 30))):
            obs.append(disc(f"p{k}", *rng.uniform((1, -4), (11, 4)), rng.uniform(0.1, 0.5)))
    elif kind == "fences":
        for k in range(int(rng.integers(1, 6))):
            p = rng.uniform((1, -4), (11, 4))
            obs.append(
                board(
                    f"f{k}",
                    p,
                    p
                    + rng.uniform(1.0, 4.0)
                    * np.array([np.cos(a := rng.uniform(0, np.pi)), np.sin(a)]),
                )
            )
    elif kind == "tiny":
        for k in range(int(rng.integers(10, 60))):
            obs.append(disc(f"t{k}", *rng.uniform((1, -4), (11, 4)), rng.uniform(0.01, 0.06), 6))
    elif kind == "gap":
        x, c, w = rng.uniform(4, 8), rng.uniform(-2, 2), rng.uniform(0.5, 1.2)
        obs += [board("lo", (x, -8), (x, c - w / 2), 0.2), board("hi", (x, c + w / 2), (x, 8), 0.2)]
    for ob in obs:
        env.place(ob)
    for _ in range(200):
        s = np.array([*rng.uniform((-1, -3), (1, 3)), rng.uniform(-np.pi, np.pi)])
        if kind == "close":
            g = s + np.array([*rng.uniform(-2, 2, 2), rng.uniform(-np.pi, np.pi)])
            if np.linalg.norm(g[:2] - s[:2]) < 0.3:
                continue
        else:
            g = np.array([*rng.uniform((10, -3), (13, 3)), rng.uniform(-np.pi, np.pi)])
        if not env.blocked(np.array([s[:2], g[:2]])).any():
            return env, s, g
    return None


def violations(patch, env, plan, goal):
    """What a found plan breaks, as a list of short words (empty when nothing)."""
    out = []
    motions = plan_motions(patch, plan)
    m = concatenate(motions)
    ground = m.ground[:, :2]
    tight = Environment(env.side, env.cells, RADIUS - SAMPLING_SLACK)
    for ob in env.obstacles.values():
        tight.place(ob)
    if tight.blocked(ground).any():
        out.append("ground path within the radius")
    hips = to_world(patch.gait.skeleton, m.ground, m.root_local, m.rotations)[0][:, :2]
    inside = Environment(env.side, env.cells, 1e-6)
    for ob in env.obstacles.values():
        inside.place(ob)
    if inside.blocked(hips).any():
        out.append("hips inside a footprint")
    if np.linalg.norm(np.diff(ground, axis=0), axis=1).max() > 0.1:
        out.append("jump")
    if np.abs(np.diff(m.ground[:, 2])).max() > 0.2:
        out.append("heading jump")
    if validate.count(validate.plan_glitches(patch, plan, motions)):
        out.append("glitch (spin, backwards or jump)")
    if np.linalg.norm(ground[-1] - goal[:2]) > 1e-6:
        out.append("goal missed")
    if abs((m.ground[-1, 2] - goal[2] + np.pi) % (2 * np.pi) - np.pi) > 1e-6:
        out.append("goal heading missed")
    return out


def test_every_layout_plans_cleanly_or_says_why(walk_patch):
    rng = np.random.default_rng(20261124)
    tried = planned = refused = 0
    broken = []
    for n in range(LAYOUTS):
        kind = KINDS[n % len(KINDS)]
        made = layout(kind, rng, walk_patch)
        if made is None:
            continue
        env, start, goal = made
        tried += 1
        try:
            plan = SegmentPlanner(walk_patch, env).plan(start, goal)
        except PlanError as exc:
            refused += 1
            if len(str(exc)) < 20:
                broken.append((n, kind, f"refused without a reason: {exc!r}"))
            continue
        planned += 1
        bad = violations(walk_patch, env, plan, goal)
        if bad:
            broken.append((n, kind, bad))
    print(
        f"\nproperty suite: {tried:,} layouts tried ({', '.join(KINDS)}), {planned:,} planned, "
        f"{refused:,} refused with a reason, violations: {len(broken)}"
    )
    assert tried >= 0.95 * LAYOUTS
    assert planned > 0.6 * tried
    assert not broken, broken[:10]


@pytest.mark.parametrize("kind", KINDS)
def test_each_kind_of_layout_is_drawn_and_planned(walk_patch, kind):
    """The generator makes what it says (so the suite above tests each kind)."""
    rng = np.random.default_rng(7)
    made = [layout(kind, rng, walk_patch) for _ in range(6)]
    made = [m for m in made if m is not None]
    assert len(made) >= 5
    found = 0
    for env, start, goal in made:
        try:
            SegmentPlanner(walk_patch, env).plan(start, goal)
            found += 1
        except PlanError:
            pass
    assert found >= 1
    if kind == "fences":  # boards 2 cm thin
        assert all(width(o.polygon) < 0.03 for e, _, _ in made for o in e.obstacles.values())


def width(poly):
    """Smallest width of a convex polygon (over its edges' directions)."""
    out = np.inf
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        d = (b - a) / max(np.linalg.norm(b - a), 1e-12)
        out = min(out, np.abs((poly - a) @ np.array([-d[1], d[0]])).max())
    return out
