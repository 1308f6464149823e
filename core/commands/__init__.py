"""Commands of ``preform`` in their own modules, above the Python API (``preform.cli`` is the
group; the grammar they share is ``preform.command_line``)."""
