"""The one pipeline case of a layup scene: it carries every fabric its plies name (the layup
step, ``preform.stack``, drapes them)."""

from __future__ import annotations

import difflib
import hashlib
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from preform.pipeline.layup_section import layup_of

if TYPE_CHECKING:
    from preform.library import Library
    from preform.pipeline.runner import Case
    from preform.pipeline.scene import Scene
    from preform.plugin_manager import PluginHost


#: The case folder of a layup scene, under the scene's (its plies' folders are inside it).
STACK_FOLDER = "stack"


def stack_label(scene: Scene) -> str:
    """The case's ``material``: the stack's fabrics in order of first use, joined by '+'."""
    return "+".join(dict.fromkeys(p.fabric for p in layup_of(scene).plies))


def layup_fabrics(library: Library, scene: Scene) -> tuple[tuple[str, dict[str, Any]], ...]:
    """(name, data) of each fabric the layup names, from ``library``; a ValueError naming the
    ply and the close library names for a fabric the library lacks."""
    names = library.names()
    out: dict[str, dict[str, Any]] = {}
    for k, ply in enumerate(layup_of(scene).plies):
        if ply.fabric in out:
            continue
        if ply.fabric not in names:
            close = difflib.get_close_matches(ply.fabric, names, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ValueError(
                f"scene {scene.name!r}: layup.plies[{k}].fabric: no fabric {ply.fabric!r} in "
                f"the library{hint}"
            )
        out[ply.fabric] = library.fabric(ply.fabric).model_dump(mode="json", exclude_none=True)
    return tuple(out.items())


def layup_case(
    library: Library,
    scene: Scene,
    scene_data: dict[str, Any],
    out_dir: Path,
    host: PluginHost,
) -> Case:
    """The case of a layup scene: its ``fabric_data`` is the tool-side ply's fabric, its
    ``layup_fabrics`` every ply's, and its input hash covers them all."""
    from preform.pipeline.runner import Case, folder_name, input_hash

    fabrics = layup_fabrics(library, scene)
    first = fabrics[0][1]
    label = stack_label(scene)
    blob = json.dumps(
        [input_hash(first, scene, scene_data, host), fabrics], sort_keys=True, default=str
    )
    return Case(
        case_id=f"{scene.name}/{label}",
        material=label,
        scene=scene.name,
        fabric_data=first,
        scene_data=scene_data,
        scene_base_dir=scene.base_dir,
        case_dir=str(out_dir / folder_name(scene.name) / STACK_FOLDER),
        input_hash=hashlib.sha256(blob.encode()).hexdigest(),
        layup_fabrics=fabrics,
    )
