"""Lapping notation: parsing, laps, classification and error positions."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from preform.plugins.warpknit.lapping import LappingSyntaxError, parse_lapping


@pytest.mark.parametrize(
    ("text", "family", "shifts", "laps"),
    [
        ("1-0/0-1", "pillar", (0, 0), {"open"}),
        ("1-0/1-0", "pillar", (1, 1), {"closed"}),
        ("1-0/1-2", "tricot", (1, -1), {"closed"}),
        ("0-1/2-1", "tricot", (1, -1), {"open"}),
        ("1-0/2-3", "cord", (2, -2), {"closed"}),
        ("1-0/3-4", "satin", (3, -3), {"closed"}),
        ("1-0/4-5", "velvet", (4, -4), {"closed"}),
        ("1-0/1-2/2-3/3-4/3-2/2-1", "atlas", (1, 0, 0, -1, 0, 0), {"open", "closed"}),
        ("2-0/0-2", "custom", (0, 0), {"open"}),
        ("1-0/1-2/1-0/1-2", "tricot", (1, -1, 1, -1), {"closed"}),
    ],
)
def test_sequences_classify_with_their_underlap_shifts(text, family, shifts, laps):
    seq = parse_lapping(text)
    assert seq.classification == family
    assert seq.underlap_shifts == shifts
    assert {c.lap for c in seq.courses} == laps


@pytest.mark.parametrize(
    "text", ["1-0/1-2/", "1-0/1-2//", " 1 - 0 / 1 - 2 // ", "1\u20130/1\u20132"]
)
def test_repeat_end_marks_and_spacing_are_accepted(text):
    seq = parse_lapping(text)
    assert [c.overlap for c in seq.courses] == [(1, 0), (1, 2)]
    assert seq.normalised() == "1-0/1-2"


def test_multi_digit_gaps():
    assert parse_lapping("10-11/12-11").courses[1].overlap == (12, 11)


@pytest.mark.parametrize(
    ("text", "position"),
    [
        ("", 0),
        ("1-0/1-", 6),
        ("1-0/1-x", 6),
        ("1-0//1-2", 5),
        ("1-0 1-2", 4),
        ("1-1", 2),
        ("a-0", 0),
        ("1-0/1-2///", 9),
    ],
)
def test_errors_point_at_the_offending_character(text, position):
    with pytest.raises(LappingSyntaxError) as info:
        parse_lapping(text)
    err = info.value
    assert err.position == position
    caret_line = str(err).splitlines()[-1]
    assert caret_line.index("^") - 2 == position
    assert isinstance(err, ValueError)


_course = st.tuples(st.integers(0, 6), st.integers(0, 6)).filter(lambda p: p[0] != p[1])
_valid = st.lists(_course, min_size=1, max_size=6).map(
    lambda cs: "/".join(f"{a}-{b}" for a, b in cs)
)


@given(_valid, st.data())
def test_random_corruptions_parse_or_point_inside_the_string(text, data):
    i = data.draw(st.integers(0, len(text)))
    char = data.draw(st.sampled_from(list("0123456789-/ x,.")))
    mode = data.draw(st.sampled_from(["insert", "replace", "delete"]))
    if mode == "insert":
        bad = text[:i] + char + text[i:]
    elif mode == "replace" and i < len(text):
        bad = text[:i] + char + text[i + 1 :]
    else:
        bad = text[:i] + text[i + 1 :]
    try:
        seq = parse_lapping(bad)
    except LappingSyntaxError as err:
        assert 0 <= err.position <= len(bad)
        assert err.text == bad
    else:
        assert all(a != b for a, b in (c.overlap for c in seq.courses))


@given(st.lists(_course, min_size=1, max_size=6))
def test_a_repeat_closes_on_itself(courses):
    seq = parse_lapping("/".join(f"{a}-{b}" for a, b in courses))
    # overlap and underlap moves over one repeat bring the guide back where it started
    assert sum(c.overlap_shift + c.underlap_shift for c in seq.courses) == 0
