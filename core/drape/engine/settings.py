"""A drape's set-up beside the tool, resolved once (:class:`DrapeSettings`): the engine's
stages read it and a scene's case records the fidelity knobs it carries, so what ran is what
is recorded (``preform.drape.steps.drape_settings`` makes a scene's)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.drape.engine.ply import PlyOutline

if TYPE_CHECKING:
    from preform.base.fidelity import Knobs


class DrapeError(ValueError):
    """A drape that cannot start: the set-up itself is wrong (start off the tool, bad angle)."""


@dataclass(frozen=True)
class DrapeSettings:
    """One drape's set-up in SI units (:func:`preform.drape.engine.net.drape` takes it, or its
    fields as keywords). :class:`DrapeError` for a spacing or tolerance that gives no net."""

    #: Node spacing d [m], the chord between neighbouring crossovers.
    node_spacing_m: float
    #: The ply outline in the flat; its origin is the start point, its axes the fibres.
    ply: PlyOutline
    #: Plan position (x, y) [m] of the start point, put on the tool's top with
    #: ``point_at_plan``; or ``start_point``, a 3-D point [m] on the tool.
    start_xy_m: Any = None
    start_point: Any = None
    #: Plan direction of the first generator +u [rad from the tool's x axis], and the angle α
    #: [rad] from +u to +v, counter-clockwise seen from the outward normal, 0 < α < π.
    orientation_rad: float | None = 0.0
    generator_angle_rad: float | None = 0.5 * np.pi
    #: "geodesic", "plan" (the tool above straight plan lines), ``PlanPolylines`` (which set
    #: orientation and α: give None), or paths with a ``nodes`` method (``CurvedGenerators``).
    generators: Any = "geodesic"
    #: Predicate on cell centroids (n, 3) [m] giving the part (default: every valid cell).
    trim: Callable[[Any], Any] | None = None
    #: Relative tolerance [-] (every solve stops at ``tolerance``·d [m]), the cap on Newton
    #: steps per front, sub-steps per spacing marching generators, and whether to use the
    #: surface's closed forms (node placement, geodesics) when it has them (False: Newton on
    #: the constraint circle, marched geodesics; a tool that places by walking its facets, a
    #: mesh, has no closed form to leave and walks either way).
    tolerance: float = 1e-9
    max_iterations: int = 30
    substeps: int = 16
    use_closed_form: bool = True
    #: The scene's fidelity knobs these were resolved from (None for a drape set by hand).
    fidelity: Knobs | None = None

    def __post_init__(self) -> None:
        d = float(self.node_spacing_m)
        if not (np.isfinite(d) and d > 0):
            raise DrapeError(f"node spacing must be a positive length, got {d!r} m")
        if not 0 < self.tolerance < 1e-2:
            raise DrapeError(f"tolerance is relative to the node spacing; got {self.tolerance!r}")

    def keywords(self) -> dict[str, Any]:
        """The set-up as keyword arguments of :func:`~preform.drape.engine.net.drape`."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name != "fidelity"}

    @property
    def tolerance_m(self) -> float:
        """The solves' stopping distance [m]: ``tolerance``·d."""
        return self.tolerance * float(self.node_spacing_m)
