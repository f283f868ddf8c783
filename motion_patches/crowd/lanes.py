# SPDX-License-Identifier: GPL-3.0-or-later
"""Lanes: where a counter-flow meets head-on, it splits in two, each side keeping to its right.

Walkers planned on their own through a doorway all take its opening, hugging whichever
corner is on their way. Two that meet head-on there share a stretch that no timing clears
unless one waits for the other to be through, and a re-route round where the other walks
then (:func:`~.crowd.ghosts`) leaves the later one a sliver beside the first. Crowd tools
settle this with a keep-right rule, and so does this module: the places where a pass of the
resolver left pairs meeting head-on (:func:`regions`) are moved onto the narrowest middle of
the flow through them (:func:`centred`), turned square to it (:func:`flow_axis`), and kept
only where the flow is held in, by a doorway or a narrow way (:func:`confined`; in the open,
re-routes and timing part walkers and a strip would only wall off the way round). Every
walker going along such a place is re-planned with a strip on its left as a passing obstacle
(:func:`strip`), the two directions' strips each reaching half a spacing over the middle
line, so the flows pass on their own sides and only the order within a lane is left to the
holds and waits. A place is kept over the passes of the resolver, so a pass that finds it
again gives its walkers the same strips. A lane plan that is a long way round is not taken.
A way too narrow for two has no sides: its re-plans find no path, and its walkers are left
to take turns by holds and waits, or are reported.
"""

from collections.abc import Callable

import numpy as np

HEAD_ON = -0.5  # cosine between two headings under which two walkers meet head-on
DETOUR = 1.5  # a lane plan longer than this many times the plan it replaces is not taken
REACH_M = 0.4  # a heading is taken between the points this far behind and ahead on a track
ALONG_M = 1.0  # a lane strip reaches this far either way of the place's middle
ACROSS_M = 1.0  # and this far into the walker's left
BIN_M = 0.25  # the narrowest place of a flow is looked for in slices this long
SWAY_M = 0.05  # the roots' sway about the planned ground track, kept clear of as well


def heading(track: np.ndarray, k: int, reach: float = REACH_M) -> np.ndarray:
    """Unit direction a ground ``track`` (frames, 2) walks through frame ``k``: from the
    point ``reach`` behind to the one ``reach`` ahead (holds and waits on it skipped);
    zero where it does not move that far."""
    track = np.asarray(track, float)
    k = int(np.clip(k, 0, len(track) - 1))
    far = np.linalg.norm(track - track[k], axis=1) >= reach
    ahead = np.nonzero(far[k:])[0]
    behind = np.nonzero(far[: k + 1])[0]
    a = track[k + ahead[0]] if ahead.size else track[-1]
    b = track[behind[-1]] if behind.size else track[0]
    d = a - b
    n = float(np.linalg.norm(d))
    return d / n if n > 1e-9 else np.zeros(2)


def meeting(
    a: tuple[int, np.ndarray], b: tuple[int, np.ndarray], frame: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """(midpoint, axis) where two walkers ``(delay, track)`` meet head-on on ``frame``:
    the point between them and the direction ``a`` walks (``b`` walks against it); None
    when they do not walk against each other then."""
    (da, ta), (db, tb) = a, b
    ka, kb = frame - da, frame - db
    ha, hb = heading(ta, ka), heading(tb, kb)
    if float(ha @ hb) > HEAD_ON or not ha.any() or not hb.any():
        return None
    axis = ha - hb
    axis /= np.linalg.norm(axis)
    pa = ta[int(np.clip(ka, 0, len(ta) - 1))]
    pb = tb[int(np.clip(kb, 0, len(tb) - 1))]
    return (pa + pb) / 2, axis


def strip(
    mid: np.ndarray,
    axis: np.ndarray,
    side: int,
    spacing: float,
    radius: float,
    sway: float = SWAY_M,
) -> np.ndarray:
    """(4, 2) counter-clockwise rectangle on the left of a walker going ``side * axis``
    past ``mid``: from half a spacing (less the planner's ``radius``, plus the sway) over
    the line through ``mid`` on its right, to :data:`ACROSS_M` on its left, :data:`ALONG_M`
    either way. Two walkers planned round the two strips (``side`` +1 and -1) pass at
    least ``spacing`` apart."""
    u = np.asarray(axis, float) * side
    n = np.array([-u[1], u[0]])  # the walker's left
    over = max(spacing / 2 - radius, 0.0) + sway
    c = np.asarray(mid, float)
    return np.array(
        [
            c - ALONG_M * u - over * n,
            c + ALONG_M * u - over * n,
            c + ALONG_M * u + ACROSS_M * n,
            c - ALONG_M * u + ACROSS_M * n,
        ]
    )


def regions(
    placed: dict[int, tuple[int, np.ndarray]], conflicts: list[dict]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """(midpoint, axis) of each place where a pair left too close meets head-on
    (:func:`meeting`), those closer than :data:`ALONG_M` along about the same axis merged
    into one (their mean)."""
    out: list[list] = []  # [sum of midpoints, sum of axes, count]
    for c in conflicts:
        if c["a"] not in placed or c["b"] not in placed:
            continue
        met = meeting(placed[c["a"]], placed[c["b"]], int(c["frame"]))
        if met is None:
            continue
        mid, axis = met
        for r in out:
            m, u = r[0] / r[2], r[1] / np.linalg.norm(r[1])
            if np.linalg.norm(mid - m) < ALONG_M and abs(float(axis @ u)) > -HEAD_ON:
                r[0], r[1], r[2] = r[0] + mid, r[1] + axis * np.sign(axis @ u), r[2] + 1
                break
        else:
            out.append([mid.copy(), axis.copy(), 1])
    return [(r[0] / r[2], r[1] / np.linalg.norm(r[1])) for r in out]


def side_of(track: np.ndarray, mid: np.ndarray, axis: np.ndarray) -> int:
    """+1 or -1: which way along ``axis`` a ground ``track`` walks through the region about
    ``mid`` (:data:`ALONG_M` along, :data:`ACROSS_M` across), 0 when it does not pass there
    or does not go half its length along it (it crosses it or turns in it)."""
    track = np.asarray(track, float)
    n = np.array([-axis[1], axis[0]])
    rel = track - mid
    inside = (np.abs(rel @ axis) <= ALONG_M) & (np.abs(rel @ n) <= ACROSS_M)
    k = np.nonzero(inside[:-1])[0]
    if not k.size:
        return 0
    along = float((track[k + 1] - track[k]).sum(axis=0) @ axis)
    return int(np.sign(along)) if abs(along) >= ALONG_M else 0


def centred(
    mid: np.ndarray, axis: np.ndarray, tracks: list[np.ndarray], again: int = 2
) -> np.ndarray:
    """``mid`` moved onto the narrowest place of the flow about it: the points of ``tracks``
    within :data:`ALONG_M` along and :data:`ACROSS_M` across, cut into :data:`BIN_M` slices
    along; of the slices that nearly every walk through the region crosses, the one they
    spread least over, and the middle of that spread. Walkers planned alone spread over a
    doorway's width, each hugging the corner on its way, so this is the doorway's middle,
    not where one pair happened to meet. Looked for again about the place found (``again``
    times), the first look being about where the pair met."""
    if again:
        mid = centred(mid, axis, tracks, again - 1)
    n = np.array([-axis[1], axis[0]])
    best, spread = mid, np.inf
    rel = [np.asarray(t, float)[:, :2] - mid for t in tracks]
    rel = [(r @ axis, r @ n) for r in rel]
    walks = [(u, v) for u, v in rel if ((np.abs(u) <= ALONG_M) & (np.abs(v) <= ACROSS_M)).any()]
    for lo in np.arange(-ALONG_M, ALONG_M, BIN_M):
        across = [v[(u >= lo) & (u < lo + BIN_M) & (np.abs(v) <= ACROSS_M)] for u, v in walks]
        across = [v for v in across if v.size]
        if len(across) < 0.9 * len(walks) or not across:
            continue
        across = np.concatenate(across)
        if np.ptp(across) < spread:
            spread = float(np.ptp(across))
            best = mid + axis * (lo + BIN_M / 2) + n * (across.min() + across.max()) / 2
    return best


def spread(mid: np.ndarray, axis: np.ndarray, tracks: list[np.ndarray], across: float) -> float:
    """Metres the points of ``tracks`` in the :data:`BIN_M` slice about ``mid`` (square to
    ``axis``) spread over, of those within ``across`` of ``mid``."""
    n = np.array([-axis[1], axis[0]])
    parts = [np.empty(0)]
    for t in tracks:
        rel = np.asarray(t, float)[:, :2] - mid
        v = rel @ n
        parts.append(v[(np.abs(rel @ axis) <= BIN_M / 2) & (np.abs(v) <= across)])
    got = np.concatenate(parts)
    return float(np.ptp(got)) if got.size else 0.0


def confined(mid: np.ndarray, axis: np.ndarray, tracks: list[np.ndarray]) -> bool:
    """Whether the flow through ``mid`` (its narrowest place, :func:`centred`) is held in
    there: looked at twice as far across (2 :data:`ACROSS_M`), it spreads no wider than
    within :data:`ACROSS_M` (to a slice, :data:`BIN_M`). So it is in a doorway or a narrow
    way, whose sides stop the walks whatever their goals; in the open the flow spreads
    further the further one looks, and walkers meeting there are kept apart by re-routes
    and timing, not lanes, whose strips would only wall off the way round."""
    return spread(mid, axis, tracks, 2 * ACROSS_M) <= spread(mid, axis, tracks, ACROSS_M) + BIN_M


def flow_axis(mid: np.ndarray, axis: np.ndarray, tracks: list[np.ndarray]) -> np.ndarray:
    """The direction the flow takes through the region about ``mid`` (:data:`ALONG_M`
    along ``axis``, :data:`ACROSS_M` across): the mean of the directions the walks through
    it go along it, each turned to ``axis``'s way (the two directions of a counter-flow
    count alike). One pair meeting at a slant gives a slanted axis; the flow through a
    doorway goes through it square."""
    axis = np.asarray(axis, float)
    n = np.array([-axis[1], axis[0]])
    total = np.zeros(2)
    for t in tracks:
        t = np.asarray(t, float)[:, :2]
        rel = t - mid
        inside = (np.abs(rel @ axis) <= ALONG_M) & (np.abs(rel @ n) <= ACROSS_M)
        k = np.nonzero(inside[:-1])[0]
        if not k.size:
            continue
        d = (t[k + 1] - t[k]).sum(axis=0)
        size = float(np.linalg.norm(d))
        if size >= ALONG_M and abs(float(d @ axis)) >= -HEAD_ON * size:
            total += d / size * np.sign(d @ axis)
    size = float(np.linalg.norm(total))
    return total / size if size > 1e-9 else axis


def length(track: np.ndarray) -> float:
    """Metres walked along a ground ``track``."""
    return float(np.linalg.norm(np.diff(np.asarray(track, float)[:, :2], axis=0), axis=1).sum())


def same_place(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> bool:
    """Whether two places (midpoint, axis) are one: closer than :data:`ALONG_M`, their axes
    along one line (either way)."""
    return bool(np.linalg.norm(a[0] - b[0]) < ALONG_M and abs(float(a[1] @ b[1])) > -HEAD_ON)


def form(
    placed: dict[int, tuple[int, np.ndarray]],
    conflicts: list[dict],
    tracks: list[np.ndarray],
    laned: dict,
    replan: Callable[[int, list[np.ndarray]], tuple[np.ndarray, np.ndarray | None] | None],
    versions: list[int],
    spacing: float,
    radius: float,
    places: list[tuple[np.ndarray, np.ndarray]] | None = None,
) -> dict[int, tuple[int, np.ndarray, np.ndarray | None, list[np.ndarray]]]:
    """Lanes where pairs were left too close head-on (:func:`regions`, from the crowd's
    reservations ``placed`` {character: (delay, track)}): every character not yet
    ``laned`` whose plan (``tracks``) walks through such a place along it is re-planned
    round the :func:`strip` on its left there (``replan(i, polygons)``, counted in
    ``versions``), so the two flows pass on their own sides. ``places`` [(midpoint, axis)]
    are the lanes of the passes before (extended in place): a place found again is the one
    already there (:func:`same_place`), so every walker through it keeps to the same
    strips, whichever pair of a pass found it. Returns {character: (version, track,
    holdable, strips)} of the new plans (a character with no path on its side keeps its
    plan)."""
    places = [] if places is None else places
    fresh = 0
    for mid, axis in regions(placed, conflicts):
        for _ in range(2):  # the flow's direction and narrowest middle, each from the other
            axis = flow_axis(mid, axis, tracks)
            mid = centred(mid, axis, tracks)
        found = (mid, axis)
        if confined(mid, axis, tracks) and not any(same_place(found, p) for p in places):
            places.append(found)
            fresh += 1
    out: dict[int, tuple[int, np.ndarray, np.ndarray | None, list[np.ndarray]]] = {}
    if not fresh:
        return out
    for i, track in enumerate(tracks):
        if i in laned:
            continue
        track = np.asarray(track, float)[:, :2]
        mine = [(p, side_of(track, *p)) for p in places]
        mine = [(p, side) for p, side in mine if side]
        if not mine:
            continue
        strips = [strip(mid, axis, side, spacing, radius) for (mid, axis), side in mine]
        got = replan(i, strips)
        if got is None:  # a lane too narrow for the planner's way through: without the sway
            strips = [strip(m, u, side, spacing, radius, 0.0) for (m, u), side in mine]
            got = replan(i, strips)
        if got is None:
            continue
        versions[i] += 1
        lane = np.asarray(got[0], float)[:, :2]
        if length(lane) <= DETOUR * length(track):  # a lane, not a way round
            out[i] = (versions[i], lane, got[1], strips)
    return out
