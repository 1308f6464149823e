"""The first run after an install against a warm run of the default study (issue 26).

Each round runs the default command (``preform pipeline run``, the process engine with
``--workers`` 2, the README's main job) twice in fresh interpreters, side by side: ``first``
with an empty kernel cache (``PREFORM_KERNEL_CACHE`` pointed at a new temporary folder: what
the first run after installing a new version meets), then ``warm`` on the cache that run
filled. The ratio first ÷ warm is per round (both halves of a round see about the same load);
goal ≤ 2. The compile time the first run printed is shown too.

Both runs share one private bytecode cache (``PYTHONPYCACHEPREFIX``, filled by an untimed run
first, on the user's own kernel cache), as ``bench_study.py`` explains: an editable checkout on a machine that sets
``PYTHONDONTWRITEBYTECODE`` would otherwise compile preform's modules from source in every
process, a cost no installed copy pays.

    python benchmarks/bench_first_run.py [--rounds 1] [--workers 2]

Each round costs the compile (20-60 s of one core here) and two runs: keep the rounds few on a
shared machine.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from preform.drape.kernels.kernel_cache import CACHE_ENV

MAIN = (
    "import sys; from preform.__main__ import main; sys.argv = ['preform', *sys.argv[1:]]; main()"
)


def run(out: Path, cache: Path | None, workers: int, env: dict[str, str]) -> tuple[float, str]:
    """Wall time [s] of one ``preform pipeline run`` and its stderr; ``cache`` is the kernel
    cache (None: the user's own)."""
    command = [sys.executable, "-c", MAIN, "pipeline", "run", "--out", str(out), "--force"]
    command += ["--workers", str(workers)]
    start = time.perf_counter()
    if cache is not None:
        env = {**env, CACHE_ENV: str(cache)}
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode:
        raise SystemExit(f"pipeline run failed ({done.returncode}):\n{done.stderr}")
    return wall, done.stderr


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="first_run_") as tmp:
        env = dict(os.environ, PYTHONPYCACHEPREFIX=str(Path(tmp) / "pycache"))
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env.pop("NUMBA_CACHE_DIR", None)
        load = os.getloadavg()[0]
        run(Path(tmp) / "out", None, args.workers, env)  # untimed: fills the bytecode cache
        rows = []
        for i in range(args.rounds):
            cache = Path(tmp) / f"cache-{i}"
            first, said = run(Path(tmp) / "out", cache, args.workers, env)
            warm, _ = run(Path(tmp) / "out", cache, args.workers, env)
            found = re.search(r"compiled in ([0-9.]+) s", said)
            rows.append((first, warm, float(found.group(1)) if found else float("nan")))
    print(f"default study, process engine, {args.workers} workers, empty kernel cache vs warm")
    print(f"{'round':>5} {'first s':>8} {'warm s':>7} {'compile s':>9} {'first/warm':>10}")
    for i, (first, warm, compile_s) in enumerate(rows, 1):
        print(f"{i:>5} {first:8.2f} {warm:7.2f} {compile_s:9.2f} {first / warm:10.2f}")
    print(f"load average before {load:.2f}, after {os.getloadavg()[0]:.2f} (1 min); goal <= 2")


if __name__ == "__main__":
    main()
