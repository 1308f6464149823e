"""Imports flow one way: no module of ``core/`` imports, at module level, something that imports
it back, the plugin machinery (registry, step contract, plugin manager) sits below the
pipeline, which plans and runs what it registered, and every import, inside functions too,
points down one order of the packages (docs/design.md, "Layers").

The static checks read the source with ``ast``. For module cycles an import counts when it runs
on import, so not inside a function; for the package order every import counts, wherever it is.
Imports under ``if TYPE_CHECKING:`` never run and may point anywhere (annotations).
"""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

import pytest

from preform._moved import MOVED_MODULES

CORE = Path(__file__).resolve().parents[2] / "core"

#: Layers: (lower, upper). No module of a lower layer imports (at module level, transitively) a
#: module of the upper one, which imports it. The plugin layer must not need the pipeline, the
#: drape or the exports (issue 16: the registry imported ``preform.pipeline.step`` while the
#: pipeline's planner and scene imported the registry); the drape engine must not need the
#: optimisation built on it.
LAYERS = [
    (
        (
            "preform.hookspecs",
            "preform.material",
            "preform.plugin_manager",
            "preform.registry",
            "preform.step",
        ),
        ("preform.pipeline", "preform.drape", "preform.export", "preform.optimise", "preform.api"),
    ),
    (("preform.drape",), ("preform.optimise",)),
]

#: The packages and top-level modules of ``core/`` from the bottom up (``preform`` is the root
#: package, the public facade). An import, wherever it is, may only name a package below its own.
PACKAGE_ORDER = [
    # primitives: moved-module aliases, atomic writes, status, fidelity knobs, version
    *("_moved", "base", "collector", "yamlsource"),
    # the model and the plugin machinery
    *("geometry", "material", "validation", "hookspecs", "step", "registry"),
    *("plugin_manager", "library", "builtin", "testing", "command_line"),
    # the engines and the writers of their results
    *("shear", "drape", "export"),
    # scenes, planning, running; then the steps that run or ask the pipeline themselves
    *("pipeline", "optimise", "stack", "compare", "report"),
    # the faces: Python API, command line, measurements of preform, the package root
    *("api", "commands", "schema", "bench", "cli", "__main__", "preform"),
]

#: Modules moved, old path -> new path; the old path is a deprecated alias served by
#: ``preform._moved``, so no file of it is part of the layer it names.
MOVED = MOVED_MODULES


def _within(module: str, packages: tuple[str, ...]) -> bool:
    return any(module == p or module.startswith(p + ".") for p in packages)


def core_modules(core: Path) -> dict[str, Path]:
    """Every module under ``core`` by its import name (``core/`` is ``preform``)."""
    modules = {}
    for path in core.rglob("*.py"):
        parts = ["preform", *path.relative_to(core).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts.pop()
        modules[".".join(parts)] = path
    return modules


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _module_level_imports(body: list[ast.stmt]) -> Iterator[ast.Import | ast.ImportFrom]:
    """Import statements that run when the module is imported (class bodies, try and if
    blocks included; functions and ``if TYPE_CHECKING:`` blocks not)."""
    for node in body:
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        elif isinstance(node, ast.If):
            if not _is_type_checking(node.test):
                yield from _module_level_imports(node.body)
            yield from _module_level_imports(node.orelse)
        elif isinstance(node, ast.ClassDef | ast.With):
            yield from _module_level_imports(node.body)
        elif isinstance(node, ast.Try):
            for block in (node.body, node.orelse, node.finalbody):
                yield from _module_level_imports(block)
            for handler in node.handlers:
                yield from _module_level_imports(handler.body)


def _every_import(tree: ast.AST) -> Iterator[ast.Import | ast.ImportFrom]:
    """Every import statement that can run: in functions too, not under ``if TYPE_CHECKING:``."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        elif isinstance(node, ast.If) and _is_type_checking(node.test):
            for other in node.orelse:
                yield from _every_import(ast.Module(body=[other], type_ignores=[]))
        else:
            yield from _every_import(node)


def package_of(module: str, core: Path) -> str:
    """The entry of ``PACKAGE_ORDER`` a module belongs to: ``preform.x...`` is ``x`` when ``x``
    is a package or module of ``core``, else (a name taken from the root) ``preform``."""
    first = module.split(".")[1] if "." in module else ""
    if (core / first).is_dir() or (core / f"{first}.py").is_file():
        return first
    return "preform"


def order_violations(core: Path, order: list[str], allowed: dict) -> list[str]:
    """``file:line: a imports b`` for every import naming a package above its own."""
    rank = {name: i for i, name in enumerate(order)}
    found = []
    for name, path in sorted(core_modules(core).items()):
        own = package_of(name, core) if name != "preform" else "preform"
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        file = path.relative_to(core).as_posix()
        for node in _every_import(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                sources = [alias.name for alias in node.names]
            else:
                base = node.module or ""
                if node.level:  # relative: from .x import y
                    parts = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                    base = ".".join([*parts, *([node.module] if node.module else [])])
                sources = [f"{base}.{a.name}" for a in node.names] if base == "preform" else [base]
            for source in sources:
                if not source.startswith("preform.") or (file, source) in allowed:
                    continue
                target = package_of(source, core)
                if target != own and rank[target] > rank[own]:
                    found.append(
                        f"{file}:{node.lineno}: {own} imports {source} ({target} is above)"
                    )
    return found


def _ancestors(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def import_graph(core: Path) -> dict[str, set[str]]:
    """Module -> the ``core`` modules its import runs, directly.

    ``import a.b.c`` runs ``a``, ``a.b`` and ``a.b.c``; a package that is the importer's own
    ancestor is already initialised (Python imports parents first), so it counts only when a
    name other than a submodule is taken from it.
    """
    modules = core_modules(core)
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        own = set(_ancestors(name)) | ({name} if path.name == "__init__.py" else set())
        targets: set[str] = set()
        for node in _module_level_imports(ast.parse(path.read_text(), str(path)).body):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    targets.update(m for m in [*_ancestors(alias.name), alias.name] if m not in own)
                continue
            if node.level:  # relative: from .x import y
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                source = ".".join([*base, *([node.module] if node.module else [])])
            else:
                source = node.module or ""
            targets.update(m for m in _ancestors(source) if m not in own)
            submodules = [
                f"{source}.{a.name}" for a in node.names if f"{source}.{a.name}" in modules
            ]
            targets.update(submodules)
            if source not in own or len(submodules) < len(node.names):
                targets.add(source)
        graph[name] = {t for t in targets if t in modules and t != name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def reachable(graph: dict[str, set[str]], start: str) -> dict[str, str]:
    """Every module ``start`` imports transitively, with the module that imports it."""
    seen: dict[str, str] = {}
    todo = [start]
    while todo:
        node = todo.pop()
        for child in graph[node]:
            if child not in seen and child != start:
                seen[child] = node
                todo.append(child)
    return seen


def test_no_module_imports_a_module_that_imports_it_back():
    found = cycles(import_graph(CORE))
    assert not found, "module-level import cycles in core/: " + "; ".join(
        " <-> ".join(c) for c in found
    )


@pytest.mark.parametrize(("lower", "upper"), LAYERS, ids=["plugin layer", "drape engine"])
def test_a_lower_layer_does_not_import_the_one_above(lower, upper):
    graph = import_graph(CORE)
    wrong = [
        f"{module} reaches {target} (imported by {via})"
        for module in sorted(graph)
        if _within(module, lower) and module not in MOVED
        for target, via in sorted(reachable(graph, module).items())
        if _within(target, upper)
    ]
    assert not wrong, "; ".join(wrong)


def test_every_import_points_down_the_package_order():
    wrong = order_violations(CORE, PACKAGE_ORDER, {})
    assert not wrong, "imports against the package order (docs/design.md):\n" + "\n".join(wrong)


def test_every_package_and_top_level_module_has_its_place_in_the_order():
    names = {package_of(m, CORE) for m in core_modules(CORE) if m != "preform"} | {"preform"}
    assert sorted(names) == sorted(PACKAGE_ORDER)


def test_the_order_check_counts_imports_in_functions_and_names_the_line(tmp_path):
    files = {
        "__init__.py": "",
        "low/__init__.py": "",
        "low/a.py": (
            "from typing import TYPE_CHECKING\n"
            "if TYPE_CHECKING:\n    from preform.high.b import B\n"
            "def f():\n    from preform.high.b import g\n    return g\n"
        ),
        "high/__init__.py": "",
        "high/b.py": "from preform.low import a\nfrom preform import __version__\n",
    }
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    order = ["low", "high", "preform"]
    assert order_violations(tmp_path, order, {}) == [
        "high/b.py:2: high imports preform.__version__ (preform is above)",
        "low/a.py:5: low imports preform.high.b (high is above)",
    ]
    assert order_violations(tmp_path, order, {("low/a.py", "preform.high.b")}) == [
        "high/b.py:2: high imports preform.__version__ (preform is above)"
    ]
    assert order_violations(tmp_path, ["high", "low", "preform"], {}) == [
        "high/b.py:1: high imports preform.low (low is above)",
        "high/b.py:2: high imports preform.__version__ (preform is above)",
    ]


def test_the_checks_see_a_cycle_and_ignore_what_does_not_run_on_import(tmp_path):
    """The checks themselves: a toy package with a real cycle, a cycle through a parent
    package, and back-imports that do not run on import (TYPE_CHECKING, in a function)."""
    files = {
        "__init__.py": "",
        "registry.py": "from preform.pipeline.step import Step\n",
        "pipeline/__init__.py": "from preform.pipeline.planner import plan\n",
        "pipeline/step.py": "class Step: ...\n",
        "pipeline/planner.py": "from preform import registry\ndef plan(): ...\n",
        "quiet.py": (
            "from typing import TYPE_CHECKING\n"
            "if TYPE_CHECKING:\n    from preform.loud import x\n"
            "def f():\n    from preform.loud import x\n"
        ),
        "loud.py": "from preform.quiet import f\nx = 1\n",
    }
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    graph = import_graph(tmp_path)
    # the registry's import of pipeline.step runs pipeline/__init__, which imports the planner
    assert graph["preform.registry"] == {"preform.pipeline", "preform.pipeline.step"}
    assert cycles(graph) == [["preform.pipeline", "preform.pipeline.planner", "preform.registry"]]
    assert graph["preform.quiet"] == set()


@pytest.mark.parametrize(
    "module",
    [
        "preform.registry",
        "preform.step",
        "preform.pipeline.step",
        "preform.pipeline.planner",
        "preform.pipeline.scene",
        "preform.plugin_manager",
    ],
)
def test_each_module_imports_first_in_a_fresh_interpreter(module):
    """Whatever is imported first, the import completes (a cycle shows as a partially
    initialised module depending on which side is imported first)."""
    done = subprocess.run(
        [sys.executable, "-c", f"import {module}"], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr


def test_step_and_case_context_keep_their_old_import_path():
    import preform
    import preform.step

    sys.modules.pop("preform.pipeline.step", None)
    with pytest.warns(DeprecationWarning, match="import preform.step"):
        import preform.pipeline.step

    assert preform.Step is preform.step.Step is preform.pipeline.step.Step
    assert preform.CaseContext is preform.step.CaseContext is preform.pipeline.step.CaseContext


@pytest.mark.parametrize(("old", "new"), sorted(MOVED.items()))
def test_a_moved_module_keeps_its_old_path_with_a_deprecation_warning(old, new):
    moved = importlib.import_module(new)
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=new) as warned:
        alias = importlib.import_module(old)
    assert alias is moved  # the same module: every name, private ones and patching included
    assert moved.__spec__.name == new  # the alias did not take the module's identity
    assert len(warned) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert importlib.import_module(old) is moved  # once: a second import does not warn


def test_an_old_path_imported_by_statement_warns_at_that_line():
    old, new = "preform.pipeline.status", "preform.base.status"
    code = (
        "import warnings\nwarnings.simplefilter('always')\n"
        f"from {old.rpartition('.')[0]} import {old.rpartition('.')[2]} as alias\n"
        f"import {new}\nassert alias is {new}\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert f"<string>:3: DeprecationWarning: {old} is deprecated: import {new}" in done.stderr


def test_no_file_is_left_at_a_moved_path():
    for old in MOVED:
        rel = Path(*old.split(".")[1:])
        assert not (CORE / rel.with_suffix(".py")).exists() and not (CORE / rel).is_dir(), old
