# SPDX-License-Identifier: GPL-3.0-or-later
"""A crowd's members planned anywhere give the same plans: in this process, on a Dask
LocalCluster of one and of two workers, and on a real `dask scheduler` with two
`dask worker` processes over TCP of which one is killed mid-run."""

import contextlib
import json
import os
import pickle
import subprocess
import sys
import time
from dataclasses import replace

import numpy as np
import pytest

from motion_patches import cluster
from motion_patches.crowd import crowd, members
from motion_patches.kinematics import keys
from motion_patches.planning import body_clearance
from motion_patches.planning.settings import PlanSettings
from motion_patches.props.environment import Environment, Obstacle

RADIUS = 0.25
SPACING = 2 * RADIUS


def box(x, y, half=0.3):
    return np.array(
        [[x - half, y - half], [x + half, y - half], [x + half, y + half], [x - half, y + half]]
    )


def crossing(patch, per_side=3, seed=5):
    """A small four-way crossing: ``per_side`` walkers enter from each side of a 10 m
    square with four pillars in the middle and cross to shuffled goals on the far side."""
    rng = np.random.default_rng(seed)
    env = Environment(patch.side, patch.cells, radius=RADIUS)
    for k, (x, y) in enumerate([(-1.5, -1.5), (1.5, -1.5), (-1.5, 1.5), (1.5, 1.5)]):
        env.place(Obstacle(f"pillar{k}", box(x, y)))
    slots = np.linspace(-3.0, 3.0, per_side)
    ends = []
    for side, (ax, heading) in enumerate(
        [((-5, 0), 0.0), ((5, 0), np.pi), ((0, -5), np.pi / 2), ((0, 5), -np.pi / 2)]
    ):
        goals = rng.permutation(slots)
        for s, g in zip(slots, goals):
            if ax[0]:
                start, goal = (ax[0], s, heading), (-ax[0], g, heading)
            else:
                start, goal = (s, ax[1], heading), (g, -ax[1], heading)
            ends.append((np.array(start, float), np.array(goal, float)))
    world = members.MemberWorld(
        patch,
        env,
        [],
        PlanSettings(radius=RADIUS),
        scene_fps=patch.gait.fps,
        rank_ends=ends,
        spot_names=[f"spot{m}" for m in range(len(ends))],
        spacing=SPACING,
    )
    tasks = [
        members.MemberTask(i, (ends[i][0], ends[i][1], None, None), rank=i)
        for i in range(len(ends))
    ]
    return world, tasks


def fingerprint(answers):
    """What must not depend on where a member was planned: each plan's pieces and cost, its
    frame bounds and its root track, to the bit."""
    out = []
    for a in answers:
        assert isinstance(a, members.Member), a
        out.append(
            (
                a.entry,
                round(a.plan.cost, 12),
                tuple(p.label for p in a.plan.pieces),
                tuple(int(b) for b in a.bounds),
                a.root_track.tobytes(),
            )
        )
    return out


@pytest.fixture(scope="module")
def crossing12(walk_patch):
    return crossing(walk_patch)


@pytest.fixture(scope="module")
def in_process(crossing12):
    world, tasks = crossing12
    return fingerprint(cluster.InProcess().map(members.plan_member, tasks, world=world))


def test_chunks_cover_every_item_once_in_order():
    for n in (0, 1, 5, 17, 100):
        for parts in (1, 2, 3, 8, 200):
            runs = cluster.chunks(n, parts)
            assert [i for r in runs for i in r] == list(range(n))
            assert len(runs) <= max(1, parts)
            if runs:
                sizes = [len(r) for r in runs]
                assert max(sizes) - min(sizes) <= 1


def test_a_worker_unpickles_a_maps_shared_inputs_once_and_lets_an_earlier_maps_go():
    """Shared inputs travel pickled and each worker process unpickles its own copy once per
    map: a task may fill caches in it while Dask copies the scattered bytes on to another
    worker."""
    import pickle

    world = {"cache": {}}
    packed = {"world": pickle.dumps(world)}
    seen = cluster.run_chunk(lambda i, world: id(world), [0, 1], packed, "map-a")
    again = cluster.run_chunk(lambda i, world: id(world), [2], packed, "map-a")
    assert len(set(seen + again)) == 1  # one copy for the map's tasks here
    first = cluster._unpacked("map-a", packed)
    first["world"]["cache"]["filled"] = True  # a task fills a cache: the bytes stay as sent
    assert pickle.loads(packed["world"]) == {"cache": {}}
    other = cluster._unpacked("map-b", packed)
    assert other["world"] == {"cache": {}} and list(cluster._UNPACKED) == ["map-b"]


def test_members_in_process_are_planned_and_kept_off_the_standing_spots(in_process, crossing12):
    world, tasks = crossing12
    assert len(in_process) == len(tasks) == 12
    assert all(cost > 0 for _, cost, *_ in in_process)


def test_members_keep_their_hips_the_spacing_from_where_the_others_stand(crossing12):
    """Each walker's root (the hips, what the crowd keeps apart) passes every other's start
    and goal at least the spacing away (but those on its own ends, where it stands itself):
    the standing spots are grown by the hips' sway about the path planned."""
    world, tasks = crossing12
    gait = world.patch.gait
    assert 0.005 < body_clearance.sway(gait, [gait.straight]) < 0.05  # a captured walk: ~2 cm
    xy = world.rank_xy
    closest = []
    for t in tasks:
        got = members.plan_member(t, world)
        assert isinstance(got, members.Member), got
        spots = np.delete(xy, t.entry, axis=0).reshape(-1, 2)
        own = np.linalg.norm(spots[:, None] - xy[t.entry][None], axis=2).min(axis=1)
        spots = spots[own > 2 * SPACING]
        d = np.linalg.norm(got.root_track[:, None, :] - spots[None], axis=2)
        closest.append(d.min())
    assert min(closest) >= SPACING, closest


def test_standing_spots_are_made_once_per_world_and_again_when_the_ranks_change(walk_patch):
    world, tasks = crossing(walk_patch)
    first = members.spots_of(tasks[0], world)
    assert first and members.spots_of(tasks[0], world) == first  # the same obstacles
    again = members.spots_of(tasks[1], world)
    shared = {ob.name for ob in first} & {ob.name for ob in again}
    assert shared and all(
        a is b for a in first for b in again if a.name == b.name
    )  # another member of the size takes the same spot obstacles
    assert pickle.loads(pickle.dumps(world))._spots is None  # made again where used
    moved = [(s + np.array([0.5, 0.0, 0.0]), g) for s, g in world.rank_ends]
    world.rank_ends = moved
    after = members.spots_of(tasks[0], world)
    assert [ob.name for ob in after] and all(
        not np.array_equal(a.polygon, b.polygon)
        for a in after
        for b in first
        if a.name == b.name and a.name.endswith("start")
    )


@pytest.mark.parametrize("workers", [1, 2])
def test_a_local_cluster_plans_the_same_members(crossing12, in_process, workers):
    world, tasks = crossing12
    before = dict(os.environ)
    with cluster.DaskCluster(workers=workers) as ex:
        assert ex.workers == workers
        # this process's environment as it was (the nannies set OMP_NUM_THREADS=1, ... in
        # it to spawn their workers; every process started after would inherit them)
        assert dict(os.environ) == before
        got = ex.map(members.plan_member, tasks, world=world)
        fitted = _fitted_in(ex)
        rerouted = _replanned_in(ex, world, tasks)
    assert fingerprint(got) == in_process
    _same_fits(fitted, _fitted_in(cluster.InProcess()))
    assert fingerprint(rerouted) == fingerprint(_replanned_in(cluster.InProcess(), world, tasks))


def _replanned_in(ex, world, tasks):
    """Three members re-planned in ``ex``'s pool round a disc where another walks, as a
    crowd's resolution asks for them (all asked before the first answer is taken, every
    size's world sent once)."""
    plain = [members.plan_member(t, world) for t in tasks[:3]]
    ghosted = [  # a disc on the middle of its path as planned alone
        replace(t, ghosts=[crowd.disc(a.root_track[len(a.root_track) // 2, :2], 0.4)])
        for t, a in zip(tasks, plain)
    ]
    pool = ex.pool()
    try:
        worlds = pool.share(worlds={1.0: world})
        asked = [pool.submit(members.plan_sized, t, shared=worlds) for t in ghosted]
        got = [a.result() for a in asked]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    assert all(a[-1] != b[-1] for a, b in zip(fingerprint(got), fingerprint(plain)))
    return got


def _fitted_in(ex):
    """Cubic keys of three curves fitted in ``ex``'s pool (what a crowd's writing sends
    there, a few characters at a time), several asked for before the first answer is taken,
    the last with its tolerance shared (sent once, as a crowd's patch is)."""
    values = np.cumsum(np.random.default_rng(3).normal(size=(90, 3)), axis=0)
    pool = ex.pool()
    try:
        futures = [pool.submit(keys.cubic_keys, values * s, 0.05) for s in (1.0, 2.0)]
        futures.append(pool.submit(keys.cubic_keys, values * 3.0, shared=pool.share(tol=0.05)))
        return [f.result() for f in futures]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _same_fits(a, b):
    assert len(a) == len(b) == 3
    for x, y in zip(a, b):
        assert x.keys() == y.keys() and x["keep"].sum() > 2
        assert all(np.array_equal(x[k], y[k]) for k in x)


def _wait_for(path, timeout=60.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if path.exists() and path.stat().st_size > 0:
            return
        time.sleep(0.1)
    raise TimeoutError(f"{path} never appeared")


@contextlib.contextmanager
def _dask_processes(tmp_path, workers=2):
    """A `dask scheduler` and ``workers`` `dask worker` processes (no nanny: a killed worker
    stays dead) on localhost: (the processes, scheduler first; its address)."""
    sched_file = tmp_path / "scheduler.json"
    py = sys.executable
    procs = [
        subprocess.Popen(
            [
                py,
                "-m",
                "distributed.cli.dask_scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(sched_file),
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    ]
    try:
        _wait_for(sched_file)
        for _ in range(workers):
            procs.append(
                subprocess.Popen(
                    [
                        py,
                        "-m",
                        "distributed.cli.dask_worker",
                        "--scheduler-file",
                        str(sched_file),
                        "--nthreads",
                        "1",
                        "--no-nanny",
                        "--no-dashboard",
                    ],
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                )
            )
        address = json.loads(sched_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        yield procs, address
    finally:
        for p in procs:
            p.kill()
            p.wait(timeout=30)


def test_a_scheduler_over_tcp_with_a_worker_killed_mid_run_plans_the_same(
    crossing12, in_process, tmp_path
):
    """A `dask scheduler` and two `dask worker` processes on localhost; one worker is killed
    when the first task is done. Dask gives its tasks to the other; the plans are the
    same."""
    world, tasks = crossing12
    with _dask_processes(tmp_path) as (procs, address):
        with cluster.DaskCluster(scheduler=address) as ex:
            ex.client.wait_for_workers(2, timeout=60)
            killed = []

            def kill_one(fraction):
                if not killed:
                    procs[1].kill()
                    killed.append(fraction)

            got = ex.map(members.plan_member, tasks, world=world, chunk=1, progress=kill_one)
            assert killed and killed[0] < 1.0  # killed with tasks still to do
            assert procs[1].wait(timeout=30) != 0
            assert ex.workers == 1
    assert fingerprint(got) == in_process


def test_a_scheduler_lost_mid_run_is_reported_as_such(crossing12, tmp_path):
    """The scheduler killed when the first task is done: the rest of the map, and a task
    of the pool waiting for its answer, raise ClusterLost naming the scheduler (Dask
    cancels every task it held), not an error of Dask's own."""
    world, tasks = crossing12
    with _dask_processes(tmp_path) as (procs, address):
        with cluster.DaskCluster(scheduler=address) as ex:
            ex.client.wait_for_workers(2, timeout=60)
            pool = ex.pool()
            slow = pool.submit(time.sleep, 60)

            def kill_scheduler(fraction):
                procs[0].kill()

            with pytest.raises(cluster.ClusterLost, match=address):
                ex.map(members.plan_member, tasks, world=world, chunk=1, progress=kill_scheduler)
            with pytest.raises(cluster.ClusterLost, match="dropped the tasks"):
                slow.result()
