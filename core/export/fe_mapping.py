"""The draped ply mapped onto the user's shell mesh: per element, the two fibre directions in the
element's plane, the shear angle, the thickness, and flags.

How (and how accurate):

1. **Which net cell.** Each element's centroid is put at its closest point on the draped net:
   every net cell of the draped region (valid and in the part) is split into two triangles
   along its (i, j)–(i+1, j+1) diagonal and the nearest of the cells whose centroids are
   nearest is searched exactly. The closest point gives net coordinates (i + s, j + t).
2. **Covered or not.** An element is covered when that closest point is the foot of a
   perpendicular (its offset along the net's surface is at most 5 % of the node spacing d, so
   the centroid is not beyond the net's edge) and the gap normal to the net is at most
   ``max_gap_mm`` (default d, which tolerates a mesh faceted differently from the tool), and
   the element has an area (a degenerate one has no plane). Elements that are not covered are *reported* (``covered`` False, NaN fields, counted and
   listed), never given a default value.
3. **Interpolation inside cells.** The drape's fields live at cell centres (i + ½, j + ½);
   a covered element gets the bilinear interpolation of the four cell centres around
   (i + s, j + t), with weights of cells outside the draped region dropped and the rest
   renormalised. This is exact for fields linear in the net coordinates, so the error is
   O(d²) in the interior, O(d) within one cell of the net's edge.
4. **Into the element's plane.** Fibre directions are projected into the plane of the
   element (normal by the right-hand rule on its node order) and normalised: that is the
   vector a shell solver can use. Angles to the reference direction (itself projected) are
   signed about the element normal, in degrees.

Mapping the net onto a mesh made of the net's own cells reproduces the net's fields to
rounding (the centroid of net cell (i, j) maps to (i + ½, j + ½) exactly, up to the cell's
non-planarity), which the tests check, and on a hemisphere the mapped shear approaches the
drape's at the element centroids as O(d²).

Thickness: the ratio t/t0 comes from the drape's energy field, which carries the case's one
thickness model (``preform.drape.properties.thickness``: the fabric's sheared unit cell where it has one,
else constant fibre volume fraction, 1/cos γ), and the thickness in mm is t0 · t/t0 when the
nominal thickness t0 is known; ``thickness_reference`` says where t0 comes from. A compaction cap (a ratio past which the
fabric cannot thicken further) is reported per element (``above_thickness_cap``) and counted,
never silently applied.

Units: mm for lengths, degrees for angles, J/m² for energy density; preform's SI drape result
is converted here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from preform.base.arrays import BoolArray, FloatArray, IntArray
from preform.drape.engine.result import DrapeResult, EnergyField
from preform.export.shell_mesh import ShellMesh

MM_PER_M = 1e3
#: Share of the node spacing a centroid may lie past the net's edge and still count as covered.
EDGE_TOLERANCE = 0.05
#: Net cells searched per element (nearest by centroid); enough for any element whose
#: centroid lies on a net of sane (non-folded) cells.
CANDIDATES = 8


@dataclass(frozen=True)
class MeshMapping:
    """The drape on each element of a :class:`ShellMesh`; arrays have one row per element.

    Float fields are NaN exactly where ``covered`` is False, and flags are False there.
    """

    mesh: ShellMesh
    covered: BoolArray
    #: Element centroid (m, 3) [mm] and unit normal (m, 3) (right-hand rule on node order).
    centroid_mm: FloatArray
    normal: FloatArray
    #: Unit fibre directions of the u and v families, projected into the element's plane (m, 3).
    fibre_u: FloatArray
    fibre_v: FloatArray
    #: Signed angle from the (projected) reference direction to each fibre, about the element
    #: normal [deg], in (−180, 180].
    angle_u_deg: FloatArray
    angle_v_deg: FloatArray
    #: Signed shear angle γ [deg], interpolated from the drape (sign convention of
    #: ``preform.drape.engine.result``).
    shear_deg: FloatArray
    #: Thickness ratio t/t0 [-] and thickness [mm] (NaN throughout when t0 is unknown).
    thickness_ratio: FloatArray
    thickness_mm: FloatArray
    #: Shear strain energy density W [J/m²] (NaN throughout without an energy field).
    energy_J_per_m2: FloatArray
    #: The element lies on a net cell past the law's locking / stitch-failure angle.
    past_locking: BoolArray
    past_failure: BoolArray
    #: The thickness ratio is above the compaction cap (never capped, only flagged).
    above_thickness_cap: BoolArray
    #: Distance from the centroid to its closest point on the net [mm] (NaN if no net).
    gap_mm: FloatArray
    #: Net cell (i, j) holding the closest point (−1 where not covered).
    cell_i: IntArray
    cell_j: IntArray
    #: Unit reference direction (global frame) the angles are measured from.
    reference_direction: tuple[float, float, float]
    nominal_thickness_mm: float | None
    thickness_model: str
    thickness_cap_ratio: float | None
    node_spacing_mm: float
    max_gap_mm: float
    #: Elements whose reference direction is normal to them (angles NaN there).
    reference_normal_to_element: BoolArray = field(default_factory=lambda: np.zeros(0, bool))
    #: Where t0 comes from, in words (``preform.drape.properties.thickness``), None when not said.
    thickness_reference: str | None = None

    @property
    def thickness_words(self) -> str:
        """The thickness model and t0 with its source, for the exports' comments."""
        words = self.thickness_model
        if self.nominal_thickness_mm is not None:
            words += f"; t0 = {self.nominal_thickness_mm:g} mm"
            if self.thickness_reference:
                words += f" ({self.thickness_reference})"
        return words

    @property
    def uncovered_ids(self) -> IntArray:
        """Labels of the elements the drape does not cover."""
        return np.asarray(self.mesh.element_ids[~self.covered])

    def summary(self) -> dict[str, Any]:
        """JSON-ready counts and extremes (degrees, mm)."""
        cov = self.covered
        n = int(cov.size)
        out: dict[str, Any] = {
            "mesh": self.mesh.source,
            "element_labels_from": self.mesh.labels_from,
            "elements": n,
            "elements_covered": int(np.count_nonzero(cov)),
            "elements_uncovered": int(n - np.count_nonzero(cov)),
            "covered_fraction": float(np.count_nonzero(cov) / n) if n else 0.0,
            "uncovered_element_ids": self.uncovered_ids.tolist(),
            "elements_past_locking": int(np.count_nonzero(self.past_locking)),
            "elements_past_failure": int(np.count_nonzero(self.past_failure)),
            "elements_above_thickness_cap": int(np.count_nonzero(self.above_thickness_cap)),
            "thickness_cap_ratio": self.thickness_cap_ratio,
            "thickness_model": self.thickness_model,
            "nominal_thickness_mm": self.nominal_thickness_mm,
            "thickness_reference": self.thickness_reference,
            "reference_direction": list(self.reference_direction),
            "node_spacing_mm": self.node_spacing_mm,
            "max_gap_mm": self.max_gap_mm,
            "length_unit": "mm",
            "angle_unit": "deg",
        }
        if cov.any():
            out["max_abs_shear_deg"] = float(np.max(np.abs(self.shear_deg[cov])))
            out["max_thickness_ratio"] = float(np.max(self.thickness_ratio[cov]))
            out["max_gap_found_mm"] = float(np.max(self.gap_mm[cov]))
        return out


def _closest_on_triangles(
    p: FloatArray, a: FloatArray, b: FloatArray, c: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Closest point of triangles (a, b, c) to points p, all (k, 3): returns the point and its
    coordinates (λ_b, λ_c) with point = a + λ_b (b − a) + λ_c (c − a).

    Region by region (vertex, edge, face), after Ericson's *Real-Time Collision Detection*
    §5.1.5, vectorised: each point keeps the first region test it passes.
    """
    ab, ac, ap = b - a, c - a, p - a
    d1 = np.einsum("ij,ij->i", ab, ap)
    d2 = np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3 = np.einsum("ij,ij->i", ab, bp)
    d4 = np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5 = np.einsum("ij,ij->i", ab, cp)
    d6 = np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(invalid="ignore", divide="ignore"):
        denom = va + vb + vc
        lb = vb / denom
        lc = vc / denom
        # edges: ab, ac, bc
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    done = np.zeros(len(p), dtype=bool)

    def take(mask: BoolArray, mb: FloatArray | float, mc: FloatArray | float) -> None:
        nonlocal done
        sel = mask & ~done
        lb[sel] = np.broadcast_to(mb, lb.shape)[sel]
        lc[sel] = np.broadcast_to(mc, lc.shape)[sel]
        done |= sel

    take((d1 <= 0) & (d2 <= 0), 0.0, 0.0)  # vertex a
    take((d3 >= 0) & (d4 <= d3), 1.0, 0.0)  # vertex b
    take((d6 >= 0) & (d5 <= d6), 0.0, 1.0)  # vertex c
    take((vc <= 0) & (d1 >= 0) & (d3 <= 0), t_ab, 0.0)
    take((vb <= 0) & (d2 >= 0) & (d6 <= 0), 0.0, t_ac)
    take((va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0), 1.0 - t_bc, t_bc)
    point = a + lb[:, None] * ab + lc[:, None] * ac
    return point, lb, lc


def _unit(v: FloatArray) -> FloatArray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(v / np.linalg.norm(v, axis=-1, keepdims=True))


def _in_plane(v: FloatArray, n: FloatArray) -> FloatArray:
    return _unit(v - np.einsum("ij,ij->i", v, n)[:, None] * n)


def _signed_angle_deg(ref: FloatArray, vec: FloatArray, n: FloatArray) -> FloatArray:
    sin = np.einsum("ij,ij->i", np.cross(ref, vec), n)
    cos = np.einsum("ij,ij->i", ref, vec)
    return np.asarray(np.degrees(np.arctan2(sin, cos)))


@dataclass(frozen=True)
class NetHit:
    """Closest points on a draped net, one per query point."""

    #: Continuous net coordinates (i + s, j + t) of the closest point.
    a: FloatArray
    b: FloatArray
    #: The cell holding it.
    cell_i: IntArray
    cell_j: IntArray
    #: Distance along the net's normal there, and along its surface (non-zero only past
    #: the net's edge) [mm].
    gap_mm: FloatArray
    tangential_mm: FloatArray


def closest_on_net(
    result: DrapeResult, points_mm: FloatArray, region: BoolArray | None = None, tree: Any = None
) -> NetHit:
    """Closest point on the draped net [m] to each of ``points_mm`` (k, 3) [mm], over the
    cells of ``region`` (default: valid and in the part; it must hold at least one cell).
    ``tree``: the caller's ``cKDTree`` of the region cells' centroids [mm] in
    ``np.nonzero(region)`` order, when it has one (built here otherwise).

    Each cell is two triangles split along its (i, j)–(i+1, j+1) diagonal, so (s, t) is
    linear on each half; the nearest cells by centroid are searched exactly."""
    from scipy.spatial import cKDTree

    if region is None:
        region = np.asarray(result.valid & result.in_part, dtype=bool)
    ci_all, cj_all = np.nonzero(region)
    if ci_all.size == 0:
        raise ValueError("the draped net has no cell to map onto")
    points = np.asarray(points_mm, dtype=float).reshape(-1, 3)
    m = len(points)
    nodes = MM_PER_M * np.asarray(result.nodes, dtype=float)
    if tree is None:
        tree = cKDTree(MM_PER_M * np.asarray(result.centroid, dtype=float)[ci_all, cj_all])
    k = min(CANDIDATES, ci_all.size)
    _, nearest = tree.query(points, k=k)
    nearest = np.asarray(nearest).reshape(m, k)
    pi = np.repeat(np.arange(m), k)
    ci, cj = ci_all[nearest.ravel()], cj_all[nearest.ravel()]
    p = points[pi]
    x00, x10 = nodes[ci, cj], nodes[ci + 1, cj]
    x11, x01 = nodes[ci + 1, cj + 1], nodes[ci, cj + 1]
    # Triangle A (x00, x10, x11): s = λ_b + λ_c, t = λ_c. Triangle B (x00, x11, x01):
    # s = λ_b, t = λ_b + λ_c.
    qa, la, ma = _closest_on_triangles(p, x00, x10, x11)
    qb, lb_, mb = _closest_on_triangles(p, x00, x11, x01)
    da = np.linalg.norm(p - qa, axis=1)
    db = np.linalg.norm(p - qb, axis=1)
    use_a = da <= db
    q = np.where(use_a[:, None], qa, qb)
    dist = np.where(use_a, da, db).reshape(m, k)
    s = np.where(use_a, la + ma, lb_)
    t = np.where(use_a, ma, lb_ + mb)
    tri_normal = _unit(
        np.where(use_a[:, None], np.cross(x10 - x00, x11 - x00), np.cross(x11 - x00, x01 - x00))
    )
    pick = np.arange(m) * k + np.argmin(dist, axis=1)
    offset = p[pick] - q[pick]
    n_best = tri_normal[pick]
    along_normal = np.einsum("ij,ij->i", offset, n_best)
    tangential = np.linalg.norm(offset - along_normal[:, None] * n_best, axis=1)
    return NetHit(
        a=ci[pick] + s[pick],
        b=cj[pick] + t[pick],
        cell_i=ci[pick],
        cell_j=cj[pick],
        gap_mm=np.abs(along_normal),
        tangential_mm=tangential,
    )


def map_to_mesh(
    result: DrapeResult,
    mesh: ShellMesh,
    energy: EnergyField | None = None,
    *,
    reference_direction: tuple[float, float, float] = (1.0, 0.0, 0.0),
    nominal_thickness_mm: float | None = None,
    thickness_cap_ratio: float | None = None,
    max_gap_mm: float | None = None,
    thickness_reference: str | None = None,
) -> MeshMapping:
    """Map a draped net [m] onto ``mesh`` [mm] (module docstring: method and accuracy).

    ``reference_direction``: global vector the fibre angles are measured from (projected into
    each element). ``nominal_thickness_mm``: the undeformed ply thickness t0 [mm], for
    ``thickness_mm``. ``thickness_cap_ratio``: the compaction limit of t/t0, flagged where
    exceeded. ``max_gap_mm``: largest normal distance [mm] between an element centroid and
    the net for it to count as covered (default: the node spacing d). ``thickness_reference``:
    where t0 comes from, in words, for the exports' comments.
    """
    d_mm = MM_PER_M * float(result.node_spacing)
    gap_limit = d_mm if max_gap_mm is None else float(max_gap_mm)
    ref = np.asarray(reference_direction, dtype=float)
    if ref.shape != (3,) or not np.all(np.isfinite(ref)) or np.linalg.norm(ref) == 0:
        raise ValueError(f"reference_direction must be a non-zero 3-vector, got {ref.tolist()}")
    ref = ref / np.linalg.norm(ref)

    m = mesh.n_elements
    centroid = mesh.centroids()
    normal = mesh.normals()
    region = np.asarray(result.valid & result.in_part, dtype=bool)
    ci_all, _ = np.nonzero(region)
    nan3 = np.full((m, 3), np.nan)
    nan1 = np.full(m, np.nan)
    covered = np.zeros(m, dtype=bool)
    cell_i = np.full(m, -1, dtype=np.int64)
    cell_j = np.full(m, -1, dtype=np.int64)
    gap = nan1.copy()
    a_coord = nan1.copy()
    b_coord = nan1.copy()

    if ci_all.size and m:
        hit = closest_on_net(result, centroid, region)
        gap = hit.gap_mm
        covered = (hit.tangential_mm <= EDGE_TOLERANCE * d_mm) & (gap <= gap_limit)
        # a degenerate element (zero area) has no plane to put a direction in
        covered &= np.all(np.isfinite(normal), axis=1)
        cell_i = np.where(covered, hit.cell_i, -1)
        cell_j = np.where(covered, hit.cell_j, -1)
        a_coord, b_coord = hit.a, hit.b

    fields: dict[str, FloatArray] = {}
    if covered.any():
        per_cell: dict[str, FloatArray] = {
            "fibre_u": np.asarray(result.fibre_u, dtype=float),
            "fibre_v": np.asarray(result.fibre_v, dtype=float),
            "shear": np.asarray(result.shear, dtype=float)[..., None],
        }
        if energy is not None:
            per_cell["ratio"] = np.asarray(energy.thickness_ratio, dtype=float)[..., None]
            per_cell["energy"] = np.asarray(energy.energy_density, dtype=float)[..., None]
        values = _dual_bilinear(per_cell, region, a_coord[covered], b_coord[covered])
        for name, v in values.items():
            out = np.full((m, v.shape[1]), np.nan)
            out[covered] = v
            fields[name] = out

    if covered.any():
        n = normal
        fu = _in_plane(fields["fibre_u"], n)
        fv = _in_plane(fields["fibre_v"], n)
        ref_p = _in_plane(np.broadcast_to(ref, (m, 3)).copy(), n)
        ref_bad = covered & ~np.all(np.isfinite(ref_p), axis=1)
        ref_bad |= covered & (
            np.linalg.norm(np.cross(np.broadcast_to(ref, (m, 3)), n), axis=1) < 1e-6
        )
        ref_p[ref_bad] = np.nan
        angle_u = _signed_angle_deg(ref_p, fu, n)
        angle_v = _signed_angle_deg(ref_p, fv, n)
        shear_rad = fields["shear"][:, 0]
        ratio = fields["ratio"][:, 0] if "ratio" in fields else 1.0 / np.cos(shear_rad)
        energy_density = fields["energy"][:, 0] if "energy" in fields else nan1.copy()
    else:
        fu, fv, angle_u, angle_v = nan3.copy(), nan3.copy(), nan1.copy(), nan1.copy()
        shear_rad, ratio, energy_density = nan1.copy(), nan1.copy(), nan1.copy()
        ref_bad = np.zeros(m, dtype=bool)

    def flag(values: BoolArray | None) -> BoolArray:
        out = np.zeros(m, dtype=bool)
        if values is not None and covered.any():
            out[covered] = np.asarray(values, dtype=bool)[cell_i[covered], cell_j[covered]]
        return out

    thickness = nominal_thickness_mm * ratio if nominal_thickness_mm is not None else nan1.copy()
    above = np.zeros(m, dtype=bool)
    if thickness_cap_ratio is not None:
        above = covered & (np.nan_to_num(ratio, nan=0.0) > thickness_cap_ratio)
    model = energy.thickness_model if energy is not None else EnergyField.thickness_model
    return MeshMapping(
        mesh=mesh,
        covered=covered,
        centroid_mm=centroid,
        normal=normal,
        fibre_u=fu,
        fibre_v=fv,
        angle_u_deg=angle_u,
        angle_v_deg=angle_v,
        shear_deg=np.degrees(shear_rad),
        thickness_ratio=np.asarray(ratio, dtype=float),
        thickness_mm=np.asarray(thickness, dtype=float),
        energy_J_per_m2=np.asarray(energy_density, dtype=float),
        past_locking=flag(None if energy is None else energy.past_locking),
        past_failure=flag(None if energy is None else energy.past_failure),
        above_thickness_cap=above,
        gap_mm=gap,
        cell_i=cell_i,
        cell_j=cell_j,
        reference_direction=(float(ref[0]), float(ref[1]), float(ref[2])),
        nominal_thickness_mm=nominal_thickness_mm,
        thickness_model=model,
        thickness_cap_ratio=thickness_cap_ratio,
        node_spacing_mm=d_mm,
        max_gap_mm=gap_limit,
        reference_normal_to_element=ref_bad,
        thickness_reference=thickness_reference,
    )


def _dual_bilinear(
    per_cell: dict[str, FloatArray], region: BoolArray, a: FloatArray, b: FloatArray
) -> dict[str, FloatArray]:
    """Bilinear interpolation of cell-centred fields (n1, n2, c) at net coordinates (a, b):
    cell (p, q) sits at (p + ½, q + ½); cells outside ``region`` drop out and the remaining
    weights are renormalised (the containing cell always keeps a weight of at least ¼)."""
    n1, n2 = region.shape
    ap, bp = a - 0.5, b - 0.5
    p0 = np.floor(ap).astype(np.int64)
    q0 = np.floor(bp).astype(np.int64)
    fa, fb = ap - p0, bp - q0
    total = np.zeros(len(a))
    sums = {name: np.zeros((len(a), v.shape[-1])) for name, v in per_cell.items()}
    for dp, dq, w in (
        (0, 0, (1 - fa) * (1 - fb)),
        (1, 0, fa * (1 - fb)),
        (0, 1, (1 - fa) * fb),
        (1, 1, fa * fb),
    ):
        p, q = p0 + dp, q0 + dq
        inside = (p >= 0) & (p < n1) & (q >= 0) & (q < n2)
        pc, qc = np.clip(p, 0, n1 - 1), np.clip(q, 0, n2 - 1)
        use = inside & region[pc, qc]
        weight = np.where(use, w, 0.0)
        total += weight
        for name, v in per_cell.items():
            sums[name] += weight[:, None] * np.where(use[:, None], v[pc, qc], 0.0)
    return {name: s / total[:, None] for name, s in sums.items()}
