"""Wrinkling as a result (issue 24): the cells past jamming or stitch failure, their area and
energy shares against a sum written here, and the status rule on both sides of one half."""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import BaseModel, ConfigDict

from preform import hookimpl
from preform.drape.engine.fields import energy_field
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.drape.judging.verdict import law_range
from preform.drape.judging.wrinkling import (
    PAST_JAMMING,
    WRINKLE_ENERGY_SHARE_MAX,
    WrinkleLimit,
    makeable,
    wrinkle_limits,
    wrinkling,
)
from preform.plugins.surfaces.basic import Hemisphere

JAM_DEG = 30.0
STIFFNESS = 2.0  # N·m/m² per rad


class JammingLaw:
    """C = k·γ up to the jamming angle γj, then the held torque h·k·γj (odd in γ): the
    woven law's shape past jamming, with the held level a free multiple h."""

    locking_angle = None
    failure_angle = None

    def __init__(self, held: float, jam_deg: float = JAM_DEG, **extra: Any) -> None:
        self.held = float(held)
        self.packing_angle = math.radians(jam_deg)
        for name, value in extra.items():
            setattr(self, name, value)

    def torque(self, gamma: Any) -> np.ndarray:
        g = np.asarray(gamma, dtype=float)
        gj = self.packing_angle
        return np.where(np.abs(g) <= gj, STIFFNESS * g, np.sign(g) * self.held * STIFFNESS * gj)

    def energy(self, gamma: Any) -> np.ndarray:
        g = np.abs(np.asarray(gamma, dtype=float))
        gj = self.packing_angle
        return np.where(
            g <= gj,
            0.5 * STIFFNESS * g**2,
            0.5 * STIFFNESS * gj**2 + self.held * STIFFNESS * gj * (g - gj),
        )


@pytest.fixture(scope="module")
def dome() -> Any:
    """A hemisphere R = 100 mm draped at α = 90° from the pole, d = 5 mm (|γ| up to ~55°)."""
    return drape(
        Hemisphere(0.1),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((0.36, 0.36)),
        start_xy_m=(0.0, 0.0),
        generator_angle_rad=math.radians(90),
        trim=Hemisphere(0.1).part(),
    )


def _sums(result: Any, held: float) -> tuple[float, float, float, float, float]:
    """Written out per cell, with the law's closed form: (A, B, C, jammed area, all area) with
    the jammed cells' energy A + h·B, the others' C [J], areas in the part [m²]."""
    gj = math.radians(JAM_DEG)
    d2 = result.node_spacing**2
    a = b = c = jam_area = all_area = 0.0
    ni, nj = result.shear.shape
    for i in range(ni):
        for j in range(nj):
            if not (result.valid[i, j] and result.in_part[i, j]):
                continue
            s = float(result.part_share[i, j])
            g = abs(float(result.shear[i, j]))
            area = float(result.area[i, j]) * s
            all_area += area
            if g > gj:
                a += 0.5 * STIFFNESS * gj * gj * s * d2
                b += STIFFNESS * gj * (g - gj) * s * d2
                jam_area += area
            else:
                c += 0.5 * STIFFNESS * g * g * s * d2
    return a, b, c, jam_area, all_area


def test_shares_match_a_sum_written_out_cell_by_cell(dome: Any) -> None:
    law = JammingLaw(held=1.0)
    energy = energy_field(dome, law)
    found = wrinkling(dome, energy.energy_density, wrinkle_limits(law_range(law)))
    a, b, c, jam_area, all_area = _sums(dome, 1.0)
    assert jam_area > 0 and c > 0
    (zone,) = found.zones
    assert zone.limit.cause == PAST_JAMMING
    assert zone.energy_share == pytest.approx((a + b) / (a + b + c), rel=1e-9)
    assert zone.area_share == pytest.approx(jam_area / all_area, rel=1e-9)
    assert zone.area_mm2 == pytest.approx(jam_area * 1e6, rel=1e-9)
    assert found.total_energy_J == pytest.approx(energy.total_energy, rel=1e-9)
    assert (found.energy_share, found.area_share) == (zone.energy_share, zone.area_share)
    # the cell flags are the same cells, and the table columns say the same numbers
    counted = dome.valid & dome.in_part
    past = counted & (np.abs(dome.shear) > math.radians(JAM_DEG))
    assert np.array_equal(energy.past_jamming, past)
    assert np.array_equal(energy.wrinkling, past)
    assert zone.cells == found.cells == int(past.sum())
    assert found.columns()["wrinkle_past_jamming_area_share"] == zone.area_share
    # how far past: the largest |γ| of those cells, less the limit
    peak = math.degrees(float(np.abs(dome.shear[past]).max()))
    assert zone.max_excess_deg == pytest.approx(peak - JAM_DEG, abs=1e-9)
    # where: on a dome draped from the pole at 90° the shear peaks on the four diagonals,
    # so four patches, one per quadrant, of equal area, adding up to the whole
    assert len(zone.patches) == 4
    assert sum(area for _, area in zone.patches) == pytest.approx(zone.area_mm2, rel=1e-9)
    quadrants = {(np.sign(x), np.sign(y)) for (x, y), _ in zone.patches}
    assert quadrants == {(1, 1), (1, -1), (-1, 1), (-1, -1)}
    x0, y0, x1, y1 = zone.bbox_mm or (0, 0, 0, 0)
    assert all(x0 <= x <= x1 and y0 <= y <= y1 for (x, y), _ in zone.patches)


def test_the_status_rule_turns_at_half_the_energy(dome: Any) -> None:
    """Held torques chosen (from the closed-form sums) to put 48 % and 52 % of the energy
    past jamming: makeable on one side, not on the other; the same area either way."""
    a, b, c, _, _ = _sums(dome, 1.0)

    def held_for(share: float) -> float:  # (a + h·b) / (a + h·b + c) = share
        return (share * (a + c) - a) / (b * (1.0 - share))

    for share, mostly in ((0.48, False), (0.52, True)):
        law = JammingLaw(held=held_for(share))
        energy = energy_field(dome, law)
        found = wrinkling(dome, energy.energy_density, wrinkle_limits(law_range(law)))
        assert found.energy_share == pytest.approx(share, rel=1e-9)
        assert found.mostly_wrinkle is mostly
        assert bool(found.reason()) is mostly
    assert WRINKLE_ENERGY_SHARE_MAX == 0.5


def test_what_can_be_made_is_judged_by_area_within_a_tolerance_and_a_cap() -> None:
    # (area share, least share any angle reaches, tolerance, cap)
    assert makeable(0.03, 0.01) and not makeable(0.03 + 1e-9, 0.01)  # default tolerance 0.02
    assert makeable(0.5, 0.5, 0.0) and not makeable(0.5 + 1e-12, 0.5, 0.0)
    assert makeable(0.05, 0.05, max_area_share=0.05)
    assert not makeable(0.0500001, 0.05, max_area_share=0.05)


def test_a_law_may_state_further_wrinkle_limits(dome: Any) -> None:
    """A law's own ``wrinkle_limits`` are reported beside jamming, in their own sense only."""
    own = WrinkleLimit("past_seam", math.radians(20.0), None, "the seam angle 20°", "it tears")
    law = JammingLaw(held=1.0, wrinkle_limits=(own,))
    energy = energy_field(dome, law)
    found = wrinkling(dome, energy.energy_density, wrinkle_limits(law_range(law)))
    assert [z.limit.cause for z in found.zones] == [PAST_JAMMING, "past_seam"]
    counted = dome.valid & dome.in_part
    seam = counted & (dome.shear > math.radians(20.0))
    jam = counted & (np.abs(dome.shear) > math.radians(JAM_DEG))
    assert found.zones[1].cells == int(seam.sum()) > 0
    assert (dome.shear[counted] < -math.radians(20.0)).any()  # the other sense is not counted
    assert found.cells == int((seam | jam).sum())  # a cell past both counts once
    assert np.array_equal(energy.wrinkling, seam | jam)
    assert found.columns()["wrinkle_past_seam_cells"] == int(seam.sum())
    with pytest.raises(TypeError, match="wrinkle_limits must hold"):
        law_range(JammingLaw(held=1.0, wrinkle_limits=("past_seam",)))


# -- through the pipeline and the API ---------------------------------------------------------


class JammingParams(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)
    law: Literal["jamming_test"]
    held: float
    jam_deg: float = JAM_DEG


class JammingPlugin:
    @hookimpl
    def preform_register_shear_laws(self, register: Any) -> None:
        register.add("jamming_test", JammingParams, lambda p, fabric: JammingLaw(p.held, p.jam_deg))


FABRIC = """\
name: jam-{tag}
architecture: woven
source: a test law (illustrative)
note: illustrative
weave: {{pattern: plain}}
tow_types:
  glass: {{fibre: glass, linear_density_tex: 1190, width_mm: 3.1, height_mm: 0.35}}
warp: {{tow_spacing_mm: 4.0, tow_type: glass}}
weft: {{tow_spacing_mm: 4.0, tow_type: glass}}
shear_law: {{law: jamming_test, held: {held}, jam_deg: {jam}}}
"""


@pytest.fixture
def jam_library(preform_plugins: Any, tmp_path: Any) -> Any:
    preform_plugins.load_builtins()
    preform_plugins.register(JammingPlugin(), "jamming-test")

    def library(**fabrics: tuple[float, float]) -> Any:
        path = tmp_path / "jam.yaml"
        path.write_text(
            "\n".join(
                "---\n" + FABRIC.format(tag=tag, held=held, jam=jam)
                for tag, (held, jam) in fabrics.items()
            )
        )
        return preform_plugins.library([path])

    return library


def test_the_api_drape_is_partial_past_half_and_ok_below(jam_library: Any) -> None:
    """The bundled hemisphere scene; held torques from the closed-form sums over its own
    net (a first drape) put 45 % and 55 % of the energy past jamming."""
    import preform

    def dome(tag: str, lib: Any) -> Any:
        return preform.drape(f"jam-{tag}", library=lib, node_spacing_mm=5, generator_angle_deg=90)

    probe = dome("probe", jam_library(probe=(1.0, JAM_DEG)))
    a, b, c, _, _ = _sums(probe.products["drape"].result, 1.0)
    low, high = ((s * (a + c) - a) / (b * (1.0 - s)) for s in (0.45, 0.55))
    lib = jam_library(low=(low, JAM_DEG), high=(high, JAM_DEG))
    kept, made = dome("low", lib), dome("high", lib)
    assert kept.status == "ok" and kept.ok
    assert kept.wrinkling is not None
    assert kept.wrinkling["energy_share"] == pytest.approx(0.45, abs=0.01)
    assert made.status == "partial" and not made.ok
    block = made.wrinkling
    assert block is not None and block["mostly_wrinkle"] is True
    share = block["causes"][PAST_JAMMING]["energy_share"]
    assert share == pytest.approx(0.55, abs=0.01)
    (reason,) = made.reasons
    assert "past jamming at 30.0°" in reason
    assert f"{100 * share:.1f} % of its total energy" in reason
    assert f"{100 * block['area_share']:.1f} % of the part's draped area" in reason
    assert made.summary["wrinkle_energy_share"] == block["energy_share"]
    assert f"({100 * block['energy_share']:.3g} % of it past jamming" in repr(made)
    # the cells table flags the same cells the block counts
    table = made.to_pandas()
    assert int(table["past_jamming"].sum()) == int(table["wrinkling"].sum()) == block["cells"]


def test_the_search_is_partial_when_no_angle_can_be_made(jam_library: Any, tmp_path: Any) -> None:
    """Jammed at 5° with a held torque 50× the jamming one, every angle is mostly wrinkle and
    more than the scene's cap of 1 % of its area is wrinkled: the search returns the angle of
    least wrinkle and says so; the trade table has every angle with its shares and makeable,
    in the summary, the CSV and the API."""
    import csv

    import preform
    from preform.optimise.search_steps import TRADE_COLUMNS

    lib = jam_library(stiff=(50.0, 5.0))
    best = preform.least_energy(
        "jam-stiff",
        library=lib,
        out_dir=tmp_path / "out",
        node_spacing_mm=10,
        generator_angle_range_deg=(60, 120),
        max_wrinkle_area_share=0.01,
        outputs=["energy_vs_angle", "optimum", "energy_vs_angle_csv"],
    )
    assert best.status == "partial" and not best.makeable
    assert any(
        "no generator angle in [60°, 120°] drapes within the wrinkling cap" in r
        for r in best.reasons
    )
    table = best.energy_vs_angle
    assert list(table.columns) == list(TRADE_COLUMNS)
    assert not table["makeable"].any()
    assert (table["wrinkle_energy_share"] > 0.5).all()
    assert (table["wrinkle_area_share"] > 0.01).all()
    least = table.loc[table["wrinkle_area_share"].idxmin(), "generator_angle_deg"]
    assert best.optimum_generator_angle_deg == pytest.approx(least)
    assert best.case_dir is not None
    with open(best.case_dir / "energy_vs_angle.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert tuple(rows[0]) == TRADE_COLUMNS and len(rows) == len(table)
    for row, (_, want) in zip(rows, table.iterrows(), strict=True):
        assert float(row["wrinkle_energy_share"]) == pytest.approx(want["wrinkle_energy_share"])
        assert row["makeable"] == str(bool(want["makeable"]))


@settings(max_examples=40, deadline=None)
@given(
    cells=st.lists(st.lists(st.booleans(), min_size=6, max_size=6), min_size=5, max_size=5),
    seed=st.integers(0, 1000),
)
def test_connected_patches_match_a_flood_fill(cells: list[list[bool]], seed: int) -> None:
    """The shared patch finder against a flood fill written here (8-neighbours), with random
    centres and weights (some zero: such a patch's centre is the plain mean)."""
    from preform.drape.judging.wrinkling import connected_patches

    mask = np.array(cells, dtype=bool)
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-50, 50, size=(*mask.shape, 2))
    weights = rng.choice([0.0, 0.5, 2.0], size=mask.shape)
    seen = np.zeros_like(mask)
    want = []
    for start in zip(*np.nonzero(mask), strict=True):
        if seen[start]:
            continue
        stack, members = [start], []
        seen[start] = True
        while stack:
            i, j = stack.pop()
            members.append((i, j))
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    a, b = i + di, j + dj
                    if 0 <= a < mask.shape[0] and 0 <= b < mask.shape[1] and mask[a, b]:
                        if not seen[a, b]:
                            seen[a, b] = True
                            stack.append((a, b))
        w = np.array([weights[m] for m in members])
        xy = np.array([centres[m] for m in members])
        mid = (xy * w[:, None]).sum(axis=0) / w.sum() if w.sum() > 0 else xy.mean(axis=0)
        want.append((tuple(mid), float(w.sum())))
    got = connected_patches(mask, centres, weights)
    assert len(got) == len(want)
    key = lambda p: (round(p[1], 9), round(p[0][0], 6), round(p[0][1], 6))  # noqa: E731
    for (c_got, t_got), (c_want, t_want) in zip(
        sorted(got, key=key), sorted(want, key=key), strict=True
    ):
        assert t_got == pytest.approx(t_want) and c_got == pytest.approx(c_want)
    assert [t for _, t in got] == sorted((t for _, t in got), reverse=True)
