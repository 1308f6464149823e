"""The compiled queries of every analytic tool (issue 15) against the numpy queries they
replaced, frozen in ``benchmarks/numpy_surfaces.py`` (a second implementation, kept as the
benchmark's baseline): the same closest points, normals and distances on random points and
extremes, the same plate nodes, and the same drape through the compiled fill as through the
Python front loop with the numpy queries. The tools' independent truths (implicit equations,
dense samplings) are in ``tests/surfaces/test_domes.py`` and ``test_basic_surfaces.py``."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import preform.drape.engine.net as net_module
from preform.drape.engine.compiled_surface import CompiledQueries
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.drape.engine.result import NodeStatus
from preform.plugins.surfaces import basic, domes


def _frozen_numpy_tools() -> ModuleType:
    path = Path(__file__).resolve().parents[2] / "benchmarks" / "numpy_surfaces.py"
    spec = importlib.util.spec_from_file_location("numpy_surfaces", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


NUMPY = _frozen_numpy_tools()

#: name -> (class name, args, kwargs); each built from preform and from the frozen numpy copy.
TOOLS: dict[str, tuple[str, tuple[Any, ...], dict[str, Any]]] = {
    "plane": ("Plane", ((1.0, 0.8),), {"centre_m": (0.1, -0.2, 0.05)}),
    "cylinder-x": ("Cylinder", (0.3, 1.0, "x"), {"centre_m": (0.05, 0.1, -0.2)}),
    "cylinder-y": ("Cylinder", (0.3, 1.0, "y"), {}),
    "flanged-square": ("FlangedHemisphere", (0.1, 0.02, 0.2), {}),
    "flanged-disc": ("FlangedHemisphere", (0.1, 0.02, 0.2), {"flange_shape": "circle"}),
    "cone-sharp": ("Cone", (0.1, 0.08), {}),
    "cone-truncated": ("Cone", (0.1, 0.05), {"top_radius_m": 0.03}),
    "ellipsoid": ("EllipsoidDome", ((0.12, 0.08, 0.05),), {}),
    "ellipsoid-tied": ("EllipsoidDome", ((0.1, 0.06, 0.06),), {}),
    "spheroid": ("EllipsoidDome", ((0.1, 0.1, 0.1),), {}),
    "paraboloid": ("ParaboloidDome", (0.1, 0.06), {}),
    "paraboloid-steep": ("ParaboloidDome", (0.05, 0.2), {}),
}


def build(name: str) -> tuple[Any, Any]:
    """(compiled tool, the same tool with the frozen numpy queries)."""
    cls, args, kwargs = TOOLS[name]
    module = basic if cls in ("Plane", "Cylinder") else domes
    return getattr(module, cls)(*args, **kwargs), getattr(NUMPY, cls)(*args, **kwargs)


def test_every_analytic_tool_has_compiled_queries_and_the_frozen_copy_has_none() -> None:
    for name in TOOLS:
        tool, numpy_tool = build(name)
        assert isinstance(tool, CompiledQueries), name
        assert not isinstance(numpy_tool, CompiledQueries), name


class UnknownKind:
    """A plugin's tool that names a kind code the compiled queries do not have."""

    bounds = ((-1.0, -1.0, 0.0), (1.0, 1.0, 1.0))
    size = 1.0

    def compiled_queries(self) -> tuple[int, np.ndarray]:
        return 99, np.zeros(3)

    def closest_point(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return points, np.zeros(len(points))

    def normal(self, points: np.ndarray) -> np.ndarray:
        return np.tile([0.0, 0.0, 1.0], (len(points), 1))

    def point_at_plan(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.column_stack((xy, np.zeros(len(xy)))), np.ones(len(xy), dtype=bool)


def test_an_unknown_kind_is_refused_in_words_not_answered_with_nan() -> None:
    from preform.drape.engine.compiled_surface import query_tool

    with pytest.raises(ValueError, match=r"kind 99.*compiled_queries"):
        query_tool(UnknownKind(), np.zeros((1, 3)))
    with pytest.raises(ValueError, match=r"kind 99"):
        drape(
            UnknownKind(), start_xy_m=(0, 0), node_spacing_m=0.1, ply=PlyOutline.rectangle((1, 1))
        )  # type: ignore[arg-type]


#: Coordinates in units of the tool's half extent about its centre: anywhere out to three
#: extents, and the special values (the axis, the centre plane, subnormal offsets, the faces of
#: the bounding box, far away).
unit_coordinate = st.one_of(
    st.floats(-3.0, 3.0),
    st.sampled_from([0.0, -0.0, 5e-324, -1e-310, 1e-200, 1.0, -1.0, 0.5, 1e6, -1e6]),
)


def _points(tool: Any, units: list[tuple[float, float, float]]) -> np.ndarray:
    lo, hi = np.array(tool.bounds[0]), np.array(tool.bounds[1])
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    # the axis of the domes and cylinders exactly: a zero unit keeps the centre's coordinate
    return centre + half * np.array(units)


def _assert_same_queries(name: str, points: np.ndarray) -> None:
    tool, numpy_tool = build(name)
    scale = tool.size * max(1.0, float(np.max(np.abs(points))) / tool.size)
    foot, dist = tool.closest_point(points)
    normal = tool.normal(points)
    foot_np, dist_np = numpy_tool.closest_point(points)
    normal_np = numpy_tool.normal(points)
    assert foot.shape == points.shape and dist.shape == points.shape[:1]
    assert np.all(np.isfinite(foot)) and np.all(np.isfinite(normal))
    np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(points - foot, axis=1), dist, atol=1e-12 * scale)
    # The numpy queries are exact except from subnormal offsets off an axis (their squares
    # lose the offset's direction: normals off unit length, feet off the tool by ~1e-8; the
    # compiled ones scale those first). There the compiled answer must be a point of the
    # tool at least as near as numpy's foot put back onto the tool; elsewhere they agree.
    unit_np = np.abs(np.linalg.norm(normal_np, axis=1) - 1.0) < 1e-12
    np.testing.assert_allclose(dist[unit_np], dist_np[unit_np], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(tool.closest_point(foot)[1], 0.0, atol=1e-12 * scale)
    back_on_tool = tool.closest_point(foot_np[~unit_np])[0]
    bound = np.linalg.norm(points[~unit_np] - back_on_tool, axis=1)
    assert np.all(dist[~unit_np] <= bound + 1e-12 * scale)
    same_foot = np.linalg.norm(foot - foot_np, axis=1) <= 1e-12 * scale
    # Where two pieces of the tool are equally near (a tie to rounding) the two codes may pick
    # different ones: then the compiled answer must be an equally near point.
    check = ~same_foot & unit_np
    np.testing.assert_allclose(
        np.linalg.norm(points - foot, axis=1)[check], dist_np[check], atol=1e-12 * scale
    )
    check = same_foot & unit_np
    np.testing.assert_allclose(normal[check], normal_np[check], rtol=0, atol=1e-9)


@settings(max_examples=150, deadline=None)
@given(
    name=st.sampled_from(sorted(TOOLS)),
    units=st.lists(st.tuples(unit_coordinate, unit_coordinate, unit_coordinate), min_size=1),
)
# on the cylinder's axis but for a subnormal-squared offset: numpy's distance was 4e-9 short
@example(name="cylinder-y", units=[(0.0, 0.0, 1.4673264461635475e-158)])
def test_compiled_queries_match_the_numpy_queries(
    name: str, units: list[tuple[float, float, float]]
) -> None:
    tool, _ = build(name)
    _assert_same_queries(name, _points(tool, units))


@pytest.mark.parametrize("name", sorted(TOOLS))
def test_compiled_queries_match_the_numpy_queries_on_a_random_cloud(name: str) -> None:
    """20 000 points over three times the tool's extent, and its own surface points."""
    tool, _ = build(name)
    rng = np.random.default_rng(15)
    cloud = _points(tool, list(map(tuple, rng.uniform(-3.0, 3.0, (20_000, 3)))))
    _assert_same_queries(name, cloud)
    _assert_same_queries(name, tool.closest_point(cloud)[0])


@settings(max_examples=100, deadline=None)
@given(
    a=st.tuples(st.floats(-0.7, 0.7), st.floats(-0.6, 0.6)),
    chord_angle=st.floats(-math.pi, math.pi),
    chord=st.sampled_from([0.0, 0.05, 0.099, 0.1, 0.19, 0.2, 0.3]),
    opposite=st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)),
    vertical=st.booleans(),
)
def test_compiled_plate_nodes_match_the_numpy_closed_form(
    a: tuple[float, float],
    chord_angle: float,
    chord: float,
    opposite: tuple[float, float],
    vertical: bool,
) -> None:
    """Inside and past the plate, with no circle (chord ≥ 2d), a zero chord and a vertical one."""
    tool, numpy_tool = build("plane")
    z = tool.centre[2]
    pa = np.array([[a[0], a[1], z]])
    step = np.array([[math.cos(chord_angle), math.sin(chord_angle), 0.0]]) * chord
    pb = pa + (np.array([[0.0, 0.0, chord]]) if vertical else step)
    pc = np.array([[opposite[0], opposite[1], z]])
    d = 0.1
    p, status = tool.place_nodes(pa, pb, pc, d)
    p_np, status_np = numpy_tool.place_nodes(pa, pb, pc, d)
    np.testing.assert_array_equal(status, status_np)
    placed = status == NodeStatus.PLACED
    assert np.all(np.isnan(p[~placed]))
    np.testing.assert_allclose(p[placed], p_np[placed], rtol=0, atol=1e-15)


#: name -> (start xy [m], ply side [m]): plies larger than the tool, so the nets run over its
#: edges (the flange edge, the cone's rim, the domes' base), started on the cone's apex too.
DRAPES = {
    "plane": ((0.1, -0.15), 1.4),
    "cylinder-x": ((0.05, 0.1), 1.2),
    "flanged-square": ((0.0, 0.0), 0.5),
    "flanged-disc": ((0.01, 0.0), 0.5),
    "cone-sharp": ((0.0, 0.0), 0.3),
    "cone-truncated": ((0.004, -0.002), 0.3),
    "ellipsoid": ((0.0, 0.0), 0.3),
    "paraboloid": ((0.003, 0.0), 0.3),
}


@pytest.mark.parametrize(
    ("name", "closed_form"),
    [("plane", True), *((name, False) for name in sorted(DRAPES))],
    ids=lambda value: {True: "closed-form", False: "newton"}.get(value, value),
)
def test_compiled_fill_gives_the_net_of_the_numpy_path(
    name: str, closed_form: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The tool through the single compiled fill and the frozen numpy tool through the Python
    front loop: the same statuses (edges reached), nodes within 1e-9 d. The plate has a
    closed-form node too (the spheres' are in ``test_kernels.py``)."""
    tool, numpy_tool = build(name)
    start, side = DRAPES[name]
    n = 41
    d = side / (n - 1)
    kwargs: dict[str, Any] = dict(
        start_xy_m=start,
        node_spacing_m=d,
        ply=PlyOutline.rectangle((side, side)),
        orientation_rad=0.3,
        generator_angle_rad=1.45,
        use_closed_form=closed_form,
    )
    python_net = drape(numpy_tool, **kwargs)

    def no_python_loop(*args: Any, **kw: Any) -> Any:
        raise AssertionError("the compiled tool took the Python front loop")

    monkeypatch.setattr(net_module, "_fill_fronts_python", no_python_loop)
    compiled_net = drape(tool, **kwargs)
    assert compiled_net.info["placement"] == python_net.info["placement"]
    np.testing.assert_array_equal(compiled_net.status, python_net.status)
    assert {NodeStatus.PLACED, NodeStatus.OFF_TOOL} <= set(np.unique(compiled_net.status))
    placed = compiled_net.status == NodeStatus.PLACED
    np.testing.assert_allclose(
        compiled_net.nodes[placed], python_net.nodes[placed], rtol=0, atol=1e-9 * d
    )
    assert compiled_net.info["fronts"] == python_net.info["fronts"]
