"""The Dask engine's fixed costs inside one ``preform pipeline run`` (issue 15k).

Runs the command in this interpreter with the Dask engine (a LocalCluster of ``--workers``)
and prints, in seconds from this script's start: when the run asked for its engine (the command
had read library and scenes), when the engine was ready (every worker warm), the first case
sent, the first and last results back, and the engine's closing. The LocalCluster opens ahead
in a thread from the command's start, so "asked -> ready" is only what the run waited for.
Repeat it, alternating with other work, on a quiet machine: every figure grows with the load.

    python benchmarks/trace_dask_engine.py [--repeat 3] [--workers 2] [--out DIR]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

ONE_RUN = r"""
import sys, time
T0 = time.perf_counter()
from preform.pipeline import engines, runner

marks, results = {}, []


def mark(what):
    marks.setdefault(what, time.perf_counter() - T0)


open_engine = runner.open_engine


def traced_open(name, **kwargs):
    mark("asked")
    engine = open_engine(name, **kwargs)
    mark("ready")
    submit, close = engine.submit, engine.close

    def traced_submit(*args, **kw):
        mark("first sent")
        future = submit(*args, **kw)
        future.add_done_callback(lambda _: results.append(time.perf_counter() - T0))
        return future

    def traced_close():
        mark("close")
        close()
        mark("closed")

    engine.submit, engine.close = traced_submit, traced_close
    return engine


runner.open_engine = traced_open
from preform.cli import main

sys.argv = ["preform", "pipeline", "run", "--engine", "dask", *sys.argv[1:]]
code = 0
try:
    main()
except SystemExit as exc:  # the command's exit code, passed on after the trace is printed
    code = exc.code if isinstance(exc.code, int) else 1
mark("exit")
if results:
    print("TRACE", *(f"{k}={v:.2f}" for k, v in marks.items()),
          f"first result={results[0]:.2f}", f"last result={results[-1]:.2f}")
sys.exit(code)
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default=None, help="results directory (default: temporary)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or os.path.join(tmp, "dask")
        for _ in range(args.repeat):
            load = os.getloadavg()[0]
            argv = ["--out", out, "--force", "--workers", str(args.workers)]
            t0 = time.perf_counter()
            proc = subprocess.run(
                [sys.executable, "-c", ONE_RUN, *argv], capture_output=True, text=True
            )
            wall = time.perf_counter() - t0
            trace = [line for line in proc.stdout.splitlines() if line.startswith("TRACE")]
            if proc.returncode not in (0, 1) or not trace:
                sys.exit(f"the run failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
            failed = "  (some cases failed: exit 1)" if proc.returncode else ""
            print(f"{trace[-1][6:]}  wall={wall:.2f}  (load {load:.1f}){failed}")


if __name__ == "__main__":
    main()
