"""The compiled sphere fill of this checkout against another git revision's, A/B (issue 15).

Kernel edits move the fill by 10–30 %, under the noise of a shared machine between runs, so
the two versions are timed in alternating fresh processes, each version with its own numba
cache (numba's cache of a kernel is not invalidated when a function it calls changes in
another module, so versions must not share one): the other revision's ``core``, ``plugins``
and ``materials`` are exported (``git archive``) into a package tree put first on
``PYTHONPATH``. Each process reports the best processor time of the fill
(``info["fill_cpu_seconds"]``) of nine closed-form and nine Newton drapes of the unit
hemisphere at n × n nodes; the best over the rounds is printed per version.

    python benchmarks/bench_fill_ab.py [--rev main] [--n 401] [--rounds 3]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

PROBE = """
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.plugins.surfaces.basic import Hemisphere

def fill(n, closed_form):
    d = 2.0 / (n - 1) * (1 - 1e-12)
    net = drape(Hemisphere(1.0), start_xy_m=(0.0, 0.0), node_spacing_m=d,
                ply=PlyOutline.rectangle(((n - 1) * d, (n - 1) * d)),
                use_closed_form=closed_form)
    return float(net.info["fill_cpu_seconds"])

for closed_form in (True, False):
    fill(21, closed_form)  # compile or load the cache
    print(min(fill({n}, closed_form) for _ in range(9)))
"""


def export(rev: str, into: Path) -> Path:
    """``rev``'s package as an importable tree under ``into`` (core/ is preform/)."""
    into.mkdir(parents=True)
    archive = into / "rev.tar"
    with archive.open("wb") as out:
        subprocess.run(
            ["git", "archive", rev, "core", "plugins", "materials"],
            cwd=ROOT,
            stdout=out,
            check=True,
        )
    with tarfile.open(archive) as tar:
        tar.extractall(into, filter="data")
    package = into / "preform"
    (into / "core").rename(package)
    (into / "plugins").rename(package / "plugins")
    (into / "materials").rename(package / "materials")
    return into


def run(path: Path | None, cache: Path, n: int) -> tuple[float, float]:
    # a revision before issue 26 caches by NUMBA_CACHE_DIR, one after by PREFORM_KERNEL_CACHE
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), PREFORM_KERNEL_CACHE=str(cache))
    if path is not None:
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(path), env.get("PYTHONPATH")]))
    done = subprocess.run(
        [sys.executable, "-c", PROBE.format(n=n)], env=env, capture_output=True, text=True
    )
    if done.returncode:
        raise SystemExit(done.stderr)
    closed, newton = (float(line) for line in done.stdout.split())
    return closed, newton


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rev", default="main", help="the git revision to compare with")
    parser.add_argument("--n", type=int, default=401, help="nodes along each side")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="fill_ab_") as tmp:
        other = export(args.rev, Path(tmp) / "rev")
        versions = {args.rev: other, "this checkout": None}
        best = {name: (float("inf"), float("inf")) for name in versions}
        for _ in range(args.rounds):
            for name, path in versions.items():
                cache = Path(tmp) / f"cache-{'rev' if path else 'here'}"
                closed, newton = run(path, cache, args.n)
                best[name] = (min(best[name][0], closed), min(best[name][1], newton))
    for name, (closed, newton) in best.items():
        print(
            f"{name:<16}{args.n:>6}  closed-form fill {closed * 1e3:7.2f} ms"
            f"   Newton fill {newton * 1e3:7.2f} ms"
        )


if __name__ == "__main__":
    main()
