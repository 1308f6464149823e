"""The kinematic drape: tool surfaces, the pin-jointed net, its shear and energy fields."""

from preform.drape.chebyshev import chebyshev_angle
from preform.drape.fields import energy_field, summary
from preform.drape.generators import ClosedFormGeodesics, PlanPolylines
from preform.drape.net import ClosedFormPlacement, DrapeError, drape
from preform.drape.part import HeightCut, Part, PlanPolygon
from preform.drape.ply import PlyOutline
from preform.drape.result import CellStatus, DrapeResult, EnergyField, NodeStatus
from preform.drape.surface import Surface

__all__ = [
    "CellStatus",
    "ClosedFormGeodesics",
    "ClosedFormPlacement",
    "DrapeError",
    "DrapeResult",
    "EnergyField",
    "HeightCut",
    "NodeStatus",
    "Part",
    "PlanPolygon",
    "PlanPolylines",
    "PlyOutline",
    "Surface",
    "chebyshev_angle",
    "drape",
    "energy_field",
    "summary",
]
