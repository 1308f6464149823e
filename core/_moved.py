"""Old import paths of moved modules: each stays one release as an alias that warns."""

import importlib
import sys
import warnings


def alias_moved_module(old: str, new: str) -> None:
    """Make the module being imported as ``old`` the module ``new`` itself (every name, private
    ones and patching included), with a DeprecationWarning at the importer's line."""
    moved = importlib.import_module(new)
    # 1: here, 2: the alias module's body, 3+: the import machinery, then the importer
    warnings.warn(f"{old} is deprecated: import {new}", DeprecationWarning, stacklevel=3)
    sys.modules[old] = moved
