"""The fibre-pattern figure says what matters and compares across fabrics: its title gives the
coverage and the nodes on the part (not the ply's run-off), cells past stitch failure are
outlined as past-locking ones are, and every figure shares one shear colour scale."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from matplotlib.colors import to_rgba

import preform
from preform.export.fig_drape import (
    FAILURE_COLOUR,
    SHEAR_SCALE_DEG,
    fibre_pattern_figure,
    percent,
    shear_view_quads,
)


def by_gid(fig, gid):
    (artist,) = [a for a in fig.get_children() if a.get_gid() == gid]
    return artist


def nodes_on_part_by_loop(net) -> int:
    """Placed nodes that are a corner of a valid cell with some of its area in the part: a
    loop over the cells, written here apart from the figure's array code."""
    ni, nj = net.shape
    counted = set()
    for i in range(ni - 1):
        for j in range(nj - 1):
            share = 1.0 if net.part_share is None else net.part_share[i, j]
            if net.valid[i, j] and net.in_part[i, j] and share > 0:
                counted |= {(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)}
    return sum(1 for i, j in counted if net.status[i, j] == 0)


def test_the_title_gives_the_coverage_and_the_nodes_on_the_part(make_net, make_energy) -> None:
    net = make_net(14, 12, generator_angle_deg=80.0)
    share = np.ones(net.valid.shape)
    share[:, :4] = 0.0  # a third of the ply hangs past the part's edge
    share[:, 4] = 0.5
    net = dataclasses.replace(net, part_share=share)
    expected = nodes_on_part_by_loop(net)
    assert expected < net.nodes_placed  # the old title counted every placed node
    fig = fibre_pattern_figure(net, make_energy(net), None, title="fabric", covered_fraction=1.0)
    title = fig._suptitle.get_text()
    assert f"covers 100 % of the ply over the tool, {expected} nodes on the part" in title
    assert "nodes placed" not in title and f"/{net.nodes_total}" not in title
    partial = fibre_pattern_figure(net, None, None, covered_fraction=0.9996)
    assert "covers 99.9 % of the ply" in partial._suptitle.get_text()
    alone = fibre_pattern_figure(net, None, None)  # coverage not known: the nodes only
    assert f"90.0°, {expected} nodes on the part" not in alone._suptitle.get_text()
    assert f"{expected} nodes on the part" in alone._suptitle.get_text()


@pytest.mark.parametrize(
    ("fraction", "words"), [(1.0, "100 %"), (0.9996, "99.9 %"), (0.5, "50.0 %"), (0.0, "0.0 %")]
)
def test_percent_says_100_only_when_whole(fraction, words) -> None:
    assert percent(fraction) == words


def test_cells_past_stitch_failure_are_outlined_in_their_colour(make_net, make_energy) -> None:
    net = make_net(10, 12, dome=True)
    energy = make_energy(net, locking_deg=10.0, failure_deg=5.0)
    failed = np.asarray(energy.past_failure) & net.valid
    locked_only = np.asarray(energy.past_locking) & net.valid & ~failed
    assert failed.any() and locked_only.any()
    fig = fibre_pattern_figure(net, energy, None)
    cells = by_gid(fig, "shear cells")
    edges = cells.get_edgecolor()
    magenta = np.all(np.isclose(edges, to_rgba(FAILURE_COLOUR)), axis=1)
    black = np.all(np.isclose(edges, (0.0, 0.0, 0.0, 1.0)), axis=1)
    assert magenta.sum() == failed.sum()  # one quad a cell at this size, in depth order
    assert black.sum() == locked_only.sum()
    title = by_gid(fig, "shear title").get_text()
    assert f"{failed.sum()} cell(s) past stitch failure (magenta outline)" in title


def test_blocks_of_a_fine_net_keep_their_failed_cells(make_net, make_energy) -> None:
    net = make_net(40, 40, dome=True)
    energy = make_energy(net, failure_deg=5.0)
    failed = np.asarray(energy.past_failure)
    view = shear_view_quads(net, net.valid, energy.past_locking, 100, past_failure=failed)
    assert view.block > 1 and view.failed is not None
    assert len(view.failed) == len(view.quads_mm)
    # a block is failed exactly when one of its cells is: at least one quad per failed region,
    # and no quad failed where no cell is
    assert view.failed.any() == failed[net.valid].any()
    untouched = shear_view_quads(net, net.valid, None, 100, past_failure=np.zeros_like(failed))
    assert not untouched.failed.any()


def test_two_fabrics_share_the_colour_scale(make_net, make_energy) -> None:
    """Two drapes of different largest shear get the same scale, so a colour is one angle in
    both; shear past it is counted in the panel's title. ``shear_scale_deg=None`` scales one
    figure to itself."""
    mild = make_net(8, 8, generator_angle_deg=80.0)  # γ = −10°
    strong = make_net(8, 8, generator_angle_deg=20.0)  # γ = −70°, past the scale
    scales = []
    for net in (mild, strong):
        fig = fibre_pattern_figure(net, make_energy(net), None)
        norm = by_gid(fig, "colour scale").norm
        scales.append((norm.vmin, norm.vmax))
    assert scales[0] == scales[1] == pytest.approx((-SHEAR_SCALE_DEG, SHEAR_SCALE_DEG))
    title = by_gid(fig, "shear title").get_text()
    beyond = int(np.count_nonzero(strong.valid))
    assert f"{beyond} cell(s) beyond ±60° (drawn in the end colours)" in title
    own = fibre_pattern_figure(mild, None, None, shear_scale_deg=None)
    assert by_gid(own, "colour scale").norm.vmax == pytest.approx(10.0)


def test_a_runs_figures_share_the_scale_and_say_the_coverage(tmp_path, monkeypatch) -> None:
    """Through the pipeline's step, for two fabrics whose optimum drapes differ: one scale, and
    a complete drape says 100 %."""
    import preform.export.fig_drape as fig_drape
    from preform.export.drape_outputs import write_fibre_pattern_png
    from preform.step import CaseContext

    drawn = []
    original = fig_drape.fibre_pattern_figure
    monkeypatch.setattr(
        fig_drape, "fibre_pattern_figure", lambda *a, **k: drawn.append(original(*a, **k))
    )
    largest = []
    for name, angle in (("plain-weave-150", 85), ("E-BX-318", 70)):
        d = preform.drape(name, node_spacing_mm=10, generator_angle_deg=angle)
        ctx = CaseContext(d.fabric, d.scene, preform.default_host().registry, tmp_path / name)
        (tmp_path / name).mkdir()
        ctx.products.update(d.products)
        ctx.summary.update(d.summary)
        write_fibre_pattern_png(ctx)
        largest.append(d.summary["max_abs_shear_deg"])
        assert (tmp_path / name / "fibre_pattern.png").stat().st_size > 10_000
    assert abs(largest[0] - largest[1]) > 1.0  # the old per-figure scales would differ
    norms = [by_gid(fig, "colour scale").norm for fig in drawn]
    assert [(n.vmin, n.vmax) for n in norms] == [(-SHEAR_SCALE_DEG, SHEAR_SCALE_DEG)] * 2
    for fig in drawn:
        assert "covers 100 % of the ply over the tool" in fig._suptitle.get_text()
