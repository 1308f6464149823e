"""Deprecated: the trade-study harness is ``preform.bench.tradeoff`` (``preform bench tradeoff``).

Kept for one release for code that imported ``preform.tradeoff``: importing it warns and gives
the same module object, so every name (and patching one) works as before.
"""

from preform._moved import alias_moved_module

alias_moved_module(__name__, "preform.bench.tradeoff")
