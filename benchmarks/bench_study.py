"""The default 10-fabric study (``preform pipeline run``), wall time per engine, as ratios.

Every configuration runs the whole command in a fresh interpreter (start-up, library, cases,
run-level figure, tables) into its own results directory with ``--force``, best of
``--repeat``, all in the same run so the ratios hold on a shared machine. Configurations:

- ``baseline``: the serial engine on the default scene with the outputs it had before issue
  15 (a per-fabric ``energy_vs_angle.png`` besides the run-level Fig. 10);
- ``serial``: the serial engine on today's default scene;
- ``process``: today's default command, the process engine with ``--workers`` (2);
- ``dask``: a Dask LocalCluster of ``--workers`` worker processes (needs ``preform[dask]``).

Goals (issue 15): process ≥ 1.7× serial and dask ≥ 1.5× serial on 2 cores; the default study
≥ 3× the baseline. The load average before and after is printed: other work on the machine
makes every ratio smaller.

    python benchmarks/bench_study.py [--repeat 3] [--workers 2] [--engines baseline,serial,process,dask]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

from preform.pipeline.scene import default_scene_path

MAIN = "import sys; from preform.cli import main; sys.argv = ['preform', *sys.argv[1:]]; main()"
#: The default scene's outputs before issue 15 (the per-case E(α) figure carried Fig. 10).
OUTPUTS_BEFORE = ["energy_vs_angle", "optimum", "fibre_pattern_png", "energy_plot_png"]
OUTPUTS_BEFORE += ["library_energy_png", "cells_csv"]


def command(engine: str, scene: Path, out: Path, workers: int) -> list[str]:
    argv = [sys.executable, "-c", MAIN, "pipeline", "run", "--scene", str(scene)]
    argv += ["--out", str(out), "--force", "--engine", engine]
    if engine != "serial":
        argv += ["--workers", str(workers)]
    return argv


def best_of(argv: list[str], repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        done = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        elapsed = time.perf_counter() - start
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(argv[3:])} failed:\n{done.stderr[-2000:]}")
        best = min(best, elapsed)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--engines", default="baseline,serial,process,dask")
    args = parser.parse_args()
    wanted = [e.strip() for e in args.engines.split(",") if e.strip()]
    with tempfile.TemporaryDirectory(prefix="preform-bench-study-") as tmp:
        root = Path(tmp)
        today = default_scene_path()
        before = root / "scene-before.yaml"
        data = yaml.safe_load(today.read_text())
        data["outputs"] = OUTPUTS_BEFORE
        before.write_text(yaml.safe_dump(data))
        runs = {
            "baseline": command("serial", before, root / "baseline", args.workers),
            "serial": command("serial", today, root / "serial", args.workers),
            "process": command("process", today, root / "process", args.workers),
            "dask": command("dask", today, root / "dask", args.workers),
        }
        load_before = os.getloadavg()
        times: dict[str, float] = {}
        for _ in range(args.repeat):  # interleaved, so a burst of load hits every engine alike
            for name in wanted:
                times[name] = min(times.get(name, float("inf")), best_of(runs[name], 1))
        load_after = os.getloadavg()
    print(f"default study ({data['name']}), {os.cpu_count()} cores, best of {args.repeat}")
    print(f"{'engine':<10}{'wall s':>9}{'x baseline':>12}{'x serial':>10}")
    for name, seconds in times.items():
        base = times.get("baseline", float("nan")) / seconds
        serial = times.get("serial", float("nan")) / seconds
        print(f"{name:<10}{seconds:>9.2f}{base:>12.2f}{serial:>10.2f}")
    print(
        f"load average before {load_before[0]:.2f}, after {load_after[0]:.2f} "
        "(1 min; other work on the machine lowers every ratio)"
    )
    print("goals: process >= 1.70 x serial, dask >= 1.50 x serial, process >= 3.00 x baseline")


if __name__ == "__main__":
    main()
