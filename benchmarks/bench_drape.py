"""Speed of the pin-jointed-net engine: nodes placed per second and peak memory.

A square ply of side 2R centred on the pole of a unit hemisphere, α = 90°, n × n nodes; the
closed-form (sphere) placement and, for the smaller nets, the general Newton placement that any
surface gets. Time is the best of ``--repeat`` runs (the machine may be shared); peak memory is
traced by tracemalloc on a separate run, since tracing slows numpy down.

    python benchmarks/bench_drape.py [--sizes 25 50 100 200 500 1000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np

from preform.drape.net import drape
from preform.drape.ply import PlyOutline
from preform.plugins.surfaces.basic import Hemisphere


def run(n: int, closed_form: bool) -> tuple[int, float]:
    radius = 1.0
    d = 2.0 * radius / (n - 1) * (1 - 1e-12)
    side = (n - 1) * d
    start = time.perf_counter()
    result = drape(
        Hemisphere(radius),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=d,
        ply=PlyOutline.rectangle((side, side)),
        use_closed_form=closed_form,
    )
    return result.nodes_placed, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=int, nargs="+", default=[25, 50, 100, 200, 500, 1000])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--newton-max", type=int, default=500, help="largest n for Newton runs")
    args = parser.parse_args()
    print(
        f"{'placement':<12}{'n':>6}{'nodes':>10}{'placed':>10}{'time s':>10}"
        f"{'nodes/s':>12}{'peak MB':>10}{'B/node':>8}"
    )
    for closed_form in (True, False):
        for n in args.sizes:
            if not closed_form and n > args.newton_max:
                continue
            best = np.inf
            placed = 0
            for _ in range(args.repeat):
                placed, seconds = run(n, closed_form)
                best = min(best, seconds)
            tracemalloc.start()
            run(n, closed_form)
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            label = "closed form" if closed_form else "newton"
            print(
                f"{label:<12}{n:>6}{n * n:>10}{placed:>10}{best:>10.3f}{placed / best:>12.3g}"
                f"{peak / 1e6:>10.1f}{peak / (n * n):>8.0f}"
            )


if __name__ == "__main__":
    main()
