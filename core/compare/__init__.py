"""Measured fibre angles against a drape: read a measurement, compare it with a draped net,
and search the set-up that best explains it (docs/compare.md).

- :mod:`preform.compare.measurement`: the measurement (CSV, point clouds), in mm and degrees;
- :mod:`preform.compare.comparison`: per-point angle and shear errors, flags, summaries;
- :mod:`preform.compare.inverse`: the inverse search over start, orientation and generator
  angle, with the uncertainty of the best set-up.
"""

from preform.compare.comparison import Comparison, UnitSlipError, compare
from preform.compare.inverse import Explanation, SetUp, explain
from preform.compare.measurement import (
    Measurement,
    MeasurementError,
    measurement,
    read_measurement,
)

__all__ = [
    "Comparison",
    "Explanation",
    "Measurement",
    "MeasurementError",
    "SetUp",
    "UnitSlipError",
    "compare",
    "explain",
    "measurement",
    "read_measurement",
]
