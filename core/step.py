"""A pipeline step: a named computation with what it provides, what it requires, a version.

The contract between plugins, the registry and the pipeline: the registry checks a ``Step`` on
the way in and the pipeline runs it with a ``CaseContext``. It lives outside ``preform.pipeline``
so the registry can import it without importing the pipeline, whose planner and scene import
the registry (imports flow one way: pipeline -> registry -> step). Public as ``preform.Step``
and ``preform.CaseContext``; ``preform.pipeline.step`` is its deprecated old path.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pydantic import BaseModel

    from preform.material import FabricBase
    from preform.pipeline.scene import Scene
    from preform.registry import Registry
    from preform.yamlsource import Document, SourceError


#: Key of a case's summary (summary.json) holding what each warning is about: a list of
#: ``{"warning": index into warnings, "cause", "scan", "area_share", "energy_share"}``, set by
#: :meth:`CaseContext.warn`; the console groups and orders a case's warnings by it.
WARNING_CAUSES = "warning_causes"


@dataclass
class CaseContext:
    """What a step sees while one (material, scene) case runs."""

    fabric: FabricBase
    scene: Scene
    registry: Registry
    #: The case's output folder; file-writing steps write here (atomically).
    case_dir: Path
    #: Products computed so far, by name.
    products: dict[str, Any] = field(default_factory=dict)
    #: Scalar results of the case (go to summary.json and a row of results.csv).
    summary: dict[str, Any] = field(default_factory=dict)
    #: Files written by the case, relative to case_dir.
    files: list[str] = field(default_factory=list)
    #: Why the result covers less than the scene asked (or is mostly no physical energy:
    #: ``preform.drape.judging.wrinkling``), in words; any makes the case
    #: ``partial`` (see ``preform.base.status``). Set through :meth:`partial`.
    partial_reasons: list[str] = field(default_factory=list)
    #: What the user must know about a result that is still complete (cells past locking,
    #: angles outside the law's data range), in words. Set through :meth:`warn`.
    warnings: list[str] = field(default_factory=list)

    def partial(self, reason: str, covered_fraction: float | None = None) -> None:
        """Mark the result partial: it is finite but does not cover what the scene asked (or
        its energy is mostly from where the fabric would wrinkle).

        ``covered_fraction`` (0..1) is the share of what was asked that the result covers
        (e.g. of the part's area); the smallest one given is recorded as ``covered_fraction``.
        """
        if reason not in self.partial_reasons:
            self.partial_reasons.append(reason)
        if covered_fraction is not None:
            previous = self.summary.get("covered_fraction")
            value = float(covered_fraction)
            self.summary["covered_fraction"] = (
                value if previous is None else min(float(previous), value)
            )

    def warn(
        self,
        message: str,
        *,
        cause: str | None = None,
        area_share: float | None = None,
        energy_share: float | None = None,
        scan: bool = False,
    ) -> None:
        """Say something the user must know about this case's result, in words.

        Every warning goes in full to summary.json and the tables. The console's end of a
        run gives each case one line, naming each ``cause`` once (a few words that read after
        "N % of the part": "past jamming"; warnings of one cause are counted together) with
        ``area_share`` (of the part's area it concerns) and ``energy_share`` (of the case's
        energy) [-, 0..1], the worst first (``preform.pipeline.console``). ``scan``: about
        angles a search only sampled, not the result it chose; shown with ``-v`` only.
        """
        if message in self.warnings:
            return
        self.warnings.append(message)
        if cause is None and area_share is None and energy_share is None and not scan:
            return
        note: dict[str, Any] = {"warning": len(self.warnings) - 1, "cause": cause, "scan": scan}
        if area_share is not None:
            note["area_share"] = float(area_share)
        if energy_share is not None:
            note["energy_share"] = float(energy_share)
        self.summary.setdefault(WARNING_CAUSES, []).append(note)


#: A step's body: reads ``ctx.products`` (its requirements), returns what it provides.
StepFunction = Callable[[CaseContext], Mapping[str, Any]]
#: A step's check of the scene sections it owns, before anything runs: given the validated
#: scene, its source document and the registry, the problems, each located by
#: ``doc.error(path, message)`` (``at_value=True`` for "this value is wrong").
SceneCheck = Callable[["Scene", "Document", "Registry"], list["SourceError"]]


@dataclass(frozen=True)
class Step:
    """One registered computation.

    ``run`` must be a module-level function (picklable). It returns a mapping with a value for
    every name in ``provides``; a file-writing step (``writes_files``) returns the relative paths
    it wrote as the value of its product.
    """

    name: str
    provides: tuple[str, ...]
    requires: tuple[str, ...]
    version: str
    run: StepFunction
    description: str = ""
    writes_files: bool = False
    #: Scene sections the step needs (checked when a scene is planned: "tool", "ply", ...).
    scene_sections: tuple[str, ...] = ()
    #: Scene sections the step owns, by top-level key, each with the pydantic model that
    #: validates it (None: a field of ``Scene`` itself, preform's own sections). A scene key no
    #: registered step owns is refused; a plugin's section reaches its step as
    #: ``ctx.scene.section(key)``.
    sections: Mapping[str, type[BaseModel] | None] = field(default_factory=dict, hash=False)
    #: Checks of the owned sections that need more than their models (module-level function),
    #: called once the scene has validated, when it holds any of them.
    check: SceneCheck | None = None
    #: Extra requirements that depend on the scene (a module-level function of the scene),
    #: e.g. the drape needs the search's optimum when the scene searches.
    extra_requires: Callable[[Scene], tuple[str, ...]] | None = None
    #: Run-level output (module-level function): called once per scene after all its cases,
    #: with the scene's results folder and the summaries of its successful cases (each with
    #: ``material`` and the case's scalar and list results); returns the files it wrote,
    #: relative to the folder. E.g. one energy curve per fabric on one figure.
    aggregate: Callable[[Path, list[Mapping[str, Any]]], list[str]] | None = None

    @classmethod
    def exporter(
        cls,
        name: str,
        requires: tuple[str, ...],
        run: StepFunction,
        description: str,
        *,
        version: str = "1",
        extra_requires: Callable[[Scene], tuple[str, ...]] | None = None,
        aggregate: Callable[[Path, list[Mapping[str, Any]]], list[str]] | None = None,
    ) -> Step:
        """A file-writing step (an exporter) providing the one product ``name``: the files it
        wrote, relative to the case folder. Every field as in :class:`Step`."""
        return cls(
            name,
            (name,),
            requires,
            version,
            run,
            description,
            writes_files=True,
            extra_requires=extra_requires,
            aggregate=aggregate,
        )
