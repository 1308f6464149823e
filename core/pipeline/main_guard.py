"""A run started from a script's top level without ``if __name__ == "__main__":``.

Worker processes that are spawned, or forked from a fork server, re-run the main script (as
``__mp_main__``) before they take work, so that the functions it defines can be found. A
``preform.run()`` at the script's top level then runs again in every worker, which meets the
run lock and dies, and the parent's healthy cases are recorded ``failed: BrokenProcessPool``
(issue 25, item 2). Both sides are caught here: the parent refuses before anything runs when
the call is plainly unguarded (:func:`unguarded_main_call`), and a worker that re-runs the
script anyway exits quietly at the call (:func:`in_worker_bootstrap`), leaving the message to
the parent.
"""

from __future__ import annotations

import ast
import sys
from types import FrameType, ModuleType

GUARD_ADVICE = (
    'put the call under `if __name__ == "__main__":` (the process and dask engines start '
    "worker processes that import the main script again, and would run it again; "
    "docs/api.md, 'Scripts')"
)


class UnguardedRunError(RuntimeError):
    """A run was started from a script's top level, outside ``if __name__ == "__main__":``."""


def in_worker_bootstrap() -> bool:
    """Whether this call comes from the top level of the parent's main script, which this
    worker process is running again (as ``__mp_main__``: ``multiprocessing.spawn`` runs it
    under that name before it takes work; ``multiprocessing.parent_process`` is not set yet
    then, and no one else uses the name)."""
    frame: FrameType | None = sys._getframe(1)
    while frame is not None:
        if frame.f_code.co_name == "<module>" and frame.f_globals.get("__name__") == "__mp_main__":
            return True
        frame = frame.f_back
    return False


def _reimported_by_workers(main: ModuleType) -> bool:
    """Whether spawned or fork-server workers run ``main`` again (as ``multiprocessing.spawn``
    decides: a script by its path, or a module run with ``-m`` unless it is a package's
    ``__main__``)."""
    name = getattr(getattr(main, "__spec__", None), "name", None)
    if name is not None:
        return not (name == "__main__" or name.endswith(".__main__"))
    return getattr(main, "__file__", None) is not None


def _module_frame(main: ModuleType) -> FrameType | None:
    """The frame running ``main``'s top-level code, if this call came from it."""
    frame: FrameType | None = sys._getframe(1)
    while frame is not None:
        if frame.f_globals is main.__dict__ and frame.f_code.co_name == "<module>":
            return frame
        frame = frame.f_back
    return None


def _tests_name(node: ast.AST) -> bool:
    return any(isinstance(n, ast.Name) and n.id == "__name__" for n in ast.walk(node))


def _inner_statements(holder: ast.stmt) -> list[ast.stmt]:
    """The statements a compound statement holds (its bodies, its handlers' and cases')."""
    inner: list[ast.stmt] = []
    for child in ast.iter_child_nodes(holder):
        if isinstance(child, ast.stmt):
            inner.append(child)
        elif isinstance(child, ast.ExceptHandler | ast.match_case):
            inner.extend(child.body)
    return inner


def _guarded(tree: ast.Module, line: int) -> bool | None:
    """Whether ``line`` of the module sits in a statement under an ``if``, ``while`` or
    ``match`` that tests ``__name__`` (None: no statement of the module holds the line)."""
    statements: list[ast.stmt] = tree.body
    guarded: bool | None = None
    while statements:
        holder = next(
            (s for s in statements if s.lineno <= line <= (s.end_lineno or s.lineno)), None
        )
        if holder is None:
            break
        tests = (isinstance(holder, ast.If | ast.While) and _tests_name(holder.test)) or (
            isinstance(holder, ast.Match) and _tests_name(holder.subject)
        )
        guarded = bool(guarded) or tests
        statements = _inner_statements(holder)
    return guarded


def unguarded_main_call() -> str | None:
    """``file:line`` of the main script's top-level statement that led to this call when it
    is under no test of ``__name__`` and workers would run the script again; None otherwise
    (and whenever it cannot be told: no source, an interactive session)."""
    main = sys.modules.get("__main__")
    if main is None or not _reimported_by_workers(main):
        return None
    frame = _module_frame(main)
    path = getattr(main, "__file__", None)
    if frame is None or path is None:
        return None
    try:
        with open(path, encoding="utf-8") as handle:
            tree = ast.parse(handle.read(), filename=path)
    except (OSError, SyntaxError, ValueError):
        return None
    line = frame.f_lineno
    if line is None or _guarded(tree, line) is not False:
        return None
    return f"{path}:{line}"


def refuse_unguarded_run(*, starts_workers: bool) -> None:
    """Before a run: exit quietly in a worker re-running its parent's script (its parent says
    why); raise ``UnguardedRunError`` in a script that would make the run's workers
    (``starts_workers``) do so."""
    if in_worker_bootstrap():
        # reached only where the parent could not tell (no source to read): say it once per
        # worker, and end it without the traceback a worker prints for an exception
        sys.stderr.write(
            "error: a worker process ran the main script again and met its run: "
            + GUARD_ADVICE
            + "\n"
        )
        sys.stderr.flush()
        raise SystemExit(1)
    where = unguarded_main_call() if starts_workers else None
    if where is not None:
        raise UnguardedRunError(
            f"{where}: a preform run is started at the top level of the main script; "
            + GUARD_ADVICE
            + "; nothing was run"
        )
