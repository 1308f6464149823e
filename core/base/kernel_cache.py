"""Where compiled kernels are cached: a folder per content key, under the user's cache.

numba caches a kernel (``cache=True``) beside its source (``__pycache__``) and checks only
that file: a kernel that inlines a function of another module, or reads one of its constants
(node and cell statuses, surface kinds: numba freezes globals into the machine code), kept
running the old code after that other file changed, a silent wrong number. And a reinstall
put new sources, and a new ``__pycache__``, in place: every kernel compiled again.

So each kernel module names the preform modules compiled into it (``COMPILED_IN``) and calls
:func:`cache_by_content` before its kernels are defined. Its kernels are then cached in
``<cache root>/<module>-<key>``, the key a hash of the module's source, the sources of
everything compiled into it (followed through their own ``COMPILED_IN``), numba's, numpy's
and Python's versions (:func:`source_key`). An edit to any of those files is a new key, so a
kernel never runs code older than its sources, and nothing stale is ever looked at; the same
sources reinstalled, in another checkout or another virtual environment, find their kernels
compiled. The cache root is ``$PREFORM_KERNEL_CACHE`` if set, else the platform's user cache
folder (``~/.cache/preform/kernels`` on Linux); where that cannot be written, a folder in the
system's temporary directory. Old keys' folders are left for the user to remove (~2 MB each).

An installed copy ships its kernels compiled: building the wheel (``pip install .``) compiles
them into ``compiled/`` beside this module (:func:`shipped_root`, ``preform.commands.kernel_compile``
``--ship``), and :func:`cache_by_content` copies a key's shipped folder into the user's cache
the first time that key is used there, so the first run after an install loads them. numba
records the processor each entry was compiled for and loads only entries of this one: a wheel
built on another machine costs the compile at first use, as without it.

The key is computed from files alone (no numba import, no kernel module imported), so a
command can ask whether the kernels are compiled before it loads numba
(``preform.commands.kernel_compile``).
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import os
import re
import shutil
import sys
import tempfile
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import Any

#: The environment variable that moves the cache root (tests and benchmarks point it at a
#: temporary folder to start with an empty cache).
CACHE_ENV = "PREFORM_KERNEL_CACHE"

#: Changed when the layout of the cache or the key changes.
_KEY_VERSION = b"preform-kernel-cache-1"

#: Kernel modules whose kernels are cached by content (``__name__``) and their folders.
_BY_CONTENT: dict[str, Path] = {}


#: The kernel modules the default study runs (not the generator marcher's: its geodesics on
#: the hemisphere are closed forms): their keys together name the compiled state.
WARMED = (
    "preform.drape.kernels.net_kernels",
    "preform.drape.kernels.surface_kernels",
    "preform.drape.kernels.field_kernels",
    "preform.drape.kernels.verdict_kernels",
    "preform.shear.surrogate_kernels",
)


def user_cache_root() -> Path:
    """The platform's user cache folder for preform's kernels (not created here)."""
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
        return base / "preform" / "Cache" / "kernels"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "preform" / "kernels"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "preform" / "kernels"


def cache_root() -> Path:
    """The folder holding every key's cache: ``$PREFORM_KERNEL_CACHE``, else
    :func:`user_cache_root`, else (not writable) ``<temp>/preform-kernels-<user>``."""
    chosen = os.environ.get(CACHE_ENV)
    if chosen:
        return Path(chosen)
    root = user_cache_root()
    if _writable(root):
        return root
    user = getattr(os, "getuid", lambda: "user")()
    return Path(tempfile.gettempdir()) / f"preform-kernels-{user}"


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


def _source_path(module: str) -> Path:
    """The source file of ``module`` (by name), found without importing it."""
    loaded = sys.modules.get(module)
    path = getattr(loaded, "__file__", None)
    if path is None:
        spec = importlib.util.find_spec(module)
        path = spec.origin if spec is not None else None
    if path is None:
        raise ModuleNotFoundError(f"kernel cache: no source file for module {module!r}")
    return Path(path)


#: A module-level ``COMPILED_IN = (...)`` (annotated or not): found by pattern, as parsing a
#: whole kernel module takes ~10 ms and the check runs at every command.
_DECLARATION = re.compile(rb"^COMPILED_IN\s*(?::[^=\n]*)?=\s*(\([^)]*\))", re.MULTILINE)


def declared_compiled_in(source: bytes) -> tuple[str, ...]:
    """The module-level ``COMPILED_IN`` tuple of a module's source (empty without one)."""
    found = _DECLARATION.search(source)
    if found is None:
        return ()
    return tuple(ast.literal_eval(found.group(1).decode()))


def compiled_in(modules: tuple[str, ...] | list[str]) -> dict[str, bytes]:
    """``modules`` and, through each one's ``COMPILED_IN``, every module compiled into them:
    name -> source bytes (read from the files, nothing imported)."""
    sources: dict[str, bytes] = {}
    todo = list(modules)
    while todo:
        name = todo.pop()
        if name in sources:
            continue
        sources[name] = _source_path(name).read_bytes()
        todo += declared_compiled_in(sources[name])
    return sources


def _version(distribution: str) -> str:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return "none"


@lru_cache(maxsize=1)
def _toolchain() -> bytes:
    """What compiled code depends on besides the sources: numba, numpy, the interpreter."""
    parts = (_version("numba"), _version("numpy"), sys.implementation.cache_tag, sys.version)
    return "\0".join(parts).encode()


def source_key(module: str) -> str:
    """The content key of ``module``'s kernels: 16 hex digits of a SHA-256 over the sources
    of the module and of everything compiled into it, and the toolchain."""
    digest = hashlib.sha256(_KEY_VERSION + b"\0" + _toolchain())
    for name, source in sorted(compiled_in([module]).items()):
        digest.update(b"\0" + name.encode() + b"\0" + hashlib.sha256(source).digest())
    return digest.hexdigest()[:16]


def cache_folder(module: str) -> Path:
    """Where ``module``'s kernels are cached: ``<cache root>/<module>-<key>``."""
    return cache_root() / f"{module}-{source_key(module)}"


def shipped_root() -> Path:
    """Where an installed copy keeps the kernels compiled when its wheel was built (absent
    in a source checkout: ``pip install -e`` compiles at first use)."""
    return Path(__file__).with_name("compiled")


def seed_from_shipped(folder: Path) -> bool:
    """Copy the shipped kernels of ``folder``'s key into ``folder`` when it holds none yet;
    whether it did. Data files before index files, each written under a temporary name and
    renamed, so a process loading meanwhile sees an index only with its data (two processes
    copying at once write the same bytes). A failure leaves the compile to first use."""
    shipped = shipped_root() / folder.name
    if folder == shipped or not shipped.is_dir() or any(folder.glob("*.nbi")):
        return False
    try:
        folder.mkdir(parents=True, exist_ok=True)
        for source in sorted(shipped.iterdir(), key=lambda f: f.suffix == ".nbi"):
            partial = folder / f".{source.name}.{os.getpid()}"
            shutil.copyfile(source, partial)
            os.replace(partial, folder / source.name)
    except OSError:
        return False
    return True


def cache_by_content(module: str) -> Path:
    """Cache the kernels of ``module`` (its ``__name__``; called by the module before it
    defines them) in :func:`cache_folder`, numba's own place for them bypassed, seeded from
    the shipped kernels (:func:`seed_from_shipped`); returns that folder. The key is taken
    now, from the sources as this process imported them."""
    from numba.core import caching

    # CacheImpl since numba 0.61, _CacheImpl before
    impl: Any = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    locator = _locator_class()
    if locator not in impl._locator_classes:
        impl._locator_classes.insert(0, locator)
    folder = cache_folder(module)
    seed_from_shipped(folder)
    _BY_CONTENT[module] = folder
    return folder


@lru_cache(maxsize=1)
def _locator_class() -> type:
    """numba's cache locator for the kernels of modules that called :func:`cache_by_content`
    (made on first use: numba is imported only by those modules)."""
    from numba.core.caching import _CacheLocator

    class ContentKeyedLocator(_CacheLocator):
        """The folder is the content key's, and the source stamp is the key itself (the
        folder's files are fresh by construction). numba asks it first for every cached
        function; it declines (None) those of other modules, which numba places as usual."""

        def __init__(self, py_func: Any, folder: Path) -> None:
            self._lineno = py_func.__code__.co_firstlineno
            self._folder = folder

        def get_cache_path(self) -> str:
            return str(self._folder)

        def get_source_stamp(self) -> str:
            return self._folder.name

        def get_disambiguator(self) -> str:
            return str(self._lineno)

        @classmethod
        def from_function(cls, py_func: Any, py_file: str) -> Any:
            folder = _BY_CONTENT.get(getattr(py_func, "__module__", None) or "")
            if folder is None:
                return None
            locator = cls(py_func, folder)
            try:
                locator.ensure_cache_path()
            except OSError:
                # not numba's own places, which would key on the kernel's file alone: a
                # folder of this process's own, compiled afresh but never stale
                locator = cls(py_func, Path(tempfile.mkdtemp(prefix=f"{folder.name}-")))
            return locator

    return ContentKeyedLocator


def load_compiled(modules: tuple[str, ...] | list[str]) -> int:
    """Load into this process every public kernel of ``modules`` (imported here) that their
    cache holds compiled for this processor and these sources, as its first call would; returns
    how many signatures were loaded. A run calls it before its cases, so that the first case
    does not pay numba's loading, and the fork server before it forks workers, so that no
    worker pays it. Nothing is compiled: a signature the cache lacks compiles at its call."""
    import importlib

    from numba.core.registry import CPUDispatcher

    loaded = 0
    for name in modules:
        for attribute, kernel in list(vars(importlib.import_module(name)).items()):
            cache = getattr(kernel, "_cache", None)
            if not isinstance(kernel, CPUDispatcher) or cache is None:
                continue
            if attribute.startswith("_"):  # a kernels' helper: its code is linked into theirs
                continue
            index_file = getattr(cache, "_cache_file", None)
            if index_file is None:  # not cached (NullCache)
                continue
            loaded += _load_cached_signatures(kernel, cache, index_file)
    return loaded


def _load_cached_signatures(kernel: Any, cache: Any, index_file: Any) -> int:
    # numba's private cache interface (the index's keys: signature, processor, bytecode
    # hashes): loading ahead only saves time, so where that interface changed, or a file
    # cannot be read, the kernel is loaded at its first call as before
    codegen = kernel.targetctx.codegen()
    loaded = 0
    try:
        for key in index_file._load_index():
            signature = key[0]
            if key == cache._index_key(signature, codegen) and signature not in kernel.overloads:
                kernel.compile(signature)
                loaded += 1
    except Exception:  # see above
        pass
    return loaded
