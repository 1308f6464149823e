"""Speed and resolution of the minimum-energy search on the bundled hemisphere scene.

The full generator-angle study (scan + refinement + a drape at the optimum) for one fabric on
the scene's 145 × 145 net (R = 100 mm, d = 2.5 mm, 360 mm ply), on one core: wall time, drapes,
the optimum and how well it is resolved, for a few settings of the fidelity knobs. The fabric's
law comes from the bundled library; ``--asymmetry r`` scales its negative-sense branch by r, an
ILLUSTRATIVE asymmetric fabric (cheaper to shear perpendicular to the stitch, as a warp-knit).
Optionally the curved-generator optimisation (``--curved``) and the net relaxation
(``--relax``, beyond the paper) at coarser nets, with their energy savings.

    python benchmarks/bench_search.py [--fabric plain-weave-600] [--asymmetry 0.3]
                                      [--repeat 3] [--curved] [--relax]
"""

from __future__ import annotations

import os

# One core: BLAS threads and the process both pinned before numpy loads.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})

import argparse  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from preform.drape.engine.net import drape  # noqa: E402
from preform.drape.engine.ply import PlyOutline  # noqa: E402
from preform.library import load_library  # noqa: E402
from preform.optimise.curved import optimise_curved_generators  # noqa: E402
from preform.optimise.relax import relax_net  # noqa: E402
from preform.optimise.search import DrapeObjective, search_generator_angle  # noqa: E402
from preform.plugins.surfaces.basic import Hemisphere  # noqa: E402

RADIUS = 0.1
PLY = PlyOutline.rectangle((0.36, 0.36))
#: The scene's tool: the hemisphere continued R/4 past its rim, clipped to z ≥ 0 (issue 11).
TOOL = Hemisphere(RADIUS, run_off_m=RADIUS / 4)


class ScaledNegative:
    """An illustrative asymmetric law: ``law`` with its γ < 0 branch scaled by ``ratio``."""

    def __init__(self, law: Any, ratio: float) -> None:
        self.law, self.ratio = law, ratio
        self.locking_angle = law.locking_angle
        self.failure_angle = law.failure_angle

    def torque(self, gamma: Any) -> Any:
        g = np.asarray(gamma, dtype=float)
        return np.where(g < 0, self.ratio, 1.0) * self.law.torque(g)

    def energy(self, gamma: Any) -> Any:
        g = np.asarray(gamma, dtype=float)
        return np.where(g < 0, self.ratio, 1.0) * self.law.energy(g)


def objective(law: Any, spacing: float, **kwargs: Any) -> DrapeObjective:
    return DrapeObjective(
        TOOL,
        law,
        node_spacing_m=spacing,
        ply=PLY,
        start_xy_m=(0.0, 0.0),
        trim=TOOL.part(),
        **kwargs,
    )


def angle_study(law: Any, label: str, repeat: int) -> None:
    print(f"\nAngle search, {label}, d = 2.5 mm (145 x 145 nodes), one core, best of {repeat}")
    print(
        f"{'scan':>6}{'tol':>6}{'drapes':>8}{'wall s':>8}{'ms/drape':>10}{'optimum':>10}"
        f"{'bracket':>9}{'std':>7}{'unc':>7}{'E_opt J':>10}"
    )
    for step, tol in ((5.0, 1.0), (5.0, 0.25), (10.0, 1.0), (2.5, 1.0)):
        best, result = math.inf, None
        for _ in range(repeat):
            obj = objective(law, 2.5e-3)
            clock = time.perf_counter()
            result = search_generator_angle(
                obj, scan_step_rad=math.radians(step), tolerance_rad=math.radians(tol)
            )
            best = min(best, time.perf_counter() - clock)
        assert result is not None
        std = result.vertex_std_rad
        print(
            f"{step:>6.1f}{tol:>6.2f}{result.drapes:>8d}{best:>8.2f}"
            f"{1e3 * best / result.drapes:>10.1f}{result.optimum_angle_deg:>10.2f}"
            f"{'±':>3}{math.degrees(result.bracket_half_width_rad):<6.2f}"
            f"{math.degrees(std) if std is not None else math.nan:>7.3f}"
            f"{result.summary()['uncertainty_deg'] or math.nan:>7.3f}"
            f"{result.optimum_energy_J:>10.4f}"
        )
    clock = time.perf_counter()
    drape(TOOL, node_spacing_m=2.5e-3, ply=PLY, start_xy_m=(0.0, 0.0), trim=TOOL.part())
    print(f"(one drape alone: {1e3 * (time.perf_counter() - clock):.0f} ms)")


def curved_study(law: Any, label: str) -> None:
    print(f"\nCurved generators (mirror families, 2 terms, angle free), {label}")
    print(
        f"{'d mm':>6}{'straight':>10}{'curved':>9}{'c1':>8}{'saving':>8}{'drapes':>8}{'wall s':>8}"
    )
    for spacing in (0.01, 0.005, 0.0025):
        obj = objective(law, spacing, substeps=4)
        search = search_generator_angle(obj)
        clock = time.perf_counter()
        res = optimise_curved_generators(
            obj,
            generator_angle_rad=search.optimum_angle_rad,
            reference_area_m2=search.reference_area_m2,
            mirror_families=True,
        )
        print(
            f"{1e3 * spacing:>6.1f}{search.optimum_angle_deg:>10.2f}"
            f"{math.degrees(res.generator_angle_rad):>9.2f}"
            f"{res.generators.coefficients[0][1]:>8.3f}{100 * res.relative_saving:>7.1f}%"
            f"{res.drapes:>8d}{time.perf_counter() - clock:>8.1f}"
        )


def relax_study(law: Any, label: str) -> None:
    print(f"\nRelaxation (beyond the paper) from the straight optimum, {label}")
    print(
        f"{'d mm':>6}{'cells':>7}{'saving':>8}{'edge err':>10}{'rms dγ':>8}{'evals':>7}"
        f"{'wall s':>8}"
    )
    for spacing in (0.01, 0.005):
        obj = objective(law, spacing)
        search = search_generator_angle(obj)
        ev = obj.evaluate(search.optimum_angle_rad, keep_result=True)
        assert ev.result is not None
        res = relax_net(ev.result, obj.surface, law, counted=obj.counted(ev.result))
        print(
            f"{1e3 * spacing:>6.1f}{int(res.counted.sum()):>7d}"
            f"{100 * res.relative_saving:>7.1f}%{res.max_edge_error_m / spacing:>10.1e}"
            f"{math.degrees(res.rms_shear_change_rad):>7.2f}°{res.evaluations:>7d}"
            f"{res.seconds:>8.1f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--fabric", default="plain-weave-600")
    parser.add_argument(
        "--asymmetry",
        type=float,
        default=None,
        help="scale of the negative-sense branch (illustrative fabric)",
    )
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--curved", action="store_true")
    parser.add_argument("--relax", action="store_true")
    args = parser.parse_args()
    print("command: python " + " ".join(sys.argv))
    law = load_library().shear_law(args.fabric)
    label = args.fabric
    if args.asymmetry is not None:
        law = ScaledNegative(law, args.asymmetry)
        label += f" with its negative branch x{args.asymmetry} (illustrative)"
    angle_study(law, label, args.repeat)
    if args.curved:
        curved_study(law, label)
    if args.relax:
        relax_study(law, label)


if __name__ == "__main__":
    main()
