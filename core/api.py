"""The Python API: a thin, typed facade over the steps the command line runs, in mm and degrees.

::

    import preform

    lib = preform.load_library()                        # bundled + PREFORM_LIBRARY (+ paths)
    fabric = lib.fabric("E-BX-318")
    d = preform.drape(fabric, generator_angle_deg=80)   # the bundled hemisphere scene
    d.status, d.summary["max_abs_shear_deg"], d.to_pandas(), d.plot(), d.to_vtu("d.vtu")
    best = preform.least_energy("E-BX-318", generator_angle_range_deg=(40, 140))
    best.optimum_generator_angle_deg, best.energy_vs_angle, best.drape.to_pandas()
    run = preform.run(scenes=["shear"], out_dir="results")   # every fabric, as `pipeline run`

Every call runs one (material, scene) case exactly as ``preform pipeline run`` does: the same
scene validation, the same planned steps, ``preform.pipeline.runner.execute_case``, the same
status (``ok``, ``partial``, ``failed``) with the same reasons and warnings. Arguments carry their
unit in their name (``_mm``, ``_deg``); results are in mm, degrees and J, as in the tables. SI
stays inside the steps. Nothing here imports numpy, pandas or matplotlib before it is used.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from preform.compare.measurement import Measurement
    from preform.library import Library
    from preform.material import FabricBase
    from preform.pipeline.runner import CaseResult, RunReport
    from preform.pipeline.scene import Scene
    from preform.shear.calibrate import Calibration
    from preform.step import CaseContext

PathLike = str | os.PathLike[str]

#: Keyword arguments of :func:`scene` and where each goes in the scene (units in the names).
SCENE_KEYWORDS: dict[str, tuple[str, ...]] = {
    "name": ("name",),
    "tool": ("tool",),
    "node_spacing_mm": ("ply", "node_spacing_mm"),
    "ply_size_mm": ("ply", "size_mm"),
    "ply_outline_mm": ("ply", "outline_mm"),
    "start_point_mm": ("start", "point_mm"),
    "orientation_deg": ("start", "orientation_deg"),
    "generator_angle_deg": ("start", "generator_angle_deg"),
    "generators": ("start", "generators"),
    "fidelity": ("fidelity",),
    "outputs": ("outputs",),
    "wrinkle_area_tolerance": ("search", "wrinkle_area_tolerance"),
    "max_wrinkle_area_share": ("search", "max_wrinkle_area_share"),
}

#: The scenes the API starts from when given none (bundled; see ``preform scenes list``).
DRAPE_SCENE = "hemisphere"
LEAST_ENERGY_SCENE = "hemisphere-min-energy"
#: The generator-angle range searched when a scene has no ``search`` section [deg].
DEFAULT_RANGE_DEG = (30.0, 150.0)


def _host() -> Any:
    from preform.plugin_manager import default_host

    return default_host()


def _plain(value: Any) -> Any:
    """Tuples and arrays as lists, numpy scalars as Python numbers: YAML-ready scene data."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if hasattr(value, "tolist"):
        return _plain(value.tolist())
    return value


# -- library and fabrics ----------------------------------------------------------------------


def load_library(
    paths: PathLike | Sequence[PathLike] = (),
    *,
    bundled: bool = True,
    env: bool = True,
) -> Library:
    """The materials library: the bundled fabrics (unless ``bundled=False``), the paths in
    ``PREFORM_LIBRARY`` (unless ``env=False``), then ``paths`` (a file or folder, or several),
    as ``--library`` and ``--no-bundled`` do. Raises ``preform.library.LibraryError`` listing
    every problem as ``FILE:LINE:COL: field: message``.

    ``library.fabric(name)`` gives a fabric; ``library.names()`` lists them.
    """
    from preform.library import load_library as load

    listed = [paths] if isinstance(paths, str | os.PathLike) else list(paths)
    return load(listed, bundled=bundled, env=env, registry=_host().registry)


def fabric(name: str, library: Library | None = None) -> FabricBase:
    """The fabric called ``name`` from ``library`` (default: :func:`load_library`). A
    ``KeyError`` suggests close names."""
    return (library or load_library()).fabric(name)


def _fabric(spec: Any, library: Library | None) -> FabricBase:
    """The fabric ``spec`` names or is; a TypeError naming the argument for anything else."""
    from preform.library import Library
    from preform.material import FabricBase

    if library is not None and not isinstance(library, Library):
        raise TypeError(
            "library must be a loaded library (preform.load_library()) or None, got "
            f"{type(library).__name__} {library!r}"
        )
    if isinstance(spec, str):
        return fabric(spec, library)
    if isinstance(spec, FabricBase):
        return spec
    raise TypeError(
        "fabric must be a fabric's name (str) or a fabric (preform.fabric(name)), got "
        f"{type(spec).__name__} {spec!r}"
    )


# -- scenes -------------------------------------------------------------------------------------


def _changes(keywords: Mapping[str, Any]) -> dict[tuple[str, ...], Any]:
    changes: dict[tuple[str, ...], Any] = {}
    for key, value in keywords.items():
        if value is None:
            continue
        if key == "generator_angle_range_deg":
            low, high = (float(v) for v in value)
            changes[("search", "generator_angle_deg")] = {"min": low, "max": high}
        elif key in SCENE_KEYWORDS:
            changes[SCENE_KEYWORDS[key]] = _plain(value)
        else:
            known = ", ".join([*SCENE_KEYWORDS, "generator_angle_range_deg"])
            raise TypeError(f"unknown scene keyword {key!r}; known: {known}")
    return changes


def _scene_and_data(
    spec: Any, changes: Mapping[tuple[str, ...], Any]
) -> tuple[Scene, dict[str, Any]]:
    from preform.pipeline.overrides import changed_data, load_scene_changed, scene_from_mapping
    from preform.pipeline.scene import Scene, missing_scene_message, resolve_scene_path

    registry = _host().registry
    if isinstance(spec, Scene):
        data = spec.model_dump(mode="json", exclude_none=True)
        return scene_from_mapping(
            changed_data(data, changes), registry, base_dir=spec.base_dir, label=spec.name
        )
    if isinstance(spec, Mapping):
        return scene_from_mapping(changed_data(_plain(spec), changes), registry)
    if not isinstance(spec, str | os.PathLike):
        raise TypeError(
            "scene must be a bundled scene's name, a scene file (str or path), a mapping of "
            f"scene data or a Scene, got {type(spec).__name__} {spec!r}"
        )
    path = resolve_scene_path(os.fspath(spec))
    if not path.is_file():
        raise FileNotFoundError(missing_scene_message(os.fspath(spec)))
    return load_scene_changed(path, registry, changes)


def scene(
    spec: Any = DRAPE_SCENE,
    *,
    name: str | None = None,
    tool: Mapping[str, Any] | None = None,
    node_spacing_mm: float | None = None,
    ply_size_mm: tuple[float, float] | None = None,
    ply_outline_mm: Sequence[tuple[float, float]] | None = None,
    start_point_mm: tuple[float, float] | None = None,
    orientation_deg: float | None = None,
    generator_angle_deg: float | None = None,
    generators: str | None = None,
    generator_angle_range_deg: tuple[float, float] | None = None,
    fidelity: str | None = None,
    outputs: Sequence[str] | None = None,
    wrinkle_area_tolerance: float | None = None,
    max_wrinkle_area_share: float | None = None,
) -> Scene:
    """A validated scene: ``spec`` (a bundled scene's name, a scene file, a mapping of scene
    data, or a ``Scene``) with the keyword arguments set.

    ``tool`` is the YAML's tool block (``{"surface": "hemisphere", "radius_mm": 100}``;
    ``preform schema --scene`` lists every surface); ``node_spacing_mm``, ``ply_size_mm`` (along
    the two fibre families), ``ply_outline_mm`` and ``start_point_mm`` (plan x, y) are in mm;
    ``orientation_deg`` (plan direction of the first generator), ``generator_angle_deg`` (angle
    between the generators) and ``generator_angle_range_deg`` (the least-energy search's range)
    in degrees; ``fidelity`` is ``draft``, ``standard`` or ``fine``; ``wrinkle_area_tolerance``
    and ``max_wrinkle_area_share`` (shares 0..1 of the part area) are the search's rule of what
    can be made (docs/physics.md, "Wrinkling and what can be made"). Invalid values raise
    ``preform.pipeline.scene.SceneError`` with located messages, as a scene file would.
    """
    given = locals()
    keywords = {k: given[k] for k in (*SCENE_KEYWORDS, "generator_angle_range_deg")}
    return _scene_and_data(spec, _changes(keywords))[0]


# -- one case -----------------------------------------------------------------------------------


@dataclass(repr=False)
class CaseRun:
    """One (material, scene) case run from Python: the pipeline's own result and summary.

    ``status`` is ``ok``, ``partial`` or ``failed`` (or ``timed_out``), decided by the pipeline
    exactly as for ``preform pipeline run``; ``reasons`` say why a result is partial,
    ``warnings`` what to know about a complete one, ``error`` why it failed. ``summary`` is the
    case's ``summary.json``: its scalar results (mm, degrees, J), status, reasons, warnings and
    timings.
    """

    fabric: FabricBase
    scene: Scene
    #: The pipeline's record of the case (``preform.pipeline.runner.CaseResult``).
    case: CaseResult
    summary: dict[str, Any]
    #: The case's products in memory (SI, internal): the net, the search.
    products: dict[str, Any] = field(default_factory=dict)
    #: The case folder when ``out_dir`` was given (files the scene asked for, summary.json).
    case_dir: Path | None = None

    @property
    def status(self) -> str:
        return self.case.status

    @property
    def ok(self) -> bool:
        """True when the result is complete, finite and physical (status ``ok``: not mostly
        energy from cells past jamming or stitch failure)."""
        return self.case.status == "ok"

    @property
    def reasons(self) -> list[str]:
        return list(self.case.reasons)

    @property
    def warnings(self) -> list[str]:
        return list(self.case.warnings)

    @property
    def error(self) -> str | None:
        return self.case.error

    @property
    def wrinkling(self) -> dict[str, Any] | None:
        """Where the drape would wrinkle (summary.json's ``wrinkling`` block: per cause the
        cells, area [mm²] and share, energy share, patches [mm], excess [deg]); None when the
        case has no drape."""
        block = self.summary.get("wrinkling")
        return dict(block) if isinstance(block, Mapping) else None

    def raise_for_status(self) -> None:
        """Raise ``preform.CaseFailure`` with the case's error when it has no result."""
        from preform.base.status import CaseFailure

        if self.case.status not in ("ok", "partial"):
            raise CaseFailure(f"{self.case.case_id}: {self.case.status}: {self.case.error}")

    def _product(self, name: str) -> Any:
        if name not in self.products:
            from preform.base.status import CaseFailure

            raise CaseFailure(
                f"{self.case.case_id} has no {name} ({self.case.status}: "
                f"{self.case.error or 'not computed'})"
            )
        return self.products[name]

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.case.case_id}: {self.case.status}{self._headline()}>"

    def _headline(self) -> str:
        return f", {self.error}" if self.error else ""


def _execute(
    fab: FabricBase, scene_: Scene, data: dict[str, Any], out_dir: PathLike | None
) -> tuple[CaseResult, dict[str, Any], dict[str, Any], Path | None]:
    """Run one case through the pipeline's ``execute_case``; (result, summary, products, dir)."""
    from preform.pipeline.rundir import read_json
    from preform.pipeline.runner import Case, execute_case, folder_name, input_hash

    host = _host()
    fabric_data = fab.model_dump(mode="json", exclude_none=True)
    kept: list[CaseContext] = []
    with tempfile.TemporaryDirectory(prefix="preform-") as scratch:
        root = Path(out_dir) if out_dir is not None else Path(scratch)
        case_dir = root / folder_name(scene_.name) / folder_name(fab.name)
        case = Case(
            case_id=f"{scene_.name}/{fab.name}",
            material=fab.name,
            scene=scene_.name,
            fabric_data=fabric_data,
            scene_data=data,
            scene_base_dir=scene_.base_dir,
            case_dir=str(case_dir),
            input_hash=input_hash(fabric_data, scene_, data, host),
            timeout_s=scene_.limits.case_timeout_s,
        )
        result = execute_case(case, host, on_context=kept.append)
        summary = read_json(case_dir / "summary.json")
    products = dict(kept[0].products) if kept else {}
    record = summary if isinstance(summary, dict) else {}
    return result, record, products, case_dir if out_dir is not None else None


@dataclass(repr=False)
class Drape(CaseRun):
    """A draped ply (:func:`drape`): its status, summary, cells and pictures."""

    @property
    def generator_angle_deg(self) -> float:
        return float(self.summary["generator_angle_deg"])

    @property
    def total_energy_J(self) -> float:
        """Total shear strain energy of the draped part [J]."""
        return float(self.summary["total_energy_J"])

    @property
    def max_abs_shear_deg(self) -> float:
        return float(self.summary["max_abs_shear_deg"])

    def to_pandas(self) -> pd.DataFrame:
        """One row per cell (``cells.csv``): index (i, j), ``status`` by name (VALID,
        INCOMPLETE, FOLDED, OUTSIDE_PLY), centroid ``x_mm``/``y_mm``/``z_mm``, ``shear_deg``,
        ``area_mm2``, ``thickness_ratio``, ``thickness_mm``, ``energy_J_per_m2``,
        ``past_locking``/``past_failure``. The thickness is the one every output of the case
        gives (:attr:`thickness_model`)."""
        from preform.export.tables import cells_table

        return cells_table(self._product("drape").result, self._energy())

    @property
    def thickness_model(self) -> str:
        """Which model gives the cells' thickness, in words: "sheared unit cell" or
        "constant fibre volume fraction (1/cos γ)" (``preform.drape.properties.thickness``)."""
        return str(self._thickness().name)

    def _thickness(self) -> Any:
        # the case's own when an output of it needed a thickness, else the same model now
        if "thickness" not in self.products:
            from preform.drape.properties.thickness import thickness_model

            export = getattr(self.scene, "export", None)
            nominal = getattr(export, "nominal_thickness_mm", None)
            self.products["thickness"] = thickness_model(self.fabric, nominal)
        return self.products["thickness"]

    def _energy(self) -> Any:
        """The drape's energy field carrying the case's one thickness."""
        draped = self._product("drape")
        return self._thickness().applied(draped.result, draped.energy)

    def plot(self, path: PathLike | None = None) -> Figure:
        """The fibre pattern (top view with the tows, 3D view coloured by shear [deg]); saved
        to ``path`` (.png, .svg, .pdf) when given. Returns the matplotlib figure."""
        from preform.export.fig_drape import fibre_pattern_figure

        draped = self._product("drape")
        every = max(1, round(5e-3 / draped.result.node_spacing))  # a tow line every ~5 mm
        return fibre_pattern_figure(
            draped.result,
            draped.energy,
            path,
            title=self.fabric.name,
            tow_every=every,
            covered_fraction=self.summary.get("covered_fraction"),
        )

    def to_vtu(self, path: PathLike) -> Path:
        """Write the net as a VTK .vtu file for ParaView (cell data: shear, fibre directions,
        energy density, thickness ratio and thickness; coordinates in mm); returns the path."""
        from preform.export.vtu import write_drape_vtu

        draped = self._product("drape")
        write_drape_vtu(draped.result, self._energy(), path)
        return Path(path)

    def _headline(self) -> str:
        if "total_energy_J" not in self.summary:
            return super()._headline()
        share = float(self.summary.get("wrinkle_energy_share") or 0.0)
        # the energy says how much of it is the law's continuation where the fabric wrinkles
        past = f" ({100 * share:.3g} % of it past jamming or stitch failure)" if share else ""
        return (
            f", generator angle {self.generator_angle_deg:.1f}°, energy "
            f"{self.total_energy_J:.4g} J{past}, max |shear| {self.max_abs_shear_deg:.1f}°"
        )


@dataclass(repr=False)
class LeastEnergy(CaseRun):
    """The least-energy drape (:func:`least_energy`): the optimum, E(α), and the drape there."""

    @property
    def optimum_generator_angle_deg(self) -> float:
        return float(self.summary["optimum_generator_angle_deg"])

    @property
    def optimum_energy_J(self) -> float:
        return float(self.summary["optimum_energy_J"])

    @property
    def makeable(self) -> bool:
        """Whether some searched angle can be made (not mostly energy past jamming or stitch
        failure; ``preform.optimise.search``, "What can be made"). When not, the optimum is
        the angle of least wrinkle and the case is ``partial``."""
        return bool(self.summary.get("search_makeable", True))

    @property
    def energy_vs_angle(self) -> pd.DataFrame:
        """The energy/wrinkle trade table, every drape of the search by angle:
        ``generator_angle_deg``, ``energy_J`` (the comparable energy), ``drape_energy_J``,
        ``coverage`` (share of the part covered, 0..1), ``wrinkle_area_share`` and
        ``wrinkle_energy_share`` (shares of its covered area and of its energy past jamming or
        stitch failure, 0..1), ``makeable``, ``feasible``, ``max_abs_shear_deg`` and
        ``stage``."""
        import pandas as pd

        self._product("energy_vs_angle")
        rows = self.summary.get("energy_vs_angle_table")
        if rows is None:  # a summary written before the trade table
            curve = dict((float(a), float(e)) for a, e in self.summary["energy_vs_angle"])
            cover = dict(self.summary.get("energy_vs_angle_coverage") or [])
            feasible = dict(self.summary.get("energy_vs_angle_feasible") or [])
            rows = [
                {
                    "generator_angle_deg": a,
                    "energy_J": curve[a],
                    "coverage": cover.get(a),
                    "feasible": feasible.get(a),
                }
                for a in sorted(curve)
            ]
            return pd.DataFrame(rows)
        from preform.optimise.search_steps import TRADE_COLUMNS

        # summary.json sorts each row's keys: the table's own column order
        return pd.DataFrame(rows, columns=list(TRADE_COLUMNS))

    def to_pandas(self) -> pd.DataFrame:
        """:attr:`energy_vs_angle`; the cells of the optimum drape are ``.drape.to_pandas()``."""
        return self.energy_vs_angle

    @property
    def drape(self) -> Drape:
        """The drape at the optimum (the same case: its status, summary and products)."""
        return Drape(self.fabric, self.scene, self.case, self.summary, self.products, self.case_dir)

    def plot(self, path: PathLike | None = None) -> Figure:
        """Total shear strain energy [J] against generator angle [deg], the optimum marked;
        saved to ``path`` when given. ``.drape.plot()`` draws the pattern at the optimum."""
        from preform.export.fig_curves import energy_vs_angle_figure

        table = self.energy_vs_angle
        name = self.fabric.name
        return energy_vs_angle_figure(
            {name: list(zip(table["generator_angle_deg"], table["energy_J"], strict=True))},
            path,
            optima={name: self.optimum_generator_angle_deg},
            title=f"{name}: total shear strain energy against generator angle",
        )

    def to_vtu(self, path: PathLike) -> Path:
        """The drape at the optimum as a .vtu file (see :meth:`Drape.to_vtu`)."""
        return self.drape.to_vtu(path)

    def _headline(self) -> str:
        if "optimum_generator_angle_deg" not in self.summary:
            return super()._headline()
        return (
            f", optimum generator angle {self.optimum_generator_angle_deg:.2f}°, energy "
            f"{self.optimum_energy_J:.4g} J"
        )


def drape(
    fabric: Any,
    scene: Any = DRAPE_SCENE,
    *,
    library: Library | None = None,
    out_dir: PathLike | None = None,
    **scene_keywords: Any,
) -> Drape:
    """Drape ``fabric`` (a name or a fabric) at a fixed generator angle.

    ``scene`` (default: the bundled ``hemisphere``, R = 100 mm) gives the tool, ply and start;
    keyword arguments change it as :func:`scene` does, in mm and degrees (e.g.
    ``generator_angle_deg=80``, ``node_spacing_mm=5``, ``tool={"surface": "hemisphere",
    "radius_mm": 150}``). A ``search`` section of the scene is ignored: the drape is at
    ``start.generator_angle_deg`` (:func:`least_energy` searches). ``out_dir`` keeps the case
    folder (``summary.json``) there; by default nothing is written.

    The drape runs as a pipeline case: the returned :class:`Drape` has the pipeline's
    ``status`` (``ok``, ``partial``, ``failed``), ``reasons``, ``warnings`` and ``summary``.
    A failed case is returned, not raised: check ``.ok`` or call ``.raise_for_status()``.
    """
    fab = _fabric(fabric, library)
    changes = _changes(scene_keywords)
    changes[("search",)] = None
    changes.setdefault(("outputs",), ["drape"])
    scene_, data = _scene_and_data(scene, changes)
    result, summary, products, case_dir = _execute(fab, scene_, data, out_dir)
    return Drape(fab, scene_, result, summary, products, case_dir)


def least_energy(
    fabric: Any,
    scene: Any = LEAST_ENERGY_SCENE,
    *,
    library: Library | None = None,
    out_dir: PathLike | None = None,
    **scene_keywords: Any,
) -> LeastEnergy:
    """The least-energy drape of ``fabric``: the search over generator angles (the founding
    paper's study) and the drape at the optimum.

    ``scene`` (default: the bundled ``hemisphere-min-energy``) and the keyword arguments as in
    :func:`drape`; ``generator_angle_range_deg=(low, high)`` sets the searched range [deg]
    (default the scene's, else 30–150°), ``fidelity`` the preset. Returns a
    :class:`LeastEnergy` with the pipeline's status, ``optimum_generator_angle_deg``,
    ``energy_vs_angle`` and ``.drape`` at the optimum.
    """
    fab = _fabric(fabric, library)
    changes = _changes(scene_keywords)
    changes.setdefault(("outputs",), ["energy_vs_angle", "optimum", "drape"])
    base, _ = _scene_and_data(scene, {})
    if base.search is None and ("search", "generator_angle_deg") not in changes:
        low, high = DEFAULT_RANGE_DEG
        changes[("search", "generator_angle_deg")] = {"min": low, "max": high}
    scene_, data = _scene_and_data(scene, changes)
    result, summary, products, case_dir = _execute(fab, scene_, data, out_dir)
    return LeastEnergy(fab, scene_, result, summary, products, case_dir)


# -- a layup -----------------------------------------------------------------------------------

LAYUP_SCENE = "hemisphere-layup"


@dataclass(repr=False)
class Layup(CaseRun):
    """A draped stack (:func:`layup`): the pipeline's status of the stack (``ok`` only when
    every ply is), each ply's record (``plies``) and the stack's maps (``to_pandas()``:
    one row per station, mm and [-]; ``plot()``: thickness and plies present). ``fabric`` is
    the tool-side ply's."""

    @property
    def plies(self) -> list[dict[str, Any]]:
        """One record per ply, tool side first: name, fabric, orientation_deg, offset_mm
        (the tool's offset under it), status, reasons, warnings, generator_angle_deg, ...
        For a failed stack, the plies draped before it stopped (the failing one included
        when its drape ran)."""
        return [dict(p) for p in self.summary.get("plies", [])]

    @property
    def stack(self) -> Any:
        """The ``layup`` product (``preform.stack.steps.Stack``: draped plies, maps)."""
        return self._product("layup")

    def to_pandas(self) -> pd.DataFrame:
        """The stack at its stations: x_mm, y_mm, z_mm, area_mm2, total_thickness_mm,
        fibre_volume_fraction, plies_present, plies_wrinkling, thickness_mm_<ply>."""
        import pandas as pd

        maps = self.stack.maps
        frame = pd.DataFrame(maps.points_mm, columns=["x_mm", "y_mm", "z_mm"])
        frame["area_mm2"] = maps.area_mm2
        frame["total_thickness_mm"] = maps.total_thickness_mm
        frame["fibre_volume_fraction"] = maps.stack_fibre_volume_fraction
        frame["plies_present"] = maps.plies_present
        frame["plies_wrinkling"] = maps.plies_wrinkling
        for k, name in enumerate(maps.ply_names):
            frame[f"thickness_mm_{name}"] = maps.thickness_mm[:, k]
        return frame

    def plot(self, path: PathLike | None = None) -> Figure:
        """The stack's total thickness and plies present from above; saved to ``path``."""
        from preform.export.fig_stack import stack_figure

        return stack_figure(self.stack.maps, path, title=self.scene.name)

    def _headline(self) -> str:
        words = self.summary.get("stack")
        return f", {words}" if words and not self.error else super()._headline()


def layup(
    scene: Any = LAYUP_SCENE,
    *,
    plies: Sequence[Mapping[str, Any]] | None = None,
    library: Library | None = None,
    out_dir: PathLike | None = None,
    **scene_keywords: Any,
) -> Layup:
    """Drape a stack of plies, each on the tool offset by the plies below (``preform.stack``).

    ``scene`` (default: the bundled ``hemisphere-layup``, [0/45/-45/90] of plain-weave-600 and
    a satin) gives the tool, ply size and layup; ``plies`` replaces its plies, tool side
    first, each a mapping in mm and degrees as in a scene (``{"fabric": "plain-weave-600",
    "orientation_deg": 45, "generator_angle_deg": 90 | "least_energy", "start_point_mm":
    (x, y), "thickness_mm": t0, "part_outline_mm": [...]}``); the keyword arguments change the
    scene as :func:`scene` does (``fidelity="draft"``, ``node_spacing_mm=5``, ``tool=...``;
    not the start's orientation or angle, which are each ply's). The fabrics come from
    ``library`` (default :func:`load_library`). ``out_dir`` keeps the case folder (a
    sub-folder per ply). Returns a :class:`Layup`; a failed stack is returned, not raised.
    """
    from preform.library import Library as LibraryType
    from preform.pipeline.layup_case import layup_case
    from preform.pipeline.runner import execute_case

    if library is not None and not isinstance(library, LibraryType):
        raise TypeError(f"library must be a loaded library or None, got {type(library).__name__}")
    lib = library or load_library()
    changes = _changes(scene_keywords)
    if plies is not None:
        changes[("layup", "plies")] = _plain([dict(p) for p in plies])
    scene_, data = _scene_and_data(scene, changes)
    if scene_.layup is None:
        raise ValueError(f"scene {scene_.name!r} has no layup section (see docs/scenes.md)")
    host = _host()
    kept: list[CaseContext] = []
    with tempfile.TemporaryDirectory(prefix="preform-") as scratch:
        root = Path(out_dir) if out_dir is not None else Path(scratch)
        case = layup_case(lib, scene_, data, root, host)
        case = dataclasses.replace(case, timeout_s=scene_.limits.case_timeout_s)
        result = execute_case(case, host, on_context=kept.append)
        from preform.pipeline.rundir import read_json

        summary = read_json(Path(case.case_dir) / "summary.json")
    products = dict(kept[0].products) if kept else {}
    first = products.get("layup_fabrics", {}).get(scene_.layup.plies[0].fabric)
    fab = first if first is not None else lib.fabric(scene_.layup.plies[0].fabric)
    record = summary if isinstance(summary, dict) else {}
    if "plies" not in record and kept and "plies" in kept[0].summary:
        # a failed case's summary.json keeps no results: the plies draped before it stopped
        record = {**record, "plies": kept[0].summary["plies"]}
    return Layup(
        fab, scene_, result, record, products, Path(case.case_dir) if out_dir is not None else None
    )


# -- a run over a library -----------------------------------------------------------------------


@dataclass(repr=False)
class RunResult:
    """A run of every (material, scene) case (:func:`run`), as ``preform pipeline run``."""

    report: RunReport

    @property
    def out_dir(self) -> Path:
        return Path(self.report.out_dir)

    @property
    def cases(self) -> list[CaseResult]:
        """This run's cases (``preform.pipeline.runner.CaseResult``), in order."""
        return list(self.report.results)

    @property
    def summary(self) -> dict[str, Any]:
        """What ``pipeline run --json`` prints: counts, exit code, every case with its status,
        covered fraction, reasons, warnings and error."""
        from preform.pipeline.summary import run_summary

        return run_summary(self.report)

    @property
    def counts(self) -> dict[str, int]:
        return self.report.counts()

    def to_pandas(self) -> pd.DataFrame:
        """One row per case of this run, as in ``results.csv``: material, scene, status,
        reasons, warnings, error, timings and scalar results (mm, degrees, J)."""
        import pandas as pd

        from preform.pipeline.rundir import read_json, table_row

        rows = []
        for case in self.report.results:
            folder = self.out_dir / _case_folder(case)
            record = read_json(folder / "summary.json")
            rows.append(table_row(record if isinstance(record, dict) else {}))
        return pd.DataFrame(rows)

    def plot(self, path: PathLike | None = None) -> Figure:
        """Total energy against generator angle, one curve per fabric with its optimum (cases
        that searched; the paper's Fig. 10); saved to ``path`` when given."""
        from preform.export.fig_curves import energy_vs_angle_figure

        table = self.to_pandas()
        curves, optima = {}, {}
        for case, row in zip(self.report.results, table.to_dict("records"), strict=True):
            pairs = case.results.get("energy_vs_angle")
            if pairs:
                curves[case.material] = [(float(a), float(e)) for a, e in pairs]
                best = row.get("optimum_generator_angle_deg")
                if best is not None:
                    optima[case.material] = float(best)
        if not curves:
            raise ValueError("no case of this run searched generator angles: nothing to plot")
        return energy_vs_angle_figure(
            curves, path, optima=optima, title="Total shear strain energy against generator angle"
        )

    def __repr__(self) -> str:
        counts = ", ".join(f"{n} {s}" for s, n in sorted(self.counts.items()))
        return f"<RunResult {self.out_dir}: {counts}>"


def _case_folder(case: CaseResult) -> str:
    from preform.pipeline.runner import folder_name

    return f"{folder_name(case.scene)}/{folder_name(case.material)}"


def run(
    library: Library | PathLike | Sequence[PathLike] | None = None,
    scenes: Sequence[Any] = (LEAST_ENERGY_SCENE,),
    *,
    materials: str | None = None,
    out_dir: PathLike = "preform-results",
    fidelity: str | None = None,
    engine: str = "process",
    workers: int | None = None,
    case_timeout_s: float | None = None,
    force: bool = False,
    bundled: bool = True,
) -> RunResult:
    """Run every (material, scene) case into ``out_dir``, as ``preform pipeline run`` does.

    ``library``: a loaded library, or paths added to the bundled library (``bundled=False``:
    only them). ``scenes``: names, files, mappings or ``Scene`` objects. ``materials``: a glob
    of fabric names. ``fidelity`` replaces every scene's preset (recorded, and part of the
    cases' input hash). ``case_timeout_s`` [s] as ``--case-timeout``. Cases already done with
    the same inputs are kept unless ``force``. Every argument is checked as its command-line
    twin is (``preform.pipeline.run_arguments``): ``TypeError`` or ``ValueError`` naming it
    (``workers=0``, ``case_timeout_s=nan``, an unknown ``engine``). Raises
    ``preform.pipeline.scene.SceneError`` or ``preform.library.LibraryError`` for invalid
    input, before anything runs.
    """
    from preform.library import Library
    from preform.pipeline.overrides import with_fidelity
    from preform.pipeline.run_arguments import check_run_arguments
    from preform.pipeline.runner import (
        DEFAULT_CASE_TIMEOUT_S,
        input_files_record,
        make_cases,
        run_cases,
    )

    # checked as `preform pipeline run` checks its options, before anything is loaded or run
    check_run_arguments(
        engine=engine,
        workers=workers,
        case_timeout_s=case_timeout_s,
        fidelity=fidelity,
        materials=materials,
        force=force,
    )
    if isinstance(scenes, str | os.PathLike | Mapping) or not isinstance(scenes, Sequence):
        raise TypeError(
            "scenes must be a list of scenes (names, files, mappings or Scene objects), got "
            f"{type(scenes).__name__} {scenes!r}"
        )
    lib = (
        library
        if isinstance(library, Library)
        else load_library(() if library is None else library, bundled=bundled)
    )
    loaded = [_scene_and_data(spec, with_fidelity(fidelity)) for spec in scenes]
    host = _host()
    out = Path(out_dir)
    cases = make_cases(
        lib, loaded, out, host, materials, timeout_s=case_timeout_s or DEFAULT_CASE_TIMEOUT_S
    )
    if not cases:
        raise ValueError("no (material, scene) case matches; check materials and the scenes")
    inputs: dict[str, Any] = {"libraries": input_files_record(lib.files), "api": True}
    if fidelity is not None:
        inputs["fidelity_override"] = fidelity
    report = run_cases(cases, out, host, engine=engine, workers=workers, force=force, inputs=inputs)
    return RunResult(report)


__all__ = [
    "SCENE_KEYWORDS",
    "CaseRun",
    "Compared",
    "Drape",
    "LeastEnergy",
    "RunResult",
    "compare_drape",
    "drape",
    "fabric",
    "least_energy",
    "load_library",
    "read_measurement",
    "run",
    "scene",
]


# -- calibration ----------------------------------------------------------------------------


def calibrate(
    fabric: str | FabricBase,
    data: PathLike | tuple[Sequence[float], Sequence[float]],
    *,
    test: str,
    side_mm: float | None = None,
    fabric_side_mm: float | None = None,
    height_mm: float | None = None,
    width_mm: float | None = None,
    constants: Sequence[str] | Mapping[str, tuple[float, float] | None] | None = None,
    max_angle_deg: float | None = None,
    weights: str = "relative",
    library: Library | None = None,
) -> Calibration:
    """Fit constants of ``fabric``'s mechanistic law to a measured shear test, as
    ``preform calibrate`` does.

    ``data``: a test CSV (displacement [mm], force [N]; see ``preform fit``) or a pair of
    sequences (displacement_mm, force_N). ``test``: ``"picture-frame"`` (``side_mm``, optional
    ``fabric_side_mm``) or ``"bias-extension"`` (``height_mm``, ``width_mm``). ``constants``:
    paths into the fabric's entry (``"shear_law.pretension_N"``, ``"threads[0].failure_strain"``,
    optionally ``"PATH=LO:HI"``) or a mapping path → (low, high) | None, in the entry's units;
    default: the law's defaults (``preform.shear.calibrate.DEFAULT_CONSTANTS``). Points up to
    ``max_angle_deg`` [deg] (default all) are fitted, with ``weights`` ``"relative"`` (residuals
    over the force, floored at 5 % of its peak) or ``"absolute"`` (in N/mm).

    Returns a ``Calibration``: ``constants`` (value, linearised standard uncertainty),
    ``correlation``, ``fit`` and ``up_to_locking`` quality, ``entry`` (the calibrated library
    entry), ``to_yaml()``, ``plot(path)``, ``as_json()``, ``apply_to(glob, library)``. Raises
    ``preform.shear.calibrate.CalibrationError`` (a ValueError) for bad input.
    """
    from preform.shear.calibrate import (
        CalibrationError,
        calibrate_law,
        file_sha256,
        resolve_constants,
    )
    from preform.shear.commands import normalise_rows, read_test_csv

    lib = library or load_library()
    chosen = _fabric(fabric, lib)
    if isinstance(data, str | os.PathLike):
        rows = read_test_csv(Path(data))
        data_file, digest = str(data), file_sha256(Path(data))
    else:
        displacement, force = data
        if len(displacement) != len(force):
            raise CalibrationError("data: displacement and force differ in length")
        rows = [
            {"displacement_mm": repr(float(d)), "force_N": repr(float(f))}
            for d, f in zip(displacement, force, strict=True)
        ]
        data_file, digest = "", ""
    angle, force_per_length = normalise_rows(
        rows,
        test,
        side_mm=side_mm,
        height_mm=height_mm,
        width_mm=width_mm,
        fabric_side_mm=fabric_side_mm,
    )
    specimen = {
        key: float(value)
        for key, value in (
            ("side", side_mm),
            ("fabric side", fabric_side_mm),
            ("height", height_mm),
            ("width", width_mm),
        )
        if value is not None
    }
    return calibrate_law(
        chosen,
        lib.registry,
        angle,
        force_per_length,
        resolve_constants(chosen, constants),
        max_angle_deg=max_angle_deg,
        test=test,
        specimen=specimen,
        data_file=data_file,
        data_sha256=digest,
        weights=weights,
    )


# -- a drape against a measurement ---------------------------------------------------------------


def read_measurement(path: PathLike, *, unit: str = "mm") -> Measurement:
    """Read measured fibre angles (docs/compare.md): a CSV (points in ``x_mm, y_mm, z_mm`` or
    ``x_m, ...``; fibre vectors ``u_x..``, ``v_x..``; ``angle_u_deg``, ``angle_v_deg``,
    ``shear_deg``, ``uncertainty_deg``, ``region``) or a point cloud meshio reads (PLY, VTK,
    VTU) with ``fibre_u``/``fibre_v`` vectors in its point data, its coordinates in ``unit``
    (``mm`` or ``m``). Raises ``preform.compare.MeasurementError`` listing every located
    problem."""
    from preform.compare.measurement import read_measurement as read

    return read(path, unit=unit)


@dataclass(repr=False)
class Compared:
    """A drape against a measurement (:func:`compare_drape`), in mm and degrees."""

    #: The drape compared (the pipeline's case: status, summary).
    drape: CaseRun
    #: Per-point errors and flags (``preform.compare.Comparison``).
    comparison: Any
    #: The inverse search's answer (``preform.compare.Explanation``), None when not asked.
    explanation: Any = None

    @property
    def status(self) -> str:
        return self.drape.status

    @property
    def summary(self) -> dict[str, Any]:
        """The comparison's summary (counts, flags, rms / max / percentiles, by region), and
        the inverse search's under ``explain``."""
        out: dict[str, Any] = {"drape_status": self.drape.status, **self.comparison.summary()}
        if self.explanation is not None:
            out["explain"] = self.explanation.summary()
        return out

    def to_pandas(self) -> pd.DataFrame:
        """One row per measured point (the drape as given; ``explanation.after.to_pandas()``
        is the table at the best set-up)."""
        return self.comparison.to_pandas()

    def plot(self, path: PathLike | None = None) -> Figure:
        """The error map (plan view and 3D), saved to ``path`` when given."""
        from preform.compare.figure import error_map_figure

        result = self.drape._product("drape").result
        return error_map_figure(self.comparison, result, path, title=self.drape.case.case_id)

    def to_vtu(self, path: PathLike) -> Path:
        """The measured points with their errors and flags, for ParaView."""
        from preform.compare.vtu import write_comparison_vtu

        write_comparison_vtu(self.comparison, path)
        return Path(path)

    def __repr__(self) -> str:
        return f"<Compared {self.drape.case.case_id}: {self.comparison.words()}>"


def _set_up(scene_: Scene) -> Any:
    from preform.compare.inverse import SetUp

    start = scene_.start
    assert start is not None
    return SetUp(
        float(start.point_mm[0]),
        float(start.point_mm[1]),
        float(start.orientation_deg),
        float(start.generator_angle_deg),
    )


def compare_drape(
    fabric: Any,
    measurement: Any,
    scene: Any = DRAPE_SCENE,
    *,
    library: Library | None = None,
    explain: bool = False,
    vary: Sequence[str] = ("start", "orientation", "generator_angle"),
    max_gap_mm: float | None = None,
    unit: str = "mm",
    **scene_keywords: Any,
) -> Compared:
    """Compare a drape with measured fibre angles, and (``explain``) search the set-up that
    best explains them (docs/compare.md).

    ``fabric``: a fabric (name or object), draped by :func:`drape` with ``scene`` and the
    scene keywords; or a :class:`Drape` / :class:`LeastEnergy` already run (compared as it
    is: a relaxed or curved-generator optimum too). ``measurement``: a file
    (:func:`read_measurement`, ``unit`` for a point cloud) or a
    ``preform.compare.Measurement``. ``max_gap_mm``: farthest a point may lie from the tool
    and the net [mm] (default the node spacing). ``vary``: what the inverse search varies
    (``start``, ``orientation``, ``generator_angle``), from the scene's set-up.

    Raises ``preform.compare.MeasurementError`` for a bad file and ``UnitSlipError`` when
    the points are in another unit than they say; ``CaseFailure`` when the drape has no
    result."""
    import numpy as np

    from preform.compare.comparison import compare
    from preform.compare.measurement import Measurement

    if isinstance(fabric, CaseRun):
        case = fabric.drape if isinstance(fabric, LeastEnergy) else fabric
    else:
        case = drape(fabric, scene, library=library, **scene_keywords)
    draped = case._product("drape")
    surface = case._product("surface")
    found = (
        measurement
        if isinstance(measurement, Measurement)
        else read_measurement(measurement, unit=unit)
    )
    comparison = compare(
        draped.result, found, surface=surface, energy=draped.energy, max_gap_mm=max_gap_mm
    )
    explanation = None
    if explain:
        from preform.compare.inverse import explain as search
        from preform.drape.engine.fields import energy_field
        from preform.drape.steps import drape_settings

        law = case._product("shear_law")
        settings = drape_settings(case.scene, surface).keywords()

        def energy_of(result: Any) -> Any:
            with np.errstate(all="ignore"):
                return energy_field(result, law)

        explanation = search(
            found, surface, settings, _set_up(case.scene), vary=vary,
            max_gap_mm=max_gap_mm, energy_of=energy_of,
        )  # fmt: skip
    return Compared(case, comparison, explanation)
