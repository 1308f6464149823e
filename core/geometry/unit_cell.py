"""The generic repeating cell of a fabric: tows and threads as centreline polylines.

Architecture plugins build a ``UnitCell`` from their own description; viewers, exporters and
derived-property code only see this. Lengths are metres.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    import numpy as np
    from numpy.typing import NDArray

    FloatArray = NDArray[np.float64]


def __getattr__(name: str) -> Any:
    # ``FloatArray`` for modules that import it at run time, built when first asked for, so
    # that importing this module (a fabric's geometry does) imports no numpy.
    if name == "FloatArray":
        import numpy as np
        from numpy.typing import NDArray

        return NDArray[np.float64]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class TowPath:
    """One tow (or stitching thread) of the cell, as a centreline polyline."""

    #: Centreline points (n, 3) [m]; z is the out-of-plane coordinate (level × tow height).
    points: FloatArray
    #: Cross-section width [m] (in the fabric plane, across the tow).
    width: float
    #: Cross-section height [m].
    height: float
    #: What the path is: "warp", "weft", "binder", "tow" (warp-knit layer) or "stitch".
    kind: str
    #: Level id of the path (woven levels are numbered warp first, then weft; see PHYSICS §1.1).
    level: int
    #: Name of the tow type (for colouring and hybrid fabrics).
    type_name: str = ""
    #: Linear density [tex = g/km].
    linear_density_tex: float = 0.0

    def length(self) -> float:
        """Polyline length [m]."""
        import numpy as np

        return float(np.linalg.norm(np.diff(self.points, axis=0), axis=1).sum())


@dataclass(frozen=True)
class UnitCell:
    """A fabric's repeating cell: in-plane period vectors and the paths inside one period."""

    #: In-plane repeat vectors [m], rows a1 and a2 (2, 2).
    period: FloatArray
    tows: tuple[TowPath, ...]
    #: Reference direction for signed shear [rad from the x axis of the cell].
    reference_direction: float = 0.0
    #: Free-form labels for viewers ("levels": {id: name}, ...).
    labels: dict[str, object] = field(default_factory=dict)

    @property
    def area(self) -> float:
        """Area of one period [m²]."""
        import numpy as np

        a1, a2 = np.asarray(self.period, dtype=float)
        return float(abs(a1[0] * a2[1] - a1[1] * a2[0]))

    def tiled(self, n1: int, n2: int) -> UnitCell:
        """The same fabric, n1 × n2 periods of it, as one cell (for viewing)."""
        import numpy as np

        if n1 < 1 or n2 < 1:
            raise ValueError(f"repeats must be at least 1x1, got {n1}x{n2}")
        a1, a2 = np.asarray(self.period, dtype=float)
        tows: list[TowPath] = []
        for i in range(n1):
            for j in range(n2):
                shift = np.array([*(i * a1 + j * a2), 0.0])
                for t in self.tows:
                    tows.append(
                        TowPath(
                            points=t.points + shift,
                            width=t.width,
                            height=t.height,
                            kind=t.kind,
                            level=t.level,
                            type_name=t.type_name,
                            linear_density_tex=t.linear_density_tex,
                        )
                    )
        return UnitCell(
            period=np.array([n1 * a1, n2 * a2]),
            tows=tuple(tows),
            reference_direction=self.reference_direction,
            labels=dict(self.labels),
        )
