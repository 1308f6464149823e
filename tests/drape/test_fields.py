"""Cell fields and strain energy of a net, against hand-built nets and symmetry."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import ArrayLike

from preform.drape.engine.fields import cell_fields, cell_status, energy_field, summary
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.drape.engine.result import CellStatus, DrapeResult, NodeStatus
from preform.plugins.surfaces.basic import Hemisphere
from preform.shear.law import ShearLaw


class QuadraticLaw:
    """W = ½·k·γ² with a different stiffness in each sense (k_pos for γ > 0)."""

    def __init__(
        self,
        k_pos: float,
        k_neg: float,
        locking_angle: float | None = None,
        failure_angle: float | None = None,
    ) -> None:
        self.k_pos, self.k_neg = k_pos, k_neg
        self.locking_angle = locking_angle
        self.failure_angle = failure_angle

    def torque(self, gamma: ArrayLike) -> np.ndarray:
        g = np.asarray(gamma, dtype=float)
        return np.where(g > 0, self.k_pos, self.k_neg) * g

    def energy(self, gamma: ArrayLike) -> np.ndarray:
        g = np.asarray(gamma, dtype=float)
        return 0.5 * np.where(g > 0, self.k_pos, self.k_neg) * g * g


def flat_rhombus_net(omega: float, d: float, n: int = 4) -> np.ndarray:
    """Nodes a·d·e_u + b·d·e_v in a tilted plane, with ω between +u and +v."""
    e_u = np.array([1.0, 0.0, 0.0])
    e_v = np.array([np.cos(omega), np.sin(omega), 0.0])
    tilt = np.array([[1, 0, 0], [0, np.cos(0.4), -np.sin(0.4)], [0, np.sin(0.4), np.cos(0.4)]])
    a = np.arange(n)[:, None, None]
    b = np.arange(n)[None, :, None]
    return (d * (a * e_u + b * e_v)) @ tilt.T + np.array([0.3, -0.1, 2.0])


@pytest.mark.parametrize("omega_deg", [60.0, 90.0, 125.0])
def test_flat_rhombus_cells(omega_deg: float) -> None:
    omega, d = np.radians(omega_deg), 0.02
    nodes = flat_rhombus_net(omega, d)
    f = cell_fields(nodes, np.zeros(nodes.shape[:2], dtype=np.int8))
    gamma = omega - np.pi / 2
    np.testing.assert_allclose(f["shear"], gamma, atol=1e-13)
    np.testing.assert_allclose(f["area"], d * d * np.cos(gamma), rtol=1e-12)
    np.testing.assert_allclose(f["fibre_u"], np.broadcast_to(f["fibre_u"][0, 0], (3, 3, 3)))
    e_u = (nodes[1, 0] - nodes[0, 0]) / d
    e_v = (nodes[0, 1] - nodes[0, 0]) / d
    np.testing.assert_allclose(f["fibre_u"][1, 2], e_u, atol=1e-13)
    np.testing.assert_allclose(f["fibre_v"][2, 0], e_v, atol=1e-13)
    np.testing.assert_allclose(f["centroid"][0, 0], nodes[0, 0] + 0.5 * d * (e_u + e_v))
    # The sign convention: γ > 0 exactly when the cell lengthens along the reference
    # direction, the bisector of +u and −v (undeformed diagonal: √2·d).
    along_reference = np.linalg.norm(nodes[1, 0] - nodes[0, 1])
    stretch = along_reference - np.sqrt(2) * d
    assert np.sign(np.round(stretch / d, 12)) == np.sign(np.round(gamma, 12))


def test_skew_cell_shear_is_the_mean_of_its_corner_angles() -> None:
    nodes = np.array([[[0.0, 0.0, 0.0], [0.1, 1.0, 0.0]], [[1.0, 0.0, 0.0], [1.0, 1.1, 0.3]]])
    f = cell_fields(nodes, np.zeros((2, 2), dtype=np.int8))

    def angle(p: np.ndarray, q: np.ndarray) -> float:
        return float(np.arccos(p @ q / np.linalg.norm(p) / np.linalg.norm(q)))

    u0, u1 = nodes[1, 0] - nodes[0, 0], nodes[1, 1] - nodes[0, 1]
    v0, v1 = nodes[0, 1] - nodes[0, 0], nodes[1, 1] - nodes[1, 0]
    corners = [angle(u0, v0), angle(u0, v1), angle(u1, v0), angle(u1, v1)]
    assert f["shear"][0, 0] == pytest.approx(np.mean(corners) - np.pi / 2, abs=1e-14)
    # Area: the mean of the two triangulations.
    t1 = 0.5 * (
        np.linalg.norm(np.cross(u0, nodes[1, 1] - nodes[0, 0]))
        + np.linalg.norm(np.cross(nodes[1, 1] - nodes[0, 0], v0))
    )
    t2 = 0.5 * (np.linalg.norm(np.cross(u0, v0)) + np.linalg.norm(np.cross(u1, v1)))
    assert f["area"][0, 0] == pytest.approx(0.5 * (t1 + t2), rel=1e-14)


def test_cell_status_precedence() -> None:
    P, OFF, FOLD, OUT = (
        NodeStatus.PLACED,
        NodeStatus.OFF_TOOL,
        NodeStatus.FOLDED,
        NodeStatus.OUTSIDE_PLY,
    )
    status = np.array([[P, P, P, OUT], [P, P, FOLD, P], [P, OFF, P, P]], dtype=np.int8)
    expected = np.array(
        [
            [CellStatus.VALID, CellStatus.FOLDED, CellStatus.OUTSIDE_PLY],
            [CellStatus.INCOMPLETE, CellStatus.FOLDED, CellStatus.FOLDED],
        ],
        dtype=np.int8,
    )
    np.testing.assert_array_equal(cell_status(status), expected)
    nodes = np.where((status == P)[..., None], np.random.default_rng(0).random((3, 4, 3)), np.nan)
    f = cell_fields(nodes, status)
    bad = f["cell_status"] != CellStatus.VALID
    assert np.all(f["shear"][bad] == 0) and np.all(f["area"][bad] == 0)
    assert np.all(np.isnan(f["centroid"][bad])) and np.all(f["fibre_u"][bad] == 0)
    assert np.all(np.isfinite(f["shear"]))


def _result_from(nodes: np.ndarray, d: float, trim: object = None) -> DrapeResult:
    status = np.zeros(nodes.shape[:2], dtype=np.int8)
    return DrapeResult(
        nodes=nodes,
        status=status,
        residual=np.zeros(status.shape),
        start_index=(0, 0),
        node_spacing=d,
        generator_angle=0.0,
        orientation=0.0,
        **cell_fields(nodes, status, trim=trim),
    )


def test_energy_takes_the_signed_branch_and_flags_limits() -> None:
    d = 0.01
    law = QuadraticLaw(k_pos=10.0, k_neg=1.0, locking_angle=0.5, failure_angle=0.3)
    assert isinstance(law, ShearLaw)
    for omega, k in ((np.radians(120.0), 10.0), (np.radians(60.0), 1.0)):
        result = _result_from(flat_rhombus_net(omega, d), d)
        energy = energy_field(result, law)
        gamma = omega - np.pi / 2
        np.testing.assert_allclose(energy.energy_density, 0.5 * k * gamma**2, rtol=1e-12)
        assert energy.total_energy == pytest.approx(9 * 0.5 * k * gamma**2 * d * d, rel=1e-12)
        np.testing.assert_allclose(energy.thickness_ratio, 1 / np.cos(gamma), rtol=1e-12)
        assert energy.past_locking.all() == (abs(gamma) > 0.5)
        # Stitch failure only in the parallel sense (γ > 0).
        assert energy.past_failure.all() == (gamma > 0.3)
        assert not energy.past_failure.any() or gamma > 0


def test_a_law_failing_in_both_senses_flags_both() -> None:
    """A law with ``failure_angle_negative`` (stitch_yarn) flags cells sheared past it the
    perpendicular way too; without it only the parallel sense is flagged (above)."""
    d = 0.01
    law = QuadraticLaw(k_pos=10.0, k_neg=1.0, locking_angle=0.5, failure_angle=0.3)
    law.failure_angle_negative = 0.4  # type: ignore[attr-defined]
    for omega_deg, flagged in ((120.0, True), (60.0, True), (70.0, False), (100.0, False)):
        result = _result_from(flat_rhombus_net(np.radians(omega_deg), d), d)
        assert energy_field(result, law).past_failure.all() == flagged, omega_deg


def test_energy_region_and_trim() -> None:
    d = 0.01
    nodes = flat_rhombus_net(np.radians(70.0), d)
    law = QuadraticLaw(1.0, 1.0)
    full = energy_field(_result_from(nodes, d), law).total_energy
    mask = np.zeros((3, 3), dtype=bool)
    mask[0] = True
    assert energy_field(_result_from(nodes, d), law, region=mask).total_energy == pytest.approx(
        full / 3
    )
    x_split = float(np.median(_result_from(nodes, d).centroid[..., 0]))
    by_predicate = energy_field(
        _result_from(nodes, d), law, region=lambda c: c[:, 0] < x_split
    ).total_energy
    trimmed = _result_from(nodes, d, trim=lambda c: c[:, 0] < x_split)
    assert energy_field(trimmed, law).total_energy == pytest.approx(by_predicate)
    assert 0 < by_predicate < full
    assert summary(trimmed)["cells_in_part"] == int(trimmed.in_part.sum())


HEMI = Hemisphere(1.0)


def _hemisphere(alpha: float, d: float = 0.05) -> DrapeResult:
    return drape(
        HEMI,
        start_xy_m=(0.0, 0.0),
        node_spacing_m=d,
        ply=PlyOutline.rectangle((1.4, 1.4)),
        generator_angle_rad=alpha,
    )


def test_symmetric_law_energy_is_mirror_symmetric_at_right_angles() -> None:
    law = QuadraticLaw(3.0, 3.0)
    energy = energy_field(_hemisphere(np.pi / 2), law)
    np.testing.assert_allclose(energy.energy_density, energy.energy_density[::-1, :], rtol=1e-10)
    np.testing.assert_allclose(energy.energy_density, energy.energy_density[:, ::-1], rtol=1e-10)


def test_energy_against_generator_angle() -> None:
    """Symmetric law: E(α) = E(180° − α) (the mirrored net has mirrored shear), so 90° is a
    stationary point. A law cheaper for γ < 0 (shear perpendicular to the stitch) moves the
    optimum below 90°, as the paper found for warp-knits on a hemisphere."""
    symmetric = QuadraticLaw(1.0, 1.0)
    e = {a: energy_field(_hemisphere(np.radians(a)), symmetric).total_energy for a in (80, 90, 100)}
    assert e[80] == pytest.approx(e[100], rel=1e-10)
    assert e[90] < e[80]
    stitch = QuadraticLaw(k_pos=10.0, k_neg=1.0)
    e = {a: energy_field(_hemisphere(np.radians(a)), stitch).total_energy for a in (80, 90, 100)}
    assert e[80] < e[90] < e[100]


def test_summary_counts() -> None:
    result = drape(
        HEMI,
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.1,
        ply=PlyOutline.rectangle((3.0, 3.0)),
    )
    law = QuadraticLaw(1.0, 1.0, locking_angle=np.radians(30.0))
    energy = energy_field(result, law)
    s = summary(result, energy)
    assert s["nodes_total"] == result.status.size
    assert s["nodes_placed"] == result.nodes_placed
    assert sum(int(s[f"nodes_{c.name.lower()}"]) for c in NodeStatus) == s["nodes_total"]
    assert s["complete"] is False and s["nodes_off_tool"] > 0
    assert s["max_abs_shear_deg"] == pytest.approx(np.degrees(np.abs(result.shear).max()))
    assert s["total_energy_J"] == energy.total_energy
    assert s["cells_past_locking"] == int(energy.past_locking.sum()) > 0
    assert s["cells_past_failure"] == 0
