"""The drape step's energy field: the law's tabulated surrogate unless the fidelity asks for the
law itself, evaluated on the counted cells only (issue 15)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import preform
from preform.base import fidelity
from preform.drape.engine.fields import energy_field
from preform.drape.steps import run_drape
from preform.shear.surrogate import TabulatedSurrogate
from preform.step import CaseContext


class CountingLaw:
    """A shear law that counts the angles its energy is evaluated at."""

    def __init__(self, law: Any) -> None:
        self.law = law
        self.sizes: list[int] = []

    def energy(self, gamma: Any) -> Any:
        self.sizes.append(int(np.size(gamma)))
        return self.law.energy(gamma)

    def torque(self, gamma: Any) -> Any:
        return self.law.torque(gamma)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.law, name)


def _case(tmp_path, fidelity_name: str) -> tuple[CaseContext, Any]:
    d = preform.drape(
        "plain-weave-150", node_spacing_mm=5, generator_angle_deg=80, fidelity=fidelity_name
    )
    assert d.ok
    ctx = CaseContext(d.fabric, d.scene, preform.default_host().registry, tmp_path)
    ctx.products.update({k: v for k, v in d.products.items() if k != "drape"})
    return ctx, ctx.products["shear_law"]


def test_the_drape_step_uses_the_surrogate_within_its_documented_error(tmp_path):
    ctx, exact = _case(tmp_path, "standard")
    knobs = fidelity.resolve(ctx.scene, float(ctx.products["surface"].size))
    assert knobs.energy_table_step_deg > 0
    ply = run_drape(ctx)["drape"]
    reference = energy_field(ply.result, exact)
    table = TabulatedSurrogate(exact, math.radians(knobs.energy_table_step_deg))
    # the documented bound: |W_table - W| <= max_relative_error * max W over |gamma| <= 60 deg
    counted = ply.result.valid & ply.result.in_part
    assert np.abs(ply.result.shear[counted]).max() < math.radians(60)
    g = np.linspace(-math.radians(60), math.radians(60), 2001)
    bound = table.max_relative_error() * float(np.max(np.abs(exact.energy(g))))
    assert table.max_relative_error() < 3e-7
    diff = np.abs(ply.energy.energy_density - reference.energy_density)
    assert diff.max() <= bound
    weights = float(np.where(counted, ply.result.part_weight, 0.0).sum())
    d2 = ply.result.node_spacing**2
    assert abs(ply.energy.total_energy - reference.total_energy) <= bound * weights * d2
    assert ply.energy.total_energy == pytest.approx(reference.total_energy, rel=1e-6)
    # the flags do not depend on the table
    assert np.array_equal(ply.energy.past_locking, reference.past_locking)
    assert np.array_equal(ply.energy.past_failure, reference.past_failure)


def test_the_exact_law_when_the_fidelity_says_so_on_counted_cells_only(tmp_path):
    ctx, exact = _case(tmp_path, "fine")
    counting = CountingLaw(exact)
    ctx.products["shear_law"] = counting
    assert fidelity.resolve(ctx.scene, 1.0).energy_table_step_deg == 0
    ply = run_drape(ctx)["drape"]
    counted = ply.result.valid & ply.result.in_part
    assert counted.sum() < counted.size  # some cells do not count
    assert int(counted.sum()) in counting.sizes  # the law itself, on the counted cells
    assert max(counting.sizes) == int(counted.sum())
    assert ply.energy.total_energy == energy_field(ply.result, exact).total_energy


def test_the_law_is_not_evaluated_per_cell_with_the_table(tmp_path):
    ctx, exact = _case(tmp_path, "standard")
    counting = CountingLaw(exact)
    ctx.products["shear_law"] = counting
    ply = run_drape(ctx)["drape"]
    counted = int((ply.result.valid & ply.result.in_part).sum())
    # the table's grid, the law's special angles and kinks, and the 8× finer stretch before its
    # jamming angle (3°, or from the locking angle where compaction starts, if longer)
    jam, lock = exact.packing_angle, exact.locking_angle
    fine_deg = max(3.0, math.degrees(jam - lock)) if jam is not None and lock is not None else 3.0
    kinks = len(getattr(exact, "kink_angles", ()))
    nodes = math.ceil(90 / 0.25) + 3 + kinks + (1 + kinks) * math.ceil(fine_deg / (0.25 / 8))
    assert counting.sizes and all(size <= nodes for size in counting.sizes)
    assert counted > nodes
