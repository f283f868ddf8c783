# SPDX-License-Identifier: GPL-3.0-or-later
"""The core's import graph, read from its source: no cycle, no import inside a function (the
way to dodge a cycle), and each module imports only its own layer or lower ones. The same
rules are import-linter contracts (pyproject.toml, ./dev lint); this test keeps them in the
core suite, which needs no linter venv, and also sees the cycles import-linter allows."""

import ast
from pathlib import Path

import pytest

CORE = Path(__file__).resolve().parents[2] / "motion_patches"
# Top to bottom: a module may import its own layer or a lower one.
LAYERS = ["cluster", "crowd", "planning", "props", "patch", "quality", "kinematics"]


def core_modules(root):
    """Dotted name (``motion_patches.patch.gait``) -> source file, for every module under
    ``root`` (a package's name is that of its ``__init__.py``)."""
    modules = {}
    for path in sorted(root.rglob("*.py")):
        parts = [root.name, *path.relative_to(root).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts.pop()
        modules[".".join(parts)] = path
    return modules


def _resolve(node, modules, module, is_package):
    """The modules of ``modules`` an import statement ``node`` in ``module`` reaches (the
    packages above them run too, but only their docstring-only ``__init__``)."""
    if isinstance(node, ast.Import):
        return {alias.name for alias in node.names} & modules.keys()
    if node.level:
        package = module.split(".") if is_package else module.split(".")[:-1]
        base = package[: len(package) - (node.level - 1)]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module
    # `from pkg import name` runs pkg.name when that is a module, else pkg.
    submodules = {f"{target}.{alias.name}" for alias in node.names} & modules.keys()
    return submodules or {target} & modules.keys()


def _of_core(node, core):
    """True if an import statement names a core module: relative, or under ``core``."""
    if isinstance(node, ast.ImportFrom):
        return bool(node.level) or node.module.split(".")[0] == core
    return any(alias.name.split(".")[0] == core for alias in node.names)


def import_graph(root):
    """(edges, nested): module -> the core modules it imports, and the imports of the core
    written inside a function, as (module, line, statement). (A function may import the
    standard library: dataclasses.replace is imported where it is used.)"""
    modules = core_modules(root)
    edges = {m: set() for m in modules}
    nested = []

    def visit(node, module, is_package, in_function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                if in_function and _of_core(child, root.name):
                    nested.append((module, child.lineno, ast.unparse(child)))
                edges[module] |= _resolve(child, modules, module, is_package) - {module}
            visit(
                child,
                module,
                is_package,
                in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)),
            )

    for module, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        visit(tree, module, path.name == "__init__.py", False)
    # A package's __init__ runs before its modules: an edge to a package is one to its
    # __init__, never a cycle through the modules it holds.
    return edges, nested


def find_cycle(edges):
    """One import cycle as [a, b, ..., a], or None."""
    state = {}  # module -> 1 on the current path, 2 done
    path = []

    def dfs(m):
        state[m] = 1
        path.append(m)
        for n in sorted(edges.get(m, ())):
            if state.get(n) == 1:
                return path[path.index(n) :] + [n]
            if n not in state:
                cycle = dfs(n)
                if cycle:
                    return cycle
        path.pop()
        state[m] = 2
        return None

    for m in sorted(edges):
        if m not in state:
            cycle = dfs(m)
            if cycle:
                return cycle
    return None


def layer(module):
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def upward_imports(edges):
    """The imports of a higher layer, as "a -> b"."""
    return sorted(
        f"{a} -> {b}"
        for a, targets in edges.items()
        for b in targets
        if layer(a) and layer(b) and LAYERS.index(layer(b)) < LAYERS.index(layer(a))
    )


@pytest.fixture(scope="module")
def graph():
    return import_graph(CORE)


def test_graph_is_read(graph):
    """The reader resolves relative imports of both forms (a failure here means the other
    tests see no edges, not that the core is clean)."""
    edges, _ = graph
    assert "motion_patches.kinematics.quat" in edges["motion_patches.kinematics.skeleton"]
    assert "motion_patches.patch.curves" in edges["motion_patches.planning.connectors"]
    assert "motion_patches.kinematics.retime" in edges["motion_patches.crowd.crowd"]
    assert sum(map(len, edges.values())) > 100


def test_no_cycle(graph):
    edges, _ = graph
    cycle = find_cycle(edges)
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_no_import_inside_a_function(graph):
    _, nested = graph
    assert not nested, "imports inside a function: " + "; ".join(
        f"{m} l.{line}: {stmt}" for m, line, stmt in nested
    )


def test_layers(graph):
    edges, _ = graph
    unknown = sorted(m for m in edges if layer(m) and layer(m) not in LAYERS)
    assert not unknown, f"modules outside the layers {LAYERS}: {unknown}"
    upward = upward_imports(edges)
    assert not upward, "imports of a higher layer: " + "; ".join(upward)


def test_checks_fail_on_a_bad_core(tmp_path):
    """The same reader on a small core with a cycle, a nested import and an upward import."""
    root = tmp_path / "motion_patches"
    for pkg in ("kinematics", "patch"):
        (root / pkg).mkdir(parents=True)
        (root / pkg / "__init__.py").write_text("")
    (root / "__init__.py").write_text("")
    (root / "kinematics" / "a.py").write_text("from . import b\n")
    (root / "kinematics" / "b.py").write_text("from .c import f\n")
    (root / "kinematics" / "c.py").write_text("def f():\n    import json\n    from .a import g\n")
    (root / "kinematics" / "d.py").write_text("from ..patch.e import h\n")
    (root / "patch" / "e.py").write_text("import motion_patches.kinematics.d\n")
    edges, nested = import_graph(root)
    cycle = find_cycle(edges)
    assert cycle is not None and cycle[0] == cycle[-1]
    assert set(cycle) in (
        {
            "motion_patches.kinematics.a",
            "motion_patches.kinematics.b",
            "motion_patches.kinematics.c",
        },
        {"motion_patches.kinematics.d", "motion_patches.patch.e"},
    )
    assert nested == [("motion_patches.kinematics.c", 3, "from .a import g")]
    assert upward_imports(edges) == ["motion_patches.kinematics.d -> motion_patches.patch.e"]
    assert "motion_patches.kinematics.d" in edges["motion_patches.patch.e"]
    del edges["motion_patches.kinematics.c"]
    edges["motion_patches.patch.e"].clear()
    assert find_cycle(edges) is None
