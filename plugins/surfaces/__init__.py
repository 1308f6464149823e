"""preform's tool-surface plugin: plane, hemisphere (alone or on a filleted flange), cylinder,
cone, ellipsoidal and paraboloidal domes, and triangle meshes from STL/OBJ files.

Registered through the ``preform`` entry-point group; a scene's ``tool: {surface: NAME, ...}``
block selects one.
"""

from __future__ import annotations

from preform.plugin_manager import hookimpl
from preform.registry import SurfaceRegistrar


@hookimpl
def preform_register_surfaces(register: SurfaceRegistrar) -> None:
    from preform.plugins.surfaces.tools import SURFACES

    for name, params, build in SURFACES:
        register.add(name, params, build)
