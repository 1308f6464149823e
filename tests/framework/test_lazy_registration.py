"""Lazy registration: entries registered by import path load on first use, checked as ``add``
checks, and a bad one fails with a message naming its plugin, entry and import path.

The built-in plugins register every step, exporter, shear law, surface and architecture this
way; the first test loads each one and compares it with the modules' own lists (a second
listing, written independently of ``preform.builtin``).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from preform import hookimpl
from preform.pipeline.planner import PlanError, plan
from preform.plugin_manager import PluginHost
from preform.registry import LazyLoadError, Registry, StepRegistrar
from preform.step import Step


@pytest.fixture
def builtin_host(monkeypatch):
    monkeypatch.setenv("PREFORM_LOAD_PLUGINS", "core,woven,warpknit,surfaces")
    monkeypatch.delenv("PREFORM_DISABLE_PLUGINS", raising=False)
    host = PluginHost()
    host.discover()
    return host


def test_every_builtin_lazy_entry_loads_and_is_what_it_declares(builtin_host):
    from preform.drape import preform_steps
    from preform.drape import steps as drape_steps
    from preform.export import drape_outputs, export_steps
    from preform.optimise import search_steps
    from preform.pipeline import core_steps
    from preform.plugins.surfaces.tools import SURFACES
    from preform.plugins.warpknit.shear import SHEAR_LAWS as STITCH_POLYNOMIAL
    from preform.plugins.warpknit.stitch_law import SHEAR_LAWS as STITCH_YARN
    from preform.plugins.woven.shear import SHEAR_LAWS as WOVEN_LAWS
    from preform.shear.laws import SHEAR_LAWS as CORE_LAWS
    from preform.stack import steps as stack_steps

    registry = builtin_host.registry
    assert all(r.error is None and not r.problems for r in builtin_host.records.values())
    modules = (
        core_steps,
        drape_steps,
        drape_outputs,
        preform_steps,
        search_steps,
        export_steps,
        stack_steps,
    )
    for kind, listing in (("steps", "STEPS"), ("exporters", "EXPORTERS")):
        expected = {s.name: s for m in modules for s in getattr(m, listing, ())}
        assert registry.names(kind) == sorted(expected)
        for name, step in expected.items():
            assert not registry.is_loaded(kind, name)
            assert registry.step(name) is step  # the very object of the module's list
            assert registry.is_loaded(kind, name)
    laws = {n: (p, b) for n, p, b in [*CORE_LAWS, *WOVEN_LAWS, *STITCH_POLYNOMIAL, *STITCH_YARN]}
    assert registry.names("shear_laws") == sorted(laws)
    for name, (params, build) in laws.items():
        law = registry.shear_law_type(name)
        assert (law.name, law.params, law.build) == (name, params, build)
    surfaces = {n: (p, b) for n, p, b in SURFACES}
    assert registry.names("surfaces") == sorted(surfaces)
    for name, (params, build) in surfaces.items():
        surface = registry.surface_type(name)
        assert (surface.name, surface.params, surface.build) == (name, params, build)
    from preform.plugins.warpknit.model import WarpKnitFabric
    from preform.plugins.woven.model import WovenFabric

    assert registry.architecture("woven") is WovenFabric
    assert registry.architecture("warp_knit") is WarpKnitFabric
    assert all(not r.problems for r in builtin_host.records.values())


def test_starting_the_host_imports_no_registered_module():
    """In a fresh interpreter: discovery and listing import none of the lazy targets."""
    code = textwrap.dedent(
        """
        import json, sys
        from preform.plugin_manager import default_host
        host = default_host()
        names = {k: host.registry.names(k) for k in host.registry.KINDS}
        assert names["steps"] and names["shear_laws"] and names["architectures"]
        print(json.dumps(sorted(m for m in sys.modules if m.startswith((
            "preform.drape", "preform.optimise", "preform.export", "preform.pipeline.core",
            "preform.shear.laws", "preform.plugins.surfaces.tools", "preform.plugins.woven.",
            "preform.plugins.warpknit.", "preform.material", "numpy", "pydantic")))))
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert done.stdout.strip().splitlines()[-1] == "[]"


LAZY_MODULE = '''
"""Steps of a third-party plugin, imported only when a plan needs one."""
from preform import Step

print("lazystuff imported")  # a plugin's output: kept off stdout, attributed


def run_weigh(ctx):
    return {"weight": 1.0}


def run_report(ctx):
    return {"report_txt": "x"}


WEIGH = Step("weigh", ("weight",), (), "1", run_weigh)
STEPS = [WEIGH, Step("other", ("other",), (), "1", run_weigh)]
LIAR = Step("liar", ("truth",), (), "1", run_weigh)
NOT_WRITING = Step("report", ("report_txt",), ("weight",), "1", run_report)
NOT_A_STEP = 42
'''


@pytest.fixture
def lazy_module(tmp_path, monkeypatch):
    (tmp_path / "lazystuff.py").write_text(LAZY_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield "lazystuff"
    sys.modules.pop("lazystuff", None)


class LazyPlugin:
    """Good and bad lazy entries side by side: only the bad ones fail, each when loaded."""

    @hookimpl
    def preform_register_steps(self, register):
        register.add_lazy("weigh", provides=["weight"], target="lazystuff:WEIGH")
        register.add_lazy("other", provides=("other",), target="lazystuff:STEPS")
        register.add_lazy("ghost", provides=["ghost"], target="nosuchmodule_xyz:STEP")
        register.add_lazy("liar", provides=["lies"], target="lazystuff:LIAR")
        register.add_lazy("misnamed", provides=["weighed"], target="lazystuff:WEIGH")
        register.add_lazy("number", provides=["number"], target="lazystuff:NOT_A_STEP")
        register.add_lazy("missing", provides=["missing"], target="lazystuff:NOPE")

    @hookimpl
    def preform_register_exporters(self, register):
        register.add_lazy("report", provides=["report_txt"], target="lazystuff:NOT_WRITING")

    @hookimpl
    def preform_register_shear_laws(self, register):
        register.add_lazy("wrong_law", params="lazystuff:WEIGH", build="lazystuff:run_weigh")


def test_lazy_entries_load_on_first_use_and_bad_ones_fail_attributed(lazy_module, capfd):
    host = PluginHost()
    record = host.add(LazyPlugin(), "lazyplug")
    registry = host.registry
    assert record.error is None
    assert record.registered["steps"] == [
        "ghost",
        "liar",
        "misnamed",
        "missing",
        "number",
        "other",
        "weigh",
    ]
    assert "lazystuff" not in sys.modules  # registering imported nothing
    assert registry.providers()["weight"] == "weigh"

    assert registry.step("weigh").provides == ("weight",)
    assert registry.step("other").name == "other"  # picked by name out of a list
    out, err = capfd.readouterr()
    assert "lazystuff imported" not in out
    assert "plugin lazyplug: lazystuff imported" in err

    expected = {
        "ghost": "from nosuchmodule_xyz:STEP: ModuleNotFoundError",
        "liar": "registered as providing ['lies'], but the step at lazystuff:LIAR provides "
        "['truth']",
        "misnamed": "the step at lazystuff:WEIGH is named 'weigh', not 'misnamed'",
        "number": "42 is not a preform.Step",
        "missing": "module 'lazystuff' has no attribute 'NOPE'",
        "report": "exporter 'report' must have writes_files=True",
    }
    for name, why in expected.items():
        with pytest.raises(LazyLoadError) as info:
            registry.step(name)
        message = str(info.value)
        kind = "exporter" if name == "report" else "step"
        assert message.startswith(f"plugin 'lazyplug': {kind} {name!r} could not be loaded from")
        assert why in message
        # asked again: the same failure, recorded once among the plugin's problems
        with pytest.raises(LazyLoadError, match="could not be loaded"):
            registry.step(name)
        assert record.problems.count(message) == 1
    with pytest.raises(LazyLoadError, match="params must be a pydantic model"):
        registry.shear_law_type("wrong_law")
    # the plugin stays loaded and its good entries keep working
    assert record.error is None
    assert registry.step("weigh").name == "weigh"


def test_a_plan_needing_a_broken_lazy_step_names_it(lazy_module):
    from preform.pipeline.scene import Scene

    host = PluginHost()
    host.add(LazyPlugin(), "lazyplug")
    assert [s.name for s in plan(Scene(name="s", outputs=["weight"]), host.registry)] == ["weigh"]
    with pytest.raises(PlanError) as info:
        plan(Scene(name="s", outputs=["weight", "ghost"]), host.registry)
    ((index, message),) = info.value.problems
    assert index == 1
    assert "plugin 'lazyplug': step 'ghost' could not be loaded from nosuchmodule_xyz:STEP" in (
        message
    )


@pytest.mark.parametrize(
    ("call", "error"),
    [
        (
            lambda r: r.add_lazy("s", provides=["p"], target="no colon"),
            "import path must be a string 'package.module:attribute', got 'no colon'",
        ),
        (
            lambda r: r.add_lazy("s", provides=["p"], target="pkg.mod:not-an-identifier"),
            "is not 'package.module:attribute'",
        ),
        (lambda r: r.add_lazy("s", provides=[], target="m:X"), "provides must be a non-empty"),
        (lambda r: r.add_lazy("s", provides="p", target="m:X"), "provides must be a non-empty"),
        (lambda r: r.add_lazy("", provides=["p"], target="m:X"), "name must be a non-empty"),
    ],
)
def test_a_malformed_lazy_entry_fails_its_plugin_at_registration(call, error):
    class Bad:
        @hookimpl
        def preform_register_steps(self, register):
            register.add_lazy("fine", provides=["fine"], target="m:FINE")
            call(register)

    host = PluginHost()
    record = host.add(Bad(), "bad")
    assert record.error is not None and error in record.error
    assert record.error.startswith("registration failed: ")
    assert host.registry.names("steps") == []  # nothing half-registered


def test_lazy_products_conflict_at_registration_like_ordinary_steps():
    def run(ctx):
        return {}

    registry = Registry()
    StepRegistrar(registry, "first", "1").add(Step("make", ("thing",), (), "1", run))
    with pytest.raises(Exception, match="product 'thing' is already provided by step 'make'"):
        StepRegistrar(registry, "second", "1").add_lazy("also", provides=["thing"], target="m:X")
    StepRegistrar(registry, "second", "1").add_lazy("lazy", provides=["other"], target="m:X")
    with pytest.raises(Exception, match="product 'other' is already provided by step 'lazy'"):
        StepRegistrar(registry, "third", "1").add(Step("eager", ("other",), (), "1", run))


def test_builtin_lazy_names_still_win_over_a_third_party_plugin(monkeypatch):
    monkeypatch.setenv("PREFORM_LOAD_PLUGINS", "core")

    class Intruder:
        @hookimpl
        def preform_register_steps(self, register):
            register.add_lazy("drape", provides=["my_drape"], target="m:X")

    host = PluginHost()
    host.discover()
    record = host.add(Intruder(), "intruder")
    assert "step 'drape' is already registered by built-in plugin 'core'" in record.error
    assert host.registry.entries("steps")["drape"].plugin == "core"


class BrokenModels:
    """A law, a surface and an architecture registered by import paths that do not load."""

    @hookimpl
    def preform_register_architectures(self, register):
        register.add_lazy("ghostweave", model="nosuchmodule_xyz:Fabric")

    @hookimpl
    def preform_register_shear_laws(self, register):
        register.add_lazy("ghost_law", params="nosuchmodule_xyz:P", build="nosuchmodule_xyz:b")

    @hookimpl
    def preform_register_surfaces(self, register):
        register.add_lazy("ghost_tool", params="nosuchmodule_xyz:P", build="nosuchmodule_xyz:b")


def test_a_law_surface_or_architecture_that_does_not_load_is_a_located_input_error(
    tmp_path, third_party_site
):
    import toyplug

    from preform.library import LibraryError, load_library
    from preform.pipeline.scene import SceneError, load_scene

    host = PluginHost()
    host.add(toyplug, "toy")
    host.add(BrokenModels(), "broken_models")
    lib = tmp_path / "lib.yaml"
    lib.write_text(
        "- {name: a, architecture: ghostweave, source: s, note: n}\n"
        "- name: b\n"
        "  architecture: toy\n"
        "  areal_density_g_m2: 100\n"
        "  shear_law: {law: ghost_law}\n"
    )
    with pytest.raises(LibraryError) as info:
        load_library([lib], bundled=False, registry=host.registry)
    errors = [str(e) for e in info.value.errors]
    assert errors[0].startswith(f"{lib}:1:")
    assert (
        "plugin 'broken_models': architecture 'ghostweave' could not be loaded from " in (errors[0])
    )
    assert any(
        e.startswith(f"{lib}:5:")
        and "shear_law.law" in e
        and "shear law 'ghost_law' could not be loaded from nosuchmodule_xyz:P" in e
        for e in errors
    )
    scene = tmp_path / "s.yaml"
    scene.write_text("name: s\ntool: {surface: ghost_tool}\noutputs: [nothing]\n")
    with pytest.raises(SceneError) as info:
        load_scene(scene, host.registry)
    assert any(
        str(e).startswith(f"{scene}:2:")
        and "plugin 'broken_models': surface 'ghost_tool' could not be loaded" in str(e)
        for e in info.value.errors
    )


def test_plugins_list_check_loads_every_entry_and_shows_what_does_not_load(lazy_module):
    import json

    from click.testing import CliRunner

    from preform.cli import cli
    from preform.plugin_manager import reset_default_host

    host = PluginHost()
    host.add(LazyPlugin(), "lazyplug")
    reset_default_host(host)
    try:
        plain = CliRunner().invoke(cli, ["plugins", "list", "--json"])
        assert "lazystuff" not in sys.modules  # listing alone imports nothing
        checked = CliRunner().invoke(cli, ["plugins", "list", "--json", "--check"])
    finally:
        reset_default_host(None)
    assert plain.exit_code == 0 and checked.exit_code == 0, checked.output
    assert json.loads(plain.stdout)[0]["problems"] == []
    (record,) = json.loads(checked.stdout)
    assert record["error"] is None
    failing = sorted(p.split("'")[3] for p in record["problems"])
    assert failing == ["ghost", "liar", "misnamed", "missing", "number", "report", "wrong_law"]
