"""The draped preform's properties (issue 14): Gebart's closed forms, the tensor following the
fibres, per-cell thickness and Vf from the sheared cell, and the ``permeability`` output."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.geometry.permeability import fabric_permeability, gebart_across, gebart_along

R = 8.5e-6
Z = np.array([0.0, 0.0, 1.0])


def gebart_truth(v: float, arrangement: str) -> tuple[float, float]:
    """Gebart (1992) eqs. for K∥ and K⊥, written out here independently of the module."""
    if arrangement == "hexagonal":
        c, c1, vmax = 53.0, 16 / (9 * math.pi * math.sqrt(6)), math.pi / (2 * math.sqrt(3))
    else:
        c, c1, vmax = 57.0, 16 / (9 * math.pi * math.sqrt(2)), math.pi / 4
    along = 8 * R**2 / c * (1 - v) ** 3 / v**2
    across = c1 * (math.sqrt(vmax / v) - 1) ** 2.5 * R**2
    return along, across


@pytest.mark.parametrize("arrangement", ["hexagonal", "quadratic"])
@pytest.mark.parametrize("v", [0.3, 0.5, 0.6, 0.7])
def test_unsheared_aligned_bed_is_gebarts_closed_form(arrangement: str, v: float) -> None:
    along, across = gebart_truth(v, arrangement)
    x = np.array([1.0, 0.0, 0.0])
    k = fabric_permeability(np.asarray(v), (x,), (1.0,), Z, R, arrangement)  # type: ignore[arg-type]
    np.testing.assert_allclose(k, np.diag([along, across, 0.0]), rtol=1e-12, atol=0)
    # a quadratic bed closes across the fibres at square packing
    assert float(gebart_across(math.pi / 4, R, "quadratic")) == 0.0
    assert float(gebart_along(v, R, arrangement)) == pytest.approx(along, rel=1e-12)


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    a = axis / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


@settings(max_examples=50, deadline=None)
@given(
    gamma=st.floats(-1.3, 1.3),
    v=st.floats(0.2, 0.75),
    turn=st.floats(-math.pi, math.pi),
    axis=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.1, 1)),
)
def test_tensor_rotates_with_the_fibres_and_principal_values_follow_gebart(
    gamma: float, v: float, turn: float, axis: tuple[float, float, float]
) -> None:
    # two equal families at ±φ about the bisector x, φ = (90° − γ)/2
    phi = (math.pi / 2 - gamma) / 2
    u = np.array([math.cos(phi), -math.sin(phi), 0.0])
    w = np.array([math.cos(phi), math.sin(phi), 0.0])
    k = fabric_permeability(np.asarray(v), (u, w), (0.5, 0.5), Z, R)
    along, across = gebart_truth(v, "hexagonal")
    k_bisector = along * math.cos(phi) ** 2 + across * math.sin(phi) ** 2
    k_normal = along * math.sin(phi) ** 2 + across * math.cos(phi) ** 2
    np.testing.assert_allclose(
        k, np.diag([k_bisector, k_normal, 0.0]), rtol=1e-10, atol=1e-12 * along
    )
    # the same fabric turned in space: the tensor turns with it, R K Rᵀ
    rot = rotation(np.asarray(axis), turn)
    turned = fabric_permeability(np.asarray(v), (rot @ u, rot @ w), (0.5, 0.5), rot @ Z, R)
    np.testing.assert_allclose(turned, rot @ k @ rot.T, rtol=1e-9, atol=1e-12 * along)


def test_principal_values_fall_as_the_fraction_rises() -> None:
    v = np.linspace(0.2, 0.8, 31)
    along, across = gebart_along(v, R, "hexagonal"), gebart_across(v, R, "hexagonal")
    assert np.all(np.diff(along) < 0) and np.all(np.diff(across) < 0)


@pytest.fixture(scope="module")
def draped(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    from preform import api

    out = tmp_path_factory.mktemp("preform")
    run = api.drape(
        "plain-weave-600",
        node_spacing_mm=10.0,
        outputs=["permeability", "cells_csv", "vtu"],
        out_dir=out,
    )
    run.raise_for_status()
    return run


def test_cells_take_thickness_and_vf_from_the_sheared_cell(draped) -> None:  # type: ignore[no-untyped-def]
    import pandas as pd

    table = pd.read_csv(draped.case_dir / "cells.csv")
    valid = table[table["status"] == "VALID"]
    assert len(valid) > 100
    fabric = draped.fabric
    # the table is linear between 0.25° steps (the locking angle on the grid): compare
    # with the cell built at each cell's own shear
    for _, row in valid.sample(40, random_state=1).iterrows():
        cell = fabric.sheared_cell(math.radians(row["shear_deg"]))
        assert row["preform_thickness_mm"] == pytest.approx(cell.thickness * 1e3, rel=2e-3)
        assert row["fibre_volume_fraction"] == pytest.approx(cell.fibre_volume_fraction, rel=2e-3)
        assert row["permeability_k1_m2"] >= row["permeability_k2_m2"] > 0
    summary = draped.summary
    # the cell's plateau: past jamming the fabric fraction stays at its value at the jam
    plateau = fabric.sheared_cell(fabric.sheared_cell(0.0).jamming_angle).fibre_volume_fraction
    assert summary["fibre_volume_fraction_max"] <= plateau + 1e-3
    assert summary["fibre_volume_fraction_min"] >= 0.366 - 1e-3  # the unsheared cell's
    assert (
        summary["preform_thickness_mm_max"]
        > summary["preform_thickness_mm_min"]
        == (pytest.approx(0.64, rel=1e-6))
    )


def test_k1_runs_along_the_bisector_the_fibres_close_on(draped) -> None:  # type: ignore[no-untyped-def]
    import meshio

    mesh = meshio.read(draped.case_dir / "drape.vtu")
    data = {k: v[0] for k, v in mesh.cell_data.items()}
    shear = np.radians(data["shear_deg"])
    sheared = np.abs(shear) > math.radians(10)
    u, v = data["fibre_u"][sheared], data["fibre_v"][sheared]
    # the fibres close about u + v when the angle between them is acute, about u − v otherwise
    acute = np.einsum("ij,ij->i", u, v) > 0
    bisector = np.where(acute[:, None], u + v, u - v)
    bisector /= np.linalg.norm(bisector, axis=1, keepdims=True)
    k1_dir = data["permeability_k1_dir"][sheared]
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", bisector, k1_dir)), 1.0, atol=1e-9)
    assert data["permeability_m2"].shape[1] == 9


def test_permeability_is_computed_only_when_a_scene_asks() -> None:
    from preform import api
    from preform.pipeline.planner import plan
    from preform.plugin_manager import default_host

    registry = default_host().registry
    for outputs, expected in (
        (["cells_csv", "vtu"], False),
        (["drape"], False),
        (["cells_csv", "permeability"], True),
        (["permeability"], True),
    ):
        steps = [s.name for s in plan(api.scene(outputs=outputs), registry)]
        assert ("permeability" in steps) is expected, outputs
        if expected and "cells_csv" in outputs:
            assert steps.index("permeability") < steps.index("cells_csv")


def flat_net(shear_deg: float, n: int = 4):  # type: ignore[no-untyped-def]
    """A flat net's cell fields, every cell at ``shear_deg`` (the drape's sign convention)."""
    from types import SimpleNamespace

    omega = math.radians(90.0 + shear_deg)
    u = np.array([1.0, 0.0, 0.0])
    v = np.array([math.cos(omega), math.sin(omega), 0.0])
    shape = (n, n)
    return SimpleNamespace(
        valid=np.ones(shape, bool),
        in_part=np.ones(shape, bool),
        shear=np.full(shape, math.radians(shear_deg)),
        fibre_u=np.broadcast_to(u, (*shape, 3)).copy(),
        fibre_v=np.broadcast_to(v, (*shape, 3)).copy(),
    )


def context(fabric, net):  # type: ignore[no-untyped-def]
    from types import SimpleNamespace

    from preform.step import CaseContext

    return CaseContext(
        fabric=fabric,
        scene=None,  # type: ignore[arg-type]
        registry=None,  # type: ignore[arg-type]
        case_dir=None,  # type: ignore[arg-type]
        products={"drape": SimpleNamespace(result=net)},
    )


def test_cells_past_the_sheared_cell_are_held_at_89_degrees_and_said() -> None:
    from preform import api
    from preform.drape.preform_steps import run_permeability

    fabric = api.fabric("plain-weave-600")
    ctx = context(fabric, flat_net(-89.6))
    field = run_permeability(ctx)["permeability"]
    end = fabric.sheared_cell(math.radians(89.0))
    np.testing.assert_allclose(field.thickness, end.thickness, rtol=1e-12)
    assert field.beyond_table.all() and field.past_jamming.all()
    assert any("past 89°" in w and "held" in w for w in ctx.warnings)
    assert ctx.summary["cells_past_jamming"] == 16
    # a cell inside the table: no warning
    quiet = context(fabric, flat_net(20.0))
    run_permeability(quiet)
    assert quiet.warnings == []
    assert quiet.summary["preform_thickness_mm_max"] == pytest.approx(0.64)


def test_a_fabric_without_a_sheared_cell_fails_the_case_in_words() -> None:
    from types import SimpleNamespace

    from preform.base.status import CaseFailure
    from preform.drape.preform_steps import run_permeability

    bare = SimpleNamespace(name="x", architecture="felt", sheared_cell=lambda _g: None)
    with pytest.raises(CaseFailure, match="'felt' has no sheared unit cell"):
        run_permeability(context(bare, flat_net(10.0)))
