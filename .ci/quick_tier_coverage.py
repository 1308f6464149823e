"""Check that the quick test tier exercises every module of the package.

Run after the quick tier ran under coverage (as ``.ci/run`` does)::

    coverage run -m pytest   # the quick tier; [tool.coverage.run] in pyproject.toml
    coverage combine -q
    python .ci/quick_tier_coverage.py

A module counts as exercised when a line inside one of its functions ran: importing a module
runs its ``def`` and ``class`` lines, so "some line ran" would only prove an import. A module
without functions (constants, re-exports) counts when it was imported. Prints what the tier
misses and exits 1 if anything is.
"""

from __future__ import annotations

import ast
import importlib.util
import pkgutil
import sys
from pathlib import Path

from coverage import Coverage

#: core/ and plugins/ (as preform.plugins), with the code of the data packages
#: (``preform.materials``, ``preform.validation_suite``) that lives under the same name.
PACKAGES = ("preform",)


def module_files() -> dict[str, Path]:
    """Every module of the installed package, by dotted name."""
    found: dict[str, Path] = {}
    for top in PACKAGES:
        spec = importlib.util.find_spec(top)
        assert spec is not None and spec.submodule_search_locations, top
        found[top] = Path(spec.origin or "")
        for info in pkgutil.walk_packages(spec.submodule_search_locations, prefix=f"{top}."):
            sub = importlib.util.find_spec(info.name)
            if sub is not None and sub.origin and sub.origin.endswith(".py"):
                found[info.name] = Path(sub.origin)
    return found


def function_body_lines(source: str) -> set[int]:
    """Line numbers of the statements inside every function (the lines a call runs)."""
    lines: set[int] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            for statement in node.body:
                for inner in ast.walk(statement):
                    if isinstance(inner, ast.stmt):
                        lines.add(inner.lineno)
    return lines


def main() -> int:
    data = Coverage().get_data()
    data.read()
    measured = {Path(f).resolve(): set(data.lines(f) or ()) for f in data.measured_files()}
    missing: list[str] = []
    modules = module_files()
    for name, path in sorted(modules.items()):
        ran = measured.get(path.resolve())
        body = function_body_lines(path.read_text(encoding="utf-8"))
        if ran is None:
            missing.append(f"{name}: never imported")
        elif body and not ran & body:
            missing.append(f"{name}: imported, but none of its functions ran")
    print(f"quick tier: {len(modules) - len(missing)} of {len(modules)} modules exercised")
    for line in missing:
        print(f"  {line}")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
