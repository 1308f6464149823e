"""preform's heavier commands load when used, and ``--help`` still lists them as they are.

Start-up (issue 15): ``LAZY_COMMANDS`` keeps the modules of ``scenes``, ``export``, ``shear``,
``fit`` and ``bench`` out of every other command; their ``--help`` line is stored beside the
import path. These tests hold that line to the command's own, and check what a fresh
interpreter imports.
"""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import click
import pytest
from click.testing import CliRunner

from preform.cli import LAZY_COMMANDS, build_cli, cli


@pytest.mark.parametrize("name", sorted(LAZY_COMMANDS))
@pytest.mark.parametrize("width", [20, 45, 74, 200])
def test_the_stored_short_help_is_the_commands_own(name: str, width: int) -> None:
    module, attribute = LAZY_COMMANDS[name][0].split(":")
    command = getattr(importlib.import_module(module), attribute)
    stored = click.Command(name, help=LAZY_COMMANDS[name][1])
    assert stored.get_short_help_str(width) == command.get_short_help_str(width)


def test_help_lists_lazy_commands_like_loaded_ones() -> None:
    lazy = CliRunner().invoke(build_cli(lazy=True), ["--help"])
    group = build_cli()
    for name in LAZY_COMMANDS:  # every command loaded
        group.commands[name] = group.get_command(click.Context(group), name)
    loaded = CliRunner().invoke(group, ["--help"])
    assert lazy.exit_code == loaded.exit_code == 0
    assert lazy.output == loaded.output
    for name in LAZY_COMMANDS:
        assert f"\n  {name} " in lazy.output


def test_a_lazy_command_runs_when_named() -> None:
    result = CliRunner().invoke(cli, ["scenes", "list", "--json"])
    assert result.exit_code == 0, result.output
    assert "hemisphere-min-energy" in {row["name"] for row in json.loads(result.output)}


PROBE = """
import contextlib, io, json, sys
from preform.cli import LAZY_COMMANDS, main
sys.argv = ["preform", *{argv!r}]
with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):
    main()
modules = [path.split(":")[0] for path, _ in LAZY_COMMANDS.values()]
print(json.dumps(sorted(m for m in modules if m in sys.modules)))
"""


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["--version"], []),
        (["--help"], []),
        (["materials", "list"], []),
        (["scenes", "list"], ["preform.commands.scenes"]),
    ],
)
def test_a_fresh_interpreter_imports_only_the_command_it_runs(
    argv: list[str], expected: list[str]
) -> None:
    done = subprocess.run(
        [sys.executable, "-c", PROBE.format(argv=argv)],
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    assert json.loads(done.stdout.strip().splitlines()[-1]) == expected
