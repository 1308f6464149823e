"""Suite-wide settings: the test tiers, the hypothesis profiles, and the ``ccx`` fixture
(CalculiX) of the solver tests.

Tiers (markers, registered in pyproject.toml). A plain ``pytest`` runs the quick tier: every
test not marked ``slow`` nor ``hostile``. Every test under ``tests/hostile/`` (the corpus of
broken inputs and faults) is marked ``hostile`` here, so a new file there joins its tier without
a marker of its own. ``pytest -m slow`` and ``pytest -m hostile`` run the others,
``pytest -m ""`` all of them; ``.ci/run`` runs every tier.

Hypothesis profiles:

- ``quick`` (a local run): a quarter of the examples each test asks for (its own
  ``max_examples``, or hypothesis' default of 100), but never fewer than ``min(its count,
  10)``. New examples on every run (that is how a property test finds bugs), so the small
  count still explores over many runs.
- ``ci`` (``CI`` set, as CI runs ``.ci/run``, which also sets ``HYPOTHESIS_PROFILE=ci``):
  every example each test asks for, derandomised, so a landing is judged on the same examples
  every time and a new counterexample surfaces locally, not as a random red CI.

``HYPOTHESIS_PROFILE=ci pytest`` runs the full counts locally; ``HYPOTHESIS_PROFILE`` wins over
``CI``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import settings

#: A test's ``max_examples`` is divided by this in the quick profile ...
QUICK_DIVISOR = 4
#: ... but never below this (or below its own count, if smaller): a handful of examples
#: still reaches the strategies' edge cases, which hypothesis tries first.
QUICK_FLOOR = 10

settings.register_profile("ci", derandomize=True, print_blob=True)
# the counts are scaled per test below: a profile's max_examples would not reach a test that
# sets its own
settings.register_profile("quick")
PROFILE = os.environ.get("HYPOTHESIS_PROFILE") or ("ci" if os.environ.get("CI") else "quick")
settings.load_profile(PROFILE)


def quick_examples(asked: int) -> int:
    """Examples the quick profile runs for a test that asks for ``asked``."""
    return max(min(asked, QUICK_FLOOR), asked // QUICK_DIVISOR)


HOSTILE = Path(__file__).parent / "hostile"


@pytest.hookimpl(tryfirst=True)  # before ``-m`` deselects by marker
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark the hostile corpus; in the quick profile, scale down the examples of every
    hypothesis test.

    Hypothesis has no public "scale every count" setting: a test's own ``@settings`` wins over
    the profile. So the settings object hypothesis keeps on the test is replaced by one with
    fewer examples. If a hypothesis release moves that attribute, stop loudly rather than run
    the full counts unnoticed.
    """
    for item in items:
        if item.path.is_relative_to(HOSTILE):
            item.add_marker(pytest.mark.hostile)
    if PROFILE != "quick":
        return
    done: set[int] = set()
    for item in items:
        test = getattr(item, "obj", None)
        test = getattr(test, "__func__", test)  # a method: the function holds the settings
        if not getattr(test, "is_hypothesis_test", False) or id(test) in done:
            continue
        done.add(id(test))
        own = getattr(test, "_hypothesis_internal_use_settings", None)
        if not isinstance(own, settings):
            raise pytest.UsageError(
                f"{item.nodeid}: cannot read the hypothesis settings of the test to scale them "
                "for the quick profile (hypothesis changed?); run with HYPOTHESIS_PROFILE=ci"
            )
        test._hypothesis_internal_use_settings = settings(
            own, max_examples=quick_examples(own.max_examples)
        )


@pytest.fixture
def ccx() -> Callable[[Path, str], str]:
    """Run CalculiX: ``ccx(folder, job)`` runs ``ccx -i job`` in ``folder`` and returns its
    output, failing on a non-zero exit or an ``*ERROR`` line. Skipped when ``ccx`` is not
    installed, a failure when ``CI`` is set (``.ci/run`` installs it: Debian ``calculix-ccx``)."""
    path = shutil.which("ccx")
    if path is None:
        if os.environ.get("CI"):
            pytest.fail("CI is set and ccx (CalculiX) is missing: .ci/run installs calculix-ccx")
        pytest.skip("ccx (CalculiX) is not installed: apt-get install calculix-ccx")

    def run(folder: Path, job: str) -> str:
        done = subprocess.run(
            [str(path), "-i", job],
            cwd=folder,
            capture_output=True,
            text=True,
            timeout=120,
            env={**os.environ, "OMP_NUM_THREADS": "1"},
        )
        output = done.stdout + done.stderr
        assert done.returncode == 0 and "*ERROR" not in output, output[-3000:]
        return output

    return run


@pytest.fixture
def cap_layup() -> Callable[..., dict[str, Any]]:
    """A layup scene over the R = 100 mm hemisphere, for the S8R cap of
    docs/examples/calculix_cap_mesh.inp: ``cap_layup([(fabric, angle_deg), ...], mesh,
    outputs)``, each ply 0.5 mm thick, draped only (``ply_outputs: [drape]``), angles from x."""

    def scene(
        plies: list[tuple[str, float]], mesh: str, outputs: list[str] | None = None
    ) -> dict[str, Any]:
        return {
            "name": "cap-stack",
            "tool": {"surface": "hemisphere", "radius_mm": 100},
            "ply": {"node_spacing_mm": 10, "size_mm": [160, 160]},
            "start": {"point_mm": [0, 0]},
            "layup": {
                "plies": [
                    {"fabric": f, "orientation_deg": a, "thickness_mm": 0.5} for f, a in plies
                ],
                "ply_outputs": ["drape"],
            },
            "export": {"mesh": mesh, "reference_direction": [1, 0, 0]},
            "outputs": outputs or ["layup"],
        }

    return scene
