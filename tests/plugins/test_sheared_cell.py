"""The sheared unit cell (issue 14): conservation, 1/cos γ before locking, thickening and the
packing limit after it, for every bundled fabric (woven and warp-knit)."""

from __future__ import annotations

import dataclasses
import math
from functools import cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.api import load_library
from preform.geometry.fibres import fibre
from preform.geometry.sheared_cell import MAX_SHEAR, pin_jointed_stretch
from preform.plugins.woven.compaction import SQUARE_PACKING, BundleCompaction
from preform.plugins.woven.tow_jamming import TowCompaction, jamming_fraction

HEXAGONAL = math.pi / (2.0 * math.sqrt(3.0))


@cache
def library():  # type: ignore[no-untyped-def]
    return load_library(env=False)


@cache
def names() -> tuple[str, ...]:
    return tuple(library().names())


@cache
def sheared(name: str, gamma_deg: float):  # type: ignore[no-untyped-def]
    return library().fabric(name).sheared_cell(math.radians(gamma_deg))


def reinforcement_areal_density_g_m2(name: str) -> float:
    """Independent truth: the fabric's reinforcement areal mass from its own geometry."""
    fab = library().fabric(name)
    if fab.architecture == "woven":
        return float(fab.woven_unit_cell.areal_density())
    geo = fab.geometry
    return sum(
        layer.tow.linear_density_tex / (fitted.spacing * 1e3)
        for layer, fitted in zip(geo.tow_layers, geo.cell_fit.layers, strict=True)
    )


def fibre_density(name: str) -> float:
    fab = library().fabric(name)
    if fab.architecture == "woven":
        return float(fab.woven_unit_cell.warp_tow_types[0][0].fibre.density_g_cm3)
    return fibre(fab.geometry.tow_layers[0].tow.fibre).density_g_cm3


fabrics = st.sampled_from(names())
angles = st.floats(-70.0, 70.0, allow_nan=False)


def test_every_bundled_fabric_has_a_sheared_cell() -> None:
    assert len(names()) >= 9
    for name in names():
        assert sheared(name, 0.0) is not None


@settings(max_examples=60, deadline=None)
@given(name=fabrics, gamma=angles)
def test_fibre_volume_is_conserved_exactly(name: str, gamma: float) -> None:
    cell = sheared(name, gamma)
    # per tow: fraction × section = the fibre area, at every angle
    for family, state in zip(cell.families, cell.states, strict=True):
        section = math.pi / 4 * float(state.width) * float(state.height)
        assert float(state.fraction) * section == pytest.approx(family.fibre_area, rel=1e-12)
    # per cell: Vf × area × thickness against the fabric's areal mass (independent: tex over
    # spacing with crimp) over the fibre density, times the undeformed area
    area0 = sheared(name, 0.0).area
    assert cell.area == pytest.approx(area0 * math.cos(math.radians(gamma)), rel=1e-12)
    fibre_volume = cell.fibre_volume_fraction * cell.area * cell.thickness
    grams = reinforcement_areal_density_g_m2(name) * area0
    # only all-glass or all-carbon fabrics are bundled: one fibre density per fabric
    assert fibre_volume * fibre_density(name) * 1e6 == pytest.approx(grams, rel=1e-9)


@settings(max_examples=60, deadline=None)
@given(name=fabrics, share=st.floats(0.0, 0.999))
def test_before_locking_vf_grows_as_one_over_cos_at_constant_thickness(
    name: str, share: float
) -> None:
    flat = sheared(name, 0.0)
    lock = math.degrees(flat.locking_angle)
    for gamma in (share * lock, -share * lock):
        cell = sheared(name, gamma)
        assert cell.thickness == pytest.approx(flat.thickness, rel=1e-12)
        expected = flat.fibre_volume_fraction / math.cos(math.radians(gamma))
        assert cell.fibre_volume_fraction == pytest.approx(expected, rel=1e-12)


@settings(max_examples=80, deadline=None)
@given(name=fabrics, gamma=st.floats(0.0, 70.0), step=st.floats(0.5, 20.0))
def test_after_locking_thickness_grows_and_vf_stays_below_packing(
    name: str, gamma: float, step: float
) -> None:
    flat = sheared(name, 0.0)
    a, b = sheared(name, gamma), sheared(name, min(70.0, gamma + step))
    assert b.thickness >= a.thickness * (1 - 1e-12)
    if math.radians(gamma) > flat.jamming_angle and b.shear > a.shear:
        assert b.thickness > a.thickness
    for cell in (a, b):
        cap = SQUARE_PACKING * (1.0 - TowCompaction().packing_margin)
        assert all(v <= cap for v in cell.tow_volume_fractions)
        assert cell.fibre_volume_fraction < max(cell.tow_volume_fractions)
        assert cell.fibre_volume_fraction < HEXAGONAL
    # the sense of shear does not change the cell's thickness or fractions
    mirror = sheared(name, -gamma)
    assert mirror.thickness == pytest.approx(a.thickness, rel=1e-12)
    assert mirror.fibre_volume_fraction == pytest.approx(a.fibre_volume_fraction, rel=1e-12)


def test_packing_limit_holds_at_the_largest_angle() -> None:
    for name in names():
        cell = library().fabric(name).sheared_cell(MAX_SHEAR)
        assert cell.fibre_volume_fraction < SQUARE_PACKING
        assert cell.thickness > sheared(name, 0.0).thickness
    with pytest.raises(ValueError, match="outside"):
        library().fabric("plain-weave-600").sheared_cell(math.radians(90.0))


def test_plain_weave_locks_at_the_papers_angle_and_narrows_as_ts_cos_gamma() -> None:
    cell = sheared("plain-weave-600", 50.0)
    assert math.degrees(cell.locking_angle) == pytest.approx(math.degrees(math.acos(3.1 / 4.0)))
    for state in cell.states:
        assert float(state.width) == pytest.approx(4e-3 * math.cos(math.radians(50.0)))
        assert float(state.spacing) == pytest.approx(4e-3 * math.cos(math.radians(50.0)))
        assert bool(state.locked) and bool(state.jammed)


@pytest.mark.parametrize("gamma", [-50.0, -20.0, 0.0, 30.0, 60.0])
def test_drawn_cell_fibres_close_to_90_minus_gamma(gamma: float) -> None:
    cell = sheared("plain-weave-600", gamma).unit_cell()
    warp = next(t for t in cell.tows if t.kind == "warp")
    weft = next(t for t in cell.tows if t.kind == "weft")
    u = warp.points[-1, :2] - warp.points[0, :2]
    v = weft.points[-1, :2] - weft.points[0, :2]
    angle = math.degrees(math.acos(np.dot(u, v) / np.linalg.norm(u) / np.linalg.norm(v)))
    assert angle == pytest.approx(90.0 - gamma, abs=1e-9)
    # lengths along the fibres are kept: the warp's plan length is still the 8 mm repeat
    assert np.linalg.norm(u) == pytest.approx(8e-3)
    area = abs(np.linalg.det(cell.period))
    assert area == pytest.approx(64e-6 * math.cos(math.radians(gamma)))


def test_drawn_cell_thickness_is_the_cells_thickness() -> None:
    for name in ("plain-weave-600", "satin-8hs-carbon", "orthogonal-3d-glass"):
        for gamma in (0.0, 45.0, 65.0):
            shear = sheared(name, gamma)
            tows = shear.unit_cell().tows
            top = max(float(t.points[:, 2].max()) + t.height / 2 for t in tows)
            bottom = min(float(t.points[:, 2].min()) - t.height / 2 for t in tows)
            assert top - bottom == pytest.approx(shear.thickness, rel=1e-12)


def test_stretch_keeps_family_lengths_and_has_determinant_cos_gamma() -> None:
    for reference in (0.0, math.pi / 4, 0.3):
        for gamma in (-1.2, -0.4, 0.0, 0.7, 1.5):
            f = pin_jointed_stretch(gamma, reference)
            assert np.linalg.det(f) == pytest.approx(math.cos(gamma))
            for offset in (-math.pi / 4, math.pi / 4):
                d = np.array([math.cos(reference + offset), math.sin(reference + offset)])
                assert np.linalg.norm(f @ d) == pytest.approx(1.0)


def test_jamming_fraction_balances_the_bundle_stress_against_the_pressure() -> None:
    v0, modulus = 0.6, 72e9
    for pressure in (1e3, 1e5, 1e7):
        settings_ = TowCompaction(confining_pressure_Pa=pressure)
        vj = jamming_fraction(v0, modulus, settings_)
        bundle = BundleCompaction(
            modulus, settings_.fibre_wave_ratio, v0, v0, SQUARE_PACKING, packing_margin=1e-2
        )
        assert float(bundle.stress(np.asarray(vj))) == pytest.approx(pressure, rel=1e-6)
    assert jamming_fraction(v0, modulus, TowCompaction(confining_pressure_Pa=0.0)) == v0
    huge = jamming_fraction(v0, modulus, TowCompaction(confining_pressure_Pa=1e30))
    assert huge == pytest.approx(SQUARE_PACKING * 0.99)
    with pytest.raises(ValueError, match="packing cap"):
        jamming_fraction(0.8, modulus)


def test_warp_knit_layer_off_the_net_families_is_refused() -> None:
    from preform.plugins.warpknit.sheared_cell import sheared_warp_knit_cell

    geo = library().fabric("E-BX-318").geometry
    with pytest.raises(ValueError, match="not one of the two fibre families"):
        sheared_warp_knit_cell(geo, 0.2, reference_deg=10.0)
    turned = dataclasses.replace(
        geo, tow_layers=(dataclasses.replace(geo.tow_layers[0], orientation_deg=0.0),)
    )
    with pytest.raises(ValueError, match="layer 1 at 0°"):
        sheared_warp_knit_cell(turned, 0.2, reference_deg=0.0)


def test_filament_diameter_from_the_entry_else_the_fibre_table() -> None:
    from preform.geometry.fibres import FIBRES
    from preform.plugins.warpknit.model import WarpKnitFabric

    assert sheared("satin-5hs-carbon", 10.0).filament_radius == pytest.approx(3.5e-6)
    assert sheared("E-BX-318", 10.0).filament_radius == pytest.approx(8.5e-6)
    entry = library().fabric("E-BX-318").model_dump(exclude_none=True)
    entry["tow_layers"] = [
        {**layer, "filament_diameter_um": 24.0} if k == 0 else layer
        for k, layer in enumerate(entry["tow_layers"])
    ]
    for layer in entry["tow_layers"][1:]:
        layer.pop("filament_diameter_um", None)
    cell = WarpKnitFabric.model_validate(entry).sheared_cell(0.1)
    # equal layers: the mean radius of 24 µm and the glass default
    assert cell.filament_radius == pytest.approx(
        0.25 * (24e-6 + FIBRES["glass"].filament_diameter_m)
    )


def test_a_tow_denser_than_packing_is_refused_and_named(tmp_path) -> None:  # type: ignore[no-untyped-def]
    entry = library().fabric("plain-weave-600").model_dump(exclude_none=True)
    entry["tow_types"]["glass-1190"]["height_mm"] = 0.2  # 1190 tex in 3.1 × 0.2 mm: Vf 0.96
    fabric = type(library().fabric("plain-weave-600")).model_validate(entry)
    with pytest.raises(ValueError, match=r"tow_types.glass-1190 \(warp-wise\).*0.958.*packing"):
        fabric.sheared_cell(0.3)
