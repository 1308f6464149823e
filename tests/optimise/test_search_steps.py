"""The minimum-energy pipeline steps: knobs, the bundled scene, a run with the library-wide
figure, and the optional stages (layout, curved generators, relaxation) in a case."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from pydantic import ValidationError

from preform.optimise import search_steps
from preform.optimise.search_steps import EXPORTERS, STEPS, search_knobs
from preform.pipeline.runner import make_cases, run_cases
from preform.pipeline.scene import Scene, bundled_scene_dir, load_scene
from preform.plugin_manager import hookimpl
from preform.step import CaseContext

ISSUE_SCENE = """\
name: hemisphere-min-energy
tool:
  surface: hemisphere
  radius_mm: 100
ply:
  node_spacing_mm: 2.5
  size_mm: [360, 360]
start:
  point_mm: [0, 0]
  orientation_deg: 0
search:
  generator_angle_deg: {min: 30, max: 150}
outputs: [energy_vs_angle, optimum, fibre_pattern_png, library_energy_png, cells_csv]
"""


class SearchStepsPlugin:
    """Registers this module's steps, as core/builtin.py will."""

    @hookimpl
    def preform_register_steps(self, register: Any) -> None:
        for step in STEPS:
            register.add(step)

    @hookimpl
    def preform_register_exporters(self, register: Any) -> None:
        for step in EXPORTERS:
            register.add(step)


@pytest.fixture
def sandbox(preform_plugins):
    preform_plugins.load_builtins()
    if "energy_vs_angle" not in preform_plugins.registry.names("steps"):
        preform_plugins.register(SearchStepsPlugin(), name="search-steps")
    return preform_plugins


def run_scene(sandbox, path: Path, materials: str, out: Path):
    """Run the scene at ``path`` over the bundled fabrics matching ``materials``, serially."""
    scene = load_scene(path, sandbox.registry)
    lib = sandbox.library(bundled=True)
    return run_cases(
        make_cases(lib, [scene], out, sandbox.host, materials_glob=materials),
        out,
        sandbox.host,
        engine="serial",
    )


def coarse_scene(tmp_path: Path, **search: Any) -> Path:
    data = yaml.safe_load(ISSUE_SCENE)
    data["ply"]["node_spacing_mm"] = 10
    data["search"].update(search)
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_bundled_scene_is_the_issues():
    path = bundled_scene_dir() / "hemisphere-min-energy.yaml"
    assert yaml.safe_load(path.read_text()) == yaml.safe_load(ISSUE_SCENE)


def test_bundled_scene_plans(sandbox):
    scene, _ = load_scene(bundled_scene_dir() / "hemisphere-min-energy.yaml", sandbox.registry)
    assert scene.search is not None


def test_knob_defaults_and_overrides():
    base = {"name": "s", "outputs": ["optimum"]}
    knobs = search_knobs(
        Scene.model_validate({**base, "search": {"generator_angle_deg": {"min": 40, "max": 140}}})
    )
    assert knobs["range_deg"] == [40, 140]
    assert knobs["scan_step_deg"] == 5.0 and knobs["tolerance_deg"] == 1.0
    assert knobs["max_drapes"] == 60 and knobs["relax"] is False
    knobs = search_knobs(
        Scene.model_validate(
            {
                **base,
                "search": {
                    "generator_angle_deg": {"min": 40, "max": 140, "step": 10},
                    "tolerance_deg": 0.25,
                    "curved_generators": {"terms": 3},
                },
            }
        )
    )
    assert knobs["scan_step_deg"] == 10 and knobs["tolerance_deg"] == 0.25
    assert knobs["curved_generators"] == {"terms": 3}
    # a misspelt knob is refused when the scene is validated, not when the case runs
    with pytest.raises(ValidationError, match="scan_stepdeg"):
        Scene.model_validate({**base, "search": {"scan_stepdeg": 3}})
    # a preset moves every knob the scene leaves alone; hand-set ones stay
    draft = search_knobs(
        Scene.model_validate({**base, "fidelity": "draft", "search": {"tolerance_deg": 0.5}})
    )
    assert draft["scan_step_deg"] == 10.0 and draft["tolerance_deg"] == 0.5


def test_run_writes_curves_optima_and_the_library_figure(sandbox, tmp_path):
    path = coarse_scene(tmp_path)
    data = yaml.safe_load(path.read_text())
    data["outputs"].append("energy_plot_png")
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / "out"
    report = run_scene(sandbox, path, "plain-weave-*", out)
    assert len(report.results) == 2
    assert [r.status for r in report.results] == ["ok", "ok"], [r.error for r in report.results]
    folder = out / "hemisphere-min-energy"
    for result in report.results:
        summary = json.loads((Path(folder) / result.material / "summary.json").read_text())
        curve = summary["energy_vs_angle"]
        assert curve[0][0] == pytest.approx(30.0) and curve[-1][0] == pytest.approx(150.0)
        assert [a for a, _ in curve] == sorted(a for a, _ in curve)
        # Woven laws are symmetric: the optimum is 90° and the drape step used it.
        assert summary["optimum_generator_angle_deg"] == pytest.approx(90.0, abs=1e-6)
        assert summary["generator_angle_deg"] == pytest.approx(90.0, abs=1e-6)
        assert summary["optimum_energy_J"] == pytest.approx(min(e for _, e in curve), rel=1e-9)
        assert len(summary["energy_vs_angle_coverage"]) == len(curve)
        assert summary["search_settings"]["scan_step_deg"] == 5.0
        assert "energy_vs_angle.png" in summary["files"]
        assert (Path(folder) / result.material / "energy_vs_angle.png").stat().st_size > 0
    assert (folder / "energy_vs_angle.png").stat().st_size > 0


def test_a_sweep_draws_no_figure_its_scene_does_not_name(sandbox, tmp_path):
    # issue 15: figures cost a quarter of a case; they are drawn only when the scene asks
    lib = sandbox.library(bundled=True)
    path = coarse_scene(tmp_path)
    data = yaml.safe_load(path.read_text())
    data["outputs"] = ["energy_vs_angle", "optimum", "drape", "cells_csv"]
    path.write_text(yaml.safe_dump(data))
    scene = load_scene(path, sandbox.registry)
    out = tmp_path / "out"
    report = run_cases(
        make_cases(lib, [scene], out, sandbox.host, materials_glob="plain-weave-*"),
        out,
        sandbox.host,
        engine="serial",
    )
    assert [r.status for r in report.results] == ["ok", "ok"], [r.error for r in report.results]
    assert list(out.rglob("*.png")) == []
    assert len(list(out.rglob("cells.csv"))) == 2


@pytest.mark.parametrize(
    ("figure", "per_case", "run_level"),
    [("energy_plot_png", True, False), ("library_energy_png", False, True)],
)
def test_the_run_level_figure_is_named_apart_from_the_per_case_one(
    sandbox, tmp_path, figure, per_case, run_level
):
    # issue 15: Fig. 10 (every fabric on one figure) no longer rides on the per-case figure
    lib = sandbox.library(bundled=True)
    path = coarse_scene(tmp_path)
    data = yaml.safe_load(path.read_text())
    data["outputs"] = ["optimum", figure]
    path.write_text(yaml.safe_dump(data))
    scene = load_scene(path, sandbox.registry)
    out = tmp_path / "out"
    report = run_cases(
        make_cases(lib, [scene], out, sandbox.host, materials_glob="plain-weave-*"),
        out,
        sandbox.host,
        engine="serial",
    )
    assert [r.status for r in report.results] == ["ok", "ok"], [r.error for r in report.results]
    folder = out / "hemisphere-min-energy"
    cases = sorted(folder / r.material / "energy_vs_angle.png" for r in report.results)
    assert [p.is_file() for p in cases] == [per_case, per_case]
    assert (folder / "energy_vs_angle.png").is_file() == run_level
    summaries = [json.loads((p.parent / "summary.json").read_text()) for p in cases]
    assert all(("energy_vs_angle.png" in s["files"]) == per_case for s in summaries)


def test_library_figure_skips_cases_without_a_curve(tmp_path):
    assert search_steps.energy_vs_angle_library(tmp_path, [{"material": "x"}]) == []
    files = search_steps.energy_vs_angle_library(
        tmp_path / "new",
        [
            {
                "material": "a",
                "energy_vs_angle": [[60, 2.0], [90, 1.0], [120, 2.0]],
                "optimum_generator_angle_deg": 90.0,
            },
            {"material": "b", "energy_vs_angle": [[60, 1.0], [90, 1.5], [120, 3.0]]},
        ],
    )
    assert files == ["energy_vs_angle.png"]
    assert (tmp_path / "new" / "energy_vs_angle.png").stat().st_size > 0


def test_optional_stages_report_in_the_summary(sandbox, tmp_path):
    lib = sandbox.library(bundled=True)
    scene, _ = load_scene(
        coarse_scene(
            tmp_path,
            generator_angle_deg={"min": 60, "max": 120, "step": 15},
            tolerance_deg=5,
            layout={"vary": ["orientation"], "max_drapes": 6},
            curved_generators={"terms": 1, "mirror_families": True, "max_drapes": 8},
            relax={"max_rounds": 1, "max_iterations": 20},
        ),
        sandbox.registry,
    )
    ctx = CaseContext(
        fabric=lib.fabric("plain-weave-150"),
        scene=scene,
        registry=sandbox.registry,
        case_dir=tmp_path,
    )
    steps = {s.name: s for s in sandbox.registry.all_steps()}
    for name in ("surface", "shear_law", "energy_vs_angle", "optimum", "energy_plot_png"):
        ctx.products.update(steps[name].run(ctx))
    summary = ctx.summary
    assert summary["layout_varied"] == ["orientation"] and summary["layout_drapes"] <= 7
    assert summary["curved_drapes"] <= 9 and "curved_relative_saving" in summary
    assert summary["relaxed_energy_J"] <= summary["relaxed_kinematic_energy_J"] * (1 + 1e-9)
    assert summary["curved_cells_outside_law_data"] >= 0 and "curved_max_abs_shear_deg" in summary
    assert summary["search_settings"]["tolerance_deg"] == 5
    # With relaxation asked for, the drape step's result (exported, summed) is the relaxed net,
    # and the kinematic energy is kept next to it.
    ctx.products.update(steps["drape"].run(ctx))
    assert summary["result_net"] == "relaxed"
    assert ctx.products["drape"].result.info["net"] == "relaxed"
    # One definition of a net's energy (issue 26): the relaxed net's, as the relaxation reports
    # it, is the exported total, and the saving is against the kinematic net summed the same way
    assert summary["relaxed_kept"] is True
    assert summary["total_energy_J"] == summary["relaxed_energy_J"]
    assert summary["kinematic_total_energy_J"] == summary["relaxed_kinematic_energy_J"]
    assert summary["relaxed_energy_J"] < summary["relaxed_kinematic_energy_J"]
    assert summary["relaxed_relative_saving"] == pytest.approx(
        1 - summary["relaxed_energy_J"] / summary["relaxed_kinematic_energy_J"]
    )
    # ... and that sum, written out here with the law itself: W(γ)·s·d² over the valid cells
    # of the part, s each cell's own share inside it (the tabulated law agrees within 1e-4)
    net = ctx.products["drape"].result
    cells = net.valid & net.in_part
    law = ctx.products["shear_law"]
    own = float(np.sum(law.energy(net.shear[cells]) * net.part_weight[cells]))
    assert summary["total_energy_J"] == pytest.approx(own * net.node_spacing**2, rel=1e-4)
    assert 0 < math.degrees(ctx.products["optimum"]["generator_angle_rad"]) < 180
    assert (tmp_path / "energy_vs_angle.png").exists()


def test_a_priced_bare_area_is_a_stated_choice_and_makes_the_case_partial(sandbox, tmp_path):
    lib = sandbox.library(bundled=True)
    results = {}
    for price in (None, 40.0):
        extra = {} if price is None else {"uncovered_shear_deg": price}
        scene, _ = load_scene(coarse_scene(tmp_path, **extra), sandbox.registry)
        ctx = CaseContext(
            fabric=lib.fabric("E-BX-318"), scene=scene, registry=sandbox.registry, case_dir=tmp_path
        )
        steps = {s.name: s for s in sandbox.registry.all_steps()}
        for name in ("surface", "shear_law", "energy_vs_angle", "optimum"):
            ctx.products.update(steps[name].run(ctx))
        results[price] = ctx
    free, priced = results[None], results[40.0]
    # No price by default: nothing charged, and the case is not partial for it.
    assert free.summary["search_uncovered_energy_density_J_per_m2"] == 0.0
    assert not free.partial_reasons
    # Priced: the density is the law's larger W at ±40°, and the case says so.
    law = priced.products["shear_law"]
    want = float(max(law.energy(np.radians(40.0)), law.energy(-np.radians(40.0))))
    assert priced.summary["search_uncovered_energy_density_J_per_m2"] == pytest.approx(want)
    (reason,) = priced.partial_reasons
    assert "priced uncovered part area" in reason and "40°" in reason


HAT_SCENE = """\
name: hat-search
tool: {surface: mesh, file: hat_mould.obj, feature_angle_deg: 30}
ply: {node_spacing_mm: 10, size_mm: [360, 360]}
start: {point_mm: [0, 0], orientation_deg: 0}
search: {generator_angle_deg: {min: 30, max: 150}}
outputs: [energy_vs_angle, optimum]
"""


def test_a_folding_tool_says_how_its_angles_were_compared(sandbox, tmp_path):
    """The hat mould folds at its block corners: the case says what fabric was left out of
    the comparison, where E(α) jumps, that the optimum is a sample, and its fold zones."""
    path = tmp_path / "hat.yaml"
    path.write_text(HAT_SCENE)
    out = tmp_path / "out"
    report = run_scene(sandbox, path, "plain-weave-600", out)
    (result,) = report.results
    summary = json.loads((out / "hat-search" / result.material / "summary.json").read_text())
    assert summary["optimum_generator_angle_deg"] == pytest.approx(90.0, abs=0.2)
    assert summary["optimum_energy_J"] <= min(e for _, e in summary["energy_vs_angle"])
    assert summary["optimum_fold_zones"] == 4
    assert summary["optimum_fold_zone_area_m2"] > 0
    assert summary["search_excluded_fabric_area_m2"] > 0
    assert summary["search_discontinuities"]
    assert summary["optimum_from"] in ("fit", "best sample")
    drape_energy = dict(map(tuple, summary["energy_vs_angle_drape_J"]))
    compared = dict(map(tuple, summary["energy_vs_angle"]))
    assert all(compared[a] <= drape_energy[a] + 1e-12 for a in compared)
    warnings = " ".join(summary["warnings"])
    assert "left out of every angle's energy" in warnings
    assert "E(α) jumps at" in warnings


def searched(
    sandbox: Any, tmp_path: Path, fabric: str, then: tuple[str, ...] = (), **search: Any
) -> CaseContext:
    """The case context of ``fabric`` on the coarse scene with ``search``, after its search
    (and the steps ``then``)."""
    scene, _ = load_scene(coarse_scene(tmp_path, **search), sandbox.registry)
    lib = sandbox.library(bundled=True)
    ctx = CaseContext(
        fabric=lib.fabric(fabric), scene=scene, registry=sandbox.registry, case_dir=tmp_path
    )
    steps = {s.name: s for s in sandbox.registry.all_steps()}
    for name in ("surface", "shear_law", "energy_vs_angle", "optimum", *then):
        ctx.products.update(steps[name].run(ctx))
    return ctx


def test_a_relaxation_that_saves_nothing_leaves_the_kinematic_net(sandbox, tmp_path, monkeypatch):
    """A relaxed net holding no less energy than the kinematic one (here: the kinematic
    nodes themselves) is not the result; the case says so."""
    import dataclasses

    from preform.optimise import relax

    real = relax.relax_net

    def unmoved(result: Any, *args: Any, **kwargs: Any) -> Any:
        done = real(result, *args, **kwargs)
        kept = np.where(np.isfinite(done.nodes), result.nodes, np.nan)
        return dataclasses.replace(done, nodes=kept)

    monkeypatch.setattr(relax, "relax_net", unmoved)
    ctx = searched(
        sandbox,
        tmp_path,
        "plain-weave-150",
        ("drape",),
        generator_angle_deg={"min": 60, "max": 120, "step": 15},
        relax={"max_rounds": 1, "max_iterations": 5},
    )
    summary = ctx.summary
    assert summary["relaxed_kept"] is False and summary["relaxed_relative_saving"] == 0.0
    assert "relaxed_nodes" not in ctx.products["optimum"]
    assert summary["result_net"] == "kinematic"
    assert summary["total_energy_J"] == summary["relaxed_kinematic_energy_J"]
    assert any("the result is the kinematic net" in w for w in ctx.warnings)


def test_a_curved_saving_resting_on_no_data_is_not_claimed(sandbox, tmp_path):
    """E-BX-318's law holds its 60° value past its data: curved generators "save" energy by
    shearing cells past 60°. When more than 1 % of the part's fabric lies there, the saving is
    said, with that share, but not claimed, and the straight generators stay the result."""
    ctx = searched(
        sandbox,
        tmp_path,
        "E-BX-318",
        curved_generators={"terms": 2, "mirror_families": True, "max_drapes": 40},
    )
    summary = ctx.summary
    share = summary["curved_area_share_outside_law_data"]
    assert share > search_steps.CURVED_UNMEASURED_SHARE_MAX
    assert summary["curved_relative_saving"] > 0.05 and summary["curved_max_abs_shear_deg"] > 60
    assert summary["curved_saving_claimed"] is False
    optimum = ctx.products["optimum"]
    assert optimum.get("generators") is None
    assert optimum["generator_angle_rad"] == pytest.approx(
        math.radians(summary["optimum_generator_angle_deg"])
    )
    (said,) = [w for w in ctx.warnings if "no saving is claimed for curved generators" in w]
    assert f"{100 * share:.2g} % of the part's fabric" in said
    assert f"{100 * summary['curved_relative_saving']:.3g} %" in said


def test_a_search_case_resolves_the_knobs_once_for_its_search_and_its_drape(tmp_path, monkeypatch):
    """The knobs are resolved once into the search's DrapeSettings, which its drapes, its
    optimum and the optimum's drape all use; the case records those."""
    import preform
    from preform.base import fidelity
    from preform.drape.steps import run_drape

    done = preform.least_energy("plain-weave-150", node_spacing_mm=20)
    ctx = CaseContext(done.fabric, done.scene, preform.default_host().registry, tmp_path)
    ctx.products.update({k: done.products[k] for k in ("surface", "shear_law")})
    resolved = []
    real = fidelity.resolve

    def counting(*args: Any, **kwargs: Any) -> Any:
        resolved.append(real(*args, **kwargs))
        return resolved[-1]

    monkeypatch.setattr(fidelity, "resolve", counting)
    for run in (search_steps.run_energy_vs_angle, search_steps.run_optimum, run_drape):
        ctx.products.update(run(ctx))
    assert len(resolved) == 1
    for key, value in resolved[0].as_dict().items():
        assert ctx.summary[key if key == "fidelity" else f"knob_{key}"] == value
    assert ctx.summary["optimum_generator_angle_deg"] == pytest.approx(
        done.summary["optimum_generator_angle_deg"]
    )
