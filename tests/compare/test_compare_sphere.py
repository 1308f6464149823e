"""The comparison and the inverse search against an independent pin-jointed net on the
hemisphere (issue 28, "What must hold"), and the bundled example measurement it makes.

The net is written here, not taken from preform's engine.

Mack & Taylor's net in closed form: two geodesic generators (great circles) through the start,
nodes a chord d apart along them; every other node is the second point at chord d from its two
neighbours (i∓1, j) and (i, j∓1) on the sphere, the first being the diagonal node (i∓1, j∓1).
Points with |P| = R, |P − A| = |P − B| = d satisfy P·A = P·B = R² − d²/2, so P = c (A + B) +
e (A × B) with c = (R² − d²/2) / (R² + A·B) and e from |P| = R; the diagonal node is the root
with the other sign of e. The net stops at the sphere's equator plane z = floor.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.compare import SetUp, compare, explain, measurement
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.plugins.surfaces.basic import Hemisphere

ROOT = Path(__file__).resolve().parents[2]


def _lift(theta: float, normal: np.ndarray) -> np.ndarray:
    """The tangent direction at a point with ``normal`` whose plan projection is at ``theta``."""
    c, s = math.cos(theta), math.sin(theta)
    z = -(normal[0] * c + normal[1] * s) / normal[2]
    t = np.array([c, s, z])
    return t / np.linalg.norm(t)


def sphere_net(
    radius: float,
    spacing: float,
    half_count: int,
    start_xy: tuple[float, float],
    orientation: float,
    generator_angle: float,
    floor_z: float = 0.0,
) -> np.ndarray:
    """Nodes (2k+1, 2k+1, 3) [m] of the net, k = ``half_count``, start at index (k, k); NaN
    where the net leaves the sphere above ``floor_z``. Angles in radians."""
    x0, y0 = start_xy
    start = np.array([x0, y0, math.sqrt(radius**2 - x0**2 - y0**2)])
    normal = start / radius
    t_u = _lift(orientation, normal)
    t_v = math.cos(generator_angle) * t_u + math.sin(generator_angle) * np.cross(normal, t_u)
    step = 2.0 * math.asin(spacing / (2.0 * radius))  # arc angle of one chord
    n = 2 * half_count + 1
    nodes = np.full((n, n, 3), np.nan)
    k0 = half_count
    nodes[k0, k0] = start
    for direction, axis in ((t_u, 0), (-t_u, 0), (t_v, 1), (-t_v, 1)):
        sign = 1 if (direction @ (t_u if axis == 0 else t_v)) > 0 else -1
        for m in range(1, half_count + 1):
            a = m * step
            p = radius * (math.cos(a) * normal + math.sin(a) * direction)
            idx = [k0, k0]
            idx[axis] += sign * m
            nodes[idx[0], idx[1]] = p
    s = radius**2 - 0.5 * spacing**2
    for si in (1, -1):
        for sj in (1, -1):
            for m in range(1, half_count + 1):
                for q in range(1, half_count + 1):
                    i, j = k0 + si * m, k0 + sj * q
                    a, b = nodes[i - si, j], nodes[i, j - sj]
                    c_ = nodes[i - si, j - sj]
                    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
                        continue
                    axb = np.cross(a, b)
                    c = s / (radius**2 + a @ b)
                    e2 = (radius**2 - c * c * ((a + b) @ (a + b))) / (axb @ axb)
                    if e2 < 0:
                        continue
                    e_c = (c_ @ axb) / (axb @ axb)
                    p = c * (a + b) - math.copysign(math.sqrt(e2), e_c) * axb
                    if p[2] >= floor_z:
                        nodes[i, j] = p
    # generators below the floor leave the sphere too
    nodes[nodes[..., 2] < floor_z] = np.nan
    return nodes


def cell_samples(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Centroid (m, 3) [m], unit u and v fibre directions (m, 3) and cell indices (m, 2) of
    every complete cell: the u direction is the sum of its two u edges, as a chord
    average."""
    x00, x10 = nodes[:-1, :-1], nodes[1:, :-1]
    x01, x11 = nodes[:-1, 1:], nodes[1:, 1:]
    ok = np.all(np.isfinite(x00 + x10 + x01 + x11), axis=-1)
    centroid = 0.25 * (x00 + x10 + x01 + x11)
    u = (x10 - x00) + (x11 - x01)
    v = (x01 - x00) + (x11 - x10)
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return centroid[ok], u[ok], v[ok], np.argwhere(ok)


def tangent_angle_deg(points: np.ndarray, fibres: np.ndarray, reference=(1.0, 0.0, 0.0)):
    """In-plane angle [deg] of ``fibres`` at ``points`` on a sphere centred at the origin,
    from the reference direction projected into the tangent plane, signed about the outward
    (radial) normal, wrapped to (−90, 90] (a fibre is a line)."""
    n = points / np.linalg.norm(points, axis=1, keepdims=True)
    ref = np.broadcast_to(np.asarray(reference, dtype=float), points.shape)
    ref = ref - np.sum(ref * n, axis=1, keepdims=True) * n
    ref /= np.linalg.norm(ref, axis=1, keepdims=True)
    sin = np.sum(np.cross(ref, fibres) * n, axis=1)
    cos = np.sum(ref * fibres, axis=1)
    angle = np.degrees(np.arctan2(sin, cos))
    return 90.0 - np.mod(90.0 - angle, 180.0)


#: The bundled example measurement (docs/examples/measured_hemisphere.csv): the set-up of the
#: synthetic preform, how many points, the noise and the seed.
EXAMPLE = {
    "start_mm": (4.0, -3.0),
    "orientation_deg": 2.0,
    "generator_angle_deg": 86.0,
    "points": 200,
    "noise_deg": 1.5,
    "seed": 2026,
}


def example_csv() -> str:
    """The text of docs/examples/measured_hemisphere.csv: this module's net on the bundled
    hemisphere scene's tool (R = 100 mm, spacing 2.5 mm) at :data:`EXAMPLE`'s set-up, fibre
    angles at cell centres with Gaussian noise, rounded to 0.01 mm and 0.01°."""
    e = EXAMPLE
    radius, spacing = 0.1, 0.0025
    nodes = sphere_net(
        radius, spacing, 60, (e["start_mm"][0] * 1e-3, e["start_mm"][1] * 1e-3),
        math.radians(e["orientation_deg"]), math.radians(e["generator_angle_deg"]),
    )  # fmt: skip
    centre, u, v, _ = cell_samples(nodes)
    keep = centre[:, 2] > 0.005
    centre, u, v = centre[keep], u[keep], v[keep]
    rng = np.random.default_rng(e["seed"])
    pick = np.sort(rng.choice(len(centre), e["points"], replace=False))
    centre, u, v = centre[pick], u[pick], v[pick]
    angle_u = tangent_angle_deg(centre, u) + rng.normal(0.0, e["noise_deg"], len(pick))
    angle_v = tangent_angle_deg(centre, v) + rng.normal(0.0, e["noise_deg"], len(pick))
    lines = [
        "# preform example measurement: SYNTHETIC, not measured. Made by the independent",
        "# pin-jointed net of preform's tests (tests/compare/test_compare_sphere.py, example_csv) on the",
        "# bundled hemisphere scene's tool (R = 100 mm, node spacing 2.5 mm) with the start at",
        f"# ({e['start_mm'][0]:g}, {e['start_mm'][1]:g}) mm, orientation "
        f"{e['orientation_deg']:g} deg and generator angle {e['generator_angle_deg']:g} deg "
        "(the scene says",
        f"# (0, 0), 0 and 90), with {e['noise_deg']:g} deg Gaussian noise on every angle "
        f"(seed {e['seed']}).",
        "# Angles: in the tool's tangent plane from the reference direction, counter-clockwise",
        "# seen from outside; u is the first generator's fibre family.",
        "# reference_direction: 1 0 0",
        "x_mm,y_mm,z_mm,angle_u_deg,angle_v_deg,uncertainty_deg,region",
    ]
    for p, a, b in zip(centre * 1e3, angle_u, angle_v, strict=True):
        region = "crown" if p[2] > 70.0 else "flank"
        lines.append(
            f"{p[0]:.2f},{p[1]:.2f},{p[2]:.2f},{a:.2f},{b:.2f},{e['noise_deg']:g},{region}"
        )
    return "\n".join(lines) + "\n"


# -- the tests ---------------------------------------------------------------------------------

RADIUS, SPACING = 0.1, 0.005
HALF = 30  # nodes each side of the start: a 300 mm ply
TRUTH = SetUp(12.0, -7.0, 10.0, 75.0)
#: Where the search starts: 3 mm and 3° off in every parameter.
GUESS = SetUp(15.0, -4.0, 13.0, 78.0)
SETTINGS = {"node_spacing_m": SPACING, "ply": PlyOutline.rectangle((0.3, 0.3)),
            "generators": "geodesic"}  # fmt: skip
TOOL = Hemisphere(RADIUS, run_off_m=0.025)


def truth_cells() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres and fibres of the independent net's cells at :data:`TRUTH`, on the part above
    z = 20 mm (clear of the rim, where the ply leaves the tool)."""
    t = TRUTH
    nodes = sphere_net(RADIUS, SPACING, HALF, (t.start_x_mm * 1e-3, t.start_y_mm * 1e-3),
                       math.radians(t.orientation_deg), math.radians(t.generator_angle_deg))  # fmt: skip
    centre, u, v, _ = cell_samples(nodes)
    keep = centre[:, 2] > 0.02
    return centre[keep], u[keep], v[keep]


CELLS = truth_cells()


def sample(seed: int, count: int = 500, noise_deg: float = 0.0, angles: bool = False):
    """A measurement of ``count`` random cells of the net, each fibre angle with Gaussian
    noise ``noise_deg`` [deg] (its stated uncertainty), as vectors or in-plane angles."""
    centre, u, v = CELLS
    rng = np.random.default_rng(seed)
    pick = rng.choice(len(centre), count, replace=False)
    centre, u, v = centre[pick], u[pick], v[pick]
    normal = centre / np.linalg.norm(centre, axis=1, keepdims=True)

    def turned(vec: np.ndarray) -> np.ndarray:
        a = np.radians(rng.normal(0.0, noise_deg, count))[:, None] if noise_deg else 0.0
        return np.cos(a) * vec + np.sin(a) * np.cross(normal, vec)

    u, v = turned(u), turned(v)
    sigma = noise_deg or None
    if angles:
        return measurement(centre * 1e3, angle_u_deg=tangent_angle_deg(centre, u),
                           angle_v_deg=tangent_angle_deg(centre, v), uncertainty_deg=sigma)  # fmt: skip
    return measurement(centre * 1e3, direction_u=u, direction_v=v, uncertainty_deg=sigma)


def preform_net(s: SetUp):
    return drape(
        TOOL,
        start_xy_m=(s.start_x_mm * 1e-3, s.start_y_mm * 1e-3),
        orientation_rad=math.radians(s.orientation_deg),
        generator_angle_rad=math.radians(s.generator_angle_deg),
        **SETTINGS,
    )


TRUTH_NET = preform_net(TRUTH)


def test_the_independent_net_is_preforms_net():
    """The two nets agree node for node: the comparison below tests the comparison."""
    i0, j0 = TRUTH_NET.start_index
    t = TRUTH
    mine = sphere_net(RADIUS, SPACING, HALF, (t.start_x_mm * 1e-3, t.start_y_mm * 1e-3),
                      math.radians(t.orientation_deg), math.radians(t.generator_angle_deg))  # fmt: skip
    theirs = TRUTH_NET.nodes[i0 - HALF : i0 + HALF + 1, j0 - HALF : j0 + HALF + 1]
    both = np.isfinite(mine[..., 0]) & np.isfinite(theirs[..., 0])
    assert both.sum() > 2000
    assert np.max(np.abs(mine[both] - theirs[both])) < 1e-9


@pytest.mark.parametrize("angles", [False, True], ids=["vectors", "angles"])
def test_no_noise_compares_below_a_hundredth_of_a_degree(angles):
    found = compare(TRUTH_NET, sample(0, angles=angles), surface=TOOL)
    assert found.compared.all()
    for errors in (found.error_u_deg, found.error_v_deg, found.error_shear_deg):
        assert np.max(np.abs(errors)) < 0.01
    stats = found.statistics()
    assert stats["angle_count"] == 1000 and stats["angle_max_deg"] < 0.01


def test_a_wrong_setup_shows_as_errors():
    """The same measurement against a drape 3° off in generator angle: errors of degrees, so
    the comparison is not blind."""
    wrong = preform_net(TRUTH.with_values({"generator_angle_deg": 78.0}))
    found = compare(wrong, sample(0), surface=TOOL)
    assert found.statistics()["angle_rms_deg"] > 1.0
    # at the start the v fibres turn by the whole 3°, the u fibres not at all
    near = np.linalg.norm(found.point_mm[:, :2] - [12.0, -7.0], axis=1) < 8.0
    assert np.all(np.abs(found.error_v_deg[near] + 3.0) < 0.6)
    assert np.all(np.abs(found.error_u_deg[near]) < 0.6)


@settings(max_examples=25, deadline=None)
@given(turn=st.floats(-85.0, 85.0), seed=st.integers(0, 10**6))
def test_a_turned_measurement_reads_as_that_angle(turn, seed):
    """Turning every measured u fibre by δ in the tangent plane gives an error of δ, and the
    shear error −δ (the angle between the fibres closes by δ) while the turned fibres still
    cross the v fibres at an angle in (0°, 180°) (lines: past that the shear is another's)."""
    centre, u, v = CELLS
    pick = np.random.default_rng(seed).choice(len(centre), 40, replace=False)
    c, u, v = centre[pick], u[pick], v[pick]
    n = c / np.linalg.norm(c, axis=1, keepdims=True)
    a = math.radians(turn)
    turned = math.cos(a) * u + math.sin(a) * np.cross(n, u)
    found = compare(TRUTH_NET, measurement(c * 1e3, direction_u=turned, direction_v=v),
                    surface=TOOL)  # fmt: skip
    assert np.allclose(found.error_u_deg, turn, atol=0.01)
    assert np.allclose(found.error_v_deg, 0.0, atol=0.01)
    omega = 90.0 + found.predicted_shear_deg  # the untouched angle between the fibres
    still = (omega - turn > 1.0) & (omega - turn < 179.0)
    assert np.allclose(found.error_shear_deg[still], -turn, atol=0.02)


def test_the_search_recovers_the_setup_without_noise():
    e = explain(sample(1), TOOL, SETTINGS, GUESS)
    assert abs(e.best.generator_angle_deg - TRUTH.generator_angle_deg) < 0.05
    assert abs(e.best.orientation_deg - TRUTH.orientation_deg) < 0.05
    assert math.hypot(e.best.start_x_mm - TRUTH.start_x_mm,
                      e.best.start_y_mm - TRUTH.start_y_mm) < 0.1  # fmt: skip
    assert e.after.statistics()["angle_max_deg"] < 0.01
    assert e.before.statistics()["angle_rms_deg"] > 1.0
    assert e.explained


def noisy_trial(seed: int) -> tuple[float, float, float]:
    """(error of the recovered generator angle [deg], its standard uncertainty [deg], s²) of
    one trial with 2° noise on 500 points."""
    e = explain(sample(seed, noise_deg=2.0), TOOL, SETTINGS, GUESS)
    sigma = e.sigma["generator_angle_deg"]
    assert sigma is not None
    return e.best.generator_angle_deg - TRUTH.generator_angle_deg, sigma, e.chi2_reduced


def test_the_search_with_noise_quick():
    """One trial of the slow test below: the error within three standard uncertainties, the
    uncertainty the data give (2°/√1000 per angle, spread over four parameters), s² near 1."""
    error, sigma, chi2 = noisy_trial(100)
    assert 0.1 < sigma < 0.3
    assert abs(error) < 3 * sigma
    assert 0.8 < chi2 < 1.3


@pytest.mark.slow
def test_the_search_with_noise_fifty_trials():
    """50 seeded trials with 2° noise on 500 points: the 95 % interval (±1.96 σ) covers the
    true generator angle in at least 90 % of them, and the angle is recovered to 0.3° rms.

    Measured (2026-12): σ ≈ 0.19° every trial (what 1000 angles of 2° scatter determine of
    four parameters); the interval covered the truth in 47 of 50, the error rms was 0.19° and
    44 of 50 trials came within 0.3° (largest 0.46°): the rms over the trials is the
    recovery the issue's 0.3° asks for, a single trial misses it about one time in eight."""
    trials = np.array([noisy_trial(seed) for seed in range(50)])
    error, sigma, chi2 = trials.T
    covered = np.abs(error) <= 1.96 * sigma
    assert covered.mean() >= 0.9
    assert math.sqrt(np.mean(error**2)) < 0.3
    assert np.mean(np.abs(error) < 0.3) >= 0.8
    assert 0.9 < np.mean(chi2) < 1.2


def test_the_bundled_example_is_this_nets():
    """docs/examples/measured_hemisphere.csv is what :func:`example_csv` writes."""
    bundled = (ROOT / "docs" / "examples" / "measured_hemisphere.csv").read_text()
    assert bundled == example_csv()
