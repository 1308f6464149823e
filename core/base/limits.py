"""Hard limits on inputs, checked where a scene is read and where the step that owns a section
checks it (both import it from here, below either)."""

#: Most vertices of a ply outline or a generator polyline: the inside test walks the edges one
#: by one, so a million-vertex outline would take the machine for hours; no ply needs more.
MAX_POLYGON_VERTICES = 10_000
