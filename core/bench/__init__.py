"""Measurements of preform itself (``preform bench``): the speed/accuracy trade of the scene's
fidelity knobs (``preform.bench.tradeoff``). Timing scripts that are not commands live in
``benchmarks/``."""
