"""`preform bench tradeoff --quick`: it writes the table (and, as it says, no figure: its coarse
reference cannot show the trade), and the numbers in it behave (a behaviour test, not a timed
one)."""

from __future__ import annotations

import csv
import math
from pathlib import Path

from click.testing import CliRunner

from preform.bench.tradeoff import bench, pareto_front


def test_quick_tradeoff_writes_a_sensible_table_and_says_why_no_figure(tmp_path: Path) -> None:
    out = tmp_path / "bench"
    result = CliRunner().invoke(bench, ["tradeoff", "--quick", "--out", str(out)])
    assert result.exit_code == 0, result.output
    table, figure = out / "tradeoff.csv", out / "tradeoff.png"
    assert not figure.exists()
    assert "no tradeoff.png with --quick" in result.stdout
    assert "Run without --quick for the figure" in result.stdout
    assert f"wrote {table}\n" in result.stdout
    with table.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    labels = [row["label"] for row in rows]
    assert labels[0] == "reference" and "standard" in labels and "draft" in labels

    errors = ("energy_rel_error", "angle_error_deg", "max_shear_error_deg")
    for row in rows:
        for column in ("wall_s", "peak_mb", *errors, "chebyshev_max_shear_error_deg"):
            assert math.isfinite(float(row[column])), (row["label"], column)
        assert float(row["wall_s"]) > 0 and float(row["peak_mb"]) > 0
    reference = rows[0]
    assert all(float(reference[column]) == 0.0 for column in errors)

    # Coarser nets err more in energy, on the measured points (standard varies none but d).
    by_spacing = sorted(
        (
            (float(row["node_spacing_mm"]), float(row["energy_rel_error"]))
            for row in rows
            if row["knob"] == "node_spacing_mm" or row["label"] == "standard"
        ),
    )
    assert len(by_spacing) >= 3
    energy_errors = [error for _, error in by_spacing]
    assert energy_errors == sorted(energy_errors)
    assert energy_errors[-1] > energy_errors[0]


def test_pareto_front_keeps_only_undominated_points() -> None:
    times = [1.0, 2.0, 3.0, 2.5, 0.5]
    errors = [0.1, 0.05, 0.0, 0.2, math.nan]
    assert pareto_front(times, errors) == [True, True, True, False, False]


def test_a_cad_tool_gets_a_tessellation_row_and_a_finer_reference() -> None:
    from preform.bench.tradeoff import (
        REFERENCE,
        TESSELLATION_TOLERANCES_MM,
        tradeoff_settings,
    )
    from preform.pipeline.scene import load_scene, resolve_scene_path
    from preform.plugin_manager import default_host

    registry = default_host().registry
    cad, _ = load_scene(resolve_scene_path("hat-stiffener-min-energy"), registry)
    settings = tradeoff_settings(cad, 0.45)
    tess = {s.label: s for s in settings if s.knob == "tessellation_tolerance_mm"}
    own = cad.tool.tessellation_tolerance_in_force_mm()  # type: ignore[union-attr]
    assert set(tess) == {f"tess={t:g}mm" for t in TESSELLATION_TOLERANCES_MM if t != own}
    for s in tess.values():
        assert s.scene.tool.tessellation_tolerance_mm == float(s.value)  # type: ignore[union-attr]
    # Everything else keeps the scene's tessellation; the reference is finer than any row.
    reference = settings[0].scene.tool
    assert reference.tessellation_tolerance_mm == REFERENCE["tessellation_tolerance_mm"]  # type: ignore[union-attr]
    assert REFERENCE["tessellation_tolerance_mm"] < min(TESSELLATION_TOLERANCES_MM)
    standard = next(s for s in settings if s.label == "standard").scene.tool
    assert standard.tessellation_tolerance_in_force_mm() == own  # type: ignore[union-attr]
    # An analytic tool has no tessellation: no such row.
    sphere, _ = load_scene(resolve_scene_path("hemisphere-min-energy"), registry)
    assert not any(s.knob == "tessellation_tolerance_mm" for s in tradeoff_settings(sphere, 0.1))


def test_quick_json_lists_the_table_only_and_names_an_earlier_figure(tmp_path: Path) -> None:
    import json

    out = tmp_path / "bench"
    out.mkdir()
    (out / "tradeoff.png").write_bytes(b"an earlier full run's figure")
    result = CliRunner().invoke(bench, ["tradeoff", "--quick", "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["files"] == [str(out / "tradeoff.csv")]
    assert report["no_figure"].startswith("no tradeoff.png with --quick")
    assert report["no_figure"].endswith(f"{out / 'tradeoff.png'} is an earlier run's")
    assert (out / "tradeoff.png").read_bytes() == b"an earlier full run's figure"  # left alone
