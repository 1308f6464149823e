"""A run folder written the way the pipeline writes one (summary.json per case, then the
manifest and tables by ``RunDirectory``), with cases of every kind, for the page's tests."""

from __future__ import annotations

import importlib.util
import math
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from preform.export.csv_columns import rows_to_columns, write_csv_columns
from preform.pipeline.rundir import RunDirectory, write_json
from preform.pipeline.runner import folder_name

RADIUS_MM = 100.0


def hemisphere_cells(n: int, spacing_mm: float = 5.0) -> list[dict[str, Any]]:
    """cells.csv rows of an n x n grid of cell centres on a hemisphere of radius 100 mm, with
    shear = x/10 degrees, cells beyond the rim INCOMPLETE, and the grid's corner cell wrinkling."""
    rows = []
    for i in range(n):
        for j in range(n):
            x = (i - n / 2) * spacing_mm
            y = (j - n / 2) * spacing_mm
            r2 = RADIUS_MM**2 - x * x - y * y
            on = r2 > 0
            rows.append(
                {
                    "i": i,
                    "j": j,
                    "status": "VALID" if on else "INCOMPLETE",
                    "in_part": on,
                    "x_mm": x if on else None,
                    "y_mm": y if on else None,
                    "z_mm": math.sqrt(r2) if on else None,
                    "shear_deg": x / 10 if on else None,
                    "wrinkling": on and x > 60,
                    "past_jamming": on and x > 60,
                    "past_failure": False,
                }
            )
    return rows


def energy_curve(optimum_deg: float, scale_J: float) -> list[list[float]]:
    return [[a, scale_J * (1 + ((a - optimum_deg) / 30) ** 2)] for a in range(30, 151, 5)]


def make_run(root: Path, *, n_grid: int = 40) -> Path:
    """Four cases: ok with a net, partial with reasons, failed with an error (scene 'dome'),
    and ok with shear curves (scene 'shear'). Returns ``root``."""
    cases: list[dict[str, Any]] = [
        {
            "scene": "dome",
            "material": "plain-weave-600",
            "status": "ok",
            "energy_vs_angle": energy_curve(90, 1.2),
            "optimum_generator_angle_deg": 90.0,
            "optimum_energy_J": 1.2,
            "max_abs_shear_deg": 53.09673863877123,
            "covered_fraction": 1.0,
            "cells_valid": 1234,
            "warnings": [
                "1208 cells (7.5 % of the part's draped area) are sheared past the locking "
                "angle 39.2°: its tows touch and compact there",
            ],
            "files": ["cells.csv"],
        },
        {
            "scene": "dome",
            "material": "satin-<b>8hs</b>",
            "status": "partial",
            "energy_vs_angle": energy_curve(80, 2.0),
            "optimum_generator_angle_deg": 80.25,
            "optimum_energy_J": 2.0000001,
            "covered_fraction": 0.542,
            "reasons": ["the net covers 54.2 % of the ply's fabric area that lies over the tool"],
            "warnings": [
                "412 cells (3.1 % of the part's draped area) are sheared past the locking "
                "angle 22.2°: its tows touch and compact there",
            ],
            "files": [],
        },
        {
            "scene": "dome",
            "material": "E-BX-318",
            "status": "failed",
            "error": "CaseFailure: the drape placed no cell",
            "files": [],
        },
        {
            "scene": "shear",
            "material": "plain-weave-600",
            "status": "ok",
            "locking_angle_deg": 39.194967425982945,
            "files": ["shear_curve.json"],
        },
    ]
    for case in cases:
        folder = root / case["scene"] / folder_name(case["material"])
        folder.mkdir(parents=True)
        record = {
            "case_id": f"{case['scene']}/{case['material']}",
            "error": None,
            "reasons": [],
            "warnings": [],
            "input_hash": "0" * 64,
            "finished": "2026-12-03T12:00:00+00:00",
            "wall_time_s": 1.5,
            "step_times_s": {"drape": 0.25},
            **case,
        }
        write_json(folder / "summary.json", record)
        if "cells.csv" in case["files"]:
            write_csv_columns(rows_to_columns(hemisphere_cells(n_grid)), folder / "cells.csv")
        if "shear_curve.json" in case["files"]:
            curve = {
                sense: [
                    {
                        "angle_deg": sign * a,
                        "force_N_per_mm": 0.01 * a,
                        "energy_J_per_m2": 0.5 * a * a,
                        "torque_N_per_m": 0.1 * a,
                    }
                    for a in range(0, 61, 5)
                ]
                for sense, sign in (("positive", 1), ("negative", -1))
            }
            write_json(folder / "shear_curve.json", {"material": case["material"], **curve})
    with RunDirectory(root) as rundir:  # reads every summary.json, as a run's end does
        run = {
            "id": "test-run",
            "preform_version": "0.1.0",
            "started": "2026-12-03T11:59:00+00:00",
            "finished": "2026-12-03T12:01:00+00:00",
            "status": "finished",
            "settings": {"engine": "serial", "workers": None},
            "inputs": {
                "libraries": [{"path": "fabrics.yaml", "sha256": "ab" * 32}],
                "scenes": [{"path": "dome.yaml", "sha256": "cd" * 32}],
                "bundled_library": True,
            },
            "plugins": [{"name": "core", "version": "0.1.0", "error": None}],
            "cases": sorted(rundir.records),
            "counts": {"ok": 2, "partial": 1, "failed": 1},
        }
        rundir.write_manifest(run)
        rundir.write_tables()
    return root


@pytest.fixture
def made_run(tmp_path: Path) -> Path:
    return make_run(tmp_path / "run")


@pytest.fixture
def run_maker() -> Callable[..., Path]:
    return make_run


@pytest.fixture
def cells_maker() -> Callable[..., list[dict[str, Any]]]:
    return hemisphere_cells


def _sibling(name: str) -> Any:
    """A module of this folder, by path (the tests run with --import-mode=importlib)."""
    key = f"preform_tests_report_{name}"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, Path(__file__).with_name(f"{name}.py"))
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[key] = module
        spec.loader.exec_module(module)
    return sys.modules[key]


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """A headless Chromium with one page (skipped without Chromium, failed under CI)."""
    driver = _sibling("browser")
    with driver.Browser(driver.require_chromium()) as b:
        yield b
