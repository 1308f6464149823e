"""Relaxing a net (beyond the paper) against truths: the analytic gradient against finite
differences, the shear field of ``cell_fields``, a plane's shear-free minimum, and the tows'
inextensibility on a dome."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.optimise.relax import cell_shear_and_gradient, relax_net
from preform.plugins.surfaces.basic import Hemisphere, Plane

R = 0.1
HEMI = Hemisphere(R)


class QuadraticLaw:
    locking_angle: float | None = math.radians(50.0)
    failure_angle: float | None = None

    def __init__(self, k_positive: float = 100.0, k_negative: float = 100.0) -> None:
        self.k_positive, self.k_negative = k_positive, k_negative

    def torque(self, gamma: object) -> np.ndarray:
        g = np.asarray(gamma, dtype=float)
        return np.where(g > 0, self.k_positive, self.k_negative) * g

    def energy(self, gamma: object) -> np.ndarray:
        g = np.asarray(gamma, dtype=float)
        return 0.5 * np.where(g > 0, self.k_positive, self.k_negative) * g * g


@pytest.fixture(scope="module")
def dome_drape():
    return drape(
        HEMI,
        node_spacing_m=0.01,
        ply=PlyOutline.rectangle((0.36, 0.36)),
        start_xy_m=(0.0, 0.0),
        generator_angle_rad=math.radians(80.0),
    )


def test_shear_is_the_drape_engines(dome_drape):
    nodes = np.where(np.isfinite(dome_drape.nodes), dome_drape.nodes, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        gamma, _ = cell_shear_and_gradient(nodes)
    ok = dome_drape.valid
    assert np.max(np.abs(gamma[ok] - dome_drape.shear[ok])) < 1e-14


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_shear_gradient_matches_finite_differences(seed):
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(np.arange(3.0), np.arange(3.0), indexing="ij"), axis=-1)
    nodes = np.concatenate([grid, np.zeros((3, 3, 1))], axis=-1) + 0.2 * rng.normal(size=(3, 3, 3))
    _, grads = cell_shear_and_gradient(nodes)
    # Node (1, 1) is corner 11 of cell (0, 0), 01 of (1, 0), 10 of (0, 1), 00 of (1, 1).
    owners = {(0, 0): 3, (1, 0): 2, (0, 1): 1, (1, 1): 0}
    h = 1e-6
    for k in range(3):
        step = np.zeros_like(nodes)
        step[1, 1, k] = h
        numeric = (
            cell_shear_and_gradient(nodes + step)[0] - cell_shear_and_gradient(nodes - step)[0]
        ) / (2 * h)
        for cell, corner in owners.items():
            assert grads[corner][cell][k] == pytest.approx(numeric[cell], abs=1e-6)


def test_plane_relaxes_to_the_unsheared_net():
    # On a plane the uniformly sheared net can unshear by its own mechanism: the minimum has
    # zero energy with every tow still at length d.
    plane = Plane((1.0, 1.0))
    d = 0.01
    sheared = drape(
        plane,
        node_spacing_m=d,
        ply=PlyOutline.rectangle((0.08, 0.08)),
        start_xy_m=(0.0, 0.0),
        generator_angle_rad=math.radians(70.0),
    )
    law = QuadraticLaw()
    relaxed = relax_net(sheared, plane, law)
    assert relaxed.kinematic_energy_J > 0
    assert relaxed.energy_J < 1e-4 * relaxed.kinematic_energy_J
    assert relaxed.max_edge_error_m < 1e-3 * d
    assert relaxed.max_shear_change_rad == pytest.approx(math.radians(20.0), abs=1e-3)
    assert relaxed.converged


@pytest.mark.parametrize("ratio", [1.0, 0.2])
def test_dome_relaxation_lowers_energy_keeping_tows_and_tool(dome_drape, ratio):
    law = QuadraticLaw(100.0, 100.0 * ratio)
    relaxed = relax_net(dome_drape, HEMI, law, max_rounds=4, max_iterations=200)
    assert relaxed.energy_J < relaxed.kinematic_energy_J
    assert 0.0 < relaxed.relative_saving < 0.5
    assert relaxed.max_edge_error_m < 1e-3 * dome_drape.node_spacing
    assert relaxed.max_surface_distance_m < 1e-12
    assert relaxed.rms_shear_change_rad > 0
    counted = relaxed.counted
    start = dome_drape.start_index
    np.testing.assert_array_equal(relaxed.nodes[start], dome_drape.nodes[start])
    assert np.all(np.isfinite(relaxed.shear[counted]))


def test_relax_refuses_an_empty_part(dome_drape):
    with pytest.raises(ValueError, match="no counted cells"):
        relax_net(dome_drape, HEMI, QuadraticLaw(), counted=np.zeros_like(dome_drape.valid))
