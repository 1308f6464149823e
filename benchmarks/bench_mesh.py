"""Mesh tools against the analytic sphere: drape speed, and a least-energy study's wall time.

1. Drape speed (issue 30's goal: the mesh within 2x of the sphere's Newton path). The same net
   (R = 100 mm hemisphere, 2.4 R square ply, alpha = 80 deg) draped on the analytic
   ``Hemisphere`` twice, through its general placement (``use_closed_form=False``: Newton on
   the constraint circle and marched geodesics, the path any smooth tool without closed forms
   takes) and through its closed forms, and on ``tessellate_hemisphere`` meshes (exact walking
   placement and straightest geodesics on the facets, ``preform.plugins.surfaces.mesh_kernels``;
   ``use_closed_form`` changes nothing there). Both ratios side by side: the mesh's time over
   the sphere's Newton path and over its closed forms. ``--nodes`` nets across (401 and 1001:
   401^2 and 1001^2 nodes); ``--divisions`` 112 and 224 give 50 176 and 200 704 triangles.
   The mesh's one-off topology build is timed separately from the drape.
2. A least-energy study (generator-angle search, 30-150 deg, the default scan and refinement)
   of the bundled plain-weave-600 on the bundled hat mould against the same study on the
   analytic hemisphere, at the same number of nodes.

Best of ``--repeat`` runs, the three drapes of a net alternated within each repeat so that the
load of a shared machine falls on all of them alike; one core (pinned before numpy loads);
the numba kernels are compiled (or loaded from the cache) before any timing. ``--clock cpu``
(the default) times the process's processor time, which other processes' load changes far
less than the wall time (``--clock wall``); the drapes are single-threaded either way.

    python benchmarks/bench_mesh.py [--repeat 3] [--divisions 112 224] [--nodes 401 1001]
        [--clock cpu|wall] [--feature-angle 180] [--no-study]
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
SIDE = 2.4 * RADIUS
PLY = PlyOutline.rectangle((SIDE, SIDE))
HAT = Path(__file__).resolve().parents[1] / "materials" / "tools" / "hat_mould.obj"


def best(fn: Callable[[], Any], repeat: int, clock: Callable[[], float]) -> tuple[float, Any]:
    times, out = [], None
    for _ in range(repeat):
        start = clock()
        out = fn()
        times.append(clock() - start)
    return min(times), out


def drape_on(surface: Any, spacing: float, closed_form: bool = True) -> Any:
    return drape(
        surface,
        node_spacing_m=spacing,
        ply=PLY,
        start_xy_m=(0.0, 0.0),
        generator_angle_rad=ALPHA,
        use_closed_form=closed_form,
    )


def drape_speed(
    repeat: int,
    divisions: list[int],
    nodes_across: list[int],
    feature_angle_deg: float,
    clock: Callable[[], float],
) -> None:
    sphere = Hemisphere(RADIUS)
    meshes, builds = [], []
    for n in divisions:
        start = time.perf_counter()
        mesh = tessellate_hemisphere(RADIUS, n)
        mesh = TriangleMesh(mesh.vertices, mesh.faces, feature_angle_deg=feature_angle_deg)
        _ = mesh.walker
        builds.append(time.perf_counter() - start)
        meshes.append(mesh)
        drape_on(mesh, 0.02)  # compile or load the kernels, outside the timing
    drape_on(sphere, 0.02)
    drape_on(sphere, 0.02, closed_form=False)
    print(
        "\n(1) Drape speed: mesh hemisphere vs analytic hemisphere (Newton path, closed forms), "
        "same net, one core"
    )
    print(
        f"{'triangles':>10}{'nodes':>10}{'placed':>10}{'build s':>9}{'newton s':>10}"
        f"{'closed s':>10}{'mesh s':>9}{'x newton':>10}{'x closed':>10}{'Mnodes/s':>10}"
        f"{'max dshear deg':>16}"
    )
    for across in nodes_across:
        d = SIDE / (across - 1)  # across nodes from edge to edge of the ply
        runs: dict[str, list[float]] = {}
        results: dict[str, Any] = {}
        kinds = [("newton", sphere, False), ("closed", sphere, True)] + [
            (f"mesh{k}", mesh, True) for k, mesh in enumerate(meshes)
        ]
        for _ in range(repeat):
            for name, surface, closed in kinds:
                seconds, results[name] = best(
                    lambda s=surface, c=closed, d=d: drape_on(s, d, c), 1, clock
                )
                runs.setdefault(name, []).append(seconds)
        newton, closed = min(runs["newton"]), min(runs["closed"])
        exact = results["closed"]
        for k, mesh in enumerate(meshes):
            t_mesh, approx = min(runs[f"mesh{k}"]), results[f"mesh{k}"]
            both = exact.valid & approx.valid
            dshear = float(np.degrees(np.max(np.abs(exact.shear - approx.shear)[both])))
            print(
                f"{mesh.n_triangles:>10}{approx.nodes_total:>10}{approx.nodes_placed:>10}"
                f"{builds[k]:>9.2f}{newton:>10.3f}{closed:>10.3f}{t_mesh:>9.3f}"
                f"{t_mesh / newton:>10.2f}{t_mesh / closed:>10.2f}"
                f"{approx.nodes_placed / t_mesh / 1e6:>10.2f}{dshear:>16.3f}"
            )


def study(
    repeat: int, spacing: float, feature_angle_deg: float, clock: Callable[[], float]
) -> None:
    law = load_library().shear_law("plain-weave-600")
    hat = read_obj(HAT, feature_angle_deg=feature_angle_deg)
    sphere = Hemisphere(RADIUS, run_off_m=RADIUS / 4)
    ply = PlyOutline.rectangle((0.36, 0.36))
    print(
        "\n(2) Least-energy study (angle search 30-150 deg), plain-weave-600, "
        f"d = {spacing * 1e3:g} mm"
    )
    print(f"{'tool':>14}{'nodes':>8}{'drapes':>8}{'time s':>8}{'ratio':>7}{'optimum deg':>13}")
    rows = []
    for name, tool, start in (
        ("hemisphere", sphere, (0.0, 0.0)),
        ("hat mould", hat, (0.004, 0.003)),
    ):
        objective = DrapeObjective(tool, law, node_spacing_m=spacing, ply=ply, start_xy_m=start)
        search_generator_angle(objective)  # warm: kernels compiled, mesh topology built
        wall, found = best(lambda o=objective: search_generator_angle(o), repeat, clock)
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
    parser.add_argument("--divisions", type=int, nargs="+", default=[112, 224])
    parser.add_argument("--nodes", type=int, nargs="+", default=[401, 1001], help="nets across")
    parser.add_argument("--clock", choices=("cpu", "wall"), default="cpu")
    parser.add_argument("--no-study", action="store_true", help="the drape speed only")
    parser.add_argument(
        "--feature-angle",
        type=float,
        default=DEFAULT_FEATURE_ANGLE_DEG,
        help="the meshes' feature_angle_deg [deg] (docs/physics.md, 'Sharp creases')",
    )
    args = parser.parse_args()
    clock = time.process_time if args.clock == "cpu" else time.perf_counter
    drape_speed(args.repeat, args.divisions, args.nodes, args.feature_angle, clock)
    if not args.no_study:
        study(args.repeat, 2.5e-3, args.feature_angle, clock)


if __name__ == "__main__":
    main()
