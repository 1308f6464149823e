"""Hostile drapes: results that are wrong must not be reported ``ok`` (issue 10, item 10).

Each test runs the real steps with a real ``CaseContext`` and asserts what the case says about
itself: the ``CaseFailure`` message, ``ctx.partial_reasons`` with the covered fraction, or the
warnings in words, each checked against an independent count where there is a number. A last
group checks that a complete drape stays quiet (no partial reason: the checks do not cry wolf).
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pytest
from pydantic import BaseModel, ConfigDict

from preform.base.status import CaseFailure
from preform.drape.engine.fields import cell_fields
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.drape.engine.result import CellStatus, NodeStatus
from preform.drape.judging.verdict import (
    coverage,
    dependency_shadow,
    flat_plan_positions,
    generator_stops_on_tool,
    plan_positions_at,
)
from preform.pipeline.planner import plan
from preform.pipeline.scene import load_scene
from preform.plugin_manager import hookimpl
from preform.plugins.surfaces.basic import Hemisphere, Plane
from preform.plugins.surfaces.mesh import tessellate_hemisphere, write_stl
from preform.step import CaseContext
from preform.testing import PluginSandbox

# --------------------------------------------------------------------------------------------
# A toy shear law that goes non-finite past an angle, registered as a third-party plugin.


class BrokenParams(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)
    law: Literal["broken"]
    #: |γ| [deg] past which the law misbehaves (0: everywhere but γ = 0).
    above_deg: float = 0.0
    #: What it returns there.
    returns: Literal["nan", "inf", "huge"] = "nan"


class BrokenLaw:
    """W = γ² (J/m²) up to ``above``, then NaN, +inf or 1e308 per cell (sum overflows)."""

    locking_angle = None
    failure_angle = None

    def __init__(self, above_rad: float, returns: str) -> None:
        self.above = above_rad
        self.bad = {"nan": math.nan, "inf": math.inf, "huge": 1e308}[returns]

    def torque(self, gamma: Any) -> Any:
        g = np.asarray(gamma, dtype=float)
        return np.where(np.abs(g) > self.above, self.bad, 2.0 * g)

    def energy(self, gamma: Any) -> Any:
        g = np.asarray(gamma, dtype=float)
        return np.where(np.abs(g) > self.above, self.bad, g * g)


def build_broken(params: BrokenParams, fabric: Any) -> BrokenLaw:
    return BrokenLaw(math.radians(params.above_deg), params.returns)


class BrokenLawPlugin:
    @hookimpl
    def preform_register_shear_laws(self, register: Any) -> None:
        register.add("broken", BrokenParams, build_broken)


WEAVE = """\
- name: {name}
  architecture: woven
  source: test
  note: a plain weave with a toy law
  weave: {{pattern: plain}}
  tow_types:
    glass: {{fibre: glass, linear_density_tex: 1190, width_mm: 3.1, height_mm: 0.35}}
  warp: {{tow_spacing_mm: 4.0, tow_type: glass}}
  weft: {{tow_spacing_mm: 4.0, tow_type: glass}}
  shear_law: {law}
"""

HEMISPHERE = """\
name: {name}
tool:
  surface: hemisphere
  radius_mm: 100
ply:
  node_spacing_mm: {spacing}
  size_mm: [360, 360]
start:
  point_mm: [0, 0]
  generator_angle_deg: {alpha}
outputs: {outputs}
"""


@pytest.fixture
def sandbox(preform_plugins: PluginSandbox) -> PluginSandbox:
    preform_plugins.load_builtins()
    preform_plugins.register(BrokenLawPlugin(), name="broken-law")
    return preform_plugins


@pytest.fixture
def bundled(sandbox: PluginSandbox) -> Any:
    return sandbox.library(bundled=True)


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def broken_library(sandbox: PluginSandbox, tmp_path: Path, law: str) -> Any:
    path = write(tmp_path / "fabrics.yaml", WEAVE.format(name="broken-weave", law=law))
    return sandbox.library([path])


def context(sandbox: PluginSandbox, lib: Any, name: str, scene_path: Path) -> CaseContext:
    scene, _ = load_scene(scene_path, sandbox.registry)
    case_dir = scene_path.parent / "case"
    case_dir.mkdir(exist_ok=True)
    return CaseContext(
        fabric=lib.fabric(name), scene=scene, registry=sandbox.registry, case_dir=case_dir
    )


def run(ctx: CaseContext) -> CaseContext:
    """Every planned step in order, as the runner does."""
    for step in plan(ctx.scene, ctx.registry):
        ctx.products.update(step.run(ctx))
    return ctx


def hemisphere_scene(
    tmp_path: Path,
    *,
    spacing: float = 10,
    alpha: float = 90,
    outputs: str = "[drape]",
    name: str = "dome",
) -> Path:
    text = HEMISPHERE.format(name=name, spacing=spacing, alpha=alpha, outputs=outputs)
    return write(tmp_path / f"{name}.yaml", text)


SEARCH = """\
search:
  generator_angle_deg: {{min: {lo}, max: {hi}}}
"""


def search_scene(
    tmp_path: Path,
    *,
    lo: float = 30,
    hi: float = 150,
    spacing: float = 10,
    outputs: str = "[energy_vs_angle, optimum, drape]",
) -> Path:
    text = HEMISPHERE.format(name="search", spacing=spacing, alpha=90, outputs=outputs).replace(
        "  generator_angle_deg: 90\n", ""
    )
    return write(tmp_path / "search.yaml", text + SEARCH.format(lo=lo, hi=hi))


# --------------------------------------------------------------------------------------------
# Non-finite laws fail, with the angle, and leave no file behind


@pytest.mark.parametrize("returns, word", [("nan", "NaN"), ("inf", "+inf")])
@pytest.mark.parametrize("scene_kind", ["drape", "search", "shear_curve"])
def test_a_non_finite_law_fails_the_case_with_the_angle(
    sandbox: PluginSandbox, tmp_path: Path, returns: str, word: str, scene_kind: str
) -> None:
    lib = broken_library(sandbox, tmp_path, f"{{law: broken, returns: {returns}}}")
    if scene_kind == "drape":
        path = hemisphere_scene(tmp_path, outputs="[drape, cells_csv, vtu]")
    elif scene_kind == "search":
        path = search_scene(tmp_path)
    else:
        path = write(tmp_path / "shear.yaml", "name: shear\noutputs: [shear_curve_json]\n")
    ctx = context(sandbox, lib, "broken-weave", path)
    with pytest.raises(CaseFailure) as info:
        run(ctx)
    message = str(info.value)
    if scene_kind == "shear_curve":
        assert re.search(r"the shear law returned a non-finite (energy|torque|force) ", message)
    else:
        assert f"the shear law returned {word} at γ = " in message
    # Nothing that looks like a result was written.
    assert not any(ctx.case_dir.iterdir()), list(ctx.case_dir.iterdir())


def test_the_failing_angle_is_the_cells(sandbox: PluginSandbox, tmp_path: Path) -> None:
    """A law that breaks past 30° fails a drape whose cells reach ~45°, naming a γ past 30°."""
    lib = broken_library(sandbox, tmp_path, "{law: broken, above_deg: 30}")
    ctx = context(sandbox, lib, "broken-weave", hemisphere_scene(tmp_path))
    with pytest.raises(CaseFailure) as info:
        run(ctx)
    found = re.search(r"at γ = (-?[\d.]+)°", str(info.value))
    assert found is not None and abs(float(found.group(1))) > 30.0
    assert "total energy is not finite" in str(info.value)


def test_a_sum_that_overflows_is_not_finite(sandbox: PluginSandbox, tmp_path: Path) -> None:
    lib = broken_library(sandbox, tmp_path, "{law: broken, above_deg: 5, returns: huge}")
    ctx = context(sandbox, lib, "broken-weave", hemisphere_scene(tmp_path))
    with pytest.raises(CaseFailure, match=r"^total energy is not finite \(inf J\)"):
        run(ctx)


def test_a_finite_law_past_its_break_angle_is_fine(sandbox: PluginSandbox, tmp_path: Path) -> None:
    """The same toy law, breaking only past 80° (never reached at α = 90°), passes."""
    lib = broken_library(sandbox, tmp_path, "{law: broken, above_deg: 80}")
    ctx = run(context(sandbox, lib, "broken-weave", hemisphere_scene(tmp_path)))
    assert math.isfinite(ctx.summary["total_energy_J"]) and ctx.partial_reasons == []


def test_the_vtu_writer_refuses_non_finite_cells(bundled: Any, tmp_path: Path) -> None:
    from preform.drape.engine.fields import energy_field
    from preform.export.vtu import write_drape_vtu

    surface = Plane((0.1, 0.1))
    result = drape(
        surface, node_spacing_m=0.01, ply=PlyOutline.rectangle((0.05, 0.05)), start_xy_m=(0.0, 0.0)
    )
    energy = energy_field(result, BrokenLaw(-1.0, "nan"))
    with pytest.raises(ValueError, match="non-finite values in energy_J_per_m2"):
        write_drape_vtu(result, energy, tmp_path / "x.vtu")
    assert not (tmp_path / "x.vtu").exists()


# --------------------------------------------------------------------------------------------
# A net without a cell fails; a start that cannot be placed fails


@pytest.fixture
def dome_stl(tmp_path: Path) -> Path:
    """A 10 mm hemisphere as a mesh: its size is unknown to scene validation."""
    path = tmp_path / "dome.stl"
    write_stl(path, tessellate_hemisphere(0.010, 8))
    return path


MESH_SCENE = """\
name: mesh-dome
tool:
  surface: mesh
  file: dome.stl
ply:
  node_spacing_mm: {spacing}
  size_mm: [{ply}, {ply}]
start:
  point_mm: [{x}, 0]
outputs: [drape, cells_csv]
"""


@pytest.mark.parametrize("spacing", [25.0, 60.0, 120.0])
def test_a_spacing_larger_than_the_tool_fails(
    sandbox: PluginSandbox, bundled: Any, dome_stl: Path, spacing: float
) -> None:
    path = write(dome_stl.parent / "s.yaml", MESH_SCENE.format(spacing=spacing, ply=300, x=0))
    ctx = context(sandbox, bundled, "plain-weave-150", path)
    with pytest.raises(CaseFailure) as info:
        run(ctx)
    message = str(info.value)
    assert message.startswith("the drape has no cell (")
    assert f"at node spacing {spacing:g} mm the net does not fit on the tool" in message
    assert "use a node spacing well below the tool's size" in message
    assert not (ctx.case_dir / "cells.csv").exists()


def test_a_start_off_a_mesh_tool_fails_at_run_time(
    sandbox: PluginSandbox, bundled: Any, dome_stl: Path
) -> None:
    path = write(dome_stl.parent / "s.yaml", MESH_SCENE.format(spacing=2, ply=30, x=50))
    ctx = context(sandbox, bundled, "plain-weave-150", path)
    with pytest.raises(CaseFailure, match=r"^the drape cannot start: the start point"):
        run(ctx)


def test_a_preset_spacing_over_the_node_limit_fails_before_allocating(
    sandbox: PluginSandbox, bundled: Any, dome_stl: Path
) -> None:
    text = MESH_SCENE.format(spacing=1, ply=100000, x=0).replace("  node_spacing_mm: 1\n", "")
    path = write(dome_stl.parent / "s.yaml", text)
    ctx = context(sandbox, bundled, "plain-weave-150", path)
    with pytest.raises(CaseFailure, match=r"more than limits\.max_nodes = 20,000,000"):
        run(ctx)


# --------------------------------------------------------------------------------------------
# The hat mould: partial, with the covered fraction checked against an independent count

HAT = """\
name: hat
tool:
  surface: mesh
  file: hat_mould.obj
ply:
  node_spacing_mm: {spacing}
  size_mm: [360, 360]
start:
  point_mm: [4, 3]
  generator_angle_deg: {alpha}
outputs: [drape]
"""


@pytest.mark.parametrize("spacing, alpha", [(10, 90), (10, 70), (7.5, 90)])
def test_the_hat_mould_is_partial_with_its_covered_fraction(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path, spacing: float, alpha: float
) -> None:
    path = write(tmp_path / "hat.yaml", HAT.format(spacing=spacing, alpha=alpha))
    ctx = run(context(sandbox, bundled, "plain-weave-150", path))
    (reason,) = [r for r in ctx.partial_reasons if r.startswith("the net covers")]
    # the cells sheared towards ±90° behind the block's rounded corners are past jamming: when
    # they carry most of the energy, that is said as a second reason (issue 24)
    wrinkle = [r for r in ctx.partial_reasons if r != reason]
    assert len(wrinkle) == int(ctx.summary["wrinkling"]["mostly_wrinkle"])
    assert all(r.startswith("the drape would wrinkle") for r in wrinkle)
    result = ctx.products["drape"].result

    # Independent count: the mould's plan is the 300 × 200 mm plate; a node's undeformed plan
    # position is the start plus its flat offsets along the generators. Every unplaced node of
    # the ply over the plate is missing (inside the plate's outline the net meets no true edge
    # of this tool: it folds at the block's four corners, and their shadows are lost), and a
    # cell is asked for when it is valid or has such a corner.
    ni, nj = result.shape
    i0, j0 = result.start_index
    a = math.radians(alpha)
    ii, jj = np.meshgrid(np.arange(ni) - i0, np.arange(nj) - j0, indexing="ij")
    x = 4.0 + spacing * (ii + jj * math.cos(a))
    y = 3.0 + spacing * (jj * math.sin(a))
    over = (np.abs(x) < 150) & (np.abs(y) < 100)
    missing = over & (result.status != NodeStatus.PLACED)
    valid = result.cell_status == CellStatus.VALID
    corner = missing[:-1, :-1] | missing[1:, :-1] | missing[:-1, 1:] | missing[1:, 1:]
    expected = np.count_nonzero(valid) / np.count_nonzero(valid | corner)

    assert ctx.summary["covered_fraction"] == pytest.approx(expected, abs=1e-12)
    # the cross-shaped band over the block and down its walls is placed; the corners' shadows
    # are not
    assert 0.3 < ctx.summary["covered_fraction"] < 0.8
    assert reason.startswith(f"the net covers {100 * expected:.1f} % of the ply's fabric area")
    assert "folded" in reason and "stopped on the tool" not in reason
    assert ctx.summary["nodes_missing"] == np.count_nonzero(missing)
    assert ctx.summary["complete"] is False
    # The uncovered fabric area by cause sums to the missing cells' d² each.
    by_cause = [v for k, v in ctx.summary.items() if k.startswith("uncovered_area_m2_")]
    lost_cells = np.count_nonzero((valid | corner) & ~valid)
    assert sum(by_cause) == pytest.approx(lost_cells * (spacing * 1e-3) ** 2, rel=1e-12)
    # nothing is lost to numerics: what is missing lies behind a fold
    assert ctx.summary["uncovered_area_m2_stopped_on_tool"] == 0
    assert ctx.summary["uncovered_area_m2_folded"] > 0


def test_the_hat_moulds_reason_names_the_folds(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    path = write(tmp_path / "hat.yaml", HAT.format(spacing=10, alpha=90))
    ctx = run(context(sandbox, bundled, "plain-weave-150", path))
    result = ctx.products["drape"].result
    folded = int(np.count_nonzero(result.status == NodeStatus.FOLDED))
    assert folded > 0
    assert f"{folded} node(s) folded (the net would turn over there" in ctx.partial_reasons[0]
    assert ctx.summary["nodes_missing_folded"] == folded


def test_a_notched_ply_is_partial_behind_the_outline() -> None:
    """An L-shaped ply on a plate: the arm the generators cannot reach is missing coverage."""
    surface = Plane((0.3, 0.3))
    # Start in the horizontal arm; the vertical arm sits past a notch of the outline.
    outline = PlyOutline.polygon(
        [[-0.05, -0.02], [0.1, -0.02], [0.1, 0.1], [0.06, 0.1], [0.06, 0.02], [-0.05, 0.02]]
    )
    result = drape(surface, node_spacing_m=0.01, ply=outline, start_xy_m=(0.0, 0.0))
    cover = coverage(result, surface, (0.0, 0.0))
    assert not cover.complete
    lost = result.status == NodeStatus.NOT_REACHED
    assert cover.missing_nodes["not_reached_behind_outline"] == np.count_nonzero(lost)
    assert "because the ply outline cuts a generator before them" in cover.reason()


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_the_dependency_shadow_is_the_rectangle_to_the_start(seed: int) -> None:
    rng = np.random.default_rng(seed)
    mask = rng.random((9, 7)) < 0.08
    start = (int(rng.integers(0, 9)), int(rng.integers(0, 7)))
    got = dependency_shadow(mask, start)
    i0, j0 = start
    for i in range(9):
        for j in range(7):
            rows = range(min(i, i0), max(i, i0) + 1)
            cols = range(min(j, j0), max(j, j0) + 1)
            assert got[i, j] == any(mask[r, c] for r in rows for c in cols)


def numpy_coverage(result: Any, surface: Any, start_xy: tuple[float, float]) -> dict[str, Any]:
    """The coverage's counts as whole-net numpy masks (the verdict's definitions, module
    docstring of ``preform.drape.judging.verdict``), a second implementation of the compiled passes."""
    status, start = result.status, result.start_index

    def shadow(mask: np.ndarray) -> np.ndarray:
        i0, j0 = start
        ii, jj = np.indices(mask.shape)
        out = np.zeros_like(mask)
        for i, j in zip(*np.nonzero(mask), strict=True):
            # every node whose rectangle to the start holds (i, j)
            out |= (
                (np.sign(ii - i0) * np.sign(i - i0) >= 0)
                & (abs(ii - i0) >= abs(i - i0))
                & (np.sign(jj - j0) * np.sign(j - j0) >= 0)
                & (abs(jj - j0) >= abs(j - j0))
            )
        return out

    placed, in_ply = status == NodeStatus.PLACED, status != NodeStatus.OUTSIDE_PLY
    stopped = generator_stops_on_tool(result, surface)
    past_edge = ~placed & in_ply & shadow((status == NodeStatus.OFF_TOOL) & ~stopped)
    failed = (status == NodeStatus.NO_INTERSECTION) | (status == NodeStatus.FOLDED) | stopped
    behind_failure, behind_outline = shadow(failed), shadow(~in_ply)
    lost = ~placed & in_ply & ~past_edge
    over = np.zeros(status.shape, dtype=bool)
    plan = flat_plan_positions(result, start_xy)
    if lost.any():
        over[lost] = surface.point_at_plan(plan[lost])[1]
    missing = lost & over
    not_reached = missing & (status == NodeStatus.NOT_REACHED)
    valid = result.cell_status == CellStatus.VALID
    in_ply_cells = result.cell_status != CellStatus.OUTSIDE_PLY

    def corner(m: np.ndarray) -> np.ndarray:
        return m[:-1, :-1] | m[1:, :-1] | m[:-1, 1:] | m[1:, 1:]

    asked = valid | (in_ply_cells & ~corner(past_edge) & corner(missing))
    left = asked & ~valid
    by_cause = []
    for node_mask in (
        lost & (status == NodeStatus.FOLDED),
        lost & (status == NodeStatus.NO_INTERSECTION),
        lost & stopped,
        missing & behind_failure,
        missing & behind_outline,
    ):
        mine = left & corner(node_mask)
        by_cause.append(int(np.count_nonzero(mine)))
        left &= ~mine
    fold = in_ply_cells & ~valid & ~corner(past_edge) & corner(lost & shadow(status == 3))
    return {
        "asked": int(np.count_nonzero(asked)),
        "covered": int(np.count_nonzero(valid)),
        "nodes": [
            int(np.count_nonzero(lost & stopped)),
            int(np.count_nonzero(lost & (status == NodeStatus.NO_INTERSECTION))),
            int(np.count_nonzero(lost & (status == NodeStatus.FOLDED))),
            int(np.count_nonzero(not_reached & behind_failure)),
            int(np.count_nonzero(not_reached & ~behind_failure & behind_outline)),
            int(np.count_nonzero(not_reached & ~behind_failure & ~behind_outline)),
        ],
        "overhang": int(np.count_nonzero(past_edge | (lost & ~over))),
        "missing": int(np.count_nonzero(missing)),
        "by_cause": by_cause,
        "other": int(np.count_nonzero(left)),
        "fold_cells": int(np.count_nonzero(fold)),
    }


@pytest.mark.parametrize("seed", range(6))
def test_coverage_counts_match_whole_net_masks(seed: int) -> None:
    """Random node statuses on a flat net (every failure kind, the outline, the overhang):
    the compiled coverage passes count what the verdict's masks count."""
    rng = np.random.default_rng(seed)
    surface = Plane((0.16, 0.12))
    start_xy = (0.01, -0.005)
    net = drape(surface, node_spacing_m=0.01, ply=PlyOutline.rectangle((0.2, 0.16)),
                start_xy_m=start_xy)  # fmt: skip
    codes = np.array([0, 1, 2, 3, 4, 5], dtype=np.int8)
    status = rng.choice(codes, size=net.status.shape, p=[0.8, 0.04, 0.04, 0.04, 0.04, 0.04])
    status = status.astype(np.int8)
    status[net.start_index] = NodeStatus.PLACED
    nodes = np.where((status == NodeStatus.PLACED)[..., None], net.nodes, np.nan)
    fields = cell_fields(nodes, status)
    result = dataclasses.replace(net, nodes=nodes, status=status, **fields)
    cover = coverage(result, surface, start_xy)
    truth = numpy_coverage(result, surface, start_xy)
    d2 = 0.01**2
    assert cover.cells_asked == truth["asked"]
    assert cover.cells_covered == truth["covered"]
    names = ["stopped_on_tool", "no_intersection", "folded"]
    names += ["not_reached_behind_failure", "not_reached_behind_outline"]
    assert [cover.missing_nodes[n] for n in names] == truth["nodes"][:5]
    assert cover.missing_nodes.get("not_reached_unexplained", 0) == truth["nodes"][5]
    assert cover.nodes_overhang == truth["overhang"]
    assert cover.nodes_missing == truth["missing"]
    causes = ["folded", "no_intersection", "stopped_on_tool", "behind_failure", "behind_outline"]
    assert [cover.uncovered_area_m2[c] / d2 for c in causes] == pytest.approx(truth["by_cause"])
    assert cover.uncovered_area_m2.get("other", 0.0) / d2 == pytest.approx(truth["other"])
    fold_area = sum(area for _, area in cover.fold_zones)
    assert fold_area / d2 == pytest.approx(truth["fold_cells"])
    assert truth["asked"] > truth["covered"] and sum(truth["by_cause"]) > 0


def test_plan_positions_at_some_nodes_are_those_of_the_whole_flat_ply() -> None:
    result = drape(
        Hemisphere(0.1),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.3, 0.2)),
        start_xy_m=(0.01, -0.02),
        orientation_rad=0.3,
        generator_angle_rad=1.3,
    )
    whole = flat_plan_positions(result, (0.01, -0.02))
    rng = np.random.default_rng(5)
    ii = rng.integers(0, result.shape[0], 40)
    jj = rng.integers(0, result.shape[1], 40)
    got = plan_positions_at(result, (0.01, -0.02), ii, jj)
    np.testing.assert_array_equal(got, whole[ii, jj])
    # and the plan geometry itself: a d step along +u is d along the orientation
    step = plan_positions_at(result, (0.0, 0.0), np.array([1]), np.array([0]))
    step -= plan_positions_at(result, (0.0, 0.0), np.array([0]), np.array([0]))
    np.testing.assert_allclose(step[0], 0.01 * np.array([np.cos(0.3), np.sin(0.3)]), atol=1e-15)


# --------------------------------------------------------------------------------------------
# Cells past the law's limits are counted and said in words


def _count(message: str) -> tuple[int, float]:
    found = re.match(r"(\d+) cells \(([\d.e+-]+) % of the part's draped area\)", message)
    assert found is not None, message
    return int(found.group(1)), float(found.group(2))


def _independent(result: Any, past: Any) -> tuple[int, float]:
    valid = result.valid & result.in_part
    # A cell cut by the part's edge counts by its share of area inside it (issue 11).
    area = np.asarray(result.area) * np.asarray(result.part_weight)
    return int(np.count_nonzero(past & valid)), 100 * area[past & valid].sum() / area[valid].sum()


@pytest.mark.parametrize(
    "fabric, alpha", [("plain-weave-600", 90), ("twill-2x2-glass", 60), ("satin-8hs-carbon", 75)]
)
def test_cells_past_locking_are_counted(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path, fabric: str, alpha: float
) -> None:
    ctx = run(context(sandbox, bundled, fabric, hemisphere_scene(tmp_path, alpha=alpha)))
    result, law = ctx.products["drape"].result, ctx.products["shear_law"]
    (message,) = [w for w in ctx.warnings if "locking angle" in w]
    count, percent = _count(message)
    want_count, want_percent = _independent(result, np.abs(result.shear) > law.locking_angle)
    assert count == want_count == ctx.summary["cells_past_locking"] and count > 0
    assert percent == pytest.approx(want_percent, abs=0.05)
    assert message.endswith(
        f"past the locking angle {math.degrees(law.locking_angle):.1f}°: its tows touch and "
        "compact there (stiffer; it wrinkles only past jamming)"
    )
    # locking alone never makes a case partial; mostly energy past jamming does (issue 24)
    wrinkle = ["the drape would wrinkle"] if ctx.summary["wrinkling"]["mostly_wrinkle"] else []
    assert [r[: len("the drape would wrinkle")] for r in ctx.partial_reasons] == wrinkle


def test_cells_past_stitch_failure_are_counted(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    ctx = run(context(sandbox, bundled, "E-BX-318", hemisphere_scene(tmp_path, alpha=120)))
    result, law = ctx.products["drape"].result, ctx.products["shear_law"]
    (message,) = [w for w in ctx.warnings if "stitch-failure" in w]
    count, percent = _count(message)
    want = _independent(result, result.shear > law.failure_angle)
    assert (count, percent) == (want[0], pytest.approx(want[1], abs=0.05)) and count > 0
    assert "35.0° (parallel to the stitch): the stitching would break there" in message


def test_cells_past_packing_are_said_to_be_unphysical(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    """Cells past the jamming angle carry the law's held torque, not a physical energy; the
    energy stays bounded (it was 1e8–1e9 J while the law followed the compaction pole)."""
    ctx = run(
        context(
            sandbox,
            bundled,
            "orthogonal-3d-glass",
            hemisphere_scene(tmp_path, spacing=2.5, alpha=30),
        )
    )
    result, law = ctx.products["drape"].result, ctx.products["shear_law"]
    assert 0 < ctx.summary["total_energy_J"] < 1e3
    (message,) = [w for w in ctx.warnings if "is jammed" in w]
    count, _ = _count(message)
    assert count == _independent(result, np.abs(result.shear) > law.packing_angle)[0] > 0
    assert f"past {math.degrees(law.packing_angle):.1f}°" in message
    assert "is not a physical energy" in message
    assert ctx.summary["cells_past_packing"] == count


def test_cells_beyond_the_laws_data_are_said(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    """The ncf polynomial is fitted to 60°; a drape at α = 30° shears cells to ~75°."""
    ctx = run(context(sandbox, bundled, "ncf-0-90-tricot", hemisphere_scene(tmp_path, alpha=30)))
    result = ctx.products["drape"].result
    (message,) = [w for w in ctx.warnings if "data range" in w]
    count, _ = _count(message)
    assert count == _independent(result, np.abs(result.shear) > math.radians(60.0))[0] > 0
    assert "(+60.0° / −60.0°), where the law holds the last measured value" in message


# --------------------------------------------------------------------------------------------
# The search says where it is not to be trusted


def test_an_optimum_at_the_range_end_is_said(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    ctx = run(context(sandbox, bundled, "plain-weave-150", search_scene(tmp_path, lo=40, hi=70)))
    assert ctx.summary["optimum_at_boundary"] is True
    (message,) = [w for w in ctx.warnings if "at an end of the searched range" in w]
    assert "[40°, 70°]" in message and "widen search.generator_angle_deg" in message


def test_search_angles_past_packing_are_named(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    ctx = run(context(sandbox, bundled, "orthogonal-3d-glass", search_scene(tmp_path, spacing=2.5)))
    study = ctx.products["energy_vs_angle"].search
    law = ctx.products["shear_law"]
    past = [p for p in study.points if p.max_abs_shear_rad > law.packing_angle]
    assert past and ctx.summary["search_angles_past_packing"] == len(past)
    (message,) = [w for w in ctx.warnings if "E(α) there" in w and "is jammed" in w]
    assert message.startswith(f"at generator angle(s) {past[0].generator_angle_deg:.4g}°")
    # The optimum itself is not affected: its drape is complete and its energy is small.
    assert ctx.partial_reasons == [] and ctx.summary["total_energy_J"] < 100


def test_a_noise_limited_search_says_so(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    ctx = run(context(sandbox, bundled, "plain-weave-150", search_scene(tmp_path)))
    search = ctx.products["energy_vs_angle"].search
    said = [w for w in ctx.warnings if "noise-limited" in w]
    assert bool(said) == search.noise_limited


# --------------------------------------------------------------------------------------------
# Complete drapes stay ok: no partial reason, covered fraction 1


@pytest.mark.parametrize("alpha", [45, 90, 135])
def test_a_complete_hemisphere_drape_has_no_partial_reason(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path, alpha: float
) -> None:
    ctx = run(context(sandbox, bundled, "plain-weave-150", hemisphere_scene(tmp_path, alpha=alpha)))
    assert ctx.partial_reasons == []
    assert ctx.summary["covered_fraction"] == 1.0 and ctx.summary["complete"] is True
    assert ctx.summary["nodes_missing"] == 0 and ctx.summary["nodes_overhang"] > 0


def test_the_bundled_hemisphere_scene_stays_ok(sandbox: PluginSandbox, bundled: Any) -> None:
    from preform.pipeline.scene import bundled_scene_dir

    scene, _ = load_scene(bundled_scene_dir() / "hemisphere.yaml", sandbox.registry)
    for fabric in ("plain-weave-150", "E-BX-318"):
        ctx = CaseContext(
            fabric=bundled.fabric(fabric),
            scene=scene,
            registry=sandbox.registry,
            case_dir=Path("/nonexistent"),
        )
        for step in plan(scene, sandbox.registry):
            if not step.writes_files:
                ctx.products.update(step.run(ctx))
        assert ctx.partial_reasons == [], ctx.partial_reasons
        assert ctx.summary["covered_fraction"] == 1.0


def test_a_mesh_hemisphere_drape_has_no_partial_reason(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    text = HEMISPHERE.format(name="m", spacing=10, alpha=80, outputs="[drape]").replace(
        "  surface: hemisphere\n  radius_mm: 100\n",
        "  surface: mesh\n  file: hemisphere_r100.stl\n",
    )
    ctx = run(context(sandbox, bundled, "plain-weave-150", write(tmp_path / "m.yaml", text)))
    assert ctx.partial_reasons == [] and ctx.summary["covered_fraction"] == 1.0


def test_a_complete_search_optimum_has_no_partial_reason(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    path = search_scene(tmp_path, outputs="[energy_vs_angle, optimum]")
    ctx = run(context(sandbox, bundled, "plain-weave-150", path))
    assert ctx.partial_reasons == []
    assert ctx.summary["optimum_covered_fraction"] == 1.0


def test_a_search_on_the_hat_mould_is_partial_without_a_drape_step(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    """A scene asking only for the optimum still learns that the drape there is partial."""
    text = HAT.format(spacing=10, alpha=90).replace("  generator_angle_deg: 90\n", "")
    text = text.replace("outputs: [drape]", "outputs: [optimum]")
    text += "search: {generator_angle_deg: {min: 70, max: 110}, scan_step_deg: 10}\n"
    ctx = run(context(sandbox, bundled, "plain-weave-150", write(tmp_path / "hs.yaml", text)))
    reason, *others = ctx.partial_reasons
    assert reason.startswith("the net covers ") and "folded" in reason
    # plain-weave-150's tows jam at 57° (issue 24): the block's corners shear past it
    assert all(r.startswith("the drape would wrinkle: ") for r in others)
    assert ctx.summary["covered_fraction"] == ctx.summary["optimum_covered_fraction"] < 1.0


TABULATED = (
    "{law: tabulated, angle_deg: [0, 20, 40], torque_N_per_m: [0, 0.5, 2.0], beyond_range: linear}"
)


def test_cells_beyond_a_tabulated_laws_last_point_are_said(
    sandbox: PluginSandbox, tmp_path: Path
) -> None:
    lib = broken_library(sandbox, tmp_path, TABULATED)
    ctx = run(context(sandbox, lib, "broken-weave", hemisphere_scene(tmp_path)))
    result = ctx.products["drape"].result
    (message,) = [w for w in ctx.warnings if "data range" in w]
    count, _ = _count(message)
    assert count == _independent(result, np.abs(result.shear) > math.radians(40.0))[0] > 0
    assert "(+40.0° / −40.0°), where the law continues the last tangent" in message
    assert ctx.summary["cells_outside_law_data"] == count


class RangedLaw(BrokenLaw):
    """A plugin law that states its own data range (negative end, positive end) [rad]."""

    data_range = (math.radians(10.0), math.radians(20.0))


def test_a_law_may_state_its_own_data_range(sandbox: PluginSandbox, tmp_path: Path) -> None:
    from preform.drape.engine.fields import energy_field
    from preform.drape.judging.verdict import law_range, shear_limit_notes
    from preform.plugins.surfaces.basic import Hemisphere

    law = RangedLaw(math.inf, "nan")
    result = drape(
        Hemisphere(0.1),
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.36, 0.36)),
        start_xy_m=(0.0, 0.0),
        generator_angle_rad=math.radians(70),
    )
    limits = law_range(law, {"max_angle_deg": 80})  # the law's own range wins over the block
    assert (limits.data_negative, limits.data_positive) == law.data_range
    notes, counts = shear_limit_notes(result, energy_field(result, law), limits)
    gamma = np.where(result.valid, result.shear, 0.0)
    want = np.count_nonzero((gamma > law.data_range[1]) | (gamma < -law.data_range[0]))
    assert counts["cells_outside_law_data"] == want > 0
    assert "(+20.0° / −10.0°)" in notes[0][0]


def test_a_warp_knit_past_its_fit_in_the_perpendicular_sense_is_said(
    sandbox: PluginSandbox, bundled: Any, tmp_path: Path
) -> None:
    """E-BX-318's stitch law is fitted to 60°; at α = 30° the perpendicular (γ < 0) shear of
    the drape passes −60°."""
    ctx = run(context(sandbox, bundled, "E-BX-318", hemisphere_scene(tmp_path, alpha=30)))
    result = ctx.products["drape"].result
    (message,) = [w for w in ctx.warnings if "data range" in w]
    # Counted in the part: the net now runs on below the rim, where cells are not the part's.
    gamma = np.where(result.valid & result.in_part, result.shear, 0.0)
    assert _count(message)[0] == np.count_nonzero(np.abs(gamma) > math.radians(60)) > 0
    assert np.count_nonzero(gamma < -math.radians(60)) > 0


def _tools() -> dict[str, Any]:
    from preform.plugins.surfaces.basic import Cylinder, Hemisphere
    from preform.plugins.surfaces.domes import EllipsoidDome, FlangedHemisphere, ParaboloidDome

    return {
        "hemisphere": Hemisphere(0.1),
        "plane": Plane((0.3, 0.2)),
        "cylinder": Cylinder(0.05, 0.3),
        "paraboloid": ParaboloidDome(0.1, 0.08),
        "ellipsoid": EllipsoidDome((0.12, 0.08, 0.06)),
        "flanged": FlangedHemisphere(0.1, 0.01, 0.15),
        "mesh-hemisphere": tessellate_hemisphere(0.1, 24),
    }


TOOLS = _tools()


@pytest.mark.parametrize("alpha", [45, 90, 135])
@pytest.mark.parametrize("tool", list(TOOLS))
def test_drapes_that_only_overhang_are_complete(tool: str, alpha: float) -> None:
    """No cry wolf: on smooth tools (analytic and meshed) a ply larger than the tool hangs over
    its edges, genuine OFF_TOOL nodes all of them, and the drape is complete."""
    surface = TOOLS[tool]
    start = (0.02, 0.01)
    result = drape(
        surface,
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.36, 0.36)),
        start_xy_m=start,
        orientation_rad=0.3,
        generator_angle_rad=math.radians(alpha),
    )
    cover = coverage(result, surface, start)
    assert cover.complete, cover.reason()
    assert cover.covered_fraction == 1.0 and cover.nodes_missing == 0
    assert np.count_nonzero(result.status == NodeStatus.OFF_TOOL) > 0
