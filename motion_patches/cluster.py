# SPDX-License-Identifier: GPL-3.0-or-later
"""Where independent work runs: in this process, or on a Dask distributed cluster.

A crowd's paths, a batch of bakes or of layout checks are many tasks that share a patch and
a layout and do not depend on each other. :class:`InProcess` runs them one after the other;
:class:`DaskCluster` runs them on a Dask ``LocalCluster`` (one single-threaded worker process
per core by default) or on any running Dask scheduler (``scheduler="tcp://host:8786"``: a
SLURM or Kubernetes cluster started by dask-jobqueue or dask-kubernetes, say). Both keep the
order of the results, so what is planned does not depend on where.

Workers need no Blender, only numpy and this core: the core is sent to every worker as a
zip (``Client.upload_file``, which also reaches workers that join or are restarted later)
under the very module name it has here, so functions and results pickle by reference both
ways, whether the core is ``motion_patches`` (tests, benches) or the package of an installed
extension. Shared inputs (the patch, the props) are scattered to every worker once per call.
Dask retries a task whose worker was lost; the tasks are pure, so the result is the same.

Dask is an optional dependency: it is imported when a :class:`DaskCluster` is made, so a
Blender session that never asks for one does not need it.
"""

import os
import pickle
import tempfile
import threading
import uuid
import weakref
import zipfile
from collections.abc import Callable, Sequence
from concurrent.futures import CancelledError, ThreadPoolExecutor
from pathlib import Path
from typing import Any

CORE = Path(__file__).resolve().parent
CORE_NAME = __name__.rpartition(".")[0]  # the core's module name in this process


class ClusterLost(RuntimeError):
    """The cluster dropped the tasks it was given before answering (its scheduler stopped
    or cannot be reached: Dask cancels every task it held then). A lost worker is not
    this: Dask gives its tasks to the others."""


def _lost(address: str) -> ClusterLost:
    return ClusterLost(
        f"the Dask scheduler at {address} dropped the tasks before answering "
        "(it stopped or cannot be reached)"
    )


def chunks(n: int, parts: int) -> list[range]:
    """``range(n)`` cut into at most ``parts`` runs of near-equal length, in order."""
    parts = max(1, min(parts, n))
    edges = [round(k * n / parts) for k in range(parts + 1)]
    return [range(a, b) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def run_chunk(fn: Callable, items: Sequence, shared: dict, token: str | None = None) -> list:
    """``[fn(item, **shared) for item in items]``: one task's share of a map. With ``token``
    the shared inputs come pickled (:meth:`DaskCluster.map`) and are unpickled once per
    worker process and map."""
    if token is not None:
        shared = _unpacked(token, shared)
    return [fn(item, **shared) for item in items]


_UNPACKED: dict = {}  # {token: shared inputs} of the map this worker process runs now
_UNPACKING = threading.Lock()


def _unpacked(token: str, packed: dict) -> dict:
    """The shared inputs of map ``token`` in this process, unpickled on its first task (an
    earlier map's let go)."""
    with _UNPACKING:
        got = _UNPACKED.get(token)
        if got is None:
            _UNPACKED.clear()
            got = _UNPACKED[token] = {k: pickle.loads(v) for k, v in packed.items()}
        return got


class _ThreadPool(ThreadPoolExecutor):
    """:class:`InProcess`'s pool: one thread, running tasks in the order they come (a
    ``priority`` is not needed there); inputs shared by its tasks (:meth:`share`) are
    passed to each as they are."""

    def share(self, **shared: Any) -> dict:
        return shared

    def submit(  # type: ignore[override]
        self,
        fn: Callable,
        /,
        *args: Any,
        shared: dict | None = None,
        priority: int = 0,
        aside: bool = False,
    ) -> Any:
        return super().submit(fn, *args, **(shared or {}))

    @staticmethod
    def done(answer: Any) -> bool:
        return bool(answer.done())


class InProcess:
    """Runs every task here, in order: the default, and what Blender's window uses."""

    workers = 0
    address = "in-process"

    def map(
        self,
        fn: Callable,
        items: Sequence,
        progress: Callable[[float], None] | None = None,
        chunk: int | None = None,
        **shared: Any,
    ) -> list:
        """``[fn(item, **shared) for item in items]``; ``progress(fraction done)`` after each."""
        out = []
        for item in items:
            out.append(fn(item, **shared))
            if progress is not None:
                progress(len(out) / len(items))
        return out

    def pool(self) -> "_ThreadPool":
        """Tasks submitted one at a time (``submit(fn, *args)``, a future's ``result()``) and
        run beside the caller: here in one thread (numpy work holds the GIL often: more
        threads slowed a crowd's writing, which needs it too). ``shutdown()`` when done."""
        return _ThreadPool(max_workers=1)

    def close(self) -> None:
        pass

    def __enter__(self) -> "InProcess":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def core_zip(folder: str | Path) -> Path:
    """A zip of the core under its module name here (``a.b.motion_patches`` becomes
    ``a/b/motion_patches/...`` with empty ``__init__.py`` files for ``a`` and ``a.b``, so the
    add-on's own ``__init__``, which needs Blender, is never run on a worker)."""
    parts = CORE_NAME.split(".")
    path = Path(folder) / f"core_{uuid.uuid4().hex[:8]}.zip"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for k in range(1, len(parts)):
            z.writestr("/".join(parts[:k]) + "/__init__.py", "")
        base = "/".join(parts)
        for f in sorted(CORE.rglob("*.py")):
            z.write(f, base + "/" + f.relative_to(CORE).as_posix())
    return path


def _restore_environ(kept: dict) -> None:
    """Put back the variables a LocalCluster's nannies set in this process to spawn their
    workers (OMP_NUM_THREADS=1, OPENBLAS_NUM_THREADS=1, PYTHONHASHSEED, ...): every process
    Blender or the command line starts later inherited them, numpy's BLAS there running on
    one thread. The nannies set them again when they start a worker anew."""
    for k in set(os.environ) - set(kept):
        del os.environ[k]
    for k, v in kept.items():
        if os.environ.get(k) != v:
            os.environ[k] = v


class DaskCluster:
    """Runs tasks on Dask distributed: a new ``LocalCluster`` of ``workers`` processes
    (default: one per core), or the running scheduler at ``scheduler``."""

    def __init__(self, workers: int | None = None, scheduler: str | None = None) -> None:
        from distributed import Client, LocalCluster  # optional: only when a cluster is asked for

        if workers is not None and workers < 1:
            raise ValueError(f"workers must be at least 1, not {workers}")
        self.cluster = None
        if scheduler:
            self.client = Client(scheduler, timeout="30s")
        else:
            import dask

            # Dask's nannies set MALLOC_TRIM_THRESHOLD_ to hand memory back early; a fixed
            # threshold also stops glibc from raising its mmap threshold, so every numpy
            # temporary over 64 KB is mapped and unmapped again: planning ran ~30 % slower.
            environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
            environ.pop("MALLOC_TRIM_THRESHOLD_", None)
            kept = dict(os.environ)
            try:
                with dask.config.set({"distributed.nanny.pre-spawn-environ": environ}):
                    self.cluster = LocalCluster(
                        n_workers=workers or os.cpu_count() or 1,
                        threads_per_worker=1,  # numpy holds the GIL often: a process per core
                        processes=True,
                        dashboard_address=None,
                    )
            finally:
                _restore_environ(kept)
            self.client = Client(self.cluster)
        self.address = self.client.scheduler.address
        self._tmp = tempfile.TemporaryDirectory(prefix="motion-patches-core-")
        self.client.upload_file(str(core_zip(self._tmp.name)))

    @property
    def workers(self) -> int:
        return len(self.client.scheduler_info().get("workers", {}))

    def map(
        self,
        fn: Callable,
        items: Sequence,
        progress: Callable[[float], None] | None = None,
        chunk: int | None = None,
        **shared: Any,
    ) -> list:
        """``[fn(item, **shared) for item in items]`` on the workers, in the items' order;
        ``progress(fraction done)`` as tasks finish. ``chunk``: items per task (default:
        about four tasks per worker)."""
        items = list(items)
        if not items:
            return []
        scattered = _scattered(self.client, shared)
        parts = (
            chunks(len(items), 4 * max(self.workers, 1))
            if chunk is None
            else [range(a, min(a + chunk, len(items))) for a in range(0, len(items), chunk)]
        )
        tag = uuid.uuid4().hex[:8]
        # Dealt round the workers: left to itself the scheduler put the tasks where the
        # shared inputs were first scattered and ran a 1,000-member crowd on one worker.
        # A task may still move when its worker is lost (allow_other_workers).
        addresses = sorted(self.client.scheduler_info().get("workers", {})) or [None]
        futures = [
            self.client.submit(
                run_chunk,
                fn,
                [items[i] for i in r],
                scattered,
                tag,
                key=f"{getattr(fn, '__name__', 'task')}-{tag}-{k}",
                pure=False,
                workers=None if addresses[0] is None else [addresses[k % len(addresses)]],
                allow_other_workers=True,
            )
            for k, r in enumerate(parts)
        ]
        from distributed import as_completed

        # Each part is taken as it is done and its future let go, so the workers drop
        # their copy then: a 10,000-member crowd is not held twice over until the end.
        at = {f.key: k for k, f in enumerate(futures)}
        got: list = [None] * len(futures)
        done = 0
        try:
            for future, part in as_completed(futures, with_results=True):
                if future.cancelled():  # handed on as its answer, not raised
                    raise CancelledError
                got[at[future.key]] = part
                future.release()
                done += 1
                if progress is not None:
                    progress(done / len(futures))
        except CancelledError:
            raise _lost(self.address) from None
        del futures
        out: list = []
        for part in got:
            out.extend(part)
        return out

    def pool(self) -> "_DaskPool":
        """Tasks submitted one at a time (``submit(fn, *args)``, a future's ``result()``),
        run on the workers while the caller goes on: a crowd's keys are fitted there while
        Blender writes the characters before. ``shutdown()`` when done."""
        return _DaskPool(self.client, self.address, own=self.cluster is not None)

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        self._tmp.cleanup()

    def __enter__(self) -> "DaskCluster":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _scattered(client: Any, shared: dict) -> dict:
    """``shared`` scattered to every worker as pickled bytes, each worker unpickling its
    own copy (:func:`_unpacked`). A broadcast is copied on from worker to worker while tasks
    already run, and a task filling a cache in the world (a gait's loops, say) while it was
    pickled again for the next worker broke the copy ("dictionary changed size during
    iteration", 10,000 members)."""
    packed = {k: pickle.dumps(v, protocol=pickle.HIGHEST_PROTOCOL) for k, v in shared.items()}
    return {k: client.scatter(v, broadcast=True) for k, v in packed.items()}


def run_shared(fn: Callable, args: tuple, shared: dict, token: str) -> Any:
    """``fn(*args, **shared)`` on a worker, the shared inputs unpickled once per worker
    process (:meth:`_DaskPool.share`)."""
    return fn(*args, **_unpacked(token, shared))


class _DaskPool:
    """Tasks submitted one by one to a Dask client (:meth:`DaskCluster.pool`). Their futures
    are only looked after weakly (a result stays on its worker while a future holds it):
    those the caller still holds unfinished are cancelled at :meth:`shutdown`."""

    def __init__(self, client: Any, address: str = "", own: bool = False) -> None:
        self.client, self.address, self.own = client, address, own
        self.futures: weakref.WeakSet = weakref.WeakSet()

    def share(self, **shared: Any) -> tuple:
        """Inputs many tasks read (a crowd's patch), sent to every worker once: pass what
        this returns as :meth:`submit`'s ``shared``."""
        return _scattered(self.client, shared), uuid.uuid4().hex[:8]

    def submit(
        self,
        fn: Callable,
        *args: Any,
        shared: tuple | None = None,
        priority: int = 0,
        aside: bool = False,
    ) -> Any:
        """``fn(*args)``, or ``fn(*args, **inputs)`` with ``shared`` from :meth:`share`.
        A task of higher ``priority`` is run before those of lower still waiting. ``aside``:
        work nobody waits for yet, put on one worker (the last) of a cluster of this
        machine's, so the others take at once what is waited for (a task running is not
        stopped for a higher priority); another worker may still take it over (Dask's
        work stealing, or the worker lost). On a cluster at a scheduler's address the
        workers may be many and are not ours to order: the task goes anywhere."""
        where: dict = {}
        if aside and self.own:
            workers = sorted(self.client.scheduler_info().get("workers", {}))
            if len(workers) > 1:
                where = {"workers": workers[-1:], "allow_other_workers": True}
        if shared is None:
            f = self.client.submit(fn, *args, pure=False, priority=priority, **where)
        else:
            f = self.client.submit(
                run_shared, fn, args, *shared, pure=False, priority=priority, **where
            )
        self.futures.add(f)
        return _Answer(f, self.address)

    @staticmethod
    def done(answer: "_Answer") -> bool:
        """Whether ``answer``'s task has finished."""
        return bool(answer.future.done())

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        if cancel_futures:
            pending = [f for f in self.futures if not f.done()]
            if pending:
                self.client.cancel(pending)
        self.futures = weakref.WeakSet()


class _Answer:
    """A task's Dask future whose :meth:`result` raises :class:`ClusterLost` when the
    cluster dropped it."""

    def __init__(self, future: Any, address: str) -> None:
        self.future, self.address = future, address

    def result(self) -> Any:
        try:
            return self.future.result()
        except CancelledError:
            raise _lost(self.address) from None


def executor(workers: int | None = None, scheduler: str | None = None) -> "InProcess | DaskCluster":
    """In process unless ``workers`` or ``scheduler`` is given."""
    if workers is None and not scheduler:
        return InProcess()
    return DaskCluster(workers, scheduler)
