"""Generators of common weaves: each returns the levels and weaving matrix of one repeat.

2D patterns are written as binary over/under matrices W[i][j] = 1 when warp i is over weft j
(PHYSICS §1.1) and turned into level lists: warp is level 1, weft level 2, so warp over weft is
the entry (2, 1) (bottom to top). Satins are warp-faced: warp i is under only at weft
(m·i) mod n.

3D weaves stack weft layers and warp stuffer layers alternately, a weft layer at the bottom
(weft 0, stuffer 0, weft 1, stuffer 1, ...; surplus layers of either kind go on top). Level
ids: stuffers 1..S, binders S+1..S+B, weft layers after them. Each binder runs at every warp
position of the repeat; the second warp position is shifted by half a binder period so that
neighbouring binders are in opposite phase.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from preform.plugins.woven.geometry import WeaveDescription

#: The crowfoot (4-harness satin, 3/1 broken twill): warp i is under only at weft
#: CROWFOOT_UNDER[i]. No regular move number exists for n = 4, so the standard broken order
#: 1-2-4-3 (0-based 0, 1, 3, 2) is used.
CROWFOOT_UNDER = (0, 1, 3, 2)


def from_over_under(over: Sequence[Sequence[int]]) -> WeaveDescription:
    """A 2D weave from its binary matrix (1 = warp over weft) [dimensionless]."""
    rows = [list(r) for r in over]
    if not rows or not rows[0]:
        raise ValueError("the over/under matrix is empty")
    if any(len(r) != len(rows[0]) for r in rows):
        raise ValueError("the over/under matrix is not rectangular")
    if any(v not in (0, 1) for r in rows for v in r):
        raise ValueError("over/under entries must be 1 (warp over) or 0 (warp under)")
    matrix = tuple(tuple((2, 1) if v else (1, 2) for v in r) for r in rows)
    return WeaveDescription(
        warp_levels=1,
        weft_levels=1,
        repeat_warp=len(rows),
        repeat_weft=len(rows[0]),
        matrix=matrix,
    )


def plain() -> WeaveDescription:
    """Plain weave: 2 × 2 repeat, every tow alternates over and under."""
    return from_over_under([[1, 0], [0, 1]])


def twill(over: int, under: int) -> WeaveDescription:
    """over/under twill: W[i][j] = 1 if (j − i) mod (over + under) < over; square repeat."""
    if over < 1 or under < 1:
        raise ValueError(f"a twill needs over ≥ 1 and under ≥ 1, got {over}/{under}")
    n = over + under
    return from_over_under([[int((j - i) % n < over) for j in range(n)] for i in range(n)])


def valid_satin_moves(harness: int) -> list[int]:
    """Move numbers m giving a regular n-harness satin: 1 < m < n − 1 and gcd(m, n) = 1."""
    return [m for m in range(2, harness - 1) if math.gcd(m, harness) == 1]


def satin_move_problem(harness: int, move: int) -> str | None:
    """Why (harness, move) is not a regular satin, or None if it is."""
    if harness < 5:
        return f"a regular satin needs at least 5 harnesses, got {harness}" + (
            "; the 4-harness satin is the irregular crowfoot" if harness == 4 else ""
        )
    if move in valid_satin_moves(harness):
        return None
    rules = "1 < move < harness − 1 and gcd(move, harness) = 1"
    moves = valid_satin_moves(harness)
    valid = (
        f"valid moves: {', '.join(map(str, moves))}"
        if moves
        else f"no move gives a regular {harness}-harness satin"
    )
    return f"move {move} does not give a regular {harness}-harness satin ({rules}); {valid}"


def satin(harness: int, move: int) -> WeaveDescription:
    """Regular warp-faced n-harness satin: warp i is under only at weft (move·i) mod n."""
    problem = satin_move_problem(harness, move)
    if problem:
        raise ValueError(problem)
    return _one_under_per_row([(move * i) % harness for i in range(harness)])


def crowfoot() -> WeaveDescription:
    """Four-harness satin (crowfoot, paper Fig. 5): warp i under only at CROWFOOT_UNDER[i]."""
    return _one_under_per_row(list(CROWFOOT_UNDER))


def _one_under_per_row(under_at: list[int]) -> WeaveDescription:
    n = len(under_at)
    return from_over_under([[int(j != under_at[i]) for j in range(n)] for i in range(n)])


def basket(warp_group: int, weft_group: int) -> WeaveDescription:
    """Basket weave: a plain weave of groups of ``warp_group`` warp and ``weft_group`` weft
    tows working together; repeat 2·warp_group × 2·weft_group (1 × 1 is the plain weave)."""
    if warp_group < 1 or weft_group < 1:
        raise ValueError(f"basket groups must be ≥ 1, got {warp_group}x{weft_group}")
    return from_over_under(
        [
            [int((i // warp_group + j // weft_group) % 2 == 0) for j in range(2 * weft_group)]
            for i in range(2 * warp_group)
        ]
    )


def orthogonal_3d(stuffer_layers: int, weft_layers: int) -> WeaveDescription:
    """3D orthogonal weave: straight stuffers and weft layers, one binder per warp position
    passing vertically through the whole thickness, over the top at one weft column and under
    the bottom at the next (repeat 2 × 2)."""
    _check_3d_layers(stuffer_layers, weft_layers)
    return _interlock(stuffer_layers, weft_layers, depth=weft_layers, positions=[weft_layers, 0])


def angle_interlock_3d(
    stuffer_layers: int, weft_layers: int, binder_depth: int | None = None
) -> WeaveDescription:
    """Angle-interlock weave: binders step diagonally through ``binder_depth`` weft layers, one
    layer per weft column (repeat 2 × 2·depth). Depth = weft_layers (default) is the
    through-thickness angle interlock; a smaller depth needs weft_layers − depth + 1 binder
    levels, binder b running through weft layers b..b+depth−1, so every layer is held."""
    _check_3d_layers(stuffer_layers, weft_layers)
    depth = weft_layers if binder_depth is None else binder_depth
    if not 2 <= depth <= weft_layers:
        raise ValueError(
            f"binder depth must be between 2 and the number of weft layers ({weft_layers}), "
            f"got {depth}"
        )
    # The binder's height in its layer range: depth, depth−1, ..., 0, ..., depth−1.
    positions = [depth - k for k in range(depth + 1)] + list(range(1, depth))
    return _interlock(stuffer_layers, weft_layers, depth=depth, positions=positions)


def layer_to_layer_3d(stuffer_layers: int, weft_layers: int) -> WeaveDescription:
    """Layer-to-layer angle interlock: each binder ties two neighbouring weft layers."""
    return angle_interlock_3d(stuffer_layers, weft_layers, binder_depth=2)


def _check_3d_layers(stuffer_layers: int, weft_layers: int) -> None:
    if stuffer_layers < 0 or weft_layers < 1:
        raise ValueError(
            f"need stuffer_layers ≥ 0 and weft_layers ≥ 1, got {stuffer_layers}, {weft_layers}"
        )
    if stuffer_layers + weft_layers < 2:
        raise ValueError("a 3D weave needs more than two levels: add stuffer or weft layers")


def _interlock(
    stuffer_layers: int, weft_layers: int, depth: int, positions: list[int]
) -> WeaveDescription:
    """Binder b (0-based) runs through weft layers b..b+depth−1; ``positions[j]`` is how many
    of them lie below it at weft column j."""
    binders = weft_layers - depth + 1
    stuffer_ids = list(range(1, stuffer_layers + 1))
    binder_ids = list(range(stuffer_layers + 1, stuffer_layers + binders + 1))
    weft_ids = list(range(stuffer_layers + binders + 1, stuffer_layers + binders + weft_layers + 1))
    base: list[int] = []
    for k in range(max(stuffer_layers, weft_layers)):
        base += weft_ids[k : k + 1] + stuffer_ids[k : k + 1]
    period = len(positions)
    rows = []
    for i in range(2):
        row = []
        for j in range(period):
            p = positions[(j + i * period // 2) % period]
            stack = list(base)
            # Insert from the top binder down so earlier insertions do not move later targets.
            for b in reversed(range(binders)):
                below = b + p
                at = stack.index(weft_ids[below]) if below < weft_layers else len(stack)
                stack.insert(at, binder_ids[b])
            row.append(tuple(stack))
        rows.append(tuple(row))
    return WeaveDescription(
        warp_levels=stuffer_layers + binders,
        weft_levels=weft_layers,
        repeat_warp=2,
        repeat_weft=period,
        matrix=tuple(rows),
        binder_levels=tuple(binder_ids),
    )
