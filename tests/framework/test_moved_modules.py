"""``preform._moved.MOVED_MODULES``: every moved module's new path is a real module, and
nothing of ours imports an old one (issue 31: old paths are for users' code only)."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

from preform._moved import MOVED_MODULES

ROOT = Path(__file__).resolve().parents[2]
#: Tests of the old paths themselves, which import them on purpose.
ALIAS_TESTS = {ROOT / "tests" / "framework" / "test_import_cycles.py"}


@pytest.mark.parametrize(("old", "new"), sorted(MOVED_MODULES.items()))
def test_each_new_path_is_a_module_of_its_own(old, new):
    module = importlib.import_module(new)
    assert module.__name__ == new != old
    assert Path(module.__file__).stem == new.rsplit(".", 1)[1]


def _imported(tree: ast.AST) -> set[str]:
    """Every module an import statement names, ``from a import b`` as both a and a.b."""
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def test_no_source_of_ours_imports_an_old_path():
    offenders = []
    for folder in ("core", "plugins", "tests", "benchmarks", "validation"):
        for path in sorted(set((ROOT / folder).rglob("*.py")) - ALIAS_TESTS):
            old = _imported(ast.parse(path.read_text(), str(path))) & MOVED_MODULES.keys()
            offenders += [f"{path.relative_to(ROOT)}: {name}" for name in sorted(old)]
    assert not offenders, "imports of moved modules' old paths:\n" + "\n".join(offenders)
