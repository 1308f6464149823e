"""What the command line says agrees with what there is (issue 26, item 7): an unknown scene
lists the bundled ones, a repeated --materials adds, ``materials list`` has a header and no
install paths, and the bundled scenes describe themselves without internal issue numbers."""

from __future__ import annotations

import json
import re
from pathlib import Path

from click.testing import CliRunner

from preform.cli import build_cli
from preform.library import bundled_library_dir
from preform.pipeline.scene import bundled_scene_dir

ROOT = Path(__file__).resolve().parents[2]


def invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(build_cli(), list(args), catch_exceptions=False)
    return result.exit_code, result.stdout, result.stderr


def test_an_unknown_scene_lists_the_bundled_scenes(tmp_path: Path) -> None:
    names = sorted(p.stem for p in bundled_scene_dir().glob("*.yaml"))
    for command in (
        ["pipeline", "run", "--scene", "nosuch", "--engine", "serial", "--out", str(tmp_path)],
        ["export", "E-BX-318", "vtu", "--scene", "nosuch", "--out", str(tmp_path)],
        ["scenes", "show", "nosuch"],
    ):
        code, _, err = invoke(*command)
        assert code == 2, command
        assert "'nosuch'" in err and all(name in err for name in names), (command, err)
    assert not any(tmp_path.iterdir())  # nothing was run


def test_a_repeated_materials_glob_adds(tmp_path: Path) -> None:
    code, out, err = invoke(
        "pipeline", "run", "--scene", "unit-cell", "--engine", "serial", "--out", str(tmp_path),
        "--materials", "plain-*", "--materials", "E-BX-318", "--json",
    )  # fmt: skip
    assert code == 0, err
    listed = json.loads(invoke("materials", "list", "--json")[1])
    want = {f["name"] for f in listed if f["name"].startswith("plain-")} | {"E-BX-318"}
    assert {case["material"] for case in json.loads(out)["cases"]} == want


def test_materials_list_has_a_header_and_no_install_path() -> None:
    code, out, _ = invoke("materials", "list")
    assert code == 0
    header, *rows = out.splitlines()
    assert header.split() == ["NAME", "ARCHITECTURE", "LIBRARY"]
    listed = json.loads(invoke("materials", "list", "--json")[1])
    assert [row.split()[0] for row in rows] == [f["name"] for f in listed]
    install = str(bundled_library_dir().resolve())
    assert install not in out and str(ROOT) not in out
    # each row names its bundled file and line, which --json gives in full
    for row, fabric in zip(rows, listed, strict=True):
        file, line, _ = fabric["origin"].rsplit(":", 2)
        assert row.split()[-1] == f"{Path(file).name}:{line}"
        assert Path(file).resolve().is_relative_to(bundled_library_dir().resolve())


def test_bundled_scenes_name_no_internal_issue() -> None:
    for path in bundled_scene_dir().glob("*.yaml"):
        assert not re.search(r"\bissues? \d+", path.read_text(), re.I), path.name
    code, out, _ = invoke("scenes", "list", "--json")
    assert code == 0 and not re.search(r"\bissues? \d+", out, re.I)
