"""The warp-knit ``stitch_yarn`` law: stitch strain, tension, energy and failure from the lapping
notation and the stitch yarn's path in the unit cell."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import preform
from preform.plugins.warpknit.model import WarpKnitFabric
from preform.plugins.warpknit.stitch_law import (
    StitchLevel,
    StitchYarnLaw,
    StitchYarnParams,
    build_stitch_yarn,
    net_stretches,
)
from preform.shear.law import ShearLaw

RAD = math.pi / 180


@pytest.fixture(scope="module")
def library() -> Any:
    return preform.load_library()


def params(**fields: Any) -> StitchYarnParams:
    return StitchYarnParams.model_validate({"law": "stitch_yarn", **fields})


def with_lapping(library: Any, sequence: str, name: str = "E-BX-318") -> WarpKnitFabric:
    data = library.fabric(name).model_dump(exclude_none=True)
    data["threads"][0]["knitting_sequence"] = sequence
    fabric = WarpKnitFabric.model_validate(data)
    assert fabric.errors() == []
    return fabric


def chain_level(failure_strain: float = 0.25, legs: float = 0.0) -> StitchLevel:
    """A pillar stitch idealised as a thread straight along r (loops of 6 mm, underlaps of
    2.5 mm per course) with vertical legs of ``legs`` [m] per loop."""
    segments = []
    for _ in range(2):
        segments += [[0.0, 0.0, legs], [3e-3, 0.0, 0.0], [-3e-3, 0.0, 0.0], [0.0, 0.0, -legs]]
        segments += [[2.5e-3, 0.0, 0.0]]
    return StitchLevel(
        segments=np.array(segments),
        repeat_area=5e-3 * 5.08e-3,
        loops=2,
        axial_stiffness=10e9 * 5.5e-9,
        failure_strain=failure_strain,
        patch_radius=1.5e-3,
    )


def test_the_law_is_registered_and_a_shear_law(library: Any) -> None:
    law = library.registry.shear_law_type("stitch_yarn").build(params(), library.fabric("E-BX-318"))
    assert isinstance(law, ShearLaw) and isinstance(law, StitchYarnLaw)


@settings(max_examples=20, deadline=None)
@given(sequence=st.sampled_from(["1-0/0-1", "1-0/1-2", "0-1/2-1", "1-0/2-3", "1-0/1-0"]))
def test_zero_strain_and_energy_at_zero_shear(library: Any, sequence: str) -> None:
    law = build_stitch_yarn(params(), with_lapping(library, sequence))
    assert isinstance(law, StitchYarnLaw)
    for level in law.levels:
        assert float(level.length(0.0)) == pytest.approx(level.rest_length, rel=1e-14)
        assert float(level.strain(0.0)) == 0.0
    assert float(law.energy(0.0)) == 0.0 and float(law.torque(0.0)) == 0.0


def test_chain_stitch_strain_is_the_fabric_stretch_along_it() -> None:
    """A thread lying along r is stretched exactly as the fabric along r, λ₁ − 1, in γ > 0 and
    is slack in γ < 0; with legs, by the share of its length in the plane."""
    g = np.radians(np.linspace(0.5, 80.0, 50))
    stretch = np.sqrt(2.0) * np.cos(np.radians(45.0) - g / 2) - 1.0  # closed form, λ₁ − 1
    flat = chain_level()
    np.testing.assert_allclose(flat.strain(g), stretch, rtol=1e-13)
    assert np.all(flat.strain(-g) == 0.0)
    legged = chain_level(legs=0.4e-3)
    in_plane = 2 * (6e-3 + 2.5e-3)
    np.testing.assert_allclose(
        legged.strain(g), stretch * in_plane / legged.rest_length, rtol=1e-13
    )


def test_bundled_chain_stitch_follows_the_closed_form(library: Any) -> None:
    """E-BX-318's pillar stitch (loops with a thread diameter between their legs): the length
    change is (λ₁ − 1)·Σ|a| within max(1, λ₂)·Σ|b| (Σ|a|, Σ|b| its path along and across r)."""
    law = build_stitch_yarn(params(), library.fabric("E-BX-318"))
    assert isinstance(law, StitchYarnLaw)
    (level,) = law.levels
    along = np.abs(level.segments[:, 0]).sum()
    across = np.abs(level.segments[:, 1]).sum()
    assert across < 0.02 * level.rest_length
    for deg in (5.0, 20.0, 35.0, 50.0):
        l1, l2 = net_stretches(deg * RAD)
        change = float(level.length(deg * RAD)) - level.rest_length
        assert abs(change - (float(l1) - 1.0) * along) <= max(1.0, float(l2)) * across
        assert float(level.strain(-deg * RAD)) == 0.0  # slack perpendicular to the stitch


def test_stretching_energy_is_the_yarns_elastic_energy() -> None:
    """Without friction, W = ½·E·A·ε²·L₀/A_repeat: the torque is the exact slope of it."""
    level = chain_level(failure_strain=0.9, legs=0.3e-3)
    law = StitchYarnLaw([level], params(ply_friction_coefficient=0.0))
    g = np.radians([5.0, 20.0, 40.0, 60.0])
    expected = 0.5 * level.axial_stiffness * level.strain(g) ** 2 * level.rest_length
    np.testing.assert_allclose(law.energy(g), expected / level.repeat_area, rtol=1e-9)


@settings(max_examples=25, deadline=None)
@given(failure_strain=st.floats(0.02, 0.4))
def test_failure_where_the_closed_form_strain_reaches_the_yarns_strain_at_break(
    failure_strain: float,
) -> None:
    level = chain_level(failure_strain=failure_strain)
    law = StitchYarnLaw([level], params())
    # √2·cos(45° − γ/2) − 1 = ε_b
    expected = 2.0 * (math.radians(45.0) - math.acos((1.0 + failure_strain) / math.sqrt(2.0)))
    assert law.failure_angle == pytest.approx(expected, abs=1e-12)
    assert law.failure_angle_negative is None  # slack that way: it never breaks
    after = np.linspace(expected + 1e-6, 85 * RAD, 20)
    assert np.all(law.torque(after) == 0.0)
    np.testing.assert_allclose(law.energy(after), law.energy(expected), rtol=1e-12)
    assert float(law.torque(expected - 1e-6)) > 0.0


def test_lapping_notations_give_different_curves(library: Any) -> None:
    g = np.radians([-50.0, -30.0, -10.0, 10.0, 30.0, 50.0])
    curves = {
        seq: build_stitch_yarn(params(yarn_failure_strain=0.9), with_lapping(library, seq))
        for seq in ("1-0/0-1", "1-0/1-2", "1-0/2-3", "1-0/3-4")
    }
    energies = {seq: law.energy(g) for seq, law in curves.items()}
    names = list(energies)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            assert not np.allclose(energies[a], energies[b], rtol=1e-3), (a, b)


def test_paper_qualitatively_chain_fails_near_35_tricot_smoother(library: Any) -> None:
    """Paper: the chain-stitched E-BX 318 fails near 35° shearing parallel to the stitch; the
    tricot E-BXhd 936 is smoother and less asymmetric. Not tuned: the yarn data are the
    bundled illustrative ones (strain at break 0.25, polyester 10 GPa)."""
    chain = build_stitch_yarn(params(), library.fabric("E-BX-318"))
    tricot = build_stitch_yarn(params(), library.fabric("E-BXhd-936"))
    assert isinstance(chain, StitchYarnLaw) and isinstance(tricot, StitchYarnLaw)
    assert chain.failure_angle is not None and 30 * RAD < chain.failure_angle < 45 * RAD
    assert chain.failure_angle_negative is None
    assert tricot.failure_angle is None and tricot.failure_angle_negative is None
    g = np.radians(np.linspace(1.0, 60.0, 60))
    gap_chain = np.abs(chain.torque(g) + chain.torque(-g))[g < chain.failure_angle]
    gap_tricot = np.abs(tricot.torque(g) + tricot.torque(-g))
    assert gap_tricot.max() < 0.1 * gap_chain.max()


def test_patch_radius_matches_the_closed_form_of_a_rectangle() -> None:
    """The loop patch's mean radius against the woven law's closed form (a separate derivation) for a
    crossover parallelogram, which at γ = 0 is the same rectangle."""
    from preform.plugins.warpknit.stitch_law import rectangle_mean_radius
    from preform.plugins.woven.shear import contact_mean_radius

    for length, width in ((2.5e-3, 5.08e-3), (1e-3, 1e-3), (4e-3, 0.5e-3)):
        closed = float(contact_mean_radius(length, width, 0.0))
        assert rectangle_mean_radius(length, width) == pytest.approx(closed, rel=1e-9)


def test_a_thread_without_its_strain_at_break_is_a_located_error(library: Any) -> None:
    data = library.fabric("E-BX-318").model_dump(exclude_none=True)
    data["shear_law"] = params()
    del data["threads"][0]["failure_strain"]
    fabric = WarpKnitFabric.model_validate(data)
    ((where, message),) = fabric.errors()
    assert where == ("threads", 0, "failure_strain") and "strain at break" in message
    data["shear_law"] = params(yarn_failure_strain=0.2)  # given in the law instead
    assert WarpKnitFabric.model_validate(data).errors() == []
