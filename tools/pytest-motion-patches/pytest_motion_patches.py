# SPDX-License-Identifier: GPL-3.0-or-later
"""pytest plugin: every layout spec beside a .blend file is collected as tests, one per pair.

``sets/lobby.blend`` with ``sets/lobby.layout.toml`` (or ``.layout.json``) beside it gives the
tests ``sets/lobby.layout.toml::<pair name>``. Each spec file is checked once, by Blender's
command line (``blender -b -c motion_patches check FILE.blend --spec SPEC --json``: Blender
with the extension enabled, the pytest process needs no bpy), and each pair's test passes
when its pair passed its limits; a failing pair reports the broken limits, the blocking props
and the figures. A spec Blender could not check (a name that is not in the file, a .blend that
does not open) fails every test of that file with Blender's one-line reason.

Options: ``--motion-patches-blender CMD`` (ini ``motion_patches_blender``; default
``blender``): the command that starts Blender, split like a shell would (``"flatpak run
org.blender.Blender"``); ``--motion-patches-no-layout`` turns collection off.
"""

import json
import shlex
import subprocess
from pathlib import Path

import pytest

SUFFIXES = (".layout.toml", ".layout.json")


def pytest_addoption(parser):
    group = parser.getgroup("motion_patches", "layout checks of Dynamic Motion Patches")
    group.addoption(
        "--motion-patches-blender",
        dest="motion_patches_blender",
        metavar="CMD",
        help="command that starts Blender with the extension enabled (default: blender)",
    )
    group.addoption(
        "--motion-patches-no-layout",
        action="store_true",
        dest="motion_patches_no_layout",
        help="do not collect layout specs beside .blend files",
    )
    parser.addini(
        "motion_patches_blender", "command that starts Blender (default: blender)", default=""
    )


def blend_of(path):
    """The .blend a layout spec belongs to (``lobby.layout.toml`` -> ``lobby.blend``), or None."""
    name = path.name
    for suffix in SUFFIXES:
        if name.endswith(suffix):
            blend = path.with_name(name[: -len(suffix)] + ".blend")
            return blend if blend.is_file() else None
    return None


def pytest_collect_file(file_path, parent):
    if parent.config.getoption("motion_patches_no_layout"):
        return None
    if blend_of(Path(file_path)) is not None:
        return LayoutFile.from_parent(parent, path=file_path)
    return None


def blender_command(config):
    cmd = config.getoption("motion_patches_blender") or config.getini("motion_patches_blender")
    return shlex.split(cmd or "blender")


class LayoutFile(pytest.File):
    """A layout spec beside its .blend: its pairs, each a test."""

    def collect(self):
        spec = Path(self.path)
        if spec.suffix == ".json":
            doc = json.loads(spec.read_text(encoding="utf-8"))
        else:
            import tomllib

            doc = tomllib.loads(spec.read_text(encoding="utf-8"))
        pairs = doc.get("pairs") if isinstance(doc, dict) else None
        if not isinstance(pairs, list) or not pairs:
            yield LayoutItem.from_parent(self, name="pairs", index=None)
            return
        for k, pair in enumerate(pairs):
            yield LayoutItem.from_parent(self, name=_pair_name(pair, k), index=k)

    def checked(self):
        """The JSON document of ``check`` on this spec and its .blend (run once)."""
        if not hasattr(self, "_doc"):
            spec = Path(self.path)
            argv = [*blender_command(self.config), "-b", "-c", "motion_patches", "check"]
            argv += [str(blend_of(spec)), "--spec", str(spec), "--json"]
            try:
                run = subprocess.run(argv, capture_output=True, text=True)
            except OSError as exc:
                self._doc = {"error": f"cannot start Blender ({argv[0]}): {exc}"}
                return self._doc
            try:
                self._doc = json.loads(run.stdout)
            except ValueError:
                tail = (run.stderr or run.stdout).strip().splitlines()[-1:] or ["no output"]
                self._doc = {"error": f"exit {run.returncode}: {tail[0]}"}
        return self._doc


def _pair_name(pair, k):
    """The name ``check`` gives the pair (its "name", else "start -> goal"), for the test id."""
    if isinstance(pair, dict) and isinstance(pair.get("name"), str):
        return pair["name"]
    if isinstance(pair, dict):
        start = pair.get("character") or pair.get("start")
        goal = pair.get("goal")

        def label(p):
            if isinstance(p, list) and len(p) == 3:
                return f"({p[0]:g}, {p[1]:g}, {p[2]:g} deg)"
            return str(p)

        return f"{label(start)} -> {label(goal)}"
    return f"pair {k + 1}"


class LayoutFailure(Exception):
    """A pair that failed its limits, or a spec that could not be checked."""


class LayoutItem(pytest.Item):
    def __init__(self, *, index, **kw):
        super().__init__(**kw)
        self.index = index

    def runtest(self):
        doc = self.parent.checked()
        if doc.get("error"):
            raise LayoutFailure(f"layout spec not checked: {doc['error']}")
        pairs = doc.get("pairs") or []
        if self.index is None or self.index >= len(pairs):
            raise LayoutFailure(f"no result for pair {self.name!r}")
        r = pairs[self.index]
        self.user_properties.append(("plan_seconds", r.get("plan_seconds")))
        if not r["passed"]:
            raise LayoutFailure(_report(r))

    def repr_failure(self, excinfo):
        if isinstance(excinfo.value, LayoutFailure):
            return str(excinfo.value)
        return super().repr_failure(excinfo)

    def reportinfo(self):
        return self.path, None, f"layout pair: {self.name}"


def _report(r):
    lines = list(r["failures"])
    if r.get("blocked_by"):
        lines.append(f"blocking props ({r['blocked_reason']}): {', '.join(r['blocked_by'])}")
    if r["reachable"]:
        lines.append(
            f"reachable: {r['length_m']:.2f} m, {r['seconds']:.2f} s of motion, "
            f"cost {r['cost']:.3f}"
        )
    return "\n".join(lines)
