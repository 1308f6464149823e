"""Every example of README.md, CONTRIBUTING.md and docs/ runs, and the notebook in examples/.

A fenced block runs by its language: ``python`` blocks execute in order, one namespace per page;
``bash`` blocks run each ``preform ...`` command through the command line (exit code 0, ``> FILE``
honoured) and skip the set-up commands listed in SETUP; ``yaml`` blocks that hold fabric entries
validate as a library file; ``toml`` blocks parse. A block preceded by
``<!-- example: fragment -->`` is a part of a file (it only has to parse, its ``...`` lines
aside); ``<!-- example: excerpt of PATH -->`` must appear verbatim in PATH, a file the suite runs
or reads. Examples run in a fresh folder holding the files of docs/examples/.
"""

from __future__ import annotations

import ast
import json
import re
import shlex
import shutil
import textwrap
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", ROOT / "CONTRIBUTING.md", *sorted((ROOT / "docs").glob("*.md"))]
#: Commands of bash blocks that set up an environment or run the checks themselves: not run
#: here (the suite is what `pytest` runs; installing is CI's job).
SETUP = {"python3", ".", "source", "pip", "pytest", "ruff", "mypy"}

_FENCE = re.compile(
    r"^(?P<indent>[ \t]*)(?:<!-- example: (?P<mark>[^>]*?) -->\n(?P=indent))?```(?P<lang>\w*)\n"
    r"(?P<body>.*?)^(?P=indent)```",
    re.M | re.S,
)


@dataclass
class Block:
    page: Path
    line: int
    lang: str
    body: str
    mark: str | None

    @property
    def id(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def blocks(page: Path) -> list[Block]:
    text = page.read_text(encoding="utf-8")
    out = []
    for m in _FENCE.finditer(text):
        body = textwrap.dedent(m.group("body"))
        line = text.count("\n", 0, m.start("lang")) + 1
        out.append(Block(page, line, m.group("lang"), body, m.group("mark")))
    return out


@pytest.fixture
def folder(tmp_path, monkeypatch) -> Path:
    for source in (ROOT / "docs" / "examples").iterdir():
        shutil.copy(source, tmp_path / source.name)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.delenv("PREFORM_LIBRARY", raising=False)
    return tmp_path


def run_preform(command: str, folder: Path) -> None:
    from preform.cli import build_cli

    words = shlex.split(command, comments=True)
    target = None
    if ">" in words:
        at = words.index(">")
        words, target = words[:at], words[at + 1]
    result = CliRunner().invoke(build_cli(), words[1:], catch_exceptions=False)
    assert result.exit_code == 0, f"{command}\n{result.stdout}\n{result.stderr}"
    if target:
        (folder / target).write_text(result.stdout)


def run_bash(block: Block, folder: Path) -> int:
    ran = 0
    text = block.body.replace("\\\n", " ")
    for line in text.splitlines():
        for part in line.split("&&"):
            command = shlex.split(part, comments=True)
            while command and "=" in command[0]:  # VAR=value before the program: its environment
                command = command[1:]
            if not command:
                continue
            if command[0] == "preform":
                run_preform(part, folder)
                ran += 1
            else:
                assert command[0] in SETUP, f"{block.id}: {part!r} is neither preform nor set-up"
    return ran


def check_yaml(block: Block, folder: Path) -> None:
    if block.mark == "fragment":
        lines = [ln for ln in block.body.splitlines() if ln.strip() != "..."]
        yaml.safe_load("\n".join(lines))
        return
    data = yaml.safe_load(block.body)
    entries = data if isinstance(data, list) else [data]
    if all(isinstance(e, dict) and "architecture" in e for e in entries):
        from preform.library import validate_files
        from preform.plugin_manager import default_host

        path = folder / "example.yaml"
        path.write_text(block.body)
        _, errors, _ = validate_files([path], default_host().registry)
        assert not errors, f"{block.id}: {errors}"


def all_pages() -> list[Path]:
    return [p for p in PAGES if blocks(p)]


@pytest.mark.parametrize("page", all_pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_example_of_the_page_runs(page: Path, folder: Path):
    namespace: dict[str, object] = {"__name__": f"example:{page.name}"}
    for block in blocks(page):
        if block.mark and block.mark.startswith("excerpt of "):
            source = ROOT / block.mark.removeprefix("excerpt of ")
            assert block.body.strip() in source.read_text(), f"{block.id} not in {source}"
        elif block.lang == "python":
            exec(compile(block.body, block.id, "exec"), namespace)
        elif block.lang == "bash" and page.name != "README.md":  # README: one test a command
            run_bash(block, folder)
        elif block.lang == "yaml":
            check_yaml(block, folder)
        elif block.lang == "toml":
            tomllib.loads(block.body)


#: README commands that take more than a few seconds (a library-wide drape, a CAD tool): run
#: with ``pytest -m slow`` (and by CI), the rest of the tour in the default tier.
SLOW_TOUR = (
    "preform pipeline run$",  # the default study, this command alone ($: nothing after it)
    "preform pipeline run --scene hemisphere$",
    "preform pipeline run --scene shear",
    "preform pipeline run --scene hat-stiffener-min-energy",
)


def slow_tour(command: str) -> bool:
    return any(
        command == s.removesuffix("$") if s.endswith("$") else command.startswith(s + " ")
        for s in SLOW_TOUR
    )


def readme_commands() -> list[str]:
    """Every ``preform ...`` line of README.md's bash blocks, as written."""
    found = []
    for block in blocks(ROOT / "README.md"):
        if block.lang != "bash":
            continue
        for line in block.body.replace("\\\n", " ").splitlines():
            for part in line.split("&&"):
                words = shlex.split(part, comments=True)
                if words and words[0] == "preform":
                    found.append(part.split(" #")[0].strip())
                elif words:
                    assert words[0] in SETUP, f"README: {part!r} is neither preform nor set-up"
    return found


@pytest.mark.parametrize(
    "command",
    [pytest.param(c, marks=[pytest.mark.slow] if slow_tour(c) else []) for c in readme_commands()],
    ids=lambda c: c.removeprefix("preform ")[:60],
)
def test_the_readme_tour_command_runs(command: str, folder: Path):
    """Each command of the README, in a fresh folder with docs/examples/ (exit code 0)."""
    run_preform(command, folder)


def test_the_readme_tour_runs_commands_and_is_not_skipped():
    """The runner really runs the README's commands (a regex slip would run none)."""
    tour = [b for b in blocks(ROOT / "README.md") if b.lang == "bash"]
    commands = [
        line for b in tour for line in b.body.splitlines() if line.lstrip().startswith("preform ")
    ]
    assert len(commands) >= 10
    assert len(readme_commands()) >= len(commands)
    slow = [c for c in readme_commands() if slow_tour(c)]
    assert len(slow) == len(SLOW_TOUR)  # each slow entry names a command that is there
    api = [b for b in blocks(ROOT / "docs" / "api.md") if b.lang == "python"]
    assert len(api) >= 5


#: IPython magics the notebook may use: the runner here is plain Python, and these only set up
#: Jupyter's display (run by hand, they would make no difference to what the cells compute).
NOTEBOOK_MAGICS = {"%matplotlib inline"}


def run_cell_as_jupyter(source: str, name: str, namespace: dict[str, object]) -> object:
    """Run a code cell as Jupyter does and return what it shows: the value of its last
    statement when that is an expression (None otherwise, or for a trailing ``;``)."""
    lines = []
    for line in source.splitlines():
        if line.startswith("%"):
            assert line.strip() in NOTEBOOK_MAGICS, f"{name}: magic {line!r} not run here"
            continue
        lines.append(line)
    code = "\n".join(lines)
    tree = ast.parse(code, name)
    last = tree.body[-1] if tree.body else None
    if isinstance(last, ast.Expr) and not code.rstrip().endswith(";"):
        exec(compile(ast.Module(tree.body[:-1], []), name, "exec"), namespace)
        return eval(compile(ast.Expression(last.value), name, "eval"), namespace)
    exec(compile(tree, name, "exec"), namespace)
    return None


def clone_files(folder: Path) -> set[str]:
    """Files under ``folder`` that git would list as changed or new, as ``git status
    --porcelain`` lines (paths from the checkout's root; every file when the tree is not a git
    checkout, e.g. an unpacked sdist)."""
    import subprocess

    try:
        listed = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=all", "--", "."],
            cwd=folder, capture_output=True, text=True, check=True, timeout=60,
        )  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return {str(p.relative_to(folder)) for p in folder.rglob("*")}
    return set(listed.stdout.splitlines())


def test_the_notebook_runs_shows_its_figures_and_leaves_the_clone_clean(tmp_path, monkeypatch):
    """examples/api_tour.ipynb: its code cells, in order, in one namespace (no Jupyter), run
    from the notebook's own folder as Jupyter runs them. Every cell that draws shows its
    figure (its last value is the Figure, which Jupyter displays inline); the files it writes
    go to its temporary folder, and nothing in examples/ changes."""
    import tempfile

    from matplotlib.figure import Figure

    examples = ROOT / "examples"
    notebook = json.loads((examples / "api_tour.ipynb").read_text())
    assert notebook["nbformat"] == 4
    cells = [c for c in notebook["cells"] if c["cell_type"] == "code"]
    assert cells
    monkeypatch.chdir(examples)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.delenv("PREFORM_LIBRARY", raising=False)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # the tour's folder lands here
    before = clone_files(examples)
    namespace: dict[str, object] = {"__name__": "api_tour"}
    shown = []
    try:
        for n, cell in enumerate(cells):
            source = "".join(cell["source"])
            value = run_cell_as_jupyter(source, f"api_tour.ipynb[cell {n}]", namespace)
            shown.append((source, value))
    finally:
        new = clone_files(examples) - before
        for line in new:  # leave the clone as it was, then say what the notebook wrote there
            path = ROOT / line[3:].strip()  # porcelain paths are the checkout's
            if line.startswith("??") and path.is_file():
                path.unlink()
    assert not new, f"the notebook changed the clone: {sorted(new)}"
    drawing = [(src, value) for src, value in shown if ".plot(" in src]
    assert len(drawing) >= 2
    for source, value in drawing:
        assert isinstance(value, Figure), f"a cell that draws does not show its figure:\n{source}"
        assert value.axes or value.artists  # something drawn
    out = namespace["out"]
    assert isinstance(out, Path) and out.parent == tmp_path
    assert (out / "api_tour_pattern.png").stat().st_size > 10_000
