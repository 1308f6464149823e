"""The compiled net kernels against the numpy path they replaced (issue 15), in one process.

Three timings of processor time, each the best of ``--repeat`` runs of the compiled code and of the frozen numpy
copy in ``numpy_baseline.py`` (the drape path as it was before the kernels), alternated so that
load on a shared machine hits both alike; the ratio is what is reported:

- closed-form sphere drape: a square ply of side 2R on the pole of a unit hemisphere, α = 90°,
  n × n nodes (``--n``, default 1001); the wavefront fill alone (``info["fill_cpu_seconds"]``) and
  the whole ``drape`` call (generators and cell fields included);
- general Newton placement: the same drape with ``use_closed_form=False`` (``--newton-n``):
  every node by Newton on the constraint circle, generators marched in sub-steps;
- the pipeline's drape step (``run_drape``) of the default hemisphere scene with the
  mechanistic plain-weave law (``plain-weave-600``) at n × n nodes, energy field, summary and
  verdict included;
- every other analytic tool (plate, cylinder, flanged hemisphere, cones, ellipsoid and
  paraboloid domes) through the single compiled fill against the vectorised path it took
  before its compiled queries: the Python front loop of today's engine with the tool's numpy
  queries, frozen in ``numpy_surfaces.py`` (``--tools-n``, and ``--tools-large-n`` for the
  tools named in ``--large-tools``); a ply larger than the tool, so the net runs over its edges.

Then the peak memory per node of the drape and of the step (tracemalloc, separate runs; numba
allocates only per-front buffers of its own, every net-sized array comes from numpy), and the
agreement of the two paths (largest node distance over d; energy relative difference).

    python benchmarks/bench_kernels.py [--n 1001] [--newton-n 1001] [--repeat 3]
        [--tools-n 145] [--tools-large-n 1001] [--large-tools plane,flanged-hemisphere]
        [--only tools]
"""

from __future__ import annotations

import argparse
import contextlib
import pathlib
import tempfile
import time
import tracemalloc
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import numpy_surfaces
from numpy_baseline import drape as numpy_drape
from numpy_baseline import numpy_path

import preform
from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.drape.steps import run_drape
from preform.plugins.surfaces import basic, domes
from preform.plugins.surfaces.basic import Hemisphere
from preform.step import CaseContext


def sphere_drape(run: Callable[..., Any], n: int, closed_form: bool) -> Any:
    d = 2.0 / (n - 1) * (1 - 1e-12)
    return run(
        Hemisphere(1.0),
        start_xy_m=(0.0, 0.0),
        node_spacing_m=d,
        ply=PlyOutline.rectangle(((n - 1) * d, (n - 1) * d)),
        use_closed_form=closed_form,
    )


def step_context(n: int) -> CaseContext:
    """The drape step's context for the default hemisphere scene at n × n nodes."""
    case = preform.drape("plain-weave-600", node_spacing_mm=5, generator_angle_deg=80)
    ply = case.scene.ply.model_copy(update={"node_spacing_mm": 360.0 / (n - 1)})
    scene = case.scene.model_copy(update={"ply": ply})
    out = pathlib.Path(tempfile.mkdtemp(prefix="bench_kernels_"))
    ctx = CaseContext(case.fabric, scene, preform.default_host().registry, out)
    ctx.products.update({k: v for k, v in case.products.items() if k != "drape"})
    return ctx


def timed(call: Callable[[], Any]) -> tuple[float, Any]:
    """Processor time [s] of ``call`` (both paths are single-threaded; on a shared machine
    processor time is far steadier than wall time) and its value."""
    start = time.process_time()
    value = call()
    return time.process_time() - start, value


def peak_bytes(call: Callable[[], Any]) -> int:
    tracemalloc.start()
    call()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak


@contextlib.contextmanager
def nothing() -> Iterator[None]:
    yield


def race(label: str, n: int, repeat: int, runs: dict[str, Callable[[], Any]]) -> str:
    """Best fill and drape processor times of the "compiled" and "numpy" drapes ``runs``,
    alternated ``repeat`` times, and how their nets agree: the report line."""
    best = {name: (np.inf, np.inf) for name in runs}
    results: dict[str, Any] = {}
    for _ in range(repeat):
        for name, run in runs.items():
            seconds, result = timed(run)
            fill = float(result.info["fill_cpu_seconds"])
            best[name] = (min(best[name][0], fill), min(best[name][1], seconds))
            results[name] = result
    a, b = results["compiled"], results["numpy"]
    same_status = bool(np.array_equal(a.status, b.status))
    both = np.isfinite(a.nodes[..., 0]) & np.isfinite(b.nodes[..., 0])
    gap = float(np.max(np.linalg.norm(a.nodes[both] - b.nodes[both], axis=-1))) / a.node_spacing
    (fill_c, all_c), (fill_n, all_n) = best["compiled"], best["numpy"]
    return (
        f"{label:<20}{n:>6}  fill {fill_n:7.3f} s -> {fill_c:7.3f} s ({fill_n / fill_c:5.1f}x)"
        f"   drape {all_n:7.3f} s -> {all_c:7.3f} s ({all_n / all_c:5.1f}x)"
        f"   same statuses {same_status}, nodes within {gap:.1e} d"
    )


def compare_drapes(n: int, closed_form: bool, repeat: int) -> None:
    label = "closed-form sphere" if closed_form else "general Newton"
    runs = {
        "compiled": lambda: sphere_drape(drape, n, closed_form),
        "numpy": lambda: sphere_drape(numpy_drape, n, closed_form),
    }
    print(race(label, n, repeat, runs))


def compare_steps(n: int, repeat: int) -> None:
    ctx = step_context(n)
    best = {"compiled": np.inf, "numpy": np.inf}
    energy: dict[str, float] = {}
    for _ in range(repeat):
        for name, path in (("compiled", nothing), ("numpy", numpy_path)):
            with path():
                seconds, out = timed(lambda: run_drape(ctx))
            best[name] = min(best[name], seconds)
            energy[name] = float(out["drape"].energy.total_energy)
    rel = abs(energy["compiled"] - energy["numpy"]) / abs(energy["numpy"])
    print(
        f"{'drape step':<20}{n:>6}  plain-weave-600 {best['numpy']:7.3f} s -> "
        f"{best['compiled']:7.3f} s ({best['numpy'] / best['compiled']:5.1f}x)"
        f"   energy {energy['compiled']:.6g} J, relative difference {rel:.1e}"
    )
    nodes = n * n
    for name, path in (("compiled", nothing), ("numpy", numpy_path)):
        runner = numpy_drape if name == "numpy" else drape
        net = peak_bytes(lambda runner=runner: sphere_drape(runner, n, True))
        with path():
            step = peak_bytes(lambda: run_drape(ctx))
        print(
            f"{'memory':<20}{n:>6}  {name:<9} drape {net / nodes:6.0f} B/node"
            f"   drape step with energy {step / nodes:6.0f} B/node"
        )


#: name -> (class, args, kwargs, start xy [m], ply side [m], closed form): built from preform
#: and from the frozen numpy copy alike.
TOOLS: dict[str, tuple[str, tuple[Any, ...], dict[str, Any], tuple[float, float], float, bool]] = {
    "plane": ("Plane", ((1.0, 0.8),), {}, (0.1, -0.15), 1.0, True),
    "cylinder": ("Cylinder", (0.3, 1.0, "x"), {}, (0.05, 0.1), 1.2, False),
    "flanged-hemisphere": ("FlangedHemisphere", (0.1, 0.02, 0.2), {}, (0.0, 0.0), 0.5, False),
    "cone": ("Cone", (0.1, 0.08), {}, (0.0, 0.0), 0.3, False),
    "truncated-cone": ("Cone", (0.1, 0.05), {"top_radius_m": 0.03}, (0.0, 0.0), 0.3, False),
    "ellipsoid-dome": ("EllipsoidDome", ((0.12, 0.08, 0.05),), {}, (0.0, 0.0), 0.3, False),
    "paraboloid-dome": ("ParaboloidDome", (0.1, 0.06), {}, (0.0, 0.0), 0.3, False),
}


def tool_drape(tool: Any, n: int, start: tuple[float, float], side: float, closed: bool) -> Any:
    d = side / (n - 1)
    return drape(
        tool,
        start_xy_m=start,
        node_spacing_m=d,
        ply=PlyOutline.rectangle((side, side)),
        orientation_rad=0.3,
        generator_angle_rad=1.45,
        use_closed_form=closed,
    )


def compare_tool(name: str, n: int, repeat: int) -> str:
    """The report line of the analytic tool ``name`` at n × n nodes."""
    cls, args, kwargs, start, side, closed = TOOLS[name]
    module = basic if cls in ("Plane", "Cylinder") else domes
    compiled = getattr(module, cls)(*args, **kwargs)
    frozen = getattr(numpy_surfaces, cls)(*args, **kwargs)
    runs = {
        "compiled": lambda: tool_drape(compiled, n, start, side, closed),
        "numpy": lambda: tool_drape(frozen, n, start, side, closed),
    }
    return race(name, n, repeat, runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=1001, help="nodes along each side")
    parser.add_argument("--newton-n", type=int, default=1001, help="n for the Newton runs")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--tools-n", type=int, default=145, help="n for every analytic tool")
    parser.add_argument("--tools-large-n", type=int, default=1001, help="n for --large-tools")
    parser.add_argument(
        "--large-tools",
        default="plane,flanged-hemisphere",
        help="comma-separated tools also run at --tools-large-n (none: empty)",
    )
    parser.add_argument(
        "--only", choices=("sphere", "tools"), help="run only the sphere rows or the tool rows"
    )
    args = parser.parse_args()
    # compile (or load the compiled cache) before timing anything
    sphere_drape(drape, 21, True)
    sphere_drape(drape, 21, False)
    run_drape(step_context(21))
    if args.only != "tools":
        compare_drapes(args.n, True, args.repeat)
        compare_drapes(args.newton_n, False, args.repeat)
        compare_steps(args.n, args.repeat)
    if args.only != "sphere":
        for name in TOOLS:
            compare_tool(name, 21, 1)  # compile its queries first
        for name in TOOLS:
            print(compare_tool(name, args.tools_n, args.repeat))
        for name in filter(None, args.large_tools.split(",")):
            print(compare_tool(name, args.tools_large_n, args.repeat))


if __name__ == "__main__":
    main()
