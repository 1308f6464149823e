"""The default 10-fabric study (``preform pipeline run``), wall time per engine, as ratios.

Every configuration runs the whole command in a fresh interpreter (start-up, library, cases,
run-level figure, tables) into its own results directory with ``--force``, best of
``--repeat``, the configurations interleaved in the same run so the ratios hold on a shared
machine. Configurations:

- ``before``: the code before issue 15 (commit ``--before``, default e649036, the merge base of
  the issue-15 branch), as a user had it: ``preform pipeline run`` with its own default engine,
  workers and default scene. Its source is taken with ``git archive`` into a temporary
  directory and installed ``--no-deps`` into a throwaway venv that sees this venv's
  site-packages (a ``.pth`` file), so both run the same numpy, matplotlib, pandas;
  both are removed at the end;
- ``serial``: today's code, the serial engine, today's default scene;
- ``process``: today's default command, the process engine with ``--workers`` (2);
- ``dask``: a Dask LocalCluster of ``--workers`` worker processes (needs ``preform[dask]``).

Every configuration runs with one private bytecode cache (``PYTHONPYCACHEPREFIX``, without
``PYTHONDONTWRITEBYTECODE``), as ``bench_startup.py`` does: this machine sets
``PYTHONDONTWRITEBYTECODE=1``, so an editable checkout would compile every preform module from
source in every process it starts (the command, the fork server, each Dask worker), a cost no
installed copy pays and ``before``, installed by pip with its bytecode, did not pay either.
The first run of each configuration fills the cache (best of ``--repeat`` ≥ 2 drops it).

Goals (issue 15): process ≥ 1.7× serial and dask ≥ 1.5× serial on 2 cores; today's default
command ≥ 3× ``before``. The load average before and after is printed: other work on the
machine makes every ratio smaller.

``--scene NAME`` (repeatable) runs those bundled scenes over the library instead of the default
one, to see how the engines scale once a run holds more work than its fixed costs (the
three bundled min-energy scenes make 30 cases); ``before`` is not run then (its scenes differ).

    python benchmarks/bench_study.py [--repeat 2] [--workers 2] [--engines before,serial,process,dask]
    python benchmarks/bench_study.py --engines serial,process,dask --scene hemisphere-min-energy \
        --scene paraboloid-min-energy --scene hat-stiffener-min-energy

``--copies N`` runs N renamed copies of the default scene over the library instead (10 copies:
the 100-case sweep of issue 30's engine goals, process ≥ 1.8× and Dask ≥ 1.6× serial):

    python benchmarks/bench_study.py --engines serial,process,dask --copies 10 --repeat 1
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

import yaml

from preform.pipeline.scene import default_scene_path

#: The ``preform`` command as its console script runs it (``preform.__main__:main``).
MAIN = (
    "import sys; from preform.__main__ import main; sys.argv = ['preform', *sys.argv[1:]]; main()"
)
#: The same for the code before issue 15, whose entry point was ``preform.cli:main``.
BEFORE_MAIN = MAIN.replace("preform.__main__", "preform.cli")
REPO = Path(__file__).resolve().parents[1]
#: The merge base of the issue-15 branch: the code the study goal is measured against.
BEFORE_COMMIT = "e649036"


def command(
    python: str, engine: str | None, out: Path, workers: int, scenes: tuple[str, ...] = ()
) -> list[str]:
    """``preform pipeline run`` of ``scenes`` (none: the default scene) into ``out``;
    ``engine`` None: the command's own default engine and workers, as a user runs it."""
    main = MAIN if engine is not None else BEFORE_MAIN
    argv = [python, "-c", main, "pipeline", "run", "--out", str(out), "--force"]
    for scene in scenes:
        argv += ["--scene", scene]
    if engine is not None:
        argv += ["--engine", engine]
        if engine != "serial":
            argv += ["--workers", str(workers)]
    return argv


def install_before(commit: str, root: Path) -> str:
    """Install ``commit`` of this repository into a throwaway venv under ``root`` that sees
    this venv's site-packages; its python."""
    source = root / "before-src"
    source.mkdir()
    archive = subprocess.run(
        ["git", "-C", str(REPO), "archive", commit], check=True, capture_output=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(source)], input=archive, check=True)
    venv = root / "before-venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = str(venv / "bin" / "python")
    purelib = subprocess.run(
        [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    # after its own site-packages: its preform wins, numpy & co. come from this venv
    (Path(purelib) / "preform-bench-deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run(
        [python, "-m", "pip", "install", "-q", "--no-deps", str(source)],
        check=True,
        capture_output=True,
    )
    return python


def copy_default_scene(folder: Path, i: int) -> str:
    """A copy of the default scene under another name, written into ``folder``; its path."""
    scene = yaml.safe_load(default_scene_path().read_text())
    scene["name"] = f"{scene['name']}-copy-{i}"
    path = folder / f"copy-{i}.yaml"
    path.write_text(yaml.safe_dump(scene, sort_keys=False))
    return str(path)


def run_once(argv: list[str], env: dict[str, str]) -> float:
    start = time.perf_counter()
    done = subprocess.run(
        argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env
    )
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv[3:])} failed:\n{done.stderr[-2000:]}")
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--engines", default="before,serial,process,dask")
    parser.add_argument("--before", default=BEFORE_COMMIT, help="commit of the 'before' code")
    parser.add_argument("--scene", action="append", default=[], help="a bundled scene (repeatable)")
    parser.add_argument("--copies", type=int, default=0, help="copies of the default scene")
    args = parser.parse_args()
    wanted = [e.strip() for e in args.engines.split(",") if e.strip()]
    scenes = tuple(args.scene)
    if (scenes or args.copies) and "before" in wanted:
        raise SystemExit("--scene runs today's code only: leave 'before' out of --engines")
    with tempfile.TemporaryDirectory(prefix="preform-bench-study-") as tmp:
        root = Path(tmp)
        if args.copies:
            scenes += tuple(copy_default_scene(root, i) for i in range(args.copies))
        runs = {
            name: command(sys.executable, name, root / name, args.workers, scenes)
            for name in ("serial", "process", "dask")
        }
        if "before" in wanted:
            python = install_before(args.before, root)
            runs["before"] = command(python, None, root / "before", args.workers)
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env["PYTHONPYCACHEPREFIX"] = str(root / "pycache")
        load_before = os.getloadavg()
        times: dict[str, float] = {}
        for _ in range(args.repeat):  # interleaved, so a burst of load hits every engine alike
            for name in wanted:
                times[name] = min(times.get(name, float("inf")), run_once(runs[name], env))
        load_after = os.getloadavg()
    if args.copies:
        scenes = (f"{args.copies} copies of the default scene",)
    study = ", ".join(scenes) if scenes else f"default study ({default_scene_path().stem})"
    print(f"{study}, {os.cpu_count()} cores, best of {args.repeat}")
    print(f"{'engine':<10}{'wall s':>9}{'x before':>10}{'x serial':>10}")
    for name, seconds in times.items():
        before = times.get("before", float("nan")) / seconds
        serial = times.get("serial", float("nan")) / seconds
        print(f"{name:<10}{seconds:>9.2f}{before:>10.2f}{serial:>10.2f}")
    print(
        f"before = commit {args.before} (its default command: process engine, all cores); "
        f"load average before {load_before[0]:.2f}, after {load_after[0]:.2f} "
        "(1 min; other work on the machine lowers every ratio)"
    )
    print("goals: process >= 1.80 x serial, dask >= 1.60 x serial (issue 30, a 100-case sweep)")


if __name__ == "__main__":
    main()
