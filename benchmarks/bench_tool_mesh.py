"""Tools from files, as ratios in one run: what mesh hygiene costs, and what splitting long
edges buys a drape on a CAD tool.

- **Hygiene** (``preform.plugins.surfaces.mesh_hygiene.repair``) of an STL-like soup of a
  tessellated hemisphere (every corner its own copy), against building the ``TriangleMesh`` of
  the same soup (which merges the copies itself): the price of repairing every file tool.
- **Surface checks**: ``TriangleMesh(vertices, faces)`` of the welded hemisphere (fins,
  winding, folds: ``mesh_hygiene.check_surface``) against the same construction without them
  (what it was before it checked, and what a ``ToolMesh`` pays: ``repair`` ran them); and
  ``read_stl`` of the soup written as a binary STL (parse, ``repair``, ``ToolMesh``) against
  parsing it into an unchecked ``TriangleMesh`` (the reader before it repaired).
- **Long edges**: one drape over the bundled ``hat_stiffener.step`` at the draft node spacing
  (22 mm), its triangles as OpenCASCADE made them (``max_edge_mm`` 1000: nothing split) against
  the default (no edge over 1/20 of the diagonal); the surface is the same.

    python benchmarks/bench_tool_mesh.py [--repeat 3] [--divisions 160]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np


def best_of(run: Callable[[], Any], repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--divisions", type=int, default=160, help="hemisphere: 4·n² triangles")
    args = parser.parse_args()

    from preform.drape import PlyOutline, drape
    from preform.plugins.surfaces.mesh import (
        TriangleMesh,
        read_stl,
        stl_triangles,
        tessellate_hemisphere,
        write_stl,
    )
    from preform.plugins.surfaces.mesh_hygiene import repair
    from preform.plugins.surfaces.tools import MeshTool, build_mesh

    dome = tessellate_hemisphere(0.1, args.divisions)
    soup = dome.vertices[dome.faces].reshape(-1, 3)
    soup_faces = np.arange(soup.shape[0]).reshape(-1, 3)
    t_repair = best_of(lambda: repair(soup, soup_faces), args.repeat)
    t_build = best_of(lambda: TriangleMesh(soup, soup_faces), args.repeat)
    print(
        f"hygiene of {dome.n_triangles} triangles: repair {t_repair:.2f} s, TriangleMesh "
        f"{t_build:.2f} s, ratio {t_repair / t_build:.2f}"
    )

    class Unchecked(TriangleMesh):
        # the constructor without the surface checks, as a ToolMesh builds
        _surface_checked = True

    t_checked = best_of(lambda: TriangleMesh(dome.vertices, dome.faces), args.repeat)
    t_unchecked = best_of(lambda: Unchecked(dome.vertices, dome.faces), args.repeat)
    print(
        f"TriangleMesh of {dome.n_triangles} triangles: checked {t_checked:.2f} s, unchecked "
        f"{t_unchecked:.2f} s, ratio {t_checked / t_unchecked:.2f}"
    )
    with tempfile.TemporaryDirectory() as folder:
        stl = Path(folder) / "dome.stl"
        write_stl(stl, dome)
        t_read = best_of(lambda: read_stl(stl), args.repeat)
        t_parse = best_of(lambda: Unchecked(*stl_triangles(stl)), args.repeat)
    print(
        f"read_stl of {dome.n_triangles} triangles: repaired {t_read:.2f} s, parsed into an "
        f"unchecked TriangleMesh {t_parse:.2f} s, ratio {t_read / t_parse:.2f}"
    )

    def drape_over(**tool: Any) -> Callable[[], Any]:
        surface = build_mesh(MeshTool(surface="mesh", file="hat_stiffener.step", **tool), ".")

        def run() -> Any:
            return drape(
                surface,
                node_spacing_m=0.0224,
                ply=PlyOutline.rectangle((0.36, 0.16)),
                start_xy_m=(0.0, 0.0),
                generator_angle_rad=np.radians(86.5),
                substeps=4,
            )

        return run

    t_whole = best_of(drape_over(max_edge_mm=1000.0), args.repeat)
    t_split = best_of(drape_over(), args.repeat)
    print(
        f"drape over the hat stiffener: as tessellated {t_whole:.2f} s, long edges split "
        f"{t_split:.2f} s, speed-up {t_whole / t_split:.1f}x"
    )


if __name__ == "__main__":
    main()
