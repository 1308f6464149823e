"""Fidelity presets and hand-set knobs: presets fill what the scene leaves, hands win."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from preform.base import fidelity
from preform.pipeline.scene import Scene

BASE = {"name": "s", "outputs": ["drape"], "ply": {"size_mm": [100, 100]}, "start": {}}


def scene(**extra: object) -> Scene:
    return Scene.model_validate({**BASE, **extra})


def test_standard_is_the_default_and_spacing_follows_the_tool():
    knobs = fidelity.resolve(scene(), tool_size_m=0.1)
    assert knobs.fidelity == "standard"
    assert knobs.node_spacing_mm == pytest.approx(2.5)  # R/40 for a 100 mm hemisphere
    assert knobs.as_dict() | {} == {
        **fidelity.PRESETS["standard"],
        "fidelity": "standard",
        "node_spacing_mm": pytest.approx(2.5),
    }


@pytest.mark.parametrize("preset", ["draft", "standard", "fine"])
def test_presets_order_cost_and_accuracy(preset):
    knobs = fidelity.resolve(scene(fidelity=preset), tool_size_m=0.1)
    assert knobs.fidelity == preset
    for key, value in fidelity.PRESETS[preset].items():
        assert getattr(knobs, key) == value


def test_finer_presets_are_finer_in_every_knob():
    draft, standard, fine = (fidelity.PRESETS[p] for p in ("draft", "standard", "fine"))
    for smaller in ("solver_tolerance", "tolerance_deg"):
        assert draft[smaller] > standard[smaller] > fine[smaller]
    # a finer scan than standard's bought nothing once d is fine (measured: benchmarks/README)
    assert draft["scan_step_deg"] > standard["scan_step_deg"] >= fine["scan_step_deg"]
    for larger in ("generator_substeps", "max_drapes"):
        assert draft[larger] < standard[larger] < fine[larger]
    assert fidelity.SPACING_FRACTION["draft"] > fidelity.SPACING_FRACTION["fine"]
    # the finest preset evaluates the shear law itself, no table
    assert fine["energy_table_step_deg"] == 0.0


def test_hand_set_knobs_win_over_the_preset():
    s = scene(
        fidelity="draft",
        ply={"size_mm": [100, 100], "node_spacing_mm": 1.0},
        numerics={"solver_tolerance": 1e-12, "energy_table_step_deg": 0},
        search={"generator_angle_deg": {"min": 40, "max": 140, "step": 2}, "max_drapes": 99},
    )
    knobs = fidelity.resolve(s, tool_size_m=0.1)
    assert knobs.node_spacing_mm == 1.0
    assert knobs.solver_tolerance == 1e-12 and knobs.energy_table_step_rad is None
    assert knobs.scan_step_deg == 2 and knobs.max_drapes == 99
    assert knobs.generator_substeps == fidelity.PRESETS["draft"]["generator_substeps"]


@pytest.mark.parametrize(
    "bad",
    [
        {"fidelity": "ultra"},
        {"numerics": {"solver_tolerance": 0.5}},
        {"numerics": {"generator_substeps": 0}},
        {"numerics": {"tolerance": 1e-9}},
    ],
)
def test_bad_knobs_are_refused_at_validation(bad):
    with pytest.raises(ValidationError):
        scene(**bad)
