"""Deprecated: the trade-study harness is ``preform.bench.tradeoff`` (``preform bench tradeoff``).

Kept for one release for code that imported ``preform.tradeoff``: importing it warns and gives
the same module object, so every name (and patching one) works as before.
"""

import sys
import warnings

from preform.bench import tradeoff as _tradeoff

warnings.warn(
    "preform.tradeoff is deprecated: import preform.bench.tradeoff",
    DeprecationWarning,
    stacklevel=2,
)
sys.modules[__name__] = _tradeoff
