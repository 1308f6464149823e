"""Generated parts on every bundled tool: never ``ok`` with an empty or ill-defined part
(issue 25, items 4 and 5).

Random plan outlines (simple and self-crossing, from a coarse integer grid so that crossings and
touchings are exact) and random height cuts, with parts made empty on purpose (a cut above the
tool, an outline beside it, a cut and an outline that miss each other), are draped at a fixed
angle on a coarse net over each bundled tool. The truths are independent of the code under
test: shapely says whether an outline is a simple polygon of nonzero area, and a counted cell
of the part has a corner node inside it (its share comes from φ linear between the corners, so
a cell with no corner inside has none), which the test checks on the placed nodes with shapely
and the cut's height. So: an ill-defined outline must be refused at validation, and an ``ok``
case must have a placed node in the part, a finite energy and a coverage in (0, 1].
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import preform
from preform.pipeline.scene import SceneError

shapely = pytest.importorskip("shapely")

#: Every bundled tool, small (top heights in mm: plane 0, cylinder 100, others their height).
TOOLS: dict[str, dict[str, Any]] = {
    "plane": {"surface": "plane", "size_mm": [200, 200]},
    "hemisphere": {"surface": "hemisphere", "radius_mm": 100},
    "cylinder": {"surface": "cylinder", "radius_mm": 100, "length_mm": 200},
    "cone": {"surface": "cone", "base_radius_mm": 100, "height_mm": 80},
    "ellipsoid": {"surface": "ellipsoid", "semi_axes_mm": [100, 80, 60]},
    "paraboloid": {"surface": "paraboloid", "radius_mm": 100, "height_mm": 60},
    "mesh": {"surface": "mesh", "file": "dome.stl"},
}

#: Grid step [mm] of generated outline vertices; the net's node spacing [mm] (coarse).
GRID_MM = 20
SPACING_MM = 20

vertices = st.lists(
    st.tuples(st.integers(-8, 8), st.integers(-8, 8)).map(
        lambda p: (p[0] * GRID_MM, p[1] * GRID_MM)
    ),
    min_size=3,
    max_size=7,
)
#: Parts empty by construction: (z cut, outline) far from every tool above (tools reach
#: |x|, |y| ≤ 100 mm and z ≤ 100 mm; the hemisphere's rim and the others' bases are low, their
#: tops at the centre).
empty_parts = st.sampled_from(
    [
        {"z_min_mm": 400},
        {"plan_outline_mm": [[300, 300], [400, 300], [400, 400]]},
        # a high cut and an outline at the low rim: each selects something, together nothing
        {"z_min_mm": 59, "plan_outline_mm": [[90, -10], [99, -10], [99, 10], [90, 10]]},
    ]
)


def _part(z_min: int | None, outline: list[tuple[int, int]] | None) -> dict[str, Any]:
    part: dict[str, Any] = {}
    if z_min is not None:
        part["z_min_mm"] = z_min
    if outline is not None:
        part["plan_outline_mm"] = [list(p) for p in outline]
    return part or {"z_min_mm": -1000}


parts = st.one_of(
    st.builds(_part, st.one_of(st.none(), st.integers(-50, 120)), st.one_of(st.none(), vertices)),
    empty_parts,
)


@pytest.fixture(scope="module")
def dome_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from preform.plugins.surfaces.mesh import tessellate_hemisphere, write_stl

    folder = tmp_path_factory.mktemp("dome")
    write_stl(folder / "dome.stl", tessellate_hemisphere(0.1, 6))
    return folder


@pytest.fixture(scope="module")
def fabric() -> Any:
    return preform.fabric("plain-weave-150")


def _scene(tool: str, part: dict[str, Any]) -> dict[str, Any]:
    """A fixed-angle drape on a coarse net over ``tool``, made on ``part``."""
    return {
        "name": f"parts-{tool}",
        "tool": TOOLS[tool],
        "ply": {"node_spacing_mm": SPACING_MM, "size_mm": [300, 300]},
        "start": {"point_mm": [0, 0], "generator_angle_deg": 90},
        "part": part,
        "outputs": ["drape"],
    }


def _outline_is_region(outline: list[list[float]]) -> bool:
    polygon = shapely.Polygon(outline)
    return bool(polygon.is_valid and polygon.area > 0)


def _node_in_part(nodes: np.ndarray, part: dict[str, Any]) -> bool:
    """Whether a placed node lies in the part (independent of preform.drape.engine.part)."""
    pts = nodes.reshape(-1, 3)[np.all(np.isfinite(nodes.reshape(-1, 3)), axis=1)] * 1e3
    keep = np.ones(len(pts), dtype=bool)
    if "z_min_mm" in part:
        keep &= pts[:, 2] >= part["z_min_mm"] - 1e-9
    if "plan_outline_mm" in part:
        region = shapely.Polygon(part["plan_outline_mm"]).buffer(1e-9)
        keep &= shapely.covers(region, shapely.points(pts[:, :2]))
    return bool(keep.any())


@pytest.mark.parametrize("tool", sorted(TOOLS))
@settings(
    max_examples=10,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(part=parts)
def test_never_ok_with_an_empty_or_ill_defined_part(
    tool: str, part: dict[str, Any], dome_dir: Path, fabric: Any
) -> None:
    scene = _scene(tool, part)
    outline = part.get("plan_outline_mm")
    try:
        # a mapping's relative paths resolve against the current directory
        with pytest.MonkeyPatch.context() as mp:
            mp.chdir(dome_dir)
            run = preform.drape(fabric, scene)
    except SceneError as error:
        event("refused at validation")
        if outline is not None and not _outline_is_region(outline):
            assert "plan_outline_mm" in str(error)
        return
    assert outline is None or _outline_is_region(outline), "an ill-defined outline was draped"
    event(run.status)
    if run.status == "ok":
        nodes = run.products["drape"].result.nodes
        assert _node_in_part(nodes, part), f"ok with an empty part: {run.summary.get('part')}"
        assert math.isfinite(run.summary["total_energy_J"])
        assert 0.0 < run.summary["covered_fraction"] <= 1.0
    elif run.status == "failed":
        assert run.error


@pytest.mark.parametrize("tool", sorted(TOOLS))
@pytest.mark.parametrize(
    "part", [{"z_min_mm": 400}, {"plan_outline_mm": [[300, 300], [400, 300], [400, 400]]}]
)
def test_a_part_off_every_tool_is_never_ok(
    tool: str, part: dict[str, Any], dome_dir: Path, fabric: Any
) -> None:
    """The empty parts of the issue on each tool: refused (analytic tools, at validation, at
    the field) or failed with the reason (a mesh tool, only known once read and draped)."""
    scene = _scene(tool, part)
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(dome_dir)
        if tool == "mesh":
            run = preform.drape(fabric, scene)
            assert run.status == "failed"
            assert "selects nothing" in (run.error or "")
            return
        with pytest.raises(
            SceneError, match=r"part\.(z_min_mm|plan_outline_mm): .*selects nothing"
        ):
            preform.drape(fabric, scene)
