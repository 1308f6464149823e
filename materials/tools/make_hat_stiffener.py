"""Write the bundled hat-stiffener tool, ``hat_stiffener.step`` and ``hat_stiffener.stl``.

A hat-section stiffener with ramped run-outs on a flat plate, the upper surface of the tool
only (the side the fabric lies on), in millimetres (illustrative dimensions, not a
particular part):

- plate z = 0, 400 × 200 mm, centred on the origin;
- the hat: crown 200 × 40 mm at z = 30 mm, webs at 60° to the plate along y, run-out ramps at
  30° to the plate along x; its foot on the plate is 2·(100 + 30/tan 30°) × 2·(20 + 30/tan 60°).

Every edge is sharp (crease angles 30° to 60°) and the four crown corners and four foot
corners are vertices where three faces meet, the case a pin-jointed net cannot pass unharmed.
All faces are planar, so any tessellation is exact: the STEP and STL describe one surface.
The faces are built on shared edges and sewn into one shell, so the STEP's faces meet edge
to edge; they are numbered as gmsh lists them on reading: 1 plate, 2 crown, 3-4 webs,
5-6 ramps (``part: faces:`` selects by number).

Run from the repository root (needs the extra ``preform[cad]``)::

    python materials/tools/make_hat_stiffener.py
"""

from __future__ import annotations

import math
from pathlib import Path

#: Dimensions [mm] (module docstring).
PLATE = (200.0, 100.0)  # half-length along x, half-width along y
CROWN = (100.0, 20.0)  # half-length, half-width
HEIGHT = 30.0
WEB_DEG, RAMP_DEG = 60.0, 30.0


def corners() -> dict[str, list[tuple[float, float, float]]]:
    """The hat's crown and foot rectangles and the plate's outline [mm], counter-clockwise."""
    cx, cy = CROWN
    fx = cx + HEIGHT / math.tan(math.radians(RAMP_DEG))
    fy = cy + HEIGHT / math.tan(math.radians(WEB_DEG))
    px, py = PLATE

    def ring(x: float, y: float, z: float) -> list[tuple[float, float, float]]:
        return [(-x, -y, z), (x, -y, z), (x, y, z), (-x, y, z)]

    return {"crown": ring(cx, cy, HEIGHT), "foot": ring(fx, fy, 0.0), "plate": ring(px, py, 0.0)}


def main(out_dir: Path) -> None:
    import gmsh

    gmsh.initialize(readConfigFiles=False, interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    occ = gmsh.model.occ
    rings = {name: [occ.addPoint(*p) for p in pts] for name, pts in corners().items()}

    def loop(points: list[int]) -> list[int]:
        return [occ.addLine(points[k], points[(k + 1) % len(points)]) for k in range(len(points))]

    crown, foot, plate = loop(rings["crown"]), loop(rings["foot"]), loop(rings["plate"])
    # Side k joins foot edge k to crown edge k: k = 0 and 2 are webs (along x), 1 and 3 ramps.
    rises = [occ.addLine(rings["foot"][k], rings["crown"][k]) for k in range(4)]
    plate_face = occ.addPlaneSurface([occ.addCurveLoop(plate), occ.addCurveLoop(foot)])
    crown_face = occ.addPlaneSurface([occ.addCurveLoop(crown)])
    sides = []
    for k in (0, 2, 1, 3):
        edge_loop = occ.addCurveLoop([foot[k], rises[(k + 1) % 4], crown[k], rises[k]])
        sides.append(occ.addPlaneSurface([edge_loop]))
    occ.healShapes([(2, t) for t in (plate_face, crown_face, *sides)], sewFaces=True)
    occ.synchronize()
    step = out_dir / "hat_stiffener.step"
    gmsh.write(str(step))
    gmsh.finalize()

    # The STL of the same surface: a planar tool tessellates exactly, so preform's own CAD
    # reader writes it from the STEP.
    from preform.plugins.surfaces.cad import read_cad
    from preform.plugins.surfaces.mesh import TriangleMesh, write_stl
    from preform.plugins.surfaces.mesh_hygiene import repair

    cad = read_cad(step)
    fixed = repair(cad.vertices, cad.faces)
    write_stl(out_dir / "hat_stiffener.stl", TriangleMesh(fixed.vertices, fixed.faces))


if __name__ == "__main__":
    main(Path(__file__).resolve().parent)
