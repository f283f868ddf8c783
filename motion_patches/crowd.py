"""Crowds of independently planned characters kept apart in time.

Each character's path is planned on its own against the props (the paper plans one
character), with the spots where the others will stand still while it walks as extra
obstacles: the goals of the characters planned before it (they end there) and the starts
of those after it (they wait there). Characters are then kept apart in time the way a
previs animator would first try: later characters wait at their start (holding their
first pose) until their whole walk, and their standing at the goal afterwards, stays clear
of everyone planned before them. What no wait within the limit clears is reported as a
conflict, not hidden; moving characters are not avoided in space.
"""

import numpy as np


def disc(centre, radius, sides=12):
    """(sides, 2) convex polygon around a point, counter-clockwise."""
    a = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    return np.column_stack((centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)))


def standing_spots(ends, n, spacing, radius):
    """[(index, polygon)] of the spots character ``n`` walks around: the goals of the
    characters before it and the starts of those after it, as discs that keep ``spacing``
    between roots once grown by the planner's ``radius``. ``ends`` [(start, goal)] are
    (x, y, heading) states; a spot within that distance of ``n``'s own start or goal is
    left out (it could not start or arrive at all)."""
    if spacing <= 0:
        return []
    grow = max(spacing - radius, 0.05)
    mine = np.array([ends[n][0][:2], ends[n][1][:2]], float)
    out = []
    for m, (start, goal) in enumerate(ends):
        if m == n:
            continue
        where = np.asarray(goal if m < n else start, float)[:2]
        if np.linalg.norm(mine - where, axis=1).min() < grow + radius:
            continue
        out.append((m, disc(where, grow)))
    return out


def timeline(track, delay, horizon):
    """(horizon, 2) positions of a ground ``track`` started ``delay`` frames late: it
    stands at its first point before and at its last point after."""
    t = np.clip(np.arange(horizon) - delay, 0, len(track) - 1)
    return track[t]


def timelines(tracks, delays):
    """Every track's timeline over the crowd's whole length (as :func:`timeline`)."""
    tracks = [np.asarray(t, float)[:, :2] for t in tracks]
    horizon = max(len(t) + d for t, d in zip(tracks, delays))
    return [timeline(t, d, horizon) for t, d in zip(tracks, delays)]


def closest_approach(a, b):
    """(frame, distance) where two equally long timelines come closest."""
    d = np.linalg.norm(a - b, axis=1)
    k = int(np.argmin(d))
    return k, float(d[k])


def stagger(tracks, clearance, max_delay, step):
    """Delays (frames) for ``tracks`` [(frames, 2) xy arrays, first frames aligned], in
    order, and the conflicts left: [{"a", "b", "frame", "distance_m"}], pairs (by index)
    closer than ``clearance`` at the same frame, with the frame they come closest.

    Each track takes the smallest delay (0, step, 2 step, ... <= max_delay) at which it
    stays ``clearance`` away from every earlier track at every frame; if none does, the
    delay with the fewest frames too close (then the smallest)."""
    tracks = [np.asarray(t, float)[:, :2] for t in tracks]
    if not tracks:
        return [], []
    delays = []
    for i, track in enumerate(tracks):
        best = None
        for d in range(0, int(max_delay) + 1, max(int(step), 1)):
            horizon = max([len(track) + d] + [len(t) + dj for t, dj in zip(tracks, delays)])
            mine = timeline(track, d, horizon)
            close = 0
            for t, dj in zip(tracks, delays):
                close += int((np.linalg.norm(mine - timeline(t, dj, horizon), axis=1)
                              < clearance).sum())
            if best is None or close < best[0]:
                best = (close, d)
            if close == 0:
                break
        delays.append(best[1])
    lines = timelines(tracks, delays)
    conflicts = []
    for i in range(len(lines)):
        for j in range(i):
            k, dist = closest_approach(lines[j], lines[i])
            if dist < clearance:
                conflicts.append({"a": j, "b": i, "frame": k, "distance_m": dist})
    return delays, conflicts


def ghosts(conflict, lines, spacing, radius, fps, window_seconds=1.5, step_m=0.3):
    """Discs [(polygon)] where character ``conflict["a"]`` walks around the frame it comes
    too close to character ``conflict["b"]``: its positions over ``window_seconds`` either
    side of that frame (``lines``: the crowd's timelines as :func:`stagger` leaves them),
    every ``step_m`` metres, as obstacles that keep ``spacing`` between the two roots once
    the planner grows them by ``radius``. Re-planning ``b`` around them routes it round
    where ``a`` is at that time (a space-time reservation of those frames, made static);
    what is left is staggered again."""
    a, k = conflict["a"], conflict["frame"]
    w = int(round(window_seconds * fps))
    pts = lines[a][max(k - w, 0):k + w + 1]
    keep = [pts[0]]
    for p in pts[1:]:
        if np.linalg.norm(p - keep[-1]) >= step_m:
            keep.append(p)
    grow = max(spacing - radius, 0.05)
    return [disc(p, grow) for p in keep]


def keep_apart(tracks, replan, spacing, radius, fps, max_delay, step, rounds=3):
    """Delays, conflicts left and the indices re-routed, for tracks [(frames, 2)] in
    priority order: :func:`stagger` first; then, for each conflict, the later character
    is re-planned (``replan(index, discs) -> new track or None``) around :func:`ghosts` of
    the earlier one near the conflict frame (its reserved stretch, added to what it
    already avoids), and the crowd is staggered again, for at most ``rounds`` rounds.
    ``tracks`` is updated in place with the re-planned tracks."""
    delays, conflicts = stagger(tracks, spacing, max_delay, step)
    reserved = {}
    rerouted = set()
    for _ in range(rounds):
        if not conflicts:
            break
        lines = timelines(tracks, delays)
        changed = False
        for c in conflicts:
            b = c["b"]
            reserved.setdefault(b, []).extend(ghosts(c, lines, spacing, radius, fps))
            new = replan(b, list(reserved[b]))
            if new is not None:
                tracks[b] = np.asarray(new, float)[:, :2]
                rerouted.add(b)
                changed = True
        if not changed:
            break
        delays, conflicts = stagger(tracks, spacing, max_delay, step)
    return delays, conflicts, sorted(rerouted)
