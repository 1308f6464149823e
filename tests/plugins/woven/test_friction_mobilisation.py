"""Friction mobilisation of the woven law (``shear_law.friction_mobilisation_deg``, γ_m).

Truths: Dahl's closed form written out here, C(γ) = C_Coulomb(γ)·(1 − exp(−γ/γ_m)) with
C_Coulomb the same fabric's law at γ_m = 0; its energy, integrated here by an independent
composite Simpson rule; the Coulomb limit γ_m → 0; symmetry C(−γ) = −C(γ).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import preform
from preform.library import build_shear_law
from preform.shear.calibrate import validated_fabric


@pytest.fixture(scope="module")
def library() -> preform.library.Library:
    return preform.load_library()


def law_with(library, name: str, mobilisation_deg: float):
    entry = library.fabric(name).model_dump(mode="json", exclude_none=True)
    entry["shear_law"]["friction_mobilisation_deg"] = mobilisation_deg
    return build_shear_law(validated_fabric(entry, library.registry), library.registry)


@settings(max_examples=12, deadline=None)
@given(mobilisation_deg=st.floats(0.2, 90.0))
def test_the_torque_is_dahls_share_of_the_coulomb_torque(library, mobilisation_deg) -> None:
    coulomb = law_with(library, "plain-weave-600", 0.0)
    dahl = law_with(library, "plain-weave-600", mobilisation_deg)
    gamma = np.radians(np.linspace(0.05, 60.0, 97))
    share = 1.0 - np.exp(-gamma / math.radians(mobilisation_deg))
    # past jamming both laws hold the torque they reached at the jamming angle
    held = np.minimum(gamma, coulomb.packing_angle or math.pi / 2)
    share_held = 1.0 - np.exp(-held / math.radians(mobilisation_deg))
    expected = coulomb.torque(gamma) * np.where(gamma < held, share, share_held)
    np.testing.assert_allclose(dahl.torque(gamma), expected, rtol=1e-12)
    np.testing.assert_allclose(dahl.torque(-gamma), -dahl.torque(gamma), rtol=1e-12)
    assert (np.diff(dahl.torque(gamma)) >= 0).all()  # still rising: a convex energy


@pytest.mark.parametrize("mobilisation_deg", [0.3, 5.0, 40.0])
def test_the_energy_integrates_the_mobilised_torque(library, mobilisation_deg) -> None:
    law = law_with(library, "plain-weave-600", mobilisation_deg)
    top = math.radians(38.0)  # before locking (39.0°): a smooth integrand
    x = np.linspace(0.0, top, 4001)
    y = law.torque(x)
    simpson = (x[1] - x[0]) / 3 * (y[0] + y[-1] + 4 * y[1:-1:2].sum() + 2 * y[2:-1:2].sum())
    assert float(law.energy(top)) == pytest.approx(simpson, rel=1e-7)


def test_a_small_mobilisation_angle_tends_to_coulomb(library) -> None:
    coulomb = law_with(library, "plain-weave-600", 0.0)
    gamma = np.radians([2.0, 20.0, 45.0])
    for small, tol in ((0.1, 1e-8), (0.01, 1e-14)):  # exp(-20), exp(-200): rounding
        near = law_with(library, "plain-weave-600", small)
        np.testing.assert_allclose(near.torque(gamma), coulomb.torque(gamma), rtol=tol)
    # the energy differs by C·γ_m (the area Dahl's ramp leaves out), nothing more
    near = law_with(library, "plain-weave-600", 0.1)
    lost = float(coulomb.energy(gamma[1]) - near.energy(gamma[1]))
    c0 = float(coulomb.torque(math.radians(0.5)))
    assert lost == pytest.approx(c0 * math.radians(0.1), rel=0.02)


def test_the_torque_starts_from_zero_with_a_finite_slope(library) -> None:
    """Dahl's slope at zero is C_Coulomb(0)/γ_m: the measured curves' initial slope."""
    mobilisation = math.radians(10.0)
    law = law_with(library, "plain-weave-600", 10.0)
    coulomb = law_with(library, "plain-weave-600", 0.0)
    tiny = 1e-6
    assert float(law.torque(0.0)) == 0.0
    slope = float(law.torque(tiny)) / tiny
    assert slope == pytest.approx(float(coulomb.torque(tiny)) / mobilisation, rel=1e-4)


def test_the_angle_is_a_checked_parameter(library) -> None:
    entry = library.fabric("plain-weave-600").model_dump(mode="json", exclude_none=True)
    entry["shear_law"]["friction_mobilisation_deg"] = -1.0
    with pytest.raises(ValueError, match="friction_mobilisation_deg"):
        validated_fabric(entry, library.registry)
    entry["shear_law"]["friction_mobilisation_deg"] = 120.0
    with pytest.raises(ValueError, match=r"friction_mobilisation_deg.*plausible"):
        validated_fabric(entry, library.registry)


@pytest.mark.parametrize("mobilisation_deg", [0.05, 0.3, 1.0, 5.0])
def test_the_drape_table_follows_the_ramp(library, mobilisation_deg) -> None:
    """The surrogate a drape evaluates holds the steep rise from zero as it holds the bundled
    laws (3e-7 of the largest energy over ±60°, its documented accuracy)."""
    from preform.shear.surrogate import TabulatedSurrogate

    law = law_with(library, "plain-weave-600", mobilisation_deg)
    assert TabulatedSurrogate(law).max_relative_error() <= 3e-7
