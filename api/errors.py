# SPDX-License-Identifier: GPL-3.0-or-later
"""The one kind of failure the API raises: a message meant for the user."""

from __future__ import annotations


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
