"""Cost of a layup against its plies draped one at a time (issue 27: at most 4.5x one ply).

The bundled ``hemisphere-layup`` scene ([0/45/-45/90], plain-weave-600 and the satin, the 45°
ply a drop-off), run by ``preform.layup`` at the given fidelity with its own ply outputs,
against:

- each of its plies draped alone by ``preform.drape`` on the bare tool with the same settings
  and outputs (its fabric, orientation, generator angle, outline), and their mean ("one ply");
- a layup of its first ply only (the same step, no offset, a stack of one).

Everything runs once before timing (imports, numba compilation, the fabrics' sheared-cell
tables); then each is timed (CPU time of this process, pinned to one core: a shared
machine's other work inflates wall time by more than the differences measured here, each
call with the collection of its own garbage: ``timed``) best of ``--repeat``, alternated. What the stack adds on top of
its drapes is the offsets and the stack maps: their times are the layup's own ``step_times_s``.

    python benchmarks/bench_layup.py [--fidelity draft] [--repeat 3]
"""

from __future__ import annotations

import argparse
import gc
import os
import tempfile
import time
from typing import Any

import preform
from preform.pipeline.scene import bundled_scene_dir

if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def timed(call: Any) -> float:
    """CPU time of ``call`` [s]: this process's own (pinned to one core), so other work on a
    shared machine does not count; file writes' waits for the disk do not either.

    What earlier calls left for the garbage collector is collected before the clock starts:
    without that, a call paid for the cycles its predecessor left (a stack's five figures, a
    ply's one) whenever the collector's thresholds fell in it, and the stack measured 0.1-0.18 s
    more at draft than its steps' times add up to. A call's own garbage is collected as the
    thresholds fall, as in a run (a full collection after each call, timed, would charge every
    call ~70 ms for walking every live object, four times the stack's plies alone)."""
    gc.collect()
    start = time.process_time()
    call()
    return time.process_time() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--fidelity", default="draft")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    scene = preform.scene(bundled_scene_dir() / "hemisphere-layup.yaml", fidelity=args.fidelity)
    layup = scene.layup
    assert layup is not None
    outputs = list(layup.ply_outputs)
    library = preform.load_library()

    def ply_alone(k: int) -> Any:
        ply = layup.plies[k]
        data = scene.model_dump(mode="json", exclude_none=True)
        data.pop("layup")
        data["start"] = {
            "point_mm": list(scene.start.point_mm if scene.start else (0.0, 0.0)),
            "orientation_deg": layup.reference_direction_deg + ply.orientation_deg,
            "generator_angle_deg": ply.generator_angle_deg,
        }
        if ply.part_outline_mm is not None:
            data["part"] = {"plan_outline_mm": [list(p) for p in ply.part_outline_mm]}
        data["outputs"] = outputs
        data["name"] = f"alone-{k}"
        with tempfile.TemporaryDirectory() as out:
            return preform.drape(ply.fabric, data, library=library, out_dir=out, outputs=outputs)

    def stack() -> Any:
        with tempfile.TemporaryDirectory() as out:
            return preform.layup(scene, library=library, out_dir=out)

    def stack_bare() -> Any:  # the plies, offsets and maps; no stack file
        with tempfile.TemporaryDirectory() as out:
            return preform.layup(scene, library=library, out_dir=out, outputs=["layup"])

    first_only = {"plies": [layup.plies[0].model_dump(exclude_none=True)]}

    def one_ply_stack() -> Any:
        with tempfile.TemporaryDirectory() as out:
            return preform.layup(scene, plies=first_only["plies"], library=library, out_dir=out)

    warm = stack()  # imports, compilation and tables, not counted
    assert warm.status in ("ok", "partial"), warm.error
    for k in range(len(layup.plies)):
        ply_alone(k)
    one_ply_stack()
    stack_bare()
    best_stack = best_one = best_bare = float("inf")
    best_alone = [float("inf")] * len(layup.plies)
    for _ in range(args.repeat):
        best_stack = min(best_stack, timed(stack))
        for k in range(len(layup.plies)):
            best_alone[k] = min(best_alone[k], timed(lambda k=k: ply_alone(k)))
        best_one = min(best_one, timed(one_ply_stack))
        best_bare = min(best_bare, timed(stack_bare))
    last = stack()
    mean_alone = sum(best_alone) / len(best_alone)
    print(
        f"scene hemisphere-layup, fidelity {args.fidelity}, CPU time, best of {args.repeat}, "
        "one core"
    )
    for k, t in enumerate(best_alone):
        ply = layup.plies[k]
        print(f"  ply {k + 1} alone ({ply.fabric}, {ply.orientation_deg:g} deg): {t:7.3f} s")
    print(f"  mean of one ply alone:            {mean_alone:7.3f} s")
    print(f"  a stack of the first ply only:    {best_one:7.3f} s")
    print(f"  the 4-ply stack:                  {best_stack:7.3f} s")
    print(f"  the 4-ply stack, outputs [layup]: {best_bare:7.3f} s")
    print(f"  stack / mean ply alone:           {best_stack / mean_alone:7.2f} x (limit 4.5)")
    print(f"  stack [layup] / mean ply alone:   {best_bare / mean_alone:7.2f} x (limit 4.5)")
    print(f"  stack / sum of plies alone:       {best_stack / sum(best_alone):7.2f} x")
    steps = last.summary.get("step_times_s", {})
    plies = sum(sum(p.get("step_times_s", {}).values()) for p in last.plies)
    print(f"  the stack's steps (wall): {', '.join(f'{k} {v:.3f} s' for k, v in steps.items())}")
    print(f"  of the layup step, the plies' own steps (wall): {plies:.3f} s")


if __name__ == "__main__":
    main()
