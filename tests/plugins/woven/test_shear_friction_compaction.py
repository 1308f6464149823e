"""Woven friction–compaction shear law (paper Eqns 1–5) and bundle compaction."""

from __future__ import annotations

import math
import pickle
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError
from scipy.integrate import quad

from preform.plugins.woven.compaction import (
    BundleCompaction,
    gutowski_coefficient,
    gutowski_stiffness,
    gutowski_stress,
)
from preform.plugins.woven.crossover import CrossoverGeometry
from preform.plugins.woven.shear import (
    SHEAR_LAWS,
    FrictionCompactionLaw,
    FrictionCompactionParams,
    build_friction_compaction,
    contact_mean_radius,
    crimp_angle,
    locking_angle,
    plain_weave_geometry,
    tow_width,
)
from preform.plugins.woven.tow_jamming import TowCompaction
from preform.shear.law import ShearLaw, force_per_length_N_per_mm

RAD = math.pi / 180
HEAVY = plain_weave_geometry(3.1, 4.0, 1190)  # Table 1, 600 g/m²
LIGHT = plain_weave_geometry(1.2, 2.0, 150)  # Table 1, 150 g/m²


def params(**fields: float) -> FrictionCompactionParams:
    base = {"law": "friction_compaction", "pretension_N": 100.0, "fabric_thickness_mm": 2.0}
    return FrictionCompactionParams.model_validate({**base, **fields})


def heavy(**fields: float) -> FrictionCompactionLaw:
    return FrictionCompactionLaw(HEAVY, params(**fields))


# -- contact radius ----------------------------------------------------------------------------


def test_square_contact_radius_closed_form() -> None:
    w = 3.1e-3
    expected = w * (math.sqrt(2) + math.log(1 + math.sqrt(2))) / 6
    assert contact_mean_radius(w, w, 0.0) == pytest.approx(expected, rel=1e-14)


def test_rectangle_contact_radius_matches_quadrature() -> None:
    a, b = 2.0, 0.5  # half-sides
    integral, _ = quad(
        lambda x: quad(lambda y: math.hypot(x, y), -b, b, epsabs=1e-13)[0], -a, a, epsabs=1e-12
    )
    assert contact_mean_radius(2 * b, 2 * a, 0.0) == pytest.approx(integral / (4 * a * b))


@pytest.mark.parametrize(("w1", "w2", "deg"), [(3.1, 3.1, 35.0), (1.0, 2.5, 60.0)])
def test_skewed_contact_radius_matches_monte_carlo(w1: float, w2: float, deg: float) -> None:
    g = deg * RAD
    phi = math.pi / 2 - g  # angle between the tow directions
    d1, d2 = np.array([1.0, 0.0]), np.array([math.cos(phi), math.sin(phi)])
    # Edge vectors: along strip 1 the parallelogram is w2/sin φ long, along strip 2 w1/sin φ.
    e1, e2 = d1 * w2 / math.sin(phi), d2 * w1 / math.sin(phi)
    rng = np.random.default_rng(7)
    uv = rng.uniform(-0.5, 0.5, size=(400_000, 2))
    points = uv[:, :1] * e1 + uv[:, 1:] * e2
    distance = np.hypot(points[:, 0], points[:, 1])
    estimate, error = distance.mean(), distance.std() / math.sqrt(len(distance))
    assert contact_mean_radius(w1, w2, g) == pytest.approx(estimate, abs=4 * error)
    # Every sampled point really lies in both strips (the parallelogram is their overlap).
    n2 = np.array([-math.sin(phi), math.cos(phi)])
    assert np.all(np.abs(points[:, 1]) <= w1 / 2 + 1e-12)
    assert np.all(np.abs(points @ n2) <= w2 / 2 + 1e-12)


@settings(max_examples=30, deadline=None)
@given(st.floats(0.1, 10.0), st.floats(0.1, 10.0), st.floats(-89.0, 89.0))
def test_contact_radius_symmetries(w1: float, w2: float, deg: float) -> None:
    r = contact_mean_radius(w1, w2, deg * RAD)
    assert r == pytest.approx(contact_mean_radius(w2, w1, deg * RAD), rel=1e-10)
    assert r == pytest.approx(contact_mean_radius(w1, w2, -deg * RAD), rel=1e-12)
    # Scale invariance, and bounded by the half-diagonal of the parallelogram.
    assert contact_mean_radius(2 * w1, 2 * w2, deg * RAD) == pytest.approx(2 * r, rel=1e-10)
    g = deg * RAD
    half_long = 0.5 * math.hypot(w2 + w1 * abs(math.sin(g)), w1 * math.cos(g)) / math.cos(g)
    assert 0.0 < r < half_long * (1 + 1e-9) + 1e-12


# -- tow width, locking -----------------------------------------------------------------------


def test_locking_angles_of_table_1() -> None:
    assert math.degrees(locking_angle(3.1, 4.0)) == pytest.approx(39.19, abs=0.005)
    assert math.degrees(locking_angle(1.2, 2.0)) == pytest.approx(53.13, abs=0.005)
    assert math.degrees(heavy().locking_angle or 0) == pytest.approx(39.19, abs=0.005)
    law = FrictionCompactionLaw(LIGHT, params(pretension_N=50, fabric_thickness_mm=0.6))
    assert math.degrees(law.locking_angle or 0) == pytest.approx(53.13, abs=0.005)


def test_tow_width_is_continuous_at_locking() -> None:
    lock = locking_angle(3.1e-3, 4e-3)
    around = tow_width(np.array([lock - 1e-9, lock, lock + 1e-9]), 3.1e-3, 4e-3)
    np.testing.assert_allclose(around, 3.1e-3, rtol=1e-8)
    assert tow_width(60 * RAD, 3.1e-3, 4e-3) == pytest.approx(4e-3 * 0.5)


def test_crimp_angle_of_a_two_arc_path() -> None:
    # tan(θ/2) = h/Ts: h = Ts gives a quarter circle each way, θ = 90°.
    assert crimp_angle(1.0, 1.0) == pytest.approx(math.pi / 2)


# -- compaction ---------------------------------------------------------------------------------


def test_gutowski_check_value_and_clamp() -> None:
    assert gutowski_stress(0.60, 1.0, 0.5, 0.785) == pytest.approx(223.06, abs=0.005)
    assert gutowski_stress(0.45, 1.0, 0.5, 0.785) == 0.0
    assert gutowski_stress(0.785, 1.0, 0.5, 0.785) == np.inf
    assert gutowski_coefficient(72e9, 350.0) == pytest.approx(3 * math.pi * 72e9 / 350.0**4)


def test_gutowski_stiffness_is_the_derivative() -> None:
    v = np.array([0.55, 0.65, 0.75])
    h = 1e-7
    numeric = (
        gutowski_stress(v + h, 1.0, 0.5, 0.785) - gutowski_stress(v - h, 1.0, 0.5, 0.785)
    ) / (2 * h)
    np.testing.assert_allclose(gutowski_stiffness(v, 1.0, 0.5, 0.785), numeric, rtol=1e-6)


def test_bundle_stress_is_gutowski_increase_and_guarded_at_the_pole() -> None:
    bundle = BundleCompaction(72e9, 30.0, initial_fraction=0.3, onset_fraction=0.3)
    a_s = bundle.coefficient
    assert bundle.stress(0.5) == pytest.approx(gutowski_stress(0.5, a_s, 0.3, math.pi / 4))
    assert bundle.stress(0.2) == 0.0
    cap = bundle.cap_fraction
    assert cap == pytest.approx(math.pi / 4 * (1 - 1e-3))
    v = np.array([cap - 1e-9, cap, cap + 1e-9, 0.9, 5.0])
    s = bundle.stress(v)
    assert np.all(np.isfinite(s)) and np.all(np.diff(s) > 0)
    assert s[0] == pytest.approx(s[1], rel=1e-4) and s[2] == pytest.approx(s[1], rel=1e-4)


def test_coupling_compliance_stiffens_the_bundle() -> None:
    free = BundleCompaction(72e9, 30.0, 0.3, 0.3)
    coupled = BundleCompaction(72e9, 30.0, 0.3, 0.3, coupling_compliance=2e-10)
    v = np.array([0.4, 0.5, 0.6])
    assert np.all(coupled.stress(v) >= free.stress(v))
    assert np.all(np.isfinite(coupled.stress(np.array([0.77, 0.9]))))
    with pytest.raises(ValueError):
        BundleCompaction(72e9, 30.0, 0.8, 0.3)  # as-woven fraction past V_a


# -- the law --------------------------------------------------------------------------------


def test_initial_torque_is_the_paper_eqn_1() -> None:
    law = heavy()
    g = 1e-6
    # Independent recomputation of μ F_c R_eff n for the plain weave at γ → 0.
    tension = 100.0 * 4e-3 / 0.150
    theta = 2 * math.atan(1e-3 / 4e-3)
    contact = 2 * tension * math.sin(theta)
    radius = 3.1e-3 * (math.sqrt(2) + math.log(1 + math.sqrt(2))) / 6
    expected = 0.3 * contact * radius / 16e-6
    assert law.torque(g) == pytest.approx(expected, rel=1e-6)
    assert law.contact_force(g) == pytest.approx(contact)


def test_law_is_a_symmetric_shear_law_and_pickles() -> None:
    law = heavy()
    assert isinstance(law, ShearLaw)
    assert law.failure_angle is None
    g = np.radians(np.linspace(0, 85, 18))
    np.testing.assert_array_equal(law.torque(-g), -law.torque(g))
    np.testing.assert_array_equal(law.energy(-g), law.energy(g))
    clone = pickle.loads(pickle.dumps(law))
    np.testing.assert_array_equal(clone.energy(g), law.energy(g))


def test_gentle_past_locking_steep_before_the_tows_limit() -> None:
    # Gutowski's stress starts at zero at the as-built fraction and rises towards its pole, so
    # the torque bends up gently past locking and steeply just before the tows reach their own
    # limit (σ_b = the confining pressure), where measured curves turn up too.
    law = heavy()
    lock = law.locking_angle or 0.0
    limit = min(law.kink_angles or (law.packing_angle or 0.0,))
    assert lock < limit
    step = 1 * RAD
    before = (law.torque(lock) - law.torque(lock - step)) / step
    after = (law.torque(lock + step) - law.torque(lock)) / step
    late = (law.torque(limit) - law.torque(limit - step)) / step
    assert 0.0 < before and after < 3 * before
    assert late > 5 * after


def test_energy_matches_independent_quadrature() -> None:
    law = heavy()
    lock = law.locking_angle or 0.0
    for deg in (20.0, 39.19, 55.0):
        expected, _ = quad(
            lambda g: float(law.torque(g)), 0, deg * RAD, points=[lock], epsabs=1e-12, limit=200
        )
        assert law.energy(deg * RAD) == pytest.approx(expected, rel=1e-9)


def test_finite_and_monotone_up_to_ninety_degrees() -> None:
    law = heavy()
    g = np.radians(np.append(np.linspace(0, 89.99, 400), [90.0, 95.0]))
    torque, energy = law.torque(g), law.energy(g)
    force = force_per_length_N_per_mm(law, g)
    assert (
        np.all(np.isfinite(torque)) and np.all(np.isfinite(energy)) and np.all(np.isfinite(force))
    )
    assert np.all(np.diff(energy) >= 0.0)
    packing = law.packing_angle or 0.0
    assert (law.locking_angle or 0.0) < packing < math.pi / 2


def test_zero_friction_and_zero_pretension() -> None:
    g = np.radians([10.0, 30.0, 50.0, 70.0])
    assert np.all(heavy(friction_coefficient=0.0).torque(g) == 0.0)
    slack = heavy(pretension_N=0.0)
    lock = slack.locking_angle or 0.0
    assert np.all(slack.torque(g[g < lock]) == 0.0)
    assert np.all(slack.torque(g[g > lock]) > 0.0)


def test_extreme_parameters_stay_finite() -> None:
    g = np.radians([1.0, 45.0, 80.0])
    laws = [heavy(pretension_N=1e6)]
    for beta in (1.0, 1e4):
        tows = TowCompaction(fibre_wave_ratio=beta)
        geometry = replace(HEAVY, compaction_warp=tows, compaction_weft=tows)
        laws.append(FrictionCompactionLaw(geometry, params()))
    for law in laws:
        assert np.all(np.isfinite(law.torque(g))) and np.all(np.isfinite(law.energy(g)))


def test_a_weave_with_floats_needs_its_tow_paths() -> None:
    twill = replace(HEAVY, interlacings_per_area=HEAVY.crossovers_per_area)  # half the gaps
    with pytest.raises(ValueError, match="rises of the tow paths"):
        FrictionCompactionLaw(twill, params())


def test_several_geometries_add() -> None:
    p = params()
    one = FrictionCompactionLaw(HEAVY, p)
    two = FrictionCompactionLaw([HEAVY, HEAVY], p)
    assert two.torque(0.5) == pytest.approx(2 * one.torque(0.5))


def test_builder_uses_the_fabric_crossover_geometry() -> None:
    class Fabric:
        def crossover_geometry(self) -> CrossoverGeometry:
            return HEAVY

    name, model, builder = SHEAR_LAWS[0]
    assert name == "friction_compaction" and model is FrictionCompactionParams
    assert builder is build_friction_compaction
    law = build_friction_compaction(params(), Fabric())
    assert law.torque(0.2) == pytest.approx(heavy().torque(0.2))


def test_params_forbid_unknown_fields_and_default_friction() -> None:
    assert params().friction_coefficient == 0.3
    with pytest.raises(ValidationError):
        params(tow_spacing_mm=4.0)
    with pytest.raises(ValidationError):
        FrictionCompactionParams.model_validate({"law": "friction_compaction"})
    # No free thickness: the law takes the unit cell's own tow heights.
    bare = FrictionCompactionParams.model_validate(
        {"law": "friction_compaction", "pretension_N": 1}
    )
    assert bare.fabric_thickness_mm is None
