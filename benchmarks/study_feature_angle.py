"""The effect of a mesh's ``feature_angle_deg`` (docs/physics.md, "Sharp creases").

Two measurements, each against an independent truth:

1. Plates folded by θ along a crease at 60° to the first fibre (α = 70°, d = 10 mm): the
   largest distance between the draped net unfolded into the plane and the flat net (zero for
   the developable answer), and the largest |shear − (α − 90°)| on the cells wholly on one
   flank; at feature angles 20° and 30° and with the chord only (180°, the default).
2. The tessellated hemisphere (R = 100 mm, d = R/10, α = 80°): the largest shear difference
   from the analytic drape at 6, 12, 24 and 48 divisions, for several feature angles.

The folded plates are those of tests/drape/test_mesh_feature_creases.py (imported from there,
so the study and the test drape the same tool).

    python benchmarks/study_feature_angle.py
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from preform.drape import PlyOutline, drape
from preform.drape.engine.result import NodeStatus
from preform.plugins.surfaces.basic import Hemisphere
from preform.plugins.surfaces.mesh import TriangleMesh, tessellate_hemisphere

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "drape"))
from test_mesh_feature_creases import drape_across, unfolded


def whole(mask: np.ndarray) -> np.ndarray:
    """Cells (…) whose four corner nodes all satisfy ``mask``."""
    return mask[:-1, :-1] & mask[1:, :-1] & mask[:-1, 1:] & mask[1:, 1:]


def plates() -> None:
    alpha = 70.0
    print("(1) folded plate, alpha 70 deg, crease at 60 deg to u, d = 10 mm")
    print("  fold deg | feature 20 | 30 | 180 (chord only, default): flat error mm, shear, placed")
    for fold in (10.0, 19.0, 21.0, 30.0, 45.0, 90.0, 135.0):
        row = [f"  {fold:8.1f}"]
        for feature in (20.0, 30.0, 180.0):
            r, flat = drape_across(fold, alpha, 60.0, feature_angle_deg=feature)
            ok = r.status == NodeStatus.PLACED
            error = np.linalg.norm(unfolded(r.nodes[ok], fold) - flat[ok], axis=-1).max()
            near = np.abs(r.nodes[..., 2]) <= 1e-12
            flank = r.valid & (whole(near) | whole(ok & ~near))
            shear = np.max(np.abs(r.shear[flank] - math.radians(alpha - 90.0)))
            inside = r.status != NodeStatus.OUTSIDE_PLY
            row.append(f"{1e3 * error:7.3f} {math.degrees(shear):6.2f} {ok[inside].mean():6.3f}")
        print(" | ".join(row))


def hemisphere() -> None:
    radius, d = 0.1, 0.01
    ply = PlyOutline.rectangle((0.24, 0.24))

    def field(surface):
        r = drape(
            surface,
            node_spacing_m=d,
            ply=ply,
            start_xy_m=(0.0, 0.0),
            generator_angle_rad=math.radians(80.0),
        )
        return np.where(r.valid, r.shear, np.nan)

    exact = field(Hemisphere(radius))
    features = (0.0, 5.0, 10.0, 15.0, 20.0, 30.0, 180.0)
    print("(2) hemisphere mesh vs analytic, max |dshear| deg; feature angle", features)
    for divisions in (6, 12, 24, 48):
        base = tessellate_hemisphere(radius, divisions)
        row = []
        for feature in features:
            mesh = TriangleMesh(base.vertices, base.faces, feature_angle_deg=feature)
            shear = field(mesh)
            both = np.isfinite(exact) & np.isfinite(shear)
            row.append(f"{math.degrees(np.max(np.abs(shear - exact)[both])):6.3f}")
        print(f"  divisions {divisions:3d}: " + " ".join(row))


if __name__ == "__main__":
    plates()
    hemisphere()
