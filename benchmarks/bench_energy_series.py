"""The polynomial laws' exact energy in its series form against the closed form it replaced.

``PiecewiseBranch`` now integrates each piece of p·cos as one polynomial (p times cos's Taylor
series about the piece's start); before, it subtracted the closed-form primitive S·sin + S'·cos
at the piece's start from its value at the angle (frozen in ``closed_form_energy_baseline.py``).
Both are built from the same laws in one process and timed alternately, processor time, best of
``--repeat``, pinned to one core:

- ``energy``: W at ``--angles`` signed angles uniform in ±60° (the range drapes shear to), what
  a drape at ``table: exact`` fidelity pays per net;
- ``build``: the law built from its parameters plus its tabulated surrogate (both senses at the
  default 0.25° step), what every case pays once.

Laws: the bundled polynomial and stitch-polynomial fabrics (E-BX-318 with its failure drop),
an illustrative tabulated force curve, and the degree-7 force polynomial hypothesis found
(F = (γ/deg)⁵ − 0.001·(γ/deg)⁷ N/mm, held past 60°). The last columns compare the two: the
largest relative difference at |γ| ≥ 1°, and near zero shear (|γ| < 1°) the largest difference
relative to the series form's W, where the closed form's rounding of its ~1e16 J/m² terms shows.
Then both forms' relative error against the exact energy (the closed form in high precision,
``exact_piece_energy`` of tests/shear/test_energy_rounding.py, mpmath) for ncf-0-90-tricot's
force polynomial from 1e-6° to 60°.

    python benchmarks/bench_energy_series.py [--angles 1000000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import math
import os
import pathlib
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from closed_form_energy_baseline import ClosedFormBranch, closed_form_path

from preform.library import load_library
from preform.shear.energy import PiecewiseBranch
from preform.shear.laws import (
    PolynomialParams,
    TabulatedParams,
    build_polynomial,
    build_tabulated,
    degree_polynomial_to_radians,
)
from preform.shear.surrogate import TabulatedSurrogate

if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def cpu(call: Callable[[], Any]) -> float:
    start = time.process_time()
    call()
    return time.process_time() - start


def law_builders() -> dict[str, Callable[[], Any]]:
    library = load_library()
    bundled = {
        name: (lambda name=name: library.shear_law(name))
        for name in ("ncf-0-90-tricot", "E-BXhd-936", "E-BX-318")
    }
    degree_seven = PolynomialParams.model_construct(
        law="polynomial",
        force_coefficients_N_per_mm=[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -0.001],
        max_angle_deg=60.0,
        beyond_range="hold",
    )
    tabulated = TabulatedParams.model_validate(
        {  # illustrative force curve [N/mm], not a measured fabric
            "law": "tabulated",
            "angle_deg": [0, 10, 20, 30, 40, 50, 60],
            "force_N_per_mm": [0.0, 0.01, 0.03, 0.06, 0.12, 0.25, 0.5],
            "beyond_range": "hold",
        }
    )
    return {
        **bundled,
        "tabulated (illustrative)": lambda: build_tabulated(tabulated),
        "degree-7 polynomial": lambda: build_polynomial(degree_seven),
    }


def measure(
    name: str,
    build: Callable[[], Any],
    gamma: np.ndarray,
    near_zero: np.ndarray,
    far: np.ndarray,
    repeat: int,
) -> None:
    """One table row: both forms of ``build``'s law timed alternately, and compared."""
    series_law = build()
    with closed_form_path():
        closed_law = build()
    times: dict[str, list[float]] = {"energy": [], "old energy": [], "build": [], "old build": []}
    for _ in range(repeat):
        times["energy"].append(cpu(lambda: series_law.energy(gamma)))
        times["old energy"].append(cpu(lambda: closed_law.energy(gamma)))
        times["build"].append(cpu(lambda: TabulatedSurrogate(build())))
        with closed_form_path():
            times["old build"].append(cpu(lambda: TabulatedSurrogate(build())))
    best = {key: min(value) for key, value in times.items()}
    w_far, old_far = series_law.energy(far), closed_law.energy(far)
    w_near, old_near = series_law.energy(near_zero), closed_law.energy(near_zero)
    with np.errstate(divide="ignore", invalid="ignore"):
        diff_far = np.nanmax(np.abs(old_far - w_far) / w_far)
        diff_near = np.nanmax(np.where(w_near > 0, np.abs(old_near - w_near) / w_near, 0.0))
    print(
        f"{name:26s} {best['energy']:9.4f} {best['old energy']:8.4f}"
        f" {best['energy'] / best['old energy']:6.2f} {best['build']:8.4f}"
        f" {best['old build']:8.4f} {best['build'] / best['old build']:6.2f}"
        f" {diff_far:11.1e} {diff_near:10.1e}"
    )


def against_exact() -> None:
    """Relative error of both forms against the exact W of ncf-0-90-tricot's force polynomial."""
    sys.path.insert(0, str(pathlib.Path(__file__).parents[1] / "tests" / "shear"))
    from test_energy_rounding import exact_piece_energy

    force = degree_polynomial_to_radians([0.0, 1.2e-3, 2.5e-5]) * 1000.0  # N/m, as the law
    series = PiecewiseBranch([0.0], [force], weight="cos")
    closed = ClosedFormBranch([0.0], [force], weight="cos")
    print("ncf-0-90-tricot force polynomial, relative error of W against the exact energy")
    print(f"{'angle deg':>10s} {'series':>9s} {'closed':>9s}")
    for degrees in [1e-6, 1e-3, 0.1, 1.0, 10.0, 60.0]:
        u = math.radians(degrees)
        exact = exact_piece_energy(list(force), 0.0, u, "cos")
        print(
            f"{degrees:10g} {float(series.energy(u)) / exact - 1:9.1e}"
            f" {float(closed.energy(u)) / exact - 1:9.1e}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--angles", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(20261202)
    gamma = rng.uniform(-math.radians(60.0), math.radians(60.0), args.angles)
    near_zero = np.concatenate(
        [-np.geomspace(1e-12, math.radians(1.0), 200), np.geomspace(1e-12, math.radians(1.0), 200)]
    )
    far = np.concatenate(
        [
            -np.linspace(math.radians(1.0), math.pi / 2, 200),
            np.linspace(math.radians(1.0), math.pi / 2, 200),
        ]
    )
    print(f"{args.angles} angles, best of {args.repeat}, processor time, one core")
    print(
        f"{'law':26s} {'energy s':>9s} {'old s':>8s} {'ratio':>6s} {'build s':>8s} {'old s':>8s}"
        f" {'ratio':>6s} {'diff >=1deg':>11s} {'diff <1deg':>10s}"
    )
    for name, build in law_builders().items():
        measure(name, build, gamma, near_zero, far, args.repeat)
    against_exact()


if __name__ == "__main__":
    main()
