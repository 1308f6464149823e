"""Start-up stays light: the commands that do not compute never import the heavy libraries.

Not a timing test (speed targets are ratios in ``benchmarks/bench_startup.py``): it checks the
import graph in a fresh interpreter, where nothing imported by the test session can hide it.
"""

from __future__ import annotations

import ast
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

#: preform's own modules that no start-up command imports: the step, search and export modules
#: (registered by import path, loaded when a run plans them) and the tool surfaces.
PREFORM_KEPT_OUT = (
    "preform.drape",
    "preform.optimise",
    "preform.export",
    "preform.pipeline.core_steps",
    "preform.pipeline.runner",
    "preform.plugins.surfaces.tools",
    "preform.plugins.surfaces.mesh",
    "preform.plugins.surfaces.cad",
    "preform.api",
)

#: What validating the library needs (``materials list``): pydantic, PyYAML and the models.
MODELS = (
    "pydantic",
    "yaml",
    "preform.material",
    "preform.library",
    "preform.shear",
    "preform.plugins.woven.model",
    "preform.plugins.warpknit.model",
)

#: What ``materials list`` does without (issue 15j): numpy (the checks a listing runs are plain
#: Python; numpy is imported where a cell, a law or a derived property is computed) and the
#: sheared cells.
ARRAYS = ("numpy", "preform.geometry.sheared_cell")

#: What ``--version`` and ``--help`` need neither of: numpy, pydantic and the fabric models
#: (``import preform`` serves its names lazily; architectures and laws register by import path).
MODELS_AND_ARRAYS = MODELS + ARRAYS

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


def _loaded(argv: list[str] | None, names: tuple[str, ...]) -> list[str]:
    probe = PROBE.replace(
        "m in sys.modules", "any(k == m or k.startswith(m + '.') for k in sys.modules)"
    )
    code = probe.format(heavy=names, argv=argv)
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    loaded: list[str] = json.loads(done.stdout.strip().splitlines()[-1])
    return loaded


@pytest.mark.parametrize(
    "argv",
    [None, ["--version"], ["--help"], ["materials", "list"]],
    ids=["import", "version", "help", "materials-list"],
)
def test_cli_start_up_imports_no_step_module(argv: list[str] | None) -> None:
    assert _loaded(argv, PREFORM_KEPT_OUT) == []


@pytest.mark.parametrize(
    "argv", [None, ["--version"], ["--help"]], ids=["import", "version", "help"]
)
def test_version_and_help_import_no_model_nor_numpy(argv: list[str] | None) -> None:
    assert _loaded(argv, MODELS_AND_ARRAYS) == []


def test_materials_list_imports_no_numpy() -> None:
    """Listing validates every bundled fabric (warp-knit cells fitted, polynomial laws checked
    for negative forces) without importing numpy."""
    assert _loaded(["materials", "list"], ARRAYS) == []


def test_the_probe_sees_what_a_command_imports() -> None:
    """The probe itself can fail: ``materials list`` validates fabrics, so it must see the
    models, pydantic and PyYAML loaded; ``materials show`` computes derived properties of a
    woven cell, its tows' jamming included (the sheared cell's tow families), so it must see
    numpy and the sheared cell."""
    assert _loaded(["materials", "list"], MODELS) == sorted(MODELS)
    assert _loaded(["materials", "show", "plain-weave-600"], ARRAYS) == sorted(ARRAYS)


def test_a_reader_leaving_the_pipe_is_not_reported_as_a_bug() -> None:
    """``preform materials list | head -1`` where ``head`` has left: a quiet end, not the
    "bug in preform" message (the reader here leaves before the first line is written)."""
    code = "import sys; from preform.cli import main; sys.argv = ['preform', *sys.argv[1:]]; main()"
    proc = subprocess.Popen(
        [sys.executable, "-c", code, "materials", "list"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None
    proc.stdout.close()  # the reader leaves at once
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1
    assert "bug" not in err and "Traceback" not in err, err


#: What ``materials list`` does without since issue 15l, though its modules hold them: the step
#: contract (steps register by import path), the generic unit cell and the crossover summary
#: (built for a run or a law, never for a listing), and the modules only a message or
#: ``--json`` needs.
LISTING_KEPT_OUT = (
    "preform.step",
    "preform.geometry.unit_cell",
    "preform.plugins.woven.crossover",
    "difflib",
    "json",
    "traceback",
)

AFTER_LISTING = """
import contextlib, io, sys
names = {names!r}
from preform.cli import main
sys.argv = ["preform", "materials", "list", *{extra!r}]
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    with contextlib.suppress(SystemExit):
        main()
{then}
print(sorted(n for n in names if n in sys.modules))
"""


def _after_listing(extra: list[str], then: str = "") -> list[str]:
    """Which of ``LISTING_KEPT_OUT`` are imported after ``materials list EXTRA`` (and the code
    ``then``) in a fresh interpreter; printed as a Python list so the probe imports no json."""
    code = AFTER_LISTING.format(names=LISTING_KEPT_OUT, extra=extra, then=then)
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    loaded: list[str] = ast.literal_eval(done.stdout.strip().splitlines()[-1])
    return loaded


def test_materials_list_imports_only_what_a_listing_uses() -> None:
    assert _after_listing([]) == []


def test_the_listing_probe_sees_each_module_where_it_is_used(tmp_path) -> None:
    """Each module kept out is imported by the work that needs it, so the probe can fail."""
    cell_and_law = """
from preform.library import load_library
lib = load_library()
lib.fabric("plain-weave-600").unit_cell()
lib.shear_law("plain-weave-600")
lib.registry.step("drape")
"""
    assert _after_listing([], cell_and_law) == [
        "preform.geometry.unit_cell",
        "preform.plugins.woven.crossover",
        "preform.step",
    ]
    assert _after_listing(["--json"]) == ["json"]
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\narchitecture: wovn\nsource: s\nnote: n\n", encoding="utf-8")
    assert _after_listing(["--library", str(bad)]) == ["difflib"]
    broken = "import preform.plugin_manager as pm; pm._short_error(ValueError('x'))"
    assert _after_listing([], broken) == ["traceback"]
