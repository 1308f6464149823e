"""Deprecated: this module is ``preform.optimise.relax`` (the optimisation on top of the drape).

Kept for one release: importing it warns and gives the same module object.
"""

from preform._moved import alias_moved_module

alias_moved_module(__name__, "preform.optimise.relax")
