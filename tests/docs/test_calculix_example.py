"""docs/examples/calculix_cap.md runs: its commands, preform's include it ships, its numbers.

The page's ``bash`` block is run line by line (``preform`` through the command line in this
process, ``ccx`` through the ``ccx`` fixture) in a folder holding the example's files but not
the shipped ``drape_calculix.inp``, which the ``preform export`` line must write again (data
lines equal to 1e-6, comments aside). The pole displacement ccx computes must be the one the
page's table gives (to its four digits).
"""

from __future__ import annotations

import re
import shlex
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
PAGE = EXAMPLES / "calculix_cap.md"


def data_lines(text: str) -> list[list[str]]:
    return [
        [f.strip() for f in line.split(",")]
        for line in text.splitlines()
        if line.strip() and not line.startswith("**")
    ]


def same_field(a: str, b: str) -> bool:
    try:
        return abs(float(a) - float(b)) <= 1e-6 * max(1.0, abs(float(b)))
    except ValueError:
        return a == b


def test_the_calculix_example_runs_as_its_page_says(tmp_path, monkeypatch, ccx) -> None:
    from preform.cli import build_cli

    for source in EXAMPLES.glob("calculix_cap*"):
        shutil.copy(source, tmp_path / source.name)
    monkeypatch.chdir(tmp_path)
    page = PAGE.read_text()
    commands = re.search(r"```bash\n(.*?)```", page, re.S)
    assert commands is not None
    ran = []
    for line in commands.group(1).splitlines():
        words = shlex.split(line)
        if words[0] == "preform":
            result = CliRunner().invoke(build_cli(), words[1:], catch_exceptions=False)
            assert result.exit_code == 0, result.output
        else:
            assert words[:2] == ["ccx", "-i"]
            ccx(tmp_path, words[2])
        ran.append(words[0])
    assert ran == ["preform", "ccx"]

    written = data_lines((tmp_path / "drape_calculix.inp").read_text())
    shipped = data_lines((EXAMPLES / "drape_calculix.inp").read_text())
    assert len(written) == len(shipped)
    for line, (got, want) in enumerate(zip(written, shipped, strict=True)):
        assert len(got) == len(want) and all(map(same_field, got, want)), (line, got, want)

    row = re.search(r"\| the mapped fibres \(this example\) \| (\S+) \| (\S+) \|", page)
    assert row is not None
    block = (tmp_path / "calculix_cap.dat").read_text().split("displacements")[-1]
    ux, uy = (float(v) for v in block.split()[-3:-1])
    assert ux == pytest.approx(float(row.group(1)), rel=1e-3)
    assert uy == pytest.approx(float(row.group(2)), rel=1e-3)
