"""A ply stack's composite sections written for the chosen solvers, one file each.

The entry point a layup exporter (a pipeline step, ``preform export`` on a stack) calls with
the targets the user named: ``abaqus`` (``stack_abaqus.inp``), ``calculix``
(``stack_calculix.inp``), ``lsdyna`` (``stack_lsdyna.k``), ``ansys`` (``stack_ansys.mac``);
each file as its writer's module says (:mod:`preform.export.stack_abaqus`,
:mod:`preform.export.stack_lsdyna`, :mod:`preform.export.stack_ansys`). Lengths in mm, angles
in degrees.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from preform.export.ply_stack import StackSections

#: Target -> file name.
STACK_FILES: dict[str, str] = {
    "abaqus": "stack_abaqus.inp",
    "calculix": "stack_calculix.inp",
    "lsdyna": "stack_lsdyna.k",
    "ansys": "stack_ansys.mac",
}


def write_stack_files(
    stack: StackSections,
    folder: str | os.PathLike[str],
    targets: Iterable[str],
    *,
    prefix: str = "PREFORM",
    title: str | None = None,
) -> dict[str, str]:
    """Write the files of ``targets`` into ``folder``; return target -> file name.
    ``prefix`` names the sets, orientations, components and material parameters."""
    from preform.export.stack_abaqus import write_stack_sections
    from preform.export.stack_ansys import write_stack_ansys
    from preform.export.stack_lsdyna import write_stack_lsdyna

    wanted = list(dict.fromkeys(targets))
    unknown = [t for t in wanted if t not in STACK_FILES]
    if unknown:
        raise ValueError(
            f"no stack target {', '.join(unknown)}; known: {', '.join(sorted(STACK_FILES))}"
        )
    out: dict[str, str] = {}
    for target in wanted:
        path = Path(folder) / STACK_FILES[target]
        if target in ("abaqus", "calculix"):
            write_stack_sections(stack, path, prefix=prefix, flavour=target, title=title)
        elif target == "lsdyna":
            write_stack_lsdyna(stack, path, title=title)
        else:
            write_stack_ansys(stack, path, prefix=prefix)
        out[target] = STACK_FILES[target]
    return out
