"""Fidelity: every knob that trades time for accuracy, its presets, and how a scene sets it.

A scene may name a preset (``fidelity: draft | standard | fine``; ``standard`` when absent) and
may set any knob by hand; a hand-set value always wins over the preset. The resolved knobs are
recorded in every case's summary. The preset values were chosen from the measured
speed/accuracy front (``preform bench tradeoff``; table and command in ``benchmarks/README.md``).

Knobs (units in the names):

- ``node_spacing_mm``: pin-jointed net spacing d. Hand-set in ``ply.node_spacing_mm``; else the
  preset's fraction of the tool's typical length (``Surface.size``: the radius of a sphere).
- ``solver_tolerance``: placement and generator solves stop at this × d (relative, never
  absolute, so refining the net does not degrade it).
- ``generator_substeps``: sub-steps per node spacing when marching geodesic generators on
  surfaces without a closed form.
- ``energy_table_step_deg``: step of the tabulated surrogate of the shear law used for every
  energy field, the search's and the drape step's (cubic Hermite, error ∝ step⁴); ``0`` uses
  the law itself.
- ``scan_step_deg``, ``tolerance_deg``, ``max_drapes``: the generator-angle search's global
  scan step, refinement tolerance and drape budget.

Presets, as measured (``python benchmarks/bench_tradeoff.py``, 2026-12-01, after issue 11,
one core of a shared 2-core machine; bundled ``hemisphere-min-energy``, R = 100 mm, the part
z ≥ 0 clipped from a net draped past the rim, fabric E-BX-318; L is ``Surface.size``, here R;
errors against a reference with every knob at its finest, d = R/320, which lies 7e-6 in energy,
0.00° in angle and 0.11° in max |shear| from one step less fine):

- ``draft`` (d = L/20, scan 10°): 0.2 s per case (0.27 × standard), 2.1 MB; energy −6e-4,
  optimum angle 0.01° off, max |shear| 1° off.
- ``standard`` (d = L/40, scan 5°): 0.75 s (1×), 7.5 MB; energy −1.5e-4, angle within 0.005°,
  max |shear| 0.1° off.
- ``fine`` (d = L/160, scan 5°, exact law): 9 s (12×), 117 MB; energy −7e-6, angle exact, max
  |shear| 0.11° off: the reference to within its own resolution.

Before issue 11 the same study gave −11 %, −4.4 % and −1.4 % in energy and 0.8°, 0.3° (1–1.4°
on other scan grids) and 0.01° in angle: whole rim cells were dropped and the bare rim band
charged, so the energy converged at first order and E(α) carried a staircase that left the
refinement noise-limited. With clipped cells what matters on this scene is the node spacing,
and then mostly for max |shear|; the energy table, solver tolerance and sub-steps had no effect,
and the scan step and refinement tolerance cost time for no measured gain in angle.

A second study on a tool without closed forms (bundled ``paraboloid-min-energy``: every node
by the general Newton solve, generators marched; mechanistic ``plain-weave-600`` law;
``python benchmarks/bench_tradeoff.py --scene paraboloid-min-energy --material
plain-weave-600``, 38 min) measured the knobs the sphere bypasses: the solver tolerance from
1e-4 to 1e-12 and the energy table from 2° to the exact law changed no output (energy, angle
and max |shear| identical to 4 digits); generator sub-steps from 4 to 32 changed none either,
while 4 sub-steps cost 0.43× and 32 cost 1.7× of 16. Hence draft 4 and standard 8 sub-steps
(measured free); fine keeps 16 as a margin for tools whose curvature varies faster than this
dome's, not because a difference was measured. Node spacing again set the energy error
(−13 %, −7.4 %, −3.7 %, −1.7 %, −0.6 % at d = 10, 5, 2.5, 1.25, 0.625 mm).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from preform.pipeline.scene import Scene


@dataclass(frozen=True)
class Knobs:
    """Resolved fidelity knobs of a scene (the units are in the names)."""

    fidelity: str
    node_spacing_mm: float | None
    solver_tolerance: float
    generator_substeps: int
    energy_table_step_deg: float
    scan_step_deg: float
    tolerance_deg: float
    max_drapes: int

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    @property
    def energy_table_step_rad(self) -> float | None:
        """The surrogate's step [rad], or None for the law itself."""
        step = self.energy_table_step_deg
        return math.radians(step) if step > 0 else None


#: d as a fraction of the tool's typical length, when the scene does not set it.
SPACING_FRACTION: dict[str, float] = {"draft": 1 / 20, "standard": 1 / 40, "fine": 1 / 160}

PRESETS: dict[str, dict[str, Any]] = {
    "draft": {
        "solver_tolerance": 1e-6,
        "generator_substeps": 4,
        "energy_table_step_deg": 1.0,
        "scan_step_deg": 10.0,
        "tolerance_deg": 2.0,
        "max_drapes": 30,
    },
    "standard": {
        "solver_tolerance": 1e-9,
        "generator_substeps": 8,
        "energy_table_step_deg": 0.25,
        "scan_step_deg": 5.0,
        "tolerance_deg": 1.0,
        "max_drapes": 60,
    },
    "fine": {
        "solver_tolerance": 1e-11,
        "generator_substeps": 16,
        "energy_table_step_deg": 0.0,
        # Not finer than standard's: at d = L/160 a 2.5° scan cost 1.5x for no measured gain.
        "scan_step_deg": 5.0,
        "tolerance_deg": 0.25,
        "max_drapes": 120,
    },
}


def resolve(scene: Scene, tool_size_m: float | None = None) -> Knobs:
    """The knobs of ``scene``: hand-set values, else its preset's (``standard`` by default).

    ``tool_size_m`` [m] is needed only when the scene leaves the node spacing to the preset.
    """
    preset = scene.fidelity or "standard"
    values = dict(PRESETS[preset])
    numerics = scene.numerics
    if numerics is not None:
        for key, value in numerics.model_dump(exclude_none=True).items():
            values[key] = value
    search = scene.search
    if search is not None:
        for key in ("scan_step_deg", "tolerance_deg", "max_drapes"):
            value = getattr(search, key, None)
            if value is not None:
                values[key] = value
        span = search.generator_angle_deg
        if search.scan_step_deg is None and span is not None and span.step is not None:
            values["scan_step_deg"] = span.step
    spacing: float | None = None
    if scene.ply is not None and scene.ply.node_spacing_mm is not None:
        spacing = scene.ply.node_spacing_mm
    elif tool_size_m is not None:
        spacing = SPACING_FRACTION[preset] * tool_size_m * 1e3
    return Knobs(fidelity=preset, node_spacing_mm=spacing, **values)
