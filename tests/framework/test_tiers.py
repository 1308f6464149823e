"""The quick tier's hypothesis counts (tests/conftest.py): a quarter of a test's own count in
the quick profile (never below min(count, 10)), untouched under the ci profile."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st


@settings(max_examples=60, deadline=None)
@given(x=st.floats(allow_nan=False, allow_infinity=False))
def test_a_property_with_its_own_count(x: float) -> None:
    """A property (|x| = |-x|), here for the count the collection gave it."""
    assert math.fabs(x) == math.fabs(-x)


def test_the_quick_profile_runs_a_quarter_of_a_tests_own_count() -> None:
    """Read from the settings hypothesis runs the test above with, after collection (so run
    with the module, not alone by its node id: then the test above is not collected)."""
    runs = test_a_property_with_its_own_count._hypothesis_internal_use_settings.max_examples
    assert runs == (15 if settings.get_current_profile_name() == "quick" else 60)
