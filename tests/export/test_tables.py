from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from preform.drape.engine.result import CellStatus, NodeStatus
from preform.export.tables import CELL_COLUMNS, cells_table, write_json, write_table


def test_cells_table_has_one_row_per_cell_with_units_in_mm_and_degrees(damaged_net, make_energy):
    energy = make_energy(damaged_net)
    table = cells_table(damaged_net, energy)

    assert list(table.columns) == list(CELL_COLUMNS)
    assert len(table) == 9 * 11
    by_cell = table.set_index(["i", "j"])
    assert by_cell.loc[(3, 3), "status"] == "FOLDED"
    assert by_cell.loc[(0, 0), "status"] == "INCOMPLETE"
    assert set(table["status"]) == {"VALID", "INCOMPLETE", "FOLDED"}
    assert not by_cell.loc[(4, 7), "in_part"] and by_cell.loc[(4, 7), "status"] == "VALID"

    invalid = table[table["status"] != "VALID"]
    numeric = [
        "x_mm",
        "y_mm",
        "z_mm",
        "shear_deg",
        "area_mm2",
        "thickness_ratio",
        "energy_J_per_m2",
    ]
    assert invalid[numeric].isna().all().all()
    assert invalid["past_locking"].isna().all()

    valid = table[table["status"] == "VALID"]
    assert valid[numeric].notna().all().all()
    row = by_cell.loc[(5, 6)]
    np.testing.assert_allclose(
        row[["x_mm", "y_mm", "z_mm"]].to_numpy(float), 1e3 * damaged_net.centroid[5, 6]
    )
    assert row["shear_deg"] == pytest.approx(np.degrees(damaged_net.shear[5, 6]))
    assert row["area_mm2"] == pytest.approx(1e6 * damaged_net.area[5, 6])
    assert row["energy_J_per_m2"] == pytest.approx(energy.energy_density[5, 6])
    # Signed: the domed net shears both ways.
    assert valid["shear_deg"].min() < 0 < valid["shear_deg"].max()
    assert valid["past_locking"].astype(bool).sum() == np.count_nonzero(energy.past_locking)


def test_cells_table_without_energy_leaves_energy_columns_empty(make_net):
    net = make_net(3, 4, spacing=0.01, generator_angle_deg=60.0)
    table = cells_table(net)
    assert table["energy_J_per_m2"].isna().all()
    assert table["past_failure"].isna().all()
    np.testing.assert_allclose(table["shear_deg"], -30.0)
    np.testing.assert_allclose(table["area_mm2"], 100.0 * np.cos(np.radians(30.0)))
    np.testing.assert_allclose(table["thickness_ratio"], 1 / np.cos(np.radians(30.0)))


def test_csv_and_parquet_read_back(tmp_path, damaged_net, make_energy):
    table = cells_table(damaged_net, make_energy(damaged_net))
    write_table(table, tmp_path / "cells.csv")
    write_table(table, tmp_path / "cells.parquet")

    from_csv = pd.read_csv(tmp_path / "cells.csv")
    assert list(from_csv.columns) == list(table.columns)
    np.testing.assert_allclose(from_csv["shear_deg"], table["shear_deg"], equal_nan=True)
    assert from_csv["status"].tolist() == table["status"].tolist()

    from_parquet = pd.read_parquet(tmp_path / "cells.parquet")
    pd.testing.assert_frame_equal(from_parquet, table)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cells.csv", "cells.parquet"]


def test_write_json_is_strict_sorted_and_converts_numpy(tmp_path):
    path = tmp_path / "summary.json"
    summary = {
        "total_energy_J": np.float64(0.125),
        "nodes_placed": np.int64(118),
        "complete": np.bool_(False),
        "worst_shear_deg": float("nan"),
        "angles_deg": np.array([60.0, np.inf, 75.0]),
        "status": CellStatus.FOLDED,
        "start_status": NodeStatus.PLACED,
        "output": Path("run/x.vtu"),
        "a_first": {2: "two", "b": (1, 2)},
    }
    write_json(summary, path)

    text = path.read_text()
    data = json.loads(text)  # strict JSON: would fail on a bare NaN
    assert "NaN" not in text and "Infinity" not in text
    assert data["worst_shear_deg"] is None
    assert data["angles_deg"] == [60.0, None, 75.0]
    assert data["nodes_placed"] == 118 and data["complete"] is False
    assert data["status"] == "FOLDED" and data["output"] == "run/x.vtu"
    assert data["a_first"] == {"2": "two", "b": [1, 2]}
    assert list(data) == sorted(data)
    assert text.splitlines()[1].startswith('  "a_first"')  # indent 2, sorted keys
    assert math.isclose(data["total_energy_J"], 0.125)


def test_write_json_rejects_unknown_objects(tmp_path):
    with pytest.raises(TypeError, match="object"):
        write_json({"x": object()}, tmp_path / "bad.json")
    assert not (tmp_path / "bad.json").exists()
