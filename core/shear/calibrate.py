"""Calibration: fit a mechanistic law's unknown constants to a measured shear curve.

A constant is named by its path in the fabric's library entry, as validation errors name it
(``shear_law.pretension_N``, ``threads[0].failure_strain``, ``tow_types.glass.compaction.
fibre_wave_ratio``; ``threads.0.x`` is read as ``threads[0].x``), so any number of any nested
mapping or list can be fitted and nothing here knows where a law keeps its constants, except
the one table of defaults, ``DEFAULT_CONSTANTS``.

Each trial law is built the way the library builds one: the entry (as ``materials show`` dumps
it) is copied with the trial values, validated by ``preform.library.validate_entry`` (schema,
plausible ranges, the architecture's own checks) and built by the law registered for its
``shear_law`` block. So a trial value the library would refuse is refused here too.

The fit [C]: ``scipy.optimize.least_squares`` (trust-region reflective, bounded) on the relative
residual (F_s/L(model) − F_s/L(data)) / max(|F_s/L(data)|, 5 % of its peak) at the data's
normalised angles up to ``max_angle_deg`` (default: every point; the measured curve is trusted as
far as it goes; narrow it for a bias-extension test past the angle where its kinematics hold).
Relative, because a measured curve's scatter grows with its force (an unweighted fit lets the
few stiff points past locking decide everything and understates its uncertainty: on synthetic
data with 2 % scatter its stated σ covered the truth in 33 % of seeds, the relative fit's in
78 %, tests/shear/test_calibrate.py); floored, so the points near zero force do not dominate.
A positive constant is fitted as its logarithm (scale-free steps, and it stays positive).
Uncertainty: the linearised estimate cov = s²·(JᵀJ)⁻¹ at the optimum, J the Jacobian of the
residuals in the fitted variables, s² = Σr²/(n − p) the residual variance; for a log-fitted
constant σ = value·σ(ln value). It assumes independent residuals of equal (relative) variance
and a model that is locally linear over ±σ, neither of which a digitised curve guarantees:
read it as an estimate, not a confidence interval.
"""

from __future__ import annotations

import copy
import datetime
import difflib
import fnmatch
import hashlib
import json
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from preform.library import Library
    from preform.material import FabricBase
    from preform.registry import Registry

    FloatArray = NDArray[np.float64]

Path_ = tuple[str | int, ...]

#: The constants fitted when none are named, per law (``shear_law.law``): paths into the entry.
#: The only place that says where a law keeps its constants; change it when they move.
#: friction_compaction: pre-tension sets the crossover force before locking and friction
#: scales it and the compaction force after; before locking only their product acts, so a
#: curve that ends before locking shows them fully correlated (reported as such).
#: stitch_yarn: the inter-ply friction and the stitch yarn's strain at break (the failure angle).
DEFAULT_CONSTANTS: dict[str, tuple[str, ...]] = {
    "friction_compaction": ("shear_law.pretension_N", "shear_law.friction_coefficient"),
    "stitch_yarn": ("shear_law.ply_friction_coefficient", "threads[0].failure_strain"),
}

#: Default bounds around a constant's value v when none are given: [v/20, 20·v], within the
#: field's plausible range (docs/ranges.md) when it has one.
DEFAULT_SPAN = 20.0

#: Floor of the force scale the residuals are divided by, as a share of the data's peak force.
RELATIVE_FLOOR = 0.05

#: Keys of a tow description compared by ``same_tows``: fibre, linear density, width, height
#: (woven ``tow_types`` spell width/height ``width_mm``/``height_mm``, warp-knit ``tow_layers``
#: ``tow_width_mm``/``tow_height_mm``).
TOW_KEYS = (
    ("fibre",),
    ("linear_density_tex",),
    ("width_mm", "tow_width_mm"),
    ("height_mm", "tow_height_mm"),
)


class CalibrationError(ValueError):
    """Bad calibration input (unknown constant path, bounds, data), with where it is."""


# -- paths into an entry -------------------------------------------------------------------


def parse_path(text: str) -> Path_:
    """``"threads[0].failure_strain"`` or ``"threads.0.failure_strain"`` → ``("threads", 0,
    "failure_strain")``."""
    parts: list[str | int] = []
    for token in re.split(r"\.|(?=\[)", text.strip()):
        if not token:
            raise CalibrationError(f"constant path {text!r}: empty part")
        index = re.fullmatch(r"\[(\d+)\]", token)
        if index:
            parts.append(int(index.group(1)))
        elif token.isdigit():
            parts.append(int(token))
        elif re.fullmatch(r"[A-Za-z_][\w-]*", token):
            parts.append(token)
        else:
            raise CalibrationError(f"constant path {text!r}: {token!r} is not a key or [index]")
    return tuple(parts)


def format_path(path: Path_) -> str:
    """The path as errors write it: ``threads[0].failure_strain``."""
    from preform.yamlsource import format_path as fmt

    return fmt(path)


def get_path(data: Any, path: Path_) -> Any:
    """The value at ``path``; KeyError naming the first step that does not exist. Inside an
    optional block left empty (None, e.g. a tow's ``compaction``) every field is empty too:
    None (the trial entry's validation then says whether the field exists)."""
    node = data
    for depth, step in enumerate(path):
        if node is None and isinstance(step, str) and depth > 0:
            return None
        if isinstance(node, dict) and isinstance(step, str) and step in node:
            node = node[step]
        elif isinstance(node, list) and isinstance(step, int) and step < len(node):
            node = node[step]
        else:
            raise KeyError(format_path(path[: depth + 1]))
    return node


def set_path(data: Any, path: Path_, value: Any) -> None:
    """Set the value at ``path`` (its parent must exist, or be an empty optional block, which
    is made; a missing last key is added)."""
    node = data
    for step in path[:-1]:  # make the empty optional blocks on the way (resolve_constants
        # checked the path against the whole entry, where such a block is None; a trial entry
        # leaves it out)
        if isinstance(node, dict) and isinstance(step, str):
            if node.get(step) is None:
                node[step] = {}
            node = node[step]
        elif isinstance(node, list) and isinstance(step, int) and 0 <= step < len(node):
            node = node[step]
        else:
            raise KeyError(format_path(path))
    parent = get_path(data, path[:-1])
    last = path[-1]
    if isinstance(parent, dict) and isinstance(last, str):
        parent[last] = value
    elif isinstance(parent, list) and isinstance(last, int) and last < len(parent):
        parent[last] = value
    else:
        raise KeyError(format_path(path))


def numeric_paths(data: Any, base: Path_ = ()) -> list[str]:
    """Every path of ``data`` holding a number or nothing (None): what may be calibrated."""
    out: list[str] = []
    if isinstance(data, dict):
        for key, value in data.items():
            out += numeric_paths(value, (*base, key))
    elif isinstance(data, list):
        for i, value in enumerate(data):
            out += numeric_paths(value, (*base, i))
    elif data is None or (isinstance(data, int | float) and not isinstance(data, bool)):
        out.append(format_path(base))
    return out


# -- the constants to fit ------------------------------------------------------------------


@dataclass(frozen=True)
class Constant:
    """One constant to fit: its path, start value and bounds, in the entry's (YAML) units."""

    path: Path_
    start: float
    low: float
    high: float

    @property
    def name(self) -> str:
        return format_path(self.path)

    @property
    def log(self) -> bool:
        """Fitted as its logarithm (positive bounds)."""
        return self.low > 0.0


def parse_constant_spec(spec: str) -> tuple[str, tuple[float, float] | None]:
    """``"PATH"`` or ``"PATH=LO:HI"`` → (path text, bounds or None)."""
    text, sep, bounds = spec.partition("=")
    if not sep:
        return text.strip(), None
    try:
        low, high = (float(v) for v in bounds.split(":"))
    except ValueError:
        raise CalibrationError(
            f"--param {spec!r}: bounds must be LO:HI (two numbers), got {bounds!r}"
        ) from None
    if not (math.isfinite(low) and math.isfinite(high)) or low >= high:
        raise CalibrationError(f"--param {spec!r}: need finite bounds with LO < HI")
    return text.strip(), (low, high)


def resolve_constants(
    fabric: FabricBase,
    specs: Iterable[str] | Mapping[str, tuple[float, float] | None] | None,
) -> list[Constant]:
    """The constants to fit, checked against ``fabric``'s entry: every path must hold a number
    (or be an optional field left empty, which then needs bounds); bounds must be finite,
    ordered, and inside the field's plausible range. ``specs`` None: ``DEFAULT_CONSTANTS`` of
    the fabric's law."""
    from preform.material import plausibility_checks

    full = fabric.model_dump(mode="json")
    if specs is None:
        law = _law_name(full)
        if law not in DEFAULT_CONSTANTS:
            known = ", ".join(sorted(DEFAULT_CONSTANTS))
            raise CalibrationError(
                f"fabric {fabric.name!r}: law {law!r} has no default constants to calibrate "
                f"(defaults exist for {known}); name them with --param PATH[=LO:HI]"
            )
        pairs: list[tuple[str, tuple[float, float] | None]] = [
            (p, None) for p in DEFAULT_CONSTANTS[law]
        ]
    elif isinstance(specs, Mapping):
        pairs = [
            (str(k), None if v is None else (float(v[0]), float(v[1]))) for k, v in specs.items()
        ]
    else:
        pairs = [parse_constant_spec(s) for s in specs]
    if not pairs:
        raise CalibrationError("no constant to calibrate")
    ranges = {format_path(c.path): c.rule for c in plausibility_checks(fabric)}
    out: list[Constant] = []
    for text, bounds in pairs:
        path = parse_path(text)
        name = format_path(path)
        try:
            value = get_path(full, path)
        except KeyError as exc:
            close = difflib.get_close_matches(name, numeric_paths(full), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise CalibrationError(
                f"fabric {fabric.name!r}: unknown constant path {name!r} (no {exc.args[0]!r} "
                f"in its entry){hint}"
            ) from None
        if isinstance(value, bool) or not (value is None or isinstance(value, int | float)):
            raise CalibrationError(
                f"fabric {fabric.name!r}: {name} is not a number (it is {value!r}); only "
                "numeric constants can be calibrated"
            )
        rule = ranges.get(name)
        if bounds is None:
            if value is None or value <= 0.0:
                raise CalibrationError(
                    f"fabric {fabric.name!r}: {name} is {value!r} in this entry; give its "
                    f"bounds: --param {name}=LO:HI"
                )
            low, high = value / DEFAULT_SPAN, value * DEFAULT_SPAN
            if rule is not None:
                low, high = max(low, rule.low), min(high, rule.high)
        else:
            low, high = bounds
            if rule is not None and (low < rule.low or high > rule.high):
                raise CalibrationError(
                    f"fabric {fabric.name!r}: bounds {low:g}:{high:g} of {name} leave its "
                    f"plausible range {rule.describe()} (docs/ranges.md)"
                )
        if value is None or not low <= value <= high:
            start = math.sqrt(low * high) if low > 0.0 else 0.5 * (low + high)
        else:
            start = float(value)
        if start == low == 0.0:
            start = 0.5 * high
        out.append(Constant(path, start, low, high))
    names = [c.name for c in out]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise CalibrationError(f"constant named twice: {', '.join(twice)}")
    return out


def check_constants_exist(
    fabric: FabricBase, constants: Sequence[Constant], registry: Registry
) -> None:
    """Validate the entry with every constant at its start value, so that a path into an empty
    optional block that names no field there is refused before the fit, in words."""
    trial = TrialLaws(fabric, registry)
    try:
        trial.fabric_with(constants, [c.start for c in constants])
    except CalibrationError as exc:
        raise CalibrationError(
            f"fabric {fabric.name!r}: the constants {', '.join(c.name for c in constants)} "
            f"do not make a valid entry: {exc}"
        ) from None


def _law_name(entry: Mapping[str, Any]) -> str:
    block = entry.get("shear_law")
    return str(block.get("law")) if isinstance(block, dict) else ""


# -- trial laws ----------------------------------------------------------------------------


class TrialLaws:
    """Builds the law of ``fabric``'s entry with some constants changed, through the library's
    own validation and the law registered for the entry."""

    def __init__(self, fabric: FabricBase, registry: Registry) -> None:
        self.fabric = fabric
        self.registry = registry
        self.entry: dict[str, Any] = fabric.model_dump(mode="json", exclude_none=True)

    def entry_with(self, constants: Sequence[Constant], values: Sequence[float]) -> dict[str, Any]:
        entry = copy.deepcopy(self.entry)
        for constant, value in zip(constants, values, strict=True):
            set_path(entry, constant.path, float(value))
        return entry

    def fabric_with(self, constants: Sequence[Constant], values: Sequence[float]) -> FabricBase:
        return validated_fabric(self.entry_with(constants, values), self.registry)

    def law(self, constants: Sequence[Constant], values: Sequence[float]) -> Any:
        from preform.library import build_shear_law

        return build_shear_law(self.fabric_with(constants, values), self.registry)


def validated_fabric(entry: Mapping[str, Any], registry: Registry, file: str = "") -> FabricBase:
    """``entry`` validated exactly as a library file's entry is; CalibrationError listing every
    problem (``path: message``) when it is not valid."""
    from preform.library import validate_entry
    from preform.yamlsource import YamlSourceError, load_yaml_text

    label = file or f"<calibrated {entry.get('name')}>"
    try:
        (doc,) = load_yaml_text(json.dumps(entry), label)
    except YamlSourceError as exc:  # cannot happen for dumped data; say so if it does
        raise CalibrationError(str(exc)) from None
    fabric, errors, _ = validate_entry(doc, (), doc.data, registry)
    if fabric is None:
        raise CalibrationError(
            "; ".join(f"{e.path}: {e.message}" if e.path else e.message for e in errors)
        )
    return fabric


# -- the fit -------------------------------------------------------------------------------


@dataclass(frozen=True)
class Quality:
    """Model against data over some points: rms [N/mm], rms relative to the data's rms [-],
    R² [-] (None with fewer than two points), number of points, largest angle [deg]."""

    points: int
    rms_N_per_mm: float
    relative_rms: float
    r_squared: float | None
    max_angle_deg: float

    def as_json(self) -> dict[str, Any]:
        return {
            "points": self.points,
            "rms_N_per_mm": self.rms_N_per_mm,
            "relative_rms": self.relative_rms,
            "r_squared": self.r_squared,
            "max_angle_deg": self.max_angle_deg,
        }

    def words(self) -> str:
        r2 = "n/a" if self.r_squared is None else f"{self.r_squared:.3f}"
        return (
            f"rms {self.rms_N_per_mm:.3g} N/mm ({100 * self.relative_rms:.1f} % of the data's "
            f"rms), R² {r2}, {self.points} points up to {self.max_angle_deg:.1f}°"
        )


def quality(model: FloatArray, data: FloatArray, angle_deg: FloatArray) -> Quality:
    """:class:`Quality` of ``model`` against ``data`` [N/mm] at ``angle_deg``."""
    import numpy as np

    if data.size == 0:
        raise CalibrationError("no data point in the range compared")
    residual = model - data
    rms = float(np.sqrt(np.mean(residual**2)))
    scale = float(np.sqrt(np.mean(data**2)))
    spread = float(np.sum((data - data.mean()) ** 2))
    r2 = 1.0 - float(np.sum(residual**2)) / spread if data.size > 1 and spread > 0 else None
    return Quality(
        int(data.size),
        rms,
        rms / scale if scale > 0 else math.inf,
        r2,
        float(np.max(angle_deg)),
    )


@dataclass(frozen=True)
class FittedConstant:
    """A calibrated constant: value, standard uncertainty (linearised; None when the data do
    not determine it), start value and bounds, in the entry's units."""

    name: str
    value: float
    sigma: float | None
    start: float
    low: float
    high: float
    at_bound: bool

    def as_json(self) -> dict[str, Any]:
        return {
            "path": self.name,
            "value": self.value,
            "sigma": self.sigma,
            "start": self.start,
            "bounds": [self.low, self.high],
            "at_bound": self.at_bound,
        }


@dataclass
class Calibration:
    """What a calibration found, with what it was fitted to (see module docstring)."""

    fabric: str
    law: str
    test: str
    specimen: dict[str, float]
    angle_deg: FloatArray
    force_N_per_mm: FloatArray
    max_angle_deg: float
    constants: list[FittedConstant]
    correlation: list[list[float | None]]
    fit: Quality
    up_to_locking: Quality
    start_up_to_locking: Quality
    locking_angle_deg: float | None
    entry: dict[str, Any]
    start_entry: dict[str, Any]
    data_file: str = ""
    data_sha256: str = ""
    date: str = field(default_factory=lambda: datetime.date.today().isoformat())
    notes: list[str] = field(default_factory=list)
    registry: Any = field(default=None, repr=False)

    # -- what it says -------------------------------------------------------------------------

    def as_json(self) -> dict[str, Any]:
        return {
            "fabric": self.fabric,
            "law": self.law,
            "test": self.test,
            "specimen_mm": self.specimen,
            "data": {"file": self.data_file, "sha256": self.data_sha256},
            "date": self.date,
            "fit_range_deg": [0.0, self.max_angle_deg],
            "locking_angle_deg": self.locking_angle_deg,
            "constants": [c.as_json() for c in self.constants],
            "correlation": self.correlation,
            "uncertainty": "linearised: Jacobian covariance scaled by the residual variance",
            "quality": {
                "fit_range": self.fit.as_json(),
                "up_to_locking": self.up_to_locking.as_json(),
                "start_up_to_locking": self.start_up_to_locking.as_json(),
            },
            "notes": self.notes,
        }

    def comment_lines(self) -> list[str]:
        """Provenance of the calibrated constants, as YAML comment lines (without ``#``)."""
        source = self.data_file or "data given in memory"
        digest = f" (sha256 {self.data_sha256[:16]})" if self.data_sha256 else ""
        size = ", ".join(f"{k} {v:g} mm" for k, v in self.specimen.items())
        lines = [
            f"calibrated by preform calibrate on {self.date}: {self.fabric} ({self.law} law)",
            f"against {self.test} data {source}{digest}, {size}",
            f"fit range 0–{self.max_angle_deg:.1f}°: {self.fit.words()}",
            self._locking_words(),
            f"before calibration, up to locking: {self.start_up_to_locking.words()}",
            "constants (± standard uncertainty, linearised: Jacobian covariance scaled by the "
            "residual variance):",
        ]
        for c in self.constants:
            sigma = "not determined by these data" if c.sigma is None else f"± {c.sigma:.3g}"
            bound = "; AT ITS BOUND: the uncertainty does not hold" if c.at_bound else ""
            lines.append(f"  {c.name} = {c.value:.6g} {sigma} (start {c.start:.6g}){bound}")
        if len(self.constants) > 1:
            for i, a in enumerate(self.constants):
                for j in range(i + 1, len(self.constants)):
                    r = self.correlation[i][j]
                    shown = "n/a" if r is None else f"{r:+.2f}"
                    lines.append(f"  correlation {a.name} / {self.constants[j].name}: {shown}")
        lines += self.notes
        return lines

    def _short(self, q: Quality) -> str:
        where = "up to locking" if self.locking_angle_deg is not None else "over the fit range"
        return f"{100 * q.relative_rms:.0f} % rms {where}"

    def _locking_words(self) -> str:
        if self.locking_angle_deg is None:
            return f"no locking angle in the law: over the fit range, {self.up_to_locking.words()}"
        return f"up to locking ({self.locking_angle_deg:.1f}°): {self.up_to_locking.words()}"

    def to_yaml(self, extra: Sequence[dict[str, Any]] = ()) -> str:
        """A library file: the calibrated entry (and ``extra`` entries), with the provenance
        as comments; loads with ``--library``."""
        import yaml

        head = "".join(f"# {line}\n" for line in self.comment_lines())
        body = yaml.safe_dump([self.entry, *extra], sort_keys=False, allow_unicode=True)
        return head + body

    def model_curve(self, angle_deg: FloatArray, calibrated: bool = True) -> FloatArray:
        """F_s/L [N/mm] of the calibrated (or starting) law at ``angle_deg``."""
        import numpy as np

        from preform.library import build_shear_law
        from preform.shear.law import force_per_length_N_per_mm

        entry = self.entry if calibrated else self.start_entry
        law = build_shear_law(validated_fabric(entry, self.registry), self.registry)
        return force_per_length_N_per_mm(law, np.radians(angle_deg))

    def apply_to(self, pattern: str, library: Library) -> list[Transfer]:
        """The calibrated constants carried to ``library``'s fabrics matching ``pattern`` (a
        glob) that are built from the same tows; see :func:`transfer`."""
        return transfers(self, library, pattern)

    def plot(self, path: str | Path, title: str | None = None) -> Any:
        """The data against the calibrated law (and the law before calibration), F_s/L [N/mm]
        over γ [deg]; the locking angle and fit range marked. Returns the saved figure."""
        import numpy as np

        from preform.shear.figures import calibration_figure

        top = float(np.max(self.angle_deg))
        grid = np.linspace(0.0, top, 300)
        return calibration_figure(
            data=(self.angle_deg, self.force_N_per_mm),
            curves=[
                (grid, self.model_curve(grid), f"calibrated: {self._short(self.up_to_locking)}"),
                (
                    grid,
                    self.model_curve(grid, calibrated=False),
                    f"before: {self._short(self.start_up_to_locking)}",
                ),
            ],
            path=path,
            locking_deg=self.locking_angle_deg,
            fit_range_deg=self.max_angle_deg,
            title=title or f"{self.fabric}: {self.law} calibrated on {self.test} data",
        )


def file_sha256(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def calibrate_law(
    fabric: FabricBase,
    registry: Registry,
    angle_deg: Sequence[float] | FloatArray,
    force_N_per_mm: Sequence[float] | FloatArray,
    constants: Sequence[Constant],
    *,
    max_angle_deg: float | None = None,
    test: str = "",
    specimen: Mapping[str, float] | None = None,
    data_file: str = "",
    data_sha256: str = "",
    weights: str = "relative",
) -> Calibration:
    """Fit ``constants`` of ``fabric``'s law to normalised shear data (γ [deg], F_s/L [N/mm]).

    Points with γ ≤ ``max_angle_deg`` (default: all) enter the fit; quality is reported over
    the fit range and up to the calibrated law's locking angle. ``weights``: ``"relative"``
    (residuals over the force, floored; see the module docstring) or ``"absolute"`` (residuals
    in N/mm: minimises the rms the report gives, and states σ for equal scatter everywhere).
    """
    import numpy as np
    from scipy.optimize import least_squares

    from preform.shear.law import force_per_length_N_per_mm

    check_constants_exist(fabric, constants, registry)
    angle = np.asarray(angle_deg, dtype=float)
    force = np.asarray(force_N_per_mm, dtype=float)
    if angle.shape != force.shape or angle.ndim != 1:
        raise CalibrationError("angles and forces must be 1-D arrays of the same length")
    if not (np.all(np.isfinite(angle)) and np.all(np.isfinite(force))):
        raise CalibrationError("the normalised data hold a non-finite value")
    top = float(np.max(angle)) if max_angle_deg is None else float(max_angle_deg)
    if not 0.0 < top < 90.0:
        raise CalibrationError(f"max angle must be within (0°, 90°), got {top:g}°")
    chosen = angle <= top
    if int(chosen.sum()) <= len(constants):
        raise CalibrationError(
            f"{int(chosen.sum())} data point(s) up to {top:g}° for {len(constants)} "
            "constant(s): need more points than constants"
        )
    trial = TrialLaws(fabric, registry)
    gamma = np.radians(angle[chosen])
    data = force[chosen]

    def to_values(x: FloatArray) -> list[float]:
        return [
            float(math.exp(v)) if c.log else float(v) for c, v in zip(constants, x, strict=True)
        ]

    def to_x(values: Sequence[float]) -> FloatArray:
        return np.array(
            [math.log(v) if c.log else v for c, v in zip(constants, values, strict=True)]
        )

    # the scatter of a measured shear curve grows with its force: residuals are relative to
    # the force, floored at RELATIVE_FLOOR of the peak so points near zero do not dominate
    if weights not in ("relative", "absolute"):
        raise CalibrationError(f"weights must be relative or absolute, got {weights!r}")
    scale = np.maximum(np.abs(data), RELATIVE_FLOOR * float(np.max(np.abs(data))))
    if weights == "absolute":
        scale = np.ones_like(data)
    if not np.all(scale > 0.0):
        raise CalibrationError("the data in the fit range carry no force")

    def residual(x: FloatArray) -> FloatArray:
        law = trial.law(constants, to_values(x))
        return np.asarray((force_per_length_N_per_mm(law, gamma) - data) / scale, dtype=float)

    low = to_x([c.low for c in constants])
    high = to_x([c.high for c in constants])
    start = np.clip(to_x([c.start for c in constants]), low, high)
    result = least_squares(
        residual, start, bounds=(low, high), method="trf", x_scale="jac", diff_step=1e-4
    )
    values = to_values(result.x)
    sigma_x, correlation = _covariance(result.jac, result.fun, len(constants))
    fitted = [
        FittedConstant(
            c.name,
            v,
            None if s is None else (v * s if c.log else s),
            c.start,
            c.low,
            c.high,
            bool(result.active_mask[i] != 0),
        )
        for i, (c, v, s) in enumerate(zip(constants, values, sigma_x, strict=True))
    ]
    calibrated_fabric = trial.fabric_with(constants, values)
    from preform.library import build_shear_law

    law = build_shear_law(calibrated_fabric, registry)
    start_law = build_shear_law(fabric, registry)
    locking = getattr(law, "locking_angle", None)
    locking_deg = None if locking is None else math.degrees(locking)
    fit_quality = quality(force_per_length_N_per_mm(law, gamma), data, angle[chosen])
    upto = angle <= (top if locking_deg is None else locking_deg)
    g_lock = np.radians(angle[upto])

    def compared(a_law: Any) -> Quality:
        return quality(force_per_length_N_per_mm(a_law, g_lock), force[upto], angle[upto])

    notes = [f"{weights} residuals (see preform.shear.calibrate)"]
    if any(c.sigma is None for c in fitted):
        notes.append(
            "a constant without uncertainty is not determined by the data in the fit range "
            "(the model's force does not depend on it independently of the others there): "
            "widen the range (--max-angle-deg) or fit fewer constants"
        )
    entry = trial.entry_with(constants, values)
    entry["name"] = f"{fabric.name}-calibrated"
    described = ", ".join(f"{c.name} = {c.value:.6g}" for c in fitted)
    entry["note"] = (
        f"{entry.get('note', '')} Calibrated by preform calibrate against {test} data "
        f"{Path(data_file).name or '(in memory)'}: {described} (see the comments of the file "
        "it was written to)."
    ).strip()
    start_entry = copy.deepcopy(trial.entry)
    return Calibration(
        fabric=fabric.name,
        law=_law_name(trial.entry),
        test=test,
        specimen=dict(specimen or {}),
        angle_deg=angle,
        force_N_per_mm=force,
        max_angle_deg=top,
        constants=fitted,
        correlation=correlation,
        fit=fit_quality,
        up_to_locking=compared(law),
        start_up_to_locking=compared(start_law),
        locking_angle_deg=locking_deg,
        entry=entry,
        start_entry=start_entry,
        notes=notes,
        registry=registry,
        data_file=data_file,
        data_sha256=data_sha256,
    )


def _covariance(
    jac: FloatArray, residual: FloatArray, count: int
) -> tuple[list[float | None], list[list[float | None]]]:
    """Standard deviations of the fitted variables and their correlation matrix from the
    Jacobian at the optimum, cov = s²(JᵀJ)⁻¹ with s² = Σr²/(n − p). A variable along a
    direction the data do not see (a singular value below 1e-8 of the largest) gets None."""
    import numpy as np

    n = residual.size
    dof = max(n - count, 1)
    s2 = float(residual @ residual) / dof
    _, singular, vt = np.linalg.svd(jac, full_matrices=False)
    keep = singular > 1e-8 * singular.max() if singular.size and singular.max() > 0 else []
    undetermined = np.zeros(count, dtype=bool)
    for k, kept in enumerate(keep):
        if not kept:
            undetermined |= np.abs(vt[k]) > 1e-6
    inv = (
        (vt.T[:, keep] / singular[keep] ** 2) @ vt[keep]
        if np.any(keep)
        else np.zeros((count, count))
    )
    cov = s2 * inv
    sigma: list[float | None] = [
        None if undetermined[i] else float(math.sqrt(max(cov[i, i], 0.0))) for i in range(count)
    ]
    corr: list[list[float | None]] = []
    for i in range(count):
        row: list[float | None] = []
        for j in range(count):
            si, sj = sigma[i], sigma[j]
            if si is None or sj is None or si == 0.0 or sj == 0.0:
                row.append(1.0 if i == j else None)
            else:
                row.append(float(cov[i, j] / math.sqrt(cov[i, i] * cov[j, j])))
        corr.append(row)
    return sigma, corr


# -- carrying constants to fabrics of the same tows ----------------------------------------


def tow_signatures(entry: Mapping[str, Any]) -> dict[str, tuple[Any, ...]]:
    """Every tow description of an entry, by where it is (``tow_types.glass``,
    ``tow_layers[0]``), as (fibre, linear density [tex], width [mm], height [mm])."""
    out: dict[str, tuple[Any, ...]] = {}

    def signature(tow: Mapping[str, Any]) -> tuple[Any, ...]:
        return tuple(next((tow[k] for k in keys if k in tow), None) for keys in TOW_KEYS)

    types = entry.get("tow_types")
    if isinstance(types, dict):
        for name, tow in types.items():
            if isinstance(tow, dict):
                out[f"tow_types.{name}"] = signature(tow)
    layers = entry.get("tow_layers")
    if isinstance(layers, list):
        for i, tow in enumerate(layers):
            if isinstance(tow, dict):
                out[f"tow_layers[{i}]"] = signature(tow)
    return out


def describe_tow(signature: tuple[Any, ...]) -> str:
    fibre, tex, width, height = signature
    return f"{fibre} {tex:g} tex {width:g}×{height:g} mm"


@dataclass(frozen=True)
class Transfer:
    """A calibration carried to another fabric: its calibrated entry, or why not."""

    fabric: str
    entry: dict[str, Any] | None
    reason: str

    def as_json(self) -> dict[str, Any]:
        return {
            "fabric": self.fabric,
            "written": self.entry is not None,
            "name": None if self.entry is None else self.entry["name"],
            "reason": self.reason,
        }


def transfer(calibration: Calibration, target: FabricBase, registry: Registry) -> Transfer:
    """``calibration``'s constants carried to ``target`` when it is built from the same tows
    (same set of fibre, tex, width and height) and has the same law; paths under a tow type
    are renamed to the target's tow type of the same signature. Otherwise the reason why not.
    """
    source = calibration.start_entry
    entry: dict[str, Any] = target.model_dump(mode="json", exclude_none=True)
    mine, theirs = tow_signatures(source), tow_signatures(entry)
    if not mine:
        return Transfer(target.name, None, "the calibrated fabric describes no tows to compare")
    if set(mine.values()) != set(theirs.values()):
        ours = "; ".join(sorted({describe_tow(s) for s in mine.values()}))
        other = "; ".join(sorted({describe_tow(s) for s in theirs.values() if None not in s}))
        return Transfer(
            target.name, None, f"different tows: {other or 'none'} (calibrated on {ours})"
        )
    if _law_name(entry) != calibration.law:
        return Transfer(
            target.name,
            None,
            f"law {_law_name(entry) or 'none'!r}, not {calibration.law!r}: the constants "
            "belong to another law",
        )
    rename = {where: _same_tow(sig, theirs) for where, sig in mine.items()}
    carried = []
    for constant in calibration.constants:
        path = parse_path(constant.name)
        for where, target_tow in rename.items():
            prefix = parse_path(where)
            if path[: len(prefix)] == prefix and target_tow is not None:
                path = (*parse_path(target_tow), *path[len(prefix) :])
                break
        try:
            get_path(entry, path[:-1])
            set_path(entry, path, constant.value)
        except KeyError:
            return Transfer(
                target.name, None, f"its entry has no {format_path(path)} to carry over"
            )
        carried.append(f"{format_path(path)} = {constant.value:.6g}")
    entry["name"] = f"{target.name}-calibrated"
    entry["note"] = (
        f"{entry.get('note', '')} Calibrated constants carried over from {calibration.fabric} "
        f"(calibrated on {calibration.test} data {Path(calibration.data_file).name or ''}, "
        f"{calibration.date}), which is built from the same tows: {', '.join(carried)}. "
        "Not fitted to a test of this fabric."
    ).strip()
    try:
        validated_fabric(entry, registry)
    except CalibrationError as exc:
        return Transfer(target.name, None, f"the carried constants do not validate: {exc}")
    return Transfer(target.name, entry, f"same tows; carried {', '.join(carried)}")


def _same_tow(signature: tuple[Any, ...], tows: Mapping[str, tuple[Any, ...]]) -> str | None:
    return next((where for where, s in tows.items() if s == signature), None)


def transfers(calibration: Calibration, library: Library, pattern: str) -> list[Transfer]:
    """:func:`transfer` to every fabric of ``library`` whose name matches ``pattern`` (a glob),
    except the calibrated fabric itself."""
    names = [n for n in library.names() if fnmatch.fnmatchcase(n, pattern)]
    if not names:
        raise CalibrationError(f"--apply-to {pattern!r} matches no fabric of the library")
    return [
        transfer(calibration, library.fabric(n), library.registry)
        for n in names
        if n != calibration.fabric
    ]
