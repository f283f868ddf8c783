# SPDX-License-Identifier: GPL-3.0-or-later
"""A crowd's keys asked for early (as the resolution places each character) are taken
only for a character written with the plan and motions they were made of; the others are
prepared again ahead of the writing, in order, and every answer is let go once taken."""

from types import SimpleNamespace


class Pool:
    """A pool that records what it is asked and answers each job with its plan."""

    def __init__(self):
        self.asked = []  # (characters' plans, aside)

    def share(self, **shared):
        return shared

    def submit(self, fn, jobs, fps, shared=None, aside=False):
        plans = [args[4] for _, _, args in jobs]
        self.asked.append((plans, aside))
        return Answer(plans)


class Answer:
    def __init__(self, plans):
        self.plans = list(plans)

    def result(self):
        return list(self.plans)


def test_keys_asked_early_are_taken_only_for_the_plan_written(addon_module, monkeypatch):
    ck = addon_module.api.crowd_keys
    monkeypatch.setattr(ck, "_skeleton", lambda rig, patch: None)
    monkeypatch.setattr(
        ck, "_prepared_args", lambda ob, skel, placed, settings, fps, plan: (0, 0, 0, 0, plan)
    )
    n = 10
    planned = [[k, f"plan{k}", [f"raw{k}"], None, None] for k in range(n)]
    c = SimpleNamespace(
        executor=SimpleNamespace(workers=2),
        patch=None,
        rigs=[None] * n,
        pairs=[(f"ob{k}", None) for k in range(n)],
        settings=None,
        fps=24.0,
    )
    pool = Pool()
    keys = ck.Keys(c, pool, planned)
    for k in range(8):  # placed as planned: asked for four at a time, aside
        keys.early(k, planned[k][1], planned[k][2])
    keys.early(3, planned[3][1], planned[3][2])  # placed again the same: not asked again
    assert pool.asked == [(["plan0", "plan1", "plan2", "plan3"], True)] + [
        (["plan4", "plan5", "plan6", "plan7"], True)
    ]
    keys.early(5, "plan5 held", ["held"])  # placed again otherwise: asked again
    written = [list(p) for p in planned]
    written[2][1] = "plan2 re-routed"  # what the writing writes
    written[5][1], written[5][2] = "plan5 held", ["held"]
    written[6][2] = ["raw6 held"]
    keys.writing(written)
    assert keys.fresh == [2, 5, 6, 8, 9]  # 5's second ask never made a batch: fresh
    got = [keys.take(k) for k in range(n)]
    assert got == [p[1] for p in written]
    assert pool.asked[2:] == [
        (["plan2 re-routed", "plan5 held", "plan6", "plan8"], False),
        (["plan9"], False),
    ]
    assert not keys.asked and not keys.uses and not keys.answers  # all let go
