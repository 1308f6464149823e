"""Compiled kernels are cached under a key of every source compiled into them
(``preform.base.kernel_cache``): an edit anywhere is a new key (numba alone checks only a
kernel's own file, so a changed constant of another module kept its old value in the machine
code), the same sources elsewhere (a reinstall) are the same key and compile nothing."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import os
import shutil
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from preform.base import kernel_cache
from preform.base.kernel_cache import (
    CACHE_ENV,
    compiled_in,
    declared_compiled_in,
    source_key,
    user_cache_root,
)

REPO = Path(__file__).resolve().parents[2]
KERNEL_FILES = sorted([*REPO.glob("core/**/*_kernels.py"), *REPO.glob("plugins/**/*_kernels.py")])


def write_package(root: Path, value: int = 1, kernel_extra: str = "") -> Path:
    """A package ``kpkg`` under ``root``: a kernel module compiling in a constant of
    ``kpkg.constants``, which compiles in one of ``kpkg.deep`` (two steps down)."""
    package = root / "kpkg"
    package.mkdir(parents=True, exist_ok=True)
    (package / "__init__.py").write_text("")
    (package / "deep.py").write_text("OFFSET = 0\n")
    (package / "constants.py").write_text(
        f'from kpkg.deep import OFFSET\nCOMPILED_IN = ("kpkg.deep",)\nVALUE = {value} + OFFSET\n'
    )
    (package / "kern.py").write_text(KERNEL + kernel_extra)
    return package


KERNEL = """
import numba
from kpkg.constants import VALUE
from preform.base.kernel_cache import cache_by_content

COMPILED_IN = ("kpkg.constants",)
cache_by_content(__name__)

@numba.njit(cache=True)
def value():
    return VALUE
"""

#: numba's compiles in a probe process, counted in ``compiles``.
COUNT = """
from numba.core import event
compiles = []

class Count(event.Listener):
    def on_start(self, ev):
        compiles.append(ev.data["dispatcher"].py_func.__name__)

    def on_end(self, ev):
        pass  # numba's Listener asks for both; a compile is counted at its start
"""

PROBE = (
    COUNT
    + """
with event.install_listener("numba:compile", Count()):
    import kpkg.kern as k
    print(k.value(), len(compiles))
"""
)


def run_kernel(root: Path, cache: Path, prefix: str = "") -> tuple[str, int]:
    """The kernel's value and how many functions numba compiled, in a fresh process (which
    runs ``prefix`` first)."""
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(root), *sys.path]),
        CACHE_ENV: str(cache),
    }
    env.pop("NUMBA_CACHE_DIR", None)
    done = subprocess.run(
        [sys.executable, "-c", prefix + PROBE], capture_output=True, text=True, env=env, check=True
    )
    value, compiles = done.stdout.split()
    return value, int(compiles)


def test_a_second_process_and_a_reinstall_load_the_kernel_compile_nothing(tmp_path):
    """The truth is numba's own count of compiles: 1 in the first process, 0 in a second
    one, and 0 for the same sources written anew elsewhere (a reinstall: new files, new
    modification times, another path)."""
    cache = tmp_path / "cache"
    first = tmp_path / "install-1"
    write_package(first)
    assert run_kernel(first, cache) == ("1", 1)
    indexes = list(cache.glob("kpkg.kern-*/kern.value-*.nbi"))
    assert len(indexes) == 1  # numba's index, in the content-keyed folder
    assert run_kernel(first, cache) == ("1", 0)
    time.sleep(0.01)
    second = tmp_path / "install-2"
    shutil.copytree(first / "kpkg", second / "kpkg", copy_function=shutil.copyfile)
    assert run_kernel(second, cache) == ("1", 0)
    assert list(cache.glob("kpkg.kern-*/kern.value-*.nbi")) == indexes


@pytest.mark.parametrize("edited", ["kern.py", "constants.py", "deep.py"])
def test_an_edited_source_compiled_in_is_a_new_key_and_runs_new_code(tmp_path, edited):
    """Editing the kernel's file, a module compiled into it, or one compiled into that one
    (followed through its COMPILED_IN) runs the new code; numba alone would have kept the
    cached value for the two other files."""
    cache = tmp_path / "cache"
    package = write_package(tmp_path)
    assert run_kernel(tmp_path, cache) == ("1", 1)
    path = package / edited
    text = path.read_text()
    path.write_text(
        {
            "kern.py": text.replace("return VALUE", "return VALUE + 10"),
            "constants.py": text.replace("VALUE = 1", "VALUE = 2"),
            "deep.py": "OFFSET = 5\n",
        }[edited]
    )
    old = path.stat().st_mtime - 100.0  # older than the cache: a modification time says nothing
    os.utime(path, (old, old))
    expected = {"kern.py": "11", "constants.py": "2", "deep.py": "6"}[edited]
    assert run_kernel(tmp_path, cache) == (expected, 1)
    assert len(list(cache.glob("kpkg.kern-*"))) == 2  # the old key's folder is left alone


def test_the_key_follows_sources_and_toolchain_not_file_times(tmp_path, monkeypatch):
    package = write_package(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    for name in ("kpkg", "kpkg.kern", "kpkg.constants", "kpkg.deep"):
        monkeypatch.delitem(sys.modules, name, raising=False)
    importlib.invalidate_caches()
    key = source_key("kpkg.kern")
    assert len(key) == 16 and int(key, 16) >= 0
    os.utime(package / "kern.py", (1e9, 1e9))
    assert source_key("kpkg.kern") == key
    (package / "deep.py").write_text("OFFSET = 0  # a comment is an edit too\n")
    changed = source_key("kpkg.kern")
    assert changed != key
    assert source_key("kpkg.constants") != source_key("kpkg.kern")
    kernel_cache._toolchain.cache_clear()
    monkeypatch.setattr(kernel_cache, "_version", lambda name: "0.0-other")
    try:
        assert source_key("kpkg.kern") != changed  # another numba or numpy
    finally:
        kernel_cache._toolchain.cache_clear()


def test_compiled_in_follows_the_declarations_and_stops_at_cycles(tmp_path, monkeypatch):
    package = tmp_path / "cyc"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "a.py").write_text('COMPILED_IN = ("cyc.b",)\n')
    (package / "b.py").write_text('COMPILED_IN: tuple[str, ...] = ("cyc.a", "cyc.c")\n')
    (package / "c.py").write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    assert set(compiled_in(["cyc.a"])) == {"cyc.a", "cyc.b", "cyc.c"}
    assert "cyc.a" not in sys.modules  # read, not imported
    assert declared_compiled_in(b"X = 1\n") == ()


def test_the_cache_root_is_the_environments_else_the_users(tmp_path, monkeypatch):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "mine"))
    assert kernel_cache.cache_root() == tmp_path / "mine"
    monkeypatch.delenv(CACHE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    if sys.platform.startswith("linux"):
        assert user_cache_root() == tmp_path / "xdg" / "preform" / "kernels"
        assert kernel_cache.cache_root() == user_cache_root()
    blocked = tmp_path / "file"
    blocked.write_text("")  # a file where the folder should be: not writable
    monkeypatch.setattr(kernel_cache, "user_cache_root", lambda: blocked / "kernels")
    assert kernel_cache.cache_root().name.startswith("preform-kernels-")


def preform_imports(path: Path) -> set[str]:
    """The preform modules a file imports at module level (``from preform.x import m`` counts
    as module ``preform.x.m`` when that is a module)."""
    found: set[str] = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("preform")}
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("preform"):
            module = str(node.module)
            package = hasattr(importlib.import_module(module), "__path__")
            for alias in node.names:
                sub = f"{module}.{alias.name}"
                is_module = package and importlib.util.find_spec(sub) is not None
                found.add(sub if is_module else module)
    return found - {"preform.base.kernel_cache"}


@pytest.mark.parametrize("path", KERNEL_FILES, ids=lambda p: p.name)
def test_every_kernel_module_declares_the_preform_modules_compiled_into_it(path: Path):
    """A kernel module that imports another preform module compiles it in (an inlined function
    or a frozen constant): it must say so, the key of its cache must cover it, and its kernels
    must be cached by content."""
    rel = path.relative_to(REPO).with_suffix("")
    parts = rel.parts
    name = ".".join(("preform", *parts[1:]) if parts[0] == "core" else ("preform", *parts))
    module = importlib.import_module(name)
    imported = preform_imports(path)
    assert hasattr(module, "COMPILED_IN"), name
    assert set(module.COMPILED_IN) == imported, f"{name}: COMPILED_IN vs imports"
    assert "cache_by_content(__name__)" in path.read_text()
    # as the key reads it (by pattern, not by import)
    assert declared_compiled_in(path.read_bytes()) == tuple(module.COMPILED_IN)
    assert set(compiled_in([name])) >= {name, *imported}
    assert kernel_cache._BY_CONTENT[name].name == f"{name}-{source_key(name)}"


def test_a_kernel_module_written_as_before_keeps_numbas_own_cache(tmp_path):
    """Kernels of modules that did not ask are numba's business: placed as numba places
    them, never in the content-keyed folders."""
    (tmp_path / "plain.py").write_text(
        textwrap.dedent(
            """
            import numba
            import preform.drape.kernels.net_kernels  # installs the locator

            @numba.njit(cache=True)
            def one():
                return 1
            """
        )
    )
    cache = tmp_path / "cache"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}
    env[CACHE_ENV] = str(cache)
    env.pop("NUMBA_CACHE_DIR", None)
    subprocess.run([sys.executable, "-c", "import plain; print(plain.one())"], env=env, check=True)
    assert list((tmp_path / "__pycache__").glob("plain.one-*.nbi"))
    assert not list(cache.glob("plain*"))


def test_kernels_shipped_with_the_package_are_taken_not_compiled(tmp_path):
    """An installed copy ships its kernels (compiled when its wheel was built): a user's
    empty cache takes that key's folder and numba compiles nothing; another key's shipped
    folder (the sources edited since) is not taken, and the edited kernel compiles."""
    root = tmp_path / "src"
    package = write_package(root)
    shipped = tmp_path / "shipped"
    assert run_kernel(root, shipped) == ("1", 1)  # the build compiling into the package
    take = (
        "import pathlib\nfrom preform.drape import kernel_cache\n"
        f"kernel_cache.shipped_root = lambda: pathlib.Path({str(shipped)!r})\n"
    )
    user = tmp_path / "user"
    assert run_kernel(root, user, prefix=take) == ("1", 0)
    assert [f.name for f in user.glob("kpkg.kern-*")] == [f.name for f in shipped.iterdir()]
    assert not list(user.glob("*/.*"))  # no partial copy left
    (package / "constants.py").write_text((package / "constants.py").read_text().replace("1", "3"))
    assert run_kernel(root, tmp_path / "user-2", prefix=take) == ("3", 1)


LOAD_AHEAD = (
    COUNT
    + """
from preform.base.kernel_cache import load_compiled

with event.install_listener("numba:compile", Count()):
    loaded = load_compiled(["kpkg.kern"])
    import kpkg.kern as k
    ready = len(k.value.overloads)  # loaded before any call
    print(loaded, ready, k.value(), len(compiles))
"""
)


def test_load_compiled_loads_what_the_cache_holds_before_any_call_and_compiles_nothing(tmp_path):
    """The truth is numba's: the kernel's overloads before its first call (none unless
    loaded) and its count of compiles. An empty cache loads nothing, and compiles nothing
    ahead: the call compiles as before."""
    write_package(tmp_path)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}
    env.pop("NUMBA_CACHE_DIR", None)

    def run(cache: Path) -> list[str]:
        done = subprocess.run(
            [sys.executable, "-c", LOAD_AHEAD],
            capture_output=True,
            text=True,
            env={**env, CACHE_ENV: str(cache)},
            check=True,
        )
        return done.stdout.split()

    assert run(tmp_path / "empty") == ["0", "0", "1", "1"]
    assert run(tmp_path / "empty") == ["1", "1", "1", "0"]  # compiled by the call before
