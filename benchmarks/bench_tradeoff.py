"""The speed/accuracy trade of the fidelity knobs on a scene: the table in benchmarks/README.md.

Runs ``preform.bench.tradeoff.run_tradeoff`` (the same study as ``preform bench tradeoff``) on one
core, prints the table and the reference's convergence, and writes tradeoff.csv and
tradeoff.png to ``--out``. Short runs are timed ``--repeat`` times (best kept), since the
machine may be shared; see ``preform.bench.tradeoff`` for what every column means.

    python benchmarks/bench_tradeoff.py [--scene hemisphere-min-energy] [--material E-BX-318]
                                        [--out preform-bench] [--repeat 3] [--quick]
"""

from __future__ import annotations

import os

# One core, as bench_search: BLAS threads and the process pinned before numpy loads.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from preform.bench.tradeoff import (  # noqa: E402
    DEFAULT_MATERIAL,
    DEFAULT_SCENE,
    TradeoffRow,
    describe_reference,
    format_table,
    plot_tradeoff,
    run_tradeoff,
    write_csv,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--scene", default=DEFAULT_SCENE)
    parser.add_argument("--material", default=DEFAULT_MATERIAL)
    parser.add_argument("--out", default="preform-bench")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    print("command: python " + " ".join(sys.argv))
    print(f"date: {time.strftime('%Y-%m-%d')}; one core of {os.cpu_count()}")

    def show(row: TradeoffRow) -> None:
        print(f"  done {row.label:<16} {row.wall_s:8.2f} s", file=sys.stderr, flush=True)

    clock = time.perf_counter()
    result = run_tradeoff(
        args.scene, args.material, quick=args.quick, repeat=args.repeat, progress=show
    )
    out = Path(args.out)
    write_csv(result, out / "tradeoff.csv")
    plot_tradeoff(result, out / "tradeoff.png")
    print(f"{result.scene}, {result.material}; wall times relative to '{result.baseline_label}'")
    print(format_table(result))
    print(describe_reference(result))
    print(f"study took {time.perf_counter() - clock:.0f} s; wrote {out}/tradeoff.csv, .png")


if __name__ == "__main__":
    main()
