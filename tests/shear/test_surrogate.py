"""The tabulated surrogate: fourth-order accurate against the exact law, and still a law."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.shear.surrogate import TabulatedSurrogate


@pytest.fixture(scope="module")
def library():
    import preform

    return preform.load_library()


BUNDLED = [
    "plain-weave-600",
    "plain-weave-150",
    "satin-8hs-carbon",
    "orthogonal-3d-glass",
    "E-BXhd-936",
    "E-BX-318",
]


@pytest.mark.parametrize("name", BUNDLED)
def test_error_within_the_stated_bound_and_fourth_order(library, name):
    law = library.shear_law(name)
    coarse = TabulatedSurrogate(law, math.radians(1.0)).max_relative_error()
    half = TabulatedSurrogate(law, math.radians(0.5)).max_relative_error()
    default = TabulatedSurrogate(law).max_relative_error()
    assert default <= 3e-7
    # Hermite interpolation of W with exact slopes: the error falls as h^4 (ratio 16 per
    # halving) unless it is already at round-off
    assert half < 1e-12 or coarse / half > 10


@pytest.mark.parametrize("name", BUNDLED)
def test_surrogate_is_still_a_law(library, name):
    law = library.shear_law(name)
    s = TabulatedSurrogate(law)
    g = np.linspace(0, math.radians(89), 4001)
    assert s.energy(0.0) == 0.0
    for sense in (1, -1):
        w = s.energy(sense * g)
        assert np.all(np.isfinite(w)) and np.all(w >= 0)
        assert np.all(np.diff(w) >= -1e-12 * w.max())
    # the surrogate's torque is the slope of its own energy, close to the law's torque
    gm = g[(g > 0.01) & (g < math.radians(60))]
    fd = (s.energy(gm + 1e-7) - s.energy(gm - 1e-7)) / 2e-7
    np.testing.assert_allclose(s.torque(gm), fd, rtol=1e-5, atol=1e-9 * s.energy(1.0))
    np.testing.assert_allclose(s.torque(gm), law.torque(gm), rtol=1e-3, atol=1e-6)
    assert s.locking_angle == law.locking_angle and s.failure_angle == law.failure_angle


def test_asymmetric_law_keeps_its_branches(library):
    law = library.shear_law("E-BX-318")
    s = TabulatedSurrogate(law)
    g = math.radians(40)
    assert s.energy(g) == pytest.approx(law.energy(g), rel=1e-6)
    assert s.energy(-g) == pytest.approx(law.energy(-g), rel=1e-6)
    assert s.energy(g) > 3 * s.energy(-g)


@settings(max_examples=60, deadline=None)
@given(st.floats(-math.pi / 2, math.pi / 2), st.floats(0.05, 2.0))
def test_matches_a_cubic_energy_exactly(gamma, step_deg):
    """A law whose W is a cubic in |γ| is reproduced to round-off by cubic Hermite tables."""

    class Cubic:
        locking_angle = None
        failure_angle = None

        def torque(self, g):
            g = np.asarray(g, dtype=float)
            return np.sign(g) * (2.0 + 3.0 * g**2)

        def energy(self, g):
            u = np.abs(np.asarray(g, dtype=float))
            return 2.0 * u + u**3

    s = TabulatedSurrogate(Cubic(), math.radians(step_deg))
    assert s.energy(gamma) == pytest.approx(Cubic().energy(gamma), rel=1e-12, abs=1e-14)


def test_bad_step_is_refused():
    with pytest.raises(ValueError, match="table step"):
        TabulatedSurrogate(None, 0.0)  # type: ignore[arg-type]
