"""The drape kernels are compiled once per install, by one process, saying so
(``preform.commands.kernel_compile``). The fast tests swap the small case for a one-line kernel
(the compile is numba's either way); the slow one runs the real command on an empty cache."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import pytest

from preform.base.kernel_cache import CACHE_ENV, shipped_root
from preform.commands import kernel_compile

#: ``ensure_compiled`` in a fresh process whose small case compiles a tiny kernel (after
#: ``sleep`` seconds, to hold the lock) or fails; prints what it returned on stdout.
PROCESS = """
import sys, time
import numba
from preform.commands import kernel_compile
def small_case():
    if {fail}:
        raise RuntimeError("no library")
    @numba.njit
    def plus_one(x):
        return x + 1
    plus_one(1)
    time.sleep({sleep})

kernel_compile._small_case = small_case
kernel_compile._start_helper = lambda: None  # the real small case's helper: its own test
kernel_compile._take_shipped = lambda marker: False  # an installed copy ships the real ones
print(kernel_compile.ensure_compiled(sys.stderr))
"""


def start(cache: Path, sleep: float = 0.0, fail: bool = False) -> subprocess.Popen[str]:
    env = {**os.environ, CACHE_ENV: str(cache)}
    code = PROCESS.format(sleep=sleep, fail=fail)
    return subprocess.Popen(
        [sys.executable, "-c", code],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
    )


def finish(process: subprocess.Popen[str]) -> tuple[str, str]:
    out, err = process.communicate(timeout=120)
    assert process.returncode == 0, err
    return out.strip(), err


def test_the_first_process_says_it_compiles_and_how_long_on_a_pipe(tmp_path):
    """stdout and stderr are pipes, not a terminal: the two lines are printed all the same;
    the next process finds the key compiled and says nothing."""
    out, err = finish(start(tmp_path))
    lines = err.splitlines()
    assert lines[0] == "preform: compiling drape kernels, once per install, ~25 s"
    assert lines[1].startswith("preform: drape kernels compiled in ")
    assert len(lines) == 2
    seconds = float(out)
    assert 0.0 < seconds < 60.0
    marker = next(tmp_path.glob("compiled-*"))
    assert float(marker.read_text()) == pytest.approx(seconds, abs=0.05)
    assert finish(start(tmp_path)) == ("None", "")


def test_two_processes_at_once_compile_once(tmp_path):
    """Started together: one takes the lock and compiles (holding it 2 s more), the other
    waits for it and compiles nothing."""
    both = [start(tmp_path, sleep=2.0), start(tmp_path, sleep=2.0)]
    results = [finish(p) for p in both]
    compiled = [err for out, err in results if out != "None"]
    assert len(compiled) == 1
    assert "compiling drape kernels, once per install" in compiled[0]
    waited = next(err for out, err in results if out == "None")
    assert waited.strip() in (
        "",
        "preform: waiting for another process compiling the drape kernels",
    )


def test_a_failed_small_case_is_said_and_not_marked(tmp_path):
    out, err = finish(start(tmp_path, fail=True))
    assert out == "None"
    assert "drape kernels not compiled ahead (RuntimeError: no library)" in err
    assert not list(tmp_path.glob("compiled-*"))


def test_kernels_compiled_at_first_use_are_marked_without_a_word(tmp_path, monkeypatch):
    """Kernels already in the cache (compiled at their first call by an earlier process, the
    API, a test): the small case compiles nothing, nothing is said, and the key is marked so
    that the next run does not run the small case again."""
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    ran: list[int] = []
    monkeypatch.setattr(kernel_compile, "_small_case", lambda: ran.append(1))
    monkeypatch.setattr(kernel_compile, "_start_helper", lambda: None)
    monkeypatch.setattr(kernel_compile, "_take_shipped", lambda marker: False)  # installed copy
    said = io.StringIO()
    assert kernel_compile.ensure_compiled(said) is None
    assert said.getvalue() == "" and ran == [1]
    assert kernel_compile.ready_marker().read_text() == "0.0\n"
    assert not (tmp_path / "last-compile-seconds").exists()
    assert kernel_compile.ensure_compiled(said) is None
    assert ran == [1]  # marked: not run again


def test_the_estimate_is_the_last_compiles_time(tmp_path, monkeypatch):
    (tmp_path / "last-compile-seconds").write_text("12.3\n")
    assert kernel_compile._estimate(tmp_path) == pytest.approx(12.3)
    (tmp_path / "last-compile-seconds").write_text("garbage\n")
    assert kernel_compile._estimate(tmp_path) == kernel_compile.TYPICAL_COMPILE_S


def test_the_compiled_key_moves_with_any_warmed_kernels_key(monkeypatch):
    key = kernel_compile.compiled_key()
    monkeypatch.setattr(kernel_compile, "source_key", lambda m: "0" if "field" in m else "1")
    other = kernel_compile.compiled_key()
    monkeypatch.setattr(kernel_compile, "source_key", lambda m: "0" if "verdict" in m else "1")
    assert len({key, other, kernel_compile.compiled_key()}) == 3


def test_the_helper_ends_with_the_process_it_helps(tmp_path):
    """Started for a process that is gone (a kill -9 of the ``preform`` process), the
    helper exits at once and compiles nothing."""
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    env = {**os.environ, CACHE_ENV: str(tmp_path)}
    command = [sys.executable, "-m", kernel_compile.HELPER_MODULE, kernel_compile.HELPER_FLAG]
    done = subprocess.run([*command, str(gone.pid)], env=env, capture_output=True, timeout=60)
    assert (done.returncode, done.stderr) == (1, b"")  # the watch's exit, not an error's
    assert not list(tmp_path.glob("*/*.nbi"))


@pytest.mark.slow
def test_the_helper_compiles_what_comes_after_the_drape_and_not_the_fill(tmp_path):
    """The helper runs the net kernels as Python: its cache holds the field, coverage and
    surrogate kernels the small case calls, and no fill."""
    env = {**os.environ, CACHE_ENV: str(tmp_path)}
    # the helper as ``python -m``, with no shipped kernels to seed the cache from (an
    # installed copy has them: every kernel, the fill too, would be there uncompiled)
    helper = (
        "import runpy, sys; from pathlib import Path; from preform.base import kernel_cache; "
        "kernel_cache.shipped_root = lambda: Path('/nonexistent-preform-shipped'); "
        f"sys.argv = ['x', {kernel_compile.HELPER_FLAG!r}]; "
        f"runpy.run_module({kernel_compile.HELPER_MODULE!r}, run_name='__main__')"
    )
    subprocess.run(
        [sys.executable, "-c", helper], env=env, check=True, capture_output=True, timeout=600
    )
    assert list(
        tmp_path.glob("preform.drape.kernels.field_kernels-*/field_kernels.node_shear-*.nbi")
    )
    assert list(tmp_path.glob("preform.drape.kernels.verdict_kernels-*/*.nbi"))
    assert list(tmp_path.glob("preform.shear.surrogate_kernels-*/*.nbi"))
    assert not list(tmp_path.glob("preform.drape.kernels.net_kernels-*/*fill_fronts*.nbi"))
    assert not list(tmp_path.glob("compiled-*"))  # the helper marks nothing


@pytest.mark.slow
def test_the_first_run_after_an_install_compiles_once_visibly_the_second_not(tmp_path):
    """The real command on an empty cache, output to pipes: the compile lines, then a run
    with nothing more to compile (numba's cache folders hold the kernels); a second run
    prints neither line. An installed copy (``pip install .``) compiled them when its wheel
    was built: its first run compiles nothing and says nothing of it."""
    env = {**os.environ, CACHE_ENV: str(tmp_path / "cache")}
    command = [
        sys.executable,
        "-m",
        "preform",
        "pipeline",
        "run",
        "--materials",
        "E-BX-318",
        "--out",
        str(tmp_path / "run"),
        "--force",
    ]
    first = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    if shipped_root().is_dir():
        assert "compil" not in first.stderr
    else:
        assert "preform: compiling drape kernels, once per install" in first.stderr
        assert "preform: drape kernels compiled in" in first.stderr
    assert list((tmp_path / "cache").glob("preform.drape.kernels.net_kernels-*/*.nbi"))
    second = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    assert "compil" not in second.stderr


@pytest.mark.parametrize("same_processor", [True, False])
def test_a_shipped_marker_counts_only_for_this_processor(tmp_path, monkeypatch, same_processor):
    """The package's marker (written when its wheel was built) makes a user's first run
    compile nothing when it names this processor; kernels compiled for another are not
    numba's to load, so the run compiles them, saying so, as without any."""
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "user"))
    shipped = tmp_path / "shipped"
    shipped.mkdir()
    monkeypatch.setattr(kernel_compile, "shipped_root", lambda: shipped)
    processor = kernel_compile.host_processor() if same_processor else "x86_64-other generic"
    marker = kernel_compile.ready_marker()
    (shipped / marker.name).write_text(f"21.5\n{processor}\n")
    ran: list[int] = []
    monkeypatch.setattr(kernel_compile, "_small_case", lambda: ran.append(1))
    monkeypatch.setattr(kernel_compile, "_start_helper", lambda: None)
    assert kernel_compile.ensure_compiled(io.StringIO()) is None
    assert ran == ([] if same_processor else [1])
    assert marker.read_text() == ("21.5\n" if same_processor else "0.0\n")


def test_ship_compiles_into_the_package_and_names_the_processor(tmp_path, monkeypatch):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "user"))  # ship() moves it; restored after
    shipped = tmp_path / "package" / "compiled"
    monkeypatch.setattr(kernel_compile, "shipped_root", lambda: shipped)
    monkeypatch.setattr(kernel_compile, "_small_case", lambda: None)
    monkeypatch.setattr(kernel_compile, "_start_helper", lambda: None)
    kernel_compile.ship(None)
    assert sorted(f.name for f in shipped.iterdir()) == [kernel_compile.ready_marker().name]
    lines = kernel_compile.ready_marker().read_text().splitlines()
    assert lines == ["0.0", kernel_compile.host_processor()]
