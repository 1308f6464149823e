"""Imported last by a process pool's fork server (``preform.pipeline.engines.pool_context``):
freezes what the server's imports made and resumes the garbage collector
:mod:`preform.pipeline.preload_begin` paused, so every worker is forked with it on
(:mod:`preform.collector`); gives SIGINT its usual handler back where the server was started
deaf to it for its imports, and quiets the start of a worker its pool gave up on
(``preform.pipeline.engines.prepare_fork_server``); loads the compiled drape kernels the server
imported (``preform.base.kernel_cache.load_compiled``), so that workers are forked with them
loaded and no worker's first case pays numba's loading."""

import sys

from preform.base.kernel_cache import WARMED, load_compiled
from preform.collector import end_startup
from preform.pipeline.engines import prepare_fork_server

load_compiled([module for module in WARMED if module in sys.modules])
end_startup()
prepare_fork_server()
