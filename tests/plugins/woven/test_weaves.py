"""Weave generators: satin move rules, crowfoot, twill/basket closed forms, 3D interlocks."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.geometry.fibres import fibre
from preform.plugins.woven import weaves
from preform.plugins.woven.geometry import TowType, WeaveDescription, WovenUnitCell


def over_under(weave: WeaveDescription) -> list[list[int]]:
    """Back to W[i][j] = 1 when warp (level 1) is over weft (level 2)."""
    return [[int(e.index(1) > e.index(2)) for e in row] for row in weave.matrix]


def build(weave: WeaveDescription) -> WovenUnitCell:
    tow = TowType("t", fibre("glass"), 600.0, 3e-3, 0.2e-3)
    return WovenUnitCell(
        weave,
        4e-3,
        4e-3,
        tuple((tow,) * weave.repeat_warp for _ in range(weave.warp_levels)),
        tuple((tow,) * weave.repeat_weft for _ in range(weave.weft_levels)),
    )


def test_plain_matches_physics_matrix() -> None:
    assert over_under(weaves.plain()) == [[1, 0], [0, 1]]
    assert weaves.plain().matrix[0][0] == (2, 1)  # warp (1) over weft (2): bottom to top


@pytest.mark.parametrize(("harness", "moves"), [(5, [2, 3]), (7, [2, 3, 4, 5]), (8, [3, 5])])
def test_valid_satin_moves_published(harness: int, moves: list[int]) -> None:
    assert weaves.valid_satin_moves(harness) == moves


@pytest.mark.parametrize("harness", [4, 6])
def test_harnesses_without_regular_satin(harness: int) -> None:
    assert weaves.valid_satin_moves(harness) == []


@given(st.integers(5, 16), st.data())
@settings(max_examples=40, deadline=None)
def test_regular_satin_is_a_permutation(harness: int, data: st.DataObject) -> None:
    moves = weaves.valid_satin_moves(harness)
    if not moves:
        return
    move = data.draw(st.sampled_from(moves))
    w = over_under(weaves.satin(harness, move))
    # Exactly one under per warp and per weft: each weft is held by exactly one warp.
    assert all(row.count(0) == 1 for row in w)
    assert all([w[i][j] for i in range(harness)].count(0) == 1 for j in range(harness))
    assert all(w[i][(move * i) % harness] == 0 for i in range(harness))
    # Neighbouring warps go under `move` wefts apart, never 1 or n-1: no twill line.
    unders = [row.index(0) for row in w]
    steps = {(unders[(i + 1) % harness] - unders[i]) % harness for i in range(harness)}
    assert steps == {move} and move not in (1, harness - 1)
    assert build(weaves.satin(harness, move)).errors() == []


@pytest.mark.parametrize(("harness", "move"), [(5, 1), (5, 4), (8, 2), (8, 4), (8, 7), (6, 5)])
def test_invalid_satin_moves_rejected_with_suggestion(harness: int, move: int) -> None:
    with pytest.raises(ValueError, match="regular") as info:
        weaves.satin(harness, move)
    if weaves.valid_satin_moves(harness):
        assert "valid moves: " + ", ".join(map(str, weaves.valid_satin_moves(harness))) in str(
            info.value
        )


def test_four_harness_satin_points_to_crowfoot() -> None:
    with pytest.raises(ValueError, match="crowfoot"):
        weaves.satin(4, 2)


def test_crowfoot_irregular_but_valid() -> None:
    w = over_under(weaves.crowfoot())
    assert [row.index(0) for row in w] == list(weaves.CROWFOOT_UNDER)
    assert all(row.count(0) == 1 for row in w)
    assert sorted(row.index(0) for row in w) == [0, 1, 2, 3]
    # No move number reproduces it (that is what "irregular" means).
    assert not any(all(w[i][(m * i) % 4] == 0 for i in range(4)) for m in range(4))
    cell = build(weaves.crowfoot())
    assert cell.errors() == []
    assert all(f == (3, 1) or f == (1, 3) for f in cell.float_lengths().values())


@given(st.integers(1, 4), st.integers(1, 4))
@settings(max_examples=20, deadline=None)
def test_twill_closed_form(over: int, under: int) -> None:
    n = over + under
    w = over_under(weaves.twill(over, under))
    assert w == [[int((j - i) % n < over) for j in range(n)] for i in range(n)]
    # Each warp row is the previous one shifted by one weft: the twill line.
    assert all(w[i] == w[i - 1][-1:] + w[i - 1][:-1] for i in range(1, n))
    floats = build(weaves.twill(over, under)).float_lengths()
    assert floats[next(iter(floats))] in {(over, under), (under, over)}


def test_basket_is_grouped_plain() -> None:
    w = over_under(weaves.basket(2, 3))
    assert len(w) == 4 and len(w[0]) == 6
    assert all(w[i][j] == (1 - (i // 2 + j // 3) % 2) for i in range(4) for j in range(6))
    assert over_under(weaves.basket(1, 1)) == over_under(weaves.plain())


def test_orthogonal_binder_goes_over_then_under_everything() -> None:
    weave = weaves.orthogonal_3d(stuffer_layers=2, weft_layers=3)
    assert (weave.warp_levels, weave.weft_levels, weave.binder_levels) == (3, 3, (3,))
    assert weave.matrix[0][0][-1] == 3 and weave.matrix[0][1][0] == 3
    assert weave.matrix[1][0][0] == 3  # neighbouring binder in opposite phase
    cell = build(weave)
    assert cell.errors() == []
    assert cell.crimp("weft") == pytest.approx(0.0, abs=1e-12)
    for level in (1, 2):  # stuffers stay straight
        key = next(k for k in cell.tow_keys() if k.level == level)
        assert cell.path_length(key) == pytest.approx(cell.straight_length(key))
    # Binder at top and bottom outside the five-tow stack: thickness = 5 h + 2 h.
    assert cell.thickness() == pytest.approx(7 * 0.2e-3)


@given(st.integers(0, 3), st.integers(2, 5), st.data())
@settings(max_examples=30, deadline=None)
def test_angle_interlock_every_level_held(stuffers: int, wefts: int, data: st.DataObject) -> None:
    depth = data.draw(st.integers(2, wefts))
    weave = weaves.angle_interlock_3d(stuffers, wefts, depth)
    assert len(weave.binder_levels) == wefts - depth + 1
    assert weave.repeat_weft == 2 * depth
    cell = build(weave)
    assert cell.errors() == []
    assert all(
        cell.interlacings()[k] > 0 for k in cell.tow_keys() if k.level in weave.binder_levels
    )
    # Binders do not open the stack; the outermost ones lie just outside it (all h = 0.2 mm).
    assert cell.thickness() == pytest.approx((stuffers + wefts + 2) * 0.2e-3)
    assert cell.crimp("weft") == pytest.approx(0.0, abs=1e-12)


def test_layer_to_layer_is_depth_two() -> None:
    assert weaves.layer_to_layer_3d(1, 4) == weaves.angle_interlock_3d(1, 4, 2)


@pytest.mark.parametrize(
    ("stuffers", "wefts", "depth"), [(0, 1, None), (-1, 3, None), (1, 3, 1), (1, 3, 4)]
)
def test_bad_3d_parameters(stuffers: int, wefts: int, depth: int | None) -> None:
    with pytest.raises(ValueError):
        weaves.angle_interlock_3d(stuffers, wefts, depth)


def test_satin_float_lengths() -> None:
    for harness, move in [(5, 2), (8, 3)]:
        floats = build(weaves.satin(harness, move)).float_lengths()
        assert all(sorted(f) == [1, harness - 1] for f in floats.values())
