"""STEP and IGES tools: read through gmsh (OpenCASCADE) and tessellated to a chordal tolerance.

gmsh is the optional extra ``preform[cad]`` and is imported only here, when a CAD tool is
read. The tessellation is OpenCASCADE's own (``BRepMesh``, what CAD systems use to write STL),
driven by two documented parameters:

- the **tessellation tolerance** [m]: the largest distance between a facet and the exact
  surface (chordal deviation); the scene knob ``tool.tessellation_tolerance_mm``;
- the **tessellation angle** [rad]: the largest angle between the normals of neighbouring
  facets, a guard that keeps small fillets round when the tolerance alone would let one facet
  span them (``tool.tessellation_angle_deg``).

Edges are tessellated once and shared by the faces meeting there, so the faces' triangles
meet vertex to vertex (the copies are welded by ``preform.plugins.surfaces.mesh_hygiene``).

**Units.** A STEP file declares its length unit (``LENGTH_UNIT`` with ``SI_UNIT`` or a
``CONVERSION_BASED_UNIT`` such as inch), an IGES file in its global section (unit flag and
name). OpenCASCADE converts the geometry from that unit to millimetres on reading, and this
reader from millimetres to metres; :func:`declared_unit` reads the declaration itself, so the
result can say which unit the file was in.

**Faces.** Each CAD face keeps its number (1, 2, ... in the order OpenCASCADE lists the faces
of the file's shapes, gmsh's surface tags) and its name when the file labels it (gmsh reads
labels of named sub-shapes); a scene's ``part: faces:`` selects faces by either.
"""

from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from preform.base.arrays import FloatArray, IntArray

#: File suffixes read as CAD, and the format each means.
CAD_FORMATS = {".step": "STEP", ".stp": "STEP", ".iges": "IGES", ".igs": "IGES"}
#: Chordal tolerance when a scene gives none [mm] (a choice: a twentieth of a millimetre is
#: far below the node spacings a drape uses, 1 to 10 mm, and below a ply's thickness).
DEFAULT_TESSELLATION_TOLERANCE_MM = 0.05
#: Normal-angle guard when a scene gives none [deg] (a choice: 15° keeps a fillet at least
#: six facets per quarter turn whatever its radius).
DEFAULT_TESSELLATION_ANGLE_DEG = 15.0

#: The unit OpenCASCADE converts STEP and IGES geometry to on reading [m]: millimetres, its
#: default (``xstep.cascade.unit``; gmsh's ``Geometry.OCCTargetUnit`` left empty, since setting
#: it fails for an IGES file read first in a process).
_OCC_UNIT_M = 1e-3
#: Longest triangle edge of a CAD tessellation when a scene gives none, as a fraction of the
#: tool's bounding-box diagonal [-] (a choice: OpenCASCADE covers a flat face with a few long
#: triangles, and closest-point queries bound their search by the largest triangle; measured
#: on the bundled hat stiffener at 22 mm node spacing: one drape 0.84 s with the triangles as
#: tessellated, 0.03 s with no edge over 1/20 of the diagonal, the surface being the same;
#: ``benchmarks/bench_tool_mesh.py``).
DEFAULT_MAX_EDGE_REL = 1 / 20
#: STEP prefixes of SI_UNIT(prefix, .METRE.) and the unit they make.
_STEP_PREFIX = {
    "$": "m",
    ".MILLI.": "mm",
    ".CENTI.": "cm",
    ".DECI.": "dm",
    ".KILO.": "km",
    ".MICRO.": "µm",
}
#: IGES global parameter 14 (unit flag) and the unit it means (IGES 5.3, section 2.2.4.3).
_IGES_UNIT_FLAG = {
    1: "inch",
    2: "mm",
    4: "ft",
    5: "mile",
    6: "m",
    7: "km",
    8: "mil",
    9: "µm",
    10: "cm",
    11: "microinch",
}


class CadError(ValueError):
    """A CAD tool file that cannot be read; the message names the file (and line)."""


@dataclass(frozen=True)
class CadTessellation:
    """A tessellated CAD tool: triangle soup of its faces, in metres.

    ``vertices`` (n, 3) [m] and ``faces`` (m, 3) (not yet welded: each CAD face has its own
    copies of the vertices on its edges); ``face_of_triangle`` (m,) the CAD face number of
    each triangle; ``face_names`` the names of the faces the file labels; ``unit`` the length
    unit the file declares (None if it declares none; OpenCASCADE then assumes mm)."""

    vertices: FloatArray
    faces: IntArray
    face_of_triangle: IntArray
    format: str
    unit: str | None
    tolerance_m: float
    angle_rad: float
    face_names: dict[int, str] = field(default_factory=dict)

    @property
    def n_faces(self) -> int:
        """Number of CAD faces tessellated."""
        return int(np.unique(self.face_of_triangle).size)


def cad_format(path: str | Path) -> str | None:
    """``"STEP"`` or ``"IGES"`` by the file's suffix, else None."""
    return CAD_FORMATS.get(Path(path).suffix.lower())


def _import_gmsh() -> Any:
    try:
        import gmsh  # the optional 'cad' extra: only when a CAD tool is read
    except ImportError as error:
        raise CadError(
            'reading STEP or IGES tools needs gmsh: pip install "preform[cad]" '
            f"(importing it failed: {error})"
        ) from None
    return gmsh


@contextlib.contextmanager
def _occ_console(said: list[str]) -> Iterator[None]:
    """Hold OpenCASCADE's console output (it writes to file descriptor 1 directly, past
    gmsh's ``General.Terminal``): kept out of the run's console and appended to ``said``, so
    a refusal can quote the translator's own located message (e.g. "Line 5: Incorrect
    syntax")."""
    sys.stdout.flush()
    with tempfile.TemporaryFile() as held:
        saved = os.dup(1)
        os.dup2(held.fileno(), 1)
        try:
            yield
        finally:
            os.dup2(saved, 1)
            os.close(saved)
            held.seek(0)
            text = held.read().decode("utf-8", errors="replace")
            said.extend(re.sub(r"\x1b\[[0-9;]*m", "", text).splitlines())


def _occ_errors(said: list[str]) -> str:
    """The translator's error lines, cleaned, or ''."""
    errors = [ln.strip(" *") for ln in said if "ERR" in ln or "rror" in ln]
    return "; ".join(e for e in errors if e)


def _step_entities(text: str) -> list[tuple[int, str]]:
    """The DATA section's entities as (line where each starts, text), split at ';'."""
    out = []
    line = 1
    start_line = 1
    current: list[str] = []
    for piece in re.split(r"(;|\n)", text):
        if piece == "\n":
            line += 1
            current.append(" ")
        elif piece == ";":
            out.append((start_line, "".join(current).strip()))
            current = []
            start_line = line
        else:
            if not "".join(current).strip():
                start_line = line
            current.append(piece)
    return out


def _check_step(file: Path, text: str) -> None:
    first = next((ln for ln in text.splitlines() if ln.strip()), "")
    if not first.strip().upper().startswith("ISO-10303-21"):
        raise CadError(
            f"{file}:1: not a STEP file: a STEP file starts with 'ISO-10303-21;', this one "
            f"with {first.strip()[:40]!r}"
        )
    if "END-ISO-10303-21" not in text.upper():
        n = text.count("\n") + 1
        raise CadError(
            f"{file}:{n}: the STEP file ends without 'END-ISO-10303-21;' (truncated? export "
            "it again)"
        )


def _step_unit(text: str) -> str | None:
    for _, entity in _step_entities(text):
        upper = entity.upper()
        if "LENGTH_UNIT" not in upper:
            continue
        named = re.search(r"CONVERSION_BASED_UNIT\s*\(\s*'([^']*)'", upper)
        if named:
            return {"INCH": "inch", "FOOT": "ft"}.get(named.group(1).strip(), named.group(1))
        si = re.search(r"SI_UNIT\s*\(\s*(\$|\.[A-Z]+\.)\s*,\s*\.METRE\.\s*\)", upper)
        if si:
            return _STEP_PREFIX.get(si.group(1), si.group(1).strip(".").lower() + "m")
    return None


def _iges_global(file: Path, text: str) -> list[str]:
    """The IGES global section's parameters (Hollerith strings decoded)."""
    lines = text.splitlines()
    if not lines or len(lines[0]) < 73 or lines[0][72] != "S":
        raise CadError(
            f"{file}:1: not an IGES file: its first line is not a start-section line (80 "
            "columns, 'S' in column 73)"
        )
    body = "".join(ln[:72] for ln in lines if len(ln) >= 73 and ln[72] == "G")
    if not body:
        raise CadError(f"{file}: the IGES file has no global section ('G' lines)")
    delimiter, end = ",", ";"
    if body.startswith("1H"):
        delimiter = body[2]
    params: list[str] = []
    i, token = 0, ""
    while i < len(body):
        ch = body[i]
        hollerith = re.match(r"(\d+)H", body[i:])
        if hollerith and not token.strip():
            n = int(hollerith.group(1))
            start = i + len(hollerith.group(0))
            token = body[start : start + n]
            i = start + n
            continue
        if ch in (delimiter, end):
            params.append(token.strip())
            token = ""
            if ch == end:
                break
        else:
            token += ch
        i += 1
    return params


def _iges_unit(file: Path, text: str) -> str | None:
    params = _iges_global(file, text)
    if len(params) < 15:
        return None
    try:
        flag = int(float(params[13]))
    except ValueError:
        return None
    if flag == 3:
        return params[14] or None
    return _IGES_UNIT_FLAG.get(flag)


def declared_unit(path: str | Path) -> str | None:
    """The length unit a STEP or IGES file declares ("mm", "m", "inch", ...), or None."""
    file = Path(path)
    text = file.read_bytes().decode("latin-1")
    if cad_format(file) == "IGES":
        return _iges_unit(file, text)
    return _step_unit(text)


def read_cad(
    path: str | Path,
    tolerance_m: float = DEFAULT_TESSELLATION_TOLERANCE_MM * 1e-3,
    angle_rad: float = float(np.radians(DEFAULT_TESSELLATION_ANGLE_DEG)),
    *,
    max_bytes: int | None = None,
) -> CadTessellation:
    """Read and tessellate a STEP or IGES file (module docstring): chordal ``tolerance_m``
    [m], normal-angle guard ``angle_rad`` [rad]. Only regular files no larger than
    ``max_bytes`` are read (``check_mesh_file``). Raises :class:`CadError` naming the file."""
    from preform.plugins.surfaces.mesh import check_mesh_file

    file = Path(path)
    kind = cad_format(file)
    if kind is None:
        raise CadError(f"{file}: not a CAD file name (.step, .stp, .iges or .igs)")
    if not (np.isfinite(tolerance_m) and tolerance_m > 0):
        raise ValueError(f"tessellation tolerance must be a positive length [m], got {tolerance_m}")
    if not (np.isfinite(angle_rad) and 0 < angle_rad < np.pi):
        raise ValueError(f"tessellation angle must lie in (0, π) rad, got {angle_rad}")
    check_mesh_file(file, max_bytes)
    text = file.read_bytes().decode("latin-1")
    if kind == "STEP":
        _check_step(file, text)
        unit = _step_unit(text)
    else:
        unit = _iges_unit(file, text)
    gmsh = _import_gmsh()
    ours = not gmsh.isInitialized()
    if ours:
        # Not interruptible: gmsh would otherwise take over SIGINT from the runner.
        gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(f"preform-tool-{id(file)}")
        said: list[str] = []
        try:
            with _occ_console(said):
                gmsh.model.occ.importShapes(str(file))
                gmsh.model.occ.synchronize()
        except Exception as error:
            detail = _occ_errors(said) or str(error)
            raise CadError(f"{file}: cannot be read as {kind}: {detail}") from None
        surfaces = [tag for _, tag in gmsh.model.getEntities(2)]
        if not surfaces:
            raise CadError(
                f"{file}: the {kind} file holds no surface (only points or curves); a tool "
                "needs its faces"
            )
        gmsh.option.setNumber("Mesh.StlLinearDeflection", float(tolerance_m) / _OCC_UNIT_M)
        gmsh.option.setNumber("Mesh.StlLinearDeflectionRelative", 0)
        gmsh.option.setNumber("Mesh.StlAngularDeflection", float(angle_rad))
        try:
            with _occ_console(said):
                gmsh.model.mesh.importStl()
        except Exception as error:
            raise CadError(f"{file}: OpenCASCADE could not tessellate its faces: {error}") from None
        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        index = np.full(int(node_tags.max()) + 1 if node_tags.size else 1, -1, dtype=np.int64)
        index[node_tags.astype(np.int64)] = np.arange(node_tags.size)
        triangles, owners, names = [], [], {}
        for tag in surfaces:
            types, _, element_nodes = gmsh.model.mesh.getElements(2, tag)
            for kind_code, nodes in zip(types, element_nodes, strict=True):
                if kind_code != 2:  # 3-node triangles only (importStl makes no others)
                    continue
                tri = index[np.asarray(nodes, dtype=np.int64).reshape(-1, 3)]
                triangles.append(tri)
                owners.append(np.full(tri.shape[0], tag, dtype=np.int64))
            name = gmsh.model.getEntityName(2, tag)
            if name:
                names[int(tag)] = name
        if not triangles:
            raise CadError(f"{file}: OpenCASCADE made no triangles of its faces")
        return CadTessellation(
            vertices=np.asarray(coords, dtype=np.float64).reshape(-1, 3) * _OCC_UNIT_M,
            faces=np.concatenate(triangles),
            face_of_triangle=np.concatenate(owners),
            format=kind,
            unit=unit,
            tolerance_m=float(tolerance_m),
            angle_rad=float(angle_rad),
            face_names=names,
        )
    finally:
        if ours:
            gmsh.finalize()
        else:
            gmsh.model.remove()


__all__ = [
    "CAD_FORMATS",
    "DEFAULT_MAX_EDGE_REL",
    "DEFAULT_TESSELLATION_ANGLE_DEG",
    "DEFAULT_TESSELLATION_TOLERANCE_MM",
    "CadError",
    "CadTessellation",
    "cad_format",
    "declared_unit",
    "read_cad",
]
