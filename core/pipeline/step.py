"""Where ``Step`` and ``CaseContext`` lived until 0.1: they are ``preform.step`` now.

Kept so plugins importing ``preform.pipeline.step`` keep working; new code imports
``preform.Step`` / ``preform.CaseContext``.
"""

from preform.step import CaseContext, Step, StepFunction

__all__ = ["CaseContext", "Step", "StepFunction"]
