"""preform: fibre-architecture-aware drape simulation of reinforcement fabrics."""

__version__ = "0.1.0"
