"""Figures a report can take (issue 16): linear energy axes with readable optima, one title,
readable warp-knit cells, no unresolved errors drawn as data; units on every axis."""

from __future__ import annotations

import math

import numpy as np
import pytest

import preform
from preform.bench.tradeoff import TradeoffResult, TradeoffRow, error_floors, plot_tradeoff
from preform.export.fig_curves import (
    ENERGY_AXIS_FACTOR,
    energy_vs_angle_figure,
    library_energy_figure,
)


def _curve(best: float, energy: float, lock: float) -> list[tuple[float, float]]:
    """E(α) with its least energy at ``best`` and a locking blow-up (1e9 J) at the ends."""
    angles = np.arange(30.0, 151.0, 10.0)
    return [(a, energy * (1 + 1e-3 * (a - best) ** 2) + lock * (abs(a - 90) > 55)) for a in angles]


def _units_on_every_axis(fig) -> None:
    from matplotlib.text import Text

    # what is drawn on the figure by hand (the 3D view): every word label gives its unit
    words = [a.get_text() for a in fig.artists if isinstance(a, Text)]
    words = [w for w in words if not w.replace("\N{MINUS SIGN}", "-").lstrip("-")[:1].isdigit()]
    assert all("[" in w for w in words if not w.startswith("Shear angle")), words
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>":
            continue
        assert "[" in ax.get_xlabel(), ax.get_xlabel()
        if ax.get_yticklabels() and ax.get_ylabel():
            assert "[" in ax.get_ylabel(), ax.get_ylabel()


def test_the_library_figure_has_linear_axes_and_one_row_per_optimum():
    names = [f"fabric-{k}" for k in range(8)]
    curves = {n: _curve(90.0 if k else 74.0, 0.3 + k, 1e9) for k, n in enumerate(names)}
    optima = {n: (90.0 if k else 74.0) for k, n in enumerate(names)}
    fig = library_energy_figure(
        curves,
        None,
        optima=optima,
        optimum_energies_J={names[0]: 0.3},
        half_widths_deg={names[0]: 1.5},
    )
    curve_ax, optimum_ax = fig.axes
    assert curve_ax.get_yscale() == optimum_ax.get_yscale() == "linear"
    assert curve_ax.get_ylim()[1] <= 3.0  # E/E*: the 1e9 J ends are off the scale, said so
    assert any("off the scale" in t.get_text() for t in curve_ax.texts)
    rows = [t.get_text() for t in optimum_ax.get_yticklabels()]
    assert sorted(rows) == sorted(names)  # seven optima at 90°, each on its own row
    notes = [t.get_text() for t in optimum_ax.texts]
    assert any(n.startswith("74.0°, E* = 0.3 J") for n in notes)
    _units_on_every_axis(fig)


def test_many_fabrics_on_one_call_get_the_library_layout():
    curves = {f"f{k}": _curve(90.0, 1.0 + k, 1e9) for k in range(6)}
    fig = energy_vs_angle_figure(curves, None, optima=dict.fromkeys(curves, 90.0))
    assert len(fig.axes) == 2 and all(ax.get_yscale() == "linear" for ax in fig.axes)


def test_one_fabric_energy_axis_is_linear_and_ends_above_the_optimum():
    fig = energy_vs_angle_figure(
        {"E-BX-318": _curve(70.0, 0.58, 1e9)}, None, optima={"E-BX-318": 70.0}
    )
    (ax,) = fig.axes
    assert ax.get_yscale() == "linear"
    assert ax.get_ylim() == pytest.approx((0.0, ENERGY_AXIS_FACTOR * 0.58))
    assert any("off the scale" in t.get_text() for t in ax.texts)
    _units_on_every_axis(fig)


def test_the_fibre_pattern_title_says_the_angle_once(tmp_path, monkeypatch):
    import preform.export.fig_drape as fig_drape
    from preform.export.drape_outputs import write_fibre_pattern_png
    from preform.step import CaseContext

    drawn = []
    original = fig_drape.fibre_pattern_figure
    monkeypatch.setattr(
        fig_drape, "fibre_pattern_figure", lambda *a, **k: drawn.append(original(*a, **k))
    )
    d = preform.drape("plain-weave-150", node_spacing_mm=10, generator_angle_deg=85)
    ctx = CaseContext(d.fabric, d.scene, preform.default_host().registry, tmp_path)
    ctx.products.update(d.products)
    write_fibre_pattern_png(ctx)
    title = drawn[0]._suptitle.get_text()
    assert title.startswith("plain-weave-150\n") and title.count("generator angle") == 1
    _units_on_every_axis(drawn[0])


def test_a_warp_knit_cell_is_shown_as_a_readable_detail(tmp_path):
    from preform.export.fig_unit_cell import DETAIL_MM, unit_cell_figure

    cell = preform.load_library().fabric("E-BX-318").unit_cell()
    fig = unit_cell_figure(cell, tmp_path / "c.png", repeats=(2, 2), title="E-BX-318")
    assert "detail 25 × 25 mm of a 60.2 × 71.1 mm unit cell" in fig._suptitle.get_text()
    view3d, plan = fig.axes
    for ax in (view3d, plan):
        assert ax.get_xlim()[1] - ax.get_xlim()[0] < 1.5 * DETAIL_MM
    assert view3d.get_legend() is not None and "y [mm]" == plan.get_ylabel()
    assert (tmp_path / "c.png").stat().st_size > 20_000


def _row(label: str, knob: str, wall_s: float, angle: float, energy: float) -> TradeoffRow:
    return TradeoffRow(
        label, knob, "", "standard", 2.5, 1e-9, 0.25, 5.0, 1.0, 60, None, 10, wall_s, 5.0,
        angle, energy, 50.0, False,
    )  # fmt: skip


def test_tradeoff_errors_below_the_reference_resolution_are_not_drawn_as_data(tmp_path):
    rows = [
        _row("reference", "reference", 1.0, 73.3, 0.5844),
        _row("standard", "preset", 0.5, 73.3 + 5e-8, 0.5844 * (1 + 2e-9)),
        _row("draft", "preset", 0.2, 74.4, 0.55),
    ]
    from preform.bench.tradeoff import _fill_errors

    _fill_errors(rows, rows[0], rows[1])
    result = TradeoffResult("hemisphere-min-energy", "E-BX-318", rows, "reference", "standard")
    floors = error_floors(result)
    assert floors == {"angle_error_deg": 1.0, "energy_rel_error": 1e-3}  # --quick: no check
    plot_tradeoff(result, tmp_path / "t.png")
    import matplotlib.image as mpimg

    assert mpimg.imread(tmp_path / "t.png").shape[:2] == (650, 1400)
    result.reference_check = {"energy_rel_error": 0.014, "angle_error_deg": 0.01,
                              "max_shear_error_deg": 0.1}  # fmt: skip
    assert error_floors(result)["energy_rel_error"] == 0.014
    assert math.isfinite(floors["angle_error_deg"])


def test_figures_print_at_a_usable_size(tmp_path):
    """At 100 dpi the figures are 13–16 inches wide: A4 landscape at 150 dpi or more."""
    d = preform.drape("plain-weave-150", node_spacing_mm=10)
    fig = d.plot()
    width, height = fig.get_size_inches() * fig.dpi
    assert width >= 1200 and height >= 600
