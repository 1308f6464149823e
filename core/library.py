"""The materials library: YAML files → validated fabric models, with located errors.

Where fabrics come from, in order: the bundled ``preform/materials/fabrics``, every path in
``PREFORM_LIBRARY`` (``os.pathsep``-separated files or directories), and the paths a command
is given. Names must be unique across everything loaded. A file holds one entry (a mapping), a
list of entries, or several YAML documents of either.

Every problem of every file is collected and reported at once as
``FILE:LINE:COL: path.to.field: message``; loading never ends in a traceback.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, NamedTuple

from pydantic import BaseModel, ValidationError

from preform.material import FabricBase, Location, plausibility_checks
from preform.registry import LazyLoadError, Registry
from preform.validation import format_path, located_errors
from preform.yamlsource import Document, SourceError, YamlSourceError, load_yaml

YAML_SUFFIXES = (".yaml", ".yml")


class LibraryError(Exception):
    """Validation failed; ``errors`` holds every located problem."""

    def __init__(self, errors: Sequence[SourceError]) -> None:
        self.errors = list(errors)
        super().__init__("\n".join(str(e) for e in self.errors))


class Origin(NamedTuple):
    """Where an entry was defined. A named tuple, not a frozen dataclass: as immutable and
    compared by value, without execing generated methods at every start-up (issue 15l)."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


def bundled_library_dir() -> Path:
    """The directory of the fabrics that ship with preform."""
    return Path(str(resources.files("preform.materials") / "fabrics"))


def environment_paths() -> list[Path]:
    """Library paths from ``PREFORM_LIBRARY``."""
    raw = os.environ.get("PREFORM_LIBRARY", "")
    return [Path(p) for p in raw.split(os.pathsep) if p.strip()]


def yaml_files(path: Path) -> list[Path]:
    """The YAML files of a library path (a file, or a directory searched recursively)."""
    if path.is_dir():
        return sorted(p for p in path.rglob("*") if p.suffix in YAML_SUFFIXES and p.is_file())
    return [path]


def _entries(doc: Document) -> Iterator[tuple[Location, Any]]:
    if isinstance(doc.data, list):
        for i, item in enumerate(doc.data):
            yield (i,), item
    else:
        yield (), doc.data


def _entry_label(entry: Any, base: Location) -> str:
    name = entry.get("name") if isinstance(entry, dict) else None
    if isinstance(name, str) and name:
        return name
    return format_path(base) or "entry"


@dataclass
class Library:
    """Validated fabrics by name, where each came from, and the lint warnings."""

    registry: Registry
    fabrics: dict[str, FabricBase] = field(default_factory=dict)
    origins: dict[str, Origin] = field(default_factory=dict)
    warnings: list[SourceError] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.fabrics)

    def __iter__(self) -> Iterator[FabricBase]:
        return iter(self.fabrics.values())

    def names(self) -> list[str]:
        return list(self.fabrics)

    def fabric(self, name: str) -> FabricBase:
        """The fabric called ``name``; a KeyError suggests close names."""
        try:
            return self.fabrics[name]
        except KeyError:
            import difflib  # for the message only: off the path of a good listing

            close = difflib.get_close_matches(name, self.fabrics, n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise KeyError(f"no fabric named {name!r} in the library{hint}") from None

    def shear_law(self, name: str) -> Any:
        """The built ``ShearLaw`` of a fabric: its ``shear_law`` block, else its architecture's
        default; a LookupError when it has neither."""
        return build_shear_law(self.fabric(name), self.registry)


def build_shear_law(fabric: FabricBase, registry: Registry) -> Any:
    """Build the ShearLaw object of a validated fabric."""
    params = fabric.shear_law if fabric.shear_law is not None else fabric.default_shear_law()
    if params is None:
        raise LookupError(
            f"fabric {fabric.name!r} has no shear_law block and its architecture "
            f"{fabric.architecture!r} gives no default; add a shear_law (see `preform fit`)"
        )
    if isinstance(params, dict):
        params = registry.shear_law_type(str(params.get("law"))).params.model_validate(params)
    law_type = registry.shear_law_type(params.law)
    return law_type.build(params, fabric)


def validate_entry(
    doc: Document, base: Location, entry: Any, registry: Registry
) -> tuple[FabricBase | None, list[SourceError], list[SourceError]]:
    """Validate one entry; returns (fabric or None, errors, warnings)."""
    label = _entry_label(entry, base)

    def err(path: Location, message: str, shown: str | None = None) -> SourceError:
        line, column = doc.locate_value(base + path)
        return SourceError(doc.file, line, column, shown or f"{label}.{format_path(path)}", message)

    if not isinstance(entry, dict):
        return (
            None,
            [err((), f"a fabric entry must be a mapping, got {type(entry).__name__}", label)],
            [],
        )
    tag = entry.get("architecture")
    known = registry.names("architectures")
    if tag is None:
        return (
            None,
            [
                err(
                    (),
                    f"missing 'architecture'; registered architectures: "
                    f"{', '.join(known) or 'none'}",
                    label,
                )
            ],
            [],
        )
    if tag not in known:
        import difflib

        close = difflib.get_close_matches(str(tag), known, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        return (
            None,
            [
                err(
                    ("architecture",),
                    f"unknown architecture {tag!r}{hint}; "
                    f"registered architectures: {', '.join(known) or 'none'}",
                )
            ],
            [],
        )
    try:
        model = registry.architecture(tag)
    except LazyLoadError as exc:  # a plugin's lazily registered model that does not load
        return None, [err(("architecture",), str(exc))], []
    errors: list[SourceError] = []
    law_params: BaseModel | None = None
    raw_law = entry.get("shear_law")
    if raw_law is not None:
        law_params, law_errors = _validate_law(doc, base, raw_law, registry, label)
        errors += law_errors
    try:
        fabric = model.model_validate(entry)
    except ValidationError as exc:
        return None, errors + located_errors(doc, base, entry, exc, model, label), []
    if errors:
        return None, errors, []
    if law_params is not None:
        fabric = fabric.model_copy(update={"shear_law": law_params})
    # Plausible ranges before the architecture's own checks: a value in the wrong unit (a tow
    # width in µm) would otherwise reach the unit-cell builder, which may take long on it.
    range_errors, range_warnings = _range_problems(fabric, err)
    if range_errors:
        return None, range_errors, []
    # the architecture's own checks are plugin code: contained like a hook (a SystemExit or a
    # print there must neither end the command nor reach a --json stdout)
    from preform.plugin_manager import call_plugin

    def own_checks() -> tuple[list[Any], list[Any]]:
        return list(fabric.errors()), list(fabric.check())

    checked, failure = call_plugin(f"architecture {tag}", own_checks)
    if failure is not None:  # a plugin bug must be reported, not crash the whole library
        return (
            None,
            [err((), f"architecture {tag!r} failed to check this entry: {failure!r}", label)],
            [],
        )
    consistency, warns = checked
    errors += [err(tuple(path), msg) for path, msg in consistency]
    if errors:
        return None, errors, []
    warnings = range_warnings + [err(tuple(path), msg) for path, msg in warns]
    return fabric, [], warnings


def _range_problems(fabric: FabricBase, err: Any) -> tuple[list[SourceError], list[SourceError]]:
    """Values outside their plausible range (errors), and the ones the entry accepts on purpose
    through ``accept_out_of_range`` (warnings); an override naming no range-checked field is an
    error, one naming a value inside its range a warning (it is not needed).

    An override names a field as the errors do (``tow_types.glass.width_mm``,
    ``shear_law.force_N_per_mm[2]``); naming a list (``shear_law.force_N_per_mm``) accepts
    every item of it."""
    checks = plausibility_checks(fabric)
    overrides = fabric.accept_out_of_range or ()
    paths = [format_path(c.path) for c in checks]

    def covered(path: str, override: str) -> bool:
        return path == override or path.startswith(override + "[")

    errors: list[SourceError] = []
    warnings: list[SourceError] = []
    for i, override in enumerate(overrides):
        where = ("accept_out_of_range", i)
        matching = [c for c, p in zip(checks, paths, strict=True) if covered(p, override)]
        if not matching:
            import difflib

            close = difflib.get_close_matches(override, paths, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            errors.append(
                err(where, f"{override!r} names no range-checked value of this entry{hint}")
            )
        elif all(c.inside for c in matching):
            warnings.append(
                err(
                    where,
                    f"{override!r} is inside its plausible range "
                    f"({matching[0].rule.describe()}); the override is not needed",
                )
            )
    for check, path in zip(checks, paths, strict=True):
        if check.inside:
            continue
        if any(covered(path, o) for o in overrides):
            warnings.append(
                err(
                    check.path,
                    f"{check.outside()}; accepted by override (accept_out_of_range)",
                )
            )
        else:
            errors.append(err(check.path, check.message(path)))
    return errors, warnings


def _validate_law(
    doc: Document, base: Location, raw: Any, registry: Registry, label: str
) -> tuple[BaseModel | None, list[SourceError]]:
    where = (*base, "shear_law")
    line, column = doc.locate(where)
    if not isinstance(raw, dict):
        return None, [
            SourceError(
                doc.file,
                line,
                column,
                f"{label}.shear_law",
                "shear_law must be a mapping with a 'law' field",
            )
        ]
    known = registry.names("shear_laws")
    law = raw.get("law")
    if law not in known:
        import difflib

        close = difflib.get_close_matches(str(law), known, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        line, column = doc.locate(where + (("law",) if "law" in raw else ()))
        return None, [
            SourceError(
                doc.file,
                line,
                column,
                f"{label}.shear_law.law",
                f"unknown shear law {law!r}{hint}; registered shear laws: "
                f"{', '.join(known) or 'none'}",
            )
        ]
    try:
        params_model = registry.shear_law_type(str(law)).params
    except LazyLoadError as exc:  # a plugin's lazily registered law that does not load
        line, column = doc.locate((*where, "law"))
        return None, [SourceError(doc.file, line, column, f"{label}.shear_law.law", str(exc))]
    try:
        return params_model.model_validate(raw), []
    except ValidationError as exc:
        return None, located_errors(doc, where, raw, exc, params_model, f"{label}.shear_law")


def validate_files(
    paths: Iterable[Path], registry: Registry
) -> tuple[list[tuple[FabricBase, Origin]], list[SourceError], list[SourceError]]:
    """Validate library files; returns (fabrics with origins, errors, warnings).

    Every file is read even after errors, so the user sees everything at once; duplicate names
    across files are errors at the second definition.
    """
    fabrics: list[tuple[FabricBase, Origin]] = []
    errors: list[SourceError] = []
    warnings: list[SourceError] = []
    seen: dict[str, Origin] = {}
    hooks = _material_lint_hooks(registry)
    for path in paths:
        if not path.exists():
            errors.append(SourceError(str(path), 1, 1, "", "no such file or directory"))
            continue
        files = yaml_files(path)
        if path.is_dir() and not files:
            errors.append(SourceError(str(path), 1, 1, "", "directory holds no .yaml files"))
        for file in files:
            try:
                docs = load_yaml(file)
            except YamlSourceError as exc:
                errors += exc.errors
                continue
            for doc in docs:
                for base, entry in _entries(doc):
                    fabric, errs, warns = validate_entry(doc, base, entry, registry)
                    errors += errs
                    warnings += warns
                    if fabric is None:
                        continue
                    line, column = doc.locate_value((*base, "name"))
                    origin = Origin(doc.file, line, column)
                    if fabric.name in seen:
                        errors.append(
                            SourceError(
                                doc.file,
                                line,
                                column,
                                f"{fabric.name}.name",
                                f"duplicate fabric name {fabric.name!r}; first defined at "
                                f"{seen[fabric.name]}; names must be unique across the library",
                            )
                        )
                        continue
                    seen[fabric.name] = origin
                    for message in hooks(fabric):
                        warnings.append(SourceError(doc.file, line, column, fabric.name, message))
                    fabrics.append((fabric, origin))
    return fabrics, errors, warnings


def _material_lint_hooks(registry: Registry) -> Any:
    """Collect warnings from every plugin's ``preform_check_material`` hook.

    The calls go through the registry's PluginHost, which calls each plugin on its own and
    turns a hook that raises or returns something malformed into a warning naming the plugin
    and the fabric: a broken lint must never stop a library from loading.
    """

    def lint(fabric: FabricBase) -> list[str]:
        if registry.host is None:
            return []
        messages: list[str] = registry.host.check_material(fabric)
        return messages

    return lint


def load_library(
    paths: Sequence[str | os.PathLike[str]] = (),
    *,
    bundled: bool = True,
    env: bool = True,
    registry: Registry | None = None,
) -> Library:
    """Load and validate the library; raises ``LibraryError`` with every problem found."""
    if registry is None:
        from preform.plugin_manager import default_host

        registry = default_host().registry
    sources: list[Path] = []
    if bundled:
        sources.append(bundled_library_dir())
    if env:
        sources += environment_paths()
    sources += [Path(p) for p in paths]
    fabrics, errors, warnings = validate_files(sources, registry)
    if errors:
        raise LibraryError(errors)
    lib = Library(registry=registry, warnings=warnings, files=sources)
    for fabric, origin in fabrics:
        lib.fabrics[fabric.name] = fabric
        lib.origins[fabric.name] = origin
    return lib


def fabric_from_data(data: dict[str, Any], registry: Registry) -> FabricBase:
    """Rebuild a validated fabric from its dumped data (worker processes).

    The data came from a fabric that already passed ``load_library``; an error here means the
    worker's plugins differ from the parent's, and it says so.
    """
    tag = data.get("architecture")
    try:
        model = registry.architecture(str(tag))
    except KeyError as exc:
        raise LookupError(f"worker cannot rebuild fabric {data.get('name')!r}: {exc}") from None
    law = data.get("shear_law")
    fabric = model.model_validate({k: v for k, v in data.items() if k != "shear_law"})
    if law is not None:
        params = registry.shear_law_type(str(law.get("law"))).params.model_validate(law)
        fabric = fabric.model_copy(update={"shear_law": params})
    return fabric
