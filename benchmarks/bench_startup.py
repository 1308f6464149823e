"""Start-up of the ``preform`` command against ``python -c "import numpy"``, as ratios.

Each command runs in a fresh interpreter (the installed ``preform`` entry point, i.e.
``preform.__main__:main``, with this interpreter), best of ``--repeat`` wall-clock runs, the
commands taking turns within each round so the ratios hold on a shared machine. Goal (issue 15): every
ratio ≤ 2. The ``cpu ms`` column is the processor time each process used (user + system, all
its threads; best of the rounds): load from other work stretches the wall clock far more than
it, so on a busy machine it tells whether a change did less work (numpy's includes its BLAS
threads starting, so it is not the ratios' baseline).

Bytecode: an installed package has its modules compiled (``pip install`` writes the ``.pyc``
files), and so do numpy's; an editable checkout run with ``PYTHONDONTWRITEBYTECODE=1`` (as on
the project's machine) compiles every preform module from source at every start, about 60 ms
that no user pays. So every command runs with a private bytecode cache (``PYTHONPYCACHEPREFIX``
set to a temporary directory, filled by one untimed run of each command first), numpy's and
preform's alike. ``--from-source`` keeps the environment as it is instead (the figures of
before 2026-12-01 late, issue 15c, were measured that way).

``--instructions`` counts instead the instructions each command executes (valgrind's
callgrind, user space, one run each after the untimed one): the same count to ~0.2 % from run
to run whatever else the machine does, so a change's effect shows on a shared machine where
the clock cannot (issue 15l). Instructions are not time (numpy's import starts BLAS threads
and maps many libraries, which the count weighs differently); use the ratios for the goal.

    python benchmarks/bench_startup.py [--repeat 5] [--from-source] [--instructions]
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

MAIN = (
    "import sys; from preform.__main__ import main; sys.argv = ['preform', *sys.argv[1:]]; main()"
)

COMMANDS: dict[str, list[str]] = {
    "import numpy": [sys.executable, "-c", "import numpy"],
    "preform --version": [sys.executable, "-c", MAIN, "--version"],
    "preform --help": [sys.executable, "-c", MAIN, "--help"],
    "preform materials list": [sys.executable, "-c", MAIN, "materials", "list"],
    # not a goal: what `materials list` cannot do without (it validates fabrics, whose models
    # are pydantic, one model built; the library is YAML; the CLI is click). Since issue 15j
    # the checks a listing runs are plain Python: numpy is not among them.
    "(import pydantic yaml click)": [
        sys.executable,
        "-c",
        "import pydantic, yaml, click\nclass M(pydantic.BaseModel):\n    x: int\nM(x=1)",
    ],
}


def run(argv: list[str], env: dict[str, str] | None) -> tuple[float, float]:
    """Wall-clock time [s] of one run, and the processor time [s] the process used (user +
    system, all its threads)."""
    start = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise subprocess.CalledProcessError(proc.returncode, argv)
    return wall, usage.ru_utime + usage.ru_stime


def instructions(argv: list[str], env: dict[str, str] | None) -> float:
    """Instructions [millions] one run of ``argv`` executes (callgrind's ``Collected``)."""
    with tempfile.TemporaryDirectory(prefix="preform-callgrind-") as out:
        done = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}/cg.out", *argv],
            capture_output=True,
            text=True,
            env=env,
            check=True,
        )
    found = re.search(r"Collected : (\d+)", done.stderr)
    if found is None:
        raise RuntimeError(f"no instruction count in valgrind's output:\n{done.stderr}")
    return int(found.group(1)) / 1e6


def best_of_each(repeat: int, env: dict[str, str] | None) -> dict[str, tuple[float, float]]:
    """Best wall-clock and best processor time of each command over ``repeat`` rounds, every
    round running each command once in turn: a burst of load on the shared machine then falls
    on all of them alike."""
    best = dict.fromkeys(COMMANDS, (float("inf"), float("inf")))
    for _ in range(repeat):
        for name, argv in COMMANDS.items():
            wall, cpu = run(argv, env)
            best[name] = (min(best[name][0], wall), min(best[name][1], cpu))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument(
        "--from-source",
        action="store_true",
        help="Keep the environment's bytecode setting (PYTHONDONTWRITEBYTECODE=1: every "
        "module of an editable install compiled at every start).",
    )
    parser.add_argument(
        "--instructions",
        action="store_true",
        help="Count each command's instructions with valgrind (callgrind) instead of timing it.",
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="preform-pycache-") as cache:
        env: dict[str, str] | None = None
        if not args.from_source:
            env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
            env["PYTHONPYCACHEPREFIX"] = cache
            for argv in COMMANDS.values():  # untimed: fills the bytecode cache
                run(argv, env)
        if args.instructions:
            if shutil.which("valgrind") is None:
                parser.error("--instructions needs valgrind on the PATH")
            count = {name: instructions(argv, env) for name, argv in COMMANDS.items()}
            print(f"{'command':<38}{'x import numpy':>16}{'M instr':>10}")
            for name, value in count.items():
                print(f"{name:<38}{value / count['import numpy']:>16.2f}{value:>10.1f}")
            print("instructions executed (callgrind, user space); not the goal's wall clock")
            return
        times = best_of_each(args.repeat, env)
    base = times["import numpy"][0]
    print(f"{'command':<38}{'x import numpy':>16}{'ms':>8}{'cpu ms':>8}")
    for name, (seconds, cpu) in times.items():
        print(f"{name:<38}{seconds / base:>16.2f}{1000 * seconds:>8.0f}{1000 * cpu:>8.0f}")
    bytecode = "compiled from source" if args.from_source else "bytecode cached"
    print(
        f"best of {args.repeat}, {bytecode}; goal: every preform command <= 2.00 (wall clock; "
        "cpu ms: processor time of the process, all threads, which load on a shared machine "
        "inflates less)"
    )


if __name__ == "__main__":
    main()
