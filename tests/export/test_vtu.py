from __future__ import annotations

import meshio
import numpy as np

from preform.drape.engine.result import CellStatus, NodeStatus
from preform.export.vtu import TOW_KIND_CODES, write_drape_vtu, write_unit_cell_vtu


def test_unit_cell_vtu_reads_back_as_one_polyline_per_tow(tmp_path, unit_cell):
    path = tmp_path / "cell.vtu"
    write_unit_cell_vtu(unit_cell, path, volumes=False)

    mesh = meshio.read(path)
    assert len(mesh.points) == sum(len(t.points) for t in unit_cell.tows)
    lines = mesh.cells_dict["line"]
    assert len(lines) == sum(len(t.points) - 1 for t in unit_cell.tows)
    # Segments join consecutive points, and a tow's segments never jump to another tow.
    assert np.all(lines[:, 1] == lines[:, 0] + 1)
    tow = mesh.cell_data_dict["tow"]["line"]
    for k, t in enumerate(unit_cell.tows):
        mine = lines[tow == k]
        # files are in mm, preform holds metres
        np.testing.assert_allclose(mesh.points[mine[:, 0]], 1e3 * t.points[:-1])
        np.testing.assert_allclose(mesh.points[mine[-1, 1]], 1e3 * t.points[-1])
        assert np.all(mesh.cell_data_dict["kind"]["line"][tow == k] == TOW_KIND_CODES[t.kind])
        assert np.all(mesh.cell_data_dict["level"]["line"][tow == k] == t.level)
        np.testing.assert_allclose(mesh.cell_data_dict["width_mm"]["line"][tow == k], 1e3 * t.width)
        np.testing.assert_allclose(
            mesh.cell_data_dict["height_mm"]["line"][tow == k], 1e3 * t.height
        )
    assert [p.name for p in tmp_path.iterdir()] == ["cell.vtu"]  # no temp file left behind


def test_drape_vtu_holds_placed_nodes_and_valid_cells_only(tmp_path, damaged_net, make_energy):
    energy = make_energy(damaged_net)
    path = tmp_path / "drape.vtu"
    write_drape_vtu(damaged_net, energy, path)

    mesh = meshio.read(path)
    assert len(mesh.points) == damaged_net.nodes_placed == 10 * 12 - 2
    quads = mesh.cells_dict["quad"]
    valid = damaged_net.cell_status == CellStatus.VALID
    assert len(quads) == np.count_nonzero(valid) == 9 * 11 - 1 - 2 - 1
    assert np.all(np.isfinite(mesh.points))
    data = {name: mesh.cell_data_dict[name]["quad"] for name in mesh.cell_data_dict}
    for name, values in data.items():
        assert np.all(np.isfinite(values)), name

    i, j = data["i"], data["j"]
    assert np.all(valid[i, j])
    np.testing.assert_allclose(data["shear_deg"], np.degrees(damaged_net.shear[i, j]))
    np.testing.assert_allclose(data["fibre_u"], damaged_net.fibre_u[i, j])
    np.testing.assert_allclose(data["fibre_v"], damaged_net.fibre_v[i, j])
    assert data["fibre_u"].shape == (len(quads), 3)
    np.testing.assert_allclose(data["energy_J_per_m2"], energy.energy_density[i, j])
    np.testing.assert_allclose(data["thickness_ratio"], 1 / np.cos(damaged_net.shear[i, j]))
    assert np.array_equal(data["past_locking"], energy.past_locking[i, j].astype(int))
    assert np.array_equal(data["past_failure"], energy.past_failure[i, j].astype(int))
    assert data["past_locking"].any() and not data["past_locking"].all()
    assert np.all(data["status"] == CellStatus.VALID)
    assert data["in_part"].sum() == len(quads) - 1

    # Each quad's corners are the net's nodes (i, j), (i+1, j), (i+1, j+1), (i, j+1).
    pi, pj = mesh.point_data["i"], mesh.point_data["j"]
    assert np.array_equal(pi[quads[:, 2]], i + 1) and np.array_equal(pj[quads[:, 2]], j + 1)
    np.testing.assert_allclose(mesh.points, 1e3 * damaged_net.nodes[pi, pj])  # mm
    np.testing.assert_allclose(mesh.point_data["residual_mm"], 1e3 * 1e-12)
    assert np.all(damaged_net.status[pi, pj] == NodeStatus.PLACED)


def test_drape_vtu_without_energy_still_has_the_thickness_ratio(tmp_path, make_net):
    net = make_net(4, 5, generator_angle_deg=60.0)
    path = tmp_path / "flat.vtu"
    write_drape_vtu(net, None, path)

    mesh = meshio.read(path)
    assert "energy_J_per_m2" not in mesh.cell_data_dict
    np.testing.assert_allclose(mesh.cell_data_dict["shear_deg"]["quad"], -30.0)
    np.testing.assert_allclose(
        mesh.cell_data_dict["thickness_ratio"]["quad"], 1 / np.cos(np.pi / 6)
    )


def test_drape_vtu_of_a_net_without_valid_cells_keeps_its_nodes(tmp_path, make_net):
    net = make_net(3, 3, unplaced=[(1, 1)])  # the centre node touches all four cells
    path = tmp_path / "empty.vtu"
    write_drape_vtu(net, None, path)

    mesh = meshio.read(path)
    assert len(mesh.points) == 8
    assert list(mesh.cells_dict) == ["vertex"]
    assert not mesh.cell_data


def wedge_volumes(points, wedges):
    """Volume of each wedge (triangular prism, possibly skewed): three tetrahedra."""
    p = points[wedges]
    total = np.zeros(len(wedges))
    for a, b, c, d in ((0, 1, 2, 3), (1, 2, 3, 4), (2, 3, 4, 5)):
        edges = np.cross(p[:, c] - p[:, a], p[:, d] - p[:, a])
        total += np.abs(np.einsum("ij,ij->i", p[:, b] - p[:, a], edges))
    return total / 6.0


def test_unit_cell_vtu_tow_volumes_hold_each_straight_tows_section_times_length(tmp_path):
    """The solids block: a straight tow's wedges add up to (π/4)·w·h·L exactly, crimped
    tows to within the chord error, and every wedge carries its tow's data."""
    import math

    from preform.api import load_library

    lib = load_library(env=False)
    for name, gamma in (("E-BX-318", 0.0), ("ncf-0-90-tricot", 0.5), ("plain-weave-600", 0.8)):
        cell = lib.fabric(name).sheared_cell(gamma).unit_cell()
        path = tmp_path / f"{name}.vtu"
        write_unit_cell_vtu(cell, path)
        mesh = meshio.read(path)
        wedges = mesh.cells_dict["wedge"]
        tow = mesh.cell_data_dict["tow"]["wedge"]
        assert np.all(mesh.cell_data_dict["solid"]["wedge"] == 1)
        assert np.all(mesh.cell_data_dict["solid"]["line"] == 0)
        volumes = wedge_volumes(mesh.points * 1e-3, wedges)
        for k, t in enumerate(cell.tows):
            if t.kind == "stitch":
                continue
            expected = math.pi / 4 * t.width * t.height * t.length()
            got = volumes[tow == k].sum()
            # straight pieces are exact; a crimped tow's polygon corners cost a little
            tolerance = 1e-9 if len(t.points) == 2 else 2e-2
            np.testing.assert_allclose(got, expected, rtol=tolerance)
            np.testing.assert_allclose(
                mesh.cell_data_dict["width_mm"]["wedge"][tow == k], 1e3 * t.width
            )
