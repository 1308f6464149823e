"""Imported first by a process pool's fork server (``preform.pipeline.engines.pool_context``):
pauses the garbage collector for the server's imports (:mod:`preform.collector`).
:mod:`preform.pipeline.preload_end`, imported last, resumes it before any worker is forked."""

from preform.collector import pause

pause()
