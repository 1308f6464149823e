"""The file that catches a plugin call's raw output (fd 1) is kept for the next call (issue 15l:
creating one per call was ~5 ms of `materials list`). Each call must still forward only its
own output, a call inside another its own, and a forked child must not share the parent's."""

from __future__ import annotations

import os
import sys

import pytest

from preform import plugin_manager
from preform.plugin_manager import call_plugin


def _raw(text: str) -> None:
    os.write(1, text.encode())


def _lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("plugin ")]


def test_successive_calls_forward_only_their_own_raw_output(capfd: pytest.CaptureFixture[str]):
    call_plugin("first", _raw, "a long first line\nand a second\n")
    call_plugin("second", _raw, "short\n")  # shorter: the first's tail must be gone
    call_plugin("third", lambda: None)
    out, err = capfd.readouterr()
    assert out == ""
    assert _lines(err) == [
        "plugin first: a long first line",
        "plugin first: and a second",
        "plugin second: short",
    ]


def test_a_call_inside_a_call_keeps_each_output_apart(capfd: pytest.CaptureFixture[str]):
    def outer() -> None:
        _raw("outer before\n")
        call_plugin("inner", _raw, "inner\n")
        _raw("outer after\n")

    call_plugin("outer", outer)
    call_plugin("next", _raw, "next\n")
    out, err = capfd.readouterr()
    assert out == ""
    assert _lines(err) == [
        "plugin inner: inner",
        "plugin outer: outer before",
        "plugin outer: outer after",
        "plugin next: next",
    ]


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork only")
def test_a_forked_child_starts_without_the_parents_files(capfd: pytest.CaptureFixture[str]):
    call_plugin("parent", _raw, "parent\n")
    assert plugin_manager._FREE_TRAPS  # the probe: kept in the parent
    sys.stdout.flush()
    pid = os.fork()
    if pid == 0:  # the child: exit code 0 only if it holds none of the parent's files
        os._exit(0 if not plugin_manager._FREE_TRAPS else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    call_plugin("parent", _raw, "again\n")
    assert _lines(capfd.readouterr().err) == ["plugin parent: parent", "plugin parent: again"]
