"""Array plumbing shared by the astro modules: float arrays in, floats or arrays out."""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
import numpy.typing as npt

FloatArray: TypeAlias = npt.NDArray[np.float64]
FloatOrArray: TypeAlias = float | FloatArray


def as_float_array(value: npt.ArrayLike) -> FloatArray:
    """Return ``value`` as a float64 array (0-d for a scalar), without copying when possible."""
    return np.asarray(value, dtype=np.float64)


def scalar_or_array(value: npt.ArrayLike) -> FloatOrArray:
    """Return a Python float for a 0-d result and a float64 array otherwise."""
    array = np.asarray(value, dtype=np.float64)
    return float(array) if array.ndim == 0 else array
