"""Start-up stays light: the commands that do not compute never import the heavy libraries.

Not a timing test (speed targets are ratios in ``benchmarks/bench_startup.py``): it checks the
import graph in a fresh interpreter, where nothing imported by the test session can hide it.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = (
    "scipy",
    "matplotlib",
    "pandas",
    "pyarrow",
    "dask",
    "distributed",
    "shapely",
    "meshio",
    "numba",
    "gmsh",
)

PROBE = """
import contextlib, io, json, sys
heavy = {heavy!r}
argv = {argv!r}
import preform.cli
if argv is not None:
    sys.argv = ["preform", *argv]
    with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):
        preform.cli.main()
print(json.dumps(sorted(m for m in heavy if m in sys.modules)))
"""


@pytest.mark.parametrize(
    "argv",
    [None, ["--version"], ["--help"], ["materials", "list"]],
    ids=["import", "version", "help", "materials-list"],
)
def test_cli_start_up_imports_no_heavy_library(argv: list[str] | None) -> None:
    code = PROBE.format(heavy=HEAVY, argv=argv)
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    loaded = json.loads(done.stdout.strip().splitlines()[-1])
    assert loaded == [], f"imported at start-up: {loaded}"
