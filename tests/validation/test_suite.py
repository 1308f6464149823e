"""The validation suite (``preform validate``): the datasets say where they come from, the
runner writes what it promises, and the calibrated law against the measured benchmark curves.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from preform.shear.commands import read_test_csv
from preform.validation_suite.runner import (
    dataset_dirs,
    load_dataset,
    read_normalised_csv,
    run_validation,
)

REQUIRED = ("title", "citation", "figure", "test", "points", "digitised_by",
            "uncertainty", "licence", "fabric", "closest_bundled")  # fmt: skip


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> dict:
    return run_validation(tmp_path_factory.mktemp("validation"))


def rows(report: dict, model: str) -> dict[str, dict]:
    return {r["dataset"]: r for r in report["rows"] if r["model"] == model}


def test_every_dataset_says_where_it_comes_from() -> None:
    folders = dataset_dirs()
    assert len(folders) >= 2
    for folder in folders:
        meta = load_dataset(folder)
        missing = [key for key in REQUIRED if not meta.get(key)]
        assert not missing, (folder, missing)
        assert "doi:" in meta["citation"]
        if meta.get("normalised"):  # the authors' normalised curve: γ [deg], F_s/L [N/mm]
            angle, force = read_normalised_csv(meta["points_path"])
            assert len(angle) == meta["point_count"]
            assert (np.diff(angle) > 0).all() and (force >= 0).all()
        else:  # a raw test: its specimen, to normalise it
            assert meta.get("specimen"), folder
            assert len(read_test_csv(meta["points_path"])) == meta["point_count"]


def test_the_runner_writes_a_figure_per_dataset_and_the_table(report: dict) -> None:
    files = report["files"]
    assert len(files["figures"]) == len(dataset_dirs())
    for figure in files["figures"]:
        assert Path(figure).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(files["table"], newline="") as handle:
        table = list(csv.DictReader(handle))
    assert len(table) == 3 * len(dataset_dirs())
    assert "| calibrated |" in Path(files["markdown"]).read_text()


def test_calibration_brings_the_law_closer_to_the_measured_curves(report: dict) -> None:
    """Never further (a least-squares fit from bounds holding the uncalibrated value), and on
    the bias-extension curves, where the uncalibrated pre-tension is 2.5× too stiff, five
    times closer."""
    before, after = rows(report, "benchmark"), rows(report, "calibrated")
    for dataset, row in after.items():
        assert row["rms_N_per_mm"] <= before[dataset]["rms_N_per_mm"] * (1 + 1e-9), dataset
        if "-bias-" in dataset:
            assert row["relative_rms"] < 0.2 * before[dataset]["relative_rms"], dataset


def test_one_fabric_gives_one_set_of_constants_whatever_the_specimen_size(report: dict) -> None:
    """Two specimen sizes of the same fabric (the normalisation removes the size): each fitted
    constant must agree within the two fits' combined uncertainty (3σ)."""
    after = rows(report, "calibrated")
    fits = [
        {c["path"]: (c["value"], c["sigma"]) for c in row["fitted"]}
        for dataset, row in after.items()
        if "-bias-" in dataset
    ]
    assert len(fits) == 2 and fits[0].keys() == fits[1].keys()
    assert set(fits[0]) == {"shear_law.pretension_N", "shear_law.friction_mobilisation_deg"}
    for path in fits[0]:
        (a, sa), (b, sb) = fits[0][path], fits[1][path]
        assert sa is not None and sb is not None, path
        assert abs(a - b) <= 3 * (sa**2 + sb**2) ** 0.5, path


def test_the_calibrated_law_reproduces_the_benchmark_within_15_percent(report: dict) -> None:
    """Issue 24's criterion: pre-tension and friction mobilisation fitted up to the locking
    angle, every measured curve (two bias-extension, four picture-frame laboratories) is met
    within 15 % rms. (Coulomb's crossover, γ_m = 0, is 27-51 %: the next test.)"""
    for dataset, row in rows(report, "calibrated").items():
        assert row["relative_rms"] <= 0.15, (dataset, row["relative_rms"])


def test_a_coulomb_crossover_cannot_meet_the_measured_rise() -> None:
    """The reason for the mobilisation: the same fit with γ_m held at 0 (Coulomb's sudden
    slip, the paper's law) leaves at least one picture-frame curve above 25 % rms, since it
    starts every curve at its full friction force while the measured ones rise from zero."""
    import math

    from preform.library import load_library
    from preform.shear.calibrate import calibrate_law, resolve_constants
    from preform.validation_suite.runner import suite_dir

    lib = load_library([suite_dir() / "fabrics.yaml"])
    fabric = lib.fabric("twintex-plain-cao2008")
    assert fabric.shear_law.friction_mobilisation_deg == 0.0
    worst = 0.0
    for folder in dataset_dirs():
        meta = load_dataset(folder)
        if not meta.get("normalised"):
            continue
        angle, force = read_normalised_csv(meta["points_path"])
        fit = calibrate_law(
            fabric,
            lib.registry,
            angle,
            force,
            resolve_constants(fabric, ["shear_law.pretension_N=1:10000"]),
            max_angle_deg=math.degrees(math.acos(4.22 / 5.18)),
            test=meta["test"],
            weights="absolute",
        )
        worst = max(worst, fit.fit.relative_rms)
    assert worst > 0.25


def test_a_constant_at_its_bound_is_said(report: dict) -> None:
    """A fit that stops at a bound says so in the table's words, and only then."""
    for row in rows(report, "calibrated").values():
        at_bound = [c for c in row["fitted"] if c["at_bound"]]
        assert row["constants"].count("(at its bound)") == len(at_bound), row["constants"]


def test_measured_angles_say_where_they_come_from_and_meet_the_model(report: dict) -> None:
    """Each measured angle cites its source and states its uncertainty. The model's locking
    angle is recomputed here from its closed form, acos(w/s) of the benchmark fabric (yarn
    width 4.22 mm, 1.93 ends/cm rounded to 5.18 mm spacing, Cao et al. 2008 Table 1), and the
    runner reports which of the
    model's angles fall inside the measurement's interval: the plain weave's tows jam (41.5°
    with the default compaction constants, nothing fitted) within the reported locking onset
    of about 45°, while their first contact (35.4°) does not."""
    import math

    from preform.validation_suite.runner import measured_angles

    entries = measured_angles()
    assert entries
    for entry in entries:
        assert "doi:" in entry["citation"] and entry["uncertainty"] and entry["how_read"]
        assert entry["uncertainty_deg"] > 0
    (row,) = [r for r in report["angles"] if r["fabric"] == "twintex-plain-cao2008"]
    assert row["model_locking_deg"] == pytest.approx(math.degrees(math.acos(4.22 / 5.18)))
    assert row["model_locking_deg"] < row["model_jamming_deg"]
    assert row["within"] == ["jamming"]
    assert (
        "| cao2008-plain-picture-frame-locking |" in Path(report["files"]["markdown"]).read_text()
    )


def test_a_bad_normalised_row_is_located(tmp_path: Path) -> None:
    path = tmp_path / "points.csv"
    path.write_text("shear_angle_deg,force_per_length_N_per_mm\n1.0,0.01\n2.0,x\n")
    with pytest.raises(ValueError, match=r"points\.csv:3: two numbers expected"):
        read_normalised_csv(path)
    path.write_text("angle,force\n1.0,0.01\n")
    with pytest.raises(ValueError, match=r"points\.csv:1: header must be"):
        read_normalised_csv(path)
