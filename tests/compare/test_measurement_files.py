"""Reading measurements (CSV, point clouds), their located errors, the unit slip, points off
the tool, and the command and API around them."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import meshio
import numpy as np
import pytest
from click.testing import CliRunner

import preform
from preform.cli import cli
from preform.compare import (
    MeasurementError,
    UnitSlipError,
    compare,
    measurement,
    read_measurement,
)
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.plugins.surfaces.basic import Hemisphere

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "docs" / "examples" / "measured_hemisphere.csv"
TOOL = Hemisphere(0.1, run_off_m=0.025)
NET = drape(TOOL, node_spacing_m=0.005, ply=PlyOutline.rectangle((0.3, 0.3)),
            start_xy_m=(0.0, 0.0), orientation_rad=0.0, generator_angle_rad=np.radians(80))  # fmt: skip


def on_sphere(xy_mm: np.ndarray) -> np.ndarray:
    xy = np.asarray(xy_mm, dtype=float)
    return np.column_stack([xy, np.sqrt(100.0**2 - np.sum(xy**2, axis=1))])


def test_the_example_reads_with_its_header():
    m = read_measurement(EXAMPLE)
    assert m.count == 200
    assert m.reference_direction == (1.0, 0.0, 0.0)
    assert set(m.region) == {"crown", "flank"}
    assert np.all(m.uncertainty_deg == 1.5)
    assert m.origin[0] == "measured_hemisphere.csv:10"
    assert any("SYNTHETIC" in note for note in m.notes)
    # mm in the file, metres inside
    assert np.max(np.linalg.norm(m.points, axis=1)) == pytest.approx(0.1, abs=0.003)


def test_every_bad_row_is_located_at_once(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text(
        "# reference_direction: 1 0\n"
        "x_mm,y_mm,z_mm,u_x,u_y,u_z,angle_v_deg,uncertainty_deg,colour\n"
        "0,0,100,1,0,0,90,1,red\n"
        "0,0,abc,1,0,0,90,1,red\n"
        "0,0,100,1,0,,90,1,red\n"
        "0,0,100,0,0,0,,1,red\n"
        "0,0,100,1,0,0,90,-2,red\n"
        "0,0,100,,,,,1,red\n"
        "0,0,100\n"
    )
    with pytest.raises(MeasurementError) as caught:
        read_measurement(path)
    text = "\n".join(caught.value.errors)
    for expected in (
        "bad.csv:1: reference_direction",
        "bad.csv:2: unknown column(s) colour",
        "bad.csv:4: z_mm: not a number: 'abc'",
        "bad.csv:5: u_x, u_y, u_z: give all three or none",
        "bad.csv:6: u_x, u_y, u_z: a zero vector",
        "bad.csv:7: uncertainty_deg: must be positive",
        "bad.csv:8: nothing measured",
        "bad.csv:9: 3 value(s) for 9 column(s)",
    ):
        assert expected in text, (expected, text)


def test_a_file_without_point_columns_says_what_it_needs(tmp_path):
    path = tmp_path / "frame.csv"
    path.write_text("displacement_mm,force_N\n0,0\n")
    with pytest.raises(MeasurementError, match="x_mm, y_mm, z_mm"):
        read_measurement(path)


def slipped(tmp_path: Path) -> Path:
    """The example with its points written in metres under mm column names."""
    m = read_measurement(EXAMPLE)
    lines = ["x_mm,y_mm,z_mm,angle_u_deg,angle_v_deg"]
    for p, a, b in zip(m.points, m.angle_u_deg, m.angle_v_deg, strict=True):
        lines.append(f"{p[0]:.5f},{p[1]:.5f},{p[2]:.5f},{a},{b}")
    path = tmp_path / "in_metres.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_unit_slip_is_caught_and_said(tmp_path):
    m = read_measurement(slipped(tmp_path))
    with pytest.raises(UnitSlipError) as caught:
        compare(NET, m, surface=TOOL)
    message = str(caught.value)
    assert "200 of 200 points are off the tool" in message
    assert "metres" in message and "x_m, y_m, z_m" in message
    # and the same points named as metres compare fine
    named = tmp_path / "named.csv"
    named.write_text(slipped(tmp_path).read_text().replace("x_mm,y_mm,z_mm", "x_m,y_m,z_m"))
    again = compare(NET, read_measurement(named), surface=TOOL)
    assert not again.off_tool.any() and again.compared.sum() > 190  # a few past the ply's edge


def test_points_off_the_tool_are_reported_not_compared():
    xy = np.array([[0.0, 0.0], [30.0, 10.0], [-20.0, 40.0], [10.0, -50.0]])
    points = on_sphere(xy)
    points[1, 2] += 40.0  # 40 mm above the tool
    points[3] = [160.0, 0.0, 5.0]  # beside it
    m = measurement(points, angle_u_deg=[0, 0, 0, 0], angle_v_deg=[80, 80, 80, 80])
    found = compare(NET, m, surface=TOOL)
    assert found.off_tool.tolist() == [False, True, False, True]
    assert np.isnan(found.error_u_deg[[1, 3]]).all()
    assert np.isfinite(found.error_u_deg[[0, 2]]).all()
    summary = found.summary()
    assert summary["points_off_tool"] == 2 and summary["points_compared"] == 2
    assert summary["off_tool_points"] == ["point 2", "point 4"]


def test_points_below_the_rim_are_outside_the_part():
    """The hemisphere's part ends at its rim (z = 0); the net runs 25 mm below it."""
    angle = np.radians(np.array([10.0, -10.0]))
    points = 100.0 * np.column_stack([np.cos(angle), np.zeros(2), np.sin(angle)])
    wide = drape(TOOL, node_spacing_m=0.005, ply=PlyOutline.rectangle((0.4, 0.4)),
                 start_xy_m=(0.0, 0.0), orientation_rad=0.0, generator_angle_rad=np.radians(80),
                 trim=TOOL.part())  # fmt: skip
    found = compare(wide, measurement(points, shear_deg=[0.0, 0.0]), surface=TOOL)
    assert found.compared.all()
    assert found.outside_part.tolist() == [False, True]
    assert "outside_part" in found.summary()["by_region"]


@pytest.mark.parametrize("suffix", [".vtu", ".ply"])
def test_a_point_cloud_reads_as_the_csv(tmp_path, suffix):
    m = read_measurement(EXAMPLE)
    found = compare(NET, m, surface=TOOL)
    # a scanner's file: points with fibre vectors (here the measured angles made vectors)
    n = m.points / np.linalg.norm(m.points, axis=1, keepdims=True)
    ref = np.array([1.0, 0.0, 0.0]) - n[:, :1] * n
    ref /= np.linalg.norm(ref, axis=1, keepdims=True)
    side = np.cross(n, ref)

    def vec(deg: np.ndarray) -> np.ndarray:
        a = np.radians(deg)[:, None]
        return np.cos(a) * ref + np.sin(a) * side

    u, v = vec(m.angle_u_deg), vec(m.angle_v_deg)
    data = ({"fibre_u": u, "fibre_v": v} if suffix == ".vtu" else
            {"u_x": u[:, 0], "u_y": u[:, 1], "u_z": u[:, 2],
             "v_x": v[:, 0], "v_y": v[:, 1], "v_z": v[:, 2]})  # fmt: skip
    path = tmp_path / f"cloud{suffix}"
    meshio.write(str(path), meshio.Mesh(m.points, [("vertex", np.arange(m.count)[:, None])],
                                        point_data=data))  # fmt: skip
    cloud = read_measurement(path, unit="m")
    again = compare(NET, cloud, surface=TOOL)
    assert np.allclose(again.error_u_deg, found.error_u_deg, atol=1e-6, equal_nan=True)
    assert np.allclose(again.error_v_deg, found.error_v_deg, atol=1e-6, equal_nan=True)


def test_a_point_cloud_without_fibres_says_so(tmp_path):
    path = tmp_path / "bare.vtu"
    meshio.write(str(path), meshio.Mesh(np.zeros((2, 3)), [("vertex", np.array([[0], [1]]))]))
    with pytest.raises(MeasurementError, match="no fibre directions or angles"):
        read_measurement(path)


def test_the_api_compares_and_writes(tmp_path):
    c = preform.compare_drape("plain-weave-600", EXAMPLE, node_spacing_mm=5)
    assert c.status == "ok"
    s = c.summary
    assert s["points_compared"] == 200 and s["angle_rms_deg"] > 1.5
    assert {"region crown", "region flank"} <= set(s["by_region"])
    table = c.to_pandas()
    assert len(table) == 200 and {"error_u_deg", "wrinkle_zone"} <= set(table.columns)
    vtu = meshio.read(c.to_vtu(tmp_path / "points.vtu"))
    assert np.allclose(vtu.point_data["error_u_deg"], c.comparison.error_u_deg)
    c.plot(tmp_path / "map.png")
    assert (tmp_path / "map.png").read_bytes()[:4] == b"\x89PNG"


def test_the_command_explains_the_example(tmp_path):
    shutil.copy(EXAMPLE, tmp_path / EXAMPLE.name)
    result = CliRunner().invoke(cli, [
        "compare", "plain-weave-600", str(tmp_path / EXAMPLE.name), "--explain",
        "--out", str(tmp_path / "cmp"), "--json",
    ])  # fmt: skip
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    best = report["explain"]["best"]
    sigma = report["explain"]["sigma"]
    # the example was made at (4, -3) mm, 2°, 86° with 1.5° noise: within 3 σ
    for name, truth in (("start_x_mm", 4.0), ("start_y_mm", -3.0), ("orientation_deg", 2.0),
                        ("generator_angle_deg", 86.0)):  # fmt: skip
        assert abs(best[name] - truth) < 3 * sigma[name], name
    assert report["explain"]["explained"]
    assert report["explain"]["after"]["angle_rms_deg"] < report["angle_rms_deg"]
    for key in ("table", "vtu", "figure", "explained_table", "explained_vtu", "summary"):
        assert Path(report["files"][key]).is_file()


def test_the_command_says_a_unit_slip(tmp_path):
    result = CliRunner().invoke(cli, ["compare", "plain-weave-600", str(slipped(tmp_path))])
    assert result.exit_code == 2
    assert "look like they are in metres" in result.stderr
    assert "Traceback" not in result.output
