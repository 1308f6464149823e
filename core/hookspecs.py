"""Every hook a preform plugin can implement. The docstrings here are the reference.

Hooks *register*; they do not compute. Each ``preform_register_*`` hook receives a typed
registrar and calls ``register.add(...)`` once per thing it provides; preform then calls the
registered objects directly. That keeps errors attributable to a plugin, keeps everything
picklable for worker processes, and lets each registry entry carry its plugin's name and version.
Every registrar but the commands' also has ``register.add_lazy(...)``, which registers by
import path (``"package.module:ATTRIBUTE"``) so the plugin's modules load only when first used
(see ``preform.registry``: what is checked at once, and what when the entry is loaded).

A plugin is a module (or object) with functions decorated by ``preform.hookimpl`` and named
exactly as below; a misspelled name is an error that fails that plugin, and so is a hook wrapper
(``hookwrapper=True``/``wrapper=True``): preform calls each plugin's implementation itself.
Plugins are found through the ``preform`` entry-point group.

What preform guarantees about every call into a plugin (its import and each hook below):

- It is contained: any exception, ``SystemExit`` included, is recorded against the plugin (its
  error in ``preform plugins list``) and the others go on; only ``KeyboardInterrupt`` stops the
  program. A registration hook that fails unloads its plugin with everything it registered.
- It is kept off stdout: what a plugin prints (or writes to file descriptor 1) goes to stderr,
  each line prefixed with ``plugin NAME:``, so ``--json`` and ``schema`` output stays valid.
- Names are first come, first served, except that preform's own plugins (``core``, ``woven``,
  ``warpknit``, ``surfaces``) load first and always keep theirs: registering a name another
  plugin holds (a law, architecture, surface, step or exporter name, a step product, a command)
  fails the plugin, naming the holder.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import pluggy

if TYPE_CHECKING:
    import click

    from preform.material import FabricBase
    from preform.registry import (
        ArchitectureRegistrar,
        ExporterRegistrar,
        ShearLawRegistrar,
        StepRegistrar,
        SurfaceRegistrar,
    )

hookspec = pluggy.HookspecMarker("preform")


@hookspec
def preform_register_architectures(register: ArchitectureRegistrar) -> None:
    """Register fabric architectures: ``register.add(Model)`` for each pydantic model deriving
    from ``preform.FabricBase`` whose ``architecture`` field is a ``Literal`` of its tag."""


@hookspec
def preform_register_shear_laws(register: ShearLawRegistrar) -> None:
    """Register shear laws: ``register.add(name, Params, build)``. ``Params`` is a pydantic
    model with ``law: Literal[name]``; ``build(params, fabric)`` returns a ``ShearLaw``."""


@hookspec
def preform_register_surfaces(register: SurfaceRegistrar) -> None:
    """Register tool surfaces: ``register.add(name, Params, build)``. ``Params`` is a pydantic
    model with ``surface: Literal[name]`` and dimensions in mm; ``build(params, base_dir)``
    returns a ``preform.drape.engine.surface.Surface`` in metres (``base_dir`` resolves file paths
    given in a scene)."""


@hookspec
def preform_register_steps(register: StepRegistrar) -> None:
    """Register pipeline steps: ``register.add(Step(...))`` with what each provides and
    requires, and a version that is recorded with every result; a step owning a scene section
    declares it (``Step.sections``, ``Step.check``; ``add_lazy(..., sections=[...])``)."""


@hookspec
def preform_register_exporters(register: ExporterRegistrar) -> None:
    """Register exporters: steps that turn computed products into files of a case folder
    (``register.add(Step(...))`` with ``writes_files=True``)."""


@hookspec
def preform_register_commands(cli: click.Group) -> None:
    """Add click commands to the ``preform`` command group. New names only: replacing one of
    preform's commands or another plugin's fails the plugin (and the original stays)."""


@hookspec
def preform_check_material(material: FabricBase) -> list[Any] | None:
    """Lint a validated fabric: return None or a list of warnings, each a message (``str``) or
    a ``(location, message)`` pair where location is a key or a path (tuple of ``str``/``int``)
    inside the entry. All plugins' warnings are collected, each plugin called on its own; one
    that raises or returns anything else is reported as a warning naming the plugin and the
    fabric (and in its ``problems`` in ``preform plugins list --json`` of that process)."""
