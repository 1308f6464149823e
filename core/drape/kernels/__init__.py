"""The drape's compiled kernels (numba), their cache by content and their compilation ahead of
a run; imported only where a kernel runs."""
