"""Plugin loading: per-plugin failure records, selection by environment, the CLI listing."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from preform.plugin_manager import PluginHost, reset_default_host


@pytest.fixture
def host(third_party_site, monkeypatch):
    monkeypatch.delenv("PREFORM_LOAD_PLUGINS", raising=False)
    monkeypatch.delenv("PREFORM_DISABLE_PLUGINS", raising=False)
    h = PluginHost()
    h.discover()
    return h


def test_broken_plugins_are_recorded_and_the_rest_work(host):
    records = host.records
    assert records["broken"].error.startswith("failed to import: ImportError")
    assert records["broken"].distribution == "preform-broken"
    assert records["broken"].version == "0.1"
    assert "preform_register_stepz" in records["typo"].error
    assert "misspelled" in records["typo"].error
    assert "registration failed" in records["badreg"].error
    assert "not a subclass of preform.FabricBase" in records["badreg"].error
    # the working third-party plugin and the built-ins are all there
    assert records["toy"].error is None
    assert records["toy"].version == "1.2.3"
    assert records["toy"].registered["architectures"] == ["toy"]
    assert records["core"].error is None
    assert "toy" in host.registry.names("architectures")
    assert "mass" in host.registry.names("steps")


def test_failed_registration_leaves_nothing_behind(third_party_site):
    from preform import hookimpl
    from preform.step import Step

    def run(ctx):
        return {"a": 1}

    class HalfBroken:
        @hookimpl
        def preform_register_steps(self, register):
            register.add(Step("good_step", ("good",), (), "1", run))
            register.add(Step("bad_step", (), (), "1", run))  # provides nothing: invalid

    h = PluginHost()
    rec = h.add(HalfBroken(), "halfbroken")
    assert "provides nothing" in rec.error
    assert "good_step" not in h.registry.names("steps")


def test_environment_selects_plugins(third_party_site, monkeypatch):
    monkeypatch.setenv("PREFORM_LOAD_PLUGINS", "core, toy")
    h = PluginHost()
    h.discover()
    assert sorted(h.records) == ["core", "toy"]
    monkeypatch.setenv("PREFORM_LOAD_PLUGINS", "")
    h = PluginHost()
    h.discover()
    assert h.records == {}
    monkeypatch.delenv("PREFORM_LOAD_PLUGINS")
    monkeypatch.setenv("PREFORM_DISABLE_PLUGINS", "broken,typo,badreg")
    h = PluginHost()
    h.discover()
    assert {"broken", "typo", "badreg"}.isdisjoint(h.records)
    assert all(r.error is None for r in h.records.values())


def test_duplicate_registration_is_attributed(third_party_site):
    import toyplug

    from preform import hookimpl

    class Copycat:
        @hookimpl
        def preform_register_architectures(self, register):
            register.add(toyplug.ToyFabric)

    h = PluginHost()
    h.add(toyplug, "toy")
    rec = h.add(Copycat(), "copycat")
    assert rec.error == (
        "registration failed: architecture 'toy' is already registered by plugin 'toy', "
        "loaded earlier"
    )


def test_plugins_list_json(host):
    from preform.cli import cli

    reset_default_host(host)
    try:
        result = CliRunner().invoke(cli, ["plugins", "list", "--json"])
    finally:
        reset_default_host(None)
    assert result.exit_code == 0, result.output
    listing = {p["name"]: p for p in json.loads(result.output)}
    assert listing["toy"]["registered"]["steps"] == ["crash", "heavy", "mass"]
    assert listing["toy"]["error"] is None
    assert listing["broken"]["error"] and listing["broken"]["registered"] == {}
    for p in listing.values():
        assert {"name", "version", "registered", "error", "builtin", "problems"} <= set(p)
    assert listing["core"]["builtin"] is True
    assert listing["toy"]["builtin"] is False
    assert listing["toy"]["problems"] == []


def test_testing_fixture_blocks_discovery(preform_plugins, third_party_site):
    from preform.plugin_manager import default_host

    assert default_host() is preform_plugins.host
    assert preform_plugins.registry.names("architectures") == []
    import toyplug

    preform_plugins.register(toyplug, "toy")
    assert preform_plugins.registry.names("architectures") == ["toy"]


def test_plugins_add_commands_and_a_failing_one_is_recorded():
    import click

    from preform import hookimpl

    class Greeter:
        @hookimpl
        def preform_register_commands(self, cli):
            @cli.command("hello")
            def hello() -> None:
                click.echo("hello from a plugin")

    class Broken:
        @hookimpl
        def preform_register_commands(self, cli):
            raise RuntimeError("no commands today")

    host = PluginHost()
    host.add(Greeter(), "greeter")
    host.add(Broken(), "broken-commands")
    group = click.Group("preform")
    host.register_commands(group)
    assert CliRunner().invoke(group, ["hello"]).output == "hello from a plugin\n"
    assert "no commands today" in host.records["broken-commands"].error
    assert host.records["greeter"].error is None


@pytest.mark.parametrize(
    ("kind", "message"),
    [
        ("not-a-model", "params must be a pydantic model"),
        ("wrong-tag", "params.law is Literal"),
        ("bad-build", "build must accept 2 arguments"),
    ],
)
def test_invalid_shear_law_registrations_are_refused(kind, message):
    from typing import Literal

    from pydantic import BaseModel, create_model

    from preform import hookimpl

    tag = "other" if kind == "wrong-tag" else "mine"
    params_model = create_model("Params", __base__=BaseModel, law=(Literal[tag], ...))

    def build(params, fabric):
        return None

    def bad_build(params):
        return None

    class Plugin:
        @hookimpl
        def preform_register_shear_laws(self, register):
            params = dict if kind == "not-a-model" else params_model
            register.add("mine", params, bad_build if kind == "bad-build" else build)

    host = PluginHost()
    record = host.add(Plugin(), "lawful")
    assert message in record.error
    assert "mine" not in host.registry.names("shear_laws")
