"""The comparison and the inverse search on the hat mould (a mesh with vertical walls) against
preform's own drape at a shifted start (issue 28, "What must hold")."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from preform.compare import SetUp, compare, explain, measurement
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.drape.engine.result import NodeStatus
from preform.plugins.surfaces.mesh import read_obj

HAT = read_obj(
    Path(__file__).resolve().parents[2] / "materials" / "tools" / "hat_mould.obj",
    units_to_m=1e-3,
)
SETTINGS = {"node_spacing_m": 0.005, "ply": PlyOutline.rectangle((0.26, 0.18)),
            "generators": "geodesic"}  # fmt: skip
#: The measured preform: laid 3 mm and 2 mm off the scene's start (0, 0), at 80°.
TRUTH = SetUp(3.0, -2.0, 0.0, 80.0)
SCENE = SetUp(0.0, 0.0, 0.0, 80.0)


def net(s: SetUp):
    return drape(
        HAT,
        start_xy_m=(s.start_x_mm * 1e-3, s.start_y_mm * 1e-3),
        orientation_rad=math.radians(s.orientation_deg),
        generator_angle_rad=math.radians(s.generator_angle_deg),
        **SETTINGS,
    )


TRUTH_NET = net(TRUTH)


def measured(count: int = 500, seed: int = 0):
    """Fibres at the centres of ``count`` cells of the true drape that lie, with their
    neighbours, on one face of the mould: where a sensor reads a face, not an edge."""
    r = TRUTH_NET
    ni, nj = r.shape
    placed = np.all(np.isfinite(r.nodes), axis=-1)
    normal = np.full((ni, nj, 3), np.nan)
    normal[placed] = HAT.normal(r.nodes[placed])
    flat = np.zeros((ni - 1, nj - 1), dtype=bool)
    for i in range(1, ni - 2):
        for j in range(1, nj - 2):
            block = normal[i - 1 : i + 3, j - 1 : j + 3].reshape(-1, 3)
            flat[i, j] = bool(
                r.valid[i - 1 : i + 2, j - 1 : j + 2].all()
                and np.all(np.isfinite(block))
                and np.all(block @ block[0] > 1 - 1e-9)
            )
    cells = np.argwhere(flat)
    pick = cells[np.random.default_rng(seed).choice(len(cells), count, replace=False)]
    i, j = pick[:, 0], pick[:, 1]
    return measurement(r.centroid[i, j] * 1e3, direction_u=r.fibre_u[i, j],
                       direction_v=r.fibre_v[i, j])  # fmt: skip


MEASURED = measured()


def test_no_shift_compares_below_a_hundredth_of_a_degree():
    found = compare(TRUTH_NET, MEASURED, surface=HAT)
    assert found.compared.all()
    assert found.statistics()["angle_max_deg"] < 0.01
    assert np.nanmax(np.abs(found.error_shear_deg)) < 0.01
    # walls and plate are measured too, not only the block's top
    z = found.point_mm[:, 2]
    assert np.any(z < 1.0) and np.any((z > 5.0) & (z < 35.0)) and np.any(z > 39.0)


def test_the_scenes_start_is_seen_to_be_off():
    found = compare(net(SCENE), MEASURED, surface=HAT)
    assert found.statistics()["angle_rms_deg"] > 3.0


def test_the_search_recovers_a_generator_angle_quick():
    """The quick version: the start known, the generator angle searched from 2° off."""
    e = explain(MEASURED, HAT, SETTINGS, TRUTH.with_values({"generator_angle_deg": 82.0}),
                vary=("generator_angle",))  # fmt: skip
    assert abs(e.best.generator_angle_deg - TRUTH.generator_angle_deg) < 0.05
    assert e.after.statistics()["angle_max_deg"] < 0.01


@pytest.mark.slow
def test_the_search_recovers_the_shifted_start():
    e = explain(MEASURED, HAT, SETTINGS, SCENE)
    assert math.hypot(e.best.start_x_mm - 3.0, e.best.start_y_mm + 2.0) < 0.1
    assert abs(e.best.generator_angle_deg - TRUTH.generator_angle_deg) < 0.05
    assert abs(e.best.orientation_deg - TRUTH.orientation_deg) < 0.05
    assert e.after.statistics()["angle_max_deg"] < 0.01
    assert e.explained


def test_points_beside_a_fold_are_flagged():
    """Where the net folds at the mould's walls, the points on the cells around the failed
    nodes and the fabric lost behind them (not reached) are flagged near_fold; points three
    cells or more from all of those are not."""
    r = TRUTH_NET
    cells = np.argwhere(r.valid)
    found = compare(r, measurement(r.centroid[cells[:, 0], cells[:, 1]] * 1e3,
                                   direction_u=r.fibre_u[cells[:, 0], cells[:, 1]]),
                    surface=HAT)  # fmt: skip
    mapped = found.compared & (found.cell_i == cells[:, 0]) & (found.cell_j == cells[:, 1])

    def cells_from(nodes: np.ndarray) -> np.ndarray:
        """Each cell's distance to the nearest of ``nodes`` (k, 2), in nodes beyond its
        corners (its corners are i..i+1, j..j+1)."""
        di = np.maximum(
            nodes[None, :, 0] - cells[:, None, 0] - 1, cells[:, None, 0] - nodes[None, :, 0]
        )
        dj = np.maximum(
            nodes[None, :, 1] - cells[:, None, 1] - 1, cells[:, None, 1] - nodes[None, :, 1]
        )
        return np.min(np.maximum(di, dj), axis=1)  # fmt: skip

    failed = np.argwhere(np.isin(r.status, (NodeStatus.FOLDED, NodeStatus.NO_INTERSECTION)))
    lost = np.argwhere(np.isin(r.status, (NodeStatus.FOLDED, NodeStatus.NO_INTERSECTION,
                                          NodeStatus.NOT_REACHED)))  # fmt: skip
    assert len(failed)
    beside = (cells_from(failed) == 1) & mapped  # a corner next to a failed node
    assert beside.any() and found.near_fold[beside].all()
    assert not found.near_fold[cells_from(lost) >= 3].any()
    assert found.summary()["points_near_fold"] == int(found.near_fold.sum())
