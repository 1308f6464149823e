"""Imported last by a process pool's fork server (``preform.pipeline.engines.pool_context``):
freezes what the server's imports made and resumes the garbage collector
:mod:`preform.pipeline.preload_begin` paused, so every worker is forked with it on
(:mod:`preform.collector`)."""

from preform.collector import end_startup

end_startup()
