"""The user's shell mesh, with the element and node labels their solver knows.

A structural model refers to its elements by label, so a mapping is only usable downstream when
the labels survive the read. meshio reads most formats but forgets Abaqus and Nastran labels, so
those two get small readers here (flat ``*NODE`` / ``*ELEMENT`` input, no parts or instances;
``GRID`` and ``CTRIA3`` / ``CQUAD4`` / ``CTRIA6`` / ``CQUAD8`` in free, small- and large-field
form). Every other format goes through meshio and its elements are labelled 1, 2, ... in the
order meshio lists them (said in ``ShellMesh.labels_from``).

Only the corner nodes of an element matter for a mapping (centroid, plane, first edge), so
6- and 8-node elements keep their first 3 or 4 nodes. Coordinates are held in millimetres:
a reader takes the file's unit as ``unit_mm`` (the length of one file unit in mm).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from preform.base.arrays import FloatArray, IntArray

#: Bytes per MB in ``limits.max_mesh_mb`` (decimal, as for tool meshes).
MB = 1_000_000


def mesh_file_problem(path: str | os.PathLike[str], max_bytes: int | None = None) -> str | None:
    """Why the FE mesh at ``path`` cannot be read, or None: checked before any drape runs,
    without reading it (its content is judged when the mapping step reads it).

    Refused: a missing path; anything but a regular file (a FIFO would block the reader, a
    device never ends, a directory is no mesh); an empty file; one larger than ``max_bytes``
    (by ``stat``, so a huge file costs nothing to refuse); one this process may not open; a
    suffix no reader here knows (``.inp``, ``.bdf``/``.nas``/``.dat``, or one of meshio's).
    """
    import stat

    file = Path(path)
    try:
        info = os.stat(file)
    except FileNotFoundError:
        return f"{file}: no such file"
    except (OSError, ValueError) as error:
        why = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
        return f"{file}: cannot be looked up: {why}"
    if not stat.S_ISREG(info.st_mode):
        kind = "a directory" if stat.S_ISDIR(info.st_mode) else "not a regular file"
        return f"{file}: is {kind}; the FE mesh must be a mesh file"
    if info.st_size == 0:
        return f"{file}: is empty (0 bytes)"
    if max_bytes is not None and info.st_size > max_bytes:
        return (
            f"{file}: {info.st_size / MB:.1f} MB, larger than the limit of {max_bytes / MB:g} MB "
            "(limits.max_mesh_mb)"
        )
    suffix = file.suffix.lower()
    if suffix not in (".inp", ".bdf", ".nas", ".dat"):
        import meshio

        known = meshio.extension_to_filetypes
        if suffix not in known and "".join(file.suffixes[-2:]).lower() not in known:
            return (
                f"{file}: no reader for {suffix or 'a file without a suffix'!r} files "
                "(Abaqus .inp, Nastran .bdf/.nas/.dat, or a format meshio reads: .stl, .obj, "
                ".vtu, .msh, ...)"
            )
    try:
        with open(file, "rb"):
            pass
    except OSError as error:
        return f"{file}: cannot be opened: {error.strerror or error}"
    return None


#: meshio cell types read as shells, and how many corner nodes each keeps.
MESHIO_SHELLS = {"triangle": 3, "triangle6": 3, "triangle7": 3, "quad": 4, "quad8": 4, "quad9": 4}


@dataclass(frozen=True)
class ShellMesh:
    """Shell elements: triangles and quadrilaterals, coordinates in mm.

    ``corners`` indexes ``points`` (0-based) with −1 in the fourth column of a triangle.
    """

    #: Node coordinates (n, 3) [mm].
    points: FloatArray
    #: The solver's node labels (n,).
    node_ids: IntArray
    #: Corner node indices (m, 4) into ``points``; −1 in column 3 for a triangle.
    corners: IntArray
    #: The solver's element labels (m,).
    element_ids: IntArray
    #: Property / part id of each element (m,) where the file has one (Nastran PID), else 0.
    property_ids: IntArray
    #: Where the labels come from: "file" or "position" (1, 2, ... in meshio's order).
    labels_from: str = "file"
    #: The file read, for summaries.
    source: str = ""

    @property
    def n_elements(self) -> int:
        return len(self.element_ids)

    @property
    def source_name(self) -> str:
        """The mesh file's name without its folder, for the header of a deck: a deck goes to
        another machine, where the folder it was written on means nothing ("" when no file)."""
        return Path(self.source).name if self.source else ""

    @property
    def is_triangle(self) -> NDArray[np.bool_]:
        return np.asarray(self.corners[:, 3] < 0)

    def corner_points(self) -> FloatArray:
        """Corners (m, 4, 3) [mm]; a triangle's fourth corner repeats its third."""
        idx = np.where(self.corners < 0, self.corners[:, [2]], self.corners)
        return np.asarray(self.points[idx])

    def centroids(self) -> FloatArray:
        """Element centroids (m, 3) [mm]: the mean of the corners (area centroid of a triangle,
        bilinear centre of a quadrilateral)."""
        pts = self.corner_points()
        tri = self.is_triangle
        out = pts.mean(axis=1)
        out[tri] = pts[tri, :3].mean(axis=1)
        return out

    def normals(self) -> FloatArray:
        """Unit element normals (m, 3) by the right-hand rule on the node order, as solvers
        define the shell's top: (x3 − x1) × (x4 − x2) for a quadrilateral (its mean plane),
        (x2 − x1) × (x3 − x1) for a triangle."""
        p = self.corner_points()
        quad_n = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
        tri_n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        n = np.where(self.is_triangle[:, None], tri_n, quad_n)
        length = np.linalg.norm(n, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.asarray(n / length)

    def first_edges(self) -> FloatArray:
        """Unit vectors (m, 3) from node 1 to node 2 of each element (LS-DYNA's and most
        solvers' default element x axis)."""
        p = self.corner_points()
        e = p[:, 1] - p[:, 0]
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.asarray(e / np.linalg.norm(e, axis=1, keepdims=True))

    def sizes(self) -> FloatArray:
        """Characteristic element size (m,) [mm]: the square root of its area."""
        p = self.corner_points()
        area = 0.5 * np.linalg.norm(np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1]), axis=1)
        tri_area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        return np.asarray(np.sqrt(np.where(self.is_triangle, tri_area, area)))


def shell_mesh(
    points_mm: FloatArray,
    corners: IntArray | list[list[int]],
    *,
    element_ids: IntArray | None = None,
    node_ids: IntArray | None = None,
    property_ids: IntArray | None = None,
    source: str = "",
) -> ShellMesh:
    """A :class:`ShellMesh` from arrays: points (n, 3) [mm], corners (m, 3 or 4) 0-based (a
    4-column array may hold −1 for triangles). Labels default to 1, 2, ..."""
    points = np.asarray(points_mm, dtype=float).reshape(-1, 3)
    rows = [list(map(int, row)) for row in corners]
    table = np.full((len(rows), 4), -1, dtype=np.int64)
    for k, row in enumerate(rows):
        if len(row) not in (3, 4):
            raise ValueError(f"element {k + 1} has {len(row)} corners; shells have 3 or 4")
        table[k, : len(row)] = row
    used = table[table >= 0]
    if used.size and (used.max() >= len(points) or table[:, :3].min() < 0):
        raise ValueError("element corners refer to nodes that do not exist")
    m = len(table)
    for what, ids in (("element", element_ids), ("node", node_ids)):
        if ids is not None:
            labels, counts = np.unique(np.asarray(ids, dtype=np.int64), return_counts=True)
            if np.any(counts > 1):
                raise ValueError(
                    f"{what} label {int(labels[np.argmax(counts > 1)])} is given "
                    f"{int(counts.max())} times; a solver needs each label once"
                )
    return ShellMesh(
        points=points,
        node_ids=np.arange(1, len(points) + 1)
        if node_ids is None
        else np.asarray(node_ids, dtype=np.int64),
        corners=table,
        element_ids=np.arange(1, m + 1)
        if element_ids is None
        else np.asarray(element_ids, dtype=np.int64),
        property_ids=np.zeros(m, dtype=np.int64)
        if property_ids is None
        else np.asarray(property_ids, dtype=np.int64),
        labels_from="file" if element_ids is not None else "position",
        source=source,
    )


def read_shell_mesh(path: str | os.PathLike[str], *, unit_mm: float = 1.0) -> ShellMesh:
    """Read the shell elements of a mesh file; coordinates times ``unit_mm`` give mm.

    ``.inp`` (Abaqus) and ``.bdf`` / ``.nas`` / ``.dat`` (Nastran) keep their labels; any
    other format meshio reads (``.stl``, ``.obj``, ``.vtu``, ``.msh``, ...) is labelled by
    position. Raises ValueError (with the file name) for a file without shell elements.
    """
    file = Path(path)
    if not np.isfinite(unit_mm) or unit_mm <= 0:
        raise ValueError(f"unit_mm must be a positive length in mm, got {unit_mm!r}")
    suffix = file.suffix.lower()
    if suffix == ".inp":
        mesh = _read_abaqus(file)
    elif suffix in (".bdf", ".nas", ".dat"):
        mesh = _read_nastran(file)
    else:
        mesh = _read_meshio(file)
    if mesh.n_elements == 0:
        raise ValueError(f"{file}: no shell elements (triangles or quadrilaterals) in the file")
    return ShellMesh(
        points=mesh.points * float(unit_mm),
        node_ids=mesh.node_ids,
        corners=mesh.corners,
        element_ids=mesh.element_ids,
        property_ids=mesh.property_ids,
        labels_from=mesh.labels_from,
        source=str(file),
    )


def _read_meshio(file: Path) -> ShellMesh:
    try:
        import meshio
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise ImportError('Reading meshes needs meshio: pip install "preform[vtk]"') from exc
    try:
        mesh = meshio.read(file)
    except Exception as error:  # meshio raises its own ReadError, KeyError, ... per format
        raise ValueError(f"{file}: meshio cannot read it: {error}") from None
    blocks = []
    for block in mesh.cells:
        keep = MESHIO_SHELLS.get(block.type)
        if keep is not None:
            blocks.append(np.asarray(block.data)[:, :keep])
    corners = [row for b in blocks for row in b.tolist()]
    points = np.asarray(mesh.points, dtype=float)[:, :3]
    bad = np.flatnonzero(~np.all(np.isfinite(points), axis=1))
    if bad.size:
        raise ValueError(
            f"{file}: {bad.size} node(s) with a coordinate that is not a finite number (the "
            f"first is node {bad[0] + 1} in the file's order: {points[bad[0]].tolist()})"
        )
    return shell_mesh(points, corners, source=str(file))


def _keyword(line: str) -> tuple[str, dict[str, str]]:
    parts = [p.strip() for p in line[1:].split(",")]
    params = {}
    for p in parts[1:]:
        key, _, value = p.partition("=")
        params[key.strip().upper()] = value.strip()
    return parts[0].upper(), params


#: Abaqus shell element types by their first letters (S3, S4R, S8R, STRI3, M3D4, ...).
_ABAQUS_SHELL_CORNERS = {3: 3, 4: 4, 6: 3, 8: 4, 9: 4}


def _node(
    nodes: dict[int, tuple[float, float, float]],
    lines: dict[int, int],
    label: int,
    xyz: list[float],
    lineno: int,
) -> None:
    """Record node ``label`` at ``xyz`` read on line ``lineno``: refused when defined before
    (a second definition would silently move every element on it) or not finite."""
    if label in lines:
        raise ValueError(f"node {label} is defined twice (first on line {lines[label]})")
    if not all(np.isfinite(xyz)):
        raise ValueError(f"node {label} has a coordinate that is not a finite number: {xyz}")
    nodes[label] = (xyz[0], xyz[1], xyz[2])
    lines[label] = lineno


def _element(
    elements: list[tuple[int, list[int]]],
    lines: dict[int, int],
    label: int,
    corners: list[int],
    lineno: int,
) -> None:
    """Record element ``label`` read on line ``lineno``: refused when defined before (both
    would be written, one label with two orientations, which a solver rejects)."""
    if label in lines:
        raise ValueError(f"element {label} is defined twice (first on line {lines[label]})")
    elements.append((label, corners))
    lines[label] = lineno


def _read_abaqus(file: Path) -> ShellMesh:
    nodes: dict[int, tuple[float, float, float]] = {}
    elements: list[tuple[int, list[int]]] = []
    node_lines: dict[int, int] = {}
    element_lines: dict[int, int] = {}
    section = ""
    pending: list[str] = []
    first_line = 0
    with open(file, encoding="utf-8", errors="replace") as handle:
        for lineno, raw in enumerate(handle, start=1):
            line = raw.strip()
            if not line or line.startswith("**"):
                continue
            if line.startswith("*"):
                name, params = _keyword(line)
                section = ""
                if name == "NODE":
                    section = "node"
                elif name == "ELEMENT":
                    kind = params.get("TYPE", "").upper()
                    # S*, STRI*, M3D* and SC* elements are shells/membranes; solids are skipped
                    if kind.startswith(("S", "M3D", "SC")) and not kind.startswith("SPRING"):
                        section = "element"
                continue
            try:
                if section == "node":
                    fields = [f for f in line.split(",") if f.strip()]
                    xyz = [float(f) for f in fields[1:4]] + [0.0] * (4 - len(fields))
                    _node(nodes, node_lines, int(fields[0]), xyz, lineno)
                elif section == "element":
                    if not pending:
                        first_line = lineno
                    pending.extend(f for f in line.split(",") if f.strip())
                    if line.endswith(","):
                        continue  # the element continues on the next line
                    label, *conn = (int(f) for f in pending)
                    pending = []
                    n_corner = _ABAQUS_SHELL_CORNERS.get(len(conn))
                    if n_corner is None:
                        raise ValueError(f"a shell element with {len(conn)} nodes")
                    _element(elements, element_lines, label, conn[:n_corner], first_line)
            except ValueError as error:
                raise ValueError(f"{file}:{lineno}: {error}") from None
    return _labelled(file, nodes, elements, [0] * len(elements))


def _nastran_fields(line: str) -> list[str]:
    if "," in line:
        return [f.strip() for f in line.split(",")]
    width = 16 if line[:8].rstrip().endswith("*") else 8
    head = [line[:8].strip()]
    body = line[8 : 8 + 4 * width] if width == 16 else line[8:72]
    return head + [body[k : k + width].strip() for k in range(0, len(body), width)]


def _nastran_float(text: str) -> float:
    text = text.strip()
    try:
        return float(text)
    except ValueError:
        # Nastran's exponent without E: 1.5-3 is 1.5e-3, -2.+4 is -2e4
        for k in range(len(text) - 1, 0, -1):
            if text[k] in "+-" and text[k - 1] not in "eE":
                return float(text[:k] + "e" + text[k:])
        raise


def _read_nastran(file: Path) -> ShellMesh:
    nodes: dict[int, tuple[float, float, float]] = {}
    elements: list[tuple[int, list[int]]] = []
    pids: list[int] = []
    node_lines: dict[int, int] = {}
    element_lines: dict[int, int] = {}
    corner_count = {"CTRIA3": 3, "CTRIA6": 3, "CTRIAR": 3, "CQUAD4": 4, "CQUAD8": 4, "CQUADR": 4}
    lines = Path(file).read_text(encoding="utf-8", errors="replace").splitlines()
    k = 0
    while k < len(lines):
        raw = lines[k].rstrip("\n")
        k += 1
        card_line = k
        if not raw.strip() or raw.lstrip().startswith("$"):
            continue
        fields = _nastran_fields(raw)
        card = fields[0].upper().rstrip("*")
        if fields[0].endswith("*") and k < len(lines) and lines[k].startswith("*"):
            cont = lines[k]
            k += 1
            fields += [cont[8 + 16 * n : 8 + 16 * (n + 1)].strip() for n in range(4)]
        try:
            if card == "GRID":
                xyz = [_nastran_float(f) if f else 0.0 for f in fields[3:6]]
                xyz += [0.0] * (3 - len(xyz))
                if fields[2].strip() not in ("", "0"):
                    raise ValueError("GRID in a local coordinate system (CP) is not supported")
                _node(nodes, node_lines, int(fields[1]), xyz, card_line)
            elif card in corner_count:
                n = corner_count[card]
                conn = [int(f) for f in fields[3 : 3 + n]]
                _element(elements, element_lines, int(fields[1]), conn, card_line)
                pids.append(int(fields[2]) if fields[2] else 0)
        except (ValueError, IndexError) as error:
            raise ValueError(f"{file}:{card_line}: {card}: {error}") from None
    return _labelled(file, nodes, elements, pids)


def _labelled(
    file: Path,
    nodes: dict[int, tuple[float, float, float]],
    elements: list[tuple[int, list[int]]],
    pids: list[int],
) -> ShellMesh:
    node_ids = np.array(sorted(nodes), dtype=np.int64)
    index = {label: k for k, label in enumerate(node_ids.tolist())}
    points = np.array([nodes[n] for n in node_ids.tolist()], dtype=float).reshape(-1, 3)
    corners = []
    for label, conn in elements:
        missing = [n for n in conn if n not in index]
        if missing:
            raise ValueError(f"{file}: element {label} refers to undefined node(s) {missing}")
        corners.append([index[n] for n in conn])
    mesh = shell_mesh(
        points,
        corners,
        element_ids=np.array([e[0] for e in elements], dtype=np.int64),
        node_ids=node_ids,
        property_ids=np.array(pids, dtype=np.int64),
        source=str(file),
    )
    return mesh
