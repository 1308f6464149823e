"""Every ``preform ...`` command that README.md and docs/*.md name exists, with every option
they give it (issue 26: docs/exports.md showed a ``--material`` option that never existed).

The truth is the command tree itself: click's groups and commands as ``preform`` builds them,
plugin commands included. A command is read from a fenced block's line or an inline code span
(which may run over a line break) starting with ``preform ``: its words walk down the tree
(``preform pipeline run``) and every ``-x``/``--xyz`` in it must be an option of a command on
that path.
"""

from __future__ import annotations

import re
from pathlib import Path

import click
import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

_INLINE = re.compile(r"(?<!`)`(preform [^`]+)`(?!`)")
_FENCED = re.compile(r"^```(?:bash|console|sh)?\n(.*?)^```", re.M | re.S)
_OPTION = re.compile(r"(?<![\w./'\"-])(--?[A-Za-z][\w-]*)")
#: Words that stand for a command the text leaves open (``preform --debug COMMAND ...``).
_PLACEHOLDER = re.compile(r"^[A-Z][A-Z_.]*$|^\.\.\.$|^\[")


def mentions(page: Path) -> list[tuple[int, str]]:
    """(line, command text) of every ``preform ...`` the page names."""
    text = page.read_text(encoding="utf-8")
    found = []
    for block in _FENCED.finditer(text):
        first = text.count("\n", 0, block.start(1)) + 1
        for n, line in enumerate(block.group(1).replace("\\\n", " ").splitlines()):
            command = line.split(" #")[0].strip()
            if command.startswith("preform "):
                found.append((first + n, command))
    prose = _FENCED.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    for span in _INLINE.finditer(prose):
        found.append((prose.count("\n", 0, span.start()) + 1, " ".join(span.group(1).split())))
    return found


def options_of(command: click.Command) -> set[str]:
    ctx = click.Context(command)
    return {name for p in command.get_params(ctx) for name in (*p.opts, *p.secondary_opts)}


def walk(root: click.Group, words: list[str]) -> tuple[list[click.Command], str | None]:
    """The commands the words name, root first, and the first word that should name a
    command but names none (None when all do)."""
    path: list[click.Command] = [root]
    for word in words:
        current = path[-1]
        if not isinstance(current, click.Group) or word.startswith("-"):
            continue
        if _PLACEHOLDER.match(word) or "=" in word:
            break
        sub = current.get_command(click.Context(current), word)
        if sub is None:
            return path, word
        path.append(sub)
    return path, None


def _cases() -> list[tuple[str, str]]:
    return [
        (f"{page.relative_to(ROOT)}:{line}", command)
        for page in PAGES
        for line, command in mentions(page)
    ]


@pytest.fixture(scope="module")
def root() -> click.Group:
    from preform.cli import build_cli

    return build_cli()


def test_the_pages_name_commands() -> None:
    """The reader finds what the pages say (a regex slip would find nothing to check)."""
    cases = _cases()
    assert len(cases) >= 40
    assert any("--materials" in command for _, command in cases)
    assert any(where.startswith("docs/exports.md") for where, _ in cases)


@pytest.mark.parametrize(("where", "command"), _cases(), ids=[w for w, _ in _cases()])
def test_every_named_command_and_option_exists(root: click.Group, where: str, command: str):
    words = command.split()[1:]
    path, unknown = walk(root, words)
    assert unknown is None, f"{where}: `{command}`: no command {unknown!r}"
    known = set().union(*(options_of(c) for c in path))
    named = set(_OPTION.findall(" ".join(words)))
    missing = sorted(named - known)
    assert not missing, f"{where}: `{command}`: {' '.join(missing)} not an option of it"


def test_the_check_catches_an_option_that_does_not_exist(root: click.Group) -> None:
    path, unknown = walk(root, "export E-BX-318 abaqus --material M".split())
    assert unknown is None and [c.name for c in path][-1] == "export"
    assert "--material" not in set().union(*(options_of(c) for c in path))
    assert walk(root, "material list".split())[1] == "material"
