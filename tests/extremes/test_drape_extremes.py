"""The drape at its edges: node spacing from a thousandth of the tool to larger than it, start
points at the pole, on the rim and off the tool, generator angles of 0.5° and 179.5°, vertical
walls (the hat mould), degenerate mesh triangles, tools in µm-to-km units, random scenes.

Why: these are the set-ups where a kinematic drape returns NaN nodes, folded cells or a crash
without a word (PHYSICS §6, "peer behaviour worth avoiding"). Every node must carry a status,
NaN exactly where it is not placed, placed nodes must meet their constraints to tolerance·d,
and the energy and JSON summary must stay finite.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape import DrapeError, NodeStatus, PlyOutline, drape, energy_field, summary
from preform.drape.engine.result import CellStatus, DrapeResult
from preform.plugins.surfaces.basic import Hemisphere
from preform.plugins.surfaces.mesh import TriangleMesh, read_obj
from preform.shear.laws import PolynomialParams, build_polynomial

HAT = Path(__file__).resolve().parents[2] / "materials" / "tools" / "hat_mould.obj"
LAW = build_polynomial(
    PolynomialParams(
        law="polynomial", force_coefficients_N_per_mm=[0.0, 1e-3, 1e-5], max_angle_deg=60.0
    )
)
TOLERANCE = 1e-9


def assert_honest(result: DrapeResult, tolerance: float = TOLERANCE) -> None:
    """The invariants every drape result keeps, whatever the set-up."""
    codes = {int(c) for c in NodeStatus}
    assert set(np.unique(result.status).tolist()) <= codes
    assert set(np.unique(result.cell_status).tolist()) <= {int(c) for c in CellStatus}
    placed = result.status == NodeStatus.PLACED
    assert np.array_equal(np.isnan(result.nodes).any(axis=-1), ~placed)
    assert np.all(np.isfinite(result.nodes[placed]))
    d = result.node_spacing
    assert np.all(result.residual[placed] <= tolerance * d * 10 + 1e-300), (
        float(result.residual[placed].max()) / d
    )
    valid = result.valid
    assert np.all(np.isfinite(result.shear)) and np.all(np.abs(result.shear[valid]) < math.pi / 2)
    assert np.all(np.isfinite(result.area)) and np.all(result.area[valid] > 0)
    energy = energy_field(result, LAW)
    assert np.all(np.isfinite(energy.energy_density)) and np.all(energy.energy_density >= 0)
    assert math.isfinite(energy.total_energy) and energy.total_energy >= 0
    assert np.all(np.isfinite(energy.thickness_ratio))
    text = json.dumps(summary(result, energy), allow_nan=False)
    assert summary(result, energy)["nodes_total"] == result.status.size, text


def hemi_drape(radius: float = 0.1, **kwargs: object) -> DrapeResult:
    settings_: dict[str, object] = {
        "node_spacing_m": radius / 10,
        "ply": PlyOutline.rectangle((3 * radius, 3 * radius)),
        "start_xy_m": (0.0, 0.0),
    }
    settings_.update(kwargs)
    return drape(Hemisphere(radius), **settings_)  # type: ignore[arg-type]


@pytest.mark.parametrize("closed_form", [True, False])
def test_scale_invariance_from_micrometres_to_kilometres(closed_form: bool) -> None:
    """The same scene at 1e-3, 1 and 1e3 times the size (d scaled too) gives the same shear
    to 1e-9 rad: no absolute tolerance hides anywhere."""
    shears, statuses = [], []
    for scale in (1e-3, 1.0, 1e3):
        result = drape(
            Hemisphere(0.1 * scale),
            node_spacing_m=0.02 * scale,
            ply=PlyOutline.rectangle((0.3 * scale, 0.3 * scale)),
            start_xy_m=(0.013 * scale, -0.021 * scale),
            orientation_rad=0.3,
            generator_angle_rad=1.2,
            use_closed_form=closed_form,
        )
        assert_honest(result)
        shears.append(result.shear)
        statuses.append(result.status)
    assert np.array_equal(statuses[0], statuses[1]) and np.array_equal(statuses[1], statuses[2])
    np.testing.assert_allclose(shears[0], shears[1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(shears[2], shears[1], rtol=0, atol=1e-9)


@pytest.mark.parametrize("spacing", [1e-4, 0.05, 0.19, 0.2, 0.5, 10.0], ids=lambda d: f"d={d}R/0.1")
def test_node_spacing_from_a_thousandth_of_the_tool_to_larger_than_it(spacing: float) -> None:
    """R = 0.1 m; d = R/1000 on a small ply, up to d ≫ diameter (only the start is placed)."""
    size = min(0.3, 200 * spacing)
    result = hemi_drape(node_spacing_m=spacing, ply=PlyOutline.rectangle((size, size)))
    assert_honest(result)
    assert result.status[result.start_index] == NodeStatus.PLACED
    if spacing > 0.2:  # a chord longer than the diameter: nothing but the start
        assert result.nodes_placed == 1


@pytest.mark.parametrize(
    ("xy", "orientation"),
    [
        ((0.0, 0.0), 0.0),  # the pole
        ((0.1, 0.0), math.pi / 2),  # on the rim, orientation along the rim
        ((0.0, -0.1), 0.0),
        ((0.0999999, 0.0), 0.0),  # a hair inside the rim, generator straight down the wall
        ((0.1 / math.sqrt(2), 0.1 / math.sqrt(2)), 3 * math.pi / 4),
    ],
)
def test_start_at_the_pole_and_on_the_rim(xy: tuple[float, float], orientation: float) -> None:
    result = hemi_drape(start_xy_m=xy, orientation_rad=orientation)
    assert_honest(result)
    assert result.status[result.start_index] == NodeStatus.PLACED


@pytest.mark.parametrize(
    ("xy", "orientation", "match"),
    # beside the tool and on the rim facing the wall: tests/drape/test_net.py
    [((float("nan"), 0.0), 0.0, "not over the tool")],
)
def test_start_off_the_tool_is_a_clear_error(
    xy: tuple[float, float], orientation: float, match: str
) -> None:
    with pytest.raises(DrapeError, match=match):
        hemi_drape(start_xy_m=xy, orientation_rad=orientation)


@pytest.mark.parametrize("alpha_deg", [0.5, 1e-6, 179.5, 180 - 1e-6])
@pytest.mark.parametrize("closed_form", [True, False])
def test_generator_angles_near_0_and_180(alpha_deg: float, closed_form: bool) -> None:
    result = hemi_drape(generator_angle_rad=math.radians(alpha_deg), use_closed_form=closed_form)
    assert_honest(result)
    # The start cell carries the generator shear α − 90° exactly.
    assert np.any(result.valid)


@pytest.mark.parametrize("alpha", [0.0, math.pi, -0.1, float("nan")])
def test_generator_angle_outside_0_180_is_refused(alpha: float) -> None:
    with pytest.raises(DrapeError, match="generator angle"):
        hemi_drape(generator_angle_rad=alpha)


@pytest.mark.parametrize(
    "xy",
    [(0.0, 0.0), (0.049999, 0.0), (0.05, 0.0), (0.1, 0.05), (-0.149, 0.099)],
    ids=["block top", "block edge", "wall top", "plate", "plate corner"],
)
def test_hat_mould_with_vertical_walls(xy: tuple[float, float]) -> None:
    """Starts on the block, at its edge and on the plate. A geodesic step onto a vertical
    wall divides by n·n' = 0; before the mesh answered NaN for non-finite queries the k-d tree
    raised ValueError out of the drape."""
    mould = read_obj(HAT)
    try:
        # geodesics cross the block's sharp edges by unfolding them; no division by n·n' = 0
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            result = drape(
                mould,
                node_spacing_m=0.01,
                ply=PlyOutline.rectangle((0.3, 0.2)),
                start_xy_m=xy,
                orientation_rad=0.0,
            )
    except DrapeError as exc:  # a start on the wall itself may be refused, in words
        assert "vertical" in str(exc)
        return
    assert_honest(result)


def test_mesh_with_degenerate_triangles_and_an_overhang() -> None:
    """A plate with a zero-area sliver and a duplicated vertex, plus an overhanging lip: the
    sliver is dropped with a warning, the drape stays honest, NaN queries answer NaN."""
    v = np.array(
        [
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],  # on the edge 2-3: triangle (2, 4, 3) has zero area
            [1.0, -1.0, 0.0],  # duplicate of vertex 1
            [1.0, -1.0, 0.3],  # lip rising from the edge x = 1 ...
            [1.0, 1.0, 0.3],
            [0.7, -1.0, 0.3],  # ... and folding back over the plate (an undercut)
            [0.7, 1.0, 0.3],
        ]
    )
    faces = np.array([[0, 5, 2], [0, 2, 3], [2, 4, 3], [1, 6, 7], [1, 7, 2], [6, 9, 7], [6, 8, 9]])
    with pytest.warns(UserWarning, match="degenerate"):
        mesh = TriangleMesh(v, faces)
    assert mesh.dropped_triangles == 1
    feet, dist = mesh.closest_point(np.array([[np.nan, 0.0, 0.0], [-0.5, 0.0, 1.0]]))
    assert np.all(np.isnan(feet[0])) and np.isnan(dist[0]) and dist[1] == pytest.approx(1.0)
    assert np.all(np.isnan(mesh.normal(np.array([[np.inf, 0.0, 0.0]]))))
    for closed_form in (True, False):
        result = drape(
            mesh,
            node_spacing_m=0.1,
            ply=PlyOutline.rectangle((1.8, 1.8)),
            start_xy_m=(-0.2, 0.0),
            use_closed_form=closed_form,
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            assert_honest(result)


@settings(max_examples=25, deadline=None)
@given(
    radius=st.sampled_from([1e-3, 0.1, 10.0]),
    spacing_ratio=st.floats(0.02, 0.8),
    start_r=st.floats(0.0, 1.0),
    start_phi=st.floats(-math.pi, math.pi),
    orientation=st.floats(-math.pi, math.pi),
    alpha_deg=st.floats(0.5, 179.5),
    ply_ratio=st.floats(0.1, 3.0),
    closed_form=st.booleans(),
)
def test_random_hemisphere_scenes(
    radius: float,
    spacing_ratio: float,
    start_r: float,
    start_phi: float,
    orientation: float,
    alpha_deg: float,
    ply_ratio: float,
    closed_form: bool,
) -> None:
    """Any scene the schema allows drapes honestly or is refused with a DrapeError."""
    d = spacing_ratio * radius
    xy = (start_r * radius * math.cos(start_phi), start_r * radius * math.sin(start_phi))
    ply = PlyOutline.rectangle((max(ply_ratio * radius, d), max(ply_ratio * radius, d)))
    try:
        result = hemi_drape(
            radius,
            node_spacing_m=d,
            ply=ply,
            start_xy_m=xy,
            orientation_rad=orientation,
            generator_angle_rad=math.radians(alpha_deg),
            use_closed_form=closed_form,
        )
    except DrapeError as exc:
        assert str(exc)
        return
    assert_honest(result)
