"""Suite-wide settings.

Hypothesis explores new examples on every local run (that is how it finds bugs); under CI
(``CI`` set, as ``.ci/run`` runs) it is derandomised, so a landing is judged on the same
examples every time and a new counterexample surfaces locally, not as a random red CI.
"""

from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")
