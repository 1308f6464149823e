"""The first run after an install against a warm run of the default study (issue 26).

Each round runs the default command (``preform pipeline run``, the process engine with
``--workers`` 2, the README's main job) twice in fresh interpreters, side by side: ``first``
with an empty kernel cache (``PREFORM_KERNEL_CACHE`` pointed at a new temporary folder: what
the first run after installing a new version meets), then ``warm`` on the cache that run
filled. The ratio first ÷ warm is per round (both halves of a round see about the same load);
goal ≤ 2. The compile time the first run printed is shown too (none: nothing compiled).

Two installs are measured. ``installed``: this checkout's last commit built into a wheel and
installed the way the README says (``pip install .``, build isolation: the build compiles the
kernels into the package, ``build_hooks/preform_build.py``) into a throwaway venv that sees
this venv's other packages (``bench_study.install_before``); the build's wall time is printed
once, as ``install s``. ``source`` (``--source``): this editable checkout, which compiles at
its first run.

Both runs share one private bytecode cache (``PYTHONPYCACHEPREFIX``, filled by an untimed run
first, on the user's own kernel cache), as ``bench_study.py`` explains: an editable checkout on
a machine that sets ``PYTHONDONTWRITEBYTECODE`` would otherwise compile preform's modules from
source in every process, a cost no installed copy pays.

    python benchmarks/bench_first_run.py [--rounds 3] [--workers 2] [--source]

A ``source`` round costs the compile (20-60 s of one core here); the build of ``installed``
costs it once (with pip installing the build's requirements, 1-2 minutes).
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

from bench_study import install_before

from preform.base.kernel_cache import CACHE_ENV

MAIN = (
    "import sys; from preform.__main__ import main; sys.argv = ['preform', *sys.argv[1:]]; main()"
)


def run(
    python: str, out: Path, cache: Path | None, workers: int, env: dict[str, str]
) -> tuple[float, str]:
    """Wall time [s] of one ``preform pipeline run`` and its stderr; ``cache`` is the kernel
    cache (None: the user's own)."""
    command = [python, "-c", MAIN, "pipeline", "run", "--out", str(out), "--force"]
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
    parser.add_argument("--source", action="store_true", help="measure the editable checkout too")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="first_run_") as tmp:
        root = Path(tmp)
        env = dict(os.environ, PYTHONPYCACHEPREFIX=str(root / "pycache"))
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env.pop("NUMBA_CACHE_DIR", None)
        load = os.getloadavg()[0]
        start = time.perf_counter()
        pythons = {"installed": install_before("HEAD", root)}
        install_s = time.perf_counter() - start
        if args.source:
            pythons["source"] = sys.executable
        for python in pythons.values():  # untimed: fills the bytecode cache
            run(python, root / "out", None, args.workers, env)
        rows = []
        for i in range(args.rounds):
            for name, python in pythons.items():
                cache = root / f"cache-{name}-{i}"
                first, said = run(python, root / "out", cache, args.workers, env)
                warm, _ = run(python, root / "out", cache, args.workers, env)
                found = re.search(r"compiled in ([0-9.]+) s", said)
                rows.append((name, first, warm, float(found.group(1)) if found else None))
    print(f"default study, process engine, {args.workers} workers, empty kernel cache vs warm")
    print(f"installed: wheel built and installed in {install_s:.1f} s (its kernels compiled)")
    print(f"{'install':>9} {'first s':>8} {'warm s':>7} {'compile s':>9} {'first/warm':>10}")
    for name, first, warm, compile_s in rows:
        said = "none" if compile_s is None else f"{compile_s:.2f}"
        print(f"{name:>9} {first:8.2f} {warm:7.2f} {said:>9} {first / warm:10.2f}")
    print(f"load average before {load:.2f}, after {os.getloadavg()[0]:.2f} (1 min); goal <= 2")


if __name__ == "__main__":
    main()
