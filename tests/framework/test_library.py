"""The materials library: every error at once, each at FILE:LINE:COL with a field path."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from preform.library import LibraryError

GOOD = """\
- name: felt-a
  architecture: toy
  source: test fixture
  note: illustrative
  areal_density_g_m2: 300
- name: felt-b
  architecture: toy
  source: test fixture
  note: illustrative
  areal_density_g_m2: 450
  width_mm: 2
"""


@pytest.fixture
def toy(preform_plugins, third_party_site):
    import toyplug

    preform_plugins.register(toyplug, "toy")
    return preform_plugins


def write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


def errors_of(toy, *paths) -> list[str]:
    with pytest.raises(LibraryError) as info:
        toy.library(list(paths))
    return [str(e) for e in info.value.errors]


def test_good_library_loads(toy, tmp_path):
    lib = toy.library([write(tmp_path, "good.yaml", GOOD)])
    assert lib.names() == ["felt-a", "felt-b"]
    assert lib.fabric("felt-b").width_mm == 2
    assert str(lib.origins["felt-b"]).endswith("good.yaml:6:9")


def test_every_error_is_reported_with_its_position(toy, tmp_path):
    bad = write(
        tmp_path,
        "bad.yaml",
        """\
        - name: one
          architecture: toy
          source: s
          note: n
          areal_density_g_m2: -3
          colour: red
        - name: two
          architecture: tow
          source: s
          note: n
        - name: three
          architecture: toy
          note: n
          areal_density_g_m2: 10
        - name: four
          architecture: toy
          source: s
          note: n
          areal_density_g_m2: 10
          width_mm: 500
        """,
    )
    errs = errors_of(toy, bad)
    f = str(bad)
    assert f"{f}:5:23: one.areal_density_g_m2: Input should be greater than 0" in errs
    assert any(e.startswith(f"{f}:6:3: one.colour: unknown field 'colour'") for e in errs)
    unknown_arch = [e for e in errs if e.startswith(f"{f}:8:17: two.architecture:")]
    assert unknown_arch and "did you mean 'toy'" in unknown_arch[0]
    assert "registered architectures: toy" in unknown_arch[0]
    assert f"{f}:11:3: three.source: required field is missing" in errs
    assert f"{f}:20:13: four.width_mm: width_mm must not exceed 100 for a toy" in errs
    assert len(errs) == 5


def test_duplicate_names_across_files(toy, tmp_path):
    a = write(tmp_path, "a.yaml", GOOD)
    b = write(
        tmp_path,
        "b.yaml",
        """\
        name: felt-a
        architecture: toy
        source: s
        note: n
        areal_density_g_m2: 1
        """,
    )
    errs = errors_of(toy, a, b)
    assert len(errs) == 1
    assert errs[0].startswith(f"{b}:1:7: felt-a.name: duplicate fabric name 'felt-a'")
    assert f"{a}:1:9" in errs[0]


@pytest.mark.parametrize(
    ("text", "position", "needle"),
    [
        ("- name: x\n  name: y\n", "2:3", "duplicate key"),
        ("- !!python/object:os.system {}\n", "1:3", "tag"),
        ("- name: x\n  areal_density_g_m2: .nan\n", "2:23", "finite"),
        ("- [unclosed\n", "2:1", ""),
        ("", "1:1", "empty"),
    ],
)
def test_yaml_level_errors(toy, tmp_path, text, position, needle):
    p = tmp_path / "broken.yaml"
    p.write_text(text)
    errs = errors_of(toy, p)
    assert any(e.startswith(f"{p}:{position}:") and needle in e for e in errs), errs


def test_non_utf8_and_missing_files(toy, tmp_path):
    p = tmp_path / "latin1.yaml"
    p.write_bytes("- name: caf\xe9\n".encode("latin-1"))
    missing = tmp_path / "nope.yaml"
    errs = errors_of(toy, p, missing)
    assert any(e.startswith(str(p)) and "UTF-8" in e for e in errs), errs
    assert any(e.startswith(str(missing)) for e in errs)


def test_material_lint_hook_warnings(toy, tmp_path):
    p = write(
        tmp_path,
        "heavy.yaml",
        """\
        name: brick
        architecture: toy
        source: s
        note: n
        areal_density_g_m2: 9000
        """,
    )
    lib = toy.library([p])
    assert any("suspiciously heavy" in str(w) for w in lib.warnings)


def test_cli_validate_reports_and_exits_nonzero(toy, tmp_path):
    from click.testing import CliRunner

    from preform.cli import cli

    good = write(tmp_path, "good.yaml", GOOD)
    bad = write(tmp_path, "bad.yaml", "- name: z\n  architecture: nope\n  source: s\n  note: n\n")
    ok = CliRunner().invoke(cli, ["materials", "validate", str(good)])
    assert ok.exit_code == 0 and "2 fabric(s) valid" in ok.output
    res = CliRunner().invoke(cli, ["materials", "validate", str(good), str(bad)])
    assert res.exit_code == 1
    assert f"{bad}:2:17: z.architecture: unknown architecture 'nope'" in res.output
    assert "Traceback" not in res.output


def test_preform_library_environment_adds_directories(toy, tmp_path, monkeypatch):
    import os

    from preform.library import load_library

    first, second = tmp_path / "lab-a", tmp_path / "lab-b"
    first.mkdir()
    second.mkdir()
    write(first, "a.yaml", GOOD)
    write(
        second,
        "b.yml",
        "name: felt-z\narchitecture: toy\nsource: s\nnote: n\nareal_density_g_m2: 5\n",
    )
    monkeypatch.setenv("PREFORM_LIBRARY", f"{first}{os.pathsep}{second}")
    lib = load_library(bundled=False, registry=toy.registry)
    assert sorted(lib.names()) == ["felt-a", "felt-b", "felt-z"]
    # the environment's fabrics clash with the same names given again on the command line
    with pytest.raises(LibraryError, match="duplicate fabric name 'felt-a'"):
        load_library([first / "a.yaml"], bundled=False, registry=toy.registry)


# -- value checks a third-party architecture gets without asking ------------------------------


def test_a_plugin_architecture_gets_finite_and_boolean_checks(toy, tmp_path):
    """The toy fabric derives from FabricBase and declares plain floats: ``inf`` written as
    text and ``true`` (read as 1 before) are refused where they stand."""
    bad = write(
        tmp_path,
        "bad.yaml",
        """\
        - name: felt-inf
          architecture: toy
          source: s
          note: n
          areal_density_g_m2: Infinity
        - name: felt-bool
          architecture: toy
          source: s
          note: n
          areal_density_g_m2: 300
          width_mm: yes
        """,
    )
    errors = errors_of(toy, bad)
    assert len(errors) == 2, errors
    assert errors[0].startswith(f"{bad}:5:23: felt-inf.areal_density_g_m2: non-finite number")
    assert errors[1].startswith(f"{bad}:11:13: felt-bool.width_mm: true is a boolean")


RANGED_PLUGIN = """
from typing import Annotated, Literal

from pydantic import Field

from preform import FabricBase, hookimpl
from preform.material import ParamsModel, Plausible, size_limit

FELT_THICKNESS = Plausible(0.1, 50.0, "mm", "a felt thickness", "felts are 0.5-20 mm thick")


class Layer(ParamsModel):
    thickness_mm: Annotated[float, FELT_THICKNESS] = Field(gt=0)


class RangedFelt(FabricBase):
    architecture: Literal["ranged"]
    layers: Annotated[list[Layer], size_limit("tow_layers")]


@hookimpl
def preform_register_architectures(register):
    register.add(RangedFelt)
"""


@pytest.fixture
def ranged(preform_plugins, tmp_path):
    """A third-party architecture that only marks its field with a Plausible range."""
    import importlib.util

    path = tmp_path / "rangedplug.py"
    path.write_text(RANGED_PLUGIN)
    spec = importlib.util.spec_from_file_location("rangedplug", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    preform_plugins.register(module, "ranged")
    return preform_plugins


RANGED = """\
- name: thick-felt
  architecture: ranged
  source: s
  note: n
  layers:
    - thickness_mm: 2.0
    - thickness_mm: 2000
"""


def test_a_plugin_architecture_gets_plausible_ranges_and_overrides(ranged, tmp_path):
    path = write(tmp_path, "felt.yaml", RANGED)
    errors = errors_of(ranged, path)
    assert errors == [
        f"{path}:7:21: thick-felt.layers[1].thickness_mm: thickness_mm = 2000 is outside the "
        "plausible range 0.1–50 mm for a felt thickness; was it given in µm? (range: felts are "
        "0.5-20 mm thick). If the value is right, add 'layers[1].thickness_mm' to this entry's "
        "accept_out_of_range"
    ]
    path = write(
        tmp_path, "felt.yaml", RANGED + "  accept_out_of_range: ['layers[1].thickness_mm']\n"
    )
    lib = ranged.library([path])
    assert lib.fabric("thick-felt").accept_out_of_range == ("layers[1].thickness_mm",)
    assert [str(w) for w in lib.warnings] == [
        f"{path}:7:21: thick-felt.layers[1].thickness_mm: thickness_mm = 2000 is outside the "
        "plausible range 0.1–50 mm for a felt thickness; accepted by override "
        "(accept_out_of_range)"
    ]
