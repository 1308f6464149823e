"""How an analytic tool tells the compiled net kernels what it is, without importing numba.

A surface whose closest point and normal have a short closed form can describe itself to the
compiled wavefront fill (``preform.drape.net_kernels``) as a kind code and a parameter vector;
the fill then runs every front of the net, Newton steps and all, inside one compiled loop
instead of calling the surface's vectorised methods once per front. Any other surface (a mesh,
a plugin's own tool) keeps the vectorised path, which uses the same compiled per-node steps.

This module holds only the codes and the protocol, so the surface plugins can name them at
import time while numba itself is imported only when a net is draped.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: A full sphere. Parameters: centre x, y, z [m], radius [m].
SPHERE = 1
#: The sphere down to a floor height: points below it belong to its edge circle. Parameters:
#: centre x, y, z [m], radius [m], floor z [m] (the lowest height of the tool).
TRIMMED_SPHERE = 2


@runtime_checkable
class CompiledQueries(Protocol):
    """Optional surface method: its kind code and parameters for the compiled kernels."""

    def compiled_queries(self) -> tuple[int, FloatArray]:
        """(kind, parameters): one of this module's codes and its parameter vector [m]."""
        ...
