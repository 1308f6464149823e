"""One grammar for every command (issue 16): each command's --help, its --json (one JSON
document on stdout, nothing else) and one error path (a clean message, a non-zero exit code, no
traceback). A command added without an entry in COMMANDS fails ``test_every_command_is_covered``.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from preform.cli import build_cli, cli

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "docs" / "examples"

#: Per command: arguments that print JSON (the run succeeds), and arguments that fail, with
#: the exit code and a fragment of the message on stderr. ``{tmp}`` is a fresh folder holding
#: the files of docs/examples/.
COMMANDS: dict[str, dict[str, object]] = {
    "plugins list": {
        "json": ["plugins", "list", "--json"],
        "error": (["plugins", "list", "--nosuch"], 2, "No such option"),
    },
    "materials list": {
        "json": ["materials", "list", "--json", "--library", "{tmp}/my-fabrics.yaml"],
        "error": (["materials", "list", "--library", "{tmp}/broken.yaml"], 2, "broken.yaml:"),
    },
    "materials show": {
        "json": ["materials", "show", "plain-weave-600", "--json"],
        "error": (["materials", "show", "plain-weave-60"], 2, "did you mean"),
    },
    "materials validate": {
        "json": ["materials", "validate", "{tmp}/my-fabrics.yaml", "--json"],
        "error": (["materials", "validate", "{tmp}/broken.yaml"], 1, "broken.yaml:"),
    },
    "view": {
        "json": ["view", "plain-weave-150", "--out", "{tmp}/cell.png", "--json"],
        "error": (["view", "nosuch"], 2, "no fabric named 'nosuch'"),
    },
    "schema": {
        "json": ["schema"],
        "error": (["schema", "--scene", "extra"], 2, "unexpected extra argument"),
    },
    "pipeline run": {
        "json": [
            "pipeline", "run", "--scene", "shear", "--materials", "plain-weave-150",
            "--engine", "serial", "--out", "{tmp}/run", "--json",
        ],
        "error": (["pipeline", "run", "--scene", "nosuch", "--out", "{tmp}/r"], 2, "nosuch"),
    },
    "export": {
        "json": [
            "export", "plain-weave-150", "abaqus", "cut-pattern", "--scene",
            "hemisphere-export", "--out", "{tmp}/export", "--json",
        ],
        "error": (["export", "nosuch", "abaqus"], 2, "no fabric named 'nosuch'"),
    },
    "scenes list": {
        "json": ["scenes", "list", "--json"],
        "error": (["scenes", "list", "extra"], 2, "unexpected extra argument"),
    },
    "scenes show": {
        "json": ["scenes", "show", "hemisphere", "--json"],
        "error": (["scenes", "show", "nosuch"], 2, "no bundled scene of that name"),
    },
    "scenes outputs": {
        "json": ["scenes", "outputs", "--json"],
        "error": (["scenes", "outputs", "--nosuch"], 2, "No such option"),
    },
    "shear": {
        "json": ["shear", "E-BX-318", "--json", "--out", "{tmp}/shear.png"],
        "error": (["shear", "nosuch"], 2, "no fabric named 'nosuch'"),
    },
    "fit": {
        "json": [
            "fit", "{tmp}/frame.csv", "--test", "picture-frame", "--side-mm", "150",
            "--out", "{tmp}/law.yaml", "--plot", "{tmp}/fit.png", "--json",
        ],
        "error": (["fit", "{tmp}/frame.csv", "--test", "picture-frame"], 2, "--side-mm"),
    },
    "calibrate": {
        "json": [
            "calibrate", "plain-weave-600", "{tmp}/frame.csv", "--test", "picture-frame",
            "--side-mm", "150", "--param", "shear_law.pretension_N", "--max-angle-deg", "35",
            "--out", "{tmp}/calibrated.yaml", "--json",
        ],
        "error": (
            ["calibrate", "plain-weave-600", "{tmp}/frame.csv", "--test", "picture-frame",
             "--side-mm", "150", "--param", "shear_law.nosuch"],
            2, "unknown constant path 'shear_law.nosuch'",
        ),
    },
    "compare": {
        "json": ["compare", "plain-weave-600", "{tmp}/measured_hemisphere.csv", "--json"],
        "error": (["compare", "plain-weave-600", "{tmp}/frame.csv"], 2, "x_mm, y_mm, z_mm"),
    },
    "validate": {
        "json": ["validate", "--out", "{tmp}/validation", "--json"],
        "error": (["validate", "--nosuch"], 2, "No such option"),
    },
    "report": {
        # docs/examples/results.csv makes {tmp} a run folder (a table and no case folders)
        "json": ["report", "{tmp}", "--json"],
        "error": (["report", "{tmp}/nosuch"], 2, "is not a directory"),
    },
    "bench tradeoff": {
        "json": ["bench", "tradeoff", "--quick", "--out", "{tmp}/bench", "--json"],
        "error": (["bench", "tradeoff", "--material", "nosuch"], 2, "nosuch"),
    },
}  # fmt: skip


def leaf_commands(group: click.Group, prefix: str = "") -> dict[str, click.Command]:
    out: dict[str, click.Command] = {}
    ctx = click.Context(group)
    for name in group.list_commands(ctx):  # click's API: lazy commands are loaded here
        command = group.get_command(ctx, name)
        assert command is not None, name
        path = f"{prefix} {name}".strip()
        if isinstance(command, click.Group):
            out.update(leaf_commands(command, path))
        else:
            out[path] = command
    return out


@pytest.fixture
def workdir(tmp_path: Path) -> Path:
    for source in EXAMPLES.iterdir():
        shutil.copy(source, tmp_path / source.name)
    (tmp_path / "broken.yaml").write_text("- name: x\n  architecture: woven\n  weave: [\n")
    return tmp_path


def invoke(args: list[str], tmp: Path) -> click.testing.Result:
    filled = [a.replace("{tmp}", str(tmp)) for a in args]
    return CliRunner().invoke(cli, filled, catch_exceptions=False)


def test_every_command_is_covered():
    """Built-in commands; a plugin's commands are the plugin's to test."""
    assert set(leaf_commands(cli)) == set(COMMANDS)
    assert set(leaf_commands(build_cli())) >= set(COMMANDS)


@pytest.mark.parametrize("path", sorted(COMMANDS))
def test_help(path: str):
    result = CliRunner().invoke(cli, [*path.split(), "--help"])
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith("Usage: ") and len(result.stdout) > 100


@pytest.mark.parametrize("path", sorted(COMMANDS))
def test_json_is_the_only_thing_on_stdout(path: str, workdir: Path):
    result = invoke(COMMANDS[path]["json"], workdir)  # type: ignore[arg-type]
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)  # the whole of stdout is one JSON document
    assert doc


@pytest.mark.parametrize("path", sorted(COMMANDS))
def test_error_is_a_clean_message(path: str, workdir: Path):
    args, code, fragment = COMMANDS[path]["error"]  # type: ignore[misc]
    result = invoke(args, workdir)
    assert result.exit_code == code, (result.stdout, result.stderr)
    assert fragment in result.stderr
    assert "Traceback" not in result.stdout + result.stderr
    assert result.stdout == ""


def test_every_command_that_prints_results_has_json():
    """schema prints JSON and nothing else anyway; every other command offers --json."""
    for path, command in leaf_commands(cli).items():
        names = {o for p in command.params for o in getattr(p, "opts", [])}
        assert path == "schema" or "--json" in names, path


def test_library_options_are_everywhere_a_library_is_read():
    for path in ("materials list", "materials show", "view", "shear", "pipeline run",
                 "bench tradeoff"):  # fmt: skip
        command = leaf_commands(cli)[path]
        names = {o for p in command.params for o in getattr(p, "opts", [])}
        assert {"--library", "--no-bundled"} <= names, path


def test_out_says_whether_it_is_a_file_or_a_directory():
    for path, command in leaf_commands(cli).items():
        for param in command.params:
            if "--out" in getattr(param, "opts", []):
                assert param.metavar in ("FILE", "DIR"), path
                assert isinstance(param.type, click.Path)
                # a file option refuses a directory (a run directory checks itself: a file
                # there is refused with "nothing was run", tests/hostile)
                if param.metavar == "FILE":
                    assert not param.type.dir_okay, path


def test_an_unexpected_error_is_one_line_and_exit_3_unless_debug(monkeypatch):
    import preform.commands.scenes as scenes

    def broken() -> list:
        raise RuntimeError("the sky fell")

    monkeypatch.setattr(scenes, "bundled_scenes", broken)
    result = CliRunner().invoke(cli, ["scenes", "list"])
    assert result.exit_code == 3
    assert "error: RuntimeError: the sky fell" in result.stderr
    assert "--debug" in result.stderr and "Traceback" not in result.stderr
    debug = CliRunner().invoke(cli, ["--debug", "scenes", "list"])
    assert isinstance(debug.exception, RuntimeError)  # raised: Python prints the traceback
    monkeypatch.setenv("PREFORM_DEBUG", "1")
    assert isinstance(CliRunner().invoke(cli, ["scenes", "list"]).exception, RuntimeError)


def test_exit_codes_are_documented_where_users_look():
    readme = (ROOT / "README.md").read_text()
    help_text = CliRunner().invoke(cli, ["--help"]).stdout
    for code in ("0", "1", "2", "3", "130"):
        assert f"\n    {code} " in help_text
        assert f"| {code} |" in readme


# -- what the options do ----------------------------------------------------------------------


def run_json(args: list[str], tmp: Path, code: int = 0) -> object:
    result = invoke(args, tmp)
    assert result.exit_code == code, result.stderr
    return json.loads(result.stdout)


def test_library_arguments_add_to_the_bundled_library_and_no_bundled_leaves_it_out(workdir):
    mine = str(workdir / "my-fabrics.yaml")
    common = ["--scene", "unit-cell", "--engine", "serial", "--json"]
    added = run_json(["pipeline", "run", mine, *common, "--out", f"{workdir}/a"], workdir)
    names = {c["material"] for c in added["cases"]}  # type: ignore[index]
    assert "my-plain-weave" in names and "plain-weave-600" in names
    only = run_json(
        ["pipeline", "run", "--library", mine, "--no-bundled", *common, "--out", f"{workdir}/b"],
        workdir,
    )
    assert [c["material"] for c in only["cases"]] == ["my-plain-weave"]  # type: ignore[index]
    listed = run_json(["materials", "list", "--no-bundled", "--library", mine, "--json"], workdir)
    assert [m["name"] for m in listed] == ["my-plain-weave"]  # type: ignore[index]


def test_fidelity_replaces_the_preset_is_recorded_and_changes_the_input_hash(workdir):
    out = workdir / "run"
    args = ["pipeline", "run", "--scene", "hemisphere", "--materials", "plain-weave-150",
            "--engine", "serial", "--out", str(out), "--json"]  # fmt: skip
    first = run_json(args, workdir)
    assert first["cases"][0]["status"] == "ok"  # type: ignore[index]
    summary_file = out / "hemisphere" / "plain-weave-150" / "summary.json"
    standard = json.loads(summary_file.read_text())
    draft_run = run_json([*args, "--fidelity", "draft"], workdir)
    case = draft_run["cases"][0]  # type: ignore[index]
    assert case["kept_from_earlier_run"] is False  # not the standard result again
    draft = json.loads(summary_file.read_text())
    assert (standard["fidelity"], draft["fidelity"]) == ("standard", "draft")
    assert draft["input_hash"] != standard["input_hash"]
    # the hemisphere scene sets its node spacing by hand: that knob keeps its value
    assert draft["knob_node_spacing_mm"] == standard["knob_node_spacing_mm"] == 2.5
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["runs"][-1]["inputs"]["fidelity_override"] == "draft"


def test_pipeline_run_json_lists_each_case_with_its_status_in_words(workdir):
    doc = run_json(
        ["pipeline", "run", "--scene", "shear", "--materials", "E-BX*", "--engine", "serial",
         "--out", f"{workdir}/r", "--json"],
        workdir,
    )  # fmt: skip
    assert doc["exit_code"] == 0 and doc["counts"] == {"ok": 2}  # type: ignore[index]
    assert doc["status_meaning"]["ok"] == "complete, finite and physical"  # type: ignore[index]
    for case in doc["cases"]:  # type: ignore[index]
        assert {"status", "reasons", "warnings", "error", "covered_fraction"} <= set(case)


def test_materials_show_rounds_derived_values_in_text_only(workdir):
    import re

    text = invoke(["materials", "show", "plain-weave-600"], workdir).stdout
    derived = text.split("derived:\n", 1)[1]
    digits = [len(m.replace(".", "").lstrip("0")) for m in re.findall(r"\d+\.\d+", derived)]
    assert digits and max(digits) <= 4
    full = run_json(["materials", "show", "plain-weave-600", "--json"], workdir)
    assert any(
        len(repr(v)) > 8
        for v in full["derived"].values()
        if isinstance(v, float)  # type: ignore[index]
    )


def test_fit_says_it_forces_zero_and_can_fit_an_intercept(workdir):
    import yaml

    base = ["fit", str(workdir / "frame.csv"), "--test", "picture-frame", "--side-mm", "150"]
    forced = run_json([*base, "--json"], workdir)
    assert forced["through_zero"] is True  # type: ignore[index]
    assert forced["shear_law"]["force_coefficients_N_per_mm"][0] == 0.0  # type: ignore[index]
    assert any("forced through zero" in c for c in forced["comments"])  # type: ignore[index]
    free = run_json([*base, "--free-intercept", "--json"], workdir)
    intercept = free["shear_law"]["force_coefficients_N_per_mm"][0]  # type: ignore[index]
    assert intercept != 0.0
    # the forced fit reported the constant a free fit finds
    reported = forced["senses"]["parallel"]["free_intercept_N_per_mm"]  # type: ignore[index]
    assert reported == pytest.approx(intercept)
    # with --out: the block goes to the file only, and --plot draws the fit against the data
    result = invoke([*base, "--out", str(workdir / "law.yaml"), "--plot", str(workdir / "f.png")],
                    workdir)  # fmt: skip
    assert "shear_law" not in result.stdout and "wrote" in result.stdout
    assert yaml.safe_load((workdir / "law.yaml").read_text())["shear_law"]["law"] == "polynomial"
    assert (workdir / "f.png").read_bytes()[:4] == b"\x89PNG"
