"""Write the bundled hat-stiffener tool, ``hat_stiffener.step`` (and with ``--stl`` its STL).

A hat-section stiffener with ramped run-outs on a flat plate, as one solid (the tool block),
in millimetres (illustrative dimensions, not a particular part):

- plate 400 × 200 × 10 mm, its top at z = 0, centred on the origin;
- the hat: crown 200 × 40 mm at z = 30 mm, webs at 60° to the plate (along x), run-out ramps
  at 30° (at the ends), the four corners between webs and ramps rounded with 12 mm fillets.

The creases at the crown's edge and at the hat's foot are sharp (30° to 60° turns), the kind
of edge a pin-jointed net must cross; the rounded corners are curved, so the tessellation
tolerance matters there. gmsh numbers the faces on reading (``part: faces:`` selects by
number): 1-6 the plate (3 its top), 7-15 the hat (7, 11 webs; 9, 13 ramps; 8, 10, 12, 14
corner fillets; 15 the crown); tests/surfaces/test_cad.py checks this numbering.

The STL (``--stl``, not bundled) is the STEP as a scene reads it by default (tessellated to
0.05 mm, repaired, no edge longer than 1/20 of the diagonal): the two describe one tool to
0.05 mm.

Run from the repository root (needs the extra ``preform[cad]``)::

    python materials/tools/make_hat_stiffener.py [--stl]
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

#: Dimensions [mm] (module docstring).
PLATE = (200.0, 100.0, 10.0)  # half-length along x, half-width along y, thickness
CROWN = (100.0, 20.0)  # half-length, half-width
HEIGHT = 30.0
WEB_DEG, RAMP_DEG = 60.0, 30.0
CORNER_FILLET = 12.0


def main(out_dir: Path, stl: bool = False) -> None:
    import gmsh

    gmsh.initialize(readConfigFiles=False, interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    occ = gmsh.model.occ

    def rectangle(half_x: float, half_y: float, z: float) -> int:
        points = [
            occ.addPoint(x, y, z)
            for x, y in ((-half_x, -half_y), (half_x, -half_y), (half_x, half_y), (-half_x, half_y))
        ]
        return occ.addCurveLoop([occ.addLine(points[k], points[(k + 1) % 4]) for k in range(4)])

    foot = rectangle(
        CROWN[0] + HEIGHT / math.tan(math.radians(RAMP_DEG)),
        CROWN[1] + HEIGHT / math.tan(math.radians(WEB_DEG)),
        0.0,
    )
    crown = rectangle(CROWN[0], CROWN[1], HEIGHT)
    (hat,) = occ.addThruSections([foot, crown], makeSolid=True, makeRuled=True)
    occ.synchronize()
    # The corner edges are the ones that rise from foot to crown.
    rising = []
    for _, edge in gmsh.model.getEntities(1):
        box = occ.getBoundingBox(1, edge)
        if box[5] - box[2] > 0.5 * HEIGHT:
            rising.append(edge)
    hat_dimtags = occ.fillet([hat[1]], rising, [CORNER_FILLET])
    px, py, thickness = PLATE
    plate = occ.addBox(-px, -py, -thickness, 2 * px, 2 * py, thickness)
    occ.fuse([(3, plate)], hat_dimtags)
    occ.synchronize()
    step = out_dir / "hat_stiffener.step"
    gmsh.write(str(step))
    gmsh.finalize()
    if not stl:
        return

    from preform.plugins.surfaces.mesh import write_stl
    from preform.plugins.surfaces.tools import MeshTool, build_mesh

    tool = build_mesh(MeshTool(surface="mesh", file=step.name), str(out_dir))
    write_stl(out_dir / "hat_stiffener.stl", tool)


if __name__ == "__main__":
    main(Path(__file__).resolve().parent, stl="--stl" in sys.argv[1:])
