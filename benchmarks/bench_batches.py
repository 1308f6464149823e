"""Batching small cases: a sweep of many small cases per batch size, as ratios.

The sweep: every fabric of the bundled library on ``--scenes`` small hemisphere scenes (a
50 mm ply at 5 mm spacing, the drape's values only, no files), so each case takes milliseconds
and what a run spends around its cases (sending each to a worker, recording its result in the
manifest and tables) shows. Each batch size runs the whole sweep on the same engine into its
own fresh results directory, sizes interleaved, best of ``--repeat``; wall time of
``run_cases`` (the engine's start-up included, the fork server already running).

    python benchmarks/bench_batches.py [--engine process] [--workers 2] [--scenes 12] [--repeat 2]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import yaml

from preform.command_line import load_library_or_exit
from preform.pipeline.runner import make_cases, run_cases
from preform.pipeline.scene import load_scene
from preform.plugin_manager import default_host

SIZES = (1, 2, 4, 8, 16, 32)


def small_scene(folder: Path, i: int) -> Path:
    path = folder / f"small-{i}.yaml"
    data = {
        "name": f"small-{i}",
        "tool": {"surface": "hemisphere", "radius_mm": 100 + i},
        "ply": {"node_spacing_mm": 5.0, "size_mm": [50, 50]},
        "start": {"point_mm": [0, 0], "orientation_deg": 0},
        "outputs": ["drape"],
    }
    path.write_text(yaml.safe_dump(data))
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="process")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--scenes", type=int, default=12)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--sizes", default=",".join(map(str, SIZES)))
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    host = default_host()
    library = load_library_or_exit((), bundled=True)
    with tempfile.TemporaryDirectory(prefix="preform-bench-batches-") as tmp:
        root = Path(tmp)
        scenes = []
        for i in range(args.scenes):
            path = small_scene(root, i)
            scenes.append(load_scene(path, host.registry))

        def sweep(out: Path, size: int | None) -> float:
            cases = make_cases(library, scenes, out, host)
            start = time.perf_counter()
            report = run_cases(
                cases, out, host, engine=args.engine, workers=args.workers, batch_size=size
            )
            elapsed = time.perf_counter() - start
            bad = [r for r in report.results if r.status not in ("ok", "partial")]
            if bad:
                raise SystemExit(f"{bad[0].case_id}: {bad[0].status} {bad[0].error}")
            return elapsed

        n = len(make_cases(library, scenes, root / "count", host))
        sweep(root / "warm", 1)  # starts the fork server, fills the caches
        load_before = os.getloadavg()
        times: dict[int, float] = {}
        for r in range(args.repeat):
            for size in sizes:
                seconds = sweep(root / f"b{size}-{r}", size)
                times[size] = min(times.get(size, float("inf")), seconds)
        load_after = os.getloadavg()
    print(f"{n} small cases, engine {args.engine}, {args.workers} workers, best of {args.repeat}")
    print(f"{'batch':>6}{'wall s':>9}{'ms/case':>9}{'x size 1':>10}")
    for size, seconds in times.items():
        print(
            f"{size:>6}{seconds:>9.3f}{1e3 * seconds / n:>9.2f}{times[sizes[0]] / seconds:>10.2f}"
        )
    print(f"load average before {load_before[0]:.2f}, after {load_after[0]:.2f}")


if __name__ == "__main__":
    main()
