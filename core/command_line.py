"""The grammar every command of ``preform`` spells the same way: ``--library PATH``
(repeatable) adds to the bundled library and ``PREFORM_LIBRARY``, ``--no-bundled`` leaves the
bundled library out; ``--json`` prints nothing but one JSON document on stdout (words go to
stderr); ``--out`` is a directory for a run and a file for a single artefact, and its metavar
says which; the exit codes. Below every package that has a command (docs/design.md, "Layers")."""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import Any, NoReturn, TypeVar

import click

F = TypeVar("F", bound=Callable[..., Any])

LIBRARY_HELP = (
    "Extra library file or directory (repeatable); added to the bundled library and "
    "PREFORM_LIBRARY."
)
NO_BUNDLED_HELP = (
    "Leave the bundled library out: use only the libraries given (--library, PREFORM_LIBRARY)."
)
JSON_HELP = "Print one JSON document on stdout and nothing else (messages go to stderr)."

#: Exit codes of every command (README, "Exit codes").
EXIT_OK = 0
#: The command ran and found a failure: invalid files, cases that failed or timed out.
EXIT_FAILED = 1
#: Bad usage or input; nothing was run (unknown fabric or scene, invalid library or scene).
EXIT_USAGE = 2
#: An unexpected error inside preform or a plugin (a bug): rerun with --debug and report it.
EXIT_INTERNAL = 3
#: Interrupted (Ctrl-C, SIGTERM).
EXIT_INTERRUPTED = 130


def library_options(func: F | None = None, *, dest: str = "libraries") -> Any:
    """``--library PATH`` (repeatable) and ``--no-bundled``, as ``dest`` and ``no_bundled``.

    Use bare (``@library_options``) or with another parameter name
    (``@library_options(dest="extra_libraries")``) where ``libraries`` is taken.
    """

    def decorate(f: F) -> F:
        f = click.option("--no-bundled", "no_bundled", is_flag=True, help=NO_BUNDLED_HELP)(f)
        return click.option(
            "--library",
            dest,
            multiple=True,
            type=click.Path(),
            metavar="PATH",
            help=LIBRARY_HELP,
        )(f)

    return decorate(func) if func is not None else decorate


def json_option(func: F) -> F:
    return click.option("--json", "as_json", is_flag=True, help=JSON_HELP)(func)


def file_option(*names: str, help: str) -> Callable[[F], F]:
    """``--NAME FILE``: one file to write (a directory is refused)."""
    return click.option(*names, type=click.Path(dir_okay=False), metavar="FILE", help=help)


def echo_json(obj: Any) -> None:
    """``obj`` as JSON on stdout: numpy values and paths made plain, non-finite numbers null."""
    import json  # here, not at the top: most commands print no JSON

    from preform.base.strict_json import clean_json

    click.echo(json.dumps(clean_json(obj), indent=2, sort_keys=False, default=str))


def fail(lines: Sequence[Any], code: int = EXIT_USAGE) -> NoReturn:
    """Print ``lines`` on stderr and exit with ``code``."""
    for line in lines:
        click.echo(str(line), err=True)
    sys.exit(code)


def load_library_or_exit(paths: Sequence[str], *, bundled: bool = True) -> Any:
    """The library (bundled unless ``bundled`` is False, PREFORM_LIBRARY, then ``paths``);
    every located error and exit 2 when it does not validate. Importing the library's modules
    and reading it is start-up: no garbage collection meanwhile (``preform.collector``)."""
    from preform.collector import startup_phase

    with startup_phase():
        from preform.library import LibraryError, load_library
        from preform.plugin_manager import default_host

        try:
            return load_library(list(paths), bundled=bundled, registry=default_host().registry)
        except LibraryError as exc:
            fail([*exc.errors, f"{len(exc.errors)} error(s); nothing was run."])


def fabric_or_exit(library: Any, name: str) -> Any:
    """``library.fabric(name)``, or the library's "no fabric named ... did you mean" and exit 2."""
    try:
        return library.fabric(name)
    except KeyError as exc:
        fail([f"error: {exc.args[0]}"])


class InputError(click.ClickException):
    """Bad input named on the command line (a missing test dimension, an unknown fabric):
    click's ``Error: ...`` and exit code 2, as for a usage error."""

    exit_code = EXIT_USAGE
