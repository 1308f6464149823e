"""A drape on a tessellated hemisphere agrees with the drape on the analytic one, within the
mesh's error, and the agreement improves as the mesh is refined."""

from __future__ import annotations

import numpy as np

from preform.drape import PlyOutline, drape
from preform.plugins.surfaces.basic import Hemisphere
from preform.plugins.surfaces.mesh import tessellate_hemisphere

R = 0.1
D = 0.01
PLY = PlyOutline.rectangle((0.24, 0.24))


def shear_field(surface, **kwargs):
    result = drape(
        surface,
        node_spacing_m=D,
        ply=PLY,
        start_xy_m=(0.0, 0.0),
        generator_angle_rad=np.radians(80.0),
        **kwargs,
    )
    return result, np.where(result.valid, result.shear, np.nan)


def test_mesh_drape_converges_to_the_analytic_drape():
    _, exact = shear_field(Hemisphere(R))
    errors = []
    for divisions in (12, 24, 48):
        mesh = tessellate_hemisphere(R, divisions)
        result, approx = shear_field(mesh)
        both = np.isfinite(exact) & np.isfinite(approx)
        # the mesh covers (almost) the same part of the dome
        assert both.sum() >= 0.9 * np.isfinite(exact).sum()
        errors.append(float(np.nanmax(np.abs(approx - exact)[both])))
        assert np.all(result.residual[result.status == 0] <= 1e-6 * D)
    # the facets' angular error falls as the edge length: so must the shear error
    assert errors[2] < errors[1] < errors[0]
    assert errors[2] < np.radians(1.0)
