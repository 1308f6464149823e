"""The sheared cell's stack over a whole grid of angles in one pass (issue 15h) against the cell
rebuilt one angle at a time, written here: the preform's table (``PreformResponse``) and
``FabricBase.sheared_thickness`` must be what ``sheared_cell(γ)`` gives at every angle. And the
tows' jamming fraction, bracketed many fractions per bundle-law call, against a bisection."""

from __future__ import annotations

import dataclasses
import math
from functools import cache
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from preform.api import load_library
from preform.drape.properties.preform_fields import PreformResponse
from preform.geometry.sheared_cell import MAX_SHEAR
from preform.plugins.warpknit.sheared_cell import sheared_stack as warp_knit_stack
from preform.plugins.woven.compaction import SQUARE_PACKING, BundleCompaction
from preform.plugins.woven.sheared_cell import sheared_stack as woven_stack
from preform.plugins.woven.tow_jamming import TowCompaction, jamming_fraction

#: Table against cell: the same arithmetic on arrays and on one angle (measured: equal bits).
RTOL = 1e-12


@cache
def library():  # type: ignore[no-untyped-def]
    return load_library(env=False)


def names(architecture: str | None = None) -> list[str]:
    lib = library()
    return [n for n in lib.names() if architecture in (None, lib.fabric(n).architecture)]


angle_lists = st.lists(
    st.floats(-math.degrees(MAX_SHEAR), math.degrees(MAX_SHEAR), allow_nan=False),
    min_size=1,
    max_size=12,
)


def tow_height_at(tow: Any, spacing: float, jamming: float, gamma: float) -> float:
    """Independent truth: a tow's height [m] at γ, written out (docs/physics.md): the width
    narrows to Ts·cos γ past locking, the tow compacts at constant height up to V_j, then
    thickens at V_j."""
    width = min(tow.width, spacing * math.cos(gamma))
    fraction = min(tow.volume_fraction * tow.width / width, jamming)
    return tow.fibre_area / (math.pi / 4.0 * width * fraction)


def woven_thickness_one_angle_at_a_time(fabric: Any, gamma: float) -> float:
    """The per-angle cell loop: the woven cell rebuilt with its tows' heights at γ, the
    thickness the envelope of its drawn tow polylines ± half their heights."""
    cell = fabric.woven_unit_cell
    jamming = {f.name: f.jamming_fraction for f in fabric.sheared_cell(0.0).families}

    def at(family: str, spacing: float, tow: Any) -> Any:
        height = tow_height_at(tow, spacing, jamming[f"{family} {tow.name}"], gamma)
        return dataclasses.replace(tow, height=height)

    sheared = dataclasses.replace(
        cell,
        warp_tow_types=tuple(
            tuple(at("warp", cell.tow_spacing_warp, t) for t in level)
            for level in cell.warp_tow_types
        ),
        weft_tow_types=tuple(
            tuple(at("weft", cell.tow_spacing_weft, t) for t in level)
            for level in cell.weft_tow_types
        ),
    )
    tows = sheared.to_unit_cell().tows
    top = max(float(t.points[:, 2].max()) + t.height / 2 for t in tows)
    bottom = min(float(t.points[:, 2].min()) - t.height / 2 for t in tows)
    return top - bottom


@st.composite
def woven_fabrics(draw: st.DrawFn) -> Any:
    """A bundled woven entry (plain, twill, satins, 3D orthogonal) with its tows made narrower
    or wider, flatter or thicker, and its spacings opened: other locking and jamming angles."""
    name = draw(st.sampled_from(names("woven")))
    entry = library().fabric(name).model_dump(exclude_none=True)
    for tow in entry["tow_types"].values():
        narrower = draw(st.floats(0.5, 1.0))
        tow["width_mm"] *= narrower
        # the section never smaller than the bundled tow's: never denser (V₀ below packing)
        tow["height_mm"] *= draw(st.floats(1.0, 1.5)) / narrower
    for family in ("warp", "weft"):
        if "tow_spacing_mm" in entry.get(family, {}):
            entry[family]["tow_spacing_mm"] *= draw(st.floats(1.0, 1.3))
    return type(library().fabric(name)).model_validate(entry)


@settings(max_examples=30, deadline=None)
@given(fabric=woven_fabrics(), angles_deg=angle_lists)
def test_woven_stack_over_angles_is_the_cell_rebuilt_per_angle(
    fabric: Any, angles_deg: list[float]
) -> None:
    gammas = np.radians(angles_deg)
    thickness = fabric.sheared_thickness(gammas)
    assert thickness.shape == gammas.shape
    for gamma, t in zip(gammas, thickness, strict=True):
        expected = woven_thickness_one_angle_at_a_time(fabric, float(gamma))
        assert t == pytest.approx(expected, rel=RTOL, abs=0.0)
        assert fabric.sheared_cell(float(gamma)).thickness == pytest.approx(t, rel=RTOL, abs=0.0)
    cell = fabric.woven_unit_cell
    if not cell.weave.is_3d:
        # 2D weave, closed form: every column stacks one warp and one weft tow, centred, so
        # the envelope is the tallest column's pair of heights
        jamming = {f.name: f.jamming_fraction for f in fabric.sheared_cell(0.0).families}
        for gamma, t in zip(gammas, thickness, strict=True):
            warp = [
                tow_height_at(w, cell.tow_spacing_warp, jamming[f"warp {w.name}"], abs(gamma))
                for w in cell.warp_tow_types[0]
            ]
            weft = [
                tow_height_at(w, cell.tow_spacing_weft, jamming[f"weft {w.name}"], abs(gamma))
                for w in cell.weft_tow_types[0]
            ]
            assert t == pytest.approx(max(warp) + max(weft), rel=RTOL, abs=0.0)


@settings(max_examples=20, deadline=None)
@given(name=st.sampled_from(names("warp_knit")), angles_deg=angle_lists)
def test_warp_knit_stack_over_angles_is_the_stitch_band_and_the_layers_at_each_angle(
    name: str, angles_deg: list[float]
) -> None:
    fabric = library().fabric(name)
    geo = fabric.geometry
    gammas = np.radians(angles_deg)
    thickness = fabric.sheared_thickness(gammas)
    flat = fabric.sheared_cell(0.0)
    for gamma, t in zip(gammas, thickness, strict=True):
        # closed form: the loop band (thickest thread), every layer's tow at γ, every
        # underlap's thread
        layers = sum(
            tow_height_at(
                SimpleNamespace(
                    width=family.width,
                    fibre_area=family.fibre_area,
                    volume_fraction=family.initial_fraction,
                ),
                family.spacing,
                family.jamming_fraction,
                float(gamma),
            )
            for family in flat.families
        )
        threads = [level.diameter for level in geo.thread_levels]
        assert t == pytest.approx(max(threads) + layers + sum(threads), rel=RTOL, abs=0.0)
        assert fabric.sheared_cell(float(gamma)).thickness == pytest.approx(t, rel=RTOL, abs=0.0)


@cache
def table(name: str) -> PreformResponse:
    response = PreformResponse.from_fabric(library().fabric(name))
    assert response is not None
    return response


@settings(max_examples=40, deadline=None)
@given(name=st.sampled_from(names()), where=st.floats(0.0, 1.0))
def test_the_preforms_table_is_the_per_angle_cell_at_every_grid_angle(
    name: str, where: float
) -> None:
    response = table(name)
    index = round(where * (response.shear.size - 1))
    cell = library().fabric(name).sheared_cell(float(response.shear[index]))
    assert response.thickness[index] == pytest.approx(cell.thickness, rel=RTOL, abs=0.0)
    assert response.fibre_volume_fraction[index] == pytest.approx(
        cell.fibre_volume_fraction, rel=RTOL, abs=0.0
    )


def test_a_fabric_with_only_the_per_angle_cell_gets_the_same_table() -> None:
    for name in ("plain-weave-150", "E-BX-318"):
        fabric = library().fabric(name)
        per_angle = SimpleNamespace(sheared_cell=fabric.sheared_cell)  # no sheared_thickness
        slow = PreformResponse.from_fabric(per_angle)
        fast = table(name)
        assert slow is not None
        np.testing.assert_array_equal(slow.shear, fast.shear)
        np.testing.assert_allclose(slow.thickness, fast.thickness, rtol=RTOL, atol=0.0)
        np.testing.assert_allclose(
            slow.fibre_volume_fraction, fast.fibre_volume_fraction, rtol=RTOL, atol=0.0
        )


@pytest.mark.parametrize("bad", [90.0, -89.5, float("nan")])
def test_a_grid_with_an_angle_past_89_degrees_is_refused_in_words(bad: float) -> None:
    woven = library().fabric("plain-weave-150")
    warp_knit = library().fabric("E-BX-318")
    gammas = np.radians([0.0, 30.0, bad])
    with pytest.raises(ValueError, match="outside ±89°"):
        woven_stack(woven.woven_unit_cell, gammas)
    with pytest.raises(ValueError, match="outside ±89°"):
        warp_knit_stack(warp_knit.geometry, gammas, warp_knit.reference_direction_deg())


def bisected_jamming_fraction(v0: float, modulus: float, settings: TowCompaction) -> float:
    """Second implementation: σ_b(V) = p by plain bisection, one bundle-law call per halving
    (the method before issue 15h)."""
    bundle = BundleCompaction(
        modulus,
        settings.fibre_wave_ratio,
        v0,
        v0,
        settings.max_fraction,
        packing_margin=settings.packing_margin,
    )
    lo, hi = v0, bundle.cap_fraction
    if float(bundle.stress(np.asarray(hi))) <= settings.confining_pressure_Pa:
        return hi
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if float(bundle.stress(np.asarray(mid))) < settings.confining_pressure_Pa:
            lo = mid
        else:
            hi = mid
    return lo


@settings(max_examples=40, deadline=None)
@given(
    v0=st.floats(0.05, 0.75),
    modulus_GPa=st.floats(3.0, 500.0),
    pressure=st.floats(1e2, 1e8),
)
@example(v0=0.12968676960320746, modulus_GPa=38.91752928599386, pressure=6098275.462180635)
def test_jamming_fraction_is_resolved_to_neighbouring_floats_as_a_bisection_finds_it(
    v0: float, modulus_GPa: float, pressure: float
) -> None:
    compaction = TowCompaction(confining_pressure_Pa=pressure)
    vj = jamming_fraction(v0, modulus_GPa * 1e9, compaction)
    bundle = BundleCompaction(
        modulus_GPa * 1e9, compaction.fibre_wave_ratio, v0, v0, SQUARE_PACKING, packing_margin=1e-2
    )
    if vj < bundle.cap_fraction:
        # the root is bracketed by vj and the next float above it, up to the rounding of σ_b
        # itself: the search evaluates σ_b on arrays, and numpy's vectorised path of the law
        # differs from its one-element path by an ulp in ~5 % of cases (hypothesis found
        # σ_b(next float) = p − 1 ulp on one path and ≥ p on the other)
        rounding = 4 * np.finfo(float).eps * pressure
        assert float(bundle.stress(np.asarray(vj))) < pressure + rounding
        above = np.nextafter(vj, 1.0)
        assert float(bundle.stress(np.asarray(above))) >= pressure - rounding
    expected = bisected_jamming_fraction(v0, modulus_GPa * 1e9, compaction)
    assert vj == pytest.approx(expected, rel=1e-15, abs=0.0)
