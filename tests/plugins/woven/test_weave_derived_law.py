"""The woven friction–compaction law derived from the weave: crimp contacts from the unit cell's
tow paths, one geometry for law and cell, and the jamming limit."""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.plugins.woven.crimp import crossover_geometry_with_crimp, wrap_rises
from preform.plugins.woven.model import WovenFabric
from preform.plugins.woven.shear import (
    FrictionCompactionLaw,
    FrictionCompactionParams,
    build_friction_compaction,
)

RAD = math.pi / 180


def fabric(weave: dict[str, Any], width: float = 3.1, height: float = 0.32) -> WovenFabric:
    return WovenFabric.model_validate(
        {
            "name": "test",
            "architecture": "woven",
            "source": "test",
            "note": "illustrative",
            "tow_types": {
                "t": {
                    "fibre": "glass",
                    "linear_density_tex": 1190,
                    "width_mm": width,
                    "height_mm": height,
                }
            },
            "warp": {"tow_spacing_mm": 4.0, "tow_type": "t"},
            "weft": {"tow_spacing_mm": 4.0, "tow_type": "t"},
            "weave": weave,
        }
    )


def law_of(weave: dict[str, Any], **fields: Any) -> FrictionCompactionLaw:
    p = FrictionCompactionParams.model_validate(
        {"law": "friction_compaction", "pretension_N": 100.0, **fields}
    )
    law = build_friction_compaction(p, fabric(weave))
    assert isinstance(law, FrictionCompactionLaw)
    return law


PLAIN = {"pattern": "plain"}
#: Same tows, fewer interlacings per crossover down the list: 1, 2/3, 1/2, 2/5, 1/4.
FAMILY = [
    PLAIN,
    {"pattern": "twill", "over": 2, "under": 1},
    {"pattern": "twill", "over": 2, "under": 2},
    {"pattern": "satin", "harness": 5, "move": 2},
    {"pattern": "satin", "harness": 8, "move": 3},
]


def gutowski_increase(v: float, v0: float, beta: float, modulus: float, va: float) -> float:
    """Second implementation of Gutowski's stress rise over the as-built fraction [Pa]."""
    a_s = 3 * math.pi * modulus / beta**4

    def sigma(x: float) -> float:
        return a_s * (math.sqrt(x / v0) - 1) / (math.sqrt(va / x) - 1) ** 4

    return sigma(v) - sigma(v0)


def test_plain_weave_is_todays_law() -> None:
    """Built from the plain-weave unit cell with the paper's free thickness (2 mm), the law is
    the paper's: F_pre = T_wp sin θ + T_wt sin θ, θ = 2 atan(h/Ts), h = thickness/2, and its
    torque before locking is the one the law gave before it was derived from the weave (values
    recorded from that release for plain-weave-600). Past locking the compaction force is the
    cell's tow under Gutowski's law (issue 24), recomputed here from the closed form."""
    law = law_of(PLAIN, fabric_thickness_mm=2.0)
    tension = 100.0 * 4.0 / 150.0  # N per tow: pre-tension × Ts / frame width
    theta = 2.0 * math.atan(1.0 / 4.0)
    f_pre = 2 * tension * math.sin(theta)
    assert law.pretension_force() == pytest.approx(f_pre, rel=1e-12)
    before = {10: 56.5446, 30: 63.1377}
    for deg, torque in before.items():
        assert float(law.torque(deg * RAD)) == pytest.approx(torque, rel=1e-5)
    lock = math.acos(3.1 / 4.0)
    assert law.locking_angle == pytest.approx(lock, rel=1e-12)
    v0 = (1190 / 2.55e3) / (math.pi / 4 * 3.1 * 0.32)  # the cell's elliptical tow, mm² / mm²
    own_limit = min(law.kink_angles or (law.packing_angle or 0.0,))
    for gamma in np.linspace(lock + 0.2 * RAD, own_limit - 0.01 * RAD, 5):
        width = 4.0e-3 * math.cos(gamma)
        v = v0 * 3.1e-3 / width
        stress = gutowski_increase(v, v0, 350.0, 72e9, math.pi / 4)
        force = f_pre + stress * width * width / math.cos(gamma)
        radius = float(law.effective_radius(gamma))
        expected = 0.3 * force * radius / (4.0e-3 * 4.0e-3)
        assert float(law.torque(gamma)) == pytest.approx(expected, rel=1e-9)


def test_wrapping_arcs_follow_the_weave() -> None:
    """Per tow and repeat: a plain weave's crossovers are wrapped twice, a 2/2 twill's once
    each, a 5-harness satin's once under the interlacing, twice... by counting its floats:
    one crossover with two arcs, two with one, two with none."""
    for weave, counts in (
        (PLAIN, {2: 1.0}),
        ({"pattern": "twill", "over": 2, "under": 2}, {1: 1.0}),
        ({"pattern": "satin", "harness": 5, "move": 2}, {2: 0.2, 1: 0.4, 0: 0.4}),
        ({"pattern": "crowfoot"}, {2: 0.25, 1: 0.5, 0: 0.25}),
    ):
        warp, weft = wrap_rises(fabric(weave).woven_unit_cell)
        for family in (warp, weft):
            n = np.array([len(r) for r in family])
            share = {k: float(np.mean(n == k)) for k in (0, 1, 2) if np.any(n == k)}
            assert share == pytest.approx(counts), weave
            # Every wrapping rise of a 2D weave of equal tows is one tow height.
            assert all(r == pytest.approx(0.32e-3, rel=1e-12) for rs in family for r in rs)


def test_resistance_falls_monotonically_with_fewer_interlacings() -> None:
    laws = [law_of(w) for w in FAMILY]
    g = np.radians(np.linspace(0.5, 80.0, 120))
    torques = np.array([law.torque(g) for law in laws])
    lock = laws[0].locking_angle or 0.0
    before = g < lock
    assert np.all(np.diff(torques[:, before], axis=0) < 0.0)  # crimp force only: strictly
    assert np.all(np.diff(torques, axis=0) <= 1e-9 * torques[:-1])  # and never more anywhere
    energies = np.array([law.energy(80 * RAD) for law in laws])
    assert np.all(np.diff(energies) < 0.0)


def test_same_interlacings_different_arrangement_differ() -> None:
    """2/2 twill and crowfoot both interlace twice per four crossovers, but the crowfoot's are
    bunched (one crossover wrapped twice, one not at all): 2T sin θ + 0 < 2·2T sin(θ/2)."""
    twill = law_of({"pattern": "twill", "over": 2, "under": 2})
    crowfoot = law_of({"pattern": "crowfoot"})
    assert crowfoot.pretension_force() < twill.pretension_force()
    tension, theta = 100.0 * 4.0 / 150.0, 2.0 * math.atan(0.32 / 4.0)
    expected_twill = 2 * tension * math.sin(theta / 2)  # one arc at every crossover
    assert twill.pretension_force() == pytest.approx(expected_twill, rel=1e-12)
    expected_crowfoot = (2 * tension * math.sin(theta) + 2 * 2 * tension * math.sin(theta / 2)) / 4
    assert crowfoot.pretension_force() == pytest.approx(expected_crowfoot, rel=1e-12)


@settings(max_examples=25, deadline=None)
@given(width=st.floats(1.0, 3.9), weave=st.sampled_from(FAMILY))
def test_tows_that_cannot_compact_lock_and_jam_at_acos_w_over_s(
    width: float, weave: dict[str, Any]
) -> None:
    """Locking is first lateral contact, acos(w/s); a tow already at the packing cap cannot
    compact laterally, so the fabric jams there too, whatever the weave."""
    cap = math.pi / 4 * (1 - 1e-2)
    fibre_area = 1190 / 2.55e3  # mm²
    height = fibre_area / (math.pi / 4 * width * cap * (1 - 1e-9))
    law = build_friction_compaction(
        FrictionCompactionParams.model_validate(
            {"law": "friction_compaction", "pretension_N": 100.0}
        ),
        fabric(weave, width=width, height=height),
    )
    expected = math.acos(width / 4.0)
    assert law.locking_angle == pytest.approx(expected, rel=1e-12)
    assert law.packing_angle == pytest.approx(expected, abs=1e-4)


def test_jamming_holds_the_torque_and_bounds_the_energy() -> None:
    law = law_of(PLAIN, fabric_thickness_mm=2.0)
    jam = law.packing_angle
    assert jam is not None and law.locking_angle is not None
    assert law.locking_angle < jam
    # Jammed where the tows reach the weave's jamming fraction: a plain weave's tows at their
    # own limit, where the bundle stress equals the confining pressure (100 kPa).
    warp, weft = law.tow_volume_fractions(jam)
    family = law._parts[0].families[0]
    assert float(warp) == pytest.approx(family.jamming_fraction, rel=1e-12)
    assert float(weft) == pytest.approx(family.jamming_fraction, rel=1e-12)
    bundle = law._parts[0].bundles[0]
    assert float(bundle.stress(np.asarray(family.jamming_fraction))) == pytest.approx(1e5, rel=1e-6)
    c_jam, w_jam = float(law.torque(jam)), float(law.energy(jam))
    past = np.radians([70.0, 80.0, 89.0, 89.999])
    assert np.all(law.torque(past) == c_jam)
    assert law.energy(past) == pytest.approx(w_jam + c_jam * (past - jam), rel=1e-9)
    assert float(law.energy(89.999 * RAD)) < 2e3  # J/m², not the pole's 1e7–1e9


def test_one_geometry_default_uses_the_cells_tows() -> None:
    """The law's as-woven tow fraction is the unit cell's own, with or without a free
    thickness (which expands only the crimp that wraps the crossovers)."""
    cell = fabric(PLAIN).woven_unit_cell
    for law in (law_of(PLAIN), law_of(PLAIN, fabric_thickness_mm=2.0)):
        bundle = law._parts[0].bundles[0]
        assert bundle.initial_fraction == pytest.approx(cell.tow_volume_fraction("warp"), rel=1e-12)
    geometry = crossover_geometry_with_crimp(cell)
    assert geometry.thickness == pytest.approx(cell.thickness())


WEAVES_BY_FLOAT = [
    PLAIN,
    {"pattern": "twill", "over": 2, "under": 1},
    {"pattern": "twill", "over": 2, "under": 2},
    {"pattern": "crowfoot"},
    {"pattern": "satin", "harness": 5, "move": 2},
    {"pattern": "satin", "harness": 8, "move": 3},
]


@settings(max_examples=20, deadline=None)
@given(
    width=st.floats(1.5, 3.8),
    v0=st.floats(0.3, 0.75),
    pressure_kPa=st.floats(1.0, 1000.0),
)
def test_longer_floats_never_jam_earlier(width: float, v0: float, pressure_kPa: float) -> None:
    """With the same tows, the jamming angle does not decrease as the mean float length grows
    (plain, 2/1 twill, 2/2 twill = crowfoot, 5HS, 8HS); the cell and the law agree on it."""
    height = (1190 / 2.55e3) / (math.pi / 4 * width * v0)
    angles = []
    for weave in WEAVES_BY_FLOAT:
        entry = fabric(weave, width=width, height=height)
        data = entry.model_dump(mode="json", exclude_none=True)
        data["tow_types"]["t"]["compaction"] = {"confining_pressure_kPa": pressure_kPa}
        entry = WovenFabric.model_validate(data)
        law = build_friction_compaction(
            FrictionCompactionParams.model_validate(
                {"law": "friction_compaction", "pretension_N": 100.0}
            ),
            entry,
        )
        cell = entry.sheared_cell(0.0)
        jam = law.packing_angle if law.packing_angle is not None else math.pi / 2
        assert cell.jamming_angle == pytest.approx(jam, abs=1e-12)
        angles.append(jam)
    assert all(b >= a - 1e-12 for a, b in itertools.pairwise(angles))
    assert angles[2] == pytest.approx(angles[3], abs=1e-12)  # 2/2 twill and crowfoot


def test_straight_stuffers_press_nothing_binders_do() -> None:
    """A 3D orthogonal weave: stuffers run straight (no wrapping arcs at any contact), binders
    wrap the weft they pass round."""
    cell = fabric({"pattern": "orthogonal", "stuffer_layers": 2, "weft_layers": 3}).woven_unit_cell
    warp, _ = wrap_rises(cell)
    binders = set(cell.weave.binder_levels)
    stuffer_wraps = [
        r for c, r in zip(cell.contacts(), warp, strict=True) if c.warp_level not in binders
    ]
    binder_wraps = [
        r for c, r in zip(cell.contacts(), warp, strict=True) if c.warp_level in binders
    ]
    assert stuffer_wraps and all(r == () for r in stuffer_wraps)
    assert binder_wraps and any(len(r) > 0 for r in binder_wraps)
