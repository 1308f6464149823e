"""The arguments of a run, checked alike from the command line (``preform pipeline run``) and
from Python (``preform.run``), so a value one entry point refuses the other refuses too, with
the argument named: a case time limit that is not a finite positive number of seconds (NaN
compares false with every bound, so a range check alone lets it through), a worker count below
one, an unknown engine or fidelity preset.
"""

from __future__ import annotations

import math
from typing import Any

#: The engines a run can use (``preform.pipeline.engines``) and the fidelity presets
#: (``preform.base.fidelity``), as the command line offers them.
ENGINE_NAMES = ("serial", "process", "dask")
FIDELITY_NAMES = ("draft", "standard", "fine")


def case_timeout_problem(seconds: float) -> str | None:
    """Why the number ``seconds`` is no case time limit (finite and > 0), or None."""
    if not math.isfinite(seconds) or seconds <= 0:
        return f"must be a finite number of seconds greater than 0, got {seconds!r}"
    return None


def _kind(name: str, value: Any, kinds: type | tuple[type, ...], words: str) -> None:
    if isinstance(value, bool) or not isinstance(value, kinds):
        raise TypeError(f"{name} must be {words}, got {type(value).__name__} {value!r}")


def check_run_arguments(
    *,
    engine: Any,
    workers: Any,
    case_timeout_s: Any,
    fidelity: Any,
    materials: Any,
    force: Any,
) -> None:
    """Refuse a run's arguments as the command line would (module docstring): ``TypeError``
    for a value of the wrong kind, ``ValueError`` for one out of range, each naming the
    argument. None means the default, for every argument that has one."""
    if not isinstance(engine, str) or engine not in ENGINE_NAMES:
        raise ValueError(f"engine must be one of {', '.join(ENGINE_NAMES)}, got {engine!r}")
    if workers is not None:
        _kind("workers", workers, int, "a whole number of worker processes")
        if workers < 1:
            raise ValueError(f"workers must be at least 1, got {workers}")
    if case_timeout_s is not None:
        _kind("case_timeout_s", case_timeout_s, (int, float), "a number of seconds")
        problem = case_timeout_problem(float(case_timeout_s))
        if problem is not None:
            raise ValueError(f"case_timeout_s {problem}")
    if fidelity is not None and fidelity not in FIDELITY_NAMES:
        raise ValueError(f"fidelity must be one of {', '.join(FIDELITY_NAMES)}, got {fidelity!r}")
    if materials is not None:
        _kind("materials", materials, str, "a glob of fabric names")
    if not isinstance(force, bool):
        raise TypeError(f"force must be True or False, got {type(force).__name__} {force!r}")


__all__ = [
    "ENGINE_NAMES",
    "FIDELITY_NAMES",
    "case_timeout_problem",
    "check_run_arguments",
]
