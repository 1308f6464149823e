"""Order and groups of a run's cases (issue 15): longest first, small cases in batches.

Checked against what the order and the groups must be whatever the estimates: every case sent
exactly once; the estimated ones longest first, those without an estimate before them in their
own order; the automatic size leaves each worker enough batches and never batches a case known
to be long; an explicit size is obeyed.
"""

from __future__ import annotations

import itertools
import json

import pytest
from hypothesis import given
from hypothesis import strategies as st

from preform.pipeline.batching import (
    BATCHES_PER_WORKER,
    MAX_AUTO_BATCH,
    SMALL_CASE_S,
    auto_batch_size,
    longest_first,
    plan_batches,
    recorded_wall_time_s,
)

estimates = st.lists(st.none() | st.floats(0, 100, allow_nan=False), max_size=60)


def _plan(costs, **kw):
    items = list(range(len(costs)))
    return items, plan_batches(items, lambda i: costs[i], **kw)


@given(estimates)
def test_longest_first_is_a_stable_order_by_estimate(costs):
    order = longest_first(list(range(len(costs))), lambda i: costs[i])
    assert sorted(order) == list(range(len(costs)))
    unknown = [i for i in order if costs[i] is None]
    known = [i for i in order if costs[i] is not None]
    assert order == unknown + known
    assert unknown == sorted(unknown)
    for a, b in itertools.pairwise(known):
        assert costs[a] > costs[b] or (costs[a] == costs[b] and a < b)


@given(estimates, st.integers(1, 8))
def test_automatic_batches_send_every_case_once_and_long_ones_alone(costs, workers):
    items, batches = _plan(costs, workers=workers)
    assert sorted(i for b in batches for i in b) == items
    size = auto_batch_size(len(items), workers)
    assert all(1 <= len(b) <= size for b in batches)
    for b in batches:
        if len(b) > 1:
            assert all((costs[i] or 0.0) <= SMALL_CASE_S for i in b)
    if size > 1:  # enough batches for every worker to get several
        assert len(batches) >= workers * BATCHES_PER_WORKER


@given(st.integers(0, 10_000), st.integers(1, 64))
def test_automatic_size_bounds(n, workers):
    size = auto_batch_size(n, workers)
    assert 1 <= size <= MAX_AUTO_BATCH
    assert size == 1 or n // size >= workers * BATCHES_PER_WORKER


def test_the_default_study_is_not_batched_on_two_workers():
    # 10 fabrics on 2 workers: batching would only lengthen the tail
    assert auto_batch_size(10, 2) == 1
    assert auto_batch_size(1000, 2) == MAX_AUTO_BATCH


@given(estimates, st.integers(1, 9))
def test_explicit_size_is_obeyed(costs, size):
    items, batches = _plan(costs, workers=2, batch_size=size)
    flat = [i for b in batches for i in b]
    assert flat == longest_first(items, lambda i: costs[i])
    assert all(len(b) == size for b in batches[:-1])


def test_a_batch_size_below_one_is_refused():
    with pytest.raises(ValueError, match="at least 1"):
        plan_batches([1, 2], lambda _: None, workers=2, batch_size=0)


def test_recorded_time_is_read_from_an_earlier_summary(tmp_path):
    assert recorded_wall_time_s(tmp_path) is None
    (tmp_path / "summary.json").write_text(json.dumps({"wall_time_s": 1.25}))
    assert recorded_wall_time_s(tmp_path) == 1.25
    for bad in ({"wall_time_s": None}, {"wall_time_s": -1}, {}, []):
        (tmp_path / "summary.json").write_text(json.dumps(bad))
        assert recorded_wall_time_s(tmp_path) is None
    (tmp_path / "summary.json").write_text("{not json")
    assert recorded_wall_time_s(tmp_path) is None
