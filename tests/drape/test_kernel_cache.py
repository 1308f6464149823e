"""Cached compiled kernels follow every source compiled into them (``preform.drape.kernel_cache``):
numba alone checks only a kernel's own file, so a changed constant of another module kept its
old value in the machine code."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import os
import subprocess
import sys
import textwrap
import types
from pathlib import Path

import pytest

from preform.drape.kernel_cache import compiled_in, drop_stale

REPO = Path(__file__).resolve().parents[2]
KERNEL_FILES = sorted([*REPO.glob("core/**/*_kernels.py"), *REPO.glob("plugins/**/*_kernels.py")])


def fake_module(monkeypatch: pytest.MonkeyPatch, name: str, path: Path, compiled=None):
    module = types.ModuleType(name)
    module.__file__ = str(path)
    if compiled is not None:
        module.COMPILED_IN = compiled
    path.write_text("# fake\n")
    monkeypatch.setitem(sys.modules, name, module)
    return module


def cache_files(cache: Path, stem: str, kernel: str, data: int) -> list[Path]:
    base = f"{stem}.{kernel}-10.py311"
    files = [cache / f"{base}.nbi", *(cache / f"{base}.{k}.nbc" for k in range(1, data + 1))]
    for f in files:
        f.write_bytes(b"x")
    return files


def age(paths: list[Path], mtime: float) -> None:
    for p in paths:
        os.utime(p, (mtime, mtime))


def test_only_the_kernels_older_than_a_source_compiled_in_are_dropped(tmp_path, monkeypatch):
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    deep = fake_module(monkeypatch, "fakepkg.deep", tmp_path / "deep.py")
    dep = fake_module(monkeypatch, "fakepkg.dep", tmp_path / "dep.py", ("fakepkg.deep",))
    fake_module(monkeypatch, "fakepkg.kern", tmp_path / "kern.py", ("fakepkg.dep",))
    fake_module(monkeypatch, "fakepkg.other", tmp_path / "other.py", ())
    old = cache_files(cache, "kern", "old", 2)
    new = cache_files(cache, "kern", "new", 1)
    others = cache_files(cache, "other", "old", 1)
    age([Path(str(deep.__file__)), Path(str(dep.__file__))], 1_000_000.0)
    age(old + others, 900_000.0)  # compiled before the sources last changed
    age(new, 1_100_000.0)  # compiled after
    # the older kernel goes with all its data; the newer one and another module's stay
    assert sorted(drop_stale("fakepkg.kern")) == sorted(old)
    assert all(p.exists() for p in new + others)
    assert drop_stale("fakepkg.kern") == []
    # the source two steps down (compiled into dep, which is compiled into kern) changes
    age([Path(str(deep.__file__))], 1_200_000.0)
    assert sorted(drop_stale("fakepkg.kern")) == sorted(new)
    assert all(p.exists() for p in others)  # another module's caches are its own business


def test_fresh_caches_are_kept_and_a_missing_cache_folder_is_no_error(tmp_path, monkeypatch):
    dep = fake_module(monkeypatch, "fakepkg2.dep", tmp_path / "dep.py")
    fake_module(monkeypatch, "fakepkg2.kern", tmp_path / "kern.py", ("fakepkg2.dep",))
    assert drop_stale("fakepkg2.kern") == []  # no __pycache__ at all
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    kept = cache_files(cache, "kern", "k", 3)
    age([Path(str(dep.__file__))], 1_000_000.0)
    age(kept, 1_000_001.0)
    assert drop_stale("fakepkg2.kern") == []
    assert all(p.exists() for p in kept)


def test_compiled_in_follows_the_declarations_and_stops_at_cycles(monkeypatch, tmp_path):
    fake_module(monkeypatch, "cyc.a", tmp_path / "a.py", ("cyc.b",))
    fake_module(monkeypatch, "cyc.b", tmp_path / "b.py", ("cyc.a", "cyc.c"))
    fake_module(monkeypatch, "cyc.c", tmp_path / "c.py")
    assert compiled_in(["cyc.a"]) == {"cyc.a", "cyc.b", "cyc.c"}


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
    return found - {"preform.drape.kernel_cache"}


@pytest.mark.parametrize("path", KERNEL_FILES, ids=lambda p: p.name)
def test_every_kernel_module_declares_the_preform_modules_compiled_into_it(path: Path):
    """A kernel module that imports another preform module compiles it in (an inlined function
    or a frozen constant): it must say so, and drop its stale caches when imported."""
    rel = path.relative_to(REPO).with_suffix("")
    parts = rel.parts
    name = ".".join(("preform", *parts[1:]) if parts[0] == "core" else ("preform", *parts))
    module = importlib.import_module(name)
    imported = preform_imports(path)
    declared = set(getattr(module, "COMPILED_IN", ()))
    assert declared == imported, f"{name}: COMPILED_IN {sorted(declared)} vs {sorted(imported)}"
    if imported:
        assert "drop_stale(__name__)" in path.read_text()


KERNEL = """
import numba
from kpkg.constants import VALUE
from preform.drape.kernel_cache import drop_stale

COMPILED_IN = ("kpkg.constants",)
{drop}

@numba.njit(cache=True)
def value():
    return VALUE
"""


def run_kernel(root: Path) -> str:
    code = "import kpkg.kern as k; print(k.value())"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(root), *sys.path])}
    env.pop("NUMBA_CACHE_DIR", None)
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    return done.stdout.strip()


@pytest.mark.parametrize("drop", [True, False], ids=["with drop_stale", "numba alone"])
def test_a_changed_constant_of_another_module_reaches_the_cached_kernel(tmp_path, drop):
    """The truth: a kernel compiled with a constant of another module, cached, then the
    constant changed in its own file. With ``drop_stale`` the next process runs the new value;
    numba alone keeps running the old one (the defect this module exists for)."""
    package = tmp_path / "kpkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "constants.py").write_text("VALUE = 1\n")
    (package / "kern.py").write_text(
        textwrap.dedent(KERNEL).format(drop="drop_stale(__name__)" if drop else "")
    )
    assert run_kernel(tmp_path) == "1"
    assert list((package / "__pycache__").glob("kern.*.nbi"))  # cached
    constants = package / "constants.py"
    constants.write_text("VALUE = 2\n")
    later = (package / "kern.py").stat().st_mtime + 10.0
    os.utime(constants, (later, later))
    assert run_kernel(tmp_path) == ("2" if drop else "1")
