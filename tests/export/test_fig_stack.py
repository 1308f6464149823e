"""The stack's figure: its stations drawn as the cells they are, coloured by their total
thickness, or as one marker a station when the cells are not given."""

from __future__ import annotations

import numpy as np
from matplotlib.collections import PathCollection, QuadMesh

from preform.export.fig_stack import stack_figure
from preform.stack.maps import StackMaps


def flat_stack() -> tuple[StackMaps, tuple[np.ndarray, np.ndarray]]:
    """A flat 6 × 7-node net [mm] whose stations are the centres of some of its cells, in
    row-major order, two plies, thicknesses that differ station by station."""
    i, j = np.meshgrid(np.arange(6.0), np.arange(7.0), indexing="ij")
    nodes = np.stack([10 * i, 10 * j, np.zeros_like(i)], axis=-1)
    region = np.zeros((5, 6), dtype=bool)
    region[1:4, 2:5] = True
    region[4, 0] = True
    ci, cj = np.nonzero(region)
    centres = np.stack([10 * ci + 5.0, 10 * cj + 5.0, np.zeros(len(ci))], axis=1)
    k = len(ci)
    thickness = np.column_stack([0.5 + 0.01 * np.arange(k), np.full(k, 0.4)])
    wrinkles = np.zeros((k, 2), dtype=bool)
    wrinkles[0, 1] = True
    maps = StackMaps(
        points_mm=centres,
        area_mm2=np.full(k, 100.0),
        ply_names=("a", "b"),
        present=np.ones((k, 2), dtype=bool),
        thickness_mm=thickness,
        fibre_volume_fraction=np.full((k, 2), 0.5),
        wrinkles=wrinkles,
    )
    return maps, (nodes, region)


def test_stations_are_drawn_as_their_cells_in_station_order(tmp_path):
    maps, net = flat_stack()
    fig = stack_figure(maps, tmp_path / "s.png", "t", net)
    (mesh,) = [a for a in fig.get_children() if isinstance(a, QuadMesh)]
    colour = mesh.get_array()
    region = net[1]
    rows, cols = np.flatnonzero(region.any(axis=1)), np.flatnonzero(region.any(axis=0))
    cropped = region[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]
    assert np.array_equal(~np.ma.getmaskarray(colour).reshape(cropped.shape), cropped)
    assert np.array_equal(colour.reshape(cropped.shape)[cropped], maps.total_thickness_mm)
    # each station's cell has the net's corners [mm] (a node no station uses may be moved)
    drawn = mesh.get_coordinates()
    own = net[0][rows[0] : rows[-1] + 2, cols[0] : cols[-1] + 2, :2]
    for ci, cj in zip(*np.nonzero(cropped), strict=True):
        cell = (slice(ci, ci + 2), slice(cj, cj + 2))
        assert np.array_equal(drawn[cell], own[cell])
    assert (tmp_path / "s.png").stat().st_size > 0


def test_without_the_cells_each_station_is_a_marker():
    maps, (nodes, region) = flat_stack()
    for net in (None, (nodes, region[:, :-1])):  # none given, or not the stations' cells
        fig = stack_figure(maps, None, "t", net)
        assert not [a for a in fig.get_children() if isinstance(a, QuadMesh)]
        (squares,) = [a for a in fig.get_children() if isinstance(a, PathCollection)]
        assert np.array_equal(squares.get_offsets(), maps.points_mm[:, :2])
        assert np.array_equal(squares.get_array(), maps.total_thickness_mm)
