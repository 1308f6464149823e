"""Suite-wide settings, and the ``ccx`` fixture (CalculiX) of the solver tests.

Hypothesis explores new examples on every local run (that is how it finds bugs); under CI
(``CI`` set, as ``.ci/run`` runs) it is derandomised, so a landing is judged on the same
examples every time and a new counterexample surfaces locally, not as a random red CI.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")


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
