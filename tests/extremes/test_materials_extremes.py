"""Fabric entries at the edges of the schema, through the real YAML loader: tows as wide as or
wider than their spacing, tex and spacing from 1e-9 to 1e9, 1×1 and large repeats, random valid
weaves and warp-knits, random shear-law blocks, and invalid entries.

Why: a user's library is the input most likely to hold a typo or an odd fabric. Every entry must
either load with finite derived properties and a usable shear law, or be refused with errors
located as ``FILE:LINE:COL: path: message``; never a traceback and never a NaN in the derived
table that ends up in a results CSV.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from preform.library import LibraryError, build_shear_law
from preform.plugins.woven.weaves import valid_satin_moves
from preform.testing import PluginSandbox

#: One located error: file, line, column, dotted path, message (message may run on).
LOCATED = re.compile(r"^(?P<file>.+?):(?P<line>[1-9]\d*):(?P<col>[1-9]\d*): (?P<path>\S+): \S")

EXTREME = st.sampled_from([1e-9, 1e-3, 0.5, 1.0, 4.0, 1e3, 1e9])
SETTINGS = settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def all_finite(value: Any) -> bool:
    """Every number in a (nested) derived-properties value is finite."""
    if isinstance(value, dict):
        return all(all_finite(v) for v in value.values())
    if isinstance(value, list | tuple):
        return all(all_finite(v) for v in value)
    if isinstance(value, bool | str) or value is None:
        return True
    return bool(np.all(np.isfinite(np.asarray(value, dtype=float))))


def load(sandbox: PluginSandbox, tmp_path: Path, entries: list[dict[str, Any]]) -> Any:
    path = tmp_path / "fabrics.yaml"
    path.write_text(yaml.safe_dump(entries, sort_keys=False))
    return sandbox.library([path])


#: The override a range error suggests: "add 'PATH' to this entry's accept_out_of_range".
OVERRIDE_HINT = re.compile(r"add '([^']+)' to this entry's accept_out_of_range")


def check_entry(sandbox: PluginSandbox, tmp_path: Path, entry: dict[str, Any]) -> None:
    """Load → finite derived properties, a unit cell and a sound law; or located errors.

    Values outside their plausible range are accepted through the override each error
    suggests: a user may do the same, so geometry and laws must stay sound for them too."""
    try:
        lib = load(sandbox, tmp_path, [entry])
    except LibraryError as exc:
        overrides = [m.group(1) for e in exc.errors if (m := OVERRIDE_HINT.search(str(e)))]
        if overrides and len(overrides) == len(exc.errors):
            check_entry(sandbox, tmp_path, {**entry, "accept_out_of_range": overrides})
            return
        assert exc.errors
        for error in exc.errors:
            text = str(error)
            assert LOCATED.match(text), text
            assert text.startswith(str(tmp_path / "fabrics.yaml"))
            assert "Traceback" not in text and "failed to check this entry" not in text, text
        return
    fabric = lib.fabric(entry["name"])
    derived = fabric.derived()
    assert all_finite(derived), derived
    json.dumps(derived, allow_nan=False)
    cell = fabric.unit_cell()
    assert cell is not None
    if fabric.shear_law is None:
        return
    try:
        law = build_shear_law(fabric, sandbox.registry)
    except ValueError as exc:  # a physically impossible combination, said in words
        assert str(exc)
        return
    gamma = np.linspace(-math.pi / 2, math.pi / 2, 181)
    torque, energy = np.asarray(law.torque(gamma)), np.asarray(law.energy(gamma))
    assert np.all(np.isfinite(torque)) and np.all(np.isfinite(energy)) and np.all(energy >= 0)
    assert float(law.energy(0.0)) == 0.0


@pytest.fixture
def sandbox(preform_plugins: PluginSandbox) -> PluginSandbox:
    preform_plugins.load_builtins()
    return preform_plugins


# -- strategies ------------------------------------------------------------------------------

weave_strategy = st.one_of(
    st.just({"pattern": "plain"}),
    st.builds(
        lambda over, under: {"pattern": "twill", "over": over, "under": under},
        st.integers(1, 6),
        st.integers(1, 6),
    ),
    st.integers(5, 24).flatmap(
        lambda n: st.sampled_from(valid_satin_moves(n) or [2]).map(
            lambda m: {"pattern": "satin", "harness": n, "move": m}
        )
    ),
)

friction_law = st.fixed_dictionaries(
    {
        "law": st.just("friction_compaction"),
        "pretension_N": st.sampled_from([0.0, 1e-9, 50.0, 1e9]),
        "fabric_thickness_mm": EXTREME,
        "friction_coefficient": st.sampled_from([0.0, 0.3, 1e3]),
    }
)


@st.composite
def woven_entries(draw: st.DrawFn) -> dict[str, Any]:
    width = draw(EXTREME)
    spacing = draw(st.one_of(EXTREME, st.just(width)))  # width = spacing: locking angle 0
    entry: dict[str, Any] = {
        "name": "random-woven",
        "architecture": "woven",
        "source": "hypothesis",
        "note": "generated by tests/extremes",
        "tow_types": {
            "t": {
                "fibre": draw(st.sampled_from(["glass", "carbon"])),
                "linear_density_tex": draw(EXTREME),
                "width_mm": width,
                "height_mm": draw(EXTREME),
            }
        },
        "warp": {"tow_spacing_mm": spacing, "tow_type": "t"},
        "weft": {"tow_spacing_mm": draw(st.one_of(EXTREME, st.just(spacing))), "tow_type": "t"},
        "weave": draw(weave_strategy),
    }
    if draw(st.booleans()):
        entry["shear_law"] = draw(friction_law)
    return entry


stitch_law = st.fixed_dictionaries(
    {
        "law": st.just("stitch_polynomial"),
        "parallel_force_coefficients_N_per_mm": st.lists(EXTREME, min_size=1, max_size=4),
        "perpendicular_force_coefficients_N_per_mm": st.lists(EXTREME, min_size=1, max_size=4),
        "max_angle_deg": st.sampled_from([1.0, 60.0, 90.0]),
    }
)


@st.composite
def warp_knit_entries(draw: st.DrawFn) -> dict[str, Any]:
    def layer(orientation: float) -> dict[str, Any]:
        return {
            "orientation_deg": orientation,
            "spacing_mm": draw(EXTREME),
            "fibre": "glass",
            "linear_density_tex": draw(EXTREME),
            "tow_width_mm": draw(EXTREME),
            "tow_height_mm": draw(st.sampled_from([1e-3, 0.2, 1.0])),
        }

    orientations = draw(st.sampled_from([[45.0, -45.0], [0.0, 90.0], [0.0], [30.0, -60.0, 90.0]]))
    entry: dict[str, Any] = {
        "name": "random-knit",
        "architecture": "warp_knit",
        "source": "hypothesis",
        "note": "generated by tests/extremes",
        "tow_layers": [layer(o) for o in orientations],
        "threads": [
            {
                "knitting_sequence": draw(
                    st.sampled_from(["1-0/0-1", "1-0/1-2", "1-0/2-3", "1-0/3-4"])
                ),
                "overlap_length_mm": draw(st.sampled_from([1e-3, 6.0, 1e3])),
                "stitch_length_mm": draw(st.sampled_from([1e-3, 2.5, 1e3])),
                "gauge_needles_per_inch": draw(st.sampled_from([0.1, 5.0, 1e3])),
                "linear_density_tex": draw(st.sampled_from([1e-9, 7.6, 1e9])),
            }
        ],
    }
    if draw(st.booleans()):
        entry["shear_law"] = draw(stitch_law)
    return entry


# -- tests -----------------------------------------------------------------------------------


@SETTINGS
@given(entry=woven_entries())
def test_random_woven_entries_load_or_fail_located(
    sandbox: PluginSandbox, tmp_path: Path, entry: dict[str, Any]
) -> None:
    check_entry(sandbox, tmp_path, entry)


@SETTINGS
@given(entry=warp_knit_entries())
def test_random_warp_knit_entries_load_or_fail_located(
    sandbox: PluginSandbox, tmp_path: Path, entry: dict[str, Any]
) -> None:
    check_entry(sandbox, tmp_path, entry)


def woven(width: float, spacing: float, weave: dict[str, Any], tex: float = 600.0) -> dict:
    return {
        "name": "w",
        "architecture": "woven",
        "source": "test",
        "note": "test",
        "tow_types": {
            "t": {"fibre": "glass", "linear_density_tex": tex, "width_mm": width, "height_mm": 0.2}
        },
        "warp": {"tow_spacing_mm": spacing, "tow_type": "t"},
        "weft": {"tow_spacing_mm": spacing, "tow_type": "t"},
        "weave": weave,
        "shear_law": {"law": "friction_compaction", "pretension_N": 50, "fabric_thickness_mm": 1},
    }


@pytest.mark.parametrize("width", [3.9999999, 4.0, 4.0000001, 8.0])
def test_tow_width_at_and_past_spacing_loads_with_a_warning(
    sandbox: PluginSandbox, tmp_path: Path, width: float
) -> None:
    """Width ≥ spacing is legal but suspicious: a warning, locking angle 0 (not NaN)."""
    lib = load(sandbox, tmp_path, [woven(width, 4.0, {"pattern": "plain"})])
    derived = lib.fabric("w").derived()
    assert all_finite(derived)
    assert derived["locking_angle_deg"] == pytest.approx(
        math.degrees(math.acos(min(1.0, width / 4.0))), abs=1e-3
    )
    if width >= 4.0:
        assert any("w.tow_types.t.width_mm" in str(w) for w in lib.warnings), lib.warnings
    check_entry(sandbox, tmp_path, woven(width, 4.0, {"pattern": "plain"}))


def test_large_repeat_satin(sandbox: PluginSandbox, tmp_path: Path) -> None:
    """A 64-harness satin builds (a large repeat is slow only in proportion to its size)."""
    moves = valid_satin_moves(64)
    check_entry(
        sandbox, tmp_path, woven(3.0, 4.0, {"pattern": "satin", "harness": 64, "move": moves[0]})
    )


@pytest.mark.parametrize(
    ("weave", "where"),
    [
        (
            {
                "pattern": "general",
                "warp_levels": 1,
                "weft_levels": 1,
                "repeat_warp": 1,
                "repeat_weft": 1,
                "matrix": [[[2, 1]]],
            },
            "w.weave",
        ),
        ({"pattern": "satin", "harness": 8, "move": 2}, "w.weave.move"),
        ({"pattern": "satin", "harness": 4, "move": 1}, "w.weave.harness"),
        ({"pattern": "twill", "over": 0, "under": 1}, "w.weave.over"),
    ],
    ids=["1x1 general", "satin bad move", "4-harness satin", "twill 0 over"],
)
def test_invalid_weaves_are_located(
    sandbox: PluginSandbox, tmp_path: Path, weave: dict[str, Any], where: str
) -> None:
    with pytest.raises(LibraryError) as info:
        load(sandbox, tmp_path, [woven(3.0, 4.0, weave)])
    texts = [str(e) for e in info.value.errors]
    assert all(LOCATED.match(t) for t in texts), texts
    assert any(f": {where}" in t for t in texts), texts


@pytest.mark.parametrize(
    ("patch", "where"),
    [
        ({"tow_types": {"t": {"fibre": "glass", "linear_density_tex": 0, "width_mm": 3, "height_mm": 0.2}}}, "w.tow_types.t.linear_density_tex"),
        ({"tow_types": {"t": {"fibre": "glass", "linear_density_tex": ".inf", "width_mm": 3, "height_mm": 0.2}}}, "w.tow_types.t.linear_density_tex"),
        ({"warp": {"tow_spacing_mm": -4, "tow_type": "t"}}, "w.warp.tow_spacing_mm"),
        ({"warp": {"tow_spacing_mm": 4, "tow_type": "nope"}}, "w.warp.tow_type"),
        ({"shear_law": {"law": "friction_compaction", "pretension_N": ".inf", "fabric_thickness_mm": 1}}, "w.shear_law.pretension_N"),
        ({"shear_law": {"law": "friction_compaction", "pretension_N": ".nan", "fabric_thickness_mm": 1}}, "w.shear_law.pretension_N"),
        ({"shear_law": {"law": "friction_compaction", "pretension_N": 1, "fabric_thickness_mm": 0}}, "w.shear_law.fabric_thickness_mm"),
    ],
    ids=["tex 0", "tex inf", "negative spacing", "unknown tow type", "inf pretension", "nan pretension", "zero thickness"],
)  # fmt: skip
def test_invalid_values_are_located(
    sandbox: PluginSandbox, tmp_path: Path, patch: dict[str, Any], where: str
) -> None:
    """Non-positive, infinite and NaN values (YAML .inf/.nan) are refused where they stand."""
    entry = woven(3.0, 4.0, {"pattern": "plain"}) | patch
    text = yaml.safe_dump([entry], sort_keys=False).replace("'.inf'", ".inf")
    path = tmp_path / "fabrics.yaml"
    path.write_text(text.replace("'.nan'", ".nan"))
    with pytest.raises(LibraryError) as info:
        sandbox.library([path])
    texts = [str(e) for e in info.value.errors]
    assert all(LOCATED.match(t) for t in texts), texts
    # The YAML reader refuses .inf/.nan before validation and names the entry by index.
    field = where.removeprefix("w.")
    assert any(f"w.{field}:" in t or f"[0].{field}:" in t for t in texts), texts
