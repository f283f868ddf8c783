# SPDX-License-Identifier: GPL-3.0-or-later
"""Layout specs: the start/goal pairs and limits a layout check plans (JSON or TOML, as a
studio writes them), validated before anything is planned, and the verdict of one pair
against its limits. Plain Python, so a spec can be checked without Blender."""

import math
from typing import Any


class SpecError(ValueError):
    """A spec that cannot be checked; the message names the key and the pair."""


TOP_KEYS = {
    "patch",
    "alpha",
    "beta",
    "gamma",
    "radius",
    "margin_tiles",
    "limits",
    "exclude",
    "pairs",
}
LIMIT_KEYS = {"must_reach", "max_seconds", "max_length", "max_cost", "allow_traversal"}
PAIR_KEYS = {"name", "character", "start", "goal", "goal_facing", "exclude"} | LIMIT_KEYS
LIMIT_DEFAULTS = {
    "must_reach": True,
    "max_seconds": None,
    "max_length": None,
    "max_cost": None,
    "allow_traversal": True,
}


def _spec_error(msg):
    return SpecError(f"layout spec: {msg}")


def _limits(d, where, base):
    out = dict(base)
    for k in LIMIT_KEYS & set(d):
        v = d[k]
        if k in ("must_reach", "allow_traversal"):
            if not isinstance(v, bool):
                raise _spec_error(f"{where}: {k} must be true or false")
        elif v is not None:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 <= v < math.inf:
                raise _spec_error(f"{where}: {k} must be a number >= 0")
            v = float(v)
        out[k] = v
    return out


def _place(value, where):
    if isinstance(value, str) and value:
        return value
    if (
        isinstance(value, (list, tuple))
        and len(value) == 3
        and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in value
        )
    ):
        return [float(v) for v in value]
    raise _spec_error(f"{where} must be an object name or [x, y, heading_deg]")


def normalise(spec: dict[str, Any]) -> dict[str, Any]:
    """A validated copy of a layout spec (keys as ``cli.SPEC_HELP`` lists); SpecError if bad."""
    if not isinstance(spec, dict):
        raise _spec_error("the top level must be a table / object")
    unknown = set(spec) - TOP_KEYS
    if unknown:
        raise _spec_error(
            f"unknown key(s) {', '.join(sorted(unknown))} (known: {', '.join(sorted(TOP_KEYS))})"
        )
    out: dict[str, Any] = {"patch": spec.get("patch")}
    if out["patch"] is not None and not isinstance(out["patch"], str):
        raise _spec_error("patch must be a name")
    for k in ("alpha", "beta", "gamma", "radius", "margin_tiles"):
        v = spec.get(k)
        if v is not None and (
            isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 <= v < math.inf
        ):
            raise _spec_error(f"{k} must be a number >= 0")
        out[k] = v
    limits = spec.get("limits", {})
    if not isinstance(limits, dict) or set(limits) - LIMIT_KEYS:
        raise _spec_error(f"limits must be a table of {', '.join(sorted(LIMIT_KEYS))}")
    base = _limits(limits, "limits", LIMIT_DEFAULTS)
    out["exclude"] = _names_list(spec.get("exclude"), "top level")
    pairs = spec.get("pairs")
    if not isinstance(pairs, list) or not pairs:
        raise _spec_error("'pairs' must be a non-empty list of start/goal pairs")
    out["pairs"] = []
    for n, p in enumerate(pairs):
        where = f"pair {n + 1}"
        if not isinstance(p, dict):
            raise _spec_error(f"{where} must be a table / object")
        unknown = set(p) - PAIR_KEYS
        if unknown:
            raise _spec_error(
                f"{where}: unknown key(s) {', '.join(sorted(unknown))} (known: "
                f"{', '.join(sorted(PAIR_KEYS))})"
            )
        if ("character" in p) == ("start" in p):
            raise _spec_error(f"{where}: give either 'character' or 'start'")
        if "goal" not in p:
            raise _spec_error(f"{where}: 'goal' is missing")
        start = p["character"] if "character" in p else p["start"]
        start = _place(start, f"{where}: {'character' if 'character' in p else 'start'}")
        if "character" in p and not isinstance(start, str):
            raise _spec_error(f"{where}: 'character' must be an armature's name")
        goal = _place(p["goal"], f"{where}: goal")
        name = p.get("name") or f"{_label(start)} -> {_label(goal)}"
        facing = p.get("goal_facing", "exact")
        if facing not in ("exact", "any"):
            raise _spec_error(f'{where}: goal_facing must be "exact" or "any"')
        out["pairs"].append(
            {
                "name": str(name),
                "start": start,
                "goal": goal,
                "character": "character" in p,
                "goal_facing": facing,
                "exclude": _names_list(p.get("exclude"), where),
                "limits": _limits(p, where, base),
            }
        )
    return out


def _names_list(value, where):
    if value is None:
        return []
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        raise _spec_error(f"{where}: exclude must be a list of object names")
    return list(value)


def _label(place):
    if isinstance(place, str):
        return place
    return f"({place[0]:g}, {place[1]:g}, {place[2]:g} deg)"


def judge(r: dict[str, Any], lim: dict[str, Any]) -> list[str]:
    """The limits a planned pair ``r`` breaks, as sentences (none: it passed)."""
    if not r["reachable"]:
        if not lim["must_reach"]:
            return []
        why = f"unreachable ({r['error']})"
        if r["blocked_by"]:
            why = (
                f"unreachable: blocked by {', '.join(r['blocked_by'][:6])}"
                + (", ..." if len(r["blocked_by"]) > 6 else "")
                + f" ({r['blocked_reason']})"
            )
        return [why]
    out = []
    for key, value, unit in (
        ("max_seconds", r["seconds"], " s of motion"),
        ("max_length", r["length_m"], " m"),
        ("max_cost", r["cost"], ""),
    ):
        if lim[key] is not None and value > lim[key]:
            out.append(f"{value:.2f}{unit} exceeds {key} {lim[key]:g}")
    if not lim["allow_traversal"] and r["traversals"]:
        out.append(f"{r['traversals']} traversal(s) but allow_traversal is false")
    return out
