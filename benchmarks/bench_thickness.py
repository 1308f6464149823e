"""Cost of the draped thickness model against the drape it belongs to.

For each bundled fabric: the default hemisphere drape (``api.drape``, outputs ``drape`` only:
the net and its energy) against the fabric's thickness model (``preform.drape.properties.thickness``:
its sheared unit cell tabulated over |γ|), cold (first time in the process) and warm (kept in
memory). The ratio thickness/drape says what an output that needs a thickness (cells.csv, the
VTU, the FE exports) adds to a case. Best of ``--repeat`` runs (the machine may be shared).

Then the table itself (``PreformResponse.from_fabric``) against the table as it was before
issue 15h (``thickness_baseline.table``: one rebuilt cell per grid angle, the jamming fractions
by bisection), alternated in the same process, cold (jamming fractions solved afresh) and warm
(kept): their times, the speed-ups, and the largest relative difference of the thickness and
of the fibre fraction over the grid (0 when every value is bit-for-bit the old one).

    python benchmarks/bench_thickness.py [--repeat 3] [--fabrics NAME ...]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import thickness_baseline

from preform import api
from preform.drape.properties import thickness
from preform.drape.properties.preform_fields import PreformResponse
from preform.plugins.woven.tow_jamming import jamming_fraction


def best(call, repeat: int) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--fabrics", nargs="*", default=None)
    args = parser.parse_args()
    library = api.load_library()
    names = args.fabrics or library.names()
    api.drape(names[0])  # imports and compilation, not counted
    print(f"{'fabric':<22}{'model':<20}{'drape s':>9}{'cold s':>9}{'warm s':>9}{'cold/drape':>12}")
    for name in names:
        fabric = api.fabric(name, library)
        drape_s = best(lambda fabric=fabric: api.drape(fabric, outputs=["drape"]), args.repeat)

        def cold(fabric=fabric):  # type: ignore[no-untyped-def]
            thickness._TABLES.clear()
            return thickness.thickness_model(fabric)

        cold_s = best(cold, args.repeat)
        warm_s = best(lambda fabric=fabric: thickness.thickness_model(fabric), args.repeat)
        model = thickness.thickness_model(fabric).name
        print(
            f"{name:<22}{model[:19]:<20}{drape_s:>9.3f}{cold_s:>9.3f}{warm_s:>9.4f}"
            f"{cold_s / drape_s:>12.2f}"
        )
    table_against_baseline(library, names, args.repeat)


def table_against_baseline(library, names: list[str], repeat: int) -> None:  # type: ignore[no-untyped-def]
    """The table now against before, alternated: cold (the tows' jamming fractions solved
    afresh, as a process's first case of a fabric has them) and warm (kept per process)."""
    print()
    print(
        f"{'fabric':<22}{'angles':>7}{'cold before':>12}{'now':>8}{'x':>6}"
        f"{'warm before':>12}{'now':>8}{'x':>6}{'thickness Δ':>13}{'fraction Δ':>12}"
    )

    def cold_caches() -> None:
        jamming_fraction.cache_clear()
        thickness_baseline.jamming_fraction.cache_clear()

    for name in names:
        fabric = api.fabric(name, library)
        times: dict[tuple[str, str], list[float]] = {}
        for _ in range(repeat):
            for state in ("cold", "warm"):
                for which in ("before", "now"):
                    if state == "cold":
                        cold_caches()
                    start = time.perf_counter()
                    if which == "before":
                        grid, t_old, v_old = thickness_baseline.table(fabric)
                    else:
                        response = PreformResponse.from_fabric(fabric)
                    times.setdefault((state, which), []).append(time.perf_counter() - start)
        assert response is not None and np.array_equal(grid, response.shear)
        d_t = float(np.max(np.abs(response.thickness / t_old - 1.0)))
        d_v = float(np.max(np.abs(response.fibre_volume_fraction / v_old - 1.0)))
        locked = int(np.count_nonzero(grid >= response.locking_angle))
        best = {k: min(v) for k, v in times.items()}
        cells = "".join(
            f"{best[(state, 'before')]:>12.4f}{best[(state, 'now')]:>8.4f}"
            f"{best[(state, 'before')] / best[(state, 'now')]:>6.0f}"
            for state in ("cold", "warm")
        )
        print(f"{name:<22}{locked:>7}{cells}{d_t:>13.1e}{d_v:>12.1e}")


if __name__ == "__main__":
    main()
