"""preform's tool-surface plugin: plane, hemisphere (alone or on a filleted flange), cylinder,
cone, ellipsoidal and paraboloidal domes, and triangle meshes from STL/OBJ files.

Registered through the ``preform`` entry-point group; a scene's ``tool: {surface: NAME, ...}``
block selects one.
"""

from __future__ import annotations

from preform.plugin_manager import hookimpl
from preform.registry import SurfaceRegistrar

_TOOLS = "preform.plugins.surfaces.tools"

#: (surface name, params model, builder) in ``preform.plugins.surfaces.tools``, registered by
#: import path: the tools module (and the surfaces, meshes and CAD readers it imports) loads when
#: a scene first names a surface, not when the plugin host starts.
SURFACES: tuple[tuple[str, str, str], ...] = (
    ("plane", "PlaneTool", "build_plane"),
    ("hemisphere", "HemisphereTool", "build_hemisphere"),
    ("cylinder", "CylinderTool", "build_cylinder"),
    ("cone", "ConeTool", "build_cone"),
    ("ellipsoid", "EllipsoidTool", "build_ellipsoid"),
    ("paraboloid", "ParaboloidTool", "build_paraboloid"),
    ("mesh", "MeshTool", "build_mesh"),
)


@hookimpl
def preform_register_surfaces(register: SurfaceRegistrar) -> None:
    for name, params, build in SURFACES:
        register.add_lazy(name, params=f"{_TOOLS}:{params}", build=f"{_TOOLS}:{build}")
