"""In which order, and in which groups, a run hands its cases to the workers.

Two things decide how long a run of many cases takes on a few workers besides the cases
themselves: the tail (the last worker busy with a long case while the others are idle) and the
cost of sending each case on its own (a task to the engine, and the parent's bookkeeping of
each result: manifest and tables). The first is shortened by starting the longest cases first,
the second by sending small cases in batches.

A case's cost is estimated from what an earlier run recorded in its folder (``wall_time_s`` of
its ``summary.json``, whatever that run's status or ``--force``); a case without such a record
has no estimate and keeps its place before the estimated ones (it may be long). Nothing here
runs a case: it only orders and groups them.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TypeVar

T = TypeVar("T")

#: Batches per worker the automatic batch size leaves at least, so that the last batches can
#: still be shared out evenly: with fewer, the tail is a whole batch long.
BATCHES_PER_WORKER = 4
#: Largest automatic batch [cases]. Measured on 120 small cases, 2 workers
#: (``benchmarks/bench_batches.py``, README section k), wall time a case: 40 ms alone, 18 in
#: batches of 4, 15 of 8, 15 of 16, 14 of 32 (load 2.2; under load 4: 79, 43, 27, 23, 25):
#: past 8 little is gained, while a worker that dies mid-batch makes more cases run twice.
MAX_AUTO_BATCH = 8
#: A case estimated to take longer than this runs alone [s]: its own dispatch and
#: bookkeeping (a few ms) are negligible beside it, and alone it can be balanced and recovered.
SMALL_CASE_S = 0.5


def recorded_wall_time_s(case_dir: str | Path) -> float | None:
    """Wall time [s] an earlier run recorded for the case in ``case_dir``, if any."""
    try:
        record = json.loads((Path(case_dir) / "summary.json").read_text(encoding="utf-8"))
        seconds = float(record["wall_time_s"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return seconds if math.isfinite(seconds) and seconds >= 0 else None


def longest_first(items: Sequence[T], estimate: Callable[[T], float | None]) -> list[T]:
    """``items`` in the order to start them: those without an estimate first (as given), then
    the estimated ones from the longest down (ties as given)."""
    return [item for item, _ in _longest_first_estimated(items, estimate)]


def _longest_first_estimated(
    items: Sequence[T], estimate: Callable[[T], float | None]
) -> list[tuple[T, float | None]]:
    """``longest_first`` with each item's estimate, asked once per item (an estimate reads
    the case's earlier summary.json)."""
    estimated = [(item, estimate(item)) for item in items]
    unknown = [pair for pair in estimated if pair[1] is None]
    known = [pair for pair in estimated if pair[1] is not None]
    known.sort(key=lambda pair: -(pair[1] or 0.0))  # sort is stable: ties keep their order
    return unknown + known


def auto_batch_size(n_cases: int, workers: int) -> int:
    """Cases per batch when the user did not choose: as many as leave every worker at least
    ``BATCHES_PER_WORKER`` batches, at most ``MAX_AUTO_BATCH``, at least 1 (no batching)."""
    per_worker = n_cases // max(1, workers * BATCHES_PER_WORKER)
    return max(1, min(MAX_AUTO_BATCH, per_worker))


def plan_batches(
    items: Sequence[T],
    estimate: Callable[[T], float | None],
    *,
    workers: int,
    batch_size: int | None = None,
) -> list[list[T]]:
    """The groups to send, in the order to send them.

    Ordered longest first (``longest_first``). With ``batch_size`` None the size is
    ``auto_batch_size``; when it is above 1, the cases estimated past ``SMALL_CASE_S`` go
    first, each alone, then the others in batches. An explicit ``batch_size`` groups every
    case so, in ``longest_first`` order (1: one case a task, no batching).
    """
    estimated = _longest_first_estimated(items, estimate)
    ordered = [item for item, _ in estimated]
    if batch_size is not None:
        if batch_size < 1:
            raise ValueError(f"batch size must be at least 1, not {batch_size}")
        size = batch_size
        alone: list[T] = []
        grouped = ordered
    else:
        size = auto_batch_size(len(ordered), workers)
        if size == 1:
            return [[x] for x in ordered]
        alone = [x for x, seconds in estimated if (seconds or 0.0) > SMALL_CASE_S]
        grouped = [x for x, seconds in estimated if (seconds or 0.0) <= SMALL_CASE_S]
    batches = [[x] for x in alone]
    batches += [list(grouped[i : i + size]) for i in range(0, len(grouped), size)]
    return batches
