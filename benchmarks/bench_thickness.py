"""Cost of the draped thickness model against the drape it belongs to.

For each bundled fabric: the default hemisphere drape (``api.drape``, outputs ``drape`` only:
the net and its energy) against the fabric's thickness model (``preform.drape.thickness``:
its sheared unit cell tabulated over |γ|), cold (first time in the process) and warm (kept in
memory). The ratio thickness/drape says what an output that needs a thickness (cells.csv, the
VTU, the FE exports) adds to a case. Best of ``--repeat`` runs (the machine may be shared).

    python benchmarks/bench_thickness.py [--repeat 3] [--fabrics NAME ...]
"""

from __future__ import annotations

import argparse
import time

from preform import api
from preform.drape import thickness


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


if __name__ == "__main__":
    main()
