"""Mesh tools against the analytic sphere: drape speed, and a least-energy study's wall time.

Two ratios, each measured in one run against its baseline (issue 12's goals: both within 3x):

1. Drape speed. The same net (R = 100 mm hemisphere, 2.4 R square ply, alpha = 80 deg) draped on
   the analytic ``Hemisphere`` (closed-form placement and great circles) and on
   ``tessellate_hemisphere`` meshes (exact walking placement and straightest geodesics on the
   facets, ``preform.plugins.surfaces.mesh_kernels``). Node spacings giving about 1e5 and 1e6
   nodes. The mesh's one-off topology build is timed separately from the drape.
2. A least-energy study (generator-angle search, 30-150 deg, the default scan and refinement)
   of the bundled plain-weave-600 on the bundled hat mould against the same study on the
   analytic hemisphere, at the same number of nodes.

Best of ``--repeat`` runs, one core (pinned before numpy loads); the numba kernels are
compiled (or loaded from the cache) before any timing.

    python benchmarks/bench_mesh.py [--repeat 3] [--divisions 80 160] [--large]
        [--feature-angle 180]
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from preform.drape.engine.net import drape  # noqa: E402
from preform.drape.engine.ply import PlyOutline  # noqa: E402
from preform.library import load_library  # noqa: E402
from preform.optimise.search import DrapeObjective, search_generator_angle  # noqa: E402
from preform.plugins.surfaces.basic import Hemisphere  # noqa: E402
from preform.plugins.surfaces.mesh import (  # noqa: E402
    DEFAULT_FEATURE_ANGLE_DEG,
    TriangleMesh,
    read_obj,
    tessellate_hemisphere,
)

RADIUS = 0.1
ALPHA = math.radians(80.0)
PLY = PlyOutline.rectangle((2.4 * RADIUS, 2.4 * RADIUS))
HAT = Path(__file__).resolve().parents[1] / "materials" / "tools" / "hat_mould.obj"


def best(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    times, out = [], None
    for _ in range(repeat):
        clock = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - clock)
    return min(times), out


def drape_on(surface: Any, spacing: float) -> Any:
    return drape(
        surface,
        node_spacing_m=spacing,
        ply=PLY,
        start_xy_m=(0.0, 0.0),
        generator_angle_rad=ALPHA,
    )


def drape_speed(
    repeat: int, divisions: list[int], spacings: list[float], feature_angle_deg: float
) -> None:
    sphere = Hemisphere(RADIUS)
    print("\n(1) Drape speed: mesh hemisphere vs analytic hemisphere, same net, one core")
    print(
        f"{'triangles':>10}{'d mm':>7}{'nodes':>10}{'placed':>10}{'build s':>9}"
        f"{'sphere s':>10}{'mesh s':>9}{'ratio':>7}{'Mnodes/s':>10}{'max dshear deg':>16}"
    )
    for n in divisions:
        clock = time.perf_counter()
        mesh = tessellate_hemisphere(RADIUS, n)
        mesh = TriangleMesh(mesh.vertices, mesh.faces, feature_angle_deg=feature_angle_deg)
        _ = mesh.walker
        build = time.perf_counter() - clock
        drape_on(mesh, 0.02)  # compile or load the kernels, outside the timing
        for d in spacings:
            t_sphere, exact = best(lambda d=d: drape_on(sphere, d), repeat)
            t_mesh, approx = best(lambda d=d, m=mesh: drape_on(m, d), repeat)
            both = exact.valid & approx.valid
            dshear = float(np.degrees(np.max(np.abs(exact.shear - approx.shear)[both])))
            print(
                f"{mesh.n_triangles:>10}{1e3 * d:>7.3g}{approx.nodes_total:>10}"
                f"{approx.nodes_placed:>10}{build:>9.2f}{t_sphere:>10.3f}{t_mesh:>9.3f}"
                f"{t_mesh / t_sphere:>7.2f}{approx.nodes_placed / t_mesh / 1e6:>10.2f}"
                f"{dshear:>16.3f}"
            )


def study(repeat: int, spacing: float, feature_angle_deg: float) -> None:
    law = load_library().shear_law("plain-weave-600")
    hat = read_obj(HAT, feature_angle_deg=feature_angle_deg)
    sphere = Hemisphere(RADIUS, run_off_m=RADIUS / 4)
    ply = PlyOutline.rectangle((0.36, 0.36))
    print(
        "\n(2) Least-energy study (angle search 30-150 deg), plain-weave-600, "
        f"d = {spacing * 1e3:g} mm"
    )
    print(f"{'tool':>14}{'nodes':>8}{'drapes':>8}{'wall s':>8}{'ratio':>7}{'optimum deg':>13}")
    rows = []
    for name, tool, start in (
        ("hemisphere", sphere, (0.0, 0.0)),
        ("hat mould", hat, (0.004, 0.003)),
    ):
        objective = DrapeObjective(tool, law, node_spacing_m=spacing, ply=ply, start_xy_m=start)
        search_generator_angle(objective)  # warm: kernels compiled, mesh topology built
        wall, found = best(lambda o=objective: search_generator_angle(o), repeat)
        nodes = int(np.prod(ply.grid_shape(spacing)))
        rows.append((name, nodes, objective.drapes // (repeat + 1), found, wall))
    base = rows[0][4]
    for name, nodes, drapes, found, wall in rows:
        print(
            f"{name:>14}{nodes:>8}{drapes:>8}{wall:>8.2f}{wall / base:>7.2f}"
            f"{math.degrees(found.optimum_angle_rad):>13.2f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--divisions", type=int, nargs="+", default=[80, 160])
    parser.add_argument("--large", action="store_true", help="also d giving ~1e6 nodes")
    parser.add_argument(
        "--feature-angle",
        type=float,
        default=DEFAULT_FEATURE_ANGLE_DEG,
        help="the meshes' feature_angle_deg [deg] (docs/physics.md, 'Sharp creases')",
    )
    args = parser.parse_args()
    spacings = [7.6e-4] + ([2.4e-4] if args.large else [])
    drape_speed(args.repeat, args.divisions, spacings, args.feature_angle)
    study(args.repeat, 2.5e-3, args.feature_angle)


if __name__ == "__main__":
    main()
