# SPDX-License-Identifier: GPL-3.0-or-later
"""String pulling's chain of Dubins parts through the pulled corners
(``shortcut._chain``): a depth-first search over the heading each corner is passed at. The
rest of a chain depends only on the corner and that heading, so a rest found not to fit is
not searched again from another way into the corner: no part is tested twice, and the
chain found is the one the search finds without that (the first that fits, in order)."""

import itertools

import numpy as np

from motion_patches.planning import shortcut


class Parts:
    """A stand-in planner whose Dubins parts fit where ``fits(j, ha, hb)`` says (part into
    corner ``j`` from heading ``ha`` at the corner before, passing ``j`` at ``hb``); every
    part tested is recorded."""

    def __init__(self, corners, fits):
        self.corners, self.fits, self.tested = corners, fits, []

    def dubins_table(self, p0, h0, p1, h1, max_length=None):
        return p1, h1

    def first_valids(self, p0, h0, table, columns):
        p1, h1 = table
        out = []
        for c in columns:
            j = int(np.flatnonzero((self.corners == p1[c]).all(axis=1))[0])
            part = (j, round(float(h0[c]), 9), round(float(h1[c]), 9))
            self.tested.append(part)
            out.append((0.0, 0, lambda part=part: part) if self.fits(*part) else None)
        return out


def headings(corners, goal_heading):
    """The headings each corner may be passed at, in the order the chain tries them (the
    bisector of its legs, its outgoing leg, its incoming leg; the goal's own)."""
    out = [None]
    for j in range(1, len(corners) - 1):
        d_in, d_out = corners[j] - corners[j - 1], corners[j + 1] - corners[j]
        a_in, a_out = np.arctan2(d_in[1], d_in[0]), np.arctan2(d_out[1], d_out[0])
        turn = (a_out - a_in + np.pi) % (2 * np.pi) - np.pi
        out.append([round(float(h), 9) for h in (a_in + turn / 2, a_out, a_in)])
    return out + [[round(goal_heading, 9)]]


def search_without_memory(corners, fits, first, goal_heading):
    """The chain the plain depth-first search finds (options in the same order)."""
    for choice in itertools.product(*headings(corners, goal_heading)[1:]):
        path, ha = [], round(first[1], 9)
        for j, hb in enumerate(choice, start=1):
            if not fits(j, ha, hb):
                break
            path.append((j, ha, hb))
            ha = hb
        else:
            return path
    return None


CORNERS = np.array([[0.0, 0.0], [2.0, 1.0], [4.0, -1.0], [6.0, 1.0], [8.0, 0.0], [10.0, 0.5]])


def test_a_rest_that_does_not_fit_is_not_searched_again():
    """Into the goal only from corner 4 passed along its incoming leg (its last option),
    which only corner 3 passed that way leads to, which only corner 2 passed that way
    leads to: the search backs up two corners, past rests that do not fit."""
    heads = headings(CORNERS, 0.0)
    last = {j: heads[j][2] for j in (2, 3, 4)}

    def fits(j, ha, hb):
        if j == 5:
            return ha == last[4]
        if j in (3, 4):
            return ha == last[j - 1] or hb != last[j]
        return True

    first = (CORNERS[0], 0.0)
    planner = Parts(CORNERS, fits)
    got = shortcut._chain(planner, CORNERS, first, 0.0, budget=10_000)
    assert got == search_without_memory(CORNERS, fits, first, 0.0)
    assert [hb for _, _, hb in got[1:4]] == [last[2], last[3], last[4]]
    assert len(planner.tested) == len(set(planner.tested))  # no part tested twice


def test_no_chain_fits():
    planner = Parts(CORNERS, lambda j, ha, hb: j < 5)
    assert shortcut._chain(planner, CORNERS, (CORNERS[0], 0.0), 1.0, budget=10_000) is None
    assert len(planner.tested) == len(set(planner.tested))
