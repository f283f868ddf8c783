# SPDX-License-Identifier: GPL-3.0-or-later
"""Every public function and method (name without a leading underscore) of the hinted parts of
the core has hints on all its parameters and its return: mypy (./dev lint) checks the calls
against them. Widen HINTED as more of the core and the API is hinted."""

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
# Files, or directories whose every .py file is hinted.
HINTED = [
    "api",
    "motion_patches/cluster.py",
    "motion_patches/planning",
    "motion_patches/kinematics",
    "motion_patches/quality",
    "motion_patches/patch",
    "motion_patches/props",
    "motion_patches/crowd",
]


def unhinted(tree):
    """(line, qualified name, what lacks a hint) of the public functions and methods of a
    module (a method's self or cls needs none)."""
    found = []

    def walk(body, prefix, in_class):
        for node in body:
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                walk(node.body, f"{prefix}{node.name}.", True)
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                if node.name.startswith("_"):
                    continue
                a = node.args
                params = a.posonlyargs + a.args
                static = any(
                    isinstance(d, ast.Name) and d.id == "staticmethod" for d in node.decorator_list
                )
                if in_class and not static and params:
                    params = params[1:]
                params = params + a.kwonlyargs + [v for v in (a.vararg, a.kwarg) if v]
                missing = [p.arg for p in params if p.annotation is None]
                if node.returns is None:
                    missing.append("return")
                if missing:
                    found.append((node.lineno, prefix + node.name, missing))

    walk(tree.body, "", False)
    return found


def hinted_files():
    for entry in HINTED:
        path = REPO / entry
        yield from sorted(path.rglob("*.py")) if path.is_dir() else [path]


def test_public_functions_are_hinted():
    files = list(hinted_files())
    assert len(files) > 30, HINTED  # the list names what exists
    missing = [
        f"{path.relative_to(REPO)}:{line}: {name} ({', '.join(what)})"
        for path in files
        for line, name, what in unhinted(ast.parse(path.read_text(encoding="utf-8")))
    ]
    assert not missing, "public functions without hints:\n" + "\n".join(missing)


def test_unhinted_is_found():
    source = """
def f(a: int, b) -> int: ...
def g(a: int): ...
def _private(a): ...
class C:
    def m(self, x: float) -> None: ...
    def n(self, *args, **kw: int) -> None: ...
    @staticmethod
    def s(x) -> None: ...
    def _p(self, x): ...
class _Hidden:
    def m(self, x): ...
"""
    assert [(name, what) for _, name, what in unhinted(ast.parse(source))] == [
        ("f", ["b"]),
        ("g", ["return"]),
        ("C.n", ["args"]),
        ("C.s", ["x"]),
    ]
