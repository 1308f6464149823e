"""The bottom layer: atomic writes, the status vocabulary, the fidelity knobs, the scene's
export section, strict JSON, the version. It imports no other package of preform (the order of
the packages is in docs/design.md, "Layers")."""

__version__ = "0.1.0"
