"""A plugin's step owns its scene section the way preform's own steps own theirs.

The test plugin below registers (by import path, as the built-in plugins do) a step that
declares a ``stamp`` section: its pydantic model and a check of what the model cannot say. A
scene holding it is validated through the registry like ``search`` is: the same located errors
for a bad type and an unknown key (with a did-you-mean), the check's problem at its key, an
unknown top-level key refused with the declared sections among the choices; and the validated
section reaches the step when a case runs.
"""

from __future__ import annotations

import importlib
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

from preform import Step, hookimpl
from preform.pipeline.runner import make_cases, run_cases
from preform.pipeline.scene import SceneError, load_scene
from preform.registry import LazyLoadError, NameConflict

STAMP_STEPS = """
from pydantic import BaseModel, ConfigDict, Field

from preform import Step

PAD_ML = 10.0


class StampSection(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)
    min_coverage: float = Field(gt=0, description="A name shared with search's, to compare.")
    ink_ml: float = Field(default=1.0, gt=0, description="Ink of one stamp [ml].")
    repeats: int = Field(default=1, ge=1, description="Stamps per case [-].")


def stamp_problems(scene, doc, registry):
    stamp = scene.section("stamp")
    if stamp.ink_ml * stamp.repeats <= PAD_ML:
        return []
    return [doc.error(("stamp", "repeats"), f"{stamp.repeats} stamps need more than the pad")]


def run_stamp(ctx):
    stamp = ctx.scene.section("stamp")
    ctx.summary["stamp_ink_ml"] = stamp.ink_ml * stamp.repeats
    return {"stamp": stamp.ink_ml * stamp.repeats}


STAMP = Step(
    "stamp", ("stamp",), (), "1", run_stamp,
    scene_sections=("stamp",), sections={"stamp": StampSection}, check=stamp_problems,
)
LIAR = Step("liar", ("liar",), (), "1", run_stamp)
"""


#: The plugin's hooks: the step is registered by import path, so its module (and the section's
#: model) loads only when a scene holds the section or a plan needs the step.
STAMP_PLUGIN = """
from preform import hookimpl


@hookimpl
def preform_register_steps(register):
    register.add_lazy("stamp", provides=["stamp"], target="stampsteps:STAMP", sections=["stamp"])
"""


@pytest.fixture
def sandbox(preform_plugins, third_party_site):
    # in the site, whose folder worker processes have on their path too
    (third_party_site / "stampsteps.py").write_text(textwrap.dedent(STAMP_STEPS))
    (third_party_site / "stampplug.py").write_text(STAMP_PLUGIN)
    preform_plugins.load_builtins("core", "surfaces")
    preform_plugins.register(importlib.import_module("toyplug"), "toy")
    record = preform_plugins.register(importlib.import_module("stampplug"), "stamp")
    assert record.error is None, record.error
    yield preform_plugins
    for module in ("stampplug", "stampsteps"):
        sys.modules.pop(module, None)


def scene_errors(tmp_path: Path, text: str, registry: Any) -> list[tuple[int, int, str, str]]:
    """(line, column, field, message) of each error of the scene ``text``, in file order."""
    path = tmp_path / "scene.yaml"
    path.write_text(textwrap.dedent(text))
    with pytest.raises(SceneError) as info:
        load_scene(path, registry)
    return sorted((e.line, e.column, e.path, e.message) for e in info.value.errors)


def test_a_bad_value_is_located_and_said_as_for_a_builtin_section(sandbox, tmp_path):
    found = scene_errors(
        tmp_path,
        """\
        name: s
        search:
          min_coverage: lots
        stamp:
          min_coverage: lots
        outputs: [stamp]
        """,
        sandbox.registry,
    )
    ((line_b, col_b, field_b, said_b), (line_p, col_p, field_p, said_p)) = found
    assert (line_b, col_b, field_b) == (3, 17, "search.min_coverage")  # at the value
    assert (line_p, col_p, field_p) == (5, 17, "stamp.min_coverage")
    assert said_p == said_b and "valid number" in said_p


def test_an_unknown_key_gets_the_same_did_you_mean(sandbox, tmp_path):
    found = scene_errors(
        tmp_path,
        """\
        name: s
        search:
          min_coverag: 0.5
        stamp:
          min_coverage: 1
          ink_mll: 1
        outputs: [stamp]
        """,
        sandbox.registry,
    )
    assert found == [
        (3, 3, "search.min_coverag", "unknown field 'min_coverag'; did you mean 'min_coverage'?"),
        (6, 3, "stamp.ink_mll", "unknown field 'ink_mll'; did you mean 'ink_ml'?"),
    ]


def test_the_steps_check_is_located_and_an_unknown_section_names_the_declared_ones(
    sandbox, tmp_path
):
    found = scene_errors(
        tmp_path,
        """\
        name: s
        stamp:
          min_coverage: 1
          ink_ml: 4
          repeats: 3
        outputs: [stamp]
        """,
        sandbox.registry,
    )
    assert found == [(5, 3, "stamp.repeats", "3 stamps need more than the pad")]
    found = scene_errors(tmp_path, "name: s\nstmp: {}\noutputs: [stamp]\n", sandbox.registry)
    assert found == [(2, 1, "stmp", "unknown field 'stmp'; did you mean 'stamp'?")]
    (*_, said) = scene_errors(tmp_path, "name: s\nzzz: 1\noutputs: [stamp]\n", sandbox.registry)[0]
    assert said.startswith("unknown field 'zzz'; allowed fields: ") and "stamp, start" in said


def test_the_section_reaches_the_step_and_its_module_loads_only_when_needed(sandbox, tmp_path):
    (tmp_path / "lib.yaml").write_text(
        "- {name: felt, architecture: toy, source: s, note: n, areal_density_g_m2: 100}\n"
    )
    library = sandbox.library([tmp_path / "lib.yaml"])
    plain = tmp_path / "plain.yaml"
    plain.write_text("name: plain\noutputs: [mass]\n")
    load_scene(plain, sandbox.registry)
    assert "stampsteps" not in sys.modules  # a scene without the section imports nothing
    path = tmp_path / "stamped.yaml"
    path.write_text("name: stamped\nstamp: {min_coverage: 1, ink_ml: 2.5, repeats: 3}\n")
    path.write_text(path.read_text() + "outputs: [stamp]\n")
    loaded = load_scene(path, sandbox.registry)
    assert loaded[0].section("stamp").repeats == 3 and loaded[0].section("search") is None
    out = tmp_path / "out"
    for engine in ("serial", "process"):
        report = run_cases(make_cases(library, [loaded], out / engine, sandbox.host),
                           out / engine, sandbox.host, engine=engine)  # fmt: skip
        (result,) = report.results
        assert result.status == "ok", result.error
        assert result.results["stamp_ink_ml"] == pytest.approx(7.5)


class Squatter:
    """A plugin step claiming a section a built-in step owns."""

    @hookimpl
    def preform_register_steps(self, register: Any) -> None:
        register.add(Step("squat", ("squat",), (), "1", _run, sections={"search": None}))


def _run(ctx: Any) -> dict[str, Any]:
    return {"squat": 1}


class Liar:
    """A plugin step declaring at registration a section its step does not own."""

    @hookimpl
    def preform_register_steps(self, register: Any) -> None:
        register.add_lazy("liar", provides=["liar"], target="stampsteps:LIAR", sections=["x"])


def test_a_section_has_one_owner_and_a_lazy_step_owns_what_it_declared(sandbox):
    record = sandbox.register(Squatter(), "squatter")
    assert record.error is not None and "scene section 'search'" in record.error
    assert "owned by step 'optimum'" in record.error
    with pytest.raises(NameConflict, match="scene section 'stamp' is already owned"):
        from preform.registry import StepRegistrar

        StepRegistrar(sandbox.registry, "other", "1").add_lazy(
            "other", provides=["other"], target="m:X", sections=["stamp"]
        )
    sandbox.register(Liar(), "liar")
    with pytest.raises(LazyLoadError, match=r"owning the scene sections \['x'\]"):
        sandbox.registry.step("liar")


def test_a_layups_plies_carry_the_plugin_sections(sandbox, tmp_path):
    """Each ply of a layup is a drape scene of its own (preform.stack.plies): a plugin step
    among the ply outputs reads its section there as in the layup's scene."""
    from preform.stack.plies import ply_scene

    path = tmp_path / "stack.yaml"
    path.write_text(
        textwrap.dedent(
            """\
            name: stamped-stack
            tool: {surface: hemisphere, radius_mm: 100}
            stamp: {min_coverage: 1, ink_ml: 2.5, repeats: 3}
            layup:
              plies:
                - {fabric: felt, orientation_deg: 0}
                - {fabric: felt, orientation_deg: 90}
              ply_outputs: [stamp]
            outputs: [layup]
            """
        )
    )
    scene, _ = load_scene(path, sandbox.registry)
    for k in range(2):
        ply = ply_scene(scene, k, sandbox.registry)
        assert ply.section("stamp") == scene.section("stamp")
        assert ply.section("stamp").repeats == 3


def test_the_scene_schema_holds_the_plugin_sections(sandbox):
    """`preform schema --scene` lists a plugin step's section with its model's fields; the scene
    schema forbids unknown keys, so without it an editor would flag the section as wrong."""
    from preform.schema import scene_schema

    schema = scene_schema(sandbox.registry)
    assert schema.get("additionalProperties") is False
    stamp = schema["properties"]["stamp"]
    (ref,) = [s["$ref"] for s in stamp["anyOf"] if "$ref" in s]
    model = schema["$defs"][ref.rsplit("/", 1)[-1]]
    assert set(model["properties"]) == {"min_coverage", "ink_ml", "repeats"}
    assert model["properties"]["repeats"]["minimum"] == 1
