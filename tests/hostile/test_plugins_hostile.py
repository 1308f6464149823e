"""Hostile plugins (issue 10, item 7): a third-party plugin can never take over a built-in name,
stop another plugin, end the program, or write into ``--json``/``schema`` output.

Every plugin here is a real distribution with an entry point in a temporary site directory, found
by the same discovery a user's installation goes through; commands run through the CLI (in
process, and in a real process where stdout must be proven clean at the descriptor level).
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest


def _load_fixtures():  # the sibling module, by path (tests run with --import-mode=importlib)
    name = "preform_tests_hostile_plugins"
    if name not in sys.modules:
        path = Path(__file__).with_name("conftest_plugins.py")
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


_f = _load_fixtures()
site = _f.site  # the fixture
GOOD_LINT, assert_contained, discover, invoke, run_preform = (
    _f.GOOD_LINT,
    _f.assert_contained,
    _f.discover,
    _f.invoke,
    _f.run_preform,
)

# -- plugin sources ------------------------------------------------------------------------------

# Each takeover plugin first registers something harmless of its own (which must be rolled back
# with the rest), then a name a built-in plugin holds.
_TAKEOVER_HEAD = """
from typing import Literal
from pydantic import BaseModel
from preform import FabricBase, Step, hookimpl

class OwnParams(BaseModel):
    law: Literal["intruder_own_law"]

class OwnFabric(FabricBase):
    architecture: Literal["intruder_own_fabric"]

def build(params, other):
    raise RuntimeError("INTRUDER BUILD CALLED")

def run(ctx):
    raise RuntimeError("INTRUDER STEP RAN")
"""

_OWN_LAW = """
@hookimpl
def preform_register_shear_laws(register):
    register.add("intruder_own_law", OwnParams, build)
"""

TAKEOVERS = {
    # case: (source tail, thing, name, built-in owner)
    "friction_compaction": (
        """
class Params(BaseModel):
    law: Literal["friction_compaction"]

@hookimpl
def preform_register_shear_laws(register):
    register.add("intruder_own_law", OwnParams, build)
    register.add("friction_compaction", Params, build)
""",
        "shear law",
        "friction_compaction",
        "woven",
    ),
    "woven": (
        """
class Woven(FabricBase):
    architecture: Literal["woven"]

@hookimpl
def preform_register_architectures(register):
    register.add(OwnFabric)
    register.add(Woven)
""",
        "architecture",
        "woven",
        "woven",
    ),
    "hemisphere": (
        _OWN_LAW
        + """
class Params(BaseModel):
    surface: Literal["hemisphere"]

@hookimpl
def preform_register_surfaces(register):
    register.add("hemisphere", Params, build)
""",
        "surface",
        "hemisphere",
        "surfaces",
    ),
    "step-name": (
        _OWN_LAW
        + """
@hookimpl
def preform_register_steps(register):
    register.add(Step("drape", ("intruder_product",), (), "1", run))
""",
        "step",
        "drape",
        "core",
    ),
    "step-product": (
        _OWN_LAW
        + """
@hookimpl
def preform_register_steps(register):
    register.add(Step("intruder_step", ("drape",), (), "1", run))
""",
        "product",
        "drape",
        "core",
    ),
    "exporter-named-as-step": (
        _OWN_LAW
        + """
@hookimpl
def preform_register_exporters(register):
    register.add(Step("shear_curve", ("intruder_file",), (), "1", run, writes_files=True))
""",
        "exporter",
        "shear_curve",
        "core",
    ),
}


def _takeover_source(case: str) -> str:
    return _TAKEOVER_HEAD + TAKEOVERS[case][0]


def _assert_builtins_intact(host) -> None:
    """Every built-in loaded and holds all its usual names."""
    for name in ("core", "woven", "warpknit", "surfaces"):
        record = host.records[name]
        assert record.error is None, record.error
        assert record.builtin
    reg = host.registry
    assert reg.entries("shear_laws")["friction_compaction"].plugin == "woven"
    assert reg.entries("architectures")["woven"].plugin == "woven"
    assert reg.entries("surfaces")["hemisphere"].plugin == "surfaces"
    assert reg.entries("steps")["drape"].plugin == "core"
    assert reg.entries("exporters")["shear_curve_json"].plugin == "core"
    assert "intruder_own_law" not in reg.names("shear_laws")
    assert "intruder_own_fabric" not in reg.names("architectures")


# -- 1. built-in names win ------------------------------------------------------------------------


@pytest.mark.parametrize("plugin_name", ["aaa", "zzz"])
@pytest.mark.parametrize("case", sorted(TAKEOVERS))
def test_a_plugin_cannot_take_over_a_builtin_name(site, case, plugin_name):
    site.install(plugin_name, _takeover_source(case))
    host = discover()
    _assert_builtins_intact(host)
    _, thing, name, owner = TAKEOVERS[case]
    record = host.records[plugin_name]
    held = f"built-in plugin {owner!r} (preform's own names cannot be taken over)"
    if thing == "product":
        expected = (
            f"step 'intruder_step': product {name!r} is already provided by step {name!r} of {held}"
        )
    else:
        expected = f"{thing} {name!r} is already registered by {held}"
    assert record.error == "registration failed: " + expected
    assert record.registered == {}
    assert not record.builtin
    # the rolled-back plugin's hooks are gone too
    assert plugin_name not in {n for n, _ in host.pm.list_name_plugin()}


def test_builtins_load_first_whatever_the_names(site):
    site.install("aaa", _takeover_source("woven"))
    site.install("zzz", "")
    order = list(discover().records)
    assert order[:4] == ["core", "surfaces", "warpknit", "woven"]
    assert order[4:] == ["aaa", "zzz"]


@pytest.mark.parametrize("case", ["friction_compaction", "woven"])
def test_builtin_still_used_by_the_cli_after_a_takeover_attempt(site, case):
    site.install("aaa", _takeover_source(case))
    run = invoke(["shear", "plain-weave-600"])
    assert_contained(run)
    assert run.exit_code == 0, run.stdout + run.stderr
    assert "INTRUDER" not in run.stdout + run.stderr
    assert "60.00" in run.stdout  # the built-in law's table reached 60 degrees
    listing = {p["name"]: p for p in invoke(["plugins", "list", "--json"]).json()}
    assert listing["woven"]["error"] is None
    assert "friction_compaction" in listing["woven"]["registered"]["shear_laws"]
    assert "built-in plugin 'woven'" in listing["aaa"]["error"]


def test_library_uses_the_builtin_law_after_a_takeover_attempt(site):
    from preform.library import load_library

    site.install("aaa", _takeover_source("friction_compaction"))
    host = discover()
    lib = load_library(registry=host.registry, env=False)
    law = lib.shear_law("plain-weave-600")
    assert type(law).__module__.startswith("preform.plugins.woven")


def test_second_of_two_third_party_plugins_fails_naming_the_first(site):
    source = """
from typing import Literal
from pydantic import BaseModel
from preform import hookimpl

class Params(BaseModel):
    law: Literal["shared_law"]

def build(params, fabric):
    return None

@hookimpl
def preform_register_shear_laws(register):
    register.add("shared_law", Params, build)
"""
    site.install("first", source)
    site.install("second", source)
    host = discover()
    assert host.records["first"].error is None
    assert host.records["first"].registered == {"shear_laws": ["shared_law"]}
    err = host.records["second"].error
    assert "shear law 'shared_law' is already registered by plugin 'first', loaded earlier" in err
    assert host.registry.entries("shear_laws")["shared_law"].plugin == "first"


def test_a_plugin_registered_before_the_builtin_is_displaced(preform_plugins, site):
    """Built-in names win in whatever order code adds plugins (e.g. a test sandbox)."""
    module = site.install("evil", _takeover_source("friction_compaction"))
    evil = importlib.import_module(module)
    record = preform_plugins.register(evil, "evil")
    assert record.error is None  # nobody held the name yet
    preform_plugins.load_builtins("woven")
    woven = preform_plugins.host.records["woven"]
    assert woven.error is None
    assert "friction_compaction" in woven.registered["shear_laws"]
    assert "shear law 'friction_compaction' belongs to built-in plugin 'woven'" in record.error
    assert record.registered == {}
    assert "intruder_own_law" not in preform_plugins.registry.names("shear_laws")


def test_an_entry_point_named_like_another_third_party_one_is_refused(site):
    site.install("toy", "", module="hp_toy_one", dist="preform-toy-one")
    site.install(
        "toy",
        "raise SystemExit('must not be imported')",
        module="hp_toy_two",
        dist="preform-toy-two",
    )
    host = discover()
    assert host.records["toy"].error is None
    assert host.records["toy"].distribution == "preform-toy-one"
    assert host.records["toy (preform-toy-two)"].error == (
        "not loaded: the plugin name 'toy' is already taken by plugin 'toy' (preform-toy-one); "
        "rename the entry point"
    )


def test_an_entry_point_named_like_a_builtin_is_refused(site):
    site.install("woven", _takeover_source("woven"), module="hp_fake_woven", dist="preform-evil")
    host = discover()
    _assert_builtins_intact(host)
    assert host.records["woven"].module == "preform.plugins.woven"
    refused = host.records["woven (preform-evil)"]
    assert "plugin name 'woven' is already taken by built-in plugin 'woven'" in refused.error
    assert "hp_fake_woven" not in sys.modules  # never imported


# -- 2. exceptions from plugin code are contained -------------------------------------------------

RAISERS = {
    "SystemExit(0)": ("raise SystemExit(0)", "SystemExit: 0"),
    "SystemExit(2)": ("raise SystemExit(2)", "SystemExit: 2"),
    "sys.exit(msg)": ("import sys; sys.exit('bye from plugin')", "SystemExit: bye from plugin"),
    "GeneratorExit": ("raise GeneratorExit('odd')", "GeneratorExit: odd"),
    "BaseException": ("raise BaseException('base')", "BaseException: base"),
    "RecursionError": ("def f(): return f()\nf()", "RecursionError"),
    "MemoryError": ("raise MemoryError('pretend')", "MemoryError: pretend"),
}


@pytest.mark.parametrize("raiser", sorted(RAISERS))
def test_import_raising_is_recorded_and_every_command_works(site, raiser):
    statement, reason = RAISERS[raiser]
    site.install("aaa", statement + "\n")
    run = invoke(["plugins", "list", "--json"])
    assert_contained(run)
    assert run.exit_code == 0, run.stdout + run.stderr
    listing = {p["name"]: p for p in run.json()}
    assert listing["aaa"]["error"].startswith("failed to import: " + reason)
    assert all(listing[b]["error"] is None for b in ("core", "woven", "warpknit", "surfaces"))
    shear = invoke(["shear", "plain-weave-600"])
    assert_contained(shear)
    assert shear.exit_code == 0


def test_keyboard_interrupt_at_import_propagates(site):
    """Ctrl-C (or a plugin raising KeyboardInterrupt) must still stop the program: only it is
    not contained."""
    site.install("aaa", "raise KeyboardInterrupt\n")
    with pytest.raises(KeyboardInterrupt):
        discover()


def test_keyboard_interrupt_at_import_ends_the_cli_without_traceback(site, tmp_path):
    site.install("aaa", "raise KeyboardInterrupt\n")
    proc = run_preform(["plugins", "list", "--json"], cwd=tmp_path)
    assert proc.returncode == 130
    assert proc.stdout == ""
    assert "Aborted!" in proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("raiser", ["SystemExit(2)", "RecursionError", "GeneratorExit"])
def test_registration_hook_raising_halfway_is_rolled_back(site, raiser):
    statement, reason = RAISERS[raiser]
    body = "\n".join("    " + line for line in statement.splitlines())
    site.install(
        "halfway",
        f"""
from typing import Literal
from preform import FabricBase, hookimpl

class Half(FabricBase):
    architecture: Literal["half"]

@hookimpl
def preform_register_architectures(register):
    register.add(Half)

@hookimpl
def preform_register_shear_laws(register):
{body}

@hookimpl
def preform_check_material(material):
    raise AssertionError("an unloaded plugin's hook was called")
""",
    )
    host = discover()
    record = host.records["halfway"]
    assert record.error.startswith("registration failed: " + reason)
    assert "half" not in host.registry.names("architectures")
    assert record.registered == {}
    _assert_builtins_intact(host)
    run = invoke(["materials", "list"])
    assert_contained(run)
    assert run.exit_code == 0
    assert "an unloaded plugin's hook was called" not in run.stderr


def test_hostile_plugin_object_is_contained_when_registered(preform_plugins):
    from preform import hookimpl

    class Hostile:
        __hash__ = object.__hash__

        def __eq__(self, other):  # pluggy compares a new plugin with the registered ones
            raise SystemExit(4)

        @hookimpl
        def preform_register_steps(self, register):
            raise AssertionError("never reached")

    preform_plugins.load_builtins("core")
    record = preform_plugins.register(Hostile(), "hostile")
    assert record.error == "invalid plugin: SystemExit: 4"
    assert "hostile" not in {n for n, _ in preform_plugins.host.pm.list_name_plugin()}
    assert preform_plugins.host.records["core"].error is None


def test_hook_wrappers_are_refused(site):
    site.install(
        "wrapper",
        """
from preform import hookimpl

@hookimpl(hookwrapper=True)
def preform_check_material(material):
    yield
""",
    )
    host = discover()
    assert host.records["wrapper"].error.startswith(
        "hook wrappers are not supported: preform_check_material"
    )


def test_worker_hosts_contain_plugins_too(site):
    """Workers build their host with discover() and add_modules(): same containment."""
    module = site.install("aaa", "raise SystemExit(9)\n")
    host = discover()
    host.add_modules([("by-module", module)])
    assert host.records["aaa"].error == "failed to import: SystemExit: 9"
    assert host.records["by-module"].error == "failed to import: SystemExit: 9"
    assert host.records["woven"].error is None


# -- 3. preform_check_material: every call contained, every result checked -----------------------

LINTS = {
    "raises ValueError": (
        "raise ValueError('lint exploded')",
        "failed on fabric {f!r}: ValueError: lint exploded",
    ),
    "raises SystemExit": ("raise SystemExit(3)", "failed on fabric {f!r}: SystemExit: 3"),
    "raises RecursionError": (
        "return preform_check_material(material)",
        "failed on fabric {f!r}: RecursionError: maximum recursion depth exceeded",
    ),
    "raises MemoryError": ("raise MemoryError", "failed on fabric {f!r}: MemoryError"),
    "raises KeyError": ("return {}['missing']", "failed on fabric {f!r}: KeyError: 'missing'"),
    "returns an int": ("return 42", "returned int, expected None or a list on fabric {f!r}"),
    "returns a dict": (
        "return {'width': 'bad'}",
        "returned dict, expected None or a list on fabric {f!r}",
    ),
    "returns a str": (
        "return 'just a string'",
        "returned str, expected None or a list on fabric {f!r}",
    ),
    "returns a generator": (
        "return (m for m in ['x'])",
        "returned generator, expected None or a list on fabric {f!r}",
    ),
    "returns a list of ints": (
        "return [1, 2]",
        "returned 2 item(s) that are neither a message (str) nor a (path, message) pair: int on fabric {f!r}",
    ),
    "returns a bad pair": (
        "return [(('width',), 5)]",
        "returned 1 item(s) that are neither a message (str) nor a (path, message) pair: tuple on fabric {f!r}",
    ),
    "returns a 1-tuple": (
        "return [('only path',)]",
        "returned 1 item(s) that are neither a message (str) nor a (path, message) pair: tuple on fabric {f!r}",
    ),
}


def _lint_plugin(body: str) -> str:
    return f"""
from preform import hookimpl

@hookimpl
def preform_check_material(material):
    {body}
"""


@pytest.mark.parametrize("lint", sorted(LINTS))
def test_check_material_failures_become_attributed_warnings(site, lint):
    body, expected = LINTS[lint]
    site.install("badlint", _lint_plugin(body))
    site.install("goodlint", GOOD_LINT)
    run = invoke(["materials", "list"])
    assert_contained(run)
    assert run.exit_code == 0, run.stdout + run.stderr
    assert "plain-weave-600" in run.stdout
    message = "plugin badlint: check_material hook " + expected.format(f="plain-weave-600")
    assert f"woven.yaml:4:9: plain-weave-600: {message}\n" in run.stderr, run.stderr
    # the other plugin's lint ran on the same fabric
    assert "woven.yaml:4:9: plain-weave-600: name: good plugin saw plain-weave-600" in run.stderr


@pytest.mark.parametrize("lint", ["raises ValueError", "raises SystemExit", "returns an int"])
def test_check_material_failure_does_not_break_json_validate_or_explain(site, lint, tmp_path):
    body, _ = LINTS[lint]
    site.install("badlint", _lint_plugin(body))
    listing = invoke(["materials", "list", "--json"])
    assert_contained(listing)
    assert listing.exit_code == 0
    assert {row["name"] for row in listing.json()} >= {"plain-weave-600", "E-BX-318"}
    from preform.library import bundled_library_dir

    validate = invoke(["materials", "validate", str(bundled_library_dir())])
    assert_contained(validate)
    assert validate.exit_code == 0
    assert validate.stdout.startswith("ok: 10 fabric(s) valid")
    assert "plugin badlint: check_material hook" in validate.stderr
    explain = invoke(["pipeline", "run", "--explain", "--materials", "plain-weave-150"])
    assert_contained(explain)
    assert explain.exit_code == 0, explain.stdout + explain.stderr


@pytest.mark.parametrize("engine", ["serial", "process"])
def test_pipeline_run_survives_hostile_plugins(site, tmp_path, engine):
    """A run (and its worker processes, which discover plugins themselves) goes through a lint
    that exits, an import that exits and a takeover attempt, with the built-in law."""
    site.install("aaa", _takeover_source("friction_compaction"))
    site.install("exits", "raise SystemExit(1)\n")
    site.install("badlint", _lint_plugin("raise SystemExit(3)"))
    out = tmp_path / "out"
    args = ["pipeline", "run", "--engine", engine, "--scene", "shear"]
    run = invoke([*args, "--materials", "plain-weave-150", "--out", str(out)])
    assert_contained(run)
    assert run.exit_code == 0, run.stdout + run.stderr
    assert "INTRUDER" not in run.stdout + run.stderr
    (summary,) = out.rglob("summary.json")
    assert json.loads(summary.read_text())["status"] == "ok"


def test_check_material_failure_is_recorded_on_the_plugin(site):
    from preform.library import load_library

    site.install("badlint", _lint_plugin("raise ValueError('nope')"))
    host = discover()
    lib = load_library(registry=host.registry, env=False)
    assert len(lib) == 10
    problems = host.records["badlint"].problems
    assert problems[0] == (
        "plugin badlint: check_material hook failed on fabric 'E-BXhd-936': ValueError: nope"
    )
    assert len(problems) == 10  # one per fabric
    assert host.records["badlint"].error is None  # still loaded: only its lint failed
    assert any(w.message == problems[0] for w in lib.warnings)


def test_check_material_valid_results_still_reported(site):
    site.install(
        "lint",
        _lint_plugin("return ['plain message', ('width_mm', 'by key'), (('a', 0, 'b'), 'deep')]"),
    )
    host = discover()
    from preform.library import load_library

    lib = load_library(registry=host.registry, env=False)
    mine = [w.message for w in lib.warnings if w.path == "plain-weave-600"]
    assert mine == ["plain message", "width_mm: by key", "a[0].b: deep"]
    assert host.records["lint"].problems == []


# -- 4. stdout stays clean --------------------------------------------------------------------------

PRINTERS = {
    "at import": "print('NOISE from plugin import')\n",
    "in a registration hook": """
from preform import hookimpl

@hookimpl
def preform_register_steps(register):
    print('NOISE from plugin registration')
""",
    "in check_material": """
from preform import hookimpl

@hookimpl
def preform_check_material(material):
    print('NOISE from plugin lint')
""",
    "in register_commands": """
from preform import hookimpl

@hookimpl
def preform_register_commands(cli):
    print('NOISE from plugin commands')
""",
    "to sys.__stdout__ at import": "import sys\nprint('NOISE raw', file=sys.__stdout__)\n",
}

JSON_COMMANDS = {
    "plugins list": ["plugins", "list", "--json"],
    "materials list": ["materials", "list", "--json"],
    "materials show": ["materials", "show", "plain-weave-600", "--json"],
    "schema": ["schema"],
    "schema --scene": ["schema", "--scene"],
}


@pytest.mark.parametrize(
    ("where", "command"),
    [
        (where, command)
        for where in sorted(PRINTERS)
        for command in sorted(JSON_COMMANDS)
        # only commands that load the library call check_material
        if where != "in check_material" or command.startswith("materials")
    ],
)
def test_plugin_output_never_reaches_json_stdout(site, capfd, where, command):
    site.install("noisy", PRINTERS[where])
    run = invoke(JSON_COMMANDS[command])
    assert_contained(run)
    assert run.exit_code == 0, run.stdout + run.stderr
    json.loads(run.stdout)  # stdout is exactly one JSON document
    assert "NOISE" not in run.stdout
    captured = capfd.readouterr()  # and nothing reached the process's real stdout
    assert "NOISE" not in captured.out
    assert "plugin noisy: NOISE" in run.stderr + captured.err


def test_os_write_to_fd1_at_import_goes_to_stderr(site, capfd):
    site.install("rawnoisy", "import os\nos.write(1, b'RAW NOISE\\n')\n")
    run = invoke(["plugins", "list", "--json"])
    assert run.exit_code == 0
    json.loads(run.stdout)
    captured = capfd.readouterr()
    assert "RAW NOISE" not in captured.out
    assert "plugin rawnoisy: RAW NOISE" in run.stderr


@pytest.mark.parametrize(
    "args", [["plugins", "list", "--json"], ["schema"], ["materials", "list", "--json"]]
)
def test_stdout_is_clean_json_in_a_real_process(site, tmp_path, args):
    site.install("noisy", "import os, sys\nprint('PY NOISE')\nos.write(1, b'FD NOISE\\n')\n")
    site.install("exits", "raise SystemExit(1)\n")
    site.install("badlint", _lint_plugin("print('LINT NOISE'); raise ValueError('x')"))
    proc = run_preform(args, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    document = json.loads(proc.stdout)
    assert document
    assert "NOISE" not in proc.stdout
    assert "plugin noisy: PY NOISE" in proc.stderr
    assert "plugin noisy: FD NOISE" in proc.stderr
    assert "Traceback" not in proc.stderr


# -- 5. preform_register_commands --------------------------------------------------------------------

COMMAND_PLUGINS = {
    "raises ValueError": (
        "raise ValueError('no commands today')",
        "register_commands failed: ValueError: no commands today",
    ),
    "raises SystemExit": ("raise SystemExit(5)", "register_commands failed: SystemExit: 5"),
    "adds one then raises": (
        "cli.add_command(click.Command('half-added', callback=lambda: None))\n"
        "    raise RuntimeError('halfway')",
        "register_commands failed: RuntimeError: halfway",
    ),
    "replaces a built-in command": (
        "cli.add_command(click.Command('materials', callback=lambda: print('HIJACKED')))",
        "register_commands failed: command 'materials' is already provided by preform itself",
    ),
}


@pytest.mark.parametrize("case", sorted(COMMAND_PLUGINS))
def test_register_commands_failures_are_contained(site, case):
    body, error = COMMAND_PLUGINS[case]
    site.install(
        "cmds",
        f"""
import click
from typing import Literal
from preform import FabricBase, hookimpl

class CmdFabric(FabricBase):
    architecture: Literal["cmd_fabric"]

@hookimpl
def preform_register_architectures(register):
    register.add(CmdFabric)

@hookimpl
def preform_register_commands(cli):
    {body}
""",
    )
    run = invoke(["plugins", "list", "--json"])
    assert_contained(run)
    assert run.exit_code == 0
    listing = {p["name"]: p for p in run.json()}
    assert listing["cmds"]["error"] == error
    assert listing["cmds"]["registered"] == {}  # unloaded as a whole
    materials = invoke(["materials", "list"])
    assert materials.exit_code == 0
    assert "HIJACKED" not in materials.stdout
    assert "plain-weave-600" in materials.stdout
    assert invoke(["half-added"]).exit_code == 2  # no such command


def test_two_plugins_adding_the_same_command(site):
    source = """
import click
from preform import hookimpl

@hookimpl
def preform_register_commands(cli):
    @cli.command("hello")
    def hello():
        click.echo("hello from {who}")
"""
    site.install("first", source.replace("{who}", "first"))
    site.install("second", source.replace("{who}", "second"))
    run = invoke(["hello"])
    assert run.exit_code == 0
    assert run.stdout == "hello from first\n"
    listing = {p["name"]: p for p in invoke(["plugins", "list", "--json"]).json()}
    assert listing["first"]["error"] is None
    assert listing["second"]["error"] == (
        "register_commands failed: command 'hello' is already provided by plugin 'first', "
        "loaded earlier"
    )


def test_build_cli_twice_does_not_stack_plugin_commands(site):
    from preform.cli import build_cli, cli

    site.install(
        "greeter",
        """
import click
from preform import hookimpl

@hookimpl
def preform_register_commands(cli):
    cli.add_command(click.Command("greet", callback=lambda: click.echo("hi")))
""",
    )
    assert "greet" in build_cli().commands
    assert "greet" not in cli.commands  # the module's group holds preform's own commands only
    assert invoke(["greet"]).stdout == "hi\n"  # a second build: no conflict with itself
    listing = {p["name"]: p for p in invoke(["plugins", "list", "--json"]).json()}
    assert listing["greeter"]["error"] is None


# -- 6. the listing -------------------------------------------------------------------------------------


def test_plugins_list_text_shows_each_failure_with_its_reason(site):
    site.install("aaa", _takeover_source("hemisphere"))
    site.install("exits", "raise SystemExit('[bold]markup[/bold] in a message')\n")
    run = invoke(["plugins", "list"])
    assert_contained(run)
    assert run.exit_code == 0
    text = " ".join(run.stdout.split())  # the table wraps long cells
    flat = text.replace("│", "").replace(" ", "")
    assert "surface'hemisphere'isalreadyregisteredbybuilt-inplugin'surfaces'" in flat
    assert "failedtoimport:SystemExit:[bold]markup[/bold]inamessage" in flat
    assert "woven(built-in)" in flat


# -- an architecture's own code (checks, derived properties) is contained too ---------------

ODD_ARCHITECTURE = """
from typing import Literal
from preform import FabricBase, hookimpl


class Odd(FabricBase):
    architecture: Literal["odd"]
    behaviour: str = "quiet"

    def check(self):
        if self.behaviour == "exit-in-check":
            raise SystemExit(5)
        if self.behaviour == "print-in-check":
            print("odd: checking")
        return []

    def derived(self):
        print("odd: deriving")
        if self.behaviour == "exit-in-derived":
            raise SystemExit(6)
        return {"answer": 42}


@hookimpl
def preform_register_architectures(register):
    register.add(Odd)
"""


@pytest.mark.parametrize(
    "behaviour", ["exit-in-check", "print-in-check", "exit-in-derived", "quiet"]
)
def test_an_architectures_own_code_cannot_end_the_command_or_corrupt_json(
    site, tmp_path, behaviour
):
    site.install("odd", ODD_ARCHITECTURE)
    lib = tmp_path / "odd.yaml"
    lib.write_text(
        f"- {{name: odd-1, architecture: odd, source: s, note: n, behaviour: {behaviour}}}\n"
    )
    validate = invoke(["materials", "validate", str(lib)])
    assert_contained(validate)
    if behaviour == "exit-in-check":
        assert validate.exit_code == 1
        assert "odd.yaml:1:3: odd-1: architecture 'odd' failed to check this entry: " in (
            validate.stderr
        )
        assert "SystemExit(5)" in validate.stderr
        return
    assert validate.exit_code == 0, validate.stdout + validate.stderr
    shown = invoke(["materials", "show", "odd-1", "--library", str(lib), "--json"])
    assert_contained(shown)
    assert shown.exit_code == 0
    doc = shown.json()  # stdout is nothing but the JSON document
    assert "plugin architecture odd: odd: deriving" in shown.stderr
    if behaviour == "exit-in-derived":
        assert doc["derived"] == {"error": "SystemExit: 6"}
    else:
        assert doc["derived"] == {"answer": 42}
