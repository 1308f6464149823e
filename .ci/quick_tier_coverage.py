"""Check that the quick test tier exercises every module of the package.

Run after the quick tier ran under coverage (as ``.ci/run`` does)::

    coverage run -m pytest -n 0   # the quick tier; [tool.coverage.run] in pyproject.toml
    python .ci/quick_tier_coverage.py

Only the test process is measured: a module counts when a test reaches it in-process, not
through a worker or a command-line subprocess.

A module counts as exercised when a line inside one of its functions ran: importing a module
runs its ``def`` and ``class`` lines, so "some line ran" would only prove an import. Left out
of the count, because coverage cannot see them run: functions compiled by numba (the
``*_kernels`` modules; their tests compare them with a numpy path) and bodies with nothing to
run (a protocol's or hook specification's docstring, ``...``). A module left with no function
to count (constants, re-exports, kernels) counts when it was imported; the report says how
many did. ``SUBPROCESS_ONLY`` lists what only a command-line subprocess runs. Prints what the
tier misses and exits 1 if anything is.
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


#: Modules only a subprocess runs (the test process is measured, not its subprocesses), with
#: the tests that run them.
SUBPROCESS_ONLY = {
    "preform.__main__": "its main() in a subprocess in tests/framework/test_collector.py, "
    "`python -m preform` in the hostile run trials",
}


def compiled_functions(name: str) -> set[str]:
    """Names of the module's functions that numba compiles (a dispatcher keeps ``py_func``)."""
    module = importlib.import_module(name)
    # a snapshot: asking a lazy module attribute for ``py_func`` may add to its globals
    return {key for key, value in list(vars(module).items()) if hasattr(value, "py_func")}


def has_nothing_to_run(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """A body of a docstring, ``...`` or ``pass`` only (a protocol, a hook specification)."""
    return all(
        isinstance(s, ast.Pass) or (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant))
        for s in node.body
    )


def function_body_lines(source: str, compiled: set[str]) -> set[int]:
    """Line numbers of the statements inside every function a test can be seen to run."""
    lines: set[int] = set()
    tree = ast.parse(source)
    skip = {
        id(node)
        for node in tree.body
        if isinstance(node, ast.FunctionDef) and node.name in compiled
    }
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            if id(node) in skip or has_nothing_to_run(node):
                continue
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
    imported_only: list[str] = []
    modules = module_files()
    for name, path in sorted(modules.items()):
        if name in SUBPROCESS_ONLY:
            continue
        ran = measured.get(path.resolve())
        if ran is None:
            missing.append(f"{name}: never imported")
            continue
        body = function_body_lines(path.read_text(encoding="utf-8"), compiled_functions(name))
        if not body:
            imported_only.append(name)
        elif not ran & body:
            missing.append(f"{name}: imported, but none of its functions ran")
    counted = len(modules) - len(SUBPROCESS_ONLY)
    print(
        f"quick tier: {counted - len(missing)} of {counted} modules exercised "
        f"({len(imported_only)} by import: no function coverage can see run: "
        f"{', '.join(imported_only)}); run in a subprocess only, not measured: "
        + "; ".join(f"{k} ({v})" for k, v in SUBPROCESS_ONLY.items())
    )
    for line in missing:
        print(f"  {line}")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
