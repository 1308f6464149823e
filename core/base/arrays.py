"""The array types preform's signatures are annotated with, by element type."""

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]
#: Node and cell status codes (``preform.drape.engine.result``).
StatusArray = NDArray[np.int8]
