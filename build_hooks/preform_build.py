"""preform's build backend: setuptools', with the drape kernels compiled into the wheel.

Building a wheel (what ``pip install .`` does) runs ``python -m preform.commands.kernel_compile
--ship`` on the built tree, so the install compiles the kernels once and the package ships them
(``preform.base.kernel_cache.shipped_root``); the first run then loads them. The build needs
preform's own dependencies for that (the compile drapes a small case), so they are the wheel's
build requirements too. An editable install (``pip install -e .``) compiles at its first run
instead, as does a build with ``PREFORM_SHIP_KERNELS=0`` (a quicker throwaway build).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path
from typing import Any

from setuptools import build_meta as _setuptools
from setuptools.build_meta import *  # noqa: F403 (the PEP 517 hooks not overridden below)
from setuptools.command.build_py import build_py

#: The command that compiles into the built tree (by module path: run on that tree).
SHIP = ("-m", "preform.commands.kernel_compile", "--ship")


def shipping_kernels() -> bool:
    return os.environ.get("PREFORM_SHIP_KERNELS") != "0"


def get_requires_for_build_wheel(config_settings: Any = None) -> list[str]:
    requires = _setuptools.get_requires_for_build_wheel(config_settings)
    if not shipping_kernels():
        return requires
    project = tomllib.loads(Path("pyproject.toml").read_text())["project"]
    return [*requires, *project["dependencies"]]


class BuildWithKernels(build_py):
    """``build_py``, then the kernels compiled into what it built (not for editable installs)."""

    def run(self) -> None:
        super().run()
        if self.editable_mode or not shipping_kernels():
            return
        with tempfile.TemporaryDirectory(prefix="preform-build-") as tmp:
            # the built tree is not installed yet: its plugins' entry points, which the small
            # case's fabrics need, come from a metadata folder made for the compile
            info = Path(tmp) / f"preform-{self.distribution.get_version()}.dist-info"
            info.mkdir()
            (info / "METADATA").write_text(
                f"Metadata-Version: 2.1\nName: preform\nVersion: {self.distribution.get_version()}\n"
            )
            groups = self.distribution.entry_points or {}
            (info / "entry_points.txt").write_text(
                "".join(f"[{g}]\n" + "".join(f"{e}\n" for e in eps) for g, eps in groups.items())
            )
            # ahead of the build environment's own path (pip's isolated build finds its
            # packages, preform's dependencies among them, through PYTHONPATH)
            ours = [str(Path(self.build_lib).resolve()), tmp]
            path = os.pathsep.join([*ours, *filter(None, [os.environ.get("PYTHONPATH")])])
            env = {**os.environ, "PYTHONPATH": path}
            env.pop("PREFORM_KERNEL_CACHE", None)
            subprocess.run([sys.executable, *SHIP], env=env, check=True, cwd=tmp)
