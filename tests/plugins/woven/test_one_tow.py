"""One tow model (issue 24): the sheared cell and the woven law hold the same tow, so they give
the same tow fibre fraction at every angle, and the fabric's fraction rises past locking until
the tows jam; thickness grows only after that."""

from __future__ import annotations

import math

import numpy as np
import pytest

import preform
from preform.plugins.woven.shear import FrictionCompactionLaw

RAD = math.pi / 180


@pytest.fixture(scope="module")
def library() -> preform.Library:
    return preform.load_library()


def woven_names(library: preform.Library) -> list[str]:
    return [n for n in library.names() if library.fabric(n).architecture == "woven"]


def test_every_bundled_woven_fabric_holds_one_tow(library: preform.Library) -> None:
    names = woven_names(library)
    assert len(names) >= 5
    angles = np.radians(np.arange(0.0, 89.0, 0.5))
    for name in names:
        fabric = library.fabric(name)
        law = library.shear_law(name)
        assert isinstance(law, FrictionCompactionLaw), name
        jam = law.packing_angle if law.packing_angle is not None else math.radians(89.0)
        warp_law, weft_law = law.tow_volume_fractions(angles)
        cells = [fabric.sheared_cell(float(g)) for g in angles]
        cell = cells[0]
        # the cell's families, warp-wise and weft-wise, of the law's level pair
        warp_cell = np.array([c.states[0].fraction for c in cells], dtype=float)
        weft_cell = np.array([c.states[-1].fraction for c in cells], dtype=float)
        if len(cell.families) == 2:  # a 2D weave of one tow type per direction
            np.testing.assert_allclose(warp_law, warp_cell, rtol=0, atol=1e-6, err_msg=name)
            np.testing.assert_allclose(weft_law, weft_cell, rtol=0, atol=1e-6, err_msg=name)
        # The cell's jamming angle is the law's (the first family to jam).
        assert cell.jamming_angle == pytest.approx(jam, abs=1e-9), name
        vf = np.array([c.fibre_volume_fraction for c in cells])
        thickness = np.array([c.thickness for c in cells])
        lock = cell.locking_angle
        compacting = (angles > lock + 1e-9) & (angles < jam - 1e-9)
        if compacting.sum() >= 2:
            # Past locking and before jamming the tows compact at constant height: the fabric
            # fraction rises and the thickness stays.
            assert np.all(np.diff(vf[compacting]) > 0), name
            assert np.ptp(thickness[compacting]) <= 1e-9 * thickness[0], name
        jammed = angles > jam + 1e-9
        if jammed.sum() >= 2:
            assert np.all(np.diff(thickness[jammed]) > 0), name  # thickens only after jamming


def test_law_and_cell_agree_on_a_hybrid_free_weave_at_many_pressures() -> None:
    """The same agreement for a plain weave whose tows carry their own compaction block."""
    from preform.plugins.woven.model import WovenFabric
    from preform.plugins.woven.shear import FrictionCompactionParams, build_friction_compaction

    for pressure in (1.0, 100.0, 2000.0):
        entry = WovenFabric.model_validate(
            {
                "name": "t",
                "architecture": "woven",
                "source": "test",
                "note": "illustrative",
                "tow_types": {
                    "t": {
                        "fibre": "carbon",
                        "linear_density_tex": 200,
                        "width_mm": 1.6,
                        "height_mm": 0.2,
                        "compaction": {
                            "fibre_wave_ratio": 200,
                            "max_volume_fraction": 0.8,
                            "confining_pressure_kPa": pressure,
                        },
                    }
                },
                "warp": {"tow_spacing_mm": 2.0, "tow_type": "t"},
                "weft": {"tow_spacing_mm": 2.0, "tow_type": "t"},
                "weave": {"pattern": "satin", "harness": 5, "move": 2},
            }
        )
        law = build_friction_compaction(
            FrictionCompactionParams.model_validate(
                {"law": "friction_compaction", "pretension_N": 30.0}
            ),
            entry,
        )
        angles = np.radians(np.arange(0.0, 89.0, 1.0))
        warp_law, _ = law.tow_volume_fractions(angles)
        warp_cell = [entry.sheared_cell(float(g)).states[0].fraction for g in angles]
        np.testing.assert_allclose(warp_law, np.asarray(warp_cell, float), atol=1e-6)


def same_tows(weave: dict[str, object]) -> object:
    """The bundled 2/2 twill's tows (600 tex glass, 3.2 × 0.17 mm at 4.0 mm) in ``weave``."""
    from preform.plugins.woven.model import WovenFabric

    return WovenFabric.model_validate(
        {
            "name": f"same-tows-{weave['pattern']}",
            "architecture": "woven",
            "source": "test",
            "note": "illustrative: the bundled twill's tows in another weave",
            "tow_types": {
                "g": {
                    "fibre": "glass",
                    "linear_density_tex": 600,
                    "width_mm": 3.2,
                    "height_mm": 0.17,
                }
            },
            "warp": {"tow_spacing_mm": 4.0, "tow_type": "g"},
            "weft": {"tow_spacing_mm": 4.0, "tow_type": "g"},
            "weave": weave,
            "shear_law": {"law": "friction_compaction", "pretension_N": 50},
        }
    )


def test_hemisphere_energy_at_ninety_orders_the_weaves_with_identical_tows() -> None:
    """Issue 24: with identical tows the hemisphere energy at α = 90° orders 8HS ≤ 5HS ≤
    crowfoot ≤ 2/2 twill (crowfoot and twill within 1 %) < plain, the known drapeability order
    of these weaves (satins drape best; e.g. Hexcel's handbook ranks plain < twill < satin)."""
    weaves = {
        "plain": {"pattern": "plain"},
        "twill": {"pattern": "twill", "over": 2, "under": 2},
        "crowfoot": {"pattern": "crowfoot"},
        "5HS": {"pattern": "satin", "harness": 5, "move": 2},
        "8HS": {"pattern": "satin", "harness": 8, "move": 3},
    }
    energy = {
        name: preform.drape(same_tows(w), generator_angle_deg=90, node_spacing_mm=5).summary[
            "total_energy_J"
        ]
        for name, w in weaves.items()
    }
    assert energy["8HS"] <= energy["5HS"] <= energy["crowfoot"] <= energy["twill"] < energy["plain"]
    assert energy["crowfoot"] == pytest.approx(energy["twill"], rel=1e-2)
