"""A tool mesh read from a file: the surface, where it came from, what hygiene repaired, and
its named faces, which a scene's ``part: faces:`` selects as the part.

:class:`ToolMesh` is a :class:`~preform.plugins.surfaces.mesh.TriangleMesh` built from a
repaired mesh (``preform.plugins.surfaces.mesh_hygiene``) with, per triangle, the face it
belongs to: a CAD face (numbered from 1, named when the file names it) or an OBJ group
(``g``/``o`` name). :meth:`ToolMesh.summary` gives the case summary's ``tool_*`` and
``mesh_*`` entries (file format, the unit the file is in and where that unit came from, the
tessellation tolerance of a CAD tool, the repairs). Every file reaches it through
:func:`repaired_tool` (one implementation): a scene's tool (``tools.build_mesh``), and
``read_stl``/``read_obj`` in Python, which also say the repairs as a warning.

The part of selected faces [D]
------------------------------
:class:`FaceSet` is a :class:`~preform.drape.engine.part.Part`; its level φ at a point is the distance
to the selection's edge (the mesh edges between a selected and an unselected triangle), signed
by whether the point's closest triangle is selected. The distance is straight-line (not along
the surface), which near the edge, where cut cells use it, differs from the distance along the
surface only across a crease; away from the edge its magnitude is that of the nearest of the
:data:`EDGE_CANDIDATES` edge segments whose midpoints are nearest, its sign exact. The part's
area is the selected triangles' area, exact for the tessellated tool.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from preform.base.arrays import FloatArray, IntArray
from preform.drape.engine.part import Part
from preform.plugins.surfaces.mesh import (
    DEFAULT_FEATURE_ANGLE_DEG,
    TriangleMesh,
    obj_triangles,
    stl_triangles,
)
from preform.plugins.surfaces.mesh_hygiene import (
    FOLD_ANGLE_DEG,
    HygieneReport,
    MeshRefused,
    RepairedMesh,
    repair,
)

MM = 1e-3
#: Edge segments examined per point for the distance to a face selection's edge.
EDGE_CANDIDATES = 16


@dataclass(frozen=True)
class ToolSource:
    """Where a tool mesh came from: ``file``, ``format`` ("STL", "OBJ", "STEP", "IGES"),
    ``unit`` its coordinates are in, ``unit_from`` ("declared in the file", "scene
    tool.units", ...), and for CAD the tessellation tolerance [m] and angle [rad]."""

    file: str
    format: str
    unit: str
    unit_from: str
    tessellation_tolerance_m: float | None = None
    tessellation_angle_rad: float | None = None


class ToolMesh(TriangleMesh):
    """A repaired tool mesh with its faces (module docstring).

    ``face_label`` (m,) is each triangle's face number; ``face_names`` maps numbers to names
    (faces without a name are selected by number only)."""

    face_label: IntArray
    face_names: dict[int, str]
    hygiene: HygieneReport
    source: ToolSource
    # repair ran TriangleMesh's checks (and more) on these arrays: not paid for twice.
    _surface_checked = True

    def __init__(
        self,
        repaired: RepairedMesh,
        face_of_input: IntArray | None,
        face_names: dict[int, str],
        source: ToolSource,
        feature_angle_deg: float | None = None,
        smooth_normals: bool = False,
    ) -> None:
        # Hygiene has welded and dropped what TriangleMesh would: nothing is merged again, so
        # the triangles stay in step with their labels.
        super().__init__(
            repaired.vertices,
            repaired.faces,
            merge_tolerance_rel=0.0,
            smooth_normals=smooth_normals,
            feature_angle_deg=(
                DEFAULT_FEATURE_ANGLE_DEG if feature_angle_deg is None else feature_angle_deg
            ),
        )
        if self.n_triangles != repaired.faces.shape[0]:
            raise ValueError(
                f"{source.file}: the mesh lost {repaired.faces.shape[0] - self.n_triangles} "
                "triangles after repair; report this mesh as a bug"
            )
        labels = (
            np.ones(repaired.faces.shape[0], dtype=np.int64)
            if face_of_input is None
            else np.asarray(face_of_input, dtype=np.int64)[repaired.origin]
        )
        self.face_label = labels
        self.face_names = dict(face_names)
        self.hygiene = repaired.report
        self.source = source

    def moved(self, vertices: FloatArray) -> ToolMesh:
        """This tool with its vertices (n, 3) [m] moved: the same triangles, face labels,
        names, source and hygiene record (a tool offset along its vertex normals,
        ``preform.drape.engine.offset``; ``part.faces`` selects the same faces of it)."""
        repaired = RepairedMesh(
            np.asarray(vertices, dtype=float),
            self.faces,
            np.arange(self.faces.shape[0], dtype=np.int64),
            self.hygiene,
        )
        return ToolMesh(
            repaired,
            self.face_label,
            self.face_names,
            self.source,
            feature_angle_deg=self.feature_angle_deg,
            smooth_normals=self.smooth_normals,
        )

    @property
    def n_faces(self) -> int:
        """Number of distinct faces (CAD faces, OBJ groups) [-]."""
        return int(np.unique(self.face_label).size)

    def summary(self) -> dict[str, Any]:
        """The case summary's entries for this tool (module docstring)."""
        out: dict[str, Any] = {
            "tool_file": self.source.file,
            "tool_format": self.source.format,
            "tool_unit": self.source.unit,
            "tool_unit_from": self.source.unit_from,
            "tool_faces": self.n_faces,
        }
        if self.source.tessellation_tolerance_m is not None:
            out["tool_tessellation_tolerance_mm"] = self.source.tessellation_tolerance_m / MM
        if self.source.tessellation_angle_rad is not None:
            out["tool_tessellation_angle_deg"] = float(
                np.degrees(self.source.tessellation_angle_rad)
            )
        out.update(self.hygiene.summary())
        return out

    def faces_of(self, selection: Sequence[int | str]) -> IntArray:
        """The face numbers ``selection`` names: numbers as they are, names matched against
        the face names (whole, or the last part after '/', gmsh's label path).

        Raises ``ValueError`` saying which entry matches nothing and what there is."""
        numbers = set(np.unique(self.face_label).tolist())
        chosen: list[int] = []
        for k, item in enumerate(selection):
            if isinstance(item, int):
                if item not in numbers:
                    raise ValueError(
                        f"faces[{k}]: the tool has no face {item} (faces "
                        f"{min(numbers)}..{max(numbers)})"
                    )
                chosen.append(item)
                continue
            hits = [
                n for n, name in self.face_names.items() if item in (name, name.rsplit("/", 1)[-1])
            ]
            if not hits:
                named = sorted({n.rsplit("/", 1)[-1] for n in self.face_names.values()})
                known = ", ".join(repr(n) for n in named[:20]) or "none (select faces by number)"
                raise ValueError(
                    f"faces[{k}]: no face of the tool is named {item!r}; named: {known}"
                )
            chosen.extend(hits)
        return np.unique(np.asarray(chosen, dtype=np.int64))

    def face_part(self, selection: Sequence[int | str]) -> FaceSet:
        """The part made of the faces ``selection`` names (:meth:`faces_of`)."""
        return FaceSet(self, self.faces_of(selection), tuple(selection))


def repaired_tool(
    file: Path,
    vertices: FloatArray,
    faces: IntArray,
    face_of_input: IntArray | None,
    face_names: dict[int, str],
    source: ToolSource,
    *,
    weld_tolerance_m: float | None = None,
    max_edge_m: float | None = None,
    fold_angle_deg: float = FOLD_ANGLE_DEG,
    feature_angle_deg: float | None = None,
    smooth_normals: bool = False,
) -> ToolMesh:
    """The tool mesh of triangles read from ``file``: repaired (``mesh_hygiene.repair``,
    lengths [m], angles [°]) and labelled. A refusal is a ``MeshRefused`` naming the file and
    keeping the place [m]. Every path from a file to a tool comes here (scenes, STEP/IGES,
    ``read_stl``, ``read_obj``)."""
    try:
        repaired = repair(
            vertices, faces, weld_tolerance_m, max_edge_m=max_edge_m, fold_angle_deg=fold_angle_deg
        )
    except MeshRefused as error:
        raise MeshRefused(f"{file}: {error}", error.where_m) from None
    return ToolMesh(
        repaired,
        face_of_input,
        face_names,
        source,
        feature_angle_deg=feature_angle_deg,
        smooth_normals=smooth_normals,
    )


def read_tool_file(
    file: Path,
    source: ToolSource,
    units_to_m: float,
    *,
    max_bytes: int | None = None,
    **options: Any,
) -> ToolMesh:
    """The repaired tool mesh of an STL or OBJ ``file`` (``source.format``) whose coordinates
    are in units of ``units_to_m`` metres; an OBJ file's ``g``/``o`` groups are its faces,
    numbered from 1 in name order. ``options`` are :func:`repaired_tool`'s."""
    labels: IntArray | None = None
    names: dict[int, str] = {}
    if source.format == "OBJ":
        vertices, faces, groups = obj_triangles(file, units_to_m, max_bytes=max_bytes)
        group_names = sorted(set(groups))
        numbering = {g: k + 1 for k, g in enumerate(group_names)}
        labels = np.array([numbering[g] for g in groups], dtype=np.int64)
        names = {numbering[g]: g for g in group_names if g}
    else:
        vertices, faces = stl_triangles(file, units_to_m, max_bytes=max_bytes)
    return repaired_tool(file, vertices, faces, labels, names, source, **options)


class FaceSet(Part):
    """The part made of some faces of a :class:`ToolMesh` (module docstring)."""

    def __init__(self, mesh: ToolMesh, numbers: IntArray, selection: tuple[int | str, ...]):
        self.mesh = mesh
        self.selection = selection
        self.selected = np.isin(mesh.face_label, numbers)
        corners = mesh.vertices[mesh.faces]
        area = 0.5 * np.linalg.norm(
            np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
        )
        self.area_m2 = float(area[self.selected].sum())
        # The selection's edge: mesh edges with a selected triangle on one side only.
        directed = np.stack([mesh.faces, np.roll(mesh.faces, -1, axis=1)], axis=2).reshape(-1, 2)
        undirected = np.sort(directed, axis=1)
        chosen_side = np.repeat(self.selected, 3)
        edges, inverse = np.unique(undirected, axis=0, return_inverse=True)
        inverse = inverse.ravel()
        inside = np.bincount(inverse, weights=chosen_side, minlength=edges.shape[0])
        outside = np.bincount(inverse, weights=~chosen_side, minlength=edges.shape[0])
        rim = edges[(inside > 0) & (outside > 0)]
        self._start = mesh.vertices[rim[:, 0]]
        self._end = mesh.vertices[rim[:, 1]]
        if rim.shape[0]:
            from scipy.spatial import cKDTree

            self._tree: Any = cKDTree(0.5 * (self._start + self._end))

    def level(self, points: FloatArray) -> FloatArray:
        p = np.asarray(points, dtype=float)
        flat = p.reshape(-1, 3)
        out = np.full(flat.shape[0], np.nan)
        ok = np.all(np.isfinite(flat), axis=1)
        q = flat[ok]
        if q.shape[0]:
            _, _, face = self.mesh.closest_faces(q)
            sign = np.where(self.selected[face], 1.0, -1.0)
            if self._start.shape[0] == 0:
                out[ok] = sign * self.mesh.size
            else:
                k = min(EDGE_CANDIDATES, self._start.shape[0])
                _, near = self._tree.query(q, k=k)
                near = np.asarray(near).reshape(q.shape[0], k)
                a, b = self._start[near], self._end[near]
                axis = b - a
                length_sq = np.maximum(np.einsum("ijk,ijk->ij", axis, axis), 1e-300)
                t = np.clip(np.einsum("ijk,ijk->ij", q[:, None] - a, axis) / length_sq, 0, 1)
                foot = a + t[..., None] * axis
                dist = np.min(np.linalg.norm(q[:, None] - foot, axis=2), axis=1)
                out[ok] = sign * dist
        return out.reshape(p.shape[:-1])

    def describe(self) -> str:
        shown = ", ".join(str(s) for s in self.selection)
        return f"faces {shown} of {self.mesh.source.file}"


__all__ = [
    "EDGE_CANDIDATES",
    "FaceSet",
    "ToolMesh",
    "ToolSource",
    "read_tool_file",
    "repaired_tool",
]
