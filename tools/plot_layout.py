# SPDX-License-Identifier: GPL-3.0-or-later
"""Top-down picture of a planned layout as a PNG, with numpy, zlib and struct only.

    .venv/blender-4.5/bin/python tools/plot_layout.py [--output docs/plan.png]

As a script it rebuilds the layout of ``tools/demo.py`` (the same jittered pillar grid,
start and goal) with the pure core, bakes the walk patch from CMU 16_15 / 16_18, plans and
writes ``docs/plan.png``. As a module, :func:`plot_layout` draws any environment and plan.
"""

import argparse
import os
import struct
import sys
import zlib
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

# -- colours (RGB 0..1) -----------------------------------------------------------------------


def _rgb(hex_code):
    h = hex_code.lstrip("#")
    return np.array([int(h[i : i + 2], 16) / 255.0 for i in (0, 2, 4)])


BACKGROUND = _rgb("#ffffff")
CELL_GRID = _rgb("#eef0f3")
TILE_GRID = _rgb("#b4bac4")
OCCLUDED = _rgb("#f7cfc4")
OBSTACLE = _rgb("#3b4250")
START = _rgb("#1e9e4a")
SEGMENT_A = _rgb("#1f6fd1")
SEGMENT_B = _rgb("#f0a020")
GOAL = _rgb("#d0263a")
DIRECT = _rgb("#7a3fb5")
STITCH_FILL = _rgb("#ffffff")
STITCH_EDGE = _rgb("#1b1f27")
TEXT = _rgb("#1b1f27")
PANEL = _rgb("#f6f7f9")


# -- PNG --------------------------------------------------------------------------------------


def write_png(path, rgb):
    """Write an (H, W, 3) array (floats 0..1 or uint8) as an 8-bit RGB PNG."""
    a = np.asarray(rgb)
    if a.dtype != np.uint8:
        a = np.clip(np.round(a * 255.0), 0, 255).astype(np.uint8)
    h, w, _ = a.shape
    raw = np.concatenate((np.zeros((h, 1), np.uint8), a.reshape(h, w * 3)), axis=1).tobytes()

    def chunk(tag, data):
        return (
            struct.pack(">I", len(data))
            + tag
            + data
            + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
        )

    png = (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as fh:
        fh.write(png)


# -- a 5x7 bitmap font (upper case, digits, a little punctuation) -----------------------------

_FONT_ROWS = {
    "A": "01110 10001 10001 11111 10001 10001 10001",
    "B": "11110 10001 10001 11110 10001 10001 11110",
    "C": "01110 10001 10000 10000 10000 10001 01110",
    "D": "11110 10001 10001 10001 10001 10001 11110",
    "E": "11111 10000 10000 11110 10000 10000 11111",
    "F": "11111 10000 10000 11110 10000 10000 10000",
    "G": "01110 10001 10000 10111 10001 10001 01111",
    "H": "10001 10001 10001 11111 10001 10001 10001",
    "I": "01110 00100 00100 00100 00100 00100 01110",
    "J": "00111 00010 00010 00010 00010 10010 01100",
    "K": "10001 10010 10100 11000 10100 10010 10001",
    "L": "10000 10000 10000 10000 10000 10000 11111",
    "M": "10001 11011 10101 10101 10001 10001 10001",
    "N": "10001 10001 11001 10101 10011 10001 10001",
    "O": "01110 10001 10001 10001 10001 10001 01110",
    "P": "11110 10001 10001 11110 10000 10000 10000",
    "Q": "01110 10001 10001 10001 10101 10010 01101",
    "R": "11110 10001 10001 11110 10100 10010 10001",
    "S": "01111 10000 10000 01110 00001 00001 11110",
    "T": "11111 00100 00100 00100 00100 00100 00100",
    "U": "10001 10001 10001 10001 10001 10001 01110",
    "V": "10001 10001 10001 10001 10001 01010 00100",
    "W": "10001 10001 10001 10101 10101 10101 01010",
    "X": "10001 10001 01010 00100 01010 10001 10001",
    "Y": "10001 10001 01010 00100 00100 00100 00100",
    "Z": "11111 00001 00010 00100 01000 10000 11111",
    "0": "01110 10001 10011 10101 11001 10001 01110",
    "1": "00100 01100 00100 00100 00100 00100 01110",
    "2": "01110 10001 00001 00010 00100 01000 11111",
    "3": "11111 00010 00100 00010 00001 10001 01110",
    "4": "00010 00110 01010 10010 11111 00010 00010",
    "5": "11111 10000 11110 00001 00001 10001 01110",
    "6": "00110 01000 10000 11110 10001 10001 01110",
    "7": "11111 00001 00010 00100 01000 01000 01000",
    "8": "01110 10001 10001 01110 10001 10001 01110",
    "9": "01110 10001 10001 01111 00001 00010 01100",
    " ": "00000 00000 00000 00000 00000 00000 00000",
    ".": "00000 00000 00000 00000 00000 01100 01100",
    ",": "00000 00000 00000 00000 01100 00100 01000",
    "-": "00000 00000 00000 11111 00000 00000 00000",
    ":": "00000 01100 01100 00000 01100 01100 00000",
    "/": "00001 00001 00010 00100 01000 10000 10000",
    "(": "00010 00100 01000 01000 01000 00100 00010",
    ")": "01000 00100 00010 00010 00010 00100 01000",
    "+": "00000 00100 00100 11111 00100 00100 00000",
    "=": "00000 00000 11111 00000 11111 00000 00000",
    "%": "11000 11001 00010 00100 01000 10011 00011",
    "?": "01110 10001 00001 00010 00100 00000 00100",
}
FONT = {
    k: np.array([[c == "1" for c in row] for row in v.split()], bool) for k, v in _FONT_ROWS.items()
}


def text_width(text, scale=2):
    return len(text) * 6 * scale - scale


def draw_text(img, x, y, text, colour=TEXT, scale=2):
    """Draw ``text`` (upper-cased) with its top-left corner at pixel (x, y)."""
    h, w, _ = img.shape
    for ch in text.upper():
        glyph = FONT.get(ch, FONT["?"])
        big = np.kron(glyph, np.ones((scale, scale), bool))
        r0, c0 = y, x
        r1, c1 = min(h, r0 + big.shape[0]), min(w, c0 + big.shape[1])
        if r0 >= 0 and c0 >= 0 and r1 > r0 and c1 > c0:
            img[r0:r1, c0:c1][big[: r1 - r0, : c1 - c0]] = colour
        x += 6 * scale


# -- canvas: world metres <-> pixels, antialiased shapes from signed distances ----------------


class Canvas:
    """An RGB float image of a world rectangle; y up in the world, down in the image."""

    def __init__(self, x0, y0, x1, y1, size_px):
        self.x0, self.y1 = x0, y1
        self.scale = size_px / max(x1 - x0, y1 - y0)  # pixels per metre
        self.w = int(np.ceil((x1 - x0) * self.scale))
        self.h = int(np.ceil((y1 - y0) * self.scale))
        self.img = np.tile(BACKGROUND, (self.h, self.w, 1))

    def to_px(self, xy):
        xy = np.asarray(xy, float)
        return np.stack(
            ((xy[..., 0] - self.x0) * self.scale, (self.y1 - xy[..., 1]) * self.scale), -1
        )

    def _window(self, lo, hi):
        """Pixel rows/cols covering the pixel-space box lo..hi, with pixel-centre coords."""
        c0, r0 = max(int(np.floor(lo[0])), 0), max(int(np.floor(lo[1])), 0)
        c1, r1 = min(int(np.ceil(hi[0])) + 1, self.w), min(int(np.ceil(hi[1])) + 1, self.h)
        if c1 <= c0 or r1 <= r0:
            return None
        cc, rr = np.meshgrid(np.arange(c0, c1) + 0.5, np.arange(r0, r1) + 0.5)
        return (slice(r0, r1), slice(c0, c1)), np.stack((cc, rr), -1)

    def blend(self, win, alpha, colour):
        a = np.clip(alpha, 0.0, 1.0)[..., None]
        self.img[win] = self.img[win] * (1 - a) + np.asarray(colour) * a

    def fill_polygon(self, poly_xy, colour, opacity=1.0, outline_px=0.0, outline=None):
        """Antialiased filled polygon (any simple polygon) given in world metres."""
        p = self.to_px(poly_xy)
        pad = outline_px + 2
        found = self._window(p.min(0) - pad, p.max(0) + pad)
        if found is None:
            return
        win, q = found
        d = _polygon_sdf(q, p)
        if outline is not None and outline_px > 0:
            self.blend(win, opacity * (0.5 - (d - outline_px)), outline)
            self.blend(win, opacity * (0.5 + d), colour)
        else:
            self.blend(win, opacity * (0.5 - d), colour)

    def disc(self, centre_xy, radius_px, colour, outline_px=0.0, outline=None):
        c = self.to_px(centre_xy)
        r = radius_px + outline_px
        found = self._window(c - r - 2, c + r + 2)
        if found is None:
            return
        win, q = found
        d = np.linalg.norm(q - c, axis=-1) - radius_px
        if outline is not None and outline_px > 0:
            self.blend(win, 0.5 - (d - outline_px), outline)
        self.blend(win, 0.5 - d, colour)

    def polyline_mask(self, xy, width_px, chunk=24):
        """(H, W) coverage of a thick polyline (round joins and caps)."""
        mask = np.zeros((self.h, self.w))
        p = self.to_px(xy)
        if p.shape[0] == 1:
            p = np.repeat(p, 2, axis=0)
        half = width_px / 2.0
        for i in range(0, p.shape[0] - 1, chunk):
            part = p[i : i + chunk + 1]
            found = self._window(part.min(0) - half - 2, part.max(0) + half + 2)
            if found is None:
                continue
            win, q = found
            d = _segments_distance(q, part[:-1], part[1:]) - half
            mask[win] = np.maximum(mask[win], np.clip(0.5 - d, 0, 1))
        return mask

    def polyline(self, xy, width_px, colour, opacity=1.0):
        m = self.polyline_mask(xy, width_px)
        self.blend((slice(None), slice(None)), m * opacity, colour)

    def hline_world(self, y, colour, opacity=1.0):
        """A one-pixel antialiased horizontal line at world y (vline_world: vertical, at x)."""
        r = (self.y1 - y) * self.scale - 0.5
        self._axis_line(r, colour, opacity, rows=True)

    def vline_world(self, x, colour, opacity=1.0):
        c = (x - self.x0) * self.scale - 0.5
        self._axis_line(c, colour, opacity, rows=False)

    def _axis_line(self, pos, colour, opacity, rows):
        i = int(np.floor(pos))
        f = pos - i
        n = self.h if rows else self.w
        for k, a in ((i, 1 - f), (i + 1, f)):
            if 0 <= k < n and a > 0:
                win = (slice(k, k + 1), slice(None)) if rows else (slice(None), slice(k, k + 1))
                shape = (1, self.w) if rows else (self.h, 1)
                self.blend(win, np.full(shape, a * opacity), colour)


def _segments_distance(q, a, b):
    """Distance of pixel points q (..., 2) to segments a -> b (E, 2): (...,)."""
    pts = q.reshape(-1, 2)
    ab = b - a
    t = ((pts[:, None] - a[None]) * ab[None]).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12)
    t = np.clip(t, 0.0, 1.0)
    proj = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(pts[:, None] - proj, axis=-1).min(axis=1).reshape(q.shape[:-1])


def _polygon_sdf(q, poly):
    """Signed distance (negative inside) of points q (..., 2) to a simple polygon (P, 2)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    d = _segments_distance(q, a, b)
    pts = q.reshape(-1, 2)
    # even-odd crossing test
    y = pts[:, 1:2]
    cond = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    xint = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / np.where(
        b[None, :, 1] == a[None, :, 1], 1e-12, b[None, :, 1] - a[None, :, 1]
    )
    inside = (np.sum(cond & (pts[:, 0:1] < xint), axis=1) % 2 == 1).reshape(q.shape[:-1])
    return np.where(inside, -d, d)


# -- the plot -------------------------------------------------------------------------------


def _piece_colours(pieces):
    out, n = [], 0
    for p in pieces:
        if p.kind == "start":
            out.append(START)
        elif p.kind == "goal":
            out.append(GOAL)
        elif p.kind == "segment":
            out.append(SEGMENT_A if n % 2 == 0 else SEGMENT_B)
            n += 1
        else:
            out.append(DIRECT)
    return out


def _arrow(canvas, state, colour, length_m, width_px):
    """A heading tick ending in an arrow head, from ``state`` (x, y, heading)."""
    x, y, h = state
    u = np.array([np.cos(h), np.sin(h)])
    n = np.array([-u[1], u[0]])
    tip = np.array([x, y]) + u * length_m
    head = 9.0 / canvas.scale  # arrow head length in metres (about 9 px)
    canvas.polyline(np.stack(([x, y], tip - u * head * 0.6)), width_px, colour)
    tri = np.stack((tip, tip - u * head + n * head * 0.55, tip - u * head - n * head * 0.55))
    canvas.fill_polygon(tri, colour)


def plot_layout(
    path_png,
    env,
    patch,
    plan,
    motions,
    size_px=900,
    margin_m=1.0,
    start=None,
    goal=None,
    title=None,
    searched=None,
):
    """Write a top-down PNG of ``env`` and a plan on it; returns the image (H, W, 3) floats.

    ``plan`` is a :class:`~motion_patches.planning.planner.Plan` (or None to draw only the scene and
    ``start`` / ``goal``), ``motions`` its per-piece world motions (``planner.plan_motions``;
    computed when None). The view is the box around the path, start and goal grown by
    ``margin_m``; ``size_px`` is its longer side. A legend strip is added below the map,
    with a summary of the plan (pieces, seconds of motion, metres, nodes expanded), an
    optional ``title`` line and a scale bar. ``start`` / ``goal`` (x, y, heading) default to
    the plan's.

    What is drawn, bottom to top:

    * white ground; faint lines of the patch's cells and grey lines of the tile grid
      (tile (i, j) has its corner at (i * side, j * side)); a plan is drawn in its plan
      frame (:mod:`motion_patches.planning.plan_frame`: the start on the left, the goal to its
      right),
      so the grid is the lattice the planner searched;
    * occluded cells in light coral: cells whose bit is clear in ``env.free_cells(tile)``
      (bit c is cell (c % cells, c // cells)), i.e. cells within the character's radius of
      a footprint, for every tile in view that holds obstacles. Computing them here is
      lazy occlusion like the planner's; ``env.occlusion_computations`` is left unchanged;
    * obstacle footprints filled dark slate;
    * ``searched`` (optional motions of the same plan before shortening) as a thin grey line;
    * the planned ground path (``motion.ground[:, :2]``) as a thick line coloured per
      piece: start connector green, motion segments alternating blue and amber, goal
      connector red (a "direct" piece purple);
    * stitch points, the boundaries between pieces, as white dots ringed in black;
    * the start (green) and the goal (red) as discs with a dark arrow along their heading.
    """
    if plan is not None and motions is None:
        from motion_patches.planning.planner import plan_motions

        motions = plan_motions(patch, plan)
    motions = motions or []
    if plan is not None:
        start = plan.start if start is None else start
        goal = plan.goal if goal is None else goal
    frame = plan.stats.get("frame") if plan is not None else None
    if frame is not None:
        # Drawn in the plan frame, where the planner laid its tile lattice (anchored at
        # the start, +x towards the goal): the grid is then the one it searched.
        from motion_patches.planning import plan_frame

        c, s_ = np.cos(frame[2]), np.sin(frame[2])
        shift = -np.array([c * frame[0] + s_ * frame[1], -s_ * frame[0] + c * frame[1]])
        motions = [m.transformed(shift[0], shift[1], -frame[2]) for m in motions]
        searched = [m.transformed(shift[0], shift[1], -frame[2]) for m in searched or []]
        start = (
            None if start is None else plan_frame.state_to_local(frame, np.asarray(start, float))
        )
        goal = None if goal is None else plan_frame.state_to_local(frame, np.asarray(goal, float))
        every = np.concatenate(
            [m.ground[:, :2] for m in motions] + [start[None, :2], goal[None, :2]]
        )
        env = plan_frame.local_environment(
            env, frame, every.min(0) - margin_m - env.side, every.max(0) + margin_m + env.side
        )
    pts = [m.ground[:, :2] for m in motions]
    pts += [np.asarray(s, float)[None, :2] for s in (start, goal) if s is not None]
    if not pts:
        raise ValueError("nothing to draw: give a plan or a start and goal")
    pts = np.concatenate(pts)
    lo, hi = pts.min(0) - margin_m, pts.max(0) + margin_m
    cv = Canvas(lo[0], lo[1], hi[0], hi[1], size_px)
    side, cells = env.side, env.cells
    cell = side / cells

    # Occluded cells (exact pixel-centre fill, so neighbouring cells show no seams).
    ti0, tj0 = env.tile_of(lo)
    ti1, tj1 = env.tile_of(hi)
    counter = env.occlusion_computations
    occ = np.zeros((cv.h, cv.w), bool)
    cols_x = cv.x0 + (np.arange(cv.w) + 0.5) / cv.scale
    rows_y = cv.y1 - (np.arange(cv.h) + 0.5) / cv.scale
    for i in range(ti0, ti1 + 1):
        for j in range(tj0, tj1 + 1):
            if not env.members((i, j)):
                continue
            free = int(env.free_cells((i, j)))
            for c in range(cells * cells):
                if free >> c & 1:
                    continue
                cx0, cy0 = i * side + (c % cells) * cell, j * side + (c // cells) * cell
                cs = (cols_x >= cx0) & (cols_x < cx0 + cell)
                rs = (rows_y >= cy0) & (rows_y < cy0 + cell)
                occ[np.ix_(rs, cs)] = True
    env.occlusion_computations = counter
    cv.img[occ] = OCCLUDED

    # Cell and tile grid.
    for k in range(int(np.floor(lo[0] / cell)), int(np.ceil(hi[0] / cell)) + 1):
        if k % cells:
            cv.vline_world(k * cell, CELL_GRID)
    for k in range(int(np.floor(lo[1] / cell)), int(np.ceil(hi[1] / cell)) + 1):
        if k % cells:
            cv.hline_world(k * cell, CELL_GRID)
    for i in range(ti0, ti1 + 2):
        cv.vline_world(i * side, TILE_GRID)
    for j in range(tj0, tj1 + 2):
        cv.hline_world(j * side, TILE_GRID)

    # Obstacles in view.
    for ob in env.obstacles.values():
        blo, bhi = ob.bounds()
        if np.all(bhi >= lo) and np.all(blo <= hi):
            cv.fill_polygon(ob.polygon, OBSTACLE)

    # Path, one colour per piece; the joins are covered by the stitch dots.
    width = max(3.0, size_px / 180.0)
    for m in searched or []:  # the path as the segment search found it, before shortening
        cv.polyline(m.ground[:, :2], max(1.5, width / 3), TILE_GRID)
    if plan is not None:
        for m, colour in zip(motions, _piece_colours(plan.pieces)):
            cv.polyline(m.ground[:, :2], width, colour)
        for m in motions[1:]:
            cv.disc(m.ground[0, :2], width * 0.75, STITCH_FILL, 1.5, STITCH_EDGE)

    # Start and goal with their headings.
    tick = max(0.6, 28.0 / cv.scale)
    for state, colour in ((start, START), (goal, GOAL)):
        if state is None:
            continue
        state = np.asarray(state, float)
        _arrow(cv, state, colour * 0.55, tick, width * 0.8)
        cv.disc(state[:2], width * 1.5, colour, 2.0, BACKGROUND)

    img = np.concatenate((cv.img, _legend(cv, plan, motions, patch, title)), axis=0)
    write_png(path_png, img)
    return img


def _legend(cv, plan, motions, patch, title):
    """The legend strip below the map: swatches, a scale bar and a one-line summary."""
    s = 2 if cv.w >= 600 else 1
    row_h = 12 * s
    entries = [
        ("line", START, "start"),
        ("line2", (SEGMENT_A, SEGMENT_B), "segments"),
        ("line", GOAL, "goal"),
        ("dot", None, "stitch"),
        ("box", OBSTACLE, "obstacle"),
        ("box", OCCLUDED, "occluded cell"),
        ("grid", TILE_GRID, "tile grid"),
    ]
    # Flow the entries left to right, wrapping onto new rows.
    widths = [34 * s + text_width(t, s) + 18 * s for _, _, t in entries]
    placed, x, r = [], 8 * s, 0
    for wd in widths:
        if x + wd > cv.w and x > 8 * s:
            x, r = 8 * s, r + 1
        placed.append((x, r))
        x += wd
    nrow = r + 1
    lines = []
    if plan is not None:
        frames = sum(m.frames for m in motions) - (len(motions) - 1)
        fps = patch.gait.fps if patch is not None else 30.0
        metres = sum(
            float(np.linalg.norm(np.diff(m.ground[:, :2], axis=0), axis=1).sum()) for m in motions
        )
        lines.append(
            f"{len(plan.pieces)} pieces, {(frames - 1) / fps:.1f} s of motion, "
            f"{metres:.1f} m, {plan.expansions} nodes expanded"
        )
    if title:
        lines.insert(0, title)
    # Scale bar: a round number of metres about a sixth of the width, right-aligned on
    # the last text line, or on a line of its own when that line is too long.
    target = cv.w / 6.0 / cv.scale
    bar_m = max(m for m in (0.5, 1, 2, 5, 10, 20, 50, 100) if m <= max(target, 0.5))
    bar = int(round(bar_m * cv.scale))
    bar_label = f"{bar_m:g} m"
    bar_w = bar + 8 * s + text_width(bar_label, s)
    last = text_width(lines[-1], s) if lines else 0
    if not lines or 8 * s + last + 24 * s + bar_w + 8 * s > cv.w:
        lines.append("")
    h = (nrow + len(lines)) * row_h + 12 * s
    strip = np.tile(PANEL, (h, cv.w, 1))
    strip[0] = TILE_GRID
    y0 = 6 * s
    for (kind, colour, label), (x, r) in zip(entries, placed):
        y = y0 + r * row_h
        mid = y + 3 * s
        sw = slice(x, x + 26 * s)
        if kind == "line":
            strip[mid - 2 * s : mid + 2 * s, sw] = colour
        elif kind == "line2":
            strip[mid - 2 * s : mid + 2 * s, x : x + 13 * s] = colour[0]
            strip[mid - 2 * s : mid + 2 * s, x + 13 * s : x + 26 * s] = colour[1]
        elif kind == "box":
            strip[y - 1 * s : y + 8 * s, sw] = colour
        elif kind == "grid":
            strip[y - 1 * s : y + 8 * s, sw] = BACKGROUND
            strip[y - 1 * s : y + 8 * s, x + 4 * s] = CELL_GRID * 0.97
            strip[y - 1 * s : y + 8 * s, x + 13 * s] = colour
            strip[mid, sw] = colour
        elif kind == "dot":
            rr, cc = np.mgrid[-5 * s : 5 * s + 1, -5 * s : 5 * s + 1]
            d = np.hypot(rr, cc)
            spot = strip[mid - 5 * s : mid + 5 * s + 1, x + 8 * s : x + 18 * s + 1]
            spot[d <= 4 * s] = STITCH_EDGE
            spot[d <= 4 * s - 1.5] = STITCH_FILL
        draw_text(strip, x + 32 * s, y, label, TEXT, s)
    y = y0 + nrow * row_h
    x = cv.w - bar_w - 8 * s
    yb = y + 2 * s + (len(lines) - 1) * row_h
    strip[yb + 3 * s : yb + 4 * s, x : x + bar] = TEXT
    strip[yb : yb + 7 * s, x : x + s] = TEXT
    strip[yb : yb + 7 * s, x + bar - s : x + bar] = TEXT
    draw_text(strip, x + bar + 8 * s, yb, bar_label, TEXT, s)
    for k, line in enumerate(lines):
        draw_text(strip, 8 * s, y + 2 * s + k * row_h, line, TEXT, s)
    return strip


# -- demo -----------------------------------------------------------------------------------


def demo_pillars(seed=7, sides=32):
    """The pillars of tools/demo.py as footprints (Blender's default cylinder has 32 sides)."""
    import demo_layout

    from motion_patches.props.environment import Obstacle

    a = np.linspace(0.0, 2.0 * np.pi, sides + 1)[:-1]
    return [
        Obstacle(f"Pillar.{n:02d}", np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))
        for n, (x, y, r) in enumerate(demo_layout.pillar_positions(seed))
    ]


def main(argv=None):
    p = argparse.ArgumentParser(description="Plan through the demo's pillar field and draw it.")
    p.add_argument("--output", default=str(REPO / "docs" / "plan.png"))
    p.add_argument(
        "--mocap",
        default=os.environ.get("MOTION_PATCHES_MOCAP", str(REPO.parent / "shared" / "mocap")),
    )
    p.add_argument("--seed", type=int, default=7, help="pillar layout seed (as tools/demo.py)")
    p.add_argument("--size", type=int, default=900, help="map width in pixels")
    p.add_argument("--radius", type=float, default=0.25, help="character radius in metres")
    p.add_argument("--margin", type=float, default=1.5, help="metres shown around the path")
    args = p.parse_args(argv)
    from motion_patches.kinematics import bvh
    from motion_patches.patch import gait, locomotion_patch
    from motion_patches.planning.planner import SegmentPlanner, plan_motions
    from motion_patches.props.environment import Environment

    mocap = Path(args.mocap) / "cmu"
    g = gait.build_gait("walk", bvh.read(mocap / "16_15.bvh"), (bvh.read(mocap / "16_18.bvh"),))
    patch = locomotion_patch.bake(g)
    import demo_layout

    start, goal = demo_layout.START, demo_layout.GOAL
    env = Environment(patch.side, patch.cells, args.radius)
    for ob in demo_pillars(args.seed):
        env.place(ob)
    plan = SegmentPlanner(patch, env).plan(start, goal)
    motions = plan_motions(patch, plan)
    found = SegmentPlanner(patch, env).plan(start, goal, shorten=False)
    plot_layout(
        args.output,
        env,
        patch,
        plan,
        motions,
        size_px=args.size,
        margin_m=args.margin,
        searched=plan_motions(patch, found),
    )
    print(
        f"wrote {args.output}: {len(plan.pieces)} pieces, {plan.expansions} nodes, "
        f"{len(env.obstacles)} pillars"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
