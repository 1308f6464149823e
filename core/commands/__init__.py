"""Pieces of the ``preform`` command line shared by its commands (``preform.cli`` is the group).

One grammar for every command: ``--library PATH`` (repeatable) adds to the bundled library and
``PREFORM_LIBRARY``, ``--no-bundled`` leaves the bundled library out; ``--json`` prints nothing
but one JSON document on stdout (words go to stderr); ``--out`` is a directory for a run and a
file for a single artefact, and its metavar says which.
"""
