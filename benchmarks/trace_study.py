"""Where the default study's wall time goes on the process engine: a timeline of one
``preform pipeline run`` read from the system calls that mark its stages (Linux, ``strace``).

Marks, in seconds from the command's start: the fork server's start (its ``execve``), the
first worker forked (the server's preload done), the run directory's first manifest (the
command has read the library and scenes and planned), every case's ``summary.json`` (by
worker), the run-level figure, the command's exit and the last process's exit. From them:
the fixed cost before the first case can start, each worker's busy span, and the tail after
the last case. The timeline is of one run under strace (which slows system calls a little);
the stages' shares are what it is for.

    python benchmarks/trace_study.py [--workers 2] [--engine process]
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

LINE = re.compile(r"^(\d+)\s+(\d+):(\d+):(\d+\.\d+)\s+(.*)$")


def seconds(h: str, m: str, s: str) -> float:
    return 3600 * int(h) + 60 * int(m) + float(s)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--engine", default="process")
    args = parser.parse_args()
    if shutil.which("strace") is None:
        raise SystemExit("needs strace (Linux): apt install strace")
    with tempfile.TemporaryDirectory(prefix="preform-trace-") as tmp:
        out, log = Path(tmp) / "out", Path(tmp) / "strace.txt"
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env["PYTHONPYCACHEPREFIX"] = str(Path(tmp) / "pycache")
        main = "import sys; from preform.__main__ import main; sys.argv = ['preform', *sys.argv[1:]]; main()"
        run = [sys.executable, "-c", main, "pipeline", "run", "--out", str(out)]
        run += ["--engine", args.engine, "--workers", str(args.workers)]
        subprocess.run(run, check=True, capture_output=True, env=env)  # fills the bytecode cache
        trace = [
            "strace",
            "-f",
            "--seccomp-bpf",
            "-tt",
            "-qq",
            "-e",
            "trace=execve,clone,clone3,rename,exit_group",
        ]
        subprocess.run(
            [*trace, "-o", str(log), *run, "--force"], check=True, capture_output=True, env=env
        )
        lines = log.read_text().splitlines()
    start = None
    command_pid = None
    marks: list[tuple[float, str]] = []
    server_pid = None
    first_fork = None
    workers: dict[str, list[tuple[float, str]]] = {}
    last_exit = 0.0
    for line in lines:
        m = LINE.match(line)
        if not m:
            continue
        pid, h, mi, s, call = m.groups()
        t = seconds(h, mi, s)
        if start is None:
            start, command_pid = t, pid
        t -= start
        if call.startswith("execve(") and "forkserver" in call:
            server_pid = pid
            marks.append((t, "fork server starts"))
        elif call.startswith("clone(") and pid == server_pid and first_fork is None:
            first_fork = t
            marks.append((t, "first worker forked (the server's preload done)"))
        elif call.startswith("rename(") and "manifest.json" in call and pid == command_pid:
            if not any("first manifest" in label for _, label in marks):
                marks.append((t, "first manifest (library, scenes and plan read)"))
        elif call.startswith("rename(") and call.rstrip().endswith("= 0"):
            target = call.split('", "')[-1].split('"')[0]
            if target.endswith("summary.json"):
                case = Path(target).parent.name
                workers.setdefault(pid, []).append((t, case))
            elif target.endswith("energy_vs_angle.png") and "/" in target:
                marks.append((t, "run-level figure written"))
        elif call.startswith("exit_group("):
            if pid == command_pid:
                marks.append((t, "command exits"))
            last_exit = max(last_exit, t)
    marks.append((last_exit, "last process exits"))
    print(f"preform pipeline run --engine {args.engine} --workers {args.workers}: timeline, s")
    for t, label in sorted(marks):
        print(f"{t:8.3f}  {label}")
    for pid, cases in workers.items():
        first, last = cases[0][0], cases[-1][0]
        names = ", ".join(c for _, c in cases)
        print(f"worker {pid}: {len(cases)} cases, first done {first:.3f}, last {last:.3f}: {names}")
    if workers:
        ends = [c[-1][0] for c in workers.values()]
        print(
            f"last case done {max(ends):.3f}; workers' last cases differ by {max(ends) - min(ends):.3f}"
        )


if __name__ == "__main__":
    main()
