"""The shear/fit command logic, without the materials library."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from preform.shear.commands import fit_command, parse_angles, plot_shear_curves, shear_curves
from preform.shear.law import ShearLaw
from preform.shear.laws import PolynomialParams, build_polynomial
from preform.shear.testdata import picture_frame_displacement


def asymmetric_law() -> ShearLaw:
    return build_polynomial(
        PolynomialParams(
            law="polynomial",
            force_coefficients_N_per_mm=[0.0, 2e-3],
            force_coefficients_negative_N_per_mm=[0.0, 1e-3],
            max_angle_deg=60.0,
            locking_angle_deg=50.0,
        )
    )


def test_parse_angles() -> None:
    np.testing.assert_allclose(parse_angles("0:60:5"), np.arange(0, 61, 5))
    np.testing.assert_allclose(parse_angles("10:12:0.5"), [10, 10.5, 11, 11.5, 12])
    for bad in ("0:60", "10:0:5", "0:90:5", "0:60:0", "a:b:c"):
        with pytest.raises(ValueError):
            parse_angles(bad)


def test_shear_curves_structure_and_values() -> None:
    curves = shear_curves(asymmetric_law(), [0, 30, 60], "demo", "polynomial")
    assert curves["material"] == "demo" and curves["law"] == "polynomial"
    assert curves["locking_angle_deg"] == pytest.approx(50.0)
    assert curves["failure_angle_deg"] is None
    pos, neg = curves["positive"], curves["negative"]
    assert set(pos[0]) == {"angle_deg", "torque_N_per_m", "force_N_per_mm", "energy_J_per_m2"}
    assert pos[1]["force_N_per_mm"] == pytest.approx(0.06)
    assert neg[1]["angle_deg"] == -30.0 and neg[1]["force_N_per_mm"] == pytest.approx(-0.03)
    assert pos[1]["torque_N_per_m"] == pytest.approx(60 * math.cos(math.radians(30)))
    assert pos[2]["energy_J_per_m2"] > neg[2]["energy_J_per_m2"] > 0.0
    json.dumps(curves)  # plain JSON types only


def test_png_is_written(tmp_path: Path) -> None:
    out = tmp_path / "curves.png"
    plot_shear_curves(shear_curves(asymmetric_law(), np.arange(0, 61, 5)), out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_fit_command_writes_a_usable_yaml_block(tmp_path: Path) -> None:
    deg = np.linspace(1, 60, 30)
    g = np.radians(deg)
    side = 150.0
    psi = (math.pi / 2 - g) / 2
    rows = ["displacement_mm,force_N,sense"]
    for sense, scale in (("parallel", 2e-3), ("perpendicular", 1e-3)):
        force = 2 * np.cos(psi) * scale * deg * side
        delta = picture_frame_displacement(g, side)
        rows += [f"{d},{f},{sense}" for d, f in zip(delta, force, strict=True)]
    data = tmp_path / "frame.csv"
    data.write_text("\n".join(rows) + "\n")
    out = tmp_path / "law.yaml"
    result = CliRunner().invoke(
        fit_command,
        [str(data), "--test", "picture-frame", "--side-mm", "150", "--sense", "both",
         "--degree", "1", "--out", str(out)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "R² = 1.0000" in result.output
    block = yaml.safe_load(out.read_text())["shear_law"]
    params = PolynomialParams.model_validate(block)
    assert params.force_coefficients_N_per_mm == pytest.approx([0.0, 2e-3])
    assert params.force_coefficients_negative_N_per_mm == pytest.approx([0.0, 1e-3])


def test_fit_command_reports_missing_options(tmp_path: Path) -> None:
    data = tmp_path / "frame.csv"
    data.write_text("displacement_mm,force_N\n1,2\n2,3\n")
    result = CliRunner().invoke(fit_command, [str(data), "--test", "picture-frame"])
    assert result.exit_code != 0
    assert "--side-mm" in result.output
