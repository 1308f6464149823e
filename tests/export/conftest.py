"""Synthetic draped nets and unit cells for the exporter tests.

The drape engine is built elsewhere; these nets are made directly from node positions so every
field (shear, centroid, area, fibre directions, statuses) is known exactly.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from preform.drape.engine.result import CellStatus, DrapeResult, EnergyField, NodeStatus
from preform.geometry.unit_cell import TowPath, UnitCell


def build_net(
    ni: int = 10,
    nj: int = 12,
    *,
    spacing: float = 0.005,
    generator_angle_deg: float = 90.0,
    start: tuple[int, int] | None = None,
    dome: bool = False,
    unplaced: list[tuple[int, int]] | None = None,
    folded: list[tuple[int, int]] | None = None,
    outside_part: list[tuple[int, int]] | None = None,
) -> DrapeResult:
    """A net of ni × nj nodes with spacing [m].

    Flat by default: u along x, v at ``generator_angle_deg`` from u (uniform shear α − 90°).
    ``dome`` bends and skews it so shear varies in sign and z is not constant. ``unplaced``
    nodes get OFF_TOOL (NaN position) and their cells INCOMPLETE; ``folded`` cells FOLDED;
    ``outside_part`` cells stay VALID but leave the part.
    """
    i0, j0 = start if start is not None else (ni // 2, nj // 2)
    alpha = np.radians(generator_angle_deg)
    u, v = np.meshgrid(
        (np.arange(ni) - i0) * spacing, (np.arange(nj) - j0) * spacing, indexing="ij"
    )
    x = u + v * np.cos(alpha)
    y = v * np.sin(alpha)
    z = np.zeros_like(x)
    if dome:
        size = spacing * max(ni, nj)
        x = x + 0.15 * y * np.sin(3 * u / size)
        z = 0.3 * size * np.exp(-(x**2 + y**2) / (0.5 * size) ** 2)
    nodes = np.stack([x, y, z], axis=-1)
    status = np.zeros((ni, nj), dtype=np.int8)
    for i, j in unplaced or []:
        status[i, j] = NodeStatus.OFF_TOOL
        nodes[i, j] = np.nan

    p00, p10, p11, p01 = nodes[:-1, :-1], nodes[1:, :-1], nodes[1:, 1:], nodes[:-1, 1:]
    eu, ev = p10 - p00, p01 - p00
    fibre_u = eu / np.linalg.norm(eu, axis=-1, keepdims=True)
    fibre_v = ev / np.linalg.norm(ev, axis=-1, keepdims=True)
    shear = np.arccos(np.clip(np.sum(fibre_u * fibre_v, axis=-1), -1, 1)) - np.pi / 2
    centroid = 0.25 * (p00 + p10 + p11 + p01)
    area = 0.5 * np.linalg.norm(np.cross(p11 - p00, p01 - p10), axis=-1)

    placed = status == NodeStatus.PLACED
    corners_placed = placed[:-1, :-1] & placed[1:, :-1] & placed[1:, 1:] & placed[:-1, 1:]
    cell_status = np.where(corners_placed, CellStatus.VALID, CellStatus.INCOMPLETE).astype(np.int8)
    for i, j in folded or []:
        cell_status[i, j] = CellStatus.FOLDED
    valid = cell_status == CellStatus.VALID
    in_part = valid.copy()
    for i, j in outside_part or []:
        in_part[i, j] = False
    # The contract: cell arrays are 0 (NaN for positions) where the cell is not VALID.
    shear = np.where(valid, shear, 0.0)
    area = np.where(valid, area, 0.0)
    centroid = np.where(valid[..., None], centroid, np.nan)
    fibre_u = np.where(valid[..., None], fibre_u, 0.0)
    fibre_v = np.where(valid[..., None], fibre_v, 0.0)
    return DrapeResult(
        nodes=nodes,
        status=status,
        residual=np.where(placed, 1e-12, np.nan),
        start_index=(i0, j0),
        node_spacing=spacing,
        generator_angle=float(alpha),
        orientation=0.0,
        cell_status=cell_status,
        shear=shear,
        centroid=centroid,
        area=area,
        fibre_u=fibre_u,
        fibre_v=fibre_v,
        in_part=in_part,
    )


def build_energy(
    result: DrapeResult,
    *,
    stiffness: float = 50.0,
    locking_deg: float = 10.0,
    failure_deg: float = 5.0,
) -> EnergyField:
    """W = k γ² [J/m²] on valid cells (k [J/m²/rad²]); locking at |γ|, failure at γ > 0."""
    valid = result.valid
    gamma = result.shear
    density = np.where(valid, stiffness * gamma**2, 0.0)
    return EnergyField(
        energy_density=density,
        thickness_ratio=np.where(valid, 1.0 / np.cos(gamma), 0.0),
        past_locking=valid & (np.abs(gamma) > np.radians(locking_deg)),
        past_failure=valid & (gamma > np.radians(failure_deg)),
        total_energy=float(np.sum(density[valid & result.in_part]) * result.node_spacing**2),
    )


def build_unit_cell(period: float = 0.008, samples: int = 17) -> UnitCell:
    """A plain-weave-like cell: two crimped warps (level 1), two wefts (level 2), one stitch."""
    s = np.linspace(0.0, period, samples)
    tows: list[TowPath] = []
    for k in range(2):
        offset = (k + 0.5) * period / 2
        crimp = 0.2e-3 * np.cos(2 * np.pi * s / period + k * np.pi)
        tows.append(
            TowPath(
                np.column_stack([s, np.full_like(s, offset), crimp]),
                3e-3,
                0.2e-3,
                "warp",
                1,
                "glass 600 tex",
            )
        )
        tows.append(
            TowPath(
                np.column_stack([np.full_like(s, offset), s, -crimp]),
                3.5e-3,
                0.2e-3,
                "weft",
                2,
                "glass 1200 tex",
            )
        )
    stitch = np.array([[0.0, 0.0, 0.4e-3], [0.0, 0.0, -0.4e-3], [period / 2, period, -0.4e-3]])
    tows.append(TowPath(stitch, 0.3e-3, 0.1e-3, "stitch", 3, "polyester"))
    return UnitCell(period=np.array([[period, 0.0], [0.0, period]]), tows=tuple(tows))


def turn_net(result: DrapeResult, angle_deg: float) -> DrapeResult:
    """``result`` turned by ``angle_deg`` about z (positions and fibre directions)."""
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return dataclasses.replace(
        result,
        nodes=result.nodes @ rot.T,
        centroid=result.centroid @ rot.T,
        fibre_u=result.fibre_u @ rot.T,
        fibre_v=result.fibre_v @ rot.T,
    )


def s8r_grid(
    nx: int, ny: int, place: Callable[[int, int], tuple[float, float, float]], elset: str
) -> tuple[list[str], Callable[[int, int], int]]:
    """``*NODE`` and ``*ELEMENT, TYPE=S8R`` lines of nx × ny quadratic shells (for ccx), and
    the node label of grid point (i, j), 0 ≤ i ≤ 2 nx, 0 ≤ j ≤ 2 ny (odd i and j together:
    an element's centre, no node). ``place(i, j)`` gives the node's position [mm]; elements
    are labelled 1, 2, ... row by row, corners counter-clockwise seen from +z."""

    def nid(i: int, j: int) -> int:
        return 1 + i + j * (2 * nx + 1)

    lines = ["*NODE"]
    for j in range(2 * ny + 1):
        for i in range(2 * nx + 1):
            if not (i % 2 and j % 2):
                lines.append(f"{nid(i, j)}, " + ", ".join(f"{v:.12g}" for v in place(i, j)))
    lines.append(f"*ELEMENT, TYPE=S8R, ELSET={elset}")
    for j in range(ny):
        for i in range(nx):
            i2, j2 = 2 * i, 2 * j
            corners = (nid(i2, j2), nid(i2 + 2, j2), nid(i2 + 2, j2 + 2), nid(i2, j2 + 2))
            mids = (nid(i2 + 1, j2), nid(i2 + 2, j2 + 1), nid(i2 + 1, j2 + 2), nid(i2, j2 + 1))
            lines.append(", ".join(str(n) for n in (1 + i + j * nx, *corners, *mids)))
    return lines, nid


@pytest.fixture(scope="session")
def quadratic_shells() -> Callable[..., tuple[list[str], Callable[[int, int], int]]]:
    return s8r_grid


@pytest.fixture
def make_net() -> Callable[..., DrapeResult]:
    return build_net


@pytest.fixture
def turned_net() -> Callable[[DrapeResult, float], DrapeResult]:
    return turn_net


@pytest.fixture
def make_energy() -> Callable[..., EnergyField]:
    return build_energy


@pytest.fixture
def unit_cell() -> UnitCell:
    return build_unit_cell()


@pytest.fixture
def damaged_net() -> DrapeResult:
    """A domed 10 × 12 net with two unplaced nodes, one folded cell and one cell out of the part."""
    return build_net(
        10, 12, dome=True, unplaced=[(0, 0), (9, 5)], folded=[(3, 3)], outside_part=[(4, 7)]
    )


def png_pixels(path: Any) -> np.ndarray:
    """The image at ``path`` as an (h, w, channels) float array."""
    from matplotlib import image

    return np.asarray(image.imread(path))


@pytest.fixture
def read_png() -> Callable[[Any], np.ndarray]:
    return png_pixels
