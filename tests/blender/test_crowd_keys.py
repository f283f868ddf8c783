# SPDX-License-Identifier: GPL-3.0-or-later
"""A crowd's keys asked for early (as the resolution places each character) are taken
only for a character written with the plan and motions they were made of; the others are
prepared again ahead of the writing, in order, and every answer is let go once taken."""

from types import SimpleNamespace


class Pool:
    """A pool that records what it is asked and answers each job with its plan."""

    def __init__(self):
        self.asked = []  # (characters' plans, aside)
        self.answers = []

    def share(self, **shared):
        return shared

    def done(self, answer):
        return answer.made

    def submit(self, fn, jobs, fps, shared=None, aside=False):
        plans = [args[4] for _, _, args in jobs]
        self.asked.append((plans, aside))
        self.answers.append(Answer(plans))
        return self.answers[-1]


class Answer:
    def __init__(self, plans):
        self.plans = list(plans)
        self.made = False

    def result(self):
        return list(self.plans)


def test_keys_asked_early_are_taken_only_for_the_plan_written(addon_module, monkeypatch):
    ck = addon_module.api.crowd_keys
    monkeypatch.setattr(ck, "_skeleton", lambda rig, patch: None)
    monkeypatch.setattr(
        ck, "_prepared_args", lambda ob, skel, placed, settings, fps, plan: (0, 0, 0, 0, plan)
    )
    n = 14
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
    assert ck.FLYING == 2
    for k in range(12):  # placed as planned: asked for four at a time, aside, two at once
        keys.early(k, planned[k][1], planned[k][2])
    keys.early(3, planned[3][1], planned[3][2])  # placed again the same: not asked again
    assert pool.asked == [
        (["plan0", "plan1", "plan2", "plan3"], True),
        (["plan4", "plan5", "plan6", "plan7"], True),
    ]
    pool.answers[0].made = True  # one made: the next four are asked for
    keys.early(12, planned[12][1], planned[12][2])
    assert pool.asked[2] == (["plan8", "plan9", "plan10", "plan11"], True)
    keys.early(5, "plan5 held", ["held"])  # placed again otherwise: asked again
    written = [list(p) for p in planned]
    written[2][1] = "plan2 re-routed"  # what the writing writes
    written[5][1], written[5][2] = "plan5 held", ["held"]
    written[6][2] = ["raw6 held"]
    keys.writing(written)
    assert keys.fresh == [2, 5, 6, 12, 13]  # 5's second ask and 12 never made a batch
    got = [keys.take(k) for k in range(n)]
    assert got == [p[1] for p in written]
    assert pool.asked[3:] == [
        (["plan2 re-routed", "plan5 held", "plan6", "plan12"], False),
        (["plan13"], False),
    ]
    assert not keys.asked and not keys.uses and not keys.answers  # all let go
