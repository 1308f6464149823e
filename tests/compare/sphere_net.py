"""An independent pin-jointed net on a sphere, written for the tests (not preform's engine).

Mack & Taylor's net in closed form: two geodesic generators (great circles) through the start,
nodes a chord d apart along them; every other node is the second point at chord d from its two
neighbours (i∓1, j) and (i, j∓1) on the sphere, the first being the diagonal node (i∓1, j∓1).
Points with |P| = R, |P − A| = |P − B| = d satisfy P·A = P·B = R² − d²/2, so P = c (A + B) +
e (A × B) with c = (R² − d²/2) / (R² + A·B) and e from |P| = R; the diagonal node is the root
with the other sign of e. The net stops at the sphere's equator plane z = floor.
"""

from __future__ import annotations

import math

import numpy as np


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
        "# pin-jointed net of preform's tests (tests/compare/sphere_net.py, example_csv) on the",
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
