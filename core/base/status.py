"""What a case's result is: the status vocabulary of every table, summary and console line.

A status is a promise to the user. ``ok`` means the result is complete and every number in it
is finite; anything less says so here, with the reasons in words next to it (``reasons`` in
summary.json and the tables, and the end-of-run console report).
"""

from __future__ import annotations

from enum import StrEnum


class CaseStatus(StrEnum):
    #: Complete, and every number is finite. Warnings (cells past locking, values outside the
    #: law's data range) may still accompany it; they are listed in words.
    OK = "ok"
    #: The result is finite but does not cover what the scene asked (the ply did not reach the
    #: whole part, a node budget cut it short, ...): ``covered_fraction`` and the reasons say how
    #: much and why. Its numbers describe only the covered part.
    PARTIAL = "partial"
    #: No trustworthy result: an error, a non-finite number, or a worker that died.
    FAILED = "failed"
    #: The case ran past its time limit (``--case-timeout`` / the scene's ``limits``) and was
    #: stopped; nothing of it is kept.
    TIMED_OUT = "timed_out"
    #: The run was interrupted (Ctrl-C, SIGTERM) before this case finished; a rerun redoes it.
    INTERRUPTED = "interrupted"
    #: Done by an earlier run into the same directory with the same inputs; its result is kept.
    SKIPPED = "skipped"
    #: Not started yet (only ever seen in the manifest of a run that is still going or died).
    PENDING = "pending"


#: One line per status, for the docs, ``--help`` and the end-of-run legend.
MEANING: dict[CaseStatus, str] = {
    CaseStatus.OK: "complete, finite and physical",
    CaseStatus.PARTIAL: "finite, but covers less than the scene asked, or its energy comes "
    "mostly from where the fabric would wrinkle (see covered_fraction and reasons)",
    CaseStatus.FAILED: "no result: see the error",
    CaseStatus.TIMED_OUT: "stopped at the case time limit",
    CaseStatus.INTERRUPTED: "the run was stopped before this case finished; rerun to redo it",
    CaseStatus.SKIPPED: "kept from an earlier run with identical inputs",
    CaseStatus.PENDING: "not run yet",
}

#: Statuses whose result folder is complete and may be reused by a later run.
REUSABLE = frozenset({CaseStatus.OK, CaseStatus.PARTIAL})


class CaseFailure(Exception):
    """Raised by a step when its result is not trustworthy (a non-finite energy, an empty net):
    the case is recorded ``failed`` with this message, without a traceback location, because
    the message is for the user, not a bug report."""
