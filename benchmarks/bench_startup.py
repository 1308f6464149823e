"""Start-up of the ``preform`` command against ``python -c "import numpy"``, as ratios.

Each command runs in a fresh interpreter (the installed ``preform`` entry point, i.e.
``preform.cli:main``, with this interpreter), best of ``--repeat`` wall-clock runs, all in the
same run so the ratios hold on a shared machine. Goal (issue 15): every ratio ≤ 2.

    python benchmarks/bench_startup.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time

MAIN = "import sys; from preform.cli import main; sys.argv = ['preform', *sys.argv[1:]]; main()"

COMMANDS: dict[str, list[str]] = {
    "import numpy": [sys.executable, "-c", "import numpy"],
    "preform --version": [sys.executable, "-c", MAIN, "--version"],
    "preform --help": [sys.executable, "-c", MAIN, "--help"],
    "preform materials list": [sys.executable, "-c", MAIN, "materials", "list"],
}


def best_of(argv: list[str], repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    times = {name: best_of(argv, args.repeat) for name, argv in COMMANDS.items()}
    base = times["import numpy"]
    print(f"{'command':<26}{'x import numpy':>16}")
    for name, seconds in times.items():
        print(f"{name:<26}{seconds / base:>16.2f}")
    print(f"best of {args.repeat}; goal: every preform command <= 2.00")


if __name__ == "__main__":
    main()
