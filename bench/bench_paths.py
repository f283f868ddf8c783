# SPDX-License-Identifier: GPL-3.0-or-later
"""Benchmark of path quality: detours, straight lines, glitches, failures, starts and stops.

Prints numbers next to their targets, asserts nothing. Run from the repository root:

    .venv/blender-4.5/bin/python bench/bench_paths.py [--only gap] [--json out.json]

1. Bakes the walk patch as bench_core does (CMU 16_15 straight, 16_18 left turn).
2. Builds scenes (empty straight walks, a wall with a 1.0 / 0.8 m gap, 40 pillars, a U-turn
   round a wall's end, walls 30 degrees off the grid, a few start / goal headings) and the
   random pillar fields of bench_core (same seed, same layouts).
3. For each start / goal pair computes a reference: the exact shortest path that keeps the
   character's radius from every footprint (a visibility graph on the footprints grown by
   the radius), and plans in two variants: "along" (the character faces along the
   reference's first leg and the goal faces along its last, the way a user sets a scene
   up) and "facing-Y" (start and goal both facing -Y, as an untouched imported rig or a
   default empty is).
4. Measures each plan: detour ratio against the reference, lateral deviation of the
   straight walks, glitches (motion_patches.validate), speed on the first and last frame,
   final heading and position error, frames within the radius of an obstacle, and where
   the extra length comes from (start connector, goal connector, lattice, route); and the
   feet as the API writes them (foot locked): the skate the planner labels planted beside
   the label-free measure (motion_patches.quality.foot_measure), each beside the source
   clip's by the same measure.

One line per plan while running, then Markdown tables with each target met / not met;
``--json PATH`` also writes every record.
"""

import argparse
import heapq
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
for p in (str(REPO), str(HERE)):
    if p not in sys.path:
        sys.path.insert(0, p)

import bench_core as core  # noqa: E402

from motion_patches.kinematics import clip as clip_mod
from motion_patches.kinematics import foot_lock
from motion_patches.kinematics.inplace import to_world
from motion_patches.kinematics.motion import Motion, concatenate
from motion_patches.planning import planner as planner_mod
from motion_patches.planning.settings import PLANNING as DEFAULTS
from motion_patches.props.environment import Environment, Obstacle, distance_to_polygon
from motion_patches.quality import foot_measure, metrics, validate

WEIGHTS = tuple(DEFAULTS[k] for k in ("alpha", "beta", "gamma"))

VARIANTS = ("along", "facing-Y")
FACING_Y = -np.pi / 2
ARC_STEP = np.radians(15.0)  # circumscribed polygon of the radius arcs: at most 0.86 % of r out
TARGETS = {  # figure: (comparison, value, shown)
    "detour_median": ("<=", 1.10, "≤ 1.10"),
    "detour_worst": ("<=", 1.25, "≤ 1.25"),
    "straight_deviation_m": ("<=", 0.05, "≤ 5 cm (16 m straight, empty scene)"),
    "glitches": ("<=", 0, "0"),
    "failures_with_clear_path": ("<=", 0, "0"),
    "start_speed_max": ("<", 0.2, "< 0.2 m/s"),
    "end_speed_max": ("<", 0.2, "< 0.2 m/s"),
    "start_speed_01s_max": ("<", 0.2, "< 0.2 m/s (over the first 0.1 s)"),
    "end_speed_01s_max": ("<", 0.2, "< 0.2 m/s (over the last 0.1 s)"),
    "heading_error_deg_max": ("<=", 5.0, "≤ 5°"),
    "position_error_m_max": ("<=", 0.05, "≤ 5 cm (chosen here)"),
    "hips_position_error_m_max": ("<=", 0.05, "≤ 5 cm (the hips over the goal point)"),
    "frames_inside": ("<=", 0, "0"),
}


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    core.add_layout_arguments(
        p,
        layouts="random pillar fields of bench_core (0: none)",
        seed="seed of the random fields and the 40-pillar scene",
    )
    p.add_argument(
        "--variants",
        nargs="+",
        choices=VARIANTS,
        default=list(VARIANTS),
        help="heading variants to plan (default both)",
    )
    p.add_argument(
        "--only",
        metavar="SCENE",
        default=None,
        help="comma-separated scene names or prefixes ('random' for the fields)",
    )
    core.add_mocap_argument(p, "cmu/16_15.bvh and cmu/16_18.bvh")
    p.add_argument("--json", metavar="PATH", help="also write all figures as JSON")
    return p.parse_args(argv)


# -- geometry -----------------------------------------------------------------------------


def unit(a):
    return np.array([np.cos(a), np.sin(a)])


def wrap(a):
    return (np.asarray(a, float) + np.pi) % (2 * np.pi) - np.pi


def wall(name, p, q, thickness=0.2):
    """Rectangle of ``thickness`` along the segment p -> q (counter-clockwise)."""
    p, q = np.asarray(p, float), np.asarray(q, float)
    d = (q - p) / np.linalg.norm(q - p)
    n = np.array([-d[1], d[0]]) * thickness / 2
    return Obstacle(name, np.array([p - n, q - n, q + n, p + n]))


def inflate(poly, r, arc_step=ARC_STEP):
    """Convex CCW polygon grown by a disc of radius r, its arcs replaced by a circumscribed
    polygon (vertex every ``arc_step`` at most): it contains the true grown footprint, so
    a path around it never comes within r of the footprint and is longer than the true
    shortest path by at most a fraction 1/cos(arc_step/2) - 1 of r per corner."""
    poly = np.asarray(poly, float)
    e = np.roll(poly, -1, axis=0) - poly
    out_angle = np.arctan2(-e[:, 0], e[:, 1])  # outward normal of edge i (v_i -> v_i+1)
    corners = []
    for i, v in enumerate(poly):
        a0 = out_angle[i - 1]
        turn = (out_angle[i] - a0) % (2 * np.pi)
        if turn > np.pi + 1e-9:  # not convex here: should not happen for footprints
            raise ValueError("inflate: polygon is not convex and counter-clockwise")
        m = max(1, int(np.ceil(turn / arc_step - 1e-9)))
        delta = turn / m
        ang = a0 + (np.arange(m) + 0.5) * delta
        corners.append(v + (r / np.cos(delta / 2)) * np.column_stack((np.cos(ang), np.sin(ang))))
    return np.concatenate(corners)


class Polygons:
    """Convex polygons as padded half-plane arrays, for vectorised tests."""

    def __init__(self, polys, eps=1e-7):
        self.polys = [np.asarray(p, float) for p in polys]
        k = max((len(p) for p in self.polys), default=1)
        n = len(self.polys)
        self.normal = np.zeros((n, k, 2))
        self.offset = np.zeros((n, k))
        self.lo = np.zeros((n, 2))
        self.hi = np.zeros((n, 2))
        for i, p in enumerate(self.polys):
            e = np.roll(p, -1, axis=0) - p
            nrm = np.column_stack((e[:, 1], -e[:, 0])) / np.linalg.norm(e, axis=1)[:, None]
            c = np.sum(nrm * p, axis=1) - eps  # interior: n.x < c (shrunk by eps)
            self.normal[i, : len(p)], self.offset[i, : len(p)] = nrm, c
            self.normal[i, len(p) :], self.offset[i, len(p) :] = nrm[-1], c[-1]
            self.lo[i], self.hi[i] = p.min(axis=0), p.max(axis=0)

    def __len__(self):
        return len(self.polys)

    def inside(self, points, skip=None):
        """(N, P) True where point n is strictly inside polygon p (``skip``: (N,) own
        polygon index to ignore, -1 none)."""
        pts = np.asarray(points, float)
        if len(self) == 0:
            return np.zeros((pts.shape[0], 0), bool)
        v = np.einsum("pkd,nd->npk", self.normal, pts) < self.offset[None]
        inside = v.all(axis=2)
        if skip is not None:
            own = np.asarray(skip)
            rows = np.flatnonzero(own >= 0)
            inside[rows, own[rows]] = False
        return inside

    def crossed(self, a, b, chunk=20000):
        """(E,) True where the open segment a -> b crosses the interior of a polygon."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        out = np.zeros(a.shape[0], bool)
        if len(self) == 0 or a.shape[0] == 0:
            return out
        slo, shi = np.minimum(a, b), np.maximum(a, b)
        for s in range(0, a.shape[0], chunk):
            sl = slice(s, s + chunk)
            near = np.all(slo[sl, None] <= self.hi[None], axis=2) & np.all(
                shi[sl, None] >= self.lo[None], axis=2
            )
            ei, pi = np.nonzero(near)
            if ei.size == 0:
                continue
            ei = ei + s
            n, c = self.normal[pi], self.offset[pi]  # (M, K, 2), (M, K)
            d = b[ei] - a[ei]
            num = c - np.einsum("mkd,md->mk", n, a[ei])
            den = np.einsum("mkd,md->mk", n, d)
            with np.errstate(divide="ignore", invalid="ignore"):
                t = num / den
            zero = np.abs(den) < 1e-15
            lo = np.max(np.where(den < -1e-15, t, -np.inf), axis=1, initial=0.0)
            hi = np.min(np.where(den > 1e-15, t, np.inf), axis=1, initial=1.0)
            feasible = ~np.any(zero & (num <= 0), axis=1)
            hit = feasible & (hi - lo > 1e-9)
            out[ei[hit]] = True
        return out


def _visibility_path(polys, start, goal):
    """Shortest start -> goal path around convex polygons (reduced visibility graph and
    Dijkstra): (length, points (K, 2)) or (None, reason)."""
    P = Polygons(polys)
    if len(P) and P.inside(np.array([start]))[0].any():
        return None, "start inside a grown footprint"
    if len(P) and P.inside(np.array([goal]))[0].any():
        return None, "goal inside a grown footprint"
    pts, owner, prev, nxt = [start, goal], [-1, -1], [0, 1], [0, 1]
    base = 2
    for i, p in enumerate(P.polys):
        k = len(p)
        pts.extend(p)
        owner.extend([i] * k)
        idx = base + np.arange(k)
        prev.extend(np.roll(idx, 1))
        nxt.extend(np.roll(idx, -1))
        base += k
    pts, owner = np.array(pts, float), np.array(owner)
    prev, nxt = np.array(prev), np.array(nxt)
    # Corners inside another grown footprint are never on a clear path.
    keep = ~P.inside(pts, owner).any(axis=1) if len(P) else np.ones(len(pts), bool)
    keep[:2] = True
    n = len(pts)
    i, j = np.triu_indices(n, 1)
    ok = keep[i] & keep[j]
    i, j = i[ok], j[ok]

    def tangent(v, w):  # the line v-w touches v's polygon only at v (or v is start/goal)
        d = pts[w] - pts[v]
        a, b = pts[prev[v]] - pts[v], pts[nxt[v]] - pts[v]
        s1 = d[:, 0] * a[:, 1] - d[:, 1] * a[:, 0]
        s2 = d[:, 0] * b[:, 1] - d[:, 1] * b[:, 0]
        scale = np.linalg.norm(d, axis=1) * 1e-9
        return (owner[v] < 0) | (s1 * s2 >= -scale * (np.abs(s1) + np.abs(s2)))

    ok = tangent(i, j) & tangent(j, i)
    i, j = i[ok], j[ok]
    vis = ~P.crossed(pts[i], pts[j])
    i, j = i[vis], j[vis]
    w = np.linalg.norm(pts[i] - pts[j], axis=1)
    adj = [[] for _ in range(n)]
    for a, b, c in zip(i.tolist(), j.tolist(), w.tolist()):
        adj[a].append((b, c))
        adj[b].append((a, c))
    dist = np.full(n, np.inf)
    back = np.full(n, -1)
    dist[0] = 0.0
    heap = [(0.0, 0)]
    while heap:
        d0, u = heapq.heappop(heap)
        if d0 > dist[u]:
            continue
        if u == 1:
            break
        for v, c in adj[u]:
            if d0 + c < dist[v]:
                dist[v], back[v] = d0 + c, u
                heapq.heappush(heap, (d0 + c, v))
    if not np.isfinite(dist[1]):
        return None, "no clear path"
    path, u = [1], 1
    while u != 0:
        u = back[u]
        path.append(u)
    return float(dist[1]), pts[path[::-1]]


def reference_path(obstacles, radius, start, goal):
    """Exact shortest path keeping ``radius`` from every convex footprint (grown footprints
    as :func:`inflate`), computed on the footprints near the way: a path of length L lies
    in the ellipse of points whose distances to start and goal sum to L, so only the
    footprints meeting that ellipse matter; L grows until the path found is no longer
    than it (then it is the shortest among all footprints). Returns a dict with
    ``length`` and ``points`` (K, 2), or ``length`` None and a ``reason``."""
    s, g = np.asarray(start[:2], float), np.asarray(goal[:2], float)
    grown = [inflate(o.polygon, radius) for o in obstacles]
    if not grown:
        return {
            "length": float(np.linalg.norm(g - s)),
            "points": np.array([s, g]),
            "footprints_used": 0,
        }
    centre = np.array([q.mean(axis=0) for q in grown])
    rho = np.array([np.linalg.norm(q - c, axis=1).max() for q, c in zip(grown, centre)])
    near = np.linalg.norm(centre - s, axis=1) + np.linalg.norm(centre - g, axis=1) - 2 * rho
    d = float(np.linalg.norm(g - s))
    bound = 1.25 * d + 1.0
    while True:
        use = near <= bound
        length, pts = _visibility_path([grown[k] for k in np.flatnonzero(use)], s, g)
        if length is not None and length <= bound:
            return {"length": length, "points": pts, "footprints_used": int(use.sum())}
        if use.all():
            if length is None:
                return {"length": None, "reason": pts, "footprints_used": int(use.sum())}
            return {"length": length, "points": pts, "footprints_used": int(use.sum())}
        bound = max(bound * 1.5, (length or 0.0) + 1e-6)


# -- heading-aware bound ----------------------------------------------------------------

TAU = 2 * np.pi


def mod2pi(a):
    return a % TAU


def _dubins_words(alpha, beta, d):
    """{word: (t, p, q)} of the Dubins words that exist, in units of the radius."""
    sa, sb, ca, cb = np.sin(alpha), np.sin(beta), np.cos(alpha), np.cos(beta)
    cab = np.cos(alpha - beta)
    out = {}
    p2 = 2 + d * d - 2 * cab + 2 * d * (sa - sb)
    if p2 >= 0:
        t1 = np.arctan2(cb - ca, d + sa - sb)
        out["LSL"] = (mod2pi(-alpha + t1), np.sqrt(p2), mod2pi(beta - t1))
    p2 = 2 + d * d - 2 * cab + 2 * d * (sb - sa)
    if p2 >= 0:
        t1 = np.arctan2(ca - cb, d - sa + sb)
        out["RSR"] = (mod2pi(alpha - t1), np.sqrt(p2), mod2pi(-beta + t1))
    p2 = -2 + d * d + 2 * cab + 2 * d * (sa + sb)
    if p2 >= 0:
        p = np.sqrt(p2)
        t2 = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, p)
        out["LSR"] = (mod2pi(-alpha + t2), p, mod2pi(-mod2pi(beta) + t2))
    p2 = -2 + d * d + 2 * cab - 2 * d * (sa + sb)
    if p2 >= 0:
        p = np.sqrt(p2)
        t2 = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, p)
        out["RSL"] = (mod2pi(alpha - t2), p, mod2pi(beta - t2))
    tmp = (6 - d * d + 2 * cab + 2 * d * (sa - sb)) / 8
    if abs(tmp) <= 1:
        p = mod2pi(TAU - np.arccos(tmp))
        t = mod2pi(alpha - np.arctan2(ca - cb, d - sa + sb) + p / 2)
        out["RLR"] = (t, p, mod2pi(alpha - beta - t + p))
    tmp = (6 - d * d + 2 * cab + 2 * d * (sb - sa)) / 8
    if abs(tmp) <= 1:
        p = mod2pi(TAU - np.arccos(tmp))
        t = mod2pi(-alpha - np.arctan2(ca - cb, d + sa - sb) + p / 2)
        out["LRL"] = (t, p, mod2pi(mod2pi(beta) - alpha - t + p))
    return out


def _dubins_walk(q, word, params, rho):
    """End state of walking a Dubins word from state q."""
    x, y, h = q
    for c, s in zip(word, params):
        if c == "S":
            x, y = x + s * rho * np.cos(h), y + s * rho * np.sin(h)
        else:
            k = 1 if c == "L" else -1
            h1 = h + k * s
            x, y = x + k * rho * (np.sin(h1) - np.sin(h)), y - k * rho * (np.cos(h1) - np.cos(h))
            h = h1
    return np.array([x, y, h])


def dubins(start, goal, rho):
    """Length of the shortest path from ``start`` to ``goal`` (x, y, heading) whose
    curvature stays within 1 / ``rho`` (Dubins 1957: the best of the six words LSL, RSR,
    LSR, RSL, RLR, LRL; formulas as in Shkel & Lumelsky 2001, each word's end checked by
    walking it). A lower bound of any walk that cannot turn sharper, obstacles or not."""
    s, g = np.asarray(start, float), np.asarray(goal, float)
    dx, dy = g[0] - s[0], g[1] - s[1]
    d = np.hypot(dx, dy) / rho
    phi = np.arctan2(dy, dx) if d > 0 else 0.0
    alpha, beta = mod2pi(s[2] - phi), mod2pi(g[2] - phi)
    best = None
    for w, prm in _dubins_words(alpha, beta, d).items():
        e = _dubins_walk(s, w, prm, rho)
        err = max(np.hypot(*(e[:2] - g[:2])), abs((e[2] - g[2] + np.pi) % TAU - np.pi))
        if err > 1e-6:
            continue
        L = sum(prm) * rho
        if best is None or L < best[0]:
            best = (L, w)
    return best[0] if best else None


# -- scenes -------------------------------------------------------------------------------


@dataclass
class Scene:
    name: str
    group: str  # "scenes" or "random"
    obstacles: list
    start: np.ndarray  # (x, y)
    goal: np.ndarray
    headings: tuple = None  # fixed (start, goal) headings: planned once, variant "given"
    straight: bool = False  # a straight walk in the open: lateral deviation measured
    probe: object = None  # callable(ground) -> dict of scene-specific figures
    notes: dict = field(default_factory=dict)


OFF = np.array([0.37, 0.81])  # scenes are shifted off the world origin (off any node grid)


def gap_probe(x, centre, width):
    def probe(ground):
        xy = ground[:, :2] - OFF
        k = np.flatnonzero(np.diff(np.sign(xy[:, 0] - x)) != 0)
        if k.size == 0:
            return {"crosses_wall_at_y": None, "through_gap": False}
        y = float(xy[k[0], 1])
        return {"crosses_wall_at_y": y, "through_gap": bool(abs(y - centre) < width / 2)}

    return probe


def build_scenes(radius, seed):
    S = []

    def at(*p):
        return OFF + np.asarray(p, float)

    for deg in (0, 17, 45, 90):
        S.append(
            Scene(
                f"straight_{deg}",
                "scenes",
                [],
                at(0, 0),
                at(*(16 * unit(np.radians(deg)))),
                straight=True,
            )
        )
    for width in (1.0, 0.8):
        c, x = 1.0, 6.0
        obs = [
            wall("wall_lo", at(x, -10), at(x, c - width / 2)),
            wall("wall_hi", at(x, c + width / 2), at(x, 10)),
        ]
        S.append(
            Scene(
                f"gap_{width:.1f}", "scenes", obs, at(0, 0), at(12, 0), probe=gap_probe(x, c, width)
            )
        )
    rng = np.random.default_rng(seed + 1000)
    obs = []
    while len(obs) < 40:
        x, y = rng.uniform((3, -6), (15, 6))
        obs.append(core.pillar(f"p{len(obs)}", *(OFF + (x, y)), rng.uniform(0.2, 0.4)))
    S.append(Scene("pillars_40", "scenes", obs, at(0, 0), at(18, 0)))
    S.append(
        Scene("uturn", "scenes", [wall("wall", at(0, 0), at(6, 0))], at(3.5, 1.0), at(3.5, -1.0))
    )
    # Chicane: three parallel walls 30 degrees off the y axis, alternately from below and
    # from above, 1 m past the line start-goal.
    u = unit(np.radians(120))
    obs = []
    for k, x in enumerate((4.0, 8.0, 12.0)):
        if k % 2 == 0:  # from below, upper end at y = +1
            p = np.array([x, 1.0])
            obs.append(wall(f"chicane{k}", OFF + p - 7 * u, OFF + p))
        else:  # from above, lower end at y = -1
            p = np.array([x, -1.0])
            obs.append(wall(f"chicane{k}", OFF + p, OFF + p + 7 * u))
    S.append(Scene("chicane_30deg", "scenes", obs, at(0, 0), at(16, 0)))
    # Corridor 30 degrees off the grid: two parallel walls 12 m long, 1.6 m apart.
    d, n = unit(np.radians(30)), unit(np.radians(120))
    obs = [
        wall("side_a", at(*(-0.8 * n)), at(*(12 * d - 0.8 * n))),
        wall("side_b", at(*(0.8 * n)), at(*(12 * d + 0.8 * n))),
    ]
    S.append(
        Scene("corridor_30deg", "scenes", obs, at(*(0.5 * d)), at(*(11.5 * d)), straight=False)
    )
    for h0, h1 in ((90, 0), (180, 0), (-135, 0), (0, 180)):
        S.append(
            Scene(
                f"heading_{h0}_to_{h1}",
                "scenes",
                [],
                at(0, 0),
                at(8, 0),
                headings=(np.radians(h0), np.radians(h1)),
            )
        )
    return S


def random_scenes(patch, args):
    """The random pillar fields of bench_core (same calls, same seed: same layouts)."""
    out = []
    for layout, (env, s, g) in enumerate(core.layouts(patch, args)):
        out.append(
            Scene(
                f"random_{layout:02d}",
                "random",
                list(env.obstacles.values()),
                s[:2],
                g[:2],
                notes={"bench_core_headings": [s[2], g[2]]},
            )
        )
    return out


def selected(scene, only):
    if not only:
        return True
    for w in only.split(","):
        w = w.strip()
        if w and (scene.name.startswith(w) or scene.group == w):
            return True
    return False


# -- measuring ----------------------------------------------------------------------------


def path_length(xy):
    return float(np.linalg.norm(np.diff(xy, axis=0), axis=1).sum())


def turning(h):
    return float(np.abs(np.diff(np.unwrap(h))).sum())


CATEGORY = {
    "start": "start",
    "goal": "goal",
    "segment": "lattice",
    "part": "lattice",
    "shortcut": "shortcut",
    "traversal": "clips",
    "interaction": "clips",
}


def decompose(pieces, motions):
    """Where the length goes. Consecutive pieces of one category (start connector, goal
    connector, lattice segments, shortcut curves, clips) form runs; per category: metres
    walked, the sum of its runs' chords (straight distance from a run's first frame to its
    last) and its turning. A category's excess (metres - chords) is what it adds over
    walking straight between its runs' ends: loops of a connector, zig-zag of the lattice;
    the chords' sum against the reference is the route's own excess."""
    out = {}
    for c in ("start", "goal", "lattice", "shortcut", "clips", "other"):
        out.update({f"{c}_m": 0.0, f"{c}_chord_m": 0.0, f"{c}_turn_deg": 0.0, f"{c}_pieces": 0})
    out["start_cycles"] = 0
    runs = []
    for p, m in zip(pieces, motions):
        c = CATEGORY.get(p.kind, "other")
        g = m.ground
        out[f"{c}_m"] += path_length(g[:, :2])
        out[f"{c}_turn_deg"] += float(np.degrees(turning(g[:, 2])))
        out[f"{c}_pieces"] += 1
        if p.kind == "start":
            out["start_cycles"] += int(getattr(p, "cycles", 0) or 0)
        if runs and runs[-1][0] == c:
            runs[-1][2] = g[-1, :2]
        else:
            runs.append([c, g[0, :2], g[-1, :2]])
    for c, a, b in runs:
        out[f"{c}_chord_m"] += float(np.linalg.norm(b - a))
    out["segments"] = out["lattice_pieces"]
    return out


def min_clearance(obstacles, xy):
    """Smallest distance from the ground path to any footprint (m), None without any."""
    if not obstacles:
        return None
    return float(min(distance_to_polygon(xy, o.polygon).min() for o in obstacles))


def measure(scene, env, patch, lim, start, goal, args, ref):
    alpha, beta, gamma = args.weights
    fps = patch.gait.fps
    k = list(patch.gait.kappa_limits) + list(patch.stats.get("curvature_limits", ()))
    rho = 1.0 / max(abs(v) for v in k)
    dub = dubins(start, goal, rho)
    rec = {
        "scene": scene.name,
        "group": scene.group,
        "radius": args.radius,
        "start": start.tolist(),
        "goal": goal.tolist(),
        "reference_m": ref.get("length"),
        "straight_line_m": float(np.linalg.norm(goal[:2] - start[:2])),
        "dubins_m": dub,
        "min_turn_radius_m": rho,
        "bound_m": (max(ref["length"], dub) if ref.get("length") else None),
    }
    if ref.get("length") is None:
        rec["reference_note"] = ref.get("reason")
    t0 = time.perf_counter()
    try:
        plan = planner_mod.SegmentPlanner(patch, env, alpha, beta, gamma).plan(start, goal)
    except planner_mod.PlanError as e:
        rec.update(seconds=time.perf_counter() - t0, failed=True, message=str(e))
        return rec
    rec["seconds"] = time.perf_counter() - t0
    motions = planner_mod.plan_motions(patch, plan)
    m = concatenate(motions)
    g = m.ground
    xy = g[:, :2]
    glitches = validate.motion_glitches(motions, plan.pieces, lim)
    hips = to_world(patch.gait.skeleton, g, m.root_local, m.rotations)[0][:, :2]
    # The feet as the API writes them (fast feet dropped from the labels, feet locked):
    # the planner-labelled skate beside the label-free measure.
    skel = patch.gait.skeleton
    labelled = Motion(g, m.root_local, m.rotations, foot_lock.still_contacts(skel, m, fps))
    locked = Motion(
        g, m.root_local, foot_lock.lock_feet(skel, labelled, fps=fps), labelled.contacts
    )
    rec.update(
        failed=False,
        expansions=plan.expansions,
        pieces=[p.label for p in plan.pieces],
        frames=int(m.frames),
        motion_seconds=(m.frames - 1) / fps,
        path_m=path_length(xy),
        path_turn_deg=float(np.degrees(turning(g[:, 2]))),
        start_speed=float(np.linalg.norm(xy[1] - xy[0]) * fps),
        end_speed=float(np.linalg.norm(xy[-1] - xy[-2]) * fps),
        # over the first / last 0.1 s: the goal connector stops mid-cycle, so its last
        # step alone may be short while the character is still walking at full speed
        start_speed_01s=float(np.linalg.norm(xy[3] - xy[0]) * fps / 3) if len(xy) > 3 else None,
        end_speed_01s=float(np.linalg.norm(xy[-1] - xy[-4]) * fps / 3) if len(xy) > 3 else None,
        heading_error_deg=float(np.degrees(abs(wrap(g[-1, 2] - goal[2])))),
        start_heading_error_deg=float(np.degrees(abs(wrap(g[0, 2] - start[2])))),
        position_error_m=float(np.linalg.norm(xy[-1] - goal[:2])),
        hips_position_error_m=float(np.linalg.norm(hips[-1] - goal[:2])),
        hips_path_m=path_length(hips),
        turns_in_place=sum(p.kind == "turn" for p in plan.pieces),
        frames_inside=int(env.blocked(xy).sum()),
        min_clearance_m=min_clearance(scene.obstacles, xy),
        glitches=glitches,
        glitch_count=validate.count(glitches),
        skate=metrics.foot_skate(core.foot_positions(locked, skel), fps, labelled.contacts),
        feet=core.feet(locked, skel, fps),
    )
    rec.update(decompose(plan.pieces, motions))
    if ref.get("length"):
        L = ref["length"]
        rec["detour"] = rec["path_m"] / L
        rec["hips_detour"] = rec["hips_path_m"] / L
        rec["detour_vs_bound"] = rec["path_m"] / rec["bound_m"]
        cats = ("start", "goal", "lattice", "shortcut", "clips", "other")
        chords = sum(rec[f"{c}_chord_m"] for c in cats)
        rec["excess_m"] = {
            "total": rec["path_m"] - L,
            "start_connector": rec["start_m"] - rec["start_chord_m"],
            "goal_connector": rec["goal_m"] - rec["goal_chord_m"],
            "lattice": rec["lattice_m"] - rec["lattice_chord_m"],
            "shortcut": rec["shortcut_m"] - rec["shortcut_chord_m"],
            "route": chords - L,
        }
        legs = np.diff(ref["points"], axis=0)
        rec["reference_turn_deg"] = (
            float(np.degrees(np.abs(wrap(np.diff(np.arctan2(legs[:, 1], legs[:, 0])))).sum()))
            if len(legs) > 1
            else 0.0
        )
    if scene.straight:
        d = (goal[:2] - start[:2]) / np.linalg.norm(goal[:2] - start[:2])
        rel = xy - start[:2]
        lateral = rel[:, 0] * d[1] - rel[:, 1] * d[0]
        rec["straight_deviation_m"] = float(np.abs(lateral).max())
    if scene.probe is not None:
        rec.update(scene.probe(g))
    return rec


def line(rec, variant):
    head = f"  {rec['scene']:<22s} {variant:<8s}"
    if rec["failed"]:
        ref = f"ref {rec['reference_m']:.1f} m" if rec["reference_m"] else "no reference"
        return f"{head} FAILED after {rec['seconds'] * 1000:6.0f} ms ({ref}): {rec['message']}"
    ref = (
        f"ref {rec['reference_m']:5.1f} m detour {rec['detour']:4.2f}"
        if rec.get("detour")
        else "no reference       "
    )
    ex = rec.get("excess_m")
    extra = (
        f" [{ex['total']:+.1f} m: start {ex['start_connector']:+.1f} goal "
        f"{ex['goal_connector']:+.1f} lattice {ex['lattice']:+.1f} shortcut "
        f"{ex['shortcut']:+.1f} route {ex['route']:+.1f}]"
        if ex
        else ""
    )
    dev = (
        f" dev {rec['straight_deviation_m'] * 100:.1f} cm" if "straight_deviation_m" in rec else ""
    )
    if rec.get("detour_vs_bound"):
        ref += f" (bound {rec['bound_m']:.1f} m: {rec['detour_vs_bound']:.2f})"
    if rec["min_clearance_m"] is not None:
        dev += f" clear {rec['min_clearance_m']:.2f} m"
    gl = sum(rec["glitch_count"].values())
    return (
        f"{head} {rec['seconds'] * 1000:6.0f} ms {rec['path_m']:5.1f} m {ref}{dev} "
        f"glitch {gl} v0 {rec['start_speed']:.2f} v1 {rec['end_speed']:.2f} "
        f"({rec['end_speed_01s']:.2f} over 0.1 s) m/s "
        f"head {rec['heading_error_deg']:.1f}° pos {rec['position_error_m'] * 100:.1f} cm "
        f"in {rec['frames_inside']}{extra}"
    )


def run(patch, scenes, args):
    lim = validate.limits(patch)
    records = []
    for scene in scenes:
        env = Environment(patch.side, patch.cells, args.radius)
        for o in scene.obstacles:
            env.place(o)
        t0 = time.perf_counter()
        ref = reference_path(scene.obstacles, args.radius, scene.start, scene.goal)
        ref_s = time.perf_counter() - t0
        if scene.headings is not None:
            variants = [("given", scene.headings)]
        else:
            variants = []
            for v in args.variants:
                if v == "facing-Y":
                    variants.append((v, (FACING_Y, FACING_Y)))
                elif ref.get("length") is not None:
                    legs = np.diff(ref["points"], axis=0)
                    variants.append(
                        (v, (float(np.arctan2(*legs[0][::-1])), float(np.arctan2(*legs[-1][::-1]))))
                    )
                else:  # no reference: face the goal
                    d = scene.goal - scene.start
                    a = float(np.arctan2(d[1], d[0]))
                    variants.append((v, (a, a)))
        for v, (h0, h1) in variants:
            start, goal = np.r_[scene.start, h0], np.r_[scene.goal, h1]
            rec = measure(scene, env, patch, lim, start, goal, args, ref)
            rec["variant"] = v
            rec["reference_seconds"] = ref_s
            rec["reference_footprints"] = ref.get("footprints_used")
            rec.update({k: v2 for k, v2 in scene.notes.items()})
            records.append(rec)
            print(line(rec, v), flush=True)
    return records, lim


# -- report -------------------------------------------------------------------------------


def summarise(recs):
    found = [r for r in recs if not r["failed"]]
    det = [r["detour"] for r in found if r.get("detour")]
    dvb = [r["detour_vs_bound"] for r in found if r.get("detour_vs_bound")]
    hips = [r["hips_detour"] for r in found if r.get("hips_detour")]
    dev = [
        r["straight_deviation_m"]
        for r in found
        if "straight_deviation_m" in r and r["scene"].startswith("straight")
    ]

    def mx(key):
        v = [r[key] for r in found if r.get(key) is not None]
        return float(max(v)) if v else None

    ex = [r["excess_m"] for r in found if r.get("excess_m")]
    clear = [r["min_clearance_m"] for r in found if r.get("min_clearance_m") is not None]
    return {
        "plans": len(recs),
        "found": len(found),
        "failed": len(recs) - len(found),
        "failures_with_clear_path": sum(r["failed"] and r["reference_m"] is not None for r in recs),
        "detour_median": float(np.median(det)) if det else None,
        "detour_mean": float(np.mean(det)) if det else None,
        "detour_worst": float(max(det)) if det else None,
        "detour_vs_bound_median": float(np.median(dvb)) if dvb else None,
        "detour_vs_bound_worst": float(max(dvb)) if dvb else None,
        "hips_detour_median": float(np.median(hips)) if hips else None,
        "hips_detour_worst": float(max(hips)) if hips else None,
        "plans_turning_in_place": int(sum(r["turns_in_place"] > 0 for r in found)),
        "straight_deviation_m": float(max(dev)) if dev else None,
        "glitches": int(sum(sum(r["glitch_count"].values()) for r in found)),
        "plans_with_glitches": int(sum(bool(r["glitch_count"]) for r in found)),
        "glitch_kinds": {
            k: int(sum(r["glitch_count"].get(k, 0) for r in found))
            for k in ("spin", "backwards", "jump")
        },
        "start_speed_max": mx("start_speed"),
        "end_speed_max": mx("end_speed"),
        "start_speed_01s_max": mx("start_speed_01s"),
        "end_speed_01s_max": mx("end_speed_01s"),
        "heading_error_deg_max": mx("heading_error_deg"),
        "position_error_m_max": mx("position_error_m"),
        "hips_position_error_m_max": mx("hips_position_error_m"),
        "frames_inside": int(sum(r["frames_inside"] for r in found)),
        "plan_seconds_median": float(np.median([r["seconds"] for r in found])) if found else None,
        "plan_seconds_max": mx("seconds"),
        "excess_mean_m": ({k: float(np.mean([e[k] for e in ex])) for k in ex[0]} if ex else None),
        "clearance_median_m": (float(np.median(clear)) if clear else None),
        "path_turn_deg_mean": float(np.mean([r["path_turn_deg"] for r in found]))
        if found
        else None,
        "reference_turn_deg_mean": (
            float(np.mean([r["reference_turn_deg"] for r in found if "reference_turn_deg" in r]))
            if any("reference_turn_deg" in r for r in found)
            else None
        ),
        "start_turn_deg_mean": float(np.mean([r["start_turn_deg"] for r in found]))
        if found
        else None,
        "goal_turn_deg_mean": float(np.mean([r["goal_turn_deg"] for r in found]))
        if found
        else None,
        "skate": core.pooled_skate(found) if found else None,
        "feet": core.pooled_feet([r["feet"] for r in found]) if found else None,
    }


def met(key, value):
    if value is None:
        return "–"
    op, target, _ = TARGETS[key]
    ok = value <= target if op == "<=" else value < target
    return "met" if ok else "**not met**"


def fmt(key, v):
    if v is None:
        return "–"
    if key in ("glitches", "failures_with_clear_path", "frames_inside"):
        return str(v)
    if key in ("straight_deviation_m", "position_error_m_max", "hips_position_error_m_max"):
        return f"{v * 100:.1f} cm"
    if key.endswith("_deg_max"):
        return f"{v:.1f}°"
    if "speed" in key:
        return f"{v:.2f} m/s"
    return f"{v:.2f}"


def markdown(records, summary, source=None):
    out = [
        "| scene | headings | reference | bound | path | detour (vs bound) | straight dev. | "
        "clearance | glitches | v start / end | heading err. | pos. err. | inside | plan | "
        "extra length from |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in records:
        if r["group"] != "scenes":
            continue
        ref = f"{r['reference_m']:.2f} m" if r["reference_m"] else "none"
        if r["failed"]:
            out.append(
                f"| {r['scene']} | {r['variant']} | {ref} | | **failed**: {r['message']} "
                "| | | | | | | | | | |"
            )
            continue
        ex = r.get("excess_m")
        extra = (
            f"start {ex['start_connector']:+.1f}, goal {ex['goal_connector']:+.1f}, "
            f"lattice {ex['lattice']:+.1f}, shortcut {ex['shortcut']:+.1f}, "
            f"route {ex['route']:+.1f} m"
            if ex
            else ""
        )
        if "through_gap" in r:
            extra += "; through the gap" if r["through_gap"] else "; **not through the gap**"
        dev = f"{r['straight_deviation_m'] * 100:.1f} cm" if "straight_deviation_m" in r else ""
        gl = sum(r["glitch_count"].values())
        clear = f"{r['min_clearance_m']:.2f} m" if r["min_clearance_m"] is not None else ""
        bound = f"{r['bound_m']:.2f} m" if r.get("bound_m") else ""
        out.append(
            f"| {r['scene']} | {r['variant']} | {ref} | {bound} | {r['path_m']:.2f} m | "
            f"{r['detour']:.2f} ({r['detour_vs_bound']:.2f}) | {dev} | {clear} | {gl or 0} | "
            f"{r['start_speed']:.2f} / {r['end_speed']:.2f} | {r['heading_error_deg']:.1f}° | "
            f"{r['position_error_m'] * 100:.1f} cm | {r['frames_inside']} | "
            f"{r['seconds'] * 1000:.0f} ms | {extra} |"
        )
    groups = list(summary)
    out += [
        "",
        "| figure | target | " + " | ".join(groups) + " |",
        "|---|---|" + "---|" * len(groups),
    ]
    for key, (_, _, shown) in TARGETS.items():
        cells = []
        for gname in groups:
            v = summary[gname][key]
            cells.append(f"{fmt(key, v)} ({met(key, v)})" if v is not None else "–")
        out.append(f"| {key.replace('_', ' ')} | {shown} | " + " | ".join(cells) + " |")
    for key, label in (
        ("plans", "plans (found)"),
        ("detour_mean", "detour mean"),
        ("detour_vs_bound_median", "detour vs heading-aware bound, median"),
        ("detour_vs_bound_worst", "detour vs heading-aware bound, worst"),
        ("hips_detour_median", "detour of the hips (sway and steps included), median"),
        ("hips_detour_worst", "detour of the hips (sway and steps included), worst"),
        ("plans_turning_in_place", "plans turning on the spot (derived turn)"),
        ("plans_with_glitches", "plans with glitches"),
        ("plan_seconds_median", "plan time median"),
    ):
        cells = []
        for gname in groups:
            s = summary[gname]
            if key == "plans":
                cells.append(f"{s['plans']} ({s['found']})")
            elif key == "plan_seconds_median":
                cells.append(f"{s[key] * 1000:.0f} ms" if s[key] is not None else "–")
            elif "detour" in key:
                cells.append(f"{s[key]:.2f}" if s[key] is not None else "–")
            else:
                cells.append(str(s[key]))
        out.append(f"| {label} | | " + " | ".join(cells) + " |")
    cells = []
    for gname in groups:
        sm = summary[gname]
        c = sm["clearance_median_m"]
        cells.append(f"{c:.2f} m" if c is not None else "–")
    out.append(
        "| closest approach to a footprint, median (the radius is "
        f"{records[0]['radius']:g} m) | | " + " | ".join(cells) + " |"
    )
    cells = []
    for gname in groups:
        sm = summary[gname]
        cells.append(
            "–"
            if sm["path_turn_deg_mean"] is None
            else f"{sm['path_turn_deg_mean']:.0f}° "
            f"(reference {sm['reference_turn_deg_mean']:.0f}°; "
            f"start connector {sm['start_turn_deg_mean']:.0f}°, goal connector "
            f"{sm['goal_turn_deg_mean']:.0f}°)"
            if sm["reference_turn_deg_mean"] is not None
            else f"{sm['path_turn_deg_mean']:.0f}°"
        )
    out.append("| total turning per path, mean | | " + " | ".join(cells) + " |")
    cells = []
    for gname in groups:
        sk = summary[gname]["skate"]
        cells.append(f"{sk['mean_cm_per_s']:.1f} cm/s" if sk else "–")
    src = f" (source clip {source['skate']['mean_cm_per_s']:.1f} cm/s)" if source else ""
    out.append(
        f"| foot skate the planner labels planted, foot locked{src} | | " + " | ".join(cells) + " |"
    )
    cells = []
    for gname in groups:
        f = summary[gname]["feet"]
        cells.append(
            f"skate {f['skate_cm_per_s']:.1f} cm/s, weighted {f['weighted_skate_cm_per_s']:.1f}, "
            f"{f['pops']} pops, clearance {f['min_swing_clearance_cm']:.1f} cm, end ankles "
            f"{f['max_end_ankle_off_cm']:.1f} cm"
            if f
            else "–"
        )
    src = (
        f" (source clip: skate {source['feet']['skate']['mean_cm_per_s']:.1f} cm/s, weighted "
        f"{source['feet']['weighted_skate']['mean_cm_per_s']:.1f}, {source['feet']['pops']} "
        f"pops, clearance {source['feet']['min_swing_clearance_cm']:.1f} cm)"
        if source
        else ""
    )
    out.append(
        "| feet by the label-free measure (toe within 3 cm of its lowest for 0.2 s), foot "
        f"locked{src} | | " + " | ".join(cells) + " |"
    )
    cells = []
    for gname in groups:
        e = summary[gname]["excess_mean_m"]
        cells.append(
            ", ".join(f"{k.replace('_connector', '')} {v:+.2f}" for k, v in e.items()) if e else "–"
        )
    out.append(
        "| extra length, mean m (total = start + goal connector loops + lattice "
        "zig-zag + shortcut curves + route) | | " + " | ".join(cells) + " |"
    )
    return "\n".join(out)


def jsonable(o):
    if isinstance(o, dict):
        return {str(k): jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [jsonable(v) for v in o]
    if isinstance(o, np.ndarray):
        return jsonable(o.tolist())
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, (np.bool_,)):
        return bool(o)
    return o


def main(argv=None):
    args = parse_args(argv)
    mocap = Path(args.mocap)
    missing = core.missing_mocap(mocap)
    if missing:
        print(missing, file=sys.stderr)
        return 2
    t_all = time.perf_counter()
    print("bake ...", flush=True)
    patch, straight, bake = core.bench_bake(mocap)
    fps = patch.gait.fps
    source = {
        "skate": core.bench_source_skate(straight, fps),
        "feet": foot_measure.of_clip(clip_mod.resample(straight, fps)),
    }
    bad = validate.segment_glitches(patch)
    print(
        f"  {bake['bake_seconds']:.1f} s: {bake['kept']} segments kept, {len(bad)} of them "
        f"glitch (validate.segment_glitches)"
    )
    scenes = [s for s in build_scenes(args.radius, args.seed) if selected(s, args.only)]
    if args.layouts:
        rnd = random_scenes(patch, args)
        scenes += [s for s in rnd if selected(s, args.only)]
    print(f"plans: {len(scenes)} scenes x variants {', '.join(args.variants)} ...", flush=True)
    records, lim = run(patch, scenes, args)
    summary = {}
    # Forced start/goal headings ("given": e.g. starting with the goal behind) are a group
    # of their own: their turns are the point of them, not a detour of the planner.
    for group in ("scenes", "random"):
        for v in ("along", "facing-Y", "given"):
            recs = [r for r in records if r["group"] == group and r["variant"] == v]
            if recs:
                summary[f"{group}, {v}"] = summarise(recs)
    res = {
        "machine": core.machine(),
        "args": {
            k: (list(v) if isinstance(v, (list, tuple)) else v) for k, v in vars(args).items()
        },
        "bake": dict(bake, glitching_segments=bad),
        "limits": lim.to_dict(),
        "targets": {k: {"op": o, "value": t} for k, (o, t, _) in TARGETS.items()},
        "summary": summary,
        "source_clip": source,
        "records": records,
    }
    print()
    print(markdown(records, summary, source))
    res["total_seconds"] = time.perf_counter() - t_all
    print(f"\n(total {res['total_seconds']:.0f} s)")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        with open(args.json, "w") as fh:
            json.dump(jsonable(res), fh, indent=1)
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
