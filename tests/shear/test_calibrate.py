"""Calibration of a mechanistic law (``preform calibrate``, ``preform.calibrate``).

The truths: data synthesised from the library's own law with known constants (the forward
picture-frame kinematics written out here, F = 2 cos ψ · L · F_s/L), which the fit must recover
within the uncertainty it states; the library's validation for entries the paths produce.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from hypothesis import given
from hypothesis import strategies as st

import preform
from preform.commands.calibrate import calibrate_command
from preform.library import build_shear_law
from preform.shear.calibrate import (
    DEFAULT_CONSTANTS,
    CalibrationError,
    FittedConstant,
    get_path,
    parse_path,
    set_path,
    transfer,
    validated_fabric,
)
from preform.shear.commands import read_test_csv
from preform.shear.law import force_per_length_N_per_mm
from preform.shear.testdata import picture_frame_displacement

SIDE_MM = 150.0
TRUTH = {"shear_law.pretension_N": 60.0, "shear_law.friction_coefficient": 0.2}


@pytest.fixture(scope="module")
def library() -> preform.library.Library:
    return preform.load_library()


def frame_test(library, truth: dict[str, float], seed: int, noise: float = 0.02):
    """Picture-frame (δ [mm], F [N]) of plain-weave-600 with ``truth`` constants, every force
    times (1 + noise·N(0,1)), from 2° to 55° (past locking at 39°: friction and pre-tension
    act apart only after it)."""
    entry = library.fabric("plain-weave-600").model_dump(mode="json", exclude_none=True)
    for path, value in truth.items():
        set_path(entry, parse_path(path), value)
    law = build_shear_law(validated_fabric(entry, library.registry), library.registry)
    gamma = np.radians(np.linspace(2.0, 55.0, 40))
    force_per_length = force_per_length_N_per_mm(law, gamma)
    half_corner = (math.pi / 2 - gamma) / 2
    force = 2.0 * np.cos(half_corner) * SIDE_MM * force_per_length
    rng = np.random.default_rng(seed)
    force = force * (1.0 + noise * rng.standard_normal(force.size))
    return picture_frame_displacement(gamma, SIDE_MM), force


def fit(library, seed: int):
    data = frame_test(library, TRUTH, seed)
    return preform.calibrate(
        "plain-weave-600",
        data,
        test="picture-frame",
        side_mm=SIDE_MM,
        constants=list(TRUTH),
        library=library,
    )


def test_the_defaults_name_paths_the_bundled_entries_hold(library) -> None:
    for fabric in library:
        law = getattr(fabric.shear_law, "law", None)
        for path in DEFAULT_CONSTANTS.get(str(law), ()):
            get_path(fabric.model_dump(mode="json"), parse_path(path))


def test_refitting_noisy_synthetic_data_recovers_the_constants(library) -> None:
    cal = fit(library, seed=1)
    for constant in cal.constants:
        truth = TRUTH[constant.name]
        assert constant.sigma is not None and constant.sigma > 0
        assert abs(constant.value - truth) <= 3 * constant.sigma, constant
        assert constant.start != truth  # it started elsewhere and moved
    assert cal.fit.relative_rms < 0.05  # 2 % noise
    assert cal.fit.r_squared is not None and cal.fit.r_squared > 0.99


def test_refitting_recovers_a_friction_mobilisation_angle(library) -> None:
    """Pre-tension and mobilisation angle from 2 %-noisy data up to locking (39°), where the
    measured curves of issue 24 are compared: both within 3σ, the fit starting at the middle
    of the angle's bounds."""
    truth = {"shear_law.pretension_N": 60.0, "shear_law.friction_mobilisation_deg": 12.0}
    data = frame_test(library, truth, seed=3)
    cal = preform.calibrate(
        "plain-weave-600",
        data,
        test="picture-frame",
        side_mm=SIDE_MM,
        constants={
            "shear_law.pretension_N": (5.0, 1000.0),
            "shear_law.friction_mobilisation_deg": (0.0, 90.0),
        },
        max_angle_deg=39.0,
        library=library,
    )
    for constant in cal.constants:
        assert constant.sigma is not None and constant.sigma > 0
        assert abs(constant.value - truth[constant.name]) <= 3 * constant.sigma, constant
        assert not constant.at_bound


@pytest.mark.slow
def test_the_stated_uncertainty_covers_the_truth_over_seeds(library) -> None:
    seeds = range(10, 20)
    inside_3 = 0
    inside_1 = 0
    for seed in seeds:
        for c in fit(library, seed).constants:
            assert c.sigma is not None
            error = abs(c.value - TRUTH[c.name])
            inside_3 += error <= 3 * c.sigma
            inside_1 += error <= c.sigma
    total = 2 * len(seeds)
    assert inside_3 == total
    assert inside_1 >= 0.5 * total  # 68 % expected; 10 of 20 holds with margin


def test_without_noise_the_fit_is_exact(library) -> None:
    data = frame_test(library, TRUTH, seed=0, noise=0.0)
    cal = preform.calibrate(
        "plain-weave-600",
        data,
        test="picture-frame",
        side_mm=SIDE_MM,
        constants=list(TRUTH),
        library=library,
    )
    for c in cal.constants:
        assert c.value == pytest.approx(TRUTH[c.name], rel=1e-4)


def test_before_locking_only_the_product_is_seen(library) -> None:
    """Before locking the force is μ·(pre-tension force): the two are not separately
    determined, and the report says so instead of printing a number."""
    data = frame_test(library, TRUTH, seed=0, noise=0.0)
    cal = preform.calibrate(
        "plain-weave-600",
        data,
        test="picture-frame",
        side_mm=SIDE_MM,
        constants=list(TRUTH),
        max_angle_deg=35.0,
        library=library,
    )
    product = math.prod(c.value for c in cal.constants)
    assert product == pytest.approx(math.prod(TRUTH.values()), rel=1e-3)
    assert any(c.sigma is None for c in cal.constants) or abs(cal.correlation[0][1]) > 0.99


def test_the_calibrated_entry_loads_as_a_library_file(library, tmp_path: Path) -> None:
    cal = fit(library, seed=2)
    path = tmp_path / "calibrated.yaml"
    path.write_text(cal.to_yaml())
    text = path.read_text()
    assert "sha256" not in text  # data given in memory: no file to hash
    assert "linearised" in text
    loaded = preform.load_library([path])
    fabric = loaded.fabric("plain-weave-600-calibrated")
    assert fabric.shear_law.pretension_N == pytest.approx(cal.constants[0].value)


# -- paths -----------------------------------------------------------------------------------


KEY = st.from_regex(r"[a-z][a-z_0-9-]{0,8}", fullmatch=True)


@given(
    first=KEY,
    keys=st.lists(st.one_of(KEY, st.integers(0, 3)), max_size=5),
    value=st.floats(allow_nan=False, allow_infinity=False),
)
def test_any_nested_path_round_trips(first: str, keys: list[str | int], value: float) -> None:
    """Build a nested dict/list along ``keys`` (an entry is a mapping: the first is a key),
    write through the path's text, read back."""
    keys = [first, *keys]
    data: object = value
    for key in reversed(keys):
        data = {key: data} if isinstance(key, str) else [None] * key + [data]
    text = preform.shear.calibrate.format_path(tuple(keys))
    assert parse_path(text) == tuple(keys)
    assert get_path(data, parse_path(text)) == value
    set_path(data, parse_path(text), 1.5)
    assert get_path(data, tuple(keys)) == 1.5


def test_dotted_indices_read_as_brackets() -> None:
    assert parse_path("threads.0.failure_strain") == parse_path("threads[0].failure_strain")
    assert parse_path("tow_types.glass-1190.compaction.fibre_wave_ratio") == (
        "tow_types",
        "glass-1190",
        "compaction",
        "fibre_wave_ratio",
    )


# -- bad input: located, no traceback ---------------------------------------------------------


def run_calibrate(tmp_path: Path, *extra: str) -> object:
    data = tmp_path / "frame.csv"
    data.write_text(Path("docs/examples/frame.csv").read_text())
    return CliRunner().invoke(
        calibrate_command,
        ["plain-weave-600", str(data), "--test", "picture-frame", "--side-mm", "150", *extra],
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--param", "shear_law.pretensoin_N"], "did you mean shear_law.pretension_N"),
        (["--param", "tow_types.nosuch.width_mm"], "unknown constant path"),
        (["--param", "weave.pattern"], "is not a number (it is 'plain')"),
        (["--param", "shear_law.law"], "is not a number"),
        (["--param", "shear_law.pretension_N=a:3"], "bounds must be LO:HI"),
        (["--param", "shear_law.pretension_N=5:1"], "LO < HI"),
        (["--param", "shear_law.pretension_N=-1:1e6"], "plausible range 0–10000 N"),
        (["--param", "tow_types.glass-1190.compaction.fibre_wave_ratio"], "give its bounds"),
        (
            ["--param", "tow_types.glass-1190.compaction.fibre_wave_ration=100:500"],
            "do not make a valid entry",
        ),
        (["--param", "shear_law.pretension_N", "--param", "shear_law.pretension_N"], "twice"),
        (["--max-angle-deg", "95"], "within (0°, 90°)"),
    ],
)
def test_bad_input_is_a_located_error(tmp_path: Path, args: list[str], message: str) -> None:
    result = run_calibrate(tmp_path, *args)
    assert result.exit_code == 2, result.output
    assert message in result.output
    assert "Traceback" not in result.output


def test_a_non_numeric_force_names_the_line(tmp_path: Path) -> None:
    data = tmp_path / "bad.csv"
    data.write_text("displacement, force\n1, 2\n2, lots\n")
    result = CliRunner().invoke(
        calibrate_command,
        ["plain-weave-600", str(data), "--test", "picture-frame", "--side-mm", "150"],
    )
    assert result.exit_code == 2
    assert f"{data}:3: force_N: 'lots' is not a number" in result.output


# -- test-file headers ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("header", "scale"),
    [
        ("displacement, force", 1.0),
        ("displacement,   force", 1.0),
        ("displacement_mm,force_N", 1.0),
        ("Displacement (mm),Force (N)", 1.0),
        ("Displacement [mm], Load [N]", 1.0),
        ("DISPLACEMENT,FORCE", 1.0),
        ("displacement (cm),force (kN)", None),
    ],
)
def test_the_usual_headers_are_read(tmp_path: Path, header: str, scale: float | None) -> None:
    path = tmp_path / "t.csv"
    path.write_text(f"# a comment line\n{header}\n0.5, 1.25\n\n1.5, 2.5\n")
    rows = read_test_csv(path)
    got = [(float(r["displacement_mm"]), float(r["force_N"])) for r in rows]
    if scale is None:  # cm and kN are converted to mm and N
        assert got == [pytest.approx((5.0, 1250.0)), pytest.approx((15.0, 2500.0))]
    else:
        assert got == [(0.5, 1.25), (1.5, 2.5)]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("time,force\n1,2\n", "need a displacement and a force column"),
        ("displacement (in),force\n1,2\n", "unit 'in' is not one of mm, cm, m"),
        ("displacement,force\n", "a header but no data rows"),
        ("displacement,force\n1\n", ":2: missing the force_N column"),
        ("displacement,force\n1,inf\n", "is not finite"),
    ],
)
def test_bad_test_files_say_where(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "t.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=None) as info:
        read_test_csv(path)
    assert message in str(info.value)
    assert str(path) in str(info.value)


# -- carrying constants to fabrics of the same tows --------------------------------------------

SAME_TOWS = """
- name: twill-same-tows
  architecture: woven
  source: test entry
  note: illustrative; plain-weave-600's tows woven as a 2/2 twill, tow type renamed
  tow_types:
    g1190: {fibre: glass, linear_density_tex: 1190, width_mm: 3.1, height_mm: 0.32}
  warp: {tow_spacing_mm: 4.0, tow_type: g1190}
  weft: {tow_spacing_mm: 4.0, tow_type: g1190}
  weave: {pattern: twill, over: 2, under: 2}
  shear_law: {law: friction_compaction, friction_coefficient: 0.3, pretension_N: 100}
- name: twill-other-tows
  architecture: woven
  source: test entry
  note: illustrative; thinner tows
  tow_types:
    g600: {fibre: glass, linear_density_tex: 600, width_mm: 3.1, height_mm: 0.2}
  warp: {tow_spacing_mm: 4.0, tow_type: g600}
  weft: {tow_spacing_mm: 4.0, tow_type: g600}
  weave: {pattern: twill, over: 2, under: 2}
  shear_law: {law: friction_compaction, friction_coefficient: 0.3, pretension_N: 100}
"""


def test_apply_to_carries_constants_to_the_same_tows_only(tmp_path: Path) -> None:
    extra = tmp_path / "twills.yaml"
    extra.write_text(SAME_TOWS)
    library = preform.load_library([extra])
    cal = fit(library, seed=3)
    carried = {t.fabric: t for t in cal.apply_to("twill-*", library)}
    same, other = carried["twill-same-tows"], carried["twill-other-tows"]
    assert other.entry is None
    assert "different tows" in other.reason and "600 tex" in other.reason
    assert same.entry is not None
    assert same.entry["name"] == "twill-same-tows-calibrated"
    assert "carried over from plain-weave-600" in same.entry["note"]
    fabric = validated_fabric(same.entry, library.registry)
    values = {c.name: c.value for c in cal.constants}
    assert fabric.shear_law.pretension_N == values["shear_law.pretension_N"]
    assert fabric.shear_law.friction_coefficient == values["shear_law.friction_coefficient"]
    # a constant under a tow type lands on the target's tow type of the same tows
    tow_constant = FittedConstant(
        "tow_types.glass-1190.filament_diameter_um", 12.0, None, 17.0, 5.0, 30.0, False
    )
    with_tow = dataclasses.replace(cal, constants=[*cal.constants, tow_constant])
    moved = transfer(with_tow, library.fabric("twill-same-tows"), library.registry)
    assert moved.entry is not None
    assert moved.entry["tow_types"]["g1190"]["filament_diameter_um"] == 12.0


def test_apply_to_through_the_command_writes_and_skips(tmp_path: Path) -> None:
    extra = tmp_path / "twills.yaml"
    extra.write_text(SAME_TOWS)
    out = tmp_path / "calibrated.yaml"
    result = run_calibrate(
        tmp_path,
        "--library",
        str(extra),
        "--param",
        "shear_law.pretension_N",
        "--max-angle-deg",
        "35",
        "--apply-to",
        "twill-*",
        "--out",
        str(out),
    )
    assert result.exit_code == 0, result.output
    assert "apply to twill-same-tows: wrote twill-same-tows-calibrated" in result.output
    assert "apply to twill-other-tows: skipped: different tows" in result.output
    names = [e["name"] for e in yaml.safe_load(out.read_text())]
    assert names == ["plain-weave-600-calibrated", "twill-same-tows-calibrated"]
    assert preform.load_library([out]).fabric("twill-same-tows-calibrated")


def test_apply_to_matching_nothing_is_an_error(tmp_path: Path) -> None:
    result = run_calibrate(tmp_path, "--max-angle-deg", "35", "--apply-to", "nosuch*")
    assert result.exit_code == 2
    assert "matches no fabric" in result.output


def test_unknown_law_defaults_say_how_to_name_constants(library) -> None:
    fabric = library.fabric("E-BX-318")  # stitch_polynomial: a fitted law, no defaults
    with pytest.raises(CalibrationError, match="--param PATH"):
        preform.shear.calibrate.resolve_constants(fabric, None)
