"""The ``preform`` command line. Plugins add commands through ``preform_register_commands``."""

from __future__ import annotations

import atexit
import contextlib
import copy
import gc
import os
import sys
from pathlib import Path
from typing import Any, Literal

import click

from preform.base import __version__
from preform.collector import end_startup, startup_phase
from preform.command_line import (
    EXIT_INTERNAL,
    echo_json,
    fabric_or_exit,
    fail,
    file_option,
    json_option,
    library_options,
    load_library_or_exit,
)

QUIET_HELP = "pipeline run: print only the summary line and the cases that failed (errors)."
VERBOSE_HELP = (
    "pipeline run: print every warning of every case in full, those about angles a search "
    "only sampled too."
)

EXIT_CODES_HELP = """\b
Exit codes:
  0    done; no case failed
  1    done, with failures: invalid files (materials validate), cases failed or timed out
  2    bad usage or input, nothing was run: unknown option, fabric or scene; invalid library
       or scene file
  3    an unexpected error inside preform or a plugin: rerun with --debug, report it
  130  interrupted (Ctrl-C, SIGTERM)
"""


def _host() -> Any:
    from preform.plugin_manager import default_host

    return default_host()


#: preform's own commands whose modules load only when the command is used (their imports,
#: scenes, laws, tables, would slow every other command): name -> (module:attribute, the
#: command's short help as ``--help`` lists it; a test checks it against the command's own).
LAZY_COMMANDS: dict[str, tuple[str, str]] = {
    "scenes": (
        "preform.commands.scenes:scenes",
        "The bundled scenes and the outputs a scene may ask for.",
    ),
    "export": (
        "preform.commands.export:export_command",
        "Drape fabric NAME as the scene says, or a layup scene's stack, and write TARGETS "
        "(abaqus, calculix, lsdyna, ansys, table, vtu, cut-pattern).",
    ),
    "shear": (
        "preform.shear.commands:shear_command",
        "Print the shear force and energy curves of fabric NAME, both senses.",
    ),
    "fit": (
        "preform.shear.commands:fit_command",
        "Normalise a shear test (DATA.csv: displacement, force[, sense]) and fit a law.",
    ),
    "calibrate": (
        "preform.commands.calibrate:calibrate_command",
        "Fit constants of fabric FABRIC's law to a shear test (DATA.csv: displacement, force).",
    ),
    "compare": (
        "preform.commands.compare:compare_command",
        "Compare fabric FABRIC's drape with measured fibre angles (MEASUREMENT).",
    ),
    "validate": (
        "preform.validation_suite.runner:validate_command",
        "Compare the model with published measured shear curves: figures and a table.",
    ),
    "bench": (
        "preform.bench.tradeoff:bench",
        "Measure preform: speed, and the speed/accuracy trade of the fidelity knobs.",
    ),
    "report": (
        "preform.report.command:report_command",
        "Write report.html of the run folder DIR: one page, offline, from its files only.",
    ),
}


class LazyCommand(click.Command):
    """Stands for one of ``LAZY_COMMANDS`` until it is used: it lists with the command's
    short help, holds its name against plugins, and ``PreformGroup`` swaps in the real command
    when the name is looked up."""

    def __init__(self, name: str, target: str, short_help: str) -> None:
        super().__init__(name, help=short_help)
        self.target = target

    def load(self) -> click.Command:
        import importlib

        module, attribute = self.target.split(":")
        command: click.Command = getattr(importlib.import_module(module), attribute)
        return command


class PreformGroup(click.Group):
    """The root group: an unexpected exception in any command ends in one line on stderr and
    exit code 3, never a traceback, unless ``--debug`` (or ``PREFORM_DEBUG=1``) asks for it.

    Start-up stays light: the commands of ``LAZY_COMMANDS`` are imported when used, and
    plugins add their commands (``preform_register_commands``) only when a command name is not
    preform's own, when the commands are listed (``--help``) or when ``plugins list`` asks.
    """

    #: Whether the plugins' commands still have to be added to this group.
    plugin_commands_pending = False

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except (click.exceptions.ClickException, click.exceptions.Exit, click.exceptions.Abort):
            raise
        except BrokenPipeError:  # `preform ... | head`: the reader left; `main` ends quietly
            raise
        except Exception as exc:
            if ctx.meta.get("preform.debug") or os.environ.get("PREFORM_DEBUG") == "1":
                raise
            from preform.pipeline.runner import _error_text

            click.echo(f"error: {_error_text(exc)}", err=True)
            click.echo(
                "This is a bug in preform or a plugin, not in your input: run the command "
                "again as `preform --debug ...` for the traceback and report it.",
                err=True,
            )
            ctx.exit(EXIT_INTERNAL)

    def load_plugin_commands(self) -> None:
        """Let each plugin add its commands to this group, once."""
        if self.plugin_commands_pending:
            self.plugin_commands_pending = False
            _host().register_commands(self)

    def resolve_command(
        self, ctx: click.Context, args: list[str]
    ) -> tuple[str | None, click.Command | None, list[str]]:
        """As click's; the command (a lazy one imported, or a plugin's) is known, so the
        command's start-up is over: the garbage collector the entry point paused
        (``preform.__main__``) runs again before the command's body, whatever it computes."""
        resolved = super().resolve_command(ctx, args)
        end_startup()
        return resolved

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        command = self.commands.get(cmd_name)
        if isinstance(command, LazyCommand):
            command = self.commands[cmd_name] = command.load()
        if command is None and self.plugin_commands_pending:
            self.load_plugin_commands()
            command = self.commands.get(cmd_name)
        return command

    def list_commands(self, ctx: click.Context) -> list[str]:
        self.load_plugin_commands()
        return sorted(self.commands)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """As click's, without loading a lazy command to read its short help."""
        rows = []
        for name in self.list_commands(ctx):
            command = self.commands[name]
            if not command.hidden:
                rows.append((name, command.get_short_help_str(formatter.width - 6 - len(name))))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)


@click.group(
    cls=PreformGroup,
    context_settings={"help_option_names": ["-h", "--help"]},
    epilog=EXIT_CODES_HELP,
)
@click.version_option(__version__, prog_name="preform")
@click.option(
    "--debug",
    is_flag=True,
    help="Show the traceback of an unexpected error (also PREFORM_DEBUG=1).",
)
@click.option("-q", "--quiet", is_flag=True, help=QUIET_HELP)
@click.option("-v", "--verbose", is_flag=True, help=VERBOSE_HELP)
@click.pass_context
def cli(ctx: click.Context, debug: bool, quiet: bool, verbose: bool) -> None:
    """preform: fabric-architecture-aware drape simulation for composite preforms.

    Lengths are in mm and angles in degrees everywhere you type or read them; --library adds
    to the bundled library (--no-bundled leaves it out); --json prints only JSON on stdout.
    """
    ctx.meta["preform.debug"] = debug
    ctx.meta["preform.verbosity"] = _verbosity(quiet, verbose)


def _verbosity(quiet: bool, verbose: bool, default: int = 0) -> int:
    """-1 (``-q``), 0 or 1 (``-v``); ``default`` when neither is given (``preform.pipeline
    .console``)."""
    if quiet and verbose:
        raise click.UsageError("-q/--quiet and -v/--verbose exclude each other")
    return -1 if quiet else (1 if verbose else default)


# -- plugins --------------------------------------------------------------------------------
@cli.group()
def plugins() -> None:
    """Inspect loaded plugins."""


@plugins.command("list")
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
@click.option(
    "--check",
    is_flag=True,
    help="Also import everything registered by import path (add_lazy) and list what does "
    "not load among each plugin's problems.",
)
def plugins_list(as_json: bool, check: bool) -> None:
    """Each plugin, its version, what it registered, and its error if it failed."""
    root = click.get_current_context().find_root().command
    if isinstance(root, PreformGroup):  # a plugin's commands can fail it: show that too
        root.load_plugin_commands()
    host = _host()
    if check:
        host.registry.load_all()
    records = [r.as_json() for r in host.records.values()]
    if as_json:
        echo_json(records)
        return
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    table = Table(title="preform plugins")
    for col in ("name", "version", "registered", "error"):
        # fold, never elide: a name cut to "friction_compactio…" would hide the reason
        table.add_column(col, overflow="fold")
    for r in records:
        reg = "; ".join(f"{k}: {', '.join(v)}" for k, v in r["registered"].items())
        name = r["name"] + (" (built-in)" if r["builtin"] else "")
        problems = "\n".join(r["problems"])
        # errors quote plugin text: escape it, so "[...]" in a message is not taken for markup
        error = "\n".join(p for p in (r["error"], problems) if p)
        table.add_row(escape(name), r["version"] or "-", reg or "-", escape(error))
    Console().print(table)


# -- materials ------------------------------------------------------------------------------
@cli.group()
def materials() -> None:
    """List, show and validate fabrics of the materials library."""


@materials.command("list")
@library_options
@json_option
def materials_list(libraries: tuple[str, ...], no_bundled: bool, as_json: bool) -> None:
    """The fabrics of the library."""
    lib = load_library_or_exit(libraries, bundled=not no_bundled)
    rows = [
        {
            "name": f.name,
            "architecture": f.architecture,
            "source": f.source,
            "origin": str(lib.origins[f.name]),
        }
        for f in lib
    ]
    for warning in lib.warnings:
        click.echo(f"warning: {warning}", err=True)
    if as_json:
        echo_json(rows)
        return
    shown = [(r["name"], r["architecture"], shown_origin(lib.origins[r["name"]])) for r in rows]
    widths = [max([len(h), *(len(row[i]) for row in shown)]) for i, h in enumerate(LIST_HEADER)]
    for row in [LIST_HEADER, *shown]:
        click.echo("  ".join(f"{v:<{w}}" for v, w in zip(row, widths, strict=True)).rstrip())


#: The columns of ``materials list`` (``--json`` gives each fabric's full origin and source).
LIST_HEADER = ("NAME", "ARCHITECTURE", "LIBRARY")


def shown_origin(origin: Any) -> str:
    """Where a fabric was defined, without the install path: ``bundled warpknit.yaml:43``
    for the bundled library, else the file relative to the current directory when it lies
    below it (as the user named it), else as it is; with the entry's line."""
    from preform.library import bundled_library_dir

    file = Path(origin.file)
    for base, prefix in ((bundled_library_dir(), "bundled "), (Path.cwd(), "")):
        with contextlib.suppress(ValueError, OSError):
            return f"{prefix}{file.resolve().relative_to(base.resolve())}:{origin.line}"
    return f"{file}:{origin.line}"


def fabric_document(fabric: Any) -> dict[str, Any]:
    """A fabric as shown by ``materials show``: YAML units, plus derived properties."""
    from preform.plugin_manager import call_plugin

    data: dict[str, Any] = fabric.model_dump(mode="json", exclude_none=True)
    # derived() is the architecture plugin's code: contained (its prints go to stderr)
    derived, exc = call_plugin(f"architecture {fabric.architecture}", fabric.derived)
    if exc is not None:
        derived = {"error": f"{type(exc).__name__}: {exc}"}
    if derived:
        data["derived"] = derived
    return data


#: Significant digits of derived properties in ``materials show`` text (JSON keeps all): four
#: is what a datasheet gives, and what a check against one needs.
SHOWN_DIGITS = 4


def rounded(value: Any, digits: int = SHOWN_DIGITS) -> Any:
    """``value`` with every float rounded to ``digits`` significant digits (nested)."""
    if isinstance(value, dict):
        return {k: rounded(v, digits) for k, v in value.items()}
    if isinstance(value, list):
        return [rounded(v, digits) for v in value]
    if isinstance(value, float) and value == value and abs(value) != float("inf"):
        return float(f"{value:.{digits}g}")
    return value


@materials.command("show")
@click.argument("name")
@library_options
@json_option
def materials_show(name: str, libraries: tuple[str, ...], no_bundled: bool, as_json: bool) -> None:
    """One fabric's validated parameters (in the YAML's units) and derived properties.

    The text shows derived properties to 4 significant digits; --json gives them in full.
    """
    lib = load_library_or_exit(libraries, bundled=not no_bundled)
    fabric = fabric_or_exit(lib, name)
    doc = fabric_document(fabric)
    if as_json:
        echo_json(doc)
        return
    import yaml

    if "derived" in doc:
        doc["derived"] = rounded(doc["derived"])
    click.echo(f"# {shown_origin(lib.origins[name])}")
    click.echo(f"# derived: {SHOWN_DIGITS} significant digits (--json: all)")
    click.echo(yaml.safe_dump(doc, sort_keys=False, allow_unicode=True).rstrip())


@materials.command("validate")
@click.argument("paths", nargs=-1, required=True, type=click.Path())
@json_option
def materials_validate(paths: tuple[str, ...], as_json: bool) -> None:
    """Validate library files or directories; every error at once as FILE:LINE:COL.

    Exit code 1 when any error is found. --json: {"valid", "fabrics", "errors", "warnings"}.
    """
    from preform.library import validate_files

    fabrics, errors, warnings = validate_files([Path(p) for p in paths], _host().registry)
    if as_json:
        echo_json(
            {
                "valid": not errors,
                "fabrics": [fabric.name for fabric, _ in fabrics],
                "errors": [str(e) for e in errors],
                "warnings": [str(w) for w in warnings],
            }
        )
        if errors:
            sys.exit(1)
        return
    for w in warnings:
        click.echo(f"warning: {w}", err=True)
    if errors:
        fail([*errors, f"{len(errors)} error(s) in {len(paths)} path(s)."], code=1)
    click.echo(f"ok: {len(fabrics)} fabric(s) valid")


# -- view ---------------------------------------------------------------------------------
def _repeats(_ctx: Any, _param: Any, value: str) -> tuple[int, int]:
    try:
        n1, n2 = (int(v) for v in value.lower().split("x"))
    except ValueError:
        raise click.BadParameter(f"expected NxM (e.g. 2x2), got {value!r}") from None
    if n1 < 1 or n2 < 1 or n1 * n2 > 400:
        raise click.BadParameter("repeats must be between 1x1 and 20x20")
    return n1, n2


def _case_timeout(_ctx: Any, _param: Any, value: float | None) -> float | None:
    # NaN passes any range (it compares false with every bound): the same check as preform.run
    from preform.pipeline.run_arguments import case_timeout_problem

    problem = None if value is None else case_timeout_problem(value)
    if problem is not None:
        raise click.BadParameter(problem)
    return value


@cli.command()
@click.argument("name")
@click.option(
    "--repeats",
    default="2x2",
    callback=_repeats,
    show_default=True,
    help="Unit cells to draw along each direction, NxM.",
)
@file_option("--out", "png", help="Figure file; .png, .svg or .pdf (default NAME.png).")
@file_option("--vtu", help="Also write the tow paths as a VTK .vtu file for ParaView.")
@click.option(
    "--colour-by", type=click.Choice(["level", "type"]), default="level", show_default=True
)
@click.option(
    "--shear-deg",
    type=float,
    default=None,
    metavar="DEG",
    help="Draw the cell sheared by this angle [deg, either sign, |γ| ≤ 89] and print its "
    "thickness and fibre volume fractions.",
)
@library_options
@json_option
def view(
    name: str,
    repeats: tuple[int, int],
    png: str | None,
    vtu: str | None,
    colour_by: Literal["level", "type"],
    shear_deg: float | None,
    libraries: tuple[str, ...],
    no_bundled: bool,
    as_json: bool,
) -> None:
    """A 3D picture of a fabric's unit cell (tows as ribbons), and optionally a VTU file
    (tow centre-lines and tow volumes)."""
    import math

    from preform.export.fig_unit_cell import unit_cell_figure
    from preform.export.vtu import write_unit_cell_vtu

    lib = load_library_or_exit(libraries, bundled=not no_bundled)
    fabric = fabric_or_exit(lib, name)
    properties: dict[str, Any] | None = None
    if shear_deg is None:
        cell = fabric.unit_cell()
    else:
        try:
            sheared = fabric.sheared_cell(math.radians(shear_deg))
        except ValueError as error:
            fail([f"{name}: {error}"])
        if sheared is None:
            fail([f"architecture {fabric.architecture!r} has no sheared-cell model"])
        cell = sheared.unit_cell()
        properties = sheared.summary()
    if cell is None:
        fail([f"architecture {fabric.architecture!r} has no unit-cell model to view"])
    out = Path(png or f"{name}.png")
    title = name if shear_deg is None else f"{name}, sheared {shear_deg:g}°"
    unit_cell_figure(cell, out, colour_by=colour_by, repeats=repeats, title=title)
    written = {"figure": str(out), "vtu": None}
    if vtu:
        write_unit_cell_vtu(cell.tiled(*repeats), Path(vtu))
        written["vtu"] = vtu
    if as_json:
        doc: dict[str, Any] = {"material": name, "repeats": list(repeats), "files": written}
        if properties is not None:
            doc["sheared_cell"] = properties
        echo_json(doc)
        return
    if properties is not None:
        click.echo(_sheared_cell_lines(properties))
    for path in written.values():
        if path:
            click.echo(f"wrote {path}")


def _sheared_cell_lines(p: dict[str, Any]) -> str:
    """The sheared cell's properties in words (``preform view --shear-deg``)."""
    state = (
        "past jamming: the tows thicken"
        if p["jammed"]
        else ("past locking: the tows compact" if p["locked"] else "before locking")
    )
    fractions = ", ".join(f"{v:.3f}" for v in p["tow_volume_fractions"])
    return (
        f"sheared {p['shear_deg']:g}° ({state}; locking {p['locking_angle_deg']:.2f}°, "
        f"jamming {p['jamming_angle_deg']:.2f}°): thickness {p['thickness_mm']:.3f} mm, "
        f"fabric Vf {p['fibre_volume_fraction']:.3f}, tow Vf {fractions}"
    )


# -- schema ---------------------------------------------------------------------------------
@cli.command()
@click.option("--scene", "for_scene", is_flag=True, help="Schema of a scene file instead.")
def schema(for_scene: bool) -> None:
    """JSON Schema of a library file (or of a scene), for editors."""
    from preform.schema import library_schema, scene_schema

    registry = _host().registry
    # Building the schema runs plugins' pydantic models (custom schema hooks are plugin code);
    # anything they print must not end up inside the JSON.
    with contextlib.redirect_stdout(sys.stderr):
        document = scene_schema(registry) if for_scene else library_schema(registry)
    echo_json(document)


# -- pipeline -------------------------------------------------------------------------------
@cli.group()
def pipeline() -> None:
    """Run scenes over materials libraries."""


@pipeline.command("run")
@click.argument("libraries", nargs=-1, type=click.Path(), metavar="[LIBRARY]...")
@library_options(dest="extra_libraries")
@click.option(
    "--scene",
    "scenes",
    multiple=True,
    help="Scene file, or the name of a bundled scene (repeatable; `preform scenes list`). "
    "Default: the bundled default scene.",
)
@click.option(
    "--materials",
    "materials_glob",
    multiple=True,
    metavar="GLOB",
    help="Only fabrics whose name matches this glob (repeatable: a fabric matching any).",
)
@click.option(
    "--fidelity",
    type=click.Choice(["draft", "standard", "fine"]),
    default=None,
    help="Replace every scene's fidelity preset (recorded with each case, part of its input "
    "hash). Knobs a scene sets by hand still win.",
)
@click.option(
    "--out",
    "out_dir",
    default="preform-results",
    # not file_okay=False: the run directory's own check says more ("nothing was run")
    type=click.Path(),
    metavar="DIR",
    show_default=True,
    help="Results directory (created; runs into it add to it).",
)
@click.option(
    "--engine",
    type=click.Choice(["serial", "process", "dask"]),
    default="process",
    show_default=True,
)
@click.option("--scheduler", default=None, help="Dask scheduler address (engine dask).")
@click.option(
    "--workers",
    type=click.IntRange(min=1),
    default=None,
    help="Worker processes (default: all cores).",
)
@click.option(
    "--case-timeout",
    "case_timeout_s",
    type=click.FloatRange(min=0, min_open=True),
    default=None,
    callback=_case_timeout,
    help="Wall-time limit of one case [s] (default 3600; a scene's limits.case_timeout_s "
    "wins). A case past it is stopped and recorded timed_out.",
)
@click.option(
    "--batch-size",
    type=click.IntRange(min=1),
    default=None,
    help="Cases sent to a worker together (default: automatic, only when there are many; "
    "1: never). See docs/engines.md.",
)
@click.option("--force", is_flag=True, help="Redo cases that already succeeded.")
@click.option("--explain", is_flag=True, help="Print the plan of each scene and stop.")
@click.option("-q", "--quiet", is_flag=True, help=QUIET_HELP)
@click.option("-v", "--verbose", is_flag=True, help=VERBOSE_HELP)
@click.option(
    "--no-report",
    is_flag=True,
    help="Do not write report.html (the run's page; `preform report DIR` writes it later).",
)
@json_option
def pipeline_run(
    libraries: tuple[str, ...],
    extra_libraries: tuple[str, ...] = (),
    no_bundled: bool = False,
    scenes: tuple[str, ...] = (),
    materials_glob: tuple[str, ...] = (),
    fidelity: str | None = None,
    out_dir: str = "preform-results",
    engine: str = "process",
    scheduler: str | None = None,
    workers: int | None = None,
    case_timeout_s: float | None = None,
    batch_size: int | None = None,
    force: bool = False,
    explain: bool = False,
    quiet: bool = False,
    verbose: bool = False,
    no_report: bool = False,
    as_json: bool = False,
) -> None:
    """Run every (material, scene) case.

    LIBRARY paths, like --library, add to the bundled library and PREFORM_LIBRARY;
    --no-bundled uses only yours.

    Each case ends with a status: ok (complete, finite and physical), partial (finite, but
    covers less than the scene asked, or its energy comes mostly from cells past jamming or
    stitch failure: see covered_fraction and reasons), failed, timed_out, interrupted;
    skipped counts cases kept from an earlier run with identical inputs. Exit code 0 when no
    case failed or timed out, 1 otherwise, 130 when interrupted. --json prints the run's
    summary (every case with its status, reasons, warnings and error) and nothing else.

    The console ends with the counts and one line per case that is not plainly ok, the
    worst first (every warning in full: -v, summary.json, results.csv); -q keeps the counts
    and the cases that failed.
    """
    root = click.get_current_context().find_root()
    verbosity = _verbosity(quiet, verbose, default=root.meta.get("preform.verbosity", 0))
    # starting the workers, importing the pipeline's modules, reading the library and the
    # scenes and planning the cases is start-up: no garbage collection meanwhile
    # (preform.collector)
    with startup_phase():
        if (engine == "process" or (engine == "dask" and not scheduler)) and not explain:
            from preform.pipeline.preload import start_workers_early

            # first: the workers' imports (the longest wait before the first case) overlap
            # this process importing its own modules and reading the library and scenes (dask:
            # the LocalCluster opens meanwhile too)
            start_workers_early(engine, workers)
        from preform.pipeline.overrides import load_scene_changed, with_fidelity
        from preform.pipeline.planner import explain as explain_plan
        from preform.pipeline.runner import (
            DEFAULT_CASE_TIMEOUT_S,
            CaseSetError,
            RunDirectoryError,
            input_files_record,
            make_cases,
            run_cases,
        )
        from preform.pipeline.scene import (
            SceneError,
            default_scene_path,
            missing_scene_message,
            resolve_scene_path,
        )
        from preform.pipeline.summary import run_summary

        host = _host()
        lib = load_library_or_exit((*libraries, *extra_libraries), bundled=not no_bundled)
        for warning in lib.warnings if verbosity >= 0 else ():
            click.echo(f"warning: {warning}", err=True)
        scene_paths = [resolve_scene_path(s) for s in scenes] or [default_scene_path()]
        missing = [s for s, path in zip(scenes, scene_paths, strict=False) if not path.exists()]
        if missing:
            fail([f"error: {missing_scene_message(s)}" for s in missing] + ["nothing was run."])
        loaded = []
        problems: list[Any] = []
        for path in scene_paths:
            try:
                loaded.append(load_scene_changed(path, host.registry, with_fidelity(fidelity)))
            except SceneError as exc:
                problems += exc.errors
        if problems:
            fail([*problems, f"{len(problems)} error(s) in scene(s); nothing was run."])
        if explain:
            plans = [
                {
                    "scene": scene.name,
                    "outputs": list(scene.outputs),
                    "plan": explain_plan(scene, host.registry),
                }
                for scene, _ in loaded
            ]
            if as_json:
                echo_json(plans)
                return
            for entry in plans:
                click.echo(f"scene {entry['scene']}: outputs {', '.join(entry['outputs'])}")
                for line in entry["plan"]:
                    click.echo(f"  {line}")
            return
        out = Path(out_dir)
        try:
            cases = make_cases(
                lib,
                loaded,
                out,
                host,
                materials_glob,
                timeout_s=case_timeout_s or DEFAULT_CASE_TIMEOUT_S,
            )
        except CaseSetError as exc:
            fail([f"error: {exc}; nothing was run."])
        if not cases:
            fail(
                [
                    "no (material, scene) case matches; check --materials and the scenes' "
                    "materials globs"
                ],
                code=1,
            )
        inputs: dict[str, Any] = {
            "libraries": input_files_record(lib.files),
            "scenes": input_files_record(scene_paths),
            "bundled_library": not no_bundled,
        }
        if fidelity is not None:
            inputs["fidelity_override"] = fidelity
    from rich.progress import Progress

    from preform.commands.kernel_compile import ensure_compiled, load_for_serial_run
    from preform.report import write_report

    # the first run after an install compiles the drape kernels here, once and saying so,
    # before any worker needs them (they then load them from the cache)
    ensure_compiled(sys.stderr)
    if engine == "serial":
        load_for_serial_run(cases)
    try:
        with Progress(transient=False, disable=not sys.stderr.isatty()) as progress:
            task = progress.add_task("cases", total=len(cases))
            report = run_cases(
                cases,
                out,
                host,
                engine=engine,
                workers=workers,
                scheduler=scheduler,
                force=force,
                inputs=inputs,
                on_done=lambda r: progress.advance(task),
                batch_size=batch_size,
                report_page=None if no_report else write_report,
            )
    except RunDirectoryError as exc:
        fail([f"error: {exc}; nothing was run."])
    except OSError as exc:  # the results directory became unwritable (disk full, ...)
        fail([f"error: could not write the results into {out}/: {exc}"], code=1)
    from preform.pipeline.console import PROBLEM_PREFIXES, run_report_lines

    for line in run_report_lines(report, verbosity):
        # with --json, stdout holds the JSON only: the words go to stderr
        problem = line.startswith(PROBLEM_PREFIXES)
        click.echo(line, err=as_json or problem)
    if report.report_error:
        click.echo(f"warning: report.html was not written: {report.report_error}", err=True)
    summary = run_summary(report)
    if as_json:
        echo_json(summary)
    if summary["exit_code"]:
        sys.exit(summary["exit_code"])


for _name, (_target, _short_help) in LAZY_COMMANDS.items():
    cli.add_command(LazyCommand(_name, _target, _short_help))


def build_cli(*, lazy: bool = False) -> PreformGroup:
    """The command group with every plugin's commands added (``lazy``: added when first
    needed, see ``PreformGroup``).

    Plugins add to a copy of ``cli``: the module's group keeps only preform's own commands, so
    building twice (tests, embedding) never stacks plugin commands, and the host can tell a
    plugin replacing a built-in command (refused) from one adding a new command.
    """
    group = copy.copy(cli)
    assert isinstance(group, PreformGroup)
    group.commands = dict(cli.commands)
    group.plugin_commands_pending = True
    if not lazy:
        group.load_plugin_commands()
    return group


def main() -> None:
    # At exit CPython makes a last garbage collection over every object the process holds
    # (pydantic's schemas, the fabric models, plugin modules): some 40 ms, a sixth of
    # `materials list` (issue 15j). Freezing them in an exit handler skips that pass; the
    # other exit handlers, weakref finalizers (temporary directories, process pools, Dask) and
    # stream flushes still run, none of them by the collector, and only cyclic garbage left
    # at exit keeps its __del__ unrun, which CPython does not promise at exit anyway.
    atexit.register(gc.freeze)
    try:
        group = build_cli(lazy=True)
    except KeyboardInterrupt:
        # Ctrl-C while plugins load (a slow import): stop, as click does inside a command
        click.echo("Aborted!", err=True)
        sys.exit(130)
    try:
        code = group.main(prog_name="preform", standalone_mode=False)
    except click.exceptions.Abort:
        # Ctrl-C (or SIGTERM) outside a run's own handling, e.g. while the library loads:
        # the conventional 128 + SIGINT, like an interrupted run, not click's generic 1
        click.echo("Aborted!", err=True)
        sys.exit(130)
    except click.exceptions.ClickException as exc:  # usage errors: click's own words and code
        exc.show()
        sys.exit(exc.exit_code)
    except BrokenPipeError:  # `preform ... | head`: the reader left; nothing to say
        sys.stderr.close()
        sys.exit(1)
    if isinstance(code, int) and not isinstance(code, bool):  # ctx.exit(code)
        sys.exit(code)
