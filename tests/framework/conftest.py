"""Fixtures: a toy third-party plugin distribution installed into a temporary directory."""

from __future__ import annotations

import importlib
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest

TOY_PLUGIN = '''
"""A third-party preform plugin, as a user would write one (used by the framework tests)."""
from typing import Literal
import os
from pathlib import Path

from pydantic import Field

import preform
from preform import FabricBase, Step, hookimpl


class ToyFabric(FabricBase):
    architecture: Literal["toy"]
    areal_density_g_m2: float = Field(gt=0, description="Areal density [g/m2].")
    width_mm: float = Field(default=1.0, gt=0, description="Width [mm].")

    def derived(self):
        return {"areal_density_g_m2": self.areal_density_g_m2}

    def errors(self):
        if self.width_mm > 100:
            return [(("width_mm",), "width_mm must not exceed 100 for a toy")]
        return []


def _count(name):
    log = os.environ.get("TOY_STEP_LOG")
    if log:
        with open(log, "a") as f:
            f.write(name + "\\n")


def run_mass(ctx):
    _count("mass")
    if ctx.fabric.name == "explodes":
        raise RuntimeError("this fabric always fails")
    ctx.summary["mass_g"] = ctx.fabric.areal_density_g_m2 * 2.0
    return {"mass": ctx.fabric.areal_density_g_m2 * 2.0}


def run_heavy(ctx):
    _count("heavy")
    return {"heavy": ctx.products["mass"] * 10}


def run_crash(ctx):
    _count("crash")
    if ctx.fabric.name == os.environ.get("TOY_CRASH_ON"):
        os._exit(3)  # simulate a power cut mid-run
    return {"crash": 1}


def write_mass_txt(ctx):
    _count("mass_txt")
    (ctx.case_dir / "mass.txt").write_text(str(ctx.products["mass"]))
    return {"mass_txt": "mass.txt"}


@hookimpl
def preform_register_architectures(register):
    register.add(ToyFabric)


@hookimpl
def preform_register_steps(register):
    register.add(Step("mass", ("mass",), (), "1", run_mass))
    register.add(Step("heavy", ("heavy",), ("mass",), "1", run_heavy))
    register.add(Step("crash", ("crash",), ("mass",), "1", run_crash))


@hookimpl
def preform_register_exporters(register):
    register.add(Step("mass_txt", ("mass_txt",), ("mass",), "1", write_mass_txt,
                      writes_files=True))


@hookimpl
def preform_check_material(material):
    if material.architecture == "toy" and material.areal_density_g_m2 > 5000:
        return [(("areal_density_g_m2",), "suspiciously heavy")]
    return []
'''

BROKEN_IMPORT = "raise ImportError('this plugin needs libfoo, which is not installed')\n"

MISSPELLED = """
from preform import hookimpl

@hookimpl
def preform_register_stepz(register):
    pass
"""

BAD_REGISTRATION = """
from preform import hookimpl

class NotAModel:
    pass

@hookimpl
def preform_register_architectures(register):
    register.add(NotAModel)
"""


def install_distribution(
    site: Path, dist: str, version: str, modules: dict[str, str], entry_points: dict[str, str]
) -> None:
    """Write modules plus a ``.dist-info`` with ``preform`` entry points into ``site``."""
    for module, source in modules.items():
        (site / f"{module}.py").write_text(textwrap.dedent(source))
    info = site / f"{dist.replace('-', '_')}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
    eps = "[preform]\n" + "".join(f"{k} = {v}\n" for k, v in entry_points.items())
    (info / "entry_points.txt").write_text(eps)


@pytest.fixture
def third_party_site(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A site directory holding the toy plugin and three broken ones, on sys.path and on the
    PYTHONPATH of worker processes."""
    site = tmp_path / "site"
    site.mkdir()
    install_distribution(site, "preform-toy", "1.2.3", {"toyplug": TOY_PLUGIN}, {"toy": "toyplug"})
    install_distribution(
        site, "preform-broken", "0.1", {"brokenplug": BROKEN_IMPORT}, {"broken": "brokenplug"}
    )
    install_distribution(
        site, "preform-typo", "0.2", {"typoplug": MISSPELLED}, {"typo": "typoplug"}
    )
    install_distribution(
        site, "preform-badreg", "0.3", {"badregplug": BAD_REGISTRATION}, {"badreg": "badregplug"}
    )
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.setenv("PYTHONPATH", str(site))
    importlib.invalidate_caches()
    for mod in ("toyplug", "brokenplug", "typoplug", "badregplug"):
        sys.modules.pop(mod, None)
    yield site
    for mod in ("toyplug", "brokenplug", "typoplug", "badregplug"):
        sys.modules.pop(mod, None)
