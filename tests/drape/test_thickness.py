"""One thickness per draped cell (``preform.drape.properties.thickness``), the same in every output.

Independent truths: the sheared unit cell keeps its thickness before locking (t = t0 exactly,
closed form), after locking each cell's thickness is ``fabric.sheared_cell(γ).thickness``
(evaluated here per cell, not from the table); the FE writers' thicknesses, parsed back from
their text, equal the cell table's; a fabric without a cell model gets 1/cos γ and says so.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform import api
from preform.drape.engine.fields import energy_field
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.drape.properties.thickness import CONSTANT_FIBRE_VOLUME, SHEARED_CELL, thickness_model
from preform.export.abaqus import abaqus_include_text
from preform.export.ansys import ansys_macro_text
from preform.export.fe_mapping import map_to_mesh
from preform.export.lsdyna import lsdyna_include_text
from preform.export.shell_mesh import shell_mesh
from preform.export.tables import cells_table
from preform.plugins.surfaces.basic import Hemisphere

#: Linear interpolation in the 0.25° table of the sheared cell: measured ≤ 3.1e-5 relative
#: (satin-4hs-crowfoot, E-BX-318, 60 random angles up to 70°).
TABLE_RTOL = 1e-4


class Quadratic:
    """A shear law W = γ² [J/m²] without limits: the energy is not what is tested here."""

    locking_angle = None
    failure_angle = None

    def energy(self, gamma):  # type: ignore[no-untyped-def]
        return np.asarray(gamma) ** 2


def hemisphere_drape():  # type: ignore[no-untyped-def]
    return drape(
        Hemisphere(0.1),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.008,
        ply=PlyOutline.rectangle((0.28, 0.28)),
        generator_angle_rad=np.radians(90.0),
    )


@pytest.fixture(scope="module")
def draped():  # type: ignore[no-untyped-def]
    """A crowfoot satin (locking 25.8°) on a hemisphere: cells before and after locking."""
    fabric = api.fabric("satin-4hs-crowfoot")
    result = hemisphere_drape()
    model = thickness_model(fabric)
    energy = model.applied(result, energy_field(result, Quadratic()))
    return fabric, result, model, energy


def test_before_locking_t0_exactly_after_locking_the_cell_itself(draped) -> None:  # type: ignore[no-untyped-def]
    fabric, result, model, energy = draped
    assert model.name == SHEARED_CELL and energy.thickness_model == SHEARED_CELL
    t0_mm = 1e3 * fabric.sheared_cell(0.0).thickness
    assert model.reference_mm == t0_mm
    table = cells_table(result, energy)
    valid = table.status == "VALID"
    shear = np.radians(table.shear_deg[valid].to_numpy())
    thickness = table.thickness_mm[valid].to_numpy()
    locking = fabric.sheared_cell(0.0).locking_angle
    jamming = fabric.sheared_cell(0.0).jamming_angle
    before = np.abs(shear) < locking
    after = np.abs(shear) > locking + math.radians(0.5)
    compacting = after & (np.abs(shear) < jamming - math.radians(0.5))
    jammed = np.abs(shear) > jamming + math.radians(0.5)
    assert before.sum() > 10 and after.sum() > 10, "the drape must straddle the locking angle"
    # closed form: the cell keeps its thickness until it locks
    assert np.all(thickness[before] == t0_mm)
    assert np.all(table.thickness_ratio[valid].to_numpy()[before] == 1.0)
    # after locking: the cell itself, per cell
    expected = np.array([1e3 * fabric.sheared_cell(float(g)).thickness for g in shear[after]])
    np.testing.assert_allclose(thickness[after], expected, rtol=TABLE_RTOL)
    # one tow (issue 24): the tows compact at constant height until they jam, then thicken;
    # never the 1/cos γ of before locking
    assert compacting.sum() > 5, "the drape must reach between locking and jamming"
    np.testing.assert_allclose(thickness[compacting], t0_mm, rtol=TABLE_RTOL)
    assert jammed.sum() > 5, "the drape must reach past the jamming angle"
    assert np.all(thickness[jammed] > t0_mm)
    assert not np.allclose(thickness[after], t0_mm / np.cos(shear[after]), rtol=1e-3)


def test_fe_writers_read_back_the_cell_table_thickness(draped) -> None:  # type: ignore[no-untyped-def]
    """Abaqus, LS-DYNA and ANSYS thicknesses, parsed from their text, on a mesh made of the
    net's own cells (an element centroid maps onto its cell's centre), equal cells.csv's."""
    _, result, model, energy = draped
    ni, nj = result.shape
    idx = np.arange(ni * nj).reshape(ni, nj)
    ci, cj = np.nonzero(result.valid & result.in_part)
    corners = np.column_stack([idx[ci, cj], idx[ci + 1, cj], idx[ci + 1, cj + 1], idx[ci, cj + 1]])
    ids = 7 + 2 * np.arange(len(ci))
    mesh = shell_mesh(1e3 * np.nan_to_num(result.nodes.reshape(-1, 3)), corners, element_ids=ids)
    mapping = map_to_mesh(
        result,
        mesh,
        energy,
        nominal_thickness_mm=model.reference_mm,
        thickness_reference=model.reference,
    )
    assert mapping.covered.all()
    table = cells_table(result, energy).set_index(["i", "j"])
    cells = table.loc[list(zip(ci, cj, strict=True)), "thickness_mm"].tolist()
    truth = dict(zip(ids.tolist(), cells, strict=True))

    abaqus = abaqus_include_text(mapping)
    assert "** Thickness model: sheared unit cell; t0 = " in abaqus
    lines = abaqus.splitlines()
    start = next(k for k, s in enumerate(lines) if "NAME=PREFORM_THICKNESS" in s) + 2
    rows = [s.split(",") for s in lines[start:] if s and s[0].isdigit()]
    read = {int(a): float(b) for a, b in rows}

    lsdyna = lsdyna_include_text(mapping)
    assert "$ Thickness model: sheared unit cell; t0 = " in lsdyna
    body = [s for s in lsdyna.splitlines() if s and s[0] not in "$*"]
    shells = {int(a[:8]): float(b[:16]) for a, b in zip(body[::2], body[1::2], strict=False)}

    ansys = ansys_macro_text(mapping)
    assert "thickness model: sheared unit cell; t0 = " in ansys
    section_t: dict[int, float] = {}
    owner: dict[int, int] = {}
    current = 0
    for line in ansys.splitlines():
        f = line.split(",")
        if f[0] == "SECTYPE":
            current = int(f[1])
            section_t[current] = 0.0
        elif f[0] == "SECDATA":
            section_t[current] += float(f[1])  # u layer f·t + v layer (1 − f)·t
        elif f[0] == "EMODIF" and f[2] == "SECNUM":
            owner[int(f[1])] = int(f[3])

    assert len(truth) == len(read) == len(shells) == len(owner) == len(ids)
    mapped = dict(zip(ids.tolist(), mapping.thickness_mm.tolist(), strict=True))
    for label, t in truth.items():
        # the writers print the mapping's value (10 significant digits; 16-character fields)
        assert read[label] == pytest.approx(mapped[label], rel=1e-9)
        assert shells[label] == pytest.approx(mapped[label], rel=1e-6)
        assert section_t[owner[label]] == pytest.approx(mapped[label], rel=1e-8)
        # which is the cell's: a curved cell's centroid lies O(d²/R) off the mesh's two
        # triangles, so the bilinear weights are the cell centre's only to O(d²/R): measured
        # 1.0e-4 relative at d = 8 mm on R = 100 mm
        assert read[label] == pytest.approx(t, rel=2e-4)
    assert mapping.summary()["max_thickness_ratio"] == pytest.approx(
        float(np.nanmax(table.thickness_ratio)), rel=2e-4
    )


def test_a_fabric_without_a_cell_model_gives_1_over_cos_and_says_so() -> None:
    custom = SimpleNamespace(
        name="felt-1", architecture="felt", sheared_cell=lambda _g: None, derived=lambda: {}
    )
    model = thickness_model(custom)
    assert model.name == CONSTANT_FIBRE_VOLUME == "constant fibre volume fraction (1/cos γ)"
    assert model.reference_mm is None and "not known" in model.reference
    result = hemisphere_drape()
    energy = model.applied(result, energy_field(result, Quadratic()))
    table = cells_table(result, energy)
    valid = table.status == "VALID"
    shear = np.radians(table.shear_deg[valid].to_numpy())
    np.testing.assert_allclose(table.thickness_ratio[valid], 1.0 / np.cos(shear), rtol=1e-12)
    assert table.thickness_mm.isna().all()  # no t0, no thickness in mm
    # with the scene's t0: t0 / cos γ, said to come from the scene
    given_t0 = thickness_model(custom, 0.5)
    assert given_t0.reference == "the scene's export.nominal_thickness_mm"
    t = cells_table(result, given_t0.applied(result, energy)).thickness_mm[valid]
    np.testing.assert_allclose(t, 0.5 / np.cos(shear), rtol=1e-12)
    summary = model.summary(result)
    assert summary["thickness_model"] == CONSTANT_FIBRE_VOLUME


def test_a_cell_that_cannot_be_sheared_falls_back_in_words() -> None:
    def refuse(_g: float) -> None:
        raise ValueError("the tows are wider than their spacing")

    odd = SimpleNamespace(name="odd", architecture="woven", sheared_cell=refuse, derived=dict)
    model = thickness_model(odd)
    assert model.name == CONSTANT_FIBRE_VOLUME
    assert model.cell_error is not None and "wider than their spacing" in model.cell_error


@settings(max_examples=25, deadline=None)
@given(gamma_deg=st.floats(-70.0, 70.0), name=st.sampled_from(["E-BX-318", "plain-weave-150"]))
def test_ratio_is_the_cells_thickness_over_its_flat_thickness(gamma_deg: float, name: str) -> None:
    fabric = api.fabric(name)
    model = thickness_model(fabric)  # tabulated once per fabric (kept in memory)
    gamma = math.radians(gamma_deg)
    cell = fabric.sheared_cell(gamma)
    flat = fabric.sheared_cell(0.0)
    ratio = float(model.ratio(np.array([gamma]))[0])
    assert ratio == pytest.approx(cell.thickness / flat.thickness, rel=TABLE_RTOL)
    if abs(gamma) < flat.locking_angle:
        assert ratio == 1.0


def test_the_pipeline_states_the_model_and_every_output_agrees(tmp_path) -> None:
    """A default hemisphere case: cells.csv, the permeability output's cell thickness and the
    summary give one thickness."""
    import pandas as pd

    run = api.drape(
        "plain-weave-150",
        out_dir=tmp_path,
        node_spacing_mm=10,
        outputs=["drape", "cells_csv", "vtu", "permeability"],
    )
    assert run.status in ("ok", "partial"), run.error
    assert run.summary["thickness_model"] == SHEARED_CELL
    assert run.summary["thickness_reference"] == "the sheared unit cell's thickness at zero shear"
    assert run.thickness_model == SHEARED_CELL
    cells = pd.read_csv(next(tmp_path.rglob("cells.csv")))
    valid = cells.status == "VALID"
    np.testing.assert_allclose(
        cells.thickness_mm[valid], cells.preform_thickness_mm[valid], rtol=1e-12
    )
    frame = run.to_pandas()
    np.testing.assert_allclose(
        frame.thickness_mm[valid].to_numpy(), cells.thickness_mm[valid].to_numpy(), rtol=1e-12
    )
    assert run.summary["thickness_ratio_max"] == pytest.approx(
        float(cells.thickness_ratio[valid & cells.in_part].max()), rel=1e-12
    )


def step_context(fabric, shear_deg: float, nominal_mm: float | None = None):  # type: ignore[no-untyped-def]
    """A case context holding a flat net whose 16 cells are all at ``shear_deg``."""
    from preform.step import CaseContext

    shape = (4, 4)
    net = SimpleNamespace(
        valid=np.ones(shape, bool),
        in_part=np.ones(shape, bool),
        shear=np.full(shape, math.radians(shear_deg)),
    )
    scene = SimpleNamespace(
        outputs=["cells_csv"], export=SimpleNamespace(nominal_thickness_mm=nominal_mm)
    )
    return CaseContext(
        fabric=fabric,
        scene=scene,  # type: ignore[arg-type]
        registry=None,  # type: ignore[arg-type]
        case_dir=None,  # type: ignore[arg-type]
        products={"drape": SimpleNamespace(result=net)},
    )


def test_the_step_says_the_model_t0_and_what_differs() -> None:
    from preform.drape.preform_steps import run_thickness

    fabric = api.fabric("plain-weave-600")
    quiet = step_context(fabric, 20.0)
    model = run_thickness(quiet)["thickness"]
    assert quiet.warnings == []
    assert quiet.summary["thickness_model"] == SHEARED_CELL
    assert quiet.summary["thickness_reference_mm"] == pytest.approx(0.64, rel=1e-12)
    assert quiet.summary["thickness_ratio_max"] == 1.0  # 20° < locking 39.2°
    # a scene t0 other than the cell's: used, and said
    told = step_context(fabric, 20.0, nominal_mm=1.0)
    assert run_thickness(told)["thickness"].reference_mm == 1.0
    assert told.summary["thickness_reference"] == "the scene's export.nominal_thickness_mm"
    assert any("1 mm is not the sheared unit cell's 0.64 mm" in w for w in told.warnings)
    # past the table's end: held at 89°, said
    far = step_context(fabric, 89.5)
    run_thickness(far)
    end = fabric.sheared_cell(math.radians(89.0)).thickness / fabric.sheared_cell(0.0).thickness
    assert far.summary["thickness_ratio_max"] == pytest.approx(end, rel=1e-12)
    assert any("16 cell(s) are sheared past 89°" in w for w in far.warnings)
    assert model.name == SHEARED_CELL


def test_a_cell_that_cannot_be_sheared_is_a_warning_not_a_silent_fallback() -> None:
    from preform.drape.preform_steps import run_thickness

    def refuse(_g: float) -> None:
        raise ValueError("the tows are wider than their spacing")

    odd = SimpleNamespace(name="odd", architecture="woven", sheared_cell=refuse, derived=dict)
    ctx = step_context(odd, 10.0)
    assert run_thickness(ctx)["thickness"].name == CONSTANT_FIBRE_VOLUME
    assert ctx.summary["thickness_model"] == CONSTANT_FIBRE_VOLUME
    assert any("wider than their spacing" in w and "1/cos γ" in w for w in ctx.warnings)
