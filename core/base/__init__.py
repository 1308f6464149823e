"""The bottom layer: what every package of preform may use and that imports none of them.

Atomic writes (``atomic``), the status vocabulary of a case (``status``), the fidelity knobs
(``fidelity``), the scene's export section (``export_section``) and the version. The order of
the packages above it is in docs/design.md ("Layers") and held by
tests/framework/test_import_cycles.py.
"""

__version__ = "0.1.0"
