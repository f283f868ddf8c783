# SPDX-License-Identifier: GPL-3.0-or-later
"""The one kind of failure the API raises: a message meant for the user."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

from ..motion_patches import cluster


class MotionPatchesError(ValueError):
    """A request the add-on cannot carry out; the message says why and what to do."""


class PathNotFound(MotionPatchesError):
    """The request was fine but no path was found; the message ends with the cause, also
    given as ``cause``: "props" (named in ``props``), "patch" (its walks turn too wide or
    connect too sparsely for this start and goal, even on open ground), "search limit" or
    "moving" (props keyframed across the path, named in ``props``)."""

    def __init__(self, message, cause=None, props=()):
        super().__init__(message)
        self.cause, self.props = cause, list(props)


class Cancelled(MotionPatchesError):
    """The user stopped long work (Esc in Blender, Ctrl-C in the CLI) before it was done;
    what it had begun to write was put back, so the scene is as it was."""

    def __init__(self, what: str = "the work") -> None:
        super().__init__(f"{what} was cancelled; the scene was left as it was")


def check_cancelled(cancelled: Callable[[], bool] | None, what: str = "the work") -> None:
    """Raise :class:`Cancelled` when ``cancelled`` (the caller's ``() -> bool``, or None:
    never) says the user asked to stop."""
    if cancelled is not None and cancelled():
        raise Cancelled(what)


class ClusterLost(MotionPatchesError):
    """The Dask cluster planning or fitting for the request dropped its tasks (its
    scheduler stopped or cannot be reached); nothing was written."""


@contextlib.contextmanager
def cluster_kept() -> Iterator[None]:
    """Work on a cluster whose loss is reported as :class:`ClusterLost`, with what to do."""
    try:
        yield
    except cluster.ClusterLost as exc:
        raise ClusterLost(
            f"{exc}: nothing was written and the scene is as it was; run again once the "
            "scheduler is back, or on this machine (without --scheduler / --workers)"
        ) from None
