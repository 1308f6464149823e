"""Tests of the example plugin, written the way a third-party plugin repository would."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import preform_bilinear

FABRIC = """\
name: my-plain-weave
architecture: woven
source: my lab, picture frame test PF-17 (2026)
note: bilinear fit of one measured curve
weave: {pattern: plain}
tow_types:
  glass: {fibre: glass, linear_density_tex: 1190, width_mm: 3.1, height_mm: 0.35}
warp: {tow_spacing_mm: 4.0, tow_type: glass}
weft: {tow_spacing_mm: 4.0, tow_type: glass}
shear_law:
  law: bilinear
  initial_slope_N_per_m_per_deg: 0.002
  locked_slope_N_per_m_per_deg: 0.05
  locking_angle_deg: 40
"""


@pytest.fixture
def plugins(preform_plugins):
    preform_plugins.load_builtins("core", "woven")
    preform_plugins.register(preform_bilinear, "bilinear")
    return preform_plugins


def test_energy_is_the_integral_of_torque():
    law = preform_bilinear.build(
        preform_bilinear.BilinearParams(
            law="bilinear",
            initial_slope_N_per_m_per_deg=0.01,
            locked_slope_N_per_m_per_deg=0.2,
            locking_angle_deg=35,
        ),
        None,
    )
    g = np.linspace(0, np.radians(60), 20001)
    trapezoid = np.concatenate(
        [[0], np.cumsum(np.diff(g) * 0.5 * (law.torque(g)[1:] + law.torque(g)[:-1]))]
    )
    np.testing.assert_allclose(law.energy(g), trapezoid, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(law.energy(-g), law.energy(g))


def test_a_library_entry_uses_the_plugin_law(plugins, tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text(FABRIC)
    lib = plugins.library([path])
    law = lib.shear_law("my-plain-weave")
    assert isinstance(law, preform_bilinear.BilinearLaw)
    assert law.locking_angle == pytest.approx(np.radians(40))


def test_bad_parameters_are_located(plugins, tmp_path):
    from preform.library import LibraryError

    path = tmp_path / "mine.yaml"
    path.write_text(FABRIC.replace("locking_angle_deg: 40", "locking_angle_deg: 95"))
    with pytest.raises(LibraryError) as info:
        plugins.library([path])
    (err,) = info.value.errors
    assert str(err).startswith(f"{path}:14:22: my-plain-weave.shear_law.locking_angle_deg:")
