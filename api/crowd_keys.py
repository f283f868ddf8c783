# SPDX-License-Identifier: GPL-3.0-or-later
"""The keys a crowd's characters are written with, prepared on the workers ahead of
Blender's writing (:func:`~..motion_patches.crowd.members.prepared_keys`: the foot lock,
the body's and the root's fitted keys, from a character's plan and piece motions).

A character's keys do not depend on when it starts, only on its plan and piece motions,
and most characters leave the crowd's resolution with the plan they came in with (no hold
laid in, not re-routed). Those are asked for as the resolution places them (:meth:`Keys.
early`): Blender's process then resolves the crowd on one core while the workers mostly
wait for re-plans. Writing takes them for each character still written with the plan and
motions they were made of, and prepares the others ahead of the character it writes, as
it did all of them before."""

from __future__ import annotations

from typing import Any

from ..motion_patches.crowd import members
from .common import _skeleton
from .writing import _prepared_args

AHEAD = 4  # characters whose writes are prepared while one is written, in process
# In process one thread prepares them (cluster.InProcess.pool): the main thread, writing
# through Blender, needs the GIL most of the time; a second preparing thread slowed it more
# than it gained (bench_blender, 200 characters on 2 cores: writing 6.0 s with one, 7.4 s
# with two or three). On a cluster its workers prepare them, this many each ahead (their
# answers come back over the network; 4 each wrote the plaza of 1,000 about a second slower).
AHEAD_PER_WORKER = 8
# Characters a worker prepares in one task: each task costs Blender's process a few
# milliseconds of Dask's own work (messages, the answer fetched), beside Blender's.
BATCH = 4
# Tasks of keys asked early that may be on the workers at once: the rest wait their turn in
# this process (those still waiting when the crowd is resolved are prepared as the writing
# comes to them). All at once, a crowd resolved in a second or two (the 1,000 lanes of
# bench_blender) had its resolution slowed by the stream of tasks and their fitting
# (planned and written 36.6 s against 35.6); two at a time it was not (31.2 s).
FLYING = 2


class Keys:
    """Each planned character's prepared keys, by its index in ``planned`` ([n, plan,
    piece motions, root track, holdable] of :func:`~.crowd._entry`), asked of ``pool``
    (``c.executor``'s): early (:meth:`early`) or ahead of the writing (:meth:`take`)."""

    def __init__(self, c: Any, pool: Any, planned: list) -> None:
        self.c, self.pool, self.planned = c, pool, planned
        self.batch = BATCH if c.executor.workers else 1
        self.depth = max(AHEAD, AHEAD_PER_WORKER * c.executor.workers)
        self._shared: Any = None
        self.asked: dict[int, tuple] = {}  # k -> (plan, motions, answer, place in it)
        self.uses: dict[Any, int] = {}  # answer -> characters still to take from it
        self.answers: dict[Any, list] = {}  # answers taken, until all their keys are
        self.waiting: list[tuple] = []  # (k, plan, motions) asked early, until a batch is full
        self.fresh: list[int] = []  # the characters to prepare while writing, in order
        self.next = 0  # of ``fresh``, the first not asked for yet
        self.flying: list = []  # answers asked early, not made yet

    def _ask(self, items: list[tuple], aside: bool = False) -> Any:
        """Ask for the keys of ``items`` [(k, plan, piece motions)] in one task."""
        if self._shared is None:  # the patch, sent to every worker once
            self._shared = self.pool.share(patch=self.c.patch)
        jobs = []
        for k, plan, raw in items:
            n = self.planned[k][0]
            skel = _skeleton(self.c.rigs[n], self.c.patch)
            args = _prepared_args(self.c.pairs[n][0], skel, None, self.c.settings, self.c.fps, plan)
            # each motion is placed where it is prepared (sent the piece motions, a quarter
            # of the bytes) and again here when written
            jobs.append((raw, self.c.rigs[n], args))
        answer = self.pool.submit(
            members.prepared_keys, jobs, self.c.fps, shared=self._shared, aside=aside
        )
        for place, (k, plan, raw) in enumerate(items):
            self.asked[k] = (plan, raw, answer, place)
        self.uses[answer] = len(items)
        return answer

    def early(self, k: int, plan: Any, raw: list) -> None:
        """Character ``k`` placed by the resolution, to be written with ``plan`` and piece
        motions ``raw`` unless it is placed again otherwise: their keys asked for now
        (:data:`BATCH` characters at a time), on one worker (``aside``: the others stay
        free for the re-plans the resolution waits for)."""
        old = self.asked.get(k)
        if old is not None:
            if old[0] is plan and old[1] is raw:
                return
            del self.asked[k]
            self._taken(old[2])
        self.waiting = [w for w in self.waiting if w[0] != k] + [(k, plan, raw)]
        self.flying = [a for a in self.flying if a in self.uses and not self.pool.done(a)]
        while len(self.waiting) >= self.batch and len(self.flying) < FLYING:
            self.flying.append(self._ask(self.waiting[: self.batch], aside=True))
            self.waiting = self.waiting[self.batch :]

    def writing(self, planned: list) -> None:
        """The crowd is resolved: ``planned`` is what is written. Keys asked for early of
        a character written with another plan or other motions (a hold laid in, a
        re-route) are let go; those characters, and the ones never asked for, are
        prepared ahead of the writing (:meth:`take`)."""
        self.planned, self.waiting = planned, []
        for k, (plan, raw, answer, _) in list(self.asked.items()):
            if planned[k][1] is not plan or planned[k][2] is not raw:
                del self.asked[k]
                self._taken(answer)
        self.fresh = [k for k in range(len(planned)) if k not in self.asked]
        self.next = 0

    def _taken(self, answer: Any) -> None:
        self.uses[answer] -= 1
        if not self.uses[answer]:  # let go of it (a future no one holds is released)
            del self.uses[answer]
            self.answers.pop(answer, None)

    def take(self, k: int) -> Any:
        """Character ``k``'s prepared keys (packed), the next characters' asked for."""
        while self.next < len(self.fresh) and self.fresh[self.next] < k + self.depth:
            ks = self.fresh[self.next : self.next + self.batch]
            self._ask([(j, self.planned[j][1], self.planned[j][2]) for j in ks])
            self.next += len(ks)
        _, _, answer, place = self.asked.pop(k)
        got = self.answers.get(answer)
        if got is None:
            got = self.answers[answer] = answer.result()
        keys, got[place] = got[place], None
        self._taken(answer)
        return keys
