"""The tool-surface contract the drape engine works against.

Lengths are in metres inside preform (scenes give millimetres; the scene converts on load).
All queries are vectorised over an (n, 3) array of points. A surface need not be a height field
z = f(x, y): vertical walls and undercuts are legal, which is why the contract is
closest-point / implicit, not a height function.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import FloatArray


@runtime_checkable
class Surface(Protocol):
    """A tool surface the fabric is draped onto."""

    #: Axis-aligned bounds [m]: ((xmin, ymin, zmin), (xmax, ymax, zmax)).
    bounds: tuple[tuple[float, float, float], tuple[float, float, float]]
    #: A length [m] typical of the tool (sphere radius, mesh diagonal): tolerances scale with it.
    size: float

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest points on the surface to ``points`` (n, 3) [m], and their distances (n,)."""
        ...

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward normals (n, 3) at surface points (n, 3) [m]."""
        ...

    def point_at_plan(self, xy: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
        """The surface point seen from above at plan positions ``xy`` (n, 2) [m] (the topmost
        one), and a mask of the positions that lie over the tool at all.

        Where the mask is false the returned point is unspecified (NaN, or a point on the base
        plane, depending on the surface): callers must use the mask, never the point."""
        ...
