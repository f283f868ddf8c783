# SPDX-License-Identifier: GPL-3.0-or-later
"""No shipped module grows past what a newcomer can read in one go: 800 lines (the tests,
benchmarks, tools and examples aside, which do not ship in the extension)."""

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
NOT_SHIPPED = {"tests", "bench", "tools", "examples", "docs", "dist", ".venv", ".git"}
LIMIT = 800


def shipped_modules():
    for path in sorted(REPO.rglob("*.py")):
        rel = path.relative_to(REPO)
        if rel.parts[0] not in NOT_SHIPPED and not any(p.startswith(".") for p in rel.parts):
            yield rel, path


def test_no_shipped_module_is_over_800_lines():
    modules = list(shipped_modules())
    assert len(modules) > 60, "the walk finds the extension's modules"
    long = {str(rel): n for rel, p in modules if (n := len(p.read_text().splitlines())) > LIMIT}
    assert not long, f"modules over {LIMIT} lines: {long}"
