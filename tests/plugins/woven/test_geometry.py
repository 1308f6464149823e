"""The general woven unit cell: paths, crossovers, derived properties and self-checks."""

from __future__ import annotations

import math
from collections import Counter

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from preform.geometry.fibres import fibre
from preform.plugins.woven import weaves
from preform.plugins.woven.geometry import (
    TowType,
    WeaveDescription,
    WovenUnitCell,
    areal_density_g_m2,
)

GLASS = fibre("glass")


def tow(tex: float = 1190.0, width: float = 3.1e-3, height: float = 0.32e-3) -> TowType:
    return TowType(f"glass-{tex:g}", GLASS, tex, width, height)


def build(
    weave: WeaveDescription,
    warp: TowType | None = None,
    weft: TowType | None = None,
    spacing_warp: float = 4e-3,
    spacing_weft: float = 4e-3,
) -> WovenUnitCell:
    warp, weft = warp or tow(), weft or tow()
    return WovenUnitCell(
        weave,
        spacing_warp,
        spacing_weft,
        tuple((warp,) * weave.repeat_warp for _ in range(weave.warp_levels)),
        tuple((weft,) * weave.repeat_weft for _ in range(weave.weft_levels)),
    )


@st.composite
def valid_2d_weaves(draw: st.DrawFn) -> WeaveDescription:
    """Random binary weaves in which every warp and every weft tow interlaces."""
    rows = draw(st.integers(2, 6))
    cols = draw(st.integers(2, 6))
    w = draw(
        st.lists(
            st.lists(st.integers(0, 1), min_size=cols, max_size=cols), min_size=rows, max_size=rows
        )
    )
    assume(all(0 < sum(r) < cols for r in w))
    assume(all(0 < sum(w[i][j] for i in range(rows)) < rows for j in range(cols)))
    return weaves.from_over_under(w)


tow_types = st.builds(
    tow,
    tex=st.floats(50, 3000),
    width=st.floats(0.5e-3, 3e-3),
    height=st.floats(0.05e-3, 0.5e-3),
)


@given(valid_2d_weaves(), tow_types, tow_types, st.floats(3e-3, 6e-3), st.floats(3e-3, 6e-3))
# Most random 0/1 matrices leave some tow without an interlacing and are filtered out; that is
# the point of the strategy, not a slow test (it failed the health check now and then).
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
def test_random_2d_weaves(
    weave: WeaveDescription, warp: TowType, weft: TowType, s_warp: float, s_weft: float
) -> None:
    cell = build(weave, warp, weft, s_warp, s_weft)
    assert cell.errors() == []
    # Paths are at least as long as the repeat along them, and crimp is the excess.
    for key in cell.tow_keys():
        assert cell.path_length(key) >= cell.straight_length(key) * (1 - 1e-12)
    nominal = warp.linear_density_tex / (s_warp * 1e3) + weft.linear_density_tex / (s_weft * 1e3)
    assert cell.areal_density() >= nominal * (1 - 1e-12)
    # Areal density does not depend on how many repeats are built.
    unit = cell.to_unit_cell()
    assert areal_density_g_m2(unit) == pytest.approx(cell.areal_density(), rel=1e-12)
    for n1, n2 in [(2, 1), (3, 2)]:
        assert areal_density_g_m2(unit.tiled(n1, n2)) == pytest.approx(
            cell.areal_density(), rel=1e-12
        )
    # Tiled paths join: each tow ends where its copy in the next repeat starts.
    for path in unit.tows:
        start, end = path.points[0], path.points[-1]
        assert start[2] == pytest.approx(end[2])


def test_plain_weave_crimp_closed_form() -> None:
    """Warp wraps a weft of height h_wt: each vector rises h_wt over one weft spacing."""
    warp, weft = tow(height=0.3e-3), tow(height=0.5e-3)
    cell = build(weaves.plain(), warp, weft, spacing_warp=2e-3, spacing_weft=4e-3)
    assert cell.crimp("warp") == pytest.approx(math.hypot(4e-3, 0.5e-3) / 4e-3 - 1)
    assert cell.crimp("weft") == pytest.approx(math.hypot(2e-3, 0.3e-3) / 2e-3 - 1)
    nominal_warp = 1190 / 2.0
    assert cell.areal_density("warp") == pytest.approx(nominal_warp * (1 + cell.crimp("warp")))
    assert cell.thickness() == pytest.approx(0.8e-3)


def test_tow_and_fabric_volume_fractions() -> None:
    t = tow()
    a_f = 1190 / (1000 * 2.55) * 1e-6  # m², PHYSICS §1.3
    assert t.volume_fraction == pytest.approx(a_f / (math.pi / 4 * 3.1e-3 * 0.32e-3))
    cell = build(weaves.plain())
    expected = cell.areal_density() / (2.55e6 * cell.thickness())  # g/m² / (g/m³ · m)
    assert cell.fibre_volume_fraction() == pytest.approx(expected)


def test_cover_factor_closed_form() -> None:
    cell = build(weaves.plain(), tow(width=3e-3), tow(width=2e-3))
    assert cell.cover_factor() == pytest.approx(1 - (1 - 3 / 4) * (1 - 2 / 4))


def test_locking_angles_and_hybrid() -> None:
    cell = build(weaves.plain(), tow(width=3.1e-3), tow(width=1.2e-3 * 2))
    assert math.degrees(cell.locking_angle("warp")) == pytest.approx(39.19, abs=0.01)
    assert math.degrees(cell.locking_angle("weft")) == pytest.approx(53.13, abs=0.01)
    # Hybrid level: neighbours 3 mm and 1 mm wide touch when Ts cos γ = 2 mm.
    weave = weaves.plain()
    a, b = tow(width=3e-3), tow(width=1e-3)
    hybrid = WovenUnitCell(weave, 4e-3, 4e-3, ((a, b),), ((a, a),))
    assert hybrid.locking_angle("warp") == pytest.approx(math.acos(2 / 4))


def test_crossover_geometry_plain_and_satin() -> None:
    plain = build(weaves.plain()).crossover_geometry()
    assert plain.crossovers_per_area == pytest.approx(1 / 4e-3**2)
    assert plain.interlacings_per_area == pytest.approx(2 / 4e-3**2)
    assert (plain.mean_float_warp, plain.mean_float_weft, plain.levels) == (1.0, 1.0, 2)
    assert plain.fibre_area_warp == pytest.approx(1190 / 2550 * 1e-6)
    satin = build(weaves.satin(5, 2)).crossover_geometry()
    assert satin.mean_float_warp == pytest.approx(2.5)
    assert satin.interlacings_per_area == pytest.approx(2 * 10 / (25 * 4e-3**2))


def test_unit_cell_kinds_levels_and_reference() -> None:
    cell = build(weaves.orthogonal_3d(2, 3), warp=tow(), weft=tow())
    unit = cell.to_unit_cell()
    kinds = Counter(t.kind for t in unit.tows)
    assert kinds == {"warp": 4, "binder": 2, "weft": 6}
    assert unit.reference_direction == pytest.approx(math.pi / 4)
    assert unit.labels["levels"] == {
        1: "stuffer",
        2: "stuffer",
        3: "binder",
        4: "weft",
        5: "weft",
        6: "weft",
    }
    assert unit.area == pytest.approx(cell.area)


# -- self-checks: each fixture triggers one problem --------------------------------------
def general(matrix: list[list[list[int]]], **kw: int) -> WeaveDescription:
    fields = {"warp_levels": 1, "weft_levels": 1, "repeat_warp": 2, "repeat_weft": 2} | kw
    return WeaveDescription(matrix=tuple(tuple(tuple(e) for e in row) for row in matrix), **fields)


PLAIN = [[[2, 1], [1, 2]], [[1, 2], [2, 1]]]


@pytest.mark.parametrize(
    ("weave", "location", "words"),
    [
        (general(PLAIN, repeat_warp=3), ("weave", "matrix"), "2 rows"),
        (general([[[2, 1], [1, 2]], [[1, 2]]]), ("weave", "matrix", 1), "1 entries"),
        (general([[[2, 1], [1, 3]], [[1, 2], [2, 1]]]), ("weave", "matrix", 0, 1), "do not exist"),
        (general([[[2, 1], [1]], [[1, 2], [2, 1]]]), ("weave", "matrix", 0, 1), "misses level"),
        (
            general([[[2, 1], [1, 2, 1]], [[1, 2], [2, 1]]]),
            ("weave", "matrix", 0, 1),
            "more than once",
        ),
        (
            general([[[2, 1], [2, 1]], [[2, 1], [1, 2]], [[1, 2], [2, 1]]], repeat_warp=3),
            ("weave", "matrix", 0),
            "floats over the whole",
        ),
        (
            general([[[2, 1], [1, 2], [1, 2]], [[1, 2], [2, 1], [1, 2]]], repeat_weft=3),
            ("weave", "matrix"),
            "weft tow 2",
        ),
    ],
)
def test_2d_self_checks(weave: WeaveDescription, location: tuple, words: str) -> None:
    errors = build(weave).errors()
    assert errors
    assert {loc for loc, _ in errors} == {location}
    assert any(words in message for _, message in errors)
    with pytest.raises(ValueError, match="invalid woven unit cell"):
        build(weave).to_unit_cell()


def test_tow_types_shape_check() -> None:
    weave = weaves.plain()
    cell = WovenUnitCell(weave, 4e-3, 4e-3, ((tow(),),), ((tow(), tow()),))
    assert cell.errors() == [
        (("warp", "tow_types", 0), "1 tow type(s) given for 2 warp-wise tows in the repeat")
    ]


def test_binder_never_interlacing_and_unbound_level() -> None:
    # Levels: 1 stuffer, 2 binder, 3-4 weft. The binder stays on top: it neither interlaces
    # nor holds anything.
    column = (3, 1, 4, 2)
    weave = WeaveDescription(2, 2, 1, 2, ((column, column),), binder_levels=(2,))
    errors = build(weave).errors()
    assert (("weave", "matrix", 0), errors[0][1]) == errors[0]
    assert "binder (level 2) at warp position 0 never interlaces" in errors[0][1]
    unbound = [e for e in errors if e[0] == ("weave", "binder_levels")]
    assert [m.split(" (")[0] for _, m in unbound] == [
        "no binder holds level 1",
        "no binder holds level 3",
        "no binder holds level 4",
    ]


def test_3d_without_binders_and_binder_level_checks() -> None:
    weave = WeaveDescription(2, 1, 1, 2, (((3, 1, 2), (1, 2, 3)),))
    assert {loc for loc, _ in build(weave).errors()} == {("weave", "binder_levels")}
    bad = WeaveDescription(2, 1, 1, 2, (((3, 1, 2), (1, 2, 3)),), binder_levels=(3,))
    assert build(bad).errors()[0][0] == ("weave", "binder_levels", 0)
    flat = WeaveDescription(1, 1, 2, 2, weaves.plain().matrix, binder_levels=(1,))
    assert build(flat).errors() == [(("weave", "binder_levels"), "binder levels need a 3D weave")]


def test_width_at_least_spacing_warns_and_locks() -> None:
    cell = build(weaves.plain(), warp=tow(width=4.2e-3))
    assert cell.errors() == []
    warnings = cell.warnings()
    assert {loc for loc, _ in warnings} == {
        ("warp", "tow_types", 0, 0),
        ("warp", "tow_types", 0, 1),
    }
    assert "locked" in warnings[0][1]
    assert cell.locking_angle("warp") == 0.0
    assert cell.locking_angle("weft") == pytest.approx(math.acos(3.1 / 4))
