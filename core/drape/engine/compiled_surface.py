"""How an analytic tool tells the compiled net kernels what it is, without importing numba.

A surface whose closest point and normal have a closed form or a short root solve can
describe itself to the compiled wavefront fill (``preform.drape.kernels.net_kernels``) as a kind code
and a parameter vector; the fill then runs every front of the net, Newton steps and all, inside
one compiled loop instead of calling the surface's vectorised methods once per front. Any other
surface (a mesh, a plugin's own tool) keeps the vectorised path, which uses the same compiled
per-node steps. The queries themselves are in ``preform.drape.kernels.surface_kernels``, once: the
tools' own ``closest_point`` and ``normal`` answer through :func:`query_tool` (:class:`CompiledTool`).

This module holds only the codes, the protocol and that lazy entry, so the surface plugins can
name them at import time while numba itself is imported only when a tool is queried.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Protocol, runtime_checkable

import numpy as np

from preform.base.arrays import FloatArray

#: A full sphere. Parameters: centre x, y, z [m], radius [m].
SPHERE = 1
#: The sphere down to a floor height: points below it belong to its edge circle. Parameters:
#: centre x, y, z [m], radius [m], floor z [m] (the lowest height of the tool).
TRIMMED_SPHERE = 2
#: A flat horizontal plate. Parameters: centre x, y, z [m], half size along x, along y [m].
PLANE = 3
#: The lateral surface of a horizontal cylinder, ending at its end circles. Parameters: centre
#: x, y, z [m], radius [m], half length [m], axis (0: along x, 1: along y).
CYLINDER = 4
#: A hemisphere on a flange joined by a concave toroidal fillet, centred at the origin.
#: Parameters: radius [m], fillet radius [m], fillet foot radius [m], flange half width [m],
#: seam elevation [rad], flange shape (1: square, 0: disc).
FLANGED_HEMISPHERE = 5
#: A cone, apex up, on z = 0 about the z axis, possibly truncated by a top disc. Parameters:
#: base radius [m], height [m], top radius [m], lateral outward normal (radial, vertical part).
CONE = 6
#: The upper half of an ellipsoid centred at the origin. Parameters: semi-axes a, b, c [m].
ELLIPSOID_DOME = 7
#: The paraboloid z = h (1 − r²/R²), r ≤ R. Parameters: R [m], h [m], h/R² [1/m].
PARABOLOID_DOME = 8

#: Every kind the compiled queries answer.
KINDS = (
    SPHERE,
    TRIMMED_SPHERE,
    PLANE,
    CYLINDER,
    FLANGED_HEMISPHERE,
    CONE,
    ELLIPSOID_DOME,
    PARABOLOID_DOME,
)
#: Length of the parameter row of the tools other than the spheres (``kernel_parameters``).
_ROW_LENGTH = 8

#: The kinds whose net node has a compiled closed form (no Newton iteration).
CLOSED_FORM_KINDS = (SPHERE, TRIMMED_SPHERE, PLANE)


@runtime_checkable
class CompiledQueries(Protocol):
    """Optional surface method: its kind code and parameters for the compiled kernels."""

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """(kind, parameters): one of this module's codes and its parameter vector [m]."""
        ...


def checked_kind(kind: int) -> int:
    """``kind`` as an int when it is one of this module's codes (``KINDS``); else a ValueError
    saying which are known (a tool's ``compiled_queries`` must name one of them)."""
    if kind not in KINDS:
        raise ValueError(
            f"compiled_queries() gave kind {kind!r}, which is none of the compiled tools' "
            f"codes {KINDS} (preform.drape.engine.compiled_surface); return one of them, or drop "
            "compiled_queries so the tool is queried through its own methods"
        )
    return int(kind)


def kernel_parameters(kind: int, params: FloatArray) -> FloatArray:
    """A tool's parameters [m] as the compiled kernels take them: a sphere's as a vector, any
    other tool's as one row (1, 8), padded with zeros. For the vectorised queries
    (``preform.drape.kernels.surface_kernels.query``) the rank picks the code when they are compiled,
    so the other tools share one compilation; the net kernels' fill unpacks either form into
    one tuple of numbers (``net_kernels._param_tuple``) and picks the query by kind code as it
    runs, which measured no slower on the sphere once the per-node steps were inlined."""
    values = np.asarray(params, dtype=float).ravel()
    if checked_kind(kind) in (SPHERE, TRIMMED_SPHERE):
        return np.ascontiguousarray(values)
    if len(values) > _ROW_LENGTH:
        raise ValueError(f"a tool has at most {_ROW_LENGTH} kernel parameters, got {values}")
    row = np.zeros((1, _ROW_LENGTH))
    row[0, : len(values)] = values
    return row


def query_tool(
    surface: CompiledQueries, points: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Closest tool points (..., 3) [m], unit outward normals there (..., 3) and distances
    (...) [m] of points (..., 3) [m], through the tool's compiled queries."""
    from preform.drape.kernels import surface_kernels

    p = np.ascontiguousarray(points, dtype=float)
    if p.shape[-1:] != (3,):
        raise ValueError(f"expected an (n, 3) array of positions [m], got {p.shape}")
    kind, params = surface.compiled_queries()
    foot, normal, dist = surface_kernels.query_points(
        checked_kind(kind), kernel_parameters(kind, params), p.reshape(-1, 3)
    )
    shape = p.shape[:-1]
    return foot.reshape(*shape, 3), normal.reshape(*shape, 3), dist.reshape(shape)


class CompiledTool(ABC):
    """An analytic tool whose ``Surface`` queries are its compiled ones (:func:`query_tool`):
    it gives ``compiled_queries``, and answers ``closest_point`` and ``normal`` for any point,
    a point off the tool with its closest tool point and the normal there. Abstract: a tool
    that does not give its queries cannot be made (rather than failing at its first query)."""

    @abstractmethod
    def compiled_queries(self) -> tuple[int, FloatArray]:
        """The tool's kind (``surface_kernels``) and kernel parameters."""

    def closest_point(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest tool points (n, 3) [m] to ``points`` (n, 3) [m] and distances (n,) [m]."""
        closest, _, distance = query_tool(self, points)
        return closest, distance

    def normal(self, points: FloatArray) -> FloatArray:
        """Unit outward normals (n, 3) at tool points (n, 3) [m]."""
        return query_tool(self, points)[1]
